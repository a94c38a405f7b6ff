//! The joint: two frames, one on each side, and the rows of its type ([`super::rows`]).
//!
//! Frame A is fixed to node A and frame B to node B (or to the ground). Rows are evaluated
//! in global ("spatial") components by the building blocks and converted here to the
//! material rotation increments of the nodes. The joint coordinates ν are unknowns of the
//! system owned by the joint; their columns follow the node columns in `B`.
//!
//! Reactions are the force and moment that A exerts on B, about the origin of frame B, in
//! frame-A components: `F = −Σ_r μ_r b_r^{x_B}`, `M = −Σ_r μ_r b_r^{θ_B} − rᴮ × F`. They
//! include what the coordinate elements transmit (a spring on a free component is carried
//! by the multiplier of the row that defines the coordinate).

use super::building_blocks::{Blocks12, FramePair, Row12, displacement};
use super::coordinate_loads::CoordinateLoads;
use super::rows::{COMPONENT_NAMES, Row, measure, rows_of};
use super::spec::{JointDef, JointType};
use super::{Constraint, CoordinateTangents};
use crate::core::EvalContext;
use crate::core::NodeRef;
use crate::core::RowRole;
use crate::core::RowTerms;
use crate::core::ServoRow;
use crate::core::{Coordinate, NodeState};
use crate::math::TimeFunction;
use crate::math::isa;
use crate::math::skew;
use nalgebra::{DMatrix, Matrix3, Vector3};

/// The ground's rotation.
static IDENTITY: Matrix3<f64> = Matrix3::new(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0);

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

impl Side {
    /// Node position, arm `R s` and axes `R A` of the frame (the ground's as given).
    #[inline(always)]
    fn frame(&self, nodes: &[NodeState]) -> (Vector3<f64>, Vector3<f64>, Matrix3<f64>) {
        match self.node {
            None => (Vector3::zeros(), self.offset, self.axes),
            Some(i) => {
                let n = &nodes[i];
                let r = n.r();
                (n.x, r * self.offset, r * self.axes)
            }
        }
    }
}

/// An active row in closed form: `e_iᴬ·d` or `e_pᴬ·e_qᴮ`, with no coordinate.
#[derive(Clone, Copy, Debug, PartialEq)]
enum PlainRow {
    Displacement(usize),
    Cosine(usize, usize),
}

/// The active rows as [`PlainRow`]s when every one of them is plain (the locked rows of a
/// joint without coordinates, drives or servos: revolute, spherical, fixed, ...); `None`
/// otherwise.
fn plain_rows(rows: &[Row], active: &[usize]) -> Option<Vec<PlainRow>> {
    active
        .iter()
        .map(|&r| match &rows[r] {
            Row::Displacement { axis, coord: None } => Some(PlainRow::Displacement(*axis)),
            Row::Angle { row, coord: None } => row.plain().map(|(p, q)| PlainRow::Cosine(p, q)),
            _ => None,
        })
        .collect()
}

/// A row evaluated in spatial components.
struct RowValue {
    phi: f64,
    b: Row12,
    /// (coordinate, ∂Φ/∂ν).
    dnu: Option<(usize, f64)>,
}

#[derive(Clone, Debug)]
pub struct Joint {
    name: String,
    kind: JointType,
    sides: [Side; 2],
    nodes: Vec<usize>,
    rows: Vec<Row>,
    /// Indices of the enforced rows (all but those dropped as redundant).
    active: Vec<usize>,
    /// The enforced rows in closed form, if they all are plain ([`plain_rows`]).
    plain: Option<Vec<PlainRow>>,
    /// Component (0..6) of each coordinate, the active ones first.
    components: Vec<usize>,
    /// Number of active coordinates (unknowns of the Newton system).
    n_active: usize,
    loads: Vec<CoordinateLoads>,
    /// Signals read by the input ports, and the input index of each active coordinate.
    inputs: Vec<String>,
    input_of: Vec<Option<usize>>,
    /// Defining rows of the passive coordinates (`coord` indexes the passive list).
    passive_rows: Vec<Row>,
    /// The servo rows (drives whose target is an input signal).
    servos: Vec<ServoRow>,
}

