//! The stages a step runs, in order: each is an object built from the run's specification only
//! when the run needs it (see `super::order`), and the plan is printed from the same objects
//! (see `super::plan`).

use std::path::Path;

use super::order::Built;
use super::outputs::{Kind, METRICS_FILE, PROBES_FILE};
use super::simulation::{Simulation, StepError};
use super::spec::RunSpec;
use crate::grid::GridStepStats;
use crate::io::{CsvSeries, IoError};
use crate::metrics::series::StateMetrics;
use crate::metrics::{
    grid_vorticity_stats, GridProbeRecorder, Metric, MetricsRecorder, Probe, ProbeRecorder,
};
use crate::scene::InitialFlow;
use crate::sph::StepStats;
use crate::state::{Restorer, Saver, StateError};
use crate::{Real, Vec3};

/// What the stages of one step share: the clock and what the solvers reported.
#[derive(Debug, Clone, Default)]
pub struct StepRecord {
    /// The step's index and start time.
    pub step: u64,
    pub time: Real,
    /// The step size every solver advances by.
    pub dt: Real,
    /// What the SPH solver's step did.
    pub sph: Option<StepStats>,
    /// What the grid solver's step did.
    pub grid: Option<GridStepStats>,
    /// The values the stages added to a solver's metrics this step, in stage order, one entry
    /// per stage that has [`Stage::added_columns`].
    pub added: Vec<(Kind, Vec<Real>)>,
}

impl StepRecord {
    /// The values added to the metrics of `kind`'s solver, in stage order.
    fn added_to(&self, kind: Kind) -> impl Iterator<Item = Real> + '_ {
        self.added
            .iter()
            .filter(move |(k, _)| *k == kind)
            .flat_map(|(_, values)| values.iter().copied())
    }
}

/// Columns a stage adds to a solver's `metrics.csv`, after the solver's own.
#[derive(Debug, Clone)]
pub struct AddedColumns {
    /// Whose `metrics.csv`.
    pub to: Kind,
    pub names: Vec<String>,
    /// What they are, for the plan.
    pub note: &'static str,
}

/// The notes of the columns added to `kind`'s metrics, each after "; ".
fn notes(added: &[AddedColumns]) -> String {
    added.iter().map(|a| format!("; {}", a.note)).collect()
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

    /// Whether its run only measures, leaving every solver's state as it found it, so that
    /// what a stage before it measured of the state ([`Simulation::particle_vorticity`])
    /// still holds after it.
    fn measures_only(&self) -> bool {
        false
    }

    /// The metrics columns it adds to a solver's `metrics.csv`; its `run` then pushes their
    /// values to [`StepRecord::added`] every step.
    fn added_columns(&self, _sim: &Simulation) -> Option<AddedColumns> {
        None
    }

    /// Told, once the stages are ordered, the columns they add (the metrics stages write
    /// those of their solver).
    fn adopt_columns(&mut self, _added: &[AddedColumns]) {}

    /// The CSV series it writes (metrics, probes) once opened, whose last row is the last
    /// step's.
    fn series(&self) -> Option<&CsvSeries> {
        None
    }

    /// The same series, to go on from a checkpoint's rows.
    fn series_mut(&mut self) -> Option<&mut CsvSeries> {
        None
    }

    /// The state was edited between steps (velocities written from Python): anything the
    /// stage measured of it for its next row is measured again.
    fn state_edited(&mut self, _sim: &Simulation) {}

    /// Puts what it carries from one step to the next (a generator, running sums, the rows it
    /// has written) into a checkpoint; most stages keep their state in the [`Simulation`].
    fn save(&self, _into: &mut Saver) {}

    /// Restores what [`Stage::save`] put, into the stage freshly built from the same scene.
    fn restore(&mut self, _from: &Restorer) -> Result<(), StateError> {
        Ok(())
    }
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
    probes: Vec<Probe>,
    file: String,
    recorder: Option<ProbeRecorder>,
}

impl SphProbes {
    /// The stage of a run with a fluid and a probe.
    pub(super) fn stage(spec: &RunSpec, sim: &mut Simulation) -> Built {
        Ok((sim.sph.is_some() && !spec.probes.is_empty()).then(|| {
            Box::new(Self {
                probes: spec.probes.clone(),
                file: Kind::Particles.file(PROBES_FILE, sim.both_media()),
                recorder: None,
            }) as Box<dyn Stage>
        }))
    }
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

    fn series_mut(&mut self) -> Option<&mut CsvSeries> {
        self.recorder.as_mut().map(|r| r.series_mut())
    }
}

/// Point and force probes of a grid at the start of each step, into `probes.csv`.
pub struct GridProbes {
    probes: Vec<Probe>,
    /// The index among the grid's bodies of each obstacle name a force probe may name.
    bodies: Vec<(String, usize)>,
    file: String,
    recorder: Option<GridProbeRecorder>,
}

