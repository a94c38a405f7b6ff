//! The generic tangent check: every element's `K, C, M` and every constraint's `B`,
//! `∂(Bᵀμ)/∂(q, ν)`, rate terms (`Φ_t`, convective acceleration) and coordinate-element
//! tangents against central finite differences taken on the configuration manifold
//! (`x + ε e_k`, `R exp(ε ẽ_k)`, `ν + ε`).
//!
//! Central differences with step ε have truncation error O(ε²) and round-off error
//! O(u/ε) relative to the residual's magnitude (u = 2.2e-16); ε = 1e-6 balances them at
//! about 1e-10, so a relative mismatch above 1e-6 is a wrong tangent, not noise.
//!
//! **Scaling per entry, not by the whole matrix.** A mismatch is measured against the size
//! that matters for its own entry, not against the largest entry of the matrix: with
//! realistic sections (EA ~ 1e9 beside GJ ~ 1e3) an error in the torsion terms would
//! otherwise hide under the axial ones. Scaling each 3×3 (node, translation or rotation)
//! block by its own size is not enough either: in a shear-deformable beam a rotation
//! block holds the shear stiffness (rotating a section shears it, ~GA) beside the torsion
//! term, so a 1 % torsion error reads 4.5e-7 of its block (tests/beam_tangents.rs). The
//! scale of entry (i, j) is the largest of
//! - its own size, |Aᵢⱼ| or |Dᵢⱼ| (analytic, finite difference);
//! - for square matrices, √|Aᵢᵢ Aⱼⱼ| — the symmetric (Jacobi) diagonal scaling, the
//!   entry's size in the energy norm of the two unknowns it couples;
//! - `RESOLUTION` times what the finite difference can resolve there: the larger of its
//!   round-off, u |r| / ε with |r| the largest residual (or Φ, Bᵀμ) of the entry's row
//!   group — a row's residual can be far larger than the entry (the moment rows of a beam
//!   carry x′ × F with F ~ EA ε) — and its truncation, estimated by the largest
//!   |D(ε) − D(2ε)| in the entry's 3×3 block; so an entry the finite difference cannot
//!   resolve better than its own error reads ~1/`RESOLUTION` = 1e-7;
//! - 1e-14 of the largest entry of the matrix (entries that are round-off).
//!
//! Row and column groups are 3 per node (translation, rotation) and 1 per scalar
//! (constraint equation, joint coordinate).

use crate::core::{
    Constraint, Coordinate, CoordinateTangents, Element, ElementInput, ElementState, EvalContext,
    LocalTerms, Need, NodeState, RowTerms, SignalTerms,
};
use nalgebra::{DMatrix, Vector3};
use std::ops::Range;

/// Finite-difference step.
pub const EPS: f64 = 1e-6;

/// What is perturbed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Slot {
    Configuration,
    Velocity,
    Acceleration,
}

fn perturb(nodes: &mut [NodeState], node: usize, dof: usize, h: f64, slot: Slot) {
    let n = &mut nodes[node];
    let mut e = Vector3::zeros();
    e[dof % 3] = h;
    match (slot, dof < 3) {
        (Slot::Configuration, true) => n.x += e,
        (Slot::Configuration, false) => n.rot = n.rot.compose_exp(&e),
        (Slot::Velocity, true) => n.v += e,
        (Slot::Velocity, false) => n.w += e,
        (Slot::Acceleration, true) => n.a += e,
        (Slot::Acceleration, false) => n.wd += e,
    }
}

/// Factor on the finite difference's error estimate in an entry's scale (module doc).
pub const RESOLUTION: f64 = 1e7;

/// Largest entry-wise mismatch between an analytic matrix and its finite difference,
/// relative to the entry's scale (module doc); a non-finite mismatch is reported as
/// infinite.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mismatch {
    pub relative: f64,
    pub row: usize,
    pub col: usize,
    /// The scale of the worst entry.
    pub scale: f64,
}

/// Row or column groups: 3 per node (translation, rotation), then one per scalar unknown
/// or equation.
fn groups(n_nodes: usize, n_scalars: usize) -> Vec<Range<usize>> {
    let mut g: Vec<Range<usize>> = (0..2 * n_nodes).map(|k| 3 * k..3 * k + 3).collect();
    let start = 6 * n_nodes;
    g.extend((0..n_scalars).map(|k| start + k..start + k + 1));
    g
}

