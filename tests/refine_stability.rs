//! The refinements in a running solver, on the small sloshing tank of
//! `scenes/refine_sloshing.toml` (750 fluid particles): each refinement's change vanishes with
//! its coefficient (zero changes nothing, and the change is a power of the coefficient with no
//! constant part), and at the papers' defaults every method stays finite and in the tank (in
//! front of its walls' boundary samples) for 5 000 steps while VRSPH (alpha = 1) and Rankine
//! (beta = 1) settle to DFSPH's kinetic energy.
//!
//! Each run gets a one-thread pool, so runs are bit-reproducible (parallel sums would otherwise
//! round differently from run to run) and several runs share the cores.

use eddy::metrics;
use eddy::pipeline::sph_solver;
use eddy::scene;
use eddy::sph::boundary::MIRROR_DEPTH;
use eddy::state::{Persist, State};
use eddy::{Real, Vec3};
use std::path::Path;

/// What a run left behind.
struct Trace {
    x: Vec<Vec3>,
    v: Vec<Vec3>,
    /// Kinetic energy after every step.
    kinetic: Vec<Real>,
}

/// Runs the sloshing tank for `steps` steps with the given overrides, checking every 50 steps
/// that all fluid particles are inside the tank.
fn run(overrides: &[String], steps: u64) -> Result<Trace, String> {
    run_from(overrides, None, steps)
}

/// [`run`] from the fluid state `start` when given ([`warmed`]; the refinement's own state
/// starts afresh), else from the scene's block at rest.
fn run_from(overrides: &[String], start: Option<&State>, steps: u64) -> Result<Trace, String> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .map_err(|e| e.to_string())?;
    pool.install(|| {
        let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/refine_sloshing.toml");
        let scene = scene::load(&file, overrides).map_err(|e| e.to_string())?;
        let mut s = sph_solver(&scene).map_err(|e| e.to_string())?;
        if let Some(start) = start {
            s.fluid
                .restore(&start.read("fluid"))
                .map_err(|e| e.to_string())?;
            s.update_neighborhoods();
        }
        let mut kinetic = Vec::new();
        for step in 0..steps {
            s.step(scene.time.end)
                .map_err(|e| format!("{overrides:?}: {e}"))?;
            kinetic.push(metrics::kinetic_energy(s.fluid.mass, &s.fluid.v));
            if step % 50 == 0 || step + 1 == steps {
                // A splash particle alone at a wall is pushed back only where the wall's
                // density alone reaches the rest density, a little past the surface; it has
                // left the tank once it is behind the wall's samples.
                let tank = [0.5, 0.4, 0.1];
                let behind = MIRROR_DEPTH * s.spacing;
                if let Some(x) = s
                    .fluid
                    .x
                    .iter()
                    .find(|x| (0..3).any(|a| x[a] < -behind || x[a] > tank[a] + behind))
                {
                    return Err(format!(
                        "{overrides:?}: left the tank at {x:?}, step {step}"
                    ));
                }
            }
        }
        Ok(Trace {
            x: s.fluid.x.clone(),
            v: s.fluid.v.clone(),
            kinetic,
        })
    })
}

/// The sloshing tank's fluid state after `steps` steps of the plain `solver`, saved as a
/// checkpoint saves it.
fn warmed(solver: &str, steps: u64) -> State {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/refine_sloshing.toml");
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool");
    pool.install(|| {
        let scene = scene::load(&file, &with(solver, &[])).expect("scene");
        let mut s = sph_solver(&scene).expect("solver");
        for _ in 0..steps {
            s.step(scene.time.end).expect("stable");
        }
        let mut state = State::new();
        s.fluid.save(&mut state.section("fluid"));
        state
    })
}

fn with(solver: &str, refinement: &[&str]) -> Vec<String> {
    let mut o = vec![format!("pressure.solver=\"{solver}\"")];
    o.extend(refinement.iter().map(|s| s.to_string()));
    o
}

