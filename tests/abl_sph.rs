//! The artificial-boundary-layer runtime on SPH particles (Pfaff et al. 2009, Figure 9 on a
//! particle fluid): without seeding it is the plain SPH run bit for bit; the particles' field is
//! the database's lookup at their nearest boundary points and rides on them unchanged; the
//! seeding routine is one function for grid cells and particles and conserves what it removes;
//! vortex kernels stay inside the liquid; it composes with a refinement; clear errors.

mod common;

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use eddy::abl::seeding::{seed, SeedSamples, SeedingParams};
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

/// Boundary points of the fixture database (`common::sphere_database`: 400 Fibonacci points on
/// the sphere), recomputed here from the fixture's definition.
const DB_POINTS: usize = 400;
/// The fixture database's gain, 1/m: it stores `omega_pre = DB_GAIN (U_s x n)`.
const DB_GAIN: Real = 4.0;
/// The ball's centre at t = 0, m.
const BALL_AT: [Real; 3] = [0.25, 0.15, 0.2];

/// The fixture's unit normals: the Fibonacci lattice of `DB_POINTS` points.
fn fixture_normals() -> Vec<Vec3> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..DB_POINTS)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as Real + 0.5) / DB_POINTS as Real;
            let r = (1.0 - z * z).sqrt();
            let phi = golden * i as Real;
            Vec3::new(r * phi.cos(), r * phi.sin(), z)
        })
        .collect()
}

/// The ball's centre at time `t`: it moves along x at [`SPEED`].
fn ball_centre(t: Real) -> Vec3 {
    Vec3::from(BALL_AT) + Vec3::new(SPEED * t, 0.0, 0.0)
}

/// At the first step every particle closer than the layer (two spacings, the kernel support)
/// to the ball takes the value of the database's boundary point nearest to it; the rest stay
/// zero. The expected value is derived from the fixture, not from the lookup: the water is
/// still at t = 0, so the ball's motion relative to it is `V = SPEED e_x`; the fixture stores,
/// for the stream `-d` past the sphere, `omega_pre = DB_GAIN (U_s x n)` with `U_s = -d + n (d . n)`
/// its slip part, so for `d = e_x` (a sampled direction, taken bit for bit) at unit speed
/// `omega_pre = DB_GAIN (n x e_x)`, and the layer holds it times the run-time gain (1) over the
/// layer's thickness (2 spacings, Eq. 1's velocity jump as a vorticity):
/// `omega_ABL = DB_GAIN |V| (n x e_x) / (2 h)`, up to 80 1/s here. The nearest point is found
/// by brute force over the recomputed Fibonacci normals (a tie within rounding accepts either)
/// and the layer by the analytic distance `|x - c| - R`; the comparison is to 1e-12 of 80 1/s.
/// Then, step after step, a particle outside the layer at the step's start (the ball having
/// moved by `SPEED t`) keeps its value exactly as it moves: the field rides on the particles.
#[test]
fn the_particles_carry_the_lookup_unchanged() {
    let dir = tempfile::tempdir().expect("temp dir");
    let db = database(dir.path());
    let mut p = built(&text(&common::abl_line(&db), "[turbulence]\nc_p = 0.0"));
    tag(&mut p);
    let before = by_tag(&p);
    let normals = fixture_normals();
    let layer = 2.0 * H;
    let scale = DB_GAIN * SPEED / layer;
    let tolerance = 1e-12 * scale;
    // The candidate values at `x` (one, or two or more on a tie within rounding).
    let expected = |x: &Vec3| -> Vec<Vec3> {
        let local = x - ball_centre(0.0);
        let d2: Vec<Real> = normals
            .iter()
            .map(|n| (n * RADIUS - local).norm_squared())
            .collect();
        let best = d2.iter().copied().fold(Real::INFINITY, Real::min);
        d2.iter()
            .zip(&normals)
            .filter(|(d, _)| **d <= best + 1e-12 * RADIUS * RADIUS)
            .map(|(_, n)| n.cross(&Vec3::x()) * scale)
            .collect()
    };
    p.step(None, None).expect("steps");
    let after = by_tag(&p);
    let (mut attached, mut ties, mut worst) = (0, 0, 0.0 as Real);
    for (id, (x0, _)) in &before {
        let got = after[id].1;
        let distance = (x0 - ball_centre(0.0)).norm() - RADIUS;
        if (distance - layer).abs() < 1e-12 {
            continue; // on the layer's edge within rounding: either is right
        }
        if distance < layer {
            let want = expected(x0);
            ties += usize::from(want.len() > 1);
            let err = want
                .iter()
                .map(|w| (got - w).norm())
                .fold(Real::INFINITY, Real::min);
            worst = worst.max(err);
            assert!(
                err <= tolerance,
                "particle {id} at {x0:?}: {got:?} against {want:?}"
            );
            attached += 1;
        } else {
            assert_eq!(got, Vec3::zeros(), "particle {id} outside the layer");
        }
    }
    eprintln!("{attached} particles in the layer ({ties} ties), worst error {worst:e} 1/s");
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
            if *w != Vec3::zeros() && (x - ball_centre(t)).norm() - RADIUS >= layer * (1.0 + 1e-9) {
                assert_eq!(end[id].1, *w, "particle {id} lost its value");
                kept += 1;
                moved = moved.max((end[id].0 - x).norm());
            }
        }
    }
    assert!(kept > 50, "{kept} particles followed outside the layer");
    assert!(moved > 0.1 * H, "the carrying particles moved {moved} m");
}

