//! Hot loops allocate nothing: once the first steps have sized the work space (the
//! Newton matrix's pattern, the sparse LU's factors), a step makes no heap allocation —
//! of the energy schemes (residual, grouped differences, refactoring, solve) and of
//! generalized-α (the trial state, assembly, the block LU) on models with every family of
//! elements; and of a two-part iteration (`partition = "two_parts"`). Counted with a
//! counting global allocator, per thread (the test harness runs tests in parallel).

mod common;
use common::{energy_stepper, example_model_text};
use samara::system::System;
use std::alloc::{GlobalAlloc, Layout, System as Heap};
use std::cell::Cell;

struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
        unsafe { Heap.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { Heap.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
        unsafe { Heap.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static COUNTING: Counting = Counting;

fn allocations() -> usize {
    ALLOCATIONS.with(Cell::get)
}

/// `text` (a model without analyses) with one dynamic analysis of `integrator`.
fn with_analysis(text: &str, integrator: &str, step: f64) -> samara::model::Model {
    with_analysis_at(text, integrator, step, std::path::Path::new("test.toml"))
}

/// [`with_analysis`] for a model whose files are relative to `path`.
fn with_analysis_at(
    text: &str,
    integrator: &str,
    step: f64,
    path: &std::path::Path,
) -> samara::model::Model {
    let rho = if integrator == "energy_decaying" {
        "rho_inf = 0.5\n"
    } else {
        ""
    };
    let text = format!(
        "{text}\n[[analyses]]\nname = \"a\"\ntype = \"dynamic\"\nintegrator = \"{integrator}\"\nt_end = 1.0\nstep = {step}\n{rho}tolerance = 1e-10\nrelative_tolerance = 1e-12\n"
    );
    match samara::model::Model::from_toml_str(&text, path) {
        Ok(l) => l.model,
        Err(e) => panic!("{e}"),
    }
}

/// Heap allocations in `steps` steps after `warm` warm-up steps, and the factorizations
/// made in them (so that a count of 0 is not a run that never refactored).
fn allocations_in_steps(m: &samara::model::Model, warm: usize, steps: usize) -> (usize, usize) {
    let sys = System::new(m);
    let (mut it, h) = energy_stepper(&sys, m);
    for _ in 0..warm {
        it.step(h).unwrap();
    }
    let (before, f0) = (allocations(), it.factorizations);
    for _ in 0..steps {
        it.step(h).unwrap();
    }
    (allocations() - before, it.factorizations - f0)
}

fn check(name: &str, text: &str, step: f64) {
    for integrator in ["energy_preserving", "energy_decaying"] {
        let m = with_analysis(text, integrator, step);
        let (n, factorizations) = allocations_in_steps(&m, 3, 20);
        println!(
            "{name}, {integrator}: {n} allocations in 20 steps, {factorizations} factorizations"
        );
        assert!(factorizations > 0, "{name} {integrator}: never refactored");
        assert_eq!(n, 0, "{name} {integrator}: {n} allocations in 20 steps");
    }
}

/// Rigid bodies and revolute joints (the joints' mid-point rows), one with a spring on
/// its coordinate (the coordinate rows and their Gonzalez gradient).
#[test]
fn joints_and_coordinate_springs_step_without_allocating() {
    let text = example_model_text("examples/double_pendulum.toml");
    let text = format!("{text}\n[joints.theta3]\nstiffness = 2.0\n");
    check("double pendulum", &text, 0.01);
}

/// Beams under an applied load (the flying spaghetti's push).
#[test]
fn beams_step_without_allocating() {
    let text = example_model_text("examples/flying_spaghetti.toml");
    check("flying spaghetti", &text, 0.05);
}

/// Heap allocations in `steps` steps of the generalized-α [`Simulation`] of `m`'s first
/// analysis after `warm` warm-up steps.
fn generalized_alpha_allocations(m: &samara::model::Model, warm: usize, steps: usize) -> usize {
    use samara::analysis::Simulation;
    use samara::model::AnalysisKind;
    let sys = System::new(m);
    let AnalysisKind::Dynamic(d) = &m.analyses[0].kind else {
        panic!("not dynamic")
    };
    let mut sim = Simulation::new(&sys, d, sys.initial_state()).unwrap();
    for _ in 0..warm {
        sim.step(d.step).unwrap();
    }
    let before = allocations();
    for _ in 0..steps {
        sim.step(d.step).unwrap();
    }
    allocations() - before
}

/// The generalized-α step loop: rigid bodies and joints, beams, a wing's lifting line,
/// a hovering rotor with dynamic inflow, contact with friction, a tire, hydraulics, a
/// motor, a controller, a servo (a joint driven by a controller's signal), and the landing
/// gear with all of them.
#[test]
fn generalized_alpha_steps_without_allocating() {
    for rel in [
        "examples/double_pendulum.toml",
        "examples/slider_crank.toml",
        "examples/flying_spaghetti.toml",
        "examples/aero/wing.toml",
        "examples/rotor/hover_rotor.toml",
        "examples/contact/incline.toml",
        "examples/contact/tire_braking.toml",
        "examples/hydraulics/actuator.toml",
        "examples/electric/motor_spinup.toml",
        "examples/control/pid_position.toml",
        "examples/control/servo_follower.toml",
        "examples/landing_gear_drop.toml",
    ] {
        let text = example_model_text(rel);
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../..")
            .join(rel);
        let m = with_analysis_at(&text, "generalized_alpha", 1e-3, &path);
        let n = generalized_alpha_allocations(&m, 3, 20);
        println!("{rel}, generalized-α: {n} allocations in 20 steps");
        assert_eq!(n, 0, "{rel}: {n} allocations in 20 steps");
    }
}

/// A two-part iteration (`partition = "two_parts"`) on a 40-link chain, full and modified
/// Newton: part 1's assembly with the partner's scratch, its residual rows copied in, the
/// node updates through owner-checked handles. With one rayon thread both parts run here,
/// every allocation counted; with two, part 1 runs on the partner thread (the same code,
/// counted in the one-thread run) and the count covers the hand-over on this side.
#[test]
fn two_part_steps_allocate_nothing() {
    use samara::analysis::Simulation;
    use samara::model::{AnalysisKind, JacobianUpdate};
    let mut text = String::from("[model]\nname = \"chain\"\ngravity = [0.0, 0.0, -9.81]\n");
    for i in 0..40 {
        let a = if i == 0 {
            "ground".to_string()
        } else {
            format!("link{}", i - 1)
        };
        text += &format!(
            "[[nodes]]\nname = \"link{i}\"\nposition = [{x}, 0.0, 0.0]\n\
             [[bodies]]\nname = \"link{i}\"\nnode = \"link{i}\"\nmass = 0.0785\n\
             inertia = [[1.3e-06, 0.0, 0.0], [0.0, 6.6e-05, 0.0], [0.0, 0.0, 6.6e-05]]\n\
             [[joints]]\nname = \"pin{i}\"\ntype = \"revolute\"\nnode_a = \"{a}\"\n\
             node_b = \"link{i}\"\nposition = [{p}, 0.0, 0.0]\naxis = [0.0, 1.0, 0.0]\n",
            x = 0.05 + 0.1 * i as f64,
            p = 0.1 * i as f64
        );
    }
    text += "[[analyses]]\nname = \"a\"\ntype = \"dynamic\"\nt_end = 1.0\nstep = 1e-3\n\
             rho_inf = 0.9\npartition = \"two_parts\"\n";
    for jacobian in [JacobianUpdate::Full, JacobianUpdate::Modified] {
        let mut m = samara::model::Model::from_toml_str(&text, "chain.toml")
            .unwrap_or_else(|e| panic!("{e}"))
            .model;
        let AnalysisKind::Dynamic(d) = &mut m.analyses[0].kind else {
            panic!("not dynamic")
        };
        d.jacobian = jacobian;
        let d = d.clone();
        let sys = System::new(&m);
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("thread pool");
            let n = pool.install(|| {
                let mut sim = Simulation::new(&sys, &d, sys.initial_state()).unwrap();
                let parts = sim.parts().expect("two parts planned");
                assert_eq!(parts.partner_thread, threads == 2);
                for _ in 0..3 {
                    sim.step(d.step).unwrap();
                }
                let before = allocations();
                for _ in 0..20 {
                    sim.step(d.step).unwrap();
                }
                allocations() - before
            });
            println!("two parts, {jacobian:?}, {threads} thread(s): {n} allocations in 20 steps");
            assert_eq!(n, 0, "{jacobian:?}, {threads} thread(s): {n} allocations");
        }
    }
}
