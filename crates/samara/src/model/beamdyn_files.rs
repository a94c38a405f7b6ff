//! `beamdyn = "…BeamDyn.dat"` in `[[beams]]`: reads an OpenFAST BeamDyn primary input
//! file and its blade file as published, and fills the beam's key points, twist, order,
//! quadrature, sections and damping in samara's conventions before the model is
//! validated (docs/aerodynamics.md, "BeamDyn blade files"):
//!
//! - key points (BeamDyn blade frame, beam along z) → global points
//!   `root_position + root_axes · kp`;
//! - `initial_twist` [deg] per key point → `twist = −θ` [rad] at the key points' η
//!   (BeamDyn negates its input twist when it builds the section frames: a frame turned
//!   by −θ about the blade axis; samara turns by +twist);
//! - BeamDyn's x axis → the section `y_axis`; the 6×6 matrices and μ re-ordered
//!   (`ordering = "beamdyn"`);
//! - `quadrature` 1 (Gauss, p + 1 points) → samara's `full`; 2 (trapezoidal over the
//!   stations) has no samara counterpart and also becomes `full` (docs say so).

use super::ModelInput;
use super::beam_input::{BeamQuadrature, SectionInput, SectionOrdering};
use super::error::{Diagnostic, SourceFile};
use crate::elements::beam::element::MAX_ORDER;
use crate::elements::beam::section::{
    check_mass, check_stiffness, damping_from_beamdyn_ordering, from_beamdyn_ordering,
};
use crate::model::Located;
use nalgebra::{Matrix3, Matrix6, Vector3};
use std::path::{Path, PathBuf};

/// A BeamDyn blade as its files give it (BeamDyn's frame and ordering).
#[derive(Clone, Debug)]
pub struct BeamDynBlade {
    /// Key points (x, y, z [m], initial twist [deg]), root to tip.
    pub key_points: Vec<[f64; 4]>,
    /// `order_elem`.
    pub order: usize,
    /// `quadrature`: 1 Gauss, 2 trapezoidal.
    pub quadrature: u32,
    /// Stations (η, 6×6 stiffness, 6×6 mass), BeamDyn ordering.
    pub stations: Vec<(f64, Matrix6<f64>, Matrix6<f64>)>,
    /// Stiffness-proportional damping μ (BeamDyn ordering) if `damp_type` = 1.
    pub damping: Option<[f64; 6]>,
}

/// What is wrong in which file, at which line (1-based; 0 = the file as a whole).
#[derive(Clone, Debug, PartialEq)]
pub struct FileError {
    pub path: PathBuf,
    pub line: usize,
    pub message: String,
}

impl std::fmt::Display for FileError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.line > 0 {
            write!(
                f,
                "'{}', line {}: {}",
                self.path.display(),
                self.line,
                self.message
            )
        } else {
            write!(f, "'{}': {}", self.path.display(), self.message)
        }
    }
}

fn unquote(s: &str) -> &str {
    s.trim_matches(|c| c == '"' || c == '\'')
}

/// The lines of a file, and a locator of `value  Keyword  - comment` lines.
struct Lines<'a> {
    path: &'a Path,
    lines: Vec<&'a str>,
}

impl<'a> Lines<'a> {
    fn err(&self, line: usize, message: impl Into<String>) -> FileError {
        FileError {
            path: self.path.to_path_buf(),
            line,
            message: message.into(),
        }
    }

    /// Index of the first line whose second token is `key`.
    fn find(&self, key: &str) -> Result<usize, FileError> {
        self.lines
            .iter()
            .position(|l| l.split_whitespace().nth(1) == Some(key))
            .ok_or_else(|| self.err(0, format!("no `{key}` line (value first, then `{key}`)")))
    }

    /// The integer before `key`, within `range`.
    fn int(&self, key: &str, range: std::ops::RangeInclusive<usize>) -> Result<usize, FileError> {
        let k = self.find(key)?;
        self.lines[k]
            .split_whitespace()
            .next()
            .and_then(|v| v.parse::<usize>().ok())
            .filter(|v| range.contains(v))
            .ok_or_else(|| {
                self.err(
                    k + 1,
                    format!(
                        "`{key}` must be an integer in {}…{}",
                        range.start(),
                        range.end()
                    ),
                )
            })
    }

