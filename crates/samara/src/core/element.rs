//! The element contract: an element touches a few nodes and, given their state, returns
//! its residual
//!
//! `r(q, v, v̇, t) = M(q) v̇ + g(q, v, t) − f(q, v, t)`
//!
//! (6 rows per node: force in global components, then moment about the node in node-frame
//! components — the virtual work of a material rotation increment) and its tangent blocks
//! `K = ∂r/∂q`, `C = ∂r/∂v`, `M = ∂r/∂v̇`, where perturbations of a node are
//! `(δx, δθ)` with `x ← x + δx`, `R ← R exp(δθ̃)` and velocities `(v, Ω)` (global linear,
//! material angular). Elements never know which analysis calls them.
//!
//! **Element states.** An element may own first-order states z (ARCHITECTURE.md, "Element
//! states"). Its local unknowns are then its nodes (6 each) followed by its states, and its
//! residual gains one row per state, `r_z(q, v, z, ż, t) = 0`; the same `K`, `C`, `M`
//! blocks carry `∂r/∂z` (in K) and `∂r/∂ż` (in C) for the state columns, so every
//! analysis treats node and state unknowns alike.
//!
//! **Signals.** An element may read named scalar signals (in [`ElementInput::signals`])
//! and returns `∂r/∂s` in [`LocalTerms::ds`]; it may produce signals from its own
//! unknowns ([`Element::signals`]) with their derivatives. The system orders producers so
//! every signal is known before it is read and applies the chain rule.

use super::{DiscreteStep, ElementState, NodeState};
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

/// Model-wide inputs of an element evaluation.
#[derive(Clone, Copy, Debug)]
pub struct EvalContext {
    /// Time (for statics, the time at which loads are evaluated).
    pub time: f64,
    /// Gravitational acceleration, global.
    pub gravity: Vector3<f64>,
    /// Multiplies all applied loads and gravity (static load continuation); 1 in dynamics.
    pub load_factor: f64,
}

/// Which outputs an evaluation must fill.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Need {
    Residual,
    ResidualAndTangents,
}

/// What an element sees of the system's state.
#[derive(Clone, Copy, Debug)]
pub struct ElementInput<'a> {
    /// Every node of the system (the element indexes its own, [`Element::nodes`]).
    pub nodes: &'a [NodeState],
    /// The element's own states, in [`Element::state_names`] order.
    pub states: &'a [ElementState],
    /// Values of the signals the element reads, in [`Element::signal_inputs`] order.
    pub signals: &'a [f64],
    /// The element's sample-and-hold values ([`Element::n_held`]), or empty when nothing
    /// samples (statics): a hold then passes its input through.
    pub held: &'a [f64],
}

impl<'a> ElementInput<'a> {
    /// Input of an element with nodes only.
    pub fn nodes(nodes: &'a [NodeState]) -> Self {
        Self {
            nodes,
            states: &[],
            signals: &[],
            held: &[],
        }
    }
}

/// Local residual and tangents of one element: `n = 6·nodes + states` local unknowns
/// (nodes first, then the element's states), `r` and `K = ∂r/∂q`, `C = ∂r/∂v`, `M = ∂r/∂v̇`
/// (for state columns: `∂r/∂z` in K, `∂r/∂ż` in C), and `ds = ∂r/∂s` (n × inputs).
#[derive(Clone, Debug)]
pub struct LocalTerms {
    pub r: DVector<f64>,
    pub k: DMatrix<f64>,
    pub c: DMatrix<f64>,
    pub m: DMatrix<f64>,
    pub ds: DMatrix<f64>,
    /// Where the element's states start after its node unknowns: its state rows and
    /// columns are `6·nodes + state_shift + j`. 0 (right after the nodes) except while
    /// the assembler evaluates a batch of accumulating elements with states into one
    /// block ([`Element::accumulates`]), each element's states after the previous ones'.
    pub state_shift: usize,
}

