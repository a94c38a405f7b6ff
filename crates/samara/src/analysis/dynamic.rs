//! Time integration with the Lie-group generalized-α method on (R³ × SO(3))ᴺ, scaled
//! index-3 constraints, Newton–Raphson per step, and step cutting on Newton failure.

use super::generalized_alpha::{FirstOrderAlpha, GeneralizedAlpha};
use super::initial::consistent_accelerations;
use super::trend_feedback::TrendFeedback;
use super::{
    AnalysisSummary, Energy, OutputFrame, Progress, Recorder, SolverFailure, StepDiagnostics,
    singular_hint,
};
use crate::core::{EvalContext, NodeState};
use crate::math::isa;
use crate::math::tangent_operator;
use crate::model::{DynamicSettings, FormulationType, IntegratorType, JacobianUpdate};
use crate::solve::condition::condition_number;
use crate::solve::newton::{Correction, NewtonWork, newton};
use crate::solve::{
    BlockMatrix, LinearError, LinearSolver, NewtonFailure, NewtonReport, NewtonSettings,
    NewtonSystem, PartSlice,
};
use crate::system::{Assembler, Coefficients, Formulation, State, System};
use nalgebra::{Matrix3, Vector3};
use std::time::Instant;

/// Consecutive successful steps after a cut before the step is doubled again.
const REGROW_AFTER: usize = 4;

/// Relative difference of step sizes below which a factorization made for one serves the
/// other (modified Newton): the steps of a fixed grid, `t0 + (k+1)·step − t_k`, differ in
/// their last bits from step to step, and a matrix is never exact for the iterate anyway.
const SAME_STEP: f64 = 1e-9;

/// Whether a matrix assembled for the step `factored` still serves the step `h`.
fn same_step(h: f64, factored: f64) -> bool {
    (h - factored).abs() <= SAME_STEP * h
}

/// How a step's first Newton iterate is predicted (λ_{n+1} = λ_n always).
///
/// - `Extrapolate`: v̇_{n+1} = v̇_n, exact for constant accelerations — the best guess for
///   motion the step resolves.
/// - `Trend`: v̇_{n+1} = v̇_n + r (v̇_n − v̇_{n−1}) (ż likewise; r = h_{n+1}/h_n): linear
///   extrapolation of the accelerations from the last two steps, exact for linearly
///   varying accelerations. For motion the step resolves (ω h ≪ 1) its error in hΔq is
///   O(h⁴ q⁗) against O(h³ q⃛) for `Extrapolate`, so the first correction starts smaller
///   by about ω h. (With λ held, a reused matrix's first correction leaves an error of the
///   size of λ's change over the step, which the second removes; modified Newton reads
///   that as slow contraction and refactorizes: the pendulum of tests/options.rs takes
///   152 factorizations instead of 48 at tolerance 1e-10. Extrapolating λ like the
///   accelerations restores the 48, but costs the chain benchmark 4 % and broke the
///   landing gear's last, 1.6e-12 s step; not used.)
/// - `Repeat`: the configuration increment of the previous step again (scaled by the step
///   ratio), i.e. a velocity taken from positions.
/// - `Hold`: q_{n+1} = q_n.
///
/// v and v̇ follow from the scheme for the predicted increment in every case. Modes the
/// step does not resolve (ωh ≫ 1: the element-scale modes of a fine beam mesh after a
/// sudden load) are computed quasi-statically in q, but with ρ∞ near 1 their algorithmic
/// v and v̇ keep ringing at O(h f/m); extrapolating them can throw the first iterate by an
/// element length, out of Newton's basin (measured: 25 step cuts in the 1,000-element
/// cantilever benchmark). Positions do not ring, so `Repeat` and `Hold` are immune (and
/// `Trend`, which extrapolates the ringing, is worse than `Extrapolate` there). After
/// every step the integrator keeps whichever of `Extrapolate`, `Trend` and `Repeat` would
/// have come closest (max-norm) to the converged increment (`Trend` only once two steps
/// of the same scheme lie behind: not across a restart of the accelerations); a step
/// whose Newton fails is retried once at the same size with `Hold` before it is cut.
/// Between steps of one size, `Trend` adds to each unknown its last miss times the
/// regression of its misses on the previous ones when that is negative ([`TrendFeedback`]):
/// the ringing of unresolved modes, which `Trend` amplifies, is then predicted too.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Predictor {
    Extrapolate,
    Trend,
    Repeat,
    Hold,
}

/// The nonlinear problem of one step, from `prev` (at t_n) to `cur` (at t_{n+1}).
struct StepProblem<'a> {
    sys: &'a System,
    asm: &'a mut Assembler,
    prev: &'a State,
    cur: &'a mut State,
    /// hΔq_n per configuration unknown (6 per node, then the joint coordinates).
    hdq: &'a mut [f64],
    /// Configuration and multiplier parts of the current Newton correction.
    dcfg: &'a mut [f64],
    dlam: &'a mut [f64],
    t_ops: &'a mut [Matrix3<f64>],
    phi: &'a mut [f64],
    /// Configuration change of the current correction (Δx + Bᵀ Δν).
    change: &'a mut [f64],
    ctx: EvalContext,
    coef: Coefficients,
    beta_p: f64,
    gamma_p: f64,
    atol: f64,
    rtol: f64,
}

impl StepProblem<'_> {
    /// The joint coordinates and element states at `hdq`: `ν = ν_n + hΔν`, `z = z_n + hΔz`
    /// (the nodes' `x = x_n + hΔx`, `R = R_n exp(hΔψ̃)` are set as they are predicted,
    /// each part's on its thread).
    #[inline(always)]
    fn update_configuration(&mut self) {
        let n6 = 6 * self.cur.nodes.len();
        for (j, (c, p)) in self
            .cur
            .coords
            .iter_mut()
            .zip(&self.prev.coords)
            .take(self.sys.n_coordinates)
            .enumerate()
        {
            c.q = p.q + self.hdq[n6 + j];
        }
        let z0 = n6 + self.sys.n_coordinates;
        for (j, (z, p)) in self
            .cur
            .states
            .iter_mut()
            .zip(&self.prev.states)
            .enumerate()
        {
            z.z = p.z + self.hdq[z0 + j];
        }
    }
}

impl NewtonSystem for StepProblem<'_> {
    fn evaluate(&mut self, residual: &mut [f64], matrix: Option<&mut BlockMatrix>) {
        if matrix.is_some()
            && let Some(plan) = self.asm.split_plan()
        {
            // Each part's nodes on its thread, through owner-checked handles.
            let hdq = &*self.hdq;
            let one = |i: usize| {
                tangent_operator(&Vector3::new(
                    hdq[6 * i + 3],
                    hdq[6 * i + 4],
                    hdq[6 * i + 5],
                ))
            };
            let [mut t0, mut t1] = PartSlice::split(self.t_ops, &plan.node_part);
            let [l0, l1] = &plan.nodes;
            crate::solve::partner::join2(
                || l0.iter().for_each(|&i| *t0.get(i) = one(i)),
                || l1.iter().for_each(|&i| *t1.get(i) = one(i)),
            );
        } else if matrix.is_some() {
            for (i, t) in self.t_ops.iter_mut().enumerate() {
                *t = tangent_operator(&Vector3::new(
                    self.hdq[6 * i + 3],
                    self.hdq[6 * i + 4],
                    self.hdq[6 * i + 5],
                ));
            }
        }
        self.asm.assemble(
            self.sys, self.cur, &self.ctx, &self.coef, self.t_ops, residual, matrix,
        );
    }

    isa::copies! {
        /// On CPUs with AVX in a copy compiled for AVX (VEX three-operand forms, 4-lane
        /// vectors), with the configuration update and its per-node `R exp(ψ̃)`
        /// (quaternion product, series, renormalization, matrix) inlined: the baseline copy
        /// spent ~4 % of the chain's full-Newton samples there. No FMA: the same bits.
        fn apply(&mut self: StepProblem<'_>, delta: &[f64]) -> Correction {
            Base | Avx => apply_impl,
        }
    }

    fn constraint_violation(&mut self) -> f64 {
        if let Some(checks) = self.asm.split_plan().and_then(|p| p.checks.as_ref()) {
            // Each part's constraints on its thread (they read the nodes it just moved).
            let [mut p0, mut p1] = PartSlice::split(self.phi, &checks.row_part);
            let (sys, ctx, cur) = (self.sys, &self.ctx, &*self.cur);
            let [k0, k1] = &checks.constraints;
            let (w0, w1) = crate::solve::partner::join2(
                || sys.constraint_values_of(ctx, cur, k0, &mut p0),
                || sys.constraint_values_of(ctx, cur, k1, &mut p1),
            );
            return w0.max(w1);
        }
        self.sys.constraint_values(&self.ctx, self.cur, self.phi);
        self.phi.iter().fold(0.0, |m, x| m.max(x.abs()))
    }
}

