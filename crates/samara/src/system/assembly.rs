//! Generic assembly of the Newton residual and iteration matrix.
//!
//! With element terms `r, K, C, M`, constraint values `Φ`, Jacobians `B` and multipliers
//! `λ` (physical units), the augmented multipliers are `μ = λ + ρ Φ`.
//!
//! **Index-3 formulation** (seed eq. 8; Bauchau, Epple & Bottasso 2009):
//!
//! ```text
//! residual  [ s_r (r + Bᵀμ) ]    matrix  [ s_r (c_M M + c_C C + c_K (K + K_c(μ) + ρ BᵀB) T)   (s_r/s_λ) Bᵀ ]
//!           [ Φ             ]            [ B T                                                 0           ]
//! ```
//!
//! **Stabilized index-2 formulation** (Gear–Gupta–Leimkuhler; for generalized-α on Lie
//! groups, Arnold, Brüls & Cardona 2015): λ enforces the velocity constraint `B v = 0`, and
//! a projection multiplier ν enforces `Φ = 0` by moving the configuration along `Bᵀν`
//! (the update becomes `h Δq ← h Δq + Bᵀ ν`):
//!
//! ```text
//! residual  [ s_r (r + Bᵀμ) ]    matrix  [ s_r (…same…)    (s_r/s_λ) Bᵀ   0     ]
//!           [ s_v B v       ]            [ s_v c_C B       0              0     ]
//!           [ Φ             ]            [ B T             0              B T Bᵀ ]
//! ```
//!
//! (`B T Bᵀ` couples the ν of every two constraints that share a node.)
//! ```text
//! ```
//!
//! The λ rows carry `s_v (γ' B + ∂(Bv)/∂q T)`. The couplings of the projection `Bᵀν`
//! into the other rows (`K T Bᵀ`, `∂(Bv)/∂q T Bᵀ`) are left out of the matrix: they are
//! O(h²) and O(h) relative to the kept terms, and Newton still converges (see the tests).
//!
//! `T` is the block-diagonal tangent operator of the configuration update (identity for
//! statics). With the scaling on, `s_r = s_λ = βh²` and `s_v = βh/γ`, which keeps every
//! block O(1) as h → 0; off, all are 1.

use super::{State, System};
use crate::elements::{EvalContext, LocalTerms, Need};
use crate::solve::{BlockKind, BlockMatrix, BlockStructure};
use nalgebra::{DMatrix, Matrix3};
use std::sync::Arc;

/// How constraints enter the dynamic equations.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Formulation {
    /// Position constraints with Lagrange multipliers (index 3), scaled.
    #[default]
    Index3,
    /// Velocity constraints with λ plus position constraints with projection multipliers ν
    /// (stabilized index 2, GGL). Stable also without numerical dissipation (ρ∞ = 1).
    StabilizedIndex2,
}

/// Coefficients combining the element tangents into one iteration matrix.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coefficients {
    /// Multiplies M: `∂v̇/∂Δ` (β' in generalized-α, 0 in statics).
    pub mass: f64,
    /// Multiplies C: `∂v/∂Δ` (γ').
    pub damping: f64,
    /// Multiplies K (1 in both).
    pub stiffness: f64,
    /// `s_r`, multiplies the configuration rows.
    pub row_scale: f64,
    /// `s_λ`: the solver's multiplier unknowns are `s_λ λ`.
    pub multiplier_scale: f64,
    /// `s_v`: multiplies the velocity-constraint rows (stabilized index 2 only).
    pub velocity_scale: f64,
    /// `ρ`: augmented-Lagrangian penalty, physical units (force per unit Φ).
    pub penalty: f64,
}

impl Coefficients {
    /// Static equilibrium `r(q) + Bᵀμ = 0`.
    pub fn statics(penalty: f64) -> Self {
        Self {
            mass: 0.0,
            damping: 0.0,
            stiffness: 1.0,
            row_scale: 1.0,
            multiplier_scale: 1.0,
            velocity_scale: 1.0,
            penalty,
        }
    }
}

