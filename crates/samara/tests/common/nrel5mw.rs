//! The NREL 5-MW rotor models shared by tests/aerodynamics.rs and the curve example
//! (crates/samara/examples/nrel5mw_curves.rs): the rigid example at an operating point, the
//! flexible rotor of examples/rotor/nrel5mw_flexible.toml generated at any wind, rpm and
//! pitch, its steady state by spinning statics, and the BeamDyn files stiffened in torsion.
#![allow(dead_code)]

use nalgebra::Vector3;
use samara::core::{Element, ElementInput, EvalContext, LocalTerms, Need, NodeState};
use samara::model::Model;
use samara::model::components::{Build, build_all, initial_nodes};
use std::path::{Path, PathBuf};

pub fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

pub fn reference() -> PathBuf {
    repo().join("reference/nrel5mw")
}

pub fn ctx(t: f64) -> EvalContext {
    EvalContext {
        time: t,
        gravity: Vector3::zeros(),
        load_factor: 1.0,
    }
}

/// Sum of the loads the elements put on `node` (force and moment in node components).
pub fn loads_on(
    elements: &[Box<dyn Element>],
    nodes: &[NodeState],
    node: usize,
) -> (Vector3<f64>, Vector3<f64>) {
    let (mut f, mut m) = (Vector3::zeros(), Vector3::zeros());
    for e in elements {
        let mut out = LocalTerms::for_element(e.as_ref());
        e.evaluate(
            &ctx(0.0),
            &ElementInput::nodes(nodes),
            Need::Residual,
            &mut out,
        );
        for (k, &n) in e.nodes().iter().enumerate() {
            if n == node {
                for i in 0..3 {
                    f[i] -= out.r[6 * k + i];
                    m[i] -= out.r[6 * k + 3 + i];
                }
            }
        }
    }
    (f, m)
}

/// The example's rotor at (wind, rpm, pitch): aerodynamic power [kW], thrust [kN].
pub fn nrel5mw_at(model: &Model, wind: f64, rpm: f64, pitch_deg: f64) -> (f64, f64) {
    let mut m = model.clone();
    let omega = rpm * std::f64::consts::PI / 30.0;
    m.nodes[0].angular_velocity = Vector3::new(omega, 0.0, 0.0);
    for l in &mut m.aero_lines {
        l.wind.speed = wind;
        l.pitch = pitch_deg.to_radians();
    }
    let initial = initial_nodes(&m);
    let mut parts = Build::new(&initial);
    build_all(&m, &mut parts);
    let (f, mo) = loads_on(&parts.elements, &initial, 0);
    (mo.x * omega / 1e3, f.x / 1e3)
}

/// The flexible NREL 5-MW rotor of `examples/rotor/nrel5mw_flexible.toml` at (wind, rpm,
/// pitch), by the same rules: three BeamDyn blades (`elements` of order `order`) clamped to
/// a driven hub, pitched with their aerodynamic sections, and `analysis` appended.
pub fn nrel5mw_flexible(
    wind: f64,
    rpm: f64,
    pitch_deg: f64,
    (order, elements): (usize, usize),
    bd: &Path,
    analysis: &str,
) -> String {
    let om = rpm * std::f64::consts::PI / 30.0;
    let rs = reference();
    let ad = rs.join("aero/NRELOffshrBsline5MW_Onshore_AeroDyn15.dat");
    let v = |x: Vector3<f64>| format!("[{:.12}, {:.12}, {:.12}]", x.x, x.y, x.z);
    let mut s = format!(
        r#"[model]
name = "nrel5mw_flexible"
[[nodes]]
name = "hub"
position = [0.0, 0.0, 90.0]
angular_velocity = [{om}, 0.0, 0.0]
[[bodies]]
name = "hub"
node = "hub"
mass = 56780.0
inertia = [[5141472.0, 0.0, 0.0], [0.0, 2600000.0, 0.0], [0.0, 0.0, 2600000.0]]
[[joints]]
name = "shaft"
type = "revolute"
node_a = "ground"
node_b = "hub"
axis = [1.0, 0.0, 0.0]
[joints.theta3]
drive = {{ type = "polynomial", coefficients = [0.0, {om}] }}
"#
    );
    let (cp, sp) = (pitch_deg.to_radians().cos(), pitch_deg.to_radians().sin());
    for k in 0..3 {
        let psi = 2.0 * std::f64::consts::PI * k as f64 / 3.0;
        let r = nalgebra::Rotation3::from_axis_angle(&Vector3::x_axis(), psi);
        let (xb, yb, zb) = (Vector3::x(), r * Vector3::y(), r * Vector3::z());
        // Pitch toward feather: BeamDyn's axes turned by −pitch about the blade axis
        // (the sense of BeamDyn's twist), the aerodynamic sections by +pitch (AeroDyn's).
        let (xp, yp) = (cp * xb - sp * yb, sp * xb + cp * yb);
        let root = Vector3::new(0.0, 0.0, 90.0) + 1.5 * zb;
        let n = k + 1;
        s += &format!(
            r#"[[beams]]
name = "blade{n}"
beamdyn = "{}"
order = {order}
elements = {elements}
root_position = {}
root_axes = [{}, {}, {}]
angular_velocity = [{om}, 0.0, 0.0]
rotation_centre = [0.0, 0.0, 90.0]
[[joints]]
name = "root{n}"
type = "fixed"
node_a = "hub"
node_b = "blade{n}.0"
[[aero_lines]]
name = "aero{n}"
beam = "blade{n}"
chord_direction = {}
normal_direction = [1.0, 0.0, 0.0]
pitch = {}
aerodyn = "{}"
wind = {{ speed = {wind}, direction = [1.0, 0.0, 0.0] }}
inflow = {{ type = "bem", centre = [0.0, 0.0, 90.0], axis = [1.0, 0.0, 0.0], blades = 3, hub_radius = 1.5, tip_radius = 63.0 }}
"#,
            bd.display(),
            v(root),
            v(xp),
            v(yp),
            v(zb),
            v(yb),
            pitch_deg.to_radians(),
            ad.display()
        );
    }
    s + analysis
}

