//! Elements with states against closed forms and independent integrations (issue #11),
//! through model files: the low-pass sensor (sine and ramp responses, and a feedback loop
//! closed through a joint's input port), and the Maxwell element (relaxation, the energy
//! its damper dissipates, and a mass on a Maxwell element).
//!
//! The time integrator is generalized-α (second order for the nodes, first-order
//! generalized-α for the states, also second order), so the tests check the error's
//! convergence rate (2 ± 0.25 when the step is halved) and its size at the finest step.
//! References nobody here wrote: the closed-form solutions of the linear ODEs, and
//! classical fourth-order Runge–Kutta at 1/20 of the finest step (its error, O(h⁴), is
//! below 1e-10 and negligible against the O(h²) errors measured).

use crate::common;
use common::{model, run};
use samara::analysis::History;
use samara::system::System;
use std::f64::consts::PI;

/// The value of element state `name` (`element.state`) in every frame.
fn state_series(toml: &str, name: &str) -> (History, Vec<(f64, f64)>) {
    let m = model(toml);
    let sys = System::new(&m);
    let k = sys
        .state_names
        .iter()
        .position(|n| n == name)
        .unwrap_or_else(|| panic!("no state {name} in {:?}", sys.state_names));
    let (_, h) = run(&m);
    let series = h
        .frames
        .iter()
        .map(|f| (f.time, f.state.states[k].z))
        .collect();
    (h, series)
}

/// Largest |numeric − exact| over the frames.
fn max_error(series: &[(f64, f64)], exact: impl Fn(f64) -> f64) -> f64 {
    series
        .iter()
        .map(|&(t, z)| (z - exact(t)).abs())
        .fold(0.0, f64::max)
}

/// Errors at steps h, h/2, h/4 → (observed orders, finest error).
fn convergence(errors: &[f64]) -> (Vec<f64>, f64) {
    let orders = errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
    (orders, *errors.last().unwrap())
}

fn assert_second_order(what: &str, errors: &[f64], finest_bound: f64) {
    let (orders, finest) = convergence(errors);
    let shown: Vec<String> = errors.iter().map(|e| format!("{e:.2e}")).collect();
    println!("{what}: errors {shown:?}, orders {orders:.3?}");
    for p in &orders {
        assert!(
            (p - 2.0).abs() < 0.25,
            "{what}: order {p} (errors {errors:?})"
        );
    }
    assert!(finest < finest_bound, "{what}: error {finest:e}");
}

/// A node held by a fixed joint, with a body, so that a model of signals and sensors has
/// a well-posed mechanical part.
const HELD_NODE: &str = r#"
[[nodes]]
name = "post"
position = [0.0, 0.0, 0.0]
[[bodies]]
name = "post"
node = "post"
mass = 1.0
inertia = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
[[joints]]
name = "base"
type = "fixed"
node_a = "ground"
node_b = "post"
position = [0.0, 0.0, 0.0]
"#;

/// τ ż + z = g A sin ωt, z(0) = 0:
/// z = g A / (1 + (ωτ)²) [sin ωt − ωτ cos ωt + ωτ e^{−t/τ}].
#[test]
fn low_pass_sensor_follows_the_sine_response() {
    let (amp, f, tau, g) = (1.5, 2.0, 0.05, 2.0);
    let w = 2.0 * PI * f;
    let exact = |t: f64| {
        let wt = w * tau;
        g * amp / (1.0 + wt * wt) * ((w * t).sin() - wt * (w * t).cos() + wt * (-t / tau).exp())
    };
    let errors: Vec<f64> = [4e-3, 2e-3, 1e-3]
        .iter()
        .map(|h| {
            let toml = format!(
                r#"[model]
name = "low_pass"
{HELD_NODE}
[[signals]]
name = "u"
function = {{ type = "sine", amplitude = {amp}, frequency = {f} }}
[[sensors]]
name = "filtered"
signal = "u"
time_constant = {tau}
gain = {g}
[[analyses]]
name = "run"
type = "dynamic"
t_end = 0.5
step = {h}
rho_inf = 0.6
"#
            );
            let (_, s) = state_series(&toml, "filtered.output");
            max_error(&s, exact)
        })
        .collect();
    // Amplitude g A/√(1+(ωτ)²) ≈ 2.5; measured 3.4e-5 at h = 1e-3 (h ω = 0.013).
    assert_second_order("sine response", &errors, 1e-4);
}

