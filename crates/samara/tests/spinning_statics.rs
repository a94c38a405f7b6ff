//! Spinning-rotor statics (issue #14): a static analysis with `rotation` against the
//! closed form of a rotating rod, against a driven hub run to steady state by the
//! dynamic analysis, and as the starting state of a rotating-frame modal analysis.

use crate::common;
use common::model;
use nalgebra::{Rotation3, Vector3};
use samara::analysis::{AnalysisSummary, History};
use samara::model::Model;
use samara::system::System;

fn run_all(m: &Model) -> Vec<(AnalysisSummary, History)> {
    let sys = System::new(m);
    samara::analysis::run_all(m, &sys, |_| Ok(History::default()), |_, _| {}).unwrap()
}

const E: f64 = 7.0e10;
const RHO: f64 = 2700.0;

/// A rod of length 1 along x, clamped at the axis, spinning about z.
fn rod(order: usize, omega: f64) -> String {
    format!(
        r#"
[model]
name = "rod"

[[beams]]
name = "rod"
order = {order}
points = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]
root = "root"
tip = "tip"

[[beams.sections]]
station = 0.0
isotropic = {{ E = {E:e}, G = 2.7e10, A = 1e-4, I2 = 1e-9, I3 = 2e-9, J = 2e-9, density = {RHO}, shear_factors = [0.83, 0.83] }}

[[joints]]
name = "clamp"
type = "fixed"
node_a = "ground"
node_b = "root"

[[analyses]]
name = "spin"
type = "static"
load_steps = 2
rotation = {{ axis = [0.0, 0.0, 1.0], omega = {omega} }}
"#
    )
}

/// The tip of a rod spinning about its clamped end stretches by `u(L) = tan(kL)/k − L`,
/// `k = Ω √(ρ/E)`: the solution of `E u'' + ρΩ²(x + u) = 0`, `u(0) = 0`, `u'(L) = 0`
/// (axial force `EA u'`, centrifugal load on the deformed position; the beam's strain
/// measure |x'| − 1 is exactly u' here, so the closed form holds at finite strain). At
/// kL = 0.5 the strain is 9 %. Spectral convergence in p: 1e-8 at p = 10 (tolerance:
/// the interpolation error of the sine, (kL)^(p+1)/(p+1)! ≈ 2e-11, well below it).
#[test]
fn rotating_rod_stretches_as_the_closed_form() {
    let kl = 0.5f64;
    let omega = kl * (E / RHO).sqrt();
    let exact = kl.tan() / kl - 1.0;
    let mut errors = Vec::new();
    for p in [2, 4, 6, 10] {
        let out = run_all(&model(&rod(p, omega)));
        let (s, _) = &out[0];
        assert!(s.failure.is_none(), "{:?}", s.failure);
        let sys = System::new(&model(&rod(p, omega)));
        let tip = sys.node_names.iter().position(|n| n == "tip").unwrap();
        let x = s.final_state.nodes[tip].x;
        let err = ((x.x - 1.0) - exact).abs() / exact;
        eprintln!(
            "p = {p}: tip stretch {:.12} vs {exact:.12}: {err:.2e} ({} Newton iterations in {} steps)",
            x.x - 1.0,
            s.newton_iterations,
            s.steps
        );
        assert!(x.y.abs() < 1e-12 && x.z.abs() < 1e-12, "{x:?}");
        // The tangent is consistent (centrifugal softening included): quadratic Newton.
        assert!(
            s.newton_iterations <= 6 * s.steps,
            "{}",
            s.newton_iterations
        );
        // The final state spins: v = Ω × x at the tip.
        let v = s.final_state.nodes[tip].v;
        assert!((v - Vector3::new(0.0, omega * x.x, 0.0)).norm() < 1e-9 * omega);
        errors.push(err);
    }
    // Spectral convergence to the round-off floor (p = 6 already holds the sine to 1e-15).
    assert!(errors[1] < 1e-3 * errors[0], "{errors:?}");
    assert!(errors[2] < 1e-12 && errors[3] < 1e-12, "{errors:?}");
}

/// A coned blade (5°) with a tip body on a hub turning on a revolute joint.
/// `analyses` is appended.
fn hub_blade(omega: f64, mu: f64, analyses: &str) -> String {
    format!(
        r#"
[model]
name = "coned_blade"

[[nodes]]
name = "hub"
position = [0.0, 0.0, 0.0]
angular_velocity = [0.0, 0.0, {omega}]

[[bodies]]
name = "hub"
node = "hub"
mass = 20.0
inertia = [[2.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 3.0]]

[[joints]]
name = "shaft"
type = "revolute"
node_a = "ground"
node_b = "hub"
axis = [0.0, 0.0, 1.0]

[joints.theta3]
drive = {{ type = "polynomial", coefficients = [0.0, {omega}] }}

[[beams]]
name = "blade"
order = 6
elements = 2
points = [[0.0, 0.0, 0.0], [1.9923893961834911, 0.0, 0.17431148549531633]]
root = "hub"
tip = "tip"
angular_velocity = [0.0, 0.0, {omega}]
rotation_centre = [0.0, 0.0, 0.0]
damping = [{mu}, {mu}, {mu}, {mu}, {mu}, {mu}]

[[beams.sections]]
station = 0.0
isotropic = {{ E = 7e10, G = 2.7e10, A = 1e-3, I2 = 2e-8, I3 = 5e-7, J = 4e-8, density = 2700.0, shear_factors = [0.83, 0.83] }}

[[bodies]]
name = "tip_mass"
node = "tip"
mass = 0.5
inertia = [[1e-3, 0.0, 0.0], [0.0, 2e-3, 0.0], [0.0, 0.0, 2.5e-3]]
{analyses}
"#
    )
}

