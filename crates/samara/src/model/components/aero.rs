//! `[[aero_lines]]`: a lifting line on a beam or a node (a rigid body), one
//! [`AeroStation`] element per station (kernel: [`crate::elements::aero`];
//! docs/aerodynamics.md). Stations, chords, twists and airfoils are given in the model or
//! read from an OpenFAST AeroDyn v15 primary file (its `ADBlFile(1)` blade table and
//! `AFNames` airfoil files, paths relative to that file).

use super::{Build, ComponentKind};
use crate::core::NodeRef;
use crate::elements::aero::RotorDisc;
use crate::elements::aero::station::{Unsteady, UserProperty};
use crate::elements::aero::{
    AeroStation, Airfoil, AttachedFlow, Attachment, BemRotor, FullField, Gust, Hgm,
    HgmCoefficients, Inflow, MAX_NODES, OyeStall, Section, Wind,
};
use crate::math::TimeFunction;
use crate::model::input::TimeFunctionInput;
use crate::model::validate::{Checker, Entry};
use crate::model::{Located, Model};
use crate::tangent_check::{TangentCase, random_node};
use nalgebra::{Matrix3, Vector3};
use schemars::JsonSchema;
use serde::Deserialize;
use std::collections::HashMap;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// One station of a lifting line.
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct StationInput {
    /// Distance from the line's root along it [m] (along the beam's reference line, or
    /// root → tip for a node).
    pub span: f64,
    /// Chord c [m], > 0.
    pub chord: f64,
    /// Aerodynamic twist [rad], positive toward feather (turns the chord toward the
    /// suction-side normal, lowering α).
    #[serde(default)]
    pub twist: f64,
    /// Airfoil table: a `.csv` file (alpha,cl,cd,cm) or an AeroDyn airfoil file, relative
    /// to the model file.
    pub airfoil: String,
    /// Distance of the aerodynamic centre from the line, along the chord toward the
    /// trailing edge [m].
    #[serde(default)]
    pub ac_offset: f64,
}

/// The wind of a line.
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct WindInput {
    /// Speed at the reference height [m/s]; required unless `turbsim` is given.
    #[serde(default)]
    pub speed: Option<f64>,
    /// A TurbSim binary full-field file (`.bts`, relative to the model file): a turbulent
    /// box advancing along `direction` (horizontal) at the file's mean hub speed, its grid
    /// centred on y = 0 of the wind frame (origin at the tower base on the ground);
    /// replaces `speed`, `shear_exponent`, `reference_height` and `function`.
    #[serde(default)]
    pub turbsim: Option<Located<String>>,
    /// Direction the air moves to, global (normalized); default +x.
    #[serde(default)]
    pub direction: Option<[f64; 3]>,
    /// Power-law shear exponent; default 0 (uniform).
    #[serde(default)]
    pub shear_exponent: Option<f64>,
    /// Reference height of the shear law [m]; required with a shear exponent.
    #[serde(default)]
    pub reference_height: Option<f64>,
    /// Vertical direction, global; default +z (heights from z = 0).
    #[serde(default)]
    pub vertical: Option<[f64; 3]>,
    /// Time function multiplying the speed (a gust); default 1.
    #[serde(default)]
    pub function: Option<Located<TimeFunctionInput>>,
    /// A gust added to the wind, `{ velocity, function, convection_speed }`: velocity g
    /// [m/s, global] times the time function f_g, uniform (f_g(t)) or convected along
    /// `direction` (f_g(t − x/U_c)); with a `turbsim` box, added to it (part of the
    /// disturbance that Küssner's gust response reads).
    #[serde(default)]
    pub gust: Option<Located<GustInput>>,
}

/// A gust of a line's wind.
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct GustInput {
    /// Gust velocity g, global [m/s].
    pub velocity: [f64; 3],
    /// Time function f_g multiplying it.
    pub function: Located<TimeFunctionInput>,
    /// Convection speed U_c [m/s] (> 0): the gust is a frozen pattern advancing along the
    /// wind's `direction`, g f_g(t − x/U_c) at x = p·ŵ (its front crosses the plane
    /// x = 0 at the function's times); usually the wind's speed. Omitted: uniform in
    /// space, g f_g(t).
    #[serde(default)]
    pub convection_speed: Option<f64>,
}

/// How an unsteady airfoil responds to the wind's gust.
#[derive(Clone, Copy, Debug, Deserialize, JsonSchema, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum GustResponseInput {
    /// Through Wagner's function, like the motion (default).
    Wagner,
    /// Through Küssner's function (Sears & Sparks' exponentials), two states per station.
    Kussner,
}

/// The induced-velocity model of a line.
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum InflowInput {
    /// No induced velocity.
    None,
    /// A given induced velocity, global [m/s].
    Uniform { velocity: [f64; 3] },
    /// Quasi-steady blade-element momentum theory of a rotor.
    Bem {
        /// Rotor centre, global [m] (fixed).
        centre: [f64; 3],
        /// Rotor axis, global, pointing downstream (the wind's way through the rotor).
        axis: [f64; 3],
        /// Number of blades.
        blades: usize,
        /// Hub and tip radius [m].
        hub_radius: f64,
        tip_radius: f64,
        /// Prandtl tip loss; default true.
        #[serde(default)]
        tip_loss: Option<bool>,
        /// Prandtl hub loss; default true.
        #[serde(default)]
        hub_loss: Option<bool>,
        /// Tangential induction a'; default true.
        #[serde(default)]
        tangential_induction: Option<bool>,
        /// Skewed-wake correction of the axial induction in yawed flow; default false.
        #[serde(default)]
        skewed_wake: Option<bool>,
        /// Dynamic wake on the axial induction: `"none"` (default, quasi-steady) or
        /// `"oye"` (Øye's two first-order filters, two states per station).
        #[serde(default)]
        dynamic_wake: Option<DynamicWakeInput>,
    },
    /// Pitt–Peters dynamic inflow of a `[[rotors]]` entry (its three inflow states,
    /// shared by every line naming it).
    PittPeters {
        /// Name of the `[[rotors]]` entry.
        rotor: String,
    },
}

/// The dynamic-wake model of a BEM line.
#[derive(Clone, Copy, Debug, Deserialize, JsonSchema, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum DynamicWakeInput {
    /// Quasi-steady induction (default).
    None,
    /// Øye's dynamic wake: τ₁ = 1.1/(1 − 1.3a) R/V₀, τ₂ = (0.39 − 0.26 (r/R)²) τ₁.
    Oye,
}

/// The attached-flow model of a line.
#[derive(Clone, Copy, Debug, Deserialize, JsonSchema, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum UnsteadyInput {
    /// Quasi-steady (default).
    QuasiSteady,
    /// Wagner's indicial response (R. T. Jones' two exponentials), two states per station.
    Wagner,
}

/// The dynamic-stall model of a line.
#[derive(Clone, Copy, Debug, Deserialize, JsonSchema, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum DynamicStallInput {
    /// None (default).
    None,
    /// Øye's separation lag, one state per station.
    Oye,
    /// Beddoes–Leishman type, Hansen–Gaunaa–Madsen's four states (OpenFAST UAMod 4).
    #[serde(alias = "beddoes_leishman")]
    Hgm,
}

/// A lifting line on a beam or a node.
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct AeroLineInput {
    /// Unique line name; its stations are elements `<name>.<k>`.
    pub name: Located<String>,
    /// The beam carrying the line (stations along its reference line, from its root).
    #[serde(default)]
    pub beam: Option<Located<String>>,
    /// Or the node carrying the line (a rigid body), with `root` and `tip`.
    #[serde(default)]
    pub node: Option<Located<String>>,
    /// Root and tip of a line on a node, global in the initial configuration [m].
    #[serde(default)]
    pub root: Option<[f64; 3]>,
    #[serde(default)]
    pub tip: Option<[f64; 3]>,
    /// Chord direction (leading → trailing edge) at zero twist, global, initial
    /// configuration (made normal to the line).
    pub chord_direction: [f64; 3],
    /// Normal toward the suction side (where lift points at positive α) at zero twist.
    pub normal_direction: [f64; 3],
    /// Pitch added to every station's twist [rad]; default 0.
    #[serde(default)]
    pub pitch: Option<f64>,
    /// Air density ρ [kg/m³]; default 1.225.
    #[serde(default)]
    pub air_density: Option<f64>,
    /// Stations (or `aerodyn`).
    #[serde(default)]
    pub stations: Vec<Located<StationInput>>,
    /// An AeroDyn v15 primary file (relative to the model): stations from its blade
    /// file `ADBlFile(1)` (BlSpn, BlTwist [deg], BlChord, BlAFID) and airfoils `AFNames`.
    #[serde(default)]
    pub aerodyn: Option<Located<String>>,
    /// The wind; default still air.
    #[serde(default)]
    pub wind: Option<Located<WindInput>>,
    /// Induced velocity; default none.
    #[serde(default)]
    pub inflow: Option<Located<InflowInput>>,
    /// The `[[rotors]]` entry whose outputs (thrust, torque, power, C_T, C_P, λ) count
    /// this line's loads (a Pitt–Peters line belongs to its inflow's rotor already).
    #[serde(default)]
    pub rotor: Option<Located<String>>,
    /// Attached-flow unsteady aerodynamics: `"quasi_steady"` (default) or `"wagner"`.
    #[serde(default)]
    pub unsteady: Option<UnsteadyInput>,
    /// Dynamic stall: `"none"` (default), `"oye"` or `"hgm"` (alias `"beddoes_leishman"`).
    #[serde(default)]
    pub dynamic_stall: Option<DynamicStallInput>,
    /// A_τ of Øye's time constant τ = A_τ c/V; default 4.
    #[serde(default)]
    pub stall_time_constant: Option<f64>,
    /// Coefficients of the HGM model that replace, for every station of the line, those of
    /// the airfoil file's unsteady-aerodynamics block (or UnsteadyAero's defaults).
    #[serde(default)]
    pub hgm: Option<Located<HgmInput>>,
    /// Which table of an airfoil with several Reynolds-number tables is read: `"first"`
    /// (default, AeroDyn's AFTabMod = 1) or `"interpolate"` (linear in ln Re at the
    /// station's Re = W c/ν, AFTabMod = 2).
    #[serde(default)]
    pub reynolds: Option<ReynoldsInput>,
    /// Kinematic viscosity ν of the air [m²/s] in Re = W c/ν; default 1.464e-5 (only with
    /// `reynolds = "interpolate"`).
    #[serde(default)]
    pub kinematic_viscosity: Option<f64>,
    /// Interpolate every airfoil's tables linearly in their `UserProp` (AeroDyn's
    /// AFTabMod = 3) at this value: a number, or the name of a signal (a flap command
    /// from a controller, a `[[signals]]` entry, a sensor).
    #[serde(default)]
    pub user_property: Option<Located<UserPropertyInput>>,
    /// The response to the wind's disturbance (its `gust` and a `turbsim` box's
    /// turbulence about its time mean): `"wagner"` (default: like the motion) or
    /// `"kussner"` (Küssner's function, two more states; needs `unsteady = "wagner"`).
    #[serde(default)]
    pub gust_response: Option<GustResponseInput>,
}

