//! Beddoes–Leishman-type dynamic stall in the continuous four-state form of Hansen,
//! Gaunaa & Madsen (2004, Risø-R-1354, "HGM"), as OpenFAST's UnsteadyAero implements it
//! for `UAMod = 4` (docs/aerodynamics.md, "Beddoes–Leishman (HGM)").
//!
//! Inputs per station: the air speed U at the aerodynamic centre (quarter chord), the
//! angle α₃/₄ at the three-quarter chord and the nose-up pitch rate ω of the section.
//! With T_u = c/(2U) (held in 0.001 … 50 s) and T_u ω held in ±1.5:
//!
//! `ẋ₁ = −(b₁/T_u) x₁ + (b₁A₁/T_u) α₃/₄`, `ẋ₂ = −(b₂/T_u) x₂ + (b₂A₂/T_u) α₃/₄`
//! (circulatory lag, Wagner's function 1 − A₁e^{−b₁s} − A₂e^{−b₂s}, s = t/T_u),
//! `ẋ₃ = (C_l^p − x₃)/T_p` (leading-edge pressure lag, T_p = T_p0 T_u),
//! `ẋ₄ = (f_st(α_F) − x₄)/T_f` (separation-point lag, T_f = T_f0 T_u),
//!
//! `α_E = α₃/₄ (1 − A₁ − A₂) + x₁ + x₂`, `C_l^p = c_lα (α_E − α₀) + π T_u ω`,
//! `α_F = x₃/c_lα + α₀`, and the outputs (x₄ clipped to 0 … 1)
//!
//! `c_l,circ = x₄ c_lα (α_E − α₀) + (1 − x₄) c_l,fs(α_E)`, `c_l = c_l,circ + π T_u ω`,
//! `c_d = c_d(α_E) + (α₃/₄ − α_E) c_l,circ + (c_d(α_E) − C_d0) ΔC''_d,f + c_l,circ T_u ω`,
//! `ΔC''_d,f = (√f_st(α_E) − √x₄)/2 − (f_st(α_E) − x₄)/4`,
//! `c_m = c_m(α_E) − (π/2) T_u ω`,
//!
//! f_st and c_l,fs the Kirchhoff separation curves of the static polar for the given α₀,
//! c_lα ([`OyeStall`]). The time constants' scaling (T_f = T_f0 T_u, T_p = T_p0 T_u), the
//! drag's induced and torsional terms, the clipping of T_u, T_u ω and x₄ and the rate
//! U̇ = 0 in the x₁, x₂ rows follow UnsteadyAero (OpenFAST `modules/aerodyn/src/
//! UnsteadyAero.f90`, `UA_CalcContStateDeriv`, `UA_CalcOutput`, since OpenFAST 3.0; before
//! it T_f was 2 T_f0 T_u and the induced drag (α_ac − α_E) c_l). welib's `dynstall_mhh_*`
//! (E. Branlard) is the same model; reference/welib_hgm/ holds its solution of a section
//! pitching through stall. The rows are written `ẋ − g(x)` (rad/s for x₁, x₂; 1/s for
//! x₃, x₄).

use super::airfoil::{Airfoil, AirfoilError, TableWeight};
use super::unsteady::OyeStall;
use crate::math::dual::Scalar;
use std::f64::consts::PI;

/// The model's coefficients (an AeroDyn airfoil file's unsteady-aerodynamics block).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HgmCoefficients {
    /// A₁, A₂, b₁, b₂ of the circulatory (Wagner) response.
    pub a: [f64; 2],
    pub b: [f64; 2],
    /// T_f0, T_p: the separation and pressure time constants in units of T_u.
    pub t_f0: f64,
    pub t_p: f64,
    /// α₀ [rad], c_lα [1/rad] (the file's `C_nalpha`, as UnsteadyAero takes it), C_d0.
    pub zero_lift: Option<f64>,
    pub lift_slope: Option<f64>,
    pub cd0: Option<f64>,
}

impl HgmCoefficients {
    /// UnsteadyAero's defaults (A₁ = 0.3, A₂ = 0.7, b₁ = 0.14, b₂ = 0.53, T_f0 = 3,
    /// T_p = 1.7), α₀, c_lα and C_d0 from the table.
    pub const DEFAULT: Self = Self {
        a: [0.3, 0.7],
        b: [0.14, 0.53],
        t_f0: 3.0,
        t_p: 1.7,
        zero_lift: None,
        lift_slope: None,
        cd0: None,
    };

