//! `samara sweep MODEL.toml --grid PARAMS.toml`: the model run once per case, one case
//! after the other, each case's results files in `<out>/case_NNNN/`, and `<out>/index.csv`
//! listing every case's values, status and error. A failing case is recorded and the
//! others go on. (From Python, `samara.sweep` runs the same cases on Dask.)
//!
//! The parameters file holds either a grid (every combination, the first parameter
//! varying slowest) or a list of cases; keys are model paths (`model::document`):
//!
//! ```toml
//! [grid]
//! "bodies.bob.mass" = [1.0, 2.0]
//! "model.gravity[2]" = [-9.81, -1.62]
//! ```
//! ```toml
//! [[cases]]
//! "bodies.bob.mass" = 1.0
//! ```

use samara::model::document::{Document, parse_path};
use samara::model::{LoadOptions, ModelError};
use samara::output::ResultsFile;
use samara::system::System;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use toml::Value;

/// One case: (path, value) in the order of the parameters file.
type Case = Vec<(String, Value)>;

/// Flattens nested tables (a bare dotted key `bodies.bob.mass = …` is a nested table in
/// TOML) into `(path, value)` pairs.
fn flatten(prefix: &str, t: &toml::Table, out: &mut Vec<(String, Value)>) {
    for (k, v) in t {
        let p = if prefix.is_empty() {
            k.clone()
        } else if k.starts_with('[') {
            format!("{prefix}{k}")
        } else {
            format!("{prefix}.{k}")
        };
        match v {
            Value::Table(sub) => flatten(&p, sub, out),
            _ => out.push((p, v.clone())),
        }
    }
}

/// Where each leaf key of a table was written (TOML tables here do not keep their order).
fn positions(prefix: &str, t: &toml::de::DeTable<'_>, out: &mut Vec<(String, usize)>) {
    for (k, v) in t {
        let k = k.get_ref().to_string();
        let p = if prefix.is_empty() {
            k
        } else if k.starts_with('[') {
            format!("{prefix}{k}")
        } else {
            format!("{prefix}.{k}")
        };
        match v.get_ref() {
            toml::de::DeValue::Table(sub) => positions(&p, sub, out),
            _ => out.push((p, v.span().start)),
        }
    }
}

/// Sorts `(path, value)` pairs into the order they were written in `section` of `text`
/// (`grid`, or the first of `cases`).
fn written_order(text: &str, params: &mut [(String, Value)]) {
    let Ok(doc) = toml::de::DeTable::parse(text) else {
        return;
    };
    let mut pos = Vec::new();
    match doc.get_ref().get("grid").map(|g| g.get_ref()) {
        Some(toml::de::DeValue::Table(g)) => positions("", g, &mut pos),
        _ => {
            if let Some(toml::de::DeValue::Array(a)) =
                doc.get_ref().get("cases").map(|c| c.get_ref())
                && let Some(toml::de::DeValue::Table(first)) = a.iter().next().map(|c| c.get_ref())
            {
                positions("", first, &mut pos);
            }
        }
    }
    params.sort_by_key(|(p, _)| {
        pos.iter()
            .find(|(q, _)| q == p)
            .map_or(usize::MAX, |(_, at)| *at)
    });
}

fn is_number(v: &Value) -> bool {
    matches!(v, Value::Float(_) | Value::Integer(_))
}

