//! Geometrically exact beam (Simo–Reissner; Hodges' GEBT) discretized with Legendre spectral
//! finite elements.
//!
//! Placeholder: see element.rs.
pub mod element;
pub mod gll;
pub mod kernel;
pub mod quaternion;
pub mod reference_line;
pub mod section;
