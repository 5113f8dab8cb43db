//! Paper cuts a new user found (issue 19): each test failed before its fix.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::mpsc;
use std::time::Duration;

use eddy::io::plot::{compare, RunSeries};
use eddy::pipeline::{run, Pipeline, Plan, RunError, RunOptions};
use eddy::scene::parse_str;

const TINY: &str = r#"name = "tiny"
gravity = [0.0, -9.81, 0.0]

[domain]
min = [0, 0, 0]
max = [1, 1, 1]

[time]
end = 1.0

[fluid]
spacing = 0.05

[[fluid.blocks]]
min = [0, 0, 0]
max = [0.5, 0.5, 0.5]
velocity = [0.0, 0.0, 0.0]

[[obstacles]]
shape = { type = "box", half_extents = [0.1, 0.1, 0.1] }
position = [0.8, 0.8, 0.8]
"#;

fn shipped(file: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(file)
}

/// A fixed-length array with more values than it holds is an error naming the key and the
/// length given, wherever it sits (top level, a block, an obstacle's shape, an override); none
/// is cut to three silently.
#[test]
fn arrays_take_exactly_their_length() {
    let cases = [
        (
            "gravity = [0.0, -9.81, 0.0]",
            "gravity = [0.0, -9.81, 0.0, 1.0]",
            "gravity",
        ),
        (
            "velocity = [0.0, 0.0, 0.0]",
            "velocity = [0.0, 0.0, 0.0, 2.0]",
            "fluid.blocks[0].velocity",
        ),
        (
            "half_extents = [0.1, 0.1, 0.1]",
            "half_extents = [0.1, 0.1, 0.1, 0.1]",
            // serde checks lengths inside a tagged shape itself, naming the shape.
            "obstacles[0].shape",
        ),
    ];
    for (good, bad, key) in cases {
        let text = TINY.replace(good, bad);
        let e = parse_str(&text, Path::new("tiny.toml"), &[]).expect_err(bad);
        let m = e.to_string();
        assert!(m.contains(key) && m.contains('4') && m.contains('3'), "{m}");
    }
    let e = parse_str(
        TINY,
        Path::new("tiny.toml"),
        &["domain.max=[1,1,1,1]".into()],
    )
    .expect_err("override with four values");
    assert!(e.to_string().contains("domain.max"), "{e}");
    parse_str(TINY, Path::new("tiny.toml"), &[]).expect("three values are fine");
}

/// Numbers in messages are short: a bound of 1e-308 is written so, not as 308 digits.
#[test]
fn numbers_in_messages_are_short() {
    let text = TINY.replace("end = 1.0", "end = 1.0\ndt_min = 1e-308\ndt_max = 1e-310");
    let m = parse_str(&text, Path::new("tiny.toml"), &[])
        .expect_err("dt_max below dt_min")
        .to_string();
    assert!(m.contains("1e-310") && m.contains("1e-308"), "{m}");
    assert!(m.len() < 200, "{m}");
}

/// `--until` must be a finite time > 0 and `--steps` at least 1.
#[test]
fn run_options_are_checked() {
    for (until, steps) in [
        (Some(f64::NAN), None),
        (Some(-1.0), None),
        (Some(f64::INFINITY), None),
        (None, Some(0)),
    ] {
        let options = RunOptions {
            out: Some(std::env::temp_dir().join("eddy_bad_option")),
            until,
            steps,
            ..RunOptions::default()
        };
        let e = run(&shipped("dam_break.toml"), &options).expect_err("refused");
        assert!(matches!(e, RunError::InvalidOption { .. }), "{e}");
    }
}

