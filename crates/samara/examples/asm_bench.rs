use samara::model::Model;
use samara::solve::BlockMatrix;
use samara::system::{Assembler, Coefficients, Formulation, State, System};
use std::time::Instant;
fn main() {
    let path = std::env::args().nth(1).unwrap();
    let model = Model::from_file(&path).unwrap().model;
    let sys = System::new(&model);
    let state = State::initial(&model, sys.n_multipliers);
    let mut asm = Assembler::new(&sys, Formulation::Index3);
    let mut m = BlockMatrix::zeros(asm.structure().clone());
    let mut r = vec![0.0; asm.n_unknowns()];
    let ctx = sys.context(0.0, 1.0);
    let coef = Coefficients {
        mass: 1e6,
        damping: 1e3,
        stiffness: 1.0,
        row_scale: 1e-6,
        multiplier_scale: 1e-6,
        velocity_scale: 1.0,
        penalty: 1e4,
    };
    let t_ops = vec![nalgebra::Matrix3::identity(); sys.n_nodes()];
    let n: usize = std::env::var("N")
        .map(|s| s.parse().unwrap())
        .unwrap_or(2000);
    let c = Instant::now();
    for _ in 0..n {
        asm.assemble(&sys, &state, &ctx, &coef, &t_ops, &mut r, Some(&mut m));
    }
    println!(
        "assemble with matrix: {:.1} µs",
        c.elapsed().as_secs_f64() / n as f64 * 1e6
    );
    let c = Instant::now();
    for _ in 0..n {
        asm.assemble(&sys, &state, &ctx, &coef, &t_ops, &mut r, None);
    }
    println!(
        "residual only: {:.1} µs",
        c.elapsed().as_secs_f64() / n as f64 * 1e6
    );
    let mut phi = vec![0.0; sys.n_multipliers];
    let c = Instant::now();
    for _ in 0..n {
        sys.constraint_values(&ctx, &state, &mut phi);
    }
    println!(
        "constraint values: {:.1} µs",
        c.elapsed().as_secs_f64() / n as f64 * 1e6
    );
}
