//! A sensor with a first-order low-pass filter: it measures a node quantity u (or reads a
//! signal) and produces the signal s = z, its state, with
//!
//! `r_z = τ ż + z − g u = 0`
//!
//! (time constant τ > 0, gain g): the transfer function g/(τ s + 1). The output is the
//! state itself, so the sensor has no feedthrough and breaks any loop of signals through
//! it. It applies no force: its node rows are zero. The state row is in units of u; the
//! assembler scales it by s_z = 1/(∂ż/∂Δz) in dynamics (block `τ + O(h)`).
//!
//! Without a filter (τ = 0) the sensor has no state: s = g u, with feedthrough (its
//! output's derivatives are those of u).
//!
//! **Sample-and-hold** (zero-order hold, noise-free): with a sample period T the output
//! is the filter's output (or g u) sampled at `t_k = k T` and held until `t_(k+1)`,
//! `s(t) = y(t_k)` for `t_k ≤ t < t_(k+1)`. The held value is a discrete state of the
//! system ([`Element::n_held`]) set after the step that lands on each `t_k`; within a step
//! it is a constant (no derivatives). Where nothing is held (statics) the output is the
//! current value, as without sampling.
//!
//! Measured quantities, global components: position x, velocity v, acceleration v̇,
//! angular velocity ω = R Ω (∂ω/∂Ω = R, ∂ω/∂θ = −R Ω̃ for the material increment).

use super::{Element, EvalContext, LocalTerms, Need};
use crate::core::{ElementInput, SignalTerms};
use crate::math::skew;

/// A node quantity, with its global component (0, 1, 2).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NodeQuantity {
    Position(usize),
    Velocity(usize),
    Acceleration(usize),
    AngularVelocity(usize),
}

/// What the sensor measures.
#[derive(Clone, Debug, PartialEq)]
pub enum SensorInput {
    Node { node: usize, quantity: NodeQuantity },
    Signal(String),
}

#[derive(Clone, Debug)]
pub struct LowPassSensor {
    name: String,
    input: SensorInput,
    nodes: Vec<usize>,
    inputs: Vec<String>,
    outputs: [String; 1],
    time_constant: f64,
    gain: f64,
    initial: f64,
    /// Sample period T [s] of the zero-order hold, if any.
    sample_period: Option<f64>,
}

impl LowPassSensor {
    /// A sensor producing signal `output`; `time_constant > 0` (or 0: no filter, no
    /// state); the state starts at `initial`.
    pub fn new(
        name: impl Into<String>,
        output: impl Into<String>,
        input: SensorInput,
        time_constant: f64,
        gain: f64,
        initial: f64,
    ) -> Self {
        let (nodes, inputs) = match &input {
            SensorInput::Node { node, .. } => (vec![*node], Vec::new()),
            SensorInput::Signal(s) => (Vec::new(), vec![s.clone()]),
        };
        Self {
            name: name.into(),
            input,
            nodes,
            inputs,
            outputs: [output.into()],
            time_constant,
            gain,
            initial,
            sample_period: None,
        }
    }

    /// The same sensor sampled every `period` T > 0 and held in between (zero-order hold).
    pub fn sampled(mut self, period: f64) -> Self {
        self.sample_period = Some(period);
        self
    }

    /// The output before the hold: the filter state z, or g u without a filter.
    pub fn continuous_output(&self, x: &ElementInput) -> f64 {
        if self.time_constant > 0.0 {
            x.states[0].z
        } else {
            self.gain * self.measure(x)
        }
    }

    /// The measured value u.
    pub fn measure(&self, x: &ElementInput) -> f64 {
        match &self.input {
            SensorInput::Signal(_) => x.signals[0],
            SensorInput::Node { node, quantity } => {
                let n = &x.nodes[*node];
                match *quantity {
                    NodeQuantity::Position(i) => n.x[i],
                    NodeQuantity::Velocity(i) => n.v[i],
                    NodeQuantity::Acceleration(i) => n.a[i],
                    NodeQuantity::AngularVelocity(i) => (n.r() * n.w)[i],
                }
            }
        }
    }
}

