//! Issue #16, verification 6: the tire (`[[tires]]`).
//!
//! References nobody here wrote:
//! - the Magic Formula itself (Pacejka, *Tire and Vehicle Dynamics*, 3rd ed., 2012,
//!   §4.3.2): `F_y = μ F_z sin(C arctan(B α − E (B α − arctan B α)))`, the pneumatic trail
//!   `t = D_t cos(C_t arctan(B_t α − E_t(B_t α − arctan B_t α))) cos α`, `M_z = −t F_y`,
//!   written out again here;
//! - the first-order relaxation of the slip (Pacejka §7.2.1): at constant speed V_x and a
//!   slip angle switched on at t = 0, `tan α'(t) = tan α (1 − exp(−V_x t/σ_α))`;
//! - the momentum balance of a braked sled: `Σ m v_x(t) − Σ m v_x(0) = ∫₀ᵗ F_x dt`, and its
//!   skid at the locked-wheel force `F_x(κ = −1)`;
//! - the coast-down of a freely rolling wheel with rolling resistance:
//!   `V̇ = −f_r R₀ F_z / (J/R_e + h M)` (h the hub height, M the rolling mass).
//!
//! The wheel runs on a flat-track rig (hub fixed by a revolute to the ground, the ground
//! moving under it), so the slip angle, speed and load are exactly known.

use crate::common;
use common::{model, model_file, orders, run};
use samara::analysis::History;
use samara::elements::EvalContext;
use samara::model::{AnalysisKind, Model};
use samara::system::System;

const R0: f64 = 0.3;
const RE: f64 = 0.29;
const K: f64 = 2e5;
const DELTA: f64 = 0.01;
const V: f64 = 10.0;
const SIGMA_A: f64 = 0.3;

/// `sin` or `cos` of `C arctan(B x − E (B x − arctan B x))`.
fn mf_angle(b: f64, c: f64, e: f64, x: f64) -> f64 {
    let bx = b * x;
    c * (bx - e * (bx - bx.atan())).atan()
}

/// The flat-track rig: the wheel's hub is held by a revolute to the ground at height
/// R₀ − δ, the belt moves at V at slip angle α under it, and the wheel spins at the
/// rolling speed.
fn rig(alpha_deg: f64, step: f64, t_end: f64, extra: &str) -> String {
    let a = alpha_deg.to_radians();
    let (vx, vy) = (V * a.cos(), -V * a.sin());
    format!(
        r#"
[model]
name = "rig"
gravity = [0.0, 0.0, -9.81]
[[nodes]]
name = "wheel"
position = [0.0, 0.0, {h}]
angular_velocity = [0.0, {w}, 0.0]
[[bodies]]
name = "wheel"
node = "wheel"
mass = 15.0
inertia = [[0.4, 0.0, 0.0], [0.0, 0.6, 0.0], [0.0, 0.0, 0.4]]
[[joints]]
name = "axle"
type = "revolute"
node_a = "ground"
node_b = "wheel"
axis = [0.0, 1.0, 0.0]
{extra}
[[tires]]
name = "tire"
hub = "axle"
radius = {R0}
rolling_radius = {RE}
vertical_stiffness = {K}
longitudinal_relaxation_length = 0.1
lateral_relaxation_length = {SIGMA_A}
longitudinal = {{ B = 10.0, C = 1.9, mu = 1.0, E = 0.97 }}
lateral = {{ B = 10.0, C = 1.3, mu = 1.0, E = 0.97 }}
trail = {{ B = 8.0, C = 1.2, D = 0.04, E = -0.5 }}
ground_velocity = [{gx}, {gy}, 0.0]
[[analyses]]
name = "roll"
type = "dynamic"
t_end = {t_end}
step = {step}
rho_inf = 0.8
"#,
        h = R0 - DELTA,
        w = vx / RE,
        gx = -vx,
        gy = -vy,
    )
}

