//! Issue #16: granular contact sets (`[[granular]]`): the broad phase, the Verlet list with
//! its redo, the pattern that follows the pairs, and a settled pile against statics.
//!
//! References:
//! - the broad phase (uniform grid) must find exactly the pairs of the O(N²) all-pairs
//!   test — same set, compared as sorted lists;
//! - a pair that comes into contact within one step from outside the candidate set is
//!   caught (the step is redone with it): the run matches, to the Newton tolerance, the
//!   same collision modelled with a fixed `[[contacts]]` sphere pair;
//! - a pile at rest in a frictionless box carries its weight on the floor: Σ ground
//!   normal forces = N m g (statics of the whole pile; the sphere–sphere forces are
//!   internal, the walls push horizontally). Tolerance 1e-3 relative: the pile's vertical
//!   momentum changes at Σ m a_z (Newton's law for the pile, checked to 1e-6 M g), and
//!   at the end of the example's 3-s run the pile is nearly at rest (speeds below 1 cm/s:
//!   the stateless sphere–sphere friction lets it creep).
//! - the run is deterministic (the same bits twice).

mod common;
use common::{model, model_file, run};
use samara::elements::GranularSet;
use samara::model::Model;
use samara::system::System;

/// The ground normal forces' sum at the last frame, and the total weight.
fn ground_reaction(m: &Model, sys: &System, state: &samara::system::State) -> (f64, f64) {
    let mut out = vec![0.0; sys.output_names.len()];
    sys.element_outputs(&sys.context(state.time, 1.0), state, &mut out);
    let sum: f64 = sys
        .output_names
        .iter()
        .zip(&out)
        .filter(|(n, _)| n.contains(".ground.") && n.ends_with(".normal_force"))
        .map(|(_, v)| v)
        .sum();
    let weight: f64 = m.bodies.iter().map(|b| b.mass).sum::<f64>() * 9.81;
    (sum, weight)
}

fn same_pairs(set: &GranularSet, nodes: &[samara::system::NodeState]) -> usize {
    let mut n = 0;
    for margin in [0.0, 0.002, 0.01, 0.05] {
        let mut grid = Vec::new();
        set.candidate_pairs(nodes, margin, &mut grid);
        let all = set.all_pairs(nodes, margin);
        assert_eq!(grid, all, "margin {margin}");
        n += all.len();
    }
    n
}

#[test]
fn the_column_settles_with_the_ground_carrying_its_weight_and_the_broad_phase_finds_all_pairs() {
    let m = model_file("examples/contact/granular_column.toml");
    let sys = System::new(&m);
    let set = &sys.granular[0];
    assert_eq!(set.nodes.len(), 27);
    let pairs0 = same_pairs(set, &sys.initial_state().nodes);
    let (s, h) = run(&m);
    let last = h.last().unwrap();
    let pairs1 = same_pairs(set, &last.state.nodes);
    let (reaction, weight) = ground_reaction(&m, &sys, &last.state);
    let vmax = last
        .state
        .nodes
        .iter()
        .map(|n| n.v.norm())
        .fold(0.0, f64::max);
    // The pile's vertical momentum rate Σ m a_z (every sphere 1 kg).
    let pz: f64 = last.state.nodes.iter().map(|n| n.a[2]).sum();
    let balance = reaction - weight - pz;
    println!(
        "{} steps, {} Newton iterations, {} pattern rebuilds, {} redos, ≤ {} candidate pairs; \
         pairs checked {pairs0} (start) {pairs1} (end); {} touching at the end; \
         Σ N_ground = {reaction:.6} N, weight {weight:.6} N (rel. {:.2e}); Σ m a_z = {pz:.3e} N; \
         Σ N − M g − Σ m a_z = {balance:.2e} N; max |v| {vmax:.2e} m/s",
        s.steps,
        s.newton_iterations,
        s.pattern_rebuilds,
        s.contact_redos,
        s.max_candidate_pairs,
        set.contacts(&last.state.nodes),
        (reaction - weight).abs() / weight
    );
    assert!(set.contacts(&last.state.nodes) >= 18, "not a pile");
    // Newton's law for the whole pile, at the converged state (to the Newton tolerance).
    assert!(balance.abs() < 1e-6 * weight, "{balance}");
    // At rest: the floor carries the weight.
    assert!(vmax < 1e-2, "{vmax}");
    assert!((reaction - weight).abs() < 1e-3 * weight);
}

#[test]
fn granular_runs_are_deterministic() {
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../examples/contact/granular_column.toml"),
    )
    .unwrap()
    .replace("t_end = 3.0", "t_end = 0.3");
    let m = model(&text);
    let (_, h1) = run(&m);
    let (_, h2) = run(&m);
    let (a, b) = (
        &h1.last().unwrap().state.nodes,
        &h2.last().unwrap().state.nodes,
    );
    assert!(a.iter().zip(b).all(|(p, q)| p.x == q.x && p.v == q.v));
}

