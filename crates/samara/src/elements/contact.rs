//! Contact of a body with a ground plane (seed §3.3: a kinematic model and a contact-force
//! model), with a compliant normal force and LuGre friction whose bristle deflection is
//! the element's state.
//!
//! **Kinematics.** The ground is the plane through `p₀` with unit normal `n` (out of the
//! ground), moving in its own plane at the surface velocity `v_g` (a belt; `n·v_g = 0`).
//! The body touches it with a point `p = x + a` of its node: a material point (`a = R s`)
//! or the lowest point of a sphere of radius ρ centred at the node (`a = −ρ n`) or at a
//! material point (`a = R s − ρ n`, each end of a capsule). The
//! penetration is `δ = −n·(p − p₀)` and the velocity of the material point at `p`
//! relative to the surface is `u = v + ω × a − v_g` (ω = R Ω); `δ̇ = −n·u`, and the slip
//! velocity is `w = (t₁·u, t₂·u)` in a tangent basis (t₁, t₂) of the plane.
//!
//! **Normal force** (zero for δ ≤ 0, and never pulling: N = max(0, ·)):
//! - Hunt & Crossley (1975): `N = k δᵉ (1 + α δ̇)`; for a free mass the coefficient of
//!   restitution at impact speed v₀ follows exactly from the phase-plane integral
//!   `f(α v₀) = f(−α ε v₀)`, `f(u) = u − ln(1 + u)` (independent of mass, k and e) —
//!   `α` is given, or computed from ε at a reference speed by [`hunt_crossley_damping`];
//! - linear spring-damper: `N = k δ + c δ̇`.
//!
//! **Friction** — LuGre (Canudas de Wit, Olsson, Åström & Lischinsky 1995), in the
//! tangent plane: bristle deflection z ∈ R² (the two states), with
//!
//! `r_z = ż − w + σ₀ |w| z / g(|w|) = 0`,  `g(s) = μ_d + (μ_s − μ_d) exp(−(s/v_s)²)`,
//!
//! and the friction force `F_t = −N (σ₀ z + σ₁ ż + σ₂ w)` along (t₁, t₂) (σ₀ bristle
//! stiffness [1/m], σ₁ bristle damping [s/m], σ₂ viscous friction [s/m], all per unit
//! normal force). Sliding at steady speed gives |F_t| = N (g(s) + σ₂ s), i.e. μ_d N well
//! above the Stribeck speed v_s; under a tangential load below μ_s N the bristle holds
//! it elastically (stick, w → 0), so Newton follows stick and slip without switching.
//! The state rows are in m/s; the assembler scales them by `1/(∂ż/∂Δz)` in dynamics, so
//! their block of the iteration matrix is `1 + O(h)`. In statics (ż = 0, w = 0) the
//! bristle row vanishes identically: friction contacts are for dynamics only (checked
//! when the model is validated).
//!
//! The total force `F = N n + F_t` acts at `p`: node rows `−F` and `−Rᵀ(a × F)`.
//! **Height-field ground** ([`Contact::on_height_field`]): a terrain z(x, y)
//! ([`HeightField`]) instead of the plane. The sphere's centre (or the point) c is
//! measured from its foot point q = (u, v, z(u, v)), the nearest point of the surface
//! (Newton on the closest-point conditions, [`foot_point`]): with the normal there,
//! `n = (−∇z, 1)/√(1 + |∇z|²)`, the signed distance `d = (c − q)·n`, `δ = ρ − d` and the
//! contact point `p = c − ρ n`. Since ∂d/∂c = n at the foot point, the normal force N n
//! is the gradient of the contact potential (energy is conserved by the elastic part)
//! and passes through the centre; on a plane the foot point is found in one iteration and
//! everything is the plane's. Where no unique foot point exists (a centre farther from a
//! concave surface than its radius of curvature — far out of contact) the surface below
//! the centre is taken instead. The rest is as on the plane with the local n and the
//! tangent basis moving with it ([`crate::elements::terrain::tangents`]): the LuGre
//! bristle deflection is kept in that moving basis. The ground does not move. Tangents
//! are exact by forward-mode differentiation of the one kernel, the foot point's through
//! the implicit function theorem (one dual Newton step at the converged point), including
//! the turning of n through the Hessian. A converged state whose foot point is outside the
//! table is an error ([`Element::range_violation`]).
//!
//! **Rolling and twisting resistance** (optional, spheres only, [`super::rolling`]): the
//! moment `M(ω)` of the sphere's angular velocity against the (non-rotating) ground, with
//! `R_eff = ρ`, added to the node's moment rows; its power `M·ω` is dissipated.
//!
//! Energies: potential `∫N_el dδ` of the elastic part, dissipated power
//! `(N − N_el) δ̇ − F_t·w` (the LuGre bristle's small elastic store counts as dissipated),
//! external power `F·v_g` (the work of a moving surface).