/// Element outputs of the frames, by name.
fn outputs(m: &Model, h: &History, names: &[&str]) -> Vec<Vec<f64>> {
    let sys = System::new(m);
    let idx: Vec<usize> = names
        .iter()
        .map(|n| {
            sys.output_names
                .iter()
                .position(|o| o == n)
                .unwrap_or_else(|| panic!("no output {n}: {:?}", sys.output_names))
        })
        .collect();
    let mut out = vec![0.0; sys.output_names.len()];
    h.frames
        .iter()
        .map(|f| {
            let ctx = EvalContext {
                time: f.time,
                gravity: m.gravity,
                load_factor: 1.0,
            };
            sys.element_outputs(&ctx, &f.state, &mut out);
            idx.iter().map(|&i| out[i]).collect()
        })
        .collect()
}

/// Steady state at fixed slip angles: F_y against the Magic Formula at F_z = k δ and
/// M_z = −t F_y against the trail formula; the slip ratio stays zero. The relaxation ODE's
/// fixed point is exact for the integrator too (it is the fixed point of the discrete
/// step), and after 16 time constants the state is within exp(−16) ≈ 1e-7 of it: the
/// tolerance is 1e-6 relative.
#[test]
fn steady_lateral_force_and_aligning_moment_follow_the_magic_formula() {
    let fz = K * DELTA;
    for alpha_deg in [-4.0, 1.0, 3.0, 6.0, 10.0] {
        let a: f64 = f64::to_radians(alpha_deg);
        let m = model(&rig(alpha_deg, 1e-3, 0.5, ""));
        let (_, h) = run(&m);
        let o = outputs(
            &m,
            &h,
            &[
                "tire.normal_force",
                "tire.lateral_force",
                "tire.aligning_moment",
                "tire.slip_angle",
                "tire.slip_ratio",
                "tire.deflection",
            ],
        );
        let last = o.last().unwrap();
        let fy = fz * mf_angle(10.0, 1.3, 0.97, a).sin();
        let t = 0.04 * mf_angle(8.0, 1.2, -0.5, a).cos() * a.cos();
        let mz = -t * fy;
        println!(
            "α = {alpha_deg}°: F_z {:.3} ({fz}), F_y {:.4} vs {fy:.4}, M_z {:.5} vs {mz:.5}, α' {:.6} rad, κ' {:.2e}",
            last[0], last[1], last[2], last[3], last[4]
        );
        assert!((last[0] - fz).abs() < 1e-9 * fz);
        assert!((last[5] - DELTA).abs() < 1e-9, "{}", last[5]);
        assert!((last[1] - fy).abs() < 1e-6 * fz, "{} {fy}", last[1]);
        assert!((last[2] - mz).abs() < 1e-6 * fz * 0.04, "{} {mz}", last[2]);
        assert!((last[3] - a).abs() < 1e-6 * a.abs());
        assert!(last[4].abs() < 1e-9);
    }
}

/// The relaxation lag: tan α'(t) against tan α (1 − exp(−V cos α t/σ_α)) over five time
/// constants, at three steps. The states are integrated by generalized-α (second order):
/// the error converges at order 2 ± 0.3 and is below 1e-3 of tan α at h = τ/60.
#[test]
fn relaxation_lag_is_first_order_with_time_constant_sigma_over_v() {
    let alpha_deg: f64 = 5.0;
    let a = alpha_deg.to_radians();
    let tau = SIGMA_A / (V * a.cos());
    let mut errors = Vec::new();
    for step in [2e-3, 1e-3, 5e-4] {
        let m = model(&rig(alpha_deg, step, 5.0 * tau, ""));
        let (_, h) = run(&m);
        let o = outputs(&m, &h, &["tire.slip_angle"]);
        let err = h
            .frames
            .iter()
            .zip(&o)
            .map(|(f, v)| {
                let exact = a.tan() * (1.0 - (-f.time / tau).exp());
                (v[0].tan() - exact).abs()
            })
            .fold(0.0, f64::max)
            / a.tan();
        errors.push(err);
    }
    let p = orders(&errors);
    println!("relaxation lag (τ = {tau:.4} s): errors {errors:?}, orders {p:?}");
    assert!(p.iter().all(|&q| (q - 2.0).abs() < 0.3), "{p:?}");
    assert!(errors[2] < 1e-3, "{errors:?}");
}

