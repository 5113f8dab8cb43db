//! Checkpoint and restart of the SPH solver: a solver saved between steps and restored into
//! one freshly built from the same scene steps on exactly as the one that never stopped, bit
//! for bit, through open boundaries, moving bodies, both pressure solvers and every
//! refinement; and a damaged state is refused with an error.
//!
//! Each pair of runs gets a one-thread pool: parallel sums round differently from run to run,
//! so only a serial run is bit-reproducible at all.

use std::path::Path;

use eddy::pipeline::sph_solver;
use eddy::scene::{self, Scene};
use eddy::sph::SphSolver;
use eddy::state::{Persist, State, StateError, Values};
use eddy::stepping::towards_end;
use eddy::Real;

/// Steps land on multiples of this, as a run's land on its frame times: the shortened steps
/// change dt, so the warm starts are rescaled on both sides of a checkpoint.
const FRAME: Real = 0.012;

/// A shipped scene with `--set`-style overrides.
fn shipped(file: &str, overrides: &[&str]) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(file);
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    scene::load(&path, &overrides).expect("the scene loads")
}

/// One step as `Pipeline::step` takes it in an SPH scene: the stable step shortened to land on
/// the next frame time, the `sph` stage (`advance`), then the `neighbours` stage.
fn step(s: &mut SphSolver) {
    let dt = s.stable_dt().expect("a stable step");
    let next_frame = ((s.time() / FRAME + 1e-9).floor() + 1.0) * FRAME;
    s.advance(towards_end(dt, next_frame - s.time()))
        .expect("the step runs");
    s.update_neighborhoods();
}

/// The solver's state, saved as a checkpoint saves it.
fn saved(s: &SphSolver) -> State {
    let mut state = State::new();
    s.save(&mut state.section("sph"));
    state
}

/// Bits of every value, so that 0.0 and -0.0 differ and NaN equals itself.
fn bits(values: &Values) -> Vec<u64> {
    match values {
        Values::F64(v) => v.iter().map(|x| x.to_bits()).collect(),
        Values::U64(v) => v.clone(),
        Values::I64(v) => v.iter().map(|&x| x as u64).collect(),
        Values::U8(v) => v.iter().map(|&x| x.into()).collect(),
    }
}

fn real_bits(v: &[Real]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

/// Asserts that two solvers hold the same state bit for bit: every stored entry (particles,
/// warm starts, moving samples, emitters, counters, the hooks' state), the pressure (which
/// only the outputs read), what the neighbourhood update recomputes from it (densities, DFSPH
/// factors), the hooks' output fields and the counts.
fn assert_same(a: &SphSolver, b: &SphSolver, when: &str) {
    assert_eq!(a.fluid.len(), b.fluid.len(), "{when}: particle counts");
    assert_eq!(a.lost_particles(), b.lost_particles(), "{when}: lost");
    assert_eq!(a.steps(), b.steps(), "{when}: steps");
    let (sa, sb) = (saved(a), saved(b));
    let names = |s: &State| s.entries().map(|(k, _)| k.to_owned()).collect::<Vec<_>>();
    assert_eq!(names(&sa), names(&sb), "{when}: entries");
    for ((name, va), (_, vb)) in sa.entries().zip(sb.entries()) {
        assert!(bits(va) == bits(vb), "{when}: {name} differs");
    }
    let fields = [
        ("pressure", &a.fluid.pressure, &b.fluid.pressure),
        ("density", &a.fluid.density, &b.fluid.density),
        (
            "density ratio",
            &a.density_ratios().to_vec(),
            &b.density_ratios().to_vec(),
        ),
        ("factor", &a.factors().to_vec(), &b.factors().to_vec()),
    ];
    for (name, fa, fb) in fields {
        assert!(real_bits(fa) == real_bits(fb), "{when}: {name} differs");
    }
    let hook_fields = |s: &SphSolver| {
        let fields = s.refinement_fields();
        let flat = fields
            .iter()
            .flat_map(|(_, f)| f.iter().flat_map(|v| v.iter().copied()));
        real_bits(&flat.collect::<Vec<_>>())
    };
    assert!(
        hook_fields(a) == hook_fields(b),
        "{when}: hook fields differ"
    );
    assert_eq!(
        a.rotational_energy().to_bits(),
        b.rotational_energy().to_bits(),
        "{when}: rotational energy"
    );
}

/// Steps `scene` `before` steps, checkpoints it into a fresh solver, then steps both `after`
/// more and checks they agree bit for bit. Returns the particle counts after every step of
/// the run that did not stop, for the callers' checks on what happened around the checkpoint.
fn restart_matches(scene: &Scene, before: usize, after: usize) -> Vec<usize> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a pool");
    pool.install(|| {
        let mut a = sph_solver(scene).expect("builds");
        let mut counts = vec![a.fluid.len()];
        for _ in 0..before {
            step(&mut a);
            counts.push(a.fluid.len());
        }
        let state = saved(&a);
        let mut b = sph_solver(scene).expect("builds");
        b.restore(&state.read("sph")).expect("restores");
        assert_same(&a, &b, "restored");
        for k in 0..after {
            step(&mut a);
            step(&mut b);
            assert_same(&a, &b, &format!("step {k} after the restart"));
            counts.push(a.fluid.len());
        }
        counts
    })
}

