//! The time integrator on the linear oscillator ẍ + ω²x = 0 against the closed-form
//! amplification matrix of generalized-α (Chung & Hulbert 1993): the real dynamic analysis
//! (model from TOML, `run_analysis`: predictor, Newton, Lie-group update) on a mass on a
//! spring, for several ρ∞ and ωh.
//!
//! Chung & Hulbert's scheme on ẍ + ω²x = 0 (undamped), in the state (d, h v, h² a) with
//! Ω = ωh, has an amplification matrix whose invariants are, with
//! D = (1 − α_m) + (1 − α_f) β Ω²,
//!
//! ```text
//! D A₁ = 2 − 3α_m − Ω² [(1 − α_f)(γ + ½ − 2β) + α_f β]          (trace)
//! D A₂ = 1 − 3α_m + Ω² [½ + β − γ − α_f (3β − 2γ)]              (sum of principal minors)
//! D A₃ = −α_m − α_f Ω² (β − γ + ½)                              (determinant)
//! ```
//!
//! so every computed displacement sequence obeys x_{n+3} = A₁ x_{n+2} − A₂ x_{n+1} + A₃ x_n,
//! and the principal roots λ = ρ e^{±iΩ̄} of λ³ − A₁λ² + A₂λ − A₃ give the algorithmic damping
//! ratio ξ̄ = −ln ρ / Ω̄ and the relative period error Ω/Ω̄ − 1. The coefficients come from
//! ρ∞ by Chung & Hulbert's optimal choice α_m = (2ρ∞ − 1)/(ρ∞ + 1), α_f = ρ∞/(ρ∞ + 1),
//! γ = ½ − α_m + α_f, β = ¼ (1 − α_m + α_f)², written here independently of the code.
//! (samara imposes equilibrium at t_{n+1} and averages accelerations, Arnold & Brüls 2007;
//! on a linear problem that is the same recurrence.)

use crate::common;

use common::{model, run};
use nalgebra::{Complex, Matrix3};

/// Mass m = 1 on a spring k = 4π² (ω = 2π, period 1 s) along x, released from x₀ = 1 with
/// the equilibrium at x = 0. The spring is anchored 10⁴ m away (rest length 10⁴): its
/// direction never changes and its length stays positive, so the problem is exactly
/// linear — also for the steps of Ω = 100, whose first Newton iterate lands ~100 m away
/// (a short spring would let Newton through the anchor onto its mirror equilibrium).
/// Rounding of the length (10⁴ u ≈ 2e-12 m) is the accuracy floor.
fn oscillator(rho: f64, step: f64, t_end: f64) -> String {
    let k = 4.0 * std::f64::consts::PI.powi(2);
    format!(
        r#"[model]
name = "oscillator"

[[nodes]]
name = "mass"
position = [1.0, 0.0, 0.0]

[[bodies]]
name = "mass"
node = "mass"
mass = 1.0
inertia = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]

[[springs]]
name = "spring"
node_a = "ground"
point_a = [-1e4, 0.0, 0.0]
node_b = "mass"
stiffness = {k:.17e}
rest_length = 1e4

[[analyses]]
name = "free"
type = "dynamic"
t_end = {t_end:.17e}
step = {step:.17e}
rho_inf = {rho}
tolerance = 1e-10
relative_tolerance = 1e-10
"#
    )
}

const OMEGA: f64 = 2.0 * std::f64::consts::PI;
const X0: f64 = 1.0;

/// The displacements x_n at t = n h of the real run.
fn displacements(rho: f64, step: f64, steps: usize) -> Vec<f64> {
    let m = model(&oscillator(rho, step, step * steps as f64));
    let (s, h) = run(&m);
    assert_eq!(s.steps, steps);
    assert_eq!(s.rejected_steps, 0);
    h.frames
        .iter()
        .enumerate()
        .map(|(n, f)| {
            assert!((f.time - n as f64 * step).abs() < 1e-9 * step);
            let x = f.state.nodes[0].x;
            // Stays on the x axis: the problem is one-dimensional.
            assert!(x.y.abs() < 1e-15 && x.z.abs() < 1e-15);
            x.x
        })
        .collect()
}

/// Chung & Hulbert's coefficients (α_m, α_f, β, γ) for ρ∞.
fn coefficients(rho: f64) -> (f64, f64, f64, f64) {
    let am = (2.0 * rho - 1.0) / (rho + 1.0);
    let af = rho / (rho + 1.0);
    let g = 0.5 - am + af;
    (am, af, 0.25 * (1.0 - am + af).powi(2), g)
}

