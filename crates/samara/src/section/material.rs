//! Elastic materials of a cross-section and their rotation into the section frame.
//!
//! Voigt ordering everywhere: `[11, 22, 33, 23, 13, 12]` with engineering shear strains
//! (γ = 2ε). In material axes, axis 1 is the fibre direction; an orthotropic material has
//! the compliance
//!
//! ```text
//! S = [[ 1/E1,   −ν21/E2, −ν31/E3, 0, 0, 0 ],
//!      [−ν12/E1,  1/E2,   −ν32/E3, 0, 0, 0 ],
//!      [−ν13/E1, −ν23/E2,  1/E3,   0, 0, 0 ],
//!      [0, 0, 0, 1/G23, 0, 0], [0, 0, 0, 0, 1/G13, 0], [0, 0, 0, 0, 0, 1/G12]]
//! ```
//!
//! (symmetric: ν21/E2 = ν12/E1, …) and `Q = S⁻¹`. A material is usable only if Q is
//! symmetric positive definite (positive strain energy for every strain).
//!
//! The orientation of an element's material axes in the section frame (x along the beam,
//! y and z in the section plane) is given by two angles, as in BECAS: first the *wall
//! angle* φ turns the frame about x (material axis 2 goes to the wall's contour direction
//! t = (0, cos φ, sin φ), axis 3 to the wall normal n = x × t), then the *ply angle* θ
//! turns it about n (the fibre goes from x towards t):
//! `a₁ = cos θ x + sin θ t`, `a₂ = −sin θ x + cos θ t`, `a₃ = n`.

use nalgebra::{Matrix3, Matrix6, SymmetricEigen};

/// A homogeneous elastic material: stiffness in its own axes and density.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    /// Stiffness `σ = Q ε` in material axes, Voigt `[11, 22, 33, 23, 13, 12]`.
    pub stiffness: Matrix6<f64>,
    /// Density [kg/m³].
    pub density: f64,
}

/// Engineering constants of an orthotropic material (axis 1 the fibre direction).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orthotropic {
    pub e1: f64,
    pub e2: f64,
    pub e3: f64,
    pub g12: f64,
    pub g13: f64,
    pub g23: f64,
    pub nu12: f64,
    pub nu13: f64,
    pub nu23: f64,
}

impl Material {
    /// Isotropic material from Young's modulus and Poisson's ratio.
    pub fn isotropic(name: &str, e: f64, nu: f64, density: f64) -> Result<Self, String> {
        let g = e / (2.0 * (1.0 + nu));
        Self::orthotropic(
            name,
            &Orthotropic {
                e1: e,
                e2: e,
                e3: e,
                g12: g,
                g13: g,
                g23: g,
                nu12: nu,
                nu13: nu,
                nu23: nu,
            },
            density,
        )
    }

    /// Orthotropic material from its nine engineering constants.
    pub fn orthotropic(name: &str, c: &Orthotropic, density: f64) -> Result<Self, String> {
        let v = [
            c.e1, c.e2, c.e3, c.g12, c.g13, c.g23, c.nu12, c.nu13, c.nu23,
        ];
        if !v.iter().all(|x| x.is_finite()) {
            return Err("the engineering constants must be finite numbers".into());
        }
        if [c.e1, c.e2, c.e3, c.g12, c.g13, c.g23]
            .iter()
            .any(|x| *x <= 0.0)
        {
            return Err("the moduli E1, E2, E3, G12, G13, G23 must be positive".into());
        }
        let mut s = Matrix6::zeros();
        s[(0, 0)] = 1.0 / c.e1;
        s[(1, 1)] = 1.0 / c.e2;
        s[(2, 2)] = 1.0 / c.e3;
        s[(0, 1)] = -c.nu12 / c.e1;
        s[(1, 0)] = s[(0, 1)];
        s[(0, 2)] = -c.nu13 / c.e1;
        s[(2, 0)] = s[(0, 2)];
        s[(1, 2)] = -c.nu23 / c.e2;
        s[(2, 1)] = s[(1, 2)];
        s[(3, 3)] = 1.0 / c.g23;
        s[(4, 4)] = 1.0 / c.g13;
        s[(5, 5)] = 1.0 / c.g12;
        check_positive_definite(&s).map_err(|min| {
            format!(
                "the engineering constants give a compliance that is not positive definite (smallest eigenvalue {min:.3e}): the Poisson ratios are too large for the moduli (need e.g. ν12² < E1/E2, and 1 − ν12ν21 − ν23ν32 − ν13ν31 − 2ν21ν32ν13 > 0)"
            )
        })?;
        let q = s
            .try_inverse()
            .ok_or_else(|| "the compliance matrix is singular".to_string())?;
        Self::anisotropic(name, &(0.5 * (q + q.transpose())), density)
    }

