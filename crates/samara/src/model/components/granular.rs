//! `[[granular]]`: a granular contact set — many spheres centred at body nodes, in
//! contact with each other (pairs found during the run by a broad phase, kernel
//! [`crate::elements::GranularSet`]) and with a ground plane (one
//! [`crate::elements::Contact`] per sphere), with the normal laws and friction keys of
//! `[[contacts]]`.
//!
//! ```toml
//! [[granular]]
//! name = "pile"
//! nodes = ["b1", "b2", "b3"]     # the spheres' nodes … or
//! # nodes_matching = "ball_*"    # every node whose name matches (one `*`)
//! radius = 0.05                  # one radius [m] … or
//! # radii = [0.05, 0.04, 0.05]   # one per node, in `nodes` order
//! margin = 0.01                  # Verlet margin [m]: pairs closer than this are candidates
//! ground_point = [0.0, 0.0, 0.0] # the ground plane (default the origin, normal +z)
//! ground_normal = [0.0, 0.0, 1.0]
//! walls = [{ point = [0.2, 0.0, 0.0], normal = [-1.0, 0.0, 0.0] }] # frictionless (a box)
//! normal = "hunt_crossley"       # the normal law, as [[contacts]]
//! stiffness = 1e6
//! restitution = 0.5
//! impact_velocity = 1.0
//! static_friction = 0.5          # friction (optional): LuGre on the ground and between
//! dynamic_friction = 0.4         # spheres (the pairs' bristles are history variables)
//! stribeck_velocity = 0.01
//! bristle_stiffness = 1e4
//! bristle_damping = 50.0
//! # regularization_velocity = 1e-3 # stateless regularized Coulomb between spheres instead
//! rolling_friction = 0.05        # μ_r (optional): rolling resistance ≤ μ_r R_eff N, on the
//! twisting_friction = 0.4        # ground and between spheres; μ_t: drilling resistance
//! # rolling_regularization = 0.01 # ω_ε [rad/s] (default 0.01), as [[contacts]]
//! ```

use super::contact::{LawKeys, NormalInput, validate_law, validate_rolling};
use super::{Build, ComponentKind, ModelInput};
use crate::core::NodeRef;
use crate::elements::{
    Contact, ContactShape, Friction, GranularSet, GroundPlane, NormalLaw, PairFriction,
    RollingResistance, SpherePair,
};
use crate::model::input::AnalysisType;
use crate::model::validate::{Checker, Entry};
use crate::model::{Located, Model};
use crate::tangent_check::{TangentCase, random_node};
use nalgebra::Vector3;
use schemars::JsonSchema;
use serde::Deserialize;

/// A granular contact set.
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct GranularInput {
    /// Unique name; the ground contacts are `<name>.ground.<node>` (outputs and states as
    /// `[[contacts]]`).
    pub name: Located<String>,
    /// The spheres' nodes (body nodes, each once).
    #[serde(default)]
    pub nodes: Option<Vec<Located<String>>>,
    /// Every node whose name matches this pattern (one `*` for any characters).
    #[serde(default)]
    pub nodes_matching: Option<Located<String>>,
    /// One radius for every sphere [m], positive.
    #[serde(default)]
    pub radius: Option<f64>,
    /// One radius per node of `nodes` [m], positive.
    #[serde(default)]
    pub radii: Option<Vec<f64>>,
    /// Verlet margin [m], positive: pairs with a gap below it are candidates, detected
    /// again when a sphere has moved half of it.
    pub margin: f64,
    /// A point of the ground plane [m]; default the origin.
    #[serde(default)]
    pub ground_point: Option<[f64; 3]>,
    /// Normal of the ground plane, out of the ground; default [0, 0, 1].
    #[serde(default)]
    pub ground_normal: Option<[f64; 3]>,
    /// Frictionless confining planes (a box): contacts `<name>.wall<k>.<node>`, k = 1, 2, …
    #[serde(default)]
    pub walls: Option<Vec<WallInput>>,
    /// Normal-force law (as `[[contacts]]`).
    pub normal: NormalInput,
    /// Contact stiffness k, positive [N/m^e].
    pub stiffness: f64,
    /// Hunt–Crossley exponent e ≥ 1 (default 1.5).
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
    /// Linear law: damping c [N s/m] ≥ 0.
    #[serde(default)]
    pub damping: Option<f64>,
    /// μ_s: friction on (LuGre against the ground and between spheres).
    #[serde(default)]
    pub static_friction: Option<f64>,
    /// μ_d, 0 < μ_d ≤ μ_s.
    #[serde(default)]
    pub dynamic_friction: Option<f64>,
    /// Stribeck speed v_s [m/s], positive.
    #[serde(default)]
    pub stribeck_velocity: Option<f64>,
    /// LuGre bristle stiffness σ₀ [1/m], positive.
    #[serde(default)]
    pub bristle_stiffness: Option<f64>,
    /// LuGre bristle damping σ₁ [s/m], ≥ 0.
    #[serde(default)]
    pub bristle_damping: Option<f64>,
    /// Viscous friction σ₂ [s/m], ≥ 0 (default 0).
    #[serde(default)]
    pub viscous_friction: Option<f64>,
    /// Sphere–sphere friction: the stateless regularized Coulomb–Stribeck law with this
    /// regularization speed v_r [m/s] > 0 instead of LuGre bristles (no stick: creep at
    /// ≈ v_r below the friction limit).
    #[serde(default)]
    pub regularization_velocity: Option<f64>,
    /// Rolling resistance μ_r ≥ 0 on the ground and between spheres (as `[[contacts]]`;
    /// R_eff = ρ_A ρ_B/(ρ_A + ρ_B) between spheres); default none.
    #[serde(default)]
    pub rolling_friction: Option<f64>,
    /// Twisting (drilling) resistance μ_t ≥ 0 (as `[[contacts]]`); default none.
    #[serde(default)]
    pub twisting_friction: Option<f64>,
    /// ω_ε [rad/s] > 0 of both (default 0.01).
    #[serde(default)]
    pub rolling_regularization: Option<f64>,
}

