//! Issue #10 through the library: the prescribed joint, degenerate over-constrained
//! loops, and result names from models built in code.

use crate::common;
use common::line_of;
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

/// The first error of `check_analyses` (the checks that need the built system) on a model
/// that validates: its 1-based line, message and hint.
fn system_error(text: &str) -> (usize, String, String) {
    let loaded = Model::from_toml_str(text, "bad.toml").unwrap_or_else(|e| panic!("{e}"));
    let sys = System::new(&loaded.model);
    let Err(e) = samara::analysis::check_analyses(&loaded, &sys) else {
        panic!("accepted:\n{text}")
    };
    let d = e.errors().next().expect("an error");
    let span = d.span.clone().expect("a located error");
    let (line, _) = e.source.line_col(span.start);
    (line, d.message.clone(), d.hint.clone().unwrap_or_default())
}

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
"#;

/// Issue #14: bad input of the linearized analyses is a located error before anything
/// runs — `samara check` and `samara run` report it with the file's other errors:
/// - a modal analysis of a model without mass (a beam with stiffness only), at the
///   analysis's name;
/// - `n_modes` above the degrees of freedom (the pendulum has one: 6 unknowns, 5
///   constraint equations), at the key; the default of 10 at the analysis's name; the same
///   in a Campbell analysis;
/// - a Floquet period that is not a period of the loads (a stiffness function of period
///   2π, T = 5 s), at `period`; T = 2π passes;
/// - a rotation axis of zero length, at validation, at the rotation.
#[test]
fn linearized_analyses_bad_input_is_located() {
    let modal = |extra: &str| {
        format!("{PENDULUM}[[analyses]]\nname = \"modes\"\ntype = \"modal\"\n{extra}")
    };
    let text = modal("n_modes = 3\n");
    let (line, message, hint) = system_error(&text);
    assert_eq!(line, line_of(&text, "n_modes = 3"));
    assert!(message.contains("1 degrees of freedom"), "{message}");
    assert!(hint.contains("n_modes = 1"), "{hint}");
    let text = modal("");
    let (line, message, _) = system_error(&text);
    assert_eq!(line, line_of(&text, "name = \"modes\""));
    assert!(message.contains("default n_modes = 10"), "{message}");
    let loaded = Model::from_toml_str(&modal("n_modes = 1\n"), "ok.toml").unwrap();
    let sys = System::new(&loaded.model);
    assert!(samara::analysis::check_analyses(&loaded, &sys).is_ok());
    let text = format!(
        "{PENDULUM}[[analyses]]\nname = \"sweep\"\ntype = \"campbell\"\nrotation = {{ axis = [0.0, 0.0, 1.0] }}\nspeeds = [0.0, 1.0]\nn_modes = 2\n"
    );
    let (line, message, _) = system_error(&text);
    assert_eq!(line, line_of(&text, "n_modes = 2"));
    assert!(message.contains("degrees of freedom"), "{message}");

    let massless = r#"[model]
name = "massless"
[[beams]]
name = "beam"
order = 2
points = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]
root = "root"
[[beams.sections]]
station = 0.0
stiffness = [
  [1e6, 0.0, 0.0, 0.0, 0.0, 0.0],
  [0.0, 1e6, 0.0, 0.0, 0.0, 0.0],
  [0.0, 0.0, 1e6, 0.0, 0.0, 0.0],
  [0.0, 0.0, 0.0, 1e3, 0.0, 0.0],
  [0.0, 0.0, 0.0, 0.0, 1e3, 0.0],
  [0.0, 0.0, 0.0, 0.0, 0.0, 1e3],
]
[[joints]]
name = "clamp"
type = "fixed"
node_a = "ground"
node_b = "root"
[[analyses]]
name = "modes"
type = "modal"
n_modes = 2
"#;
    let (line, message, hint) = system_error(massless);
    assert_eq!(line, line_of(massless, "name = \"modes\""));
    assert!(message.contains("no mass"), "{message}");
    assert!(hint.contains("mass"), "{hint}");

    let mathieu = |period: &str| {
        format!(
            r#"[model]
name = "mathieu"
[[nodes]]
name = "mass"
position = [0.0, 0.0, 0.0]
[[bodies]]
name = "mass"
node = "mass"
mass = 1.0
inertia = [[0.1, 0.0, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.1]]
[[joints]]
name = "slider"
type = "prismatic"
node_a = "ground"
node_b = "mass"
position = [0.0, 0.0, 0.0]
axis = [1.0, 0.0, 0.0]
[[springs]]
name = "spring"
node_a = "ground"
node_b = "mass"
point_a = [-1.0, 0.0, 0.0]
stiffness = 1.0
stiffness_function = {{ type = "sine", amplitude = 0.3, frequency = 0.15915494309189535, offset = 0.6 }}
[[analyses]]
name = "floquet"
type = "floquet"
{period}
steps_per_period = 50
"#
        )
    };
    let text = mathieu("period = 5.0");
    let (line, message, hint) = system_error(&text);
    assert_eq!(line, line_of(&text, "period = 5.0"));
    assert!(message.contains("not a period of the loads"), "{message}");
    assert!(hint.contains("period"), "{hint}");
    let text = mathieu("period = 6.283185307179586");
    let loaded = Model::from_toml_str(&text, "ok.toml").unwrap();
    let sys = System::new(&loaded.model);
    assert!(samara::analysis::check_analyses(&loaded, &sys).is_ok());

    let text = modal("rotation = { axis = [0.0, 0.0, 0.0], omega = 1.0 }\nn_modes = 1\n");
    let Err(e) = Model::from_toml_str(&text, "bad.toml") else {
        panic!("accepted")
    };
    let d = e.errors().next().unwrap();
    let (line, _) = e.source.line_col(d.span.clone().expect("located").start);
    assert_eq!(line, line_of(&text, "rotation = {"));
    assert!(d.message.contains("non-zero"), "{}", d.message);
    assert!(d.hint.as_deref().unwrap_or("").contains("direction"));
}

