//! Smoothed particle hydrodynamics: kernel, neighbour search, pressure solvers (DFSPH, IISPH),
//! Akinci boundary particles, viscosity.

pub mod boundary;
pub mod cg;
pub mod dfsph;
pub mod energy_bound;
pub mod fluid;
pub mod forces;
pub mod hooks;
pub mod iisph;
pub mod kernel;
pub mod lost;
pub mod neighborhood;
pub mod neighbors;
pub mod open;
pub mod operators;
pub mod pair_cache;
pub mod params;
pub mod ramp;
pub mod solver;
pub mod vortex_coupling;
pub mod walls;

pub use hooks::{StepContext, StepHook};
pub use kernel::CubicSpline;
pub use neighborhood::Neighborhood;
pub use neighbors::{CellGrid, NeighborLists};
pub use params::{
    DomainSide, FluidBlock, Inflow, InflowShape, Outflow, Pressure, PressureSolverKind, SphParams,
    Viscosity,
};
pub use solver::{Instability, SphSolver, StepStats};
