//! Results of element states and signals: `element_state(time, state)`,
//! `element_state_rate(time, state)` with names `<element>.<state>` in `state_name`, and
//! `signal(time, signal)` with names in `signal_name`, and the elements' output quantities
//! `element_output(time, output)` with `output_name` and `output_units` (each defined
//! only when the model has them).

use super::netcdf::{Definition, DimId, NcError, NcType, VarId, Writer};
use crate::core::State;
use crate::system::System;

pub struct StateVars {
    name: Option<VarId>,
    value: Option<VarId>,
    rate: Option<VarId>,
    signal_name: Option<VarId>,
    signal: Option<VarId>,
    output_name: Option<VarId>,
    output_units: Option<VarId>,
    output: Option<VarId>,
    z: Vec<f64>,
    values: Vec<f64>,
    zd: Vec<f64>,
}

fn longest(names: &[String]) -> usize {
    names.iter().map(|s| s.len()).max().unwrap_or(1).max(1)
}

impl StateVars {
    /// Defines the variables; `None` when the model has no states, signals or outputs.
    pub fn define(d: &mut Definition, sys: &System, time: DimId) -> Option<Self> {
        if sys.n_states == 0 && sys.signals.names.is_empty() && sys.output_names.is_empty() {
            return None;
        }
        let var = super::beam_vars::add;
        let (mut name, mut value, mut rate) = (None, None, None);
        if sys.n_states > 0 {
            let s = d.add_dim("state", sys.n_states);
            let len = d.add_dim("state_strlen", longest(&sys.state_names));
            name = Some(var(
                d,
                "state_name",
                NcType::Char,
                &[s, len],
                "",
                "element state name, <element>.<state>",
            ));
            value = Some(var(
                d,
                "element_state",
                NcType::Double,
                &[time, s],
                "element-specific",
                "element state z (units of the element's state; see docs/results.md)",
            ));
            rate = Some(var(
                d,
                "element_state_rate",
                NcType::Double,
                &[time, s],
                "element-specific s-1",
                "rate of the element state",
            ));
        }
        let (mut signal_name, mut signal) = (None, None);
        if !sys.signals.names.is_empty() {
            let g = d.add_dim("signal", sys.signals.names.len());
            let len = d.add_dim("signal_strlen", longest(&sys.signals.names));
            signal_name = Some(var(
                d,
                "signal_name",
                NcType::Char,
                &[g, len],
                "",
                "signal name",
            ));
            signal = Some(var(
                d,
                "signal",
                NcType::Double,
                &[time, g],
                "signal-specific",
                "signal value",
            ));
        }
        let (mut output_name, mut output_units, mut output) = (None, None, None);
        if !sys.output_names.is_empty() {
            let o = d.add_dim("output", sys.output_names.len());
            let len = d.add_dim("output_strlen", longest(&sys.output_names));
            let ulen = d.add_dim("output_units_strlen", longest(&sys.output_units));
            output_name = Some(var(
                d,
                "output_name",
                NcType::Char,
                &[o, len],
                "",
                "element output name, <element>.<output>",
            ));
            output_units = Some(var(
                d,
                "output_units",
                NcType::Char,
                &[o, ulen],
                "",
                "units of each element output",
            ));
            output = Some(var(
                d,
                "element_output",
                NcType::Double,
                &[time, o],
                "output-specific",
                "element output quantity (units in output_units)",
            ));
        }
        Some(Self {
            name,
            value,
            rate,
            signal_name,
            signal,
            output_name,
            output_units,
            output,
            values: vec![0.0; sys.output_names.len()],
            z: vec![0.0; sys.n_states],
            zd: vec![0.0; sys.n_states],
        })
    }

    /// Writes the names (fixed variables).
    pub fn write_fixed(&self, w: &mut Writer, sys: &System) -> Result<(), NcError> {
        if let Some(v) = self.name {
            let names: Vec<&str> = sys.state_names.iter().map(|s| s.as_str()).collect();
            w.put_fixed_text(v, &names)?;
        }
        if let Some(v) = self.signal_name {
            let names: Vec<&str> = sys.signals.names.iter().map(|s| s.as_str()).collect();
            w.put_fixed_text(v, &names)?;
        }
        if let (Some(n), Some(u)) = (self.output_name, self.output_units) {
            let names: Vec<&str> = sys.output_names.iter().map(|s| s.as_str()).collect();
            w.put_fixed_text(n, &names)?;
            let units: Vec<&str> = sys.output_units.iter().map(|s| s.as_str()).collect();
            w.put_fixed_text(u, &units)?;
        }
        Ok(())
    }

    /// Writes one record.
    pub fn record(
        &mut self,
        w: &mut Writer,
        sys: &System,
        state: &State,
        load_factor: f64,
    ) -> Result<(), NcError> {
        if let (Some(v), Some(r)) = (self.value, self.rate) {
            for (i, s) in state.states.iter().enumerate() {
                self.z[i] = s.z;
                self.zd[i] = s.zd;
            }
            w.set_record_f64(v, &self.z)?;
            w.set_record_f64(r, &self.zd)?;
        }
        let ctx = sys.context(state.time, load_factor);
        if let Some(v) = self.signal {
            w.set_record_f64(v, &sys.signal_values(&ctx, state))?;
        }
        if let Some(v) = self.output {
            sys.element_outputs(&ctx, state, &mut self.values);
            w.set_record_f64(v, &self.values)?;
        }
        Ok(())
    }
}
