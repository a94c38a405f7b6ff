//! Airfoil tables: lift, drag and pitching-moment coefficients cl, cd, cm(α) over the
//! whole circle −180° … 180°, read from a CSV table or an OpenFAST/AeroDyn airfoil file,
//! interpolated by a C¹ piecewise-cubic Hermite curve (docs/aerodynamics.md); several
//! tables at increasing Reynolds numbers are interpolated linearly in ln Re
//! ([`Airfoil::eval_re`]).
//!
//! Interpolation: on each interval [αᵢ, αᵢ₊₁] the cubic Hermite polynomial through the
//! values with the slopes of the three-point parabola at each knot,
//! mᵢ = (hᵢ₋₁ δᵢ + hᵢ δᵢ₋₁)/(hᵢ₋₁ + hᵢ) (δ the secant slopes, h the spacings),
//! taken across ±180° as the circle closes: the coefficients and their first derivative
//! are continuous, as Newton needs. The curve passes through every table point.

use crate::math::dual::Scalar;
use std::f64::consts::PI;

/// A parse or check error of an airfoil file, at a 1-based line and column of that file
/// (0: the file as a whole).
#[derive(Clone, Debug, PartialEq)]
pub struct AirfoilError {
    pub line: usize,
    pub column: usize,
    pub message: String,
    pub hint: Option<String>,
}

impl AirfoilError {
    fn at(line: usize, column: usize, message: impl Into<String>, hint: &str) -> Self {
        Self {
            line,
            column,
            message: message.into(),
            hint: (!hint.is_empty()).then(|| hint.to_string()),
        }
    }
}

impl std::fmt::Display for AirfoilError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.line > 0 {
            write!(
                f,
                "line {}, column {}: {}",
                self.line, self.column, self.message
            )
        } else {
            write!(f, "{}", self.message)
        }
    }
}

/// Coefficients and their derivatives with respect to α [1/rad].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Coefficients {
    pub cl: f64,
    pub cd: f64,
    pub cm: f64,
    pub dcl: f64,
    pub dcd: f64,
    pub dcm: f64,
}

/// One table of an airfoil covering −π … π.
#[derive(Clone, Debug, PartialEq)]
struct Table {
    /// Angles of attack [rad], strictly increasing, first −π, last π.
    alpha: Vec<f64>,
    /// cl, cd, cm at the knots.
    values: [Vec<f64>; 3],
    /// Their knot slopes.
    slopes: [Vec<f64>; 3],
    /// Where the interval search starts ([`Table::interval`]): entry b is the number of
    /// knots ≤ the left edge of the b-th of [`SEARCH_BINS`] equal bins of −π … π.
    bin_start: Vec<u32>,
}

/// Equal bins of −π … π indexing the interval search (1.4° each: a lookup steps over
/// the few knots of its bin instead of bisecting the whole table).
const SEARCH_BINS: usize = 256;

/// The search bin of α ∈ −π … π (the last one for π).
#[inline]
fn search_bin(a: f64) -> usize {
    (((a + PI) * (SEARCH_BINS as f64 / (2.0 * PI))) as usize).min(SEARCH_BINS - 1)
}

/// An airfoil: one table covering −π … π, or several at increasing Reynolds numbers
/// (interpolated linearly in ln Re by [`Airfoil::eval_re`], clamped to the first and last
/// table outside their range).
#[derive(Clone, Debug)]
pub struct Airfoil {
    /// The tables, at least one.
    tables: Vec<Table>,
    /// The Reynolds number of each table (NaN where a single table gives none), strictly
    /// increasing with several tables, and their logarithms.
    reynolds: Vec<f64>,
    log_reynolds: Vec<f64>,
    /// The unsteady-aerodynamics block of each table of an AeroDyn file (`InclUAdata =
    /// True`), read for the Beddoes–Leishman (HGM) model; an error is reported only where
    /// the block is used.
    ua: Vec<Option<Result<super::hgm::HgmCoefficients, AirfoilError>>>,
    /// Each table's `UserProp` (or `Ctrl`) of an AeroDyn file and its 1-based line (NaN,
    /// 0 where absent).
    user_props: Vec<(f64, usize)>,
    /// Whether the tables are interpolated in `UserProp` (AeroDyn's AFTabMod = 3,
    /// [`Self::by_user_property`]) rather than in the Reynolds number.
    by_user: bool,
}

/// Which tables a Reynolds number (or a user property) reads ([`Airfoil::reynolds_weight`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TableWeight {
    /// One table, unchanged (a single table, or Re outside the tables' range).
    One(usize),
    /// Tables k and k + 1 mixed as (1 − t) c_k + t c_{k+1}, with dt/dRe.
    Two { k: usize, t: f64, dt: f64 },
}

/// One table as read: its Reynolds number (NaN if none is given), the 1-based line where
/// the number is (0: none), and the rows (line, [α °, cl, cd, cm]).
pub type TableRows = (f64, usize, Vec<(usize, [f64; 4])>);

/// How far from ±180° a table end may be [deg] (printed tables round).
const COVER_TOL_DEG: f64 = 1e-6;

