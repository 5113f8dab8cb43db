//! All grid frames of a run behind one HDF5 index, laid out like the particle frames for h5py
//! and as crash-safe (each frame its own file, linked from an index rewritten whole; see
//! `super::hdf5_frames`).
//!
//! ```text
//! /                         root attributes: `format` ("eddy-grid-frames"), `format_version` (1),
//!                           those given at creation, and from the first frame on the grid's
//!                           `origin` (3 f64), `spacing` (f64) and `dims` (3 u64)
//! /frames/000000            group, attributes `time` (f64) and `step` (u64)
//! /frames/000000/<field>    nx x ny x nz f64 (scalar) or nx x ny x nz x 3 f64 (vector),
//!                           C order, indexed [i, j, k] = [x, y, z] as in the solver
//! /frames/000000/<set>/     a particle set of the same time laid out as a particle frame
//!                           (the vortex particles, `vortices`), when appended with one
//! ```
//!
//! Cell `(i, j, k)` spans `origin + spacing * [i, i + 1] x [j, j + 1] x [k, k + 1]`, so in h5py
//! `f["frames/000000/pressure"][i, j, k]` is the value at the cell centre
//! `origin + spacing * (i + 0.5, j + 0.5, k + 0.5)`.

use std::path::Path;

use hdf5::Group;

use super::hdf5_frames::{
    ctx, replace_file, set_grids, validate_sets, write_dataset, write_root_attributes,
    write_scalar_attr, write_sets, Failure, FrameIndex,
};
use super::hdf5_read::{FrameChoice, FrameSeries, StoredFrame};
use super::{xdmf, AttrValue, GridFrame, IoError, ParticleFrame};
use crate::{Real, Vec3};

/// Value of the root attribute `format`, so readers can tell grid files from particle files.
pub const GRID_FORMAT: &str = "eddy-grid-frames";
/// Value of the root attribute `format_version`; raised when the layout changes.
pub const GRID_FORMAT_VERSION: i64 = 1;

/// Root attributes the writer sets itself; callers may not pass them.
const RESERVED: [&str; 5] = ["format", "format_version", "origin", "spacing", "dims"];

/// The grid every frame of a file shares.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Geometry {
    pub(crate) origin: Vec3,
    pub(crate) spacing: Real,
    pub(crate) dims: [usize; 3],
}

impl Geometry {
    fn of(frame: &GridFrame) -> Self {
        Geometry {
            origin: frame.origin,
            spacing: frame.spacing,
            dims: frame.dims,
        }
    }
}

/// All grid frames in one HDF5 file readable by h5py, one group `/frames/NNNNNN` (6-digit
/// zero-padded frame index, counting from 0) per frame, with the same crash behaviour as
/// [`super::Hdf5Frames`]: each frame is its own file, and the index lists a frame only when it
/// is complete.
///
/// The grid (origin, spacing, dims) is fixed by the first frame and stored as root attributes;
/// a later frame on another grid is refused. HDF5 serializes all calls behind one global lock:
/// append from one thread.
#[derive(Debug)]
pub struct Hdf5GridFrames {
    index: FrameIndex,
    /// Set once the first frame is in the file.
    geometry: Option<Geometry>,
}

