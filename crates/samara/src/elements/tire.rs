//! A pneumatic tire on a wheel node rolling on a ground plane: vertical spring-damper on
//! the deflection, longitudinal and lateral forces by the Magic Formula from the transient
//! slip ratio and slip angle (relaxation-length states), aligning moment through the
//! pneumatic trail, rolling resistance, and a brake torque between the wheel and its
//! carrier (the hub joint's other node).
//!
//! References: H. B. Pacejka, *Tire and Vehicle Dynamics*, 3rd ed. (2012): the Magic
//! Formula `Y = D sin(C arctan(B x − E (B x − arctan(B x))))` (§4.3.2, eq. 4.49), the
//! pneumatic trail `t = D_t cos(C_t arctan(B_t α − E_t (B_t α − arctan(B_t α)))) cos α`
//! (§4.3.2, eq. 4.E40 without shifts) with `M_z = −t F_y`, and the first-order
//! relaxation-length model of the contact patch (§7.2.1, eqs. 7.9–7.11 for the lateral
//! deflection, the same for the longitudinal one), written for the transient slips
//! `κ' = u/σ_κ`, `tan α' = v/σ_α`:
//!
//! `σ_κ κ̇' + |V_x| κ' = −V_sx`,   `σ_α (tan α')˙ + |V_x| tan α' = −V_sy`,
//!
//! whose steady state is the kinematic slip `κ = −V_sx/|V_x|`, `tan α = −V_sy/|V_x|`, and
//! whose response to a step of slip at constant speed is first order with time constant
//! σ/|V_x|.
//!
//! **Kinematics.** The wheel node (hub centre `x`, orientation R) spins about the axis
//! `s = R s₀` (the hub joint's axis); the ground is the plane through `p₀` with unit
//! normal `n`, moving in its own plane at `v_g` (a flat-track test rig; zero for a road).
//! With `cos γ = |n − (n·s) s|` (γ the camber): forward `e_x = s × n / cos γ`, lateral
//! `e_y = n × e_x`, the radial direction to the ground in the wheel plane
//! `r̂ = −(n − (n·s) s)/cos γ`; hub height `h = n·(x − p₀)`; deflection
//! `δ = R₀ cos γ − h` (R₀ the unloaded radius); `δ̇ = −n·v`. The contact point is where
//! r̂ from the hub meets the ground, `c = x + (h/cos γ) r̂`. Hub velocity relative to the
//! ground `V_x = e_x·(v − v_g)`, `V_y = e_y·(v − v_g)`; spin `Ω = s₀·Ω_W` (absolute);
//! slip velocities `V_sx = V_x − R_e Ω`, `V_sy = V_y` (R_e the effective rolling radius).
//!
//! **Out of contact** (δ ≤ 0) the contact patch is gone: the slip states relax to zero,
//! `σ ż + (|V_x| + v_ε) z = 0`, so a wheel touches down with undeflected tread whatever its
//! spin in the air (Pacejka §7.2: the deflection u = σ κ' of the tread).
//!
//! **Low-speed damping.** At standstill the relaxation model is an undamped spring of
//! stiffness C/σ (Pacejka §8.6, the low-speed problem of the transient model); the forces
//! use the damped slips `κ_d = κ' − c_low w(V_x) V_sx`, `tan α_d = tan α' − c_low w(V_x) V_sy`
//! with `w = ½(1 + cos(π |V_x|/V_low))` below V_low (0 above), a damping force
//! `−C c_low V_s` (C = B C μ F_z the slip stiffness) that fades out by V_low.
//!
//! **Forces.** `F_z = max(0, k δ + c δ̇)` for δ > 0; `F_x = μ_x F_z sin(C_x φ(B_x, E_x, κ'))`,
//! `F_y = μ_y F_z sin(C_y φ(B_y, E_y, α'))` with `φ(B, E, x) = arctan(B x − E(B x −
//! arctan B x))` — the peak D = μ F_z grows linearly with the load (a constant friction
//! coefficient; B, C, E do not depend on the load, so the slip stiffness B C D ∝ F_z);
//! pure slip (no combined-slip weighting). `F = F_z n + F_x e_x + F_y e_y` acts at c; the
//! moments on the wheel are the aligning moment `M_z n`, the rolling resistance
//! `−f_r R₀ F_z tanh(R_e Ω/v_ε) s` and the brake `−T_b tanh(R_e ω_rel/v_ε) s` with
//! `ω_rel = s·(ω_W − ω_A)` the spin relative to the carrier, which takes `+T_b tanh(·) s`
//! (T_b = max(0, brake signal); v_ε a small regularization speed).
//!
//! **Height-field ground** ([`Tire::with_height_field`]): a terrain z(x, y) instead of the
//! plane, taken as its tangent plane below the hub — the single-point-contact ("point
//! follower") road model (Pacejka 2012, §10.1): with z, ∇z at the hub's (x, y), the
//! normal `n = (−∇z, 1)/√(1 + |∇z|²)` and the hub height `h = (x_z − z) n_z` (the
//! distance from that tangent plane; exact on a plane), then everything as above with this
//! n, which turns as the hub moves (its derivatives through the Hessian are in the
//! tangents). A point follower feels an obstacle shorter than the contact patch too
//! sharply (no enveloping). The ground does not move; a converged state with the hub
//! outside the table is an error ([`Element::range_violation`]).
//!
//! Tangents are exact by forward-mode differentiation of the one kernel
//! ([`crate::math::dual`]).

