//! Issue #16: the height-field ground (`ground = { type = "height_field", … }`) of
//! `[[contacts]]` and `[[tires]]`.
//!
//! References nobody here wrote:
//! - a tilted plane given as a height field is the plane ground: the block on the incline
//!   of examples/contact/incline.toml (sticks below tan φ = μ_s, slides with
//!   a = g (sin φ − μ_d cos φ) above) and the braked sled of
//!   examples/contact/tire_braking.toml tilted with its ground give the motion and forces
//!   of the plane-ground models;
//! - a frictionless bead on the curve z = R(1 − cos(x/R)) (energy conservation): its period
//!   at amplitude A is T(A) = 4 ∫₀^A √(1 + z'²)/√(2 g (z(A) − z(x))) dx (computed here by
//!   Gauss–Legendre quadrature after x = A sin θ), → 2π√(R/g) as A → 0;
//! - a tire rolling over a bump: the normal load returns to the static weight once past it.

use crate::common;
use common::{model, model_file, run};
use samara::analysis::{AnalysisSummary, History, run_analysis};
use samara::elements::EvalContext;
use samara::model::Model;
use samara::system::System;

const G: f64 = 9.81;

fn read(rel: &str) -> String {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(rel);
    std::fs::read_to_string(path).unwrap()
}

/// Element outputs of every frame, by name.
fn outputs(m: &Model, h: &History, names: &[&str]) -> Vec<Vec<f64>> {
    let sys = System::new(m);
    let idx: Vec<usize> = names
        .iter()
        .map(|n| {
            sys.output_names
                .iter()
                .position(|o| o == n)
                .unwrap_or_else(|| panic!("no output {n}"))
        })
        .collect();
    let mut out = vec![0.0; sys.output_names.len()];
    h.frames
        .iter()
        .map(|f| {
            let ctx = EvalContext {
                time: f.time,
                gravity: m.gravity,
                load_factor: 1.0,
            };
            sys.element_outputs(&ctx, &f.state, &mut out);
            idx.iter().map(|&i| out[i]).collect()
        })
        .collect()
}

/// A profile z = −tan φ · x over x ∈ [x0, x1] (two points: a plane, reproduced exactly).
fn tilted_profile(phi: f64, x0: f64, x1: f64) -> String {
    let t = phi.tan();
    format!(
        "ground = {{ type = \"height_field\", x = [{x0:?}, {x1:?}], z = [{:?}, {:?}] }}",
        -t * x0,
        -t * x1
    )
}

/// Largest difference of the node positions over all frames of two runs.
fn max_position_difference(a: &History, b: &History) -> f64 {
    assert_eq!(a.frames.len(), b.frames.len());
    a.frames
        .iter()
        .zip(&b.frames)
        .flat_map(|(fa, fb)| {
            fa.state
                .nodes
                .iter()
                .zip(&fb.state.nodes)
                .map(|(na, nb)| (na.x - nb.x).norm())
        })
        .fold(0.0, f64::max)
}

