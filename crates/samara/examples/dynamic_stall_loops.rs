//! The dynamic-stall loops of docs/aerodynamics.md: the DU21-A17 section of
//! examples/aero/pitching_airfoil.toml (Wagner + Øye) and
//! examples/aero/pitching_airfoil_hgm.toml (Beddoes–Leishman, HGM) over their last pitch
//! cycle, c_l(α) and c_m(α) against the static polar, drawn as an SVG.
//!
//! `cargo run --release -p samara --example dynamic_stall_loops [-- OUT.svg]`
//! (docs/images/make.sh runs it; default docs/images/dynamic_stall_loops.svg).

use samara::analysis::{History, run_analysis};
use samara::elements::aero::Airfoil;
use samara::model::Model;
use samara::system::System;
use std::fmt::Write;
use std::path::{Path, PathBuf};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// (α [deg], c_l, c_m) over the last `period` of an example's run.
fn last_cycle(example: &str, period: f64) -> Vec<[f64; 3]> {
    let m = Model::from_file(repo().join(example))
        .unwrap_or_else(|e| panic!("{e}"))
        .model;
    let sys = System::new(&m);
    let mut hist = History::default();
    run_analysis(
        &sys,
        &m.analyses[0],
        sys.initial_state(),
        &mut hist,
        &mut |_| {},
    )
    .unwrap();
    let col = |n: &str| sys.output_names.iter().position(|x| x == n).unwrap();
    let (ia, il, im) = (col("foil.0.alpha"), col("foil.0.cl"), col("foil.0.cm"));
    let t_end = hist.frames.last().unwrap().time;
    let mut out = Vec::new();
    for f in &hist.frames {
        if f.time < t_end - period - 1e-9 {
            continue;
        }
        let mut o = vec![0.0; sys.output_names.len()];
        sys.element_outputs(&sys.context(f.time, 1.0), &f.state, &mut o);
        out.push([o[ia].to_degrees(), o[il], o[im]]);
    }
    out
}

/// A curve: points (x, y), colour, dashed.
type Curve<'a> = (Vec<(f64, f64)>, &'a str, bool);

/// One panel: curves (points, colour, dashed) in a box at (x0, y0) of size (w, h).
#[allow(clippy::too_many_arguments)]
fn panel(
    svg: &mut String,
    (x0, y0, w, h): (f64, f64, f64, f64),
    xr: (f64, f64),
    yr: (f64, f64),
    ylabel: &str,
    curves: &[Curve],
) {
    let px = |x: f64| x0 + (x - xr.0) / (xr.1 - xr.0) * w;
    let py = |y: f64| y0 + h - (y - yr.0) / (yr.1 - yr.0) * h;
    let _ = writeln!(
        svg,
        r##"<rect x="{x0}" y="{y0}" width="{w}" height="{h}" fill="none" stroke="#444"/>"##
    );
    for k in 0..=4 {
        let x = xr.0 + (xr.1 - xr.0) * k as f64 / 4.0;
        let y = yr.0 + (yr.1 - yr.0) * k as f64 / 4.0;
        let _ = writeln!(
            svg,
            r##"<text x="{:.1}" y="{:.1}" font-size="11" text-anchor="middle">{x:.0}</text><text x="{:.1}" y="{:.1}" font-size="11" text-anchor="end">{y:.2}</text><line x1="{:.1}" y1="{y0}" x2="{:.1}" y2="{:.1}" stroke="#ddd"/><line x1="{x0}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="#ddd"/>"##,
            px(x),
            y0 + h + 15.0,
            x0 - 5.0,
            py(y) + 4.0,
            px(x),
            px(x),
            y0 + h,
            py(y),
            x0 + w,
            py(y)
        );
    }
    let _ = writeln!(
        svg,
        r##"<text x="{:.1}" y="{:.1}" font-size="12" text-anchor="middle">α [deg]</text><text x="{:.1}" y="{:.1}" font-size="12" text-anchor="middle" transform="rotate(-90 {:.1} {:.1})">{ylabel}</text>"##,
        x0 + w / 2.0,
        y0 + h + 32.0,
        x0 - 42.0,
        y0 + h / 2.0,
        x0 - 42.0,
        y0 + h / 2.0
    );
    for (pts, colour, dashed) in curves {
        let d: Vec<String> = pts
            .iter()
            .map(|&(x, y)| format!("{:.2},{:.2}", px(x), py(y)))
            .collect();
        let dash = if *dashed {
            r#" stroke-dasharray="5,3""#
        } else {
            ""
        };
        let _ = writeln!(
            svg,
            r#"<polyline points="{}" fill="none" stroke="{colour}" stroke-width="1.6"{dash}/>"#,
            d.join(" ")
        );
    }
}

fn main() {
    let out = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| repo().join("docs/images/dynamic_stall_loops.svg"));
    // Both examples pitch at ω = 6 rad/s.
    let period = 2.0 * std::f64::consts::PI / 6.0;
    let oye = last_cycle("examples/aero/pitching_airfoil.toml", period);
    let hgm = last_cycle("examples/aero/pitching_airfoil_hgm.toml", period);
    let af = Airfoil::parse(
        &std::fs::read_to_string(repo().join("reference/nrel5mw/aero/Airfoils/DU21_A17.dat"))
            .unwrap(),
        false,
    )
    .unwrap();
    let stat: Vec<[f64; 3]> = (-20..=220)
        .map(|k| {
            let a = k as f64 * 0.1;
            let c = af.eval(a.to_radians());
            [a, c.cl, c.cm]
        })
        .collect();
    let xy = |v: &[[f64; 3]], j: usize| v.iter().map(|p| (p[0], p[j])).collect::<Vec<_>>();
    let mut svg = String::from(
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="900" height="380" font-family="sans-serif">
<rect width="900" height="380" fill="white"/>
"#,
    );
    panel(
        &mut svg,
        (70.0, 40.0, 360.0, 270.0),
        (-2.0, 22.0),
        (0.0, 2.0),
        "c_l",
        &[
            (xy(&stat, 1), "#000000", false),
            (xy(&oye, 1), "#2471a3", true),
            (xy(&hgm, 1), "#c0392b", false),
        ],
    );
    panel(
        &mut svg,
        (520.0, 40.0, 360.0, 270.0),
        (-2.0, 22.0),
        (-0.2, 0.0),
        "c_m",
        &[
            (xy(&stat, 2), "#000000", false),
            (xy(&oye, 2), "#2471a3", true),
            (xy(&hgm, 2), "#c0392b", false),
        ],
    );
    svg += r##"<text x="450" y="22" font-size="14" text-anchor="middle">DU21-A17 pitching α = 10° − 10° cos ωt, k = 0.1, V = 30 m/s (last cycle)</text>
<line x1="120" y1="355" x2="150" y2="355" stroke="#000"/><text x="155" y="359" font-size="12">static polar</text>
<line x1="290" y1="355" x2="320" y2="355" stroke="#2471a3" stroke-dasharray="5,3"/><text x="325" y="359" font-size="12">Wagner + Øye (c_m quasi-steady at α_E)</text>
<line x1="600" y1="355" x2="630" y2="355" stroke="#c0392b"/><text x="635" y="359" font-size="12">Beddoes–Leishman (HGM, UAMod 4 form)</text>
</svg>
"##;
    std::fs::write(&out, svg).unwrap();
    eprintln!("wrote {}", out.display());
}
