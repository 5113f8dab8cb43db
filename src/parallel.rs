//! Parallel sums in a fixed order.
//!
//! Rayon's `sum`, `fold` and `reduce` combine partial results in a tree whose shape follows
//! work stealing, so a floating-point sum can change in its last bits from one run to the next.
//! A chaotic flow, or a solver's stopping test, turns that into different output: two runs of
//! the smoke plume differed from the fourth frame on. Here fixed blocks are summed in parallel
//! and the block sums added in order, so a sum depends on the data alone, not on scheduling or
//! the thread count.

use rayon::prelude::*;
use std::iter::Sum;

/// Terms per block of [`sum_by`].
pub const BLOCK: usize = 1 << 12;

/// The items of `parts` (each typically a block's partial sum) added in index order.
pub fn ordered_sum<S: Send + Sum, P: IndexedParallelIterator<Item = S>>(parts: P) -> S {
    parts.collect::<Vec<S>>().into_iter().sum()
}

/// sum_i f(x_i), in blocks of [`BLOCK`] terms summed in parallel and then in order.
pub fn sum_by<T: Sync, S: Send + Sum>(x: &[T], f: impl Fn(&T) -> S + Sync) -> S {
    ordered_sum(
        x.par_chunks(BLOCK)
            .map(|block| block.iter().map(&f).sum::<S>()),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The same sum on 1, 2 and 3 threads, bit for bit, on terms whose order matters (a
    /// spread of magnitudes and signs), and equal to the blocks summed one after another.
    #[test]
    fn sums_do_not_depend_on_the_thread_count() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let x: Vec<f64> = (0..200_000)
            .map(|_| rng.random_range(-1.0..1.0) * 10f64.powi(rng.random_range(-8..8)))
            .collect();
        let sequential: f64 = x
            .chunks(BLOCK)
            .map(|b| b.iter().map(|v| v * v - v).sum::<f64>())
            .sum();
        for threads in [1, 2, 3] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("a thread pool");
            let parallel = pool.install(|| sum_by(&x, |v| v * v - v));
            assert_eq!(
                parallel.to_bits(),
                sequential.to_bits(),
                "{threads} threads"
            );
        }
    }
}