impl StepProblem<'_> {
    /// The Newton correction: velocities, accelerations, multipliers and `hΔq` updated
    /// from `delta`, and the configuration at the new `hΔq`; returns the scaled norm of
    /// the configuration change. One pass per node (rates, `hΔq`, `x`, `R exp(hΔψ̃)`):
    /// the node data are read once per iteration, not once per quantity.
    #[inline(always)]
    fn apply_impl(&mut self, delta: &[f64]) -> Correction {
        let (bp, gp) = (self.beta_p, self.gamma_p);
        let (atol, rtol) = (self.atol, self.rtol);
        self.asm.configuration_of(self.sys, delta, self.dcfg);
        let projected = self.asm.formulation() == Formulation::StabilizedIndex2;
        if projected {
            self.change.copy_from_slice(self.dcfg);
            self.asm.add_projection(self.sys, delta, self.change);
        }
        let change: &[f64] = if projected { self.change } else { self.dcfg };
        // A configuration unknown's correction is weighed against its step increment
        // (positions have no natural origin); an element state's against the larger of its
        // increment and its value (a state has a natural zero — inflow, a stall fraction, a
        // pressure — so its own size sets the relative tolerance, as in ODE codes).
        let mut worst: f64 = 0.0;
        if let Some(plan) = self.asm.split_plan() {
            // Part 1's nodes on the partner thread, the others here, through
            // owner-checked handles (on the nodes and on their six entries of hΔq).
            let n = self.cur.nodes.len();
            let [mut n0, mut n1] = PartSlice::split(&mut self.cur.nodes, &plan.node_part);
            let q6 = self.hdq[..6 * n].as_chunks_mut::<6>().0;
            let [mut q0, mut q1] = PartSlice::split(q6, &plan.node_part);
            let prev = &self.prev.nodes;
            let dcfg = &*self.dcfg;
            let update = |i: usize, n: &mut crate::core::NodeState, q: &mut [f64; 6]| -> f64 {
                let r = 6 * i..6 * i + 6;
                let (d, c) = (&dcfg[r.clone()], &change[r]);
                correct_node(n, &prev[i], d, c, q, (gp, bp), (atol, rtol))
            };
            let [l0, l1] = &plan.nodes;
            let (w0, w1) = crate::solve::partner::join2(
                || {
                    let w = |m: f64, &i: &usize| m.max(update(i, n0.get(i), q0.get(i)));
                    l0.iter().fold(0.0, w)
                },
                || {
                    let w = |m: f64, &i: &usize| m.max(update(i, n1.get(i), q1.get(i)));
                    l1.iter().fold(0.0, w)
                },
            );
            worst = w0.max(w1);
        }
        let nodes = self.cur.nodes.iter_mut().zip(&self.prev.nodes);
        let all = self.asm.split_plan().is_none();
        for (i, (n, p)) in nodes.enumerate().take_while(|_| all) {
            let r = 6 * i..6 * i + 6;
            let (d, c) = (&self.dcfg[r.clone()], &change[r.clone()]);
            let w = correct_node(n, p, d, c, &mut self.hdq[r], (gp, bp), (atol, rtol));
            worst = worst.max(w);
        }
        let n6 = 6 * self.cur.nodes.len();
        let nc = self.sys.n_coordinates;
        let coords = self.cur.coords.iter_mut().zip(&self.prev.coords).take(nc);
        for (j, (c, p)) in coords.enumerate() {
            let (d, k) = (self.dcfg[n6 + j], n6 + j);
            c.v += d * gp;
            c.a += d * bp;
            self.hdq[k] += change[k];
            worst = worst.max(change[k].abs() / (atol + rtol * self.hdq[k].abs()));
            c.q = p.q + self.hdq[k];
        }
        let z0 = n6 + nc;
        let states = self.cur.states.iter_mut().zip(&self.prev.states);
        for (j, (z, p)) in states.enumerate() {
            let k = z0 + j;
            z.zd += self.dcfg[k] * self.coef.state_rate;
            self.hdq[k] += change[k];
            let scale = self.hdq[k].abs().max(z.z.abs());
            worst = worst.max(change[k].abs() / (atol + rtol * scale));
            z.z = p.z + self.hdq[k];
        }
        let s = 1.0 / self.coef.multiplier_scale;
        self.asm.multipliers_of(self.sys, delta, self.dlam);
        for (l, d) in self.cur.lambda.iter_mut().zip(self.dlam.iter_mut()) {
            *d *= s;
            *l += *d;
        }
        Correction::new(worst, self.dlam, &self.cur.lambda, rtol)
    }
}

/// One node's share of a Newton correction `d` (configuration part) and `change` (its
/// configuration change): `v += γ' Δx`, `v̇ += β' Δx` (and Ω, Ω̇), `hΔq += change`,
/// `x = x_n + hΔx`, `R = R_n exp(hΔψ̃)`; returns the largest `|change| / (atol + rtol |hΔq|)`.
#[inline(always)]
fn correct_node(
    n: &mut crate::core::NodeState,
    p: &crate::core::NodeState,
    d: &[f64],
    change: &[f64],
    q: &mut [f64],
    (gp, bp): (f64, f64),
    (atol, rtol): (f64, f64),
) -> f64 {
    let dx = Vector3::new(d[0], d[1], d[2]);
    let dth = Vector3::new(d[3], d[4], d[5]);
    n.v += dx * gp;
    n.w += dth * gp;
    n.a += dx * bp;
    n.wd += dth * bp;
    let mut worst: f64 = 0.0;
    for (q, c) in q.iter_mut().zip(change) {
        *q += c;
        worst = worst.max(c.abs() / (atol + rtol * q.abs()));
    }
    n.x = p.x + Vector3::new(q[0], q[1], q[2]);
    n.rot = p.rot.compose_exp(&Vector3::new(q[3], q[4], q[5]));
    worst
}

/// Why a state given from outside does not fit the model (its counts of nodes, joint
/// coordinates, element states and multipliers), if it does not. The held values are
/// not compared: a count other than the model's is sampled afresh at the start.
fn shape_mismatch(sys: &System, s: &State) -> Option<String> {
    let want = sys.initial_state();
    let counts = [
        ("nodes", s.nodes.len(), want.nodes.len()),
        ("joint coordinates", s.coords.len(), want.coords.len()),
        ("element states", s.states.len(), want.states.len()),
        ("multipliers", s.lambda.len(), want.lambda.len()),
    ];
    let (what, got, n) = counts.into_iter().find(|&(_, got, n)| got != n)?;
    Some(format!(
        "the state does not fit the model: {got} {what}, the model has {n}"
    ))
}

/// Mutable integrator state carried between steps.
struct Integrator<'a> {
    sys: &'a System,
    settings: &'a DynamicSettings,
    ga: GeneralizedAlpha,
    /// The first-order scheme of the element states (same ρ∞).
    fo: FirstOrderAlpha,
    asm: Assembler,
    lin: LinearSolver,
    matrix: BlockMatrix,
    work: NewtonWork,
    state: State,
    trial: State,
    /// Algorithmic accelerations a_n (6 per node, then one per coordinate).
    acc: Vec<f64>,
    hdq: Vec<f64>,
    dcfg: Vec<f64>,
    dlam: Vec<f64>,
    t_ops: Vec<Matrix3<f64>>,
    phi: Vec<f64>,
    change: Vec<f64>,
    mu: Vec<f64>,
    /// Matrix assembled for a different step size than the current factorization.
    factored_h: f64,
    /// Predictor of the next step.
    predictor: Predictor,
    /// The `Extrapolate` prediction of hΔq for the current step.
    extrapolated: Vec<f64>,
    /// The `Trend` prediction of hΔq for the current step (valid when `trended_valid`).
    trended: Vec<f64>,
    trended_valid: bool,
    /// The `Trend` predictor's misses, fed back into its next prediction.
    feedback: TrendFeedback,
    /// v̇_{n−1} (6 per node, then one per coordinate, then ż per state), for `Trend`;
    /// `trend_ok`: it belongs to the same run of the scheme (false at the start and after
    /// a restart of the accelerations).
    last_vdot: Vec<f64>,
    trend_ok: bool,
    /// hΔq and h of the last accepted step (h = 0: none yet).
    last_hdq: Vec<f64>,
    last_h: f64,
    /// Workspace of the consistent accelerations after a sample-and-hold jump (made on
    /// first use).
    restart: Option<Box<RestartWork>>,
    /// Breakpoints of the model's time functions, sorted.
    breakpoints: Vec<f64>,
    /// The granular sets' candidate pairs and where they were found.
    contacts: ContactPairs,
    /// The size of the step solved into `trial`.
    trial_step: f64,
    /// The partner thread of a two-part model (`partition = "two_parts"`).
    partner: Option<crate::solve::partner::Partner>,
}

/// Candidate pairs of the granular sets (a Verlet list, [`crate::elements::GranularSet`]):
/// `(set, i, j)`, sorted, and the spheres' positions at the detection.
#[derive(Default)]
struct ContactPairs {
    pairs: Vec<(usize, usize, usize)>,
    reference: Vec<Vec<Vector3<f64>>>,
    scratch: Vec<(usize, usize)>,
    /// Some set has pair friction with bristles (history kept in `State::pair_bristles`).
    with_bristles: bool,
    /// Times the pattern was rebuilt, largest number of pairs, and the factorizations
    /// and fallbacks of the linear solvers replaced.
    rebuilds: usize,
    most: usize,
    factorizations: usize,
    fallbacks: usize,
}

impl ContactPairs {
    /// Detects the candidate pairs of every set at `state` (broad phase, each set's margin).
    fn detect(&mut self, sys: &System, state: &State) -> Vec<(usize, usize, usize)> {
        let mut out = Vec::new();
        for (g, set) in sys.granular.iter().enumerate() {
            set.candidate_pairs(&state.nodes, set.margin, &mut self.scratch);
            out.extend(self.scratch.iter().map(|&(i, j)| (g, i, j)));
        }
        out
    }

    /// Takes `state` as the reference of the Verlet criterion.
    fn set_reference(&mut self, sys: &System, state: &State) {
        self.reference = sys
            .granular
            .iter()
            .map(|set| set.nodes.iter().map(|&i| state.nodes[i].x).collect())
            .collect();
    }

