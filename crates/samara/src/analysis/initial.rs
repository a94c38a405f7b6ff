//! Consistent initial conditions.
//!
//! 1. **Assembly** (positions): the given configuration q₀ is moved onto the constraint
//!    manifold with the least change. Each Gauss–Newton step is the minimum-norm
//!    correction in the metric `W` (1 for translations, `L²` for rotations with `L` the
//!    model's characteristic length, a tiny weight for joint coordinates so that they
//!    follow the nodes):
//!    ```text
//!    [ W  Bᵀ ] [ Δq ]   [  0 ]
//!    [ B  0  ] [ λ  ] = [ −Φ ]
//!    ```
//!    repeated until `max |Φ|` is within the tolerance. Driven coordinates are held by
//!    their drives, so the nodes move to meet them.
//! 2. **Velocities**: projected the same way onto `B v + Φ_t = 0` (one linear solve).
//! 3. **Accelerations and multipliers** solve the index-1 system (second time derivative
//!    of Φ = 0):
//!    ```text
//!    [ M  Bᵀ ] [ v̇ ]   [ f − g ]
//!    [ B  0  ] [ λ ] = [ −(Φ̈ − B v̇) ]
//!    ```
//!    Starting generalized-α from these keeps it second-order accurate (Arnold & Brüls
//!    2007).

use crate::core::EvalContext;
use crate::solve::{BlockMatrix, LinearError, LinearSolver};
use crate::system::{Assembler, Coefficients, State, System};
use nalgebra::Vector3;

/// Joint-coordinate weight in the assembly metric (relative to 1 m² per node).
const COORDINATE_WEIGHT: f64 = 1e-8;
/// Gauss–Newton iterations allowed for the assembly.
const MAX_ASSEMBLY_ITERATIONS: usize = 50;

/// What the assembly step did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AssemblyReport {
    /// max |Φ| before and after.
    pub violation_before: f64,
    pub violation_after: f64,
    pub iterations: usize,
    /// Per node: distance moved [m] and rotation [rad].
    pub moved: Vec<(f64, f64)>,
    /// Largest change of a joint coordinate's rate in the velocity projection.
    pub velocity_change: f64,
}

/// Why the initial conditions could not be made consistent.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum AssemblyError {
    #[error("the constraint equations are singular at the initial configuration (block {block})")]
    Singular { block: usize },
    #[error(
        "the initial assembly did not converge: the joints are still violated by {violation:.3e} after {iterations} iterations"
    )]
    NotConverged { violation: f64, iterations: usize },
}

/// RMS distance of the nodes from their centroid (≥ 1e-3 m): the length that converts
/// rotations into the assembly metric.
fn characteristic_length(state: &State) -> f64 {
    let n = state.nodes.len().max(1) as f64;
    let c: Vector3<f64> = state.nodes.iter().map(|x| x.x).sum::<Vector3<f64>>() / n;
    let rms = (state
        .nodes
        .iter()
        .map(|x| (x.x - c).norm_squared())
        .sum::<f64>()
        / n)
        .sqrt();
    rms.max(1e-3)
}

fn violation(sys: &System, ctx: &EvalContext, state: &State, phi: &mut [f64]) -> f64 {
    sys.constraint_values(ctx, state, phi);
    phi.iter().fold(0.0, |m, x| m.max(x.abs()))
}

/// `[W Bᵀ; B 0]` at `state` (`scratch` receives a residual that is not used).
fn projection_matrix(
    sys: &System,
    state: &State,
    ctx: &EvalContext,
    w: &[f64; 6],
    asm: &mut Assembler,
    matrix: &mut BlockMatrix,
    scratch: &mut [f64],
) {
    asm.assemble(
        sys,
        state,
        ctx,
        &Coefficients::constraints_only(),
        &[],
        scratch,
        Some(matrix),
    );
    asm.add_configuration_metric(sys, matrix, w, COORDINATE_WEIGHT);
}

