//! One Legendre spectral beam element of order p (p + 1 nodes at the GLL points): residual,
//! tangents, energies and sectional output. Orchestration only; the physics is in
//! [`super::kernel`].
//!
//! Nodal rotations enter through the section-frame quaternions `s_k = q_k ⊗ o_k` (`o_k` the
//! constant node-to-section offset, identity for nodes the beam created), sign-aligned with
//! the element's middle node. The interpolated field `Q = Σ h_k s_k` gives exact virtual
//! rotations, so the generalized forces conjugate to δQ and δQ′ map back to each node's
//! material increment through `G(s_k)ᵀ` (`δs_k = G(s_k) δθ_k`), and the tangent is the exact
//! derivative of the residual (checked by `tangent_check`).

use super::kernel::{
    self, ElasticFields, ElasticOut, ElasticSection, InertialFields, InertialOut, PointLoads,
};
use super::quaternion::{Quat, conj, dg_w, dgt_f, from_rotation, g_mat, mul, rotation};
use super::section::{SectionTable, damping_matrix};
use crate::elements::{Element, EvalContext, LocalTerms, Need, add_block};
use crate::math::Rotation;
use crate::model::TimeFunction;
use crate::system::NodeState;
use nalgebra::{Matrix3, Matrix4x3, Matrix6, Vector3, Vector6};
use std::sync::Arc;

/// Largest supported element order.
pub const MAX_ORDER: usize = 31;

/// Quadrature of the elastic terms (inertia, gravity and loads always use p + 1 points).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Quadrature {
    /// p Gauss points: no shear locking, no spurious zero-energy modes (the default).
    #[default]
    Reduced,
    /// p + 1 Gauss points.
    Full,
}

/// A distributed load per unit length (force, moment), uniform times an optional profile.
#[derive(Clone, Debug, PartialEq)]
pub struct DistributedLoad {
    pub force: Vector3<f64>,
    pub moment: Vector3<f64>,
    /// Section-frame components that follow the section (true) or global (false).
    pub follower: bool,
    pub function: TimeFunction,
    /// Piecewise-linear factor over η ∈ [0, 1]; empty = 1.
    pub profile: Vec<[f64; 2]>,
}

impl DistributedLoad {
    fn factor(&self, eta: f64) -> f64 {
        let p = &self.profile;
        if p.is_empty() {
            return 1.0;
        }
        if eta <= p[0][0] {
            return p[0][1];
        }
        for w in p.windows(2) {
            if eta <= w[1][0] {
                let t = (eta - w[0][0]) / (w[1][0] - w[0][0]);
                return w[0][1] + t * (w[1][1] - w[0][1]);
            }
        }
        p[p.len() - 1][1]
    }
}

#[derive(Clone, Debug)]
struct ElasticPoint {
    /// Gauss weight × ds/dξ.
    w: f64,
    h: Vec<f64>,
    /// dh/ds.
    dh: Vec<f64>,
    c: Matrix6<f64>,
    d: Option<Matrix6<f64>>,
    eps0: Vector3<f64>,
    k0: Vector3<f64>,
    eta: f64,
}

#[derive(Clone, Debug)]
struct InertialPoint {
    w: f64,
    h: Vec<f64>,
    m6: Matrix6<f64>,
    eta: f64,
}

/// Sectional state at an elastic quadrature point (for output).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SectionState {
    /// Position of the reference line, global.
    pub position: Vector3<f64>,
    /// Section frame (columns: axial x, y, z in global components).
    pub frame: Matrix3<f64>,
    /// Normalized arc-length coordinate η along the beam.
    pub eta: f64,
    /// (ε, κ): axial, shear y, shear z strains; twist, bending curvatures about y, z.
    pub strain: Vector6<f64>,
    /// (N, M): axial and shear forces, torsion and bending moments, section frame.
    pub stress: Vector6<f64>,
}

/// Construction data of one element.
pub struct ElementSpec<'a> {
    pub name: String,
    pub nodes: Vec<usize>,
    /// Reference positions of the nodes.
    pub x0: &'a [Vector3<f64>],
    /// Reference section frames at the nodes.
    pub sections0: &'a [Rotation],
    /// Node orientations when the element is attached (the section frame's offset from
    /// them is kept constant).
    pub node_frames: &'a [Rotation],
    /// η at the element's first and last node.
    pub eta_range: (f64, f64),
    pub table: &'a SectionTable,
    pub damping: [f64; 6],
    pub quadrature: Quadrature,
    pub loads: Arc<Vec<DistributedLoad>>,
}

