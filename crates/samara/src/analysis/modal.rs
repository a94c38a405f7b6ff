//! Modal analysis (`type = "modal"`): the equations linearized about the starting state
//! ([`crate::linear::linearize`]) and their constrained quadratic eigenproblem
//! ([`crate::linear::eigen`]). The starting state is the model's initial state or the
//! final state of an earlier analysis (`start_from`): a static equilibrium, or the last
//! instant of a dynamic run.
//!
//! With `rotation`, the starting state is set spinning rigidly about the axis
//! ([`crate::linear::SteadyRotation::impose`]) and the equations are written in the frame
//! turning with it, where those of a steadily spinning axisymmetric rotor are
//! time-invariant (frequencies are rotating-frame frequencies). The state is not
//! re-equilibrated: a rotor with centrifugal stresses should start from a state that
//! has them (a dynamic run spun up to steady speed).
//!
//! Results: one time record (the reference state) and the arrays `frequency(mode)`,
//! `damped_frequency(mode)`, `damping_ratio(mode)`, `eigenvalue(mode, 2)` and
//! `mode_shape(mode, node, 6, 2)` (see docs/results.md). With `write_matrices`, the
//! matrices M, G, K, B are written as Matrix Market files beside the results file.

use super::{AnalysisSummary, ArraySpec, Energy, OutputFrame, Progress, Recorder, SolverFailure};
use crate::core::State;
use crate::linear::eigen::{EigenMethod, EigenOptions, Mode};
use crate::linear::{LinearSystem, linearize, matrix_market};
use crate::model::{EigensolverType, ModalSettings};
use crate::system::System;
use std::path::Path;
use std::time::Instant;

/// The eigen-options of the model settings.
pub fn eigen_options(s: &ModalSettings) -> EigenOptions {
    EigenOptions {
        n_modes: s.n_modes,
        shift: s.shift,
        method: match s.eigensolver {
            EigensolverType::Auto => EigenMethod::Auto,
            EigensolverType::Dense => EigenMethod::Dense,
            EigensolverType::Sparse => EigenMethod::Sparse,
        },
    }
}

/// The arrays of a modal analysis with `n_modes` modes.
pub fn modal_arrays(sys: &System, n_modes: usize, prefix: &str) -> Vec<ArraySpec> {
    let mode = ("mode".to_string(), n_modes);
    let spec = |name: &str, dims: Vec<(String, usize)>, units: &str, long: &str| ArraySpec {
        name: format!("{prefix}{name}"),
        dims,
        units: units.into(),
        long_name: long.into(),
    };
    vec![
        spec(
            "frequency",
            vec![mode.clone()],
            "Hz",
            "natural frequency |lambda|/(2 pi); 0 for rigid-body modes",
        ),
        spec(
            "damped_frequency",
            vec![mode.clone()],
            "Hz",
            "damped frequency |Im lambda|/(2 pi)",
        ),
        spec(
            "damping_ratio",
            vec![mode.clone()],
            "1",
            "damping ratio -Re lambda/|lambda| (negative: unstable)",
        ),
        spec(
            "eigenvalue",
            vec![mode.clone(), ("complex".into(), 2)],
            "rad/s",
            "eigenvalue lambda (real, imaginary)",
        ),
        spec(
            "mode_shape",
            vec![
                mode,
                ("node".into(), sys.n_nodes()),
                ("dof6".into(), 6),
                ("complex".into(), 2),
            ],
            "m, rad",
            "mode shape per node: displacement (x, y, z) and rotation vector (x, y, z) in global axes, (real, imaginary); largest component 1",
        ),
    ]
}

/// The values of [`modal_arrays`] for `modes`, in the same order. Node rotations are
/// turned from material to global components (`R φ`) and the shape is scaled so that
/// its node component of largest modulus is 1.
pub fn modal_values(sys: &System, state: &State, modes: &[Mode]) -> Vec<Vec<f64>> {
    let nn = sys.n_nodes();
    let mut out = vec![Vec::new(); 5];
    for m in modes {
        out[0].push(m.frequency());
        out[1].push(m.damped_frequency());
        out[2].push(m.damping_ratio());
        out[3].extend([m.eigenvalue.re, m.eigenvalue.im]);
        let mut shape = Vec::with_capacity(12 * nn);
        for (i, node) in state.nodes.iter().enumerate() {
            let y = &m.shape[6 * i..6 * i + 6];
            let r = node.r();
            let mut c = [faer::c64::new(0.0, 0.0); 6];
            c[..3].copy_from_slice(&y[..3]);
            for a in 0..3 {
                for b in 0..3 {
                    c[3 + a] += y[3 + b] * r[(a, b)];
                }
            }
            shape.extend(c);
        }
        let big = shape
            .iter()
            .copied()
            .max_by(|a, b| a.norm().total_cmp(&b.norm()))
            .filter(|z| z.norm() > 0.0)
            .unwrap_or(faer::c64::new(1.0, 0.0));
        for z in shape {
            let z = z / big;
            out[4].extend([z.re, z.im]);
        }
    }
    out
}

