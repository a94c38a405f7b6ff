//! Rotor-level outputs of a `[[rotors]]` entry (docs/aerodynamics.md, "Rotor outputs"):
//! from its stations' loads F_k, M_k at p_k (global), the hub's angular velocity ω and the
//! wind W at the centre c, with n̂ the rotor axis (opposite to the thrust), R the tip radius
//! and A = πR²:
//!
//! `T = −Σ F_k·n̂`,   `Ω = |ω·n̂|`,   `Q = Σ [(p_k − c) × F_k + M_k]·ê`,   `P = Q Ω`,
//! `V = −W(c, t)·n̂`,   `λ = Ω R/V`,   `C_T = T/(½ρAV²)`,   `C_P = P/(½ρAV³)`,
//! `C_T,tip = T/(ρA(ΩR)²)`,   `C_P,tip = P/(ρA(ΩR)³)`,
//!
//! ê = n̂ sign(ω·n̂) the sense of rotation (Q > 0 drives the rotor: a wind turbine; Q < 0
//! the air resists it: a propeller or a helicopter rotor). The free-stream coefficients are
//! written 0 when V ≤ 0 and the tip-speed ones when Ω = 0 (undefined there; AeroDyn's
//! convention).
//!
//! The element owns no unknowns and adds no equation: it evaluates copies of the rotor's
//! stations with their states (read as the direct signals `state:<station>.<state>` and
//! `state_rate:…`) and input signals.

use super::station::AeroStation;
use super::wind::Wind;
use crate::core::{Element, ElementInput, EvalContext, LocalTerms, Need};
use nalgebra::Vector3;
use std::sync::Arc;

/// The rotor's geometry and air.
#[derive(Clone, Debug)]
pub struct RotorGeometry {
    /// Centre c [m] and unit axis n̂ (opposite to the thrust), global.
    pub centre: Vector3<f64>,
    pub axis: Vector3<f64>,
    /// Tip radius R [m].
    pub radius: f64,
    /// Air density ρ [kg/m³].
    pub density: f64,
}

/// The rotor-level quantities, in [`OUTPUTS`] order.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Performance {
    pub thrust: f64,
    pub torque: f64,
    pub power: f64,
    pub rotor_speed: f64,
    pub free_stream: f64,
    pub tip_speed_ratio: f64,
    pub ct: f64,
    pub cp: f64,
    pub ct_tip: f64,
    pub cp_tip: f64,
}

/// Output names and units.
pub const OUTPUTS: [(&str, &str); 10] = [
    ("thrust", "N"),
    ("torque", "N m"),
    ("power", "W"),
    ("rotor_speed", "rad/s"),
    ("free_stream", "m/s"),
    ("tip_speed_ratio", "1"),
    ("ct", "1"),
    ("cp", "1"),
    ("ct_tip", "1"),
    ("cp_tip", "1"),
];

impl RotorGeometry {
    /// The rotor quantities from the stations' (p, F, M), the hub's angular velocity ω
    /// and the wind W at the centre (all global).
    pub fn performance(
        &self,
        loads: &[(Vector3<f64>, Vector3<f64>, Vector3<f64>)],
        omega: &Vector3<f64>,
        wind: &Vector3<f64>,
    ) -> Performance {
        let n = self.axis;
        let w_n = omega.dot(&n);
        let e = if w_n < 0.0 { -n } else { n };
        let (mut f, mut q) = (Vector3::zeros(), 0.0);
        for (p, force, moment) in loads {
            f += force;
            q += ((p - self.centre).cross(force) + moment).dot(&e);
        }
        let thrust = -f.dot(&n);
        let speed = w_n.abs();
        let power = q * speed;
        let v = -wind.dot(&n);
        let area = std::f64::consts::PI * self.radius * self.radius;
        let rho = self.density;
        let (lambda, ct, cp) = if v > 0.0 {
            (
                speed * self.radius / v,
                thrust / (0.5 * rho * area * v * v),
                power / (0.5 * rho * area * v * v * v),
            )
        } else {
            (0.0, 0.0, 0.0)
        };
        let tip = speed * self.radius;
        let (ct_tip, cp_tip) = if tip > 0.0 {
            (
                thrust / (rho * area * tip * tip),
                power / (rho * area * tip * tip * tip),
            )
        } else {
            (0.0, 0.0)
        };
        Performance {
            thrust,
            torque: q,
            power,
            rotor_speed: speed,
            free_stream: v,
            tip_speed_ratio: lambda,
            ct,
            cp,
            ct_tip,
            cp_tip,
        }
    }
}

/// The outputs element of a rotor.
pub struct RotorPerformance {
    name: String,
    geometry: RotorGeometry,
    wind: Arc<Wind>,
    /// The hub node whose angular velocity is the rotor's.
    hub: usize,
    stations: Vec<AeroStation>,
    /// Per station: its own input signals, then `state:` and `state_rate:` of its states.
    inputs: Vec<String>,
}

impl RotorPerformance {
    pub fn new(
        name: impl Into<String>,
        geometry: RotorGeometry,
        wind: Arc<Wind>,
        hub: usize,
        stations: Vec<AeroStation>,
    ) -> Self {
        let mut inputs = Vec::new();
        for s in &stations {
            inputs.extend(s.signal_inputs().iter().cloned());
            let states = s.state_names();
            for prefix in ["state", "state_rate"] {
                inputs.extend(states.iter().map(|z| format!("{prefix}:{}.{z}", s.name())));
            }
        }
        Self {
            name: name.into(),
            geometry,
            wind,
            hub,
            stations,
            inputs,
        }
    }

    /// The rotor quantities at time t for the nodes and the signals read.
    pub fn evaluate_at(&self, t: f64, x: &ElementInput) -> Performance {
        let mut loads = Vec::with_capacity(self.stations.len());
        let mut k = 0;
        for s in &self.stations {
            let ni = s.signal_inputs().len();
            let ns = s.n_states();
            let sig = &x.signals[k..k + ni];
            let z = &x.signals[k + ni..k + ni + ns];
            let zd = &x.signals[k + ni + ns..k + ni + 2 * ns];
            k += ni + 2 * ns;
            loads.push(s.point_loads(t, x.nodes, z, zd, sig));
        }
        let hub = &x.nodes[self.hub];
        let omega = hub.r() * hub.w;
        let c: [f64; 3] = self.geometry.centre.into();
        let wind = Vector3::from(self.wind.velocity(&c, t));
        self.geometry.performance(&loads, &omega, &wind)
    }
}

impl Element for RotorPerformance {
    fn name(&self) -> &str {
        &self.name
    }

    fn nodes(&self) -> &[usize] {
        &[]
    }

    fn signal_inputs(&self) -> &[String] {
        &self.inputs
    }

    fn evaluate(&self, _ctx: &EvalContext, _x: &ElementInput, _need: Need, _out: &mut LocalTerms) {}

    fn output_names(&self) -> Vec<(String, &'static str)> {
        OUTPUTS.iter().map(|(n, u)| (n.to_string(), *u)).collect()
    }

    fn outputs(&self, ctx: &EvalContext, x: &ElementInput, out: &mut [f64]) {
        let p = self.evaluate_at(ctx.time, x);
        out.copy_from_slice(&[
            p.thrust,
            p.torque,
            p.power,
            p.rotor_speed,
            p.free_stream,
            p.tip_speed_ratio,
            p.ct,
            p.cp,
            p.ct_tip,
            p.cp_tip,
        ]);
    }

    fn breakpoints(&self, out: &mut Vec<f64>) {
        out.extend(
            self.wind
                .breakpoints(self.geometry.centre.dot(&self.wind.direction)),
        );
    }
}
