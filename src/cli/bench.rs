//! The command-line options of `eddy bench` and `eddy bench-grid`, turned into the library's
//! benchmark options.

use std::path::PathBuf;

use eddy::bench::abl::AblBenchOptions;
use eddy::bench::coupling::CouplingBenchOptions;
use eddy::bench::grid::GridBenchOptions;
use eddy::bench::BenchOptions;

/// The refinement methods of the registry, as `--refinements` accepts and its help lists them.
fn refinement_names() -> clap::builder::PossibleValuesParser {
    let methods = eddy::refine::registry::methods();
    clap::builder::PossibleValuesParser::new(
        methods
            .into_iter()
            .map(|m| clap::builder::PossibleValue::new(m.name).help(m.summary)),
    )
}

/// Options of `eddy bench`.
#[derive(Debug, Clone, clap::Args)]
pub struct BenchArgs {
    /// Approximate fluid particle counts (each rounded to a cube n^3).
    #[arg(long, value_delimiter = ',', default_value = "25000,100000,400000")]
    pub sizes: Vec<usize>,
    /// Pressure solvers to time.
    #[arg(long, value_delimiter = ',', default_value = "dfsph,iisph")]
    pub solvers: Vec<String>,
    /// Steps run before timing starts.
    #[arg(long, default_value_t = 10)]
    pub warmup: u64,
    /// Timed steps.
    #[arg(long, default_value_t = 30)]
    pub steps: u64,
    /// Also time these refinements on DFSPH against plain DFSPH, at their paper defaults.
    #[arg(long, value_delimiter = ',', value_parser = refinement_names())]
    pub refinements: Vec<String>,
    /// Also print MCVSPH's Biot–Savart error against run time for 0.1 % to 10 % vortex
    /// particles at the smallest size.
    #[arg(long)]
    pub mcvsph_error: bool,
    /// Also time VRSPH's four neighbour passes at each size against the floor of passes that
    /// load the same data and do no arithmetic.
    #[arg(long)]
    pub passes: bool,
    /// Also print each phase of the DFSPH step (search, pair cache, divergence, pressure, the
    /// rest) against its data-movement floor: the bytes it must move at the measured read
    /// bandwidth.
    #[arg(long)]
    pub floors: bool,
    /// Also time each size and solver on thread pools of these sizes (e.g. 1,2,4,8,16): strong
    /// scaling, each pool's speed-up and parallel efficiency against the first, and whether
    /// every pool ended in the same state to the bit (it must: the sums run in a fixed order).
    #[arg(long, value_delimiter = ',', value_parser = clap::value_parser!(u64).range(1..256))]
    pub threads: Vec<u64>,
}

impl From<BenchArgs> for BenchOptions {
    fn from(a: BenchArgs) -> Self {
        BenchOptions {
            sizes: a.sizes,
            solvers: a.solvers,
            warmup: a.warmup,
            steps: a.steps,
            refinements: a.refinements,
            mcvsph_error: a.mcvsph_error,
            passes: a.passes,
            floors: a.floors,
            threads: a.threads.into_iter().map(|t| t as usize).collect(),
        }
    }
}

/// Options of `eddy bench-grid`.
#[derive(Debug, Clone, clap::Args)]
pub struct GridBenchArgs {
    /// Smoke plume resolutions (cells per side).
    #[arg(long, value_delimiter = ',', num_args = 0.., default_value = "64,128")]
    pub plume: Vec<usize>,
    /// Steps run before timing starts (the plume has to start moving).
    #[arg(long, default_value_t = 10)]
    pub warmup: u64,
    /// Timed steps.
    #[arg(long, default_value_t = 10)]
    pub steps: u64,
    /// Taylor–Green resolutions (cells per side); the flag alone skips the table.
    #[arg(long, value_delimiter = ',', num_args = 0.., default_value = "32,64,128")]
    pub taylor_green: Vec<usize>,
}

impl From<GridBenchArgs> for GridBenchOptions {
    fn from(a: GridBenchArgs) -> Self {
        GridBenchOptions {
            plume: a.plume,
            warmup: a.warmup,
            steps: a.steps,
            taylor_green: a.taylor_green,
        }
    }
}

