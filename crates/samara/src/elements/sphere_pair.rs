//! Contact between two spheres centred at two nodes (body–body), with the normal laws of
//! [`super::contact`] and, optionally, friction.
//!
//! **Normal.** With `d = x_B − x_A`, the unit normal `n = d/|d|` (from A to B), the
//! penetration `δ = ρ_A + ρ_B − |d|` and its rate `δ̇ = −n·(v_B − v_A)`, the normal force
//! N(δ, δ̇) (Hunt–Crossley or linear, zero out of contact and never pulling) pushes B
//! along +n and A along −n through the centres. Hunt–Crossley's restitution relation
//! holds for the relative motion with the reduced mass.
//!
//! **Slip.** The contact point is the middle of the overlap,
//! `p = x_A + a_A = x_B + a_B` with the lever arms `a_A = (ρ_A − δ/2) n` and
//! `a_B = −(ρ_B − δ/2) n`; the velocity of B's material point at p relative to A's is
//! `u = v_B + ω_B × a_B − v_A − ω_A × a_A` (ω = R Ω) and the slip is its part in the
//! tangent plane, `w = (I − n nᵀ) u`.
//!
//! **Friction** (force F_t on B, −F_t on A, both at p: moments `a_B × F_t` on B and
//! `a_A × (−F_t)` on A, so friction spins both bodies; one point for both, so the pair's
//! forces have no net moment and the pair conserves angular momentum — with the two
//! surface points `x_A + ρ_A n`, `x_B − ρ_B n` instead it would gain `−δ n × F_t`):
//! - LuGre ([`PairFriction::LuGre`], as the ground contact's, Canudas de Wit et al. 1995)
//!   with the bristle deflection z ∈ R³ in global components (three states; only its
//!   tangential part `P z` acts, P = I − n nᵀ, so no tangent basis is needed and no
//!   direction of n is singular): `r_z = ż − w + σ₀ |w| z / g(|w|) = 0`,
//!   `F_t = −N (σ₀ P z + σ₁ P ż + σ₂ w)`. Sticks below μ_s N, slides at μ_d N.
//!
//!   In a granular set ([`super::GranularSet`]) the pairs come and go, so the bristle is a
//!   history variable of the pair instead of an unknown of the system (as the tangential
//!   spring of a DEM contact): its rate equation is discretized by backward Euler over the
//!   step h and condensed, `ż = (w − ψ z₀)/(1 + h ψ)`, `z = z₀ + h ż` (z₀ the deflection
//!   at the start of the step; linear in z, so this is exact), which makes F_t a function
//!   of the node unknowns alone with exact tangents through w and ψ(|w|). Backward Euler
//!   gives `ż = w − ψ z` at the end of the step, so the force at an accepted state follows
//!   from its z with h = 0 (energies, restarts), and stick (w → 0: ż → 0, z held) and steady
//!   slip (z → g(s) w/(σ₀ s)) are those of the ODE. The integrator keeps z per pair
//!   (`State::pair_bristles`, keyed by the pair), projects it on the tangent plane after
//!   each step and drops it when the pair separates ([`SpherePair::bristle_end`]).
//! - regularized Coulomb–Stribeck ([`PairFriction::Regularized`], no states):
//!   `F_t = −N (g(|w|) w / √(|w|² + v_r²) + σ₂ w)`, `g(s) = μ_d + (μ_s − μ_d) e^(−(s/v_s)²)`:
//!   |F_t| → g N when |w| ≫ v_r; below v_r it is a viscous law (creep at speed
//!   ≈ v_r F_t/(μ N) under a load below μ_s N, no true stick).
//!
//! **Rolling and twisting resistance** (optional, [`super::rolling`]): the couple
//! `M(ω_B − ω_A)` on B and `−M` on A, with `R_eff = ρ_A ρ_B/(ρ_A + ρ_B)`.
//!
//! Tangents: exact, by forward-mode differentiation of the one kernel
//! ([`crate::math::dual`]): directions 0..12 the nodes' (δx, δθ), 12..15 the states, then
//! the same for the rates.

use super::contact::{Friction, NormalLaw, normal_event, normal_potential};
use super::rolling::{RollingResistance, resisting_moment};
use super::{Element, EvalContext, LocalTerms, Need};
use crate::core::{ElementInput, ElementState, NodeState};
use crate::math::dual::{Dual, Scalar, V3, add, cross, cst3, dot, scale, sub};
use nalgebra::{Matrix3, Vector3};

