//! Quadrature-point kernels: the generalized forces of one point of the beam and their
//! exact Jacobians, as pure functions of the interpolated fields.
//!
//! The fields at a point are linear interpolations of nodal quantities: the reference-line
//! derivative `x′`, the (non-unit) quaternion `Q = Σ hᵢ sᵢ`, `Q′`, `Q̇`, `Q̈`, `Q̇′`, and the
//! velocity and acceleration. The section frame is `R = R(Q/|Q|)`; with
//! `P = (2/n) E(Q)` (see [`super::quaternion`]) the material rotation increment is
//! `δθ = P δQ`, the curvature `k = P Q′`, the angular velocity `ω = P Q̇` and the angular
//! acceleration `α = P Q̈ − ω (2 Q·Q̇/n)` — all exact for the interpolated rotation field.
//!
//! **Elastic point** (strains ε = Rᵀx′ − ε₀, κ = k − k₀; stress σ = [N; M] = C e + D ė):
//! virtual work `δε·N + δκ·M = δx′·(R N) + δθ·(N×Γ + M×k) + δθ′·M` gives the forces
//! conjugate to δx′, δQ and δQ′:
//! `F_x′ = R N`, `F_Q = Pᵀ(N×Γ + M×k) + P′ᵀ M`, `F_Q′ = Pᵀ M`, with `Γ = Rᵀx′` and
//! `P′ = dP/ds = (2/n)E(Q′) − (2 Q·Q′/n) P`.
//!
//! **Inertial point.** The sectional mass matrix has the structure of a rigid cross-section,
//! `M₆ = [[m I, Sᵀ], [S, J]]` with `S = m η̃` skew (η the mass-centre offset; enforced by
//! validation). Kirchhoff's equations `F_s = ṗ + ω×p`, `M_s = ḣ + ω×h + V×p` with
//! `[p; h] = M₆ [V; ω]`, `[ṗ; ḣ] = M₆ [A − ω×V; α]` and the section-frame velocity
//! `V = Rᵀv` then simplify exactly — the velocity terms cancel (Jacobi's identity) — to
//!
//! ```text
//! F_s = m A − S α − ω×(S ω),     M_s = S A + J α + ω×(J ω),     A = Rᵀ(a − g)
//! ```
//!
//! (gravity folded into the acceleration). With the applied distributed loads subtracted,
//! the forces conjugate to δx and δQ are
//! `F_x = m (a − g) + R (F_s − m A − f_follower) − f_dead`,
//! `F_Q = Pᵀ (M_s − m_follower − Rᵀ m_dead)`; neither depends on the translational
//! velocity.
//!
//! Jacobians are returned in blocks: rows by output, columns by point variable. Every block
//! is derived by hand and checked against central differences in the tests.

use super::quaternion::{Quat, e_hat, e_mat, rotation};
use crate::math::skew;
use nalgebra::{
    Matrix3, Matrix3x4, Matrix4, Matrix4x3, Matrix6, RowVector4, SMatrix, Vector3, Vector6,
};

/// Interpolated fields at an elastic point.
#[derive(Clone, Copy, Debug, Default)]
pub struct ElasticFields {
    pub xp: Vector3<f64>,
    pub q: Quat,
    pub qp: Quat,
    pub xpd: Vector3<f64>,
    pub qd: Quat,
    pub qpd: Quat,
}

/// Section data of an elastic point.
#[derive(Clone, Copy, Debug)]
pub struct ElasticSection<'a> {
    pub c: &'a Matrix6<f64>,
    pub d: Option<&'a Matrix6<f64>>,
    pub eps0: Vector3<f64>,
    pub k0: Vector3<f64>,
}

/// Derivatives of an R-row output with respect to the elastic point variables
/// x′, Q, Q′ and (damping only; zero otherwise) ẋ′, Q̇, Q̇′.
#[derive(Clone, Copy, Debug)]
pub struct Cols<const R: usize> {
    pub xp: SMatrix<f64, R, 3>,
    pub q: SMatrix<f64, R, 4>,
    pub qp: SMatrix<f64, R, 4>,
    pub xpd: SMatrix<f64, R, 3>,
    pub qd: SMatrix<f64, R, 4>,
    pub qpd: SMatrix<f64, R, 4>,
}

