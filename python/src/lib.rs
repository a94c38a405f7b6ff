//! `samara._samara`: the compiled core of the `samara` Python package.
//!
//! A [`Model`] is a model document (TOML tables) validated by the same rules as a model
//! file; [`Model::run_raw`] runs its analyses with the GIL released and returns each
//! results file as the bytes `samara run` would write (or writes them into a folder).
//! The Python layer (`samara/__init__.py`) turns the bytes into `xarray.Dataset`s.

use pyo3::create_exception;
use pyo3::exceptions::{PyKeyboardInterrupt, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyBytes, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use samara::model::document::Document;
use samara::model::{LoadOptions, LoadedModel, ModelError as CoreModelError, Severity};
use samara::output::ResultsFile;
use samara::system::System;
use std::path::PathBuf;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};
use toml::Value;

create_exception!(
    samara,
    SamaraError,
    pyo3::exceptions::PyException,
    "Base class of samara's errors."
);
create_exception!(
    samara,
    ModelError,
    SamaraError,
    "The model is invalid. `diagnostics` lists every finding (message, hint, path of the \
     offending value, file, line, column)."
);

/// How often a run looks for Ctrl-C and calls the progress callback.
const POLL: Duration = Duration::from_millis(50);

/// A model: a TOML document validated by the rules of a model file.
#[pyclass(module = "samara._samara", name = "Model")]
#[derive(Clone)]
struct Model {
    doc: Document,
    /// The model file it was read from (the results' `model_file` attribute).
    file: Option<PathBuf>,
}

fn py_to_toml(obj: &Bound<'_, PyAny>, path: &str) -> PyResult<Value> {
    let bad = |what: &str| {
        PyTypeError::new_err(format!(
            "{path}: {what} cannot be a model value (expected a number, string, bool, list or dict)"
        ))
    };
    if obj.is_instance_of::<PyBool>() {
        return Ok(Value::Boolean(obj.extract()?));
    }
    if obj.is_instance_of::<PyInt>() {
        return obj
            .extract::<i64>()
            .map(Value::Integer)
            .map_err(|_| PyValueError::new_err(format!("{path}: integer out of range")));
    }
    if obj.is_instance_of::<PyFloat>() {
        return Ok(Value::Float(obj.extract()?));
    }
    if obj.is_instance_of::<PyString>() {
        return Ok(Value::String(obj.extract()?));
    }
    if let Ok(d) = obj.cast::<PyDict>() {
        let mut t = toml::Table::new();
        for (k, v) in d.iter() {
            let k: String = k
                .extract()
                .map_err(|_| PyTypeError::new_err(format!("{path}: dict keys must be strings")))?;
            let sub = if path.is_empty() {
                k.clone()
            } else {
                format!("{path}.{k}")
            };
            t.insert(k, py_to_toml(&v, &sub)?);
        }
        return Ok(Value::Table(t));
    }
    if obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>() {
        let mut a = Vec::new();
        for (i, v) in obj.try_iter()?.enumerate() {
            a.push(py_to_toml(&v?, &format!("{path}[{i}]"))?);
        }
        return Ok(Value::Array(a));
    }
    // numpy scalars and arrays: integers through __index__, reals through __float__,
    // arrays through tolist().
    if obj.hasattr("tolist")? && obj.hasattr("shape")? {
        let shape: Vec<usize> = obj.getattr("shape")?.extract()?;
        if !shape.is_empty() {
            return py_to_toml(&obj.call_method0("tolist")?, path);
        }
    }
    if obj.hasattr("__index__")? {
        let i = obj.call_method0("__index__")?;
        return py_to_toml(&i, path);
    }
    if obj.hasattr("__float__")? {
        let f: f64 = obj.call_method0("__float__")?.extract()?;
        return Ok(Value::Float(f));
    }
    if obj.is_none() {
        return Err(bad("None"));
    }
    Err(bad(&obj.get_type().name()?.to_string()))
}

