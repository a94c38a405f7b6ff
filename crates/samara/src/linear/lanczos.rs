//! Block shift-invert Lanczos for the symmetric definite pencil of an undamped,
//! non-gyroscopic model,
//!
//! ```text
//!     K y = κ M y,   B y = 0,        κ = ω² = −λ²,
//! ```
//!
//! on the operator `S = (K − τM)⁻¹M` restricted to the constrained space (each
//! application is one saddle-point solve). S is self-adjoint in the M inner product, its
//! eigenvalues are `ν = 1/(κ − τ)` and the modes nearest the shift τ have the largest
//! |ν|. The Krylov basis is built a block of b vectors at a time, M-orthonormal, with full
//! re-orthogonalization by two passes of block classical Gram–Schmidt (matrix–matrix
//! products), and the Ritz pairs come from the Rayleigh quotient `T = QᵀMSQ` (Grimes,
//! Lewis & Simon 1994, "A shifted block Lanczos algorithm for solving sparse symmetric
//! generalized eigenproblems", SIAM J. Matrix Anal. Appl. 15(1)). A block of b vectors
//! finds eigenvalues of multiplicity up to b (the two bending planes of a symmetric
//! section, the six rigid-body modes of a free body), which a single-vector recurrence
//! finds only by round-off.
//!
//! The Ritz residual of a pair (ν, Qs) is `‖R s_b‖`, R the coefficients of the last
//! block's images on the next block and `s_b` the last-block part of s; a pair is
//! converged when that is at most `tol |ν|`.

use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatMut, MatRef, Par, Side};

/// The converged eigenvalues ν of S (largest |ν| first) and their M-orthonormal vectors.
pub struct RitzPairs {
    pub nu: Vec<f64>,
    pub vectors: Mat<f64>,
}

/// The problem: `apply(X, Y)` sets `Y = S X` (columns in the constrained space) and
/// `mass(X, Y)` sets `Y = M X`, for n × c blocks.
pub struct Pencil<A, B> {
    pub n: usize,
    /// Dimension of the constrained space (n − rank B).
    pub dof: usize,
    pub apply: A,
    pub mass: B,
}

/// The `want` eigenpairs of S of largest |ν|, with blocks of `block` vectors and at most
/// `max_vectors` basis vectors; `None` when they did not converge within that basis or
/// the M inner product is not positive on it (then another method must be used).
pub fn block_lanczos<A, B>(
    p: &mut Pencil<A, B>,
    want: usize,
    block: usize,
    max_vectors: usize,
    tol: f64,
) -> Option<RitzPairs>
where
    A: FnMut(MatRef<'_, f64>, MatMut<'_, f64>),
    B: FnMut(MatRef<'_, f64>, MatMut<'_, f64>),
{
    let n = p.n;
    let b = block.clamp(1, p.dof.max(1));
    let cap = max_vectors.min(p.dof);
    if want == 0 || want > cap || n == 0 {
        return None;
    }
    let mut basis = Basis {
        q: Mat::zeros(n, cap + b),
        mq: Mat::zeros(n, cap + b),
        k: 0,
        seed: 0x9e37_79b9_7f4a_7c15,
    };
    let mut t = Mat::<f64>::zeros(cap + b, cap + b);
    // The first block: S applied to random vectors (so it lies in the constrained space).
    let mut x = Mat::<f64>::zeros(n, b);
    basis.random(x.as_mut());
    let mut w = Mat::<f64>::zeros(n, b);
    (p.apply)(x.as_ref(), w.as_mut());
    basis.extend(w.as_mut(), b, p)?;
    let (mut start, mut end) = (0, basis.k);
    loop {
        let width = end - start;
        if width == 0 {
            return None;
        }
        let mut w = Mat::<f64>::zeros(n, width);
        (p.apply)(basis.q.get(.., start..end), w.as_mut());
        // Coefficients on every vector so far: column block of T.
        let c = basis.project(w.as_mut(), end);
        for j in 0..width {
            for i in 0..end {
                t[(i, start + j)] = c[(i, j)];
            }
        }
        for i in start..end {
            for j in 0..start {
                t[(i, j)] = t[(j, i)];
            }
            for j in start..i {
                let s = 0.5 * (t[(i, j)] + t[(j, i)]);
                t[(i, j)] = s;
                t[(j, i)] = s;
            }
        }
        // What is left of the images spans the next block: W = Q_next R.
        let room = (cap + b - end).min(b);
        let r = basis.extend(w.as_mut(), room, p)?;
        let added = basis.k - end;
        let complete = end >= p.dof || added == 0;
        // With less room than the block's width, R may miss part of the images.
        let trusted = room >= width;
        if end >= want {
            let tt = t.get(..end, ..end).to_owned();
            let evd = tt.self_adjoint_eigen(Side::Lower).ok()?;
            let (s, u) = (evd.S().column_vector(), evd.U());
            let mut order: Vec<usize> = (0..end).collect();
            order.sort_by(|&i, &j| s[j].abs().total_cmp(&s[i].abs()));
            let residual = |col: usize| -> f64 {
                let mut sum = 0.0;
                for a in 0..r.nrows() {
                    let mut x = 0.0;
                    for jj in 0..width {
                        x += r[(a, jj)] * u[(start + jj, col)];
                    }
                    sum += x * x;
                }
                sum.sqrt()
            };
            let converged = order[..want]
                .iter()
                .all(|&i| complete || (trusted && residual(i) <= tol * s[i].abs()));
            if converged {
                let mut sel = Mat::<f64>::zeros(end, want);
                for (c, &i) in order[..want].iter().enumerate() {
                    for a in 0..end {
                        sel[(a, c)] = u[(a, i)];
                    }
                }
                let mut vectors = Mat::<f64>::zeros(n, want);
                matmul(
                    vectors.as_mut(),
                    Accum::Replace,
                    basis.q.get(.., ..end),
                    sel.as_ref(),
                    1.0,
                    Par::Seq,
                );
                return Some(RitzPairs {
                    nu: order[..want].iter().map(|&i| s[i]).collect(),
                    vectors,
                });
            }
        }
        if complete || !trusted || basis.k > cap {
            return None;
        }
        (start, end) = (end, basis.k);
    }
}

