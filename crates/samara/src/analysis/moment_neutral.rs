//! The projection that makes the energy-decaying scheme's translational dissipation
//! moment-free (docs/integrators.md, "The decaying scheme").
//!
//! The scheme's kinematics `Δx_i/h = v̄_i + c δ_i` change the angular momentum by
//! `Σ Δx_i × m_i v̄_i = c h Σ m_i δ_i × v̄_i = c Σ m_i δ_i × Δx_i` (with `v̄_i = Δx_i/h −
//! c δ_i`). The dissipation δ is therefore taken in the subspace
//!
//! ```text
//! K = { δ : C δ = Σ_i m_i δ_i × Δx_i = 0 }
//! ```
//!
//! by the M-orthogonal projector onto it (M: the nodes' translational masses),
//!
//! ```text
//! P δ = δ − M⁻¹Cᵀ (C M⁻¹ Cᵀ)⁺ C δ,   (M⁻¹Cᵀ z)_i = Δx_i × z,
//! C M⁻¹ Cᵀ = I_Δ = Σ_i m_i (|Δx_i|² I − Δx_i Δx_iᵀ),
//! ```
//!
//! i.e. `(P δ)_i = δ_i − Δx_i × z` with `z = I_Δ⁺ Σ_j m_j δ_j × Δx_j`: the rigid
//! "rotations" of the increments are removed from δ, as the rigid motions are from a
//! discrete gradient (Gonzalez 1996). P is idempotent, `MP` is symmetric and `‖Pb‖_M ≤
//! ‖b‖_M`, which is all the energy statement needs; `C P δ = 0` makes the kinematics
//! add no angular momentum, and P depends on the directions of the increments only
//! (`Δx → αΔx` leaves it unchanged), so it is smooth along a motion and the dissipation
//! stays a second difference. Nodes without mass are left alone (the choice of `M⁻¹Cᵀ` on
//! them does not matter: they carry neither energy nor momentum). The pseudo-inverse
//! drops the eigen-directions of I_Δ below `1e-12` of its largest eigenvalue (exact
//! zeros: a single node, collinear increments); what that leaves of `C δ` is bounded by
//! `√λ ‖δ‖_M` (Cauchy–Schwarz), 1e-6 of the dissipation's moment at most.

use nalgebra::{Matrix3, SymmetricEigen, Vector3};

/// `I_Δ⁺`: the pseudo-inverse of `Σ m_i (|Δx_i|² I − Δx_i Δx_iᵀ)` (zero when every
/// increment of a massive node vanishes: then P is the identity).
pub fn increment_inertia_pinv(masses: &[f64], dx: impl Fn(usize) -> Vector3<f64>) -> Matrix3<f64> {
    let mut inertia = Matrix3::zeros();
    for (i, &m) in masses.iter().enumerate() {
        if m > 0.0 {
            let d = dx(i);
            inertia += (Matrix3::identity() * d.norm_squared() - d * d.transpose()) * m;
        }
    }
    let eig = SymmetricEigen::new(inertia);
    let top = eig.eigenvalues.max();
    let mut pinv = Matrix3::zeros();
    if !(top > 0.0 && top.is_finite()) {
        return pinv;
    }
    for k in 0..3 {
        let l = eig.eigenvalues[k];
        if l > 1e-12 * top {
            let u = eig.eigenvectors.column(k);
            pinv += u * u.transpose() / l;
        }
    }
    pinv
}

/// `z = I_Δ⁺ Σ_j m_j δ_j × Δx_j`: the rotation that `P` removes from δ
/// (`(Pδ)_i = δ_i − Δx_i × z`).
pub fn removed_rotation(
    masses: &[f64],
    pinv: &Matrix3<f64>,
    dx: impl Fn(usize) -> Vector3<f64>,
    delta: impl Fn(usize) -> Vector3<f64>,
) -> Vector3<f64> {
    let mut moment = Vector3::zeros();
    for (i, &m) in masses.iter().enumerate() {
        if m > 0.0 {
            moment += delta(i).cross(&dx(i)) * m;
        }
    }
    pinv * moment
}

