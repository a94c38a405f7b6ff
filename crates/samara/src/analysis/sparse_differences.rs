//! Sparse forward-difference Jacobians by column groups (Curtis, Powell & Reid, "On the
//! estimation of sparse Jacobian matrices", IMA J. Appl. Math. 13, 1974): columns that
//! share no row of the pattern are perturbed together, so one residual evaluation gives
//! every column of a group. The groups come from a greedy distance-2 colouring; for a
//! model's step residual their number is bounded by the coupling of one node, not by the
//! model's size.

use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::sparse::{SparseColMat, SymbolicSparseColMat};

/// A sparsity pattern (compressed columns, sorted rows) and its column groups.
#[derive(Clone, Debug)]
pub(crate) struct ColumnGroups {
    n: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    /// Columns of each group, increasing.
    groups: Vec<Vec<usize>>,
    /// The unperturbed values of a group's columns (scratch).
    saved: Vec<f64>,
}

impl ColumnGroups {
    /// The pattern whose column j has the rows `rows_of[j]` (any order, duplicates
    /// allowed), and its groups.
    pub(crate) fn new(n: usize, mut rows_of: Vec<Vec<usize>>) -> Self {
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::new();
        col_ptr.push(0);
        for rows in &mut rows_of {
            rows.sort_unstable();
            rows.dedup();
            row_idx.extend_from_slice(rows);
            col_ptr.push(row_idx.len());
        }
        // Columns of each row, to find the columns sharing a row with j.
        let mut cols_of_row: Vec<Vec<usize>> = vec![Vec::new(); n];
        for (j, rows) in rows_of.iter().enumerate() {
            for &i in rows {
                cols_of_row[i].push(j);
            }
        }
        // Greedy colouring: each column takes the first group none of its
        // row-sharing columns is in (`mark[g] == j`: group g is taken for column j).
        let mut group_of = vec![usize::MAX; n];
        let mut mark: Vec<usize> = Vec::new();
        let mut groups: Vec<Vec<usize>> = Vec::new();
        for j in 0..n {
            for &i in &rows_of[j] {
                for &k in &cols_of_row[i] {
                    let g = group_of[k];
                    if g != usize::MAX {
                        mark[g] = j;
                    }
                }
            }
            let g = (0..groups.len())
                .find(|&g| mark[g] != j)
                .unwrap_or_else(|| {
                    groups.push(Vec::new());
                    mark.push(usize::MAX);
                    groups.len() - 1
                });
            group_of[j] = g;
            groups[g].push(j);
        }
        Self {
            n,
            col_ptr,
            row_idx,
            groups,
            saved: Vec::new(),
        }
    }

    /// Number of residual evaluations per Jacobian.
    pub(crate) fn n_groups(&self) -> usize {
        self.groups.len()
    }

    /// Entries of the pattern.
    pub(crate) fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// Forward differences at `u`, where the residual is `r0`:
    /// J_ij = (r_i(u + Σ_{k∈G} ε_k e_k) − r0_i)/ε_j for the columns j of each group G and
    /// the rows i of column j, with ε_j = 1e-7 (1 + |u_j|). `residual(u, r)` evaluates r
    /// at u; `u` is left as it came in. The values are in the pattern's order.
    pub(crate) fn jacobian(
        &mut self,
        u: &mut [f64],
        r0: &[f64],
        scratch: &mut [f64],
        values: &mut Vec<f64>,
        mut residual: impl FnMut(&[f64], &mut [f64]),
    ) {
        values.clear();
        values.resize(self.nnz(), 0.0);
        let eps = |x: f64| 1e-7 * (1.0 + x.abs());
        for g in &self.groups {
            self.saved.clear();
            self.saved.extend(g.iter().map(|&j| u[j]));
            for &j in g {
                u[j] += eps(u[j]);
            }
            residual(u, scratch);
            for (&j, &uj) in g.iter().zip(&self.saved) {
                let e = u[j] - uj;
                let range = self.col_ptr[j]..self.col_ptr[j + 1];
                for (v, &i) in values[range.clone()].iter_mut().zip(&self.row_idx[range]) {
                    *v = (scratch[i] - r0[i]) / e;
                }
                u[j] = uj;
            }
        }
    }

