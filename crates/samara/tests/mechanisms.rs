//! Issue #3, verifications 1–4 and the consistent initial conditions: driven mechanisms
//! against their closed forms, an over-constrained four-bar, the Bricard linkage, a
//! screw, and the initial assembly.

use crate::common;
use common::*;
use samara::model::{AnalysisKind, Model};
use samara::system::System;
use std::f64::consts::PI;

/// Index of a joint coordinate by name.
fn coord(m: &Model, name: &str) -> usize {
    let sys = System::new(m);
    sys.coordinate_names
        .iter()
        .position(|n| n == name)
        .unwrap_or_else(|| panic!("no coordinate {name} in {:?}", sys.coordinate_names))
}

/// Slider-crank, crank driven at ω = 2π rad/s: piston position, velocity and acceleration
/// over a full turn against x = r cos θ + √(l² − r² sin² θ) and its derivatives.
///
/// Positions are fixed by the constraints (error at the Newton tolerance, 1e-10 here);
/// velocities and accelerations come from generalized-α, second-order accurate from
/// consistent initial conditions: the errors must fall by ~4 when h halves.
#[test]
fn slider_crank_piston_follows_the_closed_form() {
    let exact = common::slider_crank_piston;
    let base = model_file("examples/slider_crank.toml");
    // The slide's coordinate has nothing attached: it is passive, solved after each step
    // from its defining equation; it must agree with the piston node to round-off.
    let slide = coord(&base, "cylinder.d3");
    assert!(System::new(&base).n_passive > 0);
    let mut errs = Vec::new();
    for h in [4e-3, 2e-3, 1e-3] {
        let mut m = with_step(base.clone(), h);
        if let AnalysisKind::Dynamic(d) = &mut m.analyses[0].kind {
            d.solver.tolerance = 1e-10;
        }
        let (s, hist) = run(&m);
        assert!(
            s.max_constraint_violation < 1e-10,
            "{}",
            s.max_constraint_violation
        );
        let mut e = [0.0f64; 3];
        for f in &hist.frames {
            let p = &f.state.nodes[2];
            let ex = exact(f.time);
            e[0] = e[0].max((p.x.x - ex[0]).abs());
            e[1] = e[1].max((p.v.x - ex[1]).abs());
            e[2] = e[2].max((p.a.x - ex[2]).abs());
            // The piston stays on its axis.
            assert!(p.x.y.abs() < 1e-10 && p.x.z.abs() < 1e-10);
            let d = f.state.coords[slide];
            assert!((d.q - (p.x.x - 0.4)).abs() < 1e-12 && (d.v - p.v.x).abs() < 1e-10);
            assert!((d.a - p.a.x).abs() < 1e-8 * (1.0 + p.a.x.abs()));
        }
        println!(
            "h = {h}: max error x {:.2e} m, v {:.2e} m/s, a {:.2e} m/s²",
            e[0], e[1], e[2]
        );
        errs.push(e);
    }
    for e in &errs {
        assert!(e[0] < 1e-9, "position error {}", e[0]);
    }
    // Peak piston speed ≈ 0.66 m/s, acceleration ≈ 5.3 m/s²: relative errors at h = 1 ms.
    assert!(errs[2][1] < 2e-4 && errs[2][2] < 5e-3, "{:?}", errs[2]);
    for k in [1, 2] {
        let ov = orders(&[errs[0][k], errs[1][k], errs[2][k]]);
        assert!(
            ov.iter().all(|o| (o - 2.0).abs() < 0.3),
            "orders {k}: {ov:?}"
        );
    }
}

/// Freudenstein's equation K₁ cos θ4 − K₂ cos θ2 + K₃ = cos(θ2 − θ4) solved for the rocker
/// angle θ4 of the open branch.
fn freudenstein(th2: f64) -> f64 {
    let (a, b, c, d) = (0.2f64, 0.5f64, 0.4f64, 0.6f64);
    let k1 = d / a;
    let k2 = d / c;
    let k3 = (a * a - b * b + c * c + d * d) / (2.0 * a * c);
    let aa = th2.cos() - k1 - k2 * th2.cos() + k3;
    let bb = -2.0 * th2.sin();
    let cc = k1 - (k2 + 1.0) * th2.cos() + k3;
    2.0 * ((-bb - (bb * bb - 4.0 * aa * cc).sqrt()) / (2.0 * aa)).atan()
}