/// A beam finite element.
#[derive(Clone, Debug)]
pub struct BeamElement {
    name: String,
    nodes: Vec<usize>,
    offsets: Vec<Option<(Quat, Matrix3<f64>)>>,
    middle: usize,
    elastic: Vec<ElasticPoint>,
    inertial: Vec<InertialPoint>,
    loads: Arc<Vec<DistributedLoad>>,
}

/// Aligns `s` with `r` (s and −s are the same rotation).
#[inline]
fn aligned(s: Quat, r: &Quat) -> Quat {
    if s.dot(r) < 0.0 { -s } else { s }
}

impl BeamElement {
    pub fn new(spec: ElementSpec) -> Self {
        let nn = spec.nodes.len();
        assert!(
            (2..=MAX_ORDER + 1).contains(&nn),
            "element order out of range"
        );
        let p = nn - 1;
        let (xi_nodes, _) = super::gll::gauss_lobatto_legendre(p);
        let middle = p / 2;
        let offsets: Vec<Option<(Quat, Matrix3<f64>)>> = (0..nn)
            .map(|k| {
                let o = mul(
                    &conj(&from_rotation(&spec.node_frames[k])),
                    &from_rotation(&spec.sections0[k]),
                );
                let o = aligned(o, &Quat::new(1.0, 0.0, 0.0, 0.0));
                if (o - Quat::new(1.0, 0.0, 0.0, 0.0)).norm() < 1e-14 {
                    None
                } else {
                    Some((o, rotation(&o)))
                }
            })
            .collect();
        let s0r = from_rotation(&spec.sections0[middle]);
        let s0: Vec<Quat> = spec
            .sections0
            .iter()
            .map(|r| aligned(from_rotation(r), &s0r))
            .collect();
        let (e0, e1) = spec.eta_range;
        let mut h = vec![0.0; nn];
        let mut dh = vec![0.0; nn];
        let mut point = |xi: f64, wq: f64| {
            super::gll::lagrange(&xi_nodes, xi, &mut h, &mut dh);
            let dx: Vector3<f64> = (0..nn).map(|k| spec.x0[k] * dh[k]).sum();
            let jac = dx.norm();
            let dhs: Vec<f64> = dh.iter().map(|d| d / jac).collect();
            let q0: Quat = (0..nn).map(|k| s0[k] * h[k]).sum();
            let q0p: Quat = (0..nn).map(|k| s0[k] * dhs[k]).sum();
            let n0 = q0.norm_squared();
            let eps0 = rotation(&q0).transpose() * (dx / jac);
            let k0 = super::quaternion::e_mat(&q0) * q0p * (2.0 / n0);
            let eta = e0 + (xi + 1.0) * 0.5 * (e1 - e0);
            (wq * jac, h.clone(), dhs, eps0, k0, eta)
        };
        let n_el = match spec.quadrature {
            Quadrature::Reduced => p,
            Quadrature::Full => p + 1,
        };
        let damped = spec.damping.iter().any(|&m| m > 0.0);
        let (gx, gw) = super::gll::gauss_legendre(n_el);
        let elastic = gx
            .iter()
            .zip(&gw)
            .map(|(&xi, &wq)| {
                let (w, h, dh, eps0, k0, eta) = point(xi, wq);
                let c = spec.table.at(eta).stiffness;
                ElasticPoint {
                    w,
                    h,
                    dh,
                    d: damped.then(|| damping_matrix(&c, &spec.damping)),
                    c,
                    eps0,
                    k0,
                    eta,
                }
            })
            .collect();
        let (gx, gw) = super::gll::gauss_legendre(p + 1);
        let inertial = gx
            .iter()
            .zip(&gw)
            .map(|(&xi, &wq)| {
                let (w, h, _, _, _, eta) = point(xi, wq);
                InertialPoint {
                    w,
                    h,
                    m6: spec.table.at(eta).mass,
                    eta,
                }
            })
            .collect();
        Self {
            name: spec.name,
            nodes: spec.nodes,
            offsets,
            middle,
            elastic,
            inertial,
            loads: spec.loads,
        }
    }

    pub fn nodes_slice(&self) -> &[usize] {
        &self.nodes
    }

