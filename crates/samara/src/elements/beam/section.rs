//! Sectional properties: the 6×6 stiffness and mass matrices of a cross-section, in the
//! section frame (x along the beam axis, y and z in the section plane), ordered
//! (axial, shear y, shear z | torsion, bending about y, bending about z) — the ordering of
//! VABS and Kynema. BeamDyn orders (shear, shear, axial | bending, bending, torsion) with the
//! beam along z: the permutation is (3, 1, 2, 6, 4, 5) in BeamDyn's 1-based indices.
//!
//! - Stiffness: `[N; M] = C [ε; κ]` with ε = Rᵀx′ − R₀ᵀx₀′ and κ the material curvature
//!   change; C symmetric positive definite, fully populated allowed (all elastic couplings).
//! - Mass per unit length about the reference line:
//!   `M = [[m I, m η̃ᵀ], [m η̃, J]]` with η the mass-centre offset and J the inertia per unit
//!   length about the reference point (section frame): the momentum of a section moving
//!   with (V, ω) (section-frame velocity of the reference point, angular velocity) is M [V; ω].
//! - Isotropic sections (E, G, A, I₂, I₃, J, shear factors k₂ k₃, offsets) give
//!   `C = T_tᵀ diag(EA, 0, 0, 0, EI₂, EI₃) T_t + T_sᵀ diag(0, k₂GA, k₃GA, GJ, 0, 0) T_s`,
//!   `T_c = [[I, −c̃], [0, I]]` — axial strain and bending measured at the tension centre,
//!   shear and torsion at the shear centre (a line at offset c strains as ε + κ × c).
//! - Along the span, matrices are interpolated linearly between stations (as BeamDyn).

use crate::math::skew;
use nalgebra::{Matrix3, Matrix6, SymmetricEigen, Vector3};

/// One cross-section: stiffness and mass per unit length, section frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Section {
    pub stiffness: Matrix6<f64>,
    pub mass: Matrix6<f64>,
}

/// Inputs of an isotropic (homogeneous) section.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IsotropicSection {
    pub e: f64,
    pub g: f64,
    pub area: f64,
    /// Second moment of area about the section y axis, ∫z² dA.
    pub i2: f64,
    /// Second moment of area about the section z axis, ∫y² dA.
    pub i3: f64,
    /// Torsion constant.
    pub j: f64,
    /// Shear correction factors (k₂, k₃).
    pub shear_factors: [f64; 2],
    /// Density (0: massless).
    pub density: f64,
    /// Offsets (y, z) of the tension centre, shear centre and mass centre from the
    /// reference line, section frame.
    pub tension_centre: [f64; 2],
    pub shear_centre: [f64; 2],
    pub mass_centre: [f64; 2],
}

fn offset_transform(c: &[f64; 2]) -> Matrix6<f64> {
    let mut t = Matrix6::identity();
    let ct = skew(&Vector3::new(0.0, c[0], c[1]));
    t.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-ct));
    t
}

impl IsotropicSection {
    /// The 6×6 matrices of the section.
    pub fn build(&self) -> Section {
        let tt = offset_transform(&self.tension_centre);
        let ts = offset_transform(&self.shear_centre);
        let mut ct = Matrix6::zeros();
        ct[(0, 0)] = self.e * self.area;
        ct[(4, 4)] = self.e * self.i2;
        ct[(5, 5)] = self.e * self.i3;
        let mut cs = Matrix6::zeros();
        cs[(1, 1)] = self.shear_factors[0] * self.g * self.area;
        cs[(2, 2)] = self.shear_factors[1] * self.g * self.area;
        cs[(3, 3)] = self.g * self.j;
        let stiffness = tt.transpose() * ct * tt + ts.transpose() * cs * ts;
        let m = self.density * self.area;
        let eta = Vector3::new(0.0, self.mass_centre[0], self.mass_centre[1]);
        let j_cg = Matrix3::from_diagonal(&Vector3::new(
            self.density * (self.i2 + self.i3),
            self.density * self.i2,
            self.density * self.i3,
        ));
        Section {
            stiffness,
            mass: mass_matrix(m, &eta, &j_cg),
        }
    }
}

