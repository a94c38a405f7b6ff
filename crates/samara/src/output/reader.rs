//! Reading samara results files back: metadata, variables, and named channels such as
//! `position:bob:z`, `joint_force:pivot:x` or `kinetic_energy`.

use super::results::FORMAT_VERSION;
use crate::model::error::did_you_mean;
use netcdf3::{DataType, FileReader};
use std::path::{Path, PathBuf};

/// Why a results file cannot be read.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    #[error("cannot open results file '{}': {source}", path.display())]
    Open {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("'{}' is not a NetCDF file or its header is damaged ({detail})", path.display())]
    NotNetcdf { path: PathBuf, detail: String },
    #[error("'{}' is a NetCDF file but not a samara results file (no `format_version` attribute)", path.display())]
    NotSamara { path: PathBuf },
    #[error(
        "'{}' was written by a newer samara (results format {found}; this samara reads up to {supported}); update samara to read it",
        path.display()
    )]
    NewerFormat {
        path: PathBuf,
        found: i32,
        supported: i32,
    },
    #[error("'{}' is truncated: its header lists {listed} output times but only {complete} are complete", path.display())]
    Truncated {
        path: PathBuf,
        listed: usize,
        complete: usize,
    },
    #[error("unknown channel '{spec}': {reason}{}", suggestion.as_ref().map(|s| format!(" — did you mean '{s}'?")).unwrap_or_default())]
    UnknownChannel {
        spec: String,
        reason: String,
        suggestion: Option<String>,
    },
    #[error("time {time} is outside the output times of '{}' ({first} … {last})", path.display())]
    OutsideTimes {
        path: PathBuf,
        time: f64,
        first: f64,
        last: f64,
    },
    #[error("cannot read variable '{name}' of '{}': {detail}", path.display())]
    Variable {
        path: PathBuf,
        name: String,
        detail: String,
    },
}

/// One variable of a results file.
#[derive(Clone, Debug)]
pub struct VariableInfo {
    pub name: String,
    pub dims: Vec<String>,
    pub units: Option<String>,
    pub long_name: Option<String>,
}

/// A time history read from a results file.
#[derive(Clone, Debug)]
pub struct Channel {
    /// The channel as asked for, e.g. `position:bob:z`.
    pub label: String,
    pub units: String,
    pub long_name: String,
    pub values: Vec<f64>,
}

/// An open samara results file.
pub struct ResultsReader {
    reader: FileReader,
    path: PathBuf,
    pub format_version: i32,
    pub node_names: Vec<String>,
    pub joint_names: Vec<String>,
    pub body_names: Vec<String>,
    /// Joint coordinates (`<joint>.<component>`) and their units (`m` or `rad`).
    pub coordinate_names: Vec<String>,
    pub coordinate_units: Vec<String>,
    /// Beam sections (`<beam>#<k>`), if the model has beams.
    pub section_names: Vec<String>,
    /// Element states (`<element>.<state>`) and signals, if the model has them.
    pub state_names: Vec<String>,
    pub signal_names: Vec<String>,
    /// Element outputs (`<element>.<output>`) and their units, if the model has them.
    pub output_names: Vec<String>,
    pub output_units: Vec<String>,
    /// Complete output times in the file.
    pub records: usize,
}

fn names(reader: &mut FileReader, var: &str) -> Vec<String> {
    let Some(dims) = reader.data_set().get_var(var).map(|v| v.get_dims()) else {
        return Vec::new();
    };
    let width = dims.last().map_or(1, |d| d.size()).max(1);
    let bytes = reader.read_var_u8(var).unwrap_or_default();
    bytes
        .chunks(width)
        .map(|c| {
            String::from_utf8_lossy(c)
                .trim_end_matches('\0')
                .to_string()
        })
        .collect()
}

