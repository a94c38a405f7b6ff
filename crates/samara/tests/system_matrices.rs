//! The separately assembled M, C, K, B (System::matrices) of whole models against central
//! differences of the assembled residual and constraint values, at a moving, deformed
//! state away from equilibrium; and the Newton assembler's residual equals `r + Bᵀλ`, `Φ`
//! assembled the separate way (issue #11: one set of tangents, combined per formulation).
//!
//! Tolerance 1e-6 relative to the largest entry of each matrix. In the configuration,
//! central differences with ε = 1e-6 have truncation O(ε²) and round-off O(u/ε) ~ 1e-10
//! of the residual. The residual is at most quadratic in the rates (gyroscopic and
//! centrifugal terms) and linear in the accelerations, so there the central difference is
//! exact in exact arithmetic and a step of 1e-2 keeps the round-off (u|r|/ε, with |r| up
//! to 1e6 in a stiff beam) far below the entries of C and M. A wrong or missing term
//! shows at ≥ 1e-3.

use crate::common;
use common::{Lcg, model_file};
use faer::sparse::SparseColMat;
use nalgebra::{DMatrix, Vector3};
use samara::core::State;
use samara::system::{Assembler, Coefficients, Formulation, System};

const EPS: f64 = 1e-6;

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

/// Which derivative a perturbation takes.
#[derive(Clone, Copy, PartialEq)]
enum Channel {
    Configuration,
    Rate,
    Acceleration,
}

/// `state` with configuration unknown `i` moved by `h` in `channel`.
fn perturbed(sys: &System, state: &State, i: usize, h: f64, channel: Channel) -> State {
    let mut s = state.clone();
    let n6 = 6 * sys.n_nodes();
    let nc = sys.n_coordinates;
    if i < n6 {
        let nd = &mut s.nodes[i / 6];
        let mut e = Vector3::zeros();
        e[i % 3] = h;
        match (channel, i % 6 < 3) {
            (Channel::Configuration, true) => nd.x += e,
            (Channel::Configuration, false) => nd.rot = nd.rot.compose_exp(&e),
            (Channel::Rate, true) => nd.v += e,
            (Channel::Rate, false) => nd.w += e,
            (Channel::Acceleration, true) => nd.a += e,
            (Channel::Acceleration, false) => nd.wd += e,
        }
    } else if i < n6 + nc {
        let c = &mut s.coords[i - n6];
        match channel {
            Channel::Configuration => c.q += h,
            Channel::Rate => c.v += h,
            Channel::Acceleration => c.a += h,
        }
    } else {
        let z = &mut s.states[i - n6 - nc];
        match channel {
            Channel::Configuration => z.z += h,
            Channel::Rate => z.zd += h,
            Channel::Acceleration => {}
        }
    }
    s
}

/// A moving, deformed state: the model's initial state with random velocities,
/// accelerations, multipliers, coordinate rates, states and small displacements.
fn stirred(sys: &System, rng: &mut Lcg) -> State {
    let mut s = sys.initial_state();
    for n in &mut s.nodes {
        n.x += rng.vec3(1e-3);
        n.rot = n.rot.compose_exp(&rng.vec3(1e-2));
        n.v = rng.vec3(0.5);
        n.w = rng.vec3(0.5);
        n.a = rng.vec3(0.5);
        n.wd = rng.vec3(0.5);
    }
    for c in &mut s.coords {
        c.q += 0.01 * rng.next();
        c.v = rng.next();
        c.a = rng.next();
    }
    for z in &mut s.states {
        z.z = rng.next();
        z.zd = rng.next();
    }
    for l in &mut s.lambda {
        *l = 10.0 * rng.next();
    }
    s.time = 0.37;
    s
}

