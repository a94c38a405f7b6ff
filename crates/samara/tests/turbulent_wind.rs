//! Turbulent wind from TurbSim `.bts` files (issue #15; docs/aerodynamics.md, "Turbulent
//! wind"): a box written from an analytic field (tests/common/bts.rs, the layout
//! InflowWind reads) sampled where the stations are, Taylor's frozen turbulence, the rigid
//! NREL 5-MW rotor run in a box, and located errors for bad files and boxes too small.

use nalgebra::Vector3;
use samara::analysis::{History, run_analysis};
use samara::core::{ElementInput, EvalContext};
use samara::model::Model;
use samara::model::components::{Build, build_all, initial_nodes};
use samara::system::System;
use std::path::Path;

use crate::common::bts;
use bts::Box3;

fn repo() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A box over the NREL 5-MW rotor (hub at z = 90 m, R = 63 m): 17 × 17 points 8 m apart
/// (y = −64 … 64 m, z = 26 … 154 m), 32 steps of 0.25 s, u_hub = 11.5 m/s, u, v, w to
/// 1/1000 m/s (int16 rounding ≤ 5e-4 m/s).
fn rotor_box(periodic: bool) -> Box3 {
    Box3 {
        periodic,
        ny: 17,
        nz: 17,
        nt: 32,
        n_tower: 0,
        dy: 8.0,
        dz: 8.0,
        dt: 0.25,
        mean_speed: 11.5,
        hub_height: 90.0,
        grid_bottom: 26.0,
        slope: [1000.0; 3],
        offset: [0.0; 3],
    }
}

/// u = U + a y + b z + c τ (and v, w alike): linear, so trilinear interpolation is exact
/// and only the int16 rounding remains.
fn linear_field(y: f64, z: f64, tau: f64) -> [f64; 3] {
    [
        11.5 + 0.01 * y + 0.02 * (z - 90.0) + 0.1 * tau,
        0.5 - 0.02 * y + 0.005 * z - 0.05 * tau,
        -0.3 + 0.004 * y - 0.01 * (z - 90.0) + 0.08 * tau,
    ]
}

/// The rigid NREL 5-MW example with `wind` on every blade, `inflow` kept or removed, the
/// analysis ending at `t_end`, in `dir` (AeroDyn files by absolute path).
fn rotor_model(wind: &str, bem: bool, t_end: f64) -> String {
    let text = std::fs::read_to_string(repo().join("examples/rotor/nrel5mw_rotor.toml")).unwrap();
    let ad = repo().join("reference/nrel5mw/aero/NRELOffshrBsline5MW_Onshore_AeroDyn15.dat");
    let mut out = String::new();
    for l in text.lines() {
        let l = if l.starts_with("aerodyn = ") {
            format!("aerodyn = {:?}", ad.to_str().unwrap())
        } else if l.starts_with("wind = ") {
            wind.to_string()
        } else if l.starts_with("inflow = ") && !bem {
            continue;
        } else if l.starts_with("t_end = ") {
            format!("t_end = {t_end}")
        } else if l.starts_with("step = ") {
            "step = 0.02".to_string()
        } else {
            l.to_string()
        };
        out += &l;
        out.push('\n');
    }
    out
}

fn load(dir: &Path, text: &str) -> Model {
    match Model::from_toml_str(text, dir.join("model.toml")) {
        Ok(l) => l.model,
        Err(e) => panic!("{}", e.render_plain()),
    }
}

fn model_error(dir: &Path, text: &str) -> String {
    match Model::from_toml_str(text, dir.join("bad.toml")) {
        Ok(_) => panic!("accepted"),
        Err(e) => e.render_plain(),
    }
}

fn ctx(t: f64) -> EvalContext {
    EvalContext {
        time: t,
        gravity: Vector3::zeros(),
        load_factor: 1.0,
    }
}

