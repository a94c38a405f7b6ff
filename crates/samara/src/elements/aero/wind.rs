//! The wind field: steady uniform wind with a power-law shear, scaled by a time function
//! (a gust or any time history),
//!
//! `W(p, t) = U f(t) (h/h_ref)^α ŵ`,   h = (p − p_ground)·ẑ_up,
//!
//! sampled where each aerodynamic station is. Below `h_min = 10⁻³ h_ref` the height is
//! held at h_min (the power law is singular at the ground).
//!
//! Or a turbulent box ([`super::turbsim::FullField`]) advancing along ŵ (horizontal) at
//! its mean hub speed (Taylor's frozen turbulence): with ŷ = ẑ_up × ŵ and the point's
//! wind-frame coordinates x = p·ŵ, y = p·ŷ, z = p·ẑ_up − ground,
//!
//! `W(p, t) = u ŵ + v ŷ + w ẑ_up`,   (u, v, w) = box(y, z, t + (x₀ − x)/u_hub).
//!
//! A point outside the box gives NaN and is recorded; the analysis reports it
//! ([`Wind::outside_sample`]).
//!
//! A **gust** g f_g adds to either: uniform, g f_g(t), or convected along ŵ at a speed
//! U_c (a frozen gust pattern, its front a plane normal to ŵ), g f_g(t − x/U_c), x = p·ŵ.
//!
//! **Mean and disturbance** ([`Wind::split`]): the wind is the sum of a mean part — the
//! sheared wind times its function, or the box's time-mean profile ū(y, z) — and a
//! disturbance, the gust plus the box's turbulence u − ū. An airfoil with Küssner's gust
//! response lags the disturbance's normal velocity with Küssner's function and the rest
//! with Wagner's (Leishman, *Principles of Helicopter Aerodynamics*, 2nd ed., §8.14–8.16).

use super::turbsim::FullField;
use crate::math::TimeFunction;
use crate::math::dual::{Scalar, V3, add, sub};
use nalgebra::Vector3;
use std::sync::Arc;

/// What to do about a sample outside a TurbSim box.
pub const OUTSIDE_HINT: &str = "generate a box that covers the rotor's sweep (grid width and height) and lasts the run plus the time the box takes to reach the rotor, or use a periodic file";

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
    /// A turbulent box replacing the analytic wind (speed, shear and function unused).
    pub turbulence: Option<Arc<FullField>>,
    /// A gust added to the wind (part of the disturbance that an unsteady airfoil with
    /// Küssner's gust response takes through Küssner's function).
    pub gust: Option<Gust>,
}

/// A gust: velocity g (global) times its time function, uniform, g f_g(t), or convected
/// along the wind's direction ŵ at U_c, g f_g(t − p·ŵ/U_c).
#[derive(Clone, Debug)]
pub struct Gust {
    pub velocity: Vector3<f64>,
    pub function: TimeFunction,
    /// Convection speed U_c [m/s] (> 0); `None`: uniform in space.
    pub convection_speed: Option<f64>,
}

impl Gust {
    /// A gust uniform in space.
    pub fn uniform(velocity: Vector3<f64>, function: TimeFunction) -> Self {
        Self {
            velocity,
            function,
            convection_speed: None,
        }
    }
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
            turbulence: None,
            gust: None,
        }
    }
}

impl Wind {
    /// Wind velocity at point p, time t.
    pub fn velocity<S: Scalar>(&self, p: &V3<S>, t: f64) -> V3<S> {
        let w = self.steady_velocity(p, t);
        match &self.gust {
            None => w,
            Some(g) => add(&w, &self.gust_velocity(g, p, t)),
        }
    }

    /// The wind split into its mean part at p and its disturbance (the gust and the box's
    /// turbulence) at q: `(W̄(p) + W'(q), W'(q))`. With q = p the sum is
    /// [`Self::velocity`] (to rounding).
    pub fn split<S: Scalar>(&self, p: &V3<S>, q: &V3<S>, t: f64) -> (V3<S>, V3<S>) {
        let zero = S::cst(0.0);
        let mut dist = match &self.gust {
            None => [zero; 3],
            Some(g) => self.gust_velocity(g, q, t),
        };
        let mean = match &self.turbulence {
            None => self.steady_velocity(p, t),
            Some(field) => {
                let fluct = sub(&self.turbulent(field, q, t), &self.box_mean(field, q));
                dist = add(&dist, &fluct);
                self.box_mean(field, p)
            }
        };
        (add(&mean, &dist), dist)
    }

