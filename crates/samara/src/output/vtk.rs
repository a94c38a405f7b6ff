//! ParaView scenes from a results file: one binary VTK XML UnstructuredGrid (`.vtu`, see
//! [`super::vtu`]) per output time, a `.pvd` collection that indexes them by time, and a
//! ParaView Python script `<stem>_scene.py` that opens the animated scene
//! (`paraview --script=<stem>_scene.py`). A modal results file also gets, per mode, an
//! animation of the mode shape over one period (`<stem>_mode_NN.pvd`).
//!
//! Every file holds one piece; its cells, told apart by the cell data `cell_kind`:
//!
//! | cell_kind | cells | points |
//! |---|---|---|
//! | 0 | one vertex per node | node position |
//! | 1 | one vertex per joint | joint point (side B) |
//! | 2 | one vertex per body | centre of gravity |
//! | 3 | one hexahedron per body | corners of the body's equivalent box |
//! | 4 | one polyline per beam | its nodes, root to tip |
//! | 5 | one polyline per beam | its sections (elastic quadrature points) |
//!
//! The equivalent box of a body is the uniform box of the body's mass and principal moments
//! of inertia (`L_i² = 6 (I_j + I_k − I_i)/m`), along its principal axes, centred on the
//! CG. Point data (zero where it does not apply): `kind` (= the cell kind of the point),
//! `index` (within its kind: node, joint, body, beam node or section), `frame_x`,
//! `frame_y`, `frame_z` (node frame; joint frame A; the body's node frame; the section
//! frame at beam nodes and sections; global components), `displacement` (nodes and beam
//! nodes: position − reference position), `velocity`, `angular_velocity` (nodes, CGs),
//! `mass` (CGs), `joint_force`, `joint_moment` (joints, **global** components),
//! `beam_force`, `beam_moment`, `beam_strain`, `beam_curvature` (sections, section-frame
//! components as in the results file). Cell data: `cell_kind`, `index` (node, joint, body
//! or beam).

use super::reader::{ReadError, ResultsReader};
use super::vtu::{Grid, VTK_HEXAHEDRON, VTK_POLY_LINE, VTK_VERTEX, Values};
use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Point and cell kinds (see the module documentation).
const NODE: i32 = 0;
const JOINT: i32 = 1;
const BODY: i32 = 2;
const BODY_BOX: i32 = 3;
const BEAM_NODE: i32 = 4;
const SECTION: i32 = 5;

/// What [`write_vtk_with`] does with a modal results file.
#[derive(Clone, Debug)]
pub struct VtkOptions {
    /// Scale of the mode shapes (they are normalized to a largest component of 1); `None`:
    /// the largest node displacement is a tenth of the model's size (and no rotation
    /// exceeds 0.5 rad).
    pub mode_scale: Option<f64>,
    /// Files per period of a mode animation.
    pub mode_frames: usize,
}

impl Default for VtkOptions {
    fn default() -> Self {
        Self {
            mode_scale: None,
            mode_frames: 24,
        }
    }
}

/// What [`write_vtk`] wrote.
pub struct VtkSeries {
    pub collection: PathBuf,
    pub files: Vec<PathBuf>,
    /// Points per file of the time series.
    pub points: usize,
    /// The ParaView Python script that opens the scene.
    pub script: PathBuf,
    /// Modal results: one collection per mode (`<stem>_mode_NN.pvd`).
    pub modes: Vec<PathBuf>,
}

fn io_err(path: &Path, e: std::io::Error) -> crate::Error {
    crate::Error::Io {
        path: path.to_path_buf(),
        action: "write",
        source: e,
    }
}

fn rotation(q: &[f64]) -> Matrix3<f64> {
    quaternion(q).to_rotation_matrix().into_inner()
}

fn quaternion(q: &[f64]) -> UnitQuaternion<f64> {
    UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3]))
}

fn v3(s: &[f64]) -> Vector3<f64> {
    Vector3::new(s[0], s[1], s[2])
}

/// The fixed part of a results file the scene needs.
struct Layout {
    nn: usize,
    nj: usize,
    reference: Vec<f64>,
    body_node: Vec<usize>,
    body_offset: Vec<Vector3<f64>>,
    body_mass: Vec<f64>,
    /// Per body: principal axes (columns, node frame) and the box's side lengths.
    body_box: Vec<Option<(Matrix3<f64>, Vector3<f64>)>>,
    /// Per beam: (node index, node-to-section offset).
    beam_nodes: Vec<Vec<(usize, UnitQuaternion<f64>)>>,
    /// Per beam: its section indices, root to tip.
    beam_sections: Vec<Vec<usize>>,
}

