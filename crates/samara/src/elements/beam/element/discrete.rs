//! The beam element's discrete form for the energy-consistent integrators
//! (`integrator = "energy_preserving"` / `"energy_decaying"`; docs/integrators.md).
//!
//! - **Inertia** lumped at the nodes by Gauss–Lobatto quadrature of the kinetic energy
//!   (at a GLL node the interpolated section is the node's own, so each node carries a
//!   rigid section of mass `w_k |x₀′| m` and inertia `w_k |x₀′| J`): every node is a rigid
//!   body at its mass centre with Simo & Wong's (1991) discrete form, exact for ΔT and for
//!   the discrete balance of linear and angular momentum.
//! - **Strain energy** by a discrete gradient (Gonzalez 1996) that keeps the momenta: the
//!   mid-point gradient `g` (rows conjugate to ψ, [`crate::core::DiscreteStep`]) plus
//!   `c w`, with `w` the part of the increment Δ orthogonal to the six rigid motions of
//!   the element about the mid-point configuration and `c = (ΔV − g·Δ)/(w·Δ)`. Then
//!   `Δ·r̄ = ΔV` exactly, `g` is self-equilibrated (V is objective) and so is `w`: the
//!   internal forces have no resultant and no moment (Gonzalez 1996 builds discrete
//!   gradients on the invariants for the same reason; Simo, Tarnow & Doblaré 1995 reach
//!   the statement with mid-point strains).
//! - **Damping** (stiffness-proportional) at the mid-point configuration with the mean
//!   rates `Δ/h`: `Δ·r̄ = h ε̇ᵀ D ε̇ ≥ 0`.
//! - **Decay** (c > 0, the energy-decaying scheme): the strain increments `e_g = ε_g(q₁) −
//!   ε_g(q₀)` at the elastic points are the element's dissipation memory; the mid-point
//!   gradient is taken with the stress `C(ε − ε₀) + c C (e_g − e_g,prev)` and the
//!   correction along w completes `Δ·r̄ = ΔV + D`, `D = c Σ w_g e_gᵀ C (e_g − e_g,prev)`
//!   (the spring's `c k Δl (Δl − Δl_prev)`). The added stress goes through the same
//!   mid-point kinematics as g, so it has no resultant and no moment.
//! - **Gravity** on the lumped masses: `−m_k g`, the exact gradient of the lumped
//!   potential.

use super::{BeamElement, ElasticOut, ElasticSection, Work, g_mat, kernel, with_work};
use crate::core::{DiscreteStep, NodeState};
use crate::elements::EvalContext;
use nalgebra::{Matrix3, Matrix6, Vector3, Vector6};

impl BeamElement {
    /// The discrete form exists unless the beam carries distributed loads or its sections'
    /// mass centres are off the reference line (the lumped nodes are written about it).
    pub(super) fn check_discrete_form(&self) -> Result<(), String> {
        if !self.loads.is_empty() {
            return Err("a beam with distributed loads (`[[beams.loads]]`) has no energy-consistent discrete form yet: apply the loads at nodes with `[[forces]]`".into());
        }
        if self.lumped.iter().any(|l| l.offset) {
            return Err("a beam whose sections' mass centre is off the reference line has no energy-consistent discrete form yet (the lumped inertia is written about the reference line)".into());
        }
        Ok(())
    }

    /// Kinetic energy of the lumped inertia: `Σ ½ m_k |v_k|² + ½ Ω_kᵀ J_k Ω_k`.
    pub(super) fn lumped_kinetic_energy(&self, nodes: &[NodeState]) -> f64 {
        self.nodes
            .iter()
            .zip(&self.lumped)
            .map(|(&i, l)| {
                let n = &nodes[i];
                0.5 * (l.mass * n.v.norm_squared() + n.w.dot(&(l.inertia * n.w)))
            })
            .sum()
    }

