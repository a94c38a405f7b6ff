//! Issues #2 and #3, verification 7: every element's and constraint's tangents against
//! finite differences, through the one generic checker in `samara::tangent_check`; every
//! joint type, with and without the elements attached to its coordinates.
//!
//! States are random (seeded), away from the constraint manifold and with non-zero
//! velocities and accelerations, so that every term of every tangent is exercised.
//! Tolerance 1e-6 relative, per entry (see the module doc of `tangent_check`: each entry
//! against its own size and the diagonal scaling, with what central differences at ε = 1e-6
//! can resolve as the floor), so anything above 1e-6 is a wrong tangent.

use crate::common;
use common::Lcg;
use nalgebra::{Matrix3, Vector3};
use samara::elements::{AppliedLoad, Element, EvalContext, RigidBody, SpringDamper};
use samara::joints::{Constraint, Joint};
use samara::math::Rotation;
use samara::model::{
    BacklashDef, ComponentDef, ForceLaw, JointDef, JointType, LoadFrame, NodeRef, TimeFunction,
};
use samara::system::{Coordinate, NodeState};
use samara::tangent_check::{check_constraint, check_element};

const TOL: f64 = 1e-6;

fn random_nodes(rng: &mut Lcg, n: usize) -> Vec<NodeState> {
    (0..n)
        .map(|_| NodeState {
            x: rng.vec3(1.0),
            rot: Rotation::exp(&rng.vec3(2.0)),
            v: rng.vec3(2.0),
            w: rng.vec3(3.0),
            a: rng.vec3(5.0),
            wd: rng.vec3(5.0),
        })
        .collect()
}

fn ctx() -> EvalContext {
    EvalContext {
        time: 0.3,
        gravity: Vector3::new(0.3, -1.2, -9.81),
        load_factor: 0.7,
    }
}

fn elements(rng: &mut Lcg) -> Vec<Box<dyn Element>> {
    let inertia = Matrix3::new(2.0, 0.1, -0.2, 0.1, 3.0, 0.3, -0.2, 0.3, 4.0);
    vec![
        Box::new(RigidBody::new("body", 0, 2.5, inertia, rng.vec3(0.5))),
        Box::new(RigidBody::new(
            "body_at_cg",
            1,
            1.5,
            Matrix3::identity(),
            Vector3::zeros(),
        )),
        Box::new(SpringDamper::new(
            "spring",
            Some((0, rng.vec3(0.3))),
            Some((1, rng.vec3(0.3))),
            [Vector3::zeros(), Vector3::zeros()],
            1e3,
            20.0,
            0.4,
        )),
        Box::new(SpringDamper::new(
            "spring_to_ground",
            None,
            Some((2, rng.vec3(0.3))),
            [Vector3::new(0.5, -0.2, 2.0), Vector3::zeros()],
            300.0,
            5.0,
            1.0,
        )),
        Box::new(AppliedLoad::new(
            "dead",
            1,
            rng.vec3(10.0),
            rng.vec3(3.0),
            LoadFrame::Global,
            rng.vec3(0.4),
            TimeFunction::Sine {
                amplitude: 1.0,
                frequency: 2.0,
                phase: 0.3,
                offset: 0.5,
                start: 0.0,
            },
        )),
        Box::new(AppliedLoad::new(
            "follower",
            2,
            rng.vec3(10.0),
            rng.vec3(3.0),
            LoadFrame::Node,
            rng.vec3(0.4),
            TimeFunction::Constant(1.3),
        )),
    ]
}

const ALL_JOINTS: [JointType; 11] = [
    JointType::Fixed,
    JointType::Revolute,
    JointType::Prismatic,
    JointType::Screw,
    JointType::Cylindrical,
    JointType::Planar,
    JointType::Spherical,
    JointType::Universal,
    JointType::PointOnLine,
    JointType::PointOnPlane,
    JointType::Prescribed,
];

