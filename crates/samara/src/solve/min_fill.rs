//! Minimum-fill (minimum-deficiency) ordering of a symmetric graph (Tinney & Walker 1967,
//! scheme 3; Rose 1972): at each step eliminate the vertex whose elimination adds the fewest
//! edges to the elimination graph, i.e. the fewest pairs of its neighbours not yet adjacent
//! (ties: the smaller degree, then the smaller index).
//!
//! On long, thin graphs — a granular column is a chain of layers — minimum degree (and AMD,
//! its approximation) eliminates vertices scattered along the whole length, whose
//! eliminated regions later merge through wide fronts; the deficiency sees the fill such a
//! merge makes, and so eliminates the column from its ends, layer after layer, with fronts
//! of one layer's width.
//!
//! The elimination graph is kept explicitly (sorted adjacency lists), so the cost grows
//! with the fill; the caller gives a work budget and gets `None` if it is exceeded. After
//! an elimination the deficiencies of the eliminated vertex's neighbours are recounted;
//! those of the vertices one further out only fall by the pairs of their neighbours that
//! the new clique joins.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// Minimum-fill order of the graph `adj` (symmetric, no self loops): `order[k]` is the
/// vertex eliminated at step `k`. A vertex `v` with gates (`gates[v]` not empty: a
/// multiplier) may only be eliminated after all of them have been (used to keep a
/// multiplier after the primaries it couples). With `any_gate[v]` (if `any_gate` is not
/// empty) it may also go after one gate `p` that had no other multiplier left among its
/// neighbours when it was eliminated: `p`'s block then holds only what its eliminated
/// neighbours added to it, and `v` is the one multiplier to take it (a chain from its free
/// end; a gate shared with another multiplier, which may take up `p`'s freedom first, does
/// not release `v`; a multiplier with `silent[u]`, if `silent` is not empty, does not count
/// as another: its column is zero in `p`'s rows). A vertex with `held[v]` (if `held` is not
/// empty) waits until every vertex not held is eliminated (a separator kept last). `None`
/// if more than `budget` adjacency operations would be needed.
pub(crate) fn min_fill_order(
    adj: &[Vec<usize>],
    gates: &[Vec<usize>],
    any_gate: &[bool],
    silent: &[bool],
    held: &[bool],
    budget: usize,
) -> Option<Vec<usize>> {
    let n = adj.len();
    let mut g: Vec<Vec<usize>> = adj
        .iter()
        .map(|a| {
            let mut a = a.clone();
            a.sort_unstable();
            a.dedup();
            a
        })
        .collect();
    // Vertices waiting for their gates, and the vertices each vertex gates.
    let is_held = |v: usize| held.get(v).copied().unwrap_or(false);
    let is_any = |v: usize| any_gate.get(v).copied().unwrap_or(false);
    let is_mult = |v: usize| !gates[v].is_empty();
    let is_silent = |v: usize| silent.get(v).copied().unwrap_or(false);
    // Released by a sole gate: its other gates count no more.
    let mut released = vec![false; n];
    let mut waiting: Vec<usize> = gates
        .iter()
        .enumerate()
        .map(|(v, g)| g.len() + usize::from(is_held(v)))
        .collect();
    let mut free = (0..n).filter(|&v| !is_held(v)).count();
    let mut gated_by: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (v, gs) in gates.iter().enumerate() {
        for &p in gs {
            gated_by[p].push(v);
        }
    }
    let mut work = 0usize;
    let mut mark = vec![usize::MAX; n];
    let mut stamp = 0usize;
    // Number of pairs of neighbours of v that are not adjacent.
    let deficiency = |g: &[Vec<usize>], v: usize, mark: &mut [usize], stamp: &mut usize| {
        let nb = &g[v];
        let mut missing = 0usize;
        let mut ops = nb.len();
        for (i, &a) in nb.iter().enumerate() {
            *stamp += 1;
            for &b in &g[a] {
                mark[b] = *stamp;
            }
            ops += g[a].len() + nb.len() - i;
            missing += nb[i + 1..].iter().filter(|&&b| mark[b] != *stamp).count();
        }
        (missing, ops)
    };
    let mut score: Vec<(usize, usize)> = vec![(0, 0); n];
    let mut heap = BinaryHeap::new();
    for v in 0..n {
        let (d, ops) = deficiency(&g, v, &mut mark, &mut stamp);
        work += ops;
        score[v] = (d, g[v].len());
        if waiting[v] == 0 {
            heap.push(Reverse((d, g[v].len(), v)));
        }
    }
    let mut alive = vec![true; n];
    let mut order = Vec::with_capacity(n);
    let mut merged: Vec<usize> = Vec::new();
    // (vertex outside N(v), its neighbour in N(v)); (vertex, deficiency decrease).
    let mut outer: Vec<(usize, usize)> = Vec::new();
    let mut joined: Vec<(usize, usize)> = Vec::new();
    while let Some(Reverse((d, deg, v))) = heap.pop() {
        if !alive[v] || (d, deg) != score[v] || waiting[v] > 0 {
            continue;
        }
        if work > budget {
            return None;
        }
        alive[v] = false;
        order.push(v);
        let nb = std::mem::take(&mut g[v]);
        // The only multiplier left next to v, if any: released by v if it may go after any
        // gate (its gates still count down, so none is counted twice).
        let mut sole = nb.iter().copied().filter(|&u| is_mult(u) && !is_silent(u));
        let sole = match (sole.next(), sole.next()) {
            (Some(u), None) if is_any(u) && gates[u].contains(&v) => Some(u),
            _ => None,
        };
        // A vertex u outside N(v) keeps its neighbours; its deficiency falls by the pairs
        // of its neighbours in N(v) that the clique N(v) joins (found before the merge).
        stamp += 1;
        for &a in &nb {
            mark[a] = stamp;
        }
        outer.clear();
        for &a in &nb {
            work += g[a].len();
            outer.extend(
                g[a].iter()
                    .filter(|&&u| u != v && mark[u] != stamp)
                    .map(|&u| (u, a)),
            );
        }
        outer.sort_unstable();
        joined.clear();
        for group in outer.chunk_by(|x, y| x.0 == y.0) {
            let mut new_edges = 0;
            for (i, &(_, a)) in group.iter().enumerate() {
                for &(_, b) in &group[i + 1..] {
                    work += 1;
                    if g[a].binary_search(&b).is_err() {
                        new_edges += 1;
                    }
                }
            }
            if new_edges > 0 {
                joined.push((group[0].0, new_edges));
            }
        }
        // Each neighbour loses v and gains the other neighbours of v (a clique).
        for &a in &nb {
            merged.clear();
            let (mut i, mut j) = (0, 0);
            let ga = &g[a];
            while i < ga.len() || j < nb.len() {
                let x = if j == nb.len() || (i < ga.len() && ga[i] <= nb[j]) {
                    let x = ga[i];
                    if j < nb.len() && nb[j] == x {
                        j += 1;
                    }
                    i += 1;
                    x
                } else {
                    j += 1;
                    nb[j - 1]
                };
                if x != v && x != a {
                    merged.push(x);
                }
            }
            work += ga.len() + nb.len();
            std::mem::swap(&mut g[a], &mut merged);
        }
        for &w in &gated_by[v] {
            if released[w] {
                continue;
            }
            waiting[w] -= 1;
            if Some(w) == sole {
                // The gates left no longer hold it back (the held count stays).
                waiting[w] -= gates[w].iter().filter(|&&p| alive[p]).count();
                released[w] = true;
            }
        }
        if !is_held(v) {
            free -= 1;
            if free == 0 {
                for w in (0..n).filter(|&w| is_held(w)) {
                    waiting[w] -= 1;
                    if waiting[w] == 0 {
                        heap.push(Reverse((score[w].0, score[w].1, w)));
                    }
                }
            }
        }
        for &(u, fewer) in &joined {
            score[u].0 -= fewer;
            if waiting[u] == 0 {
                heap.push(Reverse((score[u].0, score[u].1, u)));
            }
        }
        // The neighbours of v: recounted (their neighbourhoods changed). A vertex gated
        // by v is one of them.
        for &u in &nb {
            let (d, ops) = deficiency(&g, u, &mut mark, &mut stamp);
            work += ops;
            let s = (d, g[u].len());
            let newly_eligible = waiting[u] == 0 && gated_by[v].contains(&u);
            if s != score[u] || newly_eligible {
                score[u] = s;
                if waiting[u] == 0 {
                    heap.push(Reverse((s.0, s.1, u)));
                }
            }
        }
    }
    (order.len() == n).then_some(order)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn graph(n: usize, edges: &[(usize, usize)]) -> Vec<Vec<usize>> {
        let mut adj = vec![Vec::new(); n];
        for &(a, b) in edges {
            adj[a].push(b);
            adj[b].push(a);
        }
        adj
    }

    /// A star: the centre's elimination would join all leaves (6 fill edges); the leaves
    /// make none, so the centre goes once only one leaf is left (a tie, then).
    #[test]
    fn star_eliminates_leaves_first() {
        let adj = graph(5, &[(0, 1), (0, 2), (0, 3), (0, 4)]);
        let o = min_fill_order(&adj, &vec![Vec::new(); 5], &[], &[], &[], usize::MAX).unwrap();
        assert_eq!(o, [1, 2, 3, 0, 4]);
    }

    /// A path from its ends inward (each end has deficiency 0); gates hold a vertex back.
    #[test]
    fn path_and_gates() {
        let adj = graph(4, &[(0, 1), (1, 2), (2, 3)]);
        let none = vec![Vec::new(); 4];
        let o = min_fill_order(&adj, &none, &[], &[], &[], usize::MAX).unwrap();
        assert!(o[0] == 0 || o[0] == 3, "{o:?}");
        let mut gates = none.clone();
        gates[0] = vec![1];
        let o = min_fill_order(&adj, &gates, &[], &[], &[], usize::MAX).unwrap();
        let p = |v: usize| o.iter().position(|&x| x == v).unwrap();
        assert!(p(0) > p(1), "{o:?}");
        assert!(min_fill_order(&adj, &none, &[], &[], &[], 3).is_none());
        // Vertex 1 gated by both neighbours: after both, or with `any_gate` after the
        // first (0, an end), and then at once (deficiency 0, the smaller index of a tie).
        let mut gates = none.clone();
        gates[1] = vec![0, 2];
        let o = min_fill_order(&adj, &gates, &[], &[], &[], usize::MAX).unwrap();
        let p = |v: usize| o.iter().position(|&x| x == v).unwrap();
        assert!(p(1) > p(0) && p(1) > p(2), "{o:?}");
        let any = [false, true, false, false];
        let o = min_fill_order(&adj, &gates, &any, &[], &[], usize::MAX).unwrap();
        assert_eq!(o[..2], [0, 1], "{o:?}");
        // Vertex 1 held back: the others go first.
        let held = [false, true, false, false];
        let o = min_fill_order(&adj, &none, &[], &[], &held, usize::MAX).unwrap();
        assert_eq!(o[3], 1, "{o:?}");
    }
}