    pub fn order(&self) -> usize {
        self.nodes.len() - 1
    }

    /// Number of elastic quadrature points (sectional output points).
    pub fn n_section_points(&self) -> usize {
        self.elastic.len()
    }

    /// Translational mass lumped to the nodes by the inertial quadrature (Σ = m L).
    pub fn node_masses(&self) -> Vec<f64> {
        let mut out = vec![0.0; self.nodes.len()];
        for ip in &self.inertial {
            for (k, o) in out.iter_mut().enumerate() {
                *o += ip.w * ip.m6[(0, 0)] * ip.h[k];
            }
        }
        out
    }

    /// Nodal kinematics in section frames, sign-aligned.
    fn gather(&self, nodes: &[NodeState], g: &mut Gathered) {
        let nn = self.nodes.len();
        for k in 0..nn {
            let nd = &nodes[self.nodes[k]];
            let q = from_rotation(&nd.rot);
            let (s, w, wd) = match &self.offsets[k] {
                None => (q, nd.w, nd.wd),
                Some((o, om)) => (mul(&q, o), om.transpose() * nd.w, om.transpose() * nd.wd),
            };
            g.s[k] = s;
            g.w[k] = w;
            g.wd[k] = wd;
            g.x[k] = nd.x;
            g.v[k] = nd.v;
            g.a[k] = nd.a;
        }
        let r = g.s[self.middle];
        for k in 0..nn {
            g.s[k] = aligned(g.s[k], &r);
            let gm = g_mat(&g.s[k]);
            g.sd[k] = gm * g.w[k];
            g.sdd[k] = gm * g.wd[k] - g.s[k] * (0.25 * g.w[k].norm_squared());
        }
    }

    fn elastic_fields(&self, ep: &ElasticPoint, g: &Gathered) -> ElasticFields {
        let mut f = ElasticFields::default();
        for k in 0..self.nodes.len() {
            let (h, dh) = (ep.h[k], ep.dh[k]);
            f.xp += g.x[k] * dh;
            f.q += g.s[k] * h;
            f.qp += g.s[k] * dh;
            if ep.d.is_some() {
                f.xpd += g.v[k] * dh;
                f.qd += g.sd[k] * h;
                f.qpd += g.sd[k] * dh;
            }
        }
        f
    }

    fn inertial_fields(&self, ip: &InertialPoint, g: &Gathered) -> InertialFields {
        let mut f = InertialFields::default();
        for k in 0..self.nodes.len() {
            let h = ip.h[k];
            f.q += g.s[k] * h;
            f.v += g.v[k] * h;
            f.a += g.a[k] * h;
            f.qd += g.sd[k] * h;
            f.qdd += g.sdd[k] * h;
        }
        f
    }

    fn point_loads(&self, ctx: &EvalContext, eta: f64) -> PointLoads {
        let mut pl = PointLoads::default();
        for l in self.loads.iter() {
            let f = l.function.eval(ctx.time) * ctx.load_factor * l.factor(eta);
            if l.follower {
                pl.f_follower += l.force * f;
                pl.m_follower += l.moment * f;
            } else {
                pl.f_dead += l.force * f;
                pl.m_dead += l.moment * f;
            }
        }
        pl
    }

    /// Sectional states at the elastic quadrature points.
    pub fn sections(&self, nodes: &[NodeState], out: &mut Vec<SectionState>) {
        let mut g = Gathered::default();
        self.gather(nodes, &mut g);
        let mut eo = ElasticOut::default();
        for ep in &self.elastic {
            let f = self.elastic_fields(ep, &g);
            let sec = ElasticSection {
                c: &ep.c,
                d: ep.d.as_ref(),
                eps0: ep.eps0,
                k0: ep.k0,
            };
            kernel::elastic(&f, &sec, false, &mut eo);
            let position = (0..self.nodes.len()).map(|k| g.x[k] * ep.h[k]).sum();
            out.push(SectionState {
                position,
                frame: rotation(&f.q),
                eta: ep.eta,
                strain: eo.strain,
                stress: eo.stress,
            });
        }
    }
}

