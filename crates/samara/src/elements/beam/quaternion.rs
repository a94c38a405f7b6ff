//! Quaternion algebra of the beam kernel, on plain 4-vectors `[w, x, y, z]` that need not be
//! of unit length (the interpolated quaternion Q = Σ hᵢ qᵢ is not).
//!
//! With `n = Q·Q`:
//! - `L(a) b = a ⊗ b`, `R(b) a = a ⊗ b` (left/right multiplication matrices);
//! - `E(Q) P = vec(Q̄ ⊗ P) = [−q | w I − q̃] P` (3×4), so that the material rotation
//!   increment of the unit quaternion Q/|Q| under a change δQ is `δθ = (2/n) E(Q) δQ`,
//!   its material curvature `k = (2/n) E(Q) Q′` and angular velocity `ω = (2/n) E(Q) Q̇`;
//!   `E(Q) Q = 0`, `E(Q) P = −E(P) Q`, `E(Q)ᵀ m = R((0, m)) Q`;
//! - `G(s) = ½ L(s)[0; I]` (4×3): `∂s/∂θ` for a unit quaternion updated by `s ⊗ exp(θ/2)`.

use nalgebra::{Matrix3, Matrix3x4, Matrix4, Matrix4x3, Vector3, Vector4};

pub type Quat = Vector4<f64>;

#[inline]
pub fn quat(w: f64, v: &Vector3<f64>) -> Quat {
    Quat::new(w, v.x, v.y, v.z)
}

#[inline]
pub fn vec_part(q: &Quat) -> Vector3<f64> {
    Vector3::new(q[1], q[2], q[3])
}

/// `a ⊗ b`.
#[inline]
pub fn mul(a: &Quat, b: &Quat) -> Quat {
    Quat::new(
        a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
        a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
        a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
        a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
    )
}

#[inline]
pub fn conj(a: &Quat) -> Quat {
    Quat::new(a[0], -a[1], -a[2], -a[3])
}

/// `L(a)`: `a ⊗ b = L(a) b`.
#[inline]
pub fn left(a: &Quat) -> Matrix4<f64> {
    Matrix4::new(
        a[0], -a[1], -a[2], -a[3], //
        a[1], a[0], -a[3], a[2], //
        a[2], a[3], a[0], -a[1], //
        a[3], -a[2], a[1], a[0],
    )
}

/// `R(b)`: `a ⊗ b = R(b) a`.
#[inline]
pub fn right(b: &Quat) -> Matrix4<f64> {
    Matrix4::new(
        b[0], -b[1], -b[2], -b[3], //
        b[1], b[0], b[3], -b[2], //
        b[2], -b[3], b[0], b[1], //
        b[3], b[2], -b[1], b[0],
    )
}

/// `E(Q) = [−q | w I − q̃]`, 3×4.
#[inline]
pub fn e_mat(q: &Quat) -> Matrix3x4<f64> {
    Matrix3x4::new(
        -q[1], q[0], q[3], -q[2], //
        -q[2], -q[3], q[0], q[1], //
        -q[3], q[2], -q[1], q[0],
    )
}

/// `Ê(m) = R((0, m))`, so that `E(Q)ᵀ m = Ê(m) Q`.
#[inline]
pub fn e_hat(m: &Vector3<f64>) -> Matrix4<f64> {
    right(&quat(0.0, m))
}

/// `G(s) = ½ L(s)[0; I]`, 4×3.
#[inline]
pub fn g_mat(s: &Quat) -> Matrix4x3<f64> {
    0.5 * e_mat(s).transpose()
}

/// `∂(G(s) w)/∂θ = ¼ L(s) [−wᵀ; −w̃]` (4×3), for the update `s ← s ⊗ exp(θ/2)`.
#[inline]
pub fn dg_w(s: &Quat, w: &Vector3<f64>) -> Matrix4x3<f64> {
    let mut b = Matrix4x3::zeros();
    for j in 0..3 {
        b[(0, j)] = -w[j];
    }
    let wt = crate::math::skew(w);
    for i in 0..3 {
        for j in 0..3 {
            b[(1 + i, j)] = -wt[(i, j)];
        }
    }
    left(s) * b * 0.25
}

