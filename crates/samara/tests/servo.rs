//! Issue #16: a signal as a joint drive — the servo row ν − s(x) = 0 (`drive_signal`).
//!
//! References:
//! - the same time function as `drive` and as a `[[signals]]` entry read by
//!   `drive_signal` give the same run (the servo row with a signal that touches no
//!   unknown is the drive row: same Φ, same Jacobian, same f′ and f″ in the initial
//!   conditions);
//! - examples/control/servo_follower.toml: a carriage commanded by a first-order
//!   controller reading a bob that hangs from it on a spring is the linear ODE
//!   m_S ẍ_S = −k (x_S − s) − m_S g, τ ṡ = K x_S − s, ν = s, whose solution is the matrix
//!   exponential of its (affine) system matrix (nalgebra's Padé exponential, accurate to
//!   round-off for this 4×4 matrix with ‖A t‖ ≤ 80: scaling and squaring); the actuator
//!   force is m_P (ν̈ + g) + m_S (ẍ_S + g) from the same solution;
//! - the system's Jacobian B (with −∂s/∂x on the servo row) against central differences
//!   of the constraint values Φ = ν − s: tests/system_matrices.rs (`servo_follower`).

use crate::common;
use common::*;
use nalgebra::{Matrix4, Vector4};
use samara::model::Model;
use samara::system::System;

