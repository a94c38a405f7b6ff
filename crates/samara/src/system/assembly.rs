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
//! a projection multiplier η enforces `Φ = 0` by moving the configuration along `Bᵀη`
//! (the update becomes `h Δq ← h Δq + Bᵀ η`):
//!
//! ```text
//! residual  [ s_r (r + Bᵀμ) ]    matrix  [ s_r (…same…)    (s_r/s_λ) Bᵀ   0     ]
//!           [ s_v B v       ]            [ s_v c_C B       0              0     ]
//!           [ Φ             ]            [ B T             0              B T Bᵀ ]
//! ```
//!
//! (`B T Bᵀ` couples the η of every two constraints that share a node.)
//!
//! The λ rows carry `s_v (γ' B + ∂(Bv)/∂q T)`. The couplings of the projection `Bᵀη`
//! into the other rows (`K T Bᵀ`, `∂(Bv)/∂q T Bᵀ`) are left out of the matrix: they are
//! O(h²) and O(h) relative to the kept terms, and Newton still converges (see the tests).
//!
//! **Joint coordinates** ν are configuration unknowns without mass: their rows carry
//! `s_r (f_ν(ν, ν̇) + B_νᵀ μ)` and their columns the ν-columns of `B`. They live in the
//! block of their joint, after its multipliers, so that the joint's pivot block
//! `[−B M⁻¹ Bᵀ, B_ν; B_νᵀ, K_νν]` stays invertible with no spring on the coordinate.
//!
//! `T` is the block-diagonal tangent operator of the configuration update (identity for
//! statics). With the scaling on, `s_r = s_λ = βh²` and `s_v = βh/γ`, which keeps every
//! block O(1) as h → 0; off, all are 1.

use super::{SignalValues, State, System};
use crate::core::{ElementInput, RowTerms};
use crate::elements::{Element, EvalContext, LocalTerms, Need, SpherePair};
use crate::joints::CoordinateTangents;
use crate::math::isa;
use crate::math::prefetch::prefetch;
use crate::solve::{BlockKind, BlockMatrix, BlockStructure, BlockTarget, BlockView};
use nalgebra::{DMatrix, Matrix3};
use std::ops::Range;
use std::sync::Arc;

/// The multiply–add `a·b + c` of the assembly's kernels: rounded twice (`Separate`) in the
/// baseline and AVX copies, once (`Fused`, `vfmadd`) in the copy compiled with FMA, chosen
/// at run time when the CPU has it. A type parameter, so each copy has its kernels inlined
/// with no test per operation (`f64::mul_add` outside a function with the `fma` feature is
/// a call to the C library's `fma`).
pub(crate) trait MulAdd: Copy {
    fn mul_add(a: f64, b: f64, c: f64) -> f64;
}

/// `a·b + c` rounded twice.
#[derive(Clone, Copy)]
pub(crate) struct Separate;

impl MulAdd for Separate {
    #[inline(always)]
    fn mul_add(a: f64, b: f64, c: f64) -> f64 {
        a * b + c
    }
}

/// `a·b + c` rounded once (only inside a function compiled with the `fma` feature).
#[derive(Clone, Copy)]
pub(crate) struct Fused;

impl MulAdd for Fused {
    #[inline(always)]
    fn mul_add(a: f64, b: f64, c: f64) -> f64 {
        a.mul_add(b, c)
    }
}

/// How constraints enter the dynamic equations.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Formulation {
    /// Position constraints with Lagrange multipliers (index 3), scaled.
    #[default]
    Index3,
    /// Velocity constraints with λ plus position constraints with projection multipliers η
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
    /// Multiplies the element-state columns of C: `∂ż/∂Δz` (0 in statics, where ż = 0).
    pub state_rate: f64,
    /// `s_z`, multiplies the element-state rows.
    pub state_row_scale: f64,
    /// The time step h of a dynamic step (0 otherwise): the granular pairs' condensed
    /// bristles are integrated over it ([`SpherePair::with_bristle`]).
    pub step: f64,
}

impl Coefficients {
    /// Static equilibrium `r(q) + Bᵀμ = 0` (element states with ż = 0).
    pub fn statics(penalty: f64) -> Self {
        Self {
            mass: 0.0,
            damping: 0.0,
            stiffness: 1.0,
            row_scale: 1.0,
            multiplier_scale: 1.0,
            velocity_scale: 1.0,
            penalty,
            state_rate: 0.0,
            state_row_scale: 1.0,
            step: 0.0,
        }
    }

    /// Only the constraint blocks `Bᵀ` and `B` (for projections onto the constraints).
    pub fn constraints_only() -> Self {
        Self {
            stiffness: 0.0,
            ..Self::statics(0.0)
        }
    }
}

/// Where a constraint's unknowns sit in the Newton vector.
#[derive(Clone, Debug, Default)]
struct Place {
    /// Its block (multipliers, then coordinates), if it has unknowns.
    block: Option<usize>,
    /// Its projection block (stabilized only).
    projection: Option<usize>,
    /// Vector offsets of the multipliers, coordinates and projection multipliers.
    lam: usize,
    coord: usize,
    proj: usize,
}

struct ConstraintWork {
    place: Place,
    m: usize,
    nc: usize,
    phi: Vec<f64>,
    mu: Vec<f64>,
    phi_t: Vec<f64>,
    /// `Bᵀμ` over the local columns.
    force: Vec<f64>,
    /// B (material rotation columns, then coordinates).
    b: DMatrix<f64>,
    /// B T.
    bt: DMatrix<f64>,
    /// Scratch: the rows of B, row-major (for ρ BᵀB).
    b_rows: Vec<f64>,
    k: DMatrix<f64>,
    /// ∂(B v)/∂q (stabilized only).
    dbv: DMatrix<f64>,
    /// Coordinate forces and their tangents.
    cf: Vec<f64>,
    cf_k: Vec<f64>,
    cf_c: Vec<f64>,
    /// Local velocities (node v, Ω, then ν̇).
    vel: Vec<f64>,
    /// Servo rows ([`crate::core::ServoRow`]): (enforced equation, input index, local
    /// coordinate).
    servos: Vec<(usize, usize, usize)>,
    /// The servo rows' signal values per equation (empty without servo rows).
    targets: Vec<f64>,
    /// Value offsets of the (node a, node b) blocks, row-major over local nodes.
    node_slots: Vec<usize>,
    /// Offsets of the (node, joint block) and (joint block, node) blocks, and of the
    /// joint's diagonal block.
    lam_col: Vec<usize>,
    lam_row: Vec<usize>,
    diag: usize,
    /// Offsets of (η, node) blocks, (η, joint block) and (η, η) (stabilized only).
    proj_row: Vec<usize>,
    proj_blk: usize,
    proj_diag: usize,
}

/// One block of an element's local unknowns: its block in the iteration matrix, its first
/// local index and its size (6 for a node, the number of states for its states).
#[derive(Clone, Copy, Debug)]
struct LocalBlock {
    block: usize,
    local: usize,
    size: usize,
}

/// Where a signal's derivative with respect to one support unknown lands for one consumer:
/// the support position, the column within its block, and the stored block
/// ([`BlockStructure::entry_index`]) of (each consumer row block, that block).
#[derive(Clone, Debug)]
struct SupportSlot {
    pos: usize,
    col: usize,
    slots: Vec<usize>,
}

/// Owner of a block of the iteration matrix (for messages).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BlockOwner {
    Node(usize),
    Joint(usize),
    Projection(usize),
    States(usize),
}

/// Reusable workspace for assembling one system in one formulation: nothing is
/// allocated per call.
pub struct Assembler {
    formulation: Formulation,
    structure: Arc<BlockStructure>,
    /// Element scratch, one per distinct element size (local unknowns, input signals),
    /// shared by every element of that size: the working set stays small however many
    /// elements there are.
    terms: Vec<LocalTerms>,
    /// Index into `terms` of each element (of its batch's block when it starts one).
    term_of: Vec<usize>,
    /// Index into `terms` of each element evaluated alone (the parallel window).
    alone_term_of: Vec<usize>,
    /// Per element k: one past the last element of the batch k starts (consecutive
    /// accumulating elements on the same nodes without states or input signals, see
    /// [`crate::core::Element::accumulates`]), evaluated into one local block; k + 1 for
    /// an element alone (sequential path only).
    batch_end: Vec<usize>,
    /// Models of [`PARALLEL_MIN_ELEMENTS`] elements or more: [`PARALLEL_WINDOW`] slots of
    /// element scratch for the parallel evaluation (empty otherwise).
    window: Vec<WindowSlot>,
    /// Local blocks of each element and the value offset of each (row block, column
    /// block) pair, row-major over the element's blocks.
    element_blocks: Vec<Vec<LocalBlock>>,
    element_slots: Vec<Vec<usize>>,
    /// Per element with states: the Newton-vector offset of its state block.
    state_place: Vec<Option<usize>>,
    /// Per element and input signal: where the chain-rule terms go.
    element_signal_slots: Vec<Vec<Vec<SupportSlot>>>,
    /// Per constraint and input signal: where the chain-rule terms go (joint block rows).
    constraint_signal_slots: Vec<Vec<Vec<SupportSlot>>>,
    /// Block and in-block column of every configuration unknown.
    config_place: Vec<(usize, usize)>,
    owners: Vec<BlockOwner>,
    /// Signal scratch: values, derivatives, and derivatives combined for the matrix.
    signal_values: SignalValues,
    signal_combined: Vec<Vec<f64>>,
    inputs: Vec<f64>,
    constraint_inputs: Vec<f64>,
    cf_ds: Vec<f64>,
    /// Scratch: `∂s/∂Δ` of a servo's signal (the K channel at weight 1, like B).
    servo_grad: Vec<f64>,
    constraints: Vec<ConstraintWork>,
    /// Stabilized only: (η_k, η_l) couplings of constraints k ≠ l sharing a node, as
    /// (k, l, value offset, local node index in k, local node index in l).
    nu_pairs: Vec<(usize, usize, usize, usize, usize)>,
    /// Per node, how its rates follow its configuration (empty: they do not).
    rate_maps: Vec<RateMaps>,
    /// Contacts of the granular sets' candidate pairs ([`Assembler::with_pairs`]), the
    /// value offsets of their (A,A), (A,B), (B,A), (B,B) blocks, and their scratch.
    pairs: Vec<SpherePair>,
    pair_slots: Vec<[usize; 4]>,
    pair_terms: LocalTerms,
    /// `partition = "two_parts"`: the items of part 0, part 1 and the separator.
    split: Option<Box<SplitPlan>>,
}

/// The batches (their first elements) and constraints of each part of a
/// separator order (0, 1) and of the interface (2), and the second part's assembler.
pub struct SplitPlan {
    /// The nodes of part 0 and the separator (`nodes[0]`) and of part 1 (`nodes[1]`): a
    /// partition of the nodes, each in exactly one list.
    pub nodes: [Vec<usize>; 2],
    /// The part (0, 1) each node belongs to, for [`crate::solve::PartSlice`].
    pub node_part: Vec<u8>,
    /// The constraints with passive coordinates of part 0 and the separator
    /// (`passive[0]`) and of part 1 (`passive[1]`).
    pub passive: [Vec<usize>; 2],
    /// The part (0, 1) each joint coordinate (active, then passive) belongs to: its
    /// constraint's.
    pub coord_part: Vec<u8>,
    /// Each part's share of the constraint check (`max |Φ|` at a converged iterate);
    /// `None` when a constraint has servo rows (their targets are signals, evaluated
    /// once for all: the check then runs on one thread).
    pub checks: Option<PartChecks>,
    /// Owner of each stored block (0, 1; 2 for the blocks on the separator).
    entry_part: Vec<u8>,
    /// Part 1's residual (its rows only are written) and the ranges of those rows.
    residual1: Vec<f64>,
    rows1: Vec<Range<usize>>,
    starts: [Vec<usize>; 3],
    cons: [Vec<usize>; 3],
    partner: Assembler,
}

