//! Reading OpenFAST BeamDyn blade files (issue #15): the NREL 5-MW blade read from its
//! BeamDyn files (reference/nrel5mw/structure/) against an Euler–Bernoulli
//! quadrature of the ElastoDyn blade file of the same turbine (flap and edge stiffness,
//! mass, structural twist; a different file, written for a different code), hand-written
//! BeamDyn-ordered matrices (`ordering = "beamdyn"`) against closed forms, and located
//! errors for malformed files.

use crate::common;

use common::run;
use nalgebra::{Matrix2, Vector2, Vector3};
use samara::model::Model;
use std::path::{Path, PathBuf};

fn structure() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../reference/nrel5mw/structure")
}

fn primary() -> PathBuf {
    structure().join("NRELOffshrBsline5MW_BeamDyn.dat")
}

/// The ElastoDyn blade table: (η, structural twist [deg], mass [kg/m], EI flap, EI edge).
fn elastodyn_blade() -> Vec<[f64; 5]> {
    let text = std::fs::read_to_string(structure().join("NRELOffshrBsline5MW_Blade.dat")).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let start = lines.iter().position(|l| l.contains("NBlInpSt")).unwrap();
    let n: usize = lines[start]
        .split_whitespace()
        .next()
        .unwrap()
        .parse()
        .unwrap();
    let table = lines.iter().position(|l| l.contains("BlFract")).unwrap() + 2;
    lines[table..table + n]
        .iter()
        .map(|l| {
            let v: Vec<f64> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
            [v[0], v[2], v[3], v[4], v[5]]
        })
        .collect()
}

/// Shear stiffness (x, y) per BeamDyn station (η, K11, K22): the ElastoDyn file has none.
fn beamdyn_shear() -> Vec<[f64; 3]> {
    let b = samara::model::beamdyn_files::read_beamdyn(&primary()).unwrap();
    b.stations
        .iter()
        .map(|(eta, k, _)| [*eta, k[(0, 0)], k[(1, 1)]])
        .collect()
}

/// Piecewise-linear interpolation of column `c` of a table with η in column 0.
fn lerp<const N: usize>(t: &[[f64; N]], eta: f64, c: usize) -> f64 {
    let k = t.partition_point(|r| r[0] <= eta).clamp(1, t.len() - 1);
    let (a, b) = (&t[k - 1], &t[k]);
    let s = (eta - a[0]) / (b[0] - a[0]);
    a[c] + s * (b[c] - a[c])
}

/// Linear tip displacement (x, y) in BeamDyn's blade frame of the clamped blade (length
/// L along z) under a moment distribution M(z) = ∫ (moment arm) of a load along x:
/// `moment(z)` gives the bending moment about y [N m] and `shear(z)` the shear force
/// along x. Euler–Bernoulli with twisted principal axes (BeamDyn's sense: the section
/// frame turned by −θ about z, θ = StrcTwst), plus shear compliance:
/// u_tip = ∫ (L − z) κ × e_z dz + ∫ γ dz, κ = C⁻¹ M, γ = S⁻¹ V.
fn quadrature_tip(moment: &dyn Fn(f64) -> f64, shear: &dyn Fn(f64) -> f64) -> Vector2<f64> {
    let (ed, sh) = (elastodyn_blade(), beamdyn_shear());
    let l = 61.5;
    let n = 200_000;
    let mut u = Vector2::zeros();
    for k in 0..n {
        // Midpoint rule on a fine grid: error O((L/n)²) ≪ 1e-8 relative.
        let z = (k as f64 + 0.5) * l / n as f64;
        let eta = z / l;
        let th = -lerp(&ed, eta, 1).to_radians();
        let r = Matrix2::new(th.cos(), -th.sin(), th.sin(), th.cos());
        // Moment about x' resisted by K44 = EdgStff, about y' by K55 = FlpStff.
        let c = r * Matrix2::new(lerp(&ed, eta, 4), 0.0, 0.0, lerp(&ed, eta, 3)) * r.transpose();
        let s = r * Matrix2::new(lerp(&sh, eta, 1), 0.0, 0.0, lerp(&sh, eta, 2)) * r.transpose();
        let kappa = c.try_inverse().unwrap() * Vector2::new(0.0, moment(z));
        let gamma = s.try_inverse().unwrap() * Vector2::new(shear(z), 0.0);
        let dz = l / n as f64;
        u += ((l - z) * Vector2::new(kappa.y, -kappa.x) + gamma) * dz;
    }
    u
}

