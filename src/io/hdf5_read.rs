//! Reading an HDF5 frame series back (the layout of `super::hdf5_frames`): its index, the
//! frame a reader asks for and that frame's time. One reader for the grid velocity of a static
//! flow and for `eddy slice`, so both pick frames and word their errors alike.

use std::path::{Path, PathBuf};

use hdf5::{File, Group};

use super::IoError;
use crate::Real;

/// Which frame of a series to read.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FrameChoice {
    /// The last frame written.
    Last,
    /// Frame `k`, counting from 0.
    Index(usize),
    /// The frame whose time is nearest this (s); the earlier one on a tie.
    Time(Real),
}

/// An open frame index and how many frames it lists.
pub(crate) struct FrameSeries {
    pub(crate) path: PathBuf,
    pub(crate) file: File,
    count: usize,
}

/// One frame of a series: its index, time (s) and group.
pub(crate) struct StoredFrame {
    pub(crate) index: usize,
    pub(crate) time: Real,
    pub(crate) group: Group,
}

impl FrameSeries {
    /// Opens the index `path` and counts its `/frames`.
    pub(crate) fn open(path: &Path) -> Result<Self, IoError> {
        let file = File::open(path)
            .map_err(|e| IoError::invalid(path, format!("cannot open as HDF5 frames: {e}")))?;
        let count = file
            .group("frames")
            .and_then(|g| g.member_names())
            .map_err(|e| {
                let why = "not a frame index (a coupled run's frames.h5 only links its \
                           grid_frames.h5 and particles_frames.h5)";
                IoError::invalid(path, format!("no /frames group, {why}: {e}"))
            })?
            .len();
        Ok(Self {
            path: path.to_path_buf(),
            file,
            count,
        })
    }

    /// The root attribute `format` (`"eddy-grid-frames"` for grid frames), if the file has one.
    pub(crate) fn format(&self) -> Option<String> {
        let attr = self.file.attr("format").ok()?;
        let value = attr.read_scalar::<hdf5::types::VarLenUnicode>().ok()?;
        Some(value.as_str().to_owned())
    }

    /// The frame `choice` picks, with its time.
    pub(crate) fn pick(&self, choice: FrameChoice) -> Result<StoredFrame, IoError> {
        let k = match choice {
            FrameChoice::Last if self.count > 0 => self.count - 1,
            FrameChoice::Index(k) if k < self.count => k,
            FrameChoice::Time(t) if self.count > 0 && t.is_finite() => {
                let times = (0..self.count)
                    .map(|k| self.frame(k).map(|f| f.time))
                    .collect::<Result<Vec<_>, _>>()?;
                let gap = |k: usize| (times[k] - t).abs();
                (1..self.count).fold(0, |best, k| if gap(k) < gap(best) { k } else { best })
            }
            _ => {
                let asked = match choice {
                    FrameChoice::Last => "last".to_owned(),
                    FrameChoice::Index(k) => k.to_string(),
                    FrameChoice::Time(t) => format!("nearest t = {t} s"),
                };
                return Err(IoError::invalid(
                    &self.path,
                    format!(
                        "frame {asked} asked for, the file has {} frame(s)",
                        self.count
                    ),
                ));
            }
        };
        self.frame(k)
    }

    /// Frame `k` (< the count) and its time.
    fn frame(&self, k: usize) -> Result<StoredFrame, IoError> {
        let fail = |what: String| IoError::invalid(&self.path, format!("frame {k}: {what}"));
        let group = self
            .file
            .group(&format!("frames/{k:06}"))
            .map_err(|e| fail(e.to_string()))?;
        let time = group
            .attr("time")
            .and_then(|a| a.read_scalar::<f64>())
            .map_err(|e| fail(format!("attribute `time`: {e}")))?;
        Ok(StoredFrame {
            index: k,
            time,
            group,
        })
    }
}