/// The brake torque input: examples/contact/tire_braking.toml. The brake locks the wheel
/// (slip ratio → −1, spin ≈ 0) and the sled skids to a stop. Up to the stop, the sled's
/// loss of momentum equals the friction impulse ∫F_x dt (trapezoid over the frames;
/// tolerance 2e-4 of the initial momentum: the integrator's velocity update weighs the
/// step's end forces by γ = 0.5 + α_f − α_m instead of ½, an O(h²) difference at the
/// brake's ramp and the lock); the stop time against m V₀/|F_x(κ = −1)| within 4 % (the
/// 0.1 s before the brake acts, the wheel's 30 ms spin-down and the relaxation over
/// σ_κ = 0.1 m are outside that estimate and are added to it).
#[test]
fn braking_to_a_stop_closes_the_momentum_balance() {
    let m = model_file("examples/contact/tire_braking.toml");
    let (_, h) = run(&m);
    let o = outputs(
        &m,
        &h,
        &[
            "tire.longitudinal_force",
            "tire.slip_ratio",
            "tire.normal_force",
            "tire.brake_torque",
        ],
    );
    let masses = [5.0, 280.0, 15.0];
    let momentum = |k: usize| -> f64 {
        h.frames[k]
            .state
            .nodes
            .iter()
            .zip(masses)
            .map(|(n, m)| m * n.v[0])
            .sum()
    };
    let p0 = momentum(0);
    let stop = h
        .frames
        .iter()
        .position(|f| f.state.nodes[0].v[0] <= 0.0)
        .expect("the sled stops");
    let mut impulse = 0.0;
    let mut worst: f64 = 0.0;
    for k in 1..=stop {
        let dt = h.frames[k].time - h.frames[k - 1].time;
        impulse += 0.5 * dt * (o[k][0] + o[k - 1][0]);
        worst = worst.max((momentum(k) - p0 - impulse).abs());
    }
    let t_stop = h.frames[stop].time;
    let fz = 295.0 * 9.81;
    let locked = fz * mf_angle(10.0, 1.9, 0.97, -1.0).sin();
    let estimate = 0.1 + 300.0 * 10.0 / locked.abs();
    // Mid-skid: wheel locked.
    let mid = h.at(0.6).unwrap();
    let k_mid = h.frames.iter().position(|f| f.time == mid.time).unwrap();
    println!(
        "stop at {t_stop:.4} s (estimate {estimate:.4} s); momentum balance {:.2e} of p0; mid-skid κ' {:.4}, F_z {:.1}, F_x {:.1} (locked {locked:.1}), brake {:.1} N m, spin {:.3} rad/s",
        worst / p0,
        o[k_mid][1],
        o[k_mid][2],
        o[k_mid][0],
        o[k_mid][3],
        mid.state.nodes[2].w[1]
    );
    assert!(worst < 2e-4 * p0, "{worst}");
    assert!((t_stop - estimate).abs() < 0.04 * estimate);
    assert!((o[k_mid][1] + 1.0).abs() < 0.02, "{}", o[k_mid][1]);
    assert!((o[k_mid][0] - locked).abs() < 0.01 * locked.abs());
    assert!(mid.state.nodes[2].w[1].abs() < 0.5);
}

