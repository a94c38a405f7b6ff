//! Chain benchmark (issue #2): N steel links pinned end to end, 1 s at h = 1e-3 with
//! ρ∞ = 0.9 and ρ∞ = 1, on revolute joints (released from rest) and on spherical joints
//! (spinning at 1 rad/s about z). Models: `examples/bench/chain_{revolute,spherical}_N.toml`.
//!
//! `cargo bench -p samara --bench chain [-- N… WORD… t_end=T repeats=R]` prints, per run:
//! wall time, Newton iterations and factorizations per step, tip position at 1 s, energy
//! drift, max constraint violation; then the fitted growth exponent of wall time with N.
//! Words keep only the runs whose joint kind, analysis name or Newton variant they name
//! (`revolute rho0.9 full`); `t_end` shortens the runs and `repeats` overrides the
//! repetitions (for profiling and instruction counts); `digest=1` also prints a digest of
//! the bits of every recorded frame's state (positions, rotations, velocities,
//! accelerations, coordinates, multipliers) and of the iteration counts, to check that an
//! optimization leaves the results identical to the bit. The word `two_parts` runs the
//! analyses with `partition = "two_parts"` (two threads when `RAYON_NUM_THREADS` allows).
//!
//! Issue #17's targets, N = 100 revolute, ρ∞ = 0.9: 0.3 s with full Newton, 0.15 s with
//! modified Newton. On the 2-core VM of 2026-11-27 (1.43× slower than the earlier
//! sessions', where the fifth round's code ran 0.289 / 0.139 s), after the seventh round:
//! 0.351 / 0.162 s (best of 8 interleaved runs of this bench, medians 0.358 / 0.164 s, load
//! average 0.6–0.9; 0.379 / 0.185 s for the sixth round's code in the same runs); callgrind
//! `-- 100 revolute rho0.9 full t_end=0.1 repeats=1` 582.7M instructions, `-- 100 revolute
//! rho0.9 modified repeats=1` 2161.4M (597.4M / 2346.4M before). The eighth round kept
//! nothing (full Newton's second iteration is needed for the accuracy the energy balances
//! rely on; a quadratic predictor and explicit pivot inverses did not pay); the same code
//! measured 0.364 / 0.164–0.170 s there (load average 3.4–3.9). The ninth round kept
//! nothing either (the factorization taking the assembled matrix, ρBᵀB without its skip,
//! cheaper scatter kernels: same bits, no gain in time); at its start, 2026-11-28: 0.354 /
//! 0.163 s best, 0.359 / 0.166 s median (6–10 runs, load average 2.2–3.9), callgrind
//! 588.8M / 2210.4M instructions (2.00 / 2.95 iterations per step). The tenth round
//! (2026-11-28, the machine idle, load average 0–1, 6 interleaved runs): 0.372 / 0.178 s
//! best, 0.390 / 0.189 s median, one thread or two alike (callgrind 589.7M / 2220.5M); the
//! block LU's two-thread separator order measured 0.439 / 0.221 s best with two threads (a
//! loss) and is used from 1,000 blocks on only. Targets not met on this machine, with one
//! thread or two. The eleventh round kept nothing: predicting modified Newton's multipliers
//! by the increment of the step before last gave 2.47 iterations and 0.169 factorizations
//! per step (2179.4M → 1838.2M instructions) but stops too early for tests/options.rs's
//! pendulum (docs/integrators.md). The twelfth round assembles the dynamic steps' matrix
//! straight into the block LU's factor storage (no copy; the same bits, digests
//! 7b5cfb5783245daa / a84884afb7a69216): `perf stat` task-clock of one 1 s run, 10
//! interleaved runs each, one thread, load average 1.6–2.3, full Newton 369.0 / 373.7 ms →
//! 360.2 / 366.6 ms (best / median), modified 181.9 / 183.8 → 181.2 / 183.1 ms; the bench's
//! best of 3, 10 runs each: 0.364 / 0.175 s → 0.359 / 0.174 s best, 0.372 / 0.182 →
//! 0.371 / 0.178 s median; callgrind 565.9M → 566.8M (full, `t_end=0.1 repeats=1`),
//! 2160.9M → 2157.4M (modified, 1 s). Targets not met. In the stop test it kept
//! nothing: weighing the multipliers in modified Newton's stop (2.81 iterations, 0.267 factorizations per step)
//! and judging a reused matrix's second correction on its size (2.87 / 0.217) cost the
//! flexible rotor 58 % more iterations and 44 % more factorizations respectively; the
//! unchanged code ran 0.178 s modified, 0.426 s full (one run each, load average ≈ 2),
//! callgrind `-- 100 revolute rho0.9 modified repeats=1` 2160.9M.
//! README "Benchmarks", docs/benchmarks.md, docs/integrators.md.

use samara::analysis::{History, run_analysis};
use samara::model::Model;
use samara::system::System;
use std::path::Path;
use std::time::Instant;