/// Moves `state` onto the constraints (positions, then velocities); see the module doc.
/// `asm` must have the index-3 layout.
pub fn assemble_initial_state(
    sys: &System,
    state: &mut State,
    ctx: &EvalContext,
    tolerance: f64,
    asm: &mut Assembler,
    lin: &mut LinearSolver,
    matrix: &mut BlockMatrix,
) -> Result<AssemblyReport, AssemblyError> {
    let mut report = AssemblyReport::default();
    if sys.n_multipliers == 0 {
        report.moved = vec![(0.0, 0.0); sys.n_nodes()];
        return Ok(report);
    }
    let n = asm.n_unknowns();
    let mut rhs = vec![0.0; n];
    let mut cfg = vec![0.0; sys.n_config()];
    let mut phi = vec![0.0; sys.n_multipliers];
    let l = characteristic_length(state);
    let w = [1.0, 1.0, 1.0, l * l, l * l, l * l];
    let start = state.clone();
    let n6 = 6 * sys.n_nodes();
    let nc = sys.n_coordinates;
    report.violation_before = violation(sys, ctx, state, &mut phi);
    let mut viol = report.violation_before;
    while viol > tolerance {
        if report.iterations == MAX_ASSEMBLY_ITERATIONS {
            return Err(AssemblyError::NotConverged {
                violation: viol,
                iterations: report.iterations,
            });
        }
        report.iterations += 1;
        projection_matrix(sys, state, ctx, &w, asm, matrix, &mut rhs);
        // Right-hand side [0; −Φ].
        rhs.fill(0.0);
        for k in 0..sys.constraints.len() {
            let off = sys.multiplier_offsets[k];
            for (i, r) in asm.multiplier_range(k).enumerate() {
                rhs[r] = -phi[off + i];
            }
        }
        lin.factor(matrix)
            .map_err(|LinearError::Singular { block }| AssemblyError::Singular { block })?;
        lin.solve_in_place(&mut rhs);
        asm.configuration_of(sys, &rhs, &mut cfg);
        if !cfg.iter().all(|x| x.is_finite()) {
            return Err(AssemblyError::NotConverged {
                violation: viol,
                iterations: report.iterations,
            });
        }
        for (i, nd) in state.nodes.iter_mut().enumerate() {
            let d = &cfg[6 * i..6 * i + 6];
            nd.x += Vector3::new(d[0], d[1], d[2]);
            nd.rot = nd.rot.compose_exp(&Vector3::new(d[3], d[4], d[5]));
        }
        for (c, d) in state.coords.iter_mut().zip(&cfg[n6..n6 + nc]) {
            c.q += d;
        }
        viol = violation(sys, ctx, state, &mut phi);
    }
    report.violation_after = viol;
    report.moved = state
        .nodes
        .iter()
        .zip(&start.nodes)
        .map(|(a, b)| ((a.x - b.x).norm(), b.rot.relative_log(&a.rot).norm()))
        .collect();

    // Velocities: coordinate rates from the nodes, then one projection onto
    // B v + Φ_t = 0 (which only changes what the drives or the joints demand).
    sys.measure_coordinate_rates(state);
    projection_matrix(sys, state, ctx, &w, asm, matrix, &mut rhs);
    asm.velocity_rows(sys, state, ctx, &mut rhs);
    for x in rhs.iter_mut() {
        *x = -*x;
    }
    lin.factor(matrix)
        .map_err(|LinearError::Singular { block }| AssemblyError::Singular { block })?;
    lin.solve_in_place(&mut rhs);
    asm.configuration_of(sys, &rhs, &mut cfg);
    for (i, nd) in state.nodes.iter_mut().enumerate() {
        let d = &cfg[6 * i..6 * i + 6];
        nd.v += Vector3::new(d[0], d[1], d[2]);
        nd.w += Vector3::new(d[3], d[4], d[5]);
    }
    for (c, d) in state.coords.iter_mut().zip(&cfg[n6..n6 + nc]) {
        c.v += d;
        report.velocity_change = report.velocity_change.max(d.abs());
    }
    lin.invalidate();
    Ok(report)
}

/// Solves for v̇, ν̈, the element states' rates ż and λ at `state` (positions,
/// velocities and state values given) and stores them in it. On failure returns the block whose pivot is singular.
pub fn consistent_accelerations(
    sys: &System,
    state: &mut State,
    ctx: &EvalContext,
    asm: &mut Assembler,
    lin: &mut LinearSolver,
    matrix: &mut BlockMatrix,
    residual: &mut [f64],
) -> Result<(), LinearError> {
    for n in &mut state.nodes {
        n.a = Vector3::zeros();
        n.wd = Vector3::zeros();
    }
    for c in &mut state.coords {
        c.a = 0.0;
    }
    for z in &mut state.states {
        z.zd = 0.0;
    }
    state.lambda.fill(0.0);
    let coef = Coefficients {
        mass: 1.0,
        damping: 0.0,
        stiffness: 0.0,
        row_scale: 1.0,
        multiplier_scale: 1.0,
        velocity_scale: 1.0,
        penalty: 0.0,
        // The element states' rates ż are unknowns of this problem like v̇.
        state_rate: 1.0,
        state_row_scale: 1.0,
        step: 0.0,
    };
    asm.assemble(sys, state, ctx, &coef, &[], residual, Some(matrix));
    asm.acceleration_rows(sys, state, ctx, residual);
    lin.factor(matrix)?;
    for r in residual.iter_mut() {
        *r = -*r;
    }
    lin.solve_in_place(residual);
    for (i, n) in state.nodes.iter_mut().enumerate() {
        n.a = Vector3::new(residual[6 * i], residual[6 * i + 1], residual[6 * i + 2]);
        n.wd = Vector3::new(
            residual[6 * i + 3],
            residual[6 * i + 4],
            residual[6 * i + 5],
        );
    }
    for (k, off) in sys.coordinate_offsets.iter().enumerate() {
        for (j, r) in asm.coordinate_range(k).enumerate() {
            state.coords[off + j].a = residual[r];
        }
    }
    for (k, &off) in sys.state_offsets.iter().enumerate() {
        for (j, r) in asm.state_range(sys, k).enumerate() {
            state.states[off + j].zd = residual[r];
        }
    }
    let mut lam = std::mem::take(&mut state.lambda);
    asm.multipliers_of(sys, residual, &mut lam);
    state.lambda = lam;
    Ok(())
}
