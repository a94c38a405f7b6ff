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
//! Tangents: the load kernel ([`AeroStation::loads`]) reads the nodes only through the
//! station's kinematics y = (p, e_c, e_n, ṗ, ė_c), 15 numbers linear in the node
//! quantities. It is written once over [`Scalar`]; with dual numbers seeded by y, the
//! states, their rates and the input signals (≤ 28 directions, whatever the number of
//! nodes) it returns the exact ∂(F, M, r_z)/∂y, including the BEM root through the
//! implicit-function theorem. The chain to the node increments (δxᵢ, δθᵢ: Rᵢ ← Rᵢ(I + δθ̃ᵢ))
//! and rates (vᵢ, Ωᵢ) is analytic ([`AeroStation::to_nodes`]): δ(Rᵢ bᵢ) = Rᵢ (δθᵢ × bᵢ)
//! for each node-frame vector bᵢ (dᵢ, ĉᵢ, n̂ᵢ, Ωᵢ × dᵢ, Ωᵢ × ĉᵢ), and the moment rows
//! add the node's own rotation in Rᵢᵀ: ∂(Rᵢᵀ y)/∂δθᵢ = (Rᵢᵀ y)~. Each column g of
//! ∂(F, M) is spread over the node rows as `c −= L g`, L the shares' map
//! `[wᵢ I 0; wᵢ d̃ᵢ Rᵢᵀ wᵢ Rᵢᵀ]` stacked over the nodes; on CPUs with AVX the tangents run in
//! a copy compiled for it ([`AeroStation::evaluate_body`], the same bits).
//!
//! **Unsteady airfoil** ([`super::unsteady`]): with Wagner's attached-flow states or Øye's
//! dynamic stall the station takes the air velocity at the three-quarter-chord point,
//! U₃/₄ = U − (c/2) ė_c (the point p + (c/2) e_c, p the aerodynamic centre at the
//! quarter chord), and owns up to five states (Wagner z₁, z₂ [m/s], Küssner z_K1, z_K2
//! [m/s] on the wind's gust, then Øye's
//! separation f); their rows follow the node rows, their tangents come from the same
//! dual pass.

use super::airfoil::Airfoil;
use super::bem::{BemRotor, SKEW_CONSTANT, StationFlow};
use super::dynamic_inflow::{RotorDisc, inflow_signals, thrust_signals};
use super::hgm::{Hgm, HgmFlow};
use super::root_hint::RootHint;
use super::unsteady::{AttachedFlow, JONES_A, JONES_B, KUSSNER_A, KUSSNER_B, OyeStall};
use super::wind::Wind;
use crate::core::{Element, ElementInput, EvalContext, LocalTerms, Need, NodeState, SignalTerms};
use crate::elements::slot::Slot;
use crate::math::dual::{Dual, Scalar, V3, add, cross, cst3, dot, scale, sub};
use crate::math::isa;
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
    /// Pitt–Peters dynamic inflow of the rotor `rotor` ([`super::dynamic_inflow`]): the
    /// station reads the rotor's states v₀, v_s, v_c as signals, takes the induced
    /// velocity v = v₀ + v_s (r/R) sin ψ + v_c (r/R) cos ψ along the disc axis, and
    /// produces its thrust dT = −f·n and first moments dT (r/R) sin ψ, dT (r/R) cos ψ.
    PittPeters { rotor: String, disc: RotorDisc },
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
    /// Kinematic viscosity ν [m²/s] when the airfoil's tables are interpolated in the
    /// Reynolds number Re = W c/ν ([`Airfoil::eval_re`]); `None`: its first table.
    pub viscosity: Option<f64>,
}

/// The unsteady airfoil models of a station (none by default: quasi-steady).
#[derive(Clone, Debug, Default)]
pub struct Unsteady {
    pub attached: AttachedFlow,
    /// Øye's dynamic stall with its separation curves, and A_τ (τ = A_τ c/V).
    pub stall: Option<(Arc<OyeStall>, f64)>,
    /// Øye's dynamic wake on the BEM axial induction (two filter states).
    pub dynamic_wake: bool,
    /// Beddoes–Leishman dynamic stall in Hansen–Gaunaa–Madsen's four-state form
    /// ([`super::hgm`]; its own circulatory lag: not with Wagner or Øye).
    pub hgm: Option<Arc<Hgm>>,
    /// Küssner's gust response (with Wagner): the normal velocity of the wind's
    /// disturbance (gust and turbulence, at the leading edge) through Küssner's function
    /// (two states), the rest through Wagner's.
    pub kussner: bool,
}

impl Unsteady {
    fn wagner_states(&self) -> usize {
        match self.attached {
            AttachedFlow::QuasiSteady => 0,
            AttachedFlow::Wagner => 2,
        }
    }
    /// Number of Küssner states (two with Wagner and the gust response).
    fn kussner_states(&self) -> usize {
        if self.kussner && self.wagner_states() == 2 {
            2
        } else {
            0
        }
    }
    /// Number of airfoil states (Wagner, Küssner, Øye's stall).
    fn airfoil_states(&self) -> usize {
        self.wagner_states()
            + self.kussner_states()
            + usize::from(self.stall.is_some())
            + 4 * usize::from(self.hgm.is_some())
    }
    /// Number of states (airfoil states, then the dynamic wake's two).
    pub fn states(&self) -> usize {
        self.airfoil_states() + if self.dynamic_wake { 2 } else { 0 }
    }
    /// Whether the airfoil is unsteady (three-quarter-chord velocity).
    fn active(&self) -> bool {
        self.airfoil_states() > 0
    }
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
    unsteady: Unsteady,
    initial: [f64; MAX_STATES],
    /// Signals read (the rotor's inflow states) and produced (the thrust), Pitt–Peters.
    inputs: Vec<String>,
    outputs: Vec<String>,
    /// The station's last BEM roots, the warm start of its next solve
    /// ([`BemRotor::solve_near`], [`RootHint`]). Every solve converges to rounding from
    /// any start, so the results depend on it only at rounding level; it is cleared as
    /// each analysis starts ([`Element::begin_analysis`]), and each station is evaluated
    /// in the same sequence whatever the number of threads, so a run gives the same bits
    /// every time. (Parallel linearizations of one system — Campbell, Floquet — share it
    /// between threads.)
    root_hint: RootHint,
    /// The power of the loads at the last residual evaluation, F·ṗ + M·ω̄ scaled by the
    /// load factor ([`Element::evaluated_power`]); cleared as each analysis starts.
    last_power: Slot,
    /// Distance of the station from its line's root [m] (the input's `span`; an output,
    /// the abscissa of span-wise plots).
    span: f64,
    /// Initial coordinate along the wind's direction of the point where the station
    /// samples a gust (the leading edge with Küssner's response, else p): a convected
    /// gust's breakpoints reach it x/U_c later.
    gust_x: f64,
    /// The user property the airfoil's tables are interpolated in (AeroDyn's AFTabMod
    /// = 3), if any.
    user_property: Option<UserProperty>,
    /// Whether Øye's stall curves read the section's airfoil table (then, without Re
    /// interpolation, they take the static coefficients the loads looked up already).
    stall_reads_section: bool,
}

/// Where a station's user property (e.g. a flap angle) comes from, AeroDyn's `UserProp`.
#[derive(Clone, Debug, PartialEq)]
pub enum UserProperty {
    /// A constant value.
    Value(f64),
    /// A signal (the station's last input signal); outside the tables' range the first
    /// or last table is read (clamped, ∂c/∂u = 0).
    Signal(String),
}

/// Most input signals of a station: Pitt–Peters' three and a user property.
const MAX_INPUTS: usize = 4;

/// Øye's lead factor k of the dynamic wake's first filter (Snel & Schepers 1995).
const OYE_LEAD: f64 = 0.6;

/// Floor of the free-stream speed in the dynamic wake's time constants [m/s].
const WAKE_MIN_SPEED: f64 = 0.1;

/// The most nodes a station hangs on (a beam element of order ≤ 7).
pub const MAX_NODES: usize = 8;
/// The most states a station owns (Wagner's two, Küssner's two and Øye's stall one, or
/// HGM's four; the dynamic wake two).
pub const MAX_STATES: usize = 7;

/// Number of kinematic quantities of a station the loads read, y = (p, e_c, e_n, ṗ, ė_c).
const KINEMATICS: usize = 15;

