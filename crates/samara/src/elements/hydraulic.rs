//! A lumped hydraulic circuit: volumes whose pressures are the element's states, joined
//! by orifices to each other and to reservoirs of fixed pressure, and (optionally) a
//! double-acting actuator between points on two nodes whose chambers are two of the
//! volumes (Merritt, *Hydraulic Control Systems*, 1967, ch. 3–5).
//!
//! **Volumes** (pressure p, bulk modulus β): continuity, one row per volume,
//!
//! `r_p = (V(l)/β) ṗ + dV/dt − Σ Q_in = 0`,
//!
//! with V = V₀ for a plain volume; an actuator's cap chamber has V = V₀ + A_c (l − l₀)
//! (dV/dt = A_c l̇), its rod chamber V = V₀ − A_r (l − l₀) (dV/dt = −A_r l̇), l the
//! distance between the actuator's points (its stroke from l₀). Rows in m³/s; the
//! assembler scales them by `1/(∂ż/∂Δz)` in dynamics, so their block of the iteration
//! matrix is `V/β + O(h)`.
//!
//! **Orifices** from port a to port b (Δp = p_a − p_b, flow Q from a to b):
//! - turbulent: `Q = C_d A √(2/ρ) Δp / (Δp² + Δp_t²)^¼` — the square-root law
//!   `C_d A √(2|Δp|/ρ) sgn Δp` for |Δp| ≫ Δp_t, regularized into a laminar slope at
//!   Δp → 0 (Δp_t, the transition pressure) so Newton has a finite tangent;
//! - laminar: `Q = G Δp` (a leak, a capillary);
//! - check valve: the turbulent law times the opening `x = clamp((Δp − p_c)/Δp_o, 0, 1)`
//!   (cracking pressure p_c, full opening over Δp_o): no flow from b to a.
//!
//! **Gas-charged volumes** (accumulators, a shock strut's gas chamber): a gas volume V_a at
//! the precharge pressure p₀, compressed polytropically, p V_gⁿ = p₀ V_aⁿ. Above p₀ the
//! liquid it holds, V_a − V_g(p), grows with p, so the volume's compliance gains
//! `dV_l/dp = V_g/(n p) = V_a p₀^{1/n} / (n p^{1+1/n})` (Merritt §3.9; n = 1 isothermal,
//! n = 1.4 adiabatic air/nitrogen); below p₀ an accumulator's bladder holds no liquid and
//! only the liquid compliance V/β remains (a free gas charge, as in a shock strut, follows
//! the law on both sides of p₀). The continuity row becomes
//! `(V(l)/β + [p > p₀] V_g(p)/(n p)) ṗ + dV/dt − Σ Q_in = 0`.
//!
//! **Orifice multipliers**: an orifice's flow may be scaled by a metering-pin area table
//! A(stroke) (piecewise linear in the actuator's stroke l − l₀, the law's coefficient then
//! per unit area) or by a valve opening `clamp(s, 0, 1)` read from a signal (a servo
//! valve driven by a controller).
//!
//! **Actuator**: the pressures push the points apart with `F = Σ pᵢ Aᵢ` over its chambers
//! (signed areas: the cap chamber +A_c, the rod chamber −A_r, further chambers as given;
//! a tension `−F` along the line of action); chamber i's volume is V₀ + Aᵢ (l − l₀).
//!
//! No energies are reported: the circuit's compression energy and the reservoirs' work
//! are not part of the mechanical energy balance.

use super::line_of_action::LineOfAction;
use super::{Element, EvalContext, LocalTerms, Need};
use crate::core::ElementInput;
use nalgebra::Vector3;

/// An end of an orifice.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Port {
    /// The circuit's volume with this index (its pressure is a state).
    Volume(usize),
    /// A reservoir at a fixed pressure [Pa].
    Reservoir(f64),
}

/// Flow law of an orifice.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum OrificeLaw {
    /// `coefficient` = C_d A √(2/ρ); `transition` = Δp_t > 0.
    Turbulent { coefficient: f64, transition: f64 },
    /// Conductance G [m³/(s Pa)].
    Laminar { conductance: f64 },
    /// Turbulent law times the opening between `cracking` and `cracking + opening`.
    CheckValve {
        coefficient: f64,
        transition: f64,
        cracking: f64,
        opening: f64,
    },
}

