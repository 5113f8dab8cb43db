//! The artificial-boundary-layer runtime on SPH particles (Pfaff et al. 2009, Figure 9 on a
//! particle fluid): without seeding it is the plain SPH run bit for bit; the particles' field is
//! the database's lookup at their nearest boundary points and rides on them unchanged; the
//! seeding routine is one function for grid cells and particles and conserves what it removes;
//! vortex kernels stay inside the liquid; it composes with a refinement; clear errors.

mod common;

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use eddy::abl::seeding::{seed, SeedSamples, SeedingParams};
use eddy::abl::{AblDatabase, WallLayer};
use eddy::pipeline::{fit_to_liquid, Pipeline, Surface, ABL_FIELD};
use eddy::scene::{parse_str, Scene, Shape};
use eddy::sph::SphSolver;
use eddy::vortex::{kernel, VortexParticles};
use eddy::{Point3, Real, Vec3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// Radius of the ball, m.
const RADIUS: Real = 0.08;
/// Particle spacing, m.
const H: Real = 0.025;
/// The ball's speed along x, m/s.
const SPEED: Real = 1.0;

/// A 0.8 x 0.5 x 0.4 m tank holding 0.35 m of water, the ball centred 0.2 m deep and pulled
/// along x; `abl` and `extra` are appended as written.
fn text(abl: &str, extra: &str) -> String {
    format!(
        r#"
name = "abl_sph_test"
seed = 3
[domain]
min = [-0.05, -0.05, -0.05]
max = [0.85, 0.55, 0.45]
[time]
steps = 6
cfl = 0.4
dt_max = 4e-3
[fluid]
spacing = {H}
blocks = [{{ min = [0.0, 0.0, 0.0], max = [0.8, 0.35, 0.4] }}]
[container]
shape = {{ type = "box", half_extents = [0.4, 0.25, 0.2] }}
position = [0.4, 0.25, 0.2]
[viscosity]
kinematic = 1e-4
[output]
vtk = false
metrics = []
[[obstacles]]
name = "ball"
shape = {{ type = "sphere", radius = {RADIUS} }}
position = [0.25, 0.15, 0.2]
motion = {{ linear = [{SPEED}, 0.0, 0.0] }}
{abl}
{extra}
"#
    )
}

fn database(dir: &Path) -> PathBuf {
    common::ball_database(dir, RADIUS)
}

fn scene(text: &str) -> Result<Scene, String> {
    parse_str(text, Path::new("abl_sph_test.toml"), &[]).map_err(|e| e.to_string())
}

fn built(text: &str) -> Pipeline {
    common::built(text, "abl_sph_test.toml")
}

/// Eager seeding with kernels weak enough to keep the short runs stable.
const EAGER: &str = "[turbulence]\nc_p = 1e3\ngain = 0.1";

/// Writes the scene with the ball's database and [`EAGER`] seeding, edited by `edit`, into
/// `dir` (which also holds the database); returns its path.
fn eager_file(dir: &Path, edit: impl Fn(String) -> String) -> PathBuf {
    let db = database(dir);
    let file = dir.join("abl_sph_test.toml");
    let body = edit(text(&common::abl_line(&db), EAGER));
    std::fs::write(&file, body).expect("writes the scene");
    file
}

fn sph(p: &Pipeline) -> &SphSolver {
    p.sim.sph.as_ref().expect("an SPH scene")
}

/// The carried field `name` of the fluid.
fn carried<'a>(sph: &'a SphSolver, name: &str) -> &'a [Vec3] {
    let (_, f) = sph
        .fluid
        .carried
        .iter()
        .find(|(n, _)| *n == name)
        .expect("carried field");
    f
}

/// Tags every fluid particle with its index as a carried field, so it can be followed through
/// the solver's reordering.
fn tag(p: &mut Pipeline) {
    let fluid = &mut p
        .sim
        .sph
        .as_mut()
        .expect("the scene has an SPH fluid")
        .fluid;
    let i = fluid.carry("test_id");
    let ids = &mut fluid.carried[i].1;
    for (k, id) in ids.iter_mut().enumerate() {
        *id = Vec3::new(k as Real, 0.0, 0.0);
    }
}