    /// The unsteady-aerodynamics block of one table of an AeroDyn (AirfoilInfo v1.01)
    /// airfoil file, looked for in the 1-based `lines` (the table's header): `None`
    /// without `InclUAdata = True`; a missing or unreadable coefficient, or a time
    /// constant or b ≤ 0, is an error at the file's line.
    pub fn from_aerodyn(
        text: &str,
        lines: std::ops::Range<usize>,
    ) -> Option<Result<Self, AirfoilError>> {
        let (_, incl) = keyed(text, "InclUAdata", &lines)?;
        if !incl.trim_matches('"').eq_ignore_ascii_case("true") {
            return None;
        }
        Some(Self::read(text, &lines))
    }

    fn read(text: &str, lines: &std::ops::Range<usize>) -> Result<Self, AirfoilError> {
        let get = |key: &str, positive: bool| -> Result<f64, AirfoilError> {
            let Some((line, v)) = keyed(text, key, lines) else {
                return Err(AirfoilError {
                    line: 0,
                    column: 0,
                    message: format!(
                        "the unsteady-aerodynamics block (InclUAdata = True) has no `{key}`"
                    ),
                    hint: Some(format!(
                        "add a line `<value>  {key}` to the block (the Beddoes–Leishman HGM model needs A1, A2, b1, b2, T_f0, T_p, alpha0, C_nalpha, Cd0)"
                    )),
                });
            };
            let x: f64 = v.parse().map_err(|_| AirfoilError {
                line,
                column: 1,
                message: format!("`{key}` = {v}: expected a number"),
                hint: Some("the HGM model does not take \"Default\" for this coefficient".into()),
            })?;
            if !x.is_finite() || (positive && x <= 0.0) {
                return Err(AirfoilError {
                    line,
                    column: 1,
                    message: format!(
                        "`{key}` = {v}: expected a finite number{}",
                        if positive { " > 0" } else { "" }
                    ),
                    hint: Some(
                        "time constants and the b's of the Wagner response are positive".into(),
                    ),
                });
            }
            Ok(x)
        };
        Ok(Self {
            a: [get("A1", false)?, get("A2", false)?],
            b: [get("b1", true)?, get("b2", true)?],
            t_f0: get("T_f0", true)?,
            t_p: get("T_p", true)?,
            zero_lift: Some(get("alpha0", false)?.to_radians()),
            lift_slope: Some(get("C_nalpha", true)?),
            cd0: Some(get("Cd0", false)?),
        })
    }
}

/// Value of the first `value  Name  ! comment` line within the 1-based `lines` whose
/// second token is `key`, and its line.
fn keyed<'a>(text: &'a str, key: &str, lines: &std::ops::Range<usize>) -> Option<(usize, &'a str)> {
    text.lines().enumerate().find_map(|(k, l)| {
        if !lines.contains(&(k + 1)) {
            return None;
        }
        let mut t = l.split_whitespace();
        let v = t.next()?;
        (t.next()? == key).then_some((k + 1, v))
    })
}

/// The HGM model of one airfoil: coefficients and separation curves.
#[derive(Clone, Debug)]
pub struct Hgm {
    pub a: [f64; 2],
    pub b: [f64; 2],
    pub t_f0: f64,
    pub t_p: f64,
    pub zero_lift: f64,
    pub lift_slope: f64,
    pub cd0: f64,
    curves: OyeStall,
    airfoil: Airfoil,
    /// With several Reynolds-number tables ([`Self::with_tables`]): each table's
    /// coefficients [A₁, A₂, b₁, b₂, T_f0, T_p, α₀, c_lα, C_d0]; empty otherwise.
    tables: Vec<[f64; 9]>,
}

/// The flow a station gives the model: U at the quarter chord, α₃/₄ at the three-quarter
/// chord, ω the nose-up pitch rate.
#[derive(Clone, Copy, Debug)]
pub struct HgmFlow<S> {
    pub speed: S,
    pub alpha_34: S,
    pub omega: S,
}

/// What the model gives at one instant.
#[derive(Clone, Copy, Debug)]
pub struct HgmOutput<S> {
    pub cl: S,
    pub cd: S,
    pub cm: S,
    pub alpha_e: S,
    /// The state rows ẋ − g(x).
    pub rows: [S; 4],
}

/// T_u's bounds [s] (UnsteadyAero's).
const TU_MIN: f64 = 0.001;
const TU_MAX: f64 = 50.0;
/// The bound of T_u ω (UnsteadyAero's `MaxTuOmega`).
const TU_OMEGA_MAX: f64 = 1.5;

