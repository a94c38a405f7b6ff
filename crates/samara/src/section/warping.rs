//! The warping problem of the cross-section (Giavotto et al. 1983, "Anisotropic beam
//! theory and applications", Computers & Structures 16; the formulation of ANBA and BECAS,
//! Blasques 2012) and the Timoshenko-level 6×6 compliance it gives.
//!
//! The 3-D displacement is the rigid motion of the section plus a warping field
//! `g(y, z, x) = N(y, z) w(x)` (three components at every mesh node). With the sectional
//! strains `ψ = (ε₁, γ₂, γ₃, κ₁, κ₂, κ₃)` the 3-D strain (Voigt `[xx, yy, zz, yz, xz, xy]`)
//! is
//!
//! ```text
//! ε = Z(y, z) ψ + B N w + S N ∂w/∂x,       Z rows: xx [1, 0, 0, 0, z, −y]
//!                                                   xz [0, 0, 1, y, 0, 0]
//!                                                   xy [0, 1, 0, −z, 0, 0]
//! ```
//!
//! (`B` the in-plane derivatives, `S` places ∂g/∂x). The sectional forces
//! `θ = (N, V₂, V₃, T, M₂, M₃) = ∫ Zᵀ σ dA` obey, without distributed loads, `θ′ = T θ`
//! (`M₂′ = V₃`, `M₃′ = −V₂`). The central (Saint-Venant) solution has ψ and w linear in x:
//! `w = w₀ + x w₁`, `ψ = ψ₀ + x ψ₁`, `θ = θ₀ + x T θ₀`. 3-D equilibrium for every virtual
//! warping gives, with
//! `E = ∫(BN)ᵀQ(BN)`, `R = ∫(BN)ᵀQZ`, `A = ∫ZᵀQZ`, `C = ∫(SN)ᵀQ(BN)`, `L = ∫(SN)ᵀQZ`:
//!
//! ```text
//! H [w₁; ψ₁] = [0; T θ₀]                                   H = [[E, R], [Rᵀ, A]]
//! H [w₀; ψ₀] = [(C − Cᵀ) w₁ + L ψ₁;  θ₀ − Lᵀ w₁]
//! ```
//!
//! H is singular only along the six rigid motions of the section (a rigid warping is the
//! same as a change of ψ); both right-hand sides are orthogonal to them exactly, so six
//! warping components at three nodes are held at zero, the sparse Cholesky factor of the
//! remaining matrix is computed once and used for all eight right-hand sides, and the
//! solutions are then shifted along the rigid motions so that the warping has no mean
//! rigid motion (`∫ Z_uᵀ g dA = 0`).
//!
//! The compliance is the strain energy per unit length of the section where the forces
//! are θ₀: `½ θ₀ᵀ F θ₀ = ½ ∫ ε₀ᵀ Q ε₀ dA` with `ε₀ = Z ψ₀ + B N w₀ + S N w₁`; the
//! stiffness is `K = F⁻¹`.

// Index loops over element unknowns and quadrature points read closer to the formulas.
#![allow(clippy::needless_range_loop)]

use super::element::{ElementKind, MAX_NODES};
use super::material::{Material, section_stiffness};
use super::mesh::{Mesh, jacobian};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::{
    LltRef, SymbolicCholesky, SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par, Side};
use nalgebra::{Matrix3, Matrix6, Vector3, Vector6};

/// A quadrature point of an element, mapped to the section.
pub(crate) struct Point {
    pub n: [f64; MAX_NODES],
    /// ∂N/∂y, ∂N/∂z.
    pub dn: [[f64; 2]; MAX_NODES],
    pub y: f64,
    pub z: f64,
    /// Weight × Jacobian determinant.
    pub w: f64,
}

/// Shape functions and section derivatives at reference point (ξ, η) of an element with
/// node coordinates `xy`; `weight` the quadrature weight.
pub(crate) fn map_point(
    kind: ElementKind,
    xy: &[[f64; 2]],
    xi: f64,
    eta: f64,
    weight: f64,
) -> Point {
    let mut n = [0.0; MAX_NODES];
    let mut dref = [[0.0; 2]; MAX_NODES];
    kind.shape(xi, eta, &mut n, &mut dref);
    let (j, det) = jacobian(kind, xy, &dref);
    // [∂N/∂y, ∂N/∂z] = [∂N/∂ξ, ∂N/∂η] J⁻¹.
    let inv = [
        [j[1][1] / det, -j[0][1] / det],
        [-j[1][0] / det, j[0][0] / det],
    ];
    let mut dn = [[0.0; 2]; MAX_NODES];
    let (mut y, mut z) = (0.0, 0.0);
    for k in 0..kind.n_nodes() {
        dn[k] = [
            dref[k][0] * inv[0][0] + dref[k][1] * inv[1][0],
            dref[k][0] * inv[0][1] + dref[k][1] * inv[1][1],
        ];
        y += n[k] * xy[k][0];
        z += n[k] * xy[k][1];
    }
    Point {
        n,
        dn,
        y,
        z,
        w: weight * det,
    }
}

