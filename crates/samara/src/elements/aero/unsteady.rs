//! Unsteady airfoil models with states, per station (docs/aerodynamics.md, "Unsteady
//! airfoil and dynamic stall").
//!
//! **Attached flow (Wagner).** The circulatory lift lags the downwash w = U·e_n at the
//! three-quarter-chord point with Wagner's indicial response φ(s), s = 2Vt/c the distance
//! travelled in semichords, in R. T. Jones' (1940) two-exponential approximation
//! φ(s) ≈ 1 − A₁e^{−b₁s} − A₂e^{−b₂s}, A = (0.165, 0.335), b = (0.0455, 0.3)
//! (Leishman, *Principles of Helicopter Aerodynamics*, 2nd ed., §8.14). As states
//! (Leishman's state-space form, Hansen, Gaunaa & Madsen 2004, Risø-R-1354 §2):
//!
//! `ż_i + (2V/c) b_i (z_i − A_i w) = 0`,  `w_E = w (1 − A₁ − A₂) + z₁ + z₂`,
//!
//! so a step in w gives w_E = w φ(s); the effective angle α_E = atan2(w_E, u_c) enters the
//! airfoil table. Filtering the downwash (not α) keeps the states continuous where α
//! wraps at ±180°. The rows are in m/s²; the assembler scales them by 1/(∂ż/∂Δz).
//!
//! **Gust response (Küssner).** With `gust_response = "kussner"` the normal velocity w_g
//! of the wind's disturbance (its gust and a TurbSim box's turbulence about the box's time
//! mean, [`super::wind::Wind::split`], sampled at the leading edge where ψ's front starts)
//! goes through two more states with Sears & Sparks' approximation of Küssner's function,
//! ψ(s) ≈ 1 − 0.5e^{−0.13s} − 0.5e^{−s} ([`KUSSNER_A`], [`KUSSNER_B`]); the rest w − w_g
//! (motion, mean wind, induction) through Wagner's (the station kernel, [`super::station`]).
//!
//! **Dynamic stall (Øye 1991).** The trailing-edge separation point lags its static
//! value: with Kirchhoff's flow cl = cl_inv ((1 + √f)/2)², cl_inv = c_lα(α − α₀) (α₀ the
//! table's zero-lift angle nearest 0, c_lα its least-squares slope over α₀ − 4° … α₀ + 6°;
//! cl_inv = cl_st where the table lifts more), the
//! static separation f_st(α) = (2√(cl_st/cl_inv) − 1)² (clipped to 0 … 1, and 0 beyond
//! the first angle on either side of α₀ where it reaches 0) and the fully separated
//! lift cl_fs = (cl_st − cl_inv f_st)/(1 − f_st) (cl_st/2 where f_st = 1):
//!
//! `τ ḟ + f − f_st(α) = 0`,  `τ = A_τ c/V`,  `cl = f cl_inv(α) + (1 − f) cl_fs(α)`
//!
//! (Hansen, *Aerodynamics of Wind Turbines*, 3rd ed., §9; A_τ ≈ 4). With f = f_st the
//! static table is recovered exactly. The row is written `ḟ + (V/(A_τ c)) (f − f_st)`
//! (units 1/s), so it stays finite as V → 0.

use super::airfoil::{Airfoil, Coefficients, TableWeight};
use crate::math::dual::Scalar;

/// R. T. Jones' (1940) coefficients of the Wagner function's exponential approximation.
pub const JONES_A: [f64; 2] = [0.165, 0.335];
pub const JONES_B: [f64; 2] = [0.0455, 0.3];

/// Sears & Sparks' (1941) two-exponential approximation of Küssner's sharp-edged-gust
/// function, ψ(s) ≈ 1 − 0.5 e^{−0.13 s} − 0.5 e^{−s} (Leishman, *Principles of Helicopter
/// Aerodynamics*, 2nd ed., §8.16).
pub const KUSSNER_A: [f64; 2] = [0.5, 0.5];
pub const KUSSNER_B: [f64; 2] = [0.13, 1.0];

/// The attached-flow model of a line.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum AttachedFlow {
    /// Quasi-steady: α at the station point, no states.
    #[default]
    QuasiSteady,
    /// Wagner's indicial response (Jones' approximation), two states.
    Wagner,
}