use super::node_dual::{omega, rot, rot_t, var3};
use super::rolling::{RollingResistance, resisting_moment};
use super::terrain::{normal, surface, tangents};
use super::{Element, EvalContext, LocalTerms, Need, add_block};
use crate::core::ElementInput;
use crate::math::dual::{Dual, Scalar, V3, add, cross, cst3, dot, scale, sub};
use crate::math::height_field::{Height, HeightField};
use crate::math::skew;
use nalgebra::{Matrix3, SMatrix, Vector3};
use std::sync::Arc;

/// The contact geometry on the body.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ContactShape {
    /// A sphere of this radius centred at the node.
    Sphere { radius: f64 },
    /// A material point at this offset in the node frame.
    Point { offset: Vector3<f64> },
    /// A sphere of this radius centred at a material point (offset in the node frame):
    /// each end of a capsule (a capsule touches a plane at its lowest end, or along a
    /// line at both ends when it lies flat).
    OffsetSphere { radius: f64, offset: Vector3<f64> },
}

/// The normal-force law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum NormalLaw {
    /// `N = k δᵉ (1 + α δ̇)`.
    HuntCrossley {
        stiffness: f64,
        exponent: f64,
        damping_factor: f64,
    },
    /// `N = k δ + c δ̇`.
    Linear { stiffness: f64, damping: f64 },
}

/// LuGre friction parameters (per unit normal force).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Friction {
    /// μ_s.
    pub static_coefficient: f64,
    /// μ_d ≤ μ_s.
    pub dynamic_coefficient: f64,
    /// Stribeck speed v_s [m/s] > 0.
    pub stribeck_velocity: f64,
    /// σ₀ [1/m] > 0.
    pub bristle_stiffness: f64,
    /// σ₁ [s/m] ≥ 0.
    pub bristle_damping: f64,
    /// σ₂ [s/m] ≥ 0.
    pub viscous: f64,
}

impl Friction {
    /// `(g(s), g'(s))`, the Stribeck curve.
    fn stribeck(&self, s: f64) -> (f64, f64) {
        let (ms, md, vs) = (
            self.static_coefficient,
            self.dynamic_coefficient,
            self.stribeck_velocity,
        );
        let e = (-(s / vs).powi(2)).exp();
        (md + (ms - md) * e, -(ms - md) * e * 2.0 * s / (vs * vs))
    }

    /// `(ψ, ψ')` with `ψ(s) = σ₀ s / g(s)`.
    fn psi(&self, s: f64) -> (f64, f64) {
        let (g, dg) = self.stribeck(s);
        let s0 = self.bristle_stiffness;
        (s0 * s / g, s0 * (g - s * dg) / (g * g))
    }
}

/// The ground plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GroundPlane {
    pub point: Vector3<f64>,
    /// Unit normal, out of the ground.
    pub normal: Vector3<f64>,
    /// Surface velocity (tangential).
    pub velocity: Vector3<f64>,
}

/// `[N, ∂N/∂δ, ∂N/∂δ̇, N_el]` of a normal law (all zero out of contact or when the law
/// would pull).
pub fn normal_force(law: &NormalLaw, delta: f64, delta_dot: f64) -> [f64; 4] {
    if delta <= 0.0 {
        return [0.0; 4];
    }
    let (n, dn_dd, dn_dv, el) = match *law {
        NormalLaw::HuntCrossley {
            stiffness: k,
            exponent: e,
            damping_factor: a,
        } => {
            let de = delta.powf(e);
            (
                k * de * (1.0 + a * delta_dot),
                k * e * delta.powf(e - 1.0) * (1.0 + a * delta_dot),
                k * a * de,
                k * de,
            )
        }
        NormalLaw::Linear {
            stiffness: k,
            damping: c,
        } => (k * delta + c * delta_dot, k, c, k * delta),
    };
    if n <= 0.0 {
        [0.0, 0.0, 0.0, el]
    } else {
        [n, dn_dd, dn_dv, el]
    }
}

/// The event function of a normal law ([`Element::events`]): `g = min(δ, δ_f)` with
/// `δ_f` the force before the no-pull clip in units of length — `δ + (c/k) δ̇` (linear) or
/// `δ (1 + α δ̇)` (Hunt–Crossley) — so g > 0 exactly where the law pushes, and its zeros
/// are the law's kinks (contact closing, and opening where the damping would pull). The
/// rate is δ̇ where g = δ and unknown (NaN) on the other branch.
pub fn normal_event(law: &NormalLaw, delta: f64, delta_dot: f64) -> (f64, f64) {
    let force_side = match *law {
        NormalLaw::HuntCrossley {
            damping_factor: a, ..
        } => delta * (1.0 + a * delta_dot),
        NormalLaw::Linear {
            stiffness: k,
            damping: c,
        } => delta + c / k * delta_dot,
    };
    if delta <= force_side {
        (delta, delta_dot)
    } else {
        (force_side, f64::NAN)
    }
}