/// The 5-MW blade read from its BeamDyn files, clamped at the origin, BeamDyn's axes the
/// global ones; `extra` is appended (loads, gravity).
fn blade_model(order: usize, elements: usize, header: &str, extra: &str) -> Model {
    let text = format!(
        r#"[model]
name = "nrel5mw_blade"
{header}
[[beams]]
name = "blade"
beamdyn = "{}"
order = {order}
elements = {elements}
root = "root"
tip = "tip"
[[joints]]
name = "clamp"
type = "fixed"
node_a = "ground"
node_b = "root"
{extra}
[[analyses]]
name = "load"
type = "static"
load_steps = 1
tolerance = 1e-12
"#,
        primary().display()
    );
    match Model::from_toml_str(&text, "blade.toml") {
        Ok(l) => l.model,
        Err(e) => panic!("{}", e.render_plain()),
    }
}

fn tip_displacement(m: &Model) -> Vector3<f64> {
    let (_, h) = run(m);
    let i = m.node_index("tip").unwrap();
    h.last().unwrap().state.nodes[i].x - m.nodes[i].position
}

#[test]
fn beamdyn_blade_is_read_in_samaras_conventions() {
    let m = blade_model(6, 8, "", "");
    let b = &m.beams[0];
    assert_eq!((b.order, b.n_elements), (6, 8));
    assert_eq!(
        b.quadrature,
        samara::elements::beam::element::Quadrature::Full
    );
    // Tip at 61.5 m along z; 49 stations; BeamDyn's (1,1) shear becomes samara's (2,2),
    // its axial (3,3) samara's (1,1), its torsion (6,6) samara's (4,4).
    let tip = m.node_index("tip").unwrap();
    assert!((m.nodes[tip].position - Vector3::new(0.0, 0.0, 61.5)).norm() < 1e-9);
    let s0 = b.table.at(0.0);
    assert_eq!(s0.stiffness[(0, 0)], 9.729480e9);
    assert_eq!(s0.stiffness[(1, 1)], 9.729480e8);
    assert_eq!(s0.stiffness[(3, 3)], 5.564400e9);
    assert_eq!(s0.stiffness[(4, 4)], 1.811360e10);
    assert_eq!(s0.stiffness[(5, 5)], 1.811000e10);
    assert_eq!(s0.mass[(3, 3)], 1.945900e3);
    // μ re-ordered: (axial, shear, shear, torsion, bending, bending).
    assert_eq!(b.damping, [1e-3, 1e-3, 1e-3, 0.0022, 0.0014, 0.0022]);
    // The root section frame: x along the blade (z), y = BeamDyn's x turned by −13.308°
    // about the blade axis (BeamDyn's sense of initial twist).
    let r = m.nodes[m.node_index("root").unwrap()].orientation.matrix();
    let th = -13.308f64.to_radians();
    let y = Vector3::new(th.cos(), th.sin(), 0.0);
    assert!((r.column(0) - Vector3::z()).norm() < 1e-12);
    assert!((r.column(1) - y).norm() < 1e-9, "{r}");
}

