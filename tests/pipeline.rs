//! The one pipeline: the plan is what runs, a scene with a grid and an SPH fluid steps both on
//! one clock, and the layering rules of ARCHITECTURE.md hold in the source tree.

use eddy::pipeline::{run, Pipeline, Plan, RunOptions};
use eddy::scene;
use std::path::{Path, PathBuf};
use tempfile::TempDir;

fn shipped(file: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(file)
}

/// Runs `file` for `steps` steps with a stage trace; returns the trace, the plan, and the output
/// folder.
fn traced(file: &str, overrides: &[&str], steps: u64) -> (Vec<String>, Plan, TempDir) {
    let out = tempfile::tempdir().expect("temp dir");
    let mut overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    overrides.push("output.vtk=false".into());
    let options = RunOptions {
        out: Some(out.path().to_owned()),
        overrides,
        steps: Some(steps),
        trace: true,
        ..RunOptions::default()
    };
    let summary = run(&shipped(file), &options).expect("the scene runs");
    assert_eq!(summary.steps, steps, "{file} stopped early");
    (summary.trace, summary.plan, out)
}

/// A scene of [`the_plan_is_what_runs`]: the scene, its overrides, the entries of a step's
/// trace (`stage` or `stage/part`) the plan must list for the case to exercise what it is
/// there for, and phrases the plan must say (a part's way of running that has no part of its
/// own, such as advection–reflection inside `grid/advect`).
struct Case {
    file: &'static str,
    overrides: &'static [&'static str],
    lists: &'static [&'static str],
    says: &'static [&'static str],
}

const fn case(
    file: &'static str,
    overrides: &'static [&'static str],
    lists: &'static [&'static str],
) -> Case {
    Case {
        file,
        overrides,
        lists,
        says: &[],
    }
}

/// The cylinder channel at 64 x 16 x 1 cells (the one-cell span follows the cells, which are
/// cubic).
const SMALL_CHANNEL: [&str; 2] = ["grid.resolution=[64,16,1]", "domain.max=[4.0,1.0,0.0625]"];

