//! Particles that leave the domain through a side no wall closes are removed and counted, not
//! fatal: a splash over the top of an open pool loses exactly the particles it throws out, the
//! run finishes, `metrics.csv` counts them and every per-particle array (carried fields, the
//! refinements' state, the neighbourhood) follows; losing more than `fluid.lost_fraction` of
//! the fluid stops the run with the count and the side; kinetic energy the scene has no source
//! for stops it too.

use std::path::Path;

use eddy::pipeline::{Run, RunError, RunOptions};
use eddy::scene::{parse_str, Scene};
use eddy::sph::{Instability, SphSolver};
use eddy::{Real, Vec3};

/// A pool 0.1 x 0.06 x 0.05 m at 1 cm between four walls and a floor, open at the top (y =
/// 0.2 m), and above its water a `nx` x 1 x `nz` sheet of particles thrown up at 3 m/s: it
/// leaves through the top within 0.04 s. `fluid` adds keys to `[fluid]`, `extra` whole tables.
fn splash(nx: usize, nz: usize, fluid: &str, extra: &str) -> Scene {
    load(&splash_text(nx, nz, fluid, extra)).expect("the splash scene loads")
}

fn load(text: &str) -> Result<Scene, eddy::scene::SceneError> {
    parse_str(text, Path::new("splash.toml"), &[])
}

/// The text of [`splash`].
fn splash_text(nx: usize, nz: usize, fluid: &str, extra: &str) -> String {
    format!(
        r#"
name = "splash"
[domain]
min = [-0.05, -0.05, -0.05]
max = [0.15, 0.2, 0.1]
[time]
end = 0.1
cfl = 0.4
dt_max = 2e-3
[fluid]
spacing = 0.01
{fluid}
[[fluid.blocks]]
min = [0.0, 0.0, 0.0]
max = [0.1, 0.06, 0.05]
[[fluid.blocks]]
min = [0.03, 0.1, 0.01]
max = [{x1}, 0.112, {z1}]
velocity = [0.0, 3.0, 0.0]
[[obstacles]]
name = "floor"
shape = {{ type = "box", half_extents = [0.1, 0.025, 0.075] }}
position = [0.05, -0.025, 0.025]
[[obstacles]]
name = "left"
shape = {{ type = "box", half_extents = [0.025, 0.125, 0.075] }}
position = [-0.025, 0.075, 0.025]
[[obstacles]]
name = "right"
shape = {{ type = "box", half_extents = [0.025, 0.125, 0.075] }}
position = [0.125, 0.075, 0.025]
[[obstacles]]
name = "front"
shape = {{ type = "box", half_extents = [0.1, 0.125, 0.025] }}
position = [0.05, 0.075, -0.025]
[[obstacles]]
name = "back"
shape = {{ type = "box", half_extents = [0.1, 0.125, 0.025] }}
position = [0.05, 0.075, 0.075]
[output]
vtk = false
metrics = ["particles", "lost_particles"]
{extra}
"#,
        x1 = 0.032 + 0.01 * nx as Real,
        z1 = 0.012 + 0.01 * nz as Real,
    )
}

fn start(scene: &Scene, out: &Path) -> Run {
    let options = RunOptions {
        out: Some(out.to_path_buf()),
        progress: false,
        ..RunOptions::default()
    };
    Run::start(scene, &options).expect("the run starts")
}

fn sph(run: &Run) -> &SphSolver {
    run.pipeline.sim.sph.as_ref().expect("an SPH scene")
}

/// The `column` of `metrics.csv` in `out`, row by row.
fn column(out: &Path, column: &str) -> Vec<Real> {
    let text = std::fs::read_to_string(out.join("metrics.csv")).expect("metrics.csv");
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("a header").split(',').collect();
    let k = header.iter().position(|c| *c == column).expect(column);
    lines
        .map(|l| {
            l.split(',')
                .nth(k)
                .expect("a value")
                .parse()
                .expect("a number")
        })
        .collect()
}

/// One particle thrown out of the pool's open top is removed and counted, with VRSPH's and
/// micropolar's per-particle state and a carried field: every array keeps one entry per
/// particle, the carried values stay with their particles (each still holds its own starting
/// position), the run finishes, and `lost_particles` in `metrics.csv` goes from 0 to 1 at the
/// step the particle left while `particles` drops by one.
#[test]
fn a_particle_thrown_out_of_an_open_side_is_removed_and_counted() {
    for method in ["vrsph", "micropolar"] {
        let dir = tempfile::tempdir().expect("temp dir");
        let scene = splash(1, 1, "", &format!("[refinement]\nmethod = \"{method}\""));
        let mut run = start(&scene, dir.path());
        let start_count = sph(&run).fluid.len();
        {
            let fluid = &mut run.pipeline.sim.sph.as_mut().expect("SPH").fluid;
            let k = fluid.carry("origin");
            fluid.carried[k].1 = fluid.x.clone();
        }
        let mut lost_at = None;
        while let Some(rec) = run.advance(None).expect("the splash runs to its end") {
            let s = sph(&run);
            let n = s.fluid.len();
            for (name, field) in s.refinement_fields() {
                assert_eq!(field.len(), n, "{method}: {name}");
            }
            assert_eq!(s.fluid.carried[0].1.len(), n);
            assert_eq!(s.density_ratios().len(), n);
            assert_eq!(s.factors().len(), n);
            assert_eq!(s.neighborhood().x.len(), n);
            assert_eq!(s.lost_particles(), (start_count - n) as u64);
            if n < start_count && lost_at.is_none() {
                lost_at = Some(rec.step);
            }
        }
        let summary = run.finish().expect("finishes");
        assert_eq!(summary.lost_particles, 1, "{method}");
        assert_eq!(summary.fluid_particles, start_count - 1);
        let s = sph(&run);
        let origins = &s.fluid.carried[0].1;
        assert!(
            origins.iter().all(|o| o.y < 0.06),
            "{method}: the thrown particle's carried value stayed behind"
        );
        let lost_at = lost_at.expect("the particle left") as usize;
        let lost = column(dir.path(), "lost_particles");
        let particles = column(dir.path(), "particles");
        assert!(lost[..lost_at].iter().all(|&l| l == 0.0), "{lost:?}");
        assert!(lost[lost_at..].iter().all(|&l| l == 1.0), "{lost:?}");
        assert_eq!(particles[lost_at], start_count as Real);
        assert_eq!(particles[lost_at + 1], (start_count - 1) as Real);
        let t = column(dir.path(), "time")[lost_at];
        assert!(t > 0.02 && t < 0.05, "{method}: lost at t = {t}");
    }
}

