//! Modal benchmark (issue #14): the steel cantilever of `examples/bench/cantilever_N.toml`
//! (N two-node elements, 6(N + 1) unknowns plus the clamp), linearized about its initial
//! state and solved for its lowest modes: N = 10 (sparse shift-invert, and the dense QZ
//! path for comparison) and N = 100, first 6 modes; N = 10000, first 20 modes (sparse).
//! (The dense path on N = 100, a 1212 × 1212 pencil, took 101 s: it is for small models.)
//!
//! `cargo bench -p samara --bench modal [-- N…]` prints the times of the linearization and
//! of the eigensolution and the first frequency against Euler–Bernoulli (the two-node
//! elements are not converged: the difference is their discretization error).

use samara::linear::eigen::{EigenMethod, EigenOptions};
use samara::linear::{linearize, modes};
use samara::model::Model;
use samara::system::System;
use std::f64::consts::PI;
use std::path::Path;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    let cases: Vec<String> = if args.is_empty() {
        vec!["10".into(), "100".into(), "10000".into()]
    } else {
        args
    };
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    // EB first bending frequency of the bench beam: L = 1, E = 210 GPa, I = 8.333e-10,
    // ρA = 7850 × 1e-4.
    let f1 = 1.875_104_068_711_961f64.powi(2)
        * (210e9 * 8.333_333_333_333_334e-10 / 0.785f64).sqrt()
        / (2.0 * PI);
    println!(
        "{:<8} {:>7} {:>6} {:<7} {:>12} {:>10} {:>10} {:>12}",
        "model", "unknown", "modes", "solver", "linearize", "eigen", "total", "f1 [Hz]"
    );
    for case in &cases {
        let path = root.join(format!("examples/bench/cantilever_{case}.toml"));
        let Ok(loaded) = Model::from_file(&path) else {
            eprintln!("skipping {}", path.display());
            continue;
        };
        let n_modes = if case == "10000" { 20 } else { 6 };
        let methods: &[EigenMethod] = if case == "10" {
            &[EigenMethod::Sparse, EigenMethod::Dense]
        } else {
            &[EigenMethod::Sparse]
        };
        for &method in methods {
            let sys = System::new(&loaded.model);
            let state = sys.initial_state();
            let t0 = Instant::now();
            let lin = linearize(&sys, &state, None);
            let t1 = Instant::now();
            let s = modes(
                &lin,
                &EigenOptions {
                    n_modes,
                    shift: None,
                    method,
                },
            )
            .expect("modes");
            let t2 = Instant::now();
            println!(
                "{:<8} {:>7} {:>6} {:<7} {:>10.1}ms {:>8.1}ms {:>8.1}ms {:>12.6} (EB {f1:.6})",
                case,
                lin.n,
                n_modes,
                format!("{method:?}"),
                (t1 - t0).as_secs_f64() * 1e3,
                (t2 - t1).as_secs_f64() * 1e3,
                (t2 - t0).as_secs_f64() * 1e3,
                s.modes[0].frequency()
            );
        }
    }
}
