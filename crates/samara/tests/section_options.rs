//! Every option of the section file changes what it should (each against a variant
//! without it, exactly where a closed relation exists).

use nalgebra::{Matrix3, Matrix6};
use samara::section::element::ElementKind;
use samara::section::properties::offset_transform;
use samara::section::{SectionResult, analyze, input};

fn solve(text: &str, extra: &[(&str, &str)]) -> (SectionResult, input::LoadedSection) {
    let dir = tempfile::tempdir().unwrap();
    for (n, b) in extra {
        std::fs::write(dir.path().join(n), b).unwrap();
    }
    let p = dir.path().join("s.section.toml");
    std::fs::write(&p, text).unwrap();
    let l = input::load(&p).unwrap_or_else(|e| panic!("{e}\n{text}"));
    (analyze(&l.model).unwrap(), l)
}

fn rel_max(a: &Matrix6<f64>, b: &Matrix6<f64>) -> f64 {
    (0..36)
        .map(|k| {
            let (i, j) = (k % 6, k / 6);
            (a[k] - b[k]).abs() / (b[(i, i)] * b[(j, j)]).sqrt()
        })
        .fold(0.0, f64::max)
}

const ORTHO: &str = r#"
[[materials]]
name = "cfrp"
type = "orthotropic"
E1 = 135e9
E2 = 10e9
E3 = 10e9
G12 = 5.2e9
G13 = 5.2e9
G23 = 3.9e9
nu12 = 0.3
nu13 = 0.3
nu23 = 0.28
rho = 1600.0

[[materials]]
name = "foam"
type = "isotropic"
E = 100e6
nu = 0.3
rho = 100.0
"#;

fn rect(extra: &str) -> String {
    format!(
        "{ORTHO}\n[rectangle]\nwidth = 0.04\nheight = 0.02\nmaterial = \"cfrp\"\nelements = [8, 4]\n{extra}"
    )
}

#[test]
fn placement_and_element_type() {
    let (base, _) = solve(&rect(""), &[]);
    // offset: K' = T_dᵀ K T_d.
    let (shifted, _) = solve(
        &format!(
            "[section]\noffset = [0.01, -0.02]\n{}",
            rect("ply_angle = 20.0")
        ),
        &[],
    );
    let (b20, _) = solve(&rect("ply_angle = 20.0"), &[]);
    let t = offset_transform([0.01, -0.02]);
    assert!(rel_max(&shifted.stiffness, &(t.transpose() * b20.stiffness * t)) < 1e-9);
    // rotation (degrees, about x).
    let (turned, _) = solve(
        &format!("[section]\nrotation = 30.0\n{}", rect("ply_angle = 20.0")),
        &[],
    );
    let (s, c) = 30f64.to_radians().sin_cos();
    let r = Matrix3::new(1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c);
    let mut p = Matrix6::zeros();
    p.fixed_view_mut::<3, 3>(0, 0).copy_from(&r.transpose());
    p.fixed_view_mut::<3, 3>(3, 3).copy_from(&r.transpose());
    assert!(rel_max(&turned.stiffness, &(p.transpose() * b20.stiffness * p)) < 1e-9);
    // element: 6-node triangles give the same (exact) EA.
    let (tri, l) = solve(&format!("[section]\nelement = \"tri6\"\n{}", rect("")), &[]);
    assert!(
        l.model
            .mesh
            .elements
            .iter()
            .all(|e| e.kind == ElementKind::Tri6)
    );
    assert!((tri.stiffness[(0, 0)] / base.stiffness[(0, 0)] - 1.0).abs() < 1e-12);
    // ply angle: off-axis fibres soften the beam and couple extension with shear.
    assert!(b20.stiffness[(0, 0)] < 0.8 * base.stiffness[(0, 0)]);
    assert!(b20.stiffness[(0, 1)].abs() > 1e-3 * base.stiffness[(0, 0)]);
    assert!(base.stiffness[(0, 1)].abs() < 1e-9 * base.stiffness[(0, 0)]);
}

