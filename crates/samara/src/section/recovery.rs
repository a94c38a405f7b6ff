//! Recovery: the 3-D strain and stress over the section for given sectional forces
//! θ = (N, V₂, V₃, T, M₂, M₃) (section frame, about the origin), from the solved warping
//! problem: `ε = Σᵢ θᵢ ε₀(eᵢ)` with `ε₀ = Z ψ₀ + B N w₀ + S N w₁` (the central solution at
//! the section where the forces are θ), `σ = Q ε`.
//!
//! Values are evaluated at every element's own nodes (no averaging across elements, so
//! the stress jumps between plies stay sharp) and written as a VTK unstructured grid
//! (`.vtu`, points (y, z, 0)) and as CSV.

use super::element::{ElementKind, MAX_NODES};
use super::material::{material_axes, stress_rotation};
use super::warping::{b_column, map_point, s_row, z_matrix};
use super::{SectionModel, SectionResult};
use nalgebra::{Matrix6, Vector6};
use std::fmt::Write as _;
use std::path::Path;

/// Strain and stress at one node of one element. Voigt order: section frame
/// `[xx, yy, zz, yz, xz, xy]` (engineering shear strains); material axes `[11, 22, 33, 23,
/// 13, 12]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeValues {
    pub element: usize,
    pub y: f64,
    pub z: f64,
    pub strain: [f64; 6],
    pub stress: [f64; 6],
    pub strain_material: [f64; 6],
    pub stress_material: [f64; 6],
}

/// The 3-D strain of sectional forces θ at reference point (ξ, η) of element `e`.
pub fn strain_at(
    model: &SectionModel,
    r: &SectionResult,
    e: usize,
    xi: f64,
    eta: f64,
    theta: &Vector6<f64>,
) -> (f64, f64, Vector6<f64>) {
    let el = &model.mesh.elements[e];
    let mut xy = [[0.0; 2]; MAX_NODES];
    for (p, &k) in xy.iter_mut().zip(el.node_list()) {
        *p = model.mesh.nodes[k];
    }
    let pt = map_point(el.kind, &xy[..el.kind.n_nodes()], xi, eta, 1.0);
    let w = &r.warping;
    let n = w.n;
    let zm = z_matrix(pt.y, pt.z);
    let mut eps = zm * (w.psi0 * theta);
    for (k, &node) in el.node_list().iter().enumerate() {
        for c in 0..3 {
            let dof = 3 * node + c;
            let w0: f64 = (0..6).map(|i| theta[i] * w.w0[i * n + dof]).sum();
            let w1: f64 = (0..6).map(|i| theta[i] * w.w1[i * n + dof]).sum();
            for (row, bv) in b_column(c, pt.dn[k]) {
                eps[row] += bv * w0;
            }
            eps[s_row(c)] += pt.n[k] * w1;
        }
    }
    (pt.y, pt.z, eps)
}

/// Strain and stress at every element node.
pub fn recover(model: &SectionModel, r: &SectionResult, theta: &Vector6<f64>) -> Vec<NodeValues> {
    let mut out = Vec::new();
    for (e, el) in model.mesh.elements.iter().enumerate() {
        let q: &Matrix6<f64> = &r.warping.q[e];
        let t = stress_rotation(&material_axes(el.ply_angle, el.wall_angle));
        let t_inv = stress_rotation(&material_axes(el.ply_angle, el.wall_angle).transpose());
        for p in el.kind.node_coordinates() {
            let (y, z, eps) = strain_at(model, r, e, p[0], p[1], theta);
            let sig = q * eps;
            let eps_m = t.transpose() * eps;
            let sig_m = t_inv * sig;
            out.push(NodeValues {
                element: e,
                y,
                z,
                strain: eps.into(),
                stress: sig.into(),
                strain_material: eps_m.into(),
                stress_material: sig_m.into(),
            });
        }
    }
    out
}

fn vtk_type(k: ElementKind) -> u8 {
    match k {
        ElementKind::Tri3 => 5,
        ElementKind::Tri6 => 22,
        ElementKind::Quad4 => 9,
        ElementKind::Quad8 => 23,
        ElementKind::Quad9 => 28,
    }
}

fn array(out: &mut String, name: &str, comps: usize, values: impl Iterator<Item = f64>) {
    let _ = write!(
        out,
        "        <DataArray type=\"Float64\" Name=\"{name}\" NumberOfComponents=\"{comps}\" format=\"ascii\">\n          "
    );
    for (i, v) in values.enumerate() {
        if i > 0 {
            out.push(' ');
        }
        let _ = write!(out, "{v:e}");
    }
    out.push_str("\n        </DataArray>\n");
}

const SECTION_COMPONENTS: [&str; 6] = ["xx", "yy", "zz", "yz", "xz", "xy"];
const MATERIAL_COMPONENTS: [&str; 6] = ["11", "22", "33", "23", "13", "12"];

