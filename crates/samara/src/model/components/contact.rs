//! `[[contacts]]`: a body against a ground plane, with a Hunt–Crossley or linear
//! spring-damper normal force and LuGre friction (kernel: [`crate::elements::Contact`]).
//!
//! ```toml
//! [[contacts]]
//! name = "ball"
//! node = "ball"                  # the body's node
//! shape = "sphere"               # sphere (centred at the node) | point (on the body)
//! radius = 0.1                   # sphere radius [m]
//! # point = [0.0, 0.0, -0.1]     # point: global, initial configuration; default the node
//! ground_point = [0.0, 0.0, 0.0] # a point of the ground plane (default the origin)
//! ground_normal = [0.0, 0.0, 1.0] # out of the ground (default +z)
//! # ground_velocity = [0.1, 0.0, 0.0] # surface velocity in its plane (a belt)
//! normal = "hunt_crossley"       # hunt_crossley | linear
//! stiffness = 1e6                # k [N/m^e] (linear: N/m)
//! exponent = 1.5                 # Hunt–Crossley e ≥ 1 (default 1.5)
//! restitution = 0.7              # Hunt–Crossley: ε at `impact_velocity` … (α from it)
//! impact_velocity = 2.0          # [m/s]
//! # damping_factor = 0.3         # … or α [s/m] directly
//! # damping = 100.0              # linear: c [N s/m]
//! static_friction = 0.6          # μ_s: friction on (with the four below)
//! dynamic_friction = 0.4         # μ_d ≤ μ_s
//! stribeck_velocity = 1e-3       # v_s [m/s]
//! bristle_stiffness = 1e5        # σ₀ [1/m]
//! bristle_damping = 100.0        # σ₁ [s/m]
//! # viscous_friction = 0.0       # σ₂ [s/m]
//! # rolling_friction = 0.05      # μ_r: rolling resistance torque ≤ μ_r ρ N (spheres)
//! # twisting_friction = 0.4      # μ_t: drilling torque ≤ (3π/16) μ_t √(ρ δ) N (spheres)
//! # rolling_regularization = 0.01 # ω_ε [rad/s]: both viscous below it (default 0.01)
//! ```
//!
//! Capsule: `shape = "capsule"`, `radius` and `segment = [[…], […]]` (the ends of its
//! axis): a sphere at each end, `<name>.end_a` and `<name>.end_b`.
//!
//! Body–body: `other_node` and `other_radius` put a second sphere on another node instead
//! of the ground plane (kernel [`crate::elements::SpherePair`]); the friction keys give
//! it LuGre friction at the contact point (three bristle states `<name>.bristle_x|y|z`).

use super::ground::{GroundInput, height_field};
use super::{Build, ComponentKind, ModelInput};
use crate::core::NodeRef;
use crate::elements::{
    Contact, ContactShape, Friction, GroundPlane, NormalLaw, PairFriction, RollingResistance,
    SpherePair,
};
use crate::math::height_field::HeightField;
use crate::model::input::AnalysisType;
use crate::model::validate::{Checker, Entry};
use crate::model::{Located, Model};
use crate::tangent_check::{TangentCase, random_node};
use nalgebra::Vector3;
use schemars::JsonSchema;
use serde::Deserialize;
use std::sync::Arc;

/// Contact geometry on the body.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ShapeInput {
    /// A sphere of `radius` centred at the node.
    Sphere,
    /// A material point of the body (`point`).
    Point,
    /// A capsule: the segment `segment` swept by a sphere of `radius`; it touches the
    /// ground plane with spheres at its two ends (outputs and states of
    /// `<name>.end_a` and `<name>.end_b`).
    Capsule,
}

/// Normal-force law.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum NormalInput {
    /// N = k δᵉ (1 + α δ̇) (Hunt & Crossley 1975).
    HuntCrossley,
    /// N = k δ + c δ̇.
    Linear,
}

