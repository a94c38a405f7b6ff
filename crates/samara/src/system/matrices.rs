//! The system's equations taken apart at a state: residual `r`, constraint values `Φ`,
//! and the tangent matrices `M = ∂r/∂v̇`, `C = ∂r/∂v`, `K = ∂r/∂q`, `B = ∂Φ/∂q`, each
//! assembled on its own (the Newton iteration matrix of each formulation is a
//! combination of them; linearized analyses use them as they are).
//!
//! Unknowns are the configuration unknowns of [`System::n_config`]: per node (δx global,
//! δθ material), then the active joint coordinates, then the element states. For an
//! element state, its K column is `∂r/∂z` and its C column `∂r/∂ż`. The residual is
//! `r = r_elements + Bᵀλ + r_coordinates` with the multipliers λ of the state (physical
//! units), so `K` includes the constraint forces' geometric stiffness `∂(Bᵀλ)/∂q` at
//! fixed λ. Signals enter through the chain rule, channel by channel. Perturbations of
//! rotations are material (`R exp(δθ̃)`), as everywhere else.

use super::System;
use crate::core::{CoordinateTangents, EvalContext, LocalTerms, Need, State};
use faer::sparse::{SparseColMat, Triplet};
use nalgebra::DMatrix;

/// The separated matrices at one state (sparse, compressed columns).
pub struct SystemMatrices {
    /// Number of configuration unknowns and of enforced constraint equations.
    pub n: usize,
    pub m: usize,
    pub mass: SparseColMat<usize, f64>,
    pub damping: SparseColMat<usize, f64>,
    pub stiffness: SparseColMat<usize, f64>,
    /// `B`, m × n.
    pub constraint_jacobian: SparseColMat<usize, f64>,
    pub residual: Vec<f64>,
    pub constraint_values: Vec<f64>,
}

/// Triplets of the three channels.
#[derive(Default)]
struct Channels {
    k: Vec<Triplet<usize, usize, f64>>,
    c: Vec<Triplet<usize, usize, f64>>,
    m: Vec<Triplet<usize, usize, f64>>,
}

impl Channels {
    fn push(&mut self, row: usize, col: usize, v: [f64; 3]) {
        for (list, x) in [&mut self.k, &mut self.c, &mut self.m].into_iter().zip(v) {
            if x != 0.0 {
                list.push(Triplet::new(row, col, x));
            }
        }
    }
}

fn sparse(rows: usize, cols: usize, t: &[Triplet<usize, usize, f64>]) -> SparseColMat<usize, f64> {
    SparseColMat::try_new_from_triplets(rows, cols, t)
        .expect("triplet indices are inside the matrix by construction")
}

impl System {
    /// Configuration index of each local unknown of element `k` (nodes, then states).
    fn element_config(&self, k: usize) -> Vec<usize> {
        let e = &self.elements[k];
        e.nodes()
            .iter()
            .flat_map(|&i| (0..6).map(move |d| 6 * i + d))
            .chain((0..e.n_states()).map(|i| self.state_config_index(self.state_offsets[k] + i)))
            .collect()
    }

    /// Configuration index of each local column of constraint `k`'s `B`.
    fn constraint_config(&self, k: usize) -> Vec<usize> {
        let c = &self.constraints[k];
        let n6 = 6 * self.n_nodes();
        c.nodes()
            .iter()
            .flat_map(|&i| (0..6).map(move |d| 6 * i + d))
            .chain((0..c.n_coordinates()).map(|j| n6 + self.coordinate_offsets[k] + j))
            .collect()
    }