    /// The leading numbers of line `k` (0-based; a comment may follow them), or an error
    /// naming what was expected.
    fn numbers(&self, k: usize, expected: &str) -> Result<Vec<f64>, FileError> {
        let l = self
            .lines
            .get(k)
            .ok_or_else(|| self.err(k + 1, format!("the file ends; expected {expected}")))?;
        let v: Vec<f64> = l
            .split_whitespace()
            .map_while(|t| t.trim_end_matches(',').parse::<f64>().ok())
            .collect();
        if !v.is_empty() && v.iter().all(|x| x.is_finite()) {
            Ok(v)
        } else {
            Err(self.err(k + 1, format!("expected {expected}, found '{}'", l.trim())))
        }
    }
}

/// Reads a BeamDyn primary file and the blade file it names (`BldFile`, relative to it).
pub fn read_beamdyn(primary: &Path) -> Result<BeamDynBlade, FileError> {
    let text = crate::input_files::read_text(primary).map_err(|e| FileError {
        path: primary.to_path_buf(),
        line: 0,
        message: format!("cannot read the BeamDyn file: {e}"),
    })?;
    let f = Lines {
        path: primary,
        lines: text.lines().collect(),
    };
    let members = f.int("member_total", 1..=10_000)?;
    if members != 1 {
        return Err(f.err(
            f.find("member_total")? + 1,
            format!("{members} members: only a single-member blade is read"),
        ));
    }
    let kp_line = f.find("kp_total")?;
    let kp_total = f.int("kp_total", 3..=100_000)?;
    // The member line `1  kp_total`, two header lines (names, units), then the rows.
    let m = f.numbers(kp_line + 1, "the member line `1  kp_total`")?;
    if m.len() < 2 || m[1] != kp_total as f64 {
        return Err(f.err(
            kp_line + 2,
            format!("the member line must be `1  {kp_total}` (member number, key points)"),
        ));
    }
    let mut key_points = Vec::with_capacity(kp_total);
    for k in kp_line + 4..kp_line + 4 + kp_total {
        let v = f.numbers(k, "4 numbers: kp_xr kp_yr kp_zr initial_twist [deg]")?;
        if v.len() < 4 {
            return Err(f.err(
                k + 1,
                "expected 4 numbers: kp_xr kp_yr kp_zr initial_twist [deg]",
            ));
        }
        let p = [v[0], v[1], v[2], v[3]];
        if let Some(q) = key_points.last() {
            let q: &[f64; 4] = q;
            let d = ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt();
            if d.is_nan() || d <= 0.0 {
                return Err(f.err(k + 1, "this key point repeats the one before"));
            }
        }
        key_points.push(p);
    }
    let order = f.int("order_elem", 1..=MAX_ORDER)?;
    let quadrature = f.int("quadrature", 1..=2)? as u32;
    let bl = f.find("BldFile")?;
    let name = unquote(f.lines[bl].split_whitespace().next().unwrap_or(""));
    let blade = primary.parent().unwrap_or(Path::new(".")).join(name);
    let (stations, damping) = read_blade(&blade)?;
    Ok(BeamDynBlade {
        key_points,
        order,
        quadrature,
        stations,
        damping,
    })
}

type Stations = Vec<(f64, Matrix6<f64>, Matrix6<f64>)>;

