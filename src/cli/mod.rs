//! The `eddy` command line's own parts: clap options and anyhow errors live here, never in the
//! library.

pub mod abl;
pub mod bench;
pub mod slice;
pub mod spectrum;
pub mod sweep;
