//! Section files end to end (issue #12, verifications 6 and 7): a beam built from a section
//! file against the same beam with the matrices by hand; the written results read back
//! exactly; the cache; located errors for bad input.

use nalgebra::Vector3;
use samara::analysis::{History, run_analysis};
use samara::model::{LoadOptions, Model};
use samara::section::results::{Cache, results_csv, solve_cached};
use samara::section::{analyze, analyze_all, input};
use samara::system::System;
use std::f64::consts::PI;
use std::path::Path;

const RECT: &str = r#"
[[materials]]
name = "steel"
type = "isotropic"
E = 2.1e11
nu = 0.3
rho = 7850.0

[rectangle]
width = 0.1
height = 0.05
material = "steel"
elements = [32, 16]
"#;

fn beam_model(section_lines: &str) -> String {
    format!(
        r#"[model]
name = "cantilever"
gravity = [0.0, 0.0, -9.81]

[[beams]]
name = "b"
order = 4
elements = 2
points = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0]]
root = "root"
tip = "tip"

[[beams.sections]]
station = 0.0
{section_lines}

[[joints]]
name = "clamp"
type = "fixed"
node_a = "ground"
node_b = "root"

[[forces]]
name = "f"
node = "tip"
force = [0.0, 3.0e3, -2.0e4]
moment = [500.0, 0.0, 0.0]

[[analyses]]
name = "s"
type = "static"
load_steps = 4
tolerance = 1e-12
relative_tolerance = 1e-12
"#
    )
}

fn tip_displacement(text: &str, path: &Path, options: &LoadOptions) -> Vector3<f64> {
    let loaded = Model::from_toml_str_with(text, path, options).unwrap_or_else(|e| panic!("{e}"));
    let m = loaded.model;
    let sys = System::new(&m);
    let mut h = History::default();
    let s = run_analysis(
        &sys,
        &m.analyses[0],
        sys.initial_state(),
        &mut h,
        &mut |_| {},
    )
    .unwrap();
    assert!(s.failure.is_none());
    let i = m.node_index("tip").unwrap();
    h.last().unwrap().state.nodes[i].x - m.nodes[i].position
}

/// Torsion constant of a w × t rectangle (Saint-Venant's series) and the energy shear
/// factor of a 2a × 2b rectangle loaded along 2b (see section_isotropic.rs).
fn j_rect(w: f64, t: f64) -> f64 {
    let s: f64 = (1..4000)
        .step_by(2)
        .map(|n| (n as f64 * PI * w / (2.0 * t)).tanh() / (n as f64).powi(5))
        .sum();
    w * t.powi(3) / 3.0 * (1.0 - 192.0 * t / (PI.powi(5) * w) * s)
}
fn k_rect(a: f64, b: f64, nu: f64) -> f64 {
    let k = nu / (1.0 + nu);
    let s: f64 = (1..20000)
        .map(|n| (b - a / (n as f64 * PI) * (n as f64 * PI * b / a).tanh()) / (n as f64).powi(4))
        .sum();
    1.0 / (1.2 + 18.0 * a.powi(4) * k * k / (PI.powi(4) * b.powi(5)) * s)
}

/// A steel cantilever (2 m, 100 × 50 mm) under gravity, a tip force and a tip torque:
/// built from the section file, and with the isotropic constants written by hand from
/// closed forms (A, I exact; J from Saint-Venant's series; shear factors from the flexure
/// energy). The tip displacements agree to 1e-6 — the section solver's error on J and the
/// shear factors (≤ 3e-6) weighted by their share of the deflection.
#[test]
fn beam_from_section_file_matches_the_matrices_by_hand() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("rect.section.toml"), RECT).unwrap();
    let model_path = dir.path().join("beam.toml");
    let from_file = tip_displacement(
        &beam_model("section = \"rect.section.toml\""),
        &model_path,
        &LoadOptions::default(),
    );
    let (w, h, nu) = (0.1f64, 0.05f64, 0.3);
    let by_hand = format!(
        "isotropic = {{ E = 2.1e11, G = {g:e}, A = {a:e}, I2 = {i2:e}, I3 = {i3:e}, J = {j:e}, shear_factors = [{k2:e}, {k3:e}], density = 7850.0 }}",
        g = 2.1e11 / (2.0 * (1.0 + nu)),
        a = w * h,
        i2 = w * h.powi(3) / 12.0,
        i3 = h * w.powi(3) / 12.0,
        j = j_rect(w, h),
        k2 = k_rect(0.5 * h, 0.5 * w, nu),
        k3 = k_rect(0.5 * w, 0.5 * h, nu),
    );
    let hand = tip_displacement(&beam_model(&by_hand), &model_path, &LoadOptions::default());
    let e = (from_file - hand).norm() / hand.norm();
    println!(
        "tip from the section file {from_file:?}, by hand {hand:?}: relative difference {e:.2e}"
    );
    assert!(hand.norm() > 1e-3, "a visible deflection");
    assert!(e < 1e-6, "{e:e}");
}