impl Joint {
    /// A joint as defined in the model, attached in the initial configuration `initial`
    /// (node states indexed like the model's nodes).
    pub fn new(def: &JointDef, initial: &[NodeState]) -> Self {
        let mut nodes = Vec::new();
        let mut side = |r: NodeRef, position: Vector3<f64>| match r {
            NodeRef::Ground => Side {
                node: None,
                offset: position,
                axes: def.axes,
                local: usize::MAX,
            },
            NodeRef::Node(i) => {
                nodes.push(i);
                let rt = initial[i].r().transpose();
                Side {
                    node: Some(i),
                    offset: rt * (position - initial[i].x),
                    axes: rt * def.axes,
                    local: nodes.len() - 1,
                }
            }
        };
        let sa = side(def.node_a, def.position_a);
        let sb = side(def.node_b, def.position_b);
        let rotations_wanted = def.components[3..].iter().any(|c| c.is_some());
        let drives: [Option<TimeFunction>; 6] =
            std::array::from_fn(|c| def.components[c].as_ref().and_then(|d| d.drive.clone()));
        let (mut all_rows, all_components) =
            rows_of(def.kind, def.pitch, rotations_wanted, &drives);
        let servo_of = |c: usize| {
            def.components[c]
                .as_ref()
                .and_then(|d| d.drive_signal.clone())
        };
        // Servo rows after the drives, reading the signals listed after the input ports'.
        let mut servo_signals: Vec<String> = Vec::new();
        for (j, &c) in all_components.iter().enumerate() {
            if let Some(name) = servo_of(c) {
                all_rows.push(Row::Servo {
                    coord: j,
                    input: servo_signals.len(),
                });
                servo_signals.push(name);
            }
        }
        let loads_of = |c: usize| {
            def.components[c]
                .as_ref()
                .map(CoordinateLoads::from_def)
                .unwrap_or_default()
        };
        // A coordinate is active when something acts on it: elements, a drive (every
        // component of a prescribed joint is driven, by default to 0), or (the screw)
        // another equation of the joint.
        let is_active = |c: usize| {
            matches!(def.kind, JointType::Screw | JointType::Prescribed)
                || drives[c].is_some()
                || servo_of(c).is_some()
                || !loads_of(c).is_empty()
        };
        let mut renumber = vec![0usize; all_components.len()];
        let mut components = Vec::new();
        for (j, &c) in all_components.iter().enumerate() {
            if is_active(c) {
                renumber[j] = components.len();
                components.push(c);
            }
        }
        let n_active = components.len();
        for (j, &c) in all_components.iter().enumerate() {
            if !is_active(c) {
                renumber[j] = components.len() - n_active;
                components.push(c);
            }
        }
        let mut rows = Vec::new();
        let mut passive_rows = Vec::new();
        for row in all_rows {
            let coord = match &row {
                Row::Displacement { coord, .. } => coord.map(|(c, _)| c),
                Row::Angle { coord, .. } => *coord,
                Row::Drive { coord, .. } | Row::Servo { coord, .. } => Some(*coord),
            };
            let passive = coord.is_some_and(|c| !is_active(all_components[c]));
            let row = match row {
                Row::Displacement { axis, coord } => Row::Displacement {
                    axis,
                    coord: coord.map(|(c, s)| (renumber[c], s)),
                },
                Row::Angle { row, coord } => Row::Angle {
                    row,
                    coord: coord.map(|c| renumber[c]),
                },
                Row::Drive { coord, function } => Row::Drive {
                    coord: renumber[coord],
                    function,
                },
                Row::Servo { coord, input } => Row::Servo {
                    coord: renumber[coord],
                    input,
                },
            };
            if passive {
                passive_rows.push(row);
            } else {
                rows.push(row);
            }
        }
        let loads: Vec<CoordinateLoads> = components[..n_active]
            .iter()
            .map(|&c| loads_of(c))
            .collect();
        let mut inputs: Vec<String> = Vec::new();
        let input_of = loads
            .iter()
            .map(|l| {
                l.input.as_ref().map(|name| {
                    inputs.iter().position(|n| n == name).unwrap_or_else(|| {
                        inputs.push(name.clone());
                        inputs.len() - 1
                    })
                })
            })
            .collect();
        // The servos' signals join the input list (shared when a port reads the same one).
        let mut index_of = |name: &String| {
            inputs.iter().position(|n| n == name).unwrap_or_else(|| {
                inputs.push(name.clone());
                inputs.len() - 1
            })
        };
        let servo_inputs: Vec<usize> = servo_signals.iter().map(&mut index_of).collect();
        for row in &mut rows {
            if let Row::Servo { input, .. } = row {
                *input = servo_inputs[*input];
            }
        }
        let servos = rows
            .iter()
            .enumerate()
            .filter_map(|(r, row)| match row {
                Row::Servo { coord, input } => Some(ServoRow {
                    row: r,
                    input: *input,
                    coordinate: *coord,
                }),
                _ => None,
            })
            .collect();
        let active: Vec<usize> = (0..rows.len()).collect();
        Self {
            name: def.name.clone(),
            kind: def.kind,
            sides: [sa, sb],
            nodes,
            plain: plain_rows(&rows, &active),
            active,
            rows,
            components,
            n_active,
            loads,
            inputs,
            input_of,
            passive_rows,
            servos,
        }
    }

    pub fn kind(&self) -> JointType {
        self.kind
    }

    /// All rows (enforced or not).
    pub fn rows(&self) -> &[Row] {
        &self.rows
    }

    /// Component (0..6 = d1 … θ3) of each coordinate.
    pub fn components(&self) -> &[usize] {
        &self.components
    }

    /// Current frames with the nodes' velocities (for rate terms).
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
    #[inline(always)]
    fn frames(&self, nodes: &[NodeState]) -> FramePair {
        // Each side built whole (no zeroed frame overwritten field by field: the partial
        // overwrites stalled the loads that followed on store forwarding).
        let (xa, arm_a, axes_a) = self.sides[0].frame(nodes);
        let (xb, arm_b, axes_b) = self.sides[1].frame(nodes);
        FramePair {
            x: [xa, xb],
            arm: [arm_a, arm_b],
            axes: [axes_a, axes_b],
            v: [Vector3::zeros(); 2],
            omega: [Vector3::zeros(); 2],
        }
    }