/// Voigt rows of the 3-D strain.
const XX: usize = 0;
const YY: usize = 1;
const ZZ: usize = 2;
const YZ: usize = 3;
const XZ: usize = 4;
const XY: usize = 5;

/// `Z(y, z)`: the 3-D strain of unit sectional strains.
pub(crate) fn z_matrix(y: f64, z: f64) -> Matrix6<f64> {
    let mut m = Matrix6::zeros();
    m[(XX, 0)] = 1.0;
    m[(XX, 4)] = z;
    m[(XX, 5)] = -y;
    m[(XZ, 2)] = 1.0;
    m[(XZ, 3)] = y;
    m[(XY, 1)] = 1.0;
    m[(XY, 3)] = -z;
    m
}

/// The in-plane strain operator of warping component `c` (0: x, 1: y, 2: z) of a node with
/// shape-function derivatives `d`: two (row, value) pairs.
#[inline]
pub(crate) fn b_column(c: usize, d: [f64; 2]) -> [(usize, f64); 2] {
    match c {
        0 => [(XY, d[0]), (XZ, d[1])],
        1 => [(YY, d[0]), (YZ, d[1])],
        _ => [(ZZ, d[1]), (YZ, d[0])],
    }
}

/// The row of the 3-D strain that ∂g_c/∂x enters.
#[inline]
pub(crate) fn s_row(c: usize) -> usize {
    [XX, XY, XZ][c]
}

/// The rigid displacement modes `u = Z_u r`, `r = (t₁, t₂, t₃, φ₁, φ₂, φ₃)`, at (y, z).
pub(crate) fn rigid_modes(y: f64, z: f64) -> [[f64; 6]; 3] {
    [
        [1.0, 0.0, 0.0, 0.0, z, -y],
        [0.0, 1.0, 0.0, -z, 0.0, 0.0],
        [0.0, 0.0, 1.0, y, 0.0, 0.0],
    ]
}

/// Errors of the warping solve.
#[derive(Debug, Clone, PartialEq)]
pub enum SolveError {
    EmptyMesh,
    /// The mesh falls apart into separate pieces.
    Disconnected {
        pieces: usize,
    },
    /// The factorization failed (should not happen for a valid mesh and materials).
    Factorization(String),
}

impl std::fmt::Display for SolveError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::EmptyMesh => write!(f, "the mesh has no elements"),
            Self::Disconnected { pieces } => write!(
                f,
                "the mesh is not connected: it falls apart into {pieces} separate pieces (a section must be one body)"
            ),
            Self::Factorization(m) => write!(f, "the warping system could not be factorized: {m}"),
        }
    }
}

/// The solved warping problem: six unit load cases θ₀ = e_i.
#[derive(Clone, Debug)]
pub struct Warping {
    /// Number of warping unknowns (3 per node).
    pub n: usize,
    /// w₀ for each unit load, column-major n × 6.
    pub w0: Vec<f64>,
    /// w₁ = ∂w/∂x for each unit load, column-major n × 6.
    pub w1: Vec<f64>,
    /// ψ₀ (columns: load cases).
    pub psi0: Matrix6<f64>,
    pub psi1: Matrix6<f64>,
    /// Compliance F (energy-consistent), and K = F⁻¹.
    pub compliance: Matrix6<f64>,
    pub stiffness: Matrix6<f64>,
    /// Section-frame material stiffness of each element.
    pub q: Vec<Matrix6<f64>>,
    /// Largest residual of the full (unpinned) equations, relative to the right-hand sides.
    pub residual: f64,
}

/// Lower-triangular CSC pattern of H: 3 unknowns per node, node adjacency through the
/// elements, then six dense rows/columns for ψ.
struct Pattern {
    n: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    /// Sorted neighbours (≥ itself) of each node.
    adj: Vec<Vec<usize>>,
}

