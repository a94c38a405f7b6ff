//! Issue #16: examples/landing_gear_drop.toml end to end — the main gear with the
//! oleo-pneumatic strut dropped at 2.5 m/s and 60 m/s onto the runway, the wheel spun up
//! by the tire's friction, a touch-and-go, and the PID-controlled hydraulic retraction.
//!
//! Checks against what the physics fixes (not a reference integration — the strut's own
//! verification is tests/strut.rs): the wheel spins up to rolling, v/R; the strut strokes
//! within its travel and tops out after lift-off; the tire leaves the ground; the
//! actuator's stroke follows the ramp command under the PID to a few millimetres and ends
//! at −0.4 m; the gear swings forward and up.

mod common;
use common::{model_file, run};
use samara::system::System;

#[test]
fn landing_gear_drops_spins_up_and_retracts_under_the_pid() {
    let m = model_file("examples/landing_gear_drop.toml");
    let sys = System::new(&m);
    let coord = |n: &str| sys.coordinate_names.iter().position(|c| c == n).unwrap();
    let (oleo, act, trunnion) = (
        coord("oleo.d3"),
        coord("actuator.d3"),
        coord("trunnion.theta3"),
    );
    let (_, h) = run(&m);
    let wheel = sys.node_names.iter().position(|n| n == "wheel").unwrap();
    let fus = sys.node_names.iter().position(|n| n == "fuselage").unwrap();
    let mut max_stroke = 0.0f64;
    let mut spin_err_after = 0.0f64;
    let mut track = 0.0f64;
    for f in &h.frames {
        let t = f.time;
        max_stroke = max_stroke.max(f.state.coords[oleo].q);
        let w = &f.state.nodes[wheel];
        let z = w.x[2];
        if (0.1..0.5).contains(&t) && z < -1.5 {
            // Rolling: the sphere's lowest point at rest, ω_y R = v_x (spin about +y).
            let v = w.v[0];
            let omega = w.omega_global()[1];
            spin_err_after = spin_err_after.max((0.35 * omega - v).abs() / v);
        }
        if (1.2..2.5).contains(&t) {
            let cmd = -0.4 * ((t - 1.0) / 1.5).min(1.0);
            track = track.max((f.state.coords[act].q - cmd).abs());
        }
    }
    let last = h.last().unwrap();
    println!(
        "max strut stroke {max_stroke:.4} m; rolling error {spin_err_after:.2e}; stroke tracking {track:.4} m; end: actuator {:.4} m, trunnion {:.4} rad, fuselage z {:.3} m",
        last.state.coords[act].q, last.state.coords[trunnion].q, last.state.nodes[fus].x[2]
    );
    assert!(max_stroke > 0.05 && max_stroke < 0.3, "{max_stroke}");
    assert!(spin_err_after < 0.02, "{spin_err_after}");
    assert!(track < 0.02, "{track}");
    assert!((last.state.coords[act].q + 0.4).abs() < 0.01);
    assert!(
        last.state.coords[trunnion].q.abs() > 0.5,
        "the gear swung up"
    );
    assert!(last.state.nodes[wheel].x[2] > -1.5 + 0.1, "the wheel rose");
}
