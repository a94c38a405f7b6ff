//! Thin-walled box and I-section with a ply layup on every wall.
//!
//! Box: outer `width` (y) × `height` (z) centred on the origin; the walls are traversed
//! counter-clockwise (bottom +y, right +z, top −y, left −z: wall angles 0°, 90°, 180°,
//! 270°), plies listed from the outer surface in. Corners are mitred (outer corner to
//! inner corner); all walls have the same number of plies, and where two walls meet, the
//! ply interfaces of both meet at the mean of their relative depths.
//!
//! I-section: flanges of `width` at the top and bottom of the overall `height`, web of its
//! layup's thickness centred on y = 0. Flange plies are listed from the outer surface
//! (top of the top flange, bottom of the bottom flange), wall angle 0° (contour +y); web
//! plies from its −y face, wall angle 90° (contour +z).

use super::{Meshing, Ply, layup_grid, layup_thickness, tolerance};
use crate::section::mesh::{ElementAttr, Mesh, MeshBuilder};
use std::f64::consts::FRAC_PI_2;

/// A thin-walled rectangular box.
#[derive(Clone, Debug, PartialEq)]
pub struct BoxSection {
    pub width: f64,
    pub height: f64,
    /// Layups of the bottom, right, top and left walls.
    pub walls: [Vec<Ply>; 4],
    /// Elements along the horizontal and the vertical walls.
    pub elements: [usize; 2],
    pub elements_per_ply: usize,
    pub meshing: Meshing,
}

/// Why a box or I-section cannot be built.
#[derive(Clone, Debug, PartialEq)]
pub enum WallError {
    /// Walls with different numbers of plies (wall index, its count, the bottom's count).
    PlyCount {
        wall: usize,
        plies: usize,
        first: usize,
    },
    /// The walls fill the section: thickness sum along y or z not below the outer size.
    TooThick {
        direction: &'static str,
        walls: f64,
        size: f64,
    },
}

impl std::fmt::Display for WallError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::PlyCount { wall, plies, first } => write!(
                f,
                "the {} wall has {plies} plies but the bottom wall has {first}: all walls of a box need the same number of plies",
                ["bottom", "right", "top", "left"][*wall]
            ),
            Self::TooThick {
                direction,
                walls,
                size,
            } => write!(
                f,
                "the walls are {walls:e} m thick together along {direction}, not less than the section's {size:e} m"
            ),
        }
    }
}

pub fn box_section(b: &BoxSection) -> Result<Mesh, WallError> {
    let kind = b.meshing.kind;
    let p = kind.order();
    let per = b.elements_per_ply.max(1);
    let first = b.walls[0].len();
    for (w, l) in b.walls.iter().enumerate() {
        if l.len() != first {
            return Err(WallError::PlyCount {
                wall: w,
                plies: l.len(),
                first,
            });
        }
    }
    let t: Vec<f64> = b.walls.iter().map(|l| layup_thickness(l)).collect();
    if t[1] + t[3] >= b.width {
        return Err(WallError::TooThick {
            direction: "y",
            walls: t[1] + t[3],
            size: b.width,
        });
    }
    if t[0] + t[2] >= b.height {
        return Err(WallError::TooThick {
            direction: "z",
            walls: t[0] + t[2],
            size: b.height,
        });
    }
    let grids: Vec<(Vec<f64>, Vec<usize>)> =
        b.walls.iter().map(|l| layup_grid(l, per, p)).collect();
    let (w2, h2) = (0.5 * b.width, 0.5 * b.height);
    // Outer start corners and directions of the walls (counter-clockwise).
    let corners = [[-w2, -h2], [w2, -h2], [w2, h2], [-w2, h2]];
    let mut builder = MeshBuilder::new(tolerance(b.width.max(b.height)));
    for w in 0..4 {
        let (prev, next) = ((w + 3) % 4, (w + 1) % 4);
        let phi = w as f64 * FRAC_PI_2;
        let d = [phi.cos(), phi.sin()];
        let nin = [-d[1], d[0]];
        let a = corners[w];
        let bb = corners[next];
        let (depth, rows) = &grids[w];
        let frac = |g: usize, j: usize| grids[g].0[j] / t[g];
        let n = b.elements[w % 2].max(1);
        let np = (n * p) as f64;
        let last = n * p;
        builder.patch(
            kind,
            n,
            rows.len(),
            |i, j| {
                let s0 = 0.5 * (frac(w, j) + frac(prev, j));
                let s1 = 0.5 * (frac(w, j) + frac(next, j));
                let start = [
                    a[0] + s0 * (t[prev] * d[0] + t[w] * nin[0]),
                    a[1] + s0 * (t[prev] * d[1] + t[w] * nin[1]),
                ];
                let end = [
                    bb[0] + s1 * (-t[next] * d[0] + t[w] * nin[0]),
                    bb[1] + s1 * (-t[next] * d[1] + t[w] * nin[1]),
                ];
                if i == 0 {
                    return start;
                }
                if i == last {
                    return end;
                }
                let u = i as f64 / np;
                let along = |q: [f64; 2]| q[0] * d[0] + q[1] * d[1];
                let s = (1.0 - u) * along(start) + u * along(end);
                let nrm = a[0] * nin[0] + a[1] * nin[1] + depth[j];
                [s * d[0] + nrm * nin[0], s * d[1] + nrm * nin[1]]
            },
            |_, cj| {
                let ply = &b.walls[w][rows[cj]];
                ElementAttr {
                    material: ply.material,
                    ply_angle: ply.angle,
                    wall_angle: phi,
                }
            },
        );
    }
    Ok(builder.finish())
}

