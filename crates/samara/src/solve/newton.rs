//! Newton–Raphson with convergence control.
//!
//! Each iteration solves `J Δ = −r` and applies `Δ`. It has converged when
//! 1. the weighted norm ε = `max_i |δq_i| / (atol + rtol |ref_i|)` of the configuration
//!    change made by the correction is ≤ 1 — or, once the contraction rate θ = ε_k/ε_{k−1}
//!    < 0.9 is known, the error it leaves, ε θ/(1 − θ), is ≤ 1 (Hairer & Wanner, Solving
//!    ODEs II, §IV.8). The problem computes ε: configuration unknowns only, in m and rad,
//!    so the test does not depend on the scaling of the equations. The first correction
//!    of a solve that reuses a matrix J̃ factored earlier is never accepted: its size says
//!    nothing about the error, −J̃⁻¹r against −J⁻¹r (accepting it let modified Newton on
//!    the pendulum of tests/options.rs end 2.6e-5 m from the exact answer of the step
//!    equations at tolerance 1e-10); and
//! 2. the constraint violation `max |Φ|` at the updated iterate is ≤ the tolerance.
//!
//! The rate θ is the slower of the configuration's and the multipliers' (the ratio of
//! successive max-norms of the multiplier corrections), as long as the multipliers still
//! change by more than the relative tolerance of the largest of them. With a stale matrix
//! the two contract at different rates: on the 1,000-link spherical chain of
//! examples/bench the multipliers contracted at 0.17 per iteration while the
//! configuration contracted at 0.02, so the configuration's rate alone accepted iterates
//! whose multipliers were 0.2 % off; the accelerations carried those errors into the
//! following steps, and the chain gained energy until Newton failed at t = 0.9 s. Which
//! matrix is stale (below) is still judged on the configuration's rate: judging it on the
//! slower rate too cost the 100-link chain 43 % more factorizations for 14 % fewer
//! iterations, +4 % instructions over judging the stop alone (docs/integrators.md).
//!
//! With `reuse_jacobian` (modified Newton) the factorization is kept while the correction
//! norm contracts by at least [`SLOW_CONTRACTION`] per iteration. A solve that converged
//! with a reused matrix whose last contraction rate θ exceeded [`STALE_CONTRACTION`]
//! drops the factorization, so that the next solve starts with a fresh matrix instead of
//! spending extra iterations on the stale one (the rate of a reused matrix's second
//! correction is not judged: the first carries the predictor's error in the unknowns the
//! norm does not measure, such as multipliers and element states).
//!
//! With `line_search` (damped Newton) a correction that has not converged is accepted only
//! if it lowers the residual norm, `‖r(y + αΔ)‖ ≤ (1 − 10⁻⁴ α) ‖r(y)‖` (Armijo on ‖r‖);
//! otherwise α is halved (down to 2⁻⁶, then the last α is kept). The exact Newton
//! direction descends ‖r‖² wherever r is differentiable, so this stops the cycling of
//! Newton across kinks of piecewise-smooth laws (a friction cone at zero slip) — the
//! iterates keep lowering ‖r‖ instead of jumping from one side of the kink to the other.
//! A full step that lowers the residual is taken as it is, so smooth problems iterate as
//! without it (one residual evaluation more per iteration).

use super::{BlockMatrix, LinearError, LinearSolver};

/// Contraction rate above which modified Newton refactorizes: a factorization with its
/// matrix costs about five residual iterations in the chain benchmark, so a matrix that
/// still halves the correction is worth keeping (docs/integrators.md).
pub const SLOW_CONTRACTION: f64 = 0.5;

/// Contraction rate of a reused matrix's last correction above which modified Newton
/// refactorizes at the start of the next solve: a stale matrix costs several iterations
/// in every solve until one of them contracts slower than [`SLOW_CONTRACTION`], a fresh
/// one two. Measured (docs/integrators.md): 0.1 beats 0.2 and no carry-over on the chain
/// benchmark (N = 100 revolute, modified, callgrind) and on the flexible rotor, where
/// 0.05 and 0.2 come close.
pub const STALE_CONTRACTION: f64 = 0.1;

/// A nonlinear problem `r(y) = 0` with iteration matrix `J ≈ ∂r/∂y`.
pub trait NewtonSystem {
    /// Residual at the current iterate; the iteration matrix too if `matrix` is given.
    fn evaluate(&mut self, residual: &mut [f64], matrix: Option<&mut BlockMatrix>);
    /// Applies the correction `Δ` and returns the sizes of its parts.
    fn apply(&mut self, delta: &[f64]) -> Correction;
    /// `max |Φ|` at the current iterate.
    fn constraint_violation(&mut self) -> f64;
}

/// Sizes of a Newton correction.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Correction {
    /// Weighted norm of the configuration change (≤ 1 means small enough).
    pub configuration: f64,
    /// `max |Δλ|` (0 without multipliers).
    pub multipliers: f64,
    /// `max |Δλ| ≤ rtol max |λ|`: the multipliers no longer change by more than the
    /// relative tolerance of the largest of them.
    pub multipliers_settled: bool,
}

