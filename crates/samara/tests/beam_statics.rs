//! Issue #4, verification of the beam in statics: roll-up (closed form, exponential
//! convergence in p), Timoshenko cantilever (closed forms with shear), extension–twist
//! coupling (compliance closed form), the BeamDyn regression cases and the Kynema composite
//! beam (reference/), the Bathe–Bolourchi 45° bend.

use crate::common;

use common::{model, model_file, run};
use nalgebra::{UnitQuaternion, Vector3};
use samara::analysis::History;
use samara::model::Model;

/// Final displacement and rotation (global, from the initial orientation: R R₀ᵀ) of a node.
fn node_final(m: &Model, h: &History, name: &str) -> (Vector3<f64>, UnitQuaternion<f64>) {
    let i = m.node_index(name).expect("node exists");
    let n = &h.last().unwrap().state.nodes[i];
    let n0 = &m.nodes[i];
    (
        n.x - n0.position,
        n.rot.quaternion() * n0.orientation.quaternion().inverse(),
    )
}

/// Wiener–Milenkovic parameters c = 4 tan(φ/4) n of a rotation (BeamDyn's TipRD outputs).
fn wiener_milenkovic(q: &UnitQuaternion<f64>) -> Vector3<f64> {
    let psi = samara::math::log_map(q);
    let phi = psi.norm();
    if phi < 1e-300 {
        Vector3::zeros()
    } else {
        psi / phi * 4.0 * (phi / 4.0).tan()
    }
}

/// bd_isotropic_rollup: BeamDyn's r-test output and the exact Euler solution.
/// Tolerance: BeamDyn prints 9 digits; one order-15 element resolves the circular arc to
/// ~1e-9, so 1e-7 (absolute, on a tip displacement of 5.5) checks all printed digits
/// but the last two.
#[test]
fn bd_isotropic_rollup() {
    let m = model_file("examples/verification/bd_isotropic_rollup.toml");
    let (_, h) = run(&m);
    let (u, q) = node_final(&m, &h, "tip");
    let reference = Vector3::new(0.0, 5.49867743, -2.43174319);
    println!("tip displacement {u:?}, reference {reference:?}");
    assert!((u - reference).norm() < 1e-7, "{u:?}");
    let theta: f64 = 12.5664 * 10.0 / 100.0;
    let exact = Vector3::new(
        0.0,
        10.0 / theta * (1.0 - theta.cos()),
        10.0 / theta * theta.sin() - 10.0,
    );
    assert!((u - exact).norm() < 1e-7, "exact {exact:?}");
    let c = wiener_milenkovic(&q);
    println!("tip WM {c:?}");
    assert!((c - Vector3::new(-1.29968203, 0.0, 0.0)).norm() < 1e-7);
}

/// Planar extensible, shear-deformable elastica under a dead distributed load `q` along +x:
/// a straight beam along z (length `l`, clamped at s = 0, free at s = l) with sectional
/// stiffnesses EI (bending), EA (axial) and GA (shear). With θ the section's rotation about
/// +y (tangent t = (sin θ, cos θ), normal n = (cos θ, −sin θ) in the x-z plane), the
/// internal force carried across the section at s is the load outboard of it, q (l − s) x̂,
/// so the strains are ε = q (l − s) sin θ / EA, γ = q (l − s) cos θ / GA and
///
/// ```text
/// x′ = (1 + ε) sin θ + γ cos θ,   z′ = (1 + ε) cos θ − γ sin θ,
/// θ′ = m / EI,                    m′ = −q (l − s) z′,
/// x(0) = z(0) = θ(0) = 0,          m(l) = 0,
/// ```
///
/// (m the bending moment about y: m(s) = q ∫ₛˡ (z(σ) − z(s)) dσ). This is the beam's own
/// continuum problem written directly, with no element, interpolation or rotation
/// parametrization in common with samara's beam.
struct Elastica {
    q: f64,
    l: f64,
    ei: f64,
    ea: f64,
    ga: f64,
}

impl Elastica {
    /// (x′, z′, θ′, m′) at arc length s under the load q.
    fn rhs(&self, q: f64, s: f64, y: [f64; 4]) -> [f64; 4] {
        let f = q * (self.l - s);
        let (sin, cos) = y[2].sin_cos();
        let (e, g) = (f * sin / self.ea, f * cos / self.ga);
        let dz = (1.0 + e) * cos - g * sin;
        [(1.0 + e) * sin + g * cos, dz, y[3] / self.ei, -f * dz]
    }