/// A body–ground contact.
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ContactInput {
    /// Unique name; outputs `<name>.normal_force`, `.friction_force`, `.penetration`,
    /// `.slip_velocity`, `.stick`; states `<name>.bristle_1`, `.bristle_2`.
    pub name: Located<String>,
    /// The body's node (not the ground).
    pub node: Located<String>,
    /// `sphere` or `point`.
    pub shape: ShapeInput,
    /// Sphere radius [m], positive (sphere only).
    #[serde(default)]
    pub radius: Option<f64>,
    /// Contact point on the body, global, initial configuration [m]; default the node
    /// (point only).
    #[serde(default)]
    pub point: Option<[f64; 3]>,
    /// A point of the ground plane [m]; default the origin.
    #[serde(default)]
    pub ground_point: Option<[f64; 3]>,
    /// Normal of the ground plane, out of the ground; default [0, 0, 1].
    #[serde(default)]
    pub ground_normal: Option<[f64; 3]>,
    /// Velocity of the ground surface in its plane [m/s] (a belt); default zero.
    #[serde(default)]
    pub ground_velocity: Option<[f64; 3]>,
    /// A terrain instead of the plane: `{ type = "height_field", x, y, z }` or
    /// `{ type = "height_field", file }` (docs/multi-field.md).
    #[serde(default)]
    pub ground: Option<Located<GroundInput>>,
    /// Normal-force law.
    pub normal: NormalInput,
    /// Contact stiffness k, positive [N/m^e].
    pub stiffness: f64,
    /// Hunt–Crossley exponent e ≥ 1 (default 1.5, Hertz).
    #[serde(default)]
    pub exponent: Option<f64>,
    /// Hunt–Crossley damping factor α [s/m] ≥ 0 (or `restitution`).
    #[serde(default)]
    pub damping_factor: Option<f64>,
    /// Hunt–Crossley: coefficient of restitution ε ∈ (0, 1] at `impact_velocity`.
    #[serde(default)]
    pub restitution: Option<f64>,
    /// Hunt–Crossley: impact speed [m/s] at which `restitution` holds.
    #[serde(default)]
    pub impact_velocity: Option<f64>,
    /// Linear law: damping c [N s/m] ≥ 0 (default 0).
    #[serde(default)]
    pub damping: Option<f64>,
    /// Static friction coefficient μ_s; friction is on when given.
    #[serde(default)]
    pub static_friction: Option<f64>,
    /// Dynamic (sliding) friction coefficient μ_d, 0 < μ_d ≤ μ_s.
    #[serde(default)]
    pub dynamic_friction: Option<f64>,
    /// Stribeck speed v_s [m/s], positive.
    #[serde(default)]
    pub stribeck_velocity: Option<f64>,
    /// LuGre bristle stiffness σ₀ per unit normal force [1/m], positive.
    #[serde(default)]
    pub bristle_stiffness: Option<f64>,
    /// LuGre bristle damping σ₁ per unit normal force [s/m], ≥ 0.
    #[serde(default)]
    pub bristle_damping: Option<f64>,
    /// Viscous friction σ₂ per unit normal force [s/m], ≥ 0 (default 0).
    #[serde(default)]
    pub viscous_friction: Option<f64>,
    /// Rolling resistance μ_r ≥ 0 of a sphere (docs/multi-field.md): a torque up to
    /// μ_r R_eff N against the rolling; default none.
    #[serde(default)]
    pub rolling_friction: Option<f64>,
    /// Twisting (drilling) resistance μ_t ≥ 0 of a sphere: a torque up to
    /// (3π/16) μ_t a N against the spin about the normal, a = √(R_eff δ); default none.
    #[serde(default)]
    pub twisting_friction: Option<f64>,
    /// ω_ε [rad/s] > 0: the rolling and twisting torques are viscous below it
    /// (default 0.01).
    #[serde(default)]
    pub rolling_regularization: Option<f64>,
    /// Capsule: the ends of its axis segment, global, initial configuration [m].
    #[serde(default)]
    pub segment: Option<[[f64; 3]; 2]>,
    /// Body–body contact: the node of a second sphere (instead of the ground plane);
    /// outputs `<name>.normal_force`, `.penetration` (with friction also
    /// `.friction_force`, `.slip_velocity`; states `<name>.bristle_x`, `_y`, `_z`).
    #[serde(default)]
    pub other_node: Option<Located<String>>,
    /// Radius of the second sphere [m], positive (with `other_node`).
    #[serde(default)]
    pub other_radius: Option<f64>,
}

/// A validated contact.
#[derive(Clone, Debug)]
pub struct ContactDef {
    pub name: String,
    pub node: usize,
    /// Sphere, or the point as a global point of the initial configuration (the offset is
    /// taken in the node frame when built).
    pub shape: ContactShape,
    pub point: Vector3<f64>,
    pub plane: GroundPlane,
    /// A height-field ground instead of the plane.
    pub terrain: Option<Arc<HeightField>>,
    pub law: NormalLaw,
    pub friction: Option<Friction>,
    /// Rolling and twisting resistance (spheres).
    pub rolling: Option<RollingResistance>,
    /// Body–body: the second sphere's node and radius.
    pub other: Option<(usize, f64)>,
    /// Capsule: the ends of its segment (global, initial configuration).
    pub segment: Option<[Vector3<f64>; 2]>,
}

/// The normal-law and friction keys shared by `[[contacts]]` and `[[granular]]`.
#[derive(Clone, Copy, Debug)]
pub struct LawKeys {
    pub normal: NormalInput,
    pub stiffness: f64,
    pub exponent: Option<f64>,
    pub damping_factor: Option<f64>,
    pub restitution: Option<f64>,
    pub impact_velocity: Option<f64>,
    pub damping: Option<f64>,
    pub static_friction: Option<f64>,
    pub dynamic_friction: Option<f64>,
    pub stribeck_velocity: Option<f64>,
    pub bristle_stiffness: Option<f64>,
    pub bristle_damping: Option<f64>,
    pub viscous_friction: Option<f64>,
    pub rolling_friction: Option<f64>,
    pub twisting_friction: Option<f64>,
    pub rolling_regularization: Option<f64>,
}

/// The default ω_ε of the rolling and twisting laws [rad/s].
pub const ROLLING_REGULARIZATION: f64 = 0.01;

