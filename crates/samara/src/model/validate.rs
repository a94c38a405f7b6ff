//! Checks a [`ModelInput`] and builds the [`Model`], collecting every error with its
//! location in the file and a hint.

use super::error::{Diagnostic, ModelError, Severity, SourceFile, did_you_mean};
use super::input::*;
use super::located::Located;
use super::*;
use crate::diagnostics::number_range_diagnostics;
use crate::math::Rotation;
use nalgebra::{Matrix3, Vector3};
use std::collections::HashMap;
use std::ops::Range;

/// The name of the fixed inertial frame in node references.
pub const GROUND: &str = "ground";

/// Validates a parsed model file.
pub fn validate(input: &ModelInput, source: SourceFile) -> Result<LoadedModel, ModelError> {
    let mut v = Checker {
        source: &source,
        diags: Vec::new(),
        node_map: HashMap::new(),
        signal_names: HashMap::new(),
        suggestions_left: MAX_SUGGESTIONS,
    };
    // Numbers out of range are the root cause of whatever else they would break: report
    // them alone.
    let out_of_range = number_range_diagnostics(&source.text);
    if !out_of_range.is_empty() {
        return Err(ModelError {
            source: source.clone(),
            diagnostics: out_of_range,
        });
    }
    let model = v.model(input);
    if v.diags.iter().any(|d| d.severity == Severity::Error) {
        return Err(ModelError {
            source: source.clone(),
            diagnostics: v.diags,
        });
    }
    Ok(LoadedModel {
        model,
        warnings: v.diags,
        source,
    })
}

/// The validation context shared by every component kind: diagnostics with their
/// locations, the nodes known so far, the signals produced, and the checks many kinds use
/// (node references, orientations, time functions, finite numbers).
pub struct Checker<'a> {
    pub(crate) source: &'a SourceFile,
    pub(crate) diags: Vec<Diagnostic>,
    /// Node name → index (beams add the nodes they create).
    pub(crate) node_map: HashMap<String, usize>,
    /// Every signal the model produces, with where it is declared.
    pub(crate) signal_names: HashMap<String, Option<Range<usize>>>,
    /// Unknown-name errors that still get a "did you mean" (each costs a pass over the
    /// names; a file with thousands of bad references must not take quadratic time).
    suggestions_left: usize,
}

/// How many unknown references get a spelling suggestion.
const MAX_SUGGESTIONS: usize = 100;

/// Where an entry's keys live in the file.
#[derive(Clone)]
pub struct Entry {
    pub(crate) span: Option<Range<usize>>,
}

impl<'a> Checker<'a> {
    pub(crate) fn error(
        &mut self,
        message: impl Into<String>,
        span: Option<Range<usize>>,
        hint: Option<String>,
    ) {
        let mut d = Diagnostic::error(message, span);
        d.hint = hint;
        self.diags.push(d);
    }

    pub(crate) fn warning(
        &mut self,
        message: impl Into<String>,
        span: Option<Range<usize>>,
        hint: Option<String>,
    ) {
        let mut d = Diagnostic::warning(message, span);
        d.hint = hint;
        self.diags.push(d);
    }

    /// Span of `key = value` inside an entry, pointing at the value; the entry's span if
    /// the key cannot be found (e.g. the model was built in code).
    pub(crate) fn key(&self, entry: &Entry, key: &str) -> Option<Range<usize>> {
        self.locate_key(entry, key).map(|(span, _)| span)
    }

