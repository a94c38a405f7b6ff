//! Generalized-α coefficients (Chung & Hulbert 1993) and their Lie-group use
//! (Arnold & Brüls 2007; Brüls, Cardona & Arnold 2012).
//!
//! With the algorithmic acceleration `a`:
//!
//! ```text
//! q_{n+1} = q_n ∘ exp(h Δq_n),    Δq_n = v_n + h(½ − β) a_n + hβ a_{n+1}
//! v_{n+1} = v_n + h(1 − γ) a_n + hγ a_{n+1}
//! (1 − α_m) a_{n+1} + α_m a_n = (1 − α_f) v̇_{n+1} + α_f v̇_n
//! ```
//!
//! and equilibrium `M v̇ + g + Bᵀλ = 0`, `Φ = 0` imposed at t_{n+1}. A Newton correction
//! Δx changes `v̇ += β'Δx`, `v += γ'Δx`, `hΔq += Δx`, so the iteration matrix is
//! `β'M + γ'C + K T(hΔq)`.
//!
//! Verified in `tests/generalized_alpha.rs`: the dynamic analysis on a linear oscillator
//! follows Chung & Hulbert's closed-form amplification matrix to round-off (damping ratio,
//! period error, ρ∞ at high frequency, second order).

/// Coefficients of the scheme for a given ρ∞.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GeneralizedAlpha {
    pub alpha_m: f64,
    pub alpha_f: f64,
    pub beta: f64,
    pub gamma: f64,
}

impl GeneralizedAlpha {
    /// Second-order accurate, unconditionally stable (linear) member with high-frequency
    /// spectral radius ρ∞ ∈ [0, 1]:
    /// α_m = (2ρ∞ − 1)/(ρ∞ + 1), α_f = ρ∞/(ρ∞ + 1), γ = ½ + α_f − α_m, β = ¼(γ + ½)².
    pub fn from_rho_inf(rho: f64) -> Self {
        let alpha_m = (2.0 * rho - 1.0) / (rho + 1.0);
        let alpha_f = rho / (rho + 1.0);
        let gamma = 0.5 + alpha_f - alpha_m;
        let beta = 0.25 * (gamma + 0.5).powi(2);
        Self {
            alpha_m,
            alpha_f,
            beta,
            gamma,
        }
    }

    /// β' = ∂v̇_{n+1}/∂(hΔq) = (1 − α_m)/(βh²(1 − α_f)).
    pub fn beta_prime(&self, h: f64) -> f64 {
        (1.0 - self.alpha_m) / (self.beta * h * h * (1.0 - self.alpha_f))
    }

    /// γ' = ∂v_{n+1}/∂(hΔq) = γ/(βh).
    pub fn gamma_prime(&self, h: f64) -> f64 {
        self.gamma / (self.beta * h)
    }

    /// The derivative v̇_{n+1} that gives the algorithmic acceleration `a_np1` (the inverse
    /// of [`Self::algorithmic_acceleration`]).
    #[inline]
    pub fn derivative_of(&self, a_n: f64, vdot_n: f64, a_np1: f64) -> f64 {
        ((1.0 - self.alpha_m) * a_np1 + self.alpha_m * a_n - self.alpha_f * vdot_n)
            / (1.0 - self.alpha_f)
    }

    /// v_{n+1} and v̇_{n+1} for the increment `hdq`: hΔq = h v_n + h²(½ − β) a_n + h²β a_{n+1}
    /// solved for a_{n+1}, then v_{n+1} = v_n + h(1 − γ) a_n + hγ a_{n+1}.
    #[inline]
    pub fn rates_of_increment(
        &self,
        h: f64,
        v_n: f64,
        vdot_n: f64,
        a_n: f64,
        hdq: f64,
    ) -> (f64, f64) {
        let a_np1 = (hdq / (h * h) - v_n / h - (0.5 - self.beta) * a_n) / self.beta;
        (
            v_n + h * (1.0 - self.gamma) * a_n + h * self.gamma * a_np1,
            self.derivative_of(a_n, vdot_n, a_np1),
        )
    }

    /// Algorithmic acceleration from the recurrence.
    #[inline]
    pub fn algorithmic_acceleration(&self, a_n: f64, vdot_n: f64, vdot_np1: f64) -> f64 {
        (self.alpha_f * vdot_n - self.alpha_m * a_n + (1.0 - self.alpha_f) * vdot_np1)
            / (1.0 - self.alpha_m)
    }
}

/// First-order generalized-α for element states (Jansen, Whiting & Hulbert 2000), written
/// like the structural scheme with an algorithmic rate `w` and the residual at t_{n+1}:
///
/// ```text
/// z_{n+1} = z_n + h(1 − γ) w_n + hγ w_{n+1}
/// (1 − α_m) w_{n+1} + α_m w_n = (1 − α_f) ż_{n+1} + α_f ż_n
/// ```
///
/// with α_m = (3ρ∞ − 1)/(2(1 + ρ∞)), α_f = ρ∞/(1 + ρ∞), γ = 1/(1 + ρ∞) — one minus
/// JWH's α's, the same change of variables that takes Chung–Hulbert to Arnold–Brüls. For
/// ż = λz it is second order (γ = ½ + α_f − α_m) and both eigenvalues of its amplification
/// matrix tend to −ρ∞ as hλ → −∞, so the states are damped like the structure.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FirstOrderAlpha {
    pub alpha_m: f64,
    pub alpha_f: f64,
    pub gamma: f64,
}