/// The command line prints an input error as one message, never a backtrace (even with
/// RUST_BACKTRACE=1), exits 1, and writes no colour codes when stderr is not a terminal.
#[test]
fn cli_errors_have_no_backtrace() {
    let _serial = common::hdf5_or_child();
    let out = Command::new(env!("CARGO_BIN_EXE_eddy"))
        .args(["run", "--plan", "--set", "time.cfl=7"])
        .arg(shipped("dam_break.toml"))
        .env("RUST_BACKTRACE", "1")
        .output()
        .expect("eddy runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("time.cfl") && stderr.contains("(0, 1]"),
        "{stderr}"
    );
    assert!(
        !stderr.contains("backtrace") && !stderr.contains("main.rs"),
        "{stderr}"
    );
    assert!(!stderr.contains('\u{1b}'), "{stderr}");
}

/// A run into a folder that holds an earlier run's files removes those (and only eddy's own
/// outputs) first, so ParaView never mixes two runs; the warning carries no colour codes.
#[test]
fn a_rerun_clears_the_earlier_outputs() {
    let _serial = common::hdf5_or_child();
    let dir = tempfile::tempdir().expect("temp dir");
    let eddy = |until: &str| {
        Command::new(env!("CARGO_BIN_EXE_eddy"))
            .args(["run", "--until", until, "--out"])
            .arg(dir.path())
            .arg(shipped("dam_break.toml"))
            .output()
            .expect("eddy runs")
    };
    assert!(eddy("0.1").status.success());
    std::fs::write(dir.path().join("notes.txt"), "mine").expect("user file");
    let second = eddy("0.04");
    assert!(second.status.success());
    let stderr = String::from_utf8_lossy(&second.stderr);
    assert!(
        stderr.contains("earlier run") && !stderr.contains('\u{1b}'),
        "{stderr}"
    );
    let names: Vec<String> = std::fs::read_dir(dir.path())
        .expect("folder")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    let frames = names.iter().filter(|n| n.ends_with(".vtp")).count();
    let pvd = std::fs::read_to_string(dir.path().join("particles.pvd")).expect("series");
    assert_eq!(frames, pvd.matches("<DataSet").count(), "{names:?}");
    assert_eq!(frames, 3, "frames at 0, 0.02, 0.04 s: {names:?}");
    assert!(names.contains(&"notes.txt".into()));
}

/// `eddy compare` finishes on metrics with infinite, NaN and +-1e308 values: non-finite points
/// are left out and counted, and the axes come from the finite ones.
#[test]
fn compare_survives_non_finite_and_huge_values() {
    let dir = tempfile::tempdir().expect("temp dir");
    let run_dir = dir.path().join("bad");
    std::fs::create_dir(&run_dir).expect("run folder");
    let mut csv = String::from("step,time,dt,kinetic_energy,total_energy,vorticity_mean\n");
    for i in 0..20 {
        let t = 0.01 * i as f64;
        let ke = match i {
            5 => "inf".to_owned(),
            6 => "NaN".to_owned(),
            _ => format!("{}", 0.5 * t),
        };
        let total = if i % 2 == 0 { "1e308" } else { "-1e308" };
        csv += &format!("{i},{t},0.01,{ke},{total},{t}\n");
    }
    std::fs::write(run_dir.join("metrics.csv"), csv).expect("metrics");
    let series = RunSeries::read(&run_dir).expect("reads");
    let png = dir.path().join("cmp.png");
    let (tx, rx) = mpsc::channel();
    let target = png.clone();
    std::thread::spawn(move || tx.send(compare(&[series], &target).map_err(|e| e.to_string())));
    let skipped = rx
        .recv_timeout(Duration::from_secs(60))
        .expect("compare finishes within a minute")
        .expect("compare succeeds");
    assert_eq!(skipped, 2);
    assert!(png.exists());
}

