//! Drives a grid scene: steps the MAC-grid solver to the end (or to a steady state), writing
//! metrics.csv, probes.csv, line profiles, VTK image frames and HDF5 grid frames.

use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::grid::probes::{write_profile, GridProbeRecorder};
use crate::grid::{forces::vorticity, GridError, GridSolver, GridStepStats};
use crate::io::{AttrValue, CsvSeries, GridField, GridFrame, Hdf5GridFrames, IoError, PvdSeries};
use crate::scene::{Probe, Scene};
use crate::Real;

use super::{bodies, progress_bar, RunError, RunOptions, RunSummary};

/// Columns of a grid scene's `metrics.csv` after step, time and dt.
const METRICS: [&str; 10] = [
    "kinetic_energy",
    "max_divergence",
    "pressure_iterations",
    "pressure_residual",
    "viscosity_iterations",
    "cfl",
    "change_rate",
    "advect_seconds",
    "project_seconds",
    "step_seconds",
];

/// Runs a scene with a `[grid]` into `out`.
pub(super) fn run_grid(
    scene: &Scene,
    options: &RunOptions,
    out: &Path,
) -> Result<RunSummary, RunError> {
    let started = Instant::now();
    let mut solver =
        GridSolver::new(scene, bodies(scene)?).map_err(|cause| failed(cause, 0, out))?;
    let end_time = [scene.time.end, options.until]
        .into_iter()
        .flatten()
        .reduce(Real::min);
    let end_steps = [scene.time.steps, options.steps]
        .into_iter()
        .flatten()
        .min();
    let steady = scene.grid.as_ref().and_then(|g| g.steady_tolerance);
    let mut columns: Vec<String> = ["step", "time", "dt"].map(String::from).to_vec();
    columns.extend(METRICS.map(String::from));
    let mut metrics = CsvSeries::create(&out.join("metrics.csv"), &columns)?;
    let names: Vec<Option<String>> = scene.obstacles.iter().map(|b| b.name.clone()).collect();
    let offset = usize::from(scene.container.is_some());
    let mut probes = scene
        .probes
        .iter()
        .any(|p| matches!(p, Probe::Point { .. } | Probe::Force { .. }))
        .then(|| {
            GridProbeRecorder::create(&out.join("probes.csv"), &scene.probes, |name| {
                names
                    .iter()
                    .position(|n| n.as_deref() == Some(name))
                    .map(|i| i + offset)
            })
        })
        .transpose()?;
    let mut frames = GridFrames::new(out, scene)?;
    let bar = progress_bar(options.progress, end_time, end_steps);
    let mut next_frame = 0.0;
    let mut steady_reached = false;
    loop {
        let done = steady_reached
            || end_time.is_some_and(|t| solver.time() >= t - 1e-12)
            || end_steps.is_some_and(|n| solver.steps() >= n);
        if solver.time() >= next_frame - 1e-12 || done {
            frames.write(&solver)?;
            while next_frame <= solver.time() + 1e-12 {
                next_frame += scene.output.interval;
            }
        }
        if done {
            break;
        }
        if let Some(p) = probes.as_mut() {
            p.record(&solver)?;
        }
        let limit = end_time.map(|t| t - solver.time());
        let (step, time) = (solver.steps(), solver.time());
        let stats = solver
            .advance(limit)
            .map_err(|cause| failed(cause, frames.count, out))?;
        metrics.row(&metric_row(step, time, solver.kinetic_energy(), &stats))?;
        steady_reached = steady.is_some_and(|tol| stats.change_rate < tol);
        bar.set_position(match end_time {
            Some(t) => (solver.time() / t * 1000.0).min(1000.0) as u64,
            None => solver.steps(),
        });
        bar.set_message(format!(
            "t = {:.4} s, step {}, dt = {:.2e} s, {} CG iterations, change {:.1e}/s",
            solver.time(),
            solver.steps(),
            stats.dt,
            stats.pressure_iterations,
            stats.change_rate
        ));
    }
    bar.finish_and_clear();
    for p in &scene.probes {
        if let Probe::Line {
            name,
            from,
            to,
            points,
        } = p
        {
            write_profile(
                &solver,
                &out.join(format!("profile_{name}.csv")),
                *from,
                *to,
                *points,
            )?;
        }
    }
    frames.write_average(&solver)?;
    Ok(RunSummary {
        out: out.to_path_buf(),
        steps: solver.steps(),
        time: solver.time(),
        frames: frames.count,
        fluid_particles: 0,
        boundary_particles: 0,
        grid_cells: solver.mac.cell_count(),
        wall_seconds: started.elapsed().as_secs_f64(),
    })
}

