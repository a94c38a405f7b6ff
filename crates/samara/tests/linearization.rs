//! Verification test 7 of issue #14: the linearized matrices (M, G = C + MA₁,
//! K_lin = K + CA_v + MA₀, B) of whole models about a deformed, spinning state against
//! central differences of the nonlinear residual, perturbed along the exact motion of the
//! rotating-frame unknowns (translations measured in the frame turning with the rotor,
//! material rotations), built here independently of the library's kinematic maps:
//!
//! - configuration: `x' = x + u`, `R' = R exp(φ̃)`, and the rates of the rigid rotation
//!   through the perturbed configuration, `v' = Ω × (x' − c)`, `a' = Ω × v'`, `w' = R'ᵀΩ`;
//! - rates (y = 0): `v' = v + u̇`, `a' = a + 2Ω × u̇`, `w' = w + φ̇`, `ẇ' = w × φ̇`;
//! - accelerations: `a' = a + ü`, `ẇ' = ẇ + φ̈`.
//!
//! Tolerance 1e-6 relative to the largest entry of each matrix, as in
//! tests/system_matrices.rs: central differences with ε = 1e-6 in the configuration
//! (truncation O(ε²), round-off O(u/ε) ≈ 1e-10); rates and accelerations enter the
//! residual at most quadratically, so ε = 1e-2 is exact up to round-off. A missing
//! Coriolis, centrifugal or w̃ term is of the order of the entries themselves.

use crate::common;
use common::{Lcg, model_file};
use faer::sparse::SparseColMat;
use nalgebra::{DMatrix, Vector3};
use samara::core::State;
use samara::linear::{SteadyRotation, linearize, matrix_market};
use samara::system::System;

fn dense(a: &SparseColMat<usize, f64>) -> DMatrix<f64> {
    let mut d = DMatrix::zeros(a.nrows(), a.ncols());
    let r = a.as_ref();
    for j in 0..a.ncols() {
        for (&i, &v) in r.row_idx_of_col_raw(j).iter().zip(r.val_of_col(j)) {
            d[(i, j)] += v;
        }
    }
    d
}

#[derive(Clone, Copy, PartialEq, Debug)]
enum Channel {
    Configuration,
    Rate,
    Acceleration,
}

fn perturbed(
    sys: &System,
    s0: &State,
    rot: &SteadyRotation,
    i: usize,
    h: f64,
    ch: Channel,
) -> State {
    let mut s = s0.clone();
    let om = rot.angular_velocity();
    let n6 = 6 * sys.n_nodes();
    let nc = sys.n_coordinates;
    if i < n6 {
        let nd = &mut s.nodes[i / 6];
        let mut e = Vector3::zeros();
        e[i % 3] = h;
        let translation = i % 6 < 3;
        match ch {
            Channel::Configuration => {
                if translation {
                    nd.x += e;
                    nd.v = om.cross(&(nd.x - rot.centre));
                    nd.a = om.cross(&nd.v);
                } else {
                    nd.rot = nd.rot.compose_exp(&e);
                    nd.w = nd.r().transpose() * om;
                }
            }
            Channel::Rate => {
                if translation {
                    nd.v += e;
                    nd.a += 2.0 * om.cross(&e);
                } else {
                    nd.wd += nd.w.cross(&e);
                    nd.w += e;
                }
            }
            Channel::Acceleration => {
                if translation {
                    nd.a += e;
                } else {
                    nd.wd += e;
                }
            }
        }
    } else if i < n6 + nc {
        let c = &mut s.coords[i - n6];
        match ch {
            Channel::Configuration => c.q += h,
            Channel::Rate => c.v += h,
            Channel::Acceleration => c.a += h,
        }
    } else {
        let z = &mut s.states[i - n6 - nc];
        match ch {
            Channel::Configuration => z.z += h,
            Channel::Rate => z.zd += h,
            Channel::Acceleration => {}
        }
    }
    s
}

