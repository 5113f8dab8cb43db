//! The table of allowed ranges (`eddy::scene::ranges::RANGES`, and each refinement method's
//! `ranges`) and the validation agree. Every entry names a key of the schema. Every key the
//! validation checks in the shipped scenes has its entry: each number of each shipped scene is
//! set, one at a time, to NaN and to finite values just outside its entry's range, and every
//! refusal names a key that has an entry; a value outside a key's range is refused naming that
//! key, with the range as the allowed values.

use std::collections::BTreeMap;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};

use eddy::refine::registry;
use eddy::scene::ranges::{entry, pattern, Interval, RANGES};
use eddy::scene::{parse_str, reference, SceneError};
use toml::Value;

#[test]
fn every_range_names_a_key_of_the_schema() {
    let keys: Vec<String> = reference::rows().into_iter().map(|r| r.key).collect();
    for range in RANGES {
        let found = match range.key.strip_prefix('*') {
            Some(tail) => keys.iter().any(|k| k.ends_with(tail)),
            None => keys.iter().any(|k| *k == range.key),
        };
        assert!(
            found,
            "RANGES names `{}`, which no scene key matches",
            range.key
        );
    }
}

/// One number of a scene as its resolved form holds it (defaults filled in).
struct Leaf {
    /// The key as messages write it: `obstacles[0].shape.radius`, `domain.min[1]`.
    key: String,
    /// The `--set` path of the value, or of the list of numbers that holds it (`domain.min`):
    /// a list left at its default is not in the file, and a path cannot index into it.
    path: String,
    /// The list of numbers and the element's index, for an element of one.
    list: Option<(Vec<Value>, usize)>,
    /// An integer key (a count), which takes no NaN.
    integer: bool,
}

impl Leaf {
    /// The override that sets this number to `v`.
    fn set(&self, v: &Value) -> String {
        match &self.list {
            Some((items, i)) => {
                let mut items = items.clone();
                items[*i] = v.clone();
                format!("{}={}", self.path, Value::Array(items))
            }
            None => format!("{}={v}", self.path),
        }
    }
}

/// Every number under `value`, at `key` (messages) and `path` (overrides).
fn leaves(key: &str, path: &str, value: &Value, out: &mut Vec<Leaf>) {
    let join = |a: &str, b: &str| {
        if a.is_empty() {
            b.to_owned()
        } else {
            format!("{a}.{b}")
        }
    };
    match value {
        Value::Table(t) => {
            for (k, v) in t {
                leaves(&join(key, k), &join(path, k), v, out);
            }
        }
        Value::Array(items) => {
            for (i, item) in items.iter().enumerate() {
                match item {
                    Value::Integer(_) | Value::Float(_) => out.push(Leaf {
                        key: format!("{key}[{i}]"),
                        path: path.to_owned(),
                        list: Some((items.clone(), i)),
                        integer: item.is_integer(),
                    }),
                    _ => leaves(
                        &format!("{key}[{i}]"),
                        &join(path, &i.to_string()),
                        item,
                        out,
                    ),
                }
            }
        }
        Value::Integer(_) | Value::Float(_) => out.push(Leaf {
            key: key.to_owned(),
            path: path.to_owned(),
            list: None,
            integer: value.is_integer(),
        }),
        _ => {}
    }
}

/// What loading a scene with one number changed came to.
#[derive(Debug)]
enum Outcome {
    Accepted,
    /// A validation refusal: the key it names and the allowed values.
    Refused {
        key: String,
        allowed: String,
    },
    /// The schema's type refuses the value (a negative count, a count beyond its integer type).
    Type,
    /// The validation panicked: it checked a key without an entry, or without a range.
    Panicked(String),
    Other(String),
}

fn outcome(text: &str, file: &Path, overrides: &[String]) -> Outcome {
    let loaded = catch_unwind(AssertUnwindSafe(|| parse_str(text, file, overrides)));
    match loaded {
        Ok(Ok(_)) => Outcome::Accepted,
        Ok(Err(SceneError::Invalid { key, allowed, .. })) => Outcome::Refused { key, allowed },
        Ok(Err(SceneError::Schema { .. })) => Outcome::Type,
        Ok(Err(e)) => Outcome::Other(e.to_string()),
        Err(panic) => Outcome::Panicked(
            panic
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default(),
        ),
    }
}

