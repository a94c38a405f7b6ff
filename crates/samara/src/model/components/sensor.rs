//! `[[sensors]]`: a node quantity, a joint coordinate, an element state, an element output,
//! a joint reaction or a signal, through an optional first-order low-pass filter, producing
//! a signal named like the sensor (kernel: [`crate::elements::LowPassSensor`]).
//!
//! ```toml
//! [[sensors]]
//! name = "height"            # the signal it produces
//! node = "bob"               # a node quantity …
//! quantity = "position"      # position | velocity | acceleration | angular_velocity
//! component = "z"            # global component x | y | z
//! # joint = "hinge"          # … or a joint coordinate (active: something acts on it),
//! # coordinate = "theta3"    #   quantity position | velocity | acceleration
//! # state = "pump.current"   # … or an element state `<element>.<state>` (its value)
//! # output = "spring.tension" # … or an element output `<element>.<output>`, read in the
//! #                          #   same Newton iteration (derivatives by differences)
//! # joint = "hinge"          # … or a joint reaction, held from the converged solution:
//! # reaction = "force"       #   force | moment (frame A), with `component` x | y | z
//! # quantity = "force"       #   (or, with `coordinate`, the coordinate's generalized force)
//! # signal = "command"       # … or another signal
//! time_constant = 0.05       # τ [s] > 0; absent: no filter, s = g u (no state)
//! gain = 1.0                 # g (default 1)
//! # initial = 0.0            # z(0) of the filter; default g·u(0) for node position,
//! #                          # velocity and angular velocity (the sensor starts settled),
//! #                          # 0 otherwise
//! # sample_rate = 100.0      # zero-order hold: sampled at t_k = k/rate [Hz] and held
//! # sample_period = 0.01     #   until the next sample (or give the period T [s])
//! ```

use super::{Build, ComponentKind};
use crate::core::NodeRef;
use crate::elements::{LowPassSensor, NodeQuantity, SensorInput};
use crate::model::validate::{Checker, Entry};
use crate::model::{Located, Model};
use crate::tangent_check::{TangentCase, random_node};
use schemars::JsonSchema;
use serde::Deserialize;

/// Measured node quantities (global components).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum QuantityInput {
    /// Node position [m].
    Position,
    /// Node velocity [m/s].
    Velocity,
    /// Node acceleration [m/s²].
    Acceleration,
    /// Node angular velocity [rad/s].
    AngularVelocity,
    /// Generalized force on a joint coordinate [N or N m] (`joint_coordinate_force`).
    Force,
}

/// Joint reaction measured (`joint_force` or `joint_moment` of the results).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ReactionInput {
    Force,
    Moment,
}

/// Global component of a vector.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ComponentName {
    X,
    Y,
    Z,
}

/// A sensor with a first-order low-pass filter: τ ż + z = g u, output s = z.
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SensorEntry {
    /// Unique name; also the name of the signal the sensor produces.
    pub name: Located<String>,
    /// Measured node (with `quantity` and `component`).
    #[serde(default)]
    pub node: Option<Located<String>>,
    /// Measured quantity of the node.
    #[serde(default)]
    pub quantity: Option<QuantityInput>,
    /// Global component of the quantity.
    #[serde(default)]
    pub component: Option<ComponentName>,
    /// Measured signal (instead of a node quantity).
    #[serde(default)]
    pub signal: Option<Located<String>>,
    /// Measured joint (with `coordinate` and `quantity`).
    #[serde(default)]
    pub joint: Option<Located<String>>,
    /// Measured joint coordinate (d1, d2, d3, theta1, theta2, theta3).
    #[serde(default)]
    pub coordinate: Option<Located<String>>,
    /// Measured element state `<element>.<state>` (as written in the results).
    #[serde(default)]
    pub state: Option<Located<String>>,
    /// Measured element output `<element>.<output>` (as written in the results).
    #[serde(default)]
    pub output: Option<Located<String>>,
    /// Measured joint reaction (with `joint` and `component`), frame A.
    #[serde(default)]
    pub reaction: Option<ReactionInput>,
    /// Filter time constant τ [s], positive; absent: no filter.
    #[serde(default)]
    pub time_constant: Option<f64>,
    /// Gain g (default 1).
    #[serde(default)]
    pub gain: Option<f64>,
    /// Initial output z(0); see the module documentation for the default.
    #[serde(default)]
    pub initial: Option<f64>,
    /// Sample-and-hold rate [Hz]: the output is sampled at t_k = k/rate and held
    /// (zero-order hold). Exclusive with `sample_period`.
    #[serde(default)]
    pub sample_rate: Option<f64>,
    /// Sample-and-hold period T [s] (instead of `sample_rate`).
    #[serde(default)]
    pub sample_period: Option<f64>,
}

