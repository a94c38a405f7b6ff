//! Granular column benchmark (issue #16): N spheres (radius 5 cm, 1 kg) stacked in a
//! frictionless box 0.54 m wide, in alternating square layers — 5 × 5 at a pitch of
//! 10.5 cm, then 4 × 4 in the hollows of the layer below (a body-centred stacking, each
//! sphere of a hollow layer resting on four: stable, unlike a simple-cubic stack) — each
//! layer 2 mm above its seat (deterministic horizontal offsets of ±0.5 mm), the last layer
//! filled in part; released under gravity, the column settles onto the ground with the
//! contact laws of examples/contact/granular_column.toml ([[granular]]: Hunt–Crossley,
//! LuGre on the ground and between spheres, rolling and twisting resistance, margin 1 cm).
//!
//! `cargo bench -p samara --bench granular [-- T] [N…] [regularized] [lattice] [symbolic]`
//! (`symbolic`: no simulation, only the block LU's size for each column's initial candidate
//! pairs: factor values and Schur updates per sphere) runs each
//! column until the largest speed of a sphere falls below 1e-3 m/s (checked every 25 ms
//! of simulated time; at most T = 3 s simulated, h = 1 ms; N = 125 250 500 1000 by
//! default; `regularized`: the stateless sphere–sphere friction, v_r = 1 mm/s, instead of
//! the bristles; `lattice`: the former simple-cubic start, 2 mm apart, that collapses)
//! and prints per N the simulated time to rest, steps (rejected: Newton failures),
//! Newton iterations per step, CPU and wall time per step (CPU from /proc/self/stat: the
//! machine may be shared), candidate and touching pairs, pattern rebuilds, the largest
//! speed at the end and the time of the broad phase alone (grid against all pairs); then
//! the growth exponents d log(time)/d log N (`nobroad`: without the broad phase alone on
//! larger columns, for profiles; `GRANULAR_PROGRESS=1` prints each chunk to stderr).

use samara::analysis::{History, run_analysis};
use samara::elements::{GranularSet, NormalLaw};
use samara::model::{AnalysisKind, Model};
use samara::solve::BlockLuSymbolic;
use samara::system::{Assembler, Formulation, NodeState, System};
use std::time::Instant;

/// Largest speed of a sphere at rest [m/s].
const AT_REST: f64 = 1e-3;
/// Simulated time between the checks of the largest speed [s].
const CHUNK: f64 = 0.025;

/// The spheres' centres: alternating 5 × 5 and 4 × 4 square layers (body-centred), each
/// 2 mm above its seat, or (`lattice`) the simple-cubic 5 × 5 stack 2 mm apart.
pub fn centres(n: usize, lattice: bool) -> Vec<[f64; 3]> {
    let (r, pitch, gap) = (0.05, 0.105, 0.002);
    let off = |i: usize, k: usize, size: f64| {
        let x = ((12.9898 * i as f64 + 78.233 * k as f64).sin() * 43758.5453).fract();
        (x.abs() - 0.5) * size
    };
    let mut out = Vec::with_capacity(n);
    if lattice {
        for k in 0..n {
            let (lx, ly, lz) = (k % 5, (k / 5) % 5, k / 25);
            out.push([
                (lx as f64 - 2.0) * pitch + off(k, 1, 0.004),
                (ly as f64 - 2.0) * pitch + off(k, 2, 0.004),
                r + gap + lz as f64 * (2.0 * r + gap),
            ]);
        }
        return out;
    }
    // A sphere of a hollow layer touches its four seats at the horizontal distance
    // pitch/√2: the layers are dz = √((2r + gap)² − pitch²/2) apart.
    let dz = ((2.0 * r + gap).powi(2) - 0.5 * pitch * pitch).sqrt();
    let mut layer = 0;
    while out.len() < n {
        let (m, shift) = if layer % 2 == 0 { (5, 2.0) } else { (4, 1.5) };
        for k in 0..m * m {
            if out.len() == n {
                break;
            }
            let i = out.len();
            out.push([
                ((k % m) as f64 - shift) * pitch + off(i, 1, 0.001),
                ((k / m) as f64 - shift) * pitch + off(i, 2, 0.001),
                r + gap + layer as f64 * dz,
            ]);
        }
        layer += 1;
    }
    out
}

