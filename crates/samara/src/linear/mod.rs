//! Linearized analyses: the small-motion equations about a state ([`linearize`]), their
//! eigenvalue problem ([`eigen`]) and the matrices written for users ([`matrix_market`]).

pub mod linearize;
pub mod matrix_market;

pub use linearize::{LinearSystem, SteadyRotation, linearize, unknown_names};

/// The sparse matrices of [`LinearSystem`] (compressed columns).
pub type SparseMatrix = faer::sparse::SparseColMat<usize, f64>;
pub mod eigen;
pub mod lanczos;
pub use eigen::{EigenMethod, EigenOptions, Mode, Spectrum, modes};
pub mod spin;
pub use spin::Spin;
pub mod floquet;
pub use floquet::{FloquetMode, Monodromy, monodromy};
