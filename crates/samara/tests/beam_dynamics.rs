//! Issue #4, verification of the beam in dynamics: the Kynema/BeamDyn composite beam under
//! a suddenly applied tip load (reference history), the first bending frequency of a
//! cantilever against Euler–Bernoulli, energy conservation without dissipation, and the
//! large-rotation right-angle cantilever of Simo & Vu-Quoc (1988) against the published
//! curves.

use crate::common;

use common::{model, run};
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
///
/// Issue #17, verification 4: the energy-preserving and energy-decaying (ρ∞ = 0.9) schemes
/// reproduce it within the same tolerance (their lumped inertia and Cayley update are
/// other discretizations of the same beam; measured in the output).
#[test]
fn composite_dynamic() {
    for integrator in INTEGRATORS {
        composite_dynamic_with(integrator);
    }
}

/// The analysis lines of generalized-α (the examples' own, ρ∞ = 0.9) and of the two
/// energy-consistent schemes.
const INTEGRATORS: [&str; 3] = [
    "rho_inf = 0.9",
    "integrator = \"energy_preserving\"",
    "integrator = \"energy_decaying\"\nrho_inf = 0.9",
];

/// The example with its `rho_inf = 0.9` line replaced by `integrator`'s lines.
fn example_with_integrator(rel: &str, integrator: &str) -> samara::model::Model {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(rel);
    let text = std::fs::read_to_string(path).unwrap();
    assert!(text.contains("rho_inf = 0.9\n"));
    model(&text.replace("rho_inf = 0.9\n", &format!("{integrator}\n")))
}

fn composite_dynamic_with(integrator: &str) {
    let m = example_with_integrator("examples/verification/composite_dynamic.toml", integrator);
    let (_, h) = run(&m);
    let tip = m.node_index("tip").unwrap();
    let x0 = m.nodes[tip].position;
    // The reference history, copied into the repository with its source.
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../examples/verification/composite_dynamic_reference.csv"),
    )
    .expect("examples/verification/composite_dynamic_reference.csv");
    let mut worst: f64 = 0.0;
    let mut n = 0;
    for line in text.lines().filter(|l| !l.starts_with('#')).skip(1) {
        let v: Vec<f64> = line
            .split_whitespace()
            .map(|c| c.parse().unwrap())
            .collect();
        if v[0] > T_COMPARE + 1e-9 {
            break;
        }
        let f = h.at(v[0]).unwrap();
        assert!((f.time - v[0]).abs() < 1e-9);
        let u = f.state.nodes[tip].x - x0;
        let err = (u - Vector3::new(v[3], v[2], v[1])).norm();
        if n % 20 == 0 {
            println!(
                "t {:.3} ours {:.4} {:.4} {:.4} ref {:.4} {:.4} {:.4}",
                v[0], u.z, u.y, u.x, v[1], v[2], v[3]
            );
        }
        worst = worst.max(err);
        n += 1;
    }
    println!(
        "{}: {n} samples, worst tip-displacement difference {worst:.4e} (peak response 2.35)",
        integrator.replace('\n', " ")
    );
    assert!(worst < 0.04 * 2.35, "{integrator}: {worst:e}");
}

/// Steel cantilever (L = 1 m, 0.01 m square), released from a small static tip deflection.
fn cantilever(p: usize, ne: usize, step: f64, rho: f64, t_end: f64) -> String {
    format!(
        r#"[model]
name = "free_vibration"

[[beams]]
name = "beam"
order = {p}
elements = {ne}
points = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]
root = "root"
tip = "tip"

[[beams.sections]]
station = 0.0
isotropic = {{ E = 2.1e11, G = 8.076923076923077e10, A = 1e-4, I2 = 8.333333333333334e-10, I3 = 8.333333333333334e-10, J = 1.406e-9, shear_factors = [0.8333333333333334, 0.8333333333333334], density = 7850.0 }}

[[joints]]
name = "clamp"
type = "fixed"
node_a = "ground"
node_b = "root"

[[forces]]
name = "release"
node = "tip"
force = [0.0, 0.0, -0.5]
function = {{ type = "step", time = 0.0, before = 1.0, after = 0.0 }}

[[analyses]]
name = "preload"
type = "static"
time = -1.0
tolerance = 1e-12
relative_tolerance = 1e-12

[[analyses]]
name = "swing"
type = "dynamic"
start_from = "preload"
t_end = {t_end}
step = {step}
rho_inf = {rho}
tolerance = 1e-12
relative_tolerance = 1e-10
"#
    )
}