/// Friction of a sphere pair.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PairFriction {
    /// LuGre with bristle states (three, global components).
    LuGre(Friction),
    /// Regularized Coulomb–Stribeck without states; `regularization_velocity` v_r > 0.
    Regularized {
        friction: Friction,
        regularization_velocity: f64,
    },
}

/// Derivative directions: node unknowns and states at 0..NV (K), their rates at NV.. (C).
const NV: usize = 15;
const ND: usize = 2 * NV;

/// What the kernel gives.
struct PairResult<S> {
    /// Node rows: force on A, moment on A (node frame), force on B, moment on B; the
    /// residual is minus these.
    rows: [V3<S>; 4],
    /// Bristle state rows (LuGre only).
    state_rows: [S; 3],
    normal: f64,
    elastic: f64,
    delta: f64,
    delta_dot: f64,
    friction: Vector3<f64>,
    slip: Vector3<f64>,
    /// The bristle deflection z (LuGre).
    bristle: Vector3<f64>,
    /// The rolling/twisting moment on B and the relative angular velocity ω_B − ω_A.
    rolling: Vector3<f64>,
    omega_rel: Vector3<f64>,
}

/// The condensed LuGre bristle of a pair in a granular set: its deflection at the start
/// of the step and the step (0: the rate equation at the state).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Bristle {
    pub z0: Vector3<f64>,
    pub step: f64,
}

/// A sphere–sphere contact.
#[derive(Clone, Debug)]
pub struct SpherePair {
    name: String,
    nodes: [usize; 2],
    radii: [f64; 2],
    law: NormalLaw,
    friction: Option<PairFriction>,
    /// LuGre as a history variable instead of states (pairs of a granular set).
    bristle: Option<Bristle>,
    /// Rolling and twisting resistance.
    rolling: Option<RollingResistance>,
}

/// `[N, N_el]` of a normal law over any scalar (zero out of contact and when it would
/// pull).
fn normal_law<S: Scalar>(law: &NormalLaw, delta: S, delta_dot: S) -> (S, f64) {
    let zero = S::cst(0.0);
    if delta.re() <= 0.0 {
        return (zero, 0.0);
    }
    let (n, el) = match *law {
        NormalLaw::HuntCrossley {
            stiffness: k,
            exponent: e,
            damping_factor: a,
        } => {
            let de = delta.powf(e) * k;
            (de * (delta_dot * a + 1.0), de.re())
        }
        NormalLaw::Linear {
            stiffness: k,
            damping: c,
        } => (delta * k + delta_dot * c, k * delta.re()),
    };
    if n.re() <= 0.0 { (zero, el) } else { (n, el) }
}

/// A node-vector variable: value `v`, derivative 1 in directions `dir + k`.
fn var3<S: Scalar>(v: &Vector3<f64>, dir: usize) -> V3<S> {
    let mut out = cst3::<S>(v);
    for (k, o) in out.iter_mut().enumerate() {
        o.add_deriv(dir + k, 1.0);
    }
    out
}

/// `ω = R Ω` of local node i: `R (e_j × Ω)` along δθ_j, `R e_j` along Ω_j.
fn omega<S: Scalar>(i: usize, n: &NodeState) -> V3<S> {
    let r = n.r();
    let mut out = cst3::<S>(&(r * n.w));
    if S::DIRECTIONS > 0 {
        for j in 0..3 {
            let col = r * Vector3::ith(j, 1.0).cross(&n.w);
            for (k, o) in out.iter_mut().enumerate() {
                o.add_deriv(6 * i + 3 + j, col[k]);
                o.add_deriv(NV + 6 * i + 3 + j, r[(k, j)]);
            }
        }
    }
    out
}

/// `Rᵀ y` for local node i: `Rᵀ dy − δθ × Rᵀ y`.
fn rot_t<S: Scalar>(i: usize, r: &Matrix3<f64>, y: &V3<S>) -> V3<S> {
    let mut z: V3<S> =
        std::array::from_fn(|k| y[0] * r[(0, k)] + y[1] * r[(1, k)] + y[2] * r[(2, k)]);
    if S::DIRECTIONS > 0 {
        let zv = Vector3::new(z[0].re(), z[1].re(), z[2].re());
        for j in 0..3 {
            let c = Vector3::ith(j, 1.0).cross(&zv);
            for (k, zk) in z.iter_mut().enumerate() {
                zk.add_deriv(6 * i + 3 + j, -c[k]);
            }
        }
    }
    z
}

