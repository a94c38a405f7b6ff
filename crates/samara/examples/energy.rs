use samara::analysis::{History, run_analysis};
use samara::model::{AnalysisKind, Model};
use samara::system::{State, System};
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let mut model = Model::from_file(&args[1]).unwrap().model;
    for a in &args[2..] {
        let h: f64 = a.parse().unwrap();
        if let AnalysisKind::Dynamic(d) = &mut model.analyses[0].kind {
            d.step = h;
            d.solver.tolerance = std::env::var("TOL")
                .map(|s| s.parse().unwrap())
                .unwrap_or(1e-12);
            if let Ok(r) = std::env::var("RHO") {
                d.rho_inf = r.parse().unwrap();
                d.formulation = if d.rho_inf == 1.0 {
                    samara::model::FormulationType::StabilizedIndex2
                } else {
                    samara::model::FormulationType::Index3
                };
            }
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
        let mut mx = [0.0f64; 4];
        for (i, f) in hist.frames.iter().enumerate() {
            let e = f.energy.kinetic + f.energy.potential - f.energy.external_work
                + f.energy.dissipated;
            mx[4 * i / n] = mx[4 * i / n].max((e - e0).abs());
        }
        let p1 = hist.at(1.0).unwrap().state.nodes.last().unwrap().x;
        println!(
            "h={h:e} steps={} rej={} fail={:?} iters/step={:.2} max|dE| by quarters {:?} pos(1s)={:.10?}",
            s.steps,
            s.rejected_steps,
            s.failure.map(|f| f.reason),
            s.newton_iterations as f64 / s.steps as f64,
            mx,
            p1.as_slice()
        );
    }
}