/// Per-evaluation nodal data on the stack (no allocation).
struct Gathered {
    s: [Quat; MAX_ORDER + 1],
    sd: [Quat; MAX_ORDER + 1],
    sdd: [Quat; MAX_ORDER + 1],
    w: [Vector3<f64>; MAX_ORDER + 1],
    wd: [Vector3<f64>; MAX_ORDER + 1],
    x: [Vector3<f64>; MAX_ORDER + 1],
    v: [Vector3<f64>; MAX_ORDER + 1],
    a: [Vector3<f64>; MAX_ORDER + 1],
}

impl Default for Gathered {
    fn default() -> Self {
        Self {
            s: [Quat::zeros(); MAX_ORDER + 1],
            sd: [Quat::zeros(); MAX_ORDER + 1],
            sdd: [Quat::zeros(); MAX_ORDER + 1],
            w: [Vector3::zeros(); MAX_ORDER + 1],
            wd: [Vector3::zeros(); MAX_ORDER + 1],
            x: [Vector3::zeros(); MAX_ORDER + 1],
            v: [Vector3::zeros(); MAX_ORDER + 1],
            a: [Vector3::zeros(); MAX_ORDER + 1],
        }
    }
}

/// Node matrices of the tangent.
struct NodeMats {
    g: [Matrix4x3<f64>; MAX_ORDER + 1],
    /// ∂ṡ/∂θ.
    gd: [Matrix4x3<f64>; MAX_ORDER + 1],
    /// ∂s̈/∂θ.
    gdd: [Matrix4x3<f64>; MAX_ORDER + 1],
    /// ∂s̈/∂Ω.
    sdd_w: [Matrix4x3<f64>; MAX_ORDER + 1],
}

impl Element for BeamElement {
    fn name(&self) -> &str {
        &self.name
    }

    fn nodes(&self) -> &[usize] {
        &self.nodes
    }

