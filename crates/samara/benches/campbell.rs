//! Campbell benchmark (issue #14): a sweep of a 4-blade hingeless rotor over 50 speed
//! points, with 1 and 2 threads (the points run in parallel on a rayon pool of that size;
//! the results are the same, checked here bit for bit).
//!
//! The rotor: four copies of the NREL 5-MW blade of
//! `examples/rotor/hingeless_blade_campbell.toml` (4 elements of order 8 each, 792
//! unknowns), clamped at the hub radius 90° apart; speeds 0 … 2 rad/s, 8 modes.
//!
//! `cargo bench -p samara --bench campbell [-- POINTS]` prints the wall time per sweep for
//! each pool size and the speed-up.

use samara::analysis::{History, run_analysis};
use samara::model::Model;
use samara::system::System;
use std::path::Path;
use std::time::Instant;

fn main() {
    let points: usize = std::env::args()
        .skip(1)
        .find_map(|a| a.parse().ok())
        .unwrap_or(50);
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/rotor/hingeless_blade_campbell.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let start = text.find("[[beams]]").unwrap();
    let end = text.find("[[analyses]]").unwrap();
    let blade = text[start..end]
        .replace("elements = 16", "elements = 4")
        .replace(
            "[[joints]]\nname = \"hub\"",
            "[[joints]]\nname = \"hub_BLADE\"",
        );
    let mut model = String::from("[model]\nname = \"rotor4\"\n\n");
    for k in 0..4 {
        let (c, s) = [(1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0)][k];
        model += &blade
            .replace("name = \"blade\"", &format!("name = \"blade{k}\""))
            .replace(
                "points = [[1.5, 0.0, 0.0], [63.0, 0.0, 0.0]]",
                &format!(
                    "points = [[{}, {}, 0.0], [{}, {}, 0.0]]",
                    1.5 * c,
                    1.5 * s,
                    63.0 * c,
                    63.0 * s
                ),
            )
            .replace("root = \"root\"", &format!("root = \"root{k}\""))
            .replace("tip = \"tip\"", &format!("tip = \"tip{k}\""))
            .replace("node_b = \"root\"", &format!("node_b = \"root{k}\""))
            .replace("hub_BLADE", &format!("hub{k}"));
    }
    model += &format!(
        "[[analyses]]\nname = \"campbell\"\ntype = \"campbell\"\nrotation = {{ axis = [0.0, 0.0, 1.0] }}\nspeeds = {{ start = 0.0, end = 2.0, count = {points} }}\nn_modes = 8\n"
    );
    let m = Model::from_toml_str(&model, &path)
        .unwrap_or_else(|e| panic!("{e}"))
        .model;
    let sys = System::new(&m);
    let sweep = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let t0 = Instant::now();
            let mut h = History::default();
            let s = run_analysis(
                &sys,
                &m.analyses[0],
                sys.initial_state(),
                &mut h,
                &mut |_| {},
            )
            .unwrap();
            assert!(s.failure.is_none(), "{:?}", s.failure);
            let f = h
                .arrays
                .iter()
                .find(|a| a.0.name == "campbell_frequency")
                .unwrap()
                .1
                .clone();
            (t0.elapsed().as_secs_f64(), f)
        })
    };
    println!(
        "4-blade rotor, {} unknowns, {points} speed points, 8 modes",
        sys.n_config()
    );
    let (t1, f1) = sweep(1);
    let (t2, f2) = sweep(2);
    assert_eq!(f1, f2, "the sweep depends on the number of threads");
    println!(
        "1 thread : {t1:.3} s ({:.1} ms per point)",
        t1 * 1e3 / points as f64
    );
    println!(
        "2 threads: {t2:.3} s ({:.1} ms per point)",
        t2 * 1e3 / points as f64
    );
    println!("speed-up : {:.2}", t1 / t2);
}
