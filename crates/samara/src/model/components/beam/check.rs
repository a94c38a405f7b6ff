//! Checks the `[[beams]]` tables: geometry (key points or explicit nodes), sections (inline
//! matrices, isotropic constants or a CSV file), damping and loads; creates the beam's
//! nodes.

// Index loops over nodes and quadrature points read closer to the formulas; NaN-rejecting
// comparisons (`!(x > 0.0)`) are intended.
#![allow(
    clippy::needless_range_loop,
    clippy::neg_cmp_op_on_partial_ord,
    clippy::type_complexity,
    clippy::nonminimal_bool
)]

use super::input::*;
use crate::elements::beam::BeamDef;
use crate::elements::beam::element::{DistributedLoad, MAX_ORDER, Quadrature};
use crate::elements::beam::gll::{gauss_legendre, gauss_lobatto_legendre, lagrange};
use crate::elements::beam::reference_line::ReferenceLine;
use crate::elements::beam::section::{
    IsotropicSection, Section, SectionTable, check_mass, check_stiffness, from_beamdyn_ordering,
};
use crate::math::Rotation;
use crate::model::validate::{Checker, Entry};
use crate::model::{Model, NodeDef, TimeFunction};
use nalgebra::{Matrix3, Matrix6, Vector3};
use std::collections::HashMap;

/// Columns of a sections CSV file: station, then C and M row by row.
pub const CSV_COLUMNS: usize = 73;

