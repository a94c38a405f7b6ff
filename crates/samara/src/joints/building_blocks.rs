//! The two building blocks of every lower-pair joint (Bottasso, "Computational dynamics",
//! eq. 12), with θ = 0 / d = 0 (the component constrained):
//!
//! ```text
//! (12a)  Φ = e_iᴬ · (uᴮ − uᴬ)        relative displacement along e_iᴬ
//! (12b)  Φ = e_jᴬ · e_kᴮ              relative rotation about e_iᴬ, (i, j, k) cyclic
//! ```
//!
//! and, with a joint coordinate ν set free, the defining forms `e_iᴬ·(uᴮ − uᴬ) − ν` and
//! `cos ν (e_kᴬ·e_jᴮ) − sin ν (e_jᴬ·e_jᴮ) = sin(θ − ν)` ([`AngleRow`]).
//!
//! Kernels here work in global ("spatial") components: a side X has position `x`, arm
//! `r = R s` to the joint origin, and rotation variations `δφ` with `δR = δφ̃ R`. They
//! return, per scalar constraint,
//! - `Φ`,
//! - the Jacobian row `b` over `[δxᴬ, δφᴬ, δxᴮ, δφᴮ]` (12 entries),
//! - `μ ∂(bᵀ)/∂q`, the tangent of the generalized constraint force `bᵀ μ` (12 × 12),
//! - the convective part of `Φ̈` (all terms not multiplying accelerations).
//!
//! The conversion to the material rotation increments used by the nodes is done by the
//! caller (`joint.rs`).

use crate::math::skew;
use nalgebra::{Matrix3, SVector, Vector3};
use std::mem::MaybeUninit;

pub type Row12 = SVector<f64, 12>;

/// Current kinematics of the two frames of a joint, global components.
#[derive(Clone, Debug)]
pub struct FramePair {
    /// Node positions.
    pub x: [Vector3<f64>; 2],
    /// Arms from node to frame origin, `R s`.
    pub arm: [Vector3<f64>; 2],
    /// Frame axes (columns), `R A_local`.
    pub axes: [Matrix3<f64>; 2],
    /// Node velocities.
    pub v: [Vector3<f64>; 2],
    /// Node angular velocities (global).
    pub omega: [Vector3<f64>; 2],
}

impl FramePair {
    /// Frame origins uᴬ, uᴮ.
    #[inline]
    pub fn origin(&self, side: usize) -> Vector3<f64> {
        self.x[side] + self.arm[side]
    }

    /// `(vᴬ, ωᴬ, vᴮ, ωᴮ)`, the velocities the 12-entry rows act on.
    pub fn spatial_velocities(&self) -> Row12 {
        Row12::from_iterator(
            [self.v[0], self.omega[0], self.v[1], self.omega[1]]
                .iter()
                .flat_map(|v| v.iter().copied()),
        )
    }

    /// The frames' mean over a step, `(f0 + f1)/2` entry by entry (its axes are not
    /// orthonormal): the rows, bilinear in positions, arms and axes, have there the
    /// Jacobian of the discrete product rule.
    pub fn mean(f0: &FramePair, f1: &FramePair) -> FramePair {
        let avg = |a: &Vector3<f64>, b: &Vector3<f64>| (a + b) * 0.5;
        FramePair {
            x: [avg(&f0.x[0], &f1.x[0]), avg(&f0.x[1], &f1.x[1])],
            arm: [avg(&f0.arm[0], &f1.arm[0]), avg(&f0.arm[1], &f1.arm[1])],
            axes: [
                (f0.axes[0] + f1.axes[0]) * 0.5,
                (f0.axes[1] + f1.axes[1]) * 0.5,
            ],
            v: [Vector3::zeros(); 2],
            omega: [Vector3::zeros(); 2],
        }
    }

    /// Relative displacement `d = uᴮ − uᴬ`.
    #[inline]
    pub fn d(&self) -> Vector3<f64> {
        self.origin(1) - self.origin(0)
    }
}

#[inline]
fn put3(row: &mut Row12, at: usize, v: &Vector3<f64>) {
    for i in 0..3 {
        row[at + i] = v[i];
    }
}

