//! Issue #16: rolling and twisting (drilling) resistance of sphere contacts
//! (`rolling_friction`, `twisting_friction`, `rolling_regularization` in `[[contacts]]` and
//! `[[granular]]`), against the closed forms of rigid-body mechanics with the model's
//! torques (docs/multi-field.md): rolling `M_r = μ_r R_eff N` against the rolling,
//! twisting `M_t = (3π/16) μ_t √(R_eff δ) N` against the spin (Lubkin 1951), both
//! regularized as `ω/√(ω² + ω_ε²)`.
//!
//! A solid sphere (m = 1 kg, ρ = 5 cm, I = 2/5 m ρ² = 1e-3 kg m²) on the ground with LuGre
//! friction that holds rolling without slip (μ_s = 0.5, σ₀ = 1e6 /m):
//! 1. **rolling on level ground** from v₀ = 1 m/s: `a = −μ_r g/(1 + I/(m ρ²)) = −(5/7) μ_r g`,
//!    stops after `v₀²/(2|a|)`;
//! 2. **on an incline** θ: below the rolling-resistance angle (tan θ < μ_r) it holds,
//!    creeping at the regularized law's steady speed `v = ρ ω_ε τ/√(1 − τ²)`,
//!    τ = tan θ/μ_r (so the creep falls with ω_ε: the sphere is at rest as ω_ε → 0); above
//!    it rolls down at `a = (5/7) g (sin θ − μ_r cos θ)`;
//! 3. **spinning about the vertical** from ω₀: `I ω̇ = −(3π/16) μ_t √(ρ δ) m g` with the
//!    static penetration `δ = (m g/k)^(1/e)` (Hunt–Crossley), a constant rate, until it
//!    stops;
//! 4. **a sphere pair**: the same sphere rolling and spinning on top of a clamped sphere of
//!    radius 10 km (`[[contacts]]` with `other_node`, and as a two-sphere `[[granular]]`
//!    set): R_eff = ρ_A ρ_B/(ρ_A + ρ_B) in both closed forms, the rolling about the
//!    pair's contact point (mid-overlap: lever arm ρ_B − δ/2).
//!
//! Tolerances: the closed forms assume a rigid contact and exact saturation; the
//! regularization changes the torque by the factor `1/√(1 + (ω_ε/ω)²)`, below 1e-4 for the
//! speeds used (ω ≥ 1 rad/s, ω_ε = 0.01); generalized-α integrates constant accelerations
//! exactly; the LuGre bristle's transient (≈ 1 ms) and the contact's vertical
//! oscillation (damped within 0.1 s) are over before the measuring window. 1e-3 relative
//! therefore leaves a margin of ≥ 10 over what is expected.

use crate::common;
use common::{first_error, line_of};
use common::{model, run};
use samara::analysis::History;

const G: f64 = 9.81;
const RHO: f64 = 0.05;
const K: f64 = 1e6;

/// Static penetration of the Hunt–Crossley sphere under its weight (e = 1.5).
fn delta_static() -> f64 {
    (G / K).powf(1.0 / 1.5)
}

/// A sphere (1 kg, ρ = 5 cm) resting on the ground plane z = 0 with gravity
/// `gravity`, initial velocity `v`, angular velocity `w`, and the extra contact keys
/// `keys`.
fn sphere(gravity: [f64; 3], v: [f64; 3], w: [f64; 3], keys: &str, t_end: f64) -> String {
    let z = RHO - delta_static();
    format!(
        r#"
[model]
name = "rolling"
gravity = {gravity:?}

[[nodes]]
name = "ball"
position = [0.0, 0.0, {z}]
velocity = {v:?}
angular_velocity = {w:?}

[[bodies]]
name = "ball"
node = "ball"
mass = 1.0
inertia = [[1e-3, 0.0, 0.0], [0.0, 1e-3, 0.0], [0.0, 0.0, 1e-3]]

[[contacts]]
name = "floor"
node = "ball"
shape = "sphere"
radius = {RHO}
normal = "hunt_crossley"
stiffness = {K}
restitution = 0.3
impact_velocity = 1.0
static_friction = 0.5
dynamic_friction = 0.4
stribeck_velocity = 1e-3
bristle_stiffness = 1e6
bristle_damping = 300.0
{keys}

[[analyses]]
name = "roll"
type = "dynamic"
t_end = {t_end}
step = 1e-3
rho_inf = 0.6
"#
    )
}

