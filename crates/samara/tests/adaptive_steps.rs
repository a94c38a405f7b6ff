//! Adaptive steps (issue #17): the achieved global error follows the tolerance as the
//! theory says, a fast transient followed by a slow phase takes far fewer steps than the
//! fixed step of the same accuracy, breakpoints of time functions and contact events are
//! landed on, and the options (`tolerance_abs`, `tolerance_rel`, `step_max`, `min_step`,
//! `event_location`) act and are checked.
//!
//! Theory: with the local error (O(h³) for the second-order generalized-α) held at the
//! tolerance ε per step, h ∝ ε^(1/3) and the global error ∝ h² ∝ ε^(2/3).

use crate::common;
use common::{kick_constants, kick_response, model, model_file, run};
use samara::model::Model;
use std::f64::consts::PI;

const PENDULUM: &str = r#"[model]
name = "pendulum"
gravity = [0.0, 0.0, -9.81]
[[nodes]]
name = "bob"
position = [1.0, 0.0, 0.0]
[[bodies]]
name = "bob"
node = "bob"
mass = 1.0
inertia = [[1e-3, 0.0, 0.0], [0.0, 1e-3, 0.0], [0.0, 0.0, 1e-3]]
[[joints]]
name = "pivot"
type = "revolute"
node_a = "ground"
node_b = "bob"
position = [0.0, 0.0, 0.0]
axis = [0.0, 1.0, 0.0]
"#;

