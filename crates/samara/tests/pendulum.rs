//! Issue #2, verification 1 and 6: large-amplitude planar pendulum released at 170° from
//! the lowest point. The period against the closed form
//! T = 4 √(I_O / (m g L)) K(sin(θ₀/2)) (compound pendulum, I_O = m L² + I_yy) must
//! converge at second order in h; the constraint violation must stay within the Newton
//! tolerance at every step.

use crate::common;
use common::*;

const L: f64 = 1.0;
const M: f64 = 1.0;
const J: f64 = 1e-3;
const G: f64 = 9.81;

fn pendulum(theta0_deg: f64, step: f64, t_end: f64, rho: f64) -> String {
    let th = theta0_deg.to_radians();
    format!(
        r#"
[model]
name = "pendulum170"
gravity = [0.0, 0.0, -{G}]
[[nodes]]
name = "bob"
position = [{x}, 0.0, {z}]
[[bodies]]
name = "bob"
node = "bob"
mass = {M}
inertia = [[{J}, 0.0, 0.0], [0.0, {J}, 0.0], [0.0, 0.0, {J}]]
[[joints]]
name = "pivot"
type = "revolute"
node_a = "ground"
node_b = "bob"
position = [0.0, 0.0, 0.0]
axis = [0.0, 1.0, 0.0]
[[analyses]]
name = "swing"
type = "dynamic"
t_end = {t_end}
step = {step}
rho_inf = {rho}
tolerance = 1e-12
"#,
        x = L * th.sin(),
        z = -L * th.cos(),
    )
}

/// Times at which x(t) crosses zero, located with cubic Hermite interpolation of (x, ẋ)
/// on the step that brackets the crossing (interpolation error O(h⁴), below the O(h²)
/// integration error being measured).
fn zero_crossings(h: &samara::analysis::History) -> Vec<f64> {
    let mut out = Vec::new();
    for w in h.frames.windows(2) {
        let (a, b) = (&w[0], &w[1]);
        let (x0, x1) = (a.state.nodes[0].x.x, b.state.nodes[0].x.x);
        if x0 == 0.0 || x0.signum() == x1.signum() {
            continue;
        }
        let (v0, v1) = (a.state.nodes[0].v.x, b.state.nodes[0].v.x);
        let dt = b.time - a.time;
        let herm = |s: f64| {
            let (s2, s3) = (s * s, s * s * s);
            (2.0 * s3 - 3.0 * s2 + 1.0) * x0
                + (s3 - 2.0 * s2 + s) * dt * v0
                + (-2.0 * s3 + 3.0 * s2) * x1
                + (s3 - s2) * dt * v1
        };
        let (mut lo, mut hi) = (0.0, 1.0);
        for _ in 0..80 {
            let mid = 0.5 * (lo + hi);
            if herm(mid).signum() == x0.signum() {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        out.push(a.time + 0.5 * (lo + hi) * dt);
    }
    out
}

#[test]
fn period_at_170_degrees_converges_at_second_order() {
    let theta0 = 170.0f64;
    let io = M * L * L + J;
    let exact = 4.0 * (io / (M * G * L)).sqrt() * elliptic_k((theta0.to_radians() / 2.0).sin());
    let steps = [4e-3, 2e-3, 1e-3];
    let mut errors = Vec::new();
    for &h in &steps {
        let (summary, hist) = run(&model(&pendulum(theta0, h, 1.3 * exact, 0.9)));
        let c = zero_crossings(&hist);
        assert!(c.len() >= 3, "expected 3 bottom crossings, got {c:?}");
        let period = c[2] - c[0];
        errors.push((period - exact).abs() / exact);
        // Verification 6: every step's |Φ| within the Newton tolerance.
        assert!(
            summary.max_constraint_violation <= 1e-12,
            "violation {}",
            summary.max_constraint_violation
        );
        for f in &hist.frames {
            assert!(
                f.constraint_violation <= 1e-12,
                "t = {}: {}",
                f.time,
                f.constraint_violation
            );
        }
    }
    let p = orders(&errors);
    eprintln!("exact period {exact:.9} s; relative errors {errors:?}; observed orders {p:.3?}");
    // Second order: error ratio 4 per halving; ±0.25 in the observed order allows for the
    // asymptotic regime not being reached exactly at the coarsest step.
    for o in &p {
        assert!((o - 2.0).abs() < 0.25, "orders {p:?}");
    }
    // At h = 1e-3 (≈ 4900 steps per period) the period is within 1e-5 of the closed form
    // (measured 2.4e-6; the error constant of the scheme times (ωh)² with ω ≈ 3 rad/s).
    assert!(errors[2] < 1e-5, "{errors:?}");
}

#[test]
fn small_amplitude_period_matches_linear_theory() {
    // θ₀ = 2°: K(sin 1°) = π/2 (1 + k²/4 + …); compare with the closed form itself.
    let io = M * L * L + J;
    let exact = 4.0 * (io / (M * G * L)).sqrt() * elliptic_k((1.0f64).to_radians().sin());
    let (_, hist) = run(&model(&pendulum(2.0, 1e-3, 2.6 * exact, 1.0)));
    let c = zero_crossings(&hist);
    let period = c[2] - c[0];
    assert!((period - exact).abs() / exact < 1e-5, "{period} vs {exact}");
}
