//! A force along the line between points on two nodes (or a node and the ground): the
//! kinematics and tangents shared by the spring-damper and the Maxwell element.
//!
//! Points `p = x + R s`; `d = p_B − p_A`, `l = |d|`, `n = d/l`, `l̇ = n·(ṗ_B − ṗ_A)`.
//! A tension `T(l, l̇, …)` gives the force `−T n` on B and `+T n` on A, at the points.
//! With `G = ∂p/∂(x, θ) = [I, −R s̃]` the residual of end X (σ_B = +1, σ_A = −1) is
//! `r_X = σ_X Gₓᵀ (T n)`, and `∂l/∂q_X = σ_X nᵀ Gₓ`: the same vector, so
//! `r = T g` with `g = ∂l/∂q` (the generalized direction).

use super::{LocalTerms, add_block};
use crate::core::{DiscreteStep, NodeState};
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
pub struct EndState {
    p: Vector3<f64>,
    pdot: Vector3<f64>,
    r: Matrix3<f64>,
    /// ∂ṗ/∂θ = R (s × Ω)~.
    h: Matrix3<f64>,
}

/// The line's length, direction and rate at one state.
pub struct LineState {
    pub length: f64,
    pub direction: Vector3<f64>,
    pub rate: f64,
    ends: [EndState; 2],
}

/// Two attachment points and the nodes they are on.
#[derive(Clone, Debug)]
pub struct LineOfAction {
    ends: [End; 2],
    nodes: Vec<usize>,
}

const SIGMA: [f64; 2] = [-1.0, 1.0];

