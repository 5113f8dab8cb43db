//! The offline artificial-boundary-layer precomputation (Pfaff et al. 2009, sections 3.2 and
//! 5.1): for one obstacle, every sampled flow direction and rotation axis is an independent MAC
//! grid run with raised viscosity, averaged, and evaluated at the boundary points; the result
//! is one HDF5 database that `eddy::abl::AblDatabase` opens.

pub mod bench;
pub mod parts;
#[cfg(feature = "mpi")]
pub mod ranks;
pub mod run;
pub mod solve;
pub mod spec;

pub use run::{merge, precompute, precompute_with, RunOptions, Summary};
pub use spec::ObstacleSpec;
