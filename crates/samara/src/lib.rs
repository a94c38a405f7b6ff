//! samara — flexible multibody dynamics.
//!
//! The flow of data reads top to bottom:
//! [`model`] (file → validated model) → [`system`] (elements, joints, unknown layout,
//! assembly) → [`analysis`] (statics, dynamics as stages; Newton and the integrators, using
//! [`solve`]) → [`output`] (results files).
//!
//! Layers, each importing only from the ones before it (no circular imports):
//!
//! 1. [`math`] (rotations, time functions, the kernels' compiled copies),
//!    [`diagnostics`] (located errors of input files), [`input_files`]; then [`solve`]
//!    (sparse and block linear solvers), which imports [`math`] only;
//! 2. [`core`]: node state, element states, the [`core::Element`] and
//!    [`core::Constraint`] traits every kernel implements;
//! 3. the kernels: [`elements`] (bodies, beams, springs, sensors, …) and [`joints`];
//!    [`section`] (cross-sectional analysis); [`tangent_check`] (the generic check of
//!    every kernel's tangents);
//! 4. [`model`]: the input file and its validation, one module per component kind in
//!    [`model::components`] (the registry);
//! 5. [`system`]: the system's unknowns and their assembly;
//! 6. [`analysis`]; 7. [`output`].
//!
//! ```no_run
//! use samara::model::Model;
//! use samara::system::System;
//! use samara::analysis::{History, run_analysis};
//!
//! let loaded = Model::from_file("examples/pendulum.toml")?;
//! let sys = System::new(&loaded.model);
//! let def = &loaded.model.analyses[0];
//! let initial = sys.initial_state();
//! let mut history = History::default();
//! let summary = run_analysis(&sys, def, initial, &mut history, &mut |_| {})?;
//! println!("{} steps, final time {}", summary.steps, history.last().unwrap().time);
//! # Ok::<(), samara::Error>(())
//! ```

pub mod analysis;
pub mod core;
pub mod diagnostics;
pub mod elements;
pub mod input_files;
pub mod joints;
pub mod linear;
pub mod math;
pub mod model;
pub mod output;
pub mod section;
pub mod solve;
pub mod system;
pub mod tangent_check;

use std::path::PathBuf;

/// Version written into results files.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// Everything that can go wrong in the library.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The model file is invalid (file, line, column, hint in each diagnostic).
    #[error(transparent)]
    Model(#[from] model::ModelError),
    /// A file could not be read or written.
    #[error("cannot {action} '{}': {source}", path.display())]
    Io {
        path: PathBuf,
        action: &'static str,
        #[source]
        source: std::io::Error,
    },
    /// An input file is not a readable text file (not regular, too large).
    #[error("cannot read '{}': {source}", path.display())]
    Input {
        path: PathBuf,
        #[source]
        source: input_files::InputFileError,
    },
    /// A results file could not be written.
    #[error("results file '{}': {message}", path.display())]
    Output { path: PathBuf, message: String },
    /// An analysis cannot start: the state its `start_from` names is not there.
    #[error("analysis '{analysis}': {message}")]
    Start { analysis: String, message: String },
}
