//! What `samara section` writes, and the cache of solved sections.
//!
//! - `<stem>.toml`: a `[section]` table of derived properties (name, content hash, mass per
//!   length, centres, principal axes, effective stiffnesses), then a `[[beams.sections]]`
//!   entry (`station = 0.0`, `stiffness`, `mass`) that pastes into a model as it is;
//! - `<stem>.csv`: the sections file of the beam input (`sections_file = "…"`): the header
//!   `station,K11,…,K66,M11,…,M66` and one row at station 0.
//!
//! Numbers are written with 17 significant digits, so reading them back gives the same
//! matrices bit for bit. The cache holds the same TOML under `<content hash>.toml`; the
//! hash is SHA-256 of the samara version and the bytes of every file the section is built
//! from (the section file, its mesh or coordinates file).

use super::input::SectionFile;
use super::{Properties, SectionResult};
use crate::diagnostics::{Diagnostic, Located, ModelError, SourceFile};
use nalgebra::Matrix6;
use serde::Deserialize;
use sha2::{Digest, Sha256};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Column names of the sections CSV.
pub fn csv_header() -> String {
    let mut h = String::from("station");
    for m in ["K", "M"] {
        for i in 1..=6 {
            for j in 1..=6 {
                let _ = write!(h, ",{m}{i}{j}");
            }
        }
    }
    h
}

fn num(x: f64) -> String {
    // Shortest representation that reads back exactly.
    let s = format!("{x:e}");
    if s.parse::<f64>() == Ok(x) {
        s
    } else {
        format!("{x:.16e}")
    }
}

fn matrix(m: &Matrix6<f64>) -> String {
    let rows: Vec<String> = (0..6)
        .map(|i| {
            let r: Vec<String> = (0..6).map(|j| num(m[(i, j)])).collect();
            format!("  [{}]", r.join(", "))
        })
        .collect();
    format!("[\n{},\n]", rows.join(",\n"))
}

fn pair(p: [f64; 2]) -> String {
    format!("[{}, {}]", num(p[0]), num(p[1]))
}

/// The results TOML of a solved section.
pub fn results_toml(
    name: &str,
    hash: &str,
    r: &SectionResult,
    origin: &str,
    elements: usize,
) -> String {
    let p = &r.properties;
    let mut out = String::new();
    let _ = writeln!(
        out,
        "# samara {} section results: {name} ({origin}, {elements} elements)",
        crate::VERSION
    );
    let _ = writeln!(
        out,
        "# Section frame: x along the beam, (y, z) in the section; stiffness rows and columns"
    );
    let _ = writeln!(
        out,
        "# (axial, shear y, shear z, torsion, bending about y, bending about z) about the origin;"
    );
    let _ = writeln!(
        out,
        "# mass per unit length about the origin. docs/sections.md states the convention."
    );
    let _ = writeln!(out, "[section]");
    let _ = writeln!(out, "name = {:?}", name);
    let _ = writeln!(out, "hash = {:?}", hash);
    let _ = writeln!(out, "samara = {:?}", crate::VERSION);
    let _ = writeln!(out, "elements = {elements}");
    let _ = writeln!(out, "area = {}", num(p.area));
    let _ = writeln!(out, "mass_per_length = {}", num(p.mass));
    let _ = writeln!(out, "mass_centre = {}", pair(p.mass_centre));
    let _ = writeln!(out, "tension_centre = {}", pair(p.tension_centre));
    let _ = writeln!(out, "shear_centre = {}", pair(p.shear_centre));
    let _ = writeln!(
        out,
        "elastic_axes_angle = {}  # deg, from y to the first principal bending axis",
        num(p.elastic_axes_angle.to_degrees())
    );
    let _ = writeln!(
        out,
        "principal_bending = {}  # N m², about the two principal axes",
        pair(p.principal_bending)
    );
    let _ = writeln!(
        out,
        "inertia_axes_angle = {}  # deg",
        num(p.inertia_axes_angle.to_degrees())
    );
    let _ = writeln!(
        out,
        "principal_inertia = {}  # kg m, about the mass centre",
        pair(p.principal_inertia)
    );
    let _ = writeln!(out, "axial = {}  # N, 1/F11", num(p.axial));
    let _ = writeln!(out, "torsion = {}  # N m², 1/F44", num(p.torsion));
    let _ = writeln!(out, "shear = {}  # N, 1/F22, 1/F33", pair(p.shear));
    let _ = writeln!(out);
    let _ = writeln!(out, "[[beams.sections]]");
    let _ = writeln!(out, "station = 0.0");
    let _ = writeln!(out, "stiffness = {}", matrix(&r.stiffness));
    let _ = writeln!(out, "mass = {}", matrix(&r.mass));
    out
}

/// The sections CSV of a solved section (one row, station 0).
pub fn results_csv(r: &SectionResult) -> String {
    let mut row = vec!["0".to_string()];
    for m in [&r.stiffness, &r.mass] {
        for i in 0..6 {
            for j in 0..6 {
                row.push(num(m[(i, j)]));
            }
        }
    }
    format!("{}\n{}\n", csv_header(), row.join(","))
}

