//! The numbers of a system at one time: node states, joint coordinates, multipliers.

use crate::math::Rotation;
use nalgebra::{Matrix3, Vector3};

/// State of one 6-DOF node.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NodeState {
    /// Position, global.
    pub x: Vector3<f64>,
    /// Orientation (node frame → global).
    pub rot: Rotation,
    /// Velocity, global.
    pub v: Vector3<f64>,
    /// Angular velocity Ω, node frame (material).
    pub w: Vector3<f64>,
    /// Acceleration, global.
    pub a: Vector3<f64>,
    /// Angular acceleration Ω̇, node frame.
    pub wd: Vector3<f64>,
}

impl NodeState {
    #[inline]
    pub fn r(&self) -> &Matrix3<f64> {
        self.rot.matrix()
    }

    /// Angular velocity in global components, ω = R Ω.
    pub fn omega_global(&self) -> Vector3<f64> {
        self.r() * self.w
    }
}

/// State of one scalar unknown (a joint coordinate ν): value, rate, acceleration.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Coordinate {
    pub q: f64,
    pub v: f64,
    pub a: f64,
}

/// A first-order state z owned by an element (an inflow, a pressure, a filter output, a
/// damper stretch) and its rate ż.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ElementState {
    pub z: f64,
    pub zd: f64,
}

/// State of the whole system at one time.
#[derive(Debug, Default, PartialEq)]
pub struct State {
    pub time: f64,
    pub nodes: Vec<NodeState>,
    /// Joint coordinates: the active ones constraint by constraint
    /// (`System::coordinate_offsets`), then the passive ones (`System::passive_offsets`).
    pub coords: Vec<Coordinate>,
    /// Element states, element by element (`System::state_offsets`).
    pub states: Vec<ElementState>,
    /// Lagrange multipliers in physical units (force, moment), per constraint row.
    pub lambda: Vec<f64>,
    /// Sample-and-hold values (discrete states that change only at sample instants),
    /// element by element (`System::held_offsets`). Empty when nothing samples (statics):
    /// every hold then passes its input through.
    pub held: Box<[f64]>,
    /// The LuGre bristle deflections of the granular sets' candidate sphere pairs (history
    /// variables, [`crate::elements::SpherePair::bristle_end`]), sorted by pair, in the
    /// order of the integrator's candidate list; empty without sets or pair friction.
    pub pair_bristles: Vec<PairBristle>,
}

impl Clone for State {
    fn clone(&self) -> Self {
        Self {
            time: self.time,
            nodes: self.nodes.clone(),
            coords: self.coords.clone(),
            states: self.states.clone(),
            lambda: self.lambda.clone(),
            held: self.held.clone(),
            pair_bristles: self.pair_bristles.clone(),
        }
    }

    /// Field by field, reusing the vectors' storage (a step's trial state is copied from
    /// the last one without allocating).
    fn clone_from(&mut self, source: &Self) {
        self.nodes.clone_from(&source.nodes);
        self.clone_from_but_nodes(source);
    }
}

impl State {
    /// [`Clone::clone_from`] of every field but the nodes, which the caller copies (a
    /// step's predictor copies each node as it predicts it, on the thread of its part);
    /// the nodes too if their count differs.
    pub fn clone_from_but_nodes(&mut self, source: &Self) {
        if self.nodes.len() != source.nodes.len() {
            self.nodes.clone_from(&source.nodes);
        }
        self.time = source.time;
        self.coords.clone_from(&source.coords);
        self.states.clone_from(&source.states);
        self.lambda.clone_from(&source.lambda);
        if self.held.len() == source.held.len() {
            self.held.copy_from_slice(&source.held);
        } else {
            self.held = source.held.clone();
        }
        self.pair_bristles.clone_from(&source.pair_bristles);
    }
}

/// The bristle deflection z (global components, in the tangent plane) of the sphere pair
/// `(i, j)` (i < j, indices into the set's spheres) of granular set `set`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PairBristle {
    pub key: (usize, usize, usize),
    pub z: Vector3<f64>,
}

/// The bristles of `old` carried over to the pairs `keys` (both sorted): a pair kept keeps
/// its deflection, a new pair starts at zero.
pub fn remap_bristles(old: &[PairBristle], keys: &[(usize, usize, usize)]) -> Vec<PairBristle> {
    let mut k = 0;
    keys.iter()
        .map(|&key| {
            while k < old.len() && old[k].key < key {
                k += 1;
            }
            let z = match old.get(k) {
                Some(b) if b.key == key => b.z,
                _ => Vector3::zeros(),
            };
            PairBristle { key, z }
        })
        .collect()
}
