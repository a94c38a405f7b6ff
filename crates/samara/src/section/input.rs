//! The section file (`SECTION.toml`, documented in docs/sections.md): materials, and either
//! a mesh file or one parametric generator; checked with located diagnostics (file, line,
//! column, hint) like the model file.

mod check;

use super::SectionModel;
use super::mesh_io::MeshFileError;
use crate::diagnostics::{Diagnostic, Located, ModelError, Severity, SourceFile};
use check::Checker;
use schemars::JsonSchema;
use serde::Deserialize;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// Points of an airfoil and where each is written.
pub type PointsAndSpans = (Vec<[f64; 2]>, Vec<Range<usize>>);

/// The whole section file.
#[derive(Clone, Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SectionFile {
    /// Name and placement of the section.
    #[serde(default)]
    pub section: Option<Located<Header>>,
    /// Materials, referred to by name.
    #[serde(default)]
    pub materials: Vec<Located<MaterialInput>>,
    /// A mesh file (text format or Gmsh .msh v4 ASCII).
    #[serde(default)]
    pub mesh: Option<Located<MeshInput>>,
    #[serde(default)]
    pub rectangle: Option<Located<RectangleInput>>,
    #[serde(default)]
    pub circle: Option<Located<CircleInput>>,
    #[serde(default)]
    pub tube: Option<Located<TubeInput>>,
    #[serde(default, rename = "box")]
    pub box_section: Option<Located<BoxInput>>,
    #[serde(default)]
    pub i_section: Option<Located<IInput>>,
    #[serde(default)]
    pub airfoil: Option<Located<AirfoilInput>>,
}

/// `[section]`: optional name, placement and element type.
#[derive(Clone, Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Header {
    #[serde(default)]
    pub name: Option<String>,
    /// The geometry is shifted by this vector (y, z) [m] …
    #[serde(default)]
    pub offset: Option<[f64; 2]>,
    /// … then turned by this angle [deg] about the beam axis (counter-clockwise in (y, z)).
    #[serde(default)]
    pub rotation: Option<f64>,
    /// Element of the generators: `quad8` (default), `quad9`, `tri6`, `quad4`, `tri3`.
    #[serde(default)]
    pub element: Option<Located<String>>,
}

/// Material kinds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum MaterialType {
    #[default]
    Isotropic,
    Orthotropic,
    Anisotropic,
}

/// `[[materials]]`: engineering constants (axis 1 the fibre direction) or a 6×6 matrix.
#[derive(Clone, Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MaterialInput {
    pub name: Located<String>,
    #[serde(rename = "type", default)]
    pub kind: MaterialType,
    /// Isotropic: Young's modulus [Pa] and Poisson's ratio.
    #[serde(rename = "E", default)]
    pub e: Option<f64>,
    #[serde(default)]
    pub nu: Option<f64>,
    /// Orthotropic: the nine engineering constants [Pa].
    #[serde(rename = "E1", default)]
    pub e1: Option<f64>,
    #[serde(rename = "E2", default)]
    pub e2: Option<f64>,
    #[serde(rename = "E3", default)]
    pub e3: Option<f64>,
    #[serde(rename = "G12", default)]
    pub g12: Option<f64>,
    #[serde(rename = "G13", default)]
    pub g13: Option<f64>,
    #[serde(rename = "G23", default)]
    pub g23: Option<f64>,
    #[serde(default)]
    pub nu12: Option<f64>,
    #[serde(default)]
    pub nu13: Option<f64>,
    #[serde(default)]
    pub nu23: Option<f64>,
    /// Anisotropic: the 6×6 stiffness in material axes, Voigt order (11, 22, 33, 23, 13, 12),
    /// engineering shear strains [Pa].
    #[serde(rename = "C", default)]
    pub c: Option<[[f64; 6]; 6]>,
    /// Density [kg/m³] (default 0).
    #[serde(default)]
    pub rho: Option<f64>,
}

/// One ply (or `count` identical plies) of a layup, listed from the outer surface in.
#[derive(Clone, Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PlyInput {
    pub material: Located<String>,
    /// Thickness [m] of one ply.
    pub thickness: f64,
    /// Ply angle [deg] in [−90, 90] (default 0).
    #[serde(default)]
    pub angle: Option<Located<f64>>,
    /// Number of identical plies (default 1).
    #[serde(default)]
    pub count: Option<usize>,
}

/// `[mesh]`: a mesh file and its regions.
#[derive(Clone, Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MeshInput {
    /// Path relative to the section file; `.msh` is read as Gmsh, anything else as the
    /// text format.
    pub file: Located<String>,
    pub regions: Vec<Located<RegionInput>>,
}

