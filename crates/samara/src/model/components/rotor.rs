//! `[[rotors]]`: a rotor disc with Pitt–Peters dynamic inflow (kernel:
//! [`crate::elements::aero::dynamic_inflow`]; docs/aerodynamics.md, "Dynamic inflow").
//! The lifting lines of the rotor name it with `inflow = { type = "pitt_peters", rotor =
//! "<name>" }`; the rotor's element owns the three inflow states, reads every station's
//! thrust and produces the signals `<name>.v0`, `<name>.vs`, `<name>.vc` (m/s).
//!
//! Lines of any other inflow (BEM) join a rotor with `rotor = "<name>"`; a rotor with a
//! `hub` node writes the rotor-level outputs of element `<name>.performance` (thrust,
//! torque, power, C_T, C_P, tip-speed ratio: [`crate::elements::aero::rotor_performance`]).

use super::aero::{AeroLineDef, line_stations};
use super::{Build, ComponentKind};
use crate::core::NodeRef;
use crate::elements::aero::dynamic_inflow::{PittPeters, RotorDisc, inflow_signals};
use crate::elements::aero::{Inflow, RotorGeometry, RotorPerformance, Wind};
use crate::model::validate::{Checker, Entry};
use crate::model::{Located, Model};
use crate::tangent_check::TangentCase;
use nalgebra::Vector3;
use schemars::JsonSchema;
use serde::Deserialize;
use std::sync::Arc;

/// A rotor disc with Pitt–Peters inflow states.
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RotorInput {
    /// Unique rotor name (its element and the prefix of its signals).
    pub name: Located<String>,
    /// Centre of the disc, global [m] (fixed).
    pub centre: [f64; 3],
    /// Disc axis n, global: the direction the induced flow goes through the disc,
    /// opposite to the thrust (−z for a rotor lifting along +z).
    pub axis: [f64; 3],
    /// Azimuth reference ψ = 0 (made normal to the axis), global; default: a direction
    /// normal to the axis. v_c multiplies (r/R) cos ψ, v_s (r/R) sin ψ, ψ turning from
    /// it toward axis × reference.
    #[serde(default)]
    pub azimuth_reference: Option<[f64; 3]>,
    /// Tip radius R [m], > 0.
    pub radius: f64,
    /// The node whose angular velocity about the axis is the rotor speed: with it, the
    /// rotor writes thrust, torque, power, C_T, C_P and the tip-speed ratio (element
    /// `<name>.performance`).
    #[serde(default)]
    pub hub: Option<Located<String>>,
}

/// A validated rotor.
#[derive(Clone, Debug)]
pub struct RotorDef {
    pub name: String,
    pub disc: RotorDisc,
    pub density: f64,
    pub wind: Wind,
    /// Element names of its Pitt–Peters stations (empty: no inflow states).
    pub stations: Vec<String>,
    /// Its hub node (rotor outputs).
    pub hub: Option<usize>,
    /// Every line of the rotor (Pitt–Peters or naming it), as validated.
    pub lines: Vec<AeroLineDef>,
}

pub struct RotorKind;

/// Whether a line's inflow is the Pitt–Peters inflow of `rotor`.
fn uses(l: &AeroLineDef, rotor: &str) -> bool {
    matches!(&l.inflow, Inflow::PittPeters { rotor: r, .. } if r == rotor)
}

/// Whether a line belongs to `rotor` (its Pitt–Peters inflow or its `rotor` key).
fn member(l: &AeroLineDef, rotor: &str) -> bool {
    uses(l, rotor) || l.rotor.as_ref().is_some_and(|(r, _)| r == rotor)
}

impl ComponentKind for RotorKind {
    const NOUN: &'static str = "rotor";
    type Input = RotorInput;
    type Def = RotorDef;

    fn name(input: &RotorInput) -> &Located<String> {
        &input.name
    }

    fn signals(input: &RotorInput) -> Vec<String> {
        inflow_signals(&input.name.value).to_vec()
    }