/// Reference (a), contact: the incline of examples/contact/incline.toml with its plane
/// given as a height field. The two runs solve the same equations by different code (the
/// plane's hand-written tangents, the height field's dual numbers), so they agree to
/// round-off and the Newton tolerance, not bit for bit: positions within 1e-11 m of each
/// other over a 1.15-m slide (measured 1.3e-12 m), forces within 1e-9 of the normal load.
/// The sliding acceleration is the closed form to 1e-3 (as for the plane,
/// tests/contact.rs), and at tan φ = 0.48 < μ_s the block sticks.
#[test]
fn a_tilted_plane_height_field_is_the_incline() {
    let plane = read("examples/contact/incline.toml");
    let phi = 30f64.to_radians();
    let field = plane.replace(
        "ground_point = [0.0, 0.0, 0.0]\nground_normal = [0.5, 0.0, 0.8660254037844386]   # (sin 30°, 0, cos 30°)",
        &tilted_profile(phi, -1.0, 5.0),
    );
    assert_ne!(plane, field);
    let (mp, mf) = (model(&plane), model(&field));
    let (hp, hf) = (run(&mp).1, run(&mf).1);
    let d = max_position_difference(&hp, &hf);
    let slid = (hf.last().unwrap().state.nodes[0].x - hf.frames[0].state.nodes[0].x).norm();
    let speed = |t: f64| hf.at(t).unwrap().state.nodes[0].v.norm();
    let a = (speed(1.0) - speed(0.5)) / 0.5;
    let exact = G * (phi.sin() - 0.3 * phi.cos());
    println!(
        "incline: slid {slid:.4} m, plane vs height field {d:.2e} m; a = {a:.6}, closed form {exact:.6}"
    );
    assert!(d < 1e-11, "{d}");
    assert!((a - exact).abs() < 1e-3 * exact, "{a} {exact}");
    let fo = outputs(&mf, &hf, &["slide.normal_force", "slide.friction_force"]);
    let po = outputs(&mp, &hp, &["slide.normal_force", "slide.friction_force"]);
    let last = (fo.last().unwrap(), po.last().unwrap());
    println!("forces: height field {:?}, plane {:?}", last.0, last.1);
    for k in 0..2 {
        assert!((last.0[k] - last.1[k]).abs() < 1e-9 * last.1[0], "{last:?}");
    }

    // Below the friction angle it sticks.
    let phi = 0.48f64.atan();
    let d = 2.0 * G * phi.cos() / 1e6;
    let stick = field
        .replace(
            "position = [-8.4957e-6, 0.0, -1.47150e-5]",
            &format!(
                "position = [{:e}, 0.0, {:e}]",
                -phi.sin() * d,
                -phi.cos() * d
            ),
        )
        .replace(
            &tilted_profile(30f64.to_radians(), -1.0, 5.0),
            &tilted_profile(phi, -1.0, 5.0),
        );
    let (_, h) = run(&model(&stick));
    let last = h.last().unwrap();
    let moved = (last.state.nodes[0].x - h.frames[0].state.nodes[0].x).norm();
    let v = last.state.nodes[0].v.norm();
    println!("tan φ = 0.48: moved {moved:.3e} m, speed {v:.3e} m/s");
    assert!(moved < 1e-5 && v < 1e-6, "{moved} {v}");
}

/// The braked sled of examples/contact/tire_braking.toml with its rig and ground tilted
/// by `deg` about y (the sled runs downhill along +x), on the plane or on a height field.
fn tilted_sled(deg: f64, field: bool) -> String {
    let (s, c) = deg.to_radians().sin_cos();
    let h = 0.28553025;
    let mut t = read("examples/contact/tire_braking.toml")
        .replace("t_end = 1.5", "t_end = 0.6")
        .replace(
            "position = [0.0, 0.0, 0.28553025]",
            &format!("position = [{:?}, 0.0, {:?}]", s * h, c * h),
        )
        .replace(
            "velocity = [10.0, 0.0, 0.0]",
            &format!("velocity = [{:?}, 0.0, {:?}]", 10.0 * c, -10.0 * s),
        )
        .replacen(
            "axis = [1.0, 0.0, 0.0]",
            &format!("axis = [{c:?}, 0.0, {:?}]", -s),
            1,
        )
        .replacen(
            "axis = [0.0, 0.0, 1.0]",
            &format!("axis = [{s:?}, 0.0, {c:?}]"),
            1,
        );
    let ground = if field {
        tilted_profile(deg.to_radians(), -5.0, 20.0)
    } else {
        format!("ground_normal = [{s:?}, 0.0, {c:?}]")
    };
    t = t.replace(
        "brake = \"brake\"\n",
        &format!("brake = \"brake\"\n{ground}\n"),
    );
    t
}

/// Reference (a), tire: the braked sled tilted by 10° with its ground, on the plane and
/// on the height field of the same plane: the same normal and longitudinal forces (to
/// 1e-10 of the static load; measured 3e-12) and positions (1e-12 m; measured 5e-15 m),
/// through spin-down, lock and skid: round-off between two codes for the same equations.
#[test]
fn a_tilted_plane_height_field_is_the_tire_ground() {
    let (mp, mf) = (
        model(&tilted_sled(10.0, false)),
        model(&tilted_sled(10.0, true)),
    );
    let (hp, hf) = (run(&mp).1, run(&mf).1);
    let names = ["tire.normal_force", "tire.longitudinal_force"];
    let (op, of) = (outputs(&mp, &hp, &names), outputs(&mf, &hf, &names));
    let fz0 = 295.0 * G * 10f64.to_radians().cos();
    let df = op
        .iter()
        .zip(&of)
        .flat_map(|(a, b)| a.iter().zip(b).map(|(x, y)| (x - y).abs()))
        .fold(0.0, f64::max);
    let dx = max_position_difference(&hp, &hf);
    let fx_min = of.iter().map(|v| v[1]).fold(0.0, f64::min);
    println!(
        "tilted sled: forces differ by {:.2e} of F_z0 = {fz0:.1} N (peak braking force {fx_min:.1} N), positions by {dx:.2e} m",
        df / fz0
    );
    assert!(fx_min < -0.5 * fz0, "the brake acted: {fx_min}");
    assert!(df < 1e-10 * fz0, "{df}");
    assert!(dx < 1e-12, "{dx}");
}