impl Element for LowPassSensor {
    fn name(&self) -> &str {
        &self.name
    }
    fn nodes(&self) -> &[usize] {
        &self.nodes
    }
    fn n_states(&self) -> usize {
        usize::from(self.time_constant > 0.0)
    }
    fn state_names(&self) -> Vec<String> {
        if self.time_constant > 0.0 {
            vec!["output".into()]
        } else {
            Vec::new()
        }
    }
    fn initial_states(&self, out: &mut [f64]) {
        if let Some(z) = out.first_mut() {
            *z = self.initial;
        }
    }
    fn signal_inputs(&self) -> &[String] {
        &self.inputs
    }
    fn signal_outputs(&self) -> &[String] {
        &self.outputs
    }
    fn feedthrough(&self) -> bool {
        // A hold passes its input through where nothing is held (statics).
        self.time_constant == 0.0
    }
    fn n_held(&self) -> usize {
        usize::from(self.sample_period.is_some())
    }
    fn sample_period(&self) -> Option<f64> {
        self.sample_period
    }
    fn sample(&self, _ctx: &EvalContext, x: &ElementInput, out: &mut [f64]) {
        out[0] = self.continuous_output(x);
    }

    fn signals(&self, _ctx: &EvalContext, x: &ElementInput, out: &mut SignalTerms) {
        if let (Some(_), Some(&h)) = (self.sample_period, x.held.first()) {
            // Held: a constant within the step.
            out.values[0] = h;
            return;
        }
        if self.time_constant == 0.0 {
            // s = g u: the measurement's derivatives, scaled.
            let g = self.gain;
            out.values[0] = g * self.measure(x);
            match &self.input {
                SensorInput::Signal(_) => out.ds[(0, 0)] = g,
                SensorInput::Node { node, quantity } => match *quantity {
                    NodeQuantity::Position(i) => out.k[(0, i)] = g,
                    NodeQuantity::Velocity(i) => out.c[(0, i)] = g,
                    NodeQuantity::Acceleration(i) => out.m[(0, i)] = g,
                    NodeQuantity::AngularVelocity(i) => {
                        let n = &x.nodes[*node];
                        let r = n.r();
                        let dk = -(r * skew(&n.w));
                        for j in 0..3 {
                            out.c[(0, 3 + j)] = g * r[(i, j)];
                            out.k[(0, 3 + j)] = g * dk[(i, j)];
                        }
                    }
                },
            }
            return;
        }
        let zc = 6 * self.nodes.len();
        out.values[0] = x.states[0].z;
        out.k[(0, zc)] = 1.0;
    }

    fn evaluate(&self, _ctx: &EvalContext, x: &ElementInput, need: Need, out: &mut LocalTerms) {
        if self.time_constant == 0.0 {
            return;
        }
        let zc = 6 * self.nodes.len();
        let z = x.states[0];
        let (tau, g) = (self.time_constant, self.gain);
        out.r[zc] += tau * z.zd + z.z - g * self.measure(x);
        if need == Need::Residual {
            return;
        }
        out.k[(zc, zc)] += 1.0;
        out.c[(zc, zc)] += tau;
        match &self.input {
            SensorInput::Signal(_) => out.ds[(zc, 0)] -= g,
            SensorInput::Node { node, quantity } => match *quantity {
                NodeQuantity::Position(i) => out.k[(zc, i)] -= g,
                NodeQuantity::Velocity(i) => out.c[(zc, i)] -= g,
                NodeQuantity::Acceleration(i) => out.m[(zc, i)] -= g,
                NodeQuantity::AngularVelocity(i) => {
                    let n = &x.nodes[*node];
                    let r = n.r();
                    let dk = -(r * skew(&n.w));
                    for j in 0..3 {
                        out.c[(zc, 3 + j)] -= g * r[(i, j)];
                        out.k[(zc, 3 + j)] -= g * dk[(i, j)];
                    }
                }
            },
        }
    }
}
