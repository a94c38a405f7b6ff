//! The results file of one analysis: NetCDF-3 (64-bit offset), written one output time at
//! a time, so an interrupted run keeps every completed record. The layout is documented in
//! `docs/results.md`; [`FORMAT_VERSION`] changes whenever it changes incompatibly.

use super::netcdf::{AttrValue, Definition, DimId, NcError, NcType, VarId, Writer};
use crate::analysis::{Analysis, AnalysisSummary, ArraySpec, OutputFrame, Recorder};
use crate::model::{AnalysisDef, Model};
use crate::system::System;
use std::path::{Path, PathBuf};

/// Version of the results layout (global attribute `format_version`).
/// 2: a static analysis writes the unloaded state (load factor 0) as its first record.
pub const FORMAT_VERSION: i32 = 2;

/// Header bytes kept free so the closing attributes (status, counts, failure reason) can
/// be written when the analysis ends.
const HEADER_RESERVE: usize = 4096;

struct Vars {
    time: VarId,
    load_factor: Option<VarId>,
    position: VarId,
    orientation: VarId,
    velocity: VarId,
    angular_velocity: VarId,
    joint_position: Option<VarId>,
    joint_axes: Option<VarId>,
    joint_force: Option<VarId>,
    joint_moment: Option<VarId>,
    coordinate: Option<CoordinateVars>,
    kinetic: VarId,
    potential: VarId,
    external_work: VarId,
    dissipated: VarId,
    violation: VarId,
    diagnostics: Option<DiagnosticVars>,
    /// Sectional output of the beams (models with beams only).
    beams: Option<super::beam_vars::BeamVars>,
    /// Element states and signals (models with them only).
    states: Option<super::state_vars::StateVars>,
    /// Arrays of the analysis that are not time records, by name.
    arrays: Vec<(String, VarId, usize)>,
}

struct CoordinateVars {
    value: VarId,
    rate: VarId,
    force: VarId,
}

struct DiagnosticVars {
    iterations: VarId,
    residual: VarId,
    condition: VarId,
    step: VarId,
    error: VarId,
    rejected: VarId,
    backtracks: VarId,
}

/// Writes one analysis's results as they are computed (a [`Recorder`]).
pub struct ResultsFile {
    writer: Writer,
    /// The file's path (kept apart from the writer so errors need no allocation per record).
    path: PathBuf,
    vars: Vars,
    /// Per-record scratch (no allocation per record).
    buf3: Vec<f64>,
    buf4: Vec<f64>,
    jf: Vec<f64>,
    jm: Vec<f64>,
    jp: Vec<f64>,
    ja: Vec<f64>,
    mu_all: Vec<f64>,
    cq: Vec<f64>,
    cv: Vec<f64>,
    cf: Vec<f64>,
    /// An earlier file of the same name, moved aside.
    pub backup: Option<PathBuf>,
}

fn nc_err(path: &Path, e: NcError) -> crate::Error {
    let mut message = e.to_string();
    if let NcError::Io { source, .. } = &e
        && matches!(
            source.kind(),
            std::io::ErrorKind::StorageFull | std::io::ErrorKind::QuotaExceeded
        )
    {
        // Each record is written before the header counts it (output/netcdf.rs).
        message.push_str(
            "; the disk is full (or the quota used up): free space or write the results \
             elsewhere (--out); the records written before the error, if any, stay readable \
             in the file (status `running`)",
        );
    }
    crate::Error::Output {
        path: path.to_path_buf(),
        message,
    }
}

/// The first free numbered backup name `stem.~k~.nc` beside `path`.
fn backup_name(path: &Path) -> PathBuf {
    let stem = path
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("results");
    let dir = path.parent().unwrap_or(Path::new("."));
    (1..)
        .map(|k| dir.join(format!("{stem}.~{k}~.nc")))
        .find(|p| !p.exists())
        .expect("some backup name is free")
}

impl ResultsFile {
    /// Results file path of an analysis in `dir`.
    pub fn path_for(dir: &Path, analysis: &AnalysisDef) -> PathBuf {
        dir.join(format!("{}.nc", analysis.name))
    }