#[test]
fn nrel5mw_blade_from_beamdyn_files_deflects_as_the_elastodyn_data_predict() {
    let l = 61.5;
    // 1. A flapwise tip force (BeamDyn x): small enough that the response is linear
    //    (tip deflection ~1e-4 L: geometric terms ~1e-8).
    let p = 200.0;
    let reference = quadrature_tip(&|z| p * (l - z), &|_| p);
    let mut errs = Vec::new();
    for ne in [4, 8, 16] {
        let m = blade_model(
            6,
            ne,
            "",
            &format!("[[forces]]\nname = \"tip load\"\nnode = \"tip\"\nforce = [{p}, 0.0, 0.0]\n"),
        );
        let u = tip_displacement(&m);
        let e = (Vector2::new(u.x, u.y) - reference).norm() / reference.norm();
        println!(
            "tip force, {ne} elements of order 6: u = ({:.6e}, {:.6e}) vs ({:.6e}, {:.6e}): {e:.2e}",
            u.x, u.y, reference.x, reference.y
        );
        errs.push(e);
    }
    // The stiffness is piecewise linear between 49 stations (kinks): the Gauss rule's error
    // falls as the elements shrink. The edgewise component (twist coupling) is ~1/20 of
    // the flapwise one; its sign checks the sense of the twist.
    assert!(errs[2] < 2e-3, "{errs:?}");
    assert!(errs[2] < errs[0], "{errs:?}");
    // 2. Gravity along BeamDyn x: the moment of the distributed mass (ElastoDyn BMassDen,
    //    without AdjBlMs: BeamDyn's mass is the table's own) checks the mass matrices.
    let g = 0.01;
    let ed = elastodyn_blade();
    let mass_moment = |z: f64| {
        let n = 4000;
        let h = (l - z) / n as f64;
        (0..n)
            .map(|k| {
                let s = z + (k as f64 + 0.5) * h;
                g * lerp(&ed, s / l, 2) * (s - z) * h
            })
            .sum::<f64>()
    };
    let shear_force = |z: f64| {
        let n = 4000;
        let h = (l - z) / n as f64;
        (0..n)
            .map(|k| g * lerp(&ed, (z + (k as f64 + 0.5) * h) / l, 2) * h)
            .sum::<f64>()
    };
    // A coarser outer grid suffices for this smooth integrand (checked: 1e-6 relative).
    let reference = {
        let n = 4000;
        let mut u = Vector2::zeros();
        let sh = beamdyn_shear();
        for k in 0..n {
            let z = (k as f64 + 0.5) * l / n as f64;
            let eta = z / l;
            let th = -lerp(&ed, eta, 1).to_radians();
            let r = Matrix2::new(th.cos(), -th.sin(), th.sin(), th.cos());
            let c =
                r * Matrix2::new(lerp(&ed, eta, 4), 0.0, 0.0, lerp(&ed, eta, 3)) * r.transpose();
            let s =
                r * Matrix2::new(lerp(&sh, eta, 1), 0.0, 0.0, lerp(&sh, eta, 2)) * r.transpose();
            let kappa = c.try_inverse().unwrap() * Vector2::new(0.0, mass_moment(z));
            let gamma = s.try_inverse().unwrap() * Vector2::new(shear_force(z), 0.0);
            u += ((l - z) * Vector2::new(kappa.y, -kappa.x) + gamma) * (l / n as f64);
        }
        u
    };
    let m = blade_model(6, 16, &format!("gravity = [{g}, 0.0, 0.0]"), "");
    let u = tip_displacement(&m);
    let e = (Vector2::new(u.x, u.y) - reference).norm() / reference.norm();
    println!(
        "gravity: u = ({:.6e}, {:.6e}) vs ({:.6e}, {:.6e}): {e:.2e}",
        u.x, u.y, reference.x, reference.y
    );
    assert!(e < 3e-3, "{e}");
}

/// A uniform cantilever of length 2 along global x with a BeamDyn-ordered section
/// (shear x, shear y, axial, bending x, bending y, torsion) and a tip moment `m`.
fn hand_written(ordering: &str, moment: [f64; 3]) -> Model {
    let text = format!(
        r#"[model]
name = "ordering"
[[beams]]
name = "b"
order = 2
points = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0]]
root = "root"
tip = "tip"
[[beams.sections]]
station = 0.0
{ordering}
stiffness = [[1e4, 0, 0, 0, 0, 0], [0, 2e4, 0, 0, 0, 0], [0, 0, 1e6, 0, 0, 0], [0, 0, 0, 100, 0, 0], [0, 0, 0, 0, 300, 0], [0, 0, 0, 0, 0, 50]]
mass = [[1, 0, 0, 0, 0, 0], [0, 1, 0, 0, 0, 0], [0, 0, 1, 0, 0, 0], [0, 0, 0, 0.1, 0, 0], [0, 0, 0, 0, 0.2, 0], [0, 0, 0, 0, 0, 0.3]]
[[joints]]
name = "clamp"
type = "fixed"
node_a = "ground"
node_b = "root"
[[forces]]
name = "m"
node = "tip"
moment = [{}, {}, {}]
[[analyses]]
name = "load"
type = "static"
load_steps = 1
tolerance = 1e-12
"#,
        moment[0], moment[1], moment[2]
    );
    match Model::from_toml_str(&text, "ordering.toml") {
        Ok(l) => l.model,
        Err(e) => panic!("{}", e.render_plain()),
    }
}

