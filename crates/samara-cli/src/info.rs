//! `samara info RESULTS.nc`: what a results file holds.

use samara::output::ResultsReader;

pub fn info(reader: &mut ResultsReader) -> Result<(), samara::output::ReadError> {
    let a = |k: &str| reader.attr(k).unwrap_or_else(|| "?".into());
    println!("{}", reader.path().display());
    println!(
        "  {} (results format {})",
        a("source"),
        reader.format_version
    );
    let file = reader
        .attr("model_file")
        .map(|f| format!(" from {f}"))
        .unwrap_or_default();
    println!("  model     {}{file}", a("model"));
    println!(
        "  analysis  {} ({}), status {}",
        a("analysis"),
        a("analysis_type"),
        a("status")
    );
    if let Some(f) = reader.attr("failure") {
        println!("  failure   {f}");
    }
    let t = reader.time()?;
    match (t.first(), t.last()) {
        (Some(t0), Some(t1)) => println!("  time      {t0} … {t1} s, {} output times", t.len()),
        _ => println!("  time      no output times"),
    }
    println!(
        "  nodes     {} : {}",
        reader.node_names.len(),
        list(&reader.node_names)
    );
    println!(
        "  joints    {} : {}",
        reader.joint_names.len(),
        list(&reader.joint_names)
    );
    if !reader.coordinate_names.is_empty() {
        println!(
            "  joint coordinates {} : {}",
            reader.coordinate_names.len(),
            list(&reader.coordinate_names)
        );
    }
    if let Some(steps) = reader.attr_i64("steps") {
        let its = reader.attr_i64("newton_iterations").unwrap_or(0);
        let per = if steps > 0 {
            its as f64 / steps as f64
        } else {
            0.0
        };
        println!(
            "  solver    {steps} steps, {its} Newton iterations ({per:.2}/step), {} rejected, {} factorizations, wall {:.3} s, max |Φ| {:.2e}",
            reader.attr_i64("rejected_steps").unwrap_or(0),
            reader.attr_i64("factorizations").unwrap_or(0),
            reader.attr_f64("wall_time").unwrap_or(f64::NAN),
            reader
                .attr_f64("max_constraint_violation")
                .unwrap_or(f64::NAN),
        );
        let counts = [
            "line_search_backtracks",
            "contact_redos",
            "pattern_rebuilds",
        ]
        .map(|a| reader.attr_i64(a).unwrap_or(0));
        if counts.iter().any(|&c| c > 0) {
            println!(
                "  contact   line search halved {} corrections, {} steps redone for new contacts, pattern rebuilt {} times",
                counts[0], counts[1], counts[2]
            );
        }
    }
    println!("  variables");
    for v in reader.variables() {
        println!(
            "    {:<22} ({}) [{}] {}",
            v.name,
            v.dims.join(", "),
            v.units.unwrap_or_default(),
            v.long_name.unwrap_or_default()
        );
    }
    Ok(())
}

fn list(names: &[String]) -> String {
    const MAX: usize = 8;
    let mut s = names
        .iter()
        .take(MAX)
        .cloned()
        .collect::<Vec<_>>()
        .join(", ");
    if names.len() > MAX {
        s.push_str(&format!(", … ({} more)", names.len() - MAX));
    }
    s
}
