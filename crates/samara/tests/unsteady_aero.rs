//! Unsteady airfoil aerodynamics (issue #15): Wagner's attached-flow states against
//! Theodorsen's function and the Wagner function (both evaluated here from Bessel
//! functions, independently of the model), Øye's dynamic stall against its closed-form
//! first-order response and the static polar, the pitching-airfoil example, and located
//! errors for bad options.

use nalgebra::Complex;
use samara::analysis::{History, run_analysis};
use samara::elements::aero::{Airfoil, OyeStall};
use samara::model::Model;
use samara::system::System;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

type C64 = Complex<f64>;

use crate::common::airfoil_run;
use airfoil_run::{fit, run};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Composite Simpson on [a, b] with n (even) intervals.
fn simpson(f: impl Fn(f64) -> f64, a: f64, b: f64, n: usize) -> f64 {
    let h = (b - a) / n as f64;
    let mut s = f(a) + f(b);
    for k in 1..n {
        s += f(a + k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 };
    }
    s * h / 3.0
}

/// Bessel functions of the first and second kind, orders 0 and 1, from their integral
/// representations (Abramowitz & Stegun 9.1.21 and 9.1.22 / Watson):
/// Jₙ(x) = (1/π)∫₀^π cos(nτ − x sin τ) dτ,
/// Yₙ(x) = (1/π)∫₀^π sin(x sin τ − nτ) dτ − (1/π)∫₀^∞ (e^{nt} + (−1)ⁿe^{−nt}) e^{−x sinh t} dt.
fn bessel(n: i32, x: f64) -> (f64, f64) {
    let nf = n as f64;
    let j = simpson(|t| (nf * t - x * t.sin()).cos(), 0.0, PI, 400) / PI;
    let y1 = simpson(|t| (x * t.sin() - nf * t).sin(), 0.0, PI, 4000) / PI;
    let sign = if n % 2 == 0 { 1.0 } else { -1.0 };
    // e^{−x sinh t} < e^{−60} beyond T.
    let tmax = (60.0 / x).asinh() + 1.0;
    let y2 = simpson(
        |t| ((nf * t).exp() + sign * (-nf * t).exp()) * (-x * t.sinh()).exp(),
        0.0,
        tmax,
        4000,
    ) / PI;
    (j, y1 - y2)
}

/// Theodorsen's function C(k) = H₁⁽²⁾(k)/(H₁⁽²⁾(k) + i H₀⁽²⁾(k)), H⁽²⁾ = J − iY.
fn theodorsen(k: f64) -> C64 {
    let (j0, y0) = bessel(0, k);
    let (j1, y1) = bessel(1, k);
    let h0 = C64::new(j0, -y0);
    let h1 = C64::new(j1, -y1);
    h1 / (h1 + C64::i() * h0)
}

/// The frequency response of R. T. Jones' two-exponential Wagner approximation (the
/// model's states): C_J(k) = 1 − Σ A_i ik/(ik + b_i).
fn jones(k: f64) -> C64 {
    let (a, b) = ([0.165, 0.335], [0.0455, 0.3]);
    let p = C64::new(0.0, k);
    C64::new(1.0, 0.0) - (0..2).map(|i| p * a[i] / (p + b[i])).sum::<C64>()
}

fn jones_wagner(s: f64) -> f64 {
    1.0 - 0.165 * (-0.0455 * s).exp() - 0.335 * (-0.3 * s).exp()
}

/// Wagner's function φ(s) = (2/π)∫₀^∞ F(k)/k sin(ks) dk (F = Re C; Bisplinghoff, Ashley &
/// Halfman, *Aeroelasticity*, §5-7), evaluated as Jones' φ_J plus the transform of
/// F − F_J (both → 1/2 as k → ∞, their difference decays like 1/k²).
fn wagner(s: f64, table: &[(f64, f64)]) -> f64 {
    // table: (k, F(k) − F_J(k)) on a uniform grid from 0, Simpson.
    let h = table[1].0 - table[0].0;
    let n = table.len() - 1;
    let mut sum = 0.0;
    for (i, &(k, d)) in table.iter().enumerate() {
        let f = if k == 0.0 { 0.0 } else { d / k * (k * s).sin() };
        let w = if i == 0 || i == n {
            1.0
        } else if i % 2 == 1 {
            4.0
        } else {
            2.0
        };
        sum += w * f;
    }
    jones_wagner(s) + 2.0 / PI * sum * h / 3.0
}

#[test]
fn theodorsen_function_from_bessel_functions_matches_its_published_table() {
    // Theodorsen (1935), NACA Report 496, as tabulated in Bisplinghoff, Ashley & Halfman
    // (1955), Table 5-1 (four decimals).
    for (k, f, g) in [
        (0.1, 0.8319, -0.1723),
        (0.5, 0.5979, -0.1507),
        (1.0, 0.5394, -0.1003),
    ] {
        let c = theodorsen(k);
        println!("C({k}) = {:.5} {:+.5}i", c.re, c.im);
        assert!(
            (c.re - f).abs() < 2e-3 && (c.im - g).abs() < 2e-3,
            "C({k}) = {c}"
        );
    }
}

/// A flat plate (cl = π sin 2α ≈ 2πα) of chord 1 m on a node, one station at its
/// quarter chord (the node), in a wind of `v` m/s along x, moved by a prescribed joint:
/// `theta2` and `d3` are the drives.
fn plate_model(dir: &Path, v: f64, theta2: &str, d3: &str, t_end: f64, h: f64) -> String {
    let mut csv = String::from("alpha,cl,cd,cm\n");
    for d in -180..=180 {
        let a = (d as f64).to_radians();
        csv += &format!("{d},{:.17},0,0\n", PI * (2.0 * a).sin());
    }
    std::fs::write(dir.join("plate.csv"), csv).unwrap();
    format!(
        r#"[model]
name = "plate"
[[nodes]]
name = "plate"
position = [0.0, 0.0, 0.0]
[[bodies]]
name = "plate"
node = "plate"
mass = 1.0
inertia = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
[[joints]]
name = "drive"
type = "prescribed"
node_a = "ground"
node_b = "plate"
{theta2}
{d3}
[[aero_lines]]
name = "plate"
node = "plate"
root = [0.0, -0.5, 0.0]
tip = [0.0, 0.5, 0.0]
chord_direction = [1.0, 0.0, 0.0]
normal_direction = [0.0, 0.0, 1.0]
wind = {{ speed = {v}, direction = [1.0, 0.0, 0.0], function = {{ type = "step", time = 0.00995, before = 0.0, after = 1.0 }} }}
unsteady = "wagner"
[[aero_lines.stations]]
span = 0.5
chord = 1.0
airfoil = "plate.csv"
[[analyses]]
name = "run"
type = "dynamic"
t_end = {t_end}
step = {h}
"#
    )
}

