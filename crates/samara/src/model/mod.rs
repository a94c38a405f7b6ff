//! The model: what the engineer describes, checked and with every reference resolved.
//!
//! `input` is the file schema; `validate` turns it into a [`Model`] or a list of
//! diagnostics with file, line and column. Everything downstream (system, analyses) reads
//! only the validated [`Model`].

pub mod beamdyn_files;
pub mod components;
pub mod document;
pub mod input;
pub mod section_files;
mod validate;

pub use crate::core::NodeRef;
pub use crate::diagnostics::Located;
pub use crate::diagnostics::{Diagnostic, MAX_MAGNITUDE, ModelError, Severity, SourceFile};
pub use crate::diagnostics::{error, located};
pub use crate::elements::beam::BeamDef;
pub use crate::joints::COMPONENT_NAMES;
pub use crate::joints::{BacklashDef, ComponentDef, ForceLaw, JointDef};
pub use crate::math::TimeFunction;
pub use components::beam::input as beam_input;
pub use components::body::BodyDef;
pub use components::force::LoadDef;
pub use components::signal::SignalDef;
pub use components::spring::SpringDef;
pub use components::{Model, ModelInput};
pub use input::{
    EigensolverType, FormulationType, IntegratorType, JacobianUpdate, JointType, LinearSolverType,
    LoadFrame, Partition, StepControlType,
};
pub use section_files::LoadOptions;
pub use validate::{Checker, Entry, validate};

use crate::math::Rotation;
use nalgebra::Vector3;
use std::path::Path;

/// The largest number of nodes a model may have (given and created by beams together):
/// about 1 GB of iteration matrix, well inside what one machine holds.
pub const MAX_NODES: usize = 1_000_000;

/// Whether a name can become a file name as it is: letters, digits, `_`, `-` and `.`,
/// not starting with `.` (so never `.`, `..` or a hidden file), at most 128 characters.
pub fn is_plain_file_name(name: &str) -> bool {
    !name.is_empty()
        && name.len() <= 128
        && !name.starts_with('.')
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'))
}

/// A 6-DOF node and its initial state.
#[derive(Clone, Debug)]
pub struct NodeDef {
    pub name: String,
    pub position: Vector3<f64>,
    pub orientation: Rotation,
    /// Global frame.
    pub velocity: Vector3<f64>,
    /// Global frame.
    pub angular_velocity: Vector3<f64>,
}

/// Newton and constraint settings shared by all analyses.
#[derive(Clone, Debug, PartialEq)]
pub struct SolverSettings {
    pub scaling: bool,
    pub penalty: f64,
    pub tolerance: f64,
    pub relative_tolerance: f64,
    pub max_iterations: usize,
    pub diagnostics: bool,
    pub linear_solver: LinearSolverType,
}

impl Default for SolverSettings {
    fn default() -> Self {
        Self {
            scaling: true,
            penalty: 1.0,
            tolerance: 1e-8,
            relative_tolerance: 1e-6,
            max_iterations: 20,
            diagnostics: false,
            linear_solver: LinearSolverType::Auto,
        }
    }
}

/// Time integration settings.
#[derive(Clone, Debug, PartialEq)]
pub struct DynamicSettings {
    pub t_start: f64,
    pub t_end: f64,
    pub step: f64,
    pub rho_inf: f64,
    pub min_step: f64,
    pub output_every: usize,
    /// Records at t_start + kΔ, the steps landing on them (`None`: every
    /// `output_every`-th step).
    pub output_interval: Option<f64>,
    pub jacobian: JacobianUpdate,
    pub formulation: FormulationType,
    pub solver: SolverSettings,
    /// Adaptive steps (`None`: fixed steps).
    pub adaptive: Option<AdaptiveSettings>,
    /// The time integrator (generalized-α unless chosen).
    pub integrator: IntegratorType,
    /// How the Newton iteration is shared out (generalized-α).
    pub partition: Partition,
}

/// Error control of adaptive steps: the local error estimate e of every unknown is kept
/// below `tolerance_abs + tolerance_rel·|q|`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdaptiveSettings {
    pub tolerance_abs: f64,
    pub tolerance_rel: f64,
    pub step_max: f64,
    /// Steps land on the zeros of the elements' event functions ([`crate::elements::Element::events`]).
    pub event_location: bool,
}

impl DynamicSettings {
    pub fn new(t_end: f64, step: f64, rho_inf: f64) -> Self {
        Self {
            t_start: 0.0,
            t_end,
            step,
            rho_inf,
            min_step: step / 1024.0,
            output_every: 1,
            output_interval: None,
            jacobian: JacobianUpdate::Full,
            formulation: if rho_inf >= 1.0 {
                FormulationType::StabilizedIndex2
            } else {
                FormulationType::Index3
            },
            solver: SolverSettings::default(),
            partition: Partition::None,
            adaptive: None,
            integrator: IntegratorType::GeneralizedAlpha,
        }
    }
}

