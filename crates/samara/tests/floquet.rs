//! Floquet stability (issue #14, verification 4): the Mathieu equation
//!
//!     ẍ + c ẋ + (δ + ε cos t) x = 0,      T = 2π,
//!
//! built as a 1 kg body on a prismatic joint (the index-3 constraints remove the five
//! other motions) held by a spring whose stiffness varies as k f(t) with
//! f(t) = δ + ε sin(t + π/2) (`stiffness_function`). Reference: the monodromy matrix of
//! the scalar equation integrated in the test by classical RK4 with 20,000 steps per
//! period (error ~ (h⁴) ≈ 1e-13, far below what is measured).
//!
//! Tongues of the Mathieu chart (Nayfeh & Mook, "Nonlinear Oscillations", 1979, §5.2;
//! first order in ε): the first from δ = 1/4 between δ = 1/4 ± ε/2, the second from δ = 1
//! between δ = 1 − ε²/12 and δ = 1 + 5ε²/12. The points below lie well inside or well
//! outside them, and the RK4 reference confirms each.

use crate::common;

use common::model;
use nalgebra::{Complex, Matrix2};
use samara::analysis::History;
use samara::model::AnalysisKind;
use samara::system::System;
use std::f64::consts::PI;

fn mathieu(delta: f64, eps: f64, c: f64, steps: usize, extra: &str) -> String {
    format!(
        r#"
[model]
name = "mathieu"

[[nodes]]
name = "mass"
position = [0.0, 0.0, 0.0]

[[bodies]]
name = "mass"
node = "mass"
mass = 1.0
inertia = [[0.1, 0.0, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.1]]

[[joints]]
name = "slider"
type = "prismatic"
node_a = "ground"
node_b = "mass"
position = [0.0, 0.0, 0.0]
axis = [1.0, 0.0, 0.0]

[[springs]]
name = "spring"
node_a = "ground"
node_b = "mass"
point_a = [-1.0, 0.0, 0.0]
stiffness = 1.0
damping = {c}
stiffness_function = {{ type = "sine", amplitude = {eps}, frequency = {f}, phase = {phase}, offset = {delta} }}

[[analyses]]
name = "floquet"
type = "floquet"
period = {period}
steps_per_period = {steps}
{extra}
"#,
        f = 1.0 / (2.0 * PI),
        phase = PI / 2.0,
        period = 2.0 * PI,
    )
}

/// The monodromy of ẍ + cẋ + (δ + ε cos t)x = 0 over [0, 2π] by RK4.
fn reference(delta: f64, eps: f64, c: f64) -> Matrix2<f64> {
    let n = 20_000;
    let h = 2.0 * PI / n as f64;
    let f = |t: f64, x: [f64; 2]| [x[1], -c * x[1] - (delta + eps * t.cos()) * x[0]];
    let mut phi = Matrix2::zeros();
    for col in 0..2 {
        let mut x = if col == 0 { [1.0, 0.0] } else { [0.0, 1.0] };
        for k in 0..n {
            let t = k as f64 * h;
            let k1 = f(t, x);
            let k2 = f(
                t + h / 2.0,
                [x[0] + h / 2.0 * k1[0], x[1] + h / 2.0 * k1[1]],
            );
            let k3 = f(
                t + h / 2.0,
                [x[0] + h / 2.0 * k2[0], x[1] + h / 2.0 * k2[1]],
            );
            let k4 = f(t + h, [x[0] + h * k3[0], x[1] + h * k3[1]]);
            for i in 0..2 {
                x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
            }
        }
        phi[(0, col)] = x[0];
        phi[(1, col)] = x[1];
    }
    phi
}

/// Both multipliers of a 2 × 2 monodromy, sorted by (modulus, imaginary part) descending.
fn multipliers2(phi: &Matrix2<f64>) -> Vec<Complex<f64>> {
    let (tr, det) = (phi.trace(), phi.determinant());
    let disc = Complex::new(tr * tr / 4.0 - det, 0.0).sqrt();
    let mut v = vec![tr / 2.0 + disc, tr / 2.0 - disc];
    v.sort_by(|a, b| b.norm().total_cmp(&a.norm()).then(b.im.total_cmp(&a.im)));
    v
}

/// samara's multipliers of a Floquet model with `dim` states (all of them: the
/// conjugates of the modes added back; modes beyond the system's are NaN and skipped).
fn multipliers_of(text: &str, dim: usize) -> (Vec<Complex<f64>>, History) {
    let m = model(text);
    let sys = System::new(&m);
    let mut h = History::default();
    let s = samara::analysis::run_analysis(
        &sys,
        &m.analyses[0],
        sys.initial_state(),
        &mut h,
        &mut |_| {},
    )
    .unwrap();
    assert!(s.failure.is_none(), "{:?}", s.failure);
    let rho = &h
        .arrays
        .iter()
        .find(|a| a.0.name == "floquet_multiplier")
        .unwrap()
        .1;
    let mut v = Vec::new();
    for k in 0..rho.len() / 2 {
        let z = Complex::new(rho[2 * k], rho[2 * k + 1]);
        if z.re.is_nan() {
            continue;
        }
        v.push(z);
        if z.im != 0.0 {
            v.push(z.conj());
        }
    }
    v.sort_by(|a, b| b.norm().total_cmp(&a.norm()).then(b.im.total_cmp(&a.im)));
    assert_eq!(v.len(), dim, "{v:?}");
    (v, h)
}