/// Rolling resistance: the sled of tire_braking.toml without the brake coasts down at
/// V̇ = −f_r R₀ F_z/(J/R_e + h M) (rolling without slip; the slip ratio that carries the
/// force, M V̇ / (B C μ F_z) ≈ 1e-3, changes the rate by that much). Tolerance 0.5 %.
#[test]
fn rolling_resistance_coast_down_matches_the_closed_form() {
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../examples/contact/tire_braking.toml"),
    )
    .unwrap()
    .replace("brake = \"brake\"\n", "")
    .replace("rolling_resistance = 0.01", "rolling_resistance = 0.02");
    let m = model(&text);
    let (_, h) = run(&m);
    let (f0, f1) = (h.at(0.3).unwrap(), h.at(1.5).unwrap());
    let decel = (f0.state.nodes[0].v[0] - f1.state.nodes[0].v[0]) / (f1.time - f0.time);
    let fz = 295.0 * 9.81;
    let hub = 0.3 - fz / 2e5;
    let exact = 0.02 * 0.3 * fz / (0.6 / 0.29 + hub * 300.0);
    println!("coast-down: {decel:.6} m/s², closed form {exact:.6}");
    assert!((decel - exact).abs() < 5e-3 * exact, "{decel} {exact}");
}

/// The hub revolute's coordinate input port takes a signal: a torque on θ3 spins the
/// lifted wheel up at T/J (the tire is out of contact and exerts nothing).
#[test]
fn a_signal_drives_the_hub_coordinate() {
    let text = rig(
        0.0,
        1e-3,
        0.5,
        "[joints.theta3]\ninput = \"drive\"\n[[signals]]\nname = \"drive\"\nfunction = { type = \"constant\", value = 3.0 }\n",
    )
    .replace("ground_velocity", "ground_point = [0.0, 0.0, -1.0]\nground_velocity");
    let m = model(&text);
    let (_, h) = run(&m);
    let last = h.last().unwrap();
    let w0 = V / RE;
    let exact = w0 + 3.0 / 0.6 * last.time;
    let w = last.state.nodes[0].w[1];
    println!("spin-up: {w:.9} rad/s, closed form {exact:.9}");
    assert!((w - exact).abs() < 1e-9 * exact);
    if let AnalysisKind::Dynamic(d) = &m.analyses[0].kind {
        assert!((last.time - d.t_end).abs() < 1e-12);
    }
}

/// The brake law with its regularization: while the wheel is held locked, its spin
/// settles where the brake torque balances the tire: `T_b tanh(R_e ω/v_ε) = h |F_x| −
/// f_r R₀ F_z` (h the hub height); ω measured at mid-skid for v_ε = 0.05 and 0.01 m/s
/// against that closed form with the measured forces. Tolerance 2 %: the wheel's own
/// deceleration term J ω̇ is left out of the balance.
#[test]
fn locked_wheel_creep_follows_the_brake_regularization() {
    let base = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../examples/contact/tire_braking.toml"),
    )
    .unwrap();
    for ve in [0.05, 0.01] {
        let m = model(&base.replace(
            "brake = \"brake\"\n",
            &format!("brake = \"brake\"\nregularization_speed = {ve}\n"),
        ));
        let (_, h) = run(&m);
        let o = outputs(&m, &h, &["tire.longitudinal_force", "tire.normal_force"]);
        let k = h.frames.iter().position(|f| f.time >= 0.6).unwrap();
        let (fx, fz) = (o[k][0], o[k][1]);
        let hub = h.frames[k].state.nodes[2].x[2];
        let w = h.frames[k].state.nodes[2].w[1];
        let t = (hub * fx.abs() - 0.01 * 0.3 * fz) / 1500.0;
        let exact = ve / 0.29 * t.atanh();
        println!("v_ε = {ve}: locked-wheel spin {w:.5} rad/s, closed form {exact:.5}");
        assert!((w - exact).abs() < 0.02 * exact, "{w} {exact}");
    }
}