fn toml_to_py(py: Python<'_>, v: &Value) -> PyResult<Py<PyAny>> {
    Ok(match v {
        Value::String(s) => s.into_pyobject(py)?.into_any().unbind(),
        Value::Integer(i) => i.into_pyobject(py)?.into_any().unbind(),
        Value::Float(x) => x.into_pyobject(py)?.into_any().unbind(),
        Value::Boolean(b) => b.into_pyobject(py)?.to_owned().into_any().unbind(),
        Value::Datetime(d) => d.to_string().into_pyobject(py)?.into_any().unbind(),
        Value::Array(a) => {
            let l = PyList::empty(py);
            for x in a {
                l.append(toml_to_py(py, x)?)?;
            }
            l.into_any().unbind()
        }
        Value::Table(t) => {
            let d = PyDict::new(py);
            for (k, x) in t {
                d.set_item(k, toml_to_py(py, x)?)?;
            }
            d.into_any().unbind()
        }
    })
}

/// The Python exception of a model error: message as `samara check` prints it, and
/// `diagnostics`, one dict per finding.
fn model_error(py: Python<'_>, doc: &Document, e: &CoreModelError) -> PyErr {
    let err = ModelError::new_err(e.to_string());
    let diagnostics = (|| -> PyResult<Bound<'_, PyList>> {
        let list = PyList::empty(py);
        for d in &e.diagnostics {
            let item = PyDict::new(py);
            item.set_item(
                "severity",
                match d.severity {
                    Severity::Error => "error",
                    Severity::Warning => "warning",
                },
            )?;
            item.set_item("message", &d.message)?;
            item.set_item("hint", d.hint.as_deref())?;
            item.set_item("file", e.source.path.display().to_string())?;
            match &d.span {
                Some(span) => {
                    let (line, col) = e.source.line_col(span.start);
                    item.set_item("line", line)?;
                    item.set_item("column", col)?;
                    item.set_item("path", doc.locate(span.start))?;
                }
                None => {
                    item.set_item("line", py.None())?;
                    item.set_item("column", py.None())?;
                    item.set_item("path", py.None())?;
                }
            }
            list.append(item)?;
        }
        Ok(list)
    })();
    if let Ok(list) = diagnostics {
        let _ = err.value(py).setattr("diagnostics", list);
    }
    err
}

fn samara_error(e: &samara::Error) -> PyErr {
    SamaraError::new_err(e.to_string())
}

impl Model {
    fn load(&self, py: Python<'_>, options: &LoadOptions) -> PyResult<LoadedModel> {
        self.doc
            .load(options)
            .map_err(|e| model_error(py, &self.doc, &e))
    }
}

/// Results written by a recorder that also stops the run when asked (Ctrl-C, an
/// exception in the progress callback).
struct Interruptible<'a> {
    inner: ResultsFile,
    stop: &'a AtomicBool,
}

impl samara::analysis::Recorder for Interruptible<'_> {
    fn record(
        &mut self,
        sys: &System,
        frame: &samara::analysis::OutputFrame,
    ) -> Result<(), samara::Error> {
        if self.stop.load(Ordering::Relaxed) {
            return Err(interrupted());
        }
        self.inner.record(sys, frame)
    }
    fn write_array(
        &mut self,
        sys: &System,
        spec: &samara::analysis::ArraySpec,
        values: &[f64],
    ) -> Result<(), samara::Error> {
        self.inner.write_array(sys, spec, values)
    }
}

fn interrupted() -> samara::Error {
    samara::Error::Output {
        path: PathBuf::from("<interrupted>"),
        message: "the run was interrupted".into(),
    }
}

#[pymethods]
impl Model {
    /// Reads a model file (TOML). Raises `ModelError` (with line and column) if invalid.
    #[staticmethod]
    fn from_file(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let text = std::fs::read_to_string(&path).map_err(|e| {
            SamaraError::new_err(format!(
                "cannot read the model file '{}': {e}",
                path.display()
            ))
        })?;
        let doc = Document::from_toml(&text, &path)
            .map_err(|e| model_error(py, &Document::from_table(toml::Table::new(), &path), &e))?;
        let m = Self {
            doc,
            file: Some(path),
        };
        m.load(py, &LoadOptions::default())?;
        Ok(m)
    }

