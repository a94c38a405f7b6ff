//! `[[hydraulics]]`: a lumped hydraulic circuit — volumes with pressure states, reservoirs,
//! orifices (turbulent, laminar, check valve) and an optional double-acting actuator
//! between points on two nodes (kernel: [`crate::elements::HydraulicCircuit`]).
//!
//! ```toml
//! [[hydraulics]]
//! name = "lift"
//! density = 850.0                       # ρ [kg/m³] of the fluid (turbulent orifices)
//! [[hydraulics.volumes]]
//! name = "cap"
//! volume = 1e-4                         # V₀ [m³]
//! bulk_modulus = 1.4e9                  # β [Pa]
//! initial_pressure = 1e5                # [Pa]
//! # gas_volume = 1e-3                   # V_a [m³]: a gas charge (accumulator) …
//! # precharge_pressure = 5e6            # p₀ [Pa] at which the gas fills V_a
//! # polytropic_exponent = 1.4           # n (default 1.4; 1 isothermal)
//! # bladder = true                      # false: free gas (a strut), law on both sides of p₀
//! [[hydraulics.reservoirs]]
//! name = "supply"
//! pressure = 2e7                        # [Pa], fixed
//! [[hydraulics.orifices]]
//! name = "inlet"
//! from = "supply"                       # a volume or a reservoir; Q > 0 from → to
//! to = "cap"
//! type = "turbulent"                    # turbulent | laminar | check_valve
//! area = 2e-6                           # A [m²]        (turbulent, check_valve)
//! discharge_coefficient = 0.7           # C_d           (turbulent, check_valve)
//! transition_pressure = 1e4             # Δp_t [Pa]     (turbulent, check_valve)
//! # conductance = 1e-12                 # G [m³/(s Pa)] (laminar)
//! # cracking_pressure = 2e5             # p_c [Pa]      (check_valve)
//! # opening_pressure = 5e5              # Δp_o [Pa]     (check_valve)
//! # area_table = [[-0.3, 2e-4], [0.0, 5e-4]]  # A [m²] vs actuator stroke l − l₀ [m]
//! #                                     # (metering pin; instead of `area`)
//! # opening = "valve"                   # flow × clamp(signal, 0, 1) (a servo valve)
//! [hydraulics.actuator]
//! node_a = "ground"
//! node_b = "rod"
//! point_a = [0.0, 0.0, 0.0]             # default the node
//! point_b = [0.5, 0.0, 0.0]
//! cap = "cap"                           # chamber volumes (at least one)
//! cap_area = 2e-3                       # A_c [m²]
//! rod = "annulus"
//! rod_area = 1.2e-3                     # A_r [m²]
//! # chambers = [{ volume = "gas", area = 0.01 }]  # further chambers, signed area
//! #                                     # (+ extends, − retracts)
//! ```

use super::spring::line_ends;
use super::{Build, ComponentKind};
use crate::core::NodeRef;
use crate::elements::{
    GasCharge, HydraulicCircuit, HydraulicOrifice, HydraulicVolume, OrificeLaw, OrificeMultiplier,
    Port, hydraulic_actuator,
};
use crate::model::validate::{Checker, Entry};
use crate::model::{Located, Model};
use crate::tangent_check::{TangentCase, random_node};
use nalgebra::Vector3;
use schemars::JsonSchema;
use serde::Deserialize;
use std::collections::HashMap;

/// A volume of fluid whose pressure is a state.
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct VolumeInput {
    /// Name, unique in the circuit; state `<circuit>.<name>.pressure`.
    pub name: Located<String>,
    /// V₀ [m³], positive (a chamber's volume at the actuator's initial length).
    pub volume: f64,
    /// Bulk modulus β [Pa], positive.
    pub bulk_modulus: f64,
    /// Initial pressure [Pa] (default 0).
    #[serde(default)]
    pub initial_pressure: Option<f64>,
    /// Gas charge volume V_a [m³] at the precharge pressure (an accumulator, a strut's gas).
    #[serde(default)]
    pub gas_volume: Option<f64>,
    /// Precharge pressure p₀ [Pa] (with `gas_volume`).
    #[serde(default)]
    pub precharge_pressure: Option<f64>,
    /// Polytropic exponent n of p V_gⁿ = const (default 1.4; 1 isothermal).
    #[serde(default)]
    pub polytropic_exponent: Option<f64>,
    /// The gas is in a bladder (default true: it cannot expand beyond V_a below p₀);
    /// false for free gas (a shock strut).
    #[serde(default)]
    pub bladder: Option<bool>,
}