/// Material and orientation of the elements of one region.
#[derive(Clone, Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RegionInput {
    pub name: Located<String>,
    pub material: Located<String>,
    /// Ply angle [deg] in [−90, 90] (default 0).
    #[serde(default)]
    pub ply_angle: Option<Located<f64>>,
    /// Wall angle [deg]: the wall's contour direction (0, cos φ, sin φ) (default 0).
    #[serde(default)]
    pub wall_angle: Option<f64>,
}

#[derive(Clone, Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RectangleInput {
    /// Along y [m].
    pub width: f64,
    /// Along z [m].
    pub height: f64,
    pub material: Located<String>,
    #[serde(default)]
    pub ply_angle: Option<Located<f64>>,
    /// Elements along y and z (default: 16 along the longer side, square-ish elements).
    #[serde(default)]
    pub elements: Option<[usize; 2]>,
}

#[derive(Clone, Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CircleInput {
    pub radius: f64,
    pub material: Located<String>,
    #[serde(default)]
    pub ply_angle: Option<Located<f64>>,
    /// Elements along a quarter of the circumference (default 8).
    #[serde(default)]
    pub elements: Option<usize>,
}

#[derive(Clone, Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TubeInput {
    pub outer_radius: f64,
    pub layup: Vec<Located<PlyInput>>,
    /// Elements around (default 72) and through each ply (default 1).
    #[serde(default)]
    pub elements_around: Option<usize>,
    #[serde(default)]
    pub elements_per_ply: Option<usize>,
}

#[derive(Clone, Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BoxInput {
    /// Outer width (y) and height (z) [m].
    pub width: f64,
    pub height: f64,
    /// The layup of every wall, unless given per wall below.
    #[serde(default)]
    pub layup: Option<Vec<Located<PlyInput>>>,
    #[serde(default)]
    pub top: Option<Vec<Located<PlyInput>>>,
    #[serde(default)]
    pub bottom: Option<Vec<Located<PlyInput>>>,
    #[serde(default)]
    pub left: Option<Vec<Located<PlyInput>>>,
    #[serde(default)]
    pub right: Option<Vec<Located<PlyInput>>>,
    /// Elements along the horizontal and the vertical walls (default [24, 12]).
    #[serde(default)]
    pub elements: Option<[usize; 2]>,
    #[serde(default)]
    pub elements_per_ply: Option<usize>,
}

#[derive(Clone, Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct IInput {
    /// Flange width (y) and overall height (z) [m].
    pub width: f64,
    pub height: f64,
    /// Both flanges, unless given as `top`/`bottom`.
    #[serde(default)]
    pub flanges: Option<Vec<Located<PlyInput>>>,
    #[serde(default)]
    pub top: Option<Vec<Located<PlyInput>>>,
    #[serde(default)]
    pub bottom: Option<Vec<Located<PlyInput>>>,
    pub web: Vec<Located<PlyInput>>,
    /// Elements along each flange overhang and along the web (default [6, 16]).
    #[serde(default)]
    pub elements: Option<[usize; 2]>,
    #[serde(default)]
    pub elements_per_ply: Option<usize>,
}

/// Spar-cap surfaces.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum SurfaceInput {
    #[default]
    Both,
    Upper,
    Lower,
}

#[derive(Clone, Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CapInput {
    /// `both` (default), `upper` or `lower`.
    #[serde(default)]
    pub surface: Option<SurfaceInput>,
    /// Chord stations x/c of the cap's edges (outer surface).
    pub from: f64,
    pub to: f64,
    pub layup: Vec<Located<PlyInput>>,
}

#[derive(Clone, Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct WebInput {
    /// Chord station x/c of the web's mid-plane.
    pub at: Located<f64>,
    /// Plies from the leading-edge side.
    pub layup: Vec<Located<PlyInput>>,
    /// Elements along the web's height (default: about square).
    #[serde(default)]
    pub elements: Option<usize>,
}

#[derive(Clone, Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FillInput {
    pub material: Located<String>,
    #[serde(default)]
    pub angle: Option<Located<f64>>,
}

#[derive(Clone, Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct AirfoilInput {
    /// Points (x/c, y/c), trailing edge → upper surface → leading edge → lower surface →
    /// trailing edge …
    #[serde(default)]
    pub coordinates: Option<Located<Vec<Located<[f64; 2]>>>>,
    /// … or a file of them (`x y` per line, Selig format; a first line of text is the name).
    #[serde(default)]
    pub coordinates_file: Option<Located<String>>,
    /// Chord [m].
    pub chord: f64,
    /// The section origin (x/c, y/c), e.g. the pitch axis (default [0, 0]).
    #[serde(default)]
    pub reference: Option<[f64; 2]>,
    /// Close a gap between the first and last point with a straight trailing-edge face.
    #[serde(default)]
    pub blunt_trailing_edge: Option<bool>,
    pub skin: Vec<Located<PlyInput>>,
    #[serde(default)]
    pub spar_caps: Vec<Located<CapInput>>,
    #[serde(default)]
    pub webs: Vec<Located<WebInput>>,
    /// Material between the skins in the solid trailing edge (default the innermost skin
    /// ply).
    #[serde(default)]
    pub trailing_edge_fill: Option<FillInput>,
    /// Skin elements around the contour (default 200) and through each ply (default 1).
    #[serde(default)]
    pub elements_around: Option<usize>,
    #[serde(default)]
    pub elements_per_ply: Option<usize>,
}

