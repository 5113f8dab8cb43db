//! The output seam: a format registered from outside eddy (here a dummy that writes one CSV
//! row per frame and a line at the end) is asked for by a scene, planned, opened, written at
//! every frame time and finished like the built-in ones, and its files are a run's files, with
//! no other change anywhere.

use std::path::Path;

use eddy::io::IoError;
use eddy::pipeline::outputs::{self, Format, Frame, Output, OutputSpec, RunFile};
use eddy::pipeline::{run_scene, Pipeline, Plan, RunOptions, Simulation};

/// The dummy's files.
const FILES: &[RunFile] = &[RunFile::Fixed("dummy.csv")];

/// One row `time,particles` per frame into `dummy.csv`, and `end,STEPS` when the run finishes.
struct Dummy {
    rows: Vec<String>,
    path: std::path::PathBuf,
}

impl Dummy {
    fn flush(&self) -> Result<(), IoError> {
        eddy::io::write_atomic(&self.path, |w| w.write_all(self.rows.join("\n").as_bytes()))
    }
}

impl Output for Dummy {
    fn name(&self) -> &'static str {
        "dummy"
    }

    fn describe(&self, _sim: &Simulation) -> Vec<(&'static str, String)> {
        vec![(
            "dummy",
            "dummy.csv: the particle count at every frame".into(),
        )]
    }

    fn open(&mut self, _sim: &Simulation, out: &Path) -> Result<(), IoError> {
        self.path = out.join("dummy.csv");
        self.flush()
    }

    fn write(&mut self, frame: &Frame) -> Result<(), IoError> {
        let fluid = frame.particles().expect("an SPH scene");
        let n = fluid.positions.len();
        self.rows.push(format!("{},{n}", frame.sim.time()));
        self.flush()
    }

    fn finish(&mut self, sim: &Simulation) -> Result<(), IoError> {
        self.rows.push(format!("end,{}", sim.steps()));
        self.flush()
    }
}

fn build(spec: &OutputSpec, _sim: &Simulation) -> Option<Box<dyn Output>> {
    spec.formats.iter().any(|f| f == "dummy").then(|| {
        Box::new(Dummy {
            rows: Vec::new(),
            path: Default::default(),
        }) as Box<dyn Output>
    })
}

fn register_dummy() {
    // Tests of one binary share the registry: the first registers, the others find it.
    if !outputs::formats().iter().any(|f| f.name == "dummy") {
        let _ = outputs::register(Format {
            name: "dummy",
            summary: "a test's dummy",
            files: FILES,
            build,
        });
    }
}

/// A block of water falling for 10 steps of 1 ms, a frame every 4 ms.
fn scene(formats: &str) -> Result<eddy::scene::Scene, String> {
    let text = format!(
        "name = \"dummy\"\n[domain]\nmin = [-1.0, -1.0, -1.0]\nmax = [1.0, 1.0, 1.0]\n\
         [time]\nsteps = 10\ndt = 1e-3\n[fluid]\nspacing = 0.05\n[[fluid.blocks]]\n\
         min = [-0.2, -0.2, -0.2]\nmax = [0.2, 0.2, 0.2]\n[output]\nvtk = false\n\
         interval = 0.004\nmetrics = []\nformats = {formats}\n"
    );
    eddy::scene::parse_str(&text, Path::new("dummy.toml"), &[]).map_err(|e| e.to_string())
}

