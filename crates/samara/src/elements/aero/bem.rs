//! Quasi-steady blade-element momentum theory at one station, in the one-unknown form of
//! Ning (2014, "A simple solution method for the blade element momentum equations with
//! guaranteed convergence", Wind Energy 17): the inflow angle φ solves
//!
//! `R(φ) = sin φ/(1 − a(φ)) − cos φ (1 − κ'(φ))/λᵣ = 0`   (φ > 0, windmill state),
//! `R(φ) = sin φ (1 − κ) − cos φ (1 − κ')/λᵣ = 0`          (φ < 0, propeller brake),
//!
//! with λᵣ = V_y/V_x, σ' = B c/(2π r), α = φ − θ, c_n = c_l cos φ + c_d sin φ,
//! c_t = c_l sin φ − c_d cos φ, κ = σ' c_n/(4F sin²φ), κ' = σ' c_t/(4F sin φ cos φ),
//! a = κ/(1 + κ) for κ ≤ 2/3 and Buhl's (2005) high-thrust correction above,
//! a' = κ'/(1 − κ'), and Prandtl's tip and hub losses F = F_tip F_hub,
//! F_tip = (2/π) acos exp(−B(R − r)/(2 r |sin φ|)), F_hub = (2/π) acos exp(−B(r − R_hub)/(2 R_hub |sin φ|)).
//! φ is bracketed and found by bisection–secant (always converges); its derivatives with
//! respect to the inputs follow from the implicit-function theorem, one Newton step in
//! dual numbers at the root: φ = φ* − R(φ*, p)/∂R/∂φ, the induction factors carried to
//! that φ along their φ-derivatives (one kernel pass in the inputs' dual numbers, one in
//! φ alone).
//!
//! **Warm start** ([`BemRotor::solve_near`]): given the last root φ₀ of the station in
//! the windmill bracket (0, π/2), Newton's iteration φ ← φ − R/∂R/∂φ with the exact
//! derivative (one dual direction) starts there; it is accepted when a step falls below
//! [`WARM_TOLERANCE`] without leaving the bracket within [`WARM_ITERATIONS`] steps,
//! otherwise the bracketing above runs. The implicit-function step that follows is one
//! more Newton step, so the root agrees with the bracketed one to rounding. A values-only
//! solve (f64) takes one such Newton step and then f64 residuals with the slope updated
//! from each ([`BemRotor::chord_root`]), to an estimated 1e-15 rad.

use super::airfoil::Airfoil;
use crate::math::dual::{Dual, Scalar};
use std::f64::consts::{FRAC_PI_2, PI};

/// Newton steps of the warm start before it gives way to the bracketing.
pub const WARM_ITERATIONS: usize = 8;
/// Newton step [rad] below which the warm start has converged (the implicit-function
/// step that follows squares it).
pub const WARM_TOLERANCE: f64 = 1e-10;
/// Error [rad] the values-only chord iteration leaves ([`BemRotor::chord_root`]): below
/// the bracketing's 1e-14 rad, a few ulps of φ.
pub const CHORD_TOLERANCE: f64 = 1e-15;
/// Contraction rate of the chord iteration above which Newton takes over.
pub const CHORD_CONTRACTION: f64 = 0.1;
/// Exponent x of Prandtl's e^{−x} past which acos(e^{−x}) is π/2 in f64 (from 37 on).
const LOSS_SATURATION: f64 = 40.0;
/// Lower end of the windmill bracket (0, π/2) [rad].
const BRACKET_EPS: f64 = 1e-6;

/// The rotor a station belongs to, for BEM.
#[derive(Clone, Debug, PartialEq)]
pub struct BemRotor {
    /// Number of blades B.
    pub blades: usize,
    /// Hub and tip radius [m].
    pub hub_radius: f64,
    pub tip_radius: f64,
    pub tip_loss: bool,
    pub hub_loss: bool,
    /// Include the tangential induction a'.
    pub tangential_induction: bool,
    /// Pitt–Peters/Glauert skewed-wake correction of the axial induction in yawed flow
    /// (AeroDyn's SkewMod = 2), applied by the station after the momentum solve.
    pub skewed_wake: bool,
}

