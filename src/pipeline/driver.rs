//! The one driver loop: frames at the output interval, the shared step, the end conditions
//! (end time, step count, steady state), the progress bar, and the instability stop that keeps
//! the frames written so far.

use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};

use super::build::Pipeline;
use super::checkpoint::{self, CheckpointError};
use super::outputs::{remove_earlier_outputs, Outputs, CHECKPOINT_FILE, SCENE_FILE};
use super::plan::Plan;
use super::simulation::StepError;
use super::spec::{RunEnd, RunSpec};
use super::stages::StepRecord;
use super::{RunError, RunOptions, RunSummary};
use crate::io::{write_atomic, write_checkpoint, CsvSeries, IoError};
use crate::stepping::towards_end;
use crate::Real;

/// Times closer than this count as equal (frame times, the end time).
const TIME_EPS: Real = 1e-12;

/// Runs `spec` into its output folder (from its checkpoint with [`RunOptions::resume`]). A
/// stop asked for through [`RunOptions::stop`] writes a checkpoint after the step in progress
/// and ends the run with [`RunError::Interrupted`].
pub fn drive(spec: &RunSpec, options: &RunOptions) -> Result<RunSummary, RunError> {
    let mut run = Run::begin_from(spec, options)?;
    if run.removed_outputs() > 0 {
        tracing::warn!(
            "removed {} output files of an earlier run from {}",
            run.removed_outputs(),
            run.out.display()
        );
    }
    let bar = run.progress(options.progress, None, None);
    let mut trace = Vec::new();
    while let Some(rec) = run.advance(options.trace.then_some(&mut trace))? {
        bar.update(&run, &rec);
        if options
            .stop
            .as_ref()
            .is_some_and(|s| s.load(Ordering::SeqCst))
        {
            bar.finish();
            run.checkpoint()?;
            let sim = &run.pipeline.sim;
            return Err(RunError::Interrupted {
                time: sim.time(),
                steps: sim.steps(),
                frames: run.pipeline.outputs.frames(),
                out: run.out.clone(),
            });
        }
    }
    bar.finish();
    let mut summary = run.finish()?;
    summary.trace = trace;
    Ok(summary)
}

/// A run in progress: the built pipeline writing into its output folder, when the run ends and
/// which frame is next. `eddy run` advances it to its end; the Python bindings a step at a
/// time, through the same [`Run::advance`], so both write the same frames and rows.
pub struct Run {
    pub pipeline: Pipeline,
    out: PathBuf,
    end: RunEnd,
    /// The next frame's index: frame k is at k times the interval (a product, so the times do
    /// not drift).
    frame: u64,
    steady: bool,
    /// Set once the end's frame is written.
    ended: bool,
    plan: Plan,
    started: Instant,
    /// The scene as checkpoints record it (see [`RunSpec::checkpoint_key`]).
    scene_key: String,
    checkpoints: Schedule,
    /// Files of an earlier run that starting this one removed from the output folder.
    removed_outputs: usize,
}

/// When checkpoints are written: every `interval` s of simulated time, every `every` of wall
/// time.
struct Schedule {
    interval: Option<Real>,
    /// The next checkpoint time's index (its time is a product, so the times do not drift).
    next: u64,
    every: Option<Duration>,
    last: Instant,
}

impl Schedule {
    fn new(outputs: &Outputs, time: Real) -> Self {
        let interval = outputs.checkpoint_interval;
        Self {
            interval,
            next: interval.map_or(0, |dt| (time / dt + TIME_EPS).floor() as u64 + 1),
            every: outputs
                .checkpoint_every
                .map(|m| Duration::from_secs_f64(60.0 * m)),
            last: Instant::now(),
        }
    }

    /// Whether one is due at `time`; if so, the next is scheduled.
    fn due(&mut self, time: Real) -> bool {
        let by_time = self
            .interval
            .is_some_and(|dt| time >= self.next as Real * dt - TIME_EPS);
        let by_wall = self.every.is_some_and(|e| self.last.elapsed() >= e);
        if by_time || by_wall {
            if let Some(dt) = self.interval {
                self.next = (time / dt + TIME_EPS).floor() as u64 + 1;
            }
            self.last = Instant::now();
        }
        by_time || by_wall
    }
}

