//! Floquet stability of the small motions about a periodic solution of period T.
//!
//! Along the periodic solution the linearized equations ([`super::linearize`])
//!
//! ```text
//!     M(t) ÿ + G(t) ẏ + K(t) y + B(t)ᵀ μ = 0,      B(t) y = 0
//! ```
//!
//! have T-periodic coefficients. Their monodromy matrix Φ maps the state at t₀ to the
//! state at t₀ + T; its eigenvalues are the Floquet multipliers ρ (stable when all
//! |ρ| ≤ 1), the characteristic exponents are `λ = ln ρ / T`.
//!
//! **Integration.** The equations are integrated over one period with the generalized-α
//! scheme of the dynamic analyses (Chung & Hulbert 1993 in the Arnold–Brüls form of
//! [`crate::analysis::GeneralizedAlpha`]: Newmark relations for y and ẏ with the
//! algorithmic acceleration a, equilibrium and constraints imposed at t_{n+1}), with the
//! matrices taken at t_{n+1} of the stored periodic solution. Each step solves
//!
//! ```text
//!     [β'M + γ'G + K   Bᵀ] [y_{n+1}]   [−M c_v̇ − G c_v]
//!     [      B          0] [  μ   ] = [       0       ]
//! ```
//!
//! (c_v̇, c_v the parts of v̇_{n+1}, v_{n+1} that do not depend on y_{n+1}), one LU per step
//! shared by every column. The columns of Φ (one per state) are independent: they are
//! advanced in parallel (rayon), each by the same arithmetic whatever the number of
//! threads, so the result is deterministic. The scheme is second-order accurate, so the
//! multipliers converge as h² (verified on the Mathieu equation, tests/floquet.rs).
//!
//! **State and constraints.** The state is `(η, η̇)` in the independent coordinates
//! `y = N η` of the constrained motion at t₀ (N an orthonormal basis of the null space of
//! B(t₀), by SVD; redundant constraint rows are harmless): 2r states, r = n − rank B.
//! Column j starts from the constraint-consistent perturbation
//!
//! ```text
//!     y₀ = N η,    ẏ₀ = N η̇ − B⁺ Ḃ N η,    v̇₀ from [M Bᵀ; B 0][v̇₀; μ₀] = [−Gẏ₀ − Ky₀; −2Ḃẏ₀ − B̈y₀]
//! ```
//!
//! (the derivatives of `B y = 0`; Ḃ and B̈ by central differences over the step, using
//! the periodicity B(t₀ − h) = B(t₀ + T − h)), a₀ = v̇₀, and is read back at t₀ + T as
//! `(Nᵀ y, Nᵀ ẏ)` (periodicity: B(t₀ + T) = B(t₀)), with ẏ(t₀ + T) the central difference
//! `(y_{N+1} − y_{N−1})/2h` of the positions (one more step past the period, with the
//! matrices of t₀ + h): the algorithmic velocities of index-3 generalized-α carry an O(h)
//! error when B varies in time (Arnold & Brüls 2007), the positions are second order.
//! When B is the same at every step the algorithmic velocity ẏ_N is read instead (second
//! order there, and it keeps det Φ = 1 for an undamped system with ρ∞ = 1). Index-3 enforcement keeps
//! `B y = 0` at every step. Every independent direction must have inertia (the projected
//! mass `NᵀMN` regular).
//!
//! **Element states.** The last n_z unknowns z (inflow, controller, viscoelastic states)
//! are first order: no inertia, no constraint. They are integrated in the same steps by
//! the first-order generalized-α of the dynamic analyses ([`FirstOrderAlpha`]:
//! `z_{n+1} = z_n + h(1 − γ₁)w_n + hγ₁w_{n+1}`, `ż_{n+1}` from the algorithmic rate w), so
//! the step matrix gains the columns `γ₁'G_z + K_z` (γ₁' = ∂ż_{n+1}/∂z_{n+1}), the start
//! solves `[M_s G_z Bᵀ; B 0 0][v̇; ż; μ] = [−G_sẏ − Ky; −2Ḃẏ − B̈y]`, and the state is
//! `(η, η̇, z)`: 2r + n_z columns.
//!
//! **Exponents.** `λ = (ln|ρ| + i arg ρ)/T` on the principal branch, arg ρ ∈ (−π, π]: the
//! imaginary part, hence the frequency, is known only up to multiples of 2π/T (a rotor:
//! up to multiples of the rotor speed, 1P). The modulus |ρ| and the real part
//! `ln|ρ|/T` (growth rate) are unambiguous.

