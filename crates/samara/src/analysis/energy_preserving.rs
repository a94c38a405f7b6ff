//! Energy-consistent time integration: the energy-preserving scheme and its
//! energy-decaying generalization (`integrator = "energy_preserving"` /
//! `"energy_decaying"`; docs/integrators.md).
//!
//! Each node moves over a step by `Δ = (Δx, ψ)` with `x₁ = x₀ + Δx`, `R₁ = R₀ cay(ψ)`
//! (Cayley update; Simo & Wong 1991) and the kinematics
//!
//! ```text
//! Δx/h = (v₀ + v₁)/2 + c P(Δv − s b),     ψ/h = (Ω₀ + Ω₁)/2 + c (ΔΩ − s ΔΩ_prev)
//! ```
//!
//! with `Δv = v₁ − v₀`, `ΔΩ_prev` the previous step's, `s = min(h/h_prev, 1)`, P the
//! M-orthogonal projector that makes the translations' dissipation
//! moment-free ([`super::moment_neutral`]: `Σ m_i (Pδ)_i × Δx_i = 0`) and `b` the
//! previous step's `PΔv`. Equilibrium is imposed in the discrete form of every element
//! ([`crate::core::DiscreteStep`]; a discrete gradient of its energy) plus the constraint
//! forces `B̄ᵀλ`, with the constraints enforced at the end of the step, `Φ(q₁, t₁) = 0`.
//! `B̄` is the rows' discrete gradient (`Constraint::discrete_jacobian`: their Jacobian at
//! the frames' mean over the step), `B̄Δ = Φ(q₁, t₁) − Φ(q₀, t₁)` exactly, so the
//! constraint forces do no work over a step (Gonzalez 1999, "Mechanical systems subject
//! to holonomic constraints", Physica D 132; Betsch & Leyendecker 2006 reach the same
//! statement by a discrete null space), and `B̄` annihilates the superposed rigid
//! motions, so they have no resultant and no moment.
//!
//! c = 0 is the preserving scheme. For c > 0 (the decaying scheme) every element with a
//! potential adds the dissipative stress `c C (e − s e_prev)` on its strain increments
//! e over the step (a spring's Δl, a beam's Δε at its elastic points, a joint
//! coordinate's Δν), also against the previous step's. Dotting the step's equations with
//! Δ (the inertia rows give `ΔT + c ⟨PΔv, PΔv − s Pb⟩_M + c ΔΩᵀJ(ΔΩ − sΔΩ_prev)`: MP is
//! symmetric and P² = P) and using `a(a − s b) ≥ (a² − b²)/2` for s ≤ 1 and
//! `‖Pb‖_M ≤ ‖b‖_M`:
//!
//! ```text
//! Ẽ₁ − Ẽ₀ ≤ W − D − (c/2)(‖PΔv − sPb‖²_M + ‖ΔΩ − sΔΩ_prev‖²_J + Σ‖e − s e_prev‖²_C) ≤ W − D,
//! Ẽ = E + (c/2)(‖b_last‖²_M + ‖ΔΩ_last‖²_J + Σ_e ‖e_last‖²_C),
//! ```
//!
//! the discrete energy Ẽ, which differs from E by O(h²), never increases without applied
//! loads (D ≥ 0 the dampers' dissipation). The scheme is a two-step one, and like BDF2
//! it is started by a one-step method: its first step is the preserving one (c = 0: E₁ =
//! E₀ − D exactly), whose increments are the memory of the second, so Ẽ is defined from
//! the first step on, `Ẽ₁ = E₁ + (c/2)(‖PΔv₁‖²_M + …)` (above E₀ by O(h²) on a resolved
//! motion; on any, with quadratic energies measured from their minimum, by at most
//! `2c(E₀ + E₁) = 4cE₀ ≤ E₀/4`, since ‖Δv‖² ≤ 2‖v₀‖² + 2‖v₁‖²), and never increases after. All dissipative terms are second differences
//! (O(h²) on a smooth motion; P depends on the directions of the increments only, so it
//! varies smoothly), so the scheme is second order; on a linear oscillator (where P = I)
//! its high-frequency spectral radius is the ρ∞ with `c = ρ∞(1 − ρ∞)/(2(1 + ρ∞)²)`,
//! ρ∞ ∈ [1/3, 1] (the minimum, c = 1/16, is a double root). Momenta: the dissipation on
//! the strains is internal (no resultant, no moment); linear momentum never depends on
//! the kinematics (`Σ m Δv = h Σ f̄`); the translations' kinematic term would leave the
//! angular momentum `Σ Δx_i × m v̄_i = c Σ m (Pδ)_i × Δx_i`, which P zeroes; and the
//! rotations' Simo–Wong balance holds for any ψ. So linear and angular momentum are exact
//! (to the Newton tolerance) where no external load acts, through joints too. Bauchau, Bottasso & Trainelli
//! (2003, time-discontinuous two-stage steps) and Armero & Romero (2001, EDMC methods)
//! reach the same statements by other constructions; this one (second differences with a
//! two-step memory, in the spirit of the G-stability of BDF2, Dahlquist 1978, plus the
//! projector) is samara's own.
//!
//! The Newton matrix is formed by forward differences of the step residual, sparse: the
//! columns are perturbed in groups that share no row (`sparse_differences`), so for the
//! preserving scheme one matrix costs a few dozen residual evaluations whatever the
//! model's size, and it is factored by faer's sparse LU (symbolic analysis once). Its
//! pattern is the coupling of the elements' and joints' unknowns. The decaying scheme's
//! projector P couples every node's translation to all others (through the rigid
//! rotation it removes), so there the translations form one dense block of the pattern
//! and each needs its own residual evaluation: the matrix stays exact (dropping the
//! block left Newton short of the tolerance-level momenta and energy statements), at a
//! cost that grows with the number of nodes.

