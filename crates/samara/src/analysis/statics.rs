//! Static equilibrium `r(q) + Bᵀμ = 0`, `Φ(q) = 0` with load continuation: loads and
//! gravity are scaled by the load factor λ_k = k/n, k = 1…n, each increment solved by
//! Newton from the previous equilibrium; an increment that fails is bisected.
//!
//! **Spinning-rotor statics** (`rotation`, [`crate::linear::Spin`]): the spinning nodes
//! carry the rates of the steady rotation at every iterate (`v = Ω × (x − c)`,
//! `a = Ω × v`, `w = RᵀΩ`), so the residual holds their centrifugal and gyroscopic
//! inertial loads, and the tangent holds `C A_v + M A₀` besides K (the same terms as the
//! rotating-frame linearization, so Newton converges quadratically and a modal analysis
//! started from the result finds it in equilibrium). The speed follows the load factor as
//! `Ω√λ`, so the centrifugal loads grow in proportion to λ like the other loads; the
//! final state keeps the rates of the rotation at full speed.

use super::{
    AnalysisSummary, Energy, OutputFrame, Progress, Recorder, SolverFailure, StepDiagnostics,
    singular_hint,
};
use crate::core::EvalContext;
use crate::linear::Spin;
use crate::model::StaticSettings;
use crate::solve::condition::condition_number;
use crate::solve::newton::{Correction, NewtonWork, newton};
use crate::solve::{BlockMatrix, LinearSolver, NewtonFailure, NewtonSettings, NewtonSystem};
use crate::system::{Assembler, Coefficients, Formulation, RateMaps, State, System};
use nalgebra::Vector3;
use std::time::Instant;

/// Smallest load increment, as a fraction of the nominal one, before giving up.
const MIN_INCREMENT_FRACTION: f64 = 1.0 / 1024.0;

struct StaticProblem<'a> {
    sys: &'a System,
    asm: &'a mut Assembler,
    state: &'a mut State,
    /// Accumulated configuration increment in this load step (reference for rtol).
    total: &'a mut [f64],
    /// Configuration and multiplier parts of the current correction.
    dcfg: &'a mut [f64],
    dlam: &'a mut [f64],
    phi: &'a mut [f64],
    ctx: EvalContext,
    coef: Coefficients,
    atol: f64,
    rtol: f64,
    /// The spinning nodes and the speed of this increment, with scratch for the maps.
    spin: Option<(&'a Spin, f64)>,
    maps: &'a mut Vec<RateMaps>,
}

impl NewtonSystem for StaticProblem<'_> {
    fn evaluate(&mut self, residual: &mut [f64], matrix: Option<&mut BlockMatrix>) {
        if let Some((spin, omega)) = self.spin {
            spin.impose(self.sys, self.state, omega);
            spin.rate_maps(self.state, omega, self.maps);
            self.asm.set_rate_maps(self.maps);
        }
        self.asm.assemble(
            self.sys,
            self.state,
            &self.ctx,
            &self.coef,
            &[],
            residual,
            matrix,
        );
    }

    fn apply(&mut self, delta: &[f64]) -> Correction {
        self.asm.configuration_of(self.sys, delta, self.dcfg);
        for (i, n) in self.state.nodes.iter_mut().enumerate() {
            let d = &self.dcfg[6 * i..6 * i + 6];
            n.x += Vector3::new(d[0], d[1], d[2]);
            n.rot = n.rot.compose_exp(&Vector3::new(d[3], d[4], d[5]));
        }
        let n6 = 6 * self.state.nodes.len();
        let nc = self.sys.n_coordinates;
        for (c, d) in self.state.coords.iter_mut().zip(&self.dcfg[n6..n6 + nc]) {
            c.q += d;
        }
        for (z, d) in self.state.states.iter_mut().zip(&self.dcfg[n6 + nc..]) {
            z.z += d;
        }
        let mut worst: f64 = 0.0;
        for (t, d) in self.total.iter_mut().zip(self.dcfg.iter()) {
            *t += d;
            worst = worst.max(d.abs() / (self.atol + self.rtol * t.abs()));
        }
        self.asm.multipliers_of(self.sys, delta, self.dlam);
        for (l, d) in self.state.lambda.iter_mut().zip(self.dlam.iter()) {
            *l += d;
        }
        Correction::new(worst, self.dlam, &self.state.lambda, self.rtol)
    }

    fn constraint_violation(&mut self) -> f64 {
        self.sys.constraint_values(&self.ctx, self.state, self.phi);
        self.phi.iter().fold(0.0, |m, x| m.max(x.abs()))
    }
}

