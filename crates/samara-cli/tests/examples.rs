//! The README's first command, `samara run examples/landing_gear.toml`, end to end (on a copy
//! cut to 0.05 s): exit status 0, a complete results file. Every example's analyses run
//! through the library in samara/tests/examples.rs.

use std::path::Path;
use std::process::Command;

#[test]
fn the_readme_first_command_runs_landing_gear() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let text = std::fs::read_to_string(root.join("examples/landing_gear.toml")).unwrap();
    assert!(
        text.contains("t_end = 2.5"),
        "the example's end time changed"
    );
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("landing_gear.toml");
    std::fs::write(&model, text.replace("t_end = 2.5", "t_end = 0.05")).unwrap();
    let out = dir.path().join("out");
    let o = Command::new(env!("CARGO_BIN_EXE_samara"))
        .args([
            "run",
            model.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(stdout.contains("retract"), "{stdout}");
    let mut rd = netcdf3::FileReader::open(out.join("retract.nc")).unwrap();
    let ds = rd.data_set();
    assert_eq!(
        ds.get_global_attr_as_string("status").as_deref(),
        Some("completed")
    );
    // 50 steps of 1 ms written every 5th (`output_every = 5`), and the start.
    assert_eq!(ds.num_records(), Some(11));
    let t = rd.read_var_f64("time").unwrap();
    assert!((t[10] - 0.05).abs() < 1e-12, "{t:?}");
    assert!(
        rd.read_var_f64("position")
            .unwrap()
            .iter()
            .all(|x| x.is_finite())
    );
}