impl<const R: usize> Default for Cols<R> {
    fn default() -> Self {
        Self {
            xp: SMatrix::zeros(),
            q: SMatrix::zeros(),
            qp: SMatrix::zeros(),
            xpd: SMatrix::zeros(),
            qd: SMatrix::zeros(),
            qpd: SMatrix::zeros(),
        }
    }
}

impl<const R: usize> Cols<R> {
    /// `L · self` for every block (the rate blocks only if `rates`).
    #[inline]
    fn left<const S: usize>(&self, l: &SMatrix<f64, S, R>, rates: bool) -> Cols<S> {
        let mut o = Cols::<S> {
            xp: l * self.xp,
            q: l * self.q,
            qp: l * self.qp,
            ..Default::default()
        };
        if rates {
            o.xpd = l * self.xpd;
            o.qd = l * self.qd;
            o.qpd = l * self.qpd;
        }
        o
    }

    /// `self += L · other` for every block (the rate blocks only if `rates`).
    #[inline]
    fn add_left<const S: usize>(&mut self, l: &SMatrix<f64, R, S>, other: &Cols<S>, rates: bool) {
        self.xp += l * other.xp;
        self.q += l * other.q;
        self.qp += l * other.qp;
        if rates {
            self.xpd += l * other.xpd;
            self.qd += l * other.qd;
            self.qpd += l * other.qpd;
        }
    }
}

/// Results of an elastic point: forces conjugate to δx′ (`f_xp`), δQ (`f_q`), δQ′ (`f_qp`)
/// and, with `jac`, their Jacobians `d_xp`, `d_q`, `d_qp`.
#[derive(Clone, Debug, Default)]
pub struct ElasticOut {
    pub strain: Vector6<f64>,
    pub strain_rate: Vector6<f64>,
    pub stress: Vector6<f64>,
    /// Dissipation density `ε̇ᵀ D ε̇` of the damping (0 undamped).
    pub dissipation: f64,
    pub f_xp: Vector3<f64>,
    pub f_q: Quat,
    pub f_qp: Quat,
    pub d_xp: Cols<3>,
    pub d_q: Cols<4>,
    pub d_qp: Cols<4>,
}

/// `∂(P w)/∂Q = −(2/n) E(w) − (P w)(2Qᵀ/n)` for a fixed 4-vector w.
#[inline]
fn dpw(p: &Matrix3x4<f64>, w: &Quat, q2n: &RowVector4<f64>, n: f64) -> Matrix3x4<f64> {
    -(e_mat(w) * (2.0 / n)) - (p * w) * q2n
}

/// Γ = Rᵀx′ and k = P Q′ at an elastic point (n = |Q|², P = (2/n) E(Q), R = R(Q)): the
/// strain measures [`elastic`] starts from.
struct StrainMeasures {
    n: f64,
    p: Matrix3x4<f64>,
    r: Matrix3<f64>,
    rt: Matrix3<f64>,
    gamma: Vector3<f64>,
    k: Vector3<f64>,
}

#[inline(always)]
fn strain_measures(f: &ElasticFields) -> StrainMeasures {
    let q = &f.q;
    let n = q.norm_squared();
    let p = e_mat(q) * (2.0 / n);
    let r = rotation(q);
    let rt = r.transpose();
    let gamma = rt * f.xp;
    let k = p * f.qp;
    StrainMeasures {
        n,
        p,
        r,
        rt,
        gamma,
        k,
    }
}

/// The section strain e = (Γ − ε₀, k − k₀).
#[inline(always)]
fn strain_of(m: &StrainMeasures, eps0: &Vector3<f64>, k0: &Vector3<f64>) -> Vector6<f64> {
    let mut e = Vector6::zeros();
    e.fixed_rows_mut::<3>(0).copy_from(&(m.gamma - eps0));
    e.fixed_rows_mut::<3>(3).copy_from(&(m.k - k0));
    e
}

/// The section strain alone from the positional fields x′, Q, Q′ (the strain energy's
/// ½ eᵀC e): the same operations as [`elastic`]'s, so the same bits.
pub fn strain(f: &ElasticFields, eps0: &Vector3<f64>, k0: &Vector3<f64>) -> Vector6<f64> {
    strain_of(&strain_measures(f), eps0, k0)
}

