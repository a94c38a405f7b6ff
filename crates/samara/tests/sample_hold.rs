//! Issue #16: sample-and-hold sensors (`[[sensors]] sample_rate` / `sample_period`): the
//! measurement sampled at t_k = k T and held until t_(k+1) (zero-order hold).
//!
//! References: the exact staircase of a sampled closed-form signal, and the exact
//! discrete-time recursion of a first-order plant under a zero-order hold
//! (Franklin, Powell & Workman, *Digital Control of Dynamic Systems*, 3rd ed., §4.3.3):
//! `x_(k+1) = a x_k + b u_k`, `a = e^(−T/τ)`, `b = (1 − a) K` for `τ ẋ + x = K u`.

use crate::common;
use common::{model, model_file, orders, run, with_step};
use samara::model::{AnalysisKind, Model};
use samara::system::System;

fn staircase_model(step: f64, control: &str) -> String {
    format!(
        r#"
[model]
name = "staircase"
gravity = [0.0, 0.0, 0.0]
[[nodes]]
name = "mass"
position = [0.0, 0.0, 0.0]
[[bodies]]
name = "mass"
node = "mass"
mass = 1.0
inertia = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
[[signals]]
name = "u"
function = {{ type = "sine", amplitude = 1.0, frequency = 1.0 }}
[[sensors]]
name = "held"
signal = "u"
sample_rate = 20.0
[[analyses]]
name = "run"
type = "dynamic"
t_end = 1.0
step = {step}
{control}
"#
    )
}

/// The held value of a sampled sine is the staircase sin(2π t_k), t_k = ⌊t/T⌋ T, at every
/// recorded time, and the steps land on every sample instant — with a fixed step that
/// does not divide T (0.03 s against T = 0.05 s) and with adaptive steps. The signal is
/// a closed form evaluated at t_k, so the only error is the rounding of t_k (1e-12).
#[test]
fn a_sampled_sine_is_its_exact_staircase() {
    let period = 0.05;
    for control in ["", "step_control = \"adaptive\"\nstep_max = 0.2"] {
        let m: Model = model(&staircase_model(0.03, control));
        let (_, h) = run(&m);
        let sys = System::new(&m);
        let id = sys.signals.names.iter().position(|n| n == "held").unwrap();
        for f in &h.frames {
            let k = (f.time / period + 1e-9).floor();
            let exact = (2.0 * std::f64::consts::PI * k * period).sin();
            assert!(
                (f.state.held[0] - exact).abs() < 1e-12,
                "{control}: t = {}: held {} vs {exact}",
                f.time,
                f.state.held[0]
            );
            // The signal the sensor gives its readers (and the results) is the held value.
            let s = sys.signal_values(&sys.context(f.time, 1.0), &f.state);
            assert_eq!(s[id], f.state.held[0]);
        }
        for k in 0..=20 {
            let tk = k as f64 * period;
            assert!(
                h.frames.iter().any(|f| (f.time - tk).abs() < 1e-12),
                "{control}: no step lands on t_{k} = {tk}"
            );
        }
        println!("{control:?}: {} frames", h.frames.len());
    }
}