/// The uniform box with the body's mass and principal moments: principal axes (node
/// frame) and side lengths; `None` for a point mass.
fn equivalent_box(mass: f64, inertia: &Matrix3<f64>) -> Option<(Matrix3<f64>, Vector3<f64>)> {
    let eig = nalgebra::SymmetricEigen::new(*inertia);
    let i = eig.eigenvalues;
    let sides = Vector3::from_fn(|a, _| {
        let (j, k) = ((a + 1) % 3, (a + 2) % 3);
        (6.0 * (i[j] + i[k] - i[a]) / mass).max(0.0).sqrt()
    });
    if !sides.iter().all(|s| s.is_finite()) || sides.max() <= 0.0 {
        return None;
    }
    let mut axes = eig.eigenvectors;
    if axes.determinant() < 0.0 {
        axes.column_mut(2).neg_mut();
    }
    Some((axes, sides))
}

impl Layout {
    fn read(r: &mut ResultsReader) -> Result<Self, ReadError> {
        let nn = r.node_names.len();
        let nj = r.joint_names.len();
        let nb = r.body_names.len();
        let reference = if r.has_variable("reference_position") {
            r.read("reference_position")?
        } else {
            Vec::new()
        };
        let (mut body_node, mut body_offset, mut body_mass, mut body_box) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        if nb > 0 {
            body_node = r.read("body_node")?.iter().map(|&i| i as usize).collect();
            body_offset = r.read("body_cg_offset")?.chunks(3).map(v3).collect();
            body_mass = r.read("body_mass")?;
            body_box = if r.has_variable("body_inertia") {
                let j = r.read("body_inertia")?;
                (0..nb)
                    .map(|b| {
                        let m = Matrix3::from_row_slice(&j[9 * b..9 * b + 9]);
                        equivalent_box(body_mass[b], &m)
                    })
                    .collect()
            } else {
                vec![None; nb]
            };
        }
        let section_beam = if r.section_names.is_empty() {
            Vec::new()
        } else {
            r.read("section_beam")?
        };
        let n_beams = section_beam
            .iter()
            .map(|&b| b as usize + 1)
            .max()
            .unwrap_or(0);
        let mut beam_nodes = vec![Vec::new(); n_beams];
        let mut beam_sections = vec![Vec::new(); n_beams];
        if n_beams > 0 && r.has_variable("beam_node_index") {
            let idx = r.read("beam_node_index")?;
            let beam = r.read("beam_node_beam")?;
            let off = r.read("beam_node_offset")?;
            for (k, (&i, &b)) in idx.iter().zip(&beam).enumerate() {
                if let Some(list) = beam_nodes.get_mut(b as usize)
                    && (i as usize) < nn
                {
                    list.push((i as usize, quaternion(&off[4 * k..4 * k + 4])));
                }
            }
        }
        for (s, &b) in section_beam.iter().enumerate() {
            if let Some(list) = beam_sections.get_mut(b as usize) {
                list.push(s);
            }
        }
        Ok(Self {
            nn,
            nj,
            reference,
            body_node,
            body_offset,
            body_mass,
            body_box,
            beam_nodes,
            beam_sections,
        })
    }

    /// Size of the model: the diagonal of the reference positions' bounding box (1 if the
    /// model is a point).
    fn size(&self) -> f64 {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in self.reference.chunks(3) {
            for c in 0..3 {
                lo[c] = lo[c].min(p[c]);
                hi[c] = hi[c].max(p[c]);
            }
        }
        let d = (0..3).map(|c| (hi[c] - lo[c]).powi(2)).sum::<f64>().sqrt();
        if d.is_finite() && d > 0.0 { d } else { 1.0 }
    }
}

