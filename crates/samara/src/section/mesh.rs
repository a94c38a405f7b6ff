//! The finite-element mesh of a cross-section: nodes in the section plane (y, z), elements
//! with their material and fibre orientation, and the checks every mesh passes before it
//! is solved (element orientation and non-degenerate Jacobians).

use super::element::{ElementKind, MAX_NODES};
use std::collections::HashMap;

/// One element: its type, nodes, material (index into the section's materials) and the
/// orientation of the material axes (see [`super::material`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Element {
    pub kind: ElementKind,
    pub nodes: [usize; MAX_NODES],
    pub material: usize,
    /// Ply (fibre) angle θ [rad], about the wall normal, from the beam axis towards the
    /// wall's contour direction.
    pub ply_angle: f64,
    /// Wall angle φ [rad]: the contour direction is (0, cos φ, sin φ).
    pub wall_angle: f64,
}

impl Element {
    pub fn node_list(&self) -> &[usize] {
        &self.nodes[..self.kind.n_nodes()]
    }
}

/// A cross-section mesh.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Node coordinates (y, z) [m], section frame.
    pub nodes: Vec<[f64; 2]>,
    pub elements: Vec<Element>,
}

/// Why an element cannot be used.
#[derive(Clone, Debug, PartialEq)]
pub struct BadElement {
    pub element: usize,
    pub message: String,
}

