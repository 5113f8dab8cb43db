//! Reading a scene: TOML syntax, `--set` overrides, the schema, mesh paths, then validation, each
//! step with errors that point at the file, line and key.

use std::path::{Path, PathBuf};

use toml::de::DeValue;
use toml::{Spanned, Table, Value};

use super::overrides::{apply_override, blame_override};
use super::{Body, Scene, SceneError, Shape};

/// Reads, overrides, checks and validates the scene file at `path`.
///
/// `overrides` are `dotted.key=value` assignments as given to `eddy run --set`, applied in order.
/// Relative mesh paths come back absolute, resolved against the scene file's folder.
pub fn load(path: &Path, overrides: &[String]) -> Result<Scene, SceneError> {
    let bytes = std::fs::read(path).map_err(|cause| SceneError::Io {
        file: path.to_owned(),
        cause,
    })?;
    let text = String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let valid = std::str::from_utf8(&e.as_bytes()[..at]).unwrap_or_default();
        let (line, column) = line_col(valid, at);
        SceneError::Syntax {
            file: path.to_owned(),
            line,
            column,
            message: format!("the file is not UTF-8 text (byte offset {at})"),
        }
    })?;
    parse_str(&text, path, overrides)
}

/// Like [`load`] for a scene already in memory; `origin` is the file name used in messages and
/// the base of relative mesh paths (it need not exist).
pub fn parse_str(text: &str, origin: &Path, overrides: &[String]) -> Result<Scene, SceneError> {
    // Parse to a plain table first so a syntax error is told apart from a schema error.
    let mut table: Table = toml::from_str(text).map_err(|e| syntax_error(origin, text, &e))?;
    let mut scene = if overrides.is_empty() {
        // Deserialize the user's own text so schema errors carry its line numbers.
        deserialize(text, origin, true)?
    } else {
        for assignment in overrides {
            apply_override(&mut table, assignment)?;
        }
        let rendered = toml::to_string(&table).map_err(|e| SceneError::Override {
            arg: overrides.join(" "),
            reason: format!("the overridden scene cannot be written as TOML: {e}"),
        })?;
        // Line numbers in the rendered text would mean nothing to the user: keep only the key.
        deserialize(&rendered, origin, false).map_err(|e| blame_override(e, overrides))?
    };
    check_array_lengths(&table, &scene, origin).map_err(|e| blame_override(e, overrides))?;
    resolve_paths(&mut scene, origin);
    scene
        .validate(origin)
        .map_err(|e| blame_override(e, overrides))?;
    Ok(scene)
}

/// Fixed-length arrays (a position, a velocity, a resolution) take exactly their length: serde
/// reads the first three values of a longer array and drops the rest, so every array of the
/// document is compared with the same array of the scene written back.
fn check_array_lengths(document: &Table, scene: &Scene, file: &Path) -> Result<(), SceneError> {
    let Ok(toml::Value::Table(written)) = toml::Value::try_from(scene) else {
        // A scene TOML cannot hold (a seed above i64::MAX) has no written form to compare.
        return Ok(());
    };
    let mut found = None;
    compare_arrays(document, &written, "", &mut found);
    match found {
        None => Ok(()),
        Some((key, given, kept)) => Err(SceneError::Invalid {
            file: file.to_owned(),
            key,
            value: format!("{given} values"),
            allowed: format!("exactly {kept}"),
            set_by: None,
        }),
    }
}

/// Records in `found` the first array of `given` that `kept` holds fewer values of:
/// (dotted key, values given, values kept).
fn compare_arrays(
    given: &Table,
    kept: &Table,
    prefix: &str,
    found: &mut Option<(String, usize, usize)>,
) {
    for (key, value) in given {
        let path = if prefix.is_empty() {
            key.clone()
        } else {
            format!("{prefix}.{key}")
        };
        match (value, kept.get(key)) {
            (Value::Table(g), Some(Value::Table(k))) => compare_arrays(g, k, &path, found),
            (Value::Array(g), Some(Value::Array(k))) => {
                if g.len() > k.len() && found.is_none() {
                    *found = Some((path.clone(), g.len(), k.len()));
                }
                for (i, (g, k)) in g.iter().zip(k).enumerate() {
                    if let (Value::Table(g), Value::Table(k)) = (g, k) {
                        compare_arrays(g, k, &format!("{path}[{i}]"), found);
                    }
                }
            }
            _ => {}
        }
    }
}

impl Scene {
    /// The resolved scene (defaults filled in, mesh paths absolute) as TOML, written next to a
    /// run's outputs so the run can be repeated exactly. [`parse_str`] reads it back equal.
    ///
    /// Falls back to a TOML comment naming the problem in the one case the scene cannot be
    /// written (a `seed` above `i64::MAX` or a non-UTF-8 path); see [`Scene::try_to_toml`].
    pub fn to_toml(&self) -> String {
        self.try_to_toml()
            .unwrap_or_else(|e| format!("# the resolved scene could not be written: {e}\n"))
    }