/// Compares `analytic` with the finite differences at steps ε (`fd[0]`) and 2ε (`fd[1]`);
/// `magnitude[i]` is |rᵢ|, the size of the function differenced in row i.
fn compare(
    analytic: &DMatrix<f64>,
    fd: &[DMatrix<f64>; 2],
    magnitude: &[f64],
    rows: &[Range<usize>],
    cols: &[Range<usize>],
) -> Mismatch {
    let [fd, fd2] = fd;
    let global = analytic.amax().max(fd.amax());
    let square = rows == cols;
    let mut worst = Mismatch {
        relative: 0.0,
        row: 0,
        col: 0,
        scale: 0.0,
    };
    for rb in rows {
        let round_off = rb.clone().fold(0.0f64, |m, i| {
            m.max(magnitude.get(i).map_or(0.0, |x| x.abs()))
        }) * f64::EPSILON
            / EPS;
        for cb in cols {
            let mut truncation = 0.0f64;
            for j in cb.clone() {
                for i in rb.clone() {
                    truncation = truncation.max((fd[(i, j)] - fd2[(i, j)]).abs());
                }
            }
            let floor = (RESOLUTION * round_off.max(truncation)).max(1e-14 * global);
            for j in cb.clone() {
                for i in rb.clone() {
                    let diagonal = if square {
                        (analytic[(i, i)] * analytic[(j, j)]).abs().sqrt()
                    } else {
                        0.0
                    };
                    let scale = analytic[(i, j)]
                        .abs()
                        .max(fd[(i, j)].abs())
                        .max(diagonal)
                        .max(floor);
                    let d = (analytic[(i, j)] - fd[(i, j)]).abs();
                    let r = if d == 0.0 {
                        0.0
                    } else if (d / scale).is_finite() {
                        d / scale
                    } else {
                        f64::INFINITY
                    };
                    if r > worst.relative {
                        worst = Mismatch {
                            relative: r,
                            row: i,
                            col: j,
                            scale,
                        };
                    }
                }
            }
        }
    }
    worst
}

/// The largest of some mismatches; NaN counts as infinite (`f64::max` would drop it).
fn largest(values: &[f64]) -> f64 {
    values.iter().fold(
        0.0,
        |a, &x| if x.is_nan() { f64::INFINITY } else { a.max(x) },
    )
}

/// Mismatches of an element's K, C, M, its ∂r/∂s, and (for producers) the derivatives of
/// its signals.
#[derive(Clone, Copy, Debug)]
pub struct ElementReport {
    pub k: Mismatch,
    pub c: Mismatch,
    pub m: Mismatch,
    /// ∂r/∂s of the input signals.
    pub ds: Mismatch,
    /// Derivatives of the produced signals: K, C, M channels and ∂s_out/∂s_in.
    pub signal_k: Mismatch,
    pub signal_c: Mismatch,
    pub signal_m: Mismatch,
    pub signal_ds: Mismatch,
}

impl ElementReport {
    pub fn worst(&self) -> f64 {
        largest(&[
            self.k.relative,
            self.c.relative,
            self.m.relative,
            self.ds.relative,
            self.signal_k.relative,
            self.signal_c.relative,
            self.signal_m.relative,
            self.signal_ds.relative,
        ])
    }
}

/// Checks an element with nodes only at the given node states.
pub fn check_element(e: &dyn Element, ctx: &EvalContext, nodes: &[NodeState]) -> ElementReport {
    check_element_with(e, ctx, nodes, &[], &[])
}

/// The local unknown `col` of an element perturbed by `h` in `slot`: node dofs on the
/// manifold, state values (configuration slot) and rates (velocity slot); a state has no
/// acceleration, so that slot leaves it alone.
fn perturb_local(
    nodes: &mut [NodeState],
    states: &mut [ElementState],
    element_nodes: &[usize],
    col: usize,
    h: f64,
    slot: Slot,
) {
    let n6 = 6 * element_nodes.len();
    if col < n6 {
        perturb(nodes, element_nodes[col / 6], col % 6, h, slot);
    } else {
        let z = &mut states[col - n6];
        match slot {
            Slot::Configuration => z.z += h,
            Slot::Velocity => z.zd += h,
            Slot::Acceleration => {}
        }
    }
}

