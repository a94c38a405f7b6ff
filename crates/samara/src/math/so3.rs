//! The rotation group SO(3): exponential and logarithmic maps, the tangent operator and
//! its inverse, and unit-quaternion storage.
//!
//! # Conventions (used everywhere in samara)
//! - A node's orientation `R` maps node-frame (material) components to global ones:
//!   `a_global = R a_node`.
//! - Angular velocity is **material**: `Ṙ = R Ω̃`, with `Ω` in node-frame components.
//!   Results files convert it to global components, `ω = R Ω`.
//! - Rotation increments are material (right) increments: `R ← R exp(θ̃)`.
//! - Quaternions are stored as `(w, x, y, z)`, unit norm.
//!
//! The tangent operator `T(ψ)` is the right Jacobian of the exponential map,
//! `exp(ψ + δψ) = exp(ψ) exp(T(ψ) δψ) + O(δψ²)` (Brüls, Cardona & Arnold 2012, eq. 12):
//!
//! `T(ψ) = I − (1 − cos ψ)/ψ² ψ̃ + (ψ − sin ψ)/ψ³ ψ̃²`.
//!
//! Every coefficient switches to its Taylor series for small `ψ`, so all maps are accurate
//! to machine precision near `ψ → 0`; the logarithm works on the quaternion with `atan2`,
//! so it stays accurate up to and including `ψ = π`.

use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};

/// Below this angle the trigonometric coefficients use their Taylor series.
const SMALL_ANGLE: f64 = 1e-3;

/// Skew-symmetric matrix `ṽ` such that `ṽ a = v × a`.
#[inline]
pub fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

/// `sin(ψ)/ψ`, accurate for all ψ ≥ 0.
fn sinc(psi: f64) -> f64 {
    if psi < SMALL_ANGLE {
        let p2 = psi * psi;
        1.0 - p2 / 6.0 * (1.0 - p2 / 20.0)
    } else {
        psi.sin() / psi
    }
}

/// `(1 − cos ψ)/ψ²`, as `½ (sin(ψ/2)/(ψ/2))²`: no cancellation at any ψ.
fn coef_a(psi: f64) -> f64 {
    let s = sinc(0.5 * psi);
    0.5 * s * s
}

/// Below this angle `coef_b` and `coef_inv` use their Taylor series (to ψ¹⁴, truncation
/// < 1e-17); above, the closed forms lose at most ~25ε to cancellation.
const SERIES_ANGLE: f64 = 0.7;

/// `(ψ − sin ψ)/ψ³`.
fn coef_b(psi: f64) -> f64 {
    if psi < SERIES_ANGLE {
        // Σ (−1)ⁿ ψ²ⁿ/(2n+3)!, Horner in ψ².
        let p2 = psi * psi;
        let mut acc = 0.0;
        for n in (0..=7).rev() {
            let sign = if n % 2 == 0 { 1.0 } else { -1.0 };
            acc = acc * p2 + sign / FACTORIAL_ODD[n];
        }
        acc
    } else {
        (psi - psi.sin()) / (psi * psi * psi)
    }
}

/// (2n+3)! for n = 0…7.
const FACTORIAL_ODD: [f64; 8] = [
    6.0,
    120.0,
    5040.0,
    362880.0,
    39916800.0,
    6227020800.0,
    1307674368000.0,
    355687428096000.0,
];

/// Taylor coefficients of `coef_inv` in ψ²: −(−1)ⁿ B₂ₙ/(2n)!, n = 1…8 (B: Bernoulli numbers).
const COEF_INV_SERIES: [f64; 8] = [
    1.0 / 12.0,
    1.0 / 720.0,
    1.0 / 30240.0,
    1.0 / 1209600.0,
    1.0 / 47900160.0,
    691.0 / 1307674368000.0,
    1.0 / 74724249600.0,
    3617.0 / 10670622842880000.0,
];

/// `(1 − (ψ/2) cot(ψ/2))/ψ²`, the coefficient of ψ̃² in `T⁻¹`.
fn coef_inv(psi: f64) -> f64 {
    if psi < SERIES_ANGLE {
        let p2 = psi * psi;
        COEF_INV_SERIES
            .iter()
            .rev()
            .fold(0.0, |acc, c| acc * p2 + c)
    } else {
        let h = 0.5 * psi;
        (1.0 - h * h.cos() / h.sin()) / (psi * psi)
    }
}

/// Below this |ψ|² the exponential map takes cos(ψ/2) and sin(ψ/2)/(ψ/2) from their
/// Taylor series in (ψ/2)² (|ψ| < 0.2: the increments of a time step). Truncated after
/// the (ψ/2)¹⁰ term, the first omitted terms are below (0.1)¹²/12! ≈ 2·10⁻²¹, far below
/// the rounding of the sum.
const EXP_SERIES_LIMIT: f64 = 0.04;

