//! Forward-mode automatic differentiation with N directions: a number `v + Σ dₖ εₖ`
//! (εₖ εₗ = 0). Kernels written once over [`Scalar`] give their value with `f64` and their
//! exact first derivatives with `Dual<N>` (no truncation error, unlike finite differences).
//! Used where tangents by hand would be long and fragile (aerodynamic stations, the BEM
//! solution through the implicit-function theorem). Fixed size: no allocation.

use std::ops::{Add, AddAssign, Div, Mul, Neg, Sub, SubAssign};

/// A scalar a kernel can be written over: `f64` or [`Dual`].
pub trait Scalar:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + Add<f64, Output = Self>
    + Sub<f64, Output = Self>
    + Mul<f64, Output = Self>
    + Div<f64, Output = Self>
    + AddAssign
    + SubAssign
    + std::fmt::Debug
{
    /// Number of derivative directions (0 for `f64`).
    const DIRECTIONS: usize;
    fn cst(v: f64) -> Self;
    /// The value (the f64 part).
    fn re(&self) -> f64;
    fn sqrt(self) -> Self;
    fn sin(self) -> Self;
    fn cos(self) -> Self;
    fn exp(self) -> Self;
    fn acos(self) -> Self;
    fn atan2(self, x: Self) -> Self;
    fn powf(self, p: f64) -> Self;
    /// A function of one variable given its value and derivative at `self.re()`.
    fn chain(self, f: f64, df: f64) -> Self;
    /// Adds `dv` to the derivative in direction k (nothing for `f64`).
    fn add_deriv(&mut self, k: usize, dv: f64);
    /// The derivative in direction k (0 for `f64`).
    fn deriv(&self, k: usize) -> f64;
    fn abs(self) -> Self {
        if self.re() < 0.0 { -self } else { self }
    }
}

impl Scalar for f64 {
    const DIRECTIONS: usize = 0;
    fn cst(v: f64) -> Self {
        v
    }
    fn re(&self) -> f64 {
        *self
    }
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    fn sin(self) -> Self {
        f64::sin(self)
    }
    fn cos(self) -> Self {
        f64::cos(self)
    }
    fn exp(self) -> Self {
        f64::exp(self)
    }
    fn acos(self) -> Self {
        f64::acos(self)
    }
    fn atan2(self, x: Self) -> Self {
        f64::atan2(self, x)
    }
    fn powf(self, p: f64) -> Self {
        f64::powf(self, p)
    }
    fn chain(self, f: f64, _df: f64) -> Self {
        f
    }
    fn add_deriv(&mut self, _k: usize, _dv: f64) {}
    fn deriv(&self, _k: usize) -> f64 {
        0.0
    }
}

/// A dual number with N derivative directions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dual<const N: usize> {
    pub v: f64,
    pub d: [f64; N],
}

impl<const N: usize> Dual<N> {
    /// The k-th independent variable with value v.
    pub fn var(v: f64, k: usize) -> Self {
        let mut d = [0.0; N];
        d[k] = 1.0;
        Self { v, d }
    }

    #[inline]
    fn map(self, f: f64, df: f64) -> Self {
        let mut d = self.d;
        for x in &mut d {
            *x *= df;
        }
        Self { v: f, d }
    }
}

impl<const N: usize> Scalar for Dual<N> {
    const DIRECTIONS: usize = N;
    fn cst(v: f64) -> Self {
        Self { v, d: [0.0; N] }
    }
    fn re(&self) -> f64 {
        self.v
    }
    fn sqrt(self) -> Self {
        let s = self.v.sqrt();
        self.map(s, 0.5 / s)
    }
    fn sin(self) -> Self {
        self.map(self.v.sin(), self.v.cos())
    }
    fn cos(self) -> Self {
        self.map(self.v.cos(), -self.v.sin())
    }
    fn exp(self) -> Self {
        let e = self.v.exp();
        self.map(e, e)
    }
    fn acos(self) -> Self {
        self.map(self.v.acos(), -1.0 / (1.0 - self.v * self.v).sqrt())
    }
    fn atan2(self, x: Self) -> Self {
        // d atan2(y, x) = (x dy − y dx)/(x² + y²)
        let r2 = self.v * self.v + x.v * x.v;
        let mut d = [0.0; N];
        for (k, dk) in d.iter_mut().enumerate() {
            *dk = (x.v * self.d[k] - self.v * x.d[k]) / r2;
        }
        Self {
            v: self.v.atan2(x.v),
            d,
        }
    }
    fn powf(self, p: f64) -> Self {
        self.map(self.v.powf(p), p * self.v.powf(p - 1.0))
    }
    fn chain(self, f: f64, df: f64) -> Self {
        self.map(f, df)
    }
    fn add_deriv(&mut self, k: usize, dv: f64) {
        self.d[k] += dv;
    }
    fn deriv(&self, k: usize) -> f64 {
        self.d[k]
    }
}

