//! The grid's artificial-boundary-layer runtime (Pfaff et al. 2009, Figure 9) as pipeline
//! stages: without seeding it is the plain grid bit for bit; the wall-attached layer is the
//! database's lookup for the stream; omega_ABL rides the flow; the plan is what runs; outputs;
//! and clear errors for bad databases and bad `[turbulence]` values.

mod common;

use std::path::{Path, PathBuf};

use eddy::abl::AblDatabase;
use eddy::grid::walls::{boundary_cells, wall_distance};
use eddy::grid::GridSolver;
use eddy::pipeline::{run, Pipeline, RunOptions};
use eddy::scene::{parse_str, Scene, Shape};
use eddy::{Point3, Real, Vec3};

/// Radius of the test sphere, m.
const RADIUS: Real = 0.25;
/// The stream, m/s.
const U: Real = 1.0;

/// A 32 x 16 x 16 grid over 3 x 1.5 x 1.5 m with a 1 m/s inflow, open outflow and slip sides,
/// the sphere at `at`; `abl` and `extra` are appended as written.
fn text(at: [Real; 3], abl: &str, extra: &str) -> String {
    format!(
        r#"
name = "abl_test"
gravity = [0.0, 0.0, 0.0]
seed = 7
[domain]
min = [0.0, 0.0, 0.0]
max = [3.0, 1.5, 1.5]
[time]
steps = 8
cfl = 0.8
dt_max = 0.05
[grid]
resolution = [32, 16, 16]
advection = "maccormack"
initial_velocity = [{U}, 0.0, 0.0]
[grid.boundary]
x_min = {{ inflow = [{U}, 0.0, 0.0] }}
x_max = "open"
y_min = "slip"
y_max = "slip"
z_min = "slip"
z_max = "slip"
[grid.smoke]
buoyancy = 0.0
[[grid.smoke.sources]]
shape = {{ type = "box", half_extents = [0.1, 0.3, 0.3] }}
position = [0.2, 0.75, 0.75]
[output]
vtk = false
[[obstacles]]
name = "ball"
shape = {{ type = "sphere", radius = {RADIUS} }}
position = [{}, {}, {}]
{abl}
{extra}
"#,
        at[0], at[1], at[2]
    )
}

const CENTRE: [Real; 3] = [0.9, 0.75, 0.75];

fn database(dir: &Path) -> PathBuf {
    common::ball_database(dir, RADIUS)
}

fn scene(text: &str) -> Result<Scene, String> {
    parse_str(text, Path::new("abl_test.toml"), &[]).map_err(|e| e.to_string())
}

fn built(text: &str) -> Pipeline {
    common::built(text, "abl_test.toml")
}

/// With c_p = 0 nothing is seeded, so the turbulence stages leave the flow alone: velocity and
/// smoke equal the plain scene's bit for bit. With seeding they do not (so the comparison can
/// fail).
#[test]
fn without_seeding_the_run_is_the_plain_grid_bit_for_bit() {
    let dir = tempfile::tempdir().expect("temp dir");
    let db = database(dir.path());
    let mut plain = built(&text(CENTRE, "", ""));
    let mut quiet = built(&text(
        CENTRE,
        &common::abl_line(&db),
        "[turbulence]\nc_p = 0.0",
    ));
    let mut seeded = built(&text(
        CENTRE,
        &common::abl_line(&db),
        "[turbulence]\nc_p = 1e4",
    ));
    for _ in 0..8 {
        plain.step(None, None).expect("steps");
        quiet.step(None, None).expect("steps");
        seeded.step(None, None).expect("steps");
    }
    let (a, b, c) = (
        common::grid(&plain),
        common::grid(&quiet),
        common::grid(&seeded),
    );
    for axis in 0..3 {
        assert!(a.mac.u[axis] == b.mac.u[axis], "velocity {axis} differs");
    }
    assert!(
        a.smoke.as_ref().expect("the scene has smoke").density
            == b.smoke.as_ref().expect("the scene has smoke").density
    );
    let t = common::turbulence(&seeded);
    assert!(!t.vortices.is_empty(), "c_p = 1e4 seeded nothing");
    assert!(
        a.mac.u[1] != c.mac.u[1],
        "the seeded particles changed nothing"
    );
    assert!(common::turbulence(&quiet).vortices.is_empty());
}