    /// [`Scene::to_toml`], with the serializer's error for a scene TOML cannot hold.
    pub fn try_to_toml(&self) -> Result<String, toml::ser::Error> {
        toml::to_string(self)
    }
}

/// The syntax error of `toml` with a 1-based line and column.
fn syntax_error(file: &Path, text: &str, error: &toml::de::Error) -> SceneError {
    let offset = error.span().map_or(text.len(), |span| span.start);
    let (line, column) = line_col(text, offset);
    let mut message = error.message().to_owned();
    if message == "duplicate key" {
        // toml points at the second occurrence: name the key written there.
        let rest = &text[offset.min(text.len())..];
        let key = rest.split(['=', '\n']).next().unwrap_or("").trim();
        if !key.is_empty() {
            message = format!("duplicate key `{key}`");
        }
    }
    SceneError::Syntax {
        file: file.to_owned(),
        line,
        column,
        message,
    }
}

/// Deserializes a (syntactically valid) document into a [`Scene`]; `located` says whether
/// `text` is the user's file, so that its line numbers are worth reporting.
fn deserialize(text: &str, file: &Path, located: bool) -> Result<Scene, SceneError> {
    toml::from_str::<Scene>(text).map_err(|error| {
        let (message, key, offset) = match (probe_error(text), error.span()) {
            // A `[[probes]]` entry is a table tagged by `type`: serde buffers it and its errors
            // carry the span of the whole array, so each entry is read again on its own.
            (Some((message, key, offset)), _) => (message, key, offset),
            (None, Some(span)) if !span.is_empty() => {
                let (key, offset) = locate(text, span, error.message());
                (error.message().to_owned(), key, offset)
            }
            // serde reports a missing top-level key with an empty span.
            _ => (error.message().to_owned(), String::new(), None),
        };
        let message = key_wording(&message);
        SceneError::Schema {
            file: file.to_owned(),
            key,
            // u32 keeps the error small (it travels inside every run error); a file of four
            // billion lines would be refused long before.
            location: offset.filter(|_| located).map(|o| {
                let (line, column) = line_col(text, o);
                let narrow = |n: usize| u32::try_from(n).unwrap_or(u32::MAX);
                (narrow(line), narrow(column))
            }),
            message,
            set_by: None,
        }
    })
}

/// The first `[[probes]]` entry that does not read as a probe: the error's message, its key
/// (`probes[k]`, or `probes[k].KEY` when the message names an unknown key or `type`) and the
/// offset of that key, else of the entry's first key.
fn probe_error(text: &str) -> Option<(String, String, Option<usize>)> {
    use serde::Deserialize;
    let document: Table = toml::from_str(text).ok()?;
    let probes = document.get("probes")?.as_array()?;
    let (k, error) = probes
        .iter()
        .enumerate()
        .find_map(|(k, p)| super::Probe::deserialize(p.clone()).err().map(|e| (k, e)))?;
    let message = error.message().to_owned();
    let root = toml::de::DeTable::parse(text).ok()?.into_inner();
    let entry = root.iter().find(|(key, _)| key.get_ref() == "probes")?.1;
    let DeValue::Array(entries) = entry.get_ref() else {
        return None;
    };
    let DeValue::Table(table) = entries.get(k)?.get_ref() else {
        return None;
    };
    let named = quoted_name(&message, "unknown field ");
    let variant = quoted_name(&message, "unknown variant ");
    let child = table.iter().find(|(key, v)| {
        named == Some(key.get_ref().as_ref())
            || (variant.is_some() && v.get_ref().as_str() == variant)
    });
    let first = table.iter().map(|(key, _)| key.span().start).min();
    Some(match child {
        Some((key, _)) => (
            message,
            format!("probes[{k}].{}", key.get_ref()),
            Some(key.span().start),
        ),
        None => (message, format!("probes[{k}]"), first),
    })
}

/// serde says "field" where a TOML user says "key", and names Rust types a user never wrote.
fn key_wording(message: &str) -> String {
    if let Some((head, _)) = message.split_once("internally tagged enum") {
        return format!("{head}a table with a `type` key");
    }
    for (serde, user) in [
        ("unknown field ", "unknown key "),
        ("missing field ", "missing key "),
    ] {
        if let Some(rest) = message.strip_prefix(serde) {
            return format!("{user}{rest}");
        }
    }
    message.to_owned()
}

/// 1-based line and column (in characters) of a byte offset.
fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text.as_bytes()[..offset.min(text.len())];
    let line_start = before
        .iter()
        .rposition(|&b| b == b'\n')
        .map_or(0, |nl| nl + 1);
    let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
    let tail = &before[line_start..];
    let column = std::str::from_utf8(tail).map_or(tail.len(), |s| s.chars().count()) + 1;
    (line, column)
}

/// One step of a key path.
#[derive(Clone)]
enum Segment {
    Key(String),
    Index(usize),
}

