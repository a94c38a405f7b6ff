//! The constraint contract: holonomic (possibly rheonomic) constraints `Φ(q, ν, t) = 0`
//! enforced with Lagrange multipliers, and the joint coordinates ν they own (seed eq. 13).
//!
//! A constraint returns `Φ`, its Jacobian `B = ∂Φ/∂(q, ν)` (columns: 6 per node — δx
//! global, δθ material — then one per joint coordinate), the tangent `∂(Bᵀμ)/∂(q, ν)` at
//! fixed multipliers, the parts of `Φ̇` and `Φ̈` that do not multiply velocities or
//! accelerations, and the forces of the elements attached to its coordinates (springs,
//! dampers, backlash, input ports). Scaling, the augmented-Lagrangian term and the
//! assembly of `Bᵀμ` are done generically by the assembler.

use super::{Coordinate, EvalContext, NodeState};
use nalgebra::{DMatrix, Matrix3, Vector3};

/// What a row does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RowRole {
    /// Constrains a component to zero (may be dropped when redundant).
    Constraint,
    /// Defines a joint coordinate.
    Definition,
    /// Drives a joint coordinate.
    Drive,
}

/// Tangents of the coordinate forces: `∂r/∂ν` and `∂r/∂ν̇`, diagonal (one per coordinate),
/// and `∂r/∂s` of the input signals (row-major: coordinate c, input j at `c·inputs + j`).
pub struct CoordinateTangents<'a> {
    pub stiffness: &'a mut [f64],
    pub damping: &'a mut [f64],
    pub signals: &'a mut [f64],
}

/// A servo row `Φ = ν_c − s_j = 0`: its target is input signal `input` (an index into
/// [`Constraint::signal_inputs`]) rather than a function of time. The constraint
/// evaluates the row as `Φ = ν_c` with `B = e_ν` (coordinate `coordinate`), `Φ̇ − Bv = 0`,
/// `Φ̈ − Bv̇ = 0`; the system subtracts `s_j` from Φ, `ṡ_j` from the velocity row and
/// `∂s_j/∂x` from the row's Jacobian over the signal's support. Its multiplier acts on ν
/// only (the actuator force, `−μ`): the row is not the transpose of its column.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ServoRow {
    /// Index among all rows (see [`Constraint::n_rows`]). Its value enters
    /// [`Constraint::evaluate_rows`] as [`RowTerms::targets`].
    pub row: usize,
    pub input: usize,
    pub coordinate: usize,
}

/// What one evaluation of a constraint's rows returns (see [`Constraint::evaluate_rows`]).
pub struct RowTerms<'a> {
    /// `Φ` (length `n_equations`).
    pub phi: &'a mut [f64],
    /// The augmented multipliers `μ = λ + ρ Φ`.
    pub mu: &'a mut [f64],
    /// The generalized constraint force `Bᵀμ` over the local columns (overwritten).
    pub force: &'a mut [f64],
    /// `B` (`n_equations × (6·nodes + n_coordinates)`): written when `want_b` is set or
    /// `tangent` is given, left as it was otherwise (the residual alone needs only `Bᵀμ`).
    pub b: &'a mut DMatrix<f64>,
    pub want_b: bool,
    /// `∂(Bᵀμ)/∂(q, ν)` at fixed `μ` (square, overwritten), when the matrix is wanted.
    pub tangent: Option<&'a mut DMatrix<f64>>,
    /// Per enforced equation, the value of the servo row's signal, subtracted from its
    /// `Φ` before `μ` is formed ([`ServoRow`]; zero on the other rows, or empty when the
    /// constraint has no servo rows).
    pub targets: &'a [f64],
}

