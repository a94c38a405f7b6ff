//! Elements with states and signals (issue #11): the low-pass sensor and the Maxwell
//! element pass the generic tangent check — K, C, M of node and state columns, ∂r/∂s, and
//! the derivatives of the signals they produce — at random states.

use crate::common;
use common::Lcg;
use nalgebra::Vector3;
use samara::core::{ElementState, EvalContext, NodeState};
use samara::elements::{LowPassSensor, Maxwell, NodeQuantity, SensorInput};
use samara::math::Rotation;
use samara::tangent_check::check_element_with;

/// Relative mismatch accepted (see tangent_check.rs: round-off and truncation of the
/// central differences are ~1e-10 relative; a wrong tangent is ≥ 1e-3).
const TOL: f64 = 1e-6;

fn ctx() -> EvalContext {
    EvalContext {
        time: 0.3,
        gravity: Vector3::new(0.0, 0.0, -9.81),
        load_factor: 1.0,
    }
}

fn random_node(rng: &mut Lcg) -> NodeState {
    NodeState {
        x: rng.vec3(1.0),
        rot: Rotation::exp(&rng.vec3(2.0)),
        v: rng.vec3(1.0),
        w: rng.vec3(3.0),
        a: rng.vec3(1.0),
        wd: rng.vec3(1.0),
    }
}

#[test]
fn low_pass_sensor_tangents() {
    let mut rng = Lcg(11);
    let quantities = [
        NodeQuantity::Position(0),
        NodeQuantity::Velocity(1),
        NodeQuantity::Acceleration(2),
        NodeQuantity::AngularVelocity(0),
        NodeQuantity::AngularVelocity(2),
    ];
    for q in quantities {
        let nodes = vec![random_node(&mut rng), random_node(&mut rng)];
        let e = LowPassSensor::new(
            "s",
            "s.out",
            SensorInput::Node {
                node: 1,
                quantity: q,
            },
            0.05,
            2.5,
            0.0,
        );
        let z = [ElementState {
            z: rng.next(),
            zd: rng.next(),
        }];
        let r = check_element_with(&e, &ctx(), &nodes, &z, &[]);
        assert!(r.worst() < TOL, "{q:?}: {r:?}");
    }
    // Reading a signal instead of a node.
    let e = LowPassSensor::new(
        "s",
        "s.out",
        SensorInput::Signal("u".into()),
        0.2,
        -3.0,
        0.0,
    );
    let z = [ElementState { z: 0.4, zd: -1.2 }];
    let r = check_element_with(&e, &ctx(), &[], &z, &[0.7]);
    assert!(r.worst() < TOL, "{r:?}");
}

#[test]
fn maxwell_tangents() {
    let mut rng = Lcg(12);
    for trial in 0..6 {
        let nodes = vec![random_node(&mut rng), random_node(&mut rng)];
        let (a, b) = if trial % 3 == 2 {
            (None, Some((1, rng.vec3(0.3))))
        } else {
            (Some((0, rng.vec3(0.3))), Some((1, rng.vec3(0.3))))
        };
        let e = Maxwell::new("m", a, b, [rng.vec3(2.0), rng.vec3(2.0)], 1e4, 30.0, 0.5);
        let z = [ElementState {
            z: 0.1 * rng.next(),
            zd: rng.next(),
        }];
        let r = check_element_with(&e, &ctx(), &nodes, &z, &[]);
        assert!(r.worst() < TOL, "trial {trial}: {r:?}");
    }
}
