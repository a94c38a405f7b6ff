//! Issue #16: sensors on results quantities — element outputs (`output =
//! "<element>.<output>"`, read in the same Newton iteration) and joint reactions
//! (`reaction` = force/moment with `component`, or a coordinate's `quantity = "force"`,
//! held from the converged solution).
//!
//! References (closed forms, each test states its tolerance):
//! - a spring-damper's tension T = k (L − L0) + c L̇ from the node states, and its
//!   derivatives ∂T/∂x_b = k e + c (I − e eᵀ)(v_b − v_a)/L, ∂T/∂v_b = c e;
//! - the first-order filter τ ż + z = g u driven by u = a + b sin ωt:
//!   z = g a + (z0 − g a) e^(−t/τ) + g b/(1 + (ωτ)²) (sin ωt − ωτ cos ωt + ωτ e^(−t/τ));
//! - the damped oscillator m ẍ + c' ẋ + k' x = F under a step (the closed loop of a P
//!   controller on a spring's tension);
//! - the actuator force of a driven body under gravity, F = m (g + f'').

use crate::common;
use common::{model, orders, run};
use samara::model::Model;
use samara::system::System;
use std::f64::consts::PI;

/// Signal `name` at a recorded frame.
fn signal(sys: &System, f: &samara::analysis::Frame, name: &str) -> f64 {
    let id = sys
        .signals
        .names
        .iter()
        .position(|n| n == name)
        .unwrap_or_else(|| panic!("no signal {name}"));
    sys.signal_values(&sys.context(f.time, 1.0), &f.state)[id]
}

/// Element state `name` at a frame.
fn state(sys: &System, f: &samara::analysis::Frame, name: &str) -> f64 {
    let i = sys.state_names.iter().position(|n| n == name).unwrap();
    f.state.states[i].z
}

/// τ ż + z = g (a + b sin ωt), z(0) = z0.
fn filtered_sine(t: f64, tau: f64, g: f64, a: f64, b: f64, w: f64, z0: f64) -> f64 {
    let e = (-t / tau).exp();
    let wt = w * tau;
    g * a
        + (z0 - g * a) * e
        + g * b / (1.0 + wt * wt) * ((w * t).sin() - wt * (w * t).cos() + wt * e)
}

const K: f64 = 1000.0;
const AMP: f64 = 0.1;
const FREQ: f64 = 2.0;
const TAU: f64 = 0.05;
const GAIN: f64 = 0.5;

fn driven_spring(step: f64) -> Model {
    model(&format!(
        r#"
[model]
name = "driven spring"
gravity = [0.0, 0.0, 0.0]
[[nodes]]
name = "b"
position = [1.0, 0.0, 0.0]
[[bodies]]
name = "b"
node = "b"
mass = 1.0
inertia = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
[[joints]]
name = "rail"
type = "prismatic"
node_a = "ground"
node_b = "b"
position = [1.0, 0.0, 0.0]
axis = [1.0, 0.0, 0.0]
[joints.d3]
drive = {{ type = "sine", amplitude = {AMP}, frequency = {FREQ} }}
[[springs]]
name = "spring"
node_a = "ground"
node_b = "b"
point_a = [0.0, 0.0, 0.0]
stiffness = {K}
[[sensors]]
name = "tension"
output = "spring.tension"
[[sensors]]
name = "filtered"
output = "spring.tension"
time_constant = {TAU}
gain = {GAIN}
[[analyses]]
name = "run"
type = "dynamic"
t_end = 0.5
step = {step}
"#
    ))
}

