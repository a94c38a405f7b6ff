//! Point-to-point spring-damper between points on two nodes (or a node and the ground):
//! tension `T = k f(t) (l − l₀) + c l̇` along the line ([`super::line_of_action`]), with
//! an optional time function f of the stiffness (default 1: a periodically varying
//! stiffness gives the Mathieu equation of parametric excitation).

use super::line_of_action::LineOfAction;
use super::{Element, EvalContext, LocalTerms, Need};
use crate::core::{DiscreteStep, ElementInput};
use crate::math::TimeFunction;
use nalgebra::Vector3;

#[derive(Clone, Debug)]
pub struct SpringDamper {
    name: String,
    line: LineOfAction,
    stiffness: f64,
    damping: f64,
    rest_length: f64,
    /// f(t) multiplying the stiffness.
    stiffness_function: TimeFunction,
}

impl SpringDamper {
    /// `a`, `b`: `Some((node, offset in node frame))`, or `None` with `ground_points[i]`
    /// global.
    pub fn new(
        name: impl Into<String>,
        a: Option<(usize, Vector3<f64>)>,
        b: Option<(usize, Vector3<f64>)>,
        ground_points: [Vector3<f64>; 2],
        stiffness: f64,
        damping: f64,
        rest_length: f64,
    ) -> Self {
        Self {
            name: name.into(),
            line: LineOfAction::new(a, b, ground_points),
            stiffness,
            damping,
            rest_length,
            stiffness_function: TimeFunction::Constant(1.0),
        }
    }

    /// The stiffness varies in time as `k f(t)`.
    pub fn with_stiffness_function(mut self, f: TimeFunction) -> Self {
        self.stiffness_function = f;
        self
    }

    /// k f(t).
    fn stiffness_at(&self, t: f64) -> f64 {
        self.stiffness * self.stiffness_function.eval(t)
    }
}

impl Element for SpringDamper {
    fn name(&self) -> &str {
        &self.name
    }

    fn nodes(&self) -> &[usize] {
        self.line.nodes()
    }

    fn evaluate(&self, ctx: &EvalContext, x: &ElementInput, need: Need, out: &mut LocalTerms) {
        let st = self.line.state(x.nodes);
        let (k, c) = (self.stiffness_at(ctx.time), self.damping);
        let tension = k * (st.length - self.rest_length) + c * st.rate;
        let tangents = (need == Need::ResidualAndTangents).then_some((k, c));
        self.line.add_tension(&st, tension, tangents, out);
    }

    fn discrete_form(&self) -> Result<(), String> {
        match self.stiffness_function {
            TimeFunction::Constant(_) => Ok(()),
            // k f(t) does work of its own: no energy statement to preserve.
            _ => Err("a spring with a time-varying `stiffness_function`".into()),
        }
    }

    /// Discrete gradient of `V = k(l − l₀)²/2` along the line: the mean tension
    /// `T̄ = k((l₀ + l₁)/2 − l_rest) + c_d k (Δl − Δl_prev) + c (l₁ − l₀)/h` along
    /// `ē = (d₀ + d₁)/(l₀ + l₁)`, for which `ē·Δd = Δl` and
    /// `T̄ Δl = ΔV + c_d k Δl (Δl − Δl_prev) + c Δl²/h` exactly
    /// ([`LineOfAction::add_discrete_tension`]; `c_d` = [`DiscreteStep::decay`], `Δl_prev`
    /// = [`DiscreteStep::memory`]).
    fn discrete_residual(&self, step: &DiscreteStep, out: &mut [f64]) {
        let (l0, l1) = (self.line.length(step.start), self.line.length(step.end));
        let k = self.stiffness_at(0.0); // constant (discrete_form)
        let prev = step.memory.first().copied().unwrap_or(0.0);
        let tension = k * (0.5 * (l0 + l1) - self.rest_length)
            + step.decay * k * ((l1 - l0) - prev)
            + self.damping * (l1 - l0) / step.h;
        self.line.add_discrete_tension(step, tension, out);
    }

    fn discrete_memory_len(&self) -> usize {
        1
    }

    fn discrete_memory(&self, step: &DiscreteStep, out: &mut [f64]) {
        out[0] = self.line.length(step.end) - self.line.length(step.start);
    }

    fn discrete_memory_energy(&self, memory: &[f64]) -> f64 {
        0.5 * self.stiffness_at(0.0) * memory[0] * memory[0]
    }

    fn potential_energy(&self, ctx: &EvalContext, x: &ElementInput) -> f64 {
        let st = self.line.state(x.nodes);
        0.5 * self.stiffness_at(ctx.time) * (st.length - self.rest_length).powi(2)
    }

    fn dissipated_power(&self, x: &ElementInput) -> f64 {
        let st = self.line.state(x.nodes);
        self.damping * st.rate * st.rate
    }

    fn output_names(&self) -> Vec<(String, &'static str)> {
        vec![("tension".into(), "N"), ("length".into(), "m")]
    }

    fn outputs(&self, ctx: &EvalContext, x: &ElementInput, out: &mut [f64]) {
        let st = self.line.state(x.nodes);
        out[0] =
            self.stiffness_at(ctx.time) * (st.length - self.rest_length) + self.damping * st.rate;
        out[1] = st.length;
    }

    fn breakpoints(&self, out: &mut Vec<f64>) {
        out.extend(self.stiffness_function.breakpoints());
    }
}