/// The mean acceleration along x (velocity change) between times t0 and t1.
fn accel_x(h: &History, t0: f64, t1: f64) -> f64 {
    let at = |t: f64| {
        h.frames
            .iter()
            .min_by(|a, b| (a.time - t).abs().total_cmp(&(b.time - t).abs()))
            .unwrap()
    };
    let (a, b) = (at(t0), at(t1));
    (b.state.nodes[0].v[0] - a.state.nodes[0].v[0]) / (b.time - a.time)
}

#[test]
fn a_rolling_sphere_decelerates_at_five_sevenths_mu_r_g_and_stops() {
    let mu_r = 0.1;
    let v0 = 1.0;
    let text = sphere(
        [0.0, 0.0, -G],
        [v0, 0.0, 0.0],
        [0.0, v0 / RHO, 0.0],
        &format!("rolling_friction = {mu_r}"),
        1.8,
    );
    let (_, h) = run(&model(&text));
    let a_ref = -5.0 / 7.0 * mu_r * G;
    let a = accel_x(&h, 0.2, 1.0);
    let stop = v0 * v0 / (2.0 * a_ref.abs());
    let last = &h.last().unwrap().state.nodes[0];
    println!(
        "a = {a:.7} m/s² (closed form {a_ref:.7}, rel. {:.2e}); stopped at x = {:.6} m ({stop:.6}, rel. {:.2e}), |v| = {:.2e} m/s, |ω| = {:.2e} rad/s",
        (a - a_ref).abs() / a_ref.abs(),
        last.x[0],
        (last.x[0] - stop).abs() / stop,
        last.v.norm(),
        last.w.norm()
    );
    assert!((a - a_ref).abs() < 1e-3 * a_ref.abs(), "{a} vs {a_ref}");
    // Stopped (at 1.43 s): the distance of uniform deceleration; at rest to within the
    // regularized law's decay (time constant 1.4 m ρ ω_ε/(μ_r m g) ≈ 7e-5 s).
    assert!(
        (last.x[0] - stop).abs() < 1e-3 * stop,
        "{} vs {stop}",
        last.x[0]
    );
    assert!(last.v.norm() < 1e-6, "{}", last.v.norm());
    // Without the key the sphere rolls on (today's contacts: no resistance).
    let free = sphere(
        [0.0, 0.0, -G],
        [v0, 0.0, 0.0],
        [0.0, v0 / RHO, 0.0],
        "",
        0.5,
    );
    let (_, h) = run(&model(&free));
    let a = accel_x(&h, 0.2, 0.5);
    assert!(a.abs() < 1e-6, "{a}");
}

#[test]
fn on_an_incline_a_sphere_holds_below_the_rolling_angle_and_rolls_down_above_it() {
    let mu_r: f64 = 0.1;
    let tilted = |theta: f64| [G * theta.sin(), 0.0, -G * theta.cos()];
    // Below: tan θ = μ_r/2, creeping at ρ ω_ε τ/√(1 − τ²); with the default ω_ε = 0.01
    // and with ω_ε = 0.001.
    let theta = (0.5 * mu_r).atan();
    let tau: f64 = 0.5;
    for (reg, key) in [
        (0.01, String::new()),
        (1e-3, "rolling_regularization = 1e-3".to_string()),
    ] {
        let text = sphere(
            tilted(theta),
            [0.0; 3],
            [0.0; 3],
            &format!("rolling_friction = {mu_r}\n{key}"),
            0.5,
        );
        let (_, h) = run(&model(&text));
        let creep = RHO * reg * tau / (1.0 - tau * tau).sqrt();
        let v = h.last().unwrap().state.nodes[0].v[0];
        println!(
            "θ = {:.4} rad below the rolling angle, ω_ε = {reg}: creep v = {v:.4e} m/s (closed form {creep:.4e}, rel. {:.2e})",
            theta,
            (v - creep).abs() / creep
        );
        // The steady creep of the regularized law (reached within ≈ 10 ms): 1e-3 relative.
        assert!((v - creep).abs() < 1e-3 * creep, "{v} vs {creep}");
    }
    // Above: tan θ = 2 μ_r.
    let theta = (2.0 * mu_r).atan();
    let text = sphere(
        tilted(theta),
        [0.0; 3],
        [0.0; 3],
        &format!("rolling_friction = {mu_r}"),
        0.6,
    );
    let (_, h) = run(&model(&text));
    let a = accel_x(&h, 0.2, 0.6);
    let a_ref = 5.0 / 7.0 * G * (theta.sin() - mu_r * theta.cos());
    println!(
        "θ = {theta:.4} rad above: a = {a:.7} m/s² (closed form {a_ref:.7}, rel. {:.2e})",
        (a - a_ref).abs() / a_ref
    );
    assert!((a - a_ref).abs() < 1e-3 * a_ref, "{a} vs {a_ref}");
}

