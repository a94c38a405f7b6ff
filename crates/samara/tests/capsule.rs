//! Issue #16: capsule contact (`shape = "capsule"`), through
//! examples/contact/capsule_rest.toml.
//!
//! Reference: statics of a rigid rod on two supports — the lever rule. With the centre of
//! mass at distances a = 0.3 m and b = 0.5 m from the ends, N_a = m g b/(a + b) and
//! N_b = m g a/(a + b). The contact is damped (ζ ≈ 0.2 at ω ≈ 300 rad/s), so after 1 s
//! the transient is below e^{−60}: tolerance 1e-8 relative. A tilted capsule touches with
//! its lower end only.

use crate::common;
use common::{model, model_file, run};
use samara::elements::EvalContext;
use samara::model::Model;
use samara::system::System;

fn loads(m: &Model) -> (f64, f64, f64) {
    let (_, h) = run(m);
    let sys = System::new(m);
    let last = h.last().unwrap();
    let mut out = vec![0.0; sys.output_names.len()];
    let ctx = EvalContext {
        time: last.time,
        gravity: m.gravity,
        load_factor: 1.0,
    };
    sys.element_outputs(&ctx, &last.state, &mut out);
    let get = |n: &str| out[sys.output_names.iter().position(|o| o == n).unwrap()];
    (
        get("rest.end_a.normal_force"),
        get("rest.end_b.normal_force"),
        last.state.nodes[0].w.norm(),
    )
}

#[test]
fn a_capsule_rests_on_its_ends_with_the_lever_rule_loads() {
    let m = model_file("examples/contact/capsule_rest.toml");
    let (na, nb, w) = loads(&m);
    let mg = 2.0 * 9.81;
    let (ea, eb) = (mg * 0.5 / 0.8, mg * 0.3 / 0.8);
    println!("capsule: N_a {na:.9} ({ea:.9}), N_b {nb:.9} ({eb:.9}), spin {w:.1e}");
    assert!((na - ea).abs() < 1e-8 * mg && (nb - eb).abs() < 1e-8 * mg);
}

#[test]
fn a_tilted_capsule_touches_with_its_lower_end() {
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../examples/contact/capsule_rest.toml"),
    )
    .unwrap()
    .replace(
        "segment = [[-0.3, 0.0, 0.05], [0.5, 0.0, 0.05]]",
        "segment = [[-0.3, 0.0, 0.05], [0.5, 0.0, 0.15]]",
    )
    .replace("t_end = 1.0", "t_end = 0.01");
    let m = model(&text);
    let (na, nb, _) = loads(&m);
    println!("tilted: N_a {na:.3}, N_b {nb:.3}");
    assert!(na > 0.0 && nb == 0.0);
}

#[test]
fn bad_capsules_are_rejected_where_they_are_written() {
    let base = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../examples/contact/capsule_rest.toml"),
    )
    .unwrap();
    for (from, to, message) in [
        (
            "segment = [[-0.3, 0.0, 0.05], [0.5, 0.0, 0.05]]",
            "segment = [[0.5, 0.0, 0.05], [0.5, 0.0, 0.05]]",
            "must join two different finite points",
        ),
        (
            "radius = 0.05",
            "radius = -0.05",
            "`radius` must be positive",
        ),
        (
            "shape = \"capsule\"",
            "shape = \"sphere\"",
            "`segment` does not apply here",
        ),
    ] {
        let text = base.replacen(from, to, 1);
        let Err(e) = Model::from_toml_str(&text, "bad.toml") else {
            panic!("accepted: {to}")
        };
        let d = e.errors().next().unwrap();
        let (line, _) = e.source.line_col(d.span.clone().expect("located").start);
        let needle = if message.contains("`segment` does not") {
            "segment ="
        } else {
            to
        };
        let want = text[..text.find(needle).unwrap()].matches('\n').count() + 1;
        println!("{line}: {}", d.message);
        assert!(d.message.contains(message), "{}", d.message);
        assert_eq!(line, want);
    }
    // A capsule without its segment: an error at the entry.
    let text = base.replacen("segment = [[-0.3, 0.0, 0.05], [0.5, 0.0, 0.05]]", "", 1);
    let Err(e) = Model::from_toml_str(&text, "bad.toml") else {
        panic!("accepted")
    };
    assert!(
        e.errors()
            .any(|d| d.message.contains("`segment` is required"))
    );
}
