//! Campbell diagram (`type = "campbell"`): a sweep over rotor speed, each point a
//! spinning-rotor static analysis ([`super::run_static`] with a [`Spin`] of the whole
//! model) followed by the rotating-frame eigenanalysis about it ([`linearize`],
//! [`crate::linear::modes`]). The points are independent and computed in parallel
//! (rayon; the results do not depend on the number of threads).
//!
//! **Mode tracking.** The modes of each point are matched to the tracked modes of the
//! previous point by the modal assurance criterion of the complex shapes,
//! `MAC(a, b) = |aᴴb|² / ((aᴴa)(bᴴb))`: the pairs of largest MAC are taken first
//! (greedy assignment on the whole MAC matrix), so a mode keeps its identity through a
//! crossing (its shape does not change) and follows its shape through a veering. The
//! tracked modes are those of the first point, in its order (lowest first).
//!
//! **Labels.** For models with beams, each tracked mode is named at the first point by the
//! dominant share of its beam-node motion: flap (translation along the rotation axis),
//! lag (translation in the rotor plane, across the beam), axial (along the beam) and
//! torsion (rotation about the beam axis times the beam length / 2π, a rotation measured
//! as the arc it turns a point a radian-length away). A share above one half names the
//! mode; otherwise it is `mixed`.

use super::statics::run_static;
use super::{AnalysisSummary, ArraySpec, Energy, OutputFrame, Progress, Recorder, SolverFailure};
use crate::core::{Element, State};
use crate::linear::eigen::Mode;
use crate::linear::{Spin, SteadyRotation, linearize};
use crate::model::{CampbellSettings, StaticSettings};
use crate::system::System;
use faer::c64;
use nalgebra::Vector3;
use std::time::Instant;

/// Mode labels, in the order of their codes in `campbell_mode_label`.
pub const LABELS: [&str; 5] = ["mixed", "flap", "lag", "torsion", "axial"];

/// A recorder that keeps nothing (the static analyses of the points).
struct Discard;

impl Recorder for Discard {
    fn record(&mut self, _: &System, _: &OutputFrame) -> Result<(), crate::Error> {
        Ok(())
    }
    fn write_array(&mut self, _: &System, _: &ArraySpec, _: &[f64]) -> Result<(), crate::Error> {
        Ok(())
    }
}

/// One point of the sweep: its static state and its modes.
struct Point {
    state: State,
    modes: Vec<Mode>,
}

/// Modal assurance criterion of two complex shapes.
pub fn mac(a: &[c64], b: &[c64]) -> f64 {
    let (mut ab, mut aa, mut bb) = (c64::new(0.0, 0.0), 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        ab += x.conj() * y;
        aa += x.norm_sqr();
        bb += y.norm_sqr();
    }
    if aa == 0.0 || bb == 0.0 {
        0.0
    } else {
        ab.norm_sqr() / (aa * bb)
    }
}

/// Tracks modes across the points: `order[p][k]` is the index, among the modes of point
/// `p`, of tracked mode `k` (`None` when no mode of that point is left for it). The
/// tracked modes are those of point 0; each next point is matched to the shapes of the
/// previous one by greedy largest-MAC assignment.
pub fn track(points: &[Vec<Vec<c64>>]) -> Vec<Vec<Option<usize>>> {
    let Some(first) = points.first() else {
        return Vec::new();
    };
    let n = first.len();
    let mut order: Vec<Vec<Option<usize>>> = vec![(0..n).map(Some).collect()];
    for p in 1..points.len() {
        let prev = &order[p - 1];
        let cur = &points[p];
        let mut pairs = Vec::new();
        for (k, pk) in prev.iter().enumerate() {
            if let Some(i) = pk {
                for (j, s) in cur.iter().enumerate() {
                    pairs.push((mac(&points[p - 1][*i], s), k, j));
                }
            }
        }
        // Largest MAC first; ties by tracked index then mode index (deterministic).
        pairs.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
        let mut next = vec![None; n];
        let mut taken = vec![false; cur.len()];
        for (_, k, j) in pairs {
            if next[k].is_none() && !taken[j] {
                next[k] = Some(j);
                taken[j] = true;
            }
        }
        order.push(next);
    }
    order
}