/// Elastic energy of the normal law at penetration δ: `k δ^(e+1)/(e+1)` or `½ k δ²`.
pub fn normal_potential(law: &NormalLaw, delta: f64) -> f64 {
    if delta <= 0.0 {
        return 0.0;
    }
    match *law {
        NormalLaw::HuntCrossley {
            stiffness: k,
            exponent: e,
            ..
        } => k * delta.powf(e + 1.0) / (e + 1.0),
        NormalLaw::Linear { stiffness: k, .. } => 0.5 * k * delta * delta,
    }
}

/// The Hunt–Crossley damping factor α that gives the coefficient of restitution
/// `restitution` ∈ (0, 1] at impact speed `speed` > 0: the root U = α v₀ in (0, 1/ε) of
/// `f(U) = f(−ε U)`, `f(u) = u − ln(1 + u)`, by bisection.
pub fn hunt_crossley_damping(restitution: f64, speed: f64) -> f64 {
    let e = restitution;
    if e >= 1.0 {
        return 0.0;
    }
    let f = |u: f64| u - u.ln_1p();
    let h = |u: f64| f(u) - f(-e * u);
    // h > 0 near 0 (h ≈ U²(1 − ε²)/2) and → −∞ as U → 1/ε (or grows slower than f(U)
    // for ε → 0: h(U) = f(U) − f(−εU) < 0 for U large when ε > 0).
    let mut lo = 1e-12;
    let mut hi = if e > 0.0 { 1.0 / e } else { 1e12 };
    // For ε = 0 the root is at infinity; the caller rejects ε ≤ 0.
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if h(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi) / speed
}

/// Kinematics of the contact point at one state.
struct Kinematics {
    /// Lever arm a (global).
    a: Vector3<f64>,
    delta: f64,
    delta_dot: f64,
    /// Slip velocity (t₁·u, t₂·u).
    w: [f64; 2],
    /// ∂p/∂q (3×6: x, θ).
    jp: SMatrix<f64, 3, 6>,
    /// ∂u/∂q and ∂u/∂v (3×6).
    uq: SMatrix<f64, 3, 6>,
    uv: SMatrix<f64, 3, 6>,
    r: Matrix3<f64>,
}

/// The Jacobian `J = I + ∇z ∇zᵀ + (z − c_z) H` of the closest-point conditions
/// `g = (u − c_x + (z − c_z) z_u, v − c_y + (z − c_z) z_v) = 0` at height gap `e = z − c_z`.
fn closest_point_jacobian(h: &Height, e: f64) -> [[f64; 2]; 2] {
    let (g, hs) = (h.gradient, h.hessian);
    [
        [1.0 + g[0] * g[0] + e * hs[0][0], g[0] * g[1] + e * hs[0][1]],
        [g[0] * g[1] + e * hs[1][0], 1.0 + g[1] * g[1] + e * hs[1][1]],
    ]
}

/// The foot point (u, v) of `c` on the surface z(x, y): the nearest surface point, where
/// `c − (u, v, z)` is along the normal, by Newton from (c_x, c_y) on the conditions of
/// [`closest_point_jacobian`] (one iteration on a plane; J positive definite while the
/// distance is below the radius of curvature). None when it does not converge in 30
/// iterations or J is not positive definite (no unique nearest point).
fn foot_point(hf: &HeightField, c: [f64; 3]) -> Option<(f64, f64)> {
    let (mut u, mut v) = (c[0], c[1]);
    for _ in 0..30 {
        let h = hf.eval_extended(u, v);
        let e = h.z - c[2];
        let g = [u - c[0] + e * h.gradient[0], v - c[1] + e * h.gradient[1]];
        let j = closest_point_jacobian(&h, e);
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        if !(det > 0.0 && j[0][0] > 0.0) {
            return None;
        }
        let du = (j[1][1] * g[0] - j[0][1] * g[1]) / det;
        let dv = (j[0][0] * g[1] - j[1][0] * g[0]) / det;
        u -= du;
        v -= dv;
        if du.abs() + dv.abs() <= 1e-13 * (1.0 + u.abs() + v.abs()) {
            return Some((u, v));
        }
    }
    None
}

/// A body–ground contact.
#[derive(Clone, Debug)]
pub struct Contact {
    name: String,
    node: [usize; 1],
    shape: ContactShape,
    plane: GroundPlane,
    tangents: [Vector3<f64>; 2],
    law: NormalLaw,
    friction: Option<Friction>,
    /// A height-field ground instead of the plane.
    terrain: Option<Arc<HeightField>>,
    /// Rolling and twisting resistance (spheres).
    rolling: Option<RollingResistance>,
}

/// Local unknowns of the height-field kernel: 6 node unknowns and 2 bristle states;
/// their rates are directions `NL + k`.
const NL: usize = 8;