/// The skewed-wake correction's constant 15π/32 (Pitt & Peters 1981; Moriarty & Hansen,
/// AeroDyn Theory Manual, 2005, §"Skewed wake correction").
pub const SKEW_CONSTANT: f64 = 15.0 * PI / 32.0;

/// The BEM solution at a station.
#[derive(Clone, Copy, Debug)]
pub struct Induction<S> {
    pub phi: S,
    /// Axial and tangential induction factors a, a'.
    pub a: S,
    pub ap: S,
    /// Prandtl loss factor F.
    pub loss: S,
}

/// The station's inputs: axial and tangential inflow V_x (> 0 along the axis, through
/// the rotor), V_y (> 0 against the blade motion), radius r, chord c, and θ, the chord's
/// angle to the rotor plane (twist + pitch, positive toward feather).
#[derive(Clone, Copy, Debug)]
pub struct StationFlow<S> {
    pub vx: S,
    pub vy: S,
    pub r: S,
    pub chord: f64,
    pub theta: S,
    /// The Reynolds number the airfoil's tables are interpolated at (`None`: its first
    /// table).
    pub re: Option<S>,
}

impl BemRotor {
    /// Prandtl's F = F_tip F_hub from sin φ and r.
    fn loss<S: Scalar>(&self, sin_phi: S, r: S) -> S {
        let b = self.blades as f64;
        let s = sin_phi.abs();
        let mut f = S::cst(1.0);
        if self.tip_loss && r.re() < self.tip_radius {
            let x = (S::cst(self.tip_radius) - r) * (b / 2.0) / (r * s);
            f = f * prandtl_acos(x) * (2.0 / PI);
        }
        if self.hub_loss && r.re() > self.hub_radius && self.hub_radius > 0.0 {
            let x = (r - self.hub_radius) * (b / 2.0) / (s * self.hub_radius);
            f = f * prandtl_acos(x) * (2.0 / PI);
        }
        f
    }

    /// R(φ) and the induction factors at φ.
    fn residual<S: Scalar>(
        &self,
        phi: S,
        p: &StationFlow<S>,
        airfoil: &Airfoil,
    ) -> (S, Induction<S>) {
        let (sp, cp) = (phi.sin(), phi.cos());
        let alpha = phi - p.theta;
        let [cl, cd] = airfoil.lift_drag(alpha, p.re);
        let cn = cl * cp + cd * sp;
        let ct = cl * sp - cd * cp;
        let sigma = S::cst(self.blades as f64 * p.chord / (2.0 * PI)) / p.r;
        let loss = self.loss(sp, p.r);
        let k = sigma * cn / (loss * sp * sp * 4.0);
        let mut kp = sigma * ct / (loss * sp * cp * 4.0);
        if !self.tangential_induction {
            kp = S::cst(0.0);
        }
        let lambda_r = p.vy / p.vx;
        let (a, r) = if phi.re() > 0.0 {
            let a = if k.re() <= 2.0 / 3.0 {
                k / (k + 1.0)
            } else {
                // Buhl's correction, continuous with the momentum branch at κ = 2/3.
                let f = loss;
                let g1 = f * k * 2.0 - (S::cst(10.0 / 9.0) - f);
                let g2 = f * k * 2.0 - f * (S::cst(4.0 / 3.0) - f);
                let g3 = f * k * 2.0 - (S::cst(25.0 / 9.0) - f * 2.0);
                if g3.re().abs() < 1e-6 {
                    S::cst(1.0) - S::cst(0.5) / g2.sqrt()
                } else {
                    (g1 - g2.sqrt()) / g3
                }
            };
            (
                a,
                sp / (S::cst(1.0) - a) - cp * (S::cst(1.0) - kp) / lambda_r,
            )
        } else {
            let a = if k.re() > 1.0 {
                k / (k - 1.0)
            } else {
                S::cst(0.0)
            };
            (
                a,
                sp * (S::cst(1.0) - k) - cp * (S::cst(1.0) - kp) / lambda_r,
            )
        };
        let ap = kp / (S::cst(1.0) - kp);
        (r, Induction { phi, a, ap, loss })
    }

    fn residual_value(&self, phi: f64, p: &StationFlow<f64>, airfoil: &Airfoil) -> f64 {
        self.residual(phi, p, airfoil).0
    }