impl Pattern {
    fn new(mesh: &Mesh) -> Self {
        let nn = mesh.nodes.len();
        let mut adj: Vec<Vec<usize>> = (0..nn).map(|k| vec![k]).collect();
        for e in &mesh.elements {
            for &a in e.node_list() {
                for &b in e.node_list() {
                    if b > a {
                        adj[a].push(b);
                    }
                }
            }
        }
        for l in &mut adj {
            l.sort_unstable();
            l.dedup();
        }
        let n = 3 * nn;
        let mut col_ptr = Vec::with_capacity(n + 7);
        let mut row_idx = Vec::new();
        col_ptr.push(0);
        for (j, l) in adj.iter().enumerate() {
            for cj in 0..3 {
                for &i in l {
                    let first = if i == j { cj } else { 0 };
                    for ci in first..3 {
                        row_idx.push(3 * i + ci);
                    }
                }
                row_idx.extend(n..n + 6);
                col_ptr.push(row_idx.len());
            }
        }
        for m in 0..6 {
            row_idx.extend(n + m..n + 6);
            col_ptr.push(row_idx.len());
        }
        Self {
            n,
            col_ptr,
            row_idx,
            adj,
        }
    }

    /// Position of entry (row unknown of node i component ci, column of node j component
    /// cj), i ≥ j (and ci ≥ cj when i = j).
    #[inline]
    fn pos(&self, i: usize, ci: usize, j: usize, cj: usize) -> usize {
        let start = self.col_ptr[3 * j + cj];
        if i == j {
            return start + ci - cj;
        }
        let p = self.adj[j]
            .binary_search(&i)
            .expect("node pair in the pattern");
        start + (3 - cj) + 3 * (p - 1) + ci
    }

    /// Position of row ψ_m in the column of unknown `col` (< n).
    #[inline]
    fn pos_psi(&self, col: usize, m: usize) -> usize {
        self.col_ptr[col + 1] - 6 + m
    }

    /// Position of (ψ_a, ψ_b), a ≥ b.
    #[inline]
    fn pos_psi_psi(&self, a: usize, b: usize) -> usize {
        self.col_ptr[self.n + b] + (a - b)
    }
}

/// Counts the connected pieces of the mesh (through shared nodes) and flags the nodes no
/// element uses.
fn connectivity(mesh: &Mesh) -> (usize, Vec<bool>) {
    let nn = mesh.nodes.len();
    let mut parent: Vec<usize> = (0..nn).collect();
    fn find(p: &mut [usize], mut a: usize) -> usize {
        while p[a] != a {
            p[a] = p[p[a]];
            a = p[a];
        }
        a
    }
    let mut used = vec![false; nn];
    for e in &mesh.elements {
        let l = e.node_list();
        for &k in l {
            used[k] = true;
        }
        let r0 = find(&mut parent, l[0]);
        for &k in &l[1..] {
            let r = find(&mut parent, k);
            if r != r0 {
                parent[r] = r0;
            }
        }
    }
    let mut roots: Vec<usize> = (0..nn)
        .filter(|&k| used[k])
        .map(|k| find(&mut parent, k))
        .collect();
    roots.sort_unstable();
    roots.dedup();
    (roots.len(), used)
}

/// Six warping unknowns whose pinning removes the rigid motions: all three at the node
/// farthest left (a), the axial one and one in-plane one at the node farthest from it (b),
/// the axial one at the node farthest from the line a–b (c).
fn pins(mesh: &Mesh, used: &[bool]) -> [usize; 6] {
    let nodes = &mesh.nodes;
    let cand = || (0..nodes.len()).filter(|&k| used[k]);
    let a = cand()
        .min_by(|&p, &q| {
            nodes[p][0]
                .total_cmp(&nodes[q][0])
                .then(nodes[p][1].total_cmp(&nodes[q][1]))
        })
        .expect("a used node");
    let pa = nodes[a];
    let dist = |k: usize| (nodes[k][0] - pa[0]).hypot(nodes[k][1] - pa[1]);
    let b = cand()
        .max_by(|&p, &q| dist(p).total_cmp(&dist(q)))
        .expect("a used node");
    let d = [nodes[b][0] - pa[0], nodes[b][1] - pa[1]];
    let off = |k: usize| ((nodes[k][0] - pa[0]) * d[1] - (nodes[k][1] - pa[1]) * d[0]).abs();
    let c = cand()
        .max_by(|&p, &q| off(p).total_cmp(&off(q)))
        .expect("a used node");
    // The in-plane rotation moves b perpendicular to d: pin b's component along the larger
    // perpendicular direction.
    let inplane = if d[0].abs() >= d[1].abs() { 2 } else { 1 };
    [3 * a, 3 * a + 1, 3 * a + 2, 3 * b, 3 * b + inplane, 3 * c]
}