/// A reservoir at a fixed pressure.
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ReservoirInput {
    /// Name, unique in the circuit.
    pub name: Located<String>,
    /// Pressure [Pa].
    pub pressure: f64,
}

/// Orifice laws.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum OrificeType {
    /// Q = C_d A √(2Δp/ρ), regularized below Δp_t.
    Turbulent,
    /// Q = G Δp.
    Laminar,
    /// Turbulent, opening from p_c over Δp_o, closed for reverse flow.
    CheckValve,
}

/// An orifice between two volumes or a volume and a reservoir.
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct OrificeInput {
    /// Name, unique in the circuit; output `<circuit>.<name>.flow`.
    pub name: Located<String>,
    /// Upstream port (volume or reservoir): Q > 0 flows from it.
    pub from: Located<String>,
    /// Downstream port.
    pub to: Located<String>,
    /// `turbulent`, `laminar` or `check_valve`.
    #[serde(rename = "type")]
    pub kind: OrificeType,
    /// Area A [m²] (turbulent, check valve).
    #[serde(default)]
    pub area: Option<f64>,
    /// Discharge coefficient C_d (turbulent, check valve; default 0.7).
    #[serde(default)]
    pub discharge_coefficient: Option<f64>,
    /// Δp_t [Pa] below which the square-root law turns laminar (default 1e4).
    #[serde(default)]
    pub transition_pressure: Option<f64>,
    /// Conductance G [m³/(s Pa)] (laminar).
    #[serde(default)]
    pub conductance: Option<f64>,
    /// Cracking pressure p_c [Pa] (check valve; default 0).
    #[serde(default)]
    pub cracking_pressure: Option<f64>,
    /// Pressure rise Δp_o [Pa] over which the check valve opens fully (check valve).
    #[serde(default)]
    pub opening_pressure: Option<f64>,
    /// Area [m²] against the actuator's stroke l − l₀ [m], [[stroke, area], …] (a metering
    /// pin; turbulent or check valve, instead of `area`).
    #[serde(default)]
    pub area_table: Option<Vec<[f64; 2]>>,
    /// A signal whose value, clamped to [0, 1], scales the flow (a valve opening).
    #[serde(default)]
    pub opening: Option<Located<String>>,
}

/// A further actuator chamber.
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ChamberInput {
    /// A volume of the circuit.
    pub volume: Located<String>,
    /// Signed piston area [m²]: positive extends the actuator, negative retracts it.
    pub area: f64,
}

/// A double-acting actuator.
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ActuatorInput {
    /// First node (`ground` allowed).
    pub node_a: Located<String>,
    /// Second node (`ground` allowed).
    pub node_b: Located<String>,
    /// Point on node A, global, initial configuration [m]; default the node.
    #[serde(default)]
    pub point_a: Option<[f64; 3]>,
    /// Point on node B; default the node.
    #[serde(default)]
    pub point_b: Option<[f64; 3]>,
    /// Cap chamber: a volume of the circuit (its pressure extends the actuator).
    #[serde(default)]
    pub cap: Option<Located<String>>,
    /// Cap piston area A_c [m²].
    #[serde(default)]
    pub cap_area: Option<f64>,
    /// Rod chamber: a volume of the circuit (its pressure retracts the actuator).
    #[serde(default)]
    pub rod: Option<Located<String>>,
    /// Annulus area A_r [m²].
    #[serde(default)]
    pub rod_area: Option<f64>,
    /// Further chambers with signed areas.
    #[serde(default)]
    pub chambers: Vec<Located<ChamberInput>>,
}