/// Elastic point: forces and (if `jac`) Jacobians.
pub fn elastic(f: &ElasticFields, s: &ElasticSection, jac: bool, out: &mut ElasticOut) {
    let q = &f.q;
    let m = strain_measures(f);
    let (n, p, r, rt, gamma, k) = (m.n, m.p, m.r, m.rt, m.gamma, m.k);
    let q2n = q.transpose() * (2.0 / n);
    let e = strain_of(&m, &s.eps0, &s.k0);
    let mut sigma = s.c * e;
    // Rates (stiffness-proportional damping).
    let mut edot = Vector6::zeros();
    let mut dissipation = 0.0;
    let damped = s.d.is_some();
    let (mut omega, mut cc, mut y, mut rtxpd) =
        (Vector3::zeros(), 0.0, Vector3::zeros(), Vector3::zeros());
    if let Some(d) = s.d {
        omega = p * f.qd;
        cc = q.dot(&f.qd) * 2.0 / n;
        y = e_mat(&f.qd) * f.qp * (2.0 / n);
        rtxpd = rt * f.xpd;
        // ε̇ = Rᵀẋ′ + Γ×ω, κ̇ = P Q̇′ + (2/n)E(Q̇)Q′ − k c.
        let gd = rtxpd + gamma.cross(&omega);
        let kd = p * f.qpd + y - k * cc;
        edot.fixed_rows_mut::<3>(0).copy_from(&gd);
        edot.fixed_rows_mut::<3>(3).copy_from(&kd);
        let sigma_d = d * edot;
        sigma += sigma_d;
        dissipation = edot.dot(&sigma_d);
    }
    let nf: Vector3<f64> = sigma.fixed_rows::<3>(0).into();
    let mm: Vector3<f64> = sigma.fixed_rows::<3>(3).into();
    let cp = q.dot(&f.qp) * 2.0 / n;
    let pprime = e_mat(&f.qp) * (2.0 / n) - p * cp;
    let t = nf.cross(&gamma) + mm.cross(&k);
    let pt = p.transpose();
    out.strain = e;
    out.strain_rate = edot;
    out.stress = sigma;
    out.dissipation = dissipation;
    out.f_xp = r * nf;
    out.f_q = pt * t + pprime.transpose() * mm;
    out.f_qp = pt * mm;
    if !jac {
        return;
    }
    // Strain Jacobians: dΓ/dx′ = Rᵀ, dΓ/dQ = Γ̃ P; dk/dQ′ = P, dk/dQ = ∂(P Q′)/∂Q.
    let sk_g = skew(&gamma);
    let g_q = sk_g * p;
    let k_q = dpw(&p, &f.qp, &q2n, n);
    // dσ = C de + D dė, split into its N (rows 0–2) and M (rows 3–5) parts.
    let c_nn = s.c.fixed_view::<3, 3>(0, 0);
    let c_nm = s.c.fixed_view::<3, 3>(0, 3);
    let c_mn = s.c.fixed_view::<3, 3>(3, 0);
    let c_mm = s.c.fixed_view::<3, 3>(3, 3);
    let mut dn = Cols::<3> {
        xp: c_nn * rt,
        q: c_nn * g_q + c_nm * k_q,
        qp: c_nm * p,
        ..Default::default()
    };
    let mut dm = Cols::<3> {
        xp: c_mn * rt,
        q: c_mn * g_q + c_mm * k_q,
        qp: c_mm * p,
        ..Default::default()
    };
    if let Some(d) = s.d {
        let sk_w = skew(&omega);
        let w_q = dpw(&p, &f.qd, &q2n, n);
        let c_q = f.qd.transpose() * (2.0 / n) - q2n * cc;
        // dε̇: columns x′, Q, ẋ′, Q̇.
        let gd_xp = -(sk_w * rt);
        let gd_q = skew(&rtxpd) * p + sk_g * w_q - sk_w * g_q;
        let gd_qd = sk_g * p;
        // dκ̇: columns Q, Q′, Q̇, Q̇′.
        let kd_q = dpw(&p, &f.qpd, &q2n, n) - y * q2n - k_q * cc - k * c_q;
        let kd_qp = e_mat(&f.qd) * (2.0 / n) - p * cc;
        let kd_qd = -(e_mat(&f.qp) * (2.0 / n)) - k * q2n;
        for (rows, part) in [(0, &mut dn), (3, &mut dm)] {
            let dt = d.fixed_view::<3, 3>(rows, 0);
            let db = d.fixed_view::<3, 3>(rows, 3);
            part.xp += dt * gd_xp;
            part.q += dt * gd_q + db * kd_q;
            part.qp += db * kd_qp;
            part.xpd = dt * rt;
            part.qd = dt * gd_qd + db * kd_qd;
            part.qpd = db * p;
        }
    }
    // F_x′ = R N.
    out.d_xp = dn.left(&r, damped);
    out.d_xp.q -= r * skew(&nf) * p;
    // T = N×Γ + M×k: dT = Ñ dΓ − Γ̃ dN + M̃ dk − k̃ dM.
    let sk_n = skew(&nf);
    let sk_m = skew(&mm);
    let mut dt = dn.left(&(-sk_g), damped);
    dt.add_left(&(-skew(&k)), &dm, damped);
    dt.xp += sk_n * rt;
    dt.q += sk_n * g_q + sk_m * k_q;
    dt.qp += sk_m * p;
    // F_Q = Pᵀ T + P′ᵀ M (+ the derivative of Pᵀ and P′ᵀ themselves).
    out.d_q = dt.left(&pt, damped);
    out.d_q.add_left(&pprime.transpose(), &dm, damped);
    let ptt = pt * t;
    let ptm = pt * mm;
    let eh_t = e_hat(&t) * (2.0 / n);
    let eh_m = e_hat(&mm) * (2.0 / n);
    let dptm = eh_m - ptm * q2n;
    out.d_q.q += eh_t
        - ptt * q2n
        - (eh_m * f.qp) * q2n
        - ptm * (f.qp.transpose() * (2.0 / n) - q2n * cp)
        - dptm * cp;
    out.d_q.qp += dptm;
    // F_Q′ = Pᵀ M.
    out.d_qp = dm.left(&pt, damped);
    out.d_qp.q += dptm;
}

