//! Where `eddy slice` reads a run's frames: its HDF5 series (`frames.h5`, or a coupled run's
//! `grid_frames.h5` and `particles_frames.h5`) or, for a run that wrote only VTK (the scenes'
//! default), its ParaView series (`grid.pvd`, `particles.pvd`). One interface for both, so a
//! plane is drawn the same whichever the run wrote.

use std::path::{Path, PathBuf};

use hdf5::{Group, Hyperslab, SliceOrIndex};
use ndarray::{Array2, ArrayD, Ix2, IxDyn};

use super::SliceKind;
use crate::io::hdf5_grid::{grid_geometry, GRID_FORMAT};
use crate::io::hdf5_read::{FrameChoice, FrameSeries, StoredFrame};
use crate::io::vtk_read::{read_pvd, Layout, VtkFile};
use crate::io::IoError;
use crate::Real;

/// A run's frames of one kind.
pub(super) enum Series {
    Hdf5 {
        kind: SliceKind,
        series: FrameSeries,
    },
    /// A `.pvd` series, or one VTK file as a series of one: each frame's time and file.
    Vtk {
        kind: SliceKind,
        path: PathBuf,
        frames: Vec<(Real, PathBuf)>,
    },
}

/// The regular grid a frame's cells lie on.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Grid {
    pub(super) origin: [Real; 3],
    pub(super) spacing: [Real; 3],
    pub(super) dims: [usize; 3],
}

impl Grid {
    /// The metres the grid spans along axis `a`.
    pub(super) fn span(&self, a: usize) -> std::ops::Range<Real> {
        self.origin[a]..self.origin[a] + self.spacing[a] * self.dims[a] as Real
    }
}

/// One frame of a [`Series`], open for reading.
pub(super) struct Frame<'a> {
    pub(super) index: usize,
    pub(super) time: Real,
    data: FrameData<'a>,
}

enum FrameData<'a> {
    Hdf5(&'a FrameSeries, StoredFrame),
    Vtk(Box<VtkFile>),
}

const HDF5_NAMES: &str = "frames.h5, or grid_frames.h5 and particles_frames.h5 of a coupled scene";
const VTK_NAMES: &str = "grid.pvd or particles.pvd";

/// The series of `run` to slice: of a folder, its HDF5 frames (full precision) or else its VTK
/// frames, of the kind `kind` asks for (the grid's by default); of a file, that file (`.h5`
/// frames, a `.pvd` series, one `.vti`, `.vtp` or `.vtu` frame).
pub(super) fn locate(run: &Path, kind: Option<SliceKind>) -> Result<Series, IoError> {
    let mut found = if run.is_dir() {
        let existing = |names: &[&str]| -> Vec<PathBuf> {
            let paths = names.iter().map(|n| run.join(n));
            paths.filter(|p| p.is_file()).collect()
        };
        let mut files = existing(&["grid_frames.h5", "particles_frames.h5"]);
        if files.is_empty() {
            files = existing(&["frames.h5"]);
        }
        files.extend(existing(&["grid.pvd", "particles.pvd"]));
        if files.is_empty() {
            return Err(IoError::invalid(
                run,
                format!(
                    "no frames here: neither HDF5 ({HDF5_NAMES}) nor VTK ({VTK_NAMES}); the \
                     scene's [output] must write them (output.vtk = true, or output.hdf5 = \
                     true, e.g. `eddy run SCENE --set output.hdf5=true`)"
                ),
            ));
        }
        files
            .iter()
            .map(|f| open(f))
            .collect::<Result<Vec<_>, _>>()?
    } else if run.is_file() {
        vec![open(run)?]
    } else {
        return Err(IoError::invalid(run, "no such run folder or frames file"));
    };
    let wanted = kind.unwrap_or(SliceKind::Grid);
    match found.iter().position(|s| s.kind() == wanted) {
        Some(i) => Ok(found.swap_remove(i)),
        None if kind.is_none() => Ok(found.swap_remove(0)),
        None => Err(IoError::invalid(
            run,
            format!(
                "holds no {} frames, only {} frames",
                wanted.frames(),
                found[0].kind().frames()
            ),
        )),
    }
}

/// The kind of frames a VTK file of this name holds, by its extension.
fn vtk_kind(path: &Path) -> Option<SliceKind> {
    match path.extension()?.to_str()? {
        "vti" => Some(SliceKind::Grid),
        "vtp" | "vtu" => Some(SliceKind::Particles),
        _ => None,
    }
}

