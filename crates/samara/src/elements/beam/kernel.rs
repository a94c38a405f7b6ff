//! Quadrature-point kernels: the generalized forces of one point of the beam and their
//! exact Jacobians, as pure functions of the interpolated fields.
//!
//! The fields at a point are linear interpolations of nodal quantities: the reference-line
//! derivative `x′`, the (non-unit) quaternion `Q = Σ hᵢ sᵢ`, `Q′`, `Q̇`, `Q̈`, `Q̇′`, and the
//! velocity `v` and acceleration `a`. The section frame is `R = R(Q/|Q|)`; with
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
//! **Inertial point** (section momentum `[p; h] = M₆ [V; ω]`, `V = Rᵀv`; Kirchhoff's
//! equations with gravity folded into the acceleration `A = Rᵀ(a − g)`):
//! `F_s = ṗ + ω×p`, `M_s = ḣ + ω×h + V×p` with `[ṗ; ḣ] = M₆ [A − ω×V; α]`; applied
//! distributed loads are subtracted. Forces conjugate to δx and δQ:
//! `F_x = R (F_s − f_follower) − f_dead`, `F_Q = Pᵀ (M_s − m_follower − Rᵀ m_dead)`.
//!
//! Jacobians are with respect to the stacked point variables (index constants below);
//! every block is derived by hand and checked against central differences in the tests.

use super::quaternion::{Quat, e_hat, e_mat, rotation};
use crate::math::skew;
use nalgebra::{Matrix3, Matrix3x4, Matrix6, SMatrix, SVector, Vector3, Vector6};

/// Elastic point variables: x′, Q, Q′, ẋ′, Q̇, Q̇′.
pub const E_XP: usize = 0;
pub const E_Q: usize = 3;
pub const E_QP: usize = 7;
pub const E_XPD: usize = 11;
pub const E_QD: usize = 14;
pub const E_QPD: usize = 18;
pub const NE: usize = 22;

/// Inertial point variables: Q, v, a, Q̇, Q̈.
pub const I_Q: usize = 0;
pub const I_V: usize = 4;
pub const I_A: usize = 7;
pub const I_QD: usize = 10;
pub const I_QDD: usize = 14;
pub const NI: usize = 18;

pub type J3<const N: usize> = SMatrix<f64, 3, N>;
pub type J4<const N: usize> = SMatrix<f64, 4, N>;

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

/// Results of an elastic point.
#[derive(Clone, Debug, Default)]
pub struct ElasticOut {
    pub strain: Vector6<f64>,
    pub strain_rate: Vector6<f64>,
    pub stress: Vector6<f64>,
    pub f_xp: Vector3<f64>,
    pub f_q: Quat,
    pub f_qp: Quat,
    pub d_xp: J3<NE>,
    pub d_q: J4<NE>,
    pub d_qp: J4<NE>,
}

/// `∂(P w)/∂Q = −(2/n) E(w) − (P w)(2Qᵀ/n)` for a fixed 4-vector w.
#[inline]
fn dpw(p: &Matrix3x4<f64>, w: &Quat, q2n: &nalgebra::RowVector4<f64>, n: f64) -> Matrix3x4<f64> {
    -(e_mat(w) * (2.0 / n)) - (p * w) * q2n
}

#[inline]
fn put3<const N: usize>(j: &mut J3<N>, col: usize, b: &Matrix3<f64>) {
    j.fixed_view_mut::<3, 3>(0, col).add_assign(b);
}
#[inline]
fn put34<const N: usize>(j: &mut J3<N>, col: usize, b: &Matrix3x4<f64>) {
    j.fixed_view_mut::<3, 4>(0, col).add_assign(b);
}

use std::ops::AddAssign;

