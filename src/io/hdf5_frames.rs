//! All particle frames of a run in one HDF5 file, laid out for h5py.
//!
//! ```text
//! /                      root attributes given at creation (scene name, spacing, ...)
//! /frames/000000         group, attributes `time` (f64) and `step` (u64)
//! /frames/000000/position  N x 3 f64
//! /frames/000000/<field>   N f64 (scalar) or N x 3 f64 (vector)
//! ```

use std::path::{Path, PathBuf};

use hdf5::types::VarLenUnicode;
use hdf5::{File, Group};

use super::atomic::temp_sibling;
use super::frame::flatten;
use super::{FieldData, IoError, ParticleFrame};
use crate::Real;

/// Group under which frames are listed; every member is a complete frame.
const FRAMES: &str = "frames";
/// Where a frame is built before it is moved under [`FRAMES`]; a crash mid-frame leaves it here,
/// outside the frame list, and the next append discards it.
const PARTIAL: &str = "partial_frame";

/// A root attribute value.
#[derive(Clone, Debug, PartialEq)]
pub enum AttrValue {
    /// Written as a variable-length UTF-8 string (h5py reads a `str`).
    Str(String),
    Real(Real),
    Int(i64),
}

impl From<&str> for AttrValue {
    fn from(s: &str) -> Self {
        AttrValue::Str(s.to_string())
    }
}

impl From<String> for AttrValue {
    fn from(s: String) -> Self {
        AttrValue::Str(s)
    }
}

impl From<Real> for AttrValue {
    fn from(v: Real) -> Self {
        AttrValue::Real(v)
    }
}

impl From<i64> for AttrValue {
    fn from(v: i64) -> Self {
        AttrValue::Int(v)
    }
}

/// All frames in one HDF5 file readable by h5py, one group `/frames/NNNNNN` (6-digit
/// zero-padded frame index, counting from 0) per frame.
///
/// The file is opened, appended and closed for each frame so a crash between frames keeps every
/// finished frame readable. A frame is built under a temporary group and moved (HDF5 link move)
/// to its final name only when complete, so a half-written frame never appears under
/// `/frames`. A crash *during* an append can still damage HDF5 metadata of the whole file;
/// HDF5 without SWMR offers no stronger guarantee.
///
/// HDF5 serializes all calls behind one global lock: append from one thread.
#[derive(Debug)]
pub struct Hdf5Frames {
    path: PathBuf,
    next_index: u64,
}

impl Hdf5Frames {
    /// Creates (or replaces) the file with the given root attributes and an empty `/frames`.
    ///
    /// The file is built under a temporary sibling name and renamed, so a crash here never
    /// leaves a file without its attributes.
    pub fn create(path: &Path, attributes: &[(&str, AttrValue)]) -> Result<Self, IoError> {
        for (i, (name, _)) in attributes.iter().enumerate() {
            if name.is_empty() || attributes[..i].iter().any(|(other, _)| other == name) {
                return Err(IoError::invalid(
                    path,
                    format!("root attribute name {name:?} is empty or repeated"),
                ));
            }
        }
        let tmp = temp_sibling(path)?;
        let result = create_file(&tmp, attributes)
            .map_err(|(action, message)| IoError::Hdf5 {
                path: path.to_path_buf(),
                action,
                message,
            })
            .and_then(|()| {
                std::fs::rename(&tmp, path)
                    .map_err(|e| IoError::io(path, "renaming temporary file onto", e))
            });
        if result.is_err() {
            let _ = std::fs::remove_file(&tmp);
        }
        result.map(|()| Hdf5Frames {
            path: path.to_path_buf(),
            next_index: 0,
        })
    }

    /// Appends one frame as `/frames/NNNNNN`; the index advances only when the frame is
    /// complete, so a failed append can be retried.
    pub fn append(&mut self, frame: &ParticleFrame) -> Result<(), IoError> {
        frame.validate(&self.path, "position")?;
        let name = format!("{:06}", self.next_index);
        append_frame(&self.path, &name, frame).map_err(|(action, message)| IoError::Hdf5 {
            path: self.path.clone(),
            action,
            message,
        })?;
        self.next_index += 1;
        Ok(())
    }

    /// Number of frames appended so far.
    pub fn len(&self) -> u64 {
        self.next_index
    }