#[test]
fn beamdyn_ordered_matrices_are_converted() {
    // A small tip moment M about one section axis rotates the tip by M L / K (linear
    // bending or torsion of a uniform beam, rotation 1e-3: geometric terms ~1e-6 relative;
    // tolerance 1e-5 relative).
    // With ordering = "beamdyn" the torsion stiffness is the file's (6,6) = 50, bending
    // about section y is its (4,4) = 100 and about section z its (5,5) = 300.
    let tip_rotation = |m: &Model| {
        let (_, h) = run(m);
        let i = m.node_index("tip").unwrap();
        let n = &h.last().unwrap().state.nodes[i];
        samara::math::log_map(&(n.rot.quaternion() * m.nodes[i].orientation.quaternion().inverse()))
    };
    let l = 2.0;
    for (axis, k) in [(0, 50.0), (1, 100.0), (2, 300.0)] {
        let mut mo = [0.0; 3];
        mo[axis] = 0.025;
        let th = tip_rotation(&hand_written("ordering = \"beamdyn\"", mo));
        let exact = 0.025 * l / k;
        println!(
            "moment about {axis}: rotation {:.12} vs {exact:.12}",
            th[axis]
        );
        assert!((th[axis] / exact - 1.0).abs() < 1e-5, "{th:?}");
    }
    // The same numbers read in samara's own ordering give a different beam (torsion
    // stiffness 100, not 50): the option changes the result.
    let th = tip_rotation(&hand_written("", [0.025, 0.0, 0.0]));
    assert!((th[0] / (0.025 * l / 100.0) - 1.0).abs() < 1e-5, "{th:?}");
}

/// An edit of the (primary, blade) file texts.
type Edit = dyn Fn(&mut String, &mut String);

/// A copy of the 5-MW BeamDyn files in `dir`, with `edit` applied to (primary, blade).
fn broken_copy(dir: &Path, edit: &Edit) -> PathBuf {
    let mut p = std::fs::read_to_string(primary()).unwrap();
    let mut b =
        std::fs::read_to_string(structure().join("NRELOffshrBsline5MW_BeamDyn_Blade.dat")).unwrap();
    edit(&mut p, &mut b);
    std::fs::write(dir.join("NRELOffshrBsline5MW_BeamDyn_Blade.dat"), b).unwrap();
    let path = dir.join("bd.dat");
    std::fs::write(&path, p).unwrap();
    path
}

fn model_error(dir: &Path, beam: &str) -> String {
    let text = format!(
        "[model]\nname = \"bad\"\n[[beams]]\nname = \"blade\"\n{beam}\n[[joints]]\nname = \"clamp\"\ntype = \"fixed\"\nnode_a = \"ground\"\nnode_b = \"blade.0\"\n"
    );
    match Model::from_toml_str(&text, dir.join("bad.toml")) {
        Ok(_) => panic!("accepted: {beam}"),
        Err(e) => e.render_plain(),
    }
}

