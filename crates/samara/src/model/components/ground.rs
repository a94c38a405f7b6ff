//! `ground = { type = "height_field", … }` of `[[contacts]]` and `[[tires]]`: a terrain
//! z(x, y) from a table (kernel: [`crate::math::height_field::HeightField`]), inline or
//! from a file.
//!
//! ```toml
//! ground = { type = "height_field", x = [0.0, 1.0, 2.0], y = [-1.0, 1.0],
//!            z = [[0.0, 0.1, 0.0],      # heights at y = −1 (one row per y, one column per x)
//!                 [0.0, 0.2, 0.0]] }    # heights at y = +1
//! ground = { type = "height_field", x = [0.0, 1.0, 2.0], z = [0.0, 0.1, 0.0] }  # a profile z(x)
//! ground = { type = "height_field", file = "terrain.csv" }   # relative to the model file
//! ```
//!
//! The file: comma-separated, `#` comments. A profile is two columns `x, z` per line; a
//! grid starts with a header line whose first cell is not a number (e.g. `y\x`) followed
//! by the x values, then one line per y: the y value and the heights at each x.

use crate::math::height_field::{HeightField, HeightFieldError};
use crate::model::Located;
use crate::model::validate::{Checker, Entry};
use schemars::JsonSchema;
use serde::Deserialize;
use std::ops::Range;
use std::path::Path;
use std::sync::Arc;

/// The kind of a ground given as a table.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum GroundKind {
    /// A table of heights z(x, y) (or a profile z(x)), C¹ cubic Hermite between the points.
    HeightField,
}

/// Heights: one row per y value, or one list (a profile along x).
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(untagged)]
pub enum HeightsInput {
    Profile(Vec<f64>),
    Grid(Vec<Vec<f64>>),
}

/// A ground given by a table of heights instead of a plane.
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct GroundInput {
    /// `height_field`.
    #[serde(rename = "type")]
    pub kind: GroundKind,
    /// Strictly increasing x coordinates [m], at least 2.
    #[serde(default)]
    pub x: Option<Vec<f64>>,
    /// Strictly increasing y coordinates [m]; leave out for a profile z(x) (constant in y).
    #[serde(default)]
    pub y: Option<Vec<f64>>,
    /// Heights [m]: `z[j][i]` at (x_i, y_j); a plain list for a profile.
    #[serde(default)]
    pub z: Option<HeightsInput>,
    /// A CSV file with the table instead of `x`, `y`, `z` (relative to the model file).
    #[serde(default)]
    pub file: Option<String>,
}

/// A table read from a file: the coordinates, heights, and the file line (1-based) of
/// the x values and of each y row.
struct FileTable {
    x: Vec<f64>,
    y: Vec<f64>,
    z: Vec<Vec<f64>>,
    x_line: usize,
    row_lines: Vec<usize>,
}

/// Parses a terrain CSV (see the module doc); errors are located messages.
fn parse_file(text: &str) -> Result<FileTable, String> {
    let rows: Vec<(usize, Vec<&str>)> = text
        .lines()
        .enumerate()
        .map(|(k, l)| (k + 1, l.split('#').next().unwrap_or("").trim()))
        .filter(|(_, l)| !l.is_empty())
        .map(|(k, l)| (k, l.split(',').map(str::trim).collect()))
        .collect();
    let num = |line: usize, col: usize, s: &str| -> Result<f64, String> {
        s.parse::<f64>()
            .map_err(|_| format!("line {line}, column {col}: expected a number, got '{s}'"))
    };
    let Some((first_line, first)) = rows.first() else {
        return Err("the file has no data lines".into());
    };
    if first[0].parse::<f64>().is_ok() {
        // Profile: x, z per line.
        let (mut x, mut z) = (Vec::new(), Vec::new());
        for (line, cells) in &rows {
            if cells.len() != 2 {
                return Err(format!(
                    "line {line}: a profile line has 2 values `x, z`, this one has {}",
                    cells.len()
                ));
            }
            x.push(num(*line, 1, cells[0])?);
            z.push(num(*line, 2, cells[1])?);
        }
        let n = rows.len();
        return Ok(FileTable {
            x,
            y: vec![0.0],
            z: vec![z],
            x_line: *first_line,
            row_lines: rows.iter().map(|r| r.0).take(n).collect(),
        });
    }
    let x = first[1..]
        .iter()
        .enumerate()
        .map(|(i, s)| num(*first_line, i + 2, s))
        .collect::<Result<Vec<_>, _>>()?;
    let (mut y, mut z, mut row_lines) = (Vec::new(), Vec::new(), Vec::new());
    for (line, cells) in &rows[1..] {
        y.push(num(*line, 1, cells[0])?);
        if cells.len() != x.len() + 1 {
            return Err(format!(
                "line {line}: a grid row has the y value and {} heights, this one has {} values",
                x.len(),
                cells.len()
            ));
        }
        z.push(
            cells[1..]
                .iter()
                .enumerate()
                .map(|(i, s)| num(*line, i + 2, s))
                .collect::<Result<Vec<_>, _>>()?,
        );
        row_lines.push(*line);
    }
    Ok(FileTable {
        x,
        y,
        z,
        x_line: *first_line,
        row_lines,
    })
}

