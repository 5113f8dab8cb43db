//! Checkpoint files: a run's [`State`] in one HDF5 file that h5py opens. Every entry is a
//! dataset at its path (its sections are groups); the root attributes say what the file is
//! (`format` = [`CHECKPOINT_FORMAT`], `format_version`), which eddy wrote it and whatever the
//! caller adds (the scene it continues, the time). The file is written under a temporary name
//! and renamed, so a kill during the write leaves the previous checkpoint whole.

use std::path::Path;

use hdf5::types::{FloatSize, IntSize, TypeDescriptor, VarLenUnicode};
use hdf5::{File, Group};

use super::hdf5_frames::{ctx, replace_file, write_root_attributes, Failure};
use super::{AttrValue, IoError};
use crate::state::{State, Values};

/// The root attribute `format` of a checkpoint.
pub const CHECKPOINT_FORMAT: &str = "eddy-checkpoint";
/// The layout's version: a reader refuses any other.
pub const CHECKPOINT_VERSION: i64 = 1;

/// Writes `state` with the root attributes `attributes` (beside `format`, `format_version` and
/// `eddy_version`) as the checkpoint `path`, replacing it whole.
pub fn write_checkpoint(
    path: &Path,
    attributes: &[(&str, AttrValue)],
    state: &State,
) -> Result<(), IoError> {
    let mut attrs: Vec<(String, AttrValue)> = vec![
        ("format".into(), CHECKPOINT_FORMAT.into()),
        ("format_version".into(), AttrValue::Int(CHECKPOINT_VERSION)),
        (
            "eddy_version".into(),
            AttrValue::Str(env!("CARGO_PKG_VERSION").into()),
        ),
    ];
    attrs.extend(attributes.iter().map(|(n, v)| (n.to_string(), v.clone())));
    replace_file(path, |file| {
        write_root_attributes(file, &attrs)?;
        for (name, values) in state.entries() {
            let (group, leaf) = group_of(file, name)?;
            write_values(&group, leaf, values)?;
        }
        Ok(())
    })
}

/// The group that holds the entry `path` (created on the way) and the entry's own name.
fn group_of<'a>(root: &Group, path: &'a str) -> Result<(Group, &'a str), Failure> {
    let (dirs, leaf) = path.rsplit_once('/').unwrap_or(("", path));
    let mut group = root.clone();
    for part in dirs.split('/').filter(|p| !p.is_empty()) {
        group = match group.group(part) {
            Ok(g) => g,
            Err(_) => ctx(group.create_group(part), || {
                format!("creating group {part:?}")
            })?,
        };
    }
    Ok((group, leaf))
}

fn write_values(group: &Group, name: &str, values: &Values) -> Result<(), Failure> {
    let what = || format!("writing dataset {name:?}");
    macro_rules! put {
        ($t:ty, $v:expr) => {{
            let ds = ctx(group.new_dataset::<$t>().shape($v.len()).create(name), what)?;
            if !$v.is_empty() {
                ctx(ds.as_writer().write_raw($v), what)?;
            }
        }};
    }
    match values {
        Values::F64(v) => put!(f64, v),
        Values::U64(v) => put!(u64, v),
        Values::I64(v) => put!(i64, v),
        Values::U8(v) => put!(u8, v),
    }
    Ok(())
}

/// A checkpoint read back: its root attributes' strings and numbers, and the state.
#[derive(Debug, Clone)]
pub struct StoredCheckpoint {
    pub state: State,
    attrs: Vec<(String, AttrValue)>,
}

impl StoredCheckpoint {
    /// The root attribute `name` as a string.
    pub fn text(&self, name: &str) -> Option<&str> {
        self.attrs.iter().find_map(|(n, v)| match v {
            AttrValue::Str(s) if n == name => Some(s.as_str()),
            _ => None,
        })
    }

    /// The root attribute `name` as a number.
    pub fn number(&self, name: &str) -> Option<f64> {
        self.attrs.iter().find_map(|(n, v)| match v {
            AttrValue::Real(x) if n == name => Some(*x),
            AttrValue::Int(i) if n == name => Some(*i as f64),
            _ => None,
        })
    }
}