/// An I-section (see the module doc).
#[derive(Clone, Debug, PartialEq)]
pub struct ISection {
    pub width: f64,
    pub height: f64,
    pub top: Vec<Ply>,
    pub bottom: Vec<Ply>,
    pub web: Vec<Ply>,
    /// Elements along each flange overhang and along the web.
    pub elements: [usize; 2],
    pub elements_per_ply: usize,
    pub meshing: Meshing,
}

pub fn i_section(s: &ISection) -> Result<Mesh, WallError> {
    let kind = s.meshing.kind;
    let p = kind.order();
    let per = s.elements_per_ply.max(1);
    let (tt, tb, tw) = (
        layup_thickness(&s.top),
        layup_thickness(&s.bottom),
        layup_thickness(&s.web),
    );
    if tw >= s.width {
        return Err(WallError::TooThick {
            direction: "y",
            walls: tw,
            size: s.width,
        });
    }
    if tt + tb >= s.height {
        return Err(WallError::TooThick {
            direction: "z",
            walls: tt + tb,
            size: s.height,
        });
    }
    let (w2, h2) = (0.5 * s.width, 0.5 * s.height);
    let (web_depth, web_rows) = layup_grid(&s.web, per, p);
    let web_y: Vec<f64> = web_depth.iter().map(|d| -0.5 * tw + d).collect();
    let [nf, nw] = [s.elements[0].max(1), s.elements[1].max(1)];
    let uniform = |a: f64, b: f64, n: usize| -> Vec<f64> {
        (0..=n * p)
            .map(|i| a + (b - a) * i as f64 / (n * p) as f64)
            .collect()
    };
    let mut builder = MeshBuilder::new(tolerance(s.width.max(s.height)));
    // Flanges: three blocks along y each.
    for (plies, top) in [(&s.top, true), (&s.bottom, false)] {
        let (depth, rows) = layup_grid(plies, per, p);
        let zs: Vec<f64> = if top {
            depth.iter().rev().map(|d| h2 - d).collect()
        } else {
            depth.iter().map(|d| -h2 + d).collect()
        };
        let n_rows = rows.len();
        let ply_of = |cj: usize| if top { rows[n_rows - 1 - cj] } else { rows[cj] };
        for ys in [
            uniform(-w2, -0.5 * tw, nf),
            web_y.clone(),
            uniform(0.5 * tw, w2, nf),
        ] {
            tensor_patch(&mut builder, kind, &ys, &zs, |_, cj| {
                let ply = &plies[ply_of(cj)];
                ElementAttr {
                    material: ply.material,
                    ply_angle: ply.angle,
                    wall_angle: 0.0,
                }
            });
        }
    }
    let zs = uniform(-h2 + tb, h2 - tt, nw);
    tensor_patch(&mut builder, kind, &web_y, &zs, |ci, _| {
        let ply = &s.web[web_rows[ci]];
        ElementAttr {
            material: ply.material,
            ply_angle: ply.angle,
            wall_angle: FRAC_PI_2,
        }
    });
    Ok(builder.finish())
}

/// A patch on the tensor grid `ys × zs` (fine-grid coordinates, `n·order + 1` each).
fn tensor_patch(
    b: &mut MeshBuilder,
    kind: crate::section::element::ElementKind,
    ys: &[f64],
    zs: &[f64],
    attr: impl Fn(usize, usize) -> ElementAttr,
) {
    let p = kind.order();
    b.patch(
        kind,
        (ys.len() - 1) / p,
        (zs.len() - 1) / p,
        |i, j| [ys[i], zs[j]],
        attr,
    );
}
