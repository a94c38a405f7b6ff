//! Checks a parsed section file and builds its mesh: materials, layups, the geometry
//! (a mesh file or one generator), each finding located in its file with a hint.

use super::*;
use crate::diagnostics::{Diagnostic, Located, ModelError, Severity, SourceFile};
use crate::section::element::ElementKind;
use crate::section::generators::{self as generate, Meshing, Ply};
use crate::section::material::{Material, Orthotropic};
use crate::section::mesh::{Element, Mesh};
use crate::section::mesh_io::{self, MeshFile, MeshFileError};
use nalgebra::Matrix6;
use std::ops::Range;
use std::path::PathBuf;

/// Largest mesh a section file may ask for.
pub const MAX_ELEMENTS: usize = 5_000_000;

/// Largest `count` of one ply entry.
const MAX_COUNT: usize = 10_000;

pub(super) struct Checker {
    pub(super) source: SourceFile,
    pub(super) diags: Vec<Diagnostic>,
    /// Errors located in other files (mesh, coordinates).
    pub(super) other: Vec<ModelError>,
    pub(super) files: Vec<PathBuf>,
    pub(super) base: PathBuf,
}

impl Checker {
    fn error(&mut self, msg: impl Into<String>, span: Option<Range<usize>>, hint: Option<&str>) {
        let mut d = Diagnostic::error(msg, span);
        d.hint = hint.map(str::to_string);
        self.diags.push(d);
    }

    /// Span of `key = …` (its value) inside an entry, else the entry's span.
    fn key(&self, entry: &Option<Range<usize>>, key: &str) -> Option<Range<usize>> {
        let mut span = entry.clone()?;
        // A table may be spanned by its header only: search up to the next header.
        let full = &self.source.text;
        if let Some(rest) = full.get(span.end..) {
            let next = rest.find("\n[").map_or(full.len(), |i| span.end + i);
            span.end = span.end.max(next);
        }
        let text = self.source.text.get(span.clone())?;
        let mut from = 0;
        while let Some(i) = text[from..].find(key) {
            let at = from + i;
            let before_ok = at == 0
                || !text[..at]
                    .chars()
                    .next_back()
                    .is_some_and(|c| c.is_alphanumeric() || c == '_');
            let rest = &text[at + key.len()..];
            let trimmed = rest.trim_start();
            if before_ok && trimmed.starts_with('=') {
                let v = trimmed[1..].trim_start();
                let start = span.start + at + key.len() + (rest.len() - v.len());
                let end = start + v.find(['\n', ',', '}']).unwrap_or(v.len());
                return Some(start..end.max(start + 1));
            }
            from = at + key.len();
        }
        Some(span)
    }

    fn positive(&mut self, v: f64, entry: &Option<Range<usize>>, key: &str, what: &str) -> bool {
        if v.is_finite() && v > 0.0 {
            true
        } else {
            self.error(
                format!("{what}: `{key}` must be a positive length (got {v})"),
                self.key(entry, key),
                None,
            );
            false
        }
    }

