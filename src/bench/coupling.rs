//! `eddy bench-coupling`: what the exchange across the water surface costs. A coupled scene is
//! stepped three ways at one fixed step, in alternating rounds: coupled, its grid alone and
//! its SPH fluid alone (each built exactly as in the coupled scene). The coupling's cost is
//! the coupled step over the sum of the two alone, less one; each stage's share of the coupled
//! step is listed too.

use std::path::Path;
use std::time::Instant;

use crate::pipeline::{resolve, Pipeline, RunError, RunOptions};
use crate::scene::Scene;
use crate::Real;

/// Options of the coupling benchmark.
#[derive(Debug, Clone)]
pub struct CouplingBenchOptions {
    /// Scene key overrides, applied to every run.
    pub overrides: Vec<String>,
    /// Steps of each run before timing starts.
    pub warmup: u64,
    /// Timed steps of each run per round.
    pub steps: u64,
    /// Rounds of (coupled, grid alone, SPH alone).
    pub rounds: u64,
}

/// What the benchmark measured: seconds per step.
#[derive(Debug, Clone)]
pub struct CouplingBench {
    pub scene: String,
    pub particles: usize,
    pub cells: usize,
    pub dt: Real,
    pub coupled: f64,
    pub grid_alone: f64,
    pub sph_alone: f64,
    /// Each stage of the coupled step and its seconds per step.
    pub stages: Vec<(&'static str, f64)>,
}

impl CouplingBench {
    /// The coupled step over the two solvers' steps alone, less one.
    pub fn overhead(&self) -> f64 {
        self.coupled / (self.grid_alone + self.sph_alone) - 1.0
    }
}

/// Runs the benchmark on the coupled scene at `path`.
pub fn run(path: &Path, options: &CouplingBenchOptions) -> Result<CouplingBench, RunError> {
    let run_options = RunOptions {
        overrides: options.overrides.clone(),
        ..RunOptions::default()
    };
    let mut scene = resolve(path, &run_options)?;
    if scene.coupling.is_none() {
        return Err(RunError::Unsupported(format!(
            "scene '{}' has no [coupling]: bench-coupling times a coupled scene",
            scene.name
        )));
    }
    scene.output.metrics = Some(Vec::new());
    let mut coupled = Pipeline::build(&scene)?;
    let dt = coupled
        .sim
        .stable_dt()
        .map_err(|e| RunError::Unsupported(e.to_string()))?;
    scene.time.dt = Some(dt);
    let mut coupled = Pipeline::build(&scene)?;
    let alone = |keep_grid: bool| -> Result<Pipeline, RunError> {
        let mut s: Scene = scene.clone();
        if keep_grid {
            s.fluid = None;
        } else {
            s.grid = None;
        }
        Pipeline::build(&s)
    };
    let (mut grid, mut sph) = (alone(true)?, alone(false)?);
    let mut runs = [&mut coupled, &mut grid, &mut sph];
    let mut seconds = [0.0; 3];
    let step = |p: &mut Pipeline| -> Result<(), RunError> {
        p.step(None, None)
            .map(|_| ())
            .map_err(|e| RunError::Unsupported(e.to_string()))
    };
    for p in runs.iter_mut() {
        for _ in 0..options.warmup {
            step(p)?;
        }
        p.stage_seconds.clear();
    }
    for _ in 0..options.rounds {
        for (p, total) in runs.iter_mut().zip(&mut seconds) {
            let started = Instant::now();
            for _ in 0..options.steps {
                step(p)?;
            }
            *total += started.elapsed().as_secs_f64();
        }
    }
    let n = (options.steps * options.rounds) as f64;
    let c = &runs[0];
    Ok(CouplingBench {
        scene: scene.name.clone(),
        particles: c.sim.sph.as_ref().map_or(0, |s| s.fluid.len()),
        cells: c.sim.grid.as_ref().map_or(0, |g| g.mac.cell_count()),
        dt,
        coupled: seconds[0] / n,
        grid_alone: seconds[1] / n,
        sph_alone: seconds[2] / n,
        stages: c
            .stages
            .iter()
            .zip(&c.stage_seconds)
            .map(|(s, t)| (s.name(), t / n))
            .collect(),
    })
}

/// The benchmark as a text table.
pub fn table(b: &CouplingBench) -> String {
    let ms = |s: f64| format!("{:8.2}", s * 1e3);
    let mut out = format!(
        "{}: {} fluid particles, {} grid cells, dt = {:.3e} s\n\n| run | ms per step |\n|---|---|\n",
        b.scene, b.particles, b.cells, b.dt
    );
    out += &format!("| coupled | {} |\n", ms(b.coupled));
    for (name, s) in &b.stages {
        out += &format!("| - {name} | {} |\n", ms(*s));
    }
    out += &format!("| grid alone | {} |\n", ms(b.grid_alone));
    out += &format!("| SPH alone | {} |\n", ms(b.sph_alone));
    out += &format!(
        "\ncoupling cost: coupled / (grid alone + SPH alone) - 1 = {:+.1} %\n",
        100.0 * b.overhead()
    );
    out
}