impl Run {
    /// Prepares the output folder (earlier outputs removed, the resolved `scene.toml`), builds
    /// the pipeline of `spec` (as [`RunOptions::spec`] resolves it) and opens its outputs.
    pub fn start_from(spec: &RunSpec, options: &RunOptions) -> Result<Self, RunError> {
        let started = Instant::now();
        let out = spec.output_dir(options);
        std::fs::create_dir_all(&out).map_err(|e| IoError::Io {
            path: out.clone(),
            action: "creating the output folder",
            source: e,
        })?;
        let removed = remove_earlier_outputs(&out)?;
        write_atomic(&out.join(SCENE_FILE), |w| {
            w.write_all(spec.resolved.as_bytes())
        })?;
        // A scene that cannot be built (no fluid cell, a stored flow on another grid) has
        // written no frame: its error says what is wrong and nothing about frames.
        let mut pipeline = Pipeline::from_spec(spec)?;
        pipeline.open(&out)?;
        let mut run = Run::assemble(pipeline, spec, out, 0, started);
        run.removed_outputs = removed;
        Ok(run)
    }

    /// [`Run::resume_from`] with [`RunOptions::resume`], else [`Run::start_from`].
    pub fn begin_from(spec: &RunSpec, options: &RunOptions) -> Result<Self, RunError> {
        if options.resume {
            Run::resume_from(spec, options)
        } else {
            Run::start_from(spec, options)
        }
    }

    /// Goes on from the checkpoint in the run's output folder: the pipeline built from the
    /// same scene (only `time.end`, `time.steps` and the output keys may differ) takes back
    /// the saved state; frames, series and statistics go on from it, no row written twice.
    pub fn resume_from(spec: &RunSpec, options: &RunOptions) -> Result<Self, RunError> {
        let started = Instant::now();
        let out = spec.output_dir(options);
        let state = checkpoint::load(&out, &spec.checkpoint_key)?;
        let invalid = |source| CheckpointError::State {
            path: out.join(CHECKPOINT_FILE),
            source,
        };
        let frame = state.read("run").u64("frame").map_err(invalid)?;
        let mut pipeline = Pipeline::from_spec(spec)?;
        pipeline.open_to_resume(&out, &state)?;
        pipeline.restore_state(&state).map_err(invalid)?;
        write_atomic(&out.join(SCENE_FILE), |w| {
            w.write_all(spec.resolved.as_bytes())
        })?;
        Ok(Run::assemble(pipeline, spec, out, frame, started))
    }

    fn assemble(
        pipeline: Pipeline,
        spec: &RunSpec,
        out: PathBuf,
        frame: u64,
        started: Instant,
    ) -> Self {
        let plan = Plan::of(&pipeline);
        let checkpoints = Schedule::new(&pipeline.outputs, pipeline.sim.time());
        Run {
            pipeline,
            out,
            end: spec.end,
            frame,
            steady: false,
            ended: false,
            plan,
            started,
            scene_key: spec.checkpoint_key.clone(),
            checkpoints,
            removed_outputs: 0,
        }
    }

    /// Writes the run's state between steps to `checkpoint.h5` in its folder (under a
    /// temporary name, then renamed: a kill during the write keeps the previous one).
    pub fn checkpoint(&self) -> Result<PathBuf, RunError> {
        let mut state = self.pipeline.save_state();
        state.section("run").u64("frame", self.frame);
        let path = self.out.join(CHECKPOINT_FILE);
        let sim = &self.pipeline.sim;
        let attrs = checkpoint::attributes(&self.scene_key, sim.time(), sim.steps());
        write_checkpoint(&path, &attrs, &state)?;
        Ok(path)
    }

