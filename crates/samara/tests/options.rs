//! Issue #10: every solver option changes what it says and nothing else — `penalty`,
//! `linear_solver`, `jacobian = "modified"`, the sparse-LU fallback — options that would
//! otherwise be parsed and ignored are rejected where they are written, and the beams'
//! distributed loads (`[[beams.loads]]`) against the closed form of a loaded cantilever.

mod common;

use common::model;
use nalgebra::Vector3;
use samara::analysis::{AnalysisSummary, History, run_analysis};
use samara::model::Model;
use samara::system::System;

/// Runs the first analysis; unlike `common::run`, a solver failure is returned, not a panic.
fn attempt(text: &str) -> (AnalysisSummary, History) {
    let m = model(text);
    let sys = System::new(&m);
    let mut h = History::default();
    let s = run_analysis(
        &sys,
        &m.analyses[0],
        sys.initial_state(),
        &mut h,
        &mut |_| {},
    )
    .unwrap();
    (s, h)
}

/// Final position of the last node.
fn last_node(h: &History) -> Vector3<f64> {
    h.last().unwrap().state.nodes.last().unwrap().x
}

/// The statics closed form of tests/statics.rs: a mass on a bar pinned at the origin, held
/// by a vertical spring. In statics the mass's node has no stiffness of its own across the
/// bar, so its pivot block in the iteration matrix is singular unless the augmented-
/// Lagrangian penalty (p × the mean stiffness diagonal, on BᵀB) fills it.
const BAR_ON_SPRING: &str = r#"
[model]
name = "bar_on_spring"
gravity = [0.0, 0.0, -9.81]
[[nodes]]
name = "tip"
position = [1.0, 0.0, 0.0]
[[bodies]]
name = "tip"
node = "tip"
mass = 2.0
inertia = [[1e-3, 0.0, 0.0], [0.0, 1e-3, 0.0], [0.0, 0.0, 1e-3]]
[[joints]]
name = "pivot"
type = "revolute"
node_a = "ground"
node_b = "tip"
position = [0.0, 0.0, 0.0]
axis = [0.0, 1.0, 0.0]
[[springs]]
name = "spring"
node_a = "ground"
point_a = [1.0, 0.0, 0.5]
node_b = "tip"
point_b = [1.0, 0.0, 0.0]
stiffness = 60.0
[[analyses]]
name = "sag"
type = "static"
load_steps = 10
tolerance = 1e-12
"#;

/// Statics: `penalty` and `linear_solver`, and the fallback.
/// - default (`auto`, p = 1): the block LU factors every iteration matrix, no fallback;
/// - p = 0, `auto`: every Newton factorization (30 of them) meets the singular pivot block
///   and falls back to the pivoting sparse LU — the summary counts them — with the same
///   answer;
/// - p = 0, `block`: no fallback allowed, so the run stops with "singular";
/// - p = 0, `sparse_lu`: sparse LU from the start (no fallback counted), same answer;
/// - p = 100: no fallback, same answer.
///
/// "Same answer": the node within 1e-11 m of the default run (Newton tolerance 1e-12; the
/// penalty term vanishes with Φ, so only the stopping point moves — measured ≤ 7e-13).
#[test]
fn static_penalty_linear_solver_and_fallback() {
    let with = |extra: &str| attempt(&format!("{BAR_ON_SPRING}{extra}\n"));
    let (s0, h0) = with("");
    assert!(s0.failure.is_none());
    assert_eq!(s0.fallbacks, 0);
    let x0 = last_node(&h0);
    let (s, h) = with("penalty = 0.0");
    println!(
        "p = 0, auto: {} factorizations, {} fallbacks, {} Newton iterations",
        s.factorizations, s.fallbacks, s.newton_iterations
    );
    assert!(s.failure.is_none());
    assert!(s.fallbacks >= s.newton_iterations && s.newton_iterations > 0);
    assert!((last_node(&h) - x0).norm() < 1e-11);
    let (s, _) = with("penalty = 0.0\nlinear_solver = \"block\"");
    let failure = s.failure.expect("the block LU alone cannot pivot");
    assert!(failure.reason.contains("singular"), "{}", failure.reason);
    assert_eq!(s.fallbacks, 0);
    for extra in [
        "penalty = 0.0\nlinear_solver = \"sparse_lu\"",
        "penalty = 100.0",
    ] {
        let (s, h) = with(extra);
        let d = (last_node(&h) - x0).norm();
        println!("{extra}: {} fallbacks, |Δx| = {d:.1e}", s.fallbacks);
        assert!(s.failure.is_none() && s.fallbacks == 0, "{extra}");
        assert!(d < 1e-11, "{extra}: {d:e}");
    }
}

