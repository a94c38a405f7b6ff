//! Analyses as stages of a run: each starts from a state (the model's initial state or
//! the final state of an earlier stage), writes its results through a [`Recorder`] — time
//! records, and arrays that are not time records (a modal analysis writes modes) — and
//! leaves its final state in its summary for the next stage.
//!
//! Adding an analysis type: a module with a type implementing [`Analysis`], its settings
//! in the model (validated like the others) and one arm in [`AnalysisDef::stage`].

use super::{AnalysisSummary, Progress, Recorder, run_dynamic, run_modal, run_static};
use crate::model::{
    AnalysisDef, AnalysisKind, CampbellSettings, DynamicSettings, FloquetSettings, ModalSettings,
    StaticSettings,
};
use crate::system::{State, System};

/// A result array that is not a time history, declared before the run so that a results
/// file can define it in its header.
#[derive(Clone, Debug, PartialEq)]
pub struct ArraySpec {
    pub name: String,
    /// Dimensions (name, size), outermost first; values are row-major.
    pub dims: Vec<(String, usize)>,
    pub units: String,
    pub long_name: String,
}

impl ArraySpec {
    /// Number of values.
    pub fn len(&self) -> usize {
        self.dims.iter().map(|d| d.1).product()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// One analysis of a run.
pub trait Analysis {
    fn name(&self) -> &str;
    /// `"static"`, `"dynamic"`, …
    fn kind(&self) -> &'static str;
    /// Whether the records carry a load factor (static load continuation).
    fn has_load_factor(&self) -> bool {
        false
    }
    /// Whether per-step solver diagnostics are recorded.
    fn diagnostics(&self) -> bool {
        false
    }
    /// Arrays the analysis writes besides its time records.
    fn arrays(&self, _sys: &System) -> Vec<ArraySpec> {
        Vec::new()
    }
    /// Runs from `initial`, recording as it goes.
    fn run(
        &self,
        sys: &System,
        initial: State,
        recorder: &mut dyn Recorder,
        progress: Progress,
    ) -> Result<AnalysisSummary, crate::Error>;
}

/// Time integration ([`run_dynamic`]).
pub struct DynamicAnalysis<'a> {
    pub name: &'a str,
    pub settings: &'a DynamicSettings,
}

impl Analysis for DynamicAnalysis<'_> {
    fn name(&self) -> &str {
        self.name
    }
    fn kind(&self) -> &'static str {
        "dynamic"
    }
    fn diagnostics(&self) -> bool {
        self.settings.solver.diagnostics
    }
    fn run(
        &self,
        sys: &System,
        initial: State,
        recorder: &mut dyn Recorder,
        progress: Progress,
    ) -> Result<AnalysisSummary, crate::Error> {
        sys.begin_analysis();
        run_dynamic(sys, self.name, self.settings, initial, recorder, progress)
    }
}

/// Static equilibrium with load continuation ([`run_static`]).
pub struct StaticAnalysis<'a> {
    pub name: &'a str,
    pub settings: &'a StaticSettings,
}

impl Analysis for StaticAnalysis<'_> {
    fn name(&self) -> &str {
        self.name
    }
    fn kind(&self) -> &'static str {
        "static"
    }
    fn has_load_factor(&self) -> bool {
        true
    }
    fn diagnostics(&self) -> bool {
        self.settings.solver.diagnostics
    }
    fn run(
        &self,
        sys: &System,
        initial: State,
        recorder: &mut dyn Recorder,
        progress: Progress,
    ) -> Result<AnalysisSummary, crate::Error> {
        sys.begin_analysis();
        run_static(sys, self.name, self.settings, initial, recorder, progress)
    }
}

/// Eigenanalysis about the starting state ([`run_modal`]).
pub struct ModalAnalysis<'a> {
    pub name: &'a str,
    pub settings: &'a ModalSettings,
}

impl Analysis for ModalAnalysis<'_> {
    fn name(&self) -> &str {
        self.name
    }
    fn kind(&self) -> &'static str {
        "modal"
    }
    fn arrays(&self, sys: &System) -> Vec<ArraySpec> {
        super::modal::modal_arrays(sys, self.settings.n_modes, "")
    }
    fn run(
        &self,
        sys: &System,
        initial: State,
        recorder: &mut dyn Recorder,
        progress: Progress,
    ) -> Result<AnalysisSummary, crate::Error> {
        sys.begin_analysis();
        run_modal(sys, self.name, self.settings, initial, recorder, progress)
    }
}

/// Campbell diagram: spinning statics and rotating-frame modes over a speed sweep
/// ([`super::campbell::run_campbell`]).
pub struct CampbellAnalysis<'a> {
    pub name: &'a str,
    pub settings: &'a CampbellSettings,
}

impl Analysis for CampbellAnalysis<'_> {
    fn name(&self) -> &str {
        self.name
    }
    fn kind(&self) -> &'static str {
        "campbell"
    }
    fn arrays(&self, _sys: &System) -> Vec<ArraySpec> {
        super::campbell::campbell_arrays(self.settings.speeds.len(), self.settings.modal.n_modes)
    }
    fn run(
        &self,
        sys: &System,
        initial: State,
        recorder: &mut dyn Recorder,
        progress: Progress,
    ) -> Result<AnalysisSummary, crate::Error> {
        sys.begin_analysis();
        super::campbell::run_campbell(sys, self.name, self.settings, initial, recorder, progress)
    }
}

/// Floquet stability about the periodic solution through the starting state
/// ([`super::floquet::run_floquet`]).
pub struct FloquetAnalysis<'a> {
    pub name: &'a str,
    pub settings: &'a FloquetSettings,
}

impl Analysis for FloquetAnalysis<'_> {
    fn name(&self) -> &str {
        self.name
    }
    fn kind(&self) -> &'static str {
        "floquet"
    }
    fn arrays(&self, _sys: &System) -> Vec<ArraySpec> {
        super::floquet::floquet_arrays(self.settings.n_modes)
    }
    fn run(
        &self,
        sys: &System,
        initial: State,
        recorder: &mut dyn Recorder,
        progress: Progress,
    ) -> Result<AnalysisSummary, crate::Error> {
        sys.begin_analysis();
        super::floquet::run_floquet(sys, self.name, self.settings, initial, recorder, progress)
    }
}

impl AnalysisDef {
    /// The stage that runs this analysis.
    pub fn stage(&self) -> Box<dyn Analysis + '_> {
        match &self.kind {
            AnalysisKind::Dynamic(s) => Box::new(DynamicAnalysis {
                name: &self.name,
                settings: s,
            }),
            AnalysisKind::Static(s) => Box::new(StaticAnalysis {
                name: &self.name,
                settings: s,
            }),
            AnalysisKind::Modal(s) => Box::new(ModalAnalysis {
                name: &self.name,
                settings: s,
            }),
            AnalysisKind::Campbell(s) => Box::new(CampbellAnalysis {
                name: &self.name,
                settings: s,
            }),
            AnalysisKind::Floquet(s) => Box::new(FloquetAnalysis {
                name: &self.name,
                settings: s,
            }),
        }
    }
}
