//! The constrained quadratic eigenvalue problem of a [`LinearSystem`]:
//!
//! ```text
//!     (λ²M + λG + K) y + Bᵀμ = 0,      B y = 0,
//! ```
//!
//! solved for the eigenvalues λ nearest a target σ, in first-order (companion) form with
//! `x = (y, λy)`. Two independent paths, tested against each other:
//!
//! - **dense** (small models): the constraints are removed by the orthonormal null-space
//!   basis N of B (`y = Nη`, from the SVD of B; redundant rows are harmless), and the
//!   companion pencil `[0 I; −K_N −G_N] − λ[I 0; 0 M_N]` of the projected matrices
//!   `X_N = NᵀXN` goes to the QZ algorithm. Massless directions give infinite eigenvalues
//!   (β = 0), which are dropped; no spurious eigenvalue is created by the constraints.
//! - **sparse** (large models): shift-invert Krylov–Schur (faer `partial_eigen`) on the
//!   operator `(A − σE)⁻¹E` restricted to the constrained space. Applying it solves the
//!   saddle-point system `[Q(σ) sBᵀ; sB 0] [y; μ/s] = [−Mb_v − (G + σM)b_y; 0]` with
//!   `Q(σ) = K + σG + σ²M` (sparse LU, factored once) and sets `v = b_y + σy`. Its
//!   eigenvalues are `θ = 1/(λ − σ)`: constrained modes only (B y = 0 holds exactly),
//!   infinite eigenvalues go to θ = 0 and are never found.
//! - **sparse, symmetric definite** (no damping or gyroscopic matrix, K and M symmetric,
//!   every unknown with mass, real target): the same factored saddle-point matrix with
//!   G = 0 serves block shift-invert Lanczos on `(K + σ²M)⁻¹M` ([`super::lanczos`]), which
//!   works on vectors of length n instead of 2n, in the M inner product, and needs one
//!   eigenvalue per mode instead of a conjugate pair; each `κ = ω²` found is returned as the
//!   pair `λ = ±i√κ`. When it does not converge within its basis, the general path runs.
//!
//! **Target σ.** Without a shift, `σ = −10⁻⁴ ω_d` with `ω_d = min √(K_ii/M_ii)` over the
//! unknowns with positive diagonal mass and stiffness (a Rayleigh-quotient upper bound of
//! the lowest frequency): small enough that the lowest modes come first, non-zero so
//! that `Q(σ)` is regular when the model has rigid-body modes. With a shift `f_s` [Hz],
//! `σ = i 2π f_s − 10⁻⁴ ω_d` and the modes nearest `2π f_s` come first.
//!
//! **Modes.** Eigenvalues come in conjugate pairs; each pair is one mode (the one with
//! Im λ > 0 is kept). Real eigenvalues (overdamped motion, first-order states) are one
//! mode each. Eigenvalues with `|λ| ≤ 10⁻² |Re σ|` are rigid-body (zero-frequency)
//! modes: a rigid-body degree of freedom gives λ = 0 twice (a Jordan block of the
//! companion form), so k such eigenvalues are ⌈k/2⌉ rigid-body modes, whose shapes are
//! an orthonormal basis of the span of the k eigenvectors.

use super::LinearSystem;
use faer::linalg::solvers::SolveCore;
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::sparse::{SparseColMat, Triplet};
use faer::{Conj, Mat, MatMut, MatRef, Par, c64};
use std::f64::consts::PI;

/// Models with at most this many unconstrained unknowns (n − m) use the dense path by
/// default.
pub const DENSE_LIMIT: usize = 120;

/// Which algorithm solves the eigenproblem.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum EigenMethod {
    /// Dense below [`DENSE_LIMIT`] unknowns (n − m), sparse above.
    #[default]
    Auto,
    Dense,
    Sparse,
}

/// What to compute.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EigenOptions {
    pub n_modes: usize,
    /// Frequency [Hz] near which modes are wanted (default: the lowest).
    pub shift: Option<f64>,
    pub method: EigenMethod,
}

impl Default for EigenOptions {
    fn default() -> Self {
        Self {
            n_modes: 10,
            shift: None,
            method: EigenMethod::Auto,
        }
    }
}

/// One mode.
#[derive(Clone, Debug)]
pub struct Mode {
    /// λ [rad/s]; the motion is `Re(y e^{λt})`.
    pub eigenvalue: c64,
    /// y (length n, the unknowns of the [`LinearSystem`]), scaled so that its component
    /// of largest modulus is 1.
    pub shape: Vec<c64>,
    /// A zero-frequency (rigid-body or mechanism) mode.
    pub rigid: bool,
}

impl Mode {
    /// Natural (undamped) frequency `|λ|/2π` [Hz]; 0 for a rigid-body mode.
    pub fn frequency(&self) -> f64 {
        if self.rigid {
            0.0
        } else {
            self.eigenvalue.norm() / (2.0 * PI)
        }
    }

    /// Damped frequency `|Im λ|/2π` [Hz].
    pub fn damped_frequency(&self) -> f64 {
        if self.rigid {
            0.0
        } else {
            self.eigenvalue.im.abs() / (2.0 * PI)
        }
    }