/// A pendulum whose bob is welded to a massless link node: the mechanism has mass enough,
/// but the link's own block of the iteration matrix is empty unless the penalty
/// (p m̄/(βh²) on BᵀB) fills it.
const MASSLESS_LINK: &str = r#"
[model]
name = "massless_link"
gravity = [0.0, 0.0, -9.81]
[[nodes]]
name = "link"
position = [0.5, 0.0, 0.0]
[[nodes]]
name = "bob"
position = [1.0, 0.0, 0.0]
[[bodies]]
name = "bob"
node = "bob"
mass = 1.0
inertia = [[1e-3, 0.0, 0.0], [0.0, 1e-3, 0.0], [0.0, 0.0, 1e-3]]
[[joints]]
name = "pivot"
type = "revolute"
node_a = "ground"
node_b = "link"
position = [0.0, 0.0, 0.0]
axis = [0.0, 1.0, 0.0]
[[joints]]
name = "weld"
type = "fixed"
node_a = "link"
node_b = "bob"
[[analyses]]
name = "swing"
type = "dynamic"
t_end = 0.5
step = 1e-3
rho_inf = 0.9
tolerance = 1e-12
relative_tolerance = 1e-12
"#;

/// Dynamics: with p = 0 every factorization of the 500 steps falls back to the sparse LU
/// (1000 of 1000 Newton iterations); with the default p = 1 or p = 100 none does; the bob's
/// final position is the same within 1e-11 m in all three and with `linear_solver =
/// "sparse_lu"` (Newton tolerance 1e-12; measured ≤ 1e-15).
#[test]
fn dynamic_penalty_fills_the_pivot_of_a_massless_node() {
    let with = |extra: &str| attempt(&format!("{MASSLESS_LINK}{extra}\n"));
    let (s0, h0) = with("");
    assert!(s0.failure.is_none());
    assert_eq!(s0.fallbacks, 0);
    let x0 = last_node(&h0);
    for (extra, fallback) in [
        ("penalty = 0.0", true),
        ("penalty = 100.0", false),
        ("penalty = 0.0\nlinear_solver = \"sparse_lu\"", false),
    ] {
        let (s, h) = with(extra);
        let d = (last_node(&h) - x0).norm();
        println!(
            "{extra}: {} Newton iterations, {} fallbacks, |Δx| = {d:.1e}",
            s.newton_iterations, s.fallbacks
        );
        assert!(s.failure.is_none(), "{extra}");
        if fallback {
            assert!(s.fallbacks >= s.newton_iterations, "{extra}");
        } else {
            assert_eq!(s.fallbacks, 0, "{extra}");
        }
        assert!(d < 1e-11, "{extra}: {d:e}");
    }
}

/// `linear_solver = "block"` and `"sparse_lu"` on the double pendulum (index 3, ρ∞ = 0.9,
/// 1 s): the two factorizations give the same trajectory to round-off (positions within
/// 1e-12 m at every step; measured 3e-15), no fallback.
#[test]
fn block_and_sparse_lu_solve_the_same_steps() {
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../examples/double_pendulum.toml"),
    )
    .unwrap()
    .replace("t_end = 10.0", "t_end = 1.0")
    .replace("rho_inf = 1.0", "rho_inf = 0.9");
    let (sb, hb) = attempt(&format!("{text}linear_solver = \"block\"\n"));
    let (ss, hs) = attempt(&format!("{text}linear_solver = \"sparse_lu\"\n"));
    assert!(sb.failure.is_none() && ss.failure.is_none());
    assert_eq!((sb.fallbacks, ss.fallbacks), (0, 0));
    assert_eq!(hb.frames.len(), hs.frames.len());
    let worst = hb
        .frames
        .iter()
        .zip(&hs.frames)
        .flat_map(|(a, b)| a.state.nodes.iter().zip(&b.state.nodes))
        .map(|(a, b)| (a.x - b.x).norm())
        .fold(0.0, f64::max);
    println!("block vs sparse LU: largest position difference {worst:.1e}");
    assert!(worst < 1e-12, "{worst:e}");
}