    /// Solves for φ (in f64) and returns the induction with exact derivatives for a
    /// dual `p` (values only for f64). `None` where BEM does not apply (V_x ≤ 0 or
    /// V_y ≤ 0, a station outside hub…tip, or no root in the brackets).
    pub fn solve<S: Scalar>(&self, p: &StationFlow<S>, airfoil: &Airfoil) -> Option<Induction<S>> {
        self.solve_near(p, airfoil, None)
    }

    /// [`Self::solve`] warm-started from `hint`, a previous root φ₀ in (0, π/2) (module
    /// doc); `None`: bracketing only.
    pub fn solve_near<S: Scalar>(
        &self,
        p: &StationFlow<S>,
        airfoil: &Airfoil,
        hint: Option<f64>,
    ) -> Option<Induction<S>> {
        let pv = StationFlow {
            vx: p.vx.re(),
            vy: p.vy.re(),
            r: p.r.re(),
            chord: p.chord,
            theta: p.theta.re(),
            re: p.re.map(|x| x.re()),
        };
        if !(pv.vx > 1e-9 && pv.vy > 1e-9 && pv.r > 0.0) {
            return None;
        }
        let pd = StationFlow {
            vx: Dual::<1>::cst(pv.vx),
            vy: Dual::<1>::cst(pv.vy),
            r: Dual::<1>::cst(pv.r),
            chord: pv.chord,
            theta: Dual::<1>::cst(pv.theta),
            re: pv.re.map(Dual::<1>::cst),
        };
        // R and ∂R/∂φ at φ (one dual direction), with the induction's φ-derivatives.
        let with_slope = |phi: f64| self.residual(Dual::<1>::var(phi, 0), &pd, airfoil);
        if S::DIRECTIONS == 0 {
            // Values only: the chord iteration from the hint, the implicit-function step
            // in values (no derivatives to carry).
            let ind = match hint.and_then(|h| self.chord_root(h, &pv, airfoil, &with_slope)) {
                Some(ind) => ind,
                None => {
                    let phi = self.bracketed(&pv, airfoil)?;
                    carried(phi, &with_slope(phi))
                }
            };
            return Some(Induction {
                phi: S::cst(ind.phi),
                a: S::cst(ind.a),
                ap: S::cst(ind.ap),
                loss: S::cst(ind.loss),
            });
        }
        let (phi, (r_phi, ind_phi)) = match hint.and_then(|h| self.newton_root(h, &with_slope)) {
            Some(found) => found,
            None => {
                let phi = self.bracketed(&pv, airfoil)?;
                (phi, with_slope(phi))
            }
        };
        // The implicit-function step at the root.
        let dr = r_phi.d[0];
        let (r, ind) = self.residual(S::cst(phi), p, airfoil);
        if dr.abs() <= 1e-300 {
            return Some(ind);
        }
        // φ = φ* + δφ, δφ = −R(φ*, p)/∂R/∂φ (the implicit-function step), and the
        // induction carried to φ along its φ-derivative from the same one-direction
        // pass: exact to first order, so exact derivatives, and values equal to those
        // at φ* + δφ up to O(δφ²) (δφ is the root finder's residual, ≤ 1e-14 rad).
        let dphi = -(r / dr);
        let along = |v: S, dv: Dual<1>| v + dphi * dv.d[0];
        Some(Induction {
            phi: S::cst(phi) + dphi,
            a: along(ind.a, ind_phi.a),
            ap: along(ind.ap, ind_phi.ap),
            loss: along(ind.loss, ind_phi.loss),
        })
    }
}

impl BemRotor {
    /// The root of the first bracket that holds one (windmill, propeller brake, then
    /// φ > π/2), by [`bracketed_root`]; `None` if none does.
    fn bracketed(&self, pv: &StationFlow<f64>, airfoil: &Airfoil) -> Option<f64> {
        let f = |x: f64| self.residual_value(x, pv, airfoil);
        let brackets = [
            (BRACKET_EPS, FRAC_PI_2),
            (-FRAC_PI_2 / 2.0, -BRACKET_EPS),
            (FRAC_PI_2, PI - BRACKET_EPS),
        ];
        brackets.iter().find_map(|&(lo, hi)| {
            let (flo, fhi) = (f(lo), f(hi));
            (flo.is_finite() && fhi.is_finite() && flo * fhi <= 0.0)
                .then(|| bracketed_root(&f, lo, hi, flo, fhi))
        })
    }

