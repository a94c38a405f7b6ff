//! Issue #3: the elements on joint coordinates (backlash, table spring, input port) and
//! the consistent initial conditions (assembly of a sloppy model, velocity projection).

use crate::common;
use common::*;
use std::f64::consts::PI;

fn slider(component: &str, analysis: &str, extra: &str) -> String {
    format!(
        r#"
[model]
name = "slider"
[[nodes]]
name = "block"
position = [0.0, 0.0, 0.0]
velocity = [1.0, 0.0, 0.0]
[[bodies]]
name = "block"
node = "block"
mass = 2.0
inertia = [[0.1, 0.0, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.1]]
[[joints]]
name = "rail"
type = "prismatic"
node_a = "ground"
node_b = "block"
axis = [1.0, 0.0, 0.0]
[joints.d3]
{component}
{extra}
{analysis}
"#
    )
}

/// Backlash: a 2 kg block slides at v₀ = 1 m/s inside a 0.2 m dead band and hits its end
/// (contact k = 2e4 N/m, c = 20 N s/m, so ω = 100 rad/s and ζ = 0.05). For the
/// Kelvin–Voigt contact the closed forms are: maximum penetration
/// δ = (v₀/ω) exp(−ζ ω t*), t* = atan(√(1−ζ²)/ζ)/ω_d; rebound speed e v₀ with
/// e = exp(−ζπ/√(1−ζ²)); energy lost ½ m v₀² (1 − e²), all of it in the contact damper.
///
/// The step does not land on the contact instant, so the onset of the damping force is
/// resolved to O(h): at h = 1e-5 (3,000 steps per contact) the error is ~1e-4, and the
/// tolerance is 1e-3 relative.
#[test]
fn backlash_reverses_at_the_right_place_and_loses_the_damper_energy() {
    let (m, k, c, v0, half) = (2.0f64, 2e4f64, 20.0f64, 1.0f64, 0.1f64);
    let w = (k / m).sqrt();
    let zeta = c / (2.0 * (k * m).sqrt());
    let wd = w * (1.0 - zeta * zeta).sqrt();
    let tstar = ((1.0 - zeta * zeta).sqrt() / zeta).atan() / wd;
    let delta = v0 / w * (-zeta * w * tstar).exp();
    let e = (-zeta * PI / (1.0 - zeta * zeta).sqrt()).exp();
    let text = slider(
        "backlash = { width = 0.2, stiffness = 2e4, damping = 20.0 }",
        "[[analyses]]\nname = \"bounce\"\ntype = \"dynamic\"\nt_end = 0.2\nstep = 1e-5\nrho_inf = 1.0\noutput_every = 10",
        "",
    );
    let (_, hist) = run(&model(&text));
    let x: Vec<f64> = hist.frames.iter().map(|f| f.state.coords[0].q).collect();
    let xmax = x.iter().copied().fold(f64::MIN, f64::max);
    let last = hist.last().unwrap();
    let v_out = last.state.coords[0].v;
    let lost = 0.5 * m * v0 * v0 - last.energy.kinetic;
    println!(
        "reversal at {xmax:.6} m (closed form {:.6}); rebound {v_out:.6} m/s (closed form {:.6}); energy lost {lost:.6} J, dissipated {:.6} J (closed form {:.6})",
        half + delta,
        -e * v0,
        last.energy.dissipated,
        0.5 * m * v0 * v0 * (1.0 - e * e)
    );
    assert!(
        (xmax - half - delta).abs() < 1e-3 * delta,
        "reversal {xmax}"
    );
    assert!((v_out + e * v0).abs() < 1e-3 * v0, "rebound {v_out}");
    let lost_exact = 0.5 * m * v0 * v0 * (1.0 - e * e);
    assert!((lost - lost_exact).abs() < 1e-3 * lost_exact);
    assert!((last.energy.dissipated - lost_exact).abs() < 1e-3 * lost_exact);
    // Back inside the dead band, no force: the block coasts.
    assert!(last.state.coords[0].q < half && last.coordinate_forces[0] == 0.0);
}