/// Position and omega_ABL of every particle by its tag.
fn by_tag(p: &Pipeline) -> HashMap<usize, (Vec3, Vec3)> {
    let s = sph(p);
    let ids = carried(s, "test_id");
    let abl = carried(s, ABL_FIELD);
    (0..s.fluid.len())
        .map(|k| (ids[k].x as usize, (s.fluid.x[k], abl[k])))
        .collect()
}

/// With c_p = 0 nothing is seeded, so the fluid moves exactly as without `abl`.
#[test]
fn without_seeding_the_run_is_the_plain_sph_bit_for_bit() {
    let dir = tempfile::tempdir().expect("temp dir");
    let db = database(dir.path());
    let mut plain = built(&text("", ""));
    let mut quiet = built(&text(&common::abl_line(&db), "[turbulence]\nc_p = 0.0"));
    for _ in 0..6 {
        plain.step(None, None).expect("steps");
        quiet.step(None, None).expect("steps");
    }
    let (a, b) = (sph(&plain), sph(&quiet));
    assert_eq!(a.fluid.x, b.fluid.x);
    assert_eq!(a.fluid.v, b.fluid.v);
    let abl = carried(b, ABL_FIELD);
    assert!(
        abl.iter().any(|w| *w != Vec3::zeros()),
        "the layer was attached"
    );
    assert!(common::turbulence(&quiet).vortices.is_empty());
}

/// At the first step every particle within the layer (two spacings) of the ball takes the
/// database's lookup for the ball's velocity at its nearest boundary point, over the layer's
/// thickness (the stored velocity jump as a vorticity); the rest stay zero.
/// Then, step after step, a particle outside the layer keeps its value exactly as it moves.
#[test]
fn the_particles_carry_the_lookup_unchanged() {
    let dir = tempfile::tempdir().expect("temp dir");
    let db = database(dir.path());
    let mut p = built(&text(&common::abl_line(&db), "[turbulence]\nc_p = 0.0"));
    tag(&mut p);
    let before = by_tag(&p);
    let layer = {
        let db = AblDatabase::open(&db, Some(&Shape::Sphere { radius: RADIUS })).expect("opens");
        WallLayer::new(db, 4.0 * H)
    };
    let ball = sph(&p).bodies[1].clone();
    let pose = ball.pose(0.0);
    // The water is still at t = 0, so the relative motion is the ball's own; gain 1.
    let thickness = 2.0 * H;
    let values = layer.values(
        &pose,
        &Vec3::new(SPEED, 0.0, 0.0),
        &Vec3::zeros(),
        1.0 / thickness,
    );
    p.step(None, None).expect("steps");
    let after = by_tag(&p);
    let mut attached = 0;
    for (id, (x0, _)) in &before {
        let got = after[id].1;
        let x0 = Point3::from(*x0);
        if ball.signed_distance(0.0, &x0) < 2.0 * H {
            let want = values[layer.nearest(&pose.inverse_transform_point(&x0))];
            assert_eq!(got, want, "particle {id} at {x0:?}");
            attached += 1;
        } else {
            assert_eq!(got, Vec3::zeros(), "particle {id} outside the layer");
        }
    }
    assert!(attached > 100, "{attached} particles in the layer");
    // Followed over more steps: outside the layer at the step's start, the value is kept.
    let mut kept = 0;
    let mut moved: Real = 0.0;
    for _ in 0..8 {
        let t = sph(&p).time();
        let start = by_tag(&p);
        p.step(None, None).expect("steps");
        let end = by_tag(&p);
        for (id, (x, w)) in &start {
            if *w != Vec3::zeros() && ball.signed_distance(t, &Point3::from(*x)) >= 2.0 * H {
                assert_eq!(end[id].1, *w, "particle {id} lost its value");
                kept += 1;
                moved = moved.max((end[id].0 - x).norm());
            }
        }
    }
    assert!(kept > 50, "{kept} particles followed outside the layer");
    assert!(moved > 0.1 * H, "the carrying particles moved {moved} m");
}

