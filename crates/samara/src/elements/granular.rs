//! A granular contact set: many spheres centred at nodes, mutually in contact, with the
//! sphere–sphere kernel of [`super::sphere_pair`] for every pair that touches.
//!
//! **Broad phase** (a uniform grid, spatial hashing by sorting): with the cell size
//! `h = 2 ρ_max + m` (m the Verlet margin), every sphere is keyed by its cell
//! `⌊x/h⌋ ∈ Z³`; the keys are sorted (O(N log N)) and each sphere looks for partners in
//! its own and the 26 neighbouring cells by binary search (O(log N) each). Two spheres
//! are a candidate pair when their gap `|x_i − x_j| − ρ_i − ρ_j` is below m. Cost
//! O(N log N + N k) with k the spheres per cell neighbourhood (bounded for spheres that
//! do not overlap much), against O(N²) for all pairs ([`GranularSet::all_pairs`]).
//!
//! **Verlet list.** The candidate pairs found at a configuration X₀ stay a superset of the
//! pairs in contact as long as no sphere has moved more than m/2 from X₀: a pair outside
//! the set had a gap ≥ m, and two displacements ≤ m/2 cannot close it. The integrator
//! checks this after every step ([`GranularSet::max_displacement`]) and detects again
//! when it fails; a step that ends with a pair in contact that was not a candidate is
//! redone with it (see `analysis::dynamic`).
//!
//! Rolling and twisting resistance, when on, act on every pair ([`super::rolling`],
//! stateless: nothing to carry over).
//!
//! Pair friction, when on, is LuGre with the bristle deflection as a history variable of
//! the pair ([`SpherePair::with_bristle`]: backward Euler, condensed, so the pair has no
//! unknowns of its own and the Newton unknowns do not change when pairs come and go); the
//! integrator keeps the deflections keyed by pair (`State::pair_bristles`), carries them
//! over when the candidate list is rebuilt, starts new pairs at zero and drops a pair's
//! deflection when it separates. The stateless regularized Coulomb–Stribeck law
//! ([`PairFriction::Regularized`]) is the alternative without stick.

use super::contact::NormalLaw;
use super::{Element, EvalContext, PairFriction, RollingResistance, SpherePair};
use crate::core::{ElementInput, NodeState, PairBristle};
use nalgebra::Vector3;

/// Spheres in mutual contact.
#[derive(Clone, Debug)]
pub struct GranularSet {
    pub name: String,
    /// The spheres' nodes.
    pub nodes: Vec<usize>,
    /// Their radii [m].
    pub radii: Vec<f64>,
    pub law: NormalLaw,
    pub friction: Option<PairFriction>,
    /// Verlet margin m [m] > 0.
    pub margin: f64,
    /// Rolling and twisting resistance of the pairs ([`super::rolling`]).
    pub rolling: Option<RollingResistance>,
}

impl GranularSet {
    /// The contact element of spheres i < j (indices into [`GranularSet::nodes`]).
    pub fn pair(&self, i: usize, j: usize) -> SpherePair {
        SpherePair::new(
            self.name.as_str(),
            [self.nodes[i], self.nodes[j]],
            [self.radii[i], self.radii[j]],
            self.law,
        )
        .with_friction(self.friction)
        .with_rolling(self.rolling)
        .with_bristle(Vector3::zeros(), 0.0)
    }

    /// Gap `|x_i − x_j| − ρ_i − ρ_j` of spheres i, j.
    pub fn gap(&self, nodes: &[NodeState], i: usize, j: usize) -> f64 {
        (nodes[self.nodes[j]].x - nodes[self.nodes[i]].x).norm() - self.radii[i] - self.radii[j]
    }

    /// The event function `(g, ġ)` of the pair of spheres i, j at `nodes`, as the pair's
    /// element gives it ([`super::contact::normal_event`] of the penetration
    /// δ = ρ_i + ρ_j − |x_j − x_i| and its rate): adaptive steps land on its zeros, the
    /// pair closing or opening.
    pub fn pair_event(&self, nodes: &[NodeState], i: usize, j: usize) -> (f64, f64) {
        let (a, b) = (&nodes[self.nodes[i]], &nodes[self.nodes[j]]);
        let d = b.x - a.x;
        let dist = d.norm();
        let delta = self.radii[i] + self.radii[j] - dist;
        let delta_dot = if dist > 0.0 {
            -d.dot(&(b.v - a.v)) / dist
        } else {
            -(b.v - a.v).z
        };
        super::contact::normal_event(&self.law, delta, delta_dot)
    }