/// A station's kinematics (global): point p, chord and normal directions e_c, e_n, point
/// velocity ṗ, and ė_c (read by an unsteady airfoil only).
#[derive(Clone, Copy, Debug)]
pub struct Kinematics<S> {
    pub p: V3<S>,
    pub ec: V3<S>,
    pub en: V3<S>,
    pub pd: V3<S>,
    pub ecd: V3<S>,
}

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
    /// Chordwise and normal air velocity the airfoil sees (at the three-quarter chord
    /// with unsteady models) and the effective angle of attack α_E.
    pub uc: f64,
    pub un: f64,
    pub alpha_effective: f64,
    /// Pitt–Peters forcing of the station: dT, dT (r/R) sin ψ, dT (r/R) cos ψ.
    pub rotor_forcing: [S; 3],
    /// The quasi-steady BEM axial induction (before the dynamic wake).
    pub a_quasi_steady: f64,
    /// The Reynolds number the tables are read at (NaN without Re interpolation).
    pub reynolds: f64,
    /// The disturbance's share of the normal velocity u_n (Küssner's input; 0 without it).
    pub un_gust: f64,
}

const OUTPUTS: [(&str, &str); 10] = [
    ("alpha", "rad"),
    ("relative_speed", "m/s"),
    ("cl", "1"),
    ("cd", "1"),
    ("cm", "1"),
    ("axial_induction", "1"),
    ("tangential_induction", "1"),
    ("normal_load", "N/m"),
    ("tangential_load", "N/m"),
    ("span", "m"),
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
        let name = name.into();
        let (inputs, outputs) = match &*inflow {
            Inflow::PittPeters { rotor, .. } => (
                inflow_signals(rotor).to_vec(),
                thrust_signals(&name).to_vec(),
            ),
            _ => (Vec::new(), Vec::new()),
        };
        Self {
            name,
            nodes,
            attach,
            section,
            density,
            wind,
            inflow,
            unsteady: Unsteady::default(),
            initial: [0.0; MAX_STATES],
            inputs,
            outputs,
            root_hint: RootHint::new(),
            last_power: Slot::new(),
            span: 0.0,
            gust_x: 0.0,
            user_property: None,
            stall_reads_section: false,
        }
    }

    /// The station with its airfoil's tables interpolated in a user property (the
    /// section's airfoil must be [`Airfoil::by_user_property`]); a signal is read as the
    /// station's last input.
    pub fn with_user_property(mut self, u: UserProperty) -> Self {
        if let UserProperty::Signal(name) = &u {
            self.inputs.push(name.clone());
        }
        self.user_property = Some(u);
        self
    }

    /// The station at `span` [m] from its line's root (written as the output `span`).
    pub fn with_span(mut self, span: f64) -> Self {
        self.span = span;
        self
    }

    /// The station with unsteady airfoil models; its states start at their
    /// quasi-steady values for the motion of `nodes` at time `t` (a station already in
    /// steady flow starts without a transient).
    pub fn with_unsteady(mut self, unsteady: Unsteady, t: f64, nodes: &[NodeState]) -> Self {
        self.stall_reads_section = unsteady
            .stall
            .as_ref()
            .is_some_and(|(stall, _)| stall.reads(&self.section.airfoil));
        self.unsteady = unsteady;
        self.initial = self.quasi_steady_states(t, nodes);
        let k = self.kinematics(nodes);
        let mut q = Vector3::from(k.p);
        if self.unsteady.kussner_states() == 2 {
            q -= Vector3::from(k.ec) * (0.25 * self.section.chord);
        }
        self.gust_x = q.dot(&self.wind.direction);
        self
    }

    /// The states' quasi-steady values (ż = 0): z_i = A_i w, f = f_st(α).
    pub fn quasi_steady_states(&self, t: f64, nodes: &[NodeState]) -> [f64; MAX_STATES] {
        let mut rows = [[0.0f64; 3]; 2 * MAX_NODES];
        let z = [0.0; MAX_STATES];
        let mut zr = [0.0; MAX_STATES];
        let ns = self.unsteady.states();
        let r = self.compute(t, nodes, &z[..ns], &z[..ns], &[], &mut rows, &mut zr);
        let mut out = [0.0; MAX_STATES];
        let nw = self.unsteady.wagner_states();
        let nk = self.unsteady.kussner_states();
        if nw == 2 {
            out[0] = JONES_A[0] * (r.un - r.un_gust);
            out[1] = JONES_A[1] * (r.un - r.un_gust);
        }
        if nk == 2 {
            out[2] = KUSSNER_A[0] * r.un_gust;
            out[3] = KUSSNER_A[1] * r.un_gust;
        }
        if let Some((stall, _)) = &self.unsteady.stall {
            let alpha = r.un.atan2(r.uc);
            out[nw + nk] = if stall.by_reynolds() && !r.reynolds.is_nan() {
                stall.eval_re(alpha, r.reynolds).f
            } else {
                stall.eval(alpha).f
            };
        }
        if let Some(h) = &self.unsteady.hgm {
            out[..4].copy_from_slice(&h.steady_states(r.un.atan2(r.uc), r.reynolds));
        }
        if self.unsteady.dynamic_wake {
            let iw = self.unsteady.airfoil_states();
            out[iw] = (1.0 - OYE_LEAD) * r.a_quasi_steady;
            out[iw + 1] = r.a_quasi_steady;
        }
        out
    }

    /// The station's kinematics y from its nodes (f64): `p = Σ wᵢ (xᵢ + Rᵢ dᵢ)`,
    /// `e_c = Σ wᵢ Rᵢ ĉᵢ`, `e_n = Σ wᵢ Rᵢ n̂ᵢ`, `ṗ = Σ wᵢ (vᵢ + Rᵢ (Ωᵢ × dᵢ))`,
    /// `ė_c = Σ wᵢ Rᵢ (Ωᵢ × ĉᵢ)`.
    #[inline(always)]
    fn kinematics(&self, nodes: &[NodeState]) -> Kinematics<f64> {
        let mut k = Kinematics {
            p: [0.0; 3],
            ec: [0.0; 3],
            en: [0.0; 3],
            pd: [0.0; 3],
            ecd: [0.0; 3],
        };
        for (&n, at) in self.nodes.iter().zip(&self.attach) {
            let ns = &nodes[n];
            let r = ns.r();
            let w = at.weight;
            let p = ns.x + r * at.offset;
            let pd = ns.v + r * ns.w.cross(&at.offset);
            let ec = r * at.chord_dir;
            let en = r * at.normal_dir;
            let ecd = r * ns.w.cross(&at.chord_dir);
            for c in 0..3 {
                k.p[c] += p[c] * w;
                k.pd[c] += pd[c] * w;
                k.ec[c] += ec[c] * w;
                k.en[c] += en[c] * w;
                k.ecd[c] += ecd[c] * w;
            }
        }
        k
    }

    /// Dual directions of the station's kinematics: y = (p, e_c, e_n, ṗ) and, with an
    /// unsteady airfoil (which reads ė_c), ė_c.
    fn kinematic_directions(&self) -> usize {
        if self.unsteady.active() {
            KINEMATICS
        } else {
            KINEMATICS - 3
        }
    }

    /// The kinematics as dual numbers: component c of block b (p, e_c, e_n, ṗ, ė_c) is
    /// direction 3b + c (ė_c constant when `rates_of_chord` is false).
    #[inline(always)]
    fn seeded<const M: usize>(k: &Kinematics<f64>, rates_of_chord: bool) -> Kinematics<Dual<M>> {
        let var = |a: &V3<f64>, o: usize| -> V3<Dual<M>> {
            std::array::from_fn(|c| Dual::var(a[c], o + c))
        };
        Kinematics {
            p: var(&k.p, 0),
            ec: var(&k.ec, 3),
            en: var(&k.en, 6),
            pd: var(&k.pd, 9),
            ecd: if rates_of_chord {
                var(&k.ecd, 12)
            } else {
                k.ecd.map(<Dual<M> as Scalar>::cst)
            },
        }
    }

    /// The loads of the station from its kinematics: force F = f Δs and moment M = m Δs
    /// (global, at p), the state rows, and what the outputs report. (The kinematics,
    /// the element states and rates, and the input signals are the kernel's inputs.)
    pub fn loads<S: Scalar>(
        &self,
        t: f64,
        kin: &Kinematics<S>,
        z: &[S],
        zd: &[S],
        sig: &[S],
        zrows: &mut [S; MAX_STATES],
    ) -> StationResult<S> {
        self.loads_body(t, kin, z, zd, sig, zrows)
    }

    /// The body of [`Self::loads`], inlined into the copy of the tangents compiled for
    /// AVX ([`Self::evaluate_body`]).
    #[inline(always)]
    fn loads_body<S: Scalar>(
        &self,
        t: f64,
        kin: &Kinematics<S>,
        z: &[S],
        zd: &[S],
        sig: &[S],
        zrows: &mut [S; MAX_STATES],
    ) -> StationResult<S> {
        let zero = S::cst(0.0);
        let (p, pd, ec, en, ecd) = (kin.p, kin.pd, kin.ec, kin.en, kin.ecd);
        let unsteady = self.unsteady.active();
        let (rho, ch, ds) = (self.density, self.section.chord, self.section.width);
        // The wind at the station; with Küssner's gust response its disturbance (gust and
        // turbulence) is taken at the leading edge p − (c/4) e_c, where Küssner's
        // function starts (its front reaches the leading edge at s = 0).
        let (wind_p, disturbance) = if self.unsteady.kussner_states() == 2 {
            let le = sub(&p, &scale(&ec, S::cst(0.25 * ch)));
            self.wind.split(&p, &le, t)
        } else {
            (self.wind.velocity(&p, t), [zero; 3])
        };
        let u0 = sub(&wind_p, &pd);
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
            uc: 0.0,
            un: 0.0,
            alpha_effective: 0.0,
            rotor_forcing: [zero; 3],
            a_quasi_steady: 0.0,
            reynolds: f64::NAN,
            un_gust: 0.0,
        };
        // With BEM the Reynolds number is the undisturbed one (set below).
        let mut re_bem: Option<S> = None;
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
                // Re from the in-plane speed without induction, W₀ = √(V_x² + V_y²):
                // the momentum balance and the loads read the tables at the same Re,
                // which does not depend on the induction being solved for.
                re_bem = self
                    .section
                    .viscosity
                    .map(|nu| (vx * vx + vy * vy).sqrt() * (self.section.chord / nu));
                let flow = StationFlow {
                    vx,
                    vy,
                    r: rr,
                    chord: self.section.chord,
                    theta,
                    re: re_bem,
                };
                let mut ind =
                    rotor.solve_near(&flow, &self.section.airfoil, self.root_hint.start(t));
                if let Some(i) = &mut ind {
                    self.root_hint.record(t, i.phi.re());
                    if rotor.skewed_wake {
                        // Pitt–Peters/Glauert: a ← a [1 + (15π/32)(r/R) tan(χ/2) cos ψ],
                        // χ = (1 + 0.6a) γ the wake skew, γ the wind's angle to the axis,
                        // ψ the azimuth from the most downwind position (the radial
                        // direction along the wind's in-plane part).
                        let wv = wind_p;
                        let wn = dot(&wv, &n);
                        let wip = sub(&wv, &scale(&n, wn));
                        let m2 = dot(&wip, &wip);
                        if wn.re() > 0.0 && m2.re() > 1e-24 * dot(&wv, &wv).re() {
                            let m = m2.sqrt();
                            let gamma = m.atan2(wn);
                            let half = gamma * (i.a * 0.6 + 1.0) * 0.5;
                            let cos_psi = dot(&radial, &wip) / (rr * m);
                            let k = half.sin() / half.cos()
                                * cos_psi
                                * (rr * (SKEW_CONSTANT / rotor.tip_radius));
                            i.a = i.a * (k + 1.0);
                        }
                    }
                }
                let a_qs = ind.map_or(zero, |i| i.a);
                res.a_quasi_steady = a_qs.re();
                // Øye's dynamic wake: the axial induction the station uses is the
                // quasi-steady one through two first-order filters,
                // τ₁ ż₁ + z₁ = a_qs + k τ₁ ȧ_qs, τ₂ ż₂ + z₂ = z₁, a = z₂ (rows in 1/s);
                // the lead term through the state y = z₁ − k a_qs: τ₁ ẏ + y = (1 − k) a_qs.
                let a = if self.unsteady.dynamic_wake {
                    let iw = self.unsteady.airfoil_states();
                    let v0 = dot(&wind_p, &n);
                    let v0 = if v0.re() < WAKE_MIN_SPEED {
                        S::cst(WAKE_MIN_SPEED)
                    } else {
                        v0
                    };
                    let ac = if a_qs.re() > 0.5 { S::cst(0.5) } else { a_qs };
                    let tau1 = S::cst(1.1 * rotor.tip_radius) / ((S::cst(1.0) - ac * 1.3) * v0);
                    let x = rr / rotor.tip_radius;
                    let tau2 = tau1 * (S::cst(0.39) - x * x * 0.26);
                    zrows[iw] = zd[iw] + (z[iw] - a_qs * (1.0 - OYE_LEAD)) / tau1;
                    let z1 = z[iw] + a_qs * OYE_LEAD;
                    zrows[iw + 1] = zd[iw + 1] + (z[iw + 1] - z1) / tau2;
                    Some(z[iw + 1])
                } else {
                    ind.map(|i| i.a)
                };
                match (ind, a) {
                    (Some(ind), Some(a)) => {
                        res.a = a.re();
                        res.ap = ind.ap.re();
                        let ax = vx * (S::cst(1.0) - a);
                        let tg = vy * (S::cst(1.0) + ind.ap);
                        (sub(&scale(&n, ax), &scale(&tdir, tg)), Some((n, tdir)))
                    }
                    (None, Some(a)) => {
                        // No BEM root: the filtered induction still applies axially.
                        res.a = a.re();
                        let u = sub(&u0, &scale(&n, vx * a));
                        (u, Some((n, tdir)))
                    }
                    _ => (u0, Some((n, tdir))),
                }
            }
            Inflow::PittPeters { disc, .. } => {
                // Signals missing (a station evaluated alone): no induced velocity.
                let v = if sig.len() >= 3 {
                    let (hs, hc) = disc.harmonics(&p);
                    sig[0] + sig[1] * hs + sig[2] * hc
                } else {
                    zero
                };
                (add(&u0, &scale(&cst3(&disc.axis), v)), None)
            }
        };
        let u_ac = u;
        let u = if unsteady {
            sub(&u, &scale(&ecd, S::cst(0.5 * ch)))
        } else {
            u
        };
        let uc = dot(&u, &ec);
        let un = dot(&u, &en);
        let q2 = uc * uc + un * un;
        let nw = self.unsteady.wagner_states();
        let nk = self.unsteady.kussner_states();
        (res.uc, res.un) = (uc.re(), un.re());
        if q2.re() < 1e-20 {
            // No flow: the airfoil states hold.
            for (zr, &d) in zrows
                .iter_mut()
                .zip(zd)
                .take(self.unsteady.airfoil_states())
            {
                *zr = d;
            }
            return res;
        }
        let speed = q2.sqrt();
        let alpha = un.atan2(uc);
        // Wagner: the effective downwash w_E and the states' rows. With Küssner's gust
        // response the disturbance's normal velocity w_g = W'·e_n goes through Küssner's
        // states, the rest w − w_g through Wagner's.
        let alpha_e = if nw == 2 {
            let k = speed * (2.0 / ch);
            let wg = if nk == 2 {
                dot(&disturbance, &en)
            } else {
                zero
            };
            res.un_gust = wg.re();
            let wm = un - wg;
            for i in 0..2 {
                zrows[i] = zd[i] + k * JONES_B[i] * (z[i] - wm * JONES_A[i]);
            }
            let mut we = wm * (1.0 - JONES_A[0] - JONES_A[1]) + z[0] + z[1];
            if nk == 2 {
                for i in 0..2 {
                    zrows[2 + i] = zd[2 + i] + k * KUSSNER_B[i] * (z[2 + i] - wg * KUSSNER_A[i]);
                }
                we = we + wg * (1.0 - KUSSNER_A[0] - KUSSNER_A[1]) + z[2] + z[3];
            }
            we.atan2(uc)
        } else {
            alpha
        };
        // Re = W c/ν at the speed the airfoil sees (W₀ with BEM).
        // With a user property, it takes Re's place (the tables' parameter).
        let re = match &self.user_property {
            Some(UserProperty::Value(u)) => Some(S::cst(*u)),
            Some(UserProperty::Signal(_)) => {
                // The signal is the last input (absent: a station evaluated alone, the
                // first table).
                (sig.len() == self.inputs.len()).then(|| sig[sig.len() - 1])
            }
            None => self
                .section
                .viscosity
                .map(|nu| re_bem.unwrap_or(speed * (ch / nu))),
        };
        res.reynolds = re.map_or(f64::NAN, |r| r.re());
        let ([cl, cd, cm], c) = self.section.airfoil.coefficients(alpha_e, re);
        let (mut cl, mut cd, mut cm) = (cl, cd, cm);
        let mut cl_out = c.cl;
        if let Some((stall, a_tau)) = &self.unsteady.stall {
            // Øye: cl = f cl_inv + (1 − f) cl_fs, τ ḟ = f_st − f; with Re tables the
            // curves of the polar interpolated at Re.
            let (fst, fs, inv) = match re.filter(|_| stall.by_reynolds()) {
                Some(re) => {
                    let sc = stall.eval_re(alpha_e, re);
                    (sc.f, sc.fs, sc.inv)
                }
                None => {
                    let sc = if re.is_none() && self.stall_reads_section {
                        stall.eval_with(alpha_e.re(), c)
                    } else {
                        stall.eval(alpha_e.re())
                    };
                    (
                        alpha_e.chain(sc.f, sc.df),
                        alpha_e.chain(sc.fs, sc.dfs),
                        alpha_e.chain(sc.inv, sc.dinv),
                    )
                }
            };
            let f = z[nw + nk];
            zrows[nw + nk] = zd[nw + nk] + speed * (1.0 / (a_tau * ch)) * (f - fst);
            cl = f * inv + (S::cst(1.0) - f) * fs;
            cl_out = cl.re();
        }
        // HGM: coefficients from the states; loads about the quarter-chord flow.
        let (uc, un, q2, speed, alpha_e) = match &self.unsteady.hgm {
            Some(h) => {
                let (uc_ac, un_ac) = (dot(&u_ac, &ec), dot(&u_ac, &en));
                let q2_ac = uc_ac * uc_ac + un_ac * un_ac;
                if q2_ac.re() < 1e-20 {
                    // No flow at the quarter chord: the states hold, no load.
                    zrows[..4].copy_from_slice(&zd[..4]);
                    return res;
                }
                let speed_ac = q2_ac.sqrt();
                // Nose-up pitch rate: the leading edge (−e_c) turning toward e_n.
                let omega = -dot(&ecd, &en);
                let flow = HgmFlow {
                    speed: speed_ac,
                    alpha_34: alpha,
                    omega,
                };
                let o = h.eval(ch, &flow, &z[..4], &zd[..4], re);
                zrows[..4].copy_from_slice(&o.rows);
                (cl, cd, cm) = (o.cl, o.cd, o.cm);
                cl_out = cl.re();
                (uc_ac, un_ac, q2_ac, speed_ac, o.alpha_e)
            }
            None => (uc, un, q2, speed, alpha_e),
        };
        let qf = speed * (0.5 * rho * ch);
        let f_c = (cd * uc - cl * un) * qf;
        let f_n = (cd * un + cl * uc) * qf;
        let f = add(&scale(&ec, f_c), &scale(&en, f_n));
        let span = cross(&ec, &en);
        let m = scale(&span, -(q2 * cm * (0.5 * rho * ch * ch)));
        res.alpha = alpha.re();
        res.alpha_effective = alpha_e.re();
        res.speed = speed.re();
        (res.cl, res.cd, res.cm) = if self.unsteady.hgm.is_some() {
            (cl_out, cd.re(), cm.re())
        } else {
            (cl_out, c.cd, c.cm)
        };
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
        if let Inflow::PittPeters { disc, .. } = &*self.inflow {
            let dt = -dot(&f, &cst3(&disc.axis));
            let (hs, hc) = disc.harmonics(&p);
            res.rotor_forcing = [dt, dt * hs, dt * hc];
        }
        res.force = f;
        res.moment = m;
        res
    }

    /// Node i's share of the loads F, M at p: wᵢ F and the moment about node i,
    /// wᵢ (dᵢ × Rᵢᵀ F + Rᵢᵀ M), in node components.
    #[inline(always)]
    fn node_rows(
        &self,
        nodes: &[NodeState],
        f: &V3<f64>,
        m: &V3<f64>,
        rows: &mut [V3<f64>; 2 * MAX_NODES],
    ) {
        for (i, (&n, at)) in self.nodes.iter().zip(&self.attach).enumerate() {
            let r = nodes[n].r();
            let w = at.weight;
            let ft = tr_mul(r, f);
            let mt = tr_mul(r, m);
            let arm = cst3::<f64>(&at.offset);
            rows[2 * i] = scale(f, w);
            rows[2 * i + 1] = scale(&add(&cross(&arm, &ft), &mt), w);
        }
    }

    /// The station's kinematics, loads and node rows (force, moment per node), f64.
    #[allow(clippy::too_many_arguments)]
    pub fn compute(
        &self,
        t: f64,
        nodes: &[NodeState],
        z: &[f64],
        zd: &[f64],
        sig: &[f64],
        rows: &mut [V3<f64>; 2 * MAX_NODES],
        zrows: &mut [f64; MAX_STATES],
    ) -> StationResult<f64> {
        let kin = self.kinematics(nodes);
        let r = self.loads::<f64>(t, &kin, z, zd, sig, zrows);
        self.node_rows(nodes, &r.force, &r.moment, rows);
        r
    }

    /// The power of the loads F, M at p on the nodes, Σᵢ (wᵢF)·vᵢ + wᵢ(dᵢ × RᵢᵀF + RᵢᵀM)·Ωᵢ,
    /// summed over the nodes first: `P = F·ṗ + M·ω̄`, ṗ = Σ wᵢ (vᵢ + Rᵢ (Ωᵢ × dᵢ)) the
    /// station's velocity and ω̄ = Σ wᵢ Rᵢ Ωᵢ (global), without the node rows.
    #[inline(always)]
    fn power(&self, nodes: &[NodeState], f: &V3<f64>, m: &V3<f64>, pd: &V3<f64>) -> f64 {
        let mut omega = Vector3::zeros();
        for (&n, at) in self.nodes.iter().zip(&self.attach) {
            let nd = &nodes[n];
            omega += at.weight * (nd.r() * nd.w);
        }
        Vector3::from(*f).dot(&Vector3::from(*pd)) + Vector3::from(*m).dot(&omega)
    }

    /// The same power from the node rows (force, moment per node, node components):
    /// Σᵢ rowsᵢ,F·vᵢ + rowsᵢ,M·Ωᵢ, six products per node and no rotation (equal to
    /// [`Self::power`] up to rounding).
    #[inline(always)]
    fn rows_power(&self, nodes: &[NodeState], rows: &[V3<f64>; 2 * MAX_NODES]) -> f64 {
        let mut p = 0.0;
        for (i, &n) in self.nodes.iter().enumerate() {
            let nd = &nodes[n];
            let (f, m) = (&rows[2 * i], &rows[2 * i + 1]);
            p += f[0] * nd.v[0] + f[1] * nd.v[1] + f[2] * nd.v[2];
            p += m[0] * nd.w[0] + m[1] * nd.w[1] + m[2] * nd.w[2];
        }
        p
    }

    /// Point p, force F and moment M (global, at p) of the station: the rotor outputs'
    /// view of it ([`super::rotor_performance`]).
    pub fn point_loads(
        &self,
        t: f64,
        nodes: &[NodeState],
        z: &[f64],
        zd: &[f64],
        sig: &[f64],
    ) -> (Vector3<f64>, Vector3<f64>, Vector3<f64>) {
        let kin = self.kinematics(nodes);
        let mut zrows = [0.0; MAX_STATES];
        let r = self.loads::<f64>(t, &kin, z, zd, sig, &mut zrows);
        (
            Vector3::from(kin.p),
            Vector3::from(r.force),
            Vector3::from(r.moment),
        )
    }

    /// The node-frame vectors of the chain rule ([`Self::to_nodes`]) turned to global
    /// components, once per evaluation: per node Rᵢ, Rᵢdᵢ, Rᵢĉᵢ, Rᵢn̂ᵢ, Rᵢ(Ωᵢ × dᵢ),
    /// Rᵢ(Ωᵢ × ĉᵢ).
    #[inline(always)]
    fn node_arms(&self, nodes: &[NodeState]) -> [NodeArms; MAX_NODES] {
        let mut arms = [NodeArms::default(); MAX_NODES];
        for ((&n, at), a) in self.nodes.iter().zip(&self.attach).zip(&mut arms) {
            let ns = &nodes[n];
            let r = ns.r();
            *a = NodeArms {
                r: *r,
                offset: r * at.offset,
                chord: r * at.chord_dir,
                normal: r * at.normal_dir,
                offset_rate: r * ns.w.cross(&at.offset),
                chord_rate: r * ns.w.cross(&at.chord_dir),
            };
        }
        arms
    }

    /// The chain rule from the station to its nodes: given g = ∂s/∂y of a scalar s over
    /// the kinematic directions, writes ∂s/∂(δxᵢ, δθᵢ) to `kq` and ∂s/∂(vᵢ, Ωᵢ) to `kv`
    /// (6 per node). With Rᵢ ← Rᵢ (I + δθ̃ᵢ) each term wᵢ Rᵢ bᵢ of y moves by
    /// wᵢ Rᵢ (δθᵢ × bᵢ), so g·δy = wᵢ δθᵢ · (bᵢ × Rᵢᵀ g) = wᵢ δθᵢ · Rᵢᵀ((Rᵢbᵢ) × g); Ωᵢ
    /// enters ṗ and ė_c the same way through Rᵢ (Ωᵢ × dᵢ) and Rᵢ (Ωᵢ × ĉᵢ); xᵢ and vᵢ enter
    /// p and ṗ with weight wᵢ. The cross products are taken in global components with
    /// the arms of [`Self::node_arms`], then turned by Rᵢᵀ once per column group.
    #[inline(always)]
    fn to_nodes(&self, arms: &[NodeArms], g: &[f64], kq: &mut [f64], kv: &mut [f64]) {
        let block = |b: usize| {
            if g.len() >= 3 * b + 3 {
                Vector3::new(g[3 * b], g[3 * b + 1], g[3 * b + 2])
            } else {
                Vector3::zeros()
            }
        };
        let (gp, gc, gn, gpd, gcd) = (block(0), block(1), block(2), block(3), block(4));
        for (i, (at, a)) in self.attach.iter().zip(arms).enumerate() {
            let w = at.weight;
            let th = a.r.tr_mul(
                &(a.offset.cross(&gp)
                    + a.chord.cross(&gc)
                    + a.normal.cross(&gn)
                    + a.offset_rate.cross(&gpd)
                    + a.chord_rate.cross(&gcd)),
            );
            let om = a.r.tr_mul(&(a.offset.cross(&gpd) + a.chord.cross(&gcd)));
            for k in 0..3 {
                kq[6 * i + k] = w * gp[k];
                kq[6 * i + 3 + k] = w * th[k];
                kv[6 * i + k] = w * gpd[k];
                kv[6 * i + 3 + k] = w * om[k];
            }
        }
    }

    /// The derivatives of one kernel output s over the element's columns: the nodes'
    /// (δx, δθ) then z in `kq`, the nodes' (v, Ω) then ż in `kv`, the input signals in
    /// `ks`.
    #[inline(always)]
    fn columns<const M: usize>(
        &self,
        arms: &[NodeArms],
        s: &Dual<M>,
        kq: &mut [f64],
        kv: &mut [f64],
        ks: &mut [f64],
    ) {
        let ny = self.kinematic_directions();
        let (nq, ns) = (6 * self.nodes.len(), self.unsteady.states());
        self.to_nodes(arms, &s.d[..ny], &mut kq[..nq], &mut kv[..nq]);
        for j in 0..ns {
            kq[nq + j] = s.d[ny + j];
            kv[nq + j] = s.d[ny + ns + j];
        }
        for (k, o) in ks.iter_mut().take(self.inputs.len()).enumerate() {
            *o = s.d[ny + 2 * ns + k];
        }
    }
}

