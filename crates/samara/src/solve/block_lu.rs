//! TEMPORARY dense stand-in for the block LU (replaced by the block-sparse implementation).

use super::{BlockMatrix, BlockStructure, StructureError};
use faer::linalg::solvers::SolveCore;
use std::sync::Arc;

#[derive(Clone, Debug, thiserror::Error)]
#[error("singular pivot block {block}")]
pub struct SingularBlock {
    pub block: usize,
}

pub struct BlockLuSymbolic {
    n: usize,
}

impl BlockLuSymbolic {
    pub fn new(s: &BlockStructure) -> Result<Self, StructureError> {
        Ok(Self { n: s.dim() })
    }
}

pub struct BlockLu {
    sym: Arc<BlockLuSymbolic>,
    lu: Option<faer::linalg::solvers::PartialPivLu<f64>>,
}

impl BlockLu {
    pub fn new(sym: Arc<BlockLuSymbolic>) -> Self {
        Self { sym, lu: None }
    }
    pub fn factor(&mut self, a: &BlockMatrix) -> Result<(), SingularBlock> {
        let n = self.sym.n;
        let d = a.to_dense_rowmajor();
        let m = faer::Mat::<f64>::from_fn(n, n, |i, j| d[i * n + j]);
        self.lu = Some(m.partial_piv_lu());
        Ok(())
    }
    pub fn solve_in_place(&mut self, rhs: &mut [f64]) {
        let n = rhs.len();
        if let Some(lu) = &self.lu {
            lu.solve_in_place_with_conj(
                faer::Conj::No,
                faer::MatMut::from_column_major_slice_mut(rhs, n, 1),
            );
        }
    }
    pub fn solve_transpose_in_place(&mut self, rhs: &mut [f64]) {
        let n = rhs.len();
        if let Some(lu) = &self.lu {
            lu.solve_transpose_in_place_with_conj(
                faer::Conj::No,
                faer::MatMut::from_column_major_slice_mut(rhs, n, 1),
            );
        }
    }
}