/// Checks an element at the given node states, own states and input-signal values:
/// K, C, M against central differences of its residual, `∂r/∂s` against differences in the
/// inputs, and the derivatives of the signals it produces the same way.
pub fn check_element_with(
    e: &dyn Element,
    ctx: &EvalContext,
    nodes: &[NodeState],
    states: &[ElementState],
    signals: &[f64],
) -> ElementReport {
    check_element_held(e, ctx, nodes, states, signals, &[])
}

/// [`check_element_with`] with the element's sample-and-hold values `held` (empty: none
/// held, a hold passes its input through as in statics).
pub fn check_element_held(
    e: &dyn Element,
    ctx: &EvalContext,
    nodes: &[NodeState],
    states: &[ElementState],
    signals: &[f64],
    held: &[f64],
) -> ElementReport {
    let en = e.nodes().to_vec();
    let nz = e.n_states();
    let n_in = e.signal_inputs().len();
    let n_out = e.signal_outputs().len();
    let zero_states = vec![ElementState::default(); nz];
    let states = if states.len() == nz {
        states
    } else {
        &zero_states
    };
    let zero_signals = vec![0.0; n_in];
    let signals = if signals.len() == n_in {
        signals
    } else {
        &zero_signals
    };
    let n = 6 * en.len() + nz;
    let mut t = LocalTerms::for_element(e);
    t.clear(Need::ResidualAndTangents);
    let mut st = SignalTerms::for_element(e);
    {
        let x = ElementInput {
            nodes,
            states,
            signals,
            held,
        };
        e.evaluate(ctx, &x, Need::ResidualAndTangents, &mut t);
        st.clear();
        e.signals(ctx, &x, &mut st);
    }
    let mut work = nodes.to_vec();
    let mut wz = states.to_vec();
    let mut ws = signals.to_vec();
    let mut tp = LocalTerms::for_element(e);
    let mut sp = SignalTerms::for_element(e);
    // Residual and produced signals at a perturbed input, as one vector.
    let mut eval = |work: &[NodeState], wz: &[ElementState], ws: &[f64]| -> Vec<f64> {
        let x = ElementInput {
            nodes: work,
            states: wz,
            signals: ws,
            held,
        };
        tp.clear(Need::Residual);
        e.evaluate(ctx, &x, Need::Residual, &mut tp);
        sp.clear();
        e.signals(ctx, &x, &mut sp);
        tp.r.iter().chain(sp.values.iter()).copied().collect()
    };
    // Central differences at steps ε and 2ε: rows are the residual then the signals.
    let rows = n + n_out;
    let mut fd = |slot: Option<Slot>, cols: usize| -> [DMatrix<f64>; 2] {
        let mut out = [DMatrix::zeros(rows, cols), DMatrix::zeros(rows, cols)];
        for col in 0..cols {
            for (o, step) in out.iter_mut().zip([EPS, 2.0 * EPS]) {
                let mut r = [Vec::new(), Vec::new()];
                for (k, s) in [1.0, -1.0].iter().enumerate() {
                    work.clone_from_slice(nodes);
                    wz.clone_from_slice(states);
                    ws.clone_from_slice(signals);
                    match slot {
                        Some(slot) => perturb_local(&mut work, &mut wz, &en, col, s * step, slot),
                        None => ws[col] += s * step,
                    }
                    r[k] = eval(&work, &wz, &ws);
                }
                for i in 0..rows {
                    o[(i, col)] = (r[0][i] - r[1][i]) / (2.0 * step);
                }
            }
        }
        out
    };
    let split = |m: [DMatrix<f64>; 2]| -> ([DMatrix<f64>; 2], [DMatrix<f64>; 2]) {
        let c = m[0].ncols();
        let top = |x: &DMatrix<f64>| x.view((0, 0), (n, c)).into_owned();
        let bottom = |x: &DMatrix<f64>| x.view((n, 0), (n_out, c)).into_owned();
        ([top(&m[0]), top(&m[1])], [bottom(&m[0]), bottom(&m[1])])
    };
    let (k_fd, sk_fd) = split(fd(Some(Slot::Configuration), n));
    let (c_fd, sc_fd) = split(fd(Some(Slot::Velocity), n));
    let (m_fd, sm_fd) = split(fd(Some(Slot::Acceleration), n));
    let (ds_fd, sds_fd) = split(fd(None, n_in));
    let g = groups(en.len(), nz);
    let inputs = groups(0, n_in);
    let outputs = groups(0, n_out);
    let r = t.r.as_slice();
    let sv = st.values.as_slice();
    ElementReport {
        k: compare(&t.k, &k_fd, r, &g, &g),
        c: compare(&t.c, &c_fd, r, &g, &g),
        m: compare(&t.m, &m_fd, r, &g, &g),
        ds: compare(&t.ds, &ds_fd, r, &g, &inputs),
        signal_k: compare(&st.k, &sk_fd, sv, &outputs, &g),
        signal_c: compare(&st.c, &sc_fd, sv, &outputs, &g),
        signal_m: compare(&st.m, &sm_fd, sv, &outputs, &g),
        signal_ds: compare(&st.ds, &sds_fd, sv, &outputs, &inputs),
    }
}

