//! Contact between two spheres centred at two nodes (body–body), frictionless, with the
//! normal laws of [`super::contact`].
//!
//! With `d = x_B − x_A`, the unit normal `n = d/|d|` (from A to B), the penetration
//! `δ = ρ_A + ρ_B − |d|` and its rate `δ̇ = −n·(v_B − v_A)`, the normal force N(δ, δ̇)
//! (Hunt–Crossley or linear, zero out of contact and never pulling) pushes B along +n
//! and A along −n through the centres: no moments, and the pair's momentum is conserved.
//! Hunt–Crossley's restitution relation holds for the relative motion with the reduced
//! mass (it does not depend on the mass).
//!
//! Tangents: the normal direction's derivative `∂n/∂d = (I − n nᵀ)/|d|` enters both the
//! force direction and δ̇.

use super::contact::{NormalLaw, normal_event, normal_force, normal_potential};
use super::{Element, EvalContext, LocalTerms, Need};
use crate::core::ElementInput;
use nalgebra::{Matrix3, Vector3};

/// A frictionless sphere–sphere contact.
#[derive(Clone, Debug)]
pub struct SpherePair {
    name: String,
    nodes: [usize; 2],
    radii: [f64; 2],
    law: NormalLaw,
}

impl SpherePair {
    pub fn new(
        name: impl Into<String>,
        nodes: [usize; 2],
        radii: [f64; 2],
        law: NormalLaw,
    ) -> Self {
        Self {
            name: name.into(),
            nodes,
            radii,
            law,
        }
    }

    /// `(n, |d|, δ, δ̇, relative velocity)`.
    fn kinematics(&self, x: &ElementInput) -> (Vector3<f64>, f64, f64, f64, Vector3<f64>) {
        let (a, b) = (&x.nodes[self.nodes[0]], &x.nodes[self.nodes[1]]);
        let d = b.x - a.x;
        let dist = d.norm();
        let n = if dist > 0.0 { d / dist } else { Vector3::z() };
        let u = b.v - a.v;
        (n, dist, self.radii[0] + self.radii[1] - dist, -n.dot(&u), u)
    }
}

impl Element for SpherePair {
    fn name(&self) -> &str {
        &self.name
    }

    fn nodes(&self) -> &[usize] {
        &self.nodes
    }

    fn evaluate(&self, _ctx: &EvalContext, x: &ElementInput, need: Need, out: &mut LocalTerms) {
        let (n, dist, delta, delta_dot, u) = self.kinematics(x);
        let [nf, dn_dd, dn_dv, _] = normal_force(&self.law, delta, delta_dot);
        // Residual rows: A gets +N n (the force on A is −N n), B gets −N n.
        for i in 0..3 {
            out.r[i] += nf * n[i];
            out.r[6 + i] -= nf * n[i];
        }
        if need == Need::Residual || nf == 0.0 || dist == 0.0 {
            return;
        }
        // ∂n/∂d = P/|d|, P = I − n nᵀ; ∂δ/∂d = −nᵀ; ∂δ̇/∂d = −uᵀ P/|d|; ∂δ̇/∂u = −nᵀ.
        let p = (Matrix3::identity() - n * n.transpose()) / dist;
        let dn_q = -(n.transpose()) * dn_dd - (u.transpose() * p) * dn_dv;
        let dn_u = -(n.transpose()) * dn_dv;
        // ∂(N n)/∂d and ∂(N n)/∂u.
        let kd = n * dn_q + p * nf;
        let cu = n * dn_u;
        // d = x_B − x_A: columns of B with +, of A with −; rows of A +, of B −.
        for (ro, rs) in [(0usize, 1.0), (6, -1.0)] {
            for (co, cs) in [(0usize, -1.0), (6, 1.0)] {
                for i in 0..3 {
                    for j in 0..3 {
                        out.k[(ro + i, co + j)] += rs * cs * kd[(i, j)];
                        out.c[(ro + i, co + j)] += rs * cs * cu[(i, j)];
                    }
                }
            }
        }
    }

    fn potential_energy(&self, _ctx: &EvalContext, x: &ElementInput) -> f64 {
        normal_potential(&self.law, self.kinematics(x).2)
    }

    fn dissipated_power(&self, x: &ElementInput) -> f64 {
        let (_, _, delta, delta_dot, _) = self.kinematics(x);
        let [nf, _, _, el] = normal_force(&self.law, delta, delta_dot);
        if delta > 0.0 {
            (nf - el) * delta_dot
        } else {
            0.0
        }
    }

    fn n_events(&self) -> usize {
        1
    }

    fn events(&self, x: &ElementInput, out: &mut [(f64, f64)]) {
        let (_, _, delta, delta_dot, _) = self.kinematics(x);
        out[0] = normal_event(&self.law, delta, delta_dot);
    }

    fn output_names(&self) -> Vec<(String, &'static str)> {
        vec![("normal_force".into(), "N"), ("penetration".into(), "m")]
    }

    fn outputs(&self, _ctx: &EvalContext, x: &ElementInput, out: &mut [f64]) {
        let (_, _, delta, delta_dot, _) = self.kinematics(x);
        out[0] = normal_force(&self.law, delta, delta_dot)[0];
        out[1] = delta;
    }
}