    /// Classical RK4 over [0, l] in `n` equal steps from the root moment `m0`:
    /// returns (x, z, θ, m) at the tip.
    fn shoot(&self, q: f64, m0: f64, n: usize) -> [f64; 4] {
        let h = self.l / n as f64;
        let mut y = [0.0, 0.0, 0.0, m0];
        let add = |y: [f64; 4], k: [f64; 4], c: f64| std::array::from_fn(|j| y[j] + c * k[j]);
        for i in 0..n {
            let s = i as f64 * h;
            let k1 = self.rhs(q, s, y);
            let k2 = self.rhs(q, s + h / 2.0, add(y, k1, h / 2.0));
            let k3 = self.rhs(q, s + h / 2.0, add(y, k2, h / 2.0));
            let k4 = self.rhs(q, s + h, add(y, k3, h));
            y = std::array::from_fn(|j| {
                y[j] + h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j])
            });
        }
        y
    }

    /// Newton on the root moment m₀ so that m(l) = 0 under the load q, from the guess `m0`
    /// (derivative by a central difference, good to ~1e-8 relative: after a step below
    /// 1e-10 of m₀ the remaining error is ~1e-18 of m₀, below round-off).
    fn root_moment(&self, q: f64, mut m0: f64, n: usize) -> f64 {
        for _ in 0..30 {
            let d = 1e-6 * m0.abs();
            let f = self.shoot(q, m0, n)[3];
            let df = (self.shoot(q, m0 + d, n)[3] - self.shoot(q, m0 - d, n)[3]) / (2.0 * d);
            let step = f / df;
            m0 -= step;
            if step.abs() < 1e-10 * m0.abs() {
                return m0;
            }
        }
        panic!("shooting did not converge at load {q}");
    }

    /// The tip (x, z, θ) to ~1e-12. The load is raised in 40 increments from the
    /// small-deflection root moment q l²/2, each increment's guess extrapolated linearly from
    /// the two before, so that Newton follows the physical branch (the equations also have
    /// looping solutions, which a Newton solve from a poor guess falls onto). This is done
    /// with 1000 RK4 steps; the solution is then refined with 2000 and 4000 steps, which
    /// must converge at fourth order, and Richardson's extrapolation of the last two is
    /// returned with a bound on its error (|T₄₀₀₀ − T₂₀₀₀| / 15, the error of the
    /// 4000-step solution itself).
    fn solve(&self) -> ([f64; 3], f64) {
        let mut history = vec![0.0];
        for k in 1..=40 {
            let q = self.q * k as f64 / 40.0;
            let guess = match history.len() {
                1 => q * self.l * self.l / 2.0,
                n => 2.0 * history[n - 1] - history[n - 2],
            };
            history.push(self.root_moment(q, guess, 1000));
        }
        let mut m0 = history[40];
        let t: Vec<[f64; 3]> = [1000, 2000, 4000]
            .iter()
            .map(|&n| {
                m0 = self.root_moment(self.q, m0, n);
                let y = self.shoot(self.q, m0, n);
                [y[0], y[1] - self.l, y[2]]
            })
            .collect();
        let diff =
            |a: &[f64; 3], b: &[f64; 3]| (0..3).map(|j| (a[j] - b[j]).abs()).fold(0.0, f64::max);
        let (d1, d2) = (diff(&t[0], &t[1]), diff(&t[1], &t[2]));
        println!(
            "elastica: RK4 differences {d1:.3e} (1000→2000 steps), {d2:.3e} (2000→4000), ratio {:.1}",
            d1 / d2
        );
        // Fourth order: the ratio is 16 (allow 12…20 for round-off in the small difference).
        assert!(
            d1 / d2 > 12.0 && d1 / d2 < 20.0,
            "RK4 is not in its asymptotic range: {d1:e}, {d2:e}"
        );
        let tip = std::array::from_fn(|j| t[2][j] + (t[2][j] - t[1][j]) / 15.0);
        (tip, d2 / 15.0)
    }
}