/// Options of `eddy bench-abl`.
#[derive(Debug, Clone, clap::Args)]
pub struct AblBenchArgs {
    /// A scene with an `abl` obstacle: the backward-facing step on a grid (the default), or a
    /// stream past obstacles on SPH particles (e.g. scenes/abl_sph_river_quick.toml).
    #[arg(default_value = "scenes/abl_backward_step.toml")]
    pub scene: PathBuf,
    /// Resolution factor of the plain reference run [default: 4 on a grid, 2 on particles].
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    pub scale: Option<u64>,
    /// Stations behind the obstacles, m along x [default: 1.25,1.5,2,2.5,3 on a grid; two and
    /// four obstacle lengths behind each obstacle with a database on particles].
    #[arg(long, value_delimiter = ',')]
    pub stations: Vec<f64>,
    /// Statistics from this time, s [default: the grid's average_from; half the run on
    /// particles].
    #[arg(long, value_name = "SECONDS")]
    pub from: Option<f64>,
    /// Override a scene key in every run, e.g. --set time.end=6 (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Leave out the reference run (no errors are then computed).
    #[arg(long)]
    pub skip_reference: bool,
    /// Compare with the reference profiles of an earlier run (its `reference.csv` in
    /// `--profiles`) instead of running the reference again.
    #[arg(long, value_name = "CSV")]
    pub reference: Option<PathBuf>,
    /// Write each run's profiles (station, y, U, k, U_ci, k_ci) into this folder as LABEL.csv,
    /// and its statistics as LABEL_statistics.h5, as each run ends. A run keeps its progress
    /// there as LABEL.checkpoint.h5 every 10 minutes and goes on from it when the command is
    /// run again (the reference can run in pieces); the file goes when the run ends.
    #[arg(long, value_name = "DIR")]
    pub profiles: Option<PathBuf>,
    /// Minutes of wall time between a run's checkpoints in --profiles.
    #[arg(long, value_name = "MINUTES", default_value_t = 10.0)]
    pub checkpoint_every: f64,
    /// Draw the errors against wall time and the middle station's U profiles into this PNG.
    #[arg(long, value_name = "PNG")]
    pub plot: Option<PathBuf>,
    /// Repeat the random and abl runs (and the plain one when the inflow fluctuates) with this
    /// many scene seeds (at least 1).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..))]
    pub seeds: u64,
    /// Only these runs, e.g. --runs reference to store a reference with --profiles [default:
    /// every run].
    #[arg(long, value_delimiter = ',', value_parser = ["none", "random", "abl", "reference"])]
    pub runs: Vec<String>,
}

impl From<AblBenchArgs> for AblBenchOptions {
    fn from(a: AblBenchArgs) -> Self {
        AblBenchOptions {
            scale: a.scale.map(|s| s as usize),
            stations: a.stations,
            from: a.from,
            overrides: a.set,
            skip_reference: a.skip_reference,
            reference: a.reference,
            profiles: a.profiles,
            plot: a.plot,
            seeds: a.seeds,
            runs: a.runs,
            checkpoint_every: std::time::Duration::from_secs_f64(60.0 * a.checkpoint_every),
        }
    }
}

/// Options of `eddy bench-coupling`.
#[derive(Debug, Clone, clap::Args)]
pub struct CouplingBenchArgs {
    /// A coupled scene (with `[coupling]`).
    #[arg(default_value = "scenes/coupled_wind_over_tank.toml")]
    pub scene: PathBuf,
    /// Override a scene key in every run, e.g. --set fluid.spacing=0.01 (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Steps of each run before timing starts.
    #[arg(long, default_value_t = 5)]
    pub warmup: u64,
    /// Timed steps of each run per round.
    #[arg(long, default_value_t = 20)]
    pub steps: u64,
    /// Rounds of (coupled, grid alone, SPH alone), alternating.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u64).range(1..))]
    pub rounds: u64,
}

impl From<CouplingBenchArgs> for CouplingBenchOptions {
    fn from(a: CouplingBenchArgs) -> Self {
        CouplingBenchOptions {
            overrides: a.set,
            warmup: a.warmup,
            steps: a.steps,
            rounds: a.rounds,
        }
    }
}