use super::moment_neutral;
use super::sparse_differences::{ColumnGroups, PatternLu};
use super::{AnalysisSummary, Energy, OutputFrame, Progress, Recorder, SolverFailure};
use crate::core::{Coordinate, DiscreteStep, Element, NodeState, gonzalez_correction};
use crate::math::cayley::cayley;
use crate::math::{Rotation, skew};
use crate::model::{DynamicSettings, IntegratorType};
use crate::system::{State, System};
use nalgebra::{DMatrix, Matrix3, Vector3};
use std::time::Instant;

/// The decaying scheme's dissipation coefficient c for a high-frequency spectral radius
/// ρ∞ of a linear oscillator (the root −ρ∞ of `(½ + c) r² + (½ − 2c) r + c` is the
/// dominant one for ρ∞ ≥ 1/3): `c = ρ∞(1 − ρ∞)/(2(1 + ρ∞)²)`. ρ∞ below 1/3 (refused at
/// validation) is clamped to 1/3, the scheme's strongest dissipation.
pub fn decay_parameter(rho_inf: f64) -> f64 {
    let r = rho_inf.clamp(MIN_RHO_INF, 1.0);
    r * (1.0 - r) / (2.0 * (1.0 + r) * (1.0 + r))
}

/// The smallest ρ∞ the decaying scheme reaches.
pub const MIN_RHO_INF: f64 = IntegratorType::DECAYING_MIN_RHO_INF;

/// One step's failure.
#[derive(Clone, Debug, PartialEq)]
pub struct StepFailure {
    pub reason: String,
}

/// The energy-consistent integrator, stepped by hand ([`EnergyStepper::step`]) or by
/// [`run_energy_consistent`].
pub struct EnergyStepper<'a> {
    sys: &'a System,
    /// Dissipation coefficient c (0: preserving).
    xi: f64,
    /// The coefficient of the step being taken: 0 on the decaying scheme's first step
    /// (the starting step, which seeds the memory), `xi` after it.
    xi_step: f64,
    tolerance: f64,
    relative_tolerance: f64,
    max_iterations: usize,
    state: State,
    /// Scale of the multipliers (λ = m̄ λ̃ / h²) and of the constraint rows.
    mbar: f64,
    n_node: usize,
    n_coord: usize,
    // Scratch.
    end: Vec<NodeState>,
    mid: Vec<NodeState>,
    end_coords: Vec<Coordinate>,
    mid_coords: Vec<Coordinate>,
    local: Vec<f64>,
    phi1: Vec<f64>,
    delta: Vec<f64>,
    /// Each joint's discrete Jacobian (rows × local unknowns) and its nodes' rotation
    /// column maps `R₀(I + ψ̃/2)`.
    joint_jacobians: Vec<DMatrix<f64>>,
    column_maps: Vec<Matrix3<f64>>,
    /// A joint's coordinates at rest, and their spring and total forces.
    still_coords: Vec<Coordinate>,
    coord_spring: Vec<f64>,
    coord_force: Vec<f64>,
    /// The Newton iteration's unknowns, residual, perturbed residual and correction, and
    /// the constraint values after a step.
    newton_u: Vec<f64>,
    newton_r: Vec<f64>,
    newton_rp: Vec<f64>,
    newton_du: Vec<f64>,
    phi_end: Vec<f64>,
    /// LU of the Newton matrix, for the step `lu_h` it was formed for (modified Newton:
    /// kept across steps while the iteration contracts).
    pattern_lu: PatternLu,
    lu_h: f64,
    /// The Newton matrix's pattern and column groups (taken out while differencing).
    groups: Option<ColumnGroups>,
    /// Decaying scheme's memory: the last step's PΔv, ΔΩ per node (6 per node), the
    /// elements' strain increments (offsets `mem_offsets`), the joint coordinates' Δν;
    /// `*_scaled` the same times s for the step being taken.
    dv_last: Vec<f64>,
    dv_scaled: Vec<f64>,
    mem_offsets: Vec<usize>,
    mem_last: Vec<f64>,
    mem_scaled: Vec<f64>,
    dnu_last: Vec<f64>,
    dnu_scaled: Vec<f64>,
    /// Translational mass of every node (the projector's M).
    node_mass: Vec<f64>,
    /// PΔv_c of every node's mass point at the last configured iterate (the
    /// translations' memory).
    projected_dv: Vec<Vector3<f64>>,
    /// The CG offset of the body on each node that carries one off the node (the node's
    /// mass point; the node carries no other inertia), and the mass points' increment
    /// and start velocity at the last configured iterate.
    mass_offsets: Vec<Option<Vector3<f64>>>,
    mass_dx: Vec<Vector3<f64>>,
    mass_v0: Vec<Vector3<f64>>,
    /// Weights of the joint coordinates' dissipation: |∂f/∂ν| of their springs at the
    /// start (constant, so that the energy statement telescopes).
    coord_stiffness: Vec<f64>,
    /// Step of the last step taken (NaN before the first, which is the preserving starting step).
    h_last: f64,
    /// Newton matrices formed so far.
    pub factorizations: usize,
    /// max |Φ| after the last step.
    pub constraint_violation: f64,
    /// Newton iterations of the last step.
    pub iterations: usize,
}