/// A hydraulic circuit.
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct HydraulicInput {
    /// Unique name.
    pub name: Located<String>,
    /// Fluid density ρ [kg/m³] (needed by turbulent orifices and check valves).
    #[serde(default)]
    pub density: Option<f64>,
    /// Volumes with pressure states.
    #[serde(default)]
    pub volumes: Vec<Located<VolumeInput>>,
    /// Reservoirs at fixed pressures.
    #[serde(default)]
    pub reservoirs: Vec<Located<ReservoirInput>>,
    /// Orifices.
    #[serde(default)]
    pub orifices: Vec<Located<OrificeInput>>,
    /// The actuator.
    #[serde(default)]
    pub actuator: Option<Located<ActuatorInput>>,
}

/// A validated actuator.
#[derive(Clone, Debug)]
pub struct ActuatorDef {
    pub node_a: NodeRef,
    pub node_b: NodeRef,
    pub point_a: Vector3<f64>,
    pub point_b: Vector3<f64>,
    /// (volume, signed area).
    pub chambers: Vec<(usize, f64)>,
}

/// A validated circuit.
#[derive(Clone, Debug)]
pub struct HydraulicDef {
    pub name: String,
    pub volumes: Vec<HydraulicVolume>,
    pub orifices: Vec<HydraulicOrifice>,
    pub actuator: Option<ActuatorDef>,
    /// Signals read by the orifices' openings.
    pub inputs: Vec<String>,
}

pub struct Hydraulic;

fn multiplier_is_none(m: &OrificeMultiplier) -> bool {
    matches!(m, OrificeMultiplier::None)
}

fn positive(cx: &mut Checker, e: &Entry, what: &str, key: &str, v: f64, hint: &str) -> bool {
    if v.is_finite() && v > 0.0 {
        return true;
    }
    cx.error(
        format!("{what}: `{key}` must be positive (got {v})"),
        cx.key(e, key),
        Some(hint.into()),
    );
    false
}

fn given(
    cx: &mut Checker,
    e: &Entry,
    what: &str,
    key: &str,
    v: Option<f64>,
    hint: &str,
) -> Option<f64> {
    match v {
        Some(v) => positive(cx, e, what, key, v, hint).then_some(v),
        None => {
            cx.error(
                format!("{what}: `{key}` is required"),
                e.span.clone(),
                Some(hint.into()),
            );
            None
        }
    }
}

fn not_here(cx: &mut Checker, e: &Entry, what: &str, key: &str, present: bool, hint: &str) -> bool {
    if present {
        cx.error(
            format!("{what}: `{key}` does not apply here"),
            cx.key(e, key),
            Some(hint.into()),
        );
    }
    !present
}

impl ComponentKind for Hydraulic {
    const NOUN: &'static str = "hydraulic circuit";
    type Input = HydraulicInput;
    type Def = HydraulicDef;

    fn name(input: &HydraulicInput) -> &Located<String> {
        &input.name
    }