/// The six rows of a station Jacobian as slices.
#[inline(always)]
fn by_rows<const C: usize>(j: &[[f64; C]; 6]) -> [&[f64]; 6] {
    j.each_ref().map(|c| &c[..])
}

/// One column g of ∂(F, M) spread over the rows of every node, c −= L g (L the node
/// rows' map of [`AeroStation::tangents`], by columns): row by row over the six columns
/// of L in order (the zeros of the force rows add nothing), which the compiler
/// vectorizes across the rows. A zero column (∂/∂ż of the loads) adds nothing and is
/// skipped.
#[inline(always)]
fn spread_column(lmap: &[[f64; 6 * MAX_NODES]; 6], nq: usize, g: &[f64; 6], c: &mut [f64]) {
    if g.iter().all(|&v| v == 0.0) {
        return;
    }
    let c = &mut c[..nq];
    let l: [&[f64]; 6] = std::array::from_fn(|j| &lmap[j][..nq]);
    for r in 0..nq {
        c[r] -= l[0][r] * g[0]
            + l[1][r] * g[1]
            + l[2][r] * g[2]
            + l[3][r] * g[3]
            + l[4][r] * g[4]
            + l[5][r] * g[5];
    }
}

/// The columns `jac` (rows F₁ F₂ F₃ M₁ M₂ M₃ over the element's columns) spread into
/// `mat` column by column (the local matrices are column-major); the state columns (from
/// nq on in `jac`) sit `shift` further in the terms (a batch's block). With
/// `translation` (∂(F, M)/∂p, or ∂/∂ṗ) the translation columns of node j are that
/// station derivative times its weight wⱼ ([`AeroStation::to_nodes`]): spread once,
/// then scaled per node.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn spread_columns(
    lmap: &[[f64; 6 * MAX_NODES]; 6],
    nq: usize,
    weights: &[f64; MAX_NODES],
    jac: [&[f64]; 6],
    translation: Option<[[f64; 6]; 3]>,
    mat: &mut nalgebra::DMatrix<f64>,
    cols: usize,
    shift: usize,
) {
    let nr = mat.nrows();
    let mut spread_base = [[0.0; 6 * MAX_NODES]; 3];
    if let Some(b) = &translation {
        for (g, c) in b.iter().zip(&mut spread_base) {
            spread_column(lmap, nq, g, c);
        }
    }
    let values = mat.as_mut_slice();
    for col in 0..cols {
        let mc = if col < nq { col } else { col + shift };
        let c = &mut values[mc * nr..(mc + 1) * nr];
        if translation.is_some() && col < nq && col % 6 < 3 {
            let wj = weights[col / 6];
            for (x, b) in c[..nq].iter_mut().zip(&spread_base[col % 6][..nq]) {
                *x += wj * b;
            }
        } else {
            let g: [f64; 6] = std::array::from_fn(|o| jac[o][col]);
            spread_column(lmap, nq, &g, c);
        }
    }
}