/// Elastic point: forces and (if `jac`) Jacobians.
pub fn elastic(f: &ElasticFields, s: &ElasticSection, jac: bool, out: &mut ElasticOut) {
    let q = &f.q;
    let n = q.norm_squared();
    let p = e_mat(q) * (2.0 / n);
    let r = rotation(q);
    let rt = r.transpose();
    let q2n = q.transpose() * (2.0 / n);
    let gamma = rt * f.xp;
    let k = p * f.qp;
    let mut e = Vector6::zeros();
    e.fixed_rows_mut::<3>(0).copy_from(&(gamma - s.eps0));
    e.fixed_rows_mut::<3>(3).copy_from(&(k - s.k0));
    let mut sigma = s.c * e;
    // Rates (stiffness-proportional damping).
    let mut edot = Vector6::zeros();
    let damped = s.d.is_some();
    let (mut omega, mut cc) = (Vector3::zeros(), 0.0);
    if let Some(d) = s.d {
        omega = p * f.qd;
        cc = q.dot(&f.qd) * 2.0 / n;
        let y = e_mat(&f.qd) * f.qp * (2.0 / n);
        let gd = rt * f.xpd + gamma.cross(&omega);
        let kd = p * f.qpd + y - k * cc;
        edot.fixed_rows_mut::<3>(0).copy_from(&gd);
        edot.fixed_rows_mut::<3>(3).copy_from(&kd);
        sigma += d * edot;
    }
    let nf: Vector3<f64> = sigma.fixed_rows::<3>(0).into();
    let mm: Vector3<f64> = sigma.fixed_rows::<3>(3).into();
    let cp = q.dot(&f.qp) * 2.0 / n;
    let pprime = e_mat(&f.qp) * (2.0 / n) - p * cp;
    let t = nf.cross(&gamma) + mm.cross(&k);
    out.strain = e;
    out.strain_rate = edot;
    out.stress = sigma;
    out.f_xp = r * nf;
    out.f_q = p.transpose() * t + pprime.transpose() * mm;
    out.f_qp = p.transpose() * mm;
    if !jac {
        return;
    }
    // Strain Jacobians.
    let mut dg = J3::<NE>::zeros();
    put3(&mut dg, E_XP, &rt);
    put34(&mut dg, E_Q, &(skew(&gamma) * p));
    let mut dk = J3::<NE>::zeros();
    put34(&mut dk, E_QP, &p);
    put34(&mut dk, E_Q, &dpw(&p, &f.qp, &q2n, n));
    let mut de = SMatrix::<f64, 6, NE>::zeros();
    de.fixed_view_mut::<3, NE>(0, 0).copy_from(&dg);
    de.fixed_view_mut::<3, NE>(3, 0).copy_from(&dk);
    let mut dsigma = s.c * de;
    if let Some(d) = s.d {
        let mut dw = J3::<NE>::zeros();
        put34(&mut dw, E_QD, &p);
        put34(&mut dw, E_Q, &dpw(&p, &f.qd, &q2n, n));
        let mut dc = SMatrix::<f64, 1, NE>::zeros();
        dc.fixed_view_mut::<1, 4>(0, E_QD).copy_from(&q2n);
        dc.fixed_view_mut::<1, 4>(0, E_Q)
            .copy_from(&(f.qd.transpose() * (2.0 / n) - q2n * cc));
        // ε̇ = Rᵀẋ′ + Γ×ω.
        let mut dgd = J3::<NE>::zeros();
        put3(&mut dgd, E_XPD, &rt);
        put34(&mut dgd, E_Q, &(skew(&(rt * f.xpd)) * p));
        dgd += skew(&gamma) * dw - skew(&omega) * dg;
        // κ̇ = P Q̇′ + (2/n)E(Q̇)Q′ − k c.
        let y = e_mat(&f.qd) * f.qp * (2.0 / n);
        let mut dkd = J3::<NE>::zeros();
        put34(&mut dkd, E_QPD, &p);
        put34(&mut dkd, E_Q, &dpw(&p, &f.qpd, &q2n, n));
        put34(&mut dkd, E_QD, &(-(e_mat(&f.qp) * (2.0 / n))));
        put34(&mut dkd, E_QP, &(e_mat(&f.qd) * (2.0 / n)));
        put34(&mut dkd, E_Q, &(-(y * q2n)));
        dkd -= dk * cc + k * dc;
        let mut ded = SMatrix::<f64, 6, NE>::zeros();
        ded.fixed_view_mut::<3, NE>(0, 0).copy_from(&dgd);
        ded.fixed_view_mut::<3, NE>(3, 0).copy_from(&dkd);
        dsigma += d * ded;
    }
    let _ = damped;
    let dn: J3<NE> = dsigma.fixed_view::<3, NE>(0, 0).into();
    let dm: J3<NE> = dsigma.fixed_view::<3, NE>(3, 0).into();
    // F_x′ = R N.
    out.d_xp = r * dn;
    put34(&mut out.d_xp, E_Q, &(-(r * skew(&nf)) * p));
    // T = N×Γ + M×k.
    let dt = skew(&nf) * dg - skew(&gamma) * dn + skew(&mm) * dk - skew(&k) * dm;
    // F_Q = Pᵀ T + P′ᵀ M.
    out.d_q = p.transpose() * dt + pprime.transpose() * dm;
    let ptt = p.transpose() * t;
    let ptm = p.transpose() * mm;
    let eh_t = e_hat(&t) * (2.0 / n);
    let eh_m = e_hat(&mm) * (2.0 / n);
    let dq_fixed = eh_t
        - ptt * q2n
        - (eh_m * f.qp) * q2n
        - ptm * (f.qp.transpose() * (2.0 / n) - q2n * cp)
        - (eh_m - ptm * q2n) * cp;
    out.d_q.fixed_view_mut::<4, 4>(0, E_Q).add_assign(&dq_fixed);
    out.d_q
        .fixed_view_mut::<4, 4>(0, E_QP)
        .add_assign(&(eh_m - ptm * q2n));
    // F_Q′ = Pᵀ M.
    out.d_qp = p.transpose() * dm;
    out.d_qp
        .fixed_view_mut::<4, 4>(0, E_Q)
        .add_assign(&(eh_m - ptm * q2n));
}

