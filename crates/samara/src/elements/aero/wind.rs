//! The wind field: steady uniform wind with a power-law shear, scaled by a time function
//! (a gust or any time history),
//!
//! `W(p, t) = U f(t) (h/h_ref)^α ŵ`,   h = (p − p_ground)·ẑ_up,
//!
//! sampled where each aerodynamic station is. Below `h_min = 10⁻³ h_ref` the height is
//! held at h_min (the power law is singular at the ground).

use crate::math::TimeFunction;
use crate::math::dual::{Scalar, V3};
use nalgebra::Vector3;

#[derive(Clone, Debug)]
pub struct Wind {
    /// Speed U at the reference height [m/s].
    pub speed: f64,
    /// Unit direction ŵ the air moves to, global.
    pub direction: Vector3<f64>,
    /// Shear exponent α (0: uniform).
    pub shear_exponent: f64,
    /// Reference height h_ref [m] (> 0).
    pub reference_height: f64,
    /// Unit vertical ẑ_up, global.
    pub vertical: Vector3<f64>,
    /// Height of the ground along ẑ_up [m].
    pub ground: f64,
    /// Multiplies the speed.
    pub function: TimeFunction,
}

impl Default for Wind {
    fn default() -> Self {
        Self {
            speed: 0.0,
            direction: Vector3::x(),
            shear_exponent: 0.0,
            reference_height: 1.0,
            vertical: Vector3::z(),
            ground: 0.0,
            function: TimeFunction::Constant(1.0),
        }
    }
}

impl Wind {
    /// Wind velocity at point p, time t.
    pub fn velocity<S: Scalar>(&self, p: &V3<S>, t: f64) -> V3<S> {
        let u = self.speed * self.function.eval(t);
        let mut s = S::cst(u);
        if self.shear_exponent != 0.0 {
            let up = self.vertical;
            let h = p[0] * up[0] + p[1] * up[1] + p[2] * up[2] - self.ground;
            let h_min = 1e-3 * self.reference_height;
            let h = if h.re() < h_min { S::cst(h_min) } else { h };
            s = (h / self.reference_height).powf(self.shear_exponent) * u;
        }
        let d = self.direction;
        [s * d[0], s * d[1], s * d[2]]
    }
}
