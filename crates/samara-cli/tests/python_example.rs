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

/// Reads a NetCDF file with scipy's reader (`scipy.io.netcdf_file`, the engine the example
/// and xarray use; an implementation independent of ours and of the `netcdf3` crate) and
/// returns its dimensions, variables (type, dimensions, flattened data, attributes) and
/// global attributes as JSON. Floating-point values are written as Python's shortest
/// round-trip strings (`repr`), parsed back with Rust's correctly rounded `str::parse`, so
/// they arrive bit for bit.
fn read_with_scipy(path: &Path) -> serde_json::Value {
    const SCRIPT: &str = r#"
import json, sys
from scipy.io import netcdf_file
def clean(v):
    if isinstance(v, bytes):
        return v.decode()
    if hasattr(v, "tolist"):
        v = v.tolist()
    if isinstance(v, list):
        return [clean(x) for x in v]
    if isinstance(v, float):
        return repr(v)
    return v
with netcdf_file(sys.argv[1], "r", mmap=False, maskandscale=False) as f:
    out = {"version": int(f.version_byte), "dims": {k: v for k, v in f.dimensions.items()},
           "attrs": {k: clean(v) for k, v in f._attributes.items()}, "vars": {}}
    for name, var in f.variables.items():
        data = var.data
        if data.dtype.kind == "S":
            data = [b"".join(row).rstrip(b"\0").decode() for row in data.reshape(-1, data.shape[-1])]
        else:
            data = clean(data.reshape(-1))
        out["vars"][name] = {"type": var.typecode(), "dims": list(var.dimensions),
                             "data": data, "attrs": {k: clean(v) for k, v in var._attributes.items()}}
print(json.dumps(out))
"#;
    let o = Command::new("python3")
        .args(["-c", SCRIPT, path.to_str().unwrap()])
        .output()
        .expect("python3 must be installed");
    assert!(
        o.status.success(),
        "scipy could not read {}: {}",
        path.display(),
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_slice(&o.stdout).unwrap()
}

/// The NetCDF writer (samara::output::netcdf) against an independent reader: every type
/// (byte, char, short, int, float, double), fixed and record variables, fill values (default
/// and `_FillValue`) where nothing was written, variable and global attributes (also one
/// rewritten after records were committed), and the format's special case of a single
/// record variable of a short type, whose records are not padded to 4 bytes. Values are
/// chosen exactly representable in their types, so the comparison is exact.
#[test]
fn netcdf_writer_output_reads_back_with_scipy() {
    use samara::output::netcdf::{AttrValue, Definition, NC_FILL_DOUBLE, NC_FILL_INT, NcType};
    let probe = Command::new("python3")
        .args(["-c", "import scipy"])
        .output()
        .expect("python3 must be installed");
    assert!(
        probe.status.success(),
        "needs scipy: python3 -m pip install -r examples/python/requirements.txt"
    );
    let dir = tempfile::tempdir().unwrap();

    // A file like a results file, with every type.
    let path = dir.path().join("all_types.nc");
    let mut d = Definition::new();
    let t = d.add_record_dim("time");
    let node = d.add_dim("node", 3);
    let vec3 = d.add_dim("vec3", 3);
    let strlen = d.add_dim("strlen", 16);
    let time = d.add_var("time", NcType::Double, &[t]);
    d.add_var_attr(time, "units", AttrValue::Text("s".into()));
    let pos = d.add_var("position", NcType::Double, &[t, node, vec3]);
    d.add_var_attr(pos, "_FillValue", AttrValue::Double(vec![f64::NAN]));
    let iters = d.add_var("iters", NcType::Int, &[t]);
    let level = d.add_var("level", NcType::Short, &[t, node]);
    // Never set: every record holds the default fill.
    d.add_var("unset", NcType::Double, &[t]);
    let names = d.add_var("node_name", NcType::Char, &[node, strlen]);
    let mass = d.add_var("mass", NcType::Float, &[node]);
    let flag = d.add_var("flag", NcType::Byte, &[node]);
    let conn = d.add_var("conn", NcType::Int, &[node]);
    d.add_var_attr(conn, "valid_range", AttrValue::Int(vec![0, 2]));
    // Never written: the default fill.
    d.add_var("never_written", NcType::Int, &[node]);
    d.add_global_attr("title", AttrValue::Text("writer cross-check".into()));
    d.add_global_attr("status", AttrValue::Text("running".into()));
    d.add_global_attr("gravity", AttrValue::Double(vec![0.0, 0.0, -9.81]));
    d.reserve_header(256);
    let mut w = d.create(&path).unwrap();
    w.put_fixed_text(names, &["root", "mid", "tip_node_16chars"])
        .unwrap();
    w.put_fixed_f64(mass, &[1.5, -2.25, 1024.0]).unwrap();
    w.put_fixed_i32(flag, &[-128, 0, 127]).unwrap();
    w.put_fixed_i32(conn, &[0, 1, 2]).unwrap();
    let pos_val = |r: usize, i: usize| r as f64 * 100.0 + i as f64 * 0.5 - 1.25;
    for r in 0..4 {
        w.set_record_f64(time, &[r as f64 * 0.125]).unwrap();
        if r != 2 {
            // Record 2 leaves the positions unset: they read as the _FillValue (NaN).
            let p: Vec<f64> = (0..9).map(|i| pos_val(r, i)).collect();
            w.set_record_f64(pos, &p).unwrap();
        }
        w.set_record_i32(iters, &[10 + r as i32]).unwrap();
        w.set_record_i32(level, &[-32768, r as i32, 32767]).unwrap();
        w.commit_record().unwrap();
    }
    w.set_global_attr("status", AttrValue::Text("completed".into()))
        .unwrap();
    w.finish().unwrap();

    let f = read_with_scipy(&path);
    assert_eq!(f["version"], 2, "64-bit offset format");
    assert_eq!(f["dims"]["node"], 3);
    assert_eq!(f["dims"]["strlen"], 16);
    assert!(
        f["dims"]["time"].is_null(),
        "time is the unlimited dimension"
    );
    assert_eq!(f["attrs"]["title"], "writer cross-check");
    assert_eq!(f["attrs"]["status"], "completed");
    assert_eq!(
        f["attrs"]["gravity"],
        serde_json::json!(["0.0", "0.0", "-9.81"])
    );
    let var = |name: &str| &f["vars"][name];
    let f64s = |name: &str| -> Vec<f64> {
        var(name)["data"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_str().unwrap().parse().unwrap())
            .collect()
    };
    let i64s = |name: &str| -> Vec<i64> {
        var(name)["data"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_i64().unwrap())
            .collect()
    };
    let types: Vec<(&str, &str)> = vec![
        ("time", "d"),
        ("position", "d"),
        ("iters", "i"),
        ("level", "h"),
        ("node_name", "c"),
        ("mass", "f"),
        ("flag", "b"),
        ("conn", "i"),
        ("never_written", "i"),
        ("unset", "d"),
    ];
    for (name, code) in types {
        assert_eq!(var(name)["type"], code, "type of {name}");
    }
    assert_eq!(
        var("position")["dims"],
        serde_json::json!(["time", "node", "vec3"])
    );
    assert_eq!(var("time")["attrs"]["units"], "s");
    assert_eq!(f64s("time"), vec![0.0, 0.125, 0.25, 0.375]);
    let p = f64s("position");
    assert_eq!(p.len(), 36);
    for r in 0..4 {
        for i in 0..9 {
            let got = p[9 * r + i];
            if r == 2 {
                assert!(got.is_nan(), "unset record value {got}");
            } else {
                assert_eq!(got, pos_val(r, i));
            }
        }
    }
    assert_eq!(var("position")["attrs"]["_FillValue"], "nan");
    assert_eq!(i64s("iters"), vec![10, 11, 12, 13]);
    assert_eq!(
        i64s("level"),
        (0..4)
            .flat_map(|r| [-32768, r, 32767])
            .collect::<Vec<i64>>()
    );
    assert_eq!(f64s("unset"), vec![NC_FILL_DOUBLE; 4]);
    assert_eq!(
        var("node_name")["data"],
        serde_json::json!(["root", "mid", "tip_node_16chars"])
    );
    assert_eq!(f64s("mass"), vec![1.5, -2.25, 1024.0]);
    assert_eq!(i64s("flag"), vec![-128, 0, 127]);
    assert_eq!(i64s("conn"), vec![0, 1, 2]);
    assert_eq!(
        var("conn")["attrs"]["valid_range"],
        serde_json::json!([0, 2])
    );
    assert_eq!(i64s("never_written"), vec![NC_FILL_INT as i64; 3]);

    // The single short record variable: records of 3 shorts, 6 bytes, not padded to 8.
    let path = dir.path().join("single_short.nc");
    let mut d = Definition::new();
    let t = d.add_record_dim("time");
    let k = d.add_dim("k", 3);
    let s = d.add_var("s", NcType::Short, &[t, k]);
    let mut w = d.create(&path).unwrap();
    for r in 0..3 {
        w.set_record_i32(s, &[r, r + 10, -r]).unwrap();
        w.commit_record().unwrap();
    }
    w.finish().unwrap();
    let f = read_with_scipy(&path);
    assert_eq!(
        f["vars"]["s"]["data"],
        serde_json::json!([0, 10, 0, 1, 11, -1, 2, 12, -2])
    );
}