impl GridProbes {
    /// The stage of a run with a grid and a probe read every step (line probes are profiles
    /// written at the end, by the outputs).
    pub(super) fn stage(spec: &RunSpec, sim: &mut Simulation) -> Built {
        let per_step: Vec<_> = spec
            .probes
            .iter()
            .filter(|p| !matches!(p, Probe::Line { .. }))
            .cloned()
            .collect();
        Ok((sim.grid.is_some() && !per_step.is_empty()).then(|| {
            Box::new(Self {
                probes: per_step,
                bodies: spec.body_names.clone(),
                file: Kind::Grid.file(PROBES_FILE, sim.both_media()),
                recorder: None,
            }) as Box<dyn Stage>
        }))
    }
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

    fn series_mut(&mut self) -> Option<&mut CsvSeries> {
        self.recorder.as_mut().map(|r| r.series_mut())
    }
}

fn probe_line(file: &str, probes: &[Probe]) -> String {
    let names: Vec<_> = probes.iter().map(|p| p.name()).collect();
    format!("{file}: {}", names.join(", "))
}

/// The SPH row of each step: the state the step started from and what the step did. It runs
/// after the step and keeps the state it measures for the next row.
pub struct SphMetrics {
    metrics: Vec<Metric>,
    gravity: Vec3,
    file: String,
    recorder: Option<(MetricsRecorder, StateMetrics)>,
    /// The other stages' columns of the fluid's metrics.
    added: Vec<AddedColumns>,
}

impl SphMetrics {
    /// The stage of a run with a fluid and a metric of the fluid asked for.
    pub(super) fn stage(spec: &RunSpec, sim: &mut Simulation) -> Built {
        let metrics = Metric::chosen(spec.metrics.as_deref(), &Metric::SPH);
        Ok((sim.sph.is_some() && !metrics.is_empty()).then(|| {
            Box::new(Self {
                metrics,
                gravity: spec.gravity,
                file: Kind::Particles.file(METRICS_FILE, sim.both_media()),
                recorder: None,
                added: Vec::new(),
            }) as Box<dyn Stage>
        }))
    }
}

impl Stage for SphMetrics {
    fn name(&self) -> &'static str {
        "metrics"
    }

    fn describe(&self, _sim: &Simulation) -> (String, Vec<(&'static str, String)>) {
        let names: Vec<_> = self.metrics.iter().map(|m| m.column()).collect();
        (
            format!(
                "{}: {} (state at the start of each step){}",
                self.file,
                names.join(", "),
                notes(&self.added)
            ),
            Vec::new(),
        )
    }

    fn adopt_columns(&mut self, added: &[AddedColumns]) {
        self.added = added
            .iter()
            .filter(|a| a.to == Kind::Particles)
            .cloned()
            .collect();
    }

    fn open(&mut self, sim: &Simulation, out: &Path) -> Result<(), IoError> {
        let extra: Vec<String> = self.added.iter().flat_map(|a| a.names.clone()).collect();
        let recorder = MetricsRecorder::create(&out.join(&self.file), &self.metrics, &extra)?;
        let sph = sim.sph.as_ref().expect("an SPH stage has a fluid");
        let state = recorder.measure(sph, &self.gravity, &mut None);
        self.recorder = Some((recorder, state));
        Ok(())
    }

    fn run(&mut self, sim: &mut Simulation, rec: &mut StepRecord) -> Result<(), StepError> {
        let (Some((recorder, state)), Some(stats)) = (self.recorder.as_mut(), rec.sph) else {
            return Ok(());
        };
        let extra: Vec<Real> = rec.added_to(Kind::Particles).collect();
        recorder.write(rec.step, rec.time, state, &stats, &extra)?;
        let Simulation {
            sph,
            particle_vorticity,
            ..
        } = sim;
        let sph = sph.as_ref().expect("an SPH stage has a fluid");
        *state = recorder.measure(sph, &self.gravity, particle_vorticity);
        Ok(())
    }

    fn measures_only(&self) -> bool {
        true
    }

    fn series(&self) -> Option<&CsvSeries> {
        self.recorder.as_ref().map(|(r, _)| r.series())
    }

    fn series_mut(&mut self) -> Option<&mut CsvSeries> {
        self.recorder.as_mut().map(|(r, _)| r.series_mut())
    }

    fn state_edited(&mut self, sim: &Simulation) {
        if let (Some((recorder, state)), Some(sph)) = (self.recorder.as_mut(), sim.sph.as_ref()) {
            *state = recorder.measure(sph, &self.gravity, &mut None);
        }
    }
}

/// The grid row of each step: what the step did and the state it ended with (the metrics the
/// scene asks for), the columns other stages add (the turbulence's, the coupling's), and for a
/// Taylor–Green scene the error of the energy decay.
pub struct GridMetrics {
    /// Its columns after step, time and dt, in order.
    metrics: Vec<Metric>,
    file: String,
    csv: Option<CsvSeries>,
    taylor_green: Option<TaylorGreenDecay>,
    /// The other stages' columns of the grid's metrics.
    added: Vec<AddedColumns>,
}