/// Static analysis settings.
#[derive(Clone, Debug, PartialEq)]
pub struct StaticSettings {
    pub load_steps: usize,
    pub time: f64,
    pub solver: SolverSettings,
    /// Spinning-rotor statics: the nodes turning steadily (centrifugal and gyroscopic
    /// loads; the speed follows the load factor as Ω√λ).
    pub rotation: Option<crate::linear::Spin>,
}

impl Default for StaticSettings {
    fn default() -> Self {
        Self {
            load_steps: 1,
            time: 0.0,
            solver: SolverSettings::default(),
            rotation: None,
        }
    }
}

/// Modal analysis settings.
#[derive(Clone, Debug, PartialEq)]
pub struct ModalSettings {
    pub n_modes: usize,
    /// Target frequency [Hz].
    pub shift: Option<f64>,
    pub write_matrices: bool,
    pub eigensolver: EigensolverType,
    /// Linearize in the frame turning with this rotation.
    pub rotation: Option<crate::linear::SteadyRotation>,
}

impl Default for ModalSettings {
    fn default() -> Self {
        Self {
            n_modes: 10,
            shift: None,
            write_matrices: false,
            eigensolver: EigensolverType::Auto,
            rotation: None,
        }
    }
}

/// Campbell diagram settings: each speed a spinning static analysis (`load_steps`,
/// `time`, `solver`) and a rotating-frame modal analysis (`modal`, without rotation).
#[derive(Clone, Debug, PartialEq)]
pub struct CampbellSettings {
    /// Rotor speeds [rad/s], one point each.
    pub speeds: Vec<f64>,
    /// Axis and centre of the rotation (its `omega` is not used).
    pub rotation: crate::linear::SteadyRotation,
    pub modal: ModalSettings,
    pub load_steps: usize,
    pub time: f64,
    pub solver: SolverSettings,
}

/// Floquet stability settings: the periodic solution through the starting state over
/// one `period`, integrated and linearized in `steps_per_period` generalized-α steps.
#[derive(Clone, Debug, PartialEq)]
pub struct FloquetSettings {
    /// T [s] (given, or 2π/speed).
    pub period: f64,
    pub steps_per_period: usize,
    pub rho_inf: f64,
    /// Modes written (largest multiplier modulus first).
    pub n_modes: usize,
    pub solver: SolverSettings,
}

#[derive(Clone, Debug, PartialEq)]
pub enum AnalysisKind {
    Dynamic(DynamicSettings),
    Static(StaticSettings),
    Modal(ModalSettings),
    Campbell(CampbellSettings),
    Floquet(FloquetSettings),
}

#[derive(Clone, Debug, PartialEq)]
pub struct AnalysisDef {
    pub name: String,
    /// Index of an earlier analysis whose final state is the initial state of this one.
    pub start_from: Option<usize>,
    /// With `start_from` a dynamic analysis: the time of its run whose stored state
    /// (the output nearest it) is the initial state instead of the final one.
    pub start_time: Option<f64>,
    pub kind: AnalysisKind,
    /// Where the analysis's keys are in the model file, for the checks that need the
    /// built system (`samara::analysis::check_analyses`).
    pub spans: AnalysisSpans,
}

/// Byte ranges in the model file of an analysis's entries (`None`: not written there).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AnalysisSpans {
    /// The analysis's name.
    pub name: Option<std::ops::Range<usize>>,
    /// `n_modes`.
    pub n_modes: Option<std::ops::Range<usize>>,
    /// `period` or `speed` (Floquet).
    pub period: Option<std::ops::Range<usize>>,
}