/// The non-redundant variant of `examples/four_bar.toml`: revolute – spherical –
/// universal – revolute (5 + 3 + 4 + 5 = 17 equations, one degree of freedom).
fn four_bar_rsur() -> Model {
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/four_bar.toml"),
    )
    .unwrap();
    let text = text.replacen(
        "name = \"crank_coupler\"\ntype = \"revolute\"",
        "name = \"crank_coupler\"\ntype = \"spherical\"",
        1,
    );
    // Cardan joint at B: shaft along the rocker, cross arm on the coupler along z.
    let text = text.replacen(
        "name = \"coupler_rocker\"\ntype = \"revolute\"\nnode_a = \"coupler\"\nnode_b = \"rocker\"\nposition = [0.467468745116, 0.377406235347, 0]\naxis = [0.0, 0.0, 1.0]",
        "name = \"coupler_rocker\"\ntype = \"universal\"\nnode_a = \"coupler\"\nnode_b = \"rocker\"\nposition = [0.467468745116, 0.377406235347, 0]\naxis = [0.33132811, -0.94350390, 0.0]\naxis_1 = [0.0, 0.0, 1.0]",
        1,
    );
    assert!(text.contains("\"universal\"") && text.contains("\"spherical\""));
    model(&text)
}

/// Four-bar with a driven crank: the rocker angle follows Freudenstein's closed form, for
/// the over-constrained version (four spatial revolutes, 3 redundant equations) and the
/// non-redundant R-S-U-R version alike; both move the same and need the same crank torque.
#[test]
fn four_bar_rocker_follows_freudenstein_with_and_without_redundant_joints() {
    let th4_0 = freudenstein(PI / 2.0);
    let redundant = model_file("examples/four_bar.toml");
    let sys = System::new(&redundant);
    let dropped: usize = sys.loops.iter().map(|l| l.dropped.len()).sum();
    assert_eq!(
        dropped, 3,
        "a planar loop of spatial revolutes has 3 redundant equations"
    );
    assert!(sys.warnings[0].contains("over-constrained by 3 equations"));
    let plain = four_bar_rsur();
    assert_eq!(
        System::new(&plain)
            .loops
            .iter()
            .map(|l| l.dropped.len())
            .sum::<usize>(),
        0
    );

    let mut torque = Vec::new();
    for m in [&redundant, &plain] {
        let rocker = coord(m, "rocker_pivot.theta3");
        let crank = coord(m, "crank_pivot.theta3");
        let (s, hist) = run(m);
        assert!(s.max_constraint_violation < 1e-8);
        let mut err: f64 = 0.0;
        for f in &hist.frames {
            let th2 = PI / 2.0 + f.state.coords[crank].q;
            let th4 = th4_0 + f.state.coords[rocker].q;
            err = err.max((th4 - freudenstein(th2)).abs());
        }
        println!("max rocker-angle error {err:.2e} rad");
        // Positions are exact up to the Newton tolerance (1e-8).
        assert!(err < 1e-7, "{err}");
        torque.push(
            hist.frames
                .iter()
                .map(|f| f.coordinate_forces[crank])
                .collect::<Vec<f64>>(),
        );
        // The reactions — in the redundant loop the minimum-norm particular solution —
        // balance the coupler (node at its centre of gravity): m a = F₁ − F₂ + m g, with
        // F₁ the force of crank_coupler on its side B (the coupler) and F₂ that of
        // coupler_rocker on its side B (the rocker), both turned from frame A to global.
        let sys = System::new(m);
        let mut worst: f64 = 0.0;
        for f in hist.frames.iter().skip(1) {
            let axes = |k: usize| sys.constraints[k].location(&f.state.nodes).1;
            let f1 = axes(1) * f.reactions[1].0;
            let f2 = axes(2) * f.reactions[2].0;
            let g = nalgebra::Vector3::new(0.0, -9.81, 0.0);
            let r = f.state.nodes[1].a - (f1 - f2 + g);
            worst = worst.max(r.norm());
        }
        println!("coupler force balance: max residual {worst:.2e} N/kg");
        assert!(worst < 1e-6, "{worst}");
    }
    let scale = torque[1].iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let diff = torque[0]
        .iter()
        .zip(&torque[1])
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    println!("crank torque: peak {scale:.3} N m, difference between variants {diff:.2e}");
    assert!(diff < 1e-6 * scale.max(1.0), "{diff} vs {scale}");
}

