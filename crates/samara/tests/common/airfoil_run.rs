//! Runs an airfoil or wing model and collects its element outputs and states per frame;
//! fits a sinusoid to a history (the frequency-response tests of unsteady_aero.rs and
//! dynamic_stall_hgm.rs).
#![allow(dead_code)]

use nalgebra::Complex;
use samara::analysis::{History, run_analysis};
use samara::model::Model;
use samara::system::System;
use std::path::Path;

/// Per frame: time, element outputs, element states; and the outputs' names.
pub type Run = (Vec<f64>, Vec<Vec<f64>>, Vec<String>, Vec<Vec<f64>>);

/// Runs a model's first analysis.
pub fn run(text: &str, dir: &Path) -> Run {
    let m = Model::from_toml_str(text, dir.join("m.toml"))
        .unwrap_or_else(|e| panic!("{}", e.render_plain()))
        .model;
    let sys = System::new(&m);
    let mut hist = History::default();
    let s = run_analysis(
        &sys,
        &m.analyses[0],
        sys.initial_state(),
        &mut hist,
        &mut |_| {},
    )
    .unwrap();
    assert!(s.failure.is_none(), "{:?}", s.failure);
    let mut times = Vec::new();
    let mut outs = Vec::new();
    let mut states = Vec::new();
    for f in &hist.frames {
        let mut o = vec![0.0; sys.output_names.len()];
        sys.element_outputs(&sys.context(f.time, 1.0), &f.state, &mut o);
        times.push(f.time);
        outs.push(o);
        states.push(f.state.states.iter().map(|z| z.z).collect());
    }
    (times, outs, sys.output_names.clone(), states)
}

/// Least-squares fit y ≈ a sin ωt + b cos ωt + c over the samples with t ≥ t0; returns
/// the complex amplitude a + ib (y = Im((a + ib) e^{iωt}) + c).
pub fn fit(t: &[f64], y: &[f64], w: f64, t0: f64) -> Complex<f64> {
    let mut ata = nalgebra::Matrix3::<f64>::zeros();
    let mut aty = nalgebra::Vector3::<f64>::zeros();
    for (&ti, &yi) in t.iter().zip(y) {
        if ti < t0 {
            continue;
        }
        let row = nalgebra::Vector3::new((w * ti).sin(), (w * ti).cos(), 1.0);
        ata += row * row.transpose();
        aty += row * yi;
    }
    let x = ata.lu().solve(&aty).unwrap();
    Complex::new(x[0], x[1])
}
