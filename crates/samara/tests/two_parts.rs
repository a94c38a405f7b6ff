//! Issue #17: `partition = "two_parts"`. The Newton iteration of a chain is shared out in
//! two parts and a separator (one level of nested dissection): results bit-identical with
//! one thread and with two (the partner thread), and the same solution as one part to the
//! Newton tolerance (another elimination order and summation order: round-off only).

use crate::common;

use common::{run_with_threads, state_bits};
use samara::model::{AnalysisKind, JacobianUpdate, Model, Partition};
use samara::system::System;

/// An `n`-link chain of steel bars on revolute joints released from rest (the chain
/// benchmark's links, examples/bench/make_chains.py), 50 steps of 1 ms.
fn chain(n: usize, partition: &str) -> String {
    let mut s = String::from("[model]\nname = \"chain\"\ngravity = [0.0, 0.0, -9.81]\n");
    for i in 0..n {
        s += &format!(
            "[[nodes]]\nname = \"link{i}\"\nposition = [{x}, 0.0, 0.0]\n\
             [[bodies]]\nname = \"link{i}\"\nnode = \"link{i}\"\nmass = 0.0785\n\
             inertia = [[1.3083333333333334e-06, 0.0, 0.0], [0.0, 6.607083333333335e-05, 0.0], \
             [0.0, 0.0, 6.607083333333335e-05]]\n",
            x = 0.05 + 0.1 * i as f64
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
             node_b = \"link{i}\"\nposition = [{x}, 0.0, 0.0]\naxis = [0.0, 1.0, 0.0]\n",
            x = 0.1 * i as f64
        );
    }
    s += &format!(
        "[[analyses]]\nname = \"drop\"\ntype = \"dynamic\"\nt_end = 0.05\nstep = 1e-3\n\
         rho_inf = 0.9\n{partition}"
    );
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
        let sys2 = System::new(&two);
        let sys1 = System::new(&one);
        let a = run_with_threads(&two, &sys2, 0, 1);
        let b = run_with_threads(&two, &sys2, 0, 2);
        assert_eq!(
            state_bits(&a),
            state_bits(&b),
            "{jacobian:?}: one and two threads differ"
        );
        let c = run_with_threads(&one, &sys1, 0, 1);
        assert_ne!(
            state_bits(&a),
            state_bits(&c),
            "{jacobian:?}: the two-part order was not taken"
        );
        let dx = a
            .nodes
            .iter()
            .zip(&c.nodes)
            .map(|(p, q)| (p.x - q.x).norm())
            .fold(0.0, f64::max);
        assert!(dx < 1e-9, "{jacobian:?}: positions differ by {dx:e} m");
        let lmax = c.lambda.iter().fold(0.0f64, |m, l| m.max(l.abs()));
        let dl = a
            .lambda
            .iter()
            .zip(&c.lambda)
            .map(|(p, q)| (p - q).abs())
            .fold(0.0, f64::max);
        assert!(
            dl < 1e-6 * lmax,
            "{jacobian:?}: multipliers differ by {dl:e} of {lmax:e}"
        );
    }
}
