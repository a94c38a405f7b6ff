//! Two-dimensional isoparametric elements of the cross-section: shape functions, their
//! derivatives and quadrature rules. Node numbering is Gmsh's: corners counter-clockwise,
//! then the mid-side nodes (edge 0–1 first), then the centre (9-node quadrilateral).
//!
//! Quadrature is exact for the mass-like terms of straight-sided elements: 2×2 and 3×3
//! Gauss for the 4- and 8/9-node quadrilaterals, the 3-point (degree 2) and 7-point
//! (degree 5, Radon) rules for the 3- and 6-node triangles.

/// Most nodes of any element.
pub const MAX_NODES: usize = 9;

/// The element types.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ElementKind {
    Tri3,
    Tri6,
    Quad4,
    Quad8,
    Quad9,
}

/// One quadrature point in the reference element.
#[derive(Clone, Copy, Debug)]
pub struct GaussPoint {
    pub xi: f64,
    pub eta: f64,
    pub weight: f64,
}

const G2: f64 = 0.577_350_269_189_625_8; // 1/√3
const G3: f64 = 0.774_596_669_241_483_4; // √(3/5)

impl ElementKind {
    pub fn n_nodes(self) -> usize {
        match self {
            Self::Tri3 => 3,
            Self::Tri6 => 6,
            Self::Quad4 => 4,
            Self::Quad8 => 8,
            Self::Quad9 => 9,
        }
    }

    pub fn n_corners(self) -> usize {
        match self {
            Self::Tri3 | Self::Tri6 => 3,
            _ => 4,
        }
    }

    /// Polynomial order of the edges (1 or 2).
    pub fn order(self) -> usize {
        match self {
            Self::Tri3 | Self::Quad4 => 1,
            _ => 2,
        }
    }

    pub fn is_triangle(self) -> bool {
        matches!(self, Self::Tri3 | Self::Tri6)
    }