/// What the height-field kernel gives.
struct TerrainTerms<S> {
    /// The force F on the body (global) and its moment Rᵀ(a × F) (node frame).
    rows: [V3<S>; 2],
    /// The bristle rows (m/s).
    state_rows: [S; 2],
    delta: f64,
    delta_dot: f64,
    /// The normal law's `[N, ∂N/∂δ, ∂N/∂δ̇, N_el]`.
    nf: [f64; 4],
    friction: Vector3<f64>,
    /// Slip velocity (t₁·u, t₂·u) and its vector t₁w₁ + t₂w₂.
    w: [f64; 2],
    slip: Vector3<f64>,
    /// The foot point of the centre on the terrain.
    foot: Vector3<f64>,
    /// The rolling/twisting moment (global) and the angular velocity.
    rolling: Vector3<f64>,
    omega: Vector3<f64>,
}

impl Contact {
    /// `plane.normal` is normalized here, and `plane.velocity` projected on the plane.
    pub fn new(
        name: impl Into<String>,
        node: usize,
        shape: ContactShape,
        mut plane: GroundPlane,
        law: NormalLaw,
        friction: Option<Friction>,
    ) -> Self {
        let n = plane.normal.normalize();
        plane.normal = n;
        plane.velocity -= n * n.dot(&plane.velocity);
        // t₁: the global axis least aligned with n, made orthogonal; t₂ = n × t₁.
        let k = n.iamin();
        let mut e = Vector3::zeros();
        e[k] = 1.0;
        let t1 = (e - n * n.dot(&e)).normalize();
        let t2 = n.cross(&t1);
        Self {
            name: name.into(),
            node: [node],
            shape,
            plane,
            tangents: [t1, t2],
            law,
            friction,
            terrain: None,
            rolling: None,
        }
    }

    /// The contact with rolling and twisting resistance (None: without; a sphere's only,
    /// a point has no radius and carries none).
    pub fn with_rolling(mut self, rolling: Option<RollingResistance>) -> Self {
        self.rolling = rolling;
        self
    }

    /// The sphere's radius (None for a point).
    fn sphere_radius(&self) -> Option<f64> {
        match self.shape {
            ContactShape::Sphere { radius } | ContactShape::OffsetSphere { radius, .. } => {
                Some(radius)
            }
            ContactShape::Point { .. } => None,
        }
    }

    /// The penetration δ = −n·(p − p₀) into the plane.
    fn plane_penetration(&self, x: &ElementInput) -> f64 {
        let nd = &x.nodes[self.node[0]];
        let n = self.plane.normal;
        let p = match self.shape {
            ContactShape::Sphere { radius } => nd.x - n * radius,
            ContactShape::Point { offset } => nd.x + nd.r() * offset,
            ContactShape::OffsetSphere { radius, offset } => nd.x + nd.r() * offset - n * radius,
        };
        -n.dot(&(p - self.plane.point))
    }

    /// The rolling/twisting moment (global) on a sphere against the plane, over any
    /// scalar: directions 0..6 the node's (δx, δθ), 6..12 its (v, Ω). Zero without
    /// resistance or for a point.
    fn plane_rolling<S: Scalar>(&self, x: &ElementInput) -> V3<S> {
        let zero = [S::cst(0.0); 3];
        let (Some(res), Some(rho)) = (&self.rolling, self.sphere_radius()) else {
            return zero;
        };
        let nd = &x.nodes[self.node[0]];
        let r = nd.r();
        let xs = var3::<S>(&nd.x, 0);
        let c = match self.shape {
            ContactShape::OffsetSphere { offset, .. } => add(&xs, &rot::<S>(0, r, &offset)),
            _ => xs,
        };
        let n = cst3::<S>(&self.plane.normal);
        let delta = -dot(&n, &sub(&c, &cst3(&self.plane.point))) + rho;
        let om = omega::<S>(0, r, &nd.w, 6);
        let a = sub(&sub(&c, &xs), &scale(&n, S::cst(rho)));
        let u = add(&var3::<S>(&nd.v, 6), &cross(&om, &a));
        let delta_dot = -dot(&n, &u);
        let nf = normal_force(&self.law, delta.re(), delta_dot.re());
        let nn = (delta - delta.re()) * nf[1] + (delta_dot - delta_dot.re()) * nf[2] + nf[0];
        resisting_moment(res, &n, &om, nn, delta, rho)
    }

    /// A contact with the height-field ground `terrain` (fixed).
    pub fn on_height_field(
        name: impl Into<String>,
        node: usize,
        shape: ContactShape,
        terrain: Arc<HeightField>,
        law: NormalLaw,
        friction: Option<Friction>,
    ) -> Self {
        let plane = GroundPlane {
            point: Vector3::zeros(),
            normal: Vector3::z(),
            velocity: Vector3::zeros(),
        };
        let mut c = Self::new(name, node, shape, plane, law, friction);
        c.terrain = Some(terrain);
        c
    }

