//! Control blocks (`[[controllers]]`): signal-to-signal elements whose dynamics are
//! element states, so that they are integrated with the structure in the same Newton
//! iteration. Every state row has the form
//!
//! `r_z = ż − f(z, u) = 0`
//!
//! (units of the state per second; block `1·∂ż/∂Δz + O(1)` in dynamics, statics sets
//! ż = 0), and every output is `y = g(z, u)` with its derivatives with respect to the states
//! (K channel) and the inputs (`ds`).
//!
//! Blocks (u the inputs, y the output, z the states):
//!
//! - gain `y = k u`; sum `y = Σ wᵢ uᵢ`; saturation `y = clamp(u, y_min, y_max)`;
//!   lookup table `y = table(u)` (piecewise linear, constant beyond the ends).
//! - rate limiter: `y = z`, `ż = clamp((u − z)/τ, −R, R)` — follows u with time constant τ
//!   while the rate stays below R, at the rate ±R otherwise (a continuous-time rate
//!   limiter: the pure one, ẏ = clamp(u̇, …), has no first-order state form).
//! - state space `ż = A z + B u`, `y = C z + D u`; a transfer function
//!   `N(s)/D(s)` is realized in controllable canonical form (below).
//! - PID with back-calculation anti-windup (Åström & Hägglund, *Advanced PID Control*,
//!   ISA 2006, §3.5; Åström & Murray, *Feedback Systems*, 2nd ed. 2021, §11.3):
//!
//!   ```text
//!   v = K_p e + I + D,      y = clamp(v, y_min, y_max),
//!   İ = K_i e + (y − v)/T_t,
//!   D = K_d (e − x_d)/T_f,  ẋ_d = (e − x_d)/T_f      (filtered derivative K_d s/(T_f s + 1))
//!   D = −K_d ẏ_m                                       (derivative on a measured rate)
//!   ```
//!
//!   The integral state I is the integral term itself (units of the output); while the
//!   output saturates, the tracking term (y − v)/T_t bleeds the integral back so that v
//!   stays within about K_i e T_t of the limit, instead of winding up. Back-calculation
//!   is piecewise linear in the unknowns, so Newton follows it (a clamping/conditional
//!   integrator switches the state equation on and off instead).
//!
//! **Transfer function realization.** With `D(s) = a₀ sⁿ + … + a_n` (a₀ ≠ 0) and
//! `N(s) = b₀ sⁿ + … + b_n` (leading zeros padded, degree ≤ n), normalized by a₀:
//! `ż₁…ż_{n−1} = z₂…z_n`, `ż_n = u − Σ a_{n+1−i} zᵢ`, `y = Σ (b_{n+1−i} − a_{n+1−i} b₀) zᵢ
//! + b₀ u` (Ogata, *Modern Control Engineering*, §2-5).

use super::{Element, EvalContext, LocalTerms, Need};
use crate::core::{ElementInput, SignalTerms};
use nalgebra::DMatrix;

/// PID settings (validated: gains finite, `filter` > 0 when used, `tracking` > 0).
#[derive(Clone, Debug, PartialEq)]
pub struct Pid {
    pub kp: f64,
    pub ki: f64,
    pub kd: f64,
    /// Derivative: `Some(T_f)` filters the error; `None` with `kd ≠ 0` reads a measured rate
    /// as the last input.
    pub filter: Option<f64>,
    /// Output limits (−∞, ∞ when absent).
    pub limits: (f64, f64),
    /// Tracking time T_t of the back-calculation.
    pub tracking: f64,
    pub initial_integral: f64,
}

/// One control block.
#[derive(Clone, Debug, PartialEq)]
pub enum Block {
    Gain(f64),
    Sum(Vec<f64>),
    Saturation(f64, f64),
    /// Increasing breakpoints `(u, y)`, at least two.
    Lookup(Vec<[f64; 2]>),
    RateLimit {
        rate: f64,
        time_constant: f64,
        initial: f64,
    },
    StateSpace {
        a: DMatrix<f64>,
        b: DMatrix<f64>,
        c: DMatrix<f64>,
        d: DMatrix<f64>,
        initial: Vec<f64>,
    },
    /// Inputs: the error e (or reference r and measurement y_m, e = r − y_m), then the
    /// measured rate ẏ_m when the derivative is not filtered.
    Pid {
        pid: Pid,
        reference_and_measurement: bool,
    },
}

impl Block {
    /// State-space block of the transfer function `num(s)/den(s)` (coefficients from the
    /// highest power); `None` if improper or `den` leads with zero.
    pub fn transfer_function(num: &[f64], den: &[f64]) -> Option<Self> {
        let n = den.len().checked_sub(1)?;
        if den[0] == 0.0 || num.len() > den.len() || num.is_empty() {
            return None;
        }
        let a0 = den[0];
        let a: Vec<f64> = den.iter().map(|x| x / a0).collect();
        let mut b = vec![0.0; den.len() - num.len()];
        b.extend(num.iter().map(|x| x / a0));
        let mut am = DMatrix::zeros(n, n);
        let mut bm = DMatrix::zeros(n, 1);
        let mut cm = DMatrix::zeros(1, n);
        for i in 0..n.saturating_sub(1) {
            am[(i, i + 1)] = 1.0;
        }
        if n > 0 {
            bm[(n - 1, 0)] = 1.0;
            for i in 0..n {
                // z_{i+1} multiplies a_{n−i} in the last row.
                am[(n - 1, i)] = -a[n - i];
                cm[(0, i)] = b[n - i] - a[n - i] * b[0];
            }
        }
        Some(Block::StateSpace {
            a: am,
            b: bm,
            c: cm,
            d: DMatrix::from_element(1, 1, b[0]),
            initial: vec![0.0; n],
        })
    }
}

