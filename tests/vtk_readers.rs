//! Every VTK frame and XDMF series a particle run, a grid run with boundary-layer vortices and
//! a coupled run write opens in VTK's own readers (`vtkXMLPolyDataReader`,
//! `vtkXMLImageDataReader`, `vtkXdmfReader`: what ParaView uses), and what they read equals
//! the HDF5 frames read by h5py, each grid value at its cell's centre (`tests/vtk_readers.py`).

mod common;

use std::path::Path;
use std::process::Command;

use eddy::pipeline::{run, RunOptions};

fn check(scene: &str, steps: u64, interval: &str) {
    let Some(python) = common::python_with(&["vtk", "h5py", "numpy"]) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let options = RunOptions {
        out: Some(dir.path().to_owned()),
        overrides: vec![
            "output.hdf5=true".into(),
            format!("output.interval={interval}"),
        ],
        steps: Some(steps),
        ..RunOptions::default()
    };
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let _serial = common::hdf5_or_child();
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
}

#[test]
fn vtk_reads_a_particle_run() {
    check("dam_break.toml", 3, "0.0005");
}

#[test]
fn vtk_reads_a_grid_run_with_vortex_particles() {
    check("abl_sphere_wake.toml", 12, "0.02");
}

#[test]
fn vtk_reads_a_coupled_run() {
    check("coupled_wind_over_tank.toml", 3, "0.001");
}