/// Bricard's mechanism (IFToMM multibody benchmark A04, after Bricard 1897): five rods of
/// 1 m and 1 kg with 0.1 m square sections, six revolute joints at the corners of a unit
/// cube path, gravity −9.81 y. Grübler counts 30 equations for 30 unknowns (rigid), yet the
/// linkage moves with one degree of freedom: one equation is redundant. Each hinge axis is
/// normal to the two rods it joins (the trihedral Bricard linkage).
fn bricard(rho: f64, step: f64, t_end: f64) -> Model {
    let p = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, -1.0, 0.0],
        [1.0, -1.0, 1.0],
        [0.0, -1.0, 1.0],
        [0.0, 0.0, 1.0],
    ];
    // Each hinge is normal to both rods it joins: y, z, x, y, z, x.
    let axes = ["[0.0, 1.0, 0.0]", "[0.0, 0.0, 1.0]", "[1.0, 0.0, 0.0]"];
    let mut t = format!(
        "[model]\nname = \"bricard\"\ngravity = [0.0, -9.81, 0.0]\n[[analyses]]\nname = \"swing\"\ntype = \"dynamic\"\nt_end = {t_end}\nstep = {step}\nrho_inf = {rho}\ntolerance = 1e-10\n"
    );
    // Rod k joins p[k] and p[k+1]: inertia about its centre, axial 1/6 m a², transverse
    // m (L² + a²)/12.
    let (it, ia) = ((1.0 + 0.01) / 12.0, 0.02 / 12.0);
    for k in 0..5 {
        let c: Vec<f64> = (0..3).map(|i| 0.5 * (p[k][i] + p[k + 1][i])).collect();
        let u: Vec<f64> = (0..3).map(|i| p[k + 1][i] - p[k][i]).collect();
        let inertia: Vec<String> = (0..3)
            .map(|i| {
                let row: Vec<String> = (0..3)
                    .map(|j| {
                        let d = if i == j { 1.0 } else { 0.0 };
                        format!("{}", it * (d - u[i] * u[j]) + ia * u[i] * u[j])
                    })
                    .collect();
                format!("[{}]", row.join(", "))
            })
            .collect();
        t += &format!(
            "[[nodes]]\nname = \"rod{k}\"\nposition = [{}, {}, {}]\n[[bodies]]\nname = \"rod{k}\"\nnode = \"rod{k}\"\nmass = 1.0\ninertia = [{}]\n",
            c[0],
            c[1],
            c[2],
            inertia.join(", ")
        );
    }
    for k in 0..6 {
        let a = if k == 0 {
            "ground".to_string()
        } else {
            format!("rod{}", k - 1)
        };
        let b = if k == 5 {
            "ground".to_string()
        } else {
            format!("rod{k}")
        };
        t += &format!(
            "[[joints]]\nname = \"j{k}\"\ntype = \"revolute\"\nnode_a = \"{a}\"\nnode_b = \"{b}\"\nposition = [{}, {}, {}]\naxis = {}\n",
            p[k][0],
            p[k][1],
            p[k][2],
            axes[k % 3]
        );
    }
    model(&t)
}

