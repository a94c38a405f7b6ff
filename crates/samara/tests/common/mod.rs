//! Helpers shared by the verification tests.
#![allow(dead_code)]

pub mod airfoil_run;
pub mod bts;
pub mod nrel5mw;

use samara::analysis::{AnalysisSummary, History, run_analysis};
use samara::model::{AnalysisKind, Model};
use samara::system::{State, System};

/// Parses and validates a model from TOML text (panics with the diagnostics otherwise).
pub fn model(toml: &str) -> Model {
    match Model::from_toml_str(toml, "test.toml") {
        Ok(l) => l.model,
        Err(e) => panic!("{e}"),
    }
}

/// Loads a model file relative to the workspace root.
pub fn model_file(rel: &str) -> Model {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(rel);
    match Model::from_file(&path) {
        Ok(l) => l.model,
        Err(e) => panic!("{e}"),
    }
}

/// Overrides the step (and optionally ρ∞, end time) of the first analysis.
pub fn with_step(mut m: Model, step: f64) -> Model {
    if let AnalysisKind::Dynamic(d) = &mut m.analyses[0].kind {
        d.step = step;
        d.min_step = step / 1024.0;
    }
    m
}

/// Runs the first analysis of the model and returns the summary and all frames.
pub fn run(m: &Model) -> (AnalysisSummary, History) {
    run_nth(m, 0)
}

pub fn run_nth(m: &Model, k: usize) -> (AnalysisSummary, History) {
    let (s, h) = run_unchecked(m, k);
    assert!(s.failure.is_none(), "analysis failed: {:?}", s.failure);
    (s, h)
}

/// Runs analysis `k` from the model's initial state and returns its summary and frames,
/// also when it failed (`failure` says why).
pub fn run_unchecked(m: &Model, k: usize) -> (AnalysisSummary, History) {
    let sys = System::new(m);
    let mut h = History::default();
    let s = run_analysis(
        &sys,
        &m.analyses[k],
        sys.initial_state(),
        &mut h,
        &mut |_| {},
    )
    .expect("recording to memory cannot fail");
    (s, h)
}

/// Observed order of convergence from errors at steps h, h/2, h/4, …
pub fn orders(errors: &[f64]) -> Vec<f64> {
    errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect()
}

/// Least-squares slope of log(y) against log(x).
pub fn loglog_slope(x: &[f64], y: &[f64]) -> f64 {
    let lx: Vec<f64> = x.iter().map(|v| v.ln()).collect();
    let ly: Vec<f64> = y.iter().map(|v| v.ln()).collect();
    let n = lx.len() as f64;
    let mx = lx.iter().sum::<f64>() / n;
    let my = ly.iter().sum::<f64>() / n;
    let sxy: f64 = lx.iter().zip(&ly).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = lx.iter().map(|a| (a - mx) * (a - mx)).sum();
    sxy / sxx
}

/// Complete elliptic integral of the first kind K(k) by the arithmetic–geometric mean,
/// K = π / (2 AGM(1, √(1 − k²))), exact to machine precision.
pub fn elliptic_k(k: f64) -> f64 {
    let (mut a, mut b) = (1.0f64, (1.0 - k * k).sqrt());
    for _ in 0..60 {
        let an = 0.5 * (a + b);
        b = (a * b).sqrt();
        a = an;
        if (a - b).abs() < 1e-16 * a {
            break;
        }
    }
    std::f64::consts::PI / (2.0 * a)
}

/// A small seeded generator of uniform numbers in [−1, 1) (64-bit LCG), so that the
/// randomized tangent tests are reproducible.
pub struct Lcg(pub u64);

impl Lcg {
    pub fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64) / ((1u64 << 53) as f64) * 2.0 - 1.0
    }

    pub fn vec3(&mut self, scale: f64) -> nalgebra::Vector3<f64> {
        nalgebra::Vector3::new(self.next(), self.next(), self.next()) * scale
    }
}

/// The constants of the kicked mass of `examples/adaptive_kick.toml` (a mass on a
/// prismatic joint with a linear spring-damper, hit by a step force), read from the loaded
/// model: (k, c, m, F, t_step).
pub fn kick_constants(m: &Model) -> (f64, f64, f64, f64, f64) {
    use samara::model::{ForceLaw, TimeFunction};
    let d3 = m.joints[0].components[2].as_ref().unwrap();
    let (
        Some(ForceLaw::Linear { coefficient: k, .. }),
        Some(ForceLaw::Linear { coefficient: c, .. }),
    ) = (&d3.spring, &d3.damper)
    else {
        panic!("the kicked mass's rail has a linear spring and damper")
    };
    let TimeFunction::Step { time: t0, .. } = m.forces[0].function else {
        panic!("the kick is a step force")
    };
    (*k, *c, m.bodies[0].mass, m.forces[0].force.x, t0)
}

/// The closed-form response of the kicked mass ([`kick_constants`]):
/// x = F/k [1 − e^{−ζωs}(cos ω_d s + ζ/√(1−ζ²) sin ω_d s)], s = t − t_step.
pub fn kick_response(m: &Model) -> impl Fn(f64) -> f64 + use<> {
    let (k, c, mass, force, t0) = kick_constants(m);
    let w = (k / mass).sqrt();
    let zeta = c / (2.0 * (k * mass).sqrt());
    let wd = w * (1.0 - zeta * zeta).sqrt();
    move |t: f64| {
        if t < t0 {
            return 0.0;
        }
        let s = t - t0;
        force / k
            * (1.0
                - (-zeta * w * s).exp()
                    * ((wd * s).cos() + zeta / (1.0 - zeta * zeta).sqrt() * (wd * s).sin()))
    }
}