/// Exponential map `exp(ψ̃)` as a unit quaternion: `(cos(ψ/2), sin(ψ/2) ψ/ψ)`. Small
/// rotations (below [`EXP_SERIES_LIMIT`]) need neither the square root nor the
/// trigonometric functions.
#[inline(always)]
pub fn exp_map(psi: &Vector3<f64>) -> UnitQuaternion<f64> {
    let p2 = psi.norm_squared();
    let (c, s) = if p2 < EXP_SERIES_LIMIT {
        let x = 0.25 * p2;
        // cos h = Σ (−x)ᵏ/(2k)!, sin h/h = Σ (−x)ᵏ/(2k + 1)!, x = h².
        let c = 1.0
            + x * (-1.0 / 2.0
                + x * (1.0 / 24.0
                    + x * (-1.0 / 720.0 + x * (1.0 / 40_320.0 + x * (-1.0 / 3_628_800.0)))));
        let sc = 1.0
            + x * (-1.0 / 6.0
                + x * (1.0 / 120.0
                    + x * (-1.0 / 5040.0 + x * (1.0 / 362_880.0 + x * (-1.0 / 39_916_800.0)))));
        (c, 0.5 * sc)
    } else {
        let half = 0.5 * p2.sqrt();
        (half.cos(), 0.5 * sinc(half))
    };
    UnitQuaternion::new_unchecked(Quaternion::new(c, s * psi.x, s * psi.y, s * psi.z))
}

/// Logarithmic map: the rotation vector ψ with `|ψ| ≤ π` such that `exp(ψ̃) = R(q)`.
pub fn log_map(q: &UnitQuaternion<f64>) -> Vector3<f64> {
    let q = q.quaternion();
    // q and −q are the same rotation; take w ≥ 0 so that |ψ| ≤ π.
    let (w, v) = if q.w < 0.0 {
        (-q.w, -q.imag())
    } else {
        (q.w, q.imag())
    };
    let n = v.norm();
    let angle = 2.0 * n.atan2(w);
    // ψ = angle · v/n, with angle/n = 2/w (1 − n²/(3w²) + …) for small n.
    let factor = if n < 1e-8 {
        2.0 / w * (1.0 - n * n / (3.0 * w * w))
    } else {
        angle / n
    };
    v * factor
}

/// Tangent operator `T(ψ)` (right Jacobian of the exponential map).
#[inline]
pub fn tangent_operator(psi: &Vector3<f64>) -> Matrix3<f64> {
    let angle = psi.norm();
    let p = skew(psi);
    Matrix3::identity() - p * coef_a(angle) + p * p * coef_b(angle)
}

/// Inverse tangent operator `T⁻¹(ψ) = I + ½ψ̃ + (1 − (ψ/2)cot(ψ/2))/ψ² ψ̃²`, valid for `|ψ| < 2π`.
pub fn tangent_inverse(psi: &Vector3<f64>) -> Matrix3<f64> {
    let angle = psi.norm();
    let p = skew(psi);
    Matrix3::identity() + p * 0.5 + p * p * coef_inv(angle)
}

/// Unit quaternion of a rotation matrix (Shepperd's method: the largest of the four
/// candidate pivots is used, so it is accurate for every rotation).
pub fn quaternion_from_matrix(r: &Matrix3<f64>) -> UnitQuaternion<f64> {
    let tr = r.trace();
    let cands = [tr, r[(0, 0)], r[(1, 1)], r[(2, 2)]];
    let mut k = 0;
    for i in 1..4 {
        if cands[i] > cands[k] {
            k = i;
        }
    }
    let q = match k {
        0 => {
            let s = 2.0 * (1.0 + tr).sqrt();
            Quaternion::new(
                0.25 * s,
                (r[(2, 1)] - r[(1, 2)]) / s,
                (r[(0, 2)] - r[(2, 0)]) / s,
                (r[(1, 0)] - r[(0, 1)]) / s,
            )
        }
        1 => {
            let s = 2.0 * (1.0 + r[(0, 0)] - r[(1, 1)] - r[(2, 2)]).sqrt();
            Quaternion::new(
                (r[(2, 1)] - r[(1, 2)]) / s,
                0.25 * s,
                (r[(0, 1)] + r[(1, 0)]) / s,
                (r[(0, 2)] + r[(2, 0)]) / s,
            )
        }
        2 => {
            let s = 2.0 * (1.0 - r[(0, 0)] + r[(1, 1)] - r[(2, 2)]).sqrt();
            Quaternion::new(
                (r[(0, 2)] - r[(2, 0)]) / s,
                (r[(0, 1)] + r[(1, 0)]) / s,
                0.25 * s,
                (r[(1, 2)] + r[(2, 1)]) / s,
            )
        }
        _ => {
            let s = 2.0 * (1.0 - r[(0, 0)] - r[(1, 1)] + r[(2, 2)]).sqrt();
            Quaternion::new(
                (r[(1, 0)] - r[(0, 1)]) / s,
                (r[(0, 2)] + r[(2, 0)]) / s,
                (r[(1, 2)] + r[(2, 1)]) / s,
                0.25 * s,
            )
        }
    };
    let q = if q.w < 0.0 { -q } else { q };
    UnitQuaternion::new_normalize(q)
}

