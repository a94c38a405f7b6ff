//! Sectional output of the beams in a results file (a group of variables defined only when
//! the model has beams; documented in `docs/results.md`).
//!
//! One entry per elastic quadrature point ("section") of every beam, beam by beam, root to
//! tip. Forces, moments, strains and curvatures are in **section-frame** components
//! (x along the beam axis, y and z in the cross-section — the frame of the sectional
//! matrices); `section_orientation` turns them into global components.
//!
//! Sign convention: `beam_force` and `beam_moment` are the resultant force and moment that
//! the outboard part of the beam (larger arc length s) exerts on the inboard part across the
//! section, the moment about the reference-line point — tension and the usual beam-theory
//! signs are positive: `[N; M] = C [ε; κ] (+ D [ε̇; κ̇])`.

use super::netcdf::{AttrValue, Definition, DimId, NcError, NcType, VarId, Writer};
use crate::elements::beam::element::SectionState;
use crate::system::System;

/// The beam variables of a results file and their per-record scratch.
pub(super) struct BeamVars {
    position: VarId,
    orientation: VarId,
    force: VarId,
    moment: VarId,
    strain: VarId,
    curvature: VarId,
    /// Fixed variables, written once after the file is created.
    beam_name: VarId,
    section_name: VarId,
    section_beam: VarId,
    section_eta: VarId,
    section_reference_position: VarId,
    section_reference_orientation: VarId,
    beam_node_index: VarId,
    beam_node_beam: VarId,
    beam_node_offset: VarId,
    names: Vec<String>,
    states: Vec<SectionState>,
    buf3: Vec<f64>,
    buf4: Vec<f64>,
}

/// Defines a variable with its `units` (if any), `long_name` and, for doubles, a NaN
/// `_FillValue`.
pub(super) fn add(
    d: &mut Definition,
    name: &str,
    ty: NcType,
    dims: &[DimId],
    units: &str,
    long: &str,
) -> VarId {
    let v = d.add_var(name, ty, dims);
    if !units.is_empty() {
        d.add_var_attr(v, "units", AttrValue::Text(units.into()));
    }
    d.add_var_attr(v, "long_name", AttrValue::Text(long.into()));
    if ty == NcType::Double {
        d.add_var_attr(v, "_FillValue", AttrValue::Double(vec![f64::NAN]));
    }
    v
}

impl BeamVars {
    /// Defines the dimensions `beam`, `section` (and their name lengths) and the beam
    /// variables; `None` if the system has no beams.
    pub(super) fn define(
        d: &mut Definition,
        sys: &System,
        time: DimId,
        vec3: DimId,
        quat: DimId,
    ) -> Option<Self> {
        if sys.beams.is_empty() {
            return None;
        }
        let n_sections: usize = sys.beams.iter().map(|b| b.n_section_points()).sum();
        let names: Vec<String> = sys
            .beams
            .iter()
            .flat_map(|b| (0..b.n_section_points()).map(move |k| format!("{}#{k}", b.name)))
            .collect();
        let beam = d.add_dim("beam", sys.beams.len());
        let beam_len = sys
            .beams
            .iter()
            .map(|b| b.name.len())
            .max()
            .unwrap_or(1)
            .max(1);
        let beam_strlen = d.add_dim("beam_strlen", beam_len);
        let section = d.add_dim("section", n_sections);
        let section_len = names.iter().map(String::len).max().unwrap_or(1).max(1);
        let section_strlen = d.add_dim("section_strlen", section_len);
        let n_beam_nodes: usize = sys.beams.iter().map(|b| b.nodes_with_offsets().len()).sum();
        let beam_node = d.add_dim("beam_node", n_beam_nodes);
        let v3 = [time, section, vec3];
        Some(Self {
            section_reference_position: add(
                d,
                "section_reference_position",
                NcType::Double,
                &[section, vec3],
                "m",
                "reference-line point of the section in the model's reference configuration, global frame",
            ),
            section_reference_orientation: add(
                d,
                "section_reference_orientation",
                NcType::Double,
                &[section, quat],
                "1",
                "section frame in the model's reference configuration as a unit quaternion (w, x, y, z), section frame to global",
            ),
            beam_node_index: add(
                d,
                "beam_node_index",
                NcType::Int,
                &[beam_node],
                "",
                "nodes of the beams, beam by beam from the root to the tip: index of the node in `node`",
            ),
            beam_node_beam: add(
                d,
                "beam_node_beam",
                NcType::Int,
                &[beam_node],
                "",
                "index of the beam node's beam in `beam`",
            ),
            beam_node_offset: add(
                d,
                "beam_node_offset",
                NcType::Double,
                &[beam_node, quat],
                "1",
                "node-to-section frame offset o as a unit quaternion (w, x, y, z): section frame at the node = orientation of the node ⊗ o",
            ),
            beam_name: add(
                d,
                "beam_name",
                NcType::Char,
                &[beam, beam_strlen],
                "",
                "beam name",
            ),
            section_name: add(
                d,
                "section_name",
                NcType::Char,
                &[section, section_strlen],
                "",
                "section (elastic quadrature point) name, <beam>#<k>, k from the root",
            ),
            section_beam: add(
                d,
                "section_beam",
                NcType::Int,
                &[section],
                "",
                "index of the section's beam in `beam`",
            ),
            section_eta: add(
                d,
                "section_eta",
                NcType::Double,
                &[section],
                "1",
                "normalized arc length s/L of the section along its beam (reference configuration)",
            ),
            position: add(
                d,
                "section_position",
                NcType::Double,
                &v3,
                "m",
                "reference-line point of the section, global frame",
            ),
            orientation: add(
                d,
                "section_orientation",
                NcType::Double,
                &[time, section, quat],
                "1",
                "section frame (x along the beam) as a unit quaternion (w, x, y, z), section frame to global",
            ),
            force: add(
                d,
                "beam_force",
                NcType::Double,
                &v3,
                "N",
                "sectional force on the inboard part by the outboard part: axial (tension positive), shear y, shear z; section frame",
            ),
            moment: add(
                d,
                "beam_moment",
                NcType::Double,
                &v3,
                "N m",
                "sectional moment on the inboard part by the outboard part about the reference line: torsion, bending about y, bending about z; section frame",
            ),
            strain: add(
                d,
                "beam_strain",
                NcType::Double,
                &v3,
                "1",
                "sectional strain: axial, shear y, shear z (change from the reference configuration)",
            ),
            curvature: add(
                d,
                "beam_curvature",
                NcType::Double,
                &v3,
                "m-1",
                "sectional curvature: twist, bending about y, bending about z (change from the reference configuration); section frame",
            ),
            names,
            states: vec![SectionState::default(); n_sections],
            buf3: vec![0.0; 3 * n_sections],
            buf4: vec![0.0; 4 * n_sections],
        })
    }