    /// Fully anisotropic material from its 6×6 stiffness in material axes.
    pub fn anisotropic(name: &str, q: &Matrix6<f64>, density: f64) -> Result<Self, String> {
        if !q.iter().all(|x| x.is_finite()) {
            return Err("the stiffness matrix has non-finite entries".into());
        }
        let scale = q.abs().max();
        for i in 0..6 {
            for j in 0..i {
                if (q[(i, j)] - q[(j, i)]).abs() > 1e-9 * scale {
                    return Err(format!(
                        "the stiffness matrix is not symmetric: C{}{} = {:e} but C{}{} = {:e}",
                        i + 1,
                        j + 1,
                        q[(i, j)],
                        j + 1,
                        i + 1,
                        q[(j, i)]
                    ));
                }
            }
        }
        check_positive_definite(q).map_err(|min| {
            format!(
                "the stiffness matrix is not positive definite (smallest eigenvalue {min:.3e}): some strain would store negative energy"
            )
        })?;
        if !(density.is_finite() && density >= 0.0) {
            return Err(format!("the density must be ≥ 0 (got {density})"));
        }
        Ok(Self {
            name: name.to_string(),
            stiffness: *q,
            density,
        })
    }
}

/// `Err(smallest eigenvalue)` unless the symmetric matrix is positive definite (relative to
/// its largest eigenvalue).
fn check_positive_definite(m: &Matrix6<f64>) -> Result<(), f64> {
    let eig = SymmetricEigen::new(0.5 * (m + m.transpose())).eigenvalues;
    let (min, max) = (eig.min(), eig.max());
    if max > 0.0 && min > 1e-12 * max {
        Ok(())
    } else {
        Err(min)
    }
}

/// Columns: the material axes a₁, a₂, a₃ in section components (x, y, z), for the wall
/// angle φ and ply angle θ [rad] (see the module doc).
pub fn material_axes(ply_angle: f64, wall_angle: f64) -> Matrix3<f64> {
    let (st, ct) = ply_angle.sin_cos();
    let (sp, cp) = wall_angle.sin_cos();
    let x = nalgebra::Vector3::new(1.0, 0.0, 0.0);
    let t = nalgebra::Vector3::new(0.0, cp, sp);
    let n = nalgebra::Vector3::new(0.0, -sp, cp);
    Matrix3::from_columns(&[x * ct + t * st, -x * st + t * ct, n])
}

/// Voigt index → tensor index pair, order `[11, 22, 33, 23, 13, 12]` (0-based).
const PAIRS: [(usize, usize); 6] = [(0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1)];

/// The stress transformation `σ' = T σ` (Voigt) of `σ' = a σ aᵀ`, `a[i][j]` = new axis i ·
/// old axis j. Strains (engineering shears) transform with `T⁻ᵀ`.
pub fn stress_rotation(a: &Matrix3<f64>) -> Matrix6<f64> {
    Matrix6::from_fn(|p, q| {
        let (i, j) = PAIRS[p];
        let (k, l) = PAIRS[q];
        if k == l {
            a[(i, k)] * a[(j, k)]
        } else {
            a[(i, k)] * a[(j, l)] + a[(i, l)] * a[(j, k)]
        }
    })
}

