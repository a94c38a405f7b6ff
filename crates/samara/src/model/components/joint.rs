//! `[[joints]]`: the joint library (kernel: [`crate::joints::Joint`], rows of Table I in
//! [`crate::joints::rows`]) and the elements on its free components.

use super::{Build, ComponentKind};
use crate::core::{Coordinate, NodeRef};
use crate::joints::{
    BacklashDef, ComponentDef, ForceLaw, Joint, JointDef, JointType, rows::has_coordinate,
};
use crate::math::{Rotation, TimeFunction};
use crate::model::input::*;
use crate::model::validate::{Checker, Entry};
use crate::model::{Located, Model};
use crate::tangent_check::{TangentCase, random_node};
use nalgebra::{Matrix3, Vector3};
use schemars::JsonSchema;
use serde::Deserialize;

/// What is attached to one free component (joint coordinate) of a joint. Forces act on
/// the coordinate: a positive spring force resists an increase of the coordinate.
#[derive(Clone, Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ComponentInput {
    /// Linear spring: stiffness k [N/m or N m/rad], force k (ν − `rest`).
    #[serde(default)]
    pub stiffness: Option<f64>,
    /// Rest value of the linear spring [m or rad] (default 0).
    #[serde(default)]
    pub rest: Option<f64>,
    /// Nonlinear spring: [[ν, F], …] with increasing ν; piecewise linear, extended
    /// linearly beyond the ends with the end slopes.
    #[serde(default)]
    pub spring_table: Option<Vec<[f64; 2]>>,
    /// Linear viscous damper c [N s/m or N m s/rad], force c ν̇.
    #[serde(default)]
    pub damping: Option<f64>,
    /// Nonlinear damper: [[ν̇, F], …] with increasing ν̇, piecewise linear.
    #[serde(default)]
    pub damper_table: Option<Vec<[f64; 2]>>,
    /// Dead band of free play with contact stiffness and damping outside it.
    #[serde(default)]
    pub backlash: Option<BacklashInput>,
    /// Drive: the coordinate follows this time function [m or rad]; the force it takes
    /// is written out as `joint_coordinate_force`.
    #[serde(default)]
    pub drive: Option<Located<TimeFunctionInput>>,
    /// Input port: a force/torque [N or N m] taken from the named signal, acting to
    /// increase the coordinate.
    #[serde(default)]
    pub input: Option<Located<String>>,
    /// Servo: the coordinate follows the named signal [m or rad] (a `[[signals]]` time
    /// function, a sensor's or a controller's output), ν − s = 0; the force it takes is
    /// written out as `joint_coordinate_force`. Exclusive with `drive`.
    #[serde(default)]
    pub drive_signal: Option<Located<String>>,
}
/// Free play |ν − center| ≤ width/2; beyond it a contact force k g + c ν̇ (g the
/// penetration) pushes back.
#[derive(Clone, Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BacklashInput {
    /// Total width of the dead band [m or rad], positive.
    pub width: f64,
    /// Contact stiffness [N/m or N m/rad], positive.
    pub stiffness: f64,
    /// Contact damping [N s/m or N m s/rad], non-negative (default 0).
    #[serde(default)]
    pub damping: Option<f64>,
    /// Centre of the dead band [m or rad] (default 0).
    #[serde(default)]
    pub center: Option<f64>,
}