/// The speeds of `examples/control/sampled_speed.toml` (a cart on a damper, m v̇ + c v =
/// F, under a P controller F = kp (r − v_k) reading a 10 Hz sample-and-hold) at the
/// sample instants against the exact ZOH recursion v_(k+1) = a v_k + (1 − a) F_k / c,
/// a = e^(−cT/m). Between samples the force is constant, so the only error is the
/// integrator's error within each sample: second order in the step (h = T/5, T/10, T/20;
/// the step after each jump restarts from consistent accelerations, else it would be first
/// order), and below 2e-5 of the final speed at h = T/10 = 10 ms ((h/τ)² = 4e-4 with
/// τ = 0.5 s, times the generalized-α error constant ≈ 1/12, less the settling's decay;
/// measured 1.0e-5).
#[test]
fn a_sampled_p_loop_follows_the_zoh_recursion() {
    let (m_c, c, kp, r, period) = (2.0f64, 4.0f64, 5.0f64, 1.0f64, 0.1f64);
    let a = (-c * period / m_c).exp();
    let mut exact = vec![0.0f64];
    for _ in 0..20 {
        let v = *exact.last().unwrap();
        exact.push(a * v + (1.0 - a) * kp * (r - v) / c);
    }
    let settled = kp * r / (c + kp);
    // Closed-loop pole a − (1 − a) kp/c = 0.592: within 1e-4 of v∞ after 20 samples.
    assert!((exact[20] - settled).abs() < 1e-4, "the recursion settles");
    let mut errors = Vec::new();
    for step in [0.02, 0.01, 0.005] {
        let m = with_step(model_file("examples/control/sampled_speed.toml"), step);
        let (_, h) = run(&m);
        let mut worst = 0.0f64;
        for (k, ek) in exact.iter().enumerate() {
            let tk = k as f64 * period;
            let f = h.at(tk).unwrap();
            assert!((f.time - tk).abs() < 1e-12, "t_{k} not landed on");
            worst = worst.max((f.state.nodes[0].v.x - ek).abs());
            // The held value is the speed at the sample instant.
            assert!((f.state.held[0] - f.state.nodes[0].v.x).abs() < 1e-12);
        }
        errors.push(worst / settled);
    }
    let o = orders(&errors);
    println!("relative errors {errors:?}, orders {o:.2?}");
    assert!(o.iter().all(|&p| p > 1.8), "{o:?}");
    assert!(errors[1] < 2e-5, "{errors:?}");
}

/// In statics nothing is sampled: the hold passes the current value, and the loop is
/// in equilibrium with the held value equal to the measurement. A spring-mass (k = 100
/// N/m) under a P position loop F = kp (r − x_held) (a `sum`) settles at x = kp r / (k + kp).
#[test]
fn in_statics_the_hold_passes_the_current_value() {
    let text = r#"
[model]
name = "static_hold"
gravity = [0.0, 0.0, 0.0]
[[nodes]]
name = "mass"
position = [0.0, 0.0, 0.0]
[[bodies]]
name = "mass"
node = "mass"
mass = 1.0
inertia = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
[[joints]]
name = "rail"
type = "prismatic"
node_a = "ground"
node_b = "mass"
position = [0.0, 0.0, 0.0]
axis = [1.0, 0.0, 0.0]
[[springs]]
name = "k"
node_a = "ground"
node_b = "mass"
point_a = [-1.0, 0.0, 0.0]
stiffness = 100.0
[[signals]]
name = "target"
function = { type = "constant", value = 0.1 }
[[sensors]]
name = "x"
node = "mass"
quantity = "position"
component = "x"
sample_period = 0.05
[[controllers]]
name = "p"
type = "sum"
inputs = ["target", "x"]
weights = [300.0, -300.0]
[[forces]]
name = "f"
node = "mass"
force = [1.0, 0.0, 0.0]
signal = "p"
[[analyses]]
name = "equilibrium"
type = "static"
"#;
    let m: Model = model(text);
    let (_, h) = run(&m);
    let x = h.last().unwrap().state.nodes[0].x.x;
    let exact = 300.0 * 0.1 / (100.0 + 300.0);
    println!("x = {x}, exact {exact}");
    assert!((x - exact).abs() < 1e-10, "{x} vs {exact}");
    assert!(h.last().unwrap().state.held.is_empty());
}

/// Bad sampling keys are located errors.
#[test]
fn bad_sampling_keys_are_located_errors() {
    let base = staircase_model(0.01, "");
    for (bad, expect) in [
        ("sample_rate = 0.0", "`sample_rate` must be positive"),
        ("sample_rate = -5.0", "`sample_rate` must be positive"),
        ("sample_period = 0.0", "`sample_period` must be positive"),
        ("sample_rate = 20.0\nsample_period = 0.05", "not both"),
    ] {
        let text = base.replace("sample_rate = 20.0", bad);
        let err = match Model::from_toml_str(&text, "s.toml") {
            Ok(_) => panic!("accepted {bad}"),
            Err(e) => e.to_string(),
        };
        println!("{err}");
        assert!(err.contains("s.toml:"), "{err}");
        assert!(err.contains(expect), "{err}");
    }
    // The analysis settings are untouched by the sensor (sanity of the base model).
    let m = model(&base);
    assert!(matches!(m.analyses[0].kind, AnalysisKind::Dynamic(_)));
}

