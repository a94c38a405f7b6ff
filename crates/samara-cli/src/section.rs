//! `samara section SECTION.toml [--out DIR] [--plot] [--recover RESULTS.nc --station S
//! --time T [--beam NAME]]`: solve a cross-section, print a one-screen summary, write the
//! results (TOML, CSV), a picture, and the 3-D strain and stress for sectional forces of
//! a beam run.

use crate::report;
use nalgebra::{Matrix6, Vector6};
use samara::output::ResultsReader;
use samara::section::{self, SectionResult, input::LoadedSection, results};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

/// Options of the command.
pub struct Options {
    pub file: PathBuf,
    pub out: Option<PathBuf>,
    pub plot: bool,
    pub recover: Option<PathBuf>,
    pub station: Option<String>,
    pub time: Option<f64>,
    pub beam: Option<String>,
}

/// `root.section.toml` → `root`.
pub fn stem(path: &Path) -> String {
    let name = path
        .file_name()
        .and_then(|s| s.to_str())
        .unwrap_or("section");
    let name = name.strip_suffix(".toml").unwrap_or(name);
    name.strip_suffix(".section").unwrap_or(name).to_string()
}

pub fn run(o: &Options) -> ExitCode {
    if o.recover.is_some() != (o.station.is_some() && o.time.is_some()) {
        eprintln!(
            "error: --recover RESULTS.nc needs --station and --time (and the other way round)"
        );
        return ExitCode::from(crate::EXIT_MODEL);
    }
    let clock = Instant::now();
    let loaded = match section::input::load(&o.file) {
        Ok(l) => l,
        Err(e) => {
            for m in &e.errors {
                report::diagnostics(&m.source, &m.diagnostics);
            }
            let n: usize = e.errors.iter().map(|m| m.errors().count()).sum();
            eprintln!(
                "{}: {n} error{} — nothing was computed",
                o.file.display(),
                if n == 1 { "" } else { "s" }
            );
            return ExitCode::from(crate::EXIT_MODEL);
        }
    };
    report::diagnostics(&loaded.source, &loaded.warnings);
    let meshed = clock.elapsed();
    let r = match section::analyze(&loaded.model) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("{}: error: {e}", o.file.display());
            return ExitCode::from(crate::EXIT_MODEL);
        }
    };
    let solved = clock.elapsed();
    let out_dir = o
        .out
        .clone()
        .unwrap_or_else(|| o.file.parent().unwrap_or(Path::new(".")).join("out"));
    let stem = stem(&o.file);
    summary(
        &loaded,
        &r,
        meshed.as_secs_f64(),
        (solved - meshed).as_secs_f64(),
    );
    let hash = results::content_hash(&loaded.files);
    let toml = results::results_toml(
        &loaded.name,
        &hash,
        &r,
        &loaded.origin,
        loaded.model.mesh.elements.len(),
    );
    let mut written = Vec::new();
    if let Err(e) = std::fs::create_dir_all(&out_dir) {
        eprintln!(
            "error: cannot create the output directory '{}': {e}",
            out_dir.display()
        );
        return ExitCode::from(crate::EXIT_MODEL);
    }
    for (ext, text) in [("toml", toml), ("csv", results::results_csv(&r))] {
        let p = out_dir.join(format!("{stem}.{ext}"));
        if let Err(e) = std::fs::write(&p, text) {
            eprintln!("error: cannot write '{}': {e}", p.display());
            return ExitCode::from(crate::EXIT_MODEL);
        }
        written.push(p);
    }
    if o.plot {
        let p = out_dir.join(format!("{stem}.png"));
        match crate::section_plot::plot(&loaded, &r, &p) {
            Ok(()) => written.push(p),
            Err(e) => {
                eprintln!("error: {e}");
                return ExitCode::from(crate::EXIT_MODEL);
            }
        }
    }
    if let (Some(nc), Some(st), Some(t)) = (&o.recover, &o.station, o.time) {
        match recover(&loaded, &r, nc, st, t, o.beam.as_deref(), &out_dir, &stem) {
            Ok(files) => written.extend(files),
            Err(e) => {
                eprintln!("error: {e}");
                return ExitCode::from(crate::EXIT_MODEL);
            }
        }
    }
    println!("written:");
    for p in &written {
        println!("  {}", p.display());
    }
    ExitCode::SUCCESS
}

fn summary(l: &LoadedSection, r: &SectionResult, t_mesh: f64, t_solve: f64) {
    let p = &r.properties;
    let m = &l.model.mesh;
    let kinds: std::collections::BTreeSet<&str> =
        m.elements.iter().map(|e| e.kind.name()).collect();
    println!(
        "section '{}' ({}): {} elements ({}), {} nodes, {} material{}; meshed in {:.3} s, solved in {:.3} s",
        l.name,
        l.origin,
        m.elements.len(),
        kinds.into_iter().collect::<Vec<_>>().join(", "),
        m.nodes.len(),
        l.model.materials.len(),
        if l.model.materials.len() == 1 {
            ""
        } else {
            "s"
        },
        t_mesh,
        t_solve
    );
    println!("  area {:.6e} m², mass {:.6e} kg/m", p.area, p.mass);
    let pt = |c: [f64; 2]| format!("({:+.6e}, {:+.6e})", c[0], c[1]);
    println!(
        "  tension centre {}  shear centre {}  mass centre {}  [m]",
        pt(p.tension_centre),
        pt(p.shear_centre),
        pt(p.mass_centre)
    );
    println!(
        "  principal bending axes at {:+.4}° from y: EI = {:.6e}, {:.6e} N m²",
        p.elastic_axes_angle.to_degrees(),
        p.principal_bending[0],
        p.principal_bending[1]
    );
    println!(
        "  principal inertia axes at {:+.4}° from y: {:.6e}, {:.6e} kg m (about the mass centre)",
        p.inertia_axes_angle.to_degrees(),
        p.principal_inertia[0],
        p.principal_inertia[1]
    );
    println!(
        "  EA {:.6e} N   GJ {:.6e} N m²   GA₂ {:.6e} N   GA₃ {:.6e} N  (1/compliance)",
        p.axial, p.torsion, p.shear[0], p.shear[1]
    );
    print_matrix("stiffness about the origin [N, N m, N m²]", &r.stiffness);
    print_matrix("mass per length about the origin [kg/m, kg, kg m]", &r.mass);
}

