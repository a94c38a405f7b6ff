//! Linear viscoelastic point-to-point element (Maxwell): a spring k in series with a
//! damper c between points on two nodes, the damper's stretch z as the element's state.
//!
//! With the line length l (rest length l₀, [`super::line_of_action`]) the spring carries
//! the tension `T = k (l − l₀ − z)`; the junction of spring and damper has no mass, so
//! `c ż = T`. The element's rows are the tension's forces on the nodes and the state row
//!
//! `r_z = c ż − k (l − l₀ − z) = 0`,
//!
//! (force units; the assembler scales it by s_z = 1/(∂ż/∂Δz) in dynamics, so its block
//! of the iteration matrix is `c + O(h)`). With the stretch held at e the tension relaxes
//! as `k e exp(−t k/c)` and the damper dissipates the spring's energy `½ k e²`.

use super::line_of_action::LineOfAction;
use super::{Element, EvalContext, LocalTerms, Need};
use crate::core::ElementInput;
use nalgebra::Vector3;

#[derive(Clone, Debug)]
pub struct Maxwell {
    name: String,
    line: LineOfAction,
    stiffness: f64,
    damping: f64,
    rest_length: f64,
}

impl Maxwell {
    /// `a`, `b`: `Some((node, offset in node frame))`, or `None` with `ground_points[i]`
    /// global. `damping > 0`.
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

    /// The spring's tension at line length `l` and damper stretch `z`.
    pub fn tension(&self, l: f64, z: f64) -> f64 {
        self.stiffness * (l - self.rest_length - z)
    }
}

impl Element for Maxwell {
    fn name(&self) -> &str {
        &self.name
    }

    fn nodes(&self) -> &[usize] {
        self.line.nodes()
    }

    fn n_states(&self) -> usize {
        1
    }

    fn state_names(&self) -> Vec<String> {
        vec!["damper_stretch".into()]
    }

    fn evaluate(&self, _ctx: &EvalContext, x: &ElementInput, need: Need, out: &mut LocalTerms) {
        let st = self.line.state(x.nodes);
        let z = x.states[0];
        let (k, c) = (self.stiffness, self.damping);
        let t = self.tension(st.length, z.z);
        let zr = 6 * self.line.nodes().len();
        out.r[zr] += c * z.zd - t;
        let tangents = need == Need::ResidualAndTangents;
        self.line
            .add_tension(&st, t, tangents.then_some((k, 0.0)), out);
        if !tangents {
            return;
        }
        // ∂r_nodes/∂z = −k g and ∂r_z/∂q = −k gᵀ, with g = ∂l/∂q.
        self.line.add_length_gradient(&st, -k, |i, v| {
            out.k[(i, zr)] += v;
            out.k[(zr, i)] += v;
        });
        out.k[(zr, zr)] += k;
        out.c[(zr, zr)] += c;
    }

    fn potential_energy(&self, _ctx: &EvalContext, x: &ElementInput) -> f64 {
        let st = self.line.state(x.nodes);
        let t = self.tension(st.length, x.states[0].z);
        0.5 * t * t / self.stiffness
    }

    fn dissipated_power(&self, x: &ElementInput) -> f64 {
        let zd = x.states[0].zd;
        self.damping * zd * zd
    }

    fn output_names(&self) -> Vec<(String, &'static str)> {
        vec![("tension".into(), "N"), ("length".into(), "m")]
    }

    fn outputs(&self, _ctx: &EvalContext, x: &ElementInput, out: &mut [f64]) {
        let st = self.line.state(x.nodes);
        out[0] = self.tension(st.length, x.states[0].z);
        out[1] = st.length;
    }
}