/// A key or table given twice is named, located at the second, and hinted (the TOML
/// parser's own message was only "duplicate key").
#[test]
fn keys_and_tables_given_twice_are_named_and_located() {
    let check = |text: &str, second: &str, message: &str, hint: &str| {
        let shown = Model::from_toml_str(text, "twice.toml")
            .expect_err(second)
            .to_string();
        let at = text.rfind(second).unwrap();
        let line = text[..at].matches('\n').count() + 1;
        let col = at - text[..at].rfind('\n').map_or(0, |i| i + 1) + 1;
        assert!(
            shown.contains(&format!("twice.toml:{line}:{col}: error: {message}")),
            "{shown}"
        );
        assert!(shown.contains(hint), "{shown}");
    };
    let base = BOB.replace("DRIVES\n", "");
    check(
        &base.replace("t_end = 0.5\n", "t_end = 0.5\nt_end = 0.7\n"),
        "t_end",
        "key `t_end` is given twice in this table",
        "give each key once per table",
    );
    check(
        &format!("{base}[model]\nname = \"again\"\n"),
        "model]",
        "table `model` is given twice",
        "a list of entries is written [[name]]",
    );
    check(
        &format!("{base}[ model ]\nname = \"again\"\n"),
        "model ]",
        "table `model` is given twice",
        "write each table once",
    );
    check(
        &base.replace("gravity = ", "gravity = [0.0, 0.0, 0.0]\ngravity = "),
        "gravity",
        "key `gravity` is given twice in this table",
        "remove one of the two",
    );
}