/// `jacobian = "modified"` keeps the factorization while Newton contracts: the pendulum
/// over 0.5 s needs 48 factorizations instead of ~1000, and its answer approaches full
/// Newton's as the tolerance tightens — the bob's final position differs by 3.5e-7, 7.8e-9,
/// 2.3e-11 m at tolerance 1e-10, 1e-12, 1e-14 (each stopping point is within the tolerance
/// in configuration, but the accelerations carry δq/(βh²), so the differences accumulate
/// over the 500 steps to 5–20 × N·tolerance). Asserted: ≤ 10 % of the factorizations, a
/// gain of ≥ 10 per two decades of tolerance, and < 1e-7 m at 1e-12.
#[test]
fn modified_newton_converges_to_the_full_newton_answer() {
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/pendulum.toml"),
    )
    .unwrap()
    .replace("t_end = 10.0", "t_end = 0.5");
    let mut diffs = Vec::new();
    for tol in [1e-10, 1e-12, 1e-14] {
        let run = |jacobian: &str| {
            attempt(&format!(
                "{text}tolerance = {tol:e}\nrelative_tolerance = {tol:e}\njacobian = \"{jacobian}\"\n"
            ))
        };
        let (sf, hf) = run("full");
        let (sm, hm) = run("modified");
        assert!(sf.failure.is_none() && sm.failure.is_none());
        let d = (last_node(&hf) - last_node(&hm)).norm();
        println!(
            "tolerance {tol:e}: factorizations {} (full) vs {} (modified), Newton iterations {} vs {}, |Δx| = {d:.2e}",
            sf.factorizations, sm.factorizations, sf.newton_iterations, sm.newton_iterations
        );
        assert!(sm.factorizations * 10 <= sf.factorizations);
        diffs.push(d);
    }
    assert!(diffs[1] < 1e-7, "{diffs:?}");
    assert!(
        diffs[1] < 0.1 * diffs[0] && diffs[2] < 0.1 * diffs[1],
        "{diffs:?}"
    );
}

/// The location (1-based line) of the first error of a model that must be rejected, and
/// its message and hint.
fn first_error(text: &str) -> (usize, String, String) {
    let Err(e) = Model::from_toml_str(text, "bad.toml") else {
        panic!("accepted:\n{text}")
    };
    let d = e.errors().next().expect("an error");
    let span = d.span.clone().expect("a located error");
    let (line, _) = e.source.line_col(span.start);
    (line, d.message.clone(), d.hint.clone().unwrap_or_default())
}

fn line_of(text: &str, needle: &str) -> usize {
    text[..text.find(needle).unwrap()].matches('\n').count() + 1
}

/// `scaling` scales rows and multipliers by βh² — there is no step in a static analysis,
/// and the static solver never read it: it is rejected there, at its line.
#[test]
fn scaling_in_a_static_analysis_is_rejected_where_it_is_written() {
    let text = format!("{BAR_ON_SPRING}scaling = false\n");
    let (line, message, _) = first_error(&text);
    assert_eq!(line, line_of(&text, "scaling = false"));
    assert!(
        message.contains("`scaling` is not used by a static analysis"),
        "{message}"
    );
    // Still accepted (and used) in a dynamic analysis.
    assert!(Model::from_toml_str(&format!("{MASSLESS_LINK}scaling = false\n"), "ok.toml").is_ok());
}

/// The stabilized index-2 formulation enforces Φ = 0 by projection and has no penalty
/// term (the integrator never read `penalty` there): rejected at the key, whether the
/// formulation was chosen explicitly or by ρ∞ = 1; accepted with index 3.
#[test]
fn penalty_with_the_stabilized_formulation_is_rejected_where_it_is_written() {
    let cases = [
        (
            MASSLESS_LINK.replace("rho_inf = 0.9", "rho_inf = 1.0"),
            "rho_inf = 1 selects stabilized_index2",
        ),
        (
            format!("{MASSLESS_LINK}formulation = \"stabilized_index2\"\n"),
            "remove `penalty`",
        ),
    ];
    for (base, hint) in cases {
        let text = format!("{base}penalty = 2.0\n");
        let (line, message, h) = first_error(&text);
        assert_eq!(line, line_of(&text, "penalty = 2.0"), "{message}");
        assert!(
            message.contains("`penalty` is not used by the stabilized_index2 formulation"),
            "{message}"
        );
        assert!(h.contains(hint), "{h}");
    }
    assert!(
        Model::from_toml_str(
            &format!("{MASSLESS_LINK}formulation = \"index3\"\npenalty = 2.0\n"),
            "ok.toml"
        )
        .is_ok()
    );
}