/// The CSV that `samara section` writes, read back through `sections_file`, gives the
/// same beam to the last bit (17 significant digits round-trip).
#[test]
fn written_results_read_back_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let sec = dir.path().join("rect.section.toml");
    std::fs::write(&sec, RECT).unwrap();
    let loaded = input::load(&sec).unwrap();
    let r = analyze(&loaded.model).unwrap();
    std::fs::write(dir.path().join("rect.csv"), results_csv(&r)).unwrap();
    let model_path = dir.path().join("beam.toml");
    let a = tip_displacement(
        &beam_model("section = \"rect.section.toml\""),
        &model_path,
        &LoadOptions::default(),
    );
    let csv_model = beam_model("").replace(
        "[[beams.sections]]\nstation = 0.0\n",
        "sections_file = \"rect.csv\"\n",
    );
    let b = tip_displacement(&csv_model, &model_path, &LoadOptions::default());
    assert_eq!(a, b);
}

/// The cache: the first solve writes `<hash>.toml`, the second reads it (and the cached
/// matrices are what the beam uses: a tampered cache entry shows through); a change to the
/// section file changes the hash; a read-only cache is never written.
#[test]
fn section_results_are_cached_by_content() {
    let dir = tempfile::tempdir().unwrap();
    let sec = dir.path().join("rect.section.toml");
    std::fs::write(&sec, RECT).unwrap();
    let cache = Cache {
        dir: dir.path().join("out/sections"),
        write: true,
    };
    let first = solve_cached(&sec, Some(&cache)).unwrap();
    assert!(!first.cached);
    let file = cache.dir.join(format!("{}.toml", first.hash));
    assert!(file.exists());
    let second = solve_cached(&sec, Some(&cache)).unwrap();
    assert!(second.cached);
    assert_eq!(first.stiffness, second.stiffness);
    assert_eq!(first.mass, second.mass);
    // Tamper: double EA in the cached file; the model built with the cache sees it.
    let text = std::fs::read_to_string(&file).unwrap();
    let ea = first.stiffness[(0, 0)];
    let old = format!("[{:e},", ea);
    assert!(text.contains(&old), "{old}");
    std::fs::write(&file, text.replacen(&old, &format!("[{:e},", 2.0 * ea), 1)).unwrap();
    let loaded = Model::from_toml_str_with(
        &beam_model("section = \"rect.section.toml\""),
        dir.path().join("beam.toml"),
        &LoadOptions {
            section_cache: Some(cache.clone()),
        },
    )
    .unwrap();
    let c = loaded.model.beams[0].table.sections[0].stiffness[(0, 0)];
    assert_eq!(c, 2.0 * ea);
    // A changed section file is solved again.
    std::fs::write(&sec, RECT.replace("2.1e11", "2.0e11")).unwrap();
    let third = solve_cached(&sec, Some(&cache)).unwrap();
    assert!(!third.cached && third.hash != first.hash);
    // Read-only: nothing new is written.
    std::fs::write(&sec, RECT.replace("2.1e11", "1.9e11")).unwrap();
    let ro = Cache {
        dir: cache.dir.clone(),
        write: false,
    };
    let n_before = std::fs::read_dir(&cache.dir).unwrap().count();
    let fourth = solve_cached(&sec, Some(&ro)).unwrap();
    assert!(!fourth.cached);
    assert_eq!(std::fs::read_dir(&cache.dir).unwrap().count(), n_before);
}