    /// Creates `dir/<analysis>.nc`. An existing file of that name is never overwritten: it
    /// is renamed to the first free `<analysis>.~k~.nc`, reported in [`Self::backup`].
    pub fn create(
        dir: &Path,
        model: &Model,
        model_file: Option<&Path>,
        sys: &System,
        analysis: &AnalysisDef,
    ) -> Result<Self, crate::Error> {
        Self::create_for(dir, model, model_file, sys, analysis.stage().as_ref())
    }

    /// [`Self::create`] for any analysis stage (its arrays are defined in the header).
    pub fn create_for(
        dir: &Path,
        model: &Model,
        model_file: Option<&Path>,
        sys: &System,
        analysis: &dyn Analysis,
    ) -> Result<Self, crate::Error> {
        Self::open(Some(dir), model, model_file, sys, analysis)
    }

    /// The results of an analysis written in memory instead of a file: the same bytes
    /// [`Self::create`] would write, returned by [`Self::finish_in_memory`].
    pub fn in_memory(
        model: &Model,
        model_file: Option<&Path>,
        sys: &System,
        analysis: &dyn Analysis,
    ) -> Result<Self, crate::Error> {
        Self::open(None, model, model_file, sys, analysis)
    }

    fn open(
        dir: Option<&Path>,
        model: &Model,
        model_file: Option<&Path>,
        sys: &System,
        analysis: &dyn Analysis,
    ) -> Result<Self, crate::Error> {
        let in_memory = dir.is_none();
        let dir = dir.unwrap_or(Path::new("<memory>"));
        // Validation checks this for model files; a model built in code gets it here, so
        // that no name can place a file outside `dir`.
        if !crate::model::is_plain_file_name(analysis.name()) {
            return Err(crate::Error::Output {
                path: dir.to_path_buf(),
                message: format!(
                    "analysis name {:?} is not a plain file name (letters, digits, `_`, `-`, `.`; not starting with `.`)",
                    analysis.name()
                ),
            });
        }
        let path = dir.join(format!("{}.nc", analysis.name()));
        let mut backup = None;
        if !in_memory {
            std::fs::create_dir_all(dir).map_err(|e| crate::Error::Io {
                path: dir.to_path_buf(),
                action: "create the results directory",
                source: e,
            })?;
        }
        if !in_memory && path.exists() {
            let b = backup_name(&path);
            std::fs::rename(&path, &b).map_err(|e| crate::Error::Io {
                path: path.clone(),
                action: "move the earlier results file aside",
                source: e,
            })?;
            backup = Some(b);
        }
        let diagnostics = analysis.diagnostics();
        let is_static = analysis.has_load_factor();
        let n_nodes = sys.n_nodes();
        let n_joints = model.joints.len();

        let mut d = Definition::new();
        let time = d.add_record_dim("time");
        let node = d.add_dim("node", n_nodes);
        let vec3 = d.add_dim("vec3", 3);
        let quat = d.add_dim("quat", 4);
        let longest = model
            .nodes
            .iter()
            .map(|n| n.name.len())
            .chain(model.joints.iter().map(|j| j.name.len()))
            .chain(model.bodies.iter().map(|b| b.name.len()))
            .chain(sys.coordinate_names.iter().map(|c| c.len()))
            .max()
            .unwrap_or(1)
            .max(1);
        let strlen = d.add_dim("name_strlen", longest);
        let joint = (n_joints > 0).then(|| d.add_dim("joint", n_joints));
        let n_bodies = model.bodies.len();
        let body = (n_bodies > 0).then(|| d.add_dim("body", n_bodies));
        let n_coords = sys.n_coordinates + sys.n_passive;
        let coordinate = (n_coords > 0).then(|| d.add_dim("coordinate", n_coords));
        let unit_len = d.add_dim("unit_strlen", 3);

        let text = |s: &str| AttrValue::Text(s.to_string());
        let var = |d: &mut Definition,
                   name: &str,
                   ty: NcType,
                   dims: &[DimId],
                   units: &str,
                   long: &str| {
            let v = d.add_var(name, ty, dims);
            if !units.is_empty() {
                d.add_var_attr(v, "units", text(units));
            }
            d.add_var_attr(v, "long_name", text(long));
            if ty == NcType::Double {
                d.add_var_attr(v, "_FillValue", AttrValue::Double(vec![f64::NAN]));
            }
            v
        };
        let time_v = var(
            &mut d,
            "time",
            NcType::Double,
            &[time],
            "s",
            if is_static {
                "load factor (pseudo-time of the load increments)"
            } else {
                "time"
            },
        );
        let node_name = var(
            &mut d,
            "node_name",
            NcType::Char,
            &[node, strlen],
            "",
            "node name",
        );
        let reference_position = var(
            &mut d,
            "reference_position",
            NcType::Double,
            &[node, vec3],
            "m",
            "position of the node in the model's reference configuration (displacement = position - reference_position)",
        );
        let reference_orientation = var(
            &mut d,
            "reference_orientation",
            NcType::Double,
            &[node, quat],
            "1",
            "orientation of the node in the model's reference configuration (unit quaternion w, x, y, z; global frame)",
        );
        let inertia_row = d.add_dim("inertia_row", 3);
        let body_vars = body.map(|b| {
            (
                var(
                    &mut d,
                    "body_name",
                    NcType::Char,
                    &[b, strlen],
                    "",
                    "body name",
                ),
                var(
                    &mut d,
                    "body_node",
                    NcType::Int,
                    &[b],
                    "",
                    "index of the body's node in `node`",
                ),
                var(
                    &mut d,
                    "body_cg_offset",
                    NcType::Double,
                    &[b, vec3],
                    "m",
                    "centre of gravity relative to the node, node frame",
                ),
                var(&mut d, "body_mass", NcType::Double, &[b], "kg", "body mass"),
                var(
                    &mut d,
                    "body_inertia",
                    NcType::Double,
                    &[b, inertia_row, vec3],
                    "kg m2",
                    "inertia tensor about the centre of gravity, node frame (rows inertia_row, columns vec3)",
                ),
            )
        });
        let joint_name = joint.map(|j| {
            var(
                &mut d,
                "joint_name",
                NcType::Char,
                &[j, strlen],
                "",
                "joint name",
            )
        });
        let load_factor = is_static.then(|| {
            var(
                &mut d,
                "load_factor",
                NcType::Double,
                &[time],
                "1",
                "load factor of the increment",
            )
        });
        let position = var(
            &mut d,
            "position",
            NcType::Double,
            &[time, node, vec3],
            "m",
            "node position, global frame",
        );
        let orientation = var(
            &mut d,
            "orientation",
            NcType::Double,
            &[time, node, quat],
            "1",
            "node orientation as a unit quaternion (w, x, y, z), node frame to global",
        );
        let velocity = var(
            &mut d,
            "velocity",
            NcType::Double,
            &[time, node, vec3],
            "m s-1",
            "node velocity, global frame",
        );
        let angular_velocity = var(
            &mut d,
            "angular_velocity",
            NcType::Double,
            &[time, node, vec3],
            "rad s-1",
            "node angular velocity, global frame",
        );
        let axes3 = joint.map(|_| d.add_dim("axis", 3));
        let joint_position = joint.map(|j| {
            var(
                &mut d,
                "joint_position",
                NcType::Double,
                &[time, j, vec3],
                "m",
                "joint point (on side B), global frame",
            )
        });
        let joint_axes = joint.zip(axes3).map(|(j, ax)| {
            var(
                &mut d,
                "joint_axes",
                NcType::Double,
                &[time, j, ax, vec3],
                "1",
                "axes e1, e2, e3 of joint frame A, global components",
            )
        });
        let (joint_force, joint_moment) = match joint {
            Some(j) => (
                Some(var(
                    &mut d,
                    "joint_force",
                    NcType::Double,
                    &[time, j, vec3],
                    "N",
                    "reaction force on side B by side A, joint frame A",
                )),
                Some(var(
                    &mut d,
                    "joint_moment",
                    NcType::Double,
                    &[time, j, vec3],
                    "N m",
                    "reaction moment on side B by side A about the joint point, joint frame A",
                )),
            ),
            None => (None, None),
        };
        let coordinate_names = coordinate.map(|c| {
            (
                var(
                    &mut d,
                    "coordinate_name",
                    NcType::Char,
                    &[c, strlen],
                    "",
                    "joint coordinate name, <joint>.<component>",
                ),
                var(
                    &mut d,
                    "coordinate_units",
                    NcType::Char,
                    &[c, unit_len],
                    "",
                    "units of the coordinate: m (d1, d2, d3) or rad (theta1, theta2, theta3)",
                ),
            )
        });
        let coordinate_vars = coordinate.map(|c| CoordinateVars {
            value: var(
                &mut d,
                "joint_coordinate",
                NcType::Double,
                &[time, c],
                "m or rad",
                "joint coordinate: relative displacement along or rotation about an axis of frame A (see coordinate_units)",
            ),
            rate: var(
                &mut d,
                "joint_coordinate_rate",
                NcType::Double,
                &[time, c],
                "m s-1 or rad s-1",
                "rate of the joint coordinate",
            ),
            force: var(
                &mut d,
                "joint_coordinate_force",
                NcType::Double,
                &[time, c],
                "N or N m",
                "generalized force on the coordinate from its springs, dampers, backlash, inputs and drive (the actuator force of a drive); positive tends to increase the coordinate",
            ),
        });
        let kinetic = var(
            &mut d,
            "kinetic_energy",
            NcType::Double,
            &[time],
            "J",
            "kinetic energy",
        );
        let potential = var(
            &mut d,
            "potential_energy",
            NcType::Double,
            &[time],
            "J",
            "potential energy of gravity and springs",
        );
        let external_work = var(
            &mut d,
            "external_work",
            NcType::Double,
            &[time],
            "J",
            "work done by applied loads since the start of the analysis",
        );
        let dissipated = var(
            &mut d,
            "dissipated_energy",
            NcType::Double,
            &[time],
            "J",
            "energy dissipated by dampers since the start of the analysis",
        );
        let violation = var(
            &mut d,
            "constraint_violation",
            NcType::Double,
            &[time],
            "m",
            "largest position-level constraint violation max|Phi| (m or rad)",
        );
        let diagnostics = diagnostics.then(|| DiagnosticVars {
            iterations: var(&mut d, "newton_iterations", NcType::Int, &[time], "1", "Newton iterations of the step"),
            residual: var(
                &mut d,
                "residual_norm",
                NcType::Double,
                &[time],
                "1",
                "Euclidean norm of the scaled residual at the last Newton evaluation",
            ),
            condition: var(
                &mut d,
                "condition_estimate",
                NcType::Double,
                &[time],
                "1",
                "condition number of the iteration matrix (exact 2-norm up to 400 unknowns, 1-norm estimate above)",
            ),
            step: var(&mut d, "step_size", NcType::Double, &[time], "s", "size of the accepted step"),
            error: var(
                &mut d,
                "error_estimate",
                NcType::Double,
                &[time],
                "1",
                "adaptive steps: local error estimate of the step relative to the tolerance (NaN for fixed steps)",
            ),
            rejected: var(
                &mut d,
                "rejected_attempts",
                NcType::Int,
                &[time],
                "1",
                "adaptive steps: attempts rejected by the error control before the accepted step",
            ),
            backtracks: var(
                &mut d,
                "line_search_backtracks",
                NcType::Int,
                &[time],
                "1",
                "Newton corrections halved by the line search in the step (granular models)",
            ),
        });

        let beams = super::beam_vars::BeamVars::define(&mut d, sys, time, vec3, quat);
        let states = super::state_vars::StateVars::define(&mut d, sys, time);
        let arrays: Vec<(String, VarId, usize)> = analysis
            .arrays(sys)
            .iter()
            .map(|a| {
                let dims: Vec<DimId> = a.dims.iter().map(|(n, l)| d.dim(n, *l)).collect();
                let v = var(
                    &mut d,
                    &a.name,
                    NcType::Double,
                    &dims,
                    &a.units,
                    &a.long_name,
                );
                (a.name.clone(), v, a.len())
            })
            .collect();
        d.add_global_attr(
            "title",
            text(&format!(
                "samara results: {} / {}",
                model.name,
                analysis.name()
            )),
        );
        d.add_global_attr("Conventions", text("CF-1.8"));
        d.add_global_attr("source", text(&format!("samara {}", crate::VERSION)));
        d.add_global_attr("format_version", AttrValue::Int(vec![FORMAT_VERSION]));
        d.add_global_attr("model", text(&model.name));
        if let Some(desc) = &model.description {
            d.add_global_attr("model_description", text(desc));
        }
        if let Some(f) = model_file {
            d.add_global_attr("model_file", text(&f.display().to_string()));
        }
        d.add_global_attr("analysis", text(analysis.name()));
        d.add_global_attr("analysis_type", text(analysis.kind()));
        d.add_global_attr(
            "gravity",
            AttrValue::Double(model.gravity.iter().copied().collect()),
        );
        d.add_global_attr("status", text("running"));
        d.reserve_header(HEADER_RESERVE);

        let created = if in_memory {
            d.create_in_memory(&path)
        } else {
            d.create(&path)
        };
        let mut writer = created.map_err(|e| nc_err(&path, e))?;
        let names: Vec<&str> = model.nodes.iter().map(|n| n.name.as_str()).collect();
        writer
            .put_fixed_text(node_name, &names)
            .map_err(|e| nc_err(&path, e))?;
        {
            let e = |err| nc_err(&path, err);
            let x: Vec<f64> = model
                .nodes
                .iter()
                .flat_map(|n| n.position.iter().copied())
                .collect();
            writer.put_fixed_f64(reference_position, &x).map_err(e)?;
            let q: Vec<f64> = model
                .nodes
                .iter()
                .flat_map(|n| n.orientation.wxyz())
                .collect();
            writer.put_fixed_f64(reference_orientation, &q).map_err(e)?;
        }
        if let Some((bn, bnode, boff, bmass, binertia)) = body_vars {
            let e = |err| nc_err(&path, err);
            let names: Vec<&str> = model.bodies.iter().map(|b| b.name.as_str()).collect();
            writer.put_fixed_text(bn, &names).map_err(e)?;
            let nodes: Vec<i32> = model.bodies.iter().map(|b| b.node as i32).collect();
            writer.put_fixed_i32(bnode, &nodes).map_err(e)?;
            let off: Vec<f64> = model
                .bodies
                .iter()
                .flat_map(|b| b.cg_offset.iter().copied())
                .collect();
            writer.put_fixed_f64(boff, &off).map_err(e)?;
            let mass: Vec<f64> = model.bodies.iter().map(|b| b.mass).collect();
            writer.put_fixed_f64(bmass, &mass).map_err(e)?;
            let inertia: Vec<f64> = model
                .bodies
                .iter()
                .flat_map(|b| b.inertia.transpose().iter().copied().collect::<Vec<_>>())
                .collect();
            writer.put_fixed_f64(binertia, &inertia).map_err(e)?;
        }
        let mut beams = beams;
        if let Some(b) = &mut beams {
            b.write_fixed(&mut writer, sys)
                .map_err(|e| nc_err(&path, e))?;
        }
        if let Some(s) = &states {
            s.write_fixed(&mut writer, sys)
                .map_err(|e| nc_err(&path, e))?;
        }
        if let Some(jn) = joint_name {
            let names: Vec<&str> = model.joints.iter().map(|j| j.name.as_str()).collect();
            writer
                .put_fixed_text(jn, &names)
                .map_err(|e| nc_err(&path, e))?;
        }
        if let Some((cn, cu)) = coordinate_names {
            let e = |err| nc_err(&path, err);
            let names: Vec<&str> = sys.coordinate_names.iter().map(|s| s.as_str()).collect();
            writer.put_fixed_text(cn, &names).map_err(e)?;
            let units: Vec<&str> = sys
                .coordinate_names
                .iter()
                .map(|s| {
                    if s.rsplit('.').next().is_some_and(|c| c.starts_with('d')) {
                        "m"
                    } else {
                        "rad"
                    }
                })
                .collect();
            writer.put_fixed_text(cu, &units).map_err(e)?;
        }
        Ok(Self {
            writer,
            path: path.clone(),
            vars: Vars {
                time: time_v,
                load_factor,
                position,
                orientation,
                velocity,
                angular_velocity,
                joint_position,
                joint_axes,
                joint_force,
                joint_moment,
                coordinate: coordinate_vars,
                kinetic,
                potential,
                external_work,
                dissipated,
                violation,
                diagnostics,
                beams,
                states,
                arrays,
            },
            buf3: vec![0.0; 3 * n_nodes],
            buf4: vec![0.0; 4 * n_nodes],
            jf: vec![0.0; 3 * n_joints],
            jm: vec![0.0; 3 * n_joints],
            jp: vec![0.0; 3 * n_joints],
            ja: vec![0.0; 9 * n_joints],
            mu_all: vec![0.0; sys.n_rows],
            cq: vec![0.0; n_coords],
            cv: vec![0.0; n_coords],
            cf: vec![0.0; n_coords],
            backup,
        })
    }

