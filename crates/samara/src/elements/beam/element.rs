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
//!
//! Cost: per quadrature point the kernel's Jacobian blocks are mapped to each node's columns
//! once (`… G_k`), then to each node pair's rows (`G_jᵀ …`); per-evaluation nodal data live
//! in a thread-local workspace, so an evaluation allocates nothing.

use super::kernel::{
    self, ElasticFields, ElasticOut, ElasticSection, InertialFields, InertialOut, InertialSection,
    PointLoads,
};
use super::quaternion::{Quat, conj, dg_w, dgt_f, from_rotation, g_mat, mul, rotation};
use super::section::{SectionTable, damping_matrix_from_roots};
use crate::core::{ElementInput, NodeState};
use crate::elements::slot::Slot;
use crate::elements::{Element, EvalContext, LocalTerms, Need};
use crate::math::Rotation;
use crate::math::TimeFunction;
use crate::math::isa;
use nalgebra::{DMatrix, Matrix3, Matrix4x3, Matrix6, Vector3, Vector6};
use smallvec::SmallVec;
use std::cell::RefCell;
use std::sync::Arc;

mod discrete;

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

/// An elastic quadrature point. Its section (stiffness, damping) is not stored but
/// interpolated from the beam's table at η in the pass that needs it: a few dozen flops
/// against 0.6 kB per point read from memory in every evaluation.
#[derive(Clone, Copy, Debug)]
struct ElasticPoint {
    /// Gauss weight × ds/dξ.
    w: f64,
    eps0: Vector3<f64>,
    k0: Vector3<f64>,
    eta: f64,
    /// Where h (p + 1 values) and then dh/ds (p + 1) start in [`BeamElement::shape`].
    at: usize,
}

/// An inertial quadrature point (its sectional mass interpolated from the table at η,
/// as the elastic point's stiffness).
#[derive(Clone, Copy, Debug)]
struct InertialPoint {
    w: f64,
    eta: f64,
    /// Where h (p + 1 values) starts in [`BeamElement::shape`].
    at: usize,
}

/// Sectional state at an elastic quadrature point (for output).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SectionState {
    /// Position of the reference line, global.
    pub position: Vector3<f64>,
    /// Section frame (columns: axial x, y, z in global components).
    pub frame: Matrix3<f64>,
    /// The same frame as a unit quaternion (w, x, y, z), section frame → global.
    pub orientation: Quat,
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
    /// The beam's section table (shared by its elements).
    pub table: Arc<SectionTable>,
    pub damping: [f64; 6],
    pub quadrature: Quadrature,
    pub loads: Arc<Vec<DistributedLoad>>,
}

/// The inertia of one node lumped by Gauss–Lobatto quadrature of the kinetic energy (the
/// inertia of the energy-consistent integrators, [`discrete`]).
#[derive(Clone, Copy, Debug)]
struct LumpedNode {
    /// GLL weight × ds/dξ × mass per length.
    mass: f64,
    /// GLL weight × ds/dξ × sectional inertia, node-frame components.
    inertia: Matrix3<f64>,
    /// Whether the section's mass centre is off the reference line there.
    offset: bool,
}

/// A node's constant node-to-section offset `o_k` and its rotation matrix (`None`: the
/// identity, for the nodes the beam created).
type Offset = Option<Box<(Quat, Matrix3<f64>)>>;

