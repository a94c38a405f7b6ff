//! A node's kinematic quantities as forward-mode dual numbers ([`crate::math::dual`]) for
//! kernels that get their tangents by differentiation: local unknown k of node i is
//! `6 i + k` (position 0–2, rotation increment δθ 3–5, in the node frame: `R ← R exp(δθ̃)`).

use crate::math::dual::{Scalar, V3, cst3};
use nalgebra::{Matrix3, Vector3};

/// A node-vector variable: value `v` with derivative 1 in directions `dir + k`.
pub fn var3<S: Scalar>(v: &Vector3<f64>, dir: usize) -> V3<S> {
    let mut out = cst3::<S>(v);
    for (k, o) in out.iter_mut().enumerate() {
        o.add_deriv(dir + k, 1.0);
    }
    out
}

/// `R b` for node i with b fixed in the node: derivative `R (e_j × b)` along δθ_j.
pub fn rot<S: Scalar>(i: usize, r: &Matrix3<f64>, b: &Vector3<f64>) -> V3<S> {
    let mut out = cst3::<S>(&(r * b));
    if S::DIRECTIONS > 0 {
        for j in 0..3 {
            let col = r * Vector3::ith(j, 1.0).cross(b);
            for (k, o) in out.iter_mut().enumerate() {
                o.add_deriv(6 * i + 3 + j, col[k]);
            }
        }
    }
    out
}

/// `Rᵀ y` for node i, y a function of the unknowns: `Rᵀ dy − δθ × Rᵀ y`.
pub fn rot_t<S: Scalar>(i: usize, r: &Matrix3<f64>, y: &V3<S>) -> V3<S> {
    let mut z: V3<S> =
        std::array::from_fn(|k| y[0] * r[(0, k)] + y[1] * r[(1, k)] + y[2] * r[(2, k)]);
    if S::DIRECTIONS > 0 {
        let zv = Vector3::new(z[0].re(), z[1].re(), z[2].re());
        for j in 0..3 {
            let c = Vector3::ith(j, 1.0).cross(&zv);
            for (k, zk) in z.iter_mut().enumerate() {
                zk.add_deriv(6 * i + 3 + j, -c[k]);
            }
        }
    }
    z
}

/// The angular velocity `ω = R Ω` of node i (Ω in the node frame, the rate unknowns at
/// `rate + 6 i + 3 …`): derivatives along δθ and along Ω.
pub fn omega<S: Scalar>(i: usize, r: &Matrix3<f64>, w: &Vector3<f64>, rate: usize) -> V3<S> {
    let mut out = rot::<S>(i, r, w);
    if S::DIRECTIONS > 0 {
        for j in 0..3 {
            for (k, o) in out.iter_mut().enumerate() {
                o.add_deriv(rate + 6 * i + 3 + j, r[(k, j)]);
            }
        }
    }
    out
}
