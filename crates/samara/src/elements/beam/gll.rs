//! Points, weights and Lagrange bases of the spectral element (one idea: 1-D quadrature and
//! interpolation on ξ ∈ [−1, 1]).
//!
//! - Gauss–Lobatto–Legendre (GLL) points of order p: ξ = ±1 and the p − 1 roots of P′ₚ(ξ);
//!   the element's nodes sit there (Legendre spectral elements; Patera 1984, BeamDyn).
//! - Gauss–Legendre points and weights: the n roots of Pₙ(ξ), weights 2/((1 − ξ²) P′ₙ(ξ)²);
//!   exact for polynomials of degree 2n − 1.
//! - Lagrange basis hᵢ(ξ) through given nodes, and its derivative, by the barycentric-free
//!   product formula (p ≤ 30, so the O(p²) cost is irrelevant at setup time).
//!
//! Roots are found by Newton's method on the three-term Legendre recurrence, started from
//! the Chebyshev–Gauss(–Lobatto) points, to machine precision.

/// Legendre polynomial Pₙ(x) and its derivative P′ₙ(x) by the three-term recurrence.
pub fn legendre(n: usize, x: f64) -> (f64, f64) {
    if n == 0 {
        return (1.0, 0.0);
    }
    let (mut p0, mut p1) = (1.0, x);
    for k in 2..=n {
        let kf = k as f64;
        let p2 = ((2.0 * kf - 1.0) * x * p1 - (kf - 1.0) * p0) / kf;
        p0 = p1;
        p1 = p2;
    }
    // P′ₙ = n (x Pₙ − Pₙ₋₁)/(x² − 1), with the endpoint limit n(n+1)/2 · (±1)^(n+1).
    let d = if (1.0 - x.abs()) < 1e-14 {
        let s = if x > 0.0 {
            1.0
        } else {
            (-1.0f64).powi(n as i32 + 1)
        };
        s * (n * (n + 1)) as f64 / 2.0
    } else {
        n as f64 * (x * p1 - p0) / (x * x - 1.0)
    };
    (p1, d)
}

/// Gauss–Legendre points and weights (n ≥ 1), ascending.
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut x = vec![0.0; n];
    let mut w = vec![0.0; n];
    for i in 0..n {
        // Chebyshev–Gauss initial guess, descending → store ascending.
        let mut xi = -(std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        for _ in 0..100 {
            let (p, dp) = legendre(n, xi);
            let dx = p / dp;
            xi -= dx;
            if dx.abs() < 1e-16 {
                break;
            }
        }
        let (_, dp) = legendre(n, xi);
        x[i] = xi;
        w[i] = 2.0 / ((1.0 - xi * xi) * dp * dp);
    }
    (x, w)
}

/// Gauss–Lobatto–Legendre points and weights of order p ≥ 1 (p + 1 points), ascending.
pub fn gauss_lobatto_legendre(p: usize) -> (Vec<f64>, Vec<f64>) {
    let n = p + 1;
    let mut x = vec![0.0; n];
    let mut w = vec![0.0; n];
    x[0] = -1.0;
    x[p] = 1.0;
    for i in 1..p {
        // Interior points: roots of P′ₚ, from the Chebyshev–Gauss–Lobatto guess.
        let mut xi = -(std::f64::consts::PI * i as f64 / p as f64).cos();
        for _ in 0..100 {
            // Newton on P′ₚ: (1 − x²) P″ₚ = 2x P′ₚ − p(p+1) Pₚ.
            let (pp, dp) = legendre(p, xi);
            let d2 = (2.0 * xi * dp - (p * (p + 1)) as f64 * pp) / (1.0 - xi * xi);
            let dx = dp / d2;
            xi -= dx;
            if dx.abs() < 1e-16 {
                break;
            }
        }
        x[i] = xi;
    }
    for i in 0..n {
        let (pp, _) = legendre(p, x[i]);
        w[i] = 2.0 / ((p * (p + 1)) as f64 * pp * pp);
    }
    (x, w)
}

/// Values hᵢ(ξ) and derivatives dhᵢ/dξ of the Lagrange polynomials through `nodes`.
pub fn lagrange(nodes: &[f64], xi: f64, h: &mut [f64], dh: &mut [f64]) {
    let n = nodes.len();
    for i in 0..n {
        let mut value = 1.0;
        let mut deriv = 0.0;
        for j in 0..n {
            if j == i {
                continue;
            }
            let den = nodes[i] - nodes[j];
            // d/dξ of the running product: (a·b)′ = a′b + ab′.
            deriv = deriv * (xi - nodes[j]) / den + value / den;
            value *= (xi - nodes[j]) / den;
        }
        h[i] = value;
        dh[i] = deriv;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Gauss–Legendre with n points integrates x^k exactly for k ≤ 2n − 1: ∫x^k = 2/(k+1)
    /// for even k, 0 for odd k. Round-off only (1e-14).
    #[test]
    fn gauss_is_exact_to_degree_2n_minus_1() {
        for n in 1..=16 {
            let (x, w) = gauss_legendre(n);
            for k in 0..2 * n {
                let q: f64 = x.iter().zip(&w).map(|(a, b)| b * a.powi(k as i32)).sum();
                let exact = if k % 2 == 0 {
                    2.0 / (k + 1) as f64
                } else {
                    0.0
                };
                assert!((q - exact).abs() < 1e-13, "n {n} k {k}: {q} vs {exact}");
            }
        }
    }

    /// GLL with p + 1 points is exact to degree 2p − 1; known points for p = 4:
    /// 0, ±√(3/7) (Abramowitz & Stegun 25.4.32).
    #[test]
    fn gauss_lobatto_points_and_exactness() {
        let (x, _) = gauss_lobatto_legendre(4);
        assert!((x[1] + (3.0f64 / 7.0).sqrt()).abs() < 1e-15 && x[2].abs() < 1e-15);
        for p in 1..=15 {
            let (x, w) = gauss_lobatto_legendre(p);
            for k in 0..2 * p {
                let q: f64 = x.iter().zip(&w).map(|(a, b)| b * a.powi(k as i32)).sum();
                let exact = if k % 2 == 0 {
                    2.0 / (k + 1) as f64
                } else {
                    0.0
                };
                assert!((q - exact).abs() < 1e-13, "p {p} k {k}: {q} vs {exact}");
            }
        }
    }

    /// The Lagrange basis reproduces polynomials of its degree (values and derivatives).
    #[test]
    fn lagrange_reproduces_polynomials() {
        let (nodes, _) = gauss_lobatto_legendre(6);
        let f = |x: f64| 1.0 - 2.0 * x + 0.5 * x.powi(3) - 0.25 * x.powi(6);
        let df = |x: f64| -2.0 + 1.5 * x * x - 1.5 * x.powi(5);
        let mut h = vec![0.0; 7];
        let mut dh = vec![0.0; 7];
        for &xi in &[-0.9, -0.3, 0.1, 0.77] {
            lagrange(&nodes, xi, &mut h, &mut dh);
            let v: f64 = nodes.iter().zip(&h).map(|(n, h)| f(*n) * h).sum();
            let d: f64 = nodes.iter().zip(&dh).map(|(n, h)| f(*n) * h).sum();
            assert!((v - f(xi)).abs() < 1e-13 && (d - df(xi)).abs() < 1e-12);
        }
    }
}