/// The constraints whose values Φ each part evaluates in the constraint check (part 0
/// with the separator's) and the part (0, 1) each multiplier row belongs to: its
/// constraint's, for [`crate::solve::PartSlice`].
pub struct PartChecks {
    pub constraints: [Vec<usize>; 2],
    pub row_part: Vec<u8>,
}

/// What every item of an assembly reads: the system, the state, the time context, the
/// coefficients of the iteration matrix and the nodes' tangent operators T(hΔψ).
#[derive(Clone, Copy)]
pub(crate) struct Inputs<'a> {
    sys: &'a System,
    state: &'a State,
    ctx: &'a EvalContext,
    coef: &'a Coefficients,
    tangent_ops: &'a [Matrix3<f64>],
}

type InputRefs<'a> = (
    &'a System,
    &'a State,
    &'a EvalContext,
    &'a Coefficients,
    &'a [Matrix3<f64>],
);

impl<'a> Inputs<'a> {
    /// The five inputs, in the order of their fields.
    #[inline(always)]
    fn all(self) -> InputRefs<'a> {
        (self.sys, self.state, self.ctx, self.coef, self.tangent_ops)
    }
}

/// How a node's rates follow its configuration in a steadily spinning state:
/// `δv = A_v δq` and `δv̇ = A₀ δq` on its translation (index 0) and material rotation
/// (index 1) blocks. With them the iteration matrix gets `C A_v + M A₀` added to K (the
/// centrifugal softening `MΩ̃Ω̃` and the gyroscopic stiffness of spinning statics).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RateMaps {
    pub velocity: [Matrix3<f64>; 2],
    pub acceleration: [Matrix3<f64>; 2],
}

impl Assembler {
    pub fn new(sys: &System, formulation: Formulation) -> Self {
        Self::with_pairs(sys, formulation, Vec::new())
    }