/// The cases of a parameters file, and the parameter names.
pub fn cases(text: &str) -> Result<(Vec<String>, Vec<Case>), String> {
    let table: toml::Table = toml::from_str(text).map_err(|e| e.to_string())?;
    let unknown: Vec<&String> = table
        .keys()
        .filter(|k| *k != "grid" && *k != "cases")
        .collect();
    if !unknown.is_empty() {
        return Err(format!(
            "unknown table(s) {unknown:?}: a parameters file has [grid] or [[cases]]"
        ));
    }
    let check = |p: &str, v: &Value| -> Result<(), String> {
        parse_path(p).map_err(|e| e.to_string())?;
        if !is_number(v) {
            return Err(format!("{p}: sweep values are numbers, got {v}"));
        }
        Ok(())
    };
    match (table.get("grid"), table.get("cases")) {
        (Some(Value::Table(g)), None) => {
            let mut params = Vec::new();
            flatten("", g, &mut params);
            written_order(text, &mut params);
            if params.is_empty() {
                return Err("[grid] has no parameters".into());
            }
            let mut names = Vec::new();
            let mut lists = Vec::new();
            for (p, v) in params {
                let Value::Array(a) = v else {
                    return Err(format!("{p}: a grid parameter is a list of values"));
                };
                if a.is_empty() {
                    return Err(format!("{p}: no values"));
                }
                for x in &a {
                    check(&p, x)?;
                }
                names.push(p);
                lists.push(a);
            }
            let n: usize = lists
                .iter()
                .try_fold(1usize, |n, l| n.checked_mul(l.len()))
                .filter(|&n| n <= 1_000_000)
                .ok_or("the grid has more than 1,000,000 cases")?;
            let mut out = Vec::with_capacity(n);
            for k in 0..n {
                // The first parameter varies slowest (row-major, as itertools.product).
                let mut rest = k;
                let mut case = vec![(String::new(), Value::Integer(0)); names.len()];
                for (j, l) in lists.iter().enumerate().rev() {
                    case[j] = (names[j].clone(), l[rest % l.len()].clone());
                    rest /= l.len();
                }
                out.push(case);
            }
            Ok((names, out))
        }
        (None, Some(Value::Array(list))) => {
            let mut out = Vec::new();
            let mut names: Option<Vec<String>> = None;
            for (i, c) in list.iter().enumerate() {
                let Value::Table(t) = c else {
                    return Err(format!("cases[{i}] is not a table"));
                };
                let mut case = Vec::new();
                flatten("", t, &mut case);
                written_order(text, &mut case);
                for (p, v) in &case {
                    check(p, v)?;
                }
                let these: Vec<String> = case.iter().map(|c| c.0.clone()).collect();
                match &names {
                    None => names = Some(these),
                    Some(n) if *n != these => {
                        return Err(format!(
                            "cases[{i}] sets {these:?}, cases[0] sets {n:?}: every case sets the same paths"
                        ));
                    }
                    Some(_) => {}
                }
                out.push(case);
            }
            let names = names.ok_or("[[cases]] is empty")?;
            Ok((names, out))
        }
        _ => Err("a parameters file has either a [grid] table or [[cases]], not both".into()),
    }
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

fn value_text(v: &Value) -> String {
    match v {
        Value::Float(x) => format!("{x:?}"),
        other => other.to_string(),
    }
}

/// How one case ended.
enum Outcome {
    Completed,
    /// The solver stopped early (results kept, `status = "failed"`).
    Failed(String),
    /// Nothing ran: the changed model is invalid, or a file could not be written.
    Error(String),
}

fn model_error_text(doc: &Document, e: &ModelError) -> String {
    e.errors()
        .map(|d| {
            let at = d
                .span
                .as_ref()
                .and_then(|s| doc.locate(s.start))
                .map(|p| format!("{p}: "))
                .unwrap_or_default();
            format!("{at}{}", d.message)
        })
        .collect::<Vec<_>>()
        .join("; ")
}

fn run_case(base: &Document, case: &Case, model_file: &Path, dir: &Path) -> Outcome {
    let mut doc = base.clone();
    for (p, v) in case {
        if let Err(e) = doc.set(p, v.clone()) {
            return Outcome::Error(e.to_string());
        }
    }
    let options = LoadOptions {
        section_cache: Some(samara::section::results::Cache {
            dir: dir.join("sections"),
            write: true,
        }),
    };
    let loaded = match doc.load(&options) {
        Ok(l) => l,
        Err(e) => return Outcome::Error(model_error_text(&doc, &e)),
    };
    let model = &loaded.model;
    let sys = System::new(model);
    if let Err(e) = samara::analysis::check_analyses(&loaded, &sys) {
        return Outcome::Error(model_error_text(&doc, &e));
    }
    let mut chain = samara::analysis::Chain::new(model);
    for (index, def) in model.analyses.iter().enumerate() {
        let initial = match chain.start(&sys, def) {
            Ok(state) => state,
            Err(e) => return Outcome::Error(e.to_string()),
        };
        let stage = def.stage();
        let mut file =
            match ResultsFile::create_for(dir, model, Some(model_file), &sys, stage.as_ref())
                .and_then(|f| f.ensure_space(def))
            {
                Ok(f) => f,
                Err(e) => return Outcome::Error(e.to_string()),
            };
        let mut capture = chain.capture(index, &mut file);
        let summary = match stage.run(&sys, initial, &mut capture, &mut |_| {}) {
            Ok(s) => s,
            Err(e) => return Outcome::Error(e.to_string()),
        };
        chain.finish(index, capture, summary.final_state.clone());
        if let Err(e) = file.finish(&summary) {
            return Outcome::Error(e.to_string());
        }
        if let Some(f) = &summary.failure {
            return Outcome::Failed(format!("{}: t = {}: {}", def.name, f.time, f.reason));
        }
    }
    Outcome::Completed
}

/// `samara sweep`.
pub fn sweep(model_path: &Path, grid: &Path, out: Option<PathBuf>) -> ExitCode {
    let text = match std::fs::read_to_string(model_path) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("error: cannot read '{}': {e}", model_path.display());
            return ExitCode::from(crate::EXIT_MODEL);
        }
    };
    let base = match Document::from_toml(&text, model_path) {
        Ok(d) => d,
        Err(e) => {
            eprint!("{}", e.render_plain());
            return ExitCode::from(crate::EXIT_MODEL);
        }
    };
    // The unchanged model must be valid: a typo in the model is not a per-case failure.
    if let Err(e) = base.load(&LoadOptions::default()) {
        crate::report::diagnostics(&e.source, &e.diagnostics);
        return ExitCode::from(crate::EXIT_MODEL);
    }
    let params = match std::fs::read_to_string(grid)
        .map_err(|e| e.to_string())
        .and_then(|t| cases(&t))
    {
        Ok(p) => p,
        Err(e) => {
            eprintln!("error: {}: {e}", grid.display());
            return ExitCode::from(crate::EXIT_MODEL);
        }
    };
    let (names, all) = params;
    // Every path must name a value of the model (or a key its table may take).
    for n in &names {
        let mut probe = base.clone();
        let v = &all[0]
            .iter()
            .find(|c| &c.0 == n)
            .expect("every case sets every name")
            .1;
        if let Err(e) = probe.set(n, v.clone()) {
            eprintln!("error: {}: {e}", grid.display());
            return ExitCode::from(crate::EXIT_MODEL);
        }
    }
    let out = out.unwrap_or_else(|| crate::results_dir(model_path, None).join("sweep"));
    if let Err(e) = std::fs::create_dir_all(&out) {
        eprintln!("error: cannot create '{}': {e}", out.display());
        return ExitCode::from(crate::EXIT_MODEL);
    }
    let width = all.len().saturating_sub(1).to_string().len().max(4);
    let mut index = String::from("case,status");
    for n in &names {
        index.push(',');
        index.push_str(&csv_field(n));
    }
    index.push_str(",directory,error\n");
    let mut bad = 0usize;
    let clock = std::time::Instant::now();
    for (k, case) in all.iter().enumerate() {
        let name = format!("case_{k:0width$}");
        let dir = out.join(&name);
        let outcome = run_case(&base, case, model_path, &dir);
        let (status, error) = match &outcome {
            Outcome::Completed => ("completed", String::new()),
            Outcome::Failed(e) => ("failed", e.clone()),
            Outcome::Error(e) => ("error", e.clone()),
        };
        if !matches!(outcome, Outcome::Completed) {
            bad += 1;
        }
        let values: Vec<String> = case
            .iter()
            .map(|(p, v)| format!("{p} = {}", value_text(v)))
            .collect();
        eprintln!(
            "{name}: {status} ({}){}",
            values.join(", "),
            if error.is_empty() {
                String::new()
            } else {
                format!(": {error}")
            }
        );
        let _ = write!(index, "{k},{status}");
        for (_, v) in case {
            let _ = write!(index, ",{}", value_text(v));
        }
        let _ = writeln!(index, ",{name},{}", csv_field(&error));
    }
    let index_path = out.join("index.csv");
    if let Err(e) = std::fs::write(&index_path, index) {
        eprintln!("error: cannot write '{}': {e}", index_path.display());
        return ExitCode::from(crate::EXIT_MODEL);
    }
    println!(
        "{}: {} cases, {} completed, {bad} failed, {:.2} s",
        index_path.display(),
        all.len(),
        all.len() - bad,
        clock.elapsed().as_secs_f64()
    );
    if bad > 0 {
        ExitCode::from(2)
    } else {
        ExitCode::SUCCESS
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_is_row_major_and_lists_keep_their_order() {
        // Written order, not alphabetical.
        let (names, c) = cases(
            "[grid]\n\"model.gravity[2]\" = [-1, -2, -3]\n\"bodies.bob.mass\" = [1.0, 2.0]\n",
        )
        .unwrap();
        assert_eq!(names, ["model.gravity[2]", "bodies.bob.mass"]);
        assert_eq!(c.len(), 6);
        assert_eq!(c[1][0].1, Value::Integer(-1));
        assert_eq!(c[1][1].1, Value::Float(2.0));
        assert_eq!(c[2][0].1, Value::Integer(-2));
        // A bare dotted key is a nested table in TOML; it names the same path.
        let (names, _) = cases("[grid]\nbodies.bob.mass = [1.0]\n").unwrap();
        assert_eq!(names, ["bodies.bob.mass"]);
        let (names, c) =
            cases("[[cases]]\n\"c\" = 2\n\"a.b\" = 1.0\n[[cases]]\n\"c\" = 4\n\"a.b\" = 3.0\n")
                .unwrap();
        assert_eq!(names, ["c", "a.b"]);
        assert_eq!(c[1][0].1, Value::Integer(4));
    }

    #[test]
    fn bad_parameter_files_are_refused() {
        for (text, why) in [
            ("[grid]\n", "no parameters"),
            ("[grid]\n\"a\" = 1.0\n", "list of values"),
            ("[grid]\n\"a\" = []\n", "no values"),
            ("[grid]\n\"a\" = [\"x\"]\n", "numbers"),
            ("[grid]\n\"a[\" = [1.0]\n", "without"),
            ("[other]\n", "unknown"),
            (
                "[[cases]]\n\"a\" = 1.0\n[[cases]]\n\"b\" = 1.0\n",
                "same paths",
            ),
            (
                "[grid]\n\"a\" = [1.0]\n[[cases]]\n\"a\" = 1.0\n",
                "not both",
            ),
        ] {
            let e = cases(text).unwrap_err();
            assert!(e.contains(why), "{text:?}: {e}");
        }
    }
}