/// The bead-in-a-bowl model: a point mass on z = R(1 − cos(x/R)) tabulated at spacing
/// `dx` over [−1.2, 1.2], released at rest at x = A, frictionless, for `t_end`.
fn bowl(r: f64, a: f64, dx: f64, t_end: f64) -> String {
    let n = (2.4 / dx).round() as usize;
    let xs: Vec<f64> = (0..=n).map(|i| -1.2 + 2.4 * i as f64 / n as f64).collect();
    let zs: Vec<f64> = xs.iter().map(|x| r * (1.0 - (x / r).cos())).collect();
    let k = 1e7;
    // Start on the surface with the normal load's penetration m g n_z / k along n.
    let slope = (a / r).sin();
    let nz = 1.0 / (1.0 + slope * slope).sqrt();
    let delta = G * nz / k;
    let (px, pz) = (
        a + slope * nz * delta,
        r * (1.0 - (a / r).cos()) - nz * delta,
    );
    format!(
        r#"
[model]
name = "bowl"
gravity = [0.0, 0.0, -9.81]
[[nodes]]
name = "bead"
position = [{px:?}, 0.0, {pz:?}]
[[bodies]]
name = "bead"
node = "bead"
mass = 1.0
inertia = [[1e-3, 0.0, 0.0], [0.0, 1e-3, 0.0], [0.0, 0.0, 1e-3]]
[[contacts]]
name = "bead"
node = "bead"
shape = "point"
ground = {{ type = "height_field", x = {xs:?}, z = {zs:?} }}
normal = "linear"
stiffness = {k:?}
damping = 1000.0
[[analyses]]
name = "roll"
type = "dynamic"
t_end = {t_end:?}
step = 5e-4
rho_inf = 0.5
"#
    )
}

/// The period of a bead on z = R(1 − cos(x/R)) at amplitude A: x = A sin θ,
/// T = 4 ∫₀^{π/2} √(1 + z'²) A cos θ / √(2 g (z(A) − z(x))) dθ (the integrand is smooth
/// in θ), by 64-point Gauss–Legendre on 16 panels (converged to round-off).
fn bead_period(r: f64, a: f64) -> f64 {
    let z = |x: f64| r * (1.0 - (x / r).cos());
    let f = |th: f64| {
        let x = a * th.sin();
        let zp = (x / r).sin();
        let dz = z(a) - z(x);
        if dz <= 0.0 {
            // θ → π/2: the limit √(1 + z'(A)²) A / √(g z'(A) A).
            let za = (a / r).sin();
            return (1.0 + za * za).sqrt() * a / (G * za * a).sqrt();
        }
        (1.0 + zp * zp).sqrt() * a * th.cos() / (2.0 * G * dz).sqrt()
    };
    // 8-point Gauss–Legendre nodes and weights on [−1, 1].
    let nodes = [
        (0.183_434_642_495_649_8, 0.362_683_783_378_362),
        (0.525_532_409_916_329, 0.313_706_645_877_887_3),
        (0.796_666_477_413_626_7, 0.222_381_034_453_374_5),
        (0.960_289_856_497_536_3, 0.101_228_536_290_376_3),
    ];
    let panels = 64;
    let hw = std::f64::consts::FRAC_PI_2 / panels as f64 / 2.0;
    let mut sum = 0.0;
    for p in 0..panels {
        let mid = (2 * p + 1) as f64 * hw;
        for &(t, w) in &nodes {
            sum += w * (f(mid - hw * t) + f(mid + hw * t)) * hw;
        }
    }
    4.0 * sum
}

