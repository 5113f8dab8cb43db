//! `eddy bench`: step time of the SPH solvers on the SPlisHSPlasH 3D dam-break set-up, so the
//! comparison in docs/src/benchmarks.md can be rerun. A cube of water (1 m, n^3 particles) sits in the corner
//! of a closed 4 x 3 x 1.5 m tank; fixed dt 1.92 ms, cubic kernel, density tolerance 0.05 %,
//! divergence tolerance 0.1 %, at least 2 density and 1 divergence iterations (the peer's rule),
//! viscosity 0.01. The scene file `scenes/bench_dam_break.toml` is the same set-up at the 97k
//! size.

use crate::metrics::density_errors;
use crate::pipeline::{sph_solver, RunError};
use crate::scene::{self, PressureSolverKind, Scene};
use crate::sph::neighbors::{cell_order_and_codes, CellGrid, NeighborLists};
use crate::sph::{Instability, SphSolver};
use crate::Real;
use std::path::Path;
use std::time::Instant;

/// What `eddy bench` measures.
#[derive(Debug, Clone)]
pub struct BenchOptions {
    /// Approximate fluid particle counts (each rounded to a cube n^3).
    pub sizes: Vec<usize>,
    /// Pressure solvers to time.
    pub solvers: Vec<String>,
    /// Steps run before timing starts.
    pub warmup: u64,
    /// Timed steps.
    pub steps: u64,
    /// Also time these refinement methods (names of `crate::refine::registry`) on DFSPH
    /// against plain DFSPH, at their paper defaults; see `super::refine`.
    pub refinements: Vec<String>,
    /// Also print MCVSPH's Biot–Savart error against run time for 0.1 % to 10 % vortex
    /// particles at the smallest size.
    pub mcvsph_error: bool,
    /// Also time VRSPH's four neighbour passes at each size against the floor of passes that
    /// load the same data and do no arithmetic.
    pub passes: bool,
    /// Also print each phase of the DFSPH step against its data-movement floor
    /// (see [`super::floors`]).
    pub floors: bool,
    /// Also time every size and solver on thread pools of these sizes (strong scaling); empty
    /// for none.
    pub threads: Vec<usize>,
}

/// One measured configuration.
#[derive(Debug, Clone)]
pub struct BenchResult {
    pub solver: PressureSolverKind,
    pub fluid: usize,
    pub boundary: usize,
    pub ms_per_step: f64,
    pub neighbor_ms: f64,
    /// Milliseconds per step in the neighbourhood update (sort, search, pair cache, densities).
    pub update_ms: f64,
    /// Milliseconds per step in the divergence solve.
    pub divergence_ms: f64,
    /// Milliseconds per step in the pressure solve.
    pub pressure_ms: f64,
    pub pressure_iterations: f64,
    pub divergence_iterations: f64,
    pub bytes_per_particle: f64,
    /// The average compression measured at the new positions after each timed step (a
    /// fraction of the rest density): the accuracy the time buys.
    pub compression: f64,
    /// Milliseconds per step in the turbulence refinement.
    pub refinement_ms: f64,
}

/// The cube edge, in particles, of the benchmark scene nearest to `size` fluid particles
/// (at least 4).
pub fn cube_edge(size: usize) -> usize {
    (size as f64).cbrt().round().max(4.0) as usize
}

/// The benchmark scene with a cube of `edge`^3 fluid particles (`edge` particles along each
/// side, not a particle count); at edge = 46 it is the reference set-up exactly (radius
/// 0.0106 m), other sizes scale the spacing so the cube stays ~1 m.
pub fn dam_break_scene(edge: usize, solver: PressureSolverKind) -> Scene {
    dam_break_scene_with(edge, solver, &[])
}

/// [`dam_break_scene`] with further `--set` style overrides.
pub fn dam_break_scene_with(edge: usize, solver: PressureSolverKind, extra: &[String]) -> Scene {
    let text = include_str!("../../scenes/bench_dam_break.toml");
    let spacing = 0.0212 * 46.0 / edge as Real;
    // The block starts 5 cm off the walls, as in the scene file.
    let far = 0.05 + edge as Real * spacing * (1.0 + 1e-9);
    let solver = match solver {
        PressureSolverKind::Dfsph => "dfsph",
        PressureSolverKind::Iisph => "iisph",
    };
    let mut overrides = vec![
        format!("fluid.spacing={spacing}"),
        format!("fluid.blocks.0.max=[{far}, {far}, {far}]"),
        format!("pressure.solver=\"{solver}\""),
    ];
    overrides.extend_from_slice(extra);
    scene::parse_str(text, Path::new("scenes/bench_dam_break.toml"), &overrides)
        .expect("the built-in benchmark scene is valid")
}

