//! Issue #16: friction between two bodies — a sphere pair (`[[contacts]]` with
//! `other_node` and the LuGre keys), checked against closed forms.
//!
//! 1. **Stick (rolling) and slip** of a solid sphere B (mass m, radius ρ, I = 2/5 m ρ²)
//!    resting under gravity on a sphere A clamped to the ground, pulled by a horizontal
//!    force F at its centre. A is large (ρ_A = 1000 m) so that over the 0.05 s run the
//!    contact stays on top of it: the tilt x/ρ_A < 3e-5 rad and the centripetal loss of
//!    normal force v²/(ρ_A g) < 1e-4. Rigid-body mechanics with Coulomb friction:
//!    - F < (1 + m ρ²/I) μ_s m g = 3.5 μ_s m g: B rolls without slipping, friction
//!      f = F/(1 + m ρ²/I) = 2F/7, acceleration a = F/(m + I/ρ²) = 5F/(7m), spin
//!      acceleration α = a/ρ;
//!    - F > 3.5 μ_s m g: B slides, f = μ_d m g, a = (F − μ_d m g)/m, α = 5 μ_d g/(2ρ).
//!
//!    The rolling case checks the moment of friction on B (ω × a_B in the slip velocity
//!    and a_B × F_t in B's moment rows). Tolerance 2e-3 relative on the accelerations,
//!    measured from the velocity change over the second half of the run: the LuGre
//!    bristle (σ₀ = 1e5 /m, σ₁ about critical) holds stick with a deflection of
//!    f/(σ₀ N) ≈ 3 µm whose transient (≈ 1 ms) has died out by then, in slip
//!    g(s) = μ_d to e^(−(s/v_s)²) < 1e-40 after the first millisecond; the geometric
//!    effects above stay below 1e-4.
//! 2. **Oblique collision of two free spinning spheres** with friction, no gravity: the
//!    pair's forces are equal and opposite and act at one point (the middle of the
//!    overlap), so linear momentum is conserved to the Newton tolerance (the
//!    generalized-α update of v is linear in the accelerations) and angular momentum about
//!    a fixed point exactly in time; generalized-α conserves the latter to O(h²), checked
//!    by its convergence. The kinetic energy lost equals the dissipated work (normal
//!    damping and friction, integrated by the trapezoidal rule) to O(h²).

use crate::common;
use common::{model, run};

/// B on A under gravity with a horizontal pull `force` [N]; m = 2 kg, ρ = 0.1 m.
fn pulled_sphere(force: f64, t_end: f64) -> String {
    format!(
        r#"
[model]
name = "pulled_sphere"
gravity = [0.0, 0.0, -9.81]

[[nodes]]
name = "a"
position = [0.0, 0.0, -1000.0]

[[nodes]]
name = "b"
position = [0.0, 0.0, {zb}]

[[bodies]]
name = "a"
node = "a"
mass = 100.0
inertia = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]

[[bodies]]
name = "b"
node = "b"
mass = 2.0
inertia = [[0.008, 0.0, 0.0], [0.0, 0.008, 0.0], [0.0, 0.0, 0.008]]

[[joints]]
name = "clamp"
type = "fixed"
node_a = "ground"
node_b = "a"

[[forces]]
name = "pull"
node = "b"
force = [{force}, 0.0, 0.0]

[[contacts]]
name = "touch"
node = "a"
shape = "sphere"
radius = 1000.0
other_node = "b"
other_radius = 0.1
normal = "linear"
stiffness = 1e7
damping = 2e3
static_friction = 0.5
dynamic_friction = 0.3
stribeck_velocity = 1e-3
bristle_stiffness = 1e5
bristle_damping = 200.0

[[analyses]]
name = "pull"
type = "dynamic"
t_end = {t_end}
step = 2e-4
rho_inf = 0.6
"#,
        zb = 0.1 - 2.0 * 9.81 / 1e7,
    )
}

/// (a, α) from the velocity change over the second half of the run.
fn accelerations(force: f64) -> (f64, f64) {
    let t_end = 0.05;
    let (s, h) = run(&model(&pulled_sphere(force, t_end)));
    assert!(s.failure.is_none(), "{:?}", s.failure);
    let k = h.frames.len() / 2;
    let (f0, f1) = (&h.frames[k], h.last().unwrap());
    let dt = f1.time - f0.time;
    let (b0, b1) = (&f0.state.nodes[1], &f1.state.nodes[1]);
    let a = (b1.v[0] - b0.v[0]) / dt;
    let alpha = ((b1.r() * b1.w)[1] - (b0.r() * b0.w)[1]) / dt;
    (a, alpha)
}