impl Checker<'_> {
    pub(super) fn beam(
        &mut self,
        b: &crate::model::Located<BeamInput>,
        model: &mut Model,
        node_map: &mut HashMap<String, usize>,
    ) -> Option<BeamDef> {
        let e = Entry {
            span: b.span.clone(),
        };
        let bi = &b.value;
        let what = format!("beam '{}'", bi.name.value);
        let mut ok = true;
        let p = bi.order;
        if !(1..=MAX_ORDER).contains(&p) {
            self.error(
                format!("{what}: `order` must be between 1 and {MAX_ORDER} (got {p})"),
                self.key(&e, "order"),
                Some("p = 1 is the two-node element; high orders (4–15) converge fastest on smooth problems".into()),
            );
            return None;
        }
        if bi.beamdyn.is_none() {
            for (key, given) in [
                ("root_position", bi.root_position.is_some()),
                ("root_axes", bi.root_axes.is_some()),
            ] {
                if given {
                    self.error(
                        format!("{what}: `{key}` places a BeamDyn blade; it needs `beamdyn`"),
                        self.key(&e, key),
                        Some("with `points`, give the key points in global coordinates and the section frame with `y_axis` and `twist`".into()),
                    );
                    ok = false;
                }
            }
        }
        let ne = bi.elements.unwrap_or(1);
        if ne == 0 {
            self.error(
                format!("{what}: `elements` must be at least 1"),
                self.key(&e, "elements"),
                None,
            );
            return None;
        }
        let n_nodes = match ne.checked_mul(p).and_then(|n| n.checked_add(1)) {
            Some(n) if n.saturating_add(model.nodes.len()) <= crate::model::MAX_NODES => n,
            _ => {
                self.error(
                    format!(
                        "{what}: {ne} element(s) of order {p} would make the model larger than {} nodes",
                        crate::model::MAX_NODES
                    ),
                    self.key(&e, "elements"),
                    Some("a beam needs elements · order + 1 nodes; high orders with few elements converge fastest".into()),
                );
                return None;
            }
        };
        let (xi, _) = gauss_lobatto_legendre(p);
        // Geometry: node positions, section frames and η.
        let (positions, frames, etas, names): (
            Vec<Vector3<f64>>,
            Vec<Rotation>,
            Vec<f64>,
            Vec<Option<String>>,
        ) = match (&bi.points, &bi.nodes) {
            (Some(_), Some(_)) | (None, None) => {
                self.error(
                        format!("{what}: give the reference line either as key `points` or as explicit `nodes`"),
                        e.span.clone(),
                        Some("`points = [[x, y, z], …]` (at least two key points) or `nodes = [\"n0\", \"n1\", …]`".into()),
                    );
                return None;
            }
            (Some(points), None) => {
                if !points.iter().flatten().all(|x| x.is_finite()) {
                    self.error(
                        format!("{what}: key points must be finite"),
                        self.key(&e, "points"),
                        None,
                    );
                    return None;
                }
                let pts: Vec<Vector3<f64>> = points.iter().map(|p| Vector3::from(*p)).collect();
                let twist = bi.twist.clone().unwrap_or_default();
                let line = match ReferenceLine::new(&pts, &twist, bi.y_axis.map(Vector3::from)) {
                    Ok(l) => l,
                    Err(err) => {
                        let key = match err {
                            crate::elements::beam::reference_line::LineError::BadTwistStations => {
                                "twist"
                            }
                            crate::elements::beam::reference_line::LineError::ParallelReference => {
                                "y_axis"
                            }
                            _ => "points",
                        };
                        self.error(
                                format!("{what}: {err}"),
                                self.key(&e, key),
                                Some("key points are [[x, y, z], …] in order from root to tip, at least two and all distinct".into()),
                            );
                        return None;
                    }
                };
                let etas: Vec<f64> = (0..n_nodes)
                    .map(|k| {
                        let (el, i) = if k == n_nodes - 1 {
                            (ne - 1, p)
                        } else {
                            (k / p, k % p)
                        };
                        (el as f64 + (xi[i] + 1.0) * 0.5) / ne as f64
                    })
                    .collect();
                let fr = line.frames(&etas);
                let mut names = vec![None; n_nodes];
                names[0] = bi.root.as_ref().map(|r| r.value.clone());
                names[n_nodes - 1] = bi.tip.as_ref().map(|r| r.value.clone());
                (
                    fr.iter().map(|f| f.0).collect(),
                    fr.iter().map(|f| Rotation::from_matrix(&f.1)).collect(),
                    etas,
                    names,
                )
            }
            (None, Some(list)) => {
                for key in [
                    "root",
                    "tip",
                    "twist",
                    "y_axis",
                    "rotation_centre",
                    "angular_velocity",
                ] {
                    let given = match key {
                        "root" => bi.root.is_some(),
                        "tip" => bi.tip.is_some(),
                        "twist" => bi.twist.is_some(),
                        "y_axis" => bi.y_axis.is_some(),
                        "rotation_centre" => bi.rotation_centre.is_some(),
                        _ => bi.angular_velocity.is_some(),
                    };
                    if given {
                        self.error(
                                format!("{what}: `{key}` is not used with explicit `nodes`"),
                                self.key(&e, key),
                                Some("with `nodes`, the nodes' own positions, orientations and velocities define the beam".into()),
                            );
                        ok = false;
                    }
                }
                if list.len() != n_nodes {
                    self.error(
                            format!("{what}: {ne} element(s) of order {p} need {n_nodes} nodes, `nodes` lists {}", list.len()),
                            self.key(&e, "nodes"),
                            Some("elements · order + 1 nodes, shared between neighbouring elements, root to tip".into()),
                        );
                    return None;
                }
                let mut idx = Vec::new();
                for n in list {
                    match self.node_ref_in(n, node_map, &what) {
                        Some(crate::model::NodeRef::Node(i)) => idx.push(i),
                        Some(crate::model::NodeRef::Ground) => {
                            self.error(
                                format!("{what}: a beam node cannot be the ground"),
                                n.span.clone(),
                                Some(
                                    "clamp the root with a `fixed` joint to the ground instead"
                                        .into(),
                                ),
                            );
                            return None;
                        }
                        None => return None,
                    }
                }
                let pos: Vec<Vector3<f64>> = idx.iter().map(|&i| model.nodes[i].position).collect();
                let fr: Vec<Rotation> = idx.iter().map(|&i| model.nodes[i].orientation).collect();
                // η from the arc length of the isoparametric line.
                let (gx, gw) = gauss_legendre(2 * p + 2);
                let mut h = vec![0.0; p + 1];
                let mut dh = vec![0.0; p + 1];
                let mut lengths = Vec::new();
                for el in 0..ne {
                    let xs = &pos[el * p..=(el + 1) * p];
                    let mut l = 0.0;
                    for (x, w) in gx.iter().zip(&gw) {
                        lagrange(&xi, *x, &mut h, &mut dh);
                        let d: Vector3<f64> = (0..=p).map(|k| xs[k] * dh[k]).sum();
                        l += w * d.norm();
                    }
                    if !(l > 0.0) {
                        self.error(
                            format!("{what}: element {el} has zero length"),
                            self.key(&e, "nodes"),
                            None,
                        );
                        return None;
                    }
                    lengths.push(l);
                }
                let total: f64 = lengths.iter().sum();
                let mut etas = Vec::new();
                let mut start = 0.0;
                for (el, l) in lengths.iter().enumerate() {
                    for (i, x) in xi.iter().enumerate() {
                        if el > 0 && i == 0 {
                            continue;
                        }
                        etas.push((start + (x + 1.0) * 0.5 * l) / total);
                    }
                    start += l;
                }
                return self.finish_beam(bi, &e, &what, p, ne, idx, pos, fr, etas, model, ok);
            }
        };
        // Node creation or sharing.
        let scale = positions
            .windows(2)
            .map(|w| (w[1] - w[0]).norm())
            .sum::<f64>()
            .max(1e-300);
        let omega = Vector3::from(bi.angular_velocity.unwrap_or([0.0; 3]));
        let centre = bi
            .rotation_centre
            .map(Vector3::from)
            .unwrap_or(positions[0]);
        self.finite(&e, "angular_velocity", omega.as_slice(), &what);
        let mut idx = Vec::with_capacity(n_nodes);
        for k in 0..n_nodes {
            let given = names[k].clone();
            let name = given
                .clone()
                .unwrap_or_else(|| format!("{}.{k}", bi.name.value));
            let span = if k == 0 {
                bi.root.as_ref().and_then(|r| r.span.clone())
            } else {
                bi.tip.as_ref().and_then(|r| r.span.clone())
            };
            if let Some(&i) = node_map.get(&name) {
                if given.is_none() {
                    self.error(
                        format!("{what}: the name of its node {k}, '{name}', is already taken"),
                        bi.name.span.clone(),
                        Some("rename the beam or the other node; only `root` and `tip` may share existing nodes".into()),
                    );
                    return None;
                }
                let d = (model.nodes[i].position - positions[k]).norm();
                if d > 1e-6 * scale {
                    let x = positions[k];
                    self.error(
                        format!(
                            "{what}: node '{name}' is at {:?}, but the beam's {} is at [{:.6}, {:.6}, {:.6}] ({d:.3e} m away)",
                            model.nodes[i].position.as_slice(),
                            if k == 0 { "root" } else { "tip" },
                            x.x, x.y, x.z
                        ),
                        span,
                        Some("a shared node must lie on the reference line's end; move the node or the key points".into()),
                    );
                    return None;
                }
                idx.push(i);
            } else {
                if name == crate::model::validate::GROUND {
                    self.error(
                        format!("{what}: the ground cannot be a beam node"),
                        span,
                        Some("clamp the root with a `fixed` joint to the ground".into()),
                    );
                    return None;
                }
                node_map.insert(name.clone(), model.nodes.len());
                idx.push(model.nodes.len());
                model.nodes.push(NodeDef {
                    name,
                    position: positions[k],
                    orientation: frames[k],
                    velocity: omega.cross(&(positions[k] - centre)),
                    angular_velocity: omega,
                });
            }
        }
        self.finish_beam(
            bi, &e, &what, p, ne, idx, positions, frames, etas, model, ok,
        )
    }

    #[allow(clippy::too_many_arguments)]
    fn finish_beam(
        &mut self,
        bi: &BeamInput,
        e: &Entry,
        what: &str,
        p: usize,
        ne: usize,
        nodes: Vec<usize>,
        _positions: Vec<Vector3<f64>>,
        frames: Vec<Rotation>,
        etas: Vec<f64>,
        _model: &Model,
        mut ok: bool,
    ) -> Option<BeamDef> {
        let table = self.sections(bi, e, what);
        ok &= table.is_some();
        let damping = bi.damping.unwrap_or([0.0; 6]);
        if !damping.iter().all(|m| m.is_finite() && *m >= 0.0) {
            self.error(
                format!("{what}: damping coefficients must be finite and ≥ 0 (got {damping:?})"),
                self.key(e, "damping"),
                Some("μᵢ in seconds; 0 for no structural damping".into()),
            );
            ok = false;
        }
        let mut loads = Vec::new();
        for l in &bi.loads {
            let le = Entry {
                span: l.span.clone(),
            };
            let li = &l.value;
            let lw = format!("{what}, distributed load");
            let force = li.force.unwrap_or([0.0; 3]);
            let moment = li.moment.unwrap_or([0.0; 3]);
            ok &= self.finite(&le, "force", &force, &lw) & self.finite(&le, "moment", &moment, &lw);
            let function = match &li.function {
                Some(f) => match self.time_function(f, &lw) {
                    Some(f) => f,
                    None => {
                        ok = false;
                        TimeFunction::Constant(1.0)
                    }
                },
                None => TimeFunction::Constant(1.0),
            };
            let profile = li.profile.clone().unwrap_or_default();
            if profile.windows(2).any(|w| !(w[1][0] > w[0][0]))
                || !profile.iter().flatten().all(|x| x.is_finite())
            {
                self.error(
                    format!("{lw}: `profile` stations must be finite and strictly increasing"),
                    self.key(&le, "profile"),
                    Some("[[η0, f0], [η1, f1], …] with η0 < η1 < …".into()),
                );
                ok = false;
            }
            loads.push(DistributedLoad {
                force: Vector3::from(force),
                moment: Vector3::from(moment),
                follower: li.frame.unwrap_or_default() == BeamLoadFrame::Section,
                function,
                profile,
            });
        }
        if !ok {
            return None;
        }
        Some(BeamDef {
            name: bi.name.value.clone(),
            order: p,
            n_elements: ne,
            quadrature: match bi.quadrature.unwrap_or_default() {
                BeamQuadrature::Reduced => Quadrature::Reduced,
                BeamQuadrature::Full => Quadrature::Full,
            },
            nodes,
            etas,
            sections0: frames,
            table: table?,
            damping,
            loads,
        })
    }

    fn sections(&mut self, bi: &BeamInput, e: &Entry, what: &str) -> Option<SectionTable> {
        let mut stations = Vec::new();
        let mut sections = Vec::new();
        match (&bi.sections_file, bi.sections.is_empty()) {
            (Some(_), false) | (None, true) => {
                self.error(
                    format!("{what}: give the sectional properties either as [[beams.sections]] or as `sections_file`"),
                    e.span.clone(),
                    Some("e.g. [[beams.sections]] station = 0.0, isotropic = { E = …, G = …, A = …, I2 = …, I3 = …, J = …, shear_factors = [0.8333, 0.8333] }".into()),
                );
                return None;
            }
            (Some(file), true) => {
                let (st, se) = self.sections_csv(file, what)?;
                stations = st;
                sections = se;
            }
            (None, false) => {
                for s in &bi.sections {
                    let se = Entry {
                        span: s.span.clone(),
                    };
                    let si = &s.value;
                    let sw = format!("{what}, section at station {}", si.station);
                    let section = match (&si.isotropic, &si.stiffness) {
                        (Some(iso), None) => {
                            if si.ordering.is_some() {
                                self.error(format!("{sw}: `ordering` applies to `stiffness` and `mass` matrices, not to `isotropic`"), self.key(&se, "ordering"), Some("remove `ordering`, or give the matrices".into()));
                                return None;
                            }
                            if si.mass.is_some() {
                                self.error(format!("{sw}: `mass` is computed from `isotropic` (density)"), self.key(&se, "mass"), Some("give `density` inside `isotropic`, or the full `stiffness` and `mass` matrices".into()));
                                return None;
                            }
                            let v = [
                                iso.e,
                                iso.g,
                                iso.a,
                                iso.i2,
                                iso.i3,
                                iso.j,
                                iso.shear_factors[0],
                                iso.shear_factors[1],
                            ];
                            if !v.iter().all(|x| x.is_finite() && *x > 0.0) {
                                self.error(format!("{sw}: E, G, A, I2, I3, J and the shear factors must be positive"), self.key(&se, "isotropic"), None);
                                return None;
                            }
                            let offs = [iso.tension_centre, iso.shear_centre, iso.mass_centre];
                            let density = iso.density.unwrap_or(0.0);
                            if !(density.is_finite() && density >= 0.0)
                                || !offs.iter().flatten().flatten().all(|x| x.is_finite())
                            {
                                self.error(
                                    format!("{sw}: density must be ≥ 0 and offsets finite"),
                                    self.key(&se, "isotropic"),
                                    None,
                                );
                                return None;
                            }
                            IsotropicSection {
                                e: iso.e,
                                g: iso.g,
                                area: iso.a,
                                i2: iso.i2,
                                i3: iso.i3,
                                j: iso.j,
                                shear_factors: iso.shear_factors,
                                density,
                                tension_centre: iso.tension_centre.unwrap_or_default(),
                                shear_centre: iso.shear_centre.unwrap_or_default(),
                                mass_centre: iso.mass_centre.unwrap_or_default(),
                            }
                            .build()
                        }
                        (None, Some(k)) => {
                            let s = Section {
                                stiffness: Matrix6::from_fn(|i, j| k[i][j]),
                                mass: si
                                    .mass
                                    .map_or(Matrix6::zeros(), |m| Matrix6::from_fn(|i, j| m[i][j])),
                            };
                            match si.ordering.unwrap_or_default() {
                                SectionOrdering::Samara => s,
                                SectionOrdering::Beamdyn => Section {
                                    stiffness: from_beamdyn_ordering(&s.stiffness),
                                    mass: from_beamdyn_ordering(&s.mass),
                                },
                            }
                        }
                        _ => {
                            self.error(
                                format!(
                                    "{sw}: give either `stiffness` (and `mass`) or `isotropic`"
                                ),
                                se.span.clone(),
                                None,
                            );
                            return None;
                        }
                    };
                    if let Err(msg) = check_stiffness(&section.stiffness) {
                        self.error(format!("{sw}: {msg}"), self.key(&se, "stiffness"), Some("a sectional stiffness is symmetric positive definite (axial, shear, shear, torsion, bending, bending)".into()));
                        return None;
                    }
                    if let Err(msg) = check_mass(&section.mass) {
                        self.error(format!("{sw}: {msg}"), self.key(&se, "mass"), Some("[[m, 0, 0, 0, m·ηz, −m·ηy], …]: a rigid section's mass, offsets and inertia per unit length".into()));
                        return None;
                    }
                    stations.push(si.station);
                    sections.push(section);
                }
            }
        }
        let bad = stations.iter().any(|s| !(0.0..=1.0).contains(s))
            || stations.windows(2).any(|w| !(w[1] > w[0]));
        if bad {
            self.error(
                format!("{what}: section stations must be strictly increasing within [0, 1] (got {stations:?})"),
                e.span.clone(),
                Some("stations are normalized arc lengths η = s/L, root 0 to tip 1; properties are linear in between".into()),
            );
            return None;
        }
        Some(SectionTable { stations, sections })
    }

    fn sections_csv(
        &mut self,
        file: &crate::model::Located<String>,
        what: &str,
    ) -> Option<(Vec<f64>, Vec<Section>)> {
        let base = self
            .source
            .path
            .parent()
            .unwrap_or(std::path::Path::new("."));
        let path = base.join(&file.value);
        let text = match crate::input_files::read_text(&path) {
            Ok(t) => t,
            Err(err) => {
                self.error(
                    format!(
                        "{what}: cannot read sections file '{}': {err}",
                        path.display()
                    ),
                    file.span.clone(),
                    Some("the path is relative to the model file's folder".into()),
                );
                return None;
            }
        };
        let fname = path.display().to_string();
        let fail = |v: &mut Self, line: usize, col: usize, msg: String| {
            v.error(
                format!("{what}: {fname}:{line}:{col}: {msg}"),
                file.span.clone(),
                Some(format!("a sections file has a header `station,K11,…,K66,M11,…,M66` and rows of {CSV_COLUMNS} numbers (C and M row by row)")),
            );
        };
        let mut stations = Vec::new();
        let mut sections = Vec::new();
        let mut header_seen = false;
        for (ln, raw) in text.lines().enumerate() {
            let line_no = ln + 1;
            let line = raw.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let cells: Vec<&str> = line.split(',').map(|c| c.trim()).collect();
            if !header_seen {
                header_seen = true;
                if cells
                    .first()
                    .is_some_and(|c| c.eq_ignore_ascii_case("station"))
                {
                    if cells.len() != CSV_COLUMNS {
                        fail(
                            self,
                            line_no,
                            1,
                            format!(
                                "the header has {} columns, expected {CSV_COLUMNS}",
                                cells.len()
                            ),
                        );
                        return None;
                    }
                    continue;
                }
                fail(
                    self,
                    line_no,
                    1,
                    "expected the header line starting with `station`".into(),
                );
                return None;
            }
            if cells.len() != CSV_COLUMNS {
                fail(
                    self,
                    line_no,
                    1,
                    format!("expected {CSV_COLUMNS} values, found {}", cells.len()),
                );
                return None;
            }
            let mut vals = [0.0; CSV_COLUMNS];
            let mut col = 1;
            for (i, c) in cells.iter().enumerate() {
                match c.parse::<f64>() {
                    Ok(v) if v.is_finite() => vals[i] = v,
                    _ => {
                        fail(
                            self,
                            line_no,
                            col,
                            format!("'{c}' is not a finite number (column {})", i + 1),
                        );
                        return None;
                    }
                }
                col += c.len() + 1;
            }
            let section = Section {
                stiffness: Matrix6::from_fn(|i, j| vals[1 + 6 * i + j]),
                mass: Matrix6::from_fn(|i, j| vals[37 + 6 * i + j]),
            };
            if let Err(msg) =
                check_stiffness(&section.stiffness).and_then(|_| check_mass(&section.mass))
            {
                fail(self, line_no, 1, format!("station {}: {msg}", vals[0]));
                return None;
            }
            stations.push(vals[0]);
            sections.push(section);
        }
        if sections.is_empty() {
            fail(self, 1, 1, "no data rows".into());
            return None;
        }
        let _ = Matrix3::<f64>::identity();
        Some((stations, sections))
    }
}
