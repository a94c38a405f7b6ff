//! Joints: holonomic constraints `Φ(q) = 0` enforced with Lagrange multipliers.
//!
//! A constraint returns `Φ`, its Jacobian `B = ∂Φ/∂q` (material rotation increments, the
//! same unknowns as the elements), the tangent `∂(Bᵀμ)/∂q` at fixed multipliers, and the
//! convective part of `Φ̈` for consistent initial accelerations. Scaling, the
//! augmented-Lagrangian term and the assembly of `Bᵀμ` are done generically by the
//! assembler.

pub mod building_blocks;
mod joint;

pub use joint::{Component, Joint};

use crate::elements::EvalContext;
use crate::system::NodeState;
use nalgebra::{DMatrix, Vector3};

/// A holonomic, scleronomic constraint on a few nodes.
pub trait Constraint: Send + Sync {
    fn name(&self) -> &str;
    /// Nodes touched, in the order of the local columns of `B`.
    fn nodes(&self) -> &[usize];
    /// Number of scalar equations (multipliers).
    fn n_equations(&self) -> usize;
    /// `Φ` and, if given, `B` (`n_equations × 6·nodes`, overwritten).
    fn evaluate(
        &self,
        ctx: &EvalContext,
        nodes: &[NodeState],
        phi: &mut [f64],
        b: Option<&mut DMatrix<f64>>,
    );
    /// Adds `∂(Bᵀμ)/∂q` at fixed `μ` into `k` (`6·nodes` square).
    fn reaction_tangent(
        &self,
        ctx: &EvalContext,
        nodes: &[NodeState],
        mu: &[f64],
        k: &mut DMatrix<f64>,
    );
    /// `Φ̈ − B v̇`: the part of the constraint acceleration independent of accelerations.
    fn acceleration_term(&self, ctx: &EvalContext, nodes: &[NodeState], out: &mut [f64]);
    /// Force and moment exerted on side B by side A (about B's frame origin), in frame-A
    /// components, for multipliers `μ` in physical units.
    fn reactions(&self, nodes: &[NodeState], mu: &[f64]) -> (Vector3<f64>, Vector3<f64>);
    /// Global position of the joint point on side B and the axes of frame A (columns,
    /// global components), for output.
    fn location(&self, nodes: &[NodeState]) -> (Vector3<f64>, nalgebra::Matrix3<f64>);
}