/// How the Reynolds-number tables of an airfoil are read.
#[derive(Clone, Copy, Debug, Deserialize, JsonSchema, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum ReynoldsInput {
    /// The first table of every airfoil (default).
    First,
    /// Linear interpolation in ln Re between the tables around the station's Re.
    Interpolate,
}

/// A line's user property: a constant or a signal's name.
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(untagged)]
pub enum UserPropertyInput {
    Value(f64),
    Signal(String),
}

/// The default kinematic viscosity of air [m²/s] (AeroDyn's `KinVisc` of the NREL
/// reference models, air at about 15 °C).
pub const DEFAULT_KINEMATIC_VISCOSITY: f64 = 1.464e-5;

/// HGM (Beddoes–Leishman type) coefficients set in the model; each one optional.
#[derive(Clone, Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct HgmInput {
    /// A₁, A₂ of the circulatory response 1 − A₁e^{−b₁s} − A₂e^{−b₂s}: ≥ 0, A₁ + A₂ ≤ 1.
    #[serde(default)]
    pub a1: Option<f64>,
    #[serde(default)]
    pub a2: Option<f64>,
    /// b₁, b₂ (per semichord of travel): > 0.
    #[serde(default)]
    pub b1: Option<f64>,
    #[serde(default)]
    pub b2: Option<f64>,
    /// T_f0, T_p: separation and pressure time constants in units of T_u = c/2V: > 0.
    #[serde(default)]
    pub t_f0: Option<f64>,
    #[serde(default)]
    pub t_p: Option<f64>,
}

impl HgmInput {
    /// `c` with the coefficients given here put in.
    fn apply(&self, mut c: HgmCoefficients) -> HgmCoefficients {
        let set = |v: &mut f64, x: Option<f64>| {
            if let Some(x) = x {
                *v = x;
            }
        };
        set(&mut c.a[0], self.a1);
        set(&mut c.a[1], self.a2);
        set(&mut c.b[0], self.b1);
        set(&mut c.b[1], self.b2);
        set(&mut c.t_f0, self.t_f0);
        set(&mut c.t_p, self.t_p);
        c
    }
}

/// A validated station.
#[derive(Clone, Debug)]
pub struct StationDef {
    pub span: f64,
    pub chord: f64,
    pub twist: f64,
    pub ac_offset: f64,
    pub airfoil: Arc<Airfoil>,
    /// Øye's separation curves of the airfoil (with `dynamic_stall = "oye"`).
    pub stall: Option<Arc<OyeStall>>,
    /// The Beddoes–Leishman (HGM) model of the airfoil (with `dynamic_stall = "hgm"`).
    pub hgm: Option<Arc<Hgm>>,
}

/// What carries a line.
#[derive(Clone, Debug)]
pub enum Carrier {
    /// A beam: its nodes root → tip, their normalized arc length η, the polyline length
    /// s [m] through them (s ↔ η piecewise linear), and the nodes of each element.
    Beam {
        nodes: Vec<usize>,
        etas: Vec<f64>,
        arc: Vec<f64>,
        order: usize,
    },
    /// A node, with the line from `root` to `tip`.
    Node {
        node: usize,
        root: Vector3<f64>,
        tip: Vector3<f64>,
    },
}

/// A validated lifting line.
#[derive(Clone, Debug)]
pub struct AeroLineDef {
    pub name: String,
    pub carrier: Carrier,
    pub chord_direction: Vector3<f64>,
    pub normal_direction: Vector3<f64>,
    pub pitch: f64,
    pub density: f64,
    pub stations: Vec<StationDef>,
    pub wind: Wind,
    pub inflow: Inflow,
    pub unsteady: AttachedFlow,
    /// A_τ of Øye's dynamic stall, if on.
    pub stall_time_constant: Option<f64>,
    /// Where the `inflow` is given (for errors found once every kind is validated).
    pub inflow_span: Option<std::ops::Range<usize>>,
    /// Øye's dynamic wake on the BEM induction.
    pub dynamic_wake: bool,
    /// Kinematic viscosity ν when the airfoils' tables are interpolated in Re.
    pub viscosity: Option<f64>,
    /// The user property the tables are interpolated in (AFTabMod = 3), if any.
    pub user_property: Option<UserProperty>,
    /// Küssner's gust response (with Wagner's states).
    pub kussner: bool,
    /// The TurbSim file of a turbulent wind and where its key is (the box's coverage of
    /// the stations and the analyses' times are checked once the model is known).
    pub turbsim: Option<(PathBuf, Option<std::ops::Range<usize>>)>,
    /// The rotor the line's loads count in (`rotor` key), and where the key is.
    pub rotor: Option<(String, Option<std::ops::Range<usize>>)>,
}

pub struct AeroLine;

/// Reads an airfoil file (cached per path), located at `span` on failure.
fn load_airfoil(
    cx: &mut Checker,
    cache: &mut HashMap<PathBuf, Arc<Airfoil>>,
    path: &Path,
    span: Option<std::ops::Range<usize>>,
    what: &str,
) -> Option<Arc<Airfoil>> {
    if let Some(a) = cache.get(path) {
        return Some(a.clone());
    }
    let text = match crate::input_files::read_text(path) {
        Ok(t) => t,
        Err(e) => {
            cx.error(
                format!("{what}: cannot read airfoil file '{}': {e}", path.display()),
                span,
                Some("paths are relative to the model file".into()),
            );
            return None;
        }
    };
    let csv = path
        .extension()
        .is_some_and(|x| x.eq_ignore_ascii_case("csv"));
    match Airfoil::parse(&text, csv) {
        Ok(a) => {
            let a = Arc::new(a);
            cache.insert(path.to_path_buf(), a.clone());
            Some(a)
        }
        Err(e) => {
            cx.error(
                format!("{what}: airfoil file '{}', {e}", path.display()),
                span,
                e.hint.clone(),
            );
            None
        }
    }
}

/// First token of a line, unquoted.
fn unquote(s: &str) -> &str {
    s.trim().trim_matches('"')
}

/// Rows (span, chord, twist [rad], airfoil index) and the airfoil files of an AeroDyn
/// blade.
type AeroDynBlade = (Vec<(f64, f64, f64, usize)>, Vec<PathBuf>);

/// Stations from an AeroDyn v15 primary file; errors are `(message, hint)`.
fn read_aerodyn(primary: &Path) -> Result<AeroDynBlade, (String, String)> {
    let err = |p: &Path, m: String| (format!("'{}': {m}", p.display()), String::new());
    let text = crate::input_files::read_text(primary).map_err(|e| err(primary, e.to_string()))?;
    let lines: Vec<&str> = text.lines().collect();
    let key = |k: &str| {
        lines.iter().position(|l| {
            let mut t = l.split_whitespace();
            t.next().is_some() && t.next() == Some(k)
        })
    };
    let base = primary.parent().unwrap_or(Path::new("."));
    let nline = key("NumAFfiles").ok_or_else(|| {
        err(
            primary,
            "no `NumAFfiles` line: not an AeroDyn v15 primary file".into(),
        )
    })?;
    let n: usize = lines[nline]
        .split_whitespace()
        .next()
        .and_then(|v| v.parse().ok())
        .filter(|&n| (1..=1000).contains(&n))
        .ok_or_else(|| {
            err(
                primary,
                format!("line {}: NumAFfiles must be 1…1000", nline + 1),
            )
        })?;
    let first = key("AFNames").ok_or_else(|| err(primary, "no `AFNames` line".into()))?;
    let mut airfoils = Vec::with_capacity(n);
    for k in 0..n {
        let l = lines.get(first + k).ok_or_else(|| {
            err(
                primary,
                format!("AFNames lists fewer than NumAFfiles = {n} files"),
            )
        })?;
        let name = unquote(l.split_whitespace().next().unwrap_or(""));
        airfoils.push(base.join(name));
    }
    let bl = key("ADBlFile(1)").ok_or_else(|| err(primary, "no `ADBlFile(1)` line".into()))?;
    let blade = base.join(unquote(lines[bl].split_whitespace().next().unwrap_or("")));
    let btext = crate::input_files::read_text(&blade).map_err(|e| err(&blade, e.to_string()))?;
    let blines: Vec<&str> = btext.lines().collect();
    let nl = blines
        .iter()
        .position(|l| l.split_whitespace().nth(1) == Some("NumBlNds"))
        .ok_or_else(|| {
            err(
                &blade,
                "no `NumBlNds` line: not an AeroDyn v15 blade file".into(),
            )
        })?;
    let nodes: usize = blines[nl]
        .split_whitespace()
        .next()
        .and_then(|v| v.parse().ok())
        .filter(|&n| (2..=10000).contains(&n))
        .ok_or_else(|| err(&blade, format!("line {}: NumBlNds must be 2…10000", nl + 1)))?;
    let mut rows = Vec::with_capacity(nodes);
    // Two header lines (names, units), then the rows.
    for (k, l) in blines.iter().enumerate().skip(nl + 3) {
        if rows.len() == nodes {
            break;
        }
        let v: Vec<f64> = l
            .split_whitespace()
            .map(|t| t.parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| err(&blade, format!("line {}: expected 7 numbers", k + 1)))?;
        if v.len() < 7 || v.iter().any(|x| !x.is_finite()) {
            return Err(err(&blade, format!("line {}: expected 7 numbers", k + 1)));
        }
        let id = v[6];
        if !(id >= 1.0 && id <= n as f64 && id.fract() == 0.0) {
            return Err(err(
                &blade,
                format!("line {}: BlAFID {id} is not an airfoil 1…{n}", k + 1),
            ));
        }
        rows.push((v[0], v[5], v[4].to_radians(), id as usize - 1));
    }
    if rows.len() < nodes {
        return Err(err(
            &blade,
            format!("NumBlNds = {nodes} but {} rows follow", rows.len()),
        ));
    }
    Ok((rows, airfoils))
}

impl ComponentKind for AeroLine {
    const NOUN: &'static str = "aerodynamic line";
    type Input = AeroLineInput;
    type Def = AeroLineDef;

    fn name(input: &AeroLineInput) -> &Located<String> {
        &input.name
    }