    /// The contact on the height field: one kernel for the value (`f64`) and the exact
    /// tangents (`Dual`).
    fn terrain_terms<S: Scalar>(&self, hf: &HeightField, x: &ElementInput) -> TerrainTerms<S> {
        let nd = &x.nodes[self.node[0]];
        let r = nd.r();
        let xs = var3::<S>(&nd.x, 0);
        let v = var3::<S>(&nd.v, NL);
        let om = omega::<S>(0, r, &nd.w, NL);
        let (rho, offset) = match self.shape {
            ContactShape::Sphere { radius } => (radius, None),
            ContactShape::Point { offset } => (0.0, Some(offset)),
            ContactShape::OffsetSphere { radius, offset } => (radius, Some(offset)),
        };
        let c = match offset {
            Some(o) => add(&xs, &rot::<S>(0, r, &o)),
            None => xs,
        };
        let (q, n) = match foot_point(hf, [c[0].re(), c[1].re(), c[2].re()]) {
            Some((u0, v0)) => {
                // One Newton step on dual numbers from the converged foot point: its value
                // stays, its derivatives are the implicit function's, −J⁻¹ ∂g/∂c.
                let h = hf.eval_extended(u0, v0);
                let (zu, zv) = (h.gradient[0], h.gradient[1]);
                let e = -c[2] + h.z;
                let g = [-c[0] + u0 + e * zu, -c[1] + v0 + e * zv];
                let j = closest_point_jacobian(&h, e.re());
                let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
                let u = -((g[0] * j[1][1] - g[1] * j[0][1]) / det) + u0;
                let v = -((g[1] * j[0][0] - g[0] * j[1][0]) / det) + v0;
                let (z, grad) = surface(hf, u, v);
                ([u, v, z], normal(&grad).0)
            }
            None => {
                // No foot point (far from a strongly curved surface): below the centre.
                let (z, grad) = surface(hf, c[0], c[1]);
                ([c[0], c[1], z], normal(&grad).0)
            }
        };
        let delta = -dot(&sub(&c, &q), &n) + rho;
        let a = sub(&sub(&c, &xs), &scale(&n, S::cst(rho)));
        let u = add(&v, &cross(&om, &a));
        let delta_dot = -dot(&n, &u);
        let t = tangents(&n);
        let w = [dot(&t[0], &u), dot(&t[1], &u)];
        let nf = normal_force(&self.law, delta.re(), delta_dot.re());
        let nn = (delta - delta.re()) * nf[1] + (delta_dot - delta_dot.re()) * nf[2] + nf[0];
        let zero = S::cst(0.0);
        let (phi, state_rows) = match &self.friction {
            None => ([zero; 2], [zero; 2]),
            Some(f) => {
                let z: [S; 2] = std::array::from_fn(|j| {
                    let mut zj = S::cst(x.states[j].z);
                    zj.add_deriv(6 + j, 1.0);
                    zj
                });
                let zd: [S; 2] = std::array::from_fn(|j| {
                    let mut zj = S::cst(x.states[j].zd);
                    zj.add_deriv(NL + 6 + j, 1.0);
                    zj
                });
                let phi: [S; 2] = std::array::from_fn(|i| {
                    z[i] * f.bristle_stiffness + zd[i] * f.bristle_damping + w[i] * f.viscous
                });
                // ψ(|w|) = σ₀ |w|/g(|w|); |w| has no derivative at 0, where ψ' z = 0.
                let s2 = w[0] * w[0] + w[1] * w[1];
                let s = if s2.re() > 0.0 { s2.sqrt() } else { zero };
                let (ms, md, vs) = (
                    f.static_coefficient,
                    f.dynamic_coefficient,
                    f.stribeck_velocity,
                );
                let q = s / vs;
                let gs = (-(q * q)).exp() * (ms - md) + md;
                let psi = s * f.bristle_stiffness / gs;
                (phi, std::array::from_fn(|i| zd[i] - w[i] + psi * z[i]))
            }
        };
        let ft = scale(&add(&scale(&t[0], phi[0]), &scale(&t[1], phi[1])), -nn);
        let force = add(&scale(&n, nn), &ft);
        let rolling = match (&self.rolling, self.shape) {
            (Some(res), ContactShape::Sphere { .. } | ContactShape::OffsetSphere { .. }) => {
                resisting_moment(res, &n, &om, nn, delta, rho)
            }
            _ => [zero; 3],
        };
        let moment = rot_t(0, r, &add(&cross(&a, &force), &rolling));
        let re3 = |y: &V3<S>| Vector3::new(y[0].re(), y[1].re(), y[2].re());
        let wv = [w[0].re(), w[1].re()];
        TerrainTerms {
            rows: [force, moment],
            state_rows,
            delta: delta.re(),
            delta_dot: delta_dot.re(),
            nf,
            friction: re3(&ft),
            w: wv,
            slip: re3(&t[0]) * wv[0] + re3(&t[1]) * wv[1],
            foot: re3(&q),
            rolling: re3(&rolling),
            omega: re3(&om),
        }
    }

