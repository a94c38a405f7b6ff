//! Terminal output: diagnostics (miette), solver failures, the end-of-run summary.

use miette::{LabeledSpan, MietteDiagnostic, NamedSource, Report, Severity as MSeverity};
use samara::analysis::{AnalysisSummary, SolverFailure};
use samara::model::error::{MAX_SHOWN_DIAGNOSTICS, not_shown};
use samara::model::{Diagnostic, Severity, SourceFile};
use std::io::IsTerminal;
use std::path::PathBuf;
use std::time::Duration;

pub fn install_hook() {
    let tty = std::io::stderr().is_terminal();
    let _ = miette::set_hook(Box::new(move |_| {
        Box::new(
            miette::MietteHandlerOpts::new()
                .color(tty)
                .unicode(tty)
                .terminal_links(false)
                .context_lines(1)
                .width(100)
                .build(),
        )
    }));
}

/// Prints model diagnostics: `file:line:col: error: message`, the source line, the hint.
pub fn diagnostics(source: &SourceFile, diags: &[Diagnostic]) {
    let code = SharedText(source.text.clone());
    for d in diags.iter().take(MAX_SHOWN_DIAGNOSTICS) {
        let located = d.span.as_ref().map(|s| {
            let (l, c) = source.line_col(s.start);
            format!("{}:{l}:{c}", source.path.display())
        });
        let sev = match d.severity {
            Severity::Error => "error",
            Severity::Warning => "warning",
        };
        eprintln!(
            "{}: {sev}: {}",
            located.unwrap_or_else(|| source.path.display().to_string()),
            d.message
        );
        let mut md = MietteDiagnostic::new(d.message.clone()).with_severity(match d.severity {
            Severity::Error => MSeverity::Error,
            Severity::Warning => MSeverity::Warning,
        });
        if let Some(h) = &d.hint {
            md = md.with_help(h.clone());
        }
        if let Some(s) = &d.span {
            let len = (s.end - s.start)
                .max(1)
                .min(source.text.len().saturating_sub(s.start).max(1));
            md = md.with_label(LabeledSpan::at(s.start..s.start + len, "here"));
            let report = Report::new(md).with_source_code(NamedSource::new(
                source.path.display().to_string(),
                code.clone(),
            ));
            eprintln!("{report:?}");
        } else if let Some(h) = &d.hint {
            eprintln!("  help: {h}\n");
        }
    }
    if let Some(more) = not_shown(diags) {
        eprintln!("{more}");
    }
}

/// The model text shared by every diagnostic's report (no copy per diagnostic).
#[derive(Clone)]
struct SharedText(std::sync::Arc<str>);

impl miette::SourceCode for SharedText {
    fn read_span<'a>(
        &'a self,
        span: &miette::SourceSpan,
        context_lines_before: usize,
        context_lines_after: usize,
    ) -> Result<Box<dyn miette::SpanContents<'a> + 'a>, miette::MietteError> {
        self.0
            .as_ref()
            .read_span(span, context_lines_before, context_lines_after)
    }
}

/// Prints a library error (I/O, results file) with an optional hint.
pub fn error(e: &samara::Error, hint: Option<&str>) {
    eprintln!("error: {e}");
    if let Some(h) = hint {
        eprintln!("  help: {h}");
    }
}

pub fn solver_failure(f: &SolverFailure, path: &std::path::Path, records: u64) {
    eprintln!(
        "error: analysis '{}' stopped at t = {:.6e}: {}",
        f.analysis, f.time, f.reason
    );
    if let Some(h) = &f.hint {
        eprintln!("  help: {h}");
    }
    eprintln!(
        "  the {records} output times computed before the failure are in {} (status = \"failed\")",
        path.display()
    );
}

pub struct Row {
    pub summary: AnalysisSummary,
    pub path: PathBuf,
    pub records: u64,
    pub end_time: f64,
}

/// One screen: per analysis, what it did and where the results are.
pub fn summary(model: &str, rows: &[Row], total: Duration) {
    println!("model '{model}'");
    println!(
        "  {:<14} {:<8} {:>8} {:>8} {:>7} {:>8} {:>10} {:>10}  results",
        "analysis", "type", "steps", "newton", "it/step", "rejected", "max |Φ|", "wall [s]"
    );
    for r in rows {
        let s = &r.summary;
        let per = if s.steps > 0 {
            s.newton_iterations as f64 / s.steps as f64
        } else {
            0.0
        };
        let status = if s.failure.is_some() { " (FAILED)" } else { "" };
        println!(
            "  {:<14} {:<8} {:>8} {:>8} {:>7.2} {:>8} {:>10.2e} {:>10.3}  {} ({} records){status}",
            s.name,
            s.kind,
            s.steps,
            s.newton_iterations,
            per,
            s.rejected_steps,
            s.max_constraint_violation,
            s.wall_time.as_secs_f64(),
            r.path.display(),
            r.records
        );
        if s.line_search_backtracks + s.contact_redos + s.pattern_rebuilds > 0 {
            println!(
                "  {:<14} line search halved {} corrections; {} steps redone for new contacts; contact pattern rebuilt {} times",
                "", s.line_search_backtracks, s.contact_redos, s.pattern_rebuilds
            );
        }
        if s.fallbacks > 0 {
            println!(
                "  {:<14} {} of {} factorizations needed the pivoting sparse LU",
                "", s.fallbacks, s.factorizations
            );
        }
        if let Some(p) = &s.parts {
            let [a, b, sep] = p.blocks;
            let on = if p.partner_thread {
                "part 1 on a partner thread"
            } else {
                "one thread"
            };
            println!(
                "  {:<14} two parts: {a} + {b} blocks, separator {sep}; {on}",
                ""
            );
        }
        let _ = r.end_time;
    }
    println!("  total wall time {:.3} s", total.as_secs_f64());
}