/// Everything that can hang on a free component: a table spring, a linear damper, a
/// backlash contact (engaged at the random coordinate values used here), an input and,
/// on every other component, a drive (a time function on components 0, 2, 4; a signal —
/// a servo row — on 1, 3, 5).
fn attachments(rng: &mut Lcg, c: usize) -> ComponentDef {
    ComponentDef {
        spring: Some(ForceLaw::Table {
            x: vec![-2.0, -0.1, 0.3, 2.0],
            f: vec![-50.0, -1.0, 4.0, 90.0],
        }),
        damper: Some(ForceLaw::Linear {
            coefficient: 3.0,
            reference: 0.0,
        }),
        backlash: Some(BacklashDef {
            center: 0.05 * rng.next(),
            half_width: 0.01,
            stiffness: 400.0,
            damping: 2.0,
        }),
        drive: c.is_multiple_of(2).then_some(TimeFunction::Sine {
            amplitude: 0.4,
            frequency: 1.7,
            phase: 0.2,
            offset: 0.1,
            start: 0.0,
        }),
        input: Some("u".into()),
        drive_signal: (!c.is_multiple_of(2)).then(|| "command".into()),
    }
}

fn joints(rng: &mut Lcg, nodes: &[NodeState]) -> Vec<Box<dyn Constraint>> {
    let mut out: Vec<Box<dyn Constraint>> = Vec::new();
    for kind in ALL_JOINTS {
        for (variant, (a, b)) in [
            (NodeRef::Node(0), NodeRef::Node(1)),
            (NodeRef::Ground, NodeRef::Node(2)),
            (NodeRef::Node(1), NodeRef::Ground),
        ]
        .into_iter()
        .enumerate()
        {
            let axes = *Rotation::exp(&rng.vec3(1.0)).matrix();
            let mut def = JointDef::new(
                format!("{kind:?}.{variant}"),
                kind,
                a,
                b,
                rng.vec3(1.0),
                axes,
            );
            // Separate origins on the two sides (the frames need not coincide).
            def.position_b = def.position_a + rng.vec3(0.2);
            def.pitch = 0.05;
            // Variant 0 bare; variants 1, 2 with elements on every free component (which
            // also creates the Bryant coordinates of joints with three free rotations).
            if variant > 0 {
                for c in 0..6 {
                    if samara::joints::rows::has_coordinate(kind, c) {
                        def.components[c] = Some(attachments(rng, c + variant));
                    }
                }
            }
            out.push(Box::new(Joint::new(&def, nodes)));
        }
    }
    out
}

#[test]
fn every_element_tangent_matches_finite_differences() {
    let mut rng = Lcg(7);
    let mut largest: f64 = 0.0;
    for trial in 0..5 {
        let nodes = random_nodes(&mut rng, 3);
        for e in elements(&mut rng) {
            let rep = check_element(e.as_ref(), &ctx(), &nodes);
            largest = largest.max(rep.worst());
            assert!(
                rep.worst() < TOL,
                "trial {trial}, element {}: {rep:?}",
                e.name()
            );
        }
    }
    println!("largest relative mismatch (per entry): {largest:.2e}");
}

/// Every joint type, bare and with every coordinate element, on both kinds of sides.
#[test]
fn every_constraint_tangent_matches_finite_differences() {
    let mut rng = Lcg(11);
    let (mut largest, mut rates): (f64, f64) = (0.0, 0.0);
    for trial in 0..5 {
        // Frames attached in one configuration, checked in another (Φ ≠ 0), with
        // coordinates away from their consistent values.
        let reference = random_nodes(&mut rng, 3);
        let nodes = random_nodes(&mut rng, 3);
        for c in joints(&mut rng, &reference) {
            let coords: Vec<Coordinate> = (0..c.n_coordinates())
                .map(|_| Coordinate {
                    q: 0.8 * rng.next(),
                    v: 2.0 * rng.next(),
                    a: 0.0,
                })
                .collect();
            let mu: Vec<f64> = (0..c.n_equations()).map(|_| 10.0 * rng.next()).collect();
            let rep = check_constraint(c.as_ref(), &ctx(), &nodes, &coords, &mu);
            largest = largest
                .max(rep.b.relative)
                .max(rep.k.relative)
                .max(rep.velocity_tangent.relative)
                .max(rep.coordinate_stiffness.relative)
                .max(rep.coordinate_damping.relative);
            rates = rates.max(rep.convective).max(rep.velocity);
            assert!(
                rep.b.relative < TOL
                    && rep.k.relative < TOL
                    && rep.velocity_tangent.relative < TOL
                    && rep.coordinate_stiffness.relative < TOL
                    && rep.coordinate_damping.relative < TOL,
                "trial {trial}, {}: {rep:?}",
                c.name()
            );
            // The one evaluation the assembler makes against the separate calls: the same
            // sums in another order (Bᵀμ summed in spatial components, then rotated), so
            // round-off, a few ulps of the largest entry.
            assert!(rep.combined < 1e-13, "trial {trial}, {}: {rep:?}", c.name());
            // The servo rows' contract (Φ = ν − s, B = e_ν, ∂Φ/∂s = −1): exact but for
            // the difference quotient in s (one rounding of Φ ~ 1 over ε = 1e-6).
            assert!(rep.servo < 1e-9, "trial {trial}, {}: {rep:?}", c.name());
            // Differences at ε = 1e-4: O(ε²) truncation and O(u/ε²) round-off ≈ 1e-8.
            assert!(
                rep.convective < 1e-5 && rep.velocity < 1e-5,
                "trial {trial}, {}: {rep:?}",
                c.name()
            );
        }
    }
    println!("largest relative mismatch (per entry): {largest:.2e}; rate terms {rates:.2e}");
}

