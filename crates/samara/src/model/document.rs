//! A model as an editable TOML document: values addressed by paths such as
//! `bodies.bob.mass` or `beams.blade.sections[0].stiffness[4][4]`, changed in code (the
//! Python package, parameter sweeps) and validated by the same rules as a model file.
//!
//! A path is a dotted list of keys; `[k]` indexes an array; a key that follows an array
//! of tables picks the element whose `name` is that key (`bodies.bob` is the body named
//! `bob`). [`Document::locate`] maps a byte offset of the document's text back to the
//! path of the value written there, so every diagnostic can name what it is about.

use super::{LoadOptions, LoadedModel, Model, ModelError};
use std::ops::Range;
use std::path::PathBuf;
use toml::{Table, Value};

/// One step of a path.
#[derive(Clone, Debug, PartialEq)]
pub enum Step {
    /// A key of a table, or the name of an element of an array of tables.
    Key(String),
    /// An index into an array.
    Index(usize),
}

/// A path that is not well formed, or that names nothing in the document.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{path}: {message}")]
pub struct PathError {
    pub path: String,
    pub message: String,
}

/// Parses `a.b[0].c[4][4]` into steps.
pub fn parse_path(path: &str) -> Result<Vec<Step>, PathError> {
    let err = |m: &str| PathError {
        path: path.to_string(),
        message: m.to_string(),
    };
    let mut steps = Vec::new();
    let mut rest = path;
    if rest.is_empty() {
        return Err(err("empty path"));
    }
    loop {
        let end = rest.find(['.', '[']).unwrap_or(rest.len());
        let key = &rest[..end];
        if key.is_empty() {
            if !rest.starts_with('[') || steps.is_empty() {
                return Err(err("expected a key (an empty key or a leading index)"));
            }
        } else {
            steps.push(Step::Key(key.to_string()));
        }
        rest = &rest[end..];
        while let Some(r) = rest.strip_prefix('[') {
            let close = r.find(']').ok_or_else(|| err("`[` without `]`"))?;
            let n: usize = r[..close]
                .trim()
                .parse()
                .map_err(|_| err("an index in `[ ]` must be a non-negative integer"))?;
            steps.push(Step::Index(n));
            rest = &r[close + 1..];
        }
        if rest.is_empty() {
            return Ok(steps);
        }
        rest = rest
            .strip_prefix('.')
            .ok_or_else(|| err("expected `.` or `[` after an index"))?;
        if rest.is_empty() {
            return Err(err("a path cannot end with `.`"));
        }
    }
}

/// Renders steps as a path (the inverse of [`parse_path`]).
pub fn format_path(steps: &[Step]) -> String {
    let mut s = String::new();
    for st in steps {
        match st {
            Step::Key(k) => {
                if !s.is_empty() {
                    s.push('.');
                }
                s.push_str(k);
            }
            Step::Index(i) => s.push_str(&format!("[{i}]")),
        }
    }
    s
}

/// The element of an array of tables whose `name` is `name`.
fn named(items: &[Value], name: &str) -> Option<usize> {
    items
        .iter()
        .position(|v| v.get("name").and_then(Value::as_str) == Some(name))
}

/// A model document and where it came from.
#[derive(Clone, Debug)]
pub struct Document {
    /// The document's tables and values.
    pub table: Table,
    /// The text the document was read from, while it is unchanged (diagnostics then point
    /// into the original file).
    text: Option<String>,
    /// The file (or label) used in diagnostics; its folder resolves the files the model
    /// names (section files).
    pub path: PathBuf,
}

impl Document {
    /// Parses TOML text; `path` labels diagnostics and locates the files it names.
    pub fn from_toml(text: &str, path: impl Into<PathBuf>) -> Result<Self, ModelError> {
        let path = path.into();
        match toml::from_str::<Table>(text) {
            Ok(table) => Ok(Self {
                table,
                text: Some(text.to_string()),
                path,
            }),
            Err(e) => Err(ModelError {
                source: super::SourceFile::new(&path, text),
                diagnostics: vec![crate::diagnostics::parse_error_diagnostic(
                    &e,
                    text,
                    super::input::KEY_SPELLINGS,
                )],
            }),
        }
    }

    /// A document built in code; `path` labels diagnostics (e.g. `<python>`) and its
    /// folder locates the files the model names.
    pub fn from_table(table: Table, path: impl Into<PathBuf>) -> Self {
        Self {
            table,
            text: None,
            path: path.into(),
        }
    }