fn print_matrix(title: &str, m: &Matrix6<f64>) {
    println!("  {title}:");
    for i in 0..6 {
        let row: Vec<String> = (0..6).map(|j| format!("{:+.5e}", m[(i, j)])).collect();
        println!("    {}", row.join(" "));
    }
}

/// Reads the sectional forces at a station and time of a results file and writes the
/// recovered fields.
#[allow(clippy::too_many_arguments)]
fn recover(
    l: &LoadedSection,
    r: &SectionResult,
    nc: &Path,
    station: &str,
    time: f64,
    beam: Option<&str>,
    out_dir: &Path,
    stem: &str,
) -> Result<Vec<PathBuf>, String> {
    let mut rd = ResultsReader::open(nc).map_err(|e| e.to_string())?;
    let names = rd.section_names.clone();
    if names.is_empty() {
        return Err(format!(
            "{} has no beam sections (the model has no beams)",
            nc.display()
        ));
    }
    let eta = rd.read("section_eta").map_err(|e| e.to_string())?;
    if eta.len() != names.len() {
        return Err(format!(
            "{} is damaged: {} section names but {} stations",
            nc.display(),
            names.len(),
            eta.len()
        ));
    }
    let beam_of = |n: &str| {
        n.rsplit_once('#')
            .map(|(b, _)| b.to_string())
            .unwrap_or_default()
    };
    let mut beams: Vec<String> = names.iter().map(|n| beam_of(n)).collect();
    beams.dedup();
    let k = if let Some(k) = names.iter().position(|n| n == station) {
        k
    } else {
        let s: f64 = station.parse().map_err(|_| {
            format!(
                "--station '{station}' is neither a section name ({} …) nor a number η in [0, 1]",
                names.iter().take(3).cloned().collect::<Vec<_>>().join(", ")
            )
        })?;
        if !(0.0..=1.0).contains(&s) {
            return Err(format!(
                "--station {s} is outside [0, 1] (normalized arc length)"
            ));
        }
        let b = match beam {
            Some(b) => {
                if !beams.iter().any(|x| x == b) {
                    return Err(format!(
                        "--beam '{b}' is not in the results; the beams are: {}",
                        beams.join(", ")
                    ));
                }
                b.to_string()
            }
            None if beams.len() == 1 => beams[0].clone(),
            None => {
                return Err(format!(
                    "the results have several beams ({}): name one with --beam",
                    beams.join(", ")
                ));
            }
        };
        (0..names.len())
            .filter(|&i| beam_of(&names[i]) == b)
            .min_by(|&i, &j| (eta[i] - s).abs().total_cmp(&(eta[j] - s).abs()))
            .ok_or("no section of that beam")?
    };
    let times = rd.time().map_err(|e| e.to_string())?;
    if times.is_empty() {
        return Err(format!("{} has no output times", nc.display()));
    }
    let ti = (0..times.len())
        .min_by(|&i, &j| (times[i] - time).abs().total_cmp(&(times[j] - time).abs()))
        .expect("times");
    let ns = names.len();
    let f = rd.read("beam_force").map_err(|e| e.to_string())?;
    let m = rd.read("beam_moment").map_err(|e| e.to_string())?;
    let at = |v: &[f64], c: usize| {
        v.get((ti * ns + k) * 3 + c)
            .copied()
            .ok_or_else(|| format!("{} is truncated: no beam forces at that time", nc.display()))
    };
    let theta = Vector6::new(
        at(&f, 0)?,
        at(&f, 1)?,
        at(&f, 2)?,
        at(&m, 0)?,
        at(&m, 1)?,
        at(&m, 2)?,
    );
    if !theta.iter().all(|x| x.is_finite()) {
        return Err("the sectional forces at that station and time are not finite".into());
    }
    let values = section::recovery::recover(&l.model, r, &theta);
    let vm = values
        .iter()
        .map(|v| section::recovery::von_mises(&v.stress))
        .fold(0.0f64, f64::max);
    let max_axial = values
        .iter()
        .map(|v| v.stress[0].abs())
        .fold(0.0f64, f64::max);
    println!(
        "recovery at section {} (η = {:.4}) and t = {} s (nearest output time to {time}):",
        names[k],
        eta.get(k).copied().unwrap_or(f64::NAN),
        times[ti]
    );
    println!(
        "  forces  N {:+.4e} V₂ {:+.4e} V₃ {:+.4e} N   moments T {:+.4e} M₂ {:+.4e} M₃ {:+.4e} N m",
        theta[0], theta[1], theta[2], theta[3], theta[4], theta[5]
    );
    println!("  largest |σxx| {max_axial:.4e} Pa, largest von Mises {vm:.4e} Pa");
    let name = format!("{stem}_recovery");
    let files =
        section::recovery::write(out_dir, &name, &l.model, &values).map_err(|e| e.to_string())?;
    Ok(files.to_vec())
}
