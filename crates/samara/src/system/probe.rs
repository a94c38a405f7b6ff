//! Element outputs read as signals (`output:<element>.<output>`): the value from
//! [`Element::outputs`] and its derivatives over the element's local unknowns and input
//! signals by central differences, in the channels of [`SignalTerms`]:
//!
//! `∂y/∂u_j ≈ (y(u + h_j e_j) − y(u − h_j e_j)) / (2 h_j)`,
//!
//! with the node increments taken on the configuration manifold as the tangent check
//! does (`x + h e_k`, `R exp(h ẽ_k)`; velocities `v`, material `Ω`; accelerations `a`,
//! `Ω̇`), element states `z` (value channel) and `ż` (rate channel), and the input
//! signals. The step is scaled to each unknown, `h_j = u^(1/3) max(1, |u_j|)` (u the unit
//! round-off; rotation increments `u^(1/3)` rad): the truncation error O(h²) and the
//! round-off O(u |y| / h) then balance at about `u^(2/3) ≈ 4e-11` relative.
//!
//! Outputs are not part of the element contract's tangents, so every element's outputs
//! can be read this way; the scratch ([`ProbeWork`]) is reused, nothing is allocated once
//! it has grown to the largest element probed.

use crate::core::{Element, ElementInput, ElementState, EvalContext, NodeState, SignalTerms};
use nalgebra::Vector3;

/// Relative step u^(1/3), u = 2.2e-16.
pub const PROBE_STEP: f64 = 6.055454452393343e-6;

/// Scratch of [`output_terms`]: a full-length copy of the nodes (only the element's own
/// are refreshed and perturbed), of the element's states and input signals, and the
/// outputs at the two perturbed states.
#[derive(Clone, Debug, Default)]
pub struct ProbeWork {
    nodes: Vec<NodeState>,
    states: Vec<ElementState>,
    signals: Vec<f64>,
    plus: Vec<f64>,
    minus: Vec<f64>,
}

/// Which part of the element's input a column perturbs.
#[derive(Clone, Copy)]
enum Column {
    /// Node-local unknown (node, dof 0..6) in channel 0 (value), 1 (rate), 2 (acceleration).
    Node(usize, usize, usize),
    /// Element state j, channel 0 (z) or 1 (ż).
    State(usize, usize),
    /// Input signal j.
    Signal(usize),
}

fn step(value: f64) -> f64 {
    PROBE_STEP * value.abs().max(1.0)
}

/// Sets column `col` of the work copy to its base value plus `h` (the caller restores it).
fn perturb(w: &mut ProbeWork, base: &ElementInput, node_ids: &[usize], col: Column, h: f64) {
    match col {
        Column::Node(a, d, ch) => {
            let i = node_ids[a];
            let n = &mut w.nodes[i];
            let b = &base.nodes[i];
            let mut e = Vector3::zeros();
            e[d % 3] = h;
            match (ch, d < 3) {
                (0, true) => n.x = b.x + e,
                (0, false) => n.rot = b.rot.compose_exp(&e),
                (1, true) => n.v = b.v + e,
                (1, false) => n.w = b.w + e,
                (_, true) => n.a = b.a + e,
                (_, false) => n.wd = b.wd + e,
            }
        }
        Column::State(j, 0) => w.states[j].z = base.states[j].z + h,
        Column::State(j, _) => w.states[j].zd = base.states[j].zd + h,
        Column::Signal(j) => w.signals[j] = base.signals[j] + h,
    }
}

fn restore(w: &mut ProbeWork, base: &ElementInput, node_ids: &[usize], col: Column) {
    match col {
        Column::Node(a, _, _) => {
            let i = node_ids[a];
            w.nodes[i].clone_from(&base.nodes[i]);
        }
        Column::State(j, _) => w.states[j] = base.states[j],
        Column::Signal(j) => w.signals[j] = base.signals[j],
    }
}

