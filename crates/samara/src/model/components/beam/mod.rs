//! `[[beams]]`: geometrically exact beams (kernel: [`crate::elements::beam`]). Beams are
//! validated first: they create nodes that other components may name.

mod check;
pub mod input;

pub use check::CSV_COLUMNS;

use super::{Build, ComponentKind};
use crate::elements::beam::{Beam, BeamDef};
use crate::model::validate::Checker;
use crate::model::{AnalysisKind, Located, Model, ModelInput};
use crate::tangent_check::TangentCase;
use input::BeamInput;

pub struct BeamKind;

impl ComponentKind for BeamKind {
    /// Lumped inertia and a momentum-keeping discrete gradient of the strain energy
    /// (docs/integrators.md); written about the reference line, without distributed loads.
    fn discrete_form(input: &BeamInput) -> Result<(), String> {
        if !input.loads.is_empty() {
            return Err("a beam with distributed loads (`[[beams.loads]]`) has no energy-consistent discrete form yet: apply the loads at nodes with `[[forces]]`".into());
        }
        for s in &input.sections {
            let off_mass = s
                .value
                .mass
                .is_some_and(|m| m[5][1] != 0.0 || m[3][2] != 0.0 || m[4][0] != 0.0)
                || s.value
                    .isotropic
                    .as_ref()
                    .is_some_and(|i| i.mass_centre.is_some_and(|c| c != [0.0; 2]));
            if off_mass {
                return Err("a beam whose sections' mass centre is off the reference line has no energy-consistent discrete form yet (the lumped inertia is written about the reference line)".into());
            }
        }
        Ok(())
    }
    const NOUN: &'static str = "beam";
    type Input = BeamInput;
    type Def = BeamDef;

    fn name(input: &BeamInput) -> &Located<String> {
        &input.name
    }

    fn validate(b: &Located<BeamInput>, cx: &mut Checker, model: &mut Model) -> Option<BeamDef> {
        let mut map = std::mem::take(&mut cx.node_map);
        let def = cx.beam(b, model, &mut map);
        cx.node_map = map;
        def
    }

    fn finish(input: &ModelInput, cx: &mut Checker, model: &Model) {
        // A beam without `density` or `mass` is massless (right for statics); in a dynamic
        // analysis its nodes then need mass from elsewhere, or the run stops at once.
        if let Some(dynamic) = model
            .analyses
            .iter()
            .find(|a| matches!(a.kind, AnalysisKind::Dynamic(_)))
        {
            for b in &model.beams {
                if b.table
                    .sections
                    .iter()
                    .all(|s| s.mass.iter().all(|&x| x == 0.0))
                {
                    let span = input
                        .beams
                        .iter()
                        .find(|bi| bi.value.name.value == b.name)
                        .and_then(|bi| bi.value.name.span.clone());
                    cx.warning(
                        format!(
                            "beam '{}' has no mass (no `density` in `isotropic`, no `mass` matrix), and analysis '{}' is dynamic",
                            b.name, dynamic.name
                        ),
                        span,
                        Some("give the sections a density or a mass matrix; a massless beam only works where every node that can move carries a body".into()),
                    );
                }
            }
        }
    }

    fn nodes(def: &BeamDef) -> Vec<usize> {
        def.nodes.clone()
    }

    fn build(def: &BeamDef, parts: &mut Build) {
        let beam = Beam::build(def, parts.initial);
        for e in &beam.elements {
            parts.elements.push(Box::new(e.clone()));
        }
        parts.beams.push(beam);
    }

    fn tangent_cases() -> Vec<TangentCase> {
        // A curved, twisted beam of two order-3 elements with a coupled section, mass and
        // damping, checked at a deformed, moving state.
        let text = r#"[model]
name = "beam tangent case"
gravity = [0.0, 0.0, -9.81]
[[beams]]
name = "b"
order = 3
elements = 2
points = [[0.0, 0.0, 0.0], [0.6, 0.2, 0.1], [1.0, 0.5, 0.3]]
twist = [[0.0, 0.0], [1.0, 0.4]]
damping = [1e-3, 1e-3, 1e-3, 2e-3, 2e-3, 2e-3]
[[beams.sections]]
station = 0.0
isotropic = { E = 2e9, G = 8e8, A = 1e-3, I2 = 2e-7, I3 = 5e-7, J = 4e-7, shear_factors = [0.8, 0.7], density = 1500.0 }
[[beams.loads]]
force = [0.0, 10.0, -5.0]
frame = "section"
"#;
        let Ok(loaded) = Model::from_toml_str(text, "beam_case.toml") else {
            return Vec::new();
        };
        let model = loaded.model;
        let initial = crate::model::components::initial_nodes(&model);
        let mut build = Build::new(&initial);
        Self::build(&model.beams[0], &mut build);
        let mut nodes = initial.clone();
        for (k, n) in nodes.iter_mut().enumerate() {
            let r = crate::tangent_check::random_node(500 + k as u64);
            n.x += 0.02 * r.x;
            n.rot = n
                .rot
                .compose_exp(&(0.1 * crate::math::Rotation::identity().relative_log(&r.rot)));
            n.v = r.v;
            n.w = r.w;
            n.a = r.a;
            n.wd = r.wd;
        }
        build
            .elements
            .into_iter()
            .map(|e| TangentCase::element(e, nodes.clone()))
            .collect()
    }
}
