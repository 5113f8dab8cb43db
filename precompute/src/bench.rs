//! `eddy-precompute bench`: precomputation time per direction against grid size, the mean
//! relative interpolation error of lookups at off-sample directions against direct
//! precomputation there, as a function of the azimuth samples (Pfaff et al. 2009, Figure 12),
//! and lookup throughput in boundary points per second.

use std::collections::HashMap;
use std::path::Path;
use std::time::Instant;

use eddy::abl::{AblData, AblDatabase, AblHeader, DirectionTable, MotionKind, Sampling};
use eddy::{Point3, Real, Vec3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::solve::{solve, Surface};
use crate::spec::ObstacleSpec;

/// Options of `eddy-precompute bench`.
#[derive(Debug, Clone, clap::Args)]
pub struct BenchArgs {
    /// Grid resolutions timed per direction (sphere, default settings, one thread).
    #[arg(long, value_delimiter = ',', default_value = "16,32,48,64")]
    pub sizes: Vec<usize>,
    /// Azimuth sample counts of the interpolation error (polar samples: half of these, + 1).
    #[arg(long, value_delimiter = ',', default_value = "5,10,20,40")]
    pub azimuths: Vec<usize>,
    /// Grid resolution of the interpolation-error runs.
    #[arg(long, default_value_t = 32)]
    pub error_resolution: usize,
    /// Off-sample test directions of the interpolation error.
    #[arg(long, default_value_t = 6)]
    pub directions: usize,
    /// Boundary points of the lookup throughput database.
    #[arg(long, default_value_t = 200_000)]
    pub lookup_points: usize,
    /// Leave out the parts whose names are given: timing, error, lookup.
    #[arg(long, value_delimiter = ',')]
    pub skip: Vec<String>,
}

const SPHERE: &str = r#"
name = "sphere"
shape = { type = "sphere", radius = 0.5 }
"#;
const BOX: &str = r#"
name = "box"
shape = { type = "box", half_extents = [0.5, 0.3, 0.2] }
"#;

fn spec(text: &str, overrides: &[String]) -> anyhow::Result<ObstacleSpec> {
    ObstacleSpec::parse(text, Path::new("bench.toml"), overrides)
}

/// Runs the parts not skipped and prints their tables.
pub fn run(args: &BenchArgs) -> anyhow::Result<()> {
    let want = |name: &str| !args.skip.iter().any(|s| s == name);
    println!("threads: {}", rayon::current_num_threads());
    if want("timing") {
        timing(&args.sizes)?;
    }
    if want("error") {
        for (name, text) in [("sphere", SPHERE), ("box", BOX)] {
            interpolation_error(name, text, args)?;
        }
    }
    if want("lookup") {
        lookup_throughput(args.lookup_points)?;
    }
    Ok(())
}

/// Seconds of one direction on one thread, translation and rotation, per resolution.
fn timing(sizes: &[usize]) -> anyhow::Result<()> {
    println!(
        "\n# time per direction (sphere, domain 4, default settings: at most 50 + 50 steps, \
         settle_tolerance 4e-3, tolerance 1e-3; one thread)"
    );
    println!("| grid | points | translation s | rotation s | 2 x 162 distinct on 2 cores, min |");
    println!("|---|---|---|---|---|");
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    for &n in sizes {
        let spec = spec(SPHERE, &[format!("grid.resolution={n}")])?;
        let surface = Surface::of(&spec)?;
        let d = Vec3::new(1.0, 0.4, -0.3).normalize();
        let mut secs = [0.0; 2];
        for (k, kind) in MotionKind::ALL.into_iter().enumerate() {
            let t = Instant::now();
            pool.install(|| solve(&spec, &surface, kind, &d))?;
            secs[k] = t.elapsed().as_secs_f64();
        }
        let distinct = Sampling::new(10, 20)
            .map_err(anyhow::Error::msg)?
            .distinct()
            .len() as f64;
        println!(
            "| {n}^3 | {} | {:.2} | {:.2} | {:.1} |",
            surface.points.len(),
            secs[0],
            secs[1],
            distinct * (secs[0] + secs[1]) / 2.0 / 60.0
        );
    }
    Ok(())
}

/// Mean relative error of interpolated omega against a direct solve at random directions, per
/// azimuth sample count; only the samples that [`Sampling::weights`] uses for the test
/// directions are solved (each once), weighted exactly as [`AblDatabase::lookup`] weights them.
/// The last column interpolates the potential-flow field `1.5 (d x n)` (linear in d) with the
/// same weights: the error of the interpolant alone, without the solver's departure from it.
fn interpolation_error(name: &str, text: &str, args: &BenchArgs) -> anyhow::Result<()> {
    let spec = spec(
        text,
        &[format!("grid.resolution={}", args.error_resolution)],
    )?;
    let surface = Surface::of(&spec)?;
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let tests: Vec<Vec3> = (0..args.directions)
        .map(|_| {
            let z: Real = rng.random_range(-0.95..0.95);
            let phi: Real = rng.random_range(0.0..std::f64::consts::TAU);
            let s = (1.0 - z * z).sqrt();
            Vec3::new(s * phi.cos(), s * phi.sin(), z)
        })
        .collect();
    println!(
        "\n# interpolation error, {name} (translation, {}^3, {} points, {} random directions)",
        args.error_resolution,
        surface.points.len(),
        tests.len()
    );
    println!("| azimuth samples | polar samples | mean relative error | potential flow |");
    println!("|---|---|---|---|");
    let solve_at = |d: &Vec3| solve(&spec, &surface, MotionKind::Translation, d);
    let potential =
        |d: &Vec3| -> Vec<Vec3> { surface.normals.iter().map(|n| d.cross(n) * 1.5).collect() };
    let reference: Vec<Vec<Vec3>> = tests.iter().map(solve_at).collect::<anyhow::Result<_>>()?;
    for &m in &args.azimuths {
        let s = Sampling::new(m / 2 + 1, m).map_err(anyhow::Error::msg)?;
        let mut solved: HashMap<usize, Vec<Vec3>> = HashMap::new();
        let (mut err, mut err_potential) = (0.0, 0.0);
        for (d, exact) in tests.iter().zip(&reference) {
            let mut approx = vec![Vec3::zeros(); surface.points.len()];
            let mut approx_potential = approx.clone();
            for (row, w) in s.weights(d) {
                if w == 0.0 {
                    continue;
                }
                let sample = s.direction(row / s.azimuth, row % s.azimuth);
                if let std::collections::hash_map::Entry::Vacant(e) = solved.entry(row) {
                    e.insert(solve_at(&sample)?);
                }
                for (a, v) in approx.iter_mut().zip(&solved[&row]) {
                    *a += v * w;
                }
                for (a, v) in approx_potential.iter_mut().zip(potential(&sample)) {
                    *a += v * w;
                }
            }
            err += relative_error(&approx, exact);
            err_potential += relative_error(&approx_potential, &potential(d));
        }
        let n = tests.len() as Real;
        println!(
            "| {m} | {} | {:.2} % | {:.2} % |",
            s.polar,
            100.0 * err / n,
            100.0 * err_potential / n
        );
    }
    Ok(())
}

/// Sum of the error norms over the sum of the exact norms.
fn relative_error(approx: &[Vec3], exact: &[Vec3]) -> Real {
    let num: Real = approx.iter().zip(exact).map(|(a, e)| (a - e).norm()).sum();
    let den: Real = exact.iter().map(|e| e.norm()).sum();
    num / den
}

/// Boundary points per second of `lookup_into` with translation and rotation on a 10 x 20
/// database of `points` points (synthetic values: the cost does not depend on them).
fn lookup_throughput(points: usize) -> anyhow::Result<()> {
    let s = Sampling::new(10, 20).map_err(anyhow::Error::msg)?;
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let mut table = || DirectionTable {
        sampling: s,
        omega: (0..s.len() * points * 3)
            .map(|_| rng.random_range(-1.0..1.0))
            .collect(),
        complete: vec![true; s.len()],
    };
    let data = AblData {
        header: AblHeader {
            obstacle: "bench".into(),
            fingerprint: String::new(),
            geometry_fingerprint: String::new(),
            beta: 1.0,
            layer_thickness: 0.1,
            spacing: 0.1,
            settings: String::new(),
        },
        points: (0..points)
            .map(|i| Point3::new(i as Real, 0.0, 0.0))
            .collect(),
        normals: vec![Vec3::z(); points],
        translation: table(),
        rotation: table(),
    };
    let dir = std::env::temp_dir().join(format!("eddy-lookup-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let path = dir.join("bench.h5");
    data.write(&path)?;
    let db = AblDatabase::open(&path, None)?;
    std::fs::remove_dir_all(&dir)?;
    let mut out = vec![Vec3::zeros(); points];
    let calls = (200_000_000 / points).clamp(5, 2000);
    let t = Instant::now();
    for k in 0..calls {
        let a = k as Real * 0.37;
        let v = Vec3::new(a.cos(), a.sin(), 0.3 * (2.0 * a).cos());
        let w = Vec3::new(0.2 * a.sin(), 0.5, a.cos());
        db.lookup_into(&v, &w, &mut out);
    }
    let secs = t.elapsed().as_secs_f64();
    println!(
        "\n# lookup throughput (10 x 20 samples, translation + rotation, {points} points, {} threads)",
        rayon::current_num_threads()
    );
    println!(
        "{:.1} million boundary points per second ({calls} lookups in {secs:.2} s)",
        (calls * points) as f64 / secs / 1e6
    );
    Ok(())
}