/// Characteristic stiffness: mean |diagonal| of the unconstrained stiffness at `state`.
fn characteristic_stiffness(
    sys: &System,
    asm: &mut Assembler,
    state: &State,
    ctx: &EvalContext,
    matrix: &mut BlockMatrix,
) -> f64 {
    let mut r = vec![0.0; asm.n_unknowns()];
    asm.assemble(
        sys,
        state,
        ctx,
        &Coefficients::statics(0.0),
        &[],
        &mut r,
        Some(matrix),
    );
    let mut sum = 0.0;
    let mut count = 0;
    for i in 0..sys.n_nodes() {
        if let Some(b) = matrix.block(i, i) {
            for k in 0..6 {
                sum += b[7 * k].abs();
                count += 1;
            }
        }
    }
    if count > 0 && sum > 0.0 {
        sum / count as f64
    } else {
        1.0
    }
}

/// Multipliers that best balance the current residual, `λ = argmin |r + Bᵀλ|` under
/// `B δq = 0` (the projection with the identity metric): solves
/// `[I Bᵀ; B 0] [δq; Δλ] = [−(r + Bᵀλ); 0]` and keeps Δλ.
///
/// Newton for statics starts every increment from these, so the geometric stiffness of
/// loaded joints (`∂(Bᵀλ)/∂q`, e.g. a pendulum's restoring stiffness m g L) is present from
/// the first iteration; with λ = 0 the iteration matrix of a hanging mechanism is singular.
fn least_squares_multipliers(
    sys: &System,
    asm: &mut Assembler,
    state: &mut State,
    ctx: &EvalContext,
    lin: &mut LinearSolver,
    matrix: &mut BlockMatrix,
    work: &mut NewtonWork,
) {
    if sys.n_multipliers == 0 {
        return;
    }
    let coef = Coefficients {
        stiffness: 0.0,
        ..Coefficients::statics(0.0)
    };
    asm.assemble(
        sys,
        state,
        ctx,
        &coef,
        &[],
        &mut work.residual,
        Some(matrix),
    );
    asm.add_configuration_metric(sys, matrix, &[1.0; 6], 1.0);
    for (d, r) in work.delta.iter_mut().zip(&work.residual) {
        *d = -r;
    }
    for k in 0..sys.constraints.len() {
        work.delta[asm.multiplier_range(k)].fill(0.0);
    }
    if lin.factor(matrix).is_err() {
        return; // dependent constraints: Newton reports the singular block
    }
    lin.solve_in_place(&mut work.delta);
    if work.delta.iter().all(|x| x.is_finite()) {
        let mut dl = vec![0.0; sys.n_multipliers];
        asm.multipliers_of(sys, &work.delta, &mut dl);
        for (l, d) in state.lambda.iter_mut().zip(&dl) {
            *l += d;
        }
    }
    lin.invalidate();
}