    #[inline(always)]
    fn row_value(&self, f: &FramePair, coords: &[Coordinate], t: f64, row: &Row) -> RowValue {
        match row {
            Row::Displacement { axis, coord } => RowValue {
                phi: displacement::value(f, *axis) - coord.map_or(0.0, |(c, s)| s * coords[c].q),
                b: displacement::jacobian(f, *axis),
                dnu: coord.map(|(c, s)| (c, -s)),
            },
            Row::Angle { row, coord } => {
                let nu = coord.map_or(0.0, |c| coords[c].q);
                let v = row.value(f, nu);
                RowValue {
                    phi: v[0],
                    b: row.jacobian(f, nu, 0),
                    dnu: coord.map(|c| (c, v[1])),
                }
            }
            Row::Drive { coord, function } => RowValue {
                phi: coords[*coord].q - function.eval(t),
                b: Row12::zeros(),
                dnu: Some((*coord, 1.0)),
            },
            Row::Servo { coord, .. } => RowValue {
                phi: coords[*coord].q,
                b: Row12::zeros(),
                dnu: Some((*coord, 1.0)),
            },
        }
    }

    /// `Φ` of a row only (no Jacobian), for constraint-violation checks.
    #[inline]
    fn row_phi(&self, f: &FramePair, coords: &[Coordinate], t: f64, row: &Row) -> f64 {
        match row {
            Row::Displacement { axis, coord } => {
                displacement::value(f, *axis) - coord.map_or(0.0, |(c, s)| s * coords[c].q)
            }
            Row::Angle { row, coord } => row.value(f, coord.map_or(0.0, |c| coords[c].q))[0],
            Row::Drive { coord, function } => coords[*coord].q - function.eval(t),
            Row::Servo { coord, .. } => coords[*coord].q,
        }
    }

