//! Issue #17: `partition = "two_parts"`. The Newton iteration is shared out in two parts
//! and a separator (one level of nested dissection): results bit-identical with one thread
//! and with two (the partner thread), and the same solution as one part to the Newton
//! tolerance (another elimination order and summation order: round-off only). Covered: a
//! chain (full and modified Newton), the chain with signals between its parts, the chain in
//! the stabilized index-2 form, a beam large enough for the windowed element loop, the
//! passive joint angles each part updates as the steps are accepted, and each part's check
//! of its own constraints at the end of an iteration.

use crate::common;

use common::{run_with_threads, state_bits, summary_with_threads};
use samara::model::{AnalysisKind, JacobianUpdate, Model, Partition};
use samara::system::{State, System};

/// An `n`-link chain of steel bars on revolute joints released from rest (the chain
/// benchmark's links, examples/bench/make_chains.py), 50 steps of 1 ms.
fn chain(n: usize, partition: &str) -> String {
    let mut s = String::from("[model]\nname = \"chain\"\ngravity = [0.0, 0.0, -9.81]\n");
    s += &bars(n, "[0.0, 1.0, 0.0]", |_| String::new());
    s += &format!(
        "[[analyses]]\nname = \"drop\"\ntype = \"dynamic\"\nt_end = 0.05\nstep = 1e-3\n\
         rho_inf = 0.9\n{partition}"
    );
    s
}

/// The chain's `n` bars (0.1 m, 78.5 g) along x, each pinned to the one before (the first
/// to the ground) by a revolute joint about `axis`; `node(i)` adds lines to node i.
fn bars(n: usize, axis: &str, node: impl Fn(usize) -> String) -> String {
    let mut s = String::new();
    for i in 0..n {
        s += &format!(
            "[[nodes]]\nname = \"link{i}\"\nposition = [{x}, 0.0, 0.0]\n{extra}\
             [[bodies]]\nname = \"link{i}\"\nnode = \"link{i}\"\nmass = 0.0785\n\
             inertia = [[1.3083333333333334e-06, 0.0, 0.0], [0.0, 6.607083333333335e-05, 0.0], \
             [0.0, 0.0, 6.607083333333335e-05]]\n",
            x = 0.05 + 0.1 * i as f64,
            extra = node(i)
        );
    }
    for i in 0..n {
        let a = if i == 0 {
            "ground".to_string()
        } else {
            format!("link{}", i - 1)
        };
        s += &format!(
            "[[joints]]\nname = \"pin{i}\"\ntype = \"revolute\"\nnode_a = \"{a}\"\n\
             node_b = \"link{i}\"\nposition = [{x}, 0.0, 0.0]\naxis = {axis}\n",
            x = 0.1 * i as f64
        );
    }
    s
}

fn with_jacobian(mut m: Model, j: JacobianUpdate) -> Model {
    if let AnalysisKind::Dynamic(d) = &mut m.analyses[0].kind {
        d.jacobian = j;
    }
    m
}

/// The option is read, and only dynamic generalized-α analyses take it.
#[test]
fn partition_is_read_and_checked() {
    let m = common::model(&chain(4, "partition = \"two_parts\"\n"));
    let AnalysisKind::Dynamic(d) = &m.analyses[0].kind else {
        panic!("a dynamic analysis");
    };
    assert_eq!(d.partition, Partition::TwoParts);
    let bad = chain(4, "partition = \"three\"\n");
    let e = Model::from_toml_str(&bad, "bad.toml").expect_err("an unknown partition");
    assert!(
        format!("{e}").contains("expected one of: none, two_parts"),
        "{e}"
    );
    let stat = chain(4, "").replace(
        "type = \"dynamic\"\nt_end = 0.05\nstep = 1e-3\nrho_inf = 0.9\n",
        "type = \"static\"\npartition = \"two_parts\"\n",
    );
    let e = Model::from_toml_str(&stat, "static.toml").expect_err("a static analysis");
    assert!(format!("{e}").contains("partition"), "{e}");
    for other in [
        "type = \"modal\"\nn_modes = 4\n",
        "type = \"dynamic\"\nt_end = 0.05\nstep = 1e-3\nintegrator = \"energy_preserving\"\n",
    ] {
        let text = chain(4, "").replace(
            "type = \"dynamic\"\nt_end = 0.05\nstep = 1e-3\nrho_inf = 0.9\n",
            &format!("{other}partition = \"two_parts\"\n"),
        );
        let e = Model::from_toml_str(&text, "other.toml").expect_err(other);
        assert!(format!("{e}").contains("partition"), "{other}: {e}");
    }
}

