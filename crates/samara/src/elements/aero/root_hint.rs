//! The warm start of a station's BEM root ([`super::bem::BemRotor::solve_near`]): the
//! last root φ₁ (at time t₁), and at a later time t the line through it and the last
//! root of the time before, φ₀ at t₀:
//!
//! `φ(t) ≈ φ₁ + (t − t₁)/(t₁ − t₀) (φ₁ − φ₀)`,
//!
//! so that the first evaluation of a time step starts O(h²) from its root instead of
//! O(h). Later evaluations at the same time (Newton's iterations) start from the last
//! root. The solve converges from any start to its tolerance, so the start moves the
//! root only at that level.

use crate::elements::slot::Slot;
use std::f64::consts::FRAC_PI_2;

/// Ratio (t − t₁)/(t₁ − t₀) above which the last root alone is the start (a step much
/// longer than the one before).
const MAX_RATIO: f64 = 2.0;

/// The last two roots at distinct times, kept between evaluations (shared between
/// threads as [`Slot`]s; each station is evaluated by one thread at a time).
#[derive(Clone, Debug)]
pub(crate) struct RootHint {
    t1: Slot,
    phi1: Slot,
    t0: Slot,
    phi0: Slot,
}

impl RootHint {
    pub(crate) fn new() -> Self {
        Self {
            t1: Slot::new(),
            phi1: Slot::new(),
            t0: Slot::new(),
            phi0: Slot::new(),
        }
    }

    /// The start of the solve at time t: the last root, carried along the line through
    /// the last two times' roots when t is later than the last root's and the line stays
    /// in the windmill bracket (0, π/2).
    pub(crate) fn start(&self, t: f64) -> Option<f64> {
        let phi1 = self.phi1.get()?;
        let (Some(t1), Some(t0), Some(phi0)) = (self.t1.get(), self.t0.get(), self.phi0.get())
        else {
            return Some(phi1);
        };
        let ratio = (t - t1) / (t1 - t0);
        if t > t1 && t1 > t0 && ratio <= MAX_RATIO {
            let phi = phi1 + ratio * (phi1 - phi0);
            if phi > 0.0 && phi < FRAC_PI_2 {
                return Some(phi);
            }
        }
        Some(phi1)
    }

    /// Records the root φ found at time t: a later time shifts the last root to the
    /// time before; an earlier one (a rejected step, a restart) forgets it.
    pub(crate) fn record(&self, t: f64, phi: f64) {
        match self.t1.get() {
            Some(t1) if t == t1 => {}
            Some(t1) if t > t1 => {
                self.t0.set(t1);
                self.phi0.set(self.phi1.get().unwrap_or(f64::NAN));
            }
            _ => {
                self.t0.clear();
                self.phi0.clear();
            }
        }
        self.t1.set(t);
        self.phi1.set(phi);
    }

    /// Forgets the roots (as an analysis starts).
    pub(crate) fn clear(&self) {
        for s in [&self.t1, &self.phi1, &self.t0, &self.phi0] {
            s.clear();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A root linear in time is started exactly at the next time; the same time starts
    /// from the last root; an earlier time forgets the line.
    #[test]
    fn the_start_follows_the_line_of_the_last_two_times() {
        let h = RootHint::new();
        assert_eq!(h.start(0.0), None);
        let root = |t: f64| 0.5 + 0.25 * t;
        h.record(0.0, root(0.0));
        assert_eq!(h.start(0.01), Some(root(0.0)));
        h.record(0.01, 0.3);
        h.record(0.01, root(0.01));
        assert!((h.start(0.02).unwrap() - root(0.02)).abs() < 1e-15);
        assert_eq!(h.start(0.01), Some(root(0.01)));
        // A step three times longer than the last: the last root alone.
        assert_eq!(h.start(0.04), Some(root(0.01)));
        h.record(0.005, root(0.005));
        assert_eq!(h.start(0.01), Some(root(0.005)));
        h.clear();
        assert_eq!(h.start(0.01), None);
    }
}
