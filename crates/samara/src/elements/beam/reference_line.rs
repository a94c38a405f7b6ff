//! The beam's reference line in its initial configuration: key points joined by a smooth
//! curve, section frames along it, and a twist distribution.
//!
//! - **Curve**: natural cubic spline through the key points in each coordinate, with the
//!   cumulative chord length as parameter (C² and independent of the beam's direction;
//!   two key points give a straight line).
//! - **Arc length** s by 16-point Gauss quadrature on each spline piece; stations are given
//!   as η = s/L ∈ [0, 1] and inverted to the spline parameter by Newton's method.
//! - **Frames**: x = unit tangent; at the root, y is the reference vector `y_axis` made
//!   normal to the tangent (default: the global axis after — cyclically — the one most
//!   aligned with the root tangent: beam along x → y, along z → x as in BeamDyn); the
//!   frame is then carried along the curve by parallel transport (each small step rotates
//!   it by the smallest rotation that turns one tangent into the next), and finally turned
//!   about the tangent by the twist θ(η) (natural cubic spline through the given values).

use nalgebra::{Matrix3, Rotation3, Unit, Vector3};

/// Natural cubic spline y(t) through (tᵢ, yᵢ), t strictly increasing.
#[derive(Clone, Debug)]
struct Spline {
    t: Vec<f64>,
    y: Vec<f64>,
    /// Second derivatives at the knots.
    m: Vec<f64>,
}

impl Spline {
    fn new(t: &[f64], y: &[f64]) -> Self {
        let n = t.len();
        let mut m = vec![0.0; n];
        if n > 2 {
            // Tridiagonal system for the interior second derivatives (Thomas algorithm).
            let k = n - 2;
            let mut a = vec![0.0; k];
            let mut b = vec![0.0; k];
            let mut c = vec![0.0; k];
            let mut d = vec![0.0; k];
            for i in 1..n - 1 {
                let (h0, h1) = (t[i] - t[i - 1], t[i + 1] - t[i]);
                a[i - 1] = h0;
                b[i - 1] = 2.0 * (h0 + h1);
                c[i - 1] = h1;
                d[i - 1] = 6.0 * ((y[i + 1] - y[i]) / h1 - (y[i] - y[i - 1]) / h0);
            }
            for i in 1..k {
                let w = a[i] / b[i - 1];
                b[i] -= w * c[i - 1];
                d[i] -= w * d[i - 1];
            }
            m[k] = d[k - 1] / b[k - 1];
            for i in (0..k - 1).rev() {
                m[i + 1] = (d[i] - c[i] * m[i + 2]) / b[i];
            }
        }
        Self {
            t: t.to_vec(),
            y: y.to_vec(),
            m,
        }
    }

    fn piece(&self, x: f64) -> usize {
        let n = self.t.len();
        if n == 1 {
            return 0;
        }
        self.t.partition_point(|&v| v <= x).clamp(1, n - 1) - 1
    }

    /// Value and first derivative.
    fn eval(&self, x: f64) -> (f64, f64) {
        if self.t.len() == 1 {
            return (self.y[0], 0.0);
        }
        let i = self.piece(x);
        let (t0, t1) = (self.t[i], self.t[i + 1]);
        let h = t1 - t0;
        let (a, b) = ((t1 - x) / h, (x - t0) / h);
        let (m0, m1) = (self.m[i], self.m[i + 1]);
        let v = a * self.y[i]
            + b * self.y[i + 1]
            + ((a * a * a - a) * m0 + (b * b * b - b) * m1) * h * h / 6.0;
        let d = (self.y[i + 1] - self.y[i]) / h - (3.0 * a * a - 1.0) / 6.0 * h * m0
            + (3.0 * b * b - 1.0) / 6.0 * h * m1;
        (v, d)
    }
}

/// A reference line built from key points and a twist distribution.
#[derive(Clone, Debug)]
pub struct ReferenceLine {
    coords: [Spline; 3],
    twist: Spline,
    /// Cumulative arc length at each knot.
    arc: Vec<f64>,
    length: f64,
    root_frame: Matrix3<f64>,
}

/// Why a reference line cannot be built.
#[derive(Clone, Debug, PartialEq)]
pub enum LineError {
    TooFewPoints(usize),
    CoincidentPoints(usize),
    ParallelReference,
    BadTwistStations,
}

