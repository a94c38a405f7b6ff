//! A terrain height z(x, y) given as a table on a rectangular grid (increasing, possibly
//! non-uniform coordinates), interpolated by the tensor product of cubic Hermite splines
//! with three-point (Catmull–Rom on a uniform grid) node slopes:
//!
//! `z(x, y) = Σ_k Σ_l w_k(x) v_l(y) z_kl`,
//!
//! on the cell `[x_i, x_(i+1)]`: `f = h₀₀(s) z_i + h₁₀(s) Δ m_i + h₀₁(s) z_(i+1) + h₁₁(s) Δ m_(i+1)`,
//! `s = (x − x_i)/Δ`, with the slope at an inner node the derivative of the parabola
//! through three neighbours,
//! `m_i = −Δ_R/(Δ_L(Δ_L+Δ_R)) z_(i−1) + (Δ_R−Δ_L)/(Δ_LΔ_R) z_i + Δ_L/(Δ_R(Δ_L+Δ_R)) z_(i+1)`,
//! one-sided at the ends (Fritsch & Carlson 1980, §2;
//! Catmull & Rom 1974 on a uniform grid). The surface is C¹ (continuous slope, so Newton
//! sees a continuous normal), reproduces bilinear data — planes in particular — exactly,
//! and is third-order accurate for smooth terrain away from the table's edge (second order
//! in the edge cells, where the slopes are one-sided). One row (`y` with one value) is a
//! profile z(x), constant across.
//!
//! [`HeightField::eval`] gives the height, gradient and Hessian (the exact tangents of a
//! contact on the surface need the Hessian: the normal turns with the slope).

/// Why a table is not a height field.
#[derive(Clone, Debug, PartialEq)]
pub enum HeightFieldError {
    /// Fewer than 2 x values, or no y value.
    TooFew { axis: &'static str, len: usize },
    /// Coordinates not strictly increasing (or not finite) at this index.
    NotIncreasing { axis: &'static str, index: usize },
    /// The table has `got` rows/columns where `expected` are needed.
    SizeMismatch {
        what: &'static str,
        expected: usize,
        got: usize,
    },
    /// A height that is not finite, at (row j, column i).
    NotFinite { row: usize, column: usize },
}

impl std::fmt::Display for HeightFieldError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::TooFew { axis, len } => write!(
                f,
                "the height field needs at least {} `{axis}` value{} (got {len})",
                if *axis == "x" { 2 } else { 1 },
                if *axis == "x" { "s" } else { "" }
            ),
            Self::NotIncreasing { axis, index } => write!(
                f,
                "the height field's `{axis}` values must be finite and strictly increasing (not at index {index})"
            ),
            Self::SizeMismatch {
                what,
                expected,
                got,
            } => write!(
                f,
                "the height table has {got} {what} where {expected} are needed"
            ),
            Self::NotFinite { row, column } => {
                write!(f, "the height at row {row}, column {column} is not finite")
            }
        }
    }
}

/// Height, gradient and Hessian at a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Height {
    pub z: f64,
    /// (∂z/∂x, ∂z/∂y).
    pub gradient: [f64; 2],
    /// [[z_xx, z_xy], [z_xy, z_yy]].
    pub hessian: [[f64; 2]; 2],
}

/// A tabulated terrain.
#[derive(Clone, Debug, PartialEq)]
pub struct HeightField {
    x: Vec<f64>,
    y: Vec<f64>,
    /// `z[j][i] = z(x_i, y_j)`, stored row by row.
    z: Vec<f64>,
}

/// Weights of the four nodes `idx` of a 1-D interpolation at one abscissa, with their
/// first and second derivatives.
struct Weights {
    idx: [usize; 4],
    w: [f64; 4],
    dw: [f64; 4],
    ddw: [f64; 4],
}

/// Coefficients of the slope at node i on the values of nodes i−1, i, i+1.
fn slope_coefficients(c: &[f64], i: usize) -> [f64; 3] {
    let n = c.len();
    if i == 0 {
        let h = c[1] - c[0];
        [0.0, -1.0 / h, 1.0 / h]
    } else if i == n - 1 {
        let h = c[n - 1] - c[n - 2];
        [-1.0 / h, 1.0 / h, 0.0]
    } else {
        let (hl, hr) = (c[i] - c[i - 1], c[i + 1] - c[i]);
        [
            -hr / (hl * (hl + hr)),
            (hr - hl) / (hl * hr),
            hl / (hr * (hl + hr)),
        ]
    }
}

