//! `type = "modal"` from the command line: the verification example's frequencies in the
//! results file, `write_matrices`, and the clear errors of bad modal input (issue #14).

use std::path::Path;

use crate::common;
use common::*;

fn run_text(text: &str) -> (std::process::Output, tempfile::TempDir) {
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
    (o, dir)
}

#[test]
fn cantilever_modal_example_frequencies_and_matrices() {
    let dir = tempfile::tempdir().unwrap();
    let model = root().join("examples/verification/cantilever_modal.toml");
    let o = samara(&[
        "run",
        model.to_str().unwrap(),
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut r = samara::output::ResultsReader::open(dir.path().join("modes.nc")).unwrap();
    let f = r.read("frequency").unwrap();
    // The references listed in the example (Timoshenko bending, exact torsion).
    let expected = [
        0.054686903688674,
        0.054686903688674,
        0.25,
        0.304222019453822,
        0.304222019453822,
        0.738746990880930,
        0.738746990880930,
        0.75,
    ];
    assert_eq!(f.len(), 8);
    for (a, b) in f.iter().zip(expected) {
        assert!((a - b).abs() / b < 1e-9, "{f:?}");
    }
    let zeta = r.read("damping_ratio").unwrap();
    assert!(zeta.iter().all(|z| z.abs() < 1e-9));
    let ev = r.read("eigenvalue").unwrap();
    assert_eq!(ev.len(), 16);
    assert!(
        (ev[5] - 2.0 * std::f64::consts::PI * 0.25).abs() < 1e-8,
        "{ev:?}"
    );
    // Mode shapes: largest component 1 + 0i; the torsion mode turns the tip about z.
    let shape = r.read("mode_shape").unwrap();
    let nodes = shape.len() / (8 * 12);
    assert_eq!(shape.len(), 8 * nodes * 12);
    let mode3 = &shape[2 * nodes * 12..3 * nodes * 12];
    let biggest = mode3
        .chunks(2)
        .map(|c| (c[0] * c[0] + c[1] * c[1]).sqrt())
        .fold(0.0, f64::max);
    assert!((biggest - 1.0).abs() < 1e-12);
    let names = r.channel_names();
    assert!(!names.is_empty());
    // The second analysis: the axial mode by shift, and the matrices.
    let mut a = samara::output::ResultsReader::open(dir.path().join("axial.nc")).unwrap();
    let fa = a.read("frequency").unwrap();
    assert!((fa[0] - 2.5).abs() < 1e-9, "{fa:?}");
    for tag in ["M", "G", "K", "B"] {
        let p = dir.path().join(format!("axial.{tag}.mtx"));
        let text = std::fs::read_to_string(&p).unwrap();
        let m = samara::linear::matrix_market::read(&text).unwrap();
        assert!(m.ncols() > 90, "{tag}");
        assert!(text.contains("tip.uz"), "unknown names in the header");
    }
    // Running again keeps the earlier matrices.
    let o = samara(&[
        "run",
        model.to_str().unwrap(),
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    assert!(o.status.success());
    assert!(Path::new(&dir.path().join("axial.K.~1~.mtx")).exists());
}

const SPRING_MASS: &str = r#"
[model]
name = "m"

[[nodes]]
name = "a"
position = [0.0, 0.0, 0.0]

[[bodies]]
name = "a"
node = "a"
mass = 2.0
inertia = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]

[[springs]]
name = "s"
node_a = "ground"
node_b = "a"
point_a = [-1.0, 0.0, 0.0]
stiffness = 50.0
damping = 2.0

[[analyses]]
name = "modes"
type = "modal"
n_modes = 6
"#;

/// `n_modes` above the degrees of freedom is a model error located at the key, from
/// `samara run` (nothing runs) and from `samara check`.
#[test]
fn too_many_modes_is_a_located_error() {
    let text = SPRING_MASS.replace("n_modes = 6", "n_modes = 7");
    let line = text[..text.find("n_modes = 7").unwrap()]
        .matches('\n')
        .count()
        + 1;
    let (o, _d) = run_text(&text);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(
        e.contains("`n_modes` = 7 is more than the model's 6 degrees of freedom"),
        "{e}"
    );
    assert!(e.contains("nothing was run"), "{e}");
    let (o, path, _d) = check_text("m.toml", &text);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains(&format!("{}:{line}:", path.display())), "{e}");
    assert!(e.contains("at most n_modes = 6"), "{e}");
}

#[test]
fn a_model_without_mass_is_a_located_error() {
    let text = r#"
[model]
name = "massless"

[[beams]]
name = "beam"
order = 2
elements = 1
points = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]
root = "root"
tip = "tip"

[[beams.sections]]
station = 0.0
isotropic = { E = 7e10, G = 2.7e10, A = 4e-3, I2 = 5e-7, I3 = 2e-5, J = 1.5e-6, shear_factors = [0.83, 0.83] }

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
    let (o, _d) = run_text(text);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains("no mass") && e.contains("density"), "{e}");
    let line = text[..text.find("name = \"modes\"").unwrap()]
        .matches('\n')
        .count()
        + 1;
    assert!(e.contains(&format!(":{line}:")), "{e}");
}

