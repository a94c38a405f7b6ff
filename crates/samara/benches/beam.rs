//! Beam benchmark (issue #4): the steel cantilever of `examples/bench/cantilever_N.toml`
//! (N two-node elements; `cantilever_p8x4.toml`: 4 elements of order 8), static in 10 load
//! steps and 1 s of dynamics at h = 1e-3, ρ∞ = 0.9, full and modified Newton.
//!
//! `cargo bench -p samara --bench beam [-- N… t_end=T]` (default N = 10, 100, 1000) prints
//! wall time, Newton iterations, ms per step and the tip displacement at the end of each
//! analysis, then the fitted growth exponent of the dynamic wall time with N. `t_end`
//! shortens the dynamic runs (for the large models and for profiling), `newton=full` or
//! `newton=modified` runs one variant only (`modified`: the dynamics alone),
//! `partition=two_parts` runs the dynamics in two parts (a partner thread); the elements are
//! evaluated on rayon's threads (`RAYON_NUM_THREADS`) from `PARALLEL_MIN_ELEMENTS` on.
//! Sizes without a model file are skipped: `python3 examples/bench/make_cantilevers.py N…`
//! writes `cantilever_N.toml` for a growth scan (to 100,000 elements in docs/integrators.md,
//! "Twenty-fourth round": an element step 3.3 % dearer at 100,000 than at 1,000 with full
//! Newton, 5.0 % with modified, most of it reached at 3,000).
//!
//! From 1,000 blocks on the block LU factors and solves two halves on two threads (a
//! separator order, the same bits with any thread count; the iterations run inside
//! `rayon::scope` once per step). `-- 1000 t_end=0.1`, dynamics, 6 interleaved runs, load
//! average 1.5–1.7, 2026-11-28, best / median wall: two threads, full Newton 0.557 / 0.611 →
//! 0.489 / 0.594 s, modified 0.401 / 0.426 → 0.300 / 0.350 s; one thread unchanged within
//! the noise (0.705 / 0.877 → 0.721 / 0.847 s, 0.440 / 0.522 → 0.467 / 0.502 s).
//!
//! 1,000 → 10,000 elements (`-- 1000 10000 t_end=0.1`, one thread, CPU per step, load
//! average 1–3, 2026-11-27): full Newton 5.65 → 71.8 ms (exponent 1.10), modified 3.02 →
//! 39.5 ms (1.12); before the parallel path's 128-element window (run inside
//! `rayon::scope`) 6.53 → 85.5 and 3.27 → 52.4 ms (1.12 / 1.21). Instructions grow exactly
//! with N; the excess is the working set (element data, matrix, factors) leaving the
//! shared cache (docs/benchmarks.md, "Where the growth … comes from").
//!
//! After the compact beam element (sections interpolated from the beam's shared table, not
//! stored per point; 3 alternating runs each, wall, quiet machine, 2026-11-27): full Newton
//! 6.38 → 77.2 ms before (exponent 1.08), 6.30 → 72.8 ms after (1.06); modified 3.28 →
//! 44.9 ms before (1.14), 3.39 → 38.1 ms after (1.05). Per element and step at 1,000 /
//! 2,000 / 4,000 / 10,000 elements: full Newton 6.6 / 7.2 / 7.8 / 8.0 µs before, 6.4 / 6.4 /
//! 7.5 / 7.7 µs after; modified 3.4 / 3.5 / 3.9 / 4.8 µs before, 3.3 / 3.2 / 3.6 / 4.2 µs
//! after. `cantilever_2000/4000.toml` are not kept: write them with `model()` of
//! `make_cantilevers.py`.
//!
//! Block LU cache order (2026-11-27; same operations, results bit-identical): the input
//! blocks are copied into the factor storage in the reverse of the order the elimination
//! first needs them, and the L blocks sit in a segment of their own. CPU per 100 steps,
//! one thread, 3 alternating runs each at load average 3.1–3.5: full Newton 0.750 → 8.56 s
//! before (exponent 1.06), 0.750 → 8.02 s after (1.03); modified 0.407 → 4.79 s before
//! (1.07), 0.397 → 4.76 s after (1.08). Profile samples at 10,000 elements (statics + 50
//! steps, 1 kHz): factorization ~920 → ~440, solves ~180 → ~105 (full); modified Newton's
//! solves ~300 → ~170. At load average 0.3–1 (wall, 2 alternating runs): full Newton
//! 0.805 → 8.71 s before, 0.742 → 8.45 s after; modified 0.421 → 4.84 s, 0.428 → 4.90 s
//! (noise). Simulated 32 MB LRU last level (cachegrind): no gain (15.24 → 15.95 M misses).

use samara::analysis::History;
use samara::analysis::run_all;
use samara::model::{AnalysisKind, JacobianUpdate, Model, Partition};
use samara::system::System;
use std::path::Path;
use std::time::Instant;

