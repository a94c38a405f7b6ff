//! Feedthrough edges between signals, for the model-time algebraic-loop checks (the
//! controllers' loop check, the servos' `drive_signal` check).
//!
//! An edge s → u means the signal s depends on the signal u in the same instant, with no
//! state in between:
//! - a controller block with feedthrough: each output → each input;
//! - a sensor without a filter (τ = 0): its signal → the signal it reads. A sample rate
//!   alone does not break the edge: where nothing is held (statics) the hold passes its
//!   input through;
//! - an element output read as a signal, `output:<element>.<output>` → every signal the
//!   element reads ([`signals_read_by_elements`]): the output is a function of everything
//!   the element sees, its input signals too (as the system's signal graph counts it).
//!
//! A cycle of these edges is an algebraic loop.

use super::{Build, Model};
use crate::model::validate::Checker;
use std::collections::HashMap;
use std::ops::Range;

/// Per signal with feedthrough: the signals it reads, and where its producer is written.
pub type Edges = HashMap<String, (Vec<String>, Option<Range<usize>>)>;

/// The signals each element of the model reads (its input ports: a motor's `voltage`, an
/// orifice's `opening`, a force's signal, a tire's `brake`, …), keyed by the name of each
/// of its outputs as a sensor reads it, `<element>.<output>`. Taken from the elements the
/// model builds, so every kind's input keys are covered as the system connects them.
pub fn signals_read_by_elements(model: &Model) -> HashMap<String, Vec<String>> {
    let initial = super::initial_nodes(model);
    let mut parts = Build::new(&initial);
    super::build_all(model, &mut parts);
    let mut out = HashMap::new();
    for e in &parts.elements {
        for (o, _) in e.output_names() {
            out.insert(format!("{}.{o}", e.name()), e.signal_inputs().to_vec());
        }
    }
    out
}

/// The feedthrough edges of the model's signals. Element outputs are followed only when
/// the model has no error so far (the elements are built from a consistent model).
pub fn feedthrough_edges(cx: &Checker, model: &Model) -> Edges {
    let mut edges = Edges::new();
    for c in &model.controllers {
        if crate::core::Element::feedthrough(&c.element()) {
            for o in &c.outputs {
                edges.insert(o.clone(), (c.inputs.clone(), c.span.clone()));
            }
        }
    }
    let mut probed = Vec::new();
    for s in &model.sensors {
        if s.time_constant == 0.0
            && let crate::elements::SensorInput::Signal(i) = &s.input
        {
            edges.insert(s.name.clone(), (vec![i.clone()], s.span.clone()));
            if let Some((o, span)) = &s.output {
                probed.push((o, span));
            }
        }
    }
    let clean = !cx
        .diags
        .iter()
        .any(|d| d.severity == crate::model::Severity::Error);
    if !probed.is_empty() && clean {
        let read = signals_read_by_elements(model);
        for (o, span) in probed {
            if let Some(inputs) = read.get(o.as_str()) {
                edges.insert(format!("output:{o}"), (inputs.clone(), span.clone()));
            }
        }
    }
    edges
}
