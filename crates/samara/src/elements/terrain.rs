//! The local geometry of a height-field ground z(x, y) ([`HeightField`]) as dual numbers:
//! height and slope at a point that depends on the unknowns, with the slope's derivative
//! through the Hessian (the normal turns as the point moves), and the unit normal
//!
//! `n = (−z_x, −z_y, 1)/√(1 + z_x² + z_y²)`,
//!
//! with the tangent basis that moves with it: `t₁ = (e_x − n_x n)/|·|` (along the slope in
//! the x–z plane), `t₂ = n × t₁` (n_z > 0, so e_x is never along n).

use crate::math::dual::{Scalar, V3, cross, scale};
use crate::math::height_field::HeightField;

/// Height and slope `(z, [z_x, z_y])` at (x, y): exact first derivatives through the
/// gradient and the Hessian ([`HeightField::eval_extended`] outside the table).
pub fn surface<S: Scalar>(hf: &HeightField, x: S, y: S) -> (S, [S; 2]) {
    let h = hf.eval_extended(x.re(), y.re());
    let (dx, dy) = (x - x.re(), y - y.re());
    let g = h.gradient;
    let hs = h.hessian;
    (
        dx * g[0] + dy * g[1] + h.z,
        [
            dx * hs[0][0] + dy * hs[0][1] + g[0],
            dx * hs[1][0] + dy * hs[1][1] + g[1],
        ],
    )
}

/// The unit normal out of the ground for the slope `g` and its z component
/// `n_z = 1/√(1 + |g|²)`.
pub fn normal<S: Scalar>(g: &[S; 2]) -> (V3<S>, S) {
    let nz = S::cst(1.0) / (g[0] * g[0] + g[1] * g[1] + 1.0).sqrt();
    ([-(g[0] * nz), -(g[1] * nz), nz], nz)
}

/// The tangent basis (t₁, t₂) of the unit normal n (n_z > 0).
pub fn tangents<S: Scalar>(n: &V3<S>) -> [V3<S>; 2] {
    let nx = n[0];
    let t: V3<S> = [S::cst(1.0) - nx * nx, -(nx * n[1]), -(nx * n[2])];
    let len = (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]).sqrt();
    let t1 = scale(&t, S::cst(1.0) / len);
    let t2 = cross(n, &t1);
    [t1, t2]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::dual::{Dual, dot};

    /// On a tilted plane the normal is the plane's and (t₁, t₂, n) is orthonormal and
    /// right-handed (round-off, 1e-14); derivatives of the slope are the Hessian's.
    #[test]
    fn plane_normal_and_basis() {
        let hf = HeightField::new(
            vec![-1.0, 0.0, 2.0],
            vec![-1.0, 1.0],
            &[vec![0.3, 0.0, -0.6], vec![0.5, 0.2, -0.4]],
        )
        .unwrap();
        let (z, g) = surface::<Dual<2>>(&hf, Dual::var(0.5, 0), Dual::var(0.2, 1));
        assert!((z.v - (-0.3 * 0.5 + 0.1 * 0.2 + 0.1)).abs() < 1e-14);
        assert!((g[0].v + 0.3).abs() < 1e-14 && (g[1].v - 0.1).abs() < 1e-14);
        assert!(g[0].d.iter().chain(&g[1].d).all(|d| d.abs() < 1e-14));
        let (n, _) = normal(&g);
        let [t1, t2] = tangents(&n);
        let want = nalgebra::Vector3::new(0.3, -0.1, 1.0).normalize();
        for k in 0..3 {
            assert!((n[k].v - want[k]).abs() < 1e-14);
        }
        for (a, b, v) in [
            (&t1, &t1, 1.0),
            (&t2, &t2, 1.0),
            (&t1, &t2, 0.0),
            (&t1, &n, 0.0),
        ] {
            assert!((dot(a, b).v - v).abs() < 1e-14);
        }
        assert!((dot(&cross(&t1, &t2), &n).v - 1.0).abs() < 1e-14);
    }
}
