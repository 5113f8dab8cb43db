//! Scene files: the TOML schema, loading with overrides, validation, and the stage plan.

pub mod schema;

pub use schema::*;
