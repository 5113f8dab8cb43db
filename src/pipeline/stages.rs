//! The stages a step runs, in order: each is an object built from the scene only when the
//! scene needs it, and the plan is printed from the same objects (see `super::plan`).

use std::path::Path;

use super::simulation::{Simulation, StepError};
use super::turbulence::TurbulenceStats;
use crate::grid::GridStepStats;
use crate::io::{CsvSeries, IoError};
use crate::metrics::series::StateMetrics;
use crate::metrics::{GridProbeRecorder, Metric, MetricsRecorder, Probe, ProbeRecorder};
use crate::sph::StepStats;
use crate::{Real, Vec3};

/// What the stages of one step share: the clock and what the solvers reported.
#[derive(Debug, Clone, Copy, Default)]
pub struct StepRecord {
    /// The step's index and start time.
    pub step: u64,
    pub time: Real,
    /// The step size every solver advances by.
    pub dt: Real,
    pub sph: Option<StepStats>,
    pub grid: Option<GridStepStats>,
    pub grid_turbulence: Option<TurbulenceStats>,
    pub sph_turbulence: Option<TurbulenceStats>,
    /// What the water received across its surface, in a coupled scene.
    pub exchange: Option<super::coupling::Exchange>,
}

/// One stage of a step. Stages are `Send`, so a run can step on another thread than the one
/// that built it (the Python bindings release the GIL while it steps).
pub trait Stage: Send {
    /// Short name, for the plan and the stage trace.
    fn name(&self) -> &'static str;

    /// What it does in this scene, and the parts it runs inside, in order.
    fn describe(&self, sim: &Simulation) -> (String, Vec<(&'static str, String)>);

    /// Creates its output files in `out`, before the first step.
    fn open(&mut self, _sim: &Simulation, _out: &Path) -> Result<(), IoError> {
        Ok(())
    }

    /// Runs it for the step in `rec`.
    fn run(&mut self, sim: &mut Simulation, rec: &mut StepRecord) -> Result<(), StepError>;

    /// The parts its last run ran, named as [`Stage::describe`] names them.
    fn ran<'a>(&self, _sim: &'a Simulation) -> &'a [&'static str] {
        &[]
    }

    /// The CSV series it writes (metrics, probes) once opened, whose last row is the last
    /// step's.
    fn series(&self) -> Option<&CsvSeries> {
        None
    }

    /// The state was edited between steps (velocities written from Python): anything the
    /// stage measured of it for its next row is measured again.
    fn state_edited(&mut self, _sim: &Simulation) {}
}

/// The SPH step over the shared `dt`: divergence solve, hooks, forces, pressure, positions.
pub struct SphStep;

impl Stage for SphStep {
    fn name(&self) -> &'static str {
        "sph"
    }

    fn describe(&self, sim: &Simulation) -> (String, Vec<(&'static str, String)>) {
        let sph = sim.sph.as_ref().expect("an SPH stage has a fluid");
        (sph.summary(), sph.describe())
    }

    fn run(&mut self, sim: &mut Simulation, rec: &mut StepRecord) -> Result<(), StepError> {
        rec.sph = Some(sim.sph().advance(rec.dt)?);
        Ok(())
    }

    fn ran<'a>(&self, sim: &'a Simulation) -> &'a [&'static str] {
        sim.sph.as_ref().map_or(&[], |s| s.ran())
    }
}

/// The SPH neighbourhood of the new positions: sort, neighbour lists, densities.
pub struct SphNeighbours;

impl Stage for SphNeighbours {
    fn name(&self) -> &'static str {
        "neighbours"
    }

    fn describe(&self, sim: &Simulation) -> (String, Vec<(&'static str, String)>) {
        let sph = sim.sph.as_ref().expect("an SPH stage has a fluid");
        (sph.describe_neighbourhood(), Vec::new())
    }

    fn run(&mut self, sim: &mut Simulation, _rec: &mut StepRecord) -> Result<(), StepError> {
        sim.sph().update_neighborhoods();
        Ok(())
    }
}

/// The MAC-grid step over the shared `dt`.
pub struct GridStep;

impl Stage for GridStep {
    fn name(&self) -> &'static str {
        "grid"
    }

    fn describe(&self, sim: &Simulation) -> (String, Vec<(&'static str, String)>) {
        let grid = sim.grid.as_ref().expect("a grid stage has a grid");
        (grid.summary(), grid.describe())
    }

    fn run(&mut self, sim: &mut Simulation, rec: &mut StepRecord) -> Result<(), StepError> {
        rec.grid = Some(sim.grid().advance(rec.dt)?);
        Ok(())
    }

    fn ran<'a>(&self, sim: &'a Simulation) -> &'a [&'static str] {
        sim.grid.as_ref().map_or(&[], |g| g.ran())
    }
}