/// The cubic Hermite weights of the nodes around `t` (None outside the table).
fn weights(c: &[f64], t: f64) -> Option<Weights> {
    let n = c.len();
    if n == 1 {
        return Some(Weights {
            idx: [0; 4],
            w: [1.0, 0.0, 0.0, 0.0],
            dw: [0.0; 4],
            ddw: [0.0; 4],
        });
    }
    if !(t >= c[0] && t <= c[n - 1]) {
        return None;
    }
    // The cell [c_i, c_(i+1)] holding t.
    let i = c.partition_point(|&v| v <= t).clamp(1, n - 1) - 1;
    let h = c[i + 1] - c[i];
    let s = (t - c[i]) / h;
    // Hermite basis and its derivatives in s.
    let (s2, s3) = (s * s, s * s * s);
    let b = [
        2.0 * s3 - 3.0 * s2 + 1.0,
        s3 - 2.0 * s2 + s,
        -2.0 * s3 + 3.0 * s2,
        s3 - s2,
    ];
    let db = [
        6.0 * s2 - 6.0 * s,
        3.0 * s2 - 4.0 * s + 1.0,
        -6.0 * s2 + 6.0 * s,
        3.0 * s2 - 2.0 * s,
    ];
    let ddb = [
        12.0 * s - 6.0,
        6.0 * s - 4.0,
        -12.0 * s + 6.0,
        6.0 * s - 2.0,
    ];
    // Nodes i−1 … i+2 (clamped; a clamped node has zero weight).
    let idx = [i.saturating_sub(1), i, i + 1, (i + 2).min(n - 1)];
    let (mi, mj) = (slope_coefficients(c, i), slope_coefficients(c, i + 1));
    // f = b0 z_i + b1 h m_i + b2 z_(i+1) + b3 h m_(i+1), m as combinations of the nodes.
    let combine = |b: &[f64; 4], scale: f64| -> [f64; 4] {
        let mut w = [0.0; 4];
        w[1] += b[0];
        w[2] += b[2];
        for k in 0..3 {
            w[k] += b[1] * h * mi[k];
            w[k + 1] += b[3] * h * mj[k];
        }
        w.map(|v| v * scale)
    };
    Some(Weights {
        idx,
        w: combine(&b, 1.0),
        dw: combine(&db, 1.0 / h),
        ddw: combine(&ddb, 1.0 / (h * h)),
    })
}

impl HeightField {
    /// A height field from increasing `x` (≥ 2 values), increasing `y` (≥ 1 value; one:
    /// a profile along x) and the heights `z[j][i] = z(x_i, y_j)` (one row per y value).
    pub fn new(x: Vec<f64>, y: Vec<f64>, z: &[Vec<f64>]) -> Result<Self, HeightFieldError> {
        if x.len() < 2 {
            return Err(HeightFieldError::TooFew {
                axis: "x",
                len: x.len(),
            });
        }
        if y.is_empty() {
            return Err(HeightFieldError::TooFew { axis: "y", len: 0 });
        }
        for (axis, c) in [("x", &x), ("y", &y)] {
            for (k, v) in c.iter().enumerate() {
                let ok = v.is_finite() && (k == 0 || *v > c[k - 1]);
                if !ok {
                    return Err(HeightFieldError::NotIncreasing { axis, index: k });
                }
            }
        }
        if z.len() != y.len() {
            return Err(HeightFieldError::SizeMismatch {
                what: "rows",
                expected: y.len(),
                got: z.len(),
            });
        }
        let mut flat = Vec::with_capacity(x.len().saturating_mul(y.len()));
        for (j, row) in z.iter().enumerate() {
            if row.len() != x.len() {
                return Err(HeightFieldError::SizeMismatch {
                    what: "columns",
                    expected: x.len(),
                    got: row.len(),
                });
            }
            if let Some(i) = row.iter().position(|v| !v.is_finite()) {
                return Err(HeightFieldError::NotFinite { row: j, column: i });
            }
            flat.extend_from_slice(row);
        }
        Ok(Self { x, y, z: flat })
    }

    /// The rectangle `[x_0, x_n] × [y_0, y_m]` covered by the table (for a profile, y
    /// is unbounded).
    pub fn bounds(&self) -> ([f64; 2], [f64; 2]) {
        let (nx, ny) = (self.x.len(), self.y.len());
        let yb = if ny == 1 {
            [f64::NEG_INFINITY, f64::INFINITY]
        } else {
            [self.y[0], self.y[ny - 1]]
        };
        ([self.x[0], self.x[nx - 1]], yb)
    }

