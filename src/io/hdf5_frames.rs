//! All particle frames of a run behind one HDF5 file, laid out for h5py.
//!
//! ```text
//! /                      root attributes given at creation (scene name, spacing, ...)
//! /frames/000000         group, attributes `time` (f64) and `step` (u64)
//! /frames/000000/position  N x 3 f64
//! /frames/000000/<field>   N f64 (scalar) or N x 3 f64 (vector)
//! /frames/000000/<set>/    a particle set of the same time laid out as a frame (e.g. the
//!                          vortex particles, `vortices`), when appended with one
//! ```
//!
//! **Crash safety.** Each frame is its own file `STEM_NNNNNN.h5` beside the index `STEM.h5`,
//! written under a temporary name and renamed when complete; `/frames/NNNNNN` in the index is
//! an HDF5 external link to that file's root, which h5py and the HDF5 library follow (relative
//! to the index's folder). The index is rewritten whole for every frame, under a temporary name
//! and renamed, so a kill at any point leaves an index that opens and lists only complete
//! frames. No HDF5 file is ever modified in place.
//!
//! **XDMF.** After each frame `STEM.xmf` is rewritten (atomically) beside the index, describing
//! every listed frame for ParaView's XDMF reader ([`super::xdmf`]).
//!
//! **Compression.** With a level from 1 to 9 ([`Hdf5Frames::compressed`]) every dataset is
//! chunked (about 1 MiB a chunk), byte-shuffled and deflated, HDF5's own filters that h5py and
//! ParaView read without plug-ins, the chunks compressed in parallel ([`write_dataset`]);
//! level 0 writes contiguous datasets.

use std::path::{Path, PathBuf};

use hdf5::types::VarLenUnicode;
use hdf5::{File, Group};
use rayon::prelude::*;

use super::atomic::temp_sibling;
use super::frame::flatten;
use super::zlib::zlib;
use super::{xdmf, FieldData, IoError, ParticleFrame};
use crate::Real;

/// Group under which frames are listed; every member is a complete frame.
const FRAMES: &str = "frames";

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

/// All frames behind one HDF5 index readable by h5py, one group `/frames/NNNNNN` (6-digit
/// zero-padded frame index, counting from 0) per frame, each frame in its own file (see the
/// module documentation for why a crash cannot damage a listed frame).
///
/// HDF5 serializes all calls behind one global lock: append from one thread.
#[derive(Debug)]
pub struct Hdf5Frames {
    index: FrameIndex,
}

impl Hdf5Frames {
    /// Creates (or replaces) the index with the given root attributes and an empty `/frames`,
    /// under a temporary name and renamed, so a crash here never leaves a file without its
    /// attributes.
    pub fn create(path: &Path, attributes: &[(&str, AttrValue)]) -> Result<Self, IoError> {
        Ok(Self {
            index: FrameIndex::create(path, attributes)?,
        })
    }

    /// Writes the frames' datasets deflated at `level` (0 to 9; 0: uncompressed, the default).
    pub fn compressed(mut self, level: u8) -> Self {
        self.index.compression = level.min(9);
        self
    }

    /// Appends one frame as `/frames/NNNNNN`; the index advances only when the frame is
    /// complete, so a failed append can be retried.
    pub fn append(&mut self, frame: &ParticleFrame) -> Result<(), IoError> {
        self.append_with(frame, &[])
    }

    /// Appends one frame with other particle sets of the same time, each `(name, set)` as a
    /// subgroup `/frames/NNNNNN/name` laid out as a frame.
    pub fn append_with(
        &mut self,
        frame: &ParticleFrame,
        sets: &[(&str, &ParticleFrame)],
    ) -> Result<(), IoError> {
        frame.validate(&self.index.path, "position")?;
        let names: Vec<&str> = frame.fields.iter().map(|f| f.name).collect();
        validate_sets(&self.index.path, &names, sets)?;
        let level = self.index.compression;
        self.index.append(
            frame.step,
            frame.time,
            |_| Ok(()),
            |group| {
                write_particles(group, frame, level)?;
                write_sets(group, sets, level)
            },
            |file| {
                let own = xdmf::particle_grid("particles", file, "/", frame);
                own.into_iter().chain(set_grids(file, sets)).collect()
            },
        )
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

    /// Each frame's XDMF description so far: what a checkpoint keeps to go on.
    pub fn listing(&self) -> &[String] {
        self.index.listing()
    }

    /// Goes on with the series at `path` after the frames `listing` describes (a checkpoint's
    /// [`Self::listing`]), deflating at `level`.
    pub fn resumed(
        path: &Path,
        attributes: &[(&str, AttrValue)],
        level: u8,
        listing: Vec<String>,
    ) -> Result<Self, IoError> {
        Ok(Self {
            index: FrameIndex::resumed(path, attributes, level, listing)?,
        })
    }
}

/// The index file of a frame series and the frame files it links.
#[derive(Debug)]
pub(super) struct FrameIndex {
    pub(super) path: PathBuf,
    attributes: Vec<(String, AttrValue)>,
    /// File names of the complete frames, in order.
    frames: Vec<String>,
    /// Deflate level of the datasets, 0 to 9 (0: contiguous, uncompressed).
    pub(super) compression: u8,
    /// Each listed frame's XDMF description.
    xdmf: Vec<String>,
}

impl FrameIndex {
    /// Checks the attribute names and writes the index with no frames.
    pub(super) fn create(path: &Path, attributes: &[(&str, AttrValue)]) -> Result<Self, IoError> {
        let index = Self::listing_frames(path, attributes, 0, Vec::new())?;
        index.write(&index.frames, |_| Ok(()))?;
        Ok(index)
    }

