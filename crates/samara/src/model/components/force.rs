//! `[[forces]]`: an applied force and moment on a node, dead or follower, scaled by a
//! time function and optionally by a signal — a controller's output or a sensor (kernel:
//! [`crate::elements::AppliedLoad`]).

use super::{Build, ComponentKind};
use crate::core::NodeRef;
use crate::elements::{AppliedLoad, LoadFrame};
use crate::math::TimeFunction;
use crate::model::input::*;
use crate::model::validate::{Checker, Entry};
use crate::model::{Located, Model};
use crate::tangent_check::{TangentCase, random_node};
use nalgebra::Vector3;
use schemars::JsonSchema;
use serde::Deserialize;

/// An applied force and/or moment on a node, scaled by a time function.
#[derive(Clone, Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ForceInput {
    /// Unique load name.
    pub name: Located<String>,
    /// The loaded node.
    pub node: Located<String>,
    /// Force vector [N], components in `frame`.
    #[serde(default)]
    pub force: Option<[f64; 3]>,
    /// Moment vector [N m], components in `frame`.
    #[serde(default)]
    pub moment: Option<[f64; 3]>,
    /// `global` (dead load, default) or `node` (follower load).
    #[serde(default)]
    pub frame: Option<LoadFrame>,
    /// Point of application of the force, global position in the initial configuration;
    /// it moves with the node. Default: the node.
    #[serde(default)]
    pub point: Option<[f64; 3]>,
    /// Time function multiplying force and moment; default constant 1.
    #[serde(default)]
    pub function: Option<Located<TimeFunctionInput>>,
    /// A signal multiplying force and moment as well (from `[[signals]]`, a sensor or a
    /// controller): the load is function(t) · signal · (force, moment).
    #[serde(default)]
    pub signal: Option<Located<String>>,
}

/// An applied force and moment on a node.
#[derive(Clone, Debug)]
pub struct LoadDef {
    pub name: String,
    pub node: usize,
    pub force: Vector3<f64>,
    pub moment: Vector3<f64>,
    pub frame: LoadFrame,
    /// Global point of application in the initial configuration.
    pub point: Vector3<f64>,
    pub function: TimeFunction,
    /// The signal multiplying the load, if any.
    pub signal: Option<String>,
}

pub struct Force;

impl ComponentKind for Force {
    /// The load at the mid-point time does its work over the step (docs/integrators.md).
    fn discrete_form(input: &ForceInput) -> Result<(), String> {
        match input.signal {
            None => Ok(()),
            Some(_) => Err("a force scaled by a `signal`".into()),
        }
    }
    const NOUN: &'static str = "force";
    type Input = ForceInput;
    type Def = LoadDef;

    fn name(input: &ForceInput) -> &Located<String> {
        &input.name
    }

    fn validate(
        f: &Located<Self::Input>,
        cx: &mut Checker,
        model: &mut Model,
    ) -> Option<Self::Def> {
        let _ = &model;
        let e = Entry {
            span: f.span.clone(),
        };
        let fi = &f.value;
        let what = format!("force '{}'", fi.name.value);
        let node = cx.node_ref(&fi.node, &what);
        if fi.force.is_none() && fi.moment.is_none() {
            cx.error(
                format!("{what}: give `force`, `moment`, or both"),
                e.span.clone(),
                None,
            );
        }
        let force = fi.force.unwrap_or([0.0; 3]);
        let moment = fi.moment.unwrap_or([0.0; 3]);
        cx.finite(&e, "force", &force, &what);
        cx.finite(&e, "moment", &moment, &what);
        let function = match &fi.function {
            Some(func) => cx.time_function(func, &what).unwrap_or_default(),
            None => TimeFunction::Constant(1.0),
        };
        if let Some(sig) = &fi.signal
            && !cx.signal_names.contains_key(&sig.value)
        {
            let known: Vec<String> = cx.signal_names.keys().cloned().collect();
            let hint = match cx.suggest(&sig.value, known.iter().map(|s| s.as_str())) {
                Some(b) => format!("did you mean '{b}'?"),
                None => "the factor is a signal: from [[signals]], a sensor or a controller".into(),
            };
            cx.error(
                format!("{what}: unknown signal '{}'", sig.value),
                sig.span.clone(),
                Some(hint),
            );
            return None;
        }
        match node {
            Some(NodeRef::Node(n)) => {
                let point = fi
                    .point
                    .map(Vector3::from)
                    .unwrap_or(model.nodes[n].position);
                cx.finite(&e, "point", point.as_slice(), &what);
                return Some(LoadDef {
                    name: fi.name.value.clone(),
                    node: n,
                    force: Vector3::from(force),
                    moment: Vector3::from(moment),
                    frame: fi.frame.unwrap_or_default(),
                    point,
                    function,
                    signal: fi.signal.as_ref().map(|s| s.value.clone()),
                });
            }
            Some(NodeRef::Ground) => {
                cx.error(
                    format!("{what}: a load on the ground has no effect"),
                    fi.node.span.clone(),
                    Some("apply it to a node".into()),
                );
            }
            None => {}
        }
        None
    }

    fn nodes(_def: &LoadDef) -> Vec<usize> {
        // A load gives a node no equation of its own.
        Vec::new()
    }

    fn build(def: &LoadDef, parts: &mut Build) {
        let n = &parts.initial[def.node];
        let element = AppliedLoad::new(
            &def.name,
            def.node,
            def.force,
            def.moment,
            def.frame,
            n.r().transpose() * (def.point - n.x),
            def.function.clone(),
        );
        let element = match &def.signal {
            Some(sig) => element.with_signal(sig),
            None => element,
        };
        parts.elements.push(Box::new(element));
    }

    fn tangent_cases() -> Vec<TangentCase> {
        // Each frame without and with a scaling signal.
        [
            (LoadFrame::Global, false),
            (LoadFrame::Node, false),
            (LoadFrame::Global, true),
            (LoadFrame::Node, true),
        ]
        .into_iter()
        .enumerate()
        .map(|(k, (frame, with_signal))| {
            let e = AppliedLoad::new(
                "force",
                0,
                Vector3::new(3.0, -1.0, 2.0),
                Vector3::new(0.5, 0.2, -0.7),
                frame,
                Vector3::new(0.3, -0.1, 0.2),
                TimeFunction::Constant(1.5),
            );
            if with_signal {
                TangentCase::element(
                    Box::new(e.with_signal("gain")),
                    vec![random_node(40 + k as u64)],
                )
                .with_signals(vec![-0.7])
            } else {
                TangentCase::element(Box::new(e), vec![random_node(40 + k as u64)])
            }
        })
        .collect()
    }
}
