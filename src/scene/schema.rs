//! The scene file format: serde structs that mirror the TOML one to one.
//!
//! Every struct denies unknown keys, so a misspelt key is an error rather than a silently ignored
//! setting. Defaults are the values a user gets when a key is left out; they are documented on
//! each field and in the book's "Scene files" chapter (docs/src/scene-files.md).

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

pub use crate::abl::{Seeding, TurbulenceParams};
pub use crate::geometry::{AblLink, Body, Keyframe, Motion, Shape};
pub use crate::metrics::{Axis, Metric, Probe};
pub use crate::sph::{FluidBlock, Pressure, PressureSolverKind, Viscosity};
use crate::stepping::StepLimits;
use crate::Real;

/// A whole scene: what is simulated, how, and what is written.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Name of the scene; the default output folder is `out/<name>`.
    pub name: String,
    /// Seed of every random generator in the run, so runs reproduce exactly.
    #[serde(default)]
    pub seed: u64,
    /// The simulation domain. A fluid particle beyond it (by more than 0.6 particle spacings,
    /// the depth of the wall samples behind a container flush with it) in the open, having left
    /// through a side no wall closes, is removed and counted (`fluid.lost_fraction`); one beyond
    /// it inside a solid went through a wall, and stops the run as unstable.
    pub domain: Domain,
    /// Gravitational acceleration in m/s^2.
    #[serde(default = "default_gravity")]
    pub gravity: [Real; 3],
    /// Time stepping.
    pub time: TimeStepping,
    /// The SPH fluid, if the scene has one.
    #[serde(default)]
    pub fluid: Option<Fluid>,
    /// The MAC-grid fluid, if the scene has one; its viscosity is `viscosity.kinematic`.
    #[serde(default)]
    pub grid: Option<super::grid::Grid>,
    /// The container the fluid sits in (its surface is sampled with boundary particles). In a
    /// scene with a `[fluid]` it is the water's tank: a grid in the same scene sees its outside
    /// as solid and its inside open, so a container as large as the domain leaves the whole
    /// grid to the air.
    #[serde(default)]
    pub container: Option<Body>,
    /// Obstacles in the flow, static or kinematically moving.
    #[serde(default)]
    pub obstacles: Vec<Body>,
    /// The pressure solver.
    #[serde(default)]
    pub pressure: Pressure,
    /// Viscosity.
    #[serde(default)]
    pub viscosity: Viscosity,
    /// Run-time parameters of the artificial boundary layers (obstacles with `abl`); the
    /// defaults of Pfaff et al. 2009 when left out.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub turbulence: Option<crate::abl::TurbulenceParams>,
    /// The exchange across the water surface when the scene has both a grid (the air) and a
    /// fluid (the water); without it the two only share the clock.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub coupling: Option<super::Coupling>,
    /// The SPH turbulence refinement (`none` when left out). Its keys are each method's own
    /// (`crate::refine::registry`), so the scene reference reads them from the registry.
    #[serde(default)]
    #[schemars(skip)]
    pub refinement: crate::refine::Refinement,
    /// Probes, each written as columns of `probes.csv`.
    #[serde(default)]
    pub probes: Vec<Probe>,
    /// Running statistics of the flow (mean velocity, Reynolds stresses, k, mean vorticity
    /// and enstrophy), written as `statistics.h5` at every frame time; none when left out.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub statistics: Option<Statistics>,
    /// Further stages of a step, by the names they were registered with from outside eddy
    /// (`eddy::pipeline::register_stage`); none by default.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub stages: Vec<String>,
    /// What is written, and where.
    #[serde(default)]
    pub output: Output,
}

fn default_gravity() -> [Real; 3] {
    [0.0, -9.81, 0.0]
}

/// An axis-aligned box given by its corners.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Domain {
    /// Lower corner, m.
    pub min: [Real; 3],
    /// Upper corner, m.
    pub max: [Real; 3],
}