#[test]
fn wagner_states_give_theodorsen_lift_for_a_pitching_and_plunging_plate() {
    // Thin-airfoil theory (Theodorsen 1935): the circulatory lift of a plate pitching
    // about its quarter chord (a = −½) and plunging is cl = 2π C(k) Q/V, Q = Vα + ḣ + bα̇
    // the downwash at the three-quarter chord (h down), k = ωb/V. The model's states
    // realize Jones' C_J(k) exactly; the time discretization (generalized-α, 400 steps
    // per period, second order) adds ~1e-4. So: the simulated lift against C_J to 2e-3 in
    // amplitude and 0.2° in phase; against the exact C(k) to within Jones' own error at
    // that k (computed here) plus that 2e-3 / 0.2°.
    let dir = tempfile::tempdir().unwrap();
    let (v, b) = (50.0, 0.5);
    let alpha_hat = 0.5f64.to_radians();
    for k in [0.05, 0.2, 0.5, 1.0] {
        let w = k * v / b;
        let period = 2.0 * PI / w;
        let h = period / 400.0;
        // Plunge amplitude: its downwash half the pitch's, a quarter period ahead.
        let z_hat = 0.5 * v * alpha_hat / w;
        let theta2 = format!(
            "[joints.theta2]\ndrive = {{ type = \"sine\", amplitude = {alpha_hat}, frequency = {} }}",
            w / (2.0 * PI)
        );
        let d3 = format!(
            "[joints.d3]\ndrive = {{ type = \"sine\", amplitude = {z_hat}, frequency = {}, phase = {} }}",
            w / (2.0 * PI),
            PI / 2.0
        );
        // The slowest state decays like e^{−b₁(2V/c)t} = e^{−4.55 t}: transient < 1e-5 after 2.5 s.
        let t0 = 2.5;
        let t_end = t0 + 2.0 * period;
        let text = plate_model(dir.path(), v, &theta2, &d3, t_end, h);
        let (t, outs, names, _) = run(&text, dir.path());
        let icl = names.iter().position(|n| n == "plate.0.cl").unwrap();
        let cl: Vec<f64> = outs.iter().map(|o| o[icl]).collect();
        let sim = fit(&t, &cl, w, t0);
        // Q̂ for θ = Im(α̂ e^{iωt}), z = Im(ẑ e^{iωt}), ẑ = z_hat e^{iπ/2}; ḣ = −ż.
        let zc = C64::from_polar(z_hat, PI / 2.0);
        let iw = C64::new(0.0, w);
        let q = C64::new(v * alpha_hat, 0.0) - iw * zc + iw * (b * alpha_hat);
        let cj = jones(k);
        let ce = theodorsen(k);
        let want_j = q * cj * (2.0 * PI / v);
        let want_e = q * ce * (2.0 * PI / v);
        let amp_err_j = sim.norm() / want_j.norm() - 1.0;
        let ph_err_j = (sim / want_j).arg().to_degrees();
        let amp_err_e = sim.norm() / want_e.norm() - 1.0;
        let ph_err_e = (sim / want_e).arg().to_degrees();
        let jones_amp = cj.norm() / ce.norm() - 1.0;
        let jones_ph = (cj / ce).arg().to_degrees();
        println!(
            "k = {k}: |C| = {:.4}, ∠C = {:.2}°; simulation vs C_J: {amp_err_j:+.2e}, {ph_err_j:+.3}°; vs exact C: {amp_err_e:+.2e}, {ph_err_e:+.3}° (Jones' own error {jones_amp:+.2e}, {jones_ph:+.3}°)",
            ce.norm(),
            ce.arg().to_degrees()
        );
        assert!(amp_err_j.abs() < 2e-3 && ph_err_j.abs() < 0.2, "k = {k}");
        assert!(
            amp_err_e.abs() < jones_amp.abs() + 2e-3 && ph_err_e.abs() < jones_ph.abs() + 0.2,
            "k = {k}"
        );
        // Jones' approximation is a good one: within 2.5 % and 1.5° of C(k) (measured:
        // −0.8 %, +1.7 %, −0.7 %, −2.1 % and −0.4°, +0.1°, −1.3°, −0.2° at k = 0.05, 0.2, 0.5, 1).
        assert!(jones_amp.abs() < 0.025 && jones_ph.abs() < 1.5, "k = {k}");
    }
}