impl<const N: usize> Add for Dual<N> {
    type Output = Self;
    #[inline]
    fn add(mut self, o: Self) -> Self {
        self.v += o.v;
        for k in 0..N {
            self.d[k] += o.d[k];
        }
        self
    }
}
impl<const N: usize> Sub for Dual<N> {
    type Output = Self;
    #[inline]
    fn sub(mut self, o: Self) -> Self {
        self.v -= o.v;
        for k in 0..N {
            self.d[k] -= o.d[k];
        }
        self
    }
}
impl<const N: usize> Mul for Dual<N> {
    type Output = Self;
    #[inline]
    fn mul(self, o: Self) -> Self {
        let mut d = [0.0; N];
        for (k, dk) in d.iter_mut().enumerate() {
            *dk = self.d[k] * o.v + self.v * o.d[k];
        }
        Self { v: self.v * o.v, d }
    }
}
impl<const N: usize> Div for Dual<N> {
    type Output = Self;
    #[inline]
    fn div(self, o: Self) -> Self {
        let inv = 1.0 / o.v;
        let q = self.v * inv;
        let mut d = [0.0; N];
        for (k, dk) in d.iter_mut().enumerate() {
            *dk = (self.d[k] - q * o.d[k]) * inv;
        }
        Self { v: q, d }
    }
}
impl<const N: usize> Neg for Dual<N> {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        self.map(-self.v, -1.0)
    }
}
impl<const N: usize> Add<f64> for Dual<N> {
    type Output = Self;
    #[inline]
    fn add(mut self, o: f64) -> Self {
        self.v += o;
        self
    }
}
impl<const N: usize> Sub<f64> for Dual<N> {
    type Output = Self;
    #[inline]
    fn sub(mut self, o: f64) -> Self {
        self.v -= o;
        self
    }
}
impl<const N: usize> Mul<f64> for Dual<N> {
    type Output = Self;
    #[inline]
    fn mul(self, o: f64) -> Self {
        self.map(self.v * o, o)
    }
}
impl<const N: usize> Div<f64> for Dual<N> {
    type Output = Self;
    #[inline]
    fn div(self, o: f64) -> Self {
        self.map(self.v / o, 1.0 / o)
    }
}
impl<const N: usize> AddAssign for Dual<N> {
    #[inline]
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}
impl<const N: usize> SubAssign for Dual<N> {
    #[inline]
    fn sub_assign(&mut self, o: Self) {
        *self = *self - o;
    }
}

/// A 3-vector of scalars (plain arrays: nalgebra's generic scalars need more traits).
pub type V3<S> = [S; 3];

#[inline]
pub fn dot<S: Scalar>(a: &V3<S>, b: &V3<S>) -> S {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[inline]
pub fn cross<S: Scalar>(a: &V3<S>, b: &V3<S>) -> V3<S> {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

#[inline]
pub fn add<S: Scalar>(a: &V3<S>, b: &V3<S>) -> V3<S> {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

#[inline]
pub fn sub<S: Scalar>(a: &V3<S>, b: &V3<S>) -> V3<S> {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[inline]
pub fn scale<S: Scalar>(a: &V3<S>, s: S) -> V3<S> {
    [a[0] * s, a[1] * s, a[2] * s]
}

#[inline]
pub fn cst3<S: Scalar>(a: &nalgebra::Vector3<f64>) -> V3<S> {
    [S::cst(a[0]), S::cst(a[1]), S::cst(a[2])]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivatives_match_closed_forms() {
        let x = Dual::<2>::var(0.7, 0);
        let y = Dual::<2>::var(-0.3, 1);
        let f = (x * y).sin() + y.atan2(x) * x.exp() / (x * x + 1.0).sqrt();
        // ∂f/∂x, ∂f/∂y by hand.
        let (xv, yv) = (0.7f64, -0.3f64);
        let s = (xv * xv + 1.0).sqrt();
        let g = yv.atan2(xv);
        let dfx =
            yv * (xv * yv).cos() + (-yv / (xv * xv + yv * yv)) * xv.exp() / s + g * xv.exp() / s
                - g * xv.exp() * xv / (s * s * s);
        let dfy = xv * (xv * yv).cos() + (xv / (xv * xv + yv * yv)) * xv.exp() / s;
        assert!((f.d[0] - dfx).abs() < 1e-14, "{} {}", f.d[0], dfx);
        assert!((f.d[1] - dfy).abs() < 1e-14);
        let p = Dual::<1>::var(0.4, 0).powf(0.2);
        assert!((p.d[0] - 0.2 * 0.4f64.powf(-0.8)).abs() < 1e-14);
        let a = Dual::<1>::var(0.3, 0).acos();
        assert!((a.d[0] + 1.0 / (1.0 - 0.09f64).sqrt()).abs() < 1e-14);
    }
}
