//! `samara`: run, check and describe multibody models.

mod campbell_plot;
mod info;
mod plot;
mod report;
mod section;
mod section_plot;
mod span_plot;
mod sweep;

use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use samara::analysis::{Chain, run_analysis};
use samara::math::isa::{ISA_VARIABLE, Isa};
use samara::model::{LoadOptions, LoadedModel, Model, ModelInput};
use samara::output::ResultsFile;
use samara::system::System;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant};

/// Exit status: the model (or an input/output file) is unusable.
pub(crate) const EXIT_MODEL: u8 = 1;
/// Exit status: an analysis stopped before its end.
const EXIT_SOLVER: u8 = 2;

#[derive(Parser)]
#[command(name = "samara", version, about = "Flexible multibody dynamics", long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run every analysis of a model; one results file (NetCDF) per analysis.
    Run {
        /// Model file (TOML).
        model: PathBuf,
        /// Results directory [default: out/<model file stem>/ beside the model].
        #[arg(long, short)]
        out: Option<PathBuf>,
        /// No progress bar.
        #[arg(long, short)]
        quiet: bool,
    },
    /// Run a model once per case of a parameter grid or list: `<out>/case_NNNN/` per case
    /// and `<out>/index.csv` (values, status, error of every case).
    Sweep {
        /// Model file (TOML).
        model: PathBuf,
        /// Parameters file (TOML): `[grid]` with `"path" = [values]`, or `[[cases]]`
        /// with `"path" = value`; paths such as `bodies.bob.mass`, `model.gravity[2]`.
        #[arg(long, value_name = "PARAMS.toml")]
        grid: PathBuf,
        /// Results directory [default: out/<model file stem>/sweep/ beside the model].
        #[arg(long, short)]
        out: Option<PathBuf>,
    },
    /// Validate a model without running it; print the least size of each dynamic or
    /// static analysis's results and refuse those the results folder's disk cannot hold.
    Check {
        /// Model file (TOML).
        model: PathBuf,
        /// Results directory the sizes are checked against [default: out/<model file
        /// stem>/ beside the model]; nothing is written there.
        #[arg(long, short)]
        out: Option<PathBuf>,
    },
    /// Print the JSON Schema of the model file.
    Schema,
    /// Plot time histories of channels, e.g. `position:bob:z`, `joint_force:pivot:x`, `kinetic_energy`;
    /// `campbell` draws the Campbell diagram of a Campbell analysis; `span LINE QUANTITY…`
    /// a lifting line's station outputs against span (`--time`).
    Plot {
        /// Results file (NetCDF) written by `samara run`.
        results: PathBuf,
        /// Channels: `variable` or `variable:node_or_joint:component` (x, y, z; w for quaternions);
        /// or `campbell`; or `span LINE QUANTITY…` (station outputs such as `alpha`, `cl`, `normal_load`).
        #[arg(required = true)]
        channels: Vec<String>,
        /// Figure file, .png or .svg [default: `<results stem>.png` beside the results file].
        #[arg(long, short)]
        out: Option<PathBuf>,
        /// Output time of a span-wise plot (the nearest one; repeat for several curves)
        /// [default: the last].
        #[arg(long, allow_hyphen_values = true)]
        time: Vec<f64>,
    },
    /// Write a ParaView scene from a results file: a time series (.pvd + one binary .vtu
    /// per output time), `<stem>_scene.py` (`paraview --script=...`), and for modal results
    /// one animated series per mode.
    Vtk {
        /// Results file (NetCDF) written by `samara run`.
        results: PathBuf,
        /// Output directory [default: `<results stem>_vtk/` beside the results file].
        #[arg(long, short)]
        out: Option<PathBuf>,
        /// Modal results: scale of the mode shapes [default: largest displacement a tenth
        /// of the model's size, rotations at most 0.5 rad].
        #[arg(long)]
        mode_scale: Option<f64>,
        /// Modal results: files per period of each mode's animation.
        #[arg(long, default_value_t = 24)]
        mode_frames: usize,
    },
    /// Describe a results file: analysis, time span, nodes, joints, solver statistics, variables.
    Info {
        /// Results file (NetCDF) written by `samara run`.
        results: PathBuf,
    },
    /// Cross-sectional analysis: the 6×6 stiffness and mass of a beam section from its
    /// mesh or layup (docs/sections.md); writes `<stem>.toml` and `<stem>.csv`.
    Section {
        /// Section file (TOML).
        section: PathBuf,
        /// Output directory [default: out/ beside the section file].
        #[arg(long, short)]
        out: Option<PathBuf>,
        /// Also draw the mesh by material and ply angle, with centres and principal axes
        /// (`<stem>.png`).
        #[arg(long)]
        plot: bool,
        /// Recover the 3-D strain and stress from the sectional forces of this beam run
        /// (`<stem>_recovery.vtu` and `.csv`).
        #[arg(long, value_name = "RESULTS.nc")]
        recover: Option<PathBuf>,
        /// Section of the beam run: normalized arc length η (nearest quadrature point) or a
        /// section name such as `blade#3`.
        #[arg(long)]
        station: Option<String>,
        /// Time of the beam run (nearest output time) [s].
        #[arg(long)]
        time: Option<f64>,
        /// Beam of the run, when it has several.
        #[arg(long)]
        beam: Option<String>,
    },
}

