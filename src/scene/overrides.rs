//! `--set dotted.key=value` overrides. They edit the parsed TOML before it meets the schema, so an
//! overridden key is checked exactly as if it had been written in the file (an unknown key is an
//! unknown-key error, a wrong type a type error).

use toml::{Table, Value};

use super::SceneError;

/// Applies one `dotted.key=value` assignment to the TOML document `root`.
///
/// The value is read as a TOML value (`1.5`, `[0, 1, 2]`, `"text"`, `true`,
/// `{ type = "sphere", radius = 0.1 }`); anything else is taken as a bare string, so
/// `pressure.solver=iisph` needs no quotes. A value that starts like an array, inline table or
/// quoted string but does not parse is an error rather than a string, since it was surely meant
/// as TOML. Numeric segments index arrays (`fluid.blocks.0.max`); missing tables on the way are
/// created, while an index past the end of an array is an error.
pub fn apply_override(root: &mut Table, assignment: &str) -> Result<(), SceneError> {
    let fail = |reason: String| SceneError::Override {
        arg: assignment.to_owned(),
        reason,
    };
    let Some((key, raw)) = assignment.split_once('=') else {
        return Err(fail("expected `dotted.key=value`".to_owned()));
    };
    let key = key.trim();
    if key.is_empty() {
        return Err(fail("the key before `=` is empty".to_owned()));
    }
    let segments: Vec<&str> = key.split('.').map(str::trim).collect();
    if segments.iter().any(|s| s.is_empty()) {
        return Err(fail(format!("the key `{key}` has an empty segment")));
    }
    let value = parse_value(raw).map_err(fail)?;

    // Walk a `Value` rather than the `Table` so tables and arrays are handled alike.
    let mut doc = Value::Table(std::mem::take(root));
    let result = set_path(&mut doc, &segments, value);
    if let Value::Table(table) = doc {
        *root = table;
    }
    result.map_err(fail)
}

/// Tells an error about a key that an override wrote against that override (`--set
/// "time.ennd=3" on scene.toml: ...`): the file does not hold the key. Errors about keys no
/// override wrote (the key itself or a table holding it) are returned as they are. Of several
/// overrides of a key, the last (the one that stands) is named.
pub fn blame_override(mut error: SceneError, overrides: &[String]) -> SceneError {
    let (key, set_by) = match &mut error {
        SceneError::Schema { key, set_by, .. }
        | SceneError::Invalid { key, set_by, .. }
        | SceneError::MissingMesh { key, set_by, .. } => (key, set_by),
        _ => return error,
    };
    // `obstacles[0].abl` in messages is `obstacles.0.abl` in an override.
    let dotted = key.replace('[', ".").replace(']', "");
    let within = |outer: &str| {
        dotted == outer
            || dotted
                .strip_prefix(outer)
                .is_some_and(|r| r.starts_with('.'))
    };
    *set_by = overrides
        .iter()
        .rev()
        .find(|arg| arg.split_once('=').is_some_and(|(k, _)| within(k.trim())))
        .map(|arg| arg.as_str().into());
    error
}

/// Reads the right-hand side of an assignment.
fn parse_value(raw: &str) -> Result<Value, String> {
    let text = raw.trim();
    match text.parse::<Value>() {
        Ok(value) => Ok(value),
        Err(e) if text.starts_with(['[', '{', '"', '\'']) => Err(format!(
            "`{text}` is not a valid TOML value: {}",
            e.message()
        )),
        Err(_) => Ok(Value::String(text.to_owned())),
    }
}

/// Whether a path segment is an array index.
fn is_index(segment: &str) -> bool {
    segment.bytes().all(|b| b.is_ascii_digit())
}

/// Stores `value` at `segments` below `doc`, creating missing tables on the way.
fn set_path(doc: &mut Value, segments: &[&str], value: Value) -> Result<(), String> {
    let mut value = Some(value);
    let mut cur = doc;
    for (i, &segment) in segments.iter().enumerate() {
        let here = segments[..i].join(".");
        let is_last = i + 1 == segments.len();
        cur = match cur {
            Value::Table(table) => {
                if is_last {
                    if let Some(value) = value.take() {
                        table.insert(segment.to_owned(), value);
                    }
                    return Ok(());
                }
                if !table.contains_key(segment) {
                    let next = segments[i + 1];
                    if is_index(next) {
                        let path = segments[..=i].join(".");
                        return Err(format!(
                            "index {next} is past the end of `{path}`, which is not in the scene \
                             (length 0)"
                        ));
                    }
                    table.insert(segment.to_owned(), Value::Table(Table::new()));
                }
                table
                    .get_mut(segment)
                    .ok_or_else(|| format!("`{segment}` vanished from `{here}`"))?
            }
            Value::Array(array) => {
                let len = array.len();
                let index: usize = segment
                    .parse()
                    .map_err(|_| format!("`{here}` is an array; `{segment}` is not an index"))?;
                let Some(slot) = array.get_mut(index) else {
                    return Err(format!(
                        "index {index} is past the end of `{here}`, which has length {len}"
                    ));
                };
                if is_last {
                    if let Some(value) = value.take() {
                        *slot = value;
                    }
                    return Ok(());
                }
                slot
            }
            other => {
                return Err(format!(
                    "`{here}` is a {}, not a table or an array",
                    other.type_str()
                ));
            }
        };
    }
    Ok(())
}
