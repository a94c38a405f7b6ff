//! Static analysis with load increments against closed-form equilibria.

use crate::common;
use common::*;
use nalgebra::Vector3;

/// A point mass m on a rigid bar of length L pinned at the origin (revolute about y), held
/// by a vertical spring (stiffness k, unstretched in the horizontal reference position)
/// from the anchor (L, 0, H). Gravity rotates the bar down by θ, the root of
///     dV/dθ = −m g L cos θ + k (ℓ − H) dℓ/dθ = 0,   ℓ(θ)² = (L − L cos θ)² + (H + L sin θ)²,
/// found here by bisection. The pivot reaction balances the weight and the spring force
/// (compared as a vector, with signs, in the joint's frame; and no moment).
#[test]
fn pinned_bar_held_by_a_spring_settles_at_the_closed_form_angle() {
    let (m, g, l, h, k): (f64, f64, f64, f64, f64) = (2.0, 9.81, 1.0, 0.5, 60.0);
    let text = format!(
        r#"
[model]
name = "bar_on_spring"
gravity = [0.0, 0.0, -{g}]
[[nodes]]
name = "tip"
position = [{l}, 0.0, 0.0]
[[bodies]]
name = "tip"
node = "tip"
mass = {m}
inertia = [[1e-3, 0.0, 0.0], [0.0, 1e-3, 0.0], [0.0, 0.0, 1e-3]]
[[joints]]
name = "pivot"
type = "revolute"
node_a = "ground"
node_b = "tip"
position = [0.0, 0.0, 0.0]
axis = [0.0, 1.0, 0.0]
[[springs]]
name = "spring"
node_a = "ground"
point_a = [{l}, 0.0, {h}]
node_b = "tip"
point_b = [{l}, 0.0, 0.0]
stiffness = {k}
[[analyses]]
name = "sag"
type = "static"
load_steps = 10
tolerance = 1e-12
"#
    );
    let md = model(&text);
    let (s, hist) = run(&md);
    assert_eq!(s.steps, 10);
    // Closed form by bisection on dV/dθ.
    let len = |t: f64| ((l - l * t.cos()).powi(2) + (h + l * t.sin()).powi(2)).sqrt();
    let dlen =
        |t: f64| ((l - l * t.cos()) * l * t.sin() + (h + l * t.sin()) * l * t.cos()) / len(t);
    let dv = |t: f64| -m * g * l * t.cos() + k * (len(t) - h) * dlen(t);
    let (mut a, mut b) = (0.0, 1.5);
    for _ in 0..200 {
        let c = 0.5 * (a + b);
        if dv(a) * dv(c) <= 0.0 { b = c } else { a = c }
    }
    let theta = 0.5 * (a + b);
    let tip = Vector3::new(l * theta.cos(), 0.0, -l * theta.sin());
    let last = hist.last().unwrap();
    let x = last.state.nodes[0].x;
    eprintln!("θ = {theta:.10} rad; tip {x:?} vs {tip:?}");
    // Newton converges to the tolerance 1e-12; nothing is discretized.
    assert!((x - tip).norm() < 1e-9, "{:e}", (x - tip).norm());
    assert!((last.load_factor - 1.0).abs() < 1e-15);
    // The first record is the unloaded state (load factor 0): the bar where the model put
    // it, the spring at its free length and no weight, hence no reaction (exactly: the
    // least-squares multipliers of a zero residual). Then the increments' k/10.
    assert_eq!(hist.frames.len(), 11);
    for (i, f) in hist.frames.iter().enumerate() {
        assert!((f.load_factor - i as f64 / 10.0).abs() < 1e-12);
    }
    let first = &hist.frames[0];
    assert_eq!(first.state.nodes[0].x, md.nodes[0].position);
    assert!(first.reactions[0].0.norm() < 1e-12 && first.reactions[0].1.norm() < 1e-12);
    // Pivot reaction on the bar (side B) by the ground: −(weight + spring force on the
    // bar), written in the components of the joint's frame A (docs/model-reference.md,
    // "Reactions"; A is fixed to the ground here). The moment about the pivot is zero: the
    // bar's load acts in the x-z plane, so its moment about the pivot lies along the hinge
    // axis, where the spring balances it.
    let anchor = Vector3::new(l, 0.0, h);
    let fs = k * (len(theta) - h) * (anchor - tip).normalize();
    let w = Vector3::new(0.0, 0.0, -m * g);
    let expected = md.joints[0].axes.transpose() * -(w + fs);
    let (f, moment) = last.reactions[0];
    eprintln!("F = {f:?} vs {expected:?} (frame A), M = {moment:?}");
    assert!((f - expected).norm() < 1e-8 * expected.norm());
    assert!(moment.norm() < 1e-8 * m * g * l);
}

/// A pendulum pushed sideways by a constant horizontal force F leans at tan θ = F/(m g);
/// the pivot carries the resultant of F and the weight (compared as a vector, with signs).
#[test]
fn pendulum_under_a_horizontal_force_leans_at_atan_f_over_mg() {
    let (m, g, l, force): (f64, f64, f64, f64) = (1.5, 9.81, 2.0, 7.0);
    let text = format!(
        r#"
[model]
name = "leaning"
gravity = [0.0, 0.0, -{g}]
[[nodes]]
name = "bob"
position = [0.0, 0.0, -{l}]
[[bodies]]
name = "bob"
node = "bob"
mass = {m}
inertia = [[1e-3, 0.0, 0.0], [0.0, 1e-3, 0.0], [0.0, 0.0, 1e-3]]
[[joints]]
name = "pivot"
type = "revolute"
node_a = "ground"
node_b = "bob"
position = [0.0, 0.0, 0.0]
axis = [0.0, 1.0, 0.0]
[[forces]]
name = "push"
node = "bob"
force = [{force}, 0.0, 0.0]
[[analyses]]
name = "lean"
type = "static"
load_steps = 4
tolerance = 1e-12
"#
    );
    let md = model(&text);
    let (_, hist) = run(&md);
    let theta = (force / (m * g)).atan();
    let x = hist.last().unwrap().state.nodes[0].x;
    let expected = Vector3::new(l * theta.sin(), 0.0, -l * theta.cos());
    assert!((x - expected).norm() < 1e-10, "{x:?} vs {expected:?}");
    // The pivot pulls the bob against the push and the weight: F = (−F_push, 0, m g) in
    // global components, written in the joint's frame A; no moment about the pivot.
    let (f, moment) = hist.last().unwrap().reactions[0];
    let expected = md.joints[0].axes.transpose() * Vector3::new(-force, 0.0, m * g);
    eprintln!("F = {f:?} vs {expected:?} (frame A), M = {moment:?}");
    assert!((f - expected).norm() < 1e-9 * expected.norm());
    assert!(moment.norm() < 1e-9 * m * g * l);
}