    pub(super) fn build(&mut self, input: &SectionFile) -> Option<(SectionModel, String)> {
        let (materials, names) = self.materials(input);
        let header = input.section.as_ref();
        let kind = match header.and_then(|h| h.value.element.as_ref()) {
            None => ElementKind::Quad8,
            Some(e) => match ElementKind::from_name(&e.value) {
                Some(k) => k,
                None => {
                    self.error(
                        format!("unknown element type '{}'", e.value),
                        e.span.clone(),
                        Some("one of quad8 (default), quad9, tri6, quad4, tri3"),
                    );
                    ElementKind::Quad8
                }
            },
        };
        let meshing = Meshing { kind };
        let mut given: Vec<(&str, Option<Range<usize>>)> = Vec::new();
        macro_rules! note {
            ($f:expr, $n:expr) => {
                if let Some(x) = &$f {
                    given.push(($n, x.span.clone()));
                }
            };
        }
        note!(input.mesh, "mesh");
        note!(input.rectangle, "rectangle");
        note!(input.circle, "circle");
        note!(input.tube, "tube");
        note!(input.box_section, "box");
        note!(input.i_section, "i_section");
        note!(input.airfoil, "airfoil");
        if given.len() != 1 {
            let span = given.get(1).and_then(|g| g.1.clone());
            self.error(
                if given.is_empty() {
                    "the section needs a geometry: a [mesh] or one generator".to_string()
                } else {
                    format!(
                        "give one geometry, not {} ({})",
                        given.len(),
                        given.iter().map(|g| g.0).collect::<Vec<_>>().join(", ")
                    )
                },
                span,
                Some("one of [mesh], [rectangle], [circle], [tube], [box], [i_section], [airfoil]"),
            );
            return None;
        }
        let mat = |c: &mut Self, m: &Located<String>| c.material_ref(m, &names);
        let origin = given[0].0.to_string();
        if origin == "mesh"
            && let Some(e) = header.and_then(|h| h.value.element.as_ref())
        {
            self.error(
                "`element` chooses the element of the generators; a mesh file has its own element types",
                e.span.clone(),
                Some("remove `element`, or convert the mesh (e.g. Gmsh's Mesh.ElementOrder)"),
            );
        }
        let mesh: Option<Mesh> = if let Some(m) = &input.mesh {
            self.mesh_file(m, &names)
        } else if let Some(r) = &input.rectangle {
            let (e, v) = (&r.span, &r.value);
            let ok = self.positive(v.width, e, "width", "rectangle")
                & self.positive(v.height, e, "height", "rectangle");
            let m = mat(self, &v.material);
            let angle = self.angle(v.ply_angle.as_ref());
            let divisions = v.elements.unwrap_or_else(|| {
                let n = 16.0;
                let (w, h) = (v.width.max(1e-300), v.height.max(1e-300));
                if w >= h {
                    [16, ((n * h / w).round() as usize).max(2)]
                } else {
                    [((n * w / h).round() as usize).max(2), 16]
                }
            });
            if divisions.contains(&0) {
                self.error(
                    "rectangle: `elements` must be at least 1 in each direction",
                    self.key(e, "elements"),
                    None,
                );
            }
            let fits = self.guard("rectangle", divisions[0] as u128 * divisions[1] as u128, e);
            (ok && fits && divisions.iter().all(|&d| d > 0))
                .then_some(())
                .and(m)
                .and_then(|m| {
                    angle.map(|a| {
                        generate::rectangle(&generate::Rectangle {
                            width: v.width,
                            height: v.height,
                            material: m,
                            ply_angle: a,
                            divisions,
                            meshing,
                        })
                    })
                })
        } else if let Some(c) = &input.circle {
            let ok = self.positive(c.value.radius, &c.span, "radius", "circle");
            let m = mat(self, &c.value.material);
            let angle = self.angle(c.value.ply_angle.as_ref());
            let n = c.value.elements.unwrap_or(8);
            if n == 0 {
                self.error(
                    "circle: `elements` must be at least 1",
                    self.key(&c.span, "elements"),
                    None,
                );
            }
            let fits = self.guard("circle", (n as u128).pow(2) * 3, &c.span);
            (ok && fits && n > 0).then_some(()).and(m).and_then(|m| {
                angle.map(|a| {
                    generate::circle(&generate::Circle {
                        radius: c.value.radius,
                        material: m,
                        ply_angle: a,
                        elements: n,
                        meshing,
                    })
                })
            })
        } else if let Some(t) = &input.tube {
            let ok = self.positive(t.value.outer_radius, &t.span, "outer_radius", "tube");
            let plies = self.layup(&t.value.layup, &names, &t.span, "layup", "tube");
            let plies = plies.filter(|p| {
                let th = generate::layup_thickness(p);
                if ok && th >= t.value.outer_radius {
                    self.error(
                        format!("tube: the layup ({th:e} m) is not thinner than the outer radius ({:e} m)", t.value.outer_radius),
                        self.key(&t.span, "layup"),
                        None,
                    );
                    false
                } else {
                    true
                }
            });
            let around = t.value.elements_around.unwrap_or(72).max(3);
            let per = t.value.elements_per_ply.unwrap_or(1).max(1);
            let fits = match &plies {
                Some(p) => self.guard(
                    "tube",
                    around as u128 * per as u128 * p.len() as u128,
                    &t.span,
                ),
                None => true,
            };
            (ok && fits).then_some(()).and(plies).map(|plies| {
                generate::tube(&generate::Tube {
                    outer_radius: t.value.outer_radius,
                    plies,
                    elements_around: around,
                    elements_per_ply: per,
                    meshing,
                })
            })
        } else if let Some(b) = &input.box_section {
            let (e, v) = (&b.span, &b.value);
            let ok = self.positive(v.width, e, "width", "box")
                & self.positive(v.height, e, "height", "box");
            let mut walls: Vec<Option<Vec<Ply>>> = Vec::new();
            for (key, l) in [
                ("bottom", &v.bottom),
                ("right", &v.right),
                ("top", &v.top),
                ("left", &v.left),
            ] {
                let list = match (l, &v.layup) {
                    (Some(l), _) => self.layup(l, &names, e, key, "box"),
                    (None, Some(all)) => self.layup(all, &names, e, "layup", "box"),
                    (None, None) => {
                        self.error(
                            format!("box: no layup for the {key} wall"),
                            e.clone(),
                            Some("give `layup = [...]` for all walls, or `top`, `bottom`, `left`, `right`"),
                        );
                        None
                    }
                };
                walls.push(list);
            }
            let [n1, n2] = v.elements.unwrap_or([24, 12]).map(|n| n.max(1) as u128);
            let plies = walls.iter().flatten().map(|w| w.len()).max().unwrap_or(0) as u128;
            let per = v.elements_per_ply.unwrap_or(1).max(1) as u128;
            if !ok
                || walls.iter().any(|w| w.is_none())
                || !self.guard("box", 2 * (n1 + n2) * plies * per, e)
            {
                None
            } else {
                let w: Vec<Vec<Ply>> = walls.into_iter().map(|w| w.expect("checked")).collect();
                let walls: [Vec<Ply>; 4] = [w[0].clone(), w[1].clone(), w[2].clone(), w[3].clone()];
                match generate::box_section(&generate::BoxSection {
                    width: v.width,
                    height: v.height,
                    walls,
                    elements: v.elements.unwrap_or([24, 12]).map(|n| n.max(1)),
                    elements_per_ply: v.elements_per_ply.unwrap_or(1).max(1),
                    meshing,
                }) {
                    Ok(m) => Some(m),
                    Err(err) => {
                        self.error(
                            format!("box: {err}"),
                            e.clone(),
                            Some("walls are listed as layups of plies from the outer surface in"),
                        );
                        None
                    }
                }
            }
        } else if let Some(s) = &input.i_section {
            let (e, v) = (&s.span, &s.value);
            let ok = self.positive(v.width, e, "width", "i_section")
                & self.positive(v.height, e, "height", "i_section");
            let flange = |c: &mut Self, own: &Option<Vec<Located<PlyInput>>>, key: &str| match (
                own, &v.flanges,
            ) {
                (Some(l), _) => c.layup(l, &names, e, key, "i_section"),
                (None, Some(l)) => c.layup(l, &names, e, "flanges", "i_section"),
                (None, None) => {
                    c.error(
                        format!("i_section: no layup for the {key} flange"),
                        e.clone(),
                        Some("give `flanges = [...]`, or `top` and `bottom`"),
                    );
                    None
                }
            };
            let top = flange(self, &v.top, "top");
            let bottom = flange(self, &v.bottom, "bottom");
            let web = self.layup(&v.web, &names, e, "web", "i_section");
            let [nf, nw] = v.elements.unwrap_or([6, 16]).map(|n| n.max(1) as u128);
            let per = v.elements_per_ply.unwrap_or(1).max(1) as u128;
            let rows = [&top, &bottom, &web]
                .iter()
                .map(|l| l.as_ref().map_or(0, |l| l.len()))
                .sum::<usize>() as u128;
            let fits = self.guard("i_section", (2 * nf + nw + rows) * rows * per, e);
            match (ok && fits, top, bottom, web) {
                (true, Some(top), Some(bottom), Some(web)) => {
                    match generate::i_section(&generate::ISection {
                        width: v.width,
                        height: v.height,
                        top,
                        bottom,
                        web,
                        elements: v.elements.unwrap_or([6, 16]).map(|n| n.max(1)),
                        elements_per_ply: v.elements_per_ply.unwrap_or(1).max(1),
                        meshing,
                    }) {
                        Ok(m) => Some(m),
                        Err(err) => {
                            self.error(format!("i_section: {err}"), e.clone(), None);
                            None
                        }
                    }
                }
                _ => None,
            }
        } else if let Some(a) = &input.airfoil {
            self.airfoil(a, &names, meshing)
        } else {
            None
        };
        let mut mesh = mesh?;
        if let Some(h) = header {
            let off = h.value.offset.unwrap_or([0.0, 0.0]);
            let rot = h.value.rotation.unwrap_or(0.0);
            if !(off.iter().all(|x| x.is_finite()) && rot.is_finite()) {
                self.error(
                    "`offset` and `rotation` must be finite",
                    h.span.clone(),
                    None,
                );
                return None;
            }
            mesh.transform(off, rot.to_radians());
        }
        if self.diags.iter().any(|d| d.severity == Severity::Error) {
            return None;
        }
        let materials: Vec<Material> = materials
            .into_iter()
            .map(|m| {
                m.unwrap_or_else(|| Material {
                    name: String::new(),
                    stiffness: Matrix6::identity(),
                    density: 0.0,
                })
            })
            .collect();
        match SectionModel::new(mesh, materials) {
            Ok(m) => Some((m, origin)),
            Err(bad) => {
                // Generated meshes: say where.
                for b in bad.iter().take(5) {
                    self.error(
                        format!("{origin}: element {} {}", b.element + 1, b.message),
                        given[0].1.clone(),
                        Some("the generated mesh is invalid: check the dimensions and layup thicknesses"),
                    );
                }
                None
            }
        }
    }