/// Element-level loop helper: node coordinates of element `e`.
fn coords(mesh: &Mesh, e: usize, xy: &mut [[f64; 2]; MAX_NODES]) -> usize {
    let el = &mesh.elements[e];
    for (k, &nd) in el.node_list().iter().enumerate() {
        xy[k] = mesh.nodes[nd];
    }
    el.kind.n_nodes()
}

/// Solves the warping problem of a checked mesh.
pub fn solve(mesh: &Mesh, materials: &[Material]) -> Result<Warping, SolveError> {
    if mesh.elements.is_empty() {
        return Err(SolveError::EmptyMesh);
    }
    let (pieces, used) = connectivity(mesh);
    if pieces != 1 {
        return Err(SolveError::Disconnected { pieces });
    }
    let q: Vec<Matrix6<f64>> = mesh
        .elements
        .iter()
        .map(|e| section_stiffness(&materials[e.material].stiffness, e.ply_angle, e.wall_angle))
        .collect();

    let pat = Pattern::new(mesh);
    let n = pat.n;
    let nt = n + 6;
    // Fixed unknowns: the pins and the nodes no element uses.
    let mut fixed = vec![false; n];
    for (k, &u) in used.iter().enumerate() {
        if !u {
            fixed[3 * k..3 * k + 3].fill(true);
        }
    }
    for p in pins(mesh, &used) {
        fixed[p] = true;
    }
    let mut vals = vec![0.0; pat.row_idx.len()];
    let mut xy = [[0.0; 2]; MAX_NODES];
    let mut qb = [[0.0; 6]; 3 * MAX_NODES];
    let mut bcol = [[(0usize, 0.0f64); 2]; 3 * MAX_NODES];
    let mut ee = [[0.0; 3 * MAX_NODES]; 3 * MAX_NODES];
    let mut re = [[0.0; 6]; 3 * MAX_NODES];
    for (ie, el) in mesh.elements.iter().enumerate() {
        let nn = coords(mesh, ie, &mut xy);
        let nd = 3 * nn;
        let qe = &q[ie];
        let nodes = el.node_list();
        for row in ee.iter_mut().take(nd) {
            row[..nd].fill(0.0);
        }
        for row in re.iter_mut().take(nd) {
            *row = [0.0; 6];
        }
        let mut ae = Matrix6::<f64>::zeros();
        for g in el.kind.gauss_points() {
            let pt = map_point(el.kind, &xy[..nn], g.xi, g.eta, g.weight);
            let zm = z_matrix(pt.y, pt.z);
            let qz = qe * zm;
            for a in 0..nd {
                let (k, c) = (a / 3, a % 3);
                bcol[a] = b_column(c, pt.dn[k]);
                let [(r1, v1), (r2, v2)] = bcol[a];
                for r in 0..6 {
                    qb[a][r] = pt.w * (qe[(r, r1)] * v1 + qe[(r, r2)] * v2);
                }
            }
            for a in 0..nd {
                let [(r1, v1), (r2, v2)] = bcol[a];
                for b in 0..=a {
                    ee[a][b] += v1 * qb[b][r1] + v2 * qb[b][r2];
                }
                for m in 0..6 {
                    re[a][m] += pt.w * (v1 * qz[(r1, m)] + v2 * qz[(r2, m)]);
                }
            }
            ae += pt.w * (zm.transpose() * qz);
        }
        // Scatter: E (lower triangle of the global numbering) and R.
        for a in 0..nd {
            let (ka, ca) = (a / 3, a % 3);
            let ga = 3 * nodes[ka] + ca;
            if fixed[ga] {
                continue;
            }
            for b in 0..=a {
                let (kb, cb) = (b / 3, b % 3);
                let gb = 3 * nodes[kb] + cb;
                if fixed[gb] {
                    continue;
                }
                let p = if ga >= gb {
                    pat.pos(nodes[ka], ca, nodes[kb], cb)
                } else {
                    pat.pos(nodes[kb], cb, nodes[ka], ca)
                };
                vals[p] += ee[a][b];
            }
            for m in 0..6 {
                vals[pat.pos_psi(ga, m)] += re[a][m];
            }
        }
        for a in 0..6 {
            for b in 0..=a {
                vals[pat.pos_psi_psi(a, b)] += ae[(a, b)];
            }
        }
    }
    // Pinned and unused unknowns: unit equations of the size of the mean diagonal.
    let mut diag_sum = 0.0;
    let mut diag_n = 0usize;
    for col in 0..n {
        if !fixed[col] {
            diag_sum += vals[pat.col_ptr[col]];
            diag_n += 1;
        }
    }
    let unit = if diag_n > 0 {
        diag_sum / diag_n as f64
    } else {
        1.0
    };
    for col in 0..n {
        if fixed[col] {
            vals[pat.col_ptr[col]] = unit;
        }
    }
    let sym =
        SymbolicSparseColMat::new_checked(nt, nt, pat.col_ptr.clone(), None, pat.row_idx.clone());
    let h = SparseColMat::new(sym, vals);
    let factor = Factor::new(&pat, h)?;
    let solve = |rhs: &mut [f64], cols: usize| factor.solve(rhs, cols);

    // Rigid-motion normalization: G = ∫ Z_uᵀ Z_u dA.
    let mut gram = Matrix6::<f64>::zeros();
    for (ie, el) in mesh.elements.iter().enumerate() {
        let nn = coords(mesh, ie, &mut xy);
        for g in el.kind.gauss_points() {
            let pt = map_point(el.kind, &xy[..nn], g.xi, g.eta, g.weight);
            let zu = rigid_modes(pt.y, pt.z);
            for a in 0..6 {
                for b in 0..6 {
                    gram[(a, b)] += pt.w * (0..3).map(|i| zu[i][a] * zu[i][b]).sum::<f64>();
                }
            }
        }
    }
    let gram_inv = gram.try_inverse().ok_or(SolveError::EmptyMesh)?;
    let normalize = |x: &mut [f64], cols: usize| {
        let mut proj = vec![Vector6::<f64>::zeros(); cols];
        let mut xy = [[0.0; 2]; MAX_NODES];
        for (ie, el) in mesh.elements.iter().enumerate() {
            let nn = coords(mesh, ie, &mut xy);
            let nodes = el.node_list();
            for g in el.kind.gauss_points() {
                let pt = map_point(el.kind, &xy[..nn], g.xi, g.eta, g.weight);
                let zu = rigid_modes(pt.y, pt.z);
                for (c, pc) in proj.iter_mut().enumerate() {
                    let col = &x[c * nt..(c + 1) * nt];
                    let mut u = [0.0; 3];
                    for k in 0..nn {
                        for (i, ui) in u.iter_mut().enumerate() {
                            *ui += pt.n[k] * col[3 * nodes[k] + i];
                        }
                    }
                    for a in 0..6 {
                        pc[a] += pt.w * (zu[0][a] * u[0] + zu[1][a] * u[1] + zu[2][a] * u[2]);
                    }
                }
            }
        }
        for (c, pc) in proj.iter().enumerate() {
            let col = &mut x[c * nt..(c + 1) * nt];
            let r = -(gram_inv * pc);
            for (k, p) in mesh.nodes.iter().enumerate() {
                if !used[k] {
                    continue;
                }
                let zu = rigid_modes(p[0], p[1]);
                for i in 0..3 {
                    col[3 * k + i] += (0..6).map(|a| zu[i][a] * r[a]).sum::<f64>();
                }
            }
            // ψ += −A_r r: ψ₂ += φ₃, ψ₃ −= φ₂.
            col[n + 1] += r[5];
            col[n + 2] -= r[4];
        }
    };

    // First-order problem: only shear forces make moments vary along x.
    let mut theta1 = Matrix6::zeros();
    theta1[(5, 1)] = -1.0; // M₃′ = −V₂
    theta1[(4, 2)] = 1.0; // M₂′ = V₃
    // Columns 1 and 2 (V₂, V₃); the other unit loads have w₁ = ψ₁ = 0.
    let mut x1 = vec![0.0; nt * 6];
    for c in 1..3 {
        for m in 0..6 {
            x1[c * nt + n + m] = theta1[(m, c)];
        }
    }
    let rhs1 = x1.clone();
    solve(&mut x1[nt..3 * nt], 2);
    normalize(&mut x1[nt..3 * nt], 2);

    // Zeroth-order right-hand side: [(C − Cᵀ) w₁ + L ψ₁; θ₀ − Lᵀ w₁].
    let mut x0 = vec![0.0; nt * 6];
    for c in 0..6 {
        x0[c * nt + n + c] = 1.0;
    }
    for (ie, el) in mesh.elements.iter().enumerate() {
        let nn = coords(mesh, ie, &mut xy);
        let nd = 3 * nn;
        let qe = &q[ie];
        let nodes = el.node_list();
        for g in el.kind.gauss_points() {
            let pt = map_point(el.kind, &xy[..nn], g.xi, g.eta, g.weight);
            let zm = z_matrix(pt.y, pt.z);
            for c in 1..3 {
                let col1 = &x1[c * nt..(c + 1) * nt];
                // Strains of w₁ through B and through S, and Z ψ₁.
                let mut eb = Vector6::zeros();
                let mut es = Vector6::zeros();
                for a in 0..nd {
                    let (k, cc) = (a / 3, a % 3);
                    let v = col1[3 * nodes[k] + cc];
                    for (r, bv) in b_column(cc, pt.dn[k]) {
                        eb[r] += bv * v;
                    }
                    es[s_row(cc)] += pt.n[k] * v;
                }
                let psi1 = Vector6::from_iterator((0..6).map(|m| col1[n + m]));
                let qeb = qe * eb;
                let qes = qe * es;
                let qzp = qe * (zm * psi1);
                let out = &mut x0[c * nt..(c + 1) * nt];
                for a in 0..nd {
                    let (k, cc) = (a / 3, a % 3);
                    let row = 3 * nodes[k] + cc;
                    let sr = s_row(cc);
                    let mut v = pt.n[k] * (qeb[sr] + qzp[sr]);
                    for (r, bv) in b_column(cc, pt.dn[k]) {
                        v -= bv * qes[r];
                    }
                    out[row] += pt.w * v;
                }
                // − Lᵀ w₁ = −∫ Zᵀ Q (S N w₁).
                let lt = zm.transpose() * qes;
                for m in 0..6 {
                    out[n + m] -= pt.w * lt[m];
                }
            }
        }
    }
    let rhs0 = x0.clone();
    for c in 0..6 {
        for (k, f) in fixed.iter().enumerate() {
            if *f {
                x0[c * nt + k] = 0.0;
            }
        }
    }
    solve(&mut x0, 6);
    normalize(&mut x0, 6);

    // The equations of the pinned unknowns were dropped: their residuals check that both
    // right-hand sides were orthogonal to the rigid motions.
    let pinned: Vec<usize> = pins(mesh, &used).to_vec();
    let residual = {
        let r1 = pinned_residual(mesh, &q, &x1, &rhs1, nt, &pinned);
        let r0 = pinned_residual(mesh, &q, &x0, &rhs0, nt, &pinned);
        r1.max(r0)
    };

    // Energy-consistent compliance.
    let mut f = Matrix6::zeros();
    for (ie, el) in mesh.elements.iter().enumerate() {
        let nn = coords(mesh, ie, &mut xy);
        let qe = &q[ie];
        let nodes = el.node_list();
        for g in el.kind.gauss_points() {
            let pt = map_point(el.kind, &xy[..nn], g.xi, g.eta, g.weight);
            let eps = strain_columns(&pt, nodes, nn, &x0, &x1, n, nt);
            f += pt.w * (eps.transpose() * qe * eps);
        }
    }
    let f = 0.5 * (f + f.transpose());
    let k = f
        .try_inverse()
        .ok_or_else(|| SolveError::Factorization("the compliance is singular".into()))?;
    let k = 0.5 * (k + k.transpose());

    let take = |x: &[f64]| {
        let mut w = vec![0.0; n * 6];
        let mut psi = Matrix6::zeros();
        for c in 0..6 {
            w[c * n..(c + 1) * n].copy_from_slice(&x[c * nt..c * nt + n]);
            for m in 0..6 {
                psi[(m, c)] = x[c * nt + n + m];
            }
        }
        (w, psi)
    };
    let (w0, psi0) = take(&x0);
    let (w1, psi1) = take(&x1);
    Ok(Warping {
        n,
        w0,
        w1,
        psi0,
        psi1,
        compliance: f,
        stiffness: k,
        q,
        residual,
    })
}

