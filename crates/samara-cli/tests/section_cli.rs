//! `samara section` end to end (issue #12): every example section file, the blade built
//! from section files (with the cache), recovery from a beam run, the picture, and clear
//! errors.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn samara(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_samara"))
        .args(args)
        .output()
        .expect("the samara binary runs")
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// Every section file under examples/ (the test below also checks nothing is missing).
const EXAMPLES: [&str; 12] = [
    "examples/sections/rectangle.section.toml",
    "examples/sections/circle.section.toml",
    "examples/sections/tube.section.toml",
    "examples/sections/box.section.toml",
    "examples/sections/i_section.section.toml",
    "examples/sections/airfoil.section.toml",
    "examples/sections/channel.section.toml",
    "examples/sections/sandwich.section.toml",
    "examples/sections/blade/root.section.toml",
    "examples/sections/blade/inboard.section.toml",
    "examples/sections/blade/outboard.section.toml",
    "examples/sections/blade/tip.section.toml",
];

/// Every example section file solves; the TOML parses back with the same header and the
/// CSV has the 73 columns of the beam's sections file; `--plot` draws a PNG.
#[test]
fn every_example_section_runs() {
    // The list covers every section file in examples/.
    fn walk(dir: &Path, out: &mut Vec<String>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(&p, out);
            } else if p.to_string_lossy().ends_with(".section.toml") {
                let rel = p.strip_prefix(root()).unwrap().to_string_lossy();
                out.push(rel.replace('\\', "/"));
            }
        }
    }
    let mut present = Vec::new();
    walk(&root().join("examples"), &mut present);
    present.sort();
    let mut listed: Vec<String> = EXAMPLES.iter().map(|s| s.to_string()).collect();
    listed.sort();
    assert_eq!(present, listed, "section examples not run by this test");
    let out = tempfile::tempdir().unwrap();
    for name in EXAMPLES {
        let file = root().join(name);
        let stem = Path::new(name)
            .file_name()
            .unwrap()
            .to_str()
            .unwrap()
            .trim_end_matches(".section.toml");
        let plot =
            name.ends_with("/airfoil.section.toml") || name.ends_with("/channel.section.toml");
        let mut args = vec![
            "section",
            file.to_str().unwrap(),
            "--out",
            out.path().to_str().unwrap(),
        ];
        if plot {
            args.push("--plot");
        }
        let o = samara(&args);
        assert_eq!(o.status.code(), Some(0), "{name}: {}", text(&o));
        let s = text(&o);
        assert!(
            s.contains("tension centre") && s.contains("stiffness about the origin"),
            "{s}"
        );
        let toml_text = std::fs::read_to_string(out.path().join(format!("{stem}.toml"))).unwrap();
        let v: toml::Value = toml::from_str(&toml_text).unwrap();
        assert!(v["section"]["mass_per_length"].as_float().unwrap() > 0.0);
        assert_eq!(
            v["beams"]["sections"][0]["stiffness"]
                .as_array()
                .unwrap()
                .len(),
            6
        );
        let csv = std::fs::read_to_string(out.path().join(format!("{stem}.csv"))).unwrap();
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines.len(), 2);
        assert!(lines.iter().all(|l| l.split(',').count() == 73));
        if plot {
            let png = std::fs::read(out.path().join(format!("{stem}.png"))).unwrap();
            assert_eq!(&png[1..4], b"PNG");
        }
    }
}