    /// Refuses meshes too large to build (a typo in an element count must not exhaust the
    /// memory): at most [`MAX_ELEMENTS`] elements.
    fn guard(&mut self, what: &str, estimate: u128, span: &Option<Range<usize>>) -> bool {
        if estimate <= MAX_ELEMENTS as u128 {
            return true;
        }
        self.error(
            format!("{what}: these element counts make about {estimate} elements, more than the {MAX_ELEMENTS} allowed"),
            span.clone(),
            Some("a few thousand to some tens of thousands of elements resolve a section well"),
        );
        false
    }

    /// The index of a named material; an error with a suggestion if there is none.
    fn material_ref(&mut self, m: &Located<String>, names: &[String]) -> Option<usize> {
        if let Some(i) = names.iter().position(|n| *n == m.value) {
            return Some(i);
        }
        let hint = crate::diagnostics::did_you_mean(&m.value, names.iter().map(|s| s.as_str()))
            .map(|b| format!("did you mean '{b}'?"))
            .unwrap_or_else(|| format!("the materials are: {}", names.join(", ")));
        self.error(
            format!("unknown material '{}'", m.value),
            m.span.clone(),
            Some(&hint),
        );
        None
    }

    fn angle(&mut self, a: Option<&Located<f64>>) -> Option<f64> {
        let Some(a) = a else { return Some(0.0) };
        if a.value.is_finite() && (-90.0..=90.0).contains(&a.value) {
            Some(a.value.to_radians())
        } else {
            self.error(
                format!("ply angle {} is outside [−90, 90] degrees", a.value),
                a.span.clone(),
                Some("the ply angle turns the fibre from the beam axis towards the wall's contour direction; −90 … 90 covers every direction"),
            );
            None
        }
    }