struct ConstraintWork {
    phi: Vec<f64>,
    mu: Vec<f64>,
    /// B (material rotation columns).
    b: DMatrix<f64>,
    /// B T.
    bt: DMatrix<f64>,
    k: DMatrix<f64>,
    /// Scratch: ∂(B_r · v)/∂q of one row r (stabilized only), and the unit multiplier e_r.
    kr: DMatrix<f64>,
    unit: Vec<f64>,
    dbv: DMatrix<f64>,
    /// Value offsets of the (node a, node b) blocks, row-major over local nodes.
    node_slots: Vec<usize>,
    /// Offsets of (node, λ) and (λ, node) blocks.
    lam_col: Vec<usize>,
    lam_row: Vec<usize>,
    /// Offsets of (ν, node) blocks and of the (ν, ν) block (stabilized only).
    nu_row: Vec<usize>,
    nu_diag: usize,
}

/// Reusable workspace for assembling one system in one formulation: nothing is
/// allocated per call.
pub struct Assembler {
    formulation: Formulation,
    structure: Arc<BlockStructure>,
    terms: Vec<LocalTerms>,
    element_slots: Vec<Vec<usize>>,
    constraints: Vec<ConstraintWork>,
    /// Stabilized only: (ν_k, ν_l) couplings of constraints k ≠ l sharing a node, as
    /// (k, l, value offset, local node index in k, local node index in l).
    nu_pairs: Vec<(usize, usize, usize, usize, usize)>,
}

impl Assembler {
    pub fn new(sys: &System, formulation: Formulation) -> Self {
        let n = sys.n_nodes();
        let nc = sys.constraints.len();
        let stabilized = formulation == Formulation::StabilizedIndex2;
        let mut sizes = vec![6; n];
        let mut kinds = vec![BlockKind::Primary; n];
        let mut couplings = Vec::new();
        for e in &sys.elements {
            let en = e.nodes();
            for (i, &a) in en.iter().enumerate() {
                for &b in &en[i + 1..] {
                    if a != b {
                        couplings.push((a, b));
                    }
                }
            }
        }
        // Constraints sharing a node: (k, l, local index in k, local index in l).
        let mut shared = Vec::new();
        if stabilized {
            for (k, ck) in sys.constraints.iter().enumerate() {
                for (l, cl) in sys.constraints.iter().enumerate() {
                    if k == l {
                        continue;
                    }
                    for (a, na) in ck.nodes().iter().enumerate() {
                        for (b, nb) in cl.nodes().iter().enumerate() {
                            if na == nb {
                                shared.push((k, l, a, b));
                            }
                        }
                    }
                }
            }
            for &(k, l, _, _) in &shared {
                couplings.push((n + nc + k, n + nc + l));
            }
        }
        let groups = if stabilized { 2 } else { 1 };
        for g in 0..groups {
            for (k, c) in sys.constraints.iter().enumerate() {
                sizes.push(c.n_equations());
                kinds.push(BlockKind::Multiplier);
                let blk = n + g * nc + k;
                let cn = c.nodes();
                for (i, &a) in cn.iter().enumerate() {
                    couplings.push((blk, a));
                    for &b in &cn[i + 1..] {
                        if a != b {
                            couplings.push((a, b));
                        }
                    }
                }
            }
        }
        let structure = Arc::new(
            BlockStructure::new(sizes, kinds, &couplings)
                .expect("block structure of a validated model is consistent"),
        );
        let s = &structure;
        let slot =
            |i: usize, j: usize| s.entry(i, j).expect("pattern contains every coupled block");
        let terms = sys
            .elements
            .iter()
            .map(|e| LocalTerms::new(e.nodes().len()))
            .collect();
        let element_slots = sys
            .elements
            .iter()
            .map(|e| {
                let en = e.nodes();
                en.iter()
                    .flat_map(|&a| en.iter().map(move |&b| (a, b)))
                    .map(|(a, b)| slot(a, b))
                    .collect()
            })
            .collect();
        let constraints = sys
            .constraints
            .iter()
            .enumerate()
            .map(|(k, c)| {
                let cn = c.nodes();
                let m = c.n_equations();
                let lam = n + k;
                let nu = n + nc + k;
                ConstraintWork {
                    phi: vec![0.0; m],
                    mu: vec![0.0; m],
                    b: DMatrix::zeros(m, 6 * cn.len()),
                    bt: DMatrix::zeros(m, 6 * cn.len()),
                    k: DMatrix::zeros(6 * cn.len(), 6 * cn.len()),
                    kr: DMatrix::zeros(6 * cn.len(), 6 * cn.len()),
                    unit: vec![0.0; m],
                    dbv: DMatrix::zeros(m, 6 * cn.len()),
                    node_slots: cn
                        .iter()
                        .flat_map(|&a| cn.iter().map(move |&b| (a, b)))
                        .map(|(a, b)| slot(a, b))
                        .collect(),
                    lam_col: cn.iter().map(|&a| slot(a, lam)).collect(),
                    lam_row: cn.iter().map(|&a| slot(lam, a)).collect(),
                    nu_row: if stabilized {
                        cn.iter().map(|&a| slot(nu, a)).collect()
                    } else {
                        Vec::new()
                    },
                    nu_diag: if stabilized { slot(nu, nu) } else { 0 },
                }
            })
            .collect();
        let nu_pairs = shared
            .iter()
            .map(|&(k, l, a, b)| (k, l, slot(n + nc + k, n + nc + l), a, b))
            .collect();
        Self {
            formulation,
            structure,
            terms,
            element_slots,
            constraints,
            nu_pairs,
        }
    }