/// One configuration to draw. Slices hold one record: `x` 3 per node, `q` 4 per node.
struct Frame<'a> {
    x: &'a [f64],
    q: &'a [f64],
    /// Node velocities and angular velocities.
    v: Option<(&'a [f64], &'a [f64])>,
    /// Joint points, axes (3 × 3 per joint, rows e1, e2, e3), force and moment (frame A).
    joints: Option<[&'a [f64]; 4]>,
    /// Section positions, orientations, forces, moments, strains, curvatures.
    sections: Option<[&'a [f64]; 6]>,
}

/// Names of the 3-vector point data, in the order of `PointRows::vec`.
const VECTORS: [&str; 9] = [
    "displacement",
    "velocity",
    "angular_velocity",
    "joint_force",
    "joint_moment",
    "beam_force",
    "beam_moment",
    "beam_strain",
    "beam_curvature",
];

/// Point data of a grid being built: one row per point.
#[derive(Default)]
struct PointRows {
    kind: Vec<i32>,
    index: Vec<i32>,
    frame: Vec<[[f64; 3]; 3]>,
    mass: Vec<f64>,
    vec: [Vec<f64>; 9],
}

impl PointRows {
    fn push(&mut self, kind: i32, index: usize, frame: [[f64; 3]; 3]) {
        self.kind.push(kind);
        self.index.push(index as i32);
        self.frame.push(frame);
        self.mass.push(0.0);
        for v in &mut self.vec {
            v.extend([0.0; 3]);
        }
    }

    /// Sets vector `which` (index in [`VECTORS`]) of the last point.
    fn set(&mut self, which: usize, value: [f64; 3]) {
        let n = self.vec[which].len();
        self.vec[which][n - 3..].copy_from_slice(&value);
    }
}

fn frame_of(r: &Matrix3<f64>) -> [[f64; 3]; 3] {
    [0, 1, 2].map(|e| [r[(0, e)], r[(1, e)], r[(2, e)]])
}

/// The grid of one configuration.
fn build(l: &Layout, f: &Frame) -> Grid {
    let mut g = Grid::default();
    let mut p = PointRows::default();
    let mut cells: Vec<(i32, i32)> = Vec::new();
    let nn = l.nn;
    let rot: Vec<Matrix3<f64>> = (0..nn).map(|i| rotation(&f.q[4 * i..4 * i + 4])).collect();
    let displacement = |i: usize| -> [f64; 3] {
        if l.reference.len() == 3 * nn {
            [0, 1, 2].map(|c| f.x[3 * i + c] - l.reference[3 * i + c])
        } else {
            [0.0; 3]
        }
    };
    let x = |i: usize| [f.x[3 * i], f.x[3 * i + 1], f.x[3 * i + 2]];
    for i in 0..nn {
        let id = g.add_point(x(i));
        g.add_cell(VTK_VERTEX, &[id]);
        cells.push((NODE, i as i32));
        p.push(NODE, i, frame_of(&rot[i]));
        p.set(0, displacement(i));
        if let Some((v, w)) = f.v {
            p.set(1, [v[3 * i], v[3 * i + 1], v[3 * i + 2]]);
            p.set(2, [w[3 * i], w[3 * i + 1], w[3 * i + 2]]);
        }
    }
    if let Some([jp, ja, jf, jm]) = f.joints {
        for j in 0..l.nj {
            let id = g.add_point([jp[3 * j], jp[3 * j + 1], jp[3 * j + 2]]);
            g.add_cell(VTK_VERTEX, &[id]);
            cells.push((JOINT, j as i32));
            let a = &ja[9 * j..9 * j + 9];
            let frame = [0, 1, 2].map(|e| [a[3 * e], a[3 * e + 1], a[3 * e + 2]]);
            p.push(JOINT, j, frame);
            // Frame-A components to global: F = Σ_e F_e a_e.
            let global =
                |c: &[f64]| [0, 1, 2].map(|i| (0..3).map(|e| frame[e][i] * c[e]).sum::<f64>());
            p.set(3, global(&jf[3 * j..3 * j + 3]));
            p.set(4, global(&jm[3 * j..3 * j + 3]));
        }
    }
    for (b, &i) in l.body_node.iter().enumerate() {
        let r = rot[i];
        let rc = r * l.body_offset[b];
        let cg = v3(&f.x[3 * i..3 * i + 3]) + rc;
        let id = g.add_point(cg.into());
        g.add_cell(VTK_VERTEX, &[id]);
        cells.push((BODY, b as i32));
        p.push(BODY, b, frame_of(&r));
        if let Some(m) = p.mass.last_mut() {
            *m = l.body_mass[b];
        }
        if let Some((v, w)) = f.v {
            let w = v3(&w[3 * i..3 * i + 3]);
            p.set(1, (v3(&v[3 * i..3 * i + 3]) + w.cross(&rc)).into());
            p.set(2, w.into());
        }
        if let Some((axes, sides)) = &l.body_box[b] {
            let ra = r * axes;
            let mut ids = [0usize; 8];
            // VTK hexahedron order: the face z = −1 counter-clockwise, then z = +1.
            let corners = [
                [-1., -1., -1.],
                [1., -1., -1.],
                [1., 1., -1.],
                [-1., 1., -1.],
                [-1., -1., 1.],
                [1., -1., 1.],
                [1., 1., 1.],
                [-1., 1., 1.],
            ];
            for (k, c) in corners.iter().enumerate() {
                let local = Vector3::from_fn(|a, _| 0.5 * c[a] * sides[a]);
                ids[k] = g.add_point((cg + ra * local).into());
                p.push(BODY_BOX, b, frame_of(&ra));
            }
            g.add_cell(VTK_HEXAHEDRON, &ids);
            cells.push((BODY_BOX, b as i32));
        }
    }
    for (b, list) in l.beam_nodes.iter().enumerate() {
        if list.len() < 2 {
            continue;
        }
        let mut ids = Vec::with_capacity(list.len());
        for &(i, o) in list {
            ids.push(g.add_point(x(i)));
            let s = quaternion(&f.q[4 * i..4 * i + 4]) * o;
            p.push(BEAM_NODE, i, frame_of(&s.to_rotation_matrix().into_inner()));
            p.set(0, displacement(i));
        }
        g.add_cell(VTK_POLY_LINE, &ids);
        cells.push((BEAM_NODE, b as i32));
    }
    if let Some([sx, sq, sf, sm, se, sk]) = f.sections {
        for (b, list) in l.beam_sections.iter().enumerate() {
            if list.is_empty() {
                continue;
            }
            let mut ids = Vec::with_capacity(list.len());
            for &s in list {
                ids.push(g.add_point([sx[3 * s], sx[3 * s + 1], sx[3 * s + 2]]));
                p.push(SECTION, s, frame_of(&rotation(&sq[4 * s..4 * s + 4])));
                for (k, v) in [sf, sm, se, sk].iter().enumerate() {
                    p.set(5 + k, [v[3 * s], v[3 * s + 1], v[3 * s + 2]]);
                }
            }
            g.add_cell(VTK_POLY_LINE, &ids);
            cells.push((SECTION, b as i32));
        }
    }
    g.point_data("kind", 1, Values::I32(p.kind));
    g.point_data("index", 1, Values::I32(p.index));
    for (e, name) in ["frame_x", "frame_y", "frame_z"].iter().enumerate() {
        g.point_data(
            name,
            3,
            Values::F64(p.frame.iter().flat_map(|f| f[e]).collect()),
        );
    }
    let has_joints = f.joints.is_some() && l.nj > 0;
    for (k, name) in VECTORS.iter().enumerate() {
        let wanted = match k {
            1 | 2 => f.v.is_some(),
            3 | 4 => has_joints,
            5..=8 => f.sections.is_some(),
            _ => true,
        };
        if wanted {
            g.point_data(name, 3, Values::F64(std::mem::take(&mut p.vec[k])));
        }
    }
    if !l.body_node.is_empty() {
        g.point_data("mass", 1, Values::F64(p.mass));
    }
    g.cell_data(
        "cell_kind",
        1,
        Values::I32(cells.iter().map(|c| c.0).collect()),
    );
    g.cell_data("index", 1, Values::I32(cells.iter().map(|c| c.1).collect()));
    g
}

/// Writes a `.pvd` collection of `(time, file name)`.
fn write_pvd(path: &Path, entries: &[(f64, String)]) -> Result<(), crate::Error> {
    let mut pvd = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n",
    );
    for (t, name) in entries {
        let _ = writeln!(
            pvd,
            "    <DataSet timestep=\"{t:e}\" group=\"\" part=\"0\" file=\"{name}\"/>"
        );
    }
    pvd.push_str("  </Collection>\n</VTKFile>\n");
    std::fs::write(path, pvd).map_err(|e| io_err(path, e))
}

