//! The run-time parameters of the artificial boundary layer, as a scene's `[turbulence]` table
//! writes them, with the defaults of Pfaff et al. 2009 (section 4, Table 1). The scene checks
//! their ranges; lengths the paper gives in cells of the simulation grid are in cells here.
//!
//! ```toml
//! [turbulence]
//! c_p = 2.0            # Eq. 8 seeding constant, 1/s (paper: about 1-4)
//! u0 = 1.0             # |U_0| of Eq. 8, m/s (default: the inflow speed, else the obstacle's)
//! gain = 1.0           # scales the database's omega_pre (Table 1's beta)
//! r_max = 6.0          # largest seeded particle radius, cells
//! dissipation_radius = 2.0  # cells; default 2 on a grid, 1 spacing on SPH particles
//! seeding = "abl"      # or "random": the baseline of Figure 8, middle
//! ```

use std::path::PathBuf;

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::Real;

/// Where vortex particles are seeded.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Seeding {
    /// From the artificial boundary layer by Eq. 8 (Figure 9, lines 11–20).
    #[default]
    Abl,
    /// The same particles (count, radius, strength) at uniformly random places along the
    /// walls with random axes: the baseline of Figure 8 (middle).
    Random,
}

/// The `[turbulence]` table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TurbulenceParams {
    /// c_p of Eq. 8, 1/s: `p_T = 2 c_p dt (l_m |omega_ABL| / |U_0|)^2` is a probability per
    /// sample and step while `dt` carries seconds, so c_p carries 1/s (docs/src/paper-notes.md, "Eq. 8"). 0 seeds
    /// nothing; the paper uses about 1 to 4.
    #[serde(default = "d_c_p")]
    pub c_p: Real,
    /// |U_0| of Eq. 8, m/s. Default: the fastest inflow side's speed, else the fastest
    /// obstacle's; a scene with neither must set it.
    #[serde(default)]
    pub u0: Option<Real>,
    /// Factor on the database's omega_pre (Table 1's beta, applied at run time). The stored
    /// omega_pre = U(x + l n) x n is the velocity jump across the boundary layer (Figure 5), a
    /// circulation per unit of wall area; the wall-attached layer holds it as the vorticity
    /// `gain omega_pre / thickness`, the thickness being one cell on a grid and
    /// [`LAYER_SPACINGS`] spacings on particles. So Eq. 8's `l_m |omega_ABL| / |U_0|` and the
    /// seeds' strengths are the same at any resolution: the paper's grid units, where a cell is
    /// the unit of length. Table 1 uses 0.4 to 6.2.
    #[serde(default = "d_one")]
    pub gain: Real,
    /// Largest radius `sqrt(6) sigma` of a seeded particle, in cells (section 4.3: 6).
    #[serde(default = "d_r_max")]
    pub r_max: Real,
    /// Particles with a smaller radius are dissipated, in cells or spacings. Default: 2 cells
    /// on a grid (section 4.2), 1 spacing on SPH particles.
    #[serde(default)]
    pub dissipation_radius: Option<Real>,
    /// Particles with a radius at most this (cells) are in the inertial subrange and split;
    /// larger ones merge (section 4.2, energy transfer). In SPH scenes `r_max`,
    /// `dissipation_radius` and this count particle spacings instead of cells.
    #[serde(default = "d_split")]
    pub split_radius: Real,
    /// Children per split, n (section 4.2: 2).
    #[serde(default = "d_children")]
    pub children: usize,
    /// C of the cascade time scale `dt = C (kappa_a^(-2/3) - kappa_b^(-2/3))`, s / m^(2/3).
    #[serde(default = "d_one")]
    pub cascade_time: Real,
    /// `abl` or `random`.
    #[serde(default)]
    pub seeding: Seeding,
    /// Synthesis lattice per grid cell per axis, 1 or 2 (Table 1, section 5.2: the kernels
    /// are evaluated on a grid this much finer and averaged over each face). Grid scenes only;
    /// in a scene with smoke, the smoke and temperature live on a grid twice as fine too
    /// (section 5.2).
    #[serde(default = "d_upsample")]
    pub upsample: usize,
}

fn d_c_p() -> Real {
    2.0
}
fn d_one() -> Real {
    1.0
}
fn d_r_max() -> Real {
    6.0
}
fn d_split() -> Real {
    3.0
}
fn d_children() -> usize {
    2
}
fn d_upsample() -> usize {
    1
}

/// Thickness of the wall-attached layer on SPH particles, in spacings: the particles within
/// the kernel support of a wall (the particles that feel it).
pub const LAYER_SPACINGS: Real = 2.0;

/// Default dissipation radius on a grid, cells (section 4.2: "a threshold of 2 dx").
pub const GRID_DISSIPATION: Real = 2.0;

/// Default dissipation radius on SPH particles, spacings. The paper's river (Figure 10) ran its
/// vortex particles on a lattice twice as fine as the flow (Table 1, ABL upscaling 2), so its
/// 2-cell threshold is one flow cell; on particles the kernels are sampled exactly at every
/// particle, with no face average to blur them. At 2 spacings the seeds near the river's walls
/// were born at the threshold (71 % within 1/8 of it) and their first split's children were
/// dissipated at once: 5 particles alive against 171 at 1 spacing (docs/src/abl-sph.md).
pub const PARTICLE_DISSIPATION: Real = 1.0;

impl TurbulenceParams {
    /// The dissipation radius in cells (a grid) or spacings (`on_particles`).
    pub fn dissipation(&self, on_particles: bool) -> Real {
        self.dissipation_radius.unwrap_or(if on_particles {
            PARTICLE_DISSIPATION
        } else {
            GRID_DISSIPATION
        })
    }
}

impl Default for TurbulenceParams {
    fn default() -> Self {
        toml::from_str("").expect("every turbulence key has a default")
    }
}

/// Everything the run-time boundary layer needs from a scene, resolved.
#[derive(Debug, Clone, PartialEq)]
pub struct AblSettings {
    pub params: TurbulenceParams,
    /// |U_0|, m/s, resolved from the scene when `params.u0` is left out.
    pub u0: Real,
    /// The scene's seed.
    pub seed: u64,
    /// Each obstacle with a database: its index among the scene's bodies (container first) and
    /// the database's absolute path.
    pub databases: Vec<(usize, PathBuf)>,
}