/// Piecewise-linear interpolation, constant beyond the ends: value and slope.
pub fn lookup(table: &[[f64; 2]], u: f64) -> (f64, f64) {
    let n = table.len();
    if u <= table[0][0] {
        return (table[0][1], 0.0);
    }
    if u >= table[n - 1][0] {
        return (table[n - 1][1], 0.0);
    }
    let i = table.partition_point(|p| p[0] <= u).clamp(1, n - 1);
    let ([u0, y0], [u1, y1]) = (table[i - 1], table[i]);
    let s = (y1 - y0) / (u1 - u0);
    (y0 + s * (u - u0), s)
}

/// Clamp with its derivative (1 inside, 0 outside).
fn clamp_d(v: f64, lo: f64, hi: f64) -> (f64, f64) {
    if v < lo {
        (lo, 0.0)
    } else if v > hi {
        (hi, 0.0)
    } else {
        (v, 1.0)
    }
}

/// A named control block reading `inputs` and producing `outputs`.
#[derive(Clone, Debug)]
pub struct Controller {
    name: String,
    block: Block,
    inputs: Vec<String>,
    outputs: Vec<String>,
}

impl Controller {
    pub fn new(name: &str, block: Block, inputs: Vec<String>, outputs: Vec<String>) -> Self {
        Self {
            name: name.into(),
            block,
            inputs,
            outputs,
        }
    }

    /// PID: error e and its derivative with respect to each input.
    fn error(&self, u: &[f64], rm: bool) -> (f64, [f64; 2]) {
        if rm {
            (u[0] - u[1], [1.0, -1.0])
        } else {
            (u[0], [1.0, 0.0])
        }
    }

    /// PID: unsaturated output v, with ∂v/∂z (integral, filter) and ∂v/∂u (up to 3 inputs).
    fn pid_v(&self, pid: &Pid, rm: bool, z: &[f64], u: &[f64]) -> (f64, [f64; 2], [f64; 3]) {
        let (e, de) = self.error(u, rm);
        let ne = if rm { 2 } else { 1 };
        let mut v = pid.kp * e + z[0];
        let mut dz = [1.0, 0.0];
        let mut du = [0.0; 3];
        let mut ke = pid.kp;
        match pid.filter {
            Some(tf) if pid.kd != 0.0 => {
                v += pid.kd * (e - z[1]) / tf;
                ke += pid.kd / tf;
                dz[1] = -pid.kd / tf;
            }
            None if pid.kd != 0.0 => {
                v -= pid.kd * u[ne];
                du[ne] = -pid.kd;
            }
            _ => {}
        }
        for j in 0..ne {
            du[j] += ke * de[j];
        }
        (v, dz, du)
    }
}

impl Element for Controller {
    fn name(&self) -> &str {
        &self.name
    }
    fn nodes(&self) -> &[usize] {
        &[]
    }
    fn n_states(&self) -> usize {
        match &self.block {
            Block::RateLimit { .. } => 1,
            Block::StateSpace { a, .. } => a.nrows(),
            Block::Pid { pid, .. } => {
                if pid.filter.is_some() && pid.kd != 0.0 {
                    2
                } else {
                    1
                }
            }
            _ => 0,
        }
    }
    fn state_names(&self) -> Vec<String> {
        match &self.block {
            Block::RateLimit { .. } => vec!["output".into()],
            Block::StateSpace { a, .. } => (1..=a.nrows()).map(|i| format!("x{i}")).collect(),
            Block::Pid { .. } => ["integral", "derivative_filter"][..self.n_states()]
                .iter()
                .map(|s| s.to_string())
                .collect(),
            _ => Vec::new(),
        }
    }
    fn initial_states(&self, out: &mut [f64]) {
        out.fill(0.0);
        match &self.block {
            Block::RateLimit { initial, .. } => out[0] = *initial,
            Block::StateSpace { initial, .. } => out.copy_from_slice(initial),
            Block::Pid { pid, .. } => out[0] = pid.initial_integral,
            _ => {}
        }
    }
    fn signal_inputs(&self) -> &[String] {
        &self.inputs
    }
    fn signal_outputs(&self) -> &[String] {
        &self.outputs
    }
    fn feedthrough(&self) -> bool {
        match &self.block {
            Block::RateLimit { .. } => false,
            Block::StateSpace { d, .. } => d.iter().any(|&x| x != 0.0),
            _ => true,
        }
    }

