//! A permanent-magnet DC motor between two nodes (stator on A, rotor on B) about an axis
//! fixed in A's frame, driven by a voltage signal; its armature current i is the state.
//!
//! With the relative angular velocity about the axis `ω_r = a·(ω_B − ω_A)` (a = R_A e,
//! global; ω = R Ω), armature resistance R, inductance L and motor constant k (torque
//! constant = back-EMF constant in SI units):
//!
//! `r_i = L i̇ + R i + k ω_r − V = 0`,  torque `τ = k i` on B about a (and −τ on A).
//!
//! Node rows: moment rows `−R_Bᵀ a τ` for B and `+e τ` for A. The state row is in volts;
//! the assembler scales it by `1/(∂ż/∂Δz)` in dynamics (block `L + O(h)`).
//! Energies: magnetic `½ L i²` (counted as potential), input `V i` (external), Joule
//! losses `R i²` (dissipated), so the balance closes with the mechanical energy.

use super::{Element, EvalContext, LocalTerms, Need};
use crate::core::ElementInput;
use crate::math::skew;
use nalgebra::{Matrix3, Vector3};

#[derive(Clone, Debug)]
pub struct DcMotor {
    name: String,
    /// Stator node (`None`: the ground) and rotor node.
    stator: Option<usize>,
    nodes: Vec<usize>,
    /// Axis: in the stator's node frame (or global for the ground).
    axis: Vector3<f64>,
    resistance: f64,
    inductance: f64,
    constant: f64,
    initial_current: f64,
    inputs: [String; 1],
}

impl DcMotor {
    /// `axis`: unit vector in the stator node's frame (global if `stator` is `None`).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        name: impl Into<String>,
        stator: Option<usize>,
        rotor: usize,
        axis: Vector3<f64>,
        resistance: f64,
        inductance: f64,
        constant: f64,
        initial_current: f64,
        voltage: impl Into<String>,
    ) -> Self {
        let nodes = match stator {
            Some(a) => vec![a, rotor],
            None => vec![rotor],
        };
        Self {
            name: name.into(),
            stator,
            nodes,
            axis,
            resistance,
            inductance,
            constant,
            initial_current,
            inputs: [voltage.into()],
        }
    }

    /// (global axis a, R_A, ω_A global, local row of B).
    fn frames(&self, x: &ElementInput) -> (Vector3<f64>, Matrix3<f64>, Vector3<f64>, usize) {
        match self.stator {
            None => (self.axis, Matrix3::identity(), Vector3::zeros(), 0),
            Some(a) => {
                let n = &x.nodes[a];
                (n.r() * self.axis, *n.r(), n.omega_global(), 6)
            }
        }
    }

    fn relative_speed(&self, x: &ElementInput) -> f64 {
        let (a, _, wa, b) = self.frames(x);
        let nb = &x.nodes[self.nodes[b / 6]];
        a.dot(&(nb.omega_global() - wa))
    }
}

impl Element for DcMotor {
    fn name(&self) -> &str {
        &self.name
    }
    fn nodes(&self) -> &[usize] {
        &self.nodes
    }
    fn n_states(&self) -> usize {
        1
    }
    fn state_names(&self) -> Vec<String> {
        vec!["current".into()]
    }
    fn initial_states(&self, out: &mut [f64]) {
        out[0] = self.initial_current;
    }
    fn signal_inputs(&self) -> &[String] {
        &self.inputs
    }

    fn evaluate(&self, _ctx: &EvalContext, x: &ElementInput, need: Need, out: &mut LocalTerms) {
        let (a, ra, _, b) = self.frames(x);
        let nb = &x.nodes[self.nodes[b / 6]];
        let rb = *nb.r();
        let z = x.states[0];
        let zr = 6 * self.nodes.len();
        let tau = self.constant * z.z;
        let ab = rb.transpose() * a; // axis in B's frame
        let wr = self.relative_speed(x);
        for i in 0..3 {
            out.r[b + 3 + i] -= ab[i] * tau;
            if self.stator.is_some() {
                out.r[3 + i] += self.axis[i] * tau;
            }
        }
        out.r[zr] +=
            self.inductance * z.zd + self.resistance * z.z + self.constant * wr - x.signals[0];
        if need == Need::Residual {
            return;
        }
        let k = self.constant;
        // Node rows: ∂/∂i; ∂(R_Bᵀ a)/∂θ_B = skew(R_Bᵀ a); ∂/∂θ_A = −R_Bᵀ R_A ẽ.
        let geo_b = skew(&ab) * (-tau);
        let geo_ba = rb.transpose() * ra * skew(&self.axis) * tau;
        for i in 0..3 {
            out.k[(b + 3 + i, zr)] -= ab[i] * k;
            if self.stator.is_some() {
                out.k[(3 + i, zr)] += self.axis[i] * k;
            }
            for j in 0..3 {
                out.k[(b + 3 + i, b + 3 + j)] += geo_b[(i, j)];
                if self.stator.is_some() {
                    out.k[(b + 3 + i, 3 + j)] += geo_ba[(i, j)];
                }
            }
        }
        // State row: ω_r = aᵀ R_B Ω_B − eᵀ Ω_A.
        out.k[(zr, zr)] += self.resistance;
        out.c[(zr, zr)] += self.inductance;
        out.ds[(zr, 0)] -= 1.0;
        let d_wb = -(a.transpose() * rb * skew(&nb.w)); // ∂/∂θ_B
        for j in 0..3 {
            out.c[(zr, b + 3 + j)] += k * ab[j];
            out.k[(zr, b + 3 + j)] += k * d_wb[j];
        }
        if self.stator.is_some() {
            let wb = nb.omega_global();
            let d_a = -(wb.transpose() * ra * skew(&self.axis)); // ∂/∂θ_A
            for j in 0..3 {
                out.c[(zr, 3 + j)] -= k * self.axis[j];
                out.k[(zr, 3 + j)] += k * d_a[j];
            }
        }
    }

    fn potential_energy(&self, _ctx: &EvalContext, x: &ElementInput) -> f64 {
        0.5 * self.inductance * x.states[0].z.powi(2)
    }

    fn external_power(&self, _ctx: &EvalContext, x: &ElementInput) -> f64 {
        x.signals[0] * x.states[0].z
    }

    fn dissipated_power(&self, x: &ElementInput) -> f64 {
        self.resistance * x.states[0].z.powi(2)
    }

    fn output_names(&self) -> Vec<(String, &'static str)> {
        vec![
            ("torque".into(), "N m"),
            ("speed".into(), "rad/s"),
            ("voltage".into(), "V"),
        ]
    }

    fn outputs(&self, _ctx: &EvalContext, x: &ElementInput, out: &mut [f64]) {
        out[0] = self.constant * x.states[0].z;
        out[1] = self.relative_speed(x);
        out[2] = x.signals[0];
    }
}
