//! `[[controllers]]`: control blocks reading signals and producing a signal named like
//! the controller (kernel: [`crate::elements::Controller`], equations and references
//! there and in docs/multi-field.md).
//!
//! ```toml
//! [[controllers]]
//! name = "torque"              # the signal it produces
//! type = "pid"                 # pid | transfer_function | state_space | gain | sum |
//!                              # saturation | rate_limit | lookup
//! reference = "target"         # pid: reference and measurement (e = r − y) …
//! measurement = "angle"
//! # input = "error"            # … or the error itself (also gain, saturation, rate_limit,
//! #                            # lookup, transfer_function)
//! kp = 40.0
//! ki = 10.0
//! kd = 4.0
//! measurement_rate = "rate"    # derivative on a measured rate, D = −kd·ẏ …
//! # derivative_filter = 0.01   # … or on the error through kd s/(T_f s + 1)
//! output_min = -5.0            # pid, saturation: limits (back-calculation anti-windup)
//! output_max = 5.0
//! # tracking_time = 0.1        # T_t (default √(T_i T_d), or T_i = kp/ki without kd)
//! # initial_integral = 0.0
//! ```
//!
//! Other types: `gain = k`; `inputs = [..]` with `weights = [..]` (sum, default all 1);
//! `table = [[u, y], ..]` (lookup); `rate`, `time_constant`, `initial` (rate_limit);
//! `numerator`, `denominator` (transfer_function, highest power first, proper);
//! `a`, `b`, `c`, `d` (state_space, rows; `inputs`; `outputs` names one signal per row of
//! c, default the controller's name), `initial_state`.

use super::{Build, ComponentKind, ModelInput};
use crate::elements::{Controller as ControllerElement, ControllerBlock, Pid};
use crate::model::validate::{Checker, Entry};
use crate::model::{Located, Model};
use crate::tangent_check::TangentCase;
use nalgebra::DMatrix;
use schemars::JsonSchema;
use serde::Deserialize;
use std::ops::Range;

/// The kind of control block.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ControllerType {
    Pid,
    TransferFunction,
    StateSpace,
    Gain,
    Sum,
    Saturation,
    RateLimit,
    Lookup,
}

/// One control block (keys by `type`; see the module documentation).
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ControllerInput {
    /// Unique name; also the name of the signal it produces (one output).
    pub name: Located<String>,
    #[serde(rename = "type")]
    pub kind: ControllerType,
    /// The single input signal (pid: the error).
    #[serde(default)]
    pub input: Option<Located<String>>,
    /// Input signals (sum, state_space).
    #[serde(default)]
    pub inputs: Option<Vec<Located<String>>>,
    /// Output signal names (state_space with several rows of c).
    #[serde(default)]
    pub outputs: Option<Vec<Located<String>>>,
    /// PID reference signal r.
    #[serde(default)]
    pub reference: Option<Located<String>>,
    /// PID measured signal y (e = r − y).
    #[serde(default)]
    pub measurement: Option<Located<String>>,
    /// PID: signal of the measured rate ẏ (derivative on measurement, D = −kd ẏ).
    #[serde(default)]
    pub measurement_rate: Option<Located<String>>,
    #[serde(default)]
    pub kp: Option<f64>,
    #[serde(default)]
    pub ki: Option<f64>,
    #[serde(default)]
    pub kd: Option<f64>,
    /// PID derivative filter time constant T_f [s] > 0.
    #[serde(default)]
    pub derivative_filter: Option<f64>,
    /// Lower output limit (pid, saturation).
    #[serde(default)]
    pub output_min: Option<f64>,
    /// Upper output limit (pid, saturation).
    #[serde(default)]
    pub output_max: Option<f64>,
    /// PID back-calculation tracking time T_t [s] > 0.
    #[serde(default)]
    pub tracking_time: Option<f64>,
    /// PID initial integral term (units of the output).
    #[serde(default)]
    pub initial_integral: Option<f64>,
    /// Gain k.
    #[serde(default)]
    pub gain: Option<f64>,
    /// Sum weights (default all 1).
    #[serde(default)]
    pub weights: Option<Vec<f64>>,
    /// Lookup table [[u, y], …], u strictly increasing.
    #[serde(default)]
    pub table: Option<Vec<[f64; 2]>>,
    /// Rate limit R > 0 [output units per second].
    #[serde(default)]
    pub rate: Option<f64>,
    /// Rate limiter tracking time constant τ [s] > 0 (default 1e-3).
    #[serde(default)]
    pub time_constant: Option<f64>,
    /// Rate limiter initial output.
    #[serde(default)]
    pub initial: Option<f64>,
    /// Transfer function numerator (highest power first).
    #[serde(default)]
    pub numerator: Option<Vec<f64>>,
    /// Transfer function denominator (highest power first, leading coefficient ≠ 0).
    #[serde(default)]
    pub denominator: Option<Vec<f64>>,
    /// State-space matrices, rows.
    #[serde(default)]
    pub a: Option<Vec<Vec<f64>>>,
    #[serde(default)]
    pub b: Option<Vec<Vec<f64>>>,
    #[serde(default)]
    pub c: Option<Vec<Vec<f64>>>,
    #[serde(default)]
    pub d: Option<Vec<Vec<f64>>>,
    /// Initial states (state_space, transfer_function; default zero).
    #[serde(default)]
    pub initial_state: Option<Vec<f64>>,
}