/// Reference (b): the period of a frictionless bead released at A = 0.4 m in the bowl
/// z = R(1 − cos(x/R)), R = 1 m, tabulated at spacings 0.4, 0.2, 0.1, 0.05 m, against the
/// quadrature period of the exact curve (2.1022 s; 2π√(R/g) = 2.0061 s is its small-
/// amplitude limit): the error falls with the spacing at orders 2.3–3.2 (measured 2.77,
/// 2.65, 2.55 — the interpolated height is third-order, its curvature, which sets the
/// period, between second and third on average) to below 5e-5 at 5 cm (measured 2.7e-5;
/// the 0.5-ms step's own period error is ~1e-6); energy (kinetic + gravity + contact +
/// dissipated by the normal damper) is conserved to 1e-5 of the swing energy (measured
/// 2–3e-7: at the foot point the normal force is the contact potential's gradient). The period is measured between the first and third
/// downward-then-upward zero crossings of x (linear interpolation between 0.5-ms frames).
#[test]
fn a_bead_in_a_tabulated_bowl_has_the_period_of_the_curve() {
    let (r, a) = (1.0, 0.4);
    let t_ref = bead_period(r, a);
    let t_small = 2.0 * std::f64::consts::PI * (r / G).sqrt();
    println!("period: quadrature {t_ref:.8} s, small-oscillation 2π√(R/g) = {t_small:.8} s");
    // The quadrature reproduces the small-oscillation limit at small amplitude.
    assert!((bead_period(r, 1e-3) - t_small).abs() < 1e-6 * t_small);
    let mut errors = Vec::new();
    for dx in [0.4, 0.2, 0.1, 0.05] {
        let m = model(&bowl(r, a, dx, 1.3 * t_ref));
        let sys = System::new(&m);
        let (_, h) = run(&m);
        let crossings: Vec<f64> = h
            .frames
            .windows(2)
            .filter_map(|w| {
                let (x0, x1) = (w[0].state.nodes[0].x[0], w[1].state.nodes[0].x[0]);
                (x0.signum() != x1.signum() && x0 != 0.0)
                    .then(|| w[0].time + (w[1].time - w[0].time) * x0 / (x0 - x1))
            })
            .collect();
        assert!(crossings.len() >= 3, "{crossings:?}");
        let period = crossings[2] - crossings[0];
        let err = (period - t_ref).abs() / t_ref;
        // Energy balance over the run.
        let ctx = EvalContext {
            time: 0.0,
            gravity: m.gravity,
            load_factor: 1.0,
        };
        let energy =
            |s: &samara::core::State| sys.kinetic_energy(s) + sys.potential_energy(&ctx, s);
        let (f0, fl) = (&h.frames[0], h.last().unwrap());
        let swing = G * r * (1.0 - (a / r).cos());
        let balance = (energy(&fl.state) + fl.energy.dissipated - energy(&f0.state)).abs() / swing;
        println!(
            "Δx = {dx}: period {period:.8} s, relative error {err:.3e}; energy balance {balance:.2e}, dissipated {:.2e} of the swing",
            fl.energy.dissipated / swing
        );
        assert!(balance < 1e-5, "{balance}");
        errors.push(err);
    }
    let orders = common::orders(&errors);
    println!("errors {errors:?}, orders {orders:?}");
    assert!(errors[3] < 5e-5, "{errors:?}");
    assert!(
        orders.iter().all(|&p| (2.3..3.2).contains(&p)),
        "{orders:?}"
    );
}