/// Two spheres closing at 6 m/s with a 4 mm gap and a 1 mm margin: with h = 1 ms they
/// overlap by 2 mm after the first step, from outside the candidate set.
fn fast_pair(granular: bool) -> String {
    let contact = if granular {
        r#"
[[granular]]
name = "g"
nodes = ["a", "b"]
radius = 0.1
margin = 0.001
ground_point = [0.0, 0.0, -10.0]
normal = "hunt_crossley"
stiffness = 1e7
restitution = 0.8
impact_velocity = 6.0
"#
    } else {
        r#"
[[contacts]]
name = "g"
node = "a"
shape = "sphere"
radius = 0.1
other_node = "b"
other_radius = 0.1
normal = "hunt_crossley"
stiffness = 1e7
restitution = 0.8
impact_velocity = 6.0
"#
    };
    format!(
        r#"
[model]
name = "fast_pair"
gravity = [0.0, 0.0, 0.0]

[[nodes]]
name = "a"
position = [-0.102, 0.0, 0.0]
velocity = [3.0, 0.0, 0.0]

[[nodes]]
name = "b"
position = [0.102, 0.01, 0.0]
velocity = [-3.0, 0.0, 0.0]

[[bodies]]
name = "a"
node = "a"
mass = 1.0
inertia = [[0.004, 0.0, 0.0], [0.0, 0.004, 0.0], [0.0, 0.0, 0.004]]

[[bodies]]
name = "b"
node = "b"
mass = 1.0
inertia = [[0.004, 0.0, 0.0], [0.0, 0.004, 0.0], [0.0, 0.0, 0.004]]
{contact}
[[analyses]]
name = "collide"
type = "dynamic"
t_end = 0.01
step = 1e-3
rho_inf = 0.9
"#
    )
}

#[test]
fn a_pair_entering_contact_within_a_step_is_caught_and_matches_the_fixed_pair() {
    let (s, h) = run(&model(&fast_pair(true)));
    let (_, r) = run(&model(&fast_pair(false)));
    let (a, b) = (
        &h.last().unwrap().state.nodes,
        &r.last().unwrap().state.nodes,
    );
    let dv = a
        .iter()
        .zip(b)
        .map(|(p, q)| (p.v - q.v).norm())
        .fold(0.0, f64::max);
    println!(
        "redos {}, rebuilds {}, final velocity difference {dv:.2e} m/s; v_b = {:?}",
        s.contact_redos, s.pattern_rebuilds, a[1].v
    );
    assert!(s.contact_redos >= 1, "the step into contact was not redone");
    // The collision happened: B bounced back.
    assert!(a[1].v[0] > 1.0);
    assert!(dv < 1e-6, "{dv}");
}

#[test]
fn bad_granular_sets_are_rejected_where_they_are_written() {
    let base = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../examples/contact/granular_column.toml"),
    )
    .unwrap();
    let cases: &[(&str, &str, &str)] = &[
        (
            "nodes_matching = \"s*\"",
            "nodes = [\"s0\", \"s1\", \"s0\"]",
            "node 's0' is listed twice",
        ),
        (
            "nodes_matching = \"s*\"",
            "nodes = [\"s0\", \"ground\"]",
            "the ground cannot be a sphere of the set",
        ),
        (
            "nodes_matching = \"s*\"",
            "nodes = [\"s0\", \"s99\"]",
            "s99",
        ),
        (
            "nodes_matching = \"s*\"",
            "nodes_matching = \"q*\"",
            "no node matches 'q*'",
        ),
        (
            "radius = 0.05",
            "radius = -0.05",
            "`radius` must be positive",
        ),
        ("radius = 0.05", "radius = 0.0", "`radius` must be positive"),
        (
            "nodes_matching = \"s*\"\nradius = 0.05",
            "nodes = [\"s0\", \"s1\"]\nradii = [0.05]",
            "`radii` has 1 values for 2 spheres",
        ),
        (
            "margin = 0.01 ",
            "margin = 0.0 ",
            "`margin` must be positive",
        ),
        (
            "regularization_velocity = 1e-3 ",
            "",
            "`regularization_velocity` is required with friction",
        ),
        (
            "type = \"dynamic\"",
            "type = \"static\"",
            "needs a dynamic analysis",
        ),
    ];
    for (from, to, expected) in cases {
        assert!(base.contains(from), "{from}");
        let text = base.replacen(from, to, 1);
        let Err(e) = Model::from_toml_str(&text, "bad.toml") else {
            panic!("accepted: {to}")
        };
        let d = e
            .errors()
            .find(|d| d.message.contains(expected))
            .unwrap_or_else(|| panic!("no '{expected}' in {e}"));
        let span = d.span.clone().expect("a located error");
        let (line, col) = e.source.line_col(span.start);
        println!("{line}:{col}: {} (hint: {:?})", d.message, d.hint);
        assert!(d.hint.is_some());
        // At the line written (a missing key: at its table).
        let needle = if to.is_empty() {
            "[[granular]]"
        } else {
            to.lines().last().unwrap().trim_end()
        };
        let want = text[..text.find(needle).unwrap()].matches('\n').count() + 1;
        if !to.is_empty() {
            assert_eq!(line, want, "{}", d.message);
        } else {
            assert!(line >= want, "{}", d.message);
        }
    }
}
