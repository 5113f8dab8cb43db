//! The refinement seam: a method registered from outside eddy (here a dummy, a uniform velocity
//! kick) is read from a scene, validated, planned and run inside the SPH step like the built-in
//! ones, with no other change anywhere.

mod common;

use std::sync::atomic::{AtomicUsize, Ordering};

use eddy::pipeline::{Pipeline, Plan};
use eddy::refine::registry::{self, Interval, Method, MethodParams};
use eddy::refine::{StepContext, StepHook};
use eddy::state::{Persist, Restorer, Saver, StateError};
use eddy::{Real, Vec3};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Calls of the dummy's two hook points, over every test of this file.
static BEFORE: AtomicUsize = AtomicUsize::new(0);
static AFTER: AtomicUsize = AtomicUsize::new(0);

/// The dummy's keys: `speed`, added to every particle's x velocity each step.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
struct KickParams {
    speed: Real,
}

/// The dummy's one range.
const RANGES: registry::Ranges = &[("speed", Interval::open_closed(0.0, 10.0))];

impl MethodParams for KickParams {
    fn build(&self, _n: usize, _seed: u64) -> Box<dyn StepHook> {
        Box::new(Kick(self.speed))
    }
}

struct Kick(Real);

/// The kick carries nothing from one step to the next.
impl Persist for Kick {
    fn save(&self, _into: &mut Saver) {}

    fn restore(&mut self, _from: &Restorer) -> Result<(), StateError> {
        Ok(())
    }
}

impl StepHook for Kick {
    fn name(&self) -> &'static str {
        "refine"
    }

    fn describe(&self) -> String {
        format!("a uniform kick of {} m/s along x", self.0)
    }

    fn before_advection(&mut self, _ctx: &StepContext, v: &mut [Vec3], _accel: &mut [Vec3]) {
        BEFORE.fetch_add(1, Ordering::SeqCst);
        for v in v {
            v.x += self.0;
        }
    }

    fn after_pressure(&mut self, _ctx: &StepContext, _v: &mut [Vec3]) {
        AFTER.fetch_add(1, Ordering::SeqCst);
    }
}

fn register_kick() {
    // Tests of one binary share the registry: the first registers, the others find it.
    if registry::find("kick").is_none() {
        let _ = registry::register(Method::new::<KickParams>("kick", "a test's dummy", RANGES));
    }
}

/// A block of water floating in an empty domain without gravity: its momentum changes only
/// through the refinement.
fn scene_text(refinement: &str) -> String {
    format!(
        "name = \"kick\"\ngravity = [0.0, 0.0, 0.0]\n[domain]\nmin = [-1.0, -1.0, -1.0]\n\
         max = [1.0, 1.0, 1.0]\n[time]\nsteps = 1\ndt = 1e-3\n[fluid]\nspacing = 0.05\n\
         [[fluid.blocks]]\nmin = [-0.2, -0.2, -0.2]\nmax = [0.2, 0.2, 0.2]\n[output]\n\
         vtk = false\nmetrics = []\n[refinement]\n{refinement}\n"
    )
}

fn load(refinement: &str) -> Result<eddy::scene::Scene, String> {
    eddy::scene::parse_str(
        &scene_text(refinement),
        std::path::Path::new("kick.toml"),
        &[],
    )
    .map_err(|e| e.to_string())
}

#[test]
fn a_registered_method_loads_plans_and_runs_one_step() {
    register_kick();
    let scene = load("method = \"kick\"\nspeed = 0.5").expect("the scene loads");
    assert_eq!(scene.refinement.method(), "kick");
    assert_eq!(
        toml::to_string(&scene.refinement).expect("writes"),
        "method = \"kick\"\nspeed = 0.5\n",
        "the resolved scene.toml writes the method back"
    );

    let mut p = Pipeline::build(&scene).expect("the pipeline builds");
    let plan = Plan::of(&p);
    let sph = plan.stages.iter().find(|s| s.name == "sph").expect("sph");
    assert!(
        sph.parts
            .iter()
            .any(|(name, line)| *name == "refine" && line.contains("uniform kick of 0.5")),
        "{sph:?}"
    );

    let momentum = |p: &Pipeline| -> Vec3 {
        let fluid = &p.sim.sph.as_ref().expect("fluid").fluid;
        fluid.v.iter().sum::<Vec3>() / fluid.v.len() as Real
    };
    assert_eq!(momentum(&p), Vec3::zeros(), "the block starts at rest");
    let (before, after) = (BEFORE.load(Ordering::SeqCst), AFTER.load(Ordering::SeqCst));
    p.step(None, None).expect("one step");
    assert_eq!(BEFORE.load(Ordering::SeqCst), before + 1);
    assert_eq!(AFTER.load(Ordering::SeqCst), after + 1);
    // Pressure forces between fluid particles cancel in pairs, so the mean velocity is the
    // kick's, whatever the pressure solve did inside the block.
    let mean = momentum(&p);
    assert!(
        (mean - Vec3::new(0.5, 0.0, 0.0)).norm() < 1e-9,
        "mean velocity {mean:?}"
    );
}

#[test]
fn a_registered_method_s_keys_and_ranges_are_its_own() {
    register_kick();
    let e = load("method = \"kick\"\nspeed = 20.0").expect_err("out of range");
    for needle in ["kick.toml", "refinement.speed", "20", "(0, 10]", "\"kick\""] {
        assert!(e.contains(needle), "{e} lacks {needle}");
    }
    let e = load("method = \"kick\"\nspeed = 1.0\nalpha = 1.0").expect_err("unknown key");
    assert!(
        e.contains("unknown key `alpha`") && e.contains("`speed`"),
        "{e}"
    );
    let e = load("method = \"kick\"").expect_err("speed has no default");
    assert!(e.contains("missing key `speed`"), "{e}");
}

#[test]
fn a_taken_name_is_refused() {
    register_kick();
    for name in ["none", "vrsph", "kick"] {
        let e = registry::register(Method::new::<KickParams>(name, "again", RANGES))
            .expect_err("taken");
        assert!(e.contains(name), "{e}");
    }
}

/// Every method file of `src/refine/` (one declaring `pub const METHOD`) is in the registry's
/// table under its file's name: a new method cannot be left out of it.
#[test]
fn every_method_file_is_in_the_table() {
    let declared = common::files_declaring("refine", "pub const METHOD: Method");
    let mut built_in: Vec<String> = registry::BUILT_IN
        .iter()
        .map(|m| m.name.to_owned())
        .collect();
    built_in.sort();
    assert_eq!(declared, built_in);
}

/// Ranges name numeric keys of their method: a range on a missing key is refused when the
/// method registers, and every built-in method's ranges pass the same check.
#[test]
fn ranges_name_numeric_keys() {
    const WRONG: registry::Ranges = &[("sped", Interval::gt(0.0))];
    let e = registry::register(Method::new::<KickParams>("kick_typo", "a typo", WRONG))
        .expect_err("no such key");
    assert!(e.contains("`sped`"), "{e}");
    for method in &registry::BUILT_IN {
        method.verify().expect("built-in ranges name numeric keys");
    }
}