/// Reference (c): the sled of examples/contact/tire_braking.toml, unbraked, with a stiffer
/// vertical damper, rolls at 10 m/s over a cosine bump 2 cm high and 0.5 m long at
/// x = 3 m (a profile tabulated every 2.5 cm): the normal load rises over it (more than
/// 20 %; measured 6×), and 0.65 s after it is back at the static weight of carrier and
/// wheel, (280 + 15) kg × g, to 1e-5 (measured 1e-6: the near-critically damped vertical
/// mode, ζ ≈ 1 at ω ≈ 26 rad/s, has decayed to ~1e-7 by then).
#[test]
fn a_tire_over_a_bump_returns_to_the_static_load() {
    let xs: Vec<f64> = (0..=680).map(|i| -2.0 + 0.025 * i as f64).collect();
    let zs: Vec<f64> = xs
        .iter()
        .map(|&x| {
            if (x - 3.0).abs() < 0.25 {
                0.01 * (1.0 + (2.0 * std::f64::consts::PI * (x - 3.0) / 0.5).cos())
            } else {
                0.0
            }
        })
        .collect();
    let text = read("examples/contact/tire_braking.toml")
        .replace("t_end = 1.5", "t_end = 1.0")
        .replace("vertical_damping = 3000.0", "vertical_damping = 15000.0")
        .replace(
            "brake = \"brake\"\n",
            &format!("ground = {{ type = \"height_field\", x = {xs:?}, z = {zs:?} }}\n"),
        );
    let m = model(&text);
    let (_, h) = run(&m);
    let fz = outputs(&m, &h, &["tire.normal_force"]);
    let w = 295.0 * G;
    let peak = fz.iter().map(|v| v[0]).fold(0.0, f64::max);
    let last = fz.last().unwrap()[0];
    let x_end = h.last().unwrap().state.nodes[0].x[0];
    println!(
        "bump: peak F_z {peak:.1} N, final {last:.3} N, static {w:.3} N; sled at x = {x_end:.2} m"
    );
    assert!(x_end > 8.0, "{x_end}");
    assert!(peak > 1.2 * w, "{peak}");
    assert!((last - w).abs() < 1e-5 * w, "{last} {w}");
}

/// Runs without panicking on a failure.
fn attempt(m: &Model) -> AnalysisSummary {
    let sys = System::new(m);
    let mut h = History::default();
    run_analysis(
        &sys,
        &m.analyses[0],
        sys.initial_state(),
        &mut h,
        &mut |_| {},
    )
    .unwrap()
}

/// A body that rolls off the table stops the analysis with an error naming the element,
/// where it is and the time (not a silent extrapolation).
#[test]
fn leaving_the_table_is_an_error_with_the_time_and_the_element() {
    let text = bowl(1.0, 0.4, 0.2, 1.0)
        .replace("position = [", "velocity = [5.0, 0.0, 0.0]\nposition = [");
    let s = attempt(&model(&text));
    let f = s.failure.expect("the bead leaves the table");
    println!("{f:?}");
    assert!(f.reason.contains("element 'bead'"), "{}", f.reason);
    assert!(
        f.reason.contains("left the height field's table"),
        "{}",
        f.reason
    );
    assert!(f.time > 0.0 && f.time < 1.0, "{}", f.time);
}

/// Bad tables get a located error (line and column of the key or file) with a hint.
#[test]
fn bad_tables_are_rejected_where_they_are_written() {
    let base = read("examples/contact/incline.toml");
    let old = "ground_point = [0.0, 0.0, 0.0]\nground_normal = [0.5, 0.0, 0.8660254037844386]   # (sin 30°, 0, cos 30°)";
    assert!(base.contains(old));
    let cases: &[(&str, &str)] = &[
        (
            "ground = { type = \"height_field\", x = [0.0, 2.0, 1.0], z = [0.0, 0.0, 0.0] }",
            "strictly increasing (not at index 2)",
        ),
        (
            "ground = { type = \"height_field\", x = [0.0], z = [0.0] }",
            "at least 2 `x` values",
        ),
        (
            "ground = { type = \"height_field\", x = [0.0, 1.0], y = [0.0, 1.0], z = [[0.0, 0.0], [0.0]] }",
            "1 columns where 2 are needed",
        ),
        (
            "ground = { type = \"height_field\", x = [0.0, 1.0], y = [0.0, 1.0], z = [[0.0, 0.0]] }",
            "1 rows where 2 are needed",
        ),
        (
            "ground = { type = \"height_field\", x = [0.0, 1.0], y = [0.0, 1.0], z = [0.0, 0.0] }",
            "with `y`, `z` is a table",
        ),
        (
            "ground = { type = \"height_field\", x = [0.0, 1.0], z = [[0.0, 0.0]] }",
            "needs its `y` values",
        ),
        (
            "ground = { type = \"height_field\", z = [0.0, 0.0] }",
            "needs `x` and `z`",
        ),
        (
            "ground = { type = \"height_field\", file = \"t.csv\", x = [0.0, 1.0] }",
            "`x` and `file` both give the table",
        ),
        (
            "ground = { type = \"height_field\", file = \"no_such_terrain.csv\" }",
            "cannot read terrain file",
        ),
        (
            "ground = { type = \"height_field\", x = [0.0, 1.0], z = [0.0, 0.0] }\nground_normal = [0.0, 0.0, 1.0]",
            "`ground_normal` does not apply here",
        ),
    ];
    // NaN in the model text is refused by the number check of every model key.
    let nan = base.replace(
        old,
        "ground = { type = \"height_field\", x = [0.0, 1.0], z = [0.0, nan] }",
    );
    let Err(e) = Model::from_toml_str(&nan, "bad.toml") else {
        panic!("accepted a NaN height");
    };
    let d = e.errors().next().expect("an error");
    assert!(
        d.message.contains("`nan` is outside the range"),
        "{}",
        d.message
    );
    assert!(d.span.is_some());
    for (with, want) in cases {
        let text = base.replace(old, with);
        let Err(e) = Model::from_toml_str(&text, "bad.toml") else {
            panic!("accepted: {with}");
        };
        let d = e.errors().next().expect("an error");
        let span = d.span.clone().expect("a located error");
        let (line, col) = e.source.line_col(span.start);
        let hint = d.hint.clone().unwrap_or_default();
        let needle = with.lines().last().unwrap();
        let want_line = text[..text.find(needle).unwrap()].matches('\n').count() + 1;
        println!("{line}:{col}: {} (hint: {hint})", d.message);
        assert!(d.message.contains(want), "{with}: {}", d.message);
        assert!(d.message.contains("contact 'slide'"), "{}", d.message);
        assert_eq!(line, want_line, "{}", d.message);
        assert!(!hint.is_empty());
    }
}