    /// The assembler with the contacts of `pairs` (granular candidate pairs, stateless)
    /// added to the system's elements: their (A, B) blocks enter the pattern. Built again
    /// whenever the candidate set changes (pattern and symbolic factorization follow);
    /// reused otherwise.
    pub fn with_pairs(sys: &System, formulation: Formulation, pairs: Vec<SpherePair>) -> Self {
        let n = sys.n_nodes();
        let stabilized = formulation == Formulation::StabilizedIndex2;
        let mut sizes = vec![6; n];
        let mut kinds = vec![BlockKind::Primary; n];
        let mut owners: Vec<BlockOwner> = (0..n).map(BlockOwner::Node).collect();
        let mut couplings = Vec::new();
        // Blocks of the constraints: multipliers + coordinates.
        let mut places: Vec<Place> = vec![Place::default(); sys.constraints.len()];
        for (k, c) in sys.constraints.iter().enumerate() {
            let size = c.n_equations() + c.n_coordinates();
            if size > 0 {
                places[k].block = Some(sizes.len());
                sizes.push(size);
                kinds.push(if c.is_relative() {
                    BlockKind::RelativeMultiplier
                } else {
                    BlockKind::Multiplier
                });
                owners.push(BlockOwner::Joint(k));
            }
        }
        // Blocks of the element states, one per element that has states.
        let mut state_block = vec![None; sys.elements.len()];
        for (k, e) in sys.elements.iter().enumerate() {
            if e.n_states() > 0 {
                state_block[k] = Some(sizes.len());
                sizes.push(e.n_states());
                kinds.push(BlockKind::Primary);
                owners.push(BlockOwner::States(k));
            }
        }
        if stabilized {
            for (k, c) in sys.constraints.iter().enumerate() {
                if c.n_equations() > 0 {
                    places[k].projection = Some(sizes.len());
                    sizes.push(c.n_equations());
                    kinds.push(BlockKind::Projection);
                    owners.push(BlockOwner::Projection(k));
                }
            }
        }
        // Block (and column in it) of every configuration unknown.
        let mut config_place: Vec<(usize, usize)> = (0..6 * n).map(|i| (i / 6, i % 6)).collect();
        config_place.resize(sys.n_config(), (0, 0));
        for (k, c) in sys.constraints.iter().enumerate() {
            if let Some(b) = places[k].block {
                for j in 0..c.n_coordinates() {
                    config_place[6 * n + sys.coordinate_offsets[k] + j] = (b, c.n_equations() + j);
                }
            }
        }
        for (k, e) in sys.elements.iter().enumerate() {
            if let Some(b) = state_block[k] {
                for i in 0..e.n_states() {
                    config_place[sys.state_config_index(sys.state_offsets[k] + i)] = (b, i);
                }
            }
        }
        let element_blocks: Vec<Vec<LocalBlock>> = sys
            .elements
            .iter()
            .enumerate()
            .map(|(k, e)| {
                let en = e.nodes();
                let mut b: Vec<LocalBlock> = en
                    .iter()
                    .enumerate()
                    .map(|(a, &na)| LocalBlock {
                        block: na,
                        local: 6 * a,
                        size: 6,
                    })
                    .collect();
                if let Some(sb) = state_block[k] {
                    b.push(LocalBlock {
                        block: sb,
                        local: 6 * en.len(),
                        size: e.n_states(),
                    });
                }
                b
            })
            .collect();
        for (k, blocks) in element_blocks.iter().enumerate() {
            for (i, a) in blocks.iter().enumerate() {
                for b in &blocks[i + 1..] {
                    if a.block != b.block {
                        couplings.push((a.block, b.block));
                    }
                }
            }
            // A consumer's rows couple to the supports of its input signals.
            for &j in &sys.signals.element_inputs[k] {
                for &c in &sys.signals.support[j] {
                    for a in blocks {
                        couplings.push((a.block, config_place[c].0));
                    }
                }
            }
        }
        for (k, c) in sys.constraints.iter().enumerate() {
            let cn = c.nodes();
            for (i, &a) in cn.iter().enumerate() {
                for &b in &cn[i + 1..] {
                    if a != b {
                        couplings.push((a, b));
                    }
                }
                if let Some(blk) = places[k].block {
                    couplings.push((blk, a));
                }
                if let Some(p) = places[k].projection {
                    couplings.push((p, a));
                }
            }
            if let (Some(p), Some(blk)) = (places[k].projection, places[k].block) {
                couplings.push((p, blk));
            }
            if let Some(blk) = places[k].block {
                for &j in &sys.signals.constraint_inputs[k] {
                    for &cfg in &sys.signals.support[j] {
                        couplings.push((blk, config_place[cfg].0));
                    }
                }
            }
        }
        // Constraints sharing a node: (k, l, local index in k, local index in l).
        let mut shared = Vec::new();
        if stabilized {
            for (k, ck) in sys.constraints.iter().enumerate() {
                for (l, cl) in sys.constraints.iter().enumerate() {
                    if k == l || places[k].projection.is_none() || places[l].projection.is_none() {
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
                couplings.push((
                    places[k].projection.unwrap_or(0),
                    places[l].projection.unwrap_or(0),
                ));
            }
        }
        for p in &pairs {
            debug_assert_eq!(
                p.n_states(),
                0,
                "granular pairs have no unknowns of their own"
            );
            let [a, b] = [p.nodes()[0], p.nodes()[1]];
            couplings.push((a, b));
        }
        couplings.retain(|(a, b)| a != b);
        // A relative constraint's multipliers go after either node only if its block
        // couples to no other primary (a signal's support, an element reading a joint
        // coordinate): the rank argument holds for its nodes' columns alone.
        // One pass over the couplings.
        let mut foreign = vec![false; kinds.len()];
        for &(a, b) in &couplings {
            for (m, x) in [(a, b), (b, a)] {
                if kinds[m] == BlockKind::RelativeMultiplier
                    && kinds[x] == BlockKind::Primary
                    && let BlockOwner::Joint(k) = owners[m]
                    && !sys.constraints[k].nodes().contains(&x)
                {
                    foreign[m] = true;
                }
            }
        }
        for (kind, _) in kinds.iter_mut().zip(&foreign).filter(|(_, f)| **f) {
            *kind = BlockKind::Multiplier;
        }
        let structure = Arc::new(
            BlockStructure::new(sizes, kinds, &couplings)
                .expect("block structure of a validated model is consistent"),
        );
        let s = &structure;
        for (k, c) in sys.constraints.iter().enumerate() {
            let p = &mut places[k];
            if let Some(b) = p.block {
                p.lam = s.block_offset(b);
                p.coord = p.lam + c.n_equations();
            }
            if let Some(b) = p.projection {
                p.proj = s.block_offset(b);
            }
        }
        let slot = |i: usize, j: usize| {
            s.entry_index(i, j)
                .expect("pattern contains every coupled block")
        };
        let mut sizes_seen: Vec<(usize, usize)> = Vec::new();
        // Index of a (local unknowns, input signals) size among those seen.
        let mut index_of = |key: (usize, usize)| match sizes_seen.iter().position(|&m| m == key) {
            Some(i) => i,
            None => {
                sizes_seen.push(key);
                sizes_seen.len() - 1
            }
        };
        let batch_end = batches(sys);
        let term_of: Vec<usize> = sys
            .elements
            .iter()
            .enumerate()
            .map(|(k, e)| {
                // A batch's block: the nodes, then the states of each of its elements.
                let nz: usize = (k..batch_end[k].max(k + 1))
                    .map(|j| sys.elements[j].n_states())
                    .sum();
                index_of((6 * e.nodes().len() + nz, e.signal_inputs().len()))
            })
            .collect();
        // The parallel path evaluates every element alone (no batches): its own size.
        let alone_term_of: Vec<usize> = sys
            .elements
            .iter()
            .map(|e| index_of((6 * e.nodes().len() + e.n_states(), e.signal_inputs().len())))
            .collect();
        let terms = sizes_seen
            .iter()
            .map(|&(n, i)| LocalTerms::with_sizes(n, i))
            .collect();
        let element_slots = element_blocks
            .iter()
            .map(|blocks| {
                blocks
                    .iter()
                    .flat_map(|a| blocks.iter().map(move |b| (a.block, b.block)))
                    .map(|(a, b)| slot(a, b))
                    .collect()
            })
            .collect();
        let support_slots = |rows: &[usize], signal: usize| -> Vec<SupportSlot> {
            sys.signals.support[signal]
                .iter()
                .enumerate()
                .map(|(pos, &c)| {
                    let (b, col) = config_place[c];
                    SupportSlot {
                        pos,
                        col,
                        slots: rows.iter().map(|&r| slot(r, b)).collect(),
                    }
                })
                .collect()
        };
        let element_signal_slots = element_blocks
            .iter()
            .enumerate()
            .map(|(k, blocks)| {
                let rows: Vec<usize> = blocks.iter().map(|b| b.block).collect();
                sys.signals.element_inputs[k]
                    .iter()
                    .map(|&j| support_slots(&rows, j))
                    .collect()
            })
            .collect();
        let constraint_signal_slots = (0..sys.constraints.len())
            .map(|k| match places[k].block {
                Some(blk) => sys.signals.constraint_inputs[k]
                    .iter()
                    .map(|&j| support_slots(&[blk], j))
                    .collect(),
                None => Vec::new(),
            })
            .collect();
        let state_place = state_block
            .iter()
            .map(|b| b.map(|b| s.block_offset(b)))
            .collect();
        let constraints = sys
            .constraints
            .iter()
            .zip(places)
            .map(|(c, place)| {
                let cn = c.nodes();
                let m = c.n_equations();
                let nc = c.n_coordinates();
                let nl = 6 * cn.len() + nc;
                let blk = place.block;
                let prj = place.projection;
                ConstraintWork {
                    m,
                    nc,
                    phi: vec![0.0; m],
                    mu: vec![0.0; m],
                    phi_t: vec![0.0; m],
                    force: vec![0.0; nl],
                    b: DMatrix::zeros(m, nl),
                    bt: DMatrix::zeros(m, nl),
                    b_rows: vec![0.0; m * nl],
                    k: DMatrix::zeros(nl, nl),
                    dbv: DMatrix::zeros(m, nl),
                    cf: vec![0.0; nc],
                    cf_k: vec![0.0; nc],
                    cf_c: vec![0.0; nc],
                    vel: vec![0.0; nl],
                    targets: if c.servo_rows().is_empty() {
                        Vec::new()
                    } else {
                        vec![0.0; m]
                    },
                    servos: c
                        .servo_rows()
                        .iter()
                        .filter_map(|s| {
                            let i = c.active_rows().iter().position(|&r| r == s.row)?;
                            Some((i, s.input, s.coordinate))
                        })
                        .collect(),
                    node_slots: cn
                        .iter()
                        .flat_map(|&a| cn.iter().map(move |&b| (a, b)))
                        .map(|(a, b)| slot(a, b))
                        .collect(),
                    lam_col: blk.map_or(Vec::new(), |j| cn.iter().map(|&a| slot(a, j)).collect()),
                    lam_row: blk.map_or(Vec::new(), |j| cn.iter().map(|&a| slot(j, a)).collect()),
                    diag: blk.map_or(0, |j| slot(j, j)),
                    proj_row: prj.map_or(Vec::new(), |p| cn.iter().map(|&a| slot(p, a)).collect()),
                    proj_blk: match (prj, blk) {
                        (Some(p), Some(j)) => slot(p, j),
                        _ => 0,
                    },
                    proj_diag: prj.map_or(0, |p| slot(p, p)),
                    place,
                }
            })
            .collect::<Vec<_>>();
        let nu_pairs = shared
            .iter()
            .map(|&(k, l, a, b)| {
                let (pk, pl) = (
                    constraints[k].place.projection.unwrap_or(0),
                    constraints[l].place.projection.unwrap_or(0),
                );
                (k, l, slot(pk, pl), a, b)
            })
            .collect();
        let signal_values = sys.signals.values(&sys.elements);
        let signal_combined = sys
            .signals
            .support
            .iter()
            .map(|s| vec![0.0; s.len()])
            .collect();
        let parallel = sys.elements.len() >= PARALLEL_MIN_ELEMENTS;
        let window = if parallel {
            let max_inputs = sys
                .elements
                .iter()
                .map(|e| e.signal_inputs().len())
                .max()
                .unwrap_or(0);
            (0..PARALLEL_WINDOW.min(sys.elements.len()))
                .map(|_| WindowSlot {
                    terms: sizes_seen
                        .iter()
                        .map(|&(n, i)| LocalTerms::with_sizes(n, i))
                        .collect(),
                    inputs: Vec::with_capacity(max_inputs),
                })
                .collect()
        } else {
            Vec::new()
        };
        let pair_slots = pairs
            .iter()
            .map(|p| {
                let [a, b] = [p.nodes()[0], p.nodes()[1]];
                [slot(a, a), slot(a, b), slot(b, a), slot(b, b)]
            })
            .collect();
        Self {
            pairs,
            pair_slots,
            pair_terms: LocalTerms::new(2),
            formulation,
            structure,
            terms,
            term_of,
            alone_term_of,
            batch_end,
            window,
            element_blocks,
            element_slots,
            state_place,
            element_signal_slots,
            constraint_signal_slots,
            config_place,
            owners,
            signal_values,
            signal_combined,
            inputs: Vec::new(),
            constraint_inputs: Vec::new(),
            cf_ds: Vec::new(),
            servo_grad: vec![0.0; sys.signals.support.iter().map(Vec::len).max().unwrap_or(0)],
            constraints,
            nu_pairs,
            rate_maps: Vec::new(),
            split: None,
        }
    }

    /// Plans the two-part assembly from the part of each block (0, 1, else the
    /// separator; none: the order has no separator). Refused (with the reason) for
    /// granular contact sets, whose candidate pairs change the pattern (and the order)
    /// during the run.
    pub fn plan_split(&mut self, sys: &System, part: Option<&[u8]>) -> Result<(), &'static str> {
        self.split = None;
        if !sys.granular.is_empty() || !self.pairs.is_empty() {
            return Err("granular contact sets change the pattern during the run");
        }
        let part = part.ok_or("nested dissection found no separator in the pattern")?;
        let of = |blocks: &mut dyn Iterator<Item = usize>| -> usize {
            let mut p: Option<u8> = None;
            for b in blocks {
                let q = part[b];
                if q > 1 || p.is_some_and(|p| p != q) {
                    return 2;
                }
                p = Some(q);
            }
            p.map_or(2, |p| p as usize)
        };
        // The blocks an item writes: its rows' blocks and, through its input signals,
        // the blocks of the signals' supports (columns).
        fn support<'a>(
            sys: &'a System,
            place: &'a [(usize, usize)],
            inputs: &'a [usize],
        ) -> impl Iterator<Item = usize> + 'a {
            inputs
                .iter()
                .flat_map(|&j| sys.signals.support[j].iter())
                .map(|&c| place[c].0)
        }
        let place = &self.config_place[..];
        let mut starts: [Vec<usize>; 3] = Default::default();
        let mut k = 0;
        while k < sys.elements.len() {
            let end = self.batch_end[k];
            let rows = (k..end).flat_map(|j| self.element_blocks[j].iter().map(|b| b.block));
            let cols = (k..end).flat_map(|j| support(sys, place, &sys.signals.element_inputs[j]));
            starts[of(&mut rows.chain(cols))].push(k);
            k = end;
        }
        let mut cons: [Vec<usize>; 3] = Default::default();
        for (k, c) in sys.constraints.iter().enumerate() {
            let w = &self.constraints[k];
            let nodes = c.nodes().iter().map(|&n| self.config_place[6 * n].0);
            let cols = support(sys, place, &sys.signals.constraint_inputs[k]);
            let p = of(&mut nodes
                .chain(w.place.block)
                .chain(w.place.projection)
                .chain(cols));
            cons[p].push(k);
        }
        let partner = Assembler::new(sys, self.formulation);
        let mut nodes: [Vec<usize>; 2] = Default::default();
        let mut node_part = vec![0; sys.n_nodes()];
        for (i, np) in node_part.iter_mut().enumerate() {
            *np = (part[self.config_place[6 * i].0] == 1) as u8;
            nodes[*np as usize].push(i);
        }
        // Joint coordinates go with their constraint; the separator's with part 0.
        let mut passive: [Vec<usize>; 2] = Default::default();
        let mut coord_part = vec![0u8; sys.n_coordinates + sys.n_passive];
        for (p, list) in [&cons[0], &cons[2], &cons[1]].into_iter().enumerate() {
            let p = usize::from(p == 2);
            for &k in list {
                let c = &sys.constraints[k];
                let (a, np) = (sys.coordinate_offsets[k], c.n_passive_coordinates());
                let q = sys.n_coordinates + sys.passive_offsets[k];
                coord_part[a..a + c.n_coordinates()].fill(p as u8);
                coord_part[q..q + np].fill(p as u8);
                if np > 0 {
                    passive[p].push(k);
                }
            }
        }
        let servos = sys.constraints.iter().any(|c| !c.servo_rows().is_empty());
        let checks = (!servos).then(|| {
            let mut row_part = vec![0u8; sys.n_multipliers];
            for &k in &cons[1] {
                let off = sys.multiplier_offsets[k];
                row_part[off..off + sys.constraints[k].n_equations()].fill(1);
            }
            let part0 = cons[0].iter().chain(&cons[2]).copied().collect();
            PartChecks {
                constraints: [part0, cons[1].clone()],
                row_part,
            }
        });
        let st = &*self.structure;
        let mut entry_part = vec![2u8; st.n_entries()];
        for i in 0..st.n_blocks() {
            for j in 0..st.n_blocks() {
                if let Some(e) = st.entry_index(i, j)
                    && part[i] == part[j]
                    && part[i] < 2
                {
                    entry_part[e] = part[i];
                }
            }
        }
        let rows1: Vec<Range<usize>> = (0..st.n_blocks())
            .filter(|&b| part[b] == 1)
            .map(|b| st.block_offset(b)..st.block_offset(b) + st.block_size(b))
            .collect();
        let residual1 = vec![0.0; st.dim()];
        self.split = Some(Box::new(SplitPlan {
            entry_part,
            residual1,
            rows1,
            nodes,
            node_part,
            passive,
            coord_part,
            checks,
            starts,
            cons,
            partner,
        }));
        Ok(())
    }

    /// The two-part plan, if any.
    pub fn split_plan(&self) -> Option<&SplitPlan> {
        self.split.as_deref()
    }

    /// Block of the iteration matrix and column in it of configuration unknown `i`.
    pub fn config_place(&self, i: usize) -> (usize, usize) {
        self.config_place[i]
    }

    /// What a block of the iteration matrix belongs to.
    pub fn block_owner(&self, block: usize) -> Option<BlockOwner> {
        self.owners.get(block).copied()
    }

    /// Name of a block for messages.
    pub fn block_name(&self, sys: &System, block: usize) -> String {
        match self.block_owner(block) {
            Some(BlockOwner::Node(i)) => format!("node '{}'", sys.node_names[i]),
            Some(BlockOwner::Joint(k)) | Some(BlockOwner::Projection(k)) => {
                format!("joint '{}'", sys.constraints[k].name())
            }
            Some(BlockOwner::States(k)) => {
                format!("the states of element '{}'", sys.elements[k].name())
            }
            None => format!("block {block}"),
        }
    }

    /// Range of element k's states in the Newton vector (empty without states).
    pub fn state_range(&self, sys: &System, k: usize) -> Range<usize> {
        match self.state_place[k] {
            Some(o) => o..o + sys.n_states_of(k),
            None => 0..0,
        }
    }

    /// The granular candidate pairs' contacts ([`Assembler::with_pairs`]).
    pub fn pairs(&self) -> &[SpherePair] {
        &self.pairs
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

    /// Range of constraint k's multipliers in the Newton vector.
    pub fn multiplier_range(&self, k: usize) -> Range<usize> {
        let w = &self.constraints[k];
        w.place.lam..w.place.lam + w.m
    }

    /// Range of constraint k's coordinates in the Newton vector.
    pub fn coordinate_range(&self, k: usize) -> Range<usize> {
        let w = &self.constraints[k];
        w.place.coord..w.place.coord + w.nc
    }

    /// Range of constraint k's projection multipliers (stabilized only; empty otherwise).
    pub fn projection_range(&self, k: usize) -> Range<usize> {
        let w = &self.constraints[k];
        match w.place.projection {
            Some(_) => w.place.proj..w.place.proj + w.m,
            None => 0..0,
        }
    }

    /// Gathers the configuration part of a Newton vector `v` (6 per node, then the
    /// coordinates in state order) into `cfg`.
    pub fn configuration_of(&self, sys: &System, v: &[f64], cfg: &mut [f64]) {
        let n6 = 6 * sys.n_nodes();
        cfg[..n6].copy_from_slice(&v[..n6]);
        for (k, off) in sys.coordinate_offsets.iter().enumerate() {
            let r = self.coordinate_range(k);
            cfg[n6 + off..n6 + off + r.len()].copy_from_slice(&v[r]);
        }
        for k in 0..sys.elements.len() {
            let r = self.state_range(sys, k);
            let o = sys.state_config_index(sys.state_offsets[k]);
            cfg[o..o + r.len()].copy_from_slice(&v[r]);
        }
    }

    /// Gathers the multipliers of a Newton vector `v` in `sys.multiplier_offsets` order.
    pub fn multipliers_of(&self, sys: &System, v: &[f64], out: &mut [f64]) {
        for (k, off) in sys.multiplier_offsets.iter().enumerate() {
            let r = self.multiplier_range(k);
            out[*off..off + r.len()].copy_from_slice(&v[r]);
        }
    }

    /// Adds `w_node[i]` to the 6 diagonal entries of each node block and `w_coord` to the
    /// coordinate diagonal (the metric of a projection onto the constraints).
    pub fn add_configuration_metric(
        &self,
        sys: &System,
        matrix: &mut BlockMatrix,
        w_node: &[f64; 6],
        w_coord: f64,
    ) {
        let s = matrix.structure.clone();
        for i in 0..sys.n_nodes() {
            let e = s.entry_index(i, i).expect("diagonal blocks exist");
            let v = matrix.view(e);
            for (k, w) in w_node.iter().enumerate() {
                v.values[v.at(k, k)] += w;
            }
        }
        for w in &self.constraints {
            let v = matrix.view(w.diag);
            for c in 0..w.nc {
                let d = w.m + c;
                v.values[v.at(d, d)] += w_coord;
            }
        }
        // Element states do not enter the constraints: keep them (unit weight).
        for (k, e) in sys.elements.iter().enumerate() {
            if e.n_states() == 0 {
                continue;
            }
            let blocks = &self.element_blocks[k];
            let nb = blocks.len();
            let v = matrix.view(self.element_slots[k][nb * nb - 1]);
            for i in 0..e.n_states() {
                v.values[v.at(i, i)] += 1.0;
            }
        }
    }

    /// Sets (or, with an empty slice, clears) the rate maps of the nodes: from then on
    /// the stiffness columns of every node carry `C A_v + M A₀` as well.
    pub fn set_rate_maps(&mut self, maps: &[RateMaps]) {
        self.rate_maps.clear();
        self.rate_maps.extend_from_slice(maps);
    }

    isa::copies! {
        /// Assembles the residual (always) and the iteration matrix (if given).
        ///
        /// `tangent_ops[i]` is the tangent operator of node i's rotation update; an empty
        /// slice means identity.
        ///
        /// On x86-64 CPUs with AVX2 and FMA the scatter runs in a copy compiled for them,
        /// its multiply–adds fused ([`Fused`]: one rounding, so results differ from the
        /// other copies in round-off; the same copy on CPUs with AVX-512); with AVX alone
        /// in a copy compiled for AVX (the same operations in the same order as the
        /// baseline, the same bits). The elements and constraints it calls through `dyn`
        /// are not affected.
        #[allow(clippy::too_many_arguments)]
        pub fn assemble(
            &mut self: Assembler,
            sys: &System,
            state: &State,
            ctx: &EvalContext,
            coef: &Coefficients,
            tangent_ops: &[Matrix3<f64>],
            residual: &mut [f64],
            matrix: Option<&mut BlockMatrix>,
        ) {
            Base | Avx => assemble_impl::<Separate>,
            Fma => assemble_impl::<Fused>,
        }
    }

    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn assemble_impl<M: MulAdd>(
        &mut self,
        sys: &System,
        state: &State,
        ctx: &EvalContext,
        coef: &Coefficients,
        tangent_ops: &[Matrix3<f64>],
        residual: &mut [f64],
        mut matrix: Option<&mut BlockMatrix>,
    ) {
        let stabilized = self.formulation == Formulation::StabilizedIndex2;
        let inputs = Inputs {
            sys,
            state,
            ctx,
            coef,
            tangent_ops,
        };
        residual.fill(0.0);
        if let Some(m) = matrix.as_deref_mut() {
            m.fill_zero();
        }
        let sr = coef.row_scale;

        // Signals first (in producer order), with their derivatives combined like the
        // columns they belong to.
        let has_signals = !sys.signals.names.is_empty();
        if has_signals {
            sys.signals.evaluate(
                &sys.elements,
                &sys.state_offsets,
                ctx,
                state,
                &mut self.signal_values,
                matrix.is_some(),
            );
            if matrix.is_some() {
                self.combine_signal_gradients(sys, coef, tangent_ops);
            }
        }
        if let Some(mut plan) = self.split.take() {
            // Part 0 here, part 1 on the partner thread (into its own residual rows and
            // the blocks it owns), then the items on the separator.
            let SplitPlan {
                partner,
                residual1,
                rows1,
                entry_part,
                starts,
                cons,
                ..
            } = &mut *plan;
            if has_signals {
                self.share_signals(partner, matrix.is_some());
            }
            {
                let [mut t0, mut t1] = match matrix.as_deref_mut() {
                    Some(m) => m.part_targets(entry_part).map(Some),
                    None => [None, None],
                };
                let this = &mut *self;
                let r0 = &mut *residual;
                let (s0, c0, s1, c1) = (&starts[0], &cons[0], &starts[1], &cons[1]);
                crate::solve::partner::join2(
                    move || {
                        let m = t0.as_mut();
                        this.assemble_items(inputs, r0, m, s0, c0);
                    },
                    || {
                        for r in rows1.iter() {
                            residual1[r.clone()].fill(0.0);
                        }
                        let (r1, m) = (&mut residual1[..], t1.as_mut());
                        partner.assemble_items(inputs, r1, m, s1, c1);
                    },
                );
            }
            for r in rows1.iter() {
                residual[r.clone()].copy_from_slice(&residual1[r.clone()]);
            }
            // The projection (its couplings below, `add_projection` after the solve) reads
            // every constraint's B and B T: part 1's from the partner's workspaces.
            if stabilized {
                for &k in &cons[1] {
                    let (from, into) = (&partner.constraints[k], &mut self.constraints[k]);
                    into.b.copy_from(&from.b);
                    into.bt.copy_from(&from.bt);
                }
            }
            let mut whole = matrix.as_deref_mut().map(|m| m.target());
            self.assemble_items(inputs, residual, whole.as_mut(), &starts[2], &cons[2]);
            self.split = Some(plan);
            if let Some(mat) = matrix
                && stabilized
            {
                self.add_projection_couplings(mat);
            }
            return;
        }
        let mut tgt = matrix.as_deref_mut().map(|m| m.target());
        if self.window.is_empty() {
            self.element_loop::<M>(inputs, residual, tgt.as_mut(), None);
        } else {
            // Large models, a window of elements at a time: each element of the window into
            // its own slot in parallel, then the same scatter in element order, so the sums
            // (and results) do not depend on the number of threads, and the scratch in use
            // stays a window's (in the caches) however many elements there are. The loop
            // runs on one of rayon's threads (`scope`): the windows are then shared out
            // without handing each over from outside the pool (a thread wake-up per window,
            // as much as a residual-only window costs). The closures run compiled for the
            // baseline (they do not inherit this copy's target features), so their kernels
            // take `Separate` multiply–adds: the windowed models' results are the same in
            // every copy.
            use rayon::prelude::*;
            let tangents = tgt.is_some().then_some(TangentInputs {
                coef,
                tangent_ops,
                rate_maps: &self.rate_maps,
            });
            let tangents = tangents.as_ref();
            // Taken out for the loop (a move, no allocation) and put back after it.
            let mut window = std::mem::take(&mut self.window);
            let this = &*self;
            rayon::scope(|_| {
                let values = &this.signal_values.values;
                let n = sys.elements.len();
                let mut start = 0;
                while start < n {
                    let len = window.len().min(n - start);
                    let term_of = &this.alone_term_of[start..start + len];
                    window[..len]
                        .par_iter_mut()
                        .zip(term_of.par_iter())
                        .enumerate()
                        .with_min_len(PARALLEL_CHUNK)
                        .for_each(|(i, (slot, &size))| {
                            let k = start + i;
                            element_terms::<Separate>(
                                sys,
                                k..k + 1,
                                state,
                                ctx,
                                values,
                                tangents,
                                &mut slot.terms[size],
                                &mut slot.inputs,
                            );
                        });
                    for (i, slot) in window[..len].iter().enumerate() {
                        let k = start + i;
                        let t = &slot.terms[this.alone_term_of[k]];
                        this.scatter_element::<Separate>(
                            sys,
                            k..k + 1,
                            t,
                            coef,
                            residual,
                            tgt.as_mut(),
                        );
                    }
                    start += len;
                }
            });
            self.window = window;
        }
        let tangents = tgt.is_some().then_some(TangentInputs {
            coef,
            tangent_ops,
            rate_maps: &self.rate_maps,
        });
        // Granular candidate pairs: node blocks only; their bristles (history) from the
        // state, aligned with the pairs.
        debug_assert!(
            state.pair_bristles.is_empty() || state.pair_bristles.len() == self.pairs.len()
        );
        for (k, (p, slots)) in self.pairs.iter_mut().zip(&self.pair_slots).enumerate() {
            let z0 = state
                .pair_bristles
                .get(k)
                .map_or(nalgebra::Vector3::zeros(), |b| b.z);
            p.set_bristle(z0, coef.step);
            let t = &mut self.pair_terms;
            let need = if tangents.is_some() {
                Need::ResidualAndTangents
            } else {
                Need::Residual
            };
            t.clear(need);
            p.evaluate(ctx, &ElementInput::nodes(&state.nodes), need, t);
            let en = p.nodes();
            for (a, &na) in en.iter().enumerate() {
                for i in 0..6 {
                    residual[6 * na + i] += sr * t.r[6 * a + i];
                }
            }
            let (Some(tg), Some(mat)) = (tangents.as_ref(), tgt.as_mut()) else {
                continue;
            };
            combine_node_terms::<M>(t, en, tg);
            for a in 0..2 {
                for b in 0..2 {
                    add_block6(mat.view(slots[2 * a + b]), t.k.as_slice(), 12, a, b);
                }
            }
        }

        self.constraint_loop::<M>(inputs, residual, tgt.as_mut(), None);
        if let Some(mat) = matrix
            && stabilized
        {
            self.add_projection_couplings(mat);
        }
    }

    isa::copies! {
        /// The listed batches and constraints only (one part of a split).
                pub(crate) fn assemble_items(
            &mut self: Assembler,
            inputs: Inputs<'_>,
            residual: &mut [f64],
            matrix: Option<&mut BlockTarget<'_>>,
            starts: &[usize],
            cons: &[usize],
        ) {
            Base | Avx => assemble_items_impl::<Separate>,
            Fma => assemble_items_impl::<Fused>,
        }
    }

    #[inline(always)]
    fn assemble_items_impl<M: MulAdd>(
        &mut self,
        inputs: Inputs<'_>,
        residual: &mut [f64],
        mut matrix: Option<&mut BlockTarget<'_>>,
        starts: &[usize],
        cons: &[usize],
    ) {
        self.element_loop::<M>(inputs, residual, matrix.as_deref_mut(), Some(starts));
        self.constraint_loop::<M>(inputs, residual, matrix, Some(cons));
    }

    /// The batches (all, or those starting at `starts`), evaluated and scattered through
    /// the shared scratch.
    #[inline(always)]
    fn element_loop<M: MulAdd>(
        &mut self,
        inputs: Inputs<'_>,
        residual: &mut [f64],
        mut matrix: Option<&mut BlockTarget<'_>>,
        starts: Option<&[usize]>,
    ) {
        let (sys, state, ctx, coef, tangent_ops) = inputs.all();
        let tangents = matrix.is_some().then_some(TangentInputs {
            coef,
            tangent_ops,
            rate_maps: &self.rate_maps,
        });
        let count = starts.map_or(sys.elements.len(), |l| l.len());
        let mut i = 0;
        let mut k = 0;
        while i < count && k < sys.elements.len() {
            if let Some(l) = starts {
                k = l[i];
            }
            let end = self.batch_end[k];
            let t = &mut self.terms[self.term_of[k]];
            element_terms::<M>(
                sys,
                k..end,
                state,
                ctx,
                &self.signal_values.values,
                tangents.as_ref(),
                t,
                &mut self.inputs,
            );
            let t = &self.terms[self.term_of[k]];
            self.scatter_element::<M>(sys, k..end, t, coef, residual, matrix.as_deref_mut());
            k = end;
            i += 1;
        }
    }

    /// The constraints' rows (all, or those in `list`) into the residual and the matrix.
    #[inline(always)]
    fn constraint_loop<M: MulAdd>(
        &mut self,
        inputs: Inputs<'_>,
        residual: &mut [f64],
        mut matrix: Option<&mut BlockTarget<'_>>,
        list: Option<&[usize]>,
    ) {
        let (sys, state, ctx, coef, tangent_ops) = inputs.all();
        let stabilized = self.formulation == Formulation::StabilizedIndex2;
        let sr = coef.row_scale;
        let count = list.map_or(sys.constraints.len(), |l| l.len());
        for i in 0..count {
            let k = list.map_or(i, |l| l[i]);
            let c = &sys.constraints[k];
            let w = &mut self.constraints[k];
            let (m, nc) = (w.m, w.nc);
            let off = sys.multiplier_offsets[k];
            let coords = sys.coords_of(k, state);
            // One evaluation of the rows: Φ, μ, Bᵀμ and, for the matrix, B and
            // ∂(Bᵀμ)/∂q (a constraint without unknowns left has no block to add them to).
            let with_tangent = matrix.is_some() && w.place.block.is_some();
            // Servo rows: their signals' values are the targets of Φ = ν − s.
            for &(i, j, _) in &w.servos {
                w.targets[i] = self.signal_values.values[sys.signals.constraint_inputs[k][j]];
            }
            c.evaluate_rows(
                ctx,
                &state.nodes,
                coords,
                &state.lambda[off..off + m],
                coef.penalty,
                RowTerms {
                    phi: &mut w.phi,
                    mu: &mut w.mu,
                    force: &mut w.force,
                    b: &mut w.b,
                    want_b: stabilized,
                    tangent: with_tangent.then_some(&mut w.k),
                    targets: &w.targets,
                },
            );
            let cn = c.nodes();
            let n = cn.len();
            let nq = 6 * n;
            let nl = nq + nc;
            // The velocities enter the stabilized formulation only (B v and ∂(B v)/∂q).
            if stabilized {
                local_velocities(&mut w.vel, cn, state, coords);
            }
            let p = &w.place;
            if stabilized {
                // λ rows: s_v (B v + Φ_t); η rows: Φ.
                c.velocity_term(ctx, &mut w.phi_t);
                for i in 0..m {
                    let mut bv = w.phi_t[i];
                    for j in 0..nl {
                        bv += w.b[(i, j)] * w.vel[j];
                    }
                    residual[p.lam + i] = coef.velocity_scale * bv;
                    residual[p.proj + i] = w.phi[i];
                }
            } else {
                for i in 0..m {
                    residual[p.lam + i] = w.phi[i];
                }
            }
            // Configuration rows: s_r Bᵀ μ; coordinate rows also s_r f_ν.
            for (a, &na) in cn.iter().enumerate() {
                for (r, f) in residual[6 * na..6 * na + 6]
                    .iter_mut()
                    .zip(&w.force[6 * a..6 * a + 6])
                {
                    *r += sr * f;
                }
            }
            if nc > 0 {
                for (r, f) in residual[p.coord..p.coord + nc]
                    .iter_mut()
                    .zip(&w.force[nq..nl])
                {
                    *r += sr * f;
                }
            }
            let n_in = sys.signals.constraint_inputs[k].len();
            if nc > 0 {
                w.cf.fill(0.0);
                w.cf_k.fill(0.0);
                w.cf_c.fill(0.0);
                self.constraint_inputs.clear();
                self.constraint_inputs.extend(
                    sys.signals.constraint_inputs[k]
                        .iter()
                        .map(|&j| self.signal_values.values[j]),
                );
                self.cf_ds.clear();
                self.cf_ds.resize(nc * n_in, 0.0);
                let tangents = matrix.is_some().then_some(CoordinateTangents {
                    stiffness: &mut w.cf_k,
                    damping: &mut w.cf_c,
                    signals: &mut self.cf_ds,
                });
                c.coordinate_forces(ctx, coords, &self.constraint_inputs, &mut w.cf, tangents);
                for j in 0..nc {
                    residual[p.coord + j] += sr * w.cf[j];
                }
            }
            let Some(mat) = matrix.as_deref_mut() else {
                continue;
            };
            let p = &w.place;
            if p.block.is_none() {
                // Every row dropped as redundant and no coordinates: nothing to add.
                continue;
            }
            if coef.penalty != 0.0 {
                add_gram::<M>(
                    w.k.as_mut_slice(),
                    w.b.as_slice(),
                    &mut w.b_rows,
                    m,
                    nl,
                    coef.penalty,
                );
            }
            // T is applied to the node columns as they are added (no scaled copies).
            let t_of = |a: usize| tangent_ops.get(cn[a]);
            if stabilized {
                w.bt.copy_from(&w.b);
                apply_tangent_ops(&mut w.bt, cn, tangent_ops);
            }
            let skk = sr * coef.stiffness;
            // (config, config): s_r c_K (K_c + ρ BᵀB) T, plus the coordinate elements.
            for a in 0..n {
                for b in 0..n {
                    add_node_columns::<M>(
                        &mut mat.view(w.node_slots[a * n + b]),
                        (0, 0),
                        w.k.as_slice(),
                        nl,
                        (6 * a, 6 * b),
                        6,
                        t_of(b),
                        skk,
                    );
                }
            }
            if nc > 0 {
                for a in 0..n {
                    add_sub::<M>(
                        &mut mat.view(w.lam_col[a]),
                        (0, m),
                        w.k.as_slice(),
                        nl,
                        (6 * a, nq),
                        (6, nc),
                        skk,
                    );
                    add_node_columns::<M>(
                        &mut mat.view(w.lam_row[a]),
                        (m, 0),
                        w.k.as_slice(),
                        nl,
                        (nq, 6 * a),
                        nc,
                        t_of(a),
                        skk,
                    );
                }
                let d = &mut mat.view(w.diag);
                add_sub::<M>(d, (m, m), w.k.as_slice(), nl, (nq, nq), (nc, nc), skk);
                for j in 0..nc {
                    let i = d.at(m + j, m + j);
                    d.values[i] += sr * (coef.stiffness * w.cf_k[j] + coef.damping * w.cf_c[j]);
                }
                // Chain rule through the input ports' signals.
                for (i, supports) in self.constraint_signal_slots[k].iter().enumerate() {
                    let g = &self.signal_combined[sys.signals.constraint_inputs[k][i]];
                    for sp in supports {
                        for j in 0..nc {
                            let ds = self.cf_ds[j * n_in + i];
                            if ds != 0.0 {
                                let v = mat.view(sp.slots[0]);
                                v.values[v.at(m + j, sp.col)] += sr * ds * g[sp.pos];
                            }
                        }
                    }
                }
                // Servo rows (index 3): −∂s/∂Δ in the row, at the weight of B (the K
                // channel at 1, so the initial projections see it too); the penalty's
                // −ρ ∂s/∂Δ in the coordinate's row.
                for &(i, j, cc) in &w.servos {
                    let sid = sys.signals.constraint_inputs[k][j];
                    let len = sys.signals.support[sid].len();
                    combine_gradient(
                        sys,
                        &sys.signals.support[sid],
                        &self.signal_values.gradients[sid],
                        coef,
                        1.0,
                        tangent_ops,
                        &mut self.servo_grad[..len],
                    );
                    for sp in &self.constraint_signal_slots[k][j] {
                        let g = self.servo_grad[sp.pos];
                        let v = mat.view(sp.slots[0]);
                        v.values[v.at(i, sp.col)] -= g;
                        v.values[v.at(m + cc, sp.col)] -= sr * coef.penalty * g;
                    }
                }
            }
            // (config, λ): (s_r/s_λ) Bᵀ.
            let cs = sr / coef.multiplier_scale;
            for a in 0..n {
                add_sub_t::<M>(
                    &mut mat.view(w.lam_col[a]),
                    (0, 0),
                    w.b.as_slice(),
                    m,
                    (0, 6 * a),
                    (6, m),
                    cs,
                );
            }
            if nc > 0 {
                let d = &mut mat.view(w.diag);
                add_sub_t::<M>(d, (m, 0), w.b.as_slice(), m, (0, nq), (nc, m), cs);
            }
            if stabilized {
                // ∂(B v)/∂q, row r = vᵀ ∂(B_rᵀ)/∂q = vᵀ K(e_r), then times T.
                c.velocity_tangent(ctx, &state.nodes, coords, &w.vel[..nl], &mut w.dbv);
                apply_tangent_ops(&mut w.dbv, cn, tangent_ops);
            }
            // (λ, config): B T (index 3) or s_v (γ' B + ∂(Bv)/∂q T) (stabilized); `with_t`:
            // apply T to the node columns of `src` on the way.
            // A function, not a closure: a closure called three times was not inlined and
            // ran compiled for the baseline, outside this AVX copy.
            #[inline(always)]
            #[allow(clippy::too_many_arguments)]
            fn lam_rows<M: MulAdd>(
                mat: &mut BlockTarget<'_>,
                (lam_row, diag): (&[usize], usize),
                (m, nc): (usize, usize),
                (cn, ops): (&[usize], &[Matrix3<f64>]),
                src: &DMatrix<f64>,
                scale: f64,
                with_t: bool,
            ) {
                let nq = 6 * lam_row.len();
                for (a, &slot) in lam_row.iter().enumerate() {
                    add_node_columns::<M>(
                        &mut mat.view(slot),
                        (0, 0),
                        src.as_slice(),
                        m,
                        (0, 6 * a),
                        m,
                        if with_t { ops.get(cn[a]) } else { None },
                        scale,
                    );
                }
                if nc > 0 {
                    let d = &mut mat.view(diag);
                    add_sub::<M>(d, (0, m), src.as_slice(), m, (0, nq), (m, nc), scale);
                }
            }
            let rows = (&w.lam_row[..], w.diag);
            let ts = (cn, tangent_ops);
            if stabilized {
                let sc = coef.velocity_scale * coef.damping;
                lam_rows::<M>(mat, rows, (m, nc), ts, &w.b, sc, false);
                lam_rows::<M>(mat, rows, (m, nc), ts, &w.dbv, coef.velocity_scale, false);
            } else {
                lam_rows::<M>(mat, rows, (m, nc), ts, &w.b, 1.0, true);
            }
            if stabilized && p.projection.is_some() {
                // (η, config): B T; (η, η): B T Bᵀ.
                for a in 0..n {
                    add_sub::<M>(
                        &mut mat.view(w.proj_row[a]),
                        (0, 0),
                        w.bt.as_slice(),
                        m,
                        (0, 6 * a),
                        (m, 6),
                        1.0,
                    );
                }
                if nc > 0 {
                    add_sub::<M>(
                        &mut mat.view(w.proj_blk),
                        (0, m),
                        w.bt.as_slice(),
                        m,
                        (0, nq),
                        (m, nc),
                        1.0,
                    );
                }
                let dst = mat.view(w.proj_diag);
                let (bt, b) = (w.bt.as_slice(), w.b.as_slice());
                for r in 0..m {
                    for s in 0..m {
                        let rows = bt[r..].iter().step_by(m).zip(b[s..].iter().step_by(m));
                        let acc = rows.take(nl).fold(0.0, |acc, (x, y)| acc + x * y);
                        dst.values[dst.at(r, s)] += acc;
                    }
                }
            }
        }
    }

    /// Adds the terms of the elements `ks` (one element, or a batch from [`batches`];
    /// from [`element_terms`]) into the residual and, if given, the iteration matrix,
    /// with the chain rule through the input signals.
    #[inline(always)]
    fn scatter_element<M: MulAdd>(
        &self,
        sys: &System,
        ks: Range<usize>,
        t: &LocalTerms,
        coef: &Coefficients,
        residual: &mut [f64],
        matrix: Option<&mut BlockTarget<'_>>,
    ) {
        let k = ks.start;
        let e = &sys.elements[k];
        let sr = coef.row_scale;
        let en = e.nodes();
        for (a, &na) in en.iter().enumerate() {
            for i in 0..6 {
                residual[6 * na + i] += sr * t.r[6 * a + i];
            }
        }
        let n6 = 6 * en.len();
        // Each element's states after the previous ones' (a batch's block).
        let mut shift = 0;
        for j in ks.clone() {
            let nz = sys.n_states_of(j);
            if let Some(o) = self.state_place[j] {
                for i in 0..nz {
                    residual[o + i] += coef.state_row_scale * t.r[n6 + shift + i];
                }
            }
            shift += nz;
        }
        let Some(mat) = matrix else {
            return;
        };
        if ks.len() > 1 && shift > 0 {
            self.scatter_batch_matrix(sys, ks, t, mat);
            return;
        }
        let nz = shift;
        let blocks = &self.element_blocks[k];
        let nb = blocks.len();
        let slots = &self.element_slots[k];
        let nl = n6 + nz;
        debug_assert_eq!(nl, t.r.len(), "element terms of the element's own size");
        if nz == 0 {
            // Node blocks only: 6×6 each (sizes known at compile time: the hot path).
            let n = en.len();
            for a in 0..n {
                for b in 0..n {
                    add_block6(mat.view(slots[a * n + b]), t.k.as_slice(), nl, a, b);
                }
            }
        } else {
            for (a, ra) in blocks.iter().enumerate() {
                for (b, cb) in blocks.iter().enumerate() {
                    add_sub::<M>(
                        &mut mat.view(slots[a * nb + b]),
                        (0, 0),
                        t.k.as_slice(),
                        nl,
                        (ra.local, cb.local),
                        (ra.size, cb.size),
                        1.0,
                    );
                }
            }
        }
        // Chain rule through the input signals: rows · (∂r/∂s) (∂s/∂x).
        for (j, supports) in self.element_signal_slots[k].iter().enumerate() {
            let g = &self.signal_combined[sys.signals.element_inputs[k][j]];
            for sp in supports {
                let gv = g[sp.pos];
                if gv == 0.0 {
                    continue;
                }
                for (a, ra) in blocks.iter().enumerate() {
                    let rs = if ra.local < n6 {
                        sr
                    } else {
                        coef.state_row_scale
                    };
                    let v = mat.view(sp.slots[a]);
                    for i in 0..ra.size {
                        let d = t.ds[(ra.local + i, j)];
                        v.values[v.at(i, sp.col)] += rs * d * gv;
                    }
                }
            }
        }
    }

    /// The iteration-matrix block of a batch whose elements have states (no input
    /// signals, [`batches`]): the node blocks once, then per element its state rows and
    /// columns against the nodes and its own states (the states of two elements of the
    /// batch do not couple: those entries of the block are zero).
    fn scatter_batch_matrix(
        &self,
        sys: &System,
        ks: Range<usize>,
        t: &LocalTerms,
        mat: &mut BlockTarget<'_>,
    ) {
        let k = ks.start;
        let n = sys.elements[k].nodes().len();
        let n6 = 6 * n;
        let nl = t.r.len();
        let src = t.k.as_slice();
        {
            let nb = self.element_blocks[k].len();
            let slots = &self.element_slots[k];
            for a in 0..n {
                for b in 0..n {
                    add_block6(mat.view(slots[a * nb + b]), src, nl, a, b);
                }
            }
        }
        let mut shift = 0;
        for j in ks {
            let blocks = &self.element_blocks[j];
            let nb = blocks.len();
            let slots = &self.element_slots[j];
            // The local position of block `x` of element j in the batch's block.
            let local = |x: &LocalBlock| {
                if x.local < n6 {
                    x.local
                } else {
                    x.local + shift
                }
            };
            for (a, ra) in blocks.iter().enumerate() {
                for (b, cb) in blocks.iter().enumerate() {
                    if ra.local < n6 && cb.local < n6 {
                        continue;
                    }
                    add_sub::<Separate>(
                        &mut mat.view(slots[a * nb + b]),
                        (0, 0),
                        src,
                        nl,
                        (local(ra), local(cb)),
                        (ra.size, cb.size),
                        1.0,
                    );
                }
            }
            shift += sys.n_states_of(j);
        }
    }

    /// `∂s/∂Δ` of every signal for the iteration matrix: the K channel times the tangent
    /// operator on node rotations, plus the C and M channels with the coefficients of the
    /// column's kind (second order: γ', β'; element states: ∂ż/∂Δz, 0).
    fn combine_signal_gradients(
        &mut self,
        sys: &System,
        coef: &Coefficients,
        tangent_ops: &[Matrix3<f64>],
    ) {
        for (s, support) in sys.signals.support.iter().enumerate() {
            combine_gradient(
                sys,
                support,
                &self.signal_values.gradients[s],
                coef,
                coef.stiffness,
                tangent_ops,
                &mut self.signal_combined[s],
            );
        }
    }

    /// The signals' values (and, for a matrix, their gradients and combined columns)
    /// copied into the partner's assembler: the same numbers each part reads.
    fn share_signals(&self, to: &mut Assembler, tangents: bool) {
        let (from, into) = (&self.signal_values, &mut to.signal_values);
        into.values.copy_from_slice(&from.values);
        if tangents {
            for (a, b) in into.gradients.iter_mut().zip(&from.gradients) {
                a.copy_from_slice(b);
            }
            for (a, b) in to.signal_combined.iter_mut().zip(&self.signal_combined) {
                a.copy_from_slice(b);
            }
        }
    }

    /// Couplings `(η_k, η_l) = B_k T B_lᵀ` through the nodes constraints k and l share.
    fn add_projection_couplings(&self, matrix: &mut BlockMatrix) {
        for &(k, l, o, a, b) in &self.nu_pairs {
            let (wk, wl) = (&self.constraints[k], &self.constraints[l]);
            let (mk, ml) = (wk.m, wl.m);
            let dst = matrix.view(o);
            // Node a's columns of B_k T and node b's of B_l (column-major, rows strided).
            let (bt, bl) = (
                &wk.bt.as_slice()[6 * a * mk..],
                &wl.b.as_slice()[6 * b * ml..],
            );
            for r in 0..mk {
                for s in 0..ml {
                    let cols = bt[r..].iter().step_by(mk).zip(bl[s..].iter().step_by(ml));
                    let acc = cols.take(6).fold(0.0, |acc, (x, y)| acc + x * y);
                    dst.values[dst.at(r, s)] += acc;
                }
            }
        }
    }

    /// Adds the projection `Bᵀ Δη` of the last assembly to a configuration vector (6 per
    /// node, then coordinates; stabilized index-2 only). `delta` is the Newton vector.
    pub fn add_projection(&self, sys: &System, delta: &[f64], out: &mut [f64]) {
        let n6 = 6 * sys.n_nodes();
        for (k, c) in sys.constraints.iter().enumerate() {
            let w = &self.constraints[k];
            if w.place.projection.is_none() {
                continue;
            }
            let eta = &delta[w.place.proj..w.place.proj + w.m];
            let cn = c.nodes();
            let nq = 6 * cn.len();
            for j in 0..nq + w.nc {
                let mut acc = 0.0;
                for (r, e) in eta.iter().enumerate() {
                    acc += w.b[(r, j)] * e;
                }
                let row = if j < nq {
                    6 * cn[j / 6] + j % 6
                } else {
                    n6 + sys.coordinate_offsets[k] + j - nq
                };
                out[row] += acc;
            }
        }
    }

    /// Explicit time derivatives of the signals at the last assembly's state (only when
    /// some constraint has servo rows; empty otherwise).
    fn servo_time_derivatives(&self, sys: &System, ctx: &EvalContext) -> Vec<[f64; 2]> {
        if self.constraints.iter().all(|w| w.servos.is_empty()) {
            return Vec::new();
        }
        sys.signals
            .time_derivatives(&sys.elements, ctx, &self.signal_values)
    }

    /// Overwrites the constraint rows of `residual` with the convective accelerations
    /// `Φ̈ − B (v̇, ν̈)` (for the consistent-initial-acceleration problem, index-3 layout).
    pub fn acceleration_rows(
        &mut self,
        sys: &System,
        state: &State,
        ctx: &EvalContext,
        residual: &mut [f64],
    ) {
        let rates = self.servo_time_derivatives(sys, ctx);
        for (k, c) in sys.constraints.iter().enumerate() {
            let r = self.multiplier_range(k);
            let first = r.start;
            c.acceleration_term(ctx, &state.nodes, sys.coords_of(k, state), &mut residual[r]);
            // Servo rows: ν̈ − s̈ with s̈ ≈ Σ (∂s/∂x) ẍ (in the matrix) + ∂²s/∂t².
            for &(i, j, _) in &self.constraints[k].servos {
                residual[first + i] = -rates[sys.signals.constraint_inputs[k][j]][1];
            }
        }
    }

    /// Overwrites the constraint rows of `residual` with the velocity constraint
    /// `B (v, ν̇) + Φ_t` and zeroes the configuration rows (index-3 layout; call after
    /// `assemble`, which left `B` in the workspace).
    pub fn velocity_rows(
        &mut self,
        sys: &System,
        state: &State,
        ctx: &EvalContext,
        residual: &mut [f64],
    ) {
        residual.fill(0.0);
        let rates = self.servo_time_derivatives(sys, ctx);
        for (k, c) in sys.constraints.iter().enumerate() {
            let w = &mut self.constraints[k];
            c.velocity_term(ctx, &mut w.phi_t);
            let coords = sys.coords_of(k, state);
            let cn = c.nodes();
            let nq = 6 * cn.len();
            local_velocities(&mut w.vel, cn, state, coords);
            for i in 0..w.m {
                let mut acc = w.phi_t[i];
                for j in 0..nq + w.nc {
                    acc += w.b[(i, j)] * w.vel[j];
                }
                residual[w.place.lam + i] = acc;
            }
            // Servo rows: ν̇ − ṡ with ṡ = Σ (∂s/∂x) ẋ over the signal's support (the
            // states' ż as stored; the rate and acceleration channels left out) + ∂s/∂t.
            for &(i, j, _) in &w.servos {
                let sid = sys.signals.constraint_inputs[k][j];
                let g = &self.signal_values.gradients[sid];
                let s_dot: f64 = sys.signals.support[sid]
                    .iter()
                    .zip(g)
                    .map(|(&c, g)| g[0] * config_rate(sys, state, c))
                    .sum();
                residual[w.place.lam + i] -= s_dot + rates[sid][0];
            }
        }
    }
}