use super::LinearSystem;
use crate::analysis::{FirstOrderAlpha, GeneralizedAlpha};
use faer::c64;
use nalgebra::{DMatrix, DVector};
use std::f64::consts::PI;

/// Why a monodromy matrix could not be computed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FloquetError {
    #[error("a Floquet analysis needs at least 2 steps per period and the matrices at each")]
    TooFewSteps,
    #[error("a constraint acts on an element state: constraints must act on the configuration")]
    ConstrainedStates,
    #[error("an element state has inertia: element states are first-order unknowns")]
    StateInertia,
    #[error("the constraints leave no free motion")]
    NoFreedom,
    #[error(
        "{0} independent direction(s) have no mass: a Floquet analysis needs inertia in every unconstrained direction"
    )]
    Massless(usize),
    #[error("the step matrix is singular at step {0}")]
    Singular(usize),
    #[error("the monodromy matrix has non-finite entries")]
    NotFinite,
}

/// One Floquet mode: a multiplier and its characteristic exponent.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FloquetMode {
    /// ρ, eigenvalue of the monodromy matrix.
    pub multiplier: c64,
    /// λ = ln ρ / T on the principal branch [rad/s].
    pub exponent: c64,
}

impl FloquetMode {
    fn new(multiplier: c64, period: f64) -> Self {
        let exponent = c64::new(
            multiplier.norm().ln() / period,
            multiplier.im.atan2(multiplier.re) / period,
        );
        Self {
            multiplier,
            exponent,
        }
    }

    /// |ρ|: > 1 unstable.
    pub fn modulus(&self) -> f64 {
        self.multiplier.norm()
    }

    /// `|λ|/2π` [Hz] of the principal-branch exponent (its imaginary part is known only
    /// up to multiples of 2π/T).
    pub fn frequency(&self) -> f64 {
        self.exponent.norm() / (2.0 * PI)
    }

    /// `−Re λ/|λ|` of the principal-branch exponent (negative: unstable).
    pub fn damping_ratio(&self) -> f64 {
        let r = self.exponent.norm();
        if r == 0.0 { 0.0 } else { -self.exponent.re / r }
    }
}

/// The monodromy matrix and its modes.
#[derive(Clone, Debug)]
pub struct Monodromy {
    pub period: f64,
    /// Φ, (2r + n_z) × (2r + n_z), on `(η, η̇, z)` (z: the element states).
    pub matrix: DMatrix<f64>,
    /// N, n_s × r: the independent coordinates `y = N η` of the n_s structural unknowns
    /// (nodes and joint coordinates) at t₀.
    pub basis: DMatrix<f64>,
    /// One mode per multiplier with Im ρ ≥ 0 (a conjugate pair is one mode, each real
    /// multiplier one mode), largest modulus first.
    pub modes: Vec<FloquetMode>,
}

fn dense(a: &super::SparseMatrix) -> DMatrix<f64> {
    let mut d = DMatrix::zeros(a.nrows(), a.ncols());
    let r = a.as_ref();
    for j in 0..a.ncols() {
        for (&i, &v) in r.row_idx_of_col_raw(j).iter().zip(r.val_of_col(j)) {
            d[(i, j)] += v;
        }
    }
    d
}

/// Orthonormal basis of the null space of `b` (m × n) and the pseudo-inverse `b⁺`, from
/// the SVD of `b` padded with zero rows to a square matrix (singular values below
/// 10⁻¹⁰ of the largest count as zero, as in the dense modal path).
fn null_space(b: &DMatrix<f64>) -> (DMatrix<f64>, DMatrix<f64>) {
    let (m, n) = b.shape();
    if m == 0 {
        return (DMatrix::identity(n, n), DMatrix::zeros(n, 0));
    }
    let rows = m.max(n);
    let mut padded = DMatrix::zeros(rows, n);
    padded.view_mut((0, 0), (m, n)).copy_from(b);
    let svd = padded.svd(true, true);
    let (u, vt) = (
        svd.u.as_ref().expect("requested"),
        svd.v_t.as_ref().expect("requested"),
    );
    let top = svd.singular_values.iter().fold(0.0f64, |a, &x| a.max(x));
    let mut null_cols = Vec::new();
    let mut pinv = DMatrix::zeros(n, m);
    for (k, &sv) in svd.singular_values.iter().enumerate() {
        if sv <= 1e-10 * top.max(f64::MIN_POSITIVE) {
            null_cols.push(k);
        } else {
            // B⁺ = Σ v_k u_kᵀ / σ_k over the range (u_k restricted to the rows of B).
            let v = vt.row(k).transpose();
            let uk = u.column(k).rows(0, m).into_owned();
            pinv += (v * uk.transpose()) / sv;
        }
    }
    let basis = DMatrix::from_fn(n, null_cols.len(), |i, j| vt[(null_cols[j], i)]);
    (basis, pinv)
}

