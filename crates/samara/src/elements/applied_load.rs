//! Applied force and moment on a node, scaled by a time function and, optionally, by a
//! signal s (a controller's output, a sensor): the load is `f(t) s (F, M)`, its derivative
//! with respect to the signal the load at s = 1.
//!
//! A dead load has fixed global components; a follower load has node-frame components.
//! The force acts at a point `p = x + R s` fixed to the node. Residual (`r = −f`):
//!
//! ```text
//! dead:      r_x = −F,      r_θ = −s̃ Rᵀ F − Rᵀ M
//! follower:  r_x = −R F,    r_θ = −s̃ F − M
//! ```

use super::{Element, EvalContext, LocalTerms, Need, add_block};
use crate::core::{DiscreteStep, ElementInput, NodeState};
use crate::math::TimeFunction;
use crate::math::skew;
use nalgebra::Vector3;
use schemars::JsonSchema;
use serde::Deserialize;

/// Frame in which an applied load's components are given.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum LoadFrame {
    /// Fixed global components (a dead load).
    #[default]
    Global,
    /// Components in the node frame, rotating with the node (a follower load).
    Node,
}

#[derive(Clone, Debug)]
pub struct AppliedLoad {
    name: String,
    node: [usize; 1],
    force: Vector3<f64>,
    moment: Vector3<f64>,
    frame: LoadFrame,
    /// Point of application relative to the node, node frame.
    s: Vector3<f64>,
    function: TimeFunction,
    /// The scaling signal, if any.
    inputs: Vec<String>,
}

impl AppliedLoad {
    pub fn new(
        name: impl Into<String>,
        node: usize,
        force: Vector3<f64>,
        moment: Vector3<f64>,
        frame: LoadFrame,
        offset: Vector3<f64>,
        function: TimeFunction,
    ) -> Self {
        Self {
            name: name.into(),
            node: [node],
            force,
            moment,
            frame,
            s: offset,
            function,
            inputs: Vec::new(),
        }
    }

    /// The load scaled by the named signal as well.
    pub fn with_signal(mut self, signal: impl Into<String>) -> Self {
        self.inputs = vec![signal.into()];
        self
    }

    /// The signal factor s (1 without a signal).
    fn signal_factor(&self, x: &ElementInput) -> f64 {
        if self.inputs.is_empty() {
            1.0
        } else {
            x.signals[0]
        }
    }

    /// Force and moment in global components at the current state, moment about the node.
    fn global_load(
        &self,
        ctx: &EvalContext,
        n: &NodeState,
        signal: f64,
    ) -> (Vector3<f64>, Vector3<f64>) {
        let f = self.function.eval(ctx.time) * ctx.load_factor * signal;
        let r = n.r();
        let (fg, mg) = match self.frame {
            LoadFrame::Global => (self.force * f, self.moment * f),
            LoadFrame::Node => (r * self.force * f, r * self.moment * f),
        };
        (fg, mg + (r * self.s).cross(&fg))
    }
}

impl Element for AppliedLoad {
    fn breakpoints(&self, out: &mut Vec<f64>) {
        out.extend(self.function.breakpoints());
    }

    fn name(&self) -> &str {
        &self.name
    }

    fn nodes(&self) -> &[usize] {
        &self.node
    }

    fn signal_inputs(&self) -> &[String] {
        &self.inputs
    }

    fn evaluate(&self, ctx: &EvalContext, x: &ElementInput, need: Need, out: &mut LocalTerms) {
        let nodes = x.nodes;
        let n = &nodes[self.node[0]];
        // The residual is linear in the factor: computed at f₀ = f(t) λ, scaled by s; its
        // derivative with respect to s is the residual at s = 1.
        let f0 = self.function.eval(ctx.time) * ctx.load_factor;
        let sig = self.signal_factor(x);
        let r = n.r();
        let st = skew(&self.s);
        let (rx, rt) = match self.frame {
            LoadFrame::Global => {
                let fg = self.force * f0;
                let mg = self.moment * f0;
                let rtf = r.transpose() * fg;
                let rtm = r.transpose() * mg;
                if need == Need::ResidualAndTangents {
                    add_block(&mut out.k, 3, 3, &((-(st * skew(&rtf)) - skew(&rtm)) * sig));
                }
                (-fg, -(st * rtf) - rtm)
            }
            LoadFrame::Node => {
                let fl = self.force * f0;
                if need == Need::ResidualAndTangents {
                    add_block(&mut out.k, 0, 3, &(r * skew(&fl) * sig));
                }
                (-(r * fl), -(st * fl) - self.moment * f0)
            }
        };
        out.add_r(0, &(rx * sig));
        out.add_r(3, &(rt * sig));
        if need == Need::ResidualAndTangents && !self.inputs.is_empty() {
            for k in 0..3 {
                out.ds[(k, 0)] += rx[k];
                out.ds[(3 + k, 0)] += rt[k];
            }
        }
    }

    /// A load scaled by a signal has none: the discrete step does not carry signals.
    fn discrete_form(&self) -> Result<(), String> {
        if self.inputs.is_empty() {
            Ok(())
        } else {
            Err("a force scaled by a `signal`".into())
        }
    }

    /// The load at the mid-point time, a follower one with the mean frame
    /// `R̄ = (R₀ + R₁)/2`, acting at the mean arm `(R₀s + R₁s)/2`: its work over the step is
    /// `W = F̄·Δx + m̄·(rotation conjugate to ψ)`, the `W` of the balance
    /// `Σ Δ·r̄ = ΔT + ΔV + D − W` (docs/integrators.md).
    fn discrete_residual(&self, step: &DiscreteStep, out: &mut [f64]) {
        let i = self.node[0];
        let f = self.function.eval(step.ctx.time) * step.ctx.load_factor;
        let (fg, mg) = match self.frame {
            LoadFrame::Global => (self.force * f, self.moment * f),
            LoadFrame::Node => {
                let rm = (step.start[i].r() + step.end[i].r()) * 0.5;
                (rm * self.force * f, rm * self.moment * f)
            }
        };
        let m = mg + step.mean_arm(i, &self.s).cross(&fg);
        let mr = step.conjugate_moment(i, &m);
        for q in 0..3 {
            out[q] -= fg[q];
            out[3 + q] -= mr[q];
        }
    }

    fn external_power(&self, ctx: &EvalContext, x: &ElementInput) -> f64 {
        let nodes = x.nodes;
        let n = &nodes[self.node[0]];
        let (fg, mg) = self.global_load(ctx, n, self.signal_factor(x));
        // Power = F·ẋ_node + M_node·ω, with M about the node including the lever arm.
        fg.dot(&n.v) + mg.dot(&(n.r() * n.w))
    }
}