impl Airfoil {
    /// A table from rows (α [deg], cl, cd, cm) with the 1-based file line of each row
    /// (for messages; 0 if built in code). Checks: finite values, α strictly increasing,
    /// first −180°, last 180°.
    pub fn from_rows(rows: &[(usize, [f64; 4])]) -> Result<Self, AirfoilError> {
        Ok(Self {
            tables: vec![Table::from_rows(rows)?],
            reynolds: vec![f64::NAN],
            log_reynolds: vec![f64::NAN],
            ua: vec![None],
            user_props: vec![(f64::NAN, 0)],
            by_user: false,
        })
    }

    /// An airfoil from several tables, each with its Reynolds number (> 0, strictly
    /// increasing from table to table) and each covering −180° … 180° (its own α grid).
    /// A single table may have no Reynolds number (NaN).
    pub fn from_tables(tables: &[TableRows]) -> Result<Self, AirfoilError> {
        Self::build(tables, true)
    }

    /// [`Self::from_tables`], the Reynolds numbers' order checked only if `check_re`.
    fn build(tables: &[TableRows], check_re: bool) -> Result<Self, AirfoilError> {
        let Some(first) = tables.first() else {
            return Err(AirfoilError::at(0, 0, "the file has no table", ""));
        };
        if tables.len() > 1 {
            for (k, (re, line, _)) in tables.iter().enumerate() {
                if !(re.is_finite() && *re > 0.0) {
                    return Err(AirfoilError::at(
                        *line,
                        1,
                        format!(
                            "table {} has Reynolds number {re}: with several tables each needs a Reynolds number > 0",
                            k + 1
                        ),
                        "give every table its Reynolds number",
                    ));
                }
            }
            for (k, w) in tables.windows(2).enumerate() {
                if check_re && w[1].0 <= w[0].0 {
                    return Err(AirfoilError::at(
                        w[1].1,
                        1,
                        format!(
                            "the Reynolds number of table {} ({}) does not exceed that of table {} ({}): tables must be sorted by strictly increasing Reynolds number",
                            k + 2,
                            w[1].0,
                            k + 1,
                            w[0].0
                        ),
                        "order the tables by Reynolds number; tables of one Reynolds number with increasing UserProp (AeroDyn's AFTabMod = 3) are read for a line's `user_property`",
                    ));
                }
            }
        }
        let built = tables
            .iter()
            .map(|(_, _, rows)| Table::from_rows(rows))
            .collect::<Result<Vec<_>, _>>()?;
        let reynolds: Vec<f64> = if tables.len() == 1 {
            vec![first.0]
        } else {
            tables.iter().map(|t| t.0).collect()
        };
        Ok(Self {
            ua: vec![None; built.len()],
            user_props: vec![(f64::NAN, 0); built.len()],
            by_user: false,
            tables: built,
            log_reynolds: reynolds.iter().map(|r| r.ln()).collect(),
            reynolds,
        })
    }

    /// Number of tables (Reynolds numbers).
    pub fn tables(&self) -> usize {
        self.tables.len()
    }

    /// The tables' Reynolds numbers (NaN for a single table without one).
    pub fn reynolds_numbers(&self) -> &[f64] {
        &self.reynolds
    }

    /// Table k alone, as a single-table airfoil (with its own unsteady-aerodynamics block).
    pub fn table(&self, k: usize) -> Self {
        Self {
            tables: vec![self.tables[k].clone()],
            reynolds: vec![self.reynolds[k]],
            log_reynolds: vec![self.log_reynolds[k]],
            ua: vec![self.ua[k].clone()],
            user_props: vec![self.user_props[k]],
            by_user: false,
        }
    }

    /// Whether the tables are sorted by strictly increasing Reynolds number (as
    /// `reynolds = "interpolate"` needs).
    pub fn sorted_by_reynolds(&self) -> bool {
        self.tables.len() == 1 || self.reynolds.windows(2).all(|w| w[1] > w[0])
    }

    /// The tables' user properties (`UserProp`/`Ctrl` of an AeroDyn file; NaN where absent).
    pub fn user_properties(&self) -> Vec<f64> {
        self.user_props.iter().map(|u| u.0).collect()
    }

    /// The airfoil with its tables interpolated linearly in their `UserProp` (AeroDyn's
    /// AFTabMod = 3): [`Self::eval_re`], [`Self::coefficients`] and
    /// [`Self::reynolds_weight`] then take the user property u in place of Re,
    /// c = (1 − t) c_k + t c_{k+1}, t = (u − u_k)/(u_{k+1} − u_k), the first or last table
    /// beyond the range. An error (at the file's line) unless there are several tables,
    /// each with a `UserProp`, strictly increasing.
    pub fn by_user_property(&self) -> Result<Self, AirfoilError> {
        if self.tables.len() < 2 {
            return Err(AirfoilError::at(
                0,
                0,
                "the airfoil has a single table: interpolating on a user property needs several tables, each with its `UserProp`",
                "give an AeroDyn file with NumTabs > 1 and a `UserProp` line per table",
            ));
        }
        for (k, &(u, line)) in self.user_props.iter().enumerate() {
            if !u.is_finite() {
                return Err(AirfoilError::at(
                    line,
                    1,
                    format!("table {} has no `UserProp` (or `Ctrl`) value", k + 1),
                    "give each table a line `<value>  UserProp` before its `NumAlf` line",
                ));
            }
        }
        for (k, w) in self.user_props.windows(2).enumerate() {
            if w[1].0 <= w[0].0 {
                return Err(AirfoilError::at(
                    w[1].1,
                    1,
                    format!(
                        "the UserProp of table {} ({}) does not exceed that of table {} ({}): tables must be sorted by strictly increasing UserProp",
                        k + 2,
                        w[1].0,
                        k + 1,
                        w[0].0
                    ),
                    "order the tables by UserProp",
                ));
            }
        }
        let mut a = self.clone();
        a.by_user = true;
        Ok(a)
    }