/// The series in the file `path`, by its extension: a `.pvd` series, one VTK frame, or else
/// HDF5 frames.
fn open(path: &Path) -> Result<Series, IoError> {
    let ext = path.extension().and_then(|e| e.to_str());
    if ext == Some("pvd") {
        let frames = read_pvd(path)?;
        let first = frames
            .first()
            .ok_or_else(|| IoError::invalid(path, "the series lists no frames"))?;
        let kind = vtk_kind(&first.1).ok_or_else(|| {
            IoError::invalid(
                path,
                format!(
                    "lists {}: frames are .vti (grid) or .vtp (particles)",
                    first.1.display()
                ),
            )
        })?;
        return Ok(Series::Vtk {
            kind,
            path: path.to_path_buf(),
            frames,
        });
    }
    if let Some(kind) = vtk_kind(path) {
        let time = VtkFile::open(path)?.time().unwrap_or(0.0);
        return Ok(Series::Vtk {
            kind,
            path: path.to_path_buf(),
            frames: vec![(time, path.to_path_buf())],
        });
    }
    let series = FrameSeries::open(path)?;
    let kind = if series.format().as_deref() == Some(GRID_FORMAT) {
        SliceKind::Grid
    } else {
        SliceKind::Particles
    };
    Ok(Series::Hdf5 { kind, series })
}

impl Series {
    pub(super) fn kind(&self) -> SliceKind {
        match self {
            Series::Hdf5 { kind, .. } | Series::Vtk { kind, .. } => *kind,
        }
    }

    /// The series' index file (`.h5`, `.pvd`) or its one frame.
    pub(super) fn path(&self) -> &Path {
        match self {
            Series::Hdf5 { series, .. } => &series.path,
            Series::Vtk { path, .. } => path,
        }
    }

    pub(super) fn count(&self) -> usize {
        match self {
            Series::Hdf5 { series, .. } => series
                .pick(FrameChoice::Last)
                .map_or(0, |last| last.index + 1),
            Series::Vtk { frames, .. } => frames.len(),
        }
    }

    /// The time of frame `k` (< the count), s.
    pub(super) fn time(&self, k: usize) -> Result<Real, IoError> {
        match self {
            Series::Hdf5 { series, .. } => Ok(series.pick(FrameChoice::Index(k))?.time),
            Series::Vtk { frames, .. } => Ok(frames[k].0),
        }
    }

    /// Frame `k` (< the count), open for reading.
    pub(super) fn frame(&self, k: usize) -> Result<Frame<'_>, IoError> {
        Ok(match self {
            Series::Hdf5 { series, .. } => {
                let stored = series.pick(FrameChoice::Index(k))?;
                Frame {
                    index: k,
                    time: stored.time,
                    data: FrameData::Hdf5(series, stored),
                }
            }
            Series::Vtk { frames, .. } => Frame {
                index: k,
                time: frames[k].0,
                data: FrameData::Vtk(Box::new(VtkFile::open(&frames[k].1)?)),
            },
        })
    }

    /// The particles' spacing, m: the root attribute `particle_spacing` of HDF5 frames; VTK
    /// frames do not store it, so it is the run's `fluid.spacing` from the resolved scene
    /// (`scene.toml`) beside them.
    pub(super) fn particle_spacing(&self) -> Result<Real, IoError> {
        let positive = |h: &Real| h.is_finite() && *h > 0.0;
        match self {
            Series::Hdf5 { series, .. } => series
                .file
                .attr("particle_spacing")
                .and_then(|a| a.read_scalar::<Real>())
                .ok()
                .filter(positive)
                .ok_or_else(|| {
                    IoError::invalid(
                        &series.path,
                        "no positive root attribute `particle_spacing`",
                    )
                }),
            Series::Vtk { path, .. } => {
                let scene = path.with_file_name(crate::pipeline::outputs::SCENE_FILE);
                let fail = |why: String| {
                    IoError::invalid(
                        &scene,
                        format!(
                            "particle VTK frames do not store the particle spacing, which sets \
                             the slab drawn; it is read from the run's scene beside them \
                             (fluid.spacing), which {why}"
                        ),
                    )
                };
                let text = std::fs::read_to_string(&scene).map_err(|e| fail(e.to_string()))?;
                let value: toml::Table = text.parse().map_err(|e| fail(format!("{e}")))?;
                value
                    .get("fluid")
                    .and_then(|f| f.get("spacing"))
                    .and_then(toml::Value::as_float)
                    .filter(positive)
                    .ok_or_else(|| fail("has no positive fluid.spacing".into()))
            }
        }
    }
}

/// `field` is a vector: 3 components per cell or particle.
pub(super) type Fields = Vec<(String, bool)>;

