//! The system: the model turned into elements, constraints and a DOF layout.
//!
//! Unknowns: node `i` owns 6 (δx global, δθ material); constraint `c` owns its joint
//! coordinates ν (at `coordinate_offsets[c]` in the state) and one multiplier per enforced
//! equation (at `multiplier_offsets[c]`). Where they sit in the Newton vector depends on
//! the formulation and is decided by the [`Assembler`]: node blocks first, then one block
//! per constraint holding its multipliers followed by its coordinates (so that the pivot
//! of a joint with a massless coordinate is never singular).

mod assembly;
pub mod matrices;
pub mod probe;
pub mod redundancy;
pub mod signals;

pub use crate::core::{Coordinate, NodeState, State};
pub use assembly::{
    Assembler, BlockOwner, Coefficients, Formulation, PARALLEL_MIN_ELEMENTS, PARALLEL_WINDOW,
    PartChecks, RateMaps, SplitPlan,
};
pub use matrices::SystemMatrices;
pub use redundancy::ConstraintLoop;
pub use signals::{SignalGraph, SignalValues};

use crate::core::{ElementInput, ElementState};
use crate::elements::{Element, EvalContext, RigidBody};
use crate::joints::Constraint;
use crate::model::Model;
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
    /// Granular contact sets: their pair contacts are not in `elements` (the pairs change
    /// during a run); the dynamic analysis detects them and the [`Assembler`] adds them.
    pub granular: Vec<crate::elements::GranularSet>,
    pub gravity: Vector3<f64>,
    /// Offset of each constraint's enforced multipliers in the multiplier vector.
    pub multiplier_offsets: Vec<usize>,
    pub n_multipliers: usize,
    /// Offset of each constraint's rows (enforced or dropped) in the vector of all rows.
    pub row_offsets: Vec<usize>,
    pub n_rows: usize,
    /// Offset of each constraint's active joint coordinates (unknowns of the Newton
    /// system) in the state.
    pub coordinate_offsets: Vec<usize>,
    pub n_coordinates: usize,
    /// Offset of each constraint's passive coordinates (nothing attached; solved after
    /// each step), counted from `n_coordinates` in the state.
    pub passive_offsets: Vec<usize>,
    pub n_passive: usize,
    /// `<joint>.<component>` per coordinate of the state: all active ones, then all
    /// passive ones.
    pub coordinate_names: Vec<String>,
    /// Closed loops of joints, with the equations dropped as redundant.
    pub loops: Vec<ConstraintLoop>,
    /// Remarks on the model found while building the system (over-constraint).
    pub warnings: Vec<String>,
    /// Mean translational mass per massive node [kg] (1 if the model has no mass).
    pub characteristic_mass: f64,
    /// Node states of the model's initial conditions (for [`System::initial_state`]).
    pub initial_nodes: Vec<NodeState>,
    /// Offset of each element's states in [`State::states`].
    pub state_offsets: Vec<usize>,
    pub n_states: usize,
    /// `<element>.<state>` per element state.
    pub state_names: Vec<String>,
    /// Offset of each element's sample-and-hold values in [`State::held`].
    pub held_offsets: Vec<usize>,
    pub n_held: usize,
    /// The distinct sample periods of the elements that hold values.
    pub sample_periods: Vec<f64>,
    /// Who produces and who reads each signal.
    pub signals: SignalGraph,
    /// First output of each element in the list of outputs (results only).
    pub output_offsets: Vec<usize>,
    /// `(element, first event)` of each element with event functions, and their total.
    pub event_offsets: Vec<(usize, usize)>,
    pub n_events: usize,
    /// `<element>.<output>`, with units.
    pub output_names: Vec<String>,
    pub output_units: Vec<String>,
    /// Scratch of [`System::constraint_values`] for the servo rows' signals (kept, so a
    /// step's constraint check allocates nothing).
    servo_signals: std::sync::Mutex<Option<SignalValues>>,
}

impl System {
    /// Builds the system of a validated model; elements are attached in the model's
    /// initial configuration.
    pub fn new(model: &Model) -> Self {
        let initial = crate::model::components::initial_nodes(model);
        let mut parts = crate::model::components::Build::new(&initial);
        crate::model::components::build_all(model, &mut parts);
        let crate::model::components::Build {
            elements,
            constraints,
            bodies,
            beams,
            granular,
            ..
        } = parts;
        let mut sys = Self::from_parts(
            model.nodes.iter().map(|n| n.name.clone()).collect(),
            elements,
            constraints,
            bodies,
            model.gravity,
            &initial,
        );
        sys.granular = granular;
        if !beams.is_empty() {
            sys.characteristic_mass = characteristic_mass(model, &beams);
            sys.beams = beams;
        }
        sys
    }

