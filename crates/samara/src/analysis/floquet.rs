//! Floquet stability analysis (`type = "floquet"`): the small motions about a periodic
//! solution of period T ([`crate::linear::floquet`]).
//!
//! The periodic solution is the one through the starting state (the model's initial
//! state, or with `start_from` the final state of an earlier analysis — typically a
//! dynamic run long enough for the transients to have died out): the analysis integrates
//! it over one period with the dynamic analyses' integrator (Lie-group generalized-α,
//! `steps_per_period` fixed steps, `rho_inf`), linearizes about every step
//! ([`crate::linear::linearize`], inertial frame) and integrates the linearized equations
//! along it with the same scheme and step to form the monodromy matrix.
//!
//! Checks before the result is trusted (failures with a hint, exit status 2):
//! - the loads are T-periodic: at the starting state, the residual and the stiffness and
//!   damping matrices at t₀ + s and t₀ + s + T agree (s = 0, T/3, 2T/3, relative 10⁻⁸),
//!   so a time function whose period does not divide T is caught;
//! - the motion closes: after one period, positions, orientations and rates return to
//!   their starting values within 10⁻³ (relative to the model's size, its largest rates,
//!   and 2π/T) — a driven hub whose speed does not make a whole number of turns in T, or
//!   a start that is not on the periodic solution, is caught.
//!
//! Results: one time record (the starting state) and the arrays
//! `floquet_multiplier(mode, 2)`, `floquet_modulus(mode)`, `floquet_exponent(mode, 2)`,
//! `frequency(mode)` and `damping_ratio(mode)` (docs/results.md), largest modulus first.

use super::{
    AnalysisSummary, ArraySpec, Energy, OutputFrame, Progress, Recorder, Simulation, SolverFailure,
};
use crate::core::State;
use crate::linear::floquet::{FloquetMode, monodromy};
use crate::linear::{LinearSystem, linearize};
use crate::model::{DynamicSettings, FloquetSettings};
use crate::system::System;
use std::time::Instant;

/// The arrays of a Floquet analysis with `n_modes` modes.
pub fn floquet_arrays(n_modes: usize) -> Vec<ArraySpec> {
    let mode = ("mode".to_string(), n_modes);
    let complex = ("complex".to_string(), 2);
    let spec = |name: &str, dims: Vec<(String, usize)>, units: &str, long: &str| ArraySpec {
        name: name.into(),
        dims,
        units: units.into(),
        long_name: long.into(),
    };
    vec![
        spec(
            "floquet_multiplier",
            vec![mode.clone(), complex.clone()],
            "1",
            "Floquet multiplier rho, eigenvalue of the monodromy matrix (real, imaginary); largest modulus first, NaN beyond the modes of the system",
        ),
        spec(
            "floquet_modulus",
            vec![mode.clone()],
            "1",
            "|rho|: above 1 unstable",
        ),
        spec(
            "floquet_exponent",
            vec![mode.clone(), complex],
            "rad/s",
            "characteristic exponent ln(rho)/T on the principal branch (real, imaginary); the imaginary part is known up to multiples of 2 pi/T",
        ),
        spec(
            "frequency",
            vec![mode.clone()],
            "Hz",
            "|lambda|/(2 pi) of the principal-branch exponent",
        ),
        spec(
            "damping_ratio",
            vec![mode],
            "1",
            "-Re lambda/|lambda| of the principal-branch exponent (negative: unstable)",
        ),
    ]
}

/// The values of [`floquet_arrays`] (NaN beyond the modes found).
pub fn floquet_values(modes: &[FloquetMode], n_modes: usize) -> Vec<Vec<f64>> {
    let mut out = vec![Vec::new(); 5];
    for k in 0..n_modes {
        match modes.get(k) {
            Some(m) => {
                out[0].extend([m.multiplier.re, m.multiplier.im]);
                out[1].push(m.modulus());
                out[2].extend([m.exponent.re, m.exponent.im]);
                out[3].push(m.frequency());
                out[4].push(m.damping_ratio());
            }
            None => {
                out[0].extend([f64::NAN; 2]);
                out[1].push(f64::NAN);
                out[2].extend([f64::NAN; 2]);
                out[3].push(f64::NAN);
                out[4].push(f64::NAN);
            }
        }
    }
    out
}