    /// The pairs become `pairs`: the bristle deflections of `states` follow them (kept for
    /// a pair kept, zero for a new one).
    fn adopt(&mut self, pairs: Vec<(usize, usize, usize)>, states: [&mut State; 2]) {
        for s in states {
            if !s.pair_bristles.is_empty() || self.with_bristles {
                s.pair_bristles = crate::core::remap_bristles(&s.pair_bristles, &pairs);
            }
        }
        self.pairs = pairs;
    }

    /// The contact elements of the pairs.
    fn elements(&self, sys: &System) -> Vec<crate::elements::SpherePair> {
        self.pairs
            .iter()
            .map(|&(g, i, j)| sys.granular[g].pair(i, j))
            .collect()
    }
}

/// The index-3 problem of consistent accelerations, kept for restarts.
struct RestartWork {
    asm: Assembler,
    lin: LinearSolver,
    matrix: BlockMatrix,
    residual: Vec<f64>,
}

impl Integrator<'_> {
    /// Augmented-Lagrangian penalty ρ = p m̄ / (βh²), index 3 only: in the stabilized
    /// formulation Φ is enforced by the projection ν, and a ρΦ term in the equilibrium rows
    /// would couple them to ν by an O(1) block (ρ s_r BᵀB Bᵀ) the matrix does not carry.
    fn penalty(&self, h: f64) -> f64 {
        if self.asm.formulation() == Formulation::StabilizedIndex2 {
            return 0.0;
        }
        self.settings.solver.penalty * self.sys.characteristic_mass / (self.ga.beta * h * h)
    }

    /// One generalized-α step of size h from `self.state` into `self.trial`. `Hold` is
    /// asked for only to retry a step whose Newton failed; the retry refreshes the matrix
    /// at every iteration, also under modified Newton.
    fn step(&mut self, h: f64, predictor: Predictor) -> Result<NewtonReport, NewtonFailure> {
        let retry = predictor == Predictor::Hold;
        let ga = self.ga;
        let t1 = self.state.time + h;
        self.trial_step = h;
        // The nodes are copied as they are predicted, below.
        self.trial.clone_from_but_nodes(&self.state);
        self.trial.time = t1;
        let trend_ok = self.trend_ok && self.last_h > 0.0;
        let predictor = match predictor {
            Predictor::Repeat if self.last_h == 0.0 => Predictor::Hold,
            Predictor::Trend if !trend_ok => Predictor::Extrapolate,
            p => p,
        };
        self.trended_valid = trend_ok;
        let ratio = if self.last_h > 0.0 {
            h / self.last_h
        } else {
            0.0
        };
        // Predicts one unknown: returns (hΔq, v_{n+1}, v̇_{n+1}) from v_n, v̇_n, a_n, and
        // the `Extrapolate` and `Trend` predictions of hΔq.
        let last_vdot = &self.last_vdot;
        let last_hdq = &self.last_hdq;
        // The misses are fed back only between steps of one size (module trend_feedback).
        let feedback =
            (predictor == Predictor::Trend && same_step(h, self.last_h)).then_some(&self.feedback);
        // The feedback for unknown k, if any (applied after the plain prediction).
        let trend_feedback = |k: usize| feedback.map(|f| f.correction(k)).filter(|&c| c != 0.0);
        let predict = |k: usize, v: f64, vd: f64, an: f64| {
            let increment = |vd1: f64| {
                let a1 = ga.algorithmic_acceleration(an, vd, vd1);
                (h * (v + h * (0.5 - ga.beta) * an + h * ga.beta * a1), a1)
            };
            let (hdq, a1) = increment(vd);
            let vd_trend = vd + ratio * (vd - last_vdot[k]);
            let (hdq_trend, a1_trend) = if trend_ok {
                increment(vd_trend)
            } else {
                (hdq, a1)
            };
            let rate = |a1: f64| v + h * (1.0 - ga.gamma) * an + h * ga.gamma * a1;
            let (q, v1, vd1) = match predictor {
                Predictor::Extrapolate => (hdq, rate(a1), vd),
                Predictor::Trend => (hdq_trend, rate(a1_trend), vd_trend),
                Predictor::Repeat | Predictor::Hold => {
                    let q = if predictor == Predictor::Repeat {
                        last_hdq[k] * ratio
                    } else {
                        0.0
                    };
                    let (v1, vd1) = ga.rates_of_increment(h, v, vd, an, q);
                    (q, v1, vd1)
                }
            };
            (q, v1, vd1, hdq, hdq_trend)
        };
        // Node i predicted from the step's start — rates and configuration x_n + hΔx,
        // R_n exp(hΔψ̃) — with its six entries of hΔq and of the two recorded predictions.
        let acc = &self.acc;
        let predict_node = |i: usize,
                            p: &NodeState,
                            n: &mut NodeState,
                            q: &mut [f64; 6],
                            ex: &mut [f64; 6],
                            tr: &mut [f64; 6]| {
            let vd = [p.a.x, p.a.y, p.a.z, p.wd.x, p.wd.y, p.wd.z];
            let v = [p.v.x, p.v.y, p.v.z, p.w.x, p.w.y, p.w.z];
            let (mut v1, mut vd1) = ([0.0; 6], [0.0; 6]);
            for k in 0..6 {
                let j = 6 * i + k;
                let an = acc[j];
                (q[k], v1[k], vd1[k], ex[k], tr[k]) = predict(j, v[k], vd[k], an);
                if let Some(c) = trend_feedback(j) {
                    q[k] += c;
                    (v1[k], vd1[k]) = ga.rates_of_increment(h, v[k], vd[k], an, q[k]);
                }
            }
            n.x = p.x + Vector3::new(q[0], q[1], q[2]);
            n.rot = p.rot.compose_exp(&Vector3::new(q[3], q[4], q[5]));
            n.v = Vector3::new(v1[0], v1[1], v1[2]);
            n.w = Vector3::new(v1[3], v1[4], v1[5]);
            n.a = Vector3::new(vd1[0], vd1[1], vd1[2]);
            n.wd = Vector3::new(vd1[3], vd1[4], vd1[5]);
        };
        let n6 = 6 * self.state.nodes.len();
        let prev = &self.state.nodes;
        let hdq6 = self.hdq[..n6].as_chunks_mut::<6>().0;
        let ex6 = self.extrapolated[..n6].as_chunks_mut::<6>().0;
        let tr6 = self.trended[..n6].as_chunks_mut::<6>().0;
        if let Some(plan) = self.asm.split_plan() {
            // Each part's nodes on its thread (their data stay on its core).
            let owner = &plan.node_part;
            let [mut n0, mut n1] = PartSlice::split(&mut self.trial.nodes, owner);
            let [mut q0, mut q1] = PartSlice::split(hdq6, owner);
            let [mut e0, mut e1] = PartSlice::split(ex6, owner);
            let [mut t0, mut t1] = PartSlice::split(tr6, owner);
            let [l0, l1] = &plan.nodes;
            let partner = self.partner.as_ref();
            crate::solve::partner::within(partner, || {
                crate::solve::partner::join2(
                    || {
                        for &i in l0 {
                            predict_node(i, &prev[i], n0.get(i), q0.get(i), e0.get(i), t0.get(i));
                        }
                    },
                    || {
                        for &i in l1 {
                            predict_node(i, &prev[i], n1.get(i), q1.get(i), e1.get(i), t1.get(i));
                        }
                    },
                )
            });
        } else {
            let nodes = self
                .trial
                .nodes
                .iter_mut()
                .zip(prev)
                .zip(hdq6.iter_mut().zip(ex6).zip(tr6));
            for (i, ((n, p), ((q, ex), tr))) in nodes.enumerate() {
                predict_node(i, p, n, q, ex, tr);
            }
        }
        for (j, (c, p)) in self
            .trial
            .coords
            .iter_mut()
            .zip(&self.state.coords)
            .take(self.sys.n_coordinates)
            .enumerate()
        {
            let k = n6 + j;
            let an = self.acc[k];
            (self.hdq[k], c.v, c.a, self.extrapolated[k], self.trended[k]) =
                predict(k, p.v, p.a, an);
            if let Some(f) = trend_feedback(n6 + j) {
                self.hdq[n6 + j] += f;
                (c.v, c.a) = ga.rates_of_increment(h, p.v, p.a, an, self.hdq[n6 + j]);
            }
        }
        // Element states: the same predictors in the first-order scheme.
        let fo = self.fo;
        let z0 = n6 + self.sys.n_coordinates;
        for (j, (z, p)) in self
            .trial
            .states
            .iter_mut()
            .zip(&self.state.states)
            .enumerate()
        {
            let k = z0 + j;
            let wn = self.acc[k];
            let w1 = fo.algorithmic_rate(wn, p.zd, p.zd);
            self.extrapolated[k] = fo.increment(h, wn, w1);
            let zd_trend = p.zd + ratio * (p.zd - self.last_vdot[k]);
            self.trended[k] = if trend_ok {
                fo.increment(h, wn, fo.algorithmic_rate(wn, p.zd, zd_trend))
            } else {
                self.extrapolated[k]
            };
            (self.hdq[k], z.zd) = match predictor {
                Predictor::Extrapolate => (self.extrapolated[k], p.zd),
                Predictor::Trend => match trend_feedback(k) {
                    Some(c) => {
                        let dz = self.trended[k] + c;
                        (dz, fo.rate_of_increment(h, wn, p.zd, dz))
                    }
                    _ => (self.trended[k], zd_trend),
                },
                Predictor::Repeat | Predictor::Hold => {
                    let dz = if predictor == Predictor::Repeat {
                        self.last_hdq[k] * ratio
                    } else {
                        0.0
                    };
                    (dz, fo.rate_of_increment(h, wn, p.zd, dz))
                }
            };
        }
        let scaling = self.settings.solver.scaling;
        let scale = if scaling { ga.beta * h * h } else { 1.0 };
        let coef = Coefficients {
            mass: ga.beta_prime(h),
            damping: ga.gamma_prime(h),
            stiffness: 1.0,
            row_scale: scale,
            multiplier_scale: scale,
            velocity_scale: if scaling { ga.beta * h / ga.gamma } else { 1.0 },
            penalty: self.penalty(h),
            // State rows scaled by 1/(∂ż/∂Δz) ~ h, so that their block is ∂r/∂ż + O(h).
            state_rate: self.fo.rate_prime(h),
            state_row_scale: if scaling {
                1.0 / self.fo.rate_prime(h)
            } else {
                1.0
            },
            step: h,
        };
        if !same_step(h, self.factored_h) {
            self.lin.invalidate();
        }
        let settings = NewtonSettings {
            max_iterations: self.settings.solver.max_iterations,
            constraint_tolerance: self.settings.solver.tolerance,
            // A retried step is one where a reused matrix (or its refresh rule) failed:
            // full Newton.
            reuse_jacobian: self.settings.jacobian == JacobianUpdate::Modified && !retry,
            // Granular sets: damped Newton (the pair friction's stick–slip kinks).
            line_search: !self.sys.granular.is_empty(),
        };
        // A step ending on a breakpoint sees the forcing's left limit there.
        let ctx_time = if self.on_breakpoint(t1) {
            t1.next_down()
        } else {
            t1
        };
        let lin_splits = self.lin.splits();
        let mut problem = StepProblem {
            sys: self.sys,
            asm: &mut self.asm,
            prev: &self.state,
            cur: &mut self.trial,
            hdq: &mut self.hdq,
            dcfg: &mut self.dcfg,
            dlam: &mut self.dlam,
            t_ops: &mut self.t_ops,
            phi: &mut self.phi,
            change: &mut self.change,
            ctx: self.sys.context(ctx_time, 1.0),
            coef,
            beta_p: coef.mass,
            gamma_p: coef.damping,
            atol: self.settings.solver.tolerance,
            rtol: self.settings.solver.relative_tolerance,
        };
        problem.update_configuration();
        let (lin, matrix, work) = (&mut self.lin, &mut self.matrix, &mut self.work);
        let partner = self.partner.as_ref();
        let mut solve = || newton(&mut problem, lin, matrix, work, &settings);
        // A block LU with two parts factors them on two threads from within rayon's pool:
        // the iterations then run on one of its threads (`scope`), once per step rather
        // than a hand-over from outside the pool per factorization.
        let result = if partner.is_some() {
            crate::solve::partner::within(partner, solve)
        } else if lin_splits && rayon::current_thread_index().is_none() {
            rayon::scope(|_| solve())
        } else {
            solve()
        };
        if result.as_ref().is_ok_and(|r| r.factorizations > 0) || self.lin.is_factored() {
            self.factored_h = h;
        }
        let report = result?;
        // Augmented multipliers at the converged state (Φ was evaluated by the last check).
        let rho = coef.penalty;
        for ((m, l), p) in self.mu.iter_mut().zip(&self.trial.lambda).zip(&self.phi) {
            *m = l + rho * p;
        }
        Ok(report)
    }

    /// Takes the samples due at the current time; when a held value changed, the forcing
    /// jumps, so the step restarts like the first one: consistent accelerations (and
    /// multipliers) at the current state become the algorithmic accelerations. Without
    /// the restart the stale a_n would make the next step's velocity update
    /// `h (1 − γ) a_n` wrong by O(h), the whole run first order.
    ///
    /// A step that lands on a breakpoint of the time functions restarts the same way
    /// (the step itself saw the left limit of the forcing, the restart its right limit), so
    /// a jump in a load, drive or wind is passed at second order.
    ///
    /// Joint reactions read by signals are held first: at a sample instant those of the
    /// consistent accelerations and multipliers at the converged state (the equations of
    /// motion there, not the step's algorithmic multipliers, which oscillate from step to
    /// step with ρ∞ near 1), otherwise the converged step's.
    fn settle(&mut self) {
        if !self.sys.signals.reactions.is_empty() && self.sys.sample_due(self.state.time) {
            self.restart_consistent();
        }
        self.sys.hold_reactions(&mut self.state, &self.mu);
        let jumped = self.sys.n_held > 0 && self.sys.sample(&mut self.state, false);
        if jumped || self.on_breakpoint(self.state.time) {
            self.restart_consistent();
        }
    }

    /// Whether `t` is one of the time functions' breakpoints.
    fn on_breakpoint(&self, t: f64) -> bool {
        self.breakpoints
            .binary_search_by(|b| b.total_cmp(&t))
            .is_ok()
    }

    /// Consistent accelerations, multipliers and state rates at the current state and time
    /// become the algorithmic ones ([`Integrator::restart_accelerations`]).
    fn restart_consistent(&mut self) {
        let sys = self.sys;
        let pairs = self.contacts.elements(sys);
        let work = self.restart.get_or_insert_with(|| {
            let asm = Assembler::with_pairs(sys, Formulation::Index3, pairs);
            let lin = LinearSolver::new(asm.structure(), self.settings.solver.linear_solver);
            let matrix = BlockMatrix::zeros(asm.structure().clone());
            let residual = vec![0.0; asm.n_unknowns()];
            Box::new(RestartWork {
                asm,
                lin,
                matrix,
                residual,
            })
        });
        let ctx = sys.context(self.state.time, 1.0);
        let saved = self.state.clone();
        let ok = consistent_accelerations(
            sys,
            &mut self.state,
            &ctx,
            &mut work.asm,
            &mut work.lin,
            &mut work.matrix,
            &mut work.residual,
        )
        .is_ok()
            && self
                .state
                .nodes
                .iter()
                .all(|n| n.a.iter().chain(n.wd.iter()).all(|x| x.is_finite()));
        if !ok {
            // Keep the stepping as it was (first order across this jump).
            self.state = saved;
            return;
        }
        self.restart_accelerations();
        self.mu.copy_from_slice(&self.state.lambda);
    }

    /// Restarts the scheme from the physical accelerations and state rates of the current
    /// state: the algorithmic accelerations a_n become q̈_n, as at the first step. After a
    /// kink of the forcing (a located event) or a jump (a new held value), the old a_n
    /// carries a transient that decays only as (−α_m/(1 − α_m))ⁿ per step and, with
    /// growing steps, makes an O(h ε) velocity error the local estimate does not see.
    fn restart_accelerations(&mut self) {
        let sys = self.sys;
        // The accelerations before the restart are not the trend of those after it.
        self.trend_ok = false;
        for (i, nd) in self.state.nodes.iter().enumerate() {
            let v = [nd.a.x, nd.a.y, nd.a.z, nd.wd.x, nd.wd.y, nd.wd.z];
            self.acc[6 * i..6 * i + 6].copy_from_slice(&v);
        }
        let n6 = 6 * sys.n_nodes();
        for (j, c) in self.state.coords.iter().take(sys.n_coordinates).enumerate() {
            self.acc[n6 + j] = c.a;
        }
        let z0 = n6 + sys.n_coordinates;
        for (j, z) in self.state.states.iter().enumerate() {
            self.acc[z0 + j] = z.zd;
        }
    }

    /// Assembler, linear solver (symbolic analysis) and matrix for the current candidate
    /// pairs.
    fn rebuild_pattern(&mut self) {
        self.contacts.rebuilds += 1;
        self.contacts.most = self.contacts.most.max(self.contacts.pairs.len());
        self.contacts.factorizations += self.lin.stats.factorizations;
        self.contacts.fallbacks += self.lin.stats.fallbacks;
        self.asm = Assembler::with_pairs(
            self.sys,
            self.asm.formulation(),
            self.contacts.elements(self.sys),
        );
        self.lin = LinearSolver::new(self.asm.structure(), self.settings.solver.linear_solver);
        self.matrix = iteration_matrix(&self.lin, self.asm.structure(), self.settings);
        self.factored_h = f64::NAN;
        self.restart = None;
    }

    /// After a converged step, before it is accepted: checks the granular sets' Verlet
    /// lists at the trial state. While no sphere has moved more than half its set's margin
    /// since the detection the candidate pairs are still valid (true returned: keep the
    /// step). Otherwise the pairs are detected again at the trial state; if a pair that
    /// was not a candidate is in contact there, the step missed its force: the pattern
    /// is rebuilt with the old and new pairs and false is returned (redo the step).
    /// Else the new pairs are kept for the next steps (pattern rebuilt if they changed).
    fn check_contacts(&mut self) -> bool {
        let sys = self.sys;
        if sys.granular.is_empty() {
            return true;
        }
        let moved = sys.granular.iter().enumerate().any(|(g, set)| {
            set.max_displacement(&self.trial.nodes, &self.contacts.reference[g]) > 0.5 * set.margin
        });
        if !moved {
            return true;
        }
        let found = self.contacts.detect(sys, &self.trial);
        let missed = found.iter().any(|&(g, i, j)| {
            self.contacts.pairs.binary_search(&(g, i, j)).is_err()
                && sys.granular[g].gap(&self.trial.nodes, i, j) < 0.0
        });
        if missed {
            let mut union = found;
            union.extend_from_slice(&self.contacts.pairs);
            union.sort_unstable();
            union.dedup();
            self.contacts
                .adopt(union, [&mut self.state, &mut self.trial]);
            self.rebuild_pattern();
            return false;
        }
        self.contacts.set_reference(sys, &self.trial);
        if found != self.contacts.pairs {
            // The trial's bristles are still those of the step's start (updated when it
            // is accepted, [`Integrator::accept`]): a pair kept keeps them, a new pair was
            // not in contact during the step (else it would have been missed) and starts
            // at zero.
            self.contacts
                .adopt(found, [&mut self.state, &mut self.trial]);
            self.rebuild_pattern();
        }
        true
    }

    /// Accepts the trial step: chooses the next predictor, updates the algorithmic
    /// accelerations and swaps states.
    /// Local error estimate of the step just solved (trial against state), relative to
    /// the tolerance: max over the unknowns of |e| / (tol_abs + tol_rel |q|), > 1 rejects.
    ///
    /// Second-order unknowns (node translations and rotations, joint coordinates): the
    /// Newmark-family estimate e = (β − 1/6) h² (q̈_{n+1} − q̈_n) of Zienkiewicz & Xie
    /// (1991), as used for generalized-α by Géradin & Cardona (2001, §5.9): the leading
    /// O(h³ q⃛) term of the local displacement error. Element states (first order):
    /// e = h (ż_{n+1} − ż_n)/12, the trapezoidal rule's leading term. Rotations are
    /// compared in rad with |q| = 1.
    fn local_error(&self, h: f64, tol: &crate::model::AdaptiveSettings) -> f64 {
        let c2 = (self.ga.beta - 1.0 / 6.0).abs() * h * h;
        let c1 = h / 12.0;
        let (atol, rtol) = (tol.tolerance_abs, tol.tolerance_rel);
        let mut worst: f64 = 0.0;
        for (n, p) in self.trial.nodes.iter().zip(&self.state.nodes) {
            for k in 0..3 {
                let scale = atol + rtol * n.x[k].abs().max(p.x[k].abs());
                worst = worst.max(c2 * (n.a[k] - p.a[k]).abs() / scale);
                worst = worst.max(c2 * (n.wd[k] - p.wd[k]).abs() / (atol + rtol));
            }
        }
        for (c, p) in self
            .trial
            .coords
            .iter()
            .zip(&self.state.coords)
            .take(self.sys.n_coordinates)
        {
            let scale = atol + rtol * c.q.abs().max(p.q.abs());
            worst = worst.max(c2 * (c.a - p.a).abs() / scale);
        }
        for (z, p) in self.trial.states.iter().zip(&self.state.states) {
            let scale = atol + rtol * z.z.abs().max(p.z.abs());
            worst = worst.max(c1 * (z.zd - p.zd).abs() / scale);
        }
        if worst.is_nan() { f64::INFINITY } else { worst }
    }

    fn accept(&mut self) {
        let ga = self.ga;
        let h = self.trial.time - self.state.time;
        let ratio = if self.last_h > 0.0 {
            h / self.last_h
        } else {
            0.0
        };
        // Node i: the largest misses of the three predictions of its hΔq (against the
        // `last_hdq` of the step before), then `last_hdq`, v̇_n into `last_vdot` and its
        // algorithmic accelerations a_{n+1}. Returns (repeated, extrapolated, trended).
        let (hdq, ext, tre) = (&self.hdq, &self.extrapolated, &self.trended);
        let misses = |range: std::ops::Range<usize>, last: &[f64], m: [f64; 3]| {
            let each = hdq[range.clone()]
                .iter()
                .zip(&ext[range.clone()])
                .zip(&tre[range]);
            each.zip(last).fold(m, |[r, e, t], (((q, x), y), l)| {
                [
                    r.max((q - l * ratio).abs()),
                    e.max((q - x).abs()),
                    t.max((q - y).abs()),
                ]
            })
        };
        let accept_node = |i: usize,
                           (p, n): (&NodeState, &NodeState),
                           last: &mut [f64; 6],
                           last_vd: &mut [f64; 6],
                           acc: &mut [f64; 6],
                           m: [f64; 3]| {
            let m = misses(6 * i..6 * i + 6, last, m);
            last.copy_from_slice(&hdq[6 * i..6 * i + 6]);
            let vd0 = [p.a.x, p.a.y, p.a.z, p.wd.x, p.wd.y, p.wd.z];
            let vd1 = [n.a.x, n.a.y, n.a.z, n.wd.x, n.wd.y, n.wd.z];
            *last_vd = vd0;
            for k in 0..6 {
                acc[k] = ga.algorithmic_acceleration(acc[k], vd0[k], vd1[k]);
            }
            m
        };
        let n6 = 6 * self.state.nodes.len();
        let (prev, next) = (&self.state.nodes, &self.trial.nodes);
        let last6 = self.last_hdq[..n6].as_chunks_mut::<6>().0;
        let last_vd6 = self.last_vdot[..n6].as_chunks_mut::<6>().0;
        let acc6 = self.acc[..n6].as_chunks_mut::<6>().0;
        let sys = self.sys;
        let mut m = [0.0f64; 3];
        if let Some(plan) = self.asm.split_plan() {
            // Each part's nodes and passive joint coordinates on its thread.
            let owner = &plan.node_part;
            let [mut l0, mut l1] = PartSlice::split(last6, owner);
            let [mut v0, mut v1] = PartSlice::split(last_vd6, owner);
            let [mut a0, mut a1] = PartSlice::split(acc6, owner);
            let [mut c0, mut c1] = PartSlice::split(&mut self.trial.coords, &plan.coord_part);
            let ([nodes0, nodes1], [passive0, passive1]) = (&plan.nodes, &plan.passive);
            let partner = self.partner.as_ref();
            let (m0, m1) = crate::solve::partner::within(partner, || {
                crate::solve::partner::join2(
                    || {
                        sys.update_passive_coordinates_of(passive0, next, &mut c0);
                        nodes0.iter().fold([0.0; 3], |m, &i| {
                            accept_node(i, (&prev[i], &next[i]), l0.get(i), v0.get(i), a0.get(i), m)
                        })
                    },
                    || {
                        sys.update_passive_coordinates_of(passive1, next, &mut c1);
                        nodes1.iter().fold([0.0; 3], |m, &i| {
                            accept_node(i, (&prev[i], &next[i]), l1.get(i), v1.get(i), a1.get(i), m)
                        })
                    },
                )
            });
            m = [m0[0].max(m1[0]), m0[1].max(m1[1]), m0[2].max(m1[2])];
        } else {
            let each = prev
                .iter()
                .zip(next)
                .zip(last6.iter_mut().zip(last_vd6).zip(acc6));
            for (i, (pn, ((last, last_vd), acc))) in each.enumerate() {
                m = accept_node(i, pn, last, last_vd, acc, m);
            }
        }
        // The other unknowns (joint coordinates, element states).
        let [repeated, extrapolated, trended] = misses(n6..hdq.len(), &self.last_hdq[n6..], m);
        self.predictor = if self.trended_valid && trended < extrapolated && trended <= repeated {
            Predictor::Trend
        } else if extrapolated <= repeated {
            Predictor::Extrapolate
        } else {
            Predictor::Repeat
        };
        if self.trended_valid {
            self.feedback.record(&self.hdq, &self.trended);
        } else {
            self.feedback.reset();
        }
        self.last_hdq[n6..].copy_from_slice(&self.hdq[n6..]);
        self.last_h = h;
        for (j, c) in self
            .state
            .coords
            .iter()
            .take(self.sys.n_coordinates)
            .enumerate()
        {
            self.last_vdot[n6 + j] = c.a;
        }
        let z0 = n6 + self.sys.n_coordinates;
        for (j, z) in self.state.states.iter().enumerate() {
            self.last_vdot[z0 + j] = z.zd;
        }
        self.trend_ok = true;
        for (j, (c, p)) in self
            .trial
            .coords
            .iter()
            .zip(&self.state.coords)
            .take(self.sys.n_coordinates)
            .enumerate()
        {
            let an = self.acc[n6 + j];
            self.acc[n6 + j] = ga.algorithmic_acceleration(an, p.a, c.a);
        }
        for (j, (z, p)) in self.trial.states.iter().zip(&self.state.states).enumerate() {
            let wn = self.acc[z0 + j];
            self.acc[z0 + j] = self.fo.algorithmic_rate(wn, p.zd, z.zd);
        }
        // The granular pairs' bristles at the end of the step (the trial's are the start
        // values the step used, aligned with the assembler's pairs).
        for (b, p) in self.trial.pair_bristles.iter_mut().zip(self.asm.pairs()) {
            b.z = p.bristle_end(&self.trial.nodes, b.z, self.trial_step);
        }
        if self.asm.split_plan().is_none() {
            self.sys.update_passive_coordinates(&mut self.trial, false);
        }
        std::mem::swap(&mut self.state, &mut self.trial);
    }
}