impl Mesh {
    /// Bounding box `([ymin, zmin], [ymax, zmax])`.
    pub fn bounds(&self) -> ([f64; 2], [f64; 2]) {
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for p in &self.nodes {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        (lo, hi)
    }

    /// Largest extent of the section.
    pub fn size(&self) -> f64 {
        let (lo, hi) = self.bounds();
        (hi[0] - lo[0]).max(hi[1] - lo[1])
    }

    /// Shifts the section by `offset` (y, z), then turns it by `angle` [rad] about the beam
    /// axis (counter-clockwise in the (y, z) plane); wall angles turn with it.
    pub fn transform(&mut self, offset: [f64; 2], angle: f64) {
        let (s, c) = angle.sin_cos();
        for p in &mut self.nodes {
            let (y, z) = (p[0] + offset[0], p[1] + offset[1]);
            *p = [c * y - s * z, s * y + c * z];
        }
        for e in &mut self.elements {
            e.wall_angle += angle;
        }
    }

    /// Checks every element: nodes that exist, finite coordinates, and a Jacobian
    /// determinant positive and not vanishingly small at every node and quadrature point.
    /// A mesh numbered clockwise throughout (a mirrored mesh) is renumbered; a clockwise
    /// element among counter-clockwise ones is inverted and reported.
    pub fn check(&mut self) -> Result<(), Vec<BadElement>> {
        let mut bad = Vec::new();
        let n_nodes = self.nodes.len();
        let scale = self.size().max(f64::MIN_POSITIVE);
        let tiny = 1e-10 * scale * scale;
        let mut ranges = Vec::with_capacity(self.elements.len());
        for (ie, e) in self.elements.iter().enumerate() {
            if let Some(&k) = e.node_list().iter().find(|&&k| k >= n_nodes) {
                bad.push(BadElement {
                    element: ie,
                    message: format!("refers to node {} which does not exist", k + 1),
                });
                ranges.push(None);
                continue;
            }
            let xy: Vec<[f64; 2]> = e.node_list().iter().map(|&k| self.nodes[k]).collect();
            if !xy.iter().flatten().all(|v| v.is_finite()) {
                bad.push(BadElement {
                    element: ie,
                    message: "has a node with non-finite coordinates".into(),
                });
                ranges.push(None);
                continue;
            }
            let mut sorted = e.node_list().to_vec();
            sorted.sort_unstable();
            if sorted.windows(2).any(|w| w[0] == w[1]) {
                bad.push(BadElement {
                    element: ie,
                    message: "uses the same node twice".into(),
                });
                ranges.push(None);
                continue;
            }
            ranges.push(Some((
                jacobian_range(e.kind, &xy),
                element_area(e.kind, &xy),
            )));
        }
        let clockwise = |r: &Option<((f64, f64), f64)>| {
            r.is_some_and(|((min, max), _)| min < -tiny && max < -tiny)
        };
        let mirrored = !ranges.is_empty() && ranges.iter().all(clockwise);
        for (ie, (e, r)) in self.elements.iter_mut().zip(&ranges).enumerate() {
            let Some(((min, max), area)) = *r else {
                continue;
            };
            if mirrored {
                let old = e.nodes;
                for (k, &q) in e.kind.reversed().iter().enumerate() {
                    e.nodes[k] = old[q];
                }
                continue;
            }
            if min.is_nan() || min <= tiny {
                let what = if max < -tiny {
                    "is inverted (numbered clockwise while the rest of the mesh is counter-clockwise)"
                } else {
                    "is degenerate or folded"
                };
                bad.push(BadElement {
                    element: ie,
                    message: format!(
                        "{what}: its Jacobian determinant ranges from {min:.3e} to {max:.3e} (area {:.3e} m²)",
                        area.abs()
                    ),
                });
            }
        }
        if bad.is_empty() { Ok(()) } else { Err(bad) }
    }
}

/// Smallest and largest Jacobian determinant over the nodes and quadrature points.
pub fn jacobian_range(kind: ElementKind, xy: &[[f64; 2]]) -> (f64, f64) {
    let mut n = [0.0; MAX_NODES];
    let mut dn = [[0.0; 2]; MAX_NODES];
    let mut min = f64::INFINITY;
    let mut max = f64::NEG_INFINITY;
    let pts = kind
        .node_coordinates()
        .iter()
        .copied()
        .chain(kind.gauss_points().iter().map(|g| [g.xi, g.eta]));
    for p in pts {
        kind.shape(p[0], p[1], &mut n, &mut dn);
        let d = jacobian(kind, xy, &dn).1;
        min = min.min(d);
        max = max.max(d);
    }
    (min, max)
}

/// The Jacobian `J = [[∂y/∂ξ, ∂y/∂η], [∂z/∂ξ, ∂z/∂η]]` and its determinant.
pub fn jacobian(
    kind: ElementKind,
    xy: &[[f64; 2]],
    dn: &[[f64; 2]; MAX_NODES],
) -> ([[f64; 2]; 2], f64) {
    let mut j = [[0.0; 2]; 2];
    for k in 0..kind.n_nodes() {
        for a in 0..2 {
            for b in 0..2 {
                j[a][b] += xy[k][a] * dn[k][b];
            }
        }
    }
    let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
    (j, det)
}

/// Signed area by quadrature.
pub fn element_area(kind: ElementKind, xy: &[[f64; 2]]) -> f64 {
    let mut n = [0.0; MAX_NODES];
    let mut dn = [[0.0; 2]; MAX_NODES];
    kind.gauss_points()
        .iter()
        .map(|g| {
            kind.shape(g.xi, g.eta, &mut n, &mut dn);
            g.weight * jacobian(kind, xy, &dn).1
        })
        .sum()
}

/// Attributes of generated elements.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ElementAttr {
    pub material: usize,
    pub ply_angle: f64,
    pub wall_angle: f64,
}

/// Builds meshes patch by patch; nodes closer than the tolerance are merged, so patches
/// that share an edge with the same node positions are joined.
pub struct MeshBuilder {
    pub mesh: Mesh,
    tol: f64,
    grid: HashMap<(i64, i64), Vec<usize>>,
}

impl MeshBuilder {
    /// `tol`: the distance under which two nodes are the same [m].
    pub fn new(tol: f64) -> Self {
        Self {
            mesh: Mesh::default(),
            tol,
            grid: HashMap::new(),
        }
    }

