//! Modal analysis (issue #14, tests 1 and 6): cantilever frequencies against Euler–Bernoulli
//! and Timoshenko theory with convergence in the element order p; a constrained mechanism
//! against its minimal-coordinate model; free-free bodies with exactly six zero modes; the
//! dense (null-space + QZ) and sparse (shift-invert Krylov–Schur) paths against each other.

use crate::common;
use common::model;
use nalgebra::{Matrix2, Matrix4};
use samara::analysis::History;
use samara::linear::eigen::{EigenError, EigenMethod, EigenOptions};
use samara::linear::{linearize, modes};
use samara::model::Model;
use samara::system::System;
use std::f64::consts::PI;

/// A cantilever along x, clamped at x = 0, with diagonal section matrices
/// `k = [EA, GA2, GA3, GJ, EI2, EI3]`, `m = [m, m, m, ρJ, ρI2, ρI3]`.
fn cantilever(len: f64, order: usize, elements: usize, k: [f64; 6], m: [f64; 6]) -> String {
    let diag = |d: [f64; 6]| {
        (0..6)
            .map(|i| {
                let row: Vec<String> = (0..6)
                    .map(|j| format!("{:e}", if i == j { d[i] } else { 0.0 }))
                    .collect();
                format!("[{}]", row.join(", "))
            })
            .collect::<Vec<_>>()
            .join(",\n  ")
    };
    format!(
        r#"
[model]
name = "cantilever"

[[beams]]
name = "beam"
order = {order}
elements = {elements}
points = [[0.0, 0.0, 0.0], [{len}, 0.0, 0.0]]
root = "root"
tip = "tip"

[[beams.sections]]
station = 0.0
stiffness = [
  {}
]
mass = [
  {}
]

[[joints]]
name = "clamp"
type = "fixed"
node_a = "ground"
node_b = "root"

[[analyses]]
name = "modes"
type = "modal"
n_modes = 12
"#,
        diag(k),
        diag(m)
    )
}

/// Natural frequencies [rad/s] of the first `n` modes of a model's first analysis, by the
/// given method.
fn omegas(m: &Model, n: usize, method: EigenMethod) -> Vec<f64> {
    let sys = System::new(m);
    let lin = linearize(&sys, &sys.initial_state(), None);
    let s = modes(
        &lin,
        &EigenOptions {
            n_modes: n,
            shift: None,
            method,
        },
    )
    .unwrap();
    s.modes.iter().map(|m| 2.0 * PI * m.frequency()).collect()
}

/// Clamped-free Timoshenko beam: roots in ω of det of the free-end block of the transfer
/// matrix of `z = (w, ψ, M, V)`, `w' = ψ + V/κGA`, `ψ' = M/EI`, `M' = −V − ρIω²ψ`,
/// `V' = −ρAω²w` (Timoshenko 1921; the equations themselves, integrated exactly by the
/// matrix exponential, so no transcription of a frequency equation is involved).
fn timoshenko_cantilever(
    len: f64,
    ei: f64,
    kga: f64,
    rho_a: f64,
    rho_i: f64,
    n: usize,
) -> Vec<f64> {
    let det = |w: f64| {
        let a = Matrix4::new(
            0.0,
            1.0,
            0.0,
            1.0 / kga, //
            0.0,
            0.0,
            1.0 / ei,
            0.0, //
            0.0,
            -rho_i * w * w,
            0.0,
            -1.0, //
            -rho_a * w * w,
            0.0,
            0.0,
            0.0,
        );
        let t = (a * len).exp();
        // Clamped: z(0) = (0, 0, M0, V0); free: M(L) = V(L) = 0.
        Matrix2::new(t[(2, 2)], t[(2, 3)], t[(3, 2)], t[(3, 3)]).determinant()
    };
    let scale = (ei / (rho_a * len.powi(4))).sqrt();
    let mut roots = Vec::new();
    let mut w0 = 0.01 * scale;
    let dw = 0.01 * scale;
    let mut d0 = det(w0);
    while roots.len() < n {
        let w1 = w0 + dw;
        let d1 = det(w1);
        if d0.signum() != d1.signum() {
            let (mut a, mut b, mut da) = (w0, w1, d0);
            for _ in 0..200 {
                let c = 0.5 * (a + b);
                let dc = det(c);
                if dc.signum() == da.signum() {
                    a = c;
                    da = dc;
                } else {
                    b = c;
                }
            }
            roots.push(0.5 * (a + b));
        }
        w0 = w1;
        d0 = d1;
    }
    roots
}