/// [`write_vtk_with`] with the default options.
pub fn write_vtk(reader: &mut ResultsReader, dir: &Path) -> Result<VtkSeries, crate::Error> {
    write_vtk_with(reader, dir, &VtkOptions::default())
}

/// Writes `<dir>/<stem>.pvd`, `<dir>/<stem>_NNNNNN.vtu` (one per output time) and the
/// ParaView script `<dir>/<stem>_scene.py`, creating `dir`; for a modal results file also
/// `<dir>/<stem>_mode_MM.pvd` and `<dir>/<stem>_mode_MM_KKKK.vtu` per mode. These are
/// derived files: an earlier series of the same stem in `dir` is replaced (the results
/// file itself is only read).
pub fn write_vtk_with(
    reader: &mut ResultsReader,
    dir: &Path,
    options: &VtkOptions,
) -> Result<VtkSeries, crate::Error> {
    let source = reader.path().to_path_buf();
    let rd = |e: ReadError| crate::Error::Output {
        path: source.clone(),
        message: e.to_string(),
    };
    let bad = |message: String| crate::Error::Output {
        path: source.clone(),
        message,
    };
    if options.mode_frames < 2 {
        return Err(bad(format!(
            "a mode animation needs at least 2 frames per period (got {})",
            options.mode_frames
        )));
    }
    if let Some(s) = options.mode_scale
        && !s.is_finite()
    {
        return Err(bad(format!(
            "the mode scale must be a finite number (got {s})"
        )));
    }
    std::fs::create_dir_all(dir).map_err(|e| crate::Error::Io {
        path: dir.to_path_buf(),
        action: "create the output directory",
        source: e,
    })?;
    let stem = reader
        .path()
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("results")
        .to_string();
    let layout = Layout::read(reader).map_err(rd)?;
    let (nn, nj) = (layout.nn, layout.nj);
    let time = reader.time().map_err(rd)?;
    let pos = reader.read("position").map_err(rd)?;
    let quat = reader.read("orientation").map_err(rd)?;
    let vel = reader.read("velocity").map_err(rd)?;
    let omega = reader.read("angular_velocity").map_err(rd)?;
    let joints = if nj > 0 {
        Some((
            reader.read("joint_position").map_err(rd)?,
            reader.read("joint_axes").map_err(rd)?,
            reader.read("joint_force").map_err(rd)?,
            reader.read("joint_moment").map_err(rd)?,
        ))
    } else {
        None
    };
    let ns = reader.section_names.len();
    let sections = if ns > 0 {
        let mut s = Vec::with_capacity(6);
        for name in [
            "section_position",
            "section_orientation",
            "beam_force",
            "beam_moment",
            "beam_strain",
            "beam_curvature",
        ] {
            s.push(reader.read(name).map_err(rd)?);
        }
        Some(s)
    } else {
        None
    };
    let mut files = Vec::with_capacity(time.len());
    let mut entries = Vec::with_capacity(time.len());
    let mut points = 0;
    for (k, &t) in time.iter().enumerate() {
        let r3 = |n: usize| k * n * 3..(k + 1) * n * 3;
        let frame = Frame {
            x: &pos[r3(nn)],
            q: &quat[k * nn * 4..(k + 1) * nn * 4],
            v: Some((&vel[r3(nn)], &omega[r3(nn)])),
            joints: joints.as_ref().map(|(p, a, f, m)| {
                [
                    &p[r3(nj)],
                    &a[k * nj * 9..(k + 1) * nj * 9],
                    &f[r3(nj)],
                    &m[r3(nj)],
                ]
            }),
            sections: sections.as_ref().map(|s| {
                [
                    &s[0][r3(ns)],
                    &s[1][k * ns * 4..(k + 1) * ns * 4],
                    &s[2][r3(ns)],
                    &s[3][r3(ns)],
                    &s[4][r3(ns)],
                    &s[5][r3(ns)],
                ]
            }),
        };
        let grid = build(&layout, &frame);
        points = grid.n_points();
        let name = format!("{stem}_{k:06}.vtu");
        let path = dir.join(&name);
        std::fs::write(&path, grid.to_bytes()).map_err(|e| io_err(&path, e))?;
        entries.push((t, name));
        files.push(path);
    }
    let collection = dir.join(format!("{stem}.pvd"));
    write_pvd(&collection, &entries)?;
    let modes = if reader.has_variable("mode_shape") && reader.has_variable("frequency") {
        let freq = reader.read("frequency").map_err(rd)?;
        let shape = reader.read("mode_shape").map_err(rd)?;
        if time.is_empty() || shape.len() != freq.len() * nn * 12 {
            return Err(bad(format!(
                "the mode shapes ({} values) do not match {} modes of {nn} nodes, or the file has no record",
                shape.len(),
                freq.len()
            )));
        }
        let k = time.len() - 1;
        let modal = Modal {
            freq: &freq,
            shape: &shape,
            x0: &pos[k * nn * 3..(k + 1) * nn * 3],
            q0: &quat[k * nn * 4..(k + 1) * nn * 4],
        };
        write_modes(&modal, &layout, dir, &stem, options)?
    } else {
        Vec::new()
    };
    let script = dir.join(format!("{stem}_scene.py"));
    let text = scene_script(&stem, dir, &layout, &modes);
    std::fs::write(&script, text).map_err(|e| io_err(&script, e))?;
    Ok(VtkSeries {
        collection,
        files,
        points,
        script,
        modes,
    })
}