    /// Damping ratio `−Re λ/|λ|` (0 for a rigid-body mode; negative when unstable).
    pub fn damping_ratio(&self) -> f64 {
        let r = self.eigenvalue.norm();
        if self.rigid || r == 0.0 {
            0.0
        } else {
            -self.eigenvalue.re / r
        }
    }
}

/// The modes found and how.
#[derive(Clone, Debug)]
pub struct Spectrum {
    pub modes: Vec<Mode>,
    /// The target σ [rad/s].
    pub sigma: c64,
    /// The path taken (never `Auto`).
    pub method: EigenMethod,
}

/// Why no modes could be computed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum EigenError {
    #[error("the model has no mass: a modal analysis needs inertia")]
    NoMass,
    #[error("{requested} modes requested but the model has only {dof} degrees of freedom")]
    TooManyModes { requested: usize, dof: usize },
    #[error("the shifted matrix K + σG + σ²M with the constraints is singular ({0})")]
    Singular(String),
    #[error("the eigensolver converged {found} of the {requested} eigenvalues needed")]
    NotConverged { found: usize, requested: usize },
    #[error("the dense eigensolver failed: {0}")]
    Dense(String),
}

fn dense(a: &SparseColMat<usize, f64>) -> Mat<f64> {
    let mut d = Mat::zeros(a.nrows(), a.ncols());
    let r = a.as_ref();
    for j in 0..a.ncols() {
        for (&i, &v) in r.row_idx_of_col_raw(j).iter().zip(r.val_of_col(j)) {
            d[(i, j)] += v;
        }
    }
    d
}

/// `(i, M_ii)` and `K_ii` of every unknown.
fn diagonal(a: &SparseColMat<usize, f64>) -> Vec<f64> {
    let r = a.as_ref();
    (0..a.ncols())
        .map(|j| {
            r.row_idx_of_col_raw(j)
                .iter()
                .zip(r.val_of_col(j))
                .filter(|(i, _)| **i == j)
                .map(|(_, v)| *v)
                .sum()
        })
        .collect()
}

/// The target σ of `opts` for `lin` (see the module documentation).
pub fn target(lin: &LinearSystem, opts: &EigenOptions) -> c64 {
    let (m, k) = (diagonal(&lin.mass), diagonal(&lin.stiffness));
    let wd = m
        .iter()
        .zip(&k)
        .filter(|(m, k)| **m > 0.0 && **k > 0.0)
        .map(|(m, k)| (k / m).sqrt())
        .fold(f64::INFINITY, f64::min);
    let wd = if wd.is_finite() { wd } else { 1.0 };
    c64::new(-1e-4 * wd, opts.shift.map_or(0.0, |f| 2.0 * PI * f))
}

/// The `n_modes` modes of `lin` nearest the target.
pub fn modes(lin: &LinearSystem, opts: &EigenOptions) -> Result<Spectrum, EigenError> {
    let n = lin.n;
    if lin.mass.as_ref().val().iter().all(|v| *v == 0.0) {
        return Err(EigenError::NoMass);
    }
    let dof = n.saturating_sub(lin.m);
    if opts.n_modes > dof {
        return Err(EigenError::TooManyModes {
            requested: opts.n_modes,
            dof,
        });
    }
    let sigma = target(lin, opts);
    let method = match opts.method {
        EigenMethod::Auto if dof <= DENSE_LIMIT => EigenMethod::Dense,
        EigenMethod::Auto => EigenMethod::Sparse,
        m => m,
    };
    let (values, vectors, rigid) = match method {
        EigenMethod::Dense => dense_eigenpairs(lin)?,
        _ => {
            let (v, w) = sparse_eigenpairs(lin, sigma, opts.n_modes)?;
            (v, w, None)
        }
    };
    let modes = select(values, vectors, sigma, opts.n_modes, n, rigid);
    if modes.len() < opts.n_modes {
        return Err(EigenError::NotConverged {
            found: modes.len(),
            requested: opts.n_modes,
        });
    }
    Ok(Spectrum {
        modes,
        sigma,
        method,
    })
}

/// Eigenvalues, eigenvectors and candidate rigid-body shapes.
type Eigenpairs = (Vec<c64>, Vec<Vec<c64>>, Option<Vec<Vec<f64>>>);

