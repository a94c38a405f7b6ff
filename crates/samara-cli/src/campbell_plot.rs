//! `samara plot RESULTS.nc campbell`: the Campbell diagram of a Campbell analysis —
//! the rotating-frame frequency of each tracked mode against rotor speed, with the
//! per-revolution lines 1P … 6P (f = nΩ/2π).

use plotters::prelude::*;
use samara::output::ResultsReader;
use std::path::Path;

const COLORS: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
];

/// Names of the label codes of `campbell_mode_label`.
const LABELS: [&str; 5] = ["mixed", "flap", "lag", "torsion", "axial"];

/// Draws the Campbell diagram of `reader` into `out` (`.png` or `.svg`).
pub fn plot(reader: &mut ResultsReader, out: &Path) -> Result<(), String> {
    plotters::style::register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular())
        .map_err(|_| "the built-in font could not be loaded".to_string())?;
    let read = |r: &mut ResultsReader, name: &str| {
        r.read(name).map_err(|e| {
            format!(
                "{}: {e} (`samara plot … campbell` needs the results of a `type = \"campbell\"` analysis)",
                r.path().display()
            )
        })
    };
    let speed = read(reader, "campbell_speed")?;
    let freq = read(reader, "campbell_frequency")?;
    let labels = read(reader, "campbell_mode_label")?;
    let (np, nm) = (speed.len(), labels.len());
    if np == 0 || nm == 0 || freq.len() != np * nm {
        return Err("the Campbell arrays are empty or inconsistent".into());
    }
    let title = format!(
        "{} / {}: Campbell diagram",
        reader.attr("model").unwrap_or_default(),
        reader.attr("analysis").unwrap_or_default()
    );
    let ext = out
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    let size = (900, 640);
    match ext.as_str() {
        "svg" => draw(
            SVGBackend::new(out, size).into_drawing_area(),
            &title,
            &speed,
            &freq,
            &labels,
        ),
        "png" => draw(
            BitMapBackend::new(out, size).into_drawing_area(),
            &title,
            &speed,
            &freq,
            &labels,
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
    speed: &[f64],
    freq: &[f64],
    labels: &[f64],
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let err = |e: &dyn std::fmt::Display| format!("plotting failed: {e}");
    let nm = labels.len();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let root = root
        .titled(title, ("sans-serif", 22))
        .map_err(|e| err(&e))?;
    let (w0, w1) = speed
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &w| {
            (a.min(w), b.max(w))
        });
    let w1 = if w1 > w0 { w1 } else { w0 + 1.0 };
    let fmax = freq
        .iter()
        .filter(|f| f.is_finite())
        .fold(0.0f64, |m, &f| m.max(f));
    let fmax = if fmax > 0.0 { 1.08 * fmax } else { 1.0 };
    let mut chart = ChartBuilder::on(&root)
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(w0..w1, 0.0..fmax)
        .map_err(|e| err(&e))?;
    chart
        .configure_mesh()
        .x_desc("rotor speed Ω [rad/s]")
        .y_desc("frequency (rotating frame) [Hz]")
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 15))
        .draw()
        .map_err(|e| err(&e))?;
    // Per-revolution lines nP: f = nΩ/2π, labelled where they leave the plot.
    let grey = RGBColor(150, 150, 150);
    for n in 1..=6 {
        let slope = n as f64 / std::f64::consts::TAU;
        let end = w1.min(fmax / slope);
        if end <= w0 {
            continue;
        }
        chart
            .draw_series(DashedLineSeries::new(
                [(w0, slope * w0), (end, slope * end)],
                6,
                4,
                grey.stroke_width(1),
            ))
            .map_err(|e| err(&e))?;
        chart
            .draw_series(std::iter::once(Text::new(
                format!("{n}P"),
                (end, slope * end),
                ("sans-serif", 13).into_font().color(&grey),
            )))
            .map_err(|e| err(&e))?;
    }
    for k in 0..nm {
        let color = COLORS[k % COLORS.len()];
        let code = labels[k] as usize;
        let name = format!("mode {} ({})", k + 1, LABELS.get(code).unwrap_or(&"mixed"));
        let pts: Vec<(f64, f64)> = speed
            .iter()
            .enumerate()
            .map(|(p, &w)| (w, freq[p * nm + k]))
            .filter(|(_, f)| f.is_finite())
            .collect();
        chart
            .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))
            .map_err(|e| err(&e))?
            .label(name)
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
            });
        chart
            .draw_series(pts.iter().map(|&p| Circle::new(p, 3, color.filled())))
            .map_err(|e| err(&e))?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .draw()
        .map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))?;
    Ok(())
}