    /// The rotation of a side's node (the identity for the ground), by reference.
    #[inline(always)]
    fn rotation_of<'n>(&self, side: usize, nodes: &'n [NodeState]) -> &'n Matrix3<f64> {
        match self.sides[side].node {
            Some(i) => nodes[i].r(),
            None => &IDENTITY,
        }
    }

    /// Writes a spatial 12-row into the material local row `out` (length 6·nodes + nc).
    #[inline(always)]
    fn to_local(&self, b12: &Row12, rots: &[&Matrix3<f64>; 2], mut put: impl FnMut(usize, f64)) {
        for (x, s) in self.sides.iter().enumerate() {
            if s.node.is_none() {
                continue;
            }
            let col = 6 * s.local;
            for m in 0..3 {
                put(col + m, b12[6 * x + m]);
            }
            for m in 0..3 {
                let mut acc = 0.0;
                for l in 0..3 {
                    acc += b12[6 * x + 3 + l] * rots[x][(l, m)];
                }
                put(col + 3 + m, acc);
            }
        }
    }

    fn fill(
        &self,
        ctx: &EvalContext,
        nodes: &[NodeState],
        coords: &[Coordinate],
        which: &[usize],
        phi: &mut [f64],
        b: Option<&mut DMatrix<f64>>,
    ) {
        let f = self.frames(nodes);
        let nq = 6 * self.nodes.len();
        let Some(b) = b else {
            for (i, &r) in which.iter().enumerate() {
                phi[i] = self.row_phi(&f, coords, ctx.time, &self.rows[r]);
            }
            return;
        };
        let m = b.nrows();
        let bs = b.as_mut_slice();
        bs.fill(0.0);
        let rots = [self.rotation_of(0, nodes), self.rotation_of(1, nodes)];
        for (i, &r) in which.iter().enumerate() {
            let v = self.row_value(&f, coords, ctx.time, &self.rows[r]);
            phi[i] = v.phi;
            // Column-major: entry (i, c) at c·m + i.
            self.to_local(&v.b, &rots, |c, x| bs[c * m + i] = x);
            if let Some((c, d)) = v.dnu {
                bs[(nq + c) * m + i] = d;
            }
        }
    }

    /// Passive coordinates from the frames (see [`Constraint::update_passive_coordinates`]).
    #[inline(always)]
    fn update_passive_impl(&self, nodes: &[NodeState], passive: &mut [Coordinate], rates: bool) {
        // The rates need the frames' velocities and accelerations; the values only the
        // frames.
        let f = if rates {
            self.frames_with_rates(nodes)
        } else {
            self.frames(nodes)
        };
        let mut vel = Row12::zeros();
        // Spatial accelerations: ẍ, and ω̇ = R Ω̇ (ω × ω = 0).
        let mut acc = Row12::zeros();
        if rates {
            vel = f.spatial_velocities();
            for (k, s) in self.sides.iter().enumerate() {
                if let Some(i) = s.node {
                    let (a, wd) = (nodes[i].a, nodes[i].r() * nodes[i].wd);
                    for m in 0..3 {
                        acc[6 * k + m] = a[m];
                        acc[6 * k + 3 + m] = wd[m];
                    }
                }
            }
        }
        // Principal values from the direction cosines, continued from the current value
        // (angles keep counting turns).
        let rel = f.axes[0].transpose() * f.axes[1];
        let r: [[f64; 3]; 3] = std::array::from_fn(|p| std::array::from_fn(|q| rel[(p, q)]));
        let dv = f.axes[0].transpose() * f.d();
        let d3 = [dv.x, dv.y, dv.z];
        for row in &self.passive_rows {
            let c = match row {
                Row::Displacement {
                    coord: Some((c, _)),
                    ..
                }
                | Row::Angle { coord: Some(c), .. } => *c,
                _ => continue,
            };
            let comp = self.components[self.n_active + c];
            let principal = measure(self.kind, comp, &r, &d3);
            passive[c].q = if comp < 3 {
                principal
            } else {
                let turn = 2.0 * std::f64::consts::PI;
                let delta = principal - passive[c].q;
                passive[c].q + delta - turn * (delta / turn).round()
            };
            if !rates {
                continue;
            }
            let v = self.row_value(&f, passive, 0.0, row);
            let Some((_, d)) = v.dnu else { continue };
            if d.abs() < 1e-12 {
                continue;
            }
            // Φ̇ = b·v + Φ_ν ν̇ = 0, then Φ̈ = conv + b·a + Φ_ν ν̈ = 0.
            passive[c].v = -v.b.dot(&vel) / d;
            let conv = match row {
                Row::Displacement { axis, .. } => displacement::convective(&f, *axis),
                Row::Angle { row, .. } => row.convective(&f, passive[c].q, passive[c].v),
                Row::Drive { .. } | Row::Servo { .. } => 0.0,
            };
            passive[c].a = -(conv + v.b.dot(&acc)) / d;
        }
    }

    #[inline(always)]
    fn evaluate_rows_impl(
        &self,
        ctx: &EvalContext,
        nodes: &[NodeState],
        coords: &[Coordinate],
        lambda: &[f64],
        penalty: f64,
        out: RowTerms,
    ) {
        let RowTerms {
            phi,
            mu,
            force,
            b,
            want_b,
            tangent,
            targets,
        } = out;
        let f = self.frames(nodes);
        let rots = [self.rotation_of(0, nodes), self.rotation_of(1, nodes)];
        let nq = 6 * self.nodes.len();
        let m = b.nrows();
        // Every row writes all node columns of `B` and `to_local` all node entries of the
        // force: only the coordinate columns (entries) need clearing.
        let mut bs = (want_b || tangent.is_some()).then(|| {
            let bs = b.as_mut_slice();
            bs[nq * m..].fill(0.0);
            bs
        });
        force[nq..].fill(0.0);
        // Σ μ_r b_r in spatial components: converted to the local columns once.
        let mut g12 = Row12::zeros();
        // Without B (a residual only), the displacement rows' share of Σ μ_r b_r in one
        // term: their rows b_r = [−e_r, e_r × w, e_r, r_B × e_r] (w = uᴮ − xᴬ) are linear in
        // the axis e_r, so the share is [−m, m × w, m, r_B × m] with m = Σ μ_r e_r, as in
        // their tangent ([`displacement::force_tangent_along`]): two cross products per
        // joint, not two per row (the same value up to round-off).
        let lump = bs.is_none();
        let d = f.d();
        let mut m_disp = Vector3::zeros();
        if lump && let Some(plain) = &self.plain {
            // Plain rows: the direction cosines' b_r = [0, n, 0, −n] (n = e_pᴬ × e_qᴮ) added
            // into the moment parts only, in the same order and with the same values as
            // `axpy12` over the full rows.
            for (i, &row) in plain.iter().enumerate() {
                match row {
                    PlainRow::Displacement(axis) => {
                        let e = f.axes[0].column(axis);
                        let value = e.dot(&d);
                        phi[i] = value;
                        let mu_r = lambda[i] + penalty * value;
                        mu[i] = mu_r;
                        m_disp += e * mu_r;
                    }
                    PlainRow::Cosine(p, q) => {
                        let (e, g) = (f.axes[0].column(p), f.axes[1].column(q));
                        let value = e.dot(&g);
                        phi[i] = value;
                        let mu_r = lambda[i] + penalty * value;
                        mu[i] = mu_r;
                        if mu_r != 0.0 {
                            let n = e.cross(&g);
                            for j in 0..3 {
                                let t = n[j] * mu_r;
                                g12[3 + j] += t;
                                g12[9 + j] -= t;
                            }
                        }
                    }
                }
            }
        }
        let rest = if lump && self.plain.is_some() {
            &[][..]
        } else {
            &self.active[..]
        };
        for (i, &r) in rest.iter().enumerate() {
            let row = &self.rows[r];
            if lump && let Row::Displacement { axis, coord } = row {
                let e = f.axes[0].column(*axis);
                let value = e.dot(&d) - coord.map_or(0.0, |(c, s)| s * coords[c].q);
                phi[i] = value;
                let mu_r = lambda[i] + penalty * value;
                mu[i] = mu_r;
                m_disp += e * mu_r;
                if let Some((c, s)) = *coord {
                    force[nq + c] += -s * mu_r;
                }
                continue;
            }
            let v = self.row_value(&f, coords, ctx.time, row);
            phi[i] = match row {
                Row::Servo { .. } if !targets.is_empty() => v.phi - targets[i],
                _ => v.phi,
            };
            let mu_r = lambda[i] + penalty * phi[i];
            mu[i] = mu_r;
            if mu_r != 0.0 {
                axpy12(&mut g12, mu_r, &v.b);
            }
            if let Some((c, d)) = v.dnu {
                force[nq + c] += d * mu_r;
            }
            if let Some(bs) = bs.as_deref_mut() {
                // Column-major: entry (i, c) at c·m + i.
                self.to_local(&v.b, &rots, |c, x| bs[c * m + i] = x);
                if let Some((c, d)) = v.dnu {
                    bs[(nq + c) * m + i] = d;
                }
            }
        }
        if lump && m_disp != Vector3::zeros() {
            let w = f.origin(1) - f.x[0];
            let (mw, rm) = (m_disp.cross(&w), f.arm[1].cross(&m_disp));
            for j in 0..3 {
                g12[j] -= m_disp[j];
                g12[3 + j] += mw[j];
                g12[6 + j] += m_disp[j];
                g12[9 + j] += rm[j];
            }
        }
        self.to_local(&g12, &rots, |c, x| force[c] = x);
        if let Some(k) = tangent {
            k.as_mut_slice().fill(0.0);
            self.add_reaction_tangent(&f, &rots, coords, mu, &g12, k);
        }
    }

    /// Adds `∂(Bᵀμ)/∂(q, ν)` at fixed `μ` into `k`, with `g12 = Σ μ_r b_r` (spatial) of
    /// the active rows already summed: the row force tangents `μ_r ∂(b_rᵀ)/∂q` (spatial,
    /// then to the material increments) plus the term of the rotation of the material
    /// columns themselves, `skew(Rᵀ m)` with `m` the moment part of `g12`.
    #[inline(always)]
    fn add_reaction_tangent(
        &self,
        f: &FramePair,
        rots: &[&Matrix3<f64>; 2],
        coords: &[Coordinate],
        mu: &[f64],
        g12: &Row12,
        k: &mut DMatrix<f64>,
    ) {
        let nq = 6 * self.nodes.len();
        let mut k12 = Blocks12::new();
        // The displacement rows together: one tangent along Σ μ_r e_r.
        let mut along = Vector3::zeros();
        let mut any_displacement = false;
        for (i, &r) in self.active.iter().enumerate() {
            let mu_r = mu[i];
            if mu_r == 0.0 {
                continue;
            }
            match &self.rows[r] {
                Row::Displacement { axis, .. } => {
                    along += f.axes[0].column(*axis) * mu_r;
                    any_displacement = true;
                }
                Row::Angle { row, coord } => {
                    let nu = coord.map_or(0.0, |c| coords[c].q);
                    row.force_tangent(f, nu, mu_r, &mut k12);
                    if let Some(c) = *coord {
                        // ∂(b_qᵀμ)/∂ν and ∂(b_ν μ)/∂q: the same vector μ Σ a_t' b_t.
                        let v = row.jacobian(f, nu, 1) * mu_r;
                        self.to_local(&v, rots, |j, x| {
                            k[(j, nq + c)] += x;
                            k[(nq + c, j)] += x;
                        });
                        k[(nq + c, nq + c)] += mu_r * row.value(f, nu)[2];
                    }
                }
                Row::Drive { .. } | Row::Servo { .. } => {}
            }
        }
        if any_displacement {
            displacement::force_tangent_along(f, &along, &mut k12);
        }
        // The 3 × 3 blocks of K₁₂ added to `k` (column-major, `nrows` rows) by plain
        // indexing; a block of K₁₂ no term reached (the displacement rows'
        // translation–translation blocks, a side's blocks no row couples) is skipped with
        // its rotation products.
        let blk = |r: usize, c: usize| k12.get(r, c);
        let nr = k.nrows();
        let kv = k.as_mut_slice();
        let mut add = |r: usize, c: usize, b: &Matrix3<f64>| {
            for j in 0..3 {
                let o = (c + j) * nr + r;
                for (kv, bv) in kv[o..o + 3].iter_mut().zip(b.column(j).iter()) {
                    *kv += bv;
                }
            }
        };
        for (x, sx) in self.sides.iter().enumerate() {
            if sx.node.is_none() {
                continue;
            }
            let rx = 6 * sx.local;
            let rxt = rots[x].transpose();
            for (y, sy) in self.sides.iter().enumerate() {
                if sy.node.is_none() {
                    continue;
                }
                let cy = 6 * sy.local;
                let (x6, x2, y2) = (6 * x, 2 * x, 2 * y);
                if let Some(tt) = blk(x2, y2) {
                    add(rx, cy, tt);
                }
                if let Some(b) = blk(x2, y2 + 1) {
                    add(rx, cy + 3, &(b * rots[y]));
                }
                if let Some(b) = blk(x2 + 1, y2) {
                    add(rx + 3, cy, &(rxt * b));
                }
                let mut rr = blk(x2 + 1, y2 + 1).map(|b| rxt * b * rots[y]);
                if x == y {
                    let m_sp = Vector3::new(g12[x6 + 3], g12[x6 + 4], g12[x6 + 5]);
                    let s = skew(&(rxt * m_sp));
                    *rr.get_or_insert_with(Matrix3::zeros) += s;
                }
                if let Some(rr) = rr {
                    add(rx + 3, cy + 3, &rr);
                }
            }
        }
    }
}

