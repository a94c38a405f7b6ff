//! The joint library, assembled from the eq. 12 building blocks (seed, Table I):
//!
//! ```text
//! joint        d1 d2 d3   θ1 θ2 θ3
//! fixed        C  C  C    C  C  C
//! revolute     C  C  C    C  C  F
//! spherical    C  C  C    F  F  F
//! ```
//!
//! Frame A is attached to node A and frame B to node B; both coincide with the joint frame
//! given in the initial configuration. Reactions are reported as the force and moment
//! that A exerts on B, about the origin of frame B, in frame-A components.

use super::Constraint;
use super::building_blocks::{FramePair, Mat12, Row12, displacement, rotation};
use crate::elements::EvalContext;
use crate::math::skew;
use crate::model::{JointType, NodeRef};
use crate::system::NodeState;
use nalgebra::{DMatrix, Matrix3, Vector3};

/// One scalar constraint of a joint.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Component {
    /// d_i = 0 (eq. 12a) along axis i of frame A.
    Displacement(usize),
    /// θ_i = 0 (eq. 12b) about axis i of frame A.
    Rotation(usize),
}

impl Component {
    /// The constrained components of each joint type (Table I).
    pub fn of(kind: JointType) -> Vec<Component> {
        use Component::*;
        match kind {
            JointType::Fixed => vec![
                Displacement(0),
                Displacement(1),
                Displacement(2),
                Rotation(0),
                Rotation(1),
                Rotation(2),
            ],
            JointType::Revolute => vec![
                Displacement(0),
                Displacement(1),
                Displacement(2),
                Rotation(0),
                Rotation(1),
            ],
            JointType::Spherical => vec![Displacement(0), Displacement(1), Displacement(2)],
        }
    }
}

/// One side of a joint: a frame fixed to a node, or to the ground.
#[derive(Clone, Debug)]
struct Side {
    node: Option<usize>,
    /// Frame origin: node-frame offset (global point for the ground).
    offset: Vector3<f64>,
    /// Frame axes as columns: node-frame components (global for the ground).
    axes: Matrix3<f64>,
    /// Column block in the joint's local unknowns.
    local: usize,
}

#[derive(Clone, Debug)]
pub struct Joint {
    name: String,
    kind: JointType,
    sides: [Side; 2],
    nodes: Vec<usize>,
    components: Vec<Component>,
}

impl Joint {
    /// A joint whose frame has global origin `position` and global axes `axes` in the
    /// initial configuration `initial` (node states indexed like the model's nodes).
    pub fn new(
        name: impl Into<String>,
        kind: JointType,
        a: NodeRef,
        b: NodeRef,
        position: Vector3<f64>,
        axes: Matrix3<f64>,
        initial: &[NodeState],
    ) -> Self {
        let mut nodes = Vec::new();
        let mut side = |r: NodeRef| match r {
            NodeRef::Ground => Side {
                node: None,
                offset: position,
                axes,
                local: usize::MAX,
            },
            NodeRef::Node(i) => {
                nodes.push(i);
                let rt = initial[i].r().transpose();
                Side {
                    node: Some(i),
                    offset: rt * (position - initial[i].x),
                    axes: rt * axes,
                    local: nodes.len() - 1,
                }
            }
        };
        let sa = side(a);
        let sb = side(b);
        Self {
            name: name.into(),
            kind,
            sides: [sa, sb],
            nodes,
            components: Component::of(kind),
        }
    }

    pub fn kind(&self) -> JointType {
        self.kind
    }

    pub fn components(&self) -> &[Component] {
        &self.components
    }

    /// Current frames with the nodes' velocities (for convective terms).
    fn frames_with_rates(&self, nodes: &[NodeState]) -> FramePair {
        let mut f = self.frames(nodes);
        for (k, s) in self.sides.iter().enumerate() {
            if let Some(i) = s.node {
                f.v[k] = nodes[i].v;
                f.omega[k] = nodes[i].r() * nodes[i].w;
            }
        }
        f
    }

    /// Current frames (positions, arms, axes); velocities left at zero.
    fn frames(&self, nodes: &[NodeState]) -> FramePair {
        let mut f = FramePair {
            x: [Vector3::zeros(); 2],
            arm: [Vector3::zeros(); 2],
            axes: [Matrix3::identity(); 2],
            v: [Vector3::zeros(); 2],
            omega: [Vector3::zeros(); 2],
        };
        for (k, s) in self.sides.iter().enumerate() {
            match s.node {
                None => {
                    f.arm[k] = s.offset;
                    f.axes[k] = s.axes;
                }
                Some(i) => {
                    let n = &nodes[i];
                    let r = n.r();
                    f.x[k] = n.x;
                    f.arm[k] = r * s.offset;
                    f.axes[k] = r * s.axes;
                }
            }
        }
        f
    }

    fn row(&self, f: &FramePair, c: Component) -> (f64, Row12) {
        match c {
            Component::Displacement(i) => (displacement::value(f, i), displacement::jacobian(f, i)),
            Component::Rotation(i) => (rotation::value(f, i), rotation::jacobian(f, i)),
        }
    }