    /// The airfoil with the tables' user properties set to `u` (one per table; tables
    /// built in code, which have none).
    pub fn with_user_properties(mut self, u: &[f64]) -> Self {
        for (p, &v) in self.user_props.iter_mut().zip(u) {
            *p = (v, 0);
        }
        self
    }

    /// Whether the tables are interpolated in the user property ([`Self::by_user_property`]).
    pub fn interpolates_user_property(&self) -> bool {
        self.by_user
    }

    /// The tables Re reads: linear in ln Re between the two around it,
    /// t = (ln Re − ln Re_k)/(ln Re_{k+1} − ln Re_k) (AeroDyn's AFTabMod = 2); the first
    /// or last table alone outside their range (and for a single table, or Re = NaN).
    pub fn reynolds_weight(&self, re: f64) -> TableWeight {
        let n = self.tables.len();
        if self.by_user {
            // Linear in the user property u.
            let u = re;
            let up = &self.user_props;
            if u.is_nan() || u <= up[0].0 {
                return TableWeight::One(0);
            }
            if u >= up[n - 1].0 {
                return TableWeight::One(n - 1);
            }
            let k = up.partition_point(|p| p.0 <= u) - 1;
            let span = up[k + 1].0 - up[k].0;
            return TableWeight::Two {
                k,
                t: (u - up[k].0) / span,
                dt: 1.0 / span,
            };
        }
        if n == 1 || re.is_nan() || re <= self.reynolds[0] {
            return TableWeight::One(0);
        }
        if re >= self.reynolds[n - 1] {
            return TableWeight::One(n - 1);
        }
        let k = self.reynolds.partition_point(|&r| r <= re) - 1;
        let span = self.log_reynolds[k + 1] - self.log_reynolds[k];
        TableWeight::Two {
            k,
            t: (re.ln() - self.log_reynolds[k]) / span,
            dt: 1.0 / (re * span),
        }
    }
}

impl Table {
    fn from_rows(rows: &[(usize, [f64; 4])]) -> Result<Self, AirfoilError> {
        if rows.len() < 3 {
            return Err(AirfoilError::at(
                rows.last().map_or(0, |r| r.0),
                1,
                format!("the table has {} rows; at least 3 are needed", rows.len()),
                "give cl, cd, cm from −180° to 180°",
            ));
        }
        for (line, r) in rows {
            if let Some(k) = r.iter().position(|x| !x.is_finite()) {
                return Err(AirfoilError::at(
                    *line,
                    1,
                    format!("{} is not a finite number", ["alpha", "cl", "cd", "cm"][k]),
                    "",
                ));
            }
        }
        for w in rows.windows(2) {
            if w[1].1[0] <= w[0].1[0] {
                return Err(AirfoilError::at(
                    w[1].0,
                    1,
                    format!(
                        "angles of attack must increase strictly: {}° follows {}°",
                        w[1].1[0], w[0].1[0]
                    ),
                    "sort the rows by α and remove repeated angles",
                ));
            }
        }
        let (first, last) = (&rows[0], &rows[rows.len() - 1]);
        if (first.1[0] + 180.0).abs() > COVER_TOL_DEG || (last.1[0] - 180.0).abs() > COVER_TOL_DEG {
            let (line, what) = if (first.1[0] + 180.0).abs() > COVER_TOL_DEG {
                (first.0, format!("the table starts at {}°", first.1[0]))
            } else {
                (last.0, format!("the table ends at {}°", last.1[0]))
            };
            return Err(AirfoilError::at(
                line,
                1,
                format!("{what}: airfoil tables must cover −180° … 180°"),
                "extend the polar to the full circle (e.g. Viterna extrapolation, as AirfoilPrep does); a blade section meets every angle in parked or starting rotors",
            ));
        }
        let alpha: Vec<f64> = rows.iter().map(|r| r.1[0].to_radians()).collect();
        let values: [Vec<f64>; 3] =
            std::array::from_fn(|c| rows.iter().map(|r| r.1[c + 1]).collect());
        let slopes = std::array::from_fn(|c| knot_slopes(&alpha, &values[c]));
        let bin_start = (0..SEARCH_BINS)
            .map(|b| {
                let edge = -PI + b as f64 * (2.0 * PI / SEARCH_BINS as f64);
                alpha.partition_point(|&x| x <= edge) as u32
            })
            .collect();
        Ok(Self {
            alpha,
            values,
            slopes,
            bin_start,
        })
    }

    /// The number of knots ≤ a (`partition_point(|x| x <= a)`), from the start of a's
    /// bin stepping back over knots above a (a bin edge rounded past a) and forward over
    /// knots up to a: the bisection's answer without its unpredictable branches.
    #[inline]
    fn interval(&self, a: f64) -> usize {
        let x = &self.alpha;
        let mut k = self.bin_start[search_bin(a)] as usize;
        while k > 0 && x[k - 1] > a {
            k -= 1;
        }
        while k < x.len() && x[k] <= a {
            k += 1;
        }
        k
    }