/// The 3-D strain ε₀ = Z ψ₀ + B N w₀ + S N w₁ of the six unit loads at a point (columns).
fn strain_columns(
    pt: &Point,
    nodes: &[usize],
    nn: usize,
    x0: &[f64],
    x1: &[f64],
    n: usize,
    nt: usize,
) -> Matrix6<f64> {
    let zm = z_matrix(pt.y, pt.z);
    let mut eps = Matrix6::zeros();
    for c in 0..6 {
        let c0 = &x0[c * nt..(c + 1) * nt];
        let c1 = &x1[c * nt..(c + 1) * nt];
        let psi = Vector6::from_iterator((0..6).map(|m| c0[n + m]));
        let mut e = zm * psi;
        for k in 0..nn {
            for cc in 0..3 {
                let dof = 3 * nodes[k] + cc;
                for (r, bv) in b_column(cc, pt.dn[k]) {
                    e[r] += bv * c0[dof];
                }
                e[s_row(cc)] += pt.n[k] * c1[dof];
            }
        }
        eps.set_column(c, &e);
    }
    eps
}

/// Largest |(H x − b)_i| over the rows i of `rows`, relative to max |b| (per column).
fn pinned_residual(
    mesh: &Mesh,
    q: &[Matrix6<f64>],
    x: &[f64],
    b: &[f64],
    nt: usize,
    rows: &[usize],
) -> f64 {
    let n = nt - 6;
    let cols = x.len() / nt;
    let mut r = vec![0.0; cols * rows.len()];
    let mut xy = [[0.0; 2]; MAX_NODES];
    for (ie, el) in mesh.elements.iter().enumerate() {
        let nodes = el.node_list();
        if !nodes.iter().any(|&k| rows.iter().any(|&d| d / 3 == k)) {
            continue;
        }
        let nn = coords(mesh, ie, &mut xy);
        for g in el.kind.gauss_points() {
            let pt = map_point(el.kind, &xy[..nn], g.xi, g.eta, g.weight);
            let zm = z_matrix(pt.y, pt.z);
            for c in 0..cols {
                let xc = &x[c * nt..(c + 1) * nt];
                let psi = Vector6::from_iterator((0..6).map(|m| xc[n + m]));
                let mut e = zm * psi;
                for k in 0..nn {
                    for cc in 0..3 {
                        for (row, bv) in b_column(cc, pt.dn[k]) {
                            e[row] += bv * xc[3 * nodes[k] + cc];
                        }
                    }
                }
                let s = q[ie] * e;
                for k in 0..nn {
                    for cc in 0..3 {
                        let dof = 3 * nodes[k] + cc;
                        if let Some(i) = rows.iter().position(|&d| d == dof) {
                            let mut v = 0.0;
                            for (row, bv) in b_column(cc, pt.dn[k]) {
                                v += bv * s[row];
                            }
                            r[c * rows.len() + i] += pt.w * v;
                        }
                    }
                }
            }
        }
    }
    let mut worst: f64 = 0.0;
    for c in 0..cols {
        let bc = &b[c * nt..(c + 1) * nt];
        let scale = bc.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        if scale == 0.0 {
            continue;
        }
        for (i, &d) in rows.iter().enumerate() {
            worst = worst.max((r[c * rows.len() + i] - bc[d]).abs() / scale);
        }
    }
    worst
}