/// Two threads give the bits of one, full and modified Newton; the solution is that of one
/// part to well within the Newton tolerance (relative 1e-6 on the increments: the
/// positions after 50 steps agree to 1e-9 m, the multipliers to 1e-6 of the largest).
#[test]
fn two_parts_match_one_thread_to_the_bit_and_one_part_to_the_tolerance() {
    for jacobian in [JacobianUpdate::Full, JacobianUpdate::Modified] {
        let two = with_jacobian(
            common::model(&chain(40, "partition = \"two_parts\"\n")),
            jacobian,
        );
        let one = with_jacobian(common::model(&chain(40, "")), jacobian);
        compare(&format!("{jacobian:?}"), &two, &one, 0, 1e-9);
    }
}

/// Runs analysis `k` of `two` (two parts) with one and two threads and `one` (one part):
/// the two-part runs agree to the bit, report their parts and partner thread, and agree
/// with the one-part run to `dx` in the positions and 1e-6 of the largest multiplier.
fn compare(label: &str, two: &Model, one: &Model, k: usize, dx: f64) -> State {
    let sys2 = System::new(two);
    let sys1 = System::new(one);
    let a = summary_with_threads(two, &sys2, k, 1);
    let b = summary_with_threads(two, &sys2, k, 2);
    for (s, threads) in [(&a, 1), (&b, 2)] {
        let p = s
            .parts
            .unwrap_or_else(|| panic!("{label}: no two parts: {:?}", s.warnings));
        assert!(
            p.blocks[0] > 0 && p.blocks[1] > 0 && p.blocks[2] > 0,
            "{p:?}"
        );
        assert_eq!(p.partner_thread, threads == 2, "{label}: {threads} threads");
        assert!(s.warnings.is_empty(), "{label}: {:?}", s.warnings);
    }
    let (a, b) = (a.final_state, b.final_state);
    assert_eq!(
        state_bits(&a),
        state_bits(&b),
        "{label}: one and two threads differ"
    );
    let c = run_with_threads(one, &sys1, k, 1);
    assert_ne!(
        state_bits(&a),
        state_bits(&c),
        "{label}: the two-part order was not taken"
    );
    let d = position_difference(&a, &c);
    assert!(d < dx, "{label}: positions differ by {d:e} m");
    // The joint coordinates (the chain's passive hinge angles, updated on each part's
    // thread when a step is accepted): round-off of the other order, as the positions.
    assert_eq!(a.coords.len(), c.coords.len());
    let dq = a
        .coords
        .iter()
        .zip(&c.coords)
        .map(|(p, q)| (p.q - q.q).abs());
    let dq = dq.fold(0.0, f64::max);
    assert!(dq < 1e-8, "{label}: joint coordinates differ by {dq:e} rad");
    let lmax = c.lambda.iter().fold(0.0f64, |m, l| m.max(l.abs()));
    let dl = a
        .lambda
        .iter()
        .zip(&c.lambda)
        .map(|(p, q)| (p - q).abs())
        .fold(0.0, f64::max);
    assert!(
        dl < 1e-6 * lmax,
        "{label}: multipliers differ by {dl:e} of {lmax:e}"
    );
    a
}

/// The largest distance between the nodes' positions of two states.
fn position_difference(a: &State, c: &State) -> f64 {
    let pairs = a.nodes.iter().zip(&c.nodes);
    pairs.map(|(p, q)| (p.x - q.x).norm()).fold(0.0, f64::max)
}

/// Sensors (filtered, with a state, and unfiltered) on the chain's links driving joint
/// torques: signals read in their own part, and from one part into the other (link 2's
/// velocity drives joint 37: that item goes to the separator).
#[test]
fn two_parts_carry_signals_between_elements() {
    let mut extra = String::new();
    for (sensor, link, tau) in [("s5", 5, true), ("s2", 2, true), ("s30", 30, false)] {
        let filter = if tau { "time_constant = 0.01\n" } else { "" };
        extra += &format!(
            "[[sensors]]\nname = \"{sensor}\"\nnode = \"link{link}\"\nquantity = \"velocity\"\n\
             component = \"z\"\ngain = -0.02\n{filter}"
        );
    }
    let with = |partition: &str| {
        let mut s = chain(40, partition);
        for (sensor, joint) in [("s5", 5), ("s2", 37), ("s30", 30)] {
            let head = format!("name = \"pin{joint}\"\ntype = \"revolute\"\n");
            let end = s.find(&head).expect("the joint") + head.len();
            let next = s[end..].find("[[").map_or(s.len(), |i| end + i);
            s.insert_str(next, &format!("[joints.theta3]\ninput = \"{sensor}\"\n"));
        }
        s.insert_str(s.find("[[analyses]]").expect("an analysis"), &extra);
        s
    };
    let two = common::model(&with("partition = \"two_parts\"\n"));
    let one = common::model(&with(""));
    let a = compare("signals", &two, &one, 0, 1e-9);
    assert_eq!(a.states.len(), 2, "the two filtered sensors' states");
}