#[test]
fn wagner_states_give_the_wagner_function_for_an_impulsive_start() {
    // Wagner (1925): a plate started impulsively at angle α carries the circulatory lift
    // cl(s) = 2πα φ(s), s = 2Vt/c. φ from its integral over Theodorsen's F(k) (Bessel
    // functions above; grid 0…20 in k, step 2.5e-3, Simpson): the reference. The model
    // integrates Jones' φ_J: simulation vs φ_J to 2e-3 (the step enters within one time
    // step, first-order in h = 1e-4 s = 0.01 semichords), vs φ within Jones' error + 2e-3.
    let dir = tempfile::tempdir().unwrap();
    let (v, alpha) = (50.0f64, 1.0f64.to_radians());
    // The wind blows at α to the chord from t = 0.01 s (before: still air).
    let text = plate_model(dir.path(), v, "", "", 0.01 + 0.4, 1e-4).replace(
        "direction = [1.0, 0.0, 0.0], function",
        &format!(
            "direction = [{}, 0.0, {}], function",
            alpha.cos(),
            alpha.sin()
        ),
    );
    let (t, outs, names, _) = run(&text, dir.path());
    let icl = names.iter().position(|n| n == "plate.0.cl").unwrap();
    let n = 8000;
    let table: Vec<(f64, f64)> = (0..=n)
        .map(|i| {
            let k = 20.0 * i as f64 / n as f64;
            if k == 0.0 {
                (0.0, 0.0)
            } else {
                (k, theodorsen(k).re - jones(k).re)
            }
        })
        .collect();
    let cl_inf = PI * (2.0 * alpha).sin();
    let mut worst_jones = 0.0f64;
    for s in [0.5, 1.0, 2.0, 5.0, 10.0, 20.0] {
        // The wind arrives at 0.00995 s, between two steps (±h/2 = ±0.005 semichords).
        let ts = 0.00995 + s / (2.0 * v);
        let i = (0..t.len())
            .min_by(|&a, &b| (t[a] - ts).abs().total_cmp(&(t[b] - ts).abs()))
            .unwrap();
        let sim = outs[i][icl] / cl_inf;
        let exact = wagner(s, &table);
        let pj = jones_wagner(s);
        worst_jones = worst_jones.max((pj - exact).abs());
        println!(
            "s = {s}: simulated {sim:.5}, Jones {pj:.5}, Wagner {exact:.5} (Jones − Wagner {:+.2e})",
            pj - exact
        );
        assert!((sim - pj).abs() < 2e-3, "s = {s}: {sim} vs {pj}");
        assert!((sim - exact).abs() < (pj - exact).abs() + 2e-3, "s = {s}");
    }
    // φ(0⁺) = ½ and φ(∞) = 1 (Wagner): Jones' fit is within 1 % of φ on 0.5 ≤ s ≤ 20.
    assert!((wagner(1e-6, &table) - 0.5).abs() < 1e-3);
    assert!(worst_jones < 0.01, "{worst_jones}");
}

fn du21() -> Airfoil {
    let p = repo().join("reference/nrel5mw/aero/Airfoils/DU21_A17.dat");
    Airfoil::parse(&std::fs::read_to_string(p).unwrap(), false).unwrap()
}

#[test]
fn oye_curves_reproduce_the_static_polar_and_kirchhoff_flow() {
    // At f = f_st the dynamic lift f cl_inv + (1 − f) cl_fs is the static table (Kirchhoff's
    // relation inverted pointwise; cl_inv = cl where the table lifts more): to round-off,
    // 1e-9 over ±30°.
    let af = du21();
    let stall = OyeStall::new(&af).unwrap();
    println!(
        "DU21-A17: α₀ = {:.3}°, c_lα = {:.4}/rad (the file's UA data: α₀ = −4.2°, C_nα = 6.2047)",
        stall.zero_lift.to_degrees(),
        stall.lift_slope
    );
    // The file's own UA data (from the AirfoilPrep of the 5-MW): α₀ within 0.3°. (Its
    // C_nα is the normal-force slope fitted for Beddoes–Leishman, not compared.)
    assert!((stall.zero_lift.to_degrees() + 4.2).abs() < 0.3);
    assert!(stall.lift_slope > 6.0 && stall.lift_slope < 8.0);
    let mut worst = 0.0f64;
    for d in -300..=300 {
        let a = (d as f64 * 0.1).to_radians();
        let sc = stall.eval(a);
        let f = sc.f;
        let cl = f * sc.inv + (1.0 - f) * sc.fs;
        worst = worst.max((cl - af.eval(a).cl).abs());
        assert!((0.0..=1.0).contains(&f));
    }
    println!("max |cl(f_st) − cl_st| over ±30°: {worst:.2e}");
    assert!(worst < 1e-9, "{worst}");
    // Attached flow near α₀: f_st = 1; deep stall (40°): f_st = 0.
    assert!(stall.eval(stall.zero_lift + 0.01).f > 0.95);
    assert_eq!(stall.eval(40f64.to_radians()).f, 0.0);
}

#[test]
fn oye_separation_state_relaxes_with_its_time_constant() {
    // A fixed DU21 section started impulsively in stall (α = 15°, V = 20 m/s, c = 1 m):
    // the separation state starts at f₀ = f_st(0) (still air before t₁: α = 0) and
    // relaxes as f(t) = f_st + (f₀ − f_st) e^{−(t − t₁)/τ}, τ = A_τ c/V = 4/20 = 0.2 s
    // (Øye 1991).
    // Generalized-α at h = τ/800; the wind arrives between two steps (±h/2): 2e-3.
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(
        repo().join("reference/nrel5mw/aero/Airfoils/DU21_A17.dat"),
        dir.path().join("du21.dat"),
    )
    .unwrap();
    let alpha = 15f64.to_radians();
    let text = plate_model(dir.path(), 20.0, "", "", 0.01 + 2.0, 0.00025)
        .replace("unsteady = \"wagner\"", "dynamic_stall = \"oye\"")
        .replace("airfoil = \"plate.csv\"", "airfoil = \"du21.dat\"")
        .replace(
            "direction = [1.0, 0.0, 0.0], function",
            &format!(
                "direction = [{}, 0.0, {}], function",
                alpha.cos(),
                alpha.sin()
            ),
        );
    let (t, outs, names, states) = run(&text, dir.path());
    let icl = names.iter().position(|n| n == "plate.0.cl").unwrap();
    let stall = OyeStall::new(&du21()).unwrap();
    let sc = stall.eval(alpha);
    let (fst, fs) = (sc.f, sc.fs);
    assert!(fst > 0.05 && fst < 0.9, "in stall: f_st = {fst}");
    let tau = 4.0 * 1.0 / 20.0;
    let f0 = states[0][0];
    assert!((f0 - stall.eval(0.0).f).abs() < 1e-12, "{f0}");
    let mut worst = 0.0f64;
    for (i, &ti) in t.iter().enumerate() {
        if ti < 0.01 + 0.02 {
            continue;
        }
        let f = fst + (f0 - fst) * (-(ti - 0.00995) / tau).exp();
        worst = worst.max((states[i][0] - f).abs());
        let cl = f * sc.inv + (1.0 - f) * fs;
        assert!(
            (outs[i][icl] - cl).abs() < 2e-3 * cl.abs().max(1.0),
            "t = {ti}: cl {} vs {cl}, f {} vs {f}",
            outs[i][icl],
            states[i][0]
        );
    }
    println!("separation state vs closed form: max error {worst:.2e}");
    assert!(worst < 2e-3, "{worst}");
    // After 10 τ the lift is the static one (within the interpolation error above).
    let last = outs.last().unwrap()[icl];
    println!("final cl {last:.5}, static {:.5}", du21().eval(alpha).cl);
    assert!((last - du21().eval(alpha).cl).abs() < 2e-3, "{last}");
}