/// A validated sensor.
#[derive(Clone, Debug)]
pub struct SensorDef {
    pub name: String,
    pub input: SensorInput,
    /// τ > 0, or 0 without a filter.
    pub time_constant: f64,
    /// Where the entry is (for whole-model errors).
    pub span: Option<std::ops::Range<usize>>,
    /// The joint (name, component, its span) or element state (name, span) read, checked
    /// once the whole model is known.
    pub joint: Option<(String, String, Option<std::ops::Range<usize>>)>,
    pub state: Option<(String, Option<std::ops::Range<usize>>)>,
    /// The element output read (name, span), checked once the elements are known.
    pub output: Option<(String, Option<std::ops::Range<usize>>)>,
    /// The joint whose reaction is read (name, span): a held value.
    pub reaction: Option<(String, Option<std::ops::Range<usize>>)>,
    pub gain: f64,
    pub initial: f64,
    /// Sample period T [s] of a zero-order hold, if any.
    pub sample_period: Option<f64>,
}

pub struct Sensor;

impl ComponentKind for Sensor {
    const NOUN: &'static str = "sensor";
    type Input = SensorEntry;
    type Def = SensorDef;

    fn name(input: &SensorEntry) -> &Located<String> {
        &input.name
    }

    fn signals(input: &SensorEntry) -> Vec<String> {
        vec![input.name.value.clone()]
    }

