//! The registry of component kinds (issue #11): adding an element kind is one kernel
//! module, one kind module and one registration line. Counted on the Maxwell element,
//! added through the registry: outside its own two modules, the only source lines that
//! name it are the kernel's `mod`/`pub use` in elements/mod.rs and the kind's `mod` and
//! registry line in model/components/mod.rs — no edit to validation, the system, the
//! assembler, the analyses, the output or the CLI.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// Source files (under the crates' `src/`) with a code line — not a comment — naming the
/// Maxwell element or its table, relative to the workspace root, with those lines.
fn files_naming_maxwell() -> Vec<(String, Vec<String>)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut files = Vec::new();
    for krate in ["crates/samara/src", "crates/samara-cli/src"] {
        rust_files(&root.join(krate), &mut files);
    }
    files.sort();
    files
        .into_iter()
        .filter_map(|p| {
            let text = std::fs::read_to_string(&p).unwrap();
            let lines: Vec<String> = text
                .lines()
                .map(str::trim)
                .filter(|l| !l.starts_with("//"))
                .filter(|l| {
                    let l = l.to_lowercase();
                    l.contains("maxwell") || l.contains("viscoelastic")
                })
                .map(String::from)
                .collect();
            let rel = p
                .strip_prefix(&root)
                .unwrap()
                .to_string_lossy()
                .replace('\\', "/");
            (!lines.is_empty()).then_some((rel, lines))
        })
        .collect()
}

#[test]
fn adding_the_maxwell_element_touched_four_source_files() {
    let found = files_naming_maxwell();
    let names: BTreeSet<&str> = found.iter().map(|(f, _)| f.as_str()).collect();
    let expected: BTreeSet<&str> = [
        // New: the kernel (residual and tangents) and the kind (input, validation, build,
        // tangent cases).
        "crates/samara/src/elements/maxwell.rs",
        "crates/samara/src/model/components/viscoelastic.rs",
        // One `mod` + `pub use` line, and one `mod` + registry line.
        "crates/samara/src/elements/mod.rs",
        "crates/samara/src/model/components/mod.rs",
    ]
    .into_iter()
    .collect();
    assert_eq!(names, expected, "{found:#?}");
    for (file, lines) in &found {
        if file.ends_with("/mod.rs") {
            assert!(lines.len() <= 2, "{file}: {lines:#?}");
        }
    }
    println!("files naming the Maxwell element: {}", names.len());
}