    /// The values-only root from `phi0` inside the windmill bracket: one Newton step with
    /// the exact slope m = R′(φ₀) (one dual direction), then steps φ ← φ − R(φ)/m in f64
    /// with m updated from each new residual (the slope at φ of the quadratic through the
    /// last iterate's R and m and this R; no derivative evaluated). The last step s is
    /// applied to the induction along its φ-derivatives at φ₀, an error O(s (φ − φ₀)),
    /// so it stops when |s| max(θ/(1 − θ), |φ − φ₀|) ≤ [`CHORD_TOLERANCE`], θ = |s/s_prev|
    /// the contraction (the first term the error a chord step would leave; the updated
    /// slope's is smaller). A first step ≤ [`WARM_TOLERANCE`] ends it as the
    /// implicit-function step does. A contraction slower than [`CHORD_CONTRACTION`] hands
    /// over to Newton ([`Self::newton_root`]); `None` as that does (the caller brackets).
    fn chord_root(
        &self,
        phi0: f64,
        pv: &StationFlow<f64>,
        airfoil: &Airfoil,
        with_slope: &dyn Fn(f64) -> (Dual<1>, Induction<Dual<1>>),
    ) -> Option<Induction<f64>> {
        let inside = |x: f64| x > BRACKET_EPS && x < FRAC_PI_2;
        if !inside(phi0) {
            return None;
        }
        let at = with_slope(phi0);
        let mut slope = at.0.d[0];
        let s0 = -at.0.v / slope;
        if !s0.is_finite() || !inside(phi0 + s0) {
            return None;
        }
        if s0.abs() <= WARM_TOLERANCE {
            return Some(carried(phi0, &at));
        }
        let mut phi = phi0 + s0;
        let mut last = s0;
        for _ in 0..WARM_ITERATIONS {
            let (r, ind) = self.residual(phi, pv, airfoil);
            // The slope at φ of the quadratic with the last iterate's R and slope whose
            // value here is R (the last step zeroed its linear part): m ← m + 2R/s.
            slope += 2.0 * r / last;
            let s = -r / slope;
            if !s.is_finite() || !inside(phi + s) {
                break;
            }
            let theta = (s / last).abs();
            if theta >= CHORD_CONTRACTION {
                break;
            }
            // The error the chord step would leave, and that of carrying the step along
            // the φ-derivatives at φ₀ instead of at the root.
            let moved = (phi + s - phi0).abs();
            if s.abs() * (theta / (1.0 - theta)).max(moved) <= CHORD_TOLERANCE {
                let along = |v: f64, dv: Dual<1>| v + s * dv.d[0];
                return Some(Induction {
                    phi: phi + s,
                    a: along(ind.a, at.1.a),
                    ap: along(ind.ap, at.1.ap),
                    loss: along(ind.loss, at.1.loss),
                });
            }
            phi += s;
            last = s;
        }
        self.newton_root(phi, with_slope)
            .map(|(phi, at)| carried(phi, &at))
    }

    /// Newton's iteration from `phi` inside the windmill bracket (0, π/2): the last
    /// iterate φ (its step below [`WARM_TOLERANCE`]) with R, ∂R/∂φ and the induction
    /// there, or `None` (a step leaves the bracket, a non-finite or zero slope, or no
    /// convergence in [`WARM_ITERATIONS`] steps).
    fn newton_root(
        &self,
        mut phi: f64,
        with_slope: &dyn Fn(f64) -> (Dual<1>, Induction<Dual<1>>),
    ) -> Option<(f64, (Dual<1>, Induction<Dual<1>>))> {
        let inside = |x: f64| x > BRACKET_EPS && x < FRAC_PI_2;
        if !inside(phi) {
            return None;
        }
        for _ in 0..WARM_ITERATIONS {
            let at = with_slope(phi);
            let step = -at.0.v / at.0.d[0];
            if !step.is_finite() || !inside(phi + step) {
                return None;
            }
            if step.abs() <= WARM_TOLERANCE {
                return Some((phi, at));
            }
            phi += step;
        }
        None
    }
}

