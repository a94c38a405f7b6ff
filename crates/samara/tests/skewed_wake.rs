//! Issue #15: the Pitt–Peters/Glauert skewed-wake correction of BEM's axial induction in
//! yawed inflow (AeroDyn SkewMod = 2; Moriarty & Hansen, AeroDyn Theory Manual, NREL/TP-500-
//! 36881, 2005; Burton et al., Wind Energy Handbook, §4.4):
//! a_skew = a [1 + (15π/32)(r/R) tan(χ/2) cos ψ], χ = (1 + 0.6a) γ.

use nalgebra::Vector3;
use samara::core::NodeState;
use samara::elements::aero::station::MAX_STATES;
use samara::elements::aero::{AeroStation, Airfoil, Attachment, BemRotor, Inflow, Section, Wind};
use samara::math::Rotation;
use std::f64::consts::PI;
use std::sync::Arc;

/// A blade station at radius r on a 3-blade rotor (R = 5 m) spinning at Ω about +x, the
/// blade at azimuth β from +z (turned about +x), in a wind of 8 m/s at yaw γ (in the x–y
/// plane); returns the station's axial induction.
fn induction(skewed: bool, yaw: f64, beta: f64, r: f64) -> f64 {
    let airfoil = Arc::new(Airfoil::thin_plate_with_drag());
    let wind = Arc::new(Wind {
        speed: 8.0,
        direction: Vector3::new(yaw.cos(), yaw.sin(), 0.0),
        ..Default::default()
    });
    let inflow = Arc::new(Inflow::Bem {
        rotor: BemRotor {
            blades: 3,
            hub_radius: 0.5,
            tip_radius: 5.0,
            tip_loss: true,
            hub_loss: true,
            tangential_induction: true,
            skewed_wake: skewed,
        },
        centre: Vector3::zeros(),
        axis: Vector3::x(),
    });
    // Blade along +z at β = 0 moving along −y (Ω about +x): chord +y, suction side +x,
    // turned toward feather by θ.
    let theta: f64 = 0.12;
    let (c0, n0) = (Vector3::y(), Vector3::x());
    let s = AeroStation::new(
        "s",
        vec![0],
        vec![Attachment {
            weight: 1.0,
            offset: Vector3::new(0.0, 0.0, r),
            chord_dir: c0 * theta.cos() + n0 * theta.sin(),
            normal_dir: -c0 * theta.sin() + n0 * theta.cos(),
        }],
        Section {
            chord: 0.3,
            width: 1.0,
            airfoil,
            viscosity: None,
        },
        1.2,
        wind,
        inflow,
    );
    let hub = NodeState {
        rot: Rotation::identity().compose_exp(&Vector3::new(beta, 0.0, 0.0)),
        w: Vector3::new(6.0, 0.0, 0.0),
        ..Default::default()
    };
    let mut rows = [[0.0; 3]; 16];
    let mut zr = [0.0; MAX_STATES];
    let res = s.compute(0.0, &[hub], &[], &[], &[], &mut rows, &mut zr);
    res.a
}

#[test]
fn skewed_wake_scales_the_induction_as_pitt_peters_over_a_revolution() {
    let yaw = 20f64.to_radians();
    for r in [1.5, 3.0, 4.5] {
        for k in 0..12 {
            let beta = 2.0 * PI * k as f64 / 12.0;
            let a0 = induction(false, yaw, beta, r);
            let a = induction(true, yaw, beta, r);
            // The blade's radial direction (0, −sin β, cos β); the wind's in-plane part
            // along +y: the most downwind position is β = −90°, cos ψ = −sin β.
            let cos_psi = -beta.sin();
            let chi = (1.0 + 0.6 * a0) * yaw;
            let want = 1.0 + 15.0 * PI / 32.0 * (r / 5.0) * (chi / 2.0).tan() * cos_psi;
            // The correction is applied to the converged BEM root's a (no iteration on
            // it): the ratio is the formula to rounding, 1e-12.
            assert!(a0 > 0.02, "a windmill state: {a0}");
            assert!(
                (a / a0 - want).abs() < 1e-12,
                "r {r}, β {beta}: {} vs {want}",
                a / a0
            );
        }
    }
    // Zero yaw: the correction is off (identical results, bit for bit).
    for beta in [0.0, 1.0, 2.5] {
        assert_eq!(
            induction(true, 0.0, beta, 3.0),
            induction(false, 0.0, beta, 3.0)
        );
    }
}
