//! `[[tires]]`: a pneumatic tire on the wheel of a revolute hub joint, rolling on a
//! ground plane, with Magic-Formula forces and relaxation-length slip states (kernel:
//! [`crate::elements::Tire`], docs/multi-field.md).
//!
//! ```toml
//! [[tires]]
//! name = "main"
//! hub = "axle"                  # a revolute joint: wheel = node_b, carrier = node_a
//! radius = 0.5                  # unloaded radius R₀ [m]
//! rolling_radius = 0.48         # effective rolling radius R_e [m] (default R₀)
//! vertical_stiffness = 1e6      # k [N/m]
//! vertical_damping = 2e3        # c [N s/m] (default 0)
//! longitudinal_relaxation_length = 0.3  # σ_κ [m]
//! lateral_relaxation_length = 0.6       # σ_α [m]
//! longitudinal = { B = 10.0, C = 1.9, mu = 1.0, E = 0.97 }   # F_x(κ')
//! lateral = { B = 8.0, C = 1.3, mu = 0.9, E = -1.0 }         # F_y(α')
//! # lateral = { B = 8.0, C = 1.3, D = 9000.0, E = -1.0 }     # D [N] at nominal_load
//! # nominal_load = 10000.0      # F_z0 [N], needed when a set gives D
//! trail = { B = 10.0, C = 1.2, D = 0.03, E = -1.0 }          # pneumatic trail, D [m]
//! rolling_resistance = 0.01     # f_r (default 0)
//! # regularization_speed = 0.05 # v_ε [m/s] of rolling resistance and brake
//! # low_speed_damping = 0.1      # c_low [s/m]: damped slips κ' − c_low w V_sx at low speed
//! # low_speed = 1.0              # V_low [m/s] below which that damping fades in
//! brake = "brake"               # a signal: brake torque capacity [N m]
//! ground_point = [0.0, 0.0, 0.0]
//! ground_normal = [0.0, 0.0, 1.0]
//! # ground_velocity = [0.0, 0.0, 0.0] # a flat-track rig's belt, in the ground plane
//! ```

use super::ground::{GroundInput, height_field};
use super::{Build, ComponentKind};
use crate::core::NodeRef;
use crate::elements::{MagicFormula, Tire, TireGround, TireParameters};
use crate::math::height_field::HeightField;
use crate::model::validate::{Checker, Entry};
use crate::model::{JointType, Located, Model};
use crate::tangent_check::{TangentCase, random_node};
use nalgebra::Vector3;
use schemars::JsonSchema;
use serde::Deserialize;
use std::sync::Arc;

/// One set of Magic Formula coefficients (Pacejka, *Tire and Vehicle Dynamics*, §4.3.2):
/// `Y = D sin(C arctan(B x − E (B x − arctan(B x))))`.
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PacejkaInput {
    /// Stiffness factor B, positive.
    #[serde(rename = "B", default)]
    pub b: Option<f64>,
    /// Shape factor C, positive.
    #[serde(rename = "C", default)]
    pub c: Option<f64>,
    /// Peak value D: a force [N] at `nominal_load` (scaled with the load), or for the
    /// trail a length [m].
    #[serde(rename = "D", default)]
    pub d: Option<f64>,
    /// Curvature factor E, at most 1.
    #[serde(rename = "E", default)]
    pub e: Option<f64>,
    /// Friction coefficient: D = μ F_z (forces only; instead of D).
    #[serde(default)]
    pub mu: Option<f64>,
}