/// A frictionless confining plane of a granular set.
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct WallInput {
    /// A point of the plane [m].
    pub point: [f64; 3],
    /// Its normal, pointing into the box.
    pub normal: [f64; 3],
}

/// A validated granular set.
#[derive(Clone, Debug)]
pub struct GranularDef {
    pub name: String,
    pub nodes: Vec<usize>,
    /// The nodes' names (for the ground contacts' names).
    pub node_names: Vec<String>,
    pub radii: Vec<f64>,
    pub margin: f64,
    pub plane: GroundPlane,
    /// Frictionless walls.
    pub walls: Vec<GroundPlane>,
    pub law: NormalLaw,
    pub friction: Option<Friction>,
    /// The stateless pair law instead of LuGre bristles.
    pub regularization_velocity: Option<f64>,
    /// Rolling and twisting resistance (ground and pairs).
    pub rolling: Option<RollingResistance>,
}

pub struct GranularKind;

/// Whether `name` matches `pattern` with at most one `*`.
fn matches(pattern: &str, name: &str) -> bool {
    match pattern.split_once('*') {
        None => pattern == name,
        Some((pre, post)) => {
            name.len() >= pre.len() + post.len() && name.starts_with(pre) && name.ends_with(post)
        }
    }
}

impl ComponentKind for GranularKind {
    const NOUN: &'static str = "granular set";
    type Input = GranularInput;
    type Def = GranularDef;

    fn name(input: &GranularInput) -> &Located<String> {
        &input.name
    }