/// A run's `frames.h5` survives `kill -9` at any point: whenever the index exists it opens,
/// and every frame it lists reads back whole (each frame is its own file, renamed when
/// complete, and the index is rewritten whole and renamed), and its XDMF parses.
#[test]
fn hdf5_frames_survive_a_kill_at_any_point() {
    let _serial = common::hdf5_or_child();
    let mut listed = Vec::new();
    for k in 0..16u64 {
        let dir = tempfile::tempdir().expect("temp dir");
        let mut child = Command::new(env!("CARGO_BIN_EXE_eddy"))
            .args(["run", "--until", "0.6", "--out"])
            .arg(dir.path())
            .args(["--set", "output.vtk=false", "--set", "output.hdf5=true"])
            .args(["--set", "output.interval=0.005"])
            .arg(shipped("dam_break.toml"))
            .stderr(std::process::Stdio::null())
            .spawn()
            .expect("eddy starts");
        std::thread::sleep(Duration::from_millis(60 + 97 * k));
        let _ = child.kill();
        child.wait().expect("eddy ends");
        let index = dir.path().join("frames.h5");
        if !index.exists() {
            listed.push(0);
            continue;
        }
        let file = hdf5::File::open(&index).expect("the index opens after a kill");
        let frames = file.group("frames").expect("/frames");
        let names = frames.member_names().expect("frame list");
        for name in &names {
            let g = frames.group(name).expect("a listed frame opens");
            let x = g.dataset("position").expect("position");
            let n = x.shape()[0];
            assert_eq!(x.read_raw::<f64>().expect("positions read").len(), 3 * n);
            let v = g.dataset("velocity").expect("velocity");
            assert_eq!(v.read_raw::<f64>().expect("velocities read").len(), 3 * n);
            assert!(g.attr("time").is_ok() && g.attr("step").is_ok());
        }
        // The XDMF is rewritten whole after the index: it parses, and describes the frames
        // the index lists, or all but the newest.
        let xmf = dir.path().join("frames.xmf");
        if xmf.exists() {
            let text = std::fs::read_to_string(&xmf).expect("frames.xmf reads");
            let mut reader = quick_xml::Reader::from_str(&text);
            let mut times = 0;
            loop {
                match reader.read_event().expect("frames.xmf is well-formed") {
                    quick_xml::events::Event::Empty(e) if e.name().as_ref() == b"Time" => {
                        times += 1
                    }
                    quick_xml::events::Event::Eof => break,
                    _ => {}
                }
            }
            assert!(
                times == names.len() || times + 1 == names.len(),
                "{times} of {names:?}"
            );
        }
        listed.push(names.len());
    }
    // The kill points span the run: some before the first frame, most in between frames.
    let with_frames = listed.iter().filter(|&&n| n > 0).count();
    assert!(with_frames >= 8, "{listed:?}");
    assert!(listed.windows(2).any(|w| w[1] > w[0]), "{listed:?}");
}

/// A scene too large for the machine is refused before anything is allocated, with the sizes
/// and memory it would need; `--plan` states the estimate for every scene.
#[test]
fn a_scene_too_large_is_refused_up_front() {
    let s = eddy::scene::load(&shipped("dam_break.toml"), &["fluid.spacing=1e-5".into()])
        .expect("valid scene");
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || tx.send(Pipeline::build(&s).err().map(|e| e.to_string())));
    let message = rx
        .recv_timeout(Duration::from_secs(30))
        .expect("refused within seconds, not after allocating")
        .expect("refused");
    assert!(
        message.contains("fluid particles") && message.contains("has available"),
        "{message}"
    );
    let s = eddy::scene::load(&shipped("dam_break.toml"), &[]).expect("valid scene");
    let plan = Plan::of(&Pipeline::build(&s).expect("builds")).to_string();
    let memory = plan.lines().next().expect("plan");
    assert!(
        memory.starts_with("memory: about") && memory.contains("fluid particles"),
        "{plan}"
    );
}