/// The wall-attached layer after the first step (of 1 us, so advection moves the field by 1e-5
/// cells): every cell beside the sphere holds the database's value, at the boundary point nearest
/// to it, for the sphere's motion relative to the ambient flow, over the cell size (the stored
/// velocity jump as the layer's vorticity). Both a fixed sphere in a stream
/// U (relative motion -U) and a sphere moving at V through still air (relative motion V).
#[test]
fn the_wall_layer_is_the_lookup_for_the_relative_motion() {
    let dir = tempfile::tempdir().expect("temp dir");
    let db_path = database(dir.path());
    let db = {
        let _serial = common::hdf5_or_child();
        AblDatabase::open(&db_path, Some(&Shape::Sphere { radius: RADIUS })).expect("opens")
    };
    let stream = text(
        CENTRE,
        &common::abl_line(&db_path),
        "[turbulence]\nc_p = 0.0",
    );
    let still = stream
        .replace(&format!("x_min = {{ inflow = [{U}, 0.0, 0.0] }}"), "")
        .replace(&format!("initial_velocity = [{U}, 0.0, 0.0]"), "")
        .replace(
            &common::abl_line(&db_path),
            &format!(
                "{}\nmotion = {{ linear = [0.0, 0.6, 0.8] }}",
                common::abl_line(&db_path)
            ),
        );
    for (scene_text, relative) in [
        (stream, Vec3::new(-U, 0.0, 0.0)),
        (still, Vec3::new(0.0, 0.6, 0.8)),
    ] {
        let mut p = built(&scene_text.replace("cfl = 0.8", "cfl = 0.8\ndt = 1e-6"));
        p.step(None, None).expect("steps");
        let grid = common::grid(&p);
        let abl = common::abl_field(&p);
        let pose = grid.bodies[0].pose(0.0);
        // The stored velocity jump over the layer's thickness, one cell (gain 1).
        let expected: Vec<Vec3> = db
            .lookup_world(&pose, &relative, &Vec3::zeros())
            .iter()
            .map(|w| w / grid.mac.dx)
            .collect();
        let cells = boundary_cells(grid, 0);
        assert!(cells.len() > 50, "{} wall cells", cells.len());
        let peak = expected.iter().map(|w| w.norm()).fold(0.0, Real::max);
        let mut worst: Real = 0.0;
        for c in &cells {
            let x = pose.inverse_transform_point(&Point3::from(grid.mac.cell_center(*c)));
            let nearest = (0..db.len())
                .min_by(|&i, &j| {
                    let di = (db.points()[i] - x).norm();
                    let dj = (db.points()[j] - x).norm();
                    di.total_cmp(&dj)
                })
                .expect("the database has boundary points");
            let got = Vec3::new(abl[0][*c], abl[1][*c], abl[2][*c]);
            worst = worst.max((got - expected[nearest]).norm() / peak);
        }
        assert!(
            worst < 1e-3,
            "motion {relative:?}: wall layer differs from the lookup by {worst} of its peak"
        );
    }
}