/// Terrain files: a profile (`x, z` lines) and a grid (header of x values, then `y, z…`
/// lines) give the same ground as the inline table; a bad file is rejected with its line
/// and column.
#[test]
fn terrain_files_match_the_inline_table_and_bad_files_are_located() {
    let dir = std::env::temp_dir().join(format!("samara_terrain_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let base = read("examples/contact/incline.toml").replace("t_end = 1.0", "t_end = 0.2");
    let old = "ground_point = [0.0, 0.0, 0.0]\nground_normal = [0.5, 0.0, 0.8660254037844386]   # (sin 30°, 0, cos 30°)";
    let t = 30f64.to_radians().tan();
    let inline = base.replace(old, &tilted_profile(30f64.to_radians(), -1.0, 5.0));
    std::fs::write(
        dir.join("profile.csv"),
        format!("# x, z\n-1.0, {:?}\n5.0, {:?}\n", t, -5.0 * t),
    )
    .unwrap();
    std::fs::write(
        dir.join("grid.csv"),
        format!(
            "y\\x, -1.0, 5.0\n-2.0, {:?}, {:?}\n2.0, {:?}, {:?}\n",
            t,
            -5.0 * t,
            t,
            -5.0 * t
        ),
    )
    .unwrap();
    std::fs::write(dir.join("bad.csv"), "y\\x, -1.0, 5.0\n-2.0, 0.0, abc\n").unwrap();
    std::fs::write(dir.join("order.csv"), "0.0, 0.0\n1.0, 0.0\n0.5, 0.0\n").unwrap();
    std::fs::write(dir.join("nan.csv"), "0.0, 0.0\n# a gap\n1.0, nan\n").unwrap();
    std::fs::write(dir.join("row.csv"), "y\\x, 0.0, 1.0\n0.0, 1.0\n").unwrap();
    let reference = run(&model(&inline)).1;
    for f in ["profile.csv", "grid.csv"] {
        let text = base.replace(
            old,
            &format!("ground = {{ type = \"height_field\", file = \"{f}\" }}"),
        );
        let path = dir.join("m.toml");
        std::fs::write(&path, &text).unwrap();
        let m = Model::from_file(&path).unwrap().model;
        let h = run(&m).1;
        let d = max_position_difference(&reference, &h);
        println!("{f}: differs from the inline table by {d:.2e} m");
        assert!(d < 1e-12, "{d}");
    }
    for (f, want) in [
        ("bad.csv", "line 2, column 3: expected a number, got 'abc'"),
        ("order.csv", "line 3, column 1"),
        (
            "nan.csv",
            "line 3, column 2: the height at row 0, column 1 is not finite",
        ),
        (
            "row.csv",
            "line 2: a grid row has the y value and 2 heights",
        ),
    ] {
        let text = base.replace(
            old,
            &format!("ground = {{ type = \"height_field\", file = \"{f}\" }}"),
        );
        let path = dir.join("m.toml");
        std::fs::write(&path, &text).unwrap();
        let Err(samara::Error::Model(e)) = Model::from_file(&path) else {
            panic!("accepted {f}, or not a model error");
        };
        let d = e.errors().next().expect("an error");
        let span = d.span.clone().expect("a located error");
        let (line, _) = e.source.line_col(span.start);
        let want_line = text[..text.find("ground = {").unwrap()]
            .matches('\n')
            .count()
            + 1;
        println!("{line}: {}", d.message);
        assert!(d.message.contains(want), "{}", d.message);
        assert_eq!(line, want_line);
    }
    let _ = model_file;
    std::fs::remove_dir_all(&dir).ok();
}

/// The exact tangents on a curved terrain (the registered cases of `[[contacts]]` named
/// `terrain` — sphere, point, capsule end, with and without friction — and of `[[tires]]`
/// named `tire_on_terrain`): each block against central differences with its own scale,
/// within 1e-6 (tests/tangents.rs). The terrain there is curved (Hessian of order 0.3 m⁻¹),
/// so the turning of the normal is in the checked terms.
#[test]
fn curved_terrain_tangents_pass_the_tangent_check() {
    let ctx = EvalContext {
        time: 0.3,
        gravity: nalgebra::Vector3::new(0.0, 0.0, -9.81),
        load_factor: 1.0,
    };
    let cases: Vec<_> = samara::model::components::tangent_cases()
        .into_iter()
        .filter(|(_, c)| matches!(c.name(), "terrain" | "tire_on_terrain"))
        .collect();
    assert_eq!(cases.len(), 6);
    let mut worst: f64 = 0.0;
    for (table, case) in &cases {
        let rep = case.check(&ctx);
        println!("[[{table}]] {}: {rep:?}", case.name());
        worst = worst.max(rep.tangents);
        assert!(rep.tangents < 1e-6, "{rep:?}");
    }
    println!("largest mismatch on the curved terrain: {worst:.2e}");
}

/// examples/contact/terrain.toml in full: the ball rolls down the bumpy slope (more than
/// 0.3 m in 1 s), rolling without slipping at the end (slip speed below a tenth of the
/// Stribeck speed, `stick` = 1: on the bumps the required friction stays below μ_s), and
/// the energy balance (kinetic + gravity + contact + dissipated by Hunt–Crossley and
/// LuGre) closes to 5e-4 of the potential energy released (measured 7.1e-5: the normal
/// force at the foot point is the contact potential's gradient; what remains is the
/// trapezoidal sum of the dissipated power).
#[test]
fn the_terrain_example_rolls_and_balances_energy() {
    let m = model_file("examples/contact/terrain.toml");
    let sys = System::new(&m);
    let (_, h) = run(&m);
    let (f0, fl) = (&h.frames[0], h.last().unwrap());
    let moved = fl.state.nodes[0].x - f0.state.nodes[0].x;
    let o = outputs(
        &m,
        &h,
        &["ball.slip_velocity", "ball.stick", "ball.normal_force"],
    );
    let last = o.last().unwrap();
    let ctx = EvalContext {
        time: 0.0,
        gravity: m.gravity,
        load_factor: 1.0,
    };
    let e = |s: &samara::core::State| sys.kinetic_energy(s) + sys.potential_energy(&ctx, s);
    let released = G * (f0.state.nodes[0].x.z - fl.state.nodes[0].x.z);
    let balance = (e(&fl.state) + fl.energy.dissipated - e(&f0.state)).abs() / released;
    println!(
        "terrain: moved {moved:?}, slip {:.2e} m/s, stick {}, N = {:.3} N; released {released:.4} J, dissipated {:.4} J, balance {balance:.2e}",
        last[0], last[1], last[2], fl.energy.dissipated
    );
    assert!(moved.x > 0.3, "{moved:?}");
    assert!(last[0] < 1e-3 && last[1] == 1.0, "{last:?}");
    assert!(balance < 5e-4, "{balance}");
}