use super::node_dual::{rot, rot_t, var3};
use super::terrain::{normal, surface};
use super::{Element, EvalContext, LocalTerms, Need};
use crate::core::{ElementInput, ElementState, NodeState};
use crate::math::dual::{Dual, Scalar, V3, add, cross, cst3, dot, scale, sub};
use crate::math::height_field::HeightField;
use nalgebra::Vector3;
use std::sync::Arc;

/// Magic Formula coefficients of one characteristic: stiffness factor B, shape factor C,
/// peak D (per unit normal load μ for forces, a length for the trail) and curvature E.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MagicFormula {
    pub b: f64,
    pub c: f64,
    pub d: f64,
    pub e: f64,
}

impl MagicFormula {
    /// `C arctan(B x − E (B x − arctan(B x)))`.
    fn angle<S: Scalar>(&self, x: S) -> S {
        let bx = x * self.b;
        atan(bx - (bx - atan(bx)) * self.e) * self.c
    }

    /// `D sin(C arctan(…))`: the force per unit load (D = μ) at slip x.
    pub fn sine<S: Scalar>(&self, x: S) -> S {
        self.angle(x).sin() * self.d
    }

    /// `D cos(C arctan(…)) cos x`: the pneumatic trail at slip angle x [rad].
    pub fn trail<S: Scalar>(&self, x: S) -> S {
        self.angle(x).cos() * x.cos() * self.d
    }
}

fn atan<S: Scalar>(x: S) -> S {
    let v = x.re();
    x.chain(v.atan(), 1.0 / (1.0 + v * v))
}

fn tanh<S: Scalar>(x: S) -> S {
    let t = x.re().tanh();
    x.chain(t, 1.0 - t * t)
}

/// The ground of a tire.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TireGround {
    pub point: Vector3<f64>,
    /// Unit normal, out of the ground.
    pub normal: Vector3<f64>,
    /// Surface velocity in its plane (a flat-track rig's belt).
    pub velocity: Vector3<f64>,
}

/// Tire parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TireParameters {
    /// Unloaded radius R₀ [m].
    pub radius: f64,
    /// Effective rolling radius R_e [m].
    pub rolling_radius: f64,
    /// Vertical stiffness k [N/m].
    pub stiffness: f64,
    /// Vertical damping c [N s/m].
    pub damping: f64,
    /// Relaxation lengths σ_κ, σ_α [m].
    pub relaxation: [f64; 2],
    pub longitudinal: MagicFormula,
    pub lateral: MagicFormula,
    /// Pneumatic trail (D_t in m); none: no aligning moment.
    pub trail: Option<MagicFormula>,
    /// Rolling-resistance coefficient f_r.
    pub rolling_resistance: f64,
    /// Regularization speed v_ε [m/s] of the rolling resistance and the brake; out of
    /// contact the slip states relax at |V_x| + v_ε.
    pub regularization_speed: f64,
    /// Low-speed damping c_low [s/m] of the slip states (0: none).
    pub low_speed_damping: f64,
    /// Speed V_low [m/s] below which the low-speed damping fades in.
    pub low_speed: f64,
}