/// acos(e^{−x}) of Prandtl's factor. Past [`LOSS_SATURATION`] e^{−x} < 2⁻⁵³ and acos
/// rounds to π/2 (as computed), its derivative e^{−x}/√(1 − e^{−2x}) dx below rounding:
/// π/2 without the exp and acos (most stations' hub loss).
#[inline]
fn prandtl_acos<S: Scalar>(x: S) -> S {
    if x.re() > LOSS_SATURATION {
        S::cst(FRAC_PI_2)
    } else {
        (-x).exp().acos()
    }
}

/// The induction at φ* + δφ from R, ∂R/∂φ and the induction at φ* (one dual direction),
/// δφ = −R/∂R/∂φ: the implicit-function step in values.
fn carried(phi: f64, at: &(Dual<1>, Induction<Dual<1>>)) -> Induction<f64> {
    let (r, ind) = at;
    let dr = r.d[0];
    if dr.abs() <= 1e-300 {
        return Induction {
            phi,
            a: ind.a.v,
            ap: ind.ap.v,
            loss: ind.loss.v,
        };
    }
    let dphi = -(r.v / dr);
    let along = |v: Dual<1>| v.v + dphi * v.d[0];
    Induction {
        phi: phi + dphi,
        a: along(ind.a),
        ap: along(ind.ap),
        loss: along(ind.loss),
    }
}

