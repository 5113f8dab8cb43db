//! The MAC-grid solver's parameters: plain data with their defaults. The scene's `[grid]`
//! section deserializes its boundary, advection, viscosity and smoke settings into the types
//! here, and the scene builder (`src/scene/build.rs`) assembles a [`GridParams`] from a
//! resolved scene.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::advect::Advection;
use super::poisson::SolverSettings;
use crate::geometry::{Motion, Shape};
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
    /// Fluctuations on the inflow sides' normal velocity, with the modes drawn from the
    /// scene's seed; none when None.
    pub inflow_turbulence: Option<super::InflowModes>,
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
    /// Smoke and temperature live on a grid this many times finer than the flow's (1 or 2;
    /// the turbulence's `upsample`, Pfaff et al. 2009 section 5.2).
    pub smoke_refinement: usize,
    /// Start of the time-averaged velocity, s; none kept when None.
    pub average_from: Option<Real>,
    /// The first body is a container holding the fluid (a coupled scene's tank): the cells
    /// outside it are solid, those inside fluid.
    pub container: bool,
    /// How the obstacles meet the cells.
    pub obstacle_surface: ObstacleSurface,
    /// Carry the last step's pressure gradient into the momentum before the viscosity and
    /// project only its increment (Goda 1979): the splitting error beside no-slip walls falls
    /// from first to second order in dt. Not with `reflection` nor under a coupled liquid.
    pub incremental_pressure: bool,
}

/// How the pressure and the viscosity see an obstacle's surface.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ObstacleSurface {
    /// Each cell is solid or fluid by its centre: the solvers see a staircase, first order.
    Staircase,
    /// Faces weigh their open fraction in the projection and the no-slip wall sits where the
    /// signed distance crosses zero. The default (not under a coupled liquid): on the DFG 2D-2
    /// cylinder at 20 cells per diameter it raises the peak lift coefficient from 0.66 to 0.86
    /// (the band: 0.99–1.01), and it brings the sphere's boundary-layer database at 32 cells
    /// from 5.4 % to 4.2 % (translation) and from 4.0 % to 1.3 % (rotation) of one at 64 cells.
    #[default]
    Cut,
}

/// Time discretisation of the implicit viscosity.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ViscosityScheme {
    /// First order, L-stable.
    #[default]
    BackwardEuler,
    /// Second order, A-stable.
    CrankNicolson,
}

/// One side of the grid's domain.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
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
    /// Inflow at this velocity, m/s, uniform over the side.
    Inflow([Real; 3]),
    /// Inflow whose velocity varies over the side (a developed channel inflow).
    ProfiledInflow(InflowProfile),
    /// Wraps to the opposite side, which must be periodic too.
    Periodic,
}

/// The six sides of the grid's domain.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
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
            [self.x_min.clone(), self.x_max.clone()],
            [self.y_min.clone(), self.y_max.clone()],
            [self.z_min.clone(), self.z_max.clone()],
        ]
    }
}

/// The shape of a [`InflowProfile`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ProfileShape {
    /// Plane Poiseuille flow between the two sides normal to `across`: `4 s (1 - s)`, s the
    /// position across the domain from 0 to 1 (mean 2/3 of the peak).
    Plane,
    /// Flow in a rectangular duct as the product of the two parabolas across the side
    /// (`16 s (1 - s) t (1 - t)`, mean 4/9 of the peak): the product approximation, not the
    /// series solution of duct Poiseuille flow (which it matches within a few percent of
    /// the peak on a square section).
    Duct,
    /// Factors given in `table` against the coordinate along `across`.
    Table,
}

/// An inflow whose velocity is `velocity` times a shape over the side.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct InflowProfile {
    /// Velocity where the shape is 1 (the centre of a parabola), m/s; normal to the side.
    pub velocity: [Real; 3],
    /// `plane`, `duct` or `table`.
    pub shape: ProfileShape,
    /// The axis along the side the profile varies across (`plane`, `table`): 0, 1 or 2 for x,
    /// y, z.
    #[serde(default)]
    pub across: Option<usize>,
    /// `table`: pairs [coordinate (m), factor], coordinates increasing; linear between them,
    /// constant beyond the ends.
    #[serde(default)]
    pub table: Vec<[Real; 2]>,
}

