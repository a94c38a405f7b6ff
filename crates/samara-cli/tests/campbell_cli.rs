//! `type = "campbell"` from the command line: the sweep of the rotating uniform cantilever
//! written to the results file, and `samara plot RESULTS campbell` (issue #14).

use crate::common;
use common::*;

#[test]
fn campbell_sweep_and_plot() {
    let dir = tempfile::tempdir().unwrap();
    let base =
        std::fs::read_to_string(root().join("examples/verification/rotating_beam_campbell.toml"))
            .unwrap();
    let text = base.replace(
        "[[analyses]]\nname = \"spin\"",
        "[[analyses]]\nname = \"sweep\"\ntype = \"campbell\"\nrotation = { axis = [0.0, 0.0, 1.0] }\nspeeds = { start = 2.0, end = 12.0, count = 6 }\nn_modes = 3\n\n[[analyses]]\nname = \"spin\"",
    );
    let model = dir.path().join("m.toml");
    std::fs::write(&model, text).unwrap();
    let out = dir.path().join("out");
    let o = samara(&[
        "run",
        model.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let nc = out.join("sweep.nc");
    let mut r = samara::output::ResultsReader::open(&nc).unwrap();
    assert_eq!(
        r.read("campbell_speed").unwrap(),
        vec![2.0, 4.0, 6.0, 8.0, 10.0, 12.0]
    );
    let f = r.read("campbell_frequency").unwrap();
    assert_eq!(f.len(), 18);
    // Flap 1 (tracked mode 2) at λ = 12: 13.1702 (Wright et al. 1982), in Hz.
    let f1 = f[5 * 3 + 1] * std::f64::consts::TAU;
    assert!((f1 - 13.1702).abs() < 1e-3, "{f1}");
    assert_eq!(r.read("campbell_mode_label").unwrap(), vec![2.0, 1.0, 2.0]);
    let png = dir.path().join("campbell.png");
    let o = samara(&[
        "plot",
        nc.to_str().unwrap(),
        "campbell",
        "--out",
        png.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(std::fs::metadata(&png).unwrap().len() > 10_000);
    // A results file without Campbell arrays gets a clear error.
    let o = samara(&["plot", out.join("modes.nc").to_str().unwrap(), "campbell"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("type = \"campbell\""), "{}", stderr(&o));
}
