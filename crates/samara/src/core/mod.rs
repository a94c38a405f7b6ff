//! The low layer everything builds on: the numbers of a system's state and the contracts
//! of its elements and constraints.

mod constraint;
mod discrete;
mod element;
mod state;

pub use constraint::{Constraint, CoordinateTangents, RowRole, RowTerms, ServoRow};
pub use discrete::{DiscreteStep, gonzalez_correction};
pub use element::{Element, ElementInput, EvalContext, LocalTerms, Need, SignalTerms, add_block};
pub use state::{Coordinate, ElementState, NodeState, PairBristle, State, remap_bristles};

/// Either the fixed inertial frame or one of the model's nodes (by index).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NodeRef {
    Ground,
    Node(usize),
}

impl NodeRef {
    pub fn index(self) -> Option<usize> {
        match self {
            NodeRef::Ground => None,
            NodeRef::Node(i) => Some(i),
        }
    }
}
