//! Cross-sectional analysis benchmark (issue #12): the airfoil section of
//! `examples/sections/airfoil.section.toml` refined to about 20,000 8-node elements (target:
//! under 2 s to mesh and solve), and a 50-station blade of those sections at the
//! example's resolution, solved one by one and in parallel.
//!
//! `cargo bench -p samara --bench section [-- ELEMENTS_AROUND]` prints element, node and
//! unknown counts, the wall time of meshing and of the solve (best of 3), and the blade
//! times.

use samara::section::{analyze, analyze_all, input};
use std::path::Path;
use std::time::Instant;

fn main() {
    let around: usize = std::env::args()
        .skip(1)
        .find_map(|a| a.parse().ok())
        .unwrap_or(3000);
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/sections");
    let path = dir.join("airfoil.section.toml");
    let base = std::fs::read_to_string(&path).expect("the example airfoil");
    let text = base.replace(
        "elements_around = 160",
        &format!("elements_around = {around}\nelements_per_ply = 2"),
    );
    let mut best_mesh = f64::INFINITY;
    let mut best_solve = f64::INFINITY;
    let mut summary = String::new();
    for _ in 0..3 {
        let t0 = Instant::now();
        let loaded = input::from_str(&text, &path).expect("valid section");
        let t1 = Instant::now();
        let r = analyze(&loaded.model).expect("solves");
        let t2 = Instant::now();
        best_mesh = best_mesh.min((t1 - t0).as_secs_f64());
        best_solve = best_solve.min((t2 - t1).as_secs_f64());
        let m = &loaded.model.mesh;
        summary = format!(
            "airfoil, {} elements around: {} elements, {} nodes, {} unknowns; EA {:.6e} N, GJ {:.6e} N m²",
            around,
            m.elements.len(),
            m.nodes.len(),
            3 * m.nodes.len() + 6,
            r.properties.axial,
            r.properties.torsion
        );
    }
    println!("{summary}");
    println!(
        "  mesh {best_mesh:.3} s, solve {best_solve:.3} s, total {:.3} s (best of 3)",
        best_mesh + best_solve
    );
    // A 50-station blade: the example section at 50 chords.
    let models: Vec<_> = (0..50)
        .map(|k| {
            let chord = 2.5 - 1.8 * k as f64 / 49.0;
            let t = base.replace("chord = 1.5", &format!("chord = {chord}"));
            input::from_str(&t, &path).expect("valid section").model
        })
        .collect();
    let n_el: usize = models.iter().map(|m| m.mesh.elements.len()).sum();
    let t0 = Instant::now();
    for m in &models {
        analyze(m).expect("solves");
    }
    let serial = t0.elapsed().as_secs_f64();
    let t0 = Instant::now();
    let all = analyze_all(&models);
    let parallel = t0.elapsed().as_secs_f64();
    assert!(all.iter().all(|r| r.is_ok()));
    println!(
        "blade of 50 stations ({n_el} elements): one by one {serial:.3} s, in parallel {parallel:.3} s ({} threads, speed-up {:.2})",
        rayon::current_num_threads(),
        serial / parallel
    );
}
