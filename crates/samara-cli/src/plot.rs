//! `samara plot RESULTS.nc CHANNEL… [--out FILE]`: time histories to PNG or SVG.
//!
//! Channels with the same units share a panel; panels are stacked with a common time
//! axis. Text is drawn with the DejaVu Sans font compiled into the binary, so no system
//! font or library is needed.

use plotters::prelude::*;
use samara::output::{Channel, ResultsReader};
use std::path::Path;

const COLORS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];

/// One line of a figure: `y` against `x`, in the panel of its `units`.
pub struct Curve {
    /// Legend entry.
    pub label: String,
    /// The quantity's name on the panel's axis (curves of one unit list theirs).
    pub quantity: String,
    pub units: String,
    pub x: Vec<f64>,
    pub y: Vec<f64>,
}

/// Plots `channels` of `reader` into `out` (`.png` or `.svg`).
pub fn plot(reader: &mut ResultsReader, channels: &[String], out: &Path) -> Result<(), String> {
    let time = reader.time().map_err(|e| e.to_string())?;
    if time.is_empty() {
        return Err(format!(
            "{} has no output times to plot",
            reader.path().display()
        ));
    }
    let mut curves: Vec<Curve> = Vec::new();
    for c in channels {
        let ch: Channel = reader.channel(c).map_err(|e| e.to_string())?;
        curves.push(Curve {
            quantity: ch.label.split(':').next().unwrap_or("").to_string(),
            label: ch.label,
            units: ch.units,
            x: time.clone(),
            y: ch.values,
        });
    }
    let x_label = if reader.attr("analysis_type").as_deref() == Some("static") {
        "load factor"
    } else {
        "time [s]"
    };
    let title = format!(
        "{} / {}",
        reader.attr("model").unwrap_or_default(),
        reader.attr("analysis").unwrap_or_default()
    );
    figure(&title, x_label, &curves, out)
}

/// Draws `curves` into `out` (`.png` or `.svg`), one panel per distinct unit (in order of
/// first appearance) with a common x axis.
pub fn figure(title: &str, x_label: &str, curves: &[Curve], out: &Path) -> Result<(), String> {
    plotters::style::register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular())
        .map_err(|_| "the built-in font could not be loaded".to_string())?;
    let mut units: Vec<String> = Vec::new();
    for c in curves {
        if !units.contains(&c.units) {
            units.push(c.units.clone());
        }
    }
    let height = 120 + 260 * units.len() as u32;
    let ext = out
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    match ext.as_str() {
        "svg" => draw(
            SVGBackend::new(out, (900, height)).into_drawing_area(),
            title,
            x_label,
            curves,
            &units,
        ),
        "png" => draw(
            BitMapBackend::new(out, (900, height)).into_drawing_area(),
            title,
            x_label,
            curves,
            &units,
        ),
        _ => Err(format!(
            "cannot tell the format of '{}': name it .png or .svg",
            out.display()
        )),
    }
}

fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    x_label: &str,
    data: &[Curve],
    units: &[String],
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let err = |e: &dyn std::fmt::Display| format!("plotting failed: {e}");
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let root = root
        .titled(title, ("sans-serif", 22))
        .map_err(|e| err(&e))?;
    let panels = root.split_evenly((units.len(), 1));
    let (mut t0, mut t1) = (f64::INFINITY, f64::NEG_INFINITY);
    for x in data.iter().flat_map(|c| &c.x).filter(|x| x.is_finite()) {
        t0 = t0.min(*x);
        t1 = t1.max(*x);
    }
    if !t0.is_finite() {
        (t0, t1) = (0.0, 1.0);
    }
    let t1 = if t1 > t0 { t1 } else { t0 + 1.0 };
    for (panel, unit) in panels.iter().zip(units) {
        let group: Vec<(usize, &Curve)> = data
            .iter()
            .enumerate()
            .filter(|(_, c)| &c.units == unit)
            .collect();
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for (_, c) in &group {
            for v in c.y.iter().filter(|v| v.is_finite()) {
                lo = lo.min(*v);
                hi = hi.max(*v);
            }
        }
        if !lo.is_finite() {
            (lo, hi) = (-1.0, 1.0);
        }
        let pad = if hi > lo {
            0.05 * (hi - lo)
        } else {
            0.5 * lo.abs().max(1.0)
        };
        let mut chart = ChartBuilder::on(panel)
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(80)
            .build_cartesian_2d(t0..t1, (lo - pad)..(hi + pad))
            .map_err(|e| err(&e))?;
        let mut vars: Vec<&str> = Vec::new();
        for (_, c) in &group {
            if !vars.contains(&c.quantity.as_str()) {
                vars.push(&c.quantity);
            }
        }
        let y_label = if unit.is_empty() {
            vars.join(", ")
        } else {
            format!("{} [{unit}]", vars.join(", "))
        };
        chart
            .configure_mesh()
            .x_desc(x_label)
            .y_desc(y_label)
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 15))
            .draw()
            .map_err(|e| err(&e))?;
        for (i, c) in group {
            let color = COLORS[i % COLORS.len()];
            chart
                .draw_series(LineSeries::new(
                    c.x.iter()
                        .zip(&c.y)
                        .filter(|(_, v)| v.is_finite())
                        .map(|(t, v)| (*t, *v)),
                    color.stroke_width(2),
                ))
                .map_err(|e| err(&e))?
                .label(c.label.clone())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
                });
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .label_font(("sans-serif", 14))
            .draw()
            .map_err(|e| err(&e))?;
    }
    root.present().map_err(|e| err(&e))?;
    Ok(())
}
