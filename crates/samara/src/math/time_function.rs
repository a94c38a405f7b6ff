//! Scalar time functions f(t) that scale applied loads, drive joint coordinates and feed
//! input signals. Drives also need f'(t) and f''(t) (the velocity and acceleration of a
//! rheonomic constraint); for piecewise definitions these are the one-sided derivatives
//! from the right (a ramp's corners and a step's jump give no impulse).

/// A scalar function of time.
#[derive(Clone, Debug, PartialEq)]
pub enum TimeFunction {
    /// f(t) = value.
    Constant(f64),
    /// Linear from `from` at `start` to `to` at `end`, constant outside.
    Ramp {
        start: f64,
        end: f64,
        from: f64,
        to: f64,
    },
    /// `before` for t < time, `after` for t ≥ time.
    Step { time: f64, before: f64, after: f64 },
    /// offset + amplitude · sin(2π frequency (t − start) + phase) for t ≥ start;
    /// offset + amplitude · sin(phase) before `start`.
    Sine {
        amplitude: f64,
        frequency: f64,
        phase: f64,
        offset: f64,
        start: f64,
    },
    /// Piecewise-linear through (times[i], values[i]), constant beyond the ends.
    /// `times` is strictly increasing (checked when the model is validated).
    Table { times: Vec<f64>, values: Vec<f64> },
    /// f(t) = Σ c_k (t − start)^k for t ≥ start, f(start) before (smooth drives).
    Polynomial { coefficients: Vec<f64>, start: f64 },
}

impl Default for TimeFunction {
    fn default() -> Self {
        TimeFunction::Constant(1.0)
    }
}

impl TimeFunction {
    /// Times where f or one of its first two derivatives jumps (ramp ends, steps, table
    /// knots, the start of a sine or polynomial): adaptive steps land on them.
    pub fn breakpoints(&self) -> Vec<f64> {
        match self {
            TimeFunction::Constant(_) => Vec::new(),
            TimeFunction::Ramp { start, end, .. } => vec![*start, *end],
            TimeFunction::Step { time, .. } => vec![*time],
            TimeFunction::Sine { start, .. } | TimeFunction::Polynomial { start, .. } => {
                vec![*start]
            }
            TimeFunction::Table { times, .. } => times.clone(),
        }
    }

    /// f(t).
    pub fn eval(&self, t: f64) -> f64 {
        match self {
            TimeFunction::Constant(v) => *v,
            TimeFunction::Ramp {
                start,
                end,
                from,
                to,
            } => {
                if t <= *start {
                    *from
                } else if t >= *end {
                    *to
                } else {
                    from + (to - from) * (t - start) / (end - start)
                }
            }
            TimeFunction::Step {
                time,
                before,
                after,
            } => {
                if t < *time {
                    *before
                } else {
                    *after
                }
            }
            TimeFunction::Sine {
                amplitude,
                frequency,
                phase,
                offset,
                start,
            } => {
                let tau = (t - start).max(0.0);
                offset + amplitude * (2.0 * std::f64::consts::PI * frequency * tau + phase).sin()
            }
            TimeFunction::Table { times, values } => {
                let n = times.len();
                if t <= times[0] {
                    return values[0];
                }
                if t >= times[n - 1] {
                    return values[n - 1];
                }
                // Binary search for the segment [times[i], times[i+1]).
                let i = times.partition_point(|&x| x <= t) - 1;
                let s = (t - times[i]) / (times[i + 1] - times[i]);
                values[i] + s * (values[i + 1] - values[i])
            }
            TimeFunction::Polynomial { .. } => self.derivatives(t)[0],
        }
    }