/// Øye's dynamic-stall model of one airfoil: f_st(α) and cl_fs(α) evaluated pointwise
/// from the airfoil's C¹ table, so that f_st cl_inv + (1 − f_st) cl_fs = cl_st exactly.
#[derive(Clone, Debug)]
pub struct OyeStall {
    /// Lift slope c_lα [1/rad] and zero-lift angle α₀ [rad] of the attached flow.
    pub lift_slope: f64,
    pub zero_lift: f64,
    /// The range α₀ … where f_st > 0: beyond it the flow is fully separated.
    pub attached_range: (f64, f64),
    airfoil: Airfoil,
    /// With several Reynolds-number tables: each table's (α₀, c_lα, attached range)
    /// ([`Self::with_tables`]); empty otherwise.
    tables: Vec<AttachedFlowLine>,
}

/// The attached-flow line of one table: α₀ [rad], c_lα [1/rad] and the attached range.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AttachedFlowLine {
    pub zero_lift: f64,
    pub lift_slope: f64,
    pub attached_range: (f64, f64),
}

/// Angular range where α₀ is sought [deg].
const ZERO_LIFT_SEARCH_DEG: f64 = 20.0;

impl OyeStall {
    /// The separation curves of an airfoil; `None` if its lift has no zero crossing with
    /// positive slope within ±20° (not a lifting airfoil).
    pub fn new(airfoil: &Airfoil) -> Option<Self> {
        let (alpha, cl) = airfoil.knots_cl();
        // α₀: the upward zero crossing of cl nearest 0 within ±20°, by bisection on the
        // interpolant.
        let lim = ZERO_LIFT_SEARCH_DEG.to_radians();
        let mut best: Option<f64> = None;
        for w in alpha.windows(2).zip(cl.windows(2)) {
            let ((a0, a1), (c0, c1)) = ((w.0[0], w.0[1]), (w.1[0], w.1[1]));
            if a1 < -lim || a0 > lim || !(c0 <= 0.0 && c1 > 0.0) {
                continue;
            }
            let (mut lo, mut hi) = (a0, a1);
            for _ in 0..100 {
                let m = 0.5 * (lo + hi);
                if airfoil.eval(m).cl <= 0.0 {
                    lo = m
                } else {
                    hi = m
                }
            }
            let r = 0.5 * (lo + hi);
            if best.is_none_or(|b: f64| r.abs() < b.abs()) {
                best = Some(r);
            }
        }
        let zero_lift = best?;
        // c_lα: the least-squares slope through α₀ of the table over α₀ − 4° … α₀ + 6°
        // (the attached range of wind-turbine and rotor airfoils).
        let (mut num, mut den) = (0.0, 0.0);
        for k in -8..=12 {
            let da = (0.5 * k as f64).to_radians();
            num += da * airfoil.eval(zero_lift + da).cl;
            den += da * da;
        }
        Self::with_attached(airfoil, zero_lift, num / den)
    }

    /// The separation curves for a given zero-lift angle α₀ [rad] and lift slope c_lα
    /// [1/rad] (an AeroDyn file's `alpha0` and `C_nalpha`, as UnsteadyAero takes them);
    /// `None` unless c_lα > 0. Where α₀ differs from the table's own zero crossing, the
    /// thin band between them (cl and α − α₀ of opposite signs) counts as attached.
    pub fn with_attached(airfoil: &Airfoil, zero_lift: f64, lift_slope: f64) -> Option<Self> {
        if !(lift_slope > 0.0 && lift_slope.is_finite() && zero_lift.is_finite()) {
            return None;
        }
        // The attached range: from α₀ outward to where cl/cl_inv first falls to ¼
        // (f_st = 0), by scanning in 0.1° and bisecting.
        let ratio = |a: f64| airfoil.eval(a).cl / (lift_slope * (a - zero_lift));
        let separated = |a: f64| (0.0..=0.25).contains(&ratio(a));
        let edge = |dir: f64| {
            let step = 0.1f64.to_radians() * dir;
            let mut a = zero_lift + step;
            while (a - zero_lift).abs() < std::f64::consts::FRAC_PI_2 {
                if separated(a) {
                    let (mut lo, mut hi) = (a - step, a);
                    for _ in 0..60 {
                        let m = 0.5 * (lo + hi);
                        if separated(m) { hi = m } else { lo = m }
                    }
                    return hi;
                }
                a += step;
            }
            zero_lift + dir * std::f64::consts::FRAC_PI_2
        };
        let attached_range = (edge(-1.0), edge(1.0));
        Some(Self {
            lift_slope,
            zero_lift,
            attached_range,
            airfoil: airfoil.clone(),
            tables: Vec::new(),
        })
    }