/// A benchmark run's instability (no frames are written).
pub fn unstable(cause: Instability) -> RunError {
    RunError::Unstable {
        cause,
        frames: 0,
        out: "(benchmark)".into(),
    }
}

/// Runs `steps` steps of `sph`, each with its neighbourhood update.
pub fn advance(sph: &mut SphSolver, steps: u64) -> Result<(), RunError> {
    for _ in 0..steps {
        sph.step(None).map_err(unstable)?;
    }
    Ok(())
}

/// Times `steps` steps after `warmup` steps of one configuration ([`dam_break_scene`] with
/// `edge` particles along the cube's side).
pub fn measure(
    edge: usize,
    solver: PressureSolverKind,
    warmup: u64,
    steps: u64,
) -> Result<BenchResult, RunError> {
    measure_with(edge, solver, &[], warmup, steps)
}

/// [`measure`] on the scene with further overrides (`extra`).
pub fn measure_with(
    edge: usize,
    solver: PressureSolverKind,
    extra: &[String],
    warmup: u64,
    steps: u64,
) -> Result<BenchResult, RunError> {
    let scene = dam_break_scene_with(edge, solver, extra);
    let mut sph = sph_solver(&scene)?;
    advance(&mut sph, warmup)?;
    measure_solver(&mut sph, solver, steps)
}

/// Times `steps` more steps of `sph`, which runs `solver`.
fn measure_solver(
    sph: &mut SphSolver,
    solver: PressureSolverKind,
    steps: u64,
) -> Result<BenchResult, RunError> {
    let (mut total, mut search, mut iterations, mut refine) = (0.0, 0.0, 0.0, 0.0);
    let (mut divergence_iterations, mut compression) = (0.0, 0.0);
    let (mut update, mut divergence, mut pressure) = (0.0, 0.0, 0.0);
    for _ in 0..steps {
        let t0 = Instant::now();
        let dt = sph.stable_dt().map_err(unstable)?;
        let stats = sph.advance(dt).map_err(unstable)?;
        let t1 = Instant::now();
        sph.update_neighborhoods();
        total += t0.elapsed().as_secs_f64();
        update += t1.elapsed().as_secs_f64();
        compression += density_errors(&sph.fluid.density, sph.fluid.rest_density).0;
        iterations += stats.pressure.iterations as f64;
        divergence_iterations += stats.divergence.iterations as f64;
        refine += stats.refinement_seconds;
        divergence += stats.divergence_seconds;
        pressure += stats.pressure_seconds;
        search += time_neighbor_search(sph);
    }
    let ms = |seconds: f64| 1e3 * seconds / steps as f64;
    Ok(BenchResult {
        solver,
        fluid: sph.fluid.len(),
        boundary: sph.boundary.len(),
        ms_per_step: ms(total),
        neighbor_ms: ms(search),
        update_ms: ms(update),
        divergence_ms: ms(divergence),
        pressure_ms: ms(pressure),
        pressure_iterations: iterations / steps as f64,
        divergence_iterations: divergence_iterations / steps as f64,
        bytes_per_particle: sph.memory_bytes() as f64 / sph.fluid.len() as f64,
        compression: compression / steps as f64,
        refinement_ms: ms(refine),
    })
}

/// Seconds the neighbour search alone takes on the solver's current state (sort, grid, lists).
fn time_neighbor_search(sph: &SphSolver) -> f64 {
    let h = sph.kernel.support();
    let mut x = sph.fluid.x.clone();
    let t0 = Instant::now();
    let (perm, codes) = cell_order_and_codes(&x, h);
    crate::sph::neighbors::permute(&mut x, &perm);
    let grid = CellGrid::from_codes(&x, &codes, h);
    let ff = NeighborLists::build(&x, &grid, &x, &grid, h, true);
    let fb = NeighborLists::build(&x, &grid, &sph.boundary.x, &sph.boundary.grid, h, false);
    let seconds = t0.elapsed().as_secs_f64();
    std::hint::black_box((ff, fb));
    seconds
}