    /// The spelling of a key with aliases that the entry uses (the first of `names` if it
    /// uses none), so that messages name and point at what the user wrote.
    pub(crate) fn spelling<'k>(&self, entry: &Entry, names: &[&'k str]) -> &'k str {
        let found = |n: &&&str| matches!(self.locate_key(entry, n), Some((_, true)));
        names
            .iter()
            .find(found)
            .or(names.first())
            .copied()
            .unwrap_or("")
    }

    /// [`Self::key`], and whether the key was found (`false`: the entry's span).
    fn locate_key(&self, entry: &Entry, key: &str) -> Option<(Range<usize>, bool)> {
        let mut span = entry.span.clone()?;
        // An array-of-tables entry may be spanned by its header only: extend the search to
        // the next table header. (Inline tables are spanned whole; extending them would
        // scan the rest of the file for every key.)
        let full = &self.source.text;
        if full.get(span.clone()).is_some_and(|t| t.starts_with('['))
            && let Some(rest) = full.get(span.end..)
        {
            let next = rest.find("\n[").map_or(full.len(), |i| span.end + i);
            span.end = span.end.max(next);
        }
        let text = self.source.text.get(span.clone())?;
        let bytes = text.as_bytes();
        let mut from = 0;
        while let Some(pos) = text[from..].find(key) {
            let start = from + pos;
            let end = start + key.len();
            let before_ok = start == 0
                || matches!(bytes[start - 1], b' ' | b'\t' | b'\n' | b'{' | b',' | b'\r');
            let rest = &text[end..];
            let trimmed = rest.trim_start_matches([' ', '\t']);
            if before_ok && trimmed.starts_with('=') {
                let value_start = end + (rest.len() - trimmed.len()) + 1;
                let after = &text[value_start..];
                let lead = after.len() - after.trim_start_matches([' ', '\t']).len();
                let vs = value_start + lead;
                let ve = text[vs..]
                    .find(['\n', '#'])
                    .map_or(text.len(), |i| vs + i)
                    .max(vs + 1)
                    .min(text.len());
                let value = text[vs..ve].trim_end();
                return Some((span.start + vs..span.start + vs + value.len().max(1), true));
            }
            from = end;
        }
        Some((span, false))
    }

    /// Span of `key = value` in the top-level table `[table]`, if the file has one.
    pub(crate) fn header_key(&self, table: &str, key: &str) -> Option<Range<usize>> {
        let text = &self.source.text;
        let header = format!("[{table}]");
        let start = text
            .match_indices(&header)
            .map(|(i, _)| i)
            .find(|&i| i == 0 || text.as_bytes()[i - 1] == b'\n')?;
        let entry = Entry {
            span: Some(start..start + header.len()),
        };
        self.key(&entry, key)
    }

    pub(crate) fn finite(&mut self, entry: &Entry, key: &str, values: &[f64], what: &str) -> bool {
        if values
            .iter()
            .all(|x| x.is_finite() && x.abs() <= MAX_MAGNITUDE)
        {
            true
        } else {
            self.error(
                format!("{what}: `{key}` must be finite and at most {MAX_MAGNITUDE:e} in magnitude (got {values:?})"),
                self.key(entry, key),
                Some("inf and nan are not allowed in a model".into()),
            );
            false
        }
    }

    pub(crate) fn unique_names<T>(
        &mut self,
        items: &[Located<T>],
        name: impl Fn(&T) -> &Located<String>,
        kind: &str,
    ) {
        let mut seen: HashMap<&str, Option<Range<usize>>> = HashMap::new();
        for it in items {
            let n = name(&it.value);
            if n.value.trim().is_empty() {
                self.error(
                    format!("{kind} name is empty"),
                    n.span.clone(),
                    Some("give every entry a unique, non-empty name".into()),
                );
                continue;
            }
            if let Some(first) = seen.get(n.value.as_str()) {
                let hint = match first {
                    Some(s) => {
                        let (l, c) = self.source.line_col(s.start);
                        format!(
                            "the first {kind} named '{}' is at line {l}, column {c}; names must be unique",
                            n.value
                        )
                    }
                    None => "names must be unique".to_string(),
                };
                self.error(
                    format!("duplicate {kind} name '{}'", n.value),
                    n.span.clone(),
                    Some(hint),
                );
            } else {
                seen.insert(n.value.as_str(), n.span.clone());
            }
        }
    }

    /// A "did you mean" for the first [`MAX_SUGGESTIONS`] unknown names; `None` after.
    pub(crate) fn suggest<'n>(
        &mut self,
        word: &str,
        candidates: impl IntoIterator<Item = &'n str>,
    ) -> Option<&'n str> {
        if self.suggestions_left == 0 {
            return None;
        }
        self.suggestions_left -= 1;
        did_you_mean(word, candidates)
    }

    /// A node reference resolved against the nodes known so far.
    pub(crate) fn node_ref(&mut self, r: &Located<String>, what: &str) -> Option<NodeRef> {
        let map = std::mem::take(&mut self.node_map);
        let out = self.node_ref_in(r, &map, what);
        self.node_map = map;
        out
    }

    pub(crate) fn node_ref_in(
        &mut self,
        r: &Located<String>,
        nodes: &HashMap<String, usize>,
        what: &str,
    ) -> Option<NodeRef> {
        if r.value == GROUND {
            return Some(NodeRef::Ground);
        }
        if let Some(&i) = nodes.get(&r.value) {
            return Some(NodeRef::Node(i));
        }
        let hint = if self.suggestions_left > 0 {
            self.suggestions_left -= 1;
            let candidates = nodes.keys().map(|s| s.as_str()).chain([GROUND]);
            match did_you_mean(&r.value, candidates) {
                Some(best) => format!("did you mean '{best}'?"),
                None => {
                    let mut names: Vec<&str> = nodes.keys().map(|s| s.as_str()).collect();
                    names.sort_unstable();
                    names.truncate(8);
                    format!("known nodes: {} (and 'ground')", names.join(", "))
                }
            }
        } else {
            "the node must be listed in [[nodes]] or created by a beam; 'ground' is the fixed frame"
                .to_string()
        };
        self.error(
            format!("{what}: unknown node '{}'", r.value),
            r.span.clone(),
            Some(hint),
        );
        None
    }

    pub(crate) fn orientation(
        &mut self,
        o: &OrientationInput,
        entry: &Entry,
        what: &str,
    ) -> Option<Rotation> {
        let forms = [
            o.quaternion.is_some(),
            o.rotation_vector.is_some(),
            o.matrix.is_some(),
            o.x_axis.is_some() || o.y_axis.is_some() || o.z_axis.is_some(),
        ];
        let span = self.key(entry, "orientation");
        let n = forms.iter().filter(|&&f| f).count();
        if n != 1 {
            self.error(
                format!("{what}: orientation must be given in exactly one form (found {n})"),
                span,
                Some("use one of `quaternion`, `rotation_vector`, `matrix`, or two of `x_axis`/`y_axis`/`z_axis`".into()),
            );
            return None;
        }
        if let Some(q) = o.quaternion {
            let nrm = (q.iter().map(|x| x * x).sum::<f64>()).sqrt();
            if !nrm.is_finite() || (nrm - 1.0).abs() > 1e-6 {
                self.error(
                    format!("{what}: quaternion {q:?} is not of unit length (norm {nrm})"),
                    span,
                    Some("a rotation quaternion (w, x, y, z) has w² + x² + y² + z² = 1".into()),
                );
                return None;
            }
            let uq = nalgebra::UnitQuaternion::new_normalize(nalgebra::Quaternion::new(
                q[0], q[1], q[2], q[3],
            ));
            return Some(Rotation::from_quaternion(uq));
        }
        if let Some(p) = o.rotation_vector {
            if !p.iter().all(|x| x.is_finite()) {
                self.error(
                    format!("{what}: rotation vector must be finite"),
                    span,
                    None,
                );
                return None;
            }
            return Some(Rotation::exp(&Vector3::from(p)));
        }
        if let Some(m) = o.matrix {
            let r = Matrix3::from_fn(|i, j| m[i][j]);
            let err = (r.transpose() * r - Matrix3::identity()).norm();
            if !err.is_finite() || err > 1e-6 || r.determinant() < 0.0 {
                self.error(
                    format!("{what}: matrix is not a rotation (‖RᵀR − I‖ = {err:.2e}, det = {:.3})", r.determinant()),
                    span,
                    Some("a rotation matrix is orthonormal with determinant +1; rows are given in order".into()),
                );
                return None;
            }
            return Some(Rotation::from_matrix(&r));
        }
        // Two axes.
        let axes = [o.x_axis, o.y_axis, o.z_axis];
        let given: Vec<usize> = (0..3).filter(|&i| axes[i].is_some()).collect();
        if given.len() != 2 {
            self.error(
                format!(
                    "{what}: give exactly two of `x_axis`, `y_axis`, `z_axis` (found {})",
                    given.len()
                ),
                span,
                None,
            );
            return None;
        }
        let (i, j) = (given[0], given[1]);
        let a = Vector3::from(axes[i].unwrap_or_default());
        let b = Vector3::from(axes[j].unwrap_or_default());
        let Some(m) = frame_from_two_axes(i, &a, j, &b) else {
            self.error(
                format!("{what}: the two axes must be non-zero and not parallel"),
                span,
                None,
            );
            return None;
        };
        Some(Rotation::from_matrix(&m))
    }

    pub(crate) fn time_function(
        &mut self,
        f: &Located<TimeFunctionInput>,
        what: &str,
    ) -> Option<TimeFunction> {
        let entry = Entry {
            span: f.span.clone(),
        };
        let t = &f.value;
        let given: [(&str, bool); 14] = [
            ("value", t.value.is_some()),
            ("start", t.start.is_some()),
            ("end", t.end.is_some()),
            ("from", t.from.is_some()),
            ("to", t.to.is_some()),
            ("time", t.time.is_some()),
            ("before", t.before.is_some()),
            ("after", t.after.is_some()),
            ("amplitude", t.amplitude.is_some()),
            ("frequency", t.frequency.is_some()),
            ("phase", t.phase.is_some()),
            ("offset", t.offset.is_some()),
            ("points", t.points.is_some()),
            ("coefficients", t.coefficients.is_some()),
        ];
        let (kind, allowed, required): (&str, &[&str], &[&str]) = match t.kind {
            TimeFunctionType::Constant => ("constant", &["value"], &["value"]),
            TimeFunctionType::Ramp => (
                "ramp",
                &["start", "end", "from", "to"],
                &["start", "end", "to"],
            ),
            TimeFunctionType::Step => ("step", &["time", "before", "after"], &["time", "after"]),
            TimeFunctionType::Sine => (
                "sine",
                &["amplitude", "frequency", "phase", "offset", "start"],
                &["amplitude", "frequency"],
            ),
            TimeFunctionType::Table => ("table", &["points"], &["points"]),
            TimeFunctionType::Polynomial => {
                ("polynomial", &["coefficients", "start"], &["coefficients"])
            }
        };
        let mut ok = true;
        for (k, g) in given {
            if g && !allowed.contains(&k) {
                self.error(
                    format!("{what}: `{k}` is not used by a {kind} function"),
                    self.key(&entry, k),
                    Some(format!("a {kind} function takes: {}", allowed.join(", "))),
                );
                ok = false;
            }
        }
        for k in required {
            if !given.iter().any(|(n, g)| n == k && *g) {
                self.error(
                    format!("{what}: a {kind} function needs `{k}`"),
                    f.span.clone(),
                    Some(format!("a {kind} function takes: {}", allowed.join(", "))),
                );
                ok = false;
            }
        }
        let nums: Vec<f64> = [
            t.value,
            t.start,
            t.end,
            t.from,
            t.to,
            t.time,
            t.before,
            t.after,
            t.amplitude,
            t.frequency,
            t.phase,
            t.offset,
        ]
        .iter()
        .flatten()
        .copied()
        .collect();
        if !nums.iter().all(|x| x.is_finite()) {
            self.error(
                format!("{what}: time-function values must be finite"),
                f.span.clone(),
                None,
            );
            ok = false;
        }
        if !ok {
            return None;
        }
        let func = match t.kind {
            TimeFunctionType::Constant => TimeFunction::Constant(t.value.unwrap_or(0.0)),
            TimeFunctionType::Ramp => {
                let (s, e) = (t.start.unwrap_or(0.0), t.end.unwrap_or(0.0));
                if e <= s {
                    self.error(
                        format!("{what}: ramp `end` ({e}) must be after `start` ({s})"),
                        self.key(&entry, "end"),
                        None,
                    );
                    return None;
                }
                TimeFunction::Ramp {
                    start: s,
                    end: e,
                    from: t.from.unwrap_or(0.0),
                    to: t.to.unwrap_or(0.0),
                }
            }
            TimeFunctionType::Step => TimeFunction::Step {
                time: t.time.unwrap_or(0.0),
                before: t.before.unwrap_or(0.0),
                after: t.after.unwrap_or(0.0),
            },
            TimeFunctionType::Sine => TimeFunction::Sine {
                amplitude: t.amplitude.unwrap_or(0.0),
                frequency: t.frequency.unwrap_or(0.0),
                phase: t.phase.unwrap_or(0.0),
                offset: t.offset.unwrap_or(0.0),
                start: t.start.unwrap_or(0.0),
            },
            TimeFunctionType::Table => {
                let pts = t.points.clone().unwrap_or_default();
                let span = self.key(&entry, "points");
                if pts.is_empty() {
                    self.error(
                        format!("{what}: table needs at least one point"),
                        span,
                        None,
                    );
                    return None;
                }
                if !pts.iter().flatten().all(|x| x.is_finite()) {
                    self.error(format!("{what}: table points must be finite"), span, None);
                    return None;
                }
                if pts.windows(2).any(|w| w[1][0] <= w[0][0]) {
                    self.error(
                        format!("{what}: table times must be strictly increasing"),
                        span,
                        Some("points are [[t0, f0], [t1, f1], …] with t0 < t1 < …".into()),
                    );
                    return None;
                }
                TimeFunction::Table {
                    times: pts.iter().map(|p| p[0]).collect(),
                    values: pts.iter().map(|p| p[1]).collect(),
                }
            }
            TimeFunctionType::Polynomial => {
                let c = t.coefficients.clone().unwrap_or_default();
                if c.is_empty() || !c.iter().all(|x| x.is_finite()) {
                    self.error(
                        format!("{what}: polynomial `coefficients` must be a non-empty list of finite numbers"),
                        self.key(&entry, "coefficients"),
                        Some("e.g. coefficients = [0.0, 6.2832] for f(t) = 6.2832 t".into()),
                    );
                    return None;
                }
                TimeFunction::Polynomial {
                    coefficients: c,
                    start: t.start.unwrap_or(0.0),
                }
            }
        };
        Some(func)
    }

    fn model(&mut self, input: &ModelInput) -> Model {
        let gravity = Vector3::from(input.model.gravity.unwrap_or([0.0; 3]));
        if !gravity.iter().all(|x| x.is_finite()) {
            let span = self.header_key("model", "gravity");
            self.error(
                format!("`gravity` must be finite (got {:?})", gravity.as_slice()),
                span,
                Some("give the gravitational acceleration in m/s², e.g. [0.0, 0.0, -9.81]".into()),
            );
        }
        let mut model = Model {
            name: input.model.name.clone(),
            description: input.model.description.clone(),
            gravity,
            ..Default::default()
        };

        // Nodes.
        self.unique_names(&input.nodes, |n| &n.name, "node");
        for n in &input.nodes {
            let e = Entry {
                span: n.span.clone(),
            };
            let ni = &n.value;
            let what = format!("node '{}'", ni.name.value);
            if ni.name.value == GROUND {
                self.error(
                    "the node name 'ground' is reserved for the fixed inertial frame",
                    ni.name.span.clone(),
                    Some(
                        "rename the node; refer to the inertial frame as 'ground' in joints".into(),
                    ),
                );
            }
            self.finite(&e, "position", &ni.position, &what);
            let velocity = ni.velocity.unwrap_or([0.0; 3]);
            self.finite(&e, "velocity", &velocity, &what);
            let omega = ni.angular_velocity.unwrap_or([0.0; 3]);
            self.finite(&e, "angular_velocity", &omega, &what);
            let orientation = match &ni.orientation {
                Some(o) => self.orientation(o, &e, &what).unwrap_or_default(),
                None => Rotation::identity(),
            };
            self.node_map
                .entry(ni.name.value.clone())
                .or_insert(model.nodes.len());
            model.nodes.push(NodeDef {
                name: ni.name.value.clone(),
                position: Vector3::from(ni.position),
                orientation,
                velocity: Vector3::from(velocity),
                angular_velocity: Vector3::from(omega),
            });
        }

        // Components, in the order of the registry.
        super::components::validate_all(input, self, &mut model);

        // Analyses.
        self.unique_names(&input.analyses, |a| &a.name, "analysis");
        for (k, a) in input.analyses.iter().enumerate() {
            if let Some(def) = self.analysis(a, &input.analyses[..k], &model, input) {
                model.analyses.push(def);
            }
        }
        super::components::finish_all(input, self, &model);
        if input.analyses.is_empty() {
            self.warning("the model has no [[analyses]]: nothing will run", None, Some("add e.g. [[analyses]] name = \"run\", type = \"dynamic\", t_end = 1.0, step = 1e-3".into()));
        }
        if model.nodes.is_empty() {
            self.warning("the model has no nodes", None, None);
        }
        // Nodes that nothing touches are free and massless: their equations are singular.
        let used = super::components::nodes_used(&model);
        for (i, n) in input.nodes.iter().enumerate() {
            if i < used.len() && !used[i] {
                self.error(
                    format!("node '{}' is not used by any body, joint or spring", n.value.name.value),
                    n.value.name.span.clone(),
                    Some("a node without mass, stiffness or constraint has no equation; remove it or attach something".into()),
                );
            }
        }
        model
    }

    /// A unit vector from a `key = [x, y, z]` entry, or an error.
    pub(crate) fn unit_axis(
        &mut self,
        v: [f64; 3],
        e: &Entry,
        key: &str,
        what: &str,
    ) -> Option<Vector3<f64>> {
        let ax = Vector3::from(v);
        let n = ax.norm();
        if !n.is_finite() || n < 1e-12 {
            self.error(
                format!("{what}: `{key}` must be a non-zero vector (got {v:?})"),
                self.key(e, key),
                Some("an axis is a direction, e.g. [0.0, 1.0, 0.0]".into()),
            );
            return None;
        }
        Some(ax / n)
    }

    /// The steady rotation of a `rotation = { axis, omega, centre }` entry.
    fn steady_rotation(
        &mut self,
        r: &super::input::RotationInput,
        e: &Entry,
        what: &str,
        campbell: bool,
    ) -> Option<crate::linear::SteadyRotation> {
        let axis = self.unit_axis(r.axis, e, "axis", &format!("{what}: `rotation`"));
        let centre = Vector3::from(r.centre.unwrap_or([0.0; 3]));
        let omega = match (r.omega, campbell) {
            (Some(w), false) => w,
            (None, true) => 0.0,
            (None, false) => {
                self.error(
                    format!("{what}: `rotation` needs `omega`, the angular speed [rad/s]"),
                    self.key(e, "rotation"),
                    Some("e.g. rotation = { axis = [0.0, 0.0, 1.0], omega = 40.0 }".into()),
                );
                return None;
            }
            (Some(_), true) => {
                self.error(
                    format!("{what}: a Campbell analysis takes its speeds from `speeds`, not `rotation.omega`"),
                    self.key(e, "rotation"),
                    Some("give `rotation = { axis, centre }` and `speeds = [...]`".into()),
                );
                return None;
            }
        };
        if !(omega.is_finite()
            && omega.abs() <= MAX_MAGNITUDE
            && centre
                .iter()
                .all(|x| x.is_finite() && x.abs() <= MAX_MAGNITUDE))
        {
            self.error(
                format!("{what}: `rotation` needs a finite `omega` and `centre`"),
                self.key(e, "rotation"),
                None,
            );
            return None;
        }
        Some(crate::linear::SteadyRotation {
            axis: axis?,
            omega,
            centre,
        })
    }

    /// The eigensolution keys shared by modal and Campbell analyses (`n_modes`, `shift`,
    /// `eigensolver`), parsed in one place; `ok` is cleared on an error.
    fn eigen_settings(
        &mut self,
        ai: &AnalysisInput,
        e: &Entry,
        what: &str,
        ok: &mut bool,
    ) -> ModalSettings {
        let mut m = ModalSettings::default();
        if let Some(n) = &ai.n_modes {
            if n.value == 0 {
                self.error(
                    format!("{what}: `n_modes` must be at least 1"),
                    n.span.clone(),
                    None,
                );
                *ok = false;
            }
            m.n_modes = n.value;
        }
        if let Some(f) = ai.shift {
            if !(f.is_finite() && f >= 0.0) {
                self.error(
                    format!("{what}: `shift` must be a frequency ≥ 0 Hz (got {f})"),
                    self.key(e, "shift"),
                    Some("the modes nearest this frequency are computed; leave it out for the lowest modes".into()),
                );
                *ok = false;
            }
            m.shift = Some(f);
        }
        m.eigensolver = ai.eigensolver.unwrap_or_default();
        m
    }

    /// Node indices (ascending, distinct) of the nodes, beams and bodies named in `parts`.
    fn spinning_nodes(
        &mut self,
        parts: &[Located<String>],
        model: &Model,
        what: &str,
    ) -> Option<Vec<usize>> {
        let mut nodes = Vec::new();
        let mut ok = true;
        for p in parts {
            let name = p.value.as_str();
            let before = nodes.len();
            if let Some(i) = model.node_index(name) {
                nodes.push(i);
            }
            for b in model.beams.iter().filter(|b| b.name == name) {
                nodes.extend_from_slice(&b.nodes);
            }
            for b in model.bodies.iter().filter(|b| b.name == name) {
                nodes.push(b.node);
            }
            if nodes.len() == before {
                let candidates: Vec<&str> = model
                    .beams
                    .iter()
                    .map(|b| b.name.as_str())
                    .chain(model.bodies.iter().map(|b| b.name.as_str()))
                    .chain(model.nodes.iter().map(|n| n.name.as_str()))
                    .collect();
                let hint = match self.suggest(name, candidates) {
                    Some(b) => format!("did you mean '{b}'?"),
                    None => "`parts` lists names of [[nodes]], [[beams]] and [[bodies]]".into(),
                };
                self.error(
                    format!("{what}: `rotation.parts`: no node, beam or body is named '{name}'"),
                    p.span.clone(),
                    Some(hint),
                );
                ok = false;
            }
        }
        nodes.sort_unstable();
        nodes.dedup();
        ok.then_some(nodes)
    }

    fn analysis(
        &mut self,
        a: &Located<AnalysisInput>,
        earlier: &[Located<AnalysisInput>],
        model: &Model,
        input: &ModelInput,
    ) -> Option<AnalysisDef> {
        let e = Entry {
            span: a.span.clone(),
        };
        let ai = &a.value;
        let what = format!("analysis '{}'", ai.name.value.escape_debug());
        let kind = ai.kind.value;
        if !ai.name.value.trim().is_empty() && !is_plain_file_name(&ai.name.value) {
            self.error(
                format!("{what}: the name becomes the results file name `<name>.nc` and must be plain"),
                ai.name.span.clone(),
                Some("use letters, digits, `_`, `-` and `.` only (no `/`, spaces or control characters, not starting with `.`), at most 128 characters".into()),
            );
            return None;
        }
        // Named as written (`min_step` or its alias `step_min`).
        let min_key = self.spelling(&e, super::input::MIN_STEP_SPELLINGS);
        // `scaling` multiplies rows and multipliers by βh²: there is no step in statics.
        let dynamic_keys: [(&str, bool); 16] = [
            ("partition", ai.partition.is_some()),
            ("output_interval", ai.output_interval.is_some()),
            ("step_control", ai.step_control.is_some()),
            ("event_location", ai.event_location.is_some()),
            ("tolerance_abs", ai.tolerance_abs.is_some()),
            ("tolerance_rel", ai.tolerance_rel.is_some()),
            ("step_max", ai.step_max.is_some()),
            ("scaling", ai.scaling.is_some()),
            ("formulation", ai.formulation.is_some()),
            ("t_start", ai.t_start.is_some()),
            ("t_end", ai.t_end.is_some()),
            ("step", ai.step.is_some()),
            ("rho_inf", ai.rho_inf.is_some()),
            (min_key, ai.min_step.is_some()),
            ("output_every", ai.output_every.is_some()),
            ("jacobian", ai.jacobian.is_some()),
        ];
        let static_keys: [(&str, bool); 2] = [
            ("load_steps", ai.load_steps.is_some()),
            ("time", ai.time.is_some()),
        ];
        let modal_keys: [(&str, bool); 4] = [
            ("n_modes", ai.n_modes.is_some()),
            ("shift", ai.shift.is_some()),
            ("write_matrices", ai.write_matrices.is_some()),
            ("eigensolver", ai.eigensolver.is_some()),
        ];
        let campbell_keys: [(&str, bool); 1] = [("speeds", ai.speeds.is_some())];
        let floquet_keys: [(&str, bool); 3] = [
            ("period", ai.period.is_some()),
            ("speed", ai.speed.is_some()),
            ("steps_per_period", ai.steps_per_period.is_some()),
        ];
        // A modal analysis solves no nonlinear equations.
        let newton_keys: [(&str, bool); 6] = [
            ("penalty", ai.penalty.is_some()),
            ("tolerance", ai.tolerance.is_some()),
            ("relative_tolerance", ai.relative_tolerance.is_some()),
            ("max_iterations", ai.max_iterations.is_some()),
            ("diagnostics", ai.diagnostics.is_some()),
            ("linear_solver", ai.linear_solver.is_some()),
        ];
        let (wrong, tname): (Vec<(&str, bool)>, &str) = match kind {
            AnalysisType::Dynamic => (
                [
                    &static_keys[..],
                    &modal_keys,
                    &[("rotation", ai.rotation.is_some())],
                ]
                .concat(),
                "dynamic",
            ),
            AnalysisType::Static => (
                [&dynamic_keys[..], &modal_keys, &campbell_keys].concat(),
                "static",
            ),
            AnalysisType::Modal => (
                [
                    &dynamic_keys[..],
                    &static_keys,
                    &newton_keys,
                    &campbell_keys,
                ]
                .concat(),
                "modal",
            ),
            AnalysisType::Campbell => (
                [
                    &dynamic_keys[..],
                    &[("write_matrices", ai.write_matrices.is_some())],
                ]
                .concat(),
                "campbell",
            ),
            AnalysisType::Floquet => (
                [
                    &dynamic_keys
                        .iter()
                        .copied()
                        .filter(|(k, _)| *k != "rho_inf")
                        .collect::<Vec<_>>()[..],
                    &static_keys,
                    &modal_keys
                        .iter()
                        .copied()
                        .filter(|(k, _)| *k != "n_modes")
                        .collect::<Vec<_>>(),
                    &campbell_keys,
                    &[("rotation", ai.rotation.is_some())],
                ]
                .concat(),
                "floquet",
            ),
        };
        let wrong = if kind == AnalysisType::Dynamic {
            [&wrong[..], &campbell_keys].concat()
        } else {
            wrong
        };
        let wrong = if kind == AnalysisType::Floquet {
            wrong
        } else {
            [&wrong[..], &floquet_keys].concat()
        };
        let mut ok = true;
        for (k, g) in &wrong {
            if *g {
                self.error(
                    format!("{what}: `{k}` is not used by a {tname} analysis"),
                    self.key(&e, k),
                    Some("see docs/model-reference.md for the keys of each analysis type".into()),
                );
                ok = false;
            }
        }
        let start_from = match &ai.start_from {
            None => None,
            Some(s) => match earlier
                .iter()
                .position(|x| x.value.name.value == s.value.analysis())
            {
                Some(i) => Some(i),
                None => {
                    let hint = match self.suggest(
                        s.value.analysis(),
                        earlier.iter().map(|x| x.value.name.value.as_str()),
                    ) {
                        Some(b) => format!("did you mean '{b}'?"),
                        None => "`start_from` names an analysis listed before this one".to_string(),
                    };
                    self.error(
                        format!("{what}: unknown earlier analysis '{}'", s.value.analysis()),
                        s.span.clone(),
                        Some(hint),
                    );
                    ok = false;
                    None
                }
            },
        };
        let start_time = match (&ai.start_from, start_from) {
            (Some(s), Some(i)) => match s.value.time() {
                None => None,
                Some(t) => {
                    let from = &earlier[i].value;
                    // t_start's default is the dynamic analysis's own (0); a missing t_end
                    // is reported on that analysis, so there is no range to check here.
                    let range = (from.kind.value == AnalysisType::Dynamic)
                        .then(|| (from.t_start.unwrap_or(0.0), from.t_end));
                    match range {
                        None => {
                            self.error(
                                format!("{what}: `start_from.time` needs a dynamic analysis, and '{}' is not one", from.name.value),
                                s.span.clone(),
                                Some(format!("write start_from = \"{}\" to start from its final state", from.name.value)),
                            );
                            ok = false;
                        }
                        Some((_, None)) => {}
                        Some((t0, Some(t1))) => {
                            let slack = 1e-12 * t0.abs().max(t1.abs()).max(1.0);
                            if !(t.is_finite() && t >= t0 - slack && t <= t1 + slack) {
                                self.error(
                                    format!("{what}: `start_from.time` = {t} is outside the run of '{}' ({t0} … {t1} s)", from.name.value),
                                    s.span.clone(),
                                    Some("give a time between that analysis's t_start and t_end; the state stored nearest it is used".into()),
                                );
                                ok = false;
                            }
                        }
                    }
                    Some(t)
                }
            },
            _ => None,
        };
        let mut solver = SolverSettings::default();
        if let Some(s) = ai.scaling {
            solver.scaling = s;
        }
        if let Some(p) = ai.penalty {
            if !(p.is_finite() && p >= 0.0) {
                self.error(
                    format!("{what}: penalty must be ≥ 0 (got {p})"),
                    self.key(&e, "penalty"),
                    None,
                );
                ok = false;
            }
            solver.penalty = p;
        }
        if let Some(t) = ai.tolerance {
            if !(t.is_finite() && t > 0.0) {
                self.error(
                    format!("{what}: tolerance must be positive (got {t})"),
                    self.key(&e, "tolerance"),
                    None,
                );
                ok = false;
            }
            solver.tolerance = t;
        }
        if let Some(t) = ai.relative_tolerance {
            if !(t.is_finite() && t >= 0.0) {
                self.error(
                    format!("{what}: relative_tolerance must be ≥ 0 (got {t})"),
                    self.key(&e, "relative_tolerance"),
                    None,
                );
                ok = false;
            }
            solver.relative_tolerance = t;
        }
        if let Some(m) = ai.max_iterations {
            if m == 0 {
                self.error(
                    format!("{what}: max_iterations must be at least 1"),
                    self.key(&e, "max_iterations"),
                    None,
                );
                ok = false;
            }
            solver.max_iterations = m;
        }
        solver.diagnostics = ai.diagnostics.unwrap_or(false);
        solver.linear_solver = ai.linear_solver.unwrap_or_default();

        let kind = match kind {
            AnalysisType::Dynamic => {
                let t_start = ai.t_start.unwrap_or(0.0);
                let Some(t_end) = ai.t_end else {
                    self.error(
                        format!("{what}: a dynamic analysis needs `t_end`"),
                        e.span.clone(),
                        Some("add e.g. `t_end = 1.0` (seconds)".into()),
                    );
                    return None;
                };
                let Some(step) = ai.step else {
                    self.error(
                        format!("{what}: a dynamic analysis needs `step`"),
                        e.span.clone(),
                        Some("add e.g. `step = 1e-3` (seconds)".into()),
                    );
                    return None;
                };
                if !(t_start.is_finite() && t_end.is_finite() && t_end > t_start) {
                    self.error(
                        format!("{what}: `t_end` ({t_end}) must be after `t_start` ({t_start})"),
                        self.key(&e, "t_end"),
                        None,
                    );
                    ok = false;
                }
                if !(step.is_finite() && step > 0.0) {
                    self.error(
                        format!("{what}: `step` must be positive (got {step})"),
                        self.key(&e, "step"),
                        None,
                    );
                    ok = false;
                } else if step > t_end - t_start {
                    self.error(
                        format!(
                            "{what}: `step` ({step}) is longer than the analysis ({})",
                            t_end - t_start
                        ),
                        self.key(&e, "step"),
                        None,
                    );
                    ok = false;
                }
                // Every step must move time: at least 64 ulps of the largest time, and no
                // more steps than could ever be taken.
                let resolution = 64.0 * f64::EPSILON * t_start.abs().max(t_end.abs());
                if ok && step.is_finite() && step > 0.0 {
                    let steps = (t_end - t_start) / step;
                    if step <= resolution {
                        self.error(
                            format!("{what}: `step` ({step:e}) is below the resolution of time near t = {t_end:e} ({resolution:.1e}): t_end cannot be reached"),
                            self.key(&e, "step"),
                            Some("use a larger step, or shift `t_start`/`t_end` towards 0".into()),
                        );
                        ok = false;
                    } else if steps > 1e12 {
                        self.error(
                            format!("{what}: {steps:.3e} steps of {step:e} s from t_start to t_end; at most 10¹² can be taken"),
                            self.key(&e, "step"),
                            Some("use a larger step or a shorter time span".into()),
                        );
                        ok = false;
                    }
                }
                let rho = ai.rho_inf.unwrap_or(0.9);
                if !(0.0..=1.0).contains(&rho) {
                    self.error(
                        format!("{what}: `rho_inf` must be in [0, 1] (got {rho})"),
                        self.key(&e, "rho_inf"),
                        Some("ρ∞ = 1 is no numerical dissipation, ρ∞ = 0 annihilates the highest frequencies in one step".into()),
                    );
                    ok = false;
                }
                let min_step = match ai.min_step {
                    Some(m) => m,
                    None => (step / 1024.0).max(2.0 * resolution).min(step),
                };
                if !(min_step.is_finite() && min_step > 0.0 && min_step <= step) {
                    self.error(
                        format!("{what}: `{min_key}` must be in (0, step] (got {min_step})"),
                        self.key(&e, min_key),
                        None,
                    );
                    ok = false;
                } else if ai.min_step.is_some() && min_step <= resolution {
                    self.error(
                        format!("{what}: `{min_key}` ({min_step:e}) is below the resolution of time near t = {t_end:e} ({resolution:.1e})"),
                        self.key(&e, min_key),
                        Some(format!("a step that small would not move time; use a larger `{min_key}`")),
                    );
                    ok = false;
                }
                let output_every = ai.output_every.unwrap_or(1);
                if output_every == 0 {
                    self.error(
                        format!("{what}: `output_every` must be at least 1"),
                        self.key(&e, "output_every"),
                        None,
                    );
                    ok = false;
                }
                if let Some(dt) = ai.output_interval {
                    if ai.output_every.is_some() {
                        self.error(
                            format!("{what}: give `output_interval` or `output_every`, not both"),
                            self.key(&e, "output_interval"),
                            Some("`output_interval` records at fixed times, `output_every` every n-th step".into()),
                        );
                        ok = false;
                    } else if !(dt.is_finite() && dt > 0.0) {
                        self.error(
                            format!(
                                "{what}: `output_interval` must be a positive time [s] (got {dt})"
                            ),
                            self.key(&e, "output_interval"),
                            None,
                        );
                        ok = false;
                    } else if dt <= resolution || (t_end - t_start) / dt > 1e12 {
                        self.error(
                            format!("{what}: `output_interval` ({dt:e}) gives more than 10¹² records, or is below the resolution of time near t = {t_end:e} ({resolution:.1e})"),
                            self.key(&e, "output_interval"),
                            Some("use a larger interval".into()),
                        );
                        ok = false;
                    }
                }
                let formulation = ai.formulation.unwrap_or(if rho >= 1.0 {
                    FormulationType::StabilizedIndex2
                } else {
                    FormulationType::Index3
                });
                // The stabilized formulation enforces Φ = 0 by projection: no penalty term.
                if ai.penalty.is_some() && formulation == FormulationType::StabilizedIndex2 {
                    self.error(
                        format!("{what}: `penalty` is not used by the stabilized_index2 formulation"),
                        self.key(&e, "penalty"),
                        Some(format!(
                            "the augmented-Lagrangian penalty belongs to formulation = \"index3\"{}; remove `penalty` or choose index3 (with rho_inf < 1)",
                            if ai.formulation.is_none() { " (rho_inf = 1 selects stabilized_index2)" } else { "" }
                        )),
                    );
                    ok = false;
                }
                let adaptive = match ai.step_control.unwrap_or_default() {
                    StepControlType::Fixed => {
                        for (k, given) in [
                            ("tolerance_abs", ai.tolerance_abs.is_some()),
                            ("tolerance_rel", ai.tolerance_rel.is_some()),
                            ("step_max", ai.step_max.is_some()),
                            ("event_location", ai.event_location.is_some()),
                        ] {
                            if given {
                                self.error(
                                    format!("{what}: `{k}` is used only with adaptive steps"),
                                    self.key(&e, k),
                                    Some(
                                        "add `step_control = \"adaptive\"`, or remove the key"
                                            .into(),
                                    ),
                                );
                                ok = false;
                            }
                        }
                        None
                    }
                    StepControlType::Adaptive => {
                        let tolerance_abs = ai.tolerance_abs.unwrap_or(1e-6);
                        let tolerance_rel = ai.tolerance_rel.unwrap_or(1e-4);
                        for (k, v) in [
                            ("tolerance_abs", tolerance_abs),
                            ("tolerance_rel", tolerance_rel),
                        ] {
                            if !(v.is_finite() && v >= 0.0) {
                                self.error(
                                    format!("{what}: `{k}` must be ≥ 0 (got {v})"),
                                    self.key(&e, k),
                                    None,
                                );
                                ok = false;
                            }
                        }
                        if ok && tolerance_abs == 0.0 && tolerance_rel == 0.0 {
                            self.error(
                                format!("{what}: `tolerance_abs` and `tolerance_rel` are both 0"),
                                self.key(&e, "tolerance_abs"),
                                Some("the error control needs a positive tolerance, e.g. tolerance_abs = 1e-6".into()),
                            );
                            ok = false;
                        }
                        let step_max = ai.step_max.unwrap_or(t_end - t_start);
                        if !(step_max.is_finite() && step_max >= step) {
                            self.error(
                                format!("{what}: `step_max` must be at least `step` ({step}) (got {step_max})"),
                                self.key(&e, "step_max"),
                                Some(format!("`step` is the first step; the error control chooses the others in [{min_key}, step_max]")),
                            );
                            ok = false;
                        }
                        Some(AdaptiveSettings {
                            tolerance_abs,
                            tolerance_rel,
                            step_max,
                            event_location: ai.event_location.unwrap_or(true),
                        })
                    }
                };
                let integrator = ai.integrator.unwrap_or_default();
                if integrator != IntegratorType::GeneralizedAlpha {
                    let scheme = if integrator == IntegratorType::EnergyPreserving {
                        "energy_preserving"
                    } else {
                        "energy_decaying"
                    };
                    for (k, given) in [
                        ("step_control", ai.step_control.is_some()),
                        ("formulation", ai.formulation.is_some()),
                        ("penalty", ai.penalty.is_some()),
                        ("jacobian", ai.jacobian.is_some()),
                        ("partition", ai.partition.is_some()),
                        ("scaling", ai.scaling.is_some()),
                        ("linear_solver", ai.linear_solver.is_some()),
                        ("diagnostics", ai.diagnostics.is_some()),
                        (
                            "rho_inf",
                            ai.rho_inf.is_some() && integrator == IntegratorType::EnergyPreserving,
                        ),
                    ] {
                        if given {
                            self.error(
                                format!("{what}: `{k}` is not used by integrator = \"{scheme}\""),
                                self.key(&e, k),
                                Some(if k == "rho_inf" {
                                    "the preserving scheme has no dissipation; choose integrator = \"energy_decaying\" to set rho_inf".into()
                                } else {
                                    "the energy-consistent integrators take fixed steps, enforce Φ = 0 at the end of each step and form their own Newton matrix; remove the key".into()
                                }),
                            );
                            ok = false;
                        }
                    }
                    if integrator == IntegratorType::EnergyDecaying
                        && (0.0..IntegratorType::DECAYING_MIN_RHO_INF).contains(&rho)
                    {
                        self.error(
                            format!("{what}: `rho_inf` must be in [1/3, 1] for integrator = \"energy_decaying\" (got {rho})"),
                            self.key(&e, "rho_inf"),
                            Some("the energy-decaying scheme's strongest dissipation is ρ∞ = 1/3 (docs/integrators.md); for more use integrator = \"generalized_alpha\"".into()),
                        );
                        ok = false;
                    }
                    if let Some((body, other)) = super::components::body::offset_body_sharing_node(
                        &input.bodies,
                        &input.beams,
                    ) {
                        self.error(
                            format!("{what}: integrator = \"{scheme}\": body `{body}` has a `cg_offset` and its node also carries {other}"),
                            self.key(&e, "integrator"),
                            Some("these integrators write the node's kinematics for the body's CG: give the body a node of its own, joined by a `fixed` joint".into()),
                        );
                        ok = false;
                    }
                    if let Some((table, entry, why)) =
                        super::components::without_discrete_form(input)
                    {
                        self.error(
                            format!("{what}: integrator = \"{scheme}\" has no discrete form for {table} `{entry}`: {why}"),
                            self.key(&e, "integrator"),
                            Some("use integrator = \"generalized_alpha\" for this model; docs/integrators.md lists the kinds with discrete forms".into()),
                        );
                        ok = false;
                    }
                }
                AnalysisKind::Dynamic(DynamicSettings {
                    t_start,
                    t_end,
                    step,
                    rho_inf: rho,
                    min_step,
                    output_every,
                    output_interval: ai.output_interval,
                    jacobian: ai.jacobian.unwrap_or_default(),
                    formulation,
                    solver,
                    adaptive,
                    integrator,
                    partition: ai.partition.unwrap_or_default(),
                })
            }
            AnalysisType::Static => {
                let load_steps = ai.load_steps.unwrap_or(1);
                if load_steps == 0 {
                    self.error(
                        format!("{what}: `load_steps` must be at least 1"),
                        self.key(&e, "load_steps"),
                        None,
                    );
                    ok = false;
                }
                let time = ai.time.unwrap_or(0.0);
                if !time.is_finite() {
                    self.error(
                        format!("{what}: `time` must be finite"),
                        self.key(&e, "time"),
                        None,
                    );
                    ok = false;
                }
                let rotation = match &ai.rotation {
                    None => None,
                    Some(r) => match self.steady_rotation(r, &e, &what, false) {
                        Some(rotation) => {
                            let nodes = match &r.parts {
                                None => None,
                                Some(parts) => {
                                    let n = self.spinning_nodes(parts, model, &what);
                                    ok &= n.is_some();
                                    n
                                }
                            };
                            Some(crate::linear::Spin { rotation, nodes })
                        }
                        None => {
                            ok = false;
                            None
                        }
                    },
                };
                AnalysisKind::Static(StaticSettings {
                    load_steps,
                    time,
                    solver,
                    rotation,
                })
            }
            AnalysisType::Modal => {
                let mut m = self.eigen_settings(ai, &e, &what, &mut ok);
                m.write_matrices = ai.write_matrices.unwrap_or(false);
                if let Some(r) = &ai.rotation {
                    if let Some(p) = r.parts.as_ref().and_then(|p| p.first()) {
                        self.error(
                            format!("{what}: `rotation.parts` is not used by a modal analysis"),
                            p.span.clone(),
                            Some("a modal analysis is written in the frame turning with the whole model; `parts` selects the spinning nodes of a static analysis".into()),
                        );
                        ok = false;
                    }
                    m.rotation = self.steady_rotation(r, &e, &what, false);
                    ok &= m.rotation.is_some();
                } else if let Some(i) = start_from {
                    // A modal analysis of a spinning static state is written in its frame.
                    if let Some(AnalysisKind::Static(StaticSettings {
                        rotation: Some(spin),
                        ..
                    })) =
                        (model.analyses.len() == earlier.len()).then(|| &model.analyses[i].kind)
                        && spin.is_whole_model(model.nodes.len())
                    {
                        m.rotation = Some(spin.rotation);
                    }
                }
                AnalysisKind::Modal(m)
            }
            AnalysisType::Campbell => {
                let m = self.eigen_settings(ai, &e, &what, &mut ok);
                let rotation = match &ai.rotation {
                    Some(r) => {
                        if let Some(p) = r.parts.as_ref().and_then(|p| p.first()) {
                            self.error(
                                format!(
                                    "{what}: `rotation.parts` is not used by a Campbell analysis"
                                ),
                                p.span.clone(),
                                Some("the whole model turns in a Campbell analysis".into()),
                            );
                            ok = false;
                        }
                        self.steady_rotation(r, &e, &what, true)
                    }
                    None => {
                        self.error(
                            format!("{what}: a Campbell analysis needs `rotation = {{ axis, centre }}`"),
                            a.span.clone(),
                            Some("e.g. rotation = { axis = [0.0, 0.0, 1.0] } and speeds = { start = 0.0, end = 40.0, count = 21 }".into()),
                        );
                        None
                    }
                };
                let speeds = match &ai.speeds {
                    Some(SpeedsInput::List(v)) => v.clone(),
                    Some(SpeedsInput::Range { start, end, count }) => {
                        if *count == 0 || *count > 100_000 {
                            self.error(
                                format!("{what}: `speeds.count` must be 1 … 100000 (got {count})"),
                                self.key(&e, "speeds"),
                                None,
                            );
                            ok = false;
                        }
                        let n = (*count).clamp(1, 100_000);
                        (0..n)
                            .map(|i| {
                                if n == 1 {
                                    *start
                                } else {
                                    start + (end - start) * i as f64 / (n - 1) as f64
                                }
                            })
                            .collect()
                    }
                    None => {
                        self.error(
                            format!("{what}: a Campbell analysis needs `speeds`"),
                            a.span.clone(),
                            Some("`speeds = [0.0, 10.0, 20.0]` or `speeds = { start = 0.0, end = 40.0, count = 21 }` [rad/s]".into()),
                        );
                        ok = false;
                        Vec::new()
                    }
                };
                if ai.speeds.is_some()
                    && (speeds.is_empty()
                        || !speeds
                            .iter()
                            .all(|w| w.is_finite() && w.abs() <= MAX_MAGNITUDE))
                {
                    self.error(
                        format!(
                            "{what}: `speeds` must be finite rotor speeds [rad/s], at least one"
                        ),
                        self.key(&e, "speeds"),
                        None,
                    );
                    ok = false;
                }
                let load_steps = ai.load_steps.unwrap_or(1);
                if load_steps == 0 {
                    self.error(
                        format!("{what}: `load_steps` must be at least 1"),
                        self.key(&e, "load_steps"),
                        None,
                    );
                    ok = false;
                }
                let time = ai.time.unwrap_or(0.0);
                match rotation {
                    Some(rotation) => AnalysisKind::Campbell(CampbellSettings {
                        speeds,
                        rotation,
                        modal: m,
                        load_steps,
                        time,
                        solver,
                    }),
                    None => return None,
                }
            }
            AnalysisType::Floquet => {
                let period = match (ai.period, ai.speed) {
                    (Some(t), None) => {
                        if !(t.is_finite() && t > 0.0 && t <= MAX_MAGNITUDE) {
                            self.error(
                                format!("{what}: `period` must be a positive time [s] (got {t})"),
                                self.key(&e, "period"),
                                None,
                            );
                            ok = false;
                        }
                        t
                    }
                    (None, Some(w)) => {
                        if !(w.is_finite() && w != 0.0 && w.abs() <= MAX_MAGNITUDE) {
                            self.error(
                                format!("{what}: `speed` must be a non-zero rotor speed [rad/s] (got {w})"),
                                self.key(&e, "speed"),
                                Some("the period is T = 2π/|speed|".into()),
                            );
                            ok = false;
                        }
                        std::f64::consts::TAU / w.abs()
                    }
                    (Some(_), Some(_)) => {
                        self.error(
                            format!("{what}: give either `period` or `speed`, not both"),
                            self.key(&e, "speed"),
                            Some("the period is T = 2π/|speed|".into()),
                        );
                        return None;
                    }
                    (None, None) => {
                        self.error(
                            format!("{what}: a Floquet analysis needs `period` [s] or the rotor `speed` [rad/s]"),
                            a.span.clone(),
                            Some("e.g. `speed = 40.0` (T = 2π/40 s) or `period = 0.5`".into()),
                        );
                        return None;
                    }
                };
                let steps_per_period = ai.steps_per_period.unwrap_or(100);
                if !(4..=10_000_000).contains(&steps_per_period) {
                    self.error(
                        format!("{what}: `steps_per_period` must be 4 … 10000000 (got {steps_per_period})"),
                        self.key(&e, "steps_per_period"),
                        Some("the multipliers converge as h²; 100 to 1000 steps per period is usual".into()),
                    );
                    ok = false;
                }
                let rho_inf = ai.rho_inf.unwrap_or(1.0);
                if !(0.0..=1.0).contains(&rho_inf) {
                    self.error(
                        format!("{what}: `rho_inf` must be in [0, 1] (got {rho_inf})"),
                        self.key(&e, "rho_inf"),
                        Some(
                            "ρ∞ = 1 (the default) adds no numerical damping to the multipliers"
                                .into(),
                        ),
                    );
                    ok = false;
                }
                let mut n_modes = 10;
                if let Some(n) = &ai.n_modes {
                    if n.value == 0 {
                        self.error(
                            format!("{what}: `n_modes` must be at least 1"),
                            n.span.clone(),
                            None,
                        );
                        ok = false;
                    }
                    n_modes = n.value;
                }
                AnalysisKind::Floquet(FloquetSettings {
                    period,
                    steps_per_period,
                    rho_inf,
                    n_modes,
                    solver,
                })
            }
        };
        ok.then(|| AnalysisDef {
            name: ai.name.value.clone(),
            start_from,
            start_time,
            kind,
            spans: AnalysisSpans {
                name: ai.name.span.clone(),
                n_modes: ai.n_modes.as_ref().and_then(|n| n.span.clone()),
                period: self.key(&e, "period").or_else(|| self.key(&e, "speed")),
            },
        })
    }
}