/// Issue #15: every key of `[[aero_lines]]` changes the aerodynamic loads. A two-station
/// rotor blade on a spinning node (BEM inflow) and a wing on a beam; each variant replaces
/// one piece of text and must change the loads on the nodes.
#[test]
fn every_aero_line_option_changes_the_loads() {
    use samara::core::{ElementInput, EvalContext, LocalTerms, Need};
    use samara::model::components::{Build, build_all, initial_nodes};
    let dir = tempfile::tempdir().unwrap();
    let mut csv = String::from("alpha,cl,cd,cm\n");
    let mut csv2 = csv.clone();
    for d in -180..=180 {
        let a = (d as f64).to_radians();
        csv += &format!(
            "{d},{},{},{}\n",
            std::f64::consts::PI * (2.0 * a).sin(),
            0.01 + a.sin().powi(2),
            -0.1 * a.sin()
        );
        csv2 += &format!(
            "{d},{},{},{}\n",
            0.9 * std::f64::consts::PI * (2.0 * a).sin(),
            0.02 + a.sin().powi(2),
            -0.1 * a.sin()
        );
    }
    std::fs::write(dir.path().join("a.csv"), csv).unwrap();
    std::fs::write(dir.path().join("b.csv"), csv2).unwrap();
    let base = r#"[model]
name = "aero_options"
[[nodes]]
name = "hub"
position = [0.0, 0.0, 0.0]
angular_velocity = [2.0, 0.0, 0.0]
[[bodies]]
name = "hub"
node = "hub"
mass = 1.0
inertia = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
[[aero_lines]]
name = "blade"
node = "hub"
root = [0.0, 0.0, 0.5]
tip = [0.0, 0.0, 5.0]
chord_direction = [0.0, 1.0, 0.0]
normal_direction = [1.0, 0.0, 0.0]
pitch = 0.02
air_density = 1.2
wind = { speed = 8.0, direction = [1.0, 0.0, 0.0], shear_exponent = 0.2, reference_height = 3.0, vertical = [0.0, 0.0, 1.0], function = { type = "ramp", start = 0.0, end = 1.0, from = 0.8, to = 1.0 } }
inflow = { type = "bem", centre = [0.0, 0.0, 0.0], axis = [1.0, 0.0, 0.0], blades = 3, hub_radius = 0.5, tip_radius = 5.0, tip_loss = true, hub_loss = true, tangential_induction = true }
[[aero_lines.stations]]
span = 1.0
chord = 0.6
twist = 0.2
airfoil = "a.csv"
ac_offset = 0.05
[[aero_lines.stations]]
span = 4.2
chord = 0.3
twist = 0.05
airfoil = "a.csv"
ac_offset = 0.0
[[analyses]]
name = "spin"
type = "dynamic"
t_end = 0.01
step = 0.01
"#;
    let loads = |text: &str| -> Vec<f64> {
        let m = Model::from_toml_str(text, dir.path().join("m.toml"))
            .unwrap_or_else(|e| panic!("{}", e.render_plain()))
            .model;
        let initial = initial_nodes(&m);
        let mut parts = Build::new(&initial);
        build_all(&m, &mut parts);
        let ctx = EvalContext {
            time: 0.0,
            gravity: Vector3::zeros(),
            load_factor: 1.0,
        };
        let mut total = vec![0.0; 6];
        for e in parts
            .elements
            .iter()
            .filter(|e| e.name().starts_with("blade."))
        {
            let mut out = LocalTerms::for_element(e.as_ref());
            e.evaluate(
                &ctx,
                &ElementInput::nodes(&initial),
                Need::Residual,
                &mut out,
            );
            for (k, t) in total.iter_mut().enumerate() {
                *t += out.r[k];
            }
        }
        total
    };
    let reference = loads(base);
    assert!(reference.iter().any(|x| x.abs() > 1.0), "{reference:?}");
    let variants = [
        ("root = [0.0, 0.0, 0.5]", "root = [0.0, 0.0, 0.3]"),
        ("tip = [0.0, 0.0, 5.0]", "tip = [0.0, 0.0, 5.5]"),
        (
            "chord_direction = [0.0, 1.0, 0.0]",
            "chord_direction = [0.2, 1.0, 0.0]",
        ),
        (
            "normal_direction = [1.0, 0.0, 0.0]",
            "normal_direction = [-1.0, 0.0, 0.0]",
        ),
        ("pitch = 0.02", "pitch = 0.1"),
        ("air_density = 1.2", "air_density = 1.0"),
        ("speed = 8.0", "speed = 9.0"),
        (
            "direction = [1.0, 0.0, 0.0], shear",
            "direction = [1.0, 0.3, 0.0], shear",
        ),
        ("shear_exponent = 0.2", "shear_exponent = 0.1"),
        ("reference_height = 3.0", "reference_height = 4.0"),
        ("vertical = [0.0, 0.0, 1.0]", "vertical = [0.0, 0.2, 1.0]"),
        ("from = 0.8", "from = 0.7"),
        (
            "type = \"bem\", centre = [0.0, 0.0, 0.0]",
            "type = \"bem\", centre = [0.0, 0.0, 0.2]",
        ),
        (
            "axis = [1.0, 0.0, 0.0], blades",
            "axis = [1.0, 0.1, 0.0], blades",
        ),
        ("blades = 3", "blades = 2"),
        ("hub_radius = 0.5", "hub_radius = 0.4"),
        ("tip_radius = 5.0", "tip_radius = 5.2"),
        ("tip_loss = true", "tip_loss = false"),
        ("hub_loss = true", "hub_loss = false"),
        (
            "tangential_induction = true",
            "tangential_induction = false",
        ),
        ("span = 4.2", "span = 4.0"),
        ("chord = 0.6", "chord = 0.7"),
        ("twist = 0.2", "twist = 0.25"),
        ("airfoil = \"a.csv\"", "airfoil = \"b.csv\""),
        ("ac_offset = 0.05", "ac_offset = 0.1"),
    ];
    for (from, to) in variants {
        assert!(base.contains(from), "{from}");
        let v = loads(&base.replacen(from, to, 1));
        let diff: f64 = v.iter().zip(&reference).map(|(a, b)| (a - b).abs()).sum();
        assert!(diff > 1e-6, "`{to}` changed nothing");
    }
    // Inflow models: none and uniform differ from BEM and from each other.
    let inflow_line = base.lines().find(|l| l.starts_with("inflow")).unwrap();
    let none = loads(&base.replacen(inflow_line, "inflow = { type = \"none\" }", 1));
    let uniform = loads(&base.replacen(
        inflow_line,
        "inflow = { type = \"uniform\", velocity = [-2.0, 0.0, 0.0] }",
        1,
    ));
    assert!(none != reference && uniform != reference && none != uniform);
    // `beam` (instead of `node`) and `aerodyn` (instead of `stations`): tests/aerodynamics.rs
    // (the cantilever wing, the NREL 5-MW rotor).
}