/// K(sigma), m^3: the vorticity of the kernel of Eqs. 11-13 (as corrected in the book's paper
/// notes: `u = (|omega_p| / 2) rho exp(-r^2 / (2 sigma^2)) e_phi`) integrated over its cut-off ball
/// `r < sqrt(6) sigma`, per unit omega_p. By the divergence theorem the integral of the curl is
/// the surface integral of `n x u`, `(4/3) pi R^3 g(R) omega_p` with `g(R) = exp(-R^2 / (2
/// sigma^2)) = exp(-3)` at `R = sqrt(6) sigma`: `K = (4/3) pi (sqrt(6) sigma)^3 exp(-3)`,
/// written here from that formula, not taken from the code.
fn kernel_integral(sigma: Real) -> Real {
    let r = 6f64.sqrt() * sigma;
    4.0 / 3.0 * std::f64::consts::PI * r.powi(3) * (-3f64).exp()
}

/// Seeds `samples` with p_T clamped to 1 (c_p = 1e9) and checks the result against a replay of
/// Figure 9, lines 11-20, written here from the paper, not from the code: visiting the seeds in
/// order, each sits at a sample that still held vorticity, has the radius `sqrt(6) sigma =
/// min(r_max, l_m)` of that sample (section 4.3) and no less than `r_min`, and holds in its
/// kernel, `omega_p K(sigma)` with the analytic K above, exactly the sum of omega_ABL times
/// volume of the samples closer than its radius that were not yet emptied (brute force over all
/// samples), to 1e-12 of their absolute sum. After the call the samples are the replay's: those
/// taken are zero, all others bit for bit as they were; a sample left with vorticity would not
/// seed (p_T < 1, or a radius under r_min). So what the seeds hold plus what is left is what
/// there was: vorticity is conserved to 1e-12 of the total |omega| V. Returns the seed count.
fn conserves(mut samples: SeedSamples, r_max: Real) -> usize {
    let before = samples.clone();
    let scale: Real = before
        .omega
        .iter()
        .zip(&before.volume)
        .map(|(w, v)| w.norm() * v)
        .sum();
    let total: Vec3 = before
        .omega
        .iter()
        .zip(&before.volume)
        .map(|(w, v)| w * *v)
        .sum();
    let (c_p, u0, dt) = (1e9, 1.0, 1e-3);
    let params = SeedingParams {
        c_p,
        u0,
        r_max,
        r_min: 0.25 * r_max,
    };
    let seeds = seed(&mut samples, &params, dt, &mut ChaCha8Rng::seed_from_u64(5));
    // The replay.
    let mut left = before.omega.clone();
    let (mut held, mut worst) = (Vec3::zeros(), 0.0 as Real);
    for (q, s) in seeds.iter().enumerate() {
        let i = before
            .x
            .iter()
            .position(|x| *x == s.x)
            .expect("a seed sits at a sample");
        assert_ne!(left[i], Vec3::zeros(), "seed {q} at an emptied sample");
        let r = r_max.min(before.wall_distance[i]);
        let radius = 6f64.sqrt() * s.sigma;
        assert!(
            (radius - r).abs() <= 1e-12 * r,
            "seed {q}: radius {radius} against min(r_max, l_m) = {r}"
        );
        assert!(r >= params.r_min, "seed {q} of radius {r} under r_min");
        let (mut taken, mut size) = (Vec3::zeros(), 0.0);
        for (j, w) in left.iter_mut().enumerate() {
            if *w != Vec3::zeros() && (before.x[j] - before.x[i]).norm_squared() < r * r {
                taken += *w * before.volume[j];
                size += w.norm() * before.volume[j];
                *w = Vec3::zeros();
            }
        }
        let kernel = s.omega * kernel_integral(s.sigma);
        worst = worst.max((kernel - taken).norm() / size);
        assert!(
            (kernel - taken).norm() <= 1e-12 * size,
            "seed {q}: its kernel holds {kernel:?}, it took {taken:?}"
        );
        held += kernel;
    }
    assert_eq!(samples.omega, left, "the samples are the replay's");
    for (j, w) in left.iter().enumerate() {
        if *w != Vec3::zeros() {
            let l = before.wall_distance[j];
            let p_t = 2.0 * c_p * dt * (l * w.norm() / u0).powi(2);
            assert!(
                p_t < 1.0 || r_max.min(l) < params.r_min,
                "sample {j} (l_m = {l}, p_T = {p_t}) kept its vorticity"
            );
        }
    }
    let after: Vec3 = left.iter().zip(&before.volume).map(|(w, v)| w * *v).sum();
    let imbalance = (held + after - total).norm();
    eprintln!(
        "{} seeds from {} samples: kernels within {worst:e} of what they took, \
         |held + left - before| = {imbalance:e} of {scale:e}",
        seeds.len(),
        before.len()
    );
    assert!(
        imbalance <= 1e-12 * scale,
        "{held:?} + {after:?} != {total:?}"
    );
    seeds.len()
}