/// An unfiltered sensor on a spring's tension is k (L − L0) from the node positions at
/// every frame (L0 = 1 m, the initial length). Both sides are the same arithmetic on
/// the same state, so they agree to round-off: 1e-10 of k·L0 = 1000 N.
///
/// The filtered sensor on the same tension, T(t) = k A sin ωt (the end driven along the
/// spring), follows the closed-form first-order response; its error falls at second
/// order (generalized-α on the filter state), ratio ≈ 4 per halving, and is below 3e-5 of
/// the amplitude g k A at h = 1 ms (measured 1.0e-5; (h/τ)²/12 ≈ 3e-5 bounds the
/// transient's error, (ωh)²/12 ≈ 1.3e-6 the sine's).
#[test]
fn a_sensor_reads_a_spring_tension_and_filters_it() {
    let w = 2.0 * PI * FREQ;
    let scale = GAIN * K * AMP;
    let mut errors = Vec::new();
    for step in [2e-3, 1e-3, 5e-4] {
        let m = driven_spring(step);
        let (_, h) = run(&m);
        let sys = System::new(&m);
        let mut worst = 0.0f64;
        for f in &h.frames {
            let l = f.state.nodes[0].x.norm();
            let t = signal(&sys, f, "tension");
            assert!(
                (t - K * (l - 1.0)).abs() < 1e-10 * K,
                "t = {}: sensor {t} vs k (L − L0) = {}",
                f.time,
                K * (l - 1.0)
            );
            let z = state(&sys, f, "filtered.output");
            let exact = filtered_sine(f.time, TAU, GAIN, 0.0, K * AMP, w, 0.0);
            worst = worst.max((z - exact).abs() / scale);
            // The filtered sensor's signal is its state.
            assert_eq!(signal(&sys, f, "filtered"), z);
        }
        println!("h = {step}: filter error {worst:.3e} of g k A");
        errors.push(worst);
    }
    let o = orders(&errors);
    println!("orders {o:.2?}");
    assert!(o.iter().all(|&p| (1.8..2.3).contains(&p)), "{o:?}");
    assert!(errors[1] < 3e-5, "{errors:?}");
}

/// The signal graph's derivatives of a sensor reading a spring-damper's tension against
/// the closed form: for an unfiltered sensor of gain g, ∂s/∂x_b = g (k e + c (I − e eᵀ)
/// v_rel / L), ∂s/∂v_b = g c e (the nodes' translational columns; the rotational ones
/// vanish for attachment points at the nodes, and ∂/∂x_a = −∂/∂x_b). The central
/// difference with step u^(1/3) max(1, |x|) is accurate to ~1e-10 of the entries
/// (truncation (h²/6)·T''' and round-off u |T| / h); 1e-7 of the largest entry is
/// above both and far below any wrong column.
#[test]
fn the_output_signal_derivatives_match_the_closed_form() {
    let (k, c, g) = (2.5e4, 37.0, -1.7);
    let m = model(&format!(
        r#"
[model]
name = "tangent"
gravity = [0.0, 0.0, 0.0]
[[nodes]]
name = "a"
position = [0.1, -0.2, 0.3]
velocity = [0.4, 0.1, -0.3]
[[nodes]]
name = "b"
position = [1.3, 0.7, -0.4]
velocity = [-0.2, 0.9, 0.5]
angular_velocity = [1.0, -2.0, 0.5]
[[bodies]]
name = "a"
node = "a"
mass = 1.0
inertia = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
[[bodies]]
name = "b"
node = "b"
mass = 1.0
inertia = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
[[springs]]
name = "s"
node_a = "a"
node_b = "b"
stiffness = {k}
damping = {c}
rest_length = 1.1
[[sensors]]
name = "probe"
output = "s.tension"
gain = {g}
[[analyses]]
name = "run"
type = "dynamic"
t_end = 0.01
step = 1e-3
"#
    ));
    let sys = System::new(&m);
    let state = sys.initial_state();
    let ctx = sys.context(0.0, 1.0);
    let mut v = sys.signals.values(&sys.elements);
    sys.signals.evaluate(
        &sys.elements,
        &sys.state_offsets,
        &ctx,
        &state,
        &mut v,
        true,
    );
    let id = sys.signals.names.iter().position(|n| n == "probe").unwrap();
    let (na, nb) = (&state.nodes[0], &state.nodes[1]);
    let d = nb.x - na.x;
    let l = d.norm();
    let e = d / l;
    let vr = nb.v - na.v;
    let tension = k * (l - 1.1) + c * e.dot(&vr);
    assert!((v.values[id] - g * tension).abs() < 1e-12 * tension.abs());
    let proj = (nalgebra::Matrix3::identity() - e * e.transpose()) * vr / l;
    let dx = (k * e + c * proj) * g;
    let dv = c * e * g;
    // Support: the 12 node unknowns of the spring.
    let support = &sys.signals.support[id];
    assert_eq!(support, &(0..12).collect::<Vec<_>>());
    let grad = &v.gradients[id];
    let big = dx.amax().max(dv.amax());
    let mut worst = 0.0f64;
    for i in 0..3 {
        for (col, want) in [
            (i, [-dx[i], -dv[i], 0.0]),
            (6 + i, [dx[i], dv[i], 0.0]),
            (3 + i, [0.0; 3]),
            (9 + i, [0.0; 3]),
        ] {
            for ch in 0..3 {
                worst = worst.max((grad[col][ch] - want[ch]).abs() / big);
            }
        }
    }
    println!("largest relative mismatch {worst:.2e}");
    assert!(worst < 1e-7, "{worst:e}");
}