/// Sparse Cholesky factor of the pinned H, ordered by approximate minimum degree on the
/// node graph (three unknowns per node kept together, ψ last).
struct Factor {
    symbolic: SymbolicCholesky<usize>,
    numeric: Vec<f64>,
}

impl Factor {
    fn new(pat: &Pattern, h: SparseColMat<usize, f64>) -> Result<Self, SolveError> {
        let fail = |e: &dyn std::fmt::Debug| SolveError::Factorization(format!("{e:?}"));
        let nn = pat.adj.len();
        let nt = pat.n + 6;
        // Node graph (lower triangle) for the ordering.
        let mut col_ptr = Vec::with_capacity(nn + 1);
        let mut row_idx = Vec::new();
        col_ptr.push(0);
        for l in &pat.adj {
            row_idx.extend_from_slice(l);
            col_ptr.push(row_idx.len());
        }
        let graph = SymbolicSparseColMat::new_checked(nn, nn, col_ptr, None, row_idx);
        let mut fwd = vec![0usize; nn];
        let mut inv = vec![0usize; nn];
        let mut mem = MemBuffer::try_new(faer::sparse::linalg::amd::order_scratch::<usize>(
            nn,
            graph.compute_nnz(),
        ))
        .map_err(|e| fail(&e))?;
        faer::sparse::linalg::amd::order(
            &mut fwd,
            &mut inv,
            graph.as_ref(),
            Default::default(),
            MemStack::new(&mut mem),
        )
        .map_err(|e| fail(&e))?;
        let mut pf = Vec::with_capacity(nt);
        for &k in &fwd {
            pf.extend([3 * k, 3 * k + 1, 3 * k + 2]);
        }
        pf.extend(pat.n..nt);
        let mut pi = vec![0usize; nt];
        for (i, &k) in pf.iter().enumerate() {
            pi[k] = i;
        }
        let perm = PermRef::new_checked(&pf, &pi, nt);
        let symbolic = factorize_symbolic_cholesky(
            h.symbolic(),
            Side::Lower,
            SymmetricOrdering::Custom(perm),
            Default::default(),
        )
        .map_err(|e| fail(&e))?;
        let mut numeric = vec![0.0; symbolic.len_val()];
        let par = Par::Seq;
        let mut mem = MemBuffer::try_new(
            symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()),
        )
        .map_err(|e| fail(&e))?;
        symbolic
            .factorize_numeric_llt::<f64>(
                &mut numeric,
                h.as_ref(),
                Side::Lower,
                Default::default(),
                par,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .map_err(|e| fail(&e))?;
        Ok(Self { symbolic, numeric })
    }

