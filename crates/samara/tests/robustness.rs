//! Issue #10 through the library: the prescribed joint, degenerate over-constrained
//! loops, and result names from models built in code.

mod common;
use common::*;
use samara::analysis::{History, run_analysis};
use samara::model::{AnalysisKind, Model};
use samara::output::ResultsFile;
use samara::system::System;

const BOB: &str = r#"[model]
name = "prescribed"
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
name = "p"
type = "prescribed"
node_a = "ground"
node_b = "bob"
position = [1.0, 0.0, 0.0]
DRIVES
[[analyses]]
name = "swing"
type = "dynamic"
t_end = 0.5
step = 1e-2
"#;

/// Item 2: every component of a prescribed joint without a drive is held at 0 (as the
/// model reference says); a driven one follows its function. Before the fix, the bob fell
/// under gravity (z = −g t²/2 = −1.23 m at 0.5 s) with one drive, and the run panicked
/// with none.
#[test]
fn prescribed_joint_holds_undriven_components() {
    for drives in [
        "",
        "[joints.d1]\ndrive = { type = \"sine\", amplitude = 0.1, frequency = 1.0 }",
        "[joints.theta3]\ndrive = { type = \"ramp\", start = 0.0, end = 0.5, to = 1.0 }",
    ] {
        let m = model(&BOB.replace("DRIVES", drives));
        let (s, h) = run(&m);
        assert_eq!(s.steps, 50);
        for f in &h.frames {
            let t = f.time;
            let n = &f.state.nodes[0];
            let x_expected = if drives.contains("sine") {
                1.0 + 0.1 * (2.0 * std::f64::consts::PI * t).sin()
            } else {
                1.0
            };
            // Constraint rows are satisfied to the Newton tolerance (1e-8).
            assert!(
                (n.x.x - x_expected).abs() < 1e-8,
                "{drives}: t={t} {:?}",
                n.x
            );
            assert!(
                n.x.y.abs() < 1e-8 && n.x.z.abs() < 1e-8,
                "{drives}: {:?}",
                n.x
            );
            let angle = samara::math::Rotation::identity().relative_log(&n.rot);
            let expected = if drives.contains("ramp") {
                (t / 0.5).min(1.0)
            } else {
                0.0
            };
            assert!(
                (angle - nalgebra::Vector3::new(0.0, 0.0, expected)).norm() < 1e-8,
                "{drives}: t={t} {angle:?}"
            );
        }
    }
}

/// Item 2: a four-bar of spatial revolutes with a node 1e12 m away makes every row of a
/// joint redundant; that joint then has no unknowns, and assembly used to index its
/// (absent) block and panic. Now the run ends normally or with a solver failure.
#[test]
fn a_joint_whose_rows_are_all_dropped_does_not_panic() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/four_bar.toml");
    let text = std::fs::read_to_string(path).unwrap();
    let i = text.find("position = [").unwrap();
    let j = i + text[i..].find(']').unwrap();
    let far = format!("{}position = [1e12, 0.0, 0.0{}", &text[..i], &text[j..]);
    let mut m = model(&far);
    if let AnalysisKind::Dynamic(d) = &mut m.analyses[0].kind {
        d.t_end = d.t_start + 10.0 * d.step;
    }
    let sys = System::new(&m);
    assert!(!sys.warnings.is_empty(), "the loop is over-constrained");
    let mut h = History::default();
    let r = run_analysis(
        &sys,
        &m.analyses[0],
        sys.initial_state(),
        &mut h,
        &mut |_| {},
    );
    assert!(r.is_ok());
}

/// Item 1: a model built in code cannot name an analysis so that its results file lands
/// outside the results folder either.
#[test]
fn results_files_stay_in_their_folder_for_models_built_in_code() {
    let mut m: Model = model(&BOB.replace("DRIVES", ""));
    let sys = System::new(&m);
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    for bad in ["../escape", "/tmp/x", "a/b", "..", ""] {
        m.analyses[0].name = bad.into();
        let r = ResultsFile::create(&out, &m, None, &sys, &m.analyses[0]);
        assert!(
            matches!(r, Err(samara::Error::Output { .. })),
            "{bad}: {:?}",
            r.err()
        );
    }
    assert!(!dir.path().join("escape.nc").exists());
}