#[test]
fn modal_keys_are_checked_and_located() {
    let (o, path, _d) = check_text("m.toml", &SPRING_MASS.replace("n_modes = 6", "n_modes = 0"));
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(
        e.contains(&format!("{}:", path.display())) && e.contains("`n_modes` must be at least 1"),
        "{e}"
    );
    let (o, _, _d) = check_text(
        "m.toml",
        &SPRING_MASS.replace("n_modes = 6", "shift = -1.0"),
    );
    assert!(
        stderr(&o).contains("`shift` must be a frequency"),
        "{}",
        stderr(&o)
    );
    let (o, _, _d) = check_text(
        "m.toml",
        &SPRING_MASS.replace("n_modes = 6", "tolerance = 1e-6"),
    );
    assert!(
        stderr(&o).contains("`tolerance` is not used by a modal analysis"),
        "{}",
        stderr(&o)
    );
    let (o, _, _d) = check_text(
        "m.toml",
        &PENDULUM.replace("[[analyses]]", "[[analyses]]\nn_modes = 3"),
    );
    assert!(
        stderr(&o).contains("`n_modes` is not used by a dynamic analysis"),
        "{}",
        stderr(&o)
    );
    let (o, _, _d) = check_text(
        "m.toml",
        &SPRING_MASS.replace("n_modes = 6", "eigensolver = \"lanczos\""),
    );
    assert_eq!(o.status.code(), Some(1));
}

#[test]
fn spring_mass_frequency_damping_and_eigensolver_choice() {
    // A free 2 kg body held along x by a spring-damper (k = 50 N/m, c = 2 N s/m, unstressed,
    // so no transverse stiffness): five rigid-body modes, then f = √(k/m)/2π with
    // ζ = c/(2√(km)) = 0.1 and f_d = f√(1 − ζ²).
    for solver in ["dense", "sparse"] {
        let (o, d) = run_text(&SPRING_MASS.replace(
            "n_modes = 6",
            &format!("n_modes = 6\neigensolver = \"{solver}\""),
        ));
        assert!(o.status.success(), "{}", stderr(&o));
        let mut r = samara::output::ResultsReader::open(d.path().join("out/modes.nc")).unwrap();
        let f = r.read("frequency").unwrap();
        let fd = r.read("damped_frequency").unwrap();
        let z = r.read("damping_ratio").unwrap();
        let exact = (50.0f64 / 2.0).sqrt() / (2.0 * std::f64::consts::PI);
        assert_eq!(&f[..5], &[0.0; 5], "{solver}: {f:?}");
        assert!((f[5] - exact).abs() / exact < 1e-10, "{solver}: {f:?}");
        assert!((z[5] - 0.1).abs() < 1e-10, "{solver}: {z:?}");
        assert!(
            (fd[5] - exact * 0.99f64.sqrt()).abs() / exact < 1e-10,
            "{solver}: {fd:?}"
        );
    }
}

