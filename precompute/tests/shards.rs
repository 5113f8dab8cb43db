//! Sharding, merging and resuming: shards run as separate processes (a job array) and merged
//! equal the unsharded database bit for bit,
//! overlaps and gaps are refused, and a killed run resumed completes the same database.

use std::path::PathBuf;
use std::process::Command;

use eddy::abl::{AblData, AblDatabase};
use eddy_precompute::{merge, parts, precompute};

mod common;
use common::{finished_parts, obstacle, options, serial, wait_for_parts};

const OBSTACLE: &str = r#"
name = "small sphere"
shape = { type = "sphere", radius = 0.5 }
[grid]
resolution = 16
domain = 3.0
stabilise_steps = 10
average_steps = 10
[sampling]
translation = [3, 4]
rotation = [4, 3]
"#;

#[test]
fn shards_merge_to_the_unsharded_database_and_refuse_overlaps_and_gaps() {
    let _serial = serial();
    let tmp = tempfile::tempdir().expect("temp dir");
    let (spec, _) = obstacle(tmp.path(), OBSTACLE);
    let full = tmp.path().join("full.h5");
    let s = precompute(&spec, &options(full.clone(), None, false, 2)).expect("runs");
    // Translation 1 + 4 + 1, rotation 1 + 2 * 3 + 1 distinct directions.
    assert_eq!((s.computed, s.reused), (14, 0));
    assert!(
        !parts::folder(&full).exists(),
        "parts are removed when done"
    );

    // The job-array recipe of the README: shards as independent background processes (as a
    // Slurm array runs them), then `merge`. Started before any database is open here, so no
    // child inherits an HDF5 descriptor.
    let file = tmp.path().join("sphere.toml");
    let shards: Vec<PathBuf> = (0..3)
        .map(|k| tmp.path().join(format!("shard{k}.h5")))
        .collect();
    let children: Vec<_> = shards
        .iter()
        .enumerate()
        .map(|(k, out)| {
            Command::new(env!("CARGO_BIN_EXE_eddy-precompute"))
                .arg(&file)
                .arg("--out")
                .arg(out)
                .args(["--shard", &format!("{k}/3"), "--jobs", "1"])
                .spawn()
                .expect("starts a shard")
        })
        .collect();
    for mut child in children {
        assert!(child.wait().expect("waits").success(), "a shard failed");
    }
    let merged = tmp.path().join("merged.h5");
    let status = Command::new(env!("CARGO_BIN_EXE_eddy-precompute"))
        .arg("merge")
        .args(&shards)
        .arg("--out")
        .arg(&merged)
        .status()
        .expect("runs merge");
    assert!(status.success(), "merge failed");
    let db = AblDatabase::open(&full, Some(&spec.shape)).expect("complete and ours");
    let e = AblDatabase::open(&shards[0], None).expect_err("a shard is incomplete");
    assert!(e.to_string().contains("incomplete"), "{e}");
    assert_eq!(AblData::read(&merged).expect("reads"), *db.data());

    let e = merge(&shards[..2], &tmp.path().join("gap.h5")).expect_err("a gap");
    assert!(format!("{e:#}").contains("gap"), "{e:#}");
    let twice = [
        shards[0].clone(),
        shards[1].clone(),
        shards[2].clone(),
        shards[1].clone(),
    ];
    let e = merge(&twice, &tmp.path().join("overlap.h5")).expect_err("an overlap");
    assert!(
        format!("{e:#}").contains("overlap") && format!("{e:#}").contains("shard1.h5"),
        "{e:#}"
    );
}

#[test]
fn a_killed_run_resumes_to_the_same_database() {
    let _serial = serial();
    let tmp = tempfile::tempdir().expect("temp dir");
    let (spec, file) = obstacle(tmp.path(), OBSTACLE);
    let out = tmp.path().join("db.h5");
    let dir = parts::folder(&out);
    let mut child = Command::new(env!("CARGO_BIN_EXE_eddy-precompute"))
        .arg(&file)
        .arg("--out")
        .arg(&out)
        .args(["--jobs", "1"])
        .spawn()
        .expect("starts eddy-precompute");
    wait_for_parts(&dir, 2);
    assert!(
        child.try_wait().expect("polls").is_none(),
        "killed before the end"
    );
    child.kill().expect("kills");
    child.wait().expect("reaps");
    assert!(!out.exists(), "no database from a killed run");
    let done = finished_parts(&dir);

    let e = precompute(&spec, &options(out.clone(), None, false, 2)).expect_err("parts present");
    assert!(e.to_string().contains("--resume"), "{e}");
    let s = precompute(&spec, &options(out.clone(), None, true, 2)).expect("resumes");
    assert_eq!(s.reused, done);
    assert_eq!(s.computed + s.reused, 14);

    let fresh = tmp.path().join("fresh.h5");
    precompute(&spec, &options(fresh.clone(), None, false, 2)).expect("runs");
    assert_eq!(
        AblData::read(&out).expect("reads"),
        AblData::read(&fresh).expect("reads")
    );
    // Resuming a finished database computes nothing.
    let again = precompute(&spec, &options(out.clone(), None, true, 2)).expect("resumes");
    assert_eq!((again.computed, again.reused), (0, 14));
}