/// All finite eigenpairs (λ, y) by null-space projection and QZ, and the right singular
/// vectors of the projected K from the smallest singular value up (QZ eigenvectors of the
/// defective zero eigenvalues of rigid-body modes are not usable; these are).
fn dense_eigenpairs(lin: &LinearSystem) -> Result<Eigenpairs, EigenError> {
    let n = lin.n;
    let basis: Mat<f64> = if lin.m == 0 {
        Mat::identity(n, n)
    } else {
        let b = dense(&lin.constraint_jacobian);
        let svd = b.svd().map_err(|e| EigenError::Dense(format!("{e:?}")))?;
        let s = svd.S().column_vector();
        let smax = (0..s.nrows()).map(|i| s[i]).fold(0.0, f64::max);
        let rank = (0..s.nrows())
            .filter(|&i| s[i] > 1e-10 * smax.max(f64::MIN_POSITIVE))
            .count();
        svd.V().subcols(rank, n - rank).to_owned()
    };
    let r = basis.ncols();
    let project = |a: &SparseColMat<usize, f64>| basis.transpose() * dense(a) * &basis;
    let (m, g, k) = (
        project(&lin.mass),
        project(&lin.damping),
        project(&lin.stiffness),
    );
    let mut a = Mat::<f64>::zeros(2 * r, 2 * r);
    let mut e = Mat::<f64>::zeros(2 * r, 2 * r);
    for i in 0..r {
        a[(i, r + i)] = 1.0;
        e[(i, i)] = 1.0;
        for j in 0..r {
            a[(r + i, j)] = -k[(i, j)];
            a[(r + i, r + j)] = -g[(i, j)];
            e[(r + i, r + j)] = m[(i, j)];
        }
    }
    let (sa, sb, u) = real_generalized_eigen(&a, &e)?;
    let scale = a.norm_max().max(e.norm_max());
    let mut values = Vec::new();
    let mut vectors = Vec::new();
    for j in 0..2 * r {
        let (al, be) = (sa[j], sb[j]);
        // Infinite (massless directions): β negligible against α.
        if be.norm() <= 1e-13 * al.norm().max(scale * f64::EPSILON) {
            continue;
        }
        let lam = al / be;
        if !(lam.re.is_finite() && lam.im.is_finite()) {
            continue;
        }
        let y: Vec<c64> = (0..n)
            .map(|p| {
                (0..r).fold(c64::new(0.0, 0.0), |acc, q| {
                    acc + u[(q, j)] * c64::new(basis[(p, q)], 0.0)
                })
            })
            .collect();
        values.push(lam);
        vectors.push(y);
    }
    let ksvd = k.svd().map_err(|e| EigenError::Dense(format!("{e:?}")))?;
    let (sv, v) = (ksvd.S().column_vector(), ksvd.V());
    let mut order: Vec<usize> = (0..r).collect();
    order.sort_by(|&i, &j| sv[i].total_cmp(&sv[j]));
    let rigid = order
        .iter()
        .map(|&j| {
            (0..n)
                .map(|p| (0..r).map(|q| basis[(p, q)] * v[(q, j)]).sum())
                .collect()
        })
        .collect();
    Ok((values, vectors, Some(rigid)))
}

/// The generalized eigenvalues α/β and right eigenvectors of the real pencil (A, E), by
/// faer's real QZ. faer's own `generalized_eigen` sizes its work space for the reduction
/// only, which is too small for the eigenvector stage of very small pencils (a 2 × 2 pencil
/// with a complex pair panics); this gives that stage room (n × 8 plus two columns).
/// Complex pairs come as (re, im) columns j, j + 1 of the real vectors.
#[allow(clippy::type_complexity)]
fn real_generalized_eigen(
    a: &Mat<f64>,
    e: &Mat<f64>,
) -> Result<(Vec<c64>, Vec<c64>, Mat<c64>), EigenError> {
    use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
    use faer::linalg::evd::ComputeEigenvectors;
    let n = a.nrows();
    let par = faer::get_global_parallelism();
    let mut u = Mat::<f64>::zeros(n, n);
    let (mut re, mut im, mut beta) = (
        faer::diag::Diag::<f64>::zeros(n),
        faer::diag::Diag::<f64>::zeros(n),
        faer::diag::Diag::<f64>::zeros(n),
    );
    let (mut a, mut e) = (a.clone(), e.clone());
    let req = StackReq::any_of(&[
        faer::linalg::gevd::gevd_scratch::<f64>(
            n,
            ComputeEigenvectors::No,
            ComputeEigenvectors::Yes,
            par,
            Default::default(),
        ),
        faer::linalg::temp_mat_scratch::<f64>(n, 10),
    ]);
    faer::linalg::gevd::gevd_real(
        a.as_mut(),
        e.as_mut(),
        re.as_mut(),
        im.as_mut(),
        beta.as_mut(),
        None,
        Some(u.as_mut()),
        par,
        MemStack::new(&mut MemBuffer::new(req)),
        Default::default(),
    )
    .map_err(|e| EigenError::Dense(format!("{e:?}")))?;
    let (re, im, beta) = (re.column_vector(), im.column_vector(), beta.column_vector());
    let alpha: Vec<c64> = (0..n).map(|j| c64::new(re[j], im[j])).collect();
    let beta: Vec<c64> = (0..n).map(|j| c64::new(beta[j], 0.0)).collect();
    let mut v = Mat::<c64>::zeros(n, n);
    let mut j = 0;
    while j < n {
        if im[j] != 0.0 && j + 1 < n {
            for i in 0..n {
                v[(i, j)] = c64::new(u[(i, j)], u[(i, j + 1)]);
                v[(i, j + 1)] = c64::new(u[(i, j)], -u[(i, j + 1)]);
            }
            j += 2;
        } else {
            for i in 0..n {
                v[(i, j)] = c64::new(u[(i, j)], 0.0);
            }
            j += 1;
        }
    }
    Ok((alpha, beta, v))
}