    fn kinematics(&self, x: &ElementInput) -> Kinematics {
        let nd = &x.nodes[self.node[0]];
        let r = *nd.r();
        let n = self.plane.normal;
        let omega = r * nd.w;
        let (a, a_theta) = match self.shape {
            ContactShape::Sphere { radius } => (-n * radius, Matrix3::zeros()),
            ContactShape::Point { offset } => (r * offset, -(r * skew(&offset))),
            ContactShape::OffsetSphere { radius, offset } => {
                (r * offset - n * radius, -(r * skew(&offset)))
            }
        };
        let p = nd.x + a;
        let u = nd.v + omega.cross(&a) - self.plane.velocity;
        let at = skew(&a);
        let mut jp = SMatrix::<f64, 3, 6>::zeros();
        jp.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&Matrix3::identity());
        jp.fixed_view_mut::<3, 3>(0, 3).copy_from(&a_theta);
        // u = v + (RΩ) × a: ∂/∂θ = ã R Ω̃ + ω̃ ∂a/∂θ; ∂/∂v = I; ∂/∂Ω = −ã R.
        let mut uq = SMatrix::<f64, 3, 6>::zeros();
        uq.fixed_view_mut::<3, 3>(0, 3)
            .copy_from(&(at * r * skew(&nd.w) + skew(&omega) * a_theta));
        let mut uv = SMatrix::<f64, 3, 6>::zeros();
        uv.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&Matrix3::identity());
        uv.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-(at * r)));
        Kinematics {
            a,
            delta: -n.dot(&(p - self.plane.point)),
            delta_dot: -n.dot(&u),
            w: [self.tangents[0].dot(&u), self.tangents[1].dot(&u)],
            jp,
            uq,
            uv,
            r,
        }
    }

    /// Friction coefficients φ = σ₀ z + σ₁ ż + σ₂ w (zero without friction).
    fn phi(&self, x: &ElementInput, k: &Kinematics) -> [f64; 2] {
        match &self.friction {
            None => [0.0; 2],
            Some(f) => std::array::from_fn(|i| {
                let z = x.states[i];
                f.bristle_stiffness * z.z + f.bristle_damping * z.zd + f.viscous * k.w[i]
            }),
        }
    }

    /// Normal force, friction force (global) and the normal law's values.
    fn forces(&self, x: &ElementInput, k: &Kinematics) -> ([f64; 4], Vector3<f64>) {
        let nf = normal_force(&self.law, k.delta, k.delta_dot);
        let phi = self.phi(x, k);
        let ft = -(self.tangents[0] * phi[0] + self.tangents[1] * phi[1]) * nf[0];
        (nf, ft)
    }
}

impl Element for Contact {
    fn name(&self) -> &str {
        &self.name
    }

    fn nodes(&self) -> &[usize] {
        &self.node
    }

    fn n_states(&self) -> usize {
        if self.friction.is_some() { 2 } else { 0 }
    }

    fn state_names(&self) -> Vec<String> {
        if self.friction.is_some() {
            vec!["bristle_1".into(), "bristle_2".into()]
        } else {
            Vec::new()
        }
    }