    /// The index of a resumed run, listing the first frames an earlier run wrote (their
    /// XDMF descriptions `xdmf`, from its checkpoint); nothing is written until the next
    /// append, so the index on disk stays the earlier run's, whose frames are all whole. An
    /// error names a listed frame file that is gone.
    pub(super) fn resumed(
        path: &Path,
        attributes: &[(&str, AttrValue)],
        compression: u8,
        xdmf: Vec<String>,
    ) -> Result<Self, IoError> {
        let index = Self::listing_frames(path, attributes, compression.min(9), xdmf)?;
        if let Some(gone) = index
            .frames
            .iter()
            .find(|f| !path.with_file_name(f).exists())
        {
            return Err(IoError::invalid(
                path,
                format!("the checkpoint lists the frame file {gone}, which is gone"),
            ));
        }
        Ok(index)
    }

    /// The index listing one frame file per description of `xdmf`, not yet written; an error
    /// names an empty or repeated attribute name.
    fn listing_frames(
        path: &Path,
        attributes: &[(&str, AttrValue)],
        compression: u8,
        xdmf: Vec<String>,
    ) -> Result<Self, IoError> {
        for (i, (name, _)) in attributes.iter().enumerate() {
            if name.is_empty() || attributes[..i].iter().any(|(other, _)| other == name) {
                return Err(IoError::invalid(
                    path,
                    format!("root attribute name {name:?} is empty or repeated"),
                ));
            }
        }
        let mut index = Self {
            path: path.to_path_buf(),
            attributes: attributes
                .iter()
                .map(|(n, v)| (n.to_string(), v.clone()))
                .collect(),
            frames: Vec::new(),
            compression,
            xdmf,
        };
        index.frames = (0..index.xdmf.len())
            .map(|k| index.frame_file(k))
            .collect::<Result<_, _>>()?;
        Ok(index)
    }

    /// Frames listed so far.
    pub(super) fn len(&self) -> u64 {
        self.frames.len() as u64
    }

    /// Each listed frame's XDMF description, what [`FrameIndex::resumed`] takes back.
    pub(super) fn listing(&self) -> &[String] {
        &self.xdmf
    }

    /// The file name of frame `k`: the index's stem and the frame's number.
    fn frame_file(&self, k: usize) -> Result<String, IoError> {
        Ok(format!("{}_{k:06}.h5", self.stem()?))
    }

    /// The index's file stem, which names its frame files.
    pub(super) fn stem(&self) -> Result<&str, IoError> {
        self.path
            .file_stem()
            .and_then(|s| s.to_str())
            .ok_or_else(|| IoError::invalid(&self.path, "the file name is not UTF-8"))
    }

    /// Writes the next frame's file (attributes `time`, `step`, content by `content`), then the
    /// index listing it, with root attributes beyond the creation ones from `root`, then the
    /// XDMF series with the frame's grids as `describe` gives them from the frame file's name.
    pub(super) fn append(
        &mut self,
        step: u64,
        time: Real,
        root: impl Fn(&Group) -> Result<(), Failure>,
        content: impl FnOnce(&Group) -> Result<(), Failure>,
        describe: impl FnOnce(&str) -> Vec<String>,
    ) -> Result<(), IoError> {
        let stem = self.stem()?.to_owned();
        let name = self.frame_file(self.frames.len())?;
        let frame_path = self.path.with_file_name(&name);
        replace_file(&frame_path, |file| {
            write_scalar_attr(file, "time", &time)?;
            write_scalar_attr(file, "step", &step)?;
            content(file)
        })?;
        let grids = describe(&name);
        let mut frames = self.frames.clone();
        frames.push(name);
        self.write(&frames, root)?;
        self.frames = frames;
        let k = self.xdmf.len();
        self.xdmf.push(xdmf::frame(k, time, &grids));
        xdmf::write_series(&self.path.with_extension("xmf"), &stem, &self.xdmf)
    }