    fn validate(
        s: &Located<SensorEntry>,
        cx: &mut Checker,
        model: &mut Model,
    ) -> Option<SensorDef> {
        let e = Entry {
            span: s.span.clone(),
        };
        let si = &s.value;
        let what = format!("sensor '{}'", si.name.value);
        let mut ok = true;
        let tau = si.time_constant.unwrap_or(0.0);
        if si.time_constant.is_some() && !(tau.is_finite() && tau > 0.0) {
            cx.error(
                format!("{what}: `time_constant` must be positive (got {tau})"),
                cx.key(&e, "time_constant"),
                Some("τ [s] of the filter τ ż + z = g u; a small τ follows u closely".into()),
            );
            ok = false;
        }
        let gain = si.gain.unwrap_or(1.0);
        let sample_period = match (si.sample_rate, si.sample_period) {
            (Some(_), Some(_)) => {
                cx.error(
                    format!("{what}: give `sample_rate` or `sample_period`, not both"),
                    cx.key(&e, "sample_period"),
                    Some("the period is 1/rate".into()),
                );
                ok = false;
                None
            }
            (Some(r), None) if !(r.is_finite() && r > 0.0 && (1.0 / r).is_normal()) => {
                cx.error(
                    format!("{what}: `sample_rate` must be positive and finite (got {r})"),
                    cx.key(&e, "sample_rate"),
                    Some("samples per second [Hz]; leave it out for a continuous sensor".into()),
                );
                ok = false;
                None
            }
            (None, Some(p)) if !(p.is_finite() && p > 0.0) => {
                cx.error(
                    format!("{what}: `sample_period` must be positive and finite (got {p})"),
                    cx.key(&e, "sample_period"),
                    Some(
                        "the time T [s] between samples; leave it out for a continuous sensor"
                            .into(),
                    ),
                );
                ok = false;
                None
            }
            (Some(r), None) => Some(1.0 / r),
            (None, p) => p,
        };
        let mut joint = None;
        let mut state = None;
        let mut output = None;
        let mut reaction = None;
        let joint_keys = si.joint.is_some() || si.coordinate.is_some() || si.reaction.is_some();
        let node_keys =
            si.node.is_some() || (!joint_keys && (si.component.is_some() || si.quantity.is_some()));
        let n_sources = [
            si.signal.is_some(),
            node_keys,
            joint_keys,
            si.state.is_some(),
            si.output.is_some(),
        ]
        .iter()
        .filter(|&&b| b)
        .count();
        let input = match (&si.signal, node_keys) {
            _ if n_sources != 1 => {
                cx.error(
                    format!("{what}: give exactly one of `signal`, `node` (with `quantity` and `component`), `joint` (with `coordinate` or `reaction`), `state` or `output`"),
                    e.span.clone(),
                    None,
                );
                return None;
            }
            _ if si.reaction.is_some() => {
                let kind = si.reaction?;
                let (Some(j), Some(c)) = (&si.joint, si.component) else {
                    cx.error(
                        format!("{what}: a reaction measurement needs `joint` and `component`"),
                        e.span.clone(),
                        Some("e.g. joint = \"hinge\", reaction = \"force\", component = \"z\" (frame A, as joint_force in the results)".into()),
                    );
                    return None;
                };
                if si.coordinate.is_some() || si.quantity.is_some() {
                    cx.error(
                        format!("{what}: `reaction` takes no `coordinate` or `quantity`"),
                        cx.key(&e, if si.coordinate.is_some() { "coordinate" } else { "quantity" }),
                        Some("the generalized force on a coordinate is `coordinate` with quantity = \"force\"".into()),
                    );
                    return None;
                }
                let prefix = match kind {
                    ReactionInput::Force => "joint_force",
                    ReactionInput::Moment => "joint_moment",
                };
                let comp = ["x", "y", "z"][c as usize];
                reaction = Some((j.value.clone(), j.span.clone()));
                SensorInput::Signal(format!("{prefix}:{}.{comp}", j.value))
            }
            _ if si.output.is_some() => {
                let o = si.output.as_ref()?;
                output = Some((o.value.clone(), o.span.clone()));
                SensorInput::Signal(format!("output:{}", o.value))
            }
            _ if joint_keys => {
                if si.component.is_some() {
                    cx.error(
                        format!("{what}: `component` is for node quantities and joint reactions"),
                        cx.key(&e, "component"),
                        Some("a joint coordinate is named by `coordinate` (d1 … theta3)".into()),
                    );
                    return None;
                }
                let (Some(j), Some(c)) = (&si.joint, &si.coordinate) else {
                    cx.error(
                        format!("{what}: a joint measurement needs `joint` and `coordinate`"),
                        e.span.clone(),
                        Some("e.g. joint = \"hinge\", coordinate = \"theta3\"".into()),
                    );
                    return None;
                };
                let prefix = match si.quantity.unwrap_or(QuantityInput::Position) {
                    QuantityInput::Position => "coordinate",
                    QuantityInput::Velocity => "coordinate_rate",
                    QuantityInput::Acceleration => "coordinate_acceleration",
                    QuantityInput::Force => {
                        reaction = Some((j.value.clone(), j.span.clone()));
                        "joint_coordinate_force"
                    }
                    QuantityInput::AngularVelocity => {
                        cx.error(
                            format!("{what}: a joint coordinate has no angular velocity"),
                            cx.key(&e, "quantity"),
                            Some(
                                "position, velocity, acceleration or force of the coordinate"
                                    .into(),
                            ),
                        );
                        return None;
                    }
                };
                joint = Some((j.value.clone(), c.value.clone(), j.span.clone()));
                SensorInput::Signal(format!("{prefix}:{}.{}", j.value, c.value))
            }
            _ if si.state.is_some() => {
                let st = si.state.as_ref()?;
                state = Some((st.value.clone(), st.span.clone()));
                SensorInput::Signal(format!("state:{}", st.value))
            }
            (Some(sig), false) => {
                if sig.value == si.name.value {
                    cx.error(
                        format!("{what} reads its own output"),
                        sig.span.clone(),
                        Some("a sensor filters another signal or a node quantity".into()),
                    );
                    return None;
                }
                if !cx.signal_names.contains_key(&sig.value) {
                    let known: Vec<String> = cx.signal_names.keys().cloned().collect();
                    let hint = match cx.suggest(&sig.value, known.iter().map(|s| s.as_str())) {
                        Some(b) => format!("did you mean '{b}'?"),
                        None => "signals come from [[signals]] and from sensors".into(),
                    };
                    cx.error(
                        format!("{what}: unknown signal '{}'", sig.value),
                        sig.span.clone(),
                        Some(hint),
                    );
                    return None;
                }
                SensorInput::Signal(sig.value.clone())
            }
            (None, true) => {
                let (Some(node), Some(q), Some(c)) = (&si.node, si.quantity, si.component) else {
                    cx.error(
                        format!(
                            "{what}: a node measurement needs `node`, `quantity` and `component`"
                        ),
                        e.span.clone(),
                        Some(
                            "e.g. node = \"bob\", quantity = \"position\", component = \"z\""
                                .into(),
                        ),
                    );
                    return None;
                };
                let node = match cx.node_ref(node, &what)? {
                    NodeRef::Node(i) => i,
                    NodeRef::Ground => {
                        cx.error(
                            format!("{what}: the ground does not move"),
                            node.span.clone(),
                            Some("measure a node".into()),
                        );
                        return None;
                    }
                };
                let i = c as usize;
                let quantity = match q {
                    QuantityInput::Position => NodeQuantity::Position(i),
                    QuantityInput::Velocity => NodeQuantity::Velocity(i),
                    QuantityInput::Acceleration => NodeQuantity::Acceleration(i),
                    QuantityInput::AngularVelocity => NodeQuantity::AngularVelocity(i),
                    QuantityInput::Force => {
                        cx.error(
                            format!("{what}: a node has no `force` quantity"),
                            cx.key(&e, "quantity"),
                            Some("forces are read from an element's `output` or a joint's `reaction`".into()),
                        );
                        return None;
                    }
                };
                SensorInput::Node { node, quantity }
            }
            _ => {
                cx.error(
                    format!("{what}: give either `signal` or `node`, `quantity` and `component`"),
                    e.span.clone(),
                    None,
                );
                return None;
            }
        };
        // Settled start: z(0) = g u(0) where u(0) is known from the initial conditions.
        let settled = match &input {
            SensorInput::Node { node, quantity } => {
                let n = &model.nodes[*node];
                match *quantity {
                    NodeQuantity::Position(i) => n.position[i],
                    NodeQuantity::Velocity(i) => n.velocity[i],
                    NodeQuantity::AngularVelocity(i) => n.angular_velocity[i],
                    NodeQuantity::Acceleration(_) => 0.0,
                }
            }
            SensorInput::Signal(_) => 0.0,
        };
        let initial = si.initial.unwrap_or(gain * settled);
        ok.then(|| SensorDef {
            name: si.name.value.clone(),
            input,
            time_constant: tau,
            span: s.span.clone(),
            joint,
            state,
            output,
            reaction,
            gain,
            initial,
            sample_period,
        })
    }