fn re3<S: Scalar>(y: &V3<S>) -> Vector3<f64> {
    Vector3::new(y[0].re(), y[1].re(), y[2].re())
}

impl SpherePair {
    pub fn new(
        name: impl Into<String>,
        nodes: [usize; 2],
        radii: [f64; 2],
        law: NormalLaw,
    ) -> Self {
        Self {
            name: name.into(),
            nodes,
            radii,
            law,
            friction: None,
            bristle: None,
            rolling: None,
        }
    }

    /// The pair with rolling and twisting resistance (None: without).
    pub fn with_rolling(mut self, rolling: Option<RollingResistance>) -> Self {
        self.rolling = rolling;
        self
    }

    /// The pair with its LuGre bristle condensed into a history variable (no states):
    /// deflection `z0` at the start of a step of size `step` (0: at the state).
    pub fn with_bristle(mut self, z0: Vector3<f64>, step: f64) -> Self {
        self.bristle = Some(Bristle { z0, step });
        self
    }

    /// Sets the condensed bristle's start deflection and step (no effect without one).
    #[inline]
    pub fn set_bristle(&mut self, z0: Vector3<f64>, step: f64) {
        if let Some(b) = &mut self.bristle {
            *b = Bristle { z0, step };
        }
    }

    /// Whether the pair carries a condensed bristle.
    pub fn has_bristle(&self) -> bool {
        self.bristle.is_some() && self.lugre().is_some()
    }

    /// The condensed bristle's deflection at the end of a step of size `step` that started
    /// from `z0`, at the converged `nodes`: projected on the tangent plane there (the
    /// normal part never acts), zero when the spheres are apart (a pair that separates
    /// forgets its stick).
    pub fn bristle_end(&self, nodes: &[NodeState], z0: Vector3<f64>, step: f64) -> Vector3<f64> {
        if !self.has_bristle() {
            return Vector3::zeros();
        }
        let (a, b) = (&nodes[self.nodes[0]], &nodes[self.nodes[1]]);
        let d = b.x - a.x;
        let dist = d.norm();
        if dist >= self.radii[0] + self.radii[1] || dist == 0.0 {
            return Vector3::zeros();
        }
        let n = d / dist;
        let z = self
            .compute_with::<f64>(nodes, &[], Some(&Bristle { z0, step }))
            .bristle;
        z - n * n.dot(&z)
    }

    /// The pair with friction.
    pub fn with_friction(mut self, friction: Option<PairFriction>) -> Self {
        self.friction = friction;
        self
    }

    /// Global LuGre states (a pair outside a granular set).
    fn lugre_states(&self) -> bool {
        self.lugre().is_some() && self.bristle.is_none()
    }

    fn lugre(&self) -> Option<&Friction> {
        match &self.friction {
            Some(PairFriction::LuGre(f)) => Some(f),
            _ => None,
        }
    }

    fn compute<S: Scalar>(&self, nodes: &[NodeState], states: &[ElementState]) -> PairResult<S> {
        self.compute_with(nodes, states, self.bristle.as_ref())
    }

