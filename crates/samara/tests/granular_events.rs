//! Adaptive steps land on the closing and opening of granular pairs (issue #17: "restriction
//! of the step at … contact events, so that nothing is stepped over"), as they do for
//! `[[contacts]]`.
//!
//! Two equal spheres (m = 1 kg, ρ = 0.1 m) in a `[[granular]]` set meet head-on at
//! 2 × 3 m/s on a linear undamped spring law (k = 1e6 N/m), no gravity. Closed form: the
//! overlap δ = 0.2 − |x_b − x_a| is zero until t_c = gap/v_rel, then δ = (v_rel/ω) sin ω(t −
//! t_c) with ω = √(k/μ), μ = m/2 the reduced mass; the spheres separate at t_c + π/ω with
//! their velocities exchanged. Tolerances: each of the two steps across which δ changes
//! side ends within the event resolution (10⁻³ h: 6e-6 m of overlap at 6 m/s for h ≤ 1 ms)
//! of the edge, and the exit velocities and separation time follow the tolerance of the
//! local error (ε = 1e-7 m: ≤ 1e-3 m/s, 2e-5 s). Without event location the steps across
//! the edges land anywhere (checked: at least one ends ≥ 10× farther from the edge).

use crate::common;
use common::{model, run};

const PAIR: &str = r#"
[model]
name = "head_on"
gravity = [0.0, 0.0, 0.0]

[[nodes]]
name = "a"
position = [-0.1037, 0.0, 0.0]
velocity = [3.0, 0.0, 0.0]

[[nodes]]
name = "b"
position = [0.1037, 0.0, 0.0]
velocity = [-3.0, 0.0, 0.0]

[[bodies]]
name = "a"
node = "a"
mass = 1.0
inertia = [[0.004, 0.0, 0.0], [0.0, 0.004, 0.0], [0.0, 0.0, 0.004]]

[[bodies]]
name = "b"
node = "b"
mass = 1.0
inertia = [[0.004, 0.0, 0.0], [0.0, 0.004, 0.0], [0.0, 0.0, 0.004]]

[[granular]]
name = "g"
nodes = ["a", "b"]
radius = 0.1
margin = 0.02
ground_point = [0.0, 0.0, -10.0]
normal = "linear"
stiffness = 1e6

[[analyses]]
name = "collide"
type = "dynamic"
t_end = 0.006
step = 1e-3
min_step = 1e-9
rho_inf = 0.9
step_control = "adaptive"
tolerance_abs = 1e-7
tolerance_rel = 0.0
"#;

#[test]
fn adaptive_steps_land_on_granular_pairs_closing_and_opening() {
    let (k, mu, v_rel, gap) = (1e6_f64, 0.5_f64, 6.0, 0.2074 - 0.2);
    let w = (k / mu).sqrt();
    let (t_c, t_s) = (gap / v_rel, gap / v_rel + std::f64::consts::PI / w);
    let run_with = |locate: bool| {
        let text = PAIR.replace(
            "tolerance_rel = 0.0\n",
            &format!("tolerance_rel = 0.0\nevent_location = {locate}\n"),
        );
        let (s, h) = run(&model(&text));
        assert!(s.failure.is_none(), "{:?}", s.failure);
        let delta: Vec<(f64, f64)> = h
            .frames
            .iter()
            .map(|f| {
                (
                    f.time,
                    0.2 - (f.state.nodes[1].x - f.state.nodes[0].x).norm(),
                )
            })
            .collect();
        let crossings: Vec<(f64, f64)> = delta
            .windows(2)
            .filter(|d| (d[0].1 > 0.0) != (d[1].1 > 0.0))
            .map(|d| (d[1].0, d[0].1.abs().min(d[1].1.abs())))
            .collect();
        let last = &h.frames.last().unwrap().state.nodes;
        (crossings, last[0].v.x, last[1].v.x)
    };
    let (crossings, va, vb) = run_with(true);
    println!("located: crossings {crossings:?}, exit velocities {va:.6} {vb:.6}");
    assert_eq!(crossings.len(), 2, "{crossings:?}");
    for &(t, d) in &crossings {
        assert!(
            d < 6e-6,
            "a step ends {d:.2e} m from the pair's edge (t = {t})"
        );
    }
    assert!(
        (crossings[0].0 - t_c).abs() < 2e-5,
        "{} vs {t_c}",
        crossings[0].0
    );
    assert!(
        (crossings[1].0 - t_s).abs() < 2e-5,
        "{} vs {t_s}",
        crossings[1].0
    );
    assert!(
        (va + 3.0).abs() < 1e-3 && (vb - 3.0).abs() < 1e-3,
        "{va} {vb}"
    );
    let (unlocated, _, _) = run_with(false);
    println!("not located: crossings {unlocated:?}");
    let worst = unlocated.iter().map(|c| c.1).fold(0.0, f64::max);
    let best = crossings.iter().map(|c| c.1).fold(0.0, f64::max);
    assert!(worst > 10.0 * best, "{worst:.2e} vs {best:.2e}");
}
