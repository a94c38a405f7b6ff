//! `output_interval` (issue #17, "restriction of the step at output times"): records at
//! t_start + kΔ, the steps — fixed or adaptive, generalized-α or an energy scheme —
//! landing on those instants, so that no output time is stepped over and nothing is
//! interpolated.

use crate::common;
use common::{example_model_text, kick_response, model, model_file, run};
use samara::analysis::History;
use samara::model::{AnalysisKind, Model};

/// The record times are t_start + kΔ (to 1e-12 s: k·Δ in floating point), k = 0, 1, …,
/// and t_end.
fn assert_on_grid(h: &History, t_start: f64, interval: f64, t_end: f64) {
    let n = ((t_end - t_start) / interval + 1e-9).floor() as usize;
    let mut expected: Vec<f64> = (0..=n).map(|k| t_start + k as f64 * interval).collect();
    if t_end - expected[n] > 1e-9 * interval {
        expected.push(t_end);
    }
    let times: Vec<f64> = h.frames.iter().map(|f| f.time).collect();
    assert_eq!(times.len(), expected.len(), "{times:?}");
    for (t, e) in times.iter().zip(&expected) {
        assert!((t - e).abs() < 1e-12, "record at {t}, expected {e}");
    }
}

/// The kicked mass of `examples/adaptive_kick.toml` (20 Hz, ζ = 0.05, a 100 N step at
/// 0.5 s) and its closed form.
fn kick() -> (Model, impl Fn(f64) -> f64) {
    let m = model_file("examples/adaptive_kick.toml");
    let exact = kick_response(&m);
    (m, exact)
}

fn dynamic(m: &mut Model) -> &mut samara::model::DynamicSettings {
    match &mut m.analyses[0].kind {
        AnalysisKind::Dynamic(d) => d,
        _ => panic!("a dynamic analysis"),
    }
}

/// Adaptive steps over the kick (1.5 s): with Δ = 0.05 s the records are exactly on the
/// grid and still within the adaptive run's accuracy of the closed form (2 % of the static
/// deflection F/k, the bound the example's own test uses); without it the records are at
/// the steps' own times, which are not on any grid. Landing costs about one step per
/// output instant (measured: 494 steps against 459 for 30 instants; bound: two each).
#[test]
fn adaptive_steps_land_on_every_output_instant() {
    let (base, exact) = kick();
    let run_with = |interval: Option<f64>| {
        let mut m = base.clone();
        let d = dynamic(&mut m);
        d.t_end = 1.5;
        d.output_interval = interval;
        let (s, h) = run(&m);
        assert!(s.failure.is_none(), "{:?}", s.failure);
        (s, h)
    };
    let (free, h_free) = run_with(None);
    let (landed, h) = run_with(Some(0.05));
    assert_on_grid(&h, 0.0, 0.05, 1.5);
    let off_grid = h_free
        .frames
        .iter()
        .filter(|f| (f.time / 0.05 - (f.time / 0.05).round()).abs() > 1e-6)
        .count();
    assert!(
        off_grid > 10,
        "without output_interval the records follow the steps"
    );
    let static_deflection = 100.0 / 31582.734;
    let err = h
        .frames
        .iter()
        .map(|f| (f.state.nodes[0].x.x - exact(f.time)).abs())
        .fold(0.0, f64::max);
    assert!(err < 0.02 * static_deflection, "error {err:e}");
    println!(
        "kick to 1.5 s: {} steps free, {} with Δ = 0.05 s (31 records); error at the records {err:.2e} m",
        free.steps, landed.steps
    );
    assert!(
        landed.steps <= free.steps + 2 * 31,
        "{} vs {}",
        landed.steps,
        free.steps
    );
}

/// Fixed steps: Δ = 5 h records the same frames, bit for bit, as `output_every = 5`.
#[test]
fn an_interval_on_the_step_grid_equals_output_every() {
    let (base, _) = kick();
    let run_with = |every: usize, interval: Option<f64>| {
        let mut m = base.clone();
        let d = dynamic(&mut m);
        d.adaptive = None;
        d.t_end = 0.8;
        d.step = 1e-3;
        d.min_step = 1e-3 / 1024.0;
        d.output_every = every;
        d.output_interval = interval;
        run(&m).1
    };
    let a = run_with(5, None);
    let b = run_with(1, Some(5e-3));
    assert_eq!(a.frames.len(), 161);
    assert_eq!(a.frames.len(), b.frames.len());
    for (fa, fb) in a.frames.iter().zip(&b.frames) {
        assert_eq!(fa.time, fb.time);
        assert_eq!(fa.state.nodes[0].x, fb.state.nodes[0].x);
        assert_eq!(fa.state.nodes[0].v, fb.state.nodes[0].v);
    }
}

