//! Issue #4, sectional output: the results file of a model with a beam holds `beam_force`,
//! `beam_moment`, `beam_strain`, `beam_curvature` and the sections' positions, stations and
//! frames, and the values obey the statics of a cantilever under a tip load.

use crate::common;

use common::model;
use nalgebra::{UnitQuaternion, Vector3, Vector4};
use netcdf3::FileReader;
use samara::analysis::run_analysis;
use samara::output::ResultsFile;
use samara::system::System;

const L: f64 = 2.0;
const EI: f64 = 2.0e5;
const GA: f64 = 5.0e7;

/// Steel-like cantilever along x (L = 2 m, 4 elements of order 4), clamped at the root,
/// tip force (0, 0, −F) and tip moment (0, My, 0); static in `steps` increments.
fn cantilever(force: f64, moment: f64, steps: usize) -> String {
    format!(
        r#"
[model]
name = "cantilever"

[[beams]]
name = "beam"
order = 4
elements = 4
points = [[0.0, 0.0, 0.0], [{L}, 0.0, 0.0]]
root = "root"
tip = "tip"

[[beams.sections]]
station = 0.0
stiffness = [[4e8, 0, 0, 0, 0, 0], [0, {GA}, 0, 0, 0, 0], [0, 0, {GA}, 0, 0, 0],
             [0, 0, 0, 1.5e5, 0, 0], [0, 0, 0, 0, {EI}, 0], [0, 0, 0, 0, 0, {EI}]]

[[joints]]
name = "clamp"
type = "fixed"
node_a = "ground"
node_b = "root"

[[forces]]
name = "load"
node = "tip"
force = [0.0, 0.0, {f}]
moment = [0.0, {moment}, 0.0]

[[analyses]]
name = "static"
type = "static"
load_steps = {steps}
"#,
        f = -force
    )
}

/// Runs the static analysis into a results file and reads the sectional variables of the
/// last record: (names, η, positions, quaternions, forces, moments, strains, curvatures).
struct Sections {
    names: Vec<String>,
    eta: Vec<f64>,
    x: Vec<Vector3<f64>>,
    q: Vec<UnitQuaternion<f64>>,
    force: Vec<Vector3<f64>>,
    moment: Vec<Vector3<f64>>,
    strain: Vec<Vector3<f64>>,
    curvature: Vec<Vector3<f64>>,
    tip: Vector3<f64>,
}

fn run_to_file(toml: &str) -> Sections {
    let m = model(toml);
    let sys = System::new(&m);
    let dir = tempfile::tempdir().unwrap();
    let mut file = ResultsFile::create(dir.path(), &m, None, &sys, &m.analyses[0]).unwrap();
    let s = run_analysis(
        &sys,
        &m.analyses[0],
        sys.initial_state(),
        &mut file,
        &mut |_| {},
    )
    .unwrap();
    assert!(s.failure.is_none(), "{:?}", s.failure);
    let path = file.finish(&s).unwrap();
    let mut rd = FileReader::open(&path).unwrap();
    let ds = rd.data_set();
    for v in [
        "beam_name",
        "section_name",
        "section_beam",
        "section_eta",
        "section_position",
        "section_orientation",
        "beam_force",
        "beam_moment",
        "beam_strain",
        "beam_curvature",
    ] {
        assert!(ds.has_var(v), "missing variable {v}");
    }
    let n = ds.get_dim("section").unwrap().size();
    assert_eq!(n, 16, "4 elements × 4 reduced Gauss points");
    let records = ds.num_records().unwrap();
    let strlen = ds.get_dim("section_strlen").unwrap().size();
    let raw = rd.read_var_u8("section_name").unwrap();
    let names: Vec<String> = raw
        .chunks(strlen)
        .map(|c| {
            String::from_utf8_lossy(c)
                .trim_end_matches('\0')
                .to_string()
        })
        .collect();
    let eta = rd.read_var_f64("section_eta").unwrap();
    let beam = rd.read_var_i32("section_beam").unwrap();
    assert!(beam.iter().all(|&b| b == 0));
    let last = |name: &str, rd: &mut FileReader, k: usize| -> Vec<f64> {
        let v = rd.read_var_f64(name).unwrap();
        v[(records - 1) * n * k..records * n * k].to_vec()
    };
    let v3 = |v: Vec<f64>| -> Vec<Vector3<f64>> {
        v.chunks(3)
            .map(|c| Vector3::new(c[0], c[1], c[2]))
            .collect()
    };
    let x = v3(last("section_position", &mut rd, 3));
    let q = last("section_orientation", &mut rd, 4)
        .chunks(4)
        .map(|c| UnitQuaternion::from_quaternion(Vector4::new(c[1], c[2], c[3], c[0]).into()))
        .collect();
    let force = v3(last("beam_force", &mut rd, 3));
    let moment = v3(last("beam_moment", &mut rd, 3));
    let strain = v3(last("beam_strain", &mut rd, 3));
    let curvature = v3(last("beam_curvature", &mut rd, 3));
    let tip_index = m.node_index("tip").unwrap();
    let pos = rd.read_var_f64("position").unwrap();
    let nn = m.nodes.len();
    let o = ((records - 1) * nn + tip_index) * 3;
    Sections {
        names,
        eta,
        x,
        q,
        force,
        moment,
        strain,
        curvature,
        tip: Vector3::new(pos[o], pos[o + 1], pos[o + 2]),
    }
}