    /// The value at `path`.
    pub fn get(&self, path: &str) -> Result<&Value, PathError> {
        let steps = parse_path(path)?;
        let mut here: &Value = self
            .table
            .get(match &steps[0] {
                Step::Key(k) => k.as_str(),
                Step::Index(_) => unreachable!("parse_path starts with a key"),
            })
            .ok_or_else(|| missing(path, &steps[..1]))?;
        for (i, st) in steps.iter().enumerate().skip(1) {
            here = child(here, st).ok_or_else(|| why(here, path, &steps[..=i]))?;
        }
        Ok(here)
    }

    /// Sets the value at `path`. Every step but the last must exist; the last may add a
    /// key to a table. The document's text is regenerated when it is next validated.
    pub fn set(&mut self, path: &str, value: Value) -> Result<(), PathError> {
        let steps = parse_path(path)?;
        let (last, parents) = steps.split_last().expect("a path has a step");
        let mut here: &mut Value = match parents.first() {
            None => {
                let Step::Key(k) = last else {
                    unreachable!("parse_path starts with a key")
                };
                self.table.insert(k.clone(), value);
                self.text = None;
                return Ok(());
            }
            Some(Step::Key(k)) => self
                .table
                .get_mut(k)
                .ok_or_else(|| missing(path, &steps[..1]))?,
            Some(Step::Index(_)) => unreachable!("parse_path starts with a key"),
        };
        for (i, st) in parents.iter().enumerate().skip(1) {
            if child(here, st).is_none() {
                return Err(why(here, path, &steps[..=i]));
            }
            here = child_mut(here, st).expect("checked above");
        }
        let bad = |m: String| PathError {
            path: path.to_string(),
            message: m,
        };
        match (here, last) {
            (Value::Table(t), Step::Key(k)) => {
                t.insert(k.clone(), value);
            }
            (Value::Array(a), Step::Index(n)) => {
                let len = a.len();
                let slot = a.get_mut(*n).ok_or_else(|| {
                    bad(format!(
                        "index {n} is out of range (the array has {len} values)"
                    ))
                })?;
                *slot = value;
            }
            (Value::Array(a), Step::Key(k)) => {
                let n = named(a, k).ok_or_else(|| {
                    bad(format!(
                        "no element named '{k}' in {}",
                        format_path(parents)
                    ))
                })?;
                a[n] = value;
            }
            (v, st) => {
                return Err(bad(format!(
                    "{} is a {}, it has no {}",
                    format_path(parents),
                    v.type_str(),
                    match st {
                        Step::Key(k) => format!("key '{k}'"),
                        Step::Index(n) => format!("index {n}"),
                    }
                )));
            }
        }
        self.text = None;
        Ok(())
    }

    /// The document as TOML text: the original text while unchanged, otherwise one line
    /// per top-level key (arrays of tables one element per line).
    pub fn to_toml(&self) -> String {
        if let Some(t) = &self.text {
            return t.clone();
        }
        let mut out = String::new();
        for (k, v) in &self.table {
            out.push_str(&key(k));
            out.push_str(" = ");
            match v {
                Value::Array(items) if items.iter().all(Value::is_table) && !items.is_empty() => {
                    out.push_str("[\n");
                    for it in items {
                        out.push_str("  ");
                        write_value(&mut out, it);
                        out.push_str(",\n");
                    }
                    out.push(']');
                }
                _ => write_value(&mut out, v),
            }
            out.push('\n');
        }
        out
    }

    /// Validates the document as a model (the rules of a model file). The errors'
    /// diagnostics carry byte ranges in [`Self::to_toml`]; [`Self::locate`] names them.
    pub fn load(&self, options: &LoadOptions) -> Result<LoadedModel, ModelError> {
        Model::from_toml_str_with(&self.to_toml(), &self.path, options)
    }

    /// The path of the innermost value (or key) written at byte `offset` of
    /// [`Self::to_toml`] (`bodies.bob.mass`), if any.
    pub fn locate(&self, offset: usize) -> Option<String> {
        let text = self.to_toml();
        let doc = toml::de::DeTable::parse(&text).ok()?;
        let mut best: Option<(Range<usize>, Vec<Step>)> = None;
        let mut path = Vec::new();
        visit_table(doc.get_ref(), &mut path, offset, &mut best);
        best.map(|(_, p)| format_path(&p))
    }
}

