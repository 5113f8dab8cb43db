//! The SPH solver's parameters: plain data with the papers' defaults. The scene's `[fluid]`,
//! `[pressure]` and `[viscosity]` sections deserialize into the section types here, and
//! the scene builder (`src/scene/build.rs`) assembles a [`SphParams`] from a resolved scene.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::stepping::StepLimits;
use crate::{Real, Vec3};

/// Everything an [`super::SphSolver`] is built from, besides its bodies.
#[derive(Debug, Clone, PartialEq)]
pub struct SphParams {
    /// Particle spacing (twice the particle radius), m; the kernel support is twice this.
    pub spacing: Real,
    /// Rest density, kg/m^3.
    pub rest_density: Real,
    /// Boxes filled with particles on a cubic lattice at `spacing`.
    pub blocks: Vec<FluidBlock>,
    /// Gravitational acceleration, m/s^2.
    pub gravity: Vec3,
    pub pressure: Pressure,
    pub viscosity: Viscosity,
    /// Per body (the container first): the kinematic viscosity against its samples, m^2/s
    /// (the body's `wall_viscosity`, else `viscosity.boundary`).
    pub wall_viscosity: Vec<Real>,
    pub limits: StepLimits,
    /// Lower and upper corner of the domain, m: a particle that leaves it through an open side
    /// is removed and counted, one that leaves through a wall stops the run (`super::lost`).
    pub domain: (Vec3, Vec3),
    /// The share of the fluid that may leave through open sides before the run stops.
    pub lost_fraction: Real,
    /// Seconds over which the inflows' velocity and the blocks' common velocity rise from zero
    /// (`super::ramp`); 0 starts impulsively.
    pub ramp: Real,
    /// The first body is a container (fluid is kept inside it, not outside).
    pub container: bool,
    /// Inflow emitters on the domain's sides.
    pub inflows: Vec<Inflow>,
    /// Outflow sides of the domain: particles crossing them are removed.
    pub outflows: Vec<Outflow>,
}

/// A side of the domain box.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum DomainSide {
    XMin,
    XMax,
    YMin,
    YMax,
    ZMin,
    ZMax,
}

impl DomainSide {
    /// The side normal to `axis`, the upper one when `max`.
    pub fn of(axis: usize, max: bool) -> Self {
        match (axis, max) {
            (0, false) => Self::XMin,
            (0, true) => Self::XMax,
            (1, false) => Self::YMin,
            (1, true) => Self::YMax,
            (_, false) => Self::ZMin,
            (_, true) => Self::ZMax,
        }
    }

    /// Its index in [`Self::ALL`].
    pub fn index(self) -> usize {
        2 * self.axis() + usize::from(self.is_max())
    }

    /// Every side, in the order of [`Self::index`].
    pub const ALL: [Self; 6] = [
        Self::XMin,
        Self::XMax,
        Self::YMin,
        Self::YMax,
        Self::ZMin,
        Self::ZMax,
    ];

    /// The axis the side is normal to.
    pub fn axis(self) -> usize {
        match self {
            Self::XMin | Self::XMax => 0,
            Self::YMin | Self::YMax => 1,
            Self::ZMin | Self::ZMax => 2,
        }
    }

    /// Whether it is the upper side of its axis.
    pub fn is_max(self) -> bool {
        matches!(self, Self::XMax | Self::YMax | Self::ZMax)
    }

    /// The unit normal pointing into the domain.
    pub fn inward(self) -> Vec3 {
        let mut n = Vec3::zeros();
        n[self.axis()] = if self.is_max() { -1.0 } else { 1.0 };
        n
    }

    /// The two axes along the side, in order.
    pub fn tangents(self) -> [usize; 2] {
        match self.axis() {
            0 => [1, 2],
            1 => [0, 2],
            _ => [0, 1],
        }
    }

    /// Its name in scene files.
    pub fn name(self) -> &'static str {
        match self {
            Self::XMin => "x_min",
            Self::XMax => "x_max",
            Self::YMin => "y_min",
            Self::YMax => "y_max",
            Self::ZMin => "z_min",
            Self::ZMax => "z_max",
        }
    }
}

/// An inflow emitter: a rectangle on a side of the domain through which fluid enters at a
/// prescribed velocity (see `super::open`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Inflow {
    /// The domain side it sits on.
    pub side: DomainSide,
    /// Lower corner of the rectangle in the side's two other coordinates, in axis order, m.
    pub min: [Real; 2],
    /// Upper corner, m.
    pub max: [Real; 2],
    /// Velocity of the entering fluid, m/s (the peak of a profile); its component into the
    /// domain must be positive.
    pub velocity: [Real; 3],
    /// How the velocity varies over the rectangle: `uniform` (default), `plane` or `duct`.
    #[serde(default)]
    pub shape: InflowShape,
    /// `plane`: the axis (0, 1, 2 for x, y, z) along the side the parabola runs across.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub across: Option<usize>,
}