    /// True before the first frame.
    pub fn is_empty(&self) -> bool {
        self.next_index == 0
    }

    /// The file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

/// An HDF5 failure as (what was being done, the library's message).
pub(super) type Failure = (String, String);

/// Attaches what was being done to an HDF5 error.
pub(super) fn ctx<T>(r: hdf5::Result<T>, action: impl FnOnce() -> String) -> Result<T, Failure> {
    r.map_err(|e| (action(), e.to_string()))
}

fn create_file(path: &Path, attributes: &[(&str, AttrValue)]) -> Result<(), Failure> {
    let file = ctx(File::create(path), || "creating file".into())?;
    {
        let root: &Group = &file;
        for (name, value) in attributes {
            let what = || format!("writing root attribute {name:?}");
            match value {
                AttrValue::Str(s) => {
                    let v: VarLenUnicode = s.parse().map_err(|e| (what(), format!("{e}")))?;
                    let attr = ctx(
                        root.new_attr::<VarLenUnicode>().shape(()).create(*name),
                        what,
                    )?;
                    ctx(attr.as_writer().write_scalar(&v), what)?;
                }
                AttrValue::Real(v) => write_scalar_attr(root, name, v)?,
                AttrValue::Int(v) => write_scalar_attr(root, name, v)?,
            }
        }
        ctx(root.create_group(FRAMES), || "creating /frames".into())?;
    }
    ctx(file.close(), || "closing file".into())
}

pub(super) fn write_scalar_attr<T: hdf5::H5Type>(
    loc: &Group,
    name: &str,
    v: &T,
) -> Result<(), Failure> {
    let what = || format!("writing attribute {name:?}");
    let attr = ctx(loc.new_attr::<T>().shape(()).create(name), what)?;
    ctx(attr.as_writer().write_scalar(v), what)
}

fn write_dataset(
    group: &Group,
    name: &str,
    data: &[Real],
    rows: usize,
    cols: usize,
) -> Result<(), Failure> {
    let what = || format!("writing dataset {name:?}");
    let builder = group.new_dataset::<Real>();
    let ds = if cols == 1 {
        ctx(builder.shape(rows).create(name), what)?
    } else {
        ctx(builder.shape((rows, cols)).create(name), what)?
    };
    if !data.is_empty() {
        ctx(ds.as_writer().write_raw(data), what)?;
    }
    Ok(())
}

fn append_frame(path: &Path, name: &str, frame: &ParticleFrame) -> Result<(), Failure> {
    append_group(path, name, frame.step, frame.time, |_, group| {
        let n = frame.positions.len();
        write_dataset(group, "position", &flatten(frame.positions), n, 3)?;
        for field in &frame.fields {
            match field.data {
                FieldData::Scalar(v) => write_dataset(group, field.name, v, n, 1)?,
                FieldData::Vector(v) => write_dataset(group, field.name, &flatten(v), n, 3)?,
            }
        }
        Ok(())
    })
}

/// Appends the frame group `/frames/<name>` with attributes `time` and `step`, its content
/// written by `write` (which also gets the file, for root attributes), built under
/// [`PARTIAL`] and moved into place only when complete.
pub(super) fn append_group(
    path: &Path,
    name: &str,
    step: u64,
    time: Real,
    write: impl FnOnce(&File, &Group) -> Result<(), Failure>,
) -> Result<(), Failure> {
    let file = ctx(File::open_rw(path), || "opening for append".into())?;
    {
        let frames = ctx(file.group(FRAMES), || "opening /frames".into())?;
        if frames.link_exists(name) {
            return Err((
                format!("appending frame {name}"),
                "a frame of that name already exists".into(),
            ));
        }
        // A leftover from a crashed append is incomplete by construction: drop it.
        if file.link_exists(PARTIAL) {
            ctx(file.unlink(PARTIAL), || {
                "removing an incomplete frame".into()
            })?;
        }
        let what = || format!("writing frame {name}");
        {
            let group = ctx(file.create_group(PARTIAL), what)?;
            write_scalar_attr(&group, "time", &time)?;
            write_scalar_attr(&group, "step", &step)?;
            write(&file, &group)?;
        }
        ctx(file.relink(PARTIAL, &format!("{FRAMES}/{name}")), || {
            format!("moving frame {name} into /{FRAMES}")
        })?;
    }
    ctx(file.close(), || "closing file".into())
}