impl AnalysisDef {
    pub fn type_name(&self) -> &'static str {
        match self.kind {
            AnalysisKind::Dynamic(_) => "dynamic",
            AnalysisKind::Static(_) => "static",
            AnalysisKind::Modal(_) => "modal",
            AnalysisKind::Campbell(_) => "campbell",
            AnalysisKind::Floquet(_) => "floquet",
        }
    }

    /// The fewest output times a dynamic or static analysis writes (`None` for the other
    /// kinds, whose records are few). Dynamic: the initial state, then one per
    /// `output_interval`, or one per `output_every` steps of at most `step` (fixed) or
    /// `step_max` (adaptive), and the final state; breakpoints, events and step cuts only
    /// add steps, so this is a lower bound, and the count for fixed steps that meet no
    /// breakpoint. Static: the unloaded state and one per load step (cut increments
    /// add records).
    pub fn min_records(&self) -> Option<u64> {
        let d = match &self.kind {
            AnalysisKind::Dynamic(d) => d,
            AnalysisKind::Static(s) => return Some((s.load_steps as u64).saturating_add(1)),
            _ => return None,
        };
        let span = d.t_end - d.t_start;
        if !span.is_finite() || span <= 0.0 {
            return Some(1);
        }
        // A last step shorter than 1e-9 of a step is merged into the one before
        // (analysis/dynamic.rs), and the final state is always written.
        let outputs = match d.output_interval {
            Some(dt) => (span / dt - 1e-9).ceil(),
            None => {
                let h = d.adaptive.map_or(d.step, |a| a.step_max.max(d.step));
                let steps = (span / h - 1e-9).ceil();
                (steps / d.output_every.max(1) as f64).ceil()
            }
        };
        // Validation bounds the steps and records by 10¹²; `as` saturates regardless.
        Some(
            1 + if outputs.is_finite() {
                outputs as u64
            } else {
                0
            },
        )
    }

    /// The time the analysis ends at (a static analysis: the time its loads are taken
    /// at); `None` when the state it starts from decides (a modal analysis).
    pub fn end_time(&self) -> Option<f64> {
        match &self.kind {
            AnalysisKind::Dynamic(d) => Some(d.t_end),
            AnalysisKind::Static(s) => Some(s.time),
            AnalysisKind::Modal(_) | AnalysisKind::Campbell(_) | AnalysisKind::Floquet(_) => None,
        }
    }
}

/// A validated model and the warnings found while checking it.
#[derive(Clone, Debug)]
pub struct LoadedModel {
    pub model: Model,
    pub source: SourceFile,
    pub warnings: Vec<Diagnostic>,
}

impl Model {
    /// Index of a node by name.
    pub fn node_index(&self, name: &str) -> Option<usize> {
        self.nodes.iter().position(|n| n.name == name)
    }

    /// Parses and validates model text; `path` is used in diagnostics and to find the
    /// files the model names (sections files, section files).
    pub fn from_toml_str(text: &str, path: impl AsRef<Path>) -> Result<LoadedModel, ModelError> {
        Self::from_toml_str_with(text, path, &LoadOptions::default())
    }

    /// [`Model::from_toml_str`] with options (the section cache).
    pub fn from_toml_str_with(
        text: &str,
        path: impl AsRef<Path>,
        options: &LoadOptions,
    ) -> Result<LoadedModel, ModelError> {
        let source = SourceFile::new(path.as_ref(), text);
        let mut input: ModelInput = match toml::from_str(text) {
            Ok(i) => i,
            Err(e) => {
                return Err(ModelError {
                    source,
                    diagnostics: vec![crate::diagnostics::parse_error_diagnostic(
                        &e,
                        text,
                        input::KEY_SPELLINGS,
                    )],
                });
            }
        };
        let mut notes = beamdyn_files::resolve(&mut input, &source);
        notes.extend(section_files::resolve(&mut input, &source, options));
        if notes.iter().any(|d| d.severity == Severity::Error) {
            return Err(ModelError {
                source,
                diagnostics: notes,
            });
        }
        let mut loaded = validate(&input, source)?;
        loaded.warnings.extend(notes);
        Ok(loaded)
    }

    /// Reads, parses and validates a model file.
    pub fn from_file(path: impl AsRef<Path>) -> Result<LoadedModel, crate::Error> {
        Self::from_file_with(path, &LoadOptions::default())
    }

    /// [`Model::from_file`] with options (the section cache).
    pub fn from_file_with(
        path: impl AsRef<Path>,
        options: &LoadOptions,
    ) -> Result<LoadedModel, crate::Error> {
        use crate::input_files::{InputFileError, read_text};
        let path = path.as_ref();
        let text = match read_text(path) {
            Ok(t) => t,
            Err(InputFileError::Io(e)) => {
                return Err(crate::Error::Io {
                    path: path.to_path_buf(),
                    action: "read the model file",
                    source: e,
                });
            }
            Err(InputFileError::NotUtf8 { offset, .. }) => {
                let bytes = std::fs::read(path).unwrap_or_default();
                let text = String::from_utf8_lossy(&bytes[..offset.min(bytes.len())]);
                return Err(crate::Error::Model(ModelError {
                    source: SourceFile::new(path, format!("{text}\u{FFFD}")),
                    diagnostics: vec![
                        Diagnostic::error(
                            "the file is not UTF-8 text: this byte is invalid",
                            Some(offset..offset + 1),
                        )
                        .with_hint("save the model file as UTF-8 (TOML files are UTF-8)"),
                    ],
                }));
            }
            Err(source) => {
                return Err(crate::Error::Input {
                    path: path.to_path_buf(),
                    source,
                });
            }
        };
        Ok(Self::from_toml_str_with(&text, path, options)?)
    }
}