/// bd_static_cantilever_beam (BeamDyn r-test): the roll-up beam (L = 10, EI = 100,
/// EA = GA = 1e4, 1 kg/m) bending under its own weight, gravity 9.806 along +x — a large
/// deflection (the tip turns by 89.6°, and ends 1.6 m above the root's level).
///
/// Reference: the elastica above with the beam's own sectional stiffness and q = 9.806 N/m,
/// solved by shooting to ~1e-12 (error bound asserted below 1e-10): tip displacement
/// (9.41761498, 0, −8.38915149), rotation 1.56367 rad. samara converges to it exponentially
/// in the element order p (one element): relative tip error 7.8e-3, 5.6e-3, 2.1e-3,
/// 1.6e-4, 7.4e-6, 1.2e-6, 1.2e-7, 6.5e-9, 3.3e-10 at p = 4, 5, 6, 8, 10, 12, 14, 16, 18,
/// a factor ≈ e^1.23 ≈ 3.4 per order. Tolerances: the fitted rate at least 1.0 per order
/// (e-fold), every error below the previous one, and 1e-9 at p = 18 (the two independent
/// solutions agree to 3e-10).
///
/// BeamDyn's r-test output at order 5 is (9.0601, 0, −8.5218): 3.0 % from the elastica,
/// five times samara's own order-5 error (0.56 %). That is BeamDyn's discretization error at
/// that order (its output is only given at p = 5, so its convergence cannot be seen here);
/// the test asserts that samara at the same order is closer to the exact solution than
/// BeamDyn, and does not use BeamDyn's number as a target.
#[test]
fn bd_static_cantilever_beam() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/verification/bd_static_cantilever_beam.toml");
    let text = std::fs::read_to_string(path).unwrap();
    let elastica = Elastica {
        q: 9.806,
        l: 10.0,
        ei: 100.0,
        ea: 1e4,
        ga: 1e4,
    };
    let ([ex, ez, eth], bound) = elastica.solve();
    let exact = Vector3::new(ex, 0.0, ez);
    println!(
        "elastica: tip {exact:.10?} (error bound {bound:.1e}), rotation {eth:.8} rad, WM {:.8}",
        4.0 * (eth / 4.0).tan()
    );
    assert!(bound < 1e-10, "reference not converged: {bound:e}");
    // The value stated in the docs and in issue #10, to its printed digits.
    assert!(
        (ex - 9.4176).abs() < 5e-5 && (ez + 8.3892).abs() < 5e-5,
        "{exact:?}"
    );
    let beamdyn = Vector3::new(9.06014769, 0.0, -8.52177367);
    let beamdyn_error = (beamdyn - exact).norm() / exact.norm();
    let orders = [4usize, 5, 6, 8, 10, 12, 14, 16, 18];
    let mut errs = Vec::new();
    for &p in &orders {
        let m = model(&text.replace("order = 5", &format!("order = {p}")));
        let (_, h) = run(&m);
        let (u, q) = node_final(&m, &h, "tip");
        let c = wiener_milenkovic(&q);
        let e = (u - exact).norm() / exact.norm();
        println!("p = {p}: tip {u:.8?}, WM {:.8}, rel. error {e:.3e}", c.y);
        errs.push(e);
    }
    println!("BeamDyn (order 5) vs the elastica: {beamdyn_error:.3e}");
    let p5 = errs[1];
    assert!(
        p5 < 0.5 * beamdyn_error,
        "order 5: {p5:e} vs BeamDyn's {beamdyn_error:e}"
    );
    let ps: Vec<f64> = orders.iter().map(|&p| p as f64).collect();
    // Least-squares slope of ln(error) against p (exponential convergence).
    let n = ps.len() as f64;
    let ly: Vec<f64> = errs.iter().map(|e| e.ln()).collect();
    let (mp, ml) = (ps.iter().sum::<f64>() / n, ly.iter().sum::<f64>() / n);
    let rate = -ps
        .iter()
        .zip(&ly)
        .map(|(p, l)| (p - mp) * (l - ml))
        .sum::<f64>()
        / ps.iter().map(|p| (p - mp).powi(2)).sum::<f64>();
    println!("exponential rate: error ∝ exp(−{rate:.3} p)");
    assert!(rate > 1.0, "rate {rate}: {errs:?}");
    for w in errs.windows(2) {
        assert!(w[1] < w[0], "{errs:?}");
    }
    assert!(errs[orders.len() - 1] < 1e-9, "{errs:?}");
}

/// Kynema/BeamDyn composite beam (fully populated 6×6 with bend–twist coupling), static.
/// Same discretization as the reference (one element, 15 nodes, 14 Gauss points); the
/// reference is converged to ~1e-10, so the difference is the two codes' rotation
/// interpolation at order 14: tolerance 1e-7 relative.
#[test]
fn composite_static() {
    let m = model_file("examples/verification/composite_static.toml");
    let (_, h) = run(&m);
    let (u, _) = node_final(&m, &h, "tip");
    let reference = Vector3::new(-9.02726627566299e-2, -6.47488486259036e-2, 1.22973648292371);
    let err = (u - reference).norm() / reference.norm();
    println!("tip {u:?}, relative error {err:.3e}");
    assert!(err < 1e-7);
}

