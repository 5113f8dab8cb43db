//! Scene files: the TOML schema, loading with overrides, validation, and the parameters of the
//! parts built from a resolved scene.

pub mod build;
pub mod coupling;
pub mod error;
pub mod grid;
pub mod load;
mod open;
pub mod overrides;
pub mod ranges;
pub mod reference;
pub mod schema;
pub mod turbulence;
pub mod validate;

pub use crate::refine::Refinement;
pub use coupling::Coupling;
pub use error::{Number, SceneError};
pub use grid::{
    Advection, Grid, GridBoundary, GridSide, InitialFlow, ObstacleSurface, Smoke, SmokeSource,
    ViscosityScheme,
};
pub use load::{load, parse_str};
pub use overrides::apply_override;
pub use schema::*;