/// The pendulum released from the horizontal: φ̈ = m g L cos φ / I_O (φ below the
/// horizontal, I_O = m L² + I_yy), by RK4 with 200,000 steps (error < 1e-12).
fn pendulum_reference(t_end: f64) -> (f64, f64) {
    let (g, i_o) = (9.81, 1.0 + 1e-3);
    let f = |y: [f64; 2]| [y[1], g * y[0].cos() / i_o];
    let n = 200_000;
    let h = t_end / n as f64;
    let mut y = [0.0, 0.0];
    let add = |y: [f64; 2], k: [f64; 2], s: f64| [y[0] + s * k[0], y[1] + s * k[1]];
    for _ in 0..n {
        let k1 = f(y);
        let k2 = f(add(y, k1, h / 2.0));
        let k3 = f(add(y, k2, h / 2.0));
        let k4 = f(add(y, k3, h));
        for i in 0..2 {
            y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
    }
    (y[0].cos(), -y[0].sin())
}

fn with_analysis(base: &str, analysis: &str) -> Model {
    model(&format!(
        "{base}\n[[analyses]]\nname = \"run\"\ntype = \"dynamic\"\n{analysis}"
    ))
}

/// Pendulum over 2 s (a large swing): the global error at t_end falls as ε^(2/3) over
/// four decades of the tolerance (observed exponent 0.69; accepted 0.55 … 0.8).
#[test]
fn global_error_follows_the_tolerance() {
    let t_end = 2.0;
    let (xr, zr) = pendulum_reference(t_end);
    let tols: [f64; 4] = [1e-4, 1e-5, 1e-6, 1e-7];
    let mut errors = Vec::new();
    for tol in tols {
        let m = with_analysis(
            PENDULUM,
            &format!(
                "t_end = {t_end}\nstep = 1e-3\nrho_inf = 0.9\nstep_control = \"adaptive\"\ntolerance_abs = {tol}\ntolerance_rel = 0.0"
            ),
        );
        let (s, h) = run(&m);
        assert!(s.failure.is_none());
        let last = h.frames.last().unwrap();
        assert!((last.time - t_end).abs() < 1e-12);
        let x = last.state.nodes[0].x;
        let err = ((x.x - xr).powi(2) + (x.z - zr).powi(2)).sqrt();
        println!("tolerance {tol:e}: {} steps, error {err:.3e}", s.steps);
        errors.push(err);
    }
    let slope = (errors[0] / errors[3]).log10() / (tols[0] / tols[3]).log10();
    println!("error ∝ tolerance^{slope:.3}");
    assert!(
        (0.55..=0.8).contains(&slope),
        "exponent {slope} ({errors:?})"
    );
    for w in errors.windows(2) {
        assert!(w[1] < w[0], "{errors:?}");
    }
}

/// `examples/adaptive_kick.toml`: a mass on a stiff spring-damper (20 Hz, ζ = 0.05) hit
/// by a step force at t = 0.5 s, then at rest for 4 s. Closed form (constants read from
/// the loaded model) x = F/k [1 − e^{−ζωs}(cos ω_d s + ζ/√(1−ζ²) sin ω_d s)], s = t − 0.5.
/// The adaptive run lands on the step (a record at exactly 0.5 s) and uses at least 5×
/// fewer steps than the fewest fixed steps that reach its accuracy (measured 2026-12-04:
/// 591 steps at 4.7e-5 m, 1.5 % of the static deflection, against 4,133 fixed steps of
/// 1.21 ms at 4.5e-5 m, 7.0×; the fixed steps' error falls as h², 4× per halving).
#[test]
fn a_fast_transient_then_rest_pays_for_adaptive_steps() {
    use samara::model::AnalysisKind;
    let example = model_file("examples/adaptive_kick.toml");
    let (k, c, m, force, t0) = kick_constants(&example);
    let w = (k / m).sqrt();
    let zeta = c / (2.0 * (k * m).sqrt());
    assert!((w / (2.0 * PI) - 20.0).abs() < 1e-6 && (zeta - 0.05).abs() < 1e-6);
    let exact = kick_response(&example);
    let error_and_steps = |fixed_step: Option<f64>| {
        let mut mm = example.clone();
        if let (Some(h), AnalysisKind::Dynamic(d)) = (fixed_step, &mut mm.analyses[0].kind) {
            d.adaptive = None;
            d.step = h;
            d.min_step = h / 1024.0;
        }
        let (s, h) = run(&mm);
        assert!(s.failure.is_none(), "{:?}", s.failure);
        let err = h
            .frames
            .iter()
            .map(|f| (f.state.nodes[0].x.x - exact(f.time)).abs())
            .fold(0.0, f64::max);
        (err, s.steps, h)
    };
    let (err, steps, h) = error_and_steps(None);
    assert!(
        h.frames.iter().any(|f| f.time == t0),
        "no step ends on the breakpoint"
    );
    // Every accepted step met the tolerance and the records say so.
    for f in &h.frames[1..] {
        let d = f.diagnostics.unwrap();
        assert!(d.error_estimate <= 1.0 && d.step_size > 0.0, "{d:?}");
    }
    assert!(err < 0.02 * force / k, "adaptive error {err:e}");
    // The fewest fixed steps (grid of ratio 1.1, from a quarter of the adaptive count up)
    // whose largest error reaches the adaptive run's; the error is second order and
    // monotone in h here, so one grid point settles it.
    let t_end = match &example.analyses[0].kind {
        AnalysisKind::Dynamic(d) => d.t_end,
        _ => panic!("the example's analysis is not dynamic"),
    };
    let (fixed_steps, fixed_err) = fixed_steps_for(t_end, steps, err, 1, |h| {
        let (e, n, _) = error_and_steps(Some(h));
        println!("fixed step {h:.4e}: {n} steps, error {e:.3e}");
        e
    });
    println!(
        "adaptive: {steps} steps, error {err:.3e}; fixed: {fixed_steps} steps, error {fixed_err:.3e}"
    );
    assert!(fixed_steps >= 5 * steps, "{fixed_steps} vs {steps}");
}

/// `step_max` bounds the steps, `tolerance_rel` acts (a looser relative tolerance takes
/// fewer steps), and an error the smallest step cannot meet stops the run with a clear
/// failure.
#[test]
fn options_act() {
    let steps = |analysis: &str| {
        let m = with_analysis(
            PENDULUM,
            &format!(
                "t_end = 1.0\nstep = 1e-3\nstep_control = \"adaptive\"\ndiagnostics = true\n{analysis}"
            ),
        );
        run(&m)
    };
    let (s, h) = steps("tolerance_abs = 1e-3\nstep_max = 0.01");
    assert!(s.failure.is_none());
    let largest = h.frames[1..]
        .iter()
        .map(|f| f.diagnostics.unwrap().step_size)
        .fold(0.0, f64::max);
    assert!(largest <= 0.01 + 1e-15, "{largest}");
    let (free, _) = steps("tolerance_abs = 1e-3");
    assert!(free.steps < s.steps, "{} vs {}", free.steps, s.steps);
    let (tight, _) = steps("tolerance_abs = 0.0\ntolerance_rel = 1e-6");
    let (loose, _) = steps("tolerance_abs = 0.0\ntolerance_rel = 1e-4");
    assert!(
        loose.steps < tight.steps,
        "{} vs {}",
        loose.steps,
        tight.steps
    );
    let m = with_analysis(
        PENDULUM,
        "t_end = 1.0\nstep = 1e-3\nstep_control = \"adaptive\"\ntolerance_abs = 1e-12\ntolerance_rel = 0.0\nstep_min = 1e-4",
    );
    let sys = samara::system::System::new(&m);
    let mut history = samara::analysis::History::default();
    let failed = samara::analysis::run_analysis(
        &sys,
        &m.analyses[0],
        sys.initial_state(),
        &mut history,
        &mut |_| {},
    )
    .unwrap();
    let f = failed.failure.expect("the run must stop");
    assert!(f.reason.contains("local error estimate"), "{}", f.reason);
    assert!(f.hint.unwrap().contains("tolerance_abs"));
}

/// Bad settings get located errors.
#[test]
fn bad_settings_are_located_errors() {
    let bad = |analysis: &str, message: &str| {
        let text = format!(
            "{PENDULUM}\n[[analyses]]\nname = \"run\"\ntype = \"dynamic\"\nt_end = 1.0\nstep = 1e-3\n{analysis}"
        );
        let e = Model::from_toml_str(&text, "bad.toml").expect_err(analysis);
        let shown = e.to_string();
        assert!(shown.contains(message), "{shown}");
        assert!(shown.contains("bad.toml:"), "{shown}");
    };
    bad("tolerance_abs = 1e-6", "used only with adaptive steps");
    bad("step_max = 0.1", "used only with adaptive steps");
    bad("event_location = false", "used only with adaptive steps");
    bad(
        "step_control = \"adaptive\"\ntolerance_abs = 0.0\ntolerance_rel = 0.0",
        "both 0",
    );
    bad(
        "step_control = \"adaptive\"\ntolerance_rel = -1.0",
        "`tolerance_rel` must be ≥ 0",
    );
    bad(
        "step_control = \"adaptive\"\nstep_max = 1e-4",
        "`step_max` must be at least `step`",
    );
    bad("step_control = \"adaptve\"", "unknown value `adaptve`");
    // The smallest step is named as written (`min_step` or its alias `step_min`) and the
    // error points at its value.
    for key in ["min_step", "step_min"] {
        let analysis = format!("step_control = \"adaptive\"\ntolerance_abs = 1e-6\n{key} = 1e-2");
        let text = format!(
            "{PENDULUM}\n[[analyses]]\nname = \"run\"\ntype = \"dynamic\"\nt_end = 1.0\nstep = 1e-3\n{analysis}"
        );
        let shown = Model::from_toml_str(&text, "bad.toml")
            .expect_err(key)
            .to_string();
        let line = text[..text.find(&format!("{key} = 1e-2")).unwrap()]
            .matches('\n')
            .count()
            + 1;
        let col = key.len() + 4;
        assert!(
            shown.contains(&format!(
                "bad.toml:{line}:{col}: error: analysis 'run': `{key}` must be in (0, step]"
            )),
            "{shown}"
        );
        let text = text.replace(&format!("{key} = 1e-2"), &format!("{key} = 1e-300"));
        let shown = Model::from_toml_str(&text, "bad.toml")
            .expect_err(key)
            .to_string();
        assert!(
            shown.contains(&format!("bad.toml:{line}:{col}:")),
            "{shown}"
        );
        assert!(shown.contains(&format!("use a larger `{key}`")), "{shown}");
    }
    // Both spellings at once: named as one key given twice, at the second.
    let text = format!(
        "{PENDULUM}\n[[analyses]]\nname = \"run\"\ntype = \"dynamic\"\nt_end = 1.0\nstep = 1e-3\nmin_step = 1e-5\nstep_min = 1e-5\n"
    );
    let shown = Model::from_toml_str(&text, "bad.toml")
        .expect_err("both")
        .to_string();
    let line = text[..text.find("step_min").unwrap()].matches('\n').count() + 1;
    assert!(
        shown.contains(&format!(
            "bad.toml:{line}:1: error: key `min_step` is given twice"
        )),
        "{shown}"
    );
    assert!(
        shown.contains("`min_step` and `step_min` are two spellings of one key"),
        "{shown}"
    );
    // The same in an inline table: located at the second spelling inside its braces.
    let text = format!(
        "analyses = [{{ name = \"run\", type = \"dynamic\", t_end = 1.0, step = 1e-3, step_min = 1e-5, min_step = 1e-5 }}]\n{PENDULUM}"
    );
    let shown = Model::from_toml_str(&text, "bad.toml")
        .expect_err("inline")
        .to_string();
    let col = text.find("min_step").unwrap() + 1;
    assert!(
        shown.contains(&format!(
            "bad.toml:1:{col}: error: key `min_step` is given twice"
        )),
        "{shown}"
    );
    // A static analysis names the spelling it was given among the keys it does not use.
    let text =
        format!("{PENDULUM}\n[[analyses]]\nname = \"eq\"\ntype = \"static\"\nstep_min = 1e-5\n");
    let shown = Model::from_toml_str(&text, "bad.toml")
        .expect_err("static")
        .to_string();
    assert!(
        shown.contains("`step_min` is not used by a static analysis"),
        "{shown}"
    );
}

/// Adaptive steps land on every breakpoint of ramps and table knots, not only of steps:
/// the kicked mass of `examples/adaptive_kick.toml` driven instead by a table force (knots
/// 0.3, 0.55, 1.2 s) and a ramp (0.7 … 1.9 s). Each knot must end a step (to 1e-12 s);
/// a controller that stepped over one would be caught here.
#[test]
fn adaptive_steps_land_on_ramp_and_table_knots() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/adaptive_kick.toml");
    let text = std::fs::read_to_string(path).unwrap();
    let step = "function = { type = \"step\", time = 0.5, after = 1.0 }";
    assert!(text.contains(step));
    let text = text.replace(
        step,
        "function = { type = \"table\", points = [[0.3, 0.0], [0.55, 1.0], [1.2, 0.4]] }\n\n[[forces]]\nname = \"push\"\nnode = \"mass\"\nforce = [30.0, 0.0, 0.0]\nfunction = { type = \"ramp\", start = 0.7, end = 1.9, to = 1.0 }",
    );
    let text = text.replace("t_end = 5.0", "t_end = 2.5");
    let (s, h) = run(&model(&text));
    assert!(s.failure.is_none(), "{:?}", s.failure);
    for knot in [0.3, 0.55, 0.7, 1.2, 1.9] {
        assert!(
            h.frames.iter().any(|f| (f.time - knot).abs() < 1e-12),
            "no step ends on {knot}"
        );
    }
}