    fn validate(
        s: &Located<HydraulicInput>,
        cx: &mut Checker,
        model: &mut Model,
    ) -> Option<HydraulicDef> {
        let hi = &s.value;
        let circuit = format!("hydraulic circuit '{}'", hi.name.value);
        let mut ok = true;
        let mut ports: HashMap<String, Port> = HashMap::new();
        let mut volumes = Vec::new();
        for v in &hi.volumes {
            let e = Entry {
                span: v.span.clone(),
            };
            let vi = &v.value;
            let what = format!("{circuit}, volume '{}'", vi.name.value);
            if ports.contains_key(&vi.name.value) {
                cx.error(
                    format!("{what}: the name is used twice in the circuit"),
                    vi.name.span.clone(),
                    Some("volumes and reservoirs of a circuit have distinct names".into()),
                );
                ok = false;
            }
            ok &= positive(cx, &e, &what, "volume", vi.volume, "V₀ [m³]");
            ok &= positive(
                cx,
                &e,
                &what,
                "bulk_modulus",
                vi.bulk_modulus,
                "β [Pa] of the fluid (about 1.4e9 for mineral oil; lower with entrained air)",
            );
            let p0 = vi.initial_pressure.unwrap_or(0.0);
            if !p0.is_finite() {
                cx.error(
                    format!("{what}: `initial_pressure` must be finite"),
                    cx.key(&e, "initial_pressure"),
                    Some("[Pa]".into()),
                );
                ok = false;
            }
            let gas = match (vi.gas_volume, vi.precharge_pressure) {
                (None, None) => {
                    for (key, present) in [
                        ("polytropic_exponent", vi.polytropic_exponent.is_some()),
                        ("bladder", vi.bladder.is_some()),
                    ] {
                        ok &= not_here(
                            cx,
                            &e,
                            &what,
                            key,
                            present,
                            "a gas charge needs `gas_volume` and `precharge_pressure`",
                        );
                    }
                    None
                }
                (va, pc) => {
                    let va = given(
                        cx,
                        &e,
                        &what,
                        "gas_volume",
                        va,
                        "V_a [m³] of the gas at the precharge pressure",
                    );
                    let pc = given(
                        cx,
                        &e,
                        &what,
                        "precharge_pressure",
                        pc,
                        "p₀ [Pa] at which the gas fills V_a",
                    );
                    let n = vi.polytropic_exponent.unwrap_or(1.4);
                    let n_ok = positive(
                        cx,
                        &e,
                        &what,
                        "polytropic_exponent",
                        n,
                        "n of p Vⁿ = const: 1 isothermal, 1.4 adiabatic",
                    );
                    let bladder = vi.bladder.unwrap_or(true);
                    if !bladder && p0 <= 0.0 {
                        cx.error(
                            format!("{what}: free gas needs a positive `initial_pressure`"),
                            cx.key(&e, "initial_pressure"),
                            Some("absolute pressure [Pa] of the gas".into()),
                        );
                        ok = false;
                    }
                    match (va, pc) {
                        (Some(volume), Some(precharge)) if n_ok => Some(GasCharge {
                            volume,
                            precharge,
                            exponent: n,
                            bladder,
                        }),
                        _ => {
                            ok = false;
                            None
                        }
                    }
                }
            };
            ports.insert(vi.name.value.clone(), Port::Volume(volumes.len()));
            volumes.push(HydraulicVolume {
                name: vi.name.value.clone(),
                volume: vi.volume,
                bulk_modulus: vi.bulk_modulus,
                initial_pressure: p0,
                gas,
            });
        }
        if volumes.is_empty() {
            cx.error(
                format!("{circuit} has no volume"),
                s.span.clone(),
                Some("a circuit's states are the pressures of its [[hydraulics.volumes]]".into()),
            );
            ok = false;
        }
        for r in &hi.reservoirs {
            let ri = &r.value;
            if ports.contains_key(&ri.name.value) {
                cx.error(
                    format!(
                        "{circuit}, reservoir '{}': the name is used twice in the circuit",
                        ri.name.value
                    ),
                    ri.name.span.clone(),
                    Some("volumes and reservoirs of a circuit have distinct names".into()),
                );
                ok = false;
            }
            if !ri.pressure.is_finite() {
                cx.error(
                    format!(
                        "{circuit}, reservoir '{}': `pressure` must be finite",
                        ri.name.value
                    ),
                    cx.key(
                        &Entry {
                            span: r.span.clone(),
                        },
                        "pressure",
                    ),
                    Some("[Pa]".into()),
                );
                ok = false;
            }
            ports.insert(ri.name.value.clone(), Port::Reservoir(ri.pressure));
        }
        let port = |cx: &mut Checker, name: &Located<String>, what: &str| -> Option<Port> {
            let p = ports.get(&name.value).copied();
            if p.is_none() {
                let known: Vec<String> = ports.keys().cloned().collect();
                let hint = match cx.suggest(&name.value, known.iter().map(|s| s.as_str())) {
                    Some(b) => format!("did you mean '{b}'?"),
                    None => "ports are the circuit's volumes and reservoirs".into(),
                };
                cx.error(
                    format!("{what}: unknown volume or reservoir '{}'", name.value),
                    name.span.clone(),
                    Some(hint),
                );
            }
            p
        };
        let mut orifices = Vec::new();
        let mut inputs: Vec<String> = Vec::new();
        let mut names = std::collections::HashSet::new();
        for o in &hi.orifices {
            let e = Entry {
                span: o.span.clone(),
            };
            let oi = &o.value;
            let what = format!("{circuit}, orifice '{}'", oi.name.value);
            if !names.insert(oi.name.value.clone()) {
                cx.error(
                    format!("{what}: the name is used twice in the circuit"),
                    oi.name.span.clone(),
                    Some("orifices of a circuit have distinct names".into()),
                );
                ok = false;
            }
            let from = port(cx, &oi.from, &what);
            let to = port(cx, &oi.to, &what);
            if let (Some(a), Some(b)) = (from, to) {
                let same = match (a, b) {
                    (Port::Volume(i), Port::Volume(j)) => i == j,
                    (Port::Reservoir(_), Port::Reservoir(_)) => {
                        cx.error(
                            format!("{what} joins two reservoirs"),
                            oi.to.span.clone(),
                            Some("an orifice must touch at least one volume".into()),
                        );
                        ok = false;
                        false
                    }
                    _ => false,
                };
                if same {
                    cx.error(
                        format!("{what} joins volume '{}' to itself", oi.to.value),
                        oi.to.span.clone(),
                        Some("`from` and `to` are two different ports".into()),
                    );
                    ok = false;
                }
            }
            let mut multiplier = OrificeMultiplier::None;
            if let Some(t) = &oi.area_table {
                let flat: Vec<f64> = t.iter().flatten().copied().collect();
                let good = cx.finite(&e, "area_table", &flat, &what);
                if oi.kind == OrificeType::Laminar || oi.area.is_some() {
                    cx.error(format!("{what}: `area_table` replaces `area` of a turbulent orifice or check valve"), cx.key(&e, "area_table"), Some("give either `area` or `area_table`".into()));
                    ok = false;
                } else if hi.actuator.is_none() {
                    cx.error(format!("{what}: `area_table` is against the actuator's stroke, and the circuit has no actuator"), cx.key(&e, "area_table"), Some("add [hydraulics.actuator]".into()));
                    ok = false;
                } else if !good
                    || t.len() < 2
                    || t.windows(2).any(|w| w[1][0] <= w[0][0])
                    || t.iter().any(|r| r[1] < 0.0)
                {
                    cx.error(format!("{what}: `area_table` needs at least two rows [stroke, area] with strictly increasing stroke and areas ≥ 0"), cx.key(&e, "area_table"), Some("stroke = l − l₀ [m] (negative in compression), area [m²]".into()));
                    ok = false;
                } else {
                    multiplier = OrificeMultiplier::StrokeTable(t.clone());
                }
            }
            if let Some(sig) = &oi.opening {
                if !multiplier_is_none(&multiplier) {
                    cx.error(
                        format!("{what}: `opening` and `area_table` together"),
                        sig.span.clone(),
                        Some("one multiplier per orifice".into()),
                    );
                    ok = false;
                } else if !cx.signal_names.contains_key(&sig.value) {
                    let known: Vec<String> = cx.signal_names.keys().cloned().collect();
                    let hint = match cx.suggest(&sig.value, known.iter().map(|s| s.as_str())) {
                        Some(b) => format!("did you mean '{b}'?"),
                        None => {
                            "the opening is a signal: from [[signals]], a sensor or a controller"
                                .into()
                        }
                    };
                    cx.error(
                        format!("{what}: unknown signal '{}'", sig.value),
                        sig.span.clone(),
                        Some(hint),
                    );
                    ok = false;
                } else {
                    let k = inputs
                        .iter()
                        .position(|n| n == &sig.value)
                        .unwrap_or_else(|| {
                            inputs.push(sig.value.clone());
                            inputs.len() - 1
                        });
                    multiplier = OrificeMultiplier::Opening(k);
                }
            }
            let has_table = oi.area_table.is_some();
            let turbulent = |cx: &mut Checker| -> Option<(f64, f64)> {
                let area = if has_table {
                    Some(1.0)
                } else {
                    given(cx, &e, &what, "area", oi.area, "the orifice area A [m²]")
                };
                let cd = oi.discharge_coefficient.unwrap_or(0.7);
                let cd_ok = positive(
                    cx,
                    &e,
                    &what,
                    "discharge_coefficient",
                    cd,
                    "C_d, typically 0.6–0.8",
                );
                let t = oi.transition_pressure.unwrap_or(1e4);
                let t_ok = positive(
                    cx,
                    &e,
                    &what,
                    "transition_pressure",
                    t,
                    "Δp_t [Pa]: the square-root law is regularized below it",
                );
                let rho = match hi.density {
                    Some(r) => positive(
                        cx,
                        &Entry {
                            span: s.span.clone(),
                        },
                        &circuit,
                        "density",
                        r,
                        "ρ [kg/m³] of the fluid",
                    )
                    .then_some(r),
                    None => {
                        cx.error(
                            format!("{what}: a turbulent orifice needs the circuit's `density`"),
                            s.span.clone(),
                            Some("give `density` = ρ [kg/m³] in the [[hydraulics]] entry".into()),
                        );
                        None
                    }
                };
                let (area, rho) = (area?, rho?);
                (cd_ok && t_ok).then(|| (cd * area * (2.0 / rho).sqrt(), t))
            };
            let law = match oi.kind {
                OrificeType::Laminar => {
                    for (key, present) in [
                        ("area", oi.area.is_some()),
                        ("discharge_coefficient", oi.discharge_coefficient.is_some()),
                        ("transition_pressure", oi.transition_pressure.is_some()),
                        ("cracking_pressure", oi.cracking_pressure.is_some()),
                        ("opening_pressure", oi.opening_pressure.is_some()),
                    ] {
                        ok &= not_here(
                            cx,
                            &e,
                            &what,
                            key,
                            present,
                            "a laminar orifice takes `conductance` G [m³/(s Pa)]",
                        );
                    }
                    given(
                        cx,
                        &e,
                        &what,
                        "conductance",
                        oi.conductance,
                        "G [m³/(s Pa)] of Q = G Δp",
                    )
                    .map(|g| OrificeLaw::Laminar { conductance: g })
                }
                OrificeType::Turbulent => {
                    for (key, present) in [
                        ("conductance", oi.conductance.is_some()),
                        ("cracking_pressure", oi.cracking_pressure.is_some()),
                        ("opening_pressure", oi.opening_pressure.is_some()),
                    ] {
                        ok &= not_here(
                            cx,
                            &e,
                            &what,
                            key,
                            present,
                            "a turbulent orifice takes `area`, `discharge_coefficient` and `transition_pressure`",
                        );
                    }
                    turbulent(cx).map(|(k, t)| OrificeLaw::Turbulent {
                        coefficient: k,
                        transition: t,
                    })
                }
                OrificeType::CheckValve => {
                    ok &= not_here(
                        cx,
                        &e,
                        &what,
                        "conductance",
                        oi.conductance.is_some(),
                        "a check valve is a turbulent orifice with an opening",
                    );
                    let crack = oi.cracking_pressure.unwrap_or(0.0);
                    if !(crack.is_finite() && crack >= 0.0) {
                        cx.error(format!("{what}: `cracking_pressure` must be non-negative (got {crack})"), cx.key(&e, "cracking_pressure"), Some("p_c [Pa], the pressure difference at which the valve starts to open".into()));
                        ok = false;
                    }
                    let open = given(
                        cx,
                        &e,
                        &what,
                        "opening_pressure",
                        oi.opening_pressure,
                        "Δp_o [Pa] over which the valve opens fully",
                    );
                    match (turbulent(cx), open) {
                        (Some((k, t)), Some(o)) => Some(OrificeLaw::CheckValve {
                            coefficient: k,
                            transition: t,
                            cracking: crack,
                            opening: o,
                        }),
                        _ => None,
                    }
                }
            };
            match (from, to, law) {
                (Some(from), Some(to), Some(law)) => orifices.push(HydraulicOrifice {
                    name: oi.name.value.clone(),
                    from,
                    to,
                    law,
                    multiplier,
                }),
                _ => ok = false,
            }
        }
        let actuator = match &hi.actuator {
            None => None,
            Some(a) => {
                let e = Entry {
                    span: a.span.clone(),
                };
                let ai = &a.value;
                let what = format!("{circuit}, actuator");
                let ends = line_ends(
                    cx,
                    &e,
                    &what,
                    [&ai.node_a, &ai.node_b],
                    [ai.point_a, ai.point_b],
                    model,
                );
                let chamber = |cx: &mut Checker,
                               name: &Option<Located<String>>,
                               area: Option<f64>,
                               key: &str,
                               akey: &str|
                 -> Option<Option<(usize, f64)>> {
                    match (name, area) {
                        (None, None) => Some(None),
                        (Some(n), area) => {
                            let p = port(cx, n, &what)?;
                            let Port::Volume(i) = p else {
                                cx.error(format!("{what}: `{key}` must be a volume, '{}' is a reservoir", n.value), n.span.clone(), Some("a chamber's pressure is a state: name one of the circuit's volumes".into()));
                                return None;
                            };
                            let area = given(cx, &e, &what, akey, area, "piston area [m²]")?;
                            Some(Some((i, area)))
                        }
                        (None, Some(_)) => {
                            cx.error(
                                format!("{what}: `{akey}` without `{key}`"),
                                cx.key(&e, akey),
                                Some(format!("name the chamber's volume with `{key}`")),
                            );
                            None
                        }
                    }
                };
                let cap = chamber(cx, &ai.cap, ai.cap_area, "cap", "cap_area");
                let rod = chamber(cx, &ai.rod, ai.rod_area, "rod", "rod_area");
                let (cap, rod) = (cap?, rod?);
                let mut extra = Vec::new();
                for c in &ai.chambers {
                    let p = port(cx, &c.value.volume, &what)?;
                    let Port::Volume(i) = p else {
                        cx.error(
                            format!("{what}: chamber '{}' is a reservoir", c.value.volume.value),
                            c.value.volume.span.clone(),
                            Some("a chamber is one of the circuit's volumes".into()),
                        );
                        return None;
                    };
                    if !(c.value.area.is_finite() && c.value.area != 0.0) {
                        cx.error(
                            format!(
                                "{what}: chamber '{}' needs a non-zero finite `area`",
                                c.value.volume.value
                            ),
                            c.span.clone(),
                            Some("signed area [m²]: + extends, − retracts".into()),
                        );
                        return None;
                    }
                    extra.push((i, c.value.area));
                }
                if cap.is_none() && rod.is_none() && extra.is_empty() {
                    cx.error(
                        format!("{what} has no chamber"),
                        e.span.clone(),
                        Some("give `cap` and `cap_area`, or `rod` and `rod_area`, or both".into()),
                    );
                    return None;
                }
                if let (Some((c, _)), Some((r, _))) = (cap, rod)
                    && c == r
                {
                    cx.error(
                        format!("{what}: the cap and rod chambers are the same volume"),
                        ai.rod.as_ref().and_then(|r| r.span.clone()),
                        Some("the two sides of the piston are two volumes".into()),
                    );
                    return None;
                }
                let (na, nb, pa, pb) = ends?;
                if (pb - pa).norm() < 1e-9 {
                    cx.error(
                        format!("{what}: its two points coincide"),
                        e.span.clone(),
                        Some(
                            "the actuator acts along the line between `point_a` and `point_b`"
                                .into(),
                        ),
                    );
                    return None;
                }
                let mut chambers: Vec<(usize, f64)> = cap.into_iter().collect();
                chambers.extend(rod.map(|(i, a)| (i, -a)));
                chambers.extend(extra);
                Some(ActuatorDef {
                    node_a: na,
                    node_b: nb,
                    point_a: pa,
                    point_b: pb,
                    chambers,
                })
            }
        };
        if hi.actuator.is_some() && actuator.is_none() {
            ok = false;
        }
        ok.then(|| HydraulicDef {
            name: hi.name.value.clone(),
            volumes,
            orifices,
            actuator,
            inputs,
        })
    }

