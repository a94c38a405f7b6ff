//! Aerodynamics benchmark (issue #15): the NREL 5-MW rotor of
//! `examples/rotor/nrel5mw_rotor.toml` (three rigid blades, 19 AeroDyn stations each, BEM
//! with tip and hub loss) free on its shaft in 13 m/s wind, `T` s at h = 0.01 s.
//!
//! `cargo bench -p samara --bench aero [-- T]` prints the wall time, the time per step,
//! the real-time factor, and the cost of one residual-and-tangent evaluation of all 57
//! stations.

use samara::analysis::{History, run_analysis};
use samara::core::{ElementInput, EvalContext, LocalTerms, Need};
use samara::model::Model;
use samara::model::components::{Build, build_all, initial_nodes};
use samara::system::System;
use std::path::Path;
use std::time::Instant;

fn main() {
    let t_end: f64 = std::env::args()
        .skip(1)
        .find_map(|a| a.parse().ok())
        .unwrap_or(10.0);
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let loaded = Model::from_file(root.join("examples/rotor/nrel5mw_rotor.toml")).unwrap();
    let mut m = loaded.model;
    for l in &mut m.aero_lines {
        l.wind.speed = 13.0;
    }
    if let samara::model::AnalysisKind::Dynamic(d) = &mut m.analyses[0].kind {
        d.t_end = t_end;
        d.step = 0.01;
    }
    // Station kernels alone.
    let initial = initial_nodes(&m);
    let mut parts = Build::new(&initial);
    build_all(&m, &mut parts);
    let ctx = EvalContext {
        time: 0.0,
        gravity: nalgebra::Vector3::zeros(),
        load_factor: 1.0,
    };
    let aero: Vec<_> = parts
        .elements
        .iter()
        .filter(|e| e.name().starts_with("blade"))
        .collect();
    let mut terms: Vec<LocalTerms> = aero
        .iter()
        .map(|e| LocalTerms::for_element(e.as_ref()))
        .collect();
    let reps = 200;
    let clock = Instant::now();
    for _ in 0..reps {
        for (e, t) in aero.iter().zip(&mut terms) {
            t.clear(Need::ResidualAndTangents);
            e.evaluate(
                &ctx,
                &ElementInput::nodes(&initial),
                Need::ResidualAndTangents,
                t,
            );
        }
    }
    let per_eval = clock.elapsed().as_secs_f64() / reps as f64;
    println!(
        "{} stations: residual + tangents {:.1} µs ({:.2} µs per station)",
        aero.len(),
        1e6 * per_eval,
        1e6 * per_eval / aero.len() as f64
    );
    // The whole run.
    let sys = System::new(&m);
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
    let wall = clock.elapsed().as_secs_f64();
    println!(
        "{t_end} s simulated in {wall:.3} s: {} steps, {:.3} ms/step, {:.0}× faster than real time",
        s.steps,
        1e3 * wall / s.steps as f64,
        t_end / wall
    );
}