/// omega_ABL is carried by the flow (Figure 9, line 9): a blob released away from the sphere
/// in the 1 m/s stream moves by U t, within a fraction of a cell.
#[test]
fn an_abl_blob_moves_with_the_stream() {
    let dir = tempfile::tempdir().expect("temp dir");
    let db = database(dir.path());
    // The sphere low in a corner, the blob high across from it; no seeding, no wall layer.
    let mut p = built(&text(
        [0.4, 0.35, 0.35],
        &common::abl_line(&db),
        "[turbulence]\nc_p = 0.0\ngain = 0.0",
    ));
    let dx = common::grid(&p).mac.dx;
    let start = Vec3::new(1.0, 1.0, 1.0);
    let centroid = |p: &Pipeline| {
        let grid = common::grid(p);
        let w = &common::abl_field(p)[2];
        let (mut sum, mut weighted) = (0.0, Vec3::zeros());
        for (idx, &v) in w.indexed_iter() {
            let x = grid.mac.cell_center([idx.0, idx.1, idx.2]);
            sum += v;
            weighted += x * v;
        }
        weighted / sum
    };
    {
        let grid = p.sim.grid.as_ref().expect("the scene has a grid");
        let w = &mut p
            .sim
            .grid_turbulence
            .as_mut()
            .expect("the scene has turbulence stages")
            .abl
            .as_mut()
            .expect("a grid scene carries omega_ABL on its cells")[2];
        for (idx, v) in w.indexed_iter_mut() {
            let x = grid.mac.cell_center([idx.0, idx.1, idx.2]);
            *v = (-(x - start).norm_squared() / (2.0 * (2.0 * dx).powi(2))).exp();
        }
    }
    let c0 = centroid(&p);
    let mut t = 0.0;
    while t < 0.5 - 1e-12 {
        t += p.step(Some(0.5), None).expect("steps").dt;
    }
    let moved = centroid(&p) - c0;
    let error = (moved - Vec3::new(U * t, 0.0, 0.0)).norm();
    assert!(
        error < 0.25 * dx,
        "moved {moved:?} in {t} s, off U t by {} cells",
        error / dx
    );
}

/// The mixing length of Eq. 8 is the distance to the nearest wall: the sphere's surface and
/// the domain's wall sides (slip sides included; inflow and open sides are not walls).
#[test]
fn the_mixing_length_is_the_distance_to_the_nearest_wall() {
    let dir = tempfile::tempdir().expect("temp dir");
    let db = database(dir.path());
    let p = built(&text(CENTRE, &common::abl_line(&db), ""));
    let grid = common::grid(&p);
    let d = wall_distance(grid);
    let c = Vec3::from(CENTRE);
    for (idx, &got) in d.indexed_iter() {
        let x = grid.mac.cell_center([idx.0, idx.1, idx.2]);
        // Slip sides are walls (y and z); the inflow and open sides (x) are not.
        let sides = [x.y, 1.5 - x.y, x.z, 1.5 - x.z];
        let want = sides
            .into_iter()
            .fold((x - c).norm() - RADIUS, Real::min)
            .max(0.0);
        assert!((got - want).abs() < 1e-9, "at {x:?}: {got} against {want}");
    }
}