/// The invariants (A₁, A₂, A₃) of the amplification matrix at Ω = ωh.
fn invariants(rho: f64, big_omega: f64) -> [f64; 3] {
    let (am, af, b, g) = coefficients(rho);
    let w2 = big_omega * big_omega;
    let d = (1.0 - am) + (1.0 - af) * b * w2;
    [
        (2.0 - 3.0 * am - w2 * ((1.0 - af) * (g + 0.5 - 2.0 * b) + af * b)) / d,
        (1.0 - 3.0 * am + w2 * (0.5 + b - g - af * (3.0 * b - 2.0 * g))) / d,
        (-am - af * w2 * (b - g + 0.5)) / d,
    ]
}

/// Roots of λ³ − A₁λ² + A₂λ − A₃ (eigenvalues of the companion matrix).
fn roots(a: [f64; 3]) -> Vec<Complex<f64>> {
    let c = Matrix3::new(a[0], -a[1], a[2], 1.0, 0.0, 0.0, 0.0, 1.0, 0.0);
    c.complex_eigenvalues().iter().copied().collect()
}

/// (damping ratio ξ̄, relative period error) of a principal root λ at Ω.
fn damping_and_period(lambda: Complex<f64>, big_omega: f64) -> (f64, f64) {
    let omega_bar = lambda.im.abs().atan2(lambda.re);
    (-lambda.norm().ln() / omega_bar, big_omega / omega_bar - 1.0)
}

/// The closed form's principal (complex) root; below the bifurcation Ω the principal
/// roots are a complex pair.
fn principal_root(rho: f64, big_omega: f64) -> Complex<f64> {
    roots(invariants(rho, big_omega))
        .into_iter()
        .filter(|z| z.im > 0.0)
        .max_by(|a, b| a.norm().total_cmp(&b.norm()))
        .expect("a complex pair")
}

/// The principal root measured from a sequence by Prony's method: the two-term recurrence
/// x_{n+2} = c₁ x_{n+1} + c₀ x_n fitted by least squares on `window`, λ² − c₁λ − c₀ = 0.
fn measured_root(x: &[f64], window: std::ops::Range<usize>) -> Complex<f64> {
    let (mut s11, mut s10, mut s00, mut r1, mut r0) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for n in window {
        let (a, b, y) = (x[n + 1], x[n], x[n + 2]);
        s11 += a * a;
        s10 += a * b;
        s00 += b * b;
        r1 += a * y;
        r0 += b * y;
    }
    let det = s11 * s00 - s10 * s10;
    let c1 = (r1 * s00 - r0 * s10) / det;
    let c0 = (s11 * r0 - s10 * r1) / det;
    let disc = Complex::new(c1 * c1 + 4.0 * c0, 0.0).sqrt();
    (Complex::new(c1, 0.0) + disc) / 2.0
}

/// Every run follows the closed-form recurrence to round-off: the residual of
/// x_{n+3} − A₁x_{n+2} + A₂x_{n+1} − A₃x_n, relative to x₀, is below 1e-10 over 200 steps
/// (on this linear problem Newton's first correction is exact and the second, at the
/// rounding floor ~2e-12, confirms it; the recurrence adds at most |A₁| + |A₂| + |A₃| ≈ 4
/// times that). Covers ρ∞ from 0 to 1 and Ω from 0.05 to 100 (far
/// beyond the resolved range, where the scheme must damp to ρ∞).
#[test]
fn runs_follow_the_closed_form_recurrence() {
    for rho in [0.0, 0.3, 0.6, 0.9, 1.0] {
        for big_omega in [0.05, 0.3, 1.0, 3.0, 100.0] {
            let x = displacements(rho, big_omega / OMEGA, 200);
            let [a1, a2, a3] = invariants(rho, big_omega);
            let worst = x
                .windows(4)
                .map(|w| (w[3] - a1 * w[2] + a2 * w[1] - a3 * w[0]).abs())
                .fold(0.0, f64::max)
                / X0;
            println!("ρ∞ = {rho}, Ω = {big_omega}: recurrence residual {worst:.2e}");
            assert!(worst < 1e-10, "ρ∞ = {rho}, Ω = {big_omega}: {worst:e}");
        }
    }
    // The closed form itself: spectral radius ρ∞ as Ω → ∞ (Chung & Hulbert's design), and
    // 1 at ρ∞ = 1 for every Ω (no numerical dissipation).
    for rho in [0.0, 0.3, 0.6, 0.9, 1.0] {
        let radius = |w: f64| {
            roots(invariants(rho, w))
                .iter()
                .map(|z| z.norm())
                .fold(0.0, f64::max)
        };
        // The limit roots are a triple root −ρ∞; at Ω = 1e4 the radius is within
        // ~Ω^(−2/3) ≈ 2e-3 of it (a triple root moves by the cube root of a perturbation).
        let r = radius(1e4);
        assert!((r - rho).abs() < 3e-3, "ρ∞ = {rho}: {r}");
        if rho == 1.0 {
            for w in [0.1, 1.0, 10.0] {
                assert!((radius(w) - 1.0).abs() < 1e-12);
            }
        }
    }
}