/// Interpolated fields at an inertial point.
#[derive(Clone, Copy, Debug, Default)]
pub struct InertialFields {
    pub q: Quat,
    pub a: Vector3<f64>,
    pub qd: Quat,
    pub qdd: Quat,
}

/// Mass data of an inertial point: `M₆ = [[m I, Sᵀ], [S, J]]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InertialSection {
    pub m: f64,
    /// `m η̃` (zero when the mass centre is on the reference line).
    pub s: Matrix3<f64>,
    pub j: Matrix3<f64>,
    /// `s ≠ 0`.
    pub offset: bool,
}

impl InertialSection {
    /// The blocks of a (validated) sectional mass matrix.
    pub fn new(m6: &Matrix6<f64>) -> Self {
        let s: Matrix3<f64> = m6.fixed_view::<3, 3>(3, 0).into();
        Self {
            m: m6[(0, 0)],
            s,
            j: m6.fixed_view::<3, 3>(3, 3).into(),
            offset: s.iter().any(|x| *x != 0.0),
        }
    }
}

/// Applied distributed loads at a point (per unit length, already scaled).
#[derive(Clone, Copy, Debug, Default)]
pub struct PointLoads {
    /// Dead force and moment, global components.
    pub f_dead: Vector3<f64>,
    pub m_dead: Vector3<f64>,
    /// Follower force and moment, section-frame components.
    pub f_follower: Vector3<f64>,
    pub m_follower: Vector3<f64>,
}

