//! `[[viscoelastic]]`: point-to-point viscoelastic elements; `type = "maxwell"`, a spring
//! in series with a damper whose stretch is the element's state (kernel:
//! [`crate::elements::Maxwell`]).

use super::spring::{line_ends, rest_length};
use super::{Build, ComponentKind};
use crate::core::NodeRef;
use crate::elements::Maxwell;
use crate::model::validate::{Checker, Entry};
use crate::model::{Located, Model};
use crate::tangent_check::{TangentCase, random_node};
use nalgebra::Vector3;
use schemars::JsonSchema;
use serde::Deserialize;

/// Viscoelastic laws.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ViscoelasticType {
    /// Spring k in series with damper c: tension k (l − l₀ − z), c ż = k (l − l₀ − z).
    Maxwell,
}

/// A point-to-point viscoelastic element between points on two nodes.
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ViscoelasticInput {
    /// Unique name; its state is written as `<name>.damper_stretch`.
    pub name: Located<String>,
    /// The law (`maxwell`).
    #[serde(rename = "type")]
    pub kind: ViscoelasticType,
    /// First node (`ground` allowed).
    pub node_a: Located<String>,
    /// Second node (`ground` allowed).
    pub node_b: Located<String>,
    /// Attachment point on node A, global, initial configuration [m]; default the node.
    #[serde(default)]
    pub point_a: Option<[f64; 3]>,
    /// Attachment point on node B, global, initial configuration [m]; default the node.
    #[serde(default)]
    pub point_b: Option<[f64; 3]>,
    /// Spring stiffness k [N/m], positive.
    pub stiffness: f64,
    /// Damper coefficient c [N s/m], positive.
    pub damping: f64,
    /// Rest length l₀ [m]; default: the initial distance between the points.
    #[serde(default)]
    pub rest_length: Option<f64>,
}

/// A validated viscoelastic element.
#[derive(Clone, Debug)]
pub struct ViscoelasticDef {
    pub name: String,
    pub node_a: NodeRef,
    pub node_b: NodeRef,
    pub point_a: Vector3<f64>,
    pub point_b: Vector3<f64>,
    pub stiffness: f64,
    pub damping: f64,
    pub rest_length: f64,
}

pub struct Viscoelastic;

impl ComponentKind for Viscoelastic {
    const NOUN: &'static str = "viscoelastic element";
    type Input = ViscoelasticInput;
    type Def = ViscoelasticDef;

    fn name(input: &ViscoelasticInput) -> &Located<String> {
        &input.name
    }

    fn validate(
        s: &Located<ViscoelasticInput>,
        cx: &mut Checker,
        model: &mut Model,
    ) -> Option<ViscoelasticDef> {
        let e = Entry {
            span: s.span.clone(),
        };
        let vi = &s.value;
        let what = format!("viscoelastic element '{}'", vi.name.value);
        let ends = line_ends(
            cx,
            &e,
            &what,
            [&vi.node_a, &vi.node_b],
            [vi.point_a, vi.point_b],
            model,
        );
        let mut ok = true;
        for (key, value) in [("stiffness", vi.stiffness), ("damping", vi.damping)] {
            if !(value.is_finite() && value > 0.0) {
                cx.error(
                    format!("{what}: `{key}` must be positive (got {value})"),
                    cx.key(&e, key),
                    Some("a Maxwell element is a spring (k > 0) in series with a damper (c > 0); without a damper use [[springs]]".into()),
                );
                ok = false;
            }
        }
        let (a, b, pa, pb) = ends?;
        let rest = rest_length(cx, &e, &what, vi.rest_length, (pb - pa).norm());
        ok.then(|| ViscoelasticDef {
            name: vi.name.value.clone(),
            node_a: a,
            node_b: b,
            point_a: pa,
            point_b: pb,
            stiffness: vi.stiffness,
            damping: vi.damping,
            rest_length: rest,
        })
    }

    fn nodes(def: &ViscoelasticDef) -> Vec<usize> {
        [def.node_a, def.node_b]
            .iter()
            .filter_map(|r| r.index())
            .collect()
    }

    fn build(def: &ViscoelasticDef, parts: &mut Build) {
        let element = Maxwell::new(
            &def.name,
            parts.local_offset(def.node_a, def.point_a),
            parts.local_offset(def.node_b, def.point_b),
            [def.point_a, def.point_b],
            def.stiffness,
            def.damping,
            def.rest_length,
        );
        parts.elements.push(Box::new(element));
    }

    fn tangent_cases() -> Vec<TangentCase> {
        (0..3u64)
            .map(|k| {
                let a = (k != 2).then_some((0, Vector3::new(0.1, -0.2, 0.05 * k as f64)));
                let e = Maxwell::new(
                    "m",
                    a,
                    Some((1, Vector3::new(-0.1, 0.3, 0.2))),
                    [Vector3::new(0.4, 0.2, -0.3), Vector3::zeros()],
                    1e4,
                    30.0,
                    0.5,
                );
                TangentCase::element(
                    Box::new(e),
                    vec![random_node(700 + k), random_node(710 + k)],
                )
                .with_states(vec![(0.02, 0.7)])
            })
            .collect()
    }
}
