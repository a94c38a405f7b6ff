//! `samara plot RESULTS.nc span LINE QUANTITY… [--time T]…`: a lifting line's station
//! outputs (α, cl, loads, inductions…) against span at one or several output times.

use crate::plot::{Curve, figure};
use samara::output::ResultsReader;
use std::path::Path;

/// Plots the station outputs `args = [LINE, QUANTITY…]` of `reader` at each of `times`
/// (the nearest output times; the last one when `times` is empty) into `out`.
pub fn plot(
    reader: &mut ResultsReader,
    args: &[String],
    times: &[f64],
    out: &Path,
) -> Result<(), String> {
    let lines = reader.aero_lines();
    let usage = "usage: samara plot RESULTS span LINE QUANTITY… [--time T]…";
    let Some((line, quantities)) = args.split_first() else {
        return Err(format!(
            "a span-wise plot names a lifting line and its station outputs ({usage}); {}",
            if lines.is_empty() {
                "this file has no lifting lines".to_string()
            } else {
                format!("the lines are {}", lines.join(", "))
            }
        ));
    };
    if quantities.is_empty() {
        return Err(format!(
            "name at least one station output of '{line}' to plot, e.g. alpha cl normal_load ({usage})"
        ));
    }
    let at: Vec<Option<f64>> = if times.is_empty() {
        vec![None]
    } else {
        times.iter().copied().map(Some).collect()
    };
    let load_factor = reader.attr("analysis_type").as_deref() == Some("static");
    let mut curves = Vec::new();
    let mut first_time = 0.0;
    for q in quantities {
        for t in &at {
            let p = reader
                .span_profile(line, q, *t)
                .map_err(|e| e.to_string())?;
            first_time = if curves.is_empty() {
                p.time
            } else {
                first_time
            };
            let label = if at.len() == 1 {
                q.clone()
            } else if load_factor {
                format!("{q}, load factor {:.4}", p.time)
            } else {
                format!("{q}, t = {:.4} s", p.time)
            };
            curves.push(Curve {
                label,
                quantity: q.clone(),
                units: p.units,
                x: p.span,
                y: p.values,
            });
        }
    }
    let mut title = format!(
        "{} / {}: {line}",
        reader.attr("model").unwrap_or_default(),
        reader.attr("analysis").unwrap_or_default()
    );
    if at.len() == 1 {
        title += &if load_factor {
            format!(" at load factor {first_time:.4}")
        } else {
            format!(" at t = {first_time:.4} s")
        };
    }
    figure(&title, "span [m]", &curves, out)
}