/// Time stepping: how long, and how the step size is chosen.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TimeStepping {
    /// Simulated end time, s. At least one of `end` and `steps` is given; with both the run
    /// ends at whichever comes first.
    #[serde(default)]
    pub end: Option<Real>,
    /// Number of steps (see `end`). `eddy run --until` and `--steps` are recorded in `end` and
    /// `steps` of the run's resolved `scene.toml`.
    #[serde(default)]
    pub steps: Option<u64>,
    /// CFL factor: dt = cfl * spacing / max speed. In (0, 1].
    #[serde(default = "default_cfl")]
    pub cfl: Real,
    /// Smallest allowed step, s; a run that needs a smaller one stops as unstable.
    #[serde(default = "default_dt_min")]
    pub dt_min: Real,
    /// Largest allowed step, s.
    #[serde(default = "default_dt_max")]
    pub dt_max: Real,
    /// A fixed step, s, instead of the CFL rule (benchmarks use this).
    #[serde(default)]
    pub dt: Option<Real>,
}

fn default_cfl() -> Real {
    StepLimits::default().cfl
}
fn default_dt_min() -> Real {
    StepLimits::default().dt_min
}
fn default_dt_max() -> Real {
    StepLimits::default().dt_max
}

/// The SPH fluid.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Fluid {
    /// Particle spacing (twice the particle radius), m. The kernel support is twice this.
    pub spacing: Real,
    /// Rest density, kg/m^3.
    #[serde(default = "default_density")]
    pub density: Real,
    /// Boxes filled with particles on a cubic lattice at `spacing`.
    pub blocks: Vec<FluidBlock>,
    /// Inflow emitters on the domain's sides.
    #[serde(default)]
    pub inflow: Vec<crate::sph::Inflow>,
    /// Outflow sides of the domain.
    #[serde(default)]
    pub outflow: Vec<crate::sph::Outflow>,
    /// Smooth start, s: the inflows' velocity and the blocks' velocity rise from zero as
    /// (1 - cos(pi t / ramp)) / 2; the blocks start at rest and the whole fluid is accelerated
    /// by their velocity times the ramp's rate, a uniform body acceleration (0: every block
    /// moves at its velocity and every inflow at its own from t = 0).
    #[serde(default)]
    pub ramp: Real,
    /// The share of the fluid particles that may leave the domain through sides no wall
    /// closes (a splash over the top or a bank): each is removed and counted (`lost_particles`
    /// in metrics.csv), and the run stops as unstable once they exceed this share of the
    /// particles present (0: at the first).
    #[serde(default = "default_lost_fraction")]
    pub lost_fraction: Real,
}

fn default_density() -> Real {
    1000.0
}
fn default_lost_fraction() -> Real {
    0.01
}

/// Running statistics: per grid cell, or per bin of a lattice over an SPH fluid's domain, the
/// time averages of the velocity, its fluctuations' products (the Reynolds stresses), k, the
/// vorticity and the enstrophy.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Statistics {
    /// Simulated time the averaging starts, s (the flow's start-up left out).
    #[serde(default)]
    pub from: Real,
    /// Sample every this many steps (each sample stands for the time since the last).
    #[serde(default = "default_every")]
    pub every: u64,
    /// Edge of the bins of an SPH fluid's lattice, m; two particle spacings when left out.
    /// (On a grid the statistics live on its cells.)
    #[serde(default)]
    pub bin: Option<Real>,
    /// Batches the averaging window (`from` to `time.end`) is cut into for the stations'
    /// confidence intervals (batch means).
    #[serde(default = "default_batches")]
    pub batches: u64,
    /// Stations: profiles of U and k across a box, written as `station_NAME.csv`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub stations: Vec<Station>,
}

fn default_batches() -> u64 {
    10
}

impl Default for Statistics {
    fn default() -> Self {
        Self {
            from: 0.0,
            every: default_every(),
            bin: None,
            batches: default_batches(),
            stations: Vec::new(),
        }
    }
}