/// Mismatches of a constraint's B, ∂(Bᵀμ)/∂(q, ν), rate terms and coordinate elements.
#[derive(Clone, Copy, Debug)]
pub struct ConstraintReport {
    pub b: Mismatch,
    pub k: Mismatch,
    /// ∂(B v)/∂(q, ν) at fixed local rates v ([`Constraint::velocity_tangent`]).
    pub velocity_tangent: Mismatch,
    /// Relative error of Φ̈ − B(v̇, ν̈) against the second difference along the motion.
    pub convective: f64,
    /// Relative error of Φ_t against the first difference along the motion minus B·v.
    pub velocity: f64,
    /// ∂r/∂ν and ∂r/∂ν̇ of the coordinate elements.
    pub coordinate_stiffness: Mismatch,
    pub coordinate_damping: Mismatch,
    /// ∂r/∂s of the input ports.
    pub coordinate_signals: Mismatch,
    /// Servo rows ([`crate::core::ServoRow`]): the largest deviation from their contract,
    /// Φ = ν_c − s with the target s given to `evaluate_rows`, ∂Φ/∂s = −1 (a difference
    /// in the target), B = e_ν (the system adds −∂s/∂x), zero rate terms.
    pub servo: f64,
    /// Largest difference, relative to each term's largest entry, between the one
    /// evaluation of [`Constraint::evaluate_rows`] (with the tangent, and residual only)
    /// and the separate `evaluate` (with B, and Φ alone), `reaction_tangent` and `Bᵀμ`, and between
    /// `velocity_tangent` and `vᵀ` times `reaction_tangent` at each μ = e_r (round-off).
    pub combined: f64,
}

impl ConstraintReport {
    pub fn worst(&self) -> f64 {
        largest(&[
            self.b.relative,
            self.k.relative,
            self.velocity_tangent.relative,
            self.convective,
            self.velocity,
            self.coordinate_stiffness.relative,
            self.coordinate_damping.relative,
            self.coordinate_signals.relative,
            self.servo,
            self.combined,
        ])
    }
}