/// Input port and nonlinear spring. A constant 10 N signal pushes the free block:
/// x = ½ (F/m) t² + v₀ t, and the work of the input equals F x. In statics the same force
/// on a table spring [[0, 0], [0.1, 10], [0.2, 40]] settles where the table gives 30 N:
/// ν = 0.1 + 20/300.
#[test]
fn input_port_and_table_spring() {
    let sig = "[[signals]]\nname = \"push\"\nfunction = { type = \"constant\", value = 10.0 }\n";
    let text = slider(
        "input = \"push\"",
        "[[analyses]]\nname = \"push\"\ntype = \"dynamic\"\nt_end = 1.0\nstep = 1e-3\nrho_inf = 0.9\ntolerance = 1e-12",
        sig,
    );
    let (_, hist) = run(&model(&text));
    let f = hist.last().unwrap();
    let x = 0.5 * 5.0 + 1.0;
    // Constant acceleration: generalized-α is exact up to round-off.
    assert!(
        (f.state.coords[0].q - x).abs() < 1e-9,
        "{}",
        f.state.coords[0].q
    );
    assert!((f.energy.external_work - 10.0 * x).abs() < 1e-9);
    assert!((f.coordinate_forces[0] - 10.0).abs() < 1e-12);

    let sig = "[[signals]]\nname = \"push\"\nfunction = { type = \"constant\", value = 30.0 }\n";
    let text = slider(
        "spring_table = [[0.0, 0.0], [0.1, 10.0], [0.2, 40.0]]\ninput = \"push\"",
        "[[analyses]]\nname = \"hold\"\ntype = \"static\"\ntolerance = 1e-12",
        sig,
    );
    let (_, hist) = run(&model(&text));
    let f = hist.last().unwrap();
    assert!((f.state.coords[0].q - (0.1 + 20.0 / 300.0)).abs() < 1e-10);
    // The spring and the input balance: no net force on the coordinate, no reaction.
    assert!(f.coordinate_forces[0].abs() < 1e-9 && f.reactions[0].0.x.abs() < 1e-9);

    // A table damper [[-1, -8], [0, 0], [1, 2]] (stiff in reverse) on the block launched
    // at 1 m/s: m v̇ = −2 v, so v = e^{−t} and ν(1) = 1 − e^{−1}. Second-order scheme at
    // h = 1 ms: error ~ (ωh)² with ω = 1 s⁻¹, tolerance 1e-5.
    let text = slider(
        "damper_table = [[-1.0, -8.0], [0.0, 0.0], [1.0, 2.0]]",
        "[[analyses]]\nname = \"coast\"\ntype = \"dynamic\"\nt_end = 1.0\nstep = 1e-3\nrho_inf = 1.0\ntolerance = 1e-12",
        "",
    );
    let (_, hist) = run(&model(&text));
    let f = hist.last().unwrap();
    let exact = 1.0 - (-1.0f64).exp();
    assert!(
        (f.state.coords[0].q - exact).abs() < 1e-5,
        "{}",
        f.state.coords[0].q
    );
    // All the kinetic energy lost went into the damper.
    assert!((f.energy.dissipated + f.energy.kinetic - 1.0).abs() < 1e-5);
}

