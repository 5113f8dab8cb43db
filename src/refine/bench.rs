//! The refinement part of `eddy bench`: each refinement's cost on the DFSPH dam break against
//! plain DFSPH, and MCVSPH's Monte Carlo error against its run time.
//!
//! "overhead" is the refinement's time over the rest of the same steps (the DFSPH work of
//! that run), which stays meaningful when a shared machine's load drifts between runs;
//! "step ratio" compares with the separate plain-DFSPH run.

use super::biot_savart::{biot_savart, BiotSavartTree, DEFAULT_THETA};
use super::mcvsph::sample_indices;
use crate::bench::{dam_break_scene, measure_with, BenchArgs};
use crate::run::{bodies, RunError};
use crate::scene::PressureSolverKind;
use crate::sph::SphSolver;
use crate::{Real, Vec3};
use std::time::Instant;

/// Methods the table accepts.
const METHODS: [&str; 5] = ["rankine", "vrsph", "mcvsph", "micropolar", "confinement"];

/// Prints the tables `args` asks for (none without `--refinements` or `--mcvsph-error`).
pub fn run(args: &BenchArgs) -> Result<(), RunError> {
    if let Some(bad) = args
        .refinements
        .iter()
        .find(|m| !METHODS.contains(&m.as_str()))
    {
        return Err(RunError::Unsupported(format!(
            "--refinements: unknown method '{bad}' (allowed: {})",
            METHODS.join(", ")
        )));
    }
    let cube = |size: usize| (size as f64).cbrt().round().max(4.0) as usize;
    if !args.refinements.is_empty() {
        println!(
            "\nRefinements on DFSPH at their paper defaults, same set-up, {} warm-up + {} timed \
             steps",
            args.warmup, args.steps
        );
        println!(
            "{:<12} {:>9} {:>10} {:>10} {:>12} {:>13}",
            "method", "fluid", "ms/step", "refine ms", "step ratio", "overhead"
        );
        for &size in &args.sizes {
            let n = cube(size);
            let dfsph = PressureSolverKind::Dfsph;
            let base = measure_with(n, dfsph, &[], args.warmup, args.steps)?;
            println!(
                "{:<12} {:>9} {:>10.1} {:>10.1} {:>12.3} {:>13}",
                "dfsph", base.fluid, base.ms_per_step, 0.0, 1.0, "-"
            );
            for m in &args.refinements {
                let set = [format!("refinement.method=\"{m}\"")];
                let r = measure_with(n, dfsph, &set, args.warmup, args.steps)?;
                println!(
                    "{:<12} {:>9} {:>10.1} {:>10.1} {:>12.3} {:>12.1}%",
                    m,
                    r.fluid,
                    r.ms_per_step,
                    r.refinement_ms,
                    r.ms_per_step / base.ms_per_step,
                    100.0 * r.refinement_ms / (r.ms_per_step - r.refinement_ms)
                );
            }
        }
    }
    if args.mcvsph_error {
        let n = cube(args.sizes.iter().copied().min().unwrap_or(25_000));
        mcvsph_error_table(n, args.warmup + args.steps)?;
    }
    Ok(())
}

/// MCVSPH's Biot–Savart estimate (Ye Eq. 26) against the full sum over all fluid particles, on
/// the vorticity of the dam break after `steps` steps (strengths c V omega, c = 0.05, core one
/// spacing): relative RMS error over 5 seeds and time per estimate, for 0.1 % to 10 %, by the
/// direct sum and by the treecode at its default opening parameter, with the tree's own error
/// against the direct sum of the same sample (relative RMS).
fn mcvsph_error_table(n: usize, steps: u64) -> Result<(), RunError> {
    let scene = dam_break_scene(n, PressureSolverKind::Dfsph);
    let mut sph = SphSolver::new(&scene, bodies(&scene)?);
    let unstable = |cause| RunError::Unstable {
        cause,
        frames: 0,
        out: "(benchmark)".into(),
    };
    let t0 = Instant::now();
    for _ in 0..steps {
        sph.advance().map_err(unstable)?;
        sph.update_neighborhoods();
    }
    let step_ms = 1e3 * t0.elapsed().as_secs_f64() / steps as f64;
    let omega = sph.vorticity();
    let x = &sph.fluid.x;
    let beta: Vec<Vec3> = omega
        .iter()
        .zip(&sph.fluid.density)
        .map(|(w, rho)| 0.05 * sph.fluid.mass / rho * w)
        .collect();
    let t0 = Instant::now();
    let full = biot_savart(x, x, &beta, sph.spacing);
    let full_ms = 1e3 * t0.elapsed().as_secs_f64();
    let norm: Real = full.iter().map(|u| u.norm_squared()).sum();
    println!(
        "\nMCVSPH Monte Carlo Biot-Savart vs the full sum ({} fluid particles after {steps} \
         steps; full sum {full_ms:.0} ms, DFSPH step {step_ms:.1} ms)",
        x.len()
    );
    println!(
        "{:>9} {:>7} {:>10} {:>10} {:>13} {:>14} {:>12}",
        "fraction", "N", "direct ms", "tree ms", "tree / DFSPH", "rel. RMS error", "tree error"
    );
    for fraction in [0.001, 0.003, 0.01, 0.03, 0.1] {
        let count = ((fraction * x.len() as Real).round() as usize).max(1);
        let seeds = 5;
        let (mut sq, mut tree_sq, mut direct_sq) = (0.0, 0.0, 0.0);
        let (mut direct_ms, mut tree_ms) = (0.0, 0.0);
        for seed in 0..seeds {
            let idx = sample_indices(x.len(), count, seed);
            let src: Vec<Vec3> = idx.iter().map(|&k| x[k]).collect();
            let b: Vec<Vec3> = idx.iter().map(|&k| beta[k]).collect();
            // The estimate's strengths, (N_f / N) beta, as `monte_carlo_biot_savart` scales them.
            let scale = x.len() as Real / count as Real;
            let b: Vec<Vec3> = b.iter().map(|b| scale * b).collect();
            let t0 = Instant::now();
            let direct = biot_savart(x, &src, &b, sph.spacing);
            direct_ms += 1e3 * t0.elapsed().as_secs_f64();
            let t0 = Instant::now();
            let tree = BiotSavartTree::new(&src, &b, sph.spacing).evaluate(x, DEFAULT_THETA);
            tree_ms += 1e3 * t0.elapsed().as_secs_f64();
            for ((t, d), f) in tree.iter().zip(&direct).zip(&full) {
                sq += (t - f).norm_squared();
                tree_sq += (t - d).norm_squared();
                direct_sq += d.norm_squared();
            }
        }
        let per = |ms: Real| ms / seeds as Real;
        println!(
            "{:>8.1}% {:>7} {:>10.2} {:>10.2} {:>13.3} {:>14.3} {:>11.2e}",
            100.0 * fraction,
            count,
            per(direct_ms),
            per(tree_ms),
            per(tree_ms) / step_ms,
            (sq / seeds as Real / norm).sqrt(),
            (tree_sq / direct_sq).sqrt()
        );
    }
    Ok(())
}