    /// Candidate pairs (i < j, sorted) with gap below `margin`, by the uniform grid.
    pub fn candidate_pairs(&self, nodes: &[NodeState], margin: f64, out: &mut Vec<(usize, usize)>) {
        out.clear();
        let n = self.nodes.len();
        if n < 2 {
            return;
        }
        let rmax = self.radii.iter().copied().fold(0.0, f64::max);
        let h = 2.0 * rmax + margin;
        let cell =
            |x: &Vector3<f64>| -> [i64; 3] { std::array::from_fn(|k| (x[k] / h).floor() as i64) };
        let mut keys: Vec<([i64; 3], usize)> =
            (0..n).map(|i| (cell(&nodes[self.nodes[i]].x), i)).collect();
        keys.sort_unstable();
        for i in 0..n {
            let c = cell(&nodes[self.nodes[i]].x);
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        let k = [c[0] + dx, c[1] + dy, c[2] + dz];
                        let lo = keys.partition_point(|e| e.0 < k);
                        for &(kk, j) in &keys[lo..] {
                            if kk != k {
                                break;
                            }
                            if j > i && self.gap(nodes, i, j) < margin {
                                out.push((i, j));
                            }
                        }
                    }
                }
            }
        }
        out.sort_unstable();
    }

    /// Candidate pairs by testing all N(N − 1)/2 pairs (the reference for the grid).
    pub fn all_pairs(&self, nodes: &[NodeState], margin: f64) -> Vec<(usize, usize)> {
        let n = self.nodes.len();
        let mut out = Vec::new();
        for i in 0..n {
            for j in i + 1..n {
                if self.gap(nodes, i, j) < margin {
                    out.push((i, j));
                }
            }
        }
        out
    }

    /// Largest distance a sphere's centre has moved from `reference` (positions of the
    /// spheres at the last detection).
    pub fn max_displacement(&self, nodes: &[NodeState], reference: &[Vector3<f64>]) -> f64 {
        self.nodes
            .iter()
            .zip(reference)
            .map(|(&i, r)| (nodes[i].x - r).norm())
            .fold(0.0, f64::max)
    }

    /// Σ over the touching pairs of `f(pair element)`.
    /// (the bristle deflections of set `set` looked up in `bristles`, zero where absent).
    fn sum_touching(
        &self,
        nodes: &[NodeState],
        set: usize,
        bristles: &[PairBristle],
        f: impl Fn(&SpherePair, &ElementInput) -> f64,
    ) -> f64 {
        let mut pairs = Vec::new();
        self.candidate_pairs(nodes, 0.0, &mut pairs);
        let x = ElementInput::nodes(nodes);
        pairs
            .iter()
            .map(|&(i, j)| {
                let z = bristles
                    .binary_search_by(|b| b.key.cmp(&(set, i, j)))
                    .map_or(Vector3::zeros(), |k| bristles[k].z);
                let mut p = self.pair(i, j);
                p.set_bristle(z, 0.0);
                f(&p, &x)
            })
            .sum()
    }

    /// Elastic energy of the normal forces of the touching pairs.
    pub fn potential_energy(&self, ctx: &EvalContext, nodes: &[NodeState]) -> f64 {
        self.sum_touching(nodes, 0, &[], |p, x| p.potential_energy(ctx, x))
    }

    /// Power dissipated by the touching pairs (normal damping and friction), this being
    /// set number `set` with the pairs' bristle deflections in `bristles`
    /// (`State::pair_bristles`).
    pub fn dissipated_power(
        &self,
        set: usize,
        nodes: &[NodeState],
        bristles: &[PairBristle],
    ) -> f64 {
        self.sum_touching(nodes, set, bristles, |p, x| p.dissipated_power(x))
    }

    /// Number of pairs in contact (gap < 0).
    pub fn contacts(&self, nodes: &[NodeState]) -> usize {
        let mut pairs = Vec::new();
        self.candidate_pairs(nodes, 0.0, &mut pairs);
        pairs.len()
    }
}