    pub fn formulation(&self) -> Formulation {
        self.formulation
    }

    /// Block structure of the iteration matrix.
    pub fn structure(&self) -> &Arc<BlockStructure> {
        &self.structure
    }

    /// Number of unknowns (and equations) of the Newton system.
    pub fn n_unknowns(&self) -> usize {
        self.structure.dim()
    }

    /// Assembles the residual (always) and the iteration matrix (if given).
    ///
    /// `tangent_ops[i]` is the tangent operator of node i's rotation update; an empty slice
    /// means identity.
    #[allow(clippy::too_many_arguments)]
    pub fn assemble(
        &mut self,
        sys: &System,
        state: &State,
        ctx: &EvalContext,
        coef: &Coefficients,
        tangent_ops: &[Matrix3<f64>],
        residual: &mut [f64],
        mut matrix: Option<&mut BlockMatrix>,
    ) {
        let n_cfg = sys.n_config();
        let n_mult = sys.n_multipliers;
        let stabilized = self.formulation == Formulation::StabilizedIndex2;
        residual.fill(0.0);
        let need = if matrix.is_some() {
            Need::ResidualAndTangents
        } else {
            Need::Residual
        };
        if let Some(m) = matrix.as_deref_mut() {
            m.fill_zero();
        }
        let sr = coef.row_scale;

        for (k, e) in sys.elements.iter().enumerate() {
            let t = &mut self.terms[k];
            t.clear(need);
            e.evaluate(ctx, &state.nodes, need, t);
            let en = e.nodes();
            for (a, &na) in en.iter().enumerate() {
                for i in 0..6 {
                    residual[6 * na + i] += sr * t.r[6 * a + i];
                }
            }
            if let Some(mat) = matrix.as_deref_mut() {
                apply_tangent_ops(&mut t.k, en, tangent_ops);
                // K_eff = s_r (c_M M + c_C C + c_K K), combined in place in `k`.
                let (cm, cc, ck) = (sr * coef.mass, sr * coef.damping, sr * coef.stiffness);
                for ((k, m), c) in
                    t.k.as_mut_slice()
                        .iter_mut()
                        .zip(t.m.as_slice())
                        .zip(t.c.as_slice())
                {
                    *k = ck * *k + cm * m + cc * c;
                }
                let n = en.len();
                let slots = &self.element_slots[k];
                for a in 0..n {
                    for b in 0..n {
                        let off = slots[a * n + b];
                        scatter_block(
                            &mut mat.values[off..off + 36],
                            t.k.as_slice(),
                            6 * n,
                            6 * a,
                            6 * b,
                            6,
                            6,
                            1.0,
                        );
                    }
                }
            }
        }

        for (k, c) in sys.constraints.iter().enumerate() {
            let w = &mut self.constraints[k];
            let m = c.n_equations();
            let off = sys.multiplier_offsets[k];
            c.evaluate(ctx, &state.nodes, &mut w.phi, Some(&mut w.b));
            let cn = c.nodes();
            for i in 0..m {
                w.mu[i] = state.lambda[off + i] + coef.penalty * w.phi[i];
            }
            if stabilized {
                // λ rows: s_v B v; ν rows: Φ.
                for i in 0..m {
                    let mut bv = 0.0;
                    for (a, &na) in cn.iter().enumerate() {
                        let nd = &state.nodes[na];
                        for j in 0..3 {
                            bv += w.b[(i, 6 * a + j)] * nd.v[j] + w.b[(i, 6 * a + 3 + j)] * nd.w[j];
                        }
                    }
                    residual[n_cfg + off + i] = coef.velocity_scale * bv;
                    residual[n_cfg + n_mult + off + i] = w.phi[i];
                }
            } else {
                for i in 0..m {
                    residual[n_cfg + off + i] = w.phi[i];
                }
            }
            // Configuration rows: s_r Bᵀ μ.
            for (a, &na) in cn.iter().enumerate() {
                for i in 0..6 {
                    let mut acc = 0.0;
                    for r in 0..m {
                        acc += w.b[(r, 6 * a + i)] * w.mu[r];
                    }
                    residual[6 * na + i] += sr * acc;
                }
            }
            let Some(mat) = matrix.as_deref_mut() else {
                continue;
            };
            w.k.fill(0.0);
            c.reaction_tangent(ctx, &state.nodes, &w.mu, &mut w.k);
            if coef.penalty != 0.0 {
                w.k.gemm_tr(coef.penalty, &w.b, &w.b, 1.0);
            }
            apply_tangent_ops(&mut w.k, cn, tangent_ops);
            w.bt.copy_from(&w.b);
            apply_tangent_ops(&mut w.bt, cn, tangent_ops);
            let n = cn.len();
            let nr = 6 * n;
            for a in 0..n {
                for b in 0..n {
                    let o = w.node_slots[a * n + b];
                    scatter_block(
                        &mut mat.values[o..o + 36],
                        w.k.as_slice(),
                        nr,
                        6 * a,
                        6 * b,
                        6,
                        6,
                        sr * coef.stiffness,
                    );
                }
            }
            // (node, λ): (s_r/s_λ) Bᵀ, 6 × m row-major.
            let cs = sr / coef.multiplier_scale;
            for a in 0..n {
                let o = w.lam_col[a];
                let dst = &mut mat.values[o..o + 6 * m];
                for i in 0..6 {
                    let col = &w.b.as_slice()[(6 * a + i) * m..(6 * a + i + 1) * m];
                    for (d, v) in dst[m * i..m * i + m].iter_mut().zip(col) {
                        *d += cs * v;
                    }
                }
            }
            if stabilized {
                // ∂(B v)/∂q, row r = vᵀ ∂(B_rᵀ)/∂q = vᵀ K(e_r), then times T.
                for r in 0..m {
                    w.unit.fill(0.0);
                    w.unit[r] = 1.0;
                    w.kr.fill(0.0);
                    c.reaction_tangent(ctx, &state.nodes, &w.unit, &mut w.kr);
                    for j in 0..6 * n {
                        let mut acc = 0.0;
                        for (a, &na) in cn.iter().enumerate() {
                            let nd = &state.nodes[na];
                            for i in 0..3 {
                                acc += nd.v[i] * w.kr[(6 * a + i, j)]
                                    + nd.w[i] * w.kr[(6 * a + 3 + i, j)];
                            }
                        }
                        w.dbv[(r, j)] = acc;
                    }
                }
                apply_tangent_ops(&mut w.dbv, cn, tangent_ops);
            }
            // (λ, node): B T (index 3) or s_v (γ' B + ∂(Bv)/∂q T) (stabilized), m × 6 row-major.
            for a in 0..n {
                let o = w.lam_row[a];
                let dst = &mut mat.values[o..o + 6 * m];
                if stabilized {
                    let cv = coef.velocity_scale * coef.damping;
                    scatter_block(dst, w.b.as_slice(), m, 0, 6 * a, m, 6, cv);
                    scatter_block(
                        dst,
                        w.dbv.as_slice(),
                        m,
                        0,
                        6 * a,
                        m,
                        6,
                        coef.velocity_scale,
                    );
                } else {
                    scatter_block(dst, w.bt.as_slice(), m, 0, 6 * a, m, 6, 1.0);
                }
            }
            if stabilized {
                // (ν, node): B T; (ν, ν): B T Bᵀ.
                for a in 0..n {
                    let o = w.nu_row[a];
                    scatter_block(
                        &mut mat.values[o..o + 6 * m],
                        w.bt.as_slice(),
                        m,
                        0,
                        6 * a,
                        m,
                        6,
                        1.0,
                    );
                }
                let o = w.nu_diag;
                let dst = &mut mat.values[o..o + m * m];
                for r in 0..m {
                    for s in 0..m {
                        let mut acc = 0.0;
                        for j in 0..6 * n {
                            acc += w.bt[(r, j)] * w.b[(s, j)];
                        }
                        dst[m * r + s] += acc;
                    }
                }
            }
        }
        if let Some(mat) = matrix
            && stabilized
        {
            self.add_projection_couplings(sys, mat);
        }
    }