const ROTOR: &str = r#"
[model]
name = "stodola_green"

[[beams]]
name = "shaft"
order = 4
elements = 1
points = [[0.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
root = "root"
tip = "disk"

[[beams.sections]]
station = 0.0
stiffness = [
  [1e9, 0.0, 0.0, 0.0, 0.0, 0.0],
  [0.0, 1e9, 0.0, 0.0, 0.0, 0.0],
  [0.0, 0.0, 1e9, 0.0, 0.0, 0.0],
  [0.0, 0.0, 0.0, 1e6, 0.0, 0.0],
  [0.0, 0.0, 0.0, 0.0, 2e3, 0.0],
  [0.0, 0.0, 0.0, 0.0, 0.0, 2e3],
]

[[bodies]]
name = "disk"
node = "disk"
mass = 5.0
inertia = [[0.4, 0.0, 0.0], [0.0, 0.25, 0.0], [0.0, 0.0, 0.25]]

[[joints]]
name = "clamp"
type = "fixed"
node_a = "ground"
node_b = "root"

[[analyses]]
name = "modes"
type = "modal"
n_modes = 4
rotation = { axis = [0.0, 0.0, 2.0], omega = 20.0, centre = [0.0, 0.0, 0.0] }
"#;

#[test]
fn spinning_rotor_modal_with_rotation() {
    // Disk on a massless shaft spinning at 20 rad/s (tests/modal.rs has the closed form):
    // rotating-frame whirl frequencies |ω − Ω| = 14.50028, 51.06759, 184.1000, 195.5327 rad/s
    // (Euler–Bernoulli shaft; the model's shear stiffness shifts them by 1e-5).
    let (o, d) = run_text(ROTOR);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut r = samara::output::ResultsReader::open(d.path().join("out/modes.nc")).unwrap();
    let f = r.read("frequency").unwrap();
    let expected = [
        14.500282178966444,
        51.06758981037455,
        184.0999990817167,
        195.53269145030862,
    ];
    for (a, b) in f.iter().zip(expected) {
        let w = a * 2.0 * std::f64::consts::PI;
        assert!((w - b).abs() / b < 2e-5, "{f:?}");
    }
    // Without the rotation the spin is absent: the two planes give equal frequencies.
    let (o, d) = run_text(&ROTOR.replace(
        "rotation = { axis = [0.0, 0.0, 2.0], omega = 20.0, centre = [0.0, 0.0, 0.0] }\n",
        "",
    ));
    assert!(o.status.success(), "{}", stderr(&o));
    let mut r = samara::output::ResultsReader::open(d.path().join("out/modes.nc")).unwrap();
    let g = r.read("frequency").unwrap();
    assert!((g[0] - g[1]).abs() < 1e-6 * g[0], "{g:?}");
    // A zero axis is a located error.
    let (o, path, _d) = check_text(
        "r.toml",
        &ROTOR.replace("axis = [0.0, 0.0, 2.0]", "axis = [0.0, 0.0, 0.0]"),
    );
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(
        e.contains(&format!("{}:", path.display())) && e.contains("non-zero vector"),
        "{e}"
    );
    // `rotation` belongs to modal analyses here.
    let (o, _, _d) = check_text(
        "r.toml",
        &PENDULUM.replace(
            "[[analyses]]",
            "[[analyses]]\nrotation = { axis = [0.0, 0.0, 1.0], omega = 1.0 }",
        ),
    );
    assert!(
        stderr(&o).contains("`rotation` is not used by a dynamic analysis"),
        "{}",
        stderr(&o)
    );
}
