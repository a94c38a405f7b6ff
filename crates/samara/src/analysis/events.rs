//! State events inside a step: where an element's event function g (a contact's
//! penetration, its force before the no-pull clip) changes sign, its law has a kink, and a
//! step across it is accurate only to low order. Adaptive steps land on these zeros
//! (Hairer, Nørsett & Wanner, *Solving ODEs I*, §II.6 "dense output and event location";
//! Shampine & Thompson 2000): the first zero in the step is found on the cubic Hermite
//! interpolant of g through (g₀, ġ₀) and (g₁, ġ₁), or on the secant where a rate is
//! unknown, and the step is redone ending just past it.
//!
//! The sign convention is the elements': g > 0 is the active side (in contact).

/// Fraction θ ∈ [0, 1] of a step of size `h` at which the first event function changes
/// its side (g > 0 or not), from values and rates at both ends; `None` if it keeps its
/// side. With both rates known, the cubic Hermite interpolant also finds a graze (g dips
/// across zero and back inside the step although both ends are on one side).
pub fn first_crossing(start: (f64, f64), end: (f64, f64), h: f64) -> Option<f64> {
    let (g0, d0) = start;
    let (g1, d1) = end;
    if !(g0.is_finite() && g1.is_finite()) {
        return None;
    }
    let side = |g: f64| g > 0.0;
    if !(d0.is_finite() && d1.is_finite()) {
        // Secant.
        return (side(g0) != side(g1)).then(|| (g0 / (g0 - g1)).clamp(0.0, 1.0));
    }
    // p(s) = h00 g0 + h10 h d0 + h01 g1 + h11 h d1, s ∈ [0, 1].
    let (m0, m1) = (h * d0, h * d1);
    let p = |s: f64| {
        let s2 = s * s;
        let s3 = s2 * s;
        (2.0 * s3 - 3.0 * s2 + 1.0) * g0
            + (s3 - 2.0 * s2 + s) * m0
            + (-2.0 * s3 + 3.0 * s2) * g1
            + (s3 - s2) * m1
    };
    // A cubic has at most two extrema, so 16 sub-intervals bracket the first side change
    // unless a graze is shallower than the sampling resolves (then it is missed, as it
    // would be by any finite test).
    const SAMPLES: usize = 16;
    let mut lo = 0.0;
    let mut plo = g0;
    for i in 1..=SAMPLES {
        let s = i as f64 / SAMPLES as f64;
        let ps = if i == SAMPLES { g1 } else { p(s) };
        if side(ps) != side(plo) {
            // Bisection on the bracket [lo, s] to 1e-12 of the step.
            let (mut a, mut b) = (lo, s);
            while b - a > 1e-12 {
                let m = 0.5 * (a + b);
                if side(p(m)) == side(plo) {
                    a = m;
                } else {
                    b = m;
                }
            }
            return Some(b);
        }
        lo = s;
        plo = ps;
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cubic g is found to the bisection tolerance (its Hermite interpolant is itself).
    #[test]
    fn finds_the_zero_of_a_cubic_exactly() {
        // g(t) = (t − 0.3)(t + 1)(t + 2) on a step of h = 1: first zero at 0.3.
        let g = |t: f64| (t - 0.3) * (t + 1.0) * (t + 2.0);
        let dg = |t: f64| (t + 1.0) * (t + 2.0) + (t - 0.3) * (2.0 * t + 3.0);
        let th = first_crossing((g(0.0), dg(0.0)), (g(1.0), dg(1.0)), 1.0).unwrap();
        assert!((th - 0.3).abs() < 1e-11, "{th}");
        // Scaled step: the same curve over [0, 2] with h = 2 (rates per unit time).
        let th = first_crossing((g(0.0), dg(0.0)), (g(2.0), dg(2.0)), 2.0).unwrap();
        assert!((2.0 * th - 0.3).abs() < 1e-11, "{th}");
    }

    /// A graze: g = (t − 0.25)(t − 0.5) + small, both ends positive, dips below in between.
    #[test]
    fn finds_a_graze_and_ignores_a_miss() {
        let g = |t: f64| (t - 0.25) * (t - 0.5);
        let dg = |t: f64| 2.0 * t - 0.75;
        let th = first_crossing((g(0.0), dg(0.0)), (g(1.0), dg(1.0)), 1.0).unwrap();
        // p(s) > 0 up to s = 0.25, where it reaches 0 and leaves the active side.
        assert!((th - 0.25).abs() < 1e-11, "{th}");
        let miss = |t: f64| (t - 0.4) * (t - 0.4) + 0.01;
        let dmiss = |t: f64| 2.0 * (t - 0.4);
        assert_eq!(
            first_crossing((miss(0.0), dmiss(0.0)), (miss(1.0), dmiss(1.0)), 1.0),
            None
        );
    }

    /// Without rates: the secant.
    #[test]
    fn secant_without_rates() {
        let th = first_crossing((1.0, f64::NAN), (-3.0, f64::NAN), 1.0).unwrap();
        assert!((th - 0.25).abs() < 1e-15);
        assert_eq!(first_crossing((1.0, f64::NAN), (3.0, 0.0), 1.0), None);
    }
}