impl<'a> EnergyStepper<'a> {
    /// From a consistent `state` (on the constraints, velocities tangent to them).
    /// Fails, naming the element or joint, when something has no discrete form.
    pub fn new(
        sys: &'a System,
        integrator: IntegratorType,
        rho_inf: f64,
        tolerance: f64,
        relative_tolerance: f64,
        max_iterations: usize,
        state: State,
    ) -> Result<Self, StepFailure> {
        let xi = match integrator {
            IntegratorType::EnergyPreserving => 0.0,
            IntegratorType::EnergyDecaying => decay_parameter(rho_inf),
            IntegratorType::GeneralizedAlpha => {
                return Err(StepFailure {
                    reason: "the energy-consistent stepper was asked for generalized-α".into(),
                });
            }
        };
        check_discrete_forms(sys)?;
        let n_node = 6 * sys.n_nodes();
        let n_coord = sys.n_coordinates;
        let n = n_node + n_coord + sys.n_multipliers;
        let max_local = sys
            .elements
            .iter()
            .map(|e| 6 * e.nodes().len())
            .chain(
                sys.constraints
                    .iter()
                    .map(|c| 6 * c.nodes().len() + c.n_coordinates()),
            )
            .max()
            .unwrap_or(0);
        let max_rows = sys
            .constraints
            .iter()
            .map(|c| c.n_equations())
            .max()
            .unwrap_or(0);
        let mut mem_offsets = Vec::with_capacity(sys.elements.len() + 1);
        let mut off = 0;
        for e in &sys.elements {
            mem_offsets.push(off);
            if xi > 0.0 {
                off += e.discrete_memory_len();
            }
        }
        mem_offsets.push(off);
        let mut coord_stiffness = vec![0.0; n_coord];
        if xi > 0.0 {
            let ctx = sys.context(state.time, 1.0);
            for (k, c) in sys.constraints.iter().enumerate() {
                let nc = c.n_coordinates();
                if nc == 0 {
                    continue;
                }
                let co = sys.coordinate_offsets[k];
                let mut r = vec![0.0; nc];
                let mut kk = vec![0.0; nc];
                let mut dd = vec![0.0; nc];
                let mut ss = vec![0.0; nc * c.signal_inputs().len().max(1)];
                c.coordinate_forces(
                    &ctx,
                    &state.coords[co..co + nc],
                    &[],
                    &mut r,
                    Some(crate::core::CoordinateTangents {
                        stiffness: &mut kk,
                        damping: &mut dd,
                        signals: &mut ss,
                    }),
                );
                for (j, k) in kk.iter().enumerate() {
                    coord_stiffness[co + j] = k.abs();
                }
            }
        }
        let max_coords = sys
            .constraints
            .iter()
            .map(|c| c.n_coordinates())
            .max()
            .unwrap_or(0);
        let groups = Some(newton_pattern(sys, n_node, n_coord, n, xi > 0.0));
        Ok(Self {
            sys,
            xi,
            xi_step: xi,
            groups,
            pattern_lu: PatternLu::default(),
            joint_jacobians: sys
                .constraints
                .iter()
                .map(|c| DMatrix::zeros(c.n_equations(), 6 * c.nodes().len() + c.n_coordinates()))
                .collect(),
            column_maps: vec![
                Matrix3::identity();
                sys.constraints
                    .iter()
                    .map(|c| c.nodes().len())
                    .max()
                    .unwrap_or(0)
            ],
            still_coords: vec![Coordinate::default(); max_coords],
            coord_spring: vec![0.0; max_coords],
            coord_force: vec![0.0; max_coords],
            newton_u: vec![0.0; n],
            newton_r: vec![0.0; n],
            newton_rp: vec![0.0; n],
            newton_du: vec![0.0; n],
            phi_end: vec![0.0; sys.n_multipliers],
            dv_last: vec![0.0; n_node],
            dv_scaled: vec![0.0; n_node],
            mem_last: vec![0.0; off],
            mem_scaled: vec![0.0; off],
            mem_offsets,
            dnu_last: vec![0.0; n_coord],
            dnu_scaled: vec![0.0; n_coord],
            node_mass: sys.discrete_node_masses(),
            projected_dv: vec![Vector3::zeros(); sys.n_nodes()],
            mass_offsets: offset_mass_points(sys)?,
            mass_dx: vec![Vector3::zeros(); sys.n_nodes()],
            mass_v0: vec![Vector3::zeros(); sys.n_nodes()],
            coord_stiffness,
            h_last: f64::NAN,
            tolerance,
            relative_tolerance,
            max_iterations,
            mbar: sys.characteristic_mass,
            n_node,
            n_coord,
            end: state.nodes.clone(),
            mid: state.nodes.clone(),
            end_coords: state.coords.clone(),
            mid_coords: state.coords.clone(),
            local: vec![0.0; max_local],
            phi1: vec![0.0; max_rows],
            delta: vec![0.0; max_local],
            state,
            lu_h: f64::NAN,
            factorizations: 0,
            constraint_violation: 0.0,
            iterations: 0,
        })
    }

    pub fn state(&self) -> &State {
        &self.state
    }

    /// The decaying scheme's dissipation coefficient c (0: preserving).
    pub fn xi(&self) -> f64 {
        self.xi
    }

    /// The discrete energy of the decaying scheme,
    /// `Ẽ = E + (c/2)(‖PΔv_last‖²_M + ‖ΔΩ_last‖²_J + Σ_e ‖e_last‖²_C + Σ k_ν Δν_last²)`,
    /// which never increases in a step without applied loads (the module's
    /// documentation); E for the preserving scheme.
    pub fn decaying_energy(&self) -> f64 {
        let e = self.energy();
        if self.xi == 0.0 {
            return e;
        }
        // The memory's norm is 2 T(PΔv, ΔΩ): the kinetic energy of the state moving with it.
        let mut moving = self.state.clone();
        for (i, n) in moving.nodes.iter_mut().enumerate() {
            let d = &self.dv_last[6 * i..6 * i + 6];
            n.w = Vector3::new(d[3], d[4], d[5]);
            // The memory is the mass point's: an offset body's CG moves with PΔv_c.
            let cg = self.mass_offsets[i].map_or(Vector3::zeros(), |s| n.r() * n.w.cross(&s));
            n.v = Vector3::new(d[0], d[1], d[2]) - cg;
        }
        let ctx = self.sys.context(self.state.time, 1.0);
        let (t_dv, _) = self.sys.discrete_energies(&ctx, &moving);
        let mut memory = 0.0;
        for (k, el) in self.sys.elements.iter().enumerate() {
            let (a, b) = (self.mem_offsets[k], self.mem_offsets[k + 1]);
            if b > a {
                memory += el.discrete_memory_energy(&self.mem_last[a..b]);
            }
        }
        let coords: f64 = self
            .coord_stiffness
            .iter()
            .zip(&self.dnu_last)
            .map(|(k, d)| 0.5 * k * d * d)
            .sum();
        e + self.xi * (t_dv + memory + coords)
    }

