//! The refinement part of `eddy bench`: each refinement's cost on the DFSPH dam break against
//! plain DFSPH, and MCVSPH's Monte Carlo error against its run time.
//!
//! "overhead" is the refinement's time over the rest of the same steps (the DFSPH work of
//! that run), which stays meaningful when a shared machine's load drifts between runs;
//! "step ratio" compares with the separate plain-DFSPH run.
//!
//! `--passes` times VRSPH's neighbour passes one by one against their data-movement floor:
//! a pass over the same pairs that loads what the real pass loads (neighbour index, kernel
//! gradient, the fields at j) and only adds it up. No arithmetic, however fast, takes a pass
//! below its floor, so the floors summed over a method's passes bound its overhead from below.

use super::sph::{advance, cube_edge, dam_break_scene, measure_with, BenchOptions};
use crate::pipeline::{sph_solver, RunError};
use crate::refine::biot_savart::{biot_savart, BiotSavartTree, DEFAULT_THETA};
use crate::refine::lanes::F4;
use crate::refine::mcvsph::sample_indices;
use crate::refine::packed::{fill, Field, Packed};
use crate::refine::registry;
use crate::refine::vrsph::{stream_function, stream_strength};
use crate::scene::PressureSolverKind;
use crate::sph::neighbors::NeighborLists;
use crate::sph::operators::{volumes, Operators, WallField};
use crate::sph::SphSolver;
use crate::{Real, Vec3};
use std::time::Instant;