    fn validate(
        l: &Located<AeroLineInput>,
        cx: &mut Checker,
        model: &mut Model,
    ) -> Option<AeroLineDef> {
        let e = Entry {
            span: l.span.clone(),
        };
        let li = &l.value;
        let what = format!("aerodynamic line '{}'", li.name.value);
        let base = cx
            .source
            .path
            .parent()
            .unwrap_or(Path::new("."))
            .to_path_buf();
        let mut ok = true;
        // Carrier.
        let carrier = match (&li.beam, &li.node) {
            (Some(b), None) => {
                let Some(def) = model.beams.iter().find(|d| d.name == b.value) else {
                    cx.error(
                        format!("{what}: unknown beam '{}'", b.value),
                        b.span.clone(),
                        Some("name a `[[beams]]` entry".into()),
                    );
                    return None;
                };
                if def.order + 1 > MAX_NODES {
                    cx.error(
                        format!("{what}: beam '{}' has order {}; lifting lines ride on beams of order ≤ {}", b.value, def.order, MAX_NODES - 1),
                        b.span.clone(),
                        Some("use more elements of a lower order".into()),
                    );
                    return None;
                }
                let mut arc = vec![0.0];
                for w in def.nodes.windows(2) {
                    let d = (model.nodes[w[1]].position - model.nodes[w[0]].position).norm();
                    arc.push(arc[arc.len() - 1] + d);
                }
                Carrier::Beam {
                    nodes: def.nodes.clone(),
                    etas: def.etas.clone(),
                    arc,
                    order: def.order,
                }
            }
            (None, Some(n)) => {
                let node = match cx.node_ref(n, &what) {
                    Some(NodeRef::Node(i)) => i,
                    Some(NodeRef::Ground) => {
                        cx.error(
                            format!("{what}: a line on the ground does not move; put it on a node"),
                            n.span.clone(),
                            None,
                        );
                        return None;
                    }
                    None => return None,
                };
                let (Some(root), Some(tip)) = (li.root, li.tip) else {
                    cx.error(
                        format!("{what}: a line on a node needs `root` and `tip`"),
                        e.span.clone(),
                        Some("give the line's ends, global, initial configuration".into()),
                    );
                    return None;
                };
                ok &= cx.finite(&e, "root", &root, &what) & cx.finite(&e, "tip", &tip, &what);
                let (root, tip) = (Vector3::from(root), Vector3::from(tip));
                if (tip - root).norm() <= 0.0 {
                    cx.error(
                        format!("{what}: `root` and `tip` coincide"),
                        cx.key(&e, "tip"),
                        None,
                    );
                    return None;
                }
                Carrier::Node { node, root, tip }
            }
            _ => {
                cx.error(
                    format!("{what}: give either `beam` or `node`"),
                    e.span.clone(),
                    Some("a line rides on one beam or one node (a rigid body)".into()),
                );
                return None;
            }
        };
        let length = match &carrier {
            Carrier::Beam { arc, .. } => arc[arc.len() - 1],
            Carrier::Node { root, tip, .. } => (tip - root).norm(),
        };
        ok &= cx.finite(&e, "chord_direction", &li.chord_direction, &what);
        ok &= cx.finite(&e, "normal_direction", &li.normal_direction, &what);
        let chord_direction = Vector3::from(li.chord_direction);
        let normal_direction = Vector3::from(li.normal_direction);
        if chord_direction.cross(&normal_direction).norm()
            < 1e-9 * chord_direction.norm() * normal_direction.norm()
            || chord_direction.norm() == 0.0
        {
            cx.error(
                format!("{what}: `chord_direction` and `normal_direction` must be non-zero and not parallel"),
                cx.key(&e, "normal_direction"),
                Some("the chord runs leading → trailing edge; the normal points to the suction side".into()),
            );
            ok = false;
        }
        let density = li.air_density.unwrap_or(1.225);
        if !(density.is_finite() && density > 0.0) {
            cx.error(
                format!("{what}: `air_density` must be > 0"),
                cx.key(&e, "air_density"),
                None,
            );
            ok = false;
        }
        let pitch = li.pitch.unwrap_or(0.0);
        ok &= cx.finite(&e, "pitch", &[pitch], &what);
        // Stations.
        let mut cache = HashMap::new();
        let mut stations = Vec::new();
        match (&li.aerodyn, li.stations.is_empty()) {
            (Some(f), true) => match read_aerodyn(&base.join(&f.value)) {
                Ok((rows, files)) => {
                    let mut foils = Vec::new();
                    for p in &files {
                        foils.push(load_airfoil(cx, &mut cache, p, f.span.clone(), &what));
                    }
                    for (span, chord, twist, id) in rows {
                        let Some(af) = foils[id].clone() else {
                            ok = false;
                            continue;
                        };
                        stations.push((span, chord, twist, 0.0, af, f.span.clone()));
                    }
                }
                Err((m, _)) => {
                    cx.error(
                        format!("{what}: AeroDyn file {m}"),
                        f.span.clone(),
                        Some("give an AeroDyn v15 primary file (NumAFfiles, AFNames, ADBlFile(1)); paths relative to the model file".into()),
                    );
                    return None;
                }
            },
            (None, false) => {
                for s in &li.stations {
                    let si = &s.value;
                    let Some(af) = load_airfoil(
                        cx,
                        &mut cache,
                        &base.join(&si.airfoil),
                        s.span.clone(),
                        &what,
                    ) else {
                        ok = false;
                        continue;
                    };
                    stations.push((
                        si.span,
                        si.chord,
                        si.twist,
                        si.ac_offset,
                        af,
                        s.span.clone(),
                    ));
                }
            }
            _ => {
                cx.error(
                    format!("{what}: give either `stations` or `aerodyn`"),
                    e.span.clone(),
                    None,
                );
                return None;
            }
        }
        let tol = 1e-9 * length.max(1.0);
        let mut defs: Vec<StationDef> = Vec::new();
        for (span, chord, twist, ac, airfoil, sspan) in stations {
            if ![span, chord, twist, ac].iter().all(|x| x.is_finite()) {
                cx.error(
                    format!("{what}: station values must be finite"),
                    sspan,
                    None,
                );
                ok = false;
                continue;
            }
            if chord <= 0.0 {
                cx.error(
                    format!("{what}: station at span {span} m has chord {chord} m; the chord must be > 0"),
                    sspan,
                    None,
                );
                ok = false;
                continue;
            }
            if span < -tol || span > length + tol {
                cx.error(
                    format!("{what}: station at span {span} m lies outside the line (0 … {length:.6} m)"),
                    sspan,
                    Some("span is measured from the root along the beam's reference line (or root → tip)".into()),
                );
                ok = false;
                continue;
            }
            if let Some(prev) = defs.last()
                && span <= prev.span
            {
                cx.error(
                    format!(
                        "{what}: station spans must increase strictly ({span} m follows {} m)",
                        prev.span
                    ),
                    sspan,
                    None,
                );
                ok = false;
                continue;
            }
            defs.push(StationDef {
                span: span.clamp(0.0, length),
                chord,
                twist,
                ac_offset: ac,
                airfoil,
                stall: None,
                hgm: None,
            });
        }
        // Tables interpolated in a user property (AeroDyn's AFTabMod = 3): every airfoil
        // of the line read by UserProp, a constant value inside all of
        // their ranges.
        let mut user_property = None;
        if let Some(up) = &li.user_property {
            if matches!(li.reynolds, Some(ReynoldsInput::Interpolate)) {
                cx.error(
                    format!("{what}: `user_property` with `reynolds = \"interpolate\"`: the tables are interpolated in one parameter (AeroDyn's AFTabMod is 2 or 3)"),
                    up.span.clone(),
                    Some("remove `reynolds` or `user_property`".into()),
                );
                ok = false;
            }
            let mut range = (f64::NEG_INFINITY, f64::INFINITY);
            let mut by_user: HashMap<*const Airfoil, Arc<Airfoil>> = HashMap::new();
            for d in &mut defs {
                let key = Arc::as_ptr(&d.airfoil);
                if let Some(a) = by_user.get(&key) {
                    d.airfoil = a.clone();
                    continue;
                }
                match d.airfoil.by_user_property() {
                    Ok(a) => {
                        let u = a.user_properties();
                        range = (range.0.max(u[0]), range.1.min(u[u.len() - 1]));
                        let a = Arc::new(a);
                        by_user.insert(key, a.clone());
                        d.airfoil = a;
                    }
                    Err(err) => {
                        cx.error(
                            format!(
                                "{what}: `user_property`: the airfoil file of the station at span {} m, {err}",
                                d.span
                            ),
                            up.span.clone(),
                            err.hint.clone(),
                        );
                        ok = false;
                        break;
                    }
                }
            }
            if ok && range.0 > range.1 {
                cx.error(
                    format!("{what}: `user_property`: the UserProp ranges of the line's airfoils do not overlap"),
                    up.span.clone(),
                    Some("give every airfoil of the line tables over a common UserProp range".into()),
                );
                ok = false;
            }
            match &up.value {
                UserPropertyInput::Value(v) => {
                    if ok && !(v.is_finite() && range.0 <= *v && *v <= range.1) {
                        cx.error(
                            format!(
                                "{what}: `user_property` = {v} is outside the tables' UserProp range [{}, {}]",
                                range.0, range.1
                            ),
                            up.span.clone(),
                            Some("AeroDyn's AFTabMod = 3 interpolates between the tables; add a table at this UserProp".into()),
                        );
                        ok = false;
                    }
                    user_property = Some(UserProperty::Value(*v));
                }
                UserPropertyInput::Signal(name) => {
                    if !cx.signal_names.contains_key(name) {
                        let known: Vec<String> = cx.signal_names.keys().cloned().collect();
                        let hint = match cx.suggest(name, known.iter().map(|s| s.as_str())) {
                            Some(b) => format!("did you mean '{b}'?"),
                            None => {
                                "a number, or a signal from [[signals]], a sensor or a controller"
                                    .into()
                            }
                        };
                        cx.error(
                            format!("{what}: unknown signal '{name}' as `user_property`"),
                            up.span.clone(),
                            Some(hint),
                        );
                        ok = false;
                    }
                    user_property = Some(UserProperty::Signal(name.clone()));
                }
            }
        }
        // Unsteady airfoil and dynamic stall.
        let unsteady = match li.unsteady {
            None | Some(UnsteadyInput::QuasiSteady) => AttachedFlow::QuasiSteady,
            Some(UnsteadyInput::Wagner) => AttachedFlow::Wagner,
        };
        if li.hgm.is_some() && !matches!(li.dynamic_stall, Some(DynamicStallInput::Hgm)) {
            cx.error(
                format!("{what}: `hgm` coefficients without the HGM dynamic-stall model"),
                cx.key(&e, "hgm"),
                Some("add `dynamic_stall = \"hgm\"`, or remove `hgm`".into()),
            );
            ok = false;
        }
        // Reynolds-number (or user-property) interpolation: the stall models follow the
        // station's Re (or user property).
        let by_re =
            matches!(li.reynolds, Some(ReynoldsInput::Interpolate)) || user_property.is_some();
        let stall_time_constant = match li.dynamic_stall {
            None | Some(DynamicStallInput::None) => {
                if li.stall_time_constant.is_some() {
                    cx.error(
                        format!("{what}: `stall_time_constant` without a dynamic-stall model"),
                        cx.key(&e, "stall_time_constant"),
                        Some("add `dynamic_stall = \"oye\"`".into()),
                    );
                    ok = false;
                }
                None
            }
            Some(DynamicStallInput::Oye) => {
                let a = li.stall_time_constant.unwrap_or(4.0);
                if !(a.is_finite() && a > 0.0) {
                    cx.error(
                        format!("{what}: `stall_time_constant` must be > 0 (τ = A_τ c/V)"),
                        cx.key(&e, "stall_time_constant"),
                        Some("Øye's model uses A_τ ≈ 4".into()),
                    );
                    ok = false;
                }
                let mut curves: HashMap<*const Airfoil, Arc<OyeStall>> = HashMap::new();
                for d in &mut defs {
                    let key = Arc::as_ptr(&d.airfoil);
                    if let Some(c) = curves.get(&key) {
                        d.stall = Some(c.clone());
                        continue;
                    }
                    // With Re interpolation, each table's attached-flow line (the curves
                    // are then Kirchhoff's of the polar interpolated at the station's Re).
                    let built = if by_re && d.airfoil.tables() > 1 {
                        (0..d.airfoil.tables())
                            .map(|k| OyeStall::new(&d.airfoil.table(k)).map(|c| c.line()))
                            .collect::<Option<Vec<_>>>()
                            .and_then(|lines| OyeStall::with_tables(&d.airfoil, &lines))
                    } else {
                        OyeStall::new(&d.airfoil)
                    };
                    match built {
                        Some(c) => {
                            let c = Arc::new(c);
                            curves.insert(key, c.clone());
                            d.stall = Some(c);
                        }
                        None => {
                            cx.error(
                                format!("{what}: the airfoil of the station at span {} m has no zero-lift angle with a positive lift slope within ±20°{}: Øye's dynamic stall needs an attached-flow lift curve", d.span, if by_re { " (in one of its Reynolds-number tables)" } else { "" }),
                                cx.key(&e, "dynamic_stall"),
                                Some("use `dynamic_stall = \"none\"` for non-lifting sections (cylinders)".into()),
                            );
                            ok = false;
                            break;
                        }
                    }
                }
                Some(a)
            }
            Some(DynamicStallInput::Hgm) => {
                if let Some(h) = &li.hgm {
                    let he = Entry {
                        span: h.span.clone(),
                    };
                    let v = &h.value;
                    for (key, x, lower) in [
                        ("a1", v.a1, 0.0),
                        ("a2", v.a2, 0.0),
                        ("b1", v.b1, f64::MIN_POSITIVE),
                        ("b2", v.b2, f64::MIN_POSITIVE),
                        ("t_f0", v.t_f0, f64::MIN_POSITIVE),
                        ("t_p", v.t_p, f64::MIN_POSITIVE),
                    ] {
                        let Some(x) = x else { continue };
                        if !cx.finite(&he, key, &[x], &what) {
                            ok = false;
                        } else if x < lower {
                            let bound = if lower == 0.0 { "≥ 0" } else { "> 0" };
                            cx.error(
                                format!("{what}: HGM `{key}` = {x} must be {bound}"),
                                cx.key(&he, key),
                                None,
                            );
                            ok = false;
                        }
                    }
                }
                if li.stall_time_constant.is_some() {
                    cx.error(
                        format!("{what}: `stall_time_constant` is Øye's; the HGM model takes its time constants (T_f0, T_p) from the airfoil file's unsteady-aerodynamics block"),
                        cx.key(&e, "stall_time_constant"),
                        Some("remove `stall_time_constant`, or set T_f0 and T_p in the airfoil file".into()),
                    );
                    ok = false;
                }
                if unsteady == AttachedFlow::Wagner {
                    cx.error(
                        format!("{what}: `unsteady = \"wagner\"` with `dynamic_stall = \"hgm\"`: the HGM model has its own circulatory (Wagner) lag"),
                        cx.key(&e, "unsteady"),
                        Some("remove `unsteady` (HGM includes the attached-flow response)".into()),
                    );
                    ok = false;
                }
                let mut models: HashMap<*const Airfoil, Arc<Hgm>> = HashMap::new();
                for d in &mut defs {
                    let key = Arc::as_ptr(&d.airfoil);
                    if let Some(h) = models.get(&key) {
                        d.hgm = Some(h.clone());
                        continue;
                    }
                    // Each table's UA block with Re interpolation, the first's otherwise.
                    let n_tab = if by_re { d.airfoil.tables() } else { 1 };
                    let mut per_table = Vec::with_capacity(n_tab);
                    for k in 0..n_tab {
                        let from_file = match d.airfoil.ua_coefficients_of(k) {
                            None => HgmCoefficients::DEFAULT,
                            Some(Ok(c)) => *c,
                            Some(Err(err)) => {
                                cx.error(
                                    format!(
                                        "{what}: the airfoil file of the station at span {} m, {err}",
                                        d.span
                                    ),
                                    cx.key(&e, "dynamic_stall"),
                                    err.hint.clone(),
                                );
                                break;
                            }
                        };
                        let coefficients = li
                            .hgm
                            .as_ref()
                            .map_or(from_file, |h| h.value.apply(from_file));
                        let sum = coefficients.a[0] + coefficients.a[1];
                        if sum > 1.0 {
                            cx.error(
                                format!(
                                    "{what}: HGM A₁ + A₂ = {sum} for the station at span {} m: the circulatory response 1 − A₁e^(−b₁s) − A₂e^(−b₂s) must start at or above 0",
                                    d.span
                                ),
                                li.hgm.as_ref().map_or_else(|| cx.key(&e, "dynamic_stall"), |h| h.span.clone()),
                                Some("A₁ + A₂ ≤ 1 (Jones' flat plate: 0.165 + 0.335)".into()),
                            );
                            break;
                        }
                        per_table.push(coefficients);
                    }
                    if per_table.len() < n_tab {
                        ok = false;
                        break;
                    }
                    let built = if n_tab > 1 {
                        Hgm::with_tables(&d.airfoil, &per_table)
                    } else {
                        Hgm::new(&d.airfoil, &per_table[0])
                    };
                    match built {
                        Some(h) => {
                            let h = Arc::new(h);
                            models.insert(key, h.clone());
                            d.hgm = Some(h);
                        }
                        None => {
                            cx.error(
                                format!("{what}: the airfoil of the station at span {} m has no attached-flow lift curve (no zero-lift angle with a positive slope within ±20°, or C_nalpha ≤ 0): the HGM model needs one", d.span),
                                cx.key(&e, "dynamic_stall"),
                                Some("use `dynamic_stall = \"none\"` for non-lifting sections (cylinders)".into()),
                            );
                            ok = false;
                            break;
                        }
                    }
                }
                None
            }
        };
        // Reynolds-number tables.
        let viscosity = match li.reynolds {
            None | Some(ReynoldsInput::First) => {
                if li.kinematic_viscosity.is_some() {
                    cx.error(
                        format!("{what}: `kinematic_viscosity` without `reynolds = \"interpolate\"`: the first table of each airfoil is read whatever the Reynolds number"),
                        cx.key(&e, "kinematic_viscosity"),
                        Some("add `reynolds = \"interpolate\"`, or remove `kinematic_viscosity`".into()),
                    );
                    ok = false;
                }
                None
            }
            Some(ReynoldsInput::Interpolate) => {
                let nu = li
                    .kinematic_viscosity
                    .unwrap_or(DEFAULT_KINEMATIC_VISCOSITY);
                if !(nu.is_finite() && nu > 0.0) {
                    cx.error(
                        format!("{what}: `kinematic_viscosity` = {nu} must be > 0 [m²/s]"),
                        cx.key(&e, "kinematic_viscosity"),
                        Some("air at 15 °C: 1.46e-5 m²/s".into()),
                    );
                    ok = false;
                }
                if let Some(d) = defs.iter().find(|d| !d.airfoil.sorted_by_reynolds()) {
                    cx.error(
                        format!("{what}: `reynolds = \"interpolate\"` but the airfoil of the station at span {} m has tables not sorted by increasing Reynolds number (tables told apart by UserProp: AeroDyn's AFTabMod = 3)", d.span),
                        cx.key(&e, "reynolds"),
                        Some("interpolate them with `user_property`, or give tables of increasing Re".into()),
                    );
                    ok = false;
                }
                if !defs.is_empty() && defs.iter().all(|d| d.airfoil.tables() < 2) {
                    cx.error(
                        format!("{what}: `reynolds = \"interpolate\"` but every airfoil of the line has a single table"),
                        cx.key(&e, "reynolds"),
                        Some("give airfoil files with several Reynolds-number tables (AeroDyn NumTabs > 1, or a CSV with a `re` column), or remove `reynolds`".into()),
                    );
                    ok = false;
                }
                Some(nu)
            }
        };
        // Wind.
        let mut turbsim = None;
        let wind = match &li.wind {
            None => Wind::default(),
            Some(w) => {
                let we = Entry {
                    span: w.span.clone(),
                };
                let wi = &w.value;
                let dir = Vector3::from(wi.direction.unwrap_or([1.0, 0.0, 0.0]));
                let up = Vector3::from(wi.vertical.unwrap_or([0.0, 0.0, 1.0]));
                ok &= cx.finite(&we, "direction", dir.as_slice(), &what);
                ok &= cx.finite(&we, "vertical", up.as_slice(), &what);
                if dir.norm() == 0.0 || up.norm() == 0.0 {
                    cx.error(
                        format!("{what}: wind `direction` and `vertical` must be non-zero"),
                        w.span.clone(),
                        None,
                    );
                    ok = false;
                }
                let (dir, up) = (
                    dir.try_normalize(0.0).unwrap_or_else(Vector3::x),
                    up.try_normalize(0.0).unwrap_or_else(Vector3::z),
                );
                let mut wind = Wind {
                    direction: dir,
                    vertical: up,
                    ..Default::default()
                };
                if let Some(f) = &wi.turbsim {
                    for (key, given) in [
                        ("speed", wi.speed.is_some()),
                        ("shear_exponent", wi.shear_exponent.is_some()),
                        ("reference_height", wi.reference_height.is_some()),
                        ("function", wi.function.is_some()),
                    ] {
                        if given {
                            cx.error(
                                format!("{what}: wind `{key}` with `turbsim`: the file gives the wind"),
                                cx.key(&we, key),
                                Some(format!("remove `{key}` (the box's mean hub speed, shear and time history are in the file)")),
                            );
                            ok = false;
                        }
                    }
                    if dir.dot(&up).abs() > 1e-9 {
                        cx.error(
                            format!("{what}: a TurbSim box advances horizontally, but wind `direction` is not normal to `vertical`"),
                            cx.key(&we, "direction"),
                            Some("give a horizontal direction (the box's x axis)".into()),
                        );
                        ok = false;
                    }
                    let path = base.join(&f.value);
                    // Lines sharing a file share its box.
                    let shared = model.aero_lines.iter().find_map(|l| {
                        l.turbsim
                            .as_ref()
                            .filter(|(p, _)| *p == path)
                            .and(l.wind.turbulence.clone())
                    });
                    let field = match shared {
                        Some(field) => Some(field),
                        None => match std::fs::read(&path) {
                            Err(e) => {
                                cx.error(
                                    format!(
                                        "{what}: cannot read TurbSim file '{}': {e}",
                                        path.display()
                                    ),
                                    f.span.clone(),
                                    Some("paths are relative to the model file".into()),
                                );
                                None
                            }
                            Ok(bytes) => match FullField::parse(&bytes) {
                                Ok(mut field) => {
                                    field.source = path.display().to_string();
                                    Some(Arc::new(field))
                                }
                                Err(e) => {
                                    cx.error(
                                        format!(
                                            "{what}: TurbSim file '{}': {}",
                                            path.display(),
                                            e.message
                                        ),
                                        f.span.clone(),
                                        Some(e.hint),
                                    );
                                    None
                                }
                            },
                        },
                    };
                    ok &= field.is_some();
                    wind.turbulence = field;
                    turbsim = Some((path, f.span.clone()));
                } else {
                    let Some(speed) = wi.speed else {
                        cx.error(
                            format!("{what}: the wind needs `speed` (or a `turbsim` file)"),
                            w.span.clone(),
                            Some("e.g. wind = { speed = 11.4 }".into()),
                        );
                        return None;
                    };
                    ok &= cx.finite(&we, "speed", &[speed], &what);
                    let alpha = wi.shear_exponent.unwrap_or(0.0);
                    let href = wi.reference_height.unwrap_or(0.0);
                    if alpha != 0.0 && !(href.is_finite() && href > 0.0) {
                        cx.error(
                            format!("{what}: a wind shear exponent needs `reference_height` > 0"),
                            cx.key(&we, "shear_exponent"),
                            Some("the hub height, typically".into()),
                        );
                        ok = false;
                    }
                    ok &= cx.finite(&we, "shear_exponent", &[alpha], &what);
                    wind.function = match &wi.function {
                        Some(f) => cx.time_function(f, &what).unwrap_or_default(),
                        None => TimeFunction::Constant(1.0),
                    };
                    wind.speed = speed;
                    wind.shear_exponent = alpha;
                    wind.reference_height = if href > 0.0 { href } else { 1.0 };
                }
                if let Some(g) = &wi.gust {
                    let ge = Entry {
                        span: g.span.clone(),
                    };
                    ok &= cx.finite(&ge, "velocity", &g.value.velocity, &what);
                    let f = cx
                        .time_function(&g.value.function, &what)
                        .unwrap_or_default();
                    if let Some(uc) = g.value.convection_speed
                        && !(uc.is_finite() && uc > 0.0)
                    {
                        cx.error(
                            format!("{what}: gust `convection_speed` = {uc} must be finite and > 0"),
                            cx.key(&ge, "convection_speed"),
                            Some("the speed the gust pattern advances at along the wind's direction, usually the wind's speed; omit it for a gust uniform in space".into()),
                        );
                        ok = false;
                    }
                    wind.gust = Some(Gust {
                        velocity: Vector3::from(g.value.velocity),
                        function: f,
                        convection_speed: g.value.convection_speed,
                    });
                }
                wind
            }
        };
        // Küssner's gust response.
        let kussner = match li.gust_response {
            None | Some(GustResponseInput::Wagner) => false,
            Some(GustResponseInput::Kussner) => {
                if unsteady != AttachedFlow::Wagner {
                    cx.error(
                        format!("{what}: `gust_response = \"kussner\"` without `unsteady = \"wagner\"`: Küssner's states split the downwash that Wagner's states lag"),
                        cx.key(&e, "gust_response"),
                        Some("add `unsteady = \"wagner\"`".into()),
                    );
                    ok = false;
                }
                if wind.gust.is_none() && wind.turbulence.is_none() {
                    cx.error(
                        format!("{what}: `gust_response = \"kussner\"` but the line's wind has no `gust` and no `turbsim` box (nothing for Küssner's function to lag)"),
                        cx.key(&e, "gust_response"),
                        Some("give the wind a gust: wind = { …, gust = { velocity = [0.0, 0.0, 1.0], function = { type = \"step\", … } } }, or a turbsim box".into()),
                    );
                    ok = false;
                }
                true
            }
        };
        let inflow = match li.inflow.as_ref().map(|i| &i.value) {
            None | Some(InflowInput::None) => Inflow::None,
            Some(InflowInput::Uniform { velocity }) => {
                ok &= cx.finite(&e, "velocity", velocity, &what);
                Inflow::Uniform(Vector3::from(*velocity))
            }
            Some(InflowInput::Bem {
                centre,
                axis,
                blades,
                hub_radius,
                tip_radius,
                tip_loss,
                hub_loss,
                tangential_induction,
                skewed_wake,
                ..
            }) => {
                let span = li.inflow.as_ref().and_then(|i| i.span.clone());
                let axis = Vector3::from(*axis);
                if !(*blades >= 1
                    && hub_radius.is_finite()
                    && tip_radius.is_finite()
                    && *hub_radius >= 0.0
                    && tip_radius > hub_radius
                    && axis.norm() > 0.0
                    && axis.iter().all(|x| x.is_finite())
                    && centre.iter().all(|x| x.is_finite()))
                {
                    cx.error(
                        format!("{what}: BEM needs blades ≥ 1, 0 ≤ hub_radius < tip_radius and a non-zero axis"),
                        span,
                        None,
                    );
                    ok = false;
                }
                Inflow::Bem {
                    rotor: BemRotor {
                        blades: *blades,
                        hub_radius: *hub_radius,
                        tip_radius: *tip_radius,
                        tip_loss: tip_loss.unwrap_or(true),
                        hub_loss: hub_loss.unwrap_or(true),
                        tangential_induction: tangential_induction.unwrap_or(true),
                        skewed_wake: skewed_wake.unwrap_or(false),
                    },
                    centre: Vector3::from(*centre),
                    axis: if axis.norm() > 0.0 {
                        axis.normalize()
                    } else {
                        Vector3::x()
                    },
                }
            }
            // The disc is filled in by the rotor's validation (`[[rotors]]` follows the
            // lines); a rotor that does not exist is reported by `finish`.
            Some(InflowInput::PittPeters { rotor }) => Inflow::PittPeters {
                rotor: rotor.clone(),
                disc: RotorDisc {
                    centre: Vector3::zeros(),
                    axis: Vector3::z(),
                    azimuth_reference: Vector3::x(),
                    radius: 1.0,
                },
            },
        };
        if let (Some(r), Some(InflowInput::PittPeters { rotor })) =
            (&li.rotor, li.inflow.as_ref().map(|i| &i.value))
            && &r.value != rotor
        {
            cx.error(
                format!(
                    "{what}: `rotor = \"{}\"` but the Pitt–Peters inflow names rotor '{rotor}'",
                    r.value
                ),
                r.span.clone(),
                Some("a Pitt–Peters line belongs to its inflow's rotor: remove `rotor`".into()),
            );
            ok = false;
        }
        (ok && !defs.is_empty()).then(|| AeroLineDef {
            name: li.name.value.clone(),
            carrier,
            chord_direction,
            normal_direction,
            pitch,
            density,
            stations: defs,
            wind,
            inflow,
            unsteady,
            stall_time_constant,
            inflow_span: li.inflow.as_ref().and_then(|i| i.span.clone()),
            dynamic_wake: matches!(
                li.inflow.as_ref().map(|i| &i.value),
                Some(InflowInput::Bem {
                    dynamic_wake: Some(DynamicWakeInput::Oye),
                    ..
                })
            ),
            turbsim,
            rotor: li.rotor.as_ref().map(|r| (r.value.clone(), r.span.clone())),
            viscosity,
            user_property,
            kussner,
        })
    }

