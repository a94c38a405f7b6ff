//! Error feedback for the `Trend` predictor of the dynamic integrator.
//!
//! The `Trend` prediction of an unknown's increment misses by e_n = hΔq_n − p_n. Where
//! the miss comes from a motion the prediction does not follow, consecutive misses are
//! correlated: e_{n+1} ≈ c e_n. The algorithmic accelerations of modes the step does not
//! resolve ring near the Nyquist rate (c → −ρ), and a mode of frequency ω that `Trend`
//! misses gives c ≈ cos ωh. Measured on the flexible rotor of issue #15 (10 s, h =
//! 0.01 s): the largest misses are the blade tips' torsion (spectral peak at 49 Hz,
//! lag-1 correlation −0.90) and the blade-root nodes held by the fixed joints (50 Hz,
//! −1.00); the Øye states' misses peak at 3.8 Hz (+0.4 … +0.6). The correction adds ĉ e_n
//! to the next prediction, ĉ the lag-1 regression coefficient of the unknown's own misses,
//!
//!   ĉ = Σ_k λ^{n−k} e_k e_{k−1} / Σ_k λ^{n−k} e_{k−1}²,  clamped to [−1, 0],
//!
//! with the forgetting factor λ = [`FORGETTING`]: only ringing is fed back. An unknown
//! whose misses are uncorrelated or of one sign gets no correction (the plain `Trend`
//! prediction). Clamped to [−1, 1] the rotor's misses fell further (geometric mean of the
//! per-step largest weighted miss 1533 → 1273 against 1405 here; 2.51 against 2.54
//! iterations per step), but the pendulum of tests/options.rs then took 447 modified-Newton
//! factorizations against full Newton's 823 at tolerance 1e-12 (the test asks for a third)
//! and the landing-gear drop diverged on its last, 1.5e-12-s step. The converged step does
//! not depend on the prediction beyond the Newton tolerance; only its first iterate moves.

/// Weight of the previous sums per step: an effective memory of 1/(1 − λ) = 10 steps.
/// Measured on the flexible rotor with ĉ in [−1, 1] (10 s, geometric mean of the per-step
/// largest tolerance-weighted miss): 1533 without feedback; λ = 0.7, 0.8, 0.9, 0.97, 0.99
/// give 1302, 1285, 1273, 1295, 1378.
pub const FORGETTING: f64 = 0.9;

/// Per-unknown regression of the `Trend` predictor's misses on the previous miss.
pub struct TrendFeedback {
    /// e_n, the last step's miss (0 when there is none).
    last: Vec<f64>,
    /// Σ λ^{n−k} e_k e_{k−1}.
    cross: Vec<f64>,
    /// Σ λ^{n−k} e_{k−1}².
    square: Vec<f64>,
    /// ĉ e_n, formed as the misses are recorded.
    next: Vec<f64>,
    /// Whether `last` belongs to the step just before the next one.
    valid: bool,
}

impl TrendFeedback {
    pub fn new(n: usize) -> Self {
        Self {
            last: vec![0.0; n],
            cross: vec![0.0; n],
            square: vec![0.0; n],
            next: vec![0.0; n],
            valid: false,
        }
    }

    /// Forgets the misses (after a restart of the scheme, or a step of another size).
    pub fn reset(&mut self) {
        self.last.fill(0.0);
        self.cross.fill(0.0);
        self.square.fill(0.0);
        self.next.fill(0.0);
        self.valid = false;
    }

    /// ĉ e_n, the correction to the next `Trend` prediction of unknown k.
    #[inline]
    pub fn correction(&self, k: usize) -> f64 {
        if self.valid { self.next[k] } else { 0.0 }
    }

    /// Records the misses of the step just accepted: `converged` − `predicted` (the plain
    /// `Trend` predictions, without the correction).
    pub fn record(&mut self, converged: &[f64], predicted: &[f64]) {
        for (((((l, c), s), x), q), p) in self
            .last
            .iter_mut()
            .zip(self.cross.iter_mut())
            .zip(self.square.iter_mut())
            .zip(self.next.iter_mut())
            .zip(converged)
            .zip(predicted)
        {
            let e = q - p;
            *c = FORGETTING * *c + e * *l;
            *s = FORGETTING * *s + *l * *l;
            *l = e;
            *x = if *s > 0.0 {
                (*c / *s).clamp(-1.0, 0.0) * e
            } else {
                0.0
            };
        }
        self.valid = true;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Ringing misses, e_{k+1} = c e_k with −1 < c < 0: the regression finds c and the
    /// correction is the next miss; misses of one sign (c > 0) get no correction.
    #[test]
    fn ringing_misses_are_predicted() {
        let mut f = TrendFeedback::new(3);
        let (c0, c1, c2) = (-0.93, -0.98, 0.9);
        let (mut e0, mut e1, mut e2) = (1e-5, 2e-6, 3e-6);
        for _ in 0..5 {
            f.record(&[e0, e1, e2], &[0.0, 0.0, 0.0]);
            e0 *= c0;
            e1 *= c1;
            e2 *= c2;
        }
        assert!((f.correction(0) - e0).abs() <= 1e-12 * e0.abs());
        assert!((f.correction(1) - e1).abs() <= 1e-12 * e1.abs());
        assert_eq!(f.correction(2), 0.0);
    }

    /// No correction before any miss, after a single one or after a reset; a growing
    /// alternation is clamped to c = −1.
    #[test]
    fn clamped_and_reset() {
        let mut f = TrendFeedback::new(1);
        assert_eq!(f.correction(0), 0.0);
        let (mut e, mut last) = (1e-6, 0.0);
        for _ in 0..4 {
            f.record(&[e], &[0.0]);
            last = e;
            e *= -3.0;
        }
        assert_eq!(f.correction(0), -last);
        f.reset();
        assert_eq!(f.correction(0), 0.0);
        f.record(&[1e-6], &[0.0]);
        assert_eq!(f.correction(0), 0.0);
    }
}