/// Solves the static equilibrium in `settings.load_steps` increments.
pub fn run_static(
    sys: &System,
    name: &str,
    settings: &StaticSettings,
    mut state: State,
    recorder: &mut dyn Recorder,
    progress: Progress,
) -> Result<AnalysisSummary, crate::Error> {
    let clock = Instant::now();
    for nd in &mut state.nodes {
        nd.v = Vector3::zeros();
        nd.w = Vector3::zeros();
        nd.a = Vector3::zeros();
        nd.wd = Vector3::zeros();
    }
    for c in &mut state.coords {
        c.v = 0.0;
        c.a = 0.0;
    }
    for z in &mut state.states {
        z.zd = 0.0;
    }
    // Nothing is sampled in statics: a sample-and-hold passes its input through.
    state.held = Box::default();
    state.time = settings.time;
    let mut asm = Assembler::new(sys, Formulation::Index3);
    let mut lin = LinearSolver::new(asm.structure(), settings.solver.linear_solver);
    let mut matrix = BlockMatrix::zeros(asm.structure().clone());
    let mut work = NewtonWork::new(asm.n_unknowns());
    let mut phi = vec![0.0; sys.n_multipliers];
    let mut total = vec![0.0; sys.n_config()];
    let mut dcfg = vec![0.0; sys.n_config()];
    let mut dlam = vec![0.0; sys.n_multipliers];
    let mut mu = vec![0.0; sys.n_multipliers];
    let mut summary = AnalysisSummary::new(name, "static");
    let ctx_full = sys.context(settings.time, 1.0);
    if !super::assemble_start(
        sys,
        &mut state,
        &ctx_full,
        settings.solver.tolerance,
        &mut asm,
        &mut lin,
        &mut matrix,
        &mut summary,
        0.0,
    ) {
        summary.final_state = state;
        summary.wall_time = clock.elapsed();
        return Ok(summary);
    }
    // Assembly left velocities consistent with the drives; statics has none.
    for nd in &mut state.nodes {
        nd.v = Vector3::zeros();
        nd.w = Vector3::zeros();
    }
    for c in &mut state.coords {
        c.v = 0.0;
    }
    let penalty = settings.solver.penalty
        * characteristic_stiffness(sys, &mut asm, &state, &ctx_full, &mut matrix);
    let newton_settings = NewtonSettings {
        max_iterations: settings.solver.max_iterations,
        constraint_tolerance: settings.solver.tolerance,
        reuse_jacobian: false,
        line_search: false,
    };
    // The first record is the unloaded state (load factor 0): the assembled reference
    // configuration, reactions as the least-squares multipliers there.
    {
        let ctx0 = sys.context(settings.time, 0.0);
        least_squares_multipliers(
            sys,
            &mut asm,
            &mut state,
            &ctx0,
            &mut lin,
            &mut matrix,
            &mut work,
        );
        sys.update_passive_coordinates(&mut state, true);
        let energy = Energy {
            kinetic: 0.0,
            potential: sys.potential_energy(&ctx0, &state),
            external_work: 0.0,
            dissipated: 0.0,
        };
        let violation = summary.assembly.as_ref().map_or(0.0, |r| r.violation_after);
        summary.max_constraint_violation = violation;
        if let Some(what) = super::first_non_finite(sys, &state, &energy) {
            summary.failure = Some(super::non_finite_failure(name, 0.0, what));
            summary.final_state = state;
            summary.wall_time = clock.elapsed();
            return Ok(summary);
        }
        mu.copy_from_slice(&state.lambda);
        let diag = settings.solver.diagnostics.then_some(StepDiagnostics {
            newton_iterations: 0,
            residual_norm: 0.0,
            correction_norm: 0.0,
            condition: f64::NAN,
            condition_kind: crate::solve::condition::ConditionKind::Exact2Norm,
            step_size: 0.0,
            error_estimate: f64::NAN,
            rejected: 0,
            line_search_backtracks: 0,
        });
        recorder.record(
            sys,
            &OutputFrame {
                time: 0.0,
                state: &state,
                mu: &mu,
                energy,
                constraint_violation: violation,
                load_factor: 0.0,
                diagnostics: diag,
            },
        )?;
    }
    let spin = settings.rotation.as_ref();
    let speed = |lf: f64| spin.map_or(0.0, |s| s.rotation.omega * lf.max(0.0).sqrt());
    let mut maps = Vec::new();
    let nominal = 1.0 / settings.load_steps as f64;
    let mut lf = 0.0;
    let mut inc = nominal;
    let mut saved = state.clone();
    while lf < 1.0 - 1e-12 {
        let target = (lf + inc).min(1.0);
        let ctx = sys.context(settings.time, target);
        saved.clone_from(&state);
        total.fill(0.0);
        if let Some(s) = spin {
            s.impose(sys, &mut state, speed(target));
        }
        least_squares_multipliers(
            sys,
            &mut asm,
            &mut state,
            &ctx,
            &mut lin,
            &mut matrix,
            &mut work,
        );
        let mut problem = StaticProblem {
            sys,
            asm: &mut asm,
            state: &mut state,
            total: &mut total,
            dcfg: &mut dcfg,
            dlam: &mut dlam,
            phi: &mut phi,
            ctx,
            coef: Coefficients::statics(penalty),
            atol: settings.solver.tolerance,
            rtol: settings.solver.relative_tolerance,
            spin: spin.map(|s| (s, speed(target))),
            maps: &mut maps,
        };
        match newton(
            &mut problem,
            &mut lin,
            &mut matrix,
            &mut work,
            &newton_settings,
        ) {
            Ok(report) => {
                sys.update_passive_coordinates(&mut state, true);
                if let Some(s) = spin {
                    s.impose(sys, &mut state, speed(target));
                }
                lf = target;
                summary.steps += 1;
                summary.newton_iterations += report.iterations;
                summary.max_constraint_violation = summary
                    .max_constraint_violation
                    .max(report.constraint_violation);
                for ((m, l), p) in mu.iter_mut().zip(&state.lambda).zip(&phi) {
                    *m = l + penalty * p;
                }
                let diag = settings.solver.diagnostics.then(|| {
                    let (c, kind) = condition_number(&matrix, &mut lin);
                    StepDiagnostics {
                        newton_iterations: report.iterations,
                        residual_norm: report.last_residual,
                        correction_norm: report.last_correction,
                        condition: c,
                        condition_kind: kind,
                        step_size: target - (target - inc).max(0.0),
                        error_estimate: f64::NAN,
                        rejected: 0,
                        line_search_backtracks: report.backtracks,
                    }
                });
                let energy = Energy {
                    kinetic: if spin.is_some() {
                        sys.kinetic_energy(&state)
                    } else {
                        0.0
                    },
                    potential: sys.potential_energy(&ctx, &state),
                    external_work: 0.0,
                    dissipated: 0.0,
                };
                state.time = settings.time;
                if let Some(what) = super::first_non_finite(sys, &state, &energy) {
                    summary.failure = Some(super::non_finite_failure(name, lf, what));
                    break;
                }
                recorder.record(
                    sys,
                    &OutputFrame {
                        time: lf,
                        state: &state,
                        mu: &mu,
                        energy,
                        constraint_violation: report.constraint_violation,
                        load_factor: lf,
                        diagnostics: diag,
                    },
                )?;
                progress(lf);
                inc = (2.0 * inc).min(nominal);
            }
            Err(failure) => {
                summary.rejected_steps += 1;
                state.clone_from(&saved);
                inc /= 2.0;
                if inc < nominal * MIN_INCREMENT_FRACTION {
                    let hint = match &failure {
                        NewtonFailure::Singular { block } => Some(singular_hint(sys, &asm, *block)),
                        _ => Some(
                            "more `load_steps`, a larger `tolerance`, or a check of the model's stiffness may help".into(),
                        ),
                    };
                    summary.failure = Some(SolverFailure {
                        analysis: name.to_string(),
                        time: lf,
                        reason: format!("{failure} (load factor {lf:.4} → {target:.4})"),
                        hint,
                    });
                    break;
                }
            }
        }
    }
    summary.factorizations = lin.stats.factorizations;
    summary.fallbacks = lin.stats.fallbacks;
    summary.final_state = state;
    summary.wall_time = clock.elapsed();
    Ok(summary)
}