/// An M-orthonormal basis Q (with MQ kept, so that projections are products).
struct Basis {
    q: Mat<f64>,
    mq: Mat<f64>,
    k: usize,
    seed: u64,
}

impl Basis {
    fn random(&mut self, mut x: MatMut<'_, f64>) {
        for j in 0..x.ncols() {
            for i in 0..x.nrows() {
                self.seed = self
                    .seed
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                x[(i, j)] = ((self.seed >> 11) as f64) / ((1u64 << 53) as f64) - 0.5;
            }
        }
    }

    /// Removes from W its components on the first `k` basis vectors (two passes of block
    /// Gram–Schmidt) and returns the coefficients `C = QᵀMW` (k × c).
    fn project(&self, mut w: MatMut<'_, f64>, k: usize) -> Mat<f64> {
        let mut c = Mat::<f64>::zeros(k, w.ncols());
        if k == 0 {
            return c;
        }
        let mut d = Mat::<f64>::zeros(k, w.ncols());
        for pass in 0..2 {
            let acc = if pass == 0 { &mut c } else { &mut d };
            matmul(
                acc.as_mut(),
                Accum::Replace,
                self.mq.get(.., ..k).transpose(),
                w.as_ref(),
                1.0,
                Par::Seq,
            );
            matmul(
                w.as_mut(),
                Accum::Add,
                self.q.get(.., ..k),
                acc.as_ref(),
                -1.0,
                Par::Seq,
            );
        }
        for j in 0..c.ncols() {
            for i in 0..k {
                c[(i, j)] += d[(i, j)];
            }
        }
        c
    }