/// Reads a BeamDyn blade file: stations of η, 6×6 stiffness and 6×6 mass; damping.
fn read_blade(path: &Path) -> Result<(Stations, Option<[f64; 6]>), FileError> {
    let text = crate::input_files::read_text(path).map_err(|e| FileError {
        path: path.to_path_buf(),
        line: 0,
        message: format!("cannot read the BeamDyn blade file (`BldFile`): {e}"),
    })?;
    let f = Lines {
        path,
        lines: text.lines().collect(),
    };
    let n = f.int("station_total", 2..=100_000)?;
    let damp_line = f.find("damp_type")?;
    let damp_type = f.int("damp_type", 0..=2)?;
    if damp_type == 2 {
        return Err(f.err(
            damp_line + 1,
            "modal damping (damp_type 2) is not read; use 0 or 1 (stiffness-proportional μ)",
        ));
    }
    let props = f
        .lines
        .iter()
        .position(|l| l.contains("DISTRIBUTED PROPERTIES"))
        .ok_or_else(|| f.err(0, "no `DISTRIBUTED PROPERTIES` line"))?;
    // μ: the first all-numeric line of six numbers between damp_type and the properties.
    let mut damping = None;
    if damp_type == 1 {
        let k = (damp_line + 1..props)
            .find(|&k| f.numbers(k, "").is_ok_and(|v| v.len() == 6))
            .ok_or_else(|| {
                f.err(
                    damp_line + 1,
                    "damp_type = 1 but no line of six damping coefficients mu1 … mu6 follows",
                )
            })?;
        let v = f.numbers(k, "")?;
        if v.iter().any(|&m| m < 0.0) {
            return Err(f.err(k + 1, "damping coefficients must be ≥ 0"));
        }
        damping = Some([v[0], v[1], v[2], v[3], v[4], v[5]]);
    }
    // The numbers after the properties line, each with its line.
    let mut numbers: Vec<(f64, usize)> = Vec::new();
    for k in props + 1..f.lines.len() {
        if numbers.len() >= 73 * n {
            break;
        }
        let l = f.lines[k].trim();
        if l.is_empty() {
            continue;
        }
        let v = f.numbers(
            k,
            "the numbers of a station (η, then 6×6 stiffness and 6×6 mass)",
        )?;
        numbers.extend(v.into_iter().map(|x| (x, k + 1)));
    }
    if numbers.len() < 73 * n {
        return Err(f.err(
            f.lines.len(),
            format!(
                "station_total = {n} needs {n} stations of 73 numbers (η, 36 stiffness, 36 mass); the file ends after {}",
                numbers.len()
            ),
        ));
    }
    let mut stations: Stations = Vec::with_capacity(n);
    for s in 0..n {
        let b = &numbers[73 * s..73 * (s + 1)];
        let (eta, line) = b[0];
        let last = stations.last().map_or(-1.0, |x| x.0);
        let first_last_ok = (s > 0 || eta == 0.0) && (s + 1 < n || eta == 1.0);
        if !(eta > last && (0.0..=1.0).contains(&eta) && first_last_ok) {
            return Err(f.err(
                line,
                format!(
                    "station η = {eta}: stations must rise strictly from 0 to 1 (η is the member's normalized arc length)"
                ),
            ));
        }
        let k = Matrix6::from_fn(|i, j| b[1 + 6 * i + j].0);
        let m = Matrix6::from_fn(|i, j| b[37 + 6 * i + j].0);
        let (ks, ms) = (from_beamdyn_ordering(&k), from_beamdyn_ordering(&m));
        check_stiffness(&ks).map_err(|e| f.err(b[1].1, format!("station η = {eta}: {e}")))?;
        check_mass(&ms).map_err(|e| f.err(b[37].1, format!("station η = {eta}: {e}")))?;
        stations.push((eta, k, m));
    }
    Ok((stations, damping))
}

