//! Issue #16, verification 5 (first half): a DC motor (`[[motors]]`) spinning up a
//! flywheel, examples/electric/motor_spinup.toml.
//!
//! Reference: the closed form of the linear system L i̇ = V − R i − k ω, J ω̇ = k i from
//! rest (two real modes, λ² + (R/L) λ + k²/(L J) = 0), nobody's code. samara integrates the
//! current with the first-order generalized-α and the flywheel with the second-order one:
//! the error's order as the step is halved is 2 ± 0.25, and its size at the finest step
//! is stated below; the energy balance (kinetic + ½ L i² + Joule losses − V i input)
//! closes to the integrator's O(h²).

use crate::common;
use common::{model_file, run};
use samara::model::{AnalysisKind, Model};
use samara::system::System;

fn set_step(mut m: Model, step: f64) -> Model {
    if let AnalysisKind::Dynamic(d) = &mut m.analyses[0].kind {
        d.step = step;
        d.min_step = step / 1024.0;
    }
    m
}

/// (i(t), ω(t)) of the closed form from ω = 0, i = i0, at voltage v.
fn exact(t: f64, v: f64, i0: f64) -> (f64, f64) {
    let (r, l, k, j): (f64, f64, f64, f64) = (1.0, 0.01, 0.1, 0.01);
    // y = (i, ω), ẏ = A y + b; y∞ = (0, V/k).
    let (a11, a12, a21) = (-r / l, -k / l, k / j);
    let disc = (a11 * a11 + 4.0 * a12 * a21).sqrt();
    let l1 = 0.5 * (a11 + disc);
    let l2 = 0.5 * (a11 - disc);
    // Eigenvectors (λ − a11... from the second row: a21 i = λ ω → v = (λ, a21)).
    let (v1, v2) = ((l1, a21), (l2, a21));
    // y(0) − y∞ = (i0, −V/k) = c1 v1 + c2 v2.
    let w = -v / k;
    // c1 l1 + c2 l2 = i0; (c1 + c2) a21 = w.
    let s = w / a21;
    let c1 = (i0 - s * l2) / (l1 - l2);
    let c2 = s - c1;
    let e1 = (l1 * t).exp();
    let e2 = (l2 * t).exp();
    (
        c1 * v1.0 * e1 + c2 * v2.0 * e2,
        v / k + c1 * v1.1 * e1 + c2 * v2.1 * e2,
    )
}

#[test]
fn motor_spin_up_current_and_speed_against_the_closed_form() {
    let mut ei = Vec::new();
    let mut ew = Vec::new();
    for step in [2e-3, 1e-3, 5e-4] {
        let m = set_step(model_file("examples/electric/motor_spinup.toml"), step);
        let sys = System::new(&m);
        let k = sys
            .state_names
            .iter()
            .position(|n| n == "drive.current")
            .unwrap();
        let (_, h) = run(&m);
        let (mut wi, mut ww) = (0.0f64, 0.0f64);
        for f in &h.frames {
            let (i, w) = exact(f.time, 12.0, 0.0);
            let n = &f.state.nodes[0];
            wi = wi.max((f.state.states[k].z - i).abs());
            ww = ww.max(((n.r() * n.w)[2] - w).abs());
        }
        // Peak current V/R·(…) ≈ 11 A; final speed 120 rad/s.
        println!("h = {step:e}: current error {wi:.3e} A, speed error {ww:.3e} rad/s");
        ei.push(wi);
        ew.push(ww);
        let last = h.last().unwrap();
        let (i_end, w_end) = exact(last.time, 12.0, 0.0);
        println!(
            "  at {:.1} s: i = {i_end:.5} A, ω = {w_end:.4} rad/s",
            last.time
        );
        // Energy: kinetic + ½Li² + dissipated − input = 0 (from rest).
        let en = &last.energy;
        let balance = en.kinetic + en.potential + en.dissipated - en.external_work;
        println!(
            "  energy: kinetic {:.3} J, losses {:.3} J, input {:.3} J, balance {balance:.2e} J",
            en.kinetic, en.dissipated, en.external_work
        );
        assert!(balance.abs() < 1e-4 * en.external_work, "{balance}");
    }
    for (what, e) in [("current", &ei), ("speed", &ew)] {
        let orders = common::orders(e);
        println!("{what}: orders {orders:.3?}");
        for p in &orders {
            assert!((p - 2.0).abs() < 0.25, "{what}: {orders:?} {e:?}");
        }
    }
    // At h = 0.5 ms (h/τ_e = 0.05): current within 2e-3 A of an 11 A peak (9.2e-4
    // measured); speed within 2e-4 rad/s of 120 (9.0e-5 measured).
    assert!(ei[2] < 2e-3 && ew[2] < 2e-4, "{ei:?} {ew:?}");
}