impl Hgm {
    /// The model of `airfoil` with `c` (α₀, c_lα, C_d0 taken from the table where not
    /// given: its zero-lift angle, least-squares slope and c_d(α₀)); `None` if the
    /// airfoil has no attached-flow lift curve.
    pub fn new(airfoil: &Airfoil, c: &HgmCoefficients) -> Option<Self> {
        let fitted = OyeStall::new(airfoil);
        let zero_lift = match c.zero_lift {
            Some(a) => a,
            None => fitted.as_ref()?.zero_lift,
        };
        let lift_slope = match c.lift_slope {
            Some(s) => s,
            None => fitted.as_ref()?.lift_slope,
        };
        let curves = OyeStall::with_attached(airfoil, zero_lift, lift_slope)?;
        Some(Self {
            a: c.a,
            b: c.b,
            t_f0: c.t_f0,
            t_p: c.t_p,
            zero_lift,
            lift_slope,
            cd0: c.cd0.unwrap_or_else(|| airfoil.eval(zero_lift).cd),
            curves,
            airfoil: airfoil.clone(),
            tables: Vec::new(),
        })
    }

    /// The model of an airfoil with several Reynolds-number tables, `c[k]` the
    /// coefficients of table k (its own UA block): each table's model as [`Self::new`]
    /// builds it for that table alone; at a Reynolds number ([`Self::eval`] with `re`)
    /// every coefficient is mixed linearly with the tables' weight t(Re), as AeroDyn's
    /// AirfoilInfo does for AFTabMod = 2, and the separation curves are Kirchhoff's of the
    /// interpolated polar ([`OyeStall::eval_re`]). `None` if a table has no attached-flow
    /// lift curve (or `c` is not one per table).
    pub fn with_tables(airfoil: &Airfoil, c: &[HgmCoefficients]) -> Option<Self> {
        if c.len() != airfoil.tables() {
            return None;
        }
        let models: Vec<Self> = (0..c.len())
            .map(|k| Self::new(&airfoil.table(k), &c[k]))
            .collect::<Option<_>>()?;
        let lines: Vec<_> = models.iter().map(|m| m.curves.line()).collect();
        let first = &models[0];
        Some(Self {
            curves: OyeStall::with_tables(airfoil, &lines)?,
            airfoil: airfoil.clone(),
            tables: models
                .iter()
                .map(|m| {
                    [
                        m.a[0],
                        m.a[1],
                        m.b[0],
                        m.b[1],
                        m.t_f0,
                        m.t_p,
                        m.zero_lift,
                        m.lift_slope,
                        m.cd0,
                    ]
                })
                .collect(),
            ..first.clone()
        })
    }

    /// Whether the model follows the Reynolds number ([`Self::with_tables`]).
    pub fn by_reynolds(&self) -> bool {
        self.tables.len() > 1
    }

    /// The coefficients [A₁, A₂, b₁, b₂, T_f0, T_p, α₀, c_lα, C_d0] at Reynolds number
    /// `re` (constants without Re tables).
    fn coefficients<S: Scalar>(&self, re: Option<S>) -> [S; 9] {
        let own = [
            self.a[0],
            self.a[1],
            self.b[0],
            self.b[1],
            self.t_f0,
            self.t_p,
            self.zero_lift,
            self.lift_slope,
            self.cd0,
        ];
        match re {
            Some(re) if self.by_reynolds() => match self.airfoil.reynolds_weight(re.re()) {
                TableWeight::One(k) => self.tables[k].map(S::cst),
                TableWeight::Two { k, t, dt } => {
                    let w = re.chain(t, dt);
                    let (p, q) = (&self.tables[k], &self.tables[k + 1]);
                    std::array::from_fn(|i| w * (q[i] - p[i]) + p[i])
                }
            },
            _ => own.map(S::cst),
        }
    }

    /// T_u = c/(2U) within its bounds (constant where clipped).
    fn tu<S: Scalar>(chord: f64, speed: S) -> S {
        let tu = S::cst(0.5 * chord) / speed;
        if tu.re() < TU_MIN {
            S::cst(TU_MIN)
        } else if tu.re() > TU_MAX {
            S::cst(TU_MAX)
        } else {
            tu
        }
    }