fn main() {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let words: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-') && a.parse::<usize>().is_err())
        .collect();
    let setting = |key: &str| {
        words
            .iter()
            .find_map(|w| w.strip_prefix(key)?.strip_prefix('=')?.parse::<f64>().ok())
    };
    let (t_end, repeats_set) = (setting("t_end"), setting("repeats"));
    let digest = setting("digest").is_some_and(|d| d != 0.0);
    let filters: Vec<&String> = words.iter().filter(|w| !w.contains('=')).collect();
    let wanted = |kind: &str| filters.is_empty() || filters.iter().any(|f| *f == kind);
    let sizes = if args.is_empty() {
        vec![10, 100, 1000]
    } else {
        args
    };
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    println!(
        "{:<10} {:>5} {:>5} {:<8} {:>9} {:>7} {:>9} {:>9} {:>30} {:>11} {:>9}",
        "joints",
        "N",
        "ρ∞",
        "newton",
        "wall [s]",
        "it/step",
        "fact/step",
        "ms/step",
        "tip at 1 s [m]",
        "ΔE/E_ref",
        "max |Φ|"
    );
    let mut growth: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    let kinds: Vec<&str> = ["revolute", "spherical"]
        .into_iter()
        .filter(|k| {
            wanted(k)
                || !filters
                    .iter()
                    .any(|f| *f == "revolute" || *f == "spherical")
        })
        .collect();
    for kind in kinds {
        for &n in &sizes {
            let path = root.join(format!("examples/bench/chain_{kind}_{n}.toml"));
            let loaded = match Model::from_file(&path) {
                Ok(l) => l,
                Err(e) => {
                    eprintln!("skipping {}: {e}", path.display());
                    continue;
                }
            };
            let model = loaded.model;
            let sys = System::new(&model);
            let named = |w: &str, options: &[&str]| {
                !filters.iter().any(|f| options.contains(&f.as_str())) || wanted(w)
            };
            let names: Vec<&str> = model.analyses.iter().map(|d| d.name.as_str()).collect();
            let variants = model
                .analyses
                .iter()
                .flat_map(|d| {
                    let mut d = d.clone();
                    if let (samara::model::AnalysisKind::Dynamic(s), Some(t)) = (&mut d.kind, t_end)
                    {
                        s.t_end = t;
                    }
                    if let samara::model::AnalysisKind::Dynamic(s) = &mut d.kind
                        && filters.iter().any(|f| f.as_str() == "two_parts")
                    {
                        s.partition = samara::model::Partition::TwoParts;
                    }
                    let mut m = d.clone();
                    if let samara::model::AnalysisKind::Dynamic(s) = &mut m.kind {
                        s.jacobian = samara::model::JacobianUpdate::Modified;
                    }
                    [(d, "full"), (m, "modified")]
                })
                .filter(|(d, newton)| {
                    named(&d.name, &names) && named(newton, &["full", "modified"])
                })
                .collect::<Vec<_>>();
            for (def, newton) in variants {
                let def = &def;
                // The machine is shared: small runs are repeated and the fastest is kept.
                let repeats = repeats_set.map_or(if n <= 100 { 3 } else { 1 }, |r| r as usize);
                let mut best = f64::INFINITY;
                let mut kept = None;
                for _ in 0..repeats {
                    let mut hist = History::default();
                    let clock = Instant::now();
                    let s = run_analysis(&sys, def, sys.initial_state(), &mut hist, &mut |_| {})
                        .expect("in-memory recording");
                    best = best.min(clock.elapsed().as_secs_f64());
                    kept = Some((s, hist));
                }
                let (s, hist) = kept.expect("at least one run");
                let wall = best;
                if let Some(f) = &s.failure {
                    println!(
                        "{kind:<10} {n:>5} {:>5} {newton:<8} FAILED: {}",
                        def.name, f.reason
                    );
                    continue;
                }
                let first = &hist.frames[0];
                let last = hist.last().unwrap();
                let e = |f: &samara::analysis::Frame| f.energy.kinetic + f.energy.potential;
                // Reference energy: the potential-energy change of the chain dropping by
                // its own length scale (m g L_link N) — the released energy is of that order.
                let m_link = 7850.0 * 0.1 * 0.01 * 0.01;
                let e_ref = m_link * 9.81 * 0.1 * n as f64 + first.energy.kinetic;
                let drift = (e(last) - e(first)) / e_ref;
                let tip = last.state.nodes[n - 1].x
                    + last.state.nodes[n - 1].r() * nalgebra::Vector3::new(0.05, 0.0, 0.0);
                let rho = def.name.trim_start_matches("rho");
                println!(
                    "{kind:<10} {n:>5} {rho:>5} {newton:<8} {wall:>9.3} {:>7.2} {:>9.3} {:>9.3} {:>30} {drift:>11.3e} {:>9.2e}",
                    s.newton_iterations as f64 / s.steps as f64,
                    s.factorizations as f64 / s.steps as f64,
                    1e3 * wall / s.steps as f64,
                    format!("({:.4}, {:.4}, {:.4})", tip.x, tip.y, tip.z),
                    s.max_constraint_violation
                );
                if digest {
                    println!("  digest {:016x}", state_digest(&hist, &s));
                }
                let key = format!("{kind} ρ∞={rho} {newton} Newton");
                match growth.iter_mut().find(|(k, _)| *k == key) {
                    Some((_, v)) => v.push((n as f64, wall)),
                    None => growth.push((key, vec![(n as f64, wall)])),
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
                "growth of wall time with N, {key}: exponent {:.2}",
                sxy / sxx
            );
        }
    }
}

/// FNV-1a over the bits of every recorded frame's state and the solver counts: equal
/// digests mean results identical to the bit.
fn state_digest(hist: &History, s: &samara::analysis::AnalysisSummary) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |x: u64| {
        for b in x.to_le_bytes() {
            h = (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    };
    eat(s.steps as u64);
    eat(s.newton_iterations as u64);
    eat(s.factorizations as u64);
    for f in &hist.frames {
        let st = &f.state;
        for n in &st.nodes {
            let q = n.rot.wxyz();
            for v in [&n.x, &n.v, &n.w, &n.a, &n.wd] {
                v.iter().for_each(|x| eat(x.to_bits()));
            }
            q.iter().for_each(|x| eat(x.to_bits()));
        }
        for c in &st.coords {
            [c.q, c.v, c.a].iter().for_each(|x| eat(x.to_bits()));
        }
        st.lambda.iter().for_each(|x| eat(x.to_bits()));
    }
    h
}