/// The modes of a modal results file and the configuration they are about (its last
/// record).
struct Modal<'a> {
    freq: &'a [f64],
    /// (mode, node, dof6, complex).
    shape: &'a [f64],
    x0: &'a [f64],
    q0: &'a [f64],
}

/// The scale of mode `phi` (node-major, 6 complex components per node): the largest
/// displacement amplitude a tenth of `size`, no rotation amplitude above 0.5 rad.
fn mode_scale(phi: &[f64], size: f64) -> f64 {
    let (mut t, mut r) = (0.0f64, 0.0f64);
    for (c, z) in phi.chunks(2).enumerate() {
        let a = z[0].hypot(z[1]);
        if c % 6 < 3 {
            t = t.max(a);
        } else {
            r = r.max(a);
        }
    }
    let mut s = if t > 0.0 {
        0.1 * size / t
    } else {
        f64::INFINITY
    };
    if r > 0.0 {
        s = s.min(0.5 / r);
    }
    if s.is_finite() { s } else { 0.0 }
}

/// Per mode, the shape superposed on the modal configuration over one period:
/// `x = x₀ + s Re(φ_x e^{iωt})`, `R = exp(s Re(φ_θ e^{iωt})) R₀` (φ_θ a rotation vector in
/// global components), at `t = kT/n` (`T = 1/f`; for a zero-frequency mode `t` is the
/// phase `k/n`).
fn write_modes(
    m: &Modal,
    layout: &Layout,
    dir: &Path,
    stem: &str,
    options: &VtkOptions,
) -> Result<Vec<PathBuf>, crate::Error> {
    let nn = layout.nn;
    let size = layout.size();
    let n = options.mode_frames;
    let mut out = Vec::with_capacity(m.freq.len());
    let mut x = vec![0.0; 3 * nn];
    let mut q = vec![0.0; 4 * nn];
    for (mode, &f) in m.freq.iter().enumerate() {
        let phi = &m.shape[mode * nn * 12..(mode + 1) * nn * 12];
        let s = options.mode_scale.unwrap_or_else(|| mode_scale(phi, size));
        let period = if f > 0.0 { 1.0 / f } else { 1.0 };
        let mut entries = Vec::with_capacity(n);
        for j in 0..n {
            let phase = std::f64::consts::TAU * j as f64 / n as f64;
            let (c, sn) = (phase.cos(), phase.sin());
            // s Re((a + ib)(cos + i sin)) = s (a cos − b sin).
            let re = |i: usize, d: usize| {
                let z = &phi[(i * 6 + d) * 2..(i * 6 + d) * 2 + 2];
                s * (z[0] * c - z[1] * sn)
            };
            for i in 0..nn {
                for d in 0..3 {
                    x[3 * i + d] = m.x0[3 * i + d] + re(i, d);
                }
                let theta = Vector3::new(re(i, 3), re(i, 4), re(i, 5));
                let r =
                    UnitQuaternion::from_scaled_axis(theta) * quaternion(&m.q0[4 * i..4 * i + 4]);
                q[4 * i..4 * i + 4].copy_from_slice(&[r.w, r.i, r.j, r.k]);
            }
            let frame = Frame {
                x: &x,
                q: &q,
                v: None,
                joints: None,
                sections: None,
            };
            let grid = build(layout, &frame);
            let name = format!("{stem}_mode_{:02}_{j:04}.vtu", mode + 1);
            let path = dir.join(&name);
            std::fs::write(&path, grid.to_bytes()).map_err(|e| io_err(&path, e))?;
            entries.push((period * j as f64 / n as f64, name));
        }
        let pvd = dir.join(format!("{stem}_mode_{:02}.pvd", mode + 1));
        write_pvd(&pvd, &entries)?;
        out.push(pvd);
    }
    Ok(out)
}

