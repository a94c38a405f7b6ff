//! Issue #4: bad beam input is reported with file, line, column and a hint.

use samara::model::Model;

const BASE: &str = r#"[model]
name = "m"

[[beams]]
name = "b"
order = ORDER
points = POINTS
SECTIONS

[[joints]]
name = "c"
type = "fixed"
node_a = "ground"
node_b = "b.0"
"#;

const GOOD_SECTION: &str = "[[beams.sections]]\nstation = 0.0\nisotropic = { E = 1.0, G = 1.0, A = 1.0, I2 = 1.0, I3 = 1.0, J = 1.0, shear_factors = [1.0, 1.0] }";

fn check(order: &str, points: &str, sections: &str, dir: &std::path::Path) -> String {
    let text = BASE
        .replace("ORDER", order)
        .replace("POINTS", points)
        .replace("SECTIONS", sections);
    let path = dir.join("model.toml");
    std::fs::write(&path, &text).unwrap();
    match Model::from_file(&path) {
        Ok(_) => String::new(),
        Err(samara::Error::Model(e)) => e.render_plain(),
        Err(e) => e.to_string(),
    }
}

#[test]
fn bad_beam_inputs_have_located_diagnostics() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let two = "[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]";
    // The good model loads.
    assert_eq!(check("2", two, GOOD_SECTION, d), "");
    // p < 1.
    let msg = check("0", two, GOOD_SECTION, d);
    assert!(
        msg.contains("model.toml:6:9: error") && msg.contains("`order` must be between 1"),
        "{msg}"
    );
    // Too few key points.
    let msg = check("2", "[[0.0, 0.0, 0.0]]", GOOD_SECTION, d);
    assert!(
        msg.contains("model.toml:7:10: error")
            && msg.contains("at least 2 key points")
            && msg.contains("hint"),
        "{msg}"
    );
    // Non-symmetric stiffness.
    let bad = "[[beams.sections]]\nstation = 0.0\nstiffness = [[1.0,0.5,0.0,0.0,0.0,0.0],[0.0,1.0,0.0,0.0,0.0,0.0],[0.0,0.0,1.0,0.0,0.0,0.0],[0.0,0.0,0.0,1.0,0.0,0.0],[0.0,0.0,0.0,0.0,1.0,0.0],[0.0,0.0,0.0,0.0,0.0,1.0]]";
    let msg = check("2", two, bad, d);
    assert!(
        msg.contains("model.toml:10:13: error") && msg.contains("not symmetric: entry (1,2)"),
        "{msg}"
    );
    // Non-positive stiffness.
    let bad = "[[beams.sections]]\nstation = 0.0\nstiffness = [[1.0,0.0,0.0,0.0,0.0,0.0],[0.0,1.0,0.0,0.0,0.0,0.0],[0.0,0.0,-1.0,0.0,0.0,0.0],[0.0,0.0,0.0,1.0,0.0,0.0],[0.0,0.0,0.0,0.0,1.0,0.0],[0.0,0.0,0.0,0.0,0.0,1.0]]";
    let msg = check("2", two, bad, d);
    assert!(msg.contains("not positive definite"), "{msg}");
    // Missing CSV file.
    let msg = check("2", two, "sections_file = \"nope.csv\"", d);
    assert!(
        msg.contains("model.toml:8:17: error")
            && msg.contains("cannot read sections file")
            && msg.contains("nope.csv"),
        "{msg}"
    );
    // Wrong CSV shape: a row with too few values, reported at the CSV's own line.
    let mut header = String::from("station");
    for m in ["K", "M"] {
        for i in 1..=6 {
            for j in 1..=6 {
                header += &format!(",{m}{i}{j}");
            }
        }
    }
    std::fs::write(d.join("props.csv"), format!("{header}\n0.0,1.0,2.0\n")).unwrap();
    let msg = check("2", two, "sections_file = \"props.csv\"", d);
    assert!(
        msg.contains("props.csv:2:1: expected 73 values, found 3")
            && msg.contains("model.toml:8:17"),
        "{msg}"
    );
    // A correct CSV file loads.
    let row: Vec<String> = std::iter::once("0.0".to_string())
        .chain((0..36).map(|k| {
            if k % 7 == 0 {
                "1.0".into()
            } else {
                "0.0".into()
            }
        }))
        .chain((0..36).map(|k| {
            if k % 7 == 0 {
                "1.0".into()
            } else {
                "0.0".into()
            }
        }))
        .collect();
    std::fs::write(
        d.join("props.csv"),
        format!("{header}\n{}\n", row.join(",")),
    )
    .unwrap();
    assert_eq!(check("2", two, "sections_file = \"props.csv\"", d), "");
}