impl std::fmt::Display for LineError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LineError::TooFewPoints(n) => {
                write!(f, "a reference line needs at least 2 key points (got {n})")
            }
            LineError::CoincidentPoints(i) => write!(f, "key points {} and {} coincide", i, i + 1),
            LineError::ParallelReference => write!(
                f,
                "the reference `y_axis` is parallel to the tangent at the root"
            ),
            LineError::BadTwistStations => write!(
                f,
                "twist stations must be strictly increasing within [0, 1]"
            ),
        }
    }
}

const GAUSS16: usize = 16;

impl ReferenceLine {
    /// `twist`: (η, angle [rad]) pairs, η strictly increasing in [0, 1]; empty = no twist.
    pub fn new(
        points: &[Vector3<f64>],
        twist: &[[f64; 2]],
        y_axis: Option<Vector3<f64>>,
    ) -> Result<Self, LineError> {
        let n = points.len();
        if n < 2 {
            return Err(LineError::TooFewPoints(n));
        }
        let mut chord = vec![0.0; n];
        for i in 1..n {
            let d = (points[i] - points[i - 1]).norm();
            if !(d > 0.0) {
                return Err(LineError::CoincidentPoints(i - 1));
            }
            chord[i] = chord[i - 1] + d;
        }
        let coords = [0, 1, 2].map(|k| {
            let y: Vec<f64> = points.iter().map(|p| p[k]).collect();
            Spline::new(&chord, &y)
        });
        let (tx, tw): (Vec<f64>, Vec<f64>) = if twist.is_empty() {
            (vec![0.0], vec![0.0])
        } else {
            (
                twist.iter().map(|p| p[0]).collect(),
                twist.iter().map(|p| p[1]).collect(),
            )
        };
        if tx.windows(2).any(|w| !(w[1] > w[0])) || tx.iter().any(|x| !(0.0..=1.0).contains(x)) {
            return Err(LineError::BadTwistStations);
        }
        let mut line = Self {
            coords,
            twist: Spline::new(&tx, &tw),
            arc: vec![0.0; n],
            length: 0.0,
            root_frame: Matrix3::identity(),
        };
        let (gx, gw) = super::gll::gauss_legendre(GAUSS16);
        for i in 1..n {
            let (a, b) = (chord[i - 1], chord[i]);
            let seg: f64 = gx
                .iter()
                .zip(&gw)
                .map(|(x, w)| w * line.tangent_raw(a + (x + 1.0) * 0.5 * (b - a)).norm())
                .sum::<f64>()
                * 0.5
                * (b - a);
            line.arc[i] = line.arc[i - 1] + seg;
        }
        line.length = line.arc[n - 1];
        let t0 = line.tangent_raw(0.0).normalize();
        let yref = y_axis.unwrap_or_else(|| {
            let k = t0.iamax();
            let mut e = Vector3::zeros();
            e[(k + 1) % 3] = 1.0;
            e
        });
        let y0 = yref - t0 * t0.dot(&yref);
        if y0.norm() < 1e-8 * yref.norm().max(1e-300) {
            return Err(LineError::ParallelReference);
        }
        let y0 = y0.normalize();
        line.root_frame = Matrix3::from_columns(&[t0, y0, t0.cross(&y0)]);
        Ok(line)
    }

    pub fn length(&self) -> f64 {
        self.length
    }

    fn tangent_raw(&self, t: f64) -> Vector3<f64> {
        Vector3::new(
            self.coords[0].eval(t).1,
            self.coords[1].eval(t).1,
            self.coords[2].eval(t).1,
        )
    }

    fn position_raw(&self, t: f64) -> Vector3<f64> {
        Vector3::new(
            self.coords[0].eval(t).0,
            self.coords[1].eval(t).0,
            self.coords[2].eval(t).0,
        )
    }

