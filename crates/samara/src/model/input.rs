//! The model file, exactly as written: the TOML schema (serde) and its JSON Schema (schemars).
//!
//! These types carry no physics; [`crate::model::validate`] checks them and builds the
//! [`crate::model::Model`]. Every key is documented in `docs/model-reference.md`; the doc
//! comments here become the descriptions of the JSON Schema printed by `samara schema`.

use super::located::Located;
pub use crate::elements::LoadFrame;
pub use crate::joints::JointType;
pub use crate::solve::LinearSolverType;
use schemars::JsonSchema;
use serde::Deserialize;

/// A samara model: nodes, the elements joined at them, and the analyses to run.
#[derive(Clone, Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ModelInput {
    /// Model-wide settings.
    pub model: ModelHeader,
    /// 6-DOF nodes (position and orientation).
    #[serde(default)]
    pub nodes: Vec<Located<NodeInput>>,
    /// Rigid bodies, each attached to one node.
    #[serde(default)]
    pub bodies: Vec<Located<BodyInput>>,
    /// Joints between two nodes, or a node and the ground.
    #[serde(default)]
    pub joints: Vec<Located<JointInput>>,
    /// Point-to-point spring-dampers.
    #[serde(default)]
    pub springs: Vec<Located<SpringInput>>,
    /// Named input signals (forces/torques fed into joint coordinates through `input`).
    #[serde(default)]
    pub signals: Vec<Located<SignalInput>>,
    /// Geometrically exact beams (Legendre spectral elements).
    #[serde(default)]
    pub beams: Vec<Located<super::beam_input::BeamInput>>,
    /// Applied forces and moments on nodes.
    #[serde(default)]
    pub forces: Vec<Located<ForceInput>>,
    /// Analyses, run in the order given.
    #[serde(default)]
    pub analyses: Vec<Located<AnalysisInput>>,
}

/// Model-wide settings.
#[derive(Clone, Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ModelHeader {
    /// Name of the model (written into every results file).
    pub name: String,
    /// Free-text description.
    #[serde(default)]
    pub description: Option<String>,
    /// Gravitational acceleration in the global frame [m/s²]; default zero.
    #[serde(default)]
    pub gravity: Option<[f64; 3]>,
}

/// An orientation: give exactly one of `quaternion`, `rotation_vector`, `matrix`, or two of
/// `x_axis`, `y_axis`, `z_axis` (the first in x, y, z order is kept exactly, the second is
/// orthogonalized against it).
#[derive(Clone, Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct OrientationInput {
    /// Unit quaternion (w, x, y, z); normalized if within 1e-6 of unit length.
    #[serde(default)]
    pub quaternion: Option<[f64; 4]>,
    /// Rotation vector ψ = angle · axis [rad].
    #[serde(default)]
    pub rotation_vector: Option<[f64; 3]>,
    /// Rotation matrix, row by row; its columns are the frame's axes in global components.
    #[serde(default)]
    pub matrix: Option<[[f64; 3]; 3]>,
    /// The frame's x axis in global components.
    #[serde(default)]
    pub x_axis: Option<[f64; 3]>,
    /// The frame's y axis in global components.
    #[serde(default)]
    pub y_axis: Option<[f64; 3]>,
    /// The frame's z axis in global components.
    #[serde(default)]
    pub z_axis: Option<[f64; 3]>,
}

/// A 6-DOF node: position and orientation of a frame, with its initial velocities.
#[derive(Clone, Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct NodeInput {
    /// Unique node name. `ground` is reserved for the fixed inertial frame.
    pub name: Located<String>,
    /// Initial position in the global frame [m].
    pub position: [f64; 3],
    /// Initial orientation of the node frame; default: aligned with the global frame.
    #[serde(default)]
    pub orientation: Option<OrientationInput>,
    /// Initial velocity, global frame [m/s].
    #[serde(default)]
    pub velocity: Option<[f64; 3]>,
    /// Initial angular velocity, global frame [rad/s].
    #[serde(default)]
    pub angular_velocity: Option<[f64; 3]>,
}

/// A rigid body attached to a node.
#[derive(Clone, Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BodyInput {
    /// Unique body name.
    pub name: Located<String>,
    /// The node carrying the body.
    pub node: Located<String>,
    /// Mass [kg], positive.
    pub mass: f64,
    /// Inertia tensor about the centre of gravity, node-frame components [kg m²];
    /// symmetric positive definite.
    pub inertia: [[f64; 3]; 3],
    /// Centre of gravity relative to the node, node-frame components [m]; default zero.
    #[serde(default)]
    pub cg_offset: Option<[f64; 3]>,
}

