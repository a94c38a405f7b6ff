//! Issue #4, verification of the beam in statics: roll-up (closed form, exponential
//! convergence in p), Timoshenko cantilever (closed forms with shear), extension–twist
//! coupling (compliance closed form), the BeamDyn regression cases and the Kynema composite
//! beam (../shared/reference/), the Bathe–Bolourchi 45° bend.

mod common;

use common::{model, model_file, run};
use nalgebra::{UnitQuaternion, Vector3};
use samara::analysis::History;
use samara::model::Model;

/// Final displacement and rotation (global, from the initial orientation: R R₀ᵀ) of a node.
fn node_final(m: &Model, h: &History, name: &str) -> (Vector3<f64>, UnitQuaternion<f64>) {
    let i = m.node_index(name).expect("node exists");
    let n = &h.last().unwrap().state.nodes[i];
    let n0 = &m.nodes[i];
    (n.x - n0.position, n.rot.quaternion() * n0.orientation.quaternion().inverse())
}

/// Wiener–Milenkovic parameters c = 4 tan(φ/4) n of a rotation (BeamDyn's TipRD outputs).
fn wiener_milenkovic(q: &UnitQuaternion<f64>) -> Vector3<f64> {
    let psi = samara::math::log_map(q);
    let phi = psi.norm();
    if phi < 1e-300 { Vector3::zeros() } else { psi / phi * 4.0 * (phi / 4.0).tan() }
}

/// bd_isotropic_rollup: BeamDyn's r-test output and the exact Euler solution.
/// Tolerance: BeamDyn prints 9 digits; one order-15 element resolves the circular arc to
/// ~1e-9, so 1e-7 (absolute, on a tip displacement of 5.5) checks all printed digits
/// but the last two.
#[test]
fn bd_isotropic_rollup() {
    let m = model_file("examples/verification/bd_isotropic_rollup.toml");
    let (_, h) = run(&m);
    let (u, q) = node_final(&m, &h, "tip");
    let reference = Vector3::new(0.0, 5.49867743, -2.43174319);
    println!("tip displacement {u:?}, reference {reference:?}");
    assert!((u - reference).norm() < 1e-7, "{u:?}");
    let theta: f64 = 12.5664 * 10.0 / 100.0;
    let exact = Vector3::new(0.0, 10.0 / theta * (1.0 - theta.cos()), 10.0 / theta * theta.sin() - 10.0);
    assert!((u - exact).norm() < 1e-7, "exact {exact:?}");
    let c = wiener_milenkovic(&q);
    println!("tip WM {c:?}");
    assert!((c - Vector3::new(-1.29968203, 0.0, 0.0)).norm() < 1e-7);
}
