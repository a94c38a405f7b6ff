//! Rotation and small linear-algebra kernels, scalar time functions, tabulated terrain,
//! and the kernels' copies compiled for wider instruction sets ([`isa`]).
//!
//! Pure functions only; everything here is independent of the model and of the analyses.

pub mod cayley;
pub mod dual;
pub mod height_field;
pub mod isa;
pub mod prefetch;
pub mod so3;
pub mod time_function;

pub use so3::{
    Rotation, exp_map, log_map, quaternion_from_matrix, skew, tangent_inverse, tangent_operator,
};
pub use time_function::TimeFunction;
