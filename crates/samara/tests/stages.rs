//! Analyses as stages (issue #11): the public stepper reproduces the dynamic analysis, a
//! state set from outside continues consistently, and an analysis that writes arrays
//! (not time records) gets them into its results file.

use crate::common;
use common::model;
use samara::analysis::{
    Analysis, AnalysisSummary, ArraySpec, History, Progress, Recorder, Simulation, run_analysis,
};
use samara::model::{AnalysisKind, DynamicSettings, Model};
use samara::output::{ResultsFile, ResultsReader};
use samara::system::{State, System};

const PENDULUM: &str = r#"[model]
name = "pendulum"
gravity = [0.0, 0.0, -9.81]
[[nodes]]
name = "bob"
position = [1.0, 0.0, 0.0]
[[bodies]]
name = "bob"
node = "bob"
mass = 1.0
inertia = [[1e-3, 0.0, 0.0], [0.0, 1e-3, 0.0], [0.0, 0.0, 1e-3]]
[[joints]]
name = "pivot"
type = "revolute"
node_a = "ground"
node_b = "bob"
position = [0.0, 0.0, 0.0]
axis = [0.0, 1.0, 0.0]
[[analyses]]
name = "swing"
type = "dynamic"
t_end = 0.5
step = 1e-3
rho_inf = 0.8
"#;

/// The settings of the model's first analysis, a dynamic one.
fn dynamic_settings(m: &Model) -> &DynamicSettings {
    match &m.analyses[0].kind {
        AnalysisKind::Dynamic(settings) => settings,
        _ => panic!("the first analysis is dynamic"),
    }
}

/// Stepping with `Simulation::step(h)` gives the analysis's trajectory: the same scheme,
/// steps and Newton iterations, so the same numbers up to the round-off of the step times
/// (t + h accumulated here, t₀ + k h in the analysis): 1e-12 m.
#[test]
fn stepping_reproduces_the_dynamic_analysis() {
    let m = model(PENDULUM);
    let sys = System::new(&m);
    let mut h = History::default();
    run_analysis(
        &sys,
        &m.analyses[0],
        sys.initial_state(),
        &mut h,
        &mut |_| {},
    )
    .unwrap();
    let settings = dynamic_settings(&m);
    let mut sim = Simulation::new(&sys, settings, sys.initial_state()).unwrap();
    for f in h.frames.iter().skip(1) {
        let r = sim.step(f.time - sim.time()).unwrap();
        assert_eq!(r.sub_steps, 1);
        let (a, b) = (&sim.state().nodes[0].x, &f.state.nodes[0].x);
        assert!((a - b).norm() < 1e-12, "t = {}: {a:?} vs {b:?}", f.time);
    }
    assert!((sim.time() - 0.5).abs() < 1e-12);
}

/// A state set from outside (here: the bob given a push mid-run) is made consistent and
/// the motion continues from it: the velocity is projected onto the joint (its radial
/// part removed), and energy is conserved afterwards to the scheme's accuracy.
#[test]
fn a_state_set_from_outside_continues_consistently() {
    let m = model(PENDULUM);
    let sys = System::new(&m);
    let settings = dynamic_settings(&m);
    let mut sim = Simulation::new(&sys, settings, sys.initial_state()).unwrap();
    for _ in 0..100 {
        sim.step(1e-3).unwrap();
    }
    let mut s: State = sim.state().clone();
    let r = s.nodes[0].x; // pivot at the origin: r is the radial direction
    s.nodes[0].v += r * 3.0 + nalgebra::Vector3::new(0.0, 0.0, 0.5);
    sim.set_state(s).unwrap();
    let after = sim.state().nodes[0].clone();
    assert!(
        after.v.dot(&after.x).abs() < 1e-10,
        "radial velocity removed"
    );
    let energy =
        |st: &State| sys.kinetic_energy(st) + sys.potential_energy(&sys.context(st.time, 1.0), st);
    let e0 = energy(sim.state());
    for _ in 0..200 {
        sim.step(1e-3).unwrap();
    }
    // ρ∞ = 0.8 dissipates O(h²)-little from the resolved pendulum motion.
    assert!((energy(sim.state()) - e0).abs() < 1e-4 * e0.abs().max(1.0));
}

