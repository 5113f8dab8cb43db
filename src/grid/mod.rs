//! The MAC grid's linear solvers: the pressure Poisson system (MGPCG) and implicit diffusion.

mod components;
pub mod diffusion;
mod layout;
mod multigrid;
mod pcg;
pub mod poisson;
mod stencil;
mod transfer;

pub use diffusion::{solve_diffusion, DiffusionBoundary, DiffusionSide};
pub use poisson::{
    Boundary, CellKind, PoissonSystem, Side, SolveError, SolveStats, SolverSettings,
};