impl GridMetrics {
    /// The stage of a run with a grid and a metric of the grid asked for.
    pub(super) fn stage(spec: &RunSpec, sim: &mut Simulation) -> Built {
        let metrics = Metric::chosen(spec.metrics.as_deref(), &Metric::GRID);
        let Some(grid) = spec.grid.as_ref().filter(|_| !metrics.is_empty()) else {
            return Ok(None);
        };
        let taylor_green =
            (grid.initial_flow == Some(InitialFlow::TaylorGreen)).then_some(TaylorGreenDecay {
                nu: grid.params.viscosity,
                initial_energy: 0.0,
            });
        Ok(Some(Box::new(Self {
            metrics,
            file: Kind::Grid.file(METRICS_FILE, sim.both_media()),
            csv: None,
            taylor_green,
            added: Vec::new(),
        })))
    }
}

/// The Taylor–Green vortex's energy decays as E(t) = E(0) exp(-4 nu t); the column
/// `taylor_green_error` is |ln(E / E(t))| after each step, with E(0) the grid's own energy of
/// the initial flow (so the sampling of the flow on the grid is not counted as error).
struct TaylorGreenDecay {
    nu: Real,
    initial_energy: Real,
}

impl Stage for GridMetrics {
    fn name(&self) -> &'static str {
        "metrics"
    }

    fn describe(&self, _sim: &Simulation) -> (String, Vec<(&'static str, String)>) {
        let names: Vec<_> = self.metrics.iter().map(|m| m.column()).collect();
        (
            format!(
                "{}: {}{}{}",
                self.file,
                names.join(", "),
                notes(&self.added),
                if self.taylor_green.is_some() {
                    "; Taylor-Green energy decay error |ln(E / E(0) exp(-4 nu t))|"
                } else {
                    ""
                },
            ),
            Vec::new(),
        )
    }

    fn adopt_columns(&mut self, added: &[AddedColumns]) {
        self.added = added
            .iter()
            .filter(|a| a.to == Kind::Grid)
            .cloned()
            .collect();
    }

    fn open(&mut self, sim: &Simulation, out: &Path) -> Result<(), IoError> {
        let mut columns: Vec<String> = ["step", "time", "dt"].map(String::from).to_vec();
        columns.extend(self.metrics.iter().map(|m| m.column().to_owned()));
        columns.extend(self.added.iter().flat_map(|a| a.names.clone()));
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
        let grid = sim.grid();
        let energy = grid.kinetic_energy();
        let mut vorticity = None;
        let mut vorticity = || *vorticity.get_or_insert_with(|| grid_vorticity_stats(grid));
        let mut row = vec![rec.step as Real, rec.time, s.dt];
        row.extend(self.metrics.iter().map(|m| match m {
            Metric::KineticEnergy => energy,
            Metric::MaxDivergence => s.max_divergence,
            Metric::PressureIterations => s.pressure_iterations as Real,
            Metric::PressureResidual => s.pressure_residual,
            Metric::ViscosityIterations => s.viscosity_iterations as Real,
            Metric::Cfl => s.cfl,
            Metric::ChangeRate => s.change_rate,
            Metric::AdvectSeconds => s.advect_seconds,
            Metric::ProjectSeconds => s.project_seconds,
            Metric::StepSeconds => s.total_seconds,
            Metric::VorticityMean => vorticity().mean,
            Metric::VorticityMax => vorticity().max,
            Metric::Enstrophy => vorticity().enstrophy,
            // An SPH fluid's: `Metric::GRID` leaves them out of a grid's list.
            _ => Real::NAN,
        }));
        row.extend(rec.added_to(Kind::Grid));
        if let Some(tg) = &self.taylor_green {
            let exact = tg.initial_energy * (-4.0 * tg.nu * grid.time()).exp();
            row.push((energy / exact).ln().abs());
        }
        csv.row(&row)?;
        Ok(())
    }

    fn series(&self) -> Option<&CsvSeries> {
        self.csv.as_ref()
    }

    fn series_mut(&mut self) -> Option<&mut CsvSeries> {
        self.csv.as_mut()
    }

    /// The Taylor–Green decay's reference energy, measured when the run opened.
    fn save(&self, into: &mut Saver) {
        if let Some(tg) = &self.taylor_green {
            into.real("taylor_green_initial_energy", tg.initial_energy);
        }
    }

    fn restore(&mut self, from: &Restorer) -> Result<(), StateError> {
        if let Some(tg) = self.taylor_green.as_mut() {
            tg.initial_energy = from.real("taylor_green_initial_energy")?;
        }
        Ok(())
    }
}
