//! `eddy-precompute`: precompute an obstacle's artificial-boundary-layer database, merge shards,
//! or run the benchmarks.

use std::io::IsTerminal;
use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};
use eddy_precompute::{bench, merge, precompute, run, ObstacleSpec, RunOptions};

#[derive(Parser)]
#[command(
    name = "eddy-precompute",
    version,
    about = "Precompute an obstacle's artificial boundary layer database (Pfaff et al. 2009)",
    args_conflicts_with_subcommands = true
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    #[command(flatten)]
    run: Option<RunArgs>,
}

#[derive(Args)]
struct RunArgs {
    /// The obstacle file (TOML), e.g. precompute/obstacles/sphere.toml.
    obstacle: PathBuf,
    /// The database to write (HDF5).
    #[arg(long)]
    out: PathBuf,
    /// Override an obstacle key, e.g. --set grid.resolution=64 (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// Compute every N-th direction starting at k, into a shard for `merge`.
    #[arg(long, value_name = "k/N", value_parser = run::parse_shard)]
    shard: Option<(usize, usize)>,
    /// Keep the directions already finished in the output (or by an interrupted run).
    #[arg(long)]
    resume: bool,
    /// Directions computed at once, one thread each, at least 1 (default: the number of cores).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    jobs: Option<u64>,
}

#[derive(Subcommand)]
enum Command {
    /// Combine shard files into one database (refuses overlaps and gaps).
    Merge {
        /// The shard files.
        #[arg(required = true)]
        shards: Vec<PathBuf>,
        /// The merged database.
        #[arg(long)]
        out: PathBuf,
    },
    /// Time per direction against grid size, interpolation error against azimuth samples,
    /// lookup throughput.
    Bench(bench::BenchArgs),
}

fn main() -> anyhow::Result<()> {
    let cli = Cli::parse();
    match (cli.command, cli.run) {
        (Some(Command::Merge { shards, out }), _) => {
            merge(&shards, &out)?;
            eprintln!(
                "eddy-precompute: merged {} shards -> {}",
                shards.len(),
                out.display()
            );
        }
        (Some(Command::Bench(args)), _) => bench::run(&args)?,
        (None, Some(args)) => {
            let spec = ObstacleSpec::load(&args.obstacle, &args.set)?;
            let workers = args
                .jobs
                .map(|n| n as usize)
                .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
            let options = RunOptions {
                out: args.out,
                shard: args.shard,
                resume: args.resume,
                workers,
                progress: std::io::stderr().is_terminal(),
            };
            let s = precompute(&spec, &options)?;
            eprintln!(
                "eddy-precompute: {} -> {}: {} directions computed ({:.2} s each on one thread), \
                 {} reused, {} boundary points, grid {}^3 of {:.4} m",
                spec.name,
                options.out.display(),
                s.computed,
                s.seconds_per_direction,
                s.reused,
                s.points,
                spec.grid.resolution,
                spec.spacing()?
            );
        }
        (None, None) => {
            anyhow::bail!("give an obstacle file and --out, or a subcommand (see --help)")
        }
    }
    Ok(())
}
