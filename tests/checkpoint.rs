//! Checkpoints and resume: a run stopped at a checkpoint and resumed ends in exactly the state
//! of the run that never stopped (every saved array bit for bit, its series equal but for the
//! wall-time columns, its frames byte for byte); SIGTERM leaves a checkpoint a resume goes on
//! from; a checkpoint of another scene is refused.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

use eddy::pipeline::{Run, RunOptions};
use eddy::scene::Scene;
use eddy::state::{State, Values};

fn scene(text: &str) -> Scene {
    eddy::scene::parse_str(text, Path::new("checkpoint_test.toml"), &[]).expect("the scene loads")
}

fn options(out: &Path, resume: bool) -> RunOptions {
    RunOptions {
        out: Some(out.to_path_buf()),
        resume,
        ..RunOptions::default()
    }
}

/// Two states equal bit for bit (NaN and the sign of zero included), named entry by entry.
fn assert_same(a: &State, b: &State) {
    let (ea, eb): (Vec<_>, Vec<_>) = (a.entries().collect(), b.entries().collect());
    let names = |e: &[(&str, &Values)]| e.iter().map(|(n, _)| n.to_string()).collect::<Vec<_>>();
    assert_eq!(names(&ea), names(&eb));
    for ((name, x), (_, y)) in ea.iter().zip(&eb) {
        let same = match (x, y) {
            (Values::F64(x), Values::F64(y)) => {
                x.len() == y.len() && x.iter().zip(y).all(|(p, q)| p.to_bits() == q.to_bits())
            }
            _ => x == y,
        };
        assert!(same, "{name} differs after the resume");
    }
}

/// A CSV series without its wall-time columns (`*_seconds`).
fn without_timings(path: &Path) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(path).expect("the series reads");
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("a header").split(',').collect();
    let keep: Vec<bool> = header.iter().map(|c| !c.ends_with("_seconds")).collect();
    std::iter::once(header.join(","))
        .chain(lines.map(str::to_owned))
        .map(|l| {
            l.split(',')
                .zip(&keep)
                .filter(|(_, k)| **k)
                .map(|(v, _)| v.to_owned())
                .collect()
        })
        .collect()
}

/// Two HDF5 frame series list the same frames, each with the same values.
fn assert_same_frames(a: &Path, b: &Path) {
    let (fa, fb) = (hdf5::File::open(a).unwrap(), hdf5::File::open(b).unwrap());
    let Ok(frames) = fa.group("frames") else {
        return; // a coupled run's frames.h5 only links the two series
    };
    let names = frames.member_names().unwrap();
    assert_eq!(names, fb.group("frames").unwrap().member_names().unwrap());
    for name in &names {
        let (ga, gb) = (
            frames.group(name).unwrap(),
            fb.group(&format!("frames/{name}")).unwrap(),
        );
        for field in ga.member_names().unwrap() {
            let Ok(da) = ga.dataset(&field) else {
                continue;
            };
            let x: Vec<f64> = da.read_raw().unwrap();
            let y: Vec<f64> = gb.dataset(&field).unwrap().read_raw().unwrap();
            assert!(
                x.iter().zip(&y).all(|(p, q)| p.to_bits() == q.to_bits()) && x.len() == y.len(),
                "{}: frame {name}, {field}",
                a.display()
            );
        }
    }
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        std::fs::copy(entry.path(), to.join(entry.file_name())).unwrap();
    }
}

