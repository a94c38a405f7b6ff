//! Issue #15: dynamic stall (Øye, HGM) on airfoils with several Reynolds-number tables
//! read with `reynolds = "interpolate"` (AeroDyn's AFTabMod = 2): the separation curves
//! are Kirchhoff's decomposition of the polar interpolated at the station's Re, with α₀,
//! c_lα (and the HGM coefficients) mixed between the tables by the same weight.
//! References: each table alone (at a table's Re the model must be that table's single-
//! table model) and the interpolated static polar (a steady state, ż = 0, must give it).
//! The tangents (∂/∂Re included) are in the generic check (model/components/aero.rs).

use nalgebra::Vector3;
use samara::core::NodeState;
use samara::elements::aero::station::{MAX_STATES, Unsteady};
use samara::elements::aero::{
    AeroStation, Airfoil, Attachment, Hgm, HgmCoefficients, Inflow, OyeStall, Section, Wind,
};
use samara::math::Rotation;
use samara::model::Model;
use std::path::{Path, PathBuf};
use std::sync::Arc;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The table block of an AeroDyn airfoil file (from its `Re` line to its last row), with
/// the Reynolds number set to `re_millions`.
fn table_block(file: &str, re_millions: f64) -> String {
    let text =
        std::fs::read_to_string(repo().join("reference/nrel5mw/aero/Airfoils").join(file)).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let start = lines
        .iter()
        .position(|l| l.split_whitespace().nth(1) == Some("Re"))
        .unwrap();
    let mut out = format!("{re_millions}   Re\n");
    for l in &lines[start + 1..] {
        out += l;
        out += "\n";
    }
    out
}

/// A two-table AeroDyn file: DU21-A17's table and UA block at Re = 1e6 and DU25-A17's at
/// 5e6 (two different polars standing for two Reynolds numbers: α₀ −4.2° / −3.2°,
/// C_nα 6.2047 / 6.4462, different stall).
fn two_tables() -> String {
    format!(
        "! two tables\n          2   NumTabs\n{}{}",
        table_block("DU21_A17.dat", 1.0),
        table_block("DU25_A17.dat", 5.0)
    )
}

/// A still station (node at the origin, chord along x, normal z) in a wind W at angle α.
fn station(
    af: &Arc<Airfoil>,
    nu: Option<f64>,
    w: f64,
    alpha: f64,
) -> (AeroStation, Vec<NodeState>) {
    let wind = Arc::new(Wind {
        speed: w,
        direction: Vector3::new(alpha.cos(), 0.0, alpha.sin()),
        ..Default::default()
    });
    let s = AeroStation::new(
        "s",
        vec![0],
        vec![Attachment {
            weight: 1.0,
            offset: Vector3::zeros(),
            chord_dir: Vector3::x(),
            normal_dir: Vector3::z(),
        }],
        Section {
            chord: 1.0,
            width: 1.0,
            airfoil: af.clone(),
            viscosity: nu,
        },
        1.2,
        wind,
        Arc::new(Inflow::None),
    );
    let node = NodeState {
        rot: Rotation::identity(),
        ..Default::default()
    };
    (s, vec![node])
}

/// The stall model of `af` as the model builder makes it: per table with `by_re`.
fn model(af: &Airfoil, hgm: bool, by_re: bool) -> Unsteady {
    if hgm {
        let ua = |k: usize| match af.ua_coefficients_of(k) {
            Some(Ok(c)) => *c,
            _ => HgmCoefficients::DEFAULT,
        };
        let h = if by_re {
            Hgm::with_tables(af, &[ua(0), ua(1)]).unwrap()
        } else {
            Hgm::new(af, &ua(0)).unwrap()
        };
        Unsteady {
            hgm: Some(Arc::new(h)),
            ..Unsteady::default()
        }
    } else {
        let o = if by_re {
            let lines: Vec<_> = (0..af.tables())
                .map(|k| OyeStall::new(&af.table(k)).unwrap().line())
                .collect();
            OyeStall::with_tables(af, &lines).unwrap()
        } else {
            OyeStall::new(af).unwrap()
        };
        Unsteady {
            stall: Some((Arc::new(o), 4.0)),
            ..Unsteady::default()
        }
    }
}

/// cl, cd, cm, the initial (steady) states and the state rows at states z and rates zd
/// (z = None: the steady states, zd = 0).
fn evaluate(
    s: &AeroStation,
    nodes: &[NodeState],
    ns: usize,
    off: Option<(&[f64], &[f64])>,
) -> Vec<f64> {
    let z0 = s.quasi_steady_states(0.0, nodes);
    let (z, zd): (Vec<f64>, Vec<f64>) = match off {
        None => (z0[..ns].to_vec(), vec![0.0; ns]),
        Some((dz, zd)) => ((0..ns).map(|k| z0[k] + dz[k]).collect(), zd.to_vec()),
    };
    let mut rows = [[0.0; 3]; 16];
    let mut zr = [0.0; MAX_STATES];
    let r = s.compute(0.0, nodes, &z, &zd, &[], &mut rows, &mut zr);
    let mut v = vec![r.cl, r.cd, r.cm];
    v.extend_from_slice(&z0[..ns]);
    v.extend_from_slice(&zr[..ns]);
    v
}