/// `∂(G(s)ᵀ f)/∂θ = −¼ (g_w I − g̃_v)` with `g = s̄ ⊗ f` (3×3).
#[inline]
pub fn dgt_f(s: &Quat, f: &Quat) -> Matrix3<f64> {
    let g = mul(&conj(s), f);
    (crate::math::skew(&vec_part(&g)) - Matrix3::identity() * g[0]) * 0.25
}

/// Rotation matrix of the unit quaternion `q / |q|`.
#[inline]
pub fn rotation(q: &Quat) -> Matrix3<f64> {
    let n = q.norm_squared();
    let (w, x, y, z) = (q[0], q[1], q[2], q[3]);
    let s = 2.0 / n;
    Matrix3::new(
        1.0 - s * (y * y + z * z),
        s * (x * y - w * z),
        s * (x * z + w * y),
        s * (x * y + w * z),
        1.0 - s * (x * x + z * z),
        s * (y * z - w * x),
        s * (x * z - w * y),
        s * (y * z + w * x),
        1.0 - s * (x * x + y * y),
    )
}

/// Unit quaternion `[w, x, y, z]` of a samara rotation.
#[inline]
pub fn from_rotation(r: &crate::math::Rotation) -> Quat {
    let [w, x, y, z] = r.wxyz();
    Quat::new(w, x, y, z)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{Rotation, skew};

    #[test]
    fn identities() {
        let a = Quat::new(0.3, -0.5, 0.2, 0.9);
        let b = Quat::new(-0.1, 0.4, 0.7, -0.2);
        assert!((left(&a) * b - mul(&a, &b)).norm() < 1e-15);
        assert!((right(&b) * a - mul(&a, &b)).norm() < 1e-15);
        assert!((e_mat(&a) * b - vec_part(&mul(&conj(&a), &b))).norm() < 1e-15);
        assert!((e_mat(&a) * b + e_mat(&b) * a).norm() < 1e-15);
        let m = Vector3::new(0.3, 1.0, -2.0);
        assert!((e_mat(&a).transpose() * m - e_hat(&m) * a).norm() < 1e-15);
        let r = Rotation::exp(&Vector3::new(0.4, -1.2, 0.8));
        assert!((rotation(&(from_rotation(&r) * 3.0)) - r.matrix()).norm() < 1e-14);
        let _ = skew(&m);
    }

    /// `G`, `∂(Gw)/∂θ`, `∂(Gᵀf)/∂θ` against central differences of `s ⊗ exp(θ/2)`.
    #[test]
    fn derivatives_of_g() {
        let s = from_rotation(&Rotation::exp(&Vector3::new(0.4, -1.2, 0.8)));
        let w = Vector3::new(0.3, -0.7, 1.1);
        let f = Quat::new(0.2, -0.4, 0.9, 0.1);
        let eps = 1e-6;
        for j in 0..3 {
            let mut d = Vector3::zeros();
            d[j] = eps;
            let sp = from_rotation(&Rotation::exp(&d));
            let sm = from_rotation(&Rotation::exp(&(-d)));
            let (s1, s2) = (mul(&s, &sp), mul(&s, &sm));
            let ds = (s1 - s2) / (2.0 * eps);
            assert!((ds - g_mat(&s).column(j)).norm() < 1e-9);
            let dgw = (g_mat(&s1) * w - g_mat(&s2) * w) / (2.0 * eps);
            assert!((dgw - dg_w(&s, &w).column(j)).norm() < 1e-9);
            let dgf = (g_mat(&s1).transpose() * f - g_mat(&s2).transpose() * f) / (2.0 * eps);
            assert!((dgf - dgt_f(&s, &f).column(j)).norm() < 1e-9);
        }
    }
}
