//! An airfoil section from its coordinates: a skin layup all around, spar caps on the upper
//! and/or lower surface between chord stations, and shear webs at chord stations.
//!
//! Geometry (chord-scaled airfoil coordinates, x along the chord, y up):
//! - the contour is the polyline through the points, made counter-clockwise; a gap between
//!   the first and last point is closed by a straight trailing-edge face only when
//!   `blunt_trailing_edge` is set;
//! - every layer follows the contour at a constant depth: a point of segment k at depth d
//!   is `V_k + d n_k + t_k (d tan(β_k/2) + u (ℓ_k − d tan(β_k/2) − d tan(β_{k+1}/2)))`
//!   (n the inward normal, β the turning angle at a vertex, u ∈ [0, 1] along the
//!   segment): the exact offset of the polyline, with mitred vertices;
//! - plies are listed from the outer surface in; spar caps lie inside the skin between
//!   the outer-surface stations x/c = `from` … `to`; webs are straight, perpendicular to the
//!   chord at x/c = `at`, between the innermost surfaces, plies listed from the
//!   leading-edge side;
//! - near the trailing edge, once the airfoil is thinner than 1.2 × the upper and lower
//!   layups together (always, for a sharp trailing edge), the skins are merged into a
//!   solid trailing-edge region: the skin plies continue to the trailing edge, thinning
//!   with the airfoil, with one row of the fill material between them (by default the
//!   innermost skin ply); a sharp trailing edge ends in a fan of triangles;
//! - the contour runs counter-clockwise (from the trailing edge over the upper surface),
//!   so wall angles follow it and the wall normal x × t points inwards;
//! - finally the section is shifted so that the `reference` point (x/c, y/c) is the
//!   origin: section y = (x/c − x_ref) c, z = (y/c − y_ref) c.

use super::{Meshing, Ply, layup_grid, layup_thickness, tolerance};
use crate::section::element::ElementKind;
use crate::section::mesh::{ElementAttr, Mesh, MeshBuilder};

/// Which surface a spar cap is on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Surface {
    Upper,
    Lower,
    Both,
}

/// A spar cap between two chord stations (x/c of the outer surface).
#[derive(Clone, Debug, PartialEq)]
pub struct SparCap {
    pub surface: Surface,
    pub from: f64,
    pub to: f64,
    pub plies: Vec<Ply>,
}

/// A shear web at chord station `at` (x/c of its mid-plane).
#[derive(Clone, Debug, PartialEq)]
pub struct Web {
    pub at: f64,
    pub plies: Vec<Ply>,
    /// Elements along the web's height (0: about square elements).
    pub elements: usize,
}

/// The airfoil section's definition.
#[derive(Clone, Debug, PartialEq)]
pub struct Airfoil {
    /// Points (x/c, y/c), usually trailing edge → upper surface → leading edge → lower
    /// surface → trailing edge.
    pub coordinates: Vec<[f64; 2]>,
    pub chord: f64,
    /// The section origin (x/c, y/c).
    pub reference: [f64; 2],
    pub blunt_trailing_edge: bool,
    pub skin: Vec<Ply>,
    pub caps: Vec<SparCap>,
    pub webs: Vec<Web>,
    /// Material and angle of the row between the skins in the solid trailing edge
    /// (default: the innermost skin ply).
    pub fill: Option<(usize, f64)>,
    pub elements_around: usize,
    pub elements_per_ply: usize,
    pub meshing: Meshing,
}

/// Why an airfoil section cannot be built. Indices are 0-based.
#[derive(Clone, Debug, PartialEq)]
pub enum AirfoilError {
    TooFewPoints(usize),
    NonFinite {
        point: usize,
    },
    /// First and last points apart (chord fractions) and no blunt trailing edge asked for.
    NotClosed {
        gap: f64,
    },
    /// Segments i (from point i) and j cross at `at` (x/c, y/c).
    SelfIntersecting {
        i: usize,
        j: usize,
        at: [f64; 2],
    },
    EmptySkin,
    CapRange {
        cap: usize,
        reason: String,
    },
    WebOutside {
        web: usize,
        reason: String,
    },
    WebsOverlap {
        a: usize,
        b: usize,
    },
    /// The layers fold: too thick for the contour's curvature near x/c.
    Folded {
        near: [f64; 2],
        depth: f64,
    },
    /// The upper and lower surfaces cannot be paired at x/c near the trailing edge.
    NoTrailingEdge {
        x: f64,
    },
}