/// The matrix the steps assemble into: the block LU's factor storage, factored in place
/// (`LinearSolver::assembly_matrix`), unless the diagnostics read the assembled matrix
/// after the solve (the condition number): then row-major, copied into the factor.
fn iteration_matrix(
    lin: &LinearSolver,
    structure: &std::sync::Arc<crate::solve::BlockStructure>,
    settings: &DynamicSettings,
) -> BlockMatrix {
    if settings.solver.diagnostics {
        BlockMatrix::zeros(structure.clone())
    } else {
        lin.assembly_matrix(structure)
    }
}

/// Sets up the integrator from `initial` at time `t0` with consistent initial
/// conditions (assembly, velocities, accelerations and state rates). On failure the reason
/// is in `summary` and the state reached is returned.
fn start<'a>(
    sys: &'a System,
    settings: &'a DynamicSettings,
    mut initial: State,
    t0: f64,
    summary: &mut AnalysisSummary,
) -> Result<(Integrator<'a>, f64), Box<State>> {
    initial.time = t0;
    let formulation = match settings.formulation {
        FormulationType::Index3 => Formulation::Index3,
        FormulationType::StabilizedIndex2 => Formulation::StabilizedIndex2,
    };
    let mut asm = Assembler::new(sys, formulation);
    let mut partner = None;
    let n = asm.n_unknowns();
    let two_parts = settings.partition == crate::model::Partition::TwoParts;
    let lin = LinearSolver::with_parts(asm.structure(), settings.solver.linear_solver, two_parts);
    // Two parts: planned from the block LU's separator order; the partner thread started
    // when rayon may use a second thread (`RAYON_NUM_THREADS=1` keeps one; the results
    // are the same). Where no plan is made, the run keeps one part and says why.
    if two_parts {
        match asm.plan_split(sys, lin.block_parts().as_deref()) {
            Err(why) => summary.warnings.push(format!(
                "partition = \"two_parts\" not taken ({why}): the run keeps one part"
            )),
            Ok(()) => {
                if rayon::current_num_threads() > 1 {
                    match crate::solve::partner::Partner::spawn() {
                        Ok(p) => partner = Some(p),
                        Err(e) => summary.warnings.push(format!(
                            "partition = \"two_parts\": no partner thread ({e}); both parts \
                             run on one thread (the same results)"
                        )),
                    }
                }
                let mut blocks = [0; 3];
                for &p in lin.block_parts().iter().flatten() {
                    blocks[p as usize] += 1;
                }
                summary.parts = Some(super::PartsReport {
                    blocks,
                    partner_thread: partner.is_some(),
                });
                // The separator's rows are assembled and eliminated on one thread after the
                // parts: where it is not small against them, the parts do not pay for it
                // (the hovering rotor: 5 + 2 blocks, separator 12, 11 % slower on two threads).
                let [a, b, sep] = blocks;
                if 4 * sep > a.min(b) {
                    summary.warnings.push(format!(
                        "partition = \"two_parts\": the separator ({sep} blocks) is not small \
                         against the parts ({a} + {b} blocks); one part is likely faster"
                    ));
                }
            }
        }
    }
    let matrix = iteration_matrix(&lin, asm.structure(), settings);
    let mut it = Integrator {
        sys,
        settings,
        ga: GeneralizedAlpha::from_rho_inf(settings.rho_inf),
        fo: FirstOrderAlpha::from_rho_inf(settings.rho_inf),
        lin,
        matrix,
        asm,
        work: NewtonWork::new(n),
        trial: initial.clone(),
        state: initial,
        acc: vec![0.0; sys.n_config()],
        hdq: vec![0.0; sys.n_config()],
        dcfg: vec![0.0; sys.n_config()],
        dlam: vec![0.0; sys.n_multipliers],
        t_ops: vec![Matrix3::identity(); sys.n_nodes()],
        phi: vec![0.0; sys.n_multipliers],
        change: vec![0.0; sys.n_config()],
        mu: vec![0.0; sys.n_multipliers],
        factored_h: f64::NAN,
        predictor: Predictor::Extrapolate,
        extrapolated: vec![0.0; sys.n_config()],
        trended: vec![0.0; sys.n_config()],
        trended_valid: false,
        feedback: TrendFeedback::new(sys.n_config()),
        last_vdot: vec![0.0; sys.n_config()],
        trend_ok: false,
        last_hdq: vec![0.0; sys.n_config()],
        last_h: 0.0,
        restart: None,
        breakpoints: sys.breakpoints(),
        contacts: ContactPairs::default(),
        trial_step: 0.0,
        partner,
    };
    // Granular sets: the candidate pairs at the start, in the pattern from the first
    // assembly on.
    if !sys.granular.is_empty() {
        let found = it.contacts.detect(sys, &it.state);
        it.contacts.with_bristles = sys
            .granular
            .iter()
            .any(|g| matches!(g.friction, Some(crate::elements::PairFriction::LuGre(_))));
        let mut trial = it.state.clone();
        it.contacts.adopt(found, [&mut it.state, &mut trial]);
        it.contacts.set_reference(sys, &it.state);
        it.rebuild_pattern();
    }
    let name = summary.name.clone();
    let fail = |summary: &mut AnalysisSummary, time: f64, reason: String, hint: Option<String>| {
        summary.failure = Some(SolverFailure {
            analysis: name.clone(),
            time,
            reason,
            hint,
        });
    };

    // Servo rows have the index-3 form only (their velocity row would need ṡ and its
    // derivatives, second derivatives of the signal).
    if formulation == Formulation::StabilizedIndex2
        && let Some(c) = sys.constraints.iter().find(|c| !c.servo_rows().is_empty())
    {
        fail(
            summary,
            t0,
            format!(
                "joint '{}' has a drive_signal (servo), which the stabilized_index2 formulation does not support",
                c.name()
            ),
            Some("use formulation = \"index3\" (with rho_inf < 1)".into()),
        );
        return Err(Box::new(it.state));
    }
    // Consistent initial conditions: assembly onto the constraints, then accelerations.
    let ctx0 = sys.context(t0, 1.0);
    // The initial problems have the index-3 layout in either formulation.
    let mut init_asm = Assembler::with_pairs(sys, Formulation::Index3, it.contacts.elements(sys));
    let mut init_lin = LinearSolver::new(init_asm.structure(), settings.solver.linear_solver);
    let mut init_matrix = BlockMatrix::zeros(init_asm.structure().clone());
    if !super::assemble_start(
        sys,
        &mut it.state,
        &ctx0,
        settings.solver.tolerance,
        &mut init_asm,
        &mut init_lin,
        &mut init_matrix,
        summary,
        t0,
    ) {
        return Err(Box::new(it.state));
    }
    // Sample-and-hold values at the start (kept when continuing a dynamic analysis).
    let fresh = it.state.held.len() != sys.n_held;
    sys.sample(&mut it.state, false);
    sys.constraint_values(&ctx0, &it.state, &mut it.phi);
    let viol0 = it.phi.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let mut res0 = vec![0.0; init_asm.n_unknowns()];
    let init = consistent_accelerations(
        sys,
        &mut it.state,
        &ctx0,
        &mut init_asm,
        &mut init_lin,
        &mut init_matrix,
        &mut res0,
    );
    summary.factorizations += init_lin.stats.factorizations;
    let finite = it
        .state
        .nodes
        .iter()
        .all(|nd| nd.a.iter().chain(nd.wd.iter()).all(|x| x.is_finite()))
        && it.state.coords.iter().all(|c| c.a.is_finite())
        && it.state.lambda.iter().all(|x| x.is_finite());
    match init {
        Err(LinearError::Singular { block }) => {
            fail(
                summary,
                t0,
                "cannot compute consistent initial accelerations: the mass matrix with the constraints is singular".into(),
                Some(singular_hint(sys, &init_asm, block)),
            );
        }
        Ok(()) if !finite => fail(
            summary,
            t0,
            "consistent initial accelerations are not finite (singular mass matrix)".into(),
            Some("every node in a dynamic analysis needs mass in each direction that is not constrained".into()),
        ),
        Ok(()) => {}
    }
    drop((init_asm, init_lin, init_matrix));
    if summary.failure.is_some() {
        return Err(Box::new(it.state));
    }
    for (i, nd) in it.state.nodes.iter().enumerate() {
        let v = [nd.a.x, nd.a.y, nd.a.z, nd.wd.x, nd.wd.y, nd.wd.z];
        it.acc[6 * i..6 * i + 6].copy_from_slice(&v);
    }
    let n6 = 6 * sys.n_nodes();
    for (j, c) in it.state.coords.iter().take(sys.n_coordinates).enumerate() {
        it.acc[n6 + j] = c.a;
    }
    let z0 = n6 + sys.n_coordinates;
    for (j, z) in it.state.states.iter().enumerate() {
        it.acc[z0 + j] = z.zd;
    }
    sys.update_passive_coordinates(&mut it.state, true);
    it.mu.copy_from_slice(&it.state.lambda);
    // Held joint reactions: those of the consistent initial state (the samples above
    // read the state's previous multipliers); the holds due are taken again with them.
    if !sys.signals.reactions.is_empty() {
        sys.hold_reactions(&mut it.state, &it.mu);
        if sys.sample(&mut it.state, fresh) {
            it.restart_consistent();
        }
    }
    Ok((it, viol0))
}

