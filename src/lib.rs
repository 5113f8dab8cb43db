//! eddy: wall-induced turbulence on MAC grids and SPH particles.
//!
//! The crate is laid out as `../shared/DESIGN.md` describes: `scene` reads and validates scene
//! files and compiles the stage plan, `geometry` holds obstacles and their motion, `sph` the particle
//! solvers, `metrics` the per-step diagnostics and probes, `io` the writers, and `run` drives a
//! scene from its first step to its last frame.

pub mod abl;
pub mod bench;
pub mod geometry;
pub mod grid;
pub mod io;
pub mod metrics;
pub mod parallel;
pub mod pipeline;
pub mod refine;
pub mod scene;
pub mod spatial;
pub mod sph;
pub mod stepping;
pub mod vortex;

/// The one floating-point type of eddy (f64 throughout, see DESIGN.md "Conventions").
pub type Real = f64;
/// A 3D vector of [`Real`].
pub type Vec3 = nalgebra::Vector3<Real>;
/// A 3D point of [`Real`].
pub type Point3 = nalgebra::Point3<Real>;
/// A 3 x 3 matrix of [`Real`]; velocity gradients have entry [a][b] = d u_a / d x_b.
pub type Mat3 = nalgebra::Matrix3<Real>;
