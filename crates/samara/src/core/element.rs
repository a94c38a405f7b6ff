//! The element contract: an element touches a few nodes and, given their state, returns
//! its residual
//!
//! `r(q, v, v̇, t) = M(q) v̇ + g(q, v, t) − f(q, v, t)`
//!
//! (6 rows per node: force in global components, then moment about the node in node-frame
//! components — the virtual work of a material rotation increment) and its tangent blocks
//! `K = ∂r/∂q`, `C = ∂r/∂v`, `M = ∂r/∂v̇`, where perturbations of a node are
//! `(δx, δθ)` with `x ← x + δx`, `R ← R exp(δθ̃)` and velocities `(v, Ω)` (global linear,
//! material angular). Elements never know which analysis calls them.

use super::NodeState;
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

/// Model-wide inputs of an element evaluation.
#[derive(Clone, Copy, Debug)]
pub struct EvalContext {
    /// Time (for statics, the time at which loads are evaluated).
    pub time: f64,
    /// Gravitational acceleration, global.
    pub gravity: Vector3<f64>,
    /// Multiplies all applied loads and gravity (static load continuation); 1 in dynamics.
    pub load_factor: f64,
}

/// Which outputs an evaluation must fill.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Need {
    Residual,
    ResidualAndTangents,
}

/// Local residual and tangents of one element, sized 6n (n = number of nodes).
#[derive(Clone, Debug)]
pub struct LocalTerms {
    pub r: DVector<f64>,
    pub k: DMatrix<f64>,
    pub c: DMatrix<f64>,
    pub m: DMatrix<f64>,
}

impl LocalTerms {
    pub fn new(n_nodes: usize) -> Self {
        let n = 6 * n_nodes;
        Self {
            r: DVector::zeros(n),
            k: DMatrix::zeros(n, n),
            c: DMatrix::zeros(n, n),
            m: DMatrix::zeros(n, n),
        }
    }

    pub fn clear(&mut self, need: Need) {
        // Through the slices: a plain memset (nalgebra's `fill` iterates element-wise).
        self.r.as_mut_slice().fill(0.0);
        if need == Need::ResidualAndTangents {
            self.k.as_mut_slice().fill(0.0);
            self.c.as_mut_slice().fill(0.0);
            self.m.as_mut_slice().fill(0.0);
        }
    }

    /// `r[6a + off .. +3] += v`.
    #[inline]
    pub fn add_r(&mut self, row: usize, v: &Vector3<f64>) {
        for i in 0..3 {
            self.r[row + i] += v[i];
        }
    }
}

/// Adds a 3×3 block into a local matrix at (row, col).
#[inline]
pub fn add_block(m: &mut DMatrix<f64>, row: usize, col: usize, b: &Matrix3<f64>) {
    for j in 0..3 {
        for i in 0..3 {
            m[(row + i, col + j)] += b[(i, j)];
        }
    }
}

/// A force element.
pub trait Element: Send + Sync {
    /// Name given in the model (for messages).
    fn name(&self) -> &str;
    /// Indices of the nodes the element touches, in the order of its local rows.
    fn nodes(&self) -> &[usize];
    /// Residual and (if asked) tangents; `out` is cleared by the caller.
    fn evaluate(&self, ctx: &EvalContext, nodes: &[NodeState], need: Need, out: &mut LocalTerms);
    /// Kinetic energy.
    fn kinetic_energy(&self, _nodes: &[NodeState]) -> f64 {
        0.0
    }
    /// Potential energy of conservative forces (gravity, springs).
    fn potential_energy(&self, _ctx: &EvalContext, _nodes: &[NodeState]) -> f64 {
        0.0
    }
    /// Power of the applied (non-conservative, external) loads.
    fn external_power(&self, _ctx: &EvalContext, _nodes: &[NodeState]) -> f64 {
        0.0
    }
    /// Power dissipated by dampers (≥ 0).
    fn dissipated_power(&self, _nodes: &[NodeState]) -> f64 {
        0.0
    }
}