/// The scalars of the shift-invert operator: real for a real target (half the work of
/// complex arithmetic), complex for a shift.
trait Scalar:
    faer::traits::ComplexField<Real = f64>
    + Copy
    + std::fmt::Display
    + std::ops::Add<Output = Self>
    + std::ops::Mul<Output = Self>
    + std::ops::Div<Output = Self>
    + std::ops::AddAssign
    + std::ops::MulAssign
    + std::ops::Neg<Output = Self>
    + 'static
{
    /// The real part only for `f64`.
    fn from_c64(z: c64) -> Self;
    fn modulus(self) -> f64;
    fn conjugated(self) -> Self;
}

impl Scalar for f64 {
    fn from_c64(z: c64) -> Self {
        z.re
    }
    fn modulus(self) -> f64 {
        self.abs()
    }
    fn conjugated(self) -> Self {
        self
    }
}

impl Scalar for c64 {
    fn from_c64(z: c64) -> Self {
        z
    }
    fn modulus(self) -> f64 {
        self.norm()
    }
    fn conjugated(self) -> Self {
        self.conj()
    }
}

fn zero<T: Scalar>() -> T {
    T::from_c64(c64::new(0.0, 0.0))
}

fn real<T: Scalar>(x: f64) -> T {
    T::from_c64(c64::new(x, 0.0))
}

/// Column-compressed matrix-vector product `out += alpha A x`.
fn spmv<T: Scalar>(a: &SparseColMat<usize, T>, x: &[T], alpha: T, out: &mut [T]) {
    let r = a.as_ref();
    for (j, xj) in x.iter().enumerate() {
        let s = alpha * *xj;
        for (&i, v) in r.row_idx_of_col_raw(j).iter().zip(r.val_of_col(j)) {
            out[i] += *v * s;
        }
    }
}

/// `Σ fₖ Aₖ` of real sparse matrices with scalar factors, as triplets.
fn combine<T: Scalar>(
    parts: &[(&SparseColMat<usize, f64>, T)],
    t: &mut Vec<Triplet<usize, usize, T>>,
) {
    for (a, f) in parts {
        let r = a.as_ref();
        for j in 0..a.ncols() {
            for (&i, &v) in r.row_idx_of_col_raw(j).iter().zip(r.val_of_col(j)) {
                t.push(Triplet::new(i, j, *f * real::<T>(v)));
            }
        }
    }
}

/// The shift-invert operator `(A − σE)⁻¹E` on `x = (y, v)` (length 2n).
struct ShiftInvert<T: Scalar> {
    n: usize,
    m: usize,
    sigma: T,
    mass: SparseColMat<usize, T>,
    /// G + σM.
    g_sigma: SparseColMat<usize, T>,
    lu: Lu<usize, T>,
}

impl<T: Scalar> std::fmt::Debug for ShiftInvert<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "ShiftInvert(n = {}, σ = {})", self.n, self.sigma)
    }
}

impl<T: Scalar> ShiftInvert<T> {
    fn new(lin: &LinearSystem, sigma: T) -> Result<Self, EigenError> {
        let (n, m) = (lin.n, lin.m);
        let mut t: Vec<Triplet<usize, usize, T>> = Vec::new();
        combine(
            &[
                (&lin.stiffness, real(1.0)),
                (&lin.damping, sigma),
                (&lin.mass, sigma * sigma),
            ],
            &mut t,
        );
        let kmax = t
            .iter()
            .filter(|x| x.row == x.col)
            .map(|x| x.val.modulus())
            .fold(0.0, f64::max);
        // Constraint rows scaled to the size of the diagonal (same solution y).
        let s = if kmax > 0.0 { kmax } else { 1.0 };
        let b = lin.constraint_jacobian.as_ref();
        for j in 0..n {
            for (&i, &v) in b.row_idx_of_col_raw(j).iter().zip(b.val_of_col(j)) {
                t.push(Triplet::new(n + i, j, real(s * v)));
                t.push(Triplet::new(j, n + i, real(s * v)));
            }
        }
        // A structural zero on every diagonal keeps the pattern square-factorable.
        for i in 0..n + m {
            t.push(Triplet::new(i, i, zero()));
        }
        let a = SparseColMat::try_new_from_triplets(n + m, n + m, &t)
            .map_err(|e| EigenError::Singular(format!("{e:?}")))?;
        let sym = SymbolicLu::try_new(a.symbolic())
            .map_err(|e| EigenError::Singular(format!("{e:?}")))?;
        let lu = Lu::try_new_with_symbolic(sym, a.as_ref())
            .map_err(|e| EigenError::Singular(format!("{e:?}")))?;
        let mut mt = Vec::new();
        combine(&[(&lin.mass, real(1.0))], &mut mt);
        let mass = SparseColMat::try_new_from_triplets(n, n, &mt).expect("inside");
        let mut gs = Vec::new();
        combine(&[(&lin.damping, real(1.0)), (&lin.mass, sigma)], &mut gs);
        let g_sigma = SparseColMat::try_new_from_triplets(n, n, &gs).expect("inside");
        Ok(Self {
            n,
            m,
            sigma,
            mass,
            g_sigma,
            lu,
        })
    }