    /// Every Pitt–Peters line names a rotor that exists.
    fn finish(_input: &super::ModelInput, cx: &mut Checker, model: &Model) {
        check_turbsim_boxes(cx, model);
        for l in &model.aero_lines {
            let Some((rotor, span)) = &l.rotor else {
                continue;
            };
            if model.rotors.iter().any(|r| &r.name == rotor) {
                continue;
            }
            let names: Vec<&str> = model.rotors.iter().map(|r| r.name.as_str()).collect();
            let hint = match cx.suggest(rotor, names.iter().copied()) {
                Some(b) => format!("did you mean '{b}'?"),
                None => format!(
                    "define the rotor: `[[rotors]]` with name = \"{rotor}\", centre, axis, radius and hub"
                ),
            };
            cx.error(
                format!(
                    "aerodynamic line '{}': `rotor` names '{rotor}', which is not defined",
                    l.name
                ),
                span.clone(),
                Some(hint),
            );
        }
        for l in &model.aero_lines {
            let Inflow::PittPeters { rotor, .. } = &l.inflow else {
                continue;
            };
            if model.rotors.iter().any(|r| &r.name == rotor) {
                continue;
            }
            let names: Vec<&str> = model.rotors.iter().map(|r| r.name.as_str()).collect();
            let hint = match cx.suggest(rotor, names.iter().copied()) {
                Some(b) => format!("did you mean '{b}'?"),
                None => format!(
                    "define the rotor: `[[rotors]]` with name = \"{rotor}\", centre, axis and radius"
                ),
            };
            cx.error(
                format!(
                    "aerodynamic line '{}': Pitt–Peters inflow names rotor '{rotor}', which is not defined",
                    l.name
                ),
                l.inflow_span.clone(),
                Some(hint),
            );
        }
    }