impl ContactInput {
    pub fn law_keys(&self) -> LawKeys {
        LawKeys {
            normal: self.normal,
            stiffness: self.stiffness,
            exponent: self.exponent,
            damping_factor: self.damping_factor,
            restitution: self.restitution,
            impact_velocity: self.impact_velocity,
            damping: self.damping,
            static_friction: self.static_friction,
            dynamic_friction: self.dynamic_friction,
            stribeck_velocity: self.stribeck_velocity,
            bristle_stiffness: self.bristle_stiffness,
            bristle_damping: self.bristle_damping,
            viscous_friction: self.viscous_friction,
            rolling_friction: self.rolling_friction,
            twisting_friction: self.twisting_friction,
            rolling_regularization: self.rolling_regularization,
        }
    }
}

/// Validates the rolling and twisting keys: `(resistance, ok)` (None when neither
/// `rolling_friction` nor `twisting_friction` is given), each error at its key.
pub fn validate_rolling(
    cx: &mut Checker,
    e: &Entry,
    what: &str,
    k: &LawKeys,
) -> (Option<RollingResistance>, bool) {
    if k.rolling_friction.is_none() && k.twisting_friction.is_none() {
        let ok = unused(
            cx,
            e,
            what,
            "rolling_regularization",
            k.rolling_regularization.is_some(),
            "ω_ε regularizes `rolling_friction` and `twisting_friction`; give one of them",
        );
        return (None, ok);
    }
    let mut ok = true;
    for (key, v, hint) in [
        (
            "rolling_friction",
            k.rolling_friction,
            "μ_r ≥ 0: the rolling torque is at most μ_r R_eff N (0.001–0.1 for most grains)",
        ),
        (
            "twisting_friction",
            k.twisting_friction,
            "μ_t ≥ 0: the drilling torque is at most (3π/16) μ_t √(R_eff δ) N (μ_t is a sliding friction coefficient)",
        ),
    ] {
        if let Some(v) = v {
            ok &= check(cx, e, what, (key, v), |x| x >= 0.0, "non-negative", hint);
        }
    }
    let reg = k.rolling_regularization.unwrap_or(ROLLING_REGULARIZATION);
    ok &= check(
        cx,
        e,
        what,
        ("rolling_regularization", reg),
        |x| x > 0.0,
        "positive",
        "ω_ε [rad/s]: below it the rolling and twisting torques are viscous (a sphere under a torque below the limit creeps at about ω_ε)",
    );
    let res = RollingResistance {
        rolling: k.rolling_friction.unwrap_or(0.0),
        twisting: k.twisting_friction.unwrap_or(0.0),
        regularization: reg,
    };
    (ok.then_some(res), ok)
}