    /// Joint coordinates and element states read by sensors exist (the joints and the
    /// elements' states are known once every kind is validated).
    fn finish(_input: &super::ModelInput, cx: &mut Checker, model: &Model) {
        use crate::joints::{COMPONENT_NAMES, JointType};
        for s in &model.sensors {
            let what = format!("sensor '{}'", s.name);
            if let Some((jn, span)) = &s.reaction {
                // A coordinate's joint is checked with the coordinate below.
                reaction_checks(cx, model, &what, jn, span, s.joint.is_none());
            }
            let Some((jn, comp, span)) = &s.joint else {
                continue;
            };
            let Some(j) = model.joints.iter().find(|j| &j.name == jn) else {
                let names: Vec<&str> = model.joints.iter().map(|j| j.name.as_str()).collect();
                let hint = match cx.suggest(jn, names.iter().copied()) {
                    Some(b) => format!("did you mean '{b}'?"),
                    None => "name a joint of the model".into(),
                };
                cx.error(
                    format!("{what}: unknown joint '{jn}'"),
                    span.clone(),
                    Some(hint),
                );
                continue;
            };
            let Some(c) = COMPONENT_NAMES.iter().position(|n| n == comp) else {
                cx.error(
                    format!("{what}: unknown coordinate '{comp}'"),
                    span.clone(),
                    Some(format!("one of {}", COMPONENT_NAMES.join(", "))),
                );
                continue;
            };
            let active = matches!(j.kind, JointType::Screw | JointType::Prescribed)
                || j.components[c].as_ref().is_some_and(|d| {
                    d.spring.is_some()
                        || d.damper.is_some()
                        || d.backlash.is_some()
                        || d.drive.is_some()
                        || d.drive_signal.is_some()
                        || d.input.is_some()
                });
            if !active {
                cx.error(
                    format!("{what}: coordinate '{comp}' of joint '{jn}' is passive (nothing acts on it)"),
                    span.clone(),
                    Some(format!("sensors read active coordinates: give [joints.{comp}] a spring, damper, drive or input")),
                );
            }
        }
        let wanted: Vec<&SensorDef> = model
            .sensors
            .iter()
            .filter(|s| s.state.is_some() || s.output.is_some())
            .collect();
        if wanted.is_empty()
            || cx
                .diags
                .iter()
                .any(|d| d.severity == crate::model::Severity::Error)
        {
            return;
        }
        // The elements' state names, as the system will write them.
        let initial = super::initial_nodes(model);
        let mut parts = Build::new(&initial);
        super::build_all(model, &mut parts);
        let names: Vec<String> = parts
            .elements
            .iter()
            .flat_map(|e| {
                let n = e.name().to_string();
                e.state_names().into_iter().map(move |s| format!("{n}.{s}"))
            })
            .collect();
        let outputs: Vec<(String, Vec<String>)> = parts
            .elements
            .iter()
            .map(|e| {
                let o = e.output_names().into_iter().map(|(o, _)| o).collect();
                (e.name().to_string(), o)
            })
            .collect();
        for s in &wanted {
            if let Some((o, span)) = &s.output {
                output_check(cx, &s.name, o, span, &outputs);
            }
        }
        for s in wanted {
            let Some((st, span)) = &s.state else { continue };
            if !names.contains(st) {
                let hint = match cx.suggest(st, names.iter().map(|s| s.as_str())) {
                    Some(b) => format!("did you mean '{b}'?"),
                    None => "element states are named `<element>.<state>`, as in the results' element_state names".into(),
                };
                cx.error(
                    format!("sensor '{}': unknown element state '{st}'", s.name),
                    span.clone(),
                    Some(hint),
                );
            }
        }
    }

