//! Rolling and twisting (drilling) resistance of a sphere contact: the torques a real
//! contact patch carries and a point contact does not, as in DEM codes (the constant
//! directional torque model, "model A" of Ai, Chen, Rotter & Ooi 2011, Powder Technology
//! 206, 269–282, regularized so that Newton can follow it).
//!
//! With ω the angular velocity of body B relative to body A (the sphere's own ω against
//! the ground), n the contact normal, N the normal force and δ the penetration:
//!
//! - **rolling**: `M_r = −μ_r R_eff N ω_t / √(|ω_t|² + ω_ε²)`, `ω_t = (I − n nᵀ) ω`,
//!   with `R_eff = ρ_A ρ_B/(ρ_A + ρ_B)` (ρ against the ground). Rolling faster than ω_ε,
//!   the torque is μ_r R_eff N against the rolling (a sphere rolling on level ground
//!   decelerates at `a = −μ_r g/(1 + I/(m ρ²))`, −(5/7) μ_r g for a solid sphere, and holds
//!   on an incline while tan θ ≤ μ_r); below ω_ε it is viscous (under a torque below the
//!   limit it creeps at `ω = ω_ε τ/√(1 − τ²)`, τ the torque over the limit).
//! - **twisting**: `M_t = −(3π/16) μ_t a N ω_n n / √(ω_n² + ω_ε²)`, `ω_n = n·ω`, with the
//!   Hertz contact radius `a = √(R_eff δ)`: (3π/16) μ a N is the torque of Coulomb friction
//!   μ slipping over a Hertzian pressure distribution spinning about its centre (Lubkin
//!   1951, J. Appl. Mech. 18, "The torsion of elastic spheres in contact"). A sphere
//!   spinning on the floor about the vertical slows at the constant rate `M_t/I`.
//!
//! Both act on B, their opposite on A: a couple, so the contact's forces keep their
//! resultant and the pair conserves angular momentum. The power `M·ω ≤ 0` is dissipated.
//! The kernel runs on any [`Scalar`] (values and exact tangents by forward
//! differentiation, as the contact kernels that call it).

use crate::math::dual::{Scalar, V3, add, dot, scale, sub};

/// Rolling and twisting resistance of a sphere contact.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RollingResistance {
    /// μ_r ≥ 0 (dimensionless: the torque limit over R_eff N).
    pub rolling: f64,
    /// μ_t ≥ 0 (the friction coefficient slipping over the patch when it spins).
    pub twisting: f64,
    /// ω_ε [rad/s] > 0: below it both laws are viscous.
    pub regularization: f64,
}

/// The moment on body B (minus it on A) for the relative angular velocity `omega`
/// (B's minus A's), unit normal `n`, normal force `normal` ≥ 0, penetration `delta` and
/// effective radius `r_eff`. Zero out of contact (N = 0).
pub fn resisting_moment<S: Scalar>(
    res: &RollingResistance,
    n: &V3<S>,
    omega: &V3<S>,
    normal: S,
    delta: S,
    r_eff: f64,
) -> V3<S> {
    let zero = S::cst(0.0);
    if normal.re() <= 0.0 || delta.re() <= 0.0 {
        return [zero; 3];
    }
    let e2 = res.regularization * res.regularization;
    let wn = dot(n, omega);
    let mut m = [zero; 3];
    if res.rolling > 0.0 {
        let wt = sub(omega, &scale(n, wn));
        let den = (dot(&wt, &wt) + e2).sqrt();
        m = scale(&wt, -(normal * (res.rolling * r_eff)) / den);
    }
    if res.twisting > 0.0 {
        let a = (delta * r_eff).sqrt();
        let den = (wn * wn + e2).sqrt();
        let k = 3.0 * std::f64::consts::PI / 16.0 * res.twisting;
        m = add(&m, &scale(n, -(a * normal * wn * k) / den));
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rolling fast, the torque is the limit μ_r R N against ω_t; spinning fast, the
    /// twisting torque is (3π/16) μ_t √(R δ) N against ω_n; slow, both are viscous with
    /// slope limit/ω_ε; and out of contact nothing.
    #[test]
    fn limits() {
        let res = RollingResistance {
            rolling: 0.1,
            twisting: 0.3,
            regularization: 1e-3,
        };
        let n = [0.0, 0.0, 1.0];
        let (nf, d, r) = (20.0, 1e-4, 0.05);
        let m = resisting_moment(&res, &n, &[1e3, 0.0, 0.0], nf, d, r);
        assert!((m[0] + 0.1 * r * nf).abs() < 1e-9 * 0.1 * r * nf);
        let m = resisting_moment(&res, &n, &[0.0, 0.0, -1e3], nf, d, r);
        let lim = 3.0 * std::f64::consts::PI / 16.0 * 0.3 * (r * d).sqrt() * nf;
        assert!((m[2] - lim).abs() < 1e-9 * lim && m[0] == 0.0);
        let m = resisting_moment(&res, &n, &[0.0, 1e-8, 0.0], nf, d, r);
        assert!((m[1] + 0.1 * r * nf * 1e-5).abs() < 1e-6 * 0.1 * r * nf * 1e-5);
        let m = resisting_moment(&res, &n, &[1.0, 1.0, 1.0], 0.0, d, r);
        assert_eq!(m, [0.0; 3]);
    }
}