impl ResultsReader {
    /// Opens and checks a results file.
    pub fn open(path: impl AsRef<Path>) -> Result<Self, ReadError> {
        let path = path.as_ref().to_path_buf();
        match std::fs::metadata(&path) {
            Err(e) => return Err(ReadError::Open { path, source: e }),
            Ok(m) if !m.is_file() => {
                return Err(ReadError::NotNetcdf {
                    path,
                    detail: "not a regular file".into(),
                });
            }
            Ok(_) => {}
        }
        let mut reader = FileReader::open(&path).map_err(|e| ReadError::NotNetcdf {
            path: path.clone(),
            detail: short_detail(&format!("{e:?}")),
        })?;
        let ds = reader.data_set();
        let format_version = match ds.get_global_attr_i32("format_version") {
            Some([v, ..]) => *v,
            _ => return Err(ReadError::NotSamara { path }),
        };
        if format_version > FORMAT_VERSION {
            return Err(ReadError::NewerFormat {
                path,
                found: format_version,
                supported: FORMAT_VERSION,
            });
        }
        let listed = ds.num_records().unwrap_or(0);
        // The record variable stored last in each record decides which records are complete.
        let last_var = ds
            .get_vars()
            .iter()
            .filter(|v| v.is_record_var())
            .map(|v| v.name().to_string())
            .next_back();
        let mut complete = listed;
        if let Some(v) = &last_var
            && listed > 0
            && reader.read_record(v, listed - 1).is_err()
        {
            let (mut lo, mut hi) = (0usize, listed - 1); // record lo-1 readable (or lo = 0), hi not
            while lo < hi {
                let mid = (lo + hi) / 2;
                if reader.read_record(v, mid).is_ok() {
                    lo = mid + 1;
                } else {
                    hi = mid;
                }
            }
            complete = lo;
        }
        if complete < listed {
            return Err(ReadError::Truncated {
                path,
                listed,
                complete,
            });
        }
        let node_names = names(&mut reader, "node_name");
        let joint_names = names(&mut reader, "joint_name");
        let body_names = names(&mut reader, "body_name");
        let coordinate_names = names(&mut reader, "coordinate_name");
        let coordinate_units = names(&mut reader, "coordinate_units");
        let section_names = names(&mut reader, "section_name");
        let state_names = names(&mut reader, "state_name");
        let signal_names = names(&mut reader, "signal_name");
        let output_names = names(&mut reader, "output_name");
        let output_units = names(&mut reader, "output_units");
        Ok(Self {
            reader,
            path,
            format_version,
            node_names,
            joint_names,
            body_names,
            coordinate_names,
            coordinate_units,
            section_names,
            state_names,
            signal_names,
            output_names,
            output_units,
            records: complete,
        })
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// A global text attribute.
    pub fn attr(&self, name: &str) -> Option<String> {
        self.reader.data_set().get_global_attr_as_string(name)
    }

    pub fn attr_i64(&self, name: &str) -> Option<i64> {
        self.reader
            .data_set()
            .get_global_attr_i32(name)
            .and_then(|v| v.first())
            .map(|&v| v as i64)
    }

    pub fn attr_f64(&self, name: &str) -> Option<f64> {
        self.reader
            .data_set()
            .get_global_attr_f64(name)
            .and_then(|v| v.first())
            .copied()
    }

    /// All variables, in file order.
    pub fn variables(&self) -> Vec<VariableInfo> {
        self.reader
            .data_set()
            .get_vars()
            .iter()
            .map(|v| VariableInfo {
                name: v.name().to_string(),
                dims: v.dim_names(),
                units: v.get_attr_as_string("units"),
                long_name: v.get_attr_as_string("long_name"),
            })
            .collect()
    }

    /// Whether the file has a variable of this name.
    pub fn has_variable(&self, name: &str) -> bool {
        self.reader.data_set().get_var(name).is_some()
    }

    /// A whole variable as f64 (integers converted).
    pub fn read(&mut self, name: &str) -> Result<Vec<f64>, ReadError> {
        let err = |d: String| ReadError::Variable {
            path: self.path.clone(),
            name: name.to_string(),
            detail: d,
        };
        match self.reader.data_set().var_data_type(name) {
            Some(DataType::F64) => self
                .reader
                .read_var_f64(name)
                .map_err(|e| err(format!("{e:?}"))),
            Some(DataType::I32) => self
                .reader
                .read_var_i32(name)
                .map(|v| v.into_iter().map(f64::from).collect())
                .map_err(|e| err(format!("{e:?}"))),
            Some(t) => Err(err(format!("type {t:?} is not numeric"))),
            None => Err(err("no such variable".into())),
        }
    }

    /// One record (output time) of a record variable as f64.
    pub fn read_record(&mut self, name: &str, record: usize) -> Result<Vec<f64>, ReadError> {
        let err = |d: String| ReadError::Variable {
            path: self.path.clone(),
            name: name.to_string(),
            detail: d,
        };
        let data = self
            .reader
            .read_record(name, record)
            .map_err(|e| err(format!("{e:?}")))?;
        match data.get_f64() {
            Some(v) => Ok(v.to_vec()),
            None => data
                .get_i32()
                .map(|v| v.iter().map(|&x| f64::from(x)).collect())
                .ok_or_else(|| err(format!("type {:?} is not f64 or i32", data.data_type()))),
        }
    }

    /// The output times.
    pub fn time(&mut self) -> Result<Vec<f64>, ReadError> {
        self.read("time")
    }

    /// Names of every channel in the file (for listings and suggestions).
    pub fn channel_names(&self) -> Vec<String> {
        let mut out = Vec::new();
        for v in self.variables() {
            if v.dims.first().map(String::as_str) != Some("time") || v.name == "time" {
                continue;
            }
            match v.dims.len() {
                1 => out.push(v.name.clone()),
                2 => {
                    for c in self.items_of(&v.dims[1]) {
                        out.push(format!("{}:{c}", v.name));
                    }
                }
                3 => {
                    let items = match v.dims[1].as_str() {
                        "node" => &self.node_names,
                        "joint" => &self.joint_names,
                        "section" => &self.section_names,
                        _ => continue,
                    };
                    let comps: &[&str] = if v.dims[2] == "quat" {
                        &["w", "x", "y", "z"]
                    } else {
                        &["x", "y", "z"]
                    };
                    for it in items {
                        for c in comps {
                            out.push(format!("{}:{it}:{c}", v.name));
                        }
                    }
                    if v.name == "position" {
                        for it in items {
                            for c in comps {
                                out.push(format!("displacement:{it}:{c}"));
                            }
                        }
                    }
                }
                _ => {}
            }
        }
        out
    }

    /// Names along a per-item dimension of 2-D time histories.
    fn items_of(&self, dim: &str) -> &[String] {
        match dim {
            "coordinate" => &self.coordinate_names,
            "state" => &self.state_names,
            "signal" => &self.signal_names,
            "output" => &self.output_names,
            _ => &[],
        }
    }

    /// Reads a channel: `variable` for scalar histories, `variable:item:component` for
    /// node and joint vectors (component x, y, z; w, x, y, z for `orientation`), and
    /// `variable:name` for joint coordinates (e.g. `joint_coordinate:pivot.theta3`),
    /// element states (`element_state:strut.pressure`), signals (`signal:sensor.out`) and
    /// element outputs (`element_output:strut.tension`).
    pub fn channel(&mut self, spec: &str) -> Result<Channel, ReadError> {
        if let Some(rest) = spec.strip_prefix("displacement:") {
            return self.displacement(spec, rest);
        }
        let parts: Vec<&str> = spec.split(':').collect();
        let all = self.channel_names();
        let unknown = |reason: String, candidates: &[String]| ReadError::UnknownChannel {
            spec: spec.to_string(),
            reason,
            suggestion: did_you_mean(spec, candidates.iter().map(String::as_str))
                .map(str::to_string),
        };
        let vars = self.variables();
        let Some(info) = vars
            .iter()
            .find(|v| v.name == parts[0] && v.dims.first().map(String::as_str) == Some("time"))
        else {
            return Err(unknown(
                format!("no time history named '{}'", parts[0]),
                &all,
            ));
        };
        let data = self.read(&info.name)?;
        let mut units = info.units.clone().unwrap_or_default();
        let values = match (info.dims.len(), parts.len()) {
            (1, 1) => data,
            (2, 2) => {
                let items = self.items_of(&info.dims[1]);
                let Some(i) = items.iter().position(|n| n == parts[1]) else {
                    return Err(unknown(
                        format!(
                            "'{}' has no {} named '{}'",
                            info.name, info.dims[1], parts[1]
                        ),
                        &all,
                    ));
                };
                let n = items.len();
                // Per-coordinate units: lengths or angles.
                let linear = self.coordinate_units.get(i).is_some_and(|u| u == "m");
                units = match (info.name.as_str(), linear) {
                    ("joint_coordinate", true) => "m".into(),
                    ("joint_coordinate", false) => "rad".into(),
                    ("joint_coordinate_rate", true) => "m s-1".into(),
                    ("joint_coordinate_rate", false) => "rad s-1".into(),
                    ("joint_coordinate_force", true) => "N".into(),
                    ("joint_coordinate_force", false) => "N m".into(),
                    ("element_output", _) => self.output_units.get(i).cloned().unwrap_or(units),
                    _ => units,
                };
                (0..self.records).map(|r| data[r * n + i]).collect()
            }
            (3, 3) => {
                let items = match info.dims[1].as_str() {
                    "node" => &self.node_names,
                    "section" => &self.section_names,
                    _ => &self.joint_names,
                };
                let Some(i) = items.iter().position(|n| n == parts[1]) else {
                    return Err(unknown(
                        format!(
                            "'{}' has no {} named '{}'",
                            info.name, info.dims[1], parts[1]
                        ),
                        &all,
                    ));
                };
                let comps: &[&str] = if info.dims[2] == "quat" {
                    &["w", "x", "y", "z"]
                } else {
                    &["x", "y", "z"]
                };
                let Some(c) = comps.iter().position(|c| *c == parts[2]) else {
                    return Err(unknown(
                        format!("component '{}' is not one of {comps:?}", parts[2]),
                        &all,
                    ));
                };
                let (n, m) = (items.len(), comps.len());
                (0..self.records)
                    .map(|r| data[(r * n + i) * m + c])
                    .collect()
            }
            (1, _) => {
                return Err(unknown(
                    format!(
                        "'{}' is a scalar history: write just '{}'",
                        info.name, info.name
                    ),
                    &all,
                ));
            }
            _ => {
                return Err(unknown(
                    format!(
                        "'{}' needs an item and a component, e.g. '{}'",
                        info.name,
                        all.iter()
                            .find(|c| c.starts_with(&format!("{}:", info.name)))
                            .cloned()
                            .unwrap_or_default()
                    ),
                    &all,
                ));
            }
        };
        Ok(Channel {
            label: spec.to_string(),
            units,
            long_name: info.long_name.clone().unwrap_or_default(),
            values,
        })
    }
}

impl ResultsReader {
    /// `displacement:node:component`: `position` minus `reference_position` (the model's
    /// reference configuration); files written before that variable existed use the first
    /// record's position.
    fn displacement(&mut self, spec: &str, rest: &str) -> Result<Channel, ReadError> {
        let position = self.channel(&format!("position:{rest}"))?;
        let parts: Vec<&str> = rest.split(':').collect();
        let has_reference = self
            .variables()
            .iter()
            .any(|v| v.name == "reference_position");
        let reference = if has_reference {
            let i = self
                .node_names
                .iter()
                .position(|n| n == parts[0])
                .expect("position found the node");
            let c = ["x", "y", "z"]
                .iter()
                .position(|c| *c == parts[1])
                .expect("position found the component");
            self.read("reference_position")?[3 * i + c]
        } else {
            // Older files: from the first record; a file without records has no values.
            match position.values.first() {
                Some(&x0) => x0,
                None => {
                    return Ok(Channel {
                        label: spec.to_string(),
                        ..position
                    });
                }
            }
        };
        Ok(Channel {
            label: spec.to_string(),
            units: position.units,
            long_name: "displacement of the node from its reference position".into(),
            values: position.values.iter().map(|x| x - reference).collect(),
        })
    }
}

/// The reason a parser gave, cut to one short line: its debug form can hold the whole
/// damaged header as raw bytes.
fn short_detail(detail: &str) -> String {
    const MAX: usize = 120;
    let line = detail.lines().next().unwrap_or("").trim();
    if line.chars().count() <= MAX {
        line.to_string()
    } else {
        let cut: String = line.chars().take(MAX).collect();
        format!("{cut}…")
    }
}