/// Checks the shared routine on `samples`: it seeds, each seed's kernel holds exactly the
/// vorticity it removed, and what was removed plus what is left is what there was.
fn conserves(mut samples: SeedSamples, r_max: Real) -> usize {
    let sum =
        |s: &SeedSamples| -> Vec3 { s.omega.iter().zip(&s.volume).map(|(w, v)| w * *v).sum() };
    let scale: Real = samples
        .omega
        .iter()
        .zip(&samples.volume)
        .map(|(w, v)| w.norm() * v)
        .sum();
    let before = sum(&samples);
    let params = SeedingParams {
        c_p: 1e9,
        u0: 1.0,
        r_max,
        r_min: 0.25 * r_max,
    };
    let seeds = seed(
        &mut samples,
        &params,
        1e-3,
        &mut ChaCha8Rng::seed_from_u64(5),
    );
    let mut removed = Vec3::zeros();
    for s in &seeds {
        let held = s.omega * eddy::abl::seeding::kernel_vorticity_integral(s.sigma);
        assert!((held - s.removed).norm() <= 1e-12 * s.removed.norm());
        removed += s.removed;
    }
    let after = sum(&samples);
    assert!(
        (removed + after - before).norm() <= 1e-12 * scale,
        "{removed:?} + {after:?} != {before:?}"
    );
    seeds.len()
}

/// One seeding function for both media: samples made from grid cells (cell volume, grid wall
/// distance) and from SPH particles (m / rho, the particles' wall distance) both conserve the
/// vorticity they give up.
#[test]
fn the_seeding_routine_is_shared_and_conserves_vorticity() {
    let omega = |x: &Vec3| Vec3::new(x.y.sin() + 0.3, 1.0 - x.z, 0.5 + x.x);
    // Particles: the fluid of the tank, those within 0.1 m of the floor.
    let dir = tempfile::tempdir().expect("temp dir");
    let db = database(dir.path());
    let p = built(&text(&common::abl_line(&db), ""));
    let s = sph(&p);
    let mut particles = SeedSamples::default();
    for (i, x) in s.fluid.x.iter().enumerate() {
        if x.y < 0.1 {
            let l = s.wall_distance(&Point3::from(*x));
            particles.push(*x, omega(x), s.fluid.mass / s.fluid.density[i], l);
        }
    }
    assert!(particles.len() > 1000);
    assert!(conserves(particles, 4.0 * H) > 10);
    // Cells: a grid scene's cells within 0.3 m of its floor.
    let grid_text = r#"
name = "cells"
gravity = [0.0, 0.0, 0.0]
[domain]
min = [0.0, 0.0, 0.0]
max = [1.0, 1.0, 1.0]
[time]
steps = 1
[grid]
resolution = [20, 20, 20]
"#;
    let g = built(grid_text);
    let grid = common::grid(&g);
    let distance = eddy::grid::walls::wall_distance(grid);
    let mut cells = SeedSamples::default();
    let dx = grid.mac.dx;
    for (idx, &l) in distance.indexed_iter() {
        let x = grid.mac.cell_center([idx.0, idx.1, idx.2]);
        if x.y < 0.3 {
            cells.push(x, omega(&x), dx * dx * dx, l);
        }
    }
    assert!(conserves(cells, 4.0 * dx) > 10);
}