fn missing(path: &str, upto: &[Step]) -> PathError {
    PathError {
        path: path.to_string(),
        message: format!("the model has no {}", format_path(upto)),
    }
}

/// Why the last of `upto` is not found in `parent`.
fn why(parent: &Value, path: &str, upto: &[Step]) -> PathError {
    let (last, before) = upto.split_last().expect("a path has a step");
    let message = match (parent, last) {
        (Value::Array(a), Step::Key(k)) => {
            let names: Vec<&str> = a
                .iter()
                .filter_map(|v| v.get("name").and_then(Value::as_str))
                .collect();
            format!(
                "no element named '{k}' in {} (names: {})",
                format_path(before),
                names.join(", ")
            )
        }
        (Value::Array(a), Step::Index(n)) => format!(
            "index {n} is out of range ({} has {} values)",
            format_path(before),
            a.len()
        ),
        (Value::Table(_), _) => format!("the model has no {}", format_path(upto)),
        (v, _) => format!(
            "{} is a {}, not a table or array",
            format_path(before),
            v.type_str()
        ),
    };
    PathError {
        path: path.to_string(),
        message,
    }
}

fn child<'a>(v: &'a Value, st: &Step) -> Option<&'a Value> {
    match (v, st) {
        (Value::Table(t), Step::Key(k)) => t.get(k),
        (Value::Array(a), Step::Index(n)) => a.get(*n),
        (Value::Array(a), Step::Key(k)) => named(a, k).map(|n| &a[n]),
        _ => None,
    }
}

fn child_mut<'a>(v: &'a mut Value, st: &Step) -> Option<&'a mut Value> {
    match (v, st) {
        (Value::Table(t), Step::Key(k)) => t.get_mut(k),
        (Value::Array(a), Step::Index(n)) => a.get_mut(*n),
        (Value::Array(a), Step::Key(k)) => {
            let n = named(a, k)?;
            a.get_mut(n)
        }
        _ => None,
    }
}

fn consider(
    range: Range<usize>,
    path: &[Step],
    offset: usize,
    best: &mut Option<(Range<usize>, Vec<Step>)>,
) {
    let inside = range.contains(&offset) || (range.is_empty() && range.start == offset);
    if inside && best.as_ref().is_none_or(|(r, _)| range.len() <= r.len()) {
        *best = Some((range, path.to_vec()));
    }
}

fn visit_table(
    t: &toml::de::DeTable<'_>,
    path: &mut Vec<Step>,
    offset: usize,
    best: &mut Option<(Range<usize>, Vec<Step>)>,
) {
    for (k, v) in t {
        path.push(Step::Key(k.get_ref().to_string()));
        let (ks, vs) = (k.span(), v.span());
        consider(
            ks.start.min(vs.start)..ks.end.max(vs.end),
            path,
            offset,
            best,
        );
        visit_value(v.get_ref(), path, offset, best);
        path.pop();
    }
}

fn visit_value(
    v: &toml::de::DeValue<'_>,
    path: &mut Vec<Step>,
    offset: usize,
    best: &mut Option<(Range<usize>, Vec<Step>)>,
) {
    match v {
        toml::de::DeValue::Table(t) => visit_table(t, path, offset, best),
        toml::de::DeValue::Array(a) => {
            for (i, item) in a.iter().enumerate() {
                let name = match item.get_ref() {
                    toml::de::DeValue::Table(t) => t.get("name").and_then(|n| match n.get_ref() {
                        toml::de::DeValue::String(s) => Some(s.to_string()),
                        _ => None,
                    }),
                    _ => None,
                };
                path.push(match name {
                    Some(n) => Step::Key(n),
                    None => Step::Index(i),
                });
                consider(item.span(), path, offset, best);
                visit_value(item.get_ref(), path, offset, best);
                path.pop();
            }
        }
        _ => {}
    }
}

/// A key, bare when it can be.
fn key(k: &str) -> String {
    if !k.is_empty()
        && k.chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
    {
        k.to_string()
    } else {
        Value::String(k.to_string()).to_string()
    }
}