/// A validated controller.
#[derive(Clone, Debug)]
pub struct ControllerDef {
    pub name: String,
    pub block: ControllerBlock,
    pub inputs: Vec<String>,
    pub outputs: Vec<String>,
    /// Where the entry is (for the algebraic-loop error).
    pub span: Option<Range<usize>>,
}

impl ControllerDef {
    pub(crate) fn element(&self) -> ControllerElement {
        ControllerElement::new(
            &self.name,
            self.block.clone(),
            self.inputs.clone(),
            self.outputs.clone(),
        )
    }
}

pub struct Controller;

/// Every key given, with whether it is set (to reject keys the type does not use).
fn keys_given(c: &ControllerInput) -> Vec<(&'static str, bool)> {
    vec![
        ("input", c.input.is_some()),
        ("inputs", c.inputs.is_some()),
        ("outputs", c.outputs.is_some()),
        ("reference", c.reference.is_some()),
        ("measurement", c.measurement.is_some()),
        ("measurement_rate", c.measurement_rate.is_some()),
        ("kp", c.kp.is_some()),
        ("ki", c.ki.is_some()),
        ("kd", c.kd.is_some()),
        ("derivative_filter", c.derivative_filter.is_some()),
        ("output_min", c.output_min.is_some()),
        ("output_max", c.output_max.is_some()),
        ("tracking_time", c.tracking_time.is_some()),
        ("initial_integral", c.initial_integral.is_some()),
        ("gain", c.gain.is_some()),
        ("weights", c.weights.is_some()),
        ("table", c.table.is_some()),
        ("rate", c.rate.is_some()),
        ("time_constant", c.time_constant.is_some()),
        ("initial", c.initial.is_some()),
        ("numerator", c.numerator.is_some()),
        ("denominator", c.denominator.is_some()),
        ("a", c.a.is_some()),
        ("b", c.b.is_some()),
        ("c", c.c.is_some()),
        ("d", c.d.is_some()),
        ("initial_state", c.initial_state.is_some()),
    ]
}

fn allowed(kind: ControllerType) -> &'static [&'static str] {
    match kind {
        ControllerType::Pid => &[
            "input",
            "reference",
            "measurement",
            "measurement_rate",
            "kp",
            "ki",
            "kd",
            "derivative_filter",
            "output_min",
            "output_max",
            "tracking_time",
            "initial_integral",
        ],
        ControllerType::TransferFunction => &["input", "numerator", "denominator", "initial_state"],
        ControllerType::StateSpace => &["inputs", "outputs", "a", "b", "c", "d", "initial_state"],
        ControllerType::Gain => &["input", "gain"],
        ControllerType::Sum => &["inputs", "weights"],
        ControllerType::Saturation => &["input", "output_min", "output_max"],
        ControllerType::RateLimit => &["input", "rate", "time_constant", "initial"],
        ControllerType::Lookup => &["input", "table"],
    }
}

fn type_name(kind: ControllerType) -> &'static str {
    match kind {
        ControllerType::Pid => "pid",
        ControllerType::TransferFunction => "transfer_function",
        ControllerType::StateSpace => "state_space",
        ControllerType::Gain => "gain",
        ControllerType::Sum => "sum",
        ControllerType::Saturation => "saturation",
        ControllerType::RateLimit => "rate_limit",
        ControllerType::Lookup => "lookup",
    }
}