impl std::fmt::Display for AirfoilError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::TooFewPoints(n) => {
                write!(f, "the airfoil needs at least 5 distinct points (got {n})")
            }
            Self::NonFinite { point } => {
                write!(f, "point {} is not a pair of finite numbers", point + 1)
            }
            Self::NotClosed { gap } => write!(
                f,
                "the airfoil contour is not closed: the first and last points are {gap:.4} chords apart"
            ),
            Self::SelfIntersecting { i, j, at } => write!(
                f,
                "the airfoil contour crosses itself: the segment after point {} crosses the segment after point {} at ({:.5}, {:.5})",
                i + 1,
                j + 1,
                at[0],
                at[1]
            ),
            Self::EmptySkin => write!(f, "the skin needs at least one ply"),
            Self::CapRange { cap, reason } => write!(f, "spar cap {}: {reason}", cap + 1),
            Self::WebOutside { web, reason } => write!(f, "web {}: {reason}", web + 1),
            Self::WebsOverlap { a, b } => write!(f, "webs {} and {} overlap", a + 1, b + 1),
            Self::NoTrailingEdge { x } => write!(
                f,
                "the upper and lower surfaces cannot be paired at x/c = {x:.4} to close the trailing edge: list the points from the trailing edge over the upper surface to the leading edge and back along the lower surface"
            ),
            Self::Folded { near, depth } => write!(
                f,
                "the layers ({depth:.3e} m deep) fold over near x/c = {:.4}, y/c = {:.4}: they are too thick for the curvature of the contour there",
                near[0], near[1]
            ),
        }
    }
}

/// The closed contour (chord-scaled), counter-clockwise, starting at the trailing edge.
struct Contour {
    v: Vec<[f64; 2]>,
    /// Arc length at each vertex (len + 1 values; the last closes the loop).
    s: Vec<f64>,
    /// Unit tangent and inward normal of each segment.
    t: Vec<[f64; 2]>,
    n: Vec<[f64; 2]>,
    /// tan(β/2) of the turning angle at each vertex (positive: left turn).
    tan_half: Vec<f64>,
    /// Index of the leading-edge vertex (smallest x), and whether the last segment is a
    /// blunt trailing-edge face.
    le: usize,
    blunt: bool,
}

impl Contour {
    fn len(&self) -> f64 {
        *self.s.last().expect("non-empty")
    }

    fn segment(&self, s: f64) -> (usize, f64) {
        let m = self.v.len();
        let s = s.clamp(0.0, self.len());
        let k = self
            .s
            .partition_point(|&x| x <= s)
            .saturating_sub(1)
            .min(m - 1);
        let l = self.s[k + 1] - self.s[k];
        (k, if l > 0.0 { (s - self.s[k]) / l } else { 0.0 })
    }

    /// The point at arc length s and depth d (see the module doc).
    fn at(&self, s: f64, d: f64) -> [f64; 2] {
        let m = self.v.len();
        let (k, u) = self.segment(s);
        let l = self.s[k + 1] - self.s[k];
        let a = d * self.tan_half[k];
        let b = d * self.tan_half[(k + 1) % m];
        let along = a + u * (l - a - b);
        let (v, t, n) = (self.v[k], self.t[k], self.n[k]);
        [
            v[0] + d * n[0] + along * t[0],
            v[1] + d * n[1] + along * t[1],
        ]
    }

    /// Wall angle (contour direction) at arc length s.
    fn wall_angle(&self, s: f64) -> f64 {
        let t = self.t[self.segment(s).0];
        t[1].atan2(t[0])
    }

    /// Arc length of the end of the lower surface (start of a blunt trailing-edge face).
    fn surface_end(&self) -> f64 {
        if self.blunt {
            self.s[self.v.len() - 1]
        } else {
            self.len()
        }
    }

    fn s_le(&self) -> f64 {
        self.s[self.le]
    }