    /// Residual evaluations per Newton matrix: the column groups of its pattern.
    pub fn jacobian_groups(&self) -> usize {
        self.groups.as_ref().map_or(0, ColumnGroups::n_groups)
    }

    /// Kinetic plus potential energy at the current state.
    pub fn energy(&self) -> f64 {
        let ctx = self.sys.context(self.state.time, 1.0);
        let (t, v) = self.sys.discrete_energies(&ctx, &self.state);
        t + v
    }

    /// Sets node, coordinate and scratch states for the unknowns `u`.
    fn configure(&mut self, h: f64, u: &[f64]) {
        // Rotations: ψ/h = (Ω₀ + Ω₁)/2 + c(Ω₁ − Ω₀ − s ΔΩ_prev), solved for Ω₁.
        // Translations of each node's mass point (the node, or the CG of an offset body
        // on it: Δx_c = Δx + (R₀ψ) × s̄, v_c = v + R(Ω × s)): Δx_c/h = v̄_c + c P(Δv_c − s b)
        // with P the moment-free projector of the increments (`moment_neutral`) and b the
        // last step's PΔv_c. With y = Δx_c/h − v_c0 + c P(s b) and P² = P:
        // Δv_c = (½ + cP)⁻¹ y = 2(I − P)y + P y/(½ + c).
        let xi = self.xi_step;
        let (c0, c1) = (0.5 - xi, 0.5 + xi);
        for (i, n0) in self.state.nodes.iter().enumerate() {
            let d = &u[6 * i..6 * i + 6];
            let dx = Vector3::new(d[0], d[1], d[2]);
            let psi = Vector3::new(d[3], d[4], d[5]);
            let p = &self.dv_scaled[6 * i..6 * i + 6];
            let e = &mut self.end[i];
            e.rot = Rotation::from_quaternion(n0.rot.quaternion() * cayley(&psi));
            e.w = (psi / h + Vector3::new(p[3], p[4], p[5]) * xi - n0.w * c0) / c1;
            (self.mass_dx[i], self.mass_v0[i]) = match self.mass_offsets[i] {
                Some(s) => (
                    dx + (n0.r() * psi).cross(&((n0.r() * s + e.r() * s) * 0.5)),
                    n0.v + n0.r() * n0.w.cross(&s),
                ),
                None => (dx, n0.v),
            };
        }
        let dx_of = |i: usize| self.mass_dx[i];
        let sb_of = |i: usize| {
            let p = &self.dv_scaled[6 * i..6 * i + 3];
            Vector3::new(p[0], p[1], p[2])
        };
        let w_of = |i: usize| self.mass_dx[i] / h - self.mass_v0[i];
        // The projector is formed whenever the scheme decays, also on its (preserving)
        // first step, whose PΔv is the memory of the second.
        let (zw, zb) = if self.xi > 0.0 {
            let pinv = moment_neutral::increment_inertia_pinv(&self.node_mass, dx_of);
            (
                moment_neutral::removed_rotation(&self.node_mass, &pinv, dx_of, w_of),
                moment_neutral::removed_rotation(&self.node_mass, &pinv, dx_of, sb_of),
            )
        } else {
            (Vector3::zeros(), Vector3::zeros())
        };
        for (i, n0) in self.state.nodes.iter().enumerate() {
            let d = &u[6 * i..6 * i + 6];
            let dx = Vector3::new(d[0], d[1], d[2]);
            let psi = Vector3::new(d[3], d[4], d[5]);
            let w = w_of(i);
            let mi = self.node_mass[i];
            let dxm = self.mass_dx[i];
            let pw = moment_neutral::project(mi, &dxm, &w, &zw);
            let psb = moment_neutral::project(mi, &dxm, &sb_of(i), &zb);
            let pdv = (pw + psb * xi) / c1;
            self.projected_dv[i] = pdv;
            let vm1 = self.mass_v0[i] + (w - pw) * 2.0 + pdv;
            let e = &mut self.end[i];
            let v1 = match self.mass_offsets[i] {
                Some(s) => vm1 - e.r() * e.w.cross(&s),
                None => vm1,
            };
            let a = (v1 - n0.v) / h;
            let wd = (e.w - n0.w) / h;
            e.x = n0.x + dx;
            e.v = v1;
            e.a = a;
            e.wd = wd;
            let m = &mut self.mid[i];
            m.x = n0.x + dx * 0.5;
            m.rot = Rotation::from_quaternion(n0.rot.quaternion() * cayley(&(psi * 0.5)));
            m.v = dx / h;
            m.w = psi / h;
            m.a = a;
            m.wd = wd;
        }
        for (j, c0) in self.state.coords.iter().enumerate().take(self.n_coord) {
            let dq = u[self.n_node + j];
            self.end_coords[j] = Coordinate {
                q: c0.q + dq,
                v: dq / h,
                a: 0.0,
            };
            self.mid_coords[j] = Coordinate {
                q: c0.q + 0.5 * dq,
                v: dq / h,
                a: 0.0,
            };
        }
    }