    /// The kernel with the condensed bristle `bristle` (None: global states).
    fn compute_with<S: Scalar>(
        &self,
        nodes: &[NodeState],
        states: &[ElementState],
        bristle: Option<&Bristle>,
    ) -> PairResult<S> {
        let (na, nb) = (&nodes[self.nodes[0]], &nodes[self.nodes[1]]);
        let [ra, rb] = self.radii;
        let zero = S::cst(0.0);
        let d = sub(&var3::<S>(&nb.x, 6), &var3::<S>(&na.x, 0));
        let dist2 = dot(&d, &d);
        let (n, dist) = if dist2.re() > 0.0 {
            let dist = dist2.sqrt();
            (scale(&d, S::cst(1.0) / dist), dist)
        } else {
            ([zero, zero, S::cst(1.0)], zero)
        };
        let (va, vb) = (var3::<S>(&na.v, NV), var3::<S>(&nb.v, NV + 6));
        let (wa, wb) = (omega::<S>(0, na), omega::<S>(1, nb));
        let delta = -dist + (ra + rb);
        let vrel = sub(&vb, &va);
        let delta_dot = -dot(&n, &vrel);
        let (nf, elastic) = normal_law(&self.law, delta, delta_dot);
        // The contact point, mid-overlap: lever arms a_A = (ρ_A − δ/2) n, a_B = −(ρ_B − δ/2) n
        // (one point for both bodies, so the friction pair has no net moment).
        let arm_a = scale(&n, -(delta * 0.5) + ra);
        let arm_b = scale(&n, (delta * 0.5) - rb);
        // Relative velocity of the bodies' material points there, and its tangential part.
        let u = sub(&add(&vrel, &cross(&wb, &arm_b)), &cross(&wa, &arm_a));
        let w = sub(&u, &scale(&n, dot(&n, &u)));
        let s2 = dot(&w, &w);
        let mut ft = [zero; 3];
        let mut state_rows = [zero; 3];
        let mut z_end = Vector3::zeros();
        match &self.friction {
            None => {}
            Some(PairFriction::LuGre(f)) => {
                // ψ(s) = σ₀ s / g(s); |w| is not differentiable at 0, where ψ z = 0.
                let psi = if s2.re() > 0.0 {
                    let s = s2.sqrt();
                    s * f.bristle_stiffness / stribeck(f, s2)
                } else {
                    zero
                };
                let (z, zd): (V3<S>, V3<S>) = match bristle {
                    None => {
                        let z = std::array::from_fn(|j| {
                            let mut x = S::cst(states[j].z);
                            x.add_deriv(12 + j, 1.0);
                            x
                        });
                        let zd = std::array::from_fn(|j| {
                            let mut x = S::cst(states[j].zd);
                            x.add_deriv(NV + 12 + j, 1.0);
                            x
                        });
                        for j in 0..3 {
                            state_rows[j] = zd[j] - w[j] + psi * z[j];
                        }
                        (z, zd)
                    }
                    Some(b) => {
                        // Backward Euler, condensed: ż = (w − ψ z₀)/(1 + hψ), z = z₀ + h ż.
                        let den = psi * b.step + 1.0;
                        let zd: V3<S> = std::array::from_fn(|j| (w[j] - psi * b.z0[j]) / den);
                        (std::array::from_fn(|j| zd[j] * b.step + b.z0[j]), zd)
                    }
                };
                z_end = re3(&z);
                let pz = sub(&z, &scale(&n, dot(&n, &z)));
                let pzd = sub(&zd, &scale(&n, dot(&n, &zd)));
                let phi = add(
                    &add(
                        &scale(&pz, S::cst(f.bristle_stiffness)),
                        &scale(&pzd, S::cst(f.bristle_damping)),
                    ),
                    &scale(&w, S::cst(f.viscous)),
                );
                ft = scale(&phi, -nf);
            }
            Some(PairFriction::Regularized {
                friction: f,
                regularization_velocity: vr,
            }) => {
                let coef = stribeck(f, s2) / (s2 + vr * vr).sqrt() + f.viscous;
                ft = scale(&w, -(nf * coef));
            }
        }
        let f_b = add(&scale(&n, nf), &ft);
        let f_a = scale(&f_b, S::cst(-1.0));
        let mut m_b = cross(&arm_b, &ft);
        let mut m_a = cross(&arm_a, &scale(&ft, S::cst(-1.0)));
        let omega_rel = sub(&wb, &wa);
        let mut rolling = [zero; 3];
        if let Some(res) = &self.rolling {
            rolling = resisting_moment(res, &n, &omega_rel, nf, delta, ra * rb / (ra + rb));
            m_b = add(&m_b, &rolling);
            m_a = sub(&m_a, &rolling);
        }
        PairResult {
            rows: [f_a, rot_t(0, na.r(), &m_a), f_b, rot_t(1, nb.r(), &m_b)],
            state_rows,
            normal: nf.re(),
            elastic,
            delta: delta.re(),
            delta_dot: delta_dot.re(),
            friction: re3(&ft),
            slip: re3(&w),
            bristle: z_end,
            rolling: re3(&rolling),
            omega_rel: re3(&omega_rel),
        }
    }
}

