//! `eddy lookup` and `eddy info` run as the binary on a small database written by the library:
//! the CSV holds every boundary point with the interpolated omega, the summary what the file
//! holds, and a bad file or argument ends with a message and a failure status.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use eddy::abl::{AblData, AblHeader, DirectionTable, MotionKind, Sampling};
use eddy::{Point3, Real, Vec3};

const POINTS: usize = 5;

/// omega linear in the direction d, which the lookup reproduces exactly off the samples:
/// translation `(p + 1) d x n_p`, rotation `p d`.
fn field(p: usize, normal: &Vec3, d: &Vec3, kind: MotionKind) -> Vec3 {
    match kind {
        MotionKind::Translation => d.cross(normal) * (p + 1) as Real,
        MotionKind::Rotation => d * p as Real,
    }
}

fn database(dir: &Path) -> (AblData, PathBuf) {
    let points: Vec<Point3> = (0..POINTS)
        .map(|p| Point3::new(0.1 * p as Real, -0.25, 1.0 / 3.0))
        .collect();
    let normals: Vec<Vec3> = (0..POINTS)
        .map(|p| Vec3::new(1.0, p as Real, -0.5).normalize())
        .collect();
    let table = |kind, sampling: Sampling| {
        let mut t = DirectionTable::empty(sampling, POINTS);
        for (i, j) in sampling.distinct() {
            let d = sampling.direction(i, j);
            let values: Vec<Vec3> = (0..POINTS)
                .map(|p| field(p, &normals[p], &d, kind))
                .collect();
            t.set(i, j, &values);
        }
        t
    };
    let data = AblData {
        header: AblHeader {
            obstacle: "cli-sphere".into(),
            fingerprint: "a".repeat(64),
            geometry_fingerprint: "b".repeat(64),
            beta: 2.5,
            layer_thickness: 0.05,
            spacing: 0.03125,
            settings: "[grid]\nresolution = 32\n".into(),
        },
        points,
        normals: normals.clone(),
        translation: table(
            MotionKind::Translation,
            Sampling::new(6, 12).expect("valid"),
        ),
        rotation: table(MotionKind::Rotation, Sampling::new(4, 6).expect("valid")),
    };
    let path = dir.join("cli.h5");
    data.write(&path).expect("writes");
    (data, path)
}

fn eddy(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_eddy"))
        .args(args)
        .output()
        .expect("the eddy binary runs")
}

#[test]
fn lookup_writes_every_point_with_its_interpolated_omega() {
    let _guard = common::hdf5_or_child();
    let tmp = tempfile::tempdir().expect("temp dir");
    let (data, db) = database(tmp.path());
    let csv = tmp.path().join("omega.csv");
    let (v, w) = (Vec3::new(0.3, -1.2, 0.5), Vec3::new(-0.4, 0.1, 2.0));
    let out = eddy(&[
        "lookup",
        db.to_str().expect("utf-8 path"),
        "--velocity",
        "0.3,-1.2,0.5",
        "--angular",
        "-0.4,0.1,2",
        "--csv",
        csv.to_str().expect("utf-8 path"),
    ]);
    assert!(out.status.success(), "{out:?}");
    assert!(String::from_utf8_lossy(&out.stderr).contains("5 boundary points"));
    let text = std::fs::read_to_string(&csv).expect("the CSV exists");
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("x,y,z,nx,ny,nz,omega_x,omega_y,omega_z"));
    let rows: Vec<Vec<Real>> = lines
        .map(|l| l.split(',').map(|c| c.parse().expect("a number")).collect())
        .collect();
    assert_eq!(rows.len(), POINTS);
    for (p, row) in rows.iter().enumerate() {
        assert_eq!(row.len(), 9);
        // Points and normals come back bit for bit (Rust prints f64 so that it parses back).
        assert_eq!(row[..3], data.points[p].coords.as_slice()[..]);
        assert_eq!(row[3..6], data.normals[p].as_slice()[..]);
        let n = data.normals[p];
        let expect =
            field(p, &n, &v, MotionKind::Translation) + field(p, &n, &w, MotionKind::Rotation);
        let got = Vec3::new(row[6], row[7], row[8]);
        assert!(
            (got - expect).norm() <= 1e-12 * expect.norm().max(1.0),
            "point {p}: {got:?} vs {expect:?}"
        );
    }
}