    fn nodes(_def: &SensorDef) -> Vec<usize> {
        // A sensor applies no force: it gives its node no equation.
        Vec::new()
    }

    fn build(def: &SensorDef, parts: &mut Build) {
        let sensor = LowPassSensor::new(
            &def.name,
            &def.name,
            def.input.clone(),
            def.time_constant,
            def.gain,
            def.initial,
        );
        parts.elements.push(Box::new(match def.sample_period {
            Some(period) => sensor.sampled(period),
            None => sensor,
        }));
    }

    fn tangent_cases() -> Vec<TangentCase> {
        let quantities = [
            NodeQuantity::Position(0),
            NodeQuantity::Velocity(1),
            NodeQuantity::Acceleration(2),
            NodeQuantity::AngularVelocity(0),
            NodeQuantity::AngularVelocity(2),
        ];
        let mut out: Vec<TangentCase> = quantities
            .iter()
            .enumerate()
            .map(|(k, &q)| {
                let e = LowPassSensor::new(
                    "s",
                    "s",
                    SensorInput::Node {
                        node: 0,
                        quantity: q,
                    },
                    0.05,
                    2.5,
                    0.0,
                );
                TangentCase::element(Box::new(e), vec![random_node(600 + k as u64)])
                    .with_states(vec![(0.3, -1.1)])
            })
            .collect();
        // Without a filter: the measurement itself, scaled.
        for (k, &q) in quantities.iter().enumerate() {
            let e = LowPassSensor::new(
                "s",
                "s",
                SensorInput::Node {
                    node: 0,
                    quantity: q,
                },
                0.0,
                -1.7,
                0.0,
            );
            out.push(TangentCase::element(
                Box::new(e),
                vec![random_node(620 + k as u64)],
            ));
        }
        let e = LowPassSensor::new("s", "s", SensorInput::Signal("u".into()), 0.0, 2.0, 0.0);
        out.push(TangentCase::element(Box::new(e), Vec::new()).with_signals(vec![0.3]));
        // Sampled: a held value is a constant within the step; with nothing held (statics)
        // the hold passes the filter's output or the measurement through.
        for (k, tau) in [0.0, 0.05].into_iter().enumerate() {
            let q = NodeQuantity::Velocity(2);
            let input = SensorInput::Node {
                node: 0,
                quantity: q,
            };
            let e = || LowPassSensor::new("s", "s", input.clone(), tau, 1.5, 0.0).sampled(0.01);
            let states = if tau > 0.0 {
                vec![(0.3, -1.1)]
            } else {
                Vec::new()
            };
            out.push(
                TangentCase::element(Box::new(e()), vec![random_node(640 + k as u64)])
                    .with_states(states.clone())
                    .with_held(vec![0.42]),
            );
            out.push(
                TangentCase::element(Box::new(e()), vec![random_node(650 + k as u64)])
                    .with_states(states),
            );
        }
        let e = LowPassSensor::new("s", "s", SensorInput::Signal("u".into()), 0.2, -3.0, 0.0);
        out.push(
            TangentCase::element(Box::new(e), Vec::new())
                .with_states(vec![(0.4, -1.2)])
                .with_signals(vec![0.7]),
        );
        out
    }
}

