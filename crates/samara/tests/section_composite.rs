//! Composite sections (issue #12, verifications 3 and 4).
//!
//! - The box beam of Smith & Chopra (1991) with the circumferentially uniform layup [15]₆
//!   (extension–twist and bending–shear coupling) against VABS as published by Yu, Hodges &
//!   Ho, "Variational asymptotic beam sectional analysis – an updated version", Int. J.
//!   Engineering Science 59 (2012) 40–64, Table [box beam], reproduced with PreVABS in
//!   its documentation (github.com/wenbinyugroup/prevabs, share/examples/ex_box/README.md
//!   and box_cus.xml: outer 0.953 × 0.530 in, six AS4/3501-6 plies of 0.005 in at 15° on
//!   every wall, laid inwards from the outer profile; material and results as below).
//! - A section whose material is shifted and turned gives exactly the stiffness and mass
//!   of the rigid change of reference: `K' = Tᵀ K T`.

use nalgebra::{Matrix3, Matrix6};
use samara::section::element::ElementKind;
use samara::section::generators::{BoxSection, Meshing, Ply, Rectangle, box_section, rectangle};
use samara::section::material::{Material, Orthotropic};
use samara::section::properties::offset_transform;
use samara::section::{SectionModel, SectionResult, analyze};

/// AS4/3501-6 in psi and lb s²/in⁴ (PreVABS box_cus.xml).
fn as4() -> Material {
    Material::orthotropic(
        "as4_3501",
        &Orthotropic {
            e1: 20.59e6,
            e2: 1.42e6,
            e3: 1.42e6,
            g12: 0.87e6,
            g13: 0.87e6,
            g23: 0.696e6,
            nu12: 0.30,
            nu13: 0.30,
            nu23: 0.34,
        },
        1.353e-4,
    )
    .unwrap()
}

fn box_beam(n: usize, per: usize) -> SectionResult {
    let ply = Ply {
        material: 0,
        thickness: 0.005,
        angle: 15f64.to_radians(),
    };
    let mesh = box_section(&BoxSection {
        width: 0.953,
        height: 0.530,
        walls: std::array::from_fn(|_| vec![ply; 6]),
        elements: [n, n / 2],
        elements_per_ply: per,
        meshing: Meshing {
            kind: ElementKind::Quad8,
        },
    })
    .unwrap();
    analyze(&SectionModel::new(mesh, vec![as4()]).unwrap()).unwrap()
}

/// The published stiffness terms (lb, lb·in, lb·in²; VABS ordering = samara's):
/// (i, j) 1-based, Yu–Hodges–Ho 2012, PreVABS value.
const VABS: [(usize, usize, f64, f64); 9] = [
    (1, 1, 1.437e6, 1.437e6),
    (2, 2, 9.027e4, 9.026e4),
    (3, 3, 3.943e4, 3.941e4),
    (1, 4, 1.074e5, 1.074e5),
    (2, 5, -5.201e4, -5.201e4),
    (3, 6, -5.635e4, -5.635e4),
    (4, 4, 1.679e4, 1.679e4),
    (5, 5, 6.621e4, 6.621e4),
    (6, 6, 1.725e5, 1.725e5),
];

/// Every published term within 0.5 %, signs included. The tolerance: the references are
/// printed to 4 digits (±0.05 %), the two published meshes differ by up to 0.05 %, and the
/// re-entrant corners of the box make the shear and torsion terms converge slowly — ours
/// move by 0.3 % between 40 × 20 elements (one per ply) and 80 × 40 (two per ply), towards
/// slightly lower values; we compare the finer mesh.
#[test]
fn cus_box_beam_against_vabs() {
    let coarse = box_beam(40, 1);
    let fine = box_beam(80, 2);
    let mut worst: f64 = 0.0;
    for (i, j, yu, prevabs) in VABS {
        let (c, f) = (
            coarse.stiffness[(i - 1, j - 1)],
            fine.stiffness[(i - 1, j - 1)],
        );
        let e = (f - yu).abs() / yu.abs();
        println!(
            "K{i}{j}: {f:+.5e} (coarse {c:+.5e}); VABS {yu:+.4e}, PreVABS {prevabs:+.4e}: {:+.3} %",
            100.0 * (f / yu - 1.0)
        );
        worst = worst.max(e);
        assert!(e < 5e-3, "K{i}{j}: {f:e} vs {yu:e}");
        assert_eq!(f.signum(), yu.signum(), "K{i}{j} sign");
    }
    println!("largest difference {:.3} %", 100.0 * worst);
    // The other couplings vanish (the layup couples only 1–4, 2–5 and 3–6).
    let k = fine.stiffness;
    for i in 0..6 {
        for j in 0..6 {
            if i == j
                || VABS
                    .iter()
                    .any(|v| (v.0 - 1, v.1 - 1) == (i, j) || (v.1 - 1, v.0 - 1) == (i, j))
            {
                continue;
            }
            let r = k[(i, j)].abs() / (k[(i, i)] * k[(j, j)]).sqrt();
            assert!(r < 1e-9, "K{}{} = {:e}", i + 1, j + 1, k[(i, j)]);
        }
    }
    // Mass per length ρ A with the wall area of the mitred box.
    let area = 0.953 * 0.530 - (0.953 - 0.06) * (0.530 - 0.06);
    assert!((fine.mass[(0, 0)] / (1.353e-4 * area) - 1.0).abs() < 1e-12);
}