/// Algorithmic damping ratio ξ̄ and relative period error measured on the runs (Prony's
/// method on the displacements, after the spurious root has decayed) against the closed
/// form, for ρ∞ = 0, 0.5, 0.8, 1 and Ω = 0.05 … 0.8. The measurement is exact up to
/// round-off amplified by the fit: tolerance 1e-8 absolute on ξ̄ and on the period error
/// (whose values range from 1e-4 to 0.1). For ρ∞ = 1, ξ̄ = 0 (to 1e-10).
#[test]
fn damping_and_period_error_match_the_closed_form() {
    println!("  ρ∞      Ω     ξ̄ run        ξ̄ closed      ΔT/T run      ΔT/T closed");
    for rho in [0.0f64, 0.5, 0.8, 1.0] {
        let mut previous: Option<(f64, f64)> = None;
        for big_omega in [0.05, 0.1, 0.2, 0.4, 0.8] {
            // About four periods, at least 300 steps. The spurious root has |λ₃| ≤ 0.51 at
            // these Ω for ρ∞ ≤ 0.8 (0.5, 1e-4 … 0.02 and 0.5 for ρ∞ = 0, 0.5, 0.8), so its
            // share is below 1e-17 after the 60 steps skipped; at ρ∞ = 1 (α_m = α_f) the
            // consistent start a₀ = v̇₀ leaves it unexcited.
            let steps = ((4.0 * std::f64::consts::TAU / big_omega) as usize).max(300);
            let x = displacements(rho, big_omega / OMEGA, steps);
            let skip = if rho < 1.0 { 60 } else { 0 };
            let run = damping_and_period(measured_root(&x, skip..steps - 1), big_omega);
            let closed = damping_and_period(principal_root(rho, big_omega), big_omega);
            println!(
                "{rho:5.2} {big_omega:6.2} {:13.6e} {:13.6e} {:13.6e} {:13.6e}",
                run.0, closed.0, run.1, closed.1
            );
            assert!(
                (run.0 - closed.0).abs() < 1e-8 && (run.1 - closed.1).abs() < 1e-8,
                "ρ∞ = {rho}, Ω = {big_omega}: run {run:?}, closed form {closed:?}"
            );
            if rho == 1.0 {
                assert!(run.0.abs() < 1e-10, "{run:?}");
            }
            // Both grow with Ω (second order: ~Ω² for the period, ~Ω³ for ξ̄ at small Ω).
            if let Some(p) = previous {
                assert!(closed.1 > p.1 && (rho == 1.0 || closed.0 > p.0));
            }
            previous = Some(closed);
        }
    }
}

/// Second-order convergence of the real run to the exact x₀ cos ωt at t = 2.25 s (a zero
/// crossing after two periods, where the error is the phase error, O(Ω²) per period; at a
/// peak the phase error enters squared and the damping, O(Ω³), would dominate),
/// h = T/40 … T/320, for ρ∞ = 0, 0.5, 0.9, 1: the error ratios per halving give an order
/// of 2 ± 0.1.
#[test]
fn second_order_convergence() {
    for rho in [0.0, 0.5, 0.9, 1.0] {
        let errors: Vec<f64> = [40usize, 80, 160, 320]
            .iter()
            .map(|&per_period| {
                let steps = 9 * per_period / 4;
                let x = displacements(rho, 1.0 / per_period as f64, steps);
                (x[steps] - X0 * (OMEGA * 2.25).cos()).abs() / X0
            })
            .collect();
        let orders = common::orders(&errors);
        println!("ρ∞ = {rho}: errors {errors:?} orders {orders:.3?}");
        for o in &orders {
            assert!((o - 2.0).abs() < 0.1, "ρ∞ = {rho}: {errors:?}");
        }
    }
}