/// Elements from which [`Assembler`] evaluates elements in parallel (rayon), a window of
/// [`PARALLEL_WINDOW`] at a time, each into its own slot; below, one shared scratch per
/// element size keeps the working set small.
pub const PARALLEL_MIN_ELEMENTS: usize = 256;

/// How many elements ahead of the one evaluated the assembly asks for an element's data
/// ([`Element::prefetch`]) and for the states of its nodes. The node states: full Newton's
/// step at 10,000 beam elements 1.4–2.4 % faster (medians of two sets of 7 interleaved
/// runs, 11 of the 14 pairs faster), unchanged at 1,000 elements, with modified Newton and
/// on the chain (docs/integrators.md, twenty-third round).
const PREFETCH_AHEAD: usize = 2;

/// Elements per parallel task (amortizes rayon's scheduling against a few µs per element).
const PARALLEL_CHUNK: usize = 16;

/// Elements evaluated in parallel before their terms are scattered: 128 slots of a
/// two-node element's terms are ~0.45 MB, resident in the L2 caches. One slot per element
/// (3.5 kB each for a two-node beam, 35 MB for 10,000 elements) was written and read back
/// from memory in every iteration.
pub const PARALLEL_WINDOW: usize = 128;

/// Scratch of one element of the parallel window: terms for every element size (indexed
/// like `Assembler::terms`) and the input signals.
struct WindowSlot {
    terms: Vec<LocalTerms>,
    inputs: Vec<f64>,
}