    /// Height, gradient and Hessian at (x, y); None outside the table.
    pub fn eval(&self, x: f64, y: f64) -> Option<Height> {
        let wx = weights(&self.x, x)?;
        let wy = weights(&self.y, y)?;
        let nx = self.x.len();
        let mut out = Height {
            z: 0.0,
            gradient: [0.0; 2],
            hessian: [[0.0; 2]; 2],
        };
        for l in 0..4 {
            for k in 0..4 {
                let z = self.z[wy.idx[l] * nx + wx.idx[k]];
                out.z += wx.w[k] * wy.w[l] * z;
                out.gradient[0] += wx.dw[k] * wy.w[l] * z;
                out.gradient[1] += wx.w[k] * wy.dw[l] * z;
                out.hessian[0][0] += wx.ddw[k] * wy.w[l] * z;
                out.hessian[0][1] += wx.dw[k] * wy.dw[l] * z;
                out.hessian[1][1] += wx.w[k] * wy.ddw[l] * z;
            }
        }
        out.hessian[1][0] = out.hessian[0][1];
        Some(out)
    }
}

impl HeightField {
    /// Whether (x, y) lies in the table's rectangle ([`HeightField::bounds`]).
    pub fn contains(&self, x: f64, y: f64) -> bool {
        let ([x0, x1], [y0, y1]) = self.bounds();
        x >= x0 && x <= x1 && y >= y0 && y <= y1
    }

