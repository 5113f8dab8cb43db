//! Checkpoints and resume: between two steps the whole state a run needs to go on (the
//! solvers', the turbulence's, the statistics', the stages' and outputs' own, the frame
//! counter and the rows each series has written) goes into `checkpoint.h5`; a resumed run is
//! built from the same scene, takes that state back and goes on, ending bit for bit where the
//! run that never stopped ends. What is saved is each part's [`Persist`] (`crate::state`).

use std::path::{Path, PathBuf};

use super::build::Pipeline;
use super::outputs::CHECKPOINT_FILE;
use crate::io::{kept_rows, read_checkpoint, AttrValue, IoError, KeptRows};
use crate::state::{Persist, State, StateError};

/// The exit status of a run stopped by SIGINT or SIGTERM once its checkpoint is written
/// (`EX_TEMPFAIL`: the job may be submitted again and go on).
pub const INTERRUPTED_EXIT: u8 = 75;

/// Why a run could not go on from a checkpoint.
#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    #[error(
        "no checkpoint to go on from in {}: a run writes {CHECKPOINT_FILE} every \
         output.checkpoint_interval s of simulated time, every output.checkpoint_every \
         minutes, and when SIGINT or SIGTERM stops it",
        .0.display()
    )]
    Missing(PathBuf),
    #[error("{}: {source}", path.display())]
    State {
        path: PathBuf,
        #[source]
        source: StateError,
    },
    #[error(
        "{}: the checkpoint is of another scene ({difference}); a resumed run may change only \
         time.end, time.steps and the [output] keys",
        path.display()
    )]
    OtherScene { path: PathBuf, difference: String },
}

/// The first line where two comparable scenes differ, for the refusal.
fn difference(ours: &str, theirs: &str) -> String {
    let (mut a, mut b) = (ours.lines(), theirs.lines());
    loop {
        match (a.next(), b.next()) {
            (Some(x), Some(y)) if x == y => continue,
            (x, y) => {
                return format!(
                    "this scene has `{}` where the checkpoint's has `{}`",
                    x.unwrap_or("(nothing)"),
                    y.unwrap_or("(nothing)")
                )
            }
        }
    }
}

impl Pipeline {
    /// The state between two steps: the simulation's parts, then every stage's and output's
    /// own by position and name, and the rows of each CSV series.
    pub fn save_state(&self) -> State {
        let mut state = State::new();
        self.save_into(&mut state);
        state
    }

    /// Bytes of [`Pipeline::save_state`]'s arrays, counted without copying them.
    pub fn state_bytes(&self) -> usize {
        let mut state = State::sizing();
        self.save_into(&mut state);
        state.bytes()
    }

    fn save_into(&self, state: &mut State) {
        let sim = &self.sim;
        {
            let mut s = state.section("simulation");
            s.real("time", sim.time);
            s.u64("steps", sim.steps);
            if let Some(grid) = &sim.grid {
                grid.save(&mut s.section("grid"));
            }
            if let Some(sph) = &sim.sph {
                sph.save(&mut s.section("sph"));
            }
            if let Some(t) = &sim.grid_turbulence {
                t.save(&mut s.section("grid_turbulence"));
            }
            if let Some(t) = &sim.sph_turbulence {
                t.save(&mut s.section("sph_turbulence"));
            }
            for (i, m) in sim.statistics.iter().enumerate() {
                m.stats.save(&mut s.section(&format!("statistics_{i}")));
            }
        }
        for (i, stage) in self.stages.iter().enumerate() {
            let mut s = state.section(&stage_section(i, stage.name()));
            stage.save(&mut s);
            if let Some(csv) = stage.series() {
                let file = csv.path().file_name().unwrap_or_default();
                s.bytes("csv_file", file.to_string_lossy().as_bytes());
                s.u64("csv_rows", csv.rows());
            }
        }
        self.outputs.save(&mut state.section("outputs"));
    }

    /// Takes back the state [`Pipeline::save_state`] saved, into a pipeline freshly built from
    /// the same scene (its outputs already resumed).
    pub fn restore_state(&mut self, state: &State) -> Result<(), StateError> {
        let sim = &mut self.sim;
        let s = state.read("simulation");
        sim.time = s.real("time")?;
        sim.steps = s.u64("steps")?;
        if let Some(grid) = sim.grid.as_mut() {
            grid.restore(&s.section("grid"))?;
        }
        if let Some(sph) = sim.sph.as_mut() {
            sph.restore(&s.section("sph"))?;
        }
        if let Some(t) = sim.grid_turbulence.as_mut() {
            t.restore(&s.section("grid_turbulence"))?;
        }
        if let Some(t) = sim.sph_turbulence.as_mut() {
            t.restore(&s.section("sph_turbulence"))?;
        }
        for (i, m) in sim.statistics.iter_mut().enumerate() {
            m.stats.restore(&s.section(&format!("statistics_{i}")))?;
        }
        for (i, stage) in self.stages.iter_mut().enumerate() {
            stage.restore(&state.read(&stage_section(i, stage.name())))?;
        }
        for stage in &mut self.stages {
            // Whatever a stage measured of the state when it opened is measured again.
            stage.state_edited(&self.sim);
        }
        Ok(())
    }

    /// Opens the stages' files in `out` to go on from `state`: each CSV series keeps the rows
    /// the checkpoint counted (any written after it are dropped) and goes on below them.
    pub(super) fn open_to_resume(&mut self, out: &Path, state: &State) -> Result<(), IoError> {
        let mut kept: Vec<Option<KeptRows>> = Vec::new();
        for (i, stage) in self.stages.iter().enumerate() {
            let s = state.read(&stage_section(i, stage.name()));
            let series = s
                .bytes("csv_file")
                .and_then(|file| Ok((file, s.u64("csv_rows")?)));
            kept.push(match series {
                Ok((file, rows)) => {
                    let file = String::from_utf8_lossy(&file).into_owned();
                    Some(kept_rows(&out.join(file), rows)?)
                }
                Err(_) => None,
            });
        }
        for (stage, kept) in self.stages.iter_mut().zip(&kept) {
            stage.open(&self.sim, out)?;
            if let (Some(csv), Some(kept)) = (stage.series_mut(), kept) {
                csv.go_on_from(kept)?;
            }
        }
        self.outputs.resume(&self.sim, out, &state.read("outputs"))
    }
}

fn stage_section(i: usize, name: &str) -> String {
    format!("stages/{i}_{name}")
}

/// The checkpoint in `out`, read and checked against the run's scene as a checkpoint records
/// it (`RunSpec::checkpoint_key`).
pub(super) fn load(out: &Path, ours: &str) -> Result<State, super::RunError> {
    let path = out.join(CHECKPOINT_FILE);
    if !path.exists() {
        return Err(CheckpointError::Missing(out.to_path_buf()).into());
    }
    let stored = read_checkpoint(&path)?;
    let theirs = stored.text("scene").unwrap_or_default();
    if ours != theirs {
        return Err(CheckpointError::OtherScene {
            difference: difference(ours, theirs),
            path,
        }
        .into());
    }
    Ok(stored.state)
}

/// The root attributes of a checkpoint of `scene` at `time` after `steps` steps.
pub(super) fn attributes(
    scene: &str,
    time: crate::Real,
    steps: u64,
) -> Vec<(&'static str, AttrValue)> {
    vec![
        ("scene", AttrValue::Str(scene.to_owned())),
        ("time", AttrValue::Real(time)),
        ("step", AttrValue::Int(steps as i64)),
    ]
}