/// What is attached to one free component (joint coordinate) of a joint. Forces act on
/// the coordinate: a positive spring force resists an increase of the coordinate.
#[derive(Clone, Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ComponentInput {
    /// Linear spring: stiffness k [N/m or N m/rad], force k (ν − `rest`).
    #[serde(default)]
    pub stiffness: Option<f64>,
    /// Rest value of the linear spring [m or rad] (default 0).
    #[serde(default)]
    pub rest: Option<f64>,
    /// Nonlinear spring: [[ν, F], …] with increasing ν; piecewise linear, extended
    /// linearly beyond the ends with the end slopes.
    #[serde(default)]
    pub spring_table: Option<Vec<[f64; 2]>>,
    /// Linear viscous damper c [N s/m or N m s/rad], force c ν̇.
    #[serde(default)]
    pub damping: Option<f64>,
    /// Nonlinear damper: [[ν̇, F], …] with increasing ν̇, piecewise linear.
    #[serde(default)]
    pub damper_table: Option<Vec<[f64; 2]>>,
    /// Dead band of free play with contact stiffness and damping outside it.
    #[serde(default)]
    pub backlash: Option<BacklashInput>,
    /// Drive: the coordinate follows this time function [m or rad]; the force it takes
    /// is written out as `joint_coordinate_force`.
    #[serde(default)]
    pub drive: Option<Located<TimeFunctionInput>>,
    /// Input port: a force/torque [N or N m] taken from the named signal, acting to
    /// increase the coordinate.
    #[serde(default)]
    pub input: Option<Located<String>>,
}

/// Free play |ν − center| ≤ width/2; beyond it a contact force k g + c ν̇ (g the
/// penetration) pushes back.
#[derive(Clone, Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BacklashInput {
    /// Total width of the dead band [m or rad], positive.
    pub width: f64,
    /// Contact stiffness [N/m or N m/rad], positive.
    pub stiffness: f64,
    /// Contact damping [N s/m or N m s/rad], non-negative (default 0).
    #[serde(default)]
    pub damping: Option<f64>,
    /// Centre of the dead band [m or rad] (default 0).
    #[serde(default)]
    pub center: Option<f64>,
}

/// A joint between two nodes (or a node and the ground).
///
/// The joint frame (origin and axes) is given in the reference (initial) configuration,
/// in global components, or in the frame of the node named by `relative_to`. Frame A is
/// fixed to node A and frame B to node B; both coincide with the joint frame initially,
/// unless `offset_a`/`offset_b` place the origin on each node separately (the initial
/// assembly then moves the nodes onto the constraints).
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct JointInput {
    /// Unique joint name.
    pub name: Located<String>,
    /// Joint type.
    #[serde(rename = "type")]
    pub kind: Located<JointType>,
    /// Node carrying frame A (`ground` for the inertial frame).
    pub node_a: Located<String>,
    /// Node carrying frame B (`ground` for the inertial frame).
    pub node_b: Located<String>,
    /// Give `position`, `axis`, `axis_1` and `orientation` in this node's frame (relative
    /// to its origin) instead of global components.
    #[serde(default)]
    pub relative_to: Option<Located<String>>,
    /// Origin of the joint frame [m]; default: the position of node B (of node A if B is
    /// the ground).
    #[serde(default)]
    pub position: Option<[f64; 3]>,
    /// Joint axis e₃ (hinge, slide or screw axis; plane normal; shaft of a universal
    /// joint); need not be unit length.
    #[serde(default)]
    pub axis: Option<[f64; 3]>,
    /// Axis e₁, orthogonal to `axis` (the cross arm on A of a universal joint; the d1
    /// direction of a planar joint). Default: a direction normal to `axis`.
    #[serde(default)]
    pub axis_1: Option<[f64; 3]>,
    /// Full joint frame orientation; alternative to `axis`/`axis_1`. Default: global axes.
    #[serde(default)]
    pub orientation: Option<OrientationInput>,
    /// Origin of frame A in node A's frame [m], overriding `position` on side A.
    #[serde(default)]
    pub offset_a: Option<[f64; 3]>,
    /// Origin of frame B in node B's frame [m], overriding `position` on side B.
    #[serde(default)]
    pub offset_b: Option<[f64; 3]>,
    /// Screw pitch p [m/rad]: d3 = p θ3 (screw joints only).
    #[serde(default)]
    pub pitch: Option<f64>,
    /// Relative displacement along e₁ᴬ (free in planar, point_on_plane, prescribed).
    #[serde(default)]
    pub d1: Option<Located<ComponentInput>>,
    /// Relative displacement along e₂ᴬ.
    #[serde(default)]
    pub d2: Option<Located<ComponentInput>>,
    /// Relative displacement along e₃ᴬ.
    #[serde(default)]
    pub d3: Option<Located<ComponentInput>>,
    /// Relative rotation θ1.
    #[serde(default)]
    pub theta1: Option<Located<ComponentInput>>,
    /// Relative rotation θ2.
    #[serde(default)]
    pub theta2: Option<Located<ComponentInput>>,
    /// Relative rotation θ3.
    #[serde(default)]
    pub theta3: Option<Located<ComponentInput>>,
}

