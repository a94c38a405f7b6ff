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
//!   at the end of the example's 3-s run the pile is at rest (speeds below 1 mm/s: the
//!   pairs stick, and rolling and twisting resistance stop the spheres' rolling and
//!   spinning, which point contacts alone would not).
//! - the set's pair friction sticks and slides as Coulomb's law says, and its bristle
//!   follows the pair through rebuilds of the candidate list (closed forms below).
//! - the run is deterministic (the same bits twice).

use crate::common;
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
    let fastest = last
        .state
        .nodes
        .iter()
        .max_by(|a, b| a.v.norm().total_cmp(&b.v.norm()))
        .unwrap();
    println!(
        "fastest sphere: x = {:?}, |v| = {:.2e} m/s, |ω| = {:.2e} rad/s",
        fastest.x.as_slice(),
        fastest.v.norm(),
        fastest.w.norm()
    );
    // Slip speeds of the touching pairs and of the spheres on the floor.
    let x = samara::core::ElementInput::nodes(&last.state.nodes);
    let ctx = sys.context(last.time, 1.0);
    let mut touching = Vec::new();
    set.candidate_pairs(&last.state.nodes, 0.0, &mut touching);
    let mut pair_slip: f64 = 0.0;
    for &(i, j) in &touching {
        let z = last
            .state
            .pair_bristles
            .iter()
            .find(|b| b.key == (0, i, j))
            .map_or(nalgebra::Vector3::zeros(), |b| b.z);
        let mut p = set.pair(i, j);
        p.set_bristle(z, 0.0);
        let mut out = [0.0; 4];
        samara::core::Element::outputs(&p, &ctx, &x, &mut out);
        pair_slip = pair_slip.max(out[3]);
    }
    let mut out = vec![0.0; sys.output_names.len()];
    sys.element_outputs(&ctx, &last.state, &mut out);
    let floor_slip = sys
        .output_names
        .iter()
        .zip(&out)
        .filter(|(n, _)| n.contains(".ground.") && n.ends_with(".slip_velocity"))
        .map(|(_, v)| *v)
        .fold(0.0, f64::max);
    println!(
        "largest slip speed: touching pairs {pair_slip:.2e} m/s, on the floor {floor_slip:.2e} m/s"
    );
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
    assert!(vmax < 1e-3, "{vmax}");
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
pub fn fast_pair(granular: bool) -> String {
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
            "bristle_damping = 60.0",
            "bristle_damping = 60.0\nregularization_velocity = -1e-3",
            "`regularization_velocity` must be positive",
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

/// B (m = 2 kg, ρ = 0.1 m, rotation held by a huge inertia so that it cannot roll) pressed
/// by m g onto A (ρ_A = 1000 m, clamped) and pulled sideways by `force`, in one granular
/// set with LuGre pair friction (μ_s = 0.5, μ_d = 0.3, Stribeck speed `stribeck`,
/// σ₀ = 1e5 /m, σ₁ = 200 s/m: the tangential bristle oscillator m, σ₀ m g is about
/// critically damped).
/// A third sphere C flies past B at 4 m/s, 6 mm apart (within the 1-cm margin, never
/// touching): the candidate list and the pattern are rebuilt while B is held.
fn set_pair(force: f64, stribeck: f64, t_end: f64) -> String {
    let (m, g) = (2.0, 9.81);
    format!(
        r#"
[model]
name = "set_pair"
gravity = [0.0, 0.0, 0.0]

[[nodes]]
name = "a"
position = [0.0, 0.0, -1000.0]

[[nodes]]
name = "b"
position = [0.0, 0.0, {zb}]

[[nodes]]
name = "c"
position = [-0.6, 0.205, 0.12]
velocity = [4.0, 0.0, 0.0]

[[bodies]]
name = "a"
node = "a"
mass = 100.0
inertia = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]

[[bodies]]
name = "b"
node = "b"
mass = {m}
inertia = [[1e6, 0.0, 0.0], [0.0, 1e6, 0.0], [0.0, 0.0, 1e6]]

[[bodies]]
name = "c"
node = "c"
mass = 1.0
inertia = [[0.004, 0.0, 0.0], [0.0, 0.004, 0.0], [0.0, 0.0, 0.004]]

[[joints]]
name = "clamp"
type = "fixed"
node_a = "ground"
node_b = "a"

[[forces]]
name = "pull"
node = "b"
force = [{force}, 0.0, {press}]

[[granular]]
name = "g"
nodes = ["a", "b", "c"]
radii = [1000.0, 0.1, 0.1]
margin = 0.01
ground_point = [0.0, 0.0, -10000.0]
normal = "linear"
stiffness = 1e7
damping = 2e3
static_friction = 0.5
dynamic_friction = 0.3
stribeck_velocity = {stribeck}
bristle_stiffness = 1e5
bristle_damping = 200.0

[[analyses]]
name = "pull"
type = "dynamic"
t_end = {t_end}
step = 5e-4
rho_inf = 0.6
"#,
        zb = 0.1 - m * g / 1e7,
        press = -m * g,
    )
}

/// The bristle deflection of the pair (A, B) in a frame (zero when it has none).
fn bristle_ab(state: &samara::system::State) -> nalgebra::Vector3<f64> {
    state
        .pair_bristles
        .iter()
        .find(|b| b.key == (0, 0, 1))
        .map_or(nalgebra::Vector3::zeros(), |b| b.z)
}

