//! Span-wise profiles of a lifting line's station outputs at one output time
//! (`samara plot RESULTS span LINE QUANTITY… --time T`).
//!
//! The stations of line `L` are the elements `L.0`, `L.1`, …; each writes its distance from
//! the line's root as the output `span` [m], the abscissa of the profile.

use super::reader::{ReadError, ResultsReader};
use crate::model::error::did_you_mean;

/// One quantity of a line's stations at one output time, ordered by span.
#[derive(Clone, Debug, PartialEq)]
pub struct SpanProfile {
    /// The line and the station output, e.g. `blade1` and `alpha`.
    pub line: String,
    pub quantity: String,
    pub units: String,
    /// The output time read (the nearest to the one asked for) [s] (load factor for a
    /// static analysis).
    pub time: f64,
    /// Station distances from the line's root [m], increasing.
    pub span: Vec<f64>,
    /// The quantity at each station.
    pub values: Vec<f64>,
}

impl ResultsReader {
    /// The lines whose stations write span-wise outputs (element outputs `L.k.span`).
    pub fn aero_lines(&self) -> Vec<String> {
        let mut out: Vec<String> = Vec::new();
        for n in &self.output_names {
            if let Some((line, _)) = station_of(n, "span")
                && !out.iter().any(|l| l == line)
            {
                out.push(line.to_string());
            }
        }
        out
    }

    /// The station outputs of `line` at the output time nearest to `time` (the last one
    /// when `None`), against span. `time` must lie within the file's output times.
    pub fn span_profile(
        &mut self,
        line: &str,
        quantity: &str,
        time: Option<f64>,
    ) -> Result<SpanProfile, ReadError> {
        let spec = format!("span {line} {quantity}");
        let lines = self.aero_lines();
        if !lines.iter().any(|l| l == line) {
            let reason = if lines.is_empty() {
                "the file has no lifting-line stations (element outputs `<line>.<k>.span`)"
                    .to_string()
            } else {
                format!(
                    "no lifting line '{line}'; the lines are {}",
                    lines.join(", ")
                )
            };
            return Err(ReadError::UnknownChannel {
                suggestion: did_you_mean(line, lines.iter().map(String::as_str))
                    .map(str::to_string),
                spec,
                reason,
            });
        }
        // Column of each station's span and quantity in `element_output`.
        let mut columns: Vec<(usize, usize)> = Vec::new();
        let mut quantities: Vec<String> = Vec::new();
        for (i, n) in self.output_names.iter().enumerate() {
            let Some((l, k)) = station_of(n, "span") else {
                continue;
            };
            if l != line {
                continue;
            }
            let name = format!("{l}.{k}.{quantity}");
            match self.output_names.iter().position(|m| *m == name) {
                Some(j) => columns.push((i, j)),
                None if columns.is_empty() && quantities.is_empty() => {
                    let prefix = format!("{l}.{k}.");
                    quantities = self
                        .output_names
                        .iter()
                        .filter_map(|m| m.strip_prefix(&prefix))
                        .filter(|q| *q != "span")
                        .map(str::to_string)
                        .collect();
                }
                None => {}
            }
        }
        if columns.is_empty() {
            return Err(ReadError::UnknownChannel {
                suggestion: did_you_mean(quantity, quantities.iter().map(String::as_str))
                    .map(str::to_string),
                spec,
                reason: format!(
                    "the stations of '{line}' have no output '{quantity}'; they have {}",
                    quantities.join(", ")
                ),
            });
        }
        let times = self.time()?;
        let (Some(&first), Some(&last)) = (times.first(), times.last()) else {
            return Err(ReadError::OutsideTimes {
                path: self.path().to_path_buf(),
                time: time.unwrap_or(f64::NAN),
                first: f64::NAN,
                last: f64::NAN,
            });
        };
        let slack = |t: f64| 1e-9 * t.abs().max(1.0);
        let record = match time {
            None => times.len() - 1,
            Some(t) if t.is_finite() && t >= first - slack(first) && t <= last + slack(last) => {
                nearest(&times, t)
            }
            Some(t) => {
                return Err(ReadError::OutsideTimes {
                    path: self.path().to_path_buf(),
                    time: t,
                    first,
                    last,
                });
            }
        };
        let row = self.read_record("element_output", record)?;
        let mut pairs: Vec<(f64, f64)> = columns.iter().map(|&(i, j)| (row[i], row[j])).collect();
        pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
        let units = columns
            .first()
            .and_then(|&(_, j)| self.output_units.get(j).cloned())
            .unwrap_or_default();
        Ok(SpanProfile {
            line: line.to_string(),
            quantity: quantity.to_string(),
            units,
            time: times[record],
            span: pairs.iter().map(|p| p.0).collect(),
            values: pairs.iter().map(|p| p.1).collect(),
        })
    }
}

/// `(line, k)` of a station output named `line.k.<quantity>`.
fn station_of<'a>(name: &'a str, quantity: &str) -> Option<(&'a str, &'a str)> {
    let rest = name.strip_suffix(quantity)?.strip_suffix('.')?;
    let (line, k) = rest.rsplit_once('.')?;
    (!line.is_empty() && !k.is_empty() && k.bytes().all(|b| b.is_ascii_digit()))
        .then_some((line, k))
}

/// Index of the entry of increasing `times` nearest to `t`.
fn nearest(times: &[f64], t: f64) -> usize {
    let i = times.partition_point(|&x| x < t);
    if i == 0 {
        0
    } else if i == times.len() || t - times[i - 1] <= times[i] - t {
        i - 1
    } else {
        i
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn station_names_and_nearest_times() {
        assert_eq!(station_of("blade1.12.span", "span"), Some(("blade1", "12")));
        assert_eq!(
            station_of("rotor.blade.3.span", "span"),
            Some(("rotor.blade", "3"))
        );
        assert_eq!(station_of("blade1.x.span", "span"), None);
        assert_eq!(station_of("blade1.12.cl", "span"), None);
        assert_eq!(station_of(".3.span", "span"), None);
        let t = [0.0, 0.1, 0.2, 0.30000000000000004];
        assert_eq!(nearest(&t, -1.0), 0);
        assert_eq!(nearest(&t, 0.04), 0);
        assert_eq!(nearest(&t, 0.06), 1);
        assert_eq!(nearest(&t, 0.3), 3);
        assert_eq!(nearest(&t, 9.0), 3);
    }
}