    /// Couplings `(ν_k, ν_l) = B_k T B_lᵀ` through the nodes constraints k and l share.
    fn add_projection_couplings(&self, sys: &System, matrix: &mut BlockMatrix) {
        for &(k, l, o, a, b) in &self.nu_pairs {
            let (wk, wl) = (&self.constraints[k], &self.constraints[l]);
            let (mk, ml) = (
                sys.constraints[k].n_equations(),
                sys.constraints[l].n_equations(),
            );
            let dst = &mut matrix.values[o..o + mk * ml];
            for r in 0..mk {
                for s in 0..ml {
                    let mut acc = 0.0;
                    for j in 0..6 {
                        acc += wk.bt[(r, 6 * a + j)] * wl.b[(s, 6 * b + j)];
                    }
                    dst[ml * r + s] += acc;
                }
            }
        }
    }

    /// Adds the projection `Bᵀ Δν` of the last assembly to a configuration-sized vector
    /// (stabilized index-2 only; `delta_nu` has one entry per constraint row).
    pub fn add_projection(&self, sys: &System, delta_nu: &[f64], out: &mut [f64]) {
        for (k, c) in sys.constraints.iter().enumerate() {
            let w = &self.constraints[k];
            let off = sys.multiplier_offsets[k];
            for (a, &na) in c.nodes().iter().enumerate() {
                for i in 0..6 {
                    let mut acc = 0.0;
                    for r in 0..c.n_equations() {
                        acc += w.b[(r, 6 * a + i)] * delta_nu[off + r];
                    }
                    out[6 * na + i] += acc;
                }
            }
        }
    }