    /// Arc length where the surface (upper: s ∈ [0, s_LE], lower: [s_LE, end]) at depth d
    /// reaches x; None if it does not.
    fn station_at_x(&self, upper: bool, x: f64, d: f64) -> Option<f64> {
        let (lo, hi) = if upper {
            (0.0, self.s_le())
        } else {
            (self.s_le(), self.surface_end())
        };
        // Scan vertices for a bracket, then bisect (x is continuous in s).
        let n = 400;
        let f = |s: f64| self.at(s, d)[0] - x;
        let mut prev = (lo, f(lo));
        for i in 1..=n {
            let s = lo + (hi - lo) * i as f64 / n as f64;
            let fs = f(s);
            if prev.1 == 0.0 {
                return Some(prev.0);
            }
            if prev.1.signum() != fs.signum() {
                let (mut a, mut b) = (prev.0, s);
                let fa0 = prev.1;
                for _ in 0..100 {
                    let mid = 0.5 * (a + b);
                    if f(mid).signum() == fa0.signum() {
                        a = mid;
                    } else {
                        b = mid;
                    }
                }
                return Some(0.5 * (a + b));
            }
            prev = (s, fs);
        }
        None
    }
}

fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

/// Intersection of segments p0–p1 and q0–q1 (excluding shared end points).
fn segments_cross(p0: [f64; 2], p1: [f64; 2], q0: [f64; 2], q1: [f64; 2]) -> Option<[f64; 2]> {
    let r = [p1[0] - p0[0], p1[1] - p0[1]];
    let s = [q1[0] - q0[0], q1[1] - q0[1]];
    let den = cross(r, s);
    let qp = [q0[0] - p0[0], q0[1] - p0[1]];
    if den.abs() < 1e-300 {
        return None;
    }
    let t = cross(qp, s) / den;
    let u = cross(qp, r) / den;
    let eps = 1e-12;
    if t > eps && t < 1.0 - eps && u > eps && u < 1.0 - eps {
        Some([p0[0] + t * r[0], p0[1] + t * r[1]])
    } else {
        None
    }
}

/// Builds the counter-clockwise contour (chord-scaled) from the normalized points.
fn contour(a: &Airfoil) -> Result<Contour, AirfoilError> {
    for (i, p) in a.coordinates.iter().enumerate() {
        if !(p[0].is_finite() && p[1].is_finite()) {
            return Err(AirfoilError::NonFinite { point: i });
        }
    }
    let mut pts: Vec<[f64; 2]> = Vec::new();
    for p in &a.coordinates {
        if pts
            .last()
            .is_none_or(|q: &[f64; 2]| (q[0] - p[0]).hypot(q[1] - p[1]) > 1e-12)
        {
            pts.push(*p);
        }
    }
    if pts.len() < 5 {
        return Err(AirfoilError::TooFewPoints(pts.len()));
    }
    let first = pts[0];
    let last = *pts.last().expect("points");
    let gap = (first[0] - last[0]).hypot(first[1] - last[1]);
    let blunt = if gap <= 1e-9 {
        pts.pop();
        false
    } else if a.blunt_trailing_edge {
        true
    } else {
        return Err(AirfoilError::NotClosed { gap });
    };
    let m = pts.len();
    if m < 4 {
        return Err(AirfoilError::TooFewPoints(m));
    }
    for i in 0..m {
        for j in i + 2..m {
            if i == 0 && j == m - 1 {
                continue;
            }
            if let Some(at) = segments_cross(pts[i], pts[(i + 1) % m], pts[j], pts[(j + 1) % m]) {
                return Err(AirfoilError::SelfIntersecting { i, j, at });
            }
        }
    }
    if !blunt {
        // Start at the trailing edge: the point farthest aft.
        let te = (0..m)
            .max_by(|&i, &j| pts[i][0].total_cmp(&pts[j][0]))
            .expect("points");
        pts.rotate_left(te);
    }
    let area2: f64 = (0..m).map(|i| cross(pts[i], pts[(i + 1) % m])).sum();
    if area2 < 0.0 {
        // Clockwise: reverse. A closed contour keeps its first point; an open one keeps
        // the gap (the trailing-edge face) as its last segment.
        if blunt {
            pts.reverse();
        } else {
            pts[1..].reverse();
        }
    }
    let c = a.chord;
    let v: Vec<[f64; 2]> = pts.iter().map(|p| [p[0] * c, p[1] * c]).collect();
    let mut s = vec![0.0];
    let mut t = Vec::with_capacity(m);
    let mut n = Vec::with_capacity(m);
    for i in 0..m {
        let (p, q) = (v[i], v[(i + 1) % m]);
        let l = (q[0] - p[0]).hypot(q[1] - p[1]);
        s.push(s[i] + l);
        let ti = [(q[0] - p[0]) / l, (q[1] - p[1]) / l];
        t.push(ti);
        n.push([-ti[1], ti[0]]);
    }
    let tan_half = (0..m)
        .map(|k| {
            let (tp, tk) = (t[(k + m - 1) % m], t[k]);
            let beta = cross(tp, tk).atan2(tp[0] * tk[0] + tp[1] * tk[1]);
            (0.5 * beta).tan()
        })
        .collect();
    let le = (0..m)
        .min_by(|&i, &j| v[i][0].total_cmp(&v[j][0]))
        .expect("points");
    Ok(Contour {
        v,
        s,
        t,
        n,
        tan_half,
        le,
        blunt,
    })
}