/// The file position of a table error (line and column, 1-based).
fn file_position(t: &FileTable, e: &HeightFieldError) -> String {
    let profile = t.y.len() == 1 && t.row_lines.len() == t.x.len();
    match *e {
        HeightFieldError::NotIncreasing { axis: "x", index } if profile => {
            format!("line {}, column 1", t.row_lines[index])
        }
        HeightFieldError::NotIncreasing { axis: "x", index } => {
            format!("line {}, column {}", t.x_line, index + 2)
        }
        HeightFieldError::NotIncreasing { index, .. } => {
            format!("line {}, column 1", t.row_lines.get(index).unwrap_or(&0))
        }
        HeightFieldError::NotFinite { column, .. } if profile => {
            format!("line {}, column 2", t.row_lines[column])
        }
        HeightFieldError::NotFinite { row, column } => {
            format!("line {}, column {}", t.row_lines[row], column + 2)
        }
        _ => format!("line {}", t.x_line),
    }
}

/// The height field of `g` (on a contact or tire described by `what`), or a located error.
pub fn height_field(
    cx: &mut Checker,
    g: &Located<GroundInput>,
    what: &str,
) -> Option<Arc<HeightField>> {
    let e = Entry {
        span: g.span.clone(),
    };
    let gi = &g.value;
    let at = |cx: &Checker, key: &str| -> Option<Range<usize>> {
        cx.key(&e, key).or_else(|| g.span.clone())
    };
    let hint = "a height field: `x` (increasing, ≥ 2 values), `y` (increasing; leave out for a profile z(x)) and `z` (one row of heights per y value, one column per x), or `file`";
    if let Some(file) = &gi.file {
        if let Some(key) = [
            ("x", gi.x.is_some()),
            ("y", gi.y.is_some()),
            ("z", gi.z.is_some()),
        ]
        .iter()
        .find(|k| k.1)
        {
            cx.error(
                format!(
                    "{what}: the ground's `{}` and `file` both give the table",
                    key.0
                ),
                at(cx, key.0),
                Some("keep either the file or the inline `x`, `y`, `z`".into()),
            );
            return None;
        }
        let base = cx.source.path.parent().unwrap_or(Path::new("."));
        let path = base.join(file);
        let text = match crate::input_files::read_text(&path) {
            Ok(t) => t,
            Err(err) => {
                cx.error(
                    format!(
                        "{what}: cannot read terrain file '{}': {err}",
                        path.display()
                    ),
                    at(cx, "file"),
                    Some("paths are relative to the model file".into()),
                );
                return None;
            }
        };
        let table = match parse_file(&text) {
            Ok(t) => t,
            Err(m) => {
                cx.error(
                    format!("{what}: terrain file '{}', {m}", path.display()),
                    at(cx, "file"),
                    Some("a profile is `x, z` per line; a grid a header line `y\\x, x₀, x₁, …` then `y, z₀, z₁, …` per line".into()),
                );
                return None;
            }
        };
        return match HeightField::new(table.x.clone(), table.y.clone(), &table.z) {
            Ok(h) => Some(Arc::new(h)),
            Err(err) => {
                cx.error(
                    format!(
                        "{what}: terrain file '{}', {}: {err}",
                        path.display(),
                        file_position(&table, &err)
                    ),
                    at(cx, "file"),
                    Some(hint.into()),
                );
                None
            }
        };
    }
    let (Some(x), Some(z)) = (&gi.x, &gi.z) else {
        cx.error(
            format!("{what}: the height field needs `x` and `z` (or `file`)"),
            g.span.clone(),
            Some(hint.into()),
        );
        return None;
    };
    let (y, rows) = match (z, &gi.y) {
        (HeightsInput::Profile(p), None) => (vec![0.0], vec![p.clone()]),
        (HeightsInput::Grid(r), Some(y)) => (y.clone(), r.clone()),
        (HeightsInput::Profile(_), Some(_)) => {
            cx.error(
                format!("{what}: with `y`, `z` is a table, one row per y value"),
                at(cx, "z"),
                Some("z = [[z(x₀, y₀), z(x₁, y₀), …], [z(x₀, y₁), …], …]; or leave out `y` for a profile".into()),
            );
            return None;
        }
        (HeightsInput::Grid(_), None) => {
            cx.error(
                format!("{what}: a table of heights `z` needs its `y` values"),
                at(cx, "z"),
                Some("give `y` (one value per row of `z`), or a plain list `z = [...]` for a profile z(x)".into()),
            );
            return None;
        }
    };
    match HeightField::new(x.clone(), y, &rows) {
        Ok(h) => Some(Arc::new(h)),
        Err(err) => {
            let key = match &err {
                HeightFieldError::TooFew { axis, .. }
                | HeightFieldError::NotIncreasing { axis, .. } => axis,
                _ => "z",
            };
            cx.error(format!("{what}: {err}"), at(cx, key), Some(hint.into()));
            None
        }
    }
}