/// Validates the normal law and the LuGre friction keys: `(law, friction, ok)`, each
/// error located at its key.
pub fn validate_law(
    cx: &mut Checker,
    e: &Entry,
    what: &str,
    k: &LawKeys,
) -> (Option<NormalLaw>, Option<Friction>, bool) {
    let mut ok = true;
    let e = e.clone();
    // Normal law.
    ok &= check(
        cx,
        &e,
        what,
        ("stiffness", k.stiffness),
        |v| v > 0.0,
        "positive",
        "the contact stiffness k [N/m^e]",
    );
    let law = match k.normal {
        NormalInput::HuntCrossley => {
            ok &= unused(
                cx,
                &e,
                what,
                "damping",
                k.damping.is_some(),
                "Hunt–Crossley damping is `damping_factor` α [s/m] or `restitution` with `impact_velocity`",
            );
            let exponent = k.exponent.unwrap_or(1.5);
            ok &= check(
                cx,
                &e,
                what,
                ("exponent", exponent),
                |v| v >= 1.0,
                "at least 1",
                "1.5 is Hertz's sphere; 1 a linear spring",
            );
            let alpha = match (k.damping_factor, k.restitution, k.impact_velocity) {
                (Some(a), None, None) => check(
                    cx,
                    &e,
                    what,
                    ("damping_factor", a),
                    |v| v >= 0.0,
                    "non-negative",
                    "α [s/m]; 0 is an elastic contact",
                )
                .then_some(a),
                (None, Some(r), Some(v)) => {
                    let r_ok = check(
                        cx,
                        &e,
                        what,
                        ("restitution", r),
                        |x| x > 0.0 && x <= 1.0,
                        "in (0, 1]",
                        "a restitution of 0 needs infinite Hunt–Crossley damping; use a small positive value",
                    );
                    let v_ok = check(
                        cx,
                        &e,
                        what,
                        ("impact_velocity", v),
                        |x| x > 0.0,
                        "positive",
                        "the impact speed [m/s] at which `restitution` holds",
                    );
                    (r_ok && v_ok).then(|| crate::elements::hunt_crossley_damping(r, v))
                }
                _ => {
                    cx.error(
                            format!("{what}: give either `damping_factor` or both `restitution` and `impact_velocity`"),
                            e.span.clone(),
                            Some("Hunt–Crossley damping: α [s/m], or the restitution ε at an impact speed".into()),
                        );
                    None
                }
            };
            alpha.map(|a| NormalLaw::HuntCrossley {
                stiffness: k.stiffness,
                exponent,
                damping_factor: a,
            })
        }
        NormalInput::Linear => {
            for key in [
                "exponent",
                "damping_factor",
                "restitution",
                "impact_velocity",
            ] {
                let given = match key {
                    "exponent" => k.exponent.is_some(),
                    "damping_factor" => k.damping_factor.is_some(),
                    "restitution" => k.restitution.is_some(),
                    _ => k.impact_velocity.is_some(),
                };
                ok &= unused(
                    cx,
                    &e,
                    what,
                    key,
                    given,
                    "this key belongs to normal = \"hunt_crossley\"; the linear law takes `stiffness` and `damping`",
                );
            }
            let c = k.damping.unwrap_or(0.0);
            check(
                cx,
                &e,
                what,
                ("damping", c),
                |v| v >= 0.0,
                "non-negative",
                "c [N s/m]",
            )
            .then_some(NormalLaw::Linear {
                stiffness: k.stiffness,
                damping: c,
            })
        }
    };
    // Friction.
    let friction = match k.static_friction {
        None => {
            for (key, given) in [
                ("dynamic_friction", k.dynamic_friction.is_some()),
                ("stribeck_velocity", k.stribeck_velocity.is_some()),
                ("bristle_stiffness", k.bristle_stiffness.is_some()),
                ("bristle_damping", k.bristle_damping.is_some()),
                ("viscous_friction", k.viscous_friction.is_some()),
            ] {
                ok &= unused(
                    cx,
                    &e,
                    what,
                    key,
                    given,
                    "friction is on only with `static_friction` (μ_s)",
                );
            }
            None
        }
        Some(ms) => {
            let hint = "LuGre friction takes static_friction, dynamic_friction, stribeck_velocity, bristle_stiffness and bristle_damping";
            let md = required(cx, &e, what, "dynamic_friction", k.dynamic_friction, hint);
            let vs = required(cx, &e, what, "stribeck_velocity", k.stribeck_velocity, hint);
            let s0 = required(cx, &e, what, "bristle_stiffness", k.bristle_stiffness, hint);
            let s1 = required(cx, &e, what, "bristle_damping", k.bristle_damping, hint);
            let s2 = k.viscous_friction.unwrap_or(0.0);
            let mut f_ok = check(
                cx,
                &e,
                what,
                ("static_friction", ms),
                |v| v > 0.0,
                "positive",
                "μ_s; without friction leave out the friction keys",
            );
            if let Some(md) = md {
                f_ok &= check(
                    cx,
                    &e,
                    what,
                    ("dynamic_friction", md),
                    |v| v > 0.0 && v <= ms.max(0.0),
                    "positive and at most `static_friction`",
                    "μ_d ≤ μ_s: sliding friction does not exceed stiction",
                );
            }
            if let Some(vs) = vs {
                f_ok &= check(
                    cx,
                    &e,
                    what,
                    ("stribeck_velocity", vs),
                    |v| v > 0.0,
                    "positive",
                    "v_s [m/s], the speed over which friction falls from μ_s to μ_d",
                );
            }
            if let Some(s0) = s0 {
                f_ok &= check(
                    cx,
                    &e,
                    what,
                    ("bristle_stiffness", s0),
                    |v| v > 0.0,
                    "positive",
                    "σ₀ [1/m]: stiction holds the body within about μ_s/σ₀",
                );
            }
            if let Some(s1) = s1 {
                f_ok &= check(
                    cx,
                    &e,
                    what,
                    ("bristle_damping", s1),
                    |v| v >= 0.0,
                    "non-negative",
                    "σ₁ [s/m]; about 2√(σ₀/g) damps the stuck body critically",
                );
            }
            f_ok &= check(
                cx,
                &e,
                what,
                ("viscous_friction", s2),
                |v| v >= 0.0,
                "non-negative",
                "σ₂ [s/m]",
            );
            match (md, vs, s0, s1) {
                (Some(md), Some(vs), Some(s0), Some(s1)) if f_ok => Some(Friction {
                    static_coefficient: ms,
                    dynamic_coefficient: md,
                    stribeck_velocity: vs,
                    bristle_stiffness: s0,
                    bristle_damping: s1,
                    viscous: s2,
                }),
                _ => {
                    ok = false;
                    None
                }
            }
        }
    };
    (law, friction, ok)
}

pub struct ContactKind;

/// The contact element of `def` with this name and shape, on its plane or height field.
fn contact(def: &ContactDef, name: String, shape: ContactShape) -> Contact {
    match &def.terrain {
        Some(hf) => {
            Contact::on_height_field(name, def.node, shape, hf.clone(), def.law, def.friction)
        }
        None => Contact::new(name, def.node, shape, def.plane, def.law, def.friction),
    }
    .with_rolling(def.rolling)
}

/// A curved terrain for tangent checks, z = 0.3 sin(1.1 x) cos(0.8 y) + 0.1 x y + 0.2 x
/// on a 0.4-m grid over [−3, 3]², shifted so that `c` is at the distance `d` above it
/// (vertical gap times n_z).
pub(crate) fn curved_terrain_through(c: Vector3<f64>, d: f64) -> Arc<HeightField> {
    let g: Vec<f64> = (0..16).map(|i| -3.0 + 0.4 * i as f64).collect();
    let f = |x: f64, y: f64| 0.3 * (1.1 * x).sin() * (0.8 * y).cos() + 0.1 * x * y + 0.2 * x;
    let table = |off: f64| -> Vec<Vec<f64>> {
        g.iter()
            .map(|&y| g.iter().map(|&x| f(x, y) + off).collect())
            .collect()
    };
    let h0 = HeightField::new(g.clone(), g.clone(), &table(0.0)).expect("a valid table");
    let h = h0.eval(c.x, c.y).expect("inside");
    let nz = 1.0 / (1.0 + h.gradient[0].powi(2) + h.gradient[1].powi(2)).sqrt();
    let off = c.z - h.z - d / nz;
    let z = table(off);
    Arc::new(HeightField::new(g.clone(), g, &z).expect("a valid table"))
}