/// The steady state of a hub driven at constant speed (revolute joint, drive θ = Ωt) with
/// a coned blade and a tip body, reached by the dynamic analysis from the rigid rotation
/// (the blade's stiffness-proportional damping removes the transient; it exerts no force
/// in the steady state, whose strain rates are zero), seen in the frame of the hub, is the
/// spinning static state. Tolerance: the generalized-α step error of the steady rotation,
/// second order, (Ωh)² = 4e-4 at h = 2 ms, on the centrifugal deflection; checked to
/// fall by ~4 when the step is halved.
#[test]
fn driven_hub_runs_to_the_spinning_static_state() {
    let omega = 10.0;
    let statics = model(&hub_blade(
        omega,
        0.02,
        r#"
[[analyses]]
name = "spin"
type = "static"
load_steps = 4
rotation = { axis = [0.0, 0.0, 1.0], omega = 10.0 }
"#,
    ));
    let sys = System::new(&statics);
    let tip = sys.node_names.iter().position(|n| n == "tip").unwrap();
    let out = run_all(&statics);
    let st = &out[0].0;
    assert!(st.failure.is_none(), "{:?}", st.failure);
    let x_static = st.final_state.nodes[tip].x;
    let r_static = st.final_state.nodes[tip].r();
    let cone = 5f64.to_radians();
    let x0 = Vector3::new(2.0 * cone.cos(), 0.0, 2.0 * cone.sin());
    let deflection = (x_static - x0).norm();
    eprintln!(
        "static tip {x_static:?}, deflection {deflection:.6e} ({} iterations, {} steps, {} rejected)",
        st.newton_iterations, st.steps, st.rejected_steps
    );
    // Centrifugal loads flatten the cone: the tip comes down and out.
    assert!(
        x_static.z < x0.z - 1e-3 && x_static.x > x0.x,
        "{x_static:?}"
    );
    assert!(st.newton_iterations <= 6 * st.steps);
    let t_end = 3.0;
    let mut diffs = Vec::new();
    for step in [4e-3, 2e-3] {
        let dynamic = model(&hub_blade(
            omega,
            0.02,
            &format!(
                r#"
[[analyses]]
name = "run"
type = "dynamic"
t_end = {t_end}
step = {step}
rho_inf = 0.8
output_every = 100
"#
            ),
        ));
        let out = run_all(&dynamic);
        let s = &out[0].0;
        assert!(s.failure.is_none(), "{:?}", s.failure);
        // Back to the hub frame: rotate by −θ, θ = Ω t_end.
        let back = Rotation3::from_axis_angle(&Vector3::z_axis(), -omega * t_end);
        let x = back * s.final_state.nodes[tip].x;
        let r = back.matrix() * s.final_state.nodes[tip].r();
        let dx = (x - x_static).norm() / deflection;
        let dr = (r - r_static).norm();
        eprintln!("h = {step}: tip {x:?}: position {dx:.3e} of the deflection, rotation {dr:.3e}");
        diffs.push(dx);
    }
    assert!(diffs[1] < 2e-3, "{diffs:?}");
    assert!(diffs[1] < 0.4 * diffs[0], "{diffs:?}");
}

/// `rotation.parts` spins only the named beams, bodies and nodes: a second rod, clamped
/// beside the spinning one and not listed, stays at rest and unloaded; the listed rod
/// stretches exactly as when the whole model spins. An unknown name is a located error.
#[test]
fn parts_select_the_spinning_nodes() {
    let omega = 0.5 * (E / RHO).sqrt();
    let whole = rod(6, omega);
    let other = r#"
[[beams]]
name = "other"
order = 2
points = [[0.0, 1.0, 0.0], [0.5, 1.0, 0.0]]
root = "other_root"
tip = "other_tip"

[[beams.sections]]
station = 0.0
isotropic = { E = 7e10, G = 2.7e10, A = 1e-4, I2 = 1e-9, I3 = 2e-9, J = 2e-9, density = 2700.0, shear_factors = [0.83, 0.83] }

[[joints]]
name = "other_clamp"
type = "fixed"
node_a = "ground"
node_b = "other_root"
"#;
    let parts = whole
        .replace("omega = ", "parts = [\"rod\"], omega = ")
        .replace("[[analyses]]", &format!("{other}\n[[analyses]]"));
    let tip_of = |text: &str, name: &str| {
        let m = model(text);
        let sys = System::new(&m);
        let out = run_all(&m);
        assert!(out[0].0.failure.is_none(), "{:?}", out[0].0.failure);
        let i = sys.node_names.iter().position(|n| n == name).unwrap();
        out[0].0.final_state.nodes[i].clone()
    };
    let a = tip_of(&whole, "tip");
    let b = tip_of(&parts, "tip");
    assert!((a.x - b.x).norm() < 1e-12, "{:?} {:?}", a.x, b.x);
    let still = tip_of(&parts, "other_tip");
    assert!(
        (still.x - Vector3::new(0.5, 1.0, 0.0)).norm() < 1e-14,
        "{:?}",
        still.x
    );
    assert!(still.v.norm() == 0.0 && still.w.norm() == 0.0);
    let bad = whole.replace("omega = ", "parts = [\"rdo\"], omega = ");
    let e = samara::model::Model::from_toml_str(&bad, "bad.toml")
        .expect_err("unknown part")
        .to_string();
    assert!(
        e.contains("bad.toml:")
            && e.contains("no node, beam or body is named 'rdo'")
            && e.contains("did you mean"),
        "{e}"
    );
}