    /// The interval i of α [rad] (any angle: wrapped to −π … π), its width h and the
    /// local coordinate t = (α − αᵢ)/h.
    #[inline(always)]
    fn place(&self, alpha: f64) -> (usize, f64, f64) {
        let a = wrap(alpha);
        let n = self.alpha.len();
        let i = match self.interval(a) {
            0 => 0,
            k if k >= n => n - 2,
            k => k - 1,
        };
        let h = self.alpha[i + 1] - self.alpha[i];
        (i, h, (a - self.alpha[i]) / h)
    }

    /// The cubic Hermite basis h₀₀, h₁₀, h₀₁, h₁₁ at t.
    #[inline(always)]
    fn basis(t: f64) -> [f64; 4] {
        [
            (1.0 + 2.0 * t) * (1.0 - t) * (1.0 - t),
            t * (1.0 - t) * (1.0 - t),
            t * t * (3.0 - 2.0 * t),
            t * t * (t - 1.0),
        ]
    }

    /// The cubic Hermite pieces at α [rad] (any angle: wrapped to −π … π): the interval
    /// i, its width h, and the basis functions and their α-derivatives
    /// (h₀₀, h₁₀, h₀₁, h₁₁, then d/dα of each).
    #[inline(always)]
    fn hermite(&self, alpha: f64) -> (usize, f64, [f64; 4], [f64; 4]) {
        let (i, h, t) = self.place(alpha);
        (
            i,
            h,
            Self::basis(t),
            [
                6.0 * t * (t - 1.0) / h,
                (1.0 - t) * (1.0 - 3.0 * t) / h,
                6.0 * t * (1.0 - t) / h,
                t * (3.0 * t - 2.0) / h,
            ],
        )
    }

    /// Coefficient c (cl, cd, cm) on the basis b of interval i (width h):
    /// y = h₀₀ yᵢ + h₁₀ h mᵢ + h₀₁ yᵢ₊₁ + h₁₁ h mᵢ₊₁.
    #[inline(always)]
    fn value(&self, c: usize, i: usize, h: f64, b: &[f64; 4]) -> f64 {
        let (y0, y1) = (self.values[c][i], self.values[c][i + 1]);
        let (m0, m1) = (self.slopes[c][i], self.slopes[c][i + 1]);
        b[0] * y0 + b[1] * h * m0 + b[2] * y1 + b[3] * h * m1
    }

    /// Coefficient c (cl, cd, cm) and its α-derivative on the pieces of [`Self::hermite`].
    #[inline(always)]
    fn piece(&self, c: usize, (i, h, b, d): &(usize, f64, [f64; 4], [f64; 4])) -> (f64, f64) {
        let (i, h) = (*i, *h);
        let (y0, y1) = (self.values[c][i], self.values[c][i + 1]);
        let (m0, m1) = (self.slopes[c][i], self.slopes[c][i + 1]);
        (
            self.value(c, i, h, b),
            d[0] * y0 + d[1] * h * m0 + d[2] * y1 + d[3] * h * m1,
        )
    }

    /// Coefficients at α [rad] (any angle: wrapped to −π … π).
    fn eval(&self, alpha: f64) -> Coefficients {
        let at = self.hermite(alpha);
        let (cl, dcl) = self.piece(0, &at);
        let (cd, dcd) = self.piece(1, &at);
        let (cm, dcm) = self.piece(2, &at);
        Coefficients {
            cl,
            cd,
            cm,
            dcl,
            dcd,
            dcm,
        }
    }

    /// cl and cd at α with their α-derivatives, as [`Self::eval`] gives them.
    fn eval_lift_drag(&self, alpha: f64) -> [(f64, f64); 2] {
        let at = self.hermite(alpha);
        [self.piece(0, &at), self.piece(1, &at)]
    }

    /// cl and cd at α without their derivatives (the same values as
    /// [`Self::eval_lift_drag`]'s).
    fn lift_drag_values(&self, alpha: f64) -> [f64; 2] {
        let (i, h, t) = self.place(alpha);
        let b = Self::basis(t);
        [self.value(0, i, h, &b), self.value(1, i, h, &b)]
    }
}

impl Airfoil {
    /// The flat plate of thin-airfoil theory near zero incidence, cl = 2π sin α cos α
    /// (2πα for small α), cd = 0, cm = 0, tabulated every degree.
    pub fn thin_plate() -> Self {
        let rows: Vec<(usize, [f64; 4])> = (-180..=180)
            .map(|d| {
                let a = (d as f64).to_radians();
                (0, [d as f64, PI * (2.0 * a).sin(), 0.0, 0.0])
            })
            .collect();
        // The rows are valid by construction.
        Self::from_rows(&rows).unwrap_or_else(|_| unreachable!())
    }

    /// A smooth table with lift, drag and moment everywhere (for tangent checks):
    /// cl = π sin 2α, cd = 0.01 + 1.5 sin²α, cm = −0.1 sin α.
    pub fn thin_plate_with_drag() -> Self {
        let rows: Vec<(usize, [f64; 4])> = (-180..=180)
            .map(|d| {
                let a = (d as f64).to_radians();
                (
                    0,
                    [
                        d as f64,
                        PI * (2.0 * a).sin(),
                        0.01 + 1.5 * a.sin().powi(2),
                        -0.1 * a.sin(),
                    ],
                )
            })
            .collect();
        Self::from_rows(&rows).unwrap_or_else(|_| unreachable!())
    }

