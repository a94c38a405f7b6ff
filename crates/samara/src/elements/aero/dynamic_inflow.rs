//! Pitt–Peters dynamic inflow (Pitt & Peters 1981, "Theoretical prediction of
//! dynamic-inflow derivatives", Vertica 5; Peters & HaQuang 1988, "Dynamic inflow for
//! practical applications", JAHS 33(4)): three inflow states of a rotor disc of radius R,
//! the induced velocity through it (along the disc axis n, the way the induced flow goes)
//!
//! `v(r, ψ) = v₀ + v_s (r/R) sin ψ + v_c (r/R) cos ψ`,
//!
//! driven by the thrust T and its first moments, in the work-conjugate form of
//! Peters & HaQuang (dimensional, ρ the air density, A = πR²):
//!
//! `ρ A R M v̇ + ρ A D L̃⁻¹ v = F`,  F = (T, T_s, T_c), T_s = Σ dT (r/R) sin ψ,
//! T_c = Σ dT (r/R) cos ψ,
//!
//! with the apparent masses M = diag(8/(3π), 16/(45π), 16/(45π)) (the impermeable disc),
//! the flow parameters D = diag(U_T, U_m, U_m),
//! U_T = √(μ² + (w + v₀)²) (total flow through the disc: w the free stream along n, μ in
//! the disc plane), U_m = (μ² + (w + v₀)(w + 2v₀))/U_T (the mass-flow parameter of the
//! harmonics), and the static-gain matrix with the wake skew angle χ = atan(μ/(w + v₀)),
//! in the (uniform, downstream, lateral) harmonics:
//!
//! `L̃ = [[1/2, 15π/64 tan(χ/2), 0], [15π/64 tan(χ/2), 4 cos χ/(1 + cos χ), 0], [0, 0, 4/(1 + cos χ)]]`,
//!
//! rotated into (sin ψ, cos ψ) by the direction of the edgewise flow. Steady hover and
//! axial flight give momentum theory, T = 2ρA v₀ (w + v₀); about a hover state the
//! uniform inflow has the time constant τ = M₁₁ R/(4 v₀) = 0.849/(4λΩ) under a given
//! thrust. The rows are written divided by ρAR (units m/s²).

use super::wind::Wind;
use crate::core::{Element, ElementInput, EvalContext, LocalTerms, Need, SignalTerms};
use crate::math::dual::{Dual, Scalar};
use nalgebra::Vector3;
use std::f64::consts::PI;
use std::sync::Arc;

/// Apparent masses of the uniform and first-harmonic inflow (Peters & HaQuang 1988).
pub const APPARENT_MASS: [f64; 3] = [8.0 / (3.0 * PI), 16.0 / (45.0 * PI), 16.0 / (45.0 * PI)];

/// Regularization of the total flow U_T at zero flow [m/s] (the flow parameters are
/// √(·) of the velocities; 1e-6 m/s changes a hover inflow of 1 m/s by 1e-12).
const FLOW_FLOOR: f64 = 1e-6;

/// The rotor disc: centre, unit axis n (the direction of the induced flow through the
/// disc, opposite to the thrust), the azimuth reference e₁ (ψ = 0, in the disc plane) and
/// the radius R.
#[derive(Clone, Debug, PartialEq)]
pub struct RotorDisc {
    pub centre: Vector3<f64>,
    pub axis: Vector3<f64>,
    pub azimuth_reference: Vector3<f64>,
    pub radius: f64,
}

impl RotorDisc {
    /// (r/R) sin ψ and (r/R) cos ψ of a point: its in-plane offset along e₂ = n × e₁ and
    /// e₁, over R.
    pub fn harmonics<S: Scalar>(&self, p: &[S; 3]) -> (S, S) {
        let e1 = self.azimuth_reference;
        let e2 = self.axis.cross(&e1);
        let rel: [S; 3] = std::array::from_fn(|k| p[k] - self.centre[k]);
        let d = |e: &Vector3<f64>| (rel[0] * e[0] + rel[1] * e[1] + rel[2] * e[2]) / self.radius;
        (d(&e2), d(&e1))
    }
}

/// The Pitt–Peters inflow of one rotor: an element with three states (v₀, v_s, v_c
/// [m/s]) and no nodes, reading the thrust signals of its stations (three per station:
/// dT, dT (r/R) sin ψ, dT (r/R) cos ψ) and producing its states as the signals
/// `<name>.v0`, `<name>.vs`, `<name>.vc` (no feedthrough: the stations' loads reach
/// the inflow only through its states).
#[derive(Clone, Debug)]
pub struct PittPeters {
    name: String,
    disc: RotorDisc,
    density: f64,
    wind: Arc<Wind>,
    inputs: Vec<String>,
    outputs: Vec<String>,
}

