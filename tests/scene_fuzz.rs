//! Every shipped scene's mutants (deleted keys, numbers made non-finite, huge, zero or negative,
//! wrong types, arrays one value too long, truncations, bytes that are not UTF-8) load without a
//! panic or a hang, and the mutants that cannot be valid are refused.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;
use std::time::{Duration, Instant};

use eddy::scene::{load, parse_str};

mod common;

/// Byte ranges of the numbers in the values of `line` (after its first `=`, outside strings
/// and comments).
fn numbers(line: &str) -> Vec<(usize, usize)> {
    let Some(eq) = line.find('=') else {
        return Vec::new();
    };
    let bytes = line.as_bytes();
    let (mut out, mut i, mut quoted) = (Vec::new(), eq + 1, false);
    while i < bytes.len() {
        let c = bytes[i];
        if c == b'"' {
            quoted = !quoted;
        } else if c == b'#' && !quoted {
            break;
        } else if !quoted {
            let starts = c.is_ascii_digit()
                || (c == b'-' && bytes.get(i + 1).is_some_and(u8::is_ascii_digit));
            let after_word =
                i > 0 && (bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'_');
            if starts && !after_word {
                let mut j = i + 1;
                while j < bytes.len()
                    && (bytes[j].is_ascii_digit() || b".eE+-_".contains(&bytes[j]))
                {
                    j += 1;
                }
                out.push((i, j));
                i = j;
                continue;
            }
        }
        i += 1;
    }
    out
}

/// `text` with every `static_flow = "..."` path replaced by `flow`.
fn stand_in_flows(text: &str, flow: &Path) -> String {
    let key = "static_flow = \"";
    let mut out = String::new();
    let mut rest = text;
    while let Some(at) = rest.find(key) {
        let after = &rest[at + key.len()..];
        let end = after.find('"').unwrap_or(after.len());
        out.push_str(&rest[..at + key.len()]);
        out.push_str(&flow.display().to_string());
        rest = &after[end..];
    }
    out.push_str(rest);
    out
}

/// Loads `text`; panics (failing the test) on a panic inside, or after more than a second.
fn try_load(text: &str, what: &str) -> bool {
    let started = Instant::now();
    let result = catch_unwind(AssertUnwindSafe(|| {
        parse_str(text, Path::new("scenes/fuzz.toml"), &[])
    }));
    let elapsed = started.elapsed();
    assert!(elapsed < Duration::from_secs(1), "{what}: took {elapsed:?}");
    match result {
        Ok(r) => r.is_ok(),
        Err(_) => panic!("{what}: loading panicked"),
    }
}

#[test]
fn shipped_scene_mutants_load_without_panic_and_invalid_ones_are_refused() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .expect("scenes")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    // Boundary-layer databases are built by eddy-precompute and stored flows by an earlier run,
    // not shipped: loading a scene only checks that their files exist (the pipeline reads
    // them), so stand-ins serve.
    let databases = tempfile::tempdir().expect("temp dir");
    let stand_in = databases.path().join("stand_in.h5");
    let serial = common::hdf5_or_child();
    common::sphere_database(&stand_in, 0.5, 64, 1.0);
    drop(serial);
    for path in &files {
        let text = std::fs::read_to_string(path).expect("scene text");
        for name in text.split("database = \"db/").skip(1) {
            let name = name.split('"').next().expect("a quoted name");
            std::fs::copy(&stand_in, databases.path().join(name)).expect("copies");
        }
    }
    // A stored flow is opened by the pipeline, not by loading: an empty stand-in will do.
    std::fs::write(databases.path().join("flow.h5"), b"").expect("writes");
    let mut mutants = 0;
    for path in &files {
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        // Mesh paths resolve against the scene's folder: load the text from there.
        let text = std::fs::read_to_string(path).expect("scene text");
        let text = text
            .replace(
                "path = \"meshes/",
                &format!("path = \"{}/meshes/", dir.display()),
            )
            .replace(
                "database = \"db/",
                &format!("database = \"{}/", databases.path().display()),
            );
        let text = stand_in_flows(&text, &databases.path().join("flow.h5"));
        assert!(try_load(&text, &name), "{name} itself loads");
        let lines: Vec<&str> = text.lines().collect();
        let with_line = |k: usize, new: &str| {
            let mut l = lines.clone();
            l[k] = new;
            l.join("\n")
        };
        for (k, line) in lines.iter().enumerate() {
            if line.trim_start().starts_with('#') {
                continue;
            }
            if line.contains('=') {
                try_load(
                    &with_line(k, ""),
                    &format!("{name}: line {} deleted", k + 1),
                );
                mutants += 1;
            }
            for (a, b) in numbers(line) {
                let replaced = |v: &str| format!("{}{v}{}", &line[..a], &line[b..]);
                for bad in ["nan", "inf", "-inf", "\"text\"", "{ x = 1 }"] {
                    let what = format!("{name}: line {}: {} -> {bad}", k + 1, &line[a..b]);
                    assert!(
                        !try_load(&with_line(k, &replaced(bad)), &what),
                        "{what} was accepted"
                    );
                    mutants += 1;
                }
                for odd in [
                    "1e308",
                    "-1e308",
                    "0",
                    "-1",
                    "1e-308",
                    "18446744073709551616",
                ] {
                    let what = format!("{name}: line {}: {} -> {odd}", k + 1, &line[a..b]);
                    try_load(&with_line(k, &replaced(odd)), &what);
                    mutants += 1;
                }
            }
            // An array one value too long.
            if let Some(close) = line.find(']').filter(|_| line.contains("= [")) {
                let longer = format!("{}, 1.0{}", &line[..close], &line[close..]);
                let what = format!("{name}: line {}: array one value too long", k + 1);
                if !line[..close].trim_end().ends_with('[') {
                    assert!(
                        !try_load(&with_line(k, &longer), &what),
                        "{what} was accepted"
                    );
                    mutants += 1;
                }
            }
        }
        for cut in 1..8 {
            let at = text.len() * cut / 8;
            let at = (0..=at)
                .rev()
                .find(|&i| text.is_char_boundary(i))
                .unwrap_or(0);
            try_load(&text[..at], &format!("{name}: cut at byte {at}"));
            mutants += 1;
        }
    }
    // Bytes that are not UTF-8, through the file loader.
    let tmp = tempfile::tempdir().expect("temp dir");
    for path in &files {
        let mut bytes = std::fs::read(path).expect("scene bytes");
        bytes.insert(bytes.len() / 2, 0xff);
        let bad = tmp.path().join("bad.toml");
        std::fs::write(&bad, &bytes).expect("write");
        let result = catch_unwind(|| load(&bad, &[])).expect("no panic");
        let m = result.expect_err("not UTF-8").to_string();
        assert!(m.contains("not UTF-8"), "{m}");
        mutants += 1;
    }
    assert!(mutants > 1000, "{mutants} mutants");
}