/// Every step runs exactly the stages and parts the plan lists, in its order: the trace of four
/// steps is the plan's step trace four times. The scenes cover a grid scene, SPH scenes with
/// and without a refinement and with parts switched off, a scene with both solvers side by
/// side, coupled ones, and each part that runs only when a scene asks for it, which the plan
/// must then list: advection–reflection (said in `grid/advect`, with its viscosity and
/// pressure), inflow turbulence (`grid/inflow`), the grid's running average (`grid/average`),
/// the statistics stage on the grid and on the particles (`statistics/grid`,
/// `statistics/particles`, sampling every step), moving obstacles re-voxelised on the grid
/// (`grid/obstacles`, in a grid scene and in a coupled one), and SPH open boundaries
/// (`sph/open boundaries`, with a refinement whose per-particle state follows the particles in
/// and out).
#[test]
fn the_plan_is_what_runs() {
    let cases = [
        case("lid_driven_cavity.toml", &[], &["grid/pressure"]),
        case(
            "smoke_plume.toml",
            &["grid.resolution=[16,16,16]"],
            &["grid/forces"],
        ),
        case("dam_break.toml", &[], &["sph/divergence", "metrics"]),
        case(
            "dam_break.toml",
            &["pressure.divergence_solver=false", "output.metrics=[]"],
            &["sph/pressure"],
        ),
        case(
            "refine_dam_break.toml",
            &["refinement.method=\"vrsph\""],
            &["sph/refine"],
        ),
        case(
            "refine_stirring_rod.toml",
            &["refinement.method=\"mcvsph\""],
            &["sph/refine"],
        ),
        case("coupled_tank_and_plume.toml", &[], &["sph", "grid"]),
        case(
            "coupled_wind_over_tank.toml",
            &["fluid.spacing=0.025"],
            &["coupling", "surface pressure"],
        ),
        Case {
            says: &["advection-reflection (two projections)"],
            ..case(
                "taylor_green.toml",
                &[],
                &["grid/advect", "grid/viscosity", "grid/pressure"],
            )
        },
        case(
            "cylinder_channel.toml",
            &[
                SMALL_CHANNEL[0],
                SMALL_CHANNEL[1],
                "grid.inflow_turbulence={ intensity = 0.05, length = 0.25 }",
            ],
            &["grid/inflow", "probes"],
        ),
        case(
            "cylinder_channel.toml",
            &[
                SMALL_CHANNEL[0],
                SMALL_CHANNEL[1],
                "grid.average_from=0.0",
                "statistics.from=0.0",
            ],
            &["grid/average", "statistics", "statistics/grid"],
        ),
        case(
            "coupled_tank_and_plume.toml",
            &["statistics.from=0.0"],
            &["statistics/grid", "statistics/particles"],
        ),
        case(
            "smoke_sphere.toml",
            &[
                "grid.resolution=[16,16,16]",
                "obstacles.0.motion={ linear = [0.2, 0.0, 0.0] }",
            ],
            &["grid/obstacles"],
        ),
        case("coupled_hull.toml", &[], &["grid/obstacles", "coupling"]),
        case(
            "refine_stream_ball.toml",
            &["refinement.method=\"micropolar\""],
            &["sph/open boundaries", "sph/refine"],
        ),
    ];
    for Case {
        file,
        overrides,
        lists,
        says,
    } in cases
    {
        let steps = 4;
        let (trace, plan, _) = traced(file, overrides, steps);
        let step = plan.step_trace();
        for entry in lists {
            assert!(
                step.iter().any(|s| s == entry),
                "{file} {overrides:?}: the plan does not list {entry}: {step:?}"
            );
        }
        let text = plan.to_string();
        for phrase in says {
            assert!(
                text.contains(phrase),
                "{file} {overrides:?}: the plan does not say {phrase:?}:\n{text}"
            );
        }
        let expected: Vec<String> = (0..steps).flat_map(|_| step.clone()).collect();
        assert_eq!(trace, expected, "{file} {overrides:?}");
    }
}

/// The statistics stage samples every `statistics.every` steps, as its line in the plan says:
/// each step runs the stage, and the steps that sample (the third and the sixth, every 3)
/// run exactly the parts the plan lists; the others run none.
#[test]
fn statistics_run_their_parts_on_the_steps_they_sample() {
    let overrides = [
        SMALL_CHANNEL[0],
        SMALL_CHANNEL[1],
        "statistics.from=0.0",
        "statistics.every=3",
    ];
    let steps = 6;
    let (trace, plan, _) = traced("cylinder_channel.toml", &overrides, steps);
    assert!(plan.to_string().contains("every 3 steps"), "{plan}");
    let step = plan.step_trace();
    let sampled: Vec<String> = step
        .iter()
        .filter(|s| s.starts_with("statistics/"))
        .cloned()
        .collect();
    assert_eq!(sampled, ["statistics/grid"]);
    let expected: Vec<String> = (0..steps)
        .flat_map(|k| {
            let samples = k % 3 == 2;
            step.iter()
                .filter(move |s| samples || !s.starts_with("statistics/"))
                .cloned()
        })
        .collect();
    assert_eq!(trace, expected);
}

/// A stage the plan leaves out does not run: without metrics no metrics file is written, and
/// without the divergence solve no step runs it.
#[test]
fn a_stage_left_out_does_not_run() {
    let (trace, plan, out) = traced(
        "dam_break.toml",
        &["pressure.divergence_solver=false", "output.metrics=[]"],
        3,
    );
    let step = plan.step_trace();
    assert!(!step.iter().any(|s| s == "metrics" || s == "sph/divergence"));
    assert!(!trace
        .iter()
        .any(|s| s == "metrics" || s == "sph/divergence"));
    assert!(!out.path().join("metrics.csv").exists());
    let (trace, plan, out) = traced("dam_break.toml", &[], 3);
    let step = plan.step_trace();
    assert!(step.iter().any(|s| s == "sph/divergence") && step.iter().any(|s| s == "metrics"));
    assert_eq!(trace.iter().filter(|s| *s == "metrics").count(), 3);
    assert!(out.path().join("metrics.csv").exists());
}