/// Checks a constraint at the given node states and joint coordinates with multipliers
/// `mu`; the rate terms are checked along the motion with the nodes' velocities, the
/// coordinates' rates and time.
pub fn check_constraint(
    c: &dyn Constraint,
    ctx: &EvalContext,
    nodes: &[NodeState],
    coords: &[Coordinate],
    mu: &[f64],
) -> ConstraintReport {
    let cn = c.nodes().to_vec();
    let m = c.n_equations();
    let nc = c.n_coordinates();
    let nq = 6 * cn.len();
    let n = nq + nc;
    // The analytic terms from the one evaluation the assembler makes (λ = μ, ρ = 0), and
    // the same from the separate calls, which must agree with it to round-off.
    let mut phi = vec![0.0; m];
    let mut b = DMatrix::zeros(m, n);
    let mut k = DMatrix::zeros(n, n);
    let mut mu_out = vec![0.0; m];
    let mut force = vec![0.0; n];
    // Servo rows get non-zero targets (their signals' values).
    let mut targets = vec![0.0; m];
    let servo_rows: Vec<(usize, crate::core::ServoRow)> = c
        .servo_rows()
        .iter()
        .filter_map(|s| Some((c.active_rows().iter().position(|&r| r == s.row)?, *s)))
        .collect();
    for (j, (i, _)) in servo_rows.iter().enumerate() {
        targets[*i] = 0.41 + 0.1 * j as f64;
    }
    c.evaluate_rows(
        ctx,
        nodes,
        coords,
        mu,
        0.0,
        RowTerms {
            phi: &mut phi,
            mu: &mut mu_out,
            force: &mut force,
            b: &mut b,
            want_b: false,
            tangent: Some(&mut k),
            targets: &targets,
        },
    );
    let mut phi_s = vec![0.0; m];
    let mut b_s = DMatrix::zeros(m, n);
    c.evaluate(ctx, nodes, coords, &mut phi_s, Some(&mut b_s));
    // Φ alone (the constraint check's evaluation) against Φ with B.
    let mut phi_only = vec![0.0; m];
    c.evaluate(ctx, nodes, coords, &mut phi_only, None);
    // The servo contract: Φ = ν_c (− s in evaluate_rows), B = e_ν, zero rate terms,
    // and ∂Φ/∂s = −1 against a difference in the target.
    let mut servo: f64 = 0.0;
    {
        let mut conv = vec![0.0; m];
        c.acceleration_term(ctx, nodes, coords, &mut conv);
        let mut phi_t = vec![0.0; m];
        c.velocity_term(ctx, &mut phi_t);
        let (mut mu_p, mut f_p, mut b_p) = (vec![0.0; m], vec![0.0; n], DMatrix::zeros(m, n));
        let mut phi_p = vec![0.0; m];
        for &(i, s) in &servo_rows {
            let col = nq + s.coordinate;
            for j in 0..n {
                let e = if j == col { 1.0 } else { 0.0 };
                servo = servo.max((b_s[(i, j)] - e).abs());
            }
            servo = servo.max((phi_s[i] - coords[s.coordinate].q).abs());
            servo = servo.max(conv[i].abs()).max(phi_t[i].abs());
            servo = servo.max(usize::from(s.input >= c.signal_inputs().len()) as f64);
            let mut tp = targets.clone();
            tp[i] += EPS;
            c.evaluate_rows(
                ctx,
                nodes,
                coords,
                mu,
                0.0,
                RowTerms {
                    phi: &mut phi_p,
                    mu: &mut mu_p,
                    force: &mut f_p,
                    b: &mut b_p,
                    want_b: false,
                    tangent: None,
                    targets: &tp,
                },
            );
            servo = servo.max(((phi_p[i] - phi[i]) / EPS + 1.0).abs());
        }
    }
    // The local rates: node velocities, material angular velocities, coordinate rates.
    let mut vel = vec![0.0; n];
    for (a, &node) in cn.iter().enumerate() {
        for j in 0..3 {
            vel[6 * a + j] = nodes[node].v[j];
            vel[6 * a + 3 + j] = nodes[node].w[j];
        }
    }
    for (j, q) in coords.iter().enumerate() {
        vel[nq + j] = q.v;
    }
    let mut dbv = DMatrix::zeros(m, n);
    c.velocity_tangent(ctx, nodes, coords, &vel, &mut dbv);
    // The same rows from the reaction tangent at each unit multiplier.
    let mut dbv_k = DMatrix::zeros(m, n);
    for r in 0..m {
        let mut unit = vec![0.0; m];
        unit[r] = 1.0;
        let mut kr = DMatrix::zeros(n, n);
        c.reaction_tangent(ctx, nodes, coords, &unit, &mut kr);
        for j in 0..n {
            dbv_k[(r, j)] = (0..n).map(|i| vel[i] * kr[(i, j)]).sum();
        }
    }
    let phi_targeted: Vec<f64> = phi_s.iter().zip(&targets).map(|(p, t)| p - t).collect();
    let mut k_s = DMatrix::zeros(n, n);
    c.reaction_tangent(ctx, nodes, coords, mu, &mut k_s);
    let force_s = b_s.transpose() * nalgebra::DVector::from_column_slice(mu);
    let rel = |a: &[f64], s: &[f64]| {
        let scale = s.iter().fold(1e-300f64, |x, v| x.max(v.abs()));
        a.iter()
            .zip(s)
            .fold(0.0f64, |x, (p, q)| x.max((p - q).abs() / scale))
    };
    // The residual-only evaluation (no B, no tangent: the displacement rows' forces
    // summed as one term) against the same.
    let (mut phi_r, mut mu_r, mut force_r) = (vec![0.0; m], vec![0.0; m], vec![0.0; n]);
    let mut b_r = DMatrix::zeros(m, n);
    c.evaluate_rows(
        ctx,
        nodes,
        coords,
        mu,
        0.0,
        RowTerms {
            phi: &mut phi_r,
            mu: &mut mu_r,
            force: &mut force_r,
            b: &mut b_r,
            want_b: false,
            tangent: None,
            targets: &targets,
        },
    );
    let combined = rel(&phi, &phi_targeted)
        .max(rel(&mu_out, mu))
        .max(rel(&force, force_s.as_slice()))
        .max(rel(b.as_slice(), b_s.as_slice()))
        .max(rel(k.as_slice(), k_s.as_slice()))
        .max(rel(&phi_r, &phi_targeted))
        .max(rel(&phi_only, &phi_s))
        .max(rel(&mu_r, mu))
        .max(rel(&force_r, force_s.as_slice()))
        .max(rel(dbv.as_slice(), dbv_k.as_slice()));

    let mut work = nodes.to_vec();
    let mut wc = coords.to_vec();
    // Central differences at steps ε ([0]) and 2ε ([1]).
    let mut b_fd = [DMatrix::zeros(m, n), DMatrix::zeros(m, n)];
    let mut k_fd = [DMatrix::zeros(n, n), DMatrix::zeros(n, n)];
    let mut dbv_fd = [DMatrix::zeros(m, n), DMatrix::zeros(m, n)];
    let vel_v = nalgebra::DVector::from_column_slice(&vel);
    let mut bp = DMatrix::zeros(m, n);
    let mut pp = vec![0.0; m];
    let mu_v = nalgebra::DVector::from_column_slice(mu);
    for col in 0..n {
        for (level, step) in [EPS, 2.0 * EPS].into_iter().enumerate() {
            let mut vals = Vec::new();
            let mut forces = Vec::new();
            let mut rates = Vec::new();
            for s in [1.0, -1.0] {
                work.clone_from_slice(nodes);
                wc.clone_from_slice(coords);
                if col < nq {
                    perturb(
                        &mut work,
                        cn[col / 6],
                        col % 6,
                        s * step,
                        Slot::Configuration,
                    );
                } else {
                    wc[col - nq].q += s * step;
                }
                c.evaluate(ctx, &work, &wc, &mut pp, Some(&mut bp));
                vals.push(nalgebra::DVector::from_column_slice(&pp));
                forces.push(bp.transpose() * &mu_v);
                rates.push(&bp * &vel_v);
            }
            b_fd[level].set_column(col, &((&vals[0] - &vals[1]) / (2.0 * step)));
            k_fd[level].set_column(col, &((&forces[0] - &forces[1]) / (2.0 * step)));
            dbv_fd[level].set_column(col, &((&rates[0] - &rates[1]) / (2.0 * step)));
        }
    }

    // Differences of Φ along x(s) = x + s v, R(s) = R exp(s Ω̃), ν(s) = ν + s ν̇, t + s
    // (zero accelerations).
    let mut conv = vec![0.0; m];
    c.acceleration_term(ctx, nodes, coords, &mut conv);
    let mut phi_t = vec![0.0; m];
    c.velocity_term(ctx, &mut phi_t);
    let eps2 = 1e-4;
    let mut along = |s: f64| -> Vec<f64> {
        work.clone_from_slice(nodes);
        wc.clone_from_slice(coords);
        for &node in &cn {
            let nd = &mut work[node];
            nd.x += nd.v * s;
            nd.rot = nd.rot.compose_exp(&(nd.w * s));
        }
        for q in &mut wc {
            q.q += q.v * s;
        }
        let shifted = EvalContext {
            time: ctx.time + s,
            ..*ctx
        };
        let mut p = vec![0.0; m];
        c.evaluate(&shifted, &work, &wc, &mut p, None);
        p
    };
    let (pp1, pm1) = (along(eps2), along(-eps2));
    let scale = conv.iter().fold(1.0f64, |a, x: &f64| a.max(x.abs()));
    let mut conv_err: f64 = 0.0;
    let mut vel_err: f64 = 0.0;
    for i in 0..m {
        let fd2 = (pp1[i] - 2.0 * phi_s[i] + pm1[i]) / (eps2 * eps2);
        conv_err = conv_err.max((fd2 - conv[i]).abs() / scale);
        let fd1 = (pp1[i] - pm1[i]) / (2.0 * eps2);
        let bv: f64 = (0..n).map(|j| b[(i, j)] * vel[j]).sum();
        let vscale = phi_t[i].abs().max(bv.abs()).max(1.0);
        vel_err = vel_err.max((fd1 - bv - phi_t[i]).abs() / vscale);
    }

    // Coordinate elements: ∂r/∂ν and ∂r/∂ν̇ (diagonal).
    let mut r0 = vec![0.0; nc];
    let mut kd = vec![0.0; nc];
    let mut cd = vec![0.0; nc];
    let n_in = c.signal_inputs().len();
    // Input signals at fixed, non-zero values.
    let signals: Vec<f64> = (0..n_in).map(|i| 0.7 + 0.1 * i as f64).collect();
    let mut sd = vec![0.0; nc * n_in];
    c.coordinate_forces(
        ctx,
        coords,
        &signals,
        &mut r0,
        Some(CoordinateTangents {
            stiffness: &mut kd,
            damping: &mut cd,
            signals: &mut sd,
        }),
    );
    // ∂r/∂s against differences in the input values (r is affine in them here, so one
    // step size suffices for both levels).
    let mut sig_a = DMatrix::zeros(nc.max(1), n_in.max(1));
    let mut sig_fd = DMatrix::zeros(nc.max(1), n_in.max(1));
    for i in 0..n_in {
        let mut ws = signals.clone();
        let mut rr = [vec![0.0; nc], vec![0.0; nc]];
        for (side, s) in [1.0, -1.0].iter().enumerate() {
            ws[i] = signals[i] + s * EPS;
            c.coordinate_forces(ctx, coords, &ws, &mut rr[side], None);
        }
        for j in 0..nc {
            sig_a[(j, i)] = sd[j * n_in + i];
            sig_fd[(j, i)] = (rr[0][j] - rr[1][j]) / (2.0 * EPS);
        }
    }
    // ∂r/∂ν (slot 0) and ∂r/∂ν̇ (slot 1) at steps ε and 2ε.
    let size = nc.max(1);
    let mut fds = [
        [DMatrix::zeros(size, size), DMatrix::zeros(size, size)],
        [DMatrix::zeros(size, size), DMatrix::zeros(size, size)],
    ];
    let (mut ka, mut ca) = (DMatrix::zeros(size, size), DMatrix::zeros(size, size));
    for j in 0..nc {
        ka[(j, j)] = kd[j];
        ca[(j, j)] = cd[j];
        for (slot, out) in fds.iter_mut().enumerate() {
            for (o, step) in out.iter_mut().zip([EPS, 2.0 * EPS]) {
                let mut rr = [vec![0.0; nc], vec![0.0; nc]];
                for (side, s) in [1.0, -1.0].iter().enumerate() {
                    wc.clone_from_slice(coords);
                    if slot == 0 {
                        wc[j].q += s * step;
                    } else {
                        wc[j].v += s * step;
                    }
                    c.coordinate_forces(ctx, &wc, &signals, &mut rr[side], None);
                }
                for i in 0..nc {
                    o[(i, j)] = (rr[0][i] - rr[1][i]) / (2.0 * step);
                }
            }
        }
    }
    let [kfd, cfd] = fds;
    let equations = groups(0, m);
    let unknowns = groups(cn.len(), nc);
    let scalars = groups(0, size);
    let reaction = (b.transpose() * &mu_v).as_slice().to_vec();
    // B v's round-off scale per row: Σ |b_rj v_j| (B v itself may cancel).
    let bv_all: Vec<f64> = (0..m)
        .map(|r| (0..n).map(|j| (b_s[(r, j)] * vel[j]).abs()).sum())
        .collect();
    ConstraintReport {
        b: compare(&b, &b_fd, &phi_s, &equations, &unknowns),
        k: compare(&k, &k_fd, &reaction, &unknowns, &unknowns),
        velocity_tangent: compare(&dbv, &dbv_fd, &bv_all, &equations, &unknowns),
        convective: conv_err,
        velocity: vel_err,
        coordinate_stiffness: compare(&ka, &kfd, &r0, &scalars, &scalars),
        coordinate_damping: compare(&ca, &cfd, &r0, &scalars, &scalars),
        coordinate_signals: compare(
            &sig_a,
            &[sig_fd.clone(), sig_fd],
            &r0,
            &scalars,
            &groups(0, n_in.max(1)),
        ),
        servo,
        combined,
    }
}