/// The stabilized index-2 form (its projection rows and their couplings) in two parts.
#[test]
fn two_parts_take_the_stabilized_index2_form() {
    let form = "formulation = \"stabilized_index2\"\n";
    let two = common::model(&chain(40, &format!("partition = \"two_parts\"\n{form}")));
    let one = common::model(&chain(40, form));
    compare("index-2", &two, &one, 0, 1e-9);
}

/// A beam of `PARALLEL_MIN_ELEMENTS` elements or more: two parts replace the windowed
/// parallel element loop (the 300-element cantilever of the parallel-assembly tests, 10
/// steps; its tip moves ~1e-4 m, round-off ~1e-15 m).
#[test]
fn two_parts_take_a_windowed_beam() {
    let text = crate::parallel_assembly::CANTILEVER;
    let at = text.rfind("rho_inf = 0.9\n").expect("the dynamic analysis") + 14;
    let mut two = text.to_string();
    two.insert_str(at, "partition = \"two_parts\"\n");
    compare("beam", &common::model(&two), &common::model(text), 1, 1e-12);
}

/// Where the plan cannot be made the run keeps one part and says why: granular contact
/// sets (their candidate pairs change the pattern during the run).
#[test]
fn two_parts_refused_with_a_warning_for_granular_sets() {
    let mut m = common::model(&crate::granular::fast_pair(true));
    let AnalysisKind::Dynamic(d) = &mut m.analyses[0].kind else {
        panic!("a dynamic analysis");
    };
    d.partition = Partition::TwoParts;
    let sys = System::new(&m);
    let s = summary_with_threads(&m, &sys, 0, 2);
    assert!(s.parts.is_none());
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("granular") && w.contains("one part")),
        "{:?}",
        s.warnings
    );
}

/// Every example with a generalized-α dynamic analysis (20 steps of it) in two parts: the
/// rotors (a hovering rotor with dynamic inflow, the flexible NREL 5-MW rotor), the landing
/// gear (tire, hydraulics, contact), the wing, mechanisms, control loops. Where a plan is
/// made, one and two threads give the same bits, and the positions agree with one part to
/// round-off (1e-10 of the model's size: its largest |x|, at least 1 m) and the element
/// states to 1e-9 relative; a separator not small against the parts (the rotors') is
/// warned about; where no plan is made (no separator, a granular set), a warning says why.
#[test]
fn every_example_runs_in_two_parts() {
    use samara::model::IntegratorType;
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
    let mut files = Vec::new();
    crate::examples::model_files(&root, &mut files);
    files.retain(|f| !f.starts_with(root.join("bench")));
    files.sort();
    let mut planned = Vec::new();
    for f in &files {
        let one = {
            let Ok(l) = Model::from_file(f) else {
                continue; // a model for another command (checked in tests/examples.rs)
            };
            l.model
        };
        let Some(k) = one.analyses.iter().position(|a| {
            matches!(&a.kind, AnalysisKind::Dynamic(d)
                if d.integrator == IntegratorType::GeneralizedAlpha)
        }) else {
            continue;
        };
        let name = f.strip_prefix(&root).unwrap().display().to_string();
        let mut one = one;
        if let AnalysisKind::Dynamic(d) = &mut one.analyses[k].kind {
            d.t_end = d.t_start + 20.0 * d.step;
        }
        let mut two = one.clone();
        if let AnalysisKind::Dynamic(d) = &mut two.analyses[k].kind {
            d.partition = Partition::TwoParts;
        }
        let sys = System::new(&one);
        let a = summary_with_threads(&two, &sys, k, 2);
        let Some(parts) = a.parts else {
            assert!(
                a.warnings.iter().any(|w| w.contains("not taken")),
                "{name}: neither two parts nor a warning: {:?}",
                a.warnings
            );
            continue;
        };
        assert!(parts.partner_thread, "{name}");
        let [p0, p1, sep] = parts.blocks;
        assert_eq!(
            a.warnings
                .iter()
                .any(|w| w.contains("not small against the parts")),
            4 * sep > p0.min(p1),
            "{name}: {parts:?} {:?}",
            a.warnings
        );
        let b = run_with_threads(&two, &sys, k, 1);
        let c = run_with_threads(&one, &sys, k, 1);
        let a = a.final_state;
        assert_eq!(
            state_bits(&a),
            state_bits(&b),
            "{name}: one and two threads differ"
        );
        let size = c.nodes.iter().fold(1.0f64, |m, n| m.max(n.x.amax()));
        let dx = position_difference(&a, &c);
        assert!(dx < 1e-10 * size, "{name}: positions differ by {dx:e} m");
        let dz = a
            .states
            .iter()
            .zip(&c.states)
            .map(|(p, q)| (p.z - q.z).abs() / (1.0 + q.z.abs()))
            .fold(0.0, f64::max);
        assert!(dz < 1e-9, "{name}: element states differ by {dz:e}");
        planned.push(name);
    }
    for must in [
        "rotor/hover_rotor.toml",
        "rotor/nrel5mw_flexible.toml",
        "landing_gear_drop.toml",
        "aero/wing.toml",
        "control/servo_follower.toml",
    ] {
        assert!(
            planned.iter().any(|p| p == must),
            "{must} not in two parts: {planned:?}"
        );
    }
}