/// A ball bouncing on a linear spring ground without damping (k = 1e5 N/m, m = 1 kg,
/// dropped 0.5 m): between impacts a parabola, in contact `δ(s) = δ_s(1 − cos ωs) +
/// (v₀/ω) sin ωs` (δ_s = mg/k, ω² = k/m), leaving after `t_c = (2π − 2 atan(v₀/(ωδ_s)))/ω`
/// at the impact speed. Returns the centre height at t.
fn bounce_reference(t: f64) -> f64 {
    let (g, k, m, r, gap): (f64, f64, f64, f64, f64) = (9.81, 1e5, 1.0, 0.1, 0.5);
    let (w, ds) = ((k / m).sqrt(), m * g / k);
    let t1 = (2.0 * gap / g).sqrt();
    if t < t1 {
        return r + gap - 0.5 * g * t * t;
    }
    let v0 = g * t1;
    let tc = (2.0 * PI - 2.0 * (v0 / (w * ds)).atan()) / w;
    let tf = 2.0 * v0 / g;
    let s = (t - t1) % (tc + tf);
    if s < tc {
        r - (ds * (1.0 - (w * s).cos()) + v0 / w * (w * s).sin())
    } else {
        let s = s - tc;
        r + v0 * s - 0.5 * g * s * s
    }
}