    fn solve(&self, rhs: &mut [f64], cols: usize) {
        let nt = rhs.len() / cols;
        let par = Par::Seq;
        let mut mem = MemBuffer::new(self.symbolic.solve_in_place_scratch::<f64>(cols, par));
        LltRef::<'_, usize, f64>::new(&self.symbolic, &self.numeric).solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(rhs, nt, cols),
            par,
            MemStack::new(&mut mem),
        );
    }
}

/// Sums over the section: area, mass per length, first and second moments (mass-weighted).
#[derive(Clone, Copy, Debug, Default)]
pub struct Integrals {
    pub area: f64,
    pub mass: f64,
    /// ∫ ρ y, ∫ ρ z.
    pub mass_moment: [f64; 2],
    /// ∫ ρ y², ∫ ρ z², ∫ ρ y z.
    pub mass_second: [f64; 3],
    /// ∫ y, ∫ z (geometric).
    pub area_moment: [f64; 2],
}

/// Area and mass integrals of the section.
pub fn integrals(mesh: &Mesh, materials: &[Material]) -> Integrals {
    let mut s = Integrals::default();
    let mut xy = [[0.0; 2]; MAX_NODES];
    for (ie, el) in mesh.elements.iter().enumerate() {
        let nn = coords(mesh, ie, &mut xy);
        let rho = materials[el.material].density;
        for g in el.kind.gauss_points() {
            let pt = map_point(el.kind, &xy[..nn], g.xi, g.eta, g.weight);
            s.area += pt.w;
            s.area_moment[0] += pt.w * pt.y;
            s.area_moment[1] += pt.w * pt.z;
            let m = pt.w * rho;
            s.mass += m;
            s.mass_moment[0] += m * pt.y;
            s.mass_moment[1] += m * pt.z;
            s.mass_second[0] += m * pt.y * pt.y;
            s.mass_second[1] += m * pt.z * pt.z;
            s.mass_second[2] += m * pt.y * pt.z;
        }
    }
    s
}

/// The 6×6 mass per unit length about the reference point (origin), section frame:
/// `[[m I, m η̃ᵀ], [m η̃, J]]`, `J = ∫ ρ (|p|² I − p pᵀ) dA`, p = (0, y, z).
pub fn mass_matrix(s: &Integrals) -> Matrix6<f64> {
    let m = s.mass;
    let eta = Vector3::new(0.0, s.mass_moment[0], s.mass_moment[1]);
    let et = crate::math::skew(&eta);
    let [iyy, izz, iyz] = s.mass_second;
    let j = Matrix3::new(iyy + izz, 0.0, 0.0, 0.0, izz, -iyz, 0.0, -iyz, iyy);
    let mut out = Matrix6::zeros();
    out.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&(Matrix3::identity() * m));
    out.fixed_view_mut::<3, 3>(0, 3).copy_from(&et.transpose());
    out.fixed_view_mut::<3, 3>(3, 0).copy_from(&et);
    out.fixed_view_mut::<3, 3>(3, 3).copy_from(&j);
    out
}