    pub fn path(&self) -> &Path {
        self.writer.path()
    }

    /// Number of output times written so far.
    pub fn records(&self) -> u64 {
        self.writer.num_records()
    }

    /// Bytes of the file once it holds `records` output times.
    pub fn projected_size(&self, records: u64) -> u64 {
        self.writer.size_with_records(records)
    }

    /// The least size of `def`'s results ([`AnalysisDef::min_records`] output times of
    /// the layout this model's file would have), found without writing anything: the
    /// header is laid out in memory. `None` for the analysis kinds with few records.
    pub fn projection(
        model: &Model,
        model_file: Option<&Path>,
        sys: &System,
        def: &AnalysisDef,
    ) -> Result<Option<super::ResultsProjection>, crate::Error> {
        let Some(records) = def.min_records() else {
            return Ok(None);
        };
        let f = Self::in_memory(model, model_file, sys, def.stage().as_ref())?;
        let record_bytes = f.projected_size(1) - f.projected_size(0);
        Ok(Some(super::ResultsProjection {
            records,
            record_bytes,
            bytes: f.projected_size(records),
        }))
    }

    /// Whether the analysis `def` writes more than the free space of the file's disk
    /// (results in memory: the available memory) can hold, at
    /// [`AnalysisDef::min_records`] output times, a lower bound; `None` when it fits,
    /// for the other analysis kinds, or when the system does not report the space.
    pub fn space_shortfall(&self, def: &AnalysisDef) -> Option<super::SpaceShortfall> {
        use super::space::{Storage, available_memory, available_space};
        let records = def.min_records()?;
        let record_bytes = self.projected_size(1) - self.projected_size(0);
        let (storage, needed, available) = if self.writer.is_in_memory() {
            (
                Storage::Memory,
                self.projected_size(records),
                available_memory()?,
            )
        } else {
            // The file already holds its header and fixed variables.
            let now = std::fs::metadata(&self.path).map_or(0, |m| m.len());
            let needed = self.projected_size(records).saturating_sub(now);
            (Storage::Disk, needed, available_space(&self.path)?)
        };
        super::SpaceShortfall::compare(storage, records, record_bytes, needed, available)
    }

