//! The MAC-grid solver's parameters: plain data with their defaults. The scene's `[grid]`
//! section deserializes its boundary, advection, viscosity and smoke settings into the types
//! here, and the scene builder (`src/scene/build.rs`) assembles a [`GridParams`] from a
//! resolved scene.

use serde::{Deserialize, Serialize};

use super::poisson::SolverSettings;
use crate::geometry::Shape;
use crate::stepping::StepLimits;
use crate::{Real, Vec3};

/// Most pressure iterations per step unless a scene says otherwise; a solve that hits it stops
/// the run.
pub const PRESSURE_MAX_ITERATIONS: usize = 500;

/// Everything a [`super::GridSolver`] is built from, besides its obstacles.
#[derive(Debug, Clone, PartialEq)]
pub struct GridParams {
    /// Cells along x, y and z.
    pub resolution: [usize; 3],
    /// Cell size, m (cubic cells).
    pub dx: Real,
    /// Lower corner of the grid, m.
    pub origin: Vec3,
    /// Uniform velocity at t = 0, m/s.
    pub initial_velocity: Vec3,
    /// What lies beyond each side, `[axis][0 = min, 1 = max]`.
    pub sides: [[GridSide; 2]; 3],
    pub advection: Advection,
    /// Advection–reflection (Zehnder et al. 2018): two half-step projections per step.
    pub reflection: bool,
    pub viscosity_scheme: ViscosityScheme,
    /// Kinematic viscosity, m^2/s; 0 skips the viscosity solve.
    pub viscosity: Real,
    /// Fluid density, kg/m^3: scales pressures and forces only.
    pub density: Real,
    /// Vorticity confinement strength epsilon (Fedkiw et al. 2001); 0 is off.
    pub confinement: Real,
    /// The scene's gravity: its direction is "up" for buoyancy.
    pub gravity: Vec3,
    /// Apply `gravity` as a body force too.
    pub gravity_force: bool,
    pub limits: StepLimits,
    /// Tolerance and iteration cap of the pressure (and viscosity) solves.
    pub pressure: SolverSettings,
    pub smoke: Option<Smoke>,
    /// Start of the time-averaged velocity, s; none kept when None.
    pub average_from: Option<Real>,
}

/// Advection scheme of velocity and scalars.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Advection {
    /// Semi-Lagrangian, trilinear, second-order (midpoint) backtrace.
    SemiLagrangian,
    /// MacCormack (Selle et al. 2008), clamped to the backtrace stencil's range.
    #[default]
    Maccormack,
}

/// Time discretisation of the implicit viscosity.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ViscosityScheme {
    /// First order, L-stable.
    #[default]
    BackwardEuler,
    /// Second order, A-stable.
    CrankNicolson,
}

/// One side of the grid's domain.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum GridSide {
    /// A static no-slip wall.
    #[default]
    Wall,
    /// A wall moving in its own plane with this velocity, m/s (a cavity lid).
    MovingWall([Real; 3]),
    /// A free-slip wall.
    Slip,
    /// Open outflow: zero pressure beyond the side.
    Open,
    /// Inflow at this velocity, m/s.
    Inflow([Real; 3]),
    /// Wraps to the opposite side, which must be periodic too.
    Periodic,
}

/// The six sides of the grid's domain.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GridBoundary {
    #[serde(default)]
    pub x_min: GridSide,
    #[serde(default)]
    pub x_max: GridSide,
    #[serde(default)]
    pub y_min: GridSide,
    #[serde(default)]
    pub y_max: GridSide,
    #[serde(default)]
    pub z_min: GridSide,
    #[serde(default)]
    pub z_max: GridSide,
}

impl GridBoundary {
    /// The sides as `[axis][0 = min, 1 = max]`.
    pub fn sides(&self) -> [[GridSide; 2]; 3] {
        [
            [self.x_min, self.x_max],
            [self.y_min, self.y_max],
            [self.z_min, self.z_max],
        ]
    }
}

/// Smoke: passive density and temperature carried by the flow, lifted by buoyancy.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Smoke {
    /// Regions that set smoke density and temperature every step.
    pub sources: Vec<SmokeSource>,
    /// Buoyancy per unit smoke density, m/s^2, against gravity's direction (Fedkiw et al. 2001
    /// use it with a minus sign on density: here positive density rises).
    #[serde(default = "default_buoyancy")]
    pub buoyancy: Real,
    /// Buoyancy per unit temperature above ambient, m/s^2.
    #[serde(default)]
    pub heat_buoyancy: Real,
}

fn default_buoyancy() -> Real {
    1.0
}

/// A region that sets smoke every step.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SmokeSource {
    /// An analytic shape (no meshes), in the source's frame.
    pub shape: Shape,
    /// Position of the shape's origin, m.
    #[serde(default)]
    pub position: [Real; 3],
    /// Orientation as a rotation vector, radians.
    #[serde(default)]
    pub rotation: [Real; 3],
    /// Smoke density set inside.
    #[serde(default = "default_source_density")]
    pub density: Real,
    /// Temperature above ambient set inside.
    #[serde(default)]
    pub temperature: Real,
    /// Velocity set on the faces inside, m/s; left alone when not given.
    #[serde(default)]
    pub velocity: Option<[Real; 3]>,
}

fn default_source_density() -> Real {
    1.0
}

impl Smoke {
    /// Whether a temperature field is needed: heat buoyancy and a source that heats.
    pub fn has_temperature(&self) -> bool {
        self.heat_buoyancy != 0.0 && self.sources.iter().any(|src| src.temperature != 0.0)
    }
}
