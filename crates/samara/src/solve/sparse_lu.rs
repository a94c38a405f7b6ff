//! General sparse LU with partial pivoting (faer), used when the block LU meets a singular
//! pivot block. The symbolic analysis is computed on first use and reused.

use super::BlockMatrix;
use faer::linalg::solvers::SolveCore;
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::{Conj, MatMut};

#[derive(Default)]
pub struct SparseLu {
    symbolic: Option<SymbolicLu<usize>>,
    lu: Option<Lu<usize, f64>>,
}

impl SparseLu {
    /// Factorizes `a`; `false` if faer reports a structural or numerical failure.
    pub fn factor(&mut self, a: &BlockMatrix) -> bool {
        let csc = a.to_faer_csc();
        if self.symbolic.is_none() {
            match SymbolicLu::try_new(csc.symbolic()) {
                Ok(s) => self.symbolic = Some(s),
                Err(_) => return false,
            }
        }
        let Some(sym) = &self.symbolic else {
            return false;
        };
        match Lu::try_new_with_symbolic(sym.clone(), csc.as_ref()) {
            Ok(lu) => {
                self.lu = Some(lu);
                true
            }
            Err(_) => {
                self.lu = None;
                false
            }
        }
    }

    pub fn solve_in_place(&self, rhs: &mut [f64]) {
        if let Some(lu) = &self.lu {
            let n = rhs.len();
            lu.solve_in_place_with_conj(Conj::No, MatMut::from_column_major_slice_mut(rhs, n, 1));
        }
    }

    pub fn solve_transpose_in_place(&self, rhs: &mut [f64]) {
        if let Some(lu) = &self.lu {
            let n = rhs.len();
            lu.solve_transpose_in_place_with_conj(
                Conj::No,
                MatMut::from_column_major_slice_mut(rhs, n, 1),
            );
        }
    }
}
