//! `eddy slice`: a colour map of a run's HDF5 frames whose colours follow the field, on the grid
//! (a Taylor–Green frame, whose extremes and their places are known) and on particles, and the
//! requests it refuses.

mod common;

use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use std::process::Command;

use eddy::io::slice::{draw, SliceKind, SliceOptions, SliceSummary};
use eddy::io::FrameChoice;
use eddy::metrics::Axis;
use eddy::pipeline::{resolve, run_scene, RunOptions};

/// The ends of the viridis colour map (matplotlib's values, rounded).
const BOTTOM: [u8; 3] = [68, 1, 84];
const TOP: [u8; 3] = [253, 231, 37];

/// Runs `scene` (in `scenes/`) for `steps` steps into `out`, a frame every 0.01 s in HDF5 only.
fn simulate(scene: &str, out: &Path, steps: u64) {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(scene);
    let options = RunOptions {
        out: Some(out.to_path_buf()),
        overrides: [
            "output.hdf5=true",
            "output.vtk=false",
            "output.interval=0.01",
        ]
        .map(String::from)
        .to_vec(),
        steps: Some(steps),
        progress: false,
        ..RunOptions::default()
    };
    let scene = resolve(&path, &options).expect("the scene loads");
    run_scene(&scene, &options).expect("the run finishes");
}

/// The Taylor–Green scene, 64 x 64 cells of 2 pi / 64 over [0, 2 pi]^2, 4 steps of 0.01 s: a
/// frame at t = 0, 0.01, ..., 0.04.
fn taylor_green(dir: &Path) -> PathBuf {
    let out = dir.join("tg");
    simulate("taylor_green.toml", &out, 4);
    out
}

fn options(field: &str, axis: Axis, out: PathBuf) -> SliceOptions {
    SliceOptions {
        field: field.into(),
        axis,
        at: None,
        frame: FrameChoice::Last,
        kind: None,
        out,
    }
}

/// The image pixel (column, row) of the point `p` (m) of the plot, from the plot area's pixels
/// and the metres it spans; rows grow downwards.
fn pixel(s: &SliceSummary, p: [f64; 2]) -> (u32, u32) {
    let fraction = |d: usize| (p[d] - s.extent[d].start) / (s.extent[d].end - s.extent[d].start);
    let [cols, rows] = &s.pixels;
    let col = cols.start as f64 + fraction(0) * (cols.end - cols.start) as f64;
    let row = rows.end as f64 - fraction(1) * (rows.end - rows.start) as f64;
    (col.round() as u32, row.round() as u32)
}

fn close(a: [u8; 3], b: [u8; 3], tolerance: u8) -> bool {
    a.iter().zip(&b).all(|(x, y)| x.abs_diff(*y) <= tolerance)
}

