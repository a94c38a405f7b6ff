//! The registry of component kinds.
//!
//! A component kind is one `[[table]]` of the model file: its input (serde types, which
//! also give the JSON Schema), its validation into a definition, the nodes it gives
//! equations to, its construction into the system's elements and constraints, and its
//! tangent-check cases. Each kind lives in its own module here; the one list below —
//! [`registry!`] — generates [`ModelInput`] (the file's schema), the kinds' fields of
//! [`Model`], and the loops that validate, build and check every kind. Adding a kind is a
//! module and a line in that list (docs/contributing.md).
//!
//! Kernels (residuals and tangents) of the larger kinds live in [`crate::elements`] and
//! [`crate::joints`]; a small kind may keep its kernel in its own module.

pub mod aero;
pub mod beam;
pub mod body;
pub mod contact;
pub mod controller;
pub mod feedthrough;
pub mod force;
pub mod granular;
pub mod ground;
pub mod hydraulic;
pub mod joint;
pub mod motor;
pub mod rotor;
pub mod sensor;
pub mod signal;
pub mod spring;
pub mod tire;
pub mod viscoelastic;

use super::input::{AnalysisInput, ModelHeader, NodeInput};
use super::validate::Checker;
use super::{AnalysisDef, Located, NodeDef};
use crate::core::{Constraint, Element, NodeRef, NodeState};
use crate::elements::RigidBody;
use crate::elements::beam::Beam;
use crate::tangent_check::TangentCase;
use nalgebra::Vector3;
use schemars::JsonSchema;
use serde::Deserialize;

/// What the kinds build for the system.
pub struct Build<'a> {
    /// The nodes' initial states (model order): elements attach in this configuration.
    pub initial: &'a [NodeState],
    pub elements: Vec<Box<dyn Element>>,
    pub constraints: Vec<Box<dyn Constraint>>,
    /// Copies of the rigid bodies (for momenta and output).
    pub bodies: Vec<RigidBody>,
    /// The beams' elements grouped per beam (for sectional output).
    pub beams: Vec<Beam>,
    /// Granular contact sets (pairs found during the run).
    pub granular: Vec<crate::elements::GranularSet>,
}

impl<'a> Build<'a> {
    pub fn new(initial: &'a [NodeState]) -> Self {
        Self {
            initial,
            elements: Vec::new(),
            constraints: Vec::new(),
            bodies: Vec::new(),
            beams: Vec::new(),
            granular: Vec::new(),
        }
    }

    /// Node and node-frame offset of a global point on `r` (`None` for the ground).
    pub fn local_offset(&self, r: NodeRef, p: Vector3<f64>) -> Option<(usize, Vector3<f64>)> {
        r.index().map(|i| {
            let n = &self.initial[i];
            (i, n.r().transpose() * (p - n.x))
        })
    }
}

/// One kind of component (`[[table]]` of the model file).
pub trait ComponentKind {
    /// Singular noun for messages ("body").
    const NOUN: &'static str;
    /// One entry of the table as written.
    type Input: for<'de> Deserialize<'de> + JsonSchema + Clone + std::fmt::Debug;
    /// One validated entry.
    type Def: Clone + std::fmt::Debug;
    /// The entry's name (unique within the kind; checked generically).
    fn name(input: &Self::Input) -> &Located<String>;
    /// Signals the entry produces (known to every kind's validation).
    fn signals(_input: &Self::Input) -> Vec<String> {
        Vec::new()
    }
    /// Checks one entry, with located errors in `cx`; `None` if it cannot be used. May
    /// create nodes (beams).
    fn validate(
        entry: &Located<Self::Input>,
        cx: &mut Checker,
        model: &mut Model,
    ) -> Option<Self::Def>;
    /// Whether the entry has a discrete form for the energy-consistent integrators
    /// (`integrator = "energy_preserving"` / `"energy_decaying"`); `Err` says why not.
    fn discrete_form(_input: &Self::Input) -> Result<(), String> {
        Err("this kind has no energy-consistent discrete form yet".into())
    }
    /// Checks of the whole model once every kind and analysis is validated.
    fn finish(_input: &ModelInput, _cx: &mut Checker, _model: &Model) {}
    /// Nodes the entry gives an equation to (mass, stiffness or a constraint).
    fn nodes(def: &Self::Def) -> Vec<usize>;
    /// Adds the entry's elements and constraints.
    fn build(def: &Self::Def, parts: &mut Build);
    /// States at which the generic tangent test checks the kind's elements/constraints.
    fn tangent_cases() -> Vec<TangentCase> {
        Vec::new()
    }
}

/// The nodes' initial states of a model (accelerations zero).
pub fn initial_nodes(model: &Model) -> Vec<NodeState> {
    model
        .nodes
        .iter()
        .map(|n| NodeState {
            x: n.position,
            rot: n.orientation,
            v: n.velocity,
            w: n.orientation.matrix().transpose() * n.angular_velocity,
            a: Vector3::zeros(),
            wd: Vector3::zeros(),
        })
        .collect()
}

