//! Elements attached to a joint coordinate ν (seed §3.2: springs, dampers, backlash and
//! control inputs act on the explicit relative displacement/rotation).
//!
//! The coordinate's residual row gets `r = F_s(ν) + F_d(ν̇) + F_b(ν, ν̇) − F_in(t)`:
//! - spring `F_s`: linear `k (ν − ν₀)` or piecewise linear through a table, extended
//!   linearly with the end slopes; potential `∫₀^ν F_s`;
//! - damper `F_d`: linear `c ν̇` or a table over ν̇;
//! - backlash: free play `|ν − ν_c| ≤ w/2`; outside it, with penetration
//!   `g = |ν − ν_c| − w/2`, the contact force `sign(ν − ν_c) k g + c ν̇` (Kelvin–Voigt);
//! - input port `F_in = s`, the value of a named signal, acting to increase ν
//!   (`∂r/∂s = −1`; the system applies the chain rule to the signal's producer).

use super::spec::{BacklashDef, ComponentDef, ForceLaw};

/// `[F(x), dF/dx]` of a force law.
pub fn force_law(law: &ForceLaw, x: f64) -> [f64; 2] {
    match law {
        ForceLaw::Linear {
            coefficient,
            reference,
        } => [coefficient * (x - reference), *coefficient],
        ForceLaw::Table { x: xs, f } => {
            let n = xs.len();
            if n == 1 {
                return [f[0], 0.0];
            }
            // Segment i (clamped to the end segments, so the ends extend linearly).
            let i = xs.partition_point(|&v| v <= x).clamp(1, n - 1) - 1;
            let slope = (f[i + 1] - f[i]) / (xs[i + 1] - xs[i]);
            [f[i] + slope * (x - xs[i]), slope]
        }
    }
}

/// `∫₀^x F(s) ds` of a force law (exact for the piecewise-linear table).
pub fn force_law_integral(law: &ForceLaw, x: f64) -> f64 {
    match law {
        ForceLaw::Linear {
            coefficient,
            reference,
        } => 0.5 * coefficient * ((x - reference).powi(2) - reference * reference),
        ForceLaw::Table { .. } => {
            // Integrate the piecewise-linear function between 0 and x over its breakpoints.
            let (lo, hi, sign) = if x >= 0.0 {
                (0.0, x, 1.0)
            } else {
                (x, 0.0, -1.0)
            };
            let mut cuts = vec![lo];
            if let ForceLaw::Table { x: xs, .. } = law {
                cuts.extend(xs.iter().copied().filter(|&v| v > lo && v < hi));
            }
            cuts.push(hi);
            let mut acc = 0.0;
            for w in cuts.windows(2) {
                let (a, b) = (w[0], w[1]);
                acc += 0.5 * (b - a) * (force_law(law, a)[0] + force_law(law, b)[0]);
            }
            sign * acc
        }
    }
}

/// Backlash contact: `[F, ∂F/∂ν, ∂F/∂ν̇]` at (ν, ν̇).
pub fn backlash_force(b: &BacklashDef, nu: f64, nu_dot: f64) -> [f64; 3] {
    let s = nu - b.center;
    let g = s.abs() - b.half_width;
    if g <= 0.0 {
        return [0.0; 3];
    }
    [
        s.signum() * b.stiffness * g + b.damping * nu_dot,
        b.stiffness,
        b.damping,
    ]
}

/// The elements attached to one joint coordinate.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CoordinateLoads {
    pub spring: Option<ForceLaw>,
    pub damper: Option<ForceLaw>,
    pub backlash: Option<BacklashDef>,
    /// The input port's signal: its name.
    pub input: Option<String>,
}