impl Constraint for Joint {
    fn breakpoints(&self, out: &mut Vec<f64>) {
        for r in self.rows.iter().chain(&self.passive_rows) {
            if let Row::Drive { function, .. } = r {
                out.extend(function.breakpoints());
            }
        }
    }

    fn name(&self) -> &str {
        &self.name
    }

    fn nodes(&self) -> &[usize] {
        &self.nodes
    }

    fn n_coordinates(&self) -> usize {
        self.n_active
    }

    fn n_passive_coordinates(&self) -> usize {
        self.components.len() - self.n_active
    }

    fn n_equations(&self) -> usize {
        self.active.len()
    }

    /// Displacement rows `e_iᴬ·(uᴮ − uᴬ)`, direction cosines `e_pᴬ·e_qᴮ` and their
    /// combinations are invariant under a rigid motion of both frames; drive and servo
    /// rows have no node columns.
    fn is_relative(&self) -> bool {
        true
    }

    fn evaluate(
        &self,
        ctx: &EvalContext,
        nodes: &[NodeState],
        coords: &[Coordinate],
        phi: &mut [f64],
        b: Option<&mut DMatrix<f64>>,
    ) {
        if b.is_none()
            && let Some(plain) = &self.plain
        {
            // Φ alone of plain rows: the values of `row_phi`, without its dispatch.
            let f = self.frames(nodes);
            let d = f.d();
            for (p, &row) in phi.iter_mut().zip(plain) {
                *p = match row {
                    PlainRow::Displacement(axis) => f.axes[0].column(axis).dot(&d),
                    PlainRow::Cosine(i, j) => f.axes[0].column(i).dot(&f.axes[1].column(j)),
                };
            }
            return;
        }
        self.fill(ctx, nodes, coords, &self.active, phi, b);
    }

