//! ParaView time series from a results file: one VTK XML UnstructuredGrid (`.vtu`) per
//! output time and a `.pvd` collection that indexes them by time.
//!
//! Points are the nodes, then the joints, then the bodies' centres of gravity (as vertex
//! cells). Point data: `kind` (0 node, 1 joint, 2 body), `index` (within its kind),
//! `frame_x`/`frame_y`/`frame_z` (node frame, joint frame A, or the body's node frame;
//! global components — glyph them to see orientations), `velocity`, `angular_velocity`
//! (nodes and bodies' CGs; zero on joints), `joint_force`, `joint_moment` (joints,
//! **global** components; zero elsewhere), `mass` (bodies; zero elsewhere).

use super::reader::{ReadError, ResultsReader};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// What [`write_vtk`] wrote.
pub struct VtkSeries {
    pub collection: PathBuf,
    pub files: Vec<PathBuf>,
    pub points: usize,
}

fn io_err(path: &Path, e: std::io::Error) -> crate::Error {
    crate::Error::Io {
        path: path.to_path_buf(),
        action: "write",
        source: e,
    }
}

fn data_array(out: &mut String, name: &str, comps: usize, values: impl Iterator<Item = f64>) {
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

/// Writes `<dir>/<stem>.pvd` and `<dir>/<stem>_NNNNNN.vtu`, creating `dir`. These are
/// derived files: an earlier series of the same stem in `dir` is replaced (the results
/// file itself is only read).
pub fn write_vtk(reader: &mut ResultsReader, dir: &Path) -> Result<VtkSeries, crate::Error> {
    let source = reader.path().to_path_buf();
    let rd = |e: ReadError| crate::Error::Output {
        path: source.clone(),
        message: e.to_string(),
    };
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
    let time = reader.time().map_err(rd)?;
    let nn = reader.node_names.len();
    let nj = reader.joint_names.len();
    let pos = reader.read("position").map_err(rd)?;
    let quat = reader.read("orientation").map_err(rd)?;
    let vel = reader.read("velocity").map_err(rd)?;
    let omega = reader.read("angular_velocity").map_err(rd)?;
    let (jpos, jaxes, jf, jm) = if nj > 0 {
        (
            reader.read("joint_position").map_err(rd)?,
            reader.read("joint_axes").map_err(rd)?,
            reader.read("joint_force").map_err(rd)?,
            reader.read("joint_moment").map_err(rd)?,
        )
    } else {
        Default::default()
    };
    let nb = reader.body_names.len();
    let (body_node, body_off, body_mass) = if nb > 0 {
        (
            reader.read("body_node").map_err(rd)?,
            reader.read("body_cg_offset").map_err(rd)?,
            reader.read("body_mass").map_err(rd)?,
        )
    } else {
        Default::default()
    };
    let np = nn + nj + nb;
    let mut files = Vec::with_capacity(time.len());
    let mut pvd = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n",
    );
    let mut out = String::new();
    for (k, t) in time.iter().enumerate() {
        // Node frames from the quaternions; joint frames from the stored axes.
        let mut frames = vec![[[0.0f64; 3]; 3]; np];
        for i in 0..nn {
            let q = &quat[(k * nn + i) * 4..(k * nn + i) * 4 + 4];
            let r = nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
                q[0], q[1], q[2], q[3],
            ))
            .to_rotation_matrix()
            .into_inner();
            for e in 0..3 {
                for c in 0..3 {
                    frames[i][e][c] = r[(c, e)];
                }
            }
        }
        for j in 0..nj {
            for e in 0..3 {
                for c in 0..3 {
                    frames[nn + j][e][c] = jaxes[((k * nj + j) * 3 + e) * 3 + c];
                }
            }
        }
        // Bodies: CG = x + R c, frame of their node, CG velocity v + ω × R c.
        let mut body_pts = Vec::with_capacity(3 * nb);
        let mut body_vel = Vec::with_capacity(3 * nb);
        let mut body_omega = Vec::with_capacity(3 * nb);
        for b in 0..nb {
            let i = body_node[b] as usize;
            let f = frames[i];
            let c = &body_off[3 * b..3 * b + 3];
            let rc = [0, 1, 2].map(|r| f[0][r] * c[0] + f[1][r] * c[1] + f[2][r] * c[2]);
            let x = &pos[(k * nn + i) * 3..(k * nn + i) * 3 + 3];
            let v = &vel[(k * nn + i) * 3..(k * nn + i) * 3 + 3];
            let w = &omega[(k * nn + i) * 3..(k * nn + i) * 3 + 3];
            let wxrc = [
                w[1] * rc[2] - w[2] * rc[1],
                w[2] * rc[0] - w[0] * rc[2],
                w[0] * rc[1] - w[1] * rc[0],
            ];
            body_pts.extend((0..3).map(|r| x[r] + rc[r]));
            body_vel.extend((0..3).map(|r| v[r] + wxrc[r]));
            body_omega.extend_from_slice(w);
            frames[nn + nj + b] = f;
        }
        // Reactions to global components: F = Σ_e F_e a_e.
        let global = |v: &[f64], j: usize| -> [f64; 3] {
            let a = &frames[nn + j];
            let c = &v[(k * nj + j) * 3..(k * nj + j) * 3 + 3];
            [0, 1, 2].map(|i| a[0][i] * c[0] + a[1][i] * c[1] + a[2][i] * c[2])
        };
        out.clear();
        let _ = write!(
            out,
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <UnstructuredGrid>\n    <Piece NumberOfPoints=\"{np}\" NumberOfCells=\"{np}\">\n      <Points>\n"
        );
        let points = (0..nn)
            .flat_map(|i| pos[(k * nn + i) * 3..(k * nn + i) * 3 + 3].to_vec())
            .chain((0..nj).flat_map(|j| jpos[(k * nj + j) * 3..(k * nj + j) * 3 + 3].to_vec()))
            .chain(body_pts.iter().copied());
        data_array(&mut out, "Points", 3, points);
        out.push_str("      </Points>\n      <Cells>\n");
        let ints = |out: &mut String, name: &str, v: &mut dyn Iterator<Item = usize>| {
            let _ = write!(
                out,
                "        <DataArray type=\"Int64\" Name=\"{name}\" format=\"ascii\">\n          "
            );
            let s: Vec<String> = v.map(|x| x.to_string()).collect();
            out.push_str(&s.join(" "));
            out.push_str("\n        </DataArray>\n");
        };
        ints(&mut out, "connectivity", &mut (0..np));
        ints(&mut out, "offsets", &mut (1..=np));
        out.push_str(
            "        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n          ",
        );
        out.push_str(&vec!["1"; np].join(" "));
        out.push_str(
            "\n        </DataArray>\n      </Cells>\n      <PointData Vectors=\"frame_x\">\n",
        );
        let kind = |p: usize| {
            if p < nn {
                0
            } else if p < nn + nj {
                1
            } else {
                2
            }
        };
        data_array(&mut out, "kind", 1, (0..np).map(|p| kind(p) as f64));
        let first = [0, nn, nn + nj];
        data_array(
            &mut out,
            "index",
            1,
            (0..np).map(|p| (p - first[kind(p)]) as f64),
        );
        for (e, name) in ["frame_x", "frame_y", "frame_z"].iter().enumerate() {
            data_array(&mut out, name, 3, frames.iter().flat_map(|f| f[e]));
        }
        let node_vec = |v: &[f64], bodies: &[f64]| -> Vec<f64> {
            let mut o = v[k * nn * 3..(k + 1) * nn * 3].to_vec();
            o.resize((nn + nj) * 3, 0.0);
            o.extend_from_slice(bodies);
            o
        };
        data_array(
            &mut out,
            "velocity",
            3,
            node_vec(&vel, &body_vel).into_iter(),
        );
        data_array(
            &mut out,
            "angular_velocity",
            3,
            node_vec(&omega, &body_omega).into_iter(),
        );
        let mass = (0..np).map(|p| {
            if p >= nn + nj {
                body_mass[p - nn - nj]
            } else {
                0.0
            }
        });
        data_array(&mut out, "mass", 1, mass);
        let joint_vec = |v: &[f64]| -> Vec<f64> {
            let mut o = vec![0.0; nn * 3];
            for j in 0..nj {
                o.extend(global(v, j));
            }
            o.resize(np * 3, 0.0);
            o
        };
        if nj > 0 {
            data_array(&mut out, "joint_force", 3, joint_vec(&jf).into_iter());
            data_array(&mut out, "joint_moment", 3, joint_vec(&jm).into_iter());
        }
        out.push_str("      </PointData>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n");
        let name = format!("{stem}_{k:06}.vtu");
        let path = dir.join(&name);
        std::fs::write(&path, &out).map_err(|e| io_err(&path, e))?;
        let _ = writeln!(
            pvd,
            "    <DataSet timestep=\"{t:e}\" group=\"\" part=\"0\" file=\"{name}\"/>"
        );
        files.push(path);
    }
    pvd.push_str("  </Collection>\n</VTKFile>\n");
    let collection = dir.join(format!("{stem}.pvd"));
    std::fs::write(&collection, pvd).map_err(|e| io_err(&collection, e))?;
    Ok(VtkSeries {
        collection,
        files,
        points: np,
    })
}