/// The Mathieu model's two multipliers.
fn samara_multipliers(delta: f64, eps: f64, c: f64, steps: usize) -> (Vec<Complex<f64>>, History) {
    multipliers_of(&mathieu(delta, eps, c, steps, "n_modes = 2"), 2)
}

fn error(a: &[Complex<f64>], b: &[Complex<f64>]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).norm())
        .fold(0.0, f64::max)
}

/// The multipliers converge to the reference as h² (the generalized-α scheme is second
/// order): stable (complex pair), unstable (real pair, first tongue) and damped points.
/// Tolerance: the observed order within 0.15 of 2 and the error at 400 steps below 1e-3.
#[test]
fn mathieu_multipliers_converge_as_h_squared() {
    for (delta, eps, c) in [(0.6, 0.3, 0.0), (0.25, 0.2, 0.0), (0.6, 0.3, 0.05)] {
        let exact = multipliers2(&reference(delta, eps, c));
        let errs: Vec<f64> = [100, 200, 400]
            .iter()
            .map(|&n| error(&samara_multipliers(delta, eps, c, n).0, &exact))
            .collect();
        let orders = common::orders(&errs);
        eprintln!(
            "δ = {delta}, ε = {eps}, c = {c}: errors {errs:?}, orders {orders:?}, reference {exact:?}"
        );
        for o in &orders {
            assert!((o - 2.0).abs() < 0.15, "order {o} ({errs:?})");
        }
        assert!(errs[2] < 1e-3, "{errs:?}");
    }
}

/// Stable and unstable on both sides of the first two tongues: samara's largest multiplier
/// modulus against the reference's (|ρ| > 1 + 10⁻⁶ unstable; the undamped stable points
/// have |ρ| = 1 to round-off in both — trapezoidal generalized-α, ρ∞ = 1, keeps
/// det Φ = 1).
#[test]
fn mathieu_stability_on_both_sides_of_the_first_two_tongues() {
    // (δ, ε, expected unstable): tongue 1 at ε = 0.2 spans 0.15 … 0.35; tongue 2 at
    // ε = 0.4 spans 0.987 … 1.067.
    let points = [
        (0.10, 0.2, false),
        (0.25, 0.2, true),
        (0.40, 0.2, false),
        (0.95, 0.4, false),
        (1.02, 0.4, true),
        (1.12, 0.4, false),
    ];
    for (delta, eps, unstable) in points {
        let exact = multipliers2(&reference(delta, eps, 0.0));
        let (ours, h) = samara_multipliers(delta, eps, 0.0, 400);
        let top_ref = exact[0].norm();
        let top = ours[0].norm();
        eprintln!("δ = {delta}, ε = {eps}: |ρ| = {top} (reference {top_ref})");
        assert_eq!(top_ref > 1.0 + 1e-6, unstable, "reference at δ = {delta}");
        assert_eq!(
            top > 1.0 + 1e-6,
            unstable,
            "samara at δ = {delta}: {ours:?}"
        );
        assert!((top - top_ref).abs() < 2e-3 * top_ref, "{top} {top_ref}");
        // The written modulus, exponent and damping ratio agree with the multiplier.
        let get = |n: &str| &h.arrays.iter().find(|a| a.0.name == n).unwrap().1;
        let (modulus, expo, zeta) = (
            get("floquet_modulus"),
            get("floquet_exponent"),
            get("damping_ratio"),
        );
        assert!((modulus[0] - top).abs() < 1e-14);
        assert!((expo[0] - top.ln() / (2.0 * PI)).abs() < 1e-12);
        if unstable {
            assert!(zeta[0] < 0.0);
        }
    }
}

/// `period` and `speed` give the same analysis (T = 2π/|Ω|); `rho_inf` < 1 damps the
/// multipliers (numerical dissipation), so it changes the result.
#[test]
fn speed_gives_the_period_and_rho_inf_changes_the_result() {
    let m = model(
        &mathieu(0.6, 0.3, 0.0, 100, "").replace("period = 6.283185307179586", "speed = 1.0"),
    );
    let AnalysisKind::Floquet(f) = &m.analyses[0].kind else {
        panic!()
    };
    assert!((f.period - 2.0 * PI).abs() < 1e-15);
    let top = |extra: &str| {
        let m = model(&mathieu(0.6, 0.3, 0.0, 100, extra));
        let sys = System::new(&m);
        let mut h = History::default();
        samara::analysis::run_analysis(
            &sys,
            &m.analyses[0],
            sys.initial_state(),
            &mut h,
            &mut |_| {},
        )
        .unwrap();
        h.arrays
            .iter()
            .find(|a| a.0.name == "floquet_modulus")
            .unwrap()
            .1[0]
    };
    let (a, b) = (top(""), top("rho_inf = 0.5"));
    assert!((a - 1.0).abs() < 1e-10, "{a}");
    assert!(b < 1.0 - 1e-6, "{b}");
}

