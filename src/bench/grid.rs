//! `eddy bench-grid`: the MAC-grid benchmarks of docs/src/benchmarks.md. Step time of the smoke plume
//! (advection, projection, total, pressure iterations) at several resolutions, the set-up of
//! mantaflow's simple plume so the two can be compared; and the Taylor–Green energy error
//! against run time for every advection scheme (registered ones too), with and without
//! advection–reflection, at three resolutions (the run-time-against-error table).

use std::path::Path;
use std::time::Instant;

use crate::scene::{self, Scene};
use crate::Real;

use crate::grid::advect::{schemes, Advection};
use crate::grid::{GridError, GridSolver};
use crate::scene::build::grid_params;

/// What `eddy bench-grid` measures.
#[derive(Debug, Clone)]
pub struct GridBenchOptions {
    /// Smoke plume resolutions (cells per side).
    pub plume: Vec<usize>,
    /// Steps run before timing starts (the plume has to start moving).
    pub warmup: u64,
    /// Timed steps.
    pub steps: u64,
    /// Taylor–Green resolutions (cells per side); none skips the table.
    pub taylor_green: Vec<usize>,
}

/// The grid of a built-in scene (which has a `[grid]` and no obstacles).
fn grid_solver(scene: &Scene) -> Result<GridSolver, GridError> {
    let params = grid_params(scene).expect("the built-in grid scenes have a [grid]");
    let mut grid = GridSolver::new(&params, Vec::new())?;
    if let Some(flow) = scene.grid.as_ref().and_then(|g| g.initial_flow) {
        grid.set_velocity(|x| flow.velocity(x))?;
    }
    Ok(grid)
}

/// The shipped smoke plume at `n`^3 cells.
fn plume_scene(n: usize) -> Scene {
    scene::parse_str(
        include_str!("../../scenes/smoke_plume.toml"),
        Path::new("scenes/smoke_plume.toml"),
        &[format!("grid.resolution=[{n},{n},{n}]")],
    )
    .expect("the shipped plume scene is valid")
}

/// Mean seconds per step of (advection, projection, total) and mean pressure iterations.
pub fn time_plume(n: usize, warmup: u64, steps: u64) -> Result<[f64; 4], GridError> {
    let mut solver = grid_solver(&plume_scene(n))?;
    for _ in 0..warmup {
        solver.step(None)?;
    }
    let mut sums = [0.0; 4];
    for _ in 0..steps {
        let s = solver.step(None)?;
        for (sum, v) in sums.iter_mut().zip([
            s.advect_seconds,
            s.project_seconds,
            s.total_seconds,
            s.pressure_iterations as f64,
        ]) {
            *sum += v;
        }
    }
    Ok(sums.map(|s| s / steps as f64))
}

/// A 2-D Taylor–Green run: u = (sin x cos y, -cos x sin y) on [0, 2 pi]^2, one cell thick,
/// periodic on every axis, Crank–Nicolson viscosity; its kinetic energy decays as
/// exp(-4 nu t).
#[derive(Debug, Clone, Copy)]
pub struct TaylorGreen {
    pub cells: usize,
    pub advection: Advection,
    pub reflection: bool,
    pub nu: Real,
    pub cfl: Real,
    pub end: Real,
}

impl TaylorGreen {
    /// The largest |ln(E / E_exact)| up to `end` (the error of the decay exponent, which a
    /// first-order numerical viscosity makes proportional to dx; the relative error saturates
    /// below 1 and hides the order), and the wall time the run took.
    pub fn energy_error(&self) -> Result<(Real, f64), GridError> {
        let TaylorGreen {
            cells: n,
            advection,
            reflection,
            nu,
            cfl,
            end,
        } = *self;
        let scheme = advection.name();
        let l = 2.0 * std::f64::consts::PI;
        let dz = l / n as Real;
        let text = format!(
            r#"
            name = "taylor_green"
            gravity = [0.0, 0.0, 0.0]
            domain = {{ min = [0.0, 0.0, 0.0], max = [{l}, {l}, {dz}] }}
            time = {{ end = {end}, cfl = {cfl}, dt_max = 1.0 }}
            viscosity = {{ kinematic = {nu} }}
            [grid]
            resolution = [{n}, {n}, 1]
            advection = "{scheme}"
            reflection = {reflection}
            viscosity_scheme = "crank_nicolson"
            initial_flow = "taylor_green"
            pressure_tolerance = 1e-10
            boundary = {{ x_min = "periodic", x_max = "periodic", y_min = "periodic", y_max = "periodic", z_min = "periodic", z_max = "periodic" }}
            "#
        );
        let scene = scene::parse_str(&text, Path::new("taylor_green"), &[])
            .expect("the built-in Taylor-Green scene is valid for valid arguments");
        let started = Instant::now();
        let mut g = grid_solver(&scene)?;
        let e0 = g.kinetic_energy();
        let mut worst: Real = 0.0;
        while g.time() < end - 1e-12 {
            g.step(Some(end))?;
            let exact = e0 * (-4.0 * nu * g.time()).exp();
            worst = worst.max((g.kinetic_energy() / exact).ln().abs());
        }
        Ok((worst, started.elapsed().as_secs_f64()))
    }
}

/// Runs the benchmarks and prints their tables.
pub fn run(args: &GridBenchOptions) -> Result<(), GridError> {
    let threads = rayon::current_num_threads();
    if !args.plume.is_empty() {
        println!(
            "smoke plume (scenes/smoke_plume.toml), {threads} threads, {} warm-up + {} timed steps",
            args.warmup, args.steps
        );
        println!("| cells | advect s | project s | step s | CG iterations |");
        println!("|---|---|---|---|---|");
        for &n in &args.plume {
            let [a, p, t, it] = time_plume(n, args.warmup, args.steps)?;
            println!("| {n}^3 | {a:.3} | {p:.3} | {t:.3} | {it:.1} |");
        }
    }
    if !args.taylor_green.is_empty() {
        println!("\nTaylor-Green energy error |ln(E/E_exact)| at t = 2.5 s (nu = 0.1, CFL 0.5)");
        println!("| advection | reflection | cells | error | run time s |");
        println!("|---|---|---|---|---|");
        for adv in schemes() {
            for reflection in [false, true] {
                for &n in &args.taylor_green {
                    let (e, s) = TaylorGreen {
                        cells: n,
                        advection: adv,
                        reflection,
                        nu: 0.1,
                        cfl: 0.5,
                        end: 2.5,
                    }
                    .energy_error()?;
                    let name = adv.name();
                    println!("| {name} | {reflection} | {n}^2 | {e:.2e} | {s:.2} |");
                }
            }
        }
    }
    Ok(())
}