/// A beam finite element.
///
/// Its point data are compact: per point the weight, η, the reference strains and the
/// shape functions (all points' in one array), 184 B for a two-node element against
/// ~1.7 kB with the section matrices stored per point; the sections come from the beam's
/// shared table.
///
/// What an evaluation reads is stored inline up to order 2 with the default (reduced)
/// quadrature (`SmallVec`; larger elements spill to the heap as before), in the element's
/// one allocation: as separate vectors the nodes, offsets, points and shape functions were
/// five more blocks on the heap, each a dependent cache miss per element and iteration once
/// the model outgrows the caches (docs/integrators.md, twenty-first round).
#[derive(Clone, Debug)]
pub struct BeamElement {
    name: String,
    nodes: SmallVec<[usize; 3]>,
    offsets: SmallVec<[Offset; 3]>,
    middle: usize,
    elastic: SmallVec<[ElasticPoint; 2]>,
    inertial: SmallVec<[InertialPoint; 3]>,
    /// Shape functions of the points: per elastic point h then dh/ds, per inertial point h.
    shape: SmallVec<[f64; 21]>,
    table: Arc<SectionTable>,
    /// `√μᵢ` of the stiffness-proportional damping (None: undamped).
    root_damping: Option<[f64; 6]>,
    loads: Arc<Vec<DistributedLoad>>,
    lumped: Vec<LumpedNode>,
    /// The dissipated power Σ w ε̇ᵀ D ε̇ at the last residual evaluation, damped elements
    /// only ([`Element::evaluated_dissipated_power`]); cleared as each analysis starts.
    last_dissipation: Slot,
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
        let offsets: SmallVec<[Offset; 3]> = (0..nn)
            .map(|k| {
                let o = mul(
                    &conj(&from_rotation(&spec.node_frames[k])),
                    &from_rotation(&spec.sections0[k]),
                );
                let o = aligned(o, &Quat::new(1.0, 0.0, 0.0, 0.0));
                if (o - Quat::new(1.0, 0.0, 0.0, 0.0)).norm() < 1e-14 {
                    None
                } else {
                    Some(Box::new((o, rotation(&o))))
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
        let mut shape: SmallVec<[f64; 21]> = SmallVec::new();
        let (gx, gw) = super::gll::gauss_legendre(n_el);
        let elastic = gx
            .iter()
            .zip(&gw)
            .map(|(&xi, &wq)| {
                let (w, h, dh, eps0, k0, eta) = point(xi, wq);
                let at = shape.len();
                shape.extend_from_slice(&h);
                shape.extend_from_slice(&dh);
                ElasticPoint {
                    w,
                    eps0,
                    k0,
                    eta,
                    at,
                }
            })
            .collect();
        let (gx, gw) = super::gll::gauss_legendre(p + 1);
        let inertial = gx
            .iter()
            .zip(&gw)
            .map(|(&xi, &wq)| {
                let (w, h, _, _, _, eta) = point(xi, wq);
                let at = shape.len();
                shape.extend_from_slice(&h);
                InertialPoint { w, eta, at }
            })
            .collect();
        shape.shrink_to_fit();
        // GLL lumping: at node k every Lagrange polynomial but h_k vanishes, so the
        // interpolated section there is the node's own; weight w_k |dx₀/dξ|.
        let (_, gll_w) = super::gll::gauss_lobatto_legendre(p);
        let lumped = (0..nn)
            .map(|k| {
                super::gll::lagrange(&xi_nodes, xi_nodes[k], &mut h, &mut dh);
                let jac = (0..nn)
                    .map(|j| spec.x0[j] * dh[j])
                    .sum::<Vector3<f64>>()
                    .norm();
                let eta = e0 + (xi_nodes[k] + 1.0) * 0.5 * (e1 - e0);
                let m6 = spec.table.at(eta).mass;
                let w = gll_w[k] * jac;
                let j_sec: Matrix3<f64> = m6.fixed_view::<3, 3>(3, 3).into_owned();
                let j_node = match offsets[k].as_deref() {
                    None => j_sec,
                    Some((_, om)) => om * j_sec * om.transpose(),
                };
                let m_eta = Vector3::new(m6[(5, 1)], m6[(3, 2)], m6[(4, 0)]);
                LumpedNode {
                    mass: w * m6[(0, 0)],
                    inertia: j_node * w,
                    offset: m_eta.norm() > 1e-12 * m6[(0, 0)].abs().max(f64::MIN_POSITIVE),
                }
            })
            .collect();
        Self {
            name: spec.name,
            nodes: SmallVec::from_vec(spec.nodes),
            offsets,
            middle,
            elastic,
            inertial,
            shape,
            root_damping: damped.then(|| spec.damping.map(f64::sqrt)),
            table: spec.table,
            loads: spec.loads,
            lumped,
            last_dissipation: Slot::new(),
        }
    }

    /// Shape functions h and dh/ds at an elastic point.
    #[inline]
    fn shape_of(&self, ep: &ElasticPoint) -> (&[f64], &[f64]) {
        let nn = self.nodes.len();
        let s = &self.shape[ep.at..ep.at + 2 * nn];
        s.split_at(nn)
    }

    /// Shape functions h at an inertial point.
    #[inline]
    fn inertial_shape(&self, ip: &InertialPoint) -> &[f64] {
        &self.shape[ip.at..ip.at + self.nodes.len()]
    }

    /// Sectional stiffness C and (if the beam is damped) damping D = Λ C Λ at an elastic
    /// point.
    #[inline]
    fn section_matrices(&self, ep: &ElasticPoint) -> (Matrix6<f64>, Option<Matrix6<f64>>) {
        let c = self.table.stiffness_at(ep.eta);
        let d = self
            .root_damping
            .as_ref()
            .map(|r| damping_matrix_from_roots(&c, r));
        (c, d)
    }

    /// Sectional mass matrix at an inertial point.
    #[inline]
    fn mass_of(&self, ip: &InertialPoint) -> Matrix6<f64> {
        self.table.mass_at(ip.eta)
    }

    pub fn nodes_slice(&self) -> &[usize] {
        &self.nodes
    }

    /// The constant node-to-section offset `o_k` of local node `k` as a unit quaternion
    /// (w, x, y, z): the section frame at the node is `q_k ⊗ o_k` (identity for nodes the
    /// beam created).
    pub fn section_offset(&self, k: usize) -> [f64; 4] {
        match self.offsets[k].as_deref() {
            None => [1.0, 0.0, 0.0, 0.0],
            Some((o, _)) => [o[0], o[1], o[2], o[3]],
        }
    }

    pub fn order(&self) -> usize {
        self.nodes.len() - 1
    }

    /// Number of elastic quadrature points (sectional output points).
    pub fn n_section_points(&self) -> usize {
        self.elastic.len()
    }

    /// Normalized arc length η of the elastic quadrature points.
    pub fn section_etas(&self) -> impl Iterator<Item = f64> + '_ {
        self.elastic.iter().map(|e| e.eta)
    }

    /// Translational mass lumped to the nodes by the inertial quadrature (Σ = m L).
    pub fn node_masses(&self) -> Vec<f64> {
        let mut out = vec![0.0; self.nodes.len()];
        for ip in &self.inertial {
            let (m, h) = (self.mass_of(ip)[(0, 0)], self.inertial_shape(ip));
            for (k, o) in out.iter_mut().enumerate() {
                *o += ip.w * m * h[k];
            }
        }
        out
    }

    /// Nodal kinematics in section frames, sign-aligned with the middle node.
    fn gather(&self, nodes: &[NodeState], g: &mut Work) {
        self.gather_positions(nodes, g);
        let nn = self.nodes.len();
        for k in 0..nn {
            let nd = &nodes[self.nodes[k]];
            let (w, wd) = match self.offsets[k].as_deref() {
                None => (nd.w, nd.wd),
                Some((_, om)) => (om.transpose() * nd.w, om.transpose() * nd.wd),
            };
            g.w[k] = w;
            g.wd[k] = wd;
            g.v[k] = nd.v;
            g.a[k] = nd.a;
            let gm = g_mat(&g.s[k]);
            g.sd[k] = gm * g.w[k];
            g.sdd[k] = gm * g.wd[k] - g.s[k] * (0.25 * g.w[k].norm_squared());
        }
    }

    /// The positions and the (aligned) orientation quaternions of [`Self::gather`] only.
    fn gather_positions(&self, nodes: &[NodeState], g: &mut Work) {
        let nn = self.nodes.len();
        for k in 0..nn {
            let nd = &nodes[self.nodes[k]];
            let q = from_rotation(&nd.rot);
            g.s[k] = match self.offsets[k].as_deref() {
                None => q,
                Some((o, _)) => mul(&q, o),
            };
            g.x[k] = nd.x;
        }
        let r = g.s[self.middle];
        for k in 0..nn {
            g.s[k] = aligned(g.s[k], &r);
        }
    }

    fn elastic_fields(&self, ep: &ElasticPoint, g: &Work) -> ElasticFields {
        let mut f = self.elastic_positions(ep, g);
        if self.root_damping.is_some() {
            let (hs, dhs) = self.shape_of(ep);
            for k in 0..self.nodes.len() {
                let (h, dh) = (hs[k], dhs[k]);
                f.xpd += g.v[k] * dh;
                f.qd += g.sd[k] * h;
                f.qpd += g.sd[k] * dh;
            }
        }
        f
    }

    /// x′, Q and Q′ of [`Self::elastic_fields`] (the rates zero).
    fn elastic_positions(&self, ep: &ElasticPoint, g: &Work) -> ElasticFields {
        let mut f = ElasticFields::default();
        let (hs, dhs) = self.shape_of(ep);
        for k in 0..self.nodes.len() {
            let (h, dh) = (hs[k], dhs[k]);
            f.xp += g.x[k] * dh;
            f.q += g.s[k] * h;
            f.qp += g.s[k] * dh;
        }
        f
    }

    fn inertial_fields(&self, ip: &InertialPoint, g: &Work) -> InertialFields {
        let mut f = InertialFields::default();
        let hs = self.inertial_shape(ip);
        for k in 0..self.nodes.len() {
            let h = hs[k];
            f.q += g.s[k] * h;
            f.a += g.a[k] * h;
            f.qd += g.sd[k] * h;
            f.qdd += g.sdd[k] * h;
        }
        f
    }

    /// Time factors of the distributed loads (function × load factor), into `g.load_factors`.
    fn load_factors(&self, ctx: &EvalContext, g: &mut Work) {
        g.load_factors.clear();
        g.load_factors.extend(
            self.loads
                .iter()
                .map(|l| l.function.eval(ctx.time) * ctx.load_factor),
        );
    }

    fn point_loads(&self, factors: &[f64], eta: f64) -> PointLoads {
        let mut pl = PointLoads::default();
        for (l, f) in self.loads.iter().zip(factors) {
            let f = f * l.factor(eta);
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
        with_work(self.nodes.len(), |g| {
            self.gather(nodes, g);
            let mut eo = ElasticOut::default();
            for ep in &self.elastic {
                out.push(self.section_state(ep, g, &mut eo));
            }
        })
    }

    /// Sectional states at the elastic quadrature points, written into `out` (one per
    /// point, `out.len() == n_section_points()`): allocation-free.
    pub fn sections_into(&self, nodes: &[NodeState], out: &mut [SectionState]) {
        with_work(self.nodes.len(), |g| {
            self.gather(nodes, g);
            let mut eo = ElasticOut::default();
            for (ep, o) in self.elastic.iter().zip(out.iter_mut()) {
                *o = self.section_state(ep, g, &mut eo);
            }
        })
    }

    fn section_state(&self, ep: &ElasticPoint, g: &Work, eo: &mut ElasticOut) -> SectionState {
        let f = self.elastic_fields(ep, g);
        let (c, d) = self.section_matrices(ep);
        let sec = ElasticSection {
            c: &c,
            d: d.as_ref(),
            eps0: ep.eps0,
            k0: ep.k0,
        };
        kernel::elastic(&f, &sec, false, eo);
        let h = self.shape_of(ep).0;
        let position = (0..self.nodes.len()).map(|k| g.x[k] * h[k]).sum();
        SectionState {
            position,
            frame: rotation(&f.q),
            orientation: f.q / f.q.norm(),
            eta: ep.eta,
            strain: eo.strain,
            stress: eo.stress,
        }
    }

    isa::copies! {
        /// [`Self::evaluate_gathered`], on CPUs with AVX in a copy compiled for AVX: its
        /// loops over the nodes and quadrature points run four lanes wide (the section
        /// kernels it calls are not affected). The same operations in the same order (no
        /// fused multiply–add), so the same results to the bit, as the stations' and the
        /// block LU's AVX copies.
        fn evaluate_gathered_in_copy(
            &self: BeamElement,
            ctx: &EvalContext,
            need: Need,
            g: &mut Work,
            out: &mut LocalTerms,
        ) {
            Base | Avx => evaluate_gathered,
        }
    }

    /// The body of [`Element::evaluate`] with the nodal data gathered into `g`.
    #[inline(always)]
    fn evaluate_gathered(&self, ctx: &EvalContext, need: Need, g: &mut Work, out: &mut LocalTerms) {
        let nn = self.nodes.len();
        let tangents = need == Need::ResidualAndTangents;
        if tangents {
            for k in 0..nn {
                let s = &g.s[k];
                g.g[k] = g_mat(s);
                g.gd[k] = dg_w(s, &g.w[k]);
                g.gdd[k] = dg_w(s, &g.wd[k]) - g.g[k] * (0.25 * g.w[k].norm_squared());
                g.sdd_w[k] = s * g.w[k].transpose() * (-0.5);
            }
        }
        g.fq[..nn].fill(Quat::zeros());
        let ld = 6 * nn;
        // Elastic points.
        let eo = &mut g.eo;
        let mut dissipated = 0.0;
        for ep in &self.elastic {
            let (hs, dhs) = self.shape_of(ep);
            let f = {
                let mut f = ElasticFields::default();
                for k in 0..nn {
                    let (h, dh) = (hs[k], dhs[k]);
                    f.xp += g.x[k] * dh;
                    f.q += g.s[k] * h;
                    f.qp += g.s[k] * dh;
                    if self.root_damping.is_some() {
                        f.xpd += g.v[k] * dh;
                        f.qd += g.sd[k] * h;
                        f.qpd += g.sd[k] * dh;
                    }
                }
                f
            };
            // The table's C by reference (no 288-byte copy per point on a uniform beam).
            let c = self.table.stiffness_in(ep.eta, &mut g.c_buf);
            let d = self
                .root_damping
                .as_ref()
                .map(|r| damping_matrix_from_roots(c, r));
            let sec = ElasticSection {
                c,
                d: d.as_ref(),
                eps0: ep.eps0,
                k0: ep.k0,
            };
            kernel::elastic(&f, &sec, tangents, eo);
            let w = ep.w;
            dissipated += w * eo.dissipation;
            for j in 0..nn {
                out.add_r(6 * j, &(eo.f_xp * (w * dhs[j])));
                g.fq[j] += (eo.f_q * hs[j] + eo.f_qp * dhs[j]) * w;
            }
            if !tangents {
                continue;
            }
            let damped = d.is_some();
            let (jx, jq, jp) = (&eo.d_xp, &eo.d_q, &eo.d_qp);
            // Columns of node k (θ_k; with damping also Ω_k).
            for k in 0..nn {
                let (hk, dk) = (hs[k], dhs[k]);
                let gk = &g.g[k];
                let (ax, aq, ap) = (
                    jx.q * hk + jx.qp * dk,
                    jq.q * hk + jq.qp * dk,
                    jp.q * hk + jp.qp * dk,
                );
                g.c3a[k] = ax * gk;
                g.c43a[k] = aq * gk;
                g.c43b[k] = ap * gk;
                if damped {
                    let gdk = &g.gd[k];
                    let (bx, bq, bp) = (
                        jx.qd * hk + jx.qpd * dk,
                        jq.qd * hk + jq.qpd * dk,
                        jp.qd * hk + jp.qpd * dk,
                    );
                    g.c3a[k] += bx * gdk;
                    g.c43a[k] += bq * gdk;
                    g.c43b[k] += bp * gdk;
                    g.c3b[k] = bx * gk;
                    g.c43c[k] = bq * gk;
                    g.c43d[k] = bp * gk;
                }
            }
            // Rows of node j.
            let (km, cm) = (out.k.as_mut_slice(), out.c.as_mut_slice());
            for j in 0..nn {
                let (hj, dj) = (hs[j], dhs[j]);
                let gjt = g.g[j].transpose();
                let (wj, wdj) = (w * hj, w * dj);
                let gx = gjt * (jq.xp * wj + jp.xp * wdj);
                let gxd = if damped {
                    gjt * (jq.xpd * wj + jp.xpd * wdj)
                } else {
                    Matrix3::zeros()
                };
                for k in 0..nn {
                    let dk = dhs[k];
                    let (r, c) = (6 * j, 6 * k);
                    add3(km, ld, r, c, &jx.xp, wdj * dk);
                    add3(km, ld, r, c + 3, &g.c3a[k], wdj);
                    add3(km, ld, r + 3, c, &gx, dk);
                    let b = gjt * (g.c43a[k] * wj + g.c43b[k] * wdj);
                    add3(km, ld, r + 3, c + 3, &b, 1.0);
                    if damped {
                        add3(cm, ld, r, c, &jx.xpd, wdj * dk);
                        add3(cm, ld, r, c + 3, &g.c3b[k], wdj);
                        add3(cm, ld, r + 3, c, &gxd, dk);
                        let b = gjt * (g.c43c[k] * wj + g.c43d[k] * wdj);
                        add3(cm, ld, r + 3, c + 3, &b, 1.0);
                    }
                }
            }
        }
        if self.root_damping.is_some() {
            self.last_dissipation.set(dissipated);
        }
        // Inertial points.
        let grav = ctx.gravity * ctx.load_factor;
        if !self.loads.is_empty() {
            self.load_factors(ctx, g);
        }
        let io = &mut g.io;
        for ip in &self.inertial {
            let hs = self.inertial_shape(ip);
            let mass = InertialSection::new(self.table.mass_in(ip.eta, &mut g.m_buf));
            let f = {
                let mut f = InertialFields::default();
                for k in 0..nn {
                    let h = hs[k];
                    f.q += g.s[k] * h;
                    f.a += g.a[k] * h;
                    f.qd += g.sd[k] * h;
                    f.qdd += g.sdd[k] * h;
                }
                f
            };
            let pl = if self.loads.is_empty() {
                PointLoads::default()
            } else {
                self.point_loads(&g.load_factors, ip.eta)
            };
            kernel::inertial(&f, &mass, &grav, &pl, tangents, io);
            let w = ip.w;
            for j in 0..nn {
                out.add_r(6 * j, &(io.f_x * (w * hs[j])));
                g.fq[j] += io.f_q * (w * hs[j]);
            }
            if !tangents {
                continue;
            }
            let (m, x_rot, offset) = (mass.m, io.x_rot, mass.offset);
            for k in 0..nn {
                let hk = hs[k];
                let (gk, gdk, gddk, swk) = (&g.g[k], &g.gd[k], &g.gdd[k], &g.sdd_w[k]);
                g.c43a[k] = (io.q_q * gk + io.q_qd * gdk + io.q_qdd * gddk) * hk;
                g.c43b[k] = (io.q_qd * gk + io.q_qdd * swk) * hk;
                g.c43c[k] = io.q_qdd * gk * hk;
                if x_rot {
                    g.c3a[k] = (io.x_q * gk + io.x_qd * gdk + io.x_qdd * gddk) * hk;
                    g.c3b[k] = (io.x_qd * gk + io.x_qdd * swk) * hk;
                    g.c3c[k] = io.x_qdd * gk * hk;
                }
            }
            let (km, cm, mm) = (
                out.k.as_mut_slice(),
                out.c.as_mut_slice(),
                out.m.as_mut_slice(),
            );
            for j in 0..nn {
                let wj = w * hs[j];
                let gjt = g.g[j].transpose() * wj;
                let gqa = if offset {
                    gjt * io.q_a
                } else {
                    Matrix3::zeros()
                };
                for k in 0..nn {
                    let hk = hs[k];
                    let (r, c) = (6 * j, 6 * k);
                    add3(km, ld, r + 3, c + 3, &(gjt * g.c43a[k]), 1.0);
                    add3(cm, ld, r + 3, c + 3, &(gjt * g.c43b[k]), 1.0);
                    add3(mm, ld, r + 3, c + 3, &(gjt * g.c43c[k]), 1.0);
                    for i in 0..3 {
                        mm[(c + i) * ld + r + i] += wj * hk * m;
                    }
                    if offset {
                        add3(mm, ld, r + 3, c, &gqa, hk);
                    }
                    if x_rot {
                        add3(km, ld, r, c + 3, &g.c3a[k], wj);
                        add3(cm, ld, r, c + 3, &g.c3b[k], wj);
                        add3(mm, ld, r, c + 3, &g.c3c[k], wj);
                    }
                }
            }
        }
        // Rotational rows: r_θ = G(s_j)ᵀ f_j; and the derivative of G(s_j)ᵀ itself.
        for j in 0..nn {
            let gt = g_mat(&g.s[j]).transpose() * g.fq[j];
            out.add_r(6 * j + 3, &gt);
            if tangents {
                let d = dgt_f(&g.s[j], &g.fq[j]);
                add3(out.k.as_mut_slice(), ld, 6 * j + 3, 6 * j + 3, &d, 1.0);
            }
        }
        // Section-frame increments → node-frame increments for offset nodes.
        for (j, off) in self.offsets.iter().enumerate() {
            let Some((_, om)) = off.as_deref() else {
                continue;
            };
            let rr: Vector3<f64> =
                om * Vector3::new(out.r[6 * j + 3], out.r[6 * j + 4], out.r[6 * j + 5]);
            for i in 0..3 {
                out.r[6 * j + 3 + i] = rr[i];
            }
            if tangents {
                for m in [&mut out.k, &mut out.c, &mut out.m] {
                    rotate_rows_and_columns(m, 6 * j + 3, om);
                }
            }
        }
    }
}

/// `m ← diag(…, O, …) m diag(…, Oᵀ, …)ᵀ` on the three rows and columns from `at`:
/// rows ← O·rows, columns ← columns·Oᵀ.
fn rotate_rows_and_columns(m: &mut DMatrix<f64>, at: usize, om: &Matrix3<f64>) {
    let n = m.nrows();
    for col in 0..n {
        let v = om * Vector3::new(m[(at, col)], m[(at + 1, col)], m[(at + 2, col)]);
        for i in 0..3 {
            m[(at + i, col)] = v[i];
        }
    }
    for row in 0..n {
        let v = om * Vector3::new(m[(row, at)], m[(row, at + 1)], m[(row, at + 2)]);
        for i in 0..3 {
            m[(row, at + i)] = v[i];
        }
    }
}

/// `dst[row.., col..] += s · b` for a column-major matrix with leading dimension `ld`.
#[inline(always)]
fn add3(dst: &mut [f64], ld: usize, row: usize, col: usize, b: &Matrix3<f64>, s: f64) {
    let b = b.as_slice();
    for j in 0..3 {
        let o = (col + j) * ld + row;
        let d = &mut dst[o..o + 3];
        d[0] += s * b[3 * j];
        d[1] += s * b[3 * j + 1];
        d[2] += s * b[3 * j + 2];
    }
}

/// Per-evaluation nodal data and per-point temporaries, kept per thread and grown to the
/// largest element seen: evaluations allocate nothing.
#[derive(Default)]
struct Work {
    s: Vec<Quat>,
    sd: Vec<Quat>,
    sdd: Vec<Quat>,
    w: Vec<Vector3<f64>>,
    wd: Vec<Vector3<f64>>,
    x: Vec<Vector3<f64>>,
    v: Vec<Vector3<f64>>,
    a: Vec<Vector3<f64>>,
    /// G(s_k) = ∂s_k/∂θ_k, ∂ṡ_k/∂θ_k, ∂s̈_k/∂θ_k, ∂s̈_k/∂Ω_k.
    g: Vec<Matrix4x3<f64>>,
    gd: Vec<Matrix4x3<f64>>,
    gdd: Vec<Matrix4x3<f64>>,
    sdd_w: Vec<Matrix4x3<f64>>,
    /// Generalized forces conjugate to δs_j.
    fq: Vec<Quat>,
    /// Per-node column blocks of one quadrature point.
    c3a: Vec<Matrix3<f64>>,
    c3b: Vec<Matrix3<f64>>,
    c3c: Vec<Matrix3<f64>>,
    c43a: Vec<Matrix4x3<f64>>,
    c43b: Vec<Matrix4x3<f64>>,
    c43c: Vec<Matrix4x3<f64>>,
    c43d: Vec<Matrix4x3<f64>>,
    load_factors: Vec<f64>,
    eo: ElasticOut,
    io: InertialOut,
    /// Discrete form ([`discrete`]): strains at the start of the step, nodal rows.
    strain0: Vec<Vector6<f64>>,
    strain1: Vec<Vector6<f64>>,
    rows_a: Vec<f64>,
    rows_b: Vec<f64>,
    /// The section stiffness and mass interpolated at a point (tables with stations).
    c_buf: Matrix6<f64>,
    m_buf: Matrix6<f64>,
}

impl Work {
    fn reserve(&mut self, nn: usize) {
        if self.s.len() >= nn {
            return;
        }
        let (q, v, m3, m43) = (
            Quat::zeros(),
            Vector3::zeros(),
            Matrix3::zeros(),
            Matrix4x3::zeros(),
        );
        for x in [&mut self.s, &mut self.sd, &mut self.sdd, &mut self.fq] {
            x.resize(nn, q);
        }
        for x in [&mut self.rows_a, &mut self.rows_b] {
            x.resize(6 * nn, 0.0);
        }
        // One strain per elastic point: at most p + 1 = nn.
        self.strain0.resize(nn, Vector6::zeros());
        self.strain1.resize(nn, Vector6::zeros());
        for x in [
            &mut self.w,
            &mut self.wd,
            &mut self.x,
            &mut self.v,
            &mut self.a,
        ] {
            x.resize(nn, v);
        }
        for x in [&mut self.c3a, &mut self.c3b, &mut self.c3c] {
            x.resize(nn, m3);
        }
        for x in [
            &mut self.g,
            &mut self.gd,
            &mut self.gdd,
            &mut self.sdd_w,
            &mut self.c43a,
            &mut self.c43b,
            &mut self.c43c,
            &mut self.c43d,
        ] {
            x.resize(nn, m43);
        }
    }
}

thread_local! {
    static WORK: RefCell<Work> = RefCell::new(Work::default());
}

/// Runs `f` with this thread's workspace, sized for `nn` nodes.
fn with_work<R>(nn: usize, f: impl FnOnce(&mut Work) -> R) -> R {
    WORK.with(|cell| {
        let mut w = cell.borrow_mut();
        w.reserve(nn);
        f(&mut w)
    })
}

impl Element for BeamElement {
    fn breakpoints(&self, out: &mut Vec<f64>) {
        for l in self.loads.iter() {
            out.extend(l.function.breakpoints());
        }
    }

    fn discrete_form(&self) -> Result<(), String> {
        self.check_discrete_form()
    }

    fn discrete_residual(&self, step: &crate::core::DiscreteStep, out: &mut [f64]) {
        self.discrete_rows(step, out)
    }

    fn discrete_memory_len(&self) -> usize {
        6 * self.elastic.len()
    }

    fn discrete_memory(&self, step: &crate::core::DiscreteStep, out: &mut [f64]) {
        self.strain_increments(step, out)
    }

    fn discrete_memory_energy(&self, memory: &[f64]) -> f64 {
        self.memory_energy(memory)
    }

    fn discrete_kinetic_energy(&self, x: &ElementInput) -> f64 {
        self.lumped_kinetic_energy(x.nodes)
    }

    fn discrete_potential_energy(&self, ctx: &EvalContext, x: &ElementInput) -> f64 {
        self.lumped_potential_energy(ctx, x.nodes)
    }

    fn name(&self) -> &str {
        &self.name
    }

    fn nodes(&self) -> &[usize] {
        &self.nodes
    }

    fn evaluate(&self, ctx: &EvalContext, x: &ElementInput, need: Need, out: &mut LocalTerms) {
        let nodes = x.nodes;
        with_work(self.nodes.len(), |g| {
            self.gather(nodes, g);
            self.evaluate_gathered_in_copy(ctx, need, g, out);
        })
    }

    fn kinetic_energy(&self, x: &ElementInput) -> f64 {
        let nodes = x.nodes;
        with_work(self.nodes.len(), |g| {
            self.gather(nodes, g);
            self.inertial
                .iter()
                .map(|ip| {
                    let f = self.inertial_fields(ip, g);
                    let h = self.inertial_shape(ip);
                    let v: Vector3<f64> = (0..self.nodes.len()).map(|k| g.v[k] * h[k]).sum();
                    ip.w * kernel::kinetic_density(&f.q, &f.qd, &v, &self.mass_of(ip))
                })
                .sum()
        })
    }

    fn potential_energy(&self, ctx: &EvalContext, x: &ElementInput) -> f64 {
        let nodes = x.nodes;
        // Positions and orientations only: the same operations on them as the residual's.
        with_work(self.nodes.len(), |g| {
            self.gather_positions(nodes, g);
            let mut u = 0.0;
            for ep in &self.elastic {
                let f = self.elastic_positions(ep, g);
                let c = self.table.stiffness_at(ep.eta);
                let e = kernel::strain(&f, &ep.eps0, &ep.k0);
                u += 0.5 * ep.w * e.dot(&(c * e));
            }
            let grav = ctx.gravity * ctx.load_factor;
            for ip in &self.inertial {
                let h = self.inertial_shape(ip);
                let mut q = Quat::zeros();
                for (s, hk) in g.s.iter().zip(h).take(self.nodes.len()) {
                    q += s * *hk;
                }
                let x: Vector3<f64> = (0..self.nodes.len()).map(|k| g.x[k] * h[k]).sum();
                let m6 = self.mass_of(ip);
                let m = m6[(0, 0)];
                let m_eta = Vector3::new(m6[(5, 1)], m6[(3, 2)], m6[(4, 0)]);
                u -= ip.w * grav.dot(&(x * m + rotation(&q) * m_eta));
            }
            u
        })
    }

    fn external_power(&self, ctx: &EvalContext, x: &ElementInput) -> f64 {
        let nodes = x.nodes;
        if self.loads.is_empty() {
            return 0.0;
        }
        with_work(self.nodes.len(), |g| {
            self.gather(nodes, g);
            self.load_factors(ctx, g);
            let mut p = 0.0;
            for ip in &self.inertial {
                let f = self.inertial_fields(ip, g);
                let h = self.inertial_shape(ip);
                let v: Vector3<f64> = (0..self.nodes.len()).map(|k| g.v[k] * h[k]).sum();
                let n = f.q.norm_squared();
                let r = rotation(&f.q);
                let omega = super::quaternion::e_mat(&f.q) * f.qd * (2.0 / n);
                let pl = self.point_loads(&g.load_factors, ip.eta);
                p += ip.w
                    * ((pl.f_dead + r * pl.f_follower).dot(&v)
                        + (r.transpose() * pl.m_dead + pl.m_follower).dot(&omega));
            }
            p
        })
    }

    fn dissipated_power(&self, x: &ElementInput) -> f64 {
        let nodes = x.nodes;
        if self.root_damping.is_none() {
            return 0.0;
        }
        with_work(self.nodes.len(), |g| {
            self.gather(nodes, g);
            let mut eo = ElasticOut::default();
            let mut p = 0.0;
            for ep in &self.elastic {
                let (c, Some(d)) = self.section_matrices(ep) else {
                    continue;
                };
                let d = &d;
                let f = self.elastic_fields(ep, g);
                let sec = ElasticSection {
                    c: &c,
                    d: Some(d),
                    eps0: ep.eps0,
                    k0: ep.k0,
                };
                kernel::elastic(&f, &sec, false, &mut eo);
                p += ep.w * eo.dissipation;
            }
            p
        })
    }

    /// The dissipated power at the element's last residual evaluation (the last Newton
    /// iterate of a step), kept by the evaluation; at `x` before the first.
    fn evaluated_dissipated_power(&self, x: &ElementInput) -> f64 {
        if self.root_damping.is_none() {
            return 0.0;
        }
        self.last_dissipation
            .get()
            .unwrap_or_else(|| self.dissipated_power(x))
    }

    fn begin_analysis(&self) {
        self.last_dissipation.clear();
    }
}

impl Element for Arc<BeamElement> {
    fn name(&self) -> &str {
        self.as_ref().name()
    }
    fn nodes(&self) -> &[usize] {
        self.as_ref().nodes()
    }
    fn evaluate(&self, ctx: &EvalContext, x: &ElementInput, need: Need, out: &mut LocalTerms) {
        self.as_ref().evaluate(ctx, x, need, out)
    }
    fn prefetch(&self) {
        crate::math::prefetch::prefetch(self.as_ref());
    }
    fn kinetic_energy(&self, x: &ElementInput) -> f64 {
        self.as_ref().kinetic_energy(x)
    }
    fn potential_energy(&self, ctx: &EvalContext, x: &ElementInput) -> f64 {
        self.as_ref().potential_energy(ctx, x)
    }
    fn external_power(&self, ctx: &EvalContext, x: &ElementInput) -> f64 {
        self.as_ref().external_power(ctx, x)
    }
    fn dissipated_power(&self, x: &ElementInput) -> f64 {
        self.as_ref().dissipated_power(x)
    }
    fn evaluated_dissipated_power(&self, x: &ElementInput) -> f64 {
        self.as_ref().evaluated_dissipated_power(x)
    }
    fn begin_analysis(&self) {
        self.as_ref().begin_analysis()
    }
    fn breakpoints(&self, out: &mut Vec<f64>) {
        self.as_ref().breakpoints(out)
    }
    fn discrete_form(&self) -> Result<(), String> {
        self.as_ref().discrete_form()
    }
    fn discrete_residual(&self, step: &crate::core::DiscreteStep, out: &mut [f64]) {
        self.as_ref().discrete_residual(step, out)
    }
    fn discrete_memory_len(&self) -> usize {
        self.as_ref().discrete_memory_len()
    }
    fn discrete_memory(&self, step: &crate::core::DiscreteStep, out: &mut [f64]) {
        self.as_ref().discrete_memory(step, out)
    }
    fn discrete_memory_energy(&self, memory: &[f64]) -> f64 {
        self.as_ref().discrete_memory_energy(memory)
    }
    fn discrete_kinetic_energy(&self, x: &ElementInput) -> f64 {
        self.as_ref().discrete_kinetic_energy(x)
    }
    fn discrete_potential_energy(&self, ctx: &EvalContext, x: &ElementInput) -> f64 {
        self.as_ref().discrete_potential_energy(ctx, x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::elements::beam::section::{Section, mass_matrix};

    /// The AVX copy of the element's evaluation ([`BeamElement::evaluate_gathered_in_copy`])
    /// and the baseline body give the same bits: an order-4 element on a curved line,
    /// fully populated stiffness, mass offsets, damping, a follower load and gravity, in
    /// a displaced, rotated and moving state. The dissipated power each copy keeps
    /// ([`Element::evaluated_dissipated_power`]) is [`Element::dissipated_power`]'s.
    #[test]
    fn avx_and_baseline_evaluations_agree_to_the_bit() {
        #[cfg(target_arch = "x86_64")]
        if isa::Isa::detected() >= isa::Isa::Avx {
            let p = 4;
            let stiffness = |seed: f64| {
                let a = Matrix6::from_fn(|i, j| ((i * 5 + j * 11) as f64 * 0.29 + seed).sin());
                a * a.transpose() * 2.0 + Matrix6::identity() * 5.0
            };
            let inertia = Matrix3::new(0.4, 0.01, -0.02, 0.01, 0.2, 0.015, -0.02, 0.015, 0.25);
            let table = SectionTable {
                stations: vec![0.0, 1.0],
                sections: vec![
                    Section {
                        stiffness: stiffness(0.1),
                        mass: mass_matrix(2.0, &Vector3::new(0.0, 0.05, -0.03), &inertia),
                    },
                    Section {
                        stiffness: stiffness(0.7),
                        mass: mass_matrix(3.0, &Vector3::new(0.0, 0.02, 0.01), &inertia),
                    },
                ],
            };
            let x0: Vec<Vector3<f64>> = (0..=p)
                .map(|k| {
                    let s = k as f64 / p as f64;
                    Vector3::new(s, 0.3 * s * s, 0.1 * s)
                })
                .collect();
            let sec0: Vec<Rotation> = (0..=p)
                .map(|k| Rotation::exp(&Vector3::new(0.2 * k as f64, 0.1, -0.05)))
                .collect();
            let loads = Arc::new(vec![DistributedLoad {
                force: Vector3::new(-1.5, 0.7, 2.0),
                moment: Vector3::new(0.3, -0.6, 0.1),
                follower: true,
                function: TimeFunction::Constant(0.8),
                profile: vec![],
            }]);
            let e = BeamElement::new(ElementSpec {
                name: "e".into(),
                nodes: (0..=p).collect(),
                x0: &x0,
                sections0: &sec0,
                node_frames: &sec0,
                eta_range: (0.0, 1.0),
                table: Arc::new(table),
                damping: [1e-3, 2e-3, 1e-3, 3e-3, 1e-3, 2e-3],
                quadrature: Quadrature::Reduced,
                loads,
            });
            let nodes: Vec<NodeState> = (0..=p)
                .map(|k| {
                    let f = k as f64;
                    NodeState {
                        x: x0[k] + Vector3::new(0.01 * f, -0.02, 0.03 * f.sin()),
                        rot: sec0[k].compose_exp(&Vector3::new(0.1 * f, -0.2, 0.05 * f)),
                        v: Vector3::new(0.5, -f, 0.2),
                        w: Vector3::new(0.3, 0.1 * f, -0.7),
                        a: Vector3::new(1.0, 2.0, -0.5 * f),
                        wd: Vector3::new(-0.4, 0.6, 0.2 * f),
                    }
                })
                .collect();
            let ctx = EvalContext {
                time: 0.3,
                gravity: Vector3::new(0.3, -1.2, -9.81),
                load_factor: 0.7,
            };
            let x = ElementInput::nodes(&nodes);
            for need in [Need::Residual, Need::ResidualAndTangents] {
                let (mut wide, mut base) =
                    (LocalTerms::for_element(&e), LocalTerms::for_element(&e));
                wide.clear(need);
                base.clear(need);
                e.begin_analysis();
                e.evaluate(&ctx, &x, need, &mut wide);
                let kept_wide = e.evaluated_dissipated_power(&x);
                e.begin_analysis();
                with_work(e.nodes.len(), |g| {
                    e.gather(&nodes, g);
                    e.evaluate_gathered(&ctx, need, g, &mut base);
                });
                let kept_base = e.evaluated_dissipated_power(&x);
                // The dissipated power kept by either copy is the exact one, to the bit.
                let exact = e.dissipated_power(&x);
                assert!(exact > 0.0);
                assert_eq!(kept_wide.to_bits(), exact.to_bits(), "{need:?}");
                assert_eq!(kept_base.to_bits(), exact.to_bits(), "{need:?}");
                let bits = |t: &LocalTerms| -> Vec<u64> {
                    [
                        t.r.as_slice(),
                        t.k.as_slice(),
                        t.c.as_slice(),
                        t.m.as_slice(),
                    ]
                    .iter()
                    .flat_map(|s| s.iter().map(|v| v.to_bits()))
                    .collect()
                };
                assert!(wide.r.iter().any(|&v| v != 0.0));
                assert_eq!(bits(&wide), bits(&base), "{need:?}");
            }
        }
    }
}