/// Bathe–Bolourchi 45° bend, P = 600.
/// (a) The model file as BeamDyn's input (3 key points, order 10): against BeamDyn's r-test
///     output (4 digits) and the published Bathe–Bolourchi tip displacement; the spread of
///     the published solutions (Bathe–Bolourchi vs the converged LSFE) is 0.3 on 54, and the
///     three-point spline differs from BeamDyn's: tolerance 0.5 per component.
/// (b) The exact arc (explicit nodes on the circle, one element of order p = 4 … 14):
///     exponential convergence with the order — successive tips differ by 2.3e-2, 1.2e-4,
///     5.1e-7, 1.6e-9, 5.5e-12 — to (−13.60502, 53.47611, −23.56130). Tolerances: the p = 12
///     and p = 14 tips agree to 1e-9 relative, successive differences shrink by > 100×
///     from p = 4→6 to 8→10, and the limit lies within the spread of the published
///     solutions (Bathe–Bolourchi and the converged LSFE value of the reference README),
///     component by component.
///     The limit is 2.9e-3 (relative) from that LSFE value, (−13.7208, 53.5776, −23.6460):
///     more than its own discretization error, and not explained by the rounding of the
///     section constants (the exact EI = 1e7/12 moves the tip by 1e-5) — the LSFE run's
///     section data are not given with the number, so the cause is not established. The
///     test bounds the difference at 4e-3 so that a change of it is seen, and does not
///     claim agreement beyond that.
#[test]
fn bd_curved_beam() {
    let m = model_file("examples/verification/bd_curved_beam.toml");
    let (_, h) = run(&m);
    let (u, _) = node_final(&m, &h, "tip");
    let rtest = Vector3::new(-13.46, 53.35, -23.58);
    let bathe = Vector3::new(-13.4, 53.4, -23.5);
    println!("key points: tip {u:?} (BeamDyn {rtest:?}, Bathe–Bolourchi {bathe:?})");
    for i in 0..3 {
        assert!((u[i] - rtest[i]).abs() < 0.5 && (u[i] - bathe[i]).abs() < 0.5);
    }
    let converged = Vector3::new(-13.7208006040, 53.5776450627, -23.6459716009);
    let orders = [4usize, 6, 8, 10, 12, 14];
    let tips = tips_arc(&orders);
    let limit = tips[5];
    for (p, u) in orders.iter().zip(&tips) {
        println!(
            "exact arc, p = {p}: tip {u:.10?}, relative difference from the LSFE value {:.3e}",
            (u - converged).norm() / converged.norm()
        );
    }
    let diffs: Vec<f64> = tips.windows(2).map(|w| (w[1] - w[0]).norm()).collect();
    println!(
        "successive differences {:?}",
        diffs.iter().map(|d| format!("{d:.2e}")).collect::<Vec<_>>()
    );
    assert!(diffs[4] < 1e-9 * limit.norm(), "{diffs:?}");
    // Exponential convergence: successive differences shrink by > 100× from p = 4→6 to 8→10.
    assert!(diffs[2] < 1e-2 * diffs[0], "{diffs:?}");
    let lsfe = (limit - converged).norm() / converged.norm();
    assert!(lsfe < 4e-3, "{lsfe:e}");
    // The limit lies within the spread of the published solutions, component by component.
    for i in 0..3 {
        let (lo, hi) = (bathe[i].min(converged[i]), bathe[i].max(converged[i]));
        assert!(
            limit[i] > lo - 0.05 && limit[i] < hi + 0.05,
            "component {i}: {} not in [{lo}, {hi}]",
            limit[i]
        );
    }
}

/// The 45° arc as explicit nodes at the GLL points of one element of order p.
fn arc_model(p: usize) -> String {
    let (xi, _) = samara::elements::beam::gll::gauss_lobatto_legendre(p);
    let mut s = String::from("[model]\nname = \"arc\"\n\n");
    let mut names = Vec::new();
    for (k, x) in xi.iter().enumerate() {
        let a = std::f64::consts::FRAC_PI_4 * (x + 1.0) / 2.0;
        let pos = [100.0 * (1.0 - a.cos()), 0.0, 100.0 * a.sin()];
        // Section frame: x along the tangent (sin a, 0, cos a), y in the plane, z = global y.
        let tx = [a.sin(), 0.0, a.cos()];
        let ty = [a.cos(), 0.0, -a.sin()];
        let name = if k == p {
            "tip".to_string()
        } else {
            format!("n{k}")
        };
        s += &format!(
            "[[nodes]]\nname = \"{name}\"\nposition = [{:.17e}, 0.0, {:.17e}]\norientation = {{ x_axis = [{:.17e}, 0.0, {:.17e}], y_axis = [{:.17e}, 0.0, {:.17e}] }}\n\n",
            pos[0], pos[2], tx[0], tx[2], ty[0], ty[2]
        );
        names.push(format!("\"{name}\""));
    }
    s += &format!(
        "[[beams]]\nname = \"arc\"\norder = {p}\nnodes = [{}]\n\n",
        names.join(", ")
    );
    s += "[[beams.sections]]\nstation = 0.0\nstiffness = [[100e5,0.0,0.0,0.0,0.0,0.0],[0.0,41.6667e5,0.0,0.0,0.0,0.0],[0.0,0.0,41.6667e5,0.0,0.0,0.0],[0.0,0.0,0.0,8.333e5,0.0,0.0],[0.0,0.0,0.0,0.0,8.333e5,0.0],[0.0,0.0,0.0,0.0,0.0,8.333e5]]\n\n";
    s += "[[joints]]\nname = \"clamp\"\ntype = \"fixed\"\nnode_a = \"ground\"\nnode_b = \"n0\"\n\n[[forces]]\nname = \"f\"\nnode = \"tip\"\nforce = [0.0, 600.0, 0.0]\n\n";
    s += "[[analyses]]\nname = \"s\"\ntype = \"static\"\nload_steps = 10\ntolerance = 1e-11\nrelative_tolerance = 1e-11\n";
    s
}