/// Results of an inertial point: forces conjugate to δx (`f_x`) and δQ (`f_q`) and, with
/// `jac`, their Jacobians in Q, Q̇, Q̈ and a (`∂F_x/∂a = m I`; nothing depends on v).
#[derive(Clone, Debug)]
pub struct InertialOut {
    pub f_x: Vector3<f64>,
    pub f_q: Quat,
    pub x_q: Matrix3x4<f64>,
    pub x_qd: Matrix3x4<f64>,
    pub x_qdd: Matrix3x4<f64>,
    pub q_q: Matrix4<f64>,
    pub q_qd: Matrix4<f64>,
    pub q_qdd: Matrix4<f64>,
    pub q_a: Matrix4x3<f64>,
    /// Whether the `x_*` blocks are non-zero (a mass offset or follower loads).
    pub x_rot: bool,
}

impl Default for InertialOut {
    fn default() -> Self {
        Self {
            f_x: Vector3::zeros(),
            f_q: Quat::zeros(),
            x_q: Matrix3x4::zeros(),
            x_qd: Matrix3x4::zeros(),
            x_qdd: Matrix3x4::zeros(),
            q_q: Matrix4::zeros(),
            q_qd: Matrix4::zeros(),
            q_qdd: Matrix4::zeros(),
            q_a: Matrix4x3::zeros(),
            x_rot: false,
        }
    }
}

/// Inertial point (inertia, gravity, distributed loads): forces and (if `jac`) Jacobians.
pub fn inertial(
    f: &InertialFields,
    ms: &InertialSection,
    gravity: &Vector3<f64>,
    loads: &PointLoads,
    jac: bool,
    out: &mut InertialOut,
) {
    let q = &f.q;
    let n = q.norm_squared();
    let p = e_mat(q) * (2.0 / n);
    let pt = p.transpose();
    let r = rotation(q);
    let rt = r.transpose();
    let omega = p * f.qd;
    let cc = q.dot(&f.qd) * 2.0 / n;
    let alpha = p * f.qdd - omega * cc;
    let ag = f.a - gravity;
    let jw = ms.j * omega;
    let follower = loads.f_follower != Vector3::zeros();
    // u = F_s − m A − f_follower (section frame), t = M_s − m_follower − Rᵀ m_dead.
    let mut u = -loads.f_follower;
    let mut t = ms.j * alpha + omega.cross(&jw) - loads.m_follower;
    let (mut sw, mut aa) = (Vector3::zeros(), Vector3::zeros());
    if ms.offset {
        sw = ms.s * omega;
        aa = rt * ag;
        u -= ms.s * alpha + omega.cross(&sw);
        t += ms.s * aa;
    }
    let rtmd = rt * loads.m_dead;
    t -= rtmd;
    out.f_x = ag * ms.m + r * u - loads.f_dead;
    out.f_q = pt * t;
    out.x_rot = ms.offset || follower;
    if !jac {
        return;
    }
    let q2n = q.transpose() * (2.0 / n);
    // ω = P Q̇, α = P Q̈ − ω c with c = (2/n) Q·Q̇.
    let w_q = dpw(&p, &f.qd, &q2n, n);
    let c_q = f.qd.transpose() * (2.0 / n) - q2n * cc;
    let al_q = dpw(&p, &f.qdd, &q2n, n) - w_q * cc - omega * c_q;
    let al_qd = -(p * cc) - omega * q2n;
    // d(ω×Jω)/dω.
    let wj = skew(&omega) * ms.j - skew(&jw);
    let mut t_q = ms.j * al_q + wj * w_q - skew(&rtmd) * p;
    let t_qd = ms.j * al_qd + wj * p;
    let jp = ms.j * p;
    if ms.offset {
        t_q += ms.s * skew(&aa) * p;
        out.q_a = pt * (ms.s * rt);
    } else {
        out.q_a = Matrix4x3::zeros();
    }
    out.q_q = pt * t_q + e_hat(&t) * (2.0 / n) - (pt * t) * q2n;
    out.q_qd = pt * t_qd;
    out.q_qdd = pt * jp;
    if out.x_rot {
        // F_x = m(a − g) + R u − f_dead.
        let mut x_q = -(r * skew(&u) * p);
        if ms.offset {
            // d(ω×Sω)/dω.
            let wm = skew(&omega) * ms.s - skew(&sw);
            let rs = r * ms.s;
            x_q -= rs * al_q + r * wm * w_q;
            out.x_qd = -(rs * al_qd + r * wm * p);
            out.x_qdd = -(rs * p);
        } else {
            out.x_qd = Matrix3x4::zeros();
            out.x_qdd = Matrix3x4::zeros();
        }
        out.x_q = x_q;
    }
}