    /// Assembles `r`, `Φ`, `M`, `C`, `K` and `B` at `state` (multipliers from
    /// `state.lambda`, enforced rows).
    pub fn matrices(&self, ctx: &EvalContext, state: &State) -> SystemMatrices {
        let n = self.n_config();
        let nm = self.n_multipliers;
        let mut ch = Channels::default();
        let mut residual = vec![0.0; n];
        // Signals and their derivatives.
        let mut sv = self.signals.values(&self.elements);
        self.signals.evaluate(
            &self.elements,
            &self.state_offsets,
            ctx,
            state,
            &mut sv,
            true,
        );
        let mut scratch = Vec::new();
        for (k, e) in self.elements.iter().enumerate() {
            let mut t = LocalTerms::for_element(e.as_ref());
            t.clear(Need::ResidualAndTangents);
            let x = self.element_input(k, state, &sv.values, &mut scratch);
            e.evaluate(ctx, &x, Need::ResidualAndTangents, &mut t);
            let cfg = self.element_config(k);
            for (i, &ri) in cfg.iter().enumerate() {
                residual[ri] += t.r[i];
                for (j, &cj) in cfg.iter().enumerate() {
                    ch.push(ri, cj, [t.k[(i, j)], t.c[(i, j)], t.m[(i, j)]]);
                }
                for (j, &s) in self.signals.element_inputs[k].iter().enumerate() {
                    let d = t.ds[(i, j)];
                    if d == 0.0 {
                        continue;
                    }
                    for (g, &c) in sv.gradients[s].iter().zip(&self.signals.support[s]) {
                        ch.push(ri, c, [d * g[0], d * g[1], d * g[2]]);
                    }
                }
            }
        }
        let mut b_trip = Vec::new();
        let mut phi_all = vec![0.0; nm];
        for (k, c) in self.constraints.iter().enumerate() {
            let m = c.n_equations();
            let cfg = self.constraint_config(k);
            let nl = cfg.len();
            let coords = self.coords_of(k, state);
            let mut phi = vec![0.0; m];
            let mut b = DMatrix::zeros(m, nl);
            c.evaluate(ctx, &state.nodes, coords, &mut phi, Some(&mut b));
            let off = self.multiplier_offsets[k];
            let lam = &state.lambda[off..off + m];
            self.subtract_servo_targets(k, &sv.values, &mut phi);
            phi_all[off..off + m].copy_from_slice(&phi);
            // Servo rows: −∂s/∂x joins the row of B over the signal's support (K channel;
            // the rate and acceleration channels of a servo's signal have no place in B).
            for sr in c.servo_rows() {
                let Some(i) = c.active_rows().iter().position(|&r| r == sr.row) else {
                    continue;
                };
                let s = self.signals.constraint_inputs[k][sr.input];
                for (g, &cfg) in sv.gradients[s].iter().zip(&self.signals.support[s]) {
                    if g[0] != 0.0 {
                        b_trip.push(Triplet::new(off + i, cfg, -g[0]));
                    }
                }
            }
            let mut kc = DMatrix::zeros(nl, nl);
            c.reaction_tangent(ctx, &state.nodes, coords, lam, &mut kc);
            for (j, &cj) in cfg.iter().enumerate() {
                for r in 0..m {
                    residual[cj] += b[(r, j)] * lam[r];
                    if b[(r, j)] != 0.0 {
                        b_trip.push(Triplet::new(off + r, cj, b[(r, j)]));
                    }
                }
                for (i, &ci) in cfg.iter().enumerate() {
                    ch.push(ci, cj, [kc[(i, j)], 0.0, 0.0]);
                }
            }
            // Elements on the coordinates.
            let nc = c.n_coordinates();
            if nc > 0 {
                let inputs = self.constraint_signals(k, &sv.values);
                let n_in = inputs.len();
                let (mut r, mut kd, mut cd, mut sd) = (
                    vec![0.0; nc],
                    vec![0.0; nc],
                    vec![0.0; nc],
                    vec![0.0; nc * n_in],
                );
                c.coordinate_forces(
                    ctx,
                    coords,
                    &inputs,
                    &mut r,
                    Some(CoordinateTangents {
                        stiffness: &mut kd,
                        damping: &mut cd,
                        signals: &mut sd,
                    }),
                );
                let q0 = 6 * self.n_nodes() + self.coordinate_offsets[k];
                for j in 0..nc {
                    residual[q0 + j] += r[j];
                    ch.push(q0 + j, q0 + j, [kd[j], cd[j], 0.0]);
                    for (i, &s) in self.signals.constraint_inputs[k].iter().enumerate() {
                        let d = sd[j * n_in + i];
                        if d == 0.0 {
                            continue;
                        }
                        for (g, &cfg) in sv.gradients[s].iter().zip(&self.signals.support[s]) {
                            ch.push(q0 + j, cfg, [d * g[0], d * g[1], d * g[2]]);
                        }
                    }
                }
            }
        }
        SystemMatrices {
            n,
            m: nm,
            mass: sparse(n, n, &ch.m),
            damping: sparse(n, n, &ch.c),
            stiffness: sparse(n, n, &ch.k),
            constraint_jacobian: sparse(nm, n, &b_trip),
            residual,
            constraint_values: phi_all,
        }
    }
}
