//! Helpers shared by the command-line tests.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

pub fn samara(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_samara"))
        .args(args)
        .output()
        .expect("the samara binary runs")
}

pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

pub const PENDULUM: &str = r#"[model]
name = "pendulum"
gravity = [0.0, 0.0, -9.81]

[[nodes]]
name = "bob"
position = [1.0, 0.0, 0.0]

[[bodies]]
name = "bob"
node = "bob"
mass = 1.0
inertia = [[1e-3, 0.0, 0.0], [0.0, 1e-3, 0.0], [0.0, 0.0, 1e-3]]

[[joints]]
name = "pivot"
type = "revolute"
node_a = "ground"
node_b = "bob"
position = [0.0, 0.0, 0.0]
axis = [0.0, 1.0, 0.0]

[[analyses]]
name = "swing"
type = "dynamic"
t_end = 0.5
step = 1e-3
rho_inf = 0.9
diagnostics = true
"#;

/// Writes `text` as `name` in a fresh directory and runs `samara check` on it.
pub fn check_text(name: &str, text: &str) -> (Output, PathBuf, tempfile::TempDir) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    std::fs::write(&path, text).unwrap();
    let o = samara(&["check", path.to_str().unwrap()]);
    (o, path, dir)
}
