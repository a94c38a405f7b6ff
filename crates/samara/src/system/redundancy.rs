//! Redundant constraints: loops of joints whose constraint Jacobian is rank deficient
//! although the mechanism moves (a planar four-bar built with spatial revolute joints,
//! the Bricard linkage).
//!
//! Only closed loops can be redundant: in a tree of joints every joint constrains its
//! child's motion relative to its parent, so the rows are independent. The loops are the
//! 2-edge-connected components of the graph whose vertices are the nodes and the ground
//! and whose edges are the joints (bridges found by depth-first search, Tarjan 1974).
//! In each loop the rows are taken greedily, definitions and drives first, then the
//! constraint rows in model order; a row is kept when its part orthogonal to the rows
//! kept so far is larger than [`RANK_TOL`] of its norm (Gram–Schmidt, twice). The rest
//! are dropped: the solver enforces the kept rows only, and the equations dropped are
//! implied by them near the configuration of the analysis.
//!
//! Reactions of a loop with dropped rows are not unique. The particular solution written
//! out is the minimum-norm one: `λ = (Bᵀ)⁺ (B_keptᵀ λ_kept)` over all rows of the loop,
//! multipliers in SI units (N for displacement rows, N m for rotation rows).

use crate::core::{Constraint, Coordinate, EvalContext, NodeState, RowRole};
use nalgebra::{DMatrix, DVector};

/// Relative size of a row's new direction below which it is counted as dependent.
pub const RANK_TOL: f64 = 1e-8;

/// A closed loop of joints and what was dropped from it.
#[derive(Clone, Debug, Default)]
pub struct ConstraintLoop {
    /// Constraints in the loop.
    pub constraints: Vec<usize>,
    /// Rows analysed (all rows of those constraints).
    pub rows: usize,
    /// Rank of their Jacobian.
    pub rank: usize,
    /// Dropped rows as (constraint, row index among the constraint's rows).
    pub dropped: Vec<(usize, usize)>,
}

/// Edge list of the joint graph: vertex `n_nodes` is the ground.
fn edges(n_nodes: usize, constraints: &[Box<dyn Constraint>]) -> Vec<(usize, usize)> {
    constraints
        .iter()
        .map(|c| {
            let nn = c.nodes();
            match nn.len() {
                0 => (n_nodes, n_nodes),
                1 => (nn[0], n_nodes),
                _ => (nn[0], nn[1]),
            }
        })
        .collect()
}

/// Groups of constraints forming closed loops (2-edge-connected components with an edge).
pub fn loops(n_nodes: usize, constraints: &[Box<dyn Constraint>]) -> Vec<Vec<usize>> {
    let e = edges(n_nodes, constraints);
    let nv = n_nodes + 1;
    let mut adj: Vec<Vec<(usize, usize)>> = vec![Vec::new(); nv];
    for (k, &(a, b)) in e.iter().enumerate() {
        adj[a].push((b, k));
        if a != b {
            adj[b].push((a, k));
        }
    }
    // Iterative DFS for bridges (low-link), skipping only the edge we came by.
    let mut disc = vec![usize::MAX; nv];
    let mut low = vec![0usize; nv];
    let mut bridge = vec![false; e.len()];
    let mut time = 0;
    for root in 0..nv {
        if disc[root] != usize::MAX {
            continue;
        }
        // Stack of (vertex, parent edge, next adjacency index).
        let mut stack = vec![(root, usize::MAX, 0usize)];
        disc[root] = time;
        low[root] = time;
        time += 1;
        while let Some(&mut (v, pe, ref mut i)) = stack.last_mut() {
            if *i < adj[v].len() {
                let (w, k) = adj[v][*i];
                *i += 1;
                if k == pe {
                    continue;
                }
                if disc[w] == usize::MAX {
                    disc[w] = time;
                    low[w] = time;
                    time += 1;
                    stack.push((w, k, 0));
                } else {
                    low[v] = low[v].min(disc[w]);
                }
            } else {
                stack.pop();
                if let Some(&(p, _, _)) = stack.last() {
                    low[p] = low[p].min(low[v]);
                    if low[v] > disc[p] {
                        bridge[pe] = true;
                    }
                }
            }
        }
    }
    // Union the endpoints of non-bridge edges.
    let mut parent: Vec<usize> = (0..nv).collect();
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    for (k, &(a, b)) in e.iter().enumerate() {
        if !bridge[k] {
            let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
            parent[ra] = rb;
        }
    }
    let mut groups: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
    for (k, &(a, _)) in e.iter().enumerate() {
        if !bridge[k] {
            let r = find(&mut parent, a);
            groups.entry(r).or_default().push(k);
        }
    }
    groups.into_values().collect()
}

