//! Chaining analyses through `start_from`: each analysis starts from the model's initial
//! state, from the final state of an earlier analysis (`start_from = "name"`), or from the
//! state of an earlier dynamic analysis at a time of its run
//! (`start_from = { analysis = "name", time = t }`).
//!
//! **Which state at `time`.** The state stored at the output time nearest t (the state
//! of a record of the earlier analysis's results, ties to the earlier record); it is not
//! interpolated, because an interpolated state would not satisfy the constraints nor
//! carry consistent multipliers. With `output_every = 1` the records are every step, so
//! the state is within half a step of t; with `output_every = n`, within n/2 steps. The
//! model check refuses a time outside the run (`[t_start, t_end]` of the dynamic
//! analysis).
//!
//! [`Chain`] keeps what the later analyses need: each analysis's final state, and the
//! states at the requested times, caught by a [`Capture`] recorder that wraps the
//! analysis's own recorder while it runs.

use super::{ArraySpec, OutputFrame, Recorder};
use crate::model::{AnalysisDef, Model};
use crate::system::{State, System};

/// The starting states that later analyses take from earlier ones.
pub struct Chain {
    /// Per analysis: the times later analyses start from (`start_from.time`).
    requested: Vec<Vec<f64>>,
    /// Per analysis that has run: its final state and its states at the requested times.
    kept: Vec<Option<Kept>>,
}

struct Kept {
    final_state: State,
    at: Vec<(f64, State)>,
}

impl Chain {
    /// The chain of `model`'s analyses, none run yet.
    pub fn new(model: &Model) -> Self {
        let mut requested = vec![Vec::new(); model.analyses.len()];
        for def in &model.analyses {
            if let (Some(i), Some(t)) = (def.start_from, def.start_time)
                && let Some(r) = requested.get_mut(i)
                && !r.contains(&t)
            {
                r.push(t);
            }
        }
        Self {
            kept: (0..requested.len()).map(|_| None).collect(),
            requested,
        }
    }

    /// The starting state of `def`; `None` when the analysis it starts from has not run
    /// (or recorded nothing near the time asked for).
    pub fn initial(&self, sys: &System, def: &AnalysisDef) -> Option<State> {
        match (def.start_from, def.start_time) {
            (None, _) => Some(sys.initial_state()),
            (Some(i), None) => self.kept.get(i)?.as_ref().map(|k| k.final_state.clone()),
            (Some(i), Some(t)) => self
                .kept
                .get(i)?
                .as_ref()?
                .at
                .iter()
                .find(|(ti, _)| *ti == t)
                .map(|(_, s)| s.clone()),
        }
    }

    /// The starting state of `def`, or the error that says why there is none.
    pub fn start(&self, sys: &System, def: &AnalysisDef) -> Result<State, crate::Error> {
        self.initial(sys, def).ok_or_else(|| crate::Error::Start {
            analysis: def.name.clone(),
            message: match def.start_time {
                Some(t) => format!(
                    "the analysis `start_from` names recorded no state near t = {t}, so there is none to start from"
                ),
                None => "the analysis `start_from` names has not run, so there is no state to start from".into(),
            },
        })
    }

    /// A recorder that passes everything to `inner` and catches the states of analysis
    /// `index` that later analyses start from.
    pub fn capture<'r>(&self, index: usize, inner: &'r mut dyn Recorder) -> Capture<'r> {
        let times = self.requested.get(index).cloned().unwrap_or_default();
        Capture {
            inner,
            best: vec![None; times.len()],
            times,
        }
    }

    /// Records analysis `index` as run: its final state and what `capture` caught.
    pub fn finish(&mut self, index: usize, capture: Capture, final_state: State) {
        let at = capture
            .times
            .iter()
            .zip(capture.best)
            .filter_map(|(t, b)| b.map(|(_, s)| (*t, s)))
            .collect();
        if let Some(k) = self.kept.get_mut(index) {
            *k = Some(Kept { final_state, at });
        }
    }
}

/// Passes an analysis's results to its recorder and keeps, for each requested time, the
/// state of the record nearest it.
pub struct Capture<'r> {
    inner: &'r mut dyn Recorder,
    times: Vec<f64>,
    /// Per requested time: (distance, state) of the nearest record so far.
    best: Vec<Option<(f64, State)>>,
}

impl Recorder for Capture<'_> {
    fn record(&mut self, sys: &System, frame: &OutputFrame) -> Result<(), crate::Error> {
        for (t, best) in self.times.iter().zip(self.best.iter_mut()) {
            let d = (frame.time - t).abs();
            if best.as_ref().is_none_or(|(b, _)| d < *b) {
                *best = Some((d, frame.state.clone()));
            }
        }
        self.inner.record(sys, frame)
    }

    fn write_array(
        &mut self,
        sys: &System,
        spec: &ArraySpec,
        values: &[f64],
    ) -> Result<(), crate::Error> {
        self.inner.write_array(sys, spec, values)
    }

    fn output_dir(&self) -> Option<std::path::PathBuf> {
        self.inner.output_dir()
    }
}
