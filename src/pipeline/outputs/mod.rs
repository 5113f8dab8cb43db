//! Everything a run writes besides its per-step rows, behind one [`Output`] trait: VTK frames,
//! HDF5 frames with XDMF, the running statistics, the grid's time average, line profiles. Each format is a file here
//! and one line of [`BUILT_IN`] (or a [`register`] call from outside the crate); it declares
//! the files it writes ([`RunFile`]), so [`is_run_output`] knows every run's files, and it
//! chooses from the run's [`OutputSpec`] whether it is built at all.

mod average;
mod files;
mod frame;
mod hdf5;
mod profiles;
mod statistics;
mod vtk;

use std::path::Path;
use std::sync::RwLock;

pub use files::{
    is_run_output, remove_earlier_outputs, Kind, RunFile, CHECKPOINT_FILE, METRICS_FILE,
    PROBES_FILE, SCENE_FILE, STAGE_FILES,
};
pub use frame::Frame;
pub use profiles::LineProbe;
pub use statistics::{write_statistics, STATISTICS_FORMAT, STATISTICS_FORMAT_VERSION};

use super::{RunError, Simulation};
use crate::io::{AttrValue, IoError, VtkOptions};
use crate::state::{Restorer, Saver};
use crate::Real;

/// What a run asked to have written: the scene's `[output]` and line probes, resolved by
/// `scene::build`, so no output reads a scene.
#[derive(Debug, Clone)]
pub struct OutputSpec {
    /// Simulated time between frames, s.
    pub interval: Real,
    /// VTK frames (`output.vtk`).
    pub vtk: bool,
    /// How VTK files store their arrays (`output.precision`, `output.compression`).
    pub vtk_options: VtkOptions,
    /// HDF5 frames (`output.hdf5`).
    pub hdf5: bool,
    /// Deflate level of the HDF5 datasets (`output.compression`).
    pub compression: u8,
    /// Root attributes of every HDF5 file (scene name, seed).
    pub attrs: Vec<(&'static str, AttrValue)>,
    /// Line probes of a grid, written as profiles at the end.
    pub profiles: Vec<LineProbe>,
    /// Registered formats asked for by name (`output.formats`).
    pub formats: Vec<String>,
    /// Simulated time between checkpoints, s (`output.checkpoint_interval`).
    pub checkpoint_interval: Option<Real>,
    /// Wall-clock minutes between checkpoints (`output.checkpoint_every`).
    pub checkpoint_every: Option<Real>,
}

/// One output of a run: it creates its files when the run opens, writes at every frame time
/// and once more at the end.
pub trait Output: Send {
    /// Short name, for messages.
    fn name(&self) -> &'static str;

