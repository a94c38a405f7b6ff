//! `[[springs]]`: a point-to-point spring-damper (kernel: [`crate::elements::SpringDamper`]).

use super::{Build, ComponentKind};
use crate::core::NodeRef;
use crate::elements::SpringDamper;
use crate::math::TimeFunction;
use crate::model::input::TimeFunctionInput;
use crate::model::validate::{Checker, Entry};
use crate::model::{Located, Model};
use crate::tangent_check::{TangentCase, random_node};
use nalgebra::Vector3;
use schemars::JsonSchema;
use serde::Deserialize;

/// A point-to-point spring-damper: tension k (l − l₀) + c l̇ along the line joining its points.
#[derive(Clone, Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SpringInput {
    /// Unique spring name.
    pub name: Located<String>,
    /// First node (`ground` allowed).
    pub node_a: Located<String>,
    /// Second node (`ground` allowed).
    pub node_b: Located<String>,
    /// Attachment point on node A, global position in the initial configuration [m];
    /// default: the node's position.
    #[serde(default)]
    pub point_a: Option<[f64; 3]>,
    /// Attachment point on node B, global position in the initial configuration [m];
    /// default: the node's position.
    #[serde(default)]
    pub point_b: Option<[f64; 3]>,
    /// Axial stiffness k [N/m], non-negative.
    pub stiffness: f64,
    /// Axial viscous damping c [N s/m], non-negative; default 0.
    #[serde(default)]
    pub damping: Option<f64>,
    /// Rest length l₀ [m]; default: the initial distance between the points.
    #[serde(default)]
    pub rest_length: Option<f64>,
    /// Time function f(t) multiplying the stiffness (k f(t)); default 1. A sine gives a
    /// periodically varying stiffness (Mathieu equation).
    #[serde(default)]
    pub stiffness_function: Option<Located<TimeFunctionInput>>,
}

/// A point-to-point spring-damper.
#[derive(Clone, Debug)]
pub struct SpringDef {
    pub name: String,
    pub node_a: NodeRef,
    pub node_b: NodeRef,
    /// Global attachment points in the initial configuration.
    pub point_a: Vector3<f64>,
    pub point_b: Vector3<f64>,
    pub stiffness: f64,
    pub damping: f64,
    pub rest_length: f64,
    /// f(t) of the stiffness (`None`: constant).
    pub stiffness_function: Option<TimeFunction>,
}

pub struct Spring;

impl ComponentKind for Spring {
    const NOUN: &'static str = "spring";
    type Input = SpringInput;
    type Def = SpringDef;

    /// The discrete gradient of k(l − l₀)²/2 (docs/integrators.md); a time-varying
    /// stiffness does work of its own.
    fn discrete_form(input: &SpringInput) -> Result<(), String> {
        match input.stiffness_function {
            None => Ok(()),
            Some(_) => Err("a spring with a `stiffness_function`".into()),
        }
    }

    fn name(input: &SpringInput) -> &Located<String> {
        &input.name
    }

    fn validate(
        s: &Located<SpringInput>,
        cx: &mut Checker,
        model: &mut Model,
    ) -> Option<SpringDef> {
        let e = Entry {
            span: s.span.clone(),
        };
        let si = &s.value;
        let what = format!("spring '{}'", si.name.value);
        let ends = line_ends(
            cx,
            &e,
            &what,
            [&si.node_a, &si.node_b],
            [si.point_a, si.point_b],
            model,
        );
        if !(si.stiffness.is_finite() && si.stiffness >= 0.0) {
            cx.error(
                format!("{what}: stiffness must be ≥ 0 (got {})", si.stiffness),
                cx.key(&e, "stiffness"),
                None,
            );
        }
        let damping = si.damping.unwrap_or(0.0);
        if !(damping.is_finite() && damping >= 0.0) {
            cx.error(
                format!("{what}: damping must be ≥ 0 (got {damping})"),
                cx.key(&e, "damping"),
                None,
            );
        }
        let stiffness_function = match &si.stiffness_function {
            Some(f) => Some(cx.time_function(f, &format!("{what} stiffness_function"))?),
            None => None,
        };
        let (a, b, pa, pb) = ends?;
        let rest = rest_length(cx, &e, &what, si.rest_length, (pb - pa).norm());
        Some(SpringDef {
            name: si.name.value.clone(),
            node_a: a,
            node_b: b,
            point_a: pa,
            point_b: pb,
            stiffness: si.stiffness,
            damping,
            rest_length: rest,
            stiffness_function,
        })
    }

