//! Span-wise plots of lifting-line station outputs (`samara plot RESULTS span LINE Q… --time
//! T`, `ResultsReader::span_profile`) on the NREL 5-MW rigid rotor (issue #15, "Outputs").

use crate::common;
use common::*;
use samara::output::{ReadError, ResultsReader};

/// BlSpn of the AeroDyn blade file's NumBlNds rows (lines after them are comments to
/// AeroDyn), read here independently of samara's reader.
fn aerodyn_spans() -> Vec<f64> {
    let text = std::fs::read_to_string(
        root().join("reference/nrel5mw/aero/NRELOffshrBsline5MW_AeroDyn_blade.dat"),
    )
    .unwrap();
    text.lines()
        .filter_map(|l| {
            let cols: Vec<f64> = l
                .split_whitespace()
                .map(str::parse::<f64>)
                .collect::<Result<_, _>>()
                .ok()?;
            if cols.len() == 7 { Some(cols[0]) } else { None }
        })
        .take(19)
        .collect()
}

#[test]
fn span_profiles_and_plots() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(root().join("examples/rotor/nrel5mw_rotor.toml"))
        .unwrap()
        .replace(
            "../../reference",
            root().join("reference").to_str().unwrap(),
        )
        .replace("t_end = 0.5", "t_end = 0.05");
    let model = dir.path().join("rotor.toml");
    std::fs::write(&model, text).unwrap();
    let out = dir.path().join("out");
    let o = samara(&[
        "run",
        model.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let nc = out.join("spin.nc");
    let mut r = ResultsReader::open(&nc).unwrap();
    assert_eq!(r.aero_lines(), ["blade1", "blade2", "blade3"]);
    let time = r.time().unwrap();
    assert_eq!(time.len(), 6);

    // The abscissa is the blade file's BlSpn; the values are the stations' outputs at the
    // nearest output time (0.031 → record 3, t = 0.03), bit for bit.
    let spans = aerodyn_spans();
    assert_eq!(spans.len(), 19);
    let p = r
        .span_profile("blade2", "normal_load", Some(0.031))
        .unwrap();
    assert_eq!(p.time, time[3]);
    assert_eq!(p.units, "N/m");
    assert_eq!(p.span, spans);
    for (k, v) in p.values.iter().enumerate() {
        let c = r
            .channel(&format!("element_output:blade2.{k}.normal_load"))
            .unwrap();
        assert_eq!(*v, c.values[3], "station {k}");
    }
    // Default: the last output time.
    let last = r.span_profile("blade1", "alpha", None).unwrap();
    assert_eq!(last.time, time[5]);
    assert_eq!(last.units, "rad");
    let c = r.channel("element_output:blade1.18.alpha").unwrap();
    assert_eq!(last.values[18], c.values[5]);

    // Bad requests: located, with the alternatives.
    let e = r.span_profile("blade1", "alpha", Some(0.2)).unwrap_err();
    assert!(matches!(e, ReadError::OutsideTimes { .. }), "{e}");
    assert!(e.to_string().contains("0 … 0.05"), "{e}");
    let e = r
        .span_profile("blade4", "alpha", None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("blade1, blade2, blade3"), "{e}");
    let e = r
        .span_profile("blade1", "alpah", None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("did you mean 'alpha'"), "{e}");

    // The command: PNG and SVG, one or several times.
    for (name, extra) in [
        ("span.png", vec![]),
        ("span.svg", vec!["--time", "0", "--time", "0.05"]),
    ] {
        let fig = dir.path().join(name);
        let mut args = vec![
            "plot",
            nc.to_str().unwrap(),
            "span",
            "blade1",
            "alpha",
            "cl",
            "normal_load",
            "--out",
            fig.to_str().unwrap(),
        ];
        args.extend(extra);
        let o = samara(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(std::fs::metadata(&fig).unwrap().len() > 10_000, "{name}");
    }
    let svg = std::fs::read_to_string(dir.path().join("span.svg")).unwrap();
    assert!(svg.contains("t = 0.0500 s") && svg.contains("span [m]"));
    // --time belongs to span-wise plots; a span plot needs a line and a quantity.
    let o = samara(&[
        "plot",
        nc.to_str().unwrap(),
        "kinetic_energy",
        "--time",
        "0.01",
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("span-wise plot"), "{}", stderr(&o));
    let o = samara(&["plot", nc.to_str().unwrap(), "span", "blade1"]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("at least one station output"),
        "{}",
        stderr(&o)
    );
    let o = samara(&["plot", nc.to_str().unwrap(), "span"]);
    assert!(
        stderr(&o).contains("the lines are blade1, blade2, blade3"),
        "{}",
        stderr(&o)
    );
}
