//! The names of the files a run writes, in one place: each output format declares its own
//! ([`RunFile`]s in its registry entry), the stages' series are [`STAGE_FILES`], and
//! [`is_run_output`] is their union, so clearing an earlier run's files can never miss one a
//! format writes nor touch one it does not.

use std::path::Path;

use crate::io::IoError;

/// Which medium an output belongs to: a scene with one solver keeps the plain names
/// (`metrics.csv`, `frames.h5`); a scene with both prefixes them by medium.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    Particles,
    Grid,
}

impl Kind {
    /// The file name of an output of this kind, `base` with the kind's prefix when `both`.
    pub fn file(self, base: &str, both: bool) -> String {
        match (both, self) {
            (false, _) => base.to_owned(),
            (true, Kind::Particles) => format!("particles_{base}"),
            (true, Kind::Grid) => format!("grid_{base}"),
        }
    }

    /// `name` without the prefix [`Kind::file`] gives it in a scene with both media.
    fn unprefixed(name: &str) -> &str {
        name.strip_prefix("particles_")
            .or_else(|| name.strip_prefix("grid_"))
            .unwrap_or(name)
    }
}

/// A name, or a family of names, of files a run writes into its folder.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RunFile {
    /// Exactly this name.
    Fixed(&'static str),
    /// This name, or with a medium's prefix ([`Kind::file`]) in a scene with both.
    PerMedium(&'static str),
    /// `STEM` followed by six digits and `EXT` (`grid_000012.vti`), the stem prefixed by a
    /// medium in a scene with both when `per_medium`.
    Numbered {
        stem: &'static str,
        ext: &'static str,
        per_medium: bool,
    },
    /// Any name that starts with the first and ends with the second (`profile_NAME.csv`).
    Named(&'static str, &'static str),
}

impl RunFile {
    /// Whether `name` is a file of this family.
    pub fn matches(&self, name: &str) -> bool {
        let six_digits = |n: Option<&str>| {
            n.is_some_and(|n| n.len() == 6 && n.bytes().all(|b| b.is_ascii_digit()))
        };
        match *self {
            RunFile::Fixed(f) => name == f,
            RunFile::PerMedium(f) => Kind::unprefixed(name) == f,
            RunFile::Numbered {
                stem,
                ext,
                per_medium,
            } => {
                let name = if per_medium {
                    Kind::unprefixed(name)
                } else {
                    name
                };
                six_digits(name.strip_prefix(stem).and_then(|r| r.strip_suffix(ext)))
            }
            RunFile::Named(prefix, suffix) => name.starts_with(prefix) && name.ends_with(suffix),
        }
    }
}

/// The resolved scene beside a run's outputs.
pub const SCENE_FILE: &str = "scene.toml";
/// The per-step rows of a solver (one per medium in a scene with both).
pub const METRICS_FILE: &str = "metrics.csv";
/// The point and force probes' rows (one per medium in a scene with both).
pub const PROBES_FILE: &str = "probes.csv";

/// The last checkpoint of a run (`eddy resume` goes on from it).
pub const CHECKPOINT_FILE: &str = "checkpoint.h5";

/// The files the stages and the driver write, beside the output formats' own.
pub const STAGE_FILES: [RunFile; 4] = [
    RunFile::Fixed(SCENE_FILE),
    RunFile::Fixed(CHECKPOINT_FILE),
    RunFile::PerMedium(METRICS_FILE),
    RunFile::PerMedium(PROBES_FILE),
];

/// Whether `name` is a file a run writes (the stages' and every registered format's, see the
/// table in docs/src/outputs.md), so that a run into a folder can clear an earlier run's files
/// and ParaView never mixes two runs.
pub fn is_run_output(name: &str) -> bool {
    STAGE_FILES.iter().any(|f| f.matches(name))
        || super::formats()
            .iter()
            .any(|format| format.files.iter().any(|f| f.matches(name)))
}

/// Removes the files of an earlier run from `out` (only names [`is_run_output`] accepts);
/// returns how many.
pub fn remove_earlier_outputs(out: &Path) -> Result<usize, IoError> {
    let io = |action, source| IoError::Io {
        path: out.to_path_buf(),
        action,
        source,
    };
    let mut removed = 0;
    for entry in std::fs::read_dir(out).map_err(|e| io("listing the output folder", e))? {
        let entry = entry.map_err(|e| io("listing the output folder", e))?;
        let is_file = entry.file_type().is_ok_and(|t| t.is_file());
        if is_file && entry.file_name().to_str().is_some_and(is_run_output) {
            std::fs::remove_file(entry.path())
                .map_err(|e| io("removing an earlier run's output", e))?;
            removed += 1;
        }
    }
    Ok(removed)
}
