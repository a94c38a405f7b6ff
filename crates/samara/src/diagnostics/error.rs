//! Model-file diagnostics: what is wrong, where (file, line, column), and a hint.

use std::fmt;
use std::ops::Range;
use std::path::PathBuf;
use std::sync::{Arc, OnceLock};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Severity {
    Error,
    Warning,
}

/// One finding about a model file.
#[derive(Clone, Debug)]
pub struct Diagnostic {
    pub severity: Severity,
    /// What is wrong, and what was expected.
    pub message: String,
    /// Byte range in the model file, if the finding has a location.
    pub span: Option<Range<usize>>,
    /// How to fix it.
    pub hint: Option<String>,
}

impl Diagnostic {
    pub fn error(message: impl Into<String>, span: Option<Range<usize>>) -> Self {
        Self {
            severity: Severity::Error,
            message: message.into(),
            span,
            hint: None,
        }
    }

    pub fn warning(message: impl Into<String>, span: Option<Range<usize>>) -> Self {
        Self {
            severity: Severity::Warning,
            message: message.into(),
            span,
            hint: None,
        }
    }

    pub fn with_hint(mut self, hint: impl Into<String>) -> Self {
        self.hint = Some(hint.into());
        self
    }
}

/// The text of a model file and where it came from, for locating diagnostics.
#[derive(Clone, Debug)]
pub struct SourceFile {
    pub path: PathBuf,
    pub text: Arc<str>,
    /// Byte offset of the start of every line, computed on first use (so that locating
    /// many diagnostics costs O(log n) each, not a scan of the file).
    line_starts: Arc<OnceLock<Vec<usize>>>,
}

impl SourceFile {
    pub fn new(path: impl Into<PathBuf>, text: impl Into<Arc<str>>) -> Self {
        Self {
            path: path.into(),
            text: text.into(),
            line_starts: Arc::default(),
        }
    }

    /// 1-based line and column (in characters) of a byte offset.
    pub fn line_col(&self, offset: usize) -> (usize, usize) {
        let starts = self.line_starts.get_or_init(|| {
            std::iter::once(0)
                .chain(self.text.match_indices('\n').map(|(i, _)| i + 1))
                .collect()
        });
        let offset = floor_char_boundary(&self.text, offset.min(self.text.len()));
        let line = starts.partition_point(|&s| s <= offset);
        let line_start = starts[line - 1];
        let col = self.text[line_start..offset].chars().count() + 1;
        (line, col)
    }
}

/// At most this many diagnostics are printed; the rest are counted.
pub const MAX_SHOWN_DIAGNOSTICS: usize = 50;

fn floor_char_boundary(s: &str, mut i: usize) -> usize {
    while i > 0 && !s.is_char_boundary(i) {
        i -= 1;
    }
    i
}

/// A model file that cannot be used: every error found, plus the warnings.
#[derive(Clone, Debug)]
pub struct ModelError {
    pub source: SourceFile,
    pub diagnostics: Vec<Diagnostic>,
}

impl ModelError {
    pub fn errors(&self) -> impl Iterator<Item = &Diagnostic> {
        self.diagnostics
            .iter()
            .filter(|d| d.severity == Severity::Error)
    }

    /// `path:line:col: severity: message` lines with the hints, as printed by `samara`.
    pub fn render_plain(&self) -> String {
        render_diagnostics(&self.source, &self.diagnostics)
    }
}

/// Plain-text rendering of diagnostics (one block per finding).
pub fn render_diagnostics(source: &SourceFile, diagnostics: &[Diagnostic]) -> String {
    let mut out = String::new();
    for d in diagnostics.iter().take(MAX_SHOWN_DIAGNOSTICS) {
        let sev = match d.severity {
            Severity::Error => "error",
            Severity::Warning => "warning",
        };
        match &d.span {
            Some(span) => {
                let (line, col) = source.line_col(span.start);
                out.push_str(&format!(
                    "{}:{}:{}: {}: {}\n",
                    source.path.display(),
                    line,
                    col,
                    sev,
                    d.message
                ));
            }
            None => out.push_str(&format!(
                "{}: {}: {}\n",
                source.path.display(),
                sev,
                d.message
            )),
        }
        if let Some(h) = &d.hint {
            out.push_str(&format!("  hint: {h}\n"));
        }
    }
    if let Some(more) = not_shown(diagnostics) {
        out.push_str(&more);
        out.push('\n');
    }
    out
}

/// `… and N more errors and M more warnings not shown` when the list was cut.
pub fn not_shown(diagnostics: &[Diagnostic]) -> Option<String> {
    let rest = diagnostics.get(MAX_SHOWN_DIAGNOSTICS..)?;
    if rest.is_empty() {
        return None;
    }
    let errors = rest
        .iter()
        .filter(|d| d.severity == Severity::Error)
        .count();
    let warnings = rest.len() - errors;
    let plural = |n: usize, w: &str| format!("{n} more {w}{}", if n == 1 { "" } else { "s" });
    let parts: Vec<String> = [(errors, "error"), (warnings, "warning")]
        .iter()
        .filter(|(n, _)| *n > 0)
        .map(|(n, w)| plural(*n, w))
        .collect();
    Some(format!(
        "… and {} not shown (the first {MAX_SHOWN_DIAGNOSTICS} are listed)",
        parts.join(" and ")
    ))
}

impl fmt::Display for ModelError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let n = self.errors().count();
        writeln!(
            f,
            "{} error{} in model file {}",
            n,
            if n == 1 { "" } else { "s" },
            self.source.path.display()
        )?;
        write!(f, "{}", self.render_plain())
    }
}

impl std::error::Error for ModelError {}

/// Closest candidate to `word` by edit distance, if it is close enough to be a likely typo.
pub fn did_you_mean<'a>(
    word: &str,
    candidates: impl IntoIterator<Item = &'a str>,
) -> Option<&'a str> {
    let mut best: Option<(&str, f64)> = None;
    for c in candidates {
        let score = strsim::jaro_winkler(word, c);
        if score > 0.7 && best.is_none_or(|(_, s)| score > s) {
            best = Some((c, score));
        }
    }
    best.map(|(c, _)| c)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_and_column_are_one_based_and_count_characters() {
        let s = SourceFile::new("m.toml", "a = 1\nbé = 2\n");
        assert_eq!(s.line_col(0), (1, 1));
        assert_eq!(s.line_col(6), (2, 1));
        // 'é' is two bytes; the '=' after "bé " is the 4th character.
        let eq = s.text.find("= 2").unwrap();
        assert_eq!(s.line_col(eq), (2, 4));
    }

    #[test]
    fn suggestions() {
        assert_eq!(did_you_mean("bobb", ["bob", "ground", "arm"]), Some("bob"));
        assert_eq!(did_you_mean("xyz", ["bob", "ground"]), None);
    }
}