/// A stage that writes one array and no records.
struct Table;

impl Analysis for Table {
    fn name(&self) -> &str {
        "table"
    }
    fn kind(&self) -> &'static str {
        "table"
    }
    fn arrays(&self, sys: &System) -> Vec<ArraySpec> {
        vec![ArraySpec {
            name: "node_distance".into(),
            dims: vec![("node".into(), sys.n_nodes()), ("pair".into(), 2)],
            units: "m".into(),
            long_name: "distance of each node from the origin, twice".into(),
        }]
    }
    fn run(
        &self,
        sys: &System,
        initial: State,
        recorder: &mut dyn Recorder,
        _progress: Progress,
    ) -> Result<AnalysisSummary, samara::Error> {
        let values: Vec<f64> = initial
            .nodes
            .iter()
            .flat_map(|n| [n.x.norm(), 2.0 * n.x.norm()])
            .collect();
        recorder.write_array(sys, &self.arrays(sys)[0], &values)?;
        let mut s = AnalysisSummary::new("table", "table");
        s.final_state = initial;
        Ok(s)
    }
}

#[test]
fn a_stage_writes_arrays_that_are_not_time_records() {
    let m = model(PENDULUM);
    let sys = System::new(&m);
    let dir = tempfile::tempdir().unwrap();
    let mut file = ResultsFile::create_for(dir.path(), &m, None, &sys, &Table).unwrap();
    let summary = Table
        .run(&sys, sys.initial_state(), &mut file, &mut |_| {})
        .unwrap();
    let path = file.finish(&summary).unwrap();
    let mut r = ResultsReader::open(&path).unwrap();
    assert_eq!(r.read("node_distance").unwrap(), vec![1.0, 2.0]);
    assert_eq!(r.attr("analysis_type").as_deref(), Some("table"));
    // An array of the wrong size is refused, not written.
    let mut h = History::default();
    Table
        .run(&sys, sys.initial_state(), &mut h, &mut |_| {})
        .unwrap();
    assert_eq!(h.arrays[0].1, vec![1.0, 2.0]);
    let mut file = ResultsFile::create_for(dir.path(), &m, None, &sys, &Table).unwrap();
    assert!(
        file.write_array(&sys, &Table.arrays(&sys)[0], &[1.0])
            .is_err()
    );
}

/// A state that does not fit the model (a node, a joint coordinate or a multiplier too
/// many or too few) is refused with a failure that names what differs, by
/// `Simulation::new` and by `set_state`, and the simulation keeps its state.
#[test]
fn a_state_of_another_shape_is_refused() {
    let m = model(PENDULUM);
    let sys = System::new(&m);
    let settings = dynamic_settings(&m);
    let mut wrong = sys.initial_state();
    wrong.nodes.push(wrong.nodes[0].clone());
    let e = Simulation::new(&sys, settings, wrong)
        .err()
        .expect("refused");
    assert!(
        e.reason.contains("2 nodes") && e.reason.contains("1"),
        "{}",
        e.reason
    );
    let mut sim = Simulation::new(&sys, settings, sys.initial_state()).unwrap();
    sim.step(1e-3).unwrap();
    let before = sim.state().clone();
    for cut in ["coords", "lambda", "states"] {
        let mut s = sim.state().clone();
        match cut {
            "coords" => s.coords.push(Default::default()),
            "lambda" => s.lambda.clear(),
            _ => s.states.push(Default::default()),
        }
        let e = sim.set_state(s).expect_err(cut);
        assert!(e.reason.contains("does not fit"), "{cut}: {}", e.reason);
        assert_eq!(sim.state(), &before, "{cut}: the state is kept");
    }
}