/// Section 6: a vortex centred above the water or inside the ball is removed; one whose kernel
/// reaches past the free surface is shrunk to the distance to it; one deep in the water is
/// left alone. Then, over a run that seeds, no kernel is centred outside the liquid.
#[test]
fn vortex_kernels_stay_inside_the_liquid() {
    let dir = tempfile::tempdir().expect("temp dir");
    let db = database(dir.path());
    let p = built(&text(&common::abl_line(&db), ""));
    let s = sph(&p);
    let top = s.fluid.x.iter().map(|x| x.y).fold(0.0, Real::max);
    let reach = 6.0 * H;
    let mut v = VortexParticles::new();
    let omega = Vec3::new(0.0, 0.0, 3.0);
    let sigma = kernel::sigma_for_radius(5.0 * H);
    v.push(Vec3::new(0.6, top + 3.0 * H, 0.2), omega, sigma)
        .expect("a valid vortex"); // above the water
    v.push(Vec3::new(0.25, 0.15, 0.2), omega, sigma)
        .expect("a valid vortex"); // inside the ball
    v.push(Vec3::new(0.6, top - 1.5 * H, 0.2), omega, sigma)
        .expect("a valid vortex"); // under the surface
    let deep = kernel::sigma_for_radius(2.5 * H);
    v.push(Vec3::new(0.6, 0.15, 0.2), omega, deep)
        .expect("a valid vortex"); // deep, small
    let surface = Surface::of(s, reach);
    let removed = fit_to_liquid(&mut v, s, &surface);
    assert_eq!(removed, 2);
    assert_eq!(v.len(), 2);
    let shallow = v.radius(0);
    assert!(shallow < 5.0 * H, "not shrunk: {shallow}");
    assert!(shallow > 0.0);
    let x = v.x[0];
    let to_surface = s
        .surface_positions()
        .iter()
        .map(|y| (y - x).norm())
        .fold(Real::INFINITY, Real::min);
    assert!(
        (shallow - to_surface).abs() < 1e-9,
        "radius {shallow} against {to_surface} to the surface"
    );
    assert_eq!(v.omega[0], omega, "the peak vorticity is kept");
    assert_eq!(v.sigma[1], deep);
    // A run with eager seeding: after every step each kernel is centred in the water and
    // clear of the free surface and walls as they were when the stage ran (at the step's
    // start: the fluid moves after it).
    let mut p = built(&text(
        &common::abl_line(&db),
        "[turbulence]\nc_p = 1e3\nr_max = 4.0\ndissipation_radius = 1.0",
    ));
    let mut seen = 0;
    for _ in 0..6 {
        let (water, surface, t) = {
            let s = sph(&p);
            (s.fluid.x.clone(), s.surface_positions(), s.time())
        };
        p.step(None, None).expect("steps");
        let s = sph(&p);
        let v = &common::turbulence(&p).vortices;
        seen = seen.max(v.len());
        let nearest = |points: &[Vec3], x: &Vec3| {
            points
                .iter()
                .map(|y| (y - x).norm())
                .fold(Real::INFINITY, Real::min)
        };
        for q in 0..v.len() {
            let x = v.x[q];
            let to_water = nearest(&water, &x);
            assert!(
                to_water < H,
                "vortex {q} at {x:?} is {to_water} m from the water"
            );
            let walls = eddy::sph::walls::wall_distance(&s.bodies, true, t, &Point3::from(x));
            assert!(walls > 0.0, "vortex {q} in a wall");
            let to_surface = nearest(&surface, &x);
            assert!(
                v.radius(q) <= to_surface.min(walls) * (1.0 + 1e-9),
                "vortex {q} of radius {} reaches past the surface ({to_surface} m) or a wall \
                 ({walls} m)",
                v.radius(q)
            );
        }
    }
    assert!(seen > 0, "the run seeded");
}

/// ABL seeding and a refinement run in one scene: the plan shows the turbulence stage before
/// the SPH step and the refinement inside it, and each step runs exactly that.
#[test]
fn it_composes_with_a_refinement() {
    let dir = tempfile::tempdir().expect("temp dir");
    let db = database(dir.path());
    let mut p = built(&text(
        &common::abl_line(&db),
        "[turbulence]\nc_p = 1e3\n[refinement]\nmethod = \"vrsph\"",
    ));
    let names: Vec<&str> = p.stages.iter().map(|s| s.name()).collect();
    let at = |n: &str| names.iter().position(|s| *s == n).expect(n);
    assert_eq!(at("turbulence") + 1, at("sph"), "{names:?}");
    let mut trace = Vec::new();
    for _ in 0..3 {
        p.step(None, Some(&mut trace)).expect("steps");
    }
    let parts = |prefix: &str| trace.iter().filter(|t| t.starts_with(prefix)).count();
    assert_eq!(parts("turbulence/"), 3 * 5, "{trace:?}");
    assert!(trace.iter().any(|t| t == "sph/refine"), "{trace:?}");
    assert!(!common::turbulence(&p).vortices.is_empty());
}

/// A database for another ball is refused with both fingerprints named.
#[test]
fn a_database_for_another_obstacle_is_refused() {
    let dir = tempfile::tempdir().expect("temp dir");
    let db = database(dir.path());
    let other =
        text(&common::abl_line(&db), "").replace(&format!("radius = {RADIUS}"), "radius = 0.1");
    let scene = scene(&other).expect("loads");
    let _serial = common::hdf5_or_child();
    let e = Pipeline::build(&scene).err().expect("refused").to_string();
    let fp = |r: Real| {
        eddy::abl::geometry_fingerprint(&Shape::Sphere { radius: r })
            .expect("a sphere has a fingerprint")
    };
    for needle in [fp(RADIUS), fp(0.1)] {
        assert!(e.contains(&needle), "{e} does not name {needle}");
    }
}