    fn nodes(_def: &AeroLineDef) -> Vec<usize> {
        // Loads give a node no equation of its own.
        Vec::new()
    }

    fn build(def: &AeroLineDef, parts: &mut Build) {
        for station in line_stations(def, parts) {
            parts.elements.push(Box::new(station));
        }
    }

    fn tangent_cases() -> Vec<TangentCase> {
        let airfoil = Arc::new(Airfoil::thin_plate_with_drag());
        let wind = Arc::new(Wind {
            speed: 9.0,
            direction: Vector3::new(1.0, 0.2, -0.1).normalize(),
            shear_exponent: 0.2,
            reference_height: 2.0,
            ..Default::default()
        });
        let attach = |seed: f64, w: f64| Attachment {
            weight: w,
            offset: Vector3::new(0.1 * seed, -0.2, 0.3),
            chord_dir: Vector3::new(0.0, 1.0, 0.1 * seed).normalize(),
            normal_dir: Vector3::new(1.0, 0.0, 0.05).normalize(),
        };
        let section = Section {
            chord: 0.4,
            width: 0.3,
            airfoil,
            viscosity: None,
        };
        let mut cases = Vec::new();
        let inflows = [
            Inflow::None,
            Inflow::Uniform(Vector3::new(-0.5, 0.3, 0.1)),
            Inflow::Bem {
                rotor: BemRotor {
                    blades: 3,
                    hub_radius: 0.2,
                    tip_radius: 4.0,
                    tip_loss: true,
                    hub_loss: true,
                    tangential_induction: true,
                    skewed_wake: false,
                },
                centre: Vector3::new(0.0, 0.0, 0.0),
                axis: Vector3::x(),
            },
            Inflow::PittPeters {
                rotor: "rotor".into(),
                disc: RotorDisc {
                    centre: Vector3::new(0.3, 0.0, 0.1),
                    axis: Vector3::new(-1.0, 0.1, 0.0).normalize(),
                    azimuth_reference: Vector3::new(0.0, 0.2, 1.0).normalize(),
                    radius: 2.5,
                },
            },
        ];
        for (k, inflow) in inflows.into_iter().enumerate() {
            // Pitt–Peters stations read the rotor's (v₀, v_s, v_c).
            let pp = matches!(inflow, Inflow::PittPeters { .. });
            let with_inflow = |c: TangentCase| {
                if pp {
                    c.with_signals(vec![2.0, 0.4, -0.3])
                } else {
                    c
                }
            };
            let inflow = Arc::new(inflow);
            // Two nodes of a beam (weights 0.3/0.7) and one node of a body.
            let e2 = AeroStation::new(
                "aero2",
                vec![0, 1],
                vec![attach(1.0, 0.3), attach(-1.0, 0.7)],
                section.clone(),
                1.2,
                wind.clone(),
                inflow.clone(),
            );
            let e1_inflow = inflow.clone();
            let e1 = AeroStation::new(
                "aero1",
                vec![0],
                vec![attach(0.5, 1.0)],
                section.clone(),
                1.2,
                wind.clone(),
                inflow,
            );
            // Nodes near a spinning blade station: at r ≈ 2 on the rotor, moving in the
            // plane (so BEM finds its windmill root).
            let node = |seed: u64| {
                let mut n = random_node(seed);
                n.x = Vector3::new(0.05, 0.1, 2.0) + 0.02 * n.x;
                n.v = Vector3::new(0.3, -12.0, 0.2) + 0.1 * n.v;
                n.w *= 0.3;
                n.rot = crate::math::Rotation::identity()
                    .compose_exp(&(0.1 * crate::math::Rotation::identity().relative_log(&n.rot)));
                n
            };
            cases.push(with_inflow(TangentCase::element(
                Box::new(e2),
                vec![node(700 + k as u64), node(710 + k as u64)],
            )));
            cases.push(with_inflow(TangentCase::element(
                Box::new(e1),
                vec![node(720 + k as u64)],
            )));
            // Five nodes of an order-4 beam element (Lagrange weights, summing to 1).
            let w5 = [-0.1, 0.4, 0.5, 0.3, -0.1];
            let e5 = AeroStation::new(
                "aero5",
                (0..5).collect(),
                w5.iter()
                    .enumerate()
                    .map(|(i, &w)| attach(i as f64 - 2.0, w))
                    .collect(),
                section.clone(),
                1.2,
                wind.clone(),
                e1_inflow.clone(),
            );
            cases.push(with_inflow(TangentCase::element(
                Box::new(e5),
                (0..5).map(|i| node(730 + 10 * k as u64 + i)).collect(),
            )));
            // Unsteady stations (Wagner's two states, Øye's separation) on 1, 2, 5 and
            // 8 nodes: state rows and the states' coupling into the loads.
            let stall = Arc::new(OyeStall::new(&section.airfoil).unwrap_or_else(|| unreachable!()));
            for (m, nn) in [1usize, 2, 5, 8].into_iter().enumerate() {
                for (a, (attached, with_stall)) in [
                    (AttachedFlow::Wagner, false),
                    (AttachedFlow::QuasiSteady, true),
                    (AttachedFlow::Wagner, true),
                ]
                .into_iter()
                .enumerate()
                {
                    let seed = 800 + 100 * k as u64 + 20 * m as u64 + 5 * a as u64;
                    let nodes: Vec<_> = (0..nn).map(|i| node(seed + i as u64)).collect();
                    // Lagrange-like weights summing to 1.
                    let w: Vec<f64> = (0..nn)
                        .map(|i| {
                            if nn == 1 {
                                1.0
                            } else {
                                (1.0 + 0.3 * (i as f64).sin()) / nn as f64
                            }
                        })
                        .collect();
                    let sum: f64 = w.iter().sum();
                    let unsteady = Unsteady {
                        attached,
                        stall: with_stall.then(|| (stall.clone(), 4.0)),
                        dynamic_wake: false,
                        hgm: None,
                        kussner: false,
                    };
                    let ns = unsteady.states();
                    let e = AeroStation::new(
                        "aero_unsteady",
                        (0..nn).collect(),
                        w.iter()
                            .enumerate()
                            .map(|(i, &wi)| attach(i as f64 - 1.0, wi / sum))
                            .collect(),
                        section.clone(),
                        1.2,
                        wind.clone(),
                        e1_inflow.clone(),
                    )
                    .with_unsteady(unsteady, 0.0, &nodes);
                    let states = [(0.3, -0.2), (0.5, 0.1), (0.6, 0.05)];
                    let states = if attached == AttachedFlow::Wagner {
                        states[..ns].to_vec()
                    } else {
                        vec![states[2]]
                    };
                    cases.push(with_inflow(
                        TangentCase::element(Box::new(e), nodes).with_states(states),
                    ));
                }
                // Beddoes–Leishman (HGM), four states, set a little off their steady
                // values (rows of the size of the offsets: the finite differences resolve
                // the small entries), x₄ inside 0 … 1 (clipped at its ends).
                let hgm = Arc::new(
                    Hgm::new(&section.airfoil, &HgmCoefficients::DEFAULT)
                        .unwrap_or_else(|| unreachable!()),
                );
                let seed = 2000 + 100 * k as u64 + 20 * m as u64;
                let nodes: Vec<_> = (0..nn).map(|i| node(seed + i as u64)).collect();
                let w = 1.0 / nn as f64;
                let unsteady = Unsteady {
                    hgm: Some(hgm),
                    ..Unsteady::default()
                };
                let e = AeroStation::new(
                    "aero_hgm",
                    (0..nn).collect(),
                    (0..nn).map(|i| attach(i as f64 - 1.0, w)).collect(),
                    section.clone(),
                    1.2,
                    wind.clone(),
                    e1_inflow.clone(),
                )
                .with_unsteady(unsteady, 0.0, &nodes);
                let mut z = [0.0; 4];
                crate::core::Element::initial_states(&e, &mut z);
                let states = vec![
                    (z[0] + 0.01, 0.02),
                    (z[1] - 0.01, -0.01),
                    (z[2] + 0.05, 0.1),
                    (0.7, 0.05),
                ];
                cases.push(with_inflow(
                    TangentCase::element(Box::new(e), nodes).with_states(states),
                ));
            }
        }
        // A turbulent box (TurbSim layout, 4 × 4 points 2 m apart, 4 steps of 0.5 s,
        // u_hub 9 m/s) with a smooth non-linear field: the stations' points (≈ (0.05,
        // 0.1, 2) within 0.5 m) and box times (≈ 0.6 s at t = 0.3 s) lie inside one cell,
        // away from its faces, so the trilinear gradients are smooth there.
        let mut b: Vec<u8> = Vec::new();
        b.extend(7i16.to_le_bytes());
        for n in [4i32, 4, 0, 4] {
            b.extend(n.to_le_bytes());
        }
        for v in [
            2.0f32, 2.0, 0.5, 9.0, 2.0, -1.5, 1000.0, 0.0, 1000.0, 0.0, 1000.0, 0.0,
        ] {
            b.extend(v.to_le_bytes());
        }
        b.extend(0i32.to_le_bytes());
        for k in 0..64 {
            let x = k as f64;
            for v in [
                9.0 + (0.7 * x).sin(),
                1.5 * (1.3 * x).cos(),
                0.8 * (0.4 * x).sin(),
            ] {
                b.extend(((v * 1000.0).round() as i16).to_le_bytes());
            }
        }
        let field = Arc::new(FullField::parse(&b).unwrap_or_else(|_| unreachable!()));
        let turbulent = Arc::new(Wind {
            turbulence: Some(field),
            ..Default::default()
        });
        let node = |seed: u64| {
            let mut n = random_node(seed);
            n.x = Vector3::new(0.05, 0.1, 2.0) + 0.02 * n.x;
            n.v = Vector3::new(0.3, -12.0, 0.2) + 0.1 * n.v;
            n.w *= 0.3;
            n.rot = crate::math::Rotation::identity()
                .compose_exp(&(0.1 * crate::math::Rotation::identity().relative_log(&n.rot)));
            n
        };
        for (k, inflow) in [
            Inflow::None,
            Inflow::Bem {
                rotor: BemRotor {
                    blades: 3,
                    hub_radius: 0.2,
                    tip_radius: 4.0,
                    tip_loss: true,
                    hub_loss: true,
                    tangential_induction: true,
                    skewed_wake: false,
                },
                centre: Vector3::zeros(),
                axis: Vector3::x(),
            },
        ]
        .into_iter()
        .enumerate()
        {
            let inflow = Arc::new(inflow);
            let e2 = AeroStation::new(
                "aero_turbulent2",
                vec![0, 1],
                vec![attach(1.0, 0.3), attach(-1.0, 0.7)],
                section.clone(),
                1.2,
                turbulent.clone(),
                inflow.clone(),
            );
            cases.push(TangentCase::element(
                Box::new(e2),
                vec![node(3000 + k as u64), node(3010 + k as u64)],
            ));
            let e1 = AeroStation::new(
                "aero_turbulent1",
                vec![0],
                vec![attach(0.5, 1.0)],
                section.clone(),
                1.2,
                turbulent.clone(),
                inflow,
            );
            cases.push(TangentCase::element(
                Box::new(e1),
                vec![node(3020 + k as u64)],
            ));
        }
        // Küssner's response to the box's turbulence (sampled at the leading edge, about
        // the time-mean profile at the station) plus a convected sine gust, with none and
        // BEM inflow, on 1 and 2 nodes.
        let turbulent_gusty = Arc::new(Wind {
            gust: Some(Gust {
                velocity: Vector3::new(0.2, -0.3, 0.9),
                function: crate::math::TimeFunction::Sine {
                    amplitude: 1.0,
                    frequency: 0.8,
                    phase: 0.3,
                    offset: 0.2,
                    start: -10.0,
                },
                convection_speed: Some(7.0),
            }),
            ..(*turbulent).clone()
        });
        for (k, inflow) in [Inflow::None, Inflow::Uniform(Vector3::new(-0.5, 0.3, 0.1))]
            .into_iter()
            .enumerate()
        {
            let inflow = Arc::new(inflow);
            for nn in [1usize, 2] {
                let seed = 3100 + 10 * k as u64 + nn as u64;
                let nodes: Vec<_> = (0..nn).map(|i| node(seed + 3 * i as u64)).collect();
                let w = 1.0 / nn as f64;
                let unsteady = Unsteady {
                    attached: AttachedFlow::Wagner,
                    kussner: true,
                    ..Unsteady::default()
                };
                let e = AeroStation::new(
                    "aero_kussner_turbulent",
                    (0..nn).collect(),
                    (0..nn).map(|i| attach(i as f64 - 0.5, w)).collect(),
                    section.clone(),
                    1.2,
                    turbulent_gusty.clone(),
                    inflow.clone(),
                )
                .with_unsteady(unsteady, 0.0, &nodes);
                let states = vec![(0.3, -0.2), (0.5, 0.1), (0.2, 0.3), (-0.1, 0.2)];
                cases.push(TangentCase::element(Box::new(e), nodes).with_states(states));
            }
        }
        // BEM with Øye's dynamic wake (two states), alone and with Wagner + Øye's stall,
        // on 1, 2 and 5 nodes.
        let bem = Arc::new(Inflow::Bem {
            rotor: BemRotor {
                blades: 3,
                hub_radius: 0.2,
                tip_radius: 4.0,
                tip_loss: true,
                hub_loss: true,
                tangential_induction: true,
                skewed_wake: false,
            },
            centre: Vector3::zeros(),
            axis: Vector3::x(),
        });
        let stall = Arc::new(OyeStall::new(&section.airfoil).unwrap_or_else(|| unreachable!()));
        for (m, nn) in [1usize, 2, 5].into_iter().enumerate() {
            for (a, airfoil_states) in [false, true].into_iter().enumerate() {
                let seed = 1500 + 20 * m as u64 + 7 * a as u64;
                let mut n = random_node(seed);
                let nodes: Vec<_> = (0..nn)
                    .map(|i| {
                        n = random_node(seed + i as u64);
                        n.x = Vector3::new(0.05, 0.1, 2.0) + 0.02 * n.x;
                        n.v = Vector3::new(0.3, -12.0, 0.2) + 0.1 * n.v;
                        n.w *= 0.3;
                        n.rot = crate::math::Rotation::identity().compose_exp(
                            &(0.1 * crate::math::Rotation::identity().relative_log(&n.rot)),
                        );
                        n.clone()
                    })
                    .collect();
                let w: Vec<f64> = (0..nn)
                    .map(|i| (1.0 + 0.3 * (i as f64).sin()) / nn as f64)
                    .collect();
                let sum: f64 = w.iter().sum();
                let unsteady = Unsteady {
                    attached: if airfoil_states {
                        AttachedFlow::Wagner
                    } else {
                        AttachedFlow::QuasiSteady
                    },
                    stall: airfoil_states.then(|| (stall.clone(), 4.0)),
                    dynamic_wake: true,
                    hgm: None,
                    kussner: false,
                };
                let e = AeroStation::new(
                    "aero_wake",
                    (0..nn).collect(),
                    w.iter()
                        .enumerate()
                        .map(|(i, &wi)| attach(i as f64 - 1.0, wi / sum))
                        .collect(),
                    section.clone(),
                    1.2,
                    wind.clone(),
                    bem.clone(),
                )
                .with_unsteady(unsteady, 0.0, &nodes);
                let wake = [(0.25, 0.1), (0.2, -0.05)];
                let states = if airfoil_states {
                    vec![(0.3, -0.2), (0.5, 0.1), (0.6, 0.05), wake[0], wake[1]]
                } else {
                    wake.to_vec()
                };
                cases.push(TangentCase::element(Box::new(e), nodes).with_states(states));
            }
        }
        // Reynolds-number interpolation: a two-table airfoil (Re 1e5 and 1e6, the second
        // with 1.3× the lift, more moment and less drag); the stations' Re ≈ W c/ν ≈
        // 12 · 0.4/1.5e-5 ≈ 3.2e5 lies between the tables, so Re enters every load
        // (through W, and with BEM through the undisturbed W₀), quasi-steady and with
        // Wagner's states, on 1 and 2 nodes.
        let table = |scale: f64| -> Vec<(usize, [f64; 4])> {
            (-180..=180)
                .map(|d| {
                    let a = (d as f64).to_radians();
                    (
                        0,
                        [
                            d as f64,
                            scale * PI * (2.0 * a).sin(),
                            (0.01 + 1.5 * a.sin().powi(2)) / scale,
                            -0.1 * scale * a.sin(),
                        ],
                    )
                })
                .collect()
        };
        let two = Arc::new(
            Airfoil::from_tables(&[(1e5, 0, table(1.0)), (1e6, 0, table(1.3))])
                .unwrap_or_else(|_| unreachable!()),
        );
        let re_section = Section {
            airfoil: two,
            viscosity: Some(1.5e-5),
            ..section.clone()
        };
        for (k, inflow) in [Arc::new(Inflow::None), bem.clone()]
            .into_iter()
            .enumerate()
        {
            for (a, attached) in [AttachedFlow::QuasiSteady, AttachedFlow::Wagner]
                .into_iter()
                .enumerate()
            {
                for nn in [1usize, 2] {
                    let seed = 4000 + 40 * k as u64 + 10 * a as u64 + nn as u64;
                    let nodes: Vec<_> = (0..nn).map(|i| node(seed + 3 * i as u64)).collect();
                    let w = 1.0 / nn as f64;
                    let unsteady = Unsteady {
                        attached,
                        ..Unsteady::default()
                    };
                    let e = AeroStation::new(
                        "aero_reynolds",
                        (0..nn).collect(),
                        (0..nn).map(|i| attach(i as f64 - 0.5, w)).collect(),
                        re_section.clone(),
                        1.2,
                        wind.clone(),
                        inflow.clone(),
                    )
                    .with_unsteady(unsteady, 0.0, &nodes);
                    let case = TangentCase::element(Box::new(e), nodes);
                    cases.push(if attached == AttachedFlow::Wagner {
                        case.with_states(vec![(0.3, -0.2), (0.5, 0.1)])
                    } else {
                        case
                    });
                }
            }
        }
        // Dynamic stall with Re interpolation: Øye's curves and the HGM model of the
        // polar interpolated at the station's Re (∂/∂Re through f_st, cl_fs, α₀, c_lα and
        // every HGM coefficient, the tables' own α₀ and c_lα fitted per table), no inflow
        // and BEM, 1 and 2 nodes; states a little off their steady values.
        let lines: Vec<_> = (0..2)
            .map(|k| {
                OyeStall::new(&re_section.airfoil.table(k))
                    .unwrap_or_else(|| unreachable!())
                    .line()
            })
            .collect();
        let oye_re = Arc::new(
            OyeStall::with_tables(&re_section.airfoil, &lines).unwrap_or_else(|| unreachable!()),
        );
        let hgm_re = Arc::new(
            Hgm::with_tables(
                &re_section.airfoil,
                &[HgmCoefficients::DEFAULT, HgmCoefficients::DEFAULT],
            )
            .unwrap_or_else(|| unreachable!()),
        );
        for (k, inflow) in [Arc::new(Inflow::None), bem.clone()]
            .into_iter()
            .enumerate()
        {
            for nn in [1usize, 2] {
                for with_hgm in [false, true] {
                    let seed = 4200 + 40 * k as u64 + 10 * u64::from(with_hgm) + nn as u64;
                    let nodes: Vec<_> = (0..nn).map(|i| node(seed + 3 * i as u64)).collect();
                    let w = 1.0 / nn as f64;
                    let unsteady = if with_hgm {
                        Unsteady {
                            hgm: Some(hgm_re.clone()),
                            ..Unsteady::default()
                        }
                    } else {
                        Unsteady {
                            stall: Some((oye_re.clone(), 4.0)),
                            ..Unsteady::default()
                        }
                    };
                    let e = AeroStation::new(
                        "aero_reynolds_stall",
                        (0..nn).collect(),
                        (0..nn).map(|i| attach(i as f64 - 0.5, w)).collect(),
                        re_section.clone(),
                        1.2,
                        wind.clone(),
                        inflow.clone(),
                    )
                    .with_unsteady(unsteady, 0.0, &nodes);
                    let mut z = [0.0; 4];
                    crate::core::Element::initial_states(&e, &mut z);
                    let states = if with_hgm {
                        vec![
                            (z[0] + 0.01, 0.02),
                            (z[1] - 0.01, -0.01),
                            (z[2] + 0.05, 0.1),
                            (0.7, 0.05),
                        ]
                    } else {
                        vec![(0.6, 0.05)]
                    };
                    cases.push(TangentCase::element(Box::new(e), nodes).with_states(states));
                }
            }
        }
        // Tables interpolated in a user property read from a signal (AFTabMod = 3): the
        // two tables above at UserProp 0 and 10, the signal at 3; quasi-steady, Øye's
        // stall and HGM on the interpolated polar (∂r/∂s through the weight).
        let by_user = Arc::new(
            re_section
                .airfoil
                .as_ref()
                .clone()
                .with_user_properties(&[0.0, 10.0])
                .by_user_property()
                .unwrap_or_else(|_| unreachable!()),
        );
        let user_section = Section {
            airfoil: by_user.clone(),
            viscosity: None,
            ..section.clone()
        };
        let lines: Vec<_> = (0..2)
            .map(|k| {
                OyeStall::new(&by_user.table(k))
                    .unwrap_or_else(|| unreachable!())
                    .line()
            })
            .collect();
        let oye_user =
            Arc::new(OyeStall::with_tables(&by_user, &lines).unwrap_or_else(|| unreachable!()));
        let hgm_user = Arc::new(
            Hgm::with_tables(
                &by_user,
                &[HgmCoefficients::DEFAULT, HgmCoefficients::DEFAULT],
            )
            .unwrap_or_else(|| unreachable!()),
        );
        for (m, unsteady) in [
            Unsteady::default(),
            Unsteady {
                stall: Some((oye_user, 4.0)),
                ..Unsteady::default()
            },
            Unsteady {
                hgm: Some(hgm_user),
                ..Unsteady::default()
            },
        ]
        .into_iter()
        .enumerate()
        {
            let nodes = vec![node(4400 + m as u64)];
            let ns = unsteady.states();
            let e = AeroStation::new(
                "aero_user_property",
                vec![0],
                vec![attach(0.0, 1.0)],
                user_section.clone(),
                1.2,
                wind.clone(),
                Arc::new(Inflow::None),
            )
            .with_user_property(UserProperty::Signal("flap".into()))
            .with_unsteady(unsteady, 0.0, &nodes);
            let mut z = [0.0; 4];
            crate::core::Element::initial_states(&e, &mut z);
            let states = match ns {
                0 => Vec::new(),
                1 => vec![(0.6, 0.05)],
                _ => vec![
                    (z[0] + 0.01, 0.02),
                    (z[1] - 0.01, -0.01),
                    (z[2] + 0.05, 0.1),
                    (0.7, 0.05),
                ],
            };
            cases.push(
                TangentCase::element(Box::new(e), nodes)
                    .with_states(states)
                    .with_signals(vec![3.0]),
            );
        }
        // The skewed-wake correction: BEM in the tangent cases' wind (about 13° off the
        // axis), quasi-steady and with the dynamic wake, on 1 and 2 nodes.
        let skewed = Arc::new(Inflow::Bem {
            rotor: BemRotor {
                blades: 3,
                hub_radius: 0.2,
                tip_radius: 4.0,
                tip_loss: true,
                hub_loss: true,
                tangential_induction: true,
                skewed_wake: true,
            },
            centre: Vector3::zeros(),
            axis: Vector3::x(),
        });
        for nn in [1usize, 2] {
            for wake in [false, true] {
                let seed = 6000 + 10 * nn as u64 + u64::from(wake);
                let nodes: Vec<_> = (0..nn).map(|i| node(seed + 3 * i as u64)).collect();
                let w = 1.0 / nn as f64;
                let unsteady = Unsteady {
                    dynamic_wake: wake,
                    ..Unsteady::default()
                };
                let e = AeroStation::new(
                    "aero_skewed",
                    (0..nn).collect(),
                    (0..nn).map(|i| attach(i as f64 - 0.5, w)).collect(),
                    section.clone(),
                    1.2,
                    wind.clone(),
                    skewed.clone(),
                )
                .with_unsteady(unsteady, 0.0, &nodes);
                let case = TangentCase::element(Box::new(e), nodes);
                cases.push(if wake {
                    case.with_states(vec![(0.25, 0.1), (0.2, -0.05)])
                } else {
                    case
                });
            }
        }
        // Küssner's gust response: a gusty wind (the sheared wind plus a gust along a
        // direction off the chord plane), Wagner + Küssner (four states) with none, uniform
        // and BEM inflow on 1 and 2 nodes, and all seven states (with Øye's stall and the
        // dynamic wake) on BEM.
        let gusty = Arc::new(Wind {
            gust: Some(Gust::uniform(
                Vector3::new(0.4, -0.8, 1.5),
                crate::math::TimeFunction::Constant(0.7),
            )),
            ..(*wind).clone()
        });
        // And a sine gust convected along the wind (its phase depends on the station's
        // leading edge): no inflow, 1 and 2 nodes.
        let convected = Arc::new(Wind {
            gust: Some(Gust {
                velocity: Vector3::new(0.4, -0.8, 1.5),
                function: crate::math::TimeFunction::Sine {
                    amplitude: 0.9,
                    frequency: 1.3,
                    phase: 0.4,
                    offset: 0.1,
                    start: -10.0,
                },
                convection_speed: Some(8.0),
            }),
            ..(*wind).clone()
        });
        let uniform = Arc::new(Inflow::Uniform(Vector3::new(-0.5, 0.3, 0.1)));
        for (k, inflow) in [
            Arc::new(Inflow::None),
            uniform,
            bem.clone(),
            Arc::new(Inflow::None),
        ]
        .into_iter()
        .enumerate()
        {
            let gusty = if k == 3 { &convected } else { &gusty };
            for nn in [1usize, 2] {
                for full in [false, true] {
                    if full && k != 2 {
                        continue;
                    }
                    let seed = 5000 + 40 * k as u64 + 10 * nn as u64 + u64::from(full);
                    let nodes: Vec<_> = (0..nn).map(|i| node(seed + 3 * i as u64)).collect();
                    let w = 1.0 / nn as f64;
                    let unsteady = Unsteady {
                        attached: AttachedFlow::Wagner,
                        kussner: true,
                        stall: full.then(|| (stall.clone(), 4.0)),
                        dynamic_wake: full,
                        hgm: None,
                    };
                    let e = AeroStation::new(
                        "aero_kussner",
                        (0..nn).collect(),
                        (0..nn).map(|i| attach(i as f64 - 0.5, w)).collect(),
                        section.clone(),
                        1.2,
                        gusty.clone(),
                        inflow.clone(),
                    )
                    .with_unsteady(unsteady, 0.0, &nodes);
                    let mut states = vec![(0.3, -0.2), (0.5, 0.1), (0.2, 0.3), (-0.1, 0.2)];
                    if full {
                        states.extend([(0.6, 0.05), (0.25, 0.1), (0.2, -0.05)]);
                    }
                    cases.push(TangentCase::element(Box::new(e), nodes).with_states(states));
                }
            }
        }
        cases
    }
}