/// A fully coupled section: a rectangle of a material whose fibre is turned off the beam
/// axis (15°) and out of the section plane (wall angle 30°).
fn skewed(offset: [f64; 2], angle: f64) -> SectionResult {
    let cfrp = Material::orthotropic(
        "cfrp",
        &Orthotropic {
            e1: 135e9,
            e2: 10e9,
            e3: 9e9,
            g12: 5.2e9,
            g13: 5.0e9,
            g23: 3.9e9,
            nu12: 0.3,
            nu13: 0.28,
            nu23: 0.35,
        },
        1600.0,
    )
    .unwrap();
    let mut mesh = rectangle(&Rectangle {
        width: 0.06,
        height: 0.02,
        material: 0,
        ply_angle: 15f64.to_radians(),
        divisions: [12, 4],
        meshing: Meshing {
            kind: ElementKind::Quad8,
        },
    });
    for e in &mut mesh.elements {
        e.wall_angle = 30f64.to_radians();
    }
    // Make it unsymmetric too: a corner element of another material (steel).
    mesh.elements[0].material = 1;
    mesh.transform(offset, angle);
    let steel = Material::isotropic("steel", 210e9, 0.3, 7850.0).unwrap();
    analyze(&SectionModel::new(mesh, vec![cfrp, steel]).unwrap()).unwrap()
}

fn rel_max(a: &Matrix6<f64>, b: &Matrix6<f64>) -> f64 {
    let scale = Matrix6::from_fn(|i, j| (b[(i, i)] * b[(j, j)]).sqrt());
    (0..36)
        .map(|k| (a[k] - b[k]).abs() / scale[k].max(f64::MIN_POSITIVE))
        .fold(0.0, f64::max)
}

/// Shifting the material by d: `K' = T_dᵀ K T_d`, `M' = T_dᵀ M T_d` (`T_d` the strains of
/// the line at d from those of the reference line); turning it by α about x: the strains
/// and curvatures' (y, z) components rotate, `K' = Pᵀ K P`, `P = diag(1, Rᵀ, 1, Rᵀ)`.
/// Agreement to 1e-9 of the diagonal scale (round-off through the solve: exact in theory).
#[test]
fn shifted_and_turned_sections_transform_rigidly() {
    let base = skewed([0.0, 0.0], 0.0);
    let k = base.stiffness;
    let coupled = (0..6)
        .flat_map(|i| (0..6).map(move |j| (i, j)))
        .filter(|&(i, j)| i != j && k[(i, j)].abs() > 1e-6 * (k[(i, i)] * k[(j, j)]).sqrt())
        .count();
    assert!(
        coupled >= 20,
        "the section is fully coupled ({coupled} coupling terms)"
    );
    let d = [0.013, -0.021];
    let shifted = skewed(d, 0.0);
    let t = offset_transform(d);
    let ek = rel_max(&shifted.stiffness, &(t.transpose() * k * t));
    let em = rel_max(&shifted.mass, &(t.transpose() * base.mass * t));
    println!("shift: stiffness {ek:.2e}, mass {em:.2e}");
    assert!(ek < 1e-9 && em < 1e-9, "{ek:e} {em:e}");
    let (p0, p1) = (base.properties, shifted.properties);
    for (a, b) in [
        (p0.tension_centre, p1.tension_centre),
        (p0.shear_centre, p1.shear_centre),
        (p0.mass_centre, p1.mass_centre),
    ] {
        assert!(
            (a[0] + d[0] - b[0]).abs() < 1e-10 && (a[1] + d[1] - b[1]).abs() < 1e-10,
            "{a:?} + {d:?} vs {b:?}"
        );
    }
    let alpha = 0.7f64;
    let turned = skewed([0.0, 0.0], alpha);
    let (s, c) = alpha.sin_cos();
    let r = Matrix3::new(1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c);
    let mut p = Matrix6::zeros();
    p.fixed_view_mut::<3, 3>(0, 0).copy_from(&r.transpose());
    p.fixed_view_mut::<3, 3>(3, 3).copy_from(&r.transpose());
    let ek = rel_max(&turned.stiffness, &(p.transpose() * k * p));
    let em = rel_max(&turned.mass, &(p.transpose() * base.mass * p));
    println!("turn: stiffness {ek:.2e}, mass {em:.2e}");
    assert!(ek < 1e-9 && em < 1e-9, "{ek:e} {em:e}");
    let q1 = turned.properties;
    let rot = |a: [f64; 2]| [c * a[0] - s * a[1], s * a[0] + c * a[1]];
    for (a, b) in [
        (p0.tension_centre, q1.tension_centre),
        (p0.shear_centre, q1.shear_centre),
        (p0.mass_centre, q1.mass_centre),
    ] {
        let ra = rot(a);
        assert!(
            (ra[0] - b[0]).abs() < 1e-10 && (ra[1] - b[1]).abs() < 1e-10,
            "{ra:?} vs {b:?}"
        );
    }
    // The principal axes turn with the section.
    let da = q1.elastic_axes_angle - p0.elastic_axes_angle - alpha;
    let da = (da + std::f64::consts::FRAC_PI_2).rem_euclid(std::f64::consts::PI)
        - std::f64::consts::FRAC_PI_2;
    assert!(da.abs() < 1e-9, "principal axes {da}");
}