    /// Replaces the index by one listing `frames`.
    fn write(
        &self,
        frames: &[String],
        root: impl Fn(&Group) -> Result<(), Failure>,
    ) -> Result<(), IoError> {
        replace_file(&self.path, |file| {
            write_root_attributes(file, &self.attributes)?;
            root(file)?;
            let list = ctx(file.create_group(FRAMES), || "creating /frames".into())?;
            for (k, target) in frames.iter().enumerate() {
                let link = format!("{k:06}");
                ctx(list.link_external(target, "/", &link), || {
                    format!("linking frame {link} to {target}")
                })?;
            }
            Ok(())
        })
    }
}

/// Writes `path` as an HDF5 file whose root holds `attributes` and, for each `(name, target)`,
/// an external link `/name` to the root of the file `target` (relative to `path`'s folder):
/// one file that opens several frame series together (a coupled scene's `frames.h5`, with
/// `/particles` and `/grid`). Written whole under a temporary name and renamed.
pub fn write_links(
    path: &Path,
    attributes: &[(&str, AttrValue)],
    links: &[(&str, &str)],
) -> Result<(), IoError> {
    let attributes: Vec<(String, AttrValue)> = attributes
        .iter()
        .map(|(n, v)| (n.to_string(), v.clone()))
        .collect();
    replace_file(path, |file| {
        write_root_attributes(file, &attributes)?;
        for (name, target) in links {
            ctx(file.link_external(target, "/", name), || {
                format!("linking /{name} to {target}")
            })?;
        }
        Ok(())
    })
}

/// Builds an HDF5 file with `write` under a temporary sibling name and renames it onto `path`;
/// on failure the temporary file is removed and `path` is left as it was.
pub(super) fn replace_file(
    path: &Path,
    write: impl FnOnce(&File) -> Result<(), Failure>,
) -> Result<(), IoError> {
    let tmp = temp_sibling(path)?;
    let built = (|| {
        let file = ctx(File::create(&tmp), || "creating file".into())?;
        write(&file)?;
        ctx(file.close(), || "closing file".into())
    })();
    let result = built
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
    result
}

/// An HDF5 failure as (what was being done, the library's message).
pub(super) type Failure = (String, String);

/// Attaches what was being done to an HDF5 error.
pub(super) fn ctx<T>(r: hdf5::Result<T>, action: impl FnOnce() -> String) -> Result<T, Failure> {
    r.map_err(|e| (action(), e.to_string()))
}

pub(super) fn write_root_attributes(
    root: &Group,
    attributes: &[(String, AttrValue)],
) -> Result<(), Failure> {
    for (name, value) in attributes {
        let what = || format!("writing root attribute {name:?}");
        match value {
            AttrValue::Str(s) => {
                let v: VarLenUnicode = s.parse().map_err(|e| (what(), format!("{e}")))?;
                let attr = ctx(
                    root.new_attr::<VarLenUnicode>()
                        .shape(())
                        .create(name.as_str()),
                    what,
                )?;
                ctx(attr.as_writer().write_scalar(&v), what)?;
            }
            AttrValue::Real(v) => write_scalar_attr(root, name, v)?,
            AttrValue::Int(v) => write_scalar_attr(root, name, v)?,
        }
    }
    Ok(())
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

/// Checks particle sets to be written beside a frame whose datasets are named `taken`: each
/// set a valid frame, its name a valid group name that no dataset or other set has.
pub(super) fn validate_sets(
    path: &Path,
    taken: &[&str],
    sets: &[(&str, &ParticleFrame)],
) -> Result<(), IoError> {
    for (i, (name, set)) in sets.iter().enumerate() {
        let bad = name.is_empty() || name.contains('/') || name.chars().any(char::is_control);
        if bad || taken.contains(name) || sets[..i].iter().any(|(n, _)| n == name) {
            return Err(IoError::invalid(
                path,
                format!("particle set name {name:?} is empty, repeated or holds '/'"),
            ));
        }
        set.validate(path, "position")?;
    }
    Ok(())
}

/// Writes each `(name, set)` as a subgroup of `group` laid out as a particle frame.
pub(super) fn write_sets(
    group: &Group,
    sets: &[(&str, &ParticleFrame)],
    level: u8,
) -> Result<(), Failure> {
    for (name, set) in sets {
        let sub = ctx(group.create_group(name), || {
            format!("creating group {name:?}")
        })?;
        write_particles(&sub, set, level)?;
    }
    Ok(())
}

/// The XDMF grids of particle sets written by [`write_sets`] into the frame file `file`.
pub(super) fn set_grids(file: &str, sets: &[(&str, &ParticleFrame)]) -> Vec<String> {
    sets.iter()
        .filter_map(|(name, set)| xdmf::particle_grid(name, file, &format!("/{name}/"), set))
        .collect()
}

/// Writes a particle frame's positions and fields as datasets of `group`.
fn write_particles(group: &Group, frame: &ParticleFrame, level: u8) -> Result<(), Failure> {
    let n = frame.positions.len();
    let positions = flatten(frame.positions);
    write_dataset(group, "position", &positions, &[n, 3], level)?;
    for field in &frame.fields {
        match field.data {
            FieldData::Scalar(v) => write_dataset(group, field.name, v, &[n], level)?,
            FieldData::Vector(v) => write_dataset(group, field.name, &flatten(v), &[n, 3], level)?,
        }
    }
    Ok(())
}

/// Bytes of a chunk before compression: the chunks of a frame's larger datasets compress on
/// every core, and a chunk is still large enough that its header and deflate's start-up are
/// noise.
const CHUNK_BYTES: usize = 1 << 20;

/// Writes `data` (C order) as the dataset `name` of `shape`; when `level` is above 0 and the
/// dataset is not empty, in chunks of whole rows along the first axis, each byte-shuffled and
/// deflated at `level`.
///
/// HDF5 runs its filters on one thread behind its global lock, which made a 128³ grid frame
/// take 1.8 s to deflate. Here the chunks are shuffled and compressed in parallel (zlib-rs)
/// exactly as HDF5's `shuffle` and `deflate` filters would, and handed to HDF5 as they are
/// (`H5Dwrite_chunk`); the dataset records both filters, so every reader decodes the chunks as
/// its own.
pub(super) fn write_dataset(
    group: &Group,
    name: &str,
    data: &[Real],
    shape: &[usize],
    level: u8,
) -> Result<(), Failure> {
    let what = || format!("writing dataset {name:?}");
    if level == 0 || data.is_empty() {
        let ds = ctx(group.new_dataset::<Real>().shape(shape).create(name), what)?;
        if !data.is_empty() {
            ctx(ds.as_writer().write_raw(data), what)?;
        }
        return Ok(());
    }
    let row: usize = shape[1..].iter().product();
    let rows = (CHUNK_BYTES / (std::mem::size_of::<Real>() * row)).clamp(1, shape[0]);
    let mut chunk = shape.to_vec();
    chunk[0] = rows;
    let builder = group.new_dataset::<Real>().chunk(chunk).shuffle();
    let ds = ctx(builder.deflate(level).shape(shape).create(name), what)?;
    let chunks: Vec<Vec<u8>> = data
        .par_chunks(rows * row)
        .map(|values| zlib(&shuffle(values, rows * row), level))
        .collect();
    hdf5::sync::sync(|| {
        for (k, bytes) in chunks.iter().enumerate() {
            let mut offset = vec![0 as hdf5_sys::h5::hsize_t; shape.len()];
            offset[0] = (k * rows) as hdf5_sys::h5::hsize_t;
            // SAFETY: `ds` is an open chunked dataset, `offset` has its rank and lies on a
            // chunk boundary inside it, and `bytes` is one whole chunk passed through the
            // dataset's own filters (mask 0: all applied).
            let status = unsafe {
                hdf5_sys::h5d::H5Dwrite_chunk(
                    ds.id(),
                    hdf5_sys::h5p::H5P_DEFAULT,
                    0,
                    offset.as_ptr(),
                    bytes.len(),
                    bytes.as_ptr().cast(),
                )
            };
            if status < 0 {
                return Err((what(), format!("H5Dwrite_chunk failed for chunk {k}")));
            }
        }
        Ok(())
    })
}

/// A chunk's bytes as HDF5's shuffle filter leaves them: the first byte of every value, then
/// every second byte, and so on, over the whole chunk of `len` values (an edge chunk padded
/// with zeros), so the slowly varying high bytes of neighbouring values sit together.
fn shuffle(values: &[Real], len: usize) -> Vec<u8> {
    const SIZE: usize = std::mem::size_of::<Real>();
    let mut out = vec![0u8; SIZE * len];
    for (i, v) in values.iter().enumerate() {
        for (b, byte) in v.to_ne_bytes().into_iter().enumerate() {
            out[b * len + i] = byte;
        }
    }
    out
}