    fn apply_one(&self, x: &[T], out: &mut [T], rhs: &mut Vec<T>) {
        let n = self.n;
        let (by, bv) = x.split_at(n);
        rhs.clear();
        rhs.resize(n + self.m, zero());
        let minus = real(-1.0);
        spmv(&self.mass, bv, minus, &mut rhs[..n]);
        spmv(&self.g_sigma, by, minus, &mut rhs[..n]);
        let len = rhs.len();
        self.lu
            .solve_in_place_with_conj(Conj::No, MatMut::from_column_major_slice_mut(rhs, len, 1));
        for i in 0..n {
            out[i] = rhs[i];
            out[n + i] = by[i] + self.sigma * rhs[i];
        }
    }
}

impl<T: Scalar> faer::matrix_free::LinOp<T> for ShiftInvert<T> {
    fn apply_scratch(&self, _rhs_ncols: usize, _par: Par) -> faer::dyn_stack::StackReq {
        faer::dyn_stack::StackReq::EMPTY
    }
    fn nrows(&self) -> usize {
        2 * self.n
    }
    fn ncols(&self) -> usize {
        2 * self.n
    }
    fn apply(
        &self,
        mut out: MatMut<'_, T>,
        rhs: MatRef<'_, T>,
        _par: Par,
        _stack: &mut faer::dyn_stack::MemStack,
    ) {
        let len = 2 * self.n;
        let (mut x, mut y) = (vec![zero::<T>(); len], vec![zero::<T>(); len]);
        let mut work = Vec::with_capacity(self.n + self.m);
        for c in 0..rhs.ncols() {
            for i in 0..len {
                x[i] = rhs[(i, c)];
            }
            self.apply_one(&x, &mut y, &mut work);
            for i in 0..len {
                out[(i, c)] = y[i];
            }
        }
    }
    fn conj_apply(
        &self,
        mut out: MatMut<'_, T>,
        rhs: MatRef<'_, T>,
        par: Par,
        stack: &mut faer::dyn_stack::MemStack,
    ) {
        let mut conj_rhs = Mat::<T>::zeros(rhs.nrows(), rhs.ncols());
        for c in 0..rhs.ncols() {
            for i in 0..rhs.nrows() {
                conj_rhs[(i, c)] = rhs[(i, c)].conjugated();
            }
        }
        self.apply(out.as_mut(), conj_rhs.as_ref(), par, stack);
        for c in 0..out.ncols() {
            for i in 0..out.nrows() {
                out[(i, c)] = out[(i, c)].conjugated();
            }
        }
    }
}

/// The eigenpairs nearest σ by shift-invert Krylov–Schur, in real arithmetic for a real
/// target and complex arithmetic otherwise.
fn sparse_eigenpairs(
    lin: &LinearSystem,
    sigma: c64,
    n_modes: usize,
) -> Result<(Vec<c64>, Vec<Vec<c64>>), EigenError> {
    if sigma.im == 0.0 {
        if symmetric_undamped(lin)
            && let Some(pairs) = lanczos_eigenpairs(lin, sigma.re, n_modes)?
        {
            return Ok(pairs);
        }
        krylov_schur::<f64>(lin, sigma, n_modes)
    } else {
        krylov_schur::<c64>(lin, sigma, n_modes)
    }
}

/// Width of the Lanczos blocks: the largest eigenvalue multiplicity found reliably (six
/// rigid-body modes of a free body).
const LANCZOS_BLOCK: usize = 6;

/// No damping or gyroscopic matrix, K and M symmetric, every unknown with mass: the
/// pencil is symmetric definite and [`super::lanczos`] applies.
fn symmetric_undamped(lin: &LinearSystem) -> bool {
    lin.damping.as_ref().val().iter().all(|v| *v == 0.0)
        && diagonal(&lin.mass).iter().all(|m| *m > 0.0)
        && is_symmetric(&lin.mass)
        && is_symmetric(&lin.stiffness)
}

/// `‖Ax − Aᵀx‖ ≤ 10⁻¹² ‖|A||x|‖` for a pseudo-random x (an asymmetry escapes this only
/// for x in a set of measure zero).
fn is_symmetric(a: &SparseColMat<usize, f64>) -> bool {
    let n = a.ncols();
    if a.nrows() != n {
        return false;
    }
    let x: Vec<f64> = (0..n)
        .map(|i| 1.0 + ((i as f64) * 0.618_033_988_749_895).fract())
        .collect();
    let (mut ax, mut atx, mut scale) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let r = a.as_ref();
    for j in 0..n {
        for (&i, &v) in r.row_idx_of_col_raw(j).iter().zip(r.val_of_col(j)) {
            ax[i] += v * x[j];
            atx[j] += v * x[i];
            scale[i] += v.abs() * x[j];
        }
    }
    let diff = ax
        .iter()
        .zip(&atx)
        .map(|(p, q)| (p - q).powi(2))
        .sum::<f64>();
    let size = scale.iter().map(|s| s * s).sum::<f64>();
    diff.is_finite() && diff <= 1e-24 * size
}

