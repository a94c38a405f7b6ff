//! Derived properties of a solved section: centres and principal axes from the 6×6
//! compliance and the mass integrals, in the section frame.
//!
//! - Tension (elastic) centre: where an axial force causes no bending curvature,
//!   `F[κ₂,·] θ = F[κ₃,·] θ = 0` for `θ = (N, 0, 0, 0, N z, −N y)`.
//! - Shear centre: where a shear force causes no twist (at the section where the bending
//!   moment vanishes): `z_s = F₄₂/F₄₄`, `y_s = −F₄₃/F₄₄` (1-based indices).
//! - Mass centre: `∫ρ(y, z) dA / m`.
//! - Elastic principal axes: the eigenvectors of the bending compliance (rows κ₂, κ₃)
//!   about the tension centre — a moment along one of them bends about the same axis.
//! - Inertial principal axes: those of the mass moments of inertia about the mass centre.

use super::warping::Integrals;
use nalgebra::{Matrix2, Matrix6, SymmetricEigen, Vector2};

/// Properties of a section beyond its two 6×6 matrices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Properties {
    pub area: f64,
    /// Mass per unit length [kg/m].
    pub mass: f64,
    pub mass_centre: [f64; 2],
    pub tension_centre: [f64; 2],
    pub shear_centre: [f64; 2],
    /// Angle [rad] from the y axis to the first elastic principal bending axis
    /// (in (−π/2, π/2]), and the bending stiffnesses about the two principal axes (the
    /// inverse principal compliances, other sectional forces zero) [N m²].
    pub elastic_axes_angle: f64,
    pub principal_bending: [f64; 2],
    /// Angle [rad] from the y axis to the first inertial principal axis, and the mass
    /// moments of inertia per length about the two axes through the mass centre [kg m].
    pub inertia_axes_angle: f64,
    pub principal_inertia: [f64; 2],
    /// Axial stiffness with all other forces zero, 1/F₁₁ [N].
    pub axial: f64,
    /// Torsional stiffness with all other forces zero, 1/F₄₄ (the same about any point)
    /// [N m²].
    pub torsion: f64,
    /// Shear stiffnesses with all other forces zero, 1/F₂₂ and 1/F₃₃ [N].
    pub shear: [f64; 2],
}

/// `T_c` with `ψ_c = T_c ψ_o`: the strains of a line at offset c = (y, z) from those of the
/// reference line (`ε + κ × c`).
pub fn offset_transform(c: [f64; 2]) -> Matrix6<f64> {
    let mut t = Matrix6::identity();
    // −c̃ with c = (0, y, z): rows ε, columns κ.
    let (y, z) = (c[0], c[1]);
    t[(0, 4)] = z;
    t[(0, 5)] = -y;
    t[(1, 3)] = -z;
    t[(2, 3)] = y;
    t
}

/// Principal directions of a symmetric 2×2 matrix: the angle of the eigenvector closest
/// to the y axis, and the two eigenvalues in that order (angle 0 when they are equal).
fn principal(m: &Matrix2<f64>) -> (f64, [f64; 2]) {
    let eig = SymmetricEigen::new(*m);
    let (a, b) = (eig.eigenvalues[0], eig.eigenvalues[1]);
    if (a - b).abs() <= 1e-9 * a.abs().max(b.abs()) {
        // Every direction is principal: keep the section axes.
        return (0.0, [m[(0, 0)], m[(1, 1)]]);
    }
    let v0: Vector2<f64> = eig.eigenvectors.column(0).into();
    let v1: Vector2<f64> = eig.eigenvectors.column(1).into();
    let (first, l0, l1) = if v0[0].abs() >= v1[0].abs() {
        (v0, eig.eigenvalues[0], eig.eigenvalues[1])
    } else {
        (v1, eig.eigenvalues[1], eig.eigenvalues[0])
    };
    let mut angle = first[1].atan2(first[0]);
    if angle > std::f64::consts::FRAC_PI_2 {
        angle -= std::f64::consts::PI;
    } else if angle <= -std::f64::consts::FRAC_PI_2 {
        angle += std::f64::consts::PI;
    }
    (angle, [l0, l1])
}

/// Centres and principal axes from the compliance and the integrals.
pub fn properties(f: &Matrix6<f64>, s: &Integrals) -> Properties {
    // Tension centre: [−F₅₆ F₅₅; −F₆₆ F₆₅] [y; z] = [−F₅₁; −F₆₁] (1-based).
    let a = Matrix2::new(-f[(4, 5)], f[(4, 4)], -f[(5, 5)], f[(5, 4)]);
    let tc = a
        .try_inverse()
        .map(|ai| ai * Vector2::new(-f[(4, 0)], -f[(5, 0)]))
        .unwrap_or_else(Vector2::zeros);
    let sc = [-f[(3, 2)] / f[(3, 3)], f[(3, 1)] / f[(3, 3)]];
    let mc = if s.mass > 0.0 {
        [s.mass_moment[0] / s.mass, s.mass_moment[1] / s.mass]
    } else {
        [0.0, 0.0]
    };
    // Compliance about the tension centre: F_c = T_c F T_cᵀ (θ_o = T_cᵀ θ_c).
    let t = offset_transform([tc[0], tc[1]]);
    let fc = t * f * t.transpose();
    let fb = Matrix2::new(fc[(4, 4)], fc[(4, 5)], fc[(5, 4)], fc[(5, 5)]);
    let (ea, comp) = principal(&fb);
    // Mass moments about the mass centre (components about y and z axes).
    let m = s.mass;
    let iyy = s.mass_second[0] - m * mc[0] * mc[0];
    let izz = s.mass_second[1] - m * mc[1] * mc[1];
    let iyz = s.mass_second[2] - m * mc[0] * mc[1];
    // Inertia about the y axis is ∫ρ z², about z ∫ρ y², product −∫ρ y z.
    let (ia, inertia) = principal(&Matrix2::new(izz, -iyz, -iyz, iyy));
    Properties {
        area: s.area,
        mass: m,
        mass_centre: mc,
        tension_centre: [tc[0], tc[1]],
        shear_centre: sc,
        elastic_axes_angle: ea,
        principal_bending: [1.0 / comp[0], 1.0 / comp[1]],
        inertia_axes_angle: ia,
        principal_inertia: inertia,
        axial: 1.0 / f[(0, 0)],
        torsion: 1.0 / f[(3, 3)],
        shear: [1.0 / f[(1, 1)], 1.0 / f[(2, 2)]],
    }
}
