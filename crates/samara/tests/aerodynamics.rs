//! Aerodynamics (issue #15): airfoil tables, lifting-line stations and quasi-steady BEM
//! against references nobody here wrote: Glauert's optimum rotor (closed-form integral),
//! the NREL 5-MW rotor from its public OpenFAST files against the reference operating
//! tables (../shared/reference/nrel5mw/), and located errors for bad inputs.

use nalgebra::Vector3;
use samara::core::{Element, ElementInput, EvalContext, LocalTerms, Need, NodeState};
use samara::elements::aero::{AeroStation, Airfoil, Attachment, BemRotor, Inflow, Section, Wind};
use samara::math::Rotation;
use samara::model::Model;
use samara::model::components::{Build, build_all, initial_nodes};
use std::path::{Path, PathBuf};
use std::sync::Arc;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn reference() -> PathBuf {
    repo().join("../shared/reference/nrel5mw")
}

fn ctx(t: f64) -> EvalContext {
    EvalContext {
        time: t,
        gravity: Vector3::zeros(),
        load_factor: 1.0,
    }
}

/// Sum of the loads the elements put on `node` (force and moment in node components).
fn loads_on(
    elements: &[Box<dyn Element>],
    nodes: &[NodeState],
    node: usize,
) -> (Vector3<f64>, Vector3<f64>) {
    let (mut f, mut m) = (Vector3::zeros(), Vector3::zeros());
    for e in elements {
        let mut out = LocalTerms::for_element(e.as_ref());
        e.evaluate(
            &ctx(0.0),
            &ElementInput::nodes(nodes),
            Need::Residual,
            &mut out,
        );
        for (k, &n) in e.nodes().iter().enumerate() {
            if n == node {
                for i in 0..3 {
                    f[i] -= out.r[6 * k + i];
                    m[i] -= out.r[6 * k + 3 + i];
                }
            }
        }
    }
    (f, m)
}

#[test]
fn every_nrel5mw_airfoil_file_reads_and_interpolates_its_table() {
    let dir = reference().join("aero/Airfoils");
    let mut n = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let p = entry.unwrap().path();
        if p.extension().is_some_and(|x| x == "dat") {
            let text = std::fs::read_to_string(&p).unwrap();
            let af = Airfoil::parse(&text, false).unwrap_or_else(|e| panic!("{p:?}: {e}"));
            // The curve passes through every table row (rows after the NumAlf line).
            let lines: Vec<&str> = text.lines().collect();
            let start = lines.iter().position(|l| l.contains("NumAlf")).unwrap();
            let mut rows = 0;
            for l in &lines[start + 1..] {
                let t = l.trim();
                if t.is_empty() || t.starts_with('!') {
                    continue;
                }
                let v: Vec<f64> = t.split_whitespace().map(|x| x.parse().unwrap()).collect();
                let c = af.eval(v[0].to_radians());
                // ±180° are the same angle: the table's two ends may differ in print.
                if v[0].abs() < 180.0 {
                    assert!((c.cl - v[1]).abs() < 1e-12 && (c.cd - v[2]).abs() < 1e-12);
                    assert!((c.cm - v[3]).abs() < 1e-12);
                }
                rows += 1;
            }
            assert_eq!(rows, af.len());
            n += 1;
        }
    }
    assert_eq!(n, 8, "the eight NREL 5-MW polars");
}

#[test]
fn airfoil_tables_that_do_not_cover_the_circle_are_located_errors() {
    let csv = "# a polar from −20° only\nalpha,cl,cd,cm\n-20,-1.0,0.1,0\n0,0,0.01,0\n20,1.0,0.1,0\n180,0,0.02,0\n";
    let e = Airfoil::parse(csv, true).unwrap_err();
    assert_eq!(e.line, 3, "{e}");
    assert!(e.message.contains("−180°"), "{e}");
    let bad_header = "alpha,lift,drag\n";
    assert_eq!(Airfoil::parse(bad_header, true).unwrap_err().line, 1);
    let bad_number = "alpha,cl,cd\n-180,0,0.1\n0,x,0\n180,0,0.1\n";
    let e = Airfoil::parse(bad_number, true).unwrap_err();
    assert_eq!((e.line, e.column), (3, 3), "{e}");
    let unsorted = "alpha,cl,cd\n-180,0,0.1\n10,0,0\n5,0,0\n180,0,0.1\n";
    assert_eq!(Airfoil::parse(unsorted, true).unwrap_err().line, 4);
    assert!(Airfoil::parse("nothing here", false).is_err());
}