/// A node's rotation and the station's node-frame vectors in global components
/// ([`AeroStation::node_arms`]).
#[derive(Clone, Copy, Debug, Default)]
struct NodeArms {
    r: Matrix3<f64>,
    offset: Vector3<f64>,
    chord: Vector3<f64>,
    normal: Vector3<f64>,
    offset_rate: Vector3<f64>,
    chord_rate: Vector3<f64>,
}

/// Rᵀ y, summed in the order of the columns of R.
fn tr_mul(r: &Matrix3<f64>, y: &V3<f64>) -> V3<f64> {
    std::array::from_fn(|k| y[0] * r[(0, k)] + y[1] * r[(1, k)] + y[2] * r[(2, k)])
}

/// Columns of an element's stiffness (or damping) rows: the nodes' 6 each and the states.
const COLUMNS: usize = 6 * MAX_NODES + MAX_STATES;

impl AeroStation {
    /// Local dual directions of the load kernel: the kinematics, the states and their
    /// rates, the input signals (at most 15 + 2·5 + 3 = 28).
    fn directions(&self) -> usize {
        self.kinematic_directions() + 2 * self.unsteady.states() + self.inputs.len()
    }

    /// The states' values and rates (zero beyond the station's states).
    fn state_values(&self, x: &ElementInput) -> ([f64; MAX_STATES], [f64; MAX_STATES]) {
        let mut z = [0.0; MAX_STATES];
        let mut zd = [0.0; MAX_STATES];
        for (j, s) in x.states.iter().take(self.unsteady.states()).enumerate() {
            (z[j], zd[j]) = (s.z, s.zd);
        }
        (z, zd)
    }