/// Generates, from the list of kinds (in validation order), the file schema, the model's
/// fields and the loops over the kinds.
macro_rules! registry {
    ($( $(#[$doc:meta])* $field:ident : $kind:ty ),* $(,)?) => {
        /// A samara model: nodes, the components joined at them, and the analyses to run.
        #[derive(Clone, Debug, Default, Deserialize, JsonSchema)]
        #[serde(deny_unknown_fields)]
        pub struct ModelInput {
            /// Model-wide settings.
            pub model: ModelHeader,
            /// 6-DOF nodes (position and orientation).
            #[serde(default)]
            pub nodes: Vec<Located<NodeInput>>,
            $(
                $(#[$doc])*
                #[serde(default)]
                pub $field: Vec<Located<<$kind as ComponentKind>::Input>>,
            )*
            /// Analyses, run in the order given.
            #[serde(default)]
            pub analyses: Vec<Located<AnalysisInput>>,
        }

        /// A validated model.
        #[derive(Clone, Debug, Default)]
        pub struct Model {
            pub name: String,
            pub description: Option<String>,
            pub gravity: Vector3<f64>,
            pub nodes: Vec<NodeDef>,
            $( pub $field: Vec<<$kind as ComponentKind>::Def>, )*
            pub analyses: Vec<AnalysisDef>,
        }

        /// Validates every entry of every kind, in registry order.
        pub(crate) fn validate_all(input: &ModelInput, cx: &mut Checker, model: &mut Model) {
            $(
                for e in &input.$field {
                    for s in <$kind as ComponentKind>::signals(&e.value) {
                        cx.signal_names.insert(s, e.span.clone());
                    }
                }
            )*
            $(
                cx.unique_names(
                    &input.$field,
                    |e| <$kind as ComponentKind>::name(e),
                    <$kind as ComponentKind>::NOUN,
                );
                for e in &input.$field {
                    if let Some(d) = <$kind as ComponentKind>::validate(e, cx, model) {
                        model.$field.push(d);
                    }
                }
            )*
        }

        /// The first entry without a discrete form for the energy-consistent integrators:
        /// its table (`[[field]]`), its name and why ([`ComponentKind::discrete_form`]).
        pub fn without_discrete_form(input: &ModelInput) -> Option<(String, String, String)> {
            $(
                for e in &input.$field {
                    if let Err(why) = <$kind as ComponentKind>::discrete_form(&e.value) {
                        let name = <$kind as ComponentKind>::name(&e.value).value.clone();
                        return Some((format!("[[{}]]", stringify!($field)), name, why));
                    }
                }
            )*
            None
        }

        /// The kinds' whole-model checks.
        pub(crate) fn finish_all(input: &ModelInput, cx: &mut Checker, model: &Model) {
            $( <$kind as ComponentKind>::finish(input, cx, model); )*
        }

        /// Whether each node gets an equation from some component.
        pub fn nodes_used(model: &Model) -> Vec<bool> {
            let mut used = vec![false; model.nodes.len()];
            $(
                for d in &model.$field {
                    for i in <$kind as ComponentKind>::nodes(d) {
                        if let Some(u) = used.get_mut(i) {
                            *u = true;
                        }
                    }
                }
            )*
            used
        }

        /// Builds every component's elements and constraints, in registry order.
        pub fn build_all(model: &Model, parts: &mut Build) {
            $(
                for d in &model.$field {
                    <$kind as ComponentKind>::build(d, parts);
                }
            )*
        }

        /// Every kind's tangent-check cases, named by table.
        pub fn tangent_cases() -> Vec<(&'static str, TangentCase)> {
            let mut out = Vec::new();
            $(
                out.extend(
                    <$kind as ComponentKind>::tangent_cases()
                        .into_iter()
                        .map(|c| (stringify!($field), c)),
                );
            )*
            out
        }

        /// The table names of the kinds, in registry order.
        pub const TABLES: &[&str] = &[$(stringify!($field)),*];
    };
}

registry! {
    /// Geometrically exact beams (Legendre spectral elements); they may create nodes.
    beams: beam::BeamKind,
    /// Rigid bodies, each attached to one node.
    bodies: body::Body,
    /// Named signals given as functions of time.
    signals: signal::Signal,
    /// Sensors: a node quantity or a signal through a first-order low-pass filter,
    /// producing a signal.
    sensors: sensor::Sensor,
    /// Control blocks (PID, transfer functions, state space, gain, sum, saturation, rate
    /// limit, lookup) with their dynamics as element states, producing signals.
    controllers: controller::Controller,
    /// Joints between two nodes, or a node and the ground.
    joints: joint::JointKind,
    /// Point-to-point spring-dampers.
    springs: spring::Spring,
    /// Applied forces and moments on nodes.
    forces: force::Force,
    /// Point-to-point viscoelastic elements (Maxwell: a spring in series with a damper).
    viscoelastic: viscoelastic::Viscoelastic,
    /// Lifting lines on beams or nodes: aerodynamic stations with airfoil tables, wind
    /// and induced velocity (docs/aerodynamics.md).
    aero_lines: aero::AeroLine,
    /// Rotor discs with Pitt–Peters dynamic inflow states, shared by the lifting lines
    /// that name them (docs/aerodynamics.md).
    rotors: rotor::RotorKind,
    /// Contacts of bodies with a ground plane (Hunt–Crossley or linear normal force,
    /// LuGre friction with bristle states).
    contacts: contact::ContactKind,
    /// Granular contact sets: many spheres mutually in contact and with a ground plane,
    /// pairs found by a broad phase during the run (docs/multi-field.md).
    granular: granular::GranularKind,
    /// Hydraulic circuits: volumes with pressure states, reservoirs, orifices, check
    /// valves and a double-acting actuator.
    hydraulics: hydraulic::Hydraulic,
    /// DC motors between two nodes about an axis, driven by a voltage signal (armature
    /// current as the state).
    motors: motor::Motor,
    /// Tires on revolute hub joints: Magic-Formula forces from relaxation-length slip
    /// states, rolling resistance, aligning moment and a brake-torque input.
    tires: tire::TireKind,
}