/// The ParaView Python script (paraview.simple, ParaView ≥ 5.10) that opens the series:
/// beams as tubes (the sections' tube coloured by the bending moment), bodies as their
/// boxes, joints as arrows along their first axis, nodes as points; the animation set to
/// the data's time steps. Modal results open the first mode's animation (another series:
/// the environment variable `SAMARA_SERIES`, e.g. `<stem>_mode_02.pvd`).
fn scene_script(stem: &str, dir: &Path, layout: &Layout, modes: &[PathBuf]) -> String {
    let size = layout.size();
    let first = modes
        .first()
        .and_then(|p| p.file_name())
        .and_then(|s| s.to_str())
        .map(str::to_string)
        .unwrap_or_else(|| format!("{stem}.pvd"));
    let abs = std::fs::canonicalize(dir).unwrap_or_else(|_| dir.to_path_buf());
    let mut s = format!(
        r#"# ParaView scene of '{stem}', written by `samara vtk`.
# Open it with:   paraview --script={stem}_scene.py     (or: pvpython {stem}_scene.py)
# Cells by `cell_kind`: 0 nodes, 1 joints, 2 bodies' centres of gravity, 3 bodies' equivalent
# boxes, 4 beams through their nodes, 5 beams through their sections (sectional forces).
import os
from paraview.simple import *

try:
    here = os.path.dirname(os.path.abspath(__file__))
except NameError:
    here = {abs:?}
series = os.environ.get("SAMARA_SERIES", {first:?})
data = PVDReader(registrationName={stem:?}, FileName=os.path.join(here, series))
view = GetActiveViewOrCreate("RenderView")


def cells(kind, name):
    t = Threshold(registrationName=name, Input=data)
    t.Scalars = ["CELLS", "cell_kind"]
    t.LowerThreshold = kind
    t.UpperThreshold = kind
    return t


nodes = cells(0, "nodes")
shown = Show(nodes, view)
shown.SetRepresentationType("Points")
shown.PointSize = 6
"#
    );
    if layout.beam_nodes.iter().any(|b| b.len() > 1) {
        let _ = write!(
            s,
            r#"
beams = Tube(registrationName="beams", Input=ExtractSurface(Input=cells(4, "beam lines")))
beams.Radius = {:e}
Show(beams, view)
"#,
            0.005 * size
        );
    }
    if modes.is_empty() && layout.beam_sections.iter().any(|b| !b.is_empty()) {
        let _ = write!(
            s,
            r#"
if series.endswith("{stem}.pvd"):
    sections = Tube(registrationName="sections", Input=ExtractSurface(Input=cells(5, "beam sections")))
    sections.Radius = {:e}
    shown = Show(sections, view)
    ColorBy(shown, ("POINTS", "beam_moment", "Magnitude"))
"#,
            0.007 * size
        );
    }
    if layout.body_box.iter().any(Option::is_some) {
        s.push_str(
            r#"
bodies = cells(3, "bodies")
shown = Show(bodies, view)
shown.Opacity = 0.6
"#,
        );
    }
    if layout.nj > 0 && modes.is_empty() {
        let _ = write!(
            s,
            r#"
joints = Glyph(registrationName="joint axes", Input=cells(1, "joints"), GlyphType="Arrow")
joints.OrientationArray = ["POINTS", "frame_x"]
joints.ScaleArray = ["POINTS", "No scale array"]
joints.ScaleFactor = {:e}
Show(joints, view)
"#,
            0.08 * size
        );
    }
    s.push_str(
        r#"
scene = GetAnimationScene()
scene.UpdateAnimationUsingDataTimeSteps()
view.ResetCamera()
Render(view)
"#,
    );
    s
}
