//! The assembler evaluates consecutive accumulating elements on the same nodes (the
//! stations of a lifting line on one beam element) into one local block and assembles it
//! once. Reference: the same model with every element assembled alone (each wrapped so
//! that it does not declare itself accumulating) — the element-by-element assembly.

use crate::common;

use common::model_file;
use nalgebra::{Matrix3, Vector3};
use samara::core::{Element, ElementInput, EvalContext, LocalTerms, Need, SignalTerms};
use samara::model::Model;
use samara::model::components::{Build, build_all, initial_nodes};
use samara::solve::BlockMatrix;
use samara::system::{Assembler, Coefficients, Formulation, System};

/// An element assembled alone: everything delegated but [`Element::accumulates`].
struct Alone(Box<dyn Element>);

impl Element for Alone {
    fn name(&self) -> &str {
        self.0.name()
    }
    fn nodes(&self) -> &[usize] {
        self.0.nodes()
    }
    fn n_states(&self) -> usize {
        self.0.n_states()
    }
    fn state_names(&self) -> Vec<String> {
        self.0.state_names()
    }
    fn initial_states(&self, out: &mut [f64]) {
        self.0.initial_states(out)
    }
    fn signal_inputs(&self) -> &[String] {
        self.0.signal_inputs()
    }
    fn signal_outputs(&self) -> &[String] {
        self.0.signal_outputs()
    }
    fn feedthrough(&self) -> bool {
        self.0.feedthrough()
    }
    fn signals(&self, ctx: &EvalContext, x: &ElementInput, out: &mut SignalTerms) {
        self.0.signals(ctx, x, out)
    }
    fn evaluate(&self, ctx: &EvalContext, x: &ElementInput, need: Need, out: &mut LocalTerms) {
        self.0.evaluate(ctx, x, need, out)
    }
}

fn system(m: &Model, alone: bool) -> System {
    system_copies(m, alone, 1)
}

/// The system of `m` with every element built `copies` times (on the same nodes; the
/// constraints once): enough elements for the assembler's parallel path.
fn system_copies(m: &Model, alone: bool, copies: usize) -> System {
    let initial = initial_nodes(m);
    let mut parts = Build::new(&initial);
    build_all(m, &mut parts);
    for _ in 1..copies {
        let mut more = Build::new(&initial);
        build_all(m, &mut more);
        parts.elements.extend(more.elements);
    }
    let elements: Vec<Box<dyn Element>> = if alone {
        parts
            .elements
            .into_iter()
            .map(|e| Box::new(Alone(e)) as Box<dyn Element>)
            .collect()
    } else {
        parts.elements
    };
    System::from_parts(
        m.nodes.iter().map(|n| n.name.clone()).collect(),
        elements,
        parts.constraints,
        parts.bodies,
        m.gravity,
        &initial,
    )
}

/// Residual and iteration matrix of `m` at its initial state with `coef` and tangent
/// operators away from the identity, batched and element by element: equal to rounding
/// (the batch sums the stations' terms before adding them to the matrix; 1e-12 of the
/// largest entry).
fn assert_batched_equals_alone(m: &Model, coef: &Coefficients) {
    assert_systems_assemble_alike(system(m, false), system(m, true), coef);
}

fn assert_systems_assemble_alike(batched: System, alone: System, coef: &Coefficients) {
    let state = batched.initial_state();
    let ctx = EvalContext {
        time: 0.3,
        gravity: Vector3::zeros(),
        load_factor: 1.0,
    };
    let ops: Vec<Matrix3<f64>> = (0..batched.n_nodes())
        .map(|i| {
            let t = 0.01 * (i as f64 + 1.0);
            Matrix3::identity() + Vector3::new(t, -0.5 * t, 0.2).cross_matrix() * 0.1
        })
        .collect();
    let assemble = |sys: &System| {
        let mut asm = Assembler::new(sys, Formulation::Index3);
        let mut r = vec![0.0; asm.n_unknowns()];
        let mut mat = BlockMatrix::zeros(asm.structure().clone());
        asm.assemble(sys, &state, &ctx, coef, &ops, &mut r, Some(&mut mat));
        // The residual alone (the Need::Residual path) too.
        let mut r0 = vec![0.0; asm.n_unknowns()];
        asm.assemble(sys, &state, &ctx, coef, &ops, &mut r0, None);
        (r, r0, mat.values.clone())
    };
    let (r1, q1, k1) = assemble(&batched);
    let (r2, q2, k2) = assemble(&alone);
    let close = |a: &[f64], b: &[f64], what: &str| {
        assert_eq!(a.len(), b.len());
        let scale = b.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        assert!(scale > 0.0);
        for (i, (x, y)) in a.iter().zip(b).enumerate() {
            assert!((x - y).abs() <= 1e-12 * scale, "{what}[{i}]: {x} vs {y}");
        }
    };
    close(&r1, &r2, "residual");
    close(&q1, &q2, "residual only");
    close(&k1, &k2, "matrix");
}

/// Dynamic iteration-matrix coefficients, with the element states' ∂ż/∂Δz and row scale.
fn dynamic_coefficients(state_rate: f64, state_row_scale: f64) -> Coefficients {
    Coefficients {
        mass: 2.0e4,
        damping: 150.0,
        stiffness: 1.0,
        row_scale: 0.3,
        multiplier_scale: 0.3,
        velocity_scale: 1.0,
        penalty: 0.0,
        state_rate,
        state_row_scale,
        step: 0.0,
    }
}

/// The flexible NREL 5-MW rotor, whose 19 stations per blade hang on the 7 nodes of the
/// blade's two beam elements (dynamic coefficients).
#[test]
fn batched_stations_assemble_as_the_elements_one_by_one() {
    let m = model_file("examples/rotor/nrel5mw_flexible.toml");
    let coef = dynamic_coefficients(0.0, 1.0);
    assert_batched_equals_alone(&m, &coef);
}

/// The same rotor with Øye's dynamic wake: two states per station, so a batch's block
/// holds the 7 nodes and then each station's two states in turn (state rows scaled by
/// s_z ≠ s_r, state columns with ∂ż/∂Δz ≠ 0).
#[test]
fn batched_stations_with_states_assemble_as_the_elements_one_by_one() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/rotor/nrel5mw_flexible.toml");
    let text = std::fs::read_to_string(&path).expect("example").replace(
        "tip_radius = 63.0 }",
        "tip_radius = 63.0, dynamic_wake = \"oye\" }",
    );
    let m = match Model::from_toml_str(&text, &path) {
        Ok(l) => l.model,
        Err(e) => panic!("{}", e.render_plain()),
    };
    let sys = system(&m, false);
    assert_eq!(sys.n_states, 2 * 57, "two wake states per station");
    // Five copies of every element: past PARALLEL_MIN_ELEMENTS, so the parallel window
    // evaluates each station alone (never batched) into a slot of its own size.
    let (big, big_alone) = (system_copies(&m, false, 5), system_copies(&m, true, 5));
    assert!(big.elements.len() >= samara::system::PARALLEL_MIN_ELEMENTS);
    let coef = dynamic_coefficients(70.0, 0.01);
    assert_batched_equals_alone(&m, &coef);
    assert_systems_assemble_alike(big, big_alone, &coef);
}
