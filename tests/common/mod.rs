//! Helpers shared by integration tests.

use std::sync::{Mutex, MutexGuard};

#[allow(dead_code)]
pub mod vtk_read;

/// HDF5 opens files without close-on-exec, so a child process spawned while another test of
/// the same binary has a file open inherits its descriptor and with it the file lock; the next
/// open of that file then fails with "unable to lock file" until the child exits. Tests that
/// open HDF5 files or spawn processes hold this guard, so the two never overlap.
pub fn hdf5_or_child() -> MutexGuard<'static, ()> {
    static LOCK: Mutex<()> = Mutex::new(());
    LOCK.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// A complete boundary-layer database for a sphere of `radius` at the origin, written to `path`:
/// `points` Fibonacci points on its surface, and at each Pfaff et al. 2009's Eq. 1 with an
/// analytic slip velocity, `omega_pre = gain (U_s x n)`, where U_s is the tangential part of
/// the stream `-d` past the sphere (translation along d) or of `-(d x x)` (rotation about d).
/// `gain` is in 1/m.
#[allow(dead_code)]
pub fn sphere_database(path: &std::path::Path, radius: f64, points: usize, gain: f64) {
    use eddy::abl::{
        geometry_fingerprint, AblData, AblHeader, DirectionTable, MotionKind, Sampling,
    };
    use eddy::{Point3, Vec3};
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    let normals: Vec<Vec3> = (0..points)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / points as f64;
            let r = (1.0 - z * z).sqrt();
            let phi = golden * i as f64;
            Vec3::new(r * phi.cos(), r * phi.sin(), z)
        })
        .collect();
    let xs: Vec<Point3> = normals.iter().map(|n| Point3::from(n * radius)).collect();
    let sampling = Sampling::new(5, 8).expect("valid sampling");
    let table = |kind: MotionKind| {
        let mut t = DirectionTable::empty(sampling, points);
        for (i, j) in sampling.distinct() {
            let d = sampling.direction(i, j);
            let values: Vec<Vec3> = xs
                .iter()
                .zip(&normals)
                .map(|(x, n)| {
                    let u = match kind {
                        MotionKind::Translation => -d,
                        MotionKind::Rotation => -d.cross(&x.coords),
                    };
                    let slip = u - n * u.dot(n);
                    slip.cross(n) * gain
                })
                .collect();
            t.set(i, j, &values);
        }
        t
    };
    let shape = eddy::scene::Shape::Sphere { radius };
    let (translation, rotation) = (table(MotionKind::Translation), table(MotionKind::Rotation));
    AblData {
        header: AblHeader {
            obstacle: "sphere".into(),
            fingerprint: "0".repeat(64),
            geometry_fingerprint: geometry_fingerprint(&shape).expect("analytic shape"),
            beta: gain,
            layer_thickness: 0.05,
            spacing: radius / 8.0,
            settings: "synthetic = true\n".into(),
        },
        points: xs,
        normals,
        translation,
        rotation,
    }
    .write(path)
    .expect("writes the database");
}

/// [`sphere_database`] of `radius` with 400 points and gain 4 as `DIR/ball.h5`, written under
/// the HDF5 guard.
#[allow(dead_code)]
pub fn ball_database(dir: &std::path::Path, radius: f64) -> std::path::PathBuf {
    let path = dir.join("ball.h5");
    let _serial = hdf5_or_child();
    sphere_database(&path, radius, 400, 4.0);
    path
}

/// The `abl = { database = ... }` line of an obstacle naming `db`.
#[allow(dead_code)]
pub fn abl_line(db: &std::path::Path) -> String {
    format!("abl = {{ database = {:?} }}", db.display().to_string())
}

/// The pipeline of a scene given as text (`name` is the file it reports), built under the
/// HDF5 guard (it opens databases).
#[allow(dead_code)]
pub fn built(text: &str, name: &str) -> eddy::pipeline::Pipeline {
    let scene =
        eddy::scene::parse_str(text, std::path::Path::new(name), &[]).expect("the scene loads");
    let _serial = hdf5_or_child();
    eddy::pipeline::Pipeline::build(&scene).expect("the pipeline builds")
}

/// The MAC-grid solver of a pipeline whose scene has a grid.
#[allow(dead_code)]
pub fn grid(p: &eddy::pipeline::Pipeline) -> &eddy::grid::GridSolver {
    p.sim.grid.as_ref().expect("the scene has a grid")
}

