//! Keeps examples/python/plot_pendulum.py working: it must open a fresh results file with
//! xarray, plot it, and report the same final position as the file holds.
//! Needs `pip install -r examples/python/requirements.txt` (`.ci/run` does it).

use std::path::Path;
use std::process::Command;

#[test]
fn python_example_reads_and_plots_a_results_file() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let probe = Command::new("python3")
        .args(["-c", "import xarray, scipy, matplotlib"])
        .output()
        .expect("python3 must be installed");
    assert!(
        probe.status.success(),
        "the Python example needs its packages: python3 -m pip install -r examples/python/requirements.txt\n{}",
        String::from_utf8_lossy(&probe.stderr)
    );
    let dir = tempfile::tempdir().unwrap();
    let model = std::fs::read_to_string(root.join("examples/pendulum.toml"))
        .unwrap()
        .replace("t_end = 10.0", "t_end = 1.0");
    let model_path = dir.path().join("pendulum.toml");
    std::fs::write(&model_path, model).unwrap();
    let out = dir.path().join("out");
    let o = Command::new(env!("CARGO_BIN_EXE_samara"))
        .args([
            "run",
            model_path.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "-q",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let results = out.join("swing.nc");
    let figure = dir.path().join("swing.png");
    let o = Command::new("python3")
        .arg(root.join("examples/python/plot_pendulum.py"))
        .args([results.to_str().unwrap(), figure.to_str().unwrap()])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let png = std::fs::read(&figure).unwrap();
    assert!(
        png.starts_with(b"\x89PNG") && png.len() > 10_000,
        "not a plot"
    );
    // Compare the script's final position with the file, read independently.
    let field = |key: &str| -> f64 {
        stdout
            .split_whitespace()
            .find_map(|w| w.strip_prefix(&format!("{key}=")))
            .unwrap_or_else(|| panic!("no {key} in {stdout}"))
            .parse()
            .unwrap()
    };
    let mut rd = netcdf3::FileReader::open(&results).unwrap();
    let x = rd.read_var_f64("position").unwrap();
    let n = x.len() / 3;
    assert!((field("t_end") - 1.0).abs() < 1e-9);
    assert!((field("x") - x[3 * (n - 1)]).abs() < 1e-8);
    assert!((field("z") - x[3 * (n - 1) + 2]).abs() < 1e-8);
}