/// Messages a TOML user can act on: a duplicate key is named, a non-UTF-8 file gives the byte
/// offset and line, a folder given as a mesh says so, and no Rust type name shows.
#[test]
fn messages_name_what_the_user_wrote() {
    let dir = tempfile::tempdir().expect("temp dir");
    let write = |name: &str, bytes: &[u8]| {
        let path = dir.path().join(name);
        std::fs::write(&path, bytes).expect("scene file");
        path
    };
    let load = |path: &Path| {
        eddy::scene::load(path, &[])
            .expect_err("refused")
            .to_string()
    };
    let m = load(&write(
        "dup.toml",
        TINY.replace("[time]", "[time]\nend = 2.0").as_bytes(),
    ));
    assert!(m.contains("duplicate key `end`"), "{m}");
    let mut bytes = b"name = \"tiny\"\n# caf".to_vec();
    bytes.extend([0xff, 0xfe, b'\n']);
    let m = load(&write("latin1.toml", &bytes));
    assert!(
        m.contains("not UTF-8") && m.contains("byte offset 19") && m.contains("line 2"),
        "{m}"
    );
    let folder = dir.path().join("meshes");
    std::fs::create_dir(&folder).expect("folder");
    let text = TINY.replace(
        "shape = { type = \"box\", half_extents = [0.1, 0.1, 0.1] }",
        &format!(
            "shape = {{ type = \"mesh\", path = {:?} }}",
            folder.display().to_string()
        ),
    );
    let m = load(&write("folder.toml", text.as_bytes()));
    assert!(
        m.contains("folder") && m.contains("obstacles[0].shape.path"),
        "{m}"
    );
    let text = TINY.replace(
        "shape = { type = \"box\", half_extents = [0.1, 0.1, 0.1] }",
        "shape = 5",
    );
    let m = load(&write("five.toml", text.as_bytes()));
    assert!(
        m.contains("a table with a `type` key") && !m.contains("enum"),
        "{m}"
    );
}

/// Input that was accepted and should not be: an obstacle or keyframe outside the domain, a
/// fluid block too thin to hold a particle, and inflow into a grid with no way out.
#[test]
fn impossible_set_ups_are_refused() {
    let refuse = |text: String, key: &str| {
        let m = parse_str(&text, Path::new("tiny.toml"), &[])
            .expect_err(key)
            .to_string();
        assert!(m.contains(key), "{key}: {m}");
    };
    refuse(
        TINY.replace("position = [0.8, 0.8, 0.8]", "position = [0.8, -8.0, 0.8]"),
        "obstacles[0].position[1]",
    );
    refuse(
        TINY.replace(
            "position = [0.8, 0.8, 0.8]",
            "position = [0.8, 0.8, 0.8]\nmotion = { keyframes = [{ t = 0.0, position = [0.8, 0.8, 0.8] }, \
             { t = 1.0, position = [0.8, 0.8, 3.0] }] }",
        ),
        "obstacles[0].motion.keyframes[1].position[2]",
    );
    refuse(
        TINY.replace("max = [0.5, 0.5, 0.5]", "max = [0.5, 0.03, 0.5]"),
        "fluid.blocks[0].max[1]",
    );
    let grid = |boundary: &str| {
        format!(
            "name = \"g\"\n[domain]\nmin = [0, 0, 0]\nmax = [1, 1, 1]\n[time]\nend = 1.0\n\
             [grid]\nresolution = [8, 8, 8]\nboundary = {{ {boundary} }}\n"
        )
    };
    refuse(
        grid("x_min = { inflow = [1.0, 0.0, 0.0] }"),
        "grid.boundary",
    );
    for ok in [
        "x_min = { inflow = [1.0, 0.0, 0.0] }, x_max = \"open\"",
        "x_min = { inflow = [1.0, 0.0, 0.0] }, x_max = { inflow = [1.0, 0.0, 0.0] }",
    ] {
        parse_str(&grid(ok), Path::new("g.toml"), &[]).expect(ok);
    }
}