impl OrificeLaw {
    /// `(Q, dQ/dΔp)`.
    pub fn flow(&self, dp: f64) -> (f64, f64) {
        let turbulent = |k: f64, t: f64| {
            let s = dp * dp + t * t;
            let q = k * dp * s.powf(-0.25);
            let dq = k * (0.5 * dp * dp + t * t) * s.powf(-1.25);
            (q, dq)
        };
        match *self {
            OrificeLaw::Turbulent {
                coefficient,
                transition,
            } => turbulent(coefficient, transition),
            OrificeLaw::Laminar { conductance } => (conductance * dp, conductance),
            OrificeLaw::CheckValve {
                coefficient,
                transition,
                cracking,
                opening,
            } => {
                let u = (dp - cracking) / opening;
                if u <= 0.0 {
                    return (0.0, 0.0);
                }
                let (q, dq) = turbulent(coefficient, transition);
                if u >= 1.0 {
                    (q, dq)
                } else {
                    (u * q, u * dq + q / opening)
                }
            }
        }
    }
}

/// A gas charge: V_a [m³] at the precharge pressure p₀ [Pa], polytropic exponent n;
/// in a bladder (an accumulator: the gas cannot expand beyond V_a) or free (a strut's gas
/// chamber: the law holds on both sides of p₀).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GasCharge {
    pub volume: f64,
    pub precharge: f64,
    pub exponent: f64,
    pub bladder: bool,
}

impl GasCharge {
    /// Gas volume V_g(p) = V_a (p₀/p)^{1/n} (V_a below p₀ in a bladder).
    pub fn gas_volume(&self, p: f64) -> f64 {
        if p > self.precharge || (!self.bladder && p > 0.0) {
            self.volume * (self.precharge / p).powf(1.0 / self.exponent)
        } else {
            self.volume
        }
    }

    /// `(dV_l/dp, d²V_l/dp²)` of the liquid it holds: V_g/(n p) above p₀, 0 below in a
    /// bladder.
    pub fn compliance(&self, p: f64) -> (f64, f64) {
        if p > self.precharge || (!self.bladder && p > 0.0) {
            let c = self.gas_volume(p) / (self.exponent * p);
            (c, -(1.0 + 1.0 / self.exponent) * c / p)
        } else {
            (0.0, 0.0)
        }
    }
}

/// A hydraulic volume.
#[derive(Clone, Debug, PartialEq)]
pub struct Volume {
    pub name: String,
    /// V₀ [m³] > 0 (for a chamber: at l = l₀).
    pub volume: f64,
    /// β [Pa] > 0.
    pub bulk_modulus: f64,
    pub initial_pressure: f64,
    /// A gas charge (accumulator, strut gas chamber).
    pub gas: Option<GasCharge>,
}

/// What scales an orifice's flow.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum Multiplier {
    #[default]
    None,
    /// Area [m²] against the actuator's stroke l − l₀ (piecewise linear, constant beyond).
    StrokeTable(Vec<[f64; 2]>),
    /// Opening clamp(s, 0, 1) of the circuit's input signal with this index.
    Opening(usize),
}

/// An orifice between two ports.
#[derive(Clone, Debug, PartialEq)]
pub struct Orifice {
    pub name: String,
    pub from: Port,
    pub to: Port,
    pub law: OrificeLaw,
    pub multiplier: Multiplier,
}

/// An actuator: chambers (volume indices) with signed piston areas (+ extends).
#[derive(Clone, Debug)]
pub struct Actuator {
    pub line: LineOfAction,
    /// l₀, where the chambers have their volumes V₀.
    pub rest_length: f64,
    /// (volume, signed area): the cap chamber +A_c, the rod chamber −A_r, others.
    pub chambers: Vec<(usize, f64)>,
}

/// A hydraulic circuit.
#[derive(Clone, Debug)]
pub struct HydraulicCircuit {
    name: String,
    volumes: Vec<Volume>,
    orifices: Vec<Orifice>,
    actuator: Option<Actuator>,
    nodes: Vec<usize>,
    inputs: Vec<String>,
}

