//! In-memory recorder: keeps every output frame, for the library API and the tests.

use super::{ArraySpec, Energy, OutputFrame, Recorder, StepDiagnostics};
use crate::system::{State, System};
use nalgebra::Vector3;

/// One recorded output time.
#[derive(Clone, Debug)]
pub struct Frame {
    pub time: f64,
    pub state: State,
    pub energy: Energy,
    pub constraint_violation: f64,
    pub load_factor: f64,
    /// Per joint: (force, moment) on B by A, frame-A components.
    pub reactions: Vec<(Vector3<f64>, Vector3<f64>)>,
    /// Per joint coordinate: generalized force from its elements and drive
    /// (see [`System::coordinate_forces`]).
    pub coordinate_forces: Vec<f64>,
    pub diagnostics: Option<StepDiagnostics>,
}

/// All frames of one analysis.
#[derive(Clone, Debug, Default)]
pub struct History {
    pub frames: Vec<Frame>,
    /// Arrays written by the analysis (not time records), by name.
    pub arrays: Vec<(ArraySpec, Vec<f64>)>,
}

impl History {
    pub fn last(&self) -> Option<&Frame> {
        self.frames.last()
    }

    /// The frame whose time is closest to `t`.
    pub fn at(&self, t: f64) -> Option<&Frame> {
        self.frames
            .iter()
            .min_by(|a, b| (a.time - t).abs().total_cmp(&(b.time - t).abs()))
    }

    pub fn times(&self) -> Vec<f64> {
        self.frames.iter().map(|f| f.time).collect()
    }
}

impl Recorder for History {
    fn write_array(
        &mut self,
        _sys: &System,
        spec: &ArraySpec,
        values: &[f64],
    ) -> Result<(), crate::Error> {
        self.arrays.push((spec.clone(), values.to_vec()));
        Ok(())
    }

    fn record(&mut self, sys: &System, frame: &OutputFrame) -> Result<(), crate::Error> {
        let ctx = sys.context(frame.state.time, frame.load_factor);
        let mut reactions = vec![(Vector3::zeros(), Vector3::zeros()); sys.constraints.len()];
        let mut all = vec![0.0; sys.n_rows];
        sys.reactions(&ctx, frame.state, frame.mu, &mut all, |k, f, m| {
            reactions[k] = (f, m)
        });
        let mut coordinate_forces = vec![0.0; sys.n_coordinates + sys.n_passive];
        sys.coordinate_forces(&ctx, frame.state, frame.mu, &mut coordinate_forces);
        self.frames.push(Frame {
            time: frame.time,
            state: frame.state.clone(),
            energy: frame.energy,
            constraint_violation: frame.constraint_violation,
            load_factor: frame.load_factor,
            reactions,
            coordinate_forces,
            diagnostics: frame.diagnostics,
        });
        Ok(())
    }
}