    /// The curves of an airfoil with several Reynolds-number tables, each table with its
    /// own attached-flow line `lines[k]` (from [`Self::new`] or [`Self::with_attached`] of
    /// that table alone); read at a Reynolds number by [`Self::eval_re`]. `None` if there
    /// is not one line per table or the first gives no curves.
    pub fn with_tables(airfoil: &Airfoil, lines: &[AttachedFlowLine]) -> Option<Self> {
        if lines.len() != airfoil.tables() {
            return None;
        }
        let first = lines.first()?;
        let mut s = Self::with_attached(airfoil, first.zero_lift, first.lift_slope)?;
        s.tables = lines.to_vec();
        Some(s)
    }

    /// This curve's attached-flow line.
    pub fn line(&self) -> AttachedFlowLine {
        AttachedFlowLine {
            zero_lift: self.zero_lift,
            lift_slope: self.lift_slope,
            attached_range: self.attached_range,
        }
    }

    /// Whether the curves follow the Reynolds number ([`Self::with_tables`]).
    pub fn by_reynolds(&self) -> bool {
        self.tables.len() > 1
    }

    /// f_st, cl_fs, cl_inv at α and Reynolds number Re, as functions of both (dual
    /// numbers): Kirchhoff's decomposition ([`kirchhoff`]) of the interpolated static
    /// lift cl(α, Re) ([`Airfoil::coefficients`]) with α₀, c_lα mixed between the two
    /// tables' lines with the tables' weight t(Re), and the attached range the wider of
    /// the two. So f_st cl_inv + (1 − f_st) cl_fs = cl(α, Re) wherever the single-table
    /// curves reproduce their table; at a table's own Re, that table's curves.
    pub fn eval_re<S: Scalar>(&self, alpha: S, re: S) -> Curves<S> {
        let ([cl, _, _], c) = self.airfoil.coefficients(alpha, Some(re));
        let line = |k: usize| {
            let l = self.tables.get(k).copied().unwrap_or_else(|| self.line());
            (S::cst(l.zero_lift), S::cst(l.lift_slope), l.attached_range)
        };
        let (zero_lift, lift_slope, range) = match self.airfoil.reynolds_weight(re.re()) {
            TableWeight::One(k) => line(k),
            TableWeight::Two { k, t, dt } => {
                let w = re.chain(t, dt);
                let (a0, s0, r0) = line(k);
                let (a1, s1, r1) = line(k + 1);
                (
                    a0 + (a1 - a0) * w,
                    s0 + (s1 - s0) * w,
                    (r0.0.min(r1.0), r0.1.max(r1.1)),
                )
            }
        };
        kirchhoff(alpha, cl, c.dcl, zero_lift, lift_slope, range)
    }

    /// f_st, cl_fs, cl_inv and their derivatives with respect to α. With g = √f_st =
    /// 2√(cl/cl_inv) − 1 (Kirchhoff), cl_fs = cl_inv (1 + 3g)/(4(1 + g)) (no 0/0 as f → 1);
    /// cl_fs = cl where f_st = 0, cl/2 where f_st = 1 (Hansen et al. 2004). Where the
    /// table lifts more than c_lα(α − α₀) (r > 1) the attached lift is the table's own
    /// (cl_inv = cl, f_st = 1): the static polar is reproduced everywhere.
    pub fn eval(&self, alpha: f64) -> StallCurves {
        self.eval_with(alpha, self.airfoil.eval(alpha))
    }

    /// Whether [`Self::eval_with`] may take the static coefficients from `airfoil`'s
    /// [`Airfoil::eval`] (it reads the same first table).
    pub fn reads(&self, airfoil: &Airfoil) -> bool {
        self.airfoil.same_first_table(airfoil)
    }