/// Largest relative difference of the loads (residual, K, C) at `state` between the
/// times t and t + T, over t = t₀, t₀ + T/3, t₀ + 2T/3 (each quantity relative to its
/// largest entry over all these times); with the time where it is largest.
pub fn load_periodicity(sys: &System, state: &State, period: f64) -> (f64, f64) {
    let t0 = state.time;
    // Per quantity: largest entry, and (largest difference, where).
    let mut scale = [0.0f64; 3];
    let mut diff = [(0.0f64, t0); 3];
    let mut structure = None;
    for k in 0..3 {
        let t = t0 + period * k as f64 / 3.0;
        let mut s = state.clone();
        s.time = t;
        let a = sys.matrices(&sys.context(t, 1.0), &s);
        s.time = t + period;
        let b = sys.matrices(&sys.context(t + period, 1.0), &s);
        let pairs: [(&[f64], &[f64]); 3] = [
            (&a.residual, &b.residual),
            (a.stiffness.as_ref().val(), b.stiffness.as_ref().val()),
            (a.damping.as_ref().val(), b.damping.as_ref().val()),
        ];
        for (q, (x, y)) in pairs.iter().enumerate() {
            if x.len() != y.len() {
                // A change of structure (an entry becoming exactly zero) is a change too.
                structure.get_or_insert(t);
                continue;
            }
            for (p, r) in x.iter().zip(y.iter()) {
                scale[q] = scale[q].max(p.abs()).max(r.abs());
                if (p - r).abs() > diff[q].0 {
                    diff[q] = ((p - r).abs(), t);
                }
            }
        }
    }
    if let Some(t) = structure {
        return (1.0, t);
    }
    (0..3)
        .map(|q| (diff[q].0 / scale[q].max(f64::MIN_POSITIVE), diff[q].1))
        .fold((0.0, t0), |w, x| if x.0 > w.0 { x } else { w })
}

/// How far the motion is from closing after one period: the largest of the position,
/// orientation and rate differences, each relative to its scale.
pub fn closure(a: &State, b: &State, period: f64) -> f64 {
    let centre = a
        .nodes
        .iter()
        .fold(nalgebra::Vector3::zeros(), |s, n| s + n.x)
        / a.nodes.len().max(1) as f64;
    let size = a
        .nodes
        .iter()
        .fold(0.0f64, |m, n| m.max((n.x - centre).norm()))
        .max(1e-3);
    let vmax = a.nodes.iter().fold(0.0f64, |m, n| m.max(n.v.norm()));
    let wmax = a.nodes.iter().fold(0.0f64, |m, n| m.max(n.w.norm()));
    let (vs, ws) = (vmax + size / period, wmax + std::f64::consts::TAU / period);
    let mut worst = 0.0f64;
    for (p, q) in a.nodes.iter().zip(&b.nodes) {
        let rel = p.r().transpose() * q.r();
        let angle = ((rel.trace() - 1.0) / 2.0).clamp(-1.0, 1.0).acos();
        worst = worst
            .max((p.x - q.x).norm() / size)
            .max(angle)
            .max((p.v - q.v).norm() / vs)
            .max((p.w - q.w).norm() / ws);
    }
    // Element states in their own units: relative to their size, absolute below 10⁻⁶.
    for (p, q) in a.states.iter().zip(&b.states) {
        worst = worst.max((p.z - q.z).abs() / p.z.abs().max(q.z.abs()).max(1e-6));
    }
    worst
}