impl LineOfAction {
    /// `a`, `b`: `Some((node, offset in node frame))`, or `None` with `ground_points[i]`
    /// global.
    pub fn new(
        a: Option<(usize, Vector3<f64>)>,
        b: Option<(usize, Vector3<f64>)>,
        ground_points: [Vector3<f64>; 2],
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
            ends: [ea, eb],
            nodes,
        }
    }

    /// The nodes, in the order of the local rows.
    pub fn nodes(&self) -> &[usize] {
        &self.nodes
    }

    fn end_state(e: &End, nodes: &[NodeState]) -> EndState {
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

    /// Global position of end `k`.
    fn point(&self, k: usize, nodes: &[NodeState]) -> Vector3<f64> {
        let e = &self.ends[k];
        match e.node {
            None => e.s,
            Some(i) => nodes[i].x + nodes[i].r() * e.s,
        }
    }

    /// Length |p_B − p_A|.
    pub fn length(&self, nodes: &[NodeState]) -> f64 {
        (self.point(1, nodes) - self.point(0, nodes)).norm()
    }

    /// Adds the discrete residual of a mean tension `T̄` over a step: force `T̄ ē` with
    /// `ē = (d₀ + d₁)/(l₀ + l₁)` (so that `ē·(d₁ − d₀) = l₁ − l₀`), at the mean arms of the
    /// ends (−T̄ē on B, +T̄ē on A as applied forces). Then `Σ Δ·r̄ = T̄ (l₁ − l₀)` exactly, and
    /// the pair has no resultant and no moment about any point at the mean positions, so
    /// momenta are conserved ([`DiscreteStep`]).
    pub fn add_discrete_tension(&self, step: &DiscreteStep, tension: f64, out: &mut [f64]) {
        let d0 = self.point(1, step.start) - self.point(0, step.start);
        let d1 = self.point(1, step.end) - self.point(0, step.end);
        let sum = d0.norm() + d1.norm();
        if sum == 0.0 {
            return;
        }
        let e = (d0 + d1) / sum;
        for (k, sigma) in SIGMA.iter().enumerate() {
            let end = &self.ends[k];
            let Some(i) = end.node else { continue };
            let f = e * (sigma * tension);
            let m = step.conjugate_moment(i, &step.mean_arm(i, &end.s).cross(&f));
            let row = 6 * end.local;
            for j in 0..3 {
                out[row + j] += f[j];
                out[row + 3 + j] += m[j];
            }
        }
    }

    /// Length, unit direction and rate of length.
    pub fn state(&self, nodes: &[NodeState]) -> LineState {
        let a = Self::end_state(&self.ends[0], nodes);
        let b = Self::end_state(&self.ends[1], nodes);
        let d = b.p - a.p;
        let l = d.norm();
        let n = if l > 0.0 { d / l } else { Vector3::zeros() };
        let ldot = n.dot(&(b.pdot - a.pdot));
        LineState {
            length: l,
            direction: n,
            rate: ldot,
            ends: [a, b],
        }
    }

    /// Adds `scale · g` (g = ∂l/∂q over the local node unknowns) into `out` (length
    /// 6·nodes; a column or row of a local matrix, through `set`).
    pub fn add_length_gradient(&self, st: &LineState, scale: f64, mut set: impl FnMut(usize, f64)) {
        for (x, e) in self.ends.iter().enumerate() {
            if e.node.is_none() {
                continue;
            }
            let row = 6 * e.local;
            let f = st.direction * (SIGMA[x] * scale);
            let m = skew(&e.s) * (st.ends[x].r.transpose() * f);
            for i in 0..3 {
                set(row + i, f[i]);
                set(row + 3 + i, m[i]);
            }
        }
    }

    /// Adds `scale · ∂l̇/∂q` (over the local node unknowns, at fixed velocities) into
    /// `out` through `set`: with P = I − n nᵀ, `∂l̇/∂x_X = σ_X P ḋ / l` and
    /// `∂l̇/∂θ_X = σ_X (s̃ Rᵀ P ḋ / l + hₓᵀ n)`. (`∂l̇/∂v` is the length gradient.)
    pub fn add_rate_gradient(&self, st: &LineState, scale: f64, mut set: impl FnMut(usize, f64)) {
        let l = st.length;
        if l == 0.0 {
            return;
        }
        let n = st.direction;
        let ddot = st.ends[1].pdot - st.ends[0].pdot;
        let pd = (ddot - n * n.dot(&ddot)) / l;
        for (x, e) in self.ends.iter().enumerate() {
            if e.node.is_none() {
                continue;
            }
            let row = 6 * e.local;
            let f = pd * (SIGMA[x] * scale);
            let m = (skew(&e.s) * (st.ends[x].r.transpose() * pd) + st.ends[x].h.transpose() * n)
                * (SIGMA[x] * scale);
            for i in 0..3 {
                set(row + i, f[i]);
                set(row + 3 + i, m[i]);
            }
        }
    }

    /// Adds the residual of the tension `t` and, with `tangents`, its K and C for the
    /// tension's partial derivatives `(∂T/∂l, ∂T/∂l̇)`.
    pub fn add_tension(
        &self,
        st: &LineState,
        t: f64,
        tangents: Option<(f64, f64)>,
        out: &mut LocalTerms,
    ) {
        let n = st.direction;
        let f = n * t;
        for (x, e) in self.ends.iter().enumerate() {
            if e.node.is_none() {
                continue;
            }
            let row = 6 * e.local;
            let sx = SIGMA[x];
            out.add_r(row, &(f * sx));
            out.add_r(row + 3, &(skew(&e.s) * (st.ends[x].r.transpose() * f) * sx));
        }
        let Some((k, c)) = tangents else { return };
        let l = st.length;
        if l == 0.0 {
            return;
        }
        let proj = (Matrix3::identity() - n * n.transpose()) / l;
        let ddot = st.ends[1].pdot - st.ends[0].pdot;
        // ∂f/∂d (through l, n and l̇'s dependence on n) and ∂f/∂ḋ.
        let df_dd = n * (n.transpose() * k + ddot.transpose() * proj * c) + proj * t;
        let df_dddot = n * n.transpose() * c;
        for (x, ex) in self.ends.iter().enumerate() {
            if ex.node.is_none() {
                continue;
            }
            let rx = 6 * ex.local;
            let gx_rot_t = skew(&ex.s) * st.ends[x].r.transpose(); // (−R s̃)ᵀ
            for (y, ey) in self.ends.iter().enumerate() {
                if ey.node.is_none() {
                    continue;
                }
                let cy = 6 * ey.local;
                let s = SIGMA[x] * SIGMA[y];
                let gy_rot = -(st.ends[y].r * skew(&ey.s));
                // ∂f/∂q_Y: translation and rotation columns.
                let dfx = df_dd * s;
                let dfth = (df_dd * gy_rot + df_dddot * st.ends[y].h) * s;
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
            let geo = skew(&ex.s) * skew(&(st.ends[x].r.transpose() * f)) * SIGMA[x];
            add_block(&mut out.k, rx + 3, rx + 3, &geo);
        }
    }
}