/// A joint between two nodes (or a node and the ground).
///
/// The joint frame (origin and axes) is given in the reference (initial) configuration,
/// in global components, or in the frame of the node named by `relative_to`. Frame A is
/// fixed to node A and frame B to node B; both coincide with the joint frame initially,
/// unless `offset_a`/`offset_b` place the origin on each node separately (the initial
/// assembly then moves the nodes onto the constraints).
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct JointInput {
    /// Unique joint name.
    pub name: Located<String>,
    /// Joint type.
    #[serde(rename = "type")]
    pub kind: Located<JointType>,
    /// Node carrying frame A (`ground` for the inertial frame).
    pub node_a: Located<String>,
    /// Node carrying frame B (`ground` for the inertial frame).
    pub node_b: Located<String>,
    /// Give `position`, `axis`, `axis_1` and `orientation` in this node's frame (relative
    /// to its origin) instead of global components.
    #[serde(default)]
    pub relative_to: Option<Located<String>>,
    /// Origin of the joint frame [m]; default: the position of node B (of node A if B is
    /// the ground).
    #[serde(default)]
    pub position: Option<[f64; 3]>,
    /// Joint axis e₃ (hinge, slide or screw axis; plane normal; shaft of a universal
    /// joint); need not be unit length.
    #[serde(default)]
    pub axis: Option<[f64; 3]>,
    /// Axis e₁, orthogonal to `axis` (the cross arm on A of a universal joint; the d1
    /// direction of a planar joint). Default: a direction normal to `axis`.
    #[serde(default)]
    pub axis_1: Option<[f64; 3]>,
    /// Full joint frame orientation; alternative to `axis`/`axis_1`. Default: global axes.
    #[serde(default)]
    pub orientation: Option<OrientationInput>,
    /// Origin of frame A in node A's frame [m], overriding `position` on side A.
    #[serde(default)]
    pub offset_a: Option<[f64; 3]>,
    /// Origin of frame B in node B's frame [m], overriding `position` on side B.
    #[serde(default)]
    pub offset_b: Option<[f64; 3]>,
    /// Screw pitch p [m/rad]: d3 = p θ3 (screw joints only).
    #[serde(default)]
    pub pitch: Option<f64>,
    /// Relative displacement along e₁ᴬ (free in planar, point_on_plane, prescribed).
    #[serde(default)]
    pub d1: Option<Located<ComponentInput>>,
    /// Relative displacement along e₂ᴬ.
    #[serde(default)]
    pub d2: Option<Located<ComponentInput>>,
    /// Relative displacement along e₃ᴬ.
    #[serde(default)]
    pub d3: Option<Located<ComponentInput>>,
    /// Relative rotation θ1.
    #[serde(default)]
    pub theta1: Option<Located<ComponentInput>>,
    /// Relative rotation θ2.
    #[serde(default)]
    pub theta2: Option<Located<ComponentInput>>,
    /// Relative rotation θ3.
    #[serde(default)]
    pub theta3: Option<Located<ComponentInput>>,
}

pub struct JointKind;

impl ComponentKind for JointKind {
    const NOUN: &'static str = "joint";
    type Input = JointInput;
    type Def = JointDef;

    /// Constraint rows at the end of the step, forces from the rows' discrete gradient
    /// (`Constraint::discrete_jacobian`, docs/integrators.md); input ports and servos (`drive_signal`) are refused
    /// when the analysis starts.
    fn discrete_form(_input: &JointInput) -> Result<(), String> {
        Ok(())
    }

    fn name(input: &JointInput) -> &Located<String> {
        &input.name
    }

    fn validate(j: &Located<JointInput>, cx: &mut Checker, model: &mut Model) -> Option<JointDef> {
        cx.joint(j, model)
    }

    /// Servo checks once every signal producer is known: a `drive_signal` that reads the
    /// same coordinate's value through blocks with feedthrough only (an unfiltered
    /// sensor on it, gains, sums, …) makes the row ν − s(ν) = 0 an algebraic loop
    /// (singular for a unit gain); the stabilized index-2 formulation has no servo rows.
    fn finish(input: &super::ModelInput, cx: &mut Checker, model: &Model) {
        use crate::model::AnalysisKind;
        // Feedthrough inputs of each signal's producer.
        let edges = super::feedthrough::feedthrough_edges(cx, model);
        let through: std::collections::HashMap<&str, Vec<&str>> = edges
            .iter()
            .map(|(k, (ins, _))| (k.as_str(), ins.iter().map(|s| s.as_str()).collect()))
            .collect();
        let stabilized = model.analyses.iter().any(|a| {
            matches!(&a.kind, AnalysisKind::Dynamic(d) if d.formulation == FormulationType::StabilizedIndex2)
        });
        for ji in &input.joints {
            let ji = &ji.value;
            let comps = [&ji.d1, &ji.d2, &ji.d3, &ji.theta1, &ji.theta2, &ji.theta3];
            for (c, comp) in comps.iter().enumerate() {
                let Some(ds) = comp.as_ref().and_then(|x| x.value.drive_signal.as_ref()) else {
                    continue;
                };
                let what = format!(
                    "joint '{}', `{}`",
                    ji.name.value,
                    crate::joints::COMPONENT_NAMES[c]
                );
                if stabilized {
                    cx.error(
                        format!("{what}: a `drive_signal` (servo) is not supported by the stabilized_index2 formulation"),
                        ds.span.clone(),
                        Some("use formulation = \"index3\" with rho_inf < 1 in the dynamic analyses".into()),
                    );
                }
                let own = format!(
                    "coordinate:{}.{}",
                    ji.name.value,
                    crate::joints::COMPONENT_NAMES[c]
                );
                // Depth-first over feedthrough edges from the servo's signal.
                let mut path: Vec<&str> = Vec::new();
                let mut stack: Vec<(&str, usize)> = vec![(ds.value.as_str(), 0)];
                let mut seen: std::collections::HashSet<&str> = Default::default();
                let mut found = None;
                while let Some((name, depth)) = stack.pop() {
                    path.truncate(depth);
                    path.push(name);
                    if name == own {
                        found = Some(path.clone());
                        break;
                    }
                    if !seen.insert(name) {
                        continue;
                    }
                    for &i in through.get(name).map(Vec::as_slice).unwrap_or(&[]) {
                        stack.push((i, depth + 1));
                    }
                }
                if let Some(chain) = found {
                    cx.error(
                        format!(
                            "{what}: algebraic loop: the servo's signal depends on the coordinate it drives without a state in between ({})",
                            chain.join(" ← ")
                        ),
                        ds.span.clone(),
                        Some("ν − s(ν) = 0 has no solution to follow (singular for a unit gain): filter the measurement (a sensor with time_constant > 0) or command the coordinate from another quantity".into()),
                    );
                }
            }
        }
    }