/// Fills every `beamdyn = …` beam from its files; returns the errors, each located at
/// the beam's `beamdyn` value.
pub fn resolve(input: &mut ModelInput, source: &SourceFile) -> Vec<Diagnostic> {
    let base = source.path.parent().unwrap_or(Path::new(".")).to_path_buf();
    let mut diags = Vec::new();
    for b in &mut input.beams {
        let bi = &mut b.value;
        let Some(file) = bi.beamdyn.clone() else {
            continue;
        };
        let what = format!("beam '{}'", bi.name.value);
        let given: Vec<&str> = [
            ("points", bi.points.is_some()),
            ("nodes", bi.nodes.is_some()),
            ("twist", bi.twist.is_some()),
            ("y_axis", bi.y_axis.is_some()),
            ("sections", !bi.sections.is_empty()),
            ("sections_file", bi.sections_file.is_some()),
        ]
        .iter()
        .filter(|x| x.1)
        .map(|x| x.0)
        .collect();
        if !given.is_empty() {
            diags.push(
                Diagnostic::error(
                    format!(
                        "{what}: `beamdyn` gives the reference line and the sections; do not give `{}` as well",
                        given.join("`, `")
                    ),
                    file.span.clone(),
                )
                .with_hint("place the blade with `root_position` and `root_axes`; `order`, `elements`, `quadrature` and `damping` may be given"),
            );
            continue;
        }
        let axes = bi
            .root_axes
            .unwrap_or([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);
        // Columns: BeamDyn's x, y, z in global components.
        let r = Matrix3::from_fn(|i, j| axes[j][i]);
        let orthonormal = r.iter().all(|x| x.is_finite())
            && (r.transpose() * r - Matrix3::identity()).abs().max() < 1e-6
            && r.determinant() > 0.0;
        if !orthonormal {
            diags.push(
                Diagnostic::error(
                    format!("{what}: `root_axes` must be three orthonormal rows (BeamDyn's x, y, z in global components) forming a right-handed frame"),
                    file.span.clone(),
                )
                .with_hint("e.g. a blade along global z with BeamDyn's x downwind along global x: root_axes = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]"),
            );
            continue;
        }
        let origin = Vector3::from(bi.root_position.unwrap_or([0.0; 3]));
        let blade = match read_beamdyn(&base.join(&file.value)) {
            Ok(x) => x,
            Err(e) => {
                diags.push(
                    Diagnostic::error(format!("{what}: {e}"), file.span.clone()).with_hint(
                        "an OpenFAST BeamDyn primary input file and the blade file its `BldFile` names (relative to it); paths relative to the model file",
                    ),
                );
                continue;
            }
        };
        // Key points' η: cumulative chord length (exact on straight blades).
        let mut s = vec![0.0];
        for w in blade.key_points.windows(2) {
            let d = Vector3::new(w[1][0] - w[0][0], w[1][1] - w[0][1], w[1][2] - w[0][2]);
            s.push(s[s.len() - 1] + d.norm());
        }
        let total = s[s.len() - 1];
        bi.points = Some(
            blade
                .key_points
                .iter()
                .map(|k| {
                    let p = origin + r * Vector3::new(k[0], k[1], k[2]);
                    [p.x, p.y, p.z]
                })
                .collect(),
        );
        bi.twist = Some(
            blade
                .key_points
                .iter()
                .zip(&s)
                .map(|(k, si)| [si / total, -k[3].to_radians()])
                .collect(),
        );
        let x = r.column(0);
        bi.y_axis = Some([x[0], x[1], x[2]]);
        if bi.order == 0 {
            bi.order = blade.order;
        }
        if bi.quadrature.is_none() {
            // Gauss (p + 1 points) is samara's `full`; BeamDyn's trapezoidal rule over the
            // stations has no counterpart here and is taken as `full` too.
            bi.quadrature = Some(BeamQuadrature::Full);
        }
        if bi.damping.is_none() {
            bi.damping = blade.damping.map(|mu| damping_from_beamdyn_ordering(&mu));
        }
        let arr = |m: &Matrix6<f64>| -> [[f64; 6]; 6] {
            std::array::from_fn(|i| std::array::from_fn(|j| m[(i, j)]))
        };
        bi.sections = blade
            .stations
            .iter()
            .map(|(eta, k, m)| {
                Located::new(SectionInput {
                    station: *eta,
                    stiffness: Some(arr(k)),
                    mass: Some(arr(m)),
                    ordering: Some(SectionOrdering::Beamdyn),
                    ..Default::default()
                })
            })
            .collect();
    }
    diags
}
