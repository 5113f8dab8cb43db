//! eddy: wall-induced turbulence on MAC grids and SPH particles.
//!
//! The crate is laid out as ARCHITECTURE.md maps it; every module, by layer:
//!
//! - [`pipeline`]: a scene as a [`pipeline::Simulation`] and its stages, the plan printed from
//!   them, and the one driver loop.
//! - [`scene`]: scene files (schema, overrides, validation) and the parameters each part is
//!   built from (`scene::build`).
//! - [`grid`] (MAC grid) and [`sph`] (particles, with step hooks): the solvers, each from its
//!   own parameter struct; [`refine`]: the SPH turbulence refinements, attached as step hooks.
//! - [`vortex`]: the vortex-particle layer, which reads and writes solvers through two traits;
//!   [`abl`]: the artificial-boundary-layer database and lookup.
//! - [`study`]: parameter studies (`eddy sweep`), each point a run of its own.
//! - [`geometry`] (bodies and motion), [`spatial`] (the hashed cell grid), [`stepping`] (step
//!   limits), [`parallel`] (fixed-order sums), [`simd`] (vector kernels dispatched to the
//!   CPU's widest instruction set), [`interval`] (the allowed range of a number): shared by
//!   the parts above.
//! - [`metrics`] (diagnostics and probes), [`io`] (VTK, HDF5, CSV, plots), [`bench`] (the
//!   benchmark tables behind `eddy bench` and `eddy bench-grid`).

pub mod abl;
pub mod bench;
pub mod geometry;
pub mod grid;
pub mod interval;
pub mod io;
pub mod metrics;
pub mod parallel;
pub mod pipeline;
pub mod refine;
pub mod scene;
pub mod simd;
pub mod spatial;
pub mod sph;
pub mod state;
pub mod stepping;
pub mod study;
pub mod vortex;

/// The one floating-point type of eddy (f64 throughout, see ARCHITECTURE.md, "Conventions").
pub type Real = f64;
/// A 3D vector of [`Real`].
pub type Vec3 = nalgebra::Vector3<Real>;
/// A 3D point of [`Real`].
pub type Point3 = nalgebra::Point3<Real>;
/// A 3 x 3 matrix of [`Real`]; velocity gradients have entry [a][b] = d u_a / d x_b.
pub type Mat3 = nalgebra::Matrix3<Real>;