impl LocalTerms {
    /// Terms of an element with `n_nodes` nodes and nothing else.
    pub fn new(n_nodes: usize) -> Self {
        Self::with_sizes(6 * n_nodes, 0)
    }

    /// Terms of `n` local unknowns reading `inputs` signals.
    pub fn with_sizes(n: usize, inputs: usize) -> Self {
        Self {
            r: DVector::zeros(n),
            k: DMatrix::zeros(n, n),
            c: DMatrix::zeros(n, n),
            m: DMatrix::zeros(n, n),
            ds: DMatrix::zeros(n, inputs),
            state_shift: 0,
        }
    }

    /// Terms sized for `e`.
    pub fn for_element(e: &dyn Element) -> Self {
        Self::with_sizes(6 * e.nodes().len() + e.n_states(), e.signal_inputs().len())
    }

    pub fn clear(&mut self, need: Need) {
        // Through the slices: a plain memset (nalgebra's `fill` iterates element-wise).
        self.r.as_mut_slice().fill(0.0);
        if need == Need::ResidualAndTangents {
            self.k.as_mut_slice().fill(0.0);
            self.c.as_mut_slice().fill(0.0);
            self.m.as_mut_slice().fill(0.0);
            self.ds.as_mut_slice().fill(0.0);
        }
    }

    /// `r[6a + off .. +3] += v`.
    #[inline]
    pub fn add_r(&mut self, row: usize, v: &Vector3<f64>) {
        for i in 0..3 {
            self.r[row + i] += v[i];
        }
    }
}

/// Adds a 3×3 block into a local matrix at (row, col).
#[inline]
pub fn add_block(m: &mut DMatrix<f64>, row: usize, col: usize, b: &Matrix3<f64>) {
    // One bounds check for the block, then unchecked fixed-size access.
    let mut v = m.fixed_view_mut::<3, 3>(row, col);
    v += b;
}

/// Values and derivatives of the signals an element produces: per output `o`, the value
/// and its derivatives with respect to the element's local unknowns (`k`: value, `c`:
/// rate, `m`: acceleration channel, as in [`LocalTerms`]) and to its input signals (`ds`).
#[derive(Clone, Debug)]
pub struct SignalTerms {
    pub values: Vec<f64>,
    pub k: DMatrix<f64>,
    pub c: DMatrix<f64>,
    pub m: DMatrix<f64>,
    pub ds: DMatrix<f64>,
}

impl SignalTerms {
    /// Terms sized for `e`.
    pub fn for_element(e: &dyn Element) -> Self {
        let (o, n, i) = (
            e.signal_outputs().len(),
            6 * e.nodes().len() + e.n_states(),
            e.signal_inputs().len(),
        );
        Self {
            values: vec![0.0; o],
            k: DMatrix::zeros(o, n),
            c: DMatrix::zeros(o, n),
            m: DMatrix::zeros(o, n),
            ds: DMatrix::zeros(o, i),
        }
    }

    pub fn clear(&mut self) {
        self.values.fill(0.0);
        for m in [&mut self.k, &mut self.c, &mut self.m, &mut self.ds] {
            m.as_mut_slice().fill(0.0);
        }
    }
}

