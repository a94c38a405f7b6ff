//! The `[[beams]]` tables of the model file (schema only; checked in `validate::beam`).

use crate::model::input::TimeFunctionInput;
use crate::model::located::Located;
use schemars::JsonSchema;
use serde::Deserialize;

/// Quadrature of a beam's elastic terms.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum BeamQuadrature {
    /// p Gauss points per element (default): free of shear locking.
    #[default]
    Reduced,
    /// p + 1 Gauss points per element.
    Full,
}

/// A geometrically exact beam of Legendre spectral elements.
#[derive(Clone, Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BeamInput {
    /// Unique beam name; created nodes are named `<name>.<k>` (k = 0 … elements·order).
    pub name: Located<String>,
    /// Polynomial order p ≥ 1 of each element (p + 1 nodes at Gauss–Lobatto–Legendre points).
    /// With `beamdyn` it may be left out: the file's `order_elem` is used.
    #[serde(default)]
    pub order: usize,
    /// An OpenFAST BeamDyn primary input file (path relative to the model file): key
    /// points, initial twist, `order_elem`, `quadrature` and, through its `BldFile`, the
    /// blade's stations of 6×6 stiffness and mass and its damping, converted to samara's
    /// conventions (docs/aerodynamics.md, "BeamDyn blade files"). Replaces `points`,
    /// `twist`, `y_axis` and the sections; `order`, `quadrature` and `damping` given here
    /// override the file's.
    #[serde(default)]
    pub beamdyn: Option<Located<String>>,
    /// With `beamdyn`: the global position of BeamDyn's blade-root origin (its GlbPos;
    /// default the origin).
    #[serde(default)]
    pub root_position: Option<[f64; 3]>,
    /// With `beamdyn`: the global directions of BeamDyn's blade axes x, y, z (rows; its
    /// GlbDCM transposed), orthonormal and right-handed. Default the global axes.
    #[serde(default)]
    pub root_axes: Option<[[f64; 3]; 3]>,
    /// Number of elements of equal arc length (default 1).
    #[serde(default)]
    pub elements: Option<usize>,
    /// `reduced` (default, p Gauss points for the elastic terms) or `full` (p + 1).
    #[serde(default)]
    pub quadrature: Option<BeamQuadrature>,
    /// Name of the first node; an existing node is shared (its position must be the line's
    /// start), otherwise it is created. Default `<name>.0`.
    #[serde(default)]
    pub root: Option<Located<String>>,
    /// Name of the last node (shared or created like `root`). Default `<name>.<last>`.
    #[serde(default)]
    pub tip: Option<Located<String>>,
    /// Key points of the reference line, global [m] (at least 2), joined by a natural
    /// cubic spline in chord length.
    #[serde(default)]
    pub points: Option<Vec<[f64; 3]>>,
    /// Twist of the section about the reference line, [[η, angle rad], …], η ∈ [0, 1]
    /// strictly increasing (natural cubic spline); default none.
    #[serde(default)]
    pub twist: Option<Vec<[f64; 2]>>,
    /// Reference direction of the section y axis at the root, global (made normal to the
    /// tangent). Default: the global axis after (cyclically) the one most aligned with the
    /// root tangent (beam along x → y; along z → x).
    #[serde(default)]
    pub y_axis: Option<[f64; 3]>,
    /// Instead of `points`: the beam's nodes, root to tip (elements·order + 1 names from
    /// `[[nodes]]`); their positions and orientations (x axis along the beam) are the
    /// reference line and section frames.
    #[serde(default)]
    pub nodes: Option<Vec<Located<String>>>,
    /// Sectional properties at stations along the span (linear in between).
    #[serde(default)]
    pub sections: Vec<Located<SectionInput>>,
    /// CSV file of sectional properties (path relative to the model file): a header line
    /// `station,K11,K12,…,K66,M11,…,M66` then one row of 73 numbers per station.
    #[serde(default)]
    pub sections_file: Option<Located<String>>,
    /// Stiffness-proportional damping coefficients μ₁…μ₆ [s] (default 0):
    /// damping stress D ė with D = diag(√μ) C diag(√μ).
    #[serde(default)]
    pub damping: Option<[f64; 6]>,
    /// Distributed loads per unit length.
    #[serde(default)]
    pub loads: Vec<Located<BeamLoadInput>>,
    /// Initial rigid-body angular velocity of the whole beam, global [rad/s], about
    /// `rotation_centre` (default: the root): created nodes get v = ω × (x − c).
    #[serde(default)]
    pub angular_velocity: Option<[f64; 3]>,
    /// Centre of the initial rigid rotation, global [m]; default the root point.
    #[serde(default)]
    pub rotation_centre: Option<[f64; 3]>,
}