    fn layup(
        &mut self,
        list: &[Located<PlyInput>],
        names: &[String],
        entry: &Option<Range<usize>>,
        key: &str,
        what: &str,
    ) -> Option<Vec<Ply>> {
        if list.is_empty() {
            self.error(
                format!("{what}: `{key}` needs at least one ply"),
                self.key(entry, key),
                None,
            );
            return None;
        }
        let mut out = Vec::new();
        let mut ok = true;
        for p in list {
            let v = &p.value;
            let m = self.material_ref(&v.material, names);
            let th_ok = v.thickness.is_finite() && v.thickness > 0.0;
            if !th_ok {
                self.error(
                    format!(
                        "{what}: a ply thickness must be positive (got {})",
                        v.thickness
                    ),
                    self.key(&p.span, "thickness"),
                    None,
                );
            }
            let count = v.count.unwrap_or(1);
            if count > MAX_COUNT {
                self.error(
                    format!("{what}: `count` must be at most {MAX_COUNT} (got {count})"),
                    self.key(&p.span, "count"),
                    None,
                );
            }
            if count == 0 {
                self.error(
                    format!("{what}: `count` must be at least 1"),
                    self.key(&p.span, "count"),
                    None,
                );
            }
            let angle = self.angle(v.angle.as_ref());
            match (m, angle) {
                (Some(m), Some(a)) if th_ok && count > 0 && count <= MAX_COUNT => {
                    for _ in 0..count {
                        out.push(Ply {
                            material: m,
                            thickness: v.thickness,
                            angle: a,
                        });
                    }
                }
                _ => ok = false,
            }
        }
        ok.then_some(out)
    }