    /// The matrix of `values` (in the pattern's order) for faer.
    pub(crate) fn matrix(&self, values: &[f64]) -> SparseColMat<usize, f64> {
        let sym = SymbolicSparseColMat::new_checked(
            self.n,
            self.n,
            self.col_ptr.clone(),
            None,
            self.row_idx.clone(),
        );
        SparseColMat::new(sym, values.to_vec())
    }
}

/// Sparse LU of Jacobians on one pattern: the symbolic analysis (fill-reducing order) is
/// made once and reused.
#[derive(Default)]
pub(crate) struct PatternLu {
    symbolic: Option<SymbolicLu<usize>>,
}

impl PatternLu {
    /// The LU of `a`; `None` when faer finds it singular.
    pub(crate) fn factor(&mut self, a: &SparseColMat<usize, f64>) -> Option<Lu<usize, f64>> {
        if self.symbolic.is_none() {
            self.symbolic = SymbolicLu::try_new(a.symbolic()).ok();
        }
        let sym = self.symbolic.as_ref()?;
        Lu::try_new_with_symbolic(sym.clone(), a.as_ref()).ok()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::Conj;
    use faer::linalg::solvers::SolveCore;

    /// A tridiagonal pattern needs three groups however long it is, and the grouped
    /// differences of a residual with that pattern equal its exact Jacobian to the
    /// forward-difference error (ε |r''| ≈ 1e-7).
    #[test]
    fn banded_pattern_takes_three_groups_and_gives_the_jacobian() {
        let n: usize = 50;
        let rows: Vec<Vec<usize>> = (0..n)
            .map(|j| (j.saturating_sub(1)..(j + 2).min(n)).collect())
            .collect();
        let mut g = ColumnGroups::new(n, rows);
        assert_eq!(g.n_groups(), 3);
        assert_eq!(g.nnz(), 3 * n - 2);
        // r_i = u_i³ + sin(u_{i−1}) − 2 u_{i+1}.
        let residual = |u: &[f64], r: &mut [f64]| {
            for i in 0..n {
                r[i] = u[i].powi(3);
                if i > 0 {
                    r[i] += u[i - 1].sin();
                }
                if i + 1 < n {
                    r[i] -= 2.0 * u[i + 1];
                }
            }
        };
        let mut u: Vec<f64> = (0..n).map(|i| 0.1 * i as f64 - 2.0).collect();
        let u_in = u.clone();
        let mut r0 = vec![0.0; n];
        residual(&u, &mut r0);
        let mut scratch = vec![0.0; n];
        let mut values = Vec::new();
        g.jacobian(&mut u, &r0, &mut scratch, &mut values, residual);
        assert_eq!(u, u_in);
        let a = g.matrix(&values);
        for (j, &uj) in u.iter().enumerate() {
            for (&i, &v) in a.row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
                let exact = if i == j {
                    3.0 * uj * uj
                } else if i == j + 1 {
                    uj.cos()
                } else {
                    -2.0
                };
                assert!(
                    (v - exact).abs() < 1e-5 * (1.0 + exact.abs()),
                    "({i},{j}) {v} {exact}"
                );
            }
        }
        // The LU solves with it: J x = J·1 gives x = 1 to the differences' accuracy.
        let lu = PatternLu::default().factor(&a).unwrap();
        let mut b = vec![0.0; n];
        for j in 0..n {
            for (&i, &v) in a.row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
                b[i] += v;
            }
        }
        lu.solve_in_place_with_conj(
            Conj::No,
            faer::MatMut::from_column_major_slice_mut(&mut b, n, 1),
        );
        assert!(b.iter().all(|x| (x - 1.0).abs() < 1e-10), "{b:?}");
    }

    /// Columns coupled through one dense row all need groups of their own.
    #[test]
    fn a_dense_row_separates_every_column() {
        let n = 6;
        let rows: Vec<Vec<usize>> = (0..n).map(|j| vec![0, j]).collect();
        assert_eq!(ColumnGroups::new(n, rows).n_groups(), n);
    }
}