#[test]
fn info_summarises_the_database() {
    let _guard = common::hdf5_or_child();
    let tmp = tempfile::tempdir().expect("temp dir");
    let (data, db) = database(tmp.path());
    let out = eddy(&["info", db.to_str().expect("utf-8 path")]);
    assert!(out.status.success(), "{out:?}");
    let text = String::from_utf8(out.stdout).expect("utf-8");
    let max = |kind: MotionKind| {
        data.table(kind)
            .omega
            .chunks_exact(3)
            .map(|c| Vec3::new(c[0], c[1], c[2]).norm())
            .fold(0.0, Real::max)
    };
    for line in [
        "obstacle          cli-sphere".to_string(),
        format!("fingerprint       {}", "a".repeat(64)),
        format!("geometry          {}", "b".repeat(64)),
        "boundary points   5".into(),
        "beta              2.5".into(),
        "layer thickness   0.05 m".into(),
        "grid spacing      0.03125 m".into(),
        format!(
            "translation       6 polar x 12 azimuth samples, max |omega| {:.4} per unit speed",
            max(MotionKind::Translation)
        ),
        format!(
            "rotation          4 polar x 6 azimuth samples, max |omega| {:.4} per unit speed",
            max(MotionKind::Rotation)
        ),
        "resolution = 32".into(),
    ] {
        assert!(
            text.lines().any(|l| l == line),
            "missing `{line}` in\n{text}"
        );
    }
}

#[test]
fn bad_files_and_arguments_fail_with_a_message() {
    let _guard = common::hdf5_or_child();
    let tmp = tempfile::tempdir().expect("temp dir");
    let (_, db) = database(tmp.path());
    let bytes = std::fs::read(&db).expect("reads");
    let cut = tmp.path().join("cut.h5");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).expect("writes");
    let csv = tmp.path().join("never.csv");
    let out = eddy(&[
        "lookup",
        cut.to_str().expect("utf-8 path"),
        "--velocity",
        "1,0,0",
        "--csv",
        csv.to_str().expect("utf-8 path"),
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("cut.h5"), "{err}");
    assert!(!csv.exists(), "no CSV from a failed lookup");
    let out = eddy(&["info", cut.to_str().expect("utf-8 path")]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("not an HDF5 file, or truncated"), "{err}");
    // A file that is not there is said to be missing, not to be a damaged HDF5 file.
    let gone = tmp.path().join("gone.h5");
    let out = eddy(&["info", gone.to_str().expect("utf-8 path")]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("gone.h5") && err.contains("No such file") && !err.contains("HDF5"),
        "{err}"
    );
    // A missing scene file: its cause said once.
    let out = eddy(&["run", "/definitely/not/here.toml", "--plan"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert_eq!(err.matches("No such file").count(), 1, "{err}");
    let out = eddy(&[
        "lookup",
        db.to_str().expect("utf-8 path"),
        "--velocity",
        "1,2",
        "--csv",
        csv.to_str().expect("utf-8 path"),
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("expected three finite numbers"), "{err}");
    // Finite speeds whose looked-up values are not.
    let out = eddy(&[
        "lookup",
        db.to_str().expect("utf-8 path"),
        "--velocity=1e308,1e308,1e308",
        "--csv",
        csv.to_str().expect("utf-8 path"),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success(),
        "{err} {}",
        std::fs::read_to_string(&csv).unwrap_or_default()
    );
    assert!(err.contains("overflow"), "{err}");
    assert!(!csv.exists(), "no CSV from an overflowing lookup");
}

/// `--csv -` writes the same CSV to standard output, and a vector may start with a minus sign
/// as written (`--velocity -1,0,0`).
#[test]
fn lookup_writes_to_standard_output() {
    let _guard = common::hdf5_or_child();
    let tmp = tempfile::tempdir().expect("temp dir");
    let (_, db) = database(tmp.path());
    let csv = tmp.path().join("omega.csv");
    let db = db.to_str().expect("utf-8 path");
    let args =
        |target: &str| ["lookup", db, "--velocity", "-1,0,0", "--csv", target].map(String::from);
    let to_file = eddy(
        &args(csv.to_str().expect("utf-8 path"))
            .each_ref()
            .map(|s| s.as_str()),
    );
    assert!(to_file.status.success(), "{to_file:?}");
    let to_stdout = eddy(&args("-").each_ref().map(|s| s.as_str()));
    assert!(to_stdout.status.success(), "{to_stdout:?}");
    let text = std::fs::read_to_string(&csv).expect("the CSV exists");
    assert_eq!(String::from_utf8_lossy(&to_stdout.stdout), text);
    assert!(text.ends_with('\n') && text.lines().count() == POINTS + 1);
    assert!(!tmp.path().join("-").exists());
}