    /// [`Self::space_shortfall`] as an error (message and hint), for a caller that
    /// refuses to start such a run; a file is then [discarded](Self::discard).
    pub fn ensure_space(self, def: &AnalysisDef) -> Result<Self, crate::Error> {
        let Some(s) = self.space_shortfall(def) else {
            return Ok(self);
        };
        let path = self.path.clone();
        self.discard()?;
        Err(crate::Error::Output {
            path,
            message: format!("analysis '{}': {s}; {}", def.name, s.hint()),
        })
    }

    /// Removes the file of an analysis that is not run, and moves the earlier file it
    /// had set aside ([`Self::backup`]) back to its name.
    pub fn discard(self) -> Result<(), crate::Error> {
        let in_memory = self.writer.is_in_memory();
        drop(self.writer);
        if in_memory {
            return Ok(());
        }
        let io = |action, source| crate::Error::Io {
            path: self.path.clone(),
            action,
            source,
        };
        std::fs::remove_file(&self.path).map_err(|e| io("remove the unused results file", e))?;
        if let Some(b) = &self.backup {
            std::fs::rename(b, &self.path)
                .map_err(|e| io("move the earlier results file back", e))?;
        }
        Ok(())
    }

    /// Writes the closing attributes (status, counts, failure) and closes the file.
    pub fn finish(mut self, summary: &AnalysisSummary) -> Result<PathBuf, crate::Error> {
        self.close(summary)?;
        let path = self.writer.path().to_path_buf();
        self.writer.finish().map_err(|e| nc_err(&path, e))?;
        Ok(path)
    }