    /// Step residual at `u = (Δ, Δν, λ̃)`: equilibrium rows × h², constraint rows × m̄.
    fn residual(&mut self, h: f64, u: &[f64], r: &mut [f64]) {
        self.configure(h, u);
        r.fill(0.0);
        let sys = self.sys;
        let t0 = self.state.time;
        let ctx_mid = sys.context(t0 + 0.5 * h, 1.0);
        let ctx1 = sys.context(t0 + h, 1.0);
        let h2 = h * h;
        let xi = self.xi_step;
        {
            let step = DiscreteStep {
                h,
                ctx: ctx_mid,
                start: &self.state.nodes,
                end: &self.end,
                mid: &self.mid,
                increments: &u[..self.n_node],
                decay: xi,
                memory: &[],
            };
            for (k, e) in sys.elements.iter().enumerate() {
                let nodes = e.nodes();
                let nl = 6 * nodes.len();
                let local = &mut self.local[..nl];
                local.fill(0.0);
                let own = DiscreteStep {
                    memory: &self.mem_scaled[self.mem_offsets[k]..self.mem_offsets[k + 1]],
                    ..step
                };
                e.discrete_residual(&own, local);
                for (a, &ni) in nodes.iter().enumerate() {
                    for k in 0..6 {
                        r[6 * ni + k] += h2 * self.local[6 * a + k];
                    }
                }
            }
        }
        let coords0 = &self.state.coords;
        for (k, c) in sys.constraints.iter().enumerate() {
            let nodes = c.nodes();
            let nn = 6 * nodes.len();
            let nc = c.n_coordinates();
            let cols = nn + nc;
            let m = c.n_equations();
            let co = sys.coordinate_offsets[k];
            let mo = sys.multiplier_offsets[k];
            let delta = &mut self.delta[..cols];
            for (a, &ni) in nodes.iter().enumerate() {
                delta[6 * a..6 * a + 6].copy_from_slice(&u[6 * ni..6 * ni + 6]);
            }
            delta[nn..].copy_from_slice(&u[self.n_node + co..self.n_node + co + nc]);
            if m > 0 {
                c.evaluate(
                    &ctx1,
                    &self.end,
                    &self.end_coords[co..co + nc],
                    &mut self.phi1[..m],
                    None,
                );
                // The rows' discrete gradient (`Constraint::discrete_jacobian`): B̄Δ =
                // Φ(q₁) − Φ(q₀) exactly, and no resultant or moment of B̄ᵀλ beyond the
                // ground's, with the rotation columns conjugate to ψ the way the rigid
                // bodies' are (`R₀(I + ψ̃/2)` on the spatial columns).
                for (a, &ni) in nodes.iter().enumerate() {
                    let psi = Vector3::new(delta[6 * a + 3], delta[6 * a + 4], delta[6 * a + 5]);
                    self.column_maps[a] =
                        self.state.nodes[ni].r() * (Matrix3::identity() + skew(&psi) * 0.5);
                }
                let bm = &mut self.joint_jacobians[k];
                c.discrete_jacobian(
                    &self.state.nodes,
                    &self.end,
                    [&coords0[co..co + nc], &self.end_coords[co..co + nc]],
                    &self.column_maps[..nodes.len()],
                    bm,
                );
                for j in 0..m {
                    let lam = u[self.n_node + self.n_coord + mo + j];
                    for (a, &ni) in nodes.iter().enumerate() {
                        for q in 0..6 {
                            r[6 * ni + q] += self.mbar * bm[(j, 6 * a + q)] * lam;
                        }
                    }
                    for q in 0..nc {
                        r[self.n_node + co + q] += self.mbar * bm[(j, nn + q)] * lam;
                    }
                    r[self.n_node + self.n_coord + mo + j] = self.mbar * self.phi1[j];
                }
            }
            if nc > 0 {
                // Coordinate springs: Gonzalez discrete gradient of their potential;
                // dampers at the mean rate Δν/h.
                let still = &mut self.still_coords[..nc];
                for (x, m) in still.iter_mut().zip(&self.mid_coords[co..co + nc]) {
                    *x = Coordinate {
                        q: m.q,
                        v: 0.0,
                        a: 0.0,
                    };
                }
                let fs = &mut self.coord_spring[..nc];
                fs.fill(0.0);
                c.coordinate_forces(&ctx_mid, still, &[], fs, None);
                let dv = c.potential_energy(&self.end_coords[co..co + nc])
                    - c.potential_energy(&coords0[co..co + nc]);
                let full = &mut self.coord_force[..nc];
                full.fill(0.0);
                c.coordinate_forces(&ctx_mid, &self.mid_coords[co..co + nc], &[], full, None);
                for (f, s) in full.iter_mut().zip(fs.iter()) {
                    *f -= s;
                }
                gonzalez_correction(fs, &delta[nn..], dv);
                for q in 0..nc {
                    // Decay: c k_ν (Δν − s Δν_prev), dissipating c k_ν Δν (Δν − s Δν_prev).
                    let dis = xi
                        * self.coord_stiffness[co + q]
                        * (delta[nn + q] - self.dnu_scaled[co + q]);
                    r[self.n_node + co + q] += h2 * (fs[q] + full[q] + dis);
                }
            }
        }
    }

    /// One step of size h: modified Newton (the matrix kept while it contracts), retried
    /// once with a new matrix in every iteration. On failure the state is unchanged.
    pub fn step(&mut self, h: f64) -> Result<(), StepFailure> {
        self.solve_step(h, false)
            .or_else(|_| self.solve_step(h, true))
    }

    fn solve_step(&mut self, h: f64, full: bool) -> Result<(), StepFailure> {
        if self.xi > 0.0 {
            // The decaying scheme is a two-step scheme: its first step is the preserving
            // one (c = 0, E exactly conserved), which seeds the memory, so the
            // dissipative terms are second differences from the second step on. (A
            // first step with c > 0 and no memory makes c PΔv an O(h) term and the
            // velocities first order over the start-up.)
            let starting = !self.h_last.is_finite();
            let xi_step = if starting { 0.0 } else { self.xi };
            if xi_step != self.xi_step {
                // The Newton matrix was formed for the other coefficient.
                self.pattern_lu.forget();
                self.xi_step = xi_step;
            }
            // s = min(h/h_prev, 1): the second differences are O(h²) on a smooth motion
            // for any s ≈ h/h_prev, and s ≤ 1 keeps the energy statement.
            let s = if starting {
                0.0
            } else {
                (h / self.h_last).min(1.0)
            };
            for (a, b) in self.dv_scaled.iter_mut().zip(&self.dv_last) {
                *a = s * b;
            }
            for (a, b) in self.mem_scaled.iter_mut().zip(&self.mem_last) {
                *a = s * b;
            }
            for (a, b) in self.dnu_scaled.iter_mut().zip(&self.dnu_last) {
                *a = s * b;
            }
        }
        let mut u = std::mem::take(&mut self.newton_u);
        let mut r = std::mem::take(&mut self.newton_r);
        let mut rp = std::mem::take(&mut self.newton_rp);
        let mut du = std::mem::take(&mut self.newton_du);
        let result = self.newton(h, full, &mut u, &mut r, &mut rp, &mut du);
        self.newton_u = u;
        self.newton_r = r;
        self.newton_rp = rp;
        self.newton_du = du;
        result
    }

