//! Flexible-rotor benchmark (issue #15): the NREL 5-MW rotor of
//! `examples/rotor/nrel5mw_flexible.toml` (three BeamDyn blades, 2 elements of order 6
//! each, hub driven at 12.1 rpm) with 49-station lifting lines (the AeroDyn blade table
//! interpolated to the 49 BeamDyn key points: chord and twist linear, airfoil of the
//! nearest AeroDyn node), BEM with tip and hub loss, rated wind, `T` s at h = 0.01 s.
//!
//! `cargo bench -p samara --bench flex_rotor [-- T] [oye] [modified] [turbulent] [kussner]` prints the time per
//! step, the Newton iterations and factorizations per step, the real-time factor, and the
//! split of one residual-and-tangent evaluation between the structure (beam elements,
//! hub, joints) and the aerodynamics (the 147 stations, each with its own local block),
//! each as wall time and as CPU time of the process (summed over its threads from
//! /proc/self/task/*/schedstat, Linux; less inflated than wall time on a shared machine).
//! With `oye` the lines carry Øye's dynamic stall (`dynamic_stall = "oye"`, one state per
//! station); Øye's model needs a lifting airfoil, so in that variant the stations whose
//! nearest AeroDyn node is a cylinder (non-lifting) take DU40_A17, the innermost lifting
//! section.
//!
//! With `modified` the analysis uses modified Newton (`jacobian = "modified"`).
//!
//! With `turbulent` the wind is a TurbSim box written by the bench ([`write_box`]): a
//! periodic 32 × 32 grid 4.68 m apart (145 m square centred on the hub at 90 m), 512 steps
//! of 0.05 s (a 25.6 s period), the rated 11.4 m/s mean with a 0.2 power-law shear and
//! ≈ 10 % turbulence from a few frozen Fourier modes (a load for the sampling, not a
//! turbulence spectrum), read by `wind = { turbsim }` (trilinear in y, z, τ at each station
//! and each evaluation). The bench then also times the sampling alone: the 147 stations'
//! wind at their initial points, as f64 and as the 12-direction dual numbers of the
//! station kernel. `kussner` (implies `turbulent`) adds Wagner's attached-flow states with
//! Küssner's response to the box's turbulence (`unsteady = "wagner"`, `gust_response =
//! "kussner"`, four states per station).
//!
//! Measured on the shared 2-core machine (load average ≈ 10), CPU time, `-- 10`: 1.96 ms
//! per step, 5.1× real time (3.1 ms before the BEM warm start and the batched stations;
//! 9.4 ms before the stations were differentiated over their own kinematics); with
//! `modified` 0.75 ms, 13×; with `oye` 3.73 ms, 2.7× (`oye modified` 1.28 ms, 7.8×). After
//! issue #17's fourth round (load average ≈ 12): 1.62 ms, 6.2× (1.72 ms before, builds
//! interleaved); `modified` ≈ 0.65 ms, 15.5×. Fifth round (stations with states batched
//! into their beam element's block): `oye modified turbulent` (the configuration)
//! callgrind over 0.3 s 1415.9M → 851.5M instructions, CPU 1.14–1.16 → 0.89–0.92 ms per
//! step (11.3× real time; load average ≈ 8, builds interleaved); `oye turbulent` 4001.0M
//! → 2098.9M, 3.2 → 2.3 ms (4.4×); quasi-steady BEM unchanged (1.65 ms, `modified`
//! 0.66 ms). Sixth round (the stations' tangents compiled for AVX with the spread over
//! the node rows vectorized; the airfoil tables' interval from a binned index):
//! `oye modified turbulent` callgrind over 0.3 s 849.3M → 746.3M, CPU 0.94 → 0.84 ms per
//! step (11.9× real time; load average ≈ 5.5, builds interleaved); power, thrust and tip
//! deflection unchanged. Seventh round (modified Newton keeps its factorization across
//! round-off changes of the grid's step, which had forced a refresh at every other step,
//! and replaces a matrix that contracted slower than 0.1 at the next step): 2.40 → 2.74
//! iterations and 0.49 → 0.17 factorizations per step, callgrind over 0.3 s 750.9M →
//! 561.5M, over 10 s 13.63G → 9.05G; CPU 1.07–1.09 → 0.79–0.82 ms per step (9.3× →
//! 12.4× real time; builds interleaved, load average 2–3.5, a slower machine state than
//! the sixth round's 0.84 ms for the old build: ≈ 16× there); thrust 728.26 → 728.321 kN
//! (full Newton 728.258 kN, as modified Newton at tolerance 1e-9: a tolerance effect).
//! Eighth round (the stations' f64 path: the BEM root by one Newton step with the exact
//! slope, then f64 steps with the slope updated from the residuals instead of repeated
//! dual-number Newton steps and a redundant residual; the hub loss without exp/acos where
//! it rounds to 1; Øye's curves from the loads' own table lookup; cl and cd only in the
//! momentum balance): callgrind over 10 s 9.05G → 7.88G (−12.9 %), over 2 s 2120.9M →
//! 1845.4M; CPU 0.79–0.80 → 0.69–0.70 ms per step (12.6× → 14.3× real time, builds
//! interleaved, load average ≈ 1.5); power, thrust and tip deflection unchanged. Ninth
//! round (the energy balance's station power as F·ṗ + M·ω̄ from the loads, without the
//! node rows): callgrind over 10 s 7.89G → 7.80G (−1.1 %); CPU 0.742, 0.714, 0.789 →
//! 0.716, 0.721, 0.779 ms per step (≈ 14×, builds interleaved at load average ≈ 3: within
//! the noise); last line unchanged. Tenth round (the `Trend` predictor's misses fed back
//! per unknown when they alternate, `analysis/trend_feedback.rs`: the ringing of the blade
//! tips' torsion and of the root nodes near the Nyquist rate is predicted): 2.74 → 2.54
//! iterations and 0.17 → 0.10 factorizations per step, callgrind over 10 s 7.74G → 6.37G
//! (−17.7 %); CPU 0.713, 0.732, 0.770 → 0.609, 0.616, 0.637 ms per step (13.6× → 16.1×
//! real time, builds interleaved, load average ≈ 3.8); `modified` (quasi-steady, steady
//! wind) 0.56–0.60 → 0.44–0.46 ms (22×); full Newton unchanged; thrust 728.321 → 728.304 kN
//! (full Newton 728.258 kN). Eleventh round (the energy balance takes the stations' power at
//! each step's last Newton iterate instead of a second pass over the stations; the box's
//! sample with one range test; the stations' residual and the beams' evaluation in AVX
//! copies): callgrind over 10 s 6.41G → 5.28G (−17.7 %), 2.54 → 2.53 iterations and
//! 0.10 → 0.09 factorizations per step; CPU median 0.588 → 0.504 ms per step (17.0× →
//! 19.8×; 12 runs each, builds interleaved, load average ≈ 1.3; 0.500 ms in 3 runs).
//! Twelfth round (the beams' dissipated power kept from the last iterate too): 5.278G →
//! 5.231G (−0.9 %), CPU median 0.509 → 0.5005 ms per step (≈ 20.0×, 0.500 ms or less in
//! 8 of 16 runs; 16 runs each, interleaved, load average 2.4–2.7; 0.512 → 0.510 ms in an
//! earlier set of 12 at a coarser clock), last line unchanged;
//! quasi-steady `modified` 0.44–0.50 → 0.38–0.40 ms (26×), `modified turbulent` 0.41 ms
//! (24×); thrust 728.304 → 728.302 kN (rounding-level change of the BEM root hints).
//! Thirteenth round (the energy sums skip the stations, which apply loads only; the beams'
//! potential energy from positions and orientations only): callgrind over 10 s 5.231G →
//! 5.123G (−2.1 %), CPU per step the same median as
//! the old build's in 46 interleaved runs each (0.516 ms at load 1.2–3.8; per-pair
//! difference −0.006 ms, ≤ 0.500 ms in 14 runs against 7); same bits (last line unchanged).
//! Left: 2.53 iterations per step against a floor of 2 and the Øye states' misses
//! (≈ 10³ tolerances; the largest first corrections are mid-span stations' Øye states).
//! Then an element state's Newton correction weighed against max(|hΔz|, |z|) (its value,
//! not only its increment): 2.36 iterations per step, callgrind 5.072G → 4.799G (−5.4 %,
//! `--toggle-collect='*run_analysis*'`), last line 6152.82 kW, 728.260 kN.
//! Fourteenth round (the BEM root's start at a step's first evaluation on the line through
//! the last two steps' roots; cl, cd without their derivatives in the f64 root): callgrind
//! 4.800G → 4.747G (−1.1 %), CPU median 0.474 → 0.459 ms per step (0.467–0.485 against
//! 0.454–0.467, 12 runs each interleaved, load average 5.0; ≈ 21.8×); last line unchanged.
//! The merged code on an idle machine, 15 runs each interleaved: median 0.468 ms
//! (0.456–0.508) against 0.484 ms, 21.4× real time: the 20× met.
//! The history is in docs/aerodynamics.md, "Performance".
//!
//! The run ends by printing the aerodynamic power, the thrust and blade 1's tip deflection
//! (hub frame) at its last step, to compare builds.