/// A named scalar signal (a constant or a time function now; controller outputs later).
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SignalInput {
    /// Unique signal name.
    pub name: Located<String>,
    /// The signal's value over time.
    pub function: Located<TimeFunctionInput>,
}

/// A point-to-point spring-damper: tension k (l − l₀) + c l̇ along the line joining its points.
#[derive(Clone, Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SpringInput {
    /// Unique spring name.
    pub name: Located<String>,
    /// First node (`ground` allowed).
    pub node_a: Located<String>,
    /// Second node (`ground` allowed).
    pub node_b: Located<String>,
    /// Attachment point on node A, global position in the initial configuration [m];
    /// default: the node's position.
    #[serde(default)]
    pub point_a: Option<[f64; 3]>,
    /// Attachment point on node B, global position in the initial configuration [m];
    /// default: the node's position.
    #[serde(default)]
    pub point_b: Option<[f64; 3]>,
    /// Axial stiffness k [N/m], non-negative.
    pub stiffness: f64,
    /// Axial viscous damping c [N s/m], non-negative; default 0.
    #[serde(default)]
    pub damping: Option<f64>,
    /// Rest length l₀ [m]; default: the initial distance between the points.
    #[serde(default)]
    pub rest_length: Option<f64>,
}

/// An applied force and/or moment on a node, scaled by a time function.
#[derive(Clone, Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ForceInput {
    /// Unique load name.
    pub name: Located<String>,
    /// The loaded node.
    pub node: Located<String>,
    /// Force vector [N], components in `frame`.
    #[serde(default)]
    pub force: Option<[f64; 3]>,
    /// Moment vector [N m], components in `frame`.
    #[serde(default)]
    pub moment: Option<[f64; 3]>,
    /// `global` (dead load, default) or `node` (follower load).
    #[serde(default)]
    pub frame: Option<LoadFrame>,
    /// Point of application of the force, global position in the initial configuration;
    /// it moves with the node. Default: the node.
    #[serde(default)]
    pub point: Option<[f64; 3]>,
    /// Time function multiplying force and moment; default constant 1.
    #[serde(default)]
    pub function: Option<Located<TimeFunctionInput>>,
}

/// Kinds of time function.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum TimeFunctionType {
    /// `value`.
    Constant,
    /// From `from` (default 0) at `start` linearly to `to` at `end`; constant outside.
    Ramp,
    /// `before` (default 0) for t < `time`, `after` for t ≥ `time`.
    Step,
    /// `offset` + `amplitude` sin(2π `frequency` (t − `start`) + `phase`), held at t = `start` before.
    Sine,
    /// Piecewise linear through `points` = [[t, f], …], constant beyond the ends.
    Table,
    /// Σ `coefficients`[k] (t − `start`)^k for t ≥ `start` (default 0), held before.
    Polynomial,
}

/// A scalar time function. `type` selects the kind; each kind uses the keys listed with it.
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TimeFunctionInput {
    /// Kind of function.
    #[serde(rename = "type")]
    pub kind: TimeFunctionType,
    /// constant: the value.
    #[serde(default)]
    pub value: Option<f64>,
    /// ramp: start time [s]; sine, polynomial: start time (default 0).
    #[serde(default)]
    pub start: Option<f64>,
    /// ramp: end time [s].
    #[serde(default)]
    pub end: Option<f64>,
    /// ramp: value at and before `start` (default 0).
    #[serde(default)]
    pub from: Option<f64>,
    /// ramp: value at and after `end`.
    #[serde(default)]
    pub to: Option<f64>,
    /// step: switching time [s].
    #[serde(default)]
    pub time: Option<f64>,
    /// step: value before `time` (default 0).
    #[serde(default)]
    pub before: Option<f64>,
    /// step: value from `time` on.
    #[serde(default)]
    pub after: Option<f64>,
    /// sine: amplitude.
    #[serde(default)]
    pub amplitude: Option<f64>,
    /// sine: frequency [Hz].
    #[serde(default)]
    pub frequency: Option<f64>,
    /// sine: phase [rad] (default 0).
    #[serde(default)]
    pub phase: Option<f64>,
    /// sine: offset (default 0).
    #[serde(default)]
    pub offset: Option<f64>,
    /// table: [[t, f], …] with strictly increasing t.
    #[serde(default)]
    pub points: Option<Vec<[f64; 2]>>,
    /// polynomial: c₀, c₁, … of Σ c_k (t − start)^k.
    #[serde(default)]
    pub coefficients: Option<Vec<f64>>,
}