impl InflowProfile {
    /// The factor at `x` in a domain from `lo` to `hi`, for a side normal to `axis`.
    pub fn factor(&self, x: &Vec3, lo: &Vec3, hi: &Vec3, axis: usize) -> Real {
        let s = |a: usize| ((x[a] - lo[a]) / (hi[a] - lo[a])).clamp(0.0, 1.0);
        let parabola = |a: usize| 4.0 * s(a) * (1.0 - s(a));
        match self.shape {
            ProfileShape::Plane => self.across.map_or(1.0, parabola),
            ProfileShape::Duct => (0..3).filter(|&a| a != axis).map(parabola).product(),
            ProfileShape::Table => {
                let Some(a) = self.across else { return 1.0 };
                table_at(&self.table, x[a])
            }
        }
    }

    /// The mean of the factor over the side, for the net inflow of a closed domain.
    pub fn mean_factor(&self, lo: &Vec3, hi: &Vec3) -> Real {
        match self.shape {
            ProfileShape::Plane => 2.0 / 3.0,
            ProfileShape::Duct => 4.0 / 9.0,
            ProfileShape::Table => {
                let Some(a) = self.across else { return 1.0 };
                // Trapezoids over the table's points inside the span, plus its two ends.
                let mut xs: Vec<Real> = self
                    .table
                    .iter()
                    .map(|p| p[0])
                    .filter(|&x| x > lo[a] && x < hi[a])
                    .collect();
                xs.insert(0, lo[a]);
                xs.push(hi[a]);
                let integral: Real = xs
                    .windows(2)
                    .map(|w| {
                        0.5 * (w[1] - w[0])
                            * (table_at(&self.table, w[0]) + table_at(&self.table, w[1]))
                    })
                    .sum();
                integral / (hi[a] - lo[a])
            }
        }
    }
}

/// Linear interpolation in `table` ([coordinate, value] pairs, coordinates increasing),
/// constant beyond its ends; 1 for an empty table.
fn table_at(table: &[[Real; 2]], x: Real) -> Real {
    let (Some(first), Some(last)) = (table.first(), table.last()) else {
        return 1.0;
    };
    if x <= first[0] {
        return first[1];
    }
    if x >= last[0] {
        return last[1];
    }
    let k = table.partition_point(|p| p[0] <= x);
    let (a, b) = (table[k - 1], table[k]);
    a[1] + (b[1] - a[1]) * (x - a[0]) / (b[0] - a[0])
}

impl GridSide {
    /// The velocity the side prescribes at the point `x` on it, in a domain from `lo` to `hi`
    /// (the side normal to `axis`); None for slip, open and periodic sides (no tangential
    /// value).
    pub fn velocity_at(&self, x: &Vec3, lo: &Vec3, hi: &Vec3, axis: usize) -> Option<Vec3> {
        match self {
            GridSide::Wall => Some(Vec3::zeros()),
            GridSide::MovingWall(v) | GridSide::Inflow(v) => Some(Vec3::from(*v)),
            GridSide::ProfiledInflow(p) => Some(Vec3::from(p.velocity) * p.factor(x, lo, hi, axis)),
            GridSide::Slip | GridSide::Open | GridSide::Periodic => None,
        }
    }

    /// The velocity of an inflow where it is largest, m/s; None for other sides.
    pub fn inflow_peak(&self) -> Option<[Real; 3]> {
        match self {
            GridSide::Inflow(v) => Some(*v),
            GridSide::ProfiledInflow(p) => Some(p.velocity),
            _ => None,
        }
    }
}

/// Smoke: passive density and temperature carried by the flow, lifted by buoyancy.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
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

/// A region that sets smoke every step. A still source that covers no cell centre emits
/// nothing and is run with a warning naming it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
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
    /// Its motion, as an obstacle's (give a source on a moving body the body's motion); at rest
    /// when left out.
    #[serde(default, skip_serializing_if = "Motion::is_still")]
    pub motion: Motion,
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