/// The low-speed damping weight `w(V) = ½ (1 + cos(π |V|/V_low))` below V_low, 0 above:
/// one at standstill, fading out with a continuous slope at V_low.
fn low_speed_weight<S: Scalar>(v: S, v_low: f64) -> S {
    let a = v.re().abs();
    if a >= v_low {
        return S::cst(0.0);
    }
    let ph = std::f64::consts::PI / v_low;
    let sign = if v.re() < 0.0 { -1.0 } else { 1.0 };
    v.chain(
        0.5 * (1.0 + (ph * a).cos()),
        -0.5 * ph * (ph * a).sin() * sign,
    )
}

/// Derivative directions: local unknown k at k (K), its rate at `NV + k` (C), the brake
/// signal at `2 NV`.
const NV: usize = 14;
const ND: usize = 2 * NV + 1;

/// What the kernel gives.
struct TireResult<S> {
    /// Node rows: wheel force, wheel moment (node frame), carrier force (zero), carrier
    /// moment (node frame).
    rows: [V3<S>; 4],
    /// State rows (m/s).
    state_rows: [S; 2],
    fz: f64,
    fx: f64,
    fy: f64,
    mz: f64,
    rolling: f64,
    brake: f64,
    kappa: f64,
    alpha: f64,
    delta: f64,
    /// Total force and moments (global) for the power.
    force: Vector3<f64>,
    moment_w: Vector3<f64>,
    moment_a: Vector3<f64>,
}

/// A tire on a wheel node, with an optional carrier node (the hub joint's other node).
#[derive(Clone, Debug)]
pub struct Tire {
    name: String,
    /// Wheel node, then the carrier node if there is one.
    nodes: Vec<usize>,
    /// Spin axis s₀ in the wheel node's frame (unit).
    axis: Vector3<f64>,
    ground: TireGround,
    p: TireParameters,
    /// The brake-torque signal, if any.
    inputs: Vec<String>,
    /// A height-field ground instead of the plane.
    terrain: Option<Arc<HeightField>>,
}

impl Tire {
    /// `axis` is the spin axis in the wheel node's frame; `ground.normal` is normalized
    /// and `ground.velocity` projected on the plane here.
    pub fn new(
        name: impl Into<String>,
        wheel: usize,
        carrier: Option<usize>,
        axis: Vector3<f64>,
        mut ground: TireGround,
        parameters: TireParameters,
        brake: Option<String>,
    ) -> Self {
        let n = ground.normal.normalize();
        ground.normal = n;
        ground.velocity -= n * n.dot(&ground.velocity);
        let mut nodes = vec![wheel];
        nodes.extend(carrier);
        Self {
            name: name.into(),
            nodes,
            axis: axis.normalize(),
            ground,
            p: parameters,
            inputs: brake.into_iter().collect(),
            terrain: None,
        }
    }

    /// The same tire on the height-field ground `terrain` (fixed) instead of its plane.
    pub fn with_height_field(mut self, terrain: Arc<HeightField>) -> Self {
        self.ground.velocity = Vector3::zeros();
        self.terrain = Some(terrain);
        self
    }

    /// The ground's normal and the hub's height above it at hub position `x`: the plane,
    /// or the tangent plane of the height field below the hub.
    fn local_ground<S: Scalar>(&self, x: &V3<S>) -> (V3<S>, S) {
        match &self.terrain {
            None => {
                let n = cst3::<S>(&self.ground.normal);
                let h = dot(&n, &sub(x, &cst3(&self.ground.point)));
                (n, h)
            }
            Some(hf) => {
                let (z, g) = surface(hf, x[0], x[1]);
                let (n, nz) = normal(&g);
                (n, (x[2] - z) * nz)
            }
        }
    }