/// The stations of a line (elements `<line>.<k>`), at the initial configuration of `parts`.
pub(crate) fn line_stations(def: &AeroLineDef, parts: &Build) -> Vec<AeroStation> {
    let mut out = Vec::with_capacity(def.stations.len());
    let wind = Arc::new(def.wind.clone());
    let inflow = Arc::new(def.inflow.clone());
    for (k, s) in def.stations.iter().enumerate() {
        let (nodes, weights, point, tangent) = station_place(def, s.span, parts);
        // Chord and normal at this station: made normal to the line, turned by the
        // twist (+ pitch) about the span toward the normal.
        let c0 = (def.chord_direction - tangent * tangent.dot(&def.chord_direction)).normalize();
        let n0 = {
            let n = def.normal_direction - tangent * tangent.dot(&def.normal_direction);
            (n - c0 * c0.dot(&n)).normalize()
        };
        let th = s.twist + def.pitch;
        let c = c0 * th.cos() + n0 * th.sin();
        let n = -c0 * th.sin() + n0 * th.cos();
        let ac = point + c * s.ac_offset;
        let attach = nodes
            .iter()
            .zip(&weights)
            .map(|(&i, &w)| {
                let ns = &parts.initial[i];
                let rt: Matrix3<f64> = ns.r().transpose();
                Attachment {
                    weight: w,
                    offset: rt * (ac - ns.x),
                    chord_dir: rt * c,
                    normal_dir: rt * n,
                }
            })
            .collect();
        let width = station_width(def, k);
        let unsteady = Unsteady {
            attached: def.unsteady,
            stall: s.stall.clone().zip(def.stall_time_constant),
            dynamic_wake: def.dynamic_wake,
            hgm: s.hgm.clone(),
            kussner: def.kussner,
        };
        let station = AeroStation::new(
            format!("{}.{k}", def.name),
            nodes,
            attach,
            Section {
                chord: s.chord,
                width,
                airfoil: s.airfoil.clone(),
                viscosity: def.viscosity,
            },
            def.density,
            wind.clone(),
            inflow.clone(),
        );
        let station = match &def.user_property {
            Some(u) => station.with_user_property(u.clone()),
            None => station,
        }
        .with_unsteady(unsteady, 0.0, parts.initial)
        .with_span(s.span);
        out.push(station);
    }
    out
}