    fn evaluate(&self, _ctx: &EvalContext, x: &ElementInput, need: Need, out: &mut LocalTerms) {
        if let Some(hf) = &self.terrain {
            let n = 6 + self.n_states();
            if need == Need::Residual {
                let t = self.terrain_terms::<f64>(hf, x);
                for (b, row) in t.rows.iter().enumerate() {
                    for (k, y) in row.iter().enumerate() {
                        out.r[3 * b + k] -= y;
                    }
                }
                for j in 6..n {
                    out.r[j] += t.state_rows[j - 6];
                }
                return;
            }
            let t = self.terrain_terms::<Dual<{ 2 * NL }>>(hf, x);
            let mut put = |ri: usize, y: &Dual<{ 2 * NL }>, sign: f64| {
                out.r[ri] += sign * y.v;
                for j in 0..n {
                    out.k[(ri, j)] += sign * y.d[j];
                    out.c[(ri, j)] += sign * y.d[NL + j];
                }
            };
            for (b, row) in t.rows.iter().enumerate() {
                for (k, y) in row.iter().enumerate() {
                    put(3 * b + k, y, -1.0);
                }
            }
            for j in 6..n {
                put(j, &t.state_rows[j - 6], 1.0);
            }
            return;
        }
        if self.friction.is_none() && self.plane_penetration(x) < 0.0 {
            // Apart, a contact without bristle states gives nothing, in a neighbourhood
            // (exact tangents 0): the walls of a granular box, most of the time.
            return;
        }
        if self.rolling.is_some() {
            // The rolling/twisting moment: node moment rows −Rᵀ M.
            let r = x.nodes[self.node[0]].r();
            if need == Need::Residual {
                let m = rot_t(0, r, &self.plane_rolling::<f64>(x));
                for (i, mi) in m.iter().enumerate() {
                    out.r[3 + i] -= mi;
                }
            } else {
                let m = rot_t(0, r, &self.plane_rolling::<Dual<12>>(x));
                for (i, mi) in m.iter().enumerate() {
                    out.r[3 + i] -= mi.v;
                    for j in 0..6 {
                        out.k[(3 + i, j)] -= mi.d[j];
                        out.c[(3 + i, j)] -= mi.d[6 + j];
                    }
                }
            }
        }
        let kin = self.kinematics(x);
        let n = self.plane.normal;
        let (nf, ft) = self.forces(x, &kin);
        let f = n * nf[0] + ft;
        let rt = kin.r.transpose();
        let moment = rt * kin.a.cross(&f);
        for i in 0..3 {
            out.r[i] -= f[i];
            out.r[3 + i] -= moment[i];
        }
        let fr = self.friction;
        if let Some(fr) = &fr {
            let s = (kin.w[0].powi(2) + kin.w[1].powi(2)).sqrt();
            let (psi, _) = fr.psi(s);
            for i in 0..2 {
                let z = x.states[i];
                out.r[6 + i] += z.zd - kin.w[i] + psi * z.z;
            }
        }
        if need == Need::Residual {
            return;
        }
        // Rows of F → residual: −[I; Rᵀ ã].
        let gm = rt * skew(&kin.a);
        let phi = self.phi(x, &kin);
        let dir = n - self.tangents[0] * phi[0] - self.tangents[1] * phi[1];
        // ∂δ/∂q, ∂δ̇/∂q, ∂δ̇/∂v (1×6).
        let nt = n.transpose();
        let dd_q = -(nt * kin.jp);
        let ddot_q = -(nt * kin.uq);
        let ddot_v = -(nt * kin.uv);
        let dn_q = dd_q * nf[1] + ddot_q * nf[2];
        let dn_v = ddot_v * nf[2];
        let sigma2 = fr.map_or(0.0, |f| f.viscous);
        let t = &self.tangents;
        // ∂w_i/∂q, ∂w_i/∂v.
        let wq: [SMatrix<f64, 1, 6>; 2] = std::array::from_fn(|i| t[i].transpose() * kin.uq);
        let wv: [SMatrix<f64, 1, 6>; 2] = std::array::from_fn(|i| t[i].transpose() * kin.uv);
        let df_q = dir * dn_q - (t[0] * wq[0] + t[1] * wq[1]) * (nf[0] * sigma2);
        let df_v = dir * dn_v - (t[0] * wv[0] + t[1] * wv[1]) * (nf[0] * sigma2);
        for (mat, df) in [(&mut out.k, &df_q), (&mut out.c, &df_v)] {
            let top = -df;
            let bottom = -(gm * df);
            for j in 0..6 {
                for i in 0..3 {
                    mat[(i, j)] += top[(i, j)];
                    mat[(3 + i, j)] += bottom[(i, j)];
                }
            }
        }
        // Rotation of the lever arm / of Rᵀ: ∂(−Rᵀ(a × F))/∂θ at fixed F.
        let geo = match self.shape {
            ContactShape::Point { offset } => -(skew(&offset) * skew(&(rt * f))),
            ContactShape::Sphere { .. } => -skew(&moment),
            ContactShape::OffsetSphere { radius, offset } => {
                -(skew(&offset) * skew(&(rt * f))) - skew(&(rt * (-n * radius).cross(&f)))
            }
        };
        add_block(&mut out.k, 3, 3, &geo);
        let Some(fr) = fr else { return };
        // Columns of the states: ∂F/∂z_j = −N σ₀ t_j, ∂F/∂ż_j = −N σ₁ t_j.
        for j in 0..2 {
            for (mat, coef) in [
                (&mut out.k, fr.bristle_stiffness),
                (&mut out.c, fr.bristle_damping),
            ] {
                let df = -t[j] * (nf[0] * coef);
                let dm = -(gm * df);
                for i in 0..3 {
                    mat[(i, 6 + j)] -= df[i];
                    mat[(3 + i, 6 + j)] += dm[i];
                }
            }
        }
        // State rows: ż_i − w_i + ψ(|w|) z_i.
        let s = (kin.w[0].powi(2) + kin.w[1].powi(2)).sqrt();
        let (psi, dpsi) = fr.psi(s);
        for i in 0..2 {
            let zi = x.states[i].z;
            out.k[(6 + i, 6 + i)] += psi;
            out.c[(6 + i, 6 + i)] += 1.0;
            // ∂r_zi/∂w_m = −δ_im + z_i ψ' w_m / s.
            for m in 0..2 {
                let mut coef = if s > 0.0 {
                    zi * dpsi * kin.w[m] / s
                } else {
                    0.0
                };
                if m == i {
                    coef -= 1.0;
                }
                for j in 0..6 {
                    out.k[(6 + i, j)] += coef * wq[m][j];
                    out.c[(6 + i, j)] += coef * wv[m][j];
                }
            }
        }
    }