/// A 12 × 12 spatial tangent (rows and columns `[δxᴬ, δφᴬ, δxᴮ, δφᴮ]`) as its 4 × 4 grid
/// of 3 × 3 blocks with a mask of the blocks written: a block is assigned by its first term
/// and added to after, so nothing is zeroed beforehand (1,152 bytes per joint and
/// iteration) and the blocks no term reaches are known without testing their entries.
/// The values are those of a zeroed 12 × 12 added into (`0 + x = x`, up to the sign of a
/// zero entry).
pub struct Blocks12 {
    blocks: [[MaybeUninit<Matrix3<f64>>; 4]; 4],
    used: u16,
}

impl Default for Blocks12 {
    fn default() -> Self {
        Self::new()
    }
}

impl Blocks12 {
    /// No block written.
    #[inline(always)]
    pub fn new() -> Self {
        Self {
            blocks: [[MaybeUninit::uninit(); 4]; 4],
            used: 0,
        }
    }

    /// Block (`r`, `c`) of the 4 × 4 grid, `None` if no term was added to it.
    #[inline(always)]
    pub fn get(&self, r: usize, c: usize) -> Option<&Matrix3<f64>> {
        // SAFETY: a block whose bit is set was assigned by `add`.
        (self.used & (1 << (4 * r + c)) != 0)
            .then(|| unsafe { self.blocks[r][c].assume_init_ref() })
    }

    /// `sᵀ K`, the row vector `s` (12 entries) times the tangent, over the blocks written.
    #[inline(always)]
    pub fn left_product(&self, s: &Row12) -> Row12 {
        let mut out = Row12::zeros();
        for r in 0..4 {
            let sr = Vector3::new(s[3 * r], s[3 * r + 1], s[3 * r + 2]);
            for c in 0..4 {
                if let Some(b) = self.get(r, c) {
                    let p = b.tr_mul(&sr);
                    for j in 0..3 {
                        out[3 * c + j] += p[j];
                    }
                }
            }
        }
        out
    }

    /// `K[3r.., 3c..] += b` (the first term assigned).
    #[inline(always)]
    fn add(&mut self, r: usize, c: usize, b: &Matrix3<f64>) {
        let bit = 1 << (4 * r + c);
        if self.used & bit == 0 {
            self.blocks[r][c].write(*b);
            self.used |= bit;
        } else {
            // SAFETY: the bit is set, so the block was assigned.
            *unsafe { self.blocks[r][c].assume_init_mut() } += b;
        }
    }
}

/// `K += b` at rows `r`, columns `c` (multiples of 3) of the 12 × 12 spatial tangent.
#[inline(always)]
fn add33(k: &mut Blocks12, r: usize, c: usize, b: &Matrix3<f64>) {
    k.add(r / 3, c / 3, b);
}

/// Eq. (12a) with d_i = 0 along axis `i` of frame A.
pub mod displacement {
    use super::*;

    #[inline]
    pub fn value(f: &FramePair, i: usize) -> f64 {
        f.axes[0].column(i).dot(&f.d())
    }

    /// `b = [−eᵀ, (e × w)ᵀ, eᵀ, (r_B × e)ᵀ]` with `w = uᴮ − xᴬ`.
    #[inline(always)]
    pub fn jacobian(f: &FramePair, i: usize) -> Row12 {
        let e: Vector3<f64> = f.axes[0].column(i).into();
        let w = f.origin(1) - f.x[0];
        let mut b = Row12::zeros();
        put3(&mut b, 0, &(-e));
        put3(&mut b, 3, &e.cross(&w));
        put3(&mut b, 6, &e);
        put3(&mut b, 9, &f.arm[1].cross(&e));
        b
    }

    /// `μ ∂(bᵀ)/∂q` (spatial).
    pub fn force_tangent(f: &FramePair, i: usize, mu: f64, k: &mut Blocks12) {
        let e: Vector3<f64> = f.axes[0].column(i).into();
        force_tangent_along(f, &(e * mu), k);
    }