/// Glauert's optimum rotor with wake rotation (Glauert 1935; Manwell, McGowan & Rogers,
/// "Wind Energy Explained", §3.7): a(x) from x² = (1 − a)(4a − 1)²/(1 − 3a),
/// a' = (1 − 3a)/(4a − 1), Cp = (8/λ²) ∫₀^λ a'(1 − a) x³ dx.
fn glauert_cp(lambda: f64) -> f64 {
    let a_of = |x: f64| {
        let (mut lo, mut hi) = (0.25f64, 1.0 / 3.0);
        for _ in 0..200 {
            let a = 0.5 * (lo + hi);
            let g = (1.0 - a) * (4.0 * a - 1.0).powi(2) / (1.0 - 3.0 * a) - x * x;
            if g > 0.0 { hi = a } else { lo = a }
        }
        0.5 * (lo + hi)
    };
    // Composite Simpson, 20,000 intervals (integrand smooth, error ≪ 1e-9).
    let n = 20_000;
    let h = lambda / n as f64;
    let f = |x: f64| {
        if x == 0.0 {
            return 0.0;
        }
        let a = a_of(x);
        (1.0 - 3.0 * a) / (4.0 * a - 1.0) * (1.0 - a) * x.powi(3)
    };
    let mut s = f(0.0) + f(lambda);
    for k in 1..n {
        s += f(k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 };
    }
    8.0 / (lambda * lambda) * s * h / 3.0
}

/// Cp of Glauert's optimum blade (3 blades, no drag, no losses) with `n` midpoint
/// stations of the lifting line, BEM at each, on a rotor of radius 1 in unit wind.
fn ideal_rotor_cp(lambda: f64, n: usize) -> f64 {
    let (b, alpha_d) = (3usize, 4f64.to_radians());
    let airfoil = Arc::new(Airfoil::thin_plate());
    let cl_d = airfoil.eval(alpha_d).cl;
    let wind = Arc::new(Wind {
        speed: 1.0,
        ..Default::default()
    });
    let inflow = Arc::new(Inflow::Bem {
        rotor: BemRotor {
            blades: b,
            hub_radius: 0.0,
            tip_radius: 1.0,
            tip_loss: false,
            hub_loss: false,
            tangential_induction: true,
        },
        centre: Vector3::zeros(),
        axis: Vector3::x(),
    });
    let hub = NodeState {
        rot: Rotation::identity(),
        w: Vector3::new(lambda, 0.0, 0.0),
        ..Default::default()
    };
    let nodes = vec![hub];
    let mut elements: Vec<Box<dyn Element>> = Vec::new();
    for k in 0..n {
        let r = (k as f64 + 0.5) / n as f64;
        let phi = 2.0 / 3.0 * (1.0 / (lambda * r)).atan();
        let chord = 8.0 * std::f64::consts::PI * r * (1.0 - phi.cos()) / (b as f64 * cl_d);
        let theta = phi - alpha_d;
        // Blade along +z, turning about +x: it moves along −y, so the chord (LE → TE)
        // is +y at zero twist and the suction side faces downwind (+x).
        let (c0, n0) = (Vector3::y(), Vector3::x());
        let c = c0 * theta.cos() + n0 * theta.sin();
        let nn = -c0 * theta.sin() + n0 * theta.cos();
        elements.push(Box::new(AeroStation::new(
            format!("s{k}"),
            vec![0],
            vec![Attachment {
                weight: 1.0,
                offset: Vector3::new(0.0, 0.0, r),
                chord_dir: c,
                normal_dir: nn,
            }],
            Section {
                chord,
                width: 1.0 / n as f64,
                airfoil: airfoil.clone(),
            },
            1.0,
            wind.clone(),
            inflow.clone(),
        )));
    }
    let (_, m) = loads_on(&elements, &nodes, 0);
    let power = b as f64 * m.x * lambda;
    power / (0.5 * std::f64::consts::PI)
}

#[test]
fn bem_on_glauerts_optimum_rotor_converges_to_the_ideal_power_coefficient() {
    // Published values of Glauert's optimum (Manwell et al., Table 3.1, three digits):
    // λ = 1 → 0.416, 2.5 → 0.532, 5 → 0.570; the quadrature reproduces them to the
    // printed digits (half a unit of the last: 5e-4, with margin for its rounding).
    for (l, cp) in [(1.0, 0.416), (2.5, 0.532), (5.0, 0.570)] {
        assert!(
            (glauert_cp(l) - cp).abs() < 6e-4,
            "λ = {l}: {}",
            glauert_cp(l)
        );
    }
    for lambda in [2.5, 7.5] {
        let exact = glauert_cp(lambda);
        let errs: Vec<f64> = [10, 20, 40, 80]
            .iter()
            .map(|&n| (ideal_rotor_cp(lambda, n) - exact).abs())
            .collect();
        println!("λ = {lambda}: Cp exact {exact:.6}, errors {errs:?}");
        // Midpoint rule over the span: second order, the error falls ~4× per halving.
        for w in errs.windows(2) {
            assert!(w[1] < w[0] / 3.0, "{errs:?}");
        }
        assert!(errs[3] < 2e-4, "{errs:?}");
    }
}