/// What the iteration matrix needs besides the element's own terms.
struct TangentInputs<'a> {
    coef: &'a Coefficients,
    tangent_ops: &'a [Matrix3<f64>],
    rate_maps: &'a [RateMaps],
}

/// Per element, one past the last element of its batch: a run of consecutive elements
/// that accumulate ([`crate::core::Element::accumulates`]), touch the same nodes and have
/// no input signals shares one local block, the nodes' unknowns then each element's
/// states in turn (their terms add up, and the tangent operators and coefficients act
/// linearly on the sum).
fn batches(sys: &System) -> Vec<usize> {
    let n = sys.elements.len();
    let alone = |k: usize| {
        let e = &sys.elements[k];
        !e.accumulates() || !sys.signals.element_inputs[k].is_empty()
    };
    let mut end = (1..=n).collect::<Vec<_>>();
    let mut k = 0;
    while k < n {
        let mut j = k + 1;
        if !alone(k) {
            while j < n && !alone(j) && sys.elements[j].nodes() == sys.elements[k].nodes() {
                j += 1;
            }
        }
        end[k] = j;
        k = j;
    }
    end
}

/// The residual of the elements `ks` (one element, or a batch on the same nodes, see
/// [`batches`]) and, with `tangents`, their combined iteration-matrix block in `t.k`:
/// `s_r (c_M M + c_C C + c_K K T)` on node rows (`T` the tangent operators, plus
/// `C A_v + M A₀` with rate maps), `s_z (c_K ∂r/∂z + (∂ż/∂Δz) ∂r/∂ż)` on state rows and
/// columns. Pure: touches nothing but `t` and the input scratch.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn element_terms<M: MulAdd>(
    sys: &System,
    ks: Range<usize>,
    state: &State,
    ctx: &EvalContext,
    signals: &[f64],
    tangents: Option<&TangentInputs>,
    t: &mut LocalTerms,
    inputs: &mut Vec<f64>,
) {
    let need = if tangents.is_some() {
        Need::ResidualAndTangents
    } else {
        Need::Residual
    };
    t.clear(need);
    if let Some(ahead) = sys.elements.get(ks.start + PREFETCH_AHEAD) {
        ahead.prefetch();
        for &n in ahead.nodes() {
            prefetch(&state.nodes[n]);
        }
    }
    let e = &sys.elements[ks.start];
    // A batch's elements write their states one after another ([`batches`]).
    for k in ks {
        let x = sys.element_input(k, state, signals, inputs);
        sys.elements[k].evaluate(ctx, &x, need, t);
        t.state_shift += sys.elements[k].n_states();
    }
    t.state_shift = 0;
    let Some(tg) = tangents else {
        return;
    };
    let coef = tg.coef;
    let en = e.nodes();
    let n6 = 6 * en.len();
    let nl = t.r.len();
    if nl == n6 {
        combine_node_terms::<M>(t, en, tg);
    } else {
        apply_tangent_ops(&mut t.k, en, tg.tangent_ops);
        if !tg.rate_maps.is_empty() {
            add_rate_terms(t, en, tg.rate_maps);
        }
        let (sr, sz) = (coef.row_scale, coef.state_row_scale);
        // Node columns as above; state columns: c_K ∂r/∂z + (∂ż/∂Δz) ∂r/∂ż. State
        // rows are scaled by s_z instead of s_r. Column by column (column-major).
        let cols =
            t.k.as_mut_slice()
                .chunks_exact_mut(nl)
                .zip(t.m.as_slice().chunks_exact(nl))
                .zip(t.c.as_slice().chunks_exact(nl));
        for (j, ((k, m), c)) in cols.enumerate() {
            let (cmj, ccj) = if j < n6 {
                (coef.mass, coef.damping)
            } else {
                (0.0, coef.state_rate)
            };
            for (rs, range) in [(sr, 0..n6), (sz, n6..nl)] {
                let (ck, cm, cc) = (rs * coef.stiffness, rs * cmj, rs * ccj);
                for ((kv, &mv), &cv) in k[range.clone()]
                    .iter_mut()
                    .zip(&m[range.clone()])
                    .zip(&c[range])
                {
                    *kv = ck * *kv + cm * mv + cc * cv;
                }
            }
        }
    }
}