impl FirstOrderAlpha {
    pub fn from_rho_inf(rho: f64) -> Self {
        Self {
            alpha_m: (3.0 * rho - 1.0) / (2.0 * (1.0 + rho)),
            alpha_f: rho / (1.0 + rho),
            gamma: 1.0 / (1.0 + rho),
        }
    }

    /// ∂ż_{n+1}/∂Δz = (1 − α_m)/(hγ(1 − α_f)).
    pub fn rate_prime(&self, h: f64) -> f64 {
        (1.0 - self.alpha_m) / (h * self.gamma * (1.0 - self.alpha_f))
    }

    /// Algorithmic rate w_{n+1} from the recurrence.
    #[inline]
    pub fn algorithmic_rate(&self, w_n: f64, zd_n: f64, zd_np1: f64) -> f64 {
        (self.alpha_f * zd_n - self.alpha_m * w_n + (1.0 - self.alpha_f) * zd_np1)
            / (1.0 - self.alpha_m)
    }

    /// The rate ż_{n+1} that gives the algorithmic rate `w_np1`.
    #[inline]
    pub fn rate_of(&self, w_n: f64, zd_n: f64, w_np1: f64) -> f64 {
        ((1.0 - self.alpha_m) * w_np1 + self.alpha_m * w_n - self.alpha_f * zd_n)
            / (1.0 - self.alpha_f)
    }

    /// The rate ż_{n+1} for the increment `dz` = z_{n+1} − z_n (the inverse of
    /// [`Self::increment`] followed by [`Self::rate_of`]).
    #[inline]
    pub fn rate_of_increment(&self, h: f64, w_n: f64, zd_n: f64, dz: f64) -> f64 {
        let w_np1 = (dz / h - (1.0 - self.gamma) * w_n) / self.gamma;
        self.rate_of(w_n, zd_n, w_np1)
    }

    /// The increment z_{n+1} − z_n for the algorithmic rate `w_np1`.
    #[inline]
    pub fn increment(&self, h: f64, w_n: f64, w_np1: f64) -> f64 {
        h * ((1.0 - self.gamma) * w_n + self.gamma * w_np1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The amplification of ż = λz: second order at small hλ, −ρ∞ at hλ → −∞
    /// (the properties derived in the doc comment), for several ρ∞.
    #[test]
    fn first_order_scheme_is_second_order_and_damps_like_rho_inf() {
        for rho in [0.0, 0.3, 0.6, 0.9, 1.0] {
            let a = FirstOrderAlpha::from_rho_inf(rho);
            // One step of size 1 of ż = (hλ) z (time measured in steps).
            let step = |hl: f64, z: f64, w: f64| -> (f64, f64) {
                // ż_{n+1} = λ z_{n+1}; unknown z1: z1 = z + h(1−γ)w + hγ w1,
                // w1 = ((1−α_f) λ z1 + α_f λ z − α_m w)/(1−α_m), with h = 1, λ = hl.
                let c = a.gamma * (1.0 - a.alpha_f) * hl / (1.0 - a.alpha_m);
                let rhs = z
                    + (1.0 - a.gamma) * w
                    + a.gamma * (a.alpha_f * hl * z - a.alpha_m * w) / (1.0 - a.alpha_m);
                let z1 = rhs / (1.0 - c);
                let w1 = ((1.0 - a.alpha_f) * hl * z1 + a.alpha_f * hl * z - a.alpha_m * w)
                    / (1.0 - a.alpha_m);
                (z1, w1)
            };
            // Global error at t = 1 of ż = −z with N steps falls as N⁻².
            let err = |n: usize| {
                let (mut z, mut w) = (1.0, -1.0 / n as f64);
                for _ in 0..n {
                    (z, w) = step(-1.0 / n as f64, z, w);
                }
                (z - (-1.0f64).exp()).abs()
            };
            let order = (err(200) / err(400)).log2();
            assert!((order - 2.0).abs() < 0.05, "ρ∞ = {rho}: order {order}");
            // Spectral radius at hλ = −1e8: eigenvalues of the amplification matrix of
            // (z, w) from its trace and determinant (a double root, −ρ∞).
            let hl = -1e8;
            let (a11, a21) = step(hl, 1.0, 0.0);
            let (a12, a22) = step(hl, 0.0, 1.0);
            let (tr, det) = (a11 + a22, a11 * a22 - a12 * a21);
            let disc = (0.25 * tr * tr - det).max(0.0).sqrt();
            let radius = (0.5 * tr).abs() + disc;
            assert!(
                (radius - rho).abs() < 1e-6,
                "ρ∞ = {rho}: spectral radius {radius}"
            );
            assert!(tr < 0.0 || rho == 0.0, "ρ∞ = {rho}: the root is −ρ∞ ({tr})");
        }
    }
}
