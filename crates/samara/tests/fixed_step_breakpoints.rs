//! Fixed steps land on breakpoints off their grid (issue #17: "nothing is stepped over").
//!
//! The kicked mass of `examples/adaptive_kick.toml` (20 Hz, ζ = 0.05) with its force step
//! moved off the grid, to t₀ = 0.5003 s, run with fixed generalized-α steps h = 1, 0.5,
//! 0.25 ms (t₀/h = 500.3, 1000.6, 2001.2). Reference: the closed-form step response of the
//! damped oscillator, x(s) = (F/k)[1 − e^(−ζωs)(cos ω_d s + ζ/√(1−ζ²) sin ω_d s)],
//! s = t − t₀. A step that straddled t₀ would apply the force up to one step early (the
//! step ending after t₀ sees the force over its whole length), an O(h) shift of the whole
//! response; landing on t₀ and restarting there from consistent accelerations keeps the
//! scheme's second order. Tolerance: observed orders ≥ 1.8 per halving (second order; the
//! step response at ωh = 0.13 … 0.03 is in the asymptotic range), and every step ends on t₀.

use crate::common;
use common::{model_file, orders, run};
use samara::model::{AnalysisKind, TimeFunction};

#[test]
fn fixed_steps_land_on_an_off_grid_step_at_second_order() {
    let mut example = model_file("examples/adaptive_kick.toml");
    let t0 = 0.5003;
    let TimeFunction::Step { time, .. } = &mut example.forces[0].function else {
        panic!("the example's force is a step")
    };
    *time = t0;
    let (m, k, c): (f64, f64, f64) = (2.0, 31582.734, 25.132741);
    let force = example.forces[0].force.x;
    let w = (k / m).sqrt();
    let zeta = c / (2.0 * (k * m).sqrt());
    let wd = w * (1.0 - zeta * zeta).sqrt();
    let exact = |t: f64| {
        if t < t0 {
            return 0.0;
        }
        let s = t - t0;
        force / k
            * (1.0
                - (-zeta * w * s).exp()
                    * ((wd * s).cos() + zeta / (1.0 - zeta * zeta).sqrt() * (wd * s).sin()))
    };
    let mut errors = Vec::new();
    for h in [1e-3, 5e-4, 2.5e-4] {
        let mut mm = example.clone();
        let AnalysisKind::Dynamic(d) = &mut mm.analyses[0].kind else {
            panic!("the example's analysis is dynamic")
        };
        d.adaptive = None;
        d.step = h;
        d.min_step = h / 1024.0;
        d.t_end = 1.0;
        let (s, hist) = run(&mm);
        assert!(s.failure.is_none(), "{:?}", s.failure);
        assert!(
            hist.frames.iter().any(|f| f.time == t0),
            "h = {h:e}: no step ends on the breakpoint {t0}"
        );
        // The grid resumes after the breakpoint: t₀ is the only record off k·h.
        let off_grid = hist
            .frames
            .iter()
            .filter(|f| ((f.time / h).round() * h - f.time).abs() > 1e-9 * h)
            .count();
        assert_eq!(off_grid, 1, "h = {h:e}: records off the grid");
        let err = hist
            .frames
            .iter()
            .map(|f| (f.state.nodes[0].x.x - exact(f.time)).abs())
            .fold(0.0, f64::max);
        println!("h = {h:e}: {} steps, max error {err:.3e} m", s.steps);
        errors.push(err);
    }
    let p = orders(&errors);
    println!("orders {p:?}");
    assert!(
        p.iter().all(|&o| o > 1.8),
        "orders {p:?}, errors {errors:?}"
    );
}