/// An element or a constraint and the state at which to check its tangents (the cases
/// each component kind registers, [`crate::model::components::ComponentKind::tangent_cases`]).
pub enum TangentCase {
    Element {
        element: Box<dyn Element>,
        nodes: Vec<NodeState>,
        states: Vec<ElementState>,
        signals: Vec<f64>,
        held: Vec<f64>,
    },
    Constraint {
        constraint: Box<dyn Constraint>,
        nodes: Vec<NodeState>,
        coords: Vec<Coordinate>,
        mu: Vec<f64>,
    },
}

impl TangentCase {
    pub fn element(element: Box<dyn Element>, nodes: Vec<NodeState>) -> Self {
        Self::Element {
            element,
            nodes,
            states: Vec::new(),
            signals: Vec::new(),
            held: Vec::new(),
        }
    }

    pub fn constraint(
        constraint: Box<dyn Constraint>,
        nodes: Vec<NodeState>,
        coords: Vec<Coordinate>,
        mu: Vec<f64>,
    ) -> Self {
        Self::Constraint {
            constraint,
            nodes,
            coords,
            mu,
        }
    }

    /// Element states `(z, ż)`.
    pub fn with_states(mut self, values: Vec<(f64, f64)>) -> Self {
        if let Self::Element { states, .. } = &mut self {
            *states = values
                .into_iter()
                .map(|(z, zd)| ElementState { z, zd })
                .collect();
        }
        self
    }