/// Prints the tables `args` asks for (none without `--refinements` or `--mcvsph-error`).
pub fn run(args: &BenchOptions) -> Result<(), RunError> {
    if let Some(bad) = args
        .refinements
        .iter()
        .find(|m| registry::find(m).is_none())
    {
        let names: Vec<&str> = registry::methods().iter().map(|m| m.name).collect();
        return Err(RunError::Unsupported(format!(
            "--refinements: unknown method '{bad}' (allowed: {})",
            names.join(", ")
        )));
    }
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
            let edge = cube_edge(size);
            let dfsph = PressureSolverKind::Dfsph;
            let base = measure_with(edge, dfsph, &[], args.warmup, args.steps)?;
            println!(
                "{:<12} {:>9} {:>10.1} {:>10.1} {:>12.3} {:>13}",
                "dfsph", base.fluid, base.ms_per_step, 0.0, 1.0, "-"
            );
            for m in &args.refinements {
                let set = [format!("refinement.method=\"{m}\"")];
                let r = measure_with(edge, dfsph, &set, args.warmup, args.steps)?;
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
    if args.passes {
        for &size in &args.sizes {
            vrsph_pass_table(cube_edge(size), args.warmup, args.steps)?;
        }
    }
    if args.mcvsph_error {
        let edge = cube_edge(args.sizes.iter().copied().min().unwrap_or(25_000));
        mcvsph_error_table(edge, args.warmup + args.steps)?;
    }
    Ok(())
}

/// MCVSPH's Biot–Savart estimate (Ye Eq. 26) against the full sum over all fluid particles, on
/// the vorticity of the dam break after `steps` steps (strengths c V omega, c = 0.05, core one
/// spacing): relative RMS error over 5 seeds and time per estimate, for 0.1 % to 10 %, by the
/// direct sum and by the treecode at its default opening parameter, with the tree's own error
/// against the direct sum of the same sample (relative RMS).
fn mcvsph_error_table(edge: usize, steps: u64) -> Result<(), RunError> {
    let (sph, step_ms, _) = warmed_dam_break(edge, 0, steps)?;
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

/// The dam break at edge^3 fluid particles after `warmup` steps, its mean DFSPH step over
/// `steps` more, in ms, and its kinematic viscosity.
fn warmed_dam_break(
    edge: usize,
    warmup: u64,
    steps: u64,
) -> Result<(SphSolver, Real, Real), RunError> {
    let scene = dam_break_scene(edge, PressureSolverKind::Dfsph);
    let mut sph = sph_solver(&scene)?;
    advance(&mut sph, warmup)?;
    let t0 = Instant::now();
    advance(&mut sph, steps)?;
    let step_ms = 1e3 * t0.elapsed().as_secs_f64() / steps.max(1) as f64;
    Ok((sph, step_ms, scene.viscosity.kinematic))
}

/// Median wall time of `f` over five runs, in ms.
fn median_ms(mut f: impl FnMut()) -> Real {
    let mut ms: Vec<Real> = (0..5)
        .map(|_| {
            let t0 = Instant::now();
            f();
            1e3 * t0.elapsed().as_secs_f64()
        })
        .collect();
    ms.sort_by(Real::total_cmp);
    ms[2]
}

/// The floor of a neighbour pass, into `out`: per particle, the sum over its fluid
/// neighbours j of the `fields` at j, times the pair's kernel gradient where `grads` is given.
fn floor_pass<const F: usize>(
    lists: &NeighborLists,
    fields: [&[F4]; F],
    grads: Option<&[f32]>,
    out: &mut Vec<F4>,
) {
    fill(out, lists.len(), |i| {
        let range = lists.offsets[i] as usize..lists.offsets[i + 1] as usize;
        let mut sum = F4::ZERO;
        for (k, &j) in range.clone().zip(&lists.indices[range]) {
            let loaded = fields.iter().fold(F4::ZERO, |s, f| s + f[j as usize]);
            sum += match grads {
                Some(g) => loaded * F4::load3(g, 3 * k),
                None => loaded,
            };
        }
        sum
    })
}

/// VRSPH's four neighbour passes (`super::vrsph`, in its order) on the dam break at edge^3
/// particles, each against its floor, with DFSPH's density-rate pass and step for scale.
fn vrsph_pass_table(edge: usize, warmup: u64, steps: u64) -> Result<(), RunError> {
    let (sph, step_ms, nu) = warmed_dam_break(edge, warmup, steps)?;
    let volume = volumes(sph.fluid.mass, &sph.fluid.density);
    // Fluid-only operators, VRSPH's default (`refinement.walls = false`).
    let ops = Operators {
        nb: sph.neighborhood(),
        volume: &volume,
        walls: false,
    };
    let (lists, grads) = (ops.nb.fluid, Some(ops.nb.pairs.fluid.as_flattened()));
    let count = sph.fluid.len();
    let mut positions = Vec::new();
    let packed = Packed::new(ops, &mut positions, &sph.fluid.v);
    let (mut v, mut zeta, mut psi) = (Field::default(), Field::default(), Field::default());
    packed.pack(&sph.fluid.v, &mut v);
    let curl = ops.curl(&sph.fluid.v, WallField::Velocity);
    packed.pack(&curl, &mut zeta);
    let strength: Vec<F4> = (0..count)
        .map(|i| stream_strength(volume[i], &curl[i]))
        .collect();
    stream_function(&packed, &strength, &mut psi);
    let x = packed.positions();
    // Every pass writes into buffers allocated once, as the refinements' own buffers are.
    let (mut out, mut pair, mut vec, mut mat) =
        (Field::default(), Vec::new(), Vec::new(), Vec::new());
    let mut floor = Vec::new();
    let passes: [(&str, Real, Real); 4] = [
        (
            "curl + Laplacian",
            median_ms(|| {
                fill(&mut pair, count, |i| {
                    packed.curl_diffusion_at(i, &v, &zeta, nu)
                })
            }),
            median_ms(|| floor_pass(lists, [v.lanes(), zeta.lanes(), x], grads, &mut floor)),
        ),
        (
            "stream function",
            median_ms(|| stream_function(&packed, &strength, &mut out)),
            median_ms(|| floor_pass(lists, [psi.lanes(), x], None, &mut floor)),
        ),
        (
            "curl of psi",
            median_ms(|| {
                fill(&mut vec, count, |i| {
                    packed.curl_at(i, &psi, WallField::Zero)
                })
            }),
            median_ms(|| floor_pass(lists, [psi.lanes()], grads, &mut floor)),
        ),
        (
            "gradient",
            median_ms(|| {
                fill(&mut mat, count, |i| {
                    packed.gradient_at(i, &v, WallField::Velocity)
                })
            }),
            median_ms(|| floor_pass(lists, [v.lanes()], grads, &mut floor)),
        ),
    ];
    let mut rate = Vec::new();
    let density_rate = median_ms(|| {
        fill(&mut rate, count, |i| {
            ops.nb.density_rate(i, &sph.fluid.v, true)
        })
    });
    println!(
        "\nVRSPH's neighbour passes at {count} fluid particles, {:.1} M pairs (DFSPH step \
         {step_ms:.1} ms; its density-rate pass {density_rate:.1} ms)",
        lists.indices.len() as Real / 1e6
    );
    println!(
        "{:<18} {:>8} {:>9} {:>11} {:>10} {:>12}",
        "pass", "ms", "floor ms", "pass/floor", "% of step", "floor % step"
    );
    let (mut total, mut floor) = (0.0, 0.0);
    let percent = |ms: Real| 100.0 * ms / step_ms;
    for (name, ms, floor_ms) in passes {
        println!(
            "{name:<18} {ms:>8.1} {floor_ms:>9.1} {:>11.2} {:>9.1}% {:>11.1}%",
            ms / floor_ms,
            percent(ms),
            percent(floor_ms)
        );
        (total, floor) = (total + ms, floor + floor_ms);
    }
    println!(
        "{:<18} {total:>8.1} {floor:>9.1} {:>11.2} {:>9.1}% {:>11.1}%",
        "all four",
        total / floor,
        percent(total),
        percent(floor)
    );
    Ok(())
}