    /// [`Self::finish`] for results written [`Self::in_memory`]: the file's bytes.
    pub fn finish_in_memory(mut self, summary: &AnalysisSummary) -> Result<Vec<u8>, crate::Error> {
        self.close(summary)?;
        let path = self.path.clone();
        self.writer
            .into_bytes()
            .ok_or_else(|| crate::Error::Output {
                path,
                message: "the results were written to a file, not in memory".into(),
            })
    }

    fn close(&mut self, summary: &AnalysisSummary) -> Result<(), crate::Error> {
        let path = self.writer.path().to_path_buf();
        let e = |err| nc_err(&path, err);
        let status = if summary.failure.is_some() {
            "failed"
        } else {
            "completed"
        };
        self.writer
            .set_global_attr("status", AttrValue::Text(status.into()))
            .map_err(e)?;
        let counts = [
            ("steps", summary.steps),
            ("newton_iterations", summary.newton_iterations),
            ("rejected_steps", summary.rejected_steps),
            ("factorizations", summary.factorizations),
            ("line_search_backtracks", summary.line_search_backtracks),
            ("contact_redos", summary.contact_redos),
            ("pattern_rebuilds", summary.pattern_rebuilds),
        ];
        for (name, v) in counts {
            let v = i32::try_from(v).unwrap_or(i32::MAX);
            self.writer
                .set_global_attr(name, AttrValue::Int(vec![v]))
                .map_err(e)?;
        }
        self.writer
            .set_global_attr(
                "wall_time",
                AttrValue::Double(vec![summary.wall_time.as_secs_f64()]),
            )
            .map_err(e)?;
        self.writer
            .set_global_attr(
                "max_constraint_violation",
                AttrValue::Double(vec![summary.max_constraint_violation]),
            )
            .map_err(e)?;
        if let Some(f) = &summary.failure {
            let mut reason = format!("t = {}: {}", f.time, f.reason);
            reason.truncate(1500);
            self.writer
                .set_global_attr("failure", AttrValue::Text(reason))
                .map_err(e)?;
        }
        Ok(())
    }
}