/// `[[m I, m η̃ᵀ], [m η̃, J_cg − m η̃η̃]]`.
pub fn mass_matrix(m: f64, eta: &Vector3<f64>, j_cg: &Matrix3<f64>) -> Matrix6<f64> {
    let et = skew(eta);
    let mut out = Matrix6::zeros();
    out.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&(Matrix3::identity() * m));
    out.fixed_view_mut::<3, 3>(0, 3)
        .copy_from(&(et.transpose() * m));
    out.fixed_view_mut::<3, 3>(3, 0).copy_from(&(et * m));
    out.fixed_view_mut::<3, 3>(3, 3)
        .copy_from(&(j_cg - et * et * m));
    out
}

/// For each samara sectional index, the BeamDyn index it comes from. samara orders
/// (axial, shear y, shear z, torsion, bending y, bending z) with the beam along x;
/// BeamDyn orders (shear x, shear y, axial, bending x, bending y, torsion) with the beam
/// along z. With samara's section y, z along BeamDyn's x, y (a cyclic, right-handed
/// relabelling x_s = z_BD, y_s = x_BD, z_s = y_BD), C_s[i][j] = C_BD[p[i]][p[j]].
pub const BEAMDYN_INDEX: [usize; 6] = [2, 0, 1, 5, 3, 4];

/// A BeamDyn-ordered 6×6 sectional matrix (stiffness or mass) in samara's ordering.
pub fn from_beamdyn_ordering(m: &Matrix6<f64>) -> Matrix6<f64> {
    Matrix6::from_fn(|i, j| m[(BEAMDYN_INDEX[i], BEAMDYN_INDEX[j])])
}

/// BeamDyn's damping coefficients μ (shear x, shear y, axial, bending x, bending y,
/// torsion) in samara's ordering.
pub fn damping_from_beamdyn_ordering(mu: &[f64; 6]) -> [f64; 6] {
    std::array::from_fn(|i| mu[BEAMDYN_INDEX[i]])
}

/// Why a 6×6 matrix is not acceptable as sectional stiffness or mass.
pub fn check_stiffness(c: &Matrix6<f64>) -> Result<(), String> {
    check_symmetric(c, "stiffness")?;
    let eig = SymmetricEigen::new(0.5 * (c + c.transpose())).eigenvalues;
    let (min, max) = (eig.min(), eig.max());
    if !(min > 1e-14 * max.abs() && max > 0.0) {
        return Err(format!(
            "the stiffness matrix is not positive definite (eigenvalues from {min:.4e} to {max:.4e})"
        ));
    }
    Ok(())
}

/// The mass matrix must be symmetric, positive semi-definite, with an isotropic
/// translational block m I and a skew coupling block m η̃ (a rigid cross-section).
pub fn check_mass(m: &Matrix6<f64>) -> Result<(), String> {
    check_symmetric(m, "mass")?;
    let scale = m.abs().max().max(f64::MIN_POSITIVE);
    let mt = m[(0, 0)];
    let m11 = m.fixed_view::<3, 3>(0, 0);
    if (m11 - Matrix3::identity() * mt).abs().max() > 1e-9 * scale {
        return Err(
            "the translational block (rows/columns 1–3) of the mass matrix must be m·I: the same mass per length in every direction".into(),
        );
    }
    let m21 = m.fixed_view::<3, 3>(3, 0);
    if (m21 + m21.transpose()).abs().max() > 1e-9 * scale {
        return Err("the coupling block (rows 4–6, columns 1–3) of the mass matrix must be skew-symmetric, m·η̃ with η the mass-centre offset".into());
    }
    let eig = SymmetricEigen::new(0.5 * (m + m.transpose())).eigenvalues;
    if eig.min() < -1e-12 * scale {
        return Err(format!(
            "the mass matrix is not positive semi-definite (smallest eigenvalue {:.4e})",
            eig.min()
        ));
    }
    Ok(())
}

fn check_symmetric(c: &Matrix6<f64>, what: &str) -> Result<(), String> {
    if !c.iter().all(|x| x.is_finite()) {
        return Err(format!("the {what} matrix has non-finite entries"));
    }
    let scale = c.abs().max().max(f64::MIN_POSITIVE);
    let mut worst = (0.0, 0, 0);
    for i in 0..6 {
        for j in 0..6 {
            let d = (c[(i, j)] - c[(j, i)]).abs();
            if d > worst.0 {
                worst = (d, i, j);
            }
        }
    }
    if worst.0 > 1e-9 * scale {
        return Err(format!(
            "the {what} matrix is not symmetric: entry ({},{}) differs from ({},{}) by {:.3e}",
            worst.1 + 1,
            worst.2 + 1,
            worst.2 + 1,
            worst.1 + 1,
            worst.0
        ));
    }
    Ok(())
}