/// One band of layers over an arc-length range: stations (fine grid), depth grid lines,
/// ply of each element row.
struct Band {
    stations: Vec<f64>,
    depth: Vec<f64>,
    rows: Vec<usize>,
    plies: Vec<Ply>,
}

pub fn airfoil(a: &Airfoil) -> Result<(Mesh, Vec<String>), AirfoilError> {
    if a.skin.is_empty() {
        return Err(AirfoilError::EmptySkin);
    }
    let kind = a.meshing.kind;
    let p = kind.order();
    let per = a.elements_per_ply.max(1);
    let c = contour(a)?;
    let chord = a.chord;
    let mut notes = Vec::new();
    let d_skin = layup_thickness(&a.skin);
    let x_le = c.v[c.le][0];
    let x_te = c.v.iter().map(|q| q[0]).fold(f64::NEG_INFINITY, f64::max);
    let upper_of = |cap: &SparCap, upper: bool| match cap.surface {
        Surface::Both => true,
        Surface::Upper => upper,
        Surface::Lower => !upper,
    };
    // Caps: ranges in x and checks.
    for (k, cap) in a.caps.iter().enumerate() {
        if !(cap.from.is_finite() && cap.to.is_finite() && cap.from < cap.to) {
            return Err(AirfoilError::CapRange {
                cap: k,
                reason: format!("`from` ({}) must be less than `to` ({})", cap.from, cap.to),
            });
        }
        if cap.from * chord < x_le || cap.to * chord > x_te {
            return Err(AirfoilError::CapRange {
                cap: k,
                reason: format!(
                    "x/c = {} … {} is not within the airfoil (x/c = {:.4} … {:.4})",
                    cap.from,
                    cap.to,
                    x_le / chord,
                    x_te / chord
                ),
            });
        }
        if cap.plies.is_empty() {
            return Err(AirfoilError::CapRange {
                cap: k,
                reason: "a spar cap needs at least one ply".into(),
            });
        }
    }
    // Depth of the layers on each surface at chord position x (outer-surface x).
    let depth_at = |upper: bool, x: f64| -> f64 {
        d_skin
            + a.caps
                .iter()
                .filter(|cap| upper_of(cap, upper) && x >= cap.from * chord && x <= cap.to * chord)
                .map(|cap| layup_thickness(&cap.plies))
                .sum::<f64>()
    };
    // Where the skins merge: the first x aft of the thickest point where the airfoil is
    // thinner than 1.2 × the two layups.
    let thickness_at = |x: f64| -> Option<f64> {
        let su = c.station_at_x(true, x, 0.0)?;
        let sl = c.station_at_x(false, x, 0.0)?;
        Some(c.at(su, 0.0)[1] - c.at(sl, 0.0)[1])
    };
    let samples = 400;
    let xs: Vec<f64> = (1..samples)
        .map(|i| x_le + (x_te - x_le) * i as f64 / samples as f64)
        .collect();
    let thick: Vec<Option<f64>> = xs.iter().map(|&x| thickness_at(x)).collect();
    let i_max = (0..xs.len())
        .max_by(|&i, &j| thick[i].unwrap_or(0.0).total_cmp(&thick[j].unwrap_or(0.0)))
        .expect("samples");
    let mut x_cut = None;
    for i in i_max..xs.len() {
        let need = 1.2 * (depth_at(true, xs[i]) + depth_at(false, xs[i]));
        if thick[i].is_none_or(|h| h < need) {
            x_cut = Some(xs[i.saturating_sub(1).max(i_max)]);
            break;
        }
    }
    if x_cut.is_none() {
        let face = if c.blunt {
            let (p0, p1) = (c.v[0], c.v[c.v.len() - 1]);
            (p0[0] - p1[0]).hypot(p0[1] - p1[1])
        } else {
            0.0
        };
        if face < 1.2 * (depth_at(true, x_te) + depth_at(false, x_te)) {
            x_cut = Some(xs[xs.len() - 1]);
        }
    }
    // Arc-length stations of the cut (upper, lower).
    let cut = match x_cut {
        Some(x) => {
            let (Some(su), Some(sl)) =
                (c.station_at_x(true, x, 0.0), c.station_at_x(false, x, 0.0))
            else {
                return Err(AirfoilError::NoTrailingEdge { x: x / chord });
            };
            notes.push(format!(
                "the skins merge into a solid trailing edge aft of x/c = {:.4}",
                x / chord
            ));
            Some((su, sl))
        }
        None => None,
    };
    let x_open = x_cut.unwrap_or(x_te);
    // Vertices outside the layered band (the trailing edge and the solid region) do not
    // trim the offsets: the layers end at the cut before reaching them.
    let mut c = c;
    if let Some((su, sl)) = cut {
        for k in 0..c.v.len() {
            if c.s[k] <= su || c.s[k] >= sl {
                c.tan_half[k] = 0.0;
            }
        }
    }
    let c = c;
    // Cap arc-length ranges per surface.
    let mut cap_ranges: Vec<Vec<(bool, f64, f64)>> = Vec::new();
    for (k, cap) in a.caps.iter().enumerate() {
        if cap.to * chord > x_open {
            return Err(AirfoilError::CapRange {
                cap: k,
                reason: format!(
                    "it reaches x/c = {}, into the solid trailing edge (aft of x/c = {:.4})",
                    cap.to,
                    x_open / chord
                ),
            });
        }
        let mut r = Vec::new();
        for upper in [true, false] {
            if !upper_of(cap, upper) {
                continue;
            }
            let s0 = c.station_at_x(upper, cap.from * chord, 0.0);
            let s1 = c.station_at_x(upper, cap.to * chord, 0.0);
            match (s0, s1) {
                (Some(s0), Some(s1)) => r.push((upper, s0.min(s1), s0.max(s1))),
                _ => {
                    return Err(AirfoilError::CapRange {
                        cap: k,
                        reason: "its edges are not on the airfoil's surface".into(),
                    });
                }
            }
        }
        cap_ranges.push(r);
    }
    for (k, r) in cap_ranges.iter().enumerate() {
        for (j, q) in cap_ranges.iter().enumerate().skip(k + 1) {
            for a0 in r {
                for b0 in q {
                    if a0.0 == b0.0 && a0.1 < b0.2 && b0.1 < a0.2 {
                        return Err(AirfoilError::CapRange {
                            cap: j,
                            reason: format!("it overlaps spar cap {}", k + 1),
                        });
                    }
                }
            }
        }
    }
    // Webs: foot stations (corner stations of the web's columns) on both surfaces.
    struct Foot {
        upper: Vec<f64>,
        lower: Vec<f64>,
        d_upper: f64,
        d_lower: f64,
    }
    let mut feet: Vec<Foot> = Vec::new();
    for (k, w) in a.webs.iter().enumerate() {
        let x = w.at * chord;
        if w.plies.is_empty() {
            return Err(AirfoilError::WebOutside {
                web: k,
                reason: "a web needs at least one ply".into(),
            });
        }
        let tw = layup_thickness(&w.plies);
        let margin = 1.5 * d_skin;
        if !(w.at.is_finite() && x - 0.5 * tw > x_le + margin && x + 0.5 * tw < x_open) {
            return Err(AirfoilError::WebOutside {
                web: k,
                reason: format!(
                    "at x/c = {} it is outside the hollow part of the airfoil (x/c = {:.4} … {:.4})",
                    w.at,
                    (x_le + margin) / chord,
                    x_open / chord
                ),
            });
        }
        let (dg, _) = layup_grid(&w.plies, per, 1);
        let targets: Vec<f64> = dg.iter().map(|d| x - 0.5 * tw + d).collect();
        let (du, dl) = (depth_at(true, x), depth_at(false, x));
        let mut upper = Vec::new();
        let mut lower = Vec::new();
        for &xt in &targets {
            match (c.station_at_x(true, xt, du), c.station_at_x(false, xt, dl)) {
                (Some(su), Some(sl)) => {
                    upper.push(su);
                    lower.push(sl);
                }
                _ => {
                    return Err(AirfoilError::WebOutside {
                        web: k,
                        reason: format!(
                            "at x/c = {} it does not reach the inner surfaces of the skin",
                            w.at
                        ),
                    });
                }
            }
        }
        let top = c.at(upper[0], du);
        let bottom = c.at(lower[0], dl);
        if top[1] - bottom[1] < 0.5 * (du + dl) {
            return Err(AirfoilError::WebOutside {
                web: k,
                reason: format!(
                    "at x/c = {} the airfoil is too thin for the skin, caps and web",
                    w.at
                ),
            });
        }
        feet.push(Foot {
            upper,
            lower,
            d_upper: du,
            d_lower: dl,
        });
    }
    for i in 0..feet.len() {
        for j in i + 1..feet.len() {
            let (a0, a1) = (feet[i].lower[0], *feet[i].lower.last().expect("foot"));
            let (b0, b1) = (feet[j].lower[0], *feet[j].lower.last().expect("foot"));
            if a0 <= b1 && b0 <= a1 {
                return Err(AirfoilError::WebsOverlap { a: i, b: j });
            }
        }
    }
    // A cap edge must not fall inside a web's foot: extend the cap over the foot when the
    // web stands on the cap, else stop the cap at the foot.
    for (k, ranges) in cap_ranges.iter_mut().enumerate() {
        for r in ranges.iter_mut() {
            for (wi, f) in feet.iter().enumerate() {
                let st = if r.0 { &f.upper } else { &f.lower };
                let (f0, f1) = (
                    st.iter().copied().fold(f64::INFINITY, f64::min),
                    st.iter().copied().fold(f64::NEG_INFINITY, f64::max),
                );
                let on_cap = {
                    let d = if r.0 { f.d_upper } else { f.d_lower };
                    d > d_skin
                        && a.caps[k].from * chord <= a.webs[wi].at * chord
                        && a.webs[wi].at * chord <= a.caps[k].to * chord
                };
                for edge in [1, 2] {
                    let e = if edge == 1 { r.1 } else { r.2 };
                    if e > f0 && e < f1 {
                        let new = if on_cap == (edge == 1) { f0 } else { f1 };
                        let x = |s: f64| c.at(s, 0.0)[0] / chord;
                        notes.push(format!(
                            "spar cap {} ({} surface): edge moved from x/c = {:.4} to {:.4} to {} web {}'s foot",
                            k + 1,
                            if r.0 { "upper" } else { "lower" },
                            x(e),
                            x(new),
                            if on_cap { "cover" } else { "clear" },
                            wi + 1
                        ));
                        if edge == 1 {
                            r.1 = new;
                        } else {
                            r.2 = new;
                        }
                    }
                }
            }
        }
    }
    // Corner stations of the skin band.
    let (band_start, band_end) = match cut {
        Some((su, sl)) => (su, sl),
        None => (0.0, c.len()),
    };
    let mut keys: Vec<(f64, bool)> = vec![(band_start, false), (band_end, false)];
    if cut.is_none() && c.blunt {
        keys.push((c.surface_end(), false));
    }
    keys.push((c.s_le(), false));
    for r in cap_ranges.iter().flatten() {
        keys.push((r.1, false));
        keys.push((r.2, false));
    }
    for f in &feet {
        for &s in f.upper.iter().chain(&f.lower) {
            keys.push((s, true));
        }
    }
    keys.retain(|k| k.0 >= band_start - 1e-12 && k.0 <= band_end + 1e-12);
    keys.sort_by(|a, b| a.0.total_cmp(&b.0));
    let tol_s = 1e-9 * c.len();
    let mut merged: Vec<(f64, bool)> = Vec::new();
    for k in keys {
        match merged.last_mut() {
            Some(l) if (k.0 - l.0).abs() <= tol_s => l.1 |= k.1,
            _ => merged.push(k),
        }
    }
    let band_len = band_end - band_start;
    let target = band_len / a.elements_around.max(8) as f64;
    let mut corners = vec![merged[0].0];
    for w in merged.windows(2) {
        let (s0, s1) = (w[0].0, w[1].0);
        let in_foot = w[0].1
            && w[1].1
            && feet.iter().any(|f| {
                [&f.upper, &f.lower].iter().any(|st| {
                    st.windows(2).any(|q| {
                        let (lo, hi) = (q[0].min(q[1]), q[0].max(q[1]));
                        (lo - s0).abs() <= tol_s && (hi - s1).abs() <= tol_s
                    })
                })
            });
        let n = if in_foot {
            1
        } else {
            (((s1 - s0) / target).round() as usize).max(1)
        };
        for i in 1..=n {
            corners.push(s0 + (s1 - s0) * i as f64 / n as f64);
        }
    }
    let fine = |corners: &[f64]| -> Vec<f64> {
        let mut f = vec![corners[0]];
        for w in corners.windows(2) {
            if p == 2 {
                f.push(0.5 * (w[0] + w[1]));
            }
            f.push(w[1]);
        }
        f
    };
    let skin_stations = fine(&corners);
    let mut builder = MeshBuilder::new(tolerance(chord));
    let attr_of = |ply: &Ply, s: f64| ElementAttr {
        material: ply.material,
        ply_angle: ply.angle,
        wall_angle: c.wall_angle(s),
    };
    let band_patch = |b: &mut MeshBuilder, band: &Band| {
        let n_cells = (band.stations.len() - 1) / p;
        b.patch(
            kind,
            n_cells,
            band.rows.len(),
            |i, j| c.at(band.stations[i], band.depth[j]),
            |ci, cj| {
                let s_mid = 0.5 * (band.stations[ci * p] + band.stations[(ci + 1) * p]);
                attr_of(&band.plies[band.rows[cj]], s_mid)
            },
        );
    };
    let (skin_depth, skin_rows) = layup_grid(&a.skin, per, p);
    band_patch(
        &mut builder,
        &Band {
            stations: skin_stations.clone(),
            depth: skin_depth.clone(),
            rows: skin_rows.clone(),
            plies: a.skin.clone(),
        },
    );
    // Caps.
    for (k, ranges) in cap_ranges.iter().enumerate() {
        for r in ranges {
            let i0 = corners.iter().position(|&s| (s - r.1).abs() <= tol_s);
            let i1 = corners.iter().position(|&s| (s - r.2).abs() <= tol_s);
            let (Some(i0), Some(i1)) = (i0, i1) else {
                return Err(AirfoilError::CapRange {
                    cap: k,
                    reason: "its edges are outside the hollow part of the airfoil".into(),
                });
            };
            let (cd, crows) = layup_grid(&a.caps[k].plies, per, p);
            band_patch(
                &mut builder,
                &Band {
                    stations: fine(&corners[i0..=i1]),
                    depth: cd.iter().map(|d| d + d_skin).collect(),
                    rows: crows,
                    plies: a.caps[k].plies.clone(),
                },
            );
        }
    }
    // Webs.
    for (w, f) in a.webs.iter().zip(&feet) {
        // Columns from the leading-edge side (both foot lists run with x increasing).
        let up: Vec<f64> = fine(&f.upper);
        let lo: Vec<f64> = fine(&f.lower);
        let tops: Vec<[f64; 2]> = up.iter().map(|&s| c.at(s, f.d_upper)).collect();
        let bots: Vec<[f64; 2]> = lo.iter().map(|&s| c.at(s, f.d_lower)).collect();
        let height = tops[0][1] - bots[0][1];
        let nh = if w.elements > 0 {
            w.elements
        } else {
            ((height / target).round() as usize).max(2)
        };
        let (_, wrows) = layup_grid(&w.plies, per, 1);
        let nhp = (nh * p) as f64;
        builder.patch(
            kind,
            wrows.len(),
            nh,
            |i, j| {
                let v = j as f64 / nhp;
                [
                    bots[i][0] + v * (tops[i][0] - bots[i][0]),
                    bots[i][1] + v * (tops[i][1] - bots[i][1]),
                ]
            },
            |ci, _| {
                let ply = &w.plies[wrows[ci]];
                let (b, t) = (bots[ci * p], tops[ci * p]);
                ElementAttr {
                    material: ply.material,
                    ply_angle: ply.angle,
                    wall_angle: (t[1] - b[1]).atan2(t[0] - b[0]),
                }
            },
        );
    }
    // Solid trailing edge.
    if let Some((su, sl)) = cut {
        let s_end_lower = c.surface_end();
        let n_u = ((su / target).round() as usize).max(1);
        let n_l = (((s_end_lower - sl) / target).round() as usize).max(1);
        let nf = n_u.max(n_l);
        let up_corners: Vec<f64> = (0..=nf)
            .map(|i| su * (1.0 - i as f64 / nf as f64))
            .collect();
        let lo_corners: Vec<f64> = (0..=nf)
            .map(|i| sl + (s_end_lower - sl) * i as f64 / nf as f64)
            .collect();
        let (up_s, lo_s) = (fine(&up_corners), fine(&lo_corners));
        // Rows: upper skin (outer → inner), one fill row, lower skin (inner → outer).
        let mut left: Vec<[f64; 2]> = skin_depth.iter().map(|&d| c.at(su, d)).collect();
        let inner_u = *left.last().expect("rows");
        let inner_l = c.at(sl, d_skin);
        if p == 2 {
            left.push([
                0.5 * (inner_u[0] + inner_l[0]),
                0.5 * (inner_u[1] + inner_l[1]),
            ]);
        }
        left.extend(skin_depth.iter().rev().map(|&d| c.at(sl, d)));
        let mut frac = vec![0.0];
        for w2 in left.windows(2) {
            let l = (w2[1][0] - w2[0][0]).hypot(w2[1][1] - w2[0][1]);
            frac.push(frac.last().expect("frac") + l);
        }
        let total = *frac.last().expect("frac");
        for f in &mut frac {
            *f /= total;
        }
        let n_skin_rows = skin_rows.len();
        let n_rows = 2 * n_skin_rows + 1;
        let (fill_mat, fill_angle) = a.fill.unwrap_or_else(|| {
            let last = a.skin.last().expect("skin");
            (last.material, last.angle)
        });
        let row_attr = |ci: usize, cj: usize| -> ElementAttr {
            let s_up = 0.5 * (up_s[ci * p] + up_s[((ci + 1) * p).min(up_s.len() - 1)]);
            let s_lo = 0.5 * (lo_s[ci * p] + lo_s[((ci + 1) * p).min(lo_s.len() - 1)]);
            if cj < n_skin_rows {
                attr_of(&a.skin[skin_rows[cj]], s_up)
            } else if cj == n_skin_rows {
                ElementAttr {
                    material: fill_mat,
                    ply_angle: fill_angle,
                    wall_angle: c.wall_angle(s_up),
                }
            } else {
                attr_of(&a.skin[skin_rows[n_rows - 1 - cj]], s_lo)
            }
        };
        let node = |i: usize, j: usize| -> [f64; 2] {
            if i == 0 {
                return left[j];
            }
            let u = c.at(up_s[i], 0.0);
            let l = c.at(lo_s[i], 0.0);
            [
                u[0] + frac[j] * (l[0] - u[0]),
                u[1] + frac[j] * (l[1] - u[1]),
            ]
        };
        let sharp = !c.blunt;
        let quad_cols = if sharp { nf - 1 } else { nf };
        if quad_cols > 0 {
            builder.patch(kind, quad_cols, n_rows, node, row_attr);
        }
        if sharp {
            // The last column ends in the trailing-edge point: a fan of triangles.
            let tip = c.at(0.0, 0.0);
            let i0 = (nf - 1) * p;
            let tri = if p == 2 {
                ElementKind::Tri6
            } else {
                ElementKind::Tri3
            };
            for cj in 0..n_rows {
                let (j0, j1) = (cj * p, (cj + 1) * p);
                let (a0, a1) = (node(i0, j0), node(i0, j1));
                let att = row_attr(nf - 1, cj);
                if p == 2 {
                    let mid = |q: [f64; 2]| [0.5 * (q[0] + tip[0]), 0.5 * (q[1] + tip[1])];
                    builder.element(tri, &[a0, a1, tip, node(i0, j0 + 1), mid(a1), mid(a0)], att);
                } else {
                    builder.element(tri, &[a0, a1, tip], att);
                }
            }
        }
    }
    let mut mesh = builder.finish();
    // Fold check here, to report it in airfoil terms.
    let mut probe = mesh.clone();
    if let Err(bad) = probe.check() {
        let e = &mesh.elements[bad[0].element];
        let pts: Vec<[f64; 2]> = e.node_list().iter().map(|&k| mesh.nodes[k]).collect();
        let cy = pts.iter().map(|q| q[0]).sum::<f64>() / pts.len() as f64;
        let cz = pts.iter().map(|q| q[1]).sum::<f64>() / pts.len() as f64;
        let up = cz >= 0.0;
        return Err(AirfoilError::Folded {
            near: [cy / chord, cz / chord],
            depth: depth_at(up, cy),
        });
    }
    mesh.transform([-a.reference[0] * chord, -a.reference[1] * chord], 0.0);
    Ok((mesh, notes))
}