/// `t.k ← s_r (c_M M + c_C C + c_K K T)` (plus the rate-map terms) for an element with
/// node unknowns only, in place.
#[inline(always)]
fn combine_node_terms<M: MulAdd>(t: &mut LocalTerms, en: &[usize], tg: &TangentInputs) {
    let coef = tg.coef;
    apply_tangent_ops(&mut t.k, en, tg.tangent_ops);
    if !tg.rate_maps.is_empty() {
        add_rate_terms(t, en, tg.rate_maps);
    }
    let sr = coef.row_scale;
    let (cm, cc, ck) = (sr * coef.mass, sr * coef.damping, sr * coef.stiffness);
    for ((k, m), c) in
        t.k.as_mut_slice()
            .iter_mut()
            .zip(t.m.as_slice())
            .zip(t.c.as_slice())
    {
        *k = M::mul_add(cc, *c, M::mul_add(cm, *m, ck * *k));
    }
}

/// `dst += src[6a.., 6b..]` for the 6×6 block (a, b) of a column-major `src` with `nr`
/// rows; `dst` row-major or column-major.
#[inline(always)]
fn add_block6(dst: BlockView, src: &[f64], nr: usize, a: usize, b: usize) {
    let row_major = dst.row_major();
    let dst: &mut [f64; 36] = (&mut dst.values[..36]).try_into().expect("6×6 block");
    let col = |c: usize| -> &[f64; 6] {
        let o = (6 * b + c) * nr + 6 * a;
        src[o..o + 6].try_into().expect("6 rows")
    };
    if row_major {
        for c in 0..6 {
            for (r, v) in col(c).iter().enumerate() {
                dst[6 * r + c] += v;
            }
        }
    } else {
        for (c, d) in dst.as_chunks_mut::<6>().0.iter_mut().enumerate() {
            for (d, v) in d.iter_mut().zip(col(c)) {
                *d += v;
            }
        }
    }
}