/// Checks that `name` is a known signal (located error otherwise).
fn known_signal(cx: &mut Checker, s: &Located<String>, what: &str) -> bool {
    if cx.signal_names.contains_key(&s.value) {
        return true;
    }
    let known: Vec<String> = cx.signal_names.keys().cloned().collect();
    let hint = match cx.suggest(&s.value, known.iter().map(|s| s.as_str())) {
        Some(b) => format!("did you mean '{b}'?"),
        None => "signals come from [[signals]], sensors and controllers".into(),
    };
    cx.error(
        format!("{what}: unknown signal '{}'", s.value),
        s.span.clone(),
        Some(hint),
    );
    false
}

/// A dense matrix from rows, `None` (with an error) if ragged or of the wrong size.
fn matrix(
    cx: &mut Checker,
    e: &Entry,
    key: &str,
    rows: &[Vec<f64>],
    shape: (usize, usize),
    what: &str,
) -> Option<DMatrix<f64>> {
    let ok_shape = rows.len() == shape.0 && rows.iter().all(|r| r.len() == shape.1);
    if !ok_shape {
        cx.error(
            format!(
                "{what}: `{key}` must be {}×{} (rows of equal length)",
                shape.0, shape.1
            ),
            cx.key(e, key),
            Some("a: n×n, b: n×inputs, c: outputs×n, d: outputs×inputs".into()),
        );
        return None;
    }
    let flat: Vec<f64> = rows.iter().flatten().copied().collect();
    if !cx.finite(e, key, &flat, what) {
        return None;
    }
    Some(DMatrix::from_row_slice(shape.0, shape.1, &flat))
}

impl ComponentKind for Controller {
    const NOUN: &'static str = "controller";
    type Input = ControllerInput;
    type Def = ControllerDef;

    fn name(input: &ControllerInput) -> &Located<String> {
        &input.name
    }

    fn signals(input: &ControllerInput) -> Vec<String> {
        match (&input.kind, &input.outputs) {
            (ControllerType::StateSpace, Some(o)) => o.iter().map(|s| s.value.clone()).collect(),
            _ => vec![input.name.value.clone()],
        }
    }