/// A period that is not a period of the stiffness function stops the analysis with a hint.
#[test]
fn a_period_that_is_not_a_period_of_the_loads_is_refused() {
    let m = model(
        &mathieu(0.6, 0.3, 0.0, 50, "").replace("period = 6.283185307179586", "period = 5.0"),
    );
    let sys = System::new(&m);
    let mut h = History::default();
    let s = samara::analysis::run_analysis(
        &sys,
        &m.analyses[0],
        sys.initial_state(),
        &mut h,
        &mut |_| {},
    )
    .unwrap();
    let f = s.failure.expect("refused");
    assert!(
        f.reason.contains("not a period of the loads"),
        "{}",
        f.reason
    );
    assert!(f.hint.unwrap().contains("period"));
}

/// The Mathieu oscillator with a Maxwell element (spring k₂ in series with a damper c₂,
/// whose stretch s is an element state) between the mass and the ground:
///
///     ẍ + (δ + ε cos t) x + k₂ (x − s) = 0,      c₂ ṡ = k₂ (x − s),
///
/// three Floquet multipliers (a pair and a real one from the first-order state).
/// Reference: the 3 × 3 monodromy by RK4 with 20,000 steps per period (error ~1e-13).
fn maxwell_reference(delta: f64, eps: f64, k2: f64, c2: f64) -> Vec<Complex<f64>> {
    let n = 20_000;
    let h = 2.0 * PI / n as f64;
    let f = |t: f64, x: [f64; 3]| {
        [
            x[1],
            -(delta + eps * t.cos()) * x[0] - k2 * (x[0] - x[2]),
            k2 / c2 * (x[0] - x[2]),
        ]
    };
    let mut phi = nalgebra::Matrix3::zeros();
    for col in 0..3 {
        let mut x = [0.0; 3];
        x[col] = 1.0;
        for k in 0..n {
            let t = k as f64 * h;
            let step = |x: [f64; 3], d: [f64; 3], s: f64| std::array::from_fn(|i| x[i] + s * d[i]);
            let k1 = f(t, x);
            let k2_ = f(t + h / 2.0, step(x, k1, h / 2.0));
            let k3 = f(t + h / 2.0, step(x, k2_, h / 2.0));
            let k4 = f(t + h, step(x, k3, h));
            for i in 0..3 {
                x[i] += h / 6.0 * (k1[i] + 2.0 * k2_[i] + 2.0 * k3[i] + k4[i]);
            }
        }
        for i in 0..3 {
            phi[(i, col)] = x[i];
        }
    }
    let mut v: Vec<Complex<f64>> = phi.complex_eigenvalues().iter().copied().collect();
    v.sort_by(|a, b| b.norm().total_cmp(&a.norm()).then(b.im.total_cmp(&a.im)));
    v
}

/// Floquet with an element state: the multipliers of the Mathieu–Maxwell system converge
/// to the RK4 reference as h² (second-order generalized-α for the structure and for the
/// state), at two stable points (three real multipliers; a pair and a real one) and an
/// unstable one (a soft, slow Maxwell element that stiffens the mass into the first
/// tongue). Tolerance: observed orders within 0.2 of 2, error at 400 steps per period
/// below 1e-3 (the Mathieu errors above, same scheme); the verdict as the reference's.
#[test]
fn mathieu_with_a_maxwell_state_converges_as_h_squared() {
    for (delta, eps, k2, c2, unstable) in [
        (0.6, 0.3, 0.5, 1.0, false),
        (0.2, 0.4, 0.5, 1.0, false),
        (0.15, 0.5, 0.1, 1.0, true),
    ] {
        let exact = maxwell_reference(delta, eps, k2, c2);
        assert_eq!(exact[0].norm() > 1.0 + 1e-6, unstable, "{exact:?}");
        let mut top = 0.0;
        let errs: Vec<f64> = [100, 200, 400]
            .iter()
            .map(|&steps| {
                let text = mathieu(delta, eps, 0.0, steps, "n_modes = 3")
                    + &format!(
                        r#"
[[viscoelastic]]
name = "mount"
type = "maxwell"
node_a = "ground"
node_b = "mass"
point_a = [-1.0, 0.0, 0.0]
stiffness = {k2}
damping = {c2}
"#
                    );
                // Three modes at most (a pair and a real multiplier are two).
                let (v, _) = multipliers_of(&text, 3);
                top = v[0].norm();
                error(&v, &exact)
            })
            .collect();
        let orders = common::orders(&errs);
        eprintln!(
            "δ = {delta}, ε = {eps}: errors {errs:?}, orders {orders:?}, reference {exact:?}"
        );
        for o in &orders {
            assert!((o - 2.0).abs() < 0.2, "order {o} ({errs:?})");
        }
        assert!(errs[2] < 1e-3, "{errs:?}");
        assert_eq!(top > 1.0 + 1e-6, unstable, "|ρ| = {top}");
    }
}