/// Kinetic energy density ½ [V; ω]ᵀ M₆ [V; ω].
pub fn kinetic_density(q: &Quat, qd: &Quat, v: &Vector3<f64>, m6: &Matrix6<f64>) -> f64 {
    let n = q.norm_squared();
    let omega = e_mat(q) * qd * (2.0 / n);
    let vv = rotation(q).transpose() * v;
    let vel = Vector6::new(vv.x, vv.y, vv.z, omega.x, omega.y, omega.z);
    0.5 * vel.dot(&(m6 * vel))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rq(seed: f64) -> Quat {
        Quat::new(0.9 + 0.1 * seed, 0.3 - seed, 0.2 * seed, -0.4 + 0.3 * seed)
    }

    fn full_matrix(seed: f64) -> Matrix6<f64> {
        let a = Matrix6::from_fn(|i, j| ((i * 7 + j * 3) as f64 * 0.37 + seed).sin());
        a * a.transpose() + Matrix6::identity() * 3.0
    }

    /// The elastic point variables stacked: x′, Q, Q′, ẋ′, Q̇, Q̇′ (22).
    fn stack_elastic(f: &ElasticFields) -> [f64; 22] {
        let mut z = [0.0; 22];
        let parts: [&[f64]; 6] = [
            f.xp.as_slice(),
            f.q.as_slice(),
            f.qp.as_slice(),
            f.xpd.as_slice(),
            f.qd.as_slice(),
            f.qpd.as_slice(),
        ];
        let mut k = 0;
        for p in parts {
            for v in p {
                z[k] = *v;
                k += 1;
            }
        }
        z
    }

    fn elastic_of(z: &[f64; 22]) -> ElasticFields {
        let v3 = |k: usize| Vector3::new(z[k], z[k + 1], z[k + 2]);
        let v4 = |k: usize| Quat::new(z[k], z[k + 1], z[k + 2], z[k + 3]);
        ElasticFields {
            xp: v3(0),
            q: v4(3),
            qp: v4(7),
            xpd: v3(11),
            qd: v4(14),
            qpd: v4(18),
        }
    }

    /// Column j (of the 22 stacked variables) of a block set.
    fn column<const R: usize>(c: &Cols<R>, j: usize) -> SMatrix<f64, R, 1> {
        match j {
            0..3 => c.xp.column(j).into(),
            3..7 => c.q.column(j - 3).into(),
            7..11 => c.qp.column(j - 7).into(),
            11..14 => c.xpd.column(j - 11).into(),
            14..18 => c.qd.column(j - 14).into(),
            _ => c.qpd.column(j - 18).into(),
        }
    }

    /// The strain alone ([`strain`], the strain energy's) is the elastic kernel's to the
    /// bit, with and without the rates (which the strain does not read).
    #[test]
    fn strain_alone_is_the_elastic_kernels_to_the_bit() {
        let f = ElasticFields {
            xp: Vector3::new(0.9, 0.2, -0.1),
            q: rq(0.1) * 1.3,
            qp: rq(0.7) * 0.4,
            xpd: Vector3::new(0.3, -0.4, 0.2),
            qd: rq(-0.3) * 0.5,
            qpd: rq(0.5) * 0.2,
        };
        let positions = ElasticFields {
            xpd: Vector3::zeros(),
            qd: Quat::zeros(),
            qpd: Quat::zeros(),
            ..f
        };
        let c = full_matrix(0.3);
        let d = full_matrix(0.9) * 0.1;
        let (eps0, k0) = (
            Vector3::new(1.0, 0.01, -0.02),
            Vector3::new(0.05, 0.1, -0.2),
        );
        let bits = |e: &Vector6<f64>| e.map(f64::to_bits);
        for damping in [Some(&d), None] {
            let sec = ElasticSection {
                c: &c,
                d: damping,
                eps0,
                k0,
            };
            let mut out = ElasticOut::default();
            elastic(&f, &sec, false, &mut out);
            assert!(out.strain.iter().all(|&v| v != 0.0));
            assert_eq!(bits(&strain(&f, &eps0, &k0)), bits(&out.strain));
            assert_eq!(bits(&strain(&positions, &eps0, &k0)), bits(&out.strain));
        }
    }

    /// Every Jacobian block of the elastic kernel (with a fully populated C, with and
    /// without damping D) against central differences in each point variable: step 1e-6
    /// gives ~1e-9 accuracy.
    #[test]
    fn elastic_jacobian_matches_finite_differences() {
        let f0 = ElasticFields {
            xp: Vector3::new(0.9, 0.2, -0.1),
            q: rq(0.1) * 1.3,
            qp: rq(0.7) * 0.4,
            xpd: Vector3::new(0.3, -0.4, 0.2),
            qd: rq(-0.3) * 0.5,
            qpd: rq(0.5) * 0.2,
        };
        let c = full_matrix(0.3);
        let d = full_matrix(0.9) * 0.1;
        for damping in [Some(&d), None] {
            let sec = ElasticSection {
                c: &c,
                d: damping,
                eps0: Vector3::new(1.0, 0.01, -0.02),
                k0: Vector3::new(0.05, 0.1, -0.2),
            };
            let z0 = stack_elastic(&f0);
            let mut out = ElasticOut::default();
            elastic(&f0, &sec, true, &mut out);
            let eps = 1e-6;
            let mut o1 = ElasticOut::default();
            let mut o2 = ElasticOut::default();
            let columns = if damping.is_some() { 22 } else { 11 };
            for j in 0..columns {
                let (mut zp, mut zm) = (z0, z0);
                zp[j] += eps;
                zm[j] -= eps;
                elastic(&elastic_of(&zp), &sec, false, &mut o1);
                elastic(&elastic_of(&zm), &sec, false, &mut o2);
                let fx = (o1.f_xp - o2.f_xp) / (2.0 * eps);
                let fq = (o1.f_q - o2.f_q) / (2.0 * eps);
                let fqp = (o1.f_qp - o2.f_qp) / (2.0 * eps);
                let scale = 1.0 + out.stress.norm();
                assert!(
                    (fx - column(&out.d_xp, j)).norm() < 1e-6 * scale,
                    "F_x' col {j}"
                );
                assert!(
                    (fq - column(&out.d_q, j)).norm() < 1e-6 * scale,
                    "F_Q col {j}: {fq} vs {}",
                    column(&out.d_q, j)
                );
                assert!(
                    (fqp - column(&out.d_qp, j)).norm() < 1e-6 * scale,
                    "F_Q' col {j}"
                );
            }
        }
    }

    /// The inertial kernel's blocks against central differences (with a mass offset, a full
    /// inertia, gravity and dead and follower loads; then without offset and loads, where
    /// the translational rows must not depend on the rotation).
    #[test]
    fn inertial_jacobian_matches_finite_differences() {
        let f0 = InertialFields {
            q: rq(0.2) * 0.8,
            a: Vector3::new(-0.2, 0.4, 1.5),
            qd: rq(0.6) * 0.7,
            qdd: rq(-0.4) * 0.9,
        };
        let j = Matrix3::new(0.5, 0.01, 0.02, 0.01, 0.3, -0.03, 0.02, -0.03, 0.25);
        let g = Vector3::new(0.1, -0.3, -9.81);
        let loads = PointLoads {
            f_dead: Vector3::new(1.0, 2.0, -3.0),
            m_dead: Vector3::new(0.5, -0.2, 0.1),
            f_follower: Vector3::new(-0.4, 0.6, 0.2),
            m_follower: Vector3::new(0.2, 0.3, -0.7),
        };
        let cases = [
            (Vector3::new(0.0, 0.1, -0.2), loads),
            (Vector3::zeros(), PointLoads::default()),
        ];
        for (eta, loads) in cases {
            let ms = InertialSection::new(&super::super::section::mass_matrix(2.0, &eta, &j));
            let of = |z: &[f64; 15]| InertialFields {
                q: Quat::new(z[0], z[1], z[2], z[3]),
                a: Vector3::new(z[4], z[5], z[6]),
                qd: Quat::new(z[7], z[8], z[9], z[10]),
                qdd: Quat::new(z[11], z[12], z[13], z[14]),
            };
            let mut z0 = [0.0; 15];
            for (k, v) in
                f0.q.iter()
                    .chain(f0.a.iter())
                    .chain(f0.qd.iter())
                    .chain(f0.qdd.iter())
                    .enumerate()
            {
                z0[k] = *v;
            }
            let mut out = InertialOut::default();
            inertial(&f0, &ms, &g, &loads, true, &mut out);
            let eps = 1e-6;
            let (mut o1, mut o2) = (InertialOut::default(), InertialOut::default());
            for c in 0..15 {
                let (mut zp, mut zm) = (z0, z0);
                zp[c] += eps;
                zm[c] -= eps;
                inertial(&of(&zp), &ms, &g, &loads, false, &mut o1);
                inertial(&of(&zm), &ms, &g, &loads, false, &mut o2);
                let fx = (o1.f_x - o2.f_x) / (2.0 * eps);
                let fq = (o1.f_q - o2.f_q) / (2.0 * eps);
                let (jx, jq): (Vector3<f64>, nalgebra::Vector4<f64>) = match c {
                    0..4 => (
                        if out.x_rot {
                            out.x_q.column(c).into()
                        } else {
                            Vector3::zeros()
                        },
                        out.q_q.column(c).into(),
                    ),
                    4..7 => {
                        let mut e = Vector3::zeros();
                        e[c - 4] = ms.m;
                        (e, out.q_a.column(c - 4).into())
                    }
                    7..11 => (
                        if out.x_rot {
                            out.x_qd.column(c - 7).into()
                        } else {
                            Vector3::zeros()
                        },
                        out.q_qd.column(c - 7).into(),
                    ),
                    _ => (
                        if out.x_rot {
                            out.x_qdd.column(c - 11).into()
                        } else {
                            Vector3::zeros()
                        },
                        out.q_qdd.column(c - 11).into(),
                    ),
                };
                assert!((fx - jx).norm() < 1e-6 * 30.0, "F_x col {c}: {fx} vs {jx}");
                assert!((fq - jq).norm() < 1e-6 * 30.0, "F_Q col {c}: {fq} vs {jq}");
            }
        }
    }

    /// The simplified Kirchhoff form equals the full one, `F_s = ṗ + ω×p`,
    /// `M_s = ḣ + ω×h + V×p` with `[p; h] = M₆[V; ω]`, `[ṗ; ḣ] = M₆[A − ω×V; α]`, for any
    /// translational velocity V (the V terms cancel by Jacobi's identity).
    #[test]
    fn kirchhoff_velocity_terms_cancel() {
        let m6 = super::super::section::mass_matrix(
            3.0,
            &Vector3::new(0.0, 0.2, -0.1),
            &Matrix3::new(0.5, 0.01, 0.02, 0.01, 0.3, -0.03, 0.02, -0.03, 0.25),
        );
        let ms = InertialSection::new(&m6);
        let (v, w, a, al) = (
            Vector3::new(1.3, -0.4, 2.2),
            Vector3::new(0.3, 0.9, -0.5),
            Vector3::new(-0.7, 0.2, 0.4),
            Vector3::new(0.1, -0.6, 0.8),
        );
        let stack = |x: &Vector3<f64>, y: &Vector3<f64>| Vector6::new(x.x, x.y, x.z, y.x, y.y, y.z);
        let pm = m6 * stack(&v, &w);
        let pd = m6 * stack(&(a - w.cross(&v)), &al);
        let p1: Vector3<f64> = pm.fixed_rows::<3>(0).into();
        let p2: Vector3<f64> = pm.fixed_rows::<3>(3).into();
        let fs = Vector3::from(pd.fixed_rows::<3>(0)) + w.cross(&p1);
        let msum = Vector3::from(pd.fixed_rows::<3>(3)) + w.cross(&p2) + v.cross(&p1);
        let fs2 = a * ms.m - ms.s * al - w.cross(&(ms.s * w));
        let ms2 = ms.s * a + ms.j * al + w.cross(&(ms.j * w));
        assert!((fs - fs2).norm() < 1e-14 && (msum - ms2).norm() < 1e-14);
    }
}
