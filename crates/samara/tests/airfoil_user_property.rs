//! Issue #15: airfoil tables interpolated on a user property (AeroDyn's AFTabMod = 3), a
//! line's `user_property = <number | signal>`: linear blending between the tables around
//! the value, c = (1 − t) c_k + t c_{k+1}, t = (u − u_k)/(u_{k+1} − u_k). Reference: the
//! tables themselves (rows at table knots) and that formula by hand; a signal (a flap
//! command) drives it end to end; the tangents (∂r/∂u through the signal) are in the
//! generic check (model/components/aero.rs, `aero_user_property`).

use samara::elements::aero::Airfoil;
use samara::model::Model;
use std::path::{Path, PathBuf};

use crate::common::airfoil_run;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// DU21-A17's rows with a flap's effect at UserProp 10: cl + 0.3, cm − 0.05 (one Re).
/// Without `with_user_prop` the second table has no UserProp line.
fn flap_file(second_user_prop: Option<f64>) -> String {
    let text = std::fs::read_to_string(repo().join("reference/nrel5mw/aero/Airfoils/DU21_A17.dat"))
        .unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let k = lines
        .iter()
        .position(|l| l.split_whitespace().nth(1) == Some("NumAlf"))
        .unwrap();
    let n: usize = lines[k].split_whitespace().next().unwrap().parse().unwrap();
    let rows: Vec<[f64; 4]> = lines[k + 1..]
        .iter()
        .filter(|l| !l.trim().is_empty() && !l.trim().starts_with('!'))
        .take(n)
        .map(|l| {
            let v: Vec<f64> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
            [v[0], v[1], v[2], v[3]]
        })
        .collect();
    let mut s = String::from("! DU21 with a flap\n          2   NumTabs\n");
    for (u, dcl, dcm) in [(Some(0.0), 0.0, 0.0), (second_user_prop, 0.3, -0.05)] {
        s += "       0.75   Re\n";
        if let Some(u) = u {
            s += &format!("{u}   UserProp\n");
        }
        s += &format!("False   InclUAdata\n{n}   NumAlf\n");
        for r in &rows {
            s += &format!("{} {} {} {}\n", r[0], r[1] + dcl, r[2], r[3] + dcm);
        }
    }
    s
}

/// A wing section held fixed in 20 m/s at 4° (a table knot), with `extra` line keys.
fn wing(dir: &Path, extra: &str, signals: &str) -> String {
    let a = 4f64.to_radians();
    format!(
        r#"[model]
name = "flap"
[[nodes]]
name = "wing"
position = [0.0, 0.0, 0.0]
[[bodies]]
name = "wing"
node = "wing"
mass = 1.0
inertia = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
[[joints]]
name = "fix"
type = "prescribed"
node_a = "ground"
node_b = "wing"
{signals}
[[aero_lines]]
name = "wing"
node = "wing"
root = [0.0, -0.5, 0.0]
tip = [0.0, 0.5, 0.0]
chord_direction = [1.0, 0.0, 0.0]
normal_direction = [0.0, 0.0, 1.0]
wind = {{ speed = 20.0, direction = [{}, 0.0, {}] }}
{extra}
[[aero_lines.stations]]
span = 0.5
chord = 1.0
airfoil = "flap.dat"
[[analyses]]
name = "run"
type = "dynamic"
t_end = 1.0
step = 0.1
"#,
        a.cos(),
        a.sin()
    )
    .replace("flap.dat", dir.join("flap.dat").to_str().unwrap())
}