/// Kinds of analysis.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum AnalysisType {
    /// Time integration with the Lie-group generalized-α method.
    Dynamic,
    /// Static equilibrium with load increments.
    Static,
}

/// When the iteration matrix is refactorized.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum JacobianUpdate {
    /// Every Newton iteration (full Newton).
    #[default]
    Full,
    /// Modified Newton: keep the factorization across iterations and steps while Newton
    /// contracts fast; refactor when it slows down, fails, or the step size changes.
    Modified,
}

/// How constraints enter the dynamic equations.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum FormulationType {
    /// Scaled index-3: position constraints with Lagrange multipliers. Needs some numerical
    /// dissipation (ρ∞ < 1) in constrained systems.
    #[default]
    Index3,
    /// Stabilized index-2 (Gear–Gupta–Leimkuhler): velocity constraints with λ and position
    /// constraints with projection multipliers. Stable for every ρ∞ in [0, 1], including 1.
    StabilizedIndex2,
}

/// An analysis. Keys not used by the chosen `type` are rejected.
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct AnalysisInput {
    /// Unique analysis name; also the results file name (`<name>.nc`).
    pub name: Located<String>,
    /// `dynamic` or `static`.
    #[serde(rename = "type")]
    pub kind: Located<AnalysisType>,
    /// Start from the final state of an earlier analysis of this model instead of the
    /// initial conditions written in the model.
    #[serde(default)]
    pub start_from: Option<Located<String>>,
    /// dynamic: start time [s] (default 0).
    #[serde(default)]
    pub t_start: Option<f64>,
    /// dynamic: end time [s].
    #[serde(default)]
    pub t_end: Option<f64>,
    /// dynamic: time step h [s].
    #[serde(default)]
    pub step: Option<f64>,
    /// dynamic: spectral radius at infinite frequency ρ∞ ∈ [0, 1] (default 0.9).
    #[serde(default)]
    pub rho_inf: Option<f64>,
    /// dynamic: smallest step allowed when steps are cut after Newton failures
    /// (default step/1024).
    #[serde(default)]
    pub min_step: Option<f64>,
    /// dynamic: write every n-th step (default 1).
    #[serde(default)]
    pub output_every: Option<usize>,
    /// dynamic: `full` (default) or `modified` Newton.
    #[serde(default)]
    pub jacobian: Option<JacobianUpdate>,
    /// dynamic: `index3` or `stabilized_index2`; default `index3` for ρ∞ < 1 and
    /// `stabilized_index2` for ρ∞ = 1 (index 3 without dissipation is unstable for
    /// constrained systems; Cardona & Géradin 1989).
    #[serde(default)]
    pub formulation: Option<FormulationType>,
    /// static: number of load increments (default 1).
    #[serde(default)]
    pub load_steps: Option<usize>,
    /// static: time at which time functions are evaluated (default 0).
    #[serde(default)]
    pub time: Option<f64>,
    /// dynamic: scale constraint rows and multipliers with βh² (default true). Turning it
    /// off is for conditioning studies. Not accepted in a static analysis (no step).
    #[serde(default)]
    pub scaling: Option<bool>,
    /// Augmented-Lagrangian penalty factor p ≥ 0 (default 1): the penalty is p times a
    /// characteristic mass (dynamic) or stiffness (static) of the model. Not accepted with
    /// the stabilized_index2 formulation (which has no penalty term).
    #[serde(default)]
    pub penalty: Option<f64>,
    /// Newton absolute tolerance on increments and constraint violations [m, rad]
    /// (default 1e-8).
    #[serde(default)]
    pub tolerance: Option<f64>,
    /// Newton relative tolerance on increments (default 1e-6).
    #[serde(default)]
    pub relative_tolerance: Option<f64>,
    /// Newton iteration limit per step (default 20).
    #[serde(default)]
    pub max_iterations: Option<usize>,
    /// Record per-step Newton iterations, residual norms and the iteration-matrix
    /// condition number (default false).
    #[serde(default)]
    pub diagnostics: Option<bool>,
    /// `auto` (default), `block` or `sparse_lu`.
    #[serde(default)]
    pub linear_solver: Option<LinearSolverType>,
}