    fn validate(
        s: &Located<ControllerInput>,
        cx: &mut Checker,
        _model: &mut Model,
    ) -> Option<ControllerDef> {
        let e = Entry {
            span: s.span.clone(),
        };
        let ci = &s.value;
        let what = format!("controller '{}'", ci.name.value);
        let tn = type_name(ci.kind);
        let allow = allowed(ci.kind);
        let mut ok = true;
        for (key, given) in keys_given(ci) {
            if given && !allow.contains(&key) {
                cx.error(
                    format!("{what}: `{key}` is not used by a {tn} controller"),
                    cx.key(&e, key),
                    Some(format!("a {tn} controller takes: {}", allow.join(", "))),
                );
                ok = false;
            }
        }
        if !ok {
            return None;
        }
        let mut scalars: Vec<(&str, f64)> = Vec::new();
        for (k, v) in [
            ("kp", ci.kp),
            ("ki", ci.ki),
            ("kd", ci.kd),
            ("derivative_filter", ci.derivative_filter),
            ("output_min", ci.output_min),
            ("output_max", ci.output_max),
            ("tracking_time", ci.tracking_time),
            ("initial_integral", ci.initial_integral),
            ("gain", ci.gain),
            ("rate", ci.rate),
            ("time_constant", ci.time_constant),
            ("initial", ci.initial),
        ] {
            if let Some(v) = v {
                scalars.push((k, v));
            }
        }
        for (k, v) in &scalars {
            ok &= cx.finite(&e, k, &[*v], &what);
        }
        if !ok {
            return None;
        }
        let positive = |cx: &mut Checker, key: &str, v: Option<f64>, hint: &str| -> bool {
            match v {
                Some(x) if x <= 0.0 => {
                    cx.error(
                        format!("{what}: `{key}` must be positive (got {x})"),
                        cx.key(&e, key),
                        Some(hint.into()),
                    );
                    false
                }
                _ => true,
            }
        };
        let need = |cx: &mut Checker, key: &str, given: bool| -> bool {
            if !given {
                cx.error(
                    format!("{what}: a {tn} controller needs `{key}`"),
                    e.span.clone(),
                    Some(format!("a {tn} controller takes: {}", allow.join(", "))),
                );
            }
            given
        };
        let limits = (
            ci.output_min.unwrap_or(f64::NEG_INFINITY),
            ci.output_max.unwrap_or(f64::INFINITY),
        );
        if limits.0 >= limits.1 {
            cx.error(
                format!(
                    "{what}: `output_min` ({}) must be below `output_max` ({})",
                    limits.0, limits.1
                ),
                cx.key(&e, "output_min"),
                None,
            );
            return None;
        }
        let single = |cx: &mut Checker| -> Option<Vec<String>> {
            let i = ci.input.as_ref();
            if !need(cx, "input", i.is_some()) {
                return None;
            }
            let i = i?;
            known_signal(cx, i, &what).then(|| vec![i.value.clone()])
        };
        let many = |cx: &mut Checker| -> Option<Vec<String>> {
            let list = ci.inputs.as_ref();
            if !need(cx, "inputs", list.is_some()) {
                return None;
            }
            let list = list?;
            if list.is_empty() {
                cx.error(
                    format!("{what}: `inputs` is empty"),
                    cx.key(&e, "inputs"),
                    Some("name at least one signal".into()),
                );
                return None;
            }
            let mut good = true;
            for s in list {
                good &= known_signal(cx, s, &what);
            }
            good.then(|| list.iter().map(|s| s.value.clone()).collect())
        };
        let mut outputs = vec![ci.name.value.clone()];
        let (block, inputs) = match ci.kind {
            ControllerType::Gain => {
                let inputs = single(cx)?;
                need(cx, "gain", ci.gain.is_some()).then_some(())?;
                (ControllerBlock::Gain(ci.gain?), inputs)
            }
            ControllerType::Sum => {
                let inputs = many(cx)?;
                let w = ci.weights.clone().unwrap_or(vec![1.0; inputs.len()]);
                if w.len() != inputs.len() {
                    cx.error(
                        format!("{what}: {} weights for {} inputs", w.len(), inputs.len()),
                        cx.key(&e, "weights"),
                        Some("one weight per input, e.g. [1, -1] for a difference".into()),
                    );
                    return None;
                }
                cx.finite(&e, "weights", &w, &what).then_some(())?;
                (ControllerBlock::Sum(w), inputs)
            }
            ControllerType::Saturation => {
                let inputs = single(cx)?;
                if ci.output_min.is_none() && ci.output_max.is_none() {
                    cx.error(
                        format!("{what}: a saturation needs `output_min` and/or `output_max`"),
                        e.span.clone(),
                        None,
                    );
                    return None;
                }
                (ControllerBlock::Saturation(limits.0, limits.1), inputs)
            }
            ControllerType::Lookup => {
                let inputs = single(cx)?;
                need(cx, "table", ci.table.is_some()).then_some(())?;
                let t = ci.table.clone()?;
                let flat: Vec<f64> = t.iter().flatten().copied().collect();
                cx.finite(&e, "table", &flat, &what).then_some(())?;
                if t.len() < 2 || t.windows(2).any(|w| w[1][0] <= w[0][0]) {
                    cx.error(
                        format!(
                            "{what}: `table` needs at least two rows with strictly increasing u"
                        ),
                        cx.key(&e, "table"),
                        Some("[[u, y], …]: linear between rows, constant beyond the ends".into()),
                    );
                    return None;
                }
                (ControllerBlock::Lookup(t), inputs)
            }
            ControllerType::RateLimit => {
                let inputs = single(cx)?;
                need(cx, "rate", ci.rate.is_some()).then_some(())?;
                let mut good = positive(cx, "rate", ci.rate, "R: the largest |dy/dt|");
                good &= positive(
                    cx,
                    "time_constant",
                    ci.time_constant,
                    "τ: how fast the output follows the input below the rate limit",
                );
                good.then_some(())?;
                (
                    ControllerBlock::RateLimit {
                        rate: ci.rate?,
                        time_constant: ci.time_constant.unwrap_or(1e-3),
                        initial: ci.initial.unwrap_or(0.0),
                    },
                    inputs,
                )
            }
            ControllerType::TransferFunction => {
                let inputs = single(cx)?;
                let mut good = need(cx, "numerator", ci.numerator.is_some());
                good &= need(cx, "denominator", ci.denominator.is_some());
                good.then_some(())?;
                let (num, den) = (ci.numerator.clone()?, ci.denominator.clone()?);
                let mut good = cx.finite(&e, "numerator", &num, &what);
                good &= cx.finite(&e, "denominator", &den, &what);
                good.then_some(())?;
                let Some(mut block) = ControllerBlock::transfer_function(&num, &den) else {
                    cx.error(
                        format!("{what}: the transfer function must be proper with a non-zero leading denominator coefficient"),
                        cx.key(&e, "denominator"),
                        Some("numerator degree ≤ denominator degree; e.g. numerator = [1], denominator = [0.1, 1] for 1/(0.1 s + 1)".into()),
                    );
                    return None;
                };
                if let (Some(z0), ControllerBlock::StateSpace { initial, .. }) =
                    (&ci.initial_state, &mut block)
                {
                    if z0.len() != initial.len() {
                        cx.error(
                            format!("{what}: `initial_state` needs {} values", initial.len()),
                            cx.key(&e, "initial_state"),
                            Some("one per state: the degree of the denominator".into()),
                        );
                        return None;
                    }
                    cx.finite(&e, "initial_state", z0, &what).then_some(())?;
                    initial.copy_from_slice(z0);
                }
                (block, inputs)
            }
            ControllerType::StateSpace => {
                let inputs = many(cx)?;
                let mut good = true;
                for k in ["a", "b", "c", "d"] {
                    let given = match k {
                        "a" => ci.a.is_some(),
                        "b" => ci.b.is_some(),
                        "c" => ci.c.is_some(),
                        _ => true,
                    };
                    good &= need(cx, k, given);
                }
                good.then_some(())?;
                let n = ci.a.as_ref()?.len();
                let p = ci.c.as_ref()?.len();
                let m = inputs.len();
                if let Some(o) = &ci.outputs {
                    if o.len() != p {
                        cx.error(
                            format!("{what}: {} outputs for {p} rows of c", o.len()),
                            cx.key(&e, "outputs"),
                            Some("one output signal per row of c".into()),
                        );
                        return None;
                    }
                    outputs = o.iter().map(|s| s.value.clone()).collect();
                } else if p != 1 {
                    cx.error(
                        format!("{what}: c has {p} rows: name them in `outputs`"),
                        cx.key(&e, "c"),
                        Some("outputs = [\"y1\", \"y2\"]".into()),
                    );
                    return None;
                }
                let a = matrix(cx, &e, "a", ci.a.as_ref()?, (n, n), &what);
                let b = matrix(cx, &e, "b", ci.b.as_ref()?, (n, m), &what);
                let c = matrix(cx, &e, "c", ci.c.as_ref()?, (p, n), &what);
                let d = match &ci.d {
                    Some(d) => matrix(cx, &e, "d", d, (p, m), &what),
                    None => Some(DMatrix::zeros(p, m)),
                };
                let (a, b, c, d) = (a?, b?, c?, d?);
                let initial = ci.initial_state.clone().unwrap_or(vec![0.0; n]);
                if initial.len() != n {
                    cx.error(
                        format!("{what}: `initial_state` needs {n} values"),
                        cx.key(&e, "initial_state"),
                        None,
                    );
                    return None;
                }
                cx.finite(&e, "initial_state", &initial, &what)
                    .then_some(())?;
                (
                    ControllerBlock::StateSpace {
                        a,
                        b,
                        c,
                        d,
                        initial,
                    },
                    inputs,
                )
            }
            ControllerType::Pid => {
                let (rm, mut inputs) = match (&ci.input, &ci.reference, &ci.measurement) {
                    (Some(i), None, None) => (false, vec![i]),
                    (None, Some(r), Some(y)) => (true, vec![r, y]),
                    _ => {
                        cx.error(
                            format!("{what}: give either `input` (the error) or both `reference` and `measurement`"),
                            e.span.clone(),
                            Some("e = reference − measurement".into()),
                        );
                        return None;
                    }
                };
                let kp = ci.kp.unwrap_or(0.0);
                let ki = ci.ki.unwrap_or(0.0);
                let kd = ci.kd.unwrap_or(0.0);
                // Absent gains are absent terms (0); a PID with none would output 0 silently.
                if kp == 0.0 && ki == 0.0 && kd == 0.0 {
                    cx.error(
                        format!("{what}: a pid needs at least one of `kp`, `ki`, `kd` ≠ 0"),
                        cx.key(&e, "type"),
                        Some("give the gains, e.g. kp = 50.0, kd = 5.0".into()),
                    );
                    return None;
                }
                let mut good = positive(
                    cx,
                    "derivative_filter",
                    ci.derivative_filter,
                    "T_f [s] of kd s/(T_f s + 1)",
                );
                good &= positive(
                    cx,
                    "tracking_time",
                    ci.tracking_time,
                    "T_t [s] of the back-calculation: how fast the integral unwinds",
                );
                if kd != 0.0 && ci.derivative_filter.is_none() && ci.measurement_rate.is_none() {
                    cx.error(
                        format!("{what}: a derivative term needs `measurement_rate` or `derivative_filter`"),
                        cx.key(&e, "kd"),
                        Some("measurement_rate names a signal of the measured rate (D = −kd ẏ); derivative_filter = T_f filters the error's derivative".into()),
                    );
                    good = false;
                }
                if ci.derivative_filter.is_some() && ci.measurement_rate.is_some() {
                    cx.error(
                        format!("{what}: give `measurement_rate` or `derivative_filter`, not both"),
                        cx.key(&e, "derivative_filter"),
                        None,
                    );
                    good = false;
                }
                if kd == 0.0 && (ci.derivative_filter.is_some() || ci.measurement_rate.is_some()) {
                    cx.error(
                        format!("{what}: a derivative setting without `kd`"),
                        cx.key(&e, "kd"),
                        Some("give kd ≠ 0 or drop the derivative setting".into()),
                    );
                    good = false;
                }
                if (ci.tracking_time.is_some() || ci.initial_integral.is_some()) && ki == 0.0 {
                    cx.error(
                        format!("{what}: `tracking_time`/`initial_integral` without `ki`"),
                        cx.key(&e, "ki"),
                        Some("they act on the integral term: give ki ≠ 0".into()),
                    );
                    good = false;
                }
                if let Some(r) = &ci.measurement_rate {
                    inputs.push(r);
                }
                for s in &inputs {
                    good &= known_signal(cx, s, &what);
                }
                good.then_some(())?;
                // Åström & Hägglund: T_t = √(T_i T_d), T_i without a derivative term.
                let tracking = ci.tracking_time.unwrap_or_else(|| {
                    if ki == 0.0 || kp == 0.0 {
                        1.0
                    } else if kd == 0.0 {
                        kp / ki
                    } else {
                        ((kp / ki) * (kd / kp)).abs().sqrt()
                    }
                });
                (
                    ControllerBlock::Pid {
                        pid: Pid {
                            kp,
                            ki,
                            kd,
                            filter: ci.derivative_filter,
                            limits,
                            tracking,
                            initial_integral: ci.initial_integral.unwrap_or(0.0),
                        },
                        reference_and_measurement: rm,
                    },
                    inputs.iter().map(|s| s.value.clone()).collect(),
                )
            }
        };
        if inputs.iter().any(|i| outputs.contains(i)) {
            cx.error(
                format!("{what} reads its own output"),
                e.span.clone(),
                Some("feed the output back through another block (a sensor or a state)".into()),
            );
            return None;
        }
        Some(ControllerDef {
            name: ci.name.value.clone(),
            block,
            inputs,
            outputs,
            span: s.span.clone(),
        })
    }