#[test]
fn stations_sample_the_box_of_an_analytic_field_within_the_int16_rounding() {
    let dir = tempfile::tempdir().unwrap();
    let b = rotor_box(false);
    std::fs::write(dir.path().join("box.bts"), b.bytes(linear_field)).unwrap();
    let m = load(
        dir.path(),
        &rotor_model("wind = { turbsim = \"box.bts\" }", false, 1.0),
    );
    let wind = &m.aero_lines[0].wind;
    let f = wind.turbulence.as_ref().expect("a turbulent wind");
    // The header as written.
    assert_eq!(
        (f.ny, f.nz, f.nt, f.n_tower, f.periodic),
        (17, 17, 32, 0, false)
    );
    assert_eq!((f.dy, f.dz, f.dt, f.mean_speed), (8.0, 8.0, 0.25, 11.5));
    assert_eq!((f.hub_height, f.grid_bottom), (90.0, 26.0));
    assert_eq!(f.description, "written by samara's tests");
    // Every line shares the one box read.
    assert!(std::sync::Arc::ptr_eq(
        f,
        m.aero_lines[2].wind.turbulence.as_ref().unwrap()
    ));
    // Each component rounds to the nearest 1/slope: |error| ≤ 1/(2·1000) m/s, and the
    // trilinear weights (≥ 0, summing to 1) keep that bound. x₀ = half the width, 64 m.
    let bound = 0.5 / 1000.0 + 1e-12;
    let exact = |p: Vector3<f64>, t: f64| {
        let tau = t + (64.0 - p.x) / 11.5;
        let [u, v, w] = linear_field(p.y, p.z, tau);
        // Wind frame: x = +x (direction), z up, y = z × x = +y.
        Vector3::new(u, v, w)
    };
    let mut worst: f64 = 0.0;
    let mut seed = 12345u64;
    let mut rnd = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    for _ in 0..500 {
        let p = Vector3::new(
            -5.0 + 10.0 * rnd(),
            -64.0 + 128.0 * rnd(),
            26.0 + 128.0 * rnd(),
        );
        let t = 1.5 * rnd();
        let w = Vector3::from(wind.velocity(&[p.x, p.y, p.z], t));
        worst = worst.max((w - exact(p, t)).amax());
    }
    println!("wind: worst component error {worst:.2e} m/s (bound {bound:.1e})");
    assert!(worst <= bound, "{worst}");
    assert!(worst > 1e-5, "the rounding is there: {worst}");
    // The stations (no induction): relative speed |U − (U·ŝ)ŝ| in the section (strip
    // theory drops the spanwise flow along the line ŝ), U = W(p, t) − ṗ at their own
    // points, ṗ = ω × (p − hub) of the spinning rigid rotor; | |a| − |b| | ≤ |a − b| ≤
    // √3 bound.
    let initial = initial_nodes(&m);
    let mut parts = Build::new(&initial);
    build_all(&m, &mut parts);
    let omega = Vector3::new(1.267109, 0.0, 0.0);
    let hub = Vector3::new(0.0, 0.0, 90.0);
    let mut worst: f64 = 0.0;
    let mut n = 0;
    for (k, line) in m.aero_lines.iter().enumerate() {
        let (root, tip) = match k {
            0 => (Vector3::new(0.0, 0.0, 91.5), Vector3::new(0.0, 0.0, 153.0)),
            1 => (
                Vector3::new(0.0, -1.299038106, 89.25),
                Vector3::new(0.0, -54.559600438, 58.5),
            ),
            _ => (
                Vector3::new(0.0, 1.299038106, 89.25),
                Vector3::new(0.0, 54.559600438, 58.5),
            ),
        };
        for (j, s) in line.stations.iter().enumerate() {
            let name = format!("{}.{j}", line.name);
            let e = parts.elements.iter().find(|e| e.name() == name).unwrap();
            let p = root + (tip - root).normalize() * s.span;
            let pd = omega.cross(&(p - hub));
            for t in [0.0, 0.37, 1.0] {
                let mut out = vec![0.0; e.output_names().len()];
                e.outputs(&ctx(t), &ElementInput::nodes(&initial), &mut out);
                let u = exact(p, t) - pd;
                let sdir = (tip - root).normalize();
                let exact_speed = (u - sdir * u.dot(&sdir)).norm();
                worst = worst.max((out[1] - exact_speed).abs());
                n += 1;
            }
        }
    }
    println!("{n} station samples: worst relative-speed error {worst:.2e} m/s");
    assert!(n == 3 * 19 * 3);
    assert!(worst <= 3f64.sqrt() * bound, "{worst}");
}