/// Euler–Bernoulli clamped-free roots βL of 1 + cos βL cosh βL = 0.
const EB_BETA_L: [f64; 3] = [
    1.875_104_068_711_961,
    4.694_091_132_974_175,
    7.854_757_438_237_613,
];

/// The reference of each computed frequency: the nearest value in `reference`.
fn nearest_error(computed: f64, reference: &[f64]) -> f64 {
    reference
        .iter()
        .map(|r| (computed - r).abs() / r)
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn slender_cantilever_converges_exponentially_in_p_to_timoshenko_and_euler_bernoulli() {
    // Slender beam (L/r ≈ 3000; shear flexibility EI/(κGA L²) ≤ 4e-7): Timoshenko theory
    // (the reference for the converged beam) and Euler–Bernoulli then differ by < 1e-5.
    // Distinct bending stiffnesses so that flap and lag modes differ.
    let (len, ei2, ei3, ga, ea, gj): (f64, f64, f64, f64, f64, f64) =
        (1.0, 1.0, 4.0, 1e7, 1e7, 0.8);
    let (m, rho_j, rho_i): (f64, f64, f64) = (1.0, 2e-7, 1e-7);
    let flap = timoshenko_cantilever(len, ei2, ga, m, rho_i, 2);
    let lag = timoshenko_cantilever(len, ei3, ga, m, rho_i, 2);
    let eb2: Vec<f64> = EB_BETA_L
        .iter()
        .map(|b| b * b * (ei2 / (m * len.powi(4))).sqrt())
        .collect();
    let eb3: Vec<f64> = EB_BETA_L
        .iter()
        .map(|b| b * b * (ei3 / (m * len.powi(4))).sqrt())
        .collect();
    let reference = [flap[0], lag[0], flap[1], lag[1]];
    let eb = [eb2[0], eb3[0], eb2[1], eb3[1]];
    for (t, e) in reference.iter().zip(&eb) {
        assert!(
            (t - e).abs() / e < 1e-5,
            "slender: Timoshenko {t} vs EB {e}"
        );
    }
    let mut errs = Vec::new();
    for p in [3, 4, 5, 6, 7, 8, 9] {
        let mdl = model(&cantilever(
            len,
            p,
            1,
            [ea, ga, ga, gj, ei2, ei3],
            [m, m, m, rho_j, rho_i, rho_i],
        ));
        let w = omegas(&mdl, 4, EigenMethod::Dense);
        let e = (0..4)
            .map(|i| (w[i] - reference[i]).abs() / reference[i])
            .fold(0.0, f64::max);
        let e_eb = (0..4)
            .map(|i| (w[i] - eb[i]).abs() / eb[i])
            .fold(0.0, f64::max);
        eprintln!(
            "slender p = {p}: worst of the first 4 bending modes vs Timoshenko {e:.2e}, vs EB {e_eb:.2e}"
        );
        errs.push(e);
    }
    // Exponential convergence: each step in p gains at least a factor 5 until the
    // round-off floor of this stiff problem, ε·(ω_max/ω_1)² ≈ 1e-16 · 1e8 (axial and
    // shear stiffness 1e7 against EI = 1): 2e-8.
    for w in errs.windows(2) {
        assert!(
            w[1] < 0.2 * w[0] || w[1] < 2e-8,
            "not exponential: {errs:?}"
        );
    }
    assert!(errs[6] < 2e-8, "p = 9: {errs:?}");
    // Torsion (St-Venant, exact in the beam model): first torsion mode.
    let torsion = PI / (2.0 * len) * (gj / rho_j).sqrt();
    let mdl = model(&cantilever(
        len,
        12,
        1,
        [ea, ga, ga, gj, ei2, ei3],
        [m, m, m, rho_j, rho_i, rho_i],
    ));
    let sys = System::new(&mdl);
    let lin = linearize(&sys, &sys.initial_state(), None);
    let s = modes(
        &lin,
        &EigenOptions {
            n_modes: 1,
            shift: Some(torsion / (2.0 * PI)),
            method: EigenMethod::Dense,
        },
    )
    .unwrap();
    let et = (2.0 * PI * s.modes[0].frequency() - torsion).abs() / torsion;
    eprintln!("slender torsion 1 error {et:.2e}");
    assert!(et < 1e-9);
}

#[test]
fn stocky_rollup_beam_against_timoshenko_and_torsion() {
    // The bd_isotropic_rollup beam (reference/): EI = 100, κGA = 1e4, EA = 1e4,
    // GJ = 200, m = 1, ρI = 1, ρJ = 2, L = 10: slenderness L/r = 10, so rotary inertia and
    // shear matter (Timoshenko is 2–25 % below EB over the first modes).
    let (len, ei, kga, ea, gj, m, ri, rj): (f64, f64, f64, f64, f64, f64, f64, f64) =
        (10.0, 100.0, 1e4, 1e4, 200.0, 1.0, 1.0, 2.0);
    let bend = timoshenko_cantilever(len, ei, kga, m, ri, 5);
    let eb: Vec<f64> = EB_BETA_L
        .iter()
        .map(|b| b * b * (ei / (m * len.powi(4))).sqrt())
        .collect();
    eprintln!("Timoshenko {bend:?}, EB {eb:?}");
    assert!(
        (bend[1] - eb[1]).abs() / eb[1] > 0.1,
        "the stocky case must differ from EB"
    );
    let torsion: Vec<f64> = (1..5)
        .map(|k| (2 * k - 1) as f64 * PI / (2.0 * len) * (gj / rj).sqrt())
        .collect();
    let refs: Vec<f64> = [bend.clone(), torsion.clone()].concat();
    let mut errs = Vec::new();
    for p in [5, 8, 11, 14] {
        let mdl = model(&cantilever(
            len,
            p,
            1,
            [ea, kga, kga, gj, ei, ei],
            [m, m, m, rj, ri, ri],
        ));
        let w = omegas(&mdl, 12, EigenMethod::Dense);
        // Pairs of equal bending frequencies (EI2 = EI3) and the torsion modes: the first
        // 12 are B1 B1 T1 B2 B2 T2 B3 B3 T3 B4 B4 T4.
        let err = w
            .iter()
            .map(|x| nearest_error(*x, &refs))
            .fold(0.0, f64::max);
        eprintln!("rollup p = {p}: first 12 modes worst error {err:.2e}");
        errs.push(err);
    }
    for w in errs.windows(2) {
        assert!(
            w[1] < 0.05 * w[0] || w[1] < 1e-9,
            "not exponential: {errs:?}"
        );
    }
    assert!(errs[3] < 1e-9, "p = 14: {errs:?}");
}

#[test]
fn axial_mode_with_shift() {
    // The first axial mode of the roll-up beam, 15.708 rad/s = 2.5 Hz, found by `shift`.
    let (len, ei, kga, ea, gj, m, ri, rj): (f64, f64, f64, f64, f64, f64, f64, f64) =
        (10.0, 100.0, 1e4, 1e4, 200.0, 1.0, 1.0, 2.0);
    let axial = PI / (2.0 * len) * (ea / m).sqrt();
    let mdl = model(&cantilever(
        len,
        15,
        1,
        [ea, kga, kga, gj, ei, ei],
        [m, m, m, rj, ri, ri],
    ));
    let sys = System::new(&mdl);
    let lin = linearize(&sys, &sys.initial_state(), None);
    for method in [EigenMethod::Dense, EigenMethod::Sparse] {
        let s = modes(
            &lin,
            &EigenOptions {
                n_modes: 1,
                shift: Some(axial / (2.0 * PI)),
                method,
            },
        )
        .unwrap();
        let w = 2.0 * PI * s.modes[0].frequency();
        eprintln!("{method:?}: axial {w} vs {axial}");
        assert!((w - axial).abs() / axial < 1e-10);
    }
}

const DOUBLE_PENDULUM: &str = r#"
[model]
name = "hanging_double_pendulum"
gravity = [0.0, 0.0, -9.81]

[[nodes]]
name = "bob1"
position = [0.0, 0.0, -1.0]

[[nodes]]
name = "bob2"
position = [0.0, 0.0, -2.0]

[[bodies]]
name = "bob1"
node = "bob1"
mass = 1.0
inertia = [[1e-3, 0.0, 0.0], [0.0, 1e-3, 0.0], [0.0, 0.0, 1e-3]]

[[bodies]]
name = "bob2"
node = "bob2"
mass = 0.5
inertia = [[2e-3, 0.0, 0.0], [0.0, 2e-3, 0.0], [0.0, 0.0, 2e-3]]

[[joints]]
name = "shoulder"
type = "revolute"
node_a = "ground"
node_b = "bob1"
position = [0.0, 0.0, 0.0]
axis = [0.0, 1.0, 0.0]

[[joints]]
name = "elbow"
type = "revolute"
node_a = "bob1"
node_b = "bob2"
position = [0.0, 0.0, -1.0]
axis = [0.0, 1.0, 0.0]

[[analyses]]
name = "hang"
type = "static"

[[analyses]]
name = "modes"
type = "modal"
start_from = "hang"
n_modes = 2
"#;

/// Runs every analysis of `m` to memory; the last summary and history.
fn run_all(m: &Model) -> Vec<(samara::analysis::AnalysisSummary, History)> {
    let sys = System::new(m);
    samara::analysis::run_all(m, &sys, |_| Ok(History::default()), |_, _| {}).unwrap()
}

#[test]
fn constrained_double_pendulum_against_minimal_coordinates() {
    // Minimal coordinates: absolute arm angles θ1, θ2 (l = 1), each bob turning with its
    // arm: M = [[m1l² + J1 + m2l², m2l²], [m2l², m2l² + J2]], K = diag((m1 + m2)gl, m2gl).
    // The constrained model gets its gravity stiffness only through the joint reactions
    // (∂(Bᵀλ)/∂q at the multipliers of the static solution), so this checks those too.
    let (m1, m2, j1, j2, g, l) = (1.0f64, 0.5f64, 1e-3, 2e-3, 9.81, 1.0);
    let mm = nalgebra::Matrix2::new(
        m1 * l * l + j1 + m2 * l * l,
        m2 * l * l,
        m2 * l * l,
        m2 * l * l + j2,
    );
    let kk = nalgebra::Matrix2::new((m1 + m2) * g * l, 0.0, 0.0, m2 * g * l);
    // det(K − ω²M) = 0: a quadratic in ω².
    let a = mm.determinant();
    let b = -(kk[(0, 0)] * mm[(1, 1)] + kk[(1, 1)] * mm[(0, 0)] - 2.0 * kk[(0, 1)] * mm[(0, 1)]);
    let c = kk.determinant();
    let disc = (b * b - 4.0 * a * c).sqrt();
    let exact = [
        ((-b - disc) / (2.0 * a)).sqrt(),
        ((-b + disc) / (2.0 * a)).sqrt(),
    ];
    let m = model(DOUBLE_PENDULUM);
    let out = run_all(&m);
    let sys = System::new(&m);
    let state = out[0].0.final_state.clone();
    let lin = linearize(&sys, &state, None);
    for method in [EigenMethod::Dense, EigenMethod::Sparse] {
        let s = modes(
            &lin,
            &EigenOptions {
                n_modes: 2,
                shift: None,
                method,
            },
        )
        .unwrap();
        for (mode, w) in s.modes.iter().zip(exact) {
            let err = (2.0 * PI * mode.frequency() - w).abs() / w;
            eprintln!(
                "double pendulum {method:?}: {} vs {w}: {err:.2e}",
                2.0 * PI * mode.frequency()
            );
            // The static solution is converged to 1e-8 m: the multipliers, hence the
            // gravity stiffness, to about that relative accuracy.
            assert!(err < 1e-7, "{method:?}: {err:e}");
            assert!(mode.damping_ratio().abs() < 1e-9);
        }
    }
    // Through the stage: the arrays of the modal analysis.
    let h = &out[1].1;
    let f = &h
        .arrays
        .iter()
        .find(|a| a.0.name == "frequency")
        .expect("frequency array")
        .1;
    assert!((2.0 * PI * f[0] - exact[0]).abs() / exact[0] < 1e-7);
    // Only two degrees of freedom: a third mode is refused, not invented.
    let err = modes(
        &lin,
        &EigenOptions {
            n_modes: 3,
            shift: None,
            method: EigenMethod::Dense,
        },
    );
    assert!(
        matches!(
            err,
            Err(EigenError::TooManyModes {
                requested: 3,
                dof: 2
            })
        ),
        "{err:?}"
    );
}

const FREE_BODY: &str = r#"
[model]
name = "free_body"

[[nodes]]
name = "c"
position = [0.3, -0.2, 0.5]
orientation = { rotation_vector = [1.2, 1.2, 1.2] }

[[bodies]]
name = "b"
node = "c"
mass = 3.0
inertia = [[1.0, 0.1, 0.0], [0.1, 2.0, 0.2], [0.0, 0.2, 3.0]]

[[analyses]]
name = "modes"
type = "modal"
n_modes = 6
"#;

#[test]
fn free_body_has_six_zero_modes_and_nothing_else() {
    let m = model(FREE_BODY);
    let sys = System::new(&m);
    let lin = linearize(&sys, &sys.initial_state(), None);
    for method in [EigenMethod::Dense, EigenMethod::Sparse] {
        let s = modes(
            &lin,
            &EigenOptions {
                n_modes: 6,
                shift: None,
                method,
            },
        )
        .unwrap();
        assert_eq!(s.modes.len(), 6);
        assert!(
            s.modes.iter().all(|m| m.rigid && m.frequency() == 0.0),
            "{method:?}"
        );
        // The six shapes span all six rigid-body motions.
        let mut a = nalgebra::DMatrix::<f64>::zeros(6, 6);
        for (j, md) in s.modes.iter().enumerate() {
            for i in 0..6 {
                a[(i, j)] = md.shape[i].re;
            }
        }
        let sv = a.singular_values();
        assert!(
            sv.min() > 1e-6 * sv.max(),
            "{method:?}: rigid shapes dependent {sv}"
        );
    }
    let e = modes(
        &lin,
        &EigenOptions {
            n_modes: 7,
            shift: None,
            method: EigenMethod::Dense,
        },
    );
    assert!(matches!(
        e,
        Err(EigenError::TooManyModes {
            requested: 7,
            dof: 6
        })
    ));
}

#[test]
fn free_free_beam_six_rigid_modes_then_bending() {
    // Free-free slender beam: 6 zero modes, then the first flap and lag bending modes at
    // (4.7300407)² √(EI/mL⁴) (Euler–Bernoulli; slender, so within 1e-5), nothing between.
    let (len, ei2, ei3, ga, ea, gj) = (1.0f64, 1.0, 4.0, 1e7, 1e7, 0.8);
    let (m, rho_j, rho_i) = (1.0f64, 2e-7, 1e-7);
    let text = cantilever(
        len,
        9,
        1,
        [ea, ga, ga, gj, ei2, ei3],
        [m, m, m, rho_j, rho_i, rho_i],
    );
    let cut = text.find("[[joints]]").unwrap();
    let end = text.find("[[analyses]]").unwrap();
    let text = format!("{}{}", &text[..cut], &text[end..]);
    let mdl = model(&text);
    let b = 4.730_040_744_862_704f64;
    let flap = b * b * (ei2 / (m * len.powi(4))).sqrt();
    let lag = b * b * (ei3 / (m * len.powi(4))).sqrt();
    let dense = omegas(&mdl, 8, EigenMethod::Dense);
    let sparse = omegas(&mdl, 8, EigenMethod::Sparse);
    eprintln!("free-free dense {dense:?}\nsparse {sparse:?}");
    for w in [&dense, &sparse] {
        assert!(w[..6].iter().all(|x| *x == 0.0));
        assert!((w[6] - flap).abs() / flap < 1e-5, "{w:?}");
        assert!((w[7] - lag).abs() / lag < 1e-5, "{w:?}");
    }
}

#[test]
fn dense_and_sparse_paths_agree() {
    // Roll-up beam, 4 elements of order 6 (repeated bending frequencies), 12 modes.
    let (len, ei, kga, ea, gj, m, ri, rj): (f64, f64, f64, f64, f64, f64, f64, f64) =
        (10.0, 100.0, 1e4, 1e4, 200.0, 1.0, 1.0, 2.0);
    let mdl = model(&cantilever(
        len,
        6,
        4,
        [ea, kga, kga, gj, ei, ei],
        [m, m, m, rj, ri, ri],
    ));
    let d = omegas(&mdl, 12, EigenMethod::Dense);
    let s = omegas(&mdl, 12, EigenMethod::Sparse);
    let err = d
        .iter()
        .zip(&s)
        .map(|(a, b)| (a - b).abs() / a)
        .fold(0.0, f64::max);
    eprintln!("dense vs sparse, 12 modes of a 4-element beam: {err:.2e}");
    // Both solve to round-off of the eigenproblem (Krylov–Schur residual 1e-11).
    assert!(err < 1e-9, "{d:?}\n{s:?}");
}

/// Issue #14 test 3, in the frame turning with the rotor: a rigid disk (m, polar Ip, diametral Id) spinning at
/// Ω at the tip of a massless, shear-rigid cantilever shaft (Stodola–Green rotor). With the
/// shaft's tip stiffness `K = EI/L³ [12 −6L; −6L 4L²]` acting on the tip deflection r and
/// slope θ (complex whirl coordinates), the whirl frequencies ω solve
/// `(k₁₁ − mω²)(k₂₂ − I_d ω² + I_p Ω ω) − k₁₂² = 0`: two forward (ω > 0) and two
/// backward (ω < 0) roots, which split as Ω grows (gyroscopic stiffening/softening).
/// The spinning nodes' material rotations turn with the rotor, so the linearized equations
/// are time-invariant only in the rotating frame (`SteadyRotation`), where a whirl is seen
/// at ω − Ω. Tolerance 2e-5: the model's shear stiffness (1e9 against 12EI/L² = 2.4e4)
/// shifts the frequencies by ~1e-5 from the Euler–Bernoulli closed form.
#[test]
fn spinning_disk_on_a_shaft_forward_and_backward_whirl() {
    let (len, ei, m, ip, id) = (1.0f64, 2.0e3, 5.0, 0.4, 0.25);
    let text = format!(
        r#"
[model]
name = "stodola_green"

[[beams]]
name = "shaft"
order = 4
elements = 1
points = [[0.0, 0.0, 0.0], [0.0, 0.0, {len}]]
root = "root"
tip = "disk"

[[beams.sections]]
station = 0.0
stiffness = [
  [1e9, 0.0, 0.0, 0.0, 0.0, 0.0],
  [0.0, 1e9, 0.0, 0.0, 0.0, 0.0],
  [0.0, 0.0, 1e9, 0.0, 0.0, 0.0],
  [0.0, 0.0, 0.0, 1e6, 0.0, 0.0],
  [0.0, 0.0, 0.0, 0.0, {ei}, 0.0],
  [0.0, 0.0, 0.0, 0.0, 0.0, {ei}],
]

[[bodies]]
name = "disk"
node = "disk"
mass = {m}
inertia = [[{ip}, 0.0, 0.0], [0.0, {id}, 0.0], [0.0, 0.0, {id}]]

[[joints]]
name = "clamp"
type = "fixed"
node_a = "ground"
node_b = "root"

[[analyses]]
name = "modes"
type = "modal"
n_modes = 4
"#
    );
    let mdl = model(&text);
    let sys = System::new(&mdl);
    let (k11, k12, k22) = (
        12.0 * ei / len.powi(3),
        -6.0 * ei / len.powi(2),
        4.0 * ei / len,
    );
    for omega in [0.0, 20.0, 60.0] {
        // Closed form: roots of the quartic, by bisection on a fine grid of ω.
        let f = |w: f64| (k11 - m * w * w) * (k22 - id * w * w + ip * omega * w) - k12 * k12;
        let mut roots = Vec::new();
        let (mut w0, dw) = (-400.0f64, 1e-3);
        while w0 < 400.0 {
            let w1 = w0 + dw;
            if f(w0).signum() != f(w1).signum() {
                let (mut a, mut b) = (w0, w1);
                for _ in 0..100 {
                    let c = 0.5 * (a + b);
                    if f(c).signum() == f(a).signum() {
                        a = c
                    } else {
                        b = c
                    }
                }
                // In the frame turning with the rotor (where the linearized equations of
                // the spinning, material-frame rotations are time-invariant), a whirl
                // e^{iωt} is seen at ω − Ω.
                roots.push((0.5 * (a + b) - omega).abs());
            }
            w0 = w1;
        }
        roots.sort_by(f64::total_cmp);
        assert_eq!(roots.len(), 4, "{roots:?}");
        let mut state = sys.initial_state();
        let rot = samara::linear::SteadyRotation {
            axis: nalgebra::Vector3::z(),
            omega,
            centre: nalgebra::Vector3::zeros(),
        };
        rot.impose(&sys, &mut state);
        let lin = linearize(&sys, &state, Some(&rot));
        for method in [EigenMethod::Dense, EigenMethod::Sparse] {
            let s = modes(
                &lin,
                &EigenOptions {
                    n_modes: 4,
                    shift: None,
                    method,
                },
            )
            .unwrap();
            let mut w: Vec<f64> = s.modes.iter().map(|m| 2.0 * PI * m.frequency()).collect();
            w.sort_by(f64::total_cmp);
            let err = w
                .iter()
                .zip(&roots)
                .map(|(a, b)| (a - b).abs() / b)
                .fold(0.0, f64::max);
            eprintln!("Ω = {omega}: {method:?} {w:?} vs {roots:?}: {err:.2e}");
            // Shear and axial stiffness 1e9 against EI/L² = 2e3: the shaft is Euler–Bernoulli
            // to ~1e-6; p = 4 represents the cubic static deflection exactly.
            assert!(err < 2e-5, "Ω = {omega} {method:?}: {err:e}");
        }
    }
}
