//! Linearization of a model about a state: the mass, damping/gyroscopic and stiffness
//! matrices and the constraint Jacobian of the small-motion equations
//!
//! ```text
//!     M ÿ + G ẏ + K y + Bᵀ δλ = 0,      B y = 0,
//! ```
//!
//! built from the analytic tangents of [`System::matrices`] (no finite differences).
//!
//! **Unknowns y** (the configuration unknowns of [`System::n_config`]): per node a
//! translation `u` and a material rotation `φ` (`R' = R exp(φ̃)`), then the active joint
//! coordinates, then the element states. Translations are measured in the *reference
//! frame*: the inertial frame, or, for a [`SteadyRotation`], the frame turning with the
//! rotor (`δx = R_Ω(t) u`, `R_Ω(t) = exp(t Ω̃)`). The rates and accelerations of the
//! nonlinear unknowns follow from y:
//!
//! ```text
//!     δv = u̇ + Ω̃u,     δa = ü + 2Ω̃u̇ + Ω̃Ω̃u              (translation; Ω = 0 inertial)
//!     δw = φ̇ + w̃φ,     δẇ = φ̈ + w̃φ̇ + ẇ̃φ                  (material rotation)
//! ```
//!
//! (from `R'ᵀṘ' = w̃ + (w × φ + φ̇)~` to first order). Writing `δv = ẏ + A_v y`,
//! `δa = ÿ + A₁ ẏ + A₀ y` block by block, the linear matrices are
//!
//! ```text
//!     M_lin = M,     G = C + M A₁,     K_lin = K + C A_v + M A₀,
//! ```
//!
//! with `M = ∂r/∂a`, `C = ∂r/∂v`, `K = ∂r/∂q` (K includes the geometric stiffness of the
//! stresses and of the constraint forces `∂(Bᵀλ)/∂q` at the multipliers of the state).
//! In a rotating frame this gives the Coriolis (gyroscopic) matrix `2MΩ̃` and the
//! centrifugal softening `MΩ̃Ω̃` besides the centrifugal stiffening that the stressed
//! state puts into K. The equations are written at `t = 0` of the reference motion,
//! where `R_Ω = I`; for an axisymmetric rotor in steady rotation they do not depend on t.

use crate::core::State;
use crate::math::so3::skew;
use crate::system::System;
use faer::sparse::{SparseColMat, Triplet};
use nalgebra::{Matrix3, Vector3};

/// A steady rotation of the whole model at constant angular speed `omega` [rad/s] about
/// the axis through `centre` with unit direction `axis` (right-hand rule).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SteadyRotation {
    pub axis: Vector3<f64>,
    pub omega: f64,
    pub centre: Vector3<f64>,
}

impl SteadyRotation {
    /// Angular velocity vector Ω (global).
    pub fn angular_velocity(&self) -> Vector3<f64> {
        self.axis * self.omega
    }

