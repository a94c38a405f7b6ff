//! The system: the model turned into elements, constraints and a DOF layout.
//!
//! Unknown vector layout: node `i` owns entries `6i .. 6i+6` (δx global, δθ material);
//! the multipliers of constraint `c` follow all nodes, at `6N + multiplier_offsets[c]`
//! (and, in the stabilized index-2 formulation, the projection multipliers at
//! `6N + M + multiplier_offsets[c]`). The block structure of the iteration matrix depends
//! on the formulation and is built by the [`Assembler`].

mod assembly;
mod state;

pub use assembly::{Assembler, Coefficients, Formulation};
pub use state::{NodeState, State};

use crate::elements::{AppliedLoad, Element, EvalContext, RigidBody, SpringDamper};
use crate::joints::{Constraint, Joint};
use crate::model::{Model, NodeRef};
use nalgebra::Vector3;

/// Elements, constraints and the layout of the unknowns.
pub struct System {
    pub node_names: Vec<String>,
    pub elements: Vec<Box<dyn Element>>,
    pub constraints: Vec<Box<dyn Constraint>>,
    /// The beams' elements, grouped per beam (for sectional output).
    pub beams: Vec<crate::elements::beam::Beam>,
    /// Copies of the rigid bodies (for momenta).
    pub bodies: Vec<RigidBody>,
    pub gravity: Vector3<f64>,
    /// Offset of each constraint's multipliers in the multiplier vector.
    pub multiplier_offsets: Vec<usize>,
    pub n_multipliers: usize,
    /// Mean translational mass per massive node [kg] (1 if the model has no mass).
    pub characteristic_mass: f64,
}

impl System {
    /// Builds the system of a validated model; elements are attached in the model's
    /// initial configuration.
    pub fn new(model: &Model) -> Self {
        let initial = State::initial(model, 0);
        let nodes = &initial.nodes;
        let mut elements: Vec<Box<dyn Element>> = Vec::new();
        let mut bodies = Vec::new();
        for b in &model.bodies {
            let body = RigidBody::new(&b.name, b.node, b.mass, b.inertia, b.cg_offset);
            bodies.push(body.clone());
            elements.push(Box::new(body));
        }
        let local_offset = |r: NodeRef, p: Vector3<f64>| -> Option<(usize, Vector3<f64>)> {
            r.index()
                .map(|i| (i, nodes[i].r().transpose() * (p - nodes[i].x)))
        };
        for s in &model.springs {
            elements.push(Box::new(SpringDamper::new(
                &s.name,
                local_offset(s.node_a, s.point_a),
                local_offset(s.node_b, s.point_b),
                [s.point_a, s.point_b],
                s.stiffness,
                s.damping,
                s.rest_length,
            )));
        }
        for l in &model.loads {
            let n = &nodes[l.node];
            elements.push(Box::new(AppliedLoad::new(
                &l.name,
                l.node,
                l.force,
                l.moment,
                l.frame,
                n.r().transpose() * (l.point - n.x),
                l.function.clone(),
            )));
        }
        let beams: Vec<crate::elements::beam::Beam> = model
            .beams
            .iter()
            .map(|b| crate::elements::beam::Beam::build(b, nodes))
            .collect();
        for b in &beams {
            for e in &b.elements {
                elements.push(Box::new(e.clone()));
            }
        }
        let mut constraints: Vec<Box<dyn Constraint>> = Vec::new();
        for j in &model.joints {
            constraints.push(Box::new(Joint::new(
                &j.name, j.kind, j.node_a, j.node_b, j.position, j.axes, nodes,
            )));
        }
        let mut sys = Self::from_parts(
            model.nodes.iter().map(|n| n.name.clone()).collect(),
            elements,
            constraints,
            bodies,
            model.gravity,
        );
        if !beams.is_empty() {
            sys.characteristic_mass = characteristic_mass(model, &beams);
            sys.beams = beams;
        }
        sys
    }

