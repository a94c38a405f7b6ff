//! One aerodynamic station of a lifting line (2-D strip theory): a point p of the line
//! carried by one node (a rigid body) or interpolated between two neighbouring nodes of a
//! beam, with weights wᵢ (Σ wᵢ = 1) and node-frame offsets dᵢ, chord and normal
//! directions ĉᵢ, n̂ᵢ:
//!
//! `p = Σ wᵢ (xᵢ + Rᵢ dᵢ)`, `ṗ = Σ wᵢ (vᵢ + Rᵢ (Ωᵢ × dᵢ))`,
//! `e_c = Σ wᵢ Rᵢ ĉᵢ` (leading → trailing edge), `e_n = Σ wᵢ Rᵢ n̂ᵢ` (suction side).
//!
//! The air velocity relative to the section is U = W(p, t) − ṗ + V_ind (wind, motion,
//! induced velocity); its in-section components u_c = U·e_c, u_n = U·e_n give
//! α = atan2(u_n, u_c) and the loads per unit span
//!
//! `f = ½ ρ c |U| [c_d (u_c e_c + u_n e_n) + c_l (−u_n e_c + u_c e_n)]`,
//! `m = −½ ρ c² |U|² c_m (e_c × e_n)`   (c_m nose-up positive),
//!
//! times the station's width Δs, applied at p: node i receives the share wᵢ (force, and
//! the moment about node i, dᵢ × Rᵢᵀf + Rᵢᵀm in node components). With BEM the induced
//! velocity comes from the station's momentum balance ([`super::bem`]): in the rotor
//! frame (axis n, tangential t = n × r̂), V_x = U₀·n, V_y = −U₀·t, and
//! U = V_x (1 − a) n − V_y (1 + a') t.
//!
//! Tangents: the kernel is written once over [`Scalar`]; with dual numbers seeded by the
//! node increments (δx, δθ: Rᵢ ← Rᵢ(I + δθ̃)) and rates (v, Ω) it returns the exact
//! ∂r/∂q and ∂r/∂v, including the BEM root through the implicit-function theorem.

use super::airfoil::Airfoil;
use super::bem::{BemRotor, StationFlow};
use super::wind::Wind;
use crate::core::{Element, ElementInput, EvalContext, LocalTerms, Need, NodeState};
use crate::math::dual::{Dual, Scalar, V3, add, cross, cst3, dot, scale, sub};
use nalgebra::{Matrix3, Vector3};
use std::sync::Arc;

/// The induced velocity model of a line.
#[derive(Clone, Debug, Default)]
pub enum Inflow {
    /// No induced velocity.
    #[default]
    None,
    /// A given induced velocity, global [m/s].
    Uniform(Vector3<f64>),
    /// Quasi-steady BEM of a rotor with a fixed centre and axis (global).
    Bem {
        rotor: BemRotor,
        centre: Vector3<f64>,
        axis: Vector3<f64>,
    },
}

/// How a station hangs on one node.
#[derive(Clone, Debug, PartialEq)]
pub struct Attachment {
    pub weight: f64,
    /// Offset of the station point, node frame.
    pub offset: Vector3<f64>,
    /// Chord (leading → trailing edge) and normal (suction side) directions, node frame.
    pub chord_dir: Vector3<f64>,
    pub normal_dir: Vector3<f64>,
}

/// The section's aerodynamic data.
#[derive(Clone, Debug)]
pub struct Section {
    pub chord: f64,
    /// Span width Δs the station stands for [m].
    pub width: f64,
    pub airfoil: Arc<Airfoil>,
}

#[derive(Clone, Debug)]
pub struct AeroStation {
    name: String,
    nodes: Vec<usize>,
    attach: Vec<Attachment>,
    section: Section,
    density: f64,
    wind: Arc<Wind>,
    inflow: Arc<Inflow>,
}

/// The most nodes a station hangs on (a beam element of order ≤ 7).
pub const MAX_NODES: usize = 8;