    /// [`Self::eval`] from the static coefficients `c` at α of its airfoil's first table
    /// (a caller that has them already).
    pub fn eval_with(&self, alpha: f64, c: Coefficients) -> StallCurves {
        let a = super::airfoil::wrap(alpha);
        let (lo, hi) = self.attached_range;
        let d = a - self.zero_lift;
        let inv = self.lift_slope * d;
        let separated = StallCurves {
            f: 0.0,
            df: 0.0,
            fs: c.cl,
            dfs: c.dcl,
            inv,
            dinv: self.lift_slope,
        };
        if a <= lo || a >= hi {
            return separated;
        }
        // r = cl/cl_inv (its limit dcl/c_lα at α₀).
        let (r, dr) = if d.abs() < 1e-9 {
            (c.dcl / self.lift_slope, 0.0)
        } else {
            (
                c.cl / inv,
                (c.dcl * inv - c.cl * self.lift_slope) / (inv * inv),
            )
        };
        if !(0.0..1.0).contains(&r) {
            return StallCurves {
                f: 1.0,
                df: 0.0,
                fs: 0.5 * c.cl,
                dfs: 0.5 * c.dcl,
                inv: c.cl,
                dinv: c.dcl,
            };
        }
        if r <= 0.25 {
            return separated;
        }
        let sr = r.sqrt();
        let g = 2.0 * sr - 1.0;
        let dg = dr / sr;
        let q = (1.0 + 3.0 * g) / (4.0 * (1.0 + g));
        let dq = 1.0 / (2.0 * (1.0 + g) * (1.0 + g));
        StallCurves {
            f: g * g,
            df: 2.0 * g * dg,
            fs: inv * q,
            dfs: self.lift_slope * q + inv * dq * dg,
            inv,
            dinv: self.lift_slope,
        }
    }
}

/// f_st, cl_fs, cl_inv as dual numbers ([`OyeStall::eval_re`], [`kirchhoff`]).
#[derive(Clone, Copy, Debug)]
pub struct Curves<S> {
    pub f: S,
    pub fs: S,
    pub inv: S,
}

/// Kirchhoff's decomposition of a static lift `cl` at the angle `alpha` (both dual
/// numbers; `dcl` = dcl/dα, used only at α₀ where cl/cl_inv is 0/0) for the attached line
/// cl_inv = c_lα (α − α₀) and the attached `range`, as [`OyeStall::eval`] does for one
/// table: r = cl/cl_inv, f_st = (2√r − 1)² for ¼ < r < 1, cl_fs = cl_inv (1 + 3g)/(4(1 + g))
/// (g = √f_st); f_st = 1, cl_fs = cl/2, cl_inv = cl where r ∉ [0, 1); f_st = 0, cl_fs = cl
/// where r ≤ ¼ or outside the range.
pub fn kirchhoff<S: Scalar>(
    alpha: S,
    cl: S,
    dcl: f64,
    zero_lift: S,
    lift_slope: S,
    range: (f64, f64),
) -> Curves<S> {
    let a = super::airfoil::wrap(alpha.re());
    // α wrapped to −π … π (a shift by whole turns: the same derivatives).
    let alpha = alpha + (a - alpha.re());
    let d = alpha - zero_lift;
    let inv = lift_slope * d;
    let separated = Curves {
        f: S::cst(0.0),
        fs: cl,
        inv,
    };
    if a <= range.0 || a >= range.1 {
        return separated;
    }
    let r = if d.re().abs() < 1e-9 {
        S::cst(dcl / lift_slope.re())
    } else {
        cl / inv
    };
    if !(0.0..1.0).contains(&r.re()) {
        return Curves {
            f: S::cst(1.0),
            fs: cl * 0.5,
            inv: cl,
        };
    }
    if r.re() <= 0.25 {
        return separated;
    }
    let g = r.sqrt() * 2.0 - 1.0;
    let one = S::cst(1.0);
    Curves {
        f: g * g,
        fs: inv * (one + g * 3.0) / ((one + g) * 4.0),
        inv,
    }
}

/// Øye's curves at one angle: f_st, cl_fs, cl_inv and their α-derivatives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StallCurves {
    pub f: f64,
    pub df: f64,
    pub fs: f64,
    pub dfs: f64,
    pub inv: f64,
    pub dinv: f64,
}
