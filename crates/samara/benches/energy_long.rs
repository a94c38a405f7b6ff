//! Long runs of the energy-preserving scheme (issue #17, verification 2): 1,000 periods of
//! the slowest mode, too long for the test suite (the tests in `tests/energy_schemes.rs`
//! run the double pendulum over 300 periods and the flying spaghetti over 50).
//!
//! `cargo bench -p samara --bench energy_long [-- spaghetti|double_pendulum periods=P
//! tolerance=T]` (T: the Newton tolerance on the increments, relative tolerance T/100)
//! prints, per model: steps, Newton iterations, wall time, and the largest drift of the
//! energy (and, for the free-flying beam, of the linear and angular momentum) over the run.
//!
//! - `double_pendulum`: `examples/double_pendulum.toml` released horizontal, P periods of
//!   its slow linear mode (2π/√((2 − √2) g) = 2.62 s) at h = 0.04 s, Newton tolerance
//!   1e-12 by default; drift relative to m g l = 9.81 J.
//! - `spaghetti`: `examples/flying_spaghetti.toml` (h = 0.05 s, tolerance 1e-10 by default), free
//!   from 5 s on, then P periods of its slowest elastic mode, the first free–free bending
//!   mode ω₁ = 4.730² √(EI/(ρA L⁴)) = 5.00 rad/s (T₁ = 1.256 s; the rigid tumbling
//!   is not a vibration mode); drifts relative to E, |p| and |L| at 5 s.

use samara::analysis::{History, run_analysis};
use samara::model::Model;
use samara::system::System;
use std::path::Path;
use std::time::Instant;

/// The example's model with its analyses replaced by one preserving run.
fn load(rel: &str, step: f64, t_end: f64, tolerance: f64, output_every: usize) -> Model {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let text = std::fs::read_to_string(root.join(rel)).unwrap();
    let body = text.split("[[analyses]]").next().unwrap();
    let text = format!(
        "{body}\n[[analyses]]\nname = \"p\"\ntype = \"dynamic\"\nintegrator = \"energy_preserving\"\nt_end = {t_end}\nstep = {step}\ntolerance = {tolerance}\nrelative_tolerance = {}\noutput_every = {output_every}\n",
        tolerance * 1e-2
    );
    Model::from_toml_str(&text, rel).unwrap().model
}

/// The model's analysis, its history and its wall time [s].
fn timed_run(sys: &System, m: &Model) -> (samara::analysis::AnalysisSummary, History, f64) {
    let mut h = History::default();
    let clock = Instant::now();
    let s = run_analysis(
        sys,
        &m.analyses[0],
        sys.initial_state(),
        &mut h,
        &mut |_| {},
    )
    .unwrap();
    assert!(s.failure.is_none(), "{:?}", s.failure);
    (s, h, clock.elapsed().as_secs_f64())
}

fn energy(f: &samara::analysis::Frame) -> f64 {
    f.energy.kinetic + f.energy.potential
}

fn main() {
    let words: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    let periods = words
        .iter()
        .find_map(|w| w.strip_prefix("periods=")?.parse::<f64>().ok())
        .unwrap_or(1000.0);
    let tolerance = words
        .iter()
        .find_map(|w| w.strip_prefix("tolerance=")?.parse::<f64>().ok());
    let names: Vec<&String> = words.iter().filter(|w| !w.contains('=')).collect();
    let wanted = |n: &str| names.is_empty() || names.iter().any(|w| *w == n);

    if wanted("double_pendulum") {
        let period = 2.0 * std::f64::consts::PI / ((2.0 - 2f64.sqrt()) * 9.81).sqrt();
        let m = load(
            "examples/double_pendulum.toml",
            0.04,
            periods * period,
            tolerance.unwrap_or(1e-12),
            500,
        );
        let sys = System::new(&m);
        let (s, h, wall) = timed_run(&sys, &m);
        let e0 = energy(&h.frames[0]);
        let drift = h
            .frames
            .iter()
            .map(|f| (energy(f) - e0).abs() / 9.81)
            .fold(0.0, f64::max);
        println!(
            "double_pendulum: {periods} periods ({:.0} s), {} steps ({} rejected), {:.2} Newton iterations/step, {wall:.2} s; energy drift {drift:.2e} m g l, max |Φ| {:.1e}",
            periods * period,
            s.steps,
            s.rejected_steps,
            s.newton_iterations as f64 / s.steps as f64,
            s.max_constraint_violation
        );
    }

    if wanted("spaghetti") {
        let t1 = 2.0 * std::f64::consts::PI / 5.003;
        let m = load(
            "examples/flying_spaghetti.toml",
            0.05,
            5.0 + periods * t1,
            tolerance.unwrap_or(1e-10),
            20,
        );
        let sys = System::new(&m);
        let (s, h, wall) = timed_run(&sys, &m);
        let free: Vec<_> = h.frames.iter().filter(|f| f.time >= 5.0 - 1e-9).collect();
        let e5 = energy(free[0]);
        let (p5, l5) = sys.momenta(&free[0].state);
        let (mut de, mut dp, mut dl): (f64, f64, f64) = (0.0, 0.0, 0.0);
        for f in &free {
            let (p, l) = sys.momenta(&f.state);
            de = de.max((energy(f) - e5).abs());
            dp = dp.max((p - p5).norm());
            dl = dl.max((l - l5).norm());
        }
        println!(
            "spaghetti: {periods} periods after the load ({:.0} s), {} steps ({} rejected), {:.2} Newton iterations/step, {wall:.2} s; |ΔE|/E {:.2e} (E = {e5:.3} J), |Δp|/|p| {:.2e}, |ΔL|/|L| {:.2e}",
            periods * t1,
            s.steps,
            s.rejected_steps,
            s.newton_iterations as f64 / s.steps as f64,
            de / e5,
            dp / p5.norm(),
            dl / l5.norm()
        );
    }
}
