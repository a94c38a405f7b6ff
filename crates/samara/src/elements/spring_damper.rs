//! Point-to-point spring-damper between points on two nodes (or a node and the ground).
//!
//! Points `p = x + R s`; `d = p_B − p_A`, `l = |d|`, `n = d/l`, `l̇ = n·(ṗ_B − ṗ_A)`.
//! Tension `T = k (l − l₀) + c l̇`; the force on B is `−T n`, on A `+T n`, applied at the
//! points. With `G = ∂p/∂(x, θ) = [I, −R s̃]` the residual of end X (σ_B = +1, σ_A = −1)
//! is `r_X = σ_X Gₓᵀ (T n)`.

use super::{Element, EvalContext, LocalTerms, Need, add_block};
use crate::core::{ElementInput, NodeState};
use crate::math::skew;
use nalgebra::{Matrix3, Vector3};

#[derive(Clone, Debug)]
struct End {
    /// Node index, or `None` for a fixed ground point.
    node: Option<usize>,
    /// Row block of this end in the element's local terms.
    local: usize,
    /// Offset in the node frame (or the global point for the ground).
    s: Vector3<f64>,
}

/// Kinematics of one end.
struct EndState {
    p: Vector3<f64>,
    pdot: Vector3<f64>,
    r: Matrix3<f64>,
    /// ∂ṗ/∂θ = R (s × Ω)~.
    h: Matrix3<f64>,
}

#[derive(Clone, Debug)]
pub struct SpringDamper {
    name: String,
    ends: [End; 2],
    nodes: Vec<usize>,
    stiffness: f64,
    damping: f64,
    rest_length: f64,
}

impl SpringDamper {
    /// `nodes[i]` is `Some((node, offset in node frame))` or `None` with `points[i]` global.
    pub fn new(
        name: impl Into<String>,
        a: Option<(usize, Vector3<f64>)>,
        b: Option<(usize, Vector3<f64>)>,
        ground_points: [Vector3<f64>; 2],
        stiffness: f64,
        damping: f64,
        rest_length: f64,
    ) -> Self {
        let mut nodes = Vec::new();
        let mut make = |e: Option<(usize, Vector3<f64>)>, g: Vector3<f64>| match e {
            Some((n, s)) => {
                nodes.push(n);
                End {
                    node: Some(n),
                    local: nodes.len() - 1,
                    s,
                }
            }
            None => End {
                node: None,
                local: usize::MAX,
                s: g,
            },
        };
        let ea = make(a, ground_points[0]);
        let eb = make(b, ground_points[1]);
        Self {
            name: name.into(),
            ends: [ea, eb],
            nodes,
            stiffness,
            damping,
            rest_length,
        }
    }

    fn end_state(&self, e: &End, nodes: &[NodeState]) -> EndState {
        match e.node {
            None => EndState {
                p: e.s,
                pdot: Vector3::zeros(),
                r: Matrix3::identity(),
                h: Matrix3::zeros(),
            },
            Some(i) => {
                let n = &nodes[i];
                let r = *n.r();
                EndState {
                    p: n.x + r * e.s,
                    pdot: n.v + r * n.w.cross(&e.s),
                    h: r * skew(&e.s.cross(&n.w)),
                    r,
                }
            }
        }
    }

    /// Length, unit direction, rate of length.
    fn geometry(&self, nodes: &[NodeState]) -> (f64, Vector3<f64>, f64, [EndState; 2]) {
        let a = self.end_state(&self.ends[0], nodes);
        let b = self.end_state(&self.ends[1], nodes);
        let d = b.p - a.p;
        let l = d.norm();
        let n = if l > 0.0 { d / l } else { Vector3::zeros() };
        let ldot = n.dot(&(b.pdot - a.pdot));
        (l, n, ldot, [a, b])
    }
}

impl Element for SpringDamper {
    fn name(&self) -> &str {
        &self.name
    }

    fn nodes(&self) -> &[usize] {
        &self.nodes
    }

    fn evaluate(&self, _ctx: &EvalContext, x: &ElementInput, need: Need, out: &mut LocalTerms) {
        let nodes = x.nodes;
        let (l, n, ldot, st) = self.geometry(nodes);
        let (k, c) = (self.stiffness, self.damping);
        let tension = k * (l - self.rest_length) + c * ldot;
        let f = n * tension;
        let sigma = [-1.0, 1.0];
        for (x, e) in self.ends.iter().enumerate() {
            if e.node.is_none() {
                continue;
            }
            let row = 6 * e.local;
            let sx = sigma[x];
            out.add_r(row, &(f * sx));
            out.add_r(row + 3, &(skew(&e.s) * (st[x].r.transpose() * f) * sx));
        }
        if need == Need::Residual || l == 0.0 {
            return;
        }
        let proj = (Matrix3::identity() - n * n.transpose()) / l;
        let ddot = st[1].pdot - st[0].pdot;
        // ∂f/∂d (through l, n and l̇'s dependence on n) and ∂f/∂ḋ.
        let df_dd = n * (n.transpose() * k + ddot.transpose() * proj * c) + proj * tension;
        let df_dddot = n * n.transpose() * c;
        for (x, ex) in self.ends.iter().enumerate() {
            if ex.node.is_none() {
                continue;
            }
            let rx = 6 * ex.local;
            let gx_rot_t = skew(&ex.s) * st[x].r.transpose(); // (−R s̃)ᵀ
            for (y, ey) in self.ends.iter().enumerate() {
                if ey.node.is_none() {
                    continue;
                }
                let cy = 6 * ey.local;
                let s = sigma[x] * sigma[y];
                let gy_rot = -(st[y].r * skew(&ey.s));
                // ∂f/∂q_Y: translation and rotation columns.
                let dfx = df_dd * s;
                let dfth = (df_dd * gy_rot + df_dddot * st[y].h) * s;
                let dfv = df_dddot * s;
                let dfw = df_dddot * gy_rot * s;
                // Rows: Gₓᵀ = [I; gx_rot_t].
                add_block(&mut out.k, rx, cy, &dfx);
                add_block(&mut out.k, rx, cy + 3, &dfth);
                add_block(&mut out.k, rx + 3, cy, &(gx_rot_t * dfx));
                add_block(&mut out.k, rx + 3, cy + 3, &(gx_rot_t * dfth));
                add_block(&mut out.c, rx, cy, &dfv);
                add_block(&mut out.c, rx, cy + 3, &dfw);
                add_block(&mut out.c, rx + 3, cy, &(gx_rot_t * dfv));
                add_block(&mut out.c, rx + 3, cy + 3, &(gx_rot_t * dfw));
            }
            // Rotation of the lever arm itself: δ(s̃ Rᵀ f) = s̃ (Rᵀ f)~ δθ.
            let geo = skew(&ex.s) * skew(&(st[x].r.transpose() * f)) * sigma[x];
            add_block(&mut out.k, rx + 3, rx + 3, &geo);
        }
    }

    fn potential_energy(&self, _ctx: &EvalContext, x: &ElementInput) -> f64 {
        let nodes = x.nodes;
        let (l, ..) = self.geometry(nodes);
        0.5 * self.stiffness * (l - self.rest_length).powi(2)
    }

    fn dissipated_power(&self, x: &ElementInput) -> f64 {
        let nodes = x.nodes;
        let (_, _, ldot, _) = self.geometry(nodes);
        self.damping * ldot * ldot
    }
}