#[test]
fn a_taylor_green_slice_is_coloured_by_the_fields_extremes_where_they_lie() {
    let _serial = common::hdf5_or_child();
    let dir = tempfile::tempdir().unwrap();
    let run = taylor_green(dir.path());
    let h = 2.0 * PI / 64.0;
    // u = A sin x cos y, v = -A cos x sin y with A = exp(-2 nu t), nu = 0.1. Cell centres miss
    // the peaks by half a cell on each axis and the face-to-centre average takes one more
    // cos(h / 2): the sampled extremes are +-A cos^3(h / 2).
    let extreme = |t: f64| (-2.0 * 0.1 * t).exp() * (0.5 * h).cos().powi(3);
    let centre = |i: usize, j: usize| [(i as f64 + 0.5) * h, (j as f64 + 0.5) * h];
    // Each field with cells at its maximum and at its minimum: velocity.x peaks at x = pi / 2
    // and dips at 3 pi / 2 (y = 0), which a flip in x or a swap of the axes would move;
    // velocity.y peaks at (pi, pi / 2) and dips at (0, pi / 2) and (pi, 3 pi / 2), which a flip
    // in y would swap.
    let cases = [
        (
            "velocity.x",
            vec![(15, 0), (16, 63)],
            vec![(47, 0), (48, 63)],
        ),
        (
            "velocity.y",
            vec![(31, 15), (32, 16)],
            vec![(0, 15), (31, 47)],
        ),
    ];
    for (field, top, bottom) in cases {
        let png = dir.path().join(format!("{field}.png"));
        let s = draw(&run, &options(field, Axis::Z, png.clone())).expect("draws");
        assert_eq!(
            (s.kind, s.frame, s.count, s.non_finite),
            (SliceKind::Grid, 4, 4096, 0)
        );
        assert!(
            (s.time - 0.04).abs() < 1e-12,
            "the last frame's time: {}",
            s.time
        );
        assert_eq!(s.axes, [Axis::X, Axis::Y]);
        // The grid is one cell thick in z: its middle is that cell's centre.
        assert!((s.at - 0.5 * h).abs() < 1e-12, "at {}", s.at);
        for r in &s.extent {
            assert!(
                r.start.abs() < 1e-12 && (r.end - 2.0 * PI).abs() < 1e-9,
                "{r:?}"
            );
        }
        let a = extreme(s.time);
        assert!(
            (s.max - a).abs() < 1e-3,
            "{field}: max {} against {a}",
            s.max
        );
        assert!(
            (s.min + a).abs() < 1e-3,
            "{field}: min {} against {}",
            s.min,
            -a
        );
        let image = image::open(&png).expect("the PNG decodes").to_rgb8();
        let colour = |(i, j): (usize, usize)| {
            let (col, row) = pixel(&s, centre(i, j));
            image
                .get_pixel_checked(col, row)
                .expect("inside the image")
                .0
        };
        for cell in top {
            let c = colour(cell);
            assert!(
                close(c, TOP, 4),
                "{field}: cell {cell:?} is {c:?}, not the top {TOP:?}"
            );
        }
        for cell in bottom {
            let c = colour(cell);
            assert!(
                close(c, BOTTOM, 4),
                "{field}: cell {cell:?} is {c:?}, not the bottom {BOTTOM:?}"
            );
        }
    }
}

/// `eddy slice ARGS` through the binary: whether it succeeded, and its standard error.
fn eddy_slice(args: &[&str]) -> (bool, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_eddy"))
        .arg("slice")
        .args(args)
        .output()
        .expect("eddy runs");
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!stderr.contains("panicked"), "{stderr}");
    (out.status.success(), stderr)
}

fn text(p: &Path) -> &str {
    p.to_str().expect("a UTF-8 temporary path")
}

#[test]
fn frames_are_picked_by_index_or_by_the_nearest_time() {
    let _serial = common::hdf5_or_child();
    let dir = tempfile::tempdir().unwrap();
    let run = taylor_green(dir.path());
    let png = dir.path().join("f.png");
    let pick = |frame| {
        let opts = SliceOptions {
            frame,
            ..options("velocity.x", Axis::Z, png.clone())
        };
        let s = draw(&run, &opts).expect("draws");
        (s.frame, s.time, s.max)
    };
    let (frame, time, first) = pick(FrameChoice::Index(0));
    assert_eq!((frame, time), (0, 0.0));
    let (.., last) = pick(FrameChoice::Last);
    assert!(first > last + 5e-3, "the flow decays: {first} then {last}");
    assert_eq!(pick(FrameChoice::Time(0.021)).0, 2);
    assert_eq!(pick(FrameChoice::Time(0.024)).0, 2);
    assert_eq!(pick(FrameChoice::Time(0.026)).0, 3);
    assert_eq!(pick(FrameChoice::Time(1e9)).0, 4);
    // The command line: --time, an SVG, and the summary line.
    let svg = dir.path().join("f.svg");
    let (ok, stderr) = eddy_slice(&[
        text(&run),
        "--field",
        "velocity",
        "--axis",
        "x",
        "--time",
        "0.011",
        "--out",
        text(&svg),
    ]);
    assert!(ok, "{stderr}");
    assert!(
        stderr.contains("velocity on x = ") && stderr.contains("frame 1 at t = 0.01 s"),
        "{stderr}"
    );
    assert!(
        stderr.contains("64 cells"),
        "a layer across x is 64 x 1 cells: {stderr}"
    );
    let svg = std::fs::read_to_string(&svg).expect("the SVG is written");
    assert!(
        svg.starts_with("<svg") && svg.contains("velocity, x = "),
        "{}",
        &svg[..200.min(svg.len())]
    );
}

