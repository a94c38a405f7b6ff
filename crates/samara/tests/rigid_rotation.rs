//! Issue #2, verifications 2 and 3: the heavy symmetric top in steady precession against
//! the closed form, and the torque-free asymmetric body spinning near its intermediate
//! axis (energy and angular momentum bounded, no drift, O(h²)).

use crate::common;
use common::*;
use nalgebra::Vector3;
use samara::math::Rotation;
use samara::system::System;

/// Heavy symmetric top: mass m, CG at distance l from the pivot on the symmetry axis e₃,
/// tilted by θ from the vertical. Steady precession at rate Ω (θ̇ = 0) requires
/// (Goldstein, Classical Mechanics, §5.7)
///     A Ω² cos θ − C ω₃ Ω + m g l = 0,
/// with A the transverse inertia about the pivot, C the axial inertia and ω₃ the spin
/// component along e₃. The slow root is taken.
#[test]
fn symmetric_top_precesses_at_the_closed_form_rate() {
    let (m, l, g): (f64, f64, f64) = (1.0, 0.5, 9.81);
    let (ac, c): (f64, f64) = (0.02, 0.04); // transverse inertia about the CG, axial inertia
    let a = ac + m * l * l;
    let theta = 30f64.to_radians();
    let w3 = 60.0;
    let disc = (c * w3).powi(2) - 4.0 * a * theta.cos() * m * g * l;
    let omega_p = (c * w3 - disc.sqrt()) / (2.0 * a * theta.cos());
    // Symmetry axis tilted in the x–z plane; node frame = body principal frame (z = e₃).
    let rot = Rotation::exp(&Vector3::new(0.0, theta, 0.0));
    let e3 = rot.matrix().column(2).into_owned();
    let omega = Vector3::z() * omega_p + e3 * (w3 - omega_p * theta.cos());
    let cg = e3 * l;
    let v = omega.cross(&cg);
    let toml = |step: f64| {
        format!(
            r#"
[model]
name = "symmetric_top"
gravity = [0.0, 0.0, -{g}]
[[nodes]]
name = "top"
position = [{}, {}, {}]
orientation = {{ rotation_vector = [0.0, {theta}, 0.0] }}
velocity = [{}, {}, {}]
angular_velocity = [{}, {}, {}]
[[bodies]]
name = "top"
node = "top"
mass = {m}
inertia = [[{ac}, 0.0, 0.0], [0.0, {ac}, 0.0], [0.0, 0.0, {c}]]
[[joints]]
name = "pivot"
type = "spherical"
node_a = "ground"
node_b = "top"
position = [0.0, 0.0, 0.0]
[[analyses]]
name = "spin"
type = "dynamic"
t_end = 1.0
step = {step}
rho_inf = 1.0
tolerance = 1e-12
"#,
            cg.x, cg.y, cg.z, v.x, v.y, v.z, omega.x, omega.y, omega.z
        )
    };
    let mut rate_errors = Vec::new();
    let mut tilt_errors = Vec::new();
    for step in [1e-3, 5e-4, 2.5e-4] {
        let (_, hist) = run(&model(&toml(step)));
        // Azimuth of the symmetry axis, unwrapped; the tilt must stay at θ.
        let mut max_tilt_error: f64 = 0.0;
        let mut az = Vec::new();
        let mut prev = 0.0f64;
        let mut turns = 0.0;
        for f in &hist.frames {
            let ax = f.state.nodes[0].r().column(2).into_owned();
            max_tilt_error = max_tilt_error.max((ax.z.acos() - theta).abs());
            let raw = ax.y.atan2(ax.x);
            if raw - prev > std::f64::consts::PI {
                turns -= 1.0;
            } else if prev - raw > std::f64::consts::PI {
                turns += 1.0;
            }
            prev = raw;
            az.push((f.time, raw + turns * 2.0 * std::f64::consts::PI));
        }
        let (t1, a1) = az[az.len() - 1];
        let rate = (a1 - az[0].1) / (t1 - az[0].0);
        rate_errors.push((rate - omega_p).abs() / omega_p);
        tilt_errors.push(max_tilt_error);
    }
    // The discrete solution starts on the exact steady motion; the nutation it picks up is
    // a discretization error (spin ω₃h = 0.06 rad per step at the largest step), so it too
    // must fall as h².
    let p = orders(&rate_errors);
    let pt = orders(&tilt_errors);
    eprintln!("Ω_p = {omega_p:.6} rad/s; relative rate errors {rate_errors:?}; orders {p:?}");
    eprintln!("max tilt errors {tilt_errors:?} rad; orders {pt:?}");
    assert!(tilt_errors[2] < 5e-5, "{tilt_errors:?}");
    for o in &pt {
        assert!(*o > 1.7, "tilt orders {pt:?}");
    }
    // Error constant ≈ 1.06e3 s² · h²: at h = 2.5e-4 s the rate must be within 1e-4.
    assert!(rate_errors[2] < 1e-4, "{rate_errors:?}");
    for o in &p {
        assert!((o - 2.0).abs() < 0.3, "orders {p:?}");
    }
}