/// A value on one line; floats in Rust's shortest round-trip form, so that a value set
/// in code reads back bit for bit.
fn write_value(out: &mut String, v: &Value) {
    match v {
        Value::Float(x) => {
            if x.is_nan() {
                out.push_str("nan");
            } else if x.is_infinite() {
                out.push_str(if *x > 0.0 { "inf" } else { "-inf" });
            } else {
                out.push_str(&format!("{x:?}"));
            }
        }
        Value::Integer(i) => out.push_str(&i.to_string()),
        Value::Boolean(b) => out.push_str(if *b { "true" } else { "false" }),
        Value::String(_) | Value::Datetime(_) => out.push_str(&v.to_string()),
        Value::Array(a) => {
            out.push('[');
            for (i, it) in a.iter().enumerate() {
                if i > 0 {
                    out.push_str(", ");
                }
                write_value(out, it);
            }
            out.push(']');
        }
        Value::Table(t) => {
            out.push('{');
            for (i, (k, it)) in t.iter().enumerate() {
                out.push_str(if i > 0 { ", " } else { " " });
                out.push_str(&key(k));
                out.push_str(" = ");
                write_value(out, it);
            }
            out.push_str(if t.is_empty() { "}" } else { " }" });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const PENDULUM: &str = include_str!("../../../../examples/pendulum.toml");

    #[test]
    fn paths_parse_and_format() {
        let p = parse_path("beams.blade.sections[0].stiffness[4][4]").unwrap();
        assert_eq!(
            p,
            vec![
                Step::Key("beams".into()),
                Step::Key("blade".into()),
                Step::Key("sections".into()),
                Step::Index(0),
                Step::Key("stiffness".into()),
                Step::Index(4),
                Step::Index(4),
            ]
        );
        assert_eq!(format_path(&p), "beams.blade.sections[0].stiffness[4][4]");
        for bad in [
            "", ".a", "a.", "a[", "a[x]", "a[-1]", "[0]", "a..b", "a[0]b",
        ] {
            assert!(parse_path(bad).is_err(), "{bad:?} should be refused");
        }
    }

    #[test]
    fn set_by_name_and_index_then_validate() {
        let mut d = Document::from_toml(PENDULUM, "examples/pendulum.toml").unwrap();
        assert_eq!(d.get("bodies.bob.mass").unwrap().as_float(), Some(1.0));
        d.set("bodies.bob.mass", Value::Float(2.5)).unwrap();
        d.set("model.gravity[2]", Value::Float(-1.625)).unwrap();
        let m = d.load(&LoadOptions::default()).unwrap().model;
        assert_eq!(m.bodies[0].mass, 2.5);
        assert_eq!(m.gravity.z, -1.625);
        // Setting a key that was not written adds it.
        d.set("analyses.swing.output_every", Value::Integer(5))
            .unwrap();
        assert_eq!(
            d.get("analyses.swing.output_every").unwrap().as_integer(),
            Some(5)
        );
        let e = d.set("bodies.bobb.mass", Value::Float(1.0)).unwrap_err();
        assert!(e.message.contains("no element named 'bobb'"), "{e}");
        let e = d.set("model.gravity[3]", Value::Float(1.0)).unwrap_err();
        assert!(e.message.contains("out of range"), "{e}");
        let e = d.get("joints.pivot.nothing").unwrap_err();
        assert!(e.message.contains("joints.pivot.nothing"), "{e}");
    }

    #[test]
    fn regenerated_text_reads_back_bit_for_bit() {
        let mut d = Document::from_toml(PENDULUM, "p.toml").unwrap();
        for x in [0.1 + 0.2, 1e-300, 6.02214076e23, -0.0, 1.0 / 3.0] {
            d.set("bodies.bob.mass", Value::Float(x)).unwrap();
            let back = Document::from_toml(&d.to_toml(), "p.toml").unwrap();
            let y = back.get("bodies.bob.mass").unwrap().as_float().unwrap();
            assert_eq!(x.to_bits(), y.to_bits());
        }
        assert_eq!(
            Document::from_toml(&d.to_toml(), "p.toml").unwrap().table,
            d.table
        );
    }

    #[test]
    fn diagnostics_are_located_by_path() {
        let mut d = Document::from_toml(PENDULUM, "p.toml").unwrap();
        d.set("bodies.bob.mass", Value::Float(-1.0)).unwrap();
        let e = d.load(&LoadOptions::default()).unwrap_err();
        let span = e.errors().next().unwrap().span.clone().unwrap();
        assert_eq!(d.locate(span.start).as_deref(), Some("bodies.bob.mass"));
        // An unchanged document is located in the original file's text.
        let d = Document::from_toml(PENDULUM, "p.toml").unwrap();
        let at = PENDULUM.find("rho_inf").unwrap();
        assert_eq!(d.locate(at).as_deref(), Some("analyses.swing.rho_inf"));
    }
}
