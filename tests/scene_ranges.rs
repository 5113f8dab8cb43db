//! The table of allowed ranges (`eddy::scene::ranges::RANGES`) and the scene schema agree: every
//! entry names a key of the schema, and every key the validation checks has an entry (a check
//! of a key without one panics, so validating every shipped scene finds it).

use eddy::scene::{load, ranges::RANGES, reference};
use std::path::Path;

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

#[test]
fn every_key_the_shipped_scenes_check_has_a_range() {
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut checked = 0;
    for entry in std::fs::read_dir(scenes).expect("scenes/") {
        let path = entry.expect("entry").path();
        if path.extension().is_some_and(|e| e == "toml") {
            // A scene whose database is not built stops at that check; the others run them all.
            let _ = load(&path, &[]);
            checked += 1;
        }
    }
    assert!(checked > 20, "{checked} scenes");
}
