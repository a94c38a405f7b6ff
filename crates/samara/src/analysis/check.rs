//! Checks of the analyses that need the built system, run before anything is solved and
//! reported like the model file's other errors (file, line, column, hint):
//!
//! - a modal or Campbell analysis of a model without mass (the mass matrix at the
//!   model's initial state is zero);
//! - `n_modes` above the degrees of freedom n − m (unknowns minus constraint equations),
//!   at the `n_modes` key (or at the analysis's name when the default of 10 is too many);
//! - a Floquet `period` (or `speed`) that is not a period of the loads: the residual and
//!   the K and C matrices at the model's initial state, at the time the analysis starts,
//!   differ at t and t + T ([`super::floquet::load_periodicity`], tolerance 10⁻⁸).
//!
//! The analyses check the same again when they run (a library user may skip this), so
//! these are the same errors found earlier, with their place in the file.

use super::floquet::load_periodicity;
use crate::model::{AnalysisDef, AnalysisKind, Diagnostic, LoadedModel, Model, ModelError};
use crate::system::System;

/// Tolerance of the periodicity check, relative to each quantity's largest entry.
pub const PERIODICITY_TOLERANCE: f64 = 1e-8;

/// The errors of `loaded`'s analyses found with the built system `sys`; `Ok` when there
/// are none.
pub fn check_analyses(loaded: &LoadedModel, sys: &System) -> Result<(), ModelError> {
    let diagnostics = analysis_diagnostics(&loaded.model, sys);
    if diagnostics.is_empty() {
        Ok(())
    } else {
        Err(ModelError {
            source: loaded.source.clone(),
            diagnostics,
        })
    }
}

/// The diagnostics of [`check_analyses`].
pub fn analysis_diagnostics(model: &Model, sys: &System) -> Vec<Diagnostic> {
    let mut out = Vec::new();
    let eigen = |d: &AnalysisDef| match &d.kind {
        AnalysisKind::Modal(m) => Some(m.n_modes),
        AnalysisKind::Campbell(c) => Some(c.modal.n_modes),
        _ => None,
    };
    let needs_matrices = model.analyses.iter().any(|d| eigen(d).is_some());
    let initial = sys.initial_state();
    let mats = needs_matrices.then(|| sys.matrices(&sys.context(initial.time, 1.0), &initial));
    for def in &model.analyses {
        if let (Some(n_modes), Some(mats)) = (eigen(def), &mats) {
            let what = format!("analysis '{}'", def.name);
            if mats.mass.as_ref().val().iter().all(|v| *v == 0.0) {
                let mut d = Diagnostic::error(
                    format!(
                        "{what}: the model has no mass, and a {} analysis needs inertia",
                        def.type_name()
                    ),
                    def.spans.name.clone(),
                );
                d.hint =
                    Some("give the bodies a mass and the beams a density or mass matrix".into());
                out.push(d);
                continue;
            }
            let dof = mats.n.saturating_sub(mats.m);
            if n_modes > dof {
                let (span, asked) = match &def.spans.n_modes {
                    Some(s) => (Some(s.clone()), format!("`n_modes` = {n_modes}")),
                    None => (
                        def.spans.name.clone(),
                        format!("the default n_modes = {n_modes}"),
                    ),
                };
                let mut d = Diagnostic::error(
                    format!(
                        "{what}: {asked} is more than the model's {dof} degrees of freedom ({} unknowns, {} constraint equations)",
                        mats.n, mats.m
                    ),
                    span,
                );
                d.hint = Some(format!("ask for at most n_modes = {dof}"));
                out.push(d);
            }
        }
        if let AnalysisKind::Floquet(f) = &def.kind {
            let mut state = initial.clone();
            state.time = start_time(model, def);
            let (diff, at) = load_periodicity(sys, &state, f.period);
            if diff > PERIODICITY_TOLERANCE {
                let mut d = Diagnostic::error(
                    format!(
                        "analysis '{}': T = {} s is not a period of the loads: the forces or tangents at t = {at} s and t + T differ by {diff:.3e} (relative)",
                        def.name, f.period
                    ),
                    def.spans.period.clone().or_else(|| def.spans.name.clone()),
                );
                d.hint = Some("`period` (or 2π/`speed`) must be a period of every time function of the model (a sine of frequency f repeats after k/f)".into());
                out.push(d);
            }
        }
    }
    out
}

/// The time an analysis starts at: 0, the time asked of the analysis it starts from, or
/// that analysis's end (through the chain of `start_from`).
fn start_time(model: &Model, def: &AnalysisDef) -> f64 {
    let mut d = def;
    // Each analysis starts from an earlier one, so the walk ends.
    for _ in 0..model.analyses.len() {
        let Some(i) = d.start_from else {
            return 0.0;
        };
        if let Some(t) = d.start_time {
            return t;
        }
        let from = &model.analyses[i];
        if let Some(t) = from.end_time() {
            return t;
        }
        d = from;
    }
    0.0
}