#[test]
fn a_coupled_runs_particles_are_drawn_as_dots_coloured_by_density() {
    let _serial = common::hdf5_or_child();
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("coupled");
    simulate("coupled_tank_and_plume.toml", &run, 2);
    let png = dir.path().join("dots.png");
    let grid = draw(&run, &options("pressure", Axis::Z, png.clone())).expect("draws");
    assert_eq!(
        grid.kind,
        SliceKind::Grid,
        "a run with both draws its grid by default"
    );
    let opts = SliceOptions {
        kind: Some(SliceKind::Particles),
        ..options("density", Axis::Z, png.clone())
    };
    let s = draw(&run, &opts).expect("draws");
    assert_eq!((s.kind, s.frame), (SliceKind::Particles, 1));
    assert!(s.count > 0 && s.non_finite == 0, "{s:?}");
    assert!(
        s.file.ends_with("particles_frames.h5"),
        "{}",
        s.file.display()
    );
    assert!(
        500.0 < s.min && s.min < s.max && s.max < 1100.0,
        "densities {} to {}",
        s.min,
        s.max
    );
    // The densest and the thinnest particles show in the map's end colours.
    let image = image::open(&png).expect("the PNG decodes").to_rgb8();
    let [cols, rows] = &s.pixels;
    let shown = |end: [u8; 3]| {
        (rows.start..rows.end)
            .flat_map(|r| (cols.start..cols.end).map(move |c| (c as u32, r as u32)))
            .any(|(c, r)| close(image.get_pixel(c, r).0, end, 4))
    };
    assert!(
        shown(TOP) && shown(BOTTOM),
        "both ends of the colour map are drawn"
    );
    let (ok, stderr) = eddy_slice(&[
        text(&run),
        "--field",
        "density",
        "--axis",
        "z",
        "--kind",
        "particles",
        "--out",
        text(&dir.path().join("cli.png")),
    ]);
    assert!(ok && stderr.contains("particles from"), "{stderr}");
}

#[test]
fn bad_fields_positions_frames_and_files_are_refused() {
    let _serial = common::hdf5_or_child();
    let dir = tempfile::tempdir().unwrap();
    let run = taylor_green(dir.path());
    let png = dir.path().join("never.png");
    let refused = |opts: SliceOptions| {
        let e = draw(&run, &opts).expect_err("refused").to_string();
        assert!(!png.exists(), "no figure for a refused request: {e}");
        e
    };
    let e = refused(options("presure", Axis::Z, png.clone()));
    assert!(
        e.contains("`presure`") && e.contains("pressure") && e.contains("velocity (vector)"),
        "{e}"
    );
    let e = refused(options("pressure.x", Axis::Z, png.clone()));
    assert!(e.contains("scalar"), "{e}");
    let e = refused(SliceOptions {
        at: Some(7.0),
        ..options("pressure", Axis::X, png.clone())
    });
    assert!(e.contains("x = 7 m") && e.contains("x = 0 to 6.28"), "{e}");
    let e = refused(SliceOptions {
        frame: FrameChoice::Index(9),
        ..options("pressure", Axis::Z, png.clone())
    });
    assert!(e.contains("frame 9") && e.contains("5 frame(s)"), "{e}");
    let e = refused(SliceOptions {
        kind: Some(SliceKind::Particles),
        ..options("pressure", Axis::Z, png.clone())
    });
    assert!(e.contains("no particle frames"), "{e}");
    let e = refused(options("pressure", Axis::Z, dir.path().join("f.jpg")));
    assert!(e.contains(".png"), "{e}");
    let empty = tempfile::tempdir().unwrap();
    let e = draw(empty.path(), &options("pressure", Axis::Z, png.clone()))
        .expect_err("no frames")
        .to_string();
    assert!(e.contains("output.hdf5=true"), "{e}");
    // The command line fails with the message, never a panic.
    let (ok, stderr) = eddy_slice(&[
        text(&run),
        "--field",
        "presure",
        "--axis",
        "y",
        "--out",
        text(&png),
    ]);
    assert!(
        !ok && stderr.starts_with("error:") && stderr.contains("presure"),
        "{stderr}"
    );
}