/// Renders a key path as `fluid.blocks[0].max`, quoting keys that are not bare TOML keys.
fn render_path(path: &[Segment]) -> String {
    let mut out = String::new();
    for segment in path {
        match segment {
            Segment::Key(key) => {
                if !out.is_empty() {
                    out.push('.');
                }
                let bare = !key.is_empty()
                    && key
                        .chars()
                        .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
                if bare {
                    out.push_str(key);
                } else {
                    out.push_str(&format!("{key:?}"));
                }
            }
            Segment::Index(index) => out.push_str(&format!("[{index}]")),
        }
    }
    out
}

/// The best node found so far for an error span.
struct Found<'t, 'i> {
    path: Vec<Segment>,
    value: &'t DeValue<'i>,
    /// Whether the node's key or value span is the error span itself.
    exact: bool,
}

/// The dotted key an error at byte range `span` of `text` belongs to, and the offset to report.
///
/// serde errors carry only a byte span; the key is found by walking the spanned document for
/// the deepest key or value whose span is the error span, or failing that holds its start.
/// Table headers span only the header line, so the whole tree is searched rather than just the
/// containing branch, and an implicit table shares its span with the header that made it, hence
/// exact matches first. When the error names an unknown key or variant inside the table found,
/// the path is narrowed to it.
fn locate(text: &str, span: std::ops::Range<usize>, message: &str) -> (String, Option<usize>) {
    let mut offset = span.start;
    let Ok(root) = toml::de::DeTable::parse(text) else {
        return (String::new(), Some(offset));
    };
    let root = DeValue::Table(root.into_inner());
    let mut best: Option<Found> = None;
    search(&root, &span, &mut Vec::new(), &mut best);
    let Some(mut found) = best else {
        return (String::new(), Some(offset));
    };
    if let DeValue::Table(table) = found.value {
        let named = quoted_name(message, "unknown field ");
        // A tag's value: serde's enums say "variant", the refinement registry "method".
        let variant = quoted_name(message, "unknown variant ")
            .or_else(|| quoted_name(message, "unknown method "));
        let child = table.iter().find(|(k, v)| {
            named == Some(k.get_ref().as_ref())
                || (variant.is_some() && v.get_ref().as_str() == variant)
        });
        if let Some((key, _)) = child {
            found.path.push(Segment::Key(key.get_ref().to_string()));
            offset = key.span().start;
        }
    }
    (render_path(&found.path), Some(offset))
}

/// The name in backticks after `prefix` at the start of a serde message.
fn quoted_name<'m>(message: &'m str, prefix: &str) -> Option<&'m str> {
    let rest = message.strip_prefix(prefix)?.strip_prefix('`')?;
    rest.split_once('`').map(|(name, _)| name)
}

fn search<'t, 'i>(
    value: &'t DeValue<'i>,
    span: &std::ops::Range<usize>,
    path: &mut Vec<Segment>,
    best: &mut Option<Found<'t, 'i>>,
) {
    let mut visit = |segment: Segment,
                     spans: &[std::ops::Range<usize>],
                     child: &'t Spanned<DeValue<'i>>,
                     path: &mut Vec<Segment>| {
        path.push(segment);
        let exact = spans.contains(span);
        let holds = spans
            .iter()
            .any(|s| s.start <= span.start && span.start < s.end);
        // Rank by (exact, depth): an exact match beats any mere container.
        let better = best
            .as_ref()
            .is_none_or(|b| (exact, path.len()) > (b.exact, b.path.len()));
        if (exact || holds) && better {
            *best = Some(Found {
                path: path.clone(),
                value: child.get_ref(),
                exact,
            });
        }
        search(child.get_ref(), span, path, best);
        path.pop();
    };
    match value {
        DeValue::Table(table) => {
            for (key, child) in table.iter() {
                let segment = Segment::Key(key.get_ref().to_string());
                visit(segment, &[key.span(), child.span()], child, path);
            }
        }
        DeValue::Array(array) => {
            for (index, child) in array.iter().enumerate() {
                visit(Segment::Index(index), &[child.span()], child, path);
            }
        }
        _ => {}
    }
}

/// Makes relative mesh, database and stored-flow paths absolute against the scene file's
/// folder, so the run does not depend on the working directory.
fn resolve_paths(scene: &mut Scene, origin: &Path) {
    let base = base_dir(origin);
    if let Some(path) = scene.grid.as_mut().and_then(|g| g.static_flow.as_mut()) {
        if path.is_relative() {
            *path = base.join(&*path);
        }
    }
    let bodies = scene.container.iter_mut().chain(scene.obstacles.iter_mut());
    for Body { shape, abl, .. } in bodies {
        let mesh = match shape {
            Shape::Mesh { path, .. } => Some(path),
            _ => None,
        };
        for path in mesh
            .into_iter()
            .chain(abl.as_mut().map(|a| &mut a.database))
        {
            if path.is_relative() {
                *path = base.join(&*path);
            }
        }
    }
}

/// The absolute folder of the scene file (the working directory for a bare file name).
pub(super) fn base_dir(origin: &Path) -> PathBuf {
    let dir = origin.parent().unwrap_or(Path::new(""));
    if dir.as_os_str().is_empty() {
        std::env::current_dir().unwrap_or_default()
    } else {
        std::path::absolute(dir).unwrap_or_else(|_| dir.to_path_buf())
    }
}
