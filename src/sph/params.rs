//! The SPH solver's parameters: plain data with the papers' defaults. The scene's `[fluid]`,
//! `[pressure]` and `[viscosity]` sections deserialize into the section types here, and
//! the scene builder (`src/scene/build.rs`) assembles a [`SphParams`] from a resolved scene.

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
    pub limits: StepLimits,
    /// Lower and upper corner of the domain, m: a particle that leaves it is an instability.
    pub domain: (Vec3, Vec3),
    /// The first body is a container (fluid is kept inside it, not outside).
    pub container: bool,
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
