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

    /// Algorithmic acceleration from the recurrence.
    #[inline]
    pub fn algorithmic_acceleration(&self, a_n: f64, vdot_n: f64, vdot_np1: f64) -> f64 {
        (self.alpha_f * vdot_n - self.alpha_m * a_n + (1.0 - self.alpha_f) * vdot_np1)
            / (1.0 - self.alpha_m)
    }
}