#[test]
fn tables_blend_linearly_in_the_user_property() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("flap.dat"), flap_file(Some(10.0))).unwrap();
    let af = Airfoil::parse(&flap_file(Some(10.0)), false).unwrap();
    assert_eq!(af.user_properties(), vec![0.0, 10.0]);
    // Same Re in both tables: read as user-property tables; `reynolds = "first"` reads
    // the first.
    assert!(!af.sorted_by_reynolds());
    let by_u = af.by_user_property().unwrap();
    let alpha = 4f64.to_radians();
    let (c1, c2) = (af.table(0).eval(alpha), af.table(1).eval(alpha));
    // The tables at the knot: the file's rows (DU21 at 4°: cl 0.996, cm −0.1398).
    assert!((c1.cl - 0.996).abs() < 1e-12 && (c2.cl - 1.296).abs() < 1e-12);
    for u in [0.0, 2.5, 5.0, 7.5, 10.0] {
        let (c, d) = by_u.eval_re(alpha, u);
        let t = u / 10.0;
        assert!(
            (c.cl - ((1.0 - t) * c1.cl + t * c2.cl)).abs() < 1e-12,
            "u = {u}"
        );
        assert!(
            (c.cm - ((1.0 - t) * c1.cm + t * c2.cm)).abs() < 1e-12,
            "u = {u}"
        );
        if u > 0.0 && u < 10.0 {
            // ∂c/∂u = (c₂ − c₁)/(u₂ − u₁).
            assert!((d[0] - 0.03).abs() < 1e-12 && (d[2] + 0.005).abs() < 1e-12);
        }
    }
    // A line with a constant user property: its cl is the blend (quasi-steady, and with
    // Øye's stall at a steady state), and differs from the first table's.
    for stall in ["", "dynamic_stall = \"oye\"\n"] {
        let text = wing(dir.path(), &format!("{stall}user_property = 2.5"), "");
        let (_, outs, names, _) = airfoil_run::run(&text, dir.path());
        let col = |n: &str| names.iter().position(|x| x == n).unwrap();
        let last = outs.last().unwrap();
        let want = 0.75 * c1.cl + 0.25 * c2.cl;
        println!(
            "{stall:?}: cl {:.6}, blend {want:.6}",
            last[col("wing.0.cl")]
        );
        assert!((last[col("wing.0.cl")] - want).abs() < 1e-9);
        assert_eq!(last[col("wing.0.user_property")], 2.5);
    }
}

#[test]
fn a_signal_drives_the_user_property_end_to_end() {
    // A flap command ramping 0 → 10 over 1 s ([[signals]]): at every frame the section's
    // cl is the blend at the command's value (quasi-steady: exact to rounding, 1e-12).
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("flap.dat"), flap_file(Some(10.0))).unwrap();
    let signals = "[[signals]]\nname = \"flap\"\nfunction = { type = \"ramp\", start = 0.0, end = 1.0, from = 0.0, to = 10.0 }";
    let text = wing(dir.path(), "user_property = \"flap\"", signals);
    let (t, outs, names, _) = airfoil_run::run(&text, dir.path());
    let col = |n: &str| names.iter().position(|x| x == n).unwrap();
    let af = Airfoil::parse(&flap_file(Some(10.0)), false).unwrap();
    let alpha = 4f64.to_radians();
    let (c1, c2) = (af.table(0).eval(alpha), af.table(1).eval(alpha));
    for (ti, o) in t.iter().zip(&outs) {
        let u = 10.0 * ti.clamp(0.0, 1.0);
        let want = c1.cl + (c2.cl - c1.cl) * u / 10.0;
        assert!(
            (o[col("wing.0.user_property")] - u).abs() < 1e-12,
            "t = {ti}"
        );
        assert!(
            (o[col("wing.0.cl")] - want).abs() < 1e-12,
            "t = {ti}: {} vs {want}",
            o[col("wing.0.cl")]
        );
    }
    assert!(t.len() > 5);
}

fn model_error(dir: &Path, text: &str) -> String {
    match Model::from_toml_str(text, dir.join("bad.toml")) {
        Ok(_) => panic!("accepted"),
        Err(e) => e.render_plain(),
    }
}