/// A non-linear field: every grid value distinct.
fn wavy_field(y: f64, z: f64, tau: f64) -> [f64; 3] {
    [
        10.0 + (0.3 * y).sin() + (0.2 * z).cos() + (1.7 * tau).sin(),
        (0.1 * y * z).sin() + 0.5 * (2.3 * tau).cos(),
        (0.05 * y + 0.4 * tau).cos() * (0.1 * z).sin(),
    ]
}

#[test]
fn frozen_turbulence_advects_the_box_at_the_hub_speed() {
    let dir = tempfile::tempdir().unwrap();
    for periodic in [false, true] {
        // 48 steps: the blade at y = −54.6 m sits 27 m upstream in the turned frame.
        let b = Box3 {
            nt: 48,
            ..rotor_box(periodic)
        };
        let name = format!("box{}.bts", periodic as u8);
        std::fs::write(dir.path().join(&name), b.bytes(wavy_field)).unwrap();
        // The wind blowing 30° off x (horizontal): the box's frame turns with it.
        let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
        let m = load(
            dir.path(),
            &rotor_model(
                &format!("wind = {{ turbsim = \"{name}\", direction = [{c}, {s}, 0.0] }}"),
                false,
                0.5,
            ),
        );
        let wind = &m.aero_lines[0].wind;
        let f = wind.turbulence.as_ref().unwrap();
        let d = Vector3::new(c, s, 0.0);
        let lat = Vector3::new(-s, c, 0.0);
        // u(x, t) = u(0, t − x/U): a point s metres downstream sees, at t, what the point
        // at x = 0 saw s/U earlier (to round-off: 1e-12 m/s).
        let mut worst: f64 = 0.0;
        for (k, dx) in [0.0, 3.0, -7.5, 20.0].into_iter().enumerate() {
            for t in [0.2, 0.9, 1.3] {
                let p0 =
                    lat * (-40.0 + 9.0 * k as f64) + Vector3::new(0.0, 0.0, 40.0 + 23.0 * k as f64);
                let p = p0 + d * dx;
                let a = Vector3::from(wind.velocity(&[p.x, p.y, p.z], t));
                let b = Vector3::from(wind.velocity(&[p0.x, p0.y, p0.z], t - dx / 11.5));
                worst = worst.max((a - b).amax());
            }
        }
        println!("periodic {periodic}: frozen-turbulence mismatch {worst:.1e} m/s");
        assert!(worst < 1e-12, "{worst}");
        // At a grid point and a sample time the wind is the stored sample, turned into the
        // global frame: u along the wind, v along z × wind, w up (y fastest in the file).
        let (iy, iz, it) = (3, 11, 9);
        let tau = b.t(it);
        let x = f.start_x() - (tau - 0.4) * 11.5; // seen at t = 0.4
        let p = d * x + lat * b.y(iy) + Vector3::new(0.0, 0.0, b.z(iz));
        let got = Vector3::from(wind.velocity(&[p.x, p.y, p.z], 0.4));
        let [u, v, w] = wavy_field(b.y(iy), b.z(iz), tau);
        let want = d * u + lat * v + Vector3::new(0.0, 0.0, w);
        println!("grid point: {got:?} vs {want:?}");
        assert!((got - want).amax() <= 0.5e-3 + 1e-9, "{got} {want}");
        if periodic {
            // One period (NT·dt = 12 s) later the same wind.
            let q = Vector3::new(1.0, -20.0, 100.0);
            let a = Vector3::from(wind.velocity(&[q.x, q.y, q.z], 0.3));
            let b2 = Vector3::from(wind.velocity(&[q.x, q.y, q.z], 12.3));
            assert!((a - b2).amax() < 1e-9, "{a} {b2}");
            assert_eq!(f.span(), 12.0);
        } else {
            assert_eq!(f.span(), 11.75);
        }
    }
}