impl CoordinateLoads {
    pub fn from_def(def: &ComponentDef) -> Self {
        Self {
            spring: def.spring.clone(),
            damper: def.damper.clone(),
            backlash: def.backlash.clone(),
            input: def.input.clone(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.spring.is_none()
            && self.damper.is_none()
            && self.backlash.is_none()
            && self.input.is_none()
    }

    /// `[r, ∂r/∂ν, ∂r/∂ν̇]`, with `input` the value of the input port's signal (if any).
    pub fn residual(&self, input: f64, nu: f64, nu_dot: f64) -> [f64; 3] {
        let mut out = [0.0; 3];
        if let Some(s) = &self.spring {
            let [f, k] = force_law(s, nu);
            out[0] += f;
            out[1] += k;
        }
        if let Some(d) = &self.damper {
            let [f, c] = force_law(d, nu_dot);
            out[0] += f;
            out[2] += c;
        }
        if let Some(b) = &self.backlash {
            let [f, k, c] = backlash_force(b, nu, nu_dot);
            out[0] += f;
            out[1] += k;
            out[2] += c;
        }
        if self.input.is_some() {
            out[0] -= input;
        }
        out
    }

    pub fn potential_energy(&self, nu: f64) -> f64 {
        let mut e = 0.0;
        if let Some(s) = &self.spring {
            e += force_law_integral(s, nu);
        }
        if let Some(b) = &self.backlash {
            let g = (nu - b.center).abs() - b.half_width;
            if g > 0.0 {
                e += 0.5 * b.stiffness * g * g;
            }
        }
        e
    }

    pub fn dissipated_power(&self, nu: f64, nu_dot: f64) -> f64 {
        let mut p = 0.0;
        if let Some(d) = &self.damper {
            p += force_law(d, nu_dot)[0] * nu_dot;
        }
        if let Some(b) = &self.backlash
            && (nu - b.center).abs() > b.half_width
        {
            p += b.damping * nu_dot * nu_dot;
        }
        p
    }

    /// Power of the input port, `F_in ν̇`.
    pub fn external_power(&self, input: f64, nu_dot: f64) -> f64 {
        if self.input.is_some() {
            input * nu_dot
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_spring_extends_linearly_and_integrates_exactly() {
        let law = ForceLaw::Table {
            x: vec![-1.0, 0.0, 2.0],
            f: vec![-3.0, 0.0, 2.0],
        };
        assert_eq!(force_law(&law, 1.0), [1.0, 1.0]);
        assert_eq!(force_law(&law, 3.0), [3.0, 1.0]);
        assert_eq!(force_law(&law, -2.0), [-6.0, 3.0]);
        // ∫₀³ x dx = 4.5; ∫₀^-2 = ∫ of 3x from 0 to −1 (1.5) plus from −1 to −2 (4.5).
        assert!((force_law_integral(&law, 3.0) - 4.5).abs() < 1e-14);
        assert!((force_law_integral(&law, -2.0) - 6.0).abs() < 1e-14);
        let lin = ForceLaw::Linear {
            coefficient: 4.0,
            reference: 0.5,
        };
        // Potential differences are what matter: V(2) − V(0.5) = ½ k 1.5².
        let dv = force_law_integral(&lin, 2.0) - force_law_integral(&lin, 0.5);
        assert!((dv - 0.5 * 4.0 * 2.25).abs() < 1e-14);
    }

    /// dr/dν and dr/dν̇ against central differences (inside and outside the dead band).
    #[test]
    fn residual_tangents_match_finite_differences() {
        let loads = CoordinateLoads {
            spring: Some(ForceLaw::Table {
                x: vec![-1.0, 0.0, 2.0],
                f: vec![-3.0, 0.0, 2.0],
            }),
            damper: Some(ForceLaw::Linear {
                coefficient: 0.7,
                reference: 0.0,
            }),
            backlash: Some(BacklashDef {
                center: 0.1,
                half_width: 0.2,
                stiffness: 1e3,
                damping: 3.0,
            }),
            input: Some("push".into()),
        };
        let h = 1e-7;
        for (nu, nd) in [(0.45, 0.3), (-0.37, -1.1), (0.05, 2.0), (1.3, 0.0)] {
            let r = loads.residual(2.0, nu, nd);
            let k = (loads.residual(2.0, nu + h, nd)[0] - loads.residual(2.0, nu - h, nd)[0])
                / (2.0 * h);
            let c = (loads.residual(2.0, nu, nd + h)[0] - loads.residual(2.0, nu, nd - h)[0])
                / (2.0 * h);
            assert!(
                (r[1] - k).abs() < 1e-5 * k.abs().max(1.0),
                "{nu}: {} {k}",
                r[1]
            );
            assert!((r[2] - c).abs() < 1e-6, "{nu}: {} {c}", r[2]);
        }
    }
}