    fn validate(
        s: &Located<GranularInput>,
        cx: &mut Checker,
        model: &mut Model,
    ) -> Option<GranularDef> {
        let e = Entry {
            span: s.span.clone(),
        };
        let gi = &s.value;
        let what = format!("granular set '{}'", gi.name.value);
        let mut ok = true;
        // The spheres.
        let mut nodes: Vec<usize> = Vec::new();
        match (&gi.nodes, &gi.nodes_matching) {
            (Some(list), None) => {
                for r in list {
                    match cx.node_ref(r, &what) {
                        Some(NodeRef::Node(i)) => {
                            if nodes.contains(&i) {
                                cx.error(
                                    format!("{what}: node '{}' is listed twice", r.value),
                                    r.span.clone(),
                                    Some("each sphere once: a sphere cannot touch itself".into()),
                                );
                                ok = false;
                            }
                            nodes.push(i);
                        }
                        Some(NodeRef::Ground) => {
                            cx.error(
                                format!("{what}: the ground cannot be a sphere of the set"),
                                r.span.clone(),
                                Some("list body nodes; the ground plane is given by `ground_point` and `ground_normal`".into()),
                            );
                            ok = false;
                        }
                        None => ok = false,
                    }
                }
            }
            (None, Some(p)) => {
                nodes = model
                    .nodes
                    .iter()
                    .enumerate()
                    .filter(|(_, n)| matches(&p.value, &n.name))
                    .map(|(i, _)| i)
                    .collect();
                if p.value.matches('*').count() > 1 {
                    cx.error(
                        format!(
                            "{what}: `nodes_matching` takes at most one `*` (got '{}')",
                            p.value
                        ),
                        p.span.clone(),
                        Some("e.g. nodes_matching = \"ball_*\"".into()),
                    );
                    ok = false;
                }
                if nodes.is_empty() {
                    cx.error(
                        format!("{what}: no node matches '{}'", p.value),
                        p.span.clone(),
                        Some(
                            "`*` stands for any characters: \"ball_*\" matches ball_1, ball_2, …"
                                .into(),
                        ),
                    );
                    ok = false;
                }
            }
            _ => {
                cx.error(
                    format!("{what}: give either `nodes` or `nodes_matching`"),
                    e.span.clone(),
                    Some("nodes = [\"b1\", \"b2\"] lists the spheres; nodes_matching = \"b*\" takes every node matching".into()),
                );
                ok = false;
            }
        }
        if ok && nodes.len() < 2 {
            cx.error(
                format!("{what}: needs at least two spheres (got {})", nodes.len()),
                e.span.clone(),
                Some("one sphere on the ground is a [[contacts]] entry".into()),
            );
            ok = false;
        }
        let radii = match (gi.radius, &gi.radii) {
            (Some(r), None) => vec![r; nodes.len()],
            (None, Some(v)) => {
                if v.len() != nodes.len() {
                    cx.error(
                        format!(
                            "{what}: `radii` has {} values for {} spheres",
                            v.len(),
                            nodes.len()
                        ),
                        cx.key(&e, "radii"),
                        Some("one radius per node, in the order of `nodes`".into()),
                    );
                    ok = false;
                }
                v.clone()
            }
            _ => {
                cx.error(
                    format!("{what}: give either `radius` or `radii`"),
                    e.span.clone(),
                    Some("radius = 0.05 for equal spheres, radii = [..] one per node".into()),
                );
                ok = false;
                Vec::new()
            }
        };
        if let Some(r) = radii.iter().find(|r| !(r.is_finite() && **r > 0.0)) {
            let key = if gi.radius.is_some() {
                "radius"
            } else {
                "radii"
            };
            cx.error(
                format!("{what}: `{key}` must be positive (got {r})"),
                cx.key(&e, key),
                Some("a sphere has a positive radius [m]".into()),
            );
            ok = false;
        }
        if !(gi.margin.is_finite() && gi.margin > 0.0) {
            cx.error(
                format!("{what}: `margin` must be positive (got {})", gi.margin),
                cx.key(&e, "margin"),
                Some("the Verlet margin [m], e.g. a fifth of the radius: larger means more candidate pairs, smaller more detections".into()),
            );
            ok = false;
        }
        let normal = match gi.ground_normal {
            Some(v) => cx.unit_axis(v, &e, "ground_normal", &what),
            None => Some(Vector3::z()),
        };
        if let Some(p) = gi.ground_point
            && p.iter().any(|x| !x.is_finite())
        {
            cx.error(
                format!("{what}: `ground_point` must be finite (got {p:?})"),
                cx.key(&e, "ground_point"),
                Some("three finite numbers [x, y, z]".into()),
            );
            ok = false;
        }
        let mut walls = Vec::new();
        for w in gi.walls.iter().flatten() {
            let n = cx.unit_axis(w.normal, &e, "walls", &what);
            if w.point.iter().any(|x| !x.is_finite()) {
                cx.error(
                    format!(
                        "{what}: a wall's `point` must be finite (got {:?})",
                        w.point
                    ),
                    cx.key(&e, "walls"),
                    Some("walls = [{ point = [x, y, z], normal = [nx, ny, nz] }, …]".into()),
                );
                ok = false;
            }
            match n {
                Some(normal) => walls.push(GroundPlane {
                    point: Vector3::from(w.point),
                    normal,
                    velocity: Vector3::zeros(),
                }),
                None => ok = false,
            }
        }
        let keys = LawKeys {
            normal: gi.normal,
            stiffness: gi.stiffness,
            exponent: gi.exponent,
            damping_factor: gi.damping_factor,
            restitution: gi.restitution,
            impact_velocity: gi.impact_velocity,
            damping: gi.damping,
            static_friction: gi.static_friction,
            dynamic_friction: gi.dynamic_friction,
            stribeck_velocity: gi.stribeck_velocity,
            bristle_stiffness: gi.bristle_stiffness,
            bristle_damping: gi.bristle_damping,
            viscous_friction: gi.viscous_friction,
            rolling_friction: gi.rolling_friction,
            twisting_friction: gi.twisting_friction,
            rolling_regularization: gi.rolling_regularization,
        };
        let (law, friction, law_ok) = validate_law(cx, &e, &what, &keys);
        ok &= law_ok;
        let (rolling, rolling_ok) = validate_rolling(cx, &e, &what, &keys);
        ok &= rolling_ok;
        let vr = match (gi.static_friction.is_some(), gi.regularization_velocity) {
            (true, Some(v)) if v.is_finite() && v > 0.0 => Some(v),
            (true, Some(v)) => {
                cx.error(
                    format!("{what}: `regularization_velocity` must be positive (got {v})"),
                    cx.key(&e, "regularization_velocity"),
                    Some("v_r [m/s]: below it sphere–sphere friction is viscous; a tenth of `stribeck_velocity` is typical (leave it out for LuGre bristles, which stick)".into()),
                );
                ok = false;
                None
            }
            (false, Some(_)) => {
                cx.error(
                    format!("{what}: `regularization_velocity` does not apply here"),
                    cx.key(&e, "regularization_velocity"),
                    Some("friction is on only with `static_friction` (μ_s)".into()),
                );
                ok = false;
                None
            }
            (_, None) => None,
        };
        let (normal, law) = (normal?, law?);
        ok.then(|| GranularDef {
            name: gi.name.value.clone(),
            node_names: nodes.iter().map(|&i| model.nodes[i].name.clone()).collect(),
            nodes,
            radii,
            margin: gi.margin,
            plane: GroundPlane {
                point: Vector3::from(gi.ground_point.unwrap_or([0.0; 3])),
                normal,
                velocity: Vector3::zeros(),
            },
            walls,
            law,
            friction,
            regularization_velocity: vr,
            rolling,
        })
    }

