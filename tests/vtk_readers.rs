//! Every VTK frame and XDMF series a particle run, a grid run with boundary-layer vortices and
//! a coupled run write opens in VTK's own readers (`vtkXMLPolyDataReader`,
//! `vtkXMLImageDataReader`, `vtkXdmfReader`: what ParaView uses), and what they read equals
//! the HDF5 frames read by h5py, each grid value at its cell's centre (`tests/vtk_readers.py`);
//! so do the running statistics' `.vti` and `.xmf`, the stress tensor as ParaView reads it.

mod common;

use std::path::Path;
use std::process::Command;

use eddy::pipeline::{run, RunOptions};

/// Runs `scene` for `steps` with HDF5 frames every `interval` and the overrides `more`, checks
/// its outputs with VTK's readers and returns what the checking script printed.
fn check(scene: &str, steps: u64, interval: &str, more: &[String]) -> String {
    // Held from the first child process on: none may inherit another test's open HDF5 file.
    let _serial = common::hdf5_or_child();
    let Some(python) = common::python_with(&["vtk", "h5py", "numpy"]) else {
        return String::new();
    };
    let dir = tempfile::tempdir().unwrap();
    let mut overrides = vec![
        "output.hdf5=true".into(),
        format!("output.interval={interval}"),
    ];
    overrides.extend_from_slice(more);
    let options = RunOptions {
        out: Some(dir.path().to_owned()),
        overrides,
        steps: Some(steps),
        ..RunOptions::default()
    };
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    run(&root.join("scenes").join(scene), &options).expect("the scene runs");
    let out = Command::new(python)
        .arg(root.join("tests/vtk_readers.py"))
        .arg(dir.path())
        .output()
        .expect("python runs");
    let log = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{scene}:\n{log}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(log.contains(".xmf"), "{log}");
    log.into_owned()
}

#[test]
fn vtk_reads_a_particle_run() {
    check("dam_break.toml", 3, "0.0005", &[]);
}

#[test]
fn vtk_reads_a_grid_run_with_vortex_particles() {
    // The demo's sphere on a stand-in database (the shipped one is precomputed by `./dev demo`).
    let db = tempfile::tempdir().unwrap();
    let path = db.path().join("sphere.h5");
    {
        let _serial = common::hdf5_or_child();
        common::sphere_database(&path, 0.5, 200, 1.0);
    }
    let database = format!("obstacles.0.abl.database={:?}", path.display().to_string());
    let stats = "statistics.from=0.1".to_owned();
    // Frames every 0.05 s: 12 steps reach about 0.45 s, and the wake seeds from about 0.25 s.
    let log = check("abl_sphere_wake.toml", 12, "0.05", &[database, stats]);
    assert!(
        log.is_empty() || log.contains("statistics.h5 statistics"),
        "{log}"
    );
    // Vortex particles were seeded, and their sets read as blocks of the frames.
    let sets = log.lines().find(|l| l.starts_with("frames.xmf")).map(|l| {
        let words: Vec<&str> = l.split_whitespace().collect();
        words[words.len() - 4].parse::<usize>().unwrap_or(0)
    });
    assert!(log.is_empty() || sets > Some(0), "{log}");
}

#[test]
fn vtk_reads_a_coupled_run() {
    let log = check(
        "coupled_wind_over_tank.toml",
        3,
        "0.001",
        &["statistics.from=0".into()],
    );
    for medium in ["grid", "particles"] {
        let line = format!("{medium}_statistics.h5 statistics");
        assert!(log.is_empty() || log.contains(&line), "{log}");
    }
}