fn tips_arc(orders: &[usize]) -> Vec<Vector3<f64>> {
    orders
        .iter()
        .map(|&p| {
            let m = model(&arc_model(p));
            let (_, h) = run(&m);
            node_final(&m, &h, "tip").0
        })
        .collect()
}

/// Roll-up to a full circle: a straight cantilever (L = 1, EI = 1) under the tip moment
/// M = 2π EI/L curls into a circle, tip back at the root. The tip error falls
/// exponentially with the order p (2 elements: each bends by 180°) and algebraically with
/// the number of elements at fixed p. Tolerances: error below 1e-8 at p = 10, and each
/// step p → p + 2 gains at least a factor 10 while above round-off.
#[test]
fn rollup_full_circle_converges_exponentially() {
    let text = |p: usize, ne: usize| {
        format!(
            "[model]\nname = \"rollup\"\n[[beams]]\nname = \"b\"\norder = {p}\nelements = {ne}\npoints = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]\nroot = \"root\"\ntip = \"tip\"\n[[beams.sections]]\nstation = 0.0\nstiffness = [[1e3,0.0,0.0,0.0,0.0,0.0],[0.0,1e3,0.0,0.0,0.0,0.0],[0.0,0.0,1e3,0.0,0.0,0.0],[0.0,0.0,0.0,1.0,0.0,0.0],[0.0,0.0,0.0,0.0,1.0,0.0],[0.0,0.0,0.0,0.0,0.0,1.0]]\n[[joints]]\nname = \"c\"\ntype = \"fixed\"\nnode_a = \"ground\"\nnode_b = \"root\"\n[[forces]]\nname = \"m\"\nnode = \"tip\"\nmoment = [0.0, 0.0, {}]\nframe = \"node\"\n[[analyses]]\nname = \"s\"\ntype = \"static\"\nload_steps = 8\ntolerance = 1e-12\nrelative_tolerance = 1e-12\n",
            2.0 * std::f64::consts::PI
        )
    };
    let err = |p: usize, ne: usize| {
        let m = model(&text(p, ne));
        let (_, h) = run(&m);
        let (u, _) = node_final(&m, &h, "tip");
        // Exact: the tip returns to the root, displacement (−1, 0, 0).
        (u - Vector3::new(-1.0, 0.0, 0.0)).norm()
    };
    let by_p: Vec<f64> = [2usize, 4, 6, 8, 10].iter().map(|&p| err(p, 2)).collect();
    let by_n: Vec<f64> = [2usize, 4, 8, 16].iter().map(|&n| err(2, n)).collect();
    println!("tip error vs p (2 elements): {by_p:?}");
    println!("tip error vs elements (p = 2): {by_n:?}");
    assert!(by_p[4] < 1e-8, "{by_p:?}");
    for w in by_p.windows(2) {
        assert!(w[1] < 0.1 * w[0] || w[1] < 1e-9, "{by_p:?}");
    }
    let slope = common::loglog_slope(&[2.0, 4.0, 8.0, 16.0], &by_n);
    println!(
        "algebraic order in the element count at p = 2: {:.2}",
        -slope
    );
    assert!(-slope > 1.8);
}

/// A straight beam along x (L = 1), clamped at the root, with a 6×6 section and a tip load;
/// one static increment.
fn straight_cantilever(
    order: usize,
    elements: usize,
    c: &[[f64; 6]; 6],
    force: Vector3<f64>,
    moment: Vector3<f64>,
) -> String {
    let rows: Vec<String> = c
        .iter()
        .map(|r| format!("[{}]", r.map(|x| format!("{x:e}")).join(", ")))
        .collect();
    format!(
        r#"
[model]
name = "cantilever"

[[beams]]
name = "beam"
order = {order}
elements = {elements}
points = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]
root = "root"
tip = "tip"

[[beams.sections]]
station = 0.0
stiffness = [{}]

[[joints]]
name = "clamp"
type = "fixed"
node_a = "ground"
node_b = "root"

[[forces]]
name = "load"
node = "tip"
force = [{:e}, {:e}, {:e}]
moment = [{:e}, {:e}, {:e}]

[[analyses]]
name = "static"
type = "static"
"#,
        rows.join(", "),
        force.x,
        force.y,
        force.z,
        moment.x,
        moment.y,
        moment.z
    )
}