    /// The initial conditions written in the model, at rest in acceleration, with the
    /// joint coordinates measured from the node configuration.
    pub fn initial_state(&self) -> State {
        let mut states = vec![ElementState::default(); self.n_states];
        let mut z = Vec::new();
        for (e, &off) in self.elements.iter().zip(&self.state_offsets) {
            z.resize(e.n_states(), 0.0);
            e.initial_states(&mut z);
            for (s, &v) in states[off..].iter_mut().zip(&z) {
                s.z = v;
            }
        }
        let mut s = State {
            time: 0.0,
            nodes: self.initial_nodes.clone(),
            coords: vec![Coordinate::default(); self.n_coordinates + self.n_passive],
            states,
            lambda: vec![0.0; self.n_multipliers],
            held: Box::default(),
            pair_bristles: Vec::new(),
        };
        self.measure_coordinates(&mut s);
        s
    }

    /// What element `k` sees of `state`, with `signals` the values of all signals.
    #[inline]
    pub fn element_input<'a>(
        &self,
        k: usize,
        state: &'a State,
        signals: &'a [f64],
        scratch: &'a mut Vec<f64>,
    ) -> ElementInput<'a> {
        let ids = &self.signals.element_inputs[k];
        scratch.clear();
        scratch.extend(ids.iter().map(|&j| signals[j]));
        ElementInput {
            nodes: &state.nodes,
            states: &state.states[span(&self.state_offsets, k, self.n_states)],
            signals: scratch,
            held: self.held_of(k, state),
        }
    }

    /// Number of element `k`'s states (from the offsets: no virtual call).
    #[inline]
    pub fn n_states_of(&self, k: usize) -> usize {
        span(&self.state_offsets, k, self.n_states).len()
    }

    /// The sample-and-hold values of element `k` in `state` (empty when `state` holds
    /// none: statics, where a hold passes its input through).
    #[inline]
    pub fn held_of<'a>(&self, k: usize, state: &'a State) -> &'a [f64] {
        if state.held.len() != self.n_held {
            return &[];
        }
        // The elements' held values end where the held joint reactions begin.
        let end = self.n_held - self.signals.reactions.len();
        &state.held[span(&self.held_offsets, k, end)]
    }

    /// Whether `t` is a sample instant `k T` of the period `T`, to within 1e-9 T.
    fn on_sample_instant(t: f64, period: f64) -> bool {
        let k = (t / period).round();
        (t - k * period).abs() <= 1e-9 * period
    }

    /// Whether `t` is a sample instant of some sampling element.
    pub fn sample_due(&self, t: f64) -> bool {
        self.sample_periods
            .iter()
            .any(|&p| Self::on_sample_instant(t, p))
    }

    /// The first sample instant `k T` of any sampling element later than `t` by more
    /// than 1e-9 T (None when nothing samples): time steppers land on it.
    pub fn next_sample(&self, t: f64) -> Option<f64> {
        self.sample_periods
            .iter()
            .map(|&p| {
                let mut k = (t / p).floor() + 1.0;
                if k * p - t <= 1e-9 * p {
                    k += 1.0;
                }
                k * p
            })
            .min_by(f64::total_cmp)
    }

    /// Takes the samples due at `state.time` (all of them with `all`, at the start of a
    /// dynamic analysis or when `state` holds none yet) into `state.held`: zero-order
    /// hold, the measurement at `t_k` held until `t_(k+1)`. The values are taken with the
    /// held values before the update (all holds sample at once). Returns whether a held
    /// value changed (the forcing then jumps).
    pub fn sample(&self, state: &mut State, all: bool) -> bool {
        if self.n_held == 0 {
            state.held = Box::default();
            return false;
        }
        let all = all || state.held.len() != self.n_held;
        let due = |e: &dyn Element| {
            e.sample_period()
                .is_some_and(|p| all || Self::on_sample_instant(state.time, p))
        };
        if !all
            && !self
                .sample_periods
                .iter()
                .any(|&p| Self::on_sample_instant(state.time, p))
        {
            return false;
        }
        let ctx = self.context(state.time, 1.0);
        let mut next = state.held.to_vec();
        next.resize(self.n_held, 0.0);
        let signals = self.signal_values(&ctx, state);
        let mut scratch = Vec::new();
        for (k, e) in self.elements.iter().enumerate() {
            let nh = e.n_held();
            if nh == 0 || !due(e.as_ref()) {
                continue;
            }
            let o = self.held_offsets[k];
            let x = self.element_input(k, state, &signals, &mut scratch);
            e.sample(&ctx, &x, &mut next[o..o + nh]);
        }
        if state.held.len() != self.n_held {
            // First holds: the joint reactions of the state's multipliers.
            let first = self.n_held - self.signals.reactions.len();
            self.reaction_values(state, &state.lambda, &mut next[first..]);
        }
        let changed = *next != *state.held;
        state.held = next.into_boxed_slice();
        changed
    }

    /// Holds the joint reactions that signals read ([`SignalGraph::reactions`]) at their
    /// values in the converged `state` with the multipliers `mu` (physical units, as
    /// written in the results): the dynamic analysis calls it after each accepted step,
    /// before taking the samples due, so a sensor sampling a reaction at `t_k` holds its
    /// value at `t_k`, and an unsampled reader sees it during the next step (one step
    /// late). Does nothing when `state` holds no values (statics).
    pub fn hold_reactions(&self, state: &mut State, mu: &[f64]) {
        let n = self.signals.reactions.len();
        if n == 0 || state.held.len() != self.n_held {
            return;
        }
        let mut values = vec![0.0; n];
        self.reaction_values(state, mu, &mut values);
        state.held[self.n_held - n..].copy_from_slice(&values);
    }

    /// Values of the reactions signals read, at `state` with the multipliers `mu`.
    fn reaction_values(&self, state: &State, mu: &[f64], out: &mut [f64]) {
        use signals::ReactionSource;
        let sources = &self.signals.reactions;
        if sources.is_empty() {
            return;
        }
        let ctx = self.context(state.time, 1.0);
        let joint = sources
            .iter()
            .any(|r| !matches!(r.1, ReactionSource::CoordinateForce { .. }));
        let mut fm = vec![(Vector3::zeros(), Vector3::zeros()); self.constraints.len()];
        if joint {
            let mut all = vec![0.0; self.n_rows];
            self.reactions(&ctx, state, mu, &mut all, |k, f, m| fm[k] = (f, m));
        }
        let mut cf = vec![0.0; self.n_coordinates + self.n_passive];
        if sources
            .iter()
            .any(|r| matches!(r.1, ReactionSource::CoordinateForce { .. }))
        {
            self.coordinate_forces(&ctx, state, mu, &mut cf);
        }
        for (o, (_, src)) in out.iter_mut().zip(sources) {
            *o = match *src {
                ReactionSource::Force {
                    constraint,
                    component,
                } => fm[constraint].0[component],
                ReactionSource::Moment {
                    constraint,
                    component,
                } => fm[constraint].1[component],
                ReactionSource::CoordinateForce { coordinate } => cf[coordinate],
            };
        }
    }

    /// Values of all signals at `state` (allocates; the assembler keeps its own scratch).
    pub fn signal_values(&self, ctx: &EvalContext, state: &State) -> Vec<f64> {
        if self.signals.names.is_empty() {
            return Vec::new();
        }
        let mut v = self.signals.values(&self.elements);
        self.signals.evaluate(
            &self.elements,
            &self.state_offsets,
            ctx,
            state,
            &mut v,
            false,
        );
        v.values
    }

    /// Configuration index of element state `i` (of all states).
    pub fn state_config_index(&self, i: usize) -> usize {
        6 * self.n_nodes() + self.n_coordinates + i
    }

    /// Assembles a system from elements and constraints built in code; `initial` is the
    /// configuration at which redundant constraint equations are looked for.
    pub fn from_parts(
        node_names: Vec<String>,
        elements: Vec<Box<dyn Element>>,
        mut constraints: Vec<Box<dyn Constraint>>,
        bodies: Vec<RigidBody>,
        gravity: Vector3<f64>,
        initial: &[NodeState],
    ) -> Self {
        let n = node_names.len();
        let mut coordinate_offsets = Vec::with_capacity(constraints.len());
        let mut passive_offsets = Vec::with_capacity(constraints.len());
        let mut coordinate_names = Vec::new();
        let mut passive_names = Vec::new();
        let (mut nc, mut np) = (0, 0);
        for c in &constraints {
            coordinate_offsets.push(nc);
            passive_offsets.push(np);
            let names = c.coordinate_names();
            coordinate_names.extend_from_slice(&names[..c.n_coordinates()]);
            passive_names.extend_from_slice(&names[c.n_coordinates()..]);
            nc += c.n_coordinates();
            np += c.n_passive_coordinates();
        }
        coordinate_names.extend(passive_names);
        // Redundant equations of closed loops, at the initial configuration.
        let mut coords = vec![Coordinate::default(); nc];
        let mut values = Vec::new();
        for (c, off) in constraints.iter().zip(&coordinate_offsets) {
            values.resize(c.n_coordinates() + c.n_passive_coordinates(), 0.0);
            c.measure_coordinates(initial, &mut values);
            for (k, v) in values[..c.n_coordinates()].iter().enumerate() {
                coords[off + k].q = *v;
            }
        }
        let ctx0 = EvalContext {
            time: 0.0,
            gravity,
            load_factor: 1.0,
        };
        let loops = redundancy::analyse(
            &constraints,
            &coordinate_offsets,
            n,
            &ctx0,
            initial,
            &coords,
        );
        let mut warnings = Vec::new();
        for lp in &loops {
            if lp.dropped.is_empty() {
                continue;
            }
            let names: Vec<&str> = lp
                .constraints
                .iter()
                .map(|&k| constraints[k].name())
                .collect();
            warnings.push(format!(
                "the model is over-constrained by {} equation{}: the loop of joints {} has {} equations of rank {}; the solver drops the redundant ones and writes minimum-norm reactions for the loop",
                lp.dropped.len(),
                if lp.dropped.len() == 1 { "" } else { "s" },
                names
                    .iter()
                    .map(|s| format!("'{s}'"))
                    .collect::<Vec<_>>()
                    .join(", "),
                lp.rows,
                lp.rank
            ));
            for (k, c) in constraints.iter_mut().enumerate() {
                let rows: Vec<usize> = lp
                    .dropped
                    .iter()
                    .filter(|d| d.0 == k)
                    .map(|d| d.1)
                    .collect();
                if !rows.is_empty() {
                    c.drop_rows(&rows);
                }
            }
        }
        let mut multiplier_offsets = Vec::with_capacity(constraints.len());
        let mut row_offsets = Vec::with_capacity(constraints.len());
        let (mut m, mut nr) = (0, 0);
        for c in &constraints {
            multiplier_offsets.push(m);
            m += c.n_equations();
            row_offsets.push(nr);
            nr += c.n_rows();
        }
        // Element states, element by element, after the nodes and the active coordinates
        // in the configuration vector.
        let mut state_offsets = Vec::with_capacity(elements.len());
        let mut state_names = Vec::new();
        let mut nz = 0;
        for e in &elements {
            state_offsets.push(nz);
            nz += e.n_states();
            state_names.extend(e.state_names().iter().map(|s| format!("{}.{s}", e.name())));
        }
        let mut held_offsets = Vec::with_capacity(elements.len());
        let mut n_held = 0;
        let mut sample_periods: Vec<f64> = Vec::new();
        for e in &elements {
            held_offsets.push(n_held);
            n_held += e.n_held();
            if let Some(p) = e.sample_period().filter(|_| e.n_held() > 0)
                && !sample_periods.contains(&p)
            {
                sample_periods.push(p);
            }
        }
        let mut event_offsets = Vec::new();
        let mut n_events = 0;
        for (k, e) in elements.iter().enumerate() {
            if e.n_events() > 0 {
                event_offsets.push((k, n_events));
                n_events += e.n_events();
            }
        }
        // Output quantities, element by element (results only).
        let mut output_offsets = Vec::with_capacity(elements.len());
        let (mut output_names, mut output_units) = (Vec::new(), Vec::new());
        for e in &elements {
            output_offsets.push(output_names.len());
            for (o, u) in e.output_names() {
                output_names.push(format!("{}.{o}", e.name()));
                output_units.push(u.to_string());
            }
        }
        let local_config: Vec<Vec<usize>> = elements
            .iter()
            .zip(&state_offsets)
            .map(|(e, &off)| {
                e.nodes()
                    .iter()
                    .flat_map(|&i| (0..6).map(move |d| 6 * i + d))
                    .chain((0..e.n_states()).map(|i| 6 * n + nc + off + i))
                    .collect()
            })
            .collect();
        let constraint_inputs: Vec<(String, Vec<String>)> = constraints
            .iter()
            .map(|c| (c.name().to_string(), c.signal_inputs().to_vec()))
            .collect();
        let signals = SignalGraph::build(
            &elements,
            &constraint_inputs,
            &local_config,
            signals::DirectNames {
                coordinates: &coordinate_names[..nc],
                states: &state_names,
                first_coordinate: 6 * n,
                first_state: 6 * n + nc,
            },
        );
        // The held joint reactions follow the elements' held values.
        let n_held = signals.n_held();
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
            granular: Vec::new(),
            gravity,
            multiplier_offsets,
            n_multipliers: m,
            row_offsets,
            n_rows: nr,
            coordinate_offsets,
            n_coordinates: nc,
            passive_offsets,
            n_passive: np,
            coordinate_names,
            loops,
            warnings: warnings
                .into_iter()
                .chain(signals.issues.iter().map(|i| i.to_string()))
                .collect(),
            characteristic_mass,
            initial_nodes: initial.to_vec(),
            state_offsets,
            n_states: nz,
            state_names,
            held_offsets,
            n_held,
            sample_periods,
            signals,
            event_offsets,
            n_events,
            output_offsets,
            output_names,
            output_units,
            servo_signals: std::sync::Mutex::new(None),
        }
    }

    /// The joint coordinates of constraint `k` in `s`.
    #[inline]
    pub fn coords_of<'a>(&self, k: usize, s: &'a State) -> &'a [Coordinate] {
        &s.coords[span(&self.coordinate_offsets, k, self.n_coordinates)]
    }

    /// Sets every joint coordinate (active and passive) to the principal value implied by
    /// the nodes of `s`.
    pub fn measure_coordinates(&self, s: &mut State) {
        let mut values = Vec::new();
        for (k, c) in self.constraints.iter().enumerate() {
            let (na, np) = (c.n_coordinates(), c.n_passive_coordinates());
            values.resize(na + np, 0.0);
            c.measure_coordinates(&s.nodes, &mut values);
            let (o, p) = (
                self.coordinate_offsets[k],
                self.n_coordinates + self.passive_offsets[k],
            );
            for (j, v) in values[..na].iter().enumerate() {
                s.coords[o + j].q = *v;
            }
            for (j, v) in values[na..].iter().enumerate() {
                s.coords[p + j].q = *v;
            }
        }
    }

    /// Solves the passive coordinates of `s` from the nodes: the value (continued from the
    /// current one; needed every step so that turns are counted) and, with `rates`, rate
    /// and acceleration (for output).
    pub fn update_passive_coordinates(&self, s: &mut State, rates: bool) {
        if self.n_passive == 0 {
            return;
        }
        for (k, c) in self.constraints.iter().enumerate() {
            let np = c.n_passive_coordinates();
            if np > 0 {
                let p = self.n_coordinates + self.passive_offsets[k];
                c.update_passive_coordinates(&s.nodes, &mut s.coords[p..p + np], rates);
            }
        }
    }

    /// [`Self::update_passive_coordinates`] of the constraints `of` (positions only),
    /// writing their passive coordinates through one part's handle on `coords`.
    pub fn update_passive_coordinates_of(
        &self,
        of: &[usize],
        nodes: &[crate::core::NodeState],
        coords: &mut crate::solve::PartSlice<'_, crate::core::Coordinate>,
    ) {
        for &k in of {
            let c = &self.constraints[k];
            let p = self.n_coordinates + self.passive_offsets[k];
            let np = c.n_passive_coordinates();
            c.update_passive_coordinates(nodes, coords.get_range(p..p + np), false);
        }
    }

    /// Sets every joint coordinate's rate to the value implied by the node velocities.
    pub fn measure_coordinate_rates(&self, s: &mut State) {
        let mut values = Vec::new();
        for (k, (c, off)) in self
            .constraints
            .iter()
            .zip(&self.coordinate_offsets)
            .enumerate()
        {
            let nc = c.n_coordinates();
            values.clear();
            values.extend(self.coords_of(k, s).iter().map(|q| q.v));
            c.measure_coordinate_rates(&s.nodes, &s.coords[*off..off + nc], &mut values);
            for (j, v) in values.iter().enumerate() {
                s.coords[off + j].v = *v;
            }
        }
    }

    /// Multipliers of all rows (zeros at dropped rows, then the minimum-norm solution in
    /// loops with dropped rows), from the enforced multipliers `mu` (physical units).
    pub fn all_multipliers(&self, ctx: &EvalContext, s: &State, mu: &[f64], out: &mut [f64]) {
        out.fill(0.0);
        for (k, c) in self.constraints.iter().enumerate() {
            let (mo, ro) = (self.multiplier_offsets[k], self.row_offsets[k]);
            for (i, &r) in c.active_rows().iter().enumerate() {
                out[ro + r] = mu[mo + i];
            }
        }
        for lp in self.loops.iter().filter(|l| !l.dropped.is_empty()) {
            redundancy::minimum_norm(
                lp,
                &self.constraints,
                &self.row_offsets,
                &self.coordinate_offsets,
                ctx,
                &s.nodes,
                &s.coords,
                out,
            );
        }
    }

    /// Generalized force each coordinate receives from its drive (the actuator force or
    /// torque, `−μ_drive`), zero where there is none; `mu` enforced multipliers.
    pub fn drive_forces(&self, mu: &[f64], out: &mut [f64]) {
        out.fill(0.0);
        for (k, c) in self.constraints.iter().enumerate() {
            let active = c.active_rows();
            for j in 0..c.n_coordinates() {
                if let Some(r) = c.drive_row(j)
                    && let Some(i) = active.iter().position(|&x| x == r)
                {
                    out[self.coordinate_offsets[k] + j] = -mu[self.multiplier_offsets[k] + i];
                }
            }
        }
    }

    /// Generalized force on each coordinate from its elements and its drive (positive
    /// tends to increase the coordinate): `−(f_ν − f_in) − μ_drive`. By the coordinate's
    /// equilibrium it equals the force the joint transmits along the component.
    pub fn coordinate_forces(&self, ctx: &EvalContext, s: &State, mu: &[f64], out: &mut [f64]) {
        self.drive_forces(mu, out);
        let signals = self.signal_values(ctx, s);
        for (k, c) in self.constraints.iter().enumerate() {
            let nc = c.n_coordinates();
            if nc == 0 {
                continue;
            }
            // A joint has at most six coordinates.
            let mut buf = [0.0; 6];
            let r = &mut buf[..nc];
            let sig = self.constraint_signals(k, &signals);
            c.coordinate_forces(ctx, self.coords_of(k, s), &sig, r, None);
            for (j, x) in r.iter().enumerate() {
                out[self.coordinate_offsets[k] + j] -= x;
            }
        }
    }

    /// Reaction force and moment of every joint (on B by A, about B's frame origin, frame-A
    /// components) from the enforced multipliers `mu`; `all` is scratch of `n_rows`.
    pub fn reactions(
        &self,
        ctx: &EvalContext,
        s: &State,
        mu: &[f64],
        all: &mut [f64],
        mut out: impl FnMut(usize, Vector3<f64>, Vector3<f64>),
    ) {
        self.all_multipliers(ctx, s, mu, all);
        for (k, c) in self.constraints.iter().enumerate() {
            let o = self.row_offsets[k];
            let (f, m) = c.reactions(&s.nodes, self.coords_of(k, s), &all[o..o + c.n_rows()]);
            out(k, f, m);
        }
    }

    /// Power delivered by the drives, `Σ (−μ_drive) ν̇`.
    pub fn drive_power(&self, s: &State, mu: &[f64]) -> f64 {
        let mut p = 0.0;
        for (k, c) in self.constraints.iter().enumerate() {
            let active = c.active_rows();
            for j in 0..c.n_coordinates() {
                if let Some(r) = c.drive_row(j)
                    && let Some(i) = active.iter().position(|&x| x == r)
                {
                    let nu_dot = s.coords[self.coordinate_offsets[k] + j].v;
                    p -= mu[self.multiplier_offsets[k] + i] * nu_dot;
                }
            }
        }
        p
    }

    /// Values of the signals read by constraint `k`, from the values of all signals.
    pub fn constraint_signals(&self, k: usize, all: &[f64]) -> Vec<f64> {
        self.signals.constraint_inputs[k]
            .iter()
            .map(|&j| all[j])
            .collect()
    }

    pub fn n_nodes(&self) -> usize {
        self.node_names.len()
    }

    /// Number of configuration unknowns: 6 per node, then the active joint coordinates,
    /// then the element states.
    pub fn n_config(&self) -> usize {
        6 * self.n_nodes() + self.n_coordinates + self.n_states
    }

    /// Clears the elements' warm starts before an analysis ([`Element::begin_analysis`]).
    pub fn begin_analysis(&self) {
        for e in &self.elements {
            e.begin_analysis();
        }
    }

    /// Evaluation context at time `t` with load factor `lf`.
    pub fn context(&self, t: f64, lf: f64) -> EvalContext {
        EvalContext {
            time: t,
            gravity: self.gravity,
            load_factor: lf,
        }
    }

    /// Potential, dissipated and input power of the joint-coordinate elements.
    fn coordinate_sum(&self, s: &State, f: impl Fn(&dyn Constraint, &[Coordinate]) -> f64) -> f64 {
        self.constraints
            .iter()
            .enumerate()
            .map(|(k, c)| f(c.as_ref(), self.coords_of(k, s)))
            .sum()
    }

    /// Σ f(element, input) over the elements; with `energy`, the elements that apply loads
    /// only ([`Element::loads_only`]: zero energies and dissipation) are skipped — the sum
    /// is the same (+0 for an empty sum, as a sum of zeros gives).
    fn element_sum(
        &self,
        s: &State,
        signals: &[f64],
        energy: bool,
        f: impl Fn(&dyn Element, &ElementInput) -> f64,
    ) -> f64 {
        let mut scratch = Vec::new();
        let sum: f64 = (0..self.elements.len())
            .filter(|&k| !(energy && self.elements[k].loads_only()))
            .map(|k| {
                let x = self.element_input(k, s, signals, &mut scratch);
                f(self.elements[k].as_ref(), &x)
            })
            .sum();
        sum + 0.0
    }

    /// [`Self::element_sum`] of an energy or a dissipated power.
    fn energy_sum(
        &self,
        s: &State,
        signals: &[f64],
        f: impl Fn(&dyn Element, &ElementInput) -> f64,
    ) -> f64 {
        self.element_sum(s, signals, true, f)
    }

    /// The first element whose state in `s` is outside its range
    /// ([`Element::range_violation`], which sees nodes and states, no signals), named
    /// with its message.
    pub fn range_violation(&self, s: &State) -> Option<String> {
        self.elements.iter().enumerate().find_map(|(k, e)| {
            let off = self.state_offsets[k];
            let x = ElementInput {
                nodes: &s.nodes,
                states: &s.states[off..off + e.n_states()],
                signals: &[],
                held: &[],
            };
            e.range_violation(&x)
                .map(|m| format!("element '{}': {m}", e.name()))
        })
    }

    pub fn kinetic_energy(&self, s: &State) -> f64 {
        // Elements see their input signals in every evaluation (kinetic energy
        // included), so the signals are evaluated at the state's time.
        let signals = self.signal_values(&self.context(s.time, 1.0), s);
        self.energy_sum(s, &signals, |e, x| e.kinetic_energy(x))
    }

    pub fn potential_energy(&self, ctx: &EvalContext, s: &State) -> f64 {
        let signals = self.signal_values(ctx, s);
        self.energy_sum(s, &signals, |e, x| e.potential_energy(ctx, x))
            + self.coordinate_sum(s, |c, q| c.potential_energy(q))
            + self
                .granular
                .iter()
                .map(|g| g.potential_energy(ctx, &s.nodes))
                .sum::<f64>()
    }

    pub fn external_power(&self, ctx: &EvalContext, s: &State) -> f64 {
        self.power_of(ctx, s, |e, x| e.external_power(ctx, x))
    }

    /// [`Self::external_power`] with each element's [`Element::evaluated_power`]: the
    /// energy balance's power at a step's converged state `s`, right after its Newton
    /// solve.
    pub fn evaluated_external_power(&self, ctx: &EvalContext, s: &State) -> f64 {
        self.power_of(ctx, s, |e, x| e.evaluated_power(ctx, x))
    }

    /// The coordinates' input power plus `element` summed over the elements.
    fn power_of(
        &self,
        ctx: &EvalContext,
        s: &State,
        element: impl Fn(&dyn Element, &ElementInput) -> f64,
    ) -> f64 {
        let signals = self.signal_values(ctx, s);
        let coordinate_inputs: f64 = self
            .constraints
            .iter()
            .enumerate()
            .map(|(k, c)| {
                c.external_power(
                    ctx,
                    self.coords_of(k, s),
                    &self.constraint_signals(k, &signals),
                )
            })
            .sum();
        self.element_sum(s, &signals, false, element) + coordinate_inputs
    }

    /// The sorted, distinct breakpoints of every time function in the model (loads,
    /// signals, drives): adaptive steps land on them.
    pub fn breakpoints(&self) -> Vec<f64> {
        let mut out = Vec::new();
        for e in &self.elements {
            e.breakpoints(&mut out);
        }
        for c in &self.constraints {
            c.breakpoints(&mut out);
        }
        out.retain(|t| t.is_finite());
        out.sort_by(f64::total_cmp);
        out.dedup();
        out
    }

    /// The event functions `(g, ġ)` of every element at `s` ([`Element::events`];
    /// `out.len()` = [`System::n_events`]).
    pub fn event_values(&self, s: &State, out: &mut [(f64, f64)], scratch: &mut Vec<f64>) {
        if self.n_events == 0 {
            return;
        }
        let ctx = self.context(s.time, 1.0);
        let signals = self.signal_values(&ctx, s);
        for &(k, off) in &self.event_offsets {
            let n = self.elements[k].n_events();
            let x = self.element_input(k, s, &signals, scratch);
            self.elements[k].events(&x, &mut out[off..off + n]);
        }
    }

    /// Values of every element's outputs at `s` (`out.len()` = number of outputs).
    pub fn element_outputs(&self, ctx: &EvalContext, s: &State, out: &mut [f64]) {
        if self.output_names.is_empty() {
            return;
        }
        let signals = self.signal_values(ctx, s);
        let mut scratch = Vec::new();
        for (k, e) in self.elements.iter().enumerate() {
            let off = self.output_offsets[k];
            let n = self.output_offsets.get(k + 1).copied().unwrap_or(out.len()) - off;
            if n > 0 {
                let x = self.element_input(k, s, &signals, &mut scratch);
                e.outputs(ctx, &x, &mut out[off..off + n]);
            }
        }
    }

    pub fn dissipated_power(&self, s: &State) -> f64 {
        self.dissipation_of(s, |e, x| e.dissipated_power(x))
    }

    /// [`Self::dissipated_power`] with each element's
    /// [`Element::evaluated_dissipated_power`]: the energy balance's dissipation at a
    /// step's converged state `s`, right after its Newton solve.
    pub fn evaluated_dissipated_power(&self, s: &State) -> f64 {
        self.dissipation_of(s, |e, x| e.evaluated_dissipated_power(x))
    }

    /// The coordinates' and granular sets' dissipation plus `element` summed over the
    /// elements.
    fn dissipation_of(
        &self,
        s: &State,
        element: impl Fn(&dyn Element, &ElementInput) -> f64,
    ) -> f64 {
        let ctx = self.context(s.time, 1.0);
        let signals = self.signal_values(&ctx, s);
        self.energy_sum(s, &signals, element)
            + self.coordinate_sum(s, |c, q| c.dissipated_power(q))
            + self
                .granular
                .iter()
                .enumerate()
                .map(|(k, g)| g.dissipated_power(k, &s.nodes, &s.pair_bristles))
                .sum::<f64>()
    }

    /// Total linear and angular momentum (about the global origin) of the rigid bodies and
    /// the beams (with their inertia lumped at the nodes, as the energy-consistent
    /// integrators take it).
    pub fn momenta(&self, s: &State) -> (Vector3<f64>, Vector3<f64>) {
        let mut p = Vector3::zeros();
        let mut h = Vector3::zeros();
        for b in &self.bodies {
            let (pb, hb) = b.momenta(&s.nodes[b.nodes()[0]]);
            p += pb;
            h += hb;
        }
        for e in self.beams.iter().flat_map(|b| &b.elements) {
            let (pb, hb) = e.lumped_momenta(&s.nodes);
            p += pb;
            h += hb;
        }
        (p, h)
    }

    /// Translational mass of every node as the energy-consistent integrators take it: the
    /// rigid bodies' at their node (the CG there: offsets are refused), the beams' inertia
    /// lumped to their nodes.
    pub fn discrete_node_masses(&self) -> Vec<f64> {
        let mut m = vec![0.0; self.n_nodes()];
        for b in &self.bodies {
            m[b.nodes()[0]] += b.mass();
        }
        for e in self.beams.iter().flat_map(|b| &b.elements) {
            for (i, mk) in e.lumped_node_masses() {
                m[i] += mk;
            }
        }
        m
    }

    /// Kinetic and potential energy as the energy-consistent integrators state their
    /// balance ([`Element::discrete_kinetic_energy`]: a beam's inertia lumped at its nodes).
    pub fn discrete_energies(&self, ctx: &EvalContext, s: &State) -> (f64, f64) {
        let signals = self.signal_values(ctx, s);
        let t = self.energy_sum(s, &signals, |e, x| e.discrete_kinetic_energy(x));
        let v = self.energy_sum(s, &signals, |e, x| e.discrete_potential_energy(ctx, x))
            + self.coordinate_sum(s, |c, q| c.potential_energy(q));
        (t, v)
    }

    /// Constraint values Φ of all constraints, concatenated (servo rows with their
    /// signals subtracted).
    pub fn constraint_values(&self, ctx: &EvalContext, s: &State, out: &mut [f64]) {
        let has_servos = self.constraints.iter().any(|c| !c.servo_rows().is_empty());
        let mut scratch = self
            .servo_signals
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        let signals: &[f64] = if has_servos && !self.signals.names.is_empty() {
            let v = scratch.get_or_insert_with(|| self.signals.values(&self.elements));
            self.signals
                .evaluate(&self.elements, &self.state_offsets, ctx, s, v, false);
            &v.values
        } else {
            &[]
        };
        for (k, (c, off)) in self
            .constraints
            .iter()
            .zip(&self.multiplier_offsets)
            .enumerate()
        {
            let m = c.n_equations();
            let phi = &mut out[*off..off + m];
            c.evaluate(ctx, &s.nodes, self.coords_of(k, s), phi, None);
            self.subtract_servo_targets(k, signals, phi);
        }
    }

    /// [`Self::constraint_values`] of the constraints `of` (none with servo rows), each
    /// into its rows through one part's handle on `out`; returns their largest `|Φ|`
    /// (a NaN passed over, as by the check of all of them).
    pub fn constraint_values_of(
        &self,
        ctx: &EvalContext,
        s: &State,
        of: &[usize],
        out: &mut crate::solve::PartSlice<'_, f64>,
    ) -> f64 {
        let mut worst: f64 = 0.0;
        for &k in of {
            let c = &self.constraints[k];
            let off = self.multiplier_offsets[k];
            let phi = out.get_range(off..off + c.n_equations());
            c.evaluate(ctx, &s.nodes, self.coords_of(k, s), phi, None);
            worst = phi.iter().fold(worst, |m, x| m.max(x.abs()));
        }
        worst
    }

    /// `Φ_i −= s` on the servo rows of constraint `k` (`phi` its enforced equations,
    /// `signals` the values of all signals).
    pub fn subtract_servo_targets(&self, k: usize, signals: &[f64], phi: &mut [f64]) {
        let c = &self.constraints[k];
        for sr in c.servo_rows() {
            if let Some(i) = c.active_rows().iter().position(|&r| r == sr.row) {
                phi[i] -= signals[self.signals.constraint_inputs[k][sr.input]];
            }
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

/// Item `k`'s range in a vector laid out by running `offsets` (one per item, in order)
/// that ends at `total`: `offsets[k]..offsets[k + 1]`. The sizes are fixed per system, so
/// the hot accessors read them here rather than through a virtual `n_states()` /
/// `n_held()` / `n_coordinates()` call per element and Newton iteration.
#[inline(always)]
fn span(offsets: &[usize], k: usize, total: usize) -> std::ops::Range<usize> {
    offsets[k]..offsets.get(k + 1).copied().unwrap_or(total)
}