/// A finite number satisfying `ok`, or an error at `key`.
fn check(
    cx: &mut Checker,
    e: &Entry,
    what: &str,
    (key, value): (&str, f64),
    ok: impl Fn(f64) -> bool,
    expected: &str,
    hint: &str,
) -> bool {
    if value.is_finite() && ok(value) {
        return true;
    }
    cx.error(
        format!("{what}: `{key}` must be {expected} (got {value})"),
        cx.key(e, key),
        Some(hint.into()),
    );
    false
}

/// A key that must be given.
fn required(
    cx: &mut Checker,
    e: &Entry,
    what: &str,
    key: &str,
    v: Option<f64>,
    hint: &str,
) -> Option<f64> {
    if v.is_none() {
        cx.error(
            format!("{what}: `{key}` is required"),
            e.span.clone(),
            Some(hint.into()),
        );
    }
    v
}

/// A key that does not belong to the chosen option.
fn unused(cx: &mut Checker, e: &Entry, what: &str, key: &str, given: bool, hint: &str) -> bool {
    if given {
        cx.error(
            format!("{what}: `{key}` does not apply here"),
            cx.key(e, key),
            Some(hint.into()),
        );
    }
    !given
}

impl ComponentKind for ContactKind {
    const NOUN: &'static str = "contact";
    type Input = ContactInput;
    type Def = ContactDef;

    fn name(input: &ContactInput) -> &Located<String> {
        &input.name
    }

