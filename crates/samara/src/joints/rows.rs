//! The rows of each joint type (seed Table I, extended): which components are constrained,
//! which are joint coordinates, and the equations that define them.
//!
//! Components are indexed `0..6` = d1, d2, d3, θ1, θ2, θ3. Locked rotations are
//! `R_pq = 0` for pairs of axes that stay independent over the joint's free motion: with
//! θ3 free, `R₃₂ = R₃₁ = 0` (e₃ᴬ normal to e₁ᴮ and e₂ᴮ); with all rotations locked, the
//! cyclic `R₂₃, R₃₁, R₁₂` of eq. 12b. Free rotations:
//! - one free rotation about e₃ᴬ (revolute, screw, cylindrical, planar):
//!   `cos ν R₂₁ − sin ν R₁₁ = sin(θ3 − ν)` with `R_pq = e_pᴬ·e_qᴮ` (1-based here);
//! - universal: θ1 about e₁ᴬ from `R₃₂, R₂₂`, θ2 about e₂ᴮ from `R₁₃, R₁₁`, and the
//!   constraint `R₁₂ = 0` (the cross arms stay orthogonal); exact for any angles;
//! - three free rotations (spherical, point_on_line, point_on_plane, prescribed): Bryant
//!   angles, `Aᵀ B = R_x(θ1) R_y(θ2) R_z(θ3)`, defined by `c₂ sin(θ1 − ν1)`,
//!   `sin θ2 − sin ν2`, `c₂ sin(θ3 − ν3)`; singular at θ2 = ±90° (gimbal lock), so these
//!   coordinates exist only when something is attached to a rotation of the joint.

use super::JointType;
use super::building_blocks::{AngleRow, Trig};
use crate::core::RowRole;
use crate::math::TimeFunction;

/// Names of the six relative components, in order.
pub const COMPONENT_NAMES: [&str; 6] = ["d1", "d2", "d3", "theta1", "theta2", "theta3"];

/// One scalar equation of a joint.
#[derive(Clone, Debug, PartialEq)]
pub enum Row {
    /// `e_iᴬ·(uᴮ − uᴬ) − s ν_c = 0` (eq. 12a); `coord = Some((c, s))`.
    Displacement {
        axis: usize,
        coord: Option<(usize, f64)>,
    },
    /// Generalized eq. 12b, defining coordinate `coord` if given.
    Angle { row: AngleRow, coord: Option<usize> },
    /// `ν_c − f(t) = 0`.
    Drive {
        coord: usize,
        function: TimeFunction,
    },
    /// Servo `ν_c − s = 0`, `s` the joint's input signal `input`: the joint evaluates
    /// `ν_c` (B = e_ν); the system subtracts `s` and adds `−∂s/∂x` to the row
    /// ([`crate::core::ServoRow`]).
    Servo { coord: usize, input: usize },
}

impl Row {
    pub fn role(&self) -> RowRole {
        match self {
            Row::Displacement { coord: None, .. } | Row::Angle { coord: None, .. } => {
                RowRole::Constraint
            }
            Row::Drive { .. } | Row::Servo { .. } => RowRole::Drive,
            _ => RowRole::Definition,
        }
    }
}

/// Whether a component of a joint type is free (can carry a coordinate).
pub fn is_free(kind: JointType, component: usize) -> bool {
    use JointType::*;
    let free: [bool; 6] = match kind {
        Fixed => [false; 6],
        Revolute | Screw => [false, false, false, false, false, true],
        Prismatic => [false, false, true, false, false, false],
        Cylindrical => [false, false, true, false, false, true],
        Planar => [true, true, false, false, false, true],
        Spherical => [false, false, false, true, true, true],
        Universal => [false, false, false, true, true, false],
        PointOnLine => [false, false, true, true, true, true],
        PointOnPlane => [true, true, false, true, true, true],
        Prescribed => [true; 6],
    };
    free[component]
}

/// Whether a component can carry a coordinate and its elements (free, and not the
/// screw's d3, which is tied to θ3).
pub fn has_coordinate(kind: JointType, component: usize) -> bool {
    is_free(kind, component) && !(kind == JointType::Screw && component == 2)
}

/// Whether a joint type leaves all three rotations free (Bryant coordinates on demand).
pub fn has_free_rotation_triple(kind: JointType) -> bool {
    (3..6).all(|c| is_free(kind, c))
}