/// The consistent initial state of a dynamic analysis (assembly onto the joints,
/// velocities, accelerations and multipliers), for the other integrators. On failure the
/// reason is in `summary` and the state reached is returned.
pub(super) fn consistent_start(
    sys: &System,
    settings: &DynamicSettings,
    initial: State,
    summary: &mut AnalysisSummary,
) -> Result<State, Box<State>> {
    start(sys, settings, initial, settings.t_start, summary).map(|(it, _)| {
        let mut s = it.state;
        s.lambda.clone_from(&it.mu);
        s
    })
}

/// Integrates from `initial` over `[t_start, t_end]`.
pub fn run_dynamic(
    sys: &System,
    name: &str,
    settings: &DynamicSettings,
    initial: State,
    recorder: &mut dyn Recorder,
    progress: Progress,
) -> Result<AnalysisSummary, crate::Error> {
    if settings.integrator != IntegratorType::GeneralizedAlpha {
        return super::energy_preserving::run_energy_consistent(
            sys, name, settings, initial, recorder, progress,
        );
    }
    let clock = Instant::now();
    let t0 = settings.t_start;
    let mut summary = AnalysisSummary::new(name, "dynamic");
    let fail = |summary: &mut AnalysisSummary, time: f64, reason: String, hint: Option<String>| {
        summary.failure = Some(SolverFailure {
            analysis: name.to_string(),
            time,
            reason,
            hint,
        });
    };
    let (mut it, viol0) = match start(sys, settings, initial, settings.t_start, &mut summary) {
        Ok(x) => x,
        Err(state) => {
            summary.final_state = *state;
            summary.wall_time = clock.elapsed();
            return Ok(summary);
        }
    };
    let ctx0 = sys.context(t0, 1.0);
    let mut energy = Energy {
        kinetic: sys.kinetic_energy(&it.state),
        potential: sys.potential_energy(&ctx0, &it.state),
        external_work: 0.0,
        dissipated: 0.0,
    };
    // External power: applied loads, input ports, and the drives (rheonomic constraints).
    let mut p_ext = sys.external_power(&ctx0, &it.state) + sys.drive_power(&it.state, &it.mu);
    let mut p_dis = sys.dissipated_power(&it.state);
    let record = |it: &Integrator,
                  energy: Energy,
                  viol: f64,
                  diag: Option<StepDiagnostics>,
                  rec: &mut dyn Recorder| {
        rec.record(
            sys,
            &OutputFrame {
                time: it.state.time,
                state: &it.state,
                mu: &it.mu,
                energy,
                constraint_violation: viol,
                load_factor: 1.0,
                diagnostics: diag,
            },
        )
    };
    let diag0 = settings.solver.diagnostics.then_some(StepDiagnostics {
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
    let bad = super::first_non_finite(sys, &it.state, &energy)
        .map(|what| super::non_finite_failure(name, t0, what))
        .or_else(|| {
            sys.range_violation(&it.state)
                .map(|what| super::range_failure(name, t0, what))
        });
    if let Some(f) = bad {
        summary.failure = Some(f);
        summary.final_state = it.state.clone();
        summary.wall_time = clock.elapsed();
        return Ok(summary);
    }
    record(&it, energy, viol0, diag0, recorder)?;
    summary.max_constraint_violation = viol0;

    let span = settings.t_end - t0;
    let mut h = settings.step;
    let mut good_since_cut = usize::MAX;
    let mut step_index: usize = 0;
    // Steps on the nominal grid are placed at t0 + k·step, so long runs do not drift.
    let mut grid_k: u64 = 0;
    let adaptive = settings.adaptive;
    let mut on_grid = adaptive.is_none();
    let mut hold_next = false;
    // Adaptive steps: breakpoints of the time functions to land on, the previous error
    // (PI controller) and the rejections since the last accepted step.
    let breakpoints = it.breakpoints.clone();
    let mut previous_error: f64 = 1.0;
    let mut rejected_here: usize = 0;
    // Event location (adaptive steps): the event functions at the start of the step and
    // at the trial end, and the end of a step redone to land just past an event.
    let locate = adaptive.is_some_and(|a| a.event_location)
        && (sys.n_events > 0 || !sys.granular.is_empty());
    let mut ev = EventWork {
        start: vec![(0.0, 0.0); if locate { sys.n_events } else { 0 }],
        end: vec![(0.0, 0.0); if locate { sys.n_events } else { 0 }],
        scratch: Vec::new(),
        pair_start: Vec::new(),
        pair_end: Vec::new(),
    };
    if locate {
        sys.event_values(&it.state, &mut ev.start, &mut ev.scratch);
    }
    let mut event_target: Option<f64> = None;
    let mut outputs = super::output_grid::OutputGrid::new(t0, settings.output_interval);
    while it.state.time < settings.t_end {
        let t = it.state.time;
        let mut target = if on_grid && h == settings.step {
            t0 + (grid_k + 1) as f64 * settings.step
        } else {
            t + h
        };
        let nominal = target;
        // Fixed and adaptive steps land on every breakpoint (one on the grid is snapped to
        // the last ulp), so that the restart there applies; a fixed step cut short by one
        // leaves its grid point ahead (the grid resumes after it).
        if let Some(&b) = breakpoints.iter().find(|&&b| b > t + 1e-9 * h)
            && b < target + 1e-9 * h
        {
            target = b;
        }
        if let Some(e) = event_target
            && e < target
        {
            target = e;
        }
        // Fixed or adaptive, steps land on the sample instants of sample-and-hold values.
        if let Some(b) = sys.next_sample(t)
            && b < target + 1e-9 * h
        {
            target = b;
        }
        // Steps land on the output instants of `output_interval`.
        if let Some(g) = &outputs {
            target = g.land(target, h);
        }
        if target > settings.t_end || settings.t_end - target < 1e-9 * h {
            target = settings.t_end;
        }
        let h_try = target - t;
        let predictor = if hold_next {
            Predictor::Hold
        } else {
            it.predictor
        };
        match it.step(h_try, predictor) {
            Ok(_) if !it.check_contacts() => {
                // A granular pair came into contact outside the candidate set: redo the
                // step with it.
                summary.contact_redos += 1;
                continue;
            }
            Ok(report) => {
                hold_next = false;
                let error = match &adaptive {
                    Some(a) => it.local_error(h_try, a),
                    None => f64::NAN,
                };
                if error > 1.0 {
                    summary.rejected_steps += 1;
                    rejected_here += 1;
                    if h_try <= settings.min_step * (1.0 + 1e-9) {
                        fail(
                            &mut summary,
                            t,
                            format!(
                                "the local error estimate is {error:.3} times the tolerance at the smallest step {h_try:.3e} s"
                            ),
                            Some(
                                "raise `tolerance_abs`/`tolerance_rel`, or lower `min_step`".into(),
                            ),
                        );
                        break;
                    }
                    // Retry with the step the error asks for (local error O(h³)).
                    h = (h_try * (0.9 * error.powf(-1.0 / 3.0)).max(0.2)).max(settings.min_step);
                    event_target = None;
                    continue;
                }
                let mut first_crossing_found = false;
                if locate {
                    sys.event_values(&it.trial, &mut ev.end, &mut ev.scratch);
                    pair_events(sys, &it.contacts.pairs, &it.state, &mut ev.pair_start);
                    pair_events(sys, &it.contacts.pairs, &it.trial, &mut ev.pair_end);
                    // An event crossed more than the resolution before the end: redo the
                    // step ending just past it (the law is smooth on each side).
                    let resolution = (1e-3 * h).max(settings.min_step);
                    let first = ev
                        .start
                        .iter()
                        .zip(&ev.end)
                        .chain(ev.pair_start.iter().zip(&ev.pair_end))
                        .filter_map(|(&g0, &g1)| super::events::first_crossing(g0, g1, h_try))
                        .min_by(f64::total_cmp);
                    if let Some(theta) = first
                        && (1.0 - theta) * h_try > resolution
                    {
                        summary.rejected_steps += 1;
                        rejected_here += 1;
                        event_target =
                            Some(t + (theta * h_try + 0.5 * resolution).max(settings.min_step));
                        continue;
                    }
                    first_crossing_found = first.is_some();
                    std::mem::swap(&mut ev.start, &mut ev.end);
                }
                event_target = None;
                it.accept();
                if first_crossing_found {
                    it.restart_accelerations();
                }
                // The step was aimed at `target`; t + (target − t) may miss it by an ulp.
                it.state.time = target;
                step_index += 1;
                summary.steps += 1;
                summary.newton_iterations += report.iterations;
                summary.line_search_backtracks += report.backtracks;
                // A step shortened to a sample instant leaves the grid point ahead.
                if on_grid && h == settings.step && (target - nominal).abs() <= 1e-9 * h {
                    grid_k += 1;
                }
                it.settle();
                let ctx = sys.context(it.state.time, 1.0);
                // The elements' power at the last Newton iterate where they keep it
                // (aerodynamic stations, damped beams; docs/aerodynamics.md,
                // "Performance").
                let p_ext1 = sys.evaluated_external_power(&ctx, &it.state)
                    + sys.drive_power(&it.state, &it.mu);
                let p_dis1 = sys.evaluated_dissipated_power(&it.state);
                energy.external_work += 0.5 * h_try * (p_ext + p_ext1);
                energy.dissipated += 0.5 * h_try * (p_dis + p_dis1);
                p_ext = p_ext1;
                p_dis = p_dis1;
                let viol = report.constraint_violation;
                summary.max_constraint_violation = summary.max_constraint_violation.max(viol);
                let last = it.state.time >= settings.t_end;
                let output = match outputs.as_mut() {
                    Some(g) => g.reached(it.state.time, h_try),
                    None => step_index.is_multiple_of(settings.output_every),
                } || last;
                if output {
                    sys.update_passive_coordinates(&mut it.state, true);
                    energy.kinetic = sys.kinetic_energy(&it.state);
                    energy.potential = sys.potential_energy(&ctx, &it.state);
                }
                if let Some(what) = super::first_non_finite(sys, &it.state, &energy) {
                    summary.failure = Some(super::non_finite_failure(name, it.state.time, what));
                    break;
                }
                if let Some(what) = sys.range_violation(&it.state) {
                    summary.failure = Some(super::range_failure(name, it.state.time, what));
                    break;
                }
                if output {
                    let diag = if settings.solver.diagnostics {
                        let (c, kind) = if it.lin.is_factored() {
                            condition_number(&it.matrix, &mut it.lin)
                        } else {
                            (f64::NAN, crate::solve::condition::ConditionKind::Exact2Norm)
                        };
                        Some(StepDiagnostics {
                            newton_iterations: report.iterations,
                            residual_norm: report.last_residual,
                            correction_norm: report.last_correction,
                            condition: c,
                            condition_kind: kind,
                            step_size: h_try,
                            error_estimate: error,
                            rejected: rejected_here,
                            line_search_backtracks: report.backtracks,
                        })
                    } else {
                        None
                    };
                    record(&it, energy, viol, diag, recorder)?;
                }
                progress(((it.state.time - t0) / span).clamp(0.0, 1.0));
                rejected_here = 0;
                if let Some(a) = &adaptive {
                    // PI controller (Gustafsson 1991; Hairer & Wanner, IV.2), local error
                    // order 3: h_new = 0.9 h e_n^(−0.7/3) e_(n−1)^(0.4/3), growth in [0.2, 5].
                    let e = error.max(1e-10);
                    let factor =
                        (0.9 * e.powf(-0.7 / 3.0) * previous_error.powf(0.4 / 3.0)).clamp(0.2, 5.0);
                    let mut next = h_try * factor;
                    // A step shortened to land on a breakpoint or t_end does not shrink
                    // the next one.
                    if h_try < h * (1.0 - 1e-9) {
                        next = next.max(h);
                    }
                    h = next.clamp(settings.min_step, a.step_max);
                    previous_error = e.max(1e-4);
                } else if h < settings.step {
                    good_since_cut = good_since_cut.saturating_add(1);
                    if good_since_cut >= REGROW_AFTER {
                        h = (2.0 * h).min(settings.step);
                        good_since_cut = 0;
                    }
                }
            }
            Err(failure) => {
                summary.rejected_steps += 1;
                it.lin.invalidate();
                hold_next = true;
                if predictor != Predictor::Hold {
                    // Retry at the same size from the held configuration.
                    continue;
                }
                on_grid = false;
                let next = h_try / 2.0;
                if next < settings.min_step {
                    let hint = match &failure {
                        NewtonFailure::Singular { block } => Some(singular_hint(sys, &it.asm, *block)),
                        NewtonFailure::NotFinite { .. } => Some(
                            "the solution blew up: check units, masses and stiffnesses, or reduce `step`".into(),
                        ),
                        _ => Some(format!(
                            "the step was cut down to {:.3e} s (min_step {:.3e}); a smaller `step`, more dissipation (lower rho_inf) or a larger `tolerance` may help",
                            h_try, settings.min_step
                        )),
                    };
                    fail(
                        &mut summary,
                        t,
                        format!("{failure} with step {h_try:.3e} s"),
                        hint,
                    );
                    break;
                }
                h = next;
                good_since_cut = 0;
            }
        }
    }
    summary.factorizations += it.lin.stats.factorizations + it.contacts.factorizations;
    summary.fallbacks = it.lin.stats.fallbacks + it.contacts.fallbacks;
    summary.pattern_rebuilds = it.contacts.rebuilds;
    summary.max_candidate_pairs = it.contacts.most;
    summary.final_state = it.state;
    summary.wall_time = clock.elapsed();
    Ok(summary)
}

/// Event functions at both ends of a step ([`super::events`]).
struct EventWork {
    start: Vec<(f64, f64)>,
    end: Vec<(f64, f64)>,
    scratch: Vec<f64>,
    /// The granular candidate pairs' event functions at the step's start and end (the
    /// pairs change between steps, so both are evaluated for each attempt).
    pair_start: Vec<(f64, f64)>,
    pair_end: Vec<(f64, f64)>,
}

/// The event functions of the granular candidate `pairs` at `s`
/// ([`crate::elements::GranularSet::pair_event`]).
fn pair_events(
    sys: &System,
    pairs: &[(usize, usize, usize)],
    s: &State,
    out: &mut Vec<(f64, f64)>,
) {
    out.clear();
    out.extend(
        pairs
            .iter()
            .map(|&(g, i, j)| sys.granular[g].pair_event(&s.nodes, i, j)),
    );
}

/// What one [`Simulation::step`] did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepReport {
    /// Time reached (the requested end of the step).
    pub time: f64,
    /// Accepted sub-steps (1 unless Newton failures made the step be cut).
    pub sub_steps: usize,
    pub newton_iterations: usize,
    pub rejected: usize,
    /// max |Φ| at the end of the step.
    pub constraint_violation: f64,
}

/// A dynamic analysis driven one step at a time, state in and out: for scripting and
/// co-simulation. The same integrator as [`run_dynamic`] (Lie-group generalized-α with
/// the settings' ρ∞, formulation, tolerances and Newton variant); it records nothing.
///
/// ```no_run
/// # let loaded = samara::model::Model::from_file("examples/pendulum.toml")?;
/// # let sys = samara::system::System::new(&loaded.model);
/// # let samara::model::AnalysisKind::Dynamic(settings) = &loaded.model.analyses[0].kind else { panic!() };
/// let mut sim = samara::analysis::Simulation::new(&sys, settings, sys.initial_state())?;
/// while sim.time() < 1.0 {
///     sim.step(1e-3)?;
///     let bob = &sim.state().nodes[0];
///     // … exchange data with another code, then possibly sim.set_state(…) …
/// }
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub struct Simulation<'a> {
    it: Integrator<'a>,
    name: String,
    parts: Option<super::PartsReport>,
    warnings: Vec<String>,
}