/// The model's initial state deformed at random, with random multipliers, then set
/// spinning rigidly at `rot`.
fn deformed_spinning(sys: &System, rot: &SteadyRotation, rng: &mut Lcg) -> State {
    let mut s = sys.initial_state();
    for n in &mut s.nodes {
        n.x += rng.vec3(1e-2);
        n.rot = n.rot.compose_exp(&rng.vec3(2e-2));
    }
    for c in &mut s.coords {
        c.q += 0.01 * rng.next();
    }
    for z in &mut s.states {
        z.z = rng.next();
    }
    for l in &mut s.lambda {
        *l = 100.0 * rng.next();
    }
    rot.impose(sys, &mut s);
    s.time = 0.3;
    s
}

fn check(path: &str, rot: SteadyRotation) {
    let m = model_file(path);
    let sys = System::new(&m);
    let state = deformed_spinning(&sys, &rot, &mut Lcg(11));
    let lin = linearize(&sys, &state, Some(&rot));
    let n = lin.n;
    assert_eq!(lin.unknown_names.len(), n);
    let ctx = sys.context(state.time, 1.0);
    let b = dense(&lin.constraint_jacobian);
    for (ch, a) in [
        (Channel::Configuration, dense(&lin.stiffness)),
        (Channel::Rate, dense(&lin.damping)),
        (Channel::Acceleration, dense(&lin.mass)),
    ] {
        let eps = if ch == Channel::Configuration {
            1e-6
        } else {
            1e-2
        };
        let mut fd = DMatrix::zeros(n, n);
        let mut bfd = DMatrix::zeros(lin.m, n);
        for j in 0..n {
            let p = sys.matrices(&ctx, &perturbed(&sys, &state, &rot, j, eps, ch));
            let q = sys.matrices(&ctx, &perturbed(&sys, &state, &rot, j, -eps, ch));
            for i in 0..n {
                fd[(i, j)] = (p.residual[i] - q.residual[i]) / (2.0 * eps);
            }
            for i in 0..lin.m {
                bfd[(i, j)] = (p.constraint_values[i] - q.constraint_values[i]) / (2.0 * eps);
            }
        }
        let scale = a.amax().max(fd.amax());
        assert!(scale > 0.0);
        let err = (&a - &fd).amax() / scale;
        eprintln!("{path} {ch:?}: max relative difference {err:.2e}");
        assert!(err < 1e-6, "{path}: {ch:?} mismatch {err:e}");
        if ch == Channel::Configuration {
            let err = (&b - &bfd).amax() / b.amax().max(1.0);
            assert!(err < 1e-6, "{path}: B mismatch {err:e}");
        }
    }
    // Without the rotating frame the Coriolis terms are gone: the test can fail.
    let inertial = linearize(&sys, &state, None);
    let diff = (dense(&inertial.damping) - dense(&lin.damping)).amax();
    assert!(diff > 1e-3 * dense(&lin.damping).amax().max(1.0));
}

#[test]
fn spinning_blade_on_hub() {
    check(
        "examples/blade_spinup.toml",
        SteadyRotation {
            axis: Vector3::z(),
            omega: 3.0,
            centre: Vector3::zeros(),
        },
    );
}

#[test]
fn landing_gear_with_coordinate_elements_spinning_off_axis() {
    check(
        "examples/landing_gear.toml",
        SteadyRotation {
            axis: Vector3::new(1.0, 2.0, 2.0) / 3.0,
            omega: 1.5,
            centre: Vector3::new(0.3, -0.2, 0.1),
        },
    );
}

#[test]
fn matrix_market_round_trip() {
    let m = model_file("examples/blade_spinup.toml");
    let sys = System::new(&m);
    let lin = linearize(&sys, &sys.initial_state(), None);
    let mut buf = Vec::new();
    matrix_market::write(&mut buf, &lin.stiffness, &["K".to_string()]).unwrap();
    let back = matrix_market::read(std::str::from_utf8(&buf).unwrap()).unwrap();
    let (a, b) = (dense(&lin.stiffness), dense(&back));
    assert!((&a - &b).amax() <= 1e-15 * a.amax());
}