const BOUNCE: &str = r#"[model]
name = "bounce"
gravity = [0.0, 0.0, -9.81]
[[nodes]]
name = "ball"
position = [0.0, 0.0, 0.6]
[[bodies]]
name = "ball"
node = "ball"
mass = 1.0
inertia = [[0.004, 0.0, 0.0], [0.0, 0.004, 0.0], [0.0, 0.0, 0.004]]
[[contacts]]
name = "ground"
node = "ball"
shape = "sphere"
radius = 0.1
normal = "linear"
stiffness = 1e5
"#;

/// The bouncing ball of [`bounce_reference`] over two impacts (to 1.3 s), adaptive steps.
/// With the contact's closing and opening located (`event_location`, the default: steps
/// end within 10⁻³ h of each zero of the contact's event function, and the scheme restarts
/// from the physical accelerations there) the global error follows ε^(2/3) as for a smooth
/// problem (observed 0.63–0.67 per decade; accepted 0.55 … 0.8). Stepping across the
/// kinks instead, the error is erratic and at ε ≤ 1e-6 over 10× larger (observed 12×, 39×).
#[test]
fn a_bouncing_ball_lands_on_its_impacts() {
    let t_end = 1.3;
    let zr = bounce_reference(t_end);
    let run_at = |tol: f64, locate: bool| {
        let m = with_analysis(
            BOUNCE,
            &format!(
                "t_end = {t_end}\nstep = 1e-3\nmin_step = 1e-9\nrho_inf = 0.9\nstep_control = \"adaptive\"\ntolerance_abs = {tol}\ntolerance_rel = 0.0\nevent_location = {locate}"
            ),
        );
        let (s, h) = run(&m);
        assert!(s.failure.is_none(), "{:?}", s.failure);
        let last = h.frames.last().unwrap();
        let delta: Vec<f64> = h
            .frames
            .iter()
            .map(|f| 0.1 - f.state.nodes[0].x.z)
            .collect();
        ((last.state.nodes[0].x.z - zr).abs(), delta)
    };
    let tols = [1e-4, 1e-5, 1e-6, 1e-7];
    let mut located = Vec::new();
    for tol in tols {
        let (e1, delta) = run_at(tol, true);
        let (e0, _) = run_at(tol, false);
        eprintln!("tolerance {tol:e}: error {e1:.3e} with event location, {e0:.3e} without");
        // Two impacts: four steps across which the penetration δ changes side, each ending
        // on the zero — within 10⁻³ h at ≈ 3 m/s, 3e-6 m for h ≤ 1 ms.
        let crossings: Vec<f64> = delta
            .windows(2)
            .filter(|d| (d[0] > 0.0) != (d[1] > 0.0))
            .map(|d| d[0].abs().min(d[1].abs()))
            .collect();
        assert_eq!(crossings.len(), 4, "tolerance {tol:e}");
        for c in &crossings {
            assert!(
                *c < 1e-5,
                "tolerance {tol:e}: a step ends {c:.2e} m from the contact's edge"
            );
        }
        if tol <= 1e-6 {
            assert!(e0 > 10.0 * e1, "tolerance {tol:e}: {e0:.3e} vs {e1:.3e}");
        }
        located.push(e1);
    }
    for k in 1..located.len() {
        let slope = (located[k - 1] / located[k]).log10();
        assert!(
            (0.55..0.8).contains(&slope),
            "exponent {slope:.3} at {:e}",
            tols[k]
        );
    }
}