/// Sections at increasing stations η ∈ [0, 1] (normalized arc length), linearly
/// interpolated; constant beyond the ends.
#[derive(Clone, Debug, PartialEq)]
pub struct SectionTable {
    pub stations: Vec<f64>,
    pub sections: Vec<Section>,
}

impl SectionTable {
    pub fn uniform(s: Section) -> Self {
        Self {
            stations: vec![0.0],
            sections: vec![s],
        }
    }

    /// The section at η.
    pub fn at(&self, eta: f64) -> Section {
        Section {
            stiffness: self.stiffness_at(eta),
            mass: self.mass_at(eta),
        }
    }

    /// The stiffness at η (as [`Self::at`]).
    pub fn stiffness_at(&self, eta: f64) -> Matrix6<f64> {
        self.interpolate(eta, |s| &s.stiffness)
    }

    /// The mass matrix at η (as [`Self::at`]).
    pub fn mass_at(&self, eta: f64) -> Matrix6<f64> {
        self.interpolate(eta, |s| &s.mass)
    }

    /// [`Self::stiffness_at`] without the copy: the table's own matrix for a uniform beam
    /// and outside the stations, else interpolated into `buf`.
    #[inline]
    pub fn stiffness_in<'a>(&'a self, eta: f64, buf: &'a mut Matrix6<f64>) -> &'a Matrix6<f64> {
        self.interpolate_in(eta, |s| &s.stiffness, buf)
    }

    /// [`Self::mass_at`] without the copy (as [`Self::stiffness_in`]).
    #[inline]
    pub fn mass_in<'a>(&'a self, eta: f64, buf: &'a mut Matrix6<f64>) -> &'a Matrix6<f64> {
        self.interpolate_in(eta, |s| &s.mass, buf)
    }

    #[inline]
    fn interpolate(&self, eta: f64, of: impl Fn(&Section) -> &Matrix6<f64>) -> Matrix6<f64> {
        *self.interpolate_in(eta, of, &mut Matrix6::zeros())
    }

    /// `(1 − t) X_{k−1} + t X_k` between the stations around η (written into `buf`); the
    /// end sections outside, by reference.
    #[inline]
    fn interpolate_in<'a>(
        &'a self,
        eta: f64,
        of: impl Fn(&Section) -> &Matrix6<f64>,
        buf: &'a mut Matrix6<f64>,
    ) -> &'a Matrix6<f64> {
        let n = self.stations.len();
        if n == 1 || eta <= self.stations[0] {
            return of(&self.sections[0]);
        }
        if eta >= self.stations[n - 1] {
            return of(&self.sections[n - 1]);
        }
        let k = self.stations.partition_point(|&s| s <= eta).clamp(1, n - 1);
        let (a, b) = (self.stations[k - 1], self.stations[k]);
        let t = (eta - a) / (b - a);
        *buf = of(&self.sections[k - 1]) * (1.0 - t) + of(&self.sections[k]) * t;
        buf
    }
}

/// Stiffness-proportional damping `D = Λ C Λ`, `Λ = diag(√μᵢ)`: symmetric positive
/// semi-definite for any μᵢ ≥ 0 (dissipation ėᵀDė ≥ 0), and `μ C` for equal μᵢ
/// (Hansen 2001's anisotropic form of Rayleigh damping).
pub fn damping_matrix(c: &Matrix6<f64>, mu: &[f64; 6]) -> Matrix6<f64> {
    damping_matrix_from_roots(c, &mu.map(f64::sqrt))
}

