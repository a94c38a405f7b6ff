use samara::section::element::ElementKind;
use samara::section::generators::*;
use samara::section::material::{Material, Orthotropic};
use samara::section::*;

fn naca(m: f64, p: f64, t: f64, n: usize, closed: bool) -> Vec<[f64; 2]> {
    let a4 = if closed { -0.1036 } else { -0.1015 };
    let mut up = Vec::new();
    let mut lo = Vec::new();
    for i in 0..=n {
        let beta = std::f64::consts::PI * i as f64 / n as f64;
        let x = 0.5 * (1.0 - beta.cos());
        let yt = 5.0
            * t
            * (0.2969 * x.sqrt() - 0.1260 * x - 0.3516 * x * x
                + 0.2843 * x.powi(3)
                + a4 * x.powi(4));
        let (yc, dyc) = if m == 0.0 {
            (0.0, 0.0)
        } else if x < p {
            (
                m / (p * p) * (2.0 * p * x - x * x),
                2.0 * m / (p * p) * (p - x),
            )
        } else {
            (
                m / ((1.0 - p).powi(2)) * ((1.0 - 2.0 * p) + 2.0 * p * x - x * x),
                2.0 * m / ((1.0 - p).powi(2)) * (p - x),
            )
        };
        let th = dyc.atan();
        up.push([x - yt * th.sin(), yc + yt * th.cos()]);
        lo.push([x + yt * th.sin(), yc - yt * th.cos()]);
    }
    let mut pts: Vec<[f64; 2]> = up.iter().rev().copied().collect();
    pts.extend(lo.iter().skip(1).copied());
    pts
}

#[test]
fn scratch() {
    let glass = Material::orthotropic(
        "glass",
        &Orthotropic {
            e1: 41.8e9,
            e2: 14.0e9,
            e3: 14.0e9,
            g12: 2.63e9,
            g13: 2.63e9,
            g23: 2.63e9,
            nu12: 0.28,
            nu13: 0.28,
            nu23: 0.28,
        },
        1915.0,
    )
    .unwrap();
    let foam = Material::isotropic("foam", 256e6, 0.3, 200.0).unwrap();
    for (closed, around, per) in [(true, 120usize, 1usize), (false, 120, 1), (true, 1500, 3)] {
        let skin = vec![
            Ply {
                material: 0,
                thickness: 0.002,
                angle: 45f64.to_radians(),
            },
            Ply {
                material: 0,
                thickness: 0.002,
                angle: -45f64.to_radians(),
            },
        ];
        let cap = vec![
            Ply {
                material: 0,
                thickness: 0.004,
                angle: 0.0
            };
            4
        ];
        let web = vec![
            Ply {
                material: 0,
                thickness: 0.002,
                angle: 45f64.to_radians(),
            },
            Ply {
                material: 1,
                thickness: 0.01,
                angle: 0.0,
            },
            Ply {
                material: 0,
                thickness: 0.002,
                angle: -45f64.to_radians(),
            },
        ];
        let af = Airfoil {
            coordinates: naca(0.02, 0.4, 0.18, 100, closed),
            chord: 1.0,
            reference: [0.25, 0.0],
            blunt_trailing_edge: !closed,
            skin,
            caps: vec![SparCap {
                surface: Surface::Both,
                from: 0.2,
                to: 0.5,
                plies: cap,
            }],
            webs: vec![
                Web {
                    at: 0.2,
                    plies: web.clone(),
                    elements: 0,
                },
                Web {
                    at: 0.5,
                    plies: web,
                    elements: 0,
                },
            ],
            fill: None,
            elements_around: around,
            elements_per_ply: per,
            meshing: Meshing {
                kind: ElementKind::Quad8,
            },
        };
        let t = std::time::Instant::now();
        let (mesh, notes) = match airfoil(&af) {
            Ok(x) => x,
            Err(e) => {
                println!("ERR {e}");
                continue;
            }
        };
        let tm = t.elapsed();
        let m = SectionModel::new(mesh, vec![glass.clone(), foam.clone()]).unwrap();
        let r = analyze(&m).unwrap();
        println!(
            "closed {closed} elements {} nodes {} mesh {:?} total {:?} notes {:?}",
            m.mesh.elements.len(),
            m.mesh.nodes.len(),
            tm,
            t.elapsed(),
            notes
        );
        println!("resid {:.2e} {:?}", r.warping.residual, r.properties);
        println!("{:.4e}", r.stiffness);
    }
}
