//! `samara vtk`: binary VTU files read back with an independent reader (vtkio), beams as
//! polylines through their nodes with section frames and sectional forces, bodies as
//! their equivalent boxes, joints with their axes, the ParaView script, and the mode
//! animations of a modal results file (issue #13, verification 3).

use samara::output::ResultsReader;
use std::path::{Path, PathBuf};
use vtkio::model::{Attribute, CellType, DataSet, IOBuffer, Piece, UnstructuredGridPiece};

use crate::common;
use common::*;

/// The blade spin-up example (examples/blade_spinup.toml) cut to 0.04 s: a hub body on a
/// revolute joint and a 13-node beam.
fn blade_results() -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(root().join("examples/blade_spinup.toml")).unwrap();
    assert!(text.contains("t_end = 4.0"));
    let text = text.replace("t_end = 4.0", "t_end = 0.04");
    let model = dir.path().join("blade.toml");
    std::fs::write(&model, text).unwrap();
    let out = dir.path().join("out");
    let o = samara(&[
        "run",
        model.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "-q",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    (dir, out.join("spinup.nc"))
}

fn piece(path: &Path) -> UnstructuredGridPiece {
    let vtk = vtkio::Vtk::import(path).expect("a valid binary .vtu");
    let DataSet::UnstructuredGrid { mut pieces, .. } = vtk.data else {
        panic!("not an unstructured grid")
    };
    match pieces.remove(0) {
        Piece::Inline(p) => *p,
        _ => panic!("piece not inline"),
    }
}

fn f64s(b: &IOBuffer) -> Vec<f64> {
    match b {
        IOBuffer::F64(v) => v.clone(),
        IOBuffer::I32(v) => v.iter().map(|&x| x as f64).collect(),
        other => panic!("unexpected buffer {other:?}"),
    }
}

fn array(attrs: &[Attribute], name: &str) -> Vec<f64> {
    for a in attrs {
        if let Attribute::DataArray(d) = a
            && d.name == name
        {
            return f64s(&d.data);
        }
    }
    panic!("no array {name}")
}

/// The cells as (type, point ids).
fn cells(p: &UnstructuredGridPiece) -> Vec<(CellType, Vec<usize>)> {
    let (conn, offsets) = p.cells.cell_verts.clone().into_xml();
    let mut start = 0usize;
    offsets
        .iter()
        .zip(&p.cells.types)
        .map(|(&end, &t)| {
            let ids = conn[start..end as usize]
                .iter()
                .map(|&i| i as usize)
                .collect();
            start = end as usize;
            (t, ids)
        })
        .collect()
}

#[test]
fn blade_scene_reads_back_with_polylines_boxes_and_joint_axes() {
    let (dir, results) = blade_results();
    let out = dir.path().join("vtk");
    let o = samara(&[
        "vtk",
        results.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("paraview --script="));
    let mut r = ResultsReader::open(&results).unwrap();
    let n_records = r.records;
    let pvd = std::fs::read_to_string(out.join("spinup.pvd")).unwrap();
    assert_eq!(pvd.matches("<DataSet ").count(), n_records);
    let nn = r.node_names.len();
    let ns = r.section_names.len();
    let beam_nodes: Vec<usize> = r
        .read("beam_node_index")
        .unwrap()
        .iter()
        .map(|&i| i as usize)
        .collect();
    // order 6, 2 elements: 13 nodes root (the hub) to tip, the shared one once.
    assert_eq!(beam_nodes.len(), 13);
    assert_eq!(
        beam_nodes[0],
        r.node_names.iter().position(|n| n == "hub").unwrap()
    );
    let x = r.read("position").unwrap();
    let sx = r.read("section_position").unwrap();
    let sm = r.read("beam_moment").unwrap();
    let axes = r.read("joint_axes").unwrap();
    for k in [0, n_records - 1] {
        let p = piece(&out.join(format!("spinup_{k:06}.vtu")));
        let pts = f64s(&p.points);
        let cs = cells(&p);
        let kind = array(&p.data.cell, "cell_kind");
        assert_eq!(kind.len(), cs.len());
        // Nodes, the joint, the body's CG, its box, the beam twice.
        assert_eq!(cs.len(), nn + 1 + 1 + 1 + 2);
        let of = |want: f64| -> Vec<&(CellType, Vec<usize>)> {
            cs.iter()
                .zip(&kind)
                .filter(|(_, k)| **k == want)
                .map(|(c, _)| c)
                .collect()
        };
        // The beam's polyline points are its nodes' positions, bit for bit.
        let line = of(4.0);
        assert_eq!(line.len(), 1);
        assert_eq!(line[0].0, CellType::PolyLine);
        assert_eq!(line[0].1.len(), 13);
        for (&id, &node) in line[0].1.iter().zip(&beam_nodes) {
            for c in 0..3 {
                assert_eq!(
                    pts[3 * id + c].to_bits(),
                    x[(k * nn + node) * 3 + c].to_bits()
                );
            }
        }
        // The sections' polyline carries the sectional moments of the results file.
        let sections = of(5.0);
        assert_eq!(sections[0].1.len(), ns);
        let moment = array(&p.data.point, "beam_moment");
        for (s, &id) in sections[0].1.iter().enumerate() {
            for c in 0..3 {
                assert_eq!(pts[3 * id + c], sx[(k * ns + s) * 3 + c]);
                assert_eq!(moment[3 * id + c], sm[(k * ns + s) * 3 + c]);
            }
        }
        // The hub's box: inertia diag(10, 10, 10) kg m², 50 kg → sides √(6·10/50) m.
        let hex = of(3.0);
        assert_eq!(hex[0].0, CellType::Hexahedron);
        let corner = |i: usize| {
            let id = hex[0].1[i];
            [pts[3 * id], pts[3 * id + 1], pts[3 * id + 2]]
        };
        let dist = |a: [f64; 3], b: [f64; 3]| {
            ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
        };
        let side = (6.0f64 * 10.0 / 50.0).sqrt();
        for (a, b) in [(0, 1), (1, 2), (0, 4), (3, 7)] {
            assert!(
                (dist(corner(a), corner(b)) - side).abs() < 1e-12,
                "box edge {a}-{b}"
            );
        }
        // The joint's axes as point data.
        let joint = of(1.0)[0].1[0];
        for (e, name) in ["frame_x", "frame_y", "frame_z"].iter().enumerate() {
            let f = array(&p.data.point, name);
            for c in 0..3 {
                assert_eq!(f[3 * joint + c], axes[(k * 3 + e) * 3 + c], "{name}");
            }
        }
        // Section frames at the beam nodes: at t = 0 the straight blade's axis is x.
        if k == 0 {
            let fx = array(&p.data.point, "frame_x");
            for &id in &line[0].1 {
                assert!((fx[3 * id] - 1.0).abs() < 1e-12 && fx[3 * id + 1].abs() < 1e-12);
            }
        }
    }
    // The ParaView script names the series and the arrays the files have.
    let script = std::fs::read_to_string(out.join("spinup_scene.py")).unwrap();
    for want in [
        "spinup.pvd",
        "cell_kind",
        "beam_moment",
        "frame_x",
        "Tube",
        "Glyph",
    ] {
        assert!(script.contains(want), "{want} missing from the script");
    }
}

#[test]
fn modal_results_get_one_animated_series_per_mode() {
    let dir = tempfile::tempdir().unwrap();
    let model = root().join("examples/verification/cantilever_modal.toml");
    let o = samara(&[
        "run",
        model.to_str().unwrap(),
        "--out",
        dir.path().to_str().unwrap(),
        "-q",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let results = dir.path().join("modes.nc");
    let out = dir.path().join("vtk");
    let scale = 0.01;
    let o = samara(&[
        "vtk",
        results.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--mode-scale",
        "0.01",
        "--mode-frames",
        "8",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut r = ResultsReader::open(&results).unwrap();
    let nn = r.node_names.len();
    let freq = r.read("frequency").unwrap();
    let shape = r.read("mode_shape").unwrap();
    let x0 = r.read("position").unwrap();
    let q0 = r.read("orientation").unwrap();
    let k = r.records - 1;
    for (m, &f) in freq.iter().enumerate() {
        let pvd =
            std::fs::read_to_string(out.join(format!("modes_mode_{:02}.pvd", m + 1))).unwrap();
        assert_eq!(pvd.matches("<DataSet ").count(), 8, "mode {}", m + 1);
        // Times over one period: t_j = j T / 8.
        let times: Vec<f64> = pvd
            .split("timestep=\"")
            .skip(1)
            .map(|s| s.split('"').next().unwrap().parse().unwrap())
            .collect();
        for (j, t) in times.iter().enumerate() {
            let want = j as f64 / (8.0 * f);
            assert!((t - want).abs() <= 1e-14 * want.max(1.0), "{times:?}");
        }
        // Phase 0 and a half period: x₀ ± s Re φ at every node.
        for (j, sign) in [(0, 1.0), (4, -1.0)] {
            let p = piece(&out.join(format!("modes_mode_{:02}_{j:04}.vtu", m + 1)));
            let pts = f64s(&p.points);
            for i in 0..nn {
                for c in 0..3 {
                    let re = shape[((m * nn + i) * 6 + c) * 2];
                    let want = x0[(k * nn + i) * 3 + c] + sign * scale * re;
                    assert!(
                        (pts[3 * i + c] - want).abs() < 1e-14,
                        "mode {} frame {j} node {i}",
                        m + 1
                    );
                }
            }
        }
    }
    // The torsion mode (0.25 Hz): the node of largest rotation turns by s·1 rad at phase 0.
    let m = freq.iter().position(|f| (f - 0.25).abs() < 1e-9).unwrap();
    let p = piece(&out.join(format!("modes_mode_{:02}_0000.vtu", m + 1)));
    let fy = array(&p.data.point, "frame_y");
    let mut largest = 0.0f64;
    for i in 0..nn {
        let q = &q0[(k * nn + i) * 4..(k * nn + i) * 4 + 4];
        let r0 = nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
            q[0], q[1], q[2], q[3],
        ));
        let y0 = r0 * nalgebra::Vector3::y();
        let y = nalgebra::Vector3::new(fy[3 * i], fy[3 * i + 1], fy[3 * i + 2]);
        largest = largest.max(y0.angle(&y));
    }
    assert!((largest - scale).abs() < 1e-9, "{largest}");
    // Bad options are clear errors.
    let o = samara(&[
        "vtk",
        results.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--mode-frames",
        "1",
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("at least 2 frames"), "{}", stderr(&o));
}