/// `(Pδ)_i` for node `i` of mass `m`, increment `dx`, given the removed rotation `z`.
#[inline]
pub fn project(m: f64, dx: &Vector3<f64>, delta: &Vector3<f64>, z: &Vector3<f64>) -> Vector3<f64> {
    if m > 0.0 { delta - dx.cross(z) } else { *delta }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic spread of values in [−1, 1].
    fn val(k: usize) -> f64 {
        ((k as f64 * 0.754_877_666).fract() * 2.0) - 1.0
    }

    /// Masses (node 2 massless), increments and two fields δ.
    type Fields = (
        Vec<f64>,
        Vec<Vector3<f64>>,
        Vec<Vector3<f64>>,
        Vec<Vector3<f64>>,
    );

    fn setup(n: usize) -> Fields {
        let masses: Vec<f64> = (0..n)
            .map(|i| if i == 2 { 0.0 } else { 1.0 + val(i).abs() })
            .collect();
        let v = |o: usize| -> Vec<Vector3<f64>> {
            (0..n)
                .map(|i| Vector3::new(val(o + 3 * i), val(o + 3 * i + 1), val(o + 3 * i + 2)))
                .collect()
        };
        (masses, v(1), v(100), v(200))
    }

    fn apply(masses: &[f64], dx: &[Vector3<f64>], d: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
        let pinv = increment_inertia_pinv(masses, |i| dx[i]);
        let z = removed_rotation(masses, &pinv, |i| dx[i], |i| d[i]);
        (0..masses.len())
            .map(|i| project(masses[i], &dx[i], &d[i], &z))
            .collect()
    }

    fn dot_m(masses: &[f64], a: &[Vector3<f64>], b: &[Vector3<f64>]) -> f64 {
        (0..masses.len()).map(|i| masses[i] * a[i].dot(&b[i])).sum()
    }

    /// The properties the scheme's statements rest on, to round-off: `C P δ = 0`,
    /// `P² = P`, `⟨a, P b⟩_M = ⟨P a, b⟩_M`, and invariance under scaling of the increments.
    #[test]
    fn projector_is_m_orthogonal_and_moment_free() {
        let (masses, dx, a, b) = setup(7);
        let pa = apply(&masses, &dx, &a);
        let pb = apply(&masses, &dx, &b);
        let moment: Vector3<f64> = (0..7).map(|i| pa[i].cross(&dx[i]) * masses[i]).sum();
        assert!(moment.norm() < 1e-14, "{moment}");
        let ppa = apply(&masses, &dx, &pa);
        let idem = (0..7).map(|i| (ppa[i] - pa[i]).norm()).fold(0.0, f64::max);
        assert!(idem < 1e-14, "{idem:e}");
        let sym = dot_m(&masses, &a, &pb) - dot_m(&masses, &pa, &b);
        assert!(sym.abs() < 1e-14, "{sym:e}");
        assert!(dot_m(&masses, &pb, &pb) <= dot_m(&masses, &b, &b));
        let scaled: Vec<_> = dx.iter().map(|d| d * 1e-7).collect();
        let pa2 = apply(&masses, &scaled, &a);
        let diff = (0..7).map(|i| (pa2[i] - pa[i]).norm()).fold(0.0, f64::max);
        assert!(diff < 1e-12, "{diff:e}");
        // The massless node is left alone.
        assert_eq!(pa[2], a[2]);
    }

    /// A single node: only the component of δ along the increment is kept; collinear
    /// increments of several nodes likewise (I_Δ singular along them).
    #[test]
    fn single_node_keeps_the_component_along_its_increment() {
        let dx = [Vector3::new(0.3, -0.4, 1.2)];
        let d = [Vector3::new(1.0, 2.0, -0.5)];
        let p = apply(&[2.0], &dx, &d);
        let along = dx[0] * (d[0].dot(&dx[0]) / dx[0].norm_squared());
        assert!((p[0] - along).norm() < 1e-15, "{} vs {along}", p[0]);
        let dx2 = [dx[0], dx[0] * -2.0];
        let d2 = [d[0], Vector3::new(0.1, 0.0, 0.7)];
        let p2 = apply(&[1.0, 3.0], &dx2, &d2);
        let moment: Vector3<f64> = p2[0].cross(&dx2[0]) + p2[1].cross(&dx2[1]) * 3.0;
        assert!(moment.norm() < 1e-14, "{moment}");
        // At rest (no increments) P is the identity.
        let p0 = apply(&[1.0], &[Vector3::zeros()], &d);
        assert_eq!(p0[0], d[0]);
    }
}