/// The boundary-layer turbulence state of a pipeline whose scene has an `abl` obstacle.
#[allow(dead_code)]
pub fn turbulence(p: &eddy::pipeline::Pipeline) -> &eddy::pipeline::Turbulence {
    p.sim
        .grid_turbulence
        .as_ref()
        .or(p.sim.sph_turbulence.as_ref())
        .expect("the scene has turbulence stages")
}

/// omega_ABL on the grid of a grid scene with boundary layers, one array per component.
#[allow(dead_code)]
pub fn abl_field(p: &eddy::pipeline::Pipeline) -> &[ndarray::Array3<eddy::Real>; 3] {
    turbulence(p)
        .abl
        .as_ref()
        .expect("a grid scene carries omega_ABL on its cells")
}

/// A Python interpreter that imports `modules`, for tests that check files with the readers
/// researchers use (h5py, VTK). `./dev test` installs them into `.venv` and names that Python
/// in `EDDY_PYTHON`: then a missing module fails the test. Without `EDDY_PYTHON` (a plain
/// `cargo test`) the `python3` on the path is tried and the check is skipped, said on stderr,
/// when it lacks them.
#[allow(dead_code)]
pub fn python_with(modules: &[&str]) -> Option<std::path::PathBuf> {
    let required = std::env::var_os("EDDY_PYTHON");
    let python = required.clone().unwrap_or_else(|| "python3".into());
    let imports = format!("import {}", modules.join(", "));
    let works = std::process::Command::new(&python)
        .args(["-c", &imports])
        .output()
        .is_ok_and(|o| o.status.success());
    match (works, required) {
        (true, _) => Some(python.into()),
        (false, Some(p)) => panic!("EDDY_PYTHON={p:?} cannot `{imports}`"),
        (false, None) => {
            eprintln!("skipped: python3 cannot `{imports}` (./dev test installs it)");
            None
        }
    }
}

/// A 1.5 x 1 x 1 m channel of 36 x 24 x 24 cells, fed at 1 m/s through x_min and open at x_max,
/// with a ball of radius 0.2 m crossing it at 0.3 m/s, projected to 1e-14; `surface` is its
/// `grid.obstacle_surface`.
#[allow(dead_code)]
pub fn moving_ball_channel(surface: &str) -> String {
    format!(
        r#"
        name = "channel"
        gravity = [0.0, 0.0, 0.0]
        domain = {{ min = [0.0, 0.0, 0.0], max = [1.5, 1.0, 1.0] }}
        time = {{ end = 1.0, cfl = 0.8, dt_max = 0.05 }}
        viscosity = {{ kinematic = 0.01 }}
        [grid]
        resolution = [36, 24, 24]
        pressure_tolerance = 1e-14
        obstacle_surface = "{surface}"
        initial_velocity = [1.0, 0.0, 0.0]
        boundary = {{ x_min = {{ inflow = [1.0, 0.0, 0.0] }}, x_max = "open" }}
        [[obstacles]]
        name = "ball"
        shape = {{ type = "sphere", radius = 0.2 }}
        position = [0.6, 0.5, 0.5]
        motion = {{ linear = [0.0, 0.3, 0.0] }}
        "#
    )
}

/// One step of `g`, after which every cell with a pressure has a divergence below
/// 1e-9 |u|max / dx (with cut cells, of the fluid's share of the cell).
#[allow(dead_code)]
pub fn step_divergence_free(g: &mut eddy::grid::GridSolver) {
    g.step(None).expect("stable");
    let umax = g.mac.max_face_speed();
    let div = eddy::grid::project::max_divergence(&g.mac, &g.bounds);
    assert!(
        div < 1e-9 * umax / g.mac.dx,
        "divergence {div:.3e} at |u| {umax}"
    );
}

/// The names of the files of `src/FOLDER` whose text holds `marker` (the declaration each
/// entry of a registry's table makes), sorted: what the table must list, so that an entry's
/// file cannot be left out of it.
#[allow(dead_code)]
pub fn files_declaring(folder: &str, marker: &str) -> Vec<String> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("src")
        .join(folder);
    let mut declared: Vec<String> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("entry").path())
        .filter(|p| std::fs::read_to_string(p).is_ok_and(|s| s.contains(marker)))
        .map(|p| {
            p.file_stem()
                .expect("a file")
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    declared.sort();
    declared
}
