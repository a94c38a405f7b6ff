//! Geometrically exact beam (Simo–Reissner; Hodges' geometrically exact beam theory)
//! discretized with Legendre spectral finite elements, in the engine's node-based form:
//! every element node is an ordinary 6-DOF node (position, orientation), so beams share
//! nodes with bodies, joints and loads.
//!
//! # Formulation
//! - **Kinematics.** Reference line x(s) and section frame R(s) (x axis along the beam);
//!   strains in the section frame `ε = Rᵀx′ − R₀ᵀx₀′` (extension, two shears) and
//!   `κ = k − k₀` with `k̃ = RᵀR′` (twist, two bending curvatures) — Simo & Vu-Quoc 1986,
//!   Hodges 2006. Sectional forces `[N; M] = C [ε; κ] + D [ε̇; κ̇]` with a fully populated
//!   6×6 C (all couplings) and stiffness-proportional damping `D = diag(√μ) C diag(√μ)`.
//! - **Discretization.** Elements of order p with nodes at the Gauss–Lobatto–Legendre
//!   points (BeamDyn's LSFE; Wang et al. 2017). Positions are interpolated with the
//!   Lagrange polynomials; rotations by interpolating the nodal quaternions and
//!   normalizing, `R(s) = R(Σ hᵢ sᵢ / |Σ hᵢ sᵢ|)` (as Kynema), with the nodal quaternions
//!   sign-aligned to the element's middle node. The interpolation is objective (a rigid
//!   rotation of all nodes rotates the field) and path independent; reference strains are
//!   computed with the same interpolation, so the initial state is exactly strain free.
//!   An element may bend by less than 180° between its middle node and either end.
//! - **Exact variations.** Virtual rotations, angular velocities and accelerations of the
//!   interpolated field are derived from the interpolated quaternion itself
//!   ([`kernel`]), so the discrete inertia forces are the Euler–Lagrange forces of the
//!   interpolated kinetic energy (energy is conserved by the semi-discrete system) and the
//!   tangents K, C, M are the exact derivatives of the residual.
//! - **Quadrature.** Elastic terms with p Gauss points (`reduced`, default: no shear
//!   locking, no spurious zero-energy modes) or p + 1 (`full`); inertia, gravity and
//!   distributed loads always with p + 1 Gauss points.
//! - **Inertia** from the 6×6 sectional mass matrix (mass-centre offset, full inertia),
//!   Kirchhoff's form `F = ṗ + ω×p`, `M = ḣ + ω×h + V×p`; gravity as an acceleration.

// Index loops over nodes and quadrature points read closer to the formulas; NaN-rejecting
// comparisons (`!(x > 0.0)`) are intended.
#![allow(
    clippy::needless_range_loop,
    clippy::neg_cmp_op_on_partial_ord,
    clippy::type_complexity,
    clippy::nonminimal_bool
)]

pub mod element;
pub mod gll;
pub mod kernel;
pub mod quaternion;
pub mod reference_line;
pub mod section;
pub mod spec;

use crate::core::NodeState;
use crate::math::Rotation;
use element::{BeamElement, ElementSpec, SectionState};
use nalgebra::Vector3;
pub use spec::BeamDef;
use std::sync::Arc;

/// The elements of one beam (for output; the same elements are in the system's list).
#[derive(Clone, Debug)]
pub struct Beam {
    pub name: String,
    pub elements: Vec<Arc<BeamElement>>,
}

impl Beam {
    /// Builds the elements of a validated beam; the nodes' current orientations (the
    /// model's initial state) fix the node-to-section offsets.
    pub fn build(def: &BeamDef, nodes: &[NodeState]) -> Self {
        let loads = Arc::new(def.loads.clone());
        let table = Arc::new(def.table.clone());
        let p = def.order;
        let elements = (0..def.n_elements)
            .map(|e| {
                let idx = def.element_nodes(e);
                let local = e * p..=(e + 1) * p;
                let x0: Vec<Vector3<f64>> = idx.iter().map(|&i| nodes[i].x).collect();
                let frames: Vec<Rotation> = idx.iter().map(|&i| nodes[i].rot).collect();
                let etas = &def.etas[local.clone()];
                Arc::new(BeamElement::new(ElementSpec {
                    name: format!("{}[{e}]", def.name),
                    nodes: idx.to_vec(),
                    x0: &x0,
                    sections0: &def.sections0[local],
                    node_frames: &frames,
                    eta_range: (etas[0], etas[p]),
                    table: table.clone(),
                    damping: def.damping,
                    quadrature: def.quadrature,
                    loads: loads.clone(),
                }))
            })
            .collect();
        Self {
            name: def.name.clone(),
            elements,
        }
    }

    /// Sectional states at every elastic quadrature point, root to tip.
    pub fn sections(&self, nodes: &[NodeState]) -> Vec<SectionState> {
        let mut out = Vec::new();
        for e in &self.elements {
            e.sections(nodes, &mut out);
        }
        out
    }

    /// Sectional states at every elastic quadrature point, root to tip, written into `out`
    /// (`out.len() == n_section_points()`): allocation-free.
    pub fn sections_into(&self, nodes: &[NodeState], out: &mut [SectionState]) {
        let mut at = 0;
        for e in &self.elements {
            let n = e.n_section_points();
            e.sections_into(nodes, &mut out[at..at + n]);
            at += n;
        }
    }

    /// The beam's nodes root to tip (a node shared by two elements once) with their
    /// node-to-section offsets (w, x, y, z): the section frame at a node is its
    /// orientation ⊗ offset.
    pub fn nodes_with_offsets(&self) -> Vec<(usize, [f64; 4])> {
        let mut out: Vec<(usize, [f64; 4])> = Vec::new();
        for e in &self.elements {
            for (k, &n) in e.nodes_slice().iter().enumerate() {
                if k == 0 && out.last().is_some_and(|&(last, _)| last == n) {
                    continue;
                }
                out.push((n, e.section_offset(k)));
            }
        }
        out
    }

    pub fn n_section_points(&self) -> usize {
        self.elements.iter().map(|e| e.n_section_points()).sum()
    }
}