/// A P controller holds a spring's tension at a set point through a joint's input force:
/// u = kp (T_ref − T), T = k x + c ẋ the tension read by an unfiltered sensor in the same
/// Newton iteration. The closed loop is m ẍ + c (1 + kp) ẋ + k (1 + kp) x = kp T_ref,
/// steady tension kp/(1 + kp) T_ref; from rest, x(t) is the closed-form step response of
/// the damped oscillator (ω_n = 20 rad/s, ζ = 0.2). The displacement error falls at
/// second order (ratio ≈ 4 per halving) and is below 1e-4 of x∞ at h = 1 ms (measured
/// 6.3e-5: a phase error (ω_n h)²/12 ≈ 3e-5 per radian over ~3 periods, damped); at
/// t = 3 s (e^(−ζ ω_n t) = 6e-6) with h = 10 ms the tension is within 1e-4 of the steady
/// value (measured 4.5e-6).
#[test]
fn a_loop_closed_through_a_spring_tension_follows_the_closed_form() {
    let (m_b, k, c, kp, t_ref) = (1.0f64, 100.0f64, 2.0f64, 3.0f64, 40.0f64);
    let text = |step: f64, t_end: f64| {
        format!(
            r#"
[model]
name = "tension loop"
gravity = [0.0, 0.0, 0.0]
[[nodes]]
name = "b"
position = [1.0, 0.0, 0.0]
[[bodies]]
name = "b"
node = "b"
mass = {m_b}
inertia = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
[[joints]]
name = "rail"
type = "prismatic"
node_a = "ground"
node_b = "b"
position = [1.0, 0.0, 0.0]
axis = [1.0, 0.0, 0.0]
[joints.d3]
input = "u"
[[springs]]
name = "spring"
node_a = "ground"
node_b = "b"
point_a = [0.0, 0.0, 0.0]
stiffness = {k}
damping = {c}
[[signals]]
name = "set_point"
function = {{ type = "constant", value = {t_ref} }}
[[sensors]]
name = "tension"
output = "spring.tension"
[[controllers]]
name = "u"
type = "sum"
inputs = ["set_point", "tension"]
weights = [{kp}, {nkp}]
[[analyses]]
name = "run"
type = "dynamic"
t_end = {t_end}
step = {step}
rho_inf = 0.9
"#,
            nkp = -kp
        )
    };
    let wn = (k * (1.0 + kp) / m_b).sqrt();
    let zeta = c * (1.0 + kp) / (2.0 * m_b * wn);
    let wd = wn * (1.0 - zeta * zeta).sqrt();
    let x_inf = kp * t_ref / (k * (1.0 + kp));
    let exact = |t: f64| {
        let e = (-zeta * wn * t).exp();
        x_inf * (1.0 - e * ((wd * t).cos() + zeta * wn / wd * (wd * t).sin()))
    };
    let mut errors = Vec::new();
    for step in [2e-3, 1e-3, 5e-4] {
        let (_, h) = run(&model(&text(step, 1.0)));
        let worst = h
            .frames
            .iter()
            .map(|f| (f.state.nodes[0].x.x - 1.0 - exact(f.time)).abs())
            .fold(0.0, f64::max);
        println!("h = {step}: displacement error {:.3e} of x∞", worst / x_inf);
        errors.push(worst / x_inf);
    }
    let o = orders(&errors);
    println!("orders {o:.2?}");
    assert!(o.iter().all(|&p| (1.8..2.3).contains(&p)), "{o:?}");
    assert!(errors[1] < 1e-4, "{errors:?}");
    let m = model(&text(1e-2, 3.0));
    let (_, h) = run(&m);
    let sys = System::new(&m);
    let f = h.last().unwrap();
    let settled = kp / (1.0 + kp) * t_ref;
    let t = signal(&sys, f, "tension");
    println!("steady tension {t} vs {settled}");
    assert!((t - settled).abs() < 1e-4 * settled, "{t} vs {settled}");
}