    /// [`HeightField::eval`] inside the table; outside, the tangent plane at the nearest
    /// point c of the table, `z(c) + ∇z(c)·(p − c)`, with zero Hessian: a continuous
    /// continuation for Newton iterates that stray out (an element reports a converged
    /// state outside as an error). NaN coordinates give a NaN height.
    pub fn eval_extended(&self, x: f64, y: f64) -> Height {
        if let Some(h) = self.eval(x, y) {
            return h;
        }
        let ([x0, x1], [y0, y1]) = self.bounds();
        let (cx, cy) = (x.clamp(x0, x1), y.clamp(y0, y1));
        match self.eval(cx, cy) {
            Some(h) => Height {
                z: h.z + h.gradient[0] * (x - cx) + h.gradient[1] * (y - cy),
                gradient: h.gradient,
                hessian: [[0.0; 2]; 2],
            },
            None => Height {
                z: f64::NAN,
                gradient: [f64::NAN; 2],
                hessian: [[f64::NAN; 2]; 2],
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(x: &[f64], y: &[f64], f: impl Fn(f64, f64) -> f64) -> HeightField {
        let z: Vec<Vec<f64>> = y
            .iter()
            .map(|&yj| x.iter().map(|&xi| f(xi, yj)).collect())
            .collect();
        HeightField::new(x.to_vec(), y.to_vec(), &z).unwrap()
    }

    /// A plane (and any bilinear table) is reproduced exactly, with its gradient, on a
    /// non-uniform grid: the three-point slopes are exact for it (round-off, 1e-12).
    #[test]
    fn a_plane_is_reproduced_exactly() {
        let (x, y) = ([-2.0, -0.5, 0.0, 1.5, 4.0], [0.0, 0.7, 1.0, 3.0]);
        let f = |x: f64, y: f64| 0.3 + 0.25 * x - 0.4 * y + 0.05 * x * y;
        let hf = table(&x, &y, f);
        for k in 0..50 {
            let (px, py) = (
                -2.0 + 6.0 * (k as f64 * 0.37).fract(),
                3.0 * (k as f64 * 0.61).fract(),
            );
            let h = hf.eval(px, py).unwrap();
            assert!((h.z - f(px, py)).abs() < 1e-12);
            assert!((h.gradient[0] - (0.25 + 0.05 * py)).abs() < 1e-12);
            assert!((h.gradient[1] - (-0.4 + 0.05 * px)).abs() < 1e-12);
            assert!((h.hessian[0][1] - 0.05).abs() < 1e-12);
            assert!(h.hessian[0][0].abs() < 1e-12 && h.hessian[1][1].abs() < 1e-12);
        }
    }

    /// Gradient and Hessian are the derivatives of the height (central differences,
    /// ε = 1e-6: error ~1e-8 relative), and the surface is C¹: value and slope agree on
    /// both sides of a cell boundary (1e-9).
    #[test]
    fn derivatives_are_consistent_and_the_surface_is_c1() {
        let x: Vec<f64> = (0..9)
            .map(|i| 0.5 * i as f64 + 0.05 * (i * i) as f64)
            .collect();
        let y: Vec<f64> = (0..7).map(|j| 0.4 * j as f64).collect();
        let hf = table(&x, &y, |x, y| {
            (1.3 * x).sin() * (0.7 * y).cos() + 0.1 * x * x
        });
        let e = 1e-6;
        for &(px, py) in &[(0.77, 0.9), (2.3, 1.7), (4.1, 0.3), (1.6, 2.2)] {
            let h = hf.eval(px, py).unwrap();
            let hx = (hf.eval(px + e, py).unwrap(), hf.eval(px - e, py).unwrap());
            let hy = (hf.eval(px, py + e).unwrap(), hf.eval(px, py - e).unwrap());
            let d = |a: f64, b: f64| (a - b) / (2.0 * e);
            assert!((d(hx.0.z, hx.1.z) - h.gradient[0]).abs() < 1e-7);
            assert!((d(hy.0.z, hy.1.z) - h.gradient[1]).abs() < 1e-7);
            assert!((d(hx.0.gradient[0], hx.1.gradient[0]) - h.hessian[0][0]).abs() < 1e-6);
            assert!((d(hy.0.gradient[0], hy.1.gradient[0]) - h.hessian[0][1]).abs() < 1e-6);
            assert!((d(hy.0.gradient[1], hy.1.gradient[1]) - h.hessian[1][1]).abs() < 1e-6);
        }
        for &xb in &x[1..x.len() - 1] {
            let (l, r) = (
                hf.eval(xb - 1e-12, 1.1).unwrap(),
                hf.eval(xb + 1e-12, 1.1).unwrap(),
            );
            assert!((l.z - r.z).abs() < 1e-9);
            assert!(
                (l.gradient[0] - r.gradient[0]).abs() < 1e-9,
                "slope jumps at {xb}"
            );
        }
    }

    /// Third-order accuracy on a smooth profile z = sin x away from the edge cells: the
    /// error drops by about 8 when the uniform grid is refined (orders within 2.7–3.3);
    /// second order in the edge cells (one-sided slopes: orders within 1.8–2.4).
    #[test]
    fn a_smooth_profile_converges_at_third_order() {
        let (mut inner, mut all) = (Vec::new(), Vec::new());
        for n in [11usize, 21, 41, 81] {
            let x: Vec<f64> = (0..n).map(|i| 3.0 * i as f64 / (n - 1) as f64).collect();
            let hf = table(&x, &[0.0], |x, _| x.sin());
            let err = |t: f64| (hf.eval(t, 5.0).unwrap().z - t.sin()).abs();
            let ts = (0..301).map(|k| 3.0 * k as f64 / 300.0);
            inner.push(
                ts.clone()
                    .filter(|t| (0.5..=2.5).contains(t))
                    .map(err)
                    .fold(0.0, f64::max),
            );
            all.push(ts.map(err).fold(0.0, f64::max));
        }
        let order =
            |e: &[f64]| -> Vec<f64> { e.windows(2).map(|w| (w[0] / w[1]).log2()).collect() };
        let (oi, oa) = (order(&inner), order(&all));
        assert!(
            oi.iter().all(|&p| (2.7..3.3).contains(&p)),
            "{inner:?} {oi:?}"
        );
        assert!(
            oa.iter().all(|&p| (1.8..2.4).contains(&p)),
            "{all:?} {oa:?}"
        );
    }

    #[test]
    fn bad_tables_and_points_outside_are_refused() {
        let z = vec![vec![0.0, 1.0, 2.0]];
        assert_eq!(
            HeightField::new(vec![0.0, 2.0, 1.0], vec![0.0], &z),
            Err(HeightFieldError::NotIncreasing {
                axis: "x",
                index: 2
            })
        );
        assert_eq!(
            HeightField::new(vec![0.0, 1.0, 2.0], vec![0.0, 1.0], &z),
            Err(HeightFieldError::SizeMismatch {
                what: "rows",
                expected: 2,
                got: 1
            })
        );
        assert!(matches!(
            HeightField::new(vec![0.0, 1.0], vec![0.0], &z),
            Err(HeightFieldError::SizeMismatch {
                what: "columns",
                ..
            })
        ));
        assert!(matches!(
            HeightField::new(vec![0.0], vec![0.0], &[vec![0.0]]),
            Err(HeightFieldError::TooFew { axis: "x", .. })
        ));
        let hf = HeightField::new(vec![0.0, 1.0, 2.0], vec![0.0], &z).unwrap();
        assert!(hf.eval(2.5, 0.0).is_none() && hf.eval(f64::NAN, 0.0).is_none());
        assert!(hf.eval(1.5, 1e9).is_some(), "a profile is constant across");
    }
}