/// The stations of a blade solved in parallel give the same matrices as one by one.
#[test]
fn stations_in_parallel_match_serial() {
    let dir = tempfile::tempdir().unwrap();
    let mut models = Vec::new();
    for (k, w) in [0.1, 0.08, 0.06, 0.05].iter().enumerate() {
        let p = dir.path().join(format!("s{k}.section.toml"));
        std::fs::write(&p, RECT.replace("width = 0.1", &format!("width = {w}"))).unwrap();
        models.push(input::load(&p).unwrap().model);
    }
    let par = analyze_all(&models);
    for (m, r) in models.iter().zip(par) {
        assert_eq!(analyze(m).unwrap().stiffness, r.unwrap().stiffness);
    }
}

// ---------------------------------------------------------------------------------------
// Bad input: every error names the file, line and column of what is wrong.

/// Loads section text from a file in a fresh folder (with `extra` files beside it) and
/// returns the rendered errors.
fn errors_of(text: &str, extra: &[(&str, &str)]) -> String {
    let dir = tempfile::tempdir().unwrap();
    for (name, body) in extra {
        std::fs::write(dir.path().join(name), body).unwrap();
    }
    let p = dir.path().join("bad.section.toml");
    std::fs::write(&p, text).unwrap();
    match input::load(&p) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e
            .to_string()
            .replace(&format!("{}/", dir.path().display()), ""),
    }
}

/// `file:line:col` of the first occurrence of `what` in `text`.
fn at(file: &str, text: &str, what: &str) -> String {
    let off = text.find(what).unwrap_or_else(|| panic!("{what}"));
    let line = text[..off].matches('\n').count() + 1;
    let col = off - text[..off].rfind('\n').map_or(0, |i| i + 1) + 1;
    format!("{file}:{line}:{col}")
}

const AIRFOIL: &str = r#"
[[materials]]
name = "glass"
type = "orthotropic"
E1 = 41.8e9
E2 = 14.0e9
E3 = 14.0e9
G12 = 2.63e9
G13 = 2.63e9
G23 = 2.63e9
nu12 = 0.28
nu13 = 0.28
nu23 = 0.28
rho = 1915.0

[airfoil]
chord = 1.0
coordinates = [
  [1.0, 0.0], [0.75, 0.05], [0.5, 0.08], [0.25, 0.09], [0.1, 0.07], [0.02, 0.03],
  [0.0, 0.0], [0.02, -0.03], [0.1, -0.06], [0.25, -0.07], [0.5, -0.06], [0.75, -0.03],
  [1.0, 0.0],
]
skin = [{ material = "glass", thickness = 2e-3, angle = 45.0 }]

[[airfoil.webs]]
at = 0.3
layup = [{ material = "glass", thickness = 5e-3 }]
"#;

#[test]
fn the_airfoil_template_is_valid() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("ok.section.toml");
    std::fs::write(&p, AIRFOIL).unwrap();
    let l = input::load(&p).unwrap_or_else(|e| panic!("{e}"));
    assert!(analyze(&l.model).is_ok());
}

#[test]
fn a_non_closed_airfoil_is_located_at_its_last_point() {
    let bad = AIRFOIL.replace(
        "[0.75, -0.03],\n  [1.0, 0.0],",
        "[0.75, -0.03],\n  [0.95, -0.01],",
    );
    let e = errors_of(&bad, &[]);
    assert!(
        e.contains(&format!(
            "{}: error: airfoil: the airfoil contour is not closed",
            at("bad.section.toml", &bad, "[0.95, -0.01]")
        )),
        "{e}"
    );
    assert!(e.contains("blunt_trailing_edge"), "{e}");
}

#[test]
fn a_self_intersecting_airfoil_is_located_at_the_crossing_segment() {
    // The upper surface dips below the lower one between x = 0.5 and 0.25.
    let bad = AIRFOIL.replace("[0.25, 0.09]", "[0.25, -0.12]");
    let e = errors_of(&bad, &[]);
    assert!(e.contains("crosses itself"), "{e}");
    assert!(
        e.contains(&at("bad.section.toml", &bad, "[0.5, 0.08]"))
            || e.contains(&at("bad.section.toml", &bad, "[0.25, -0.12]")),
        "{e}"
    );
}