/// Runs `scene` to its end in `a`, writing a checkpoint after `at` steps and copying the
/// folder as it stands then into `b` (a row written after the checkpoint is appended to each
/// series there, as a run killed later leaves it); resumes in `b` to the end. Both end in the
/// same state, series and frames.
fn stopped_and_resumed_equals_uninterrupted(scene: &Scene, at: u64) {
    let _serial = common::hdf5_or_child();
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    let mut run = Run::start(scene, &options(&a, false)).expect("the run starts");
    while run.advance(None).expect("a step").is_some() {
        if run.pipeline.sim.steps() == at {
            run.checkpoint().expect("the checkpoint is written");
            copy_dir(&a, &b);
        }
    }
    assert!(
        run.pipeline.sim.steps() > at + 2,
        "the run ends after the checkpoint"
    );
    let end_a = run.pipeline.save_state();
    run.finish().unwrap();
    for csv in ["metrics.csv", "probes.csv"] {
        let path = b.join(csv);
        if path.exists() {
            let mut text = std::fs::read_to_string(&path).unwrap();
            let last = text.lines().last().unwrap().to_owned();
            text += &format!("{last}\n");
            std::fs::write(&path, text).unwrap();
        }
    }

    let mut resumed = Run::resume(scene, &options(&b, true)).expect("the run resumes");
    assert_eq!(resumed.pipeline.sim.steps(), at);
    while resumed.advance(None).expect("a step").is_some() {}
    assert_same(&end_a, &resumed.pipeline.save_state());
    resumed.finish().unwrap();

    let mut compared = 0;
    for entry in std::fs::read_dir(&a).unwrap() {
        let name = entry.unwrap().file_name();
        let (fa, fb) = (a.join(&name), b.join(&name));
        let name = name.to_string_lossy().into_owned();
        if name.ends_with(".csv") {
            assert_eq!(without_timings(&fa), without_timings(&fb), "{name}");
        } else if name.ends_with(".xmf") {
            let text = |p: &Path| std::fs::read_to_string(p).unwrap();
            assert_eq!(text(&fa), text(&fb), "{name}");
        } else if name.ends_with("frames.h5") {
            assert_same_frames(&fa, &fb);
        } else if name.ends_with(".vtu") || name.ends_with(".vti") || name.ends_with(".vtp") {
            assert!(
                std::fs::read(&fa).unwrap() == std::fs::read(&fb).unwrap(),
                "{name} differs"
            );
        } else {
            continue;
        }
        compared += 1;
    }
    assert!(compared >= 4, "{compared} files compared");
}

/// The channel of a ball crossing it (moving boundaries every step) with boundary layers from a
/// synthetic database, smoke, running statistics with a station, a probe.
fn grid_scene(db: &Path) -> Scene {
    scene(&format!(
        r#"
        name = "channel"
        gravity = [0.0, 0.0, 0.0]
        seed = 3
        domain = {{ min = [0.0, 0.0, 0.0], max = [1.5, 1.0, 1.0] }}
        time = {{ end = 0.5, cfl = 0.8, dt_max = 0.05 }}
        viscosity = {{ kinematic = 0.001 }}
        [grid]
        resolution = [18, 12, 12]
        initial_velocity = [1.0, 0.0, 0.0]
        boundary = {{ x_min = {{ inflow = [1.0, 0.0, 0.0] }}, x_max = "open" }}
        [grid.smoke]
        buoyancy = 0.0
        [[grid.smoke.sources]]
        shape = {{ type = "box", half_extents = [0.1, 0.2, 0.2] }}
        position = [0.2, 0.5, 0.5]
        density = 1.0
        [[obstacles]]
        name = "ball"
        shape = {{ type = "sphere", radius = 0.2 }}
        position = [0.6, 0.4, 0.5]
        motion = {{ linear = [0.0, 0.3, 0.0] }}
        {abl}
        [turbulence]
        c_p = 20.0
        [statistics]
        from = 0.1
        batches = 2
        [[statistics.stations]]
        name = "wake"
        min = [0.9, 0.0, 0.0]
        max = [1.2, 1.0, 1.0]
        axis = "y"
        bins = 4
        [[probes]]
        type = "point"
        name = "wake"
        position = [1.0, 0.5, 0.5]
        [output]
        interval = 0.1
        hdf5 = true
        "#,
        abl = common::abl_line(db)
    ))
}

#[test]
fn a_grid_run_with_boundary_layers_smoke_and_statistics_resumes_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let db = common::ball_database(dir.path(), 0.2);
    let s = grid_scene(&db);
    stopped_and_resumed_equals_uninterrupted(&s, 7);
}