impl Correction {
    /// Sizes of a correction that changed the configuration by the weighted norm
    /// `configuration` and the multipliers by `dlambda` to `lambda`.
    pub fn new(configuration: f64, dlambda: &[f64], lambda: &[f64], rtol: f64) -> Self {
        let largest = |v: &[f64]| v.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        let multipliers = largest(dlambda);
        Self {
            configuration,
            multipliers,
            multipliers_settled: multipliers <= rtol * largest(lambda),
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NewtonSettings {
    pub max_iterations: usize,
    /// Tolerance on `max |Φ|`.
    pub constraint_tolerance: f64,
    /// Modified Newton: keep the factorization while convergence is fast.
    pub reuse_jacobian: bool,
    /// Damped Newton: backtrack corrections that do not lower the residual norm.
    pub line_search: bool,
}

/// Armijo constant and the smallest step fraction of the line search.
const ARMIJO: f64 = 1e-4;
const MIN_STEP_FRACTION: f64 = 1.0 / 64.0;

/// How a converged solve went.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NewtonReport {
    pub iterations: usize,
    pub factorizations: usize,
    /// Euclidean norm of the residual at the first and last evaluation.
    pub first_residual: f64,
    pub last_residual: f64,
    /// Weighted correction norm of the last iteration.
    pub last_correction: f64,
    pub constraint_violation: f64,
    /// Corrections shortened by the line search (halvings).
    pub backtracks: usize,
}

/// Why Newton stopped without converging.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum NewtonFailure {
    #[error(
        "Newton did not converge in {iterations} iterations (last correction norm {correction:.3e}, constraint violation {violation:.3e})"
    )]
    NotConverged {
        iterations: usize,
        correction: f64,
        violation: f64,
    },
    #[error(
        "Newton diverged at iteration {iteration} (correction norm grew from {previous:.3e} to {correction:.3e})"
    )]
    Diverged {
        iteration: usize,
        previous: f64,
        correction: f64,
    },
    #[error("the residual or the correction became NaN or infinite at iteration {iteration}")]
    NotFinite { iteration: usize },
    #[error("the iteration matrix is singular at block {block}")]
    Singular { block: usize },
}

/// Reusable Newton buffers.
pub struct NewtonWork {
    pub residual: Vec<f64>,
    pub delta: Vec<f64>,
}

impl NewtonWork {
    pub fn new(n: usize) -> Self {
        Self {
            residual: vec![0.0; n],
            delta: vec![0.0; n],
        }
    }
}

/// `‖v‖₂` from eight partial sums: one running sum is a chain of dependent adds (add
/// latency per entry), 1.5 % of the chain benchmark's modified-Newton time.
fn norm2(v: &[f64]) -> f64 {
    let (chunks, rest) = v.as_chunks::<8>();
    let mut acc = [0.0f64; 8];
    for c in chunks {
        for (a, x) in acc.iter_mut().zip(c) {
            *a += x * x;
        }
    }
    let tail: f64 = rest.iter().map(|x| x * x).sum();
    (acc.iter().sum::<f64>() + tail).sqrt()
}

/// Whether every entry is finite, eight at a time with no early exit (vectorized; the
/// entry-by-entry test with its exit was another 1 % of the same benchmark).
fn all_finite(v: &[f64]) -> bool {
    let (chunks, rest) = v.as_chunks::<8>();
    chunks
        .iter()
        .all(|c| c.iter().fold(true, |ok, x| ok & x.is_finite()))
        && rest.iter().all(|x| x.is_finite())
}