fn failed(cause: GridError, frames: usize, out: &Path) -> RunError {
    RunError::Grid {
        cause: Box::new(cause),
        frames,
        out: out.to_path_buf(),
    }
}

fn metric_row(step: u64, time: Real, energy: Real, s: &GridStepStats) -> [Real; 13] {
    [
        step as Real,
        time,
        s.dt,
        energy,
        s.max_divergence,
        s.pressure_iterations as Real,
        s.pressure_residual,
        s.viscosity_iterations as Real,
        s.cfl,
        s.change_rate,
        s.advect_seconds,
        s.project_seconds,
        s.total_seconds,
    ]
}

/// The grid frame writers a scene asked for.
struct GridFrames {
    out: PathBuf,
    pvd: Option<PvdSeries>,
    hdf5: Option<Hdf5GridFrames>,
    count: usize,
}

impl GridFrames {
    fn new(out: &Path, scene: &Scene) -> Result<Self, IoError> {
        let pvd = scene
            .output
            .vtk
            .then(|| PvdSeries::new(&out.join("grid.pvd")));
        let hdf5 = scene
            .output
            .hdf5
            .then(|| {
                Hdf5GridFrames::create(
                    &out.join("frames.h5"),
                    &[
                        ("scene", AttrValue::Str(scene.name.clone())),
                        ("seed", AttrValue::Int(scene.seed as i64)),
                    ],
                )
            })
            .transpose()?;
        Ok(Self {
            out: out.to_path_buf(),
            pvd,
            hdf5,
            count: 0,
        })
    }

    /// Velocity, vorticity, pressure, smoke, temperature and the obstacle cells.
    fn write(&mut self, solver: &GridSolver) -> Result<(), IoError> {
        if self.pvd.is_none() && self.hdf5.is_none() {
            return Ok(());
        }
        let vel = solver.mac.cell_velocity();
        let w = vorticity(&solver.mac);
        let solid = solver
            .bounds
            .fluid_mask()
            .mapv(|f| if f { 0.0 } else { 1.0 });
        let mut fields = vec![
            GridField::vector("velocity", [vel[0].view(), vel[1].view(), vel[2].view()]),
            GridField::vector("vorticity", [w[0].view(), w[1].view(), w[2].view()]),
            GridField::scalar("pressure", solver.pressure.view()),
            GridField::scalar("solid", solid.view()),
        ];
        if let Some(smoke) = &solver.smoke {
            fields.push(GridField::scalar("smoke", smoke.density.view()));
            if let Some(t) = &smoke.temperature {
                fields.push(GridField::scalar("temperature", t.view()));
            }
        }
        let frame = GridFrame {
            step: solver.steps(),
            time: solver.time(),
            origin: solver.mac.origin,
            spacing: solver.mac.dx,
            dims: solver.mac.dims,
            fields,
        };
        if let Some(pvd) = self.pvd.as_mut() {
            let name = format!("grid_{:06}.vti", self.count);
            crate::io::write_grid_vtk(&self.out.join(&name), &frame)?;
            pvd.push(frame.time, &name)?;
        }
        if let Some(h5) = self.hdf5.as_mut() {
            h5.append(&frame)?;
        }
        self.count += 1;
        Ok(())
    }

    /// The time-averaged velocity as `average.vti`, when the scene keeps one.
    fn write_average(&self, solver: &GridSolver) -> Result<(), IoError> {
        let Some((_, avg)) = &solver.average else {
            return Ok(());
        };
        let Some(mean) = avg.mean(&solver.mac) else {
            return Ok(());
        };
        let vel = mean.cell_velocity();
        let frame = GridFrame {
            step: solver.steps(),
            time: solver.time(),
            origin: mean.origin,
            spacing: mean.dx,
            dims: mean.dims,
            fields: vec![GridField::vector(
                "velocity_mean",
                [vel[0].view(), vel[1].view(), vel[2].view()],
            )],
        };
        crate::io::write_grid_vtk(&self.out.join("average.vti"), &frame)
    }
}