/// Bad databases and bad `[turbulence]` values are refused with the key, the value and what is
/// allowed; a database of another obstacle names both geometry fingerprints.
#[test]
fn bad_databases_and_turbulence_values_are_refused_clearly() {
    let dir = tempfile::tempdir().expect("temp dir");
    let db = database(dir.path());
    let abl = common::abl_line(&db);
    let refused = |text: &str, needles: &[&str]| {
        let e = scene(text).expect_err("refused");
        for n in needles {
            assert!(e.contains(n), "{e:?} does not name {n:?}");
        }
    };
    // A missing database: the command that writes it, with the obstacle file beside it when
    // there is one, and the file to write otherwise.
    let missing = common::abl_line(&dir.path().join("none.h5"));
    refused(
        &text(CENTRE, &missing, ""),
        &[
            "obstacles[0].abl.database",
            "none.h5",
            "obstacle file such as",
            "none.toml",
        ],
    );
    std::fs::write(dir.path().join("none.toml"), "").expect("writes");
    let beside = format!("eddy-precompute {}", dir.path().join("none.toml").display());
    refused(&text(CENTRE, &missing, ""), &[&beside, "--out", "none.h5"]);
    for (extra, key) in [
        ("c_p = -1.0", "turbulence.c_p"),
        ("c_p = nan", "turbulence.c_p"),
        ("u0 = 0.0", "turbulence.u0"),
        ("gain = -2.0", "turbulence.gain"),
        ("r_max = 1.0", "turbulence.r_max"),
        ("dissipation_radius = -1.0", "turbulence.dissipation_radius"),
        ("children = 1", "turbulence.children"),
        ("children = 100", "turbulence.children"),
        ("cascade_time = -1.0", "turbulence.cascade_time"),
    ] {
        refused(
            &text(CENTRE, &abl, &format!("[turbulence]\n{extra}")),
            &[key],
        );
    }
    refused(
        &text(CENTRE, &abl, "[turbulence]\nseeding = \"everywhere\""),
        &["seeding"],
    );
    // A table with nothing to act on.
    refused(
        &text(CENTRE, "", "[turbulence]\nc_p = 1.0"),
        &["turbulence"],
    );
    // No velocity scale: no inflow, and the sphere does not move.
    let still = text(CENTRE, &abl, "")
        .replace("x_min = { inflow = [1, 0.0, 0.0] }", "")
        .replace(&format!("x_min = {{ inflow = [{U}, 0.0, 0.0] }}"), "");
    refused(&still, &["turbulence.u0", "velocity scale"]);
    // With u0 given it loads.
    scene(&format!("{still}\n[turbulence]\nu0 = 2.0")).expect("u0 set");

    // A database precomputed for another sphere: refused when the pipeline opens it.
    let other = text(CENTRE, &abl, "").replace(&format!("radius = {RADIUS}"), "radius = 0.3");
    let scene = scene(&other).expect("loads: the file exists");
    let e = {
        let _serial = common::hdf5_or_child();
        Pipeline::build(&scene).err().expect("refused").to_string()
    };
    let fp = |r: Real| {
        eddy::abl::geometry_fingerprint(&Shape::Sphere { radius: r })
            .expect("a sphere has a fingerprint")
    };
    for needle in [fp(RADIUS), fp(0.3)] {
        assert!(e.contains(&needle), "{e} does not name {needle}");
    }
}

/// `abl` belongs to obstacles, not to the container.
#[test]
fn abl_is_refused_on_the_container() {
    let dir = tempfile::tempdir().expect("temp dir");
    let db = database(dir.path());
    let body = text(CENTRE, &common::abl_line(&db), "");
    let container = body.replacen("[[obstacles]]", "[container]", 1);
    let e = scene(&container).expect_err("refused");
    assert!(e.contains("container.abl"), "{e}");
}