/// A constraint on a few nodes and its own joint coordinates.
pub trait Constraint: Send + Sync {
    fn name(&self) -> &str;
    /// Nodes touched, in the order of the local columns of `B`.
    fn nodes(&self) -> &[usize];
    /// Number of joint coordinates owned (their columns follow the node columns).
    fn n_coordinates(&self) -> usize {
        0
    }
    /// Number of scalar equations enforced (multipliers).
    fn n_equations(&self) -> usize;
    /// Whether every row is invariant under a rigid motion of the whole constraint (a
    /// relative constraint between two frames). Then `B_A G_A + B_B G_B = 0` for the
    /// rigid motions, with `G_A`, `G_B` invertible, so the rows restricted to either
    /// node's columns have the rank of all of them, and the block LU may eliminate the
    /// multipliers right after either node, if they are that node's only multipliers left
    /// and couple to nothing but their nodes ([`crate::solve::BlockKind`]).
    fn is_relative(&self) -> bool {
        false
    }
    /// `Φ` and, if given, `B` (`n_equations × (6·nodes + n_coordinates)`, overwritten).
    fn evaluate(
        &self,
        ctx: &EvalContext,
        nodes: &[NodeState],
        coords: &[Coordinate],
        phi: &mut [f64],
        b: Option<&mut DMatrix<f64>>,
    );
    /// The enforced rows' discrete gradient over a step (the energy-consistent
    /// integrators): `B̄` (`n_equations × (6·nodes + n_coordinates)`, overwritten) with
    /// `B̄ Δ = Φ(q₁, ν₁, t) − Φ(q₀, ν₀, t)` exactly for the step's increments
    /// `Δ = (Δx, ψ, Δν)` (`R₁ = R₀ cay(ψ)`), and `B̄ G = 0` for every superposed rigid
    /// motion G that leaves the rows invariant, so that the constraint forces `B̄ᵀλ`
    /// do no work and have no resultant or moment beyond the ground's reaction.
    /// `column_maps[k]` maps node k's spatial rotation column to its ψ column,
    /// `R₀(I + ψ̃/2)`.
    fn discrete_jacobian(
        &self,
        start: &[NodeState],
        end: &[NodeState],
        coords: [&[Coordinate]; 2],
        column_maps: &[Matrix3<f64>],
        b: &mut DMatrix<f64>,
    );
    /// Adds `∂(Bᵀμ)/∂(q, ν)` at fixed `μ` into `k` (square, `6·nodes + n_coordinates`).
    fn reaction_tangent(
        &self,
        ctx: &EvalContext,
        nodes: &[NodeState],
        coords: &[Coordinate],
        mu: &[f64],
        k: &mut DMatrix<f64>,
    );
    /// `∂(B v)/∂(q, ν)` at fixed `v` (`n_equations × (6·nodes + n_coordinates)`,
    /// overwritten), `v` the local rates (node velocities, material angular velocities,
    /// coordinate rates): row r is `vᵀ ∂(b_rᵀ)/∂(q, ν)`, the reaction tangent at μ = e_r
    /// applied to `v` — the velocity rows' tangent of the stabilized index-2 step.
    fn velocity_tangent(
        &self,
        ctx: &EvalContext,
        nodes: &[NodeState],
        coords: &[Coordinate],
        v: &[f64],
        out: &mut DMatrix<f64>,
    );
    /// One evaluation of the rows for the Newton iteration: `Φ`, `μ = λ + ρΦ` (`lambda`
    /// in physical units, `penalty` = ρ), `Bᵀμ` and, if asked, `B` and `∂(Bᵀμ)/∂(q, ν)`
    /// at that μ — what [`Constraint::evaluate`] and [`Constraint::reaction_tangent`] give
    /// together, without evaluating the rows twice. The default calls those two.
    fn evaluate_rows(
        &self,
        ctx: &EvalContext,
        nodes: &[NodeState],
        coords: &[Coordinate],
        lambda: &[f64],
        penalty: f64,
        out: RowTerms,
    ) {
        self.evaluate(ctx, nodes, coords, out.phi, Some(out.b));
        for (p, s) in out.phi.iter_mut().zip(out.targets) {
            *p -= s;
        }
        for ((m, l), p) in out.mu.iter_mut().zip(lambda).zip(out.phi.iter()) {
            *m = l + penalty * p;
        }
        let b = &*out.b;
        for (j, f) in out.force.iter_mut().enumerate() {
            *f = (0..b.nrows()).map(|r| b[(r, j)] * out.mu[r]).sum();
        }
        if let Some(k) = out.tangent {
            k.fill(0.0);
            self.reaction_tangent(ctx, nodes, coords, out.mu, k);
        }
    }
    /// `Φ̈ − B (v̇, ν̈)`: the part of the constraint acceleration without accelerations
    /// (convective terms and `∂²Φ/∂t²`).
    fn acceleration_term(
        &self,
        ctx: &EvalContext,
        nodes: &[NodeState],
        coords: &[Coordinate],
        out: &mut [f64],
    );
    /// `∂Φ/∂t` (non-zero for drives).
    fn velocity_term(&self, _ctx: &EvalContext, out: &mut [f64]) {
        out.fill(0.0);
    }
    /// Residual rows of the coordinates from attached elements, `r = f_int(ν, ν̇) − f_in(t)`,
    /// added into `r`; with `tangents`, `∂r/∂ν` and `∂r/∂ν̇` added too.
    fn coordinate_forces(
        &self,
        _ctx: &EvalContext,
        _coords: &[Coordinate],
        _signals: &[f64],
        _r: &mut [f64],
        _tangents: Option<CoordinateTangents>,
    ) {
    }
    /// Names of the signals read by the coordinate elements (input ports) and the servo
    /// rows.
    fn signal_inputs(&self) -> &[String] {
        &[]
    }
    /// The servo rows, whose targets are input signals.
    fn servo_rows(&self) -> &[ServoRow] {
        &[]
    }
    /// Potential energy of the coordinate springs and backlash contacts.
    fn potential_energy(&self, _coords: &[Coordinate]) -> f64 {
        0.0
    }
    /// Power dissipated by coordinate dampers and contact damping (≥ 0).
    fn dissipated_power(&self, _coords: &[Coordinate]) -> f64 {
        0.0
    }
    /// Times where the constraint's drives jump or kink (their breakpoints).
    fn breakpoints(&self, _out: &mut Vec<f64>) {}
    /// Power of the input ports.
    fn external_power(&self, _ctx: &EvalContext, _coords: &[Coordinate], _signals: &[f64]) -> f64 {
        0.0
    }
    /// All rows, including those dropped as redundant (for reactions).
    fn n_rows(&self) -> usize {
        self.n_equations()
    }
    /// What row `r` (among all rows) does.
    fn row_role(&self, _r: usize) -> RowRole {
        RowRole::Constraint
    }
    /// Stops enforcing the given constraint rows (found redundant).
    fn drop_rows(&mut self, rows: &[usize]);
    /// Index of each enforced equation among all rows.
    fn active_rows(&self) -> &[usize];
    /// `Φ` and `B` of all rows (enforced or not), same layout as [`Constraint::evaluate`].
    fn evaluate_all_rows(
        &self,
        ctx: &EvalContext,
        nodes: &[NodeState],
        coords: &[Coordinate],
        phi: &mut [f64],
        b: &mut DMatrix<f64>,
    ) {
        self.evaluate(ctx, nodes, coords, phi, Some(b));
    }
    /// Force and moment exerted on side B by side A (about B's frame origin), in frame-A
    /// components, for multipliers of all rows `mu_all` in physical units.
    fn reactions(
        &self,
        nodes: &[NodeState],
        coords: &[Coordinate],
        mu_all: &[f64],
    ) -> (Vector3<f64>, Vector3<f64>);
    /// Global position of the joint point on side B and the axes of frame A (columns,
    /// global components), for output.
    fn location(&self, nodes: &[NodeState]) -> (Vector3<f64>, Matrix3<f64>);
    /// Passive coordinates: free components with nothing attached. Nothing depends on
    /// them, so they are not unknowns of the Newton system; they follow from their
    /// defining equations after each step ([`Constraint::update_passive_coordinates`]).
    fn n_passive_coordinates(&self) -> usize {
        0
    }
    /// Names of the joint coordinates (`<joint>.<component>`), the active ones first.
    fn coordinate_names(&self) -> Vec<String> {
        Vec::new()
    }
    /// Values of all coordinates (active, then passive) implied by the node configuration
    /// (principal values; for initialization).
    fn measure_coordinates(&self, _nodes: &[NodeState], _out: &mut [f64]) {}
    /// Solves the defining equations of the passive coordinates for value (continued from
    /// the current value, so angles keep counting turns) and, with `rates`, rate and
    /// acceleration.
    fn update_passive_coordinates(
        &self,
        _nodes: &[NodeState],
        _passive: &mut [Coordinate],
        _rates: bool,
    ) {
    }
    /// Coordinate rates implied by the node velocities (through the defining equations).
    fn measure_coordinate_rates(
        &self,
        _nodes: &[NodeState],
        _coords: &[Coordinate],
        _out: &mut [f64],
    ) {
    }
    /// Whether coordinate `c` is driven (its value is prescribed).
    fn is_driven(&self, _c: usize) -> bool {
        false
    }
    /// Row of all rows that drives coordinate `c`, if any (its multiplier is the
    /// actuator force).
    fn drive_row(&self, _c: usize) -> Option<usize> {
        None
    }
}