    /// The times where the wind's functions (speed and gust) jump or kink, at a point whose
    /// coordinate along ŵ is x (a convected gust reaches it x/U_c later).
    pub fn breakpoints(&self, x: f64) -> Vec<f64> {
        let mut v = self.function.breakpoints();
        if let Some(g) = &self.gust {
            let shift = g.convection_speed.map_or(0.0, |u| x / u);
            v.extend(
                g.function
                    .breakpoints()
                    .into_iter()
                    .map(|b| shifted_breakpoint(b, shift)),
            );
        }
        v
    }

    /// The gust at p: g f_g(t), or g f_g(t − p·ŵ/U_c) convected.
    fn gust_velocity<S: Scalar>(&self, g: &Gust, p: &V3<S>, t: f64) -> V3<S> {
        let f = match g.convection_speed {
            None => S::cst(g.function.eval(t)),
            Some(uc) => {
                let d = self.direction;
                let x = p[0] * d[0] + p[1] * d[1] + p[2] * d[2];
                let theta = S::cst(t) - x / uc;
                let [f, df, _] = g.function.derivatives(theta.re());
                theta.chain(f, df)
            }
        };
        let v = g.velocity;
        [f * v[0], f * v[1], f * v[2]]
    }

    /// The wind without its gust: the sheared wind times its function, or the box.
    fn steady_velocity<S: Scalar>(&self, p: &V3<S>, t: f64) -> V3<S> {
        if let Some(field) = &self.turbulence {
            return self.turbulent(field, p, t);
        }
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

    /// The wind-frame lateral direction ŷ = ẑ_up × ŵ.
    pub fn lateral(&self) -> Vector3<f64> {
        self.vertical.cross(&self.direction)
    }

    /// Wind-frame coordinates (x, y, z) of a point.
    pub fn frame<S: Scalar>(&self, p: &V3<S>) -> [S; 3] {
        let proj = |d: Vector3<f64>| p[0] * d[0] + p[1] * d[1] + p[2] * d[2];
        [
            proj(self.direction),
            proj(self.lateral()),
            proj(self.vertical) - self.ground,
        ]
    }

    fn turbulent<S: Scalar>(&self, field: &FullField, p: &V3<S>, t: f64) -> V3<S> {
        let [x, y, z] = self.frame(p);
        let tau = field.box_time(x, t);
        let Some([u, v, w]) = field.sample(y, z, tau) else {
            if let Some(why) = field.outside(y.re(), z.re(), tau.re()) {
                field.record_outside(format!(
                    "at t = {t} s a station sampled the wind of TurbSim file '{}' outside its box, at ({:.4}, {:.4}, {:.4}) m: {why}",
                    field.source,
                    p[0].re(),
                    p[1].re(),
                    p[2].re()
                ));
            }
            return [S::cst(f64::NAN); 3];
        };
        let (d, l, h) = (self.direction, self.lateral(), self.vertical);
        let c = |k: usize| u * d[k] + v * l[k] + w * h[k];
        [c(0), c(1), c(2)]
    }

    /// The box's time-mean wind at p (NaN outside the grid, and recorded).
    fn box_mean<S: Scalar>(&self, field: &FullField, p: &V3<S>) -> V3<S> {
        let [_, y, z] = self.frame(p);
        let Some([u, v, w]) = field.mean(y, z) else {
            if let Some(why) = field.outside(y.re(), z.re(), 0.0) {
                field.record_outside(format!(
                    "a station sampled the mean wind of TurbSim file '{}' outside its grid, at ({:.4}, {:.4}, {:.4}) m: {why}",
                    field.source,
                    p[0].re(),
                    p[1].re(),
                    p[2].re()
                ));
            }
            return [S::cst(f64::NAN); 3];
        };
        let (d, l, h) = (self.direction, self.lateral(), self.vertical);
        let c = |k: usize| u * d[k] + v * l[k] + w * h[k];
        [c(0), c(1), c(2)]
    }

    /// The first sample a turbulent wind took outside its box, if any.
    pub fn outside_sample(&self) -> Option<&str> {
        self.turbulence.as_ref().and_then(|f| f.outside_sample())
    }
}

/// The time t at which a gust breakpoint b reaches a point `shift` = x/U_c downstream,
/// chosen in floating point so that the gust's argument t − shift is ≥ b at t and < b
/// at the next float below: a step ending on t sees the left limit there (it is
/// evaluated at t's predecessor) and the restart the right limit, as for a breakpoint of
/// an unshifted function. b + shift alone may round to either side.
fn shifted_breakpoint(b: f64, shift: f64) -> f64 {
    let mut t = b + shift;
    for _ in 0..4 {
        if t.next_down() - shift >= b {
            t = t.next_down();
        } else if t - shift < b {
            t = t.next_up();
        } else {
            break;
        }
    }
    t
}
