//! What a joint is, independent of how a model file writes it: type, frames, pitch, and
//! what is attached to each free component (the input of [`super::Joint::new`]).

use crate::core::NodeRef;
use crate::math::TimeFunction;
use nalgebra::{Matrix3, Vector3};
use schemars::JsonSchema;
use serde::Deserialize;

/// Joint types, in the components of Bottasso's Table I (d_i relative displacement along
/// e_iᴬ, θ_i relative rotation; C constrained, F free, a joint coordinate):
///
/// ```text
/// type            d1 d2 d3   θ1 θ2 θ3
/// fixed           C  C  C    C  C  C
/// revolute        C  C  C    C  C  F
/// prismatic       C  C  F    C  C  C
/// screw           C  C  pθ3  C  C  F
/// cylindrical     C  C  F    C  C  F
/// planar          F  F  C    C  C  F
/// spherical       C  C  C    F  F  F
/// universal       C  C  C    F  F  C     (θ1 about e₁ᴬ, θ2 about e₂ᴮ)
/// point_on_line   C  C  F    F  F  F
/// point_on_plane  F  F  C    F  F  F
/// prescribed      F  F  F    F  F  F     (every component driven)
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum JointType {
    /// All six relative motions constrained (a clamp when one side is the ground).
    Fixed,
    /// Rotation θ3 about the joint axis e₃ free; all else constrained.
    Revolute,
    /// Translation d3 along the joint axis e₃ free; all else constrained.
    Prismatic,
    /// Rotation θ3 about e₃ free with translation d3 = p θ3 (`pitch` p).
    Screw,
    /// Translation d3 along and rotation θ3 about e₃ free.
    Cylindrical,
    /// Translations d1, d2 in the plane normal to e₃ and rotation θ3 about e₃ free.
    Planar,
    /// Relative translation constrained; relative rotation free.
    Spherical,
    /// Cardan joint: rotations θ1 about e₁ᴬ (the cross arm on A) and θ2 about e₂ᴮ (the
    /// arm on B) free; translation and the rotation about e₃ constrained.
    Universal,
    /// The joint point of B stays on the line through A's origin along e₃ᴬ.
    PointOnLine,
    /// The joint point of B stays in the plane through A's origin normal to e₃ᴬ.
    PointOnPlane,
    /// All six relative components follow time functions (`drive` on each; default 0).
    Prescribed,
}

impl JointType {
    /// The name used in model files.
    pub fn name(self) -> &'static str {
        match self {
            JointType::Fixed => "fixed",
            JointType::Revolute => "revolute",
            JointType::Prismatic => "prismatic",
            JointType::Screw => "screw",
            JointType::Cylindrical => "cylindrical",
            JointType::Planar => "planar",
            JointType::Spherical => "spherical",
            JointType::Universal => "universal",
            JointType::PointOnLine => "point_on_line",
            JointType::PointOnPlane => "point_on_plane",
            JointType::Prescribed => "prescribed",
        }
    }
}

/// A force as a function of one scalar (a coordinate or its rate).
#[derive(Clone, Debug, PartialEq)]
pub enum ForceLaw {
    /// `coefficient (x − reference)`.
    Linear { coefficient: f64, reference: f64 },
    /// Piecewise linear through (x[i], f[i]) (x strictly increasing), extended linearly.
    Table { x: Vec<f64>, f: Vec<f64> },
}

/// Free play `|ν − center| ≤ half_width` with a Kelvin–Voigt contact outside it.
#[derive(Clone, Debug, PartialEq)]
pub struct BacklashDef {
    pub center: f64,
    pub half_width: f64,
    pub stiffness: f64,
    pub damping: f64,
}

/// What is attached to one free component of a joint.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ComponentDef {
    /// Spring force as a function of the coordinate.
    pub spring: Option<ForceLaw>,
    /// Damper force as a function of the coordinate rate.
    pub damper: Option<ForceLaw>,
    pub backlash: Option<BacklashDef>,
    /// The coordinate follows this function of time.
    pub drive: Option<TimeFunction>,
    /// Input port: the name of the signal whose value is the force/torque.
    pub input: Option<String>,
    /// Servo: the coordinate follows this signal, `ν − s = 0` (exclusive with `drive`).
    pub drive_signal: Option<String>,
}

/// A joint. Frames are given in the initial configuration, global components: frame A
/// has origin `position_a`, frame B origin `position_b` (equal unless offsets were given),
/// both the axes `axes`.
#[derive(Clone, Debug)]
pub struct JointDef {
    pub name: String,
    pub kind: JointType,
    pub node_a: NodeRef,
    pub node_b: NodeRef,
    pub position_a: Vector3<f64>,
    pub position_b: Vector3<f64>,
    /// Columns are the joint axes e₁, e₂, e₃ in global components.
    pub axes: Matrix3<f64>,
    /// Screw pitch [m/rad].
    pub pitch: f64,
    /// Attachments per component d1, d2, d3, θ1, θ2, θ3 (free components only).
    pub components: [Option<ComponentDef>; 6],
}

impl JointDef {
    /// A joint with coincident frames and nothing attached.
    pub fn new(
        name: impl Into<String>,
        kind: JointType,
        node_a: NodeRef,
        node_b: NodeRef,
        position: Vector3<f64>,
        axes: Matrix3<f64>,
    ) -> Self {
        Self {
            name: name.into(),
            kind,
            node_a,
            node_b,
            position_a: position,
            position_b: position,
            axes,
            pitch: 0.0,
            components: Default::default(),
        }
    }
}