/// A right-handed orthonormal frame whose third axis is `e3` (unit).
pub fn frame_from_axis(e3: &Vector3<f64>) -> Matrix3<f64> {
    // Start from the global axis least aligned with e3.
    let i = e3.iamin();
    let mut t = Vector3::zeros();
    t[i] = 1.0;
    let e1 = (t - e3 * e3.dot(&t)).normalize();
    let e2 = e3.cross(&e1);
    Matrix3::from_columns(&[e1, e2, *e3])
}

/// Frame from two of its axes (indices i < j); the first is kept, the second orthogonalized.
pub(crate) fn frame_from_two_axes(
    i: usize,
    a: &Vector3<f64>,
    j: usize,
    b: &Vector3<f64>,
) -> Option<Matrix3<f64>> {
    let na = a.norm();
    if !(na.is_finite() && na > 1e-12) {
        return None;
    }
    let ea = a / na;
    let bo = b - ea * ea.dot(b);
    let nb = bo.norm();
    if !(nb.is_finite() && nb > 1e-9 * b.norm().max(1e-300)) || b.norm() < 1e-12 {
        return None;
    }
    let eb = bo / nb;
    let mut cols = [Vector3::zeros(); 3];
    cols[i] = ea;
    cols[j] = eb;
    let k = 3 - i - j;
    // Right-handed: e_k = e_i × e_j for cyclic (i, j, k), otherwise reversed.
    cols[k] = if (j + 3 - i) % 3 == 1 {
        ea.cross(&eb)
    } else {
        eb.cross(&ea)
    };
    Some(Matrix3::from_columns(&cols))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_are_right_handed() {
        for ax in [
            Vector3::new(0.0, 1.0, 0.0),
            Vector3::new(1.0, 1.0, 1.0).normalize(),
            Vector3::new(0.0, 0.0, -1.0),
        ] {
            let f = frame_from_axis(&ax);
            assert!((f.transpose() * f - Matrix3::identity()).norm() < 1e-14);
            assert!((f.determinant() - 1.0).abs() < 1e-14);
            assert!((f.column(2) - ax).norm() < 1e-15);
        }
        let f = frame_from_two_axes(
            0,
            &Vector3::new(0.0, 1.0, 0.0),
            2,
            &Vector3::new(1.0, 0.0, 0.1),
        )
        .unwrap();
        assert!((f.determinant() - 1.0).abs() < 1e-14);
        assert!((f.column(0) - Vector3::new(0.0, 1.0, 0.0)).norm() < 1e-15);
        let g = frame_from_two_axes(
            1,
            &Vector3::new(0.0, 0.0, 1.0),
            2,
            &Vector3::new(1.0, 0.0, 0.0),
        )
        .unwrap();
        assert!((g.determinant() - 1.0).abs() < 1e-14);
    }
}