impl Recorder for ResultsFile {
    fn output_dir(&self) -> Option<PathBuf> {
        Some(self.path.parent().unwrap_or(Path::new(".")).to_path_buf())
    }

    fn write_array(
        &mut self,
        _sys: &System,
        spec: &ArraySpec,
        values: &[f64],
    ) -> Result<(), crate::Error> {
        let path = self.path.clone();
        let Some((_, v, len)) = self.vars.arrays.iter().find(|a| a.0 == spec.name) else {
            return Err(crate::Error::Output {
                path,
                message: format!("array '{}' was not declared by the analysis", spec.name),
            });
        };
        if *len != values.len() {
            return Err(crate::Error::Output {
                path,
                message: format!(
                    "array '{}' has {} values, {len} declared",
                    spec.name,
                    values.len()
                ),
            });
        }
        self.writer
            .put_fixed_f64(*v, values)
            .map_err(|e| nc_err(&path, e))
    }

    fn record(&mut self, sys: &System, frame: &OutputFrame) -> Result<(), crate::Error> {
        let v = &self.vars;
        let w = &mut self.writer;
        let path = &self.path;
        let e = |err| nc_err(path, err);
        let nodes = &frame.state.nodes;
        w.set_record_f64(v.time, &[frame.time]).map_err(e)?;
        if let Some(lf) = v.load_factor {
            w.set_record_f64(lf, &[frame.load_factor]).map_err(e)?;
        }
        let mut put3 = |w: &mut Writer, var: VarId, f: &dyn Fn(usize) -> [f64; 3]| {
            for i in 0..nodes.len() {
                self.buf3[3 * i..3 * i + 3].copy_from_slice(&f(i));
            }
            w.set_record_f64(var, &self.buf3)
        };
        put3(w, v.position, &|i| nodes[i].x.into()).map_err(e)?;
        put3(w, v.velocity, &|i| nodes[i].v.into()).map_err(e)?;
        put3(w, v.angular_velocity, &|i| nodes[i].omega_global().into()).map_err(e)?;
        for (i, n) in nodes.iter().enumerate() {
            self.buf4[4 * i..4 * i + 4].copy_from_slice(&n.rot.wxyz());
        }
        w.set_record_f64(v.orientation, &self.buf4).map_err(e)?;
        if let (Some(fv), Some(mv)) = (v.joint_force, v.joint_moment) {
            let ctx = sys.context(frame.state.time, frame.load_factor);
            let (jf, jm) = (&mut self.jf, &mut self.jm);
            sys.reactions(&ctx, frame.state, frame.mu, &mut self.mu_all, |k, f, m| {
                jf[3 * k..3 * k + 3].copy_from_slice(f.as_slice());
                jm[3 * k..3 * k + 3].copy_from_slice(m.as_slice());
            });
            for (k, c) in sys.constraints.iter().enumerate() {
                let (p, axes) = c.location(nodes);
                self.jp[3 * k..3 * k + 3].copy_from_slice(p.as_slice());
                for e in 0..3 {
                    for i in 0..3 {
                        self.ja[9 * k + 3 * e + i] = axes[(i, e)];
                    }
                }
            }
            if let (Some(pv), Some(av)) = (v.joint_position, v.joint_axes) {
                w.set_record_f64(pv, &self.jp).map_err(e)?;
                w.set_record_f64(av, &self.ja).map_err(e)?;
            }
            w.set_record_f64(fv, &self.jf).map_err(e)?;
            w.set_record_f64(mv, &self.jm).map_err(e)?;
        }
        if let Some(cv) = &v.coordinate {
            let ctx = sys.context(frame.state.time, frame.load_factor);
            for (j, c) in frame.state.coords.iter().enumerate() {
                self.cq[j] = c.q;
                self.cv[j] = c.v;
            }
            sys.coordinate_forces(&ctx, frame.state, frame.mu, &mut self.cf);
            w.set_record_f64(cv.value, &self.cq).map_err(e)?;
            w.set_record_f64(cv.rate, &self.cv).map_err(e)?;
            w.set_record_f64(cv.force, &self.cf).map_err(e)?;
        }
        let en = frame.energy;
        w.set_record_f64(v.kinetic, &[en.kinetic]).map_err(e)?;
        w.set_record_f64(v.potential, &[en.potential]).map_err(e)?;
        w.set_record_f64(v.external_work, &[en.external_work])
            .map_err(e)?;
        w.set_record_f64(v.dissipated, &[en.dissipated])
            .map_err(e)?;
        w.set_record_f64(v.violation, &[frame.constraint_violation])
            .map_err(e)?;
        if let Some(b) = &mut self.vars.beams {
            b.record(w, sys, nodes).map_err(e)?;
        }
        if let Some(s) = &mut self.vars.states {
            s.record(w, sys, frame.state, frame.load_factor)
                .map_err(e)?;
        }
        let v = &self.vars;
        if let (Some(dv), Some(dg)) = (&v.diagnostics, frame.diagnostics) {
            w.set_record_i32(dv.iterations, &[dg.newton_iterations as i32])
                .map_err(e)?;
            w.set_record_f64(dv.residual, &[dg.residual_norm])
                .map_err(e)?;
            w.set_record_f64(dv.condition, &[dg.condition]).map_err(e)?;
            w.set_record_f64(dv.step, &[dg.step_size]).map_err(e)?;
            w.set_record_f64(dv.error, &[dg.error_estimate])
                .map_err(e)?;
            w.set_record_i32(dv.rejected, &[dg.rejected.min(i32::MAX as usize) as i32])
                .map_err(e)?;
            w.set_record_i32(
                dv.backtracks,
                &[dg.line_search_backtracks.min(i32::MAX as usize) as i32],
            )
            .map_err(e)?;
        }
        w.commit_record().map_err(e)
    }
}

#[cfg(test)]
mod tests {
    use super::{NcError, nc_err};
    use std::io::{Error, ErrorKind};
    use std::path::{Path, PathBuf};

    /// A full disk is said so, with what to do; other write errors keep their own words.
    #[test]
    fn a_full_disk_is_named_with_a_remedy() {
        let io = |kind| NcError::Io {
            path: PathBuf::from("out/run.nc"),
            source: Error::from(kind),
        };
        let shown = |kind| nc_err(Path::new("out/run.nc"), io(kind)).to_string();
        for kind in [ErrorKind::StorageFull, ErrorKind::QuotaExceeded] {
            let s = shown(kind);
            assert!(s.starts_with("results file 'out/run.nc': I/O error"), "{s}");
            assert!(
                s.contains("the disk is full (or the quota used up): free space"),
                "{s}"
            );
        }
        let s = shown(ErrorKind::PermissionDenied);
        assert!(!s.contains("disk is full"), "{s}");
    }
}