/// Every station of a line in a TurbSim wind starts inside the box's grid, and the box
/// lasts every analysis (a normal file: the box times t + (x₀ − x)/u_hub of the stations'
/// initial x over each analysis's time range lie in 0 … (NT−1)dt).
fn check_turbsim_boxes(cx: &mut Checker, model: &Model) {
    let initial = super::initial_nodes(model);
    let parts = Build::new(&initial);
    for def in &model.aero_lines {
        let (Some(field), Some((path, span))) = (&def.wind.turbulence, &def.turbsim) else {
            continue;
        };
        let what = format!("aerodynamic line '{}'", def.name);
        let file = path.display();
        let mut xs: Vec<f64> = Vec::new();
        for s in &def.stations {
            let (_, _, p, _) = station_place(def, s.span, &parts);
            let [x, y, z] = def.wind.frame(&[p.x, p.y, p.z]);
            if let Some(why) = field.outside(y, z, 0.0) {
                cx.error(
                    format!(
                        "{what}: the station at span {} m, at ({:.3}, {:.3}, {:.3}) m, is outside the grid of TurbSim file '{file}': {why}",
                        s.span, p.x, p.y, p.z
                    ),
                    span.clone(),
                    Some("the grid is centred laterally on y = 0 of the wind frame (the tower axis through the global origin) and starts at the file's grid-bottom height: generate a box that covers the rotor".into()),
                );
                break;
            }
            xs.push(x);
        }
        if field.periodic || xs.len() < def.stations.len() {
            continue;
        }
        let x_min = xs.iter().copied().fold(f64::INFINITY, f64::min);
        let x_max = xs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        for a in &model.analyses {
            let (t0, t1) = match &a.kind {
                crate::model::AnalysisKind::Dynamic(d) => (d.t_start, d.t_end),
                crate::model::AnalysisKind::Static(s) => (s.time, s.time),
                _ => continue,
            };
            let (tau0, tau1) = (field.box_time(x_max, t0), field.box_time(x_min, t1));
            if tau0 < -1e-9 * field.dt || tau1 > field.span() * (1.0 + 1e-9) {
                cx.error(
                    format!(
                        "{what}: analysis '{}' (t = {t0} … {t1} s) needs box times {tau0:.4} … {tau1:.4} s of TurbSim file '{file}', which spans 0 … {:.4} s (a normal file's box reaches the origin {:.4} s after t = 0: it starts half its width, {:.4} m, upstream at {} m/s)",
                        a.name,
                        field.span(),
                        field.start_x() / field.mean_speed,
                        field.start_x(),
                        field.mean_speed
                    ),
                    span.clone(),
                    Some("shorten the analysis, generate a longer box (TurbSim's AnalysisTime / UsableTime), or use a periodic file".into()),
                );
            }
        }
    }
}