    fn materials(&mut self, input: &SectionFile) -> (Vec<Option<Material>>, Vec<String>) {
        let mut out = Vec::new();
        let mut names: Vec<String> = Vec::new();
        for m in &input.materials {
            let v = &m.value;
            let what = format!("material '{}'", v.name.value);
            if names.contains(&v.name.value) {
                self.error(
                    format!("{what} is defined twice"),
                    v.name.span.clone(),
                    Some("material names must be unique"),
                );
            }
            names.push(v.name.value.clone());
            let rho = v.rho.unwrap_or(0.0);
            let need = |c: &mut Self, x: Option<f64>, key: &str| -> Option<f64> {
                if x.is_none() {
                    c.error(
                        format!(
                            "{what}: a {} material needs `{key}`",
                            match v.kind {
                                MaterialType::Isotropic => "isotropic",
                                MaterialType::Orthotropic => "orthotropic",
                                MaterialType::Anisotropic => "anisotropic",
                            }
                        ),
                        m.span.clone(),
                        Some(match v.kind {
                            MaterialType::Isotropic => "isotropic: E, nu (and rho)",
                            MaterialType::Orthotropic => {
                                "orthotropic: E1, E2, E3, G12, G13, G23, nu12, nu13, nu23 (and rho)"
                            }
                            MaterialType::Anisotropic => "anisotropic: C = [[…6×6…]] (and rho)",
                        }),
                    );
                }
                x
            };
            let built = match v.kind {
                MaterialType::Isotropic => match (need(self, v.e, "E"), need(self, v.nu, "nu")) {
                    (Some(e), Some(nu)) => Some(Material::isotropic(&v.name.value, e, nu, rho)),
                    _ => None,
                },
                MaterialType::Orthotropic => {
                    let vals: Vec<Option<f64>> = [
                        (v.e1, "E1"),
                        (v.e2, "E2"),
                        (v.e3, "E3"),
                        (v.g12, "G12"),
                        (v.g13, "G13"),
                        (v.g23, "G23"),
                        (v.nu12, "nu12"),
                        (v.nu13, "nu13"),
                        (v.nu23, "nu23"),
                    ]
                    .iter()
                    .map(|(x, k)| need(self, *x, k))
                    .collect();
                    if vals.iter().all(|x| x.is_some()) {
                        let x: Vec<f64> = vals.into_iter().map(|x| x.expect("checked")).collect();
                        Some(Material::orthotropic(
                            &v.name.value,
                            &Orthotropic {
                                e1: x[0],
                                e2: x[1],
                                e3: x[2],
                                g12: x[3],
                                g13: x[4],
                                g23: x[5],
                                nu12: x[6],
                                nu13: x[7],
                                nu23: x[8],
                            },
                            rho,
                        ))
                    } else {
                        None
                    }
                }
                MaterialType::Anisotropic => {
                    v.c.map(|c| {
                        Material::anisotropic(&v.name.value, &Matrix6::from_fn(|i, j| c[i][j]), rho)
                    })
                    .or_else(|| {
                        need(self, None, "C");
                        None
                    })
                }
            };
            let built = match built {
                Some(Ok(mat)) if rho.is_finite() && rho >= 0.0 => Some(mat),
                Some(Ok(_)) => {
                    self.error(
                        format!("{what}: the density `rho` must be ≥ 0 (got {rho})"),
                        self.key(&m.span, "rho"),
                        None,
                    );
                    None
                }
                Some(Err(msg)) => {
                    self.error(
                        format!("{what}: {msg}"),
                        m.span.clone(),
                        Some("a material must store positive energy for every strain (positive moduli, Poisson ratios within their bounds, C symmetric positive definite)"),
                    );
                    None
                }
                None => None,
            };
            out.push(built);
        }
        (out, names)
    }