    /// Coefficients of the first table at α [rad] (any angle: wrapped to −π … π).
    pub fn eval(&self, alpha: f64) -> Coefficients {
        self.tables[0].eval(alpha)
    }

    /// Whether [`Self::eval`] of the two airfoils is the same function (equal first
    /// tables).
    pub fn same_first_table(&self, other: &Airfoil) -> bool {
        self.tables[0] == other.tables[0]
    }

    /// Coefficients at α [rad] and Reynolds number Re, with their derivatives over Re:
    /// linear in ln Re between the two tables around Re,
    /// c = (1 − t) c_k + t c_{k+1}, t = (ln Re − ln Re_k)/(ln Re_{k+1} − ln Re_k)
    /// (as AeroDyn's AFTabMod = 2), each table's own C¹ cubic in α; below the first
    /// table's Re the first table, above the last the last (∂/∂Re = 0 there). A single
    /// table: its coefficients whatever Re.
    pub fn eval_re(&self, alpha: f64, re: f64) -> (Coefficients, [f64; 3]) {
        let (k, t, dt) = match self.reynolds_weight(re) {
            TableWeight::One(k) => return (self.tables[k].eval(alpha), [0.0; 3]),
            TableWeight::Two { k, t, dt } => (k, t, dt),
        };
        let (a, b) = (self.tables[k].eval(alpha), self.tables[k + 1].eval(alpha));
        let mix = |x: f64, y: f64| (1.0 - t) * x + t * y;
        (
            Coefficients {
                cl: mix(a.cl, b.cl),
                cd: mix(a.cd, b.cd),
                cm: mix(a.cm, b.cm),
                dcl: mix(a.dcl, b.dcl),
                dcd: mix(a.dcd, b.dcd),
                dcm: mix(a.dcm, b.dcm),
            },
            [(b.cl - a.cl) * dt, (b.cd - a.cd) * dt, (b.cm - a.cm) * dt],
        )
    }

    /// cl, cd, cm as functions of α and, if given, Re ([`Self::eval_re`]; the first
    /// table without), with the derivatives of both carried (dual numbers), and their
    /// values.
    pub fn coefficients<S: Scalar>(&self, alpha: S, re: Option<S>) -> ([S; 3], Coefficients) {
        match re {
            None => {
                let c = self.eval(alpha.re());
                (
                    [
                        alpha.chain(c.cl, c.dcl),
                        alpha.chain(c.cd, c.dcd),
                        alpha.chain(c.cm, c.dcm),
                    ],
                    c,
                )
            }
            Some(re) => {
                let (c, d) = self.eval_re(alpha.re(), re.re());
                let dre = re - S::cst(re.re());
                (
                    [
                        alpha.chain(c.cl, c.dcl) + dre * d[0],
                        alpha.chain(c.cd, c.dcd) + dre * d[1],
                        alpha.chain(c.cm, c.dcm) + dre * d[2],
                    ],
                    c,
                )
            }
        }
    }

    /// cl and cd of [`Self::coefficients`] (the same values and derivatives, c_m left out:
    /// the momentum balance's lookup).
    pub fn lift_drag<S: Scalar>(&self, alpha: S, re: Option<S>) -> [S; 2] {
        match re {
            None if S::DIRECTIONS == 0 => self.tables[0].lift_drag_values(alpha.re()).map(S::cst),
            None => {
                let [(cl, dcl), (cd, dcd)] = self.tables[0].eval_lift_drag(alpha.re());
                [alpha.chain(cl, dcl), alpha.chain(cd, dcd)]
            }
            Some(_) => {
                let ([cl, cd, _], _) = self.coefficients(alpha, re);
                [cl, cd]
            }
        }
    }

    /// The knots' angles [rad] and lift coefficients (first table).
    pub fn knots_cl(&self) -> (&[f64], &[f64]) {
        (&self.tables[0].alpha, &self.tables[0].values[0])
    }

    /// Number of rows of the first table.
    pub fn len(&self) -> usize {
        self.tables[0].alpha.len()
    }

    pub fn is_empty(&self) -> bool {
        self.tables[0].alpha.is_empty()
    }

