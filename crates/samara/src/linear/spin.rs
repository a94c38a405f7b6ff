//! A steady rotation applied to a set of nodes (spinning-rotor statics).
//!
//! The spinning nodes move rigidly with the rotation about the axis: with `Ω = Ω e`,
//!
//! ```text
//!     v = Ω × (x − c),     a = Ω × v,     w = RᵀΩ,     ẇ = 0,
//! ```
//!
//! so that the inertial forces of the elements at these rates are the centrifugal and
//! gyroscopic loads of the steady rotation. Perturbing the configuration (`x + δx`,
//! `R exp(δθ̃)`) with the rotation held gives `δv = Ω̃ δx`, `δa = Ω̃Ω̃ δx`, `δw = w̃ δθ`,
//! `δẇ = 0`: the rate maps of [`Spin::rate_maps`], which put `C A_v + M A₀` (centrifugal
//! softening `MΩ̃Ω̃`, gyroscopic stiffness `C_θ w̃`) into the static tangent. They are the
//! same maps as those of the rotating-frame linearization ([`super::linearize`]), so a
//! modal analysis that starts from a spinning static state finds it in equilibrium.

use super::SteadyRotation;
use crate::core::State;
use crate::math::so3::skew;
use crate::system::{RateMaps, System};
use nalgebra::{Matrix3, Vector3};

/// A steady rotation of some nodes of a model (all when `nodes` is `None`).
#[derive(Clone, Debug, PartialEq)]
pub struct Spin {
    pub rotation: SteadyRotation,
    /// Indices of the spinning nodes, ascending; `None`: every node.
    pub nodes: Option<Vec<usize>>,
}

impl Spin {
    /// Whether node `i` spins.
    pub fn spins(&self, i: usize) -> bool {
        self.nodes
            .as_ref()
            .is_none_or(|n| n.binary_search(&i).is_ok())
    }

    /// Whether every node of a model with `n_nodes` nodes spins.
    pub fn is_whole_model(&self, n_nodes: usize) -> bool {
        self.nodes.as_ref().is_none_or(|n| n.len() == n_nodes)
    }

    /// Sets the rates of `state` to the steady rotation at speed `omega` (the spinning
    /// nodes) and at rest (the others); joint-coordinate rates measured from the nodes,
    /// their accelerations and the element-state rates zero.
    pub fn impose(&self, sys: &System, state: &mut State, omega: f64) {
        let om = self.rotation.axis * omega;
        for (i, n) in state.nodes.iter_mut().enumerate() {
            if self.spins(i) {
                n.v = om.cross(&(n.x - self.rotation.centre));
                n.a = om.cross(&n.v);
                n.w = n.r().transpose() * om;
            } else {
                n.v = Vector3::zeros();
                n.a = Vector3::zeros();
                n.w = Vector3::zeros();
            }
            n.wd = Vector3::zeros();
        }
        sys.measure_coordinate_rates(state);
        for c in &mut state.coords {
            c.a = 0.0;
        }
        for z in &mut state.states {
            z.zd = 0.0;
        }
    }

    /// The rate maps of every node of `state` at speed `omega` (zero for nodes at rest):
    /// `A_v = (Ω̃, w̃)`, `A₀ = (Ω̃Ω̃, 0)`.
    pub fn rate_maps(&self, state: &State, omega: f64, out: &mut Vec<RateMaps>) {
        let om = skew(&(self.rotation.axis * omega));
        out.clear();
        out.extend(state.nodes.iter().enumerate().map(|(i, n)| {
            if self.spins(i) {
                RateMaps {
                    velocity: [om, skew(&n.w)],
                    acceleration: [om * om, Matrix3::zeros()],
                }
            } else {
                RateMaps::default()
            }
        }));
    }
}