/// Runs several configurations on two threads at once.
fn run_all(configs: &[Vec<String>], steps: u64) -> Vec<Result<Trace, String>> {
    std::thread::scope(|scope| {
        let handles: Vec<_> = configs
            .chunks(configs.len().div_ceil(2))
            .map(|chunk| {
                scope.spawn(move || chunk.iter().map(|c| run(c, steps)).collect::<Vec<_>>())
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().expect("run thread"))
            .collect::<Vec<_>>()
    })
}

/// Steps of each run of [`zero_parameters_leave_the_solvers_unchanged`]: Rankine and VRSPH
/// record the vorticity at their first step and act from the second.
const STEPS: u64 = 3;

/// The refinements' formulas vanish with their coefficients, not only through the early
/// return each method takes at exactly zero (`if beta == 0.0 { return }` and the like in
/// `src/refine/`). From the same sloshing state (150 plain steps, so the flow carries
/// vorticity and the start's lattice is gone), each method runs [`STEPS`] steps at zero and at
/// the coefficient c, 2c and 3c, with DFSPH and with IISPH; D(c) is the difference from the
/// plain solver's run, over all positions or all velocities:
///
/// - at zero, D = 0 to 1e-12 (the early return);
/// - D(3c) - 3 D(2c) + 3 D(c) = D(0) for any D quadratic in c: this extrapolation of the
///   change to c = 0 is under 2 % of |D(c)| (measured 0.16–0.81 %); a term the coefficient
///   does not multiply would leave it near 100 %;
/// - |D(2c)| / |D(c)| is the formula's power of c within 1 % (measured within 0.24 %): 2 for
///   VRSPH's alpha curl(psi) (Liu et al. 2021, Alg. 2), MCVSPH's volume coefficient c (Ye et
///   al., Eq. 24, the strengths of Eq. 26) and confinement's epsilon; 4 for Rankine, whose
///   induced velocity is r_c^2 / (2 r) outside the core (Wang et al. 2020, Eq. 15) with
///   r_c = beta sqrt(4 alpha nu dt) (Eq. 11; at most 8.5e-4 m here, under its cap and inside
///   every pair); for micropolar, whose force (nu + nu_t) curl(omega) carries omega ~ nu_t,
///   2 (1 + 2 r) / (1 + r) with r = nu_t / nu;
/// - |D(c)| of the velocities is above 1e-5 m/s (measured 3.6e-5 to 2.6e-4), ten times what
///   rounding alone leaves: any change of the positions rounds the solvers' single-precision
///   pair gradients (`sph::pair_cache`) and the refinements' packed fields afresh, which is
///   the 3e-7 to 9e-7 m/s left in the extrapolation above.
///
/// The coefficients keep each change small enough to stay linear: at five times confinement's
/// epsilon here, N = grad|omega| / |grad|omega|| turned where that gradient nearly vanishes and
/// |D(2c)| was 10 |D(c)|. The runs start from a flowing state because the block at rest is not
/// smooth in its positions: its lattice pairs sit at exactly the kernel support (two
/// spacings), so moving the particles by 1e-13 m after the first step changed 287 neighbour
/// counts, 8 of them across DFSPH's `MIN_NEIGHBORS_FOR_DIVERGENCE`, and MCVSPH at c = 5e-8 and
/// at 5e-4 both changed the velocities by 1.13e-3 m/s (in norm) after two steps: the solver's
/// start, not the formula.
#[test]
fn zero_parameters_leave_the_solvers_unchanged() {
    // (method, key, c, the expected |D(2c)| / |D(c)|).
    let nu = 0.01; // the scene's viscosity.kinematic
    let nu_t = 2e-3;
    let r = nu_t / nu;
    let methods: [(&str, &str, Real, Real); 5] = [
        ("rankine", "beta", 0.02, 4.0),
        ("vrsph", "alpha", 2e-3, 2.0),
        ("mcvsph", "volume_coefficient", 2.5e-4, 2.0),
        (
            "micropolar",
            "nu_t",
            nu_t,
            2.0 * (1.0 + 2.0 * r) / (1.0 + r),
        ),
        ("confinement", "epsilon", 2e-4, 2.0),
    ];
    for solver in ["dfsph", "iisph"] {
        let start = warmed(solver, 150);
        let mut configs = vec![with(solver, &["refinement.method=\"none\""])];
        for (method, key, c, _) in methods {
            for k in [0.0, 1.0, 2.0, 3.0] {
                configs.push(with(
                    solver,
                    &[
                        &format!("refinement.method=\"{method}\""),
                        &format!("refinement.{key}={:e}", k * c),
                    ],
                ));
            }
        }
        let traces: Vec<Trace> = configs
            .iter()
            .map(|c| run_from(c, Some(&start), STEPS).expect("stable"))
            .collect();
        let plain = &traces[0];
        assert!(plain.kinetic.iter().all(|&e| e > 1e-3), "the tank sloshes");
        for (m, (method, _, c, power)) in methods.iter().enumerate() {
            let runs = &traces[1 + 4 * m..5 + 4 * m];
            for (what, velocity) in [("x", false), ("v", true)] {
                let pick = |t: &'_ Trace| if velocity { t.v.clone() } else { t.x.clone() };
                let d: Vec<Vec<Vec3>> = runs
                    .iter()
                    .map(|t| {
                        let (a, b) = (pick(t), pick(plain));
                        a.iter().zip(&b).map(|(a, b)| a - b).collect()
                    })
                    .collect();
                let norm = |d: &[Vec3]| d.iter().map(|d| d.norm_squared()).sum::<Real>().sqrt();
                let largest = d[0].iter().map(|d| d.norm()).fold(0.0, Real::max);
                let at_zero: Vec<Vec3> = (0..d[1].len())
                    .map(|i| d[3][i] - 3.0 * d[2][i] + 3.0 * d[1][i])
                    .collect();
                let (size, ratio) = (norm(&d[1]), norm(&d[2]) / norm(&d[1]));
                let extrapolated = norm(&at_zero) / size;
                println!(
                    "{solver} {method} (c = {c:e}) {what}: |D(c)| {size:.3e}, |D(2c)| / |D(c)| \
                     {ratio:.5} (expected {power:.5}), extrapolated to zero {extrapolated:.2e} |D(c)|"
                );
                assert!(
                    largest <= 1e-12,
                    "{solver} {method} at zero: {what} moved {largest:e}"
                );
                assert!(
                    extrapolated < 0.02,
                    "{solver} {method} {what}: extrapolated to zero {extrapolated:e} of |D(c)|"
                );
                assert!(
                    (ratio / power - 1.0).abs() < 0.01,
                    "{solver} {method} {what}: |D(2c)| / |D(c)| = {ratio}, expected {power}"
                );
                if velocity {
                    assert!(size > 1e-5, "{solver} {method}: |D(c)| = {size:e} m/s");
                }
            }
        }
    }
}

/// Every method at its paper default runs 5 000 steps (about 25 s of sloshing) without a
/// non-finite value or a particle leaving the tank; after the motion settles (the last 1 000
/// steps), the mean kinetic energy with VRSPH at alpha = 1 and Rankine at beta = 1 is within
/// 3 % of DFSPH's peak kinetic energy of DFSPH's own settled value (the papers' claim that
/// these two add no energy, Liu et al. Fig. 7, Wang et al. Fig. 11).
#[test]
fn every_method_is_stable_and_vrsph_and_rankine_settle_like_dfsph() {
    let methods: [&[&str]; 6] = [
        &["refinement.method=\"none\""],
        &["refinement.method=\"rankine\"", "refinement.beta=1.0"],
        &["refinement.method=\"vrsph\"", "refinement.alpha=1.0"],
        &["refinement.method=\"mcvsph\""],
        &["refinement.method=\"micropolar\""],
        &["refinement.method=\"confinement\""],
    ];
    let configs: Vec<Vec<String>> = methods.iter().map(|r| with("dfsph", r)).collect();
    let traces = run_all(&configs, 5000);
    for t in &traces {
        if let Err(e) = t {
            panic!("{e}");
        }
    }
    let settled = |t: &Trace| t.kinetic[4000..].iter().sum::<Real>() / 1000.0;
    let plain = traces[0].as_ref().expect("checked");
    let peak = plain.kinetic.iter().copied().fold(0.0, Real::max);
    for (config, t) in configs.iter().zip(&traces).take(3).skip(1) {
        let t = t.as_ref().expect("checked");
        let gap = (settled(t) - settled(plain)).abs();
        assert!(
            gap < 0.03 * peak,
            "{config:?}: settled KE {:.3e} J vs DFSPH {:.3e} J (peak {peak:.3e} J)",
            settled(t),
            settled(plain)
        );
    }
}