/// What a station computes besides its loads.
#[derive(Clone, Copy, Debug)]
pub struct StationResult<S> {
    pub force: V3<S>,
    pub moment: V3<S>,
    pub point_velocity: V3<S>,
    pub alpha: f64,
    pub speed: f64,
    pub cl: f64,
    pub cd: f64,
    pub cm: f64,
    pub a: f64,
    pub ap: f64,
    pub normal: f64,
    pub tangential: f64,
}

const OUTPUTS: [(&str, &str); 9] = [
    ("alpha", "rad"),
    ("relative_speed", "m/s"),
    ("cl", "1"),
    ("cd", "1"),
    ("cm", "1"),
    ("axial_induction", "1"),
    ("tangential_induction", "1"),
    ("normal_load", "N/m"),
    ("tangential_load", "N/m"),
];

impl AeroStation {
    /// A station on one or two nodes (`nodes` and `attach` of equal length).
    pub fn new(
        name: impl Into<String>,
        nodes: Vec<usize>,
        attach: Vec<Attachment>,
        section: Section,
        density: f64,
        wind: Arc<Wind>,
        inflow: Arc<Inflow>,
    ) -> Self {
        Self {
            name: name.into(),
            nodes,
            attach,
            section,
            density,
            wind,
            inflow,
        }
    }

    /// R b for node i, as a function of the increment δθᵢ.
    fn rot<S: Scalar>(i: usize, r: &Matrix3<f64>, b: &Vector3<f64>) -> V3<S> {
        let v = r * b;
        let mut out = cst3::<S>(&v);
        for j in 0..3 {
            let col = r * Vector3::ith(j, 1.0).cross(b);
            for (k, o) in out.iter_mut().enumerate() {
                o.add_deriv(6 * i + 3 + j, col[k]);
            }
        }
        out
    }

    /// Rᵀ y for node i, y a function of the unknowns: Rᵀ dy − δθ × Rᵀy.
    fn rot_t<S: Scalar>(i: usize, r: &Matrix3<f64>, y: &V3<S>) -> V3<S> {
        let mut z: V3<S> =
            std::array::from_fn(|k| y[0] * r[(0, k)] + y[1] * r[(1, k)] + y[2] * r[(2, k)]);
        let zv = Vector3::new(z[0].re(), z[1].re(), z[2].re());
        for j in 0..3 {
            let c = Vector3::ith(j, 1.0).cross(&zv);
            for (k, zk) in z.iter_mut().enumerate() {
                zk.add_deriv(6 * i + 3 + j, -c[k]);
            }
        }
        z
    }