/// The smallest number of fixed steps (generalized-α, the adaptive run's ρ∞) on the
/// geometric grid N₀ · 1.1ᵏ from which `settle` consecutive grid points all have an error
/// `error(h)` of at most `target`; that count and its error. The grid starts at a quarter
/// of the adaptive run's count, so a fixed run as cheap as the adaptive one is found if it
/// exists. `settle` > 1 guards against an error that is not monotone in h (a lucky
/// cancellation at one step size is not accepted).
fn fixed_steps_for(
    t_end: f64,
    adaptive_steps: usize,
    target: f64,
    settle: usize,
    error: impl Fn(f64) -> f64,
) -> (usize, f64) {
    let mut n = (adaptive_steps / 4).max(10) as f64;
    let mut run_of_good: Vec<(usize, f64)> = Vec::new();
    loop {
        let steps = n.ceil() as usize;
        let e = error(t_end / steps as f64);
        if e <= target {
            run_of_good.push((steps, e));
            if run_of_good.len() == settle {
                return run_of_good[0];
            }
        } else {
            run_of_good.clear();
        }
        n *= 1.1;
        assert!(
            n < 200.0 * adaptive_steps as f64,
            "fixed steps never reach {target:e}"
        );
    }
}

/// The large-angle pendulum of [`global_error_follows_the_tolerance`] (reference: RK4 with
/// 200,000 steps, error < 1e-12): at tolerances 1e-4 … 1e-7 the adaptive run's global
/// error at 2 s, and the fewest fixed steps (grid of ratio 1.1, so within 10 % of the
/// break-even count; the fixed error ∝ h² is monotone here) that reach it. Measured: the
/// fixed steps need 0.86 of the adaptive count at every tolerance (201/235, 422/491,
/// 1012/1172, 2227/2583) — on a swing with no slow phase, holding the *local* error at ε
/// per step does not beat the even spacing that minimizes the accumulated phase error, and
/// the controller's safety factor and rejected attempts cost the rest. So adaptive steps
/// do not pay here; asserted: the ratio stays in [0.75, 1.25] (a controller that wasted
/// steps, or an error estimate that lost its order, would leave it).
#[test]
fn pendulum_adaptive_steps_against_fixed_steps_at_equal_accuracy() {
    let t_end = 2.0;
    let (xr, zr) = pendulum_reference(t_end);
    let error_of = |analysis: String| {
        let (s, h) = run(&with_analysis(PENDULUM, &analysis));
        assert!(s.failure.is_none());
        let last = h.frames.last().unwrap();
        assert!((last.time - t_end).abs() < 1e-12);
        let x = last.state.nodes[0].x;
        (((x.x - xr).powi(2) + (x.z - zr).powi(2)).sqrt(), s.steps)
    };
    let mut ratios = Vec::new();
    for tol in [1e-4, 1e-5, 1e-6, 1e-7] {
        let (err, steps) = error_of(format!(
            "t_end = {t_end}\nstep = 1e-3\nrho_inf = 0.9\nstep_control = \"adaptive\"\ntolerance_abs = {tol}\ntolerance_rel = 0.0"
        ));
        let (fixed, fixed_err) = fixed_steps_for(t_end, steps, err, 1, |h| {
            error_of(format!(
                "t_end = {t_end}\nstep = {h}\nmin_step = {}\nrho_inf = 0.9\noutput_every = 1000000",
                h / 1024.0
            ))
            .0
        });
        println!(
            "pendulum, tolerance {tol:e}: adaptive {steps} steps, error {err:.3e}; fixed {fixed} steps, error {fixed_err:.3e}; ratio {:.2}",
            fixed as f64 / steps as f64
        );
        ratios.push(fixed as f64 / steps as f64);
    }
    println!("pendulum: fixed/adaptive step ratios {ratios:.3?}");
    for r in &ratios {
        assert!((0.75..=1.25).contains(r), "{ratios:?}");
    }
}