/// The model text of a column of `n` spheres, simulated for `t_end`.
pub fn column(n: usize, t_end: f64, regularized: bool, lattice: bool) -> String {
    let r = 0.05;
    let inertia = 0.4 * r * r;
    let mut s =
        String::from("[model]\nname = \"granular_column\"\ngravity = [0.0, 0.0, -9.81]\n\n");
    for (k, [x, y, z]) in centres(n, lattice).into_iter().enumerate() {
        s += &format!("[[nodes]]\nname = \"s{k}\"\nposition = [{x}, {y}, {z}]\n\n");
    }
    for k in 0..n {
        s += &format!(
            "[[bodies]]\nname = \"s{k}\"\nnode = \"s{k}\"\nmass = 1.0\ninertia = [[{inertia}, 0.0, 0.0], [0.0, {inertia}, 0.0], [0.0, 0.0, {inertia}]]\n\n"
        );
    }
    let regularization = if regularized {
        "regularization_velocity = 1e-3"
    } else {
        ""
    };
    s += &format!(
        r#"[[granular]]
name = "pile"
nodes_matching = "s*"
radius = {r}
margin = 0.01
walls = [
  {{ point = [0.27, 0.0, 0.0], normal = [-1.0, 0.0, 0.0] }},
  {{ point = [-0.27, 0.0, 0.0], normal = [1.0, 0.0, 0.0] }},
  {{ point = [0.0, 0.27, 0.0], normal = [0.0, -1.0, 0.0] }},
  {{ point = [0.0, -0.27, 0.0], normal = [0.0, 1.0, 0.0] }},
]
normal = "hunt_crossley"
stiffness = 1e6
restitution = 0.3
impact_velocity = 1.0
static_friction = 0.5
dynamic_friction = 0.4
stribeck_velocity = 0.01
bristle_stiffness = 1e4
bristle_damping = 60.0
rolling_friction = 0.05
twisting_friction = 0.3
{regularization}

[[analyses]]
name = "settle"
type = "dynamic"
t_end = {t_end}
step = 1e-3
rho_inf = 0.6
output_every = 1000000
"#
    );
    s
}

/// CPU time of this process [s] (user + system, from /proc/self/stat; 0 where absent).
fn cpu_time() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return 0.0;
    };
    // Fields after the command name's closing parenthesis: utime is the 12th, stime the 13th.
    let rest = &stat[stat.rfind(')').map_or(0, |i| i + 2)..];
    let f: Vec<f64> = rest
        .split_whitespace()
        .skip(11)
        .take(2)
        .filter_map(|x| x.parse().ok())
        .collect();
    f.iter().sum::<f64>() / 100.0
}

