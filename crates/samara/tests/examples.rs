//! Every model file under examples/ (found by walking the folder, so a new example cannot be
//! forgotten) loads, validates and runs every one of its analyses — chained through
//! `start_from` as `samara run` does — with each dynamic analysis cut to its first
//! `STEPS` steps. Static analyses run in full. The command-line run of the README's first
//! example is in samara-cli/tests/examples.rs.

use samara::analysis::{History, run_all};
use samara::model::{AnalysisKind, Model};
use samara::system::System;
use std::path::{Path, PathBuf};

/// Steps of each dynamic analysis.
const STEPS: usize = 10;

pub fn model_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            model_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "toml")
            && !path.to_string_lossy().ends_with(".section.toml")
        {
            // Section files (examples/sections/) are not models: samara-cli's
            // section tests run every one of them.
            out.push(path);
        }
    }
}

#[test]
fn every_example_runs() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
    let mut files = Vec::new();
    model_files(&root, &mut files);
    files.sort();
    // The walk found the folder's examples (not, say, an empty directory).
    for name in [
        "landing_gear.toml",
        "blade_spinup.toml",
        "curved_cantilever.toml",
        "loaded_cantilever.toml",
        "verification/heavy_top.toml",
        "bench/chain_revolute_1000.toml",
        "bench/cantilever_10000.toml",
        "rotor/nrel5mw_rotor.toml",
        "rotor/nrel5mw_flexible.toml",
    ] {
        assert!(files.contains(&root.join(name)), "{name} not found");
    }
    for path in &files {
        let rel = path.strip_prefix(&root).unwrap().display().to_string();
        let loaded = Model::from_file(path).unwrap_or_else(|e| panic!("{rel}: {e}"));
        let mut m = loaded.model;
        assert!(!m.analyses.is_empty(), "{rel}: no analysis");
        for a in &mut m.analyses {
            if let AnalysisKind::Dynamic(d) = &mut a.kind {
                d.t_end = d.t_end.min(d.t_start + STEPS as f64 * d.step);
            }
        }
        let sys = System::new(&m);
        let clock = std::time::Instant::now();
        let out = run_all(&m, &sys, |_| Ok(History::default()), |_, _| {})
            .unwrap_or_else(|e| panic!("{rel}: {e}"));
        assert_eq!(
            out.len(),
            m.analyses.len(),
            "{rel}: an analysis did not run"
        );
        for ((s, h), def) in out.iter().zip(&m.analyses) {
            assert!(s.failure.is_none(), "{rel}, {}: {:?}", def.name, s.failure);
            let last = h
                .last()
                .unwrap_or_else(|| panic!("{rel}: nothing recorded"));
            match &def.kind {
                AnalysisKind::Dynamic(d) => {
                    assert!((last.time - d.t_end).abs() < 1e-9 * d.t_end.abs().max(1.0));
                    // Fixed steps: all of them taken; adaptive steps choose their own.
                    let expected = if d.adaptive.is_some() {
                        1
                    } else {
                        STEPS.min(((d.t_end - d.t_start) / d.step).round() as usize)
                    };
                    assert!(s.steps >= expected, "{rel}: {} steps", s.steps);
                }
                AnalysisKind::Static(_) => {
                    assert!((last.load_factor - 1.0).abs() < 1e-12, "{rel}");
                }
                AnalysisKind::Modal(ms) => {
                    let f = &h.arrays.iter().find(|a| a.0.name == "frequency");
                    let f = &f.unwrap_or_else(|| panic!("{rel}: no frequencies")).1;
                    assert_eq!(f.len(), ms.n_modes, "{rel}");
                }
                AnalysisKind::Campbell(cs) => {
                    let f = &h.arrays.iter().find(|a| a.0.name == "campbell_frequency");
                    let f = &f
                        .unwrap_or_else(|| panic!("{rel}: no Campbell frequencies"))
                        .1;
                    assert_eq!(f.len(), cs.modal.n_modes * cs.speeds.len(), "{rel}");
                }
                AnalysisKind::Floquet(fs) => {
                    let f = &h.arrays.iter().find(|a| a.0.name == "floquet_modulus");
                    let f = &f
                        .unwrap_or_else(|| panic!("{rel}: no Floquet multipliers"))
                        .1;
                    assert_eq!(f.len(), fs.n_modes, "{rel}");
                }
            }
            let finite = last.state.nodes.iter().all(|n| {
                n.x.iter()
                    .chain(n.v.iter())
                    .chain(n.w.iter())
                    .all(|x| x.is_finite())
            });
            assert!(finite, "{rel}, {}: non-finite state", def.name);
        }
        println!(
            "{rel}: {} analyses, {:.2} s",
            m.analyses.len(),
            clock.elapsed().as_secs_f64()
        );
    }
}

/// examples/bench/make_cantilevers.py, run from a copy in a scratch folder: without
/// arguments it writes the committed benchmark models byte for byte; with element counts it
/// writes those models only, each a cantilever of that many elements; a count that is not a
/// whole number from 1 to 10,000,000 in ASCII digits is refused with its value named and
/// nothing written.
#[test]
fn cantilever_generator_writes_the_committed_models_and_named_sizes() {
    let bench = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/bench");
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(
        bench.join("make_cantilevers.py"),
        dir.path().join("make_cantilevers.py"),
    )
    .unwrap();
    let run = |args: &[&str]| {
        std::process::Command::new("python3")
            .arg(dir.path().join("make_cantilevers.py"))
            .args(args)
            .output()
            .expect("python3 runs")
    };
    let written = || {
        let mut names: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".toml"))
            .collect();
        names.sort();
        names
    };
    assert!(run(&[]).status.success());
    let defaults = written();
    assert_eq!(
        defaults,
        [
            "cantilever_10.toml",
            "cantilever_100.toml",
            "cantilever_1000.toml",
            "cantilever_10000.toml",
            "cantilever_p8x4.toml"
        ]
    );
    for name in &defaults {
        let ours = std::fs::read_to_string(dir.path().join(name)).unwrap();
        let committed = std::fs::read_to_string(bench.join(name)).unwrap();
        assert!(ours == committed, "{name} differs from the committed model");
        std::fs::remove_file(dir.path().join(name)).unwrap();
    }

    assert!(run(&["7", "12"]).status.success());
    assert_eq!(written(), ["cantilever_12.toml", "cantilever_7.toml"]);
    for n in [7usize, 12] {
        let m = Model::from_file(dir.path().join(format!("cantilever_{n}.toml")))
            .unwrap()
            .model;
        assert_eq!(m.name, format!("cantilever_{n}"));
        // One two-node beam element per span between consecutive beam nodes: root, n − 1
        // inner nodes and the tip (the clamp's ground is not a model node).
        assert_eq!(m.nodes.len(), n + 1, "cantilever_{n}");
        std::fs::remove_file(dir.path().join(format!("cantilever_{n}.toml"))).unwrap();
    }

    let long = "9".repeat(5000);
    for bad in ["3x", "0", "-5", "10000001", "²", "", long.as_str()] {
        let out = run(&["4", bad]);
        assert_eq!(out.status.code(), Some(1), "{bad}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains(&format!("'{bad}' is not an element count")),
            "{bad}: {err}"
        );
        assert!(written().is_empty(), "{bad}: a model was written");
    }
}