    /// The station's kinematics, loads and node rows (force, moment per node).
    pub fn compute<S: Scalar>(
        &self,
        t: f64,
        nodes: &[NodeState],
        rows: &mut [V3<S>; 2 * MAX_NODES],
    ) -> StationResult<S> {
        // Derivative directions: (δx, δθ) of node i at 6i…6i+5, (v, Ω) at vo + 6i…,
        // vo half the directions of S (unused for f64).
        let vo = S::DIRECTIONS / 2;
        let zero = S::cst(0.0);
        let mut p = [zero; 3];
        let mut pd = [zero; 3];
        let mut ec = [zero; 3];
        let mut en = [zero; 3];
        for (i, (&n, at)) in self.nodes.iter().zip(&self.attach).enumerate() {
            let ns = &nodes[n];
            let r = ns.r();
            let w = at.weight;
            let mut x = cst3::<S>(&ns.x);
            let mut v = cst3::<S>(&ns.v);
            for k in 0..3 {
                x[k].add_deriv(6 * i + k, 1.0);
                v[k].add_deriv(vo + 6 * i + k, 1.0);
            }
            let rd = Self::rot::<S>(i, r, &at.offset);
            // R (Ω × d): Ω enters linearly (direction 12 + 6i + 3 + j: R (e_j × d)).
            let mut wd = Self::rot::<S>(i, r, &ns.w.cross(&at.offset));
            for j in 0..3 {
                let col = r * Vector3::ith(j, 1.0).cross(&at.offset);
                for (k, o) in wd.iter_mut().enumerate() {
                    o.add_deriv(vo + 6 * i + 3 + j, col[k]);
                }
            }
            p = add(&p, &scale(&add(&x, &rd), S::cst(w)));
            pd = add(&pd, &scale(&add(&v, &wd), S::cst(w)));
            ec = add(&ec, &scale(&Self::rot::<S>(i, r, &at.chord_dir), S::cst(w)));
            en = add(
                &en,
                &scale(&Self::rot::<S>(i, r, &at.normal_dir), S::cst(w)),
            );
        }
        let u0 = sub(&self.wind.velocity(&p, t), &pd);
        let mut res = StationResult {
            force: [zero; 3],
            moment: [zero; 3],
            point_velocity: pd,
            alpha: 0.0,
            speed: 0.0,
            cl: 0.0,
            cd: 0.0,
            cm: 0.0,
            a: 0.0,
            ap: 0.0,
            normal: 0.0,
            tangential: 0.0,
        };
        let (u, bem_frame) = match &*self.inflow {
            Inflow::None => (u0, None),
            Inflow::Uniform(vi) => (add(&u0, &cst3(vi)), None),
            Inflow::Bem {
                rotor,
                centre,
                axis,
            } => {
                let n = cst3::<S>(axis);
                let rel = sub(&p, &cst3(centre));
                let radial = sub(&rel, &scale(&n, dot(&rel, &n)));
                let rr = dot(&radial, &radial).sqrt();
                let tdir = scale(&cross(&n, &radial), S::cst(1.0) / rr);
                let vx = dot(&u0, &n);
                let vy = -dot(&u0, &tdir);
                let theta = dot(&ec, &n).atan2(-dot(&ec, &tdir));
                let flow = StationFlow {
                    vx,
                    vy,
                    r: rr,
                    chord: self.section.chord,
                    theta,
                };
                match rotor.solve(&flow, &self.section.airfoil) {
                    Some(ind) => {
                        res.a = ind.a.re();
                        res.ap = ind.ap.re();
                        let ax = vx * (S::cst(1.0) - ind.a);
                        let tg = vy * (S::cst(1.0) + ind.ap);
                        (sub(&scale(&n, ax), &scale(&tdir, tg)), Some((n, tdir)))
                    }
                    None => (u0, Some((n, tdir))),
                }
            }
        };
        let uc = dot(&u, &ec);
        let un = dot(&u, &en);
        let q2 = uc * uc + un * un;
        if q2.re() < 1e-20 {
            return res;
        }
        let speed = q2.sqrt();
        let alpha = un.atan2(uc);
        let c = self.section.airfoil.eval(alpha.re());
        let (cl, cd, cm) = (
            alpha.chain(c.cl, c.dcl),
            alpha.chain(c.cd, c.dcd),
            alpha.chain(c.cm, c.dcm),
        );
        let (rho, ch, ds) = (self.density, self.section.chord, self.section.width);
        let qf = speed * (0.5 * rho * ch);
        let f_c = (cd * uc - cl * un) * qf;
        let f_n = (cd * un + cl * uc) * qf;
        let f = add(&scale(&ec, f_c), &scale(&en, f_n));
        let span = cross(&ec, &en);
        let m = scale(&span, -(q2 * cm * (0.5 * rho * ch * ch)));
        res.alpha = alpha.re();
        res.speed = speed.re();
        (res.cl, res.cd, res.cm) = (c.cl, c.cd, c.cm);
        match bem_frame {
            Some((n, tdir)) => {
                res.normal = dot(&f, &n).re();
                res.tangential = dot(&f, &tdir).re();
            }
            None => {
                res.normal = f_n.re();
                res.tangential = -f_c.re();
            }
        }
        let f = scale(&f, S::cst(ds));
        let m = scale(&m, S::cst(ds));
        for (i, (&n, at)) in self.nodes.iter().zip(&self.attach).enumerate() {
            let r = nodes[n].r();
            let w = S::cst(at.weight);
            let ft = Self::rot_t(i, r, &f);
            let mt = Self::rot_t(i, r, &m);
            let arm = cst3::<S>(&at.offset);
            rows[2 * i] = scale(&f, w);
            rows[2 * i + 1] = scale(&add(&cross(&arm, &ft), &mt), w);
        }
        res.force = f;
        res.moment = m;
        res
    }
}