/// Strong scaling: each size and solver on a pool of each thread count of `args.threads`, the
/// same steps from the same start. The step's sums run in a fixed order (`crate::parallel`,
/// the solvers' per-particle passes), so every pool must end in the same state to the bit;
/// the table says whether it did.
fn scaling(args: &BenchOptions) -> Result<(), RunError> {
    println!(
        "\nStrong scaling, {} warm-up + {} timed steps (efficiency: the first row's time x its \
         threads over this row's)",
        args.warmup, args.steps
    );
    println!(
        "{:<6} {:>9} {:>8} {:>10} {:>9} {:>11} {:>11}",
        "solver", "fluid", "threads", "ms/step", "speed-up", "efficiency", "same state"
    );
    for &size in &args.sizes {
        for name in &args.solvers {
            let solver = solver_kind(name)?;
            let mut first: Option<(usize, f64, Vec<u64>)> = None;
            for &threads in &args.threads {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .map_err(|e| RunError::Unsupported(format!("--threads {threads}: {e}")))?;
                let (r, state) = pool.install(|| -> Result<_, RunError> {
                    let mut sph = sph_solver(&dam_break_scene(cube_edge(size), solver))?;
                    advance(&mut sph, args.warmup)?;
                    let r = measure_solver(&mut sph, solver, args.steps)?;
                    let state: Vec<u64> = sph
                        .fluid
                        .x
                        .iter()
                        .flat_map(|x| x.iter().map(|c| c.to_bits()))
                        .collect();
                    Ok((r, state))
                })?;
                let (t0, ms0, state0) =
                    first.get_or_insert_with(|| (threads, r.ms_per_step, state.clone()));
                println!(
                    "{:<6} {:>9} {:>8} {:>10.1} {:>9.2} {:>10.0}% {:>11}",
                    name,
                    r.fluid,
                    threads,
                    r.ms_per_step,
                    *ms0 / r.ms_per_step,
                    100.0 * (*t0 as f64 * *ms0) / (threads as f64 * r.ms_per_step),
                    if *state0 == state { "yes" } else { "NO" }
                );
            }
        }
    }
    Ok(())
}

/// The pressure solver named `name` on the command line.
fn solver_kind(name: &str) -> Result<PressureSolverKind, RunError> {
    match name {
        "dfsph" => Ok(PressureSolverKind::Dfsph),
        "iisph" => Ok(PressureSolverKind::Iisph),
        other => Err(RunError::Unsupported(format!(
            "--solvers: unknown solver '{other}' (allowed: dfsph, iisph)"
        ))),
    }
}

/// Peak resident memory of this process, bytes (Linux; None elsewhere).
pub fn peak_rss() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Runs `eddy bench` and prints a table.
pub fn run(args: &BenchOptions) -> Result<(), RunError> {
    println!(
        "SPH dam break (SPlisHSPlasH set-up), {} threads, {} warm-up + {} timed steps, dt 1.92 ms",
        rayon::current_num_threads(),
        args.warmup,
        args.steps
    );
    println!(
        "{:<6} {:>9} {:>9} {:>10} {:>11} {:>10} {:>8} {:>10} {:>8} {:>12} {:>10} {:>8}",
        "solver",
        "fluid",
        "boundary",
        "ms/step",
        "search ms",
        "update ms",
        "div ms",
        "press ms",
        "p-iters",
        "M p-steps/s",
        "B/particle",
        "comp %"
    );
    for &size in &args.sizes {
        let edge = cube_edge(size);
        for name in &args.solvers {
            let solver = solver_kind(name)?;
            let mut sph = sph_solver(&dam_break_scene(edge, solver))?;
            advance(&mut sph, args.warmup)?;
            let r = measure_solver(&mut sph, solver, args.steps)?;
            println!(
                "{:<6} {:>9} {:>9} {:>10.1} {:>11.1} {:>10.1} {:>8.1} {:>10.1} {:>8.1} {:>12.3} {:>10.0} {:>8.4}",
                name,
                r.fluid,
                r.boundary,
                r.ms_per_step,
                r.neighbor_ms,
                r.update_ms,
                r.divergence_ms,
                r.pressure_ms,
                r.pressure_iterations,
                r.fluid as f64 / r.ms_per_step / 1e3,
                r.bytes_per_particle,
                100.0 * r.compression
            );
            if args.floors && solver == PressureSolverKind::Dfsph {
                super::floors::print(&sph, &r, super::floors::read_bandwidth());
            }
        }
    }
    if !args.threads.is_empty() {
        scaling(args)?;
    }
    super::refine::run(args)?;
    if let Some(rss) = peak_rss() {
        let note = if args.floors {
            format!(
                " (with the {} MiB buffer of the bandwidth measurement)",
                super::floors::BANDWIDTH_BUFFER >> 20
            )
        } else {
            String::new()
        };
        println!(
            "peak resident memory: {:.1} MiB{note}",
            rss as f64 / 1048576.0
        );
    }
    Ok(())
}
