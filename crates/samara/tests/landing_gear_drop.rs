//! Issue #16: examples/landing_gear_drop.toml end to end — the main gear with the
//! oleo-pneumatic strut dropped at 2.5 m/s and 60 m/s onto the runway on a Magic-Formula
//! tire, the wheel spun up by the tire's friction, anti-skid braking under a PI, take-off
//! and the PID-controlled hydraulic retraction.
//!
//! Checks against what the physics fixes (the strut's own verification against an
//! independent integration is tests/strut.rs, the tire's tests/tire.rs):
//! - spin-up: the wheel reaches rolling, R_e Ω = V_x (1 + κ) with the small slip κ that
//!   carries the rolling resistance and bearing friction;
//! - braking: the momentum of the whole aircraft along the runway changes by the tire's
//!   friction impulse ∫F_x dt (the only horizontal external force: the rig's prismatic
//!   joint along x takes none); the PI holds the skid at its 8 % target;
//! - the strut strokes within its travel; the tire leaves the ground after take-off;
//! - retraction: the actuator's stroke follows the ramp command under the PID and ends
//!   at −0.4 m; the gear swings forward and up.

use crate::common;
use common::{model_file, run};
use nalgebra::Vector3;
use samara::elements::EvalContext;
use samara::model::AnalysisKind;
use samara::system::System;

