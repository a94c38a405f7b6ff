//! A beam as the system builds it: its nodes (shared or created), reference section
//! frames, sections, damping and loads.

use super::element::{DistributedLoad, Quadrature};
use super::section::SectionTable;
use crate::math::Rotation;

#[derive(Clone, Debug)]
pub struct BeamDef {
    pub name: String,
    pub order: usize,
    pub n_elements: usize,
    pub quadrature: Quadrature,
    /// Model node indices, root to tip (n_elements·order + 1).
    pub nodes: Vec<usize>,
    /// Normalized arc length η of each node.
    pub etas: Vec<f64>,
    /// Reference section frame at each node.
    pub sections0: Vec<Rotation>,
    pub table: SectionTable,
    pub damping: [f64; 6],
    pub loads: Vec<DistributedLoad>,
}

impl BeamDef {
    /// Node indices of element e.
    pub fn element_nodes(&self, e: usize) -> &[usize] {
        &self.nodes[e * self.order..=(e + 1) * self.order]
    }
}
