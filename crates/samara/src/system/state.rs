//! Kinematic state of the nodes, the joint coordinates and the multipliers.

use crate::math::Rotation;
use crate::model::Model;
use nalgebra::{Matrix3, Vector3};

/// State of one 6-DOF node.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NodeState {
    /// Position, global.
    pub x: Vector3<f64>,
    /// Orientation (node frame → global).
    pub rot: Rotation,
    /// Velocity, global.
    pub v: Vector3<f64>,
    /// Angular velocity Ω, node frame (material).
    pub w: Vector3<f64>,
    /// Acceleration, global.
    pub a: Vector3<f64>,
    /// Angular acceleration Ω̇, node frame.
    pub wd: Vector3<f64>,
}

impl NodeState {
    #[inline]
    pub fn r(&self) -> &Matrix3<f64> {
        self.rot.matrix()
    }

    /// Angular velocity in global components, ω = R Ω.
    pub fn omega_global(&self) -> Vector3<f64> {
        self.r() * self.w
    }
}

/// State of one scalar unknown (a joint coordinate ν): value, rate, acceleration.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Coordinate {
    pub q: f64,
    pub v: f64,
    pub a: f64,
}

/// State of the whole system at one time.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct State {
    pub time: f64,
    pub nodes: Vec<NodeState>,
    /// Joint coordinates: the active ones constraint by constraint
    /// (`System::coordinate_offsets`), then the passive ones (`System::passive_offsets`).
    pub coords: Vec<Coordinate>,
    /// Lagrange multipliers in physical units (force, moment), per constraint row.
    pub lambda: Vec<f64>,
}

impl State {
    /// The initial conditions written in the model, at rest in acceleration, with the
    /// joint coordinates measured from the node configuration.
    pub fn initial(model: &Model, sys: &super::System) -> Self {
        let mut s = Self::nodes_only(model);
        s.coords = vec![Coordinate::default(); sys.n_coordinates + sys.n_passive];
        s.lambda = vec![0.0; sys.n_multipliers];
        sys.measure_coordinates(&mut s);
        s
    }

    /// The nodes' initial conditions only (no coordinates, no multipliers).
    pub(crate) fn nodes_only(model: &Model) -> Self {
        Self {
            time: 0.0,
            nodes: model
                .nodes
                .iter()
                .map(|n| NodeState {
                    x: n.position,
                    rot: n.orientation,
                    v: n.velocity,
                    w: n.orientation.matrix().transpose() * n.angular_velocity,
                    a: Vector3::zeros(),
                    wd: Vector3::zeros(),
                })
                .collect(),
            coords: Vec::new(),
            lambda: Vec::new(),
        }
    }
}
