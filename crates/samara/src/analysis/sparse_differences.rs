//! Sparse forward-difference Jacobians by column groups (Curtis, Powell & Reid, "On the
//! estimation of sparse Jacobian matrices", IMA J. Appl. Math. 13, 1974): columns that
//! share no row of the pattern are perturbed together, so one residual evaluation gives
//! every column of a group. The groups come from a greedy distance-2 colouring; for a
//! model's step residual their number is bounded by the coupling of one node, not by the
//! model's size.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::sparse::linalg::lu::{NumericLu, SymbolicLu, factorize_symbolic_lu};
use faer::sparse::{SparseColMat, SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par};

/// A sparsity pattern (compressed columns, sorted rows), its column groups, and the
/// matrix on it that [`ColumnGroups::jacobian`] fills.
#[derive(Clone, Debug)]
pub(crate) struct ColumnGroups {
    /// The Jacobian's values on the pattern (allocated once).
    matrix: SparseColMat<usize, f64>,
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
        let nnz = row_idx.len();
        let sym = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        Self {
            matrix: SparseColMat::new(sym, vec![0.0; nnz]),
            groups,
            saved: Vec::new(),
        }
    }

    /// Number of residual evaluations per Jacobian.
    pub(crate) fn n_groups(&self) -> usize {
        self.groups.len()
    }

    /// Entries of the pattern.
    #[cfg(test)]
    pub(crate) fn nnz(&self) -> usize {
        self.matrix.val().len()
    }

    /// The Jacobian of the last [`ColumnGroups::jacobian`] (zero before the first).
    pub(crate) fn matrix(&self) -> SparseColMatRef<'_, usize, f64> {
        self.matrix.as_ref()
    }

    /// Forward differences at `u`, where the residual is `r0`:
    /// J_ij = (r_i(u + Σ_{k∈G} ε_k e_k) − r0_i)/ε_j for the columns j of each group G and
    /// the rows i of column j, with ε_j = 1e-7 (1 + |u_j|). `residual(u, r)` evaluates r
    /// at u; `u` is left as it came in. The values go to [`ColumnGroups::matrix`].
    pub(crate) fn jacobian(
        &mut self,
        u: &mut [f64],
        r0: &[f64],
        scratch: &mut [f64],
        mut residual: impl FnMut(&[f64], &mut [f64]),
    ) {
        let eps = |x: f64| 1e-7 * (1.0 + x.abs());
        let Self {
            matrix,
            groups,
            saved,
        } = self;
        let (pattern, values) = matrix.parts_mut();
        let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
        for g in groups.iter() {
            saved.clear();
            saved.extend(g.iter().map(|&j| u[j]));
            for &j in g {
                u[j] += eps(u[j]);
            }
            residual(u, scratch);
            for (&j, &uj) in g.iter().zip(saved.iter()) {
                let e = u[j] - uj;
                let range = col_ptr[j]..col_ptr[j + 1];
                for (v, &i) in values[range.clone()].iter_mut().zip(&row_idx[range]) {
                    *v = (scratch[i] - r0[i]) / e;
                }
                u[j] = uj;
            }
        }
    }
}

/// Sparse LU of Jacobians on one pattern: the symbolic analysis (fill-reducing order) is
/// made once; the numeric factors and the work space are reused, so refactoring and
/// solving allocate nothing once the first factorization has sized them.
#[derive(Default)]
pub(crate) struct PatternLu {
    symbolic: Option<SymbolicLu<usize>>,
    numeric: NumericLu<usize, f64>,
    work: Option<MemBuffer>,
    factored: bool,
}

impl PatternLu {
    /// Factors `a` (always on the same pattern); false when faer finds it singular (or
    /// cannot allocate), and then [`PatternLu::is_factored`] is false.
    pub(crate) fn factor(&mut self, a: SparseColMatRef<'_, usize, f64>) -> bool {
        self.factored = false;
        let par = Par::Seq;
        if self.symbolic.is_none() {
            let Ok(sym) = factorize_symbolic_lu(a.symbolic(), Default::default()) else {
                return false;
            };
            let req = StackReq::any_of(&[
                sym.factorize_numeric_lu_scratch::<f64>(par, Default::default()),
                sym.solve_in_place_scratch::<f64>(1, par),
            ]);
            let Ok(work) = MemBuffer::try_new(req) else {
                return false;
            };
            self.symbolic = Some(sym);
            self.work = Some(work);
        }
        let (Some(sym), Some(work)) = (&self.symbolic, &mut self.work) else {
            return false;
        };
        self.factored = sym
            .factorize_numeric_lu(
                &mut self.numeric,
                a,
                par,
                MemStack::new(work),
                Default::default(),
            )
            .is_ok();
        self.factored
    }

    /// Whether the last [`PatternLu::factor`] succeeded (and nothing forgot it since).
    pub(crate) fn is_factored(&self) -> bool {
        self.factored
    }

    /// Forgets the factors (the next use factors anew).
    pub(crate) fn forget(&mut self) {
        self.factored = false;
    }

    /// Solves A x = b in place with the last factors; false if there are none.
    pub(crate) fn solve_in_place(&mut self, b: &mut [f64]) -> bool {
        let (true, Some(sym), Some(work)) = (self.factored, &self.symbolic, &mut self.work) else {
            return false;
        };
        let n = b.len();
        // The numeric part is from `factorize_numeric_lu` on this symbolic analysis.
        let lu = faer::sparse::linalg::lu::LuRef::new_unchecked(sym, &self.numeric);
        lu.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(b, n, 1),
            Par::Seq,
            MemStack::new(work),
        );
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
        g.jacobian(&mut u, &r0, &mut scratch, residual);
        assert_eq!(u, u_in);
        let a = g.matrix();
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
        let mut lu = PatternLu::default();
        assert!(lu.factor(a));
        let mut b = vec![0.0; n];
        for j in 0..n {
            for (&i, &v) in a.row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
                b[i] += v;
            }
        }
        assert!(lu.solve_in_place(&mut b));
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