#[test]
fn at_a_tables_reynolds_number_the_stall_models_are_that_tables() {
    // The two-table airfoil read with Re interpolation at Re = 1e6 and 5e6 against the
    // single-table model of DU21 and of DU25: outputs, steady states and state rows (at
    // states off the steady ones too) equal to 1e-12 (the two paths evaluate the same
    // formulas: Kirchhoff's curves in dual numbers against the f64 ones; rounding only).
    let two = Arc::new(Airfoil::parse(&two_tables(), false).unwrap());
    assert_eq!(two.reynolds_numbers(), &[1e6, 5e6]);
    let (w, c) = (10.0, 1.0);
    for hgm in [false, true] {
        let ns = if hgm { 4 } else { 1 };
        let dz = [0.01, -0.02, 0.05, -0.1];
        let zd = [0.3, -0.1, 0.2, 0.4];
        for (k, re) in [(0usize, 1e6), (1, 5e6)] {
            let one = Arc::new(two.table(k));
            for deg in [-6.0, 2.0, 8.0, 12.0, 16.0, 25.0, 60.0] {
                let alpha = f64::to_radians(deg);
                let (s2, nodes) = station(&two, Some(w * c / re), w, alpha);
                let s2 = s2.with_unsteady(model(&two, hgm, true), 0.0, &nodes);
                let (s1, _) = station(&one, None, w, alpha);
                let s1 = s1.with_unsteady(model(&one, hgm, false), 0.0, &nodes);
                for off in [None, Some((&dz[..ns], &zd[..ns]))] {
                    let (a, b) = (
                        evaluate(&s2, &nodes, ns, off),
                        evaluate(&s1, &nodes, ns, off),
                    );
                    let worst = a
                        .iter()
                        .zip(&b)
                        .map(|(x, y)| (x - y).abs())
                        .fold(0.0, f64::max);
                    assert!(worst < 1e-12, "hgm {hgm}, Re {re}, α {deg}: {a:?} vs {b:?}");
                }
            }
        }
    }
}

#[test]
fn between_tables_a_steady_state_gives_the_interpolated_static_polar() {
    // At Re = √(1e6 · 5e6) (t = ½): the steady states (ż = 0) make every row vanish and the
    // coefficients equal the static polar interpolated in ln Re, c = (c₁ + c₂)/2:
    // Øye everywhere (f_st cl_inv + (1 − f_st) cl_fs = cl by construction), HGM where its
    // attached line does not exceed the table (f_st < 1, cl, cd, cm; below the stall
    // angle the HGM lift is c_lα(α − α₀) by design, f_st = 1). Tolerance 1e-12 (rounding).
    // The stall models do read the interpolated polar: at 20° and 40° the tables differ
    // by more than 4e-2.
    let two = Arc::new(Airfoil::parse(&two_tables(), false).unwrap());
    let (w, c) = (10.0, 1.0);
    let re = (1e6f64 * 5e6).sqrt();
    for hgm in [false, true] {
        let ns = if hgm { 4 } else { 1 };
        let angles: &[f64] = if hgm {
            &[12.0, 16.0, 20.0, 40.0, 120.0]
        } else {
            &[-30.0, -6.0, 2.0, 8.0, 12.0, 16.0, 20.0, 40.0, 120.0]
        };
        for &deg in angles {
            let alpha = deg.to_radians();
            let (s, nodes) = station(&two, Some(w * c / re), w, alpha);
            let s = s.with_unsteady(model(&two, hgm, true), 0.0, &nodes);
            let got = evaluate(&s, &nodes, ns, None);
            let (st, _) = two.eval_re(alpha, re);
            let (t1, t2) = (two.table(0).eval(alpha), two.table(1).eval(alpha));
            assert!((st.cl - 0.5 * (t1.cl + t2.cl)).abs() < 1e-12);
            let want = [st.cl, st.cd, st.cm];
            println!(
                "hgm {hgm}, α {deg}°: cl {:.6} (static {:.6}; tables {:.4}, {:.4}), rows {:?}",
                got[0],
                st.cl,
                t1.cl,
                t2.cl,
                &got[3 + ns..]
            );
            let n_check = if hgm { 3 } else { 1 };
            for j in 0..n_check {
                assert!(
                    (got[j] - want[j]).abs() < 1e-12,
                    "hgm {hgm}, α {deg}: {got:?} vs {want:?}"
                );
            }
            assert!(got[3 + ns..].iter().all(|r| r.abs() < 1e-12), "{got:?}");
            if deg == 20.0 || deg == 40.0 {
                assert!((t1.cl - t2.cl).abs() > 4e-2, "the tables differ at {deg}°");
            }
        }
    }
}