/// A root of f in [lo, hi] with f(lo) f(hi) ≤ 0: Illinois false position with bisection
/// safeguard, to 1e-14 rad.
fn bracketed_root(
    f: &dyn Fn(f64) -> f64,
    mut lo: f64,
    mut hi: f64,
    mut flo: f64,
    mut fhi: f64,
) -> f64 {
    if flo == 0.0 {
        return lo;
    }
    if fhi == 0.0 {
        return hi;
    }
    let mut side = 0;
    for it in 0..200 {
        let x = if it % 4 == 3 {
            0.5 * (lo + hi)
        } else {
            let x = (lo * fhi - hi * flo) / (fhi - flo);
            if x.is_finite() && x > lo && x < hi {
                x
            } else {
                0.5 * (lo + hi)
            }
        };
        let fx = f(x);
        if fx == 0.0 || (hi - lo) < 1e-14 {
            return x;
        }
        if fx * flo < 0.0 {
            hi = x;
            fhi = fx;
            if side == -1 {
                flo *= 0.5;
            }
            side = -1;
        } else {
            lo = x;
            flo = fx;
            if side == 1 {
                fhi *= 0.5;
            }
            side = 1;
        }
    }
    0.5 * (lo + hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An NREL 5-MW-like rotor (3 blades, hub 1.5 m, tip 63 m, both losses).
    fn sweep_rotor() -> BemRotor {
        BemRotor {
            blades: 3,
            hub_radius: 1.5,
            tip_radius: 63.0,
            tip_loss: true,
            hub_loss: true,
            tangential_induction: true,
            skewed_wake: false,
        }
    }

    /// Its stations' flow over a sweep: 11.4 m/s, 12.1 rpm, radii 5…62 m, chords and
    /// twists around the blade's.
    fn sweep_flows() -> impl Iterator<Item = StationFlow<f64>> {
        [5.0, 12.0, 25.0, 40.0, 55.0, 62.0]
            .into_iter()
            .flat_map(|r| {
                [-0.05, 0.0, 0.1, 0.25].map(|theta| StationFlow {
                    vx: 11.4,
                    vy: 1.267 * r,
                    r,
                    chord: 4.0 - 0.04 * r,
                    theta,
                    re: None,
                })
            })
    }

    /// `p` in one-direction dual numbers (no direction set).
    fn dual_flow(p: &StationFlow<f64>) -> StationFlow<Dual<1>> {
        StationFlow {
            vx: Dual::<1>::cst(p.vx),
            vy: Dual::<1>::cst(p.vy),
            r: Dual::<1>::cst(p.r),
            chord: p.chord,
            theta: Dual::<1>::cst(p.theta),
            re: None,
        }
    }

    /// The warm start finds the bracketed root: over [`sweep_flows`], from a hint 0.05 rad
    /// off (a previous step's root) and from a far one (1.5 rad), φ, a, a' and F agree
    /// with the bracketed solution. Both end with the same implicit-function (Newton)
    /// step from a root converged to ≤ 1e-10 rad (warm) or 1e-14 rad (bracketing), so
    /// they agree to rounding: 1e-12.
    #[test]
    fn warm_start_finds_the_bracketed_root() {
        let rotor = sweep_rotor();
        let airfoil = Airfoil::thin_plate_with_drag();
        let mut warm = 0;
        for p in sweep_flows() {
            let (r, theta) = (p.r, p.theta);
            let cold = rotor.solve(&p, &airfoil).unwrap();
            for hint in [cold.phi + 0.05, cold.phi - 0.05, 1.5] {
                let hot = rotor.solve_near(&p, &airfoil, Some(hint)).unwrap();
                for (x, y) in [
                    (hot.phi, cold.phi),
                    (hot.a, cold.a),
                    (hot.ap, cold.ap),
                    (hot.loss, cold.loss),
                ] {
                    assert!((x - y).abs() <= 1e-12, "r {r} θ {theta}: {x} vs {y}");
                }
                let pd = dual_flow(&p);
                let with_slope = |phi: f64| rotor.residual(Dual::<1>::var(phi, 0), &pd, &airfoil);
                warm += usize::from(rotor.newton_root(hint, &with_slope).is_some());
            }
        }
        // The near hints converge by Newton (not by the fallback): at least the 48 near
        // ones of the 72.
        assert!(warm >= 48, "{warm} warm starts converged");
    }

    /// The values-only solve (f64: one dual Newton step from the hint, then f64 steps
    /// with the updated slope, [`BemRotor::chord_root`]) gives the values of the dual
    /// path (Newton in one-direction dual numbers to 1e-10 rad, then the implicit-function
    /// step): over [`sweep_flows`], from hints 1e-2, 1e-4 and 1e-6 rad off the root (a
    /// step's, an iteration's and a converged state's change of φ), φ, a, a′ and F agree
    /// to 1e-13 (the values-only path stops at an estimated 1e-15 rad, the dual one
    /// squares a ≤ 1e-10 step; both round differently).
    #[test]
    fn values_only_root_matches_the_dual_path() {
        let rotor = sweep_rotor();
        let airfoil = Airfoil::thin_plate_with_drag();
        for p in sweep_flows() {
            let (r, theta) = (p.r, p.theta);
            let pd = dual_flow(&p);
            let root = rotor.solve(&p, &airfoil).unwrap().phi;
            for off in [1e-2, -1e-2, 1e-4, -1e-6] {
                let hint = Some(root + off);
                let f = rotor.solve_near(&p, &airfoil, hint).unwrap();
                let d = rotor.solve_near(&pd, &airfoil, hint).unwrap();
                for (x, y) in [
                    (f.phi, d.phi.v),
                    (f.a, d.a.v),
                    (f.ap, d.ap.v),
                    (f.loss, d.loss.v),
                ] {
                    assert!(
                        (x - y).abs() <= 1e-13,
                        "r {r} θ {theta} hint {off:e} off: {x} vs {y}"
                    );
                }
            }
        }
    }

    /// A hint outside the windmill bracket is not used: the bracketing finds the root.
    #[test]
    fn a_hint_outside_the_windmill_bracket_falls_back_to_bracketing() {
        let rotor = BemRotor {
            blades: 3,
            hub_radius: 1.5,
            tip_radius: 63.0,
            tip_loss: true,
            hub_loss: false,
            tangential_induction: true,
            skewed_wake: false,
        };
        let airfoil = Airfoil::thin_plate_with_drag();
        let p = StationFlow {
            vx: 11.4,
            vy: 30.0,
            r: 30.0,
            chord: 3.0,
            theta: 0.05,
            re: None,
        };
        let pd = dual_flow(&p);
        let with_slope = |phi: f64| rotor.residual(Dual::<1>::var(phi, 0), &pd, &airfoil);
        let cold = rotor.solve(&p, &airfoil).unwrap();
        for hint in [-0.3, 2.0, f64::NAN] {
            assert!(rotor.newton_root(hint, &with_slope).is_none());
            let hot = rotor.solve_near(&p, &airfoil, Some(hint)).unwrap();
            assert_eq!(hot.phi, cold.phi);
            assert_eq!(hot.a, cold.a);
        }
    }
}