fn main() {
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let regularized = std::env::args().any(|a| a == "regularized");
    let lattice = std::env::args().any(|a| a == "lattice");
    let t_max = args.first().copied().unwrap_or(3.0);
    let sizes: Vec<usize> = if args.len() > 1 {
        args[1..].iter().map(|&x| x as usize).collect()
    } else {
        vec![125, 250, 500, 1000]
    };
    if std::env::args().any(|a| a == "symbolic") {
        symbolic_only(&sizes, regularized, lattice);
        return;
    }
    let mut rows = Vec::new();
    for &n in &sizes {
        let mut text = column(n, CHUNK, regularized, lattice);
        // Experiments: GRANULAR_EDIT="from=>to;from=>to" edits the model text.
        if let Ok(edits) = std::env::var("GRANULAR_EDIT") {
            for e in edits.split(';').filter(|e| !e.is_empty()) {
                let (from, to) = e.split_once("=>").expect("from=>to");
                assert!(text.contains(from), "{from}");
                text = text.replace(from, to);
            }
        }
        let mut m = Model::from_toml_str(&text, "column.toml").unwrap().model;
        let sys = System::new(&m);
        let mut state = sys.initial_state();
        let (mut steps, mut rejected, mut iterations, mut redos, mut rebuilds, mut most) =
            (0, 0, 0, 0, 0, 0);
        let (mut vmax, mut t) = (f64::INFINITY, 0.0);
        let cpu0 = cpu_time();
        let clock = Instant::now();
        // Chunks of CHUNK simulated seconds, each from the state the last one reached,
        // until the largest speed is below AT_REST (or t_max).
        while vmax >= AT_REST && t < t_max - 1e-9 {
            if let AnalysisKind::Dynamic(d) = &mut m.analyses[0].kind {
                d.t_start = t;
                d.t_end = t + CHUNK;
            }
            let mut h = History::default();
            let s = run_analysis(&sys, &m.analyses[0], state, &mut h, &mut |_| {}).unwrap();
            assert!(s.failure.is_none(), "{:?}", s.failure);
            steps += s.steps;
            rejected += s.rejected_steps;
            iterations += s.newton_iterations;
            redos += s.contact_redos;
            rebuilds += s.pattern_rebuilds;
            most = most.max(s.max_candidate_pairs);
            state = s.final_state;
            t = state.time;
            vmax = state.nodes.iter().map(|x| x.v.norm()).fold(0.0, f64::max);
            if std::env::var_os("GRANULAR_PROGRESS").is_some() {
                eprintln!(
                    "N = {n}: t = {t:.3} s, max speed {vmax:.2e} m/s, {steps} steps ({rejected} rejected), {:.2} it./step, {:.1} s CPU",
                    iterations as f64 / steps as f64,
                    cpu_time() - cpu0
                );
            }
        }
        let wall = clock.elapsed().as_secs_f64();
        let cpu = cpu_time() - cpu0;
        let set = &sys.granular[0];
        let last = &state.nodes;
        // The broad phase alone, at the final state: grid against all pairs.
        let mut pairs = Vec::new();
        let clock = Instant::now();
        let reps = 20;
        for _ in 0..reps {
            set.candidate_pairs(last, set.margin, &mut pairs);
        }
        let grid = clock.elapsed().as_secs_f64() / reps as f64;
        let clock = Instant::now();
        let all = set.all_pairs(last, set.margin);
        let brute = clock.elapsed().as_secs_f64();
        assert_eq!(all, pairs);
        let per_step = cpu / steps as f64;
        // The block LU's size for the final candidate pairs: the Schur updates (6 × 6
        // block products, most of them) one factorization makes.
        let elements = pairs.iter().map(|&(i, j)| set.pair(i, j)).collect();
        let asm = Assembler::with_pairs(&sys, Formulation::Index3, elements);
        let lu = BlockLuSymbolic::new(asm.structure()).unwrap();
        println!(
            "N = {n:5}: block LU of the final pattern: {} blocks, {} factor values, {} Schur updates ({:.0} per sphere)",
            asm.structure().n_blocks(),
            lu.n_factor_values(),
            lu.n_updates(),
            lu.n_updates() as f64 / n as f64
        );
        if std::env::var_os("GRANULAR_FASTEST").is_some() {
            let mut order: Vec<usize> = (0..last.len()).collect();
            order.sort_by(|&a, &b| last[b].v.norm().total_cmp(&last[a].v.norm()));
            for &k in order.iter().take(5) {
                println!(
                    "  sphere {k}: x = {:.4?}, v = {:.3e}, ω = {:.3e}",
                    last[k].x.as_slice(),
                    last[k].v.norm(),
                    (last[k].r() * last[k].w).norm()
                );
            }
        }
        let rest = if vmax < AT_REST {
            format!("at rest (max speed < {AT_REST:.0e} m/s) at t = {t:.3} s")
        } else {
            format!("NOT at rest at t = {t:.3} s")
        };
        println!(
            "N = {n:5}: {rest}, {:.1} s CPU, {:.3} ms CPU/step, {:.3} ms wall/step ({steps} steps, {rejected} rejected, {:.2} Newton it./step, {redos} redos), max speed at the end {vmax:.2e} m/s, {} candidate pairs (max {most}), {} touching, {rebuilds} pattern rebuilds; broad phase {:.3} ms (all pairs {:.3} ms)",
            cpu,
            1e3 * per_step,
            1e3 * wall / steps as f64,
            iterations as f64 / steps as f64,
            pairs.len(),
            set.contacts(last),
            1e3 * grid,
            1e3 * brute
        );
        rows.push((n as f64, per_step, grid, brute));
    }
    for w in rows.windows(2) {
        let (a, b) = (w[0], w[1]);
        let e = |x: f64, y: f64| (y / x).ln() / (b.0 / a.0).ln();
        println!(
            "N {} → {}: growth exponent CPU time/step {:.2}, broad phase {:.2}, all pairs {:.2}",
            a.0,
            b.0,
            e(a.1, b.1),
            e(a.2, b.2),
            e(a.3, b.3)
        );
    }
    if std::env::args().any(|a| a == "nobroad") {
        return;
    }
    // The broad phase alone on larger columns (5 × 5 spheres per layer, the same lattice,
    // no simulation): grid against all pairs.
    let mut broad = Vec::new();
    for n in [1000usize, 4000, 16000, 64000] {
        let nodes: Vec<NodeState> = (0..n)
            .map(|k| {
                let off = |i: usize, c: usize| {
                    ((12.9898 * i as f64 + 78.233 * c as f64).sin() * 43758.5453).fract() * 0.004
                };
                NodeState {
                    x: nalgebra::Vector3::new(
                        (k % 5) as f64 * 0.105 + off(k, 1),
                        ((k / 5) % 5) as f64 * 0.105 + off(k, 2),
                        (k / 25) as f64 * 0.105,
                    ),
                    ..NodeState::default()
                }
            })
            .collect();
        let set = GranularSet {
            name: "column".into(),
            nodes: (0..n).collect(),
            radii: vec![0.05; n],
            law: NormalLaw::Linear {
                stiffness: 1.0,
                damping: 0.0,
            },
            friction: None,
            margin: 0.01,
            rolling: None,
        };
        let mut pairs = Vec::new();
        let reps = (64000 / n).max(1);
        let clock = Instant::now();
        for _ in 0..reps {
            set.candidate_pairs(&nodes, set.margin, &mut pairs);
        }
        let grid = clock.elapsed().as_secs_f64() / reps as f64;
        let brute = if n <= 16000 {
            let clock = Instant::now();
            let all = set.all_pairs(&nodes, set.margin);
            let t = clock.elapsed().as_secs_f64();
            assert_eq!(all, pairs);
            t
        } else {
            f64::NAN
        };
        println!(
            "broad phase, N = {n:6}: {} pairs, grid {:.3} ms ({:.3} µs per sphere), all pairs {:.3} ms",
            pairs.len(),
            1e3 * grid,
            1e6 * grid / n as f64,
            1e3 * brute
        );
        broad.push((n as f64, grid, brute));
    }
    for w in broad.windows(2) {
        let e = |x: f64, y: f64| (y / x).ln() / (w[1].0 / w[0].0).ln();
        println!(
            "broad phase N {} → {}: growth exponent grid {:.2}, all pairs {:.2}",
            w[0].0,
            w[1].0,
            e(w[0].1, w[1].1),
            e(w[0].2, w[1].2)
        );
    }
}