/// The modes of a symmetric definite pencil by block shift-invert Lanczos on
/// `(K − τM)⁻¹M`, τ = −σ² (the same factored matrix `K + σ²M` as the general path);
/// `None` when it does not converge, so the general path runs instead. Each κ = ω² is
/// returned as the pair λ = ±i√κ (±√−κ when κ < 0), as the companion form has it.
#[allow(clippy::type_complexity)]
fn lanczos_eigenpairs(
    lin: &LinearSystem,
    sigma: f64,
    n_modes: usize,
) -> Result<Option<(Vec<c64>, Vec<Vec<c64>>)>, EigenError> {
    let op = ShiftInvert::<f64>::new(lin, sigma)?;
    let (n, m) = (lin.n, lin.m);
    let tau = -sigma * sigma;
    let mass = &op.mass;
    let mut rhs = Mat::<f64>::zeros(n + m, 0);
    let mut pencil = super::lanczos::Pencil {
        n,
        dof: n.saturating_sub(m),
        apply: |x: MatRef<'_, f64>, mut y: MatMut<'_, f64>| {
            rhs.resize_with(n + m, x.ncols(), |_, _| 0.0);
            rhs.fill(0.0);
            for j in 0..x.ncols() {
                let col = rhs.col_mut(j).try_as_col_major_mut().expect("contiguous");
                spmv(
                    mass,
                    x.col(j).try_as_col_major().expect("contiguous").as_slice(),
                    1.0,
                    &mut col.as_slice_mut()[..n],
                );
            }
            op.lu.solve_in_place_with_conj(Conj::No, rhs.as_mut());
            y.copy_from(rhs.get(..n, ..));
        },
        mass: |x: MatRef<'_, f64>, mut y: MatMut<'_, f64>| {
            y.fill(0.0);
            for j in 0..x.ncols() {
                let mut col = y.as_mut().col_mut(j);
                let out = col.as_mut().try_as_col_major_mut().expect("contiguous");
                spmv(
                    mass,
                    x.col(j).try_as_col_major().expect("contiguous").as_slice(),
                    1.0,
                    out.as_slice_mut(),
                );
            }
        },
    };
    let Some(pairs) = super::lanczos::block_lanczos(
        &mut pencil,
        n_modes,
        LANCZOS_BLOCK,
        3 * n_modes + 10 * LANCZOS_BLOCK,
        1e-10,
    ) else {
        return Ok(None);
    };
    let (mut values, mut vectors) = (Vec::new(), Vec::new());
    for (c, nu) in pairs.nu.iter().enumerate() {
        let kappa = tau + 1.0 / nu;
        let y: Vec<c64> = (0..n)
            .map(|i| c64::new(pairs.vectors[(i, c)], 0.0))
            .collect();
        let lam = if kappa >= 0.0 {
            c64::new(0.0, kappa.sqrt())
        } else {
            c64::new((-kappa).sqrt(), 0.0)
        };
        values.push(lam);
        vectors.push(y.clone());
        values.push(if kappa >= 0.0 { lam.conj() } else { -lam });
        vectors.push(y);
    }
    Ok(Some((values, vectors)))
}

fn krylov_schur<T: Scalar>(
    lin: &LinearSystem,
    sigma: c64,
    n_modes: usize,
) -> Result<(Vec<c64>, Vec<Vec<c64>>), EigenError> {
    let op = ShiftInvert::<T>::new(lin, T::from_c64(sigma))?;
    let n = lin.n;
    let len = 2 * n;
    // Conjugate pairs and the double zero eigenvalues of rigid-body modes: twice the
    // modes, and a few more to see the pairs complete.
    let k = (2 * n_modes + 6).min(len);
    if len <= 2 * k + 20 {
        // The Krylov space would be the whole space (and Arnoldi breaks down early on the
        // tiny invariant subspaces of rigid-body Jordan blocks): form the operator.
        return Ok(explicit_eigenpairs(&op, sigma));
    }
    // Start in the range of the operator (so that B y = 0 and B v = 0 hold).
    let mut seed = 0x9e37_79b9_7f4a_7c15u64;
    let mut rnd = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((seed >> 11) as f64) / ((1u64 << 53) as f64) - 0.5
    };
    let x: Vec<T> = (0..len).map(|_| real(rnd())).collect();
    let mut work = Vec::with_capacity(n + lin.m);
    let mut tmp = vec![zero::<T>(); len];
    let mut v0 = vec![zero::<T>(); len];
    op.apply_one(&x, &mut tmp, &mut work);
    op.apply_one(&tmp, &mut v0, &mut work);
    let norm = v0.iter().map(|z| z.modulus().powi(2)).sum::<f64>().sqrt();
    if !(norm.is_finite() && norm > 0.0) {
        return Err(EigenError::Singular(
            "the shifted solve produced no finite vector".into(),
        ));
    }
    for z in &mut v0 {
        *z *= real::<T>(1.0 / norm);
    }
    let v0 = faer::ColRef::from_slice(&v0);
    let params = faer::matrix_free::eigen::PartialEigenParams {
        max_dim: (2 * k + 20).min(len),
        ..Default::default()
    };
    let par = Par::Seq;
    let mut vecs = Mat::<c64>::zeros(len, k);
    let mut vals = vec![c64::new(0.0, 0.0); k];
    let mut mem = faer::dyn_stack::MemBuffer::new(faer::matrix_free::eigen::partial_eigen_scratch(
        &op, k, par, params,
    ));
    let info = faer::matrix_free::eigen::partial_eigen(
        vecs.as_mut(),
        &mut vals,
        &op,
        v0,
        1e-11,
        par,
        faer::dyn_stack::MemStack::new(&mut mem),
        params,
    );
    let found = info.n_converged_eigen;
    let mut values = Vec::with_capacity(found);
    let mut vectors = Vec::with_capacity(found);
    for j in 0..found {
        let th = vals[j];
        if th.norm() == 0.0 {
            continue;
        }
        values.push(sigma + c64::new(1.0, 0.0) / th);
        vectors.push((0..n).map(|i| vecs[(i, j)]).collect());
    }
    Ok((values, vectors))
}

