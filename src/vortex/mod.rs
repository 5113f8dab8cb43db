//! The shared vortex-particle layer (Pfaff et al. 2009, sections 4.2 and 4.3): particles with a
//! Gaussian vector-potential kernel, their dynamics (advection, stretching, dissipation, split,
//! merge), and the synthesis of their velocity onto whichever solver runs the scene.
//!
//! The layer knows nothing of MAC grids or SPH particles (DESIGN.md, "The one seam"): it reads
//! velocity through [`VelocitySource`] and writes through [`VelocitySink`]; `grid` and `sph`
//! implement both.

pub mod dynamics;
pub mod kernel;
pub mod particles;
mod spatial;
pub mod synthesis;

pub use dynamics::{Dynamics, DynamicsSettings, StepReport};
pub use particles::VortexParticles;
pub use synthesis::{synthesize, SynthesisReport};

use crate::{Real, Vec3};
use ndarray::Array3;

/// A 3 x 3 matrix of [`Real`]; velocity gradients have entry [a][b] = d u_a / d x_b.
pub type Mat3 = nalgebra::Matrix3<Real>;

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

/// A velocity increment in a sink's layout.
#[derive(Debug, Clone)]
pub enum SinkField {
    /// Face components, `faces[a]` of shape dims + e_a (the MAC layout).
    Faces(Box<[Array3<Real>; 3]>),
    /// One vector per point.
    Points(Vec<Vec3>),
}

/// Where the layer writes velocity to (synthesis, section 4.3).
pub trait VelocitySink {
    /// The sink's samples.
    fn layout(&self) -> SinkLayout<'_>;
    /// The sink's own vorticity (step 1 of section 4.3): at the cell centres in [i, j, k]
    /// order (k fastest) for [`SinkLayout::Faces`], at the points for [`SinkLayout::Points`].
    fn vorticity(&self) -> Vec<Vec3>;
    /// Adds a velocity field given in the sink's layout.
    fn add_velocity(&mut self, field: &SinkField) -> Result<(), VortexError>;
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