/// The label code (index into [`LABELS`]) of a mode shape `y` (node blocks first) of
/// `sys` at `state`, spinning about `axis`.
pub fn label(sys: &System, state: &State, axis: &Vector3<f64>, y: &[c64]) -> usize {
    let mut share = [0.0f64; 5];
    for beam in &sys.beams {
        let mut nodes: Vec<usize> = beam
            .elements
            .iter()
            .flat_map(|e| e.nodes().iter().copied())
            .collect();
        nodes.dedup();
        let (Some(&a), Some(&b)) = (nodes.first(), nodes.last()) else {
            continue;
        };
        let length = (state.nodes[b].x - state.nodes[a].x).norm().max(1e-12);
        for &i in &nodes {
            let r = state.nodes[i].r();
            let e1 = r.column(0).into_owned();
            let lag_dir = axis.cross(&e1);
            let lag_dir = if lag_dir.norm() > 1e-12 {
                lag_dir.normalize()
            } else {
                r.column(1).into_owned()
            };
            let u: Vec<c64> = y[6 * i..6 * i + 3].to_vec();
            // Rotation vector, global: R φ.
            let phi: Vec<c64> = (0..3)
                .map(|k| (0..3).map(|j| y[6 * i + 3 + j] * r[(k, j)]).sum())
                .collect();
            let dot =
                |v: &[c64], d: &Vector3<f64>| (v[0] * d.x + v[1] * d.y + v[2] * d.z).norm_sqr();
            share[1] += dot(&u, axis);
            share[2] += dot(&u, &lag_dir);
            share[4] += dot(&u, &e1);
            share[3] += dot(&phi, &e1) * (length / std::f64::consts::TAU).powi(2);
        }
    }
    let total: f64 = share.iter().sum();
    if total <= 0.0 {
        return 0;
    }
    let (best, value) = share
        .iter()
        .enumerate()
        .skip(1)
        .max_by(|a, b| a.1.total_cmp(b.1))
        .map(|(i, v)| (i, *v))
        .unwrap_or((0, 0.0));
    if value > 0.5 * total { best } else { 0 }
}

/// The arrays of a Campbell analysis with `points` speeds and `n_modes` tracked modes.
pub fn campbell_arrays(points: usize, n_modes: usize) -> Vec<ArraySpec> {
    let point = ("point".to_string(), points);
    let mode = ("mode".to_string(), n_modes);
    vec![
        ArraySpec {
            name: "campbell_speed".into(),
            dims: vec![point.clone()],
            units: "rad/s".into(),
            long_name: "rotor speed of each point".into(),
        },
        ArraySpec {
            name: "campbell_frequency".into(),
            dims: vec![point.clone(), mode.clone()],
            units: "Hz".into(),
            long_name: "natural frequency |lambda|/(2 pi) of each tracked mode in the rotating frame (NaN where lost)".into(),
        },
        ArraySpec {
            name: "campbell_damping_ratio".into(),
            dims: vec![point, mode.clone()],
            units: "1".into(),
            long_name: "damping ratio -Re lambda/|lambda| of each tracked mode (NaN where lost)".into(),
        },
        ArraySpec {
            name: "campbell_mode_label".into(),
            dims: vec![mode],
            units: "1".into(),
            long_name: "dominant character of each tracked mode: 0 mixed, 1 flap, 2 lag, 3 torsion, 4 axial".into(),
        },
    ]
}