#[test]
fn pitching_airfoil_example_opens_a_dynamic_stall_loop() {
    // The example's DU21 section pitching 0° … 20° at k = 0.1 through its static stall
    // (cl_max ≈ 1.2 near 11°…14°): Øye's lag raises cl above the static maximum on the
    // upstroke and lowers it on the downstroke, so the loop encloses area (clockwise in
    // (α, cl)); Wagner's lag does the same in attached flow. Not compared with
    // measurements here (see docs/aerodynamics.md).
    let path = repo().join("examples/aero/pitching_airfoil.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let dir = path.parent().unwrap();
    let m = Model::from_toml_str(&text, path.clone())
        .unwrap_or_else(|e| panic!("{}", e.render_plain()))
        .model;
    let sys = System::new(&m);
    let mut hist = History::default();
    let s = run_analysis(
        &sys,
        &m.analyses[0],
        sys.initial_state(),
        &mut hist,
        &mut |_| {},
    )
    .unwrap();
    assert!(s.failure.is_none(), "{:?}", s.failure);
    let _ = dir;
    let ia = sys
        .output_names
        .iter()
        .position(|n| n == "foil.0.alpha")
        .unwrap();
    let icl = sys
        .output_names
        .iter()
        .position(|n| n == "foil.0.cl")
        .unwrap();
    let period = 2.0 * PI / 6.0;
    let mut area = 0.0;
    let mut cl_max = f64::MIN;
    let mut prev: Option<(f64, f64)> = None;
    for f in &hist.frames {
        let mut o = vec![0.0; sys.output_names.len()];
        sys.element_outputs(&sys.context(f.time, 1.0), &f.state, &mut o);
        if f.time < 4.0 - period {
            continue;
        }
        let (a, cl) = (o[ia], o[icl]);
        cl_max = cl_max.max(cl);
        if let Some((a0, c0)) = prev {
            area += 0.5 * (cl + c0) * (a - a0);
        }
        prev = Some((a, cl));
    }
    let af = du21();
    let static_max = (0..=20)
        .map(|d| af.eval((d as f64).to_radians()).cl)
        .fold(f64::MIN, f64::max);
    println!(
        "last cycle: loop area ∮cl dα = {area:.4}, cl max {cl_max:.3} (static {static_max:.3})"
    );
    assert!(cl_max > static_max + 0.05, "{cl_max} vs {static_max}");
    assert!(area.abs() > 0.01, "{area}");
}

fn model_error(dir: &Path, text: &str) -> String {
    match Model::from_toml_str(text, dir.join("bad.toml")) {
        Ok(_) => panic!("accepted"),
        Err(e) => e.render_plain(),
    }
}

#[test]
fn bad_unsteady_options_are_located_errors() {
    let dir = tempfile::tempdir().unwrap();
    let good = plate_model(dir.path(), 10.0, "", "", 0.1, 0.01);
    assert!(Model::from_toml_str(&good, dir.path().join("ok.toml")).is_ok());
    let line = |text: &str, key: &str| text.lines().position(|l| l.starts_with(key)).unwrap() + 1;
    // An unknown model name.
    let bad = good.replace("unsteady = \"wagner\"", "unsteady = \"theodorsen\"");
    let e = model_error(dir.path(), &bad);
    assert!(
        e.contains(&format!("bad.toml:{}:", line(&bad, "unsteady"))) && e.contains("wagner"),
        "{e}"
    );
    // A stall time constant ≤ 0, and one without a stall model.
    let bad = good.replace(
        "unsteady = \"wagner\"",
        "dynamic_stall = \"oye\"\nstall_time_constant = -1.0",
    );
    let e = model_error(dir.path(), &bad);
    assert!(
        e.contains("must be > 0")
            && e.contains(&format!("bad.toml:{}:", line(&bad, "stall_time_constant"))),
        "{e}"
    );
    let bad = good.replace("unsteady = \"wagner\"", "stall_time_constant = 3.0");
    let e = model_error(dir.path(), &bad);
    assert!(e.contains("without a dynamic-stall model"), "{e}");
    // Øye's model on a section that does not lift (a cylinder: cl = 0).
    let mut csv = String::from("alpha,cl,cd\n");
    for d in -180..=180 {
        csv += &format!("{d},0,1.2\n");
    }
    std::fs::write(dir.path().join("cylinder.csv"), csv).unwrap();
    let bad = good
        .replace("unsteady = \"wagner\"", "dynamic_stall = \"oye\"")
        .replace("plate.csv", "cylinder.csv");
    let e = model_error(dir.path(), &bad);
    assert!(
        e.contains("no zero-lift angle")
            && e.contains(&format!("bad.toml:{}:", line(&bad, "dynamic_stall"))),
        "{e}"
    );
}

/// Sears & Sparks' approximation of Küssner's function, the model's states' closed form.
fn sears_sparks(s: f64) -> f64 {
    1.0 - 0.5 * (-0.13 * s).exp() - 0.5 * (-s).exp()
}

/// The plate of [`plate_model`] held at α = 0 in a steady wind `v` along the chord, hit at
/// `t0` by a sharp-edged vertical gust `wg` (the wind's `gust`), with Küssner's response.
fn gust_model(dir: &Path, v: f64, wg: f64, t0: f64, t_end: f64, h: f64) -> String {
    plate_model(dir, v, "", "", t_end, h)
        .replace(
            "function = { type = \"step\", time = 0.00995, before = 0.0, after = 1.0 } }",
            &format!(
                "gust = {{ velocity = [0.0, 0.0, {wg}], function = {{ type = \"step\", time = {t0}, before = 0.0, after = 1.0 }} }} }}"
            ),
        )
        .replace("unsteady = \"wagner\"", "unsteady = \"wagner\"\ngust_response = \"kussner\"")
}

#[test]
fn kussner_states_give_the_sharp_edged_gust_response() {
    // A flat plate (cl = π sin 2α, c = 1 m) at α = 0 in a 50 m/s wind meets a vertical
    // sharp-edged gust w_g = 0.5 m/s at t₀: its lift builds as Küssner's function,
    // cl = π sin 2α_E, α_E = atan2(w_g ψ(s), V), s = 2|U|(t − t₀)/c, with ψ the model's
    // Sears–Sparks exponentials 1 − ½e^{−0.13s} − ½e^{−s} (their closed form; the motion
    // part, zero here, goes through Wagner's states). The gust arrives between two grid
    // points; the fixed steps land on it (a breakpoint) and restart there, so the error is
    // second order in h until it meets a floor of 1e-5 … 3e-5 (the lift is
    // compared at the records' times, the nearest to the sample points): at h = 0.1, 0.05
    // and 0.025 semichords it must stay below 2e-3 of the final lift and fall under
    // halving by at least 2× while above 1e-4.
    let dir = tempfile::tempdir().unwrap();
    let (v, wg) = (50.0f64, 0.5f64);
    let speed = (v * v + wg * wg).sqrt();
    let t0 = 0.009975;
    let cl_inf = PI * (2.0 * wg.atan2(v)).sin();
    let mut worst = Vec::new();
    for h in [1e-3, 5e-4, 2.5e-4] {
        let text = gust_model(dir.path(), v, wg, t0, t0 + 0.21, h);
        let (t, outs, names, states) = run(&text, dir.path());
        let icl = names.iter().position(|n| n == "plate.0.cl").unwrap();
        let mut err = 0.0f64;
        for s in [0.25, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0] {
            let ts = t0 + s / (2.0 * speed);
            let i = (0..t.len())
                .min_by(|&a, &b| (t[a] - ts).abs().total_cmp(&(t[b] - ts).abs()))
                .unwrap();
            let si = 2.0 * speed * (t[i] - t0);
            let want = PI * (2.0 * (wg * sears_sparks(si)).atan2(v)).sin();
            let got = outs[i][icl];
            println!(
                "h = {h}: s = {si:.3}: cl/cl∞ simulated {:.5}, Küssner (Sears–Sparks) {:.5}",
                got / cl_inf,
                want / cl_inf
            );
            err = err.max((got - want).abs() / cl_inf);
        }
        // Before the gust: no lift, Küssner and Wagner states at rest.
        let before = t.iter().position(|&x| x > t0).unwrap() - 1;
        assert!(outs[before][icl].abs() < 1e-12);
        assert!(states[before].iter().all(|z| z.abs() < 1e-12));
        // After it: the Wagner states stay at rest (no motion downwash).
        let last = states.last().unwrap();
        assert!(last[0].abs() < 1e-12 && last[1].abs() < 1e-12, "{last:?}");
        println!("h = {h}: worst |cl − cl_K|/cl∞ = {err:.2e}");
        assert!(err < 2e-3, "h = {h}: {err}");
        worst.push(err);
    }
    for w in worst.windows(2) {
        assert!(
            w[1] < 0.5 * w[0] || w[0] < 1e-4,
            "no convergence: {worst:?}"
        );
    }
}

#[test]
fn kussner_keeps_the_wagner_response_to_motion() {
    // With Küssner's gust response on and no gust acting (the gust's function 0), the
    // plate pitching at k = 0.2 gives the same lift as with Wagner alone (the motion goes
    // through Wagner's states unchanged; the Küssner states stay exactly 0): equal to the
    // Newton tolerance, 1e-9 of the peak.
    let dir = tempfile::tempdir().unwrap();
    let (v, b, k) = (50.0, 0.5, 0.2);
    let w = k * v / b;
    let alpha_hat = 0.5f64.to_radians();
    let theta2 = format!(
        "[joints.theta2]\ndrive = {{ type = \"sine\", amplitude = {alpha_hat}, frequency = {} }}",
        w / (2.0 * PI)
    );
    let period = 2.0 * PI / w;
    let base = plate_model(dir.path(), v, &theta2, "", 2.0 * period, period / 100.0).replace(
        ", function = { type = \"step\", time = 0.00995, before = 0.0, after = 1.0 } }",
        " }",
    );
    let with = base
        .replace(
            "direction = [1.0, 0.0, 0.0] }",
            "direction = [1.0, 0.0, 0.0], gust = { velocity = [0.0, 0.0, 1.0], function = { type = \"constant\", value = 0.0 } } }",
        )
        .replace("unsteady = \"wagner\"", "unsteady = \"wagner\"\ngust_response = \"kussner\"");
    assert!(
        with.contains("kussner") && with.contains("gust ="),
        "{with}"
    );
    let (_, a, na, _) = run(&base, dir.path());
    let (_, g, ng, _) = run(&with, dir.path());
    let ia = na.iter().position(|n| n == "plate.0.cl").unwrap();
    let ig = ng.iter().position(|n| n == "plate.0.cl").unwrap();
    assert_eq!(a.len(), g.len());
    let peak = a.iter().map(|o| o[ia].abs()).fold(0.0, f64::max);
    assert!(peak > 0.01);
    for (x, y) in a.iter().zip(&g) {
        assert!(
            (x[ia] - y[ig]).abs() < 1e-9 * peak,
            "{} vs {}",
            x[ia],
            y[ig]
        );
    }
}

#[test]
fn bad_gust_options_are_located_errors() {
    let dir = tempfile::tempdir().unwrap();
    let good = gust_model(dir.path(), 10.0, 0.5, 0.05, 0.1, 0.01);
    assert!(Model::from_toml_str(&good, dir.path().join("ok.toml")).is_ok());
    let line = |text: &str, key: &str| text.lines().position(|l| l.starts_with(key)).unwrap() + 1;
    // Küssner without Wagner's states.
    let bad = good.replace("unsteady = \"wagner\"\n", "");
    let e = model_error(dir.path(), &bad);
    assert!(
        e.contains("without `unsteady = \"wagner\"`")
            && e.contains(&format!("bad.toml:{}:", line(&bad, "gust_response"))),
        "{e}"
    );
    // Küssner with no gust in the wind.
    let bad = plate_model(dir.path(), 10.0, "", "", 0.1, 0.01).replace(
        "unsteady = \"wagner\"",
        "unsteady = \"wagner\"\ngust_response = \"kussner\"",
    );
    let e = model_error(dir.path(), &bad);
    assert!(
        e.contains("has no `gust`")
            && e.contains(&format!("bad.toml:{}:", line(&bad, "gust_response"))),
        "{e}"
    );
    // An unknown response, a non-finite gust.
    let bad = good.replace("gust_response = \"kussner\"", "gust_response = \"sears\"");
    assert!(model_error(dir.path(), &bad).contains("sears"));
    let bad = good.replace("velocity = [0.0, 0.0, 0.5]", "velocity = [0.0, 0.0, nan]");
    let e = model_error(dir.path(), &bad);
    assert!(e.contains("finite") || e.contains("velocity"), "{e}");
}

/// Sears' function S(k) = [J₀(k) − iJ₁(k)] C(k) + iJ₁(k): the lift of a flat plate in a
/// sinusoidal vertical gust w = ŵ e^{iω(t − x/V)}, cl = 2π (ŵ/V) S(k) e^{iωt}, referred to
/// the gust at the mid-chord x = 0 of this formula (Sears 1941; Bisplinghoff, Ashley &
/// Halfman, *Aeroelasticity*, §5-7). C(k) and J₀, J₁ from the Bessel functions above.
fn sears(k: f64) -> C64 {
    let (j0, _) = bessel(0, k);
    let (j1, _) = bessel(1, k);
    C64::new(j0, -j1) * theodorsen(k) + C64::new(0.0, j1)
}

/// The frequency response of the model's Küssner states (Sears & Sparks' exponentials),
/// referred to the gust where the states read it (the leading edge, where ψ's front starts):
/// K(k) = ik ∫₀^∞ ψ(s) e^{−iks} ds = 1 − Σ A_i ik/(ik + b_i).
fn sears_sparks_response(k: f64) -> C64 {
    let (a, b) = ([0.5, 0.5], [0.13, 1.0]);
    let p = C64::new(0.0, k);
    C64::new(1.0, 0.0) - (0..2).map(|i| p * a[i] / (p + b[i])).sum::<C64>()
}

/// The plate of [`plate_model`] held at α = 0 in a steady wind `v` along the chord, its
/// wind given the extra keys `wind_keys` (a gust, or a `turbsim` box instead of `speed`),
/// with Küssner's gust response.
fn kussner_model(dir: &Path, v: f64, wind_keys: &str, t_end: f64, h: f64) -> String {
    plate_model(dir, v, "", "", t_end, h)
        .replace(
            "function = { type = \"step\", time = 0.00995, before = 0.0, after = 1.0 } }",
            &format!("{wind_keys} }}"),
        )
        .replace(
            "unsteady = \"wagner\"",
            "unsteady = \"wagner\"\ngust_response = \"kussner\"",
        )
}

use crate::common::bts;

#[test]
fn kussner_states_give_the_sears_lift_for_a_convected_sinusoidal_gust() {
    // A flat plate (c = 2b = 1 m, cl = π sin 2α) at α = 0 in V = 50 m/s meets a vertical
    // gust convected with the flow, w = ŵ sin ω(t − x/V) (the wind's `gust` with
    // `convection_speed = V`), ŵ = 0.25 m/s. Thin-airfoil theory: cl = 2π (ŵ/V) S(k)
    // referred to the gust at the mid-chord (x = +b/2 here: the station, the quarter chord,
    // is at x = 0). The model's Küssner states read the gust at the leading edge
    // x = −b/2, so their lift is 2π (ŵ/V) K(k) e^{ik/2} (K the exponentials' response,
    // the leading edge b/(2V) ahead of x = 0), the exact one 2π (ŵ/V) S(k) e^{−ik/2}:
    // the approximation's own error is K(k) e^{ik}/S(k) − 1 (computed here).
    // Tolerances: against the model's K, 2e-3 in amplitude and 0.2° in phase (400 steps per
    // period, second order, as the Wagner test; the α nonlinearity adds ≈ 2e-5); against
    // Sears' S, the approximation's error plus the same.
    // Then the same gust carried by a periodic TurbSim box (w = ŵ sin ωτ about a
    // uniform 50 m/s mean, τ = t − x/u_hub: the turbulence about the box's mean goes
    // through Küssner's states), at k = 0.2, with 200 box steps per period: its linear
    // interpolation in time scales the amplitude by ≈ 1 − (ω dt)²/12 = 1 − 8e-5.
    let dir = tempfile::tempdir().unwrap();
    let (v, b, wg) = (50.0f64, 0.5f64, 0.25f64);
    let check = |k: f64, text: &str, w: f64, t0: f64, what: &str| -> (f64, f64) {
        let (t, outs, names, _) = run(text, dir.path());
        let icl = names.iter().position(|n| n == "plate.0.cl").unwrap();
        let cl: Vec<f64> = outs.iter().map(|o| o[icl]).collect();
        let sim = fit(&t, &cl, w, t0);
        let scale = 2.0 * PI * wg / v;
        let model = sears_sparks_response(k) * C64::from_polar(scale, 0.5 * k);
        let exact = sears(k) * C64::from_polar(scale, -0.5 * k);
        let amp_m = sim.norm() / model.norm() - 1.0;
        let ph_m = (sim / model).arg().to_degrees();
        let amp_e = sim.norm() / exact.norm() - 1.0;
        let ph_e = (sim / exact).arg().to_degrees();
        let own = model / exact;
        let (own_amp, own_ph) = (own.norm() - 1.0, own.arg().to_degrees());
        let s = sears(k);
        println!(
            "{what} k = {k}: |S| = {:.4}, ∠S = {:.2}°; simulation vs Sears–Sparks K: {amp_m:+.2e}, {ph_m:+.3}°; vs Sears S: {amp_e:+.2e}, {ph_e:+.2}° (the exponentials' own error {own_amp:+.2e}, {own_ph:+.2}°)",
            s.norm(),
            s.arg().to_degrees()
        );
        assert!(amp_m.abs() < 2e-3 && ph_m.abs() < 0.2, "{what} k = {k}");
        assert!(
            amp_e.abs() < own_amp.abs() + 2e-3 && ph_e.abs() < own_ph.abs() + 0.2,
            "{what} k = {k}"
        );
        (own_amp, own_ph)
    };
    for k in [0.05, 0.2, 0.5, 1.0] {
        let w = k * v / b;
        let period = 2.0 * PI / w;
        // The slowest Küssner pole decays like e^{−0.13 (2V/c) t} = e^{−13 t}: < 1e-8 at 1.5 s.
        // The sine starts at θ = t + b/(2V) = 0, before the run, at the leading edge.
        let t0 = 1.5;
        let gust = format!(
            "gust = {{ velocity = [0.0, 0.0, {wg}], function = {{ type = \"sine\", amplitude = 1.0, frequency = {} }}, convection_speed = {v} }}",
            w / (2.0 * PI)
        );
        let text = kussner_model(dir.path(), v, &gust, t0 + 2.0 * period, period / 400.0);
        let (own_amp, own_ph) = check(k, &text, w, t0, "gust");
        // Sears & Sparks' fit is that of the exact response within 5 % and 13° up to
        // k = 1 (measured: +4.3 %, −0.7° at k = 0.05; −1.6 %, −3.0° at 0.2; +2.3 %, −3.3°
        // at 0.5; +4.4 %, −12.1° at 1).
        assert!(own_amp.abs() < 0.05 && own_ph.abs() < 13.0, "k = {k}");
    }
    // The box: 2 × 2 points 2 m apart around the plate (y, z = −1 … 1 m), 400 steps over
    // two periods of the k = 0.2 wave, u = 50, v = 0, w = ŵ sin ωτ.
    let k = 0.2;
    let period = 2.0 * PI / (k * v / b);
    let dt = (period / 200.0) as f32;
    let w = 2.0 * PI / (200.0 * dt as f64);
    let boxed = bts::Box3 {
        periodic: true,
        ny: 2,
        nz: 2,
        nt: 400,
        n_tower: 0,
        dy: 2.0,
        dz: 2.0,
        dt,
        mean_speed: v as f32,
        hub_height: 0.0,
        grid_bottom: -1.0,
        slope: [600.0, 1000.0, 1e5],
        offset: [0.0; 3],
    };
    std::fs::write(
        dir.path().join("wave.bts"),
        boxed.bytes(|_, _, tau| [v, 0.0, wg * (w * tau).sin()]),
    )
    .unwrap();
    let text = kussner_model(dir.path(), v, "", 1.5 + 2.0 * period, period / 400.0).replace(
        &format!("speed = {v}, direction = [1.0, 0.0, 0.0], "),
        "turbsim = \"wave.bts\", direction = [1.0, 0.0, 0.0]",
    );
    assert!(text.contains("wave.bts"), "{text}");
    check(k, &text, w, 1.5, "TurbSim box");
}

#[test]
fn a_convected_gust_front_reaches_two_stations_delta_x_over_u_apart() {
    // Two plates (c = 1 m, cl = π sin 2α, α = 0) at x = 0 and x = Δx = 2 m in V = 50 m/s
    // meet a sharp-edged vertical gust front w_g = 0.5 m/s convected at V (`convection_speed
    // = 50`) that crosses x = 0 at t₀: each plate's lift builds as Küssner's function
    // (Sears–Sparks' exponentials, the model's closed form) from the time the front
    // reaches its leading edge, x_LE = x − c/4: cl = π sin 2 atan(w_g ψ(s)/V),
    // s = 2|U|(t − t₀ − x_LE/V)/c, i.e. the second plate's lift is the first's delayed by
    // Δx/V = 0.04 s. Tolerance as the uniform sharp-edged gust: 2e-3 of the final lift,
    // shrinking when the step halves (the fronts arrive between steps). Without
    // `convection_speed` (a uniform gust) the two lifts are equal.
    let dir = tempfile::tempdir().unwrap();
    let (v, wg, dx) = (50.0f64, 0.5f64, 2.0f64);
    let speed = (v * v + wg * wg).sqrt();
    let t0 = 0.010025;
    let cl_inf = PI * (2.0 * wg.atan2(v)).sin();
    let two_plates = |text: String| -> String {
        let second = text
            .split("[[aero_lines]]")
            .nth(1)
            .unwrap()
            .split("[[analyses]]")
            .next()
            .unwrap()
            .replace("name = \"plate\"", "name = \"aft\"")
            .replace(
                "root = [0.0, -0.5, 0.0]",
                &format!("root = [{dx}, -0.5, 0.0]"),
            )
            .replace("tip = [0.0, 0.5, 0.0]", &format!("tip = [{dx}, 0.5, 0.0]"))
            .replace("node = \"aft\"", "node = \"plate\"");
        text.replace(
            "[[analyses]]",
            &format!("[[aero_lines]]{second}[[analyses]]"),
        )
    };
    let gust = |convected: bool| {
        format!(
            "gust = {{ velocity = [0.0, 0.0, {wg}], function = {{ type = \"step\", time = {t0}, before = 0.0, after = 1.0 }}{} }}",
            if convected {
                format!(", convection_speed = {v}")
            } else {
                String::new()
            }
        )
    };
    let mut worst = Vec::new();
    for h in [1e-3, 5e-4, 2.5e-4] {
        let text = two_plates(kussner_model(dir.path(), v, &gust(true), t0 + 0.25, h));
        assert_eq!(text.matches("[[aero_lines]]").count(), 2, "{text}");
        let (t, outs, names, _) = run(&text, dir.path());
        let mut err = 0.0f64;
        for (line, x) in [("plate", 0.0), ("aft", dx)] {
            let icl = names
                .iter()
                .position(|n| *n == format!("{line}.0.cl"))
                .unwrap();
            let arrival = t0 + (x - 0.25) / v;
            for s in [0.25, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0] {
                let ts = arrival + s / (2.0 * speed);
                let i = (0..t.len())
                    .min_by(|&a, &b| (t[a] - ts).abs().total_cmp(&(t[b] - ts).abs()))
                    .unwrap();
                let si = 2.0 * speed * (t[i] - arrival);
                let want = PI * (2.0 * (wg * sears_sparks(si)).atan2(v)).sin();
                err = err.max((outs[i][icl] - want).abs() / cl_inf);
            }
            // Nothing before the front arrives.
            let before = t.iter().position(|&x| x > arrival).unwrap() - 1;
            assert!(
                outs[before][icl].abs() < 1e-12,
                "{line}: cl = {} at t = {} (arrival {arrival})",
                outs[before][icl],
                t[before]
            );
        }
        println!("h = {h}: worst |cl − cl_K(t − x_LE/V)|/cl∞ over both plates = {err:.2e}");
        assert!(err < 2e-3, "h = {h}: {err}");
        worst.push(err);
    }
    for w in worst.windows(2) {
        assert!(
            w[1] < 0.5 * w[0] || w[0] < 1e-4,
            "no convergence: {worst:?}"
        );
    }
    // A uniform gust (no convection speed) lifts both plates at once.
    let text = two_plates(kussner_model(dir.path(), v, &gust(false), t0 + 0.05, 1e-4));
    let (_, outs, names, _) = run(&text, dir.path());
    let ia = names.iter().position(|n| n == "plate.0.cl").unwrap();
    let ib = names.iter().position(|n| n == "aft.0.cl").unwrap();
    let last = outs.last().unwrap();
    assert!(last[ia] > 0.3 * cl_inf && (last[ia] - last[ib]).abs() < 1e-12 * cl_inf);
}

#[test]
fn bad_convected_gusts_are_located_errors() {
    let dir = tempfile::tempdir().unwrap();
    let gust = |uc: &str| {
        format!(
            "gust = {{ velocity = [0.0, 0.0, 0.5], function = {{ type = \"step\", time = 0.05, before = 0.0, after = 1.0 }}, convection_speed = {uc} }}"
        )
    };
    let good = kussner_model(dir.path(), 10.0, &gust("10.0"), 0.1, 0.01);
    assert!(Model::from_toml_str(&good, dir.path().join("ok.toml")).is_ok());
    let line = |text: &str| text.lines().position(|l| l.starts_with("wind =")).unwrap() + 1;
    for uc in ["0.0", "-5.0"] {
        let bad = kussner_model(dir.path(), 10.0, &gust(uc), 0.1, 0.01);
        let e = model_error(dir.path(), &bad);
        assert!(
            e.contains("gust `convection_speed`")
                && e.contains("must be finite and > 0")
                && e.contains(&format!("bad.toml:{}:", line(&bad))),
            "{uc}: {e}"
        );
    }
    // Non-finite numbers are refused by the reader, at the number.
    for uc in ["nan", "inf"] {
        let bad = kussner_model(dir.path(), 10.0, &gust(uc), 0.1, 0.01);
        let e = model_error(dir.path(), &bad);
        assert!(
            e.contains("outside the range") && e.contains(&format!("bad.toml:{}:", line(&bad))),
            "{uc}: {e}"
        );
    }
    let bad = kussner_model(dir.path(), 10.0, &gust("\"fast\""), 0.1, 0.01);
    assert!(model_error(dir.path(), &bad).contains("bad.toml"));
}

#[test]
fn kussner_leaves_a_steady_box_to_wagner() {
    // A TurbSim box constant in time (u = 50, w = 0.5 m/s everywhere) has no turbulence
    // about its time mean: with Küssner's response the whole downwash goes through
    // Wagner's states. The plate at α = 0 sees w from the start: every state starts at its
    // quasi-steady value and stays there, Küssner's at 0 (to 1e-15: the box mean of equal
    // int16 samples is the sample itself; the trilinear and bilinear weights sum to 1 to
    // rounding) and Wagner's at A_i w (to 1e-12), and the lift
    // stays at its first value (to 1e-12), the static cl = π sin 2 atan(w/u) to within the
    // table's interpolation between its 1° knots (1e-4).
    let dir = tempfile::tempdir().unwrap();
    let (v, wg) = (50.0f64, 0.5f64);
    let boxed = bts::Box3 {
        periodic: true,
        ny: 2,
        nz: 2,
        nt: 8,
        n_tower: 0,
        dy: 2.0,
        dz: 2.0,
        dt: 0.1,
        mean_speed: v as f32,
        hub_height: 0.0,
        grid_bottom: -1.0,
        slope: [600.0, 1000.0, 1e4],
        offset: [0.0; 3],
    };
    std::fs::write(
        dir.path().join("steady.bts"),
        boxed.bytes(|_, _, _| [v, 0.0, wg]),
    )
    .unwrap();
    let text = kussner_model(dir.path(), v, "", 0.2, 1e-3).replace(
        &format!("speed = {v}, direction = [1.0, 0.0, 0.0], "),
        "turbsim = \"steady.bts\", direction = [1.0, 0.0, 0.0]",
    );
    assert!(
        text.contains("steady.bts") && text.contains("kussner"),
        "{text}"
    );
    let (_, outs, names, states) = run(&text, dir.path());
    let icl = names.iter().position(|n| n == "plate.0.cl").unwrap();
    let cl = outs[0][icl];
    assert!(
        (cl / (PI * (2.0 * wg.atan2(v)).sin()) - 1.0).abs() < 1e-4,
        "{cl}"
    );
    for (o, z) in outs.iter().zip(&states) {
        assert!((o[icl] - cl).abs() < 1e-12 * cl, "{} vs {cl}", o[icl]);
        assert!(
            (z[0] - 0.165 * wg).abs() < 1e-12 && (z[1] - 0.335 * wg).abs() < 1e-12,
            "{z:?}"
        );
        assert!(z[2].abs() < 1e-15 && z[3].abs() < 1e-15, "{z:?}");
    }
}