#[test]
fn malformed_beamdyn_files_are_located_errors() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // Each error names the model's `beamdyn` line, the file, its line and what was expected.
    let cases: Vec<(Box<Edit>, &str, &str)> = vec![
        (
            Box::new(|p: &mut String, _: &mut String| {
                *p = p.replacen(
                    "0.0000000E+00  0.0000000E+00  1.9987500E-01",
                    "0.0 0.0 x",
                    1,
                )
            }),
            "bd.dat', line 26: expected 4 numbers",
            "key point row",
        ),
        (
            Box::new(|p: &mut String, _: &mut String| {
                *p = p.replacen("5   order_elem", "99   order_elem", 1)
            }),
            "`order_elem` must be an integer in 1…",
            "order",
        ),
        (
            Box::new(|_: &mut String, b: &mut String| *b = b.replacen("9.729480E+08", "oops", 1)),
            "_Blade.dat', line 12: expected the numbers of a station",
            "blade number",
        ),
        (
            Box::new(|_: &mut String, b: &mut String| *b = b.replacen("0.003250", "0.5", 1)),
            "stations must rise strictly from 0 to 1",
            "station order",
        ),
        (
            Box::new(|_: &mut String, b: &mut String| {
                // An asymmetric stiffness: K12 ≠ K21 at the first station.
                *b = b.replacen(
                    "9.729480E+08    0.000000E+00    0.000000E+00",
                    "9.729480E+08    5.000000E+07    0.000000E+00",
                    1,
                )
            }),
            "_Blade.dat', line 12: station η = 0: ",
            "asymmetric stiffness",
        ),
        (
            Box::new(|_: &mut String, b: &mut String| {
                let cut = b.find("0.035770").unwrap();
                b.truncate(cut);
            }),
            "needs 49 stations of 73 numbers",
            "short file",
        ),
        (
            Box::new(|p: &mut String, _: &mut String| {
                *p = p.replace(
                    "\"NRELOffshrBsline5MW_BeamDyn_Blade.dat\"",
                    "\"missing.dat\"",
                )
            }),
            "cannot read the BeamDyn blade file",
            "missing blade file",
        ),
    ];
    for (edit, expected, what) in cases {
        let path = broken_copy(d, edit.as_ref());
        let e = model_error(d, &format!("beamdyn = \"{}\"", path.display()));
        println!("{what}: {e}");
        assert!(e.contains(expected), "{what}: {e}");
        assert!(
            e.contains("bad.toml:5:"),
            "{what}: located at the beamdyn key: {e}"
        );
    }
    // Conflicting keys and misplaced placement options.
    let ok = primary().display().to_string();
    let e = model_error(
        d,
        &format!("beamdyn = \"{ok}\"\npoints = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]"),
    );
    assert!(e.contains("do not give `points`"), "{e}");
    let e = model_error(
        d,
        &format!(
            "beamdyn = \"{ok}\"\nroot_axes = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 1.0, 0.0]]"
        ),
    );
    assert!(e.contains("orthonormal"), "{e}");
    let e = model_error(
        d,
        "order = 2\npoints = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]\nroot_position = [0.0, 0.0, 1.0]\n[[beams.sections]]\nstation = 0.0\nisotropic = { E = 1e9, G = 4e8, A = 1e-2, I2 = 1e-5, I3 = 1e-5, J = 2e-5, shear_factors = [0.8, 0.8] }",
    );
    assert!(e.contains("`root_position` places a BeamDyn blade"), "{e}");
    let e = model_error(
        d,
        "order = 2\npoints = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]\n[[beams.sections]]\nstation = 0.0\nordering = \"beamdyn\"\nisotropic = { E = 1e9, G = 4e8, A = 1e-2, I2 = 1e-5, I3 = 1e-5, J = 2e-5, shear_factors = [0.8, 0.8] }",
    );
    assert!(e.contains("`ordering` applies to"), "{e}");
}

#[test]
fn beamdyn_placement_and_overrides_change_the_beam() {
    // root_position and root_axes place BeamDyn's frame: blade along global −y from
    // (1, 2, 3), BeamDyn x along global z; `damping`, `quadrature` and `order` override.
    let text = format!(
        r#"[model]
name = "placed"
[[beams]]
name = "blade"
beamdyn = "{}"
root_position = [1.0, 2.0, 3.0]
root_axes = [[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]]
quadrature = "reduced"
damping = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
"#,
        primary().display()
    );
    let m = Model::from_toml_str(&text, "placed.toml").unwrap().model;
    let b = &m.beams[0];
    assert_eq!(b.order, 5, "the file's order_elem");
    assert_eq!(b.damping, [0.0; 6]);
    assert_eq!(
        b.quadrature,
        samara::elements::beam::element::Quadrature::Reduced
    );
    let tip = *b.nodes.last().unwrap();
    assert!((m.nodes[tip].position - Vector3::new(1.0, -59.5, 3.0)).norm() < 1e-9);
    let r = m.nodes[b.nodes[0]].orientation.matrix();
    let th = -13.308f64.to_radians();
    // Section y = BeamDyn x (global z) turned by −θ about the blade axis (global −y).
    let y = Vector3::new(0.0, 0.0, 1.0) * th.cos() - Vector3::new(1.0, 0.0, 0.0) * th.sin();
    assert!((r.column(0) + Vector3::y()).norm() < 1e-12, "{r}");
    assert!((r.column(1) - y).norm() < 1e-9, "{r}");
}