/// Wheels on a free axle (revolute joints about x, no gravity), spinning at ±10 rad/s in
/// turn: each hinge's passive angle grows at the closed-form rate ω_b − ω_a (steady spin
/// about a principal axis; the Lie-group update is exact for it), 0.5 s = 1.6 turns of
/// each relative hinge. The angles count turns only if they are updated every step (the
/// principal value is continued from the last one), and the run writes its only output
/// at the end: each part must update its own joints' angles as the steps are accepted.
/// Tolerance 1e-9 rad: round-off and the Newton tolerance over 500 steps.
#[test]
fn two_parts_count_the_passive_angles_turns_in_both_parts() {
    let n = 24;
    let omega = |i: usize| if i.is_multiple_of(2) { 10.0 } else { -10.0 };
    let mut s = String::from("[model]\nname = \"axle\"\ngravity = [0.0, 0.0, 0.0]\n");
    s += &bars(n, "[1.0, 0.0, 0.0]", |i| {
        format!("angular_velocity = [{}, 0.0, 0.0]\n", omega(i))
    });
    s += "[[analyses]]\nname = \"spin\"\ntype = \"dynamic\"\nt_end = 0.5\nstep = 1e-3\n\
          rho_inf = 0.9\noutput_every = 1000\npartition = \"two_parts\"\n";
    let m = Model::from_toml_str(&s, "axle.toml").unwrap().model;
    let sys = System::new(&m);
    for threads in [1, 2] {
        let r = summary_with_threads(&m, &sys, 0, threads);
        let p = r.parts.expect("two parts");
        assert_eq!(p.partner_thread, threads == 2);
        let q = &r.final_state.coords;
        assert_eq!(q.len(), n, "one passive angle per hinge");
        for (i, c) in q.iter().enumerate() {
            let before = if i == 0 { 0.0 } else { omega(i - 1) };
            let want = (omega(i) - before) * 0.5;
            assert!(
                (c.q - want).abs() < 1e-9,
                "{threads} threads: hinge {i}: {} rad, want {want} rad",
                c.q
            );
        }
    }
}

/// Each part evaluates its own constraints in the constraint check that ends a Newton
/// iteration (on the part's thread, into its rows of Φ). With steps of 10 ms and a loose
/// relative tolerance on the corrections (5e-2) it is that check (`max |Φ| ≤ tolerance`,
/// 1e-11 m) which ends many iterations: the two-part run must take the one-part run's
/// iterations (116; with part 1's constraints left out of the check, 99) and report its
/// largest violation to 1e-15 m (round-off of the 4 m chain's coordinates), with one
/// thread and with two.
#[test]
fn two_parts_check_the_constraints_of_both_parts() {
    let run = |partition: &str, threads: usize| {
        let settings = format!("{partition}tolerance = 1e-11\nrelative_tolerance = 5e-2\n");
        let s =
            chain(40, &settings).replace("t_end = 0.05\nstep = 1e-3", "t_end = 0.4\nstep = 1e-2");
        let m = common::model(&s);
        summary_with_threads(&m, &System::new(&m), 0, threads)
    };
    let one = run("", 1);
    assert!(
        one.max_constraint_violation > 1e-12,
        "the check must matter"
    );
    for threads in [1, 2] {
        let two = run("partition = \"two_parts\"\n", threads);
        assert!(two.parts.is_some(), "two parts");
        assert_eq!(
            two.newton_iterations, one.newton_iterations,
            "{threads} threads"
        );
        let (a, b) = (two.max_constraint_violation, one.max_constraint_violation);
        assert!(
            (a - b).abs() <= 1e-15,
            "{threads} threads: {a:e} m, one part {b:e} m"
        );
    }
}