    fn signals(&self, _ctx: &EvalContext, x: &ElementInput, out: &mut SignalTerms) {
        let u = x.signals;
        match &self.block {
            Block::Gain(k) => {
                out.values[0] = k * u[0];
                out.ds[(0, 0)] = *k;
            }
            Block::Sum(w) => {
                out.values[0] = w.iter().zip(u).map(|(w, u)| w * u).sum();
                for (j, w) in w.iter().enumerate() {
                    out.ds[(0, j)] = *w;
                }
            }
            Block::Saturation(lo, hi) => {
                let (y, d) = clamp_d(u[0], *lo, *hi);
                out.values[0] = y;
                out.ds[(0, 0)] = d;
            }
            Block::Lookup(t) => {
                let (y, d) = lookup(t, u[0]);
                out.values[0] = y;
                out.ds[(0, 0)] = d;
            }
            Block::RateLimit { .. } => {
                out.values[0] = x.states[0].z;
                out.k[(0, 0)] = 1.0;
            }
            Block::StateSpace { c, d, .. } => {
                for o in 0..c.nrows() {
                    let mut y = 0.0;
                    for i in 0..c.ncols() {
                        y += c[(o, i)] * x.states[i].z;
                        out.k[(o, i)] = c[(o, i)];
                    }
                    for j in 0..d.ncols() {
                        y += d[(o, j)] * u[j];
                        out.ds[(o, j)] = d[(o, j)];
                    }
                    out.values[o] = y;
                }
            }
            Block::Pid {
                pid,
                reference_and_measurement: rm,
            } => {
                let z2 = [x.states[0].z, x.states.get(1).map_or(0.0, |s| s.z)];
                let (v, dz, du) = self.pid_v(pid, *rm, &z2, u);
                let (y, dy) = clamp_d(v, pid.limits.0, pid.limits.1);
                out.values[0] = y;
                for (i, d) in dz.iter().enumerate().take(x.states.len()) {
                    out.k[(0, i)] = dy * d;
                }
                for (j, d) in du.iter().enumerate().take(u.len()) {
                    out.ds[(0, j)] = dy * d;
                }
            }
        }
    }

    fn evaluate(&self, _ctx: &EvalContext, x: &ElementInput, need: Need, out: &mut LocalTerms) {
        let u = x.signals;
        let tangents = need == Need::ResidualAndTangents;
        match &self.block {
            Block::RateLimit {
                rate,
                time_constant,
                ..
            } => {
                let z = x.states[0];
                let (f, d) = clamp_d((u[0] - z.z) / time_constant, -rate, *rate);
                out.r[0] = z.zd - f;
                if tangents {
                    out.c[(0, 0)] = 1.0;
                    out.k[(0, 0)] = d / time_constant;
                    out.ds[(0, 0)] = -d / time_constant;
                }
            }
            Block::StateSpace { a, b, .. } => {
                for i in 0..a.nrows() {
                    let mut r = x.states[i].zd;
                    for k in 0..a.ncols() {
                        r -= a[(i, k)] * x.states[k].z;
                    }
                    for j in 0..b.ncols() {
                        r -= b[(i, j)] * u[j];
                    }
                    out.r[i] = r;
                    if tangents {
                        out.c[(i, i)] = 1.0;
                        for k in 0..a.ncols() {
                            out.k[(i, k)] = -a[(i, k)];
                        }
                        for j in 0..b.ncols() {
                            out.ds[(i, j)] = -b[(i, j)];
                        }
                    }
                }
            }
            Block::Pid {
                pid,
                reference_and_measurement: rm,
            } => {
                let n = x.states.len();
                let z2 = [x.states[0].z, if n > 1 { x.states[1].z } else { 0.0 }];
                let (e, de) = self.error(u, *rm);
                let (v, dz, du) = self.pid_v(pid, *rm, &z2, u);
                let (y, dy) = clamp_d(v, pid.limits.0, pid.limits.1);
                // İ − K_i e − (y − v)/T_t = 0.
                let tt = pid.tracking;
                out.r[0] = x.states[0].zd - pid.ki * e - (y - v) / tt;
                if tangents {
                    out.c[(0, 0)] = 1.0;
                    let g = (dy - 1.0) / tt;
                    for (i, d) in dz.iter().enumerate().take(n) {
                        out.k[(0, i)] = -g * d;
                    }
                    let ne = if *rm { 2 } else { 1 };
                    for j in 0..u.len() {
                        let dej = if j < ne { de[j] } else { 0.0 };
                        out.ds[(0, j)] = -pid.ki * dej - g * du[j];
                    }
                }
                if n > 1 {
                    // ẋ_d − (e − x_d)/T_f = 0.
                    let tf = pid.filter.unwrap_or(1.0);
                    out.r[1] = x.states[1].zd - (e - z2[1]) / tf;
                    if tangents {
                        out.c[(1, 1)] = 1.0;
                        out.k[(1, 1)] = 1.0 / tf;
                        let ne = if *rm { 2 } else { 1 };
                        for (j, d) in de.iter().enumerate().take(ne) {
                            out.ds[(1, j)] = -d / tf;
                        }
                    }
                }
            }
            _ => {}
        }
    }
}
