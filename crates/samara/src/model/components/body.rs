//! `[[bodies]]`: a rigid body on a node (kernel: [`crate::elements::RigidBody`]).

use super::{Build, ComponentKind};
use crate::core::NodeRef;
use crate::elements::RigidBody;
use crate::model::validate::{Checker, Entry};
use crate::model::{Located, Model};
use crate::tangent_check::{TangentCase, random_node};
use nalgebra::{Matrix3, SymmetricEigen, Vector3};
use schemars::JsonSchema;
use serde::Deserialize;

/// A rigid body attached to a node.
#[derive(Clone, Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BodyInput {
    /// Unique body name.
    pub name: Located<String>,
    /// The node carrying the body.
    pub node: Located<String>,
    /// Mass [kg], positive.
    pub mass: f64,
    /// Inertia tensor about the centre of gravity, node-frame components [kg m²];
    /// symmetric positive definite.
    pub inertia: [[f64; 3]; 3],
    /// Centre of gravity relative to the node, node-frame components [m]; default zero.
    #[serde(default)]
    pub cg_offset: Option<[f64; 3]>,
}

/// A rigid body on a node.
#[derive(Clone, Debug)]
pub struct BodyDef {
    pub name: String,
    pub node: usize,
    pub mass: f64,
    /// About the CG, node-frame components.
    pub inertia: Matrix3<f64>,
    /// CG relative to the node, node-frame components.
    pub cg_offset: Vector3<f64>,
}

pub struct Body;

impl ComponentKind for Body {
    /// Simo & Wong's form about the centre of gravity, also with a `cg_offset`
    /// ([`crate::elements::RigidBody`]'s `discrete_residual`).
    fn discrete_form(_input: &BodyInput) -> Result<(), String> {
        Ok(())
    }
    const NOUN: &'static str = "body";
    type Input = BodyInput;
    type Def = BodyDef;

    fn name(input: &BodyInput) -> &Located<String> {
        &input.name
    }

    fn validate(
        b: &Located<Self::Input>,
        cx: &mut Checker,
        model: &mut Model,
    ) -> Option<Self::Def> {
        let _ = &model;
        let e = Entry {
            span: b.span.clone(),
        };
        let bi = &b.value;
        let what = format!("body '{}'", bi.name.value);
        let node = cx.node_ref(&bi.node, &what);
        if node == Some(NodeRef::Ground) {
            cx.error(format!("{what}: a body cannot be attached to the ground"), bi.node.span.clone(), Some("attach it to a node; fix the node to the ground with a `fixed` joint if it must not move".into()));
        }
        if !(bi.mass.is_finite() && bi.mass > 0.0) {
            cx.error(
                format!("{what}: mass must be positive (got {})", bi.mass),
                cx.key(&e, "mass"),
                Some("a massless attachment needs no body; give the mass in kg".into()),
            );
        }
        let inertia = Matrix3::from_fn(|i, j| bi.inertia[i][j]);
        cx.check_inertia(&inertia, &e, &what);
        let cg = bi.cg_offset.unwrap_or([0.0; 3]);
        cx.finite(&e, "cg_offset", &cg, &what);
        if let Some(NodeRef::Node(node)) = node {
            return Some(BodyDef {
                name: bi.name.value.clone(),
                node,
                mass: bi.mass,
                inertia: 0.5 * (inertia + inertia.transpose()),
                cg_offset: Vector3::from(cg),
            });
        }
        None
    }

    fn nodes(def: &BodyDef) -> Vec<usize> {
        vec![def.node]
    }

    fn build(def: &BodyDef, parts: &mut Build) {
        let body = RigidBody::new(&def.name, def.node, def.mass, def.inertia, def.cg_offset);
        parts.bodies.push(body.clone());
        parts.elements.push(Box::new(body));
    }

    fn tangent_cases() -> Vec<TangentCase> {
        let inertia = Matrix3::new(0.3, 0.02, -0.01, 0.02, 0.5, 0.03, -0.01, 0.03, 0.4);
        (0..3)
            .map(|k| {
                let body = RigidBody::new(
                    "body",
                    0,
                    2.5,
                    inertia,
                    Vector3::new(0.1, -0.2, 0.05 * k as f64),
                );
                TangentCase::element(Box::new(body), vec![random_node(10 + k)])
            })
            .collect()
    }
}

/// A body with a `cg_offset` whose node also carries another body or belongs to a beam
/// (its root, tip or a created `<beam>.<k>` node): `(body, the other inertia)`. The
/// energy-consistent integrators write such a node's kinematics for the body's CG, so it
/// must carry no other inertia.
pub fn offset_body_sharing_node(
    bodies: &[Located<BodyInput>],
    beams: &[Located<super::beam::input::BeamInput>],
) -> Option<(String, String)> {
    for b in bodies {
        let b = &b.value;
        if b.cg_offset.is_none_or(|c| c == [0.0; 3]) {
            continue;
        }
        let node = &b.node.value;
        if let Some(other) = bodies
            .iter()
            .find(|o| o.value.name.value != b.name.value && &o.value.node.value == node)
        {
            return Some((
                b.name.value.clone(),
                format!("body `{}`", other.value.name.value),
            ));
        }
        if let Some(beam) = beams.iter().find(|beam| {
            let beam = &beam.value;
            beam.root.as_ref().is_some_and(|r| &r.value == node)
                || beam.tip.as_ref().is_some_and(|t| &t.value == node)
                || node
                    .strip_prefix(&format!("{}.", beam.name.value))
                    .is_some_and(|k| k.parse::<usize>().is_ok())
        }) {
            return Some((
                b.name.value.clone(),
                format!("beam `{}`", beam.value.name.value),
            ));
        }
    }
    None
}

impl Checker<'_> {
    fn check_inertia(&mut self, j: &Matrix3<f64>, e: &Entry, what: &str) {
        let span = self.key(e, "inertia");
        if !j.iter().all(|x| x.is_finite()) {
            self.error(format!("{what}: inertia must be finite"), span, None);
            return;
        }
        let scale = j.abs().max().max(f64::MIN_POSITIVE);
        let asym = (j - j.transpose()).abs().max();
        if asym > 1e-9 * scale {
            self.error(
                format!("{what}: inertia is not symmetric (largest |Jᵢⱼ − Jⱼᵢ| = {asym:.3e})"),
                span,
                Some(
                    "give the full symmetric tensor about the CG; products of inertia appear twice"
                        .into(),
                ),
            );
            return;
        }
        let eig = SymmetricEigen::new(0.5 * (j + j.transpose())).eigenvalues;
        let min = eig.min();
        // Also rejects a NaN from an overflowing eigen-solve.
        if min.is_nan() || min <= 0.0 {
            self.error(
                format!("{what}: inertia is not positive definite (principal moments {:.4e}, {:.4e}, {:.4e})", eig[0], eig[1], eig[2]),
                span,
                Some("every principal moment of inertia of a rigid body must be positive".into()),
            );
            return;
        }
        let mut p = [eig[0], eig[1], eig[2]];
        p.sort_by(f64::total_cmp);
        if p[0] + p[1] < p[2] * (1.0 - 1e-9) {
            self.warning(
                format!("{what}: principal moments {:.4e}, {:.4e}, {:.4e} violate the triangle inequality (J₁ + J₂ ≥ J₃), so no real body has them", p[0], p[1], p[2]),
                span,
                None,
            );
        }
    }
}