/// The plan lists the turbulence stage and its parts before the grid's step, every step runs
/// exactly them, and the run writes the vortex particles, the ABL field and the turbulence
/// metrics. A scene without `abl` builds no turbulence stage.
#[test]
fn the_plan_is_what_runs_and_the_outputs_are_written() {
    let dir = tempfile::tempdir().expect("temp dir");
    let db = database(dir.path());
    let file = dir.path().join("abl.toml");
    let body = text(CENTRE, &common::abl_line(&db), "[turbulence]\nc_p = 1e4")
        .replace("vtk = false", "vtk = true\nhdf5 = true\ninterval = 0.05");
    std::fs::write(&file, body).expect("writes the scene");
    let out = dir.path().join("out");
    let options = RunOptions {
        out: Some(out.clone()),
        trace: true,
        progress: false,
        ..RunOptions::default()
    };
    let summary = {
        let _serial = common::hdf5_or_child();
        run(&file, &options).expect("runs")
    };
    let names: Vec<&str> = summary.plan.stages.iter().map(|s| s.name).collect();
    let at = |n: &str| names.iter().position(|s| *s == n).expect(n);
    assert!(at("turbulence") + 1 == at("grid"), "{names:?}");
    let per_step = summary.plan.step_trace();
    for (k, step) in summary.trace.chunks(per_step.len()).enumerate() {
        assert_eq!(step, per_step.as_slice(), "step {k}");
    }
    for f in ["vortices.pvd", "vortices_000000.vtp", "grid_000000.vti"] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    // Each grid frame in frames.h5 holds the vortex particles of its time, the same set as the
    // VTK series' file of that frame.
    {
        let _serial = common::hdf5_or_child();
        let h5 = hdf5::File::open(out.join("frames.h5")).expect("frames.h5 opens");
        let listed = h5.group("frames").and_then(|g| g.member_names());
        let listed = listed.expect("frames.h5 lists its frames");
        let mut seeded = 0;
        for (k, name) in listed.iter().enumerate() {
            let vtp = common::vtk_read::read_vtk(&out.join(format!("vortices_{k:06}.vtp")));
            let n: usize = vtp
                .attr("Piece", "NumberOfPoints")
                .parse()
                .expect("a count");
            let set = h5
                .group(&format!("frames/{name}/vortices"))
                .expect("vortices group");
            assert_eq!(set.dataset("position").expect("position").shape(), [n, 3]);
            assert_eq!(set.dataset("vorticity").expect("vorticity").shape(), [n, 3]);
            for field in ["radius", "energy", "age"] {
                assert_eq!(set.dataset(field).expect(field).shape(), [n], "{field}");
            }
            seeded = seeded.max(n);
        }
        assert!(listed.len() > 2 && seeded > 0, "{} frames", listed.len());
    }
    let vti = common::vtk_read::read_vtk(&out.join("grid_000001.vti"));
    assert!(vti
        .section("CellData")
        .iter()
        .any(|a| a.name == "abl_vorticity"));
    let metrics = std::fs::read_to_string(out.join("metrics.csv")).expect("metrics");
    let header = metrics.lines().next().expect("metrics.csv has a header");
    for column in [
        "vortex_particles",
        "seeded",
        "vortex_energy",
        "abl_magnitude_sum",
        "seeding_seconds",
        "synthesis_seconds",
    ] {
        assert!(header.split(',').any(|c| c == column), "{column} missing");
    }
    let plain = built(&text(CENTRE, "", ""));
    assert!(plain.stages.iter().all(|s| s.name() != "turbulence"));
    assert!(plain.sim.grid_turbulence.is_none());
}

/// With the smoke on the grid twice as fine, a run writes it as its own series
/// (`smoke_fine.pvd`, `smoke_fine.h5` on the fine grid, h5py-readable) and the flow's frames
/// hold its cell means: the two files agree frame by frame.
#[test]
fn the_fine_smoke_is_written_beside_the_flow_frames() {
    let dir = tempfile::tempdir().expect("temp dir");
    let db = database(dir.path());
    let file = dir.path().join("abl.toml");
    let body = text(
        CENTRE,
        &common::abl_line(&db),
        "[turbulence]\nc_p = 1e4\nupsample = 2",
    )
    .replace("steps = 8", "steps = 4")
    .replace("vtk = false", "vtk = true\nhdf5 = true\ninterval = 0.05");
    std::fs::write(&file, body).expect("writes the scene");
    let out = dir.path().join("out");
    let options = RunOptions {
        out: Some(out.clone()),
        progress: false,
        ..RunOptions::default()
    };
    let _serial = common::hdf5_or_child();
    run(&file, &options).expect("runs");
    for f in ["smoke_fine.pvd", "smoke_fine_000000.vti", "grid_000000.vti"] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let flow = hdf5::File::open(out.join("frames.h5")).expect("frames.h5 opens");
    let fine = hdf5::File::open(out.join("smoke_fine.h5")).expect("smoke_fine.h5 opens");
    let dims: Vec<u64> = fine.attr("dims").and_then(|a| a.read_raw()).expect("dims");
    assert_eq!(dims, [64, 32, 32]);
    let spacing = |f: &hdf5::File| f.attr("spacing").and_then(|a| a.read_scalar::<Real>());
    assert_eq!(
        spacing(&fine).expect("spacing") * 2.0,
        spacing(&flow).expect("spacing")
    );
    let names = fine
        .group("frames")
        .and_then(|g| g.member_names())
        .expect("frames");
    assert!(names.len() > 1, "{names:?}");
    let mut smoke = 0.0;
    for name in &names {
        let read = |f: &hdf5::File| {
            f.dataset(&format!("frames/{name}/smoke"))
                .and_then(|d| d.read::<Real, ndarray::Ix3>())
                .expect("smoke")
        };
        let (means, fine) = (read(&flow), read(&fine));
        assert_eq!(means.dim(), (32, 16, 16));
        for ((i, j, k), &m) in means.indexed_iter() {
            let block = fine.slice(ndarray::s![
                2 * i..2 * i + 2,
                2 * j..2 * j + 2,
                2 * k..2 * k + 2
            ]);
            assert!(
                (block.sum() / 8.0 - m).abs() < 1e-12,
                "frame {name}, cell {i} {j} {k}"
            );
        }
        smoke = fine.sum();
    }
    assert!(smoke > 0.0, "the source's smoke reached no frame");
}