/// Runs the model's first analysis; returns the summary and history.
fn run(m: &Model) -> (samara::analysis::AnalysisSummary, History, System) {
    let sys = System::new(m);
    let mut hist = History::default();
    let s = run_analysis(
        &sys,
        &m.analyses[0],
        sys.initial_state(),
        &mut hist,
        &mut |_| {},
    )
    .unwrap();
    (s, hist, sys)
}

#[test]
fn nrel5mw_rotor_in_a_uniform_box_runs_as_in_the_steady_wind() {
    // A box holding u = 11.4 m/s everywhere (11400/1000 exactly in int16) and BEM on:
    // the free rotor spun by the wind must follow the steady-wind run to round-off
    // (1e-9 of the hub's speed change over 0.4 s).
    let dir = tempfile::tempdir().unwrap();
    let b = rotor_box(false);
    std::fs::write(
        dir.path().join("box.bts"),
        b.bytes(|_, _, _| [11.4, 0.0, 0.0]),
    )
    .unwrap();
    let boxed = load(
        dir.path(),
        &rotor_model("wind = { turbsim = \"box.bts\" }", true, 0.4),
    );
    let steady = load(
        dir.path(),
        &rotor_model(
            "wind = { speed = 11.4, direction = [1.0, 0.0, 0.0] }",
            true,
            0.4,
        ),
    );
    let (s1, h1, _) = run(&boxed);
    let (s2, h2, _) = run(&steady);
    assert!(
        s1.failure.is_none() && s2.failure.is_none(),
        "{:?}",
        s1.failure
    );
    let w = |h: &History| h.last().unwrap().state.nodes[0].w.x;
    let w0 = h1.frames[0].state.nodes[0].w.x;
    let (a, b2) = (w(&h1) - w0, w(&h2) - w0);
    println!("hub speed change over 0.4 s: box {a:.9e}, steady {b2:.9e} rad/s");
    assert!(a > 1e-4, "the wind spins the rotor up: {a}");
    assert!((a - b2).abs() < 1e-9 * a.abs(), "{a} {b2}");
    // And a turbulent (wavy) box runs end to end, its rotor spun up differently.
    std::fs::write(dir.path().join("wavy.bts"), b.bytes(wavy_field)).unwrap();
    let wavy = load(
        dir.path(),
        &rotor_model("wind = { turbsim = \"wavy.bts\" }", true, 0.4),
    );
    let (s3, h3, _) = run(&wavy);
    assert!(s3.failure.is_none(), "{:?}", s3.failure);
    let c = w(&h3) - w0;
    println!("wavy box: {c:.6e} rad/s");
    assert!(c.is_finite() && (c - a).abs() > 1e-6, "{c} {a}");
}

