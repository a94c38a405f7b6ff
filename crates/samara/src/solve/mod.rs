//! Linear and nonlinear solvers.
//!
//! - `block_matrix`, `block_lu`: the block-sparse iteration matrix and its LU without
//!   inter-block pivoting (constrained ordering: multipliers after their nodes), symbolic
//!   analysis once per topology;
//! - `sparse_lu`: faer's general sparse LU with partial pivoting, the fallback;
//! - `linear`: the facade the analyses use;
//! - `condition`: condition-number estimates of the factorized matrix;
//! - `newton`: the Newton–Raphson driver with convergence control;
//! - `partner`, `part_slice`: the second thread of a two-part iteration and the
//!   owner-checked handles through which the parts write shared slices.

mod block_lu;
mod block_matrix;
pub mod condition;
mod linear;
mod min_fill;
pub mod newton;
mod part_slice;
pub mod partner;
mod sparse_lu;

pub use block_lu::{BlockLu, BlockLuSymbolic, SPLIT_MIN_BLOCKS, SingularBlock};
pub use block_matrix::{
    BlockKind, BlockMatrix, BlockSlot, BlockStructure, BlockTarget, BlockView, StructureError,
};
pub use linear::{LinearError, LinearSolver, LinearSolverType, LinearStats};
pub use newton::{Correction, NewtonFailure, NewtonReport, NewtonSettings, NewtonSystem, newton};
pub use part_slice::PartSlice;