/// `K += ρ BᵀB` for `B` (`m × nl`, column-major) and `K` (`nl × nl`, column-major), as
/// rank-one updates `K[:, j] += ρ b_r[j] b_r` per row `b_r` of `B` (copied row-major into
/// `rows`): contiguous column updates the compiler vectorizes, in place of nalgebra's
/// `gemm_tr` (one short dot product per entry).
/// One- and two-node constraints (`nl` = 6, 12) have the column length as a constant:
/// each column of `K` is held in a local array (registers) while the rows' updates are
/// added to it in row order (each entry gets the same sum in the same order as row by
/// row), with no test for zero `b_r[j]` — written into `K` row by row with that test, the
/// kernel had compiled to scalar multiply–adds behind a mispredicting branch.
#[inline(always)]
fn add_gram<M: MulAdd>(k: &mut [f64], b: &[f64], rows: &mut [f64], m: usize, nl: usize, rho: f64) {
    #[inline(always)]
    fn fixed<M: MulAdd, const NL: usize>(
        k: &mut [f64],
        b: &[f64],
        rows: &mut [f64],
        m: usize,
        rho: f64,
    ) {
        // Row by row (strided reads, contiguous writes): written column by column, the
        // last stores into every row came just before the wide loads of the first rows,
        // which then waited on store forwarding (5 % of the assembly's samples).
        let rows = &mut rows[..m * NL];
        for (r, row) in rows.chunks_exact_mut(NL).enumerate() {
            for (j, x) in row.iter_mut().enumerate() {
                *x = b[j * m + r];
            }
        }
        let rows = rows.as_chunks::<NL>().0;
        let (k, _) = k[..NL * NL].as_chunks_mut::<NL>();
        for (j, kc) in k.iter_mut().enumerate() {
            let mut acc: [f64; NL] = *kc;
            for row in rows {
                let s = rho * row[j];
                for (a, &bi) in acc.iter_mut().zip(row) {
                    *a = M::mul_add(s, bi, *a);
                }
            }
            *kc = acc;
        }
    }
    match nl {
        12 => return fixed::<M, 12>(k, b, rows, m, rho),
        6 => return fixed::<M, 6>(k, b, rows, m, rho),
        _ => {}
    }
    let rows = &mut rows[..m * nl];
    for (j, col) in b[..m * nl].chunks_exact(m).enumerate() {
        for (r, &x) in col.iter().enumerate() {
            rows[r * nl + j] = x;
        }
    }
    for row in rows.chunks_exact(nl) {
        for (kc, &bj) in k[..nl * nl].chunks_exact_mut(nl).zip(row) {
            let s = rho * bj;
            if s == 0.0 {
                continue;
            }
            for (kv, &bi) in kc.iter_mut().zip(row) {
                *kv = M::mul_add(s, bi, *kv);
            }
        }
    }
}