/// The signals a rotor produces, named after it.
pub fn inflow_signals(rotor: &str) -> [String; 3] {
    ["v0", "vs", "vc"].map(|s| format!("{rotor}.{s}"))
}

/// The three thrust signals a station of a Pitt–Peters rotor produces.
pub fn thrust_signals(station: &str) -> [String; 3] {
    ["thrust", "thrust_sine", "thrust_cosine"].map(|s| format!("{station}.{s}"))
}

impl PittPeters {
    /// The inflow of the rotor `name` over the stations `stations` (element names).
    pub fn new(
        name: impl Into<String>,
        disc: RotorDisc,
        density: f64,
        wind: Arc<Wind>,
        stations: &[String],
    ) -> Self {
        let name = name.into();
        let inputs = stations.iter().flat_map(|s| thrust_signals(s)).collect();
        let outputs = inflow_signals(&name).to_vec();
        Self {
            name,
            disc,
            density,
            wind,
            inputs,
            outputs,
        }
    }

    pub fn disc(&self) -> &RotorDisc {
        &self.disc
    }

    /// Free stream at the centre: along the axis w, in the disc plane μ (magnitude) and its
    /// direction's (sin, cos) in azimuth (ψ of the downstream edge).
    fn free_stream(&self, t: f64) -> (f64, f64, f64, f64) {
        let c: [f64; 3] = self.disc.centre.into();
        let wv = Vector3::from(self.wind.velocity(&c, t));
        let n = self.disc.axis;
        let w = wv.dot(&n);
        let edge = wv - n * w;
        let mu = edge.norm();
        let e1 = self.disc.azimuth_reference;
        let e2 = n.cross(&e1);
        if mu > 1e-12 {
            (w, mu, edge.dot(&e2) / mu, edge.dot(&e1) / mu)
        } else {
            (w, 0.0, 0.0, 1.0)
        }
    }

    /// (1/R) D L̃⁻¹ v: the static part of the rows, in (uniform, sine, cosine).
    pub fn static_rows<S: Scalar>(&self, t: f64, v: &[S; 3]) -> [S; 3] {
        let (w, mu, ds, dc) = self.free_stream(t);
        let axial = v[0] + w;
        // |w + v₀|, floored: the skew angle is measured from the axis whatever the
        // sense of the flow (χ ∈ [0, 90°]), and pure axial flow (μ = 0) has χ = 0 even
        // at zero flow.
        let a_r = (axial * axial + FLOW_FLOOR * FLOW_FLOOR).sqrt();
        let ut = (a_r * a_r + mu * mu).sqrt();
        let um = (axial * (v[0] * 2.0 + w) + mu * mu + FLOW_FLOOR * FLOW_FLOOR) / ut;
        // cos χ = |w + v₀|/U_T, tan(χ/2) = sin χ/(1 + cos χ) = μ/(U_T + |w + v₀|).
        let cos_chi = a_r / ut;
        let tan_half = S::cst(mu) / (ut + a_r);
        let k = tan_half * (15.0 * PI / 64.0);
        let lat = S::cst(4.0) / (cos_chi + 1.0);
        let down = cos_chi * lat;
        // L̃ in (uniform, sine, cosine): the downstream direction d = (d_s, d_c).
        let l = [
            [S::cst(0.5), k * ds, k * dc],
            [
                k * ds,
                lat + (down - lat) * (ds * ds),
                (down - lat) * (ds * dc),
            ],
            [
                k * dc,
                (down - lat) * (ds * dc),
                lat + (down - lat) * (dc * dc),
            ],
        ];
        let x = solve3(&l, v);
        [
            ut * x[0] / self.disc.radius,
            um * x[1] / self.disc.radius,
            um * x[2] / self.disc.radius,
        ]
    }

    fn forcing(&self, signals: &[f64]) -> [f64; 3] {
        let mut f = [0.0; 3];
        for (k, s) in signals.iter().enumerate() {
            f[k % 3] += s;
        }
        f
    }

    fn area_scale(&self) -> f64 {
        self.density * PI * self.disc.radius.powi(3)
    }