    /// `Σ_i μ_i ∂(b_iᵀ)/∂q` of several axes at once, with `m = Σ_i μ_i e_iᴬ`: every term
    /// of [`force_tangent`] is linear in `μ ẽ`, and `w`, `r_B` are the same for all axes.
    #[inline(always)]
    pub fn force_tangent_along(f: &FramePair, m: &Vector3<f64>, k: &mut Blocks12) {
        let et = skew(m);
        let w = f.origin(1) - f.x[0];
        let wt = skew(&w);
        let rbt = skew(&f.arm[1]);
        // F_A = −μe, M_A = μ e × w, F_B = μe, M_B = μ r_B × e.
        add33(k, 0, 3, &et);
        add33(k, 6, 3, &(-et));
        add33(k, 3, 0, &(-et));
        add33(k, 3, 3, &(wt * et));
        add33(k, 3, 6, &et);
        add33(k, 3, 9, &(-(et * rbt)));
        add33(k, 9, 3, &(-(rbt * et)));
        add33(k, 9, 9, &(et * rbt));
    }

    /// Convective acceleration `ë·d + 2 ė·ḋ + e·d̈` at zero accelerations.
    pub fn convective(f: &FramePair, i: usize) -> f64 {
        let e: Vector3<f64> = f.axes[0].column(i).into();
        let (wa, wb) = (f.omega[0], f.omega[1]);
        let edot = wa.cross(&e);
        let eddot = wa.cross(&edot);
        let ddot = f.v[1] + wb.cross(&f.arm[1]) - f.v[0] - wa.cross(&f.arm[0]);
        let dddot = wb.cross(&wb.cross(&f.arm[1])) - wa.cross(&wa.cross(&f.arm[0]));
        eddot.dot(&f.d()) + 2.0 * edot.dot(&ddot) + e.dot(&dddot)
    }
}

/// Eq. (12b): the direction cosine `R_pq = e_pᴬ · e_qᴮ` between an axis of frame A and an
/// axis of frame B. A rotation row is a combination `Σ a_t(ν) R_{p_t q_t} + c(ν)` of these
/// (see [`AngleRow`]); θ_i = 0 about axis i is `R_jk = 0` with (i, j, k) cyclic.
pub mod direction_cosine {
    use super::*;

    #[inline]
    fn pair(f: &FramePair, p: usize, q: usize) -> (Vector3<f64>, Vector3<f64>) {
        (f.axes[0].column(p).into(), f.axes[1].column(q).into())
    }

    #[inline(always)]
    pub fn value(f: &FramePair, p: usize, q: usize) -> f64 {
        let (e, g) = pair(f, p, q);
        e.dot(&g)
    }

    /// `b = [0, nᵀ, 0, −nᵀ]` with `n = e_pᴬ × e_qᴮ`.
    #[inline(always)]
    pub fn jacobian(f: &FramePair, p: usize, q: usize) -> Row12 {
        let (e, g) = pair(f, p, q);
        let n = e.cross(&g);
        let mut b = Row12::zeros();
        put3(&mut b, 3, &n);
        put3(&mut b, 9, &(-n));
        b
    }

    /// `μ ∂(bᵀ)/∂q` (spatial): ∂n/∂φᴬ = g̃ ẽ, ∂n/∂φᴮ = −ẽ g̃.
    #[inline(always)]
    pub fn force_tangent(f: &FramePair, p: usize, q: usize, mu: f64, k: &mut Blocks12) {
        let (e, g) = pair(f, p, q);
        let (et, gt) = (skew(&e), skew(&g));
        let dn_a = gt * et * mu;
        let dn_b = -(et * gt) * mu;
        add33(k, 3, 3, &dn_a);
        add33(k, 3, 9, &dn_b);
        add33(k, 9, 3, &(-dn_a));
        add33(k, 9, 9, &(-dn_b));
    }

    /// `Ṙ_pq = b · (0, ωᴬ, 0, ωᴮ)`.
    pub fn rate(f: &FramePair, p: usize, q: usize) -> f64 {
        let (e, g) = pair(f, p, q);
        let n = e.cross(&g);
        n.dot(&f.omega[0]) - n.dot(&f.omega[1])
    }

