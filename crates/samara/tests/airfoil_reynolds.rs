//! Issue #15: airfoils with several Reynolds-number tables (AeroDyn `NumTabs > 1`, or a CSV
//! with a `re` column), read at the station's Re = W c/ν, interpolated linearly in ln Re
//! (AeroDyn's AFTabMod = 2) and clamped outside the tables' range.

use nalgebra::Vector3;
use samara::core::NodeState;
use samara::elements::aero::{AeroStation, Airfoil, Attachment, BemRotor, Inflow, Section, Wind};
use samara::math::Rotation;
use samara::model::Model;
use std::f64::consts::PI;
use std::path::Path;
use std::sync::Arc;

/// Rows of a thin-plate polar scaled in lift by `k`: cl = k π sin 2α, cd = d, cm = −0.05 k sin α.
fn polar(k: f64, d: f64) -> Vec<(f64, f64, f64, f64)> {
    (-180..=180)
        .map(|deg| {
            let a = (deg as f64).to_radians();
            (deg as f64, k * PI * (2.0 * a).sin(), d, -0.05 * k * a.sin())
        })
        .collect()
}

/// A CSV with a `re` column: the plate polar at Re = 1e5 (lift × 1, cd 0.02) and at
/// Re = 1e6 (lift × 1.5, cd 0.01).
fn two_table_csv() -> String {
    let mut s = String::from("# two Reynolds numbers\nre,alpha,cl,cd,cm\n");
    for (re, k, d) in [(1e5, 1.0, 0.02), (1e6, 1.5, 0.01)] {
        for (a, cl, cd, cm) in polar(k, d) {
            s += &format!("{re},{a},{cl:.17},{cd},{cm:.17}\n");
        }
    }
    s
}

