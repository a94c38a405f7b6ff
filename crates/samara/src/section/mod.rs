//! Cross-sectional analysis: the 6×6 stiffness and mass matrices of a beam section from a
//! 2-D finite-element model of the section (Giavotto et al. 1983 / ANBA, BECAS), in the
//! section convention of [`crate::elements::beam::section`] (docs/sections.md states it
//! once for all).
//!
//! - [`material`]: elastic materials and their rotation into the section frame;
//! - [`element`]: 3-, 6-node triangles and 4-, 8-, 9-node quadrilaterals;
//! - [`mesh`]: the mesh, its checks, and a builder for structured patches;
//! - [`generators`]: parametric sections (rectangle, circle, tube, box, I, airfoil);
//! - [`mesh_io`]: the text mesh format and Gmsh `.msh` v4 ASCII;
//! - [`warping`]: the warping problem and the Timoshenko-level compliance;
//! - [`properties`]: centres and principal axes;
//! - [`input`]: the `SECTION.toml` file; [`results`]: the files `samara section` writes and
//!   the cache; [`recovery`]: 3-D strain and stress from sectional forces.

pub mod element;
pub mod generators;
pub mod input;
pub mod material;
pub mod mesh;
pub mod mesh_io;
pub mod properties;
pub mod recovery;
pub mod results;
pub mod warping;

use crate::elements::beam::section::Section;
use material::Material;
use mesh::{BadElement, Mesh};
use nalgebra::Matrix6;
pub use properties::Properties;
pub use warping::SolveError;

/// A section ready to solve: a checked mesh and its materials.
#[derive(Clone, Debug)]
pub struct SectionModel {
    pub mesh: Mesh,
    pub materials: Vec<Material>,
}

impl SectionModel {
    /// Checks the mesh (renumbering clockwise elements) and the material references.
    pub fn new(mut mesh: Mesh, materials: Vec<Material>) -> Result<Self, Vec<BadElement>> {
        let mut bad = match mesh.check() {
            Ok(()) => Vec::new(),
            Err(b) => b,
        };
        for (k, e) in mesh.elements.iter().enumerate() {
            if e.material >= materials.len() {
                bad.push(BadElement {
                    element: k,
                    message: format!("refers to material {} which does not exist", e.material),
                });
            }
            if !(e.ply_angle.is_finite() && e.wall_angle.is_finite()) {
                bad.push(BadElement {
                    element: k,
                    message: "has a non-finite orientation angle".into(),
                });
            }
        }
        if bad.is_empty() {
            Ok(Self { mesh, materials })
        } else {
            Err(bad)
        }
    }
}

/// The solved section.
#[derive(Clone, Debug)]
pub struct SectionResult {
    /// `[N; M] = K [ε; κ]`, section frame, about the origin of the mesh coordinates.
    pub stiffness: Matrix6<f64>,
    /// `F = K⁻¹`.
    pub compliance: Matrix6<f64>,
    /// Mass per unit length about the origin.
    pub mass: Matrix6<f64>,
    pub properties: Properties,
    pub warping: warping::Warping,
}

impl SectionResult {
    /// The stiffness and mass as a beam section.
    pub fn section(&self) -> Section {
        Section {
            stiffness: self.stiffness,
            mass: self.mass,
        }
    }
}

/// Solves one section.
pub fn analyze(model: &SectionModel) -> Result<SectionResult, SolveError> {
    let w = warping::solve(&model.mesh, &model.materials)?;
    let s = warping::integrals(&model.mesh, &model.materials);
    let properties = properties::properties(&w.compliance, &s);
    Ok(SectionResult {
        stiffness: w.stiffness,
        compliance: w.compliance,
        mass: warping::mass_matrix(&s),
        properties,
        warping: w,
    })
}

/// Solves several sections (the stations of a blade) in parallel.
pub fn analyze_all(models: &[SectionModel]) -> Vec<Result<SectionResult, SolveError>> {
    use rayon::prelude::*;
    models.par_iter().map(analyze).collect()
}