    /// Writes the fixed variables (names, beam indices, stations, the reference sections,
    /// the beams' nodes).
    pub(super) fn write_fixed(&mut self, w: &mut Writer, sys: &System) -> Result<(), NcError> {
        let beams: Vec<&str> = sys.beams.iter().map(|b| b.name.as_str()).collect();
        w.put_fixed_text(self.beam_name, &beams)?;
        let names: Vec<&str> = self.names.iter().map(String::as_str).collect();
        w.put_fixed_text(self.section_name, &names)?;
        let index: Vec<i32> = sys
            .beams
            .iter()
            .enumerate()
            .flat_map(|(i, b)| std::iter::repeat_n(i as i32, b.n_section_points()))
            .collect();
        w.put_fixed_i32(self.section_beam, &index)?;
        // Stations come from the reference configuration (η is fixed per point).
        let etas: Vec<f64> = sys
            .beams
            .iter()
            .flat_map(|b| b.elements.iter().flat_map(|e| e.section_etas()))
            .collect();
        w.put_fixed_f64(self.section_eta, &etas)?;
        // Sections of the reference configuration (the model's node positions and
        // orientations, from which the beams were built).
        let mut reference = vec![SectionState::default(); self.states.len()];
        let mut at = 0;
        for b in &sys.beams {
            let n = b.n_section_points();
            b.sections_into(&sys.initial_nodes, &mut reference[at..at + n]);
            at += n;
        }
        let x: Vec<f64> = reference
            .iter()
            .flat_map(|s| s.position.iter().copied())
            .collect();
        w.put_fixed_f64(self.section_reference_position, &x)?;
        let q: Vec<f64> = reference
            .iter()
            .flat_map(|s| s.orientation.iter().copied())
            .collect();
        w.put_fixed_f64(self.section_reference_orientation, &q)?;
        let mut index = Vec::new();
        let mut beam = Vec::new();
        let mut offset = Vec::new();
        for (i, b) in sys.beams.iter().enumerate() {
            for (n, o) in b.nodes_with_offsets() {
                index.push(n as i32);
                beam.push(i as i32);
                offset.extend(o);
            }
        }
        w.put_fixed_i32(self.beam_node_index, &index)?;
        w.put_fixed_i32(self.beam_node_beam, &beam)?;
        w.put_fixed_f64(self.beam_node_offset, &offset)
    }

    /// Stages one record of the beam variables (no allocation).
    pub(super) fn record(
        &mut self,
        w: &mut Writer,
        sys: &System,
        nodes: &[crate::system::NodeState],
    ) -> Result<(), NcError> {
        let mut at = 0;
        for b in &sys.beams {
            let n = b.n_section_points();
            b.sections_into(nodes, &mut self.states[at..at + n]);
            at += n;
        }
        let states = &self.states;
        let mut put = |w: &mut Writer, var: VarId, f: &dyn Fn(&SectionState) -> [f64; 3]| {
            for (i, s) in states.iter().enumerate() {
                self.buf3[3 * i..3 * i + 3].copy_from_slice(&f(s));
            }
            w.set_record_f64(var, &self.buf3)
        };
        put(w, self.position, &|s| s.position.into())?;
        put(w, self.force, &|s| [s.stress[0], s.stress[1], s.stress[2]])?;
        put(w, self.moment, &|s| [s.stress[3], s.stress[4], s.stress[5]])?;
        put(w, self.strain, &|s| [s.strain[0], s.strain[1], s.strain[2]])?;
        put(w, self.curvature, &|s| {
            [s.strain[3], s.strain[4], s.strain[5]]
        })?;
        for (i, s) in states.iter().enumerate() {
            self.buf4[4 * i..4 * i + 4].copy_from_slice(s.orientation.as_slice());
        }
        w.set_record_f64(self.orientation, &self.buf4)
    }
}