/// One column of the integration: the structural part (y, ẏ, v̇ and the algorithmic
/// acceleration a) and the element states (z, ż and the algorithmic rate w).
#[derive(Clone)]
struct Column {
    y: DVector<f64>,
    v: DVector<f64>,
    vd: DVector<f64>,
    a: DVector<f64>,
    z: DVector<f64>,
    zd: DVector<f64>,
    w: DVector<f64>,
}

/// The monodromy matrix of the linear equations `systems[k]` at `t₀ + k h`,
/// `k = 0 … N` (`h = T/N`; `systems[N]` is the state after one period, `systems[N − 1]`
/// also stands for t₀ − h), integrated by generalized-α with spectral radius `rho_inf`.
/// The last `n_states` unknowns of the systems are element states (first order).
pub fn monodromy(
    period: f64,
    systems: &[LinearSystem],
    rho_inf: f64,
    n_states: usize,
) -> Result<Monodromy, FloquetError> {
    use rayon::prelude::*;
    if systems.len() < 3 {
        return Err(FloquetError::TooFewSteps);
    }
    let steps = systems.len() - 1;
    let h = period / steps as f64;
    let n = systems[0].n;
    let nz = n_states.min(n);
    let ns = n - nz;
    // The constraints act on the configuration, never on element states, and no state
    // has inertia (z̈ appears nowhere).
    let structural = |lin: &LinearSystem| -> Result<DMatrix<f64>, FloquetError> {
        let b = dense(&lin.constraint_jacobian);
        if b.ncols() != n || (nz > 0 && b.columns(ns, nz).amax() > 0.0) {
            return Err(FloquetError::ConstrainedStates);
        }
        if nz > 0 && dense(&lin.mass).columns(ns, nz).amax() > 0.0 {
            return Err(FloquetError::StateInertia);
        }
        Ok(b.columns(0, ns).into_owned())
    };
    let b0 = structural(&systems[0])?;
    let (basis, pinv) = null_space(&b0);
    let r = basis.ncols();
    if r == 0 && nz == 0 {
        return Err(FloquetError::NoFreedom);
    }
    // Every independent direction has mass.
    let m0 = dense(&systems[0].mass);
    if r > 0 {
        let mp = basis.transpose() * m0.view((0, 0), (ns, ns)) * &basis;
        let me = mp.symmetric_eigen();
        let top = me.eigenvalues.iter().fold(0.0f64, |a, &x| a.max(x.abs()));
        let massless = me.eigenvalues.iter().filter(|&&x| x <= 1e-12 * top).count();
        if massless > 0 || top == 0.0 {
            return Err(FloquetError::Massless(massless.max(1)));
        }
    }
    // Ḃ, B̈ at t₀ by central differences (B(t₀ − h) = B(t₀ + T − h) by periodicity).
    let b1 = structural(&systems[1])?;
    let bm = structural(&systems[steps - 1])?;
    let bdot = (&b1 - &bm) / (2.0 * h);
    let bddot = (&b1 - 2.0 * &b0 + &bm) / (h * h);
    let (g0, k0) = (dense(&systems[0].damping), dense(&systems[0].stiffness));
    let m = b0.nrows();
    // Consistent start: [M_s G_z Bᵀ; B_s 0 0] [v̇; ż; μ] = [−G_s ẏ − K y; −2Ḃẏ − B̈y].
    let mut start = DMatrix::zeros(n + m, n + m);
    start
        .view_mut((0, 0), (n, ns))
        .copy_from(&m0.columns(0, ns));
    start
        .view_mut((0, ns), (n, nz))
        .copy_from(&g0.columns(ns, nz));
    start.view_mut((0, n), (ns, m)).copy_from(&b0.transpose());
    start.view_mut((n, 0), (m, ns)).copy_from(&b0);
    let start_lu = start.lu();
    if !start_lu.is_invertible() {
        return Err(FloquetError::Singular(0));
    }
    let mut columns: Vec<Column> = (0..2 * r + nz)
        .map(|j| {
            let (mut y, mut etad, mut z) =
                (DVector::zeros(ns), DVector::zeros(ns), DVector::zeros(nz));
            if j < r {
                y = basis.column(j).into_owned();
            } else if j < 2 * r {
                etad = basis.column(j - r).into_owned();
            } else {
                z[j - 2 * r] = 1.0;
            }
            let v = etad - &pinv * (&bdot * &y);
            let mut full = DVector::zeros(n);
            full.rows_mut(0, ns).copy_from(&y);
            full.rows_mut(ns, nz).copy_from(&z);
            let mut rhs = DVector::zeros(n + m);
            rhs.rows_mut(0, n)
                .copy_from(&(-(g0.columns(0, ns) * &v) - &k0 * &full));
            rhs.rows_mut(n, m)
                .copy_from(&(-2.0 * (&bdot * &v) - &bddot * &y));
            let x = start_lu
                .solve(&rhs)
                .unwrap_or_else(|| DVector::from_element(n + m, f64::NAN));
            let vd = x.rows(0, ns).into_owned();
            let zd = x.rows(ns, nz).into_owned();
            Column {
                a: vd.clone(),
                y,
                v,
                vd,
                w: zd.clone(),
                z,
                zd,
            }
        })
        .collect();
    let ga = GeneralizedAlpha::from_rho_inf(rho_inf);
    let fa = FirstOrderAlpha::from_rho_inf(rho_inf);
    let (bp, gp, rp) = (ga.beta_prime(h), ga.gamma_prime(h), fa.rate_prime(h));
    let scale = ga.beta * h * h;
    // Steps 1 … N, then one more (N + 1 ≡ 1 by periodicity) for the velocity read-back.
    let mut before_end: Vec<DVector<f64>> = Vec::new();
    let mut b_change = 0.0f64;
    let mut end: Vec<Column> = Vec::new();
    for step in 1..=steps + 1 {
        let lin = &systems[if step > steps { 1 } else { step }];
        if step == steps {
            before_end = columns.iter().map(|c| c.y.clone()).collect();
        }
        if step == steps + 1 {
            end = columns.clone();
        }
        let (mm, gg, kk, bb) = (
            dense(&lin.mass),
            dense(&lin.damping),
            dense(&lin.stiffness),
            structural(lin)?,
        );
        if bb.shape() == b0.shape() {
            b_change = b_change.max((&bb - &b0).amax());
        } else {
            b_change = f64::INFINITY;
        }
        // ∂(residual)/∂(y_{n+1}, z_{n+1}), times βh².
        let mut s = kk.clone();
        for j in 0..n {
            let (mf, gf) = if j < ns { (bp, gp) } else { (0.0, rp) };
            for i in 0..n {
                s[(i, j)] = (s[(i, j)] + mf * mm[(i, j)] + gf * gg[(i, j)]) * scale;
            }
        }
        let smax = s.amax().max(f64::MIN_POSITIVE);
        let bmax = bb.amax();
        let bs = if bmax > 0.0 { smax / bmax } else { 1.0 };
        let m = bb.nrows();
        let mut a = DMatrix::zeros(n + m, n + m);
        a.view_mut((0, 0), (n, n)).copy_from(&s);
        a.view_mut((0, n), (ns, m))
            .copy_from(&(bb.transpose() * bs));
        a.view_mut((n, 0), (m, ns)).copy_from(&(&bb * bs));
        let lu = a.lu();
        if !lu.is_invertible() {
            return Err(FloquetError::Singular(step));
        }
        let (ms, gs, gz) = (mm.columns(0, ns), gg.columns(0, ns), gg.columns(ns, nz));
        columns.par_iter_mut().for_each(|c| {
            // a_{n+1} = y_{n+1}/(βh²) + c_a; w_{n+1} = z_{n+1}/(hγ₁) + c_w.
            let c_a = -(&c.y + h * &c.v + (h * h * (0.5 - ga.beta)) * &c.a) / scale;
            let c_v = &c.v + (h * (1.0 - ga.gamma)) * &c.a + (h * ga.gamma) * &c_a;
            let c_d = ((1.0 - ga.alpha_m) * &c_a + ga.alpha_m * &c.a - ga.alpha_f * &c.vd)
                / (1.0 - ga.alpha_f);
            let c_w = -(&c.z + (h * (1.0 - fa.gamma)) * &c.w) / (h * fa.gamma);
            let c_zd = ((1.0 - fa.alpha_m) * &c_w + fa.alpha_m * &c.w - fa.alpha_f * &c.zd)
                / (1.0 - fa.alpha_f);
            let mut rhs = DVector::zeros(n + m);
            rhs.rows_mut(0, n)
                .copy_from(&((-(ms * &c_d) - gs * &c_v - gz * &c_zd) * scale));
            let x = lu.solve(&rhs).expect("the LU is invertible");
            let y1 = x.rows(0, ns).into_owned();
            let z1 = x.rows(ns, nz).into_owned();
            c.v = &c_v + (h * ga.gamma) * (&y1 / scale);
            c.vd = &c_d + bp * &y1;
            c.a = &y1 / scale + &c_a;
            c.y = y1;
            c.w = &z1 / (h * fa.gamma) + &c_w;
            c.zd = &c_zd + rp * &z1;
            c.z = z1;
        });
    }
    // A constant B (no order reduction): the algorithmic velocity, which keeps the
    // scheme's structure (det Φ = 1 for an undamped system with ρ∞ = 1).
    let constant_b = b_change <= 1e-14 * b0.amax().max(f64::MIN_POSITIVE);
    let mut phi = DMatrix::zeros(2 * r + nz, 2 * r + nz);
    for (j, c) in columns.iter().enumerate() {
        // y(t₀ + T), and ẏ(t₀ + T) by the central difference of the positions (the
        // algorithmic velocities of index-3 generalized-α carry an O(h) error when B
        // varies in time; the positions are second order).
        let eta = basis.transpose() * &end[j].y;
        let etad = if constant_b {
            basis.transpose() * &end[j].v
        } else {
            basis.transpose() * ((&c.y - &before_end[j]) / (2.0 * h))
        };
        phi.view_mut((0, j), (r, 1)).copy_from(&eta);
        phi.view_mut((r, j), (r, 1)).copy_from(&etad);
        phi.view_mut((2 * r, j), (nz, 1)).copy_from(&end[j].z);
    }
    if !phi.iter().all(|x| x.is_finite()) {
        return Err(FloquetError::NotFinite);
    }
    let modes = floquet_modes(&phi, period);
    Ok(Monodromy {
        period,
        matrix: phi,
        basis,
        modes,
    })
}