impl AeroStation {
    /// Residual and tangents with M dual directions (M/2 ≥ 6 × nodes).
    fn tangents<const M: usize>(&self, ctx: &EvalContext, x: &ElementInput, out: &mut LocalTerms) {
        let lf = ctx.load_factor;
        let nn = self.nodes.len();
        let mut rows = [[Dual::<M>::cst(0.0); 3]; 2 * MAX_NODES];
        self.compute::<Dual<M>>(ctx.time, x.nodes, &mut rows);
        let (n, vo) = (6 * nn, M / 2);
        for (b, row) in rows.iter().take(2 * nn).enumerate() {
            for (k, rk) in row.iter().enumerate() {
                let ri = 3 * b + k;
                out.r[ri] -= lf * rk.v;
                for j in 0..n {
                    out.k[(ri, j)] -= lf * rk.d[j];
                    out.c[(ri, j)] -= lf * rk.d[vo + j];
                }
            }
        }
    }
}

impl Element for AeroStation {
    fn name(&self) -> &str {
        &self.name
    }
    fn nodes(&self) -> &[usize] {
        &self.nodes
    }

    fn evaluate(&self, ctx: &EvalContext, x: &ElementInput, need: Need, out: &mut LocalTerms) {
        let nn = self.nodes.len();
        // Loads are applied loads: scaled by the load factor in statics.
        let lf = ctx.load_factor;
        if need == Need::Residual {
            let mut rows = [[0.0f64; 3]; 2 * MAX_NODES];
            self.compute::<f64>(ctx.time, x.nodes, &mut rows);
            for (b, row) in rows.iter().take(2 * nn).enumerate() {
                for (k, rk) in row.iter().enumerate() {
                    out.r[3 * b + k] -= lf * rk;
                }
            }
            return;
        }
        match nn {
            0..=2 => self.tangents::<24>(ctx, x, out),
            3..=4 => self.tangents::<48>(ctx, x, out),
            _ => self.tangents::<96>(ctx, x, out),
        }
    }

    fn external_power(&self, ctx: &EvalContext, x: &ElementInput) -> f64 {
        let mut rows = [[0.0f64; 3]; 2 * MAX_NODES];
        self.compute::<f64>(ctx.time, x.nodes, &mut rows);
        // Power of the loads on the nodes' velocities.
        let mut p = 0.0;
        for (i, &n) in self.nodes.iter().enumerate() {
            let ns = &x.nodes[n];
            let f = Vector3::from(rows[2 * i]);
            let m = Vector3::from(rows[2 * i + 1]);
            p += f.dot(&ns.v) + m.dot(&ns.w);
        }
        ctx.load_factor * p
    }

    fn output_names(&self) -> Vec<(String, &'static str)> {
        OUTPUTS.iter().map(|(n, u)| (n.to_string(), *u)).collect()
    }

    fn outputs(&self, ctx: &EvalContext, x: &ElementInput, out: &mut [f64]) {
        let mut rows = [[0.0f64; 3]; 2 * MAX_NODES];
        let r = self.compute::<f64>(ctx.time, x.nodes, &mut rows);
        let vals = [
            r.alpha,
            r.speed,
            r.cl,
            r.cd,
            r.cm,
            r.a,
            r.ap,
            r.normal,
            r.tangential,
        ];
        out[..vals.len()].copy_from_slice(&vals);
    }

    fn breakpoints(&self, out: &mut Vec<f64>) {
        out.extend(self.wind.function.breakpoints());
    }
}