/// The fixed range of a key: its `RANGES` entry's, or its refinement method's for
/// `refinement.KEY`.
fn fixed_range(key: &str, method: &str) -> Option<Interval<'static>> {
    let pattern = pattern(key);
    match pattern.strip_prefix("refinement.") {
        Some(name) => {
            let ranges = registry::find(method)?.ranges;
            ranges.iter().find(|(k, _)| *k == name).map(|(_, r)| *r)
        }
        None => entry(&pattern)?.range,
    }
}

/// Whether the table has an entry for a key the validation named.
fn has_entry(key: &str, method: &str) -> bool {
    let pattern = pattern(key);
    match pattern.strip_prefix("refinement.") {
        Some(name) => {
            registry::find(method).is_some_and(|m| m.ranges.iter().any(|(k, _)| *k == name))
        }
        None => entry(&pattern).is_some(),
    }
}

/// Values tried just outside a range: each one of these that the range refuses and whose
/// neighbour in the list it allows (so a value across each of its ends).
const LADDER: [f64; 29] = [
    -1e12, -1e3, -1.0, -0.5, 0.0, 0.05, 0.5, 0.99, 1.0, 1.5, 2.0, 2.5, 3.0, 4.0, 8.0, 9.0, 10.0,
    100.0, 101.0, 981.0, 982.0, 1000.0, 1001.0, 4096.0, 4097.0, 1e5, 100_001.0, 1e6, 1e12,
];

/// The values of [`LADDER`] across the ends of `range`; whole ones for a count.
fn outside(range: &Interval, integer: bool) -> Vec<f64> {
    let contains = |v: f64| range.contains(v);
    let ladder: Vec<f64> = LADDER
        .into_iter()
        .filter(|v| !integer || v.fract() == 0.0)
        .collect();
    let mut out = Vec::new();
    for (i, &v) in ladder.iter().enumerate() {
        let inside_next =
            |j: Option<usize>| j.and_then(|j| ladder.get(j)).is_some_and(|&w| contains(w));
        if !contains(v) && (inside_next(i.checked_sub(1)) || inside_next(Some(i + 1))) {
            out.push(v);
        }
    }
    out
}

/// A shipped scene's text with the overrides that let every check run here: a precomputed
/// database or stored flow that is not built is replaced by an existing file (the validation
/// asks only that the file exists; it is read when the run is built).
fn loadable(file: &Path, text: &str, extra: &[String]) -> Vec<String> {
    let mut overrides: Vec<String> = extra.to_vec();
    for _ in 0..16 {
        match outcome(text, file, &overrides) {
            Outcome::Refused { key, .. }
                if key.ends_with(".abl.database") || key == "grid.static_flow" =>
            {
                let path = key.replace('[', ".").replace(']', "");
                overrides.push(format!("{path}={:?}", file.display().to_string()));
            }
            Outcome::Accepted => return overrides,
            other => panic!("{}: {other:?}", file.display()),
        }
    }
    panic!("{}: too many files to replace", file.display())
}