    /// The Newton iteration of [`EnergyStepper::solve_step`] on the work vectors given
    /// (each of length n).
    fn newton(
        &mut self,
        h: f64,
        full: bool,
        u: &mut [f64],
        r: &mut [f64],
        rp: &mut [f64],
        du: &mut [f64],
    ) -> Result<(), StepFailure> {
        u.fill(0.0);
        // Predictor: Δ = h v₀.
        for (i, nd) in self.state.nodes.iter().enumerate() {
            let p = nd.v * h;
            let w = nd.w * h;
            u[6 * i..6 * i + 3].copy_from_slice(p.as_slice());
            u[6 * i + 3..6 * i + 6].copy_from_slice(w.as_slice());
        }
        for j in 0..self.n_coord {
            u[self.n_node + j] = self.state.coords[j].v * h;
        }
        let lscale = h * h / self.mbar;
        for (j, l) in self.state.lambda.iter().enumerate() {
            u[self.n_node + self.n_coord + j] = l * lscale;
        }
        if self.lu_h != h {
            self.pattern_lu.forget();
        }
        let mut last = f64::INFINITY;
        let mut converged = false;
        let ncfg = self.n_node + self.n_coord;
        for it in 0..self.max_iterations {
            self.residual(h, u, r);
            if r.iter().any(|x| !x.is_finite()) {
                return Err(StepFailure {
                    reason: "the step residual is not finite".into(),
                });
            }
            if !self.pattern_lu.is_factored() {
                // Grouped forward differences from the residual just evaluated.
                let mut groups = self
                    .groups
                    .take()
                    .expect("the pattern is kept between uses");
                groups.jacobian(u, r, rp, |x, out| self.residual(h, x, out));
                let factored = self.pattern_lu.factor(groups.matrix());
                self.groups = Some(groups);
                // `residual` left the scratch states at the last perturbation.
                self.configure(h, u);
                if !factored {
                    return Err(StepFailure {
                        reason: "the Newton matrix of the step is singular".into(),
                    });
                }
                self.factorizations += 1;
            }
            du.copy_from_slice(r);
            self.pattern_lu.solve_in_place(du);
            if !du.iter().all(|x| x.is_finite()) {
                return Err(StepFailure {
                    reason: "the Newton matrix of the step is singular".into(),
                });
            }
            let mut worst: f64 = 0.0;
            for (j, (x, d)) in u.iter_mut().zip(du.iter()).enumerate() {
                *x -= d;
                if j < ncfg {
                    worst =
                        worst.max(d.abs() / (self.tolerance + self.relative_tolerance * x.abs()));
                }
            }
            self.iterations = it + 1;
            if !worst.is_finite() {
                return Err(StepFailure {
                    reason: "the Newton correction is not finite".into(),
                });
            }
            if worst <= 1.0 {
                converged = true;
                break;
            }
            // Modified Newton: a new matrix when the iteration stops contracting fast
            // (a fresh one contracts quadratically).
            if full || worst > 0.05 * last {
                self.pattern_lu.forget();
            }
            last = worst;
        }
        self.lu_h = h;
        if !converged {
            self.pattern_lu.forget();
            return Err(StepFailure {
                reason: format!(
                    "Newton did not converge in {} iterations",
                    self.max_iterations
                ),
            });
        }
        self.configure(h, u);
        if self.xi > 0.0 {
            self.update_memory(h, u);
        }
        std::mem::swap(&mut self.state.nodes, &mut self.end);
        for j in 0..self.n_coord {
            self.state.coords[j] = self.end_coords[j];
        }
        let s = self.mbar / (h * h);
        for (j, l) in self.state.lambda.iter_mut().enumerate() {
            *l = u[ncfg + j] * s;
        }
        self.state.time += h;
        self.sys.update_passive_coordinates(&mut self.state, true);
        let ctx = self.sys.context(self.state.time, 1.0);
        self.sys
            .constraint_values(&ctx, &self.state, &mut self.phi_end);
        self.constraint_violation = self.phi_end.iter().fold(0.0, |m, x| m.max(x.abs()));
        // Keep the scratch copies in step with the new state (their rotations are reused).
        self.end.clone_from(&self.state.nodes);
        Ok(())
    }
}

impl EnergyStepper<'_> {
    /// After a converged step (scratch states configured for `u`): the memories of the
    /// decaying scheme.
    fn update_memory(&mut self, h: f64, u: &[f64]) {
        for (i, (n0, n1)) in self.state.nodes.iter().zip(&self.end).enumerate() {
            // The translations keep PΔv (`configure`), the rotations ΔΩ.
            let dv = self.projected_dv[i];
            let dw = n1.w - n0.w;
            self.dv_last[6 * i..6 * i + 3].copy_from_slice(dv.as_slice());
            self.dv_last[6 * i + 3..6 * i + 6].copy_from_slice(dw.as_slice());
        }
        let step = DiscreteStep {
            h,
            ctx: self.sys.context(self.state.time + 0.5 * h, 1.0),
            start: &self.state.nodes,
            end: &self.end,
            mid: &self.mid,
            increments: &u[..self.n_node],
            decay: self.xi,
            memory: &[],
        };
        for (k, e) in self.sys.elements.iter().enumerate() {
            let (a, b) = (self.mem_offsets[k], self.mem_offsets[k + 1]);
            if b > a {
                e.discrete_memory(&step, &mut self.mem_last[a..b]);
            }
        }
        self.dnu_last
            .copy_from_slice(&u[self.n_node..self.n_node + self.n_coord]);
        self.h_last = h;
    }
}