    /// Steady-state inflow (v̇ = 0) under the forcing F, by Newton from momentum theory.
    pub fn steady(&self, t: f64, forcing: [f64; 3]) -> [f64; 3] {
        let s = self.area_scale();
        let (w, mu, _, _) = self.free_stream(t);
        let a = PI * self.disc.radius.powi(2) * self.density;
        // Start: the climb formula with μ neglected, v₀ = −w/2 + √(w²/4 + T/(2ρA)).
        let t0 = forcing[0];
        let v0 = if t0 > 0.0 {
            -0.5 * w + (0.25 * w * w + t0 / (2.0 * a)).sqrt()
        } else {
            0.0
        };
        let mut v = [v0.max(0.0) + 1e-3 * (1.0 + mu), 0.0, 0.0];
        for _ in 0..100 {
            let vd: [Dual<3>; 3] = std::array::from_fn(|k| Dual::var(v[k], k));
            let r = self.static_rows(t, &vd);
            let res: [f64; 3] = std::array::from_fn(|k| r[k].v - forcing[k] / s);
            let jac: [[f64; 3]; 3] = std::array::from_fn(|i| r[i].d);
            let dv = solve3(&jac, &res);
            for k in 0..3 {
                v[k] -= dv[k];
            }
            if dv.iter().map(|x| x.abs()).fold(0.0, f64::max) < 1e-13 * (1.0 + v[0].abs()) {
                break;
            }
        }
        v
    }
}

/// x = A⁻¹ b by Cramer's rule (A 3×3, non-singular).
fn solve3<S: Scalar>(a: &[[S; 3]; 3], b: &[S; 3]) -> [S; 3] {
    let det3 = |m: &[[S; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det3(a);
    std::array::from_fn(|c| {
        let mut m = *a;
        for r in 0..3 {
            m[r][c] = b[r];
        }
        det3(&m) / d
    })
}

impl Element for PittPeters {
    fn name(&self) -> &str {
        &self.name
    }
    fn nodes(&self) -> &[usize] {
        &[]
    }
    fn n_states(&self) -> usize {
        3
    }
    fn state_names(&self) -> Vec<String> {
        vec!["v0".into(), "vs".into(), "vc".into()]
    }
    fn signal_inputs(&self) -> &[String] {
        &self.inputs
    }
    fn signal_outputs(&self) -> &[String] {
        &self.outputs
    }
    fn feedthrough(&self) -> bool {
        false
    }
    fn signals(&self, _ctx: &EvalContext, x: &ElementInput, out: &mut SignalTerms) {
        for k in 0..3 {
            out.values[k] = x.states[k].z;
            out.k[(k, k)] = 1.0;
        }
    }

    /// Rows `M v̇ + (1/R) D L̃⁻¹ v − F/(ρAR)` [m/s²].
    fn evaluate(&self, ctx: &EvalContext, x: &ElementInput, need: Need, out: &mut LocalTerms) {
        let f = self.forcing(x.signals);
        let s = self.area_scale();
        let vd: [Dual<3>; 3] = std::array::from_fn(|k| Dual::var(x.states[k].z, k));
        let r = self.static_rows(ctx.time, &vd);
        for k in 0..3 {
            out.r[k] += APPARENT_MASS[k] * x.states[k].zd + r[k].v - f[k] / s;
        }
        if need == Need::ResidualAndTangents {
            for i in 0..3 {
                out.c[(i, i)] += APPARENT_MASS[i];
                for j in 0..3 {
                    out.k[(i, j)] += r[i].d[j];
                }
            }
            for j in 0..x.signals.len() {
                out.ds[(j % 3, j)] -= 1.0 / s;
            }
        }
    }

    fn output_names(&self) -> Vec<(String, &'static str)> {
        vec![
            ("thrust".into(), "N"),
            ("thrust_sine".into(), "N"),
            ("thrust_cosine".into(), "N"),
            ("skew_angle".into(), "rad"),
        ]
    }

    fn outputs(&self, ctx: &EvalContext, x: &ElementInput, out: &mut [f64]) {
        let f = self.forcing(x.signals);
        out[..3].copy_from_slice(&f);
        let (w, mu, _, _) = self.free_stream(ctx.time);
        out[3] = mu.atan2((w + x.states[0].z).abs());
    }

    fn breakpoints(&self, out: &mut Vec<f64>) {
        out.extend(
            self.wind
                .breakpoints(self.disc.centre.dot(&self.wind.direction)),
        );
    }
}