    /// Values of the input signals.
    pub fn with_signals(mut self, values: Vec<f64>) -> Self {
        if let Self::Element { signals, .. } = &mut self {
            *signals = values;
        }
        self
    }

    /// Sample-and-hold values of the element (as in dynamics; none: as in statics).
    pub fn with_held(mut self, values: Vec<f64>) -> Self {
        if let Self::Element { held, .. } = &mut self {
            *held = values;
        }
        self
    }

    /// Name of the element or constraint.
    pub fn name(&self) -> &str {
        match self {
            Self::Element { element, .. } => element.name(),
            Self::Constraint { constraint, .. } => constraint.name(),
        }
    }

    /// The largest relative mismatches of the case's tangents (per entry, differences at
    /// ε = 1e-6) and of its rate terms (constraints' convective and velocity terms,
    /// differences along the motion at ε = 1e-4, floor ≈ 1e-8).
    pub fn check(&self, ctx: &EvalContext) -> CaseReport {
        match self {
            Self::Element {
                element,
                nodes,
                states,
                signals,
                held,
            } => CaseReport {
                tangents: check_element_held(element.as_ref(), ctx, nodes, states, signals, held)
                    .worst(),
                rates: 0.0,
            },
            Self::Constraint {
                constraint,
                nodes,
                coords,
                mu,
            } => {
                let r = check_constraint(constraint.as_ref(), ctx, nodes, coords, mu);
                CaseReport {
                    tangents: largest(&[
                        r.b.relative,
                        r.k.relative,
                        r.velocity_tangent.relative,
                        r.coordinate_stiffness.relative,
                        r.coordinate_damping.relative,
                        r.coordinate_signals.relative,
                    ]),
                    rates: largest(&[r.convective, r.velocity]),
                }
            }
        }
    }
}

/// Result of [`TangentCase::check`].
#[derive(Clone, Copy, Debug)]
pub struct CaseReport {
    /// Largest relative mismatch of the tangent matrices.
    pub tangents: f64,
    /// Largest relative mismatch of the rate terms (constraints only).
    pub rates: f64,
}

/// A node in a reproducible, generic state (position, orientation, velocities and
/// accelerations of order one) from `seed`.
pub fn random_node(seed: u64) -> NodeState {
    let mut s = seed.wrapping_mul(0x9e37_79b9_7f4a_7c15).wrapping_add(1);
    let mut next = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 11) as f64) / ((1u64 << 53) as f64) * 2.0 - 1.0
    };
    let mut v3 = |scale: f64| Vector3::new(next(), next(), next()) * scale;
    NodeState {
        x: v3(1.0),
        rot: crate::math::Rotation::exp(&v3(2.0)),
        v: v3(1.0),
        w: v3(2.0),
        a: v3(1.0),
        wd: v3(1.0),
    }
}