/// Small tip force F = 100 N (tip rotation θ = F L²/(2 EI) = 1e-3, so linear theory holds
/// to O(θ²) = 1e-6): the shear force is −F (section z: the outboard part pulls the inboard
/// part down) and the bending moment about y is F (L − s), at the root F·L — constant and
/// linear in s, so the elements reproduce them exactly and only the geometric
/// nonlinearity and the Newton tolerance remain. Tolerance 1e-5 relative.
#[test]
fn cantilever_tip_force_shear_and_root_moment() {
    let f = 100.0;
    let s = run_to_file(&cantilever(f, 0.0, 1));
    assert_eq!(s.names[0], "beam#0");
    assert_eq!(s.names[15], "beam#15");
    let theta_max = f * L * L / (2.0 * EI);
    for k in 0..s.eta.len() {
        let sk = s.eta[k] * L;
        assert!((s.x[k].x - sk).abs() < 1e-3 * L, "station {k}");
        let n = s.force[k];
        let m = s.moment[k];
        assert!((n.z + f).abs() < 1e-5 * f, "shear at {k}: {n:?}");
        // The section turns by θ(s) ≤ θ_max: the load has an axial component F sin θ.
        assert!(
            n.x.abs() <= f * theta_max * 1.01 && n.y.abs() < 1e-5 * f,
            "{k}: {n:?}, θ max {theta_max}"
        );
        let exact = f * (L - sk);
        assert!(
            (m.y - exact).abs() < 1e-5 * f * L,
            "moment at {k}: {m:?} vs {exact}"
        );
        // Strains and curvatures follow from the compliance of the (diagonal) section.
        assert!((s.strain[k].z - n.z / GA).abs() < 1e-12);
        assert!((s.curvature[k].y - m.y / EI).abs() < 1e-12);
    }
    // The root moment, linearly extrapolated from the first two sections, is F·L.
    let (s0, s1) = (s.eta[0] * L, s.eta[1] * L);
    let root = s.moment[0].y - s0 * (s.moment[1].y - s.moment[0].y) / (s1 - s0);
    println!(
        "root moment {root} (F L = {}), shear {}",
        f * L,
        s.force[0].z
    );
    assert!((root - f * L).abs() < 1e-5 * f * L);
}

/// Large tip force (tip deflection ≈ 0.3 L, rotation ≈ 0.5 rad): the free body of the
/// outboard part gives the sectional resultants exactly, n = F and m = (x_tip − x(s)) × F
/// (global), whatever the deformation; in section-frame components Rᵀn, Rᵀm with R from
/// `section_orientation`. The discrete solution satisfies this to the discretization
/// error of 4 elements of order 4 on a curve of this curvature, measured 3e-7 relative;
/// tolerance 1e-5 of F·L.
#[test]
fn cantilever_large_deflection_free_body() {
    let f = 1.0e5;
    let s = run_to_file(&cantilever(f, 0.0, 10));
    let load = Vector3::new(0.0, 0.0, -f);
    println!("tip {:?}", s.tip);
    assert!(s.tip.z < -0.2 * L, "the case is geometrically nonlinear");
    let mut worst: f64 = 0.0;
    for k in 0..s.eta.len() {
        let r = s.q[k];
        let n = r.inverse_transform_vector(&load);
        let m = r.inverse_transform_vector(&(s.tip - s.x[k]).cross(&load));
        worst = worst
            .max((s.force[k] - n).norm() / f)
            .max((s.moment[k] - m).norm() / (f * L));
    }
    println!("worst free-body mismatch {worst:e}");
    assert!(worst < 1e-5);
}
