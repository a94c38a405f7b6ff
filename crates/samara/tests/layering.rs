//! The layering written at the top of lib.rs holds: each top-level module imports
//! (`crate::…` outside comments) only from the layers below it, so there are no circular
//! imports between model, elements, joints and system (issue #11).

use std::collections::BTreeSet;
use std::path::Path;

/// Module → the modules it may import from.
const ALLOWED: &[(&str, &[&str])] = &[
    ("math", &[]),
    ("diagnostics", &[]),
    ("input_files", &[]),
    ("solve", &["math"]),
    ("core", &["math"]),
    ("elements", &["core", "math"]),
    ("joints", &["core", "math", "elements"]),
    ("tangent_check", &["core", "math"]),
    (
        "section",
        &["diagnostics", "input_files", "math", "elements"],
    ),
    (
        "model",
        &[
            "math",
            "diagnostics",
            "input_files",
            "solve",
            "core",
            "elements",
            "joints",
            "section",
            "tangent_check",
        ],
    ),
    (
        "system",
        &["math", "solve", "core", "elements", "joints", "model"],
    ),
    (
        "analysis",
        &[
            "math", "solve", "core", "elements", "joints", "model", "system",
        ],
    ),
    (
        "output",
        &[
            "math", "solve", "core", "elements", "joints", "model", "system", "analysis",
        ],
    ),
];

fn imports(path: &Path, out: &mut BTreeSet<String>) {
    if path.is_dir() {
        for e in std::fs::read_dir(path).unwrap() {
            imports(&e.unwrap().path(), out);
        }
        return;
    }
    if path.extension().is_none_or(|x| x != "rs") {
        return;
    }
    let text = std::fs::read_to_string(path).unwrap();
    for line in text.lines().filter(|l| !l.trim_start().starts_with("//")) {
        for (i, _) in line.match_indices("crate::") {
            let name: String = line[i + 7..]
                .chars()
                .take_while(|c| c.is_ascii_lowercase() || *c == '_')
                .collect();
            if !name.is_empty() {
                out.insert(name);
            }
        }
    }
}

#[test]
fn modules_import_only_from_lower_layers() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut bad = Vec::new();
    for (module, allowed) in ALLOWED {
        let dir = src.join(module);
        let path = if dir.is_dir() {
            dir
        } else {
            src.join(format!("{module}.rs"))
        };
        assert!(path.exists(), "{module}");
        let mut found = BTreeSet::new();
        imports(&path, &mut found);
        for m in found {
            // The crate root (`crate::Error`, `crate::VERSION`) is allowed everywhere.
            let is_module = ALLOWED.iter().any(|(n, _)| *n == m);
            if is_module && m != *module && !allowed.contains(&m.as_str()) {
                bad.push(format!("{module} imports {m}"));
            }
        }
    }
    assert!(bad.is_empty(), "layering broken: {bad:#?}");
}
