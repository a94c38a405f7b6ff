//! `[[sensors]]`: a node quantity (or a signal) through a first-order low-pass filter,
//! producing a signal named like the sensor (kernel: [`crate::elements::LowPassSensor`]).
//!
//! ```toml
//! [[sensors]]
//! name = "height"            # the signal it produces
//! node = "bob"               # a node quantity …
//! quantity = "position"      # position | velocity | acceleration | angular_velocity
//! component = "z"            # global component x | y | z
//! # signal = "command"       # … or another signal
//! time_constant = 0.05       # τ [s] > 0
//! gain = 1.0                 # g (default 1)
//! # initial = 0.0            # z(0); default g·u(0) for position, velocity and angular
//! #                          # velocity (the sensor starts settled), 0 otherwise
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
    /// Filter time constant τ [s], positive.
    pub time_constant: f64,
    /// Gain g (default 1).
    #[serde(default)]
    pub gain: Option<f64>,
    /// Initial output z(0); see the module documentation for the default.
    #[serde(default)]
    pub initial: Option<f64>,
}

/// A validated sensor.
#[derive(Clone, Debug)]
pub struct SensorDef {
    pub name: String,
    pub input: SensorInput,
    pub time_constant: f64,
    pub gain: f64,
    pub initial: f64,
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
        if !(si.time_constant.is_finite() && si.time_constant > 0.0) {
            cx.error(
                format!(
                    "{what}: `time_constant` must be positive (got {})",
                    si.time_constant
                ),
                cx.key(&e, "time_constant"),
                Some("τ [s] of the filter τ ż + z = g u; a small τ follows u closely".into()),
            );
            ok = false;
        }
        let gain = si.gain.unwrap_or(1.0);
        let node_keys = si.node.is_some() || si.quantity.is_some() || si.component.is_some();
        let input = match (&si.signal, node_keys) {
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
            time_constant: si.time_constant,
            gain,
            initial,
        })
    }

    fn nodes(_def: &SensorDef) -> Vec<usize> {
        // A sensor applies no force: it gives its node no equation.
        Vec::new()
    }

    fn build(def: &SensorDef, parts: &mut Build) {
        parts.elements.push(Box::new(LowPassSensor::new(
            &def.name,
            &def.name,
            def.input.clone(),
            def.time_constant,
            def.gain,
            def.initial,
        )));
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
        let e = LowPassSensor::new("s", "s", SensorInput::Signal("u".into()), 0.2, -3.0, 0.0);
        out.push(
            TangentCase::element(Box::new(e), Vec::new())
                .with_states(vec![(0.4, -1.2)])
                .with_signals(vec![0.7]),
        );
        out
    }
}