/// A linearization takes a held value as a constant input: in `sampled_speed.toml` the
/// cart's linearized damping is the damper's c = 4 N s/m alone (the loop through the hold
/// is open), where the same sensor without sampling closes the loop, c + kp = 9 N s/m
/// (the P force's −kp v). Both are exact sums of the model's coefficients (1e-12).
#[test]
fn a_linearization_holds_the_sample_constant() {
    use samara::linear::linearize;
    let damping_ux = |m: &Model| -> f64 {
        let sys = System::new(m);
        let lin = linearize(&sys, &sys.initial_state(), None);
        let i = lin
            .unknown_names
            .iter()
            .position(|n| n == "cart.ux")
            .unwrap();
        let r = lin.damping.as_ref();
        r.row_idx_of_col_raw(i)
            .iter()
            .zip(r.val_of_col(i))
            .filter(|(row, _)| **row == i)
            .map(|(_, v)| *v)
            .sum()
    };
    let sampled = model_file("examples/control/sampled_speed.toml");
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../examples/control/sampled_speed.toml"),
    )
    .unwrap();
    let continuous = model(&text.replace("sample_rate = 10.0", ""));
    let (held, closed) = (damping_ux(&sampled), damping_ux(&continuous));
    println!("linearized damping: held {held}, continuous {closed}");
    assert!((held - 4.0).abs() < 1e-12, "{held}");
    assert!((closed - 9.0).abs() < 1e-12, "{closed}");
}

/// The held value is written to the results file as the sensor's signal
/// (`signal:speed`): read back, it is the staircase of the cart's speed — at every output
/// time the speed at the last sample instant ⌊t/T⌋ T (exact copies, 1e-12). Stepping with
/// `Simulation::step` lands on the sample instants too (a 0.03 s step across t_k is cut
/// there: two sub-steps) and gives the same held values.
#[test]
fn the_held_value_is_written_and_stepping_lands_on_samples() {
    use samara::analysis::{Simulation, run_analysis};
    use samara::output::{ResultsFile, ResultsReader};
    let m = model_file("examples/control/sampled_speed.toml");
    let sys = System::new(&m);
    let dir = tempfile::tempdir().unwrap();
    let mut file = ResultsFile::create(dir.path(), &m, None, &sys, &m.analyses[0]).unwrap();
    let summary = run_analysis(
        &sys,
        &m.analyses[0],
        sys.initial_state(),
        &mut file,
        &mut |_| {},
    )
    .unwrap();
    let path = file.finish(&summary).unwrap();
    let mut r = ResultsReader::open(&path).unwrap();
    let time = r.time().unwrap();
    let held = r.channel("signal:speed").unwrap().values;
    let speed = r.channel("velocity:cart:x").unwrap().values;
    let period = 0.1;
    let mut checked = 0;
    for (i, &t) in time.iter().enumerate() {
        let tk = (t / period + 1e-9).floor() * period;
        let j = time.iter().position(|&s| (s - tk).abs() < 1e-9).unwrap();
        assert!((held[i] - speed[j]).abs() < 1e-12, "t = {t}");
        checked += 1;
    }
    assert_eq!(checked, 201);
    let AnalysisKind::Dynamic(settings) = &m.analyses[0].kind else {
        unreachable!()
    };
    let mut sim = Simulation::new(&sys, settings, sys.initial_state()).unwrap();
    let mut cut = 0;
    while sim.time() < 0.5 - 1e-12 {
        let t = sim.time();
        let report = sim.step(0.03f64.min(0.5 - t)).unwrap();
        let crossed = ((t / period + 1e-9).floor() + 1.0) * period < sim.time() - 1e-9;
        if crossed {
            assert_eq!(report.sub_steps, 2, "t = {t}");
            cut += 1;
        }
        let tk = (sim.time() / period + 1e-9).floor() * period;
        let j = time.iter().position(|&s| (s - tk).abs() < 1e-9).unwrap();
        // Different steps (0.03 s against 0.01 s): the held speeds agree to the
        // integrators' errors (1e-5 of v∞ at these steps, tests above).
        assert!(
            (sim.state().held[0] - speed[j]).abs() < 1e-4,
            "t = {}",
            sim.time()
        );
    }
    assert!(cut >= 3, "{cut}");
}