    /// Overwrites the constraint rows of `residual` with the convective accelerations
    /// `Φ̈ − B v̇` (for the consistent-initial-acceleration problem, index-3 layout).
    pub fn acceleration_rows(
        &mut self,
        sys: &System,
        state: &State,
        ctx: &EvalContext,
        residual: &mut [f64],
    ) {
        let n_cfg = sys.n_config();
        for (k, c) in sys.constraints.iter().enumerate() {
            let m = c.n_equations();
            let off = n_cfg + sys.multiplier_offsets[k];
            c.acceleration_term(ctx, &state.nodes, &mut residual[off..off + m]);
        }
    }
}

/// `dst[r][c] += scale · src[r0 + r, c0 + c]` for an `rows × cols` row-major block `dst`
/// and a column-major `src` with `nr` rows.
#[inline]
#[allow(clippy::too_many_arguments)]
fn scatter_block(
    dst: &mut [f64],
    src: &[f64],
    nr: usize,
    r0: usize,
    c0: usize,
    rows: usize,
    cols: usize,
    scale: f64,
) {
    for c in 0..cols {
        let col = &src[(c0 + c) * nr + r0..(c0 + c) * nr + r0 + rows];
        for (r, v) in col.iter().enumerate() {
            dst[r * cols + c] += scale * v;
        }
    }
}

/// Right-multiplies the rotation columns of each local node block by its tangent operator.
fn apply_tangent_ops(m: &mut DMatrix<f64>, nodes: &[usize], ops: &[Matrix3<f64>]) {
    if ops.is_empty() {
        return;
    }
    for (b, &nb) in nodes.iter().enumerate() {
        let t = &ops[nb];
        let c0 = 6 * b + 3;
        for r in 0..m.nrows() {
            let row = [m[(r, c0)], m[(r, c0 + 1)], m[(r, c0 + 2)]];
            for j in 0..3 {
                m[(r, c0 + j)] = row[0] * t[(0, j)] + row[1] * t[(1, j)] + row[2] * t[(2, j)];
            }
        }
    }
}