    fn rotation_of(&self, side: usize, nodes: &[NodeState]) -> Matrix3<f64> {
        match self.sides[side].node {
            Some(i) => *nodes[i].r(),
            None => Matrix3::identity(),
        }
    }
}

impl Constraint for Joint {
    fn name(&self) -> &str {
        &self.name
    }

    fn nodes(&self) -> &[usize] {
        &self.nodes
    }

    fn n_equations(&self) -> usize {
        self.components.len()
    }

    fn evaluate(
        &self,
        _ctx: &EvalContext,
        nodes: &[NodeState],
        phi: &mut [f64],
        b: Option<&mut DMatrix<f64>>,
    ) {
        let f = self.frames(nodes);
        let Some(b) = b else {
            // Values only (constraint-violation checks): no Jacobian rows.
            for (row, &c) in self.components.iter().enumerate() {
                phi[row] = match c {
                    Component::Displacement(i) => displacement::value(&f, i),
                    Component::Rotation(i) => rotation::value(&f, i),
                };
            }
            return;
        };
        let rots = [self.rotation_of(0, nodes), self.rotation_of(1, nodes)];
        for (row, &c) in self.components.iter().enumerate() {
            let (value, b12) = self.row(&f, c);
            phi[row] = value;
            for (x, s) in self.sides.iter().enumerate() {
                if s.node.is_none() {
                    continue;
                }
                let col = 6 * s.local;
                for m in 0..3 {
                    b[(row, col + m)] = b12[6 * x + m];
                }
                // Material rotation columns: b_φ R.
                for m in 0..3 {
                    let mut acc = 0.0;
                    for l in 0..3 {
                        acc += b12[6 * x + 3 + l] * rots[x][(l, m)];
                    }
                    b[(row, col + 3 + m)] = acc;
                }
            }
        }
    }

    fn reaction_tangent(
        &self,
        _ctx: &EvalContext,
        nodes: &[NodeState],
        mu: &[f64],
        k: &mut DMatrix<f64>,
    ) {
        let f = self.frames(nodes);
        let rots = [self.rotation_of(0, nodes), self.rotation_of(1, nodes)];
        let mut k12 = Mat12::zeros();
        let mut g12 = Row12::zeros();
        for (row, &c) in self.components.iter().enumerate() {
            let (_, b12) = self.row(&f, c);
            g12 += b12 * mu[row];
            match c {
                Component::Displacement(i) => displacement::force_tangent(&f, i, mu[row], &mut k12),
                Component::Rotation(i) => rotation::force_tangent(&f, i, mu[row], &mut k12),
            }
        }
        for (x, sx) in self.sides.iter().enumerate() {
            if sx.node.is_none() {
                continue;
            }
            let rx = 6 * sx.local;
            for (y, sy) in self.sides.iter().enumerate() {
                if sy.node.is_none() {
                    continue;
                }
                let cy = 6 * sy.local;
                let blk = |r: usize, c: usize| -> Matrix3<f64> {
                    k12.fixed_view::<3, 3>(6 * x + r, 6 * y + c).into_owned()
                };
                let tt = blk(0, 0);
                let tr = blk(0, 3) * rots[y];
                let rt = rots[x].transpose() * blk(3, 0);
                let mut rr = rots[x].transpose() * blk(3, 3) * rots[y];
                if x == y {
                    let m_sp = Vector3::new(g12[6 * x + 3], g12[6 * x + 4], g12[6 * x + 5]);
                    rr += skew(&(rots[x].transpose() * m_sp));
                }
                crate::elements::add_block(k, rx, cy, &tt);
                crate::elements::add_block(k, rx, cy + 3, &tr);
                crate::elements::add_block(k, rx + 3, cy, &rt);
                crate::elements::add_block(k, rx + 3, cy + 3, &rr);
            }
        }
    }

    fn acceleration_term(&self, _ctx: &EvalContext, nodes: &[NodeState], out: &mut [f64]) {
        let f = self.frames_with_rates(nodes);
        for (row, &c) in self.components.iter().enumerate() {
            out[row] = match c {
                Component::Displacement(i) => displacement::convective(&f, i),
                Component::Rotation(i) => rotation::convective(&f, i),
            };
        }
    }

    fn location(&self, nodes: &[NodeState]) -> (Vector3<f64>, Matrix3<f64>) {
        let f = self.frames(nodes);
        (f.x[1] + f.arm[1], f.axes[0])
    }

    fn reactions(&self, nodes: &[NodeState], mu: &[f64]) -> (Vector3<f64>, Vector3<f64>) {
        let f = self.frames(nodes);
        let ea = f.axes[0];
        let mut force = Vector3::zeros();
        let mut moment = Vector3::zeros();
        for (row, &c) in self.components.iter().enumerate() {
            match c {
                // Generalized force on B is +μ e; the reaction on B is its opposite.
                Component::Displacement(i) => force -= ea.column(i) * mu[row],
                // Generalized moment on B is −μ n; the reaction moment is +μ n.
                Component::Rotation(i) => {
                    let b12 = rotation::jacobian(&f, i);
                    moment += Vector3::new(b12[3], b12[4], b12[5]) * mu[row];
                }
            }
        }
        (ea.transpose() * force, ea.transpose() * moment)
    }
}
