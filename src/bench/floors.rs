//! `eddy bench --floors`: each phase of a DFSPH step against its data-movement floor, the
//! time the bytes the phase must move at least once take at this machine's read bandwidth.
//!
//! A phase near its floor can only get faster by moving fewer bytes (fewer passes, smaller
//! pair data); a phase far above it is bound by arithmetic or latency, and that is where
//! speed can still be won. The bandwidth is measured here, in the same process, as the best
//! of five parallel streaming sums over [`BANDWIDTH_BUFFER`] bytes (four times the last-level
//! cache of the machines eddy is benchmarked on).

use super::sph::BenchResult;
use crate::sph::SphSolver;
use rayon::prelude::*;
use std::time::Instant;

/// Bytes a fluid-pair entry occupies in every pass over the lists: a `u32` neighbour index and
/// the cached f32 kernel gradient (`crate::sph::pair_cache`).
const PAIR_BYTES: f64 = 16.0;

/// Bytes streamed by [`read_bandwidth`].
pub const BANDWIDTH_BUFFER: usize = 128 << 20;

/// The machine's read bandwidth, bytes per second, with all of rayon's threads.
pub fn read_bandwidth() -> f64 {
    let data = vec![1.0f64; BANDWIDTH_BUFFER / std::mem::size_of::<f64>()];
    (0..5)
        .map(|_| {
            let start = Instant::now();
            let sum: f64 = data.par_chunks(1 << 16).map(stream_sum).sum();
            std::hint::black_box(sum);
            BANDWIDTH_BUFFER as f64 / start.elapsed().as_secs_f64()
        })
        .fold(0.0, f64::max)
}

/// The sum of `values` in eight independent running sums, so the loads and not the adder's
/// latency bound the loop.
fn stream_sum(values: &[f64]) -> f64 {
    let mut sums = [0.0; 8];
    for chunk in values.chunks_exact(8) {
        for (s, v) in sums.iter_mut().zip(chunk) {
            *s += v;
        }
    }
    sums.iter().sum::<f64>() + values.chunks_exact(8).remainder().iter().sum::<f64>()
}

/// One phase: its measured time and the bytes it must move per step.
struct Phase {
    name: &'static str,
    ms: f64,
    bytes: f64,
    what: &'static str,
}

/// Prints the phases of the DFSPH step `r` (measured on `sph`) against their floors at
/// `bandwidth` bytes per second.
pub fn print(sph: &SphSolver, r: &BenchResult, bandwidth: f64) {
    let nb = sph.neighborhood();
    let n = sph.fluid.len() as f64;
    let boundary = sph.boundary.len() as f64;
    let fluid_pairs = nb.fluid.indices.len() as f64;
    let wall_pairs = nb.boundary_lists.indices.len() as f64;
    let pairs = fluid_pairs + wall_pairs;
    // A density-rate pass reads the pair data, v (24 B), the wall sums (32 B) and the density
    // ratio (8 B), and writes the error (8 B); a pressure pass reads the pair data, kappa
    // (8 B) and the wall gradient (24 B), and reads and writes v (48 B).
    let rate_pass = PAIR_BYTES * fluid_pairs + 72.0 * n;
    let pressure_pass = PAIR_BYTES * fluid_pairs + 80.0 * n;
    // A solve of k iterations after its warm start: k + 2 rate passes, k + 1 pressure passes.
    let solve = |k: f64| (k + 2.0) * rate_pass + (k + 1.0) * pressure_pass;
    let phases = [
        Phase {
            name: "search",
            ms: r.neighbor_ms,
            // Positions in (24 B each), lists out (4 B a pair, 4 B an offset).
            bytes: 24.0 * (n + boundary) + 4.0 * (pairs + 2.0 * n),
            what: "read positions, write lists",
        },
        Phase {
            name: "pair cache",
            ms: r.update_ms - r.neighbor_ms,
            // Lists and positions in; gradients (12 B a pair) and five per-particle sums out.
            bytes: 4.0 * pairs + 24.0 * (n + boundary) + 12.0 * pairs + 56.0 * n,
            what: "read lists, write gradients and densities",
        },
        Phase {
            name: "divergence",
            ms: r.divergence_ms,
            bytes: solve(r.divergence_iterations),
            what: "k + 2 rate and k + 1 pressure passes",
        },
        Phase {
            name: "pressure",
            ms: r.pressure_ms,
            bytes: solve(r.pressure_iterations),
            what: "k + 2 rate and k + 1 pressure passes",
        },
        Phase {
            name: "rest",
            ms: r.ms_per_step - r.update_ms - r.divergence_ms - r.pressure_ms,
            // Viscosity: one pass over the fluid and wall pairs (gradients and positions),
            // reading x and v and writing the acceleration; then the velocity and position
            // updates read and write v and x.
            bytes: PAIR_BYTES * pairs + 72.0 * n + 96.0 * n,
            what: "viscosity pass, velocity and position updates",
        },
    ];
    println!(
        "\nDFSPH phases at {} fluid particles against their data-movement floors \
         ({:.1} M fluid pairs, {:.1} M wall pairs, read bandwidth {:.1} GB/s, \
         {:.1} divergence and {:.1} pressure iterations)",
        sph.fluid.len(),
        fluid_pairs / 1e6,
        wall_pairs / 1e6,
        bandwidth / 1e9,
        r.divergence_iterations,
        r.pressure_iterations
    );
    println!(
        "{:<12} {:>8} {:>9} {:>10} {:>11}  bytes counted",
        "phase", "ms", "MB", "floor ms", "ms / floor"
    );
    let mut total = (0.0, 0.0);
    for p in &phases {
        let floor = 1e3 * p.bytes / bandwidth;
        total = (total.0 + p.ms, total.1 + floor);
        println!(
            "{:<12} {:>8.1} {:>9.1} {:>10.2} {:>11.1}  {}",
            p.name,
            p.ms,
            p.bytes / 1e6,
            floor,
            p.ms / floor,
            p.what
        );
    }
    println!(
        "{:<12} {:>8.1} {:>9} {:>10.2} {:>11.1}",
        "step",
        total.0,
        "",
        total.1,
        total.0 / total.1
    );
}

#[cfg(test)]
mod tests {
    use super::stream_sum;

    #[test]
    fn stream_sum_counts_every_value_once() {
        // Lengths below, at and past whole chunks of eight, so the remainder is exercised.
        for n in 0..40 {
            let values: Vec<f64> = (1..=n).map(f64::from).collect();
            let want = f64::from(n * (n + 1) / 2);
            assert_eq!(stream_sum(&values), want, "sum of 1..={n}");
        }
    }
}