fn check(path: &str) {
    let m = model_file(path);
    let sys = System::new(&m);
    let mut rng = Lcg(3);
    let state = stirred(&sys, &mut rng);
    let ctx = sys.context(state.time, 1.0);
    let mats = sys.matrices(&ctx, &state);
    let n = mats.n;
    let analytic = [
        (Channel::Configuration, dense(&mats.stiffness)),
        (Channel::Rate, dense(&mats.damping)),
        (Channel::Acceleration, dense(&mats.mass)),
    ];
    let b = dense(&mats.constraint_jacobian);
    for (channel, a) in &analytic {
        let mut fd = DMatrix::zeros(n, n);
        let mut bfd = DMatrix::zeros(mats.m, n);
        let eps = if *channel == Channel::Configuration {
            EPS
        } else {
            1e-2
        };
        for j in 0..n {
            let p = sys.matrices(&ctx, &perturbed(&sys, &state, j, eps, *channel));
            let q = sys.matrices(&ctx, &perturbed(&sys, &state, j, -eps, *channel));
            for i in 0..n {
                fd[(i, j)] = (p.residual[i] - q.residual[i]) / (2.0 * eps);
            }
            for i in 0..mats.m {
                bfd[(i, j)] = (p.constraint_values[i] - q.constraint_values[i]) / (2.0 * eps);
            }
        }
        // Column blocks of 3 (node translations/rotations) or 1.
        let scale = a.amax().max(fd.amax()).max(1e-300);
        let diff = a - &fd;
        let err = diff.amax() / scale;
        if err >= 1e-6 {
            let (mut bi, mut bj, mut bv) = (0, 0, 0.0);
            for j in 0..n {
                for i in 0..n {
                    if diff[(i, j)].abs() > bv {
                        bv = diff[(i, j)].abs();
                        bi = i;
                        bj = j;
                    }
                }
            }
            eprintln!(
                "worst at ({bi}, {bj}): analytic {} fd {} (n6 = {}, nc = {})",
                a[(bi, bj)],
                fd[(bi, bj)],
                6 * sys.n_nodes(),
                sys.n_coordinates
            );
        }
        assert!(err < 1e-6, "{path}: {:?} mismatch {err:e}", *channel as u8);
        if *channel == Channel::Configuration {
            let err = (&b - &bfd).amax() / b.amax().max(1.0);
            assert!(err < 1e-6, "{path}: B mismatch {err:e}");
        }
    }
    // The Newton assembler (statics coefficients, no penalty) gives the same residual.
    let mut asm = Assembler::new(&sys, Formulation::Index3);
    let mut res = vec![0.0; asm.n_unknowns()];
    asm.assemble(
        &sys,
        &state,
        &ctx,
        &Coefficients::statics(0.0),
        &[],
        &mut res,
        None,
    );
    let mut cfg = vec![0.0; n];
    asm.configuration_of(&sys, &res, &mut cfg);
    let rmax = mats.residual.iter().fold(1.0f64, |m, x| m.max(x.abs()));
    for (a, b) in cfg.iter().zip(&mats.residual) {
        assert!((a - b).abs() < 1e-12 * rmax, "{path}: residual {a} vs {b}");
    }
    let mut phi = vec![0.0; sys.n_multipliers];
    asm.multipliers_of(&sys, &res, &mut phi);
    for (a, b) in phi.iter().zip(&mats.constraint_values) {
        assert!((a - b).abs() < 1e-14, "{path}: Φ {a} vs {b}");
    }
}

#[test]
fn slider_crank() {
    check("examples/slider_crank.toml");
}

#[test]
fn landing_gear_with_coordinate_elements() {
    check("examples/landing_gear.toml");
}

#[test]
fn curved_beam_with_a_body() {
    check("examples/blade_spinup.toml");
}

#[test]
fn active_suspension_with_states_and_signals() {
    check("examples/active_suspension.toml");
}

/// A servo row (`drive_signal`): B carries −∂s/∂x of the controller's output.
#[test]
fn servo_follower() {
    check("examples/control/servo_follower.toml");
}