#[test]
fn a_pulled_sphere_rolls_below_the_friction_limit_and_slides_above_it() {
    let (m, g, rho, ms, md) = (2.0, 9.81, 0.1, 0.5, 0.3);
    let limit = 3.5 * ms * m * g;
    // Stick: rolling without slipping.
    let f = 0.6 * limit;
    let (a, alpha) = accelerations(f);
    let a_ref = 5.0 * f / (7.0 * m);
    println!(
        "rolling: F = {f:.3} N, a = {a:.6} (closed form {a_ref:.6}), α ρ = {:.6}",
        alpha * rho
    );
    assert!((a - a_ref).abs() < 2e-3 * a_ref, "{a} vs {a_ref}");
    assert!((alpha * rho - a_ref).abs() < 2e-3 * a_ref, "{alpha}");
    // Slip: sliding friction μ_d m g, spin-up by its moment.
    let f = 1.3 * limit;
    let (a, alpha) = accelerations(f);
    let a_ref = (f - md * m * g) / m;
    let alpha_ref = 2.5 * md * g / rho;
    println!("sliding: F = {f:.3} N, a = {a:.6} ({a_ref:.6}), α = {alpha:.5} ({alpha_ref:.5})");
    assert!((a - a_ref).abs() < 2e-3 * a_ref, "{a} vs {a_ref}");
    assert!(
        (alpha - alpha_ref).abs() < 2e-3 * alpha_ref,
        "{alpha} vs {alpha_ref}"
    );
}

/// Two spinning spheres meeting off-centre, with friction, no gravity.
fn oblique(step: f64) -> String {
    format!(
        r#"
[model]
name = "oblique"
gravity = [0.0, 0.0, 0.0]

[[nodes]]
name = "a"
position = [0.0, 0.0, 0.0]
velocity = [0.5, 0.0, 0.0]
angular_velocity = [0.0, 3.0, -20.0]

[[nodes]]
name = "b"
position = [0.25, 0.12, 0.03]
velocity = [-1.5, 0.0, 0.0]
angular_velocity = [10.0, 0.0, 15.0]

[[bodies]]
name = "a"
node = "a"
mass = 1.0
inertia = [[0.004, 0.0, 0.0], [0.0, 0.004, 0.0], [0.0, 0.0, 0.004]]

[[bodies]]
name = "b"
node = "b"
mass = 3.0
inertia = [[0.012, 0.0, 0.0], [0.0, 0.012, 0.0], [0.0, 0.0, 0.012]]

[[contacts]]
name = "impact"
node = "a"
shape = "sphere"
radius = 0.1
other_node = "b"
other_radius = 0.1
normal = "hunt_crossley"
stiffness = 1e7
restitution = 0.7
impact_velocity = 2.0
static_friction = 0.4
dynamic_friction = 0.3
stribeck_velocity = 1e-2
bristle_stiffness = 1e4
bristle_damping = 30.0

[[analyses]]
name = "collide"
type = "dynamic"
t_end = 0.06
step = {step}
rho_inf = 0.9
"#
    )
}

#[test]
fn an_oblique_collision_with_friction_conserves_momentum_and_spins_both_spheres() {
    let mut drifts = Vec::new();
    for step in [4e-5, 2e-5, 1e-5] {
        let m = model(&oblique(step));
        let sys = samara::system::System::new(&m);
        let (s, h) = run(&m);
        assert!(s.failure.is_none(), "{:?}", s.failure);
        let first = &h.frames[0];
        let last = h.last().unwrap();
        let (p0, l0) = sys.momenta(&first.state);
        let (p1, l1) = sys.momenta(&last.state);
        let dp = (p1 - p0).norm();
        let dl = (l1 - l0).norm();
        let e0 = first.energy.kinetic + first.energy.potential;
        let e1 = last.energy.kinetic + last.energy.potential;
        let lost = e0 - e1;
        let dissipated = last.energy.dissipated;
        // The friction spun both spheres about new axes (their spins changed).
        let spin_change = |k: usize| {
            let n0 = &first.state.nodes[k];
            let n1 = &last.state.nodes[k];
            (n1.r() * n1.w - n0.r() * n0.w).norm()
        };
        println!(
            "h = {step:.0e}: |Δp| = {dp:.2e}, |ΔL| = {dl:.3e} (L = {:.4}), energy lost {lost:.6} J, dissipated {dissipated:.6} J, spin changes {:.3} {:.3} rad/s, gap {:.4}",
            l0.norm(),
            spin_change(0),
            spin_change(1),
            (last.state.nodes[1].x - last.state.nodes[0].x).norm() - 0.2
        );
        assert!(dp < 1e-9 * p0.norm().max(1.0), "{dp}");
        assert!(spin_change(0) > 0.5 && spin_change(1) > 0.1);
        assert!(lost > 0.0 && (lost - dissipated).abs() < 2e-3 * lost);
        drifts.push(dl);
    }
    let orders = common::orders(&drifts);
    println!("angular momentum drift orders {orders:?}");
    assert!(orders.iter().all(|&o| o > 1.7), "{orders:?}");
}