#[test]
fn a_registered_format_is_planned_written_at_every_frame_and_finished() {
    register_dummy();
    let asked = scene("[\"dummy\"]").expect("the scene loads");
    let plan = Plan::of(&Pipeline::build(&asked).expect("builds"));
    assert!(
        plan.outputs
            .iter()
            .any(|(name, line)| *name == "dummy" && line.starts_with("dummy.csv")),
        "{:?}",
        plan.outputs
    );

    let dir = tempfile::tempdir().expect("temp dir");
    let options = RunOptions {
        out: Some(dir.path().to_path_buf()),
        ..Default::default()
    };
    let summary = run_scene(&asked, &options).expect("runs");
    assert_eq!(summary.steps, 10);
    let text = std::fs::read_to_string(dir.path().join("dummy.csv")).expect("dummy.csv");
    let rows: Vec<&str> = text.lines().collect();
    let n = summary.fluid_particles;
    // Frames at 0, 4 and 8 ms, and the end's at 10 ms; then the end's line.
    let expected: Vec<String> = ["0", "0.004", "0.008", "0.01"]
        .iter()
        .map(|t| format!("{t},{n}"))
        .chain(["end,10".to_owned()])
        .collect();
    assert_eq!(rows.len(), expected.len(), "{text}");
    for (row, want) in rows.iter().zip(&expected) {
        let (t, rest) = row.split_once(',').expect("two columns");
        let (t_want, rest_want) = want.split_once(',').expect("two columns");
        if t_want == "end" {
            assert_eq!(row, want);
        } else {
            let t: f64 = t.parse().expect("a time");
            let t_want: f64 = t_want.parse().expect("a time");
            assert!((t - t_want).abs() < 1e-12, "{row} against {want}");
            assert_eq!(rest, rest_want);
        }
    }
    // It is a run's file: the next run into the folder replaces it, and leaves others alone.
    assert!(outputs::is_run_output("dummy.csv"));
    std::fs::write(dir.path().join("notes.txt"), "mine").expect("writes");
    let again = scene("[]").expect("loads");
    run_scene(&again, &options).expect("runs");
    assert!(
        !dir.path().join("dummy.csv").exists(),
        "the earlier run's dummy.csv is cleared"
    );
    assert!(
        dir.path().join("notes.txt").exists(),
        "a user's file is kept"
    );
}

#[test]
fn an_unknown_format_is_refused_with_the_names_there_are() {
    register_dummy();
    let scene = scene("[\"dumy\"]").expect("the scene loads");
    let e = Pipeline::build(&scene).err().expect("refused").to_string();
    for needle in ["output.formats", "`dumy`", "vtk", "hdf5", "dummy"] {
        assert!(e.contains(needle), "{e} lacks {needle}");
    }
}

#[test]
fn a_taken_name_or_file_is_refused() {
    register_dummy();
    let again = |name, files| {
        outputs::register(Format {
            name,
            summary: "again",
            files,
            build,
        })
    };
    for name in ["vtk", "hdf5", "dummy"] {
        let e = again(name, &[]).expect_err("a taken name");
        assert!(e.contains(name), "{e}");
    }
    const METRICS: &[RunFile] = &[RunFile::PerMedium("metrics.csv")];
    let e = again("metrics_again", METRICS).expect_err("a stage's file");
    assert!(e.contains("metrics.csv"), "{e}");
}

/// Every file a coupled run with VTK and HDF5 frames, vortex-free, writes is one the run layer
/// knows (so the next run clears it), and the built-in formats declare their files.
#[test]
fn every_file_a_run_writes_is_a_run_output() {
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = eddy::scene::load(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/coupled_wind_over_tank.toml"),
        &[
            "output.hdf5=true".into(),
            "time.steps=2".into(),
            "fluid.spacing=0.025".into(),
        ],
    )
    .expect("loads");
    let options = RunOptions {
        out: Some(dir.path().to_path_buf()),
        ..Default::default()
    };
    run_scene(&scene, &options).expect("runs");
    let mut names = Vec::new();
    for entry in std::fs::read_dir(dir.path()).expect("lists") {
        let name = entry
            .expect("entry")
            .file_name()
            .into_string()
            .expect("utf-8");
        assert!(outputs::is_run_output(&name), "{name} is not a run output");
        names.push(name);
    }
    for must in [
        "frames.h5",
        "particles_frames_000000.h5",
        "grid_000000.vti",
        "scene.toml",
    ] {
        assert!(names.iter().any(|n| n == must), "{must} not in {names:?}");
    }
    assert!(!outputs::is_run_output("notes.txt"));
    assert!(
        !outputs::is_run_output("grid_00001.vti"),
        "five digits are not a frame"
    );
}