/// One seeding function for both media: samples made from SPH particles (volume m / rho, the
/// particles' wall distance) and from grid cells (cell volume, the grid's wall distance) both
/// seed as Figure 9 says and conserve the vorticity they give up, checked against the replay
/// and the analytic kernel integral of [`conserves`].
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

/// The tank's inside, `[0, 0.8] x [0, 0.5] x [0, 0.4]` m (the container box of [`text`]).
const TANK: [Real; 3] = [0.8, 0.5, 0.4];

/// Distance from `x` to the nearest wall at time `t`, from the scene's geometry: the tank's
/// faces and the ball's surface (negative inside a solid).
fn analytic_wall_distance(x: &Vec3, t: Real) -> Real {
    let faces = (0..3)
        .map(|a| x[a].min(TANK[a] - x[a]))
        .fold(Real::INFINITY, Real::min);
    faces.min((x - ball_centre(t)).norm() - RADIUS)
}

/// `m` directions spread evenly over the unit sphere (a Fibonacci lattice).
fn directions(m: usize) -> Vec<Vec3> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..m)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as Real + 0.5) / m as Real;
            let r = (1.0 - z * z).sqrt();
            Vec3::new(
                r * (golden * i as Real).cos(),
                r * (golden * i as Real).sin(),
                z,
            )
        })
        .collect()
}