/// Timoshenko cantilever (L = 1, EI = 1e4, shear stiffness k GA = 1e5, so shear adds 30 %
/// to the bending deflection): tip force F along z gives
/// δ = F L³/(3 EI) + F L/(k GA), θ = F L²/(2 EI) (rotation about −y);
/// tip moment M about y gives δ = −M L²/(2 EI), θ = M L/EI.
/// Loads are small (δ/L ≈ 1.3e-5), so geometric nonlinearity changes the answers by
/// O((δ/L)²) ≈ 2e-10 relative; the cubic deflection and quadratic rotation are represented
/// exactly from p = 3 on (2 elements of order 4 here: errors ~1e-11 measured); 20 linear
/// elements (one reduced Gauss point each) miss the deflection by the O(h²) term
/// F L³/(12 EI N²) = 4.8e-4 relative. Tolerance 1e-7 relative (p = 4), 1e-3 (p = 1).
#[test]
fn timoshenko_cantilever_tip_force_and_moment() {
    let (ei, kga, l): (f64, f64, f64) = (1.0e4, 1.0e5, 1.0);
    let mut c = [[0.0; 6]; 6];
    for (i, v) in [1e7, kga, kga, 5e3, ei, ei].iter().enumerate() {
        c[i][i] = *v;
    }
    for (order, elements, tol) in [(4, 2, 1e-7), (1, 20, 1e-3)] {
        // Tip force.
        let f = 0.1;
        let m = model(&straight_cantilever(
            order,
            elements,
            &c,
            Vector3::new(0.0, 0.0, f),
            Vector3::zeros(),
        ));
        let (_, h) = run(&m);
        let (u, q) = node_final(&m, &h, "tip");
        let delta = f * l.powi(3) / (3.0 * ei) + f * l / kga;
        let theta = f * l * l / (2.0 * ei);
        let rot = samara::math::log_map(&q);
        println!(
            "p = {order}, {elements} el., tip force: δ = {:.10e} (exact {delta:.10e}, rel. error {:.1e}), θ = {:.10e} (exact {theta:.10e}, {:.1e})",
            u.z,
            (u.z - delta).abs() / delta,
            -rot.y,
            (-rot.y - theta).abs() / theta
        );
        assert!((u.z - delta).abs() < tol * delta, "deflection");
        assert!((-rot.y - theta).abs() < tol * theta, "rotation");
        assert!(
            u.x.abs() < 1e-3 * delta
                && u.y.abs() < 1e-12
                && rot.x.abs() < 1e-12
                && rot.z.abs() < 1e-12
        );
        // Tip moment about y.
        let mm = 0.1;
        let m = model(&straight_cantilever(
            order,
            elements,
            &c,
            Vector3::zeros(),
            Vector3::new(0.0, mm, 0.0),
        ));
        let (_, h) = run(&m);
        let (u, q) = node_final(&m, &h, "tip");
        let delta = -mm * l * l / (2.0 * ei);
        let theta = mm * l / ei;
        let rot = samara::math::log_map(&q);
        println!(
            "p = {order}, {elements} el., tip moment: δ = {:.10e} (exact {delta:.10e}, rel. error {:.1e}), θ = {:.10e} (exact {theta:.10e}, {:.1e})",
            u.z,
            (u.z - delta).abs() / delta.abs(),
            rot.y,
            (rot.y - theta).abs() / theta
        );
        assert!((u.z - delta).abs() < tol * delta.abs(), "deflection");
        assert!((rot.y - theta).abs() < tol * theta, "rotation");
    }
}