/// Rows and coordinates of a joint. `rotations_wanted`: create the Bryant coordinates of a
/// joint with three free rotations. `drives[c]`: the drive of component c, if any.
/// Returns the rows (constraints, definitions, drives in that order) and, per coordinate,
/// its component.
pub fn rows_of(
    kind: JointType,
    pitch: f64,
    rotations_wanted: bool,
    drives: &[Option<TimeFunction>; 6],
) -> (Vec<Row>, Vec<usize>) {
    let mut comps: Vec<usize> = (0..6).filter(|&c| is_free(kind, c)).collect();
    if kind == JointType::Screw {
        comps = vec![5];
    }
    let triple = has_free_rotation_triple(kind);
    if triple && !rotations_wanted && kind != JointType::Prescribed {
        comps.retain(|&c| c < 3);
    }
    let coord_of = |c: usize| comps.iter().position(|&x| x == c);
    let mut rows = Vec::new();
    // Constrained components.
    for i in 0..3 {
        if !(is_free(kind, i) || kind == JointType::Screw && i == 2) {
            rows.push(Row::Displacement {
                axis: i,
                coord: None,
            });
        }
    }
    let spin_free = is_free(kind, 5) && !is_free(kind, 3) && !is_free(kind, 4);
    for i in 0..3 {
        if !is_free(kind, 3 + i) {
            let row = if spin_free {
                // θ3 free: keep e₃ᴬ normal to e₁ᴮ and e₂ᴮ. These stay independent at any
                // θ3, where R₂₃ and R₃₁ would both turn about e₁ᴬ at θ3 = 90°.
                AngleRow::direction_cosine(2, 1 - i)
            } else {
                AngleRow::locked(i)
            };
            rows.push(Row::Angle { row, coord: None });
        }
    }
    // Definitions.
    for (c, &comp) in comps.iter().enumerate() {
        let row = match comp {
            0..=2 => Row::Displacement {
                axis: comp,
                coord: Some((c, 1.0)),
            },
            _ => Row::Angle {
                row: angle_definition(kind, comp - 3),
                coord: Some(c),
            },
        };
        rows.push(row);
    }
    if kind == JointType::Screw {
        rows.push(Row::Displacement {
            axis: 2,
            coord: coord_of(5).map(|c| (c, pitch)),
        });
    }
    // Drives.
    for (c, &comp) in comps.iter().enumerate() {
        let f = match (&drives[comp], kind) {
            (Some(f), _) => f.clone(),
            (None, JointType::Prescribed) => TimeFunction::Constant(0.0),
            (None, _) => continue,
        };
        rows.push(Row::Drive {
            coord: c,
            function: f,
        });
    }
    (rows, comps)
}

/// The equation defining rotation θ_{i+1} of a joint type.
fn angle_definition(kind: JointType, i: usize) -> AngleRow {
    use JointType::*;
    match kind {
        Universal if i == 1 => AngleRow {
            terms: [(Trig::Cos(1.0), 0, 2), (Trig::Sin(-1.0), 0, 0)],
            constant: Trig::Zero,
        },
        Universal => AngleRow::about_a(0),
        _ if has_free_rotation_triple(kind) => match i {
            0 => AngleRow {
                terms: [(Trig::Cos(-1.0), 1, 2), (Trig::Sin(-1.0), 2, 2)],
                constant: Trig::Zero,
            },
            1 => AngleRow {
                terms: [(Trig::One(1.0), 0, 2), (Trig::Zero, 0, 0)],
                constant: Trig::Sin(-1.0),
            },
            _ => AngleRow {
                terms: [(Trig::Cos(-1.0), 0, 1), (Trig::Sin(-1.0), 0, 0)],
                constant: Trig::Zero,
            },
        },
        _ => AngleRow::about_a(i),
    }
}

/// Coordinate value of component `comp` from the relative rotation `Aᵀ B` (entries
/// `r[p][q] = e_pᴬ·e_qᴮ`) and the relative displacement `d` in frame A.
pub fn measure(kind: JointType, comp: usize, r: &[[f64; 3]; 3], d: &[f64; 3]) -> f64 {
    use JointType::*;
    if comp < 3 {
        return d[comp];
    }
    let i = comp - 3;
    match kind {
        Universal if i == 1 => r[0][2].atan2(r[0][0]),
        Universal => r[2][1].atan2(r[1][1]),
        _ if has_free_rotation_triple(kind) => match i {
            0 => (-r[1][2]).atan2(r[2][2]),
            1 => r[0][2].clamp(-1.0, 1.0).asin(),
            _ => (-r[0][1]).atan2(r[0][0]),
        },
        _ => {
            let (j, k) = ((i + 1) % 3, (i + 2) % 3);
            r[k][j].atan2(r[j][j])
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Table I: the number of enforced equations is 6 minus the free components, plus
    /// the definitions and drives of the coordinates.
    #[test]
    fn row_counts_follow_table_one() {
        let none: [Option<TimeFunction>; 6] = Default::default();
        let cases = [
            (JointType::Fixed, 6, 0),
            (JointType::Revolute, 5, 1),
            (JointType::Prismatic, 5, 1),
            (JointType::Screw, 5, 1),
            (JointType::Cylindrical, 4, 2),
            (JointType::Planar, 3, 3),
            (JointType::Spherical, 3, 0),
            (JointType::Universal, 4, 2),
            (JointType::PointOnLine, 2, 1),
            (JointType::PointOnPlane, 1, 2),
        ];
        for (kind, constrained, coords) in cases {
            let (rows, comps) = rows_of(kind, 0.1, false, &none);
            let c = rows
                .iter()
                .filter(|r| r.role() == RowRole::Constraint)
                .count();
            // The screw's d3 = p θ3 row counts as a constraint of the translation.
            let c = if kind == JointType::Screw { c + 1 } else { c };
            assert_eq!(c, constrained, "{kind:?}");
            assert_eq!(comps.len(), coords, "{kind:?}");
        }
        let (rows, comps) = rows_of(JointType::Prescribed, 0.0, false, &none);
        assert_eq!(comps.len(), 6);
        assert_eq!(rows.len(), 12);
        let (_, comps) = rows_of(JointType::Spherical, 0.0, true, &none);
        assert_eq!(comps, vec![3, 4, 5]);
    }
}