/// Section 6 ("we reduce a particle's kernel size once it extends past the liquid phase"),
/// checked against the scene's geometry rather than the code's own surface and wall distances.
/// Four vortices by hand: one centred three spacings above the water (no fluid particle within
/// one spacing) and one inside the ball are removed; one whose 5-spacing kernel reaches past the
/// free surface is shrunk, keeping its peak vorticity, to the distance from its centre, 1.5
/// spacings under the top row of particles and half a spacing off the lattice's columns in x
/// and z, to the nearest particle of that row (the free surface), `sqrt(0.5^2 + 1.5^2 + 0.5^2)
/// h = 1.658 h` (to 1e-9): not past the liquid's surface half a spacing above that row (2 h).
/// One deep and small is left alone.
///
/// Then, over a run that seeds, after every step each kernel (as the stage left it, against
/// the fluid and the ball at the step's start) is centred in the water (within one spacing of
/// a fluid particle) inside the tank and outside the ball; its radius is at most the distance
/// to the tank's faces and the ball's surface (to 1e-9); and no point of its support (sampled
/// on spheres of its radius and half of it) lies past the free surface. A point is in the
/// liquid when more than half of a ball of two spacings around it holds fluid particles: more
/// than half of the `(4/3) pi 2^3 = 33.5` a ball holds at the rest spacing. A point on a flat
/// free surface has half, one half a spacing beyond it about 10.6; the test checks the rule on
/// the hand-placed kernel (the shrunk one's top has 24 particles around it, the unshrunk one's
/// none). Points within two spacings of a wall are left to the wall bound: there the ball of
/// the count reaches into the solid, and the fluid keeps clear of the moving ball's surface.
#[test]
fn vortex_kernels_stay_inside_the_liquid() {
    let dir = tempfile::tempdir().expect("temp dir");
    let db = database(dir.path());
    let p = built(&text(&common::abl_line(&db), ""));
    let s = sph(&p);
    let top = s.fluid.x.iter().map(|x| x.y).fold(0.0, Real::max);
    // The water was seeded on the lattice (i + 1/2) h to 0.35 m: its top row is at 0.3375 m.
    assert!((top - (0.35 - 0.5 * H)).abs() < 1e-12, "top row at {top} m");
    let reach = 6.0 * H;
    let mut v = VortexParticles::new();
    let omega = Vec3::new(0.0, 0.0, 3.0);
    let sigma = kernel::sigma_for_radius(5.0 * H);
    let shallow_at = Vec3::new(0.6, top - 1.5 * H, 0.2);
    let deep_at = Vec3::new(0.6, 0.15, 0.2);
    v.push(Vec3::new(0.6, top + 3.0 * H, 0.2), omega, sigma)
        .expect("a valid vortex"); // above the water
    v.push(ball_centre(0.0), omega, sigma)
        .expect("a valid vortex"); // inside the ball
    v.push(shallow_at, omega, sigma).expect("a valid vortex"); // under the surface
    let deep = kernel::sigma_for_radius(2.5 * H);
    v.push(deep_at, omega, deep).expect("a valid vortex"); // deep, small
    let surface = Surface::of(s, reach);
    let removed = fit_to_liquid(&mut v, s, &surface);
    assert_eq!(removed, 2);
    assert_eq!(v.x, vec![shallow_at, deep_at]);
    let shallow = v.radius(0);
    let want = (0.25 + 2.25 + 0.25 as Real).sqrt() * H;
    eprintln!(
        "shallow kernel shrunk from {} to {shallow} m, {} spacings (expected {})",
        5.0 * H,
        shallow / H,
        want / H
    );
    assert!(
        (shallow - want).abs() <= 1e-9 * want,
        "radius {shallow} against {want} to the top row"
    );
    assert!(shallow < 2.0 * H, "past the liquid's surface");
    assert_eq!(v.omega[0], omega, "the peak vorticity is kept");
    assert_eq!(v.sigma[1], deep);
    // Fluid particles in a ball of two spacings' radius at the rest spacing, (4/3) pi 2^3 =
    // 33.5: a point past the free surface has fewer than half of them around it. So it tells
    // the liquid from the air: the top of the shrunk kernel has more, that of the kernel as it
    // was (3.5 spacings above the top row) none.
    let half_ball = 0.5 * 4.0 / 3.0 * std::f64::consts::PI * 8.0;
    let around =
        |water: &[Vec3], p: &Vec3| water.iter().filter(|y| (*y - p).norm() < 2.0 * H).count();
    let (inside, outside) = (
        around(&s.fluid.x, &(shallow_at + Vec3::y() * shallow)),
        around(&s.fluid.x, &(shallow_at + Vec3::y() * 5.0 * H)),
    );
    eprintln!("{inside} and {outside} fluid particles around the shrunk and unshrunk tops");
    assert!(
        inside as Real > half_ball && outside == 0,
        "{inside} and {outside} particles around the kernels' tops"
    );
    // A run with eager seeding.
    let mut p = built(&text(
        &common::abl_line(&db),
        "[turbulence]\nc_p = 1e3\nr_max = 4.0\ndissipation_radius = 1.0",
    ));
    let sphere = directions(32);
    let (mut seen, mut fewest, mut worst_wall, mut shrunk) = (0, usize::MAX, 0.0 as Real, 0);
    for _ in 0..6 {
        let (water, t) = {
            let s = sph(&p);
            (s.fluid.x.clone(), s.time())
        };
        p.step(None, None).expect("steps");
        let v = &common::turbulence(&p).vortices;
        seen = seen.max(v.len());
        for q in 0..v.len() {
            let (x, r) = (v.x[q], v.radius(q));
            shrunk += usize::from(r < 4.0 * H * (1.0 - 1e-12));
            let near: Vec<Vec3> = water
                .iter()
                .filter(|y| (*y - x).norm() < r + 2.0 * H)
                .copied()
                .collect();
            let to_water = |p: &Vec3| {
                near.iter()
                    .map(|y| (y - p).norm())
                    .fold(Real::INFINITY, Real::min)
            };
            assert!(to_water(&x) < H, "vortex {q} at {x:?} is out of the water");
            let walls = analytic_wall_distance(&x, t);
            assert!(walls > 0.0, "vortex {q} at {x:?} in a wall");
            worst_wall = worst_wall.max(r / walls);
            assert!(
                r <= walls * (1.0 + 1e-9),
                "vortex {q} at {x:?} of radius {r} reaches into a wall {walls} m away"
            );
            for d in &sphere {
                for f in [0.5, 1.0] {
                    let point = x + d * (f * r);
                    if analytic_wall_distance(&point, t) < 2.0 * H {
                        continue; // the count's ball reaches a wall, which the radius clears
                    }
                    let count = around(&near, &point);
                    fewest = fewest.min(count);
                    assert!(
                        count as Real > half_ball,
                        "vortex {q} at {x:?} of radius {r}: its support at {point:?} has {count} \
                         fluid particles within two spacings, not more than half a ball's \
                         {half_ball}: it is past the free surface"
                    );
                }
            }
        }
    }
    eprintln!(
        "{seen} kernels at most, {shrunk} shrunk; at least {fewest} fluid particles within two \
         spacings of a support point (more than {half_ball} asserted); radius at most \
         {worst_wall} of the wall distance"
    );
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
/// stream cascade as section 4.2 says, the history derived here from the paper's rules with
/// the scene defaults (n = 2 children, C = 1 s/m^(2/3), split radius 3 spacings), not from the
/// code's: a particle of scale sigma (radius `sqrt(6) sigma`, below the split radius, so in the
/// inertial range) splits once its age reaches the Kolmogorov time `C (sigma^(2/3) -
/// sigma_c^(2/3))` into n children of `sigma_c = n^(-1/3) sigma` (the parent's volume) with
/// `|omega_c| = |omega| (sigma / sigma_c)^(5/3) / sqrt(n)` (energy `E ~ |omega|^2 sigma^5`, so
/// `E_parent / E_child = n (kappa_parent / kappa_child)^(-5/3)`), and a child whose radius is
/// under the dissipation radius is dissipated. With the step dt = 2 ms the splits come after
/// `ceil(T_g / dt)` steps of each generation's age: T_0 = 12.37 ms (7 steps), T_1 = 10.61 ms
/// (6), T_2 = 9.09 ms (5), T_3 = 7.79 ms (4), each at least 0.1 step from a whole step, so the
/// summed ages' rounding cannot move a split; the radii are 2.5, 1.98, 1.57, 1.25 and 0.99
/// spacings. At the particle default of one spacing three generations live: 1 particle for
/// steps 1-6, 2 for 7-12, 4 for 13-17, 8 for 18-21, then none (the fourth split's children are
/// dissipated). At the grid's two cells the first split's children (1.98 spacings) are
/// dissipated: the seed is gone after step 7. The count after every step, and the radius and
/// strength of every living particle (to 1e-12), are those.
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
    // The defaults the derivation below assumes.
    let defaults = TurbulenceParams::default();
    assert_eq!(defaults.dissipation(true), 1.0);
    assert_eq!(defaults.dissipation(false), 2.0);
    assert_eq!((PARTICLE_DISSIPATION, GRID_DISSIPATION), (1.0, 2.0));
    assert_eq!(
        (
            defaults.children,
            defaults.cascade_time,
            defaults.split_radius
        ),
        (2, 1.0, 3.0)
    );
    let (n, c) = (2.0 as Real, 1.0 as Real);
    let dt = 2e-3;
    let birth = 2.5 * h;
    let strength = 20.0;
    let cutoff = 6f64.sqrt();
    // The history of section 4.2: (count, radius, strength) after each step.
    let predict = |dissipation: Real, steps: usize| -> Vec<(usize, Real, Real)> {
        let (mut sigma, mut w, mut alive, mut age_steps) = (birth / cutoff, strength, 1, 0);
        let mut history = Vec::new();
        for _ in 0..steps {
            age_steps += 1;
            let child = sigma * n.powf(-1.0 / 3.0);
            let split_time = c * (sigma.powf(2.0 / 3.0) - child.powf(2.0 / 3.0));
            let whole = split_time / dt;
            assert!(
                (whole - whole.round()).abs() > 0.1,
                "T = {split_time} s is {whole} steps: too close to a whole step"
            );
            if alive > 0 && age_steps as Real >= whole {
                w *= (sigma / child).powf(5.0 / 3.0) / n.sqrt();
                sigma = child;
                age_steps = 0;
                alive *= 2;
                if cutoff * sigma < dissipation * h {
                    alive = 0;
                }
            }
            history.push((alive, cutoff * sigma, w));
        }
        history
    };
    let run = |dissipation: Real, steps: usize| -> Vec<(usize, Real, Real)> {
        let settings = DynamicsSettings {
            dissipation_cells: dissipation,
            inertial_radius: defaults.split_radius * h,
            children: defaults.children,
            cascade_time: defaults.cascade_time,
            ..DynamicsSettings::default()
        };
        let mut dynamics = Dynamics::new(settings, 7).expect("settings");
        let mut v = VortexParticles::new();
        v.push(
            Vec3::new(0.2, 0.2, 0.2),
            Vec3::new(0.0, 0.0, strength),
            birth / cutoff,
        )
        .expect("a valid vortex");
        (0..steps)
            .map(|_| {
                dynamics.step(&mut v, &source, dt, h);
                let radius = (0..v.len()).map(|q| v.radius(q)).fold(0.0, Real::max);
                let w = v.omega.iter().map(|w| w.norm()).fold(0.0, Real::max);
                // Every living particle is of one generation: one radius, one strength.
                for q in 0..v.len() {
                    assert!((v.radius(q) - radius).abs() <= 1e-12 * radius);
                    assert!((v.omega[q].norm() - w).abs() <= 1e-12 * w);
                }
                (v.len(), radius, w)
            })
            .collect()
    };
    let check = |dissipation: Real, counts: &[usize]| {
        let steps = counts.len();
        let predicted = predict(dissipation, steps);
        let got = run(dissipation, steps);
        let predicted_counts: Vec<usize> = predicted.iter().map(|p| p.0).collect();
        assert_eq!(predicted_counts, counts, "the derivation's history");
        for (k, (g, p)) in got.iter().zip(&predicted).enumerate() {
            assert_eq!(g.0, p.0, "step {}: {got:?}", k + 1);
            if g.0 > 0 {
                assert!(
                    (g.1 - p.1).abs() <= 1e-12 * p.1,
                    "step {}: radius {} against {}",
                    k + 1,
                    g.1,
                    p.1
                );
                assert!(
                    (g.2 - p.2).abs() <= 1e-12 * p.2,
                    "step {}: strength {} against {}",
                    k + 1,
                    g.2,
                    p.2
                );
            }
        }
    };
    let hand = |runs: &[(usize, usize)], steps: usize| -> Vec<usize> {
        let mut v: Vec<usize> = runs
            .iter()
            .flat_map(|&(count, len)| std::iter::repeat_n(count, len))
            .collect();
        v.resize(steps, 0);
        v
    };
    // Three generations at one spacing; no child survives at two.
    check(1.0, &hand(&[(1, 6), (2, 6), (4, 5), (8, 4)], 40));
    check(2.0, &hand(&[(1, 6)], 40));
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
/// tank, without the reference, gives the plain, random and ABL rows, with vortex particles in
/// the two seeded runs and none in the plain one, and their profiles at the default stations
/// (two and four ball lengths from the ball's start along x; the second, 0.89 m, lies beyond
/// the 0.85 m domain and is left out), 8 bins of two spacings across z. What they measure must
/// obey:
/// - each row's mean k is the mean of the k column its profiles file holds (the table and the
///   file agree);
/// - every bin's k, half a velocity variance, is finite and >= 0;
/// - every bin's time-averaged U is under a tenth of the ball's speed V: the ball is pulled
///   along +x, so the station (x from 0.55 to 0.6 m) lies ahead of it (its centre reaches
///   x = 0.29 m at the end, t = 0.04 s) in water at rest at t = 0. There the sphere's potential
///   flow is at most `V (R/d)^3 = 0.029 V` (d >= 0.26 m from its centre) and the closed tank's
///   return flow is about V times the ball's volume over the water's, 0.019 V: 0.048 V
///   together, the bound twice that for the SPH noise and the synthesised kernels.
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
    assert!(
        rows[0].particles == 0 && rows[0].mean_particles == 0.0,
        "{:?}",
        rows[0]
    );
    assert!(rows[1].mean_particles > 0.0, "{:?}", rows[1]);
    assert!(rows[2].mean_particles > 0.0, "{:?}", rows[2]);
    let (mut fastest, mut largest_k): (Real, Real) = (0.0, 0.0);
    for r in &rows {
        let file = dir.path().join(format!("profiles/{}.csv", r.label));
        let csv = std::fs::read_to_string(&file).expect("profiles");
        let bins: Vec<(Real, Real)> = csv
            .lines()
            .skip(1)
            .map(|l| {
                let c: Vec<Real> = l.split(',').map(|x| x.parse().expect("a number")).collect();
                (c[2], c[3])
            })
            .collect();
        assert_eq!(bins.len(), 8, "{}", r.label);
        let mean_k = bins.iter().map(|b| b.1).sum::<Real>() / bins.len() as Real;
        assert!(
            (mean_k - r.mean_k).abs() <= 1e-12 * r.mean_k,
            "{}: mean k {} against the file's {mean_k}",
            r.label,
            r.mean_k
        );
        for (u, k) in bins {
            assert!(k.is_finite() && k >= 0.0, "{}: k = {k}", r.label);
            assert!(
                u.is_finite() && u.abs() < 0.1 * SPEED,
                "{}: U = {u} m/s",
                r.label
            );
            fastest = fastest.max(u.abs());
            largest_k = largest_k.max(k);
        }
    }
    eprintln!("|U| at most {fastest} m/s, k at most {largest_k} m^2/s^2");
    // Two and four ball lengths from the ball's start (0.25 m + 2 and 4 times its 0.16 m): the
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