/// The held values are part of the state a continued run starts from (`start_from`): the
/// loop of `examples/control/sampled_speed.toml` run to 0.47 s (between the samples of 0.4
/// and 0.5 s) or to 0.5 s (on one), then continued to 2 s from that final state. At the
/// start of the continuation the held value is still the sample of 0.4 s (not the speed at
/// 0.47 s: nothing is re-sampled between instants), and on an instant it is that
/// instant's sample, taken once. Split on the instant, the two runs end where the single
/// run ends to 1e-12 (the step after a sample restarts from consistent accelerations in
/// both); split between instants, the continuation restarts the integrator's
/// acceleration off an instant, so the speeds at the later sample instants follow the
/// exact ZOH recursion to the same 2e-5 of the final speed as the single run (h = 10 ms,
/// test above), not to round-off.
#[test]
fn a_run_split_in_two_carries_the_held_values() {
    let (m_c, c, kp, r, period) = (2.0f64, 4.0f64, 5.0f64, 1.0f64, 0.1f64);
    let a = (-c * period / m_c).exp();
    let mut exact = vec![0.0f64];
    for _ in 0..20 {
        let v = *exact.last().unwrap();
        exact.push(a * v + (1.0 - a) * kp * (r - v) / c);
    }
    let settled = kp * r / (c + kp);
    let base = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../examples/control/sampled_speed.toml"),
    )
    .unwrap();
    let single = {
        let m = model(&base);
        run(&m).1
    };
    let v_end = single.last().unwrap().state.nodes[0].v.x;
    for split in [0.47, 0.5] {
        let text = base.replace("t_end = 2.0", &format!("t_end = {split:?}"))
            + &format!(
                "\n[[analyses]]\nname = \"more\"\ntype = \"dynamic\"\nstart_from = \"run\"\nt_start = {split:?}\nt_end = 2.0\nstep = 0.01\nrho_inf = 0.8\n"
            );
        let m = model(&text);
        let sys = System::new(&m);
        let out = samara::analysis::run_all(
            &m,
            &sys,
            |_| Ok(samara::analysis::History::default()),
            |_, _| {},
        )
        .unwrap();
        assert!(out.iter().all(|(s, _)| s.failure.is_none()));
        let (first, second) = (&out[0].1, &out[1].1);
        let start = &second.frames[0];
        assert!((start.time - split).abs() < 1e-12);
        // The held value the continuation starts with: the last sample of the first run.
        let last_instant = (split / period + 1e-9).floor() * period;
        let sampled = first.at(last_instant).unwrap().state.nodes[0].v.x;
        println!(
            "split at {split}: held {:.12} at the start, v({last_instant:.1}) = {sampled:.12}, v({split}) = {:.12}",
            start.state.held[0], start.state.nodes[0].v.x
        );
        assert_eq!(start.state.held[0], sampled);
        let mut worst = 0.0f64;
        for (k, ek) in exact.iter().enumerate() {
            let tk = k as f64 * period;
            if tk <= split {
                continue;
            }
            let f = second.at(tk).unwrap();
            assert!((f.time - tk).abs() < 1e-9, "t_{k} not landed on");
            worst = worst.max((f.state.nodes[0].v.x - ek).abs());
        }
        let v2 = second.last().unwrap().state.nodes[0].v.x;
        println!(
            "  after the split: ZOH recursion within {:.2e} of v∞; final speed {v2:.12} vs single run {v_end:.12}",
            worst / settled
        );
        assert!(worst / settled < 2e-5, "{worst}");
        if split == 0.5 {
            assert!((v2 - v_end).abs() < 1e-12, "{v2} {v_end}");
        }
    }
}
