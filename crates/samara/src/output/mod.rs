//! Results output.
//!
//! - `netcdf`: a dependency-free incremental NetCDF-3 (64-bit offset) writer;
//! - `results`: the layout of a samara results file, one per analysis, as a
//!   [`crate::analysis::Recorder`].

pub mod netcdf;
mod results;

pub use results::{FORMAT_VERSION, ResultsFile};
