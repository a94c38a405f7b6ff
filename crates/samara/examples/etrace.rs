use samara::analysis::{History, run_analysis};
use samara::model::{AnalysisKind, Model};
use samara::system::{State, System};
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let mut model = Model::from_file(&args[1]).unwrap().model;
    let h: f64 = args[2].parse().unwrap();
    if let AnalysisKind::Dynamic(d) = &mut model.analyses[0].kind {
        d.step = h;
        d.solver.tolerance = args[3].parse().unwrap();
    }
    let sys = System::new(&model);
    let mut hist = History::default();
    let s = run_analysis(
        &sys,
        &model.analyses[0],
        State::initial(&model, sys.n_multipliers),
        &mut hist,
        &mut |_| {},
    )
    .unwrap();
    let e0 = hist.frames[0].energy.kinetic + hist.frames[0].energy.potential;
    let n = hist.frames.len();
    for chunk in hist.frames.chunks(n / 20) {
        let es: Vec<f64> = chunk
            .iter()
            .map(|f| f.energy.kinetic + f.energy.potential - e0)
            .collect();
        let mn = es.iter().cloned().fold(f64::MAX, f64::min);
        let mx = es.iter().cloned().fold(f64::MIN, f64::max);
        println!(
            "t={:.2} dE in [{mn:.3e}, {mx:.3e}] KE={:.2}",
            chunk[0].time, chunk[0].energy.kinetic
        );
    }
    println!(
        "iters/step {:.2} rejected {}",
        s.newton_iterations as f64 / s.steps as f64,
        s.rejected_steps
    );
}