    /// Name as written in mesh files.
    pub fn name(self) -> &'static str {
        match self {
            Self::Tri3 => "tri3",
            Self::Tri6 => "tri6",
            Self::Quad4 => "quad4",
            Self::Quad8 => "quad8",
            Self::Quad9 => "quad9",
        }
    }

    pub fn from_name(s: &str) -> Option<Self> {
        Some(match s {
            "tri3" => Self::Tri3,
            "tri6" => Self::Tri6,
            "quad4" => Self::Quad4,
            "quad8" => Self::Quad8,
            "quad9" => Self::Quad9,
            _ => return None,
        })
    }

    pub const ALL: [ElementKind; 5] = [
        Self::Tri3,
        Self::Tri6,
        Self::Quad4,
        Self::Quad8,
        Self::Quad9,
    ];

    /// Reference coordinates of the nodes.
    pub fn node_coordinates(self) -> &'static [[f64; 2]] {
        match self {
            Self::Tri3 => &[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
            Self::Tri6 => &[
                [0.0, 0.0],
                [1.0, 0.0],
                [0.0, 1.0],
                [0.5, 0.0],
                [0.5, 0.5],
                [0.0, 0.5],
            ],
            Self::Quad4 => &[[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]],
            Self::Quad8 => &[
                [-1.0, -1.0],
                [1.0, -1.0],
                [1.0, 1.0],
                [-1.0, 1.0],
                [0.0, -1.0],
                [1.0, 0.0],
                [0.0, 1.0],
                [-1.0, 0.0],
            ],
            Self::Quad9 => &[
                [-1.0, -1.0],
                [1.0, -1.0],
                [1.0, 1.0],
                [-1.0, 1.0],
                [0.0, -1.0],
                [1.0, 0.0],
                [0.0, 1.0],
                [-1.0, 0.0],
                [0.0, 0.0],
            ],
        }
    }

    /// Node order of the same element traversed clockwise (mirror of the numbering).
    pub fn reversed(self) -> &'static [usize] {
        match self {
            Self::Tri3 => &[0, 2, 1],
            Self::Tri6 => &[0, 2, 1, 5, 4, 3],
            Self::Quad4 => &[0, 3, 2, 1],
            Self::Quad8 => &[0, 3, 2, 1, 7, 6, 5, 4],
            Self::Quad9 => &[0, 3, 2, 1, 7, 6, 5, 4, 8],
        }
    }

    /// The quadrature rule (weights sum to the reference area: ½ for triangles, 4 for
    /// quadrilaterals).
    pub fn gauss_points(self) -> &'static [GaussPoint] {
        match self {
            Self::Tri3 => &TRI3_RULE,
            Self::Tri6 => &TRI7_RULE,
            Self::Quad4 => &QUAD2_RULE,
            Self::Quad8 | Self::Quad9 => &QUAD3_RULE,
        }
    }

    /// Shape functions `n` and their derivatives `dn[k] = (∂N_k/∂ξ, ∂N_k/∂η)` at (ξ, η).
    pub fn shape(
        self,
        xi: f64,
        eta: f64,
        n: &mut [f64; MAX_NODES],
        dn: &mut [[f64; 2]; MAX_NODES],
    ) {
        match self {
            Self::Tri3 => {
                n[0] = 1.0 - xi - eta;
                n[1] = xi;
                n[2] = eta;
                dn[0] = [-1.0, -1.0];
                dn[1] = [1.0, 0.0];
                dn[2] = [0.0, 1.0];
            }
            Self::Tri6 => {
                let l1 = 1.0 - xi - eta;
                let (l2, l3) = (xi, eta);
                n[0] = l1 * (2.0 * l1 - 1.0);
                n[1] = l2 * (2.0 * l2 - 1.0);
                n[2] = l3 * (2.0 * l3 - 1.0);
                n[3] = 4.0 * l1 * l2;
                n[4] = 4.0 * l2 * l3;
                n[5] = 4.0 * l3 * l1;
                // ∂L1 = (−1, −1), ∂L2 = (1, 0), ∂L3 = (0, 1).
                let d1 = 4.0 * l1 - 1.0;
                dn[0] = [-d1, -d1];
                dn[1] = [4.0 * l2 - 1.0, 0.0];
                dn[2] = [0.0, 4.0 * l3 - 1.0];
                dn[3] = [4.0 * (l1 - l2), -4.0 * l2];
                dn[4] = [4.0 * l3, 4.0 * l2];
                dn[5] = [-4.0 * l3, 4.0 * (l1 - l3)];
            }
            Self::Quad4 => {
                for (k, c) in QUAD_CORNERS.iter().enumerate() {
                    n[k] = 0.25 * (1.0 + c[0] * xi) * (1.0 + c[1] * eta);
                    dn[k] = [
                        0.25 * c[0] * (1.0 + c[1] * eta),
                        0.25 * c[1] * (1.0 + c[0] * xi),
                    ];
                }
            }
            Self::Quad8 => {
                for (k, c) in QUAD_CORNERS.iter().enumerate() {
                    let (a, b) = (1.0 + c[0] * xi, 1.0 + c[1] * eta);
                    let s = c[0] * xi + c[1] * eta - 1.0;
                    n[k] = 0.25 * a * b * s;
                    dn[k] = [0.25 * c[0] * b * (s + a), 0.25 * c[1] * a * (s + b)];
                }
                // Mid-side nodes on η = ∓1 (4, 6) and ξ = ±1 (5, 7).
                for (k, e) in [(4, -1.0), (6, 1.0)] {
                    n[k] = 0.5 * (1.0 - xi * xi) * (1.0 + e * eta);
                    dn[k] = [-xi * (1.0 + e * eta), 0.5 * e * (1.0 - xi * xi)];
                }
                for (k, e) in [(5, 1.0), (7, -1.0)] {
                    n[k] = 0.5 * (1.0 + e * xi) * (1.0 - eta * eta);
                    dn[k] = [0.5 * e * (1.0 - eta * eta), -eta * (1.0 + e * xi)];
                }
            }
            Self::Quad9 => {
                let (lx, dlx) = lagrange3(xi);
                let (ly, dly) = lagrange3(eta);
                // (i, j) index of each node in the 3×3 tensor grid (0: −1, 1: 0, 2: +1).
                const IJ: [(usize, usize); 9] = [
                    (0, 0),
                    (2, 0),
                    (2, 2),
                    (0, 2),
                    (1, 0),
                    (2, 1),
                    (1, 2),
                    (0, 1),
                    (1, 1),
                ];
                for (k, &(i, j)) in IJ.iter().enumerate() {
                    n[k] = lx[i] * ly[j];
                    dn[k] = [dlx[i] * ly[j], lx[i] * dly[j]];
                }
            }
        }
    }
}

const QUAD_CORNERS: [[f64; 2]; 4] = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];

/// The 1-D quadratic Lagrange polynomials on nodes −1, 0, 1 and their derivatives.
fn lagrange3(x: f64) -> ([f64; 3], [f64; 3]) {
    (
        [0.5 * x * (x - 1.0), 1.0 - x * x, 0.5 * x * (x + 1.0)],
        [x - 0.5, -2.0 * x, x + 0.5],
    )
}

const fn gp(xi: f64, eta: f64, weight: f64) -> GaussPoint {
    GaussPoint { xi, eta, weight }
}

static QUAD2_RULE: [GaussPoint; 4] = [
    gp(-G2, -G2, 1.0),
    gp(G2, -G2, 1.0),
    gp(G2, G2, 1.0),
    gp(-G2, G2, 1.0),
];