/// `g(s) = μ_d + (μ_s − μ_d) exp(−s²/v_s²)` from s².
fn stribeck<S: Scalar>(f: &Friction, s2: S) -> S {
    let vs2 = f.stribeck_velocity * f.stribeck_velocity;
    (s2 * (-1.0 / vs2)).exp() * (f.static_coefficient - f.dynamic_coefficient)
        + f.dynamic_coefficient
}

impl Element for SpherePair {
    fn name(&self) -> &str {
        &self.name
    }

    fn nodes(&self) -> &[usize] {
        &self.nodes
    }

    fn n_states(&self) -> usize {
        if self.lugre_states() { 3 } else { 0 }
    }

    fn state_names(&self) -> Vec<String> {
        if self.lugre_states() {
            vec!["bristle_x".into(), "bristle_y".into(), "bristle_z".into()]
        } else {
            Vec::new()
        }
    }

    fn evaluate(&self, _ctx: &EvalContext, x: &ElementInput, need: Need, out: &mut LocalTerms) {
        let nz = self.n_states();
        if nz == 0 {
            // Apart, a stateless pair gives nothing, in a neighbourhood (exact tangents 0).
            let (a, b) = (&x.nodes[self.nodes[0]], &x.nodes[self.nodes[1]]);
            if self.radii[0] + self.radii[1] <= (b.x - a.x).norm() {
                return;
            }
        }
        if need == Need::Residual {
            let t = self.compute::<f64>(x.nodes, x.states);
            for (b, row) in t.rows.iter().enumerate() {
                for (k, y) in row.iter().enumerate() {
                    out.r[3 * b + k] -= y;
                }
            }
            for j in 0..nz {
                out.r[12 + j] += t.state_rows[j];
            }
            return;
        }
        let t = self.compute::<Dual<ND>>(x.nodes, x.states);
        let n = 12 + nz;
        let mut put = |ri: usize, y: &Dual<ND>, sign: f64| {
            out.r[ri] += sign * y.v;
            for j in 0..n {
                out.k[(ri, j)] += sign * y.d[j];
                out.c[(ri, j)] += sign * y.d[NV + j];
            }
        };
        for (b, row) in t.rows.iter().enumerate() {
            for (k, y) in row.iter().enumerate() {
                put(3 * b + k, y, -1.0);
            }
        }
        for j in 0..nz {
            put(12 + j, &t.state_rows[j], 1.0);
        }
    }

    fn potential_energy(&self, _ctx: &EvalContext, x: &ElementInput) -> f64 {
        let (a, b) = (&x.nodes[self.nodes[0]], &x.nodes[self.nodes[1]]);
        normal_potential(
            &self.law,
            self.radii[0] + self.radii[1] - (b.x - a.x).norm(),
        )
    }

    /// `(N − N_el) δ̇ − F_t·w − M·(ω_B − ω_A)` (the LuGre bristle's small elastic store counts as
    /// dissipated, as for the ground contact).
    fn dissipated_power(&self, x: &ElementInput) -> f64 {
        let t = self.compute::<f64>(x.nodes, x.states);
        let normal = if t.delta > 0.0 {
            (t.normal - t.elastic) * t.delta_dot
        } else {
            0.0
        };
        normal - t.friction.dot(&t.slip) - t.rolling.dot(&t.omega_rel)
    }

    fn n_events(&self) -> usize {
        1
    }

    fn events(&self, x: &ElementInput, out: &mut [(f64, f64)]) {
        let t = self.compute::<f64>(x.nodes, x.states);
        out[0] = normal_event(&self.law, t.delta, t.delta_dot);
    }

    fn output_names(&self) -> Vec<(String, &'static str)> {
        let mut v = vec![("normal_force".into(), "N"), ("penetration".into(), "m")];
        if self.friction.is_some() {
            v.push(("friction_force".into(), "N"));
            v.push(("slip_velocity".into(), "m/s"));
        }
        v
    }

    fn outputs(&self, _ctx: &EvalContext, x: &ElementInput, out: &mut [f64]) {
        let t = self.compute::<f64>(x.nodes, x.states);
        out[0] = t.normal;
        out[1] = t.delta;
        if self.friction.is_some() {
            out[2] = t.friction.norm();
            out[3] = t.slip.norm();
        }
    }
}