/// Distributed loads (`[[beams.loads]]`) on the Timoshenko cantilever above (L = 1,
/// EI = 1e4, k GA = 1e5; 2 elements of order 5), against the closed forms of beam theory
/// with shear (w the load per length along z, δ the tip deflection along z, θ the tip
/// rotation about −y):
/// - uniform dead load q (`frame = "global"`): δ = q L⁴/(8 EI) + q L²/(2 k GA),
///   θ = q L³/(6 EI);
/// - the same load following the sections (`frame = "section"`; the load turns with the
///   section by θ ≈ 1.7e-5, which changes δ by O(θ²));
/// - a triangular load, zero at the root (`profile = [[0, 0], [1, 1]]`):
///   δ = 11 q L⁴/(120 EI) + q L²/(3 k GA), θ = q L³/(8 EI);
/// - a time function (a table 0 → 2 over t = 0…1, evaluated at the analysis `time` 0.25:
///   factor 0.5) on the uniform load: half the uniform answer;
/// - a uniform distributed moment m about y: δ = −m L³/(3 EI), θ = −m L²/(2 EI) (no shear).
///
/// Loads are small (δ/L ≈ 1.6e-5: geometric nonlinearity O((δ/L)²) ≈ 3e-10 relative) and
/// the exact deflections are polynomials of degree ≤ 5, represented exactly at p = 5; the
/// loads are integrated with p + 1 Gauss points. Tolerance 1e-7 relative (measured
/// ≤ 1.7e-10).
///
/// The example `examples/loaded_cantilever.toml` (aluminium bar, L = 2 m, 50 N/m) against
/// the same closed form: its static analysis deflects the tip by δ/L = 3.3e-3, so geometric
/// nonlinearity changes it by O((δ/L)²) ≈ 1e-5: tolerance 1e-4 relative.
#[test]
fn distributed_loads_match_the_loaded_cantilever() {
    let (ei, kga, l, q, mm): (f64, f64, f64, f64, f64) = (1.0e4, 1.0e5, 1.0, 1.0, 0.5);
    let text = |load: &str, time: f64| {
        format!(
            r#"[model]
name = "loaded_cantilever"

[[beams]]
name = "beam"
order = 5
elements = 2
points = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]
root = "root"
tip = "tip"

[[beams.sections]]
station = 0.0
stiffness = [[1e7, 0.0, 0.0, 0.0, 0.0, 0.0], [0.0, 1e5, 0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1e5, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 5e3, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0, 1e4, 0.0], [0.0, 0.0, 0.0, 0.0, 0.0, 1e4]]

[[beams.loads]]
{load}

[[joints]]
name = "clamp"
type = "fixed"
node_a = "ground"
node_b = "root"

[[analyses]]
name = "static"
type = "static"
time = {time}
tolerance = 1e-14
relative_tolerance = 1e-12
"#
        )
    };
    let uniform = (
        q * l.powi(4) / (8.0 * ei) + q * l * l / (2.0 * kga),
        q * l.powi(3) / (6.0 * ei),
    );
    let cases = [
        (
            "uniform, dead",
            format!("force = [0.0, 0.0, {q}]"),
            0.0,
            uniform,
        ),
        (
            "uniform, follower",
            format!("force = [0.0, 0.0, {q}]\nframe = \"section\""),
            0.0,
            uniform,
        ),
        (
            "triangular",
            format!("force = [0.0, 0.0, {q}]\nprofile = [[0.0, 0.0], [1.0, 1.0]]"),
            0.0,
            (
                11.0 * q * l.powi(4) / (120.0 * ei) + q * l * l / (3.0 * kga),
                q * l.powi(3) / (8.0 * ei),
            ),
        ),
        (
            "uniform × table(0.25) = 0.5",
            format!(
                "force = [0.0, 0.0, {q}]\nfunction = {{ type = \"table\", points = [[0.0, 0.0], [1.0, 2.0]] }}"
            ),
            0.25,
            (0.5 * uniform.0, 0.5 * uniform.1),
        ),
        (
            "distributed moment",
            format!("moment = [0.0, {mm}, 0.0]"),
            0.0,
            (-mm * l.powi(3) / (3.0 * ei), -mm * l * l / (2.0 * ei)),
        ),
    ];
    for (what, load, time, (delta, theta)) in cases {
        let m = model(&text(&load, time));
        let (_, h) = run(&m);
        let (u, rot) = node_final(&m, &h, "tip");
        let rot = samara::math::log_map(&rot);
        let (ed, et) = (
            (u.z - delta).abs() / delta.abs(),
            (-rot.y - theta).abs() / theta.abs(),
        );
        println!(
            "{what}: δ = {:.10e} (closed form {delta:.10e}, {ed:.1e}), θ = {:.10e} ({theta:.10e}, {et:.1e})",
            u.z, -rot.y
        );
        assert!(ed < 1e-7 && et < 1e-7, "{what}");
        assert!(u.y.abs() < 1e-12 * delta.abs() && rot.x.abs() < 1e-12 && rot.z.abs() < 1e-12);
    }
    let m = model_file("examples/loaded_cantilever.toml");
    let (_, h) = run(&m);
    let (u, _) = node_final(&m, &h, "tip");
    let (e, g, a, i, k, q, l): (f64, f64, f64, f64, f64, f64, f64) = (
        7e10,
        2.6e10,
        1.6e-3,
        0.04f64.powi(4) / 12.0,
        5.0 / 6.0,
        50.0,
        2.0,
    );
    let delta = -(q * l.powi(4) / (8.0 * e * i) + q * l * l / (2.0 * k * g * a));
    let err = (u.z - delta).abs() / delta.abs();
    println!(
        "examples/loaded_cantilever.toml: tip {:.6e} m, closed form {delta:.6e} m, {err:.1e}",
        u.z
    );
    assert!(err < 1e-4, "{err:e}");
}