/// The blade example runs statically from its section files; the second run takes all
/// four sections from the cache (same results to the last bit); recovery at a station
/// writes a VTU that a VTK reader opens and a CSV per element node.
#[test]
fn blade_from_section_files_runs_and_recovers() {
    let out = tempfile::tempdir().unwrap();
    let model = root().join("examples/sections/blade.toml");
    let o = samara(&[
        "run",
        model.to_str().unwrap(),
        "--out",
        out.path().to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let cache = out.path().join("sections");
    let cached: Vec<_> = std::fs::read_dir(&cache).unwrap().collect();
    assert_eq!(cached.len(), 4, "one cache entry per section file");
    let first = std::fs::read(out.path().join("sag.nc")).unwrap();
    let mtimes: Vec<_> = std::fs::read_dir(&cache)
        .unwrap()
        .map(|e| e.unwrap().metadata().unwrap().modified().unwrap())
        .collect();
    let o = samara(&[
        "run",
        model.to_str().unwrap(),
        "--out",
        out.path().to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let again: Vec<_> = std::fs::read_dir(&cache)
        .unwrap()
        .map(|e| e.unwrap().metadata().unwrap().modified().unwrap())
        .collect();
    assert_eq!(mtimes, again, "the cache is read, not rewritten");
    // Same beam results (the file's timestamps differ; compare the sectional forces).
    let read = |p: &Path| {
        let mut r = netcdf3::FileReader::open(p).unwrap();
        r.read_var_f64("beam_moment").unwrap()
    };
    let second = out.path().join("sag.nc");
    let backup = std::fs::read_dir(out.path())
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.to_str().unwrap().contains("sag.~"))
        .expect("the first results were kept");
    assert_eq!(std::fs::read(&backup).unwrap(), first);
    assert_eq!(read(&backup), read(&second));
    // Recovery.
    let sec = root().join("examples/sections/blade/inboard.section.toml");
    let o = samara(&[
        "section",
        sec.to_str().unwrap(),
        "--out",
        out.path().to_str().unwrap(),
        "--recover",
        second.to_str().unwrap(),
        "--station",
        "0.15",
        "--time",
        "1.0",
    ]);
    let s = text(&o);
    assert_eq!(o.status.code(), Some(0), "{s}");
    assert!(
        s.contains("recovery at section blade#") && s.contains("largest von Mises"),
        "{s}"
    );
    let vtu = out.path().join("inboard_recovery.vtu");
    let vtk = vtkio::Vtk::import(&vtu).expect("a VTK reader opens the recovery file");
    match vtk.data {
        vtkio::model::DataSet::UnstructuredGrid { pieces, .. } => {
            let p = pieces[0].load_piece_data(None).unwrap();
            assert!(p.num_points() > 100);
            let names: Vec<String> = p
                .data
                .point
                .iter()
                .map(|a| match a {
                    vtkio::model::Attribute::DataArray(d) => d.name.clone(),
                    vtkio::model::Attribute::Field { name, .. } => name.clone(),
                })
                .collect();
            for n in ["strain", "stress", "stress_material", "von_mises"] {
                assert!(names.iter().any(|x| x == n), "{names:?}");
            }
        }
        _ => panic!("not an unstructured grid"),
    }
    let csv = std::fs::read_to_string(out.path().join("inboard_recovery.csv")).unwrap();
    let header = csv.lines().next().unwrap();
    assert_eq!(header.split(',').count(), 30, "{header}");
    // A section name works as a station too; the results' beam must exist.
    let o = samara(&[
        "section",
        sec.to_str().unwrap(),
        "--out",
        out.path().to_str().unwrap(),
        "--recover",
        second.to_str().unwrap(),
        "--station",
        "blade#0",
        "--time",
        "0.5",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let o = samara(&[
        "section",
        sec.to_str().unwrap(),
        "--out",
        out.path().to_str().unwrap(),
        "--recover",
        second.to_str().unwrap(),
        "--station",
        "0.5",
        "--time",
        "1",
        "--beam",
        "wing",
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        text(&o).contains("--beam 'wing' is not in the results; the beams are: blade"),
        "{}",
        text(&o)
    );
    let o = samara(&[
        "section",
        sec.to_str().unwrap(),
        "--recover",
        second.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o).contains("needs --station and --time"));
}

/// `samara check` reads the section cache but never writes it (nor any results folder).
#[test]
fn check_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    for f in ["blade.toml", "naca2418.dat"] {
        std::fs::copy(root().join("examples/sections").join(f), dir.path().join(f)).unwrap();
    }
    std::fs::create_dir(dir.path().join("blade")).unwrap();
    for f in ["root", "inboard", "outboard", "tip"] {
        let name = format!("{f}.section.toml");
        std::fs::copy(
            root().join("examples/sections/blade").join(&name),
            dir.path().join("blade").join(&name),
        )
        .unwrap();
    }
    let model = dir.path().join("blade.toml");
    let o = samara(&["check", model.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    assert!(!dir.path().join("out").exists());
}

/// A bad section file: exit status 1, the error at file:line:col with a hint, nothing
/// written.
#[test]
fn a_bad_section_file_is_a_located_error() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("bad.section.toml");
    let body = "[[materials]]\nname = \"steel\"\ntype = \"isotropic\"\nE = 2e11\nnu = 0.3\n\n[tube]\nouter_radius = 0.05\nlayup = [{ material = \"steel\", thickness = 0.002, angle = -95.0 }]\n";
    std::fs::write(&p, body).unwrap();
    let o = samara(&[
        "section",
        p.to_str().unwrap(),
        "--out",
        dir.path().join("out").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    let s = text(&o);
    assert!(
        s.contains("bad.section.toml:9:59: error: ply angle -95 is outside [−90, 90] degrees"),
        "{s}"
    );
    assert!(s.contains("nothing was computed"), "{s}");
    assert!(!dir.path().join("out").exists());
}