use samara::analysis::{History, run_analysis};
use samara::core::{ElementInput, EvalContext, LocalTerms, Need};
use samara::model::Model;
use samara::model::components::{Build, build_all, initial_nodes};
use samara::system::System;
use std::path::Path;
use std::time::Instant;

/// `[[aero_lines.stations]]` of the 49-station line.
fn stations(reference: &Path, stall: bool) -> String {
    let numbers = |l: &str| -> Vec<f64> {
        l.split_whitespace()
            .map_while(|t| t.parse::<f64>().ok())
            .collect()
    };
    let blade =
        std::fs::read_to_string(reference.join("structure/NRELOffshrBsline5MW_BeamDyn.dat"))
            .unwrap();
    let kp: Vec<f64> = blade
        .lines()
        .map(numbers)
        .filter(|v| v.len() == 4)
        .map(|v| v[2])
        .collect();
    assert_eq!(kp.len(), 49);
    let ad = std::fs::read_to_string(reference.join("aero/NRELOffshrBsline5MW_AeroDyn_blade.dat"))
        .unwrap();
    let rows: Vec<Vec<f64>> = ad.lines().map(numbers).filter(|v| v.len() == 7).collect();
    let airfoils = [
        "Cylinder1",
        "Cylinder2",
        "DU40_A17",
        "DU35_A17",
        "DU30_A17",
        "DU25_A17",
        "DU21_A17",
        "NACA64_A17",
    ];
    let mut s = String::new();
    for z in kp {
        let k = rows.partition_point(|r| r[0] <= z).clamp(1, rows.len() - 1);
        let (a, b) = (&rows[k - 1], &rows[k]);
        let t = (z - a[0]) / (b[0] - a[0]);
        let near = if t < 0.5 { a } else { b };
        let mut id = near[6] as usize - 1;
        if stall && id < 2 {
            id = 2;
        }
        let af = reference.join(format!("aero/Airfoils/{}.dat", airfoils[id]));
        s += &format!(
            "[[aero_lines.stations]]\nspan = {z}\nchord = {}\ntwist = {}\nairfoil = \"{}\"\n",
            a[5] + t * (b[5] - a[5]),
            (a[4] + t * (b[4] - a[4])).to_radians(),
            af.display()
        );
    }
    s
}

