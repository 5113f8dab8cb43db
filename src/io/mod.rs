//! Writers: VTK particle frames for ParaView, HDF5 frames for h5py, CSV series.
