//! `cargo bench --bench statistics`: what the running statistics (`[statistics]`) cost, as the
//! statistics stage's share of a whole step: the smoke plume on a grid and the dam break on
//! particles, each sampled every step. The target is at most 5 % of a step.

use std::path::Path;

use crate::pipeline::{Pipeline, RunError};
use crate::scene::{self, Scene};

/// One row: the scene, its size, the mean step and the statistics stage's mean share of it.
#[derive(Debug, Clone)]
pub struct StatisticsCost {
    pub scene: String,
    /// Grid cells or fluid particles.
    pub size: usize,
    /// Mean wall seconds of a whole step (every stage).
    pub step_seconds: f64,
    /// Mean wall seconds of the statistics stage in a step.
    pub statistics_seconds: f64,
}

impl StatisticsCost {
    /// The stage's share of a step.
    pub fn share(&self) -> f64 {
        self.statistics_seconds / self.step_seconds
    }
}

fn step(p: &mut Pipeline) -> Result<(), RunError> {
    p.step(None, None)
        .map(|_| ())
        .map_err(|e| RunError::Unsupported(e.to_string()))
}

/// Times `steps` steps of `scene` with statistics from t = 0, after `warmup` steps.
pub fn measure(scene: &Scene, warmup: u64, steps: u64) -> Result<StatisticsCost, RunError> {
    let mut scene = scene.clone();
    scene.statistics = Some(Default::default());
    scene.output.metrics = Some(Vec::new());
    let mut p = Pipeline::build(&scene)?;
    for _ in 0..warmup {
        step(&mut p)?;
    }
    p.stage_seconds.iter_mut().for_each(|s| *s = 0.0);
    for _ in 0..steps {
        step(&mut p)?;
    }
    let at = p
        .stages
        .iter()
        .position(|s| s.name() == "statistics")
        .expect("the statistics stage is built");
    let total: f64 = p.stage_seconds.iter().sum();
    let size = match (&p.sim.grid, &p.sim.sph) {
        (Some(g), _) => g.mac.cell_count(),
        (None, Some(s)) => s.fluid.len(),
        (None, None) => 0,
    };
    Ok(StatisticsCost {
        scene: scene.name.clone(),
        size,
        step_seconds: total / steps as f64,
        statistics_seconds: p.stage_seconds[at] / steps as f64,
    })
}

/// The shipped scene `file` with `overrides`.
pub fn shipped(file: &str, overrides: &[String]) -> Result<Scene, RunError> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(file);
    Ok(scene::load(&path, overrides)?)
}