    /// Parses model text (TOML); `path` labels errors and locates the files the model
    /// names (default `<string>` in the current folder).
    #[staticmethod]
    #[pyo3(signature = (text, path = None))]
    fn from_toml(py: Python<'_>, text: &str, path: Option<PathBuf>) -> PyResult<Self> {
        let path = path.unwrap_or_else(|| PathBuf::from("<string>"));
        let doc = Document::from_toml(text, &path)
            .map_err(|e| model_error(py, &Document::from_table(toml::Table::new(), &path), &e))?;
        let m = Self { doc, file: None };
        m.load(py, &LoadOptions::default())?;
        Ok(m)
    }

    /// A model from a dict with the layout of a model file (`{"model": {...}, "nodes":
    /// [...], ...}`); `base_dir` locates the files the model names.
    #[staticmethod]
    #[pyo3(signature = (data, base_dir = None))]
    fn from_dict(
        py: Python<'_>,
        data: &Bound<'_, PyAny>,
        base_dir: Option<PathBuf>,
    ) -> PyResult<Self> {
        let Value::Table(table) = py_to_toml(data, "")? else {
            return Err(PyTypeError::new_err("a model is a dict of tables"));
        };
        let path = base_dir.unwrap_or_default().join("<dict>");
        let m = Self {
            doc: Document::from_table(table, path),
            file: None,
        };
        m.load(py, &LoadOptions::default())?;
        Ok(m)
    }

    /// The model as a dict with the layout of a model file.
    fn to_dict(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        toml_to_py(py, &Value::Table(self.doc.table.clone()))
    }

    /// The model as TOML text (the original text while unchanged).
    fn to_toml(&self) -> String {
        self.doc.to_toml()
    }

    /// The value at a path such as `bodies.bob.mass` or `model.gravity[2]`.
    fn get(&self, py: Python<'_>, path: &str) -> PyResult<Py<PyAny>> {
        let v = self
            .doc
            .get(path)
            .map_err(|e| pyo3::exceptions::PyKeyError::new_err(e.to_string()))?;
        toml_to_py(py, v)
    }

    /// Sets the value at a path (every step but the last must exist) and validates the
    /// changed model; on a `ModelError` the model is left unchanged.
    fn set(&mut self, py: Python<'_>, path: &str, value: &Bound<'_, PyAny>) -> PyResult<()> {
        let v = py_to_toml(value, path)?;
        let mut doc = self.doc.clone();
        doc.set(path, v)
            .map_err(|e| pyo3::exceptions::PyKeyError::new_err(e.to_string()))?;
        doc.load(&LoadOptions::default())
            .map_err(|e| model_error(py, &doc, &e))?;
        self.doc = doc;
        Ok(())
    }

    /// A copy that can be changed independently.
    fn copy(&self) -> Self {
        self.clone()
    }

    /// The model's name (`[model] name`).
    #[getter]
    fn name(&self) -> String {
        self.doc
            .get("model.name")
            .ok()
            .and_then(|v| v.as_str())
            .unwrap_or("model")
            .to_string()
    }

    /// The names of the analyses, in order.
    #[getter]
    fn analyses(&self) -> Vec<String> {
        match self.doc.table.get("analyses") {
            Some(Value::Array(a)) => a
                .iter()
                .filter_map(|x| x.get("name").and_then(Value::as_str).map(String::from))
                .collect(),
            _ => Vec::new(),
        }
    }

    /// The model file it was read from, if any.
    #[getter]
    fn file(&self) -> Option<PathBuf> {
        self.file.clone()
    }

    fn __repr__(&self) -> String {
        format!(
            "samara.Model('{}', analyses={:?}{})",
            self.name(),
            self.analyses(),
            self.file
                .as_ref()
                .map(|f| format!(", file='{}'", f.display()))
                .unwrap_or_default()
        )
    }