/// The particle budget of the turbulence stage balances every step: the count after a step is
/// the count before plus the seeded and the children born of splits, less the particles that
/// split, the merged pairs, the dissipated and those the liquid bounds removed. Eager seeding,
/// so seeds, splits and dissipation all occur.
#[test]
fn the_vortex_budget_balances_every_step() {
    let dir = tempfile::tempdir().expect("temp dir");
    let db = database(dir.path());
    let mut p = built(&text(&common::abl_line(&db), EAGER));
    let mut count = 0;
    let mut totals = [0usize; 6];
    for _ in 0..40 {
        let rec = p.step(None, None).expect("steps");
        let t = common::turbulence(&p).last.expect("the stage ran");
        let after = count + t.seeded + t.born;
        let gone = t.split + t.merged + t.dissipated + t.removed;
        assert_eq!(after - gone, t.particles, "step {}: {t:?}", rec.step);
        assert_eq!(
            t.particles,
            p.sim.sph_turbulence.as_ref().expect("state").vortices.len()
        );
        count = t.particles;
        for (s, n) in
            totals
                .iter_mut()
                .zip([t.seeded, t.split, t.born, t.dissipated, t.removed, t.merged])
        {
            *s += n;
        }
    }
    let [seeded, split, born, dissipated, ..] = totals;
    assert!(seeded > 10 && split > 0 && dissipated > 0, "{totals:?}");
    assert_eq!(born, 2 * split, "two children per split");
}

/// Seeds of the size the river's walls leave room for (2.5 spacings) carried by a uniform SPH
/// stream: in the inertial range each splits on its Kolmogorov time into two of 2^(-1/3) its
/// radius, and a child under the dissipation radius is dissipated. At the particle default of
/// one spacing the seeds live three generations and their count after every step is 2^g, g
/// the generations whose split time has passed; at the grid's two cells the first split's
/// children fall under the threshold and the seeds are gone after one split time.
#[test]
fn seeds_in_a_uniform_stream_cascade_as_the_rules_predict_at_sph_scale() {
    use eddy::abl::params::{GRID_DISSIPATION, PARTICLE_DISSIPATION};
    use eddy::abl::TurbulenceParams;
    use eddy::vortex::{Dynamics, DynamicsSettings};
    let h = 0.025;
    let stream = format!(
        "name = \"stream\"\ngravity = [0.0, 0.0, 0.0]\n[domain]\nmin = [-0.1, -0.1, -0.1]\n\
         max = [0.9, 0.5, 0.5]\n[time]\nsteps = 1\n[fluid]\nspacing = {h}\n[[fluid.blocks]]\n\
         min = [0.0, 0.0, 0.0]\nmax = [0.8, 0.4, 0.4]\nvelocity = [1.0, 0.0, 0.0]\n\
         [output]\nvtk = false\nmetrics = []\n"
    );
    let scene = parse_str(&stream, Path::new("stream.toml"), &[]).expect("scene");
    let fluid = eddy::pipeline::sph_solver(&scene).expect("solver builds");
    let source = fluid.velocity_source();
    let defaults = TurbulenceParams::default();
    assert_eq!(defaults.dissipation(true), PARTICLE_DISSIPATION);
    assert_eq!(defaults.dissipation(false), GRID_DISSIPATION);
    let dt = 2e-3;
    let birth = 2.5 * h;
    // The history the rules predict: generation g has radius birth * s^g and splits when its
    // age, summed step by step as the dynamics sum it, reaches split_time.
    let predict = |settings: &DynamicsSettings, steps: usize| -> Vec<usize> {
        let (mut sigma, mut age, mut alive) = (kernel::sigma_for_radius(birth), 0.0, 1);
        let mut counts = Vec::new();
        for _ in 0..steps {
            age += dt;
            if alive > 0 && age >= settings.split_time(sigma) {
                sigma *= settings.child_scale;
                age = 0.0;
                alive *= settings.children;
                if kernel::radius(sigma) < settings.dissipation_cells * h {
                    alive = 0;
                }
            }
            counts.push(alive);
        }
        counts
    };
    let lifetime = |dissipation: Real| -> (Vec<usize>, Vec<usize>) {
        let settings = DynamicsSettings {
            dissipation_cells: dissipation,
            inertial_radius: defaults.split_radius * h,
            children: defaults.children,
            cascade_time: defaults.cascade_time,
            ..DynamicsSettings::default()
        };
        let mut dynamics = Dynamics::new(settings.clone(), 7).expect("settings");
        let mut v = VortexParticles::new();
        v.push(
            Vec3::new(0.2, 0.2, 0.2),
            Vec3::new(0.0, 0.0, 20.0),
            kernel::sigma_for_radius(birth),
        )
        .expect("a valid vortex");
        let steps = 120;
        let counts = (0..steps)
            .map(|_| {
                dynamics.step(&mut v, &source, dt, h);
                v.len()
            })
            .collect();
        (counts, predict(&settings, steps))
    };
    // The count step by step is the prediction, peaks at `most` and is nonzero for so many steps.
    let alive = |dissipation: Real, most: usize| -> usize {
        let (counts, predicted) = lifetime(dissipation);
        assert_eq!(counts, predicted);
        assert_eq!(counts.iter().max(), Some(&most), "{counts:?}");
        counts.iter().filter(|&&n| n > 0).count()
    };
    // Three generations at one spacing; no child survives at two.
    let lived = alive(PARTICLE_DISSIPATION, 8);
    let died = alive(GRID_DISSIPATION, 1);
    assert!(lived > 3 * died, "{lived} steps against {died}");
}

