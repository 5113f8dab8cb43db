//! Writers: VTK particle and grid frames for ParaView, HDF5 particle and grid frames for h5py,
//! CSV series.
//!
//! Every writer is built so that a run killed at any moment leaves readable output: single files
//! are replaced atomically ([`write_atomic`]), the ParaView series is rewritten after each frame
//! ([`PvdSeries`]), HDF5 frames appear under their final name only when complete
//! ([`Hdf5Frames`], [`Hdf5GridFrames`]), and CSV rows reach the OS one whole row at a time ([`CsvSeries`]).

mod atomic;
mod checkpoint;
mod csv;
mod error;
mod frame;
mod grid_frame;
mod hdf5_frames;
mod hdf5_grid;
mod hdf5_read;
pub mod plot;
mod pvd;
mod shard;
pub mod slice;
pub mod spectrum_plot;
mod vti;
mod vtk;
mod vtk_read;
mod vtk_xml;
mod xdmf;
mod zlib;

pub use atomic::write_atomic;
pub use checkpoint::{
    read_checkpoint, write_checkpoint, StoredCheckpoint, CHECKPOINT_FORMAT, CHECKPOINT_VERSION,
};
pub use csv::{kept_rows, CsvSeries, KeptRows};
pub use error::IoError;
pub use frame::{Field, FieldData, ParticleFrame};
pub use grid_frame::{GridField, GridFieldData, GridFrame};
pub use hdf5_frames::{write_links, AttrValue, Hdf5Frames};
pub use hdf5_grid::{
    read_solid, read_velocity, write_grid_file, Hdf5GridFrames, StoredVelocity, GRID_FORMAT,
    GRID_FORMAT_VERSION,
};
pub use hdf5_read::FrameChoice;
pub use pvd::PvdSeries;
pub use shard::parse_shard;
pub use vti::write_grid_vtk;
pub use vtk::write_particles_vtk;
pub use vtk_xml::{Precision, VtkOptions};
pub use xdmf::write_includes;