    fn __getstate__(&self) -> (String, PathBuf, Option<PathBuf>) {
        (self.doc.to_toml(), self.doc.path.clone(), self.file.clone())
    }

    fn __setstate__(&mut self, state: (String, PathBuf, Option<PathBuf>)) -> PyResult<()> {
        let (text, path, file) = state;
        self.doc =
            Document::from_toml(&text, path).map_err(|e| SamaraError::new_err(e.to_string()))?;
        self.file = file;
        Ok(())
    }

    fn __getnewargs__(&self) -> (String,) {
        (String::new(),)
    }

    #[new]
    #[pyo3(signature = (_text = String::new()))]
    fn __new__(_text: String) -> Self {
        Self {
            doc: Document::from_table(toml::Table::new(), "<unpickled>"),
            file: None,
        }
    }

    /// The linearized equations `M ÿ + G ẏ + K y + Bᵀ μ = 0`, `B y = 0` (docs/
    /// linearized-analyses.md) about the state of the modal analysis `analysis` (after the
    /// analyses it starts from, in its rotating frame), or about the model's initial state
    /// when `analysis` is `None`. Returns `(unknown names, {"M"|"G"|"K"|"B": triplets})`;
    /// runs with the GIL released.
    #[pyo3(signature = (analysis = None))]
    fn linearize_raw(&self, py: Python<'_>, analysis: Option<String>) -> PyResult<Linearized> {
        let loaded = self.load(py, &LoadOptions::default())?;
        let model = &loaded.model;
        let (chain, rotation, target) = match &analysis {
            None => (Vec::new(), None, None),
            Some(name) => {
                let Some(k) = model.analyses.iter().position(|a| &a.name == name) else {
                    return Err(PyValueError::new_err(format!(
                        "the model has no analysis '{name}' (analyses: {})",
                        self.analyses().join(", ")
                    )));
                };
                let samara::model::AnalysisKind::Modal(settings) = &model.analyses[k].kind else {
                    return Err(PyValueError::new_err(format!(
                        "analysis '{name}' is {} and not modal: only a modal analysis says what to linearize about (or pass no analysis for the initial state)",
                        model.analyses[k].type_name()
                    )));
                };
                // The analyses the modal one starts from, first to last.
                let mut chain = Vec::new();
                let mut i = model.analyses[k].start_from;
                while let Some(j) = i {
                    chain.push(j);
                    i = model.analyses[j].start_from;
                }
                chain.reverse();
                (chain, settings.rotation, Some(k))
            }
        };
        let file = self.file.as_deref();
        let lin = py
            .detach(|| -> Result<samara::linear::LinearSystem, samara::Error> {
                let sys = System::new(model);
                let mut starts = samara::analysis::Chain::new(model);
                for &j in &chain {
                    let def = &model.analyses[j];
                    let stage = def.stage();
                    let mut rec = ResultsFile::in_memory(model, file, &sys, stage.as_ref())?
                        .ensure_space(def)?;
                    let state = starts.start(&sys, def)?;
                    let mut capture = starts.capture(j, &mut rec);
                    let summary = stage.run(&sys, state, &mut capture, &mut |_| {})?;
                    starts.finish(j, capture, summary.final_state.clone());
                    if let Some(f) = &summary.failure {
                        return Err(samara::Error::Output {
                            path: PathBuf::from(&model.analyses[j].name),
                            message: format!(
                                "analysis '{}' failed at t = {}: {}",
                                model.analyses[j].name, f.time, f.reason
                            ),
                        });
                    }
                }
                let mut state = match target {
                    Some(k) => starts.start(&sys, &model.analyses[k])?,
                    None => sys.initial_state(),
                };
                if let Some(rot) = &rotation {
                    rot.impose(&sys, &mut state);
                }
                Ok(samara::linear::linearize(&sys, &state, rotation.as_ref()))
            })
            .map_err(|e| samara_error(&e))?;
        let mats = vec![
            ("M".to_string(), triplets(&lin.mass)),
            ("G".to_string(), triplets(&lin.damping)),
            ("K".to_string(), triplets(&lin.stiffness)),
            ("B".to_string(), triplets(&lin.constraint_jacobian)),
        ];
        Ok((lin.unknown_names, mats))
    }