/// The bouncing ball of [`bounce_reference`] (closed form, two impacts, to 1.3 s): the
/// adaptive run with located contact events at tolerances 1e-4, 1e-5 and 1e-6, and the
/// fewest fixed steps (grid of ratio 1.1) whose error at 1.3 s reaches the adaptive one.
/// Fixed steps straddle the contact's closing and opening, where the acceleration jumps,
/// so their error is first order there and erratic in h: the count found must hold at
/// three consecutive grid points (a lucky cancellation is not accepted). Measured: 49,
/// 69, 111 adaptive steps against 3654, 4706, 14565 fixed ones (ratios 75, 68, 131);
/// asserted ≥ 5, the issue's criterion for a problem with fast and slow phases.
#[test]
fn bouncing_ball_adaptive_steps_against_fixed_steps_at_equal_accuracy() {
    let t_end = 1.3;
    let zr = bounce_reference(t_end);
    let error_of = |analysis: String| {
        let (s, h) = run(&with_analysis(BOUNCE, &analysis));
        assert!(s.failure.is_none(), "{:?}", s.failure);
        let last = h.frames.last().unwrap();
        assert!((last.time - t_end).abs() < 1e-12);
        ((last.state.nodes[0].x.z - zr).abs(), s.steps)
    };
    let fixed_error = |h: f64| {
        error_of(format!(
            "t_end = {t_end}\nstep = {h}\nmin_step = {}\nrho_inf = 0.9\noutput_every = 1000000",
            h / 1024.0
        ))
        .0
    };
    let mut ratios = Vec::new();
    for tol in [1e-4, 1e-5, 1e-6] {
        let (err, steps) = error_of(format!(
            "t_end = {t_end}\nstep = 1e-3\nmin_step = 1e-9\nrho_inf = 0.9\nstep_control = \"adaptive\"\ntolerance_abs = {tol}\ntolerance_rel = 0.0"
        ));
        let (fixed, fixed_err) = fixed_steps_for(t_end, steps, err, 3, fixed_error);
        println!(
            "bounce, tolerance {tol:e}: adaptive {steps} steps, error {err:.3e}; fixed {fixed} steps, error {fixed_err:.3e}; ratio {:.2}",
            fixed as f64 / steps as f64
        );
        ratios.push(fixed as f64 / steps as f64);
    }
    println!("bounce: fixed/adaptive step ratios {ratios:.3?}");
    for r in &ratios {
        assert!(*r >= 5.0, "{ratios:?}");
    }
}

