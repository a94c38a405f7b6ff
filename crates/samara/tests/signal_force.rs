//! Issue #16: controller outputs drive forces. `[[forces]] signal = "…"` multiplies the
//! load by a signal; here a position sensor and a gain controller close the loop
//! F = −k x on a free mass (no gravity), which is the harmonic oscillator
//! `m ẍ + k x = 0`: x(t) = x₀ cos(ω t), ω = √(k/m) (closed form). Unknown signals are
//! located errors.

use crate::common;
use common::{model, orders, run};
use samara::model::Model;

fn oscillator(step: f64) -> String {
    format!(
        r#"
[model]
name = "signal_force"
gravity = [0.0, 0.0, 0.0]
[[nodes]]
name = "mass"
position = [0.1, 0.0, 0.0]
[[bodies]]
name = "mass"
node = "mass"
mass = 2.0
inertia = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
[[sensors]]
name = "x"
node = "mass"
quantity = "position"
component = "x"
[[controllers]]
name = "spring_law"
type = "gain"
input = "x"
gain = -50.0                          # −k [N/m]
[[forces]]
name = "actuator"
node = "mass"
force = [1.0, 0.0, 0.0]
signal = "spring_law"
[[analyses]]
name = "swing"
type = "dynamic"
t_end = 1.0
step = {step}
rho_inf = 1.0
"#
    )
}

/// Position against x₀ cos(ω t) over 1 s (1.6 periods): second order in the step
/// (generalized-α, ρ∞ = 1), and 1e-4 x₀ at h = 1 ms ((ω h)²/12 · ω t ≈ 2.1e-5 phase).
#[test]
fn a_controller_output_drives_a_force() {
    let omega = (50.0f64 / 2.0).sqrt();
    let mut errors = Vec::new();
    for step in [4e-3, 2e-3, 1e-3] {
        let m: Model = model(&oscillator(step));
        let (_, h) = run(&m);
        let worst = h
            .frames
            .iter()
            .map(|f| (f.state.nodes[0].x[0] - 0.1 * (omega * f.time).cos()).abs())
            .fold(0.0, f64::max);
        errors.push(worst);
    }
    let o = orders(&errors);
    println!("errors {errors:?} m, orders {o:.2?}");
    assert!(o.iter().all(|&p| (p - 2.0).abs() < 0.15), "{o:?}");
    assert!(errors[2] < 1e-4 * 0.1, "{errors:?}");
}

#[test]
fn an_unknown_force_signal_is_a_located_error() {
    let text = oscillator(1e-3).replace("signal = \"spring_law\"", "signal = \"spring_lw\"");
    let err = match samara::model::Model::from_toml_str(&text, "f.toml") {
        Ok(_) => panic!("an unknown signal was accepted"),
        Err(e) => e.to_string(),
    };
    println!("{err}");
    assert!(err.contains("f.toml:"), "{err}");
    assert!(err.contains("unknown signal 'spring_lw'"), "{err}");
    assert!(err.contains("did you mean 'spring_law'"), "{err}");
}