    fn evaluate(&self, ctx: &EvalContext, nodes: &[NodeState], need: Need, out: &mut LocalTerms) {
        let nn = self.nodes.len();
        let tangents = need == Need::ResidualAndTangents;
        let mut g = Gathered::default();
        self.gather(nodes, &mut g);
        let mut fq = [Quat::zeros(); MAX_ORDER + 1];
        let z43 = Matrix4x3::zeros();
        let mut nm = NodeMats {
            g: [z43; MAX_ORDER + 1],
            gd: [z43; MAX_ORDER + 1],
            gdd: [z43; MAX_ORDER + 1],
            sdd_w: [z43; MAX_ORDER + 1],
        };
        if tangents {
            for k in 0..nn {
                let s = &g.s[k];
                nm.g[k] = g_mat(s);
                nm.gd[k] = dg_w(s, &g.w[k]);
                nm.gdd[k] = dg_w(s, &g.wd[k]) - nm.g[k] * (0.25 * g.w[k].norm_squared());
                nm.sdd_w[k] = s * g.w[k].transpose() * (-0.5);
            }
        }
        // Elastic points.
        let mut eo = ElasticOut::default();
        for ep in &self.elastic {
            let f = self.elastic_fields(ep, &g);
            let sec = ElasticSection {
                c: &ep.c,
                d: ep.d.as_ref(),
                eps0: ep.eps0,
                k0: ep.k0,
            };
            kernel::elastic(&f, &sec, tangents, &mut eo);
            let w = ep.w;
            for j in 0..nn {
                out.add_r(6 * j, &(eo.f_xp * (w * ep.dh[j])));
                fq[j] += (eo.f_q * ep.h[j] + eo.f_qp * ep.dh[j]) * w;
            }
            if !tangents {
                continue;
            }
            use kernel::{E_Q, E_QD, E_QP, E_QPD, E_XP, E_XPD};
            let damped = ep.d.is_some();
            for k in 0..nn {
                let (hk, dk) = (ep.h[k], ep.dh[k]);
                let gk = nm.g[k];
                // Columns of node k: ∂(outputs)/∂x_k, ∂/∂θ_k (and rates for C).
                let col_th = |jm: &nalgebra::SMatrix<f64, 4, { kernel::NE }>| -> Matrix4x3<f64> {
                    let mut c = jm.fixed_view::<4, 4>(0, E_Q) * gk * hk
                        + jm.fixed_view::<4, 4>(0, E_QP) * gk * dk;
                    if damped {
                        c += jm.fixed_view::<4, 4>(0, E_QD) * nm.gd[k] * hk
                            + jm.fixed_view::<4, 4>(0, E_QPD) * nm.gd[k] * dk;
                    }
                    c
                };
                let col_w = |jm: &nalgebra::SMatrix<f64, 4, { kernel::NE }>| -> Matrix4x3<f64> {
                    jm.fixed_view::<4, 4>(0, E_QD) * gk * hk
                        + jm.fixed_view::<4, 4>(0, E_QPD) * gk * dk
                };
                let jx = &eo.d_xp;
                let mut xp_th = jx.fixed_view::<3, 4>(0, E_Q) * gk * hk
                    + jx.fixed_view::<3, 4>(0, E_QP) * gk * dk;
                if damped {
                    xp_th += jx.fixed_view::<3, 4>(0, E_QD) * nm.gd[k] * hk
                        + jx.fixed_view::<3, 4>(0, E_QPD) * nm.gd[k] * dk;
                }
                let xp_x: Matrix3<f64> = jx.fixed_view::<3, 3>(0, E_XP) * dk;
                let q_x = eo.d_q.fixed_view::<4, 3>(0, E_XP) * dk;
                let qp_x = eo.d_qp.fixed_view::<4, 3>(0, E_XP) * dk;
                let q_th = col_th(&eo.d_q);
                let qp_th = col_th(&eo.d_qp);
                for j in 0..nn {
                    let (hj, dj) = (ep.h[j], ep.dh[j]);
                    let gjt = nm.g[j].transpose();
                    add_block(&mut out.k, 6 * j, 6 * k, &(xp_x * (w * dj)));
                    add_block(&mut out.k, 6 * j, 6 * k + 3, &(xp_th * (w * dj)));
                    add_block(
                        &mut out.k,
                        6 * j + 3,
                        6 * k,
                        &(gjt * (q_x * hj + qp_x * dj) * w),
                    );
                    add_block(
                        &mut out.k,
                        6 * j + 3,
                        6 * k + 3,
                        &(gjt * (q_th * hj + qp_th * dj) * w),
                    );
                }
                if damped {
                    let xp_v: Matrix3<f64> = jx.fixed_view::<3, 3>(0, E_XPD) * dk;
                    let xp_w = jx.fixed_view::<3, 4>(0, E_QD) * gk * hk
                        + jx.fixed_view::<3, 4>(0, E_QPD) * gk * dk;
                    let q_v = eo.d_q.fixed_view::<4, 3>(0, E_XPD) * dk;
                    let qp_v = eo.d_qp.fixed_view::<4, 3>(0, E_XPD) * dk;
                    let q_w = col_w(&eo.d_q);
                    let qp_w = col_w(&eo.d_qp);
                    for j in 0..nn {
                        let (hj, dj) = (ep.h[j], ep.dh[j]);
                        let gjt = nm.g[j].transpose();
                        add_block(&mut out.c, 6 * j, 6 * k, &(xp_v * (w * dj)));
                        add_block(&mut out.c, 6 * j, 6 * k + 3, &(xp_w * (w * dj)));
                        add_block(
                            &mut out.c,
                            6 * j + 3,
                            6 * k,
                            &(gjt * (q_v * hj + qp_v * dj) * w),
                        );
                        add_block(
                            &mut out.c,
                            6 * j + 3,
                            6 * k + 3,
                            &(gjt * (q_w * hj + qp_w * dj) * w),
                        );
                    }
                }
            }
        }
        // Inertial points.
        let grav = ctx.gravity * ctx.load_factor;
        let mut io = InertialOut::default();
        for ip in &self.inertial {
            let f = self.inertial_fields(ip, &g);
            let pl = self.point_loads(ctx, ip.eta);
            kernel::inertial(&f, &ip.m6, &grav, &pl, tangents, &mut io);
            let w = ip.w;
            for j in 0..nn {
                out.add_r(6 * j, &(io.f_x * (w * ip.h[j])));
                fq[j] += io.f_q * (w * ip.h[j]);
            }
            if !tangents {
                continue;
            }
            use kernel::{I_A, I_Q, I_QD, I_QDD, I_V};
            for k in 0..nn {
                let hk = ip.h[k];
                let gk = nm.g[k];
                let th = |jm_q: nalgebra::SMatrix<f64, 3, 4>,
                          jm_qd: nalgebra::SMatrix<f64, 3, 4>,
                          jm_qdd: nalgebra::SMatrix<f64, 3, 4>| {
                    (jm_q * gk + jm_qd * nm.gd[k] + jm_qdd * nm.gdd[k]) * hk
                };
                let dx = &io.d_x;
                let x_th = th(
                    dx.fixed_view::<3, 4>(0, I_Q).into(),
                    dx.fixed_view::<3, 4>(0, I_QD).into(),
                    dx.fixed_view::<3, 4>(0, I_QDD).into(),
                );
                let dq = &io.d_q;
                let q_th = (dq.fixed_view::<4, 4>(0, I_Q) * gk
                    + dq.fixed_view::<4, 4>(0, I_QD) * nm.gd[k]
                    + dq.fixed_view::<4, 4>(0, I_QDD) * nm.gdd[k])
                    * hk;
                let x_v: Matrix3<f64> = dx.fixed_view::<3, 3>(0, I_V) * hk;
                let x_w = (dx.fixed_view::<3, 4>(0, I_QD) * gk
                    + dx.fixed_view::<3, 4>(0, I_QDD) * nm.sdd_w[k])
                    * hk;
                let q_v = dq.fixed_view::<4, 3>(0, I_V) * hk;
                let q_w = (dq.fixed_view::<4, 4>(0, I_QD) * gk
                    + dq.fixed_view::<4, 4>(0, I_QDD) * nm.sdd_w[k])
                    * hk;
                let x_a: Matrix3<f64> = dx.fixed_view::<3, 3>(0, I_A) * hk;
                let x_wd = dx.fixed_view::<3, 4>(0, I_QDD) * gk * hk;
                let q_a = dq.fixed_view::<4, 3>(0, I_A) * hk;
                let q_wd = dq.fixed_view::<4, 4>(0, I_QDD) * gk * hk;
                for j in 0..nn {
                    let hj = ip.h[j] * w;
                    let gjt = nm.g[j].transpose();
                    add_block(&mut out.k, 6 * j, 6 * k + 3, &(x_th * hj));
                    add_block(&mut out.k, 6 * j + 3, 6 * k + 3, &(gjt * q_th * hj));
                    add_block(&mut out.c, 6 * j, 6 * k, &(x_v * hj));
                    add_block(&mut out.c, 6 * j, 6 * k + 3, &(x_w * hj));
                    add_block(&mut out.c, 6 * j + 3, 6 * k, &(gjt * q_v * hj));
                    add_block(&mut out.c, 6 * j + 3, 6 * k + 3, &(gjt * q_w * hj));
                    add_block(&mut out.m, 6 * j, 6 * k, &(x_a * hj));
                    add_block(&mut out.m, 6 * j, 6 * k + 3, &(x_wd * hj));
                    add_block(&mut out.m, 6 * j + 3, 6 * k, &(gjt * q_a * hj));
                    add_block(&mut out.m, 6 * j + 3, 6 * k + 3, &(gjt * q_wd * hj));
                }
            }
        }
        // Rotational rows: r_θ = G(s_j)ᵀ f_j; and the derivative of G(s_j)ᵀ itself.
        for j in 0..nn {
            let gt = g_mat(&g.s[j]).transpose() * fq[j];
            out.add_r(6 * j + 3, &gt);
            if tangents {
                add_block(&mut out.k, 6 * j + 3, 6 * j + 3, &dgt_f(&g.s[j], &fq[j]));
            }
        }
        // Section-frame increments → node-frame increments for offset nodes.
        for (j, off) in self.offsets.iter().enumerate() {
            let Some((_, om)) = off else { continue };
            let rr: Vector3<f64> =
                om * Vector3::new(out.r[6 * j + 3], out.r[6 * j + 4], out.r[6 * j + 5]);
            for i in 0..3 {
                out.r[6 * j + 3 + i] = rr[i];
            }
            if tangents {
                for m in [&mut out.k, &mut out.c, &mut out.m] {
                    let n = m.nrows();
                    for col in 0..n {
                        let v = om
                            * Vector3::new(
                                m[(6 * j + 3, col)],
                                m[(6 * j + 4, col)],
                                m[(6 * j + 5, col)],
                            );
                        for i in 0..3 {
                            m[(6 * j + 3 + i, col)] = v[i];
                        }
                    }
                    for row in 0..n {
                        let v = om
                            * Vector3::new(
                                m[(row, 6 * j + 3)],
                                m[(row, 6 * j + 4)],
                                m[(row, 6 * j + 5)],
                            );
                        for i in 0..3 {
                            m[(row, 6 * j + 3 + i)] = v[i];
                        }
                    }
                }
            }
        }
    }