#[test]
fn bad_turbsim_inputs_are_located_errors() {
    let dir = tempfile::tempdir().unwrap();
    let good = rotor_box(false);
    std::fs::write(dir.path().join("box.bts"), good.bytes(linear_field)).unwrap();
    let text = |file: &str, t_end: f64| {
        rotor_model(&format!("wind = {{ turbsim = \"{file}\" }}"), false, t_end)
    };
    load(dir.path(), &text("box.bts", 1.0));
    let line = |t: &str| t.lines().position(|l| l.contains("turbsim =")).unwrap() + 1;
    let check = |t: String, what: &str| {
        let e = model_error(dir.path(), &t);
        assert!(e.contains(what), "{e}");
        assert!(e.contains(&format!("bad.toml:{}:", line(&t))), "{e}");
        println!("{e}");
    };
    // Not a .bts: format id, truncated, sizes that overflow, no file.
    let mut bytes = good.bytes(linear_field);
    bytes[0] = 5;
    std::fs::write(dir.path().join("id.bts"), &bytes).unwrap();
    check(text("id.bts", 1.0), "format id 5");
    let bytes = good.bytes(linear_field);
    std::fs::write(dir.path().join("cut.bts"), &bytes[..bytes.len() - 7]).unwrap();
    check(text("cut.bts", 1.0), "bytes follow");
    std::fs::write(dir.path().join("head.bts"), &bytes[..30]).unwrap();
    check(text("head.bts", 1.0), "the file ends at byte 30");
    let mut huge = bytes.clone();
    huge[2..6].copy_from_slice(&(1i32 << 23).to_le_bytes());
    huge[6..10].copy_from_slice(&(1i32 << 23).to_le_bytes());
    std::fs::write(dir.path().join("huge.bts"), &huge).unwrap();
    check(text("huge.bts", 1.0), "too large");
    let mut neg = bytes.clone();
    neg[14..18].copy_from_slice(&(-3i32).to_le_bytes());
    std::fs::write(dir.path().join("neg.bts"), &neg).unwrap();
    check(text("neg.bts", 1.0), "NT (time steps) = -3");
    check(text("none.bts", 1.0), "cannot read TurbSim file");
    // A grid narrower than the rotor (y = ±32 m): the blade tips at y = ±54.6 m.
    let narrow = Box3 {
        ny: 9,
        ..good.clone()
    };
    std::fs::write(dir.path().join("narrow.bts"), narrow.bytes(linear_field)).unwrap();
    let t = text("narrow.bts", 1.0);
    let e = model_error(dir.path(), &t);
    let second = t
        .lines()
        .enumerate()
        .filter(|(_, l)| l.contains("turbsim ="))
        .nth(1)
        .unwrap()
        .0
        + 1;
    assert!(
        e.contains("aerodynamic line 'blade2'") && e.contains("is outside the grid"),
        "{e}"
    );
    assert!(e.contains(&format!("bad.toml:{second}:")), "{e}");
    assert!(
        !e.contains("'blade1'"),
        "blade 1 stands inside the grid: {e}"
    );
    // A run longer than the box: τ = t + 64/11.5 must stay ≤ 7.75 s.
    check(text("box.bts", 2.5), "needs box times");
    // A periodic box has no end.
    std::fs::write(
        dir.path().join("periodic.bts"),
        rotor_box(true).bytes(linear_field),
    )
    .unwrap();
    load(dir.path(), &text("periodic.bts", 50.0));
    // Keys the file replaces; a direction off the horizontal.
    let t = rotor_model("wind = { turbsim = \"box.bts\", speed = 11.4 }", false, 1.0);
    assert!(model_error(dir.path(), &t).contains("wind `speed` with `turbsim`"));
    let t = rotor_model(
        "wind = { turbsim = \"box.bts\", direction = [1.0, 0.0, 0.1] }",
        false,
        1.0,
    );
    assert!(model_error(dir.path(), &t).contains("not normal to `vertical`"));
    let t = rotor_model("wind = { direction = [1.0, 0.0, 0.0] }", false, 1.0);
    assert!(model_error(dir.path(), &t).contains("needs `speed` (or a `turbsim` file)"));
}

#[test]
fn a_station_leaving_the_box_is_a_clear_runtime_error() {
    // The grid's bottom row at 55 m: the blades start inside (lowest tips at 58.5 m) and
    // the spinning rotor carries a tip below it within a few degrees.
    let dir = tempfile::tempdir().unwrap();
    let low = Box3 {
        grid_bottom: 55.0,
        nz: 14,
        ..rotor_box(false)
    };
    std::fs::write(dir.path().join("low.bts"), low.bytes(linear_field)).unwrap();
    let m = load(
        dir.path(),
        &rotor_model("wind = { turbsim = \"low.bts\" }", true, 0.5),
    );
    let (s, _, _) = run(&m);
    let f = s.failure.expect("the run stops");
    println!("{} (hint: {:?}) at t = {}", f.reason, f.hint, f.time);
    assert!(f.reason.contains("outside its box"), "{}", f.reason);
    assert!(f.reason.contains("height z = "), "{}", f.reason);
    assert!(
        f.reason.contains("TurbSim file '") && f.reason.contains("low.bts'"),
        "{}",
        f.reason
    );
    assert!(f.hint.unwrap().contains("covers the rotor's sweep"));
    assert!(f.time < 0.2, "{}", f.time);
}
