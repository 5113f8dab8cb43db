//! `eddy-precompute`: precompute an obstacle's artificial-boundary-layer database, merge shards,
//! or run the benchmarks.

use std::io::IsTerminal;
use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};
#[cfg(feature = "mpi")]
use eddy_precompute::precompute_with;
use eddy_precompute::{bench, merge, precompute, ObstacleSpec, RunOptions, Summary};

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
    #[arg(long, value_name = "k/N", value_parser = eddy::io::parse_shard)]
    shard: Option<(usize, usize)>,
    /// Keep the directions already finished in the output (or by an interrupted run).
    #[arg(long)]
    resume: bool,
    /// Directions computed at once, one thread each, at least 1 (default: the number of cores).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..), conflicts_with = "mpi")]
    jobs: Option<u64>,
    /// Hand the directions out to MPI ranks, one at a time each (start with `mpirun -n R`, one
    /// rank per core); rank 0 writes the output. Needs a build with `--features mpi`.
    #[arg(long)]
    mpi: bool,
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

/// One obstacle's run: on threads here, or as one rank of an MPI job.
fn run_obstacle(args: RunArgs) -> anyhow::Result<()> {
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
    let s = if args.mpi {
        match over_mpi(&spec, &options)? {
            Some(s) => s,
            None => return Ok(()),
        }
    } else {
        precompute(&spec, &options)?
    };
    eprintln!(
        "eddy-precompute: {} -> {}: {} directions computed ({:.2} s each on one thread), {} \
         reused, {} boundary points, grid {} cells of {:.4} m",
        spec.name,
        options.out.display(),
        s.computed,
        s.seconds_per_direction,
        s.reused,
        s.points,
        spec.grid_box()?.describe(),
        spec.spacing()?
    );
    Ok(())
}

/// The run as one rank of an MPI job: rank 0's summary, None on the other ranks. An error on
/// any rank ends the whole job (`MPI_Abort`), so no rank waits for one that has stopped.
#[cfg(feature = "mpi")]
fn over_mpi(spec: &ObstacleSpec, options: &RunOptions) -> anyhow::Result<Option<Summary>> {
    use mpi::topology::Communicator;
    let (universe, _) = mpi::initialize_with_threading(mpi::Threading::Funneled)
        .ok_or_else(|| anyhow::anyhow!("MPI was initialised already"))?;
    let world = universe.world();
    let result = if world.rank() == 0 {
        let mut root = eddy_precompute::ranks::Root { world: &world };
        precompute_with(spec, options, &mut root).map(Some)
    } else {
        eddy_precompute::ranks::serve(spec, &world).map(|()| None)
    };
    if let Err(e) = &result {
        eprintln!("eddy-precompute (rank {}): error: {e:#}", world.rank());
        world.abort(1);
    }
    result
}

#[cfg(not(feature = "mpi"))]
fn over_mpi(_: &ObstacleSpec, _: &RunOptions) -> anyhow::Result<Option<Summary>> {
    anyhow::bail!(
        "--mpi needs eddy-precompute built with MPI: cargo build --release -p eddy-precompute \
         --features mpi (an MPI library and libclang must be installed; ./dev test-mpi does it)"
    )
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
        (None, Some(args)) => run_obstacle(args)?,
        (None, None) => {
            anyhow::bail!("give an obstacle file and --out, or a subcommand (see --help)")
        }
    }
    Ok(())
}