    /// Algebraic loops: signals that depend on each other only through blocks with
    /// feedthrough (controllers without a state in the path, unfiltered sensors, element
    /// outputs read by unfiltered sensors, which depend on the element's input signals;
    /// [`super::feedthrough`]).
    fn finish(_input: &ModelInput, cx: &mut Checker, model: &Model) {
        let owned = super::feedthrough::feedthrough_edges(cx, model);
        // Producer of each signal with feedthrough: (its inputs, where it is declared).
        let edges: std::collections::HashMap<&str, (Vec<&str>, Option<Range<usize>>)> = owned
            .iter()
            .map(|(k, (ins, span))| {
                (
                    k.as_str(),
                    (ins.iter().map(|s| s.as_str()).collect(), span.clone()),
                )
            })
            .collect();
        // Depth-first search for a cycle (0 new, 1 on the path, 2 done).
        let mut names: Vec<&str> = edges.keys().copied().collect();
        names.sort_unstable();
        let mut mark: std::collections::HashMap<&str, u8> = Default::default();
        for &start in &names {
            if mark.get(start).copied().unwrap_or(0) != 0 {
                continue;
            }
            let mut path: Vec<(&str, usize)> = vec![(start, 0)];
            mark.insert(start, 1);
            while let Some(&mut (node, ref mut next)) = path.last_mut() {
                let ins = edges.get(node).map(|e| e.0.as_slice()).unwrap_or(&[]);
                if *next >= ins.len() {
                    mark.insert(node, 2);
                    path.pop();
                    continue;
                }
                let child = ins[*next];
                *next += 1;
                match mark.get(child).copied().unwrap_or(0) {
                    0 if edges.contains_key(child) => {
                        mark.insert(child, 1);
                        path.push((child, 0));
                    }
                    1 => {
                        let from = path.iter().position(|p| p.0 == child).unwrap_or(0);
                        let mut cycle: Vec<&str> = path[from..].iter().map(|p| p.0).collect();
                        cycle.push(child);
                        cx.error(
                            format!(
                                "algebraic loop: the signals {} depend on each other without a state in between",
                                cycle.join(" → ")
                            ),
                            edges[child].1.clone(),
                            Some("break the loop with a block that has a state: a filtered sensor (time_constant > 0; a sample rate alone does not break it, statics pass the value through), a transfer function without direct feedthrough, a rate limiter, or a PID's integral".into()),
                        );
                        return;
                    }
                    _ => {}
                }
            }
        }
    }

