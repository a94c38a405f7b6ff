//! Landing-gear drop benchmark (issue #16): `examples/landing_gear_drop.toml` — the main gear
//! with its oleo-pneumatic strut, the Magic-Formula tire with its PI anti-skid brake, and
//! the PID-controlled hydraulic retraction circuit — `T` s simulated (default 1 s: the drop,
//! spin-up and half of the anti-skid braking) at the example's step, with the History kept
//! in memory.
//!
//! `cargo bench -p samara --bench drop [-- T]` prints the wall time, steps, Newton
//! iterations per step and the time per step. Target (issue #16): 1 s in under 0.2 s on
//! one core.

use samara::analysis::{History, run_analysis};
use samara::model::Model;
use samara::system::System;
use std::path::Path;
use std::time::Instant;

fn main() {
    let t_end: f64 = std::env::args()
        .skip(1)
        .find_map(|a| a.parse().ok())
        .unwrap_or(1.0);
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut m = Model::from_file(root.join("examples/landing_gear_drop.toml"))
        .unwrap()
        .model;
    if let samara::model::AnalysisKind::Dynamic(d) = &mut m.analyses[0].kind {
        d.t_end = t_end;
    }
    let sys = System::new(&m);
    let mut best = f64::INFINITY;
    let mut steps = 0;
    let mut iterations = 0;
    for _ in 0..3 {
        let mut h = History::default();
        let clock = Instant::now();
        let s = run_analysis(
            &sys,
            &m.analyses[0],
            sys.initial_state(),
            &mut h,
            &mut |_| {},
        )
        .unwrap();
        assert!(s.failure.is_none(), "{:?}", s.failure);
        best = best.min(clock.elapsed().as_secs_f64());
        steps = s.steps;
        iterations = s.newton_iterations;
    }
    println!(
        "landing_gear_drop: {t_end} s simulated in {best:.3} s (best of 3): {steps} steps, {:.2} Newton iterations per step, {:.3} ms/step",
        iterations as f64 / steps as f64,
        1e3 * best / steps as f64
    );
}