    fn discrete_jacobian(
        &self,
        start: &[NodeState],
        end: &[NodeState],
        coords: [&[Coordinate]; 2],
        column_maps: &[Matrix3<f64>],
        b: &mut DMatrix<f64>,
    ) {
        let (f0, f1) = (self.frames(start), self.frames(end));
        let fm = FramePair::mean(&f0, &f1);
        let nq = 6 * self.nodes.len();
        let m = b.nrows();
        let bs = b.as_mut_slice();
        bs.fill(0.0);
        let mut rots = [&IDENTITY; 2];
        for (x, s) in self.sides.iter().enumerate() {
            if s.node.is_some() {
                rots[x] = &column_maps[s.local];
            }
        }
        for (i, &r) in self.active.iter().enumerate() {
            let (b12, dnu) = match &self.rows[r] {
                Row::Displacement { axis, coord } => (
                    displacement::jacobian(&fm, *axis),
                    coord.map(|(c, s)| (c, -s)),
                ),
                Row::Angle { row, coord } => {
                    let (n0, n1) = coord.map_or((0.0, 0.0), |c| (coords[0][c].q, coords[1][c].q));
                    let (q, d) = row.discrete_jacobian(&f0, &f1, &fm, n0, n1);
                    (q, coord.map(|c| (c, d)))
                }
                Row::Drive { coord, .. } | Row::Servo { coord, .. } => {
                    (Row12::zeros(), Some((*coord, 1.0)))
                }
            };
            self.to_local(&b12, &rots, |c, x| bs[c * m + i] = x);
            if let Some((c, d)) = dnu {
                bs[(nq + c) * m + i] = d;
            }
        }
    }

    fn reaction_tangent(
        &self,
        _ctx: &EvalContext,
        nodes: &[NodeState],
        coords: &[Coordinate],
        mu: &[f64],
        k: &mut DMatrix<f64>,
    ) {
        let f = self.frames(nodes);
        let rots = [self.rotation_of(0, nodes), self.rotation_of(1, nodes)];
        let mut g12 = Row12::zeros();
        for (i, &r) in self.active.iter().enumerate() {
            let mu_r = mu[i];
            if mu_r == 0.0 {
                continue;
            }
            match &self.rows[r] {
                Row::Displacement { axis, .. } => {
                    axpy12(&mut g12, mu_r, &displacement::jacobian(&f, *axis));
                }
                Row::Angle { row, coord } => {
                    let nu = coord.map_or(0.0, |c| coords[c].q);
                    axpy12(&mut g12, mu_r, &row.jacobian(&f, nu, 0));
                }
                Row::Drive { .. } | Row::Servo { .. } => {}
            }
        }
        self.add_reaction_tangent(&f, &rots, coords, mu, &g12, k);
    }