    fn compute<S: Scalar>(
        &self,
        nodes: &[NodeState],
        states: &[ElementState],
        signals: &[f64],
    ) -> TireResult<S> {
        let p = &self.p;
        let w = &nodes[self.nodes[0]];
        let rw = w.r();
        let nn = self.nodes.len();
        let x = var3::<S>(&w.x, 0);
        let v = sub(&var3::<S>(&w.v, NV), &cst3(&self.ground.velocity));
        let s = rot::<S>(0, rw, &self.axis);
        let (n, h) = self.local_ground(&x);
        let ns = dot(&n, &s);
        let cv = sub(&n, &scale(&s, ns));
        let cg = dot(&cv, &cv).sqrt();
        let ex = scale(&cross(&s, &n), S::cst(1.0) / cg);
        let ey = cross(&n, &ex);
        let rhat = scale(&cv, -(S::cst(1.0) / cg));
        let delta = cg * p.radius - h;
        let delta_dot = -dot(&n, &v);
        let zero = S::cst(0.0);
        let mut fz = zero;
        if delta.re() > 0.0 {
            fz = delta * p.stiffness + delta_dot * p.damping;
            if fz.re() <= 0.0 {
                fz = zero;
            }
        }
        let vx = dot(&ex, &v);
        let vy = dot(&ey, &v);
        let mut spin = S::cst(self.axis.dot(&w.w));
        for j in 0..3 {
            spin.add_deriv(NV + 3 + j, self.axis[j]);
        }
        let vsx = vx - spin * p.rolling_radius;
        let z: [S; 2] = std::array::from_fn(|j| {
            let mut zj = S::cst(states[j].z);
            zj.add_deriv(6 * nn + j, 1.0);
            zj
        });
        let zd: [S; 2] = std::array::from_fn(|j| {
            let mut zj = S::cst(states[j].zd);
            zj.add_deriv(NV + 6 * nn + j, 1.0);
            zj
        });
        let avx = vx.abs();
        let state_rows = if delta.re() > 0.0 {
            [
                zd[0] * p.relaxation[0] + avx * z[0] + vsx,
                zd[1] * p.relaxation[1] + avx * z[1] + vy,
            ]
        } else {
            let rate = avx + p.regularization_speed;
            [
                zd[0] * p.relaxation[0] + rate * z[0],
                zd[1] * p.relaxation[1] + rate * z[1],
            ]
        };
        let (kappa, alpha) = if p.low_speed_damping > 0.0 {
            let d = low_speed_weight(vx, p.low_speed) * p.low_speed_damping;
            (z[0] - d * vsx, atan(z[1] - d * vy))
        } else {
            (z[0], atan(z[1]))
        };
        let fx = fz * p.longitudinal.sine(kappa);
        let fy = fz * p.lateral.sine(alpha);
        let mz = match &p.trail {
            Some(t) => -(t.trail(alpha) * fy),
            None => zero,
        };
        let ve = p.regularization_speed;
        let rolling =
            -(fz * tanh(spin * (p.rolling_radius / ve))) * (p.rolling_resistance * p.radius);
        // Brake: spin relative to the carrier.
        let mut brake = zero;
        if let Some(&tb) = signals.first()
            && tb > 0.0
        {
            let mut tbs = S::cst(tb);
            tbs.add_deriv(2 * NV, 1.0);
            let mut rel = spin;
            if nn == 2 {
                let a = &nodes[self.nodes[1]];
                let ra = a.r();
                // s·(R_A Ω_A): δθ_A and Ω_A derivatives, plus δθ_W through s.
                let wa = rot::<S>(1, ra, &a.w);
                let mut wa = wa;
                if S::DIRECTIONS > 0 {
                    for j in 0..3 {
                        for (k, o) in wa.iter_mut().enumerate() {
                            o.add_deriv(NV + 9 + j, ra[(k, j)]);
                        }
                    }
                }
                rel -= dot(&s, &wa);
            }
            brake = -(tbs * tanh(rel * (p.rolling_radius / ve)));
        }
        let arm = scale(&rhat, h / cg);
        let force = add(&add(&scale(&n, fz), &scale(&ex, fx)), &scale(&ey, fy));
        let m_w = add(
            &add(&cross(&arm, &force), &scale(&n, mz)),
            &scale(&s, rolling + brake),
        );
        let m_a = scale(&s, -brake);
        let rows = [force, rot_t(0, rw, &m_w), [zero; 3], {
            if nn == 2 {
                rot_t(1, nodes[self.nodes[1]].r(), &m_a)
            } else {
                [zero; 3]
            }
        }];
        let re3 = |y: &V3<S>| Vector3::new(y[0].re(), y[1].re(), y[2].re());
        TireResult {
            rows,
            state_rows,
            fz: fz.re(),
            fx: fx.re(),
            fy: fy.re(),
            mz: mz.re(),
            rolling: rolling.re(),
            brake: brake.re(),
            kappa: kappa.re(),
            alpha: alpha.re(),
            delta: delta.re(),
            force: re3(&force),
            moment_w: re3(&m_w),
            moment_a: re3(&m_a),
        }
    }