    /// Sets the rates of `state` to those of the rigid rotation through its positions:
    /// `v = Ω × (x − c)`, `a = Ω × v`, `w = Rᵀ Ω`, `ẇ = 0`, joint-coordinate rates measured
    /// from the nodes with zero accelerations, element-state rates zero.
    pub fn impose(&self, sys: &System, state: &mut State) {
        let om = self.angular_velocity();
        for n in &mut state.nodes {
            n.v = om.cross(&(n.x - self.centre));
            n.a = om.cross(&n.v);
            n.w = n.r().transpose() * om;
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
}

/// The linearized equations about one state (sparse, compressed columns).
pub struct LinearSystem {
    /// Number of unknowns y and of constraint equations.
    pub n: usize,
    pub m: usize,
    /// `M`, n × n.
    pub mass: SparseColMat<usize, f64>,
    /// `G = C + M A₁`: damping, gyroscopic and Coriolis terms, n × n.
    pub damping: SparseColMat<usize, f64>,
    /// `K_lin = K + C A_v + M A₀`: elastic, geometric and centrifugal stiffness, n × n.
    pub stiffness: SparseColMat<usize, f64>,
    /// `B = ∂Φ/∂q`, m × n.
    pub constraint_jacobian: SparseColMat<usize, f64>,
    /// Name of each unknown, e.g. `tip.ux`, `tip.rz`, `shaft.theta`, `damper.stretch`.
    pub unknown_names: Vec<String>,
}

/// The kinematic maps of one node: `δv = ẏ + A_v y`, `δa = ÿ + A₁ẏ + A₀y` on its
/// translation block (index 0) and rotation block (index 1).
struct NodeMaps {
    a_v: [Matrix3<f64>; 2],
    a_1: [Matrix3<f64>; 2],
    a_0: [Matrix3<f64>; 2],
}

fn node_maps(state: &State, rotation: Option<&SteadyRotation>) -> Vec<NodeMaps> {
    let om = skew(&rotation.map_or(Vector3::zeros(), |r| r.angular_velocity()));
    state
        .nodes
        .iter()
        .map(|n| {
            let w = skew(&n.w);
            NodeMaps {
                a_v: [om, w],
                a_1: [2.0 * om, w],
                a_0: [om * om, skew(&n.wd)],
            }
        })
        .collect()
}

/// `A · T` for a sparse `A` and the block-diagonal map `T` of the nodes (identity, i.e.
/// nothing, on coordinates and states), as triplets appended to `out` with factor 1.
fn times_blocks(
    a: &SparseColMat<usize, f64>,
    maps: &[NodeMaps],
    pick: impl Fn(&NodeMaps) -> &[Matrix3<f64>; 2],
    out: &mut Vec<Triplet<usize, usize, f64>>,
) {
    let n6 = 6 * maps.len();
    let r = a.as_ref();
    for j in 0..a.ncols().min(n6) {
        let (node, d) = (j / 6, j % 6);
        let (blk, jj) = (d / 3, d % 3);
        let t = &pick(&maps[node])[blk];
        let base = 6 * node + 3 * blk;
        for (&i, &v) in r.row_idx_of_col_raw(j).iter().zip(r.val_of_col(j)) {
            for k in 0..3 {
                let x = v * t[(jj, k)];
                if x != 0.0 {
                    out.push(Triplet::new(i, base + k, x));
                }
            }
        }
    }
}

fn triplets(a: &SparseColMat<usize, f64>) -> Vec<Triplet<usize, usize, f64>> {
    let r = a.as_ref();
    let mut out = Vec::with_capacity(r.compute_nnz());
    for j in 0..a.ncols() {
        for (&i, &v) in r.row_idx_of_col_raw(j).iter().zip(r.val_of_col(j)) {
            out.push(Triplet::new(i, j, v));
        }
    }
    out
}

fn sparse(n: usize, t: &[Triplet<usize, usize, f64>]) -> SparseColMat<usize, f64> {
    SparseColMat::try_new_from_triplets(n, n, t)
        .expect("triplet indices are inside the matrix by construction")
}

/// Names of the configuration unknowns of `sys`.
pub fn unknown_names(sys: &System) -> Vec<String> {
    const DOF: [&str; 6] = ["ux", "uy", "uz", "rx", "ry", "rz"];
    let mut out: Vec<String> = sys
        .node_names
        .iter()
        .flat_map(|n| DOF.iter().map(move |d| format!("{n}.{d}")))
        .collect();
    out.extend(sys.coordinate_names.iter().take(sys.n_coordinates).cloned());
    out.extend(sys.state_names.iter().cloned());
    out
}

/// Linearizes `sys` about `state` (positions, rates, accelerations and multipliers as
/// they are), in the inertial frame or, with `rotation`, in the frame turning with it.
/// For a steadily rotating state, impose its rates first with [`SteadyRotation::impose`].
pub fn linearize(sys: &System, state: &State, rotation: Option<&SteadyRotation>) -> LinearSystem {
    // A sample-and-hold is a constant input of the linearized equations: its value held
    // at the operating point (taken there when the state holds none, after statics).
    let sampled;
    let state = if state.held.len() == sys.n_held {
        state
    } else {
        let mut s = state.clone();
        sys.sample(&mut s, true);
        sampled = s;
        &sampled
    };
    let ctx = sys.context(state.time, 1.0);
    let mats = sys.matrices(&ctx, state);
    let n = mats.n;
    let maps = node_maps(state, rotation);
    let mut g = triplets(&mats.damping);
    times_blocks(&mats.mass, &maps, |m| &m.a_1, &mut g);
    let mut k = triplets(&mats.stiffness);
    times_blocks(&mats.damping, &maps, |m| &m.a_v, &mut k);
    times_blocks(&mats.mass, &maps, |m| &m.a_0, &mut k);
    LinearSystem {
        n,
        m: mats.m,
        mass: mats.mass,
        damping: sparse(n, &g),
        stiffness: sparse(n, &k),
        constraint_jacobian: mats.constraint_jacobian,
        unknown_names: unknown_names(sys),
    }
}