    fn nodes(def: &JointDef) -> Vec<usize> {
        [def.node_a, def.node_b]
            .iter()
            .filter_map(|r| r.index())
            .collect()
    }

    fn build(def: &JointDef, parts: &mut Build) {
        parts
            .constraints
            .push(Box::new(Joint::new(def, parts.initial)));
    }

    fn tangent_cases() -> Vec<TangentCase> {
        use JointType::*;
        let kinds = [
            Fixed,
            Revolute,
            Prismatic,
            Screw,
            Cylindrical,
            Planar,
            Spherical,
            Universal,
            PointOnLine,
            PointOnPlane,
            Prescribed,
        ];
        let mut out = Vec::new();
        for (k, &kind) in kinds.iter().enumerate() {
            let seed = 100 + 10 * k as u64;
            let nodes = vec![random_node(seed), random_node(seed + 1)];
            let axes = Rotation::exp(&Vector3::new(0.3, -0.2, 0.5))
                .matrix()
                .to_owned();
            let mut def = JointDef::new(
                "joint",
                kind,
                NodeRef::Node(0),
                NodeRef::Node(1),
                Vector3::new(0.1, 0.2, 0.3),
                axes,
            );
            def.pitch = 0.05;
            // A spring, a damper and an input on every free component, so every
            // coordinate is an unknown; a drive on the first.
            let mut first = true;
            let mut servo_placed = false;
            for c in 0..6 {
                if has_coordinate(kind, c) {
                    def.components[c] = Some(ComponentDef {
                        spring: Some(ForceLaw::Linear {
                            coefficient: 50.0,
                            reference: 0.1,
                        }),
                        damper: Some(ForceLaw::Linear {
                            coefficient: 3.0,
                            reference: 0.0,
                        }),
                        backlash: Some(BacklashDef {
                            center: 0.0,
                            half_width: 0.01,
                            stiffness: 1e3,
                            damping: 2.0,
                        }),
                        drive: first.then_some(TimeFunction::Sine {
                            amplitude: 0.1,
                            frequency: 1.0,
                            phase: 0.2,
                            offset: 0.0,
                            start: 0.0,
                        }),
                        input: Some("push".into()),
                        // A servo on the second coordinate (the row the system completes
                        // with the signal's derivatives).
                        drive_signal: (!first && !servo_placed).then(|| "command".into()),
                    });
                    servo_placed |= !first;
                    first = false;
                }
            }
            let joint = Joint::new(&def, &nodes);
            let n = crate::core::Constraint::n_coordinates(&joint);
            let m = crate::core::Constraint::n_equations(&joint);
            let coords = (0..n)
                .map(|i| Coordinate {
                    q: 0.05 * i as f64 - 0.02,
                    v: 0.3 - 0.1 * i as f64,
                    a: 0.2,
                })
                .collect();
            let mu = (0..m).map(|i| 1.0 + 0.37 * i as f64).collect();
            out.push(TangentCase::constraint(Box::new(joint), nodes, coords, mu));
        }
        out
    }
}