/// `initial_current`: with the supply at 0 V and 5 A in the armature at the start, the
/// flywheel is kicked and braked by the back-EMF (closed form with i(0) = 5 A, V = 0;
/// the O((h/τ_e)²) error, 1.5e-3 A of 5 A measured at h = 1 ms, h/τ_e = 0.1; bound 3e-3).
#[test]
fn initial_current_decays_through_the_closed_form() {
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../examples/electric/motor_spinup.toml"),
    )
    .unwrap()
    .replace("value = 12.0", "value = 0.0")
    .replace(
        "voltage = \"supply\"",
        "voltage = \"supply\"\ninitial_current = 5.0",
    );
    let m = common::model(&text);
    let (_, h) = run(&m);
    let mut worst = 0.0f64;
    for f in &h.frames {
        let (i, w) = exact(f.time, 0.0, 5.0);
        let n = &f.state.nodes[0];
        worst = worst
            .max((f.state.states[0].z - i).abs())
            .max(((n.r() * n.w)[2] - w).abs());
    }
    println!("initial current: error {worst:.2e}");
    assert!(worst < 3e-3, "{worst}");
}

/// Bad motor input: located errors with hints.
#[test]
fn bad_motor_input_is_rejected_where_it_is_written() {
    let base = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../examples/electric/motor_spinup.toml"),
    )
    .unwrap();
    for (from, to, message) in [
        (
            "resistance = 1.0 ",
            "resistance = -1.0 ",
            "`resistance` must be positive",
        ),
        (
            "inductance = 0.01 ",
            "inductance = 0.0 ",
            "`inductance` must be positive",
        ),
        (
            "motor_constant = 0.1 ",
            "motor_constant = -0.1 ",
            "`motor_constant` must be positive",
        ),
        (
            "voltage = \"supply\"",
            "voltage = \"suply\"",
            "unknown signal 'suply'",
        ),
        (
            "node_b = \"flywheel\"\naxis",
            "node_b = \"ground\"\naxis",
            "the rotor cannot be the ground",
        ),
        (
            "node_a = \"ground\"\nnode_b = \"flywheel\"\naxis",
            "node_a = \"flywheel\"\nnode_b = \"flywheel\"\naxis",
            "stator and rotor are the same node",
        ),
        (
            "axis = [0.0, 0.0, 1.0]\nresistance",
            "axis = [0.0, 0.0, 0.0]\nresistance",
            "`axis` must be a non-zero vector",
        ),
    ] {
        assert!(base.contains(from), "{from}");
        let text = base.replacen(from, to, 1);
        let Err(e) = samara::model::Model::from_toml_str(&text, "bad.toml") else {
            panic!("accepted: {to}")
        };
        let d = e.errors().next().unwrap();
        let span = d.span.clone().expect("located");
        let (line, _) = e.source.line_col(span.start);
        let want = text[..text.find(to).unwrap()].matches('\n').count() + 1;
        let want = want
            + to.lines()
                .position(|l| l.contains("node_b") || l.contains("axis =") || !to.contains('\n'))
                .unwrap_or(0);
        println!("{message}: line {line}: {}", d.message);
        assert!(d.message.contains(message), "{}", d.message);
        assert!(d.hint.is_some());
        assert_eq!(line, want, "{}", d.message);
    }
}