    /// The input signals (the rotor's inflow states) as f64, zero where absent.
    fn signal_values(&self, x: &ElementInput) -> [f64; MAX_INPUTS] {
        let mut s = [0.0; MAX_INPUTS];
        for (k, v) in x.signals.iter().take(self.inputs.len()).enumerate() {
            s[k] = *v;
        }
        s
    }

    /// The load kernel with M dual directions: the kinematics y at 0…ny, the states at
    /// ny + j, their rates at ny + ns + j, the input signals at ny + 2 ns + k.
    #[inline(always)]
    fn dual_pass<const M: usize, const INLINE: bool>(
        &self,
        ctx: &EvalContext,
        x: &ElementInput,
        zrows: &mut [Dual<M>; MAX_STATES],
    ) -> StationResult<Dual<M>> {
        let ny = self.kinematic_directions();
        let ns = self.unsteady.states();
        let ni = self.inputs.len();
        let kin = Self::seeded::<M>(&self.kinematics(x.nodes), ny == KINEMATICS);
        let mut z = [Dual::<M>::cst(0.0); MAX_STATES];
        let mut zd = [Dual::<M>::cst(0.0); MAX_STATES];
        for (j, st) in x.states.iter().take(ns).enumerate() {
            z[j] = Dual::var(st.z, ny + j);
            zd[j] = Dual::var(st.zd, ny + ns + j);
        }
        let sv = self.signal_values(x);
        let sig: [Dual<M>; MAX_INPUTS] = std::array::from_fn(|k| {
            if k < ni {
                Dual::var(sv[k], ny + 2 * ns + k)
            } else {
                Dual::cst(0.0)
            }
        });
        if INLINE {
            self.loads_body::<Dual<M>>(ctx.time, &kin, &z[..ns], &zd[..ns], &sig[..ni], zrows)
        } else {
            self.loads::<Dual<M>>(ctx.time, &kin, &z[..ns], &zd[..ns], &sig[..ni], zrows)
        }
    }