/// All eigenpairs of the operator formed column by column (small problems).
fn explicit_eigenpairs<T: Scalar>(op: &ShiftInvert<T>, sigma: c64) -> (Vec<c64>, Vec<Vec<c64>>) {
    let (n, len) = (op.n, 2 * op.n);
    let mut s = Mat::<T>::zeros(len, len);
    let mut e = vec![zero::<T>(); len];
    let mut col = vec![zero::<T>(); len];
    let mut work = Vec::new();
    for j in 0..len {
        e.fill(zero());
        e[j] = real(1.0);
        op.apply_one(&e, &mut col, &mut work);
        for i in 0..len {
            s[(i, j)] = col[i];
        }
    }
    let Ok(evd) = s.eigen() else {
        return (Vec::new(), Vec::new());
    };
    let (vals, vecs) = (evd.S().column_vector(), evd.U());
    let mut values = Vec::new();
    let mut vectors = Vec::new();
    for j in 0..len {
        let th: c64 = vals[j];
        // θ = 0: infinite λ, or directions outside the constrained space.
        if th.norm() <= 1e-12 * (1.0 / sigma.norm()) {
            continue;
        }
        values.push(sigma + c64::new(1.0, 0.0) / th);
        vectors.push((0..n).map(|i| vecs[(i, j)]).collect());
    }
    (values, vectors)
}

/// Scales `y` so that its component of largest modulus is 1.
fn normalize(y: &mut [c64]) {
    let (mut best, mut big) = (c64::new(1.0, 0.0), 0.0);
    for z in y.iter() {
        if z.norm() > big {
            big = z.norm();
            best = *z;
        }
    }
    if big > 0.0 {
        for z in y.iter_mut() {
            *z /= best;
        }
    }
}

/// One mode per conjugate pair (or real eigenvalue), rigid-body modes grouped, sorted by
/// distance to σ, the first `n_modes`.
fn select(
    values: Vec<c64>,
    vectors: Vec<Vec<c64>>,
    sigma: c64,
    n_modes: usize,
    n: usize,
    rigid_shapes: Option<Vec<Vec<f64>>>,
) -> Vec<Mode> {
    let zero = 1e-2 * sigma.re.abs();
    let mut rigid_vecs = Vec::new();
    let mut modes = Vec::new();
    for (lam, y) in values.into_iter().zip(vectors) {
        if lam.norm() <= zero {
            rigid_vecs.push(y);
        } else if lam.im >= -1e-9 * lam.norm() {
            let lam = if lam.im.abs() <= 1e-9 * lam.norm() {
                c64::new(lam.re, 0.0)
            } else {
                lam
            };
            modes.push(Mode {
                eigenvalue: lam,
                shape: y,
                rigid: false,
            });
        }
    }
    let mut out = match rigid_shapes {
        Some(shapes) => shapes
            .into_iter()
            .take(rigid_vecs.len().div_ceil(2))
            .map(|y| Mode {
                eigenvalue: c64::new(0.0, 0.0),
                shape: y.into_iter().map(|x| c64::new(x, 0.0)).collect(),
                rigid: true,
            })
            .collect(),
        None => rigid_modes(rigid_vecs, n),
    };
    out.extend(modes);
    out.sort_by(|a, b| {
        (a.eigenvalue - sigma)
            .norm()
            .total_cmp(&(b.eigenvalue - sigma).norm())
    });
    out.truncate(n_modes);
    for m in &mut out {
        normalize(&mut m.shape);
    }
    out
}

