//! Consistent initial accelerations and multipliers.
//!
//! At the initial configuration and velocities, the accelerations and multipliers solve
//! the index-1 system (the second time derivative of Φ = 0):
//!
//! ```text
//! [ M  Bᵀ ] [ v̇ ]   [ f − g ]
//! [ B  0  ] [ λ ] = [ −(Φ̈ − B v̇) ]
//! ```
//!
//! Starting generalized-α from these keeps it second-order accurate (Arnold & Brüls 2007).

use crate::elements::EvalContext;
use crate::solve::{BlockMatrix, LinearError, LinearSolver};
use crate::system::{Assembler, Coefficients, State, System};
use nalgebra::Vector3;

/// Solves for v̇ and λ at `state` (positions and velocities given) and stores them in it.
/// On failure returns the block whose pivot is singular.
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
    state.lambda.fill(0.0);
    let coef = Coefficients {
        mass: 1.0,
        damping: 0.0,
        stiffness: 0.0,
        row_scale: 1.0,
        multiplier_scale: 1.0,
        velocity_scale: 1.0,
        penalty: 0.0,
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
    let n_cfg = sys.n_config();
    state.lambda.copy_from_slice(&residual[n_cfg..]);
    Ok(())
}