/// A 16^3 box whose lid drags the fluid (viscosity 0.01 m^2/s): twenty steps of it give a
/// stored flow with structure.
fn lid_scene(extra: &str) -> String {
    format!(
        r#"
name = "lid"
gravity = [0.0, 0.0, 0.0]
[domain]
min = [0.0, 0.0, 0.0]
max = [1.0, 1.0, 1.0]
[time]
steps = 20
cfl = 0.8
dt_max = 0.02
[grid]
resolution = [16, 16, 16]
advection = "maccormack"
{extra}
[grid.boundary]
y_max = {{ moving_wall = [1.0, 0.0, 0.0] }}
[grid.smoke]
buoyancy = 0.0
[[grid.smoke.sources]]
shape = {{ type = "box", half_extents = [0.05, 0.05, 0.05] }}
position = [0.1, 0.1, 0.1]
[output]
vtk = false
hdf5 = true
interval = 0.1
[viscosity]
kinematic = 0.01
"#
    )
}

/// A 32 x 16 x 16 box of 2 x 1 x 1 m (cells of 1/16 m), periodic along x and slip across,
/// holding a uniform 1 m/s stream along x, stepped at the fixed dt = 1/16 s (one cell per
/// step), with a smoke source of 2 x 2 x 2 cells (x in [3/16, 5/16] m: cells 3 and 4 along x;
/// y, z in [7/16, 9/16] m: cells 7 and 8); `extra` goes into `[grid]`.
fn uniform_scene(extra: &str) -> String {
    format!(
        r#"
name = "uniform"
gravity = [0.0, 0.0, 0.0]
[domain]
min = [0.0, 0.0, 0.0]
max = [2.0, 1.0, 1.0]
[time]
steps = 2
dt = 0.0625
dt_max = 0.0625
[grid]
resolution = [32, 16, 16]
advection = "maccormack"
initial_velocity = [1.0, 0.0, 0.0]
{extra}
[grid.boundary]
x_min = "periodic"
x_max = "periodic"
y_min = "slip"
y_max = "slip"
z_min = "slip"
z_max = "slip"
[grid.smoke]
buoyancy = 0.0
[[grid.smoke.sources]]
shape = {{ type = "box", half_extents = [0.0625, 0.0625, 0.0625] }}
position = [0.25, 0.5, 0.5]
[output]
vtk = false
hdf5 = true
interval = 0.0625
"#
    )
}

