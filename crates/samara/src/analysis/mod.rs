//! Analyses: each owns its Newton loop and, for dynamics, the integrator.
//!
//! Analyses see the system only through the assembler (residual and iteration matrix) and
//! the state; they never know element types. Results leave through a [`Recorder`].

pub mod campbell;
pub mod chain;
pub mod check;
mod dynamic;
pub mod energy_preserving;
pub mod events;
pub mod floquet;
pub mod generalized_alpha;
mod history;
mod initial;
pub mod modal;
mod moment_neutral;
mod output_grid;
mod sparse_differences;
mod stage;
mod statics;
mod trend_feedback;

pub use chain::{Capture, Chain};
pub use check::check_analyses;
pub use dynamic::{Simulation, StepReport, run_dynamic};
pub use generalized_alpha::{FirstOrderAlpha, GeneralizedAlpha};
pub use history::{Frame, History};
pub use initial::{
    AssemblyError, AssemblyReport, assemble_initial_state, consistent_accelerations,
};
pub use modal::run_modal;
pub use stage::{
    Analysis, ArraySpec, CampbellAnalysis, DynamicAnalysis, FloquetAnalysis, ModalAnalysis,
    StaticAnalysis,
};
pub use statics::run_static;

use crate::model::{AnalysisDef, Model};
use crate::solve::condition::ConditionKind;
use crate::system::{Assembler, BlockOwner, State, System};
use std::time::Duration;

/// Energy bookkeeping at one output time.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Energy {
    pub kinetic: f64,
    /// Gravity and springs.
    pub potential: f64,
    /// Work done by applied loads since the start of the analysis.
    pub external_work: f64,
    /// Energy dissipated by dampers since the start of the analysis.
    pub dissipated: f64,
}

/// Per-step solver diagnostics.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepDiagnostics {
    pub newton_iterations: usize,
    /// Euclidean norm of the (scaled) residual at the last Newton evaluation.
    pub residual_norm: f64,
    /// Weighted correction norm of the last Newton iteration (≤ 1 at convergence).
    pub correction_norm: f64,
    pub condition: f64,
    pub condition_kind: ConditionKind,
    pub step_size: f64,
    /// Adaptive steps: the local error estimate relative to the tolerance (≤ 1); NaN for
    /// fixed steps.
    pub error_estimate: f64,
    /// Adaptive steps: attempts rejected by the error control before this step.
    pub rejected: usize,
    /// Newton corrections the line search halved in this step (granular models).
    pub line_search_backtracks: usize,
}

/// Everything written at one output time.
pub struct OutputFrame<'a> {
    pub time: f64,
    pub state: &'a State,
    /// Augmented multipliers μ = λ + ρΦ in physical units, per constraint row.
    pub mu: &'a [f64],
    pub energy: Energy,
    /// max |Φ| over all constraint equations.
    pub constraint_violation: f64,
    /// Static analyses: the load factor; dynamics: 1.
    pub load_factor: f64,
    pub diagnostics: Option<StepDiagnostics>,
}

/// Receives the results of an analysis as they are computed.
pub trait Recorder {
    /// One time record.
    fn record(&mut self, sys: &System, frame: &OutputFrame) -> Result<(), crate::Error>;
    /// The values of an array declared by the analysis ([`Analysis::arrays`]).
    fn write_array(
        &mut self,
        sys: &System,
        spec: &ArraySpec,
        values: &[f64],
    ) -> Result<(), crate::Error>;
    /// The folder of the results, where an analysis may write files of its own (a modal
    /// analysis's matrices); `None` for recorders that keep results in memory.
    fn output_dir(&self) -> Option<std::path::PathBuf> {
        None
    }
}

/// Why an analysis stopped early.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("analysis '{analysis}' failed at t = {time}: {reason}")]
pub struct SolverFailure {
    pub analysis: String,
    pub time: f64,
    pub reason: String,
    pub hint: Option<String>,
}

/// What an analysis did.
#[derive(Clone, Debug)]
pub struct AnalysisSummary {
    pub name: String,
    pub kind: &'static str,
    /// Accepted steps (load steps for statics).
    pub steps: usize,
    pub newton_iterations: usize,
    pub rejected_steps: usize,
    pub factorizations: usize,
    /// Factorizations that needed the pivoting sparse LU.
    pub fallbacks: usize,
    pub wall_time: Duration,
    pub final_state: State,
    pub max_constraint_violation: f64,
    /// What the initial assembly moved (analyses that start from the model's state).
    pub assembly: Option<AssemblyReport>,
    pub warnings: Vec<String>,
    /// Set when the analysis stopped before its end.
    pub failure: Option<SolverFailure>,
    /// Granular sets: steps redone because a pair came into contact outside the
    /// candidate set, times the candidate set changed (pattern and symbolic
    /// factorization rebuilt), and the largest number of candidate pairs.
    pub contact_redos: usize,
    pub pattern_rebuilds: usize,
    pub max_candidate_pairs: usize,
    /// Newton corrections halved by the line search, over the accepted steps.
    pub line_search_backtracks: usize,
    /// `partition = "two_parts"` taken: the blocks of each part and of the separator.
    pub parts: Option<PartsReport>,
}