#[test]
fn a_sphere_spinning_on_the_floor_stops_its_drilling_at_the_lubkin_rate() {
    let mu_t = 0.4;
    let w0 = 10.0;
    let text = sphere(
        [0.0, 0.0, -G],
        [0.0; 3],
        [0.0, 0.0, w0],
        &format!("twisting_friction = {mu_t}"),
        1.2,
    );
    let (_, h) = run(&model(&text));
    let m_t = 3.0 * std::f64::consts::PI / 16.0 * mu_t * (RHO * delta_static()).sqrt() * G;
    let rate_ref = -m_t / 1e-3;
    let wz = |t: f64| {
        let f = h
            .frames
            .iter()
            .min_by(|a, b| (a.time - t).abs().total_cmp(&(b.time - t).abs()))
            .unwrap();
        ((f.state.nodes[0].r() * f.state.nodes[0].w)[2], f.time)
    };
    let ((w1, t1), (w2, t2)) = (wz(0.1), wz(0.6));
    let rate = (w2 - w1) / (t2 - t1);
    let last = &h.last().unwrap().state.nodes[0];
    println!(
        "spin rate {rate:.6} rad/s² (closed form {rate_ref:.6}, rel. {:.2e}); at {:.2} s |ω| = {:.2e} rad/s (stops at {:.3} s)",
        (rate - rate_ref).abs() / rate_ref.abs(),
        h.last().unwrap().time,
        last.w.norm(),
        w0 / rate_ref.abs()
    );
    assert!(
        (rate - rate_ref).abs() < 1e-3 * rate_ref.abs(),
        "{rate} vs {rate_ref}"
    );
    assert!(last.w.norm() < 1e-4, "{}", last.w.norm());
}

/// Radius of the clamped sphere under the pair's sphere B [m].
const RA: f64 = 1e4;

/// Sphere B (as above) rolling at v₀ and spinning at ω₀ on top of sphere A (ρ_A =
/// 10 km, clamped), through `[[contacts]]` (granular = false) or a `[[granular]]` set.
fn on_a_sphere(granular: bool, keys: &str) -> String {
    let (ra, v0, w0) = (RA, 0.5, 5.0);
    // Resting at the static penetration of the pair, δ = (m g/k)^(2/3).
    let zb = RHO - delta_static();
    let contact = if granular {
        format!(
            r#"[[granular]]
name = "pair"
nodes = ["a", "b"]
radii = [{ra}, {RHO}]
margin = 0.01
ground_point = [0.0, 0.0, -5000.0]"#
        )
    } else {
        format!(
            r#"[[contacts]]
name = "pair"
node = "a"
shape = "sphere"
radius = {ra}
other_node = "b"
other_radius = {RHO}"#
        )
    };
    format!(
        r#"
[model]
name = "on_a_sphere"
gravity = [0.0, 0.0, -9.81]

[[nodes]]
name = "a"
position = [0.0, 0.0, -{ra}]

[[nodes]]
name = "b"
position = [0.0, 0.0, {zb}]
velocity = [{v0}, 0.0, 0.0]
angular_velocity = [0.0, {wy}, {w0}]

[[bodies]]
name = "a"
node = "a"
mass = 100.0
inertia = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]

[[bodies]]
name = "b"
node = "b"
mass = 1.0
inertia = [[1e-3, 0.0, 0.0], [0.0, 1e-3, 0.0], [0.0, 0.0, 1e-3]]

[[joints]]
name = "clamp"
type = "fixed"
node_a = "ground"
node_b = "a"

{contact}
normal = "hunt_crossley"
stiffness = {K}
restitution = 0.3
impact_velocity = 1.0
static_friction = 0.5
dynamic_friction = 0.4
stribeck_velocity = 1e-3
bristle_stiffness = 1e6
bristle_damping = 300.0
{keys}

[[analyses]]
name = "roll"
type = "dynamic"
t_end = 0.4
step = 1e-3
rho_inf = 0.6
"#,
        wy = v0 / RHO,
    )
}