/// Every key the validation checks in the shipped scenes (`scenes/*.toml`, and the refinement
/// dam break under each refinement method: the shipped scenes leave `method = "none"`) has its
/// entry in the range table, and the table's ranges are the ones enforced:
///
/// - each number of each scene (as resolved, defaults included) is set in turn to NaN (a
///   float) or 0, -1 and 2^40 (a count), and to the values just across each end of its
///   entry's range (from a ladder of candidates); the scene is loaded with that one change;
/// - no load panics (a check of a key without an entry, or of one without a range, panics),
///   and every refusal names a key with an entry: the checked keys, collected;
/// - a value outside a key's fixed range is refused naming that very key, with the range in
///   words as the allowed values (or, a count beyond its integer type, by the schema); so
///   NaN is refused for every float key with a range, and every key with a range is refused
///   at least once.
#[test]
fn every_key_the_shipped_scenes_check_has_a_range() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("scenes/")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    let mut runs: Vec<(PathBuf, Vec<String>, &str)> = Vec::new();
    for file in &files {
        runs.push((file.clone(), Vec::new(), "none"));
    }
    let refine_scene = dir.join("refine_dam_break.toml");
    for m in registry::methods() {
        runs.push((
            refine_scene.clone(),
            vec![format!("refinement.method={:?}", m.name)],
            m.name,
        ));
    }
    let mut checked: BTreeMap<String, String> = BTreeMap::new();
    let mut ranged_refusals = 0;
    let mut problems: Vec<String> = Vec::new();
    let mut loads = 0;
    // Numbers no value tried was refused for (said, not asserted: a key without a check needs
    // no entry).
    let mut unchecked: BTreeMap<String, String> = BTreeMap::new();
    for (file, extra, method) in &runs {
        let text = std::fs::read_to_string(file).expect("scene file");
        let base = loadable(file, &text, extra);
        let scene = parse_str(&text, file, &base).expect("loads");
        let resolved: Value = toml::from_str(&scene.to_toml()).expect("resolved scene");
        let mut numbers = Vec::new();
        leaves("", "", &resolved, &mut numbers);
        let name = file.file_name().unwrap().to_string_lossy().into_owned();
        let name = format!("{name} {extra:?}");
        for leaf in &numbers {
            let range = fixed_range(&leaf.key, method);
            let mut tries: Vec<Value> = if leaf.integer {
                vec![
                    Value::Integer(0),
                    Value::Integer(-1),
                    Value::Integer(1 << 40),
                ]
            } else {
                vec![Value::Float(f64::NAN)]
            };
            let across = range
                .as_ref()
                .map_or(Vec::new(), |r| outside(r, leaf.integer));
            tries.extend(across.iter().map(|&v| {
                if leaf.integer {
                    Value::Integer(v as i64)
                } else {
                    Value::Float(v)
                }
            }));
            // Refusals of this number naming it, of values outside its range; and of any value.
            let (mut refused_here, mut refused_any) = (0, false);
            for v in &tries {
                let mut overrides = base.clone();
                overrides.push(leaf.set(v));
                loads += 1;
                let got = outcome(&text, file, &overrides);
                let at = format!("{name}: `{}` = {v}", leaf.key);
                match &got {
                    Outcome::Panicked(m) => problems.push(format!("{at}: panicked: {m}")),
                    Outcome::Other(m) => problems.push(format!("{at}: {m}")),
                    Outcome::Refused { key, .. } => {
                        refused_any = true;
                        if has_entry(key, method) {
                            checked.entry(pattern(key)).or_insert_with(|| at.clone());
                        } else {
                            problems
                                .push(format!("{at}: refused naming `{key}`, which has no entry"));
                        }
                    }
                    Outcome::Accepted | Outcome::Type => {}
                }
                // Every range holds finite numbers only: NaN is outside each.
                let number = v
                    .as_float()
                    .unwrap_or_else(|| v.as_integer().unwrap_or(0) as f64);
                let Some(words) = range
                    .filter(|r| !(number.is_finite() && r.contains(number)))
                    .map(|r| r.describe(false))
                else {
                    continue;
                };
                match &got {
                    Outcome::Refused { key, allowed, .. } if *key == leaf.key => {
                        if !allowed.contains(words.as_str()) {
                            problems.push(format!(
                                "{at}: refused with allowed `{allowed}`, not the range `{words}`"
                            ));
                        }
                        ranged_refusals += 1;
                        refused_here += 1;
                    }
                    Outcome::Type if leaf.integer => {}
                    other => {
                        problems.push(format!("{at}: outside the range `{words}`, and {other:?}"))
                    }
                }
            }
            if !refused_any {
                unchecked
                    .entry(pattern(&leaf.key))
                    .or_insert_with(|| name.clone());
            }
            if range.is_some() && refused_here == 0 {
                problems.push(format!(
                    "{name}: `{}` has a range, and no value outside it was refused naming it",
                    leaf.key
                ));
            }
        }
    }
    eprintln!(
        "{} scene runs, {loads} loads, {} keys checked, {ranged_refusals} refusals of values \
         outside a range",
        runs.len(),
        checked.len()
    );
    for (key, at) in &checked {
        eprintln!("  {key:<45} {at}");
    }
    eprintln!("numbers no check refused:");
    for (key, at) in &unchecked {
        eprintln!("  {key:<45} {at}");
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
    assert!(files.len() > 30, "{} scenes", files.len());
    // The refinement keys are among the checked ones: each method's numbers were reached.
    for m in registry::methods() {
        for (k, _) in m.ranges {
            assert!(
                checked.contains_key(&format!("refinement.{k}")),
                "refinement.{k} of \"{}\" never checked",
                m.name
            );
        }
    }
    assert!(checked.len() > 60, "{} keys checked", checked.len());
}