impl Checker<'_> {
    fn joint(&mut self, j: &Located<JointInput>, model: &Model) -> Option<JointDef> {
        let e = Entry {
            span: j.span.clone(),
        };
        let ji = &j.value;
        let kind = ji.kind.value;
        let what = format!("joint '{}'", ji.name.value);
        let a = self.node_ref(&ji.node_a, &what);
        let b = self.node_ref(&ji.node_b, &what);
        let (a, b) = (a?, b?);
        if a == b {
            let msg = if a == NodeRef::Ground {
                format!("{what} connects the ground to itself")
            } else {
                format!("{what} connects node '{}' to itself", ji.node_a.value)
            };
            self.error(
                msg,
                ji.node_b.span.clone(),
                Some("a joint needs two different nodes (or a node and 'ground')".into()),
            );
            return None;
        }
        // Frame in which position and axes are given.
        let (origin, rot) = match &ji.relative_to {
            None => (Vector3::zeros(), Matrix3::identity()),
            Some(r) => match self.node_ref(r, &what)? {
                NodeRef::Ground => (Vector3::zeros(), Matrix3::identity()),
                NodeRef::Node(i) => (
                    model.nodes[i].position,
                    *model.nodes[i].orientation.matrix(),
                ),
            },
        };
        let position = match ji.position {
            Some(p) => {
                if !self.finite(&e, "position", &p, &what) {
                    return None;
                }
                origin + rot * Vector3::from(p)
            }
            None => {
                let n = b.index().or(a.index()).unwrap_or(0);
                model.nodes.get(n).map(|n| n.position).unwrap_or_default()
            }
        };
        if ji.orientation.is_some() && (ji.axis.is_some() || ji.axis_1.is_some()) {
            self.error(
                format!("{what}: give either `axis` (and `axis_1`) or `orientation`, not both"),
                self.key(&e, "orientation"),
                None,
            );
            return None;
        }
        let needs_axis = !matches!(
            kind,
            JointType::Fixed | JointType::Spherical | JointType::Prescribed
        );
        let local_axes = if let Some(axis) = ji.axis {
            let e3 = self.unit_axis(axis, &e, "axis", &what)?;
            match ji.axis_1 {
                None => crate::model::validate::frame_from_axis(&e3),
                Some(a1) => {
                    let e1 = self.unit_axis(a1, &e, "axis_1", &what)?;
                    let c = e1.dot(&e3);
                    if c.abs() > 1e-6 {
                        self.error(
                            format!(
                                "{what}: `axis_1` is not orthogonal to `axis` (cosine {c:.3e}, angle {:.4}°)",
                                c.clamp(-1.0, 1.0).acos().to_degrees()
                            ),
                            self.key(&e, "axis_1"),
                            Some("the joint axes must be orthogonal to within 1e-6; give e₁ normal to e₃".into()),
                        );
                        return None;
                    }
                    let e1 = (e1 - e3 * c).normalize();
                    Matrix3::from_columns(&[e1, e3.cross(&e1), e3])
                }
            }
        } else if ji.axis_1.is_some() {
            self.error(
                format!("{what}: `axis_1` needs `axis`"),
                self.key(&e, "axis_1"),
                Some("give the joint axis e₃ as `axis` too".into()),
            );
            return None;
        } else if let Some(o) = &ji.orientation {
            *self.orientation(o, &e, &what)?.matrix()
        } else {
            if needs_axis {
                self.error(
                    format!("{what}: a {} joint needs `axis` (or `orientation`, whose z axis is the joint axis)", kind.name()),
                    e.span.clone(),
                    Some("add e.g. `axis = [0.0, 1.0, 0.0]`".into()),
                );
                return None;
            }
            Matrix3::identity()
        };
        let axes = rot * local_axes;
        // Per-side origins.
        let side = |this: &mut Self,
                    r: NodeRef,
                    off: Option<[f64; 3]>,
                    key: &str|
         -> Option<Vector3<f64>> {
            match off {
                None => Some(position),
                Some(o) => {
                    if !this.finite(&e, key, &o, &what) {
                        return None;
                    }
                    Some(match r {
                        NodeRef::Ground => Vector3::from(o),
                        NodeRef::Node(i) => {
                            model.nodes[i].position
                                + model.nodes[i].orientation.matrix() * Vector3::from(o)
                        }
                    })
                }
            }
        };
        let position_a = side(self, a, ji.offset_a, "offset_a")?;
        let position_b = side(self, b, ji.offset_b, "offset_b")?;
        let pitch = match (kind, ji.pitch) {
            (JointType::Screw, Some(p)) if p.is_finite() => p,
            (JointType::Screw, _) => {
                self.error(
                    format!("{what}: a screw joint needs a finite `pitch` [m/rad]"),
                    if ji.pitch.is_some() {
                        self.key(&e, "pitch")
                    } else {
                        ji.kind.span.clone()
                    },
                    Some(
                        "d3 = pitch · θ3; e.g. a 2 mm lead is pitch = 0.002 / (2π) = 3.183e-4"
                            .into(),
                    ),
                );
                return None;
            }
            (_, Some(_)) => {
                self.error(
                    format!("{what}: `pitch` is only used by screw joints"),
                    self.key(&e, "pitch"),
                    None,
                );
                return None;
            }
            (_, None) => 0.0,
        };
        let inputs = [&ji.d1, &ji.d2, &ji.d3, &ji.theta1, &ji.theta2, &ji.theta3];
        let mut components: [Option<ComponentDef>; 6] = Default::default();
        let mut ok = true;
        for (c, input) in inputs.iter().enumerate() {
            let Some(ci) = input else { continue };
            let name = crate::joints::COMPONENT_NAMES[c];
            let free =
                crate::joints::rows::is_free(kind, c) && !(kind == JointType::Screw && c == 2);
            if !free {
                let list: Vec<&str> = (0..6)
                    .filter(|&k| {
                        crate::joints::rows::is_free(kind, k)
                            && !(kind == JointType::Screw && k == 2)
                    })
                    .map(|k| crate::joints::COMPONENT_NAMES[k])
                    .collect();
                let hint = if list.is_empty() {
                    format!("a {} joint has no free component", kind.name())
                } else {
                    format!(
                        "the free components of a {} joint are: {}",
                        kind.name(),
                        list.join(", ")
                    )
                };
                self.error(
                    format!("{what}: `{name}` is constrained by a {} joint; nothing can be attached to it", kind.name()),
                    ci.span.clone().or(e.span.clone()),
                    Some(hint),
                );
                ok = false;
                continue;
            }
            let cw = format!("{what}, `{name}`");
            match self.component(ci, &cw) {
                Some(d) => components[c] = Some(d),
                None => ok = false,
            }
        }
        if !ok {
            return None;
        }
        Some(JointDef {
            name: ji.name.value.clone(),
            kind,
            node_a: a,
            node_b: b,
            position_a,
            position_b,
            axes,
            pitch,
            components,
        })
    }
    /// A piecewise-linear force law from `[[x, F], …]`.
    fn force_table(
        &mut self,
        pts: &[[f64; 2]],
        e: &Entry,
        key: &str,
        what: &str,
    ) -> Option<ForceLaw> {
        if pts.len() < 2 {
            self.error(
                format!("{what}: `{key}` needs at least two points"),
                self.key(e, key),
                Some("points are [[x0, F0], [x1, F1], …] with x0 < x1 < …".into()),
            );
            return None;
        }
        if !pts.iter().flatten().all(|x| x.is_finite()) {
            self.error(
                format!("{what}: `{key}` must be finite"),
                self.key(e, key),
                None,
            );
            return None;
        }
        if pts.windows(2).any(|w| w[1][0] <= w[0][0]) {
            self.error(
                format!("{what}: the first column of `{key}` must be strictly increasing"),
                self.key(e, key),
                Some("points are [[x0, F0], [x1, F1], …] with x0 < x1 < …".into()),
            );
            return None;
        }
        Some(ForceLaw::Table {
            x: pts.iter().map(|p| p[0]).collect(),
            f: pts.iter().map(|p| p[1]).collect(),
        })
    }
    fn component(&mut self, ci: &Located<ComponentInput>, what: &str) -> Option<ComponentDef> {
        let e = Entry {
            span: ci.span.clone(),
        };
        let c = &ci.value;
        let mut ok = true;
        let mut nonneg = |this: &mut Self, v: Option<f64>, key: &str| -> Option<f64> {
            let x = v?;
            if !(x.is_finite() && x >= 0.0) {
                this.error(
                    format!("{what}: `{key}` must be ≥ 0 (got {x})"),
                    this.key(&e, key),
                    None,
                );
                ok = false;
                return None;
            }
            Some(x)
        };
        let stiffness = nonneg(self, c.stiffness, "stiffness");
        let damping = nonneg(self, c.damping, "damping");
        let rest = c.rest.unwrap_or(0.0);
        if !rest.is_finite() {
            self.error(
                format!("{what}: `rest` must be finite"),
                self.key(&e, "rest"),
                None,
            );
            ok = false;
        }
        if c.rest.is_some() && c.stiffness.is_none() {
            self.error(
                format!(
                    "{what}: `rest` is the rest value of a linear spring and needs `stiffness`"
                ),
                self.key(&e, "rest"),
                None,
            );
            ok = false;
        }
        let mut spring = stiffness.map(|k| ForceLaw::Linear {
            coefficient: k,
            reference: rest,
        });
        if let Some(t) = &c.spring_table {
            if c.stiffness.is_some() {
                self.error(
                    format!("{what}: give either `stiffness` or `spring_table`, not both"),
                    self.key(&e, "spring_table"),
                    None,
                );
                ok = false;
            }
            spring = self.force_table(t, &e, "spring_table", what);
            ok &= spring.is_some();
        }
        let mut damper = damping.map(|c| ForceLaw::Linear {
            coefficient: c,
            reference: 0.0,
        });
        if let Some(t) = &c.damper_table {
            if c.damping.is_some() {
                self.error(
                    format!("{what}: give either `damping` or `damper_table`, not both"),
                    self.key(&e, "damper_table"),
                    None,
                );
                ok = false;
            }
            damper = self.force_table(t, &e, "damper_table", what);
            ok &= damper.is_some();
        }
        let backlash = match &c.backlash {
            None => None,
            Some(b) => {
                let bad = |this: &mut Self, msg: String| {
                    this.error(
                        format!("{what}: backlash {msg}"),
                        this.key(&e, "backlash"),
                        Some(
                            "backlash = { width = 0.01, stiffness = 1e6, damping = 100.0 }".into(),
                        ),
                    );
                };
                let damping = b.damping.unwrap_or(0.0);
                let center = b.center.unwrap_or(0.0);
                if !(b.width.is_finite() && b.width > 0.0) {
                    bad(self, format!("`width` must be positive (got {})", b.width));
                    ok = false;
                    None
                } else if !(b.stiffness.is_finite() && b.stiffness > 0.0) {
                    bad(
                        self,
                        format!("`stiffness` must be positive (got {})", b.stiffness),
                    );
                    ok = false;
                    None
                } else if !(damping.is_finite() && damping >= 0.0 && center.is_finite()) {
                    bad(self, "`damping` must be ≥ 0 and `center` finite".into());
                    ok = false;
                    None
                } else {
                    Some(BacklashDef {
                        center,
                        half_width: 0.5 * b.width,
                        stiffness: b.stiffness,
                        damping,
                    })
                }
            }
        };
        let drive = match &c.drive {
            None => None,
            Some(f) => {
                let d = self.time_function(f, &format!("{what} drive"));
                ok &= d.is_some();
                d
            }
        };
        let input = self.known_signal(c.input.as_ref(), what, "input");
        ok &= c.input.is_none() || input.is_some();
        let drive_signal = self.known_signal(c.drive_signal.as_ref(), what, "drive_signal");
        ok &= c.drive_signal.is_none() || drive_signal.is_some();
        if let (Some(_), Some(ds)) = (&c.drive, &c.drive_signal) {
            self.error(
                format!("{what}: give either `drive` (a time function) or `drive_signal` (a signal), not both"),
                ds.span.clone(),
                Some("a [[signals]] entry turns a time function into a signal: drive_signal = \"name\" with [[signals]] name = \"name\", function = { … }".into()),
            );
            ok = false;
        }
        ok.then_some(ComponentDef {
            spring,
            damper,
            backlash,
            drive,
            input,
            drive_signal,
        })
    }

    /// The signal named by `key` if some entry produces it; otherwise a located error
    /// with the closest known name.
    fn known_signal(
        &mut self,
        name: Option<&Located<String>>,
        what: &str,
        key: &str,
    ) -> Option<String> {
        let name = name?;
        if self.signal_names.contains_key(&name.value) {
            return Some(name.value.clone());
        }
        let known: Vec<String> = self.signal_names.keys().cloned().collect();
        let hint = match self.suggest(&name.value, known.iter().map(|s| s.as_str())) {
            Some(b) => format!("did you mean '{b}'?"),
            None => "declare it in a [[signals]] table (name and function), or name a sensor's or a controller's output".into(),
        };
        self.error(
            format!("{what}: `{key}` names an unknown signal '{}'", name.value),
            name.span.clone(),
            Some(hint),
        );
        None
    }
}