    /// Deflection δ and its exact rate (with the camber rate).
    fn deflection(&self, w: &NodeState) -> (f64, f64) {
        if self.terrain.is_some() {
            // δ = R₀ cos γ − h along the motion: x' = v, s' = ω × s.
            let s0 = w.r() * self.axis;
            let sd = w.omega_global().cross(&s0);
            let x: V3<Dual<1>> = std::array::from_fn(|k| Dual {
                v: w.x[k],
                d: [w.v[k]],
            });
            let s: V3<Dual<1>> = std::array::from_fn(|k| Dual {
                v: s0[k],
                d: [sd[k]],
            });
            let (n, h) = self.local_ground(&x);
            let ns = dot(&n, &s);
            let cv = sub(&n, &scale(&s, ns));
            let delta = dot(&cv, &cv).sqrt() * self.p.radius - h;
            return (delta.v, delta.d[0]);
        }
        let n = self.ground.normal;
        let s = w.r() * self.axis;
        let ns = n.dot(&s);
        let cg = (1.0 - ns * ns).max(0.0).sqrt();
        let delta = self.p.radius * cg - n.dot(&(w.x - self.ground.point));
        let sdot = w.omega_global().cross(&s);
        let dcg = if cg > 0.0 {
            -ns * n.dot(&sdot) / cg
        } else {
            0.0
        };
        (delta, self.p.radius * dcg - n.dot(&w.v))
    }
}

impl Element for Tire {
    fn name(&self) -> &str {
        &self.name
    }

    fn nodes(&self) -> &[usize] {
        &self.nodes
    }

    fn n_states(&self) -> usize {
        2
    }

    fn state_names(&self) -> Vec<String> {
        vec!["slip_ratio".into(), "lateral_slip".into()]
    }

    fn signal_inputs(&self) -> &[String] {
        &self.inputs
    }

    fn evaluate(&self, _ctx: &EvalContext, x: &ElementInput, need: Need, out: &mut LocalTerms) {
        let nn = self.nodes.len();
        let ns = 6 * nn;
        if need == Need::Residual {
            let t = self.compute::<f64>(x.nodes, x.states, x.signals);
            for (b, row) in t.rows.iter().take(2 * nn).enumerate() {
                for (k, y) in row.iter().enumerate() {
                    out.r[3 * b + k] -= y;
                }
            }
            for j in 0..2 {
                out.r[ns + j] += t.state_rows[j];
            }
            return;
        }
        let t = self.compute::<Dual<ND>>(x.nodes, x.states, x.signals);
        let n = ns + 2;
        let has_signal = !self.inputs.is_empty();
        let mut put = |ri: usize, y: &Dual<ND>, sign: f64| {
            out.r[ri] += sign * y.v;
            for j in 0..n {
                out.k[(ri, j)] += sign * y.d[j];
                out.c[(ri, j)] += sign * y.d[NV + j];
            }
            if has_signal {
                out.ds[(ri, 0)] += sign * y.d[2 * NV];
            }
        };
        for (b, row) in t.rows.iter().take(2 * nn).enumerate() {
            for (k, y) in row.iter().enumerate() {
                put(3 * b + k, y, -1.0);
            }
        }
        for j in 0..2 {
            put(ns + j, &t.state_rows[j], 1.0);
        }
    }