    /// Residual and tangents with M ≥ [`Self::directions`] dual directions: the loads'
    /// derivatives over the station's kinematics, chained to the nodes
    /// ([`Self::to_nodes`]), then distributed like the loads, with the node's own
    /// rotation in Rᵢᵀ: ∂(Rᵢᵀ y)/∂δθᵢ = (Rᵢᵀ y)~.
    #[inline(always)]
    fn tangents<const M: usize, const INLINE: bool>(
        &self,
        ctx: &EvalContext,
        x: &ElementInput,
        out: &mut LocalTerms,
    ) {
        let lf = ctx.load_factor;
        let nn = self.nodes.len();
        let ns = self.unsteady.states();
        let ni = self.inputs.len();
        let (nq, n) = (6 * nn, 6 * nn + ns);
        let mut zrows = [Dual::<M>::cst(0.0); MAX_STATES];
        let r = self.dual_pass::<M, INLINE>(ctx, x, &mut zrows);
        // ∂F/∂·, ∂M/∂· (rows F₁ F₂ F₃ M₁ M₂ M₃) over (q, z), (v, ż) and the signals.
        let mut jq = [[0.0; COLUMNS]; 6];
        let mut jv = [[0.0; COLUMNS]; 6];
        let mut js = [[0.0; MAX_INPUTS]; 6];
        let arms = self.node_arms(x.nodes);
        for (o, s) in r.force.iter().chain(&r.moment).enumerate() {
            self.columns(&arms, s, &mut jq[o], &mut jv[o], &mut js[o]);
        }
        let f = r.force.map(|s| s.v);
        let m = r.moment.map(|s| s.v);
        let mut rows = [[0.0f64; 3]; 2 * MAX_NODES];
        self.node_rows(x.nodes, &f, &m, &mut rows);
        self.last_power.set(lf * self.rows_power(x.nodes, &rows));
        for (b, row) in rows.iter().take(2 * nn).enumerate() {
            for (k, rk) in row.iter().enumerate() {
                out.r[3 * b + k] -= lf * rk;
            }
        }
        // Per node: the force rows take wᵢ ∂F, the moment rows wᵢ (d̃ᵢ Rᵢᵀ ∂F + Rᵢᵀ ∂M)
        // (load factor included): the node rows' map L = [wᵢ I 0; wᵢ d̃ᵢ Rᵢᵀ wᵢ Rᵢᵀ] stacked
        // over the nodes, stored by columns (`lmap[j]` the nq rows of column j).
        let mut w = [0.0; MAX_NODES];
        let mut lmap = [[0.0; 6 * MAX_NODES]; 6];
        for (i, (&nd, at)) in self.nodes.iter().zip(&self.attach).enumerate() {
            let rt = x.nodes[nd].r().transpose();
            let a = at.offset.cross_matrix() * rt;
            w[i] = lf * at.weight;
            for k in 0..3 {
                lmap[k][6 * i + k] = w[i];
                for j in 0..3 {
                    lmap[j][6 * i + 3 + k] = w[i] * a[(k, j)];
                    lmap[3 + j][6 * i + 3 + k] = w[i] * rt[(k, j)];
                }
            }
        }
        // The translation columns of node j are the station's ∂(F, M)/∂p (∂/∂ṗ in C)
        // times its weight ([`Self::to_nodes`]): spread once, then scaled per node.
        let base = |first: usize| -> [[f64; 6]; 3] {
            std::array::from_fn(|k| {
                std::array::from_fn(|o| {
                    if o < 3 {
                        r.force[o].d[first + k]
                    } else {
                        r.moment[o - 3].d[first + k]
                    }
                })
            })
        };
        let shift = out.state_shift;
        let weights: [f64; MAX_NODES] =
            std::array::from_fn(|i| self.attach.get(i).map_or(0.0, |a| a.weight));
        // (Calls, not a closure: inlined into the AVX copy.)
        let wts = &weights;
        let (jq, jv, js) = (by_rows(&jq), by_rows(&jv), by_rows(&js));
        spread_columns(&lmap, nq, wts, jq, Some(base(0)), &mut out.k, n, shift);
        spread_columns(&lmap, nq, wts, jv, Some(base(9)), &mut out.c, n, shift);
        spread_columns(&lmap, nq, wts, js, None, &mut out.ds, ni, 0);
        // The node's own rotation in Rᵢᵀ F, Rᵢᵀ M: ∂(Rᵢᵀ y)/∂δθᵢ = (Rᵢᵀ y)~.
        for (i, (&nd, at)) in self.nodes.iter().zip(&self.attach).enumerate() {
            let rt = x.nodes[nd].r().transpose();
            let ft = rt * Vector3::from(f);
            let mt = rt * Vector3::from(m);
            for j in 0..3 {
                let e = Vector3::ith(j, 1.0);
                let g = at.offset.cross(&ft.cross(&e)) + mt.cross(&e);
                for k in 0..3 {
                    out.k[(6 * i + 3 + k, 6 * i + 3 + j)] -= w[i] * g[k];
                }
            }
        }
        // State rows: not loads, not scaled by the load factor.
        let mut kq = [0.0; COLUMNS];
        let mut kv = [0.0; COLUMNS];
        let mut ks = [0.0; MAX_INPUTS];
        for (s, zr) in zrows.iter().take(ns).enumerate() {
            let ri = nq + shift + s;
            out.r[ri] += zr.v;
            self.columns(&arms, zr, &mut kq, &mut kv, &mut ks);
            for j in 0..n {
                let cj = if j < nq { j } else { j + shift };
                out.k[(ri, cj)] += kq[j];
                out.c[(ri, cj)] += kv[j];
            }
            for (j, v) in ks.iter().enumerate().take(ni) {
                out.ds[(ri, j)] += v;
            }
        }
    }