/// Issue #16: the sphere–sphere friction of a granular set sticks. Closed forms
/// (Coulomb friction on a block that cannot roll, N = m g):
/// - F = 0.8 μ_s N < μ_s N, applied at t = 0 (v_s = 0.1 m/s: the load's transient slip,
///   ≈ F/(m ω) = 4 mm/s, keeps g(s) within 3e-4 of μ_s — with a Stribeck speed below the
///   transient LuGre breaks away under a sudden load, as it should): B sticks. At rest the
///   bristle carries the load,
///   σ₀ N |z| = F (the LuGre law at w = 0; tolerance 1e-6 relative, the Newton tolerance
///   on a 4-µm deflection), B's speed decays with the tangential oscillator
///   (ω = √(σ₀ g) ≈ 990 rad/s, about critically damped: e^(−ωt) < 1e-40 after 0.1 s;
///   tolerance 1e-7 m/s, far below the ≈ 8e-4 m/s creep the stateless law gives here),
///   and B does not move while C passes and the pairs are rebuilt (|Δx_B| < 1e-7 m, ten
///   Newton tolerances (1e-8 m), against the 4-µm jump a bristle reset to zero would
///   cause).
/// - F = 1.5 μ_s N > μ_s N (v_s = 1 mm/s): B slides with a = (F − μ_d N)/m (the bristle
///   settles at
///   g(s)/σ₀ with g(s) = μ_d to e^(−(s/v_s)²) < 1e-40 once s > 1 cm/s); tolerance 1e-4
///   relative on a from the velocity change over the second half (A's curvature under
///   the 5-mm slide changes N by < 1e-5).
#[test]
fn set_pairs_stick_below_the_static_limit_and_slide_with_coulomb_friction_above_it() {
    let (m, g, ms, md, s0) = (2.0, 9.81, 0.5, 0.3, 1e5);
    let n = m * g;
    // Stick, with C passing.
    let f = 0.8 * ms * n;
    let (s, h) = run(&model(&set_pair(f, 0.1, 0.3)));
    assert!(s.failure.is_none(), "{:?}", s.failure);
    let last = h.last().unwrap();
    let z = bristle_ab(&last.state);
    let vb = last.state.nodes[1].v.norm();
    // Before C comes near (t = 0.1 s: C 0.2 m away) and at the end.
    let before = h.frames.iter().find(|fr| fr.time >= 0.1 - 1e-9).unwrap();
    let dx = (last.state.nodes[1].x - before.state.nodes[1].x).norm();
    let c_passed = last.state.nodes[2].x[0] > 0.5;
    println!(
        "stick: σ₀ N |z| = {:.9} N vs F = {f:.9} N ({:.2e}); |v_B| = {vb:.2e} m/s; Δx_B during C's pass {dx:.2e} m; {} pattern rebuilds, {} steps rejected",
        s0 * n * z.norm(),
        (s0 * n * z.norm() - f).abs() / f,
        s.pattern_rebuilds,
        s.rejected_steps
    );
    assert!(c_passed);
    assert!(s.pattern_rebuilds >= 2, "C never became a candidate");
    assert!((s0 * n * z.norm() - f).abs() < 1e-6 * f);
    assert!(z[0] > 0.0, "the bristle holds B against the pull");
    assert!(vb < 1e-7, "{vb}");
    assert!(dx < 1e-7, "{dx}");
    // Every frame: the pair (A, B) keeps its deflection through the rebuilds (no reset),
    // and the pairs apart (C with A or B) carry none.
    for fr in h.frames.iter().filter(|fr| fr.time >= 0.1) {
        assert!((bristle_ab(&fr.state) - z).norm() < 1e-6 * z.norm());
        for b in &fr.state.pair_bristles {
            if b.key != (0, 0, 1) {
                assert_eq!(b.z, nalgebra::Vector3::zeros(), "{:?}", b.key);
            }
        }
    }
    // Slide.
    let f = 1.5 * ms * n;
    let (s, h) = run(&model(&set_pair(f, 1e-3, 0.05)));
    assert!(s.failure.is_none(), "{:?}", s.failure);
    let k = h.frames.len() / 2;
    let (f0, f1) = (&h.frames[k], h.last().unwrap());
    let a = (f1.state.nodes[1].v[0] - f0.state.nodes[1].v[0]) / (f1.time - f0.time);
    let a_ref = (f - md * n) / m;
    println!(
        "slide: a = {a:.6} vs (F − μ_d N)/m = {a_ref:.6} m/s² ({:.2e})",
        (a - a_ref).abs() / a_ref
    );
    assert!((a - a_ref).abs() < 1e-4 * a_ref);
}

/// The bristles follow the pairs through a new candidate list: a pair kept keeps its
/// deflection, a new pair starts at zero, a pair dropped is forgotten.
#[test]
fn pair_bristles_follow_their_pairs_when_the_list_changes() {
    use nalgebra::Vector3;
    use samara::core::{PairBristle, remap_bristles};
    let old = vec![
        PairBristle {
            key: (0, 1, 2),
            z: Vector3::new(1.0, 0.0, 0.0),
        },
        PairBristle {
            key: (0, 1, 5),
            z: Vector3::new(0.0, 2.0, 0.0),
        },
        PairBristle {
            key: (1, 0, 1),
            z: Vector3::new(0.0, 0.0, 3.0),
        },
    ];
    let new = remap_bristles(&old, &[(0, 0, 1), (0, 1, 5), (0, 2, 3), (1, 0, 1)]);
    let got: Vec<_> = new.iter().map(|b| (b.key, b.z)).collect();
    assert_eq!(
        got,
        vec![
            ((0, 0, 1), Vector3::zeros()),
            ((0, 1, 5), Vector3::new(0.0, 2.0, 0.0)),
            ((0, 2, 3), Vector3::zeros()),
            ((1, 0, 1), Vector3::new(0.0, 0.0, 3.0)),
        ]
    );
}