/// The particle frames carry what a turbulence researcher looks at: the fluid's vorticity (the
/// solver's curl, the field `metrics.csv` summarises: the frame's mean |omega| is the metrics
/// row's at the same time) and the boundary layer's `abl_vorticity`, one vector per particle.
#[test]
fn particle_frames_carry_the_vorticity_and_the_layer() {
    let dir = tempfile::tempdir().expect("temp dir");
    let file = eager_file(dir.path(), |body| {
        body.replace("steps = 6", "steps = 12").replace(
            "vtk = false\nmetrics = []",
            "vtk = false\nhdf5 = true\ninterval = 0.004\nmetrics = [\"vorticity_mean\"]",
        )
    });
    let out = dir.path().join("out");
    let options = eddy::pipeline::RunOptions {
        out: Some(out.clone()),
        progress: false,
        ..eddy::pipeline::RunOptions::default()
    };
    let _serial = common::hdf5_or_child();
    eddy::pipeline::run(&file, &options).expect("runs");
    let metrics = std::fs::read_to_string(out.join("metrics.csv")).expect("metrics");
    let rows: Vec<(Real, Real)> = metrics
        .lines()
        .skip(1)
        .map(|l| {
            let c: Vec<Real> = l.split(',').map(|x| x.parse().expect("a number")).collect();
            (c[1], c[3])
        })
        .collect();
    let h5 = hdf5::File::open(out.join("frames.h5")).expect("frames.h5");
    let frames = h5.group("frames").expect("frames");
    let mut compared = 0;
    for name in frames.member_names().expect("names") {
        let g = frames.group(&name).expect("frame");
        let n = g.dataset("position").expect("position").shape()[0];
        for field in ["vorticity", ABL_FIELD] {
            assert_eq!(g.dataset(field).expect(field).shape(), [n, 3], "{field}");
        }
        let t: Real = g.attr("time").expect("time").read_scalar().expect("time");
        let w: Vec<Real> = g
            .dataset("vorticity")
            .expect("vorticity")
            .read_raw()
            .expect("read");
        let mean = w
            .chunks(3)
            .map(|c| Vec3::new(c[0], c[1], c[2]).norm())
            .sum::<Real>()
            / n as Real;
        if let Some(&(_, row)) = rows.iter().find(|(rt, _)| (rt - t).abs() < 1e-12) {
            assert!(
                (mean - row).abs() <= 1e-12 * row.max(1.0),
                "t = {t}: {mean} against {row}"
            );
            compared += usize::from(row > 0.0);
        }
    }
    assert!(
        compared >= 2,
        "{compared} frames with a moving fluid compared"
    );
}