const MASS: f64 = 2.0;
const G: f64 = 9.81;
const LIFT_AMP: f64 = 0.05;
const LIFT_FREQ: f64 = 1.0;
const RATE: f64 = 20.0;

fn lift(step: f64) -> Model {
    model(&format!(
        r#"
[model]
name = "lift"
gravity = [0.0, 0.0, {ng}]
[[nodes]]
name = "b"
position = [0.0, 0.0, 0.0]
[[bodies]]
name = "b"
node = "b"
mass = {MASS}
inertia = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
[[joints]]
name = "lift"
type = "prismatic"
node_a = "ground"
node_b = "b"
position = [0.0, 0.0, 0.0]
axis = [0.0, 0.0, 1.0]
[joints.d3]
drive = {{ type = "sine", amplitude = {LIFT_AMP}, frequency = {LIFT_FREQ} }}
[[sensors]]
name = "load_cell"
joint = "lift"
coordinate = "d3"
quantity = "force"
sample_rate = {RATE}
[[sensors]]
name = "reaction_z"
joint = "lift"
reaction = "force"
component = "z"
sample_period = {period}
[[sensors]]
name = "reaction_mx"
joint = "lift"
reaction = "moment"
component = "x"
sample_rate = {RATE}
[[sensors]]
name = "lagged"
joint = "lift"
coordinate = "d3"
quantity = "force"
time_constant = {TAU}
initial = {f0}
[[analyses]]
name = "run"
type = "dynamic"
t_end = 1.0
step = {step}
formulation = "stabilized_index2"
"#,
        ng = -G,
        period = 1.0 / RATE,
        f0 = MASS * G,
    ))
}