const W5: f64 = 5.0 / 9.0;
const W8: f64 = 8.0 / 9.0;
static QUAD3_RULE: [GaussPoint; 9] = [
    gp(-G3, -G3, W5 * W5),
    gp(0.0, -G3, W8 * W5),
    gp(G3, -G3, W5 * W5),
    gp(-G3, 0.0, W5 * W8),
    gp(0.0, 0.0, W8 * W8),
    gp(G3, 0.0, W5 * W8),
    gp(-G3, G3, W5 * W5),
    gp(0.0, G3, W8 * W5),
    gp(G3, G3, W5 * W5),
];

static TRI3_RULE: [GaussPoint; 3] = [
    gp(1.0 / 6.0, 1.0 / 6.0, 1.0 / 6.0),
    gp(2.0 / 3.0, 1.0 / 6.0, 1.0 / 6.0),
    gp(1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0),
];

// Radon's 7-point rule (degree 5): a = (6 ∓ √15)/21, weights (155 ± √15)/2400 on the
// reference triangle of area ½.
#[allow(clippy::excessive_precision)]
const TA: f64 = 0.101_286_507_323_456_34; // (6 − √15)/21
#[allow(clippy::excessive_precision)]
const TB: f64 = 0.470_142_064_105_115_1; // (6 + √15)/21
#[allow(clippy::excessive_precision)]
const WA: f64 = 0.062_969_590_272_413_58; // (155 − √15)/2400
#[allow(clippy::excessive_precision)]
const WB: f64 = 0.066_197_076_394_253_09; // (155 + √15)/2400
static TRI7_RULE: [GaussPoint; 7] = [
    gp(1.0 / 3.0, 1.0 / 3.0, 9.0 / 80.0),
    gp(TA, TA, WA),
    gp(1.0 - 2.0 * TA, TA, WA),
    gp(TA, 1.0 - 2.0 * TA, WA),
    gp(TB, TB, WB),
    gp(1.0 - 2.0 * TB, TB, WB),
    gp(TB, 1.0 - 2.0 * TB, WB),
];

#[cfg(test)]
#[allow(clippy::needless_range_loop)]
mod tests {
    use super::*;

    #[test]
    fn partition_of_unity_and_kronecker_property() {
        for kind in ElementKind::ALL {
            let mut n = [0.0; MAX_NODES];
            let mut dn = [[0.0; 2]; MAX_NODES];
            for (k, p) in kind.node_coordinates().iter().enumerate() {
                kind.shape(p[0], p[1], &mut n, &mut dn);
                for j in 0..kind.n_nodes() {
                    let want = if j == k { 1.0 } else { 0.0 };
                    assert!((n[j] - want).abs() < 1e-14, "{kind:?} node {k} N{j}");
                }
            }
            // Derivatives against central differences at an interior point.
            let (x, y) = (0.21, 0.17);
            kind.shape(x, y, &mut n, &mut dn);
            let s: f64 = n[..kind.n_nodes()].iter().sum();
            assert!((s - 1.0).abs() < 1e-14);
            let h = 1e-6;
            let mut np = [0.0; MAX_NODES];
            let mut nm = [0.0; MAX_NODES];
            let mut d = [[0.0; 2]; MAX_NODES];
            for dir in 0..2 {
                let (dx, dy) = if dir == 0 { (h, 0.0) } else { (0.0, h) };
                kind.shape(x + dx, y + dy, &mut np, &mut d);
                kind.shape(x - dx, y - dy, &mut nm, &mut d);
                for j in 0..kind.n_nodes() {
                    let fd = (np[j] - nm[j]) / (2.0 * h);
                    assert!((fd - dn[j][dir]).abs() < 1e-8, "{kind:?} dN{j}/d{dir}");
                }
            }
        }
    }

    #[test]
    fn quadrature_integrates_polynomials() {
        // ∫ ξ^a η^b over the reference element, for a + b up to the rule's degree.
        let fact = |n: u32| (1..=n).map(f64::from).product::<f64>();
        for kind in ElementKind::ALL {
            let degree = match kind {
                ElementKind::Tri3 => 2,
                ElementKind::Tri6 => 5,
                ElementKind::Quad4 => 3,
                _ => 5,
            };
            for a in 0..=degree {
                for b in 0..=(degree - a) {
                    let got: f64 = kind
                        .gauss_points()
                        .iter()
                        .map(|g| g.weight * g.xi.powi(a as i32) * g.eta.powi(b as i32))
                        .sum();
                    let want = if kind.is_triangle() {
                        fact(a) * fact(b) / fact(a + b + 2)
                    } else {
                        let m = |p: u32| {
                            if p % 2 == 1 {
                                0.0
                            } else {
                                2.0 / (p as f64 + 1.0)
                            }
                        };
                        m(a) * m(b)
                    };
                    assert!(
                        (got - want).abs() < 1e-14,
                        "{kind:?} ξ^{a} η^{b}: {got} vs {want}"
                    );
                }
            }
        }
    }
}