    /// Runs the analyses (all, or `analysis` and the ones it starts from) with the GIL
    /// released. Returns `[(name, results, summary)]`: `results` is the NetCDF file's
    /// bytes, or its path when `out` (a folder) is given. `progress(analysis, fraction)`
    /// is called about every 50 ms. Ctrl-C stops the run at its next output time and
    /// raises `KeyboardInterrupt`.
    #[pyo3(signature = (analysis = None, out = None, progress = None))]
    fn run_raw(
        &self,
        py: Python<'_>,
        analysis: Option<String>,
        out: Option<PathBuf>,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<Vec<RunOutput>> {
        let options = match &out {
            Some(dir) => LoadOptions {
                section_cache: Some(samara::section::results::Cache {
                    dir: dir.join("sections"),
                    write: true,
                }),
            },
            None => LoadOptions::default(),
        };
        let loaded = self.load(py, &options)?;
        // The checks that need the built system, as `samara run` makes them: a located
        // ModelError before anything runs.
        samara::analysis::check_analyses(&loaded, &System::new(&loaded.model))
            .map_err(|e| model_error(py, &self.doc, &e))?;
        let model = &loaded.model;
        let wanted = match &analysis {
            None => vec![true; model.analyses.len()],
            Some(name) => {
                let Some(mut i) = model.analyses.iter().position(|a| &a.name == name) else {
                    return Err(PyValueError::new_err(format!(
                        "the model has no analysis '{name}' (analyses: {})",
                        self.analyses().join(", ")
                    )));
                };
                let mut w = vec![false; model.analyses.len()];
                loop {
                    w[i] = true;
                    match model.analyses[i].start_from {
                        Some(j) => i = j,
                        None => break,
                    }
                }
                w
            }
        };
        let stop = AtomicBool::new(false);
        let pending: Mutex<Option<PyErr>> = Mutex::new(None);
        let file = self.file.as_deref();
        let outcome = py.detach(|| -> Result<Vec<Finished>, samara::Error> {
            let sys = System::new(model);
            let mut finals = samara::analysis::Chain::new(model);
            let mut done = Vec::new();
            for (k, def) in model.analyses.iter().enumerate() {
                if !wanted[k] {
                    continue;
                }
                let initial = finals.start(&sys, def)?;
                let stage = def.stage();
                let inner = match &out {
                    Some(dir) => ResultsFile::create_for(dir, model, file, &sys, stage.as_ref())?
                        .ensure_space(def)?,
                    None => ResultsFile::in_memory(model, file, &sys, stage.as_ref())?
                        .ensure_space(def)?,
                };
                let mut rec = Interruptible { inner, stop: &stop };
                let mut last = Instant::now();
                let mut poll = |f: f64| {
                    if stop.load(Ordering::Relaxed) || last.elapsed() < POLL {
                        return;
                    }
                    last = Instant::now();
                    Python::attach(|py| {
                        let r = py.check_signals().and_then(|()| match &progress {
                            Some(cb) => cb.call1(py, (def.name.as_str(), f)).map(|_| ()),
                            None => Ok(()),
                        });
                        if let Err(e) = r {
                            *pending.lock().expect("not poisoned") = Some(e);
                            stop.store(true, Ordering::Relaxed);
                        }
                    });
                };
                let mut capture = finals.capture(k, &mut rec);
                let summary = stage.run(&sys, initial, &mut capture, &mut poll)?;
                finals.finish(k, capture, summary.final_state.clone());
                let results = match &out {
                    Some(_) => Results::File(rec.inner.finish(&summary)?),
                    None => Results::Bytes(rec.inner.finish_in_memory(&summary)?),
                };
                let failed = summary.failure.is_some();
                done.push(Finished {
                    name: def.name.clone(),
                    results,
                    summary,
                });
                if failed {
                    break;
                }
            }
            Ok(done)
        });
        if let Some(e) = pending.into_inner().expect("not poisoned") {
            return Err(e);
        }
        if stop.load(Ordering::Relaxed) {
            return Err(PyKeyboardInterrupt::new_err("the run was interrupted"));
        }
        let done = outcome.map_err(|e| samara_error(&e))?;
        if let Some(cb) = &progress {
            for d in &done {
                cb.call1(py, (d.name.as_str(), 1.0))?;
            }
        }
        let mut list = Vec::new();
        for d in done {
            let results = match d.results {
                Results::Bytes(b) => PyBytes::new(py, &b).into_any().unbind(),
                Results::File(p) => p.into_pyobject(py)?.into_any().unbind(),
            };
            let s = PyDict::new(py);
            s.set_item("steps", d.summary.steps)?;
            s.set_item("newton_iterations", d.summary.newton_iterations)?;
            s.set_item("rejected_steps", d.summary.rejected_steps)?;
            s.set_item("factorizations", d.summary.factorizations)?;
            s.set_item("wall_time", d.summary.wall_time.as_secs_f64())?;
            s.set_item(
                "max_constraint_violation",
                d.summary.max_constraint_violation,
            )?;
            s.set_item("warnings", d.summary.warnings.clone())?;
            match &d.summary.failure {
                Some(f) => s.set_item("failure", format!("t = {}: {}", f.time, f.reason))?,
                None => s.set_item("failure", py.None())?,
            }
            list.push((d.name, results, s.unbind()));
        }
        Ok(list)
    }
}

/// A sparse matrix as coordinate triplets: (rows, columns, values, (n_rows, n_cols)).
type Triplets = (Vec<usize>, Vec<usize>, Vec<f64>, (usize, usize));

fn triplets(a: &samara::linear::SparseMatrix) -> Triplets {
    let r = a.as_ref();
    let (mut rows, mut cols, mut vals) = (Vec::new(), Vec::new(), Vec::new());
    for j in 0..a.ncols() {
        for (&i, &v) in r.row_idx_of_col_raw(j).iter().zip(r.val_of_col(j)) {
            rows.push(i);
            cols.push(j);
            vals.push(v);
        }
    }
    (rows, cols, vals, (a.nrows(), a.ncols()))
}

/// Unknown names and the named matrices of a linearization.
type Linearized = (Vec<String>, Vec<(String, Triplets)>);

/// One analysis run from Python: name, results (bytes or path), summary.
type RunOutput = (String, Py<PyAny>, Py<PyDict>);

enum Results {
    Bytes(Vec<u8>),
    File(PathBuf),
}

struct Finished {
    name: String,
    results: Results,
    summary: samara::analysis::AnalysisSummary,
}

/// Whether `path` is a plain file name (letters, digits, `_`, `-`, `.`), as analysis and
/// model names must be to name results files.
#[pyfunction]
fn is_plain_file_name(path: &str) -> bool {
    samara::model::is_plain_file_name(path)
}

/// Refuses a `SAMARA_ISA` that names no compiled copy (`ValueError`), as the `samara`
/// command does; the engine alone would ignore it ([`samara::math::isa::Isa::requested`]).
#[pyfunction]
fn check_isa_variable() -> PyResult<()> {
    samara::math::isa::Isa::requested()
        .map(|_| ())
        .map_err(|m| {
            PyValueError::new_err(format!(
                "{m} (unset it to run the widest copy this CPU has)"
            ))
        })
}

/// The version of the samara engine.
#[pyfunction]
fn version() -> &'static str {
    samara::VERSION
}

#[pymodule]
fn _samara(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Model>()?;
    m.add("SamaraError", m.py().get_type::<SamaraError>())?;
    m.add("ModelError", m.py().get_type::<ModelError>())?;
    m.add_function(wrap_pyfunction!(version, m)?)?;
    m.add_function(wrap_pyfunction!(is_plain_file_name, m)?)?;
    m.add_function(wrap_pyfunction!(check_isa_variable, m)?)?;
    Ok(())
}