/// `integrator` (issue #17): each choice changes the answer (the schemes differ at O(h²))
/// and `rho_inf` changes the energy-decaying scheme's dissipation; the preserving scheme
/// keeps the pendulum's energy to the Newton tolerance where generalized-α at ρ∞ = 0.9
/// loses some (docs/integrators.md; the verification is tests/energy_schemes.rs).
#[test]
fn integrator_and_its_rho_inf_change_the_answer() {
    let pendulum = |analysis: &str| {
        format!(
            r#"
[model]
name = "p"
gravity = [0.0, 0.0, -9.81]
[[nodes]]
name = "bob"
position = [1.0, 0.0, 0.0]
[[bodies]]
name = "bob"
node = "bob"
mass = 1.0
inertia = [[1e-3, 0.0, 0.0], [0.0, 1e-3, 0.0], [0.0, 0.0, 1e-3]]
[[joints]]
name = "pivot"
type = "revolute"
node_a = "ground"
node_b = "bob"
position = [0.0, 0.0, 0.0]
axis = [0.0, 1.0, 0.0]
[[analyses]]
name = "swing"
type = "dynamic"
t_end = 2.0
step = 0.01
tolerance = 1e-12
relative_tolerance = 1e-14
{analysis}
"#
        )
    };
    let energy = |h: &History| {
        let e = |f: &samara::analysis::Frame| f.energy.kinetic + f.energy.potential;
        (e(h.last().unwrap()) - e(&h.frames[0])).abs()
    };
    let (_, ga) = attempt(&pendulum("rho_inf = 0.9"));
    let (_, ep) = attempt(&pendulum("integrator = \"energy_preserving\""));
    let (_, ed) = attempt(&pendulum("integrator = \"energy_decaying\"\nrho_inf = 0.5"));
    let (_, ed1) = attempt(&pendulum("integrator = \"energy_decaying\"\nrho_inf = 1.0"));
    let x = |h: &History| last_node(h);
    assert!((x(&ga) - x(&ep)).norm() > 1e-6);
    assert!((x(&ep) - x(&ed)).norm() > 1e-6);
    // ρ∞ = 1 is the preserving scheme.
    assert!((x(&ep) - x(&ed1)).norm() < 1e-10);
    let (e_ga, e_ep, e_ed) = (energy(&ga), energy(&ep), energy(&ed));
    eprintln!(
        "|ΔE| over 2 s: generalized-α {e_ga:.2e}, preserving {e_ep:.2e}, decaying {e_ed:.2e}"
    );
    assert!(
        e_ep < 1e-10 && e_ga > 1e-6 && e_ed > 1e-4,
        "{e_ga} {e_ep} {e_ed}"
    );
}