fn main() {
    let all: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    let t_end: Option<f64> = all
        .iter()
        .find_map(|a| a.strip_prefix("t_end=")?.parse().ok());
    let only_newton: Option<String> = all
        .iter()
        .find_map(|a| a.strip_prefix("newton=").map(String::from));
    let two_parts = all.iter().any(|a| a == "partition=two_parts");
    let args: Vec<String> = all.into_iter().filter(|a| !a.contains('=')).collect();
    let cases: Vec<String> = if args.is_empty() {
        vec!["10".into(), "100".into(), "1000".into(), "p8x4".into()]
    } else {
        args
    };
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    println!(
        "{:<8} {:<8} {:<9} {:>9} {:>8} {:>8} {:>9} {:>12}",
        "model", "analysis", "newton", "wall [s]", "cpu [s]", "it/step", "ms/step", "tip w [m]"
    );
    let mut growth: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    for case in &cases {
        let path = root.join(format!("examples/bench/cantilever_{case}.toml"));
        let Ok(loaded) = Model::from_file(&path) else {
            eprintln!("skipping {}", path.display());
            continue;
        };
        for newton in ["full", "modified"] {
            if only_newton.as_deref().is_some_and(|o| o != newton) {
                continue;
            }
            let mut model = loaded.model.clone();
            for a in &mut model.analyses {
                if let AnalysisKind::Dynamic(d) = &mut a.kind {
                    if let Some(t) = t_end {
                        d.t_end = t;
                    }
                    if two_parts {
                        d.partition = Partition::TwoParts;
                    }
                    d.jacobian = if newton == "full" {
                        JacobianUpdate::Full
                    } else {
                        JacobianUpdate::Modified
                    };
                }
            }
            let sys = System::new(&model);
            let tip = model.node_index("tip").expect("tip node");
            let x0 = model.nodes[tip].position;
            // The static and dynamic analyses are independent (both start from rest).
            for (k, def) in model.analyses.iter().enumerate() {
                if newton == "modified" && def.type_name() == "static" {
                    continue;
                }
                let mut single = model.clone();
                single.analyses = vec![def.clone()];
                let _ = k;
                let (clock, cpu0) = (Instant::now(), cpu_seconds());
                let out = run_all(&single, &sys, |_| Ok(History::default()), |_, _| {})
                    .expect("in-memory");
                let wall = clock.elapsed().as_secs_f64();
                let cpu = cpu_seconds() - cpu0;
                let (s, h) = &out[0];
                if let Some(f) = &s.failure {
                    println!("{case:<8} {:<8} {newton:<9} FAILED: {}", def.name, f.reason);
                    continue;
                }
                let w = h.last().unwrap().state.nodes[tip].x.z - x0.z;
                println!(
                    "{case:<8} {:<8} {newton:<9} {wall:>9.3} {cpu:>8.2} {:>8.2} {:>9.3} {w:>12.6e}",
                    def.name,
                    s.newton_iterations as f64 / s.steps as f64,
                    1e3 * wall / s.steps as f64
                );
                if def.type_name() == "dynamic"
                    && let Ok(n) = case.parse::<f64>()
                {
                    {
                        let key = format!("dynamic, {newton} Newton");
                        match growth.iter_mut().find(|(g, _)| *g == key) {
                            Some((_, v)) => v.push((n, wall)),
                            None => growth.push((key, vec![(n, wall)])),
                        }
                    }
                }
            }
        }
    }
    for (key, pts) in &growth {
        if pts.len() >= 2 {
            let lx: Vec<f64> = pts.iter().map(|p| p.0.ln()).collect();
            let ly: Vec<f64> = pts.iter().map(|p| p.1.ln()).collect();
            let k = lx.len() as f64;
            let (mx, my) = (lx.iter().sum::<f64>() / k, ly.iter().sum::<f64>() / k);
            let sxy: f64 = lx.iter().zip(&ly).map(|(a, b)| (a - mx) * (b - my)).sum();
            let sxx: f64 = lx.iter().map(|a| (a - mx) * (a - mx)).sum();
            println!(
                "growth of wall time with N, {key}: exponent {:.3}",
                sxy / sxx
            );
        }
    }
}

/// CPU time of the process, all threads, user + system (Linux `/proc/self/stat`, in clock
/// ticks of 10 ms; NaN elsewhere): on a shared machine it is steadier than wall time.
fn cpu_seconds() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return f64::NAN;
    };
    // Fields after the command name: state is field 3, utime 14 and stime 15.
    let Some((_, rest)) = stat.rsplit_once(')') else {
        return f64::NAN;
    };
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks = |i: usize| f.get(i - 3).and_then(|x| x.parse::<f64>().ok());
    match (ticks(14), ticks(15)) {
        (Some(u), Some(s)) => (u + s) / 100.0,
        _ => f64::NAN,
    }
}