impl Frame<'_> {
    /// The file that holds the frame, for errors: the HDF5 index or the VTK frame.
    pub(super) fn path(&self) -> &Path {
        match &self.data {
            FrameData::Hdf5(series, _) => &series.path,
            FrameData::Vtk(file) => &file.path,
        }
    }

    /// An error about this frame.
    pub(super) fn fail(&self, what: impl std::fmt::Display) -> IoError {
        IoError::invalid(self.path(), format!("frame {}: {what}", self.index))
    }

    /// The fields of a frame of `kind`: scalars (one value per cell or particle) and vectors
    /// (flagged true), in the file's order; particle positions are where values lie, no field.
    pub(super) fn fields(&self, kind: SliceKind) -> Fields {
        match &self.data {
            FrameData::Hdf5(_, stored) => {
                let rank = match kind {
                    SliceKind::Grid => 3,
                    SliceKind::Particles => 1,
                };
                hdf5_fields(&stored.group, rank)
            }
            FrameData::Vtk(file) => file
                .fields()
                .into_iter()
                .filter(|&(_, c)| c == 1 || c == 3)
                .map(|(name, c)| (name.to_owned(), c == 3))
                .collect(),
        }
    }

    /// The grid of a grid frame.
    pub(super) fn grid(&self) -> Result<Grid, IoError> {
        match &self.data {
            FrameData::Hdf5(series, _) => {
                let g = grid_geometry(series)?;
                Ok(Grid {
                    origin: g.origin.into(),
                    spacing: [g.spacing; 3],
                    dims: g.dims,
                })
            }
            FrameData::Vtk(file) => match &file.layout {
                Layout::Image {
                    origin,
                    spacing,
                    cells,
                } => Ok(Grid {
                    origin: *origin,
                    spacing: *spacing,
                    dims: *cells,
                }),
                Layout::Points(_) => Err(self.fail("holds particles, not a grid")),
            },
        }
    }

    /// The layer `layer` across axis `a` of the grid field `name` on `grid`: its cells over
    /// the other two axes in x, y, z order, with a vector's components along a third.
    pub(super) fn grid_layer(
        &self,
        name: &str,
        grid: &Grid,
        a: usize,
        layer: usize,
    ) -> Result<ArrayD<Real>, IoError> {
        let read = |e: hdf5::Error| self.fail(format!("reading `{name}`: {e}"));
        let whole = match &self.data {
            FrameData::Hdf5(_, stored) => {
                let dataset = stored
                    .group
                    .dataset(name)
                    .map_err(|e| self.fail(format!("dataset `{name}`: {e}")))?;
                if dataset.shape().get(..3) != Some(&grid.dims[..]) {
                    return Err(self.fail(format!(
                        "`{name}` has shape {:?}, the grid is {:?}",
                        dataset.shape(),
                        grid.dims
                    )));
                }
                let selection: Vec<SliceOrIndex> = (0..dataset.ndim())
                    .map(|d| if d == a { layer.into() } else { (..).into() })
                    .collect();
                return dataset
                    .read_slice::<Real, _, IxDyn>(Hyperslab::from(selection))
                    .map_err(read);
            }
            FrameData::Vtk(file) => file.field(name)?,
        };
        // VTK orders cells x fastest, a cell's components side by side: C order [z, y, x, c].
        let [nx, ny, nz] = grid.dims;
        let components = whole.len() / (nx * ny * nz).max(1);
        let cells = ArrayD::from_shape_vec(IxDyn(&[nz, ny, nx, components]), whole)
            .map_err(|e| self.fail(format!("`{name}`: {e}")))?
            .permuted_axes(IxDyn(&[2, 1, 0, 3]));
        let layer = cells.index_axis(ndarray::Axis(a), layer);
        Ok(if components == 1 {
            layer.index_axis(ndarray::Axis(2), 0).to_owned()
        } else {
            layer.to_owned()
        })
    }

    /// The particles' positions, one row of x, y, z each.
    pub(super) fn positions(&self) -> Result<Array2<Real>, IoError> {
        let positions = match &self.data {
            FrameData::Hdf5(_, stored) => stored
                .group
                .dataset("position")
                .and_then(|d| d.read::<Real, Ix2>())
                .map_err(|e| self.fail(format!("dataset `position`: {e}")))?,
            FrameData::Vtk(file) => {
                let points = file.points()?;
                Array2::from_shape_vec((points.len() / 3, 3), points)
                    .map_err(|e| self.fail(format!("points: {e}")))?
            }
        };
        if positions.ncols() != 3 {
            return Err(self.fail(format!(
                "`position` has shape {:?}, not N x 3",
                positions.shape()
            )));
        }
        Ok(positions)
    }

    /// The particle field `name`: one value, or one vector's three components, per particle.
    pub(super) fn particle_values(
        &self,
        name: &str,
        vector: bool,
    ) -> Result<ArrayD<Real>, IoError> {
        match &self.data {
            FrameData::Hdf5(_, stored) => stored
                .group
                .dataset(name)
                .and_then(|d| d.read_dyn::<Real>())
                .map_err(|e| self.fail(format!("reading `{name}`: {e}"))),
            FrameData::Vtk(file) => {
                let values = file.field(name)?;
                let shape = if vector {
                    vec![values.len() / 3, 3]
                } else {
                    vec![values.len()]
                };
                ArrayD::from_shape_vec(IxDyn(&shape), values)
                    .map_err(|e| self.fail(format!("`{name}`: {e}")))
            }
        }
    }
}

/// The fields of an HDF5 frame group: its datasets of scalar `rank`, or one more with 3
/// components (flagged true), in name order; `position` is where particles lie, no field.
fn hdf5_fields(group: &Group, rank: usize) -> Fields {
    let names = group.member_names().unwrap_or_default();
    names
        .into_iter()
        .filter(|n| n != "position")
        .filter_map(|n| {
            let shape = group.dataset(&n).ok()?.shape();
            match shape.len() {
                r if r == rank => Some((n, false)),
                r if r == rank + 1 && shape[rank] == 3 => Some((n, true)),
                _ => None,
            }
        })
        .collect()
}