/// Torque-free rigid body (no gravity, no joints) started spinning about its intermediate
/// principal axis with a small perturbation: it flips periodically (Dzhanibekov). With
/// ρ∞ = 1 the scheme has no numerical dissipation; energy and angular momentum errors must
/// stay bounded (no drift between the first and the last third of the run) and fall as h².
#[test]
fn intermediate_axis_spin_keeps_energy_and_momentum_bounded() {
    let toml = |step: f64| {
        format!(
            r#"
[model]
name = "dzhanibekov"
[[nodes]]
name = "body"
position = [0.0, 0.0, 0.0]
angular_velocity = [0.02, 3.0, 0.01]
[[bodies]]
name = "body"
node = "body"
mass = 1.0
inertia = [[1.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 3.0]]
[[analyses]]
name = "spin"
type = "dynamic"
t_end = 30.0
step = {step}
rho_inf = 1.0
tolerance = 1e-12
"#
        )
    };
    let mut e_err = Vec::new();
    let mut h_err = Vec::new();
    for step in [0.02, 0.01, 0.005] {
        let m = model(&toml(step));
        let sys = System::new(&m);
        let (_, hist) = run(&m);
        let e0 = hist.frames[0].energy.kinetic;
        let h0 = sys.momenta(&hist.frames[0].state).1;
        let n = hist.frames.len();
        let mut max_e = [0.0f64; 3];
        let mut max_h = 0.0f64;
        for (i, f) in hist.frames.iter().enumerate() {
            let de = (f.energy.kinetic - e0).abs() / e0;
            max_e[3 * i / n] = max_e[3 * i / n].max(de);
            max_h = max_h.max((sys.momenta(&f.state).1 - h0).norm() / h0.norm());
        }
        // Flips: the spin axis reverses, so the test covers the whole separatrix motion.
        let w_end = hist.frames[n - 1].state.nodes[0].w;
        eprintln!(
            "step {step}: max |ΔE|/E by thirds {max_e:?}, max |Δh|/|h| {max_h:e}, Ω(T) {w_end:?}"
        );
        // No drift: the last third's worst error is not larger than the first third's
        // worst by more than the oscillation's own variation (factor 2).
        assert!(
            max_e[2] < 2.0 * max_e[0].max(max_e[1]),
            "energy drifts: {max_e:?}"
        );
        e_err.push(max_e.iter().cloned().fold(0.0, f64::max));
        h_err.push(max_h);
    }
    let pe = orders(&e_err);
    let ph = orders(&h_err);
    eprintln!("energy errors {e_err:?} orders {pe:?}; momentum errors {h_err:?} orders {ph:?}");
    for o in pe.iter().chain(&ph) {
        assert!(
            (o - 2.0).abs() < 0.3,
            "orders: energy {pe:?}, momentum {ph:?}"
        );
    }
}