/// ⌈k/2⌉ orthonormal shapes spanning the k eigenvectors of zero eigenvalues.
fn rigid_modes(vecs: Vec<Vec<c64>>, n: usize) -> Vec<Mode> {
    let k = vecs.len();
    if k == 0 {
        return Vec::new();
    }
    let r = k.div_ceil(2);
    // Real and imaginary parts as real columns, then the leading left singular vectors.
    let mut a = nalgebra::DMatrix::<f64>::zeros(n, 2 * k);
    for (j, y) in vecs.iter().enumerate() {
        for i in 0..n {
            a[(i, 2 * j)] = y[i].re;
            a[(i, 2 * j + 1)] = y[i].im;
        }
    }
    if !a.iter().all(|x| x.is_finite()) {
        return Vec::new();
    }
    let svd = a.svd(true, false);
    let Some(u) = svd.u else {
        return Vec::new();
    };
    // Singular values in decreasing order.
    let mut order: Vec<usize> = (0..svd.singular_values.len()).collect();
    order.sort_by(|&i, &j| svd.singular_values[j].total_cmp(&svd.singular_values[i]));
    order
        .into_iter()
        .take(r)
        .map(|j| Mode {
            eigenvalue: c64::new(0.0, 0.0),
            shape: (0..n).map(|i| c64::new(u[(i, j)], 0.0)).collect(),
            rigid: true,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two identical fixed–free chains of `N` unit masses joined by springs k, each
    /// with its wall end a massive unknown held by a constraint: every frequency is
    /// double, `ω_j = 2√(k/m) sin((2j − 1)π / (2(2N + 1)))` (the discrete string).
    fn twin_chains(big: usize, k: f64) -> LinearSystem {
        let per = big + 1;
        let n = 2 * per;
        let (mut kt, mut mt, mut bt) = (Vec::new(), Vec::new(), Vec::new());
        for c in 0..2 {
            let o = c * per;
            for i in 0..per {
                mt.push(Triplet::new(o + i, o + i, 1.0));
            }
            for i in 0..big {
                let (a, b) = (o + i, o + i + 1);
                kt.push(Triplet::new(a, a, k));
                kt.push(Triplet::new(b, b, k));
                kt.push(Triplet::new(a, b, -k));
                kt.push(Triplet::new(b, a, -k));
            }
            bt.push(Triplet::new(c, o, 1.0));
        }
        let sq = |t: &[Triplet<usize, usize, f64>], r: usize| {
            SparseColMat::try_new_from_triplets(r, n, t).unwrap()
        };
        LinearSystem {
            n,
            m: 2,
            mass: sq(&mt, n),
            damping: sq(&[], n),
            stiffness: sq(&kt, n),
            constraint_jacobian: sq(&bt, 2),
            unknown_names: (0..n).map(|i| format!("y{i}")).collect(),
        }
    }

    /// Block Lanczos (the symmetric path) and Krylov–Schur on the companion form (the
    /// general path) find the same double frequencies, both against the closed form to
    /// the eigensolvers' residual tolerance (1e-10 relative, with margin).
    #[test]
    fn lanczos_and_krylov_schur_agree_with_the_discrete_string() {
        let (big, k) = (100, 1e4);
        let lin = twin_chains(big, k);
        assert!(symmetric_undamped(&lin));
        let opts = EigenOptions {
            n_modes: 12,
            ..Default::default()
        };
        let sigma = target(&lin, &opts);
        let (v, w) = lanczos_eigenpairs(&lin, sigma.re, 12)
            .unwrap()
            .expect("converges");
        let lanczos = select(v, w, sigma, 12, lin.n, None);
        let (v, w) = krylov_schur::<f64>(&lin, sigma, 12).unwrap();
        let arnoldi = select(v, w, sigma, 12, lin.n, None);
        assert_eq!(lanczos.len(), 12);
        assert_eq!(arnoldi.len(), 12);
        for (i, (a, b)) in lanczos.iter().zip(&arnoldi).enumerate() {
            let j = (i / 2 + 1) as f64;
            let exact =
                2.0 * k.sqrt() * ((2.0 * j - 1.0) * PI / (2.0 * (2 * big + 1) as f64)).sin();
            let (wa, wb) = (a.eigenvalue.im, b.eigenvalue.im);
            assert!(
                (wa - exact).abs() < 1e-8 * exact,
                "lanczos {i}: {wa} vs {exact}"
            );
            assert!(
                (wb - exact).abs() < 1e-8 * exact,
                "arnoldi {i}: {wb} vs {exact}"
            );
        }
        // A non-symmetric stiffness is sent to the general path.
        let mut lin = lin;
        let t = [Triplet::new(3usize, 4usize, 1.0)];
        let extra = SparseColMat::try_new_from_triplets(lin.n, lin.n, &t).unwrap();
        let mut all = Vec::new();
        combine(&[(&lin.stiffness, 1.0), (&extra, 1.0)], &mut all);
        lin.stiffness = SparseColMat::try_new_from_triplets(lin.n, lin.n, &all).unwrap();
        assert!(!symmetric_undamped(&lin));
    }
}