    /// Per row, `u = sᵀ K₁₂(e_r)` with `s = (vᴬ, Rᴬwᴬ, vᴮ, Rᴮwᴮ)` the spatial velocities,
    /// to the material columns (`u_θ Rᵀ`), plus the rotation of those columns,
    /// `w × (Rᵀ m_r)` (`m_r` the row's moment part), and the coordinate terms of a
    /// defining row: `ν̇ ∂b_r/∂ν` in the node columns, `s·∂b_r/∂ν + ν̇ ∂²Φ/∂ν²` in its own.
    /// The same terms as [`Self::reaction_tangent`] at μ = e_r times `v`, without forming
    /// the 12 × 12 matrices.
    fn velocity_tangent(
        &self,
        _ctx: &EvalContext,
        nodes: &[NodeState],
        coords: &[Coordinate],
        v: &[f64],
        out: &mut DMatrix<f64>,
    ) {
        let f = self.frames(nodes);
        let rots = [self.rotation_of(0, nodes), self.rotation_of(1, nodes)];
        let nq = 6 * self.nodes.len();
        let m = out.nrows();
        let os = out.as_mut_slice();
        os.fill(0.0);
        let mut s12 = Row12::zeros();
        for (x, side) in self.sides.iter().enumerate() {
            if side.node.is_none() {
                continue;
            }
            let c = 6 * side.local;
            let w = rots[x] * Vector3::new(v[c + 3], v[c + 4], v[c + 5]);
            for j in 0..3 {
                s12[6 * x + j] = v[c + j];
                s12[6 * x + 3 + j] = w[j];
            }
        }
        for (i, &r) in self.active.iter().enumerate() {
            let mut k12 = Blocks12::new();
            let (b12, coordinate) = match &self.rows[r] {
                Row::Displacement { axis, .. } => {
                    displacement::force_tangent(&f, *axis, 1.0, &mut k12);
                    (displacement::jacobian(&f, *axis), None)
                }
                Row::Angle { row, coord } => {
                    let nu = coord.map_or(0.0, |c| coords[c].q);
                    row.force_tangent(&f, nu, 1.0, &mut k12);
                    let d = coord.map(|c| (c, row.jacobian(&f, nu, 1), row.value(&f, nu)[2]));
                    (row.jacobian(&f, nu, 0), d)
                }
                Row::Drive { .. } | Row::Servo { .. } => continue,
            };
            let u = k12.left_product(&s12);
            self.to_local(&u, &rots, |c, x| os[c * m + i] = x);
            for (x, side) in self.sides.iter().enumerate() {
                if side.node.is_none() {
                    continue;
                }
                let c = 6 * side.local;
                let mom = Vector3::new(b12[6 * x + 3], b12[6 * x + 4], b12[6 * x + 5]);
                let w = Vector3::new(v[c + 3], v[c + 4], v[c + 5]);
                let t = w.cross(&(rots[x].transpose() * mom));
                for j in 0..3 {
                    os[(c + 3 + j) * m + i] += t[j];
                }
            }
            if let Some((c, db, d2)) = coordinate {
                let nu_dot = v[nq + c];
                self.to_local(&db, &rots, |col, x| os[col * m + i] += nu_dot * x);
                os[(nq + c) * m + i] += db.dot(&s12) + nu_dot * d2;
            }
        }
    }

    isa::copies! {
        /// On x86-64 CPUs with AVX the rows run in a copy compiled for AVX (called through
        /// `dyn Constraint`, they would otherwise be compiled for the baseline only): the
        /// same operations in the same order, no fused multiply–add, so the same bits.
        fn evaluate_rows(
            &self: Joint,
            ctx: &EvalContext,
            nodes: &[NodeState],
            coords: &[Coordinate],
            lambda: &[f64],
            penalty: f64,
            out: RowTerms,
        ) {
            Base | Avx => evaluate_rows_impl,
        }
    }

    fn acceleration_term(
        &self,
        ctx: &EvalContext,
        nodes: &[NodeState],
        coords: &[Coordinate],
        out: &mut [f64],
    ) {
        let f = self.frames_with_rates(nodes);
        for (i, &r) in self.active.iter().enumerate() {
            out[i] = match &self.rows[r] {
                Row::Displacement { axis, .. } => displacement::convective(&f, *axis),
                Row::Angle { row, coord } => {
                    let (nu, nu_dot) = coord.map_or((0.0, 0.0), |c| (coords[c].q, coords[c].v));
                    row.convective(&f, nu, nu_dot)
                }
                Row::Drive { function, .. } => -function.derivatives(ctx.time)[2],
                // The signal's part is the system's (ServoRow).
                Row::Servo { .. } => 0.0,
            };
        }
    }

    fn velocity_term(&self, ctx: &EvalContext, out: &mut [f64]) {
        for (i, &r) in self.active.iter().enumerate() {
            out[i] = match &self.rows[r] {
                Row::Drive { function, .. } => -function.derivatives(ctx.time)[1],
                _ => 0.0,
            };
        }
    }

    fn coordinate_forces(
        &self,
        _ctx: &EvalContext,
        coords: &[Coordinate],
        signals: &[f64],
        r: &mut [f64],
        mut tangents: Option<CoordinateTangents>,
    ) {
        let n_in = self.inputs.len();
        for (c, loads) in self.loads.iter().enumerate() {
            if loads.is_empty() {
                continue;
            }
            let input = self.input_of[c].map_or(0.0, |i| signals[i]);
            let [f, k, d] = loads.residual(input, coords[c].q, coords[c].v);
            r[c] += f;
            if let Some(t) = tangents.as_mut() {
                t.stiffness[c] += k;
                t.damping[c] += d;
                if let Some(i) = self.input_of[c] {
                    t.signals[c * n_in + i] -= 1.0;
                }
            }
        }
    }

    fn signal_inputs(&self) -> &[String] {
        &self.inputs
    }

    fn servo_rows(&self) -> &[ServoRow] {
        &self.servos
    }