/// The pattern of the step residual's Jacobian in the unknowns `(Δ, Δν, λ̃)`: every
/// element couples the 6-blocks of its nodes; every joint its nodes, coordinates and
/// multipliers (its rows Φ₁, its forces B̄ᵀλ, its coordinate springs). Each node's own
/// block is always there; with `decaying` all translations couple (the projector P).
fn newton_pattern(
    sys: &System,
    n_node: usize,
    n_coord: usize,
    n: usize,
    decaying: bool,
) -> ColumnGroups {
    let mut rows_of: Vec<Vec<usize>> = vec![Vec::new(); n];
    let mut couple = |cols: &[usize]| {
        for &j in cols {
            rows_of[j].extend_from_slice(cols);
        }
    };
    let node_cols = |nodes: &[usize], out: &mut Vec<usize>| {
        for &i in nodes {
            out.extend(6 * i..6 * i + 6);
        }
    };
    let mut cols = Vec::new();
    if decaying {
        cols.extend((0..sys.n_nodes()).flat_map(|i| 6 * i..6 * i + 3));
        couple(&cols);
    }
    for i in 0..sys.n_nodes() {
        cols.clear();
        node_cols(&[i], &mut cols);
        couple(&cols);
    }
    for e in &sys.elements {
        cols.clear();
        node_cols(e.nodes(), &mut cols);
        couple(&cols);
    }
    for (k, c) in sys.constraints.iter().enumerate() {
        cols.clear();
        node_cols(c.nodes(), &mut cols);
        let co = sys.coordinate_offsets[k];
        cols.extend(n_node + co..n_node + co + c.n_coordinates());
        let mo = sys.multiplier_offsets[k];
        cols.extend(n_node + n_coord + mo..n_node + n_coord + mo + c.n_equations());
        couple(&cols);
    }
    ColumnGroups::new(n, rows_of)
}

/// The consistent start of a dynamic analysis from the model's initial state (assembled
/// onto the joints, velocities tangent to them, multipliers): what [`EnergyStepper::new`]
/// takes when stepping by hand. `Err` gives the reason.
pub fn consistent_initial_state(sys: &System, settings: &DynamicSettings) -> Result<State, String> {
    let mut summary = AnalysisSummary::new("start", "dynamic");
    super::dynamic::consistent_start(sys, settings, sys.initial_state(), &mut summary).map_err(
        |_| {
            summary
                .failure
                .map_or_else(|| "no consistent start".into(), |f| f.reason)
        },
    )
}

/// Fails, naming the element or joint, when something in `sys` has no discrete form.
pub fn check_discrete_forms(sys: &System) -> Result<(), StepFailure> {
    for e in &sys.elements {
        if let Err(why) = e.discrete_form() {
            return Err(StepFailure {
                reason: format!("element `{}`: {why}", e.name()),
            });
        }
        if e.n_states() > 0 {
            return Err(StepFailure {
                reason: format!(
                    "element `{}` has first-order states, which the energy-consistent integrators do not integrate yet",
                    e.name()
                ),
            });
        }
    }
    for c in &sys.constraints {
        if !c.signal_inputs().is_empty() {
            return Err(StepFailure {
                reason: format!(
                    "joint `{}` has input ports or a drive_signal (servo), which the energy-consistent integrators do not support yet",
                    c.name()
                ),
            });
        }
    }
    Ok(())
}

/// The CG offset of the body on each node whose body sits off it (`None` elsewhere).
/// Such a node's kinematic relation is written for the CG, so it must carry no other
/// inertia (another body, or a beam's lumped mass): refused, naming both.
fn offset_mass_points(sys: &System) -> Result<Vec<Option<Vector3<f64>>>, StepFailure> {
    let mut carriers: Vec<Vec<String>> = vec![Vec::new(); sys.n_nodes()];
    for b in &sys.bodies {
        carriers[b.nodes()[0]].push(format!("body `{}`", b.name()));
    }
    for beam in &sys.beams {
        for e in &beam.elements {
            for (i, _) in e.lumped_node_masses() {
                let who = format!("beam `{}`", beam.name);
                if !carriers[i].contains(&who) {
                    carriers[i].push(who);
                }
            }
        }
    }
    let mut out = vec![None; sys.n_nodes()];
    for b in &sys.bodies {
        let s = b.cg_offset();
        if s == Vector3::zeros() {
            continue;
        }
        let i = b.nodes()[0];
        if carriers[i].len() > 1 {
            return Err(StepFailure {
                reason: format!(
                    "body `{}` has a `cg_offset` and its node `{}` also carries {}: the energy-consistent integrators write that node's kinematics for the body's CG, so it must carry no other inertia (give the body a node of its own, joined by a `fixed` joint)",
                    b.name(),
                    sys.node_names[i],
                    carriers[i]
                        .iter()
                        .filter(|c| **c != format!("body `{}`", b.name()))
                        .cloned()
                        .collect::<Vec<_>>()
                        .join(" and ")
                ),
            });
        }
        out[i] = Some(s);
    }
    Ok(out)
}

