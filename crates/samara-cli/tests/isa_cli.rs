//! `SAMARA_ISA` narrows the compiled copies the kernels run (`samara::math::isa`). The
//! copies' documented statements, checked end to end through `samara run`: AVX gives the
//! same bits as the baseline and AVX-512 the same bits as AVX2 + FMA (only the vector width
//! differs); the fused copies differ from the baseline by round-off only. A value that
//! names no copy is refused.

use crate::common::stderr;
use netcdf3::{DataVector, FileReader};
use samara::math::isa::Isa;
use std::collections::BTreeMap;
use std::process::{Command, Output};

/// A beam hung from a revolute joint and a body on a spherical joint at its tip, swinging
/// under gravity: the beam element, the rigid body, the joint rows, the assembly, the block
/// LU and the Newton correction all run their copies.
const MODEL: &str = r#"[model]
name = "isa"
gravity = [0.0, 0.0, -9.81]

[[beams]]
name = "arm"
order = 2
elements = 3
points = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]
root = "root"
tip = "tip"

[[beams.sections]]
station = 0.0
isotropic = { E = 2e9, G = 8e8, A = 1e-3, I2 = 1e-7, I3 = 1e-7, J = 2e-7, shear_factors = [0.8333, 0.8333], density = 1000.0 }

[[nodes]]
name = "bob"
position = [1.2, 0.0, 0.0]

[[bodies]]
name = "bob"
node = "bob"
mass = 0.5
inertia = [[1e-3, 0.0, 0.0], [0.0, 1e-3, 0.0], [0.0, 0.0, 1e-3]]

[[joints]]
name = "hinge"
type = "revolute"
node_a = "ground"
node_b = "root"
position = [0.0, 0.0, 0.0]
axis = [0.0, 1.0, 0.0]

[[joints]]
name = "ball"
type = "spherical"
node_a = "tip"
node_b = "bob"
position = [1.0, 0.0, 0.0]

[[analyses]]
name = "swing"
type = "dynamic"
t_end = 0.05
step = 1e-3
rho_inf = 0.9
"#;

/// Writes [`MODEL`] into a fresh folder and runs it with `SAMARA_ISA` set to `isa` (unset
/// for `None`); the folder (results in `out/`) is returned with the output.
fn run_with(isa: Option<&str>) -> (Output, tempfile::TempDir) {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("isa.toml");
    std::fs::write(&model, MODEL).unwrap();
    let mut c = Command::new(env!("CARGO_BIN_EXE_samara"));
    c.arg("run")
        .arg(&model)
        .arg("--out")
        .arg(dir.path().join("out"));
    match isa {
        Some(v) => c.env("SAMARA_ISA", v),
        None => c.env_remove("SAMARA_ISA"),
    };
    (c.output().expect("the samara binary runs"), dir)
}

/// Every floating-point variable of the results file but the wall time.
fn results(isa: Option<&str>) -> BTreeMap<String, Vec<f64>> {
    let (o, dir) = run_with(isa);
    assert!(o.status.success(), "SAMARA_ISA={isa:?}: {}", stderr(&o));
    let mut rd = FileReader::open(dir.path().join("out/swing.nc")).unwrap();
    let names = rd.data_set().get_var_names();
    let mut vars = BTreeMap::new();
    for name in names.into_iter().filter(|n| !n.contains("wall")) {
        if let DataVector::F64(v) = rd.read_var(&name).unwrap() {
            vars.insert(name, v);
        }
    }
    assert!(vars.contains_key("position"), "{:?}", vars.keys());
    vars
}

fn assert_same_bits(a: &BTreeMap<String, Vec<f64>>, b: &BTreeMap<String, Vec<f64>>, what: &str) {
    assert_eq!(a.keys().collect::<Vec<_>>(), b.keys().collect::<Vec<_>>());
    for (name, va) in a {
        let vb = &b[name];
        let same =
            va.len() == vb.len() && va.iter().zip(vb).all(|(x, y)| x.to_bits() == y.to_bits());
        assert!(same, "{what}: `{name}` differs");
    }
}

#[test]
fn each_copy_keeps_its_statement_from_the_command_line() {
    let cpu = Isa::cpu();
    let base = results(Some("base"));
    if cpu >= Isa::Avx {
        assert_same_bits(&base, &results(Some("avx")), "avx against base");
    }
    if cpu >= Isa::Fma {
        let fma = results(Some("fma"));
        if cpu >= Isa::Avx512 {
            assert_same_bits(&fma, &results(Some("avx512")), "avx512 against fma");
        }
        // Fused multiply-adds round each c ± ab once: the same motion to round-off. Over
        // 50 steps of a well-conditioned swing (positions ~1 m, Newton tolerance 1e-10
        // relative) the copies stay within 1e-9 m of each other.
        let (xb, xf) = (&base["position"], &fma["position"]);
        let worst = xb
            .iter()
            .zip(xf)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(
            worst < 1e-9,
            "fma against base: positions differ by {worst:e} m"
        );
    }
    // Unset, the widest copy runs: the same bits as asking for the CPU's own.
    assert_same_bits(
        &results(None),
        &results(Some(cpu.name())),
        "unset against the cpu's",
    );
}

#[test]
fn an_unknown_instruction_set_is_refused_with_the_accepted_names() {
    let (o, dir) = run_with(Some("sse9"));
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(
        e.contains("SAMARA_ISA") && e.contains("\"sse9\"") && e.contains("base, avx, fma, avx512"),
        "{e}"
    );
    assert!(!dir.path().join("out").exists(), "nothing is written");
    // Any command checks it, before it reads anything.
    let o = Command::new(env!("CARGO_BIN_EXE_samara"))
        .args(["check", "missing.toml"])
        .env("SAMARA_ISA", "avx2")
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("SAMARA_ISA"), "{}", stderr(&o));
}

#[test]
fn a_wider_copy_than_the_cpu_runs_is_a_warning() {
    if Isa::cpu() == Isa::Avx512 {
        return; // every copy runs here: nothing to warn about
    }
    let (o, _dir) = run_with(Some("avx512"));
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("wider than this CPU runs"),
        "{}",
        stderr(&o)
    );
}