/// A station of chord `c` on a still node at the origin, in a wind of speed `w` at angle α
/// to the chord (+x), normal +z, reading the tables at Re = W c/ν.
fn station(
    af: &Arc<Airfoil>,
    c: f64,
    w: f64,
    alpha: f64,
    nu: f64,
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
            chord: c,
            width: 1.0,
            airfoil: af.clone(),
            viscosity: Some(nu),
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

#[test]
fn a_station_reads_two_tables_interpolated_in_log_reynolds_and_clamped_outside() {
    let af = Arc::new(Airfoil::parse(&two_table_csv(), true).unwrap());
    assert_eq!(af.tables(), 2);
    assert_eq!(af.reynolds_numbers(), &[1e5, 1e6]);
    let (c, nu) = (0.5, 1.5e-5);
    // α = 4° is a table knot: each table's cubic passes through its row exactly, so the
    // reference is the closed form of the rows, cl₁ = π sin 8°, cl₂ = 1.5 cl₁, cd 0.02/0.01.
    let alpha = 4f64.to_radians();
    let cl1 = PI * (2.0 * alpha).sin();
    let cm1 = -0.05 * alpha.sin();
    for (re, t) in [
        (3e5, (3f64).ln() / (10f64).ln()),
        (1e5, 0.0),
        (1e6, 1.0),
        (5e5, (5f64).ln() / (10f64).ln()),
        // Below the first and above the last table: clamped to them.
        (2e4, 0.0),
        (4e7, 1.0),
    ] {
        let w = re * nu / c;
        let (s, nodes) = station(&af, c, w, alpha, nu);
        let mut rows = [[0.0; 3]; 16];
        let mut zr = [0.0; samara::elements::aero::station::MAX_STATES];
        let r = s.compute(0.0, &nodes, &[], &[], &[], &mut rows, &mut zr);
        // By hand: c = (1 − t) c₁ + t c₂, t = ln(Re/1e5)/ln 10. Rounding only (the α the
        // station sees is atan2 of the wind's components, ≈ 1e-16 rad off the knot): 1e-12.
        let want = [
            (1.0 - t) * cl1 + t * 1.5 * cl1,
            (1.0 - t) * 0.02 + t * 0.01,
            (1.0 - t) * cm1 + t * 1.5 * cm1,
        ];
        assert!(
            (r.reynolds / re - 1.0).abs() < 1e-12,
            "Re {} vs {re}",
            r.reynolds
        );
        for (got, want) in [r.cl, r.cd, r.cm].iter().zip(want) {
            assert!((got - want).abs() < 1e-12, "Re {re}: {got} vs {want}");
        }
        // The loads follow: lift ½ρW²c cl along +z at this α (drag along the wind).
        let q = 0.5 * 1.2 * w * w * c;
        let lift = q * want[0];
        let f = Vector3::from(r.force);
        let ul = Vector3::new(-alpha.sin(), 0.0, alpha.cos());
        assert!(
            (f.dot(&ul) - lift).abs() < 1e-12 * q,
            "{} vs {lift}",
            f.dot(&ul)
        );
    }
    // ∂c/∂Re inside the range: (c₂ − c₁)/(Re ln(Re₂/Re₁)) (the ln-linear law's derivative);
    // zero outside (clamped).
    let (co, d) = af.eval_re(alpha, 3e5);
    assert!((co.cl - (1.0 + 0.5 * (3f64).ln() / (10f64).ln()) * cl1).abs() < 1e-12);
    let want = 0.5 * cl1 / (3e5 * (10f64).ln());
    assert!((d[0] / want - 1.0).abs() < 1e-12, "{} vs {want}", d[0]);
    assert!((d[1] - (-0.01 / (3e5 * (10f64).ln()))).abs() < 1e-20);
    assert_eq!(af.eval_re(alpha, 2e4).1, [0.0; 3]);
    assert_eq!(af.eval_re(alpha, 4e7).1, [0.0; 3]);
    // The interpolation stays C¹ in α (each table is, and the weights do not depend on α):
    // value and slope continuous across a knot, at Re between the tables.
    let k = 10f64.to_radians();
    let (l, r) = (af.eval_re(k - 1e-9, 3e5).0, af.eval_re(k + 1e-9, 3e5).0);
    assert!((l.cl - r.cl).abs() < 1e-7 && (l.dcl - r.dcl).abs() < 1e-6);
}

#[test]
fn a_bem_station_reads_the_tables_at_the_undisturbed_reynolds_number() {
    // With BEM the tables are read at W₀ = √(V_x² + V_y²) c/ν (no induction): the station
    // reports that Re, and its cl is the interpolated table at its α and that Re.
    let af = Arc::new(Airfoil::parse(&two_table_csv(), true).unwrap());
    let (c, nu, omega, r0, v) = (0.3, 1.5e-5, 3.0, 4.0, 6.0);
    let wind = Arc::new(Wind {
        speed: v,
        direction: Vector3::x(),
        ..Default::default()
    });
    let inflow = Arc::new(Inflow::Bem {
        rotor: BemRotor {
            blades: 3,
            hub_radius: 0.5,
            tip_radius: 5.0,
            tip_loss: true,
            hub_loss: true,
            tangential_induction: true,
            skewed_wake: false,
        },
        centre: Vector3::zeros(),
        axis: Vector3::x(),
    });
    let theta: f64 = 0.1;
    let (c0, n0) = (Vector3::y(), Vector3::x());
    let s = AeroStation::new(
        "s",
        vec![0],
        vec![Attachment {
            weight: 1.0,
            offset: Vector3::new(0.0, 0.0, r0),
            chord_dir: c0 * theta.cos() + n0 * theta.sin(),
            normal_dir: -c0 * theta.sin() + n0 * theta.cos(),
        }],
        Section {
            chord: c,
            width: 1.0,
            airfoil: af.clone(),
            viscosity: Some(nu),
        },
        1.2,
        wind,
        inflow,
    );
    let hub = NodeState {
        rot: Rotation::identity(),
        w: Vector3::new(omega, 0.0, 0.0),
        ..Default::default()
    };
    let mut rows = [[0.0; 3]; 16];
    let mut zr = [0.0; samara::elements::aero::station::MAX_STATES];
    let r = s.compute(0.0, &[hub], &[], &[], &[], &mut rows, &mut zr);
    let w0 = (v * v + (omega * r0).powi(2)).sqrt();
    assert!((r.reynolds / (w0 * c / nu) - 1.0).abs() < 1e-12);
    assert!(r.a > 0.05 && r.a < 0.5, "a windmill state: a = {}", r.a);
    let (co, _) = af.eval_re(r.alpha, r.reynolds);
    assert!((r.cl - co.cl).abs() < 1e-12 && (r.cd - co.cd).abs() < 1e-12);
}

/// A small AeroDyn (AirfoilInfo v1.01) file with tables at `re` [millions], the k-th with
/// lift × (1 + 0.5k); `alphas` the angles of every table.
fn aerodyn_file(re: &[f64], alphas: &[f64]) -> String {
    let mut s = String::from(
        "! ------------ AirfoilInfo v1.01.x Input File ----------------------------------\n\
         ! a thin plate at several Reynolds numbers\n\
         ! ------------------------------------------------------------------------------\n\
         \"DEFAULT\"     InterpOrd         ! Interpolation order\n\
         1             NonDimArea        ! The non-dimensional area of the airfoil\n\
         0             NumCoords         ! The number of coordinates in the airfoil shape file\n",
    );
    s += &format!(
        "{}             NumTabs           ! Number of airfoil tables in this file\n",
        re.len()
    );
    for (k, r) in re.iter().enumerate() {
        s += &format!(
            "! ------------------------------------------------------------------------------\n\
             ! data for table {}\n\
             ! ------------------------------------------------------------------------------\n\
             {r}   Re                ! Reynolds number in millions\n\
             0     UserProp          ! User property (control) setting\n\
             False InclUAdata        ! Is unsteady aerodynamics data included in this table?\n\
             !........................................\n\
             ! Table of aerodynamics coefficients\n\
             {}    NumAlf            ! Number of data lines in the following table\n\
             !    Alpha      Cl      Cd        Cm\n\
             !    (deg)      (-)     (-)       (-)\n",
            k + 1,
            alphas.len()
        );
        let lift = 1.0 + 0.5 * k as f64;
        for &a in alphas {
            let x = a.to_radians();
            s += &format!(
                "  {a:8.2}  {:.12}  {:.4}  {:.6}\n",
                lift * PI * (2.0 * x).sin(),
                0.01 * (k + 1) as f64,
                -0.02 * lift * x.sin()
            );
        }
    }
    s
}

#[test]
fn an_aerodyn_file_with_several_tables_reads_each_at_its_reynolds_number() {
    let alphas: Vec<f64> = (-36..=36).map(|k| 5.0 * k as f64).collect();
    let text = aerodyn_file(&[0.5, 2.0, 8.0], &alphas);
    let af = Airfoil::parse(&text, false).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(af.tables(), 3);
    assert_eq!(af.reynolds_numbers(), &[0.5e6, 2e6, 8e6]);
    // At each table's Re the station reads that table (through its rows at the knots;
    // the rows are printed to 12 decimals): 1e-12.
    for (k, re) in [0.5e6, 2e6, 8e6].into_iter().enumerate() {
        for a in [-40.0f64, 0.0, 15.0, 170.0] {
            let (c, _) = af.eval_re(a.to_radians(), re);
            let lift = 1.0 + 0.5 * k as f64;
            let want = lift * PI * (2.0 * a.to_radians()).sin();
            assert!(
                (c.cl - want).abs() < 1e-11,
                "table {k}, α {a}: {} vs {want}",
                c.cl
            );
            assert!((c.cd - 0.01 * (k + 1) as f64).abs() < 1e-12);
        }
    }
    // Between the second and third: Re = 4e6, t = ln 2/ln 4 = ½.
    let a = 10f64.to_radians();
    let (c, _) = af.eval_re(a, 4e6);
    let want = 1.75 * PI * (2.0 * a).sin();
    assert!((c.cl - want).abs() < 1e-11, "{} vs {want}", c.cl);
    // The first table is what `eval` (and `reynolds = "first"`) reads.
    assert_eq!(af.eval(a).cl, af.eval_re(a, 0.5e6).0.cl);
    // A single-table file (the NREL 5-MW's) still reads, with its Re.
    let one = aerodyn_file(&[0.75], &alphas);
    let af1 = Airfoil::parse(&one, false).unwrap();
    assert_eq!((af1.tables(), af1.reynolds_numbers()), (1, &[0.75e6][..]));
}

#[test]
fn bad_reynolds_tables_are_located_errors() {
    let alphas: Vec<f64> = (-36..=36).map(|k| 5.0 * k as f64).collect();
    let line_of = |text: &str, needle: &str, nth: usize| {
        text.lines()
            .enumerate()
            .filter(|(_, l)| l.contains(needle))
            .nth(nth)
            .unwrap()
            .0
            + 1
    };
    // AeroDyn: tables not sorted by Re: located at the second table's `Re` line.
    let text = aerodyn_file(&[2.0, 0.5], &alphas);
    let e = Airfoil::parse(&text, false).unwrap_err();
    assert_eq!(e.line, line_of(&text, "  Re  ", 1), "{e}");
    assert!(e.message.contains("strictly increasing Reynolds"), "{e}");
    // A second table that does not cover the circle: located at its first row.
    let short: Vec<f64> = (-4..=36).map(|k| 5.0 * k as f64).collect();
    let mut text = aerodyn_file(&[0.5, 2.0], &alphas);
    let t2 = aerodyn_file(&[0.5, 2.0], &short);
    let cut = t2.find("! data for table 2").unwrap();
    let own = text.find("! data for table 2").unwrap();
    text.replace_range(own.., &t2[cut..]);
    let e = Airfoil::parse(&text, false).unwrap_err();
    let first_row = line_of(&text, "   -20.00", 1);
    assert_eq!(e.line, first_row, "{e}");
    assert!(e.message.contains("−180°"), "{e}");
    // NumTabs larger than the tables given: located at NumTabs.
    let text =
        aerodyn_file(&[0.5], &alphas).replace("1             NumTabs", "2             NumTabs");
    let e = Airfoil::parse(&text, false).unwrap_err();
    assert_eq!(e.line, line_of(&text, "NumTabs", 0), "{e}");
    // A negative Reynolds number.
    let text = aerodyn_file(&[-0.5, 2.0], &alphas);
    let e = Airfoil::parse(&text, false).unwrap_err();
    assert_eq!(e.line, line_of(&text, "  Re  ", 0), "{e}");
    // CSV: a table that comes back after another (or a lower Re): located at that row.
    let csv = two_table_csv();
    let bad = csv.replacen("100000,180,", "2000000,180,", 1);
    let e = Airfoil::parse(&bad, true).unwrap_err();
    let l = line_of(&bad, "1000000,-180,", 0);
    assert_eq!(e.line, l, "{e}");
    assert!(e.message.contains("strictly increasing"), "{e}");
}

/// A node-borne wing line in a wind, with `extra` keys and the airfoil file `airfoil`.
fn line_model(dir: &Path, airfoil: &str, extra: &str) -> String {
    std::fs::write(dir.join("two.csv"), two_table_csv()).unwrap();
    let mut one = String::from("alpha,cl,cd,cm\n");
    for (a, cl, cd, cm) in polar(1.0, 0.02) {
        one += &format!("{a},{cl},{cd},{cm}\n");
    }
    std::fs::write(dir.join("one.csv"), one).unwrap();
    format!(
        r#"[model]
name = "re"
[[nodes]]
name = "wing"
position = [0.0, 0.0, 0.0]
[[bodies]]
name = "wing"
node = "wing"
mass = 1.0
inertia = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
[[aero_lines]]
name = "wing"
node = "wing"
root = [0.0, -1.0, 0.0]
tip = [0.0, 1.0, 0.0]
chord_direction = [1.0, 0.0, 0.0]
normal_direction = [0.0, 0.0, 1.0]
wind = {{ speed = 10.0 }}
{extra}
[[aero_lines.stations]]
span = 1.0
chord = 0.5
airfoil = "{airfoil}"
[[analyses]]
name = "run"
type = "dynamic"
t_end = 0.01
step = 0.01
"#
    )
}

fn model_error(dir: &Path, text: &str) -> String {
    match Model::from_toml_str(text, dir.join("bad.toml")) {
        Ok(_) => panic!("accepted"),
        Err(e) => e.render_plain(),
    }
}

#[test]
fn bad_reynolds_options_are_located_errors() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let ok = line_model(
        d,
        "two.csv",
        "reynolds = \"interpolate\"\nkinematic_viscosity = 1.5e-5",
    );
    Model::from_toml_str(&ok, d.join("ok.toml")).unwrap_or_else(|e| panic!("{}", e.render_plain()));
    let at = |text: &str, key: &str| {
        let l = text.lines().position(|l| l.starts_with(key)).unwrap() + 1;
        format!("bad.toml:{l}:")
    };
    // Interpolating a line whose airfoils have one table each: at `reynolds`.
    let bad = line_model(d, "one.csv", "reynolds = \"interpolate\"");
    let e = model_error(d, &bad);
    assert!(
        e.contains("single table") && e.contains(&at(&bad, "reynolds")),
        "{e}"
    );
    // A viscosity without interpolation, and one ≤ 0: at `kinematic_viscosity`.
    let bad = line_model(d, "two.csv", "kinematic_viscosity = 1.5e-5");
    let e = model_error(d, &bad);
    assert!(
        e.contains("without `reynolds") && e.contains(&at(&bad, "kinematic_viscosity")),
        "{e}"
    );
    let bad = line_model(
        d,
        "two.csv",
        "reynolds = \"interpolate\"\nkinematic_viscosity = -1.0",
    );
    let e = model_error(d, &bad);
    assert!(
        e.contains("must be > 0") && e.contains(&at(&bad, "kinematic_viscosity")),
        "{e}"
    );
    // With a dynamic-stall model (the curves of the interpolated polar,
    // tests/dynamic_stall_reynolds.rs): accepted.
    for stall in ["oye", "hgm"] {
        let ok = line_model(
            d,
            "two.csv",
            &format!("reynolds = \"interpolate\"\ndynamic_stall = \"{stall}\""),
        );
        Model::from_toml_str(&ok, d.join("ok.toml"))
            .unwrap_or_else(|e| panic!("{}", e.render_plain()));
    }
    // An unknown mode.
    let bad = line_model(d, "two.csv", "reynolds = \"nearest\"");
    let e = model_error(d, &bad);
    assert!(e.contains("reynolds") || e.contains("nearest"), "{e}");
}