/// How a two-part run shared out its iteration ([`crate::model::Partition::TwoParts`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PartsReport {
    /// Blocks of part 0, of part 1 and of the separator.
    pub blocks: [usize; 3],
    /// Whether part 1 ran on a partner thread (rayon had a second thread).
    pub partner_thread: bool,
}

impl AnalysisSummary {
    /// An analysis that has not taken a step yet.
    pub fn new(name: &str, kind: &'static str) -> Self {
        Self {
            name: name.to_string(),
            kind,
            steps: 0,
            newton_iterations: 0,
            rejected_steps: 0,
            factorizations: 0,
            fallbacks: 0,
            wall_time: Duration::ZERO,
            final_state: State::default(),
            max_constraint_violation: 0.0,
            assembly: None,
            warnings: Vec::new(),
            failure: None,
            contact_redos: 0,
            pattern_rebuilds: 0,
            max_candidate_pairs: 0,
            line_search_backtracks: 0,
            parts: None,
        }
    }
}

/// Progress callback: fraction of the analysis done, in [0, 1].
pub type Progress<'a> = &'a mut dyn FnMut(f64);

/// Runs one analysis from `initial`.
pub fn run_analysis(
    sys: &System,
    def: &AnalysisDef,
    initial: State,
    recorder: &mut dyn Recorder,
    progress: Progress,
) -> Result<AnalysisSummary, crate::Error> {
    let mut summary = def.stage().run(sys, initial, recorder, progress)?;
    // An element whose loads could not be evaluated (a wind sampled outside its box)
    // explains the failure better than the solver's symptom.
    if let Some(f) = &mut summary.failure
        && let Some((why, hint)) = sys.elements.iter().find_map(|e| e.runtime_error())
    {
        f.hint = Some(format!("{hint} (the solver reported: {})", f.reason));
        f.reason = why;
    }
    Ok(summary)
}

/// Runs every analysis of a model in order, chaining `start_from` ([`Chain`]). `make_recorder` is
/// called once per analysis.
pub fn run_all<R: Recorder>(
    model: &Model,
    sys: &System,
    mut make_recorder: impl FnMut(&AnalysisDef) -> Result<R, crate::Error>,
    mut progress: impl FnMut(&AnalysisDef, f64),
) -> Result<Vec<(AnalysisSummary, R)>, crate::Error> {
    let mut out: Vec<(AnalysisSummary, R)> = Vec::new();
    let mut chain = Chain::new(model);
    for (index, def) in model.analyses.iter().enumerate() {
        let mut rec = make_recorder(def)?;
        let initial = match chain.start(sys, def) {
            Ok(state) => state,
            // Only a `start_from.time` with no record near it gets here (analyses run in
            // order and the loop stops at the first failure, so the analysis named has
            // run). Reported as a failure, so the results before it are kept.
            Err(e) => {
                let mut summary = AnalysisSummary::new(&def.name, def.type_name());
                summary.failure = Some(SolverFailure {
                    analysis: def.name.clone(),
                    time: def.start_time.unwrap_or_else(|| sys.initial_state().time),
                    reason: e.to_string(),
                    hint: Some("check `start_from`".into()),
                });
                out.push((summary, rec));
                break;
            }
        };
        let mut p = |f: f64| progress(def, f);
        let mut capture = chain.capture(index, &mut rec);
        let summary = run_analysis(sys, def, initial, &mut capture, &mut p)?;
        chain.finish(index, capture, summary.final_state.clone());
        let failed = summary.failure.is_some();
        out.push((summary, rec));
        if failed {
            break;
        }
    }
    Ok(out)
}

/// Runs the initial assembly (positions and velocities onto the joints) and records its
/// report and warnings in `summary`; on failure records it at time `t` and returns false.
#[allow(clippy::too_many_arguments)]
pub(crate) fn assemble_start(
    sys: &System,
    state: &mut State,
    ctx: &crate::core::EvalContext,
    tolerance: f64,
    asm: &mut crate::system::Assembler,
    lin: &mut crate::solve::LinearSolver,
    matrix: &mut crate::solve::BlockMatrix,
    summary: &mut AnalysisSummary,
    t: f64,
) -> bool {
    match assemble_initial_state(sys, state, ctx, tolerance, asm, lin, matrix) {
        Ok(report) => {
            summary
                .warnings
                .extend(assembly_warnings(sys, &report, tolerance));
            summary.assembly = Some(report);
            true
        }
        Err(e) => {
            summary.failure = Some(SolverFailure {
                analysis: summary.name.clone(),
                time: t,
                reason: format!("cannot assemble the initial configuration: {e}"),
                hint: Some("check the joint positions and axes, the drives' values at the start, and that the mechanism can reach them".into()),
            });
            false
        }
    }
}