/// Whether the count rose at some step and fell at another among `counts`: an inflow layer
/// entered and the outflow removed particles (a layer and a column are tens of particles, half
/// a period apart, so neither hides the other).
fn emitted_and_removed(counts: &[usize]) -> bool {
    let rose = counts.windows(2).any(|w| w[1] > w[0]);
    let fell = counts.windows(2).any(|w| w[1] < w[0]);
    rose && fell
}

/// The river of `scenes/abl_sph_river_quick.toml` without its pillars and their boundary
/// layers (they need a database the tests do not build), at 5 cm, with MCVSPH, whose generator draws the
/// vortex particles of entering fluid: layers enter at the inflow and columns leave through
/// the outflow before the checkpoint and after it.
#[test]
fn the_river_restarts_bit_for_bit_through_its_inflow_and_outflow() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/abl_sph_river_quick.toml");
    let text = std::fs::read_to_string(&path).expect("the river scene");
    let kept: Vec<&str> = text
        .split("\n\n")
        .filter(|b| !b.contains("name = \"pillar_") && !b.contains("[turbulence]"))
        .collect();
    let overrides = [
        "fluid.spacing=0.05",
        "refinement.method=\"mcvsph\"",
        "refinement.sample_fraction=0.1",
    ]
    .map(String::from);
    let scene = scene::parse_str(&kept.join("\n\n"), &path, &overrides).expect("the river");
    let (before, after) = (28, 28);
    let counts = restart_matches(&scene, before, after);
    assert!(
        emitted_and_removed(&counts[..=before]) && emitted_and_removed(&counts[before..]),
        "no inflow layer or no outflow removal on one side of the checkpoint: {counts:?}"
    );
}

/// Every refinement on the sloshing tank of `scenes/refine_sloshing.toml`, restarted after its
/// state has built up (the vorticity of the last step, angular velocities, vortex particles).
#[test]
fn every_refinement_restarts_bit_for_bit() {
    for method in ["rankine", "vrsph", "mcvsph", "micropolar", "confinement"] {
        let scene = shipped(
            "refine_sloshing.toml",
            &[&format!("refinement.method=\"{method}\"")],
        );
        restart_matches(&scene, 12, 8);
    }
}

/// DFSPH and IISPH around the moving rod of `scenes/refine_stirring_rod.toml` at 4 cm: the
/// warm starts and the rod's samples, whose order after 30 re-sorts is no longer that of
/// samples placed afresh (it was after 12, and the restart fails by 20 without it stored).
#[test]
fn both_pressure_solvers_restart_bit_for_bit_around_a_moving_body() {
    for solver in ["dfsph", "iisph"] {
        let scene = shipped(
            "refine_stirring_rod.toml",
            &["fluid.spacing=0.04", &format!("pressure.solver={solver}")],
        );
        restart_matches(&scene, 30, 8);
    }
}

/// A state with an entry missing, too short, or out of range is refused with the entry's
/// name, and nothing panics.
#[test]
fn a_damaged_state_is_refused() {
    let scene = shipped(
        "refine_stirring_rod.toml",
        &["fluid.spacing=0.04", "refinement.method=\"micropolar\""],
    );
    let mut s = sph_solver(&scene).expect("builds");
    step(&mut s);
    let state = saved(&s);
    let altered = |name: &str, values: Option<Values>| {
        let mut out = State::new();
        for (k, v) in state.entries().filter(|(k, _)| *k != name) {
            out.insert(k.to_owned(), v.clone());
        }
        if let Some(values) = values {
            out.insert(name.to_owned(), values);
        }
        let mut fresh = sph_solver(&scene).expect("builds");
        fresh
            .restore(&out.read("sph"))
            .expect_err("a damaged state")
    };
    assert_eq!(
        altered("sph/fluid/kappa", None),
        StateError::Missing("sph/fluid/kappa".into())
    );
    let short = |name: &str| match state.entries().find(|(k, _)| *k == name) {
        Some((_, Values::F64(v))) => Some(Values::F64(v[3..].to_vec())),
        _ => panic!("the state has {name}"),
    };
    let wrong_lengths = [
        ("sph/fluid/v", "sph/fluid/v"),
        ("sph/boundary/x", "sph/boundary/x"),
        // The hook takes any count; the solver checks it against the fluid's.
        ("sph/hooks/0_refine/omega", "sph/hooks/0_refine"),
    ];
    for (entry, named) in wrong_lengths {
        let e = altered(entry, short(entry));
        assert!(
            matches!(&e, StateError::Mismatch { name, .. } if name == named),
            "{entry}: {e}"
        );
    }
    let e = altered(
        "sph/boundary/body",
        Some(Values::U64(vec![99; s.boundary.len()])),
    );
    assert!(e.to_string().contains("body index 99"), "{e}");
    let e = altered("sph/lost/by_side", Some(Values::U64(vec![0; 5])));
    assert!(e.to_string().contains("sph/lost/by_side"), "{e}");
}