/// Extension–twist coupling: a section whose 6×6 stiffness couples axial strain and twist
/// (C₁₄ ≠ 0, as in a composite blade with ±θ plies) under a tip axial force F and a tip
/// torque T. The strains are uniform and, by the compliance, [ε₁; κ₁] = C⁻¹ [F; T]: the tip
/// moves u = ε₁ L along the axis and twists by φ = κ₁ L — a pull alone twists the beam.
/// Uniform extension and twist about the axis is an exact solution of the nonlinear
/// problem (the loads stay axial in the section frame), so only the element's
/// interpolation of a uniform twist remains: tolerance 1e-9 relative.
#[test]
fn extension_twist_coupling_matches_compliance() {
    let mut c = [[0.0; 6]; 6];
    for (i, v) in [1e6, 4e5, 4e5, 1e3, 2e3, 3e3].iter().enumerate() {
        c[i][i] = *v;
    }
    c[0][3] = 2.0e4;
    c[3][0] = 2.0e4;
    let cm = nalgebra::Matrix6::from_fn(|i, j| c[i][j]);
    let compliance = cm.try_inverse().unwrap();
    for (f, t) in [(100.0, 0.0), (0.0, 1.0), (100.0, -2.0)] {
        let m = model(&straight_cantilever(
            4,
            2,
            &c,
            Vector3::new(f, 0.0, 0.0),
            Vector3::new(t, 0.0, 0.0),
        ));
        let (_, h) = run(&m);
        let (u, q) = node_final(&m, &h, "tip");
        let e = compliance * nalgebra::Vector6::new(f, 0.0, 0.0, t, 0.0, 0.0);
        let phi = samara::math::log_map(&q).x;
        println!(
            "F = {f}, T = {t}: u = {:.12e} (C⁻¹: {:.12e}), φ = {:.12e} (C⁻¹: {:.12e})",
            u.x, e[0], phi, e[3]
        );
        let scale_u = e[0].abs().max(1e-300);
        let scale_p = e[3].abs().max(1e-300);
        assert!((u.x - e[0]).abs() < 1e-9 * scale_u);
        assert!((phi - e[3]).abs() < 1e-9 * scale_p);
        assert!(u.y.abs() < 1e-12 && u.z.abs() < 1e-12);
    }
}

/// Bathe–Bolourchi 45° bend along its load path: the tip displacement at P = 300, 450 and
/// 600 against the published load–displacement curves (Izzuddin & Elnashai 1993, digitized
/// points in `examples/verification/bd_curved_beam_load_path_reference.csv`, with the
/// source). Their beam is the isotropic 1 × 1 square (E = 1e7, ν = 0.3, torsion constant
/// 0.1406, shear factor 5/6). Tolerance: 3 % of the normal displacement per component —
/// the spread of the published solutions (Bathe–Bolourchi, Simo–Vu-Quoc, Izzuddin–
/// Elnashai differ by ~2 %) plus reading points off a figure (~0.5).
#[test]
fn bd_curved_beam_along_the_published_load_path() {
    let g = 1e7 / (2.0 * 1.3);
    let text = arc_model(8).replace("load_steps = 10", "load_steps = 20");
    let start = text.find("stiffness = ").unwrap();
    let end = start + text[start..].find('\n').unwrap();
    let text = format!(
        "{}isotropic = {{ E = 1e7, G = {g}, A = 1.0, I2 = 0.0833333333333333, I3 = 0.0833333333333333, J = 0.1406, shear_factors = [0.8333333333333334, 0.8333333333333334] }}{}",
        &text[..start],
        &text[end..]
    );
    let m = model(&text);
    let (_, h) = run(&m);
    // Reference curves: (component, u, P).
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/verification/bd_curved_beam_load_path_reference.csv");
    let csv = std::fs::read_to_string(path).unwrap();
    let mut curves: [Vec<(f64, f64)>; 3] = Default::default();
    for line in csv
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("component"))
    {
        let f: Vec<&str> = line.split(',').collect();
        let k = ["normal", "inplane_small", "inplane_large"]
            .iter()
            .position(|c| *c == f[0])
            .unwrap();
        curves[k].push((f[2].parse().unwrap(), f[1].parse().unwrap()));
    }
    let interp = |c: &[(f64, f64)], p: f64| -> f64 {
        let mut c = c.to_vec();
        c.sort_by(|a, b| a.0.total_cmp(&b.0));
        let i = c
            .windows(2)
            .position(|w| w[0].0 <= p && p <= w[1].0 && w[1].0 > w[0].0)
            .unwrap();
        let (a, b) = (c[i], c[i + 1]);
        a.1 + (b.1 - a.1) * (p - a.0) / (b.0 - a.0)
    };
    let tip = m.nodes.iter().position(|n| n.name == "tip").unwrap();
    let x0 = m.nodes[tip].position;
    for p in [300.0, 450.0, 600.0] {
        let f = h.at(p / 600.0).unwrap();
        assert!((f.load_factor - p / 600.0).abs() < 1e-9);
        let u = f.state.nodes[tip].x - x0;
        // The arc lies in the x-z plane, the load along y: normal = u_y; the in-plane
        // components are |u_x| (≈ 13 at 600) and u_z (≈ −23).
        let ours = [u.y, u.x.abs(), u.z];
        let refs = [
            interp(&curves[0], p),
            interp(&curves[1], p),
            interp(&curves[2], p),
        ];
        println!("P = {p}: tip {ours:.3?}, published {refs:.3?}");
        for k in 0..3 {
            assert!(
                (ours[k] - refs[k]).abs() < 0.03 * refs[0],
                "P = {p}, component {k}: {} vs {}",
                ours[k],
                refs[k]
            );
        }
    }
}
