//! The linear-solver facade used by the analyses.
//!
//! `Auto` factorizes with the block LU (no inter-block pivoting, symbolic analysis reused)
//! and falls back to faer's pivoting sparse LU for a factorization whose pivot block is
//! singular; `Block` and `SparseLu` force one of them.
//!
//! With the block LU, the matrix of [`LinearSolver::assembly_matrix`] is assembled straight
//! into the factor storage and factored there (no copy). The sparse LU needs the matrix
//! row-major: when the block LU rejects such a matrix, the matrix is switched to the
//! row-major layout and [`LinearSolver::needs_assembly`] asks for it to be assembled again.

use super::block_lu::{BlockLu, BlockLuSymbolic, SingularBlock};
use super::sparse_lu::SparseLu;
use super::{BlockMatrix, BlockStructure};
use schemars::JsonSchema;
use serde::Deserialize;
use std::sync::Arc;

/// Linear solver for the iteration matrix.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum LinearSolverType {
    /// Block LU without inter-block pivoting (fast; needs the augmented-Lagrangian term);
    /// falls back to the general sparse LU when a pivot block is singular.
    #[default]
    Auto,
    /// Block LU only.
    Block,
    /// General sparse LU with partial pivoting (faer).
    SparseLu,
}

/// Why a factorization failed.
#[derive(Clone, Debug, thiserror::Error)]
pub enum LinearError {
    /// The pivot block of this block (node or constraint) is singular, and the fallback
    /// (if any) failed too.
    #[error("the iteration matrix is singular at block {block}")]
    Singular { block: usize },
}

/// Counters for the run summary.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LinearStats {
    pub factorizations: usize,
    pub fallbacks: usize,
    pub solves: usize,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Active {
    None,
    Block,
    Sparse,
}

pub struct LinearSolver {
    kind: LinearSolverType,
    block: BlockLu,
    sparse: SparseLu,
    active: Active,
    /// The block whose singular pivot sent the current factorization to the sparse LU.
    fallback_from: Option<usize>,
    /// The last factorization failed on a matrix in the factor layout, now row-major and
    /// to be assembled again for the fallback.
    reassemble: bool,
    pub stats: LinearStats,
}

impl LinearSolver {
    /// Performs the symbolic analysis of `structure` (once per topology).
    pub fn new(structure: &BlockStructure, kind: LinearSolverType) -> Self {
        Self::with_parts(structure, kind, false)
    }

    /// [`Self::new`]; with `two_parts`, the block LU takes a separator order whenever the
    /// pattern has two parts ([`BlockLuSymbolic::two_parts`]).
    pub fn with_parts(structure: &BlockStructure, kind: LinearSolverType, two_parts: bool) -> Self {
        let symbolic = if two_parts {
            BlockLuSymbolic::two_parts(structure)
        } else {
            BlockLuSymbolic::new(structure)
        };
        let symbolic = Arc::new(symbolic.expect("structure built by the system is valid"));
        Self {
            kind,
            block: BlockLu::new(symbolic),
            sparse: SparseLu::default(),
            active: Active::None,
            fallback_from: None,
            reassemble: false,
            stats: LinearStats::default(),
        }
    }

    /// Whether the block LU factors and solves two parts on two threads (a separator order
    /// and more than one rayon thread; only from within rayon's pool).
    pub fn splits(&self) -> bool {
        self.block.symbolic().split().is_some() && rayon::current_num_threads() > 1
    }

    /// Per block, 0 or 1 for the parts of a separator order, 2 for the
    /// separator.
    pub fn block_parts(&self) -> Option<Vec<u8>> {
        let sym = self.block.symbolic();
        let [a, b] = sym.split()?;
        let n = sym.elimination_order().len();
        Some(
            (0..n)
                .map(|blk| {
                    let p = sym.position(blk);
                    if p < a {
                        0
                    } else if p < b {
                        1
                    } else {
                        2
                    }
                })
                .collect(),
        )
    }

    pub fn is_factored(&self) -> bool {
        self.active != Active::None
    }

    /// Forgets the current factorization (the next solve needs a new one).
    pub fn invalidate(&mut self) {
        self.active = Active::None;
    }

    /// A zero matrix to assemble the iteration matrix into: with the block LU, in its
    /// factor storage ([`LinearSolver::factor`] then factors it in place), else row-major.
    pub fn assembly_matrix(&self, structure: &Arc<BlockStructure>) -> BlockMatrix {
        match self.kind {
            LinearSolverType::SparseLu => BlockMatrix::zeros(structure.clone()),
            LinearSolverType::Block | LinearSolverType::Auto => {
                let sym = self.block.symbolic();
                BlockMatrix::with_placement(
                    structure.clone(),
                    sym.placement().clone(),
                    sym.n_factor_values(),
                    sym.n_input_values(),
                )
            }
        }
    }