#[test]
fn bad_user_property_input_is_a_located_error() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("flap.dat"), flap_file(Some(10.0))).unwrap();
    let at = |text: &str| {
        let l = text
            .lines()
            .position(|l| l.starts_with("user_property"))
            .unwrap()
            + 1;
        format!("bad.toml:{l}:")
    };
    // Outside the tables' range.
    let bad = wing(d, "user_property = 12.0", "");
    let e = model_error(d, &bad);
    println!("{e}");
    assert!(
        e.contains("outside") && e.contains("[0, 10]") && e.contains(&at(&bad)),
        "{e}"
    );
    // An unknown signal (with a suggestion).
    let bad = wing(
        d,
        "user_property = \"flp\"",
        "[[signals]]\nname = \"flap\"\nfunction = { type = \"constant\", value = 1.0 }",
    );
    let e = model_error(d, &bad);
    println!("{e}");
    assert!(
        e.contains("unknown signal 'flp'") && e.contains("flap") && e.contains(&at(&bad)),
        "{e}"
    );
    // With Re interpolation.
    let bad = wing(d, "user_property = 5.0\nreynolds = \"interpolate\"", "");
    let e = model_error(d, &bad);
    assert!(e.contains("one parameter") && e.contains(&at(&bad)), "{e}");
    // Re interpolation of tables told apart by UserProp only.
    let bad = wing(d, "reynolds = \"interpolate\"", "");
    let e = model_error(d, &bad);
    assert!(e.contains("not sorted by increasing Reynolds"), "{e}");
    // A table without UserProp: its tables have equal Re, so the file is refused at the
    // second table's Re line; with increasing Re and no UserProp, at `user_property`.
    std::fs::write(d.join("flap.dat"), flap_file(None)).unwrap();
    let bad = wing(d, "user_property = 5.0", "");
    let e = model_error(d, &bad);
    println!("{e}");
    assert!(
        e.contains("Reynolds number") && e.contains("UserProp"),
        "{e}"
    );
    let two_re = flap_file(None).replacen("0.75   Re", "0.5   Re", 1);
    std::fs::write(d.join("flap.dat"), two_re).unwrap();
    let bad = wing(d, "user_property = 5.0", "");
    let e = model_error(d, &bad);
    println!("{e}");
    assert!(
        e.contains("table 2 has no `UserProp`") && e.contains(&at(&bad)),
        "{e}"
    );
    // A single-table airfoil.
    std::fs::copy(
        repo().join("reference/nrel5mw/aero/Airfoils/DU21_A17.dat"),
        d.join("flap.dat"),
    )
    .unwrap();
    let bad = wing(d, "user_property = 0.0", "");
    let e = model_error(d, &bad);
    assert!(e.contains("single table") && e.contains(&at(&bad)), "{e}");
}

#[test]
fn a_signal_beyond_the_user_property_range_reads_the_end_table() {
    // The flap command ramps 0 → 20 over 1 s, past the tables' UserProp range [0, 10]:
    // beyond 10 the last table is read (clamped, as the tables' end), c_l = table 2's.
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("flap.dat"), flap_file(Some(10.0))).unwrap();
    let signals = "[[signals]]\nname = \"flap\"\nfunction = { type = \"ramp\", start = 0.0, end = 1.0, from = 0.0, to = 20.0 }";
    let text = wing(dir.path(), "user_property = \"flap\"", signals);
    let (t, outs, names, _) = airfoil_run::run(&text, dir.path());
    let col = |n: &str| names.iter().position(|x| x == n).unwrap();
    let af = Airfoil::parse(&flap_file(Some(10.0)), false).unwrap();
    let alpha = 4f64.to_radians();
    let (c1, c2) = (af.table(0).eval(alpha), af.table(1).eval(alpha));
    for (ti, o) in t.iter().zip(&outs) {
        let u = (20.0 * ti).min(10.0);
        let want = c1.cl + (c2.cl - c1.cl) * u / 10.0;
        assert!((o[col("wing.0.cl")] - want).abs() < 1e-12, "t = {ti}");
    }
}