/// First bending frequency from the tip's upward zero crossings against Euler–Bernoulli,
/// ω₁ = 1.87510407² √(EI/(ρA L⁴)). Tolerance 1e-3: shear and rotary inertia (Timoshenko,
/// (h/L)² = 1e-4 with a factor of a few), the time discretization (period error
/// (ωh)²/12 ≈ 8e-5 at h = T/200) and the crossing interpolation are all below it.
#[test]
fn cantilever_first_bending_frequency() {
    let (e, i, rho, a): (f64, f64, f64, f64) = (2.1e11, 1e-8 / 12.0, 7850.0, 1e-4);
    let omega = 1.875104069f64.powi(2) * (e * i / (rho * a)).sqrt();
    let period = 2.0 * std::f64::consts::PI / omega;
    let m = model(&cantilever(4, 4, period / 200.0, 1.0, 5.2 * period));
    let (_, h) = run_chain(&m);
    let tip = m.node_index("tip").unwrap();
    let z: Vec<(f64, f64)> = h
        .frames
        .iter()
        .map(|f| (f.time, f.state.nodes[tip].x.z))
        .collect();

    let ups: Vec<f64> = z
        .windows(2)
        .filter(|w| w[0].1 < 0.0 && w[1].1 >= 0.0)
        .map(|w| w[0].0 + (w[1].0 - w[0].0) * (-w[0].1) / (w[1].1 - w[0].1))
        .collect();
    let measured = (ups[ups.len() - 1] - ups[0]) / (ups.len() - 1) as f64;
    let err = (measured - period) / period;
    println!(
        "period {measured:.6e} s vs Euler–Bernoulli {period:.6e} s: rel. error {err:.3e} over {} periods",
        ups.len() - 1
    );
    assert!(err.abs() < 1e-3);
}

/// Undamped, ρ∞ = 1 (no numerical dissipation): the total energy (kinetic + strain) of the
/// released cantilever. At ρ∞ = 1, α_m = α_f makes the algorithmic acceleration equal to
/// v̇ and the scheme the trapezoidal rule, which conserves the energy of a linear system
/// exactly, so what remains is the geometric nonlinearity's share: it must scale with the
/// square of the amplitude, (δ/L)² — measured: × 97.5 for a 10× larger release load — and
/// fall at second order in h. Measured max |ΔE|/E over 3 periods at the 0.5 N release
/// (δ/L ≈ 1e-3): 7.75e-8, 3.1e-8, 6.4e-9 at h = T/40, T/80, T/160 (fitted order 1.8; at
/// T/20 and coarser the released element-scale modes, ωh ≫ 1 and undamped, make it
/// irregular: 2.7e-6 at T/10, 8.8e-6 at T/20). Expected size (δ/L)² (ωh)² ≈ 1.4e-9 at
/// T/160 times a constant of a few. Tolerances: amplitude exponent 2 ± 0.05, fitted order
/// in h ≥ 1.6, and 1.5e-8 at T/160.
#[test]
fn energy_conserved_to_second_order() {
    let (e, i, rho, a): (f64, f64, f64, f64) = (2.1e11, 1e-8 / 12.0, 7850.0, 1e-4);
    let period = 2.0 * std::f64::consts::PI / (1.875104069f64.powi(2) * (e * i / (rho * a)).sqrt());
    let deviation = |k: f64, load: f64| {
        let text = cantilever(2, 4, period / k, 1.0, 3.0 * period).replace(
            "force = [0.0, 0.0, -0.5]",
            &format!("force = [0.0, 0.0, {:e}]", -load),
        );
        let (_, h) = run_chain(&model(&text));
        let en = |f: &samara::analysis::Frame| f.energy.kinetic + f.energy.potential;
        let e0 = en(&h.frames[0]);
        h.frames
            .iter()
            .map(|f| (en(f) - e0).abs())
            .fold(0.0, f64::max)
            / e0
    };
    let ks = [40.0, 80.0, 160.0];
    let devs: Vec<f64> = ks.iter().map(|&k| deviation(k, 0.5)).collect();
    let hs: Vec<f64> = ks.iter().map(|k| period / k).collect();
    let order = common::loglog_slope(&hs, &devs);
    println!("max |ΔE|/E at h = T/40, T/80, T/160: {devs:?}; fitted order {order:.2}");
    let large = deviation(40.0, 5.0);
    let exponent = (large / devs[0]).log10();
    println!("10× the release load: {large:.3e}, amplitude exponent {exponent:.3}");
    assert!((exponent - 2.0).abs() < 0.05, "{exponent}");
    assert!(order > 1.6, "{devs:?}");
    assert!(devs[2] < 1.5e-8, "{devs:?}");
}