/// Size of the base value of a column (for its step).
fn magnitude(base: &ElementInput, node_ids: &[usize], col: Column) -> f64 {
    match col {
        Column::Node(a, d, ch) => {
            let n = &base.nodes[node_ids[a]];
            match (ch, d < 3) {
                (0, false) => 0.0,
                (0, true) => n.x[d],
                (1, true) => n.v[d],
                (1, false) => n.w[d - 3],
                (_, true) => n.a[d],
                (_, false) => n.wd[d - 3],
            }
        }
        Column::State(j, 0) => base.states[j].z,
        Column::State(j, _) => base.states[j].zd,
        Column::Signal(j) => base.signals[j],
    }
}

/// Values of outputs `which` (indices into [`Element::output_names`], of which `e` has
/// `n_out`) of `e` at `x`, and with `derivatives` their derivatives by central differences
/// into `out` (one row per entry of `which`; `out` sized `which.len()` × local unknowns and
/// × input signals, cleared by the caller).
pub fn output_terms(
    e: &dyn Element,
    ctx: &EvalContext,
    x: &ElementInput,
    (which, n_out): (&[usize], usize),
    derivatives: bool,
    w: &mut ProbeWork,
    out: &mut SignalTerms,
) {
    w.plus.resize(n_out, 0.0);
    w.minus.resize(n_out, 0.0);
    e.outputs(ctx, x, &mut w.plus);
    for (r, &o) in which.iter().enumerate() {
        out.values[r] = w.plus[o];
    }
    if !derivatives {
        return;
    }
    // The work copy: the element's own nodes (the others are never read), states, inputs.
    let ids = e.nodes();
    if w.nodes.len() != x.nodes.len() {
        w.nodes.clear();
        w.nodes.extend_from_slice(x.nodes);
    } else {
        for &i in ids {
            w.nodes[i].clone_from(&x.nodes[i]);
        }
    }
    w.states.clear();
    w.states.extend_from_slice(x.states);
    w.signals.clear();
    w.signals.extend_from_slice(x.signals);
    let nn = 6 * ids.len();
    let columns = (0..3)
        .flat_map(|ch| (0..nn).map(move |l| (l, Column::Node(l / 6, l % 6, ch))))
        .chain(
            (0..2).flat_map(|ch| (0..x.states.len()).map(move |j| (nn + j, Column::State(j, ch)))),
        )
        .chain((0..x.signals.len()).map(|j| (j, Column::Signal(j))));
    for (l, col) in columns {
        let h = step(magnitude(x, ids, col));
        let eval = |w: &mut ProbeWork, h: f64, plus: bool| {
            perturb(w, x, ids, col, h);
            let px = ElementInput {
                nodes: &w.nodes,
                states: &w.states,
                signals: &w.signals,
                held: x.held,
            };
            let buf = if plus { &mut w.plus } else { &mut w.minus };
            e.outputs(ctx, &px, buf);
        };
        eval(w, h, true);
        eval(w, -h, false);
        restore(w, x, ids, col);
        for (r, &o) in which.iter().enumerate() {
            let d = (w.plus[o] - w.minus[o]) / (2.0 * h);
            match col {
                Column::Node(_, _, 0) | Column::State(_, 0) => out.k[(r, l)] = d,
                Column::Node(_, _, 1) | Column::State(_, _) => out.c[(r, l)] = d,
                Column::Node(_, _, _) => out.m[(r, l)] = d,
                Column::Signal(_) => out.ds[(r, l)] = d,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::{LocalTerms, Need};

    /// An element whose output is a known smooth function of everything it sees.
    struct Known {
        nodes: [usize; 1],
        inputs: Vec<String>,
    }
    impl Element for Known {
        fn name(&self) -> &str {
            "known"
        }
        fn nodes(&self) -> &[usize] {
            &self.nodes
        }
        fn n_states(&self) -> usize {
            1
        }
        fn signal_inputs(&self) -> &[String] {
            &self.inputs
        }
        fn evaluate(&self, _: &EvalContext, _: &ElementInput, _: Need, _: &mut LocalTerms) {}
        fn output_names(&self) -> Vec<(String, &'static str)> {
            vec![("a".into(), "1"), ("b".into(), "1")]
        }
        /// a = x₀² v₁ + 3 a₂ + z ż + s², b = (R e₁)·e₂ + 1000 x₁ (large-valued position).
        fn outputs(&self, _: &EvalContext, x: &ElementInput, out: &mut [f64]) {
            let n = &x.nodes[self.nodes[0]];
            let (z, s) = (x.states[0], x.signals[0]);
            out[0] = n.x[0] * n.x[0] * n.v[1] + 3.0 * n.a[2] + z.z * z.zd + s * s;
            out[1] = (n.r() * Vector3::x())[1] + 1000.0 * n.x[1];
        }
    }

    #[test]
    fn differences_match_the_closed_form() {
        let e = Known {
            nodes: [1],
            inputs: vec!["s".into()],
        };
        let node = |x: [f64; 3], psi: [f64; 3]| NodeState {
            x: Vector3::from(x),
            rot: crate::math::Rotation::exp(&Vector3::from(psi)),
            v: Vector3::new(0.3, -0.8, 0.5),
            w: Vector3::new(1.1, 0.2, -0.7),
            a: Vector3::new(-0.4, 0.6, 0.9),
            wd: Vector3::new(0.5, -1.2, 0.3),
        };
        // A large position (250 m): the step scales with it.
        let nodes = vec![
            node([0.1, 0.2, 0.3], [0.0; 3]),
            node([0.8, 250.0, -0.6], [0.7, -1.3, 0.4]),
        ];
        let states = [ElementState { z: 0.7, zd: -1.3 }];
        let signals = [0.4];
        let x = ElementInput {
            nodes: &nodes,
            states: &states,
            signals: &signals,
            held: &[],
        };
        let ctx = EvalContext {
            time: 0.0,
            gravity: Vector3::zeros(),
            load_factor: 1.0,
        };
        let mut out = SignalTerms {
            values: vec![0.0; 2],
            k: nalgebra::DMatrix::zeros(2, 7),
            c: nalgebra::DMatrix::zeros(2, 7),
            m: nalgebra::DMatrix::zeros(2, 7),
            ds: nalgebra::DMatrix::zeros(2, 1),
        };
        let mut w = ProbeWork::default();
        output_terms(&e, &ctx, &x, (&[1, 0], 2), true, &mut w, &mut out);
        let n = &nodes[1];
        // Rows: b, then a.
        let r = n.r();
        // ∂[(R e₁)₂]/∂θ = −(R ẽ₁)₂,: = (R [0, 0, 1; …]) — δ(R e₁) = R (δθ × e₁).
        let db: Vec<f64> = (0..3)
            .map(|k| {
                let mut t = Vector3::zeros();
                t[k] = 1.0;
                (r * t.cross(&Vector3::x()))[1]
            })
            .collect();
        // Round-off u |y| / h bounds the differences: 1e-8 for the order-one output a,
        // 1e-10 |b| for b ≈ 2.5e5.
        let tol = 1e-8;
        let tol_b = 1e-10 * out.values[0].abs();
        assert!(
            (out.values[1] - (n.x[0] * n.x[0] * n.v[1] + 3.0 * n.a[2] - 0.7 * 1.3 + 0.16)).abs()
                < 1e-14
        );
        assert!((out.k[(0, 1)] - 1000.0).abs() < tol_b, "{}", out.k[(0, 1)]);
        for (k, want) in db.iter().enumerate() {
            assert!(
                (out.k[(0, 3 + k)] - want).abs() < tol_b,
                "{k}: {} vs {want}",
                out.k[(0, 3 + k)]
            );
        }
        assert!((out.k[(1, 0)] - 2.0 * n.x[0] * n.v[1]).abs() < tol);
        assert!((out.c[(1, 1)] - n.x[0] * n.x[0]).abs() < tol);
        assert!((out.m[(1, 2)] - 3.0).abs() < tol);
        assert!((out.k[(1, 6)] - states[0].zd).abs() < tol);
        assert!((out.c[(1, 6)] - states[0].z).abs() < tol);
        assert!((out.ds[(1, 0)] - 0.8).abs() < tol);
        // Nothing else.
        assert!(out.m[(0, 2)].abs() < tol_b && out.c[(0, 0)].abs() < tol_b);
        // A second call reuses the scratch (same answers).
        let before = out.clone();
        output_terms(&e, &ctx, &x, (&[1, 0], 2), true, &mut w, &mut out);
        assert_eq!(before.k, out.k);
    }
}
