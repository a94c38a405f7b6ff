//! Rigid body on a node, with CG offset, full inertia tensor, gyroscopic terms and gravity.
//!
//! With node position x, orientation R, material angular velocity Ω and CG offset s (node
//! frame), the CG moves as `x_c = x + R s`, so `ẍ_c = v̇ − R s̃ Ω̇ + R Ω̃ Ω̃ s`. The
//! Newton–Euler equations about the node (Géradin & Cardona 2001, ch. 8) are
//!
//! ```text
//! m (v̇ − R s̃ Ω̇ + R Ω̃Ω̃ s) − m g           = 0   (global)
//! J_O Ω̇ + Ω̃ J_O Ω + m s̃ Rᵀ (v̇ − g)      = 0   (node frame)
//! ```
//!
//! with `J_O = J_c − m s̃ s̃` the inertia about the node. The mass matrix
//! `[[m I, −m R s̃], [m s̃ Rᵀ, J_O]]` is symmetric.

use super::{Element, EvalContext, LocalTerms, Need, add_block};
use crate::core::{DiscreteStep, ElementInput, NodeState};
use crate::math::isa;
use crate::math::skew;
use nalgebra::{Matrix3, Vector3};

#[derive(Clone, Debug)]
pub struct RigidBody {
    name: String,
    node: [usize; 1],
    mass: f64,
    /// Inertia about the CG, node frame.
    j_cg: Matrix3<f64>,
    /// Inertia about the node, node frame: J_c − m s̃ s̃.
    j_o: Matrix3<f64>,
    s: Vector3<f64>,
}

impl RigidBody {
    pub fn new(
        name: impl Into<String>,
        node: usize,
        mass: f64,
        inertia_cg: Matrix3<f64>,
        cg_offset: Vector3<f64>,
    ) -> Self {
        let st = skew(&cg_offset);
        Self {
            name: name.into(),
            node: [node],
            mass,
            j_cg: inertia_cg,
            j_o: inertia_cg - st * st * mass,
            s: cg_offset,
        }
    }

    pub fn mass(&self) -> f64 {
        self.mass
    }

    /// The CG relative to the node, node frame.
    pub fn cg_offset(&self) -> Vector3<f64> {
        self.s
    }

    /// Position of the CG.
    pub fn cg_position(&self, n: &NodeState) -> Vector3<f64> {
        n.x + n.r() * self.s
    }

    /// Linear momentum m ẋ_c and angular momentum about the global origin, global frame.
    pub fn momenta(&self, n: &NodeState) -> (Vector3<f64>, Vector3<f64>) {
        let r = n.r();
        let vc = n.v + r * n.w.cross(&self.s);
        let p = vc * self.mass;
        let h_cg = r * (self.j_cg * n.w);
        (p, h_cg + self.cg_position(n).cross(&p))
    }
}

impl RigidBody {
    #[inline(always)]
    fn evaluate_impl(&self, ctx: &EvalContext, x: &ElementInput, need: Need, out: &mut LocalTerms) {
        let nodes = x.nodes;
        let n = &nodes[self.node[0]];
        let r = n.r();
        let m = self.mass;
        let st = skew(&self.s);
        let wt = skew(&n.w);
        let g = ctx.gravity * ctx.load_factor;
        let a_rel = n.a - g;
        // w = −m s̃ Ω̇ + m Ω̃Ω̃ s (node frame), so the force rows are m(v̇ − g) + R w.
        let w_loc = (-(st * n.wd) + wt * (wt * self.s)) * m;
        out.add_r(0, &(a_rel * m + r * w_loc));
        let rt_a = r.transpose() * a_rel;
        let jw = self.j_o * n.w;
        out.add_r(3, &(self.j_o * n.wd + n.w.cross(&jw) + st * rt_a * m));

        if need == Need::Residual {
            return;
        }
        // M = ∂r/∂v̇.
        let mi = Matrix3::identity() * m;
        add_block(&mut out.m, 0, 0, &mi);
        add_block(&mut out.m, 0, 3, &(-(r * st) * m));
        add_block(&mut out.m, 3, 0, &(st * r.transpose() * m));
        add_block(&mut out.m, 3, 3, &self.j_o);
        // C = ∂r/∂v: ∂(Ω̃Ω̃s)/∂Ω = −((Ω×s)~ + Ω̃ s̃); ∂(Ω̃ J Ω)/∂Ω = Ω̃ J − (JΩ)~.
        let c_xw = -(r * (skew(&n.w.cross(&self.s)) + wt * st)) * m;
        add_block(&mut out.c, 0, 3, &c_xw);
        add_block(&mut out.c, 3, 3, &(wt * self.j_o - skew(&jw)));
        // K = ∂r/∂θ: δ(R w) = −R w̃ δθ; δ(Rᵀ b) = (Rᵀ b)~ δθ.
        add_block(&mut out.k, 0, 3, &(-(r * skew(&w_loc))));
        add_block(&mut out.k, 3, 3, &(st * skew(&rt_a) * m));
    }
}