/// Sectional properties at one station: either `stiffness` (and `mass`) 6×6 matrices,
/// `isotropic` engineering constants, or a `section` file.
#[derive(Clone, Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SectionInput {
    /// Normalized arc length η ∈ [0, 1] of the station.
    pub station: f64,
    /// A section file (`SECTION.toml`, path relative to the model file) whose stiffness and
    /// mass samara's cross-sectional analysis computes (docs/sections.md).
    #[serde(default)]
    pub section: Option<Located<String>>,
    /// 6×6 stiffness, section frame, (axial, shear y, shear z, torsion, bending y, bending z).
    #[serde(default)]
    pub stiffness: Option<[[f64; 6]; 6]>,
    /// 6×6 mass per unit length about the reference line, same ordering (default zero).
    #[serde(default)]
    pub mass: Option<[[f64; 6]; 6]>,
    /// Isotropic section instead of the matrices.
    #[serde(default)]
    pub isotropic: Option<IsotropicInput>,
    /// Index ordering of `stiffness` and `mass`: `samara` (default; axial, shear y,
    /// shear z, torsion, bending y, bending z) or `beamdyn` (shear x, shear y, axial,
    /// bending x, bending y, torsion, as in a BeamDyn blade file), converted on reading.
    #[serde(default)]
    pub ordering: Option<SectionOrdering>,
}

/// Index ordering of a 6×6 sectional matrix.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum SectionOrdering {
    /// (axial, shear y, shear z, torsion, bending y, bending z).
    #[default]
    Samara,
    /// BeamDyn's (shear x, shear y, axial, bending x, bending y, torsion).
    Beamdyn,
}

/// Isotropic, homogeneous section.
#[derive(Clone, Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct IsotropicInput {
    /// Young's modulus [Pa].
    #[serde(rename = "E")]
    pub e: f64,
    /// Shear modulus [Pa].
    #[serde(rename = "G")]
    pub g: f64,
    /// Area [m²].
    #[serde(rename = "A")]
    pub a: f64,
    /// Second moment of area about the section y axis [m⁴].
    #[serde(rename = "I2")]
    pub i2: f64,
    /// Second moment of area about the section z axis [m⁴].
    #[serde(rename = "I3")]
    pub i3: f64,
    /// Torsion constant [m⁴].
    #[serde(rename = "J")]
    pub j: f64,
    /// Shear correction factors [k₂, k₃] (5/6 for a solid rectangle).
    pub shear_factors: [f64; 2],
    /// Density [kg/m³] (default 0: massless).
    #[serde(default)]
    pub density: Option<f64>,
    /// Tension centre (y, z) from the reference line [m] (default 0).
    #[serde(default)]
    pub tension_centre: Option<[f64; 2]>,
    /// Shear centre (y, z) [m] (default 0).
    #[serde(default)]
    pub shear_centre: Option<[f64; 2]>,
    /// Mass centre (y, z) [m] (default 0).
    #[serde(default)]
    pub mass_centre: Option<[f64; 2]>,
}

/// Components of a distributed beam load.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum BeamLoadFrame {
    /// Global components (dead load).
    #[default]
    Global,
    /// Section-frame components, following the section (follower load).
    Section,
}

/// A distributed force and moment per unit length, times a time function and a profile.
#[derive(Clone, Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BeamLoadInput {
    /// Force per length [N/m].
    #[serde(default)]
    pub force: Option<[f64; 3]>,
    /// Moment per length [N m/m].
    #[serde(default)]
    pub moment: Option<[f64; 3]>,
    /// `global` (default) or `section`.
    #[serde(default)]
    pub frame: Option<BeamLoadFrame>,
    /// Time function (default constant 1).
    #[serde(default)]
    pub function: Option<Located<TimeFunctionInput>>,
    /// Spanwise factor [[η, f], …], piecewise linear, η increasing (default 1).
    #[serde(default)]
    pub profile: Option<Vec<[f64; 2]>>,
}