/// Writes `lin`'s matrices as `<dir>/<name>.{M,G,K,B}.mtx` (an existing file of that name
/// is moved aside to `<name>.{X}.~k~.mtx`, never overwritten).
pub fn write_matrices(dir: &Path, name: &str, lin: &LinearSystem) -> Result<(), crate::Error> {
    let header = |what: &str| {
        vec![
            format!("samara {}: {what} of analysis '{name}'", crate::VERSION),
            format!(
                "unknowns: {}",
                lin.unknown_names
                    .iter()
                    .enumerate()
                    .map(|(i, n)| format!("{}={n}", i + 1))
                    .collect::<Vec<_>>()
                    .join(" ")
            ),
        ]
    };
    for (tag, what, a) in [
        ("M", "mass matrix M", &lin.mass),
        ("G", "damping and gyroscopic matrix G", &lin.damping),
        (
            "K",
            "stiffness matrix K (elastic, geometric, centrifugal)",
            &lin.stiffness,
        ),
        (
            "B",
            "constraint Jacobian B (rows: constraint equations)",
            &lin.constraint_jacobian,
        ),
    ] {
        let path = dir.join(format!("{name}.{tag}.mtx"));
        if path.exists() {
            let aside = (1..)
                .map(|k| dir.join(format!("{name}.{tag}.~{k}~.mtx")))
                .find(|p| !p.exists())
                .expect("some backup name is free");
            std::fs::rename(&path, &aside).map_err(|source| crate::Error::Io {
                path: path.clone(),
                action: "move aside",
                source,
            })?;
        }
        let io = |source| crate::Error::Io {
            path: path.clone(),
            action: "write",
            source,
        };
        let file = std::fs::File::create(&path).map_err(io)?;
        let mut w = std::io::BufWriter::new(file);
        matrix_market::write(&mut w, a, &header(what)).map_err(io)?;
        std::io::Write::flush(&mut w).map_err(io)?;
    }
    Ok(())
}

/// Runs a modal analysis from `initial`.
pub fn run_modal(
    sys: &System,
    name: &str,
    settings: &ModalSettings,
    initial: State,
    recorder: &mut dyn Recorder,
    progress: Progress,
) -> Result<AnalysisSummary, crate::Error> {
    let clock = Instant::now();
    let mut summary = AnalysisSummary::new(name, "modal");
    let mut state = initial;
    if let Some(rot) = &settings.rotation {
        rot.impose(sys, &mut state);
    }
    let ctx = sys.context(state.time, 1.0);
    let lin = linearize(sys, &state, settings.rotation.as_ref());
    progress(0.2);
    if settings.write_matrices {
        match recorder.output_dir() {
            Some(dir) => write_matrices(&dir, name, &lin)?,
            None => summary.warnings.push(
                "write_matrices: this recorder has no output folder; the matrices were not written"
                    .into(),
            ),
        }
    }
    let mut phi = vec![0.0; sys.n_multipliers];
    sys.constraint_values(&ctx, &state, &mut phi);
    let violation = phi.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    recorder.record(
        sys,
        &OutputFrame {
            time: state.time,
            state: &state,
            mu: &state.lambda,
            energy: Energy {
                kinetic: sys.kinetic_energy(&state),
                potential: sys.potential_energy(&ctx, &state),
                external_work: 0.0,
                dissipated: 0.0,
            },
            constraint_violation: violation,
            load_factor: 1.0,
            diagnostics: None,
        },
    )?;
    match crate::linear::modes(&lin, &eigen_options(settings)) {
        Ok(spectrum) => {
            let values = modal_values(sys, &state, &spectrum.modes);
            for (spec, v) in modal_arrays(sys, settings.n_modes, "").iter().zip(&values) {
                recorder.write_array(sys, spec, v)?;
            }
            summary.steps = 1;
            summary.factorizations = 1;
        }
        Err(e) => {
            let hint = match &e {
                crate::linear::eigen::EigenError::NoMass => {
                    "give the bodies a mass and the beams a density or mass matrix".to_string()
                }
                crate::linear::eigen::EigenError::TooManyModes { dof, .. } => {
                    format!("lower `n_modes` of analysis '{name}' to at most {dof}")
                }
                _ => "check that every direction has mass or stiffness, or set `shift`".into(),
            };
            summary.failure = Some(SolverFailure {
                analysis: name.to_string(),
                time: state.time,
                reason: e.to_string(),
                hint: Some(hint),
            });
        }
    }
    progress(1.0);
    summary.max_constraint_violation = violation;
    summary.final_state = state;
    summary.wall_time = clock.elapsed();
    Ok(summary)
}