/// The refinement scenes write frames by default: a user wants to look at them. Each scene's
/// frame at t = 0 is written, as a run writes it, and holds every fluid particle.
#[test]
fn refinement_scenes_write_frames() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut checked = 0;
    for entry in std::fs::read_dir(&dir).expect("scenes") {
        let path = entry.expect("entry").path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        if name.starts_with("refine_") && name.ends_with(".toml") {
            let s = eddy::scene::load(&path, &[]).expect("shipped scene loads");
            let out = tempfile::tempdir().expect("temp dir");
            let _serial = common::hdf5_or_child();
            let mut p = eddy::pipeline::Pipeline::build(&s).expect("the scene builds");
            p.open(out.path()).expect("its outputs open");
            p.outputs.write(&p.sim).expect("the first frame is written");
            let frame = std::fs::read(out.path().join("particles_000000.vtp"))
                .unwrap_or_else(|e| panic!("{name} writes no particle frame: {e}"));
            // The XML header is text; the appended arrays after it are not.
            let frame = String::from_utf8_lossy(&frame);
            let n = p.sim.sph.as_ref().expect("an SPH scene").fluid.len();
            assert!(
                frame.contains(&format!("NumberOfPoints=\"{n}\"")),
                "{name}: the frame does not hold its {n} particles"
            );
            checked += 1;
        }
    }
    assert!(checked >= 9);
}

/// The resolved `scene.toml` records `--until` and `--steps`: rerunning it reproduces the run.
#[test]
fn the_resolved_scene_records_until_and_steps() {
    let _serial = common::hdf5_or_child();
    for (until, steps) in [(Some(0.05), None), (None, Some(4))] {
        let dir = tempfile::tempdir().expect("temp dir");
        let options = RunOptions {
            out: Some(dir.path().join("first")),
            overrides: vec!["output.vtk=false".into()],
            until,
            steps,
            ..RunOptions::default()
        };
        let first = run(&shipped("dam_break.toml"), &options).expect("runs");
        let resolved = dir.path().join("first/scene.toml");
        let again = RunOptions {
            out: Some(dir.path().join("again")),
            ..RunOptions::default()
        };
        let second = run(&resolved, &again).expect("the resolved scene runs");
        assert_eq!((second.steps, second.time), (first.steps, first.time));
        let metrics = |run: &str| {
            let text =
                std::fs::read_to_string(dir.path().join(run).join("metrics.csv")).expect("metrics");
            text.lines()
                .map(|l| l.split(',').take(5).collect::<Vec<_>>().join(","))
                .collect::<Vec<_>>()
        };
        assert_eq!(metrics("first"), metrics("again"));
    }
}

/// Issue 52, 1: in a scene with a grid and a fluid (no coupling) the container is the water's
/// tank, open to the air inside. One as large as the domain (the natural set-up) was refused as
/// an obstacle covering every cell; a smaller one made the inside of the tank solid to the air.
#[test]
fn a_domain_sized_container_leaves_the_air_inside_it_open() {
    for half in [0.5, 0.45] {
        let text = format!(
            "name = \"tank\"\n[domain]\nmin = [0, 0, 0]\nmax = [1, 1, 1]\n[time]\nsteps = 3\n\
             [fluid]\nspacing = 0.05\n[[fluid.blocks]]\nmin = [0.1, 0.1, 0.1]\n\
             max = [0.5, 0.4, 0.5]\n[container]\n\
             shape = {{ type = \"box\", half_extents = [{half}, {half}, {half}] }}\n\
             position = [0.5, 0.5, 0.5]\n[grid]\nresolution = [16, 16, 16]\n\
             [output]\nvtk = false\nmetrics = []\n"
        );
        let scene = parse_str(&text, Path::new("tank.toml"), &[]).expect("the scene");
        let mut p = Pipeline::build(&scene).expect("a container as large as the domain runs");
        for _ in 0..3 {
            p.step(None, None).expect("steps");
        }
        let grid = common::grid(&p);
        let (mut inside, mut solid) = (0, 0);
        for i in 0..16 {
            for j in 0..16 {
                for k in 0..16 {
                    let c = grid.mac.cell_center([i, j, k]);
                    if (0..3).all(|a| (c[a] - 0.5).abs() < half) {
                        inside += 1;
                        solid += usize::from(grid.bounds.is_solid([i, j, k]));
                    }
                }
            }
        }
        assert!(inside > 2000, "{inside} cells inside the tank");
        assert_eq!(
            solid, 0,
            "half extent {half}: {solid} of {inside} cells solid"
        );
    }
}