/// Probes of an SPH fluid at the start of each step, into `probes.csv`.
pub struct SphProbes {
    pub probes: Vec<Probe>,
    pub file: String,
    pub recorder: Option<ProbeRecorder>,
}

impl Stage for SphProbes {
    fn name(&self) -> &'static str {
        "probes"
    }

    fn describe(&self, _sim: &Simulation) -> (String, Vec<(&'static str, String)>) {
        (probe_line(&self.file, &self.probes), Vec::new())
    }

    fn open(&mut self, _sim: &Simulation, out: &Path) -> Result<(), IoError> {
        self.recorder = Some(ProbeRecorder::create(&out.join(&self.file), &self.probes)?);
        Ok(())
    }

    fn run(&mut self, sim: &mut Simulation, _rec: &mut StepRecord) -> Result<(), StepError> {
        if let Some(r) = self.recorder.as_mut() {
            r.record(sim.sph())?;
        }
        Ok(())
    }

    fn series(&self) -> Option<&CsvSeries> {
        self.recorder.as_ref().map(|r| r.series())
    }
}

/// Point and force probes of a grid at the start of each step, into `probes.csv`.
pub struct GridProbes {
    pub probes: Vec<Probe>,
    /// The index among the grid's bodies of each obstacle name a force probe may name.
    pub bodies: Vec<(String, usize)>,
    pub file: String,
    pub recorder: Option<GridProbeRecorder>,
}

impl Stage for GridProbes {
    fn name(&self) -> &'static str {
        "probes"
    }

    fn describe(&self, _sim: &Simulation) -> (String, Vec<(&'static str, String)>) {
        (probe_line(&self.file, &self.probes), Vec::new())
    }

    fn open(&mut self, _sim: &Simulation, out: &Path) -> Result<(), IoError> {
        let index = |name: &str| self.bodies.iter().find(|(n, _)| n == name).map(|&(_, i)| i);
        self.recorder = Some(GridProbeRecorder::create(
            &out.join(&self.file),
            &self.probes,
            index,
        )?);
        Ok(())
    }

    fn run(&mut self, sim: &mut Simulation, _rec: &mut StepRecord) -> Result<(), StepError> {
        if let Some(r) = self.recorder.as_mut() {
            r.record(sim.grid())?;
        }
        Ok(())
    }

    fn series(&self) -> Option<&CsvSeries> {
        self.recorder.as_ref().map(|r| r.series())
    }
}

fn probe_line(file: &str, probes: &[Probe]) -> String {
    let names: Vec<_> = probes.iter().map(|p| p.name()).collect();
    format!("{file}: {}", names.join(", "))
}

/// The SPH row of each step: the state the step started from and what the step did. It runs
/// after the step and keeps the state it measures for the next row.
pub struct SphMetrics {
    pub metrics: Vec<Metric>,
    pub gravity: Vec3,
    pub file: String,
    pub recorder: Option<(MetricsRecorder, StateMetrics)>,
}

impl Stage for SphMetrics {
    fn name(&self) -> &'static str {
        "metrics"
    }

    fn describe(&self, sim: &Simulation) -> (String, Vec<(&'static str, String)>) {
        let names: Vec<_> = self.metrics.iter().map(|m| m.column()).collect();
        (
            format!(
                "{}: {} (state at the start of each step){}",
                self.file,
                names.join(", "),
                sim.sph_turbulence
                    .as_ref()
                    .map_or(String::new(), |t| format!("; {}", t.describe_columns()))
            ),
            Vec::new(),
        )
    }

    fn open(&mut self, sim: &Simulation, out: &Path) -> Result<(), IoError> {
        let extra = sim
            .sph_turbulence
            .as_ref()
            .map_or(Vec::new(), |t| t.columns());
        let recorder = MetricsRecorder::create(&out.join(&self.file), &self.metrics, &extra)?;
        let sph = sim.sph.as_ref().expect("an SPH stage has a fluid");
        let state = recorder.measure(sph, &self.gravity);
        self.recorder = Some((recorder, state));
        Ok(())
    }

    fn run(&mut self, sim: &mut Simulation, rec: &mut StepRecord) -> Result<(), StepError> {
        let (Some((recorder, state)), Some(stats)) = (self.recorder.as_mut(), rec.sph) else {
            return Ok(());
        };
        let extra = match (&sim.sph_turbulence, rec.sph_turbulence) {
            (Some(_), Some(t)) => t.row(),
            _ => Vec::new(),
        };
        recorder.write(rec.step, rec.time, state, &stats, &extra)?;
        *state = recorder.measure(sim.sph(), &self.gravity);
        Ok(())
    }

    fn series(&self) -> Option<&CsvSeries> {
        self.recorder.as_ref().map(|(r, _)| r.series())
    }

    fn state_edited(&mut self, sim: &Simulation) {
        if let (Some((recorder, state)), Some(sph)) = (self.recorder.as_mut(), sim.sph.as_ref()) {
            *state = recorder.measure(sph, &self.gravity);
        }
    }
}

