//! The step of the energy-consistent integrators as elements see it
//! (`integrator = "energy_preserving"` / `"energy_decaying"`, docs/integrators.md).
//!
//! Over a step of size h each node moves by `Δ = (Δx, ψ)`: `x₁ = x₀ + Δx`,
//! `R₁ = R₀ cay(ψ)` ([`crate::math::cayley`]). An element with a discrete form returns
//! its *discrete residual* `r̄` (6 rows per node, like [`super::Element::evaluate`]) such
//! that over the step
//!
//! ```text
//! Σ_nodes Δ · r̄ = (T₁ − T₀) + (V₁ − V₀) + D − W        exactly,
//! ```
//!
//! with T its kinetic and V its potential energy, D ≥ 0 what its dampers dissipate and W
//! the work of its applied loads: a discrete gradient in the sense of Gonzalez (1996).
//! Rotation rows are the moments conjugate to ψ: a spatial moment m̄ about the node (forces
//! at the mean arms `(R₀s + R₁s)/2`) enters as `(I − ψ̃/2) R₀ᵀ m̄`, which makes the
//! discrete moment balance of the Cayley update exact, so momenta are conserved where the
//! forces are internal (Simo & Wong 1991).

use super::{EvalContext, NodeState};
use nalgebra::Vector3;

/// One step as seen by a discrete form.
#[derive(Clone, Copy, Debug)]
pub struct DiscreteStep<'a> {
    pub h: f64,
    /// Context at the mid-point time t₀ + h/2.
    pub ctx: EvalContext,
    /// Node states at the start of the step (t₀).
    pub start: &'a [NodeState],
    /// Node states at the end (t₀ + h), with the velocities of the scheme.
    pub end: &'a [NodeState],
    /// Mid-point states: `x₀ + Δx/2`, `R₀ cay(ψ/2)`, velocities `Δx/h`, `ψ/h`.
    pub mid: &'a [NodeState],
    /// `(Δx, ψ)` of every node, 6 per node.
    pub increments: &'a [f64],
    /// Dissipation coefficient c ≥ 0 of the energy-decaying scheme (0: preserving). An
    /// element with a potential that keeps a dissipation memory
    /// ([`super::Element::discrete_memory_len`]) adds the dissipative stress
    /// `c C (e − e_prev)` on its strain increments e over the step, with `e_prev` =
    /// [`DiscreteStep::memory`] (the previous step's, already scaled by the step ratio),
    /// so that its balance gains `D = c eᵀ C (e − e_prev)` exactly.
    pub decay: f64,
    /// The element's strain increments of the previous step times `min(h/h_prev, 1)`
    /// (zeros on the first step); empty when the scheme is preserving or the element
    /// keeps no memory.
    pub memory: &'a [f64],
}

impl DiscreteStep<'_> {
    /// `(Δx, ψ)` of node `i`.
    #[inline]
    pub fn increment(&self, i: usize) -> (Vector3<f64>, Vector3<f64>) {
        let d = &self.increments[6 * i..6 * i + 6];
        (
            Vector3::new(d[0], d[1], d[2]),
            Vector3::new(d[3], d[4], d[5]),
        )
    }

    /// The moment row conjugate to ψ of node `i` for a spatial moment `m` about the node
    /// taken with the mean arms: `(I − ψ̃/2) R₀ᵀ m`.
    #[inline]
    pub fn conjugate_moment(&self, i: usize, m: &Vector3<f64>) -> Vector3<f64> {
        let (_, psi) = self.increment(i);
        let a = self.start[i].r().transpose() * m;
        a - psi.cross(&a) * 0.5
    }

    /// Mean arm `(R₀ s + R₁ s)/2` of a body point at offset `s` (node frame) on node `i`.
    #[inline]
    pub fn mean_arm(&self, i: usize, s: &Vector3<f64>) -> Vector3<f64> {
        (self.start[i].r() * s + self.end[i].r() * s) * 0.5
    }
}

/// Gonzalez's correction of a mid-point gradient `g` into a discrete gradient:
/// `g + (ΔV − g·Δ) Δ/|Δ|²`, so that `g·Δ = ΔV` exactly (Gonzalez 1996, J. Nonlinear Sci.
/// 6, eq. 3.4). The correction is O(|Δ|²) for a smooth V, keeping second order. Nothing is
/// done for `Δ = 0` (ΔV = 0 then).
pub fn gonzalez_correction(g: &mut [f64], delta: &[f64], dv: f64) {
    let n2: f64 = delta.iter().map(|d| d * d).sum();
    if n2 == 0.0 || !n2.is_finite() {
        return;
    }
    let gd: f64 = g.iter().zip(delta).map(|(a, b)| a * b).sum();
    let c = (dv - gd) / n2;
    for (gi, d) in g.iter_mut().zip(delta) {
        *gi += c * d;
    }
}
