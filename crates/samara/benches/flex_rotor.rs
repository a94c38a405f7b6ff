//! Flexible-rotor benchmark (issue #15): the NREL 5-MW rotor of
//! `examples/rotor/nrel5mw_flexible.toml` (three BeamDyn blades, 2 elements of order 6
//! each, hub driven at 12.1 rpm) with 49-station lifting lines (the AeroDyn blade table
//! interpolated to the 49 BeamDyn key points: chord and twist linear, airfoil of the
//! nearest AeroDyn node), BEM with tip and hub loss, rated wind, `T` s at h = 0.01 s.
//!
//! `cargo bench -p samara --bench flex_rotor [-- T]` prints the wall time, the time per
//! step, the real-time factor, and the split of one residual-and-tangent evaluation
//! between the structure (beam elements) and the aerodynamics (the 147 stations).

use samara::analysis::{History, run_analysis};
use samara::core::{ElementInput, EvalContext, LocalTerms, Need};
use samara::model::Model;
use samara::model::components::{Build, build_all, initial_nodes};
use samara::system::System;
use std::path::Path;
use std::time::Instant;

/// `[[aero_lines.stations]]` of the 49-station line.
fn stations(reference: &Path) -> String {
    let numbers = |l: &str| -> Vec<f64> {
        l.split_whitespace()
            .map_while(|t| t.parse::<f64>().ok())
            .collect()
    };
    let blade =
        std::fs::read_to_string(reference.join("structure/NRELOffshrBsline5MW_BeamDyn.dat"))
            .unwrap();
    let kp: Vec<f64> = blade
        .lines()
        .map(numbers)
        .filter(|v| v.len() == 4)
        .map(|v| v[2])
        .collect();
    assert_eq!(kp.len(), 49);
    let ad = std::fs::read_to_string(reference.join("aero/NRELOffshrBsline5MW_AeroDyn_blade.dat"))
        .unwrap();
    let rows: Vec<Vec<f64>> = ad.lines().map(numbers).filter(|v| v.len() == 7).collect();
    let airfoils = [
        "Cylinder1",
        "Cylinder2",
        "DU40_A17",
        "DU35_A17",
        "DU30_A17",
        "DU25_A17",
        "DU21_A17",
        "NACA64_A17",
    ];
    let mut s = String::new();
    for z in kp {
        let k = rows.partition_point(|r| r[0] <= z).clamp(1, rows.len() - 1);
        let (a, b) = (&rows[k - 1], &rows[k]);
        let t = (z - a[0]) / (b[0] - a[0]);
        let near = if t < 0.5 { a } else { b };
        let af = reference.join(format!(
            "aero/Airfoils/{}.dat",
            airfoils[near[6] as usize - 1]
        ));
        s += &format!(
            "[[aero_lines.stations]]\nspan = {z}\nchord = {}\ntwist = {}\nairfoil = \"{}\"\n",
            a[5] + t * (b[5] - a[5]),
            (a[4] + t * (b[4] - a[4])).to_radians(),
            af.display()
        );
    }
    s
}

fn main() {
    let t_end: f64 = std::env::args()
        .skip(1)
        .find_map(|a| a.parse().ok())
        .unwrap_or(10.0);
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let example = root.join("examples/rotor/nrel5mw_flexible.toml");
    let reference = root.join("reference/nrel5mw");
    let st = stations(&reference);
    let mut text = String::new();
    for l in std::fs::read_to_string(&example).unwrap().lines() {
        if l.starts_with("aerodyn = ") {
            continue;
        }
        text += l;
        text.push('\n');
        if l.starts_with("inflow = ") {
            text += &st;
        }
    }
    let text = text.replace("t_end = 0.5", &format!("t_end = {t_end}"));
    let m = match Model::from_toml_str(&text, &example) {
        Ok(l) => l.model,
        Err(e) => panic!("{}", e.render_plain()),
    };
    // One residual-and-tangent evaluation, structure and aerodynamics apart.
    let initial = initial_nodes(&m);
    let mut parts = Build::new(&initial);
    build_all(&m, &mut parts);
    let ctx = EvalContext {
        time: 0.0,
        gravity: nalgebra::Vector3::zeros(),
        load_factor: 1.0,
    };
    let time_of = |aero: bool| {
        let els: Vec<_> = parts
            .elements
            .iter()
            .filter(|e| e.name().starts_with("aero") == aero)
            .collect();
        let mut terms: Vec<LocalTerms> = els
            .iter()
            .map(|e| LocalTerms::for_element(e.as_ref()))
            .collect();
        let reps = 100;
        let clock = Instant::now();
        for _ in 0..reps {
            for (e, t) in els.iter().zip(&mut terms) {
                t.clear(Need::ResidualAndTangents);
                e.evaluate(
                    &ctx,
                    &ElementInput::nodes(&initial),
                    Need::ResidualAndTangents,
                    t,
                );
            }
        }
        (els.len(), clock.elapsed().as_secs_f64() / reps as f64)
    };
    let (ns, ts) = time_of(false);
    let (na, ta) = time_of(true);
    println!(
        "one evaluation: structure ({ns} elements, bodies, joints) {:.1} µs, aerodynamics ({na} stations) {:.1} µs ({:.0} % aerodynamics)",
        1e6 * ts,
        1e6 * ta,
        100.0 * ta / (ts + ta)
    );
    let sys = System::new(&m);
    let mut h = History::default();
    let clock = Instant::now();
    let s = run_analysis(
        &sys,
        &m.analyses[0],
        sys.initial_state(),
        &mut h,
        &mut |_| {},
    )
    .unwrap();
    let wall = clock.elapsed().as_secs_f64();
    assert!(s.failure.is_none(), "{:?}", s.failure);
    println!(
        "{t_end} s simulated in {wall:.3} s: {} steps, {:.2} Newton iterations per step, {:.3} ms/step, {:.2}× real time",
        s.steps,
        s.newton_iterations as f64 / s.steps as f64,
        1e3 * wall / s.steps as f64,
        t_end / wall
    );
}
