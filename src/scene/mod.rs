//! Scene files: the TOML schema, loading with overrides, validation, and the stage plan.

pub mod error;
pub mod grid;
pub mod load;
pub mod overrides;
pub mod plan;
pub mod refinement;
pub mod schema;
pub mod validate;

pub use error::SceneError;
pub use grid::{Advection, Grid, GridBoundary, GridSide, Smoke, SmokeSource, ViscosityScheme};
pub use load::{load, parse_str};
pub use overrides::apply_override;
pub use refinement::Refinement;
pub use schema::*;