/// A body falling freely (v = −g₀ t, integrated exactly by generalized-α) seen through a
/// velocity sensor starting settled (z(0) = g·v(0) = 0): the ramp response
/// z = −g₀ [t − τ (1 − e^{−t/τ})].
#[test]
fn velocity_sensor_follows_the_ramp_response() {
    let (g0, tau) = (9.81, 0.04);
    let exact = |t: f64| -g0 * (t - tau * (1.0 - (-t / tau).exp()));
    let errors: Vec<f64> = [4e-3, 2e-3, 1e-3]
        .iter()
        .map(|h| {
            let toml = format!(
                r#"[model]
name = "falling"
gravity = [0.0, 0.0, -{g0}]
[[nodes]]
name = "stone"
position = [0.0, 0.0, 0.0]
[[bodies]]
name = "stone"
node = "stone"
mass = 2.0
inertia = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
[[sensors]]
name = "vz"
node = "stone"
quantity = "velocity"
component = "z"
time_constant = {tau}
[[analyses]]
name = "run"
type = "dynamic"
t_end = 0.4
step = {h}
rho_inf = 0.8
"#
            );
            let (h, s) = state_series(&toml, "vz.output");
            // The body itself falls exactly: the sensor's error is the filter's.
            let last = h.frames.last().unwrap();
            assert!((last.state.nodes[0].v.z + g0 * last.time).abs() < 1e-9);
            max_error(&s, exact)
        })
        .collect();
    assert_second_order("ramp response", &errors, 2e-5);
}

