//! The generic tangent check: every element's `K, C, M` and every constraint's `B`,
//! `∂(Bᵀμ)/∂(q, ν)`, rate terms (`Φ_t`, convective acceleration) and coordinate-element
//! tangents against central finite differences taken on the configuration manifold
//! (`x + ε e_k`, `R exp(ε ẽ_k)`, `ν + ε`).
//!
//! Central differences with step ε have truncation error O(ε²) and round-off error
//! O(u/ε) relative to the residual's magnitude (u = 2.2e-16); ε = 1e-6 balances them at
//! about 1e-10, so a relative mismatch above 1e-6 is a wrong tangent, not noise.

use crate::core::{
    Constraint, Coordinate, CoordinateTangents, Element, EvalContext, LocalTerms, Need, NodeState,
};
use nalgebra::{DMatrix, Vector3};

/// Finite-difference step.
pub const EPS: f64 = 1e-6;

/// What is perturbed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Slot {
    Configuration,
    Velocity,
    Acceleration,
}

fn perturb(nodes: &mut [NodeState], node: usize, dof: usize, h: f64, slot: Slot) {
    let n = &mut nodes[node];
    let mut e = Vector3::zeros();
    e[dof % 3] = h;
    match (slot, dof < 3) {
        (Slot::Configuration, true) => n.x += e,
        (Slot::Configuration, false) => n.rot = n.rot.compose_exp(&e),
        (Slot::Velocity, true) => n.v += e,
        (Slot::Velocity, false) => n.w += e,
        (Slot::Acceleration, true) => n.a += e,
        (Slot::Acceleration, false) => n.wd += e,
    }
}

/// Largest entry-wise mismatch between two matrices, relative to the larger of 1 and the
/// largest analytic entry.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mismatch {
    pub relative: f64,
    pub row: usize,
    pub col: usize,
}

fn compare(analytic: &DMatrix<f64>, fd: &DMatrix<f64>) -> Mismatch {
    let scale = analytic.iter().fold(1.0f64, |m, x| m.max(x.abs()));
    let mut worst = Mismatch {
        relative: 0.0,
        row: 0,
        col: 0,
    };
    for j in 0..analytic.ncols() {
        for i in 0..analytic.nrows() {
            let r = (analytic[(i, j)] - fd[(i, j)]).abs() / scale;
            if r > worst.relative || r.is_nan() {
                worst = Mismatch {
                    relative: r,
                    row: i,
                    col: j,
                };
            }
        }
    }
    worst
}

/// Mismatches of an element's K, C and M.
#[derive(Clone, Copy, Debug)]
pub struct ElementReport {
    pub k: Mismatch,
    pub c: Mismatch,
    pub m: Mismatch,
}

impl ElementReport {
    pub fn worst(&self) -> f64 {
        self.k.relative.max(self.c.relative).max(self.m.relative)
    }
}

/// Checks an element's tangents at the given node states.
pub fn check_element(e: &dyn Element, ctx: &EvalContext, nodes: &[NodeState]) -> ElementReport {
    let en = e.nodes().to_vec();
    let n = 6 * en.len();
    let mut t = LocalTerms::new(en.len());
    t.clear(Need::ResidualAndTangents);
    e.evaluate(ctx, nodes, Need::ResidualAndTangents, &mut t);
    let mut work = nodes.to_vec();
    let mut fd = |slot: Slot| -> DMatrix<f64> {
        let mut out = DMatrix::zeros(n, n);
        let mut tp = LocalTerms::new(en.len());
        for (b, &node) in en.iter().enumerate() {
            for dof in 0..6 {
                let mut r = [None, None];
                for (k, s) in [1.0, -1.0].iter().enumerate() {
                    work.clone_from_slice(nodes);
                    perturb(&mut work, node, dof, s * EPS, slot);
                    tp.clear(Need::Residual);
                    e.evaluate(ctx, &work, Need::Residual, &mut tp);
                    r[k] = Some(tp.r.clone());
                }
                let col = (r[0].take().unwrap_or_default() - r[1].take().unwrap_or_default())
                    / (2.0 * EPS);
                out.set_column(6 * b + dof, &col);
            }
        }
        out
    };
    let k = fd(Slot::Configuration);
    let c = fd(Slot::Velocity);
    let m = fd(Slot::Acceleration);
    ElementReport {
        k: compare(&t.k, &k),
        c: compare(&t.c, &c),
        m: compare(&t.m, &m),
    }
}

/// Mismatches of a constraint's B, ∂(Bᵀμ)/∂(q, ν), rate terms and coordinate elements.
#[derive(Clone, Copy, Debug)]
pub struct ConstraintReport {
    pub b: Mismatch,
    pub k: Mismatch,
    /// Relative error of Φ̈ − B(v̇, ν̈) against the second difference along the motion.
    pub convective: f64,
    /// Relative error of Φ_t against the first difference along the motion minus B·v.
    pub velocity: f64,
    /// ∂r/∂ν and ∂r/∂ν̇ of the coordinate elements.
    pub coordinate_stiffness: Mismatch,
    pub coordinate_damping: Mismatch,
}

impl ConstraintReport {
    pub fn worst(&self) -> f64 {
        self.b
            .relative
            .max(self.k.relative)
            .max(self.convective)
            .max(self.velocity)
            .max(self.coordinate_stiffness.relative)
            .max(self.coordinate_damping.relative)
    }
}

