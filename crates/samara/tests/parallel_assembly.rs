//! Issue #17: parallel element evaluation. Models of `PARALLEL_MIN_ELEMENTS` elements or
//! more evaluate their elements in parallel (rayon), `PARALLEL_WINDOW` at a time, each into
//! its own slot, and scatter them in element order, so a run gives bit-identical results
//! with any number of threads; and the parallel path computes the right answer (a
//! 300-element cantilever against the Timoshenko closed form).

use crate::common;

use common::{model, run_with_threads, state_bits};
use samara::model::{AnalysisKind, JacobianUpdate};
use samara::solve::{BlockLuSymbolic, SPLIT_MIN_BLOCKS};
use samara::system::{Assembler, Formulation, PARALLEL_MIN_ELEMENTS, PARALLEL_WINDOW, System};

/// Steel cantilever (L = 1 m, 10 mm square) in 300 two-node elements, a 0.5 N tip load
/// and a small tip mass (a second element size in the same model).
pub const CANTILEVER: &str = r#"
[model]
name = "cantilever_300"

[[beams]]
name = "beam"
order = 1
elements = 300
points = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]
root = "root"
tip = "tip"

[[beams.sections]]
station = 0.0
isotropic = { E = 210000000000.0, G = 80769230769.23077, A = 0.0001, I2 = 8.333333333333334e-10, I3 = 8.333333333333334e-10, J = 1.4060000000000001e-09, shear_factors = [0.8333333333333334, 0.8333333333333334], density = 7850.0 }

[[bodies]]
name = "tip_mass"
node = "tip"
mass = 0.01
inertia = [[1e-7, 0.0, 0.0], [0.0, 1e-7, 0.0], [0.0, 0.0, 1e-7]]

[[joints]]
name = "clamp"
type = "fixed"
node_a = "ground"
node_b = "root"

[[forces]]
name = "tip_load"
node = "tip"
force = [0.0, 0.0, -0.5]

[[analyses]]
name = "static"
type = "static"
load_steps = 2

[[analyses]]
name = "dynamic"
type = "dynamic"
t_end = 0.01
step = 1e-3
rho_inf = 0.9
"#;

#[test]
fn model_is_large_enough_for_the_parallel_path() {
    let m = model(CANTILEVER);
    let sys = System::new(&m);
    let n = sys.elements.len();
    assert!(n >= PARALLEL_MIN_ELEMENTS);
    // Several windows of parallel evaluation, the last one partial.
    assert!(
        n > 2 * PARALLEL_WINDOW && !n.is_multiple_of(PARALLEL_WINDOW),
        "{n} elements"
    );
}

/// Static and dynamic runs (full and modified Newton) with 1 and 2 threads agree to the
/// last bit.
#[test]
fn one_and_two_threads_give_identical_results() {
    let mut m = model(CANTILEVER);
    let sys = System::new(&m);
    for k in 0..m.analyses.len() {
        let one = run_with_threads(&m, &sys, k, 1);
        let two = run_with_threads(&m, &sys, k, 2);
        assert_eq!(
            state_bits(&one),
            state_bits(&two),
            "analysis {}",
            m.analyses[k].name
        );
    }
    if let AnalysisKind::Dynamic(d) = &mut m.analyses[1].kind {
        d.jacobian = JacobianUpdate::Modified;
    }
    let one = run_with_threads(&m, &sys, 1, 1);
    let two = run_with_threads(&m, &sys, 1, 2);
    assert_eq!(
        state_bits(&one),
        state_bits(&two),
        "dynamic, modified Newton"
    );
}

/// Tip deflection of the statically loaded cantilever through the parallel path against
/// Timoshenko's w = PL³/(3EI) + PL/(k G A) (9.5245e-4 m). The load keeps w/L ≈ 1e-3, so the
/// geometric nonlinearity is O((w/L)²) ≈ 1e-6 relative; 300 elements resolve the cubic
/// deflection line to well below the 1e-4 tolerance.
#[test]
fn parallel_static_cantilever_matches_timoshenko() {
    let m = model(CANTILEVER);
    let sys = System::new(&m);
    let s = run_with_threads(&m, &sys, 0, 2);
    let tip = m.node_index("tip").expect("tip node");
    let w = -s.nodes[tip].x.z;
    let (p, l, e, i, g, a, k): (f64, f64, f64, f64, f64, f64, f64) = (
        0.5,
        1.0,
        210e9,
        8.333333333333334e-10,
        80769230769.23077,
        1e-4,
        0.8333333333333334,
    );
    let exact = p * l.powi(3) / (3.0 * e * i) + p * l / (k * g * a);
    assert!(
        ((w - exact) / exact).abs() < 1e-4,
        "tip deflection {w:e}, Timoshenko {exact:e}"
    );
}