/// Runs a Floquet analysis from `initial`.
pub fn run_floquet(
    sys: &System,
    name: &str,
    settings: &FloquetSettings,
    initial: State,
    recorder: &mut dyn Recorder,
    progress: Progress,
) -> Result<AnalysisSummary, crate::Error> {
    use rayon::prelude::*;
    let clock = Instant::now();
    let mut summary = AnalysisSummary::new(name, "floquet");
    let period = settings.period;
    let n = settings.steps_per_period;
    let h = period / n as f64;
    let t0 = initial.time;
    let fail = |summary: &mut AnalysisSummary, time: f64, reason: String, hint: &str| {
        summary.failure = Some(SolverFailure {
            analysis: name.to_string(),
            time,
            reason,
            hint: Some(hint.to_string()),
        });
    };
    let (d, at) = load_periodicity(sys, &initial, period);
    if d > 1e-8 {
        fail(
            &mut summary,
            t0,
            format!(
                "the period T = {period} s is not a period of the loads: the forces or tangents at t = {at} s and t + T differ by {d:.3e} (relative)"
            ),
            "`period` (or 2π/`speed`) must be a period of every time function of the model (a sine of frequency f repeats after k/f)",
        );
        summary.final_state = initial;
        summary.wall_time = clock.elapsed();
        return Ok(summary);
    }
    let mut dynamic = DynamicSettings::new(t0 + period, h, settings.rho_inf);
    dynamic.t_start = t0;
    dynamic.solver = settings.solver.clone();
    let mut states = Vec::with_capacity(n + 1);
    {
        let mut sim = match Simulation::new(sys, &dynamic, initial.clone()) {
            Ok(s) => s,
            Err(f) => {
                summary.failure = Some(SolverFailure {
                    analysis: name.to_string(),
                    ..f
                });
                summary.final_state = initial;
                summary.wall_time = clock.elapsed();
                return Ok(summary);
            }
        };
        states.push(sim.state().clone());
        for k in 0..n {
            match sim.step(h) {
                Ok(r) => {
                    summary.newton_iterations += r.newton_iterations;
                    summary.rejected_steps += r.rejected;
                    summary.max_constraint_violation =
                        summary.max_constraint_violation.max(r.constraint_violation);
                }
                Err(f) => {
                    summary.failure = Some(SolverFailure {
                        analysis: name.to_string(),
                        ..f
                    });
                    summary.final_state = sim.state().clone();
                    summary.wall_time = clock.elapsed();
                    return Ok(summary);
                }
            }
            let mut s = sim.state().clone();
            // On the grid exactly (the integrator lands there up to an ulp).
            s.time = t0 + (k + 1) as f64 * h;
            states.push(s);
            progress(0.5 * (k + 1) as f64 / n as f64);
        }
    }
    summary.steps = n;
    let c = closure(&states[0], &states[n], period);
    if c > 1e-3 {
        fail(
            &mut summary,
            t0 + period,
            format!(
                "the motion does not repeat after one period T = {period} s (difference {c:.3e}, relative): the starting state is not on a T-periodic solution"
            ),
            "check that `period` (or `speed`) matches the drives (a driven hub must turn a whole number of times in T), and start from a dynamic analysis run until the motion is periodic (`start_from`)",
        );
        summary.final_state = states.pop().unwrap_or(initial);
        summary.wall_time = clock.elapsed();
        return Ok(summary);
    }
    let systems: Vec<LinearSystem> = states.par_iter().map(|s| linearize(sys, s, None)).collect();
    progress(0.6);
    let start = &states[0];
    let ctx = sys.context(start.time, 1.0);
    let mut phi = vec![0.0; sys.n_multipliers];
    sys.constraint_values(&ctx, start, &mut phi);
    recorder.record(
        sys,
        &OutputFrame {
            time: start.time,
            state: start,
            mu: &start.lambda,
            energy: Energy {
                kinetic: sys.kinetic_energy(start),
                potential: sys.potential_energy(&ctx, start),
                external_work: 0.0,
                dissipated: 0.0,
            },
            constraint_violation: phi.iter().fold(0.0f64, |m, x| m.max(x.abs())),
            load_factor: 1.0,
            diagnostics: None,
        },
    )?;
    match monodromy(period, &systems, settings.rho_inf, sys.state_names.len()) {
        Ok(mono) => {
            if mono.modes.len() < settings.n_modes {
                summary.warnings.push(format!(
                    "the system has {} Floquet modes; the other {} of the n_modes = {} are NaN",
                    mono.modes.len(),
                    settings.n_modes - mono.modes.len(),
                    settings.n_modes
                ));
            }
            let values = floquet_values(&mono.modes, settings.n_modes);
            for (spec, v) in floquet_arrays(settings.n_modes).iter().zip(&values) {
                recorder.write_array(sys, spec, v)?;
            }
        }
        Err(e) => fail(
            &mut summary,
            t0,
            e.to_string(),
            "give every moving part a mass; element states must be first-order unknowns that no constraint acts on",
        ),
    }
    progress(1.0);
    summary.factorizations = n;
    summary.final_state = states.pop().unwrap_or(initial);
    summary.wall_time = clock.elapsed();
    Ok(summary)
}