    /// The plan's lines: (what, which files and when).
    fn describe(&self, sim: &Simulation) -> Vec<(&'static str, String)>;

    /// Creates its files in `out`, before the first step.
    fn open(&mut self, sim: &Simulation, out: &Path) -> Result<(), IoError>;

    /// Writes what is due at a frame time (the frame's fields are computed once, on first
    /// use, for all outputs).
    fn write(&mut self, frame: &Frame) -> Result<(), IoError>;

    /// Writes what is due at the end of the run (a run may go on stepping after it).
    fn finish(&mut self, _sim: &Simulation) -> Result<(), IoError> {
        Ok(())
    }

    /// Frames written so far (0 for an output that writes none).
    fn frames(&self) -> usize {
        0
    }

    /// Puts what it needs to go on after a resume (the frames it has listed) into a
    /// checkpoint.
    fn save(&self, _into: &mut Saver) {}

    /// Opens its files in `out` to go on from a checkpoint, instead of [`Output::open`]. An
    /// output that rewrites whole files at every frame (the statistics, the profiles, the
    /// average) opens as usual; one that appends must say how it goes on, or refuse.
    fn resume(&mut self, sim: &Simulation, out: &Path, _from: &Restorer) -> Result<(), IoError> {
        self.open(sim, out)
    }
}

/// An output format: its name, the files it writes and its constructor.
pub struct Format {
    pub name: &'static str,
    /// One line, for help texts.
    pub summary: &'static str,
    /// Every file it may write into a run's folder.
    pub files: &'static [RunFile],
    /// Its writer for this run, or `None` when the run does not ask for it.
    pub build: fn(&OutputSpec, &Simulation) -> Option<Box<dyn Output>>,
}

/// The built-in formats, in the order they write and the plan lists them.
pub static BUILT_IN: [Format; 5] = [
    Format {
        name: "vtk",
        summary: "VTK frames with ParaView .pvd series (output.vtk)",
        files: vtk::FILES,
        build: vtk::build,
    },
    Format {
        name: "hdf5",
        summary: "HDF5 frames with XDMF for h5py and ParaView (output.hdf5)",
        files: hdf5::FILES,
        build: hdf5::build,
    },
    Format {
        name: "statistics",
        summary: "the running statistics of [statistics], at every frame time",
        files: statistics::FILES,
        build: statistics::build,
    },
    Format {
        name: "profile",
        summary: "grid velocity along each line probe, at the end",
        files: profiles::FILES,
        build: profiles::build,
    },
    Format {
        name: "average",
        summary: "the grid's time-averaged velocity, at the end",
        files: average::FILES,
        build: average::build,
    },
];

/// Formats added by [`register`].
static REGISTERED: RwLock<Vec<&'static Format>> = RwLock::new(Vec::new());

/// Adds a format from outside the crate: a run builds it when `output.formats` names it (its
/// `build` decides). Refuses a name that is taken or a file family a run already writes.
pub fn register(format: Format) -> Result<(), String> {
    let mut registered = REGISTERED.write().unwrap_or_else(|e| e.into_inner());
    let all: Vec<&Format> = BUILT_IN.iter().chain(registered.iter().copied()).collect();
    if all.iter().any(|f| f.name == format.name) {
        return Err(format!("an output format named `{}` exists", format.name));
    }
    let taken = all
        .iter()
        .flat_map(|f| f.files.iter())
        .chain(&STAGE_FILES)
        .find(|f| format.files.contains(f));
    if let Some(f) = taken {
        return Err(format!("{f:?} is written by another output"));
    }
    registered.push(Box::leak(Box::new(format)));
    Ok(())
}

/// Every format: the built-in ones, then the registered ones.
pub fn formats() -> Vec<&'static Format> {
    let registered = REGISTERED.read().unwrap_or_else(|e| e.into_inner());
    BUILT_IN.iter().chain(registered.iter().copied()).collect()
}

/// The outputs of one run, in the order of [`formats`].
pub struct Outputs {
    /// Simulated time between frames, s.
    pub interval: Real,
    /// Simulated time between checkpoints, s.
    pub checkpoint_interval: Option<Real>,
    /// Wall-clock minutes between checkpoints.
    pub checkpoint_every: Option<Real>,
    list: Vec<Box<dyn Output>>,
}

impl Outputs {
    /// The writers `spec` asks for; nothing is written. An unknown name in `output.formats` is
    /// refused with the names there are.
    pub fn build(spec: &OutputSpec, sim: &Simulation) -> Result<Self, RunError> {
        let all = formats();
        if let Some(unknown) = spec
            .formats
            .iter()
            .find(|n| !all.iter().any(|f| f.name == n.as_str()))
        {
            let names: Vec<_> = all.iter().map(|f| f.name).collect();
            return Err(RunError::Unsupported(format!(
                "`output.formats`: unknown format `{unknown}`, expected one of {}",
                names.join(", ")
            )));
        }
        Ok(Self {
            interval: spec.interval,
            checkpoint_interval: spec.checkpoint_interval,
            checkpoint_every: spec.checkpoint_every,
            list: all.iter().filter_map(|f| (f.build)(spec, sim)).collect(),
        })
    }

    /// Creates every output's files in `out`.
    pub fn open(&mut self, sim: &Simulation, out: &Path) -> Result<(), IoError> {
        self.list.iter_mut().try_for_each(|o| o.open(sim, out))
    }

    /// Writes every output's frame of the current state.
    pub fn write(&mut self, sim: &Simulation) -> Result<(), IoError> {
        let frame = Frame::new(sim);
        self.list.iter_mut().try_for_each(|o| o.write(&frame))
    }

    /// Writes what every output writes at the end.
    pub fn finish(&mut self, sim: &Simulation) -> Result<(), IoError> {
        self.list.iter_mut().try_for_each(|o| o.finish(sim))
    }

    /// Puts each output's state under `into`, by position and name.
    pub fn save(&self, into: &mut Saver) {
        for (i, o) in self.list.iter().enumerate() {
            o.save(&mut into.section(&format!("{i}_{}", o.name())));
        }
    }

    /// Opens every output in `out` to go on from a checkpoint (see [`Output::resume`]).
    pub fn resume(&mut self, sim: &Simulation, out: &Path, from: &Restorer) -> Result<(), IoError> {
        for (i, o) in self.list.iter_mut().enumerate() {
            let section = from.section(&format!("{i}_{}", o.name()));
            o.resume(sim, out, &section)?;
        }
        Ok(())
    }

    /// Frames written so far (of the output that wrote most).
    pub fn frames(&self) -> usize {
        self.list.iter().map(|o| o.frames()).max().unwrap_or(0)
    }

    /// The plan's lines on the outputs, in order.
    pub fn describe(&self, sim: &Simulation) -> Vec<(&'static str, String)> {
        self.list.iter().flat_map(|o| o.describe(sim)).collect()
    }

    /// The outputs' names, in order.
    pub fn names(&self) -> Vec<&'static str> {
        self.list.iter().map(|o| o.name()).collect()
    }
}