/// A ground plane tilted by 30° (normal, hub axis, belt velocity and hub position all
/// rotated together): the same steady lateral force and aligning moment as on level
/// ground.
#[test]
fn a_tilted_ground_gives_the_same_tire_forces() {
    let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
    let a = 4f64.to_radians();
    let level = rig(4.0, 1e-3, 0.5, "");
    let hgt = R0 - DELTA;
    let (vx, vy) = (V * a.cos(), -V * a.sin());
    let w = vx / RE;
    let tilted = level
        .replace(
            &format!("position = [0.0, 0.0, {hgt}]"),
            &format!("position = [0.0, {}, {}]", -s * hgt, c * hgt),
        )
        .replace(
            &format!("angular_velocity = [0.0, {w}, 0.0]"),
            &format!("angular_velocity = [0.0, {}, {}]", c * w, s * w),
        )
        .replace("axis = [0.0, 1.0, 0.0]", &format!("axis = [0.0, {c}, {s}]"))
        .replace(
            &format!("ground_velocity = [{}, {}, 0.0]", -vx, -vy),
            &format!(
                "ground_normal = [0.0, {}, {c}]\nground_velocity = [{}, {}, {}]",
                -s,
                -vx,
                -vy * c,
                -vy * s
            ),
        );
    assert_ne!(level, tilted);
    let names = [
        "tire.lateral_force",
        "tire.aligning_moment",
        "tire.normal_force",
    ];
    let ml = model(&level);
    let mt = model(&tilted);
    let ol = outputs(&ml, &run(&ml).1, &names);
    let ot = outputs(&mt, &run(&mt).1, &names);
    let (l, t) = (ol.last().unwrap(), ot.last().unwrap());
    println!("level {l:?}, tilted {t:?}");
    for i in 0..3 {
        assert!((l[i] - t[i]).abs() < 1e-6 * l[i].abs(), "{l:?} {t:?}");
    }
}

/// Bad tire input gets a located error with a hint, at the key or set that is wrong.
#[test]
fn bad_tire_input_is_rejected_where_it_is_written() {
    let base = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../examples/contact/tire_braking.toml"),
    )
    .unwrap();
    let long = "longitudinal = { B = 10.0, C = 1.9, mu = 1.0, E = 0.97 }";
    let lat = "lateral = { B = 10.0, C = 1.3, mu = 1.0, E = 0.97 }";
    let trail = "trail = { B = 8.0, C = 1.2, D = 0.04, E = -0.5 }";
    let cases: &[(&str, &str, &str)] = &[
        (
            long,
            "longitudinal = { B = 10.0, C = 1.9, mu = 1.0 }",
            "the Pacejka coefficient `E` is missing",
        ),
        (
            lat,
            "lateral = { C = 1.3, mu = 1.0, E = 0.97 }",
            "the Pacejka coefficient `B` is missing",
        ),
        (
            lat,
            "lateral = { B = 10.0, C = 1.3, E = 0.97 }",
            "the Pacejka coefficient `D` is missing",
        ),
        (
            trail,
            "trail = { B = 8.0, C = 1.2, E = -0.5 }",
            "the Pacejka coefficient `D` is missing",
        ),
        (
            lat,
            "lateral = { B = 10.0, C = 1.3, mu = 1.0, D = 3000.0, E = 0.97 }",
            "give either `mu` or `D`",
        ),
        (
            lat,
            "lateral = { B = 10.0, C = 1.3, D = 3000.0, E = 0.97 }",
            "needs the tire's `nominal_load`",
        ),
        (
            long,
            "longitudinal = { B = 10.0, C = 1.9, mu = 1.0, E = 1.5 }",
            "`E` must be at most 1",
        ),
        (
            long,
            "longitudinal = { B = -10.0, C = 1.9, mu = 1.0, E = 0.97 }",
            "`B` must be positive",
        ),
        (
            trail,
            "trail = { B = 8.0, C = 1.2, D = 0.04, E = -0.5, mu = 1.0 }",
            "`mu` does not apply to the trail",
        ),
        (
            "hub = \"axle\"",
            "hub = \"rail\"",
            "is a prismatic joint, not a revolute",
        ),
        ("hub = \"axle\"", "hub = \"axel\"", "unknown joint 'axel'"),
        (
            "brake = \"brake\"",
            "brake = \"brakes\"",
            "unknown signal 'brakes'",
        ),
        (
            "radius = 0.3 ",
            "radius = -0.3 ",
            "`radius` must be positive",
        ),
        (
            "vertical_damping = 3000.0",
            "vertical_damping = -1.0",
            "`vertical_damping` must be non-negative",
        ),
        (
            "longitudinal_relaxation_length = 0.1",
            "longitudinal_relaxation_length = 0.0",
            "`longitudinal_relaxation_length` must be positive",
        ),
        (
            "rolling_resistance = 0.01",
            "rolling_resistance = -0.01",
            "`rolling_resistance` must be non-negative",
        ),
        (
            "brake = \"brake\"",
            "brake = \"brake\"\nground_velocity = [0.0, 0.0, 1.0]",
            "`ground_velocity` must lie in the ground plane",
        ),
        (
            "brake = \"brake\"",
            "brake = \"brake\"\nground_normal = [0.0, 1.0, 0.0]",
            "the hub axis is along the ground normal",
        ),
    ];
    for (from, to, message) in cases {
        assert!(base.contains(from), "{from}");
        let text = base.replacen(from, to, 1);
        let Err(e) = Model::from_toml_str(&text, "bad.toml") else {
            panic!("accepted: {to}")
        };
        let d = e.errors().next().expect("an error");
        let span = d.span.clone().expect("a located error");
        let (line, _) = e.source.line_col(span.start);
        let hint = d.hint.clone().unwrap_or_default();
        // The error is on the replaced text's line (the hub for the axis check).
        let needle = if message.contains("along the ground normal") {
            "hub = \"axle\""
        } else {
            to.lines().last().unwrap()
        };
        let want = text[..text.find(needle).unwrap()].matches('\n').count() + 1;
        println!("{line}: {} (hint: {hint})", d.message);
        assert!(d.message.contains(message), "{}", d.message);
        assert_eq!(line, want, "{}", d.message);
        assert!(!hint.is_empty());
    }
}