/// Writes the bench's TurbSim box ([`main`]'s `turbulent`) to `path`: the layout of a
/// `.bts` file (docs/aerodynamics.md, "Turbulent wind"), periodic, values to 1/1000 m/s.
fn write_box(path: &Path) {
    let (n, nt, dy, dt, hub) = (32usize, 512usize, 145.0f32 / 31.0, 0.05f32, 90.0f32);
    let bottom = hub - 0.5 * 31.0 * dy;
    let mut b: Vec<u8> = Vec::new();
    b.extend(8i16.to_le_bytes());
    for k in [n as i32, n as i32, 0, nt as i32] {
        b.extend(k.to_le_bytes());
    }
    for v in [
        dy, dy, dt, 11.4, hub, bottom, 1000.0, -11400.0, 1000.0, 0.0, 1000.0, 0.0,
    ] {
        b.extend(v.to_le_bytes());
    }
    b.extend(0i32.to_le_bytes());
    // Frozen modes: amplitude [m/s], wavenumbers in y and z [1/m], frequency [rad/s]
    // (multiples of 2π/25.6 s, periodic over the box), phase.
    let w0 = 2.0 * std::f64::consts::PI / 25.6;
    let modes = [
        (0.8, 0.02, 0.013, 3.0 * w0, 0.3),
        (0.5, -0.045, 0.031, 11.0 * w0, 1.9),
        (0.3, 0.09, -0.07, 29.0 * w0, 4.1),
        (0.2, 0.17, 0.12, 61.0 * w0, 2.6),
    ];
    for it in 0..nt {
        let tau = it as f64 * dt as f64;
        for iz in 0..n {
            let z = bottom as f64 + iz as f64 * dy as f64;
            for iy in 0..n {
                let y = (iy as f64 - 15.5) * dy as f64;
                let mut v = [11.4 * (z / 90.0).powf(0.2), 0.0, 0.0];
                for (c, vc) in v.iter_mut().enumerate() {
                    for &(a, ky, kz, w, ph) in &modes {
                        let scale = [1.0, 0.8, 0.5][c];
                        *vc += scale * a * (ky * y + kz * z + w * tau + ph + c as f64).sin();
                    }
                }
                let raw = [
                    (v[0] * 1000.0 - 11400.0).round() as i16,
                    (v[1] * 1000.0).round() as i16,
                    (v[2] * 1000.0).round() as i16,
                ];
                for r in raw {
                    b.extend(r.to_le_bytes());
                }
            }
        }
    }
    std::fs::write(path, b).unwrap();
}