#[test]
fn a_self_intersecting_coordinates_file_is_located_in_that_file() {
    let dat = "crossed\n1.0 0.0\n0.5 0.08\n0.25 -0.12\n0.0 0.0\n0.25 -0.07\n0.5 -0.06\n1.0 0.0\n";
    let text = AIRFOIL.replace(
        "coordinates = [\n  [1.0, 0.0], [0.75, 0.05], [0.5, 0.08], [0.25, 0.09], [0.1, 0.07], [0.02, 0.03],\n  [0.0, 0.0], [0.02, -0.03], [0.1, -0.06], [0.25, -0.07], [0.5, -0.06], [0.75, -0.03],\n  [1.0, 0.0],\n]",
        "coordinates_file = \"crossed.dat\"",
    );
    let e = errors_of(&text, &[("crossed.dat", dat)]);
    assert!(
        e.contains("crossed.dat:3:1: error: airfoil: the airfoil contour crosses itself")
            || e.contains("crossed.dat:4:1: error"),
        "{e}"
    );
}

#[test]
fn a_ply_angle_out_of_range_is_located_at_the_angle() {
    let bad = AIRFOIL.replace("angle = 45.0", "angle = 120.0");
    let e = errors_of(&bad, &[]);
    assert!(
        e.contains(&format!(
            "{}: error: ply angle 120 is outside [−90, 90] degrees",
            at("bad.section.toml", &bad, "120.0")
        )),
        "{e}"
    );
}

#[test]
fn a_web_outside_the_airfoil_is_located_at_its_station() {
    let bad = AIRFOIL.replace("at = 0.3", "at = 1.2");
    let e = errors_of(&bad, &[]);
    assert!(
        e.contains(&format!(
            "{}: error: airfoil: web 1: at x/c = 1.2 it is outside the hollow part",
            at("bad.section.toml", &bad, "1.2")
        )),
        "{e}"
    );
}

#[test]
fn a_material_that_is_not_positive_definite_is_located_at_its_entry() {
    let bad = AIRFOIL.replace("nu23 = 0.28", "nu23 = 1.4");
    let e = errors_of(&bad, &[]);
    assert!(e.contains(&format!("{}: error: material 'glass': the engineering constants give a compliance that is not positive definite", at("bad.section.toml", &bad, "[[materials]]"))), "{e}");
    let aniso = "[[materials]]\nname = \"m\"\ntype = \"anisotropic\"\nC = [[1,0,0,0,0,0],[0,1,0,0,0,0],[0,0,1,0,0,0],[0,0,0,1,0,0],[0,0,0,0,1,0],[0,0,0,0,0,-1]]\n\n[rectangle]\nwidth = 1.0\nheight = 1.0\nmaterial = \"m\"\n";
    let e = errors_of(aniso, &[]);
    assert!(e.contains("bad.section.toml:1:1: error: material 'm': the stiffness matrix is not positive definite"), "{e}");
}

const SQUARE_MESH: &str = "nodes\n1 0 0\n2 1 0\n3 1 1\n4 0 1\n5 2 0\n6 2 1\nelements\n1 quad4 core 1 2 3 4\n2 quad4 core 2 5 6 3\n";

fn mesh_section(mesh_file: &str) -> String {
    format!(
        "[[materials]]\nname = \"steel\"\ntype = \"isotropic\"\nE = 2e11\nnu = 0.3\n\n[mesh]\nfile = \"{mesh_file}\"\n\n[[mesh.regions]]\nname = \"core\"\nmaterial = \"steel\"\n"
    )
}