/// Issue #17: the discrete gradient of every joint's rows over a step
/// (`Constraint::discrete_jacobian`, the energy-consistent integrators' constraint
/// forces), every joint type bare and with coordinates, on both kinds of sides, over
/// large Cayley steps (|ψ| up to 0.35 rad, |Δx| up to 0.35 m, |Δν| up to 0.3):
/// - `B̄Δ = Φ(q₁, ν₁) − Φ(q₀, ν₀)`: the rows are bilinear in the frames' vectors, which
///   move by `ψ × v̄` exactly over a Cayley step, and the coordinates' trigonometric
///   factors enter through their secants, so this is exact: tolerance 1e-12 of
///   `|B̄||Δ|` (round-off of sums of O(1) terms);
/// - for joints between two nodes, `B̄Ḡ = 0` for the six superposed rigid motions in the
///   step's discrete form (translation t: `(t, 0)` at each node; rotation e:
///   `(e × x̄, (I + ψ̃/2)⁻¹R₀ᵀe)`, the motion against which the rigid bodies' Simo–Wong
///   form balances angular momentum): the rows are invariant functions of the frames, so
///   the forces `B̄ᵀλ` have no resultant and no moment, at any configuration;
///   tolerance 1e-12 of `|B̄||x̄|`.
#[test]
fn every_joint_discrete_jacobian_is_an_exact_discrete_gradient_and_moment_free() {
    use nalgebra::{DMatrix, DVector};
    use samara::math::{cayley::cayley, skew};
    let mut rng = Lcg(23);
    let (mut energy, mut momentum): (f64, f64) = (0.0, 0.0);
    for trial in 0..5 {
        let reference = random_nodes(&mut rng, 3);
        let start = random_nodes(&mut rng, 3);
        let steps: Vec<(Vector3<f64>, Vector3<f64>)> =
            (0..3).map(|_| (rng.vec3(0.2), rng.vec3(0.2))).collect();
        let end: Vec<NodeState> = start
            .iter()
            .zip(&steps)
            .map(|(n, (dx, psi))| NodeState {
                x: n.x + dx,
                rot: Rotation::from_quaternion(n.rot.quaternion() * cayley(psi)),
                ..*n
            })
            .collect();
        for c in joints(&mut rng, &reference) {
            let nc = c.n_coordinates();
            let (m, nodes) = (c.n_equations(), c.nodes().to_vec());
            let cols = 6 * nodes.len() + nc;
            let c0: Vec<Coordinate> = (0..nc)
                .map(|_| Coordinate {
                    q: 0.8 * rng.next(),
                    ..Default::default()
                })
                .collect();
            let c1: Vec<Coordinate> = c0
                .iter()
                .map(|q| Coordinate {
                    q: q.q + 0.3 * rng.next(),
                    ..Default::default()
                })
                .collect();
            let mut delta = DVector::zeros(cols);
            let mut maps = Vec::new();
            for (a, &ni) in nodes.iter().enumerate() {
                let (dx, psi) = steps[ni];
                delta.fixed_rows_mut::<3>(6 * a).copy_from(&dx);
                delta.fixed_rows_mut::<3>(6 * a + 3).copy_from(&psi);
                maps.push(start[ni].r() * (Matrix3::identity() + skew(&psi) * 0.5));
            }
            for q in 0..nc {
                delta[6 * nodes.len() + q] = c1[q].q - c0[q].q;
            }
            let mut bbar = DMatrix::zeros(m, cols);
            c.discrete_jacobian(&start, &end, [&c0, &c1], &maps, &mut bbar);
            let (mut phi0, mut phi1) = (vec![0.0; m], vec![0.0; m]);
            c.evaluate(&ctx(), &start, &c0, &mut phi0, None);
            c.evaluate(&ctx(), &end, &c1, &mut phi1, None);
            let scale = bbar.norm() * delta.norm();
            let work = &bbar * &delta;
            for j in 0..m {
                let e = (work[j] - (phi1[j] - phi0[j])).abs() / scale.max(1.0);
                energy = energy.max(e);
                assert!(e < 1e-12, "trial {trial}, {} row {j}: {e:e}", c.name());
            }
            if nodes.len() < 2 {
                continue;
            }
            let xbar: Vec<Vector3<f64>> = nodes
                .iter()
                .map(|&ni| (start[ni].x + end[ni].x) * 0.5)
                .collect();
            let lever = xbar.iter().map(|x| x.norm()).fold(1.0, f64::max);
            for k in 0..6 {
                let e = Vector3::ith(k % 3, 1.0);
                let mut g = DVector::zeros(cols);
                for (a, &ni) in nodes.iter().enumerate() {
                    if k < 3 {
                        g.fixed_rows_mut::<3>(6 * a).copy_from(&e);
                    } else {
                        let psi = steps[ni].1;
                        let turn = (Matrix3::identity() + skew(&psi) * 0.5)
                            .try_inverse()
                            .unwrap()
                            * start[ni].r().transpose()
                            * e;
                        g.fixed_rows_mut::<3>(6 * a).copy_from(&e.cross(&xbar[a]));
                        g.fixed_rows_mut::<3>(6 * a + 3).copy_from(&turn);
                    }
                }
                let moment = (&bbar * &g).amax() / (bbar.norm() * lever);
                momentum = momentum.max(moment);
                assert!(
                    moment < 1e-12,
                    "trial {trial}, {} generator {k}: {moment:e}",
                    c.name()
                );
            }
        }
    }
    println!("largest defect ΔΦ − B̄Δ {energy:.2e}; largest B̄Ḡ {momentum:.2e}");
}

