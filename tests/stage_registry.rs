//! The stage seam: a stage registered from outside eddy (here a dummy that counts the steps it
//! ran and the fluid's kinetic energy change over the step, as two columns of the fluid's
//! metrics) is asked for by a scene, placed in its slot of the step, planned, run every step
//! and written by the metrics stage like the built-in ones, with no other change anywhere.

use std::path::Path;

use eddy::io::plot::RunSeries;
use eddy::pipeline::{
    register_stage, stage_kinds, AddedColumns, Built, Kind, Pipeline, Plan, RunOptions, RunSpec,
    Simulation, Slot, Stage, StageKind, StepError, StepRecord,
};

/// Counts its runs and measures the kinetic energy the fluid gained since the last one.
struct Dummy {
    runs: u64,
    energy: f64,
}

fn kinetic_energy(sim: &Simulation) -> f64 {
    let fluid = &sim.sph.as_ref().expect("a fluid").fluid;
    let m = fluid.mass;
    fluid.v.iter().map(|v| 0.5 * m * v.norm_squared()).sum()
}

impl Stage for Dummy {
    fn name(&self) -> &'static str {
        "dummy"
    }

    fn describe(&self, _sim: &Simulation) -> (String, Vec<(&'static str, String)>) {
        ("counts its runs".into(), Vec::new())
    }

    fn run(&mut self, sim: &mut Simulation, rec: &mut StepRecord) -> Result<(), StepError> {
        self.runs += 1;
        let energy = kinetic_energy(sim);
        rec.added.push((
            Kind::Particles,
            vec![self.runs as f64, energy - self.energy],
        ));
        self.energy = energy;
        Ok(())
    }

    fn measures_only(&self) -> bool {
        true
    }

    fn added_columns(&self, _sim: &Simulation) -> Option<AddedColumns> {
        Some(AddedColumns {
            to: Kind::Particles,
            names: vec!["dummy_runs".into(), "dummy_energy_gain".into()],
            note: "the dummy's runs and the kinetic energy gained over the step",
        })
    }
}

fn build(spec: &RunSpec, sim: &mut Simulation) -> Built {
    let asked = spec.stages.iter().any(|s| s == "dummy");
    Ok((asked && sim.sph.is_some()).then(|| {
        Box::new(Dummy {
            runs: 0,
            energy: kinetic_energy(sim),
        }) as Box<dyn Stage>
    }))
}

fn register_dummy() {
    // Tests of one binary share the registry: the first registers, the others find it.
    if !stage_kinds().iter().any(|k| k.name == "dummy") {
        let _ = register_stage(StageKind {
            name: "dummy",
            summary: "a test's dummy",
            slot: Slot::AfterStep,
            build,
        });
    }
}

/// A block of water falling from rest for 10 steps of 1 ms, with the kinetic energy among
/// its metrics.
fn scene(stages: &str) -> Result<eddy::scene::Scene, String> {
    let text = format!(
        "name = \"dummy\"\nstages = {stages}\n[domain]\nmin = [-1.0, -1.0, -1.0]\n\
         max = [1.0, 1.0, 1.0]\n[time]\nsteps = 10\ndt = 1e-3\n[fluid]\nspacing = 0.05\n\
         [[fluid.blocks]]\nmin = [-0.2, -0.2, -0.2]\nmax = [0.2, 0.2, 0.2]\n[output]\n\
         vtk = false\ninterval = 0.004\nmetrics = [\"kinetic_energy\"]\n"
    );
    eddy::scene::parse_str(&text, Path::new("dummy.toml"), &[]).map_err(|e| e.to_string())
}

/// The column `name` of `metrics.csv` in `dir`.
fn column(dir: &Path, name: &str) -> Vec<f64> {
    let metrics = RunSeries::read_file(dir, "metrics.csv").expect("metrics.csv");
    metrics
        .column(name)
        .unwrap_or_else(|| panic!("no column {name} in {:?}", metrics.columns()))
}

#[test]
fn a_registered_stage_runs_in_its_slot_every_step_and_adds_its_columns() {
    register_dummy();
    let asked = scene("[\"dummy\"]").expect("the scene loads");
    let plan = Plan::of(&Pipeline::build(&asked).expect("builds"));
    let names: Vec<&str> = plan.stages.iter().map(|s| s.name).collect();
    // After the solver's step and the new neighbourhood, before the metrics that write its
    // columns.
    assert_eq!(
        names,
        ["sph", "neighbours", "dummy", "metrics"],
        "{names:?}"
    );

    let dir = tempfile::tempdir().expect("temp dir");
    let options = RunOptions {
        out: Some(dir.path().to_path_buf()),
        trace: true,
        ..Default::default()
    };
    let summary = eddy::pipeline::run_scene(&asked, &options).expect("runs");
    assert_eq!(summary.steps, 10);
    let dummies = summary.trace.iter().filter(|t| *t == "dummy").count();
    assert_eq!(dummies, 10, "{:?}", summary.trace);

    // Its runs, 1 to 10, in the rows of steps 0 to 9.
    let runs = column(dir.path(), "dummy_runs");
    assert_eq!(runs, (1..=10).map(f64::from).collect::<Vec<_>>());
    // It ran after the step: what it measured is the energy the step added, which the next
    // row's kinetic energy (the state at the start of each step) shows; the fluid falls, so
    // it gains.
    let energy = column(dir.path(), "kinetic_energy");
    let gain = column(dir.path(), "dummy_energy_gain");
    for k in 0..9 {
        let expected = energy[k + 1] - energy[k];
        assert!(expected > 0.0, "the falling block gains energy at step {k}");
        assert!(
            (gain[k] - expected).abs() <= 1e-9 * expected,
            "step {k}: the dummy measured {} J, the metrics show {expected} J",
            gain[k]
        );
    }
    // The resolved scene keeps the key, and reads back equal.
    let resolved = std::fs::read_to_string(dir.path().join("scene.toml")).expect("scene.toml");
    let again = eddy::scene::parse_str(&resolved, Path::new("scene.toml"), &[]).expect("reads");
    assert_eq!(again.stages, ["dummy"]);
}

#[test]
fn a_stage_nobody_asks_for_is_not_built() {
    register_dummy();
    let plain = scene("[]").expect("the scene loads");
    let plan = Plan::of(&Pipeline::build(&plain).expect("builds"));
    assert!(plan.stages.iter().all(|s| s.name != "dummy"));
}

#[test]
fn an_unknown_stage_is_refused_with_the_names_there_are() {
    register_dummy();
    let scene = scene("[\"dumy\"]").expect("the scene loads");
    let e = Pipeline::build(&scene).err().expect("refused").to_string();
    for needle in ["`stages`", "`dumy`", "statistics", "dummy"] {
        assert!(e.contains(needle), "{e} lacks {needle}");
    }
}

#[test]
fn a_taken_name_is_refused() {
    register_dummy();
    for name in ["statistics", "sph_metrics", "dummy"] {
        let e = register_stage(StageKind {
            name,
            summary: "again",
            slot: Slot::Start,
            build,
        })
        .expect_err("a taken name");
        assert!(e.contains(name), "{e}");
    }
}