    /// Reads tables from text: CSV if `csv` (header `alpha,cl,cd[,cm]`, α in degrees, `#`
    /// comments; with a first column `re`, several tables: consecutive rows of equal Re
    /// form one, Re increasing), otherwise the OpenFAST/AeroDyn airfoil file format
    /// (AirfoilInfo v1.01: `NumTabs` tables, each with its `Re` line [millions] and the
    /// `NumAlf` rows of α [deg], cl, cd[, cm] after its `NumAlf` line; `!` comments).
    pub fn parse(text: &str, csv: bool) -> Result<Self, AirfoilError> {
        let (tables, user_props) = if csv {
            (parse_csv(text)?, Vec::new())
        } else {
            parse_aerodyn(text)?
        };
        // Tables of one Reynolds number told apart by their UserProp (AeroDyn's
        // AFTabMod = 3) are read unsorted in Re (their order is checked where they are
        // interpolated); otherwise the Reynolds numbers must increase.
        let by_user_prop = tables.len() > 1
            && user_props.len() == tables.len()
            && user_props.iter().all(|u: &(f64, usize)| u.0.is_finite())
            && user_props.windows(2).all(|w| w[1].0 > w[0].0);
        let mut a = Self::build(&tables, !by_user_prop)?;
        if !user_props.is_empty() {
            a.user_props = user_props;
        }
        if !csv {
            // Table k's header runs from the end of table k − 1's rows (its NumAlf line)
            // to its own NumAlf line.
            let starts = keyed_all(text, "NumAlf");
            for k in 0..a.ua.len() {
                let from = if k == 0 { 0 } else { starts[k - 1].0 };
                a.ua[k] = super::hgm::HgmCoefficients::from_aerodyn(text, from..starts[k].0);
            }
        }
        Ok(a)
    }

    /// The unsteady-aerodynamics coefficients of an AeroDyn file's first table, if it has
    /// them (or the error in them).
    pub fn ua_coefficients(&self) -> Option<&Result<super::hgm::HgmCoefficients, AirfoilError>> {
        self.ua[0].as_ref()
    }

    /// Those of table k.
    pub fn ua_coefficients_of(
        &self,
        k: usize,
    ) -> Option<&Result<super::hgm::HgmCoefficients, AirfoilError>> {
        self.ua[k].as_ref()
    }
}

/// α wrapped to [−π, π].
pub fn wrap(a: f64) -> f64 {
    if (-PI..=PI).contains(&a) {
        a
    } else {
        let w = (a + PI).rem_euclid(2.0 * PI) - PI;
        w.clamp(-PI, PI)
    }
}

/// Three-point slopes, periodic across the ends (the first and last knots are the same
/// angle, −π ≡ π).
fn knot_slopes(x: &[f64], y: &[f64]) -> Vec<f64> {
    let n = x.len();
    let three = |hl: f64, dl: f64, hr: f64, dr: f64| (hl * dr + hr * dl) / (hl + hr);
    let mut m = vec![0.0; n];
    for i in 1..n - 1 {
        let (hl, hr) = (x[i] - x[i - 1], x[i + 1] - x[i]);
        m[i] = three(hl, (y[i] - y[i - 1]) / hl, hr, (y[i + 1] - y[i]) / hr);
    }
    let (hl, hr) = (x[n - 1] - x[n - 2], x[1] - x[0]);
    let ends = three(hl, (y[n - 1] - y[n - 2]) / hl, hr, (y[1] - y[0]) / hr);
    m[0] = ends;
    m[n - 1] = ends;
    m
}

fn number(tok: &str, line: usize, column: usize, what: &str) -> Result<f64, AirfoilError> {
    tok.trim().parse::<f64>().map_err(|_| {
        AirfoilError::at(
            line,
            column,
            format!("expected a number ({what}), found '{}'", tok.trim()),
            "",
        )
    })
}

fn parse_csv(text: &str) -> Result<Vec<TableRows>, AirfoilError> {
    let mut tables: Vec<TableRows> = Vec::new();
    // Columns and whether the first is Re.
    let mut columns: Option<(usize, bool)> = None;
    const NAMES: [&str; 5] = ["re", "alpha", "cl", "cd", "cm"];
    for (k, raw) in text.lines().enumerate() {
        let line = k + 1;
        let content = raw.split('#').next().unwrap_or("").trim();
        if content.is_empty() {
            continue;
        }
        let cells: Vec<&str> = content.split(',').collect();
        match columns {
            None => {
                let names: Vec<String> = cells.iter().map(|c| c.trim().to_lowercase()).collect();
                let with_re = names.first().is_some_and(|n| n == "re");
                let n = &names[usize::from(with_re)..];
                let ok = n.len() >= 3
                    && n.len() <= 4
                    && (n[0] == "alpha" || n[0] == "alpha_deg")
                    && n[1] == "cl"
                    && n[2] == "cd"
                    && (n.len() == 3 || n[3] == "cm");
                if !ok {
                    return Err(AirfoilError::at(
                        line,
                        1,
                        format!(
                            "expected the header `alpha,cl,cd,cm` (or `re,alpha,cl,cd,cm`), found '{content}'"
                        ),
                        "the first line that is not a comment names the columns: optionally re (the Reynolds number of the row's table), then alpha (degrees), cl, cd and optionally cm",
                    ));
                }
                columns = Some((names.len(), with_re));
            }
            Some((nc, with_re)) => {
                if cells.len() != nc {
                    return Err(AirfoilError::at(
                        line,
                        1,
                        format!("expected {nc} values, found {}", cells.len()),
                        if with_re {
                            "one row per angle: re, alpha, cl, cd[, cm]"
                        } else {
                            "one row per angle: alpha, cl, cd[, cm]"
                        },
                    ));
                }
                let mut v = [0.0; 5];
                let mut col = 1;
                let names = &NAMES[usize::from(!with_re)..];
                for (j, c) in cells.iter().enumerate() {
                    v[j] = number(c, line, col, names[j])?;
                    col += c.len() + 1;
                }
                let (re, r) = if with_re {
                    (v[0], [v[1], v[2], v[3], v[4]])
                } else {
                    (f64::NAN, [v[0], v[1], v[2], v[3]])
                };
                match tables.last_mut() {
                    Some(t) if t.0 == re || (re.is_nan() && t.0.is_nan()) => t.2.push((line, r)),
                    Some(t) if re.partial_cmp(&t.0) != Some(std::cmp::Ordering::Greater) => {
                        return Err(AirfoilError::at(
                            line,
                            1,
                            format!(
                                "Re = {re} after a table at Re = {}: the tables must follow each other by strictly increasing Reynolds number, each in one block of rows",
                                t.0
                            ),
                            "sort the rows by re, then by alpha",
                        ));
                    }
                    _ => tables.push((re, line, vec![(line, r)])),
                }
            }
        }
    }
    if columns.is_none() {
        return Err(AirfoilError::at(
            0,
            0,
            "the file is empty",
            "give the header `alpha,cl,cd,cm` and one row per angle",
        ));
    }
    if tables.is_empty() {
        tables.push((f64::NAN, 0, Vec::new()));
    }
    Ok(tables)
}