#[test]
fn a_checkpoint_of_another_scene_is_refused_with_the_difference() {
    let dir = tempfile::tempdir().unwrap();
    let db = common::ball_database(dir.path(), 0.2);
    let out = dir.path().join("run");
    let s = grid_scene(&db);
    {
        let _serial = common::hdf5_or_child();
        let mut run = Run::start(&s, &options(&out, false)).unwrap();
        run.advance(None).unwrap();
        run.advance(None).unwrap();
        run.checkpoint().unwrap();
    }
    let other = eddy::scene::parse_str(
        &s.to_toml(),
        Path::new("other.toml"),
        &["viscosity.kinematic=0.002".into()],
    )
    .unwrap();
    let _serial = common::hdf5_or_child();
    let e = Run::resume(&other, &options(&out, true))
        .err()
        .expect("refused");
    let text = e.to_string();
    assert!(
        text.contains("another scene") && text.contains("0.002"),
        "{text}"
    );
    // Only the end time and the outputs may change.
    let longer = eddy::scene::parse_str(
        &s.to_toml(),
        Path::new("longer.toml"),
        &["time.end=0.6".into(), "output.interval=0.05".into()],
    )
    .unwrap();
    let run = Run::resume(&longer, &options(&out, true)).expect("a later end resumes");
    assert_eq!(run.pipeline.sim.steps(), 2);
    // Without a checkpoint there is nothing to go on from.
    let e = Run::resume(&s, &options(&dir.path().join("none"), true))
        .err()
        .expect("refused");
    assert!(e.to_string().contains("no checkpoint"), "{e}");
}

fn eddy() -> Command {
    Command::new(env!("CARGO_BIN_EXE_eddy"))
}

fn last_row(dir: &Path) -> Vec<String> {
    without_timings(&dir.join("metrics.csv"))
        .pop()
        .expect("a row")
}

/// SIGTERM to a running `eddy run` leaves a checkpoint and exits with status 75; `eddy
/// resume` goes on from it to the end the uninterrupted run reaches.
#[test]
fn sigterm_leaves_a_checkpoint_that_resumes_to_the_same_end() {
    let dir = tempfile::tempdir().unwrap();
    let db = common::ball_database(dir.path(), 0.2);
    let file = dir.path().join("channel.toml");
    let mut s = grid_scene(&db);
    s.time.end = Some(1.5);
    std::fs::write(&file, s.to_toml()).unwrap();
    let (whole, stopped) = (dir.path().join("whole"), dir.path().join("stopped"));
    let _serial = common::hdf5_or_child();
    let status = eddy()
        .args(["run", "--out"])
        .arg(&whole)
        .arg(&file)
        .stderr(std::process::Stdio::null())
        .status()
        .unwrap();
    assert!(status.success());
    let child = eddy()
        .args(["run", "--out"])
        .arg(&stopped)
        .arg(&file)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let rows = |d: &PathBuf| {
        std::fs::read_to_string(d.join("metrics.csv")).map_or(0, |t| t.lines().count())
    };
    while rows(&stopped) < 10 {
        std::thread::sleep(Duration::from_millis(5));
    }
    let pid = child.id().to_string();
    assert!(Command::new("kill")
        .args(["-TERM", &pid])
        .status()
        .unwrap()
        .success());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(75), "{stderr}");
    assert!(stderr.contains("eddy resume"), "{stderr}");
    assert!(stopped.join("checkpoint.h5").exists());
    assert!(rows(&stopped) < rows(&whole), "stopped before the end");
    let status = eddy()
        .arg("resume")
        .arg(&stopped)
        .stderr(std::process::Stdio::null())
        .status()
        .unwrap();
    assert!(status.success());
    assert_eq!(
        without_timings(&whole.join("metrics.csv")),
        without_timings(&stopped.join("metrics.csv"))
    );
    assert_eq!(last_row(&whole), last_row(&stopped));
}

fn shipped(name: &str, overrides: &[&str]) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name);
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    eddy::scene::load(&path, &overrides).expect("the shipped scene loads")
}

/// The stream past a ball (an inflow, an outflow) with boundary layers on the ball from a
/// synthetic database, VRSPH, and the statistics on their bins.
#[test]
fn an_sph_run_with_open_boundaries_a_refinement_and_statistics_resumes_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let db = common::ball_database(dir.path(), 0.08);
    let abl = format!("obstacles.3.abl.database={:?}", db.display().to_string());
    let s = shipped(
        "abl_sph_stream_ball.toml",
        &[
            &abl,
            "fluid.spacing=0.04",
            "time.end=0.12",
            "output.interval=0.03",
            "output.hdf5=true",
            "turbulence.c_p=200.0",
            "refinement.method=\"vrsph\"",
            "statistics.from=0.02",
            "statistics.batches=2",
        ],
    );
    stopped_and_resumed_equals_uninterrupted(&s, 12);
}

