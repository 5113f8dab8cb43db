//! The scene file format: serde structs that mirror the TOML one to one.
//!
//! Every struct denies unknown keys, so a misspelt key is an error rather than a silently ignored
//! setting. Defaults are the values a user gets when a key is left out; they are documented on
//! each field and in `scenes/README.md`.

use serde::{Deserialize, Serialize};
use std::path::PathBuf;

use crate::Real;

/// A whole scene: what is simulated, how, and what is written.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Name of the scene; the default output folder is `out/<name>`.
    pub name: String,
    /// Seed of every random generator in the run, so runs reproduce exactly.
    #[serde(default)]
    pub seed: u64,
    /// The simulation domain; a particle that leaves it stops the run as unstable.
    pub domain: Domain,
    /// Gravitational acceleration in m/s^2.
    #[serde(default = "default_gravity")]
    pub gravity: [Real; 3],
    /// Time stepping.
    pub time: TimeStepping,
    /// The SPH fluid, if the scene has one.
    #[serde(default)]
    pub fluid: Option<Fluid>,
    /// The MAC-grid fluid, if the scene has one.
    #[serde(default)]
    pub grid: Option<super::grid::Grid>,
    /// The container the fluid sits in (its surface is sampled with boundary particles).
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
    /// The SPH turbulence refinement (`none` when left out).
    #[serde(default)]
    pub refinement: super::refinement::Refinement,
    /// Probes, each written as columns of `probes.csv`.
    #[serde(default)]
    pub probes: Vec<Probe>,
    /// What is written, and where.
    #[serde(default)]
    pub output: Output,
}

fn default_gravity() -> [Real; 3] {
    [0.0, -9.81, 0.0]
}

/// An axis-aligned box given by its corners.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Domain {
    /// Lower corner, m.
    pub min: [Real; 3],
    /// Upper corner, m.
    pub max: [Real; 3],
}

/// Time stepping: how long, and how the step size is chosen.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TimeStepping {
    /// Simulated end time, s. Exactly one of `end` and `steps` is given.
    #[serde(default)]
    pub end: Option<Real>,
    /// Number of steps. Exactly one of `end` and `steps` is given.
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
    0.4
}
fn default_dt_min() -> Real {
    1e-6
}
fn default_dt_max() -> Real {
    5e-3
}

/// The SPH fluid.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Fluid {
    /// Particle spacing (twice the particle radius), m. The kernel support is twice this.
    pub spacing: Real,
    /// Rest density, kg/m^3.
    #[serde(default = "default_density")]
    pub density: Real,
    /// Boxes filled with particles on a cubic lattice at `spacing`.
    pub blocks: Vec<FluidBlock>,
}

fn default_density() -> Real {
    1000.0
}

/// A box of fluid.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FluidBlock {
    /// Lower corner, m.
    pub min: [Real; 3],
    /// Upper corner, m.
    pub max: [Real; 3],
    /// Initial velocity, m/s.
    #[serde(default)]
    pub velocity: [Real; 3],
}

/// A rigid body: the container or an obstacle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Body {
    /// Name used in messages and outputs; defaults to the shape and index.
    #[serde(default)]
    pub name: Option<String>,
    /// The shape, in the body's own frame.
    pub shape: Shape,
    /// Position of the body's origin at t = 0, m.
    #[serde(default)]
    pub position: [Real; 3],
    /// Orientation at t = 0 as a rotation vector (axis times angle, radians).
    #[serde(default)]
    pub rotation: [Real; 3],
    /// Kinematic motion; static when left out.
    #[serde(default)]
    pub motion: Motion,
}

/// Shapes, after parry3d's conventions: cylinders and capsules lie along the local y axis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum Shape {
    /// A box with the given half extents, m.
    Box { half_extents: [Real; 3] },
    /// A sphere.
    Sphere { radius: Real },
    /// A cylinder along local y.
    Cylinder { radius: Real, half_height: Real },
    /// A capsule along local y (half_height is that of the cylindrical part).
    Capsule { radius: Real, half_height: Real },
    /// A closed triangle mesh from an OBJ or STL file, relative to the scene file.
    Mesh {
        path: PathBuf,
        #[serde(default = "default_scale")]
        scale: Real,
    },
}