/// The flexible rotor's steady state at (wind, rpm, pitch) by spinning statics: aerodynamic
/// power [kW] (Σ f·v + m·ω of the stations on the nodes), thrust [kN] (Σ f along the
/// shaft) and blade 1's tip deflection [m] (out of plane, downwind; in plane).
pub fn nrel5mw_flexible_at(bd: &Path, wind: f64, rpm: f64, pitch_deg: f64) -> (f64, f64, f64, f64) {
    nrel5mw_flexible_try(bd, wind, rpm, pitch_deg).unwrap_or_else(|e| panic!("{e}"))
}

/// [`nrel5mw_flexible_at`], with the solver's failure as an error.
pub fn nrel5mw_flexible_try(
    bd: &Path,
    wind: f64,
    rpm: f64,
    pitch_deg: f64,
) -> Result<(f64, f64, f64, f64), String> {
    let om = rpm * std::f64::consts::PI / 30.0;
    let analysis = format!(
        "[[analyses]]\nname = \"steady\"\ntype = \"static\"\nload_steps = 4\nrotation = {{ axis = [1.0, 0.0, 0.0], omega = {om}, centre = [0.0, 0.0, 90.0] }}\n"
    );
    let text = nrel5mw_flexible(wind, rpm, pitch_deg, (6, 2), bd, &analysis);
    let m = Model::from_toml_str(&text, repo().join("flex.toml"))
        .unwrap_or_else(|e| panic!("{}", e.render_plain()))
        .model;
    let sys = samara::system::System::new(&m);
    let mut h = samara::analysis::History::default();
    let s = samara::analysis::run_analysis(
        &sys,
        &m.analyses[0],
        sys.initial_state(),
        &mut h,
        &mut |_| {},
    )
    .unwrap();
    if let Some(f) = &s.failure {
        return Err(format!("{f:?}"));
    }
    let nodes = &s.final_state.nodes;
    let initial = initial_nodes(&m);
    let mut parts = Build::new(&initial);
    build_all(&m, &mut parts);
    let aero: Vec<Box<dyn Element>> = parts
        .elements
        .into_iter()
        .filter(|e| e.name().starts_with("aero"))
        .collect();
    assert_eq!(aero.len(), 57);
    let (mut power, mut thrust) = (0.0, 0.0);
    for n in 0..m.nodes.len() {
        let (f, mo) = loads_on(&aero, nodes, n);
        power += f.dot(&nodes[n].v) + mo.dot(&nodes[n].w);
        thrust += f.x;
    }
    let tip = m.node_index("blade1.12").unwrap();
    let d = nodes[tip].x - m.nodes[tip].position;
    Ok((power / 1e3, thrust / 1e3, d.x, d.y))
}

/// A copy of the 5-MW BeamDyn files in `dir` with the torsional stiffness (BeamDyn's
/// K66) times `factor`: the blade of ElastoDyn, which has no torsion degree of freedom.
pub fn stiff_in_torsion(dir: &Path, factor: f64) -> PathBuf {
    let src = reference().join("structure");
    let blade = std::fs::read_to_string(src.join("NRELOffshrBsline5MW_BeamDyn_Blade.dat")).unwrap();
    let lines: Vec<&str> = blade.lines().collect();
    let start = lines
        .iter()
        .position(|l| l.contains("DISTRIBUTED PROPERTIES"))
        .unwrap();
    let mut out: Vec<String> = lines[..=start].iter().map(|l| l.to_string()).collect();
    // Each station: η line, six stiffness rows (the sixth is torsion), blank, six mass rows.
    let mut row = 0usize;
    for l in &lines[start + 1..] {
        let v: Vec<&str> = l.split_whitespace().collect();
        if v.len() == 6 {
            row += 1;
            if row % 12 == 6 {
                let mut x: Vec<f64> = v.iter().map(|t| t.parse().unwrap()).collect();
                x[5] *= factor;
                out.push(
                    x.iter()
                        .map(|t| format!("{t:e}"))
                        .collect::<Vec<_>>()
                        .join(" "),
                );
                continue;
            }
        }
        out.push(l.to_string());
    }
    std::fs::write(
        dir.join("NRELOffshrBsline5MW_BeamDyn_Blade.dat"),
        out.join("\n"),
    )
    .unwrap();
    let p = dir.join("NRELOffshrBsline5MW_BeamDyn.dat");
    std::fs::copy(src.join("NRELOffshrBsline5MW_BeamDyn.dat"), &p).unwrap();
    p
}
