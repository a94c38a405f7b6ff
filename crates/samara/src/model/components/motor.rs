//! `[[motors]]`: a DC motor between a stator node (or the ground) and a rotor node about
//! an axis, driven by a voltage signal; its armature current is its state (kernel:
//! [`crate::elements::DcMotor`]).
//!
//! ```toml
//! [[motors]]
//! name = "drive"
//! node_a = "ground"            # stator (`ground` allowed)
//! node_b = "rotor"             # rotor
//! axis = [0.0, 0.0, 1.0]       # global, initial configuration; fixed in the stator
//! resistance = 1.0             # R [Ω]
//! inductance = 0.01            # L [H]
//! motor_constant = 0.1         # k [N m/A] = [V s/rad]
//! voltage = "supply"           # a signal [V]
//! # initial_current = 0.0      # [A]
//! ```

use super::{Build, ComponentKind};
use crate::core::NodeRef;
use crate::elements::DcMotor;
use crate::model::validate::{Checker, Entry};
use crate::model::{Located, Model};
use crate::tangent_check::{TangentCase, random_node};
use nalgebra::Vector3;
use schemars::JsonSchema;
use serde::Deserialize;

/// A DC motor.
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MotorInput {
    /// Unique name; state `<name>.current`, outputs `<name>.torque`, `.speed`, `.voltage`.
    pub name: Located<String>,
    /// Stator node (`ground` allowed).
    pub node_a: Located<String>,
    /// Rotor node.
    pub node_b: Located<String>,
    /// Rotation axis, global in the initial configuration, fixed in the stator.
    pub axis: [f64; 3],
    /// Armature resistance R [Ω], positive.
    pub resistance: f64,
    /// Armature inductance L [H], positive.
    pub inductance: f64,
    /// Motor constant k [N m/A] (torque constant = back-EMF constant), positive.
    pub motor_constant: f64,
    /// The signal giving the terminal voltage [V].
    pub voltage: Located<String>,
    /// Initial current [A] (default 0).
    #[serde(default)]
    pub initial_current: Option<f64>,
}

/// A validated motor.
#[derive(Clone, Debug)]
pub struct MotorDef {
    pub name: String,
    pub stator: NodeRef,
    pub rotor: usize,
    /// Global axis (initial configuration).
    pub axis: Vector3<f64>,
    pub resistance: f64,
    pub inductance: f64,
    pub constant: f64,
    pub voltage: String,
    pub initial_current: f64,
}

pub struct Motor;

impl ComponentKind for Motor {
    const NOUN: &'static str = "motor";
    type Input = MotorInput;
    type Def = MotorDef;

    fn name(input: &MotorInput) -> &Located<String> {
        &input.name
    }

    fn validate(s: &Located<MotorInput>, cx: &mut Checker, _model: &mut Model) -> Option<MotorDef> {
        let e = Entry {
            span: s.span.clone(),
        };
        let mi = &s.value;
        let what = format!("motor '{}'", mi.name.value);
        let mut ok = true;
        let stator = cx.node_ref(&mi.node_a, &what);
        let rotor = match cx.node_ref(&mi.node_b, &what) {
            Some(NodeRef::Node(i)) => Some(i),
            Some(NodeRef::Ground) => {
                cx.error(
                    format!("{what}: the rotor cannot be the ground"),
                    mi.node_b.span.clone(),
                    Some(
                        "node_b is the rotor's node; put the ground as node_a (the stator)".into(),
                    ),
                );
                None
            }
            None => None,
        };
        if let (Some(NodeRef::Node(a)), Some(b)) = (stator, rotor)
            && a == b
        {
            cx.error(
                format!("{what}: stator and rotor are the same node"),
                mi.node_b.span.clone(),
                Some("a motor turns its rotor relative to its stator: two different nodes".into()),
            );
            ok = false;
        }
        let axis = cx.unit_axis(mi.axis, &e, "axis", &what);
        for (key, v, hint) in [
            ("resistance", mi.resistance, "R [Ω] of the armature"),
            (
                "inductance",
                mi.inductance,
                "L [H] of the armature (its electrical time constant is L/R)",
            ),
            (
                "motor_constant",
                mi.motor_constant,
                "k [N m/A]: torque per ampere, also back-EMF per rad/s",
            ),
        ] {
            if !(v.is_finite() && v > 0.0) {
                cx.error(
                    format!("{what}: `{key}` must be positive (got {v})"),
                    cx.key(&e, key),
                    Some(hint.into()),
                );
                ok = false;
            }
        }
        let i0 = mi.initial_current.unwrap_or(0.0);
        if !i0.is_finite() {
            cx.error(
                format!("{what}: `initial_current` must be finite"),
                cx.key(&e, "initial_current"),
                Some("[A]".into()),
            );
            ok = false;
        }
        if !cx.signal_names.contains_key(&mi.voltage.value) {
            let known: Vec<String> = cx.signal_names.keys().cloned().collect();
            let hint = match cx.suggest(&mi.voltage.value, known.iter().map(|s| s.as_str())) {
                Some(b) => format!("did you mean '{b}'?"),
                None => {
                    "the voltage is a signal: from [[signals]] (a function of time) or a sensor"
                        .into()
                }
            };
            cx.error(
                format!("{what}: unknown signal '{}'", mi.voltage.value),
                mi.voltage.span.clone(),
                Some(hint),
            );
            ok = false;
        }
        let (stator, rotor, axis) = (stator?, rotor?, axis?);
        ok.then(|| MotorDef {
            name: mi.name.value.clone(),
            stator,
            rotor,
            axis,
            resistance: mi.resistance,
            inductance: mi.inductance,
            constant: mi.motor_constant,
            voltage: mi.voltage.value.clone(),
            initial_current: i0,
        })
    }

    fn nodes(def: &MotorDef) -> Vec<usize> {
        let mut v = vec![def.rotor];
        if let Some(a) = def.stator.index() {
            v.push(a);
        }
        v
    }

    fn build(def: &MotorDef, parts: &mut Build) {
        let (stator, axis) = match def.stator.index() {
            Some(a) => (Some(a), parts.initial[a].r().transpose() * def.axis),
            None => (None, def.axis),
        };
        parts.elements.push(Box::new(DcMotor::new(
            &def.name,
            stator,
            def.rotor,
            axis,
            def.resistance,
            def.inductance,
            def.constant,
            def.initial_current,
            &def.voltage,
        )));
    }

    fn tangent_cases() -> Vec<TangentCase> {
        let axis = Vector3::new(0.3, -0.5, 0.8).normalize();
        [Some(0), None]
            .into_iter()
            .enumerate()
            .map(|(k, stator)| {
                let e = DcMotor::new("m", stator, 1, axis, 1.3, 0.02, 0.4, 0.0, "v");
                TangentCase::element(
                    Box::new(e),
                    vec![random_node(960 + k as u64), random_node(965 + k as u64)],
                )
                .with_states(vec![(2.5, -7.0)])
                .with_signals(vec![12.0])
            })
            .collect()
    }
}