/// The root attributes of a grid series: the format's, then `attributes` (none of the names
/// the writer reserves).
fn with_format<'a>(
    path: &Path,
    attributes: &[(&'a str, AttrValue)],
) -> Result<Vec<(&'a str, AttrValue)>, IoError> {
    if let Some((name, _)) = attributes.iter().find(|(n, _)| RESERVED.contains(n)) {
        return Err(IoError::invalid(
            path,
            format!("root attribute name {name:?} is reserved for the grid writer"),
        ));
    }
    let mut all = vec![
        ("format", AttrValue::from(GRID_FORMAT)),
        ("format_version", AttrValue::Int(GRID_FORMAT_VERSION)),
    ];
    all.extend_from_slice(attributes);
    Ok(all)
}

impl Hdf5GridFrames {
    /// Creates (or replaces) the file with the format attributes, the given root attributes and
    /// an empty `/frames`, atomically as [`Hdf5Frames::create`] does.
    pub fn create(path: &Path, attributes: &[(&str, AttrValue)]) -> Result<Self, IoError> {
        Ok(Hdf5GridFrames {
            index: FrameIndex::create(path, &with_format(path, attributes)?)?,
            geometry: None,
        })
    }

    /// Writes the frames' datasets deflated at `level` (0 to 9; 0: uncompressed, the default),
    /// as [`super::Hdf5Frames::compressed`].
    pub fn compressed(mut self, level: u8) -> Self {
        self.index.compression = level.min(9);
        self
    }

    /// Appends one frame as `/frames/NNNNNN`; the index advances only when the frame is
    /// complete, so a failed append can be retried.
    pub fn append(&mut self, frame: &GridFrame) -> Result<(), IoError> {
        self.append_with(frame, &[])
    }

    /// Appends one frame with particle sets of the same time, each `(name, set)` as a subgroup
    /// `/frames/NNNNNN/name` laid out as a particle frame.
    pub fn append_with(
        &mut self,
        frame: &GridFrame,
        sets: &[(&str, &ParticleFrame)],
    ) -> Result<(), IoError> {
        frame.validate(&self.index.path)?;
        let names: Vec<&str> = frame.fields.iter().map(|f| f.name).collect();
        validate_sets(&self.index.path, &names, sets)?;
        let geometry = Geometry::of(frame);
        if let Some(fixed) = self.geometry {
            if fixed != geometry {
                return Err(IoError::invalid(
                    &self.index.path,
                    format!(
                        "grid frame has origin {:?}, spacing {}, dims {:?}, but the file's grid \
                         has origin {:?}, spacing {}, dims {:?}",
                        geometry.origin.as_slice(),
                        geometry.spacing,
                        geometry.dims,
                        fixed.origin.as_slice(),
                        fixed.spacing,
                        fixed.dims
                    ),
                ));
            }
        }
        let level = self.index.compression;
        let points = format!("{}_points.h5", self.index.stem()?);
        if self.geometry.is_none() {
            let (coordinates, shape) = xdmf::grid_points(frame);
            replace_file(&self.index.path.with_file_name(&points), |file| {
                write_dataset(file, "points", &coordinates, &shape, level)
            })?;
        }
        self.index.append(
            frame.step,
            frame.time,
            |root| write_geometry(root, &geometry),
            |group| {
                write_fields(group, frame, level)?;
                write_sets(group, sets, level)
            },
            |file| {
                let own = xdmf::cell_grid("grid", file, &points, frame);
                std::iter::once(own).chain(set_grids(file, sets)).collect()
            },
        )?;
        self.geometry = Some(geometry);
        Ok(())
    }

    /// Each frame's XDMF description so far: what a checkpoint keeps to go on.
    pub fn listing(&self) -> &[String] {
        self.index.listing()
    }

    /// Goes on with the series at `path` after the frames `listing` describes (a checkpoint's
    /// [`Self::listing`]), deflating at `level`; the grid's points are written again with the
    /// next frame.
    pub fn resumed(
        path: &Path,
        attributes: &[(&str, AttrValue)],
        level: u8,
        listing: Vec<String>,
    ) -> Result<Self, IoError> {
        Ok(Self {
            index: FrameIndex::resumed(path, &with_format(path, attributes)?, level, listing)?,
            geometry: None,
        })
    }

    /// Number of frames appended so far.
    pub fn len(&self) -> u64 {
        self.index.len()
    }

    /// True before the first frame.
    pub fn is_empty(&self) -> bool {
        self.index.len() == 0
    }

    /// The index file's path.
    pub fn path(&self) -> &Path {
        &self.index.path
    }
}

/// The grid's root attributes, written into every index from the first frame on.
fn write_geometry(root: &Group, g: &Geometry) -> Result<(), Failure> {
    write_array_attr(root, "origin", &[g.origin.x, g.origin.y, g.origin.z])?;
    write_scalar_attr(root, "spacing", &g.spacing)?;
    write_array_attr(root, "dims", &g.dims.map(|n| n as u64))
}

/// Writes `frame` alone as the HDF5 file `path`: its fields as datasets at the root (laid out
/// as a frame's), and as root attributes `attributes`, the grid's `origin`, `spacing` and
/// `dims`, and the frame's `time` and `step`; then `STEM.xmf` beside it, one XDMF grid on the
/// nodes of `STEM_points.h5`, so ParaView opens it as it opens the frames. Each file is written
/// under a temporary name and renamed: a kill leaves the previous file whole. For results that
/// are replaced as a run goes on (its statistics), not for a series.
pub fn write_grid_file(
    path: &Path,
    frame: &GridFrame,
    attributes: &[(&str, AttrValue)],
    level: u8,
) -> Result<(), IoError> {
    frame.validate(path)?;
    let reserved = ["origin", "spacing", "dims", "time", "step"];
    if let Some((name, _)) = attributes.iter().find(|(n, _)| reserved.contains(n)) {
        return Err(IoError::invalid(
            path,
            format!("root attribute name {name:?} is reserved for the grid writer"),
        ));
    }
    let stem = path
        .file_stem()
        .and_then(|s| s.to_str())
        .ok_or_else(|| IoError::invalid(path, "the file name is not UTF-8"))?;
    let name = path
        .file_name()
        .and_then(|s| s.to_str())
        .ok_or_else(|| IoError::invalid(path, "the file name is not UTF-8"))?;
    let points = format!("{stem}_points.h5");
    let (coordinates, shape) = xdmf::grid_points(frame);
    let level = level.min(9);
    replace_file(&path.with_file_name(&points), |file| {
        write_dataset(file, "points", &coordinates, &shape, level)
    })?;
    let attributes: Vec<(String, AttrValue)> = attributes
        .iter()
        .map(|(n, v)| (n.to_string(), v.clone()))
        .collect();
    replace_file(path, |file| {
        write_root_attributes(file, &attributes)?;
        write_geometry(file, &Geometry::of(frame))?;
        write_scalar_attr(file, "time", &frame.time)?;
        write_scalar_attr(file, "step", &frame.step)?;
        write_fields(file, frame, level)
    })?;
    let grid = xdmf::cell_grid(stem, name, &points, frame);
    xdmf::write_single(&path.with_extension("xmf"), &grid)
}

fn write_array_attr<T: hdf5::H5Type>(loc: &Group, name: &str, v: &[T]) -> Result<(), Failure> {
    let what = || format!("writing attribute {name:?}");
    let attr = ctx(loc.new_attr::<T>().shape(v.len()).create(name), what)?;
    ctx(attr.write_raw(v), what)
}

fn write_fields(group: &Group, frame: &GridFrame, level: u8) -> Result<(), Failure> {
    let [nx, ny, nz] = frame.dims;
    for field in &frame.fields {
        // The identity order is the view's own [i, j, k] C order, which is h5py's.
        let values = field.data.flatten(|v| v);
        let shape: &[usize] = match field.data.count() {
            1 => &[nx, ny, nz],
            c => &[nx, ny, nz, c],
        };
        write_dataset(group, field.name, &values, shape, level)?;
    }
    Ok(())
}

/// A velocity field read back from a grid frames file: the grid it lies on and its cell-centre
/// components.
#[derive(Debug, Clone)]
pub struct StoredVelocity {
    pub origin: Vec3,
    pub spacing: Real,
    pub dims: [usize; 3],
    /// The frame's index in the file, and its time, s.
    pub frame: usize,
    pub time: Real,
    /// Cell-centre velocity, m/s, one array per component.
    pub velocity: [ndarray::Array3<Real>; 3],
}

/// Reads the `velocity` of frame `frame` (the last when `None`) of the grid frames file
/// `path` (an index written by [`Hdf5GridFrames`]). HDF5 holds a global lock: call from one
/// thread.
pub fn read_velocity(path: &Path, frame: Option<usize>) -> Result<StoredVelocity, IoError> {
    let fail = |what: String| IoError::invalid(path, what);
    let series = FrameSeries::open(path)?;
    let Geometry {
        origin,
        spacing,
        dims,
    } = grid_geometry(&series)?;
    let StoredFrame {
        index: k,
        time,
        group,
    } = series.pick(frame.map_or(FrameChoice::Last, FrameChoice::Index))?;
    let data = group
        .dataset("velocity")
        .and_then(|d| d.read::<f64, ndarray::Ix4>())
        .map_err(|e| fail(format!("frame {k}: dataset `velocity`: {e}")))?;
    if data.shape() != [dims[0], dims[1], dims[2], 3] {
        return Err(fail(format!(
            "frame {k}: velocity has shape {:?}, the file's grid is {dims:?} x 3",
            data.shape()
        )));
    }
    if data.iter().any(|v| !v.is_finite()) {
        return Err(fail(format!("frame {k}: velocity holds non-finite values")));
    }
    Ok(StoredVelocity {
        origin,
        spacing,
        dims,
        frame: k,
        time,
        velocity: std::array::from_fn(|c| data.index_axis(ndarray::Axis(3), c).to_owned()),
    })
}

/// The obstacle cells (`solid` > 0.5) of frame `frame` of the grid frames file `path`, or
/// None when the frame has no `solid` field. HDF5 holds a global lock: call from one thread.
pub fn read_solid(path: &Path, frame: usize) -> Result<Option<ndarray::Array3<bool>>, IoError> {
    let series = FrameSeries::open(path)?;
    let dims = grid_geometry(&series)?.dims;
    let StoredFrame {
        index: k, group, ..
    } = series.pick(FrameChoice::Index(frame))?;
    let Ok(dataset) = group.dataset("solid") else {
        return Ok(None);
    };
    let fail = |what: String| IoError::invalid(path, format!("frame {k}: {what}"));
    let data = dataset
        .read::<f64, ndarray::Ix3>()
        .map_err(|e| fail(format!("dataset `solid`: {e}")))?;
    if data.shape() != dims {
        return Err(fail(format!(
            "solid has shape {:?}, the file's grid is {dims:?}",
            data.shape()
        )));
    }
    Ok(Some(data.mapv(|s| s > 0.5)))
}

/// The grid the frames of `series` share, refusing a series that is not grid frames.
pub(crate) fn grid_geometry(series: &FrameSeries) -> Result<Geometry, IoError> {
    let fail = |what: String| IoError::invalid(&series.path, what);
    match series.format() {
        Some(format) if format == GRID_FORMAT => {}
        Some(other) => {
            return Err(fail(format!(
                "root attribute `format` is {other:?}, expected {GRID_FORMAT:?} (grid frames)"
            )))
        }
        None => {
            return Err(fail(
                "no root attribute `format`: not eddy grid frames".into(),
            ))
        }
    }
    let file = &series.file;
    let read = |name: &str| {
        file.attr(name)
            .and_then(|a| a.read_raw::<f64>())
            .map_err(|e| fail(format!("root attribute `{name}`: {e}")))
    };
    let (origin, spacing) = (read("origin")?, read("spacing")?);
    let dims = file
        .attr("dims")
        .and_then(|a| a.read_raw::<u64>())
        .map_err(|e| fail(format!("root attribute `dims`: {e}")))?;
    match (origin.as_slice(), dims.as_slice(), spacing.as_slice()) {
        (&[x, y, z], &[nx, ny, nz], &[spacing]) => Ok(Geometry {
            origin: Vec3::new(x, y, z),
            spacing,
            dims: [nx, ny, nz].map(|n| n as usize),
        }),
        _ => Err(fail(
            "root attributes origin, dims, spacing have wrong sizes".into(),
        )),
    }
}
