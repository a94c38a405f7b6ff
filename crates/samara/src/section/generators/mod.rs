//! Parametric sections: each generator returns a [`super::mesh::Mesh`] in the section
//! frame (origin at the generator's documented reference point), built from structured
//! patches of the chosen element type.

pub mod airfoil;
mod solid;
mod thin_walled;

pub use airfoil::{Airfoil, AirfoilError, SparCap, Surface, Web, airfoil};
pub use solid::{Circle, Rectangle, Tube, circle, rectangle, tube};
pub use thin_walled::{BoxSection, ISection, WallError, box_section, i_section};

use super::element::ElementKind;

/// One ply of a layup: material (index), thickness [m] and ply angle θ [rad].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ply {
    pub material: usize,
    pub thickness: f64,
    pub angle: f64,
}

/// Total thickness of a layup.
pub fn layup_thickness(plies: &[Ply]) -> f64 {
    plies.iter().map(|p| p.thickness).sum()
}

/// Depths (from the outer surface) of the grid lines through a layup with `per_ply`
/// elements per ply and element order `order`: `plies.len()·per_ply·order + 1` values, and
/// the ply index of every element row.
pub(crate) fn layup_grid(plies: &[Ply], per_ply: usize, order: usize) -> (Vec<f64>, Vec<usize>) {
    let mut depth = vec![0.0];
    let mut rows = Vec::new();
    let mut d0 = 0.0;
    for (k, p) in plies.iter().enumerate() {
        let m = per_ply * order;
        for i in 1..=m {
            depth.push(d0 + p.thickness * i as f64 / m as f64);
        }
        for _ in 0..per_ply {
            rows.push(k);
        }
        d0 += p.thickness;
    }
    (depth, rows)
}

/// Merge tolerance for a section of size `size`.
pub(crate) fn tolerance(size: f64) -> f64 {
    1e-9 * size.max(f64::MIN_POSITIVE)
}

/// Element options shared by the generators.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Meshing {
    pub kind: ElementKind,
}

impl Default for Meshing {
    fn default() -> Self {
        Self {
            kind: ElementKind::Quad8,
        }
    }
}
