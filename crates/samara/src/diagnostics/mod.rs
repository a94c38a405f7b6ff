//! Located diagnostics for every input file (models, sections): the source text with
//! line/column lookup, errors and warnings with spans and hints, values that remember
//! where they were written ([`Located`]), and the TOML checks common to every file.
//! Below the model and section layers, which both report through it.

pub mod error;
pub mod located;

pub use error::{Diagnostic, ModelError, Severity, SourceFile, did_you_mean};
pub use located::Located;

/// The largest magnitude a number in a model may have. Products of a few such numbers
/// (energies, stiffness times strain) stay finite in f64; no SI quantity of a mechanical
/// model comes near it.
pub const MAX_MAGNITUDE: f64 = 1e100;

/// Every number written in the file must be finite and at most [`MAX_MAGNITUDE`] in
/// magnitude, whatever key it belongs to: one located error per offending number.
pub fn number_range_diagnostics(text: &str) -> Vec<Diagnostic> {
    use toml::de::{DeTable, DeValue};
    let mut out = Vec::new();
    let Ok(doc) = DeTable::parse(text) else {
        return out; // syntax errors are reported by the parser itself
    };
    let mut stack: Vec<&toml::Spanned<DeValue>> = doc.get_ref().values().collect();
    while let Some(v) = stack.pop() {
        match v.get_ref() {
            DeValue::Float(f) => {
                let raw = f.as_str();
                let x: f64 = raw.replace('_', "").parse().unwrap_or(f64::NAN);
                if !(x.is_finite() && x.abs() <= MAX_MAGNITUDE) {
                    out.push(
                        Diagnostic::error(
                            format!("the number `{raw}` is outside the range samara computes with (finite, |x| ≤ {MAX_MAGNITUDE:e})"),
                            Some(v.span()),
                        )
                        .with_hint("inf and nan are not allowed in a model; use SI units, where no input comes near this bound"),
                    );
                }
            }
            DeValue::Array(a) => stack.extend(a.iter()),
            DeValue::Table(t) => stack.extend(t.values()),
            _ => {}
        }
    }
    out.sort_by_key(|d| d.span.as_ref().map_or(0, |s| s.start));
    out
}

/// Where a parse error without a location most likely is: the most deeply nested line
/// (dotted keys and headers, brackets), for the parser's recursion limit.
fn deepest_line(text: &str) -> Option<std::ops::Range<usize>> {
    let mut best: Option<(usize, std::ops::Range<usize>)> = None;
    let mut start = 0;
    for line in text.split_inclusive('\n') {
        let depth = line
            .bytes()
            .filter(|b| matches!(b, b'.' | b'[' | b'{'))
            .count();
        if best.as_ref().is_none_or(|(d, _)| depth > *d) {
            best = Some((depth, start..start + line.trim_end().len().max(1)));
        }
        start += line.len();
    }
    best.map(|(_, r)| r)
}

/// Hint for a key given twice.
const GIVE_ONCE: &str = "give each key once per table; remove one of the two";