    /// Appends to the basis the M-orthonormalized columns of W (already orthogonal to the
    /// basis), at most `room` of them, and returns R with `W = Q_new R`. Columns that
    /// vanish (an invariant subspace, or W of rank below its width) are replaced by
    /// random directions mapped through S, so the block keeps its width.
    fn extend<A, B>(
        &mut self,
        mut w: MatMut<'_, f64>,
        room: usize,
        p: &mut Pencil<A, B>,
    ) -> Option<Mat<f64>>
    where
        A: FnMut(MatRef<'_, f64>, MatMut<'_, f64>),
        B: FnMut(MatRef<'_, f64>, MatMut<'_, f64>),
    {
        let n = w.nrows();
        let first = self.k;
        let mut r = Mat::<f64>::zeros(room.max(1), w.ncols());
        let mut mw = Mat::<f64>::zeros(n, 1);
        // Reference sizes before any projection, for the vanishing test.
        let size: Vec<f64> = (0..w.ncols())
            .map(|j| {
                (p.mass)(w.as_ref().col(j).as_mat(), mw.as_mut());
                dot(w.as_ref().col(j).as_mat(), mw.as_ref()).max(0.0).sqrt()
            })
            .collect();
        for j in 0..w.ncols() {
            if self.k - first >= room {
                break;
            }
            let added = self.k - first;
            for _ in 0..2 {
                for a in 0..added {
                    let c = dot(
                        self.mq.get(.., first + a..first + a + 1),
                        w.as_ref().get(.., j..j + 1),
                    );
                    r[(a, j)] += c;
                    let qa = self.q.get(.., first + a..first + a + 1);
                    let mut wj = w.as_mut().get_mut(.., j..j + 1);
                    for i in 0..n {
                        wj[(i, 0)] -= c * qa[(i, 0)];
                    }
                }
            }
            (p.mass)(w.as_ref().get(.., j..j + 1), mw.as_mut());
            let norm2 = dot(w.as_ref().get(.., j..j + 1), mw.as_ref());
            if !norm2.is_finite() || norm2 < -1e-12 * size[j] * size[j] {
                // M is not positive on the Krylov space.
                return None;
            }
            let norm = norm2.max(0.0).sqrt();
            if norm > 1e-8 * size[j] && norm > 0.0 {
                let k = self.k;
                for i in 0..n {
                    self.q[(i, k)] = w[(i, j)] / norm;
                    self.mq[(i, k)] = mw[(i, 0)] / norm;
                }
                r[(added, j)] = norm;
                self.k += 1;
            }
        }
        // Keep the block width with fresh directions while the space allows.
        let mut tries = 0;
        while self.k - first < room && self.k < p.dof && tries < 3 * room {
            tries += 1;
            let mut x = Mat::<f64>::zeros(n, 1);
            self.random(x.as_mut());
            let mut v = Mat::<f64>::zeros(n, 1);
            (p.apply)(x.as_ref(), v.as_mut());
            (p.mass)(v.as_ref(), mw.as_mut());
            let size = dot(v.as_ref(), mw.as_ref()).max(0.0).sqrt();
            let k = self.k;
            self.project(v.as_mut(), k);
            (p.mass)(v.as_ref(), mw.as_mut());
            let norm2 = dot(v.as_ref(), mw.as_ref());
            if !norm2.is_finite() {
                return None;
            }
            let norm = norm2.max(0.0).sqrt();
            if norm > 1e-8 * size && norm > 0.0 {
                for i in 0..n {
                    self.q[(i, k)] = v[(i, 0)] / norm;
                    self.mq[(i, k)] = mw[(i, 0)] / norm;
                }
                self.k += 1;
            }
        }
        Some(r)
    }
}

fn dot(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> f64 {
    (0..a.nrows()).map(|i| a[(i, 0)] * b[(i, 0)]).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A diagonal pencil with a double eigenvalue: every κ found, the double one twice.
    #[test]
    fn finds_a_double_eigenvalue_of_a_diagonal_pencil() {
        let n = 400;
        // κ_i = i² for i ≥ 1, with κ = 4 appearing twice (entries 1 and 2).
        let kappa: Vec<f64> = (0..n)
            .map(|i| {
                if i == 2 {
                    4.0
                } else {
                    ((i + 1) * (i + 1)) as f64
                }
            })
            .collect();
        let mass: Vec<f64> = (0..n).map(|i| 1.0 + (i % 7) as f64).collect();
        let tau = -0.5;
        let mut p = Pencil {
            n,
            dof: n,
            apply: |x: MatRef<'_, f64>, mut y: MatMut<'_, f64>| {
                for j in 0..x.ncols() {
                    for i in 0..n {
                        // (K − τM)⁻¹ M with K = κ M.
                        y[(i, j)] = x[(i, j)] / (kappa[i] - tau);
                    }
                }
            },
            mass: |x: MatRef<'_, f64>, mut y: MatMut<'_, f64>| {
                for j in 0..x.ncols() {
                    for i in 0..n {
                        y[(i, j)] = mass[i] * x[(i, j)];
                    }
                }
            },
        };
        let got = block_lanczos(&mut p, 6, 3, 120, 1e-10).expect("converges");
        let mut k: Vec<f64> = got.nu.iter().map(|nu| tau + 1.0 / nu).collect();
        k.sort_by(f64::total_cmp);
        let expect = [1.0, 4.0, 4.0, 16.0, 25.0, 36.0];
        for (a, e) in k.iter().zip(expect) {
            assert!((a - e).abs() < 1e-8 * e, "{k:?}");
        }
    }
}