/// A reaction sensor's joint exists, and no static analysis runs it (statics hold
/// nothing: the reactions of the iteration are not known to the signals).
fn reaction_checks(
    cx: &mut Checker,
    model: &Model,
    what: &str,
    joint: &str,
    span: &Option<std::ops::Range<usize>>,
    check_name: bool,
) {
    if !model.joints.iter().any(|j| j.name == joint) {
        if !check_name {
            return;
        }
        let names: Vec<&str> = model.joints.iter().map(|j| j.name.as_str()).collect();
        let hint = match cx.suggest(joint, names.iter().copied()) {
            Some(b) => format!("did you mean '{b}'?"),
            None => "name a joint of the model".into(),
        };
        cx.error(
            format!("{what}: unknown joint '{joint}'"),
            span.clone(),
            Some(hint),
        );
        return;
    }
    if let Some(a) = model
        .analyses
        .iter()
        .find(|a| matches!(a.kind, crate::model::AnalysisKind::Static(_)))
    {
        cx.error(
            format!(
                "{what} reads a joint reaction, which a static analysis ('{}') cannot give it",
                a.name
            ),
            span.clone(),
            Some("reaction sensors hold the converged reactions of a dynamic analysis; in statics read an element output or a node quantity instead".into()),
        );
    }
}

/// An output sensor names `<element>.<output>` of an element that has it; the hint lists
/// the element's outputs (or suggests an element).
fn output_check(
    cx: &mut Checker,
    sensor: &str,
    wanted: &str,
    span: &Option<std::ops::Range<usize>>,
    outputs: &[(String, Vec<String>)],
) {
    let all: Vec<String> = outputs
        .iter()
        .flat_map(|(e, o)| o.iter().map(move |o| format!("{e}.{o}")))
        .collect();
    if all.iter().any(|n| n == wanted) {
        return;
    }
    let element = wanted.rsplit_once('.').map_or(wanted, |p| p.0);
    let hint = match outputs.iter().find(|(e, _)| e == element) {
        Some((_, o)) if o.is_empty() => format!("element '{element}' has no outputs"),
        Some((_, o)) => {
            let list = o.join(", ");
            match cx.suggest(wanted, all.iter().map(|s| s.as_str())) {
                Some(b) => format!("did you mean '{b}'? '{element}' has outputs {list}"),
                None => format!("'{element}' has outputs {list}"),
            }
        }
        None => match cx.suggest(wanted, all.iter().map(|s| s.as_str())) {
            Some(b) => format!("did you mean '{b}'?"),
            None => "element outputs are named `<element>.<output>`, as in the results' element_output names".into(),
        },
    };
    cx.error(
        format!("sensor '{sensor}': unknown element output '{wanted}'"),
        span.clone(),
        Some(hint),
    );
}