#[test]
fn a_degenerate_element_is_located_in_the_mesh_file() {
    // Element 2 with two coincident corners' worth of collapse: nodes 2, 5, 5's twin on
    // the same line.
    let mesh = SQUARE_MESH.replace("6 2 1", "6 3 0");
    let e = errors_of(&mesh_section("m.mesh"), &[("m.mesh", &mesh)]);
    assert!(
        e.contains(&format!(
            "{}: error: this element is degenerate or folded",
            at("m.mesh", &mesh, "2 quad4")
        )),
        "{e}"
    );
    // An inverted element among counter-clockwise ones.
    let inverted = SQUARE_MESH.replace("2 quad4 core 2 5 6 3", "2 quad4 core 2 3 6 5");
    let e = errors_of(&mesh_section("m.mesh"), &[("m.mesh", &inverted)]);
    assert!(
        e.contains(&format!(
            "{}: error: this element is inverted",
            at("m.mesh", &inverted, "2 quad4")
        )),
        "{e}"
    );
    // A node that does not exist, located at the node id.
    let missing = SQUARE_MESH.replace("2 5 6 3", "2 5 7 3");
    let e = errors_of(&mesh_section("m.mesh"), &[("m.mesh", &missing)]);
    assert!(
        e.contains(&format!(
            "{}: error: node 7 is not defined",
            at("m.mesh", &missing, "7 3")
        )),
        "{e}"
    );
    // The good mesh solves.
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("m.mesh"), SQUARE_MESH).unwrap();
    std::fs::write(dir.path().join("s.section.toml"), mesh_section("m.mesh")).unwrap();
    let l = input::load(&dir.path().join("s.section.toml")).unwrap();
    assert!(analyze(&l.model).is_ok());
}

#[test]
fn unknown_regions_materials_and_keys_are_named() {
    let text = mesh_section("m.mesh").replace("name = \"core\"", "name = \"cor\"");
    let e = errors_of(&text, &[("m.mesh", SQUARE_MESH)]);
    assert!(
        e.contains(&format!(
            "{}: error: region 'core' has no entry",
            at("m.mesh", SQUARE_MESH, "1 quad4")
        )),
        "{e}"
    );
    let text = mesh_section("m.mesh").replace("material = \"steel\"", "material = \"steal\"");
    let e = errors_of(&text, &[("m.mesh", SQUARE_MESH)]);
    assert!(
        e.contains("unknown material 'steal'") && e.contains("did you mean 'steel'?"),
        "{e}"
    );
    let text = mesh_section("m.mesh").replace("[mesh]\n", "[mesh]\nfromat = \"text\"\n");
    let e = errors_of(&text, &[("m.mesh", SQUARE_MESH)]);
    assert!(
        e.contains("bad.section.toml:8:1: error: unknown key `fromat`"),
        "{e}"
    );
    let text = format!("[section]\nelement = \"quad9\"\n{}", mesh_section("m.mesh"));
    let e = errors_of(&text, &[("m.mesh", SQUARE_MESH)]);
    assert!(
        e.contains("bad.section.toml:2:11: error: `element` chooses the element of the generators"),
        "{e}"
    );
    let two = format!(
        "{}\n[circle]\nradius = 1.0\nmaterial = \"steel\"\n",
        mesh_section("m.mesh")
    );
    let e = errors_of(&two, &[("m.mesh", SQUARE_MESH)]);
    assert!(e.contains("give one geometry, not 2 (mesh, circle)"), "{e}");
}

/// A model whose section file is broken: the error is at the `section` key of the model,
/// and carries the section file's own located error.
#[test]
fn a_bad_section_file_is_reported_in_the_model() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("rect.section.toml"),
        RECT.replace("width = 0.1", "width = -0.1"),
    )
    .unwrap();
    let text = beam_model("section = \"rect.section.toml\"");
    let path = dir.path().join("beam.toml");
    let e = Model::from_toml_str(&text, &path).unwrap_err();
    let s = e
        .render_plain()
        .replace(&format!("{}/", dir.path().display()), "");
    assert!(
        s.contains(&format!(
            "{}: error: beam 'b', section at station 0: the section file",
            at("beam.toml", &text, "\"rect.section.toml\"")
        )),
        "{s}"
    );
    let bad = RECT.replace("width = 0.1", "width = -0.1");
    assert!(
        s.contains(&format!(
            "{}: error: rectangle: `width` must be a positive length (got -0.1)",
            at("rect.section.toml", &bad, "-0.1")
        )),
        "{s}"
    );
    let e = Model::from_toml_str(&beam_model("section = \"missing.toml\""), &path).unwrap_err();
    assert!(
        e.render_plain().contains("cannot read the section file"),
        "{}",
        e.render_plain()
    );
    let both = beam_model(
        "section = \"rect.section.toml\"\nisotropic = { E = 1.0, G = 1.0, A = 1.0, I2 = 1.0, I3 = 1.0, J = 1.0, shear_factors = [1.0, 1.0] }",
    );
    let e = Model::from_toml_str(&both, &path).unwrap_err();
    assert!(
        e.render_plain()
            .contains("do not give `stiffness`, `mass` or `isotropic` as well"),
        "{}",
        e.render_plain()
    );
}

