//! The advection seam: a scheme registered from outside eddy (here a dummy that carries
//! nothing) is named by a scene, listed by the scene reference, labelled in the plan and called
//! by the grid's step like the built-in ones, with no other change anywhere.

mod common;

use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Once;

use eddy::grid::advect::{self, Advection, Band, Scheme};
use eddy::grid::{MacGrid, Stagger};
use eddy::pipeline::{Pipeline, Plan};
use eddy::Real;
use ndarray::Array3;

/// The dummy's name in scene files.
const NAME: &str = "carry_nothing";

/// Calls of the dummy's step, by every test of the binary.
static CALLS: AtomicUsize = AtomicUsize::new(0);

/// Leaves every field where it is: `out` is `field` (the smoke's band is the whole grid).
fn carry_nothing(
    field: &Array3<Real>,
    _stagger: Stagger,
    _vel: &MacGrid,
    _dt: Real,
    _band: &Band,
    out: &mut Array3<Real>,
) {
    CALLS.fetch_add(1, Ordering::SeqCst);
    out.assign(field);
}

fn register_dummy() {
    // Tests of one binary share the registry: the first to get here registers.
    static REGISTERED: Once = Once::new();
    REGISTERED.call_once(|| {
        advect::register(Scheme {
            name: NAME,
            label: "carry-nothing",
            summary: "A test's dummy that carries nothing.",
            advect: carry_nothing,
        })
        .expect("the dummy's name is free");
    });
}

/// Smoke in a uniform stream of 1 m/s along x, periodic on every side, no sources or buoyancy.
fn scene(advection: &str) -> Result<eddy::scene::Scene, String> {
    let text = format!(
        r#"
name = "still_smoke"
gravity = [0.0, 0.0, 0.0]
[domain]
min = [0.0, 0.0, 0.0]
max = [1.0, 0.25, 0.25]
[time]
dt_max = 0.01
steps = 1
[grid]
resolution = [16, 4, 4]
advection = "{advection}"
initial_velocity = [1.0, 0.0, 0.0]
[grid.smoke]
sources = []
buoyancy = 0.0
[grid.boundary]
x_min = "periodic"
x_max = "periodic"
y_min = "periodic"
y_max = "periodic"
z_min = "periodic"
z_max = "periodic"
[output]
vtk = false
metrics = []
"#
    );
    eddy::scene::parse_str(&text, Path::new("still_smoke.toml"), &[]).map_err(|e| e.to_string())
}

/// The smoke density of a pipeline's grid.
fn density(pipeline: &mut Pipeline) -> &mut Array3<Real> {
    let grid = pipeline.sim.grid.as_mut().expect("a grid");
    &mut grid.smoke.as_mut().expect("smoke").density
}

/// The x centroid of a smoke blob at x = 0.4 m after one step with `advection`, whether the
/// smoke is exactly as it was, and the step's dt.
fn step_blob(advection: &str) -> (Real, bool, Real) {
    let scene = scene(advection).expect("the scene loads");
    let mut pipeline = Pipeline::build(&scene).expect("builds");
    let dx = pipeline.sim.grid.as_ref().expect("a grid").mac.dx;
    let x = |i: usize| (i as Real + 0.5) * dx;
    let blob = density(&mut pipeline);
    *blob = Array3::from_shape_fn(blob.raw_dim(), |(i, _, _)| {
        (-(x(i) - 0.4).powi(2) / (2.0 * 0.08f64.powi(2))).exp()
    });
    let before = blob.clone();
    let dt = pipeline.step(None, None).expect("steps").dt;
    let after = density(&mut pipeline);
    let (mut m0, mut m1) = (0.0, 0.0);
    for ((i, _, _), &v) in after.indexed_iter() {
        m0 += v;
        m1 += v * x(i);
    }
    (m1 / m0, *after == before, dt)
}

#[test]
fn a_registered_scheme_is_loaded_listed_planned_and_stepped() {
    register_dummy();
    let chosen = scene(NAME).expect("the scene loads");
    let advection = chosen.grid.as_ref().expect("a grid").advection;
    assert_eq!(Some(advection), advect::find(NAME));
    assert_eq!(advection.label(), "carry-nothing");
    let written = toml::to_string(&chosen).expect("the scene writes back");
    assert!(
        written.contains(&format!("advection = \"{NAME}\"")),
        "{written}"
    );

    let row = eddy::scene::reference::rows()
        .into_iter()
        .find(|r| r.key == "grid.advection")
        .expect("the reference lists grid.advection");
    assert!(row.allowed.contains(&format!("\"{NAME}\"")), "{row:?}");
    assert!(row.details.contains("A test's dummy"), "{row:?}");

    let plan = Plan::of(&Pipeline::build(&chosen).expect("builds")).to_string();
    assert!(
        plan.contains("carry-nothing advection of velocity and smoke density"),
        "{plan}"
    );

    let calls = CALLS.load(Ordering::SeqCst);
    let (still, unchanged, _) = step_blob(NAME);
    assert!(CALLS.load(Ordering::SeqCst) > calls, "the dummy was called");
    assert!(unchanged, "the dummy leaves the smoke exactly where it was");
    // The built-in scheme carries it 1 m/s over the step.
    let (moved, unchanged, dt) = step_blob(Advection::MACCORMACK.name());
    assert!(!unchanged);
    assert!(
        (moved - still - dt).abs() < 0.1 * dt,
        "{moved} against {still} + {dt}"
    );
}

#[test]
fn an_unknown_scheme_is_refused_with_the_names_there_are() {
    register_dummy();
    let e = scene("carry_nothin").expect_err("refused");
    for needle in [
        "grid.advection",
        "`carry_nothin`",
        "`semi_lagrangian`",
        "`maccormack`",
        "`carry_nothing`",
    ] {
        assert!(e.contains(needle), "{e} lacks {needle}");
    }
}

#[test]
fn a_taken_name_is_refused() {
    register_dummy();
    for name in ["semi_lagrangian", "maccormack", NAME] {
        let e = advect::register(Scheme {
            name,
            label: "again",
            summary: "Again.",
            advect: carry_nothing,
        })
        .expect_err("a taken name");
        assert!(e.contains(name), "{e}");
    }
    assert_eq!(advect::schemes().len(), 3, "nothing was added");
}

/// Every scheme file of `src/grid/advect/` (one declaring `static SCHEME: Scheme`) is in the
/// registry's table under its file's name: a new scheme cannot be left out of it.
#[test]
fn every_scheme_file_is_in_the_table() {
    let declared = common::files_declaring("grid/advect", "static SCHEME: Scheme");
    let mut built_in: Vec<&str> = advect::BUILT_IN.iter().map(|s| s.name).collect();
    built_in.sort();
    assert_eq!(declared, built_in);
}