/// A scene with a grid and an SPH fluid advances both by one dt, the smaller of their stable
/// steps, and writes both kinds of frames into one folder with one .pvd series per kind.
#[test]
fn grid_and_fluid_share_one_clock() {
    let file = shipped("coupled_tank_and_plume.toml");
    let s = scene::load(&file, &[]).expect("scene loads");
    let mut p = Pipeline::build(&s).expect("builds");
    for _ in 0..60 {
        let sph_dt = p
            .sim
            .sph
            .as_mut()
            .expect("sph")
            .stable_dt()
            .expect("stable");
        let grid_dt = p
            .sim
            .grid
            .as_ref()
            .expect("grid")
            .stable_dt()
            .expect("stable");
        let rec = p.step(s.time.end, None).expect("steps");
        assert_eq!(rec.dt, sph_dt.min(grid_dt));
        assert_eq!(rec.sph.expect("sph stepped").dt, rec.dt);
        assert_eq!(rec.grid.expect("grid stepped").dt, rec.dt);
        let (sph, grid) = (
            p.sim.sph.as_ref().expect("the scene has an SPH fluid"),
            p.sim.grid.as_ref().expect("the scene has a grid"),
        );
        assert_eq!(sph.time(), p.sim.time());
        assert_eq!(grid.time(), p.sim.time());
    }
    assert!(p.sim.time() > 0.0);

    let out = tempfile::tempdir().expect("temp dir");
    let options = RunOptions {
        out: Some(out.path().to_owned()),
        until: Some(0.1),
        ..RunOptions::default()
    };
    let summary = run(&file, &options).expect("runs");
    assert!(summary.fluid_particles > 0 && summary.grid_cells > 0);
    let names: Vec<String> = std::fs::read_dir(out.path())
        .expect("output folder")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    let count = |ext: &str| names.iter().filter(|n| n.ends_with(ext)).count();
    assert_eq!(count(".pvd"), 2, "{names:?}");
    assert!(names.contains(&"particles.pvd".into()) && names.contains(&"grid.pvd".into()));
    assert_eq!(count(".vtp"), summary.frames);
    assert_eq!(count(".vti"), summary.frames);
    let dts = |name: &str| -> Vec<String> {
        let text = std::fs::read_to_string(out.path().join(name)).expect(name);
        text.lines()
            .skip(1)
            .map(|l| l.split(',').nth(2).expect("dt").to_owned())
            .collect()
    };
    let (sph, grid) = (dts("particles_metrics.csv"), dts("grid_metrics.csv"));
    assert_eq!(sph.len() as u64, summary.steps);
    assert_eq!(sph, grid);
}

/// Frames land on the output interval: with a fixed step of 3 ms and frames every 10 ms, the
/// steps before each frame time are shortened (as before the end time) so every frame is at
/// k x 10 ms, not at the first step past it (12, 21, 30, ... ms), and no step is shorter than
/// half the fixed one.
#[test]
fn frames_land_on_the_output_interval() {
    let out = tempfile::tempdir().expect("temp dir");
    let options = RunOptions {
        out: Some(out.path().to_owned()),
        overrides: [
            "time.dt=0.003",
            "time.end=0.05",
            "output.interval=0.01",
            "output.vtk=true",
        ]
        .map(String::from)
        .to_vec(),
        ..RunOptions::default()
    };
    run(&shipped("hydrostatic_tank.toml"), &options).expect("the scene runs");
    let pvd = std::fs::read_to_string(out.path().join("particles.pvd")).expect("series");
    let times: Vec<f64> = pvd
        .split("timestep=\"")
        .skip(1)
        .map(|s| {
            s.split('"')
                .next()
                .expect("a quoted time")
                .parse()
                .expect("a time")
        })
        .collect();
    assert_eq!(times.len(), 6, "{times:?}");
    for (k, t) in times.iter().enumerate() {
        assert!((t - 0.01 * k as f64).abs() < 1e-12, "frame {k} at {t}");
    }
    let metrics = std::fs::read_to_string(out.path().join("metrics.csv")).expect("metrics");
    let dts: Vec<f64> = metrics
        .lines()
        .skip(1)
        .map(|l| {
            l.split(',')
                .nth(2)
                .expect("a dt column")
                .parse()
                .expect("dt")
        })
        .collect();
    assert!(dts.iter().all(|&dt| dt >= 0.0015 - 1e-15), "{dts:?}");
}

