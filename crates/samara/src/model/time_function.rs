//! Scalar time functions f(t) that scale applied loads (and, later, drive joints).

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
}

impl Default for TimeFunction {
    fn default() -> Self {
        TimeFunction::Constant(1.0)
    }
}

impl TimeFunction {
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
    }
}