/// Solves the problem from its current iterate.
pub fn newton(
    problem: &mut dyn NewtonSystem,
    lin: &mut LinearSolver,
    matrix: &mut BlockMatrix,
    work: &mut NewtonWork,
    settings: &NewtonSettings,
) -> Result<NewtonReport, NewtonFailure> {
    let mut report = NewtonReport::default();
    let mut previous = f64::INFINITY;
    let mut previous_multipliers = f64::INFINITY;
    let mut refactor = !settings.reuse_jacobian || !lin.is_factored();
    for it in 1..=settings.max_iterations {
        report.iterations = it;
        let fresh = refactor;
        if refactor {
            problem.evaluate(&mut work.residual, Some(matrix));
        } else {
            problem.evaluate(&mut work.residual, None);
        }
        let rn = norm2(&work.residual);
        if !rn.is_finite() {
            return Err(NewtonFailure::NotFinite { iteration: it });
        }
        if it == 1 {
            report.first_residual = rn;
        }
        report.last_residual = rn;
        for (d, r) in work.delta.iter_mut().zip(&work.residual) {
            *d = -r;
        }
        if refactor {
            // Factored and solved in one sweep where the linear solver can.
            let mut factored = lin.factor_and_solve(matrix, &mut work.delta);
            if lin.needs_assembly() {
                // The block LU rejected a matrix assembled into its storage: the fallback
                // gets it assembled again, row-major (the same iterate, the same values).
                problem.evaluate(&mut work.residual, Some(matrix));
                for (d, r) in work.delta.iter_mut().zip(&work.residual) {
                    *d = -r;
                }
                factored = lin.factor_and_solve(matrix, &mut work.delta);
            }
            factored.map_err(|e| match e {
                LinearError::Singular { block } => NewtonFailure::Singular { block },
            })?;
            report.factorizations += 1;
        } else {
            lin.solve_in_place(&mut work.delta);
        }
        if !all_finite(&work.delta) {
            // A pivot the block LU rejected that the sparse LU let through is the cause.
            return Err(match lin.fallback_block() {
                Some(block) => NewtonFailure::Singular { block },
                None => NewtonFailure::NotFinite { iteration: it },
            });
        }
        let correction = problem.apply(&work.delta);
        let eps = correction.configuration;
        report.last_correction = eps;
        if settings.line_search && eps > 1.0 {
            // Backtrack while the residual norm does not drop enough.
            let mut alpha = 1.0;
            loop {
                problem.evaluate(&mut work.residual, None);
                let trial = norm2(&work.residual);
                if trial.is_finite() && trial <= (1.0 - ARMIJO * alpha) * rn
                    || alpha <= MIN_STEP_FRACTION
                {
                    break;
                }
                let next = 0.5 * alpha;
                for d in work.delta.iter_mut() {
                    *d *= (next - alpha) / alpha;
                }
                problem.apply(&work.delta);
                for d in work.delta.iter_mut() {
                    *d *= next / (next - alpha);
                }
                alpha = next;
                report.backtracks += 1;
            }
        }
        // Error left after this correction: ≈ eps·θ/(1 − θ) for a contraction rate θ
        // (Hairer & Wanner, Solving ODEs II, §IV.8); before θ is known, eps itself. θ is
        // the multipliers' rate if that is slower and they still change (module doc).
        let rate = eps / previous;
        let mut theta = rate;
        if !correction.multipliers_settled {
            theta = theta.max(correction.multipliers / previous_multipliers);
        }
        previous_multipliers = correction.multipliers;
        let remaining = if it > 1 && theta < 0.9 {
            eps * theta / (1.0 - theta)
        } else {
            eps
        };
        // A reused matrix's first correction is not judged (module doc).
        if (fresh || it > 1) && (eps <= 1.0 || remaining <= 1.0) {
            let viol = problem.constraint_violation();
            report.constraint_violation = viol;
            if viol <= settings.constraint_tolerance {
                // A matrix that contracted slowly is replaced at the next solve (module doc).
                if settings.reuse_jacobian && !fresh && it >= 3 && rate > STALE_CONTRACTION {
                    lin.invalidate();
                }
                return Ok(report);
            }
        }
        if fresh && it >= 3 && rate > 2.0 && !settings.line_search {
            return Err(NewtonFailure::Diverged {
                iteration: it,
                previous,
                correction: eps,
            });
        }
        refactor = !settings.reuse_jacobian || rate > SLOW_CONTRACTION;
        previous = eps;
    }
    let violation = problem.constraint_violation();
    Err(NewtonFailure::NotConverged {
        iterations: settings.max_iterations,
        correction: report.last_correction,
        violation,
    })
}

#[cfg(test)]
mod tests {
    use super::{Correction, all_finite, norm2};

    /// `Correction::new`: the multipliers are settled when their largest change is within
    /// `rtol` of the largest multiplier (4e-3 here), and trivially without multipliers.
    #[test]
    fn multipliers_settle_below_the_relative_tolerance_of_the_largest() {
        let lambda = [4000.0, -3.0, 0.0];
        let c = Correction::new(0.5, &[1e-3, -3e-3, 0.0], &lambda, 1e-6);
        assert_eq!((c.configuration, c.multipliers), (0.5, 3e-3));
        assert!(c.multipliers_settled, "3e-3 ≤ 1e-6 × 4000");
        let c = Correction::new(0.5, &[1e-3, -5e-3, 0.0], &lambda, 1e-6);
        assert!(!c.multipliers_settled, "5e-3 > 1e-6 × 4000");
        let none = Correction::new(2.0, &[], &[], 1e-6);
        assert!(none.multipliers == 0.0 && none.multipliers_settled);
    }

    /// The lane sums against the one running sum: both add n ≤ 40 positive squares, so
    /// they agree within n·ε of the result (summation-order round-off); the finite check
    /// finds a NaN or an infinity in every position, in the lanes and in the tail.
    #[test]
    fn lane_sums_and_finite_check_match_the_plain_loops() {
        for n in 0..40 {
            let v: Vec<f64> = (0..n).map(|i| ((i * 37 % 11) as f64 - 5.0) * 0.3).collect();
            let plain = v.iter().map(|x| x * x).sum::<f64>().sqrt();
            assert!((norm2(&v) - plain).abs() <= 40.0 * f64::EPSILON * plain);
            assert!(all_finite(&v));
            for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                for k in 0..n {
                    let mut w = v.clone();
                    w[k] = bad;
                    assert!(!all_finite(&w), "n = {n}, entry {k} = {bad}");
                }
            }
        }
    }
}