/// Runs all analyses (chaining `start_from`) and returns the last one's summary and frames.
fn run_chain(
    m: &samara::model::Model,
) -> (samara::analysis::AnalysisSummary, samara::analysis::History) {
    let sys = samara::system::System::new(m);
    let mut out = samara::analysis::run_all(
        m,
        &sys,
        |_| Ok(samara::analysis::History::default()),
        |_, _| {},
    )
    .unwrap();
    let (s, h) = out.pop().unwrap();
    assert!(s.failure.is_none(), "{:?}", s.failure);
    (s, h)
}

/// Right-angle cantilever (Simo & Vu-Quoc 1988, CMAME 66: an L-frame hit out of plane at the
/// elbow, 30 s of large out-of-plane motion coupled with torsion): the elbow and tip
/// out-of-plane displacements against the published curves
/// (examples/verification/right_angle_cantilever_reference.csv, digitized points).
///
/// Our solution (2 elements of order 4 per member, h = 0.05, ρ∞ = 0.9) is converged: 4
/// elements of order 6 at h = 0.0125 differ by < 0.033 over the 30 s, and ρ∞ = 1 changes
/// nothing visible. The reference is the authors' own discretization (10 linear elements per
/// member, step 0.25 — our run at h = 0.25 moves towards it) read off a figure, and its phase
/// error grows with time. Measured: over the first 15 s max |Δu₃| = 7 % (elbow) and 4 % (tip)
/// of the peak displacement; over 30 s the RMS difference is 6 % and 3 %. Tolerances: 10 %
/// of the peak (max, 15 s) and 8 % (RMS, 30 s). Issue #17, verification 4: the
/// energy-preserving and energy-decaying (ρ∞ = 0.9) schemes, the same tolerances.
#[test]
fn right_angle_cantilever_against_simo_vu_quoc() {
    for integrator in INTEGRATORS {
        right_angle_cantilever_with(integrator);
    }
}

fn right_angle_cantilever_with(integrator: &str) {
    let m = example_with_integrator(
        "examples/verification/right_angle_cantilever.toml",
        integrator,
    );
    let (s, h) = run(&m);
    // Generalized-α takes every step; the energy schemes halve a few where their Newton
    // iteration (modified, with the matrix of finite differences) stalls at the hit.
    println!(
        "{}: {} steps, {} rejected",
        integrator.replace('\n', " "),
        s.steps,
        s.rejected_steps
    );
    if !integrator.contains("energy") {
        assert_eq!(s.rejected_steps, 0);
    }
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../examples/verification/right_angle_cantilever_reference.csv"),
    )
    .unwrap();
    for point in ["elbow", "tip"] {
        let node = m.node_index(point).unwrap();
        let z0 = m.nodes[node].position.z;
        // Our history, for linear interpolation at the reference times.
        let ours: Vec<(f64, f64)> = h
            .frames
            .iter()
            .map(|f| (f.time, f.state.nodes[node].x.z - z0))
            .collect();
        let at = |t: f64| -> f64 {
            let k = ours.partition_point(|p| p.0 <= t).clamp(1, ours.len() - 1);
            let (a, b) = (ours[k - 1], ours[k]);
            a.1 + (b.1 - a.1) * (t - a.0) / (b.0 - a.0)
        };
        let reference: Vec<(f64, f64)> = text
            .lines()
            .filter(|l| l.starts_with(&format!("{point},")))
            .map(|l| {
                let v: Vec<f64> = l.split(',').skip(1).map(|c| c.parse().unwrap()).collect();
                (v[0], v[1])
            })
            .collect();
        let peak = reference.iter().fold(0.0f64, |m, r| m.max(r.1.abs()));
        let (mut max15, mut sum2) = (0.0f64, 0.0);
        for &(t, u) in &reference {
            let e = at(t) - u;
            if t <= 15.0 {
                max15 = max15.max(e.abs());
            }
            sum2 += e * e;
        }
        let rms = (sum2 / reference.len() as f64).sqrt();
        println!(
            "{}: {point}: peak {peak:.2}, max |Δ| over 15 s {max15:.3} ({:.1} %), RMS over 30 s {rms:.3} ({:.1} %)",
            integrator.replace('\n', " "),
            100.0 * max15 / peak,
            100.0 * rms / peak
        );
        assert!(
            max15 < 0.10 * peak && rms < 0.08 * peak,
            "{integrator}: {point} {max15} {rms}"
        );
    }
}