/// The Jacobian of all rows of the loop's constraints over the loop's unknowns, with the
/// rotation columns scaled by the loop's length `scale` so that all columns carry
/// lengths. Returns the matrix and, per row, (constraint, row index).
fn loop_jacobian(
    members: &[usize],
    constraints: &[Box<dyn Constraint>],
    coord_offsets: &[usize],
    ctx: &EvalContext,
    nodes: &[NodeState],
    coords: &[Coordinate],
    scale: f64,
) -> (DMatrix<f64>, Vec<(usize, usize)>) {
    let mut node_cols: Vec<usize> = Vec::new();
    for &k in members {
        for &n in constraints[k].nodes() {
            if !node_cols.contains(&n) {
                node_cols.push(n);
            }
        }
    }
    let n_coord_cols: usize = members
        .iter()
        .map(|&k| constraints[k].n_coordinates())
        .sum();
    let n_rows: usize = members.iter().map(|&k| constraints[k].n_rows()).sum();
    let ncols = 6 * node_cols.len() + n_coord_cols;
    let mut big = DMatrix::zeros(n_rows, ncols);
    let mut ids = Vec::with_capacity(n_rows);
    let (mut r0, mut c0) = (0, 6 * node_cols.len());
    for &k in members {
        let c = &constraints[k];
        let (m, nc) = (c.n_rows(), c.n_coordinates());
        let cn = c.nodes();
        let mut phi = vec![0.0; m];
        let mut b = DMatrix::zeros(m, 6 * cn.len() + nc);
        let own = &coords[coord_offsets[k]..coord_offsets[k] + nc];
        c.evaluate_all_rows(ctx, nodes, own, &mut phi, &mut b);
        for r in 0..m {
            for (a, n) in cn.iter().enumerate() {
                let col = 6 * node_cols.iter().position(|x| x == n).unwrap_or(0);
                for j in 0..6 {
                    let s = if j < 3 { 1.0 } else { scale };
                    big[(r0 + r, col + j)] = b[(r, 6 * a + j)] * s;
                }
            }
            for j in 0..nc {
                big[(r0 + r, c0 + j)] = b[(r, 6 * cn.len() + j)];
            }
            ids.push((k, r));
        }
        r0 += m;
        c0 += nc;
    }
    (big, ids)
}

/// Characteristic length of a loop: the largest distance between its nodes (≥ 1e-3 m).
fn loop_length(members: &[usize], constraints: &[Box<dyn Constraint>], nodes: &[NodeState]) -> f64 {
    let mut pts = Vec::new();
    for &k in members {
        pts.push(constraints[k].location(nodes).0);
        for &n in constraints[k].nodes() {
            pts.push(nodes[n].x);
        }
    }
    let mut l: f64 = 1e-3;
    for a in &pts {
        for b in &pts {
            l = l.max((a - b).norm());
        }
    }
    l
}

/// Finds the loops, their rank and the rows to drop (nothing is changed here).
pub fn analyse(
    constraints: &[Box<dyn Constraint>],
    coord_offsets: &[usize],
    n_nodes: usize,
    ctx: &EvalContext,
    nodes: &[NodeState],
    coords: &[Coordinate],
) -> Vec<ConstraintLoop> {
    let mut out = Vec::new();
    for members in loops(n_nodes, constraints) {
        let scale = loop_length(&members, constraints, nodes);
        let (b, ids) = loop_jacobian(
            &members,
            constraints,
            coord_offsets,
            ctx,
            nodes,
            coords,
            scale,
        );
        // Order: definitions and drives first (never dropped), then constraint rows.
        let role = |i: usize| -> RowRole {
            let (k, r) = ids[i];
            constraints[k].row_role(r)
        };
        let mut order: Vec<usize> = (0..ids.len())
            .filter(|&i| role(i) != RowRole::Constraint)
            .collect();
        order.extend((0..ids.len()).filter(|&i| role(i) == RowRole::Constraint));
        let mut basis: Vec<DVector<f64>> = Vec::new();
        let mut dropped = Vec::new();
        for i in order {
            let row: DVector<f64> = b.row(i).transpose();
            let norm = row.norm();
            let mut v = row.clone();
            for _ in 0..2 {
                for q in &basis {
                    let d = q.dot(&v);
                    v.axpy(-d, q, 1.0);
                }
            }
            let rest = v.norm();
            if norm > 0.0 && rest > RANK_TOL * norm {
                basis.push(v / rest);
            } else if role(i) == RowRole::Constraint {
                dropped.push(ids[i]);
            } else {
                // A dependent definition or drive: kept (the solver will report it).
                basis.push(row / norm.max(f64::MIN_POSITIVE));
            }
        }
        out.push(ConstraintLoop {
            constraints: members,
            rows: ids.len(),
            rank: ids.len() - dropped.len(),
            dropped,
        });
    }
    out
}

/// Minimum-norm multipliers of all rows of a loop that produce the same generalized
/// forces as the enforced multipliers (`mu_all` holds those, zeros at dropped rows).
#[allow(clippy::too_many_arguments)]
pub fn minimum_norm(
    lp: &ConstraintLoop,
    constraints: &[Box<dyn Constraint>],
    row_offsets: &[usize],
    coord_offsets: &[usize],
    ctx: &EvalContext,
    nodes: &[NodeState],
    coords: &[Coordinate],
    mu_all: &mut [f64],
) {
    let (b, ids) = loop_jacobian(
        &lp.constraints,
        constraints,
        coord_offsets,
        ctx,
        nodes,
        coords,
        1.0,
    );
    let mu = DVector::from_iterator(
        ids.len(),
        ids.iter().map(|&(k, r)| mu_all[row_offsets[k] + r]),
    );
    let g = b.transpose() * &mu;
    let bt = b.transpose();
    let svd = bt.svd(true, true);
    let smax = svd.singular_values.max();
    if let Ok(lam) = svd.solve(&g, RANK_TOL * smax.max(f64::MIN_POSITIVE)) {
        for (i, &(k, r)) in ids.iter().enumerate() {
            mu_all[row_offsets[k] + r] = lam[i];
        }
    }
}