/// The sled of tire_braking.toml at a crawl with its wheel clamped (a stiff torsion spring
/// on the hub, no brake, no rolling resistance): the slip state is the tread deflection
/// u = σ_κ κ' = −x (σ κ̇' = −V_sx = −ẋ, the |V_x| κ' term of relative size x/σ ≈ 1e-3),
/// and the force `F_x = C (κ' − c_low ẋ)` (C = B C μ F_z, the Magic Formula linear at
/// |κ| ≈ 1e-3) makes the sled a damped oscillator
/// `M ẍ + C c_low ẋ + (C/σ) x = 0` (Pacejka 2012, §8.6: without the damping the tire is an
/// undamped spring at standstill). Sled velocity against the closed form from ẋ(0) = v₀,
/// x(0) = 0, over 0.5 s (3.4 periods): tolerance 1 % of v₀ (the neglected |V_x| κ', of
/// relative size x/σ ≈ 1e-3 per cycle, a slight amplitude-dependent damping that adds up to
/// 0.6 % of v₀ over the undamped run; the curvature of the formula, 1e-4; the step's phase
/// error (ω h)²/12 per radian ≈ 4e-5 over 21 rad at h = 0.5 ms); without the damping the
/// sled keeps rocking.
#[test]
fn low_speed_damping_makes_the_standstill_tire_a_damped_oscillator() {
    let v0 = 0.005;
    let base = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../examples/contact/tire_braking.toml"),
    )
    .unwrap()
    .replace("brake = \"brake\"\n", "")
    .replace("rolling_resistance = 0.01", "rolling_resistance = 0.0")
    .replace(
        "velocity = [10.0, 0.0, 0.0]",
        &format!("velocity = [{v0}, 0.0, 0.0]"),
    )
    .replace(
        "angular_velocity = [0.0, 34.48275862068966, 0.0]",
        "angular_velocity = [0.0, 0.0, 0.0]",
    )
    .replace(
        "# spin axis: forward is axis × ground normal = +x",
        "\n[joints.theta3]\nstiffness = 1e9",
    )
    .replace("t_end = 1.5", "t_end = 0.5")
    .replace("step = 1e-3", "step = 5e-4");
    assert!(base.contains("stiffness = 1e9"));
    let damped = base.replace(
        "rolling_resistance = 0.0",
        "rolling_resistance = 0.0\nlow_speed_damping = 0.1\nlow_speed = 1.0",
    );
    let mass = 300.0;
    for (text, c_low) in [(&damped, 0.1), (&base, 0.0)] {
        let m = model(text);
        let (_, h) = run(&m);
        let fz = outputs(&m, &h, &["tire.normal_force"])[0][0];
        let c = 10.0 * 1.9 * 1.0 * fz;
        let omega = (c / (0.1 * mass)).sqrt();
        let zeta = c * c_low / (2.0 * mass * omega);
        let wd = omega * (1.0 - zeta * zeta).sqrt();
        let mut worst = 0.0f64;
        for f in &h.frames {
            let t = f.time;
            let exact = v0
                * (-zeta * omega * t).exp()
                * ((wd * t).cos() - zeta * omega / wd * (wd * t).sin());
            worst = worst.max((f.state.nodes[0].v[0] - exact).abs());
        }
        let late = h
            .frames
            .iter()
            .filter(|f| f.time > 0.35)
            .map(|f| f.state.nodes[0].v[0].abs())
            .fold(0.0, f64::max);
        println!(
            "c_low = {c_low}: ω = {omega:.3} rad/s, ζ = {zeta:.4}; velocity error {:.2e} of v₀; late amplitude {:.3} v₀",
            worst / v0,
            late / v0
        );
        assert!(worst < 1e-2 * v0, "{worst}");
        if c_low == 0.0 {
            assert!(late > 0.95 * v0, "undamped: keeps rocking");
        } else {
            assert!(late < 0.15 * v0, "damped: {late}");
        }
    }
}