/// Warnings for nodes the initial assembly moved by more than the tolerance.
pub(crate) fn assembly_warnings(sys: &System, r: &AssemblyReport, tol: f64) -> Vec<String> {
    let mut out = Vec::new();
    if r.violation_before <= tol {
        return out;
    }
    let mut moved: Vec<String> = r
        .moved
        .iter()
        .enumerate()
        .filter(|(_, (d, a))| *d > tol || *a > tol)
        .map(|(i, (d, a))| format!("'{}' by {d:.3e} m and {a:.3e} rad", sys.node_names[i]))
        .collect();
    let total = moved.len();
    moved.truncate(10);
    out.push(format!(
        "the initial configuration violated the joints by up to {:.3e}; the assembly ({} iteration{}) moved {} node{}: {}{}",
        r.violation_before,
        r.iterations,
        if r.iterations == 1 { "" } else { "s" },
        total,
        if total == 1 { "" } else { "s" },
        moved.join(", "),
        if total > 10 { ", …" } else { "" }
    ));
    out
}

/// The first quantity of `state` or `energy` that is not finite, named for a message.
pub(crate) fn first_non_finite(sys: &System, state: &State, energy: &Energy) -> Option<String> {
    let bad = |v: &[f64]| !v.iter().all(|x| x.is_finite());
    for (i, n) in state.nodes.iter().enumerate() {
        let q = n.rot.quaternion();
        let parts: [(&str, &[f64]); 6] = [
            ("position", n.x.as_slice()),
            ("orientation", q.coords.as_slice()),
            ("velocity", n.v.as_slice()),
            ("angular velocity", n.w.as_slice()),
            ("acceleration", n.a.as_slice()),
            ("angular acceleration", n.wd.as_slice()),
        ];
        if let Some((what, _)) = parts.iter().find(|(_, v)| bad(v)) {
            return Some(format!("the {what} of node '{}'", sys.node_names[i]));
        }
    }
    if let Some(j) = state
        .coords
        .iter()
        .position(|c| !(c.q.is_finite() && c.v.is_finite() && c.a.is_finite()))
    {
        let name = sys.coordinate_names.get(j).map_or("?", |s| s.as_str());
        return Some(format!("joint coordinate '{name}'"));
    }
    if bad(&state.lambda) {
        return Some("a joint reaction (Lagrange multiplier)".into());
    }
    let e = [
        ("kinetic energy", energy.kinetic),
        ("potential energy", energy.potential),
        ("external work", energy.external_work),
        ("dissipated energy", energy.dissipated),
    ];
    e.iter()
        .find(|(_, x)| !x.is_finite())
        .map(|(what, x)| format!("the {what} ({x})"))
}

/// The failure of an analysis whose state left an element's range
/// ([`System::range_violation`]).
pub(crate) fn range_failure(analysis: &str, time: f64, what: String) -> SolverFailure {
    SolverFailure {
        analysis: analysis.to_string(),
        time,
        reason: what,
        hint: Some("extend the table to cover the motion (or shorten `t_end`)".into()),
    }
}

/// The failure of an analysis whose state stopped being finite.
pub(crate) fn non_finite_failure(analysis: &str, time: f64, what: String) -> SolverFailure {
    SolverFailure {
        analysis: analysis.to_string(),
        time,
        reason: format!("{what} is not finite"),
        hint: Some("the numbers overflowed: check units and magnitudes (masses, stiffnesses, loads, initial velocities), or reduce `step`".into()),
    }
}

/// A hint for a Newton failure, naming the block where the matrix is singular.
pub(crate) fn singular_hint(sys: &System, asm: &Assembler, block: usize) -> String {
    let what = asm.block_name(sys, block);
    match asm.block_owner(block) {
        Some(BlockOwner::Node(_)) => format!(
            "the iteration matrix is singular at {what}: some direction of that node has no mass, stiffness or constraint (a free massless node, or a mechanism in a static analysis)"
        ),
        Some(BlockOwner::States(_)) => format!(
            "the iteration matrix is singular at {what}: its state equations do not determine the states"
        ),
        _ => format!(
            "the iteration matrix is singular at {what}: its constraint equations are dependent (redundant joints) or its nodes cannot move in the constrained directions"
        ),
    }
}