/// An orientation stored as a unit quaternion together with its rotation matrix.
///
/// The matrix is recomputed whenever the quaternion changes, so kernels can use either
/// without paying for the conversion again.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rotation {
    q: UnitQuaternion<f64>,
    m: Matrix3<f64>,
}

impl Default for Rotation {
    fn default() -> Self {
        Self::identity()
    }
}

impl Rotation {
    pub fn identity() -> Self {
        Self {
            q: UnitQuaternion::identity(),
            m: Matrix3::identity(),
        }
    }

    #[inline(always)]
    pub fn from_quaternion(q: UnitQuaternion<f64>) -> Self {
        // Renormalize to keep |q| = 1 to machine precision over millions of updates.
        let q = UnitQuaternion::new_normalize(q.into_inner());
        Self {
            m: q.to_rotation_matrix().into_inner(),
            q,
        }
    }

    pub fn from_matrix(m: &Matrix3<f64>) -> Self {
        Self::from_quaternion(quaternion_from_matrix(m))
    }

    /// `exp(ψ̃)`.
    pub fn exp(psi: &Vector3<f64>) -> Self {
        Self::from_quaternion(exp_map(psi))
    }

    #[inline]
    pub fn quaternion(&self) -> &UnitQuaternion<f64> {
        &self.q
    }

    #[inline]
    pub fn matrix(&self) -> &Matrix3<f64> {
        &self.m
    }

    /// Material (right) update `R exp(ψ̃)` (always inlined: the configuration update's
    /// AVX copy takes it in).
    #[inline(always)]
    pub fn compose_exp(&self, psi: &Vector3<f64>) -> Self {
        Self::from_quaternion(self.q * exp_map(psi))
    }

    /// `R₁ R₂`.
    pub fn compose(&self, other: &Rotation) -> Self {
        Self::from_quaternion(self.q * other.q)
    }

    pub fn inverse(&self) -> Self {
        Self {
            q: self.q.inverse(),
            m: self.m.transpose(),
        }
    }

    /// The material rotation vector from `self` to `other`: `log(Rᵀ R_other)`.
    pub fn relative_log(&self, other: &Rotation) -> Vector3<f64> {
        log_map(&(self.q.inverse() * other.q))
    }