/// CPU time of this process so far [s] (all threads, from the scheduler's statistics),
/// or `None` where /proc is not available.
fn cpu_time() -> Option<f64> {
    let mut ns = 0u64;
    for task in std::fs::read_dir("/proc/self/task").ok()? {
        let stat = std::fs::read_to_string(task.ok()?.path().join("schedstat")).ok()?;
        ns += stat.split_whitespace().next()?.parse::<u64>().ok()?;
    }
    Some(ns as f64 * 1e-9)
}

/// Wall and CPU seconds of `f`, with its result.
fn timed<T>(f: impl FnOnce() -> T) -> (T, f64, Option<f64>) {
    let (clock, cpu) = (Instant::now(), cpu_time());
    let out = f();
    let wall = clock.elapsed().as_secs_f64();
    (out, wall, cpu.zip(cpu_time()).map(|(a, b)| b - a))
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let t_end: f64 = args.iter().find_map(|a| a.parse().ok()).unwrap_or(10.0);
    let stall = args.iter().any(|a| a == "oye");
    let modified = args.iter().any(|a| a == "modified");
    let kussner = args.iter().any(|a| a == "kussner");
    let turbulent = kussner || args.iter().any(|a| a == "turbulent");
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let example = root.join("examples/rotor/nrel5mw_flexible.toml");
    let reference = root.join("reference/nrel5mw");
    let st = stations(&reference, stall);
    let mut text = String::new();
    for l in std::fs::read_to_string(&example).unwrap().lines() {
        if l.starts_with("aerodyn = ") {
            continue;
        }
        text += l;
        text.push('\n');
        if l.starts_with("inflow = ") {
            if stall {
                text += "dynamic_stall = \"oye\"\n";
            }
            if kussner {
                text += "unsteady = \"wagner\"\ngust_response = \"kussner\"\n";
            }
            text += &st;
        }
    }
    let mut text = text.replace("t_end = 0.5", &format!("t_end = {t_end}"));
    let box_path =
        std::env::temp_dir().join(format!("samara_flex_rotor_{}.bts", std::process::id()));
    if turbulent {
        write_box(&box_path);
        text = text.replace(
            "wind = { speed = 11.4, direction = [1.0, 0.0, 0.0] }",
            &format!(
                "wind = {{ turbsim = {:?}, direction = [1.0, 0.0, 0.0] }}",
                box_path.to_str().unwrap()
            ),
        );
        assert_eq!(text.matches("turbsim =").count(), 3);
    }
    if modified {
        text = text.replace("step = 0.01", "step = 0.01\njacobian = \"modified\"");
    }
    let m = match Model::from_toml_str(&text, &example) {
        Ok(l) => l.model,
        Err(e) => panic!("{}", e.render_plain()),
    };
    if turbulent {
        let _ = std::fs::remove_file(&box_path);
    }
    // One residual-and-tangent evaluation, structure and aerodynamics apart.
    let initial = initial_nodes(&m);
    let mut parts = Build::new(&initial);
    build_all(&m, &mut parts);
    let ctx = EvalContext {
        time: 0.0,
        gravity: nalgebra::Vector3::zeros(),
        load_factor: 1.0,
    };
    let time_of = |aero: bool, need: Need| {
        let els: Vec<_> = parts
            .elements
            .iter()
            .filter(|e| e.name().starts_with("aero") == aero)
            .collect();
        let mut terms: Vec<LocalTerms> = els
            .iter()
            .map(|e| LocalTerms::for_element(e.as_ref()))
            .collect();
        let reps = 100;
        let ((), wall, cpu) = timed(|| {
            for _ in 0..reps {
                for (e, t) in els.iter().zip(&mut terms) {
                    t.clear(need);
                    e.evaluate(&ctx, &ElementInput::nodes(&initial), need, t);
                }
            }
        });
        let per = |s: f64| 1e6 * s / reps as f64;
        (els.len(), per(wall), cpu.map(per))
    };
    let us = |c: Option<f64>| c.map_or("—".to_string(), |c| format!("{c:.1}"));
    let (ns, ts, cs) = time_of(false, Need::ResidualAndTangents);
    let (na, ta, ca) = time_of(true, Need::ResidualAndTangents);
    let (_, tr, cr) = time_of(true, Need::Residual);
    println!(
        "one residual-and-tangent evaluation, wall (CPU) µs: structure ({ns} elements, bodies, joints) {ts:.1} ({}), aerodynamics ({na} stations) {ta:.1} ({}), {:.1} ({}) per station, {:.0} % aerodynamics; aerodynamic residual only {tr:.1} ({})",
        us(cs),
        us(ca),
        ta / na as f64,
        us(ca.map(|c| c / na as f64)),
        100.0 * ta / (ts + ta),
        us(cr),
    );
    if turbulent {
        // The sampling alone: 49 points per line spread over the rotor disc (radius
        // 1.5 … 63 m), f64 and dual.
        let points: Vec<(std::sync::Arc<samara::elements::aero::Wind>, [f64; 3])> = m
            .aero_lines
            .iter()
            .flat_map(|l| {
                let wind = std::sync::Arc::new(l.wind.clone());
                (0..l.stations.len()).map(move |k| (wind.clone(), k))
            })
            .map(|(w, k)| {
                let r = 1.5 + 61.5 * (k as f64 + 0.5) / 49.0;
                let psi = 2.1 * k as f64;
                (w, [0.0, r * psi.sin(), 90.0 + r * psi.cos()])
            })
            .collect();
        let reps = 1000;
        let (sum, wall, cpu) = timed(|| {
            let mut s = 0.0;
            for i in 0..reps {
                for (w, p) in &points {
                    s += w.velocity(p, 0.01 * i as f64)[0];
                }
            }
            s
        });
        let (dsum, dwall, dcpu) = timed(|| {
            use samara::math::dual::{Dual, Scalar};
            let mut s = 0.0;
            for i in 0..reps {
                for (w, p) in &points {
                    let q: [Dual<12>; 3] = std::array::from_fn(|c| Dual::var(p[c], c));
                    s += w.velocity(&q, 0.01 * i as f64)[0].re();
                }
            }
            s
        });
        let per = |s: f64| 1e9 * s / (reps * points.len()) as f64;
        println!(
            "wind sampling ({} points): f64 {:.0} ns ({} ns CPU), dual (12 directions) {:.0} ns ({} ns CPU) per sample [{:.3}, {:.3}]",
            points.len(),
            per(wall),
            cpu.map_or("—".into(), |c| format!("{:.0}", per(c))),
            per(dwall),
            dcpu.map_or("—".into(), |c| format!("{:.0}", per(c))),
            sum / (reps * points.len()) as f64,
            dsum / (reps * points.len()) as f64,
        );
    }
    let sys = System::new(&m);
    let mut h = History::default();
    let (s, wall, cpu) = timed(|| {
        run_analysis(
            &sys,
            &m.analyses[0],
            sys.initial_state(),
            &mut h,
            &mut |_| {},
        )
        .unwrap()
    });
    assert!(s.failure.is_none(), "{:?}", s.failure);
    // What the run computed, at its end: the aerodynamic power on the nodes and the
    // thrust (Σ of the stations' forces along the axis x), and blade 1's tip
    // deflection — to compare builds (equal to the Newton tolerance).
    let end = &s.final_state;
    let (mut power, mut thrust, mut scratch) = (0.0, 0.0, Vec::new());
    let ctx = EvalContext {
        time: end.time,
        ..ctx
    };
    for (k, e) in sys.elements.iter().enumerate() {
        if !e.name().starts_with("aero") {
            continue;
        }
        let x = sys.element_input(k, end, &[], &mut scratch);
        power += e.external_power(&ctx, &x);
        let mut t = LocalTerms::for_element(e.as_ref());
        t.clear(Need::Residual);
        e.evaluate(&ctx, &x, Need::Residual, &mut t);
        thrust -= (0..e.nodes().len()).map(|a| t.r[6 * a]).sum::<f64>();
    }
    // The tip's displacement in the hub's frame (the deflection, rotation removed).
    let tip = m.node_index("blade1.12").expect("blade 1's tip node");
    let hub = m.node_index("hub").expect("the hub node");
    let d = end.nodes[hub]
        .r()
        .tr_mul(&(end.nodes[tip].x - end.nodes[hub].x))
        - m.nodes[hub]
            .orientation
            .matrix()
            .tr_mul(&(m.nodes[tip].position - m.nodes[hub].position));
    println!(
        "at t = {:.2} s: aerodynamic power {:.2} kW, thrust {:.3} kN, blade 1 tip deflection (hub frame) [{:.4}, {:.4}, {:.4}] m",
        end.time,
        power / 1e3,
        thrust / 1e3,
        d.x,
        d.y,
        d.z
    );
    let steps = s.steps as f64;
    println!(
        "{t_end} s simulated{}{}{}: {} steps, {:.2} Newton iterations and {:.2} factorizations per step; wall {wall:.3} s, {:.3} ms/step, {:.2}× real time; CPU {}",
        if stall {
            " with Øye's dynamic stall"
        } else {
            ""
        },
        match (turbulent, kussner) {
            (true, true) => " in the TurbSim box, Wagner + Küssner states",
            (true, false) => " in the TurbSim box",
            _ => "",
        },
        if modified { ", modified Newton" } else { "" },
        s.steps,
        s.newton_iterations as f64 / steps,
        s.factorizations as f64 / steps,
        1e3 * wall / steps,
        t_end / wall,
        cpu.map_or("—".to_string(), |c| format!(
            "{c:.3} s, {:.3} ms/step, {:.2}× real time",
            1e3 * c / steps,
            t_end / c
        )),
    );
}