/// An anisotropic material given as the 6×6 of an orthotropic one is the same material.
#[test]
fn anisotropic_matrix_equals_its_engineering_constants() {
    let m = samara::section::material::Material::orthotropic(
        "x",
        &samara::section::material::Orthotropic {
            e1: 135e9,
            e2: 10e9,
            e3: 10e9,
            g12: 5.2e9,
            g13: 5.2e9,
            g23: 3.9e9,
            nu12: 0.3,
            nu13: 0.3,
            nu23: 0.28,
        },
        1600.0,
    )
    .unwrap();
    let rows: Vec<String> = (0..6)
        .map(|i| {
            format!(
                "[{}]",
                (0..6)
                    .map(|j| format!("{:e}", m.stiffness[(i, j)]))
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        })
        .collect();
    let text = rect("ply_angle = 20.0").replace(
        "type = \"orthotropic\"\nE1 = 135e9\nE2 = 10e9\nE3 = 10e9\nG12 = 5.2e9\nG13 = 5.2e9\nG23 = 3.9e9\nnu12 = 0.3\nnu13 = 0.3\nnu23 = 0.28\n",
        &format!("type = \"anisotropic\"\nC = [{}]\n", rows.join(", ")),
    );
    assert!(text.contains("anisotropic"));
    let (a, _) = solve(&text, &[]);
    let (o, _) = solve(&rect("ply_angle = 20.0"), &[]);
    assert!(rel_max(&a.stiffness, &o.stiffness) < 1e-12);
    assert_eq!(a.mass, o.mass);
}

#[test]
fn mesh_counts() {
    let count = |t: &str| solve(t, &[]).1.model.mesh.elements.len();
    let circ = |n: &str| format!("{ORTHO}\n[circle]\nradius = 0.02\nmaterial = \"foam\"\n{n}");
    assert_eq!(count(&circ("")), 64 + 4 * 8 * 3);
    assert_eq!(count(&circ("elements = 4")), 16 + 4 * 4); // core 4 × 4, four patches of 4 × 1
    let tube = |n: &str| {
        format!(
            "{ORTHO}\n[tube]\nouter_radius = 0.02\nlayup = [{{ material = \"cfrp\", thickness = 1e-3, count = 2 }}]\n{n}"
        )
    };
    assert_eq!(count(&tube("")), 72 * 2);
    assert_eq!(
        count(&tube("elements_around = 10\nelements_per_ply = 3")),
        10 * 6
    );
}

#[test]
fn box_walls_and_i_section_flanges() {
    let bx = |walls: &str| {
        format!("{ORTHO}\n[box]\nwidth = 0.1\nheight = 0.05\nelements = [10, 6]\n{walls}")
    };
    let ply =
        |a: f64| format!("[{{ material = \"cfrp\", thickness = 1e-3, angle = {a}, count = 2 }}]");
    let (cus, _) = solve(&bx(&format!("layup = {}", ply(20.0))), &[]);
    // The same plies given wall by wall.
    let (walls, _) = solve(
        &bx(&format!(
            "top = {0}\nbottom = {0}\nleft = {0}\nright = {0}",
            ply(20.0)
        )),
        &[],
    );
    assert!(rel_max(&walls.stiffness, &cus.stiffness) < 1e-12);
    // Circumferentially asymmetric: the top −20°, the others +20°: bending–twist (K45)
    // appears, extension–twist (K14) drops.
    let (cas, _) = solve(
        &bx(&format!("layup = {}\ntop = {}", ply(20.0), ply(-20.0))),
        &[],
    );
    let k = |r: &SectionResult, i: usize, j: usize| {
        r.stiffness[(i, j)] / (r.stiffness[(i, i)] * r.stiffness[(j, j)]).sqrt()
    };
    assert!(
        k(&cus, 3, 4).abs() < 1e-9 && k(&cas, 3, 4).abs() > 1e-3,
        "{} {}",
        k(&cus, 3, 4),
        k(&cas, 3, 4)
    );
    assert!(k(&cas, 0, 3).abs() < k(&cus, 0, 3).abs());
    let (per, l) = solve(
        &bx(&format!("layup = {}\nelements_per_ply = 2", ply(20.0))),
        &[],
    );
    assert_eq!(l.model.mesh.elements.len(), 2 * (10 + 6) * 2 * 2);
    assert!(rel_max(&per.stiffness, &cus.stiffness) < 1e-2);
    let i_sec = |flanges: &str| {
        format!(
            "{ORTHO}\n[i_section]\nwidth = 0.1\nheight = 0.15\n{flanges}\nweb = [{{ material = \"cfrp\", thickness = 2e-3 }}]\n"
        )
    };
    let (sym, _) = solve(
        &i_sec("flanges = [{ material = \"cfrp\", thickness = 3e-3 }]"),
        &[],
    );
    let (thick_top, _) = solve(
        &i_sec(
            "top = [{ material = \"cfrp\", thickness = 6e-3 }]\nbottom = [{ material = \"cfrp\", thickness = 3e-3 }]",
        ),
        &[],
    );
    assert!(sym.properties.tension_centre[1].abs() < 1e-9);
    assert!(
        thick_top.properties.tension_centre[1] > 0.01,
        "{:?}",
        thick_top.properties.tension_centre
    );
}

const AIRFOIL: &str = r#"
[airfoil]
chord = 1.0
coordinates_file = "naca.dat"
blunt_trailing_edge = true
skin = [{ material = "cfrp", thickness = 2e-3, angle = 45.0 }, { material = "cfrp", thickness = 2e-3, angle = -45.0 }]
elements_around = 80

[[airfoil.spar_caps]]
from = 0.2
to = 0.45
layup = [{ material = "cfrp", thickness = 4e-3, count = 2 }]

[[airfoil.webs]]
at = 0.3
layup = [{ material = "cfrp", thickness = 4e-3 }]
"#;

fn naca() -> String {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/sections/naca2418.dat");
    std::fs::read_to_string(root).unwrap()
}

#[test]
fn airfoil_options() {
    let dat = naca();
    let files = [("naca.dat", dat.as_str())];
    let base_text = format!("{ORTHO}{AIRFOIL}");
    let (base, bl) = solve(&base_text, &files);
    // reference: the origin moves to (x/c, y/c) = (0.25, 0.01): K' = T_dᵀ K T_d, d = −ref·c.
    let (refd, _) = solve(
        &base_text.replace("chord = 1.0", "chord = 1.0\nreference = [0.25, 0.01]"),
        &files,
    );
    let t = offset_transform([-0.25, -0.01]);
    assert!(rel_max(&refd.stiffness, &(t.transpose() * base.stiffness * t)) < 1e-9);
    // An upper cap only: the tension centre rises.
    let (upper, _) = solve(
        &base_text.replace("from = 0.2", "surface = \"upper\"\nfrom = 0.2"),
        &files,
    );
    assert!(upper.properties.tension_centre[1] > base.properties.tension_centre[1] + 0.005);
    let (lower, _) = solve(
        &base_text.replace("from = 0.2", "surface = \"lower\"\nfrom = 0.2"),
        &files,
    );
    assert!(lower.properties.tension_centre[1] < base.properties.tension_centre[1] - 0.005);
    // The trailing-edge fill material changes the mass (foam instead of cfrp).
    let (fill, _) = solve(
        &base_text.replace(
            "elements_around = 80",
            "elements_around = 80\ntrailing_edge_fill = { material = \"foam\" }",
        ),
        &files,
    );
    assert!(fill.mass[(0, 0)] < base.mass[(0, 0)]);
    // Web elements and elements per ply.
    let (_, wl) = solve(
        &base_text.replace("at = 0.3", "at = 0.3\nelements = 7"),
        &files,
    );
    let webs = |l: &input::LoadedSection| {
        l.model
            .mesh
            .elements
            .iter()
            .filter(|e| (e.wall_angle.to_degrees() - 90.0).abs() < 20.0 && e.material == 0)
            .count()
    };
    assert_ne!(webs(&wl), webs(&bl));
    let (_, pl) = solve(
        &base_text.replace(
            "elements_around = 80",
            "elements_around = 80\nelements_per_ply = 2",
        ),
        &files,
    );
    assert!(pl.model.mesh.elements.len() > 3 * bl.model.mesh.elements.len() / 2);
}

#[test]
fn mesh_region_angles() {
    let mesh = "nodes\n1 0 0\n2 0.02 0\n3 0.02 0.01\n4 0 0.01\nelements\n1 quad4 a 1 2 3 4\n";
    let sec = |region: &str| {
        format!(
            "{ORTHO}\n[mesh]\nfile = \"m.mesh\"\n\n[[mesh.regions]]\nname = \"a\"\nmaterial = \"cfrp\"\n{region}"
        )
    };
    let files = [("m.mesh", mesh)];
    let (zero, _) = solve(&sec(""), &files);
    let (ply, _) = solve(&sec("ply_angle = 30.0"), &files);
    let (wall, _) = solve(&sec("ply_angle = 30.0\nwall_angle = 90.0"), &files);
    assert!(ply.stiffness[(0, 0)] < 0.9 * zero.stiffness[(0, 0)]);
    // Turning the wall moves the fibre's off-axis component from y to z: the extension–shear
    // coupling goes from K12 to K13.
    assert!(
        ply.stiffness[(0, 1)].abs() > 1e-3 * ply.stiffness[(0, 0)]
            && ply.stiffness[(0, 2)].abs() < 1e-9 * ply.stiffness[(0, 0)]
    );
    assert!(
        wall.stiffness[(0, 2)].abs() > 1e-3 * wall.stiffness[(0, 0)]
            && wall.stiffness[(0, 1)].abs() < 1e-9 * wall.stiffness[(0, 0)]
    );
}

/// The contour's direction does not matter: NACA 0012 (sharp trailing edge, the solid
/// trailing edge ending in triangles) listed clockwise gives the same section as listed
/// counter-clockwise, and its symmetry shows (no coupling of z-bending with extension).
#[test]
fn clockwise_coordinates_give_the_same_section() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/sections/naca0012.dat");
    let dat = std::fs::read_to_string(root).unwrap();
    let mut lines: Vec<&str> = dat.lines().collect();
    let title = lines.remove(0);
    let reversed = format!(
        "{title}\n{}\n",
        lines.iter().rev().copied().collect::<Vec<_>>().join("\n")
    );
    let text = format!(
        "{ORTHO}\n[airfoil]\nchord = 0.5\ncoordinates_file = \"a.dat\"\nreference = [0.25, 0.0]\nskin = [{{ material = \"cfrp\", thickness = 1e-3, angle = 0.0 }}]\nelements_around = 120\n"
    );
    let (ccw, l) = solve(&text, &[("a.dat", dat.as_str())]);
    let (cw, _) = solve(&text, &[("a.dat", reversed.as_str())]);
    assert!(
        l.model
            .mesh
            .elements
            .iter()
            .any(|e| e.kind == ElementKind::Tri6),
        "the sharp edge ends in triangles"
    );
    assert!(
        rel_max(&cw.stiffness, &ccw.stiffness) < 1e-9,
        "{}",
        rel_max(&cw.stiffness, &ccw.stiffness)
    );
    let k = ccw.stiffness;
    assert!(
        k[(0, 4)].abs() < 1e-6 * (k[(0, 0)] * k[(4, 4)]).sqrt(),
        "symmetric about the chord"
    );
    assert!(ccw.properties.tension_centre[1].abs() < 1e-6 * 0.5);
}