/// The layering rules of ARCHITECTURE.md ("Layering"), all in this table: per source folder, the paths its code
/// may not name (comments may point anywhere). No part names the scene; the two solvers do not
/// name each other; neither the vortex layer nor the boundary layer's seeding and lookup name
/// a solver; the SPH solver names neither the refinements on top of it nor the metrics that
/// read it (which closed a cycle); the metrics, spectra included, read the grid and io only.
const BANNED: [(&str, &[&str]); 7] = [
    ("grid", &["crate::scene", "crate::sph"]),
    ("metrics", &["crate::scene", "crate::pipeline"]),
    (
        "sph",
        &[
            "crate::scene",
            "crate::grid",
            "crate::refine",
            "crate::metrics",
        ],
    ),
    ("refine", &["crate::scene"]),
    ("abl", &["crate::scene", "crate::grid", "crate::sph"]),
    ("geometry", &["crate::scene"]),
    ("vortex", &["crate::scene", "crate::sph", "crate::grid"]),
];

/// The parts of `sph` that `refine` may reach (ARCHITECTURE.md: "only through its operators and the
/// step hooks"); any other `crate::sph` path in `refine` is a crossing.
const REFINE_REACHES: [&str; 2] = ["crate::sph::operators", "crate::sph::hooks"];

/// What a `crate::scene` path in the pipeline may not reach, but in its front door
/// (`entry.rs`): the pipeline builds from the `RunSpec` that `scene::build` hands over, so it
/// names no `Scene`, and neither builds nor loads one (the scene's parameter types, such as
/// `Coupling`, it may name).
const PIPELINE_FRONT_DOOR: &str = "entry.rs";
const PIPELINE_MAY_NOT_REACH: [&str; 3] = ["Scene", "build", "load"];

/// Every `crate::scene` path in the pipeline's code outside its front door that reaches what
/// [`PIPELINE_MAY_NOT_REACH`] names: the text from the path to the end of its statement, so a
/// `use` over several lines is read whole.
fn pipeline_reaches_into_the_scene() -> Vec<String> {
    let mut files: Vec<(String, String)> = Vec::new();
    for (at, line) in code_lines("pipeline") {
        let file = at
            .rsplit_once(':')
            .map_or(at.clone(), |(f, _)| f.to_owned());
        match files.last_mut() {
            Some((f, text)) if *f == file => {
                text.push_str(&line);
                text.push('\n');
            }
            _ => files.push((file, format!("{line}\n"))),
        }
    }
    let mut found = Vec::new();
    for (file, text) in files
        .iter()
        .filter(|(f, _)| !f.ends_with(PIPELINE_FRONT_DOOR))
    {
        for (k, _) in text.match_indices("crate::scene") {
            let statement = text[k..].split(';').next().unwrap_or("");
            let words = statement.split(|c: char| !(c.is_alphanumeric() || c == '_'));
            if words
                .into_iter()
                .any(|w| PIPELINE_MAY_NOT_REACH.contains(&w))
            {
                found.push(format!("{file}: {}", statement.trim()));
            }
        }
    }
    found
}

/// Every line of code (not comment) in the source folder `folder`, with its file and number.
fn code_lines(folder: &str) -> Vec<(String, String)> {
    let mut lines = Vec::new();
    let mut stack = vec![Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("src")
        .join(folder)];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).expect("source folder") {
            let path = entry.expect("entry").path();
            if path.is_dir() {
                stack.push(path);
                continue;
            }
            let text = std::fs::read_to_string(&path).expect("source file");
            for (n, line) in text.lines().enumerate() {
                if !line.trim_start().starts_with("//") {
                    lines.push((format!("{}:{}", path.display(), n + 1), line.to_owned()));
                }
            }
        }
    }
    lines
}