/// A force element.
pub trait Element: Send + Sync {
    /// Name given in the model (for messages).
    fn name(&self) -> &str;
    /// Indices of the nodes the element touches, in the order of its local rows.
    fn nodes(&self) -> &[usize];
    /// Number of first-order states the element owns.
    fn n_states(&self) -> usize {
        0
    }
    /// Names of the states (`"pressure"`; the system writes `<element>.pressure`).
    fn state_names(&self) -> Vec<String> {
        Vec::new()
    }
    /// Initial values of the states (zero unless overridden).
    fn initial_states(&self, out: &mut [f64]) {
        out.fill(0.0);
    }
    /// Names of the signals the element reads.
    fn signal_inputs(&self) -> &[String] {
        &[]
    }
    /// Names of the signals the element produces.
    fn signal_outputs(&self) -> &[String] {
        &[]
    }
    /// Whether an output depends directly on the inputs' values (not only through the
    /// element's states). A loop of signals must pass through an element without
    /// feedthrough.
    fn feedthrough(&self) -> bool {
        true
    }
    /// Values of the produced signals and their derivatives; `out` is cleared by the caller.
    fn signals(&self, _ctx: &EvalContext, _x: &ElementInput, _out: &mut SignalTerms) {}
    /// Explicit time derivatives `[∂s/∂t, ∂²s/∂t²]` of the produced signals at fixed
    /// unknowns and inputs (a time function's f′, f″); zero by default. A servo's target
    /// rate and acceleration in the consistent initial conditions use them.
    fn signal_time_derivatives(&self, _ctx: &EvalContext, _out: &mut [[f64; 2]]) {}
    /// Residual and (if asked) tangents; `out` is cleared by the caller.
    fn evaluate(&self, ctx: &EvalContext, x: &ElementInput, need: Need, out: &mut LocalTerms);
    /// Asks for the element's data to be brought into the caches (a hint, called a few
    /// elements ahead of [`Self::evaluate`] by the assembly). By default the element's own
    /// bytes; an element whose data sit behind a pointer asks for those.
    fn prefetch(&self) {
        crate::math::prefetch::prefetch(self);
    }
    /// Whether [`Element::evaluate`] only adds into `out` (never overwrites or reads it)
    /// and writes its state rows and columns at [`LocalTerms::state_shift`] past its node
    /// unknowns: then consecutive such elements on the same nodes without input signals
    /// are evaluated into one local block (the nodes, then each element's states in turn)
    /// and assembled once (the stations of a lifting line on one beam element).
    fn accumulates(&self) -> bool {
        false
    }
    /// Whether the element only applies loads: its kinetic and potential energy and its
    /// dissipated power (and their discrete and evaluated forms) are zero at every state,
    /// so the energy sums skip it (an aerodynamic station). Only its power remains.
    fn loads_only(&self) -> bool {
        false
    }
    /// Kinetic energy.
    fn kinetic_energy(&self, _x: &ElementInput) -> f64 {
        0.0
    }
    /// Potential energy of conservative forces (gravity, springs).
    fn potential_energy(&self, _ctx: &EvalContext, _x: &ElementInput) -> f64 {
        0.0
    }
    /// Power of the applied (non-conservative, external) loads.
    fn external_power(&self, _ctx: &EvalContext, _x: &ElementInput) -> f64 {
        0.0
    }
    /// [`Self::external_power`] for the energy balance after a converged step: an element
    /// whose loads are costly may return the power at its last residual evaluation (the
    /// last Newton iterate, one correction from `x`) instead of evaluating them again;
    /// by default the power at `x`.
    fn evaluated_power(&self, ctx: &EvalContext, x: &ElementInput) -> f64 {
        self.external_power(ctx, x)
    }
    /// Power dissipated by dampers (≥ 0).
    fn dissipated_power(&self, _x: &ElementInput) -> f64 {
        0.0
    }
    /// [`Self::dissipated_power`] for the energy balance after a converged step, as
    /// [`Self::evaluated_power`]: the power at the last residual evaluation where the
    /// element keeps it; by default the power at `x`.
    fn evaluated_dissipated_power(&self, x: &ElementInput) -> f64 {
        self.dissipated_power(x)
    }
    /// Names and units of the element's output quantities (`("tension", "N")`; written
    /// as `element_output` named `<element>.tension`). Outputs are for the results only:
    /// no equation depends on them.
    fn output_names(&self) -> Vec<(String, &'static str)> {
        Vec::new()
    }
    /// Values of the outputs, in the order of [`Element::output_names`].
    fn outputs(&self, _ctx: &EvalContext, _x: &ElementInput, _out: &mut [f64]) {}
    /// Why the converged state `x` is outside what the element is defined for (a body
    /// that left a height field's table), or None; an analysis stops with this message at
    /// the time of the first such state.
    fn range_violation(&self, _x: &ElementInput) -> Option<String> {
        None
    }
    /// Times where the element's loads jump or kink (its time functions' breakpoints).
    fn breakpoints(&self, _out: &mut Vec<f64>) {}
    /// Number of event functions: scalars g(q, v) whose zeros are kinks of the element's
    /// law in the state (a contact closing or opening); adaptive steps land on them.
    fn n_events(&self) -> usize {
        0
    }
    /// Values and rates `(g, ġ)` of the event functions (ġ = NaN where the rate is not
    /// known); the law is smooth where no g changes sign.
    fn events(&self, _x: &ElementInput, _out: &mut [(f64, f64)]) {}
    /// Forgets what earlier evaluations left in the element (a solver's warm start), so
    /// that every analysis gives the same bits however often and wherever the system ran
    /// before; called as each analysis starts.
    fn begin_analysis(&self) {}
    /// Why the element's loads could not be evaluated (a wind sampled outside its box),
    /// and a hint: the analysis reports it when it fails.
    fn runtime_error(&self) -> Option<(String, String)> {
        None
    }
    /// Number of sample-and-hold values (discrete states) the element keeps: constant
    /// between its sample instants `t_k = k T`, set by [`Element::sample`] at each.
    fn n_held(&self) -> usize {
        0
    }
    /// Sample period T [s] of the held values (`Some` when [`Element::n_held`] > 0).
    fn sample_period(&self) -> Option<f64> {
        None
    }
    /// The values to hold from now on, taken from the current state (called at the
    /// start of a dynamic analysis and after the step that lands on each sample instant).
    fn sample(&self, _ctx: &EvalContext, _x: &ElementInput, _out: &mut [f64]) {}
    /// Whether the element has a discrete form for the energy-consistent integrators
    /// ([`Element::discrete_residual`]); `Err` says why not (its kind, or the option that
    /// has none).
    fn discrete_form(&self) -> Result<(), String> {
        Err("this element kind has no energy-consistent discrete form yet".into())
    }
    /// Discrete residual over a step ([`DiscreteStep`]): 6 rows per node, with
    /// `Σ Δ·r̄ = ΔT + ΔV + D − W` exactly. Called only when [`Element::discrete_form`] is Ok.
    fn discrete_residual(&self, _step: &DiscreteStep, _out: &mut [f64]) {}
    /// Length of the element's dissipation memory for the energy-decaying scheme: its
    /// strain increments over a step (1 for a spring's length, 6 per elastic point of a
    /// beam); 0 for elements without a potential to dissipate through.
    fn discrete_memory_len(&self) -> usize {
        0
    }
    /// The strain increments e of the step (what the next step reads as
    /// [`DiscreteStep::memory`]), `discrete_memory_len` values.
    fn discrete_memory(&self, _step: &DiscreteStep, _out: &mut [f64]) {}
    /// `½ eᵀ C e` of a memory `e` (the element's part of the decaying scheme's discrete
    /// energy beyond E).
    fn discrete_memory_energy(&self, _memory: &[f64]) -> f64 {
        0.0
    }
    /// The kinetic energy whose balance [`Element::discrete_residual`] states (the
    /// element's own unless its discrete form uses another inertia, as the beam's lumped
    /// one).
    fn discrete_kinetic_energy(&self, x: &ElementInput) -> f64 {
        self.kinetic_energy(x)
    }
    /// The potential energy whose balance [`Element::discrete_residual`] states.
    fn discrete_potential_energy(&self, ctx: &EvalContext, x: &ElementInput) -> f64 {
        self.potential_energy(ctx, x)
    }
}