    fn validate(r: &Located<RotorInput>, cx: &mut Checker, model: &mut Model) -> Option<RotorDef> {
        let e = Entry {
            span: r.span.clone(),
        };
        let ri = &r.value;
        let name = &ri.name.value;
        let what = format!("rotor '{name}'");
        let mut ok = cx.finite(&e, "centre", &ri.centre, &what);
        ok &= cx.finite(&e, "axis", &ri.axis, &what);
        let axis = Vector3::from(ri.axis);
        if ok && axis.norm() == 0.0 {
            cx.error(
                format!("{what}: `axis` must be non-zero"),
                cx.key(&e, "axis"),
                Some("the direction of the induced flow through the disc".into()),
            );
            ok = false;
        }
        if !(ri.radius.is_finite() && ri.radius > 0.0) {
            cx.error(
                format!("{what}: `radius` must be > 0 (got {})", ri.radius),
                cx.key(&e, "radius"),
                Some("the tip radius R of the disc [m]".into()),
            );
            ok = false;
        }
        let n = if axis.norm() > 0.0 {
            axis.normalize()
        } else {
            Vector3::z()
        };
        let reference = match ri.azimuth_reference {
            Some(a) => {
                ok &= cx.finite(&e, "azimuth_reference", &a, &what);
                let a = Vector3::from(a);
                let p = a - n * n.dot(&a);
                if p.norm() <= 1e-9 * a.norm().max(1e-300) {
                    cx.error(
                        format!("{what}: `azimuth_reference` must not be parallel to the axis"),
                        cx.key(&e, "azimuth_reference"),
                        Some("a direction in the disc plane (ψ = 0)".into()),
                    );
                    ok = false;
                    n.cross(&Vector3::x())
                } else {
                    p
                }
            }
            None => {
                let t = if n.x.abs() < 0.9 {
                    Vector3::x()
                } else {
                    Vector3::y()
                };
                t - n * n.dot(&t)
            }
        }
        .normalize();
        let lines: Vec<usize> = (0..model.aero_lines.len())
            .filter(|&k| member(&model.aero_lines[k], name))
            .collect();
        let Some(&first) = lines.first() else {
            cx.error(
                format!("{what}: no lifting line uses it"),
                ri.name.span.clone(),
                Some(format!(
                    "give its blades' `[[aero_lines]]` `inflow = {{ type = \"pitt_peters\", rotor = \"{name}\" }}` or `rotor = \"{name}\"`"
                )),
            );
            return None;
        };
        let pitt_peters = lines.iter().any(|&k| uses(&model.aero_lines[k], name));
        let hub = match &ri.hub {
            None => None,
            Some(h) => match cx.node_ref(h, &what) {
                Some(NodeRef::Node(i)) => Some(i),
                Some(NodeRef::Ground) => {
                    cx.error(
                        format!("{what}: the hub cannot be the ground"),
                        h.span.clone(),
                        Some("name the node the blades turn with".into()),
                    );
                    ok = false;
                    None
                }
                None => {
                    ok = false;
                    None
                }
            },
        };
        if !pitt_peters && ri.hub.is_none() {
            cx.error(
                format!("{what}: a rotor without Pitt–Peters lines only writes rotor outputs, which need `hub`"),
                ri.name.span.clone(),
                Some("add `hub = \"<node>\"`: the node whose angular velocity about the axis is the rotor speed".into()),
            );
            ok = false;
        }
        let density = model.aero_lines[first].density;
        let wind = model.aero_lines[first].wind.clone();
        for &k in &lines[1..] {
            let l = &model.aero_lines[k];
            if l.density != density || format!("{:?}", l.wind) != format!("{wind:?}") {
                cx.error(
                    format!(
                        "{what}: its lines '{}' and '{}' differ in air density or wind",
                        model.aero_lines[first].name, l.name
                    ),
                    ri.name.span.clone(),
                    Some("the lines of one rotor see the same air: give them the same `air_density` and `wind`".into()),
                );
                ok = false;
            }
        }
        if !ok {
            return None;
        }
        let disc = RotorDisc {
            centre: Vector3::from(ri.centre),
            axis: n,
            azimuth_reference: reference,
            radius: ri.radius,
        };
        let mut stations = Vec::new();
        for &k in &lines {
            let l = &mut model.aero_lines[k];
            if !uses(l, name) {
                continue;
            }
            l.inflow = Inflow::PittPeters {
                rotor: name.clone(),
                disc: disc.clone(),
            };
            stations.extend((0..l.stations.len()).map(|s| format!("{}.{s}", l.name)));
        }
        Some(RotorDef {
            name: name.clone(),
            disc,
            density,
            wind,
            stations,
            hub,
            lines: lines.iter().map(|&k| model.aero_lines[k].clone()).collect(),
        })
    }

    fn nodes(_def: &RotorDef) -> Vec<usize> {
        Vec::new()
    }

    fn build(def: &RotorDef, parts: &mut Build) {
        let wind = Arc::new(def.wind.clone());
        if !def.stations.is_empty() {
            parts.elements.push(Box::new(PittPeters::new(
                def.name.clone(),
                def.disc.clone(),
                def.density,
                wind.clone(),
                &def.stations,
            )));
        }
        if let Some(hub) = def.hub {
            let stations = def
                .lines
                .iter()
                .flat_map(|l| line_stations(l, parts))
                .collect();
            let geometry = RotorGeometry {
                centre: def.disc.centre,
                axis: def.disc.axis,
                radius: def.disc.radius,
                density: def.density,
            };
            parts.elements.push(Box::new(RotorPerformance::new(
                format!("{}.performance", def.name),
                geometry,
                wind,
                hub,
                stations,
            )));
        }
    }

    fn tangent_cases() -> Vec<TangentCase> {
        let disc = RotorDisc {
            centre: Vector3::new(0.1, -0.2, 3.0),
            axis: Vector3::new(0.1, 0.0, -1.0).normalize(),
            azimuth_reference: Vector3::new(1.0, 0.0, 0.1).normalize(),
            radius: 5.0,
        };
        let stations: Vec<String> = (0..4).map(|k| format!("blade.{k}")).collect();
        let signals: Vec<f64> = (0..12)
            .map(|k| 800.0 + 150.0 * (k as f64).sin() + if k % 3 == 0 { 2000.0 } else { 0.0 })
            .collect();
        let mut cases = Vec::new();
        // Hover (no free stream), axial climb, and edgewise flight (wake skew) in a wind
        // oblique to the azimuth reference.
        for (k, wind) in [
            Vector3::zeros(),
            Vector3::new(0.0, 0.0, -4.0),
            Vector3::new(12.0, 5.0, -2.0),
        ]
        .into_iter()
        .enumerate()
        {
            let w = Wind {
                speed: wind.norm(),
                direction: if wind.norm() > 0.0 {
                    wind.normalize()
                } else {
                    Vector3::x()
                },
                ..Default::default()
            };
            let e = PittPeters::new("rotor", disc.clone(), 1.2, Arc::new(w), &stations);
            let states = vec![(6.0 + k as f64, 0.3), (0.7, -0.1), (-0.4, 0.2)];
            cases.push(
                TangentCase::element(Box::new(e), Vec::new())
                    .with_states(states)
                    .with_signals(signals.clone()),
            );
        }
        cases
    }
}
