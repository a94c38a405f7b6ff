//! The `samara` command end to end: runs, results files, exit codes, and clear errors for
//! bad input (issue #2, verification 8).

use netcdf3::FileReader;
use std::path::{Path, PathBuf};

use crate::common;
use common::*;

/// `text` with the first occurrence of `from` replaced by `to` fails `samara check` with
/// exit status 1 and an error at `line:col` (of the replaced text) containing `message`
/// (and `hint`, if given).
fn assert_bad(from: &str, to: &str, message: &str, hint: Option<&str>) {
    assert_bad_at(from, to, to, message, hint)
}

/// As [`assert_bad`], with the error expected on the line of the last occurrence of `at`.
fn assert_bad_at(from: &str, to: &str, at: &str, message: &str, hint: Option<&str>) {
    assert!(PENDULUM.contains(from), "{from}");
    let text = PENDULUM.replacen(from, to, 1);
    let (o, path, _dir) = check_text("bad.toml", &text);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    let offset = text.rfind(at).unwrap();
    let line = text[..offset].matches('\n').count() + 1;
    let first = err
        .lines()
        .find(|l| l.contains(": error: "))
        .unwrap_or_else(|| panic!("{err}"));
    let prefix = format!("{}:{line}:", path.display());
    assert!(
        first.starts_with(&prefix),
        "expected the error on line {line}:\n{err}"
    );
    assert!(first.contains(message), "expected '{message}' in:\n{err}");
    if let Some(h) = hint {
        assert!(err.contains(h), "expected hint '{h}' in:\n{err}");
    }
}