/// The model part of an example file (everything before its first `[[analyses]]`), to
/// which a test appends analyses of its own.
pub fn example_model_text(rel: &str) -> String {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(rel);
    let text = std::fs::read_to_string(&path).unwrap();
    match text.find("[[analyses]]") {
        Some(i) => text[..i].to_string(),
        None => text,
    }
}

/// The Kynema reference of the heavy top of Brüls, Cardona & Arnold (2012)
/// (`reference/kynema_verification/heavy_top_kynema_material_0pt000002s.csv`, dt = 2e-6:
/// CG displacement u and orientation quaternion q at t = 1 s and 2 s), as printed in that
/// file; `constrained.rs::heavy_top_matches_the_kynema_reference` checks this copy against
/// the file.
pub const KYNEMA_HEAVY_TOP: [(f64, [f64; 7]); 2] = [
    (
        1.0,
        [
            0.1733440435722807,
            -0.3599112987333657,
            -0.7484906793466106,
            0.7329439942283007,
            -0.2782856278135421,
            0.5318246439927058,
            -0.3201761370231893,
        ],
    ),
    (
        2.0,
        [
            -0.1504168894608856,
            -1.7241654846852867,
            -0.6730223697288009,
            0.1229471344095339,
            -0.4910798717314375,
            0.3504301068655838,
            -0.7879868665928781,
        ],
    ),
];

/// The slider-crank of `examples/slider_crank.toml` (crank r = 0.1 m, rod l = 0.3 m, driven
/// at ω = 2π rad/s): piston position, velocity and acceleration at t from
/// x = r cos θ + √(l² − r² sin² θ), θ = ω t, and its derivatives.
pub fn slider_crank_piston(t: f64) -> [f64; 3] {
    let (r, l, w) = (0.1f64, 0.3f64, 2.0 * std::f64::consts::PI);
    let th = w * t;
    let (s, c) = th.sin_cos();
    let d = (l * l - r * r * s * s).sqrt();
    let x = r * c + d;
    let x1 = -r * s - r * r * s * c / d;
    let x2 = -r * c - r * r * (c * c - s * s) / d - r.powi(4) * s * s * c * c / d.powi(3);
    [x, w * x1, w * w * x2]
}

/// An energy-scheme stepper at the consistent start of `m`'s first analysis (dynamic, an
/// energy scheme), and that analysis's step.
pub fn energy_stepper<'a>(
    sys: &'a System,
    m: &Model,
) -> (samara::analysis::energy_preserving::EnergyStepper<'a>, f64) {
    use samara::analysis::energy_preserving::{EnergyStepper, consistent_initial_state};
    let AnalysisKind::Dynamic(d) = &m.analyses[0].kind else {
        panic!("not dynamic")
    };
    let start = consistent_initial_state(sys, d).unwrap();
    let it = EnergyStepper::new(
        sys,
        d.integrator,
        d.rho_inf,
        d.solver.tolerance,
        d.solver.relative_tolerance,
        d.solver.max_iterations,
        start,
    )
    .unwrap();
    (it, d.step)
}

/// The 1-based line of the first error of a rejected model, its message and hint.
pub fn first_error(text: &str) -> (usize, String, String) {
    let Err(e) = Model::from_toml_str(text, "bad.toml") else {
        panic!("accepted:\n{text}")
    };
    let d = e.errors().next().expect("an error");
    let span = d.span.clone().expect("a located error");
    let (line, _) = e.source.line_col(span.start);
    (line, d.message.clone(), d.hint.clone().unwrap_or_default())
}

/// The 1-based line of the first occurrence of `needle` in `text`.
pub fn line_of(text: &str, needle: &str) -> usize {
    text[..text.find(needle).unwrap()].matches('\n').count() + 1
}

/// Analysis `k` of `m` run on a rayon pool of `threads` threads; its final state.
pub fn run_with_threads(m: &Model, sys: &System, k: usize, threads: usize) -> State {
    summary_with_threads(m, sys, k, threads).final_state
}

/// Analysis `k` of `m` run on a rayon pool of `threads` threads; its summary.
pub fn summary_with_threads(m: &Model, sys: &System, k: usize, threads: usize) -> AnalysisSummary {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool");
    pool.install(|| {
        let mut h = History::default();
        let s = run_analysis(
            sys,
            &m.analyses[k],
            sys.initial_state(),
            &mut h,
            &mut |_| {},
        )
        .expect("recording to memory cannot fail");
        assert!(s.failure.is_none(), "analysis failed: {:?}", s.failure);
        s
    })
}

/// Every number of the state, as bits.
pub fn state_bits(s: &State) -> Vec<u64> {
    let mut out = Vec::new();
    for n in &s.nodes {
        let r = n.r();
        for v in [&n.x, &n.v, &n.w, &n.a, &n.wd] {
            out.extend(v.iter().map(|x| x.to_bits()));
        }
        out.extend(r.iter().map(|x| x.to_bits()));
    }
    for c in &s.coords {
        out.extend([c.q, c.v, c.a].map(f64::to_bits));
    }
    for z in &s.states {
        out.extend([z.z, z.zd].map(f64::to_bits));
    }
    out.extend(s.lambda.iter().map(|x| x.to_bits()));
    out
}