/// Static flow-field mode (Figure 11): the velocity is the stored frame's, made divergence-free
/// once, and restored after every step; the smoke is carried by that field, one advection per
/// step, then the sources; the plan and every step have no projection. A stored flow on another
/// grid is refused with both grids named.
///
/// The smoke's motion is checked against an exact solution, not against the advection code:
/// in a stored uniform stream of 1 m/s stepped at dt = dx / (1 m/s), a MacCormack step (and
/// the semi-Lagrangian steps inside it) backtraces every cell centre onto the centre one cell
/// upstream, where the trilinear weights are 0 and 1, so it translates the smoke by exactly one
/// cell. Starting from no smoke, with the 2 x 2 x 2-cell source set to 1 after each
/// advection, the smoke after step n is 1 on the cells x = 3 ..= 4 + (n - 1), y, z = 7, 8 (the
/// source's streak) and 0 elsewhere, to rounding (1e-12). Carrying it twice a step, before the
/// sources, or by a projected or shifted field would lengthen, move or smear the streak. In the
/// lid-driven flow (where a projection or viscosity would change the velocity), the velocity is
/// the stored field bit for bit after every step, and the smoke stays within [0, 1] (the
/// clamped MacCormack scheme is bounded by its stencil's values, the sources set 1).
#[test]
fn a_static_flow_carries_the_smoke_and_is_never_projected() {
    let dir = tempfile::tempdir().expect("temp dir");
    let options = |out: &str| RunOptions {
        out: Some(dir.path().join(out)),
        trace: true,
        ..RunOptions::default()
    };
    // The uniform stream, stored and then replayed.
    let stream = dir.path().join("stream.toml");
    std::fs::write(&stream, uniform_scene("")).expect("writes");
    {
        let _serial = common::hdf5_or_child();
        run(&stream, &options("stream")).expect("the stored stream");
    }
    let frames = dir.path().join("stream").join("frames.h5");
    let stored = format!("static_flow = {:?}", frames.display().to_string());
    let mut p = built(&uniform_scene(&stored));
    let mac = &common::grid(&p).mac;
    assert_eq!(mac.dx, 0.0625);
    let off_uniform = (0..3)
        .flat_map(|a| {
            let want = if a == 0 { 1.0 } else { 0.0 };
            mac.u[a].iter().map(move |v| (v - want).abs())
        })
        .fold(0.0, Real::max);
    assert!(
        off_uniform <= 1e-12,
        "the stored stream is {off_uniform} m/s off uniform"
    );
    let mut worst: Real = 0.0;
    for n in 1..=10 {
        assert_eq!(p.sim.stable_dt().expect("dt"), 0.0625);
        p.step(None, None).expect("steps");
        let smoke = &common::grid(&p).smoke.as_ref().expect("smoke").density;
        assert_eq!(smoke.dim(), (32, 16, 16));
        for ((i, j, k), got) in smoke.indexed_iter() {
            let streak =
                (3..=4 + (n - 1)).contains(&i) && (7..=8).contains(&j) && (7..=8).contains(&k);
            let want = if streak { 1.0 } else { 0.0 };
            worst = worst.max((got - want).abs());
            assert!(
                (got - want).abs() <= 1e-12,
                "step {n}: smoke {got} at cell ({i}, {j}, {k}), expected {want}"
            );
        }
    }
    eprintln!(
        "uniform stream: {off_uniform:e} m/s off uniform, smoke within {worst:e} of the streak"
    );
    // The lid-driven flow.
    let first = dir.path().join("first.toml");
    std::fs::write(&first, lid_scene("")).expect("writes");
    {
        let _serial = common::hdf5_or_child();
        run(&first, &options("first")).expect("the stored run");
    }
    let frames = dir.path().join("first").join("frames.h5");
    let stored = format!("static_flow = {:?}", frames.display().to_string());
    let text = lid_scene(&stored);
    let mut p = built(&text);
    let frozen = common::grid(&p).mac.u.clone();
    let speed = frozen[0].iter().fold(0.0, |m: Real, v| m.max(v.abs()));
    assert!(speed > 0.1, "the stored flow is still: {speed}");
    for _ in 0..10 {
        p.step(None, None).expect("steps");
        let grid = common::grid(&p);
        assert!(
            grid.mac.u == frozen,
            "the velocity drifted from the stored field"
        );
        let smoke = &grid.smoke.as_ref().expect("the scene has smoke").density;
        assert!(
            smoke.iter().all(|s| (0.0..=1.0).contains(s)),
            "smoke outside [0, 1]"
        );
    }
    let summary = {
        let file = dir.path().join("second.toml");
        std::fs::write(&file, &text).expect("writes");
        let _serial = common::hdf5_or_child();
        run(&file, &options("second")).expect("the static run")
    };
    let grid = summary
        .plan
        .stages
        .iter()
        .find(|s| s.name == "grid")
        .expect("the plan has a grid stage");
    let parts: Vec<&str> = grid.parts.iter().map(|(n, _)| *n).collect();
    assert!(
        parts.contains(&"static flow") && !parts.contains(&"pressure"),
        "{parts:?}"
    );
    let per_step = summary.plan.step_trace();
    for step in summary.trace.chunks(per_step.len()) {
        assert_eq!(step, per_step.as_slice());
    }
    // Another grid.
    let coarse = text.replace("resolution = [16, 16, 16]", "resolution = [8, 8, 8]");
    let scene = scene(&coarse).expect("loads");
    let e = {
        let _serial = common::hdf5_or_child();
        Pipeline::build(&scene).err().expect("refused").to_string()
    };
    assert!(e.contains("[16, 16, 16]") && e.contains("[8, 8, 8]"), "{e}");
}