    fn nodes(def: &HydraulicDef) -> Vec<usize> {
        def.actuator.as_ref().map_or(Vec::new(), |a| {
            [a.node_a, a.node_b]
                .iter()
                .filter_map(|r| r.index())
                .collect()
        })
    }

    fn build(def: &HydraulicDef, parts: &mut Build) {
        let actuator = def.actuator.as_ref().map(|a| {
            hydraulic_actuator(
                parts.local_offset(a.node_a, a.point_a),
                parts.local_offset(a.node_b, a.point_b),
                [a.point_a, a.point_b],
                (a.point_b - a.point_a).norm(),
                a.chambers.clone(),
            )
        });
        parts.elements.push(Box::new(HydraulicCircuit::new(
            &def.name,
            def.volumes.clone(),
            def.orifices.clone(),
            actuator,
            def.inputs.clone(),
        )));
    }

    fn tangent_cases() -> Vec<TangentCase> {
        let vol = |n: &str, v: f64| HydraulicVolume {
            name: n.into(),
            volume: v,
            bulk_modulus: 1e9,
            initial_pressure: 0.0,
            gas: None,
        };
        // Scaled units keep every block of order one: pressures in MPa-like numbers.
        let orifices = vec![
            HydraulicOrifice {
                name: "in".into(),
                from: Port::Reservoir(3.0),
                to: Port::Volume(0),
                law: OrificeLaw::Turbulent {
                    coefficient: 0.2,
                    transition: 0.1,
                },
                multiplier: OrificeMultiplier::Opening(0),
            },
            HydraulicOrifice {
                name: "x".into(),
                from: Port::Volume(0),
                to: Port::Volume(1),
                law: OrificeLaw::CheckValve {
                    coefficient: 0.3,
                    transition: 0.2,
                    cracking: 0.1,
                    opening: 2.0,
                },
                multiplier: OrificeMultiplier::StrokeTable(vec![
                    [-1.0, 0.5],
                    [0.0, 1.0],
                    [2.0, 3.0],
                ]),
            },
            HydraulicOrifice {
                name: "leak".into(),
                from: Port::Volume(1),
                to: Port::Reservoir(0.0),
                law: OrificeLaw::Laminar { conductance: 0.05 },
                multiplier: OrificeMultiplier::None,
            },
            HydraulicOrifice {
                name: "out".into(),
                from: Port::Volume(2),
                to: Port::Reservoir(0.5),
                law: OrificeLaw::Turbulent {
                    coefficient: 0.1,
                    transition: 0.3,
                },
                multiplier: OrificeMultiplier::None,
            },
        ];
        let mut out = Vec::new();
        for k in 0..3u64 {
            let a = (k != 2).then_some((0, Vector3::new(0.1, -0.2, 0.05)));
            let act = hydraulic_actuator(
                a,
                Some((1, Vector3::new(-0.1, 0.3, 0.2))),
                [Vector3::new(0.4, 0.2, -0.3), Vector3::zeros()],
                0.7,
                [
                    Some((1, 0.8)),
                    (k != 1).then_some((2, -0.5)),
                    (k == 0).then_some((0, 0.3)),
                ]
                .into_iter()
                .flatten()
                .collect(),
            );
            let mut volumes = vec![vol("a", 2e9), vol("cap", 1.5e9), vol("rod", 1e9)];
            // A bladder accumulator above its precharge and a free gas chamber.
            volumes[0].gas = Some(GasCharge {
                volume: 0.7,
                precharge: 0.6,
                exponent: 1.3,
                bladder: true,
            });
            volumes[1].gas = Some(GasCharge {
                volume: 0.4,
                precharge: 2.0,
                exponent: 1.0,
                bladder: false,
            });
            let e = HydraulicCircuit::new(
                "h",
                volumes,
                orifices.clone(),
                Some(act),
                vec!["valve".into()],
            );
            let nodes = vec![random_node(940 + k), random_node(945 + k)];
            out.push(
                TangentCase::element(Box::new(e), nodes)
                    .with_states(vec![(1.0, 0.3), (1.7, -0.4), (0.9, 0.8)])
                    .with_signals(vec![0.4]),
            );
        }
        // Without an actuator (no nodes).
        let orifices: Vec<HydraulicOrifice> = orifices
            .into_iter()
            .map(|mut o| {
                if matches!(o.multiplier, OrificeMultiplier::StrokeTable(_)) {
                    o.multiplier = OrificeMultiplier::None;
                }
                o
            })
            .collect();
        let e = HydraulicCircuit::new(
            "h",
            vec![vol("a", 2e9), vol("cap", 1.5e9), vol("rod", 1e9)],
            orifices,
            None,
            vec!["valve".into()],
        );
        out.push(
            TangentCase::element(Box::new(e), Vec::new())
                .with_states(vec![(1.0, 0.3), (2.2, -0.4), (0.3, 0.8)])
                .with_signals(vec![0.7]),
        );
        out
    }
}