    /// Spline parameter of arc length s.
    fn parameter(&self, s: f64) -> f64 {
        let chord = &self.coords[0].t;
        let i = self
            .arc
            .partition_point(|&a| a <= s)
            .clamp(1, self.arc.len() - 1)
            - 1;
        let (s0, s1) = (self.arc[i], self.arc[i + 1]);
        let (t0, t1) = (chord[i], chord[i + 1]);
        let mut t = t0 + (s - s0) / (s1 - s0) * (t1 - t0);
        let (gx, gw) = super::gll::gauss_legendre(GAUSS16);
        for _ in 0..50 {
            let len: f64 = gx
                .iter()
                .zip(&gw)
                .map(|(x, w)| w * self.tangent_raw(t0 + (x + 1.0) * 0.5 * (t - t0)).norm())
                .sum::<f64>()
                * 0.5
                * (t - t0);
            let f = s0 + len - s;
            let dt = f / self.tangent_raw(t).norm();
            t -= dt;
            if dt.abs() < 1e-15 * (1.0 + t.abs()) {
                break;
            }
        }
        t
    }

    /// Positions and section frames (columns: axial x, y, z; global components) at the
    /// stations η (any order).
    pub fn frames(&self, etas: &[f64]) -> Vec<(Vector3<f64>, Matrix3<f64>)> {
        let mut order: Vec<usize> = (0..etas.len()).collect();
        order.sort_by(|&a, &b| etas[a].total_cmp(&etas[b]));
        let mut out = vec![(Vector3::zeros(), Matrix3::identity()); etas.len()];
        let mut frame = self.root_frame;
        let mut t_prev = 0.0;
        for &k in &order {
            let eta = etas[k].clamp(0.0, 1.0);
            let t = self.parameter(eta * self.length);
            // Parallel transport from t_prev to t in small steps.
            let steps = 64;
            for j in 1..=steps {
                let ta = t_prev + (t - t_prev) * (j - 1) as f64 / steps as f64;
                let tb = t_prev + (t - t_prev) * j as f64 / steps as f64;
                let (a, b) = (
                    self.tangent_raw(ta).normalize(),
                    self.tangent_raw(tb).normalize(),
                );
                let axis = a.cross(&b);
                let sin = axis.norm();
                if sin > 1e-15 {
                    let angle = sin.atan2(a.dot(&b));
                    let rot = Rotation3::from_axis_angle(&Unit::new_normalize(axis), angle);
                    frame = rot.matrix() * frame;
                }
            }
            t_prev = t;
            // Re-orthonormalize around the exact tangent.
            let x = self.tangent_raw(t).normalize();
            let y = (frame.column(1) - x * x.dot(&frame.column(1))).normalize();
            let base = Matrix3::from_columns(&[x, y, x.cross(&y)]);
            let twist = self.twist.eval(eta).0;
            let turn = Rotation3::from_axis_angle(&Vector3::x_axis(), twist);
            out[k] = (self.position_raw(t), base * turn.matrix());
            frame = base;
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn straight_line_with_linear_twist() {
        let line = ReferenceLine::new(
            &[Vector3::zeros(), Vector3::new(0.0, 0.0, 10.0)],
            &[[0.0, 0.0], [1.0, 0.6]],
            None,
        )
        .unwrap();
        assert!((line.length() - 10.0).abs() < 1e-13);
        let f = line.frames(&[0.0, 0.5, 1.0]);
        assert!((f[1].0 - Vector3::new(0.0, 0.0, 5.0)).norm() < 1e-13);
        // Along z: y defaults to global x, turned by the twist about the axis.
        let y = f[1].1.column(1);
        assert!((y - Vector3::new(0.3f64.cos(), 0.3f64.sin(), 0.0)).norm() < 1e-13);
        assert!((f[2].1.determinant() - 1.0).abs() < 1e-13);
    }

    /// Key points on a circle: the spline is close to the arc (length within 1e-4 for
    /// 9 points on 45°), and the transported frame stays in the plane of the curve.
    #[test]
    fn planar_arc() {
        let r = 100.0;
        let pts: Vec<Vector3<f64>> = (0..9)
            .map(|i| {
                let a = std::f64::consts::FRAC_PI_4 * i as f64 / 8.0;
                Vector3::new(r * (1.0 - a.cos()), 0.0, r * a.sin())
            })
            .collect();
        let line = ReferenceLine::new(&pts, &[], None).unwrap();
        let exact = r * std::f64::consts::FRAC_PI_4;
        assert!(((line.length() - exact) / exact).abs() < 1e-4);
        for (_, f) in line.frames(&[0.0, 0.3, 0.7, 1.0]) {
            // z axis of the section stays normal to the x–z plane (y-direction).
            assert!(f.column(2).y.abs() > 1.0 - 1e-9);
        }
    }
}