/// The four-bar (examples/four_bar.toml) with its crank driven by `drive` (a time
/// function) and by `drive_signal` (the same function as a `[[signals]]` entry): the
/// same run to the bit. The closed loop has redundant rows, so this covers the servo row
/// among dropped constraint rows too.
#[test]
fn signal_time_function_as_drive_equals_the_drive() {
    let text = example_model_text("examples/four_bar.toml")
        + "\n[[analyses]]\nname = \"turn\"\ntype = \"dynamic\"\nt_end = 1.0\nstep = 2e-3\nrho_inf = 0.9\n";
    let drive = r#"drive = { type = "polynomial", coefficients = [0.0, 6.283185307179586] }"#;
    assert!(text.contains(drive));
    let servo = text.replace(drive, r#"drive_signal = "crank_angle""#)
        + r#"
[[signals]]
name = "crank_angle"
function = { type = "polynomial", coefficients = [0.0, 6.283185307179586] }
"#;
    let (a, b) = (model(&text), model(&servo));
    let (sa, ha) = run(&a);
    let (sb, hb) = run(&b);
    assert_eq!(sa.steps, sb.steps);
    assert_eq!(ha.frames.len(), hb.frames.len());
    assert!(ha.frames.len() > 400);
    for (fa, fb) in ha.frames.iter().zip(&hb.frames) {
        for (na, nb) in fa.state.nodes.iter().zip(&fb.state.nodes) {
            assert_eq!(na.x, nb.x, "t = {}", fa.time);
            assert_eq!(na.v, nb.v, "t = {}", fa.time);
            assert_eq!(na.a, nb.a, "t = {}", fa.time);
        }
        assert_eq!(
            fa.coordinate_forces, fb.coordinate_forces,
            "t = {}",
            fa.time
        );
        assert_eq!(fa.reactions, fb.reactions, "t = {}", fa.time);
    }
    // The crank's actuator torque is there (not zero): it turns a mechanism with mass.
    let torque = ha.frames.iter().map(|f| f.coordinate_forces[0].abs());
    assert!(torque.fold(0.0, f64::max) > 0.1);
}

const M_P: f64 = 2.0;
const M_S: f64 = 1.0;
const G: f64 = 9.81;
const OMEGA2: f64 = 4.0 * std::f64::consts::PI * std::f64::consts::PI;
const TAU: f64 = 0.1;
const GAIN: f64 = 0.5;

/// The servo_follower ODE in the state y = (x_S, ẋ_S, s, 1): y′ = A y.
fn system_matrix() -> Matrix4<f64> {
    Matrix4::new(
        0.0,
        1.0,
        0.0,
        0.0,
        -OMEGA2,
        0.0,
        OMEGA2,
        -G,
        GAIN / TAU,
        0.0,
        -1.0 / TAU,
        0.0,
        0.0,
        0.0,
        0.0,
        0.0,
    )
}

/// (ν, x_S, actuator force) of the closed form at t, from rest at 0.
fn closed_form(t: f64) -> (f64, f64, f64) {
    let a = system_matrix();
    let y = (a * t).exp() * Vector4::new(0.0, 0.0, 0.0, 1.0);
    let yd = a * y;
    let ydd = a * yd;
    // ν = s, ν̈ = s̈; ẍ_S from the bob's equation.
    let force = M_P * (ydd[2] + G) + M_S * (yd[1] + G);
    (y[2], y[0], force)
}

fn index_of(names: &[String], name: &str) -> usize {
    names.iter().position(|n| n == name).unwrap()
}

/// Largest errors of ν, x_S and the actuator force over the run at step h, and of the
/// force after the start (t ≥ 0.5 s).
fn follower_errors(h: f64) -> [f64; 4] {
    let m: Model = with_step(model_file("examples/control/servo_follower.toml"), h);
    let sys = System::new(&m);
    let nu = index_of(&sys.coordinate_names, "slide.d3");
    let (_, hist) = run(&m);
    let mut err = [0.0f64; 4];
    for f in &hist.frames {
        let (nu_x, xs_x, force_x) = closed_form(f.time);
        let ef = (f.coordinate_forces[nu] - force_x).abs();
        err[0] = err[0].max((f.state.coords[nu].q - nu_x).abs());
        err[1] = err[1].max((f.state.nodes[1].x.z - xs_x).abs());
        err[2] = err[2].max(ef);
        if f.time >= 0.5 {
            err[3] = err[3].max(ef);
        }
    }
    err
}

/// The closed loop through the servo against the closed form, at h, h/2, h/4: second
/// order (error ratio ≈ 4 per halving) in the commanded coordinate, the bob's height and
/// the actuator force. The force is a multiplier: index-3 generalized-α started from
/// consistent accelerations has an O(h) start-up layer in the accelerations and
/// multipliers that decays like ρ∞ⁿ (Arnold & Brüls 2007; here the largest force error
/// is at t = 3h, halving with h), so its second order is checked after it (t ≥ 0.5 s,
/// ~125 steps at the coarsest h, ρ∞¹²⁵ ≈ 1e-12).
#[test]
fn servo_closed_loop_follows_the_linear_ode() {
    // Scale of the motion: the bob falls ~0.4 m, the force is ~30 N.
    let (_, xs_end, f_end) = closed_form(2.0);
    println!("closed form at t = 2: x_S = {xs_end:.5} m, F = {f_end:.4} N");
    let steps = [4e-3, 2e-3, 1e-3];
    let errors: Vec<[f64; 4]> = steps.iter().map(|&h| follower_errors(h)).collect();
    for (h, e) in steps.iter().zip(&errors) {
        println!(
            "h = {h:e}: |ν − ν*| {:.3e} m, |x_S − x_S*| {:.3e} m, |F − F*| {:.3e} N (t ≥ 0.5 s: {:.3e} N)",
            e[0], e[1], e[2], e[3]
        );
    }
    let order = |q: usize, expected: f64| {
        let series: Vec<f64> = errors.iter().map(|e| e[q]).collect();
        let orders = orders(&series);
        println!("quantity {q}: orders {orders:.3?}");
        for p in &orders {
            assert!(
                (p - expected).abs() < 0.2,
                "quantity {q}: {orders:?} {series:?}"
            );
        }
    };
    order(0, 2.0);
    order(1, 2.0);
    order(3, 2.0);
    // The start-up layer of the multiplier: first order, as the theory says.
    order(2, 1.0);
    // At h = 1 ms: ν and x_S within 1.0e-6 and 2.0e-6 m of 0.57 m of motion (measured
    // 0.98e-6, 2.0e-6), the force within 1e-4 N of ~30 N after the start (9.2e-5).
    let fine = errors[2];
    assert!(fine[0] < 1.2e-6 && fine[1] < 2.4e-6, "{fine:?}");
    assert!(fine[3] < 1.2e-4 && fine[2] < 3.5e-3, "{fine:?}");
}

/// Moves one unknown of a state by h.
type Shift = Box<dyn Fn(&mut samara::system::State, f64)>;

/// The Newton matrix the assembler builds for the follower (statics coefficients, with
/// the augmented-Lagrangian penalty so that its servo term ρ ∂s/∂Δ is in too) against
/// central differences of the assembled residual, column by column over the nodes, the
/// joint coordinates, the controller's state and the multipliers. Tolerance 1e-7 of the
/// largest entry: the residual is linear or smooth of order one here and the differences
/// are taken at 1e-6 (truncation ~1e-12, round-off ~1e-10 relative).
#[test]
fn servo_newton_matrix_matches_differences_of_the_residual() {
    use samara::solve::BlockMatrix;
    use samara::system::{Assembler, Coefficients, Formulation};
    let m = model_file("examples/control/servo_follower.toml");
    let sys = System::new(&m);
    let mut state = sys.initial_state();
    for (i, n) in state.nodes.iter_mut().enumerate() {
        n.x += nalgebra::Vector3::new(0.01, -0.02, 0.1 + 0.05 * i as f64);
    }
    for (i, z) in state.states.iter_mut().enumerate() {
        z.z = 0.3 - 0.1 * i as f64;
    }
    for (i, c) in state.coords.iter_mut().enumerate() {
        c.q = 0.2 + 0.07 * i as f64;
    }
    for (i, l) in state.lambda.iter_mut().enumerate() {
        *l = 1.0 + 0.3 * i as f64;
    }
    let ctx = sys.context(0.3, 1.0);
    let coef = Coefficients::statics(50.0);
    let mut asm = Assembler::new(&sys, Formulation::Index3);
    let n = asm.n_unknowns();
    let mut matrix = BlockMatrix::zeros(asm.structure().clone());
    let mut r0 = vec![0.0; n];
    asm.assemble(&sys, &state, &ctx, &coef, &[], &mut r0, Some(&mut matrix));
    let dense = matrix.to_dense_rowmajor();
    let scale = dense.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    // Newton column of each configuration unknown, and how to move it.
    let n6 = 6 * sys.n_nodes();
    let mut columns: Vec<(usize, Shift)> = Vec::new();
    for j in 0..sys.n_config() {
        let (b, c) = asm.config_place(j);
        let col = asm.structure().block_offset(b) + c;
        let nc = sys.n_coordinates;
        columns.push((
            col,
            Box::new(move |s, h| {
                if j < n6 {
                    let d = j % 6;
                    if d < 3 {
                        s.nodes[j / 6].x[d] += h;
                    } else {
                        let mut w = nalgebra::Vector3::zeros();
                        w[d - 3] = h;
                        s.nodes[j / 6].rot = s.nodes[j / 6].rot.compose_exp(&w);
                    }
                } else if j < n6 + nc {
                    s.coords[j - n6].q += h;
                } else {
                    s.states[j - n6 - nc].z += h;
                }
            }),
        ));
    }
    for k in 0..sys.constraints.len() {
        let off = sys.multiplier_offsets[k];
        for (i, col) in asm.multiplier_range(k).enumerate() {
            columns.push((col, Box::new(move |s, h| s.lambda[off + i] += h)));
        }
    }
    let eps = 1e-6;
    let (mut rp, mut rm) = (vec![0.0; n], vec![0.0; n]);
    let mut worst = 0.0f64;
    for (col, shift) in &columns {
        let mut s = state.clone();
        shift(&mut s, eps);
        asm.assemble(&sys, &s, &ctx, &coef, &[], &mut rp, None);
        let mut s = state.clone();
        shift(&mut s, -eps);
        asm.assemble(&sys, &s, &ctx, &coef, &[], &mut rm, None);
        for i in 0..n {
            let fd = (rp[i] - rm[i]) / (2.0 * eps);
            worst = worst.max((fd - dense[i * n + col]).abs() / scale);
        }
    }
    assert!(
        worst < 1e-7,
        "Newton matrix mismatch {worst:e} (scale {scale:e})"
    );
}

/// Bad servo input gets a located error: an unknown signal (with the closest name), a
/// value of the wrong type, a drive and a drive signal on one coordinate, a servo that
/// reads its own coordinate without a state in between (an algebraic loop), and the
/// stabilized index-2 formulation, which has no servo rows.
#[test]
fn bad_servo_input_is_rejected_where_it_is_written() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/control/servo_follower.toml");
    let good = std::fs::read_to_string(path).unwrap();
    let servo_line = r#"drive_signal = "command""#;
    assert!(good.contains(servo_line));

    let text = good.replace(servo_line, r#"drive_signal = "comand""#);
    let (line, msg, hint) = first_error(&text);
    assert_eq!(line, line_of(&text, r#""comand""#));
    assert!(
        msg.contains("joint 'slide', `d3`") && msg.contains("unknown signal 'comand'"),
        "{msg}"
    );
    assert!(hint.contains("did you mean 'command'?"), "{hint}");

    let text = good.replace(servo_line, "drive_signal = 3");
    let (line, msg, _) = first_error(&text);
    assert_eq!(line, line_of(&text, "drive_signal = 3"));
    assert!(msg.contains("string"), "{msg}");

    let text = good.replace(
        servo_line,
        &format!("{servo_line}\ndrive = {{ type = \"sine\", amplitude = 0.1, frequency = 1.0 }}"),
    );
    let (line, msg, _) = first_error(&text);
    assert_eq!(line, line_of(&text, servo_line));
    assert!(
        msg.contains("either `drive`") && msg.contains("not both"),
        "{msg}"
    );

    // The slide's own coordinate through an unfiltered sensor and a gain: ν − 0.5 ν = 0.
    let text = good.replace(servo_line, r#"drive_signal = "half""#)
        + r#"
[[sensors]]
name = "slide_position"
joint = "slide"
coordinate = "d3"

[[controllers]]
name = "half"
type = "gain"
input = "slide_position"
gain = 0.5
"#;
    let (line, msg, hint) = first_error(&text);
    assert_eq!(line, line_of(&text, r#""half""#));
    assert!(
        msg.contains("algebraic loop") && msg.contains("coordinate:slide.d3"),
        "{msg}"
    );
    assert!(hint.contains("time_constant"), "{hint}");
    // Through a filter (a state in between) it is a feedback loop, accepted.
    let filtered = text.replace(
        "coordinate = \"d3\"\n",
        "coordinate = \"d3\"\ntime_constant = 0.05\n",
    );
    assert!(Model::from_toml_str(&filtered, "ok.toml").is_ok());

    let text = good.replace("rho_inf = 0.8", "rho_inf = 1.0");
    let (line, msg, hint) = first_error(&text);
    assert_eq!(line, line_of(&text, servo_line));
    assert!(msg.contains("stabilized_index2"), "{msg}");
    assert!(hint.contains("index3"), "{hint}");
}

/// A drive signal counts as something attached: a sensor may read the servo's
/// coordinate (it is active), and the servo's actuator force is written like a drive's.
#[test]
fn a_servo_coordinate_is_active_and_its_force_is_written() {
    let m = model_file("examples/control/servo_follower.toml");
    let sys = System::new(&m);
    assert!(sys.coordinate_names.contains(&"slide.d3".to_string()));
    let c = &sys.constraints[0];
    assert_eq!(c.servo_rows().len(), 1);
    assert!(c.is_driven(0));
}

/// Statics: at equilibrium the controller's state has ṡ = 0, so s = K x_S; the bob hangs
/// k (x_S − ν) = −m_S g below the carriage and the servo holds ν = s:
/// ν = −K m_S g / (k (1 − K)), x_S = ν − m_S g / k, and the actuator carries the weight of
/// both, F = (m_P + m_S) g. Linear: exact to the solver's tolerance at every load step
/// (ν = s holds at each, with gravity scaled by the load factor).
#[test]
fn servo_statics_hold_the_signal_at_every_load_step() {
    let text = example_model_text("examples/control/servo_follower.toml")
        + "\n[[analyses]]\nname = \"hang\"\ntype = \"static\"\nload_steps = 4\n";
    let m = model(&text);
    let sys = System::new(&m);
    let nu = index_of(&sys.coordinate_names, "slide.d3");
    let (_, hist) = run(&m);
    // The start (load factor 0, all at rest at 0) and the four steps.
    assert_eq!(hist.frames.len(), 5);
    let k = OMEGA2 * M_S;
    for f in &hist.frames {
        let g = G * f.load_factor;
        let nu_x = -GAIN * M_S * g / (k * (1.0 - GAIN));
        let xs_x = nu_x - M_S * g / k;
        let force_x = (M_P + M_S) * g;
        assert!(
            (f.state.coords[nu].q - nu_x).abs() < 1e-10,
            "{} vs {nu_x}",
            f.state.coords[nu].q
        );
        assert!((f.state.nodes[1].x.z - xs_x).abs() < 1e-10);
        let fa = f.coordinate_forces[nu];
        assert!(
            (fa - force_x).abs() < 1e-8 * (M_P + M_S) * G,
            "{fa} vs {force_x}"
        );
        // The servo row itself: ν = s (the controller's output, its state here).
        assert!((f.state.coords[nu].q - GAIN * f.state.nodes[1].x.z).abs() < 1e-10);
    }
}

/// Why `m`'s first analysis stops at its start (it must stop).
fn refusal(m: &Model) -> String {
    let sys = System::new(m);
    let mut h = samara::analysis::History::default();
    let s = samara::analysis::run_analysis(
        &sys,
        &m.analyses[0],
        sys.initial_state(),
        &mut h,
        &mut |_| {},
    )
    .expect("recording to memory cannot fail");
    s.failure.expect("refused").reason
}

/// The energy-consistent integrators have no discrete form of a servo row: the run stops
/// at its start with the reason (the four-bar's crank driven through a signal).
#[test]
fn energy_integrators_refuse_a_servo() {
    let text = example_model_text("examples/four_bar.toml").replace(
        r#"drive = { type = "polynomial", coefficients = [0.0, 6.283185307179586] }"#,
        r#"drive_signal = "crank_angle""#,
    ) + r#"
[[signals]]
name = "crank_angle"
function = { type = "polynomial", coefficients = [0.0, 6.283185307179586] }

[[analyses]]
name = "turn"
type = "dynamic"
integrator = "energy_preserving"
t_end = 0.1
step = 1e-3
"#;
    let m = model(&text);
    let reason = refusal(&m);
    assert!(
        reason.contains("crank_pivot") && reason.contains("drive_signal"),
        "{reason}"
    );
}

/// A library caller that sets the stabilized index-2 formulation on a model with a servo
/// (the model file check does not see it) gets the analysis refused at its start.
#[test]
fn stabilized_formulation_refuses_a_servo_at_the_start() {
    use samara::model::{AnalysisKind, input::FormulationType};
    let mut m = model_file("examples/control/servo_follower.toml");
    if let AnalysisKind::Dynamic(d) = &mut m.analyses[0].kind {
        d.formulation = FormulationType::StabilizedIndex2;
    }
    let reason = refusal(&m);
    assert!(
        reason.contains("slide") && reason.contains("stabilized_index2"),
        "{reason}"
    );
}

/// A servo reading another body's position with feedthrough (an unfiltered sensor and a
/// gain, ν = K x_S) from a moving start: the bob starts at 0.3 m/s. The consistent initial
/// conditions must give ν̇(0) = K ẋ_S(0) (velocity projection with ∂s/∂x) and
/// ν̈(0) = K ẍ_S(0) (acceleration problem); then m_S ẍ_S = −k (1 − K) x_S − m_S g, a
/// harmonic oscillator about −m_S g/(k(1 − K)), from the projected ẋ_S(0). Second order
/// (orders within 0.2 of 2; measured 5.7e-5, 1.4e-5, 3.6e-6 m at h = 4, 2, 1 ms); the
/// initial rate and acceleration to round-off (1e-12, 1e-10).
#[test]
fn feedthrough_servo_starts_consistent_and_follows_the_oscillator() {
    let base = example_model_text("examples/control/servo_follower.toml");
    let text = base
        .replace(
            "name = \"bob\"\nposition = [0.0, 0.0, 0.0]",
            "name = \"bob\"\nposition = [0.0, 0.0, 0.0]\nvelocity = [0.0, 0.0, 0.3]",
        )
        .replace(
            "type = \"transfer_function\"\ninput = \"height\"\nnumerator = [0.5]\ndenominator = [0.1, 1.0]",
            "type = \"gain\"\ninput = \"height\"\ngain = 0.5",
        )
        + "\n[[analyses]]\nname = \"swing\"\ntype = \"dynamic\"\nt_end = 1.0\nstep = 4e-3\nrho_inf = 0.8\n";
    assert!(text.contains("velocity = [0.0, 0.0, 0.3]") && text.contains("type = \"gain\""));
    let k = OMEGA2 * M_S;
    let w = (k * (1.0 - GAIN) / M_S).sqrt();
    let centre = -M_S * G / (k * (1.0 - GAIN));
    let mut errors = Vec::new();
    for h in [4e-3, 2e-3, 1e-3] {
        let m = with_step(model(&text), h);
        let sys = System::new(&m);
        let nu = index_of(&sys.coordinate_names, "slide.d3");
        let (_, hist) = run(&m);
        let f0 = &hist.frames[0];
        let (bob, nu0) = (&f0.state.nodes[1], &f0.state.coords[nu]);
        assert!(
            (nu0.v - GAIN * bob.v.z).abs() < 1e-12,
            "{} vs {}",
            nu0.v,
            bob.v.z
        );
        assert!(
            (nu0.a - GAIN * bob.a.z).abs() < 1e-10,
            "{} vs {}",
            nu0.a,
            bob.a.z
        );
        assert!(bob.v.z > 0.1);
        let v0 = bob.v.z;
        let mut worst = 0.0f64;
        for f in &hist.frames {
            let t = f.time;
            let x = centre + (0.0 - centre) * (w * t).cos() + v0 / w * (w * t).sin();
            worst = worst.max((f.state.nodes[1].x.z - x).abs());
            worst = worst.max((f.state.coords[nu].q - GAIN * x).abs());
        }
        println!("h = {h:e}: max error {worst:.3e} m (v0 {v0})");
        errors.push(worst);
    }
    let orders = orders(&errors);
    for p in &orders {
        assert!((p - 2.0).abs() < 0.2, "{orders:?} {errors:?}");
    }
}