impl<'a> Simulation<'a> {
    /// Starts at `settings.t_start` from `initial`, made consistent (assembly onto the
    /// joints, velocities, accelerations and state rates).
    pub fn new(
        sys: &'a System,
        settings: &'a DynamicSettings,
        initial: State,
    ) -> Result<Self, SolverFailure> {
        if let Some(why) = shape_mismatch(sys, &initial) {
            return Err(SolverFailure {
                analysis: "simulation".into(),
                time: settings.t_start,
                reason: why,
                hint: Some("start from `System::initial_state` or a state of this model".into()),
            });
        }
        let mut summary = AnalysisSummary::new("simulation", "dynamic");
        match start(sys, settings, initial, settings.t_start, &mut summary) {
            Ok((it, _)) => Ok(Self {
                it,
                name: summary.name,
                parts: summary.parts,
                warnings: summary.warnings,
            }),
            Err(_) => Err(summary.failure.unwrap_or_else(|| SolverFailure {
                analysis: "simulation".into(),
                time: settings.t_start,
                reason: "the initial conditions could not be made consistent".into(),
                hint: None,
            })),
        }
    }

    pub fn time(&self) -> f64 {
        self.it.state.time
    }

    /// How a two-part run shares out its iteration (`partition = "two_parts"`, planned).
    pub fn parts(&self) -> Option<super::PartsReport> {
        self.parts
    }