    /// The states' steady values for constant inputs (x₁ = A₁α₃/₄, x₂ = A₂α₃/₄,
    /// x₃ = c_lα(α₃/₄ − α₀), x₄ = f_st(α₃/₄)), UnsteadyAero's `HGM_Steady`; with Re
    /// tables, at the Reynolds number `re` (NaN: the first table).
    pub fn steady_states(&self, alpha_34: f64, re: f64) -> [f64; 4] {
        if self.by_reynolds() && !re.is_nan() {
            let [a1, a2, _, _, _, _, a0, cla, _] = self.coefficients(Some(re));
            let x3 = cla * (alpha_34 - a0);
            let alpha_f = x3 / cla + a0;
            return [
                a1 * alpha_34,
                a2 * alpha_34,
                x3,
                self.curves.eval_re(alpha_f, re).f,
            ];
        }
        let x3 = self.lift_slope * (alpha_34 - self.zero_lift);
        let alpha_f = x3 / self.lift_slope + self.zero_lift;
        [
            self.a[0] * alpha_34,
            self.a[1] * alpha_34,
            x3,
            self.curves.eval(alpha_f).f,
        ]
    }

    /// The state rows and the coefficients (module doc) for the flow `u`, the four states
    /// `x` and rates `xd`, chord c; with Re tables, at the Reynolds number `re` (`None`:
    /// the first table).
    pub fn eval<S: Scalar>(
        &self,
        chord: f64,
        u: &HgmFlow<S>,
        x: &[S],
        xd: &[S],
        re: Option<S>,
    ) -> HgmOutput<S> {
        let HgmFlow {
            speed,
            alpha_34,
            omega,
        } = *u;
        let by_re = re.filter(|_| self.by_reynolds());
        let [a1, a2, b1, b2, t_f0, t_p, zero_lift, lift_slope, cd0] = self.coefficients(by_re);
        let tu = Self::tu(chord, speed);
        let one = S::cst(1.0);
        let alpha_e = alpha_34 * (one - a1 - a2) + x[0] + x[1];
        // T_u ω within ±1.5 (constant where clipped).
        let tu_omega = tu * omega;
        let tu_omega = if tu_omega.re().abs() > TU_OMEGA_MAX {
            S::cst(TU_OMEGA_MAX.copysign(tu_omega.re()))
        } else {
            tu_omega
        };
        let pitch = tu_omega * PI;
        let clp = (alpha_e - zero_lift) * lift_slope + pitch;
        let alpha_f = x[2] / lift_slope + zero_lift;
        let fst_f = match by_re {
            Some(re) => self.curves.eval_re(alpha_f, re).f,
            None => {
                let ff = self.curves.eval(alpha_f.re());
                alpha_f.chain(ff.f, ff.df)
            }
        };
        // x₄ clipped to 0 … 1 (constant where clipped), as UnsteadyAero does.
        let x4 = if x[3].re() > 1.0 {
            S::cst(1.0)
        } else if x[3].re() < 0.0 {
            S::cst(0.0)
        } else {
            x[3]
        };
        let t_p = tu * t_p;
        let t_f = tu * t_f0;
        let rows = [
            xd[0] + (x[0] - alpha_34 * a1) * b1 / tu,
            xd[1] + (x[1] - alpha_34 * a2) * b2 / tu,
            xd[2] + (x[2] - clp) / t_p,
            xd[3] + (x4 - fst_f) / t_f,
        ];
        // Static f_st, c_l,fs, c_d, c_m at α_E.
        let (fst_e, cl_fs, cd_e, cm_e) = match by_re {
            Some(re) => {
                let sc = self.curves.eval_re(alpha_e, re);
                let ([_, cd, cm], _) = self.airfoil.coefficients(alpha_e, Some(re));
                (sc.f, sc.fs, cd, cm)
            }
            None => {
                let ae = alpha_e.re();
                let sc = self.curves.eval(ae);
                let tab = self.airfoil.eval(ae);
                (
                    alpha_e.chain(sc.f, sc.df),
                    alpha_e.chain(sc.fs, sc.dfs),
                    alpha_e.chain(tab.cd, tab.dcd),
                    alpha_e.chain(tab.cm, tab.dcm),
                )
            }
        };
        let cl_circ = x4 * (alpha_e - zero_lift) * lift_slope + (one - x4) * cl_fs;
        let cl = cl_circ + pitch;
        // ΔC''_d,f; √ has no derivative at 0: held constant there.
        let root = |v: S| {
            if v.re() > 1e-12 {
                v.sqrt()
            } else {
                S::cst(v.re().max(0.0).sqrt())
            }
        };
        let dcd = (root(fst_e) - root(x4)) * 0.5 - (fst_e - x4) * 0.25;
        let cd = cd_e + (alpha_34 - alpha_e) * cl_circ + (cd_e - cd0) * dcd + cl_circ * tu_omega;
        let cm = cm_e - pitch * 0.5;
        HgmOutput {
            cl,
            cd,
            cm,
            alpha_e,
            rows,
        }
    }
}