/// A tire.
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TireInput {
    /// Unique name; outputs `<name>.normal_force`, `.longitudinal_force`,
    /// `.lateral_force`, `.aligning_moment`, `.rolling_resistance_moment`,
    /// `.brake_torque`, `.slip_ratio`, `.slip_angle`, `.deflection`; states
    /// `<name>.slip_ratio`, `<name>.lateral_slip` (tan α').
    pub name: Located<String>,
    /// The revolute joint of the wheel: the wheel is its node_b (node_a if node_b is the
    /// ground), spinning about the joint axis; the other node carries the brake reaction.
    pub hub: Located<String>,
    /// Unloaded radius R₀ [m], positive.
    pub radius: f64,
    /// Effective rolling radius R_e [m], positive (default `radius`).
    #[serde(default)]
    pub rolling_radius: Option<f64>,
    /// Vertical stiffness k [N/m], positive.
    pub vertical_stiffness: f64,
    /// Vertical damping c [N s/m], ≥ 0 (default 0).
    #[serde(default)]
    pub vertical_damping: Option<f64>,
    /// Longitudinal relaxation length σ_κ [m], positive.
    pub longitudinal_relaxation_length: f64,
    /// Lateral relaxation length σ_α [m], positive.
    pub lateral_relaxation_length: f64,
    /// Magic Formula of F_x(κ'): B, C, E and `mu` or D.
    pub longitudinal: Located<PacejkaInput>,
    /// Magic Formula of F_y(α'): B, C, E and `mu` or D.
    pub lateral: Located<PacejkaInput>,
    /// Magic Formula of the pneumatic trail t(α') (D in m); M_z = −t F_y. Default: no
    /// aligning moment.
    #[serde(default)]
    pub trail: Option<Located<PacejkaInput>>,
    /// F_z0 [N] at which a set's D is given (D scales with F_z/F_z0).
    #[serde(default)]
    pub nominal_load: Option<f64>,
    /// Rolling-resistance coefficient f_r ≥ 0 (moment f_r R₀ F_z against the spin;
    /// default 0).
    #[serde(default)]
    pub rolling_resistance: Option<f64>,
    /// Speed v_ε [m/s] below which rolling resistance and brake torque fade out
    /// (tanh(R_e ω/v_ε)); default 0.05.
    #[serde(default)]
    pub regularization_speed: Option<f64>,
    /// Low-speed damping c_low [s/m] ≥ 0 of the slip states: the forces take the damped
    /// slips κ' − c_low w V_sx, tan α' − c_low w V_sy with w = ½(1 + cos(π|V_x|/V_low))
    /// below `low_speed` (Pacejka 2012, §8.6); default 0.
    #[serde(default)]
    pub low_speed_damping: Option<f64>,
    /// V_low [m/s], positive: the speed below which the low-speed damping fades in
    /// (default 1.0).
    #[serde(default)]
    pub low_speed: Option<f64>,
    /// A signal giving the brake-torque capacity T_b [N m] between wheel and carrier.
    #[serde(default)]
    pub brake: Option<Located<String>>,
    /// A point of the ground plane [m]; default the origin.
    #[serde(default)]
    pub ground_point: Option<[f64; 3]>,
    /// Ground normal, out of the ground; default [0, 0, 1].
    #[serde(default)]
    pub ground_normal: Option<[f64; 3]>,
    /// Velocity of the ground surface in its plane [m/s] (a flat-track rig); default 0.
    #[serde(default)]
    pub ground_velocity: Option<[f64; 3]>,
    /// A terrain instead of the plane: `{ type = "height_field", x, y, z }` or
    /// `{ type = "height_field", file }` (docs/multi-field.md).
    #[serde(default)]
    pub ground: Option<Located<GroundInput>>,
}

/// A validated tire.
#[derive(Clone, Debug)]
pub struct TireDef {
    pub name: String,
    pub wheel: usize,
    pub carrier: NodeRef,
    /// Spin axis, global, initial configuration.
    pub axis: Vector3<f64>,
    pub ground: TireGround,
    /// A height-field ground instead of the plane.
    pub terrain: Option<Arc<HeightField>>,
    pub parameters: TireParameters,
    pub brake: Option<String>,
}

pub struct TireKind;

/// Which characteristic a set is.
#[derive(Clone, Copy, PartialEq)]
enum SetKind {
    Force,
    Trail,
}

