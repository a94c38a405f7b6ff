//! The Cayley map of SO(3), the rotation update of the energy-consistent integrators
//! (Simo & Wong 1991; Lewis & Simo 1994):
//!
//! ```text
//! cay(ψ) = (I − ψ̃/2)⁻¹ (I + ψ̃/2),    quaternion ∝ (1, ψ/2)
//! cay(ψ)ᵀ δcay(ψ) = (T_c(ψ) δψ)~,     T_c(ψ) = (I − ψ̃/2) / (1 + |ψ|²/4)
//! ```
//!
//! Its useful identities: `cay(ψ) − I = (I − ψ̃/2)⁻¹ ψ̃`, `(I + cay(ψ))/2 = (I − ψ̃/2)⁻¹`,
//! so for a body point s the step `R₁s − R₀s = R₀ (I − ψ̃/2)⁻¹ (ψ × s)` and the mean arm
//! `(R₀s + R₁s)/2 = R₀ (I − ψ̃/2)⁻¹ s`.

use super::skew;
use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};

/// `cay(ψ)` as a unit quaternion.
pub fn cayley(psi: &Vector3<f64>) -> UnitQuaternion<f64> {
    UnitQuaternion::new_normalize(Quaternion::new(1.0, 0.5 * psi.x, 0.5 * psi.y, 0.5 * psi.z))
}

/// Left-trivialized tangent `T_c(ψ) = (I − ψ̃/2)/(1 + |ψ|²/4)`: `δ(R₀ cay(ψ)) = R₀ cay(ψ) (T_c δψ)~`.
pub fn cayley_tangent(psi: &Vector3<f64>) -> Matrix3<f64> {
    (Matrix3::identity() - skew(psi) * 0.5) / (1.0 + 0.25 * psi.norm_squared())
}

/// `(I − ψ̃/2)⁻¹ a`: closed form `a + (ψ̃a/2 + ψ̃ψ̃a/4)/(1 + |ψ|²/4)`.
pub fn cayley_half_inverse(psi: &Vector3<f64>, a: &Vector3<f64>) -> Vector3<f64> {
    let pa = psi.cross(a) * 0.5;
    let ppa = psi.cross(&pa) * 0.5;
    a + (pa + ppa) / (1.0 + 0.25 * psi.norm_squared())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Rotation;

    #[test]
    fn cayley_matches_its_matrix_form_and_tangent() {
        let psi = Vector3::new(0.3, -0.7, 0.45);
        let s = skew(&psi) * 0.5;
        let c = (Matrix3::identity() - s).try_inverse().unwrap() * (Matrix3::identity() + s);
        let q = cayley(&psi).to_rotation_matrix().into_inner();
        assert!((c - q).norm() < 1e-14);
        // (I − ψ̃/2)⁻¹ a against the matrix inverse.
        let a = Vector3::new(0.2, 0.1, -1.3);
        let inv = (Matrix3::identity() - s).try_inverse().unwrap() * a;
        assert!((inv - cayley_half_inverse(&psi, &a)).norm() < 1e-14);
        // Tangent: central differences of cay(ψ)ᵀ cay(ψ + ε e_k), axial part.
        let t = cayley_tangent(&psi);
        let r0 = Rotation::from_quaternion(cayley(&psi));
        for k in 0..3 {
            let mut d = Vector3::zeros();
            d[k] = 1e-6;
            let rp = Rotation::from_quaternion(cayley(&(psi + d)));
            let rm = Rotation::from_quaternion(cayley(&(psi - d)));
            let num = (r0.relative_log(&rp) - r0.relative_log(&rm)) / 2e-6;
            assert!(
                (num - t.column(k)).norm() < 1e-8,
                "column {k}: {num} vs {}",
                t.column(k)
            );
        }
    }
}