/// A load cell on a drive: the actuator force of a body of mass m lifted along the
/// vertical by ν = A sin ωt under gravity is F = m (g − A ω² sin ωt). A sensor sampling
/// it at 20 Hz holds F(t_k) over [t_k, t_(k+1)): at every frame its signal is F(⌊t/T⌋ T).
/// At a sample instant the reaction is taken from the consistent accelerations at the
/// converged state, so with the motion prescribed it is the closed form to round-off
/// (1e-12 of m g); the reaction force's z component (frame A = global here) gives the
/// same, the moment is zero, and both equal what the results write at the sample
/// instants.
///
/// Without a sample rate a sensor sees the reaction of the last converged step: a
/// filtered one (τ = 0.05 s) lags the closed-form response z(t) by exactly one step,
/// z_h(t) ≈ z(t) − h ż(t). Its error against z is first order (ratio ≈ 2 per halving);
/// with the one-step lag taken out it is second order (ratio ≈ 4; 1.9e-5 of m g at
/// h = 1 ms, bound 3e-5, against h |ż| ≈ 1e-3 m g for the lag itself). The stabilized
/// index-2 formulation is used: index-3 multipliers with ρ∞ = 0.9 oscillate from step to
/// step by ~0.5 % here (as the results' joint_coordinate_force do), which the filter
/// would see.
#[test]
fn a_load_cell_on_a_drive_holds_the_actuator_force() {
    let w = 2.0 * PI * LIFT_FREQ;
    let force = |t: f64| MASS * (G - LIFT_AMP * w * w * (w * t).sin());
    let period = 1.0 / RATE;
    let (a, b) = (MASS * G, -MASS * LIFT_AMP * w * w);
    let z_exact = |t: f64| filtered_sine(t, TAU, 1.0, a, b, w, MASS * G);
    let zd_exact = |t: f64| (a + b * (w * t).sin() - z_exact(t)) / TAU;
    let (mut raw, mut delayed) = (Vec::new(), Vec::new());
    for step in [2e-3, 1e-3, 5e-4] {
        let m = lift(step);
        let (_, h) = run(&m);
        let sys = System::new(&m);
        let mut worst = 0.0f64;
        let (mut e_raw, mut e_delayed) = (0.0f64, 0.0f64);
        for f in &h.frames {
            let tk = (f.time / period + 1e-9).floor() * period;
            let held = signal(&sys, f, "load_cell");
            worst = worst.max((held - force(tk)).abs() / (MASS * G));
            assert!(
                worst < 1e-12,
                "t = {}: held {held} vs F(t_k) = {}",
                f.time,
                force(tk)
            );
            assert_eq!(signal(&sys, f, "reaction_z"), held, "t = {}", f.time);
            assert!(signal(&sys, f, "reaction_mx").abs() < 1e-9 * MASS * G);
            let on_sample = (f.time - tk).abs() < 1e-12;
            if on_sample {
                // The results' actuator force and reaction at the same instant.
                assert!((f.coordinate_forces[0] - held).abs() < 1e-12 * MASS * G);
                assert!((f.reactions[0].0.z - held).abs() < 1e-12 * MASS * G);
            }
            let z = state(&sys, f, "lagged.output");
            e_raw = e_raw.max((z - z_exact(f.time)).abs() / (MASS * G));
            let lag = if f.time > 0.0 { step } else { 0.0 };
            e_delayed =
                e_delayed.max((z - z_exact(f.time) + lag * zd_exact(f.time)).abs() / (MASS * G));
        }
        for k in 0..=20 {
            let tk = k as f64 * period;
            assert!(
                h.frames.iter().any(|f| (f.time - tk).abs() < 1e-12),
                "t_{k} missed"
            );
        }
        println!(
            "h = {step}: held force error {worst:.2e}, lagged filter {e_raw:.2e}, without the lag {e_delayed:.2e} (of m g)"
        );
        if step == 1e-3 {
            assert!(e_delayed < 3e-5, "{e_delayed:e}");
        }
        raw.push(e_raw);
        delayed.push(e_delayed);
    }
    let (o_raw, o_delayed) = (orders(&raw), orders(&delayed));
    println!("orders: lagged {o_raw:.2?}, lag removed {o_delayed:.2?}");
    assert!(o_raw.iter().all(|&p| (0.9..1.2).contains(&p)), "{o_raw:?}");
    assert!(o_delayed.iter().all(|&p| p > 1.7), "{o_delayed:?}");
}

/// Each element sees only its own sample-and-hold values: the held joint reactions are
/// stored after the elements' held values and belong to no element (whichever element
/// comes last must not see them).
#[test]
fn each_element_sees_only_its_own_held_values() {
    let m = lift(1e-3);
    let sys = System::new(&m);
    let mut st = sys.initial_state();
    sys.sample(&mut st, true);
    assert_eq!(st.held.len(), sys.n_held);
    assert!(!sys.signals.reactions.is_empty(), "held joint reactions");
    for (k, e) in sys.elements.iter().enumerate() {
        assert_eq!(sys.held_of(k, &st).len(), e.n_held(), "{}", e.name());
    }
}