/// `examples/adaptive_kick.toml` (the stiff spring–mass with a sudden load; closed form in
/// [`a_fast_transient_then_rest_pays_for_adaptive_steps`]): the largest error over the
/// records against the closed form falls with the tolerance as ε^(2/3) (local error O(h³)
/// held at ε per step: h ∝ ε^(1/3), global error ∝ h²) over three decades, 1e-5 … 1e-8;
/// accepted exponent 0.55 … 0.8 (the pendulum's window), and each decade must lower the
/// error. Measured: 323, 588, 1153, 2375 steps, errors 2.06e-4, 4.74e-5, 1.14e-5,
/// 2.61e-6 m (of a static deflection 3.2e-3 m), exponent 0.632.
#[test]
fn kick_global_error_follows_the_tolerance() {
    use samara::model::AnalysisKind;
    let example = model_file("examples/adaptive_kick.toml");
    let exact = kick_response(&example);
    let tols = [1e-5, 1e-6, 1e-7, 1e-8];
    let mut errors = Vec::new();
    for tol in tols {
        let mut mm = example.clone();
        let AnalysisKind::Dynamic(d) = &mut mm.analyses[0].kind else {
            panic!("dynamic")
        };
        d.adaptive.as_mut().unwrap().tolerance_abs = tol;
        let (s, h) = run(&mm);
        let err = h
            .frames
            .iter()
            .map(|f| (f.state.nodes[0].x.x - exact(f.time)).abs())
            .fold(0.0, f64::max);
        println!(
            "kick, tolerance {tol:e}: {} steps, error {err:.3e}",
            s.steps
        );
        errors.push(err);
    }
    let slope = (errors[0] / errors[3]).log10() / (tols[0] / tols[3]).log10();
    println!("kick: error ∝ tolerance^{slope:.3}");
    assert!(
        (0.55..=0.8).contains(&slope),
        "exponent {slope} ({errors:?})"
    );
    for w in errors.windows(2) {
        assert!(w[1] < w[0], "{errors:?}");
    }
}