    fn kinetic_energy(&self, nodes: &[NodeState]) -> f64 {
        let mut g = Gathered::default();
        self.gather(nodes, &mut g);
        self.inertial
            .iter()
            .map(|ip| {
                let f = self.inertial_fields(ip, &g);
                ip.w * kernel::kinetic_density(&f.q, &f.qd, &f.v, &ip.m6)
            })
            .sum()
    }

    fn potential_energy(&self, ctx: &EvalContext, nodes: &[NodeState]) -> f64 {
        let mut g = Gathered::default();
        self.gather(nodes, &mut g);
        let mut eo = ElasticOut::default();
        let mut u = 0.0;
        for ep in &self.elastic {
            let f = self.elastic_fields(ep, &g);
            let sec = ElasticSection {
                c: &ep.c,
                d: None,
                eps0: ep.eps0,
                k0: ep.k0,
            };
            kernel::elastic(&f, &sec, false, &mut eo);
            u += 0.5 * ep.w * eo.strain.dot(&(ep.c * eo.strain));
        }
        let grav = ctx.gravity * ctx.load_factor;
        for ip in &self.inertial {
            let f = self.inertial_fields(ip, &g);
            let x: Vector3<f64> = (0..self.nodes.len()).map(|k| g.x[k] * ip.h[k]).sum();
            let m = ip.m6[(0, 0)];
            let m_eta = Vector3::new(ip.m6[(5, 1)], ip.m6[(3, 2)], ip.m6[(4, 0)]);
            u -= ip.w * grav.dot(&(x * m + rotation(&f.q) * m_eta));
        }
        u
    }