#[test]
fn landing_gear_drops_spins_up_brakes_and_retracts_under_the_pid() {
    let mut m = model_file("examples/landing_gear_drop.toml");
    // Every step recorded, so that the trapezoid of F_x over the frames is the step's.
    if let AnalysisKind::Dynamic(d) = &mut m.analyses[0].kind {
        d.output_every = 1;
    }
    let sys = System::new(&m);
    let coord = |n: &str| sys.coordinate_names.iter().position(|c| c == n).unwrap();
    let (oleo, act, trunnion) = (
        coord("oleo.d3"),
        coord("actuator.d3"),
        coord("trunnion.theta3"),
    );
    let out = |n: &str| sys.output_names.iter().position(|o| o == n).unwrap();
    let (o_fz, o_fx, o_kappa, o_brake, o_delta) = (
        out("tire.normal_force"),
        out("tire.longitudinal_force"),
        out("tire.slip_ratio"),
        out("tire.brake_torque"),
        out("tire.deflection"),
    );
    let (_, h) = run(&m);
    let node = |n: &str| sys.node_names.iter().position(|x| x == n).unwrap();
    let wheel = node("wheel");
    let fus = node("fuselage");
    // Bodies: (node, mass, centre-of-mass offset in the initial, unrotated frame).
    let bodies: Vec<(usize, f64, Vector3<f64>)> = [
        ("carriage", 10.0, [0.0, 0.0, 0.0]),
        ("fuselage", 2000.0, [0.0, 0.0, 0.0]),
        ("strut", 40.0, [0.0, 0.0, -0.6]),
        ("piston", 15.0, [0.0, 0.0, -0.15]),
        ("wheel", 30.0, [0.0, 0.0, 0.0]),
        ("barrel", 6.0, [0.0, 0.0, 0.0]),
        ("rod", 4.0, [0.0, 0.0, 0.0]),
    ]
    .iter()
    .map(|(n, mass, c)| (node(n), *mass, Vector3::from(*c)))
    .collect();
    let total_mass: f64 = bodies.iter().map(|b| b.1).sum();
    let momentum_x = |k: usize| -> f64 {
        let s = &h.frames[k].state;
        bodies
            .iter()
            .map(|&(i, mass, c)| {
                let n = &s.nodes[i];
                mass * (n.v + n.omega_global().cross(&(n.r() * c)))[0]
            })
            .sum()
    };
    let mut o = vec![0.0; sys.output_names.len()];
    let outs: Vec<Vec<f64>> = h
        .frames
        .iter()
        .map(|f| {
            let ctx = EvalContext {
                time: f.time,
                gravity: m.gravity,
                load_factor: 1.0,
            };
            sys.element_outputs(&ctx, &f.state, &mut o);
            o.clone()
        })
        .collect();
    let angle = |k: usize| h.frames[k].state.coords[trunnion].q;
    let mut max_stroke = 0.0f64;
    let mut max_fz = 0.0f64;
    let (mut rolling_sum, mut rolling_n, mut rolling_err) = (0.0f64, 0usize, 0.0f64);
    let (mut skid_sum, mut skid_n, mut skid_dev) = (0.0f64, 0usize, 0.0f64);
    let mut track = 0.0f64;
    let (mut impulse, mut worst_balance) = (0.0f64, 0.0f64);
    let k_brake0 = h.frames.iter().position(|f| f.time >= 0.45).unwrap();
    let k_brake1 = h.frames.iter().position(|f| f.time >= 1.35).unwrap();
    let p0 = momentum_x(k_brake0);
    let mut airborne_at = None;
    for (k, f) in h.frames.iter().enumerate() {
        let t = f.time;
        let ok = &outs[k];
        max_stroke = max_stroke.max(f.state.coords[oleo].q);
        max_fz = max_fz.max(ok[o_fz]);
        let w = &f.state.nodes[wheel];
        if (0.2..0.5).contains(&t) {
            let v = w.v[0];
            let omega = w.omega_global()[1];
            let slip = (0.34 * omega - v) / v;
            // The free-rolling slip: F_x (R₀ − δ) balances the rolling resistance and the
            // bearing friction, F_x = B C μ F_z κ for small κ.
            let (fz, delta) = (ok[o_fz], ok[o_delta]);
            let free = -(0.01 * 0.35 * fz + 0.5 * omega) / ((0.35 - delta) * 10.0 * 1.9 * 0.8 * fz);
            rolling_sum += slip - free;
            rolling_n += 1;
            rolling_err = rolling_err.max(slip.abs());
        }
        if (0.65..1.2).contains(&t) {
            let skid = -ok[o_kappa];
            skid_sum += skid;
            skid_n += 1;
            skid_dev = skid_dev.max((skid - 0.08).abs());
            assert!(ok[o_brake] < 0.0, "the brake acts at {t}");
        }
        if k > k_brake0 && k <= k_brake1 {
            let dt = t - h.frames[k - 1].time;
            impulse += 0.5 * dt * (ok[o_fx] + outs[k - 1][o_fx]);
            worst_balance = worst_balance.max((momentum_x(k) - p0 - impulse).abs());
        }
        if t > 1.3 && airborne_at.is_none() && ok[o_fz] == 0.0 {
            airborne_at = Some(t);
        }
        if t < 1.5 && t > 0.05 {
            assert!(
                ok[o_fz] > 0.0,
                "the tire stays on the runway until take-off ({t})"
            );
        }
        if (2.0..3.4).contains(&t) {
            let cmd = 0.8 * ((t - 1.8) / 1.2).min(1.0);
            track = track.max((angle(k) - cmd).abs());
        }
    }
    let dv = (momentum_x(k_brake1) - p0) / total_mass;
    let skid_mean = skid_sum / skid_n as f64;
    let rolling_mean = rolling_sum / rolling_n as f64;
    let last = h.last().unwrap();
    let k_last = h.frames.len() - 1;
    let wheel_rise = (last.state.nodes[wheel].x - last.state.nodes[fus].x)[2] + 1.5;
    let wheel_aft = (last.state.nodes[wheel].x - last.state.nodes[fus].x)[0];
    println!(
        "max strut stroke {max_stroke:.4} m, max F_z {max_fz:.0} N; rolling slip less the free-rolling slip: mean {rolling_mean:.2e}; slip max {rolling_err:.2e}; skid mean {skid_mean:.4}, deviation {skid_dev:.4}; momentum balance {:.2e} of the change {dv:.3} m/s; airborne at {airborne_at:?}; angle tracking {track:.4} rad; end: angle {:.4} rad, actuator {:.4} m, wheel rise {wheel_rise:.3} m, wheel x {wheel_aft:.3} m",
        worst_balance / (total_mass * dv.abs()),
        angle(k_last),
        last.state.coords[act].q,
    );
    // Drop: the strut strokes within its travel (bottom stop at 0.3 m).
    assert!(max_stroke > 0.1 && max_stroke < 0.3, "{max_stroke}");
    // Spin-up: rolling, R_e Ω = V_x (1 + κ₀) with the free-rolling slip κ₀ ≈ −2e-3 that
    // carries the rolling resistance and the bearing friction; on average over 0.2–0.5 s
    // within 3e-4 (the relaxation lag while the load and speed change); at every instant
    // within 2 % (the hub's fore-aft vibration on the gear, which the wheel's inertia does
    // not follow).
    assert!(rolling_mean.abs() < 3e-4, "{rolling_mean}");
    assert!(rolling_err < 2e-2, "{rolling_err}");
    // Braking: the momentum along the runway changes by the friction impulse, to 1e-4 of
    // the change (the trapezoid of F_x over the steps against the integrator's
    // γ-weighted velocity update: O(h²)); the brakes take off at least 2.5 m/s.
    assert!(dv < -2.5, "{dv}");
    assert!(
        worst_balance < 1e-4 * total_mass * dv.abs(),
        "{worst_balance}"
    );
    // The PI holds the mean skid at its target (integral action) to 5e-3; the gear's
    // fore-aft vibration modulates it by up to 0.03.
    assert!((skid_mean - 0.08).abs() < 5e-3, "{skid_mean}");
    assert!(skid_dev < 0.03, "{skid_dev}");
    // Take-off after the lift rises (1.3–1.6 s).
    assert!(airborne_at.is_some_and(|t| t < 1.7), "{airborne_at:?}");
    // Retraction: the PID follows the ramp to 0.03 rad and holds the end angle to 0.01 rad;
    // the wheel swings aft and up.
    assert!(track < 0.03, "{track}");
    assert!((angle(k_last) - 0.8).abs() < 0.01, "{}", angle(k_last));
    assert!(
        wheel_rise > 0.4 && wheel_aft < -0.5,
        "{wheel_rise} {wheel_aft}"
    );
}
