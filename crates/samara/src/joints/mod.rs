//! Joints: the eq. 12 building blocks, the rows of each joint type (Table I), the joint
//! constraint and the elements on its coordinates. The contract is
//! [`crate::core::Constraint`].

pub mod building_blocks;
pub mod coordinate_loads;
mod joint;
pub mod rows;
pub mod spec;

pub use coordinate_loads::CoordinateLoads;
pub use joint::Joint;
pub use rows::{COMPONENT_NAMES, Row};
pub use spec::{BacklashDef, ComponentDef, ForceLaw, JointDef, JointType};

pub use crate::core::{Constraint, CoordinateTangents, RowRole};
