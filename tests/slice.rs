//! `eddy slice`: a colour map of a run's frames whose colours follow the field, on the grid (a
//! Taylor–Green frame, whose extremes and their places are known) and on particles; the same
//! picture from a run's VTK frames as from its HDF5 frames; a series of frames as numbered
//! PNGs or an animated GIF on one colour scale, obstacles outlined; the README's commands on
//! the demo's output; and the requests it refuses.

mod common;

use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use std::process::Command;

use eddy::io::slice::{draw, FrameSelection, SliceKind, SliceOptions, SliceSummary};
use eddy::io::{
    write_grid_vtk, FrameChoice, GridField, GridFrame, Hdf5GridFrames, Precision, PvdSeries,
    VtkOptions,
};
use eddy::metrics::Axis;
use eddy::pipeline::{resolve, run_scene, RunOptions};
use eddy::Vec3;
use ndarray::Array3;
use plotters::style::colors::colormaps::ViridisRGB;

/// The ends of the viridis colour map (matplotlib's values, rounded).
const BOTTOM: [u8; 3] = [68, 1, 84];
const TOP: [u8; 3] = [253, 231, 37];
/// The obstacles' outline.
const OUTLINE: [u8; 3] = [230, 20, 20];

/// Runs `scene` (in `scenes/`) for `steps` steps into `out`, a frame every 0.01 s as HDF5 and
/// as VTK at full precision, with `more` overrides.
fn simulate(scene: &str, out: &Path, steps: u64, more: &[&str]) {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(scene);
    let overrides = [
        "output.hdf5=true",
        "output.vtk=true",
        "output.precision=\"f64\"",
        "output.interval=0.01",
    ];
    let options = RunOptions {
        out: Some(out.to_path_buf()),
        overrides: overrides
            .iter()
            .chain(more)
            .map(|s| s.to_string())
            .collect(),
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
    simulate("taylor_green.toml", &out, 4, &[]);
    out
}

fn options(field: &str, axis: Axis, out: PathBuf) -> SliceOptions {
    SliceOptions {
        field: field.into(),
        axis,
        at: None,
        frames: FrameSelection::One(FrameChoice::Last),
        kind: None,
        range: None,
        out,
    }
}

/// [`draw`] without a progress report.
fn drawn(run: &Path, opts: &SliceOptions) -> Result<Vec<SliceSummary>, eddy::io::IoError> {
    draw(run, opts, &mut |_, _, _| {})
}

/// [`drawn`] of one frame.
fn one(run: &Path, opts: &SliceOptions) -> SliceSummary {
    let mut all = drawn(run, opts).expect("draws");
    assert_eq!(all.len(), 1);
    all.remove(0)
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

fn viridis(t: f64) -> [u8; 3] {
    let c = ViridisRGB::get_color(t);
    [c.0, c.1, c.2]
}

fn png(path: &Path) -> image::RgbImage {
    image::open(path).expect("the PNG decodes").to_rgb8()
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
        let path = dir.path().join(format!("{field}.png"));
        let s = one(&run, &options(field, Axis::Z, path.clone()));
        assert_eq!(
            (s.kind, s.frame, s.count, s.non_finite, s.obstacle_cells),
            (SliceKind::Grid, 4, 4096, 0, 0)
        );
        assert!(s.file.ends_with("frames.h5"), "HDF5 first: {:?}", s.file);
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
        assert_eq!(s.scale, s.min..s.max, "one frame: its own range");
        let image = png(&path);
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

/// `eddy ARGS` through the binary, in `cwd`: whether it succeeded, and its standard error.
fn eddy_in(cwd: &Path, args: &[&str]) -> (bool, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_eddy"))
        .args(args)
        .current_dir(cwd)
        .output()
        .expect("eddy runs");
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!stderr.contains("panicked"), "{stderr}");
    (out.status.success(), stderr)
}

/// `eddy slice ARGS` through the binary.
fn eddy_slice(args: &[&str]) -> (bool, String) {
    let all: Vec<&str> = ["slice"].iter().chain(args).copied().collect();
    eddy_in(Path::new(env!("CARGO_MANIFEST_DIR")), &all)
}

fn text(p: &Path) -> &str {
    p.to_str().expect("a UTF-8 temporary path")
}

#[test]
fn frames_are_picked_by_index_or_by_the_nearest_time() {
    let _serial = common::hdf5_or_child();
    let dir = tempfile::tempdir().unwrap();
    let run = taylor_green(dir.path());
    let path = dir.path().join("f.png");
    let pick = |choice| {
        let opts = SliceOptions {
            frames: FrameSelection::One(choice),
            ..options("velocity.x", Axis::Z, path.clone())
        };
        let s = one(&run, &opts);
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
    // The command line: --time, an SVG, and the summary line with the field's unit.
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
        stderr.contains("64 cells") && stderr.contains(" m/s"),
        "a layer across x is 64 x 1 cells, of velocities in m/s: {stderr}"
    );
    let svg = std::fs::read_to_string(&svg).expect("the SVG is written");
    assert!(
        svg.starts_with("<svg") && svg.contains("velocity, x = ") && svg.contains("velocity (m/s)"),
        "{}",
        &svg[..200.min(svg.len())]
    );
}

#[test]
fn a_runs_vtk_frames_draw_the_picture_its_hdf5_frames_draw() {
    let _serial = common::hdf5_or_child();
    let dir = tempfile::tempdir().unwrap();
    let run = taylor_green(dir.path());
    for frame in [0, 3] {
        let picture = |from: &Path, name: &str| {
            let path = dir.path().join(name);
            let opts = SliceOptions {
                frames: FrameSelection::One(FrameChoice::Index(frame)),
                ..options("vorticity", Axis::Z, path.clone())
            };
            (one(from, &opts), png(&path))
        };
        let (h5, h5_image) = picture(&run, "h5.png");
        let (vtk, vtk_image) = picture(&run.join("grid.pvd"), "vtk.png");
        assert!(vtk.file.ends_with("grid.pvd"), "{:?}", vtk.file);
        assert_eq!(
            (vtk.frame, vtk.time, vtk.count, vtk.min, vtk.max, vtk.at),
            (h5.frame, h5.time, h5.count, h5.min, h5.max, h5.at)
        );
        assert!(
            vtk_image == h5_image,
            "frame {frame}: the same values, the same picture"
        );
    }
    // One VTK file alone is a frame too; at the scenes' default single precision its values
    // round to f32.
    let f32_run = dir.path().join("f32");
    simulate(
        "taylor_green.toml",
        &f32_run,
        1,
        &["output.precision=\"f32\""],
    );
    let path = dir.path().join("one.png");
    let h5 = one(&f32_run, &options("pressure", Axis::Z, path.clone()));
    let vti = one(
        &f32_run.join("grid_000001.vti"),
        &options("pressure", Axis::Z, path),
    );
    assert_eq!((vti.count, vti.time), (h5.count, h5.time));
    for (a, b) in [(vti.min, h5.min), (vti.max, h5.max)] {
        assert!((a - b).abs() <= 1e-6 * b.abs().max(1.0), "{a} against {b}");
    }
}

#[test]
fn a_coupled_runs_particles_are_drawn_as_dots_coloured_by_density() {
    let _serial = common::hdf5_or_child();
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("coupled");
    simulate("coupled_tank_and_plume.toml", &run, 2, &[]);
    let path = dir.path().join("dots.png");
    let grid = one(&run, &options("pressure", Axis::Z, path.clone()));
    assert_eq!(
        grid.kind,
        SliceKind::Grid,
        "a run with both draws its grid by default"
    );
    let opts = SliceOptions {
        kind: Some(SliceKind::Particles),
        ..options("density", Axis::Z, path.clone())
    };
    let s = one(&run, &opts);
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
    let image = png(&path);
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
    // The particles' VTK frames, their spacing from the run's scene.toml: the same picture.
    let vtk_path = dir.path().join("vtk_dots.png");
    let vtk = one(
        &run.join("particles.pvd"),
        &options("density", Axis::Z, vtk_path.clone()),
    );
    assert_eq!(
        (vtk.kind, vtk.frame, vtk.count, vtk.min, vtk.max),
        (s.kind, s.frame, s.count, s.min, s.max)
    );
    assert!(png(&vtk_path) == image, "the same dots in the same colours");
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
    assert!(
        ok && stderr.contains("particles from") && stderr.contains("kg/m³"),
        "{stderr}"
    );
}

/// Cells of the synthetic grid: 8 x 4 x 1 of 1 m.
const DIMS: [usize; 3] = [8, 4, 1];

/// `pressure` of frame `f` of the synthetic run at cell column `i`: (f + 1) i / 8, so frame 0
/// spans 0 to 7/8 and frame 1 0 to 7/4, and 0.5 lies at i = 4 in frame 0 and at i = 2 in
/// frame 1.
fn pressure(f: usize, i: usize) -> f64 {
    (f + 1) as f64 * i as f64 / 8.0
}

/// Whether cell (i, j) of the synthetic grid is an obstacle's: a block of 2 x 2 cells.
fn solid(i: usize, j: usize) -> bool {
    (5..7).contains(&i) && (2..4).contains(&j)
}

/// A run of two frames (t = 0, 0.5 s) of the synthetic grid written as HDF5 (`frames.h5`) and
/// as VTK at full precision (`grid.pvd`).
fn synthetic(dir: &Path) -> PathBuf {
    let run = dir.join("synthetic");
    std::fs::create_dir_all(&run).unwrap();
    let mut h5 = Hdf5GridFrames::create(&run.join("frames.h5"), &[]).expect("creates");
    let mut pvd = PvdSeries::new(&run.join("grid.pvd"));
    let vtk = VtkOptions {
        precision: Precision::F64,
        compression: 4,
    };
    for f in 0..2 {
        let p = Array3::from_shape_fn(DIMS, |(i, _, _)| pressure(f, i));
        let s = Array3::from_shape_fn(DIMS, |(i, j, _)| if solid(i, j) { 1.0 } else { 0.0 });
        let frame = GridFrame {
            step: f as u64,
            time: 0.5 * f as f64,
            origin: Vec3::zeros(),
            spacing: 1.0,
            dims: DIMS,
            fields: vec![
                GridField::scalar("pressure", p.view()),
                GridField::scalar("solid", s.view()),
            ],
        };
        h5.append(&frame).expect("appends");
        let name = format!("grid_{f:06}.vti");
        write_grid_vtk(&run.join(&name), &frame, vtk).expect("writes");
        pvd.push(frame.time, &name).expect("lists");
    }
    run
}

/// The frames of the GIF `path`, as RGB images.
fn gif_frames(path: &Path) -> Vec<image::RgbImage> {
    let mut options = gif::DecodeOptions::new();
    options.set_color_output(gif::ColorOutput::RGBA);
    let file = std::fs::File::open(path).expect("the GIF is written");
    let mut decoder = options.read_info(file).expect("a GIF");
    let mut frames = Vec::new();
    while let Some(frame) = decoder.read_next_frame().expect("a frame decodes") {
        let rgb: Vec<u8> = frame
            .buffer
            .chunks_exact(4)
            .flat_map(|p| [p[0], p[1], p[2]])
            .collect();
        let image = image::RgbImage::from_raw(frame.width.into(), frame.height.into(), rgb);
        frames.push(image.expect("a whole frame"));
    }
    frames
}

/// The colour at the centre of cell (i, j) of the synthetic grid.
fn cell(image: &image::RgbImage, s: &SliceSummary, (i, j): (usize, usize)) -> [u8; 3] {
    let (col, row) = pixel(s, [i as f64 + 0.5, j as f64 + 0.5]);
    image.get_pixel(col, row).0
}

/// The colour bar's pixels: beside the plot (past its margin and the gap), as tall as it.
fn colour_bar(image: &image::RgbImage, s: &SliceSummary) -> Vec<[u8; 3]> {
    let [cols, rows] = &s.pixels;
    let (c0, c1) = (cols.end as u32 + 44, cols.end as u32 + 60);
    (rows.start as u32 + 2..rows.end as u32 - 2)
        .flat_map(|r| (c0..c1).map(move |c| image.get_pixel(c, r).0))
        .collect()
}

#[test]
fn a_gif_has_a_frame_per_frame_drawn_on_one_colour_range_over_them_all() {
    let _serial = common::hdf5_or_child();
    let dir = tempfile::tempdir().unwrap();
    let run = synthetic(dir.path());
    let out = dir.path().join("anim.gif");
    let opts = SliceOptions {
        frames: FrameSelection::All,
        ..options("pressure", Axis::Z, out.clone())
    };
    let mut stages = Vec::new();
    let s = draw(&run, &opts, &mut |stage, done, of| {
        stages.push((stage, done, of))
    })
    .expect("draws");
    assert_eq!(s.len(), 2);
    assert_eq!(
        stages.last().map(|p| (p.1, p.2)),
        Some((2, 2)),
        "{stages:?}"
    );
    assert_eq!(s[0].scale, 0.0..pressure(1, 7), "the range of both frames");
    assert_eq!((s[0].max, s[1].max), (pressure(0, 7), pressure(1, 7)));
    assert!(s.iter().all(|f| f.image == out && f.obstacle_cells == 4));
    let frames = gif_frames(&out);
    assert_eq!(frames.len(), 2, "a GIF frame per frame drawn");
    let [a, b] = [&frames[0], &frames[1]];
    // 0.5 in both frames is one colour; frame 0's top value is mid-scale, frame 1's the top.
    assert_eq!(cell(a, &s[0], (4, 0)), cell(b, &s[1], (2, 0)));
    let mid = viridis(pressure(0, 7) / pressure(1, 7));
    assert!(
        close(cell(a, &s[0], (7, 0)), mid, 4),
        "{:?}",
        cell(a, &s[0], (7, 0))
    );
    assert!(
        close(cell(b, &s[1], (7, 0)), TOP, 4),
        "{:?}",
        cell(b, &s[1], (7, 0))
    );
    assert!(close(cell(a, &s[0], (0, 0)), BOTTOM, 4));
    assert!(
        colour_bar(a, &s[0]) == colour_bar(b, &s[1]),
        "one colour bar"
    );
    assert!(
        std::fs::read_dir(dir.path()).unwrap().all(|e| !e
            .unwrap()
            .file_name()
            .to_string_lossy()
            .starts_with('.')),
        "no temporary file left"
    );
    // The command line draws every frame into a .gif by default and reports its progress.
    let (ok, stderr) = eddy_slice(&[
        text(&run),
        "--field",
        "pressure",
        "--axis",
        "z",
        "--out",
        text(&dir.path().join("cli.gif")),
    ]);
    assert!(ok && stderr.contains("2 frames (0 to 1"), "{stderr}");
    assert!(stderr.contains("drawing, 2 of 2 frames done"), "{stderr}");
    assert_eq!(gif_frames(&dir.path().join("cli.gif")).len(), 2);
}

#[test]
fn a_png_series_is_numbered_by_frame_on_a_fixed_range_with_the_obstacle_outlined() {
    let _serial = common::hdf5_or_child();
    let dir = tempfile::tempdir().unwrap();
    let run = synthetic(dir.path());
    let opts = SliceOptions {
        frames: FrameSelection::Span(0, 1),
        range: Some(0.0..1.0),
        ..options("pressure", Axis::Z, dir.path().join("series.png"))
    };
    // From the VTK frames: the grid's `solid` field is there as in HDF5.
    let s = drawn(&run.join("grid.pvd"), &opts).expect("draws");
    let names: Vec<PathBuf> = ["series_000000.png", "series_000001.png"]
        .iter()
        .map(|n| dir.path().join(n))
        .collect();
    assert_eq!(s.iter().map(|f| f.image.clone()).collect::<Vec<_>>(), names);
    assert!(!dir.path().join("series.png").exists());
    let [a, b] = [png(&names[0]), png(&names[1])];
    assert!(s.iter().all(|f| f.scale == (0.0..1.0)));
    assert_eq!(cell(&a, &s[0], (4, 0)), cell(&b, &s[1], (2, 0)));
    assert!(close(cell(&a, &s[0], (4, 0)), viridis(0.5), 4));
    assert!(close(cell(&b, &s[1], (7, 0)), TOP, 4), "clamped to the top");
    assert!(
        colour_bar(&a, &s[0]) == colour_bar(&b, &s[1]),
        "one colour bar"
    );
    // The block of cells 5..7 x 2..4 is outlined where it meets the fluid, not across it.
    assert_eq!(s[0].obstacle_cells, 4);
    let at = |p: [f64; 2]| {
        let (c, r) = pixel(&s[0], p);
        a.get_pixel(c, r).0
    };
    for edge in [[5.0, 3.0], [6.0, 2.0], [6.5, 2.0], [5.0, 2.5]] {
        assert!(close(at(edge), OUTLINE, 30), "{edge:?}: {:?}", at(edge));
    }
    for inside in [[6.0, 3.0], [5.5, 2.5], [3.0, 1.0]] {
        assert!(
            !close(at(inside), OUTLINE, 60),
            "{inside:?}: {:?}",
            at(inside)
        );
    }
    // A series of one frame is still numbered.
    let single = SliceOptions {
        frames: FrameSelection::Span(1, 1),
        ..opts.clone()
    };
    let s = drawn(&run, &single).expect("draws");
    assert_eq!(s[0].image, names[1]);
}

#[test]
fn the_readmes_slice_and_compare_commands_run_on_the_demos_output() {
    let dir = tempfile::tempdir().unwrap();
    let db = dir.path().join("sphere.h5");
    {
        let _serial = common::hdf5_or_child();
        common::sphere_database(&db, 0.5, 200, 1.0);
    }
    // The demo's run, short, on a stand-in database: as `./dev demo` leaves it, VTK only.
    let demo = dir.path().join("out/abl_sphere_wake");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/abl_sphere_wake.toml");
    let database = format!("obstacles.0.abl.database={:?}", text(&db));
    let _serial = common::hdf5_or_child();
    let (ok, stderr) = eddy_in(
        dir.path(),
        &[
            "run",
            text(&scene),
            "--out",
            text(&demo),
            "--set",
            "time.end=0.2",
            "--set",
            &database,
        ],
    );
    assert!(ok, "{stderr}");
    assert!(!demo.join("frames.h5").exists() && demo.join("grid.pvd").exists());
    let readme = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md"))
        .expect("README.md");
    let commands: Vec<&str> = readme
        .lines()
        .filter_map(|l| l.strip_prefix("target/release/eddy "))
        .filter(|l| l.starts_with("slice out/abl_sphere_wake") || l.starts_with("compare out/"))
        .collect();
    assert!(commands.len() >= 3, "{commands:?}");
    for command in &commands {
        let args: Vec<&str> = command.split_whitespace().collect();
        let (ok, stderr) = eddy_in(dir.path(), &args);
        assert!(ok, "eddy {command}:\n{stderr}");
        let out = args.iter().skip_while(|a| **a != "--out").nth(1);
        let out = dir.path().join(out.expect("an --out"));
        assert!(out.is_file(), "eddy {command} wrote {}", out.display());
    }
    let gif = dir.path().join("wake.gif");
    assert_eq!(gif_frames(&gif).len(), 3, "frames at t = 0, 0.1, 0.2");
}

#[test]
fn bad_fields_positions_frames_and_files_are_refused() {
    let _serial = common::hdf5_or_child();
    let dir = tempfile::tempdir().unwrap();
    let run = taylor_green(dir.path());
    let png = dir.path().join("never.png");
    let refused = |opts: SliceOptions| {
        let e = drawn(&run, &opts).expect_err("refused").to_string();
        assert!(!opts.out.exists(), "no figure for a refused request: {e}");
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
        frames: FrameSelection::One(FrameChoice::Index(9)),
        ..options("pressure", Axis::Z, png.clone())
    });
    assert!(
        e.contains("frame 9") && e.contains("5 frame(s), 0 to 4"),
        "{e}"
    );
    let e = refused(SliceOptions {
        frames: FrameSelection::Span(2, 9),
        ..options("pressure", Axis::Z, dir.path().join("never.gif"))
    });
    assert!(e.contains("frames 2 to 9") && e.contains("0 to 4"), "{e}");
    let e = refused(SliceOptions {
        kind: Some(SliceKind::Particles),
        ..options("pressure", Axis::Z, png.clone())
    });
    assert!(e.contains("no particle frames"), "{e}");
    let e = refused(options("pressure", Axis::Z, dir.path().join("f.jpg")));
    assert!(e.contains(".png") && e.contains(".gif"), "{e}");
    let empty = tempfile::tempdir().unwrap();
    let e = drawn(empty.path(), &options("pressure", Axis::Z, png.clone()))
        .expect_err("no frames")
        .to_string();
    assert!(
        e.contains("output.hdf5=true") && e.contains("grid.pvd"),
        "{e}"
    );
    // A VTK frame that is no VTK frame is refused by its name.
    let broken = run.join("grid_000002.vti");
    std::fs::write(
        &broken,
        b"<?xml version=\"1.0\"?>\n<VTKFile type=\"ImageData\"",
    )
    .unwrap();
    let e = drawn(
        &run.join("grid.pvd"),
        &SliceOptions {
            frames: FrameSelection::All,
            ..options("pressure", Axis::Z, dir.path().join("never.gif"))
        },
    )
    .expect_err("a broken frame")
    .to_string();
    assert!(e.contains("grid_000002.vti"), "{e}");
    assert!(!dir.path().join("never.gif").exists());
    // The command line fails with the message, never a panic.
    for (args, says) in [
        (vec!["--field", "presure"], "presure"),
        (
            vec!["--field", "pressure", "--range", "2:1"],
            "MIN 2 is not below MAX 1",
        ),
        (
            vec!["--field", "pressure", "--frames", "3:1"],
            "comes after",
        ),
        (vec!["--field", "pressure", "--frames", "0:9"], "0 to 4"),
    ] {
        let mut all = vec![text(&run), "--axis", "y", "--out", text(&png)];
        all.extend(args);
        let (ok, stderr) = eddy_slice(&all);
        assert!(
            !ok && stderr.contains("error") && stderr.contains(says),
            "{stderr}"
        );
    }
}
