//! The precomputation over MPI ranks (`--features mpi`; `./dev test-mpi` installs OpenMPI and
//! runs this): `mpirun -n 2 ... --mpi` writes the single-process database bit for bit, and a
//! job killed part way and restarted with `--resume` keeps what it finished and ends with the
//! same database.
#![cfg(feature = "mpi")]

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use eddy::abl::AblData;
use eddy_precompute::{parts, precompute, ObstacleSpec};

mod common;
use common::{finished_parts, obstacle, options, serial, wait_for_parts};

const OBSTACLE: &str = r#"
name = "small sphere"
shape = { type = "sphere", radius = 0.5 }
[grid]
resolution = 24
domain = 3.0
stabilise_steps = 30
average_steps = 30
settle_tolerance = 0.0
[sampling]
translation = [3, 4]
rotation = [4, 3]
"#;

/// Translation 1 + 4 + 1, rotation 1 + 2 x 3 + 1 distinct directions.
const DIRECTIONS: usize = 14;

/// The single-process database, on one thread.
fn single(spec: &ObstacleSpec, out: PathBuf) -> AblData {
    precompute(spec, &options(out.clone(), None, false, 1)).expect("runs");
    AblData::read(&out).expect("reads")
}

/// `mpirun -n ranks eddy-precompute file --out out --mpi`, allowed to run as root (CI) and on
/// more ranks than cores.
fn mpirun(ranks: usize, file: &Path, out: &Path) -> Command {
    let mut c = Command::new("mpirun");
    c.env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        .args(["-n", &ranks.to_string(), "--oversubscribe"])
        .arg(env!("CARGO_BIN_EXE_eddy-precompute"))
        .arg(file)
        .arg("--out")
        .arg(out)
        .arg("--mpi");
    c
}

#[test]
fn two_ranks_write_the_single_process_database_bit_for_bit() {
    let _serial = serial();
    let tmp = tempfile::tempdir().expect("temp dir");
    let (spec, file) = obstacle(tmp.path(), OBSTACLE);
    let out = tmp.path().join("mpi.h5");
    let status = mpirun(2, &file, &out).status().expect("starts mpirun");
    assert!(status.success(), "mpirun failed: {status}");
    assert!(!parts::folder(&out).exists(), "parts are removed when done");
    let fresh = single(&spec, tmp.path().join("single.h5"));
    assert_eq!(AblData::read(&out).expect("reads"), fresh);
}

#[test]
fn a_killed_mpi_job_resumes_to_the_same_database() {
    let _serial = serial();
    let tmp = tempfile::tempdir().expect("temp dir");
    let (spec, file) = obstacle(tmp.path(), OBSTACLE);
    let out = tmp.path().join("db.h5");
    let dir = parts::folder(&out);
    let mut job = mpirun(2, &file, &out)
        .stderr(Stdio::null())
        .spawn()
        .expect("starts mpirun");
    wait_for_parts(&dir, 2);
    assert!(
        job.try_wait().expect("polls").is_none(),
        "killed before the end"
    );
    // As a scheduler ends a job: SIGTERM to mpirun, which passes it on to the ranks.
    let term = Command::new("kill")
        .args(["-TERM", &job.id().to_string()])
        .status()
        .expect("runs kill");
    assert!(term.success());
    job.wait().expect("reaps mpirun");
    assert!(!out.exists(), "no database from a killed job");
    let done = finished_parts(&dir);
    assert!((2..DIRECTIONS).contains(&done), "{done} parts kept");

    let resumed = mpirun(2, &file, &out)
        .arg("--resume")
        .output()
        .expect("restarts mpirun");
    assert!(resumed.status.success(), "the resumed job failed");
    let said = String::from_utf8_lossy(&resumed.stderr);
    assert!(
        said.contains(&format!("{} directions computed", DIRECTIONS - done))
            && said.contains(&format!("{done} reused")),
        "{said}"
    );
    let fresh = single(&spec, tmp.path().join("single.h5"));
    assert_eq!(AblData::read(&out).expect("reads"), fresh);
}