    fn validate(
        s: &Located<ContactInput>,
        cx: &mut Checker,
        model: &mut Model,
    ) -> Option<ContactDef> {
        let e = Entry {
            span: s.span.clone(),
        };
        let ci = &s.value;
        let what = format!("contact '{}'", ci.name.value);
        let mut ok = true;
        let node = match cx.node_ref(&ci.node, &what) {
            Some(NodeRef::Node(i)) => Some(i),
            Some(NodeRef::Ground) => {
                cx.error(
                    format!("{what}: the ground cannot touch itself"),
                    ci.node.span.clone(),
                    Some("a contact is between a body's node and the ground plane".into()),
                );
                None
            }
            None => None,
        };
        // Geometry.
        if ci.shape != ShapeInput::Capsule {
            ok &= unused(
                cx,
                &e,
                &what,
                "segment",
                ci.segment.is_some(),
                "`segment` is the axis of shape = \"capsule\"",
            );
        }
        let mut segment = None;
        let shape = match ci.shape {
            ShapeInput::Capsule => {
                ok &= unused(
                    cx,
                    &e,
                    &what,
                    "point",
                    ci.point.is_some(),
                    "a capsule is given by `segment` and `radius`",
                );
                let hint = "a capsule: `radius` [m] and `segment = [[x, y, z], [x, y, z]]`, the ends of its axis";
                let r = required(cx, &e, &what, "radius", ci.radius, hint);
                let seg = required(cx, &e, &what, "segment", ci.segment.map(|_| 0.0), hint)
                    .and(ci.segment);
                if let Some([a, b]) = seg {
                    let (a, b) = (Vector3::from(a), Vector3::from(b));
                    let len = (b - a).norm();
                    if !len.is_finite() || len <= 0.0 {
                        cx.error(
                            format!("{what}: the capsule's `segment` must join two different finite points"),
                            cx.key(&e, "segment"),
                            Some(hint.into()),
                        );
                        ok = false;
                    } else {
                        segment = Some([a, b]);
                    }
                } else {
                    ok = false;
                }
                match r {
                    Some(r)
                        if check(
                            cx,
                            &e,
                            &what,
                            ("radius", r),
                            |v| v > 0.0,
                            "positive",
                            "a capsule has a positive radius [m]",
                        ) =>
                    {
                        Some(ContactShape::Sphere { radius: r })
                    }
                    _ => None,
                }
            }
            ShapeInput::Sphere => {
                ok &= unused(
                    cx,
                    &e,
                    &what,
                    "point",
                    ci.point.is_some(),
                    "`point` is for shape = \"point\"; a sphere is centred at its node",
                );
                match required(
                    cx,
                    &e,
                    &what,
                    "radius",
                    ci.radius,
                    "the sphere's radius [m], e.g. radius = 0.1",
                ) {
                    Some(r)
                        if check(
                            cx,
                            &e,
                            &what,
                            ("radius", r),
                            |v| v > 0.0,
                            "positive",
                            "a sphere has a positive radius [m]",
                        ) =>
                    {
                        Some(ContactShape::Sphere { radius: r })
                    }
                    _ => None,
                }
            }
            ShapeInput::Point => {
                ok &= unused(
                    cx,
                    &e,
                    &what,
                    "radius",
                    ci.radius.is_some(),
                    "`radius` is for shape = \"sphere\"",
                );
                Some(ContactShape::Point {
                    offset: Vector3::zeros(),
                })
            }
        };
        let normal = match ci.ground_normal {
            Some(v) => cx.unit_axis(v, &e, "ground_normal", &what),
            None => Some(Vector3::z()),
        };
        for (key, v) in [
            ("point", ci.point),
            ("ground_point", ci.ground_point),
            ("ground_velocity", ci.ground_velocity),
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
        if let Some(g) = &ci.ground {
            for (key, given) in [
                ("ground_point", ci.ground_point.is_some()),
                ("ground_normal", ci.ground_normal.is_some()),
                ("ground_velocity", ci.ground_velocity.is_some()),
                ("other_node", ci.other_node.is_some()),
            ] {
                ok &= unused(
                    cx,
                    &e,
                    &what,
                    key,
                    given,
                    "`ground` gives the terrain as a height field; the plane keys (and a second body) do not go with it",
                );
            }
            terrain = height_field(cx, g, &what);
            ok &= terrain.is_some();
        }
        let velocity = Vector3::from(ci.ground_velocity.unwrap_or([0.0; 3]));
        if let Some(n) = normal
            && n.dot(&velocity).abs() > 1e-9 * velocity.norm().max(1.0)
        {
            cx.error(
                format!("{what}: `ground_velocity` must lie in the ground plane"),
                cx.key(&e, "ground_velocity"),
                Some("the surface moves in its own plane (a belt); its normal component would move the plane".into()),
            );
            ok = false;
        }
        let (law, friction, law_ok) = validate_law(cx, &e, &what, &ci.law_keys());
        ok &= law_ok;
        let (rolling, rolling_ok) = validate_rolling(cx, &e, &what, &ci.law_keys());
        ok &= rolling_ok;
        if rolling.is_some() && ci.shape == ShapeInput::Point {
            let key = if ci.rolling_friction.is_some() {
                "rolling_friction"
            } else {
                "twisting_friction"
            };
            cx.error(
                format!("{what}: `{key}` needs a sphere (a point has no contact patch)"),
                cx.key(&e, key),
                Some(
                    "rolling and twisting resistance act on shape = \"sphere\" or \"capsule\""
                        .into(),
                ),
            );
            ok = false;
        }
        // Body–body.
        let mut other = None;
        if let Some(on) = &ci.other_node {
            let hint = "a body–body contact is between two spheres: `shape = \"sphere\"`, `radius`, `other_node`, `other_radius`, the normal law and optionally the LuGre friction keys";
            match cx.node_ref(on, &what) {
                Some(NodeRef::Node(j)) if Some(j) == node => {
                    cx.error(
                        format!("{what}: a contact between a body and itself"),
                        on.span.clone(),
                        Some("`other_node` must be another body's node".into()),
                    );
                    ok = false;
                }
                Some(NodeRef::Node(j)) => other = Some(j),
                Some(NodeRef::Ground) => {
                    cx.error(
                        format!("{what}: `other_node` cannot be the ground"),
                        on.span.clone(),
                        Some("against the ground, leave out `other_node` and give the ground plane (`ground_point`, `ground_normal`)".into()),
                    );
                    ok = false;
                }
                None => ok = false,
            }
            if ci.shape != ShapeInput::Sphere {
                cx.error(
                    format!("{what}: a body–body contact is between two spheres"),
                    cx.key(&e, "shape"),
                    Some(hint.into()),
                );
                ok = false;
            }
            for (key, given) in [
                ("ground_point", ci.ground_point.is_some()),
                ("ground_normal", ci.ground_normal.is_some()),
                ("ground_velocity", ci.ground_velocity.is_some()),
            ] {
                ok &= unused(cx, &e, &what, key, given, hint);
            }
            match required(cx, &e, &what, "other_radius", ci.other_radius, hint) {
                Some(r) => {
                    ok &= check(
                        cx,
                        &e,
                        &what,
                        ("other_radius", r),
                        |v| v > 0.0,
                        "positive",
                        "the second sphere's radius [m]",
                    );
                }
                None => ok = false,
            }
        } else {
            ok &= unused(
                cx,
                &e,
                &what,
                "other_radius",
                ci.other_radius.is_some(),
                "`other_radius` is the radius of the sphere on `other_node`",
            );
        }
        let (node, shape, normal, law) = (node?, shape?, normal?, law?);
        let point = match ci.point {
            Some(p) => Vector3::from(p),
            None => model.nodes[node].position,
        };
        ok.then(|| ContactDef {
            name: ci.name.value.clone(),
            node,
            shape,
            point,
            plane: GroundPlane {
                point: Vector3::from(ci.ground_point.unwrap_or([0.0; 3])),
                normal,
                velocity,
            },
            terrain: terrain.clone(),
            law,
            friction,
            rolling,
            other: other.zip(ci.other_radius),
            segment,
        })
    }

    /// Friction contacts have no static equilibrium of their own (the bristle row is
    /// 0 = 0 at rest): a static analysis of a model with one is rejected.
    fn finish(input: &ModelInput, cx: &mut Checker, _model: &Model) {
        let Some(c) = input.contacts.iter().find(|c| {
            let c = &c.value;
            c.static_friction.is_some()
                || c.rolling_friction.is_some()
                || c.twisting_friction.is_some()
        }) else {
            return;
        };
        for a in &input.analyses {
            if a.value.kind.value == AnalysisType::Static {
                cx.error(
                    format!(
                        "analysis '{}': a static analysis cannot hold the friction of contact '{}'",
                        a.value.name.value, c.value.name.value
                    ),
                    a.value.kind.span.clone(),
                    Some("static friction is indeterminate at rest (the LuGre bristle row vanishes; rolling and twisting resistance vanish too); run a dynamic analysis and let it settle, or leave out the friction keys".into()),
                );
            }
        }
    }

    fn nodes(def: &ContactDef) -> Vec<usize> {
        let mut v = vec![def.node];
        v.extend(def.other.map(|o| o.0));
        v
    }

    fn build(def: &ContactDef, parts: &mut Build) {
        if let (Some((j, rb)), ContactShape::Sphere { radius }) = (def.other, def.shape) {
            parts.elements.push(Box::new(
                SpherePair::new(&def.name, [def.node, j], [radius, rb], def.law)
                    .with_friction(def.friction.map(PairFriction::LuGre))
                    .with_rolling(def.rolling),
            ));
            return;
        }
        if let (Some(seg), ContactShape::Sphere { radius }) = (def.segment, def.shape) {
            for (end, p) in ["end_a", "end_b"].into_iter().zip(seg) {
                let offset = parts
                    .local_offset(NodeRef::Node(def.node), p)
                    .map_or(Vector3::zeros(), |(_, s)| s);
                parts.elements.push(Box::new(contact(
                    def,
                    format!("{}.{end}", def.name),
                    ContactShape::OffsetSphere { radius, offset },
                )));
            }
            return;
        }
        let shape = match def.shape {
            ContactShape::Point { .. } => ContactShape::Point {
                offset: parts
                    .local_offset(NodeRef::Node(def.node), def.point)
                    .map_or(Vector3::zeros(), |(_, s)| s),
            },
            s => s,
        };
        parts
            .elements
            .push(Box::new(contact(def, def.name.clone(), shape)));
    }

    fn tangent_cases() -> Vec<TangentCase> {
        let friction = Friction {
            static_coefficient: 0.7,
            dynamic_coefficient: 0.4,
            stribeck_velocity: 0.8,
            bristle_stiffness: 50.0,
            bristle_damping: 3.0,
            viscous: 0.2,
        };
        let hc = NormalLaw::HuntCrossley {
            stiffness: 2e3,
            exponent: 1.5,
            damping_factor: 0.3,
        };
        let lin = NormalLaw::Linear {
            stiffness: 1e3,
            damping: 20.0,
        };
        let mut out = Vec::new();
        for k in 0..6u64 {
            let node = random_node(900 + k);
            let normal = Vector3::new(0.2, -0.3, 1.0).normalize();
            let shape = if k % 2 == 0 {
                ContactShape::Sphere { radius: 0.4 }
            } else {
                ContactShape::Point {
                    offset: Vector3::new(0.1, -0.2, 0.15),
                }
            };
            // The plane through a point 0.1 below the contact point: in contact (δ = 0.1)
            // except case 5 (0.1 above: out of contact, only the bristle rows remain).
            let a = match shape {
                ContactShape::Sphere { radius } => -normal * radius,
                ContactShape::Point { offset } => node.r() * offset,
                ContactShape::OffsetSphere { radius, offset } => {
                    node.r() * offset - normal * radius
                }
            };
            let lift = if k == 5 { -0.1 } else { 0.1 };
            let plane = GroundPlane {
                point: node.x + a + normal * lift,
                normal,
                velocity: Vector3::new(0.3, 0.5, 0.0),
            };
            let law = if k < 3 { hc } else { lin };
            let with_friction = k != 2;
            let e = Contact::new("c", 0, shape, plane, law, with_friction.then_some(friction));
            let case = TangentCase::element(Box::new(e), vec![node]);
            out.push(if with_friction {
                case.with_states(vec![(0.004, -0.3), (-0.002, 0.5)])
            } else {
                case
            });
        }
        // Capsule ends (spheres at material points), with and without friction.
        for k in 0..2u64 {
            let node = random_node(940 + k);
            let normal = Vector3::new(-0.1, 0.3, 1.0).normalize();
            let offset = Vector3::new(0.3, -0.1, 0.2);
            let a = node.r() * offset - normal * 0.25;
            let plane = GroundPlane {
                point: node.x + a + normal * 0.08,
                normal,
                velocity: Vector3::new(-0.2, 0.1, 0.0),
            };
            let shape = ContactShape::OffsetSphere {
                radius: 0.25,
                offset,
            };
            let e = Contact::new("end", 0, shape, plane, hc, (k == 0).then_some(friction));
            let case = TangentCase::element(Box::new(e), vec![node]);
            out.push(if k == 0 {
                case.with_states(vec![(0.003, 0.2), (-0.001, -0.4)])
            } else {
                case
            });
        }
        // Height-field ground (a curved grid): sphere, point and capsule end, with and
        // without friction, each 0.1 into the surface below its centre.
        for k in 0..4u64 {
            let node = random_node(960 + k);
            let (shape, rho) = match k {
                0 | 3 => (ContactShape::Sphere { radius: 0.3 }, 0.3),
                1 => (
                    ContactShape::Point {
                        offset: Vector3::new(0.1, -0.2, 0.15),
                    },
                    0.0,
                ),
                _ => (
                    ContactShape::OffsetSphere {
                        radius: 0.2,
                        offset: Vector3::new(0.3, -0.1, 0.2),
                    },
                    0.2,
                ),
            };
            let c = match shape {
                ContactShape::Point { offset } | ContactShape::OffsetSphere { offset, .. } => {
                    node.x + node.r() * offset
                }
                ContactShape::Sphere { .. } => node.x,
            };
            let hf = curved_terrain_through(c, rho - 0.1);
            let with_friction = k != 3;
            let e = Contact::on_height_field(
                "terrain",
                0,
                shape,
                hf,
                if k % 2 == 0 { hc } else { lin },
                with_friction.then_some(friction),
            );
            let case = TangentCase::element(Box::new(e), vec![node]);
            out.push(if with_friction {
                case.with_states(vec![(0.004, -0.3), (-0.002, 0.5)])
            } else {
                case
            });
        }
        // Sphere pairs: in contact (the radii exceed the distance), both laws.
        for (k, law) in [hc, lin].into_iter().enumerate() {
            let a = random_node(930 + k as u64);
            let b = random_node(935 + k as u64);
            let dist = (b.x - a.x).norm();
            let e = SpherePair::new("pair", [0, 1], [0.6 * dist, 0.5 * dist], law);
            out.push(TangentCase::element(Box::new(e), vec![a, b]));
        }
        // Sphere pairs with friction: LuGre (bristle states, in contact and, k = 2, apart)
        // and regularized Coulomb–Stribeck; spinning nodes (random Ω) so the contact
        // points' velocities carry ω × (±ρ n).
        for k in 0..4u64 {
            let a = random_node(960 + k);
            let b = random_node(970 + k);
            let dist = (b.x - a.x).norm();
            let radii = if k == 2 {
                [0.4 * dist, 0.3 * dist]
            } else {
                [0.6 * dist, 0.5 * dist]
            };
            let law = if k % 2 == 0 { hc } else { lin };
            let pf = if k < 3 {
                PairFriction::LuGre(friction)
            } else {
                PairFriction::Regularized {
                    friction,
                    regularization_velocity: 0.05,
                }
            };
            let e = SpherePair::new("pair", [0, 1], radii, law).with_friction(Some(pf));
            let case = TangentCase::element(Box::new(e), vec![a, b]);
            out.push(if k < 3 {
                case.with_states(vec![(0.004, -0.3), (-0.002, 0.5), (0.001, 0.2)])
            } else {
                case
            });
        }
        // Rolling and twisting resistance (spinning nodes, ω_ε comparable to |ω| so the
        // regularized part is tested): on the plane (sphere, capsule end), on the height
        // field, and between spheres (with and without LuGre).
        let res = RollingResistance {
            rolling: 0.15,
            twisting: 0.4,
            regularization: 0.7,
        };
        for k in 0..5u64 {
            let node = random_node(1010 + k);
            let normal = Vector3::new(0.2, -0.3, 1.0).normalize();
            let (shape, a) = match k {
                1 => {
                    let offset = Vector3::new(0.3, -0.1, 0.2);
                    (
                        ContactShape::OffsetSphere {
                            radius: 0.25,
                            offset,
                        },
                        node.r() * offset - normal * 0.25,
                    )
                }
                _ => (ContactShape::Sphere { radius: 0.4 }, -normal * 0.4),
            };
            let plane = GroundPlane {
                point: node.x + a + normal * 0.1,
                normal,
                velocity: Vector3::zeros(),
            };
            let law = if k == 0 { hc } else { lin };
            let case = match k {
                0 | 1 => {
                    let e = Contact::new("r", 0, shape, plane, law, Some(friction))
                        .with_rolling(Some(res));
                    TangentCase::element(Box::new(e), vec![node])
                        .with_states(vec![(0.004, -0.3), (-0.002, 0.5)])
                }
                2 => {
                    let hf = curved_terrain_through(node.x, 0.3);
                    let e = Contact::on_height_field("r", 0, shape, hf, hc, None)
                        .with_rolling(Some(res));
                    TangentCase::element(Box::new(e), vec![node])
                }
                _ => {
                    let b = random_node(1020 + k);
                    let dist = (b.x - node.x).norm();
                    let e = SpherePair::new("rp", [0, 1], [0.6 * dist, 0.5 * dist], law)
                        .with_friction((k == 4).then_some(PairFriction::LuGre(friction)))
                        .with_rolling(Some(res));
                    let case = TangentCase::element(Box::new(e), vec![node, b]);
                    if k == 4 {
                        case.with_states(vec![(0.004, -0.3), (-0.002, 0.5), (0.001, 0.2)])
                    } else {
                        case
                    }
                }
            };
            out.push(case);
        }
        out
    }
}
