//! Aerodynamics (docs/aerodynamics.md): airfoil tables, the wind field, quasi-steady BEM
//! induction, and the lifting-line station element.

pub mod airfoil;
pub mod bem;
pub mod dynamic_inflow;
pub mod hgm;
mod root_hint;
pub mod rotor_performance;
pub mod station;
pub mod turbsim;
pub mod unsteady;
pub mod wind;

pub use airfoil::{Airfoil, AirfoilError, Coefficients};
pub use bem::{BemRotor, Induction, StationFlow};
pub use dynamic_inflow::{PittPeters, RotorDisc};
pub use hgm::{Hgm, HgmCoefficients, HgmFlow};
pub use rotor_performance::{Performance, RotorGeometry, RotorPerformance};
pub use station::{AeroStation, Attachment, Inflow, MAX_NODES, Section};
pub use turbsim::{BtsError, FullField};
pub use unsteady::{AttachedFlow, OyeStall};
pub use wind::{Gust, Wind};
