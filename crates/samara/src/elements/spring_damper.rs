//! Point-to-point spring-damper between points on two nodes (or a node and the ground):
//! tension `T = k (l − l₀) + c l̇` along the line ([`super::line_of_action`]).

use super::line_of_action::LineOfAction;
use super::{Element, EvalContext, LocalTerms, Need};
use crate::core::{DiscreteStep, ElementInput};
use nalgebra::Vector3;

#[derive(Clone, Debug)]
pub struct SpringDamper {
    name: String,
    line: LineOfAction,
    stiffness: f64,
    damping: f64,
    rest_length: f64,
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
        }
    }
}

impl Element for SpringDamper {
    fn name(&self) -> &str {
        &self.name
    }

    fn nodes(&self) -> &[usize] {
        self.line.nodes()
    }

    fn evaluate(&self, _ctx: &EvalContext, x: &ElementInput, need: Need, out: &mut LocalTerms) {
        let st = self.line.state(x.nodes);
        let (k, c) = (self.stiffness, self.damping);
        let tension = k * (st.length - self.rest_length) + c * st.rate;
        let tangents = (need == Need::ResidualAndTangents).then_some((k, c));
        self.line.add_tension(&st, tension, tangents, out);
    }

    fn discrete_form(&self) -> Result<(), String> {
        Ok(())
    }

    /// Discrete gradient of `V = k(l − l₀)²/2` along the line: the mean tension
    /// `T̄ = k((l₀ + l₁)/2 − l_rest) + ξ k (l₁ − l₀) + c (l₁ − l₀)/h` along
    /// `ē = (d₀ + d₁)/(l₀ + l₁)`, for which `ē·Δd = Δl` and
    /// `T̄ Δl = ΔV + ξ k Δl² + c Δl²/h` exactly ([`LineOfAction::add_discrete_tension`];
    /// ξ = [`DiscreteStep::decay`]).
    fn discrete_residual(&self, step: &DiscreteStep, out: &mut [f64]) {
        let (l0, l1) = (self.line.length(step.start), self.line.length(step.end));
        let tension = self.stiffness * (0.5 * (l0 + l1) - self.rest_length)
            + step.decay * self.stiffness * (l1 - l0)
            + self.damping * (l1 - l0) / step.h;
        self.line.add_discrete_tension(step, tension, out);
    }

    fn potential_energy(&self, _ctx: &EvalContext, x: &ElementInput) -> f64 {
        let st = self.line.state(x.nodes);
        0.5 * self.stiffness * (st.length - self.rest_length).powi(2)
    }

    fn dissipated_power(&self, x: &ElementInput) -> f64 {
        let st = self.line.state(x.nodes);
        self.damping * st.rate * st.rate
    }

    fn output_names(&self) -> Vec<(String, &'static str)> {
        vec![("tension".into(), "N"), ("length".into(), "m")]
    }

    fn outputs(&self, _ctx: &EvalContext, x: &ElementInput, out: &mut [f64]) {
        let st = self.line.state(x.nodes);
        out[0] = self.stiffness * (st.length - self.rest_length) + self.damping * st.rate;
        out[1] = st.length;
    }
}