fn pacejka_set(
    cx: &mut Checker,
    set: &Located<PacejkaInput>,
    what: &str,
    key: &str,
    kind: SetKind,
    nominal_load: Option<f64>,
) -> Option<MagicFormula> {
    let p = &set.value;
    let e = Entry {
        span: set.span.clone(),
    };
    let sw = format!("{what}, `{key}`");
    let hint_all = match kind {
        SetKind::Force => {
            "a Pacejka set gives B, C, E and either mu (D = μ F_z) or D [N] with the tire's nominal_load, e.g. { B = 10.0, C = 1.9, mu = 1.0, E = 0.97 }"
        }
        SetKind::Trail => {
            "the trail set gives B, C, D [m] and E, e.g. { B = 10.0, C = 1.2, D = 0.03, E = -1.0 }"
        }
    };
    let get =
        |cx: &mut Checker, name: &str, v: Option<f64>, good: fn(f64) -> bool, expected: &str| {
            match v {
                None => {
                    cx.error(
                        format!("{sw}: the Pacejka coefficient `{name}` is missing"),
                        set.span.clone(),
                        Some(hint_all.into()),
                    );
                    None
                }
                Some(x) if !(x.is_finite() && good(x)) => {
                    cx.error(
                        format!("{sw}: `{name}` must be {expected} (got {x})"),
                        cx.key(&e, name),
                        Some(hint_all.into()),
                    );
                    None
                }
                Some(x) => Some(x),
            }
        };
    let b = get(cx, "B", p.b, |x| x > 0.0, "positive");
    let c = get(cx, "C", p.c, |x| x > 0.0, "positive");
    let ev = get(cx, "E", p.e, |x| x <= 1.0, "at most 1");
    let d = match (kind, p.d, p.mu) {
        (SetKind::Trail, d, mu) => {
            let dv = get(cx, "D", d, |x| x >= 0.0, "non-negative");
            if mu.is_some() {
                cx.error(
                    format!("{sw}: `mu` does not apply to the trail"),
                    cx.key(&e, "mu"),
                    Some(hint_all.into()),
                );
                None
            } else {
                dv
            }
        }
        (SetKind::Force, Some(_), Some(_)) => {
            cx.error(
                format!("{sw}: give either `mu` or `D`, not both"),
                cx.key(&e, "mu"),
                Some(hint_all.into()),
            );
            None
        }
        (SetKind::Force, None, mu @ Some(_)) => get(cx, "mu", mu, |x| x > 0.0, "positive"),
        (SetKind::Force, d, None) => {
            let dv = get(cx, "D", d, |x| x > 0.0, "positive");
            match (dv, nominal_load) {
                (Some(dv), Some(f0)) => Some(dv / f0),
                (Some(_), None) => {
                    cx.error(
                        format!("{sw}: `D` [N] needs the tire's `nominal_load`"),
                        cx.key(&e, "D"),
                        Some("D is the peak force at the nominal load F_z0 and scales with F_z/F_z0; or give mu = D/F_z0 instead".into()),
                    );
                    None
                }
                (None, _) => None,
            }
        }
    };
    Some(MagicFormula {
        b: b?,
        c: c?,
        d: d?,
        e: ev?,
    })
}

impl ComponentKind for TireKind {
    const NOUN: &'static str = "tire";
    type Input = TireInput;
    type Def = TireDef;

    fn name(input: &TireInput) -> &Located<String> {
        &input.name
    }

