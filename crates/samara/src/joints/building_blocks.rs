//! The two building blocks of every lower-pair joint (Bottasso, "Computational dynamics",
//! eq. 12), with θ = 0 / d = 0 (the component constrained):
//!
//! ```text
//! (12a)  Φ = e_iᴬ · (uᴮ − uᴬ)        relative displacement along e_iᴬ
//! (12b)  Φ = e_jᴬ · e_kᴮ              relative rotation about e_iᴬ, (i, j, k) cyclic
//! ```
//!
//! Kernels here work in global ("spatial") components: a side X has position `x`, arm
//! `r = R s` to the joint origin, and rotation variations `δφ` with `δR = δφ̃ R`. They
//! return, per scalar constraint,
//! - `Φ`,
//! - the Jacobian row `b` over `[δxᴬ, δφᴬ, δxᴮ, δφᴮ]` (12 entries),
//! - `μ ∂(bᵀ)/∂q`, the tangent of the generalized constraint force `bᵀ μ` (12 × 12),
//! - the convective part of `Φ̈` (all terms not multiplying accelerations).
//!
//! The conversion to the material rotation increments used by the nodes is done by the
//! caller (`joint.rs`).

use crate::math::skew;
use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

pub type Row12 = SVector<f64, 12>;
pub type Mat12 = SMatrix<f64, 12, 12>;

/// Current kinematics of the two frames of a joint, global components.
#[derive(Clone, Debug)]
pub struct FramePair {
    /// Node positions.
    pub x: [Vector3<f64>; 2],
    /// Arms from node to frame origin, `R s`.
    pub arm: [Vector3<f64>; 2],
    /// Frame axes (columns), `R A_local`.
    pub axes: [Matrix3<f64>; 2],
    /// Node velocities.
    pub v: [Vector3<f64>; 2],
    /// Node angular velocities (global).
    pub omega: [Vector3<f64>; 2],
}

impl FramePair {
    /// Frame origins uᴬ, uᴮ.
    pub fn origin(&self, side: usize) -> Vector3<f64> {
        self.x[side] + self.arm[side]
    }

    /// Relative displacement `d = uᴮ − uᴬ`.
    pub fn d(&self) -> Vector3<f64> {
        self.origin(1) - self.origin(0)
    }
}

fn put3(row: &mut Row12, at: usize, v: &Vector3<f64>) {
    for i in 0..3 {
        row[at + i] = v[i];
    }
}

fn add33(k: &mut Mat12, r: usize, c: usize, b: &Matrix3<f64>) {
    for j in 0..3 {
        for i in 0..3 {
            k[(r + i, c + j)] += b[(i, j)];
        }
    }
}

/// Eq. (12a) with d_i = 0 along axis `i` of frame A.
pub mod displacement {
    use super::*;

    pub fn value(f: &FramePair, i: usize) -> f64 {
        f.axes[0].column(i).dot(&f.d())
    }

    /// `b = [−eᵀ, (e × w)ᵀ, eᵀ, (r_B × e)ᵀ]` with `w = uᴮ − xᴬ`.
    pub fn jacobian(f: &FramePair, i: usize) -> Row12 {
        let e: Vector3<f64> = f.axes[0].column(i).into();
        let w = f.origin(1) - f.x[0];
        let mut b = Row12::zeros();
        put3(&mut b, 0, &(-e));
        put3(&mut b, 3, &e.cross(&w));
        put3(&mut b, 6, &e);
        put3(&mut b, 9, &f.arm[1].cross(&e));
        b
    }

    /// `μ ∂(bᵀ)/∂q` (spatial).
    pub fn force_tangent(f: &FramePair, i: usize, mu: f64, k: &mut Mat12) {
        let e: Vector3<f64> = f.axes[0].column(i).into();
        let et = skew(&e) * mu;
        let w = f.origin(1) - f.x[0];
        let wt = skew(&w);
        let rbt = skew(&f.arm[1]);
        // F_A = −μe, M_A = μ e × w, F_B = μe, M_B = μ r_B × e.
        add33(k, 0, 3, &et);
        add33(k, 6, 3, &(-et));
        add33(k, 3, 0, &(-et));
        add33(k, 3, 3, &(wt * et));
        add33(k, 3, 6, &et);
        add33(k, 3, 9, &(-(et * rbt)));
        add33(k, 9, 3, &(-(rbt * et)));
        add33(k, 9, 9, &(et * rbt));
    }

    /// Convective acceleration `ë·d + 2 ė·ḋ + e·d̈` at zero accelerations.
    pub fn convective(f: &FramePair, i: usize) -> f64 {
        let e: Vector3<f64> = f.axes[0].column(i).into();
        let (wa, wb) = (f.omega[0], f.omega[1]);
        let edot = wa.cross(&e);
        let eddot = wa.cross(&edot);
        let ddot = f.v[1] + wb.cross(&f.arm[1]) - f.v[0] - wa.cross(&f.arm[0]);
        let dddot = wb.cross(&wb.cross(&f.arm[1])) - wa.cross(&wa.cross(&f.arm[0]));
        eddot.dot(&f.d()) + 2.0 * edot.dot(&ddot) + e.dot(&dddot)
    }
}

/// Eq. (12b) with θ_i = 0 about axis `i` of frame A.
pub mod rotation {
    use super::*;

    fn pair(f: &FramePair, i: usize) -> (Vector3<f64>, Vector3<f64>) {
        let j = (i + 1) % 3;
        let k = (i + 2) % 3;
        (f.axes[0].column(j).into(), f.axes[1].column(k).into())
    }

    pub fn value(f: &FramePair, i: usize) -> f64 {
        let (e, g) = pair(f, i);
        e.dot(&g)
    }

    /// `b = [0, nᵀ, 0, −nᵀ]` with `n = e_jᴬ × e_kᴮ`.
    pub fn jacobian(f: &FramePair, i: usize) -> Row12 {
        let (e, g) = pair(f, i);
        let n = e.cross(&g);
        let mut b = Row12::zeros();
        put3(&mut b, 3, &n);
        put3(&mut b, 9, &(-n));
        b
    }

    /// `μ ∂(bᵀ)/∂q` (spatial): ∂n/∂φᴬ = g̃ ẽ, ∂n/∂φᴮ = −ẽ g̃.
    pub fn force_tangent(f: &FramePair, i: usize, mu: f64, k: &mut Mat12) {
        let (e, g) = pair(f, i);
        let (et, gt) = (skew(&e), skew(&g));
        let dn_a = gt * et * mu;
        let dn_b = -(et * gt) * mu;
        add33(k, 3, 3, &dn_a);
        add33(k, 3, 9, &dn_b);
        add33(k, 9, 3, &(-dn_a));
        add33(k, 9, 9, &(-dn_b));
    }

    /// `ë·g + 2 ė·ġ + e·g̈` at zero accelerations.
    pub fn convective(f: &FramePair, i: usize) -> f64 {
        let (e, g) = pair(f, i);
        let (wa, wb) = (f.omega[0], f.omega[1]);
        let edot = wa.cross(&e);
        let gdot = wb.cross(&g);
        wa.cross(&edot).dot(&g) + 2.0 * edot.dot(&gdot) + e.dot(&wb.cross(&gdot))
    }
}
