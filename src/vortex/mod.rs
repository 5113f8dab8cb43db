//! The shared vortex-particle layer (Pfaff et al. 2009, sections 4.2 and 4.3): particles with a
//! Gaussian vector-potential kernel, their dynamics (advection, stretching, dissipation, split,
//! merge), and the synthesis of their velocity onto whichever solver runs the scene.
//!
//! The layer knows nothing of MAC grids or SPH particles (ARCHITECTURE.md, "The seams"): it reads
//! velocity through [`VelocitySource`] and writes through [`VelocitySink`]; `grid` and `sph`
//! implement both.

pub mod dynamics;
pub mod kernel;
pub mod particles;
pub mod synthesis;

pub use dynamics::{Dynamics, DynamicsSettings, StepReport};
pub use particles::VortexParticles;
pub use synthesis::{synthesize, synthesize_refined, SynthesisReport};

use crate::{Real, Vec3};
use ndarray::ArrayViewMut3;

pub use crate::Mat3;

/// Where the layer reads velocity from (advection and stretching, section 4.2).
pub trait VelocitySource {
    /// Velocity at a world position, m/s.
    fn velocity(&self, x: &Vec3) -> Vec3;
    /// Velocity gradient at a world position, entry [a][b] = d u_a / d x_b, 1/s.
    fn velocity_gradient(&self, x: &Vec3) -> Mat3;
}

/// A regular lattice of cubic cells: all the layer needs to know of a grid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lattice {
    /// Cells along x, y, z.
    pub dims: [usize; 3],
    /// Cell size, m.
    pub dx: Real,
    /// Lower corner, m.
    pub origin: Vec3,
    /// Axes that wrap.
    pub periodic: [bool; 3],
}

impl Lattice {
    /// Number of cells.
    pub fn cell_count(&self) -> usize {
        self.dims.iter().product()
    }

    /// The same box with every cell split into `factor`^3 cells.
    pub fn refined(&self, factor: usize) -> Self {
        Self {
            dims: self.dims.map(|n| n * factor),
            dx: self.dx / factor as Real,
            ..*self
        }
    }
}

/// Where a sink's samples are.
#[derive(Debug, Clone, Copy)]
pub enum SinkLayout<'a> {
    /// The faces of a MAC lattice; its vorticity is given at the cell centres.
    Faces(Lattice),
    /// A set of points; velocity and vorticity are given at the points.
    Points(&'a [Vec3]),
}

/// A sink's own vorticity (step 1 of section 4.3).
pub enum SinkVorticity<'a> {
    /// At the cell centres of a [`SinkLayout::Faces`] lattice, by rows along z: `f([i, j, k],
    /// out)` writes the vorticity of cells `[i, j, k]` to `[i, j, k + out.len() - 1]` into
    /// `out`. Finite differences are local, so the layer asks only for the rows under some
    /// kernel's cut-off, and a grid computes a row from contiguous runs of face values.
    Cells(CellRows<'a>),
    /// At each point of a [`SinkLayout::Points`] sink (a point set's curl needs its
    /// neighbourhoods, so it comes in one sweep).
    Points(Vec<Vec3>),
}

/// See [`SinkVorticity::Cells`].
pub type CellRows<'a> = Box<dyn Fn([usize; 3], &mut [Vec3]) + Sync + 'a>;

/// A sink's velocity samples, lent to the layer for an in-place addition.
pub enum SinkSamples<'a> {
    /// Face components, `faces[a]` of shape dims + e_a (the MAC layout).
    Faces([ArrayViewMut3<'a, Real>; 3]),
    /// One vector per point.
    Points(&'a mut [Vec3]),
}

/// What the layer does with lent samples.
pub type AddVelocity<'f> = dyn FnMut(SinkSamples<'_>) -> Result<(), VortexError> + 'f;

/// Where the layer writes velocity to (synthesis, section 4.3).
pub trait VelocitySink {
    /// The sink's samples.
    fn layout(&self) -> SinkLayout<'_>;
    /// The sink's own vorticity: [`SinkVorticity::Cells`] for [`SinkLayout::Faces`],
    /// [`SinkVorticity::Points`] for [`SinkLayout::Points`]. Synthesis reads it only under the
    /// particles' cut-offs, so a point sink is told those points in `only` and may leave the
    /// others zero (a cell sink reads its cells on demand and ignores it).
    fn vorticity(&self, only: Option<&[bool]>) -> SinkVorticity<'_>;
    /// Lends the velocity samples to `add`, which adds to them in place, then restores what the
    /// sink derives from them (a grid's periodic copies). Writing in place spares a dense
    /// increment field the size of the grid.
    fn add_velocity(&mut self, add: &mut AddVelocity<'_>) -> Result<(), VortexError>;
}

/// Errors of the vortex layer.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum VortexError {
    #[error("vortex particle: {0}")]
    InvalidParticle(String),
    #[error("vortex settings: {0}")]
    InvalidSettings(String),
    #[error("velocity sink: {0}")]
    Layout(String),
}