    /// What the start noted (e.g. why `partition = "two_parts"` was not taken).
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// The state at [`Self::time`].
    pub fn state(&self) -> &State {
        &self.it.state
    }

    /// Augmented multipliers μ = λ + ρΦ per enforced constraint equation (physical units).
    pub fn multipliers(&self) -> &[f64] {
        &self.it.mu
    }

    /// Advances by `h`: one step, or — when Newton fails even from the held configuration
    /// — sub-steps halved down to the settings' `min_step` that together reach `t + h`.
    pub fn step(&mut self, h: f64) -> Result<StepReport, SolverFailure> {
        let it = &mut self.it;
        let t0 = it.state.time;
        let target = t0 + h;
        let mut report = StepReport {
            time: target,
            sub_steps: 0,
            newton_iterations: 0,
            rejected: 0,
            constraint_violation: 0.0,
        };
        if !(h > 0.0 && target > t0) {
            return Err(self.failure(t0, format!("the step {h:e} does not move time")));
        }
        let mut hh = h;
        let mut hold = false;
        let mut good = 0usize;
        while it.state.time < target {
            let t = it.state.time;
            let mut end = t + hh;
            if end > target || target - end < 1e-9 * hh {
                end = target;
            }
            if let Some(b) = it.sys.next_sample(t)
                && b < end + 1e-9 * hh
            {
                end = b;
            }
            // Sub-steps land on every breakpoint inside the step, as the fixed steps of
            // `run_dynamic` do.
            if let Some(&b) = it.breakpoints.iter().find(|&&b| b > t + 1e-9 * hh)
                && b < end + 1e-9 * hh
            {
                end = b;
            }
            let predictor = if hold { Predictor::Hold } else { it.predictor };
            match it.step(end - t, predictor) {
                Ok(_) if !it.check_contacts() => continue,
                Ok(r) => {
                    it.accept();
                    it.state.time = end;
                    it.settle();
                    hold = false;
                    report.sub_steps += 1;
                    report.newton_iterations += r.iterations;
                    report.constraint_violation = r.constraint_violation;
                    good += 1;
                    if hh < h && good >= REGROW_AFTER {
                        hh = (2.0 * hh).min(h);
                        good = 0;
                    }
                }
                Err(f) => {
                    report.rejected += 1;
                    it.lin.invalidate();
                    if predictor != Predictor::Hold {
                        hold = true;
                        continue;
                    }
                    hold = true;
                    hh /= 2.0;
                    good = 0;
                    if hh < it.settings.min_step {
                        return Err(self.failure(t, format!("{f} (step cut to {hh:.3e} s)")));
                    }
                }
            }
        }
        it.sys.update_passive_coordinates(&mut it.state, true);
        Ok(report)
    }

    /// Replaces the state (for instance after a co-simulation exchange) and makes it
    /// consistent again from its time on, like a new start.
    pub fn set_state(&mut self, state: State) -> Result<(), SolverFailure> {
        let (settings, sys, t) = (self.it.settings, self.it.sys, state.time);
        if let Some(why) = shape_mismatch(sys, &state) {
            let mut f = self.failure(t, why);
            f.hint = Some("set a state of this model, e.g. a changed copy of `state()`".into());
            return Err(f);
        }
        let mut summary = AnalysisSummary::new(&self.name, "dynamic");
        match start(sys, settings, state, t, &mut summary) {
            Ok((it, _)) => {
                self.it = it;
                Ok(())
            }
            Err(_) => Err(summary.failure.unwrap_or_else(|| {
                self.failure(t, "the state could not be made consistent".into())
            })),
        }
    }

    fn failure(&self, time: f64, reason: String) -> SolverFailure {
        SolverFailure {
            analysis: self.name.clone(),
            time,
            reason,
            hint: None,
        }
    }
}