/// The modes of a monodromy matrix `phi` of period `period`: one per multiplier with
/// Im ρ ≥ 0 (a conjugate pair counts once), largest modulus first.
pub fn floquet_modes(phi: &DMatrix<f64>, period: f64) -> Vec<FloquetMode> {
    let values = phi.complex_eigenvalues();
    let scale = values.iter().fold(0.0f64, |a, z| a.max(z.norm()));
    let tiny = 1e-12 * scale.max(f64::MIN_POSITIVE);
    let mut out: Vec<FloquetMode> = values
        .iter()
        .filter(|z| z.im >= -tiny)
        .map(|z| {
            let im = if z.im.abs() <= tiny { 0.0 } else { z.im };
            FloquetMode::new(c64::new(z.re, im), period)
        })
        .collect();
    out.sort_by(|a, b| {
        b.modulus()
            .total_cmp(&a.modulus())
            .then(b.multiplier.im.total_cmp(&a.multiplier.im))
            .then(b.multiplier.re.total_cmp(&a.multiplier.re))
    });
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A constant matrix exp(AT) of a damped oscillator: exponents come back on the
    /// principal branch, frequency and damping ratio as for a modal analysis.
    #[test]
    fn modes_of_a_known_monodromy() {
        let (wn, zeta, t) = (3.0f64, 0.05f64, 0.7f64);
        let wd = wn * (1.0 - zeta * zeta).sqrt();
        // Eigenvalues −ζω ± iω_d; Φ = exp(AT) in real form.
        let (re, im) = (-zeta * wn * t, wd * t);
        let e = re.exp();
        let phi = DMatrix::from_row_slice(
            2,
            2,
            &[e * im.cos(), -e * im.sin(), e * im.sin(), e * im.cos()],
        );
        let modes = floquet_modes(&phi, t);
        assert_eq!(modes.len(), 1);
        let m = modes[0];
        assert!((m.modulus() - e).abs() < 1e-14);
        assert!((m.exponent.re + zeta * wn).abs() < 1e-12);
        assert!((m.exponent.im - wd).abs() < 1e-12);
        assert!((m.frequency() - wn / (2.0 * PI)).abs() < 1e-12);
        assert!((m.damping_ratio() - zeta).abs() < 1e-12);
        // Two real multipliers are two modes, the larger first.
        let modes = floquet_modes(
            &DMatrix::from_diagonal(&DVector::from_vec(vec![0.5, -2.0])),
            1.0,
        );
        assert_eq!(modes.len(), 2);
        assert_eq!(modes[0].multiplier, c64::new(-2.0, 0.0));
        assert!((modes[0].exponent.im - PI).abs() < 1e-15);
    }
}