/// A section file, read, checked and meshed.
#[derive(Clone, Debug)]
pub struct LoadedSection {
    pub model: SectionModel,
    pub name: String,
    pub source: SourceFile,
    /// Every file the section was built from (the section file first), for the cache key.
    pub files: Vec<PathBuf>,
    /// Warnings and notes (e.g. moved cap edges).
    pub warnings: Vec<Diagnostic>,
    /// Which generator or mesh format built it.
    pub origin: String,
}

/// A section file that cannot be used: its diagnostics, and those of the files it reads.
#[derive(Clone, Debug)]
pub struct SectionError {
    pub errors: Vec<ModelError>,
}

impl std::fmt::Display for SectionError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        for e in &self.errors {
            write!(f, "{}", e.render_plain())?;
        }
        Ok(())
    }
}

impl std::error::Error for SectionError {}

/// Reads and checks a section file.
pub fn load(path: &Path) -> Result<LoadedSection, SectionError> {
    let text = crate::input_files::read_text(path).map_err(|e| SectionError {
        errors: vec![ModelError {
            source: SourceFile::new(path, ""),
            diagnostics: vec![
                Diagnostic::error(format!("cannot read the section file: {e}"), None)
                    .with_hint("check the path (relative to the current folder, or to the model file for `section = …`)"),
            ],
        }],
    })?;
    from_str(&text, path)
}

/// Parses and checks section text; `path` locates diagnostics and relative file names.
pub fn from_str(text: &str, path: &Path) -> Result<LoadedSection, SectionError> {
    let source = SourceFile::new(path, text);
    let input: SectionFile = match toml::from_str(text) {
        Ok(i) => i,
        Err(e) => {
            return Err(SectionError {
                errors: vec![ModelError {
                    source,
                    diagnostics: vec![crate::diagnostics::parse_error_diagnostic(&e, text, &[])],
                }],
            });
        }
    };
    let mut c = Checker {
        source: source.clone(),
        diags: Vec::new(),
        other: Vec::new(),
        files: vec![path.to_path_buf()],
        base: path.parent().unwrap_or(Path::new(".")).to_path_buf(),
    };
    let built = c.build(&input);
    let errors = c.diags.iter().any(|d| d.severity == Severity::Error);
    if errors || !c.other.is_empty() || built.is_none() {
        let mut all = Vec::new();
        if !c.diags.is_empty() {
            all.push(ModelError {
                source,
                diagnostics: c.diags,
            });
        }
        all.extend(c.other);
        return Err(SectionError { errors: all });
    }
    let (model, origin) = built.expect("checked");
    let name = input
        .section
        .as_ref()
        .and_then(|h| h.value.name.clone())
        .unwrap_or_else(|| {
            path.file_stem()
                .and_then(|s| s.to_str())
                .unwrap_or("section")
                .trim_end_matches(".section")
                .to_string()
        });
    Ok(LoadedSection {
        model,
        name,
        source,
        files: c.files,
        warnings: c.diags,
        origin,
    })
}

/// Reads airfoil coordinates (`x y` per line; a first line that is not two numbers is the
/// name; blank lines and `#` comments are skipped); returns the points and their spans.
pub fn read_coordinates(text: &str) -> Result<PointsAndSpans, MeshFileError> {
    let mut pts = Vec::new();
    let mut spans = Vec::new();
    let mut start = 0;
    let mut first = true;
    for line in text.split_inclusive('\n') {
        let body = line.split('#').next().unwrap_or("");
        let words: Vec<&str> = body.split_whitespace().collect();
        let off = body.len() - body.trim_start().len();
        let span = start + off..start + body.trim_end().len().max(off + 1);
        start += line.len();
        if words.is_empty() {
            continue;
        }
        let nums: Vec<Option<f64>> = words.iter().map(|w| w.parse::<f64>().ok()).collect();
        if words.len() == 2 && nums.iter().all(|n| n.is_some_and(f64::is_finite)) {
            pts.push([nums[0].expect("number"), nums[1].expect("number")]);
            spans.push(span);
        } else if first && pts.is_empty() {
            // The title line.
        } else {
            return Err(MeshFileError {
                span,
                message: format!("expected two numbers `x y`, found '{}'", body.trim()),
                hint: Some("one point per line: x/c and y/c separated by spaces".into()),
            });
        }
        first = false;
    }
    Ok((pts, spans))
}