/// [`damping_matrix`] from `√μᵢ`: `D_ij = √μᵢ C_ij √μⱼ`.
#[inline]
pub fn damping_matrix_from_roots(c: &Matrix6<f64>, root_mu: &[f64; 6]) -> Matrix6<f64> {
    Matrix6::from_fn(|i, j| root_mu[i] * c[(i, j)] * root_mu[j])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A rectangular steel section with offsets: the assembled C reproduces the energy of
    /// a strain state computed by hand at the tension and shear centres.
    #[test]
    fn isotropic_builder_with_offsets() {
        let s = IsotropicSection {
            e: 2.0,
            g: 0.8,
            area: 3.0,
            i2: 0.5,
            i3: 0.7,
            j: 0.9,
            shear_factors: [0.8, 0.9],
            density: 2.0,
            tension_centre: [0.1, -0.2],
            shear_centre: [-0.05, 0.15],
            mass_centre: [0.2, 0.1],
        }
        .build();
        assert!(check_stiffness(&s.stiffness).is_ok());
        assert!(check_mass(&s.mass).is_ok());
        let e = nalgebra::Vector6::new(0.01, 0.02, -0.03, 0.4, -0.2, 0.3);
        // Axial strain at the tension centre (y_t, z_t): ε₁ − y κ₃ + z κ₂.
        let eps_t = e[0] - 0.1 * e[5] + (-0.2) * e[4];
        // Shear at the shear centre (y_s, z_s): γ₂ − z κ₁, γ₃ + y κ₁.
        let g2 = e[1] - 0.15 * e[3];
        let g3 = e[2] + (-0.05) * e[3];
        let energy = 2.0 * 3.0 * eps_t * eps_t
            + 2.0 * 0.5 * e[4] * e[4]
            + 2.0 * 0.7 * e[5] * e[5]
            + 0.8 * 0.8 * 3.0 * g2 * g2
            + 0.9 * 0.8 * 3.0 * g3 * g3
            + 0.8 * 0.9 * e[3] * e[3];
        let u = e.dot(&(s.stiffness * e));
        assert!((u - energy).abs() < 1e-14, "{u} vs {energy}");
        // Mass, from the momentum of the rigid section moving with (V, ω) (reference-point
        // velocity and angular velocity, section frame), worked by hand: m = ρA = 6, mass
        // centre η = (0, y_m, z_m) = (0, 0.2, 0.1).
        // Linear momentum m (V + ω × η): ω × η = (ω₂ z_m − ω₃ y_m, ω₃·0 − ω₁ z_m, ω₁ y_m),
        // so the (translation, rotation) block is m [[0, z_m, −y_m], [−z_m, 0, 0], [y_m, 0, 0]].
        // Angular momentum about the reference point J_cg ω + η × m(V + ω × η): the
        // (rotation, translation) block is its transpose, and the rotation block is J_cg plus
        // the parallel-axis term m (|η|² I − η ηᵀ), with J_cg = ρ diag(I₂ + I₃, I₂, I₃) =
        // diag(2.4, 1.0, 1.4) and m (|η|² I − η ηᵀ) = [[0.3, 0, 0], [0, 0.06, −0.12],
        // [0, −0.12, 0.24]].
        #[rustfmt::skip]
        let expected = Matrix6::new(
            6.0,  0.0,  0.0,  0.0,   0.6,  -1.2,
            0.0,  6.0,  0.0, -0.6,   0.0,   0.0,
            0.0,  0.0,  6.0,  1.2,   0.0,   0.0,
            0.0, -0.6,  1.2,  2.7,   0.0,   0.0,
            0.6,  0.0,  0.0,  0.0,   1.06, -0.12,
           -1.2,  0.0,  0.0,  0.0,  -0.12,  1.64,
        );
        // Entries are sums of a few products of short decimals: round-off only.
        assert!(
            (s.mass - expected).abs().max() < 1e-14,
            "{} vs {expected}",
            s.mass
        );
    }

    #[test]
    fn checks_reject_bad_matrices() {
        let mut c = Matrix6::identity();
        c[(0, 3)] = 0.5;
        assert!(check_stiffness(&c).unwrap_err().contains("(1,4)"));
        let mut c = Matrix6::identity();
        c[(2, 2)] = -1.0;
        assert!(
            check_stiffness(&c)
                .unwrap_err()
                .contains("positive definite")
        );
        let mut m = Matrix6::identity();
        m[(1, 1)] = 2.0;
        assert!(check_mass(&m).unwrap_err().contains("m·I"));
    }

    #[test]
    fn linear_interpolation_between_stations() {
        let a = Section {
            stiffness: Matrix6::identity(),
            mass: Matrix6::identity(),
        };
        let b = Section {
            stiffness: Matrix6::identity() * 3.0,
            mass: Matrix6::identity() * 5.0,
        };
        let t = SectionTable {
            stations: vec![0.0, 0.5],
            sections: vec![a, b],
        };
        assert_eq!(t.at(0.25).stiffness[(0, 0)], 2.0);
        assert_eq!(t.at(0.9).mass[(0, 0)], 5.0);
    }
}