/// The recovered field as a VTU file (each element with its own nodes).
pub fn vtu(model: &SectionModel, values: &[NodeValues]) -> String {
    let n_cells = model.mesh.elements.len();
    let mut s = String::new();
    s.push_str("<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\">\n  <UnstructuredGrid>\n");
    let _ = writeln!(
        s,
        "    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{n_cells}\">",
        values.len()
    );
    s.push_str("      <Points>\n");
    array(
        &mut s,
        "Points",
        3,
        values.iter().flat_map(|v| [v.y, v.z, 0.0]),
    );
    s.push_str("      </Points>\n      <Cells>\n");
    let _ = write!(
        s,
        "        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n          "
    );
    let conn: Vec<String> = (0..values.len()).map(|i| i.to_string()).collect();
    s.push_str(&conn.join(" "));
    s.push_str("\n        </DataArray>\n");
    let _ = write!(
        s,
        "        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n          "
    );
    let mut off = 0;
    let offs: Vec<String> = model
        .mesh
        .elements
        .iter()
        .map(|e| {
            off += e.kind.n_nodes();
            off.to_string()
        })
        .collect();
    s.push_str(&offs.join(" "));
    s.push_str("\n        </DataArray>\n");
    let _ = write!(
        s,
        "        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n          "
    );
    let types: Vec<String> = model
        .mesh
        .elements
        .iter()
        .map(|e| vtk_type(e.kind).to_string())
        .collect();
    s.push_str(&types.join(" "));
    s.push_str("\n        </DataArray>\n      </Cells>\n      <PointData>\n");
    for (name, get) in [
        (
            "strain",
            (|v: &NodeValues| v.strain) as fn(&NodeValues) -> [f64; 6],
        ),
        ("stress", |v: &NodeValues| v.stress),
        ("strain_material", |v: &NodeValues| v.strain_material),
        ("stress_material", |v: &NodeValues| v.stress_material),
    ] {
        array(&mut s, name, 6, values.iter().flat_map(get));
    }
    array(
        &mut s,
        "von_mises",
        1,
        values.iter().map(|v| von_mises(&v.stress)),
    );
    s.push_str("      </PointData>\n      <CellData>\n");
    array(
        &mut s,
        "material",
        1,
        model.mesh.elements.iter().map(|e| e.material as f64),
    );
    array(
        &mut s,
        "ply_angle",
        1,
        model.mesh.elements.iter().map(|e| e.ply_angle.to_degrees()),
    );
    array(
        &mut s,
        "wall_angle",
        1,
        model
            .mesh
            .elements
            .iter()
            .map(|e| e.wall_angle.to_degrees()),
    );
    s.push_str("      </CellData>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n");
    s
}

/// Von Mises equivalent stress of a Voigt stress.
pub fn von_mises(s: &[f64; 6]) -> f64 {
    let [xx, yy, zz, yz, xz, xy] = *s;
    (0.5 * ((xx - yy).powi(2) + (yy - zz).powi(2) + (zz - xx).powi(2))
        + 3.0 * (yz * yz + xz * xz + xy * xy))
        .sqrt()
}

/// The recovered field as CSV: one row per element node.
pub fn csv(model: &SectionModel, values: &[NodeValues]) -> String {
    let mut s = String::from("element,y,z,material,ply_angle_deg");
    for (p, comps) in [
        ("strain_", SECTION_COMPONENTS),
        ("stress_", SECTION_COMPONENTS),
        ("strain_", MATERIAL_COMPONENTS),
        ("stress_", MATERIAL_COMPONENTS),
    ] {
        for c in comps {
            let _ = write!(s, ",{p}{c}");
        }
    }
    s.push_str(",von_mises\n");
    for v in values {
        let e = &model.mesh.elements[v.element];
        let _ = write!(
            s,
            "{},{:e},{:e},{},{}",
            v.element + 1,
            v.y,
            v.z,
            model.materials[e.material].name,
            e.ply_angle.to_degrees()
        );
        for a in [v.strain, v.stress, v.strain_material, v.stress_material] {
            for x in a {
                let _ = write!(s, ",{x:e}");
            }
        }
        let _ = writeln!(s, ",{:e}", von_mises(&v.stress));
    }
    s
}

/// Writes `<dir>/<stem>.vtu` and `<dir>/<stem>.csv`.
pub fn write(
    dir: &Path,
    stem: &str,
    model: &SectionModel,
    values: &[NodeValues],
) -> Result<[std::path::PathBuf; 2], crate::Error> {
    std::fs::create_dir_all(dir).map_err(|e| crate::Error::Io {
        path: dir.to_path_buf(),
        action: "create the output directory",
        source: e,
    })?;
    let vtu_path = dir.join(format!("{stem}.vtu"));
    let csv_path = dir.join(format!("{stem}.csv"));
    for (p, text) in [
        (&vtu_path, vtu(model, values)),
        (&csv_path, csv(model, values)),
    ] {
        std::fs::write(p, text).map_err(|e| crate::Error::Io {
            path: p.clone(),
            action: "write",
            source: e,
        })?;
    }
    Ok([vtu_path, csv_path])
}
