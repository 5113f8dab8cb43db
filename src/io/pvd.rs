//! The ParaView series file that ties per-frame VTK files to their times.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::vtk_xml::xml_escape;
use super::{write_atomic, IoError};
use crate::Real;

/// The ParaView series file (`.pvd`, an XML `Collection` of `DataSet` entries with `timestep`
/// and `file`), rewritten atomically after each frame so a run cut short still has a valid
/// series.
///
/// File names are written as given; ParaView resolves relative names against the directory of
/// the `.pvd` file, so pass names relative to it.
#[derive(Debug, Clone)]
pub struct PvdSeries {
    path: PathBuf,
    entries: Vec<(Real, String)>,
}

impl PvdSeries {
    /// A series with no entries yet; nothing is written until the first [`push`](Self::push).
    pub fn new(path: &Path) -> Self {
        PvdSeries {
            path: path.to_path_buf(),
            entries: Vec::new(),
        }
    }

    /// Adds a frame and rewrites the whole file. A failed rewrite leaves the previous file and
    /// does not keep the entry, so the next push retries with a consistent list.
    pub fn push(&mut self, time: Real, file_name: &str) -> Result<(), IoError> {
        if !time.is_finite() {
            return Err(IoError::invalid(
                &self.path,
                format!("series time {time} is not finite"),
            ));
        }
        if file_name.is_empty() || file_name.chars().any(char::is_control) {
            return Err(IoError::invalid(
                &self.path,
                format!("series file name {file_name:?} is empty or holds control characters"),
            ));
        }
        self.entries.push((time, file_name.to_string()));
        let xml = self.to_xml();
        let result = write_atomic(&self.path, |out| out.write_all(xml.as_bytes()));
        if result.is_err() {
            self.entries.pop();
        }
        result
    }

    /// The entries listed so far: (time, file name).
    pub fn entries(&self) -> &[(Real, String)] {
        &self.entries
    }

    /// A series that goes on from `entries` (a resumed run's frames); the file is rewritten
    /// with the next push.
    pub fn resumed(path: &Path, entries: Vec<(Real, String)>) -> Self {
        PvdSeries {
            path: path.to_path_buf(),
            entries,
        }
    }

    /// The series file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Number of frames listed.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// True before the first frame.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    fn to_xml(&self) -> String {
        let mut s = String::from(
            "<?xml version=\"1.0\"?>\n\
             <VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n",
        );
        for (time, file) in &self.entries {
            // `{}` of f64 prints the shortest text that parses back to the same value.
            let _ = writeln!(
                s,
                "    <DataSet timestep=\"{time}\" group=\"\" part=\"0\" file=\"{}\"/>",
                xml_escape(file)
            );
        }
        s.push_str("  </Collection>\n</VTKFile>\n");
        s
    }
}