impl Element for RigidBody {
    fn name(&self) -> &str {
        &self.name
    }

    fn nodes(&self) -> &[usize] {
        &self.node
    }

    isa::copies! {
        /// On x86-64 CPUs with AVX this runs in a copy compiled for AVX (called through
        /// `dyn Element`, it would otherwise be compiled for the baseline only): the same
        /// operations in the same order, no fused multiply–add, so the same bits.
        fn evaluate(
            &self: RigidBody,
            ctx: &EvalContext,
            x: &ElementInput,
            need: Need,
            out: &mut LocalTerms,
        ) {
            Base | Avx => evaluate_impl,
        }
    }

    fn kinetic_energy(&self, x: &ElementInput) -> f64 {
        let nodes = x.nodes;
        let n = &nodes[self.node[0]];
        let vc = n.v + n.r() * n.w.cross(&self.s);
        0.5 * self.mass * vc.norm_squared() + 0.5 * n.w.dot(&(self.j_cg * n.w))
    }

    /// Written about the CG, also with a `cg_offset` (the integrator then moves the node
    /// so that the CG obeys the mid-point relation; the node must carry no other inertia,
    /// checked when the analysis starts).
    fn discrete_form(&self) -> Result<(), String> {
        Ok(())
    }

    /// Simo & Wong's (1991) energy–momentum form about the CG, with the Cayley update
    /// `R₁ = R₀ cay(ψ)` and the CG `x_c = x + R s` moving by `Δx_c = Δx + (R₀ψ) × s̄`
    /// (s̄ = (R₀s + R₁s)/2, exact for the Cayley update), `v_c = v + R(Ω × s)`:
    ///
    /// ```text
    /// F = m (v_c1 − v_c0)/h − m g                                      (global)
    /// J (Ω₁ − Ω₀)/h + (ψ/h) × J (Ω₀ + Ω₁)/2 + (I − ψ̃/2) R₀ᵀ (s̄ × F)   (conjugate to ψ)
    /// ```
    ///
    /// The integrator moves the node so that the CG obeys the mid-point relation,
    /// `Δx_c = h(v_c0 + v_c1)/2` (the scheme's kinematics, written for the CG of a node
    /// carrying an offset body). Then `Δx·F + ψ·r_ψ = F·Δx_c + ΔT_rot = ΔT − m g·Δx_c`
    /// exactly (`ψ·(I − ψ̃/2)a = ψ·a`, ψ ⟂ ψ × ·), and the rotation rows are the change of
    /// spatial angular momentum about the CG plus the moment `s̄ × F` of the CG's force:
    /// `R₁JΩ₁ − R₀JΩ₀ = h R₀ (I − ψ̃/2)⁻¹ r_ψ − h s̄ × F`, so the angular momentum balance is
    /// exact as for a body with its node at the CG (s = 0 gives that form).
    fn discrete_residual(&self, step: &DiscreteStep, out: &mut [f64]) {
        let i = self.node[0];
        let (n0, n1) = (&step.start[i], &step.end[i]);
        let (_, psi) = step.increment(i);
        let h = step.h;
        let g = step.ctx.gravity * step.ctx.load_factor;
        let (vc0, vc1) = (
            n0.v + n0.r() * n0.w.cross(&self.s),
            n1.v + n1.r() * n1.w.cross(&self.s),
        );
        let f = (vc1 - vc0) * (self.mass / h) - g * self.mass;
        let jw = self.j_cg * (n0.w + n1.w) * 0.5;
        let mut m = self.j_cg * (n1.w - n0.w) / h + psi.cross(&jw) / h;
        if self.s != Vector3::zeros() {
            m += step.conjugate_moment(i, &step.mean_arm(i, &self.s).cross(&f));
        }
        out[..3].copy_from_slice(f.as_slice());
        out[3..6].copy_from_slice(m.as_slice());
    }

    fn potential_energy(&self, ctx: &EvalContext, x: &ElementInput) -> f64 {
        let nodes = x.nodes;
        -self.mass * ctx.load_factor * ctx.gravity.dot(&self.cg_position(&nodes[self.node[0]]))
    }
}