    /// Writes the frame that is due, then takes one step; `None`, once the run has reached its
    /// end (and written the end's frame). Steps land on the next frame time as on the end
    /// time, whether or not frames are written, so a run's steps do not depend on its output
    /// formats. With `trace`, appends the stages and parts the step ran.
    pub fn advance(
        &mut self,
        trace: Option<&mut Vec<String>>,
    ) -> Result<Option<StepRecord>, RunError> {
        if self.ended {
            return Ok(None);
        }
        let interval = self.pipeline.outputs.interval;
        let frame_time = |k: u64| k as Real * interval;
        let (end, p) = (&self.end, &mut self.pipeline);
        let sim = &p.sim;
        let done = self.steady
            || end.time.is_some_and(|t| sim.time() >= t - TIME_EPS)
            || end.steps.is_some_and(|n| sim.steps() >= n);
        if sim.time() >= frame_time(self.frame) - TIME_EPS || done {
            p.outputs.write(sim)?;
            while frame_time(self.frame) <= sim.time() + TIME_EPS {
                self.frame += 1;
            }
        }
        if done {
            self.ended = true;
            return Ok(None);
        }
        let next_frame = frame_time(self.frame);
        let target = end.time.map_or(next_frame, |t| t.min(next_frame));
        let rec = p
            .step(Some(target), trace)
            .map_err(|e| stopped(e, p.outputs.frames(), &self.out))?;
        self.steady = end
            .steady
            .zip(rec.grid)
            .is_some_and(|(tol, g)| g.change_rate < tol);
        if self.checkpoints.due(self.pipeline.sim.time()) {
            self.checkpoint()?;
        }
        Ok(Some(rec))
    }

    /// Tells every stage that the state was edited between steps (see
    /// [`Stage::state_edited`](super::Stage::state_edited)).
    pub fn state_edited(&mut self) {
        let p = &mut self.pipeline;
        for stage in &mut p.stages {
            stage.state_edited(&p.sim);
        }
    }

    /// Whether the run has reached its end.
    pub fn ended(&self) -> bool {
        self.ended
    }

    /// The output folder.
    pub fn out(&self) -> &Path {
        &self.out
    }

    /// The stages the run was built with.
    pub fn plan(&self) -> &Plan {
        &self.plan
    }

    /// How many files of an earlier run starting this one removed from its output folder
    /// (frames, series, statistics, a checkpoint; nothing else in the folder is touched).
    pub fn removed_outputs(&self) -> usize {
        self.removed_outputs
    }

    /// The CSV series the run writes (metrics, probes), row by row as it steps.
    pub fn series(&self) -> impl Iterator<Item = &CsvSeries> {
        self.pipeline.stages.iter().filter_map(|s| s.series())
    }

    /// A progress bar (drawn only with `show`) over the stretch from here to where stepping
    /// stops: the run's end, or the time `until` (s) or `steps` more steps if they come first.
    pub fn progress(&self, show: bool, until: Option<Real>, steps: Option<u64>) -> Progress {
        let sim = &self.pipeline.sim;
        let start = (sim.time(), sim.steps());
        let end_time = self.end.time.into_iter().chain(until).reduce(Real::min);
        let end_step = self.end.steps.into_iter().chain(steps.map(|n| start.1 + n));
        Progress::new(show, start, (end_time, end_step.min()))
    }

    /// Writes what a run writes at its end (the line probes, the time-averaged velocity) and
    /// says what it did; the trace is left empty. A run may go on stepping after it.
    pub fn finish(&mut self) -> Result<RunSummary, RunError> {
        let p = &mut self.pipeline;
        p.outputs.finish(&p.sim)?;
        let p = &self.pipeline;
        let sph = p.sim.sph.as_ref();
        Ok(RunSummary {
            steps: p.sim.steps(),
            time: p.sim.time(),
            frames: p.outputs.frames(),
            fluid_particles: sph.map_or(0, |s| s.fluid.len()),
            lost_particles: sph.map_or(0, |s| s.lost_particles()),
            boundary_particles: sph.map_or(0, |s| s.boundary.len()),
            grid_cells: p.sim.grid.as_ref().map_or(0, |g| g.mac.cell_count()),
            wall_seconds: self.started.elapsed().as_secs_f64(),
            plan: self.plan.clone(),
            trace: Vec::new(),
            out: self.out.clone(),
        })
    }
}