    fn nodes(def: &SpringDef) -> Vec<usize> {
        [def.node_a, def.node_b]
            .iter()
            .filter_map(|r| r.index())
            .collect()
    }

    fn build(def: &SpringDef, parts: &mut Build) {
        let element = SpringDamper::new(
            &def.name,
            parts.local_offset(def.node_a, def.point_a),
            parts.local_offset(def.node_b, def.point_b),
            [def.point_a, def.point_b],
            def.stiffness,
            def.damping,
            def.rest_length,
        );
        let element = match &def.stiffness_function {
            Some(f) => element.with_stiffness_function(f.clone()),
            None => element,
        };
        parts.elements.push(Box::new(element));
    }

    fn tangent_cases() -> Vec<TangentCase> {
        let offsets = |k: u64| {
            (
                Vector3::new(0.1, 0.2, -0.1 * k as f64),
                Vector3::new(-0.2, 0.0, 0.1),
            )
        };
        (0..3)
            .map(|k| {
                let (sa, sb) = offsets(k);
                let a = (k != 2).then_some((0, sa));
                let e = SpringDamper::new(
                    "spring",
                    a,
                    Some((1, sb)),
                    [Vector3::new(0.5, -0.3, 0.2), Vector3::zeros()],
                    2e3,
                    15.0,
                    0.4,
                );
                // The third case with a time-varying stiffness (the check's time).
                let e = if k == 2 {
                    e.with_stiffness_function(TimeFunction::Sine {
                        amplitude: 0.4,
                        frequency: 1.3,
                        phase: 0.3,
                        offset: 0.9,
                        start: -1.0,
                    })
                } else {
                    e
                };
                TangentCase::element(Box::new(e), vec![random_node(20 + k), random_node(30 + k)])
            })
            .collect()
    }
}

/// The two ends of a point-to-point element: nodes (or the ground) and global points in
/// the initial configuration (default: the nodes' positions; required for the ground).
pub(super) fn line_ends(
    cx: &mut Checker,
    e: &Entry,
    what: &str,
    nodes: [&Located<String>; 2],
    points: [Option<[f64; 3]>; 2],
    model: &Model,
) -> Option<(NodeRef, NodeRef, Vector3<f64>, Vector3<f64>)> {
    let a = cx.node_ref(nodes[0], what);
    let b = cx.node_ref(nodes[1], what);
    let (Some(a), Some(b)) = (a, b) else {
        return None;
    };
    if a == b {
        cx.error(
            format!("{what} connects a node to itself"),
            nodes[1].span.clone(),
            Some("it needs two different nodes (or a node and 'ground')".into()),
        );
        return None;
    }
    let mut out = [Vector3::zeros(); 2];
    for (k, (r, key)) in [(a, "point_a"), (b, "point_b")].into_iter().enumerate() {
        out[k] = match (points[k], r) {
            (Some(p), _) => Vector3::from(p),
            (None, NodeRef::Node(i)) => model.nodes[i].position,
            (None, NodeRef::Ground) => {
                cx.error(
                    format!("{what}: the ground end needs `{key}`"),
                    e.span.clone(),
                    Some("give the global position of the anchor point".into()),
                );
                Vector3::zeros()
            }
        };
        cx.finite(e, key, out[k].as_slice(), what);
    }
    if (out[1] - out[0]).norm() < 1e-12 {
        cx.error(
            format!("{what}: its two points coincide, so its direction is undefined"),
            e.span.clone(),
            Some("give distinct `point_a` and `point_b`".into()),
        );
    }
    Some((a, b, out[0], out[1]))
}

/// `rest_length` (default: the initial length), checked.
pub(super) fn rest_length(
    cx: &mut Checker,
    e: &Entry,
    what: &str,
    given: Option<f64>,
    initial: f64,
) -> f64 {
    let rest = given.unwrap_or(initial);
    if !(rest.is_finite() && rest >= 0.0) {
        cx.error(
            format!("{what}: rest_length must be ≥ 0 (got {rest})"),
            cx.key(e, "rest_length"),
            None,
        );
    }
    rest
}
