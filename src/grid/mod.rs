//! The MAC-grid fluid: staggered velocities on cubic cells, semi-Lagrangian and MacCormack
//! advection, implicit viscosity, MGPCG pressure projection with walls, obstacles, inflow,
//! open and periodic sides, smoke with buoyancy, vorticity confinement and running averages
//! (Pfaff et al. 2009, sections 1 and 5; the precomputation runs it with raised viscosity).

pub mod advect;
pub mod average;
pub mod boundary;
mod components;
pub mod cut;
pub mod diffusion;
pub mod fine;
pub mod forces;
pub mod inflow_turbulence;
pub mod interp;
mod layout;
pub mod liquid;
pub mod mac;
mod multigrid;
pub mod params;
mod pcg;
mod persist;
pub mod poisson;
pub mod project;
pub mod smoke;
pub mod solver;
mod stencil;
mod transfer;
pub mod viscosity;
pub mod vortex_coupling;
pub mod walls;

pub use advect::Advection;
pub use average::RunningAverage;
pub use boundary::Boundaries;
pub use diffusion::{solve_diffusion, DiffusionBoundary, DiffusionSide, DiffusionSystem};
pub use inflow_turbulence::{InflowModes, InflowTurbulence};
pub use interp::Stagger;
pub use liquid::Liquid;
pub use mac::MacGrid;
pub use params::{
    GridBoundary, GridParams, GridSide, InflowProfile, ObstacleSurface, ProfileShape, Smoke,
    SmokeSource, ViscosityScheme,
};
pub use poisson::{
    Boundary, CellKind, PoissonSystem, Side, SolveError, SolveStats, SolverSettings,
};
pub use solver::{GridError, GridSolver, GridStepStats};