/// Classical RK4 for y' = f(y) from 0 to t_end with n steps, keeping every `every`-th
/// value.
fn rk4<const N: usize>(
    f: impl Fn(&[f64; N]) -> [f64; N],
    y0: [f64; N],
    t_end: f64,
    n: usize,
) -> Vec<[f64; N]> {
    let h = t_end / n as f64;
    let mut y = y0;
    let mut out = vec![y];
    let axpy = |y: &[f64; N], k: &[f64; N], s: f64| {
        let mut r = *y;
        for i in 0..N {
            r[i] += s * k[i];
        }
        r
    };
    for _ in 0..n {
        let k1 = f(&y);
        let k2 = f(&axpy(&y, &k1, h / 2.0));
        let k3 = f(&axpy(&y, &k2, h / 2.0));
        let k4 = f(&axpy(&y, &k3, h));
        for i in 0..N {
            y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
        out.push(y);
    }
    out
}

/// RK4 reference sampled at multiples of `h` (which divides the RK4 step count).
fn sample<const N: usize>(reference: &[[f64; N]], t_end: f64, t: f64, i: usize) -> f64 {
    let n = reference.len() - 1;
    let k = (t / t_end * n as f64).round() as usize;
    assert!((k as f64 * t_end / n as f64 - t).abs() < 1e-9);
    reference[k][i]
}

/// A cart on a prismatic joint with a spring, pushed by the signal of a low-pass sensor
/// of its own position (feedback through the joint's input port):
/// m q̈ + k q = z, τ ż + z = g q, q(0) = 0, q̇(0) = v₀, z(0) = 0; against RK4.
#[test]
fn feedback_loop_through_an_input_port_matches_rk4() {
    let (m, k, tau, g, v0, t_end) = (2.0, 50.0, 0.02, -30.0, 1.0, 1.0);
    let reference = rk4(
        |y: &[f64; 3]| [y[1], (-k * y[0] + y[2]) / m, (g * y[0] - y[2]) / tau],
        [0.0, v0, 0.0],
        t_end,
        20_000,
    );
    let errors: Vec<f64> = [4e-3, 2e-3, 1e-3]
        .iter()
        .map(|h| {
            let toml = format!(
                r#"[model]
name = "feedback"
[[nodes]]
name = "cart"
position = [0.0, 0.0, 0.0]
velocity = [{v0}, 0.0, 0.0]
[[bodies]]
name = "cart"
node = "cart"
mass = {m}
inertia = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
[[joints]]
name = "rail"
type = "prismatic"
node_a = "ground"
node_b = "cart"
position = [0.0, 0.0, 0.0]
axis = [1.0, 0.0, 0.0]
[joints.d3]
stiffness = {k}
input = "position_feedback"
[[sensors]]
name = "position_feedback"
node = "cart"
quantity = "position"
component = "x"
time_constant = {tau}
gain = {g}
[[analyses]]
name = "run"
type = "dynamic"
t_end = {t_end}
step = {h}
rho_inf = 0.8
"#
            );
            let m = model(&toml);
            let (_, hist) = run(&m);
            hist.frames
                .iter()
                .map(|f| (f.state.nodes[0].x.x - sample(&reference, t_end, f.time, 0)).abs())
                .fold(0.0, f64::max)
        })
        .collect();
    // Amplitude ≈ v₀/ω ≈ 0.2 m; measured 4.0e-6 m at h = 1e-3.
    assert_second_order("feedback loop", &errors, 1.2e-5);
}

/// A Maxwell element stretched by e and held (its end fixed): z = e (1 − e^{−t k/c}), the
/// tension k (e − z) relaxes as k e e^{−t k/c}, and the damper dissipates the spring's
/// energy: dissipated(t) + ½ T²/k = ½ k e² at every t (to the O(h²) accuracy of the
/// energy's trapezoidal integral), ½ k e² (1 − e^{−2tk/c}) dissipated.
#[test]
fn maxwell_element_relaxes_and_dissipates_the_spring_energy() {
    let (k, c, e) = (1000.0, 10.0, 0.1);
    let rate = k / c;
    let exact_z = |t: f64| e * (1.0 - (-rate * t).exp());
    let mut z_errors = Vec::new();
    let mut energy_errors = Vec::new();
    for h in [1e-3, 5e-4, 2.5e-4] {
        let toml = format!(
            r#"[model]
name = "relaxation"
[[nodes]]
name = "end"
position = [1.0, 0.0, 0.0]
[[bodies]]
name = "end"
node = "end"
mass = 1.0
inertia = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
[[joints]]
name = "clamp"
type = "fixed"
node_a = "ground"
node_b = "end"
position = [1.0, 0.0, 0.0]
[[viscoelastic]]
name = "pad"
type = "maxwell"
node_a = "ground"
node_b = "end"
point_a = [0.0, 0.0, 0.0]
stiffness = {k}
damping = {c}
rest_length = {}
[[analyses]]
name = "run"
type = "dynamic"
t_end = 0.05
step = {h}
rho_inf = 0.6
"#,
            1.0 - e
        );
        let (hist, s) = state_series(&toml, "pad.damper_stretch");
        z_errors.push(max_error(&s, exact_z));
        let total = 0.5 * k * e * e;
        energy_errors.push(
            hist.frames
                .iter()
                .map(|f| {
                    let dissipated = 0.5 * k * e * e * (1.0 - (-2.0 * rate * f.time).exp());
                    let stored = f.energy.potential;
                    (f.energy.dissipated - dissipated)
                        .abs()
                        .max((f.energy.dissipated + stored - total).abs())
                })
                .fold(0.0, f64::max)
                / total,
        );
        // Relaxed at the end (5 time constants): the tension is k e e^{−5}.
        let (t_last, z_last) = *s.last().unwrap();
        assert!((t_last - 0.05).abs() < 1e-12);
        assert!((k * (e - z_last) - k * e * (-5.0f64).exp()).abs() < 0.02 * k * e);
    }
    // Stretch error relative to e: measured 1.9e-5 at h = τ/40.
    assert_second_order("relaxation", &z_errors, 6e-5 * e);
    assert_second_order("dissipated energy", &energy_errors, 5e-4);
}

/// A mass on a rail tied to the ground by a Maxwell element, launched with v₀:
/// m q̈ = −k (q − z), c ż = k (q − z); against RK4, and the energy balance
/// kinetic + stored + dissipated = ½ m v₀².
#[test]
fn mass_on_a_maxwell_element_matches_rk4() {
    let (m, k, c, v0, t_end) = (1.0, 100.0, 2.0, 1.0, 1.0);
    let reference = rk4(
        |y: &[f64; 3]| {
            let t = k * (y[0] - y[2]);
            [y[1], -t / m, t / c]
        },
        [0.0, v0, 0.0],
        t_end,
        20_000,
    );
    let mut q_errors = Vec::new();
    let mut balance = 0.0f64;
    for h in [4e-3, 2e-3, 1e-3] {
        let toml = format!(
            r#"[model]
name = "maxwell_oscillator"
[[nodes]]
name = "mass"
position = [1.0, 0.0, 0.0]
velocity = [{v0}, 0.0, 0.0]
[[bodies]]
name = "mass"
node = "mass"
mass = {m}
inertia = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
[[joints]]
name = "rail"
type = "prismatic"
node_a = "ground"
node_b = "mass"
position = [1.0, 0.0, 0.0]
axis = [1.0, 0.0, 0.0]
[[viscoelastic]]
name = "mount"
type = "maxwell"
node_a = "ground"
node_b = "mass"
point_a = [0.0, 0.0, 0.0]
stiffness = {k}
damping = {c}
[[analyses]]
name = "run"
type = "dynamic"
t_end = {t_end}
step = {h}
rho_inf = 0.9
"#
        );
        let (hist, s) = state_series(&toml, "mount.damper_stretch");
        let mut err: f64 = 0.0;
        for (f, &(t, z)) in hist.frames.iter().zip(&s) {
            err = err
                .max((f.state.nodes[0].x.x - 1.0 - sample(&reference, t_end, t, 0)).abs())
                .max((z - sample(&reference, t_end, t, 2)).abs());
        }
        q_errors.push(err);
        let e0 = 0.5 * m * v0 * v0;
        for f in &hist.frames {
            let e = f.energy.kinetic + f.energy.potential + f.energy.dissipated;
            balance = balance.max((e - e0).abs() / e0);
        }
    }
    // Amplitude ≈ v₀/ω = 0.1 m; measured 1.6e-6 m at h = 1e-3.
    assert_second_order("Maxwell oscillator", &q_errors, 5e-6);
    // The balance at the coarsest step (ρ∞ = 0.9 adds a little numerical dissipation on
    // top of the damper's): within 1 %.
    assert!(balance < 1e-2, "energy balance {balance:e}");
}

/// The other measured quantities and the `initial` option, one closed form each (step
/// 1e-3, τ = 0.05):
/// - acceleration of a falling body, u = −g₀ from a start at 0: z = −g₀ (1 − e^{−t/τ});
/// - angular velocity of a body spinning freely about its symmetry axis, settled: z = ω;
/// - a zero signal from `initial = 1`: z = e^{−t/τ}.
#[test]
fn sensor_quantities_and_initial_value_follow_their_closed_forms() {
    let (g0, w, tau) = (9.81, 3.0, 0.05);
    let toml = format!(
        r#"[model]
name = "sensors"
gravity = [0.0, 0.0, -{g0}]
[[nodes]]
name = "stone"
position = [0.0, 0.0, 0.0]
angular_velocity = [0.0, 0.0, {w}]
[[bodies]]
name = "stone"
node = "stone"
mass = 2.0
inertia = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 2.0]]
[[signals]]
name = "zero"
function = {{ type = "constant", value = 0.0 }}
[[sensors]]
name = "az"
node = "stone"
quantity = "acceleration"
component = "z"
time_constant = {tau}
[[sensors]]
name = "wz"
node = "stone"
quantity = "angular_velocity"
component = "z"
time_constant = {tau}
gain = 2.0
[[sensors]]
name = "decay"
signal = "zero"
time_constant = {tau}
initial = 1.0
[[analyses]]
name = "run"
type = "dynamic"
t_end = 0.3
step = 1e-3
rho_inf = 0.8
"#
    );
    let m = model(&toml);
    let sys = System::new(&m);
    let (_, hist) = run(&m);
    let idx = |n: &str| sys.state_names.iter().position(|s| s == n).unwrap();
    let (ia, iw, id) = (idx("az.output"), idx("wz.output"), idx("decay.output"));
    let (mut ea, mut ew, mut ed) = (0.0f64, 0.0f64, 0.0f64);
    for f in &hist.frames {
        let t = f.time;
        let z = |i: usize| f.state.states[i].z;
        // The acceleration's initial value is the consistent −g₀ (the filter starts at 0).
        ea = ea.max((z(ia) + g0 * (1.0 - (-t / tau).exp())).abs());
        ew = ew.max((z(iw) - 2.0 * w).abs());
        ed = ed.max((z(id) - (-t / tau).exp()).abs());
    }
    println!("acceleration {ea:.2e}, angular velocity {ew:.2e}, initial value {ed:.2e}");
    // Filter errors O((h/τ)²) of the values (g₀ and 1), h/τ = 0.02: measured 1.2e-5
    // relative.
    assert!(ea < 5e-5 * g0, "acceleration sensor error {ea:e}");
    assert!(ew < 1e-12, "angular velocity sensor error {ew:e}");
    assert!(ed < 5e-5, "initial value error {ed:e}");
}
