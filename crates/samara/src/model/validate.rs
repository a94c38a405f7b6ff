//! Checks a [`ModelInput`] and builds the [`Model`], collecting every error with its
//! location in the file and a hint.

use super::error::{Diagnostic, ModelError, Severity, SourceFile, did_you_mean};
use super::input::*;
use super::located::Located;
use super::*;
use crate::math::Rotation;
use nalgebra::{Matrix3, SymmetricEigen, Vector3};
use std::collections::HashMap;
use std::ops::Range;

mod beam;

/// The name of the fixed inertial frame in node references.
pub const GROUND: &str = "ground";

/// Validates a parsed model file.
pub fn validate(input: &ModelInput, source: SourceFile) -> Result<LoadedModel, ModelError> {
    let mut v = Validator {
        source: &source,
        diags: Vec::new(),
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

/// Every number written in the file must be finite and at most [`MAX_MAGNITUDE`] in
/// magnitude, whatever key it belongs to: one located error per offending number.
pub(crate) fn number_range_diagnostics(text: &str) -> Vec<Diagnostic> {
    use toml::de::{DeTable, DeValue};
    let mut out = Vec::new();
    let Ok(doc) = DeTable::parse(text) else {
        return out; // syntax errors are reported by the parser itself
    };
    let mut stack: Vec<&toml::Spanned<DeValue>> = doc.get_ref().values().collect();
    while let Some(v) = stack.pop() {
        match v.get_ref() {
            DeValue::Float(f) => {
                let raw = f.as_str();
                let x: f64 = raw.replace('_', "").parse().unwrap_or(f64::NAN);
                if !(x.is_finite() && x.abs() <= MAX_MAGNITUDE) {
                    out.push(
                        Diagnostic::error(
                            format!("the number `{raw}` is outside the range samara computes with (finite, |x| ≤ {MAX_MAGNITUDE:e})"),
                            Some(v.span()),
                        )
                        .with_hint("inf and nan are not allowed in a model; use SI units, where no input comes near this bound"),
                    );
                }
            }
            DeValue::Array(a) => stack.extend(a.iter()),
            DeValue::Table(t) => stack.extend(t.values()),
            _ => {}
        }
    }
    out.sort_by_key(|d| d.span.as_ref().map_or(0, |s| s.start));
    out
}

/// Where a parse error without a location most likely is: the most deeply nested line
/// (dotted keys and headers, brackets), for the parser's recursion limit.
fn deepest_line(text: &str) -> Option<std::ops::Range<usize>> {
    let mut best: Option<(usize, std::ops::Range<usize>)> = None;
    let mut start = 0;
    for line in text.split_inclusive('\n') {
        let depth = line
            .bytes()
            .filter(|b| matches!(b, b'.' | b'[' | b'{'))
            .count();
        if best.as_ref().is_none_or(|(d, _)| depth > *d) {
            best = Some((depth, start..start + line.trim_end().len().max(1)));
        }
        start += line.len();
    }
    best.map(|(_, r)| r)
}

/// Turns a TOML/serde error into a diagnostic with a hint where one can be guessed.
pub(crate) fn parse_error_diagnostic(e: &toml::de::Error, text: &str) -> Diagnostic {
    let msg = e.message().trim().to_string();
    if e.span().is_none() && msg.contains("recursion") {
        return Diagnostic::error(
            format!("{msg}: the file nests tables or arrays too deeply"),
            deepest_line(text),
        )
        .with_hint("a model needs only a few levels of nesting; check this line's dotted keys and brackets");
    }
    let mut d = Diagnostic::error(msg.clone(), e.span());
    if let Some(rest) = msg.strip_prefix("unknown field `") {
        if let Some((field, expected)) = rest.split_once('`') {
            let candidates = backticked(expected);
            d.message = format!("unknown key `{field}`");
            d = match did_you_mean(field, candidates.iter().map(|s| s.as_str())) {
                Some(best) => d.with_hint(format!("did you mean `{best}`?")),
                None => d.with_hint(format!(
                    "the keys allowed here are: {}",
                    candidates.join(", ")
                )),
            };
        }
    } else if let Some(rest) = msg.strip_prefix("unknown variant `") {
        if let Some((word, expected)) = rest.split_once('`') {
            let candidates = backticked(expected);
            d.message = format!("unknown value `{word}`");
            d = match did_you_mean(word, candidates.iter().map(|s| s.as_str())) {
                Some(best) => d.with_hint(format!("did you mean `{best}`?")),
                None => d.with_hint(format!("expected one of: {}", candidates.join(", "))),
            };
        }
    } else if let Some(rest) = msg.strip_prefix("missing field `") {
        if let Some((field, _)) = rest.split_once('`') {
            d.message = format!("missing required key `{field}`");
            d = d.with_hint(format!(
                "add `{field} = …` to this table (see docs/model-reference.md)"
            ));
        }
    } else if msg.contains("invalid type") || msg.contains("expected") {
        d = d.with_hint("check the value's type: numbers are written like 1.0 or 2e-3, vectors like [0.0, 1.0, 0.0], names in quotes");
    }
    d
}

fn backticked(s: &str) -> Vec<String> {
    s.split('`')
        .enumerate()
        .filter(|(i, _)| i % 2 == 1)
        .map(|(_, w)| w.to_string())
        .collect()
}

struct Validator<'a> {
    source: &'a SourceFile,
    diags: Vec<Diagnostic>,
    /// Unknown-name errors that still get a "did you mean" (each costs a pass over the
    /// names; a file with thousands of bad references must not take quadratic time).
    suggestions_left: usize,
}

/// How many unknown references get a spelling suggestion.
const MAX_SUGGESTIONS: usize = 100;

/// Where an entry's keys live in the file.
#[derive(Clone)]
struct Entry {
    span: Option<Range<usize>>,
}

impl<'a> Validator<'a> {
    fn error(
        &mut self,
        message: impl Into<String>,
        span: Option<Range<usize>>,
        hint: Option<String>,
    ) {
        let mut d = Diagnostic::error(message, span);
        d.hint = hint;
        self.diags.push(d);
    }

    fn warning(
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
    fn key(&self, entry: &Entry, key: &str) -> Option<Range<usize>> {
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
                return Some(span.start + vs..span.start + vs + value.len().max(1));
            }
            from = end;
        }
        Some(span)
    }

    /// Span of `key = value` in the top-level table `[table]`, if the file has one.
    fn header_key(&self, table: &str, key: &str) -> Option<Range<usize>> {
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

    fn finite(&mut self, entry: &Entry, key: &str, values: &[f64], what: &str) -> bool {
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

    fn unique_names<T>(
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
    fn suggest<'n>(
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

    fn node_ref(
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

    fn orientation(&mut self, o: &OrientationInput, entry: &Entry, what: &str) -> Option<Rotation> {
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

    fn time_function(
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
        let mut node_map = HashMap::new();
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
            node_map
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

        // Beams (may create nodes).
        self.beams(input, &mut model, &mut node_map);

        // Bodies.
        self.unique_names(&input.bodies, |b| &b.name, "body");
        for b in &input.bodies {
            let e = Entry {
                span: b.span.clone(),
            };
            let bi = &b.value;
            let what = format!("body '{}'", bi.name.value);
            let node = self.node_ref(&bi.node, &node_map, &what);
            if node == Some(NodeRef::Ground) {
                self.error(format!("{what}: a body cannot be attached to the ground"), bi.node.span.clone(), Some("attach it to a node; fix the node to the ground with a `fixed` joint if it must not move".into()));
            }
            if !(bi.mass.is_finite() && bi.mass > 0.0) {
                self.error(
                    format!("{what}: mass must be positive (got {})", bi.mass),
                    self.key(&e, "mass"),
                    Some("a massless attachment needs no body; give the mass in kg".into()),
                );
            }
            let inertia = Matrix3::from_fn(|i, j| bi.inertia[i][j]);
            self.check_inertia(&inertia, &e, &what);
            let cg = bi.cg_offset.unwrap_or([0.0; 3]);
            self.finite(&e, "cg_offset", &cg, &what);
            if let Some(NodeRef::Node(node)) = node {
                model.bodies.push(BodyDef {
                    name: bi.name.value.clone(),
                    node,
                    mass: bi.mass,
                    inertia: 0.5 * (inertia + inertia.transpose()),
                    cg_offset: Vector3::from(cg),
                });
            }
        }

        // Signals.
        self.unique_names(&input.signals, |g| &g.name, "signal");
        let mut signals: HashMap<String, TimeFunction> = HashMap::new();
        for g in &input.signals {
            let what = format!("signal '{}'", g.value.name.value);
            if let Some(f) = self.time_function(&g.value.function, &what) {
                signals.insert(g.value.name.value.clone(), f.clone());
                model.signals.push(SignalDef {
                    name: g.value.name.value.clone(),
                    function: f,
                });
            }
        }

        // Joints.
        self.unique_names(&input.joints, |j| &j.name, "joint");
        for j in &input.joints {
            if let Some(def) = self.joint(j, &node_map, &model, &signals) {
                model.joints.push(def);
            }
        }

        // Springs.
        self.unique_names(&input.springs, |s| &s.name, "spring");
        for s in &input.springs {
            let e = Entry {
                span: s.span.clone(),
            };
            let si = &s.value;
            let what = format!("spring '{}'", si.name.value);
            let a = self.node_ref(&si.node_a, &node_map, &what);
            let b = self.node_ref(&si.node_b, &node_map, &what);
            let (Some(a), Some(b)) = (a, b) else { continue };
            if a == b {
                self.error(
                    format!("{what} connects a node to itself"),
                    si.node_b.span.clone(),
                    Some("a spring needs two different nodes (or a node and 'ground')".into()),
                );
                continue;
            }
            let default_point = |r: NodeRef| {
                r.index()
                    .map(|i| model.nodes[i].position)
                    .unwrap_or_default()
            };
            let pa = si
                .point_a
                .map(Vector3::from)
                .unwrap_or_else(|| default_point(a));
            let pb = si
                .point_b
                .map(Vector3::from)
                .unwrap_or_else(|| default_point(b));
            if a == NodeRef::Ground && si.point_a.is_none() {
                self.error(
                    format!("{what}: the ground end needs `point_a`"),
                    e.span.clone(),
                    Some("give the global position of the anchor point".into()),
                );
            }
            if b == NodeRef::Ground && si.point_b.is_none() {
                self.error(
                    format!("{what}: the ground end needs `point_b`"),
                    e.span.clone(),
                    Some("give the global position of the anchor point".into()),
                );
            }
            self.finite(&e, "point_a", pa.as_slice(), &what);
            self.finite(&e, "point_b", pb.as_slice(), &what);
            if !(si.stiffness.is_finite() && si.stiffness >= 0.0) {
                self.error(
                    format!("{what}: stiffness must be ≥ 0 (got {})", si.stiffness),
                    self.key(&e, "stiffness"),
                    None,
                );
            }
            let damping = si.damping.unwrap_or(0.0);
            if !(damping.is_finite() && damping >= 0.0) {
                self.error(
                    format!("{what}: damping must be ≥ 0 (got {damping})"),
                    self.key(&e, "damping"),
                    None,
                );
            }
            let l0 = (pb - pa).norm();
            if l0 < 1e-12 {
                self.error(
                    format!("{what}: its two points coincide, so its direction is undefined"),
                    e.span.clone(),
                    Some("give distinct `point_a` and `point_b`".into()),
                );
            }
            let rest = si.rest_length.unwrap_or(l0);
            if !(rest.is_finite() && rest >= 0.0) {
                self.error(
                    format!("{what}: rest_length must be ≥ 0 (got {rest})"),
                    self.key(&e, "rest_length"),
                    None,
                );
            }
            model.springs.push(SpringDef {
                name: si.name.value.clone(),
                node_a: a,
                node_b: b,
                point_a: pa,
                point_b: pb,
                stiffness: si.stiffness,
                damping,
                rest_length: rest,
            });
        }

        // Applied loads.
        self.unique_names(&input.forces, |f| &f.name, "force");
        for f in &input.forces {
            let e = Entry {
                span: f.span.clone(),
            };
            let fi = &f.value;
            let what = format!("force '{}'", fi.name.value);
            let node = self.node_ref(&fi.node, &node_map, &what);
            if fi.force.is_none() && fi.moment.is_none() {
                self.error(
                    format!("{what}: give `force`, `moment`, or both"),
                    e.span.clone(),
                    None,
                );
            }
            let force = fi.force.unwrap_or([0.0; 3]);
            let moment = fi.moment.unwrap_or([0.0; 3]);
            self.finite(&e, "force", &force, &what);
            self.finite(&e, "moment", &moment, &what);
            let function = match &fi.function {
                Some(func) => self.time_function(func, &what).unwrap_or_default(),
                None => TimeFunction::Constant(1.0),
            };
            match node {
                Some(NodeRef::Node(n)) => {
                    let point = fi
                        .point
                        .map(Vector3::from)
                        .unwrap_or(model.nodes[n].position);
                    self.finite(&e, "point", point.as_slice(), &what);
                    model.loads.push(LoadDef {
                        name: fi.name.value.clone(),
                        node: n,
                        force: Vector3::from(force),
                        moment: Vector3::from(moment),
                        frame: fi.frame.unwrap_or_default(),
                        point,
                        function,
                    });
                }
                Some(NodeRef::Ground) => {
                    self.error(
                        format!("{what}: a load on the ground has no effect"),
                        fi.node.span.clone(),
                        Some("apply it to a node".into()),
                    );
                }
                None => {}
            }
        }

        // Analyses.
        self.unique_names(&input.analyses, |a| &a.name, "analysis");
        for (k, a) in input.analyses.iter().enumerate() {
            if let Some(def) = self.analysis(a, &input.analyses[..k]) {
                model.analyses.push(def);
            }
        }
        // A beam without `density` or `mass` is massless (right for statics); in a dynamic
        // analysis its nodes then need mass from elsewhere, or the run stops at once.
        if let Some(dynamic) = model
            .analyses
            .iter()
            .find(|a| matches!(a.kind, AnalysisKind::Dynamic(_)))
        {
            for b in &model.beams {
                if b.table
                    .sections
                    .iter()
                    .all(|s| s.mass.iter().all(|&x| x == 0.0))
                {
                    let span = input
                        .beams
                        .iter()
                        .find(|bi| bi.value.name.value == b.name)
                        .and_then(|bi| bi.value.name.span.clone());
                    self.warning(
                        format!(
                            "beam '{}' has no mass (no `density` in `isotropic`, no `mass` matrix), and analysis '{}' is dynamic",
                            b.name, dynamic.name
                        ),
                        span,
                        Some("give the sections a density or a mass matrix; a massless beam only works where every node that can move carries a body".into()),
                    );
                }
            }
        }
        if input.analyses.is_empty() {
            self.warning("the model has no [[analyses]]: nothing will run", None, Some("add e.g. [[analyses]] name = \"run\", type = \"dynamic\", t_end = 1.0, step = 1e-3".into()));
        }
        if model.nodes.is_empty() {
            self.warning("the model has no nodes", None, None);
        }
        // Nodes that nothing touches are free and massless: their equations are singular.
        let mut used = vec![false; model.nodes.len()];
        for b in &model.bodies {
            used[b.node] = true;
        }
        for s in &model.springs {
            for r in [s.node_a, s.node_b] {
                if let Some(i) = r.index() {
                    used[i] = true;
                }
            }
        }
        for j in &model.joints {
            for r in [j.node_a, j.node_b] {
                if let Some(i) = r.index() {
                    used[i] = true;
                }
            }
        }
        for b in &model.beams {
            for &i in &b.nodes {
                used[i] = true;
            }
        }
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
    fn unit_axis(&mut self, v: [f64; 3], e: &Entry, key: &str, what: &str) -> Option<Vector3<f64>> {
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

    fn joint(
        &mut self,
        j: &Located<JointInput>,
        node_map: &HashMap<String, usize>,
        model: &Model,
        signals: &HashMap<String, TimeFunction>,
    ) -> Option<JointDef> {
        let e = Entry {
            span: j.span.clone(),
        };
        let ji = &j.value;
        let kind = ji.kind.value;
        let what = format!("joint '{}'", ji.name.value);
        let a = self.node_ref(&ji.node_a, node_map, &what);
        let b = self.node_ref(&ji.node_b, node_map, &what);
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
            Some(r) => match self.node_ref(r, node_map, &what)? {
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
                None => frame_from_axis(&e3),
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
            match self.component(ci, &cw, signals) {
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

    fn component(
        &mut self,
        ci: &Located<ComponentInput>,
        what: &str,
        signals: &HashMap<String, TimeFunction>,
    ) -> Option<ComponentDef> {
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
        let input = match &c.input {
            None => None,
            Some(name) => match signals.get(&name.value) {
                Some(f) => Some((name.value.clone(), f.clone())),
                None => {
                    let hint = match self.suggest(&name.value, signals.keys().map(|s| s.as_str())) {
                        Some(b) => format!("did you mean '{b}'?"),
                        None => "declare it in a [[signals]] table: name and function".into(),
                    };
                    self.error(
                        format!("{what}: unknown signal '{}'", name.value),
                        name.span.clone(),
                        Some(hint),
                    );
                    ok = false;
                    None
                }
            },
        };
        ok.then_some(ComponentDef {
            spring,
            damper,
            backlash,
            drive,
            input,
        })
    }

    fn check_inertia(&mut self, j: &Matrix3<f64>, e: &Entry, what: &str) {
        let span = self.key(e, "inertia");
        if !j.iter().all(|x| x.is_finite()) {
            self.error(format!("{what}: inertia must be finite"), span, None);
            return;
        }
        let scale = j.abs().max().max(f64::MIN_POSITIVE);
        let asym = (j - j.transpose()).abs().max();
        if asym > 1e-9 * scale {
            self.error(
                format!("{what}: inertia is not symmetric (largest |Jᵢⱼ − Jⱼᵢ| = {asym:.3e})"),
                span,
                Some(
                    "give the full symmetric tensor about the CG; products of inertia appear twice"
                        .into(),
                ),
            );
            return;
        }
        let eig = SymmetricEigen::new(0.5 * (j + j.transpose())).eigenvalues;
        let min = eig.min();
        // Also rejects a NaN from an overflowing eigen-solve.
        if min.is_nan() || min <= 0.0 {
            self.error(
                format!("{what}: inertia is not positive definite (principal moments {:.4e}, {:.4e}, {:.4e})", eig[0], eig[1], eig[2]),
                span,
                Some("every principal moment of inertia of a rigid body must be positive".into()),
            );
            return;
        }
        let mut p = [eig[0], eig[1], eig[2]];
        p.sort_by(f64::total_cmp);
        if p[0] + p[1] < p[2] * (1.0 - 1e-9) {
            self.warning(
                format!("{what}: principal moments {:.4e}, {:.4e}, {:.4e} violate the triangle inequality (J₁ + J₂ ≥ J₃), so no real body has them", p[0], p[1], p[2]),
                span,
                None,
            );
        }
    }

    fn analysis(
        &mut self,
        a: &Located<AnalysisInput>,
        earlier: &[Located<AnalysisInput>],
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
        // `scaling` multiplies rows and multipliers by βh²: there is no step in statics.
        let dynamic_keys: [(&str, bool); 9] = [
            ("scaling", ai.scaling.is_some()),
            ("formulation", ai.formulation.is_some()),
            ("t_start", ai.t_start.is_some()),
            ("t_end", ai.t_end.is_some()),
            ("step", ai.step.is_some()),
            ("rho_inf", ai.rho_inf.is_some()),
            ("min_step", ai.min_step.is_some()),
            ("output_every", ai.output_every.is_some()),
            ("jacobian", ai.jacobian.is_some()),
        ];
        let static_keys: [(&str, bool); 2] = [
            ("load_steps", ai.load_steps.is_some()),
            ("time", ai.time.is_some()),
        ];
        let (wrong, tname): (&[(&str, bool)], &str) = match kind {
            AnalysisType::Dynamic => (&static_keys, "dynamic"),
            AnalysisType::Static => (&dynamic_keys, "static"),
        };
        let mut ok = true;
        for (k, g) in wrong {
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
            Some(s) => match earlier.iter().position(|x| x.value.name.value == s.value) {
                Some(i) => Some(i),
                None => {
                    let hint = match self.suggest(
                        &s.value,
                        earlier.iter().map(|x| x.value.name.value.as_str()),
                    ) {
                        Some(b) => format!("did you mean '{b}'?"),
                        None => "`start_from` names an analysis listed before this one".to_string(),
                    };
                    self.error(
                        format!("{what}: unknown earlier analysis '{}'", s.value),
                        s.span.clone(),
                        Some(hint),
                    );
                    ok = false;
                    None
                }
            },
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
                        format!("{what}: `min_step` must be in (0, step] (got {min_step})"),
                        self.key(&e, "min_step"),
                        None,
                    );
                    ok = false;
                } else if ai.min_step.is_some() && min_step <= resolution {
                    self.error(
                        format!("{what}: `min_step` ({min_step:e}) is below the resolution of time near t = {t_end:e} ({resolution:.1e})"),
                        self.key(&e, "min_step"),
                        Some("a step that small would not move time; use a larger `min_step`".into()),
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
                AnalysisKind::Dynamic(DynamicSettings {
                    t_start,
                    t_end,
                    step,
                    rho_inf: rho,
                    min_step,
                    output_every,
                    jacobian: ai.jacobian.unwrap_or_default(),
                    formulation,
                    solver,
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
                AnalysisKind::Static(StaticSettings {
                    load_steps,
                    time,
                    solver,
                })
            }
        };
        ok.then(|| AnalysisDef {
            name: ai.name.value.clone(),
            start_from,
            kind,
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
fn frame_from_two_axes(
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