/// Bad input: located errors with a hint, never a panic.
#[test]
fn bad_output_and_reaction_sensors_are_located_errors() {
    let base = r#"
[model]
name = "bad"
gravity = [0.0, 0.0, -9.81]
[[nodes]]
name = "b"
position = [1.0, 0.0, 0.0]
[[bodies]]
name = "b"
node = "b"
mass = 1.0
inertia = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
[[joints]]
name = "rail"
type = "prismatic"
node_a = "ground"
node_b = "b"
position = [1.0, 0.0, 0.0]
axis = [1.0, 0.0, 0.0]
[joints.d3]
stiffness = 10.0
[[springs]]
name = "spring"
node_a = "ground"
node_b = "b"
point_a = [0.0, 0.0, 0.0]
stiffness = 100.0
"#;
    let dynamic = "[[analyses]]\nname = \"run\"\ntype = \"dynamic\"\nt_end = 0.1\nstep = 1e-3\n";
    let cases: &[(&str, &str, &[&str])] = &[
        (
            "[[sensors]]\nname = \"s\"\noutput = \"sprung.tension\"\n",
            dynamic,
            &[
                "unknown element output 'sprung.tension'",
                "did you mean 'spring.tension'?",
                "bad.toml:",
            ],
        ),
        (
            "[[sensors]]\nname = \"s\"\noutput = \"spring.force\"\n",
            dynamic,
            &[
                "unknown element output 'spring.force'",
                "'spring' has outputs tension, length",
            ],
        ),
        (
            "[[sensors]]\nname = \"s\"\njoint = \"rial\"\nreaction = \"force\"\ncomponent = \"z\"\n",
            dynamic,
            &["unknown joint 'rial'", "did you mean 'rail'?"],
        ),
        (
            "[[sensors]]\nname = \"s\"\njoint = \"rail\"\nreaction = \"moment\"\n",
            dynamic,
            &["a reaction measurement needs `joint` and `component`"],
        ),
        (
            "[[sensors]]\nname = \"s\"\njoint = \"rail\"\nreaction = \"force\"\ncomponent = \"x\"\ncoordinate = \"d3\"\n",
            dynamic,
            &["`reaction` takes no `coordinate` or `quantity`"],
        ),
        (
            "[[sensors]]\nname = \"s\"\njoint = \"rail\"\ncoordinate = \"d4\"\nquantity = \"force\"\n",
            dynamic,
            &[
                "unknown coordinate 'd4'",
                "one of d1, d2, d3, theta1, theta2, theta3",
            ],
        ),
        (
            "[[sensors]]\nname = \"s\"\njoint = \"rail\"\ncoordinate = \"d3\"\ncomponent = \"x\"\n",
            dynamic,
            &["`component` is for node quantities and joint reactions"],
        ),
        (
            "[[sensors]]\nname = \"s\"\nnode = \"b\"\nquantity = \"force\"\ncomponent = \"x\"\n",
            dynamic,
            &["a node has no `force` quantity"],
        ),
        (
            "[[sensors]]\nname = \"s\"\njoint = \"rail\"\nreaction = \"force\"\ncomponent = \"x\"\n",
            "[[analyses]]\nname = \"equilibrium\"\ntype = \"static\"\n",
            &["reads a joint reaction, which a static analysis ('equilibrium') cannot give it"],
        ),
        (
            "[[sensors]]\nname = \"s\"\njoint = \"rail\"\ncoordinate = \"d3\"\nquantity = \"force\"\n",
            "[[analyses]]\nname = \"equilibrium\"\ntype = \"static\"\n",
            &["static analysis ('equilibrium')"],
        ),
        (
            "[[sensors]]\nname = \"s\"\noutput = \"spring.tension\"\nstate = \"x.y\"\n",
            dynamic,
            &["give exactly one of"],
        ),
    ];
    for (sensor, analysis, wanted) in cases {
        let text = format!("{base}{sensor}{analysis}");
        let msg = match Model::from_toml_str(&text, "bad.toml") {
            Ok(_) => panic!("accepted:\n{sensor}"),
            Err(e) => e.render_plain(),
        };
        for w in *wanted {
            assert!(msg.contains(w), "{sensor}: expected '{w}' in\n{msg}");
        }
        assert!(msg.contains("bad.toml:"), "not located:\n{msg}");
    }
    // The same sensors are accepted in a dynamic analysis and static analyses take an
    // element output.
    let ok = format!(
        "{base}[[sensors]]\nname = \"s\"\noutput = \"spring.tension\"\n[[analyses]]\nname = \"eq\"\ntype = \"static\"\n"
    );
    let m = model(&ok);
    let (_, h) = run(&m);
    let sys = System::new(&m);
    let f = h.last().unwrap();
    let l = f.state.nodes[0].x.norm();
    assert!((signal(&sys, f, "s") - 100.0 * (l - 1.0)).abs() < 1e-9);
}