/// Consistent initial conditions. A four-bar (crank 0.2, coupler 0.5, rocker 0.4, ground
/// 0.6 m) is given MBDyn-style: nodes at the link centres with joint points as offsets in
/// the node frames, and the node positions and orientations off by millimetres and
/// milliradians (the crank's position only). With the crank driven to 90° (and 1 rev/s), the assembled configuration
/// is unique: it must be the exact one (open branch, Freudenstein), and the projected
/// velocities the exact ones, ω₄ = ω₂ a sin(θ₃ − θ₂) / (c sin(θ₃ − θ₄)).
#[test]
fn initial_assembly_moves_a_sloppy_model_onto_the_joints() {
    let (a, b, c, d) = (0.2f64, 0.5f64, 0.4f64, 0.6f64);
    let th2 = PI / 2.0;
    let k1 = d / a;
    let k2 = d / c;
    let k3 = (a * a - b * b + c * c + d * d) / (2.0 * a * c);
    let (aa, bb, cc) = (
        th2.cos() - k1 - k2 * th2.cos() + k3,
        -2.0 * th2.sin(),
        k1 - (k2 + 1.0) * th2.cos() + k3,
    );
    let th4 = 2.0 * ((-bb - (bb * bb - 4.0 * aa * cc).sqrt()) / (2.0 * aa)).atan();
    let pa = [a * th2.cos(), a * th2.sin()];
    let pb = [d + c * th4.cos(), c * th4.sin()];
    let th3 = (pb[1] - pa[1]).atan2(pb[0] - pa[0]);
    let w2 = 2.0 * PI;
    let w4 = w2 * a * (th3 - th2).sin() / (c * (th3 - th4).sin());
    // Exact link centres and directions; the model gets them perturbed.
    let cr = [0.5 * pa[0], 0.5 * pa[1]];
    let cp = [0.5 * (pa[0] + pb[0]), 0.5 * (pa[1] + pb[1])];
    let ro = [0.5 * (pb[0] + d), 0.5 * pb[1]];
    let rocker_dir = (0.0f64 - pb[1]).atan2(d - pb[0]);
    let node = |name: &str, p: [f64; 2], ang: f64, dp: [f64; 2], da: f64| {
        let t = ang + da;
        format!(
            "[[nodes]]\nname = \"{name}\"\nposition = [{}, {}, 0.0]\norientation = {{ x_axis = [{}, {}, 0.0], y_axis = [{}, {}, 0.0] }}\n",
            p[0] + dp[0],
            p[1] + dp[1],
            t.cos(),
            t.sin(),
            -t.sin(),
            t.cos()
        )
    };
    let body = |name: &str| {
        format!(
            "[[bodies]]\nname = \"{name}\"\nnode = \"{name}\"\nmass = 1.0\ninertia = [[1e-3, 0.0, 0.0], [0.0, 0.02, 0.0], [0.0, 0.0, 0.02]]\n"
        )
    };
    let joint = |name: &str, na: &str, nb: &str, oa: Option<f64>, ob: Option<f64>, extra: &str| {
        let mut t = format!(
            "[[joints]]\nname = \"{name}\"\ntype = \"revolute\"\nnode_a = \"{na}\"\nnode_b = \"{nb}\"\naxis = [0.0, 0.0, 1.0]\n"
        );
        if let Some(x) = oa {
            t += &format!("offset_a = [{x}, 0.0, 0.0]\n");
        }
        if let Some(x) = ob {
            t += &format!("offset_b = [{x}, 0.0, 0.0]\n");
        }
        t + extra
    };
    let mut text = String::from("[model]\nname = \"sloppy_four_bar\"\n");
    // The crank's orientation is exact: its frame defines θ3 = 0 of the driven pivot (joint
    // coordinates count from the reference configuration).
    text += &node("crank", cr, th2, [0.003, -0.002], 0.0);
    text += &node("coupler", cp, th3, [-0.004, 0.003], -0.003);
    text += &node("rocker", ro, rocker_dir, [0.002, 0.004], 0.005);
    for n in ["crank", "coupler", "rocker"] {
        text += &body(n);
    }
    // Ground pivots: frame A is the global point itself (offset_a on the ground side).
    text += &joint(
        "crank_pivot",
        "ground",
        "crank",
        Some(0.0),
        Some(-a / 2.0),
        "[joints.theta3]\ndrive = { type = \"polynomial\", coefficients = [0.0, 6.283185307179586] }\n",
    );
    text += &joint(
        "crank_coupler",
        "crank",
        "coupler",
        Some(a / 2.0),
        Some(-b / 2.0),
        "",
    );
    text += &joint(
        "coupler_rocker",
        "coupler",
        "rocker",
        Some(b / 2.0),
        Some(-c / 2.0),
        "",
    );
    text += &joint(
        "rocker_pivot",
        "rocker",
        "ground",
        Some(c / 2.0),
        None,
        "position = [0.6, 0.0, 0.0]\n",
    );
    text += "[[analyses]]\nname = \"turn\"\ntype = \"dynamic\"\nt_end = 0.01\nstep = 1e-3\ntolerance = 1e-12\n";
    let m = model(&text);
    let (s, hist) = run(&m);
    let report = s.assembly.as_ref().expect("assembly ran");
    println!(
        "assembly: violation {:.2e} → {:.2e} in {} iterations; moved {:?}",
        report.violation_before, report.violation_after, report.iterations, report.moved
    );
    assert!(report.violation_before > 1e-3 && report.violation_after < 1e-12);
    assert!(
        s.warnings.iter().any(|w| w.contains("moved 3 nodes")),
        "{:?}",
        s.warnings
    );
    let f0 = &hist.frames[0];
    let exact = [(cr, th2), (cp, th3), (ro, rocker_dir)];
    for (n, (p, ang)) in f0.state.nodes.iter().zip(exact) {
        assert!(
            (n.x.x - p[0]).abs() < 1e-10 && (n.x.y - p[1]).abs() < 1e-10 && n.x.z.abs() < 1e-10,
            "{:?} vs {p:?}",
            n.x
        );
        let t = n.r()[(1, 0)].atan2(n.r()[(0, 0)]);
        assert!((t - ang).abs() < 1e-10, "{t} vs {ang}");
    }
    let wz: Vec<f64> = f0.state.nodes.iter().map(|n| n.omega_global().z).collect();
    println!("angular velocities {wz:?}, exact crank {w2}, rocker {w4}");
    assert!((wz[0] - w2).abs() < 1e-9 && (wz[2] - w4).abs() < 1e-9);
}