    /// The produced thrust signals and their derivatives (M dual directions), scaled by
    /// the load factor like the loads.
    fn signal_terms<const M: usize>(
        &self,
        ctx: &EvalContext,
        x: &ElementInput,
        out: &mut SignalTerms,
    ) {
        let lf = ctx.load_factor;
        let n = 6 * self.nodes.len() + self.unsteady.states();
        let ni = self.inputs.len();
        let mut zrows = [Dual::<M>::cst(0.0); MAX_STATES];
        let r = self.dual_pass::<M, false>(ctx, x, &mut zrows);
        let mut kq = [0.0; COLUMNS];
        let mut kv = [0.0; COLUMNS];
        let mut ks = [0.0; MAX_INPUTS];
        let arms = self.node_arms(x.nodes);
        for (o, f) in r.rotor_forcing.iter().enumerate() {
            out.values[o] = lf * f.v;
            self.columns(&arms, f, &mut kq, &mut kv, &mut ks);
            for j in 0..n {
                out.k[(o, j)] = lf * kq[j];
                out.c[(o, j)] = lf * kv[j];
            }
            for (j, v) in ks.iter().enumerate().take(ni) {
                out.ds[(o, j)] = lf * v;
            }
        }
    }

    /// Residual only (f64); with `INLINE` the load kernel inlined (the AVX copy,
    /// [`Self::evaluate_body`]).
    #[inline(always)]
    fn residual<const INLINE: bool>(
        &self,
        ctx: &EvalContext,
        x: &ElementInput,
        out: &mut LocalTerms,
    ) {
        let nn = self.nodes.len();
        let ns = self.unsteady.states();
        let mut rows = [[0.0f64; 3]; 2 * MAX_NODES];
        let mut zrows = [0.0; MAX_STATES];
        let (z, zd) = self.state_values(x);
        let sv = self.signal_values(x);
        let (z, zd, sig) = (&z[..ns], &zd[..ns], &sv[..self.inputs.len()]);
        if INLINE {
            let kin = self.kinematics(x.nodes);
            let r = self.loads_body::<f64>(ctx.time, &kin, z, zd, sig, &mut zrows);
            self.node_rows(x.nodes, &r.force, &r.moment, &mut rows);
        } else {
            self.compute(ctx.time, x.nodes, z, zd, sig, &mut rows, &mut zrows);
        }
        self.last_power
            .set(ctx.load_factor * self.rows_power(x.nodes, &rows));
        for (b, row) in rows.iter().take(2 * nn).enumerate() {
            for (k, rk) in row.iter().enumerate() {
                out.r[3 * b + k] -= ctx.load_factor * rk;
            }
        }
        for (s, zr) in zrows.iter().take(ns).enumerate() {
            out.r[6 * nn + out.state_shift + s] += zr;
        }
    }
}

impl AeroStation {
    /// [`Self::tangents`] with the dual directions of the station (its kinematics,
    /// states, rates and signals, at most 15 + 2·6 + 3) rounded up to the sizes compiled.
    #[inline(always)]
    fn tangents_of_size<const INLINE: bool>(
        &self,
        ctx: &EvalContext,
        x: &ElementInput,
        out: &mut LocalTerms,
    ) {
        match self.directions() {
            0..=12 => self.tangents::<12, INLINE>(ctx, x, out),
            13..=16 => self.tangents::<16, INLINE>(ctx, x, out),
            17..=20 => self.tangents::<20, INLINE>(ctx, x, out),
            21..=28 => self.tangents::<28, INLINE>(ctx, x, out),
            _ => self.tangents::<{ KINEMATICS + 2 * MAX_STATES + MAX_INPUTS }, INLINE>(ctx, x, out),
        }
    }