/// An aeroelastic model through the parallel path: the flexible NREL 5-MW rotor
/// (examples/rotor/nrel5mw_flexible.toml) with 70 linear elements per blade, so that with
/// its 3 × 19 BEM stations it has more than `PARALLEL_MIN_ELEMENTS` elements, and Øye's
/// dynamic wake (two states per station). The BEM stations keep a warm-start hint of their
/// last root, cleared as each analysis starts; every station is evaluated in the same
/// sequence whatever the number of threads, so 1 and 2 threads, and a run on a reused or
/// a fresh system, agree to the last bit (full and modified Newton). Without the clearing
/// the second run of a system differed from the first in the last bits.
#[test]
fn aeroelastic_rotor_is_deterministic_across_threads() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let text = std::fs::read_to_string(root.join("examples/rotor/nrel5mw_flexible.toml"))
        .expect("example")
        .replace(
            "../../reference",
            root.join("reference").to_str().expect("utf-8"),
        )
        .replace("order = 6\nelements = 2", "order = 1\nelements = 70")
        .replace(
            "tip_radius = 63.0 }",
            "tip_radius = 63.0, dynamic_wake = \"oye\" }",
        )
        .replace("t_end = 0.5", "t_end = 0.03");
    let mut m = model(&text);
    let sys = System::new(&m);
    assert!(
        sys.elements.len() >= PARALLEL_MIN_ELEMENTS,
        "{}",
        sys.elements.len()
    );
    assert!(sys.n_states >= 114, "dynamic wake states: {}", sys.n_states);
    let one = run_with_threads(&m, &sys, 0, 1);
    let two = run_with_threads(&m, &sys, 0, 2);
    assert!(
        state_bits(&one) == state_bits(&two),
        "full Newton: 1 and 2 threads differ"
    );
    let fresh = run_with_threads(&m, &System::new(&m), 0, 2);
    assert!(
        state_bits(&one) == state_bits(&fresh),
        "a fresh system differs from a reused one"
    );
    if let AnalysisKind::Dynamic(d) = &mut m.analyses[0].kind {
        d.jacobian = JacobianUpdate::Modified;
    }
    let one = run_with_threads(&m, &sys, 0, 1);
    let two = run_with_threads(&m, &sys, 0, 2);
    assert!(
        state_bits(&one) == state_bits(&two),
        "modified Newton: 1 and 2 threads differ"
    );
}

/// Issue #17, tenth round: from `SPLIT_MIN_BLOCKS` blocks on, the block LU may take a
/// separator order and factor and solve its two parts on two threads. The cantilever in
/// 1,000 elements (1,001 node blocks and the clamp's multipliers) takes it; its static and
/// dynamic runs (full and modified Newton) through the split factorization give the same
/// bits with 1 and 2 threads, and its static tip deflection is Timoshenko's (as above, to
/// 1e-4; 1,000 elements resolve the deflection line better than 300).
#[test]
fn split_factorization_is_deterministic_end_to_end() {
    let text = CANTILEVER
        .replace("elements = 300", "elements = 1000")
        .replace("t_end = 0.01", "t_end = 0.004");
    let mut m = model(&text);
    let sys = System::new(&m);
    let asm = Assembler::new(&sys, Formulation::Index3);
    let structure = asm.structure();
    assert!(
        structure.n_blocks() >= SPLIT_MIN_BLOCKS,
        "{}",
        structure.n_blocks()
    );
    let sym = BlockLuSymbolic::new(structure).expect("block structure");
    assert!(sym.split().is_some(), "the separator order is taken");
    for k in 0..m.analyses.len() {
        let one = run_with_threads(&m, &sys, k, 1);
        let two = run_with_threads(&m, &sys, k, 2);
        assert!(
            state_bits(&one) == state_bits(&two),
            "analysis {}",
            m.analyses[k].name
        );
        if k == 0 {
            let tip = m.node_index("tip").expect("tip node");
            let w = -two.nodes[tip].x.z;
            let exact = 0.5 / (3.0 * 210e9 * 8.333333333333334e-10)
                + 0.5 / (0.8333333333333334 * 80769230769.23077 * 1e-4);
            assert!(
                ((w - exact) / exact).abs() < 1e-4,
                "tip {w:e}, Timoshenko {exact:e}"
            );
        }
    }
    if let AnalysisKind::Dynamic(d) = &mut m.analyses[1].kind {
        d.jacobian = JacobianUpdate::Modified;
    }
    let one = run_with_threads(&m, &sys, 1, 1);
    let two = run_with_threads(&m, &sys, 1, 2);
    assert!(
        state_bits(&one) == state_bits(&two),
        "dynamic, modified Newton"
    );
}
