//! A signal that is a given function of time, `s = f(t)` (the `[[signals]]` of a model):
//! it touches no unknown, so its derivatives are zero.

use crate::core::{Element, ElementInput, EvalContext, LocalTerms, Need, SignalTerms};
use crate::math::TimeFunction;

#[derive(Clone, Debug)]
pub struct TimeSignal {
    name: [String; 1],
    function: TimeFunction,
}

impl TimeSignal {
    pub fn new(name: &str, function: TimeFunction) -> Self {
        Self {
            name: [name.to_string()],
            function,
        }
    }
}

impl Element for TimeSignal {
    fn breakpoints(&self, out: &mut Vec<f64>) {
        out.extend(self.function.breakpoints());
    }

    fn name(&self) -> &str {
        &self.name[0]
    }
    fn nodes(&self) -> &[usize] {
        &[]
    }
    fn signal_outputs(&self) -> &[String] {
        &self.name
    }
    fn signals(&self, ctx: &EvalContext, _x: &ElementInput, out: &mut SignalTerms) {
        out.values[0] = self.function.eval(ctx.time);
    }
    fn signal_time_derivatives(&self, ctx: &EvalContext, out: &mut [[f64; 2]]) {
        let d = self.function.derivatives(ctx.time);
        out[0] = [d[1], d[2]];
    }
    fn evaluate(&self, _ctx: &EvalContext, _x: &ElementInput, _need: Need, _out: &mut LocalTerms) {}
    /// No nodes, no energy: nothing to discretize.
    fn discrete_form(&self) -> Result<(), String> {
        Ok(())
    }
}