/// Largest violation of every joint equation, the redundant one included.
fn full_violation(sys: &System, state: &samara::system::State) -> f64 {
    let ctx = sys.context(state.time, 1.0);
    let mut worst: f64 = 0.0;
    for (k, c) in sys.constraints.iter().enumerate() {
        let n = c.n_rows();
        let mut phi = vec![0.0; n];
        let mut b = nalgebra::DMatrix::zeros(n, 6 * c.nodes().len() + c.n_coordinates());
        c.evaluate_all_rows(
            &ctx,
            &state.nodes,
            sys.coords_of(k, state),
            &mut phi,
            &mut b,
        );
        worst = phi.iter().fold(worst, |m, x| m.max(x.abs()));
    }
    worst
}

/// Bricard's mechanism runs through full cycles of its one-degree-of-freedom motion: the
/// redundant equation is found (rank 35 of 36 rows, with the six coordinate definitions),
/// every equation — the dropped one too — holds to the Newton tolerance, and with ρ∞ = 1
/// the energy is conserved to O(h²).
#[test]
fn bricard_mechanism_moves_with_one_degree_of_freedom() {
    let m = bricard(1.0, 2e-3, 10.0);
    let sys = System::new(&m);
    assert_eq!(sys.loops.len(), 1);
    assert_eq!(sys.loops[0].dropped.len(), 1, "{:?}", sys.loops[0]);
    let j0 = coord(&m, "j0.theta3");
    let mut drift = Vec::new();
    for h in [2e-3, 1e-3] {
        let m = bricard(1.0, h, 10.0);
        let (s, hist) = run(&m);
        assert_eq!(s.rejected_steps, 0);
        let e0 = hist.frames[0].energy.kinetic + hist.frames[0].energy.potential;
        let mut de: f64 = 0.0;
        let mut viol: f64 = 0.0;
        for f in &hist.frames {
            de = de.max((f.energy.kinetic + f.energy.potential - e0).abs());
            viol = viol.max(full_violation(&sys, &f.state));
        }
        // Full cycles: released at rest, the first hinge swings from 0 to π and back in
        // about 5 s; its rate changes sign at each end of the swing.
        let rates: Vec<f64> = hist.frames.iter().map(|f| f.state.coords[j0].v).collect();
        let reversals = rates.windows(2).filter(|w| w[0] * w[1] < 0.0).count();
        let amplitude = hist
            .frames
            .iter()
            .map(|f| f.state.coords[j0].q.abs())
            .fold(0.0, f64::max);
        println!(
            "h = {h}: max |ΔE| {de:.3e} J, max |Φ| (all rows) {viol:.2e}, {reversals} reversals, amplitude {amplitude:.3} rad"
        );
        assert!(viol < 1e-9, "{viol}");
        assert!(reversals >= 3, "fewer than two full cycles in 10 s");
        assert!((amplitude - PI).abs() < 1e-2, "{amplitude}");
        drift.push(de);
    }
    let order = orders(&drift)[0];
    assert!(
        (order - 2.0).abs() < 0.4,
        "energy error order {order} ({drift:?})"
    );
    // Index 3 with dissipation runs through as well.
    let (s, _) = run(&bricard(0.9, 2e-3, 10.0));
    assert!(s.max_constraint_violation < 1e-9);
}