    fn potential_energy(&self, _ctx: &EvalContext, x: &ElementInput) -> f64 {
        let (delta, _) = self.deflection(&x.nodes[self.nodes[0]]);
        if delta > 0.0 {
            0.5 * self.p.stiffness * delta * delta
        } else {
            0.0
        }
    }

    /// `−P − k δ δ̇`: the power the tire takes from the nodes less the rate of its elastic
    /// energy (this includes the small store of the relaxation states and the work of a
    /// moving ground, which [`Element::external_power`] gives back).
    fn dissipated_power(&self, x: &ElementInput) -> f64 {
        let t = self.compute::<f64>(x.nodes, x.states, x.signals);
        let w = &x.nodes[self.nodes[0]];
        let mut power = t.force.dot(&w.v) + t.moment_w.dot(&w.omega_global());
        if let Some(&a) = self.nodes.get(1) {
            power += t.moment_a.dot(&x.nodes[a].omega_global());
        }
        let (delta, rate) = self.deflection(w);
        let elastic = if delta > 0.0 {
            self.p.stiffness * delta * rate
        } else {
            0.0
        };
        -power - elastic + t.force.dot(&self.ground.velocity)
    }

    fn external_power(&self, _ctx: &EvalContext, x: &ElementInput) -> f64 {
        let t = self.compute::<f64>(x.nodes, x.states, x.signals);
        t.force.dot(&self.ground.velocity)
    }

    /// `g = min(δ, δ + (c/k) δ̇_n)` (δ̇_n = −n·v, the rate the damper sees): positive
    /// exactly where F_z > 0 ([`super::contact::normal_event`]).
    fn n_events(&self) -> usize {
        1
    }

    fn events(&self, x: &ElementInput, out: &mut [(f64, f64)]) {
        let w = &x.nodes[self.nodes[0]];
        let (delta, rate) = self.deflection(w);
        // On a height field the damper's rate is taken as the deflection's (it differs
        // by the camber and slope rates, which only move the event, not the kink, a little).
        let rate_n = if self.terrain.is_some() {
            rate
        } else {
            -self.ground.normal.dot(&w.v)
        };
        let force_side = delta + self.p.damping / self.p.stiffness * rate_n;
        out[0] = if delta <= force_side {
            (delta, rate)
        } else {
            (force_side, f64::NAN)
        };
    }

    fn output_names(&self) -> Vec<(String, &'static str)> {
        OUTPUTS.iter().map(|(n, u)| (n.to_string(), *u)).collect()
    }

    fn outputs(&self, _ctx: &EvalContext, x: &ElementInput, out: &mut [f64]) {
        let t = self.compute::<f64>(x.nodes, x.states, x.signals);
        let vals = [
            t.fz, t.fx, t.fy, t.mz, t.rolling, t.brake, t.kappa, t.alpha, t.delta,
        ];
        out[..vals.len()].copy_from_slice(&vals);
    }

    fn range_violation(&self, x: &ElementInput) -> Option<String> {
        let hf = self.terrain.as_ref()?;
        let c = x.nodes[self.nodes[0]].x;
        (!hf.contains(c.x, c.y)).then(|| {
            let ([x0, x1], [y0, y1]) = hf.bounds();
            format!(
                "the hub at ({:.6}, {:.6}) left the height field's table x ∈ [{x0}, {x1}], y ∈ [{y0}, {y1}]",
                c.x, c.y
            )
        })
    }
}

