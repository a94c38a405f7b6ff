//! The NREL 5-MW power and thrust curves for the README picture: at the rpm and pitch of
//! OpenFAST's rigid and flexible steady tables (reference/nrel5mw/), the rigid
//! rotor of examples/rotor/nrel5mw_rotor.toml and the flexible rotor of
//! examples/rotor/nrel5mw_flexible.toml (BeamDyn blades, and the same blades stiff in
//! torsion as ElastoDyn's), with the tables' own aerodynamic power and thrust.
//!
//! `cargo run --release -p samara --example nrel5mw_curves > curves.csv`
//! (docs/images/make.sh runs it and docs/images/nrel5mw_curves.py draws the picture).

#[path = "../tests/common/nrel5mw.rs"]
mod nrel5mw;
use nrel5mw::*;
use samara::model::Model;

fn table(name: &str) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(
        reference()
            .join("operating_points/welib_openfast_steady")
            .join(name),
    )
    .unwrap();
    text.lines()
        .skip(1)
        .map(|l| l.split('\t').map(|x| x.parse().unwrap()).collect())
        .collect()
}

fn main() {
    let rigid = Model::from_file(repo().join("examples/rotor/nrel5mw_rotor.toml"))
        .unwrap()
        .model;
    let dir = std::env::temp_dir().join(format!("samara_curves_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let stiff = stiff_in_torsion(&dir, 1e3);
    let beamdyn = reference().join("structure/NRELOffshrBsline5MW_BeamDyn.dat");
    println!("case,wind,rpm,pitch,power_ref_kW,thrust_ref_kN,power_kW,thrust_kN");
    for v in table("NREL5MW_Oper_Onshore_Rigid_Discon.csv") {
        if v[0] < 4.0 || v[0].fract() != 0.0 {
            continue;
        }
        let p_ref = v[7] * v[1] * std::f64::consts::PI / 30.0;
        let (p, t) = nrel5mw_at(&rigid, v[0], v[1], v[2]);
        println!("rigid,{},{},{},{p_ref},{},{p},{t}", v[0], v[1], v[2], v[6]);
    }
    for v in table("NREL5MW_Oper_Onshore_Flexible_Discon.csv") {
        if v[0] < 4.0 || v[0].fract() != 0.0 {
            continue;
        }
        let p_ref = v[7] * v[1] * std::f64::consts::PI / 30.0;
        for (case, bd) in [("torsion_stiff", &stiff), ("beamdyn", &beamdyn)] {
            match nrel5mw_flexible_try(bd, v[0], v[1], v[2]) {
                Ok((p, t, _, _)) => {
                    println!("{case},{},{},{},{p_ref},{},{p},{t}", v[0], v[1], v[2], v[6])
                }
                Err(e) => eprintln!("{case} at {} m/s: no steady state: {e}", v[0]),
            }
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}