    fn nodes(_def: &ControllerDef) -> Vec<usize> {
        Vec::new()
    }

    fn build(def: &ControllerDef, parts: &mut Build) {
        parts.elements.push(Box::new(def.element()));
    }

    fn tangent_cases() -> Vec<TangentCase> {
        let pid = |filter: Option<f64>, limits: (f64, f64)| Pid {
            kp: 3.0,
            ki: 2.0,
            kd: 0.5,
            filter,
            limits,
            tracking: 0.3,
            initial_integral: 0.0,
        };
        let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
        let mut cases = vec![
            (ControllerBlock::Gain(-2.5), s(&["u"]), vec![], vec![0.7]),
            (
                ControllerBlock::Sum(vec![1.0, -2.0, 0.5]),
                s(&["u", "v", "w"]),
                vec![],
                vec![0.7, -0.2, 1.1],
            ),
            (
                ControllerBlock::Saturation(-1.0, 2.0),
                s(&["u"]),
                vec![],
                vec![0.7],
            ),
            (
                ControllerBlock::Lookup(vec![[0.0, 1.0], [1.0, 3.0], [2.0, 2.0]]),
                s(&["u"]),
                vec![],
                vec![1.3],
            ),
            (
                ControllerBlock::RateLimit {
                    rate: 5.0,
                    time_constant: 0.1,
                    initial: 0.0,
                },
                s(&["u"]),
                vec![(0.2, 1.5)],
                vec![0.4],
            ),
            (
                ControllerBlock::RateLimit {
                    rate: 5.0,
                    time_constant: 0.1,
                    initial: 0.0,
                },
                s(&["u"]),
                vec![(0.2, 1.5)],
                vec![3.0],
            ),
            (
                ControllerBlock::Pid {
                    pid: pid(Some(0.05), (-10.0, 10.0)),
                    reference_and_measurement: true,
                },
                s(&["r", "y"]),
                vec![(0.3, 0.1), (0.2, -0.4)],
                vec![1.0, 0.3],
            ),
            (
                ControllerBlock::Pid {
                    pid: pid(None, (-1.0, 1.0)),
                    reference_and_measurement: false,
                },
                s(&["e", "ydot"]),
                vec![(0.3, 0.1)],
                vec![1.0, -0.3],
            ),
        ];
        if let Some(tf) = ControllerBlock::transfer_function(&[2.0, 1.0, 3.0], &[1.0, 4.0, 5.0]) {
            cases.push((tf, s(&["u"]), vec![(0.3, 0.1), (-0.2, 0.5)], vec![0.9]));
        }
        cases
            .into_iter()
            .map(|(block, inputs, states, signals)| {
                let e = ControllerElement::new("c", block, inputs, vec!["y".into()]);
                TangentCase::element(Box::new(e), Vec::new())
                    .with_states(states)
                    .with_signals(signals)
            })
            .collect()
    }
}
