//! `samara section … --plot`: the mesh coloured by material (left) and by ply angle
//! (right), with the tension centre (○), shear centre (×), mass centre (△) and the elastic
//! principal axes through the tension centre.

use plotters::prelude::*;
use samara::section::{SectionResult, input::LoadedSection};
use std::path::Path;

const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(188, 189, 34),
];

/// Blue (−90°) – white (0°) – red (+90°).
fn angle_colour(deg: f64) -> RGBColor {
    let t = (deg / 90.0).clamp(-1.0, 1.0);
    let mix = |a: u8, b: u8, s: f64| (a as f64 + (b as f64 - a as f64) * s).round() as u8;
    if t < 0.0 {
        let s = -t;
        RGBColor(mix(245, 33, s), mix(245, 102, s), mix(245, 172, s))
    } else {
        RGBColor(mix(245, 178, t), mix(245, 24, t), mix(245, 43, t))
    }
}

/// Boundary of an element as a polygon through its corner and mid-side nodes.
fn outline(l: &LoadedSection, e: usize) -> Vec<(f64, f64)> {
    let el = &l.model.mesh.elements[e];
    let nodes = el.node_list();
    let nc = el.kind.n_corners();
    let mut pts = Vec::new();
    for k in 0..nc {
        let p = l.model.mesh.nodes[nodes[k]];
        pts.push((p[0], p[1]));
        if el.kind.order() == 2 {
            let q = l.model.mesh.nodes[nodes[nc + k]];
            pts.push((q[0], q[1]));
        }
    }
    pts
}

pub fn plot(l: &LoadedSection, r: &SectionResult, out: &Path) -> Result<(), String> {
    plotters::style::register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular())
        .map_err(|_| "the built-in font could not be loaded".to_string())?;
    let ext = out
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    let size = (1400, 620);
    match ext.as_str() {
        "svg" => draw(SVGBackend::new(out, size).into_drawing_area(), l, r),
        _ => draw(BitMapBackend::new(out, size).into_drawing_area(), l, r),
    }
}

fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    l: &LoadedSection,
    r: &SectionResult,
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| x.to_string();
    root.fill(&WHITE).map_err(e)?;
    let (lo, hi) = l.model.mesh.bounds();
    let p = &r.properties;
    // Equal scales: pad the shorter range.
    let (w, h) = (hi[0] - lo[0], hi[1] - lo[1]);
    let span = w.max(h * 650.0 / 520.0) * 1.08;
    let cy = 0.5 * (lo[0] + hi[0]);
    let cz = 0.5 * (lo[1] + hi[1]);
    let yr = (cy - 0.5 * span)..(cy + 0.5 * span);
    let zspan = span * 520.0 / 650.0;
    let zr = (cz - 0.5 * zspan)..(cz + 0.5 * zspan);
    let panels = root.split_evenly((1, 2));
    for (k, area) in panels.iter().enumerate() {
        let title = if k == 0 {
            format!("{} — materials", l.name)
        } else {
            "ply angle (blue −90°, white 0°, red +90°)".to_string()
        };
        let mut chart = ChartBuilder::on(area)
            .caption(title, ("sans-serif", 20))
            .margin(12)
            .x_label_area_size(36)
            .y_label_area_size(60)
            .build_cartesian_2d(yr.clone(), zr.clone())
            .map_err(e)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc("y [m]")
            .y_desc("z [m]")
            .label_style(("sans-serif", 13))
            .draw()
            .map_err(e)?;
        let edge = if l.model.mesh.elements.len() > 2000 {
            None
        } else {
            Some(RGBColor(60, 60, 60).mix(0.25))
        };
        for (ie, el) in l.model.mesh.elements.iter().enumerate() {
            let poly = outline(l, ie);
            let fill = if k == 0 {
                PALETTE[el.material % PALETTE.len()]
            } else {
                angle_colour(el.ply_angle.to_degrees())
            };
            chart
                .draw_series(std::iter::once(Polygon::new(poly.clone(), fill.filled())))
                .map_err(e)?;
            if let Some(c) = edge {
                let mut closed = poly;
                closed.push(closed[0]);
                chart
                    .draw_series(std::iter::once(PathElement::new(closed, c.stroke_width(1))))
                    .map_err(e)?;
            }
        }
        // Principal axes through the tension centre.
        let tc = (p.tension_centre[0], p.tension_centre[1]);
        let len = 0.35 * span;
        for (a, style) in [
            (p.elastic_axes_angle, BLACK.stroke_width(2)),
            (
                p.elastic_axes_angle + std::f64::consts::FRAC_PI_2,
                BLACK.stroke_width(1),
            ),
        ] {
            let (s, c) = a.sin_cos();
            chart
                .draw_series(std::iter::once(PathElement::new(
                    vec![
                        (tc.0 - len * c, tc.1 - len * s),
                        (tc.0 + len * c, tc.1 + len * s),
                    ],
                    style,
                )))
                .map_err(e)?;
        }
        let sc = (p.shear_centre[0], p.shear_centre[1]);
        let mc = (p.mass_centre[0], p.mass_centre[1]);
        chart
            .draw_series(std::iter::once(Circle::new(tc, 7, BLACK.stroke_width(2))))
            .map_err(e)?
            .label("tension centre")
            .legend(|(x, y)| Circle::new((x + 10, y), 5, BLACK.stroke_width(2)));
        chart
            .draw_series(std::iter::once(Cross::new(sc, 7, RED.stroke_width(2))))
            .map_err(e)?
            .label("shear centre")
            .legend(|(x, y)| Cross::new((x + 10, y), 5, RED.stroke_width(2)));
        chart
            .draw_series(std::iter::once(TriangleMarker::new(mc, 7, BLUE.filled())))
            .map_err(e)?
            .label("mass centre")
            .legend(|(x, y)| TriangleMarker::new((x + 10, y), 5, BLUE.filled()));
        if k == 0 {
            for (i, m) in l.model.materials.iter().enumerate() {
                let c = PALETTE[i % PALETTE.len()];
                chart
                    .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())
                    .map_err(e)?
                    .label(m.name.clone())
                    .legend(move |(x, y)| {
                        Rectangle::new([(x, y - 5), (x + 20, y + 5)], c.filled())
                    });
            }
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 13))
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(e)?;
    }
    root.present().map_err(e)?;
    Ok(())
}