    /// Quaternion components `(w, x, y, z)`.
    pub fn wxyz(&self) -> [f64; 4] {
        let q = self.q.quaternion();
        [q.w, q.i, q.j, q.k]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rodrigues(psi: &Vector3<f64>) -> Matrix3<f64> {
        // Reference: textbook Rodrigues formula, only used away from ψ = 0.
        let a = psi.norm();
        let k = skew(&(psi / a));
        Matrix3::identity() + k * a.sin() + k * k * (1.0 - a.cos())
    }

    /// The series branch of the exponential map against the trigonometric one
    /// (`(cos h, sin h/h)` from libm) on both sides of its limit: equal to a few ulps
    /// (4e-16), the rounding of the two evaluations.
    #[test]
    fn exp_series_matches_trigonometric_form() {
        for &angle in &[
            1e-9, 1e-4, 1e-3, 0.01, 0.05, 0.1, 0.15, 0.199_999, 0.2, 0.25,
        ] {
            for dir in [
                Vector3::new(1.0, 0.0, 0.0),
                Vector3::new(0.3, -0.5, 0.8).normalize(),
            ] {
                let psi = dir * angle;
                let q = exp_map(&psi);
                let h: f64 = 0.5 * angle;
                let (c, s) = (h.cos(), 0.5 * h.sin() / h);
                let want = [c, s * psi.x, s * psi.y, s * psi.z];
                let got = [q.w, q.i, q.j, q.k];
                for (g, w) in got.iter().zip(want) {
                    assert!(
                        (g - w).abs() <= 4e-16 * w.abs().max(1e-300) + 1e-300,
                        "|ψ| = {angle}: {g} against {w}"
                    );
                }
            }
        }
    }

    #[test]
    fn exp_matches_rodrigues_for_finite_angles() {
        for psi in [
            Vector3::new(0.3, -0.2, 0.9),
            Vector3::new(2.0, 1.0, -0.5),
            Vector3::new(0.0, 0.0, std::f64::consts::PI),
        ] {
            let r = exp_map(&psi).to_rotation_matrix().into_inner();
            assert!((r - rodrigues(&psi)).norm() < 1e-14, "{psi}");
        }
    }

    #[test]
    fn log_inverts_exp_near_zero_and_near_pi() {
        // Near ψ → 0 the naive formula divides 0/0; near π the matrix-trace formula loses
        // all digits. Relative error of the round trip is required at 1e-13 (a few ulps
        // times the conditioning of atan2, which is 1 here).
        let dirs = [
            Vector3::new(1.0, 2.0, -0.5).normalize(),
            Vector3::new(0.0, 0.0, 1.0),
            Vector3::new(-0.3, 0.1, 0.9).normalize(),
        ];
        for d in dirs {
            for angle in [
                1e-12,
                1e-8,
                1e-4,
                1e-2,
                0.5,
                2.0,
                std::f64::consts::PI - 1e-6,
                std::f64::consts::PI - 1e-10,
            ] {
                let psi = d * angle;
                let back = log_map(&exp_map(&psi));
                let err = (back - psi).norm() / angle;
                assert!(
                    err < 1e-13 * (1.0 + 1e-10 / (std::f64::consts::PI - angle).max(1e-16)),
                    "angle {angle}: rel err {err}"
                );
            }
        }
        // Exactly π: either ±ψ is correct.
        let psi = Vector3::new(0.0, std::f64::consts::PI, 0.0);
        let back = log_map(&exp_map(&psi));
        assert!((back.norm() - std::f64::consts::PI).abs() < 1e-14);
        assert!(back.x.abs() < 1e-14 && back.z.abs() < 1e-14);
    }

    #[test]
    fn matrix_quaternion_round_trip_all_branches() {
        for psi in [
            Vector3::new(0.1, 0.2, 0.3),
            Vector3::new(3.1, 0.0, 0.1),
            Vector3::new(0.0, 3.1, 0.1),
            Vector3::new(0.1, 0.0, 3.1),
        ] {
            let r = exp_map(&psi).to_rotation_matrix().into_inner();
            let q = quaternion_from_matrix(&r);
            assert!((q.to_rotation_matrix().into_inner() - r).norm() < 1e-14);
        }
    }

    /// `exp(ψ + εδ) ≈ exp(ψ) exp(ε T(ψ) δ)`: central differences of `log(exp(ψ)ᵀ exp(ψ+εδ))`
    /// have truncation error O(ε²) ≈ 1e-12 and roundoff ≈ 1e-16/ε ≈ 1e-10 at ε = 1e-6.
    #[test]
    fn tangent_operator_is_the_right_jacobian() {
        for psi in [
            Vector3::new(1e-9, -2e-9, 0.0),
            Vector3::new(1e-4, 2e-4, -1e-4),
            Vector3::new(0.4, -1.1, 0.7),
            Vector3::new(2.5, 0.3, -1.0),
        ] {
            let t = tangent_operator(&psi);
            let base = exp_map(&psi);
            let eps = 1e-6;
            for j in 0..3 {
                let mut d = Vector3::zeros();
                d[j] = eps;
                let plus = log_map(&(base.inverse() * exp_map(&(psi + d))));
                let minus = log_map(&(base.inverse() * exp_map(&(psi - d))));
                let col = (plus - minus) / (2.0 * eps);
                assert!((col - t.column(j)).norm() < 1e-8, "psi {psi} col {j}");
            }
            let ti = tangent_inverse(&psi);
            assert!((t * ti - Matrix3::identity()).norm() < 1e-13);
        }
    }

    #[test]
    fn series_and_closed_forms_agree_at_the_switch() {
        for (switch, fs) in [
            (SMALL_ANGLE, &[sinc, coef_a][..]),
            (SERIES_ANGLE, &[coef_b, coef_inv][..]),
        ] {
            let (below, above) = (switch.next_down(), switch);
            for f in fs {
                let (a, b) = (f(below), f(above));
                // The closed forms lose ε/(1 − (ψ/2)cot(ψ/2)) ≈ 25ε to cancellation at 0.7.
                assert!((a - b).abs() < 1e-14 * a.abs(), "{a} vs {b} at {switch}");
            }
        }
    }

    #[test]
    fn rotation_composition() {
        let a = Rotation::exp(&Vector3::new(0.2, 0.1, -0.3));
        let d = Vector3::new(-0.05, 0.3, 0.2);
        let b = a.compose_exp(&d);
        assert!((a.relative_log(&b) - d).norm() < 1e-14);
        assert!(
            (b.matrix() - a.matrix() * exp_map(&d).to_rotation_matrix().into_inner()).norm()
                < 1e-14
        );
        assert!((a.inverse().compose(&a).matrix() - Matrix3::identity()).norm() < 1e-15);
    }
}