impl HydraulicCircuit {
    /// A circuit; `inputs` are the signals the orifices' openings read.
    pub fn new(
        name: impl Into<String>,
        volumes: Vec<Volume>,
        orifices: Vec<Orifice>,
        actuator: Option<Actuator>,
        inputs: Vec<String>,
    ) -> Self {
        let nodes = actuator
            .as_ref()
            .map_or(Vec::new(), |a| a.line.nodes().to_vec());
        Self {
            name: name.into(),
            volumes,
            orifices,
            actuator,
            nodes,
            inputs,
        }
    }

    /// Flow multiplier m, dm/dl (stroke), dm/ds (its input signal).
    fn multiplier(&self, o: &Orifice, stroke: f64, x: &ElementInput) -> (f64, f64, f64) {
        match &o.multiplier {
            Multiplier::None => (1.0, 0.0, 0.0),
            Multiplier::StrokeTable(t) => {
                let (a, d) = super::controller_lookup(t, stroke);
                (a, d, 0.0)
            }
            Multiplier::Opening(i) => {
                let s = x.signals[*i];
                if s <= 0.0 {
                    (0.0, 0.0, 0.0)
                } else if s >= 1.0 {
                    (1.0, 0.0, 0.0)
                } else {
                    (s, 0.0, 1.0)
                }
            }
        }
    }

    fn pressure(&self, x: &ElementInput, p: Port) -> f64 {
        match p {
            Port::Volume(i) => x.states[i].z,
            Port::Reservoir(v) => v,
        }
    }

    /// Per volume i: `∂V/∂l`, the sum of its chambers' signed areas.
    fn chamber_rate(&self, i: usize) -> f64 {
        let Some(a) = &self.actuator else { return 0.0 };
        a.chambers.iter().filter(|c| c.0 == i).map(|c| c.1).sum()
    }

    /// Actuator force F = Σ pᵢ Aᵢ pushing the points apart.
    fn actuator_force(&self, x: &ElementInput) -> f64 {
        let Some(a) = &self.actuator else { return 0.0 };
        a.chambers
            .iter()
            .map(|&(c, area)| x.states[c].z * area)
            .sum()
    }
}

impl Element for HydraulicCircuit {
    fn name(&self) -> &str {
        &self.name
    }

    fn nodes(&self) -> &[usize] {
        &self.nodes
    }

    fn n_states(&self) -> usize {
        self.volumes.len()
    }

    fn state_names(&self) -> Vec<String> {
        self.volumes
            .iter()
            .map(|v| format!("{}.pressure", v.name))
            .collect()
    }

    fn initial_states(&self, out: &mut [f64]) {
        for (o, v) in out.iter_mut().zip(&self.volumes) {
            *o = v.initial_pressure;
        }
    }

    fn signal_inputs(&self) -> &[String] {
        &self.inputs
    }

    fn evaluate(&self, _ctx: &EvalContext, x: &ElementInput, need: Need, out: &mut LocalTerms) {
        let nn = 6 * self.nodes.len();
        let tangents = need == Need::ResidualAndTangents;
        // Stroke and its rate.
        let line = self.actuator.as_ref().map(|a| (a, a.line.state(x.nodes)));
        let (dl, ldot) = line
            .as_ref()
            .map_or((0.0, 0.0), |(a, st)| (st.length - a.rest_length, st.rate));
        // Continuity rows.
        for (i, v) in self.volumes.iter().enumerate() {
            let row = nn + i;
            let s = self.chamber_rate(i);
            let vol = v.volume + s * dl;
            let pd = x.states[i].zd;
            let (cg, dcg) = v.gas.map_or((0.0, 0.0), |g| g.compliance(x.states[i].z));
            out.r[row] += (vol / v.bulk_modulus + cg) * pd + s * ldot;
            if !tangents {
                continue;
            }
            out.c[(row, row)] += vol / v.bulk_modulus + cg;
            out.k[(row, row)] += dcg * pd;
            if let Some((a, st)) = &line
                && s != 0.0
            {
                // ∂/∂q: (ṗ/β) s ∂l/∂q + s ∂l̇/∂q; ∂/∂v: s ∂l/∂q.
                a.line
                    .add_length_gradient(st, pd / v.bulk_modulus * s, |j, g| out.k[(row, j)] += g);
                a.line.add_rate_gradient(st, s, |j, g| out.k[(row, j)] += g);
                a.line
                    .add_length_gradient(st, s, |j, g| out.c[(row, j)] += g);
            }
        }
        // Orifices: outflow of `from`, inflow of `to`.
        for o in &self.orifices {
            let dp = self.pressure(x, o.from) - self.pressure(x, o.to);
            let (q0, dq0) = o.law.flow(dp);
            let (m, dm_dl, dm_ds) = self.multiplier(o, dl, x);
            let (q, dq) = (m * q0, m * dq0);
            for (port, sign) in [(o.from, 1.0), (o.to, -1.0)] {
                let Port::Volume(i) = port else { continue };
                out.r[nn + i] += sign * q;
                if !tangents {
                    continue;
                }
                for (col, cs) in [(o.from, 1.0), (o.to, -1.0)] {
                    if let Port::Volume(j) = col {
                        out.k[(nn + i, nn + j)] += sign * cs * dq;
                    }
                }
                if dm_dl != 0.0
                    && let Some((a, st)) = &line
                {
                    a.line
                        .add_length_gradient(st, sign * q0 * dm_dl, |j, g| out.k[(nn + i, j)] += g);
                }
                if let Multiplier::Opening(k) = o.multiplier {
                    out.ds[(nn + i, k)] += sign * q0 * dm_ds;
                }
            }
        }
        // Actuator force: tension −F on the line; ∂/∂p through the length gradient.
        if let Some((a, st)) = &line {
            let f = self.actuator_force(x);
            a.line
                .add_tension(st, -f, tangents.then_some((0.0, 0.0)), out);
            if tangents {
                for &(i, area) in &a.chambers {
                    a.line
                        .add_length_gradient(st, -area, |j, g| out.k[(j, nn + i)] += g);
                }
            }
        }
    }