    fn validate(s: &Located<TireInput>, cx: &mut Checker, model: &mut Model) -> Option<TireDef> {
        let e = Entry {
            span: s.span.clone(),
        };
        let ti = &s.value;
        let what = format!("tire '{}'", ti.name.value);
        let mut ok = true;
        // The hub joint.
        let hub = model.joints.iter().find(|j| j.name == ti.hub.value);
        let hub = match hub {
            None => {
                let known: Vec<String> = model.joints.iter().map(|j| j.name.clone()).collect();
                let hint = match cx.suggest(&ti.hub.value, known.iter().map(|s| s.as_str())) {
                    Some(b) => format!("did you mean '{b}'?"),
                    None => "`hub` names the wheel's revolute joint in [[joints]]".into(),
                };
                cx.error(
                    format!("{what}: unknown joint '{}'", ti.hub.value),
                    ti.hub.span.clone(),
                    Some(hint),
                );
                None
            }
            Some(j) if j.kind != JointType::Revolute => {
                cx.error(
                    format!(
                        "{what}: the hub '{}' is a {} joint, not a revolute",
                        j.name,
                        j.kind.name()
                    ),
                    ti.hub.span.clone(),
                    Some("the wheel spins on a revolute joint about its axis".into()),
                );
                None
            }
            Some(j) => match (j.node_a, j.node_b) {
                (a, NodeRef::Node(b)) => Some((b, a, j.axes.column(2).into_owned())),
                (NodeRef::Node(a), NodeRef::Ground) => {
                    Some((a, NodeRef::Ground, j.axes.column(2).into_owned()))
                }
                _ => None,
            },
        };
        let mut pos = |cx: &mut Checker, key: &str, v: f64, hint: &str| {
            if !(v.is_finite() && v > 0.0) {
                cx.error(
                    format!("{what}: `{key}` must be positive (got {v})"),
                    cx.key(&e, key),
                    Some(hint.into()),
                );
                ok = false;
            }
        };
        pos(cx, "radius", ti.radius, "the unloaded radius R₀ [m]");
        let re = ti.rolling_radius.unwrap_or(ti.radius);
        pos(
            cx,
            "rolling_radius",
            re,
            "the effective rolling radius R_e [m], a little below R₀",
        );
        pos(
            cx,
            "vertical_stiffness",
            ti.vertical_stiffness,
            "k [N/m]: F_z = k δ + c δ̇",
        );
        pos(
            cx,
            "longitudinal_relaxation_length",
            ti.longitudinal_relaxation_length,
            "σ_κ [m], of the order of the radius",
        );
        pos(
            cx,
            "lateral_relaxation_length",
            ti.lateral_relaxation_length,
            "σ_α [m], of the order of the radius",
        );
        let reg = ti.regularization_speed.unwrap_or(0.05);
        pos(
            cx,
            "regularization_speed",
            reg,
            "v_ε [m/s]: rolling resistance and brake fade out below it",
        );
        let v_low = ti.low_speed.unwrap_or(1.0);
        pos(
            cx,
            "low_speed",
            v_low,
            "V_low [m/s]: the low-speed damping fades in below it, about 1 m/s",
        );
        if let Some(f0) = ti.nominal_load {
            pos(
                cx,
                "nominal_load",
                f0,
                "F_z0 [N] at which the sets' D are given",
            );
        }
        let nonneg = |cx: &mut Checker, key: &str, v: f64, hint: &str| {
            if !(v.is_finite() && v >= 0.0) {
                cx.error(
                    format!("{what}: `{key}` must be non-negative (got {v})"),
                    cx.key(&e, key),
                    Some(hint.into()),
                );
                false
            } else {
                true
            }
        };
        let damping = ti.vertical_damping.unwrap_or(0.0);
        let fr = ti.rolling_resistance.unwrap_or(0.0);
        let c_low = ti.low_speed_damping.unwrap_or(0.0);
        ok &= nonneg(cx, "vertical_damping", damping, "c [N s/m]");
        ok &= nonneg(
            cx,
            "low_speed_damping",
            c_low,
            "c_low [s/m]: damping force C c_low V_s at standstill (C the slip stiffness)",
        );
        ok &= nonneg(
            cx,
            "rolling_resistance",
            fr,
            "f_r, about 0.01 on a hard surface",
        );
        let f0 = ti.nominal_load.filter(|v| v.is_finite() && *v > 0.0);
        let long = pacejka_set(
            cx,
            &ti.longitudinal,
            &what,
            "longitudinal",
            SetKind::Force,
            f0,
        );
        let lat = pacejka_set(cx, &ti.lateral, &what, "lateral", SetKind::Force, f0);
        let trail = ti
            .trail
            .as_ref()
            .map(|t| pacejka_set(cx, t, &what, "trail", SetKind::Trail, f0));
        let normal = match ti.ground_normal {
            Some(v) => cx.unit_axis(v, &e, "ground_normal", &what),
            None => Some(Vector3::z()),
        };
        for (key, v) in [
            ("ground_point", ti.ground_point),
            ("ground_velocity", ti.ground_velocity),
        ] {
            if let Some(v) = v
                && v.iter().any(|x| !x.is_finite())
            {
                cx.error(
                    format!("{what}: `{key}` must be finite (got {v:?})"),
                    cx.key(&e, key),
                    Some("three finite numbers [x, y, z]".into()),
                );
                ok = false;
            }
        }
        let mut terrain = None;
        if let Some(g) = &ti.ground {
            for (key, given) in [
                ("ground_point", ti.ground_point.is_some()),
                ("ground_normal", ti.ground_normal.is_some()),
                ("ground_velocity", ti.ground_velocity.is_some()),
            ] {
                if given {
                    cx.error(
                        format!("{what}: `{key}` does not apply here"),
                        cx.key(&e, key),
                        Some("`ground` gives the terrain as a height field; the plane keys do not go with it".into()),
                    );
                    ok = false;
                }
            }
            terrain = height_field(cx, g, &what);
            ok &= terrain.is_some();
        }
        let velocity = Vector3::from(ti.ground_velocity.unwrap_or([0.0; 3]));
        if let Some(n) = normal
            && n.dot(&velocity).abs() > 1e-9 * velocity.norm().max(1.0)
        {
            cx.error(
                format!("{what}: `ground_velocity` must lie in the ground plane"),
                cx.key(&e, "ground_velocity"),
                Some("the surface moves in its own plane (a flat-track rig's belt)".into()),
            );
            ok = false;
        }
        if let Some(b) = &ti.brake
            && !cx.signal_names.contains_key(&b.value)
        {
            let known: Vec<String> = cx.signal_names.keys().cloned().collect();
            let hint = match cx.suggest(&b.value, known.iter().map(|s| s.as_str())) {
                Some(x) => format!("did you mean '{x}'?"),
                None => "the brake torque is a signal: from [[signals]] or a sensor".into(),
            };
            cx.error(
                format!("{what}: unknown signal '{}'", b.value),
                b.span.clone(),
                Some(hint),
            );
            ok = false;
        }
        let (wheel, carrier, axis) = hub?;
        if let (Some(n), true) = (normal, ok) {
            let s = axis.normalize();
            if (1.0 - n.dot(&s).powi(2)).sqrt() < 1e-3 {
                cx.error(
                    format!("{what}: the hub axis is along the ground normal"),
                    ti.hub.span.clone(),
                    Some("a wheel's spin axis lies (nearly) in the ground plane".into()),
                );
                ok = false;
            }
        }
        let (long, lat, normal) = (long?, lat?, normal?);
        let trail = match trail {
            Some(None) => return None,
            Some(Some(t)) => Some(t),
            None => None,
        };
        ok.then(|| TireDef {
            name: ti.name.value.clone(),
            wheel,
            carrier,
            axis,
            ground: TireGround {
                point: Vector3::from(ti.ground_point.unwrap_or([0.0; 3])),
                normal,
                velocity,
            },
            terrain: terrain.clone(),
            parameters: TireParameters {
                radius: ti.radius,
                rolling_radius: re,
                stiffness: ti.vertical_stiffness,
                damping,
                relaxation: [
                    ti.longitudinal_relaxation_length,
                    ti.lateral_relaxation_length,
                ],
                longitudinal: long,
                lateral: lat,
                trail,
                rolling_resistance: fr,
                regularization_speed: reg,
                low_speed_damping: c_low,
                low_speed: v_low,
            },
            brake: ti.brake.as_ref().map(|b| b.value.clone()),
        })
    }