/// Turns a TOML/serde error into a diagnostic with a hint where one can be guessed.
/// `spellings` lists the file's keys that have a second spelling (canonical first).
pub fn parse_error_diagnostic(
    e: &toml::de::Error,
    text: &str,
    spellings: &[&[&str]],
) -> Diagnostic {
    let msg = e.message().trim().to_string();
    if e.span().is_none() && msg.contains("recursion") {
        return Diagnostic::error(
            format!("{msg}: the file nests tables or arrays too deeply"),
            deepest_line(text),
        )
        .with_hint("a model needs only a few levels of nesting; check this line's dotted keys and brackets");
    }
    let mut d = Diagnostic::error(msg.clone(), e.span());
    if let Some(rest) = msg.strip_prefix("unknown field `") {
        if let Some((field, expected)) = rest.split_once('`') {
            let candidates = backticked(expected);
            d.message = format!("unknown key `{field}`");
            d = match did_you_mean(field, candidates.iter().map(|s| s.as_str())) {
                Some(best) => d.with_hint(format!("did you mean `{best}`?")),
                None => d.with_hint(format!(
                    "the keys allowed here are: {}",
                    candidates.join(", ")
                )),
            };
        }
    } else if let Some(rest) = msg.strip_prefix("unknown variant `") {
        if let Some((word, expected)) = rest.split_once('`') {
            let candidates = backticked(expected);
            d.message = format!("unknown value `{word}`");
            d = match did_you_mean(word, candidates.iter().map(|s| s.as_str())) {
                Some(best) => d.with_hint(format!("did you mean `{best}`?")),
                None => d.with_hint(format!("expected one of: {}", candidates.join(", "))),
            };
        }
    } else if msg == "duplicate key" {
        let span = e.span().unwrap_or(0..0);
        let key = text.get(span.clone()).map(str::trim);
        // A table header (`[model]` again, `[nodes]` after `[[nodes]]`, `[ a.b ]`): its
        // line starts with `[`, which no key's line does.
        let line_start = text
            .get(..span.start)
            .and_then(|t| t.rfind('\n'))
            .map_or(0, |i| i + 1);
        let header = text
            .get(line_start..)
            .is_some_and(|l| l.trim_start().starts_with('['));
        let key = key.filter(|k| !k.is_empty() && k.len() <= 64);
        if header {
            if let Some(key) = key {
                d.message = format!("table `{key}` is given twice");
            }
            d = d.with_hint(
                "write each table once; a list of entries is written [[name]] for every entry",
            );
        } else {
            if let Some(key) = key {
                d.message = format!("key `{key}` is given twice in this table");
            }
            d = d.with_hint(GIVE_ONCE);
        }
    } else if let Some(rest) = msg.strip_prefix("duplicate field `") {
        if let Some((field, _)) = rest.split_once('`') {
            let spellings: &[&str] = spellings
                .iter()
                .find(|s| s.contains(&field))
                .copied()
                .unwrap_or(&[]);
            d.message = format!("key `{field}` is given twice in this table");
            if let Some(at) = e.span().and_then(|t| second_key(text, t, field, spellings)) {
                d.span = Some(at);
            }
            d = d.with_hint(if spellings.is_empty() {
                GIVE_ONCE.to_string()
            } else {
                format!(
                    "{} are two spellings of one key: give it once",
                    spellings
                        .iter()
                        .map(|k| format!("`{k}`"))
                        .collect::<Vec<_>>()
                        .join(" and ")
                )
            });
        }
    } else if let Some(rest) = msg.strip_prefix("missing field `") {
        if let Some((field, _)) = rest.split_once('`') {
            d.message = format!("missing required key `{field}`");
            d = d.with_hint(format!(
                "add `{field} = …` to this table (see docs/model-reference.md)"
            ));
        }
    } else if msg.contains("invalid type") || msg.contains("expected") {
        d = d.with_hint("check the value's type: numbers are written like 1.0 or 2e-3, vectors like [0.0, 1.0, 0.0], names in quotes");
    }
    d
}

/// Where the second `key = …` (any of its `spellings`) is written in the table spanned by
/// `table`: an inline table's braces, or a header's lines up to the next header.
fn second_key(
    text: &str,
    table: std::ops::Range<usize>,
    key: &str,
    spellings: &[&str],
) -> Option<std::ops::Range<usize>> {
    let from = table.start.min(text.len());
    let rest = text.get(from..)?;
    let (start, region) = if rest.starts_with('{') {
        (from, text.get(from..table.end.clamp(from, text.len()))?)
    } else {
        // Past the header line, to the next table header.
        let body_start = rest.find('\n').map_or(rest.len(), |i| i + 1);
        let body = &rest[body_start..];
        (
            from + body_start,
            &body[..body.find("\n[").map_or(body.len(), |i| i + 1)],
        )
    };
    let names: Vec<&str> = if spellings.is_empty() {
        vec![key]
    } else {
        spellings.to_vec()
    };
    let bytes = region.as_bytes();
    let mut hits = names
        .iter()
        .flat_map(|n| region.match_indices(n).map(move |(i, _)| (i, n.len())))
        .filter(|&(i, len)| {
            let before_ok = i == 0 || matches!(bytes[i - 1], b' ' | b'\t' | b'\n' | b'{' | b',');
            let after = region[i + len..].trim_start_matches([' ', '\t']);
            before_ok && after.starts_with('=')
        })
        .collect::<Vec<_>>();
    hits.sort_unstable();
    hits.get(1).map(|&(i, len)| start + i..start + i + len)
}

fn backticked(s: &str) -> Vec<String> {
    s.split('`')
        .enumerate()
        .filter(|(i, _)| i % 2 == 1)
        .map(|(_, w)| w.to_string())
        .collect()
}