    /// `ë·g + 2 ė·ġ + e·g̈` at zero accelerations.
    pub fn convective(f: &FramePair, p: usize, q: usize) -> f64 {
        let (e, g) = pair(f, p, q);
        let (wa, wb) = (f.omega[0], f.omega[1]);
        let edot = wa.cross(&e);
        let gdot = wb.cross(&g);
        wa.cross(&edot).dot(&g) + 2.0 * edot.dot(&gdot) + e.dot(&wb.cross(&gdot))
    }
}

/// A coefficient of a rotation row as a function of the row's joint coordinate ν.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Trig {
    Zero,
    /// s (constant).
    One(f64),
    /// s cos ν.
    Cos(f64),
    /// s sin ν.
    Sin(f64),
}

impl Trig {
    /// `[a(ν), a'(ν), a''(ν)]`.
    #[inline]
    pub fn eval(self, nu: f64) -> [f64; 3] {
        match self {
            Trig::Zero => [0.0; 3],
            Trig::One(s) => [s, 0.0, 0.0],
            Trig::Cos(s) => {
                let (sn, cs) = nu.sin_cos();
                [s * cs, -s * sn, -s * cs]
            }
            Trig::Sin(s) => {
                let (sn, cs) = nu.sin_cos();
                [s * sn, s * cs, -s * sn]
            }
        }
    }
}

impl Trig {
    /// `[(a(ν₀) + a(ν₁))/2, (a(ν₁) − a(ν₀))/(ν₁ − ν₀)]`: the mean and the difference
    /// quotient of the discrete product rule `Δ(a R) = Δa R̄ + ā ΔR` (the quotient's limit
    /// a'(ν̄) at ν₀ = ν₁, taken without cancellation as `−sin ν̄ · sinc(Δν/2)` and
    /// `cos ν̄ · sinc(Δν/2)`).
    #[inline]
    pub fn mean_and_secant(self, nu0: f64, nu1: f64) -> [f64; 2] {
        let (m, h) = (0.5 * (nu0 + nu1), 0.5 * (nu1 - nu0));
        let sinc = if h.abs() < 1e-4 {
            1.0 - h * h / 6.0
        } else {
            h.sin() / h
        };
        match self {
            Trig::Zero => [0.0; 2],
            Trig::One(s) => [s, 0.0],
            Trig::Cos(s) => {
                let (sn, cs) = m.sin_cos();
                [s * cs * h.cos(), -s * sn * sinc]
            }
            Trig::Sin(s) => {
                let (sn, cs) = m.sin_cos();
                [s * sn * h.cos(), s * cs * sinc]
            }
        }
    }
}

/// A rotation row (generalized eq. 12b):
/// `Φ = a₁(ν) R_{p₁q₁} + a₂(ν) R_{p₂q₂} + c(ν)`, with `R_pq = e_pᴬ · e_qᴮ`.
///
/// θ = 0 about axis i is `R_jk` ((i, j, k) cyclic). A free rotation θ about e_iᴬ with the
/// other two constrained is defined by `cos ν R_kj − sin ν R_jj = sin(θ − ν)`, which is
/// eq. 12b with its sign convention made explicit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AngleRow {
    pub terms: [(Trig, usize, usize); 2],
    pub constant: Trig,
}

impl AngleRow {
    /// θ_i = 0: `R_jk = 0`.
    pub fn locked(i: usize) -> Self {
        Self {
            terms: [
                (Trig::One(1.0), (i + 1) % 3, (i + 2) % 3),
                (Trig::Zero, 0, 0),
            ],
            constant: Trig::Zero,
        }
    }

    /// `R_pq = 0`.
    pub fn direction_cosine(p: usize, q: usize) -> Self {
        Self {
            terms: [(Trig::One(1.0), p, q), (Trig::Zero, 0, 0)],
            constant: Trig::Zero,
        }
    }

    /// Defines θ about e_iᴬ (the other two rotations constrained): `sin(θ − ν)`.
    pub fn about_a(i: usize) -> Self {
        let (j, k) = ((i + 1) % 3, (i + 2) % 3);
        Self {
            terms: [(Trig::Cos(1.0), k, j), (Trig::Sin(-1.0), j, j)],
            constant: Trig::Zero,
        }
    }

