//! The model file, exactly as written: the TOML schema (serde) and its JSON Schema (schemars).
//!
//! These are the tables every model has (`[model]`, `[[nodes]]`, `[[analyses]]`) and the
//! shared value types; the component tables are in [`super::components`], whose registry
//! assembles [`ModelInput`]. These types carry no physics; validation checks them. Every key is documented in `docs/model-reference.md`; the doc
//! comments here become the descriptions of the JSON Schema printed by `samara schema`.

use super::located::Located;
pub use crate::elements::LoadFrame;
pub use crate::joints::JointType;
pub use crate::solve::LinearSolverType;
use schemars::JsonSchema;
use serde::Deserialize;

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
    /// Eigenanalysis of the equations linearized about the starting state.
    Modal,
    /// Campbell diagram: spinning statics and rotating-frame modes over a speed sweep.
    Campbell,
    /// Floquet stability of the periodic solution through the starting state.
    Floquet,
}

/// Eigensolver of a modal analysis.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum EigensolverType {
    /// Dense QZ up to 120 unconstrained unknowns, sparse shift-invert above.
    #[default]
    Auto,
    /// Null-space projection and dense QZ.
    Dense,
    /// Shift-invert Krylov–Schur with a sparse LU.
    Sparse,
}

/// When the iteration matrix is refactorized.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum JacobianUpdate {
    /// Every Newton iteration (full Newton).
    #[default]
    Full,
    /// Modified Newton: keep the factorization across iterations and steps while Newton
    /// contracts fast; refactor when it slows down, fails, or the step size changes. A
    /// step retried after a failure runs full Newton.
    Modified,
}

/// How a dynamic analysis's Newton iteration is shared out.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Partition {
    /// One part (default).
    #[default]
    None,
    /// Two parts and a separator (one level of nested dissection of the iteration
    /// matrix): each part's rows, assembly, elimination, substitutions and corrections on
    /// a thread of its own when the machine has two cores; the same results with one.
    TwoParts,
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

/// The time integrator of a dynamic analysis (docs/integrators.md).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum IntegratorType {
    /// Lie-group generalized-α with numerical dissipation ρ∞ (default).
    #[default]
    GeneralizedAlpha,
    /// Mid-point discrete-gradient scheme: energy and momenta conserved exactly (up to the
    /// Newton tolerance).
    EnergyPreserving,
    /// The preserving scheme with second-difference dissipation: second order, a discrete
    /// energy Ẽ = E + O(h²) that never increases in a step, high-frequency radius
    /// `rho_inf` ∈ [1/3, 1].
    EnergyDecaying,
}

impl IntegratorType {
    /// The smallest `rho_inf` the energy-decaying scheme reaches (its strongest
    /// dissipation: a double root of its linear-oscillator amplification).
    pub const DECAYING_MIN_RHO_INF: f64 = 1.0 / 3.0;
}

/// How a dynamic analysis chooses its steps.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum StepControlType {
    /// The given `step` (halved only after a Newton failure).
    #[default]
    Fixed,
    /// Steps chosen from a local error estimate to meet `tolerance_abs`/`tolerance_rel`.
    Adaptive,
}