/// `symbolic`: no simulation; the block LU of each column's initial candidate pairs (the
/// seats 2 mm away and the neighbours in a layer, within the 1 cm margin): blocks, factor
/// values and Schur updates, per sphere, and the time of the symbolic factorization.
fn symbolic_only(sizes: &[usize], regularized: bool, lattice: bool) {
    for &n in sizes {
        let m = Model::from_toml_str(&column(n, CHUNK, regularized, lattice), "column.toml")
            .unwrap()
            .model;
        let sys = System::new(&m);
        let state = sys.initial_state();
        let set = &sys.granular[0];
        let mut pairs = Vec::new();
        set.candidate_pairs(&state.nodes, set.margin, &mut pairs);
        let elements = pairs.iter().map(|&(i, j)| set.pair(i, j)).collect();
        let asm = Assembler::with_pairs(&sys, Formulation::Index3, elements);
        let clock = Instant::now();
        let lu = BlockLuSymbolic::new(asm.structure()).unwrap();
        let t = clock.elapsed().as_secs_f64();
        println!(
            "N = {n:5}: {} pairs, {} factor values ({:.0} per sphere), {} Schur updates ({:.0} per sphere), symbolic {:.2} ms",
            pairs.len(),
            lu.n_factor_values(),
            lu.n_factor_values() as f64 / n as f64,
            lu.n_updates(),
            lu.n_updates() as f64 / n as f64,
            1e3 * t
        );
    }
}