    fn mesh_file(&mut self, m: &Located<MeshInput>, names: &[String]) -> Option<Mesh> {
        let path = self.base.join(&m.value.file.value);
        let text = match crate::input_files::read_text(&path) {
            Ok(t) => t,
            Err(e) => {
                self.error(
                    format!("cannot read the mesh file '{}': {e}", path.display()),
                    m.value.file.span.clone(),
                    Some("the path is relative to the section file's folder"),
                );
                return None;
            }
        };
        self.files.push(path.clone());
        let gmsh = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("msh"));
        let read = if gmsh {
            mesh_io::read_gmsh(&text)
        } else {
            mesh_io::read_text(&text)
        };
        let mesh_source = SourceFile::new(&path, text.as_str());
        let file: MeshFile = match read {
            Ok(f) => f,
            Err(e) => {
                self.file_error(&mesh_source, e);
                return None;
            }
        };
        // Regions → material and angles.
        let mut regions = Vec::new();
        for r in &m.value.regions {
            let mat = self.material_ref(&r.value.material, names);
            let angle = self.angle(r.value.ply_angle.as_ref());
            let wall = r.value.wall_angle.unwrap_or(0.0);
            if !wall.is_finite() {
                self.error(
                    "`wall_angle` must be finite",
                    self.key(&r.span, "wall_angle"),
                    None,
                );
            }
            regions.push((r.value.name.value.clone(), mat, angle, wall.to_radians()));
        }
        let mut elements = Vec::new();
        let mut missing: Vec<String> = Vec::new();
        for e in &file.elements {
            match regions.iter().find(|r| r.0 == e.region) {
                Some((_, Some(mat), Some(angle), wall)) => elements.push(Element {
                    kind: e.kind,
                    nodes: e.nodes,
                    material: *mat,
                    ply_angle: *angle,
                    wall_angle: *wall,
                }),
                Some(_) => return None,
                None => {
                    if !missing.contains(&e.region) {
                        missing.push(e.region.clone());
                        self.file_error(
                            &mesh_source,
                            MeshFileError {
                                span: e.span.clone(),
                                message: format!("region '{}' has no entry in the section file's [[mesh.regions]]", e.region),
                                hint: Some(format!(
                                    "add [[mesh.regions]] name = \"{}\", material = …; the regions given are: {}",
                                    e.region,
                                    regions.iter().map(|r| r.0.as_str()).collect::<Vec<_>>().join(", ")
                                )),
                            },
                        );
                    }
                }
            }
        }
        if !missing.is_empty() {
            return None;
        }
        let mut mesh = Mesh {
            nodes: file.nodes.clone(),
            elements,
        };
        if let Err(bad) = mesh.check() {
            for b in bad.iter().take(10) {
                self.file_error(
                    &mesh_source,
                    MeshFileError {
                        span: file.elements[b.element].span.clone(),
                        message: format!("this element {}", b.message),
                        hint: Some("corners counter-clockwise, then the mid-side nodes in Gmsh order; no repeated or collinear corners".into()),
                    },
                );
            }
            return None;
        }
        Some(mesh)
    }

    fn file_error(&mut self, source: &SourceFile, e: MeshFileError) {
        let mut d = Diagnostic::error(e.message, Some(e.span));
        d.hint = e.hint;
        match self.other.iter_mut().find(|m| m.source.path == source.path) {
            Some(m) => m.diagnostics.push(d),
            None => self.other.push(ModelError {
                source: source.clone(),
                diagnostics: vec![d],
            }),
        }
    }

    fn airfoil(
        &mut self,
        a: &Located<AirfoilInput>,
        names: &[String],
        meshing: Meshing,
    ) -> Option<Mesh> {
        let (e, v) = (&a.span, &a.value);
        let ok = self.positive(v.chord, e, "chord", "airfoil");
        // Coordinates and where each point is written.
        type Points = (Vec<[f64; 2]>, Vec<Option<Range<usize>>>, Option<SourceFile>);
        let (coords, spans, source): Points = match (&v.coordinates, &v.coordinates_file) {
            (Some(c), None) => (
                c.value.iter().map(|p| p.value).collect(),
                c.value.iter().map(|p| p.span.clone()).collect(),
                None,
            ),
            (None, Some(f)) => {
                let path = self.base.join(&f.value);
                let text = match crate::input_files::read_text(&path) {
                    Ok(t) => t,
                    Err(err) => {
                        self.error(
                            format!(
                                "cannot read the coordinates file '{}': {err}",
                                path.display()
                            ),
                            f.span.clone(),
                            Some("the path is relative to the section file's folder"),
                        );
                        return None;
                    }
                };
                self.files.push(path.clone());
                let src = SourceFile::new(&path, text.as_str());
                match read_coordinates(&text) {
                    Ok((c, s)) => (c, s.into_iter().map(Some).collect(), Some(src)),
                    Err(err) => {
                        self.file_error(&src, err);
                        return None;
                    }
                }
            }
            _ => {
                self.error(
                        "airfoil: give either `coordinates` or `coordinates_file`",
                        e.clone(),
                        Some("coordinates = [[1.0, 0.0], [0.5, 0.06], …] from the trailing edge over the upper surface"),
                    );
                return None;
            }
        };
        let skin = self.layup(&v.skin, names, e, "skin", "airfoil");
        let mut caps = Vec::new();
        let mut caps_ok = true;
        for c in &v.spar_caps {
            match self.layup(&c.value.layup, names, &c.span, "layup", "spar cap") {
                Some(plies) => caps.push(generate::SparCap {
                    surface: match c.value.surface.unwrap_or_default() {
                        SurfaceInput::Both => generate::Surface::Both,
                        SurfaceInput::Upper => generate::Surface::Upper,
                        SurfaceInput::Lower => generate::Surface::Lower,
                    },
                    from: c.value.from,
                    to: c.value.to,
                    plies,
                }),
                None => caps_ok = false,
            }
        }
        let mut webs = Vec::new();
        let mut webs_ok = true;
        for w in &v.webs {
            match self.layup(&w.value.layup, names, &w.span, "layup", "web") {
                Some(plies) => webs.push(generate::Web {
                    at: w.value.at.value,
                    plies,
                    elements: w.value.elements.unwrap_or(0),
                }),
                None => webs_ok = false,
            }
        }
        let fill = match &v.trailing_edge_fill {
            None => Some(None),
            Some(f) => {
                let m = self.material_ref(&f.material, names);
                let ang = self.angle(f.angle.as_ref());
                m.zip(ang).map(Some)
            }
        };
        let (Some(skin), true, true, true, Some(fill)) = (skin, caps_ok, webs_ok, ok, fill) else {
            return None;
        };
        let af = generate::Airfoil {
            coordinates: coords,
            chord: v.chord,
            reference: v.reference.unwrap_or([0.0, 0.0]),
            blunt_trailing_edge: v.blunt_trailing_edge.unwrap_or(false),
            skin,
            caps,
            webs,
            fill,
            elements_around: v.elements_around.unwrap_or(200).max(8),
            elements_per_ply: v.elements_per_ply.unwrap_or(1).max(1),
            meshing,
        };
        let rows = af.skin.len() + af.caps.iter().map(|c| c.plies.len()).sum::<usize>();
        let estimate =
            af.elements_around as u128 * (rows as u128 + 2) * af.elements_per_ply as u128
                + af.webs
                    .iter()
                    .map(|w| {
                        (w.plies.len() as u128)
                            * (w.elements.max(1) as u128 + af.elements_around as u128)
                    })
                    .sum::<u128>();
        if !self.guard("airfoil", estimate, e) {
            return None;
        }
        match generate::airfoil(&af) {
            Ok((mesh, notes)) => {
                for n in notes {
                    self.diags
                        .push(Diagnostic::warning(format!("airfoil: {n}"), e.clone()));
                }
                Some(mesh)
            }
            Err(err) => {
                use generate::AirfoilError as E;
                let coord_key = if v.coordinates.is_some() {
                    "coordinates"
                } else {
                    "coordinates_file"
                };
                let at_point = |c: &mut Self, i: usize, msg: String, hint: &str| match &source {
                    Some(src) => c.file_error(
                        src,
                        MeshFileError {
                            span: spans[i].clone().unwrap_or(0..1),
                            message: msg,
                            hint: Some(hint.into()),
                        },
                    ),
                    None => c.error(
                        msg,
                        spans[i].clone().or_else(|| c.key(e, coord_key)),
                        Some(hint),
                    ),
                };
                match &err {
                    E::NonFinite { point } => at_point(self, *point, format!("airfoil: {err}"), "coordinates are pairs of finite numbers [x/c, y/c]"),
                    E::SelfIntersecting { i, .. } => at_point(
                        self,
                        *i,
                        format!("airfoil: {err}"),
                        "list the points once around: trailing edge, upper surface, leading edge, lower surface, trailing edge",
                    ),
                    E::NotClosed { .. } => {
                        let last = spans.len().saturating_sub(1);
                        at_point(
                            self,
                            last,
                            format!("airfoil: {err}"),
                            "repeat the first point at the end, or set `blunt_trailing_edge = true` to close the gap with a straight trailing-edge face",
                        )
                    }
                    E::CapRange { cap, .. } => self.error(
                        format!("airfoil: {err}"),
                        v.spar_caps.get(*cap).and_then(|c| c.span.clone()),
                        Some("`from` and `to` are chord fractions x/c of the cap's edges, within the hollow part of the airfoil"),
                    ),
                    E::WebOutside { web, .. } | E::WebsOverlap { b: web, .. } => self.error(
                        format!("airfoil: {err}"),
                        v.webs.get(*web).and_then(|w| w.value.at.span.clone()),
                        Some("`at` is the chord fraction x/c of the web's mid-plane, between the leading edge and the solid trailing edge"),
                    ),
                    E::Folded { .. } => self.error(
                        format!("airfoil: {err}"),
                        self.key(e, "skin"),
                        Some("use thinner plies, a larger chord, or more points where the contour is sharply curved"),
                    ),
                    E::TooFewPoints(_) | E::EmptySkin | E::NoTrailingEdge { .. } => self.error(format!("airfoil: {err}"), self.key(e, coord_key), None),
                }
                None
            }
        }
    }
}