/// Fixed steps with an interval that is not a multiple of the step (h = 1 ms, Δ = 2.5 ms:
/// every other step is cut to land): the records are on the grid and the error against the
/// closed form at them stays second order (h → h/2 divides it by ≈ 4; measured 3.40 —
/// the cut steps' share of the error changes with h; accepted 3–5).
#[test]
fn fixed_steps_cut_to_the_output_instants_stay_second_order() {
    let (base, exact) = kick();
    let error_at = |step: f64| {
        let mut m = base.clone();
        let d = dynamic(&mut m);
        d.adaptive = None;
        d.t_end = 0.7;
        d.step = step;
        d.min_step = step / 1024.0;
        d.output_interval = Some(2.5e-3);
        let (s, h) = run(&m);
        assert!(s.failure.is_none(), "{:?}", s.failure);
        assert_on_grid(&h, 0.0, 2.5e-3, 0.7);
        h.frames
            .iter()
            .map(|f| (f.state.nodes[0].x.x - exact(f.time)).abs())
            .fold(0.0, f64::max)
    };
    let e1 = error_at(1e-3);
    let e2 = error_at(5e-4);
    println!("errors {e1:.3e} {e2:.3e}, ratio {:.2}", e1 / e2);
    assert!((3.0..5.0).contains(&(e1 / e2)), "{e1:e} {e2:e}");
}

/// The energy-preserving scheme lands on the output instants too (pendulum, h = 4 ms,
/// Δ = 10 ms), and its energy stays constant to the Newton tolerance at every record.
#[test]
fn energy_scheme_lands_on_the_output_instants() {
    let m = model(&format!(
        "{}[[analyses]]\nname = \"swing\"\ntype = \"dynamic\"\nintegrator = \"energy_preserving\"\nt_end = 1.0\nstep = 4e-3\noutput_interval = 1e-2\ntolerance = 1e-12\nrelative_tolerance = 1e-14\n",
        example_model_text("examples/pendulum.toml")
    ));
    let (s, h) = run(&m);
    assert!(s.failure.is_none(), "{:?}", s.failure);
    assert_on_grid(&h, 0.0, 1e-2, 1.0);
    let e0 = h.frames[0].energy.kinetic + h.frames[0].energy.potential;
    for f in &h.frames {
        let e = f.energy.kinetic + f.energy.potential;
        // Scale m g L = 9.81 J; Newton stops at 1e-12 on increments.
        assert!((e - e0).abs() < 1e-9 * 9.81, "t = {}: {e} vs {e0}", f.time);
    }
}

#[test]
fn bad_output_intervals_are_located_errors() {
    let bad = |analysis: &str, message: &str| {
        let text = format!(
            "{}[[analyses]]\nname = \"run\"\n{analysis}",
            example_model_text("examples/pendulum.toml")
        );
        let e = Model::from_toml_str(&text, "bad.toml").expect_err(analysis);
        let shown = e.to_string();
        assert!(shown.contains(message), "{shown}");
        assert!(shown.contains("bad.toml:"), "{shown}");
    };
    let dynamic = "type = \"dynamic\"\nt_end = 1.0\nstep = 1e-3\n";
    bad(
        &format!("{dynamic}output_interval = 0.01\noutput_every = 2"),
        "not both",
    );
    bad(
        &format!("{dynamic}output_interval = 0.0"),
        "`output_interval` must be a positive time",
    );
    bad(
        &format!("{dynamic}output_interval = -0.5"),
        "`output_interval` must be a positive time",
    );
    bad(
        &format!("{dynamic}output_interval = nan"),
        "outside the range samara computes with",
    );
    bad(
        &format!("{dynamic}output_interval = 1e-14"),
        "more than 10¹² records",
    );
    bad(
        "type = \"static\"\noutput_interval = 0.1",
        "output_interval",
    );
}