/// A joint frame given in a node's frame (`relative_to`) is the same joint as the one
/// given globally: a pendulum on a node turned by 30° about z, its hinge axis given as the
/// node's x axis, swings exactly like the one given with the global axis.
#[test]
fn joint_frames_relative_to_a_node_match_global_ones() {
    let c = 30f64.to_radians().cos();
    let s = 30f64.to_radians().sin();
    let text = |joint: &str| {
        format!(
            r#"
[model]
name = "pendulum"
gravity = [0.0, 0.0, -9.81]
[[nodes]]
name = "bob"
position = [0.0, 0.0, -1.0]
orientation = {{ x_axis = [{c}, {s}, 0.0], y_axis = [{ms}, {c}, 0.0] }}
velocity = [{vx}, {vy}, 0.0]
[[bodies]]
name = "bob"
node = "bob"
mass = 1.0
inertia = [[1e-3, 0.0, 0.0], [0.0, 2e-3, 0.0], [0.0, 0.0, 3e-3]]
[[joints]]
name = "pivot"
type = "revolute"
node_a = "ground"
node_b = "bob"
{joint}
[[analyses]]
name = "swing"
type = "dynamic"
t_end = 0.5
step = 1e-3
"#,
            ms = -s,
            vx = -s,
            vy = c
        )
    };
    let global = model(&text(&format!(
        "position = [0.0, 0.0, 0.0]\naxis = [{c}, {s}, 0.0]"
    )));
    let local = model(&text(
        "relative_to = \"bob\"\nposition = [0.0, 0.0, 1.0]\naxis = [1.0, 0.0, 0.0]",
    ));
    let (_, hg) = run(&global);
    let (_, hl) = run(&local);
    let (a, b) = (hg.last().unwrap(), hl.last().unwrap());
    assert!((a.state.nodes[0].x - b.state.nodes[0].x).norm() < 1e-12);
    assert!((a.state.coords[0].q - b.state.coords[0].q).abs() < 1e-12);
    // It swung: the velocity was normal to the hinge axis.
    assert!(a.state.coords[0].q.abs() > 0.1, "{}", a.state.coords[0].q);
}