/// A node-borne wing in a 30 m/s wind at 25° with `extra` keys, the two-table airfoil.
fn wing(dir: &Path, extra: &str) -> String {
    std::fs::write(dir.join("two.dat"), two_tables()).unwrap();
    let a = 25f64.to_radians();
    format!(
        r#"[model]
name = "re_stall"
[[nodes]]
name = "wing"
position = [0.0, 0.0, 0.0]
[[bodies]]
name = "wing"
node = "wing"
mass = 1.0
inertia = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
[[joints]]
name = "fix"
type = "prescribed"
node_a = "ground"
node_b = "wing"
[[aero_lines]]
name = "wing"
node = "wing"
root = [0.0, -0.5, 0.0]
tip = [0.0, 0.5, 0.0]
chord_direction = [1.0, 0.0, 0.0]
normal_direction = [0.0, 0.0, 1.0]
wind = {{ speed = 30.0, direction = [{}, 0.0, {}] }}
{extra}
[[aero_lines.stations]]
span = 0.5
chord = 1.0
airfoil = "two.dat"
[[analyses]]
name = "run"
type = "dynamic"
t_end = 0.02
step = 0.01
"#,
        a.cos(),
        a.sin()
    )
}

use crate::common::airfoil_run;

#[test]
fn a_line_runs_dynamic_stall_on_interpolated_tables() {
    // End to end through the model keys: Re = 30 · 1/ν; with ν = 1.34e-5 Re ≈ 2.24e6
    // (t ≈ 0.5 between the tables). The steady lift equals the interpolated polar (1e-9:
    // Newton's tolerance on the states) and differs from the first table's (reynolds =
    // "first") by more than 1e-2.
    let dir = tempfile::tempdir().unwrap();
    let two = Airfoil::parse(&two_tables(), false).unwrap();
    let alpha = 25f64.to_radians();
    let nu = 1.34e-5;
    let re = 30.0 / nu;
    for stall in ["oye", "hgm"] {
        let keys = format!(
            "dynamic_stall = \"{stall}\"\nreynolds = \"interpolate\"\nkinematic_viscosity = {nu}"
        );
        let (_, outs, names, _) = airfoil_run::run(&wing(dir.path(), &keys), dir.path());
        let col = |n: &str| names.iter().position(|x| x == n).unwrap();
        let cl = outs.last().unwrap()[col("wing.0.cl")];
        let r = outs.last().unwrap()[col("wing.0.reynolds")];
        assert!((r / re - 1.0).abs() < 1e-12, "{r}");
        let want = two.eval_re(alpha, re).0.cl;
        let (_, first, _, _) = airfoil_run::run(
            &wing(dir.path(), &format!("dynamic_stall = \"{stall}\"")),
            dir.path(),
        );
        let cl_first = first.last().unwrap()[col("wing.0.cl")];
        println!("{stall}: cl {cl:.6}, interpolated polar {want:.6}, first table {cl_first:.6}");
        assert!((cl - want).abs() < 1e-9, "{stall}: {cl} vs {want}");
        assert!((cl - cl_first).abs() > 1e-2, "{stall}");
    }
}

#[test]
fn bad_reynolds_stall_input_is_a_located_error() {
    // A UA block error in the second table (T_f0 ≤ 0) is reported with HGM and Re
    // interpolation (the first table's block alone is read without it).
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let text = wing(d, "dynamic_stall = \"hgm\"\nreynolds = \"interpolate\"");
    let bad_file = two_tables();
    let second = bad_file.rfind("T_f0").unwrap();
    let line_start = bad_file[..second].rfind('\n').unwrap() + 1;
    let bad_file = format!(
        "{}       -3   T_f0{}",
        &bad_file[..line_start],
        &bad_file[second + 4..]
    );
    let line = bad_file[..line_start].lines().count() + 1;
    std::fs::write(d.join("bad.dat"), &bad_file).unwrap();
    let bad = text.replace("two.dat", "bad.dat");
    // wing() rewrote two.dat; point at bad.dat.
    let e = match Model::from_toml_str(&bad, d.join("bad.toml")) {
        Ok(_) => panic!("accepted"),
        Err(e) => e.render_plain(),
    };
    println!("{e}");
    let key = bad
        .lines()
        .position(|l| l.starts_with("dynamic_stall"))
        .unwrap()
        + 1;
    assert!(
        e.contains(&format!("line {line}"))
            && e.contains("T_f0")
            && e.contains(&format!("bad.toml:{key}:")),
        "{e}"
    );
    let first_only = bad.replace("reynolds = \"interpolate\"", "reynolds = \"first\"");
    assert!(Model::from_toml_str(&first_only, d.join("ok.toml")).is_ok());
}