impl Pipeline {
    /// One step: every solver's stable step, the smallest of them shortened to land on `end`,
    /// then every stage in order with it. With `trace`, appends each stage's name and then
    /// `name/part` for each part it ran.
    pub fn step(
        &mut self,
        end: Option<Real>,
        mut trace: Option<&mut Vec<String>>,
    ) -> Result<StepRecord, StepError> {
        let sim = &mut self.sim;
        let dt = sim.stable_dt()?;
        let dt = end.map_or(dt, |t| towards_end(dt, t - sim.time));
        let mut rec = StepRecord {
            step: sim.steps,
            time: sim.time,
            dt,
            ..Default::default()
        };
        self.stage_seconds.resize(self.stages.len(), 0.0);
        // The state may have been edited between steps (Python, a restore).
        sim.particle_vorticity = None;
        for (stage, seconds) in self.stages.iter_mut().zip(&mut self.stage_seconds) {
            let started = Instant::now();
            if !stage.measures_only() {
                sim.particle_vorticity = None;
            }
            stage.run(sim, &mut rec)?;
            *seconds += started.elapsed().as_secs_f64();
            if let Some(trace) = trace.as_deref_mut() {
                trace.push(stage.name().to_owned());
                let parts = stage.ran(sim).iter();
                trace.extend(parts.map(|part| format!("{}/{part}", stage.name())));
            }
        }
        sim.time += dt;
        sim.steps += 1;
        Ok(rec)
    }
}

/// A failed step as a run error that says how many frames were kept, and where.
fn stopped(e: StepError, frames: usize, out: &Path) -> RunError {
    let out = out.to_path_buf();
    match e {
        StepError::Sph(cause) => RunError::Unstable { cause, frames, out },
        StepError::Grid(cause) => RunError::Grid {
            cause: Box::new(cause),
            frames,
            out,
        },
        StepError::Io(e) => RunError::Io(e),
        StepError::Vortex(e) => RunError::Vortex(e),
    }
}

/// A run's progress bar, as `eddy run` and `Simulation.run(progress=True)` show it: the share
/// done of a stretch of simulated time or of steps (whichever is further along, as the first
/// to reach its end stops the run), elapsed time, ETA and the step's figures.
pub struct Progress {
    bar: ProgressBar,
    /// Simulated time (s) and steps at the stretch's start.
    start: (Real, u64),
    /// Where it ends, in time and in steps, if bounded.
    end: (Option<Real>, Option<u64>),
}

/// Positions along a bounded bar: the share done in thousandths.
const BAR_LENGTH: u64 = 1000;

impl Progress {
    fn new(show: bool, start: (Real, u64), end: (Option<Real>, Option<u64>)) -> Self {
        let bar = match (show, end.0.is_some() || end.1.is_some()) {
            (false, _) => ProgressBar::hidden(),
            (true, true) => ProgressBar::new(BAR_LENGTH),
            (true, false) => ProgressBar::no_length(),
        };
        bar.set_style(
            ProgressStyle::with_template(
                "{spinner} [{elapsed_precise}] {wide_bar} {percent:>3}% ETA {eta} {msg}",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        Self { bar, start, end }
    }

    /// Shows where `run` is after the step `rec`.
    pub fn update(&self, run: &Run, rec: &StepRecord) {
        let sim = &run.pipeline.sim;
        let (time, steps) = (sim.time(), sim.steps());
        let share = |now: Real, from: Real, to: Real| {
            if to > from {
                ((now - from) / (to - from)).clamp(0.0, 1.0)
            } else {
                1.0
            }
        };
        let taken = steps - self.start.1;
        let by_time = self.end.0.map(|to| share(time, self.start.0, to));
        let by_steps = self
            .end
            .1
            .map(|to| share(steps as Real, self.start.1 as Real, to as Real));
        match by_time.into_iter().chain(by_steps).reduce(Real::max) {
            Some(done) => self
                .bar
                .set_position((done * BAR_LENGTH as Real).round() as u64),
            None => self.bar.set_position(taken),
        }
        let elapsed = self.bar.elapsed().as_secs_f64().max(1e-9);
        let mut msg = format!(
            "t = {time:.4} s, step {steps}, dt = {:.2e} s, {:.1} steps/s",
            rec.dt,
            taken as f64 / elapsed
        );
        if let Some(g) = rec.grid {
            msg += &format!(
                ", {} CG iterations, change {:.1e}/s",
                g.pressure_iterations, g.change_rate
            );
        }
        if let Some(lost) = rec.sph.map(|s| s.lost).filter(|&n| n > 0) {
            msg += &format!(", {lost} fluid particles lost");
        }
        self.bar.set_message(msg);
    }

    /// Clears the bar from the terminal.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}