    /// A plain direction cosine `R_pq` (no coordinate): the fast path of the locked rows.
    #[inline]
    pub fn plain(&self) -> Option<(usize, usize)> {
        match (self.terms, self.constant) {
            ([(Trig::One(1.0), p, q), (Trig::Zero, _, _)], Trig::Zero) => Some((p, q)),
            _ => None,
        }
    }

    /// `Φ`, `∂Φ/∂ν`, `∂²Φ/∂ν²` at the frames `f` and coordinate ν.
    #[inline(always)]
    pub fn value(&self, f: &FramePair, nu: f64) -> [f64; 3] {
        if let Some((p, q)) = self.plain() {
            return [direction_cosine::value(f, p, q), 0.0, 0.0];
        }
        let mut out = self.constant.eval(nu);
        for &(a, p, q) in &self.terms {
            if a == Trig::Zero {
                continue;
            }
            let r = direction_cosine::value(f, p, q);
            let c = a.eval(nu);
            for m in 0..3 {
                out[m] += c[m] * r;
            }
        }
        out
    }

    /// `Σ a_t^{(d)}(ν) b_t`: the q-Jacobian row for d = 0, its ν-derivative for d = 1.
    #[inline(always)]
    pub fn jacobian(&self, f: &FramePair, nu: f64, d: usize) -> Row12 {
        if let Some((p, q)) = self.plain() {
            return if d == 0 {
                direction_cosine::jacobian(f, p, q)
            } else {
                Row12::zeros()
            };
        }
        let mut b = Row12::zeros();
        for &(a, p, q) in &self.terms {
            if a == Trig::Zero {
                continue;
            }
            b += direction_cosine::jacobian(f, p, q) * a.eval(nu)[d];
        }
        b
    }

    /// The discrete gradient over a step from frames `f0` to `f1` (`fm` their mean) and
    /// ν₀ to ν₁: the q-row `Σ ā_t b_t(fm)` and the ν-entry `Σ (Δa_t/Δν) R̄_t + Δc/Δν`,
    /// with R̄_t the mean of the two ends' `R_pq`. `R_pq` is bilinear in the frames' axes,
    /// which move by `ψ × ē` exactly over a Cayley step, so `b(fm)Δ = ΔR_pq` and the
    /// row times the increments is ΔΦ exactly.
    pub fn discrete_jacobian(
        &self,
        f0: &FramePair,
        f1: &FramePair,
        fm: &FramePair,
        nu0: f64,
        nu1: f64,
    ) -> (Row12, f64) {
        if let Some((p, q)) = self.plain() {
            return (direction_cosine::jacobian(fm, p, q), 0.0);
        }
        let mut b = Row12::zeros();
        let mut dnu = self.constant.mean_and_secant(nu0, nu1)[1];
        for &(a, p, q) in &self.terms {
            if a == Trig::Zero {
                continue;
            }
            let [mean, secant] = a.mean_and_secant(nu0, nu1);
            b += direction_cosine::jacobian(fm, p, q) * mean;
            let r = 0.5 * (direction_cosine::value(f0, p, q) + direction_cosine::value(f1, p, q));
            dnu += secant * r;
        }
        (b, dnu)
    }

    /// `μ Σ a_t(ν) ∂(b_tᵀ)/∂q` (spatial).
    #[inline(always)]
    pub fn force_tangent(&self, f: &FramePair, nu: f64, mu: f64, k: &mut Blocks12) {
        for &(a, p, q) in &self.terms {
            if a == Trig::Zero {
                continue;
            }
            direction_cosine::force_tangent(f, p, q, mu * a.eval(nu)[0], k);
        }
    }

    /// Part of Φ̈ without accelerations (q̈, ν̈), for coordinate rate `nu_dot`.
    pub fn convective(&self, f: &FramePair, nu: f64, nu_dot: f64) -> f64 {
        let mut out = self.constant.eval(nu)[2] * nu_dot * nu_dot;
        for &(a, p, q) in &self.terms {
            if a == Trig::Zero {
                continue;
            }
            let c = a.eval(nu);
            out += c[2] * nu_dot * nu_dot * direction_cosine::value(f, p, q)
                + 2.0 * c[1] * nu_dot * direction_cosine::rate(f, p, q)
                + c[0] * direction_cosine::convective(f, p, q);
        }
        out
    }
}