/// Recovery: the recovered 3-D stresses, integrated over the section (`∫ Zᵀ σ dA`), give
/// back the sectional forces they were recovered from — one of the equations the warping
/// solve satisfies exactly (tolerance 1e-9 of the largest force, round-off).
#[test]
fn recovered_stresses_integrate_to_the_sectional_forces() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("a.section.toml");
    std::fs::write(&p, AIRFOIL).unwrap();
    let l = input::load(&p).unwrap();
    let r = analyze(&l.model).unwrap();
    let theta = nalgebra::Vector6::new(3.0e4, -2.0e3, 5.0e3, 1.2e3, -4.0e3, 2.5e3);
    let mut sum = nalgebra::Vector6::zeros();
    for (e, el) in l.model.mesh.elements.iter().enumerate() {
        let xy: Vec<[f64; 2]> = el
            .node_list()
            .iter()
            .map(|&k| l.model.mesh.nodes[k])
            .collect();
        for g in el.kind.gauss_points() {
            let (y, z, eps) =
                samara::section::recovery::strain_at(&l.model, &r, e, g.xi, g.eta, &theta);
            let sigma = r.warping.q[e] * eps;
            let mut n = [0.0; 9];
            let mut dn = [[0.0; 2]; 9];
            el.kind.shape(g.xi, g.eta, &mut n, &mut dn);
            let det = samara::section::mesh::jacobian(el.kind, &xy, &dn).1;
            let w = g.weight * det;
            // Zᵀ σ: N = ∫σxx, V₂ = ∫σxy, V₃ = ∫σxz, T = ∫(y σxz − z σxy), M₂ = ∫z σxx, M₃ = −∫y σxx.
            sum += w * nalgebra::Vector6::new(
                sigma[0],
                sigma[5],
                sigma[4],
                y * sigma[4] - z * sigma[5],
                z * sigma[0],
                -y * sigma[0],
            );
        }
    }
    let err = (sum - theta).abs().max() / theta.abs().max();
    println!("resultants {sum:?} vs {theta:?}: {err:.2e}");
    assert!(err < 1e-9, "{err:e}");
    // The nodal values written out agree with the quadrature-point evaluation at nodes.
    let values = samara::section::recovery::recover(&l.model, &r, &theta);
    assert_eq!(
        values.len(),
        l.model
            .mesh
            .elements
            .iter()
            .map(|e| e.kind.n_nodes())
            .sum::<usize>()
    );
    let vtu = samara::section::recovery::vtu(&l.model, &values);
    assert!(vtu.contains("Name=\"stress_material\"") && vtu.contains("NumberOfCells=\""));
}

/// Element counts that would exhaust the memory are refused before meshing, with the key
/// located; so is an absurd ply `count`.
#[test]
fn oversized_meshes_are_refused() {
    let bad = RECT.replace("elements = [32, 16]", "elements = [100000, 100000]");
    let e = errors_of(&bad, &[]);
    assert!(e.contains("rectangle: these element counts make about 10000000000 elements, more than the 5000000 allowed"), "{e}");
    let bad = AIRFOIL.replace("angle = 45.0 }", "angle = 45.0, count = 100000000 }");
    let e = errors_of(&bad, &[]);
    assert!(
        e.contains(&format!(
            "{}: error: airfoil: `count` must be at most 10000",
            at("bad.section.toml", &bad, "100000000")
        )),
        "{e}"
    );
}