/// How an inflow's velocity varies over its rectangle (s, t: the position across it along
/// its two axes, from 0 to 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum InflowShape {
    /// The same velocity everywhere.
    #[default]
    Uniform,
    /// Plane Poiseuille flow between the rectangle's edges normal to `across`: 4 s (1 - s),
    /// mean 2/3 of the peak (the inflow of Schaefer & Turek's 1996 cylinder benchmark).
    Plane,
    /// The product of both parabolas, 16 s (1 - s) t (1 - t), mean 4/9 of the peak.
    Duct,
}

impl Inflow {
    /// The velocity's factor at `x` over the rectangle.
    pub fn factor(&self, x: &Vec3) -> Real {
        let tangents = self.side.tangents();
        let parabola = |k: usize| {
            let a = tangents[k];
            let s = ((x[a] - self.min[k]) / (self.max[k] - self.min[k])).clamp(0.0, 1.0);
            4.0 * s * (1.0 - s)
        };
        match self.shape {
            InflowShape::Uniform => 1.0,
            InflowShape::Plane => tangents
                .iter()
                .position(|&a| Some(a) == self.across)
                .map_or(1.0, parabola),
            InflowShape::Duct => parabola(0) * parabola(1),
        }
    }
}

/// An outflow side: particles that cross it leave the simulation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Outflow {
    /// The domain side.
    pub side: DomainSide,
}

/// A box of fluid.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
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

/// Which pressure solver runs.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum PressureSolverKind {
    /// Divergence-free SPH (Bender & Koschier 2015/2017).
    #[default]
    Dfsph,
    /// Implicit incompressible SPH (Ihmsen et al. 2014).
    Iisph,
}

/// Pressure solver settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
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
    /// DFSPH: predict the density after the step to second order in dt (IISPH always does),
    /// so the measured compression stays at the tolerance; costs a Hessian pass per iteration.
    #[serde(default)]
    pub second_order: bool,
    /// DFSPH: let the pressure go negative, so the fluid can pull as well as push, and solve
    /// both systems by conjugate gradients. For fluids that fill their walls
    /// (channels, wakes): the clamped default lets a wake cavitate. There is no free-surface
    /// rule, so a free surface would pull itself together; outflows are held at `ambient`.
    #[serde(default)]
    pub signed: bool,
    /// The signed solve's pressure at the outflows, Pa. Set it above the flow's deepest
    /// suction (some rho U^2 for a body in a stream of speed U): where the pressure is
    /// negative SPH particles clump (the tensile instability).
    #[serde(default)]
    pub ambient: Real,
    /// Least iterations per solve.
    #[serde(default = "default_min_iterations")]
    pub min_iterations: u32,
    /// Least iterations of the DFSPH divergence solve, when it should differ from
    /// `min_iterations` (its default). Bender & Koschier's divergence solve, and
    /// SPlisHSPlasH's, run at least one; their density solve at least two.
    #[serde(default)]
    pub divergence_min_iterations: Option<u32>,
    /// Most iterations per solve; a solve that hits it is reported in metrics.csv.
    #[serde(default = "default_max_iterations")]
    pub max_iterations: u32,
}

impl Pressure {
    /// The divergence solve's least iterations: its own setting, else `min_iterations`.
    pub fn divergence_min_iterations(&self) -> u32 {
        self.divergence_min_iterations
            .unwrap_or(self.min_iterations)
    }
}

impl Default for Pressure {
    fn default() -> Self {
        Self {
            solver: PressureSolverKind::default(),
            density_tolerance: default_density_tolerance(),
            divergence_tolerance: default_divergence_tolerance(),
            divergence_solver: true,
            second_order: false,
            signed: false,
            ambient: 0.0,
            min_iterations: default_min_iterations(),
            divergence_min_iterations: None,
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
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Viscosity {
    /// Kinematic viscosity of the Laplacian form (Liu et al. 2021 Eq. 4), m^2/s.
    #[serde(default)]
    pub kinematic: Real,
    /// Kinematic viscosity against boundary particles, m^2/s: the walls' no-slip strength,
    /// for every body that does not set its own `wall_viscosity`. Equal to `kinematic` is a
    /// no-slip wall, 0 free slip.
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