/// The local velocity vector of a constraint: node v (global) and Ω (material) per node,
/// then the coordinate rates.
/// `∂s/∂Δ` of one signal over its `support` from its channels `g`: the K channel times
/// the tangent operator on node rotations, at weight `k_config` on the nodes and joint
/// coordinates (the element states' at `coef.stiffness`), plus the C and M channels with
/// the coefficients of the column's kind (second order: γ', β'; element states: ∂ż/∂Δz).
fn combine_gradient(
    sys: &System,
    support: &[usize],
    g: &[[f64; 3]],
    coef: &Coefficients,
    k_config: f64,
    tangent_ops: &[Matrix3<f64>],
    out: &mut [f64],
) {
    let n6 = 6 * sys.n_nodes();
    let first_state = n6 + sys.n_coordinates;
    let mut p = 0;
    while p < support.len() {
        let c = support[p];
        if c < n6 && c % 6 == 3 && p + 2 < support.len() && support[p + 2] == c + 2 {
            // A node's rotation triplet: gₖᵀ T.
            let node = c / 6;
            let t = tangent_ops
                .get(node)
                .copied()
                .unwrap_or_else(Matrix3::identity);
            for j in 0..3 {
                let mut acc = 0.0;
                for i in 0..3 {
                    acc += g[p + i][0] * t[(i, j)];
                }
                out[p + j] = k_config * acc + coef.damping * g[p + j][1] + coef.mass * g[p + j][2];
            }
            p += 3;
            continue;
        }
        out[p] = if c >= first_state {
            coef.stiffness * g[p][0] + coef.state_rate * g[p][1]
        } else {
            k_config * g[p][0] + coef.damping * g[p][1] + coef.mass * g[p][2]
        };
        p += 1;
    }
}

/// Rate of configuration unknown `c`: a node's v or Ω, a coordinate's ν̇, a state's ż.
fn config_rate(sys: &System, state: &State, c: usize) -> f64 {
    let n6 = 6 * sys.n_nodes();
    if c < n6 {
        let nd = &state.nodes[c / 6];
        let d = c % 6;
        if d < 3 { nd.v[d] } else { nd.w[d - 3] }
    } else if c < n6 + sys.n_coordinates {
        state.coords[c - n6].v
    } else {
        state.states[c - n6 - sys.n_coordinates].zd
    }
}

fn local_velocities(
    vel: &mut [f64],
    nodes: &[usize],
    state: &State,
    coords: &[crate::system::Coordinate],
) {
    for (a, &na) in nodes.iter().enumerate() {
        let nd = &state.nodes[na];
        for j in 0..3 {
            vel[6 * a + j] = nd.v[j];
            vel[6 * a + 3 + j] = nd.w[j];
        }
    }
    let nq = 6 * nodes.len();
    for (j, q) in coords.iter().enumerate() {
        vel[nq + j] = q.v;
    }
}

/// `dst[r0 + r, c0 + c] += scale · src[sr0 + r, sc0 + c]` for a `rows × cols` block;
/// `src` column-major with `nr` rows.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn add_sub<M: MulAdd>(
    dst: &mut BlockView,
    (r0, c0): (usize, usize),
    src: &[f64],
    nr: usize,
    (sr0, sc0): (usize, usize),
    (rows, cols): (usize, usize),
    scale: f64,
) {
    for c in 0..cols {
        let col = &src[(sc0 + c) * nr + sr0..(sc0 + c) * nr + sr0 + rows];
        if dst.row_major() {
            for (r, &v) in col.iter().enumerate() {
                let i = dst.at(r0 + r, c0 + c);
                dst.values[i] = M::mul_add(scale, v, dst.values[i]);
            }
        } else {
            let o = dst.at(r0, c0 + c);
            for (d, &v) in dst.values[o..o + rows].iter_mut().zip(col) {
                *d = M::mul_add(scale, v, *d);
            }
        }
    }
}

/// [`add_sub`] of a `rows × 6` block of node columns (δx, then δθ) of `src`, the
/// rotation columns right-multiplied by the node's tangent operator `t` on the way (`None`:
/// identity) — the same sums as [`apply_tangent_ops`] then [`add_sub`].
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn add_node_columns<M: MulAdd>(
    dst: &mut BlockView,
    at0: (usize, usize),
    src: &[f64],
    nr: usize,
    src0: (usize, usize),
    rows: usize,
    t: Option<&Matrix3<f64>>,
    scale: f64,
) {
    // A node's rows (6) and a five-row joint's λ rows with the count a constant: the
    // column updates are then whole vector operations, not loops of run-time length.
    match rows {
        6 => add_node_columns_of::<M>(dst, at0, src, nr, src0, 6, t, scale),
        5 => add_node_columns_of::<M>(dst, at0, src, nr, src0, 5, t, scale),
        _ => add_node_columns_of::<M>(dst, at0, src, nr, src0, rows, t, scale),
    }
}

#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn add_node_columns_of<M: MulAdd>(
    dst: &mut BlockView,
    (r0, c0): (usize, usize),
    src: &[f64],
    nr: usize,
    (sr0, sc0): (usize, usize),
    rows: usize,
    t: Option<&Matrix3<f64>>,
    scale: f64,
) {
    let col = |c: usize| &src[(sc0 + c) * nr + sr0..(sc0 + c) * nr + sr0 + rows];
    let (x, y, z) = (col(3), col(4), col(5));
    if !dst.row_major() {
        // Column-major: each column of the block is contiguous.
        let ld = dst.col_stride;
        let dst = &mut *dst.values;
        let at = |c: usize| (c0 + c) * ld + r0..(c0 + c) * ld + r0 + rows;
        for c in 0..3 {
            for (d, &v) in dst[at(c)].iter_mut().zip(col(c)) {
                *d = M::mul_add(scale, v, *d);
            }
        }
        match t {
            None => {
                for (c, v3) in [x, y, z].into_iter().enumerate() {
                    for (d, &v) in dst[at(3 + c)].iter_mut().zip(v3) {
                        *d = M::mul_add(scale, v, *d);
                    }
                }
            }
            Some(t) => {
                for j in 0..3 {
                    let (t0, t1, t2) = (t[(0, j)], t[(1, j)], t[(2, j)]);
                    let xyz = x.iter().zip(y).zip(z);
                    for (d, ((&a, &b), &c)) in dst[at(3 + j)].iter_mut().zip(xyz) {
                        let v = M::mul_add(c, t2, M::mul_add(b, t1, a * t0));
                        *d = M::mul_add(scale, v, *d);
                    }
                }
            }
        }
        return;
    }
    let stride = dst.row_stride;
    let dst = &mut *dst.values;
    for c in 0..3 {
        for (r, &v) in col(c).iter().enumerate() {
            let d = &mut dst[(r0 + r) * stride + c0 + c];
            *d = M::mul_add(scale, v, *d);
        }
    }
    match t {
        None => {
            for (c, v3) in [x, y, z].into_iter().enumerate() {
                for (r, &v) in v3.iter().enumerate() {
                    let d = &mut dst[(r0 + r) * stride + c0 + 3 + c];
                    *d = M::mul_add(scale, v, *d);
                }
            }
        }
        Some(t) => {
            for r in 0..rows {
                let row = [x[r], y[r], z[r]];
                for j in 0..3 {
                    let v = M::mul_add(
                        row[2],
                        t[(2, j)],
                        M::mul_add(row[1], t[(1, j)], row[0] * t[(0, j)]),
                    );
                    let d = &mut dst[(r0 + r) * stride + c0 + 3 + j];
                    *d = M::mul_add(scale, v, *d);
                }
            }
        }
    }
}

/// Like [`add_sub`] with the source transposed: `dst[r, c] += scale · src[sr0 + c, sc0 + r]`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn add_sub_t<M: MulAdd>(
    dst: &mut BlockView,
    (r0, c0): (usize, usize),
    src: &[f64],
    nr: usize,
    (sr0, sc0): (usize, usize),
    (rows, cols): (usize, usize),
    scale: f64,
) {
    if dst.row_major() {
        for r in 0..rows {
            let col = &src[(sc0 + r) * nr + sr0..(sc0 + r) * nr + sr0 + cols];
            let o = dst.at(r0 + r, c0);
            for (x, &v) in dst.values[o..o + cols].iter_mut().zip(col) {
                *x = M::mul_add(scale, v, *x);
            }
        }
    } else {
        // Column-major: column c of the block is row sr0 + c of `src` (stride nr); a node's
        // six rows at a compile-time count.
        if rows == 6 {
            for c in 0..cols {
                let o = dst.at(r0, c0 + c);
                let d: &mut [f64; 6] = (&mut dst.values[o..o + 6]).try_into().expect("6 rows");
                let base = sc0 * nr + sr0 + c;
                let col = &src[base..=base + 5 * nr];
                for (r, d) in d.iter_mut().enumerate() {
                    *d = M::mul_add(scale, col[r * nr], *d);
                }
            }
            return;
        }
        for c in 0..cols {
            let o = dst.at(r0, c0 + c);
            let row = src[sc0 * nr + sr0 + c..].iter().step_by(nr);
            for (d, &v) in dst.values[o..o + rows].iter_mut().zip(row) {
                *d = M::mul_add(scale, v, *d);
            }
        }
    }
}

/// `K += C A_v + M A₀` on the columns of each local node block (rows: all).
fn add_rate_terms(t: &mut LocalTerms, nodes: &[usize], maps: &[RateMaps]) {
    for (b, &nb) in nodes.iter().enumerate() {
        let map = &maps[nb];
        for blk in 0..2 {
            let (av, a0) = (&map.velocity[blk], &map.acceleration[blk]);
            if av.iter().all(|x| *x == 0.0) && a0.iter().all(|x| *x == 0.0) {
                continue;
            }
            let c0 = 6 * b + 3 * blk;
            for r in 0..t.k.nrows() {
                let c = [t.c[(r, c0)], t.c[(r, c0 + 1)], t.c[(r, c0 + 2)]];
                let m = [t.m[(r, c0)], t.m[(r, c0 + 1)], t.m[(r, c0 + 2)]];
                for j in 0..3 {
                    t.k[(r, c0 + j)] += (0..3)
                        .map(|i| c[i] * av[(i, j)] + m[i] * a0[(i, j)])
                        .sum::<f64>();
                }
            }
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