/// Columns of a grid's metrics after step, time and dt.
const GRID_METRICS: [&str; 10] = [
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

/// The grid row of each step: what the step did and the kinetic energy it ended with, what
/// the turbulence stage did when the scene has one, and for a Taylor–Green scene the error of
/// the energy decay.
pub struct GridMetrics {
    pub file: String,
    pub csv: Option<CsvSeries>,
    pub taylor_green: Option<TaylorGreenDecay>,
    /// A coupled scene's: the forces the water felt across its surface.
    pub coupled: bool,
}

/// Columns of a coupled scene's grid metrics: the forces on the water (the air's are opposite),
/// N, the cells under the liquid and the area the drag acted on, m^2.
const COUPLING_METRICS: [&str; 8] = [
    "drag_force_x",
    "drag_force_y",
    "drag_force_z",
    "pressure_force_x",
    "pressure_force_y",
    "pressure_force_z",
    "liquid_cells",
    "surface_area",
];

/// The Taylor–Green vortex's energy decays as E(t) = E(0) exp(-4 nu t); the column
/// `taylor_green_error` is |ln(E / E(t))| after each step, with E(0) the grid's own energy of
/// the initial flow (so the sampling of the flow on the grid is not counted as error).
pub struct TaylorGreenDecay {
    pub nu: Real,
    pub initial_energy: Real,
}

impl Stage for GridMetrics {
    fn name(&self) -> &'static str {
        "metrics"
    }

    fn describe(&self, sim: &Simulation) -> (String, Vec<(&'static str, String)>) {
        (
            format!(
                "{}: kinetic energy, max divergence, pressure and viscosity iterations, CFL, \
                 change rate, stage times{}{}{}",
                self.file,
                sim.grid_turbulence
                    .as_ref()
                    .map_or(String::new(), |t| format!("; {}", t.describe_columns())),
                if self.taylor_green.is_some() {
                    "; Taylor-Green energy decay error |ln(E / E(0) exp(-4 nu t))|"
                } else {
                    ""
                },
                if self.coupled {
                    "; the air's drag and pressure force on the water, liquid cells, surface area"
                } else {
                    ""
                }
            ),
            Vec::new(),
        )
    }

    fn open(&mut self, sim: &Simulation, out: &Path) -> Result<(), IoError> {
        let mut columns: Vec<String> = ["step", "time", "dt"].map(String::from).to_vec();
        columns.extend(GRID_METRICS.map(String::from));
        if let Some(t) = &sim.grid_turbulence {
            columns.extend(t.columns());
        }
        if self.coupled {
            columns.extend(COUPLING_METRICS.map(String::from));
        }
        if let (Some(tg), Some(grid)) = (self.taylor_green.as_mut(), sim.grid.as_ref()) {
            tg.initial_energy = grid.kinetic_energy();
            columns.push("taylor_green_error".into());
        }
        self.csv = Some(CsvSeries::create(&out.join(&self.file), &columns)?);
        Ok(())
    }

    fn run(&mut self, sim: &mut Simulation, rec: &mut StepRecord) -> Result<(), StepError> {
        let (Some(csv), Some(s)) = (self.csv.as_mut(), rec.grid) else {
            return Ok(());
        };
        let energy = sim.grid().kinetic_energy();
        let mut row = vec![
            rec.step as Real,
            rec.time,
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
        ];
        if let (Some(_), Some(t)) = (&sim.grid_turbulence, rec.grid_turbulence) {
            row.extend(t.row());
        }
        if self.coupled {
            let e = rec.exchange.unwrap_or_default();
            let (drag, pressure) = (e.drag / rec.dt, e.pressure / rec.dt);
            row.extend(drag.iter().chain(pressure.iter()));
            row.extend([e.liquid_cells as Real, e.area]);
        }
        if let Some(tg) = &self.taylor_green {
            let exact = tg.initial_energy * (-4.0 * tg.nu * sim.grid().time()).exp();
            row.push((energy / exact).ln().abs());
        }
        csv.row(&row)?;
        Ok(())
    }

    fn series(&self) -> Option<&CsvSeries> {
        self.csv.as_ref()
    }
}