/// Reads the checkpoint `path`: an error says when it is no HDF5 file (a truncated one is
/// not), not a checkpoint, or of another layout version.
pub fn read_checkpoint(path: &Path) -> Result<StoredCheckpoint, IoError> {
    let file = File::open(path).map_err(|e| {
        IoError::invalid(
            path,
            format!("cannot open as a checkpoint (truncated, or not an HDF5 file): {e}"),
        )
    })?;
    let invalid = |reason: String| IoError::invalid(path, reason);
    let mut attrs = Vec::new();
    for name in file.attr_names().map_err(|e| invalid(e.to_string()))? {
        let attr = file.attr(&name).map_err(|e| invalid(e.to_string()))?;
        // By the stored type: HDF5 would convert a float to an integer when asked.
        let kind = attr.dtype().and_then(|t| t.to_descriptor());
        let value = match kind {
            Ok(TypeDescriptor::VarLenUnicode) => attr
                .read_scalar::<VarLenUnicode>()
                .map(|s| AttrValue::Str(s.as_str().to_owned())),
            Ok(TypeDescriptor::Integer(_)) => attr.read_scalar::<i64>().map(AttrValue::Int),
            Ok(TypeDescriptor::Float(_)) => attr.read_scalar::<f64>().map(AttrValue::Real),
            _ => continue,
        }
        .map_err(|e| invalid(format!("root attribute {name:?}: {e}")))?;
        attrs.push((name, value));
    }
    let stored = StoredCheckpoint {
        state: State::new(),
        attrs,
    };
    if stored.text("format") != Some(CHECKPOINT_FORMAT) {
        return Err(invalid(format!(
            "not an eddy checkpoint (its root attribute format is {:?}, expected {CHECKPOINT_FORMAT:?})",
            stored.text("format").unwrap_or("missing")
        )));
    }
    let version = stored.number("format_version");
    if version != Some(CHECKPOINT_VERSION as f64) {
        return Err(invalid(format!(
            "a checkpoint of layout version {}, written by eddy {}; this eddy reads version \
             {CHECKPOINT_VERSION} only",
            version.map_or("(none)".into(), |v| v.to_string()),
            stored.text("eddy_version").unwrap_or("(unknown)"),
        )));
    }
    let mut state = State::new();
    read_group(&file, "", &mut state).map_err(|(action, message)| IoError::Hdf5 {
        path: path.to_path_buf(),
        action,
        message,
    })?;
    Ok(StoredCheckpoint { state, ..stored })
}

fn read_group(group: &Group, prefix: &str, state: &mut State) -> Result<(), Failure> {
    let names = ctx(group.member_names(), || format!("listing {prefix:?}"))?;
    for name in names {
        let path = if prefix.is_empty() {
            name.clone()
        } else {
            format!("{prefix}/{name}")
        };
        if let Ok(sub) = group.group(&name) {
            read_group(&sub, &path, state)?;
            continue;
        }
        let what = || format!("reading dataset {path:?}");
        let ds = ctx(group.dataset(&name), what)?;
        let kind = ctx(ds.dtype().and_then(|t| t.to_descriptor()), what)?;
        let values = match kind {
            TypeDescriptor::Float(FloatSize::U8) => Values::F64(ctx(ds.read_raw(), what)?),
            TypeDescriptor::Unsigned(IntSize::U8) => Values::U64(ctx(ds.read_raw(), what)?),
            TypeDescriptor::Integer(IntSize::U8) => Values::I64(ctx(ds.read_raw(), what)?),
            TypeDescriptor::Unsigned(IntSize::U1) => Values::U8(ctx(ds.read_raw(), what)?),
            other => return Err((what(), format!("unexpected element type {other:?}"))),
        };
        state.insert(path, values);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Vec3;

    fn sample() -> State {
        let mut state = State::new();
        let mut s = state.section("sph");
        s.vec3s("x", &[Vec3::new(1.0, 2.0, 3.0)]);
        s.u64("step", 12);
        s.section("open").i64s("phase", &[-1, 2]);
        s.flag("on", true);
        s.reals("empty", &[]);
        state
    }

    #[test]
    fn a_checkpoint_reads_back_as_written() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("checkpoint.h5");
        let state = sample();
        write_checkpoint(&path, &[("scene", "name = 'x'".into())], &state).unwrap();
        let back = read_checkpoint(&path).unwrap();
        assert_eq!(back.state, state);
        assert_eq!(back.text("scene"), Some("name = 'x'"));
        assert_eq!(back.number("format_version"), Some(1.0));
        write_checkpoint(&path, &[("time", AttrValue::Real(0.15))], &state).unwrap();
        assert_eq!(read_checkpoint(&path).unwrap().number("time"), Some(0.15));
    }

    #[test]
    fn truncated_or_foreign_files_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("checkpoint.h5");
        write_checkpoint(&path, &[], &sample()).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        std::fs::write(&path, &bytes[..bytes.len() / 2]).unwrap();
        let e = read_checkpoint(&path).unwrap_err().to_string();
        assert!(e.contains("truncated"), "{e}");
        let other = dir.path().join("other.h5");
        replace_file(&other, |f| {
            write_root_attributes(f, &[("format".into(), "eddy-grid-frames".into())])
        })
        .unwrap();
        let e = read_checkpoint(&other).unwrap_err().to_string();
        assert!(e.contains("not an eddy checkpoint"), "{e}");
        replace_file(&other, |f| {
            write_root_attributes(
                f,
                &[
                    ("format".into(), CHECKPOINT_FORMAT.into()),
                    ("format_version".into(), AttrValue::Int(0)),
                ],
            )
        })
        .unwrap();
        let e = read_checkpoint(&other).unwrap_err().to_string();
        assert!(e.contains("layout version 0"), "{e}");
    }
}
