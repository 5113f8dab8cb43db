//! `cargo bench --bench grid_poisson`: MGPCG pressure solves in a closed box with a solid sphere
//! (radius a quarter of the box) at 32^3, 64^3 and 128^3, relative residual 1e-6, seeded white-
//! noise right-hand side. Prints iterations, build time (hierarchy and components, paid once per
//! step) and solve time (best of a few repeats), and the same for implicit diffusion at a = 1e4.
//! The sphere is voxelised by cell centres, and then, as a scene's obstacle, once a staircase and
//! once cutting cells (faces weighted by their open fraction): the cost of cut cells.

use eddy::grid::{
    solve_diffusion, Boundary, CellKind, DiffusionBoundary, DiffusionSide, PoissonSystem,
    SolverSettings,
};
use ndarray::Array3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::time::Instant;

const REPEATS: usize = 3;

/// CPU seconds used so far by this process, all threads (utime + stime of /proc/self/stat, in
/// the usual 100 Hz clock ticks): on a shared machine wall time measures the neighbours too,
/// CPU time does not. `None` where /proc is missing.
fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    let after_name = &stat[stat.rfind(')')? + 2..];
    let fields: Vec<&str> = after_name.split_whitespace().collect();
    let ticks = fields.get(11)?.parse::<f64>().ok()? + fields.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

fn sphere_box(n: usize) -> Array3<CellKind> {
    let c = n as f64 / 2.0;
    let r = n as f64 / 4.0;
    Array3::from_shape_fn((n, n, n), |(i, j, k)| {
        let d2 = [i, j, k]
            .iter()
            .map(|&v| (v as f64 + 0.5 - c).powi(2))
            .sum::<f64>();
        if d2 < r * r {
            CellKind::Solid
        } else {
            CellKind::Fluid
        }
    })
}

/// A closed unit box of n^3 cells with the sphere of [`sphere_box`] as a scene's obstacle,
/// `surface` its `grid.obstacle_surface`.
fn sphere_scene(n: usize, surface: &str) -> eddy::grid::GridSolver {
    let text = format!(
        r#"
        name = "sphere in a box"
        domain = {{ min = [0.0, 0.0, 0.0], max = [1.0, 1.0, 1.0] }}
        time = {{ end = 1.0 }}
        [grid]
        resolution = [{n}, {n}, {n}]
        obstacle_surface = "{surface}"
        [[obstacles]]
        name = "sphere"
        shape = {{ type = "sphere", radius = 0.25 }}
        position = [0.5, 0.5, 0.5]
        "#
    );
    let scene = eddy::scene::parse_str(&text, std::path::Path::new("bench.toml"), &[])
        .expect("the bench scene is valid");
    eddy::pipeline::grid_solver(&scene).expect("the grid builds")
}

/// Mean CPU seconds per repeat since `start`, as a table cell.
fn cpu_per_solve(start: Option<f64>) -> String {
    match (start, cpu_seconds()) {
        (Some(a), Some(b)) => format!("{:.2}", (b - a) / REPEATS as f64),
        _ => "-".into(),
    }
}

fn main() -> Result<(), eddy::grid::SolveError> {
    let settings = SolverSettings {
        tolerance: 1e-6,
        max_iterations: 200,
    };
    // `cargo bench --bench grid_poisson -- 64 128` picks sizes (default 32 64 128).
    let mut sizes: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    if sizes.is_empty() {
        sizes = vec![32, 64, 128];
    }
    println!("threads: {}", rayon::current_num_threads());
    println!("| solve | n^3 | levels | iterations | build (ms) | solve (ms) | ms / iteration | CPU s / solve (all threads) |");
    println!("|---|---|---|---|---|---|---|---|");
    let systems = |n: usize| {
        let voxels = (sphere_box(n), None);
        let [staircase, cut] = ["staircase", "cut"].map(|surface| {
            let g = sphere_scene(n, surface);
            (g.bounds.cell_kinds(), g.bounds.face_fractions([n; 3]))
        });
        [
            ("pressure", voxels),
            ("pressure, staircase", staircase),
            ("pressure, cut cells", cut),
        ]
    };
    for (label, (cells, fractions)) in sizes.iter().flat_map(|&n| systems(n)) {
        let n = cells.dim().0;
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let rhs = Array3::from_shape_fn((n, n, n), |_| rng.random::<f64>() * 2.0 - 1.0);
        let t = Instant::now();
        let mut sys = PoissonSystem::with_fractions(&cells, Boundary::closed(), fractions);
        let build = t.elapsed().as_secs_f64();
        let mut best = f64::INFINITY;
        let mut stats = Default::default();
        let cpu0 = cpu_seconds();
        for _ in 0..REPEATS {
            let mut x = Array3::zeros((n, n, n));
            let t = Instant::now();
            stats = sys.solve(&rhs, &mut x, &settings)?;
            best = best.min(t.elapsed().as_secs_f64());
        }
        println!(
            "| {label} | {n} | {} | {} | {:.1} | {:.1} | {:.2} | {} |",
            stats.levels,
            stats.iterations,
            build * 1e3,
            best * 1e3,
            best * 1e3 / stats.iterations as f64,
            cpu_per_solve(cpu0)
        );
    }
    for &n in &sizes {
        let unknown = sphere_box(n).map(|&c| c == CellKind::Fluid);
        let boundary = DiffusionBoundary {
            periodic: [false; 3],
            sides: [[DiffusionSide::Mirror; 2]; 3],
        };
        let mut rng = ChaCha8Rng::seed_from_u64(8);
        let x0 = Array3::from_shape_fn((n, n, n), |_| rng.random::<f64>());
        let mut best = f64::INFINITY;
        let mut stats = Default::default();
        let cpu0 = cpu_seconds();
        for _ in 0..REPEATS {
            let mut x = x0.clone();
            let t = Instant::now();
            stats = solve_diffusion(&unknown, &boundary, 1e4, &mut x, &settings)?;
            best = best.min(t.elapsed().as_secs_f64());
        }
        println!(
            "| diffusion a=1e4 (with build) | {n} | {} | {} | - | {:.1} | {:.2} | {} |",
            stats.levels,
            stats.iterations,
            best * 1e3,
            best * 1e3 / stats.iterations as f64,
            cpu_per_solve(cpu0)
        );
    }
    Ok(())
}