/// Interpolated fields at an inertial point.
#[derive(Clone, Copy, Debug, Default)]
pub struct InertialFields {
    pub q: Quat,
    pub v: Vector3<f64>,
    pub a: Vector3<f64>,
    pub qd: Quat,
    pub qdd: Quat,
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

#[derive(Clone, Debug, Default)]
pub struct InertialOut {
    pub f_x: Vector3<f64>,
    pub f_q: Quat,
    pub d_x: J3<NI>,
    pub d_q: J4<NI>,
}

/// Inertial point (inertia, gravity, distributed loads): forces and (if `jac`) Jacobians.
pub fn inertial(
    f: &InertialFields,
    m6: &Matrix6<f64>,
    gravity: &Vector3<f64>,
    loads: &PointLoads,
    jac: bool,
    out: &mut InertialOut,
) {
    let q = &f.q;
    let n = q.norm_squared();
    let p = e_mat(q) * (2.0 / n);
    let r = rotation(q);
    let rt = r.transpose();
    let q2n = q.transpose() * (2.0 / n);
    let omega = p * f.qd;
    let cc = q.dot(&f.qd) * 2.0 / n;
    let alpha = p * f.qdd - omega * cc;
    let v = rt * f.v;
    let a = rt * (f.a - gravity);
    let mut vel = Vector6::zeros();
    vel.fixed_rows_mut::<3>(0).copy_from(&v);
    vel.fixed_rows_mut::<3>(3).copy_from(&omega);
    let mut u = Vector6::zeros();
    u.fixed_rows_mut::<3>(0).copy_from(&(a - omega.cross(&v)));
    u.fixed_rows_mut::<3>(3).copy_from(&alpha);
    let pm = m6 * vel;
    let pd = m6 * u;
    let pm1: Vector3<f64> = pm.fixed_rows::<3>(0).into();
    let pm2: Vector3<f64> = pm.fixed_rows::<3>(3).into();
    let fs = Vector3::from(pd.fixed_rows::<3>(0)) + omega.cross(&pm1);
    let ms = Vector3::from(pd.fixed_rows::<3>(3)) + omega.cross(&pm2) + v.cross(&pm1);
    let fnet = fs - loads.f_follower;
    let rtmd = rt * loads.m_dead;
    let t = ms - loads.m_follower - rtmd;
    out.f_x = r * fnet - loads.f_dead;
    out.f_q = p.transpose() * t;
    if !jac {
        return;
    }
    let mut dw = J3::<NI>::zeros();
    put34(&mut dw, I_QD, &p);
    put34(&mut dw, I_Q, &dpw(&p, &f.qd, &q2n, n));
    let mut dc = SMatrix::<f64, 1, NI>::zeros();
    dc.fixed_view_mut::<1, 4>(0, I_QD).copy_from(&q2n);
    dc.fixed_view_mut::<1, 4>(0, I_Q)
        .copy_from(&(f.qd.transpose() * (2.0 / n) - q2n * cc));
    let mut dal = J3::<NI>::zeros();
    put34(&mut dal, I_QDD, &p);
    put34(&mut dal, I_Q, &dpw(&p, &f.qdd, &q2n, n));
    dal -= dw * cc + omega * dc;
    let mut dv = J3::<NI>::zeros();
    put3(&mut dv, I_V, &rt);
    put34(&mut dv, I_Q, &(skew(&v) * p));
    let mut da = J3::<NI>::zeros();
    put3(&mut da, I_A, &rt);
    put34(&mut da, I_Q, &(skew(&a) * p));
    let du1 = da - skew(&omega) * dv + skew(&v) * dw;
    let m11 = m6.fixed_view::<6, 3>(0, 0);
    let m12 = m6.fixed_view::<6, 3>(0, 3);
    let dpm = m11 * dv + m12 * dw;
    let dpd = m11 * du1 + m12 * dal;
    let dpm1: J3<NI> = dpm.fixed_view::<3, NI>(0, 0).into();
    let dpm2: J3<NI> = dpm.fixed_view::<3, NI>(3, 0).into();
    let dfs = dpd.fixed_view::<3, NI>(0, 0) + skew(&omega) * dpm1 - skew(&pm1) * dw;
    let dms = dpd.fixed_view::<3, NI>(3, 0) + skew(&omega) * dpm2 - skew(&pm2) * dw
        + skew(&v) * dpm1
        - skew(&pm1) * dv;
    out.d_x = r * dfs;
    put34(&mut out.d_x, I_Q, &(-(r * skew(&fnet)) * p));
    let mut dt = dms;
    put34(&mut dt, I_Q, &(-(skew(&rtmd) * p)));
    out.d_q = p.transpose() * dt;
    let ptt = p.transpose() * t;
    out.d_q
        .fixed_view_mut::<4, 4>(0, I_Q)
        .add_assign(&(e_hat(&t) * (2.0 / n) - ptt * q2n));
}

/// Kinetic energy density ½ [V; ω]ᵀ M₆ [V; ω].
pub fn kinetic_density(q: &Quat, qd: &Quat, v: &Vector3<f64>, m6: &Matrix6<f64>) -> f64 {
    let n = q.norm_squared();
    let omega = e_mat(q) * qd * (2.0 / n);
    let vv = rotation(q).transpose() * v;
    let vel = Vector6::new(vv.x, vv.y, vv.z, omega.x, omega.y, omega.z);
    0.5 * vel.dot(&(m6 * vel))
}

/// The stacked variables as one vector (tests and finite differences).
pub fn stack<const N: usize>(parts: &[&[f64]]) -> SVector<f64, N> {
    let mut z = SVector::<f64, N>::zeros();
    let mut k = 0;
    for p in parts {
        for v in *p {
            z[k] = *v;
            k += 1;
        }
    }
    z
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

    fn elastic_of(z: &SVector<f64, NE>) -> ElasticFields {
        let v3 = |k: usize| Vector3::new(z[k], z[k + 1], z[k + 2]);
        let v4 = |k: usize| Quat::new(z[k], z[k + 1], z[k + 2], z[k + 3]);
        ElasticFields {
            xp: v3(E_XP),
            q: v4(E_Q),
            qp: v4(E_QP),
            xpd: v3(E_XPD),
            qd: v4(E_QD),
            qpd: v4(E_QPD),
        }
    }

    /// Every Jacobian block of the elastic kernel (with a fully populated C and damping D)
    /// against central differences in each point variable: step 1e-6 gives ~1e-9 accuracy.
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
        let sec = ElasticSection {
            c: &c,
            d: Some(&d),
            eps0: Vector3::new(1.0, 0.01, -0.02),
            k0: Vector3::new(0.05, 0.1, -0.2),
        };
        let z0 = stack::<NE>(&[
            f0.xp.as_slice(),
            f0.q.as_slice(),
            f0.qp.as_slice(),
            f0.xpd.as_slice(),
            f0.qd.as_slice(),
            f0.qpd.as_slice(),
        ]);
        let mut out = ElasticOut::default();
        elastic(&f0, &sec, true, &mut out);
        let eps = 1e-6;
        let mut o1 = ElasticOut::default();
        let mut o2 = ElasticOut::default();
        for j in 0..NE {
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
                (fx - out.d_xp.column(j)).norm() < 1e-6 * scale,
                "F_x' col {j}"
            );
            assert!(
                (fq - out.d_q.column(j)).norm() < 1e-6 * scale,
                "F_Q col {j}: {fq} vs {}",
                out.d_q.column(j)
            );
            assert!(
                (fqp - out.d_qp.column(j)).norm() < 1e-6 * scale,
                "F_Q' col {j}"
            );
        }
    }

    #[test]
    fn inertial_jacobian_matches_finite_differences() {
        let f0 = InertialFields {
            q: rq(0.2) * 0.8,
            v: Vector3::new(0.3, -1.0, 0.5),
            a: Vector3::new(-0.2, 0.4, 1.5),
            qd: rq(0.6) * 0.7,
            qdd: rq(-0.4) * 0.9,
        };
        let m6 = super::super::section::mass_matrix(
            2.0,
            &Vector3::new(0.0, 0.1, -0.2),
            &Matrix3::new(0.5, 0.01, 0.02, 0.01, 0.3, -0.03, 0.02, -0.03, 0.25),
        );
        let g = Vector3::new(0.1, -0.3, -9.81);
        let loads = PointLoads {
            f_dead: Vector3::new(1.0, 2.0, -3.0),
            m_dead: Vector3::new(0.5, -0.2, 0.1),
            f_follower: Vector3::new(-0.4, 0.6, 0.2),
            m_follower: Vector3::new(0.2, 0.3, -0.7),
        };
        let z0 = stack::<NI>(&[
            f0.q.as_slice(),
            f0.v.as_slice(),
            f0.a.as_slice(),
            f0.qd.as_slice(),
            f0.qdd.as_slice(),
        ]);
        let of = |z: &SVector<f64, NI>| InertialFields {
            q: Quat::new(z[0], z[1], z[2], z[3]),
            v: Vector3::new(z[4], z[5], z[6]),
            a: Vector3::new(z[7], z[8], z[9]),
            qd: Quat::new(z[10], z[11], z[12], z[13]),
            qdd: Quat::new(z[14], z[15], z[16], z[17]),
        };
        let mut out = InertialOut::default();
        inertial(&f0, &m6, &g, &loads, true, &mut out);
        let eps = 1e-6;
        let (mut o1, mut o2) = (InertialOut::default(), InertialOut::default());
        for j in 0..NI {
            let (mut zp, mut zm) = (z0, z0);
            zp[j] += eps;
            zm[j] -= eps;
            inertial(&of(&zp), &m6, &g, &loads, false, &mut o1);
            inertial(&of(&zm), &m6, &g, &loads, false, &mut o2);
            let fx = (o1.f_x - o2.f_x) / (2.0 * eps);
            let fq = (o1.f_q - o2.f_q) / (2.0 * eps);
            assert!((fx - out.d_x.column(j)).norm() < 1e-6 * 30.0, "F_x col {j}");
            assert!(
                (fq - out.d_q.column(j)).norm() < 1e-6 * 30.0,
                "F_Q col {j}: {fq} vs {}",
                out.d_q.column(j)
            );
        }
    }
}