/// Nine particles thrown out at once are more than 2 % of the 300 left: the run stops with the
/// new diagnostic, which names the count and the side; at 5 % the same run finishes with all
/// nine counted.
#[test]
fn losing_more_than_the_share_stops_the_run() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut run = start(&splash(3, 3, "lost_fraction = 0.02", ""), dir.path());
    let err = loop {
        match run.advance(None) {
            Ok(Some(_)) => {}
            Ok(None) => panic!("the run lost 9 of 309 particles and went on"),
            Err(e) => break e,
        }
    };
    let text = err.to_string();
    match err {
        RunError::Unstable {
            cause:
                Instability::Lost {
                    lost,
                    particles,
                    fraction,
                    ..
                },
            ..
        } => {
            assert_eq!((lost, particles), (9, 300));
            assert_eq!(fraction, 0.02);
        }
        other => panic!("stopped for another reason: {other}"),
    }
    assert!(
        text.contains("9 fluid particles have left the domain through open sides (9 through y_max")
            && text.contains("fluid.lost_fraction = 0.02"),
        "{text}"
    );
    let dir = tempfile::tempdir().expect("temp dir");
    let mut run = start(&splash(3, 3, "lost_fraction = 0.05", ""), dir.path());
    while run.advance(None).expect("runs").is_some() {}
    assert_eq!(run.finish().expect("finishes").lost_particles, 9);
}

/// The energy stop: a block without gravity, walls or inflow, started at 0.1 m/s, may reach a
/// mean kinetic energy of 1/2 (10 x 0.1 m/s)^2 = 0.5 J/kg; with its velocities written to
/// 0.9 m/s (0.405 J/kg) after the first step it runs on, at 1.1 m/s (0.605 J/kg) the next step
/// stops, naming both.
#[test]
fn kinetic_energy_without_a_source_stops_the_run() {
    let text = r#"
name = "block"
gravity = [0.0, 0.0, 0.0]
[domain]
min = [-1.0, -1.0, -1.0]
max = [1.0, 1.0, 1.0]
[time]
end = 0.1
[fluid]
spacing = 0.02
[[fluid.blocks]]
min = [0.0, 0.0, 0.0]
max = [0.1, 0.1, 0.1]
velocity = [0.1, 0.0, 0.0]
"#;
    let scene = parse_str(text, Path::new("block.toml"), &[]).expect("loads");
    let mut s = eddy::pipeline::sph_solver(&scene).expect("builds");
    s.step(None).expect("the first step runs");
    s.fluid.v.fill(Vec3::new(0.0, 0.9, 0.0));
    s.update_neighborhoods();
    s.step(None).expect("under the bound");
    s.fluid.v.fill(Vec3::new(0.0, 1.1, 0.0));
    s.update_neighborhoods();
    match s.step(None) {
        Err(Instability::Energy { energy, bound, .. }) => {
            assert!((energy - 0.605).abs() < 1e-3, "{energy}");
            assert!((bound - 0.5).abs() < 1e-12, "{bound}");
        }
        other => panic!("not stopped for its energy: {other:?}"),
    }
}

/// Out-of-range shares and ramps are refused with the key and what it allows: a ramp under
/// blocks of different velocities (the splash's pool is still, its sheet moves) has no one
/// velocity to accelerate the fluid to.
#[test]
fn bad_shares_and_ramps_are_refused() {
    let refused = |fluid: &str, key: &str, allowed: &str| {
        let text = load(&splash_text(1, 1, fluid, ""))
            .expect_err("refused")
            .to_string();
        assert!(text.contains(key) && text.contains(allowed), "{text}");
    };
    refused("lost_fraction = 1.5", "fluid.lost_fraction", "[0, 1]");
    refused("lost_fraction = -0.01", "fluid.lost_fraction", "[0, 1]");
    refused("ramp = -0.1", "fluid.ramp", ">= 0");
    refused(
        "ramp = 0.2",
        "fluid.ramp",
        "0 while the blocks' velocities differ (fluid.blocks[0] and fluid.blocks[1])",
    );
}