#[test]
fn run_writes_a_complete_results_file_and_keeps_earlier_ones() {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("pendulum.toml");
    std::fs::write(&model, PENDULUM).unwrap();
    let out = dir.path().join("results");
    let o = samara(&[
        "run",
        model.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let summary = String::from_utf8_lossy(&o.stdout);
    assert!(
        summary.contains("swing") && summary.contains("500"),
        "{summary}"
    );

    let path = out.join("swing.nc");
    let mut rd = FileReader::open(&path).unwrap();
    let ds = rd.data_set();
    assert_eq!(ds.num_records(), Some(501));
    assert_eq!(
        ds.get_global_attr_as_string("status").as_deref(),
        Some("completed")
    );
    assert_eq!(
        ds.get_global_attr_as_string("analysis").as_deref(),
        Some("swing")
    );
    assert_eq!(ds.get_global_attr_i32("format_version"), Some(&[2][..]));
    assert_eq!(ds.get_global_attr_i32("steps"), Some(&[500][..]));
    for v in [
        "time",
        "node_name",
        "position",
        "orientation",
        "velocity",
        "angular_velocity",
        "joint_name",
        "joint_force",
        "joint_moment",
        "kinetic_energy",
        "potential_energy",
        "external_work",
        "dissipated_energy",
        "constraint_violation",
        "newton_iterations",
        "condition_estimate",
        "residual_norm",
        "step_size",
    ] {
        assert!(ds.has_var(v), "missing variable {v}");
    }
    let t = rd.read_var_f64("time").unwrap();
    assert_eq!(t.len(), 501);
    assert!((t[500] - 0.5).abs() < 1e-12);
    let names = rd.read_var_u8("node_name").unwrap();
    assert_eq!(&names[..3], b"bob");
    let x = rd.read_var_f64("position").unwrap();
    let q = rd.read_var_f64("orientation").unwrap();
    let ke = rd.read_var_f64("kinetic_energy").unwrap();
    let pe = rd.read_var_f64("potential_energy").unwrap();
    let viol = rd.read_var_f64("constraint_violation").unwrap();
    let iters = rd.read_var_i32("newton_iterations").unwrap();
    let kappa = rd.read_var_f64("condition_estimate").unwrap();
    let f = rd.read_var_f64("joint_force").unwrap();
    for k in 0..501 {
        let r = (x[3 * k].powi(2) + x[3 * k + 1].powi(2) + x[3 * k + 2].powi(2)).sqrt();
        assert!(
            (r - 1.0).abs() < 1e-8,
            "bob off the circle at record {k}: {r}"
        );
        let qn: f64 = q[4 * k..4 * k + 4].iter().map(|v| v * v).sum();
        assert!((qn - 1.0).abs() < 1e-12);
        assert!(viol[k] <= 1e-8);
        if k > 0 {
            assert!(iters[k] >= 1 && kappa[k].is_finite() && kappa[k] > 1.0);
        }
    }
    // Energy is nearly conserved with ρ∞ = 0.9 over 0.5 s (mild numerical dissipation).
    let e0 = ke[0] + pe[0];
    assert!((ke[500] + pe[500] - e0).abs() < 1e-3 * 9.81);
    // Pivot force magnitude at the start: m g I/(I + m L²) (released from rest, horizontal).
    let f0 = (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt();
    let expected = 9.81 * 1e-3 / (1e-3 + 1.0);
    assert!((f0 - expected).abs() < 1e-9, "{f0} vs {expected}");

    // A second run moves the first file aside instead of overwriting it.
    let o = samara(&[
        "run",
        model.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success());
    assert!(out.join("swing.~1~.nc").exists());
    assert!(stderr(&o).contains("swing.~1~.nc"));
    assert!(FileReader::open(out.join("swing.nc")).is_ok());
}

#[test]
fn examples_check_clean() {
    for m in [
        "examples/pendulum.toml",
        "examples/double_pendulum.toml",
        "examples/heavy_top.toml",
        "examples/verification/heavy_top.toml",
        "examples/slider_crank.toml",
        "examples/four_bar.toml",
        "examples/landing_gear.toml",
        "examples/joint_gallery.toml",
    ] {
        let o = samara(&["check", root().join(m).to_str().unwrap()]);
        assert!(o.status.success(), "{m}: {}", stderr(&o));
        assert!(String::from_utf8_lossy(&o.stdout).contains("ok"));
    }
}

/// `samara check` says when a model is over-constrained, and by how many equations.
#[test]
fn check_warns_about_redundant_constraints() {
    let o = samara(&[
        "check",
        root().join("examples/four_bar.toml").to_str().unwrap(),
    ]);
    assert!(o.status.success());
    let err = stderr(&o);
    assert!(
        err.contains("warning") && err.contains("over-constrained by 3 equations"),
        "{err}"
    );
    assert!(String::from_utf8_lossy(&o.stdout).contains("after dropping 3 redundant"));
}

#[test]
fn joint_axes_must_be_orthogonal() {
    assert_bad_at(
        "axis = [0.0, 1.0, 0.0]",
        "axis = [0.0, 1.0, 0.0]\naxis_1 = [0.0, 0.5, 1.0]",
        "axis_1 =",
        "not orthogonal",
        Some("orthogonal"),
    );
}

#[test]
fn a_joint_cannot_connect_a_node_to_itself() {
    assert_bad_at(
        r#"node_a = "ground""#,
        r#"node_a = "bob""#,
        r#"node_b = "bob""#,
        "connects node 'bob' to itself",
        None,
    );
}

#[test]
fn nothing_can_be_attached_to_a_constrained_component() {
    assert_bad_at(
        "axis = [0.0, 1.0, 0.0]",
        "axis = [0.0, 1.0, 0.0]\n[joints.d1]\nstiffness = 10.0",
        "[joints.d1]",
        "`d1` is constrained by a revolute joint",
        Some("theta3"),
    );
}

#[test]
fn joint_inputs_are_checked() {
    // An input port naming an unknown signal.
    assert_bad_at(
        "axis = [0.0, 1.0, 0.0]",
        "axis = [0.0, 1.0, 0.0]\n[joints.theta3]\ninput = \"pilto\"\n[[signals]]\nname = \"pilot\"\nfunction = { type = \"constant\", value = 1.0 }",
        "\"pilto\"",
        "unknown signal 'pilto'",
        Some("did you mean 'pilot'"),
    );
    // A screw needs its pitch.
    assert_bad(r#"type = "revolute""#, r#"type = "screw""#, "pitch", None);
    // Backlash needs a positive width.
    assert_bad_at(
        "axis = [0.0, 1.0, 0.0]",
        "axis = [0.0, 1.0, 0.0]\n[joints.theta3]\nbacklash = { width = -0.1, stiffness = 1e4 }",
        "backlash =",
        "width",
        None,
    );
}

#[test]
fn schema_is_json_describing_the_model_file() {
    let o = samara(&["schema"]);
    assert!(o.status.success());
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("valid JSON");
    let props = &v["properties"];
    for key in [
        "model", "nodes", "bodies", "joints", "springs", "forces", "analyses",
    ] {
        assert!(props.get(key).is_some(), "schema lacks '{key}'");
    }
}

#[test]
fn unknown_node_suggests_the_closest_name() {
    assert_bad(
        r#"node_b = "bob""#,
        r#"node_b = "bobb""#,
        "unknown node 'bobb'",
        Some("did you mean 'bob'"),
    );
}

#[test]
fn duplicate_names_are_rejected() {
    assert_bad_at(
        "[[analyses]]",
        "[[nodes]]\nname = \"bob\"\nposition = [2.0, 0.0, 0.0]\n\n[[analyses]]",
        "name = \"bob\"",
        "duplicate",
        None,
    );
}

#[test]
fn non_positive_mass_is_rejected() {
    assert_bad("mass = 1.0", "mass = -2.0", "mass", None);
    assert_bad("mass = 1.0", "mass = 0.0", "mass", None);
}

#[test]
fn inertia_must_be_symmetric_positive_definite() {
    assert_bad(
        "[0.0, 1e-3, 0.0], [0.0, 0.0, 1e-3]]",
        "[0.0, -1e-3, 0.0], [0.0, 0.0, 1e-3]]",
        "positive definite",
        None,
    );
    assert_bad(
        "[[1e-3, 0.0, 0.0], [0.0, 1e-3",
        "[[1e-3, 5e-4, 0.0], [0.0, 1e-3",
        "symmetric",
        None,
    );
}

#[test]
fn zero_axis_is_rejected() {
    assert_bad(
        "axis = [0.0, 1.0, 0.0]",
        "axis = [0.0, 0.0, 0.0]",
        "axis",
        None,
    );
}

#[test]
fn unknown_keys_are_named_with_a_suggestion() {
    assert_bad("mass = 1.0", "mas = 1.0", "unknown", Some("mass"));
}

#[test]
fn malformed_numbers_are_located() {
    assert_bad("step = 1e-3", "step = 1e-3.5", "", None);
    assert_bad("t_end = 0.5", "t_end = \"half\"", "", None);
}

#[test]
fn a_missing_model_file_is_a_clear_error() {
    let o = samara(&["check", "/nonexistent/model.toml"]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(
        e.contains("/nonexistent/model.toml") && e.contains("cannot read"),
        "{e}"
    );
}

#[test]
fn an_unwritable_results_directory_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("pendulum.toml");
    std::fs::write(&model, PENDULUM).unwrap();
    // A regular file where the results directory should be.
    let blocker = dir.path().join("blocker");
    std::fs::write(&blocker, "x").unwrap();
    let out = blocker.join("results");
    let o = samara(&[
        "run",
        model.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(
        e.contains("results directory") && e.contains("--out"),
        "{e}"
    );
}

#[test]
fn a_solver_failure_exits_with_status_2_and_keeps_the_partial_results() {
    // A node with no mass, held only by a spring, cannot be accelerated consistently.
    let text = PENDULUM.replace(
        "[[analyses]]",
        "[[nodes]]\nname = \"loose\"\nposition = [3.0, 0.0, 0.0]\n\n[[springs]]\nname = \"s\"\nnode_a = \"bob\"\nnode_b = \"loose\"\nstiffness = 10.0\n\n[[analyses]]",
    );
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("m.toml");
    std::fs::write(&model, text).unwrap();
    let out = dir.path().join("out");
    let o = samara(&[
        "run",
        model.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("swing") && e.contains("help:"), "{e}");
    let rd = FileReader::open(out.join("swing.nc")).unwrap();
    assert_eq!(
        rd.data_set().get_global_attr_as_string("status").as_deref(),
        Some("failed")
    );
}

/// Runs the pendulum into a fresh directory; returns (dir guard, results path).
fn pendulum_results() -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("pendulum.toml");
    std::fs::write(&model, PENDULUM).unwrap();
    let out = dir.path().join("out");
    let o = samara(&[
        "run",
        model.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "-q",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    (dir, out.join("swing.nc"))
}

#[test]
fn info_describes_a_results_file() {
    let (_dir, path) = pendulum_results();
    let o = samara(&["info", path.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = String::from_utf8_lossy(&o.stdout);
    for want in [
        "pendulum",
        "swing (dynamic)",
        "completed",
        "501 output times",
        "bob",
        "pivot",
        "500 steps",
        "joint_force",
    ] {
        assert!(s.contains(want), "'{want}' missing from:\n{s}");
    }
}

#[test]
fn info_reports_missing_truncated_foreign_and_newer_files() {
    let (dir, path) = pendulum_results();
    // Missing.
    let o = samara(&["info", dir.path().join("nope.nc").to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("cannot open results file"),
        "{}",
        stderr(&o)
    );
    // Truncated in the middle of the records.
    let bytes = std::fs::read(&path).unwrap();
    let cut = dir.path().join("cut.nc");
    std::fs::write(&cut, &bytes[..bytes.len() * 2 / 3]).unwrap();
    let o = samara(&["info", cut.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(e.contains("truncated") && e.contains("501"), "{e}");
    // Not NetCDF at all.
    let junk = dir.path().join("junk.nc");
    std::fs::write(&junk, "hello").unwrap();
    let o = samara(&["info", junk.to_str().unwrap()]);
    assert!(stderr(&o).contains("not a NetCDF file"), "{}", stderr(&o));
    // A results file from a newer samara (format_version 99).
    use samara::output::netcdf::{AttrValue, Definition, NcType};
    let newer = dir.path().join("newer.nc");
    let mut d = Definition::new();
    let t = d.add_record_dim("time");
    d.add_var("time", NcType::Double, &[t]);
    d.add_global_attr("format_version", AttrValue::Int(vec![99]));
    d.create(&newer).unwrap().finish().unwrap();
    let o = samara(&["info", newer.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(e.contains("newer samara") && e.contains("99"), "{e}");
}

#[test]
fn vtk_series_reads_back_with_a_vtk_reader() {
    use vtkio::model::{Attribute, DataSet, IOBuffer, Piece};
    let (dir, path) = pendulum_results();
    let out = dir.path().join("vtk");
    let o = samara(&[
        "vtk",
        path.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let pvd = std::fs::read_to_string(out.join("swing.pvd")).unwrap();
    assert_eq!(pvd.matches("<DataSet ").count(), 501);
    // Last time: the bob (point 0) and the pivot (point 1).
    let vtk = vtkio::Vtk::import(out.join("swing_000500.vtu")).expect("a valid .vtu");
    let DataSet::UnstructuredGrid { pieces, .. } = vtk.data else {
        panic!("not an unstructured grid")
    };
    let Piece::Inline(piece) = &pieces[0] else {
        panic!("piece not inline")
    };
    let IOBuffer::F64(points) = &piece.points else {
        panic!("points not f64")
    };
    // The bob's node, the pivot, the bob's CG (no offset: on the node), then the 8
    // corners of the bob's equivalent box.
    assert_eq!(points.len(), 3 * 11);
    let mut rd = FileReader::open(&path).unwrap();
    let x = rd.read_var_f64("position").unwrap();
    for i in 0..3 {
        assert!((points[i] - x[3 * 500 + i]).abs() < 1e-12);
        assert!(points[3 + i].abs() < 1e-9, "pivot at the origin");
        assert!(
            (points[6 + i] - x[3 * 500 + i]).abs() < 1e-12,
            "CG on the node"
        );
    }
    let names: Vec<&str> = piece
        .data
        .point
        .iter()
        .map(|a| match a {
            Attribute::DataArray(d) => d.name.as_str(),
            Attribute::Field { name, .. } => name.as_str(),
        })
        .collect();
    for want in [
        "kind",
        "frame_x",
        "frame_y",
        "frame_z",
        "velocity",
        "joint_force",
        "joint_moment",
    ] {
        assert!(names.contains(&want), "{want} missing: {names:?}");
    }
    // The joint force in global components has the magnitude of the stored frame-A one.
    let f = rd.read_var_f64("joint_force").unwrap();
    let stored = (f[1500].powi(2) + f[1501].powi(2) + f[1502].powi(2)).sqrt();
    let Attribute::DataArray(jf) = piece
        .data
        .point
        .iter()
        .find(|a| matches!(a, Attribute::DataArray(d) if d.name == "joint_force"))
        .unwrap()
    else {
        unreachable!()
    };
    let IOBuffer::F64(g) = &jf.data else { panic!() };
    let global = (g[3].powi(2) + g[4].powi(2) + g[5].powi(2)).sqrt();
    assert!((stored - global).abs() < 1e-9 * stored.max(1.0));
}

#[test]
fn plot_writes_png_and_svg_and_suggests_channel_names() {
    let (dir, path) = pendulum_results();
    let png = dir.path().join("swing.png");
    let o = samara(&[
        "plot",
        path.to_str().unwrap(),
        "position:bob:z",
        "joint_force:pivot:y",
        "kinetic_energy",
        "--out",
        png.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let bytes = std::fs::read(&png).unwrap();
    assert!(bytes.starts_with(b"\x89PNG\r\n\x1a\n") && bytes.len() > 20_000);
    let svg = dir.path().join("swing.svg");
    let o = samara(&[
        "plot",
        path.to_str().unwrap(),
        "orientation:bob:w",
        "--out",
        svg.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(
        text.starts_with("<svg") && text.contains("time [s]") && text.contains("orientation:bob:w")
    );
    // Unknown channels: a clear error with the closest name.
    let o = samara(&["plot", path.to_str().unwrap(), "position:bobb:z"]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(
        e.contains("unknown channel") && e.contains("did you mean 'position:bob:z'"),
        "{e}"
    );
    let o = samara(&["plot", path.to_str().unwrap(), "kinetic_enrgy"]);
    assert!(
        stderr(&o).contains("did you mean 'kinetic_energy'"),
        "{}",
        stderr(&o)
    );
    let o = samara(&["plot", path.to_str().unwrap(), "position:bob:q"]);
    assert!(stderr(&o).contains("component 'q'"), "{}", stderr(&o));
    let o = samara(&[
        "plot",
        path.to_str().unwrap(),
        "kinetic_energy",
        "--out",
        "figure.pdf",
    ]);
    assert!(stderr(&o).contains(".png or .svg"), "{}", stderr(&o));
}

/// A beam left without mass (no `density`, no `mass`) is fine for statics, but a dynamic
/// analysis of it stops at once: `samara check` warns, at the beam.
#[test]
fn a_massless_beam_in_a_dynamic_analysis_is_flagged() {
    let text = r#"[model]
name = "massless"

[[beams]]
name = "b"
order = 2
points = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]

[[beams.sections]]
station = 0.0
isotropic = { E = 2e11, G = 8e10, A = 1e-4, I2 = 1e-9, I3 = 1e-9, J = 2e-9, shear_factors = [0.83, 0.83] }

[[joints]]
name = "clamp"
type = "fixed"
node_a = "ground"
node_b = "b.0"

[[analyses]]
name = "d"
type = "dynamic"
t_end = 0.01
step = 1e-3
"#;
    let (o, path, _dir) = check_text("massless.toml", text);
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    let line = format!("{}:5:8: warning: beam 'b' has no mass", path.display());
    assert!(err.contains(&line), "{err}");
    assert!(err.contains("density"));
    // The same beam in statics is not flagged.
    let (o, _, _dir) = check_text(
        "static.toml",
        &text.replace(
            "type = \"dynamic\"\nt_end = 0.01\nstep = 1e-3",
            "type = \"static\"",
        ),
    );
    assert!(!stderr(&o).contains("no mass"), "{}", stderr(&o));
}

/// Element states, signals and element outputs, end to end through `samara run` and the
/// results file (examples/active_suspension.toml): the Maxwell mount's tension output
/// equals k (l − l₀ − z) from its length output and its state; its length equals the
/// body's height (the mount hangs from the origin); the skyhook signal equals the sensor's
/// state; and the channels carry their units.
#[test]
fn element_states_signals_and_outputs_reach_the_results_file() {
    let dir = tempfile::tempdir().unwrap();
    let model = root().join("examples/active_suspension.toml");
    let o = samara(&[
        "run",
        model.to_str().unwrap(),
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut r = samara::output::ResultsReader::open(dir.path().join("settle.nc")).unwrap();
    let tension = r.channel("element_output:mount.tension").unwrap();
    let length = r.channel("element_output:mount.length").unwrap();
    let stretch = r.channel("element_state:mount.damper_stretch").unwrap();
    let height = r.channel("position:body:z").unwrap();
    let filtered = r.channel("element_state:skyhook.output").unwrap();
    let signal = r.channel("signal:skyhook").unwrap();
    assert_eq!((tension.units.as_str(), length.units.as_str()), ("N", "m"));
    let (k, l0) = (8000.0, 0.5);
    for i in 0..tension.values.len() {
        let expected = k * (length.values[i] - l0 - stretch.values[i]);
        assert!(
            (tension.values[i] - expected).abs() < 1e-9 * k,
            "record {i}"
        );
        assert!((length.values[i] - height.values[i]).abs() < 1e-12);
        assert!((signal.values[i] - filtered.values[i]).abs() < 1e-12);
    }
    // Settled on the coil spring (the mount relaxed): tension → 0, sag m g / k_coil.
    let last = tension.values.len() - 1;
    assert!(tension.values[last].abs() < 5.0, "{}", tension.values[last]);
    assert!((height.values[last] - (0.5 - 250.0 * 9.81 / 16000.0)).abs() < 1e-3);
}

/// Two models in one folder with the same analysis name: by default each gets its own
/// results folder `out/<model file stem>/`, so neither file is moved aside (issue #13).
#[test]
fn two_models_of_one_folder_never_share_results() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a.toml");
    let b = dir.path().join("b.toml");
    std::fs::write(&a, PENDULUM).unwrap();
    // A different model: a longer pendulum (same analysis name `swing`).
    let longer = PENDULUM.replacen(
        "position = [1.0, 0.0, 0.0]",
        "position = [2.0, 0.0, 0.0]",
        1,
    );
    assert_ne!(longer, PENDULUM);
    std::fs::write(&b, &longer).unwrap();
    for m in [&a, &b] {
        let o = samara(&["run", m.to_str().unwrap(), "-q"]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let out = dir.path().join("out");
    let mut files: Vec<String> = walk(&out);
    files.sort();
    assert_eq!(files, ["a/swing.nc", "b/swing.nc"], "{files:?}");
    let mut ra = FileReader::open(out.join("a/swing.nc")).unwrap();
    let mut rb = FileReader::open(out.join("b/swing.nc")).unwrap();
    let xa = ra.read_var_f64("reference_position").unwrap();
    let xb = rb.read_var_f64("reference_position").unwrap();
    assert_ne!(xa, xb, "each folder holds its own model's results");
    // `samara sweep` defaults to out/<model file stem>/sweep/.
    let grid = dir.path().join("grid.toml");
    std::fs::write(&grid, "[grid]\n\"analyses.swing.t_end\" = [0.01]\n").unwrap();
    let o = samara(&[
        "sweep",
        a.to_str().unwrap(),
        "--grid",
        grid.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.join("a/sweep/index.csv").exists());
}

/// Files under `dir`, relative, with `/` separators.
fn walk(dir: &Path) -> Vec<String> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            let name = p.file_name().unwrap().to_string_lossy().to_string();
            out.extend(walk(&p).into_iter().map(|f| format!("{name}/{f}")));
        } else {
            out.push(p.file_name().unwrap().to_string_lossy().to_string());
        }
    }
    out
}

/// A granular run reports what its Newton line search and contact handling did: the
/// halved corrections per step (`line_search_backtracks`, with `diagnostics = true`), and
/// in the file's attributes, the run summary and `samara info` the totals with the steps
/// redone for new contacts and the contact-pattern rebuilds. The 27-sphere column of
/// examples/contact/granular_column.toml over its first 0.25 s (the pile compacting) needs
/// the line search; the per-step values must add up to the total.
#[test]
fn granular_runs_report_line_search_and_contact_counts() {
    let text =
        std::fs::read_to_string(root().join("examples/contact/granular_column.toml")).unwrap();
    assert!(text.contains("t_end = 3.0\n") && text.contains("output_every = 10\n"));
    let text = text
        .replace("t_end = 3.0\n", "t_end = 0.25\ndiagnostics = true\n")
        .replace("output_every = 10\n", "output_every = 1\n");
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("column.toml");
    std::fs::write(&model, text).unwrap();
    let out = dir.path().join("out");
    let o = samara(&[
        "run",
        model.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let path = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.extension().is_some_and(|x| x == "nc"))
        .unwrap();
    let mut r = samara::output::ResultsReader::open(&path).unwrap();
    let total = r.attr_i64("line_search_backtracks").unwrap();
    let per_step: f64 = r.read("line_search_backtracks").unwrap().iter().sum();
    let (redos, rebuilds) = (
        r.attr_i64("contact_redos").unwrap(),
        r.attr_i64("pattern_rebuilds").unwrap(),
    );
    println!("backtracks {total}, redos {redos}, rebuilds {rebuilds}");
    assert!(total > 0, "the compacting pile needed no line search");
    assert_eq!(per_step, total as f64);
    assert!(rebuilds > 0);
    let line = format!(
        "line search halved {total} corrections; {redos} steps redone for new contacts; contact pattern rebuilt {rebuilds} times"
    );
    let s = String::from_utf8_lossy(&o.stdout);
    assert!(s.contains(&line), "'{line}' missing from:\n{s}");
    let o = samara(&["info", path.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = String::from_utf8_lossy(&o.stdout);
    let line = format!(
        "line search halved {total} corrections, {redos} steps redone for new contacts, pattern rebuilt {rebuilds} times"
    );
    assert!(s.contains(&line), "'{line}' missing from:\n{s}");
}

/// The landing-gear drop from the command line (issue #16): `samara run` on
/// `examples/landing_gear_drop.toml` shortened to its touchdown and spin-up (0.25 s)
/// writes the strut's gas pressure (an element state), the tire's forces (element
/// outputs) and the brake controller's signal; the pressure is the library's run of the
/// same model record for record (1e-12 relative: the same computation), the gear touches
/// down (tire load above the aircraft's weight share, m g = 19.6 kN, at the impact) and
/// the strut's gas is compressed above its initial pressure.
#[test]
fn landing_gear_drop_runs_from_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(root().join("examples/landing_gear_drop.toml")).unwrap();
    let short = text.replace("t_end = 3.4", "t_end = 0.25");
    assert_ne!(short, text);
    let file = dir.path().join("landing_gear_drop.toml");
    std::fs::write(&file, &short).unwrap();
    let out = dir.path().join("out");
    let o = samara(&[
        "run",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut r = samara::output::ResultsReader::open(out.join("drop_and_retract.nc")).unwrap();
    let pressure = r
        .channel("element_state:shock_strut.upper.pressure")
        .unwrap();
    let load = r.channel("element_output:tire.normal_force").unwrap();
    let brake = r.channel("signal:brake_torque").unwrap();
    assert_eq!(load.units, "N");
    // The library's run of the same file.
    let m = samara::model::Model::from_toml_str(&short, &file)
        .unwrap()
        .model;
    let sys = samara::system::System::new(&m);
    let mut h = samara::analysis::History::default();
    let s = samara::analysis::run_analysis(
        &sys,
        &m.analyses[0],
        sys.initial_state(),
        &mut h,
        &mut |_| {},
    )
    .unwrap();
    assert!(s.failure.is_none(), "{:?}", s.failure);
    let k = sys
        .state_names
        .iter()
        .position(|n| n == "shock_strut.upper.pressure")
        .unwrap();
    assert_eq!(h.frames.len(), pressure.values.len());
    for (f, p) in h.frames.iter().zip(&pressure.values) {
        let z = f.state.states[k].z;
        assert!(
            (z - p).abs() <= 1e-12 * z.abs(),
            "t = {}: {z} vs {p}",
            f.time
        );
    }
    let peak = load.values.iter().fold(0.0f64, |a, &b| a.max(b));
    let p_max = pressure.values.iter().fold(0.0f64, |a, &b| a.max(b));
    println!(
        "peak tire load {peak:.0} N, peak gas pressure {p_max:.4e} Pa (initial {:.4e}), brake signal {} records",
        pressure.values[0],
        brake.values.len()
    );
    assert!(peak > 2000.0 * 9.81, "{peak}");
    assert!(p_max > 1.2 * pressure.values[0], "{p_max}");
    assert_eq!(brake.values.len(), pressure.values.len());
}

/// `partition = "two_parts"` from the command line: the summary says how the run shared
/// out its iteration; where no plan can be made (a granular set), a warning says why and
/// the run keeps one part.
#[test]
fn run_reports_two_parts_or_why_not() {
    let dir = tempfile::tempdir().unwrap();
    let chain = std::fs::read_to_string(root().join("examples/bench/chain_revolute_100.toml"))
        .unwrap()
        .replace("t_end = 1.0", "t_end = 0.005")
        .replace(
            "rho_inf = 0.9\n",
            "rho_inf = 0.9\npartition = \"two_parts\"\n",
        );
    let granular =
        std::fs::read_to_string(root().join("examples/contact/granular_column.toml")).unwrap();
    let at = granular
        .find("type = \"dynamic\"\n")
        .expect("a dynamic analysis");
    let mut granular = granular.replace("t_end = 3.0", "t_end = 0.002");
    granular.insert_str(at, "partition = \"two_parts\"\n");
    for (name, text) in [("chain", chain), ("granular", granular)] {
        let model = dir.path().join(format!("{name}.toml"));
        std::fs::write(&model, text).unwrap();
        let out = dir.path().join(name);
        let o = samara(&[
            "run",
            model.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        let (stdout, err) = (String::from_utf8_lossy(&o.stdout), stderr(&o));
        assert!(o.status.success(), "{name}: {err}");
        if name == "chain" {
            assert_eq!(stdout.matches("two parts: ").count(), 1, "{stdout}");
            assert!(stdout.contains("blocks, separator"), "{stdout}");
        } else {
            assert!(!stdout.contains("two parts: "), "{stdout}");
            assert!(
                err.contains("warning") && err.contains("granular") && err.contains("one part"),
                "{err}"
            );
        }
    }
}