#[test]
fn between_spheres_the_resistance_uses_the_effective_radius() {
    let (mu_r, mu_t) = (0.1, 0.4);
    let r_eff = RA * RHO / (RA + RHO);
    let keys = format!("rolling_friction = {mu_r}\ntwisting_friction = {mu_t}");
    // The pair's normal force is m g and its penetration δ the static one; B spins about
    // the normal (ω̇) at the closed form, and rolls on the pair's contact point, the
    // middle of the overlap (lever arm r = ρ − δ/2, the sphere-pair kernel's), so that
    // `m a r = −(M_r − I a/r)`, `a = −M_r r/(I + m r²)`.
    let delta = delta_static();
    let r = RHO - 0.5 * delta;
    let a_ref = -mu_r * r_eff * G * r / (1e-3 + r * r);
    let rate_ref = -3.0 * std::f64::consts::PI / 16.0 * mu_t * (r_eff * delta).sqrt() * G / 1e-3;
    for granular in [false, true] {
        let (_, h) = run(&model(&on_a_sphere(granular, &keys)));
        let b = |t: f64| {
            let f = h
                .frames
                .iter()
                .min_by(|a, b| (a.time - t).abs().total_cmp(&(b.time - t).abs()))
                .unwrap();
            let n = &f.state.nodes[1];
            (n.v[0], (n.r() * n.w)[2], f.time)
        };
        let ((v1, w1, t1), (v2, w2, t2)) = (b(0.1), b(0.3));
        let (a, rate) = ((v2 - v1) / (t2 - t1), (w2 - w1) / (t2 - t1));
        println!(
            "pair ({}): a = {a:.6} ({a_ref:.6}, rel. {:.2e}), spin rate {rate:.5} ({rate_ref:.5}, rel. {:.2e})",
            if granular { "granular" } else { "contacts" },
            (a - a_ref).abs() / a_ref.abs(),
            (rate - rate_ref).abs() / rate_ref.abs()
        );
        // 1e-3: the tilt of the contact normal on A (x/ρ_A < 2e-5 rad) adds g x/ρ_A
        // ≈ 1e-4 of a; the rest as for the ground.
        assert!((a - a_ref).abs() < 1e-3 * a_ref.abs(), "{a} vs {a_ref}");
        assert!(
            (rate - rate_ref).abs() < 1e-3 * rate_ref.abs(),
            "{rate} vs {rate_ref}"
        );
    }
}

/// Bad input: each new key's errors, located at the key, with a hint.
#[test]
fn bad_rolling_keys_get_located_errors() {
    let base = sphere([0.0, 0.0, -G], [0.0; 3], [0.0; 3], "KEYS", 0.1);
    let point = base.replace("shape = \"sphere\"\nradius = 0.05", "shape = \"point\"");
    let granular = on_a_sphere(true, "KEYS");
    for (text, keys, at, expected) in [
        (
            &base,
            "rolling_friction = -0.1",
            "rolling_friction",
            "`rolling_friction` must be non-negative",
        ),
        (
            &base,
            "twisting_friction = -1.0",
            "twisting_friction",
            "`twisting_friction` must be non-negative",
        ),
        (
            &base,
            "rolling_friction = 0.1\nrolling_regularization = 0.0",
            "rolling_regularization",
            "`rolling_regularization` must be positive",
        ),
        (
            &base,
            "rolling_regularization = 0.1",
            "rolling_regularization",
            "`rolling_regularization` does not apply here",
        ),
        (
            &point,
            "twisting_friction = 0.3",
            "twisting_friction",
            "`twisting_friction` needs a sphere",
        ),
        (
            &granular,
            "rolling_friction = -0.2",
            "rolling_friction",
            "`rolling_friction` must be non-negative",
        ),
        (
            &granular,
            "twisting_friction = 0.2\nrolling_regularization = -1.0",
            "rolling_regularization",
            "`rolling_regularization` must be positive",
        ),
    ] {
        let text = text.replace("KEYS", keys);
        let (line, message, hint) = first_error(&text);
        println!("{message} (line {line}; {hint})");
        assert!(message.contains(expected), "{keys}: {message}");
        assert_eq!(line, line_of(&text, at), "{keys}: {message}");
        assert!(!hint.is_empty());
    }
    // Statics cannot hold rolling resistance (it vanishes at rest): at the analysis type.
    let friction = "static_friction = 0.5\ndynamic_friction = 0.4\nstribeck_velocity = 1e-3\nbristle_stiffness = 1e6\nbristle_damping = 300.0\n";
    assert!(base.contains(friction));
    let text = base
        .replace(friction, "")
        .replace("KEYS", "rolling_friction = 0.1")
        .replace("type = \"dynamic\"", "type = \"static\"");
    let Err(e) = samara::model::Model::from_toml_str(&text, "bad.toml") else {
        panic!("statics with rolling resistance accepted")
    };
    assert!(
        e.errors()
            .any(|d| d.message.contains("a static analysis cannot hold")),
        "{e}"
    );
}