/// `turbulence.upsample = 2` synthesises on a lattice twice as fine and keeps the smoke there
/// (Table 1, section 5.2): the plan says so, the smoke has twice the cells along each axis,
/// and the same seeds give a different grid velocity than at 1; 3 is refused.
#[test]
fn synthesis_upsampling_is_wired_through() {
    let dir = tempfile::tempdir().expect("temp dir");
    let db = database(dir.path());
    let run = |upsample: usize| {
        let extra = format!("[turbulence]\nc_p = 1e4\nupsample = {upsample}");
        let mut p = built(&text(CENTRE, &common::abl_line(&db), &extra));
        for _ in 0..4 {
            p.step(None, None).expect("steps");
        }
        p
    };
    let (one, two) = (run(1), run(2));
    let line = |p: &Pipeline| {
        let stage = p
            .stages
            .iter()
            .find(|s| s.name() == "turbulence")
            .expect("the plan has a turbulence stage");
        let (_, parts) = stage.describe(&p.sim);
        parts
            .iter()
            .find(|(n, _)| *n == "synthesis")
            .expect("the turbulence stage has a synthesis part")
            .1
            .clone()
    };
    assert!(line(&two).contains("2x finer"), "{}", line(&two));
    assert!(line(&two).contains("smoke's fine faces"), "{}", line(&two));
    let (a, b) = (common::turbulence(&one), common::turbulence(&two));
    assert!(!a.vortices.is_empty() && !b.vortices.is_empty());
    let (ga, gb) = (common::grid(&one), common::grid(&two));
    assert!(ga.mac.u[1] != gb.mac.u[1], "upsampling changed nothing");
    // Section 5.2: the smoke lives on the grid twice as fine, the flow's stays.
    let smoke = |g: &GridSolver| g.smoke.as_ref().expect("the scene has smoke").density.dim();
    assert_eq!(smoke(ga), (32, 16, 16));
    assert_eq!(smoke(gb), (64, 32, 32));
    assert!(gb
        .describe()
        .iter()
        .any(|(n, d)| *n == "advect" && d.contains("2x finer")));
    let e = scene(&text(
        CENTRE,
        &common::abl_line(&db),
        "[turbulence]\nupsample = 3",
    ))
    .expect_err("refused");
    assert!(e.contains("turbulence.upsample"), "{e}");
}