#[derive(Deserialize)]
struct Cached {
    section: CachedHeader,
    beams: CachedBeams,
}

#[derive(Deserialize)]
struct CachedHeader {
    hash: String,
    samara: String,
}

#[derive(Deserialize)]
struct CachedBeams {
    sections: Vec<CachedSection>,
}

#[derive(Deserialize)]
struct CachedSection {
    stiffness: [[f64; 6]; 6],
    mass: [[f64; 6]; 6],
}

/// Stiffness and mass from a results TOML whose hash is `hash` (None if it does not match
/// or cannot be read).
pub fn read_results(text: &str, hash: &str) -> Option<(Matrix6<f64>, Matrix6<f64>)> {
    let c: Cached = toml::from_str(text).ok()?;
    if c.section.hash != hash || c.section.samara != crate::VERSION {
        return None;
    }
    let s = c.beams.sections.first()?;
    Some((
        Matrix6::from_fn(|i, j| s.stiffness[i][j]),
        Matrix6::from_fn(|i, j| s.mass[i][j]),
    ))
}

/// The files a section file reads (itself first), from a light parse; the paths of
/// referenced files are relative to the section file.
pub fn dependencies(text: &str, path: &Path) -> Vec<PathBuf> {
    let mut out = vec![path.to_path_buf()];
    let base = path.parent().unwrap_or(Path::new("."));
    if let Ok(f) = toml::from_str::<SectionFile>(text) {
        if let Some(m) = &f.mesh {
            out.push(base.join(&m.value.file.value));
        }
        if let Some(Located {
            value:
                super::input::AirfoilInput {
                    coordinates_file: Some(c),
                    ..
                },
            ..
        }) = &f.airfoil
        {
            out.push(base.join(&c.value));
        }
    }
    out
}

/// SHA-256 (hex) of the samara version and the contents of `files` (missing files hash as
/// their absence).
pub fn content_hash(files: &[PathBuf]) -> String {
    let mut h = Sha256::new();
    h.update(b"samara-section\0");
    h.update(crate::VERSION.as_bytes());
    for f in files {
        match std::fs::read(f) {
            Ok(bytes) => {
                h.update((bytes.len() as u64).to_le_bytes());
                h.update(&bytes);
            }
            Err(_) => h.update(b"\0missing\0"),
        }
    }
    h.finalize().iter().map(|b| format!("{b:02x}")).collect()
}

/// A solved (or cached) section for the beam input.
#[derive(Clone, Debug)]
pub struct Solved {
    pub stiffness: Matrix6<f64>,
    pub mass: Matrix6<f64>,
    pub hash: String,
    /// Taken from the cache.
    pub cached: bool,
    /// Properties (only when solved now).
    pub properties: Option<Properties>,
}

/// Where cached section results live and whether new ones may be written.
#[derive(Clone, Debug)]
pub struct Cache {
    pub dir: PathBuf,
    pub write: bool,
}

/// Solves the section file at `path` or takes it from the cache.
pub fn solve_cached(path: &Path, cache: Option<&Cache>) -> Result<Solved, Vec<ModelError>> {
    let text = crate::input_files::read_text(path).map_err(|e| {
        vec![ModelError {
            source: SourceFile::new(path, ""),
            diagnostics: vec![Diagnostic::error(
                format!("cannot read the section file: {e}"),
                None,
            )],
        }]
    })?;
    let hash = content_hash(&dependencies(&text, path));
    if let Some(c) = cache {
        let file = c.dir.join(format!("{hash}.toml"));
        if let Ok(t) = crate::input_files::read_text(&file)
            && let Some((k, m)) = read_results(&t, &hash)
        {
            return Ok(Solved {
                stiffness: k,
                mass: m,
                hash,
                cached: true,
                properties: None,
            });
        }
    }
    let loaded = super::input::from_str(&text, path).map_err(|e| e.errors)?;
    let r = super::analyze(&loaded.model).map_err(|e| {
        vec![ModelError {
            source: loaded.source.clone(),
            diagnostics: vec![Diagnostic::error(e.to_string(), None)],
        }]
    })?;
    if let Some(c) = cache.filter(|c| c.write) {
        let toml = results_toml(
            &loaded.name,
            &hash,
            &r,
            &loaded.origin,
            loaded.model.mesh.elements.len(),
        );
        // A cache that cannot be written only costs a recomputation next time.
        if std::fs::create_dir_all(&c.dir).is_ok() {
            let tmp = c.dir.join(format!("{hash}.toml.tmp"));
            if std::fs::write(&tmp, toml).is_ok() {
                let _ = std::fs::rename(&tmp, c.dir.join(format!("{hash}.toml")));
            }
        }
    }
    Ok(Solved {
        stiffness: r.stiffness,
        mass: r.mass,
        hash,
        cached: false,
        properties: Some(r.properties),
    })
}