/// An analysis. Keys not used by the chosen `type` are rejected.
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct AnalysisInput {
    /// Unique analysis name; also the results file name (`<name>.nc`).
    pub name: Located<String>,
    /// `dynamic`, `static` or `modal`.
    #[serde(rename = "type")]
    pub kind: Located<AnalysisType>,
    /// Start from the final state of an earlier analysis of this model instead of the
    /// initial conditions written in the model (`start_from = "name"`), or from the state
    /// of an earlier dynamic analysis at a time of its run
    /// (`start_from = { analysis = "name", time = t }`: the stored output nearest t).
    #[serde(default)]
    pub start_from: Option<Located<StartFromInput>>,
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
    /// dynamic: smallest step allowed when steps are cut after Newton failures or by the
    /// error control (default step/1024); also spelled `step_min` ([`KEY_SPELLINGS`]).
    #[serde(default, alias = "step_min")]
    pub min_step: Option<f64>,
    /// dynamic: `generalized_alpha` (default), `energy_preserving` or `energy_decaying`.
    #[serde(default)]
    pub integrator: Option<IntegratorType>,
    /// dynamic: `fixed` (default) or `adaptive` step sizes.
    #[serde(default)]
    pub step_control: Option<StepControlType>,
    /// dynamic, adaptive: absolute tolerance on the local error estimate [m, rad]
    /// (default 1e-6).
    #[serde(default)]
    pub tolerance_abs: Option<f64>,
    /// dynamic, adaptive: relative tolerance on the local error estimate (default 1e-4).
    #[serde(default)]
    pub tolerance_rel: Option<f64>,
    /// dynamic, adaptive: largest step [s] (default t_end − t_start).
    #[serde(default)]
    pub step_max: Option<f64>,
    /// dynamic, adaptive: land the steps on the zeros of the elements' event functions
    /// (a contact closing or opening) instead of stepping across them (default true).
    #[serde(default)]
    pub event_location: Option<bool>,
    /// dynamic: write every n-th step (default 1).
    #[serde(default)]
    pub output_every: Option<usize>,
    /// dynamic: write at t_start + kΔ for this interval Δ [s] (and at t_end), the steps
    /// landing on those instants; instead of `output_every`.
    #[serde(default)]
    pub output_interval: Option<f64>,
    /// dynamic: `full` (default) or `modified` Newton.
    #[serde(default)]
    pub jacobian: Option<JacobianUpdate>,
    /// dynamic: `none` (default) or `two_parts`.
    #[serde(default)]
    pub partition: Option<Partition>,
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
    /// modal: number of modes (default 10).
    #[serde(default)]
    pub n_modes: Option<Located<usize>>,
    /// modal: frequency [Hz] near which the modes are wanted (default: the lowest).
    #[serde(default)]
    pub shift: Option<f64>,
    /// modal: also write M, G, K and B (Matrix Market) next to the results (default false).
    #[serde(default)]
    pub write_matrices: Option<bool>,
    /// modal: `auto` (default), `dense` or `sparse`.
    #[serde(default)]
    pub eigensolver: Option<EigensolverType>,
    /// modal: linearize in the frame turning at `omega` [rad/s] about `axis` through
    /// `centre` (default the origin); the starting state is set spinning rigidly.
    /// static: spinning-rotor statics, the model (or the nodes, beams and bodies named in
    /// `parts`) turning steadily at `omega`.
    #[serde(default)]
    pub rotation: Option<RotationInput>,
    /// campbell: rotor speeds [rad/s], a list or `{ start, end, count }` (evenly spaced).
    #[serde(default)]
    pub speeds: Option<SpeedsInput>,
    /// Floquet: the period T of the periodic solution [s] (or give `speed`).
    #[serde(default)]
    pub period: Option<f64>,
    /// Floquet: the rotor speed Ω [rad/s]; the period is T = 2π/|Ω|.
    #[serde(default)]
    pub speed: Option<f64>,
    /// Floquet: generalized-α steps per period (default 100).
    #[serde(default)]
    pub steps_per_period: Option<usize>,
}

/// Where an analysis starts: an earlier analysis's final state, or its state at a time.
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(
    untagged,
    expecting = "an earlier analysis's name, or { analysis = \"name\", time = t }"
)]
pub enum StartFromInput {
    /// The final state of the named analysis.
    Name(String),
    /// The state of the named dynamic analysis at `time` [s] (the stored output nearest
    /// it).
    At { analysis: String, time: f64 },
}

impl StartFromInput {
    /// The analysis named.
    pub fn analysis(&self) -> &str {
        match self {
            Self::Name(n) | Self::At { analysis: n, .. } => n,
        }
    }

    /// The time asked for, if any.
    pub fn time(&self) -> Option<f64> {
        match self {
            Self::Name(_) => None,
            Self::At { time, .. } => Some(*time),
        }
    }
}

/// The speeds of a Campbell analysis.
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(untagged)]
pub enum SpeedsInput {
    List(Vec<f64>),
    Range { start: f64, end: f64, count: usize },
}

/// A steady rotation: `{ axis = [x, y, z], omega = Ω, centre = [x, y, z] }`.
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RotationInput {
    /// Direction of the rotation axis (normalized; right-hand rule).
    pub axis: [f64; 3],
    /// Angular speed [rad/s] (required, except in a Campbell analysis, which takes its
    /// speeds from `speeds`).
    #[serde(default)]
    pub omega: Option<f64>,
    /// A point of the axis [m] (default the origin).
    #[serde(default)]
    pub centre: Option<[f64; 3]>,
    /// static: names of the nodes, beams and bodies that turn (default: every node).
    #[serde(default)]
    pub parts: Option<Vec<Located<String>>>,
}

/// The keys of a model file with a second spelling (the serde aliases above), canonical
/// name first: messages name and locate the spelling the user wrote.
pub const KEY_SPELLINGS: &[&[&str]] = &[MIN_STEP_SPELLINGS];

/// `min_step` and its alias.
pub const MIN_STEP_SPELLINGS: &[&str] = &["min_step", "step_min"];
