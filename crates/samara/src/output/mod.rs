//! Results output.
//!
//! - `netcdf`: a dependency-free incremental NetCDF-3 (64-bit offset) writer;
//! - `results`: the layout of a samara results file, one per analysis, as a
//!   [`crate::analysis::Recorder`];
//! - `beam_vars`: the beams' sectional variables of a results file (models with beams);
//! - `state_vars`: element states and signals of a results file (models with them);
//! - `space`: a results file's projected size against its disk's free space (or the
//!   available memory);
//! - `reader`: reading results files back (metadata, variables, named channels);
//! - `span`: span-wise profiles of a lifting line's station outputs at one time;
//! - `vtk`: ParaView scenes (`.pvd` + binary `.vtu`, a ParaView script, mode animations)
//!   from a results file;
//! - `vtu`: the binary VTK XML UnstructuredGrid writer.

mod beam_vars;
pub mod netcdf;
mod reader;
mod results;
mod space;
mod span;
mod state_vars;
mod vtk;
pub mod vtu;

pub use reader::{Channel, ReadError, ResultsReader, VariableInfo};
pub use results::{FORMAT_VERSION, ResultsFile};
pub use space::{ResultsProjection, SpaceShortfall, Storage};
pub use span::SpanProfile;
pub use vtk::{VtkOptions, VtkSeries, write_vtk, write_vtk_with};