    /// The node at `p`, created if none is within the tolerance.
    pub fn node(&mut self, p: [f64; 2]) -> usize {
        let cell = |v: f64| (v / (2.0 * self.tol)).floor() as i64;
        let (cy, cz) = (cell(p[0]), cell(p[1]));
        for dy in -1..=1 {
            for dz in -1..=1 {
                if let Some(list) = self.grid.get(&(cy + dy, cz + dz)) {
                    for &k in list {
                        let q = self.mesh.nodes[k];
                        if (q[0] - p[0]).hypot(q[1] - p[1]) <= self.tol {
                            return k;
                        }
                    }
                }
            }
        }
        let k = self.mesh.nodes.len();
        self.mesh.nodes.push(p);
        self.grid.entry((cy, cz)).or_default().push(k);
        k
    }

    /// Adds one element from its node positions (Gmsh order); a clockwise element is
    /// renumbered counter-clockwise.
    pub fn element(&mut self, kind: ElementKind, pts: &[[f64; 2]], attr: ElementAttr) {
        let reverse = element_area(kind, pts) < 0.0;
        self.oriented(kind, pts, attr, reverse);
    }

    fn oriented(&mut self, kind: ElementKind, pts: &[[f64; 2]], attr: ElementAttr, reverse: bool) {
        let mut nodes = [0; MAX_NODES];
        for (k, p) in pts.iter().enumerate().take(kind.n_nodes()) {
            nodes[k] = self.node(*p);
        }
        if reverse {
            let old = nodes;
            for (k, &r) in kind.reversed().iter().enumerate() {
                nodes[k] = old[r];
            }
        }
        self.mesh.elements.push(Element {
            kind,
            nodes,
            material: attr.material,
            ply_angle: attr.ply_angle,
            wall_angle: attr.wall_angle,
        });
    }

    /// A structured patch of `ni × nj` cells. `pos(i, j)` gives the node position at grid
    /// index (i, j), 0 ≤ i ≤ ni·p, 0 ≤ j ≤ nj·p with p the element order (mid-side and
    /// centre nodes at odd indices); `attr(ci, cj)` the attributes of cell (ci, cj).
    /// Triangles split each cell along its (0,0)–(1,1) diagonal. All cells take the
    /// orientation of the patch as a whole, so a folded cell stays inverted and the mesh
    /// check reports it.
    pub fn patch(
        &mut self,
        kind: ElementKind,
        ni: usize,
        nj: usize,
        pos: impl Fn(usize, usize) -> [f64; 2],
        attr: impl Fn(usize, usize) -> ElementAttr,
    ) {
        let p = kind.order();
        let mut signed = 0.0;
        for ci in 0..ni {
            for cj in 0..nj {
                let (i0, j0) = (ci * p, cj * p);
                let q = [
                    pos(i0, j0),
                    pos(i0 + p, j0),
                    pos(i0 + p, j0 + p),
                    pos(i0, j0 + p),
                ];
                signed += (0..4)
                    .map(|k| q[k][0] * q[(k + 1) % 4][1] - q[(k + 1) % 4][0] * q[k][1])
                    .sum::<f64>();
            }
        }
        let rev = signed < 0.0;
        for ci in 0..ni {
            for cj in 0..nj {
                let (i0, j0) = (ci * p, cj * p);
                let at = |a: usize, b: usize| pos(i0 + a, j0 + b);
                let att = attr(ci, cj);
                match kind {
                    ElementKind::Quad4 => {
                        self.oriented(kind, &[at(0, 0), at(1, 0), at(1, 1), at(0, 1)], att, rev)
                    }
                    ElementKind::Quad8 | ElementKind::Quad9 => {
                        let pts = [
                            at(0, 0),
                            at(2, 0),
                            at(2, 2),
                            at(0, 2),
                            at(1, 0),
                            at(2, 1),
                            at(1, 2),
                            at(0, 1),
                            at(1, 1),
                        ];
                        self.oriented(kind, &pts[..kind.n_nodes()], att, rev)
                    }
                    ElementKind::Tri3 => {
                        self.oriented(kind, &[at(0, 0), at(1, 0), at(1, 1)], att, rev);
                        self.oriented(kind, &[at(0, 0), at(1, 1), at(0, 1)], att, rev);
                    }
                    ElementKind::Tri6 => {
                        self.oriented(
                            kind,
                            &[at(0, 0), at(2, 0), at(2, 2), at(1, 0), at(2, 1), at(1, 1)],
                            att,
                            rev,
                        );
                        self.oriented(
                            kind,
                            &[at(0, 0), at(2, 2), at(0, 2), at(1, 1), at(1, 2), at(0, 1)],
                            att,
                            rev,
                        );
                    }
                }
            }
        }
    }