/// Screw jack (pitch p = 5 mm/rev): a nut driven in rotation along the screw axis.
/// Dynamics: d3 = p θ3 holds to the solver tolerance at every step of a driven turn.
/// Statics: under an axial load F the drive must hold the torque −p F (virtual work:
/// T δθ + F p δθ = 0), and the reaction on the nut is −F: the thread carries F and +p F,
/// the drive −p F.
#[test]
fn screw_joint_ties_translation_to_rotation() {
    let p = 0.005 / (2.0 * PI);
    let text = |analysis: &str| {
        format!(
            r#"
[model]
name = "screw_jack"
gravity = [0.0, 0.0, -9.81]
[[nodes]]
name = "nut"
position = [0.0, 0.0, 0.2]
[[bodies]]
name = "nut"
node = "nut"
mass = 3.0
inertia = [[0.01, 0.0, 0.0], [0.0, 0.01, 0.0], [0.0, 0.0, 0.02]]
cg_offset = [0.05, 0.0, 0.0]
[[joints]]
name = "jack"
type = "screw"
node_a = "ground"
node_b = "nut"
axis = [0.0, 0.0, 1.0]
pitch = {p}
[joints.theta3]
drive = {{ type = "polynomial", coefficients = [0.0, 3.0, 2.0] }}
[[forces]]
name = "load"
node = "nut"
force = [0.0, 0.0, -500.0]
{analysis}
"#
        )
    };
    let dynamic = model(&text(
        "[[analyses]]\nname = \"lift\"\ntype = \"dynamic\"\nt_end = 1.0\nstep = 1e-3\ntolerance = 1e-10",
    ));
    let (_, hist) = run(&dynamic);
    let mut worst: f64 = 0.0;
    for f in &hist.frames {
        let th = 3.0 * f.time + 2.0 * f.time * f.time;
        assert!((f.state.coords[0].q - th).abs() < 1e-10);
        worst = worst.max((f.state.nodes[0].x.z - 0.2 - p * th).abs());
    }
    println!(
        "screw: max |d3 − p θ3| = {worst:.2e} m over {:.2} turns",
        5.0 / (2.0 * PI)
    );
    assert!(worst < 1e-10, "{worst}");

    let stat = model(&text(
        "[[analyses]]\nname = \"hold\"\ntype = \"static\"\ntime = 0.5\ntolerance = 1e-12",
    ));
    let (_, hist) = run(&stat);
    let f = hist.last().unwrap();
    // Load: 500 N applied down plus the weight 3 g: F = −(500 + 29.43) N along e3.
    let axial = -(500.0 + 3.0 * 9.81);
    let torque = f.coordinate_forces[0];
    println!(
        "screw: drive torque {torque:.6} N m, −p F = {:.6}",
        -p * axial
    );
    assert!(
        (torque + p * axial).abs() < 1e-9 * (p * axial).abs(),
        "{torque}"
    );
    let (rf, rm) = f.reactions[0];
    assert!((rf.z + axial).abs() < 1e-9 * axial.abs() && rf.x.abs() < 1e-9 && rf.y.abs() < 1e-9);
    // The weight acts at the CG, 5 cm off the axis and turned by θ = 2 rad with the nut:
    // the joint takes its moment −r × W.
    let r = nalgebra::Vector3::new(0.05 * 2f64.cos(), 0.05 * 2f64.sin(), 0.0);
    let w = nalgebra::Vector3::new(0.0, 0.0, -3.0 * 9.81);
    assert!((rm + r.cross(&w)).norm() < 1e-9, "{rm:?}");
}

/// Universal (Cardan) joint between shafts at β = 20° (from `examples/joint_gallery.toml`):
/// the output shaft's angle obeys tan θ_out = cos β tan θ_in (both measured from the
/// position where the input's cross arm is normal to the plane of the shafts), over two
/// turns of the input driven at 1 rev/s — here through a loop over-constrained by 3.
#[test]
fn cardan_joint_output_angle_follows_the_closed_form() {
    let m = model_file("examples/joint_gallery.toml");
    let (input, output) = (
        coord(&m, "input_bearing.theta3"),
        coord(&m, "output_bearing.theta3"),
    );
    let (_, hist) = run(&m);
    let beta = 20f64.to_radians();
    let mut worst: f64 = 0.0;
    let mut turns: f64 = 0.0;
    for f in &hist.frames {
        let th = f.state.coords[input].q;
        let exact = (beta.cos() * th.sin()).atan2(th.cos());
        let d = f.state.coords[output].q - exact;
        // Compare angles modulo 2π.
        worst = worst.max((d.sin()).abs().max((1.0 - d.cos()).abs()));
        turns = th / (2.0 * PI);
    }
    println!("Cardan joint: max angle error {worst:.2e} rad over {turns:.2} turns");
    assert!(turns > 1.99 && worst < 1e-9, "{worst}");
}
