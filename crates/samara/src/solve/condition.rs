//! Condition-number estimates of the iteration matrix.
//!
//! Small systems (n ≤ [`EXACT_LIMIT`]): exact 2-norm condition number σ_max/σ_min from a
//! dense SVD. Larger ones: the 1-norm estimate ‖A‖₁·est(‖A⁻¹‖₁) of Hager (1984) as refined
//! by Higham (1988, "FORTRAN codes for estimating the one-norm…", Algorithm 4.1 with the
//! extra alternating-sign test vector), which needs solves with A and Aᵀ only.

use super::{BlockMatrix, LinearSolver};

/// Largest order for which the exact condition number is computed.
pub const EXACT_LIMIT: usize = 400;

/// Which condition number a value is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ConditionKind {
    Exact2Norm,
    Estimate1Norm,
}

/// κ₂(A) from the singular values of the dense matrix.
pub fn exact_2norm(a: &BlockMatrix) -> f64 {
    let n = a.structure.dim();
    let dense = a.to_dense_rowmajor();
    let m = faer::Mat::<f64>::from_fn(n, n, |i, j| dense[i * n + j]);
    match m.singular_values() {
        Ok(s) if !s.is_empty() => {
            let smax = s[0];
            let smin = s[s.len() - 1];
            if smin > 0.0 {
                smax / smin
            } else {
                f64::INFINITY
            }
        }
        _ => f64::NAN,
    }
}

/// Hager–Higham estimate of ‖A⁻¹‖₁ using the factorization held by `lin`.
pub fn inverse_norm1_estimate(lin: &mut LinearSolver, n: usize) -> f64 {
    if n == 0 {
        return 0.0;
    }
    let mut x = vec![1.0 / n as f64; n];
    let mut est = 0.0;
    let mut last_j = usize::MAX;
    for _ in 0..5 {
        let mut y = x.clone();
        lin.solve_in_place(&mut y);
        let new_est: f64 = y.iter().map(|v| v.abs()).sum();
        let mut z: Vec<f64> = y
            .iter()
            .map(|&v| if v >= 0.0 { 1.0 } else { -1.0 })
            .collect();
        lin.solve_transpose_in_place(&mut z);
        est = f64::max(est, new_est);
        let (j, zmax) =
            z.iter().enumerate().fold(
                (0, 0.0),
                |(bj, bv), (i, v)| if v.abs() > bv { (i, v.abs()) } else { (bj, bv) },
            );
        let ztx: f64 = z.iter().zip(&x).map(|(a, b)| a * b).sum();
        if zmax <= ztx || j == last_j {
            break;
        }
        last_j = j;
        x.fill(0.0);
        x[j] = 1.0;
    }
    // Alternating-sign vector: guards against the cases where the power iteration stalls.
    let mut b: Vec<f64> = (0..n)
        .map(|i| {
            let s = if i % 2 == 0 { 1.0 } else { -1.0 };
            s * (1.0 + i as f64 / (n.max(2) - 1) as f64)
        })
        .collect();
    lin.solve_in_place(&mut b);
    let alt = 2.0 * b.iter().map(|v| v.abs()).sum::<f64>() / (3.0 * n as f64);
    est.max(alt)
}

/// Condition number of `a`, whose factorization `lin` holds.
pub fn condition_number(a: &BlockMatrix, lin: &mut LinearSolver) -> (f64, ConditionKind) {
    let n = a.structure.dim();
    if n <= EXACT_LIMIT {
        (exact_2norm(a), ConditionKind::Exact2Norm)
    } else {
        (
            a.norm_1() * inverse_norm1_estimate(lin, n),
            ConditionKind::Estimate1Norm,
        )
    }
}