/// Out of contact the slip states relax to zero: the braked sled's wheel skids with
/// κ' ≈ −1, then a force lifts the carrier off the ground; from the first frame out of
/// contact κ'(t) = κ'(t₁) exp(−(V + v_ε)(t − t₁)/σ_κ) (the sled coasts at constant V).
/// Tolerance 2e-3 of κ'(t₁): the trapezoidal-like step's error (h/τ)²/12 with
/// τ = σ/(V + v_ε) ≈ 15 ms and h = 0.25 ms.
#[test]
fn slip_states_relax_to_zero_out_of_contact() {
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../examples/contact/tire_braking.toml"),
    )
    .unwrap()
    .replace("t_end = 1.5", "t_end = 0.65")
    .replace("step = 1e-3", "step = 2.5e-4")
        + r#"
[[forces]]
name = "lift"
node = "carrier"
force = [0.0, 0.0, 8000.0]
function = { type = "table", points = [[0.0, 0.0], [0.5, 0.0], [0.51, 1.0]] }
"#;
    let m = model(&text);
    let (_, h) = run(&m);
    let o = outputs(&m, &h, &["tire.deflection", "tire.slip_ratio"]);
    let k1 = o
        .iter()
        .position(|r| r[0] <= 0.0)
        .expect("the tire leaves the ground");
    let (t1, kappa1) = (h.frames[k1].time, o[k1][1]);
    let v = h.frames[k1].state.nodes[2].v[0];
    let mut worst = 0.0f64;
    for (f, r) in h.frames.iter().zip(&o).skip(k1) {
        assert!(r[0] <= 0.0, "stays in the air");
        let exact = kappa1 * (-(v + 0.05) * (f.time - t1) / 0.1).exp();
        worst = worst.max((r[1] - exact).abs());
    }
    let last = o.last().unwrap()[1];
    println!(
        "lift-off at {t1:.4} s with κ' = {kappa1:.4}, V = {v:.3} m/s; error {:.2e} of κ'(t₁); κ' at the end {last:.2e}",
        worst / kappa1.abs()
    );
    assert!(kappa1 < -0.9, "locked before lift-off");
    assert!(worst < 2e-3 * kappa1.abs(), "{worst}");
}