/// The example's rotor at (wind, rpm, pitch): aerodynamic power [kW], thrust [kN].
fn nrel5mw_at(model: &Model, wind: f64, rpm: f64, pitch_deg: f64) -> (f64, f64) {
    let mut m = model.clone();
    let omega = rpm * std::f64::consts::PI / 30.0;
    m.nodes[0].angular_velocity = Vector3::new(omega, 0.0, 0.0);
    for l in &mut m.aero_lines {
        l.wind.speed = wind;
        l.pitch = pitch_deg.to_radians();
    }
    let initial = initial_nodes(&m);
    let mut parts = Build::new(&initial);
    build_all(&m, &mut parts);
    let (f, mo) = loads_on(&parts.elements, &initial, 0);
    (mo.x * omega / 1e3, f.x / 1e3)
}

#[test]
fn nrel5mw_rigid_rotor_matches_the_reference_power_and_thrust() {
    let loaded = Model::from_file(repo().join("examples/rotor/nrel5mw_rotor.toml")).unwrap();
    let model = loaded.model;
    assert_eq!(model.aero_lines.len(), 3);
    assert_eq!(model.aero_lines[0].stations.len(), 19);
    // 1. Region 3 (Jonkman et al. 2009, Table 7-1): at 12.1 rpm and the tabulated pitch
    //    the aerodynamic power is the rated mechanical power, 5296.6 kW. Plain steady BEM
    //    (two independent codes, reference README) reproduces it within about 1 %; this
    //    model also leaves out the precone (−2.5°, cos² ≈ 0.998) and the blades' AC
    //    offsets: tolerance 3 %.
    let table = std::fs::read_to_string(
        reference().join("transcribed/Jonkman2009_Table7-1_transcribed.csv"),
    )
    .unwrap();
    let mut worst: f64 = 0.0;
    for l in table.lines().filter(|l| !l.starts_with('#')).skip(1) {
        let v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
        if v[0] < 12.0 || v[0] > 22.0 {
            continue;
        }
        let (p, t) = nrel5mw_at(&model, v[0], v[1], v[2]);
        let err = p / 5296.6 - 1.0;
        println!(
            "Table 7-1: V = {} m/s, pitch {}°: P = {p:.1} kW ({:+.2} %), T = {t:.1} kN",
            v[0],
            v[2],
            100.0 * err
        );
        worst = worst.max(err.abs());
    }
    assert!(worst < 0.03, "worst {worst}");
    // 2. The OpenFAST rigid-turbine steady table (welib): plain BEM gives power and thrust
    //    6–14 % above it (dynamic wake, unsteady airfoil, tilt, tower flow, skew there;
    //    reference README). Loose check: within −3 % … +16 %.
    let oper = std::fs::read_to_string(
        reference()
            .join("operating_points/welib_openfast_steady/NREL5MW_Oper_Onshore_Rigid_Discon.csv"),
    )
    .unwrap();
    for l in oper.lines().skip(1) {
        let v: Vec<f64> = l.split('\t').map(|x| x.parse().unwrap()).collect();
        let ws = v[0];
        if ![5.0, 8.0, 11.0, 15.0, 20.0].contains(&ws) {
            continue;
        }
        let (p, t) = nrel5mw_at(&model, ws, v[1], v[2]);
        let p_ref = v[7] * v[1] * std::f64::consts::PI / 30.0; // RtAeroMxh [kN m] × Ω
        let t_ref = v[6];
        let (ep, et) = (p / p_ref - 1.0, t / t_ref - 1.0);
        println!(
            "OpenFAST rigid: V = {ws} m/s: P = {p:.1} kW vs {p_ref:.1} ({:+.1} %), T = {t:.1} kN vs {t_ref:.1} ({:+.1} %)",
            100.0 * ep,
            100.0 * et
        );
        assert!((-0.03..0.16).contains(&ep), "power at {ws} m/s: {ep}");
        assert!((-0.03..0.16).contains(&et), "thrust at {ws} m/s: {et}");
    }
}