#[test]
fn no_import_crosses_the_layers() {
    let mut crossings = Vec::new();
    for (folder, banned) in BANNED {
        for (at, line) in code_lines(folder) {
            if banned.iter().any(|b| line.contains(b)) {
                crossings.push(format!("{at}: {line}"));
            }
        }
    }
    for (at, line) in code_lines("refine") {
        let reaches = line.match_indices("crate::sph").all(|(k, _)| {
            REFINE_REACHES
                .iter()
                .any(|allowed| line[k..].starts_with(allowed))
        });
        if !reaches {
            crossings.push(format!(
                "{at}: {line} (refine reaches sph beyond its operators and hooks)"
            ));
        }
    }
    crossings.extend(pipeline_reaches_into_the_scene());
    assert!(crossings.is_empty(), "{}", crossings.join("\n"));
}

/// Solvers build from their own parameters, with no scene: a block of SPH fluid and a
/// periodic grid, both in uniform motion without gravity, translate as a whole (Galilean
/// invariance: the mean velocity is kept to round-off and the SPH block's centre moves by v t).
#[test]
fn solvers_build_from_parameters_alone() {
    use eddy::grid::{GridParams, GridSide, GridSolver};
    use eddy::sph::{FluidBlock, SphParams, SphSolver};
    use eddy::stepping::StepLimits;
    use eddy::Vec3;

    let v = Vec3::new(0.3, -0.2, 0.1);
    let params = SphParams {
        spacing: 0.05,
        rest_density: 1000.0,
        blocks: vec![FluidBlock {
            min: [0.0; 3],
            max: [0.5; 3],
            velocity: v.into(),
        }],
        gravity: Vec3::zeros(),
        pressure: Default::default(),
        viscosity: Default::default(),
        wall_viscosity: Vec::new(),
        limits: StepLimits::default(),
        domain: (Vec3::repeat(-5.0), Vec3::repeat(5.0)),
        lost_fraction: 0.01,
        ramp: 0.0,
        container: false,
        inflows: Vec::new(),
        outflows: Vec::new(),
    };
    let mut sph = SphSolver::new(&params, Vec::new());
    let centre = |s: &SphSolver| s.fluid.x.iter().sum::<Vec3>() / s.fluid.len() as f64;
    let start = centre(&sph);
    for _ in 0..20 {
        sph.step(None).expect("stable");
    }
    let mean_v = sph.fluid.v.iter().sum::<Vec3>() / sph.fluid.len() as f64;
    assert!((mean_v - v).norm() < 1e-9 * v.norm(), "{mean_v:?}");
    let moved = centre(&sph) - start;
    assert!((moved - v * sph.time()).norm() < 1e-9, "{moved:?}");

    let grid = GridParams {
        resolution: [8, 8, 8],
        dx: 0.125,
        origin: Vec3::zeros(),
        initial_velocity: v,
        sides: std::array::from_fn(|_| [GridSide::Periodic, GridSide::Periodic]),
        inflow_turbulence: None,
        advection: Default::default(),
        reflection: false,
        viscosity_scheme: Default::default(),
        viscosity: 0.0,
        density: 1.0,
        confinement: 0.0,
        gravity: Vec3::zeros(),
        gravity_force: false,
        limits: StepLimits::default(),
        pressure: Default::default(),
        smoke: None,
        smoke_refinement: 1,
        average_from: None,
        container: false,
        obstacle_surface: Default::default(),
        incremental_pressure: true,
    };
    let mut g = GridSolver::new(&grid, Vec::new()).expect("grid builds");
    for _ in 0..5 {
        g.step(None).expect("stable");
    }
    let u = g.mac.velocity_at(&Vec3::new(0.4, 0.6, 0.3));
    assert!((u - v).norm() < 1e-9, "{u:?}");
}