/// The dynamic analysis with an energy-consistent integrator: fixed steps (halved after
/// a Newton failure, down to `min_step`; shortened to land on the breakpoints of the time
/// functions), recorded every `output_every` steps.
pub(super) fn run_energy_consistent(
    sys: &System,
    name: &str,
    settings: &DynamicSettings,
    initial: State,
    recorder: &mut dyn Recorder,
    progress: Progress,
) -> Result<AnalysisSummary, crate::Error> {
    let clock = Instant::now();
    let mut summary = AnalysisSummary::new(name, "dynamic");
    let fail = |summary: &mut AnalysisSummary, time: f64, reason: String, hint: Option<String>| {
        summary.failure = Some(SolverFailure {
            analysis: name.to_string(),
            time,
            reason,
            hint,
        });
    };
    if let Err(f) = check_discrete_forms(sys) {
        fail(
            &mut summary,
            settings.t_start,
            f.reason,
            Some("use integrator = \"generalized_alpha\" for this model (docs/integrators.md lists the element kinds with discrete forms)".into()),
        );
        summary.final_state = initial;
        summary.wall_time = clock.elapsed();
        return Ok(summary);
    }
    let state = match super::dynamic::consistent_start(sys, settings, initial, &mut summary) {
        Ok(s) => s,
        Err(s) => {
            summary.final_state = *s;
            summary.wall_time = clock.elapsed();
            return Ok(summary);
        }
    };
    let t0 = settings.t_start;
    let mut it = match EnergyStepper::new(
        sys,
        settings.integrator,
        settings.rho_inf,
        settings.solver.tolerance,
        settings.solver.relative_tolerance,
        settings.solver.max_iterations,
        state,
    ) {
        Ok(it) => it,
        Err(f) => {
            fail(&mut summary, t0, f.reason, None);
            summary.wall_time = clock.elapsed();
            return Ok(summary);
        }
    };
    let energy_at = |it: &EnergyStepper| {
        let ctx = sys.context(it.state.time, 1.0);
        let (kinetic, potential) = sys.discrete_energies(&ctx, &it.state);
        Energy {
            kinetic,
            potential,
            external_work: 0.0,
            dissipated: 0.0,
        }
    };
    let power_in = |it: &EnergyStepper| {
        let ctx = sys.context(it.state.time, 1.0);
        sys.external_power(&ctx, &it.state)
    };
    let mut p_dis = sys.dissipated_power(&it.state);
    let mut p_ext = power_in(&it);
    let mut dissipated = 0.0;
    let mut external_work = 0.0;
    let record = |it: &EnergyStepper, energy: Energy, rec: &mut dyn Recorder| {
        rec.record(
            sys,
            &OutputFrame {
                time: it.state.time,
                state: &it.state,
                mu: &it.state.lambda,
                energy,
                constraint_violation: it.constraint_violation,
                load_factor: 1.0,
                diagnostics: None,
            },
        )
    };
    record(&it, energy_at(&it), recorder)?;
    let span = settings.t_end - t0;
    let mut h = settings.step;
    let mut grid_k: u64 = 0;
    let mut good = 0usize;
    let mut step_index = 0usize;
    // Steps land on the breakpoints of the time functions (load kinks and jumps), so the
    // mid-point rule never straddles one: a piecewise-linear load then does exactly its
    // impulse.
    let breakpoints = sys.breakpoints();
    // Steps also land on the output instants of `output_interval` (short of the grid
    // point like a breakpoint).
    let mut outputs = super::output_grid::OutputGrid::new(t0, settings.output_interval);
    while it.state.time < settings.t_end {
        let t = it.state.time;
        let mut target = if h == settings.step {
            t0 + (grid_k + 1) as f64 * settings.step
        } else {
            t + h
        };
        let mut on_breakpoint = false;
        if let Some(&b) = breakpoints.iter().find(|&&b| b > t + 1e-9 * h)
            && b < target - 1e-9 * h
        {
            target = b;
            on_breakpoint = true;
        }
        if let Some(g) = &outputs {
            let o = g.land(target, h);
            if o < target - 1e-9 * h {
                target = o;
                on_breakpoint = true;
            }
        }
        if target > settings.t_end || settings.t_end - target < 1e-9 * h {
            target = settings.t_end;
        }
        let h_try = target - t;
        match it.step(h_try) {
            Ok(()) => {
                it.state.time = target;
                summary.steps += 1;
                summary.newton_iterations += it.iterations;
                step_index += 1;
                if on_breakpoint {
                    // Short of the grid point: the next step completes it.
                } else if h == settings.step {
                    grid_k += 1;
                } else {
                    good += 1;
                    if good >= 4 {
                        h = (2.0 * h).min(settings.step);
                        good = 0;
                        if h == settings.step {
                            grid_k = ((it.state.time - t0) / settings.step).round() as u64;
                        }
                    }
                }
                summary.max_constraint_violation = summary
                    .max_constraint_violation
                    .max(it.constraint_violation);
                let p1 = sys.dissipated_power(&it.state);
                dissipated += 0.5 * h_try * (p_dis + p1);
                p_dis = p1;
                let e1 = power_in(&it);
                external_work += 0.5 * h_try * (p_ext + e1);
                p_ext = e1;
                let last = it.state.time >= settings.t_end;
                let output = match outputs.as_mut() {
                    Some(g) => g.reached(it.state.time, h_try),
                    None => step_index.is_multiple_of(settings.output_every),
                };
                if output || last {
                    let mut energy = energy_at(&it);
                    energy.dissipated = dissipated;
                    energy.external_work = external_work;
                    if let Some(what) = super::first_non_finite(sys, &it.state, &energy) {
                        summary.failure =
                            Some(super::non_finite_failure(name, it.state.time, what));
                        break;
                    }
                    if let Some(what) = sys.range_violation(&it.state) {
                        summary.failure = Some(super::range_failure(name, it.state.time, what));
                        break;
                    }
                    record(&it, energy, recorder)?;
                }
                progress(((it.state.time - t0) / span).clamp(0.0, 1.0));
            }
            Err(f) => {
                summary.rejected_steps += 1;
                let next = h_try / 2.0;
                if next < settings.min_step {
                    fail(
                        &mut summary,
                        t,
                        format!("{} with step {h_try:.3e} s", f.reason),
                        Some(format!(
                            "the step was cut down to {h_try:.3e} s (min_step {:.3e}); a smaller `step` or a larger `tolerance` may help",
                            settings.min_step
                        )),
                    );
                    break;
                }
                h = next;
                good = 0;
            }
        }
    }
    summary.final_state = it.state;
    summary.wall_time = clock.elapsed();
    Ok(summary)
}