/// A station: the box from `min` to `max` cut into `bins` equal bins along `axis`; each bin's
/// time-averaged U and k (averaged over the statistics' cells whose centres lie in it) with
/// their 95 % confidence half-widths, at every frame time.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Station {
    /// Names the file `station_NAME.csv`.
    pub name: String,
    /// Lower corner, m.
    pub min: [Real; 3],
    /// Upper corner, m.
    pub max: [Real; 3],
    /// The axis the profile runs along.
    pub axis: Axis,
    /// Bins along `axis`.
    pub bins: usize,
    /// A homogeneous direction (a periodic span) along which the cells are pooled as one
    /// ensemble, so the spread of their means counts as fluctuation; none by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pool: Option<Axis>,
}

fn default_every() -> u64 {
    1
}

/// Outputs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Output {
    /// Output folder; `out/<scene name>` when left out. `eddy run --out` overrides it.
    #[serde(default)]
    pub dir: Option<PathBuf>,
    /// Simulated time between frames, s (the first frame is t = 0). Frame k is written at
    /// exactly k x interval: the steps before each frame time are shortened as before the end
    /// time, whether or not frames are written, so the output formats do not change the run.
    #[serde(default = "default_interval")]
    pub interval: Real,
    /// Write one VTK file per frame plus a `.pvd` series for ParaView (`particles.pvd`,
    /// `grid.pvd`).
    #[serde(default = "default_true")]
    pub vtk: bool,
    /// Write the frames as HDF5 as well: each frame its own file `frames_NNNNNN.h5`, the index
    /// `frames.h5` linking the complete ones, and `frames.xmf` beside it for ParaView
    /// (`grid_frames.*` and `particles_frames.*` in a scene with both media).
    #[serde(default)]
    pub hdf5: bool,
    /// Compression level of the frames, 0 to 9 (0: uncompressed). HDF5 datasets are chunked
    /// whole, byte-shuffled and deflated, HDF5's built-in filters that h5py and ParaView read
    /// as they are; VTK arrays are appended raw in zlib blocks, as VTK's own writers do.
    #[serde(default = "default_compression")]
    pub compression: u8,
    /// Precision of the VTK frames' arrays, "f32" (the default: half the bytes, for looking
    /// at) or "f64" (the solver's values exactly). HDF5 frames are always f64.
    #[serde(default)]
    pub precision: crate::io::Precision,
    /// Columns of `metrics.csv` beyond step, time and dt, by name: every metric the scene's
    /// solvers offer when left out, none (and no `metrics.csv`) with []. Each solver writes
    /// those it offers (a name offered by neither is refused): an SPH fluid kinetic_energy,
    /// potential_energy, density_error_avg, density_error_max, max_speed,
    /// pressure_iterations, divergence_iterations, rotational_energy, total_energy,
    /// vorticity_mean, vorticity_max, enstrophy, refinement_seconds, particles,
    /// open_boundary_seconds, step_seconds; a grid kinetic_energy, max_divergence,
    /// pressure_iterations, pressure_residual, viscosity_iterations, cfl, change_rate,
    /// advect_seconds, project_seconds, step_seconds, vorticity_mean, vorticity_max, enstrophy.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub metrics: Option<Vec<Metric>>,
    /// Further output formats, by the names they were registered with from outside eddy
    /// (`eddy::pipeline::outputs::register`); none by default.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub formats: Vec<String>,
    /// Simulated time between checkpoints (`checkpoint.h5`, the whole state a run needs to go
    /// on with `eddy resume`), s; none by default. A run also writes one when it receives
    /// SIGINT or SIGTERM, whatever this says.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub checkpoint_interval: Option<Real>,
    /// Wall-clock minutes between checkpoints (for a job with a time limit); none by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub checkpoint_every: Option<Real>,
}

pub(super) fn default_true() -> bool {
    true
}
fn default_compression() -> u8 {
    4
}
fn default_interval() -> Real {
    1.0 / 30.0
}

impl Default for Output {
    fn default() -> Self {
        Self {
            dir: None,
            interval: default_interval(),
            vtk: true,
            hdf5: false,
            compression: default_compression(),
            precision: Default::default(),
            metrics: None,
            formats: Vec::new(),
            checkpoint_interval: None,
            checkpoint_every: None,
        }
    }
}