    /// The pairs change during a run: only the generalized-α dynamic analysis follows
    /// them (statics and the linearized analyses would see no sphere–sphere contact).
    fn finish(input: &ModelInput, cx: &mut Checker, _model: &Model) {
        let Some(g) = input.granular.first() else {
            return;
        };
        for a in &input.analyses {
            if a.value.kind.value != AnalysisType::Dynamic {
                cx.error(
                    format!(
                        "analysis '{}': granular set '{}' needs a dynamic analysis",
                        a.value.name.value, g.value.name.value
                    ),
                    a.value.kind.span.clone(),
                    Some("the sphere pairs are found during time integration; statics and the linearized analyses do not see them".into()),
                );
            }
        }
    }

    fn nodes(def: &GranularDef) -> Vec<usize> {
        def.nodes.clone()
    }

    fn build(def: &GranularDef, parts: &mut Build) {
        for ((&node, &radius), node_name) in def.nodes.iter().zip(&def.radii).zip(&def.node_names) {
            parts.elements.push(Box::new(
                Contact::new(
                    format!("{}.ground.{node_name}", def.name),
                    node,
                    ContactShape::Sphere { radius },
                    def.plane,
                    def.law,
                    def.friction,
                )
                .with_rolling(def.rolling),
            ));
            for (k, wall) in def.walls.iter().enumerate() {
                parts.elements.push(Box::new(Contact::new(
                    format!("{}.wall{}.{node_name}", def.name, k + 1),
                    node,
                    ContactShape::Sphere { radius },
                    *wall,
                    def.law,
                    None,
                )));
            }
        }
        parts.granular.push(GranularSet {
            name: def.name.clone(),
            nodes: def.nodes.clone(),
            radii: def.radii.clone(),
            law: def.law,
            friction: def
                .friction
                .map(|friction| match def.regularization_velocity {
                    Some(regularization_velocity) => PairFriction::Regularized {
                        friction,
                        regularization_velocity,
                    },
                    None => PairFriction::LuGre(friction),
                }),
            margin: def.margin,
            rolling: def.rolling,
        });
    }

    /// The set's pair contact at generic spinning states, in contact: regularized
    /// friction, frictionless, and LuGre with the condensed bristle (a start deflection,
    /// over a step and at the state); its ground contacts are `[[contacts]]`' elements.
    fn tangent_cases() -> Vec<TangentCase> {
        let friction = Friction {
            static_coefficient: 0.6,
            dynamic_coefficient: 0.3,
            stribeck_velocity: 0.5,
            bristle_stiffness: 40.0,
            bristle_damping: 2.0,
            viscous: 0.1,
        };
        let law = NormalLaw::HuntCrossley {
            stiffness: 3e3,
            exponent: 1.5,
            damping_factor: 0.2,
        };
        (0..5u64)
            .map(|k| {
                let a = random_node(980 + k);
                let b = random_node(985 + k);
                let dist = (b.x - a.x).norm();
                let set = GranularSet {
                    name: "g".into(),
                    nodes: vec![0, 1],
                    radii: vec![0.55 * dist, 0.5 * dist],
                    law,
                    friction: match k {
                        0 => Some(PairFriction::Regularized {
                            friction,
                            regularization_velocity: 0.1,
                        }),
                        1 => None,
                        _ => Some(PairFriction::LuGre(friction)),
                    },
                    margin: 0.01,
                    // k = 4: with rolling and twisting resistance.
                    rolling: (k == 4).then_some(RollingResistance {
                        rolling: 0.1,
                        twisting: 0.3,
                        regularization: 0.5,
                    }),
                };
                let mut e: SpherePair = set.pair(0, 1);
                let step = if k >= 2 { 0.05 } else { 0.0 };
                e.set_bristle(Vector3::new(0.004, -0.007, 0.002), step);
                TangentCase::element(Box::new(e), vec![a, b])
            })
            .collect()
    }
}