/// Refuses a `SAMARA_ISA` that names no compiled copy, and says when it asks for a wider
/// one than the CPU runs (the kernels then run the CPU's widest; [`Isa::detected`]).
fn check_isa_variable() -> Option<ExitCode> {
    match Isa::requested() {
        Err(message) => {
            eprintln!(
                "error: {message}\n  hint: unset it to run the widest copy this CPU has ({})",
                Isa::cpu().name()
            );
            Some(ExitCode::from(EXIT_MODEL))
        }
        Ok(Some(asked)) if asked > Isa::cpu() => {
            eprintln!(
                "warning: {ISA_VARIABLE} = {} is wider than this CPU runs; running {}",
                asked.name(),
                Isa::cpu().name()
            );
            None
        }
        Ok(_) => None,
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    report::install_hook();
    if let Some(code) = check_isa_variable() {
        return code;
    }
    match cli.command {
        Command::Run { model, out, quiet } => run(&model, out, quiet),
        Command::Check { model, out } => check(&model, out),
        Command::Sweep { model, grid, out } => sweep::sweep(&model, &grid, out),
        Command::Section {
            section,
            out,
            plot,
            recover,
            station,
            time,
            beam,
        } => section::run(&section::Options {
            file: section,
            out,
            plot,
            recover,
            station,
            time,
            beam,
        }),
        Command::Info { results } => {
            let r =
                samara::output::ResultsReader::open(&results).and_then(|mut r| info::info(&mut r));
            match r {
                Ok(()) => ExitCode::SUCCESS,
                Err(e) => {
                    eprintln!("error: {e}");
                    ExitCode::from(EXIT_MODEL)
                }
            }
        }
        Command::Plot {
            results,
            channels,
            out,
            time,
        } => {
            let out = out.unwrap_or_else(|| results.with_extension("png"));
            let done = samara::output::ResultsReader::open(&results)
                .map_err(|e| e.to_string())
                .and_then(|mut r| {
                    if channels.first().is_some_and(|c| c == "span") {
                        span_plot::plot(&mut r, &channels[1..], &time, &out)
                    } else if !time.is_empty() {
                        Err("--time picks the output time of a span-wise plot (`samara plot RESULTS span LINE QUANTITY… --time T`); time histories and Campbell diagrams take every time".to_string())
                    } else if channels == ["campbell"] {
                        campbell_plot::plot(&mut r, &out)
                    } else {
                        plot::plot(&mut r, &channels, &out)
                    }
                });
            match done {
                Ok(()) => {
                    println!("{}", out.display());
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("error: {e}");
                    ExitCode::from(EXIT_MODEL)
                }
            }
        }
        Command::Vtk {
            results,
            out,
            mode_scale,
            mode_frames,
        } => {
            let dir = out.unwrap_or_else(|| {
                let stem = results
                    .file_stem()
                    .and_then(|s| s.to_str())
                    .unwrap_or("results");
                results
                    .parent()
                    .unwrap_or(Path::new("."))
                    .join(format!("{stem}_vtk"))
            });
            let written = samara::output::ResultsReader::open(&results)
                .map_err(|e| e.to_string())
                .and_then(|mut r| {
                    let options = samara::output::VtkOptions {
                        mode_scale,
                        mode_frames,
                    };
                    samara::output::write_vtk_with(&mut r, &dir, &options)
                        .map_err(|e| e.to_string())
                });
            match written {
                Ok(s) => {
                    println!(
                        "{}: {} time steps, {} points each",
                        s.collection.display(),
                        s.files.len(),
                        s.points
                    );
                    for m in &s.modes {
                        println!("{}: mode animation", m.display());
                    }
                    println!("open the scene: paraview --script={}", s.script.display());
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("error: {e}");
                    ExitCode::from(EXIT_MODEL)
                }
            }
        }
        Command::Schema => {
            let schema = schemars::schema_for!(ModelInput);
            println!(
                "{}",
                serde_json::to_string_pretty(&schema).expect("a schema serializes")
            );
            ExitCode::SUCCESS
        }
    }
}

/// Results directory of a model: `--out`, or `out/<model file stem>/` beside the model
/// file, so that two models of one folder never share a results folder (a folder cannot
/// hold two files of the same name).
pub(crate) fn results_dir(path: &Path, out: Option<PathBuf>) -> PathBuf {
    out.unwrap_or_else(|| {
        let stem = path
            .file_stem()
            .and_then(|s| s.to_str())
            .filter(|s| samara::model::is_plain_file_name(s))
            .unwrap_or("model");
        path.parent()
            .unwrap_or(Path::new("."))
            .join("out")
            .join(stem)
    })
}

/// Section files named by the model are cached in `<results dir>/sections/`; `write`
/// false only reads the cache (`samara check`).
fn load_options(results: &Path, write: bool) -> LoadOptions {
    LoadOptions {
        section_cache: Some(samara::section::results::Cache {
            dir: results.join("sections"),
            write,
        }),
    }
}

/// Loads a model, printing its diagnostics; `None` if it has errors.
fn load(path: &Path, options: &LoadOptions) -> Option<LoadedModel> {
    match Model::from_file_with(path, options) {
        Ok(loaded) => {
            report::diagnostics(&loaded.source, &loaded.warnings);
            Some(loaded)
        }
        Err(samara::Error::Model(e)) => {
            report::diagnostics(&e.source, &e.diagnostics);
            nothing_was_run(&e.source.path, e.errors().count());
            None
        }
        Err(e) => {
            report::error(&e, None);
            None
        }
    }
}

/// The model checks that need the built system (`samara::analysis::check_analyses`),
/// printed like the file's other errors; false if there are any.
fn system_checks(loaded: &LoadedModel, sys: &System) -> bool {
    match samara::analysis::check_analyses(loaded, sys) {
        Ok(()) => true,
        Err(e) => {
            report::diagnostics(&e.source, &e.diagnostics);
            nothing_was_run(&e.source.path, e.errors().count());
            false
        }
    }
}

fn check(path: &Path, out: Option<PathBuf>) -> ExitCode {
    let out_dir = results_dir(path, out);
    let Some(loaded) = load(path, &load_options(&out_dir, false)) else {
        return ExitCode::from(EXIT_MODEL);
    };
    let m = &loaded.model;
    let sys = System::new(m);
    for w in &sys.warnings {
        eprintln!("warning: {}: {w}", path.display());
    }
    if !system_checks(&loaded, &sys) {
        return ExitCode::from(EXIT_MODEL);
    }
    let Some(sizes) = results_sizes(&loaded, path, &sys, &out_dir) else {
        return ExitCode::from(EXIT_MODEL);
    };
    let dropped: usize = sys.loops.iter().map(|l| l.dropped.len()).sum();
    println!(
        "{}: ok — model '{}': {} nodes, {} bodies, {} joints ({} constraint equations{}, {} joint coordinates), {} springs, {} loads, {} analyses",
        path.display(),
        m.name,
        m.nodes.len(),
        m.bodies.len(),
        m.joints.len(),
        sys.n_multipliers,
        if dropped > 0 {
            format!(" after dropping {dropped} redundant")
        } else {
            String::new()
        },
        sys.n_coordinates,
        m.springs.len(),
        m.forces.len(),
        m.analyses.len()
    );
    for line in sizes {
        println!("  {line}");
    }
    ExitCode::SUCCESS
}

/// The least size of each dynamic or static analysis's results, a line each; `None` (with the
/// errors printed, located at the analyses) when the disk of `out_dir` cannot hold them,
/// which `samara run` would refuse at the analysis's start.
fn results_sizes(
    loaded: &LoadedModel,
    path: &Path,
    sys: &System,
    out_dir: &Path,
) -> Option<Vec<String>> {
    let mut lines = Vec::new();
    let mut errors = Vec::new();
    for def in &loaded.model.analyses {
        let projection = match ResultsFile::projection(&loaded.model, Some(path), sys, def) {
            Ok(Some(p)) => p,
            Ok(None) => continue,
            Err(e) => {
                report::error(&e, None);
                return None;
            }
        };
        if let Some(s) = projection.shortfall_in(out_dir) {
            errors.push(shortfall_diagnostic(def, &s));
        }
        lines.push(format!(
            "analysis '{}': results of {projection} in {}",
            def.name,
            out_dir.display()
        ));
    }
    if errors.is_empty() {
        return Some(lines);
    }
    report::diagnostics(&loaded.source, &errors);
    nothing_was_run(path, errors.len());
    None
}

/// An analysis whose results cannot fit, located at its name, with what to change.
fn shortfall_diagnostic(
    def: &samara::model::AnalysisDef,
    s: &samara::output::SpaceShortfall,
) -> samara::model::Diagnostic {
    samara::model::Diagnostic {
        hint: Some(s.hint().into()),
        ..samara::model::Diagnostic::error(
            format!("analysis '{}': {s}", def.name),
            def.spans.name.clone(),
        )
    }
}

/// The closing line of a model's errors.
fn nothing_was_run(path: &Path, n: usize) {
    eprintln!(
        "{}: {n} error{} — nothing was run",
        path.display(),
        if n == 1 { "" } else { "s" }
    );
}

fn run(path: &Path, out: Option<PathBuf>, quiet: bool) -> ExitCode {
    let out_dir = results_dir(path, out);
    let Some(loaded) = load(path, &load_options(&out_dir, true)) else {
        return ExitCode::from(EXIT_MODEL);
    };
    let model = &loaded.model;
    let sys = System::new(model);
    for w in &sys.warnings {
        eprintln!("warning: {w}");
    }
    if !system_checks(&loaded, &sys) {
        return ExitCode::from(EXIT_MODEL);
    }
    let show_progress = !quiet && std::io::stderr().is_terminal();
    let clock = Instant::now();
    let mut rows = Vec::new();
    let mut chain = Chain::new(model);
    let mut failed = false;
    for (index, def) in model.analyses.iter().enumerate() {
        let initial = match chain.start(&sys, def) {
            Ok(state) => state,
            Err(e) => {
                eprintln!("error: {e}");
                return ExitCode::from(EXIT_MODEL);
            }
        };
        let mut file = match ResultsFile::create(&out_dir, model, Some(path), &sys, def) {
            Ok(f) => f,
            Err(e) => {
                report::error(
                    &e,
                    Some("choose a writable results directory with --out DIR"),
                );
                return ExitCode::from(EXIT_MODEL);
            }
        };
        // Refused at its start, not hours later at a full disk (which also stalls
        // everything else writing there), located at the analysis whose settings give
        // the records; an earlier file goes back to its name.
        if let Some(s) = file.space_shortfall(def) {
            report::diagnostics(&loaded.source, &[shortfall_diagnostic(def, &s)]);
            if let Err(e) = file.discard() {
                report::error(&e, None);
            }
            return ExitCode::from(EXIT_MODEL);
        }
        if let Some(b) = &file.backup {
            eprintln!(
                "note: an earlier {} was kept as {}",
                file.path().display(),
                b.display()
            );
        }
        let bar = if show_progress {
            let b = ProgressBar::new(1000);
            b.set_style(
                ProgressStyle::with_template(
                    "{prefix:>12} [{bar:40}] {percent:>3}% {elapsed_precise} (eta {eta})",
                )
                .expect("valid template")
                .progress_chars("=> "),
            );
            b.set_prefix(def.name.clone());
            b.enable_steady_tick(Duration::from_millis(200));
            b
        } else {
            ProgressBar::hidden()
        };
        let mut progress = |f: f64| bar.set_position((f * 1000.0).round() as u64);
        let mut capture = chain.capture(index, &mut file);
        let result = run_analysis(&sys, def, initial, &mut capture, &mut progress);
        bar.finish_and_clear();
        let summary = match result {
            Ok(s) => s,
            Err(e) => {
                report::error(&e, None);
                return ExitCode::from(EXIT_MODEL);
            }
        };
        chain.finish(index, capture, summary.final_state.clone());
        let records = file.records();
        let written = match file.finish(&summary) {
            Ok(p) => p,
            Err(e) => {
                report::error(&e, None);
                return ExitCode::from(EXIT_MODEL);
            }
        };
        for w in &summary.warnings {
            eprintln!("warning: {}: {w}", def.name);
        }
        if let Some(f) = &summary.failure {
            report::solver_failure(f, &written, records);
            failed = true;
        }
        let end_time = def.end_time().unwrap_or(summary.final_state.time);
        rows.push(report::Row {
            summary: summary.clone(),
            path: written,
            records,
            end_time,
        });
        if failed {
            break;
        }
    }
    report::summary(&model.name, &rows, clock.elapsed());
    if failed {
        ExitCode::from(EXIT_SOLVER)
    } else {
        ExitCode::SUCCESS
    }
}