    fn nodes(def: &TireDef) -> Vec<usize> {
        let mut v = vec![def.wheel];
        v.extend(def.carrier.index());
        v
    }

    fn build(def: &TireDef, parts: &mut Build) {
        let axis = parts.initial[def.wheel].r().transpose() * def.axis;
        let tire = Tire::new(
            &def.name,
            def.wheel,
            def.carrier.index(),
            axis,
            def.ground,
            def.parameters,
            def.brake.clone(),
        );
        parts.elements.push(Box::new(match &def.terrain {
            Some(hf) => tire.with_height_field(hf.clone()),
            None => tire,
        }));
    }

    fn tangent_cases() -> Vec<TangentCase> {
        let params = TireParameters {
            radius: 0.5,
            rolling_radius: 0.47,
            stiffness: 2e4,
            damping: 30.0,
            relaxation: [0.3, 0.7],
            longitudinal: MagicFormula {
                b: 4.0,
                c: 1.6,
                d: 1.1,
                e: 0.5,
            },
            lateral: MagicFormula {
                b: 3.0,
                c: 1.3,
                d: 0.9,
                e: -0.8,
            },
            trail: Some(MagicFormula {
                b: 2.0,
                c: 1.2,
                d: 0.04,
                e: -0.5,
            }),
            rolling_resistance: 0.02,
            regularization_speed: 0.8,
            low_speed_damping: 0.0,
            low_speed: 1.0,
        };
        let mut out = Vec::new();
        for k in 0..4u64 {
            let wheel = random_node(1100 + k);
            let carrier = random_node(1110 + k);
            let axis = Vector3::new(0.2, 0.9, -0.3).normalize();
            let normal = Vector3::new(0.1, -0.2, 1.0).normalize();
            // The plane 0.05 inside the rim's lowest point (δ = 0.05), except case 3
            // (out of contact: only the state rows remain).
            let s = wheel.r() * axis;
            let cv = normal - s * normal.dot(&s);
            let lowest = wheel.x - cv.normalize() * 0.5;
            let lift = if k == 3 { -0.05 } else { 0.05 };
            let ground = TireGround {
                point: lowest + normal * lift,
                normal,
                velocity: if k == 1 {
                    Vector3::new(0.4, 0.3, 0.0)
                } else {
                    Vector3::zeros()
                },
            };
            // Cases 0 and 3: low-speed damping, V_low above the random speeds so that the
            // fading weight and its slope are in play.
            let p = match k {
                2 => TireParameters {
                    trail: None,
                    ..params
                },
                0 | 3 => TireParameters {
                    low_speed_damping: 0.4,
                    low_speed: 30.0,
                    ..params
                },
                _ => params,
            };
            let with_carrier = k != 1;
            let brake = (k != 2).then(|| "brake".to_string());
            let e = Tire::new(
                "tire",
                0,
                with_carrier.then_some(1),
                axis,
                ground,
                p,
                brake.clone(),
            );
            let nodes = if with_carrier {
                vec![wheel, carrier]
            } else {
                vec![wheel]
            };
            let case = TangentCase::element(Box::new(e), nodes)
                .with_states(vec![(-0.08, 0.7), (0.15, -0.4)]);
            out.push(if brake.is_some() {
                case.with_signals(vec![300.0])
            } else {
                case
            });
        }
        // Height-field ground (curved): 0.05 of deflection, with and without carrier.
        for k in 0..2u64 {
            let wheel = random_node(1120 + k);
            let carrier = random_node(1130 + k);
            let axis = Vector3::new(0.2, 0.9, -0.3).normalize();
            let probe = super::contact::curved_terrain_through(wheel.x, 0.0);
            let hh = probe.eval(wheel.x.x, wheel.x.y).expect("inside");
            let n = Vector3::new(-hh.gradient[0], -hh.gradient[1], 1.0).normalize();
            let s = wheel.r() * axis;
            let cg = (n - s * n.dot(&s)).norm();
            let hf = super::contact::curved_terrain_through(wheel.x, 0.5 * cg - 0.05);
            let ground = TireGround {
                point: Vector3::zeros(),
                normal: Vector3::z(),
                velocity: Vector3::zeros(),
            };
            let p = if k == 0 {
                TireParameters {
                    low_speed_damping: 0.4,
                    low_speed: 30.0,
                    ..params
                }
            } else {
                params
            };
            let e = Tire::new(
                "tire_on_terrain",
                0,
                (k == 0).then_some(1),
                axis,
                ground,
                p,
                Some("brake".to_string()),
            )
            .with_height_field(hf);
            let nodes = if k == 0 {
                vec![wheel, carrier]
            } else {
                vec![wheel]
            };
            out.push(
                TangentCase::element(Box::new(e), nodes)
                    .with_states(vec![(-0.08, 0.7), (0.15, -0.4)])
                    .with_signals(vec![300.0]),
            );
        }
        out
    }
}