    fn potential_energy(&self, _ctx: &EvalContext, x: &ElementInput) -> f64 {
        if let Some(hf) = &self.terrain {
            return normal_potential(&self.law, self.terrain_terms::<f64>(hf, x).delta);
        }
        normal_potential(&self.law, self.kinematics(x).delta)
    }

    fn dissipated_power(&self, x: &ElementInput) -> f64 {
        if let Some(hf) = &self.terrain {
            let t = self.terrain_terms::<f64>(hf, x);
            return (t.nf[0] - t.nf[3]) * t.delta_dot
                - t.friction.dot(&t.slip)
                - t.rolling.dot(&t.omega);
        }
        let kin = self.kinematics(x);
        let (nf, ft) = self.forces(x, &kin);
        let ut = self.tangents[0] * kin.w[0] + self.tangents[1] * kin.w[1];
        let rolling = if self.rolling.is_some() {
            let nd = &x.nodes[self.node[0]];
            -Vector3::from(self.plane_rolling::<f64>(x)).dot(&(nd.r() * nd.w))
        } else {
            0.0
        };
        (nf[0] - nf[3]) * kin.delta_dot - ft.dot(&ut) + rolling
    }

    fn external_power(&self, _ctx: &EvalContext, x: &ElementInput) -> f64 {
        if self.terrain.is_some() {
            return 0.0;
        }
        let kin = self.kinematics(x);
        let (nf, ft) = self.forces(x, &kin);
        (self.plane.normal * nf[0] + ft).dot(&self.plane.velocity)
    }

    fn n_events(&self) -> usize {
        1
    }

    fn events(&self, x: &ElementInput, out: &mut [(f64, f64)]) {
        let kin = self.kinematics(x);
        out[0] = normal_event(&self.law, kin.delta, kin.delta_dot);
    }

    fn output_names(&self) -> Vec<(String, &'static str)> {
        vec![
            ("normal_force".into(), "N"),
            ("friction_force".into(), "N"),
            ("penetration".into(), "m"),
            ("slip_velocity".into(), "m/s"),
            ("stick".into(), "1"),
        ]
    }

    fn outputs(&self, _ctx: &EvalContext, x: &ElementInput, out: &mut [f64]) {
        let (nf, ft, delta, w) = match &self.terrain {
            Some(hf) => {
                let t = self.terrain_terms::<f64>(hf, x);
                (t.nf, t.friction, t.delta, t.w)
            }
            None => {
                let kin = self.kinematics(x);
                let (nf, ft) = self.forces(x, &kin);
                (nf, ft, kin.delta, kin.w)
            }
        };
        let slip = (w[0].powi(2) + w[1].powi(2)).sqrt();
        out[0] = nf[0];
        out[1] = ft.norm();
        out[2] = delta;
        out[3] = slip;
        // Sticking: in contact and slipping slower than a tenth of the Stribeck speed.
        let stick = self
            .friction
            .is_some_and(|f| nf[0] > 0.0 && slip < 0.1 * f.stribeck_velocity);
        out[4] = if stick { 1.0 } else { 0.0 };
    }

    fn range_violation(&self, x: &ElementInput) -> Option<String> {
        let hf = self.terrain.as_ref()?;
        let c = self.terrain_terms::<f64>(hf, x).foot;
        (!hf.contains(c.x, c.y)).then(|| {
            let ([x0, x1], [y0, y1]) = hf.bounds();
            format!(
                "its foot point on the terrain, ({:.6}, {:.6}), left the height field's table x ∈ [{x0}, {x1}], y ∈ [{y0}, {y1}]",
                c.x, c.y
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The restitution relation is symmetric in the way it is solved: the α found for ε at
    /// v₀ satisfies f(α v₀) = f(−α ε v₀) to round-off, and the small-damping limit is the
    /// classical ε ≈ 1 − (2/3) α v₀ (Hunt & Crossley 1975).
    #[test]
    fn damping_from_restitution() {
        let f = |u: f64| u - u.ln_1p();
        for (e, v) in [(0.9, 1.0), (0.5, 3.0), (0.2, 0.7)] {
            let a = hunt_crossley_damping(e, v);
            let u = a * v;
            assert!((f(u) - f(-e * u)).abs() < 1e-12 * f(u), "{e} {v}");
        }
        let e = 0.999;
        let a = hunt_crossley_damping(e, 2.0);
        assert!(((1.0 - e) - 2.0 / 3.0 * a * 2.0).abs() < 1e-2 * (1.0 - e));
    }
}