/// Value of a `value  Name  ! comment` line of an OpenFAST file whose second token is `key`.
fn keyed<'a>(text: &'a str, key: &str) -> Option<(usize, &'a str)> {
    text.lines().enumerate().find_map(|(k, l)| {
        let mut t = l.split_whitespace();
        let v = t.next()?;
        (t.next()? == key).then_some((k + 1, v))
    })
}

/// The 1-based lines whose second token is `key`, and their first token.
fn keyed_all<'a>(text: &'a str, key: &str) -> Vec<(usize, &'a str)> {
    text.lines()
        .enumerate()
        .filter_map(|(k, l)| {
            let mut t = l.split_whitespace();
            let v = t.next()?;
            (t.next()? == key).then_some((k + 1, v))
        })
        .collect()
}

/// The tables of an AeroDyn file and each table's `UserProp` (or `Ctrl`) with its line
/// (NaN, 0 where absent).
type AeroDynTables = (Vec<TableRows>, Vec<(f64, usize)>);

fn parse_aerodyn(text: &str) -> Result<AeroDynTables, AirfoilError> {
    let ntabs = match keyed(text, "NumTabs") {
        Some((line, v)) => {
            let n = number(v, line, 1, "NumTabs")?;
            if !((1.0..=1000.0).contains(&n) && n.fract() == 0.0) {
                return Err(AirfoilError::at(
                    line,
                    1,
                    format!("NumTabs = {v}: expected a whole number of tables 1…1000"),
                    "",
                ));
            }
            Some((line, n as usize))
        }
        None => None,
    };
    let counts = keyed_all(text, "NumAlf");
    if counts.is_empty() {
        return Err(AirfoilError::at(
            0,
            0,
            "no `NumAlf` line: this is not an AeroDyn airfoil file",
            "give an AeroDyn (AirfoilInfo v1.01) file, or a `.csv` table with the header alpha,cl,cd,cm",
        ));
    }
    let res = keyed_all(text, "Re");
    let n_tabs = ntabs.map_or(1, |t| t.1);
    if counts.len() < n_tabs {
        let line = ntabs.map_or(0, |t| t.0);
        return Err(AirfoilError::at(
            line,
            1,
            format!(
                "NumTabs = {n_tabs} but the file has {} `NumAlf` line(s)",
                counts.len()
            ),
            "each table has its `Re`, `UserProp` (or `Ctrl`), `InclUAdata` and `NumAlf` lines, then its rows",
        ));
    }
    if n_tabs > 1 && res.len() < n_tabs {
        return Err(AirfoilError::at(
            ntabs.map_or(0, |t| t.0),
            1,
            format!(
                "NumTabs = {n_tabs} but the file has {} `Re` line(s)",
                res.len()
            ),
            "each table starts with its Reynolds number in millions: `<value>  Re`",
        ));
    }
    let mut tables = Vec::with_capacity(n_tabs);
    let mut user_props = Vec::with_capacity(n_tabs);
    for (t, &(line0, v)) in counts.iter().take(n_tabs).enumerate() {
        // The table's Reynolds number [millions], on a line before its NumAlf (and after
        // the previous table's).
        let re = match res.get(t) {
            Some(&(rl, rv)) => {
                let prev = if t > 0 { counts[t - 1].0 } else { 0 };
                if !(rl < line0 && rl > prev) {
                    return Err(AirfoilError::at(
                        rl,
                        1,
                        format!(
                            "the `Re` line of table {} is not between its `NumAlf` line and the previous table's",
                            t + 1
                        ),
                        "each table gives `Re` before its `NumAlf` line",
                    ));
                }
                (number(rv, rl, 1, "Re [millions]")? * 1e6, rl)
            }
            None => (f64::NAN, 0),
        };
        let n = number(v, line0, 1, "NumAlf")?;
        if !((3.0..=1e6).contains(&n) && n.fract() == 0.0) {
            return Err(AirfoilError::at(
                line0,
                1,
                format!("NumAlf = {v}: expected a whole number of rows ≥ 3"),
                "",
            ));
        }
        let n = n as usize;
        let mut rows = Vec::with_capacity(n);
        for (k, l) in text.lines().enumerate().skip(line0) {
            if rows.len() == n {
                break;
            }
            let tr = l.trim();
            if tr.is_empty() || tr.starts_with('!') {
                continue;
            }
            let line = k + 1;
            let toks: Vec<&str> = tr.split_whitespace().collect();
            if toks.len() < 3 {
                return Err(AirfoilError::at(
                    line,
                    1,
                    format!("expected alpha, cl, cd[, cm], found '{tr}'"),
                    "the NumAlf rows follow the NumAlf line",
                ));
            }
            let mut r = [0.0; 4];
            for j in 0..toks.len().min(4) {
                let col = l.find(toks[j]).map_or(1, |c| c + 1);
                r[j] = number(toks[j], line, col, ["alpha", "cl", "cd", "cm"][j])?;
            }
            rows.push((line, r));
        }
        if rows.len() < n {
            return Err(AirfoilError::at(
                line0,
                1,
                format!("NumAlf = {n} but the file has {} rows after it", rows.len()),
                "make NumAlf the number of table rows",
            ));
        }
        tables.push((re.0, re.1, rows));
        // The table's UserProp (or Ctrl), between the previous table's NumAlf line and
        // its own (its line, for messages: the NumAlf line where absent).
        let prev = if t > 0 { counts[t - 1].0 } else { 0 };
        let mut up = (f64::NAN, line0);
        for key in ["UserProp", "Ctrl"] {
            if let Some(&(ul, uv)) = keyed_all(text, key)
                .iter()
                .find(|(ul, _)| *ul > prev && *ul < line0)
            {
                up = (number(uv, ul, 1, key)?, ul);
                break;
            }
        }
        user_props.push(up);
    }
    Ok((tables, user_props))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The values-only lift and drag (f64) are the bits of the values the dual path reads.
    #[test]
    fn values_only_lift_drag_equals_the_differentiated_one() {
        let foil = Airfoil::thin_plate_with_drag();
        for k in -2000..=2000 {
            let alpha = 0.0017 * k as f64 + 1e-3;
            let [cl, cd] = foil.lift_drag(alpha, None);
            let [(vl, _), (vd, _)] = foil.tables[0].eval_lift_drag(alpha);
            assert_eq!(
                (cl.to_bits(), cd.to_bits()),
                (vl.to_bits(), vd.to_bits()),
                "{alpha}"
            );
            let c = foil.eval(alpha);
            assert_eq!(
                (cl.to_bits(), cd.to_bits()),
                (c.cl.to_bits(), c.cd.to_bits())
            );
        }
    }

    #[test]
    fn binned_interval_search_equals_bisection() {
        // Irregular knots (dense near 0, sparse at the ends, several per bin and bins with
        // none), probed at every knot, just beside it, at the bin edges and at random
        // angles: the binned search must give exactly the bisection's count.
        let mut deg: Vec<f64> = vec![-180.0, -170.0, -100.0, -31.3];
        deg.extend((-80..=80).map(|k| 0.25 * k as f64));
        deg.extend([27.5, 40.0, 90.0, 179.9, 180.0]);
        let rows: Vec<(usize, [f64; 4])> = deg.iter().map(|&d| (0, [d, 0.0, 0.0, 0.0])).collect();
        let t = Table::from_rows(&rows).unwrap();
        let bisect = |a: f64| t.alpha.partition_point(|&x| x <= a);
        let mut probes = vec![-PI, PI, 0.0, -0.0];
        for &x in &t.alpha {
            probes.extend([x, x.next_down(), x.next_up()]);
        }
        for b in 0..=SEARCH_BINS {
            let e = -PI + b as f64 * (2.0 * PI / SEARCH_BINS as f64);
            probes.extend([e, e.next_down(), e.next_up()]);
        }
        let mut u = 0.123_f64;
        for _ in 0..10_000 {
            u = (u * 9301.0 + 0.49297).fract();
            probes.push(-PI + 2.0 * PI * u);
        }
        for a in probes.into_iter().filter(|a| (-PI..=PI).contains(a)) {
            assert_eq!(t.interval(a), bisect(a), "α = {a}");
        }
    }

    #[test]
    fn cubic_reproduces_a_quadratic_inside_and_is_c1() {
        // On a uniform grid the three-point slopes are exact for a parabola: the Hermite
        // cubic reproduces it between interior knots.
        let rows: Vec<(usize, [f64; 4])> = (-36..=36)
            .map(|k| {
                let d = 5.0 * k as f64;
                let a = d.to_radians();
                (0, [d, 1.0 + a - 0.3 * a * a, 0.01, 0.0])
            })
            .collect();
        let af = Airfoil::from_rows(&rows).unwrap();
        for a in [-1.0, -0.1234, 0.0, 0.4, 2.0] {
            let c = af.eval(a);
            assert!((c.cl - (1.0 + a - 0.3 * a * a)).abs() < 1e-12);
            assert!((c.dcl - (1.0 - 0.6 * a)).abs() < 1e-12);
        }
        // Continuity of value and slope across every knot (and across ±180°).
        for row in &rows[1..rows.len() - 1] {
            let a = row.1[0].to_radians();
            let (l, r) = (af.eval(a - 1e-9), af.eval(a + 1e-9));
            assert!((l.cl - r.cl).abs() < 1e-7 && (l.dcl - r.dcl).abs() < 1e-6);
        }
    }
}