/// `eddy bench-abl` on particles: a short run of the protocol on the ball pulled through the
/// tank, without the reference, gives the plain, random and ABL rows with finite wake
/// statistics at the default stations behind the ball (two and four ball lengths), and the ABL
/// run's vortex particles counted over the window.
#[test]
fn the_protocol_runs_on_particles() {
    use eddy::bench::abl::{run, AblBenchOptions};
    let dir = tempfile::tempdir().expect("temp dir");
    let file = eager_file(dir.path(), |body| body.replace("steps = 6", "end = 0.04"));
    let options = AblBenchOptions {
        scale: None,
        stations: Vec::new(),
        from: None,
        overrides: Vec::new(),
        skip_reference: true,
        reference: None,
        profiles: Some(dir.path().join("profiles")),
        plot: None,
        seeds: 1,
        runs: Vec::new(),
        checkpoint_every: std::time::Duration::from_secs(600),
    };
    let rows = {
        let _serial = common::hdf5_or_child();
        run(&file, &options).expect("the protocol runs")
    };
    let labels: Vec<&str> = rows.iter().map(|r| r.label).collect();
    assert_eq!(labels, ["none", "random", "abl"]);
    for r in &rows {
        assert!(r.failed.is_none() && r.steps > 5, "{r:?}");
        assert!(r.mean_k.is_finite() && r.mean_k >= 0.0, "{r:?}");
    }
    assert!(rows[2].mean_particles > 0.0, "{:?}", rows[2]);
    // Two and four ball lengths behind the ball (0.25 m + 2 and 4 times its 0.16 m): the
    // second, 0.89 m, lies beyond the 0.85 m domain and is left out; 8 bins of two spacings
    // across z.
    let csv = std::fs::read_to_string(dir.path().join("profiles/abl.csv")).expect("profiles");
    let stations: Vec<Real> = csv
        .lines()
        .skip(1)
        .map(|l| {
            l.split(',')
                .next()
                .expect("station")
                .parse()
                .expect("a number")
        })
        .collect();
    assert_eq!(stations.len(), 8);
    assert!(
        stations.iter().all(|s| (s - 0.57).abs() < 1e-9),
        "{stations:?}"
    );
}

/// A bench-abl run killed after a checkpoint and run again goes on from the checkpoint and
/// writes the profiles of a run that never stopped, value for value.
#[test]
fn a_killed_protocol_run_goes_on_from_its_checkpoint() {
    use std::process::{Command, Stdio};
    let dir = tempfile::tempdir().expect("temp dir");
    let file = eager_file(dir.path(), |body| body.replace("steps = 6", "end = 0.3"));
    let bench = |profiles: &Path| {
        let mut c = Command::new(env!("CARGO_BIN_EXE_eddy"));
        c.arg("bench-abl")
            .arg(&file)
            .args([
                "--runs",
                "none",
                "--skip-reference",
                "--checkpoint-every",
                "0",
            ])
            .arg("--profiles")
            .arg(profiles)
            .stdout(Stdio::null())
            .stderr(Stdio::null());
        c
    };
    let _serial = common::hdf5_or_child();
    let (whole, killed) = (dir.path().join("whole"), dir.path().join("killed"));
    assert!(bench(&whole).status().expect("runs").success());
    let mut child = bench(&killed).spawn().expect("starts");
    let checkpoint = killed.join("none.checkpoint.h5");
    let mut waited = 0;
    while !checkpoint.exists() && waited < 20_000 {
        std::thread::sleep(std::time::Duration::from_millis(2));
        waited += 2;
    }
    // A few more checkpoints, then the kill (one may be mid-write: the last whole one stays).
    std::thread::sleep(std::time::Duration::from_millis(30));
    child.kill().expect("kill");
    child.wait().expect("ends");
    assert!(checkpoint.exists(), "the killed run left its checkpoint");
    assert!(!killed.join("none.csv").exists(), "killed before its end");
    assert!(bench(&killed).status().expect("runs").success());
    assert!(
        !checkpoint.exists(),
        "the checkpoint goes when the run ends"
    );
    let read = |d: &Path| std::fs::read_to_string(d.join("none.csv")).expect("profiles");
    assert_eq!(read(&whole), read(&killed));
}