fn default_scale() -> Real {
    1.0
}

/// Kinematic motion of a body: constant linear and angular velocity, or a keyframed path.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Motion {
    /// Linear velocity, m/s.
    #[serde(default)]
    pub linear: [Real; 3],
    /// Angular velocity about the body origin, rad/s.
    #[serde(default)]
    pub angular: [Real; 3],
    /// Keyframes (times strictly increasing); when given they replace `linear` and `angular`.
    /// Position is interpolated linearly, orientation by slerp; the pose is held outside the range.
    #[serde(default)]
    pub keyframes: Vec<Keyframe>,
}

/// A pose at a time.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Keyframe {
    /// Time, s.
    pub t: Real,
    /// Position of the body origin, m.
    pub position: [Real; 3],
    /// Orientation as a rotation vector, radians.
    #[serde(default)]
    pub rotation: [Real; 3],
}

/// Which pressure solver runs.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PressureSolverKind {
    /// Divergence-free SPH (Bender & Koschier 2015/2017).
    #[default]
    Dfsph,
    /// Implicit incompressible SPH (Ihmsen et al. 2014).
    Iisph,
}

/// Pressure solver settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Pressure {
    /// `dfsph` or `iisph`.
    #[serde(default)]
    pub solver: PressureSolverKind,
    /// Allowed average density error, as a fraction of the rest density (0.0005 = 0.05 %).
    #[serde(default = "default_density_tolerance")]
    pub density_tolerance: Real,
    /// Allowed average density change rate times dt, as a fraction (DFSPH divergence solver).
    #[serde(default = "default_divergence_tolerance")]
    pub divergence_tolerance: Real,
    /// Run the DFSPH divergence-free solver (ignored by IISPH).
    #[serde(default = "default_true")]
    pub divergence_solver: bool,
    /// Least iterations per solve.
    #[serde(default = "default_min_iterations")]
    pub min_iterations: u32,
    /// Most iterations per solve; a solve that hits it is reported in metrics.csv.
    #[serde(default = "default_max_iterations")]
    pub max_iterations: u32,
}

impl Default for Pressure {
    fn default() -> Self {
        Self {
            solver: PressureSolverKind::default(),
            density_tolerance: default_density_tolerance(),
            divergence_tolerance: default_divergence_tolerance(),
            divergence_solver: true,
            min_iterations: default_min_iterations(),
            max_iterations: default_max_iterations(),
        }
    }
}

fn default_density_tolerance() -> Real {
    0.0005
}
fn default_divergence_tolerance() -> Real {
    0.001
}
fn default_true() -> bool {
    true
}
fn default_min_iterations() -> u32 {
    2
}
fn default_max_iterations() -> u32 {
    100
}

/// Viscosity settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Viscosity {
    /// Kinematic viscosity of the Laplacian form (Liu et al. 2021 Eq. 4), m^2/s.
    #[serde(default)]
    pub kinematic: Real,
    /// Kinematic viscosity against boundary particles, m^2/s.
    #[serde(default)]
    pub boundary: Real,
    /// XSPH velocity smoothing factor in [0, 1].
    #[serde(default)]
    pub xsph: Real,
}

impl Default for Viscosity {
    fn default() -> Self {
        Self {
            kinematic: 0.0,
            boundary: 0.0,
            xsph: 0.0,
        }
    }
}

/// A coordinate axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Axis {
    X,
    Y,
    Z,
}

impl Axis {
    /// Index of the axis in a vector.
    pub fn index(self) -> usize {
        match self {
            Axis::X => 0,
            Axis::Y => 1,
            Axis::Z => 2,
        }
    }
}