    fn potential_energy(&self, coords: &[Coordinate]) -> f64 {
        self.loads
            .iter()
            .zip(coords)
            .map(|(l, c)| l.potential_energy(c.q))
            .sum()
    }

    fn dissipated_power(&self, coords: &[Coordinate]) -> f64 {
        self.loads
            .iter()
            .zip(coords)
            .map(|(l, c)| l.dissipated_power(c.q, c.v))
            .sum()
    }

    fn external_power(&self, _ctx: &EvalContext, coords: &[Coordinate], signals: &[f64]) -> f64 {
        self.loads
            .iter()
            .zip(coords)
            .zip(&self.input_of)
            .map(|((l, c), i)| l.external_power(i.map_or(0.0, |i| signals[i]), c.v))
            .sum()
    }

    fn n_rows(&self) -> usize {
        self.rows.len()
    }

    fn row_role(&self, r: usize) -> RowRole {
        self.rows[r].role()
    }

    fn drop_rows(&mut self, rows: &[usize]) {
        debug_assert!(
            rows.iter()
                .all(|&r| self.rows[r].role() == RowRole::Constraint)
        );
        self.active.retain(|r| !rows.contains(r));
        self.plain = plain_rows(&self.rows, &self.active);
    }

    fn active_rows(&self) -> &[usize] {
        &self.active
    }

    fn evaluate_all_rows(
        &self,
        ctx: &EvalContext,
        nodes: &[NodeState],
        coords: &[Coordinate],
        phi: &mut [f64],
        b: &mut DMatrix<f64>,
    ) {
        let all: Vec<usize> = (0..self.rows.len()).collect();
        self.fill(ctx, nodes, coords, &all, phi, Some(b));
    }

    fn reactions(
        &self,
        nodes: &[NodeState],
        coords: &[Coordinate],
        mu_all: &[f64],
    ) -> (Vector3<f64>, Vector3<f64>) {
        let f = self.frames(nodes);
        let mut g = Row12::zeros();
        for (row, &mu) in self.rows.iter().zip(mu_all) {
            if mu != 0.0 {
                g += self.row_value(&f, coords, 0.0, row).b * mu;
            }
        }
        let force = -Vector3::new(g[6], g[7], g[8]);
        let moment = -Vector3::new(g[9], g[10], g[11]) - f.arm[1].cross(&force);
        let ea = f.axes[0];
        (ea.transpose() * force, ea.transpose() * moment)
    }

    fn location(&self, nodes: &[NodeState]) -> (Vector3<f64>, Matrix3<f64>) {
        let f = self.frames(nodes);
        (f.x[1] + f.arm[1], f.axes[0])
    }

    fn coordinate_names(&self) -> Vec<String> {
        self.components
            .iter()
            .map(|&c| format!("{}.{}", self.name, COMPONENT_NAMES[c]))
            .collect()
    }

    fn measure_coordinates(&self, nodes: &[NodeState], out: &mut [f64]) {
        let f = self.frames(nodes);
        let rel = f.axes[0].transpose() * f.axes[1];
        let r: [[f64; 3]; 3] = std::array::from_fn(|p| std::array::from_fn(|q| rel[(p, q)]));
        let dv = f.axes[0].transpose() * f.d();
        let d = [dv.x, dv.y, dv.z];
        for (c, &comp) in self.components.iter().enumerate() {
            out[c] = measure(self.kind, comp, &r, &d);
        }
    }

    fn measure_coordinate_rates(
        &self,
        nodes: &[NodeState],
        coords: &[Coordinate],
        out: &mut [f64],
    ) {
        let f = self.frames_with_rates(nodes);
        let vel = f.spatial_velocities();
        let mut done = [false; 6];
        for row in &self.rows {
            if row.role() != RowRole::Definition {
                continue;
            }
            let v = self.row_value(&f, coords, 0.0, row);
            if let Some((c, d)) = v.dnu
                && !done[c]
                && d.abs() > 1e-12
            {
                // Φ̇ = b·(v, ω) + (∂Φ/∂ν) ν̇ = 0.
                out[c] = -v.b.dot(&vel) / d;
                done[c] = true;
            }
        }
    }

    isa::copies! {
        /// On x86-64 CPUs with AVX this runs in a copy compiled for AVX (behind `dyn
        /// Constraint` it would be compiled for the baseline only; ~1.5 % of the chain's
        /// samples, once per joint and step): no fused multiply–add, the same bits.
        fn update_passive_coordinates(
            &self: Joint,
            nodes: &[NodeState],
            passive: &mut [Coordinate],
            rates: bool,
        ) {
            Base | Avx => update_passive_impl,
        }
    }

    fn is_driven(&self, c: usize) -> bool {
        self.drive_row(c).is_some()
    }

    fn drive_row(&self, c: usize) -> Option<usize> {
        self.rows.iter().position(
            |r| matches!(r, Row::Drive { coord, .. } | Row::Servo { coord, .. } if *coord == c),
        )
    }
}

/// `g += μ b` for 12-entry rows (the sum of the row forces).
#[inline]
fn axpy12(g: &mut Row12, mu: f64, b: &Row12) {
    for (g, b) in g.as_mut_slice().iter_mut().zip(b.as_slice()) {
        *g += b * mu;
    }
}