/// Nodes, weights, initial point and unit tangent of the line at `span`.
fn station_place(
    def: &AeroLineDef,
    span: f64,
    parts: &Build,
) -> (Vec<usize>, Vec<f64>, Vector3<f64>, Vector3<f64>) {
    match &def.carrier {
        Carrier::Node { node, root, tip } => {
            let t = (tip - root).normalize();
            (vec![*node], vec![1.0], root + t * span, t)
        }
        Carrier::Beam {
            nodes,
            etas,
            arc,
            order,
        } => {
            // η of the station (s ↔ η linear between nodes), its element, and the
            // element's Lagrange shape functions Nₐ(η) and derivatives: the station moves
            // and deforms with the beam's own interpolation.
            let n = nodes.len();
            let j = arc.partition_point(|&s| s <= span).clamp(1, n - 1) - 1;
            let len = arc[j + 1] - arc[j];
            let xi = if len > 0.0 {
                (span - arc[j]) / len
            } else {
                0.0
            };
            let eta = etas[j] * (1.0 - xi) + etas[j + 1] * xi;
            let e = (j / order).min((n - 1) / order - 1);
            let idx: Vec<usize> = (e * order..=(e + 1) * order).collect();
            let mut w = vec![0.0; idx.len()];
            let mut dw = vec![0.0; idx.len()];
            for (a, &ia) in idx.iter().enumerate() {
                let mut v = 1.0;
                let mut d = 0.0;
                for (b, &ib) in idx.iter().enumerate() {
                    if a == b {
                        continue;
                    }
                    let den = etas[ia] - etas[ib];
                    // d(∏)/dη by the product rule.
                    d = d * (eta - etas[ib]) / den + v / den;
                    v *= (eta - etas[ib]) / den;
                }
                w[a] = v;
                dw[a] = d;
            }
            let mut p = Vector3::zeros();
            let mut t = Vector3::zeros();
            for (a, &ia) in idx.iter().enumerate() {
                p += parts.initial[nodes[ia]].x * w[a];
                t += parts.initial[nodes[ia]].x * dw[a];
            }
            (idx.iter().map(|&i| nodes[i]).collect(), w, p, t.normalize())
        }
    }
}

/// Width of station k: its cell between midpoints to the neighbours, clipped to the line
/// (the trapezoid rule for stations at both ends, the midpoint rule for cell centres).
fn station_width(def: &AeroLineDef, k: usize) -> f64 {
    let s = &def.stations;
    let length = match &def.carrier {
        Carrier::Beam { arc, .. } => arc[arc.len() - 1],
        Carrier::Node { root, tip, .. } => (tip - root).norm(),
    };
    let lo = if k == 0 {
        0.0
    } else {
        0.5 * (s[k - 1].span + s[k].span)
    };
    let hi = if k + 1 == s.len() {
        length
    } else {
        0.5 * (s[k].span + s[k + 1].span)
    };
    (hi - lo).max(0.0)
}