    /// Strain energy plus the lumped masses' gravity potential `−Σ m_k g·x_k`.
    pub(super) fn lumped_potential_energy(&self, ctx: &EvalContext, nodes: &[NodeState]) -> f64 {
        let grav = ctx.gravity * ctx.load_factor;
        let u = with_work(self.nodes.len(), |g| {
            self.gather(nodes, g);
            self.strains(g, None)
        });
        u - self
            .nodes
            .iter()
            .zip(&self.lumped)
            .map(|(&i, l)| l.mass * grav.dot(&nodes[i].x))
            .sum::<f64>()
    }

    /// `(node, mass)` of the lumped inertia.
    pub fn lumped_node_masses(&self) -> impl Iterator<Item = (usize, f64)> + '_ {
        self.nodes
            .iter()
            .zip(&self.lumped)
            .map(|(&i, l)| (i, l.mass))
    }

    /// Linear and angular momentum (about the origin) of the lumped inertia.
    pub fn lumped_momenta(&self, nodes: &[NodeState]) -> (Vector3<f64>, Vector3<f64>) {
        let mut p = Vector3::zeros();
        let mut l = Vector3::zeros();
        for (&i, ln) in self.nodes.iter().zip(&self.lumped) {
            let n = &nodes[i];
            let pk = n.v * ln.mass;
            p += pk;
            l += n.x.cross(&pk) + n.r() * (ln.inertia * n.w);
        }
        (p, l)
    }

    /// Strain energy of the gathered configuration; the strains at the elastic points
    /// into `out` if given.
    fn strains(&self, g: &Work, mut out: Option<&mut [Vector6<f64>]>) -> f64 {
        let mut eo = ElasticOut::default();
        let mut u = 0.0;
        for (p, ep) in self.elastic.iter().enumerate() {
            let f = self.elastic_fields(ep, g);
            let c = self.table.stiffness_at(ep.eta);
            let sec = ElasticSection {
                c: &c,
                d: None,
                eps0: ep.eps0,
                k0: ep.k0,
            };
            kernel::elastic(&f, &sec, false, &mut eo);
            u += 0.5 * ep.w * eo.strain.dot(&(c * eo.strain));
            if let Some(o) = out.as_deref_mut() {
                o[p] = eo.strain;
            }
        }
        u
    }

    /// Elastic (and, with `damping`, damping) residual rows of the gathered configuration
    /// into `out` (6 per node; rotation rows conjugate to the node's material increment).
    /// `shift`: strain offsets per elastic point subtracted from the reference strains
    /// (a stress `C shift` added: the decaying scheme's dissipative stress).
    fn elastic_rows(
        &self,
        g: &mut Work,
        damping: bool,
        shift: Option<&[Vector6<f64>]>,
        out: &mut [f64],
    ) {
        let nn = self.nodes.len();
        out[..6 * nn].fill(0.0);
        g.fq[..nn].fill(super::Quat::zeros());
        let mut eo = ElasticOut::default();
        for (p, ep) in self.elastic.iter().enumerate() {
            let f = self.elastic_fields(ep, g);
            let (mut eps0, mut k0) = (ep.eps0, ep.k0);
            if let Some(sh) = shift {
                eps0 -= sh[p].fixed_rows::<3>(0);
                k0 -= sh[p].fixed_rows::<3>(3);
            }
            let (c, d) = self.section_matrices(ep);
            let sec = ElasticSection {
                c: &c,
                d: if damping { d.as_ref() } else { None },
                eps0,
                k0,
            };
            kernel::elastic(&f, &sec, false, &mut eo);
            let (h, dh) = self.shape_of(ep);
            for j in 0..nn {
                let fx = eo.f_xp * (ep.w * dh[j]);
                for i in 0..3 {
                    out[6 * j + i] += fx[i];
                }
                g.fq[j] += (eo.f_q * h[j] + eo.f_qp * dh[j]) * ep.w;
            }
        }
        for j in 0..nn {
            let mut m = g_mat(&g.s[j]).transpose() * g.fq[j];
            if let Some((_, om)) = self.offsets[j].as_deref() {
                m = om * m;
            }
            for i in 0..3 {
                out[6 * j + 3 + i] = m[i];
            }
        }
    }

    /// The discrete residual ([`DiscreteStep`]; the module's documentation).
    pub(super) fn discrete_rows(&self, step: &DiscreteStep, out: &mut [f64]) {
        let nn = self.nodes.len();
        let h = step.h;
        let grav = step.ctx.gravity * step.ctx.load_factor;
        // Lumped inertia and gravity (Simo & Wong's Cayley form, as the rigid body's).
        for (k, (&i, l)) in self.nodes.iter().zip(&self.lumped).enumerate() {
            let (n0, n1) = (&step.start[i], &step.end[i]);
            let (_, psi) = step.increment(i);
            let f = (n1.v - n0.v) * (l.mass / h) - grav * l.mass;
            let jw = l.inertia * (n0.w + n1.w) * 0.5;
            let m = l.inertia * (n1.w - n0.w) / h + psi.cross(&jw) / h;
            for q in 0..3 {
                out[6 * k + q] += f[q];
                out[6 * k + 3 + q] += m[q];
            }
        }
        with_work(nn, |g| {
            // Strain energies and strains at both ends of the step.
            let mut strain0 = std::mem::take(&mut g.strain0);
            let mut strain1 = std::mem::take(&mut g.strain1);
            self.gather(step.start, g);
            let v0 = self.strains(g, Some(&mut strain0));
            self.gather(step.end, g);
            let v1 = self.strains(g, Some(&mut strain1));
            // Decay: dissipative stress c C (e − e_prev) through the strain offsets
            // (strain1 becomes the offsets), its dissipation D = c Σ w eᵀ C (e − e_prev).
            let mut dis = 0.0;
            let decaying = step.decay > 0.0;
            if decaying {
                for (p, ep) in self.elastic.iter().enumerate() {
                    let e = strain1[p] - strain0[p];
                    let prev = if step.memory.len() >= 6 * (p + 1) {
                        Vector6::from_column_slice(&step.memory[6 * p..6 * p + 6])
                    } else {
                        Vector6::zeros()
                    };
                    let shift = (e - prev) * step.decay;
                    dis += ep.w * e.dot(&(self.table.stiffness_at(ep.eta) * shift));
                    strain1[p] = shift;
                }
            }
            // Mid-point gradient, rows conjugate to ψ: (I − ψ̃/2) R₀ᵀ R_mid r_θ.
            self.gather(step.mid, g);
            let mut rows = std::mem::take(&mut g.rows_a);
            let mut damp = std::mem::take(&mut g.rows_b);
            let shift = decaying.then_some(&strain1[..self.elastic.len()]);
            self.elastic_rows(g, false, shift, &mut rows);
            let damped = self.root_damping.is_some();
            if damped {
                self.elastic_rows(g, true, shift, &mut damp);
                for (a, b) in damp.iter_mut().zip(&rows) {
                    *a -= b;
                }
            }
            let to_psi = |k: usize, r: &mut [f64]| {
                let i = self.nodes[k];
                let (_, psi) = step.increment(i);
                let c = step.start[i].r().transpose() * step.mid[i].r();
                let a = c * Vector3::new(r[6 * k + 3], r[6 * k + 4], r[6 * k + 5]);
                let m = a - psi.cross(&a) * 0.5;
                r[6 * k + 3..6 * k + 6].copy_from_slice(m.as_slice());
            };
            for k in 0..nn {
                to_psi(k, &mut rows);
                if damped {
                    to_psi(k, &mut damp);
                }
            }
            // Part of Δ orthogonal to the rigid motions about the mid-point configuration:
            // translation t and rotation θ move node k by (t + θ × x̄_k, A_k θ) with
            // A_k = (I + ψ̃_k/2)⁻¹ R₀ₖᵀ, the ψ that a rigid rotation θ gives the node.
            let mut gram = Matrix6::<f64>::zeros();
            let mut b = Vector6::<f64>::zeros();
            let rigid = |k: usize| -> Matrix6<f64> {
                let i = self.nodes[k];
                let (_, psi) = step.increment(i);
                let xm = step.mid[i].x;
                let a = (Matrix3::identity() + crate::math::skew(&psi) * 0.5)
                    .try_inverse()
                    .unwrap_or_else(Matrix3::identity)
                    * step.start[i].r().transpose();
                let mut z = Matrix6::zeros();
                z.fixed_view_mut::<3, 3>(0, 0)
                    .copy_from(&Matrix3::identity());
                z.fixed_view_mut::<3, 3>(0, 3)
                    .copy_from(&(-crate::math::skew(&xm)));
                z.fixed_view_mut::<3, 3>(3, 3).copy_from(&a);
                z
            };
            let delta_of = |k: usize| -> Vector6<f64> {
                let (dx, psi) = step.increment(self.nodes[k]);
                Vector6::new(dx[0], dx[1], dx[2], psi[0], psi[1], psi[2])
            };
            let mut gd = 0.0;
            let mut dd = 0.0;
            for k in 0..nn {
                let z = rigid(k);
                let dk = delta_of(k);
                gram += z.transpose() * z;
                b += z.transpose() * dk;
                dd += dk.norm_squared();
                for q in 0..6 {
                    gd += rows[6 * k + q] * dk[q];
                }
            }
            let coef = gram
                .cholesky()
                .map(|c| c.solve(&b))
                .unwrap_or_else(Vector6::zeros);
            let mut ww = 0.0;
            for k in 0..nn {
                let wk = delta_of(k) - rigid(k) * coef;
                ww += wk.norm_squared();
            }
            // Correction along w (skipped when the step is rigid to round-off: then
            // ΔV + D − g·Δ vanishes with it).
            let scale = if ww > 1e-28 * dd.max(f64::MIN_POSITIVE) {
                (v1 - v0 + dis - gd) / ww
            } else {
                0.0
            };
            for k in 0..nn {
                let wk = delta_of(k) - rigid(k) * coef;
                for q in 0..6 {
                    let mut r = rows[6 * k + q] + scale * wk[q];
                    if damped {
                        r += damp[6 * k + q];
                    }
                    out[6 * k + q] += r;
                }
            }
            g.rows_a = rows;
            g.rows_b = damp;
            g.strain0 = strain0;
            g.strain1 = strain1;
        });
    }

    /// The strain increments `ε(q₁) − ε(q₀)` of the step at the elastic points, 6 each
    /// (the decaying scheme's memory).
    pub(super) fn strain_increments(&self, step: &DiscreteStep, out: &mut [f64]) {
        with_work(self.nodes.len(), |g| {
            let mut strain0 = std::mem::take(&mut g.strain0);
            let mut strain1 = std::mem::take(&mut g.strain1);
            self.gather(step.start, g);
            self.strains(g, Some(&mut strain0));
            self.gather(step.end, g);
            self.strains(g, Some(&mut strain1));
            for p in 0..self.elastic.len() {
                let e = strain1[p] - strain0[p];
                out[6 * p..6 * p + 6].copy_from_slice(e.as_slice());
            }
            g.strain0 = strain0;
            g.strain1 = strain1;
        });
    }

    /// `½ Σ w eᵀ C e` of a memory of strain increments.
    pub(super) fn memory_energy(&self, memory: &[f64]) -> f64 {
        self.elastic
            .iter()
            .enumerate()
            .map(|(p, ep)| {
                let e = Vector6::from_column_slice(&memory[6 * p..6 * p + 6]);
                0.5 * ep.w * e.dot(&(self.table.stiffness_at(ep.eta) * e))
            })
            .sum()
    }
}
