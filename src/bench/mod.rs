//! The benchmark tables behind `eddy bench` and `eddy bench-grid`: SPH step times on the
//! dam break ([`sph`]) and each phase of it against its data-movement floor ([`floors`]), the
//! refinements' overheads against plain DFSPH ([`refine`]), the MAC grid's plume step times
//! and Taylor–Green error against run time ([`grid`]), what the exchange of a coupled
//! grid + SPH scene costs ([`coupling`]), and the running statistics' share of a step
//! ([`statistics`]).

pub mod abl;
pub mod abl_particles;
pub mod coupling;
pub mod dfg;
pub mod floors;
pub mod grid;
pub mod refine;
pub mod sph;
pub mod statistics;

pub use sph::{
    advance, cube_edge, dam_break_scene, dam_break_scene_with, measure, measure_with, run,
    BenchOptions, BenchResult,
};