    pub fn finish(self) -> Mesh {
        self.mesh
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn attr() -> ElementAttr {
        ElementAttr {
            material: 0,
            ply_angle: 0.0,
            wall_angle: 0.0,
        }
    }

    #[test]
    fn patches_share_nodes_and_areas_add_up() {
        for kind in ElementKind::ALL {
            let mut b = MeshBuilder::new(1e-9);
            let p = kind.order();
            let (ni, nj) = (3, 2);
            let h = 1.0 / (ni * p) as f64;
            let v = 0.5 / (nj * p) as f64;
            // Two patches side by side (x from 0 to 1 and 1 to 2), one of them mirrored
            // (clockwise): the builder renumbers it.
            b.patch(
                kind,
                ni,
                nj,
                |i, j| [i as f64 * h, j as f64 * v],
                |_, _| attr(),
            );
            b.patch(
                kind,
                ni,
                nj,
                |i, j| [2.0 - i as f64 * h, j as f64 * v],
                |_, _| attr(),
            );
            let mut m = b.finish();
            let grid = 2 * ni * p + 1;
            let per_col = nj * p + 1;
            let expect = match kind {
                ElementKind::Quad8 => grid * per_col - 2 * ni * nj,
                _ => grid * per_col,
            };
            assert_eq!(m.nodes.len(), expect, "{kind:?}");
            assert!(m.check().is_ok());
            let area: f64 = m
                .elements
                .iter()
                .map(|e| {
                    let xy: Vec<_> = e.node_list().iter().map(|&k| m.nodes[k]).collect();
                    element_area(e.kind, &xy)
                })
                .sum();
            assert!((area - 1.0).abs() < 1e-14, "{kind:?} {area}");
        }
    }

    #[test]
    fn degenerate_inverted_and_mirrored_elements() {
        let el = |kind, nodes: &[usize]| {
            let mut n = [0; MAX_NODES];
            n[..nodes.len()].copy_from_slice(nodes);
            Element {
                kind,
                nodes: n,
                material: 0,
                ply_angle: 0.0,
                wall_angle: 0.0,
            }
        };
        let nodes = vec![
            [0.0, 0.0],
            [1.0, 0.0],
            [1.0, 1.0],
            [0.0, 1.0],
            [2.0, 0.0],
            [2.0, 1.0],
        ];
        // A flat triangle and a clockwise quadrilateral next to a counter-clockwise one.
        let mut m = Mesh {
            nodes: nodes.clone(),
            elements: vec![
                el(ElementKind::Quad4, &[0, 3, 2, 1]),
                el(ElementKind::Tri3, &[0, 1, 4]),
                el(ElementKind::Quad4, &[1, 4, 5, 2]),
            ],
        };
        let bad = m.check().unwrap_err();
        assert_eq!(bad.len(), 2);
        assert_eq!(bad[0].element, 0);
        assert!(bad[0].message.contains("inverted"), "{}", bad[0].message);
        assert_eq!(bad[1].element, 1);
        assert!(bad[1].message.contains("degenerate"), "{}", bad[1].message);
        // A mesh numbered clockwise throughout is renumbered.
        let mut m = Mesh {
            nodes,
            elements: vec![
                el(ElementKind::Quad4, &[0, 3, 2, 1]),
                el(ElementKind::Quad4, &[1, 2, 5, 4]),
            ],
        };
        assert!(m.check().is_ok());
        assert_eq!(m.elements[0].node_list(), &[0, 1, 2, 3]);
    }
}