/// A results file's projected size ([`ResultsFile::projected_size`] of
/// [`samara::model::AnalysisDef::min_records`]) is the size it reaches, to the byte, for
/// fixed steps that divide the span: every step, every 10th (`output_every`), and at
/// `output_interval`; for adaptive steps it is a lower bound; for a static analysis, its
/// load steps and the unloaded state (10¹² load steps are refused). A run that fits raises no
/// shortfall; one of 10¹² records (10¹² steps, the most validation accepts: 320 TB) does, on any
/// disk the suite runs on, with the numbers in its message, and `ensure_space` then
/// removes the file and puts an earlier one back.
#[test]
fn the_projected_results_size_is_the_written_size() {
    let analysis = |t_end: f64, extra: &str| {
        model(&format!(
            "{PENDULUM}[[analyses]]\nname = \"swing\"\ntype = \"dynamic\"\nt_end = {t_end:e}\n{extra}"
        ))
    };
    let cases = [
        ("step = 1e-3\n", 101),
        ("step = 1e-3\noutput_every = 10\n", 11),
        ("step = 1e-3\noutput_interval = 0.02\n", 6),
        (
            "step = 2e-3\nstep_control = \"adaptive\"\nstep_max = 0.01\n",
            11,
        ),
    ];
    for (extra, expected) in cases {
        let m = analysis(0.1, extra);
        let def = &m.analyses[0];
        let records = def.min_records().expect("a dynamic analysis");
        assert_eq!(records, expected, "{extra}");
        let sys = System::new(&m);
        let dir = tempfile::tempdir().unwrap();
        let mut file = ResultsFile::create(dir.path(), &m, None, &sys, def).unwrap();
        assert_eq!(file.space_shortfall(def), None, "{extra}");
        let projected = file.projected_size(records);
        let summary = run_analysis(&sys, def, sys.initial_state(), &mut file, &mut |_| {}).unwrap();
        assert!(summary.failure.is_none(), "{extra}: {:?}", summary.failure);
        let written = file.records();
        let path = file.finish(&summary).unwrap();
        let size = std::fs::metadata(&path).unwrap().len();
        if extra.contains("adaptive") {
            assert!(written >= records, "{extra}: {written} records");
            assert!(size >= projected, "{extra}: {size} < {projected}");
        } else {
            assert_eq!(written, records, "{extra}");
            assert_eq!(size, projected, "{extra}");
        }
    }
    // Statics: the unloaded state and one record per load step, to the byte (gravity
    // along the rod: the pendulum hangs where it starts, no increment is cut).
    let hanging = PENDULUM.replace("gravity = [0.0, 0.0, -9.81]", "gravity = [9.81, 0.0, 0.0]");
    let statics = |load_steps: &str| {
        model(&format!(
            "{hanging}[[analyses]]\nname = \"hang\"\ntype = \"static\"\nload_steps = {load_steps}\n"
        ))
    };
    let m = statics("4");
    let def = &m.analyses[0];
    assert_eq!(def.min_records(), Some(5));
    let sys = System::new(&m);
    let dir = tempfile::tempdir().unwrap();
    let mut file = ResultsFile::create(dir.path(), &m, None, &sys, def).unwrap();
    assert_eq!(file.space_shortfall(def), None);
    let projected = file.projected_size(5);
    let summary = run_analysis(&sys, def, sys.initial_state(), &mut file, &mut |_| {}).unwrap();
    assert!(summary.failure.is_none(), "{:?}", summary.failure);
    assert_eq!(file.records(), 5);
    let path = file.finish(&summary).unwrap();
    assert_eq!(std::fs::metadata(&path).unwrap().len(), projected);
    let m = statics("1_000_000_000_000");
    let def = &m.analyses[0];
    let sys = System::new(&m);
    let file = ResultsFile::create(dir.path(), &m, None, &sys, def).unwrap();
    let s = file
        .space_shortfall(def)
        .expect("1e12 load steps' records fit no disk");
    assert_eq!(s.records, 1_000_000_000_001);
    assert!(s.hint().contains("`load_steps`"));
    assert!(file.ensure_space(def).is_err());

    let m = analysis(1e3, "step = 1e-9\n");
    let def = &m.analyses[0];
    assert_eq!(def.min_records(), Some(1_000_000_000_001));
    let sys = System::new(&m);
    let dir = tempfile::tempdir().unwrap();
    let file = ResultsFile::create(dir.path(), &m, None, &sys, def).unwrap();
    let s = file.space_shortfall(def).expect("1e12 records fit no disk");
    assert_eq!(s.records, 1_000_000_000_001);
    assert!(s.record_bytes >= 300, "{} bytes per record", s.record_bytes);
    assert!(s.needed > s.available);
    let text = s.to_string();
    assert!(
        text.starts_with("the results need at least ") && text.contains("TB"),
        "{text}"
    );
    assert!(s.hint().contains("output_interval"));
    // Refused: the file removed, the earlier one back at its name.
    let Err(e) = file.ensure_space(def) else {
        panic!("refused")
    };
    assert!(
        e.to_string().contains("analysis 'swing': the results need"),
        "{e}"
    );
    assert!(!dir.path().join("swing.nc").exists());
    std::fs::write(dir.path().join("swing.nc"), b"earlier").unwrap();
    let file = ResultsFile::create(dir.path(), &m, None, &sys, def).unwrap();
    assert!(file.backup.is_some());
    assert!(file.ensure_space(def).is_err());
    assert_eq!(
        std::fs::read(dir.path().join("swing.nc")).unwrap(),
        b"earlier"
    );
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}