/// Issue 52, 2: smoke sources that cannot work are refused with their key (one outside the
/// domain, a density or buoyancy of 1e300), and one smaller than a cell, which emits nothing,
/// is run with a warning that names it.
#[test]
fn smoke_sources_that_cannot_work_are_named() {
    let scene = |source: &str, buoyancy: &str| {
        format!(
            "name = \"plume\"\n[domain]\nmin = [0, 0, 0]\nmax = [0.16, 0.16, 0.16]\n[time]\n\
             steps = 1\n[grid]\nresolution = [16, 16, 16]\n[grid.smoke]\nbuoyancy = {buoyancy}\n\
             [[grid.smoke.sources]]\n{source}\n[output]\nvtk = false\nmetrics = []\n"
        )
    };
    let ball = |radius: &str, at: &str, density: &str| {
        format!(
            "shape = {{ type = \"sphere\", radius = {radius} }}\nposition = {at}\n\
             density = {density}"
        )
    };
    let inside = "[0.08, 0.08, 0.08]";
    for (text, key) in [
        (
            scene(&ball("0.02", "[0.08, 0.5, 0.08]", "1.0"), "1.0"),
            "grid.smoke.sources[0].position[1]",
        ),
        (
            scene(&ball("0.02", inside, "1e300"), "1.0"),
            "grid.smoke.sources[0].density",
        ),
        (
            scene(&ball("0.02", inside, "1.0"), "1e300"),
            "grid.smoke.buoyancy",
        ),
    ] {
        let err = parse_str(&text, Path::new("plume.toml"), &[]).expect_err("refused");
        assert!(err.to_string().contains(key), "{err} should name {key}");
    }
    // Radius 8e-5 m on a 1 cm grid, off the cell centres: valid, but it covers no cell.
    let dir = tempfile::tempdir().expect("temp dir");
    let file = dir.path().join("plume.toml");
    std::fs::write(
        &file,
        scene(&ball("8e-5", "[0.08, 0.08, 0.08]", "1.0"), "1.0"),
    )
    .expect("writes the scene");
    let out = Command::new(env!("CARGO_BIN_EXE_eddy"))
        .args(["run", "--out"])
        .arg(dir.path().join("out"))
        .arg(&file)
        .output()
        .expect("eddy runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains("grid.smoke.sources[0] covers no cell"),
        "{stderr}"
    );
}

/// Issue 52, 4: the memory estimate a run is admitted by bounds what the SPH set-up allocates,
/// the neighbour lists and pair caches included, for every shipped SPH scene (those needing a
/// precomputed database aside). What a refinement's step hook adds once it has stepped is
/// measured as heap in `tests/memory_estimate.rs`, a test binary of its own.
#[test]
fn the_memory_estimate_bounds_the_sph_set_up() {
    let mut checked = 0;
    for entry in std::fs::read_dir(shipped("")).expect("scenes") {
        let path = entry.expect("entry").path();
        let text = std::fs::read_to_string(&path).unwrap_or_default();
        if path.extension().is_none_or(|e| e != "toml") || text.contains("abl =") {
            continue;
        }
        let scene = eddy::scene::load(&path, &[]).expect("a shipped scene loads");
        if scene.fluid.is_none() {
            continue;
        }
        let spec = eddy::scene::build::run_spec(&scene).expect("the run");
        let estimate = eddy::pipeline::Footprint::of(&spec).bytes;
        let p = Pipeline::build(&scene).expect("builds");
        let used = p.sim.sph.as_ref().expect("a fluid").memory_bytes() as f64;
        assert!(
            used <= estimate,
            "{}: {used:.3e} B allocated, {estimate:.3e} B estimated",
            path.display()
        );
        checked += 1;
    }
    assert!(checked >= 10, "{checked} scenes");
}