/// Air over a tank of water: the grid, the particles and the exchange between them.
#[test]
fn a_coupled_run_with_statistics_resumes_bit_for_bit() {
    let s = shipped(
        "coupled_tank_and_plume.toml",
        &[
            "fluid.spacing=0.04",
            "grid.resolution=[16,16,8]",
            "time.end=0.15",
            "output.interval=0.05",
            "output.hdf5=true",
            "statistics.from=0.0",
        ],
    );
    stopped_and_resumed_equals_uninterrupted(&s, 5);
}

/// `kill -9` at any point of a run that writes a checkpoint every step or two leaves, whenever
/// there is one, a checkpoint that reads whole and resumes: each is written under a temporary
/// name and renamed.
#[test]
fn a_kill_during_a_checkpoint_write_keeps_the_previous_one() {
    let dir = tempfile::tempdir().unwrap();
    let db = common::ball_database(dir.path(), 0.2);
    let file = dir.path().join("channel.toml");
    let mut s = grid_scene(&db);
    s.time.end = Some(2.0);
    s.output.checkpoint_interval = Some(0.01);
    s.output.vtk = false;
    std::fs::write(&file, s.to_toml()).unwrap();
    let _serial = common::hdf5_or_child();
    let mut resumed = 0;
    for k in 0..8u64 {
        let out = dir.path().join(format!("run{k}"));
        let mut child = eddy()
            .args(["run", "--out"])
            .arg(&out)
            .arg(&file)
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(Duration::from_millis(150 + 61 * k));
        let _ = child.kill();
        child.wait().unwrap();
        if !out.join("checkpoint.h5").exists() {
            continue;
        }
        let stored = eddy::io::read_checkpoint(&out.join("checkpoint.h5"))
            .expect("the last whole checkpoint reads after a kill");
        let t = stored.number("time").expect("its time");
        let status = eddy()
            .args(["resume", "--until"])
            .arg((t + 0.02).to_string())
            .arg(&out)
            .stderr(std::process::Stdio::null())
            .status()
            .unwrap();
        assert!(status.success(), "resuming after kill {k} at t = {t}");
        resumed += 1;
    }
    assert!(resumed >= 4, "{resumed} of 8 kills left a checkpoint");
}

/// Checkpoints come at the first step on or after each multiple of
/// `output.checkpoint_interval`, and after every step when `output.checkpoint_every` has
/// passed since the last.
#[test]
fn checkpoints_follow_their_schedule() {
    let dir = tempfile::tempdir().unwrap();
    let db = common::ball_database(dir.path(), 0.2);
    let mut s = grid_scene(&db);
    s.output.vtk = false;
    s.output.checkpoint_interval = Some(0.15);
    let _serial = common::hdf5_or_child();
    let out = dir.path().join("by_time");
    let mut run = Run::start(&s, &options(&out, false)).unwrap();
    let mut times = Vec::new();
    while run.advance(None).unwrap().is_some() {
        let stored = eddy::io::read_checkpoint(&out.join("checkpoint.h5"));
        if let Some(t) = stored.ok().and_then(|c| c.number("time")) {
            if times.last() != Some(&t) {
                times.push(t);
            }
        }
    }
    assert_eq!(times.len(), 3, "{times:?}");
    for (k, t) in times.iter().enumerate() {
        let due = 0.15 * (k + 1) as f64;
        assert!(*t >= due - 1e-12 && *t < due + 0.05, "{times:?}");
    }
    s.output.checkpoint_interval = None;
    s.output.checkpoint_every = Some(1e-9);
    let out = dir.path().join("by_wall");
    let mut run = Run::start(&s, &options(&out, false)).unwrap();
    for _ in 0..3 {
        run.advance(None).unwrap();
    }
    let stored = eddy::io::read_checkpoint(&out.join("checkpoint.h5")).unwrap();
    assert_eq!(stored.number("step"), Some(3.0));
}