    /// Assembles a system from elements and constraints built in code.
    pub fn from_parts(
        node_names: Vec<String>,
        elements: Vec<Box<dyn Element>>,
        constraints: Vec<Box<dyn Constraint>>,
        bodies: Vec<RigidBody>,
        gravity: Vector3<f64>,
    ) -> Self {
        let n = node_names.len();
        let mut multiplier_offsets = Vec::with_capacity(constraints.len());
        let mut m = 0;
        for c in &constraints {
            multiplier_offsets.push(m);
            m += c.n_equations();
        }
        let mut node_mass = vec![0.0; n];
        for b in &bodies {
            node_mass[b.nodes()[0]] += b.mass();
        }
        let massive: Vec<f64> = node_mass.iter().copied().filter(|&x| x > 0.0).collect();
        let characteristic_mass = if massive.is_empty() {
            1.0
        } else {
            massive.iter().sum::<f64>() / massive.len() as f64
        };
        Self {
            node_names,
            elements,
            constraints,
            beams: Vec::new(),
            bodies,
            gravity,
            multiplier_offsets,
            n_multipliers: m,
            characteristic_mass,
        }
    }

    pub fn n_nodes(&self) -> usize {
        self.node_names.len()
    }

    /// Number of configuration unknowns (6 per node).
    pub fn n_config(&self) -> usize {
        6 * self.n_nodes()
    }

    /// Evaluation context at time `t` with load factor `lf`.
    pub fn context(&self, t: f64, lf: f64) -> EvalContext {
        EvalContext {
            time: t,
            gravity: self.gravity,
            load_factor: lf,
        }
    }

    pub fn kinetic_energy(&self, s: &State) -> f64 {
        self.elements
            .iter()
            .map(|e| e.kinetic_energy(&s.nodes))
            .sum()
    }

    pub fn potential_energy(&self, ctx: &EvalContext, s: &State) -> f64 {
        self.elements
            .iter()
            .map(|e| e.potential_energy(ctx, &s.nodes))
            .sum()
    }

    pub fn external_power(&self, ctx: &EvalContext, s: &State) -> f64 {
        self.elements
            .iter()
            .map(|e| e.external_power(ctx, &s.nodes))
            .sum()
    }

    pub fn dissipated_power(&self, s: &State) -> f64 {
        self.elements
            .iter()
            .map(|e| e.dissipated_power(&s.nodes))
            .sum()
    }

    /// Total linear and angular momentum (about the global origin) of the rigid bodies.
    pub fn momenta(&self, s: &State) -> (Vector3<f64>, Vector3<f64>) {
        let mut p = Vector3::zeros();
        let mut h = Vector3::zeros();
        for b in &self.bodies {
            let (pb, hb) = b.momenta(&s.nodes[b.nodes()[0]]);
            p += pb;
            h += hb;
        }
        (p, h)
    }

    /// Constraint values Φ of all constraints, concatenated.
    pub fn constraint_values(&self, ctx: &EvalContext, s: &State, out: &mut [f64]) {
        for (c, off) in self.constraints.iter().zip(&self.multiplier_offsets) {
            let m = c.n_equations();
            c.evaluate(ctx, &s.nodes, &mut out[*off..off + m], None);
        }
    }

    /// Name of a block of the iteration matrix (node, or joint multipliers) for messages.
    pub fn block_name(&self, block: usize) -> String {
        let n = self.n_nodes();
        let c = self.constraints.len();
        if block < n {
            format!("node '{}'", self.node_names[block])
        } else if c > 0 && block - n < 2 * c {
            format!("joint '{}'", self.constraints[(block - n) % c].name())
        } else {
            format!("block {block}")
        }
    }
}

/// Mean translational mass of the massive nodes, with the beams' mass lumped to their nodes.
fn characteristic_mass(model: &Model, beams: &[crate::elements::beam::Beam]) -> f64 {
    let mut node_mass = vec![0.0; model.nodes.len()];
    for b in &model.bodies {
        node_mass[b.node] += b.mass;
    }
    for b in beams {
        for e in &b.elements {
            for (k, m) in e.node_masses().into_iter().enumerate() {
                node_mass[e.as_ref().nodes_slice()[k]] += m;
            }
        }
    }
    let massive: Vec<f64> = node_mass.into_iter().filter(|&x| x > 0.0).collect();
    if massive.is_empty() {
        1.0
    } else {
        massive.iter().sum::<f64>() / massive.len() as f64
    }
}