/// Checks a constraint at the given node states and joint coordinates with multipliers
/// `mu`; the rate terms are checked along the motion with the nodes' velocities, the
/// coordinates' rates and time.
pub fn check_constraint(
    c: &dyn Constraint,
    ctx: &EvalContext,
    nodes: &[NodeState],
    coords: &[Coordinate],
    mu: &[f64],
) -> ConstraintReport {
    let cn = c.nodes().to_vec();
    let m = c.n_equations();
    let nc = c.n_coordinates();
    let nq = 6 * cn.len();
    let n = nq + nc;
    let mut phi = vec![0.0; m];
    let mut b = DMatrix::zeros(m, n);
    c.evaluate(ctx, nodes, coords, &mut phi, Some(&mut b));
    let mut k = DMatrix::zeros(n, n);
    c.reaction_tangent(ctx, nodes, coords, mu, &mut k);

    let mut work = nodes.to_vec();
    let mut wc = coords.to_vec();
    let mut b_fd = DMatrix::zeros(m, n);
    let mut k_fd = DMatrix::zeros(n, n);
    let mut bp = DMatrix::zeros(m, n);
    let mut pp = vec![0.0; m];
    let mu_v = nalgebra::DVector::from_column_slice(mu);
    for col in 0..n {
        let mut vals = Vec::new();
        let mut forces = Vec::new();
        for s in [1.0, -1.0] {
            work.clone_from_slice(nodes);
            wc.clone_from_slice(coords);
            if col < nq {
                perturb(
                    &mut work,
                    cn[col / 6],
                    col % 6,
                    s * EPS,
                    Slot::Configuration,
                );
            } else {
                wc[col - nq].q += s * EPS;
            }
            c.evaluate(ctx, &work, &wc, &mut pp, Some(&mut bp));
            vals.push(nalgebra::DVector::from_column_slice(&pp));
            forces.push(bp.transpose() * &mu_v);
        }
        b_fd.set_column(col, &((&vals[0] - &vals[1]) / (2.0 * EPS)));
        k_fd.set_column(col, &((&forces[0] - &forces[1]) / (2.0 * EPS)));
    }

    // Differences of Φ along x(s) = x + s v, R(s) = R exp(s Ω̃), ν(s) = ν + s ν̇, t + s
    // (zero accelerations).
    let mut conv = vec![0.0; m];
    c.acceleration_term(ctx, nodes, coords, &mut conv);
    let mut phi_t = vec![0.0; m];
    c.velocity_term(ctx, &mut phi_t);
    let eps2 = 1e-4;
    let mut along = |s: f64| -> Vec<f64> {
        work.clone_from_slice(nodes);
        wc.clone_from_slice(coords);
        for &node in &cn {
            let nd = &mut work[node];
            nd.x += nd.v * s;
            nd.rot = nd.rot.compose_exp(&(nd.w * s));
        }
        for q in &mut wc {
            q.q += q.v * s;
        }
        let shifted = EvalContext {
            time: ctx.time + s,
            ..*ctx
        };
        let mut p = vec![0.0; m];
        c.evaluate(&shifted, &work, &wc, &mut p, None);
        p
    };
    let (pp1, pm1) = (along(eps2), along(-eps2));
    let mut vel = vec![0.0; n];
    for (a, &node) in cn.iter().enumerate() {
        for j in 0..3 {
            vel[6 * a + j] = nodes[node].v[j];
            vel[6 * a + 3 + j] = nodes[node].w[j];
        }
    }
    for (j, q) in coords.iter().enumerate() {
        vel[nq + j] = q.v;
    }
    let scale = conv.iter().fold(1.0f64, |a, x: &f64| a.max(x.abs()));
    let mut conv_err: f64 = 0.0;
    let mut vel_err: f64 = 0.0;
    for i in 0..m {
        let fd2 = (pp1[i] - 2.0 * phi[i] + pm1[i]) / (eps2 * eps2);
        conv_err = conv_err.max((fd2 - conv[i]).abs() / scale);
        let fd1 = (pp1[i] - pm1[i]) / (2.0 * eps2);
        let bv: f64 = (0..n).map(|j| b[(i, j)] * vel[j]).sum();
        let vscale = phi_t[i].abs().max(bv.abs()).max(1.0);
        vel_err = vel_err.max((fd1 - bv - phi_t[i]).abs() / vscale);
    }

    // Coordinate elements: ∂r/∂ν and ∂r/∂ν̇ (diagonal).
    let mut r0 = vec![0.0; nc];
    let mut kd = vec![0.0; nc];
    let mut cd = vec![0.0; nc];
    c.coordinate_forces(
        ctx,
        coords,
        &mut r0,
        Some(CoordinateTangents {
            stiffness: &mut kd,
            damping: &mut cd,
        }),
    );
    let mut kfd = DMatrix::zeros(nc.max(1), nc.max(1));
    let mut cfd = DMatrix::zeros(nc.max(1), nc.max(1));
    let (mut ka, mut ca) = (kfd.clone(), cfd.clone());
    for j in 0..nc {
        ka[(j, j)] = kd[j];
        ca[(j, j)] = cd[j];
        for (slot, out) in [(0, &mut kfd), (1, &mut cfd)] {
            let mut rr = [vec![0.0; nc], vec![0.0; nc]];
            for (side, s) in [1.0, -1.0].iter().enumerate() {
                wc.clone_from_slice(coords);
                if slot == 0 {
                    wc[j].q += s * EPS;
                } else {
                    wc[j].v += s * EPS;
                }
                c.coordinate_forces(ctx, &wc, &mut rr[side], None);
            }
            for i in 0..nc {
                out[(i, j)] = (rr[0][i] - rr[1][i]) / (2.0 * EPS);
            }
        }
    }
    ConstraintReport {
        b: compare(&b, &b_fd),
        k: compare(&k, &k_fd),
        convective: conv_err,
        velocity: vel_err,
        coordinate_stiffness: compare(&ka, &kfd),
        coordinate_damping: compare(&ca, &cfd),
    }
}