    /// The residual alone or with the tangents; with `INLINE` the load kernel inlined (the
    /// AVX copy of [`Element::evaluate`]). Loads are applied loads: scaled by the load
    /// factor in statics.
    #[inline(always)]
    fn evaluate_body<const INLINE: bool>(
        &self,
        ctx: &EvalContext,
        x: &ElementInput,
        need: Need,
        out: &mut LocalTerms,
    ) {
        if need == Need::Residual {
            self.residual::<INLINE>(ctx, x, out)
        } else {
            self.tangents_of_size::<INLINE>(ctx, x, out)
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

    fn n_states(&self) -> usize {
        self.unsteady.states()
    }

    fn state_names(&self) -> Vec<String> {
        let mut v = Vec::new();
        if self.unsteady.wagner_states() == 2 {
            v.extend(["wagner_1".to_string(), "wagner_2".to_string()]);
        }
        if self.unsteady.kussner_states() == 2 {
            v.extend(["kussner_1".to_string(), "kussner_2".to_string()]);
        }
        if self.unsteady.stall.is_some() {
            v.push("separation".into());
        }
        if self.unsteady.hgm.is_some() {
            v.extend(["hgm_1", "hgm_2", "hgm_3", "hgm_4"].map(String::from));
        }
        if self.unsteady.dynamic_wake {
            v.extend(["wake_1".to_string(), "wake_2".to_string()]);
        }
        v
    }

    fn initial_states(&self, out: &mut [f64]) {
        let ns = self.unsteady.states();
        out[..ns].copy_from_slice(&self.initial[..ns]);
    }

    isa::copies! {
        /// On CPUs with AVX in a copy compiled for AVX, the load kernel inlined into it:
        /// the dual numbers' arithmetic, the kinematics and the spreading over the node
        /// rows run four lanes wide instead of two. The same operations in the same order
        /// (no fused multiply–add), so the same results to the bit (as the assembler's and
        /// the block LU's AVX copies); the wind, BEM root, airfoil tables and stall curves
        /// it calls are not affected.
        fn evaluate(
            &self: AeroStation,
            ctx: &EvalContext,
            x: &ElementInput,
            need: Need,
            out: &mut LocalTerms,
        ) {
            Base => evaluate_body::<false>,
            Avx => evaluate_body::<true>,
        }
    }

    fn accumulates(&self) -> bool {
        true
    }

    /// Loads only: no kinetic or potential energy, no dissipation (the default zeros).
    fn loads_only(&self) -> bool {
        true
    }

    fn signal_inputs(&self) -> &[String] {
        &self.inputs
    }

    fn signal_outputs(&self) -> &[String] {
        &self.outputs
    }

    fn signals(&self, ctx: &EvalContext, x: &ElementInput, out: &mut SignalTerms) {
        if self.outputs.is_empty() {
            return;
        }
        match self.directions() {
            0..=12 => self.signal_terms::<12>(ctx, x, out),
            13..=16 => self.signal_terms::<16>(ctx, x, out),
            17..=20 => self.signal_terms::<20>(ctx, x, out),
            21..=28 => self.signal_terms::<28>(ctx, x, out),
            _ => self.signal_terms::<{ KINEMATICS + 2 * MAX_STATES + MAX_INPUTS }>(ctx, x, out),
        }
    }

    /// The power of the loads on the nodes ([`Self::power`]) at `x`.
    fn external_power(&self, ctx: &EvalContext, x: &ElementInput) -> f64 {
        let mut zrows = [0.0; MAX_STATES];
        let (z, zd) = self.state_values(x);
        let ns = self.unsteady.states();
        let sv = self.signal_values(x);
        let kin = self.kinematics(x.nodes);
        let r = self.loads::<f64>(
            ctx.time,
            &kin,
            &z[..ns],
            &zd[..ns],
            &sv[..self.inputs.len()],
            &mut zrows,
        );
        ctx.load_factor * self.power(x.nodes, &r.force, &r.moment, &kin.pd)
    }

    /// The power at the station's last residual evaluation (the last Newton iterate of a
    /// step), kept by the evaluation; at `x` before the first.
    fn evaluated_power(&self, ctx: &EvalContext, x: &ElementInput) -> f64 {
        self.last_power
            .get()
            .unwrap_or_else(|| self.external_power(ctx, x))
    }

    fn output_names(&self) -> Vec<(String, &'static str)> {
        let mut v: Vec<(String, &'static str)> =
            OUTPUTS.iter().map(|(n, u)| (n.to_string(), *u)).collect();
        if self.unsteady.wagner_states() == 2 || self.unsteady.hgm.is_some() {
            v.push(("effective_alpha".into(), "rad"));
        }
        if self.user_property.is_some() {
            v.push(("user_property".into(), "1"));
        } else if self.section.viscosity.is_some() {
            v.push(("reynolds".into(), "1"));
        }
        v
    }

    fn outputs(&self, ctx: &EvalContext, x: &ElementInput, out: &mut [f64]) {
        let mut rows = [[0.0f64; 3]; 2 * MAX_NODES];
        let mut zrows = [0.0; MAX_STATES];
        let (z, zd) = self.state_values(x);
        let ns = self.unsteady.states();
        let sv = self.signal_values(x);
        let r = self.compute(
            ctx.time,
            x.nodes,
            &z[..ns],
            &zd[..ns],
            &sv[..self.inputs.len()],
            &mut rows,
            &mut zrows,
        );
        let mut k = OUTPUTS.len();
        if self.unsteady.wagner_states() == 2 || self.unsteady.hgm.is_some() {
            out[k] = r.alpha_effective;
            k += 1;
        }
        if self.user_property.is_some() || self.section.viscosity.is_some() {
            out[k] = r.reynolds;
        }
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
            self.span,
        ];
        out[..vals.len()].copy_from_slice(&vals);
    }

    fn breakpoints(&self, out: &mut Vec<f64>) {
        out.extend(self.wind.breakpoints(self.gust_x));
    }

    fn begin_analysis(&self) {
        self.root_hint.clear();
        self.last_power.clear();
    }

    fn runtime_error(&self) -> Option<(String, String)> {
        self.wind
            .outside_sample()
            .map(|w| (w.to_string(), super::wind::OUTSIDE_HINT.to_string()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::ElementState;

    /// A node in a generic state from `k` (deterministic; components of order one).
    fn generic_node(k: u64) -> NodeState {
        let val = |j: u64| ((k * 31 + j) as f64 * 0.754_877_666).fract() * 2.0 - 1.0;
        let v3 = |j: u64| Vector3::new(val(j), val(j + 1), val(j + 2));
        NodeState {
            x: v3(0),
            rot: crate::math::Rotation::exp(&(v3(3) * 2.0)),
            v: v3(6),
            w: v3(9) * 2.0,
            a: v3(12),
            wd: v3(15),
        }
    }

    /// A station with Øye's stall near a spinning blade at r ≈ 2 (BEM finds its windmill
    /// root), on seven generic nodes.
    fn spinning_station() -> (AeroStation, Vec<NodeState>) {
        let airfoil = Arc::new(Airfoil::thin_plate_with_drag());
        let stall = Arc::new(OyeStall::new(&airfoil).expect("a lifting airfoil"));
        let wind = Arc::new(Wind {
            speed: 9.0,
            direction: Vector3::new(1.0, 0.2, -0.1).normalize(),
            shear_exponent: 0.2,
            reference_height: 2.0,
            ..Default::default()
        });
        let inflow = Arc::new(Inflow::Bem {
            rotor: BemRotor {
                blades: 3,
                hub_radius: 0.2,
                tip_radius: 4.0,
                tip_loss: true,
                hub_loss: true,
                tangential_induction: true,
                skewed_wake: false,
            },
            centre: Vector3::zeros(),
            axis: Vector3::x(),
        });
        let section = Section {
            chord: 0.4,
            width: 0.3,
            airfoil,
            viscosity: None,
        };
        // Nodes near a spinning blade station at r ≈ 2 (BEM finds its windmill root).
        let nodes: Vec<NodeState> = (0..7)
            .map(|i| {
                let mut n = generic_node(900 + i);
                n.x = Vector3::new(0.05, 0.1, 2.0) + 0.02 * n.x;
                n.v = Vector3::new(0.3, -12.0, 0.2) + 0.1 * n.v;
                n.w *= 0.3;
                n
            })
            .collect();
        let attach: Vec<Attachment> = (0..7)
            .map(|i| Attachment {
                weight: (1.0 + 0.3 * (i as f64).sin()) / 7.0,
                offset: Vector3::new(0.1 * i as f64, -0.2, 0.3),
                chord_dir: Vector3::new(0.0, 1.0, 0.1 * i as f64).normalize(),
                normal_dir: Vector3::new(1.0, 0.0, 0.05).normalize(),
            })
            .collect();
        let unsteady = Unsteady {
            attached: AttachedFlow::QuasiSteady,
            stall: Some((stall, 4.0)),
            dynamic_wake: false,
            hgm: None,
            kussner: false,
        };
        let e = AeroStation::new("aero", (0..7).collect(), attach, section, 1.2, wind, inflow)
            .with_unsteady(unsteady, 0.0, &nodes);
        (e, nodes)
    }

    /// The AVX copy of the tangents ([`AeroStation::evaluate_body`], taken by `evaluate`
    /// on CPUs with AVX) and the baseline copy give the same residual and tangents to the
    /// bit: a BEM station with Øye's dynamic stall on the 7 nodes of an order-6 beam
    /// element, at generic node states (reference: the baseline copy itself; tolerance
    /// zero, since the AVX copy only widens the vectors — no fused multiply–add).
    #[test]
    fn avx_and_baseline_copies_agree_to_the_bit() {
        #[cfg(target_arch = "x86_64")]
        if isa::Isa::detected() >= isa::Isa::Avx {
            let (e, nodes) = spinning_station();
            let states = [ElementState { z: 0.6, zd: 0.05 }];
            let x = ElementInput {
                states: &states,
                ..ElementInput::nodes(&nodes)
            };
            let ctx = EvalContext {
                time: 0.3,
                gravity: Vector3::zeros(),
                load_factor: 1.0,
            };
            let (mut wide, mut base) = (LocalTerms::for_element(&e), LocalTerms::for_element(&e));
            for t in [&mut wide, &mut base] {
                t.clear(Need::ResidualAndTangents);
            }
            // Each from a cleared BEM root hint (the warm start changes the last bits).
            e.begin_analysis();
            e.evaluate(&ctx, &x, Need::ResidualAndTangents, &mut wide);
            e.begin_analysis();
            e.tangents_of_size::<false>(&ctx, &x, &mut base);
            let bits = |t: &LocalTerms| -> Vec<u64> {
                [
                    t.r.as_slice(),
                    t.k.as_slice(),
                    t.c.as_slice(),
                    t.ds.as_slice(),
                ]
                .iter()
                .flat_map(|s| s.iter().map(|v| v.to_bits()))
                .collect()
            };
            assert!(wide.k.iter().any(|&v| v != 0.0));
            assert_eq!(bits(&wide), bits(&base));
            // The residual-only copies too, and the power each keeps.
            let mut powers = Vec::new();
            for t in [&mut wide, &mut base] {
                t.clear(Need::Residual);
            }
            e.begin_analysis();
            e.evaluate(&ctx, &x, Need::Residual, &mut wide);
            powers.push(e.evaluated_power(&ctx, &x));
            e.begin_analysis();
            e.residual::<false>(&ctx, &x, &mut base);
            powers.push(e.evaluated_power(&ctx, &x));
            let r_bits = |t: &LocalTerms| -> Vec<u64> { t.r.iter().map(|v| v.to_bits()).collect() };
            assert!(wide.r.iter().any(|&v| v != 0.0));
            assert_eq!(r_bits(&wide), r_bits(&base));
            assert_eq!(powers[0].to_bits(), powers[1].to_bits());
            // The kept power is the loads' power at x, up to rounding.
            let exact = e.external_power(&ctx, &x);
            assert!(
                (powers[0] - exact).abs() <= 1e-12 * exact.abs(),
                "{powers:?} {exact}"
            );
        }
    }

    /// A station applies loads only ([`Element::loads_only`]): the energy sums skip it, so
    /// its energies and dissipated power must be zero.
    #[test]
    fn a_station_stores_and_dissipates_no_energy() {
        let (e, nodes) = spinning_station();
        let states = [ElementState { z: 0.6, zd: 0.05 }];
        let x = ElementInput {
            states: &states,
            ..ElementInput::nodes(&nodes)
        };
        let ctx = EvalContext {
            time: 0.3,
            gravity: Vector3::new(0.0, 0.0, -9.81),
            load_factor: 1.0,
        };
        assert!(e.loads_only());
        assert_ne!(e.external_power(&ctx, &x), 0.0);
        for v in [
            e.kinetic_energy(&x),
            e.potential_energy(&ctx, &x),
            e.discrete_kinetic_energy(&x),
            e.discrete_potential_energy(&ctx, &x),
            e.dissipated_power(&x),
            e.evaluated_dissipated_power(&x),
        ] {
            assert_eq!(v, 0.0);
        }
    }
}