    /// Whether the last [`LinearSolver::factor`] failed on a matrix assembled into the
    /// factor storage that the sparse LU may still factor: the matrix is row-major now and
    /// wants assembling again before the next `factor` (asked once; the matrix stays
    /// row-major).
    pub fn needs_assembly(&mut self) -> bool {
        std::mem::take(&mut self.reassemble)
    }

    /// Factors `a`: a row-major matrix is copied into the solver's storage and kept; one
    /// assembled into the block LU's factor storage ([`Self::assembly_matrix`]) is
    /// factored in place, and its values are garbage afterwards.
    pub fn factor(&mut self, a: &mut BlockMatrix) -> Result<(), LinearError> {
        self.active = Active::None;
        self.fallback_from = None;
        self.reassemble = false;
        if !a.is_row_major() {
            let r = self.block.factor_in_place(a.settled_values());
            return self.factored_in_place(a, r);
        }
        self.stats.factorizations += 1;
        let block_err = match self.kind {
            LinearSolverType::SparseLu => None,
            LinearSolverType::Block | LinearSolverType::Auto => match self.block.factor(a) {
                Ok(()) => {
                    self.active = Active::Block;
                    return Ok(());
                }
                Err(e) => Some(e.block),
            },
        };
        if self.kind == LinearSolverType::Block {
            return Err(LinearError::Singular {
                block: block_err.unwrap_or(0),
            });
        }
        if block_err.is_some() {
            self.stats.fallbacks += 1;
        }
        if self.sparse.factor(a) {
            self.active = Active::Sparse;
            self.fallback_from = block_err;
            Ok(())
        } else {
            Err(LinearError::Singular {
                block: block_err.unwrap_or(0),
            })
        }
    }

    /// [`Self::factor`] and [`Self::solve_in_place`] of `rhs` in one. For a matrix
    /// assembled into the block LU's factor storage, the forward substitution runs in the
    /// elimination's sweep ([`BlockLu::factor_in_place_and_solve`]; the same bits as the two
    /// calls). On an error `rhs` is garbage.
    pub fn factor_and_solve(
        &mut self,
        a: &mut BlockMatrix,
        rhs: &mut [f64],
    ) -> Result<(), LinearError> {
        if a.is_row_major() {
            self.factor(a)?;
            self.solve_in_place(rhs);
            return Ok(());
        }
        self.active = Active::None;
        self.fallback_from = None;
        self.reassemble = false;
        let r = self
            .block
            .factor_in_place_and_solve(a.settled_values(), rhs);
        if r.is_ok() {
            self.stats.solves += 1;
        }
        self.factored_in_place(a, r)
    }

    /// The outcome of a factorization of `a` in the block LU's factor storage.
    fn factored_in_place(
        &mut self,
        a: &mut BlockMatrix,
        r: Result<(), SingularBlock>,
    ) -> Result<(), LinearError> {
        match r {
            Ok(()) => {
                self.stats.factorizations += 1;
                self.active = Active::Block;
                Ok(())
            }
            Err(e) if self.kind == LinearSolverType::Block => {
                self.stats.factorizations += 1;
                Err(LinearError::Singular { block: e.block })
            }
            Err(e) => {
                // The fallback needs the matrix, which the elimination overwrote:
                // row-major from now on, assembled again by the caller.
                *a = BlockMatrix::zeros(a.structure.clone());
                self.reassemble = true;
                Err(LinearError::Singular { block: e.block })
            }
        }
    }

    /// The block whose pivot the block LU found singular, when the current factorization
    /// is the sparse-LU fallback for it: the suspect when a solve is not finite.
    pub fn fallback_block(&self) -> Option<usize> {
        (self.active == Active::Sparse)
            .then_some(self.fallback_from)
            .flatten()
    }

    /// Solves `A x = b` in place with the current factorization.
    pub fn solve_in_place(&mut self, rhs: &mut [f64]) {
        self.stats.solves += 1;
        match self.active {
            Active::Block => self.block.solve_in_place(rhs),
            Active::Sparse => self.sparse.solve_in_place(rhs),
            Active::None => rhs.fill(f64::NAN),
        }
    }

    /// Solves `Aᵀ x = b` in place.
    pub fn solve_transpose_in_place(&mut self, rhs: &mut [f64]) {
        match self.active {
            Active::Block => self.block.solve_transpose_in_place(rhs),
            Active::Sparse => self.sparse.solve_transpose_in_place(rhs),
            Active::None => rhs.fill(f64::NAN),
        }
    }
}
