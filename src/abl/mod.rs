//! Artificial boundary layers (Pfaff et al. 2009, sections 3.2 and 5.1): the direction-sampled
//! database of precomputed confined vorticity `omega_pre = beta (U(x + l n) x n)` (Figure 5) and
//! its run-time lookup by bilinear spherical interpolation, scaled by speed, translation plus
//! rotation.
//!
//! The database is written by the `eddy-precompute` binary (the `precompute/` crate); this module
//! owns the file format so that the library can open, validate and query it without that crate.

mod database;
mod error;
mod fingerprint;
mod format;
pub mod params;
mod quad;
mod sampling;
pub mod seeding;
pub mod wall;

pub use database::AblDatabase;
pub use error::AblError;
pub use fingerprint::{geometry_fingerprint, hash_hex};
pub use format::{AblData, AblHeader, DirectionTable, MotionKind, ABL_FORMAT, ABL_FORMAT_VERSION};
pub use params::{AblSettings, Seeding, TurbulenceParams};
pub use sampling::Sampling;
pub use wall::WallLayer;