/// Runs the sweep from `initial` (each point starts from it).
pub fn run_campbell(
    sys: &System,
    name: &str,
    settings: &CampbellSettings,
    initial: State,
    recorder: &mut dyn Recorder,
    progress: Progress,
) -> Result<AnalysisSummary, crate::Error> {
    use rayon::prelude::*;
    let clock = Instant::now();
    let mut summary = AnalysisSummary::new(name, "campbell");
    let options = super::modal::eigen_options(&settings.modal);
    let results: Vec<Result<Point, SolverFailure>> = settings
        .speeds
        .par_iter()
        .map(|&omega| {
            let rotation = SteadyRotation {
                omega,
                ..settings.rotation
            };
            let statics = StaticSettings {
                load_steps: settings.load_steps,
                time: settings.time,
                solver: settings.solver.clone(),
                rotation: Some(Spin {
                    rotation,
                    nodes: None,
                }),
            };
            let point_name = format!("{name} (Ω = {omega} rad/s)");
            let s = run_static(
                sys,
                &point_name,
                &statics,
                initial.clone(),
                &mut Discard,
                &mut |_| {},
            )
            .map_err(|e| SolverFailure {
                analysis: name.to_string(),
                time: omega,
                reason: e.to_string(),
                hint: None,
            })?;
            if let Some(f) = s.failure {
                return Err(f);
            }
            let mut state = s.final_state;
            rotation.impose(sys, &mut state);
            let lin = linearize(sys, &state, Some(&rotation));
            let spectrum = crate::linear::modes(&lin, &options).map_err(|e| SolverFailure {
                analysis: name.to_string(),
                time: omega,
                reason: format!("eigenanalysis at Ω = {omega} rad/s: {e}"),
                hint: Some("see the modal analysis of the same model for the cause".into()),
            })?;
            Ok(Point {
                state,
                modes: spectrum.modes,
            })
        })
        .collect();
    progress(0.9);
    let mut points = Vec::with_capacity(results.len());
    for r in results {
        match r {
            Ok(p) => points.push(p),
            Err(f) => {
                summary.failure = Some(f);
                summary.final_state = initial;
                summary.wall_time = clock.elapsed();
                return Ok(summary);
            }
        }
    }
    for (p, &omega) in points.iter().zip(&settings.speeds) {
        let ctx = sys.context(p.state.time, 1.0);
        recorder.record(
            sys,
            &OutputFrame {
                time: omega,
                state: &p.state,
                mu: &p.state.lambda,
                energy: Energy {
                    kinetic: sys.kinetic_energy(&p.state),
                    potential: sys.potential_energy(&ctx, &p.state),
                    external_work: 0.0,
                    dissipated: 0.0,
                },
                constraint_violation: 0.0,
                load_factor: 1.0,
                diagnostics: None,
            },
        )?;
    }
    let shapes: Vec<Vec<Vec<c64>>> = points
        .iter()
        .map(|p| p.modes.iter().map(|m| m.shape.clone()).collect())
        .collect();
    let order = track(&shapes);
    let n = settings.modal.n_modes;
    let mut freq = Vec::with_capacity(points.len() * n);
    let mut zeta = Vec::with_capacity(points.len() * n);
    for (p, ord) in points.iter().zip(&order) {
        for k in 0..n {
            match ord.get(k).copied().flatten() {
                Some(i) => {
                    freq.push(p.modes[i].frequency());
                    zeta.push(p.modes[i].damping_ratio());
                }
                None => {
                    freq.push(f64::NAN);
                    zeta.push(f64::NAN);
                }
            }
        }
    }
    let labels: Vec<f64> = (0..n)
        .map(|k| {
            points[0].modes.get(k).map_or(0.0, |m| {
                label(sys, &points[0].state, &settings.rotation.axis, &m.shape) as f64
            })
        })
        .collect();
    let values = [settings.speeds.clone(), freq, zeta, labels];
    for (spec, v) in campbell_arrays(points.len(), n).iter().zip(&values) {
        recorder.write_array(sys, spec, v)?;
    }
    summary.steps = points.len();
    summary.final_state = points.pop().map_or(initial, |p| p.state);
    summary.wall_time = clock.elapsed();
    Ok(summary)
}