    fn output_names(&self) -> Vec<(String, &'static str)> {
        let mut v: Vec<(String, &'static str)> = self
            .orifices
            .iter()
            .map(|o| (format!("{}.flow", o.name), "m^3/s"))
            .collect();
        if self.actuator.is_some() {
            v.push(("actuator.force".into(), "N"));
            v.push(("actuator.stroke".into(), "m"));
        }
        v
    }

    fn outputs(&self, _ctx: &EvalContext, x: &ElementInput, out: &mut [f64]) {
        let dl = self
            .actuator
            .as_ref()
            .map_or(0.0, |a| a.line.state(x.nodes).length - a.rest_length);
        for (k, o) in self.orifices.iter().enumerate() {
            let dp = self.pressure(x, o.from) - self.pressure(x, o.to);
            out[k] = self.multiplier(o, dl, x).0 * o.law.flow(dp).0;
        }
        if let Some(a) = &self.actuator {
            let n = self.orifices.len();
            out[n] = self.actuator_force(x);
            out[n + 1] = a.line.state(x.nodes).length - a.rest_length;
        }
    }
}

/// An actuator between `a` and `b` (see [`LineOfAction::new`]) with chambers of signed
/// areas (+ extends).
pub fn actuator(
    a: Option<(usize, Vector3<f64>)>,
    b: Option<(usize, Vector3<f64>)>,
    ground_points: [Vector3<f64>; 2],
    rest_length: f64,
    chambers: Vec<(usize, f64)>,
) -> Actuator {
    Actuator {
        line: LineOfAction::new(a, b, ground_points),
        rest_length,
        chambers,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each law's dQ/dΔp against central differences, and the turbulent law's limits.
    #[test]
    fn orifice_laws() {
        let laws = [
            OrificeLaw::Turbulent {
                coefficient: 2e-8,
                transition: 1e4,
            },
            OrificeLaw::Laminar { conductance: 3e-11 },
            OrificeLaw::CheckValve {
                coefficient: 2e-8,
                transition: 1e4,
                cracking: 2e4,
                opening: 5e4,
            },
        ];
        for law in laws {
            for dp in [-3e5, -5e3, 1e3, 3e4, 5e4, 2e5] {
                let (_, d) = law.flow(dp);
                let h = 1e-3;
                let fd = (law.flow(dp + h).0 - law.flow(dp - h).0) / (2.0 * h);
                assert!((d - fd).abs() < 1e-6 * d.abs().max(1e-14), "{law:?} {dp}");
            }
        }
        // Far above the transition: the square-root law to (Δp_t/Δp)².
        let (q, _) = laws[0].flow(1e7);
        let exact = 2e-8 * 1e7f64.sqrt();
        assert!((q - exact).abs() < 1e-6 * exact);
    }
}
