//! `[[signals]]`: a named signal that is a given function of time (kernel:
//! [`crate::elements::TimeSignal`]).

use super::{Build, ComponentKind};
use crate::elements::TimeSignal;
use crate::math::TimeFunction;
use crate::model::input::TimeFunctionInput;
use crate::model::validate::Checker;
use crate::model::{Located, Model};
use crate::tangent_check::TangentCase;
use schemars::JsonSchema;
use serde::Deserialize;

/// A named scalar signal (a constant or a time function now; controller outputs later).
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SignalInput {
    /// Unique signal name.
    pub name: Located<String>,
    /// The signal's value over time.
    pub function: Located<TimeFunctionInput>,
}

/// A named input signal.
#[derive(Clone, Debug)]
pub struct SignalDef {
    pub name: String,
    pub function: TimeFunction,
}

pub struct Signal;

impl ComponentKind for Signal {
    const NOUN: &'static str = "signal";
    type Input = SignalInput;
    type Def = SignalDef;

    /// Signals are functions of time only.
    fn discrete_form(_input: &SignalInput) -> Result<(), String> {
        Ok(())
    }

    fn name(input: &SignalInput) -> &Located<String> {
        &input.name
    }

    fn signals(input: &SignalInput) -> Vec<String> {
        vec![input.name.value.clone()]
    }

    fn validate(
        g: &Located<SignalInput>,
        cx: &mut Checker,
        _model: &mut Model,
    ) -> Option<SignalDef> {
        let what = format!("signal '{}'", g.value.name.value);
        let function = cx.time_function(&g.value.function, &what)?;
        Some(SignalDef {
            name: g.value.name.value.clone(),
            function,
        })
    }

    fn nodes(_def: &SignalDef) -> Vec<usize> {
        Vec::new()
    }

    fn build(def: &SignalDef, parts: &mut Build) {
        parts
            .elements
            .push(Box::new(TimeSignal::new(&def.name, def.function.clone())));
    }

    fn tangent_cases() -> Vec<TangentCase> {
        vec![TangentCase::element(
            Box::new(TimeSignal::new("s", TimeFunction::Constant(2.0))),
            Vec::new(),
        )]
    }
}
