//! Output instants of a dynamic analysis given as a time interval (`output_interval` Δ):
//! the records are taken at t₀ + kΔ, and the steps — fixed or adaptive, of every
//! integrator — are shortened to land on those instants, so that no record is
//! interpolated and no output time is stepped over.

/// The output instants t₀ + kΔ, k = 1, 2, …, not yet reached.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct OutputGrid {
    t0: f64,
    interval: f64,
    /// Index of the last instant reached.
    k: u64,
}

impl OutputGrid {
    /// The grid of `interval` from `t0` (`None` without an interval).
    pub(crate) fn new(t0: f64, interval: Option<f64>) -> Option<Self> {
        interval.map(|interval| Self { t0, interval, k: 0 })
    }

    /// The next output instant.
    pub(crate) fn next(&self) -> f64 {
        self.t0 + (self.k + 1) as f64 * self.interval
    }

    /// The end of a step from `t` aimed at `target` (step size about `h`), cut back to the
    /// next output instant when that lies before it (within 1e-9 h: an instant just past
    /// the target is taken instead of leaving a sliver).
    pub(crate) fn land(&self, target: f64, h: f64) -> f64 {
        let o = self.next();
        if o < target + 1e-9 * h { o } else { target }
    }

    /// Whether a step that ended at `t` (size `h`) reached the next instant (within
    /// 1e-9 h); the grid then moves past every instant reached.
    pub(crate) fn reached(&mut self, t: f64, h: f64) -> bool {
        let mut hit = false;
        while self.next() <= t + 1e-9 * h {
            self.k += 1;
            hit = true;
        }
        hit
    }
}

#[cfg(test)]
mod tests {
    use super::OutputGrid;

    #[test]
    fn steps_land_on_the_instants_and_each_is_reached_once() {
        let mut g = OutputGrid::new(0.5, Some(0.1)).unwrap();
        // A step of 0.03 from 0.5 is not cut; one of 0.25 is cut to 0.6.
        assert_eq!(g.land(0.53, 0.03), 0.53);
        assert!((g.land(0.75, 0.25) - 0.6).abs() < 1e-15);
        assert!(!g.reached(0.53, 0.03));
        assert!(g.reached(0.6, 0.07));
        assert!(!g.reached(0.6, 0.07));
        assert!((g.next() - 0.7).abs() < 1e-15);
        // An instant within 1e-9 h past the target is taken as the target.
        assert_eq!(g.land(0.7 - 1e-12, 0.1), g.next());
    }

    #[test]
    fn no_interval_no_grid() {
        assert!(OutputGrid::new(0.0, None).is_none());
    }
}