/// The material stiffness rotated into the section frame: `Q_s = T Q Tᵀ` with `T` the
/// stress rotation from material to section axes.
pub fn section_stiffness(q: &Matrix6<f64>, ply_angle: f64, wall_angle: f64) -> Matrix6<f64> {
    let t = stress_rotation(&material_axes(ply_angle, wall_angle));
    let qs = t * q * t.transpose();
    0.5 * (qs + qs.transpose())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn isotropic_is_invariant_under_rotation() {
        let m = Material::isotropic("steel", 2e11, 0.3, 7850.0).unwrap();
        let r = section_stiffness(&m.stiffness, 0.7, -1.9);
        assert!((r - m.stiffness).abs().max() < 1e-6 * m.stiffness.abs().max());
        // Lamé constants.
        let (e, nu) = (2e11, 0.3);
        let lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
        let mu = e / (2.0 * (1.0 + nu));
        assert!((m.stiffness[(0, 0)] - (lambda + 2.0 * mu)).abs() < 1e-3);
        assert!((m.stiffness[(0, 1)] - lambda).abs() < 1e-3);
        assert!((m.stiffness[(5, 5)] - mu).abs() < 1e-3);
    }

    #[test]
    fn strain_energy_is_frame_independent() {
        let m = Material::orthotropic(
            "cfrp",
            &Orthotropic {
                e1: 140e9,
                e2: 10e9,
                e3: 9e9,
                g12: 5e9,
                g13: 4.5e9,
                g23: 3.5e9,
                nu12: 0.3,
                nu13: 0.28,
                nu23: 0.4,
            },
            1600.0,
        )
        .unwrap();
        let (theta, phi) = (0.4, 1.1);
        let a = material_axes(theta, phi);
        assert!((a.transpose() * a - Matrix3::identity()).abs().max() < 1e-15);
        assert!((a.determinant() - 1.0).abs() < 1e-15);
        // A section-frame strain, rotated into material axes: same energy both ways.
        let eps_s = nalgebra::Vector6::new(1e-3, -2e-4, 3e-4, 5e-4, -7e-4, 2e-4);
        let t = stress_rotation(&a);
        let eps_m = t.transpose() * eps_s;
        let qs = section_stiffness(&m.stiffness, theta, phi);
        let u_s = eps_s.dot(&(qs * eps_s));
        let u_m = eps_m.dot(&(m.stiffness * eps_m));
        assert!((u_s - u_m).abs() < 1e-12 * u_s.abs());
        // A fibre along x at θ = φ = 0: Q_s = Q.
        let q0 = section_stiffness(&m.stiffness, 0.0, 0.0);
        assert!((q0 - m.stiffness).abs().max() < 1e-3);
        // Fibre turned by 90° towards y: the 11 and 22 moduli swap.
        let q90 = section_stiffness(&m.stiffness, std::f64::consts::FRAC_PI_2, 0.0);
        assert!((q90[(1, 1)] - m.stiffness[(0, 0)]).abs() < 1e-3 * m.stiffness[(0, 0)]);
    }

    #[test]
    fn bad_constants_are_rejected() {
        let mut c = Orthotropic {
            e1: 140e9,
            e2: 10e9,
            e3: 10e9,
            g12: 5e9,
            g13: 5e9,
            g23: 3e9,
            nu12: 0.3,
            nu13: 0.3,
            nu23: 0.4,
        };
        assert!(Material::orthotropic("ok", &c, 1.0).is_ok());
        c.nu23 = 1.2;
        let e = Material::orthotropic("bad", &c, 1.0).unwrap_err();
        assert!(e.contains("not positive definite"), "{e}");
        assert!(Material::isotropic("bad", 1.0, 0.5, 1.0).is_err());
        assert!(Material::isotropic("bad", -1.0, 0.3, 1.0).is_err());
    }
}