    fn external_power(&self, ctx: &EvalContext, nodes: &[NodeState]) -> f64 {
        if self.loads.is_empty() {
            return 0.0;
        }
        let mut g = Gathered::default();
        self.gather(nodes, &mut g);
        let mut p = 0.0;
        for ip in &self.inertial {
            let f = self.inertial_fields(ip, &g);
            let n = f.q.norm_squared();
            let r = rotation(&f.q);
            let omega = super::quaternion::e_mat(&f.q) * f.qd * (2.0 / n);
            let pl = self.point_loads(ctx, ip.eta);
            p += ip.w
                * ((pl.f_dead + r * pl.f_follower).dot(&f.v)
                    + (r.transpose() * pl.m_dead + pl.m_follower).dot(&omega));
        }
        p
    }

    fn dissipated_power(&self, nodes: &[NodeState]) -> f64 {
        if self.elastic.iter().all(|e| e.d.is_none()) {
            return 0.0;
        }
        let mut g = Gathered::default();
        self.gather(nodes, &mut g);
        let mut eo = ElasticOut::default();
        let mut p = 0.0;
        for ep in &self.elastic {
            let Some(d) = &ep.d else { continue };
            let f = self.elastic_fields(ep, &g);
            let sec = ElasticSection {
                c: &ep.c,
                d: Some(d),
                eps0: ep.eps0,
                k0: ep.k0,
            };
            kernel::elastic(&f, &sec, false, &mut eo);
            p += ep.w * eo.strain_rate.dot(&(d * eo.strain_rate));
        }
        p
    }
}

impl Element for Arc<BeamElement> {
    fn name(&self) -> &str {
        self.as_ref().name()
    }
    fn nodes(&self) -> &[usize] {
        self.as_ref().nodes()
    }
    fn evaluate(&self, ctx: &EvalContext, nodes: &[NodeState], need: Need, out: &mut LocalTerms) {
        self.as_ref().evaluate(ctx, nodes, need, out)
    }
    fn kinetic_energy(&self, nodes: &[NodeState]) -> f64 {
        self.as_ref().kinetic_energy(nodes)
    }
    fn potential_energy(&self, ctx: &EvalContext, nodes: &[NodeState]) -> f64 {
        self.as_ref().potential_energy(ctx, nodes)
    }
    fn external_power(&self, ctx: &EvalContext, nodes: &[NodeState]) -> f64 {
        self.as_ref().external_power(ctx, nodes)
    }
    fn dissipated_power(&self, nodes: &[NodeState]) -> f64 {
        self.as_ref().dissipated_power(nodes)
    }
}
