//! Solid rectangle and circle, and the circular tube with a layup.

use super::{Meshing, Ply, layup_grid, tolerance};
use crate::section::mesh::{ElementAttr, Mesh, MeshBuilder};
use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

/// A solid rectangle centred on the origin: `width` along y, `height` along z.
#[derive(Clone, Debug, PartialEq)]
pub struct Rectangle {
    pub width: f64,
    pub height: f64,
    pub material: usize,
    /// Fibre angle from x towards y [rad].
    pub ply_angle: f64,
    /// Elements along y and z.
    pub divisions: [usize; 2],
    pub meshing: Meshing,
}

pub fn rectangle(r: &Rectangle) -> Mesh {
    let kind = r.meshing.kind;
    let p = kind.order();
    let [ny, nz] = r.divisions;
    let mut b = MeshBuilder::new(tolerance(r.width.max(r.height)));
    let (hy, hz) = (r.width / (ny * p) as f64, r.height / (nz * p) as f64);
    let attr = ElementAttr {
        material: r.material,
        ply_angle: r.ply_angle,
        wall_angle: 0.0,
    };
    b.patch(
        kind,
        ny,
        nz,
        |i, j| {
            [
                -0.5 * r.width + i as f64 * hy,
                -0.5 * r.height + j as f64 * hz,
            ]
        },
        |_, _| attr,
    );
    b.finish()
}

/// A solid circle centred on the origin: a square core of `elements × elements` and four
/// blended patches out to the circle (nodes on the boundary lie on the exact circle).
#[derive(Clone, Debug, PartialEq)]
pub struct Circle {
    pub radius: f64,
    pub material: usize,
    pub ply_angle: f64,
    /// Elements along a quarter of the circumference (and across the core).
    pub elements: usize,
    pub meshing: Meshing,
}

pub fn circle(c: &Circle) -> Mesh {
    let kind = c.meshing.kind;
    let p = kind.order();
    let n = c.elements.max(1);
    let m = ((n as f64 / 3.0).round() as usize).max(1);
    let a = 0.5 * c.radius;
    let mut b = MeshBuilder::new(tolerance(c.radius));
    let attr = ElementAttr {
        material: c.material,
        ply_angle: c.ply_angle,
        wall_angle: 0.0,
    };
    let np = (n * p) as f64;
    b.patch(
        kind,
        n,
        n,
        |i, j| [-a + 2.0 * a * i as f64 / np, -a + 2.0 * a * j as f64 / np],
        |_, _| attr,
    );
    let mp = (m * p) as f64;
    for side in 0..4 {
        let rot = side as f64 * FRAC_PI_2;
        let (s, co) = rot.sin_cos();
        b.patch(
            kind,
            n,
            m,
            |i, j| {
                let u = i as f64 / np;
                let v = j as f64 / mp;
                // The right-hand patch, turned by `rot`.
                let inner = [a, -a + 2.0 * a * u];
                let th = -FRAC_PI_4 + FRAC_PI_2 * u;
                let outer = [c.radius * th.cos(), c.radius * th.sin()];
                let q = [
                    (1.0 - v) * inner[0] + v * outer[0],
                    (1.0 - v) * inner[1] + v * outer[1],
                ];
                [co * q[0] - s * q[1], s * q[0] + co * q[1]]
            },
            |_, _| attr,
        );
    }
    b.finish()
}

/// A circular tube centred on the origin: outer radius, plies from the outer surface in.
/// The wall's contour direction runs counter-clockwise.
#[derive(Clone, Debug, PartialEq)]
pub struct Tube {
    pub outer_radius: f64,
    pub plies: Vec<Ply>,
    /// Elements around the circumference and through each ply.
    pub elements_around: usize,
    pub elements_per_ply: usize,
    pub meshing: Meshing,
}

pub fn tube(t: &Tube) -> Mesh {
    let kind = t.meshing.kind;
    let p = kind.order();
    let n = t.elements_around.max(3);
    let (depth, rows) = layup_grid(&t.plies, t.elements_per_ply.max(1), p);
    let mut b = MeshBuilder::new(tolerance(t.outer_radius));
    let np = (n * p) as f64;
    b.patch(
        kind,
        n,
        rows.len(),
        |i, j| {
            let th = 2.0 * PI * i as f64 / np;
            let r = t.outer_radius - depth[j];
            [r * th.cos(), r * th.sin()]
        },
        |ci, cj| {
            let ply = &t.plies[rows[cj]];
            let th = 2.0 * PI * (ci as f64 + 0.5) / n as f64;
            ElementAttr {
                material: ply.material,
                ply_angle: ply.angle,
                wall_angle: th + FRAC_PI_2,
            }
        },
    );
    b.finish()
}