/// Output names and units, in [`Element::outputs`] order.
const OUTPUTS: [(&str, &str); 9] = [
    ("normal_force", "N"),
    ("longitudinal_force", "N"),
    ("lateral_force", "N"),
    ("aligning_moment", "N m"),
    ("rolling_resistance_moment", "N m"),
    ("brake_torque", "N m"),
    ("slip_ratio", "1"),
    ("slip_angle", "rad"),
    ("deflection", "m"),
];

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Rotation;

    /// Out of contact only the brake acts: equal and opposite torques about the spin axis
    /// on wheel and carrier, −T_b tanh(R_e ω_rel/v_ε) on the wheel, no forces.
    #[test]
    fn brake_torques_are_equal_and_opposite() {
        let mf = MagicFormula {
            b: 10.0,
            c: 1.9,
            d: 1.0,
            e: 0.97,
        };
        let p = TireParameters {
            radius: 0.3,
            rolling_radius: 0.29,
            stiffness: 1e5,
            damping: 0.0,
            relaxation: [0.1, 0.3],
            longitudinal: mf,
            lateral: mf,
            trail: None,
            rolling_resistance: 0.01,
            regularization_speed: 0.05,
            low_speed_damping: 0.0,
            low_speed: 1.0,
        };
        let ground = TireGround {
            point: Vector3::new(0.0, 0.0, -5.0),
            normal: Vector3::z(),
            velocity: Vector3::zeros(),
        };
        let axis = Vector3::new(0.0, 1.0, 0.0);
        let tire = Tire::new("t", 0, Some(1), axis, ground, p, Some("b".into()));
        let wheel = NodeState {
            rot: Rotation::exp(&Vector3::new(0.0, 0.7, 0.0)),
            w: Vector3::new(0.0, 0.2, 0.0),
            ..NodeState::default()
        };
        let carrier = NodeState {
            rot: Rotation::exp(&Vector3::new(0.3, 0.0, -0.2)),
            w: Vector3::new(0.0, 0.0, 0.0),
            ..NodeState::default()
        };
        let nodes = [wheel, carrier];
        let states = [ElementState::default(); 2];
        let ctx = EvalContext {
            time: 0.0,
            gravity: Vector3::zeros(),
            load_factor: 1.0,
        };
        let x = ElementInput {
            nodes: &nodes,
            states: &states,
            signals: &[100.0],
            held: &[],
        };
        let mut out = LocalTerms::for_element(&tire);
        tire.evaluate(&ctx, &x, Need::Residual, &mut out);
        let rw = nodes[0].r() * Vector3::new(out.r[3], out.r[4], out.r[5]);
        let ra = nodes[1].r() * Vector3::new(out.r[9], out.r[10], out.r[11]);
        let t = 100.0 * (0.29 * 0.2f64 / 0.05).tanh();
        for i in 0..3 {
            assert_eq!(out.r[i], 0.0);
            assert_eq!(out.r[6 + i], 0.0);
        }
        // Residual rows are −(moment): the wheel's moment is −T about y.
        assert!((rw - Vector3::new(0.0, t, 0.0)).norm() < 1e-12, "{rw}");
        assert!((ra + rw).norm() < 1e-12, "{ra}");
    }

    /// The Magic Formula at a few points against its definition written out, and the
    /// peak: for E = 0 the maximum D is reached at B x = tan(π/(2C)) (Pacejka 2012, §4.3.2).
    #[test]
    fn magic_formula_values() {
        let mf = MagicFormula {
            b: 10.0,
            c: 1.9,
            d: 1.0,
            e: 0.97,
        };
        for x in [-0.4, -0.05, 0.0, 0.02, 0.1, 0.8] {
            let bx: f64 = 10.0 * x;
            let want = (1.9 * (bx - 0.97 * (bx - bx.atan())).atan()).sin();
            assert!((mf.sine(x) - want).abs() < 1e-15);
        }
        let mf0 = MagicFormula { e: 0.0, ..mf };
        let xp = (std::f64::consts::PI / (2.0 * 1.9)).tan() / 10.0;
        assert!((mf0.sine(xp) - 1.0).abs() < 1e-14);
    }
}