/// A probe, sampled every step into `probes.csv`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum Probe {
    /// The fluid front: the largest coordinate along `axis` of any fluid particle, less `origin`.
    Front {
        name: String,
        axis: Axis,
        #[serde(default)]
        origin: Real,
    },
    /// Pressure and velocity at a point: kernel-interpolated (Shepard-normalised) on SPH,
    /// trilinear on the grid.
    Point { name: String, position: [Real; 3] },
    /// Grid only: the velocity at `points` evenly spaced samples from `from` to `to`, written
    /// as `profile_NAME.csv` at the end of the run.
    Line {
        name: String,
        from: [Real; 3],
        to: [Real; 3],
        #[serde(default = "default_line_points")]
        points: usize,
    },
    /// Grid only: the force of the fluid on an obstacle (named by its `name`), pressure and
    /// viscous parts, N.
    Force { name: String, body: String },
}

fn default_line_points() -> usize {
    65
}

impl Probe {
    /// The probe's name.
    pub fn name(&self) -> &str {
        match self {
            Probe::Front { name, .. }
            | Probe::Point { name, .. }
            | Probe::Line { name, .. }
            | Probe::Force { name, .. } => name,
        }
    }
}

/// Per-step metrics a scene can ask for; each is a column of `metrics.csv`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Metric {
    KineticEnergy,
    PotentialEnergy,
    DensityErrorAvg,
    DensityErrorMax,
    MaxSpeed,
    PressureIterations,
    DivergenceIterations,
    /// Rotational energy of a micropolar refinement, J (zero for other methods).
    RotationalEnergy,
    /// Kinetic (linear plus rotational) plus potential energy, J.
    TotalEnergy,
    /// Mean |curl v| over the fluid particles, 1/s.
    VorticityMean,
    /// Largest |curl v|, 1/s.
    VorticityMax,
    /// Enstrophy sum_i V |curl v_i|^2 / 2, m^3/s^2.
    Enstrophy,
    /// Wall-clock time of the refinement in the step, s.
    RefinementSeconds,
}

impl Metric {
    /// Every metric, in column order.
    pub const ALL: [Metric; 13] = [
        Metric::KineticEnergy,
        Metric::PotentialEnergy,
        Metric::DensityErrorAvg,
        Metric::DensityErrorMax,
        Metric::MaxSpeed,
        Metric::PressureIterations,
        Metric::DivergenceIterations,
        Metric::RotationalEnergy,
        Metric::TotalEnergy,
        Metric::VorticityMean,
        Metric::VorticityMax,
        Metric::Enstrophy,
        Metric::RefinementSeconds,
    ];
    /// Column name in `metrics.csv`.
    pub fn column(self) -> &'static str {
        match self {
            Metric::KineticEnergy => "kinetic_energy",
            Metric::PotentialEnergy => "potential_energy",
            Metric::DensityErrorAvg => "density_error_avg",
            Metric::DensityErrorMax => "density_error_max",
            Metric::MaxSpeed => "max_speed",
            Metric::PressureIterations => "pressure_iterations",
            Metric::DivergenceIterations => "divergence_iterations",
            Metric::RotationalEnergy => "rotational_energy",
            Metric::TotalEnergy => "total_energy",
            Metric::VorticityMean => "vorticity_mean",
            Metric::VorticityMax => "vorticity_max",
            Metric::Enstrophy => "enstrophy",
            Metric::RefinementSeconds => "refinement_seconds",
        }
    }
}

/// Outputs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Output {
    /// Output folder; `out/<scene name>` when left out. `eddy run --out` overrides it.
    #[serde(default)]
    pub dir: Option<PathBuf>,
    /// Simulated time between frames, s (the first frame is t = 0).
    #[serde(default = "default_interval")]
    pub interval: Real,
    /// Write one VTK file per frame plus a `particles.pvd` series for ParaView.
    #[serde(default = "default_true")]
    pub vtk: bool,
    /// Write the frames into one `frames.h5` as well.
    #[serde(default)]
    pub hdf5: bool,
    /// Columns of `metrics.csv` beyond step, time and dt; every metric when left out, none with [].
    #[serde(default = "default_metrics")]
    pub metrics: Vec<Metric>,
}

fn default_interval() -> Real {
    1.0 / 30.0
}
fn default_metrics() -> Vec<Metric> {
    Metric::ALL.to_vec()
}

impl Default for Output {
    fn default() -> Self {
        Self {
            dir: None,
            interval: default_interval(),
            vtk: true,
            hdf5: false,
            metrics: default_metrics(),
        }
    }
}