/// The checker itself must catch a wrong tangent: a spring whose analytic stiffness is
/// evaluated with the wrong stiffness value must fail.
#[test]
fn checker_detects_a_wrong_tangent() {
    struct Wrong(SpringDamper, SpringDamper);
    impl Element for Wrong {
        fn name(&self) -> &str {
            "wrong"
        }
        fn nodes(&self) -> &[usize] {
            self.0.nodes()
        }
        fn evaluate(
            &self,
            ctx: &EvalContext,
            nodes: &samara::core::ElementInput,
            need: samara::elements::Need,
            out: &mut samara::elements::LocalTerms,
        ) {
            // Residual from one spring, tangents from a slightly stiffer one.
            if need == samara::elements::Need::Residual {
                self.0.evaluate(ctx, nodes, need, out);
            } else {
                self.1.evaluate(ctx, nodes, need, out);
            }
        }
    }
    let mk = |k: f64| {
        SpringDamper::new(
            "s",
            Some((0, Vector3::zeros())),
            Some((1, Vector3::zeros())),
            [Vector3::zeros(); 2],
            k,
            0.0,
            0.5,
        )
    };
    let mut rng = Lcg(3);
    let nodes = random_nodes(&mut rng, 2);
    let rep = check_element(&Wrong(mk(100.0), mk(100.5)), &ctx(), &nodes);
    assert!(rep.k.relative > 1e-4, "{rep:?}");
}

/// The generic loop over the registry of component kinds: every kind of the model file
/// supplies tangent cases (its elements and constraints at generic states, with element
/// states and input signals where it has them), and every case passes. A new kind that
/// registers no case fails here.
#[test]
fn every_registered_kind_passes_the_tangent_check() {
    use samara::model::components::{TABLES, tangent_cases};
    let cases = tangent_cases();
    for table in TABLES {
        assert!(
            cases.iter().any(|(t, _)| t == table),
            "the kind `[[{table}]]` registers no tangent case"
        );
    }
    let (mut tangents, mut rates): (f64, f64) = (0.0, 0.0);
    for (table, case) in &cases {
        let rep = case.check(&ctx());
        tangents = tangents.max(rep.tangents);
        rates = rates.max(rep.rates);
        assert!(
            rep.tangents < TOL && rep.rates < 1e-5,
            "[[{table}]] {}: {rep:?}",
            case.name()
        );
    }
    println!(
        "{} cases over {} kinds; largest mismatch: tangents {tangents:.2e}, rate terms {rates:.2e}",
        cases.len(),
        TABLES.len()
    );
}