    /// `[f(t), f'(t), f''(t)]`.
    pub fn derivatives(&self, t: f64) -> [f64; 3] {
        use std::f64::consts::PI;
        match self {
            TimeFunction::Constant(_) | TimeFunction::Step { .. } => [self.eval(t), 0.0, 0.0],
            TimeFunction::Ramp {
                start,
                end,
                from,
                to,
            } => {
                let slope = if t >= *start && t < *end {
                    (to - from) / (end - start)
                } else {
                    0.0
                };
                [self.eval(t), slope, 0.0]
            }
            TimeFunction::Sine {
                amplitude,
                frequency,
                phase,
                start,
                ..
            } => {
                if t < *start {
                    return [self.eval(t), 0.0, 0.0];
                }
                let w = 2.0 * PI * frequency;
                let arg = w * (t - start) + phase;
                [
                    self.eval(t),
                    amplitude * w * arg.cos(),
                    -amplitude * w * w * arg.sin(),
                ]
            }
            TimeFunction::Table { times, values } => {
                let n = times.len();
                if t < times[0] || t >= times[n - 1] {
                    return [self.eval(t), 0.0, 0.0];
                }
                let i = times.partition_point(|&x| x <= t) - 1;
                let slope = (values[i + 1] - values[i]) / (times[i + 1] - times[i]);
                [self.eval(t), slope, 0.0]
            }
            TimeFunction::Polynomial {
                coefficients,
                start,
            } => {
                let tau = (t - start).max(0.0);
                // Horner for f, f', f''.
                let (mut f, mut d1, mut d2) = (0.0, 0.0, 0.0);
                for &c in coefficients.iter().rev() {
                    d2 = d2 * tau + 2.0 * d1;
                    d1 = d1 * tau + f;
                    f = f * tau + c;
                }
                if t < *start {
                    [f, 0.0, 0.0]
                } else {
                    [f, d1, d2]
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_kind_evaluates_as_documented() {
        let r = TimeFunction::Ramp {
            start: 1.0,
            end: 3.0,
            from: 2.0,
            to: 6.0,
        };
        assert_eq!(r.eval(0.0), 2.0);
        assert_eq!(r.eval(2.0), 4.0);
        assert_eq!(r.eval(5.0), 6.0);
        let s = TimeFunction::Step {
            time: 1.0,
            before: -1.0,
            after: 1.0,
        };
        assert_eq!(s.eval(0.999), -1.0);
        assert_eq!(s.eval(1.0), 1.0);
        let w = TimeFunction::Sine {
            amplitude: 2.0,
            frequency: 0.25,
            phase: 0.0,
            offset: 1.0,
            start: 0.0,
        };
        assert!((w.eval(1.0) - 3.0).abs() < 1e-15);
        let t = TimeFunction::Table {
            times: vec![0.0, 1.0, 3.0],
            values: vec![0.0, 10.0, 0.0],
        };
        assert_eq!(t.eval(-1.0), 0.0);
        assert_eq!(t.eval(0.5), 5.0);
        assert_eq!(t.eval(2.0), 5.0);
        assert_eq!(t.eval(1.0), 10.0);
        assert_eq!(t.eval(9.0), 0.0);
        let p = TimeFunction::Polynomial {
            coefficients: vec![1.0, 2.0, 3.0],
            start: 1.0,
        };
        assert_eq!(p.derivatives(3.0), [1.0 + 4.0 + 12.0, 2.0 + 12.0, 6.0]);
        assert_eq!(p.derivatives(0.0), [1.0, 0.0, 0.0]);
    }

    /// f' and f'' against central differences away from corners: a wrong derivative would
    /// break the velocity and acceleration of every drive.
    #[test]
    fn derivatives_match_finite_differences() {
        let fs = [
            TimeFunction::Ramp {
                start: 0.0,
                end: 2.0,
                from: 1.0,
                to: 5.0,
            },
            TimeFunction::Sine {
                amplitude: 0.7,
                frequency: 1.3,
                phase: 0.4,
                offset: 0.2,
                start: 0.1,
            },
            TimeFunction::Table {
                times: vec![0.0, 1.0, 3.0],
                values: vec![0.0, 10.0, 0.0],
            },
            TimeFunction::Polynomial {
                coefficients: vec![0.5, -1.0, 0.25, 0.125],
                start: 0.0,
            },
        ];
        let h = 1e-4;
        for f in &fs {
            for t in [0.37, 0.81, 1.55] {
                let [_, d1, d2] = f.derivatives(t);
                let fd1 = (f.eval(t + h) - f.eval(t - h)) / (2.0 * h);
                let fd2 = (f.eval(t + h) - 2.0 * f.eval(t) + f.eval(t - h)) / (h * h);
                assert!((d1 - fd1).abs() < 1e-6, "{f:?} at {t}: {d1} vs {fd1}");
                assert!((d2 - fd2).abs() < 1e-4, "{f:?} at {t}: {d2} vs {fd2}");
            }
        }
    }
}
