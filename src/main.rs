//! The `eddy` command line: run scenes, print their plans, benchmark the solvers.

use anyhow::Context;
use clap::{Parser, Subcommand};
use eddy::pipeline::{self as run, Pipeline, Plan, RunOptions};
use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

mod cli;

#[derive(Parser)]
#[command(
    name = "eddy",
    version,
    about = "Wall-induced turbulence on MAC grids and SPH particles"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a scene file.
    Run {
        /// The scene (TOML).
        scene: PathBuf,
        /// Output folder (default: the scene's output.dir, else out/<name>).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Override a scene key, e.g. --set time.end=0.5 (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// Stop at this simulated time (s) if it comes first.
        #[arg(long)]
        until: Option<f64>,
        /// Stop after this many steps if they come first.
        #[arg(long)]
        steps: Option<u64>,
        /// Print the stages the scene will run, and exit.
        #[arg(long)]
        plan: bool,
        /// Write how the run ended (finished, unstable, failed; its cause; peak memory) to
        /// this TOML file: what `eddy sweep` reads of each point.
        #[arg(long, value_name = "FILE")]
        status: Option<PathBuf>,
        /// Go on from the checkpoint in the output folder (checkpoint.h5) instead of starting
        /// at t = 0; the scene may differ from the checkpoint's only in time.end, time.steps
        /// and the [output] keys.
        #[arg(long)]
        resume: bool,
    },
    /// Go on with the run in DIR from its checkpoint (checkpoint.h5, written every
    /// output.checkpoint_interval or output.checkpoint_every, and when SIGINT or SIGTERM
    /// stops a run), with the scene it ran (DIR/scene.toml).
    Resume {
        /// The run's output folder.
        dir: PathBuf,
        /// Override a key of the run's scene, e.g. --set time.end=10 (repeatable; only
        /// time.end, time.steps and [output] keys may change).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// Stop at this simulated time (s) if it comes first.
        #[arg(long)]
        until: Option<f64>,
    },
    /// A parameter study of a scene: one run per point of the varied values, each in its own
    /// folder, and a sweep.csv with how each ended, its steps, wall time and peak memory.
    Sweep(cli::sweep::SweepArgs),
    /// Plot two columns of a sweep.csv against each other (log-log by default), one curve per
    /// value of a column: error against wall time, one curve per method.
    PlotSweep(cli::sweep::PlotArgs),
    /// Time the SPH solvers on the 3D dam-break benchmark (docs/src/benchmarks.md).
    Bench(cli::bench::BenchArgs),
    /// Time the MAC grid: smoke plume steps and Taylor-Green error against run time.
    BenchGrid(cli::bench::GridBenchArgs),
    /// Run time against error of the artificial boundary layers (Pfaff et al. Figure 8): the
    /// backward-facing step with ABL seeding, random seeding and none, against a finer plain run.
    BenchAbl(cli::bench::AblBenchArgs),
    /// What the exchange of a coupled grid + SPH scene costs: the coupled step against its grid
    /// and its SPH fluid stepped alone, in alternating rounds, and the coupled step by stage.
    BenchCoupling(cli::bench::CouplingBenchArgs),
    /// Plot energy and vorticity against time for several runs into one PNG.
    Compare {
        /// Run output folders (each with a metrics.csv).
        #[arg(required = true)]
        runs: Vec<PathBuf>,
        /// The PNG (or SVG) to write.
        #[arg(long)]
        out: PathBuf,
        /// Legend labels, one per run in order (default: each run folder's name).
        #[arg(long, value_delimiter = ',', value_name = "A,B,...")]
        label: Vec<String>,
        /// One panel of this column against time instead of the energy panels:
        /// metrics:COLUMN or probes:COLUMN, e.g. probes:front.
        #[arg(long, value_name = "FILE:COLUMN")]
        column: Option<String>,
        /// A table of published values (CSV with `time` and the column; `#` starts a comment
        /// line) drawn as markers, e.g. scenes/reference/martin_moyce_1952.csv.
        #[arg(long, value_name = "FILE", requires = "column")]
        reference_csv: Option<PathBuf>,
    },
    /// A quick look at a run without ParaView: a colour map of one field of its frames (HDF5 or
    /// VTK) on a plane across an axis (the grid's cells, or the particles of a thin slab as
    /// dots), with a colour bar and its unit, axes in metres and the time in the title; one
    /// frame, a numbered series or an animated GIF on one colour range.
    Slice(cli::slice::SliceArgs),
    /// Spectra of a run: the power spectral density of a probe's (or any probes.csv or
    /// metrics.csv column's) time series by Welch's method, with its peak frequency, or the
    /// shell-averaged kinetic-energy spectrum E(k) of a grid frame; a CSV and a log-log PNG.
    Spectrum(cli::spectrum::SpectrumArgs),
    /// The DFG cylinder benchmark (Schäfer & Turek 1996) from a run of scenes/dfg_2d1.toml
    /// (steady, Re 20) or scenes/dfg_2d2.toml (periodic, Re 100): drag and lift coefficients,
    /// the recirculation length or the Strouhal number, and the pressure difference across the
    /// cylinder, each against the published band.
    Dfg {
        /// The run's output folder.
        run: PathBuf,
    },
    /// Look up artificial-boundary-layer vorticity in a precomputed database, written as CSV.
    Lookup(cli::abl::LookupArgs),
    /// Summarise an artificial-boundary-layer database.
    Info(cli::abl::InfoArgs),
    /// Every scene key: its type, default, allowed range and meaning, from the code itself.
    SceneKeys {
        /// Print the book's page instead (docs/src/scene-reference.md).
        #[arg(long)]
        markdown: bool,
    },
}

/// Runs the command; an error is printed as its chain of causes, never as a backtrace (an input
/// error is the user's to fix, not a crash), and the exit status is 1.
fn main() -> ExitCode {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| "warn".into()),
        )
        .with_ansi(std::io::stderr().is_terminal())
        .with_writer(std::io::stderr)
        // Warnings are for the person at the terminal: the level and the message, no timestamp
        // or module path.
        .without_time()
        .with_target(false)
        .init();
    let command = Cli::parse().command;
    // The command runs on a worker of rayon's pool, not on the main thread: a parallel loop
    // started from outside the pool hands its work over and sleeps on a lock until it is done,
    // a wake-up per loop that a small scene pays for every loop of its step (measured in the
    // book's benchmarks chapter). From a worker the loop starts in place.
    // Results are unchanged: every sum is in a fixed order (`parallel.rs`).
    match rayon::scope(|_| run(command)) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            let interrupted = e.chain().any(|c| {
                matches!(
                    c.downcast_ref::<run::RunError>(),
                    Some(run::RunError::Interrupted { .. })
                )
            });
            if interrupted {
                ExitCode::from(run::INTERRUPTED_EXIT)
            } else {
                ExitCode::FAILURE
            }
        }
    }
}

fn run(command: Command) -> anyhow::Result<()> {
    match command {
        Command::Resume { dir, set, until } => {
            let options = RunOptions {
                out: Some(dir.clone()),
                overrides: set,
                until,
                resume: true,
                ..RunOptions::default()
            };
            run_one(dir.join(run::outputs::SCENE_FILE), options, false)?;
        }
        Command::Run {
            scene,
            out,
            set,
            until,
            steps,
            plan,
            status,
            resume,
        } => {
            let options = RunOptions {
                out,
                overrides: set,
                until,
                steps,
                resume,
                ..RunOptions::default()
            };
            let result = run_one(scene, options, plan);
            if let Some(path) = status {
                let (how, cause) = match &result {
                    Ok(()) => (eddy::study::Status::Finished, String::new()),
                    Err(e) => {
                        let unstable = e.chain().any(|c| {
                            matches!(
                                c.downcast_ref::<run::RunError>(),
                                Some(run::RunError::Unstable { .. } | run::RunError::Grid { .. })
                            )
                        });
                        let how = if unstable {
                            eddy::study::Status::Unstable
                        } else {
                            eddy::study::Status::Failed
                        };
                        (how, format!("{e:#}"))
                    }
                };
                eddy::study::write_status(&path, how, &cause)?;
            }
            result?;
        }
        Command::Sweep(args) => {
            let exe = std::env::current_exe().context("finding the eddy executable")?;
            cli::sweep::run(&args, &exe)?;
        }
        Command::PlotSweep(args) => cli::sweep::plot(&args)?,
        Command::Dfg { run } => {
            let rows = eddy::bench::dfg::evaluate(&run)
                .map_err(|e| anyhow::anyhow!("{}: {e}", run.display()))?;
            print!("{}", eddy::bench::dfg::table(&rows));
        }
        Command::Bench(args) => eddy::bench::run(&args.into())?,
        Command::BenchGrid(args) => eddy::bench::grid::run(&args.into())?,
        Command::BenchAbl(args) => {
            let rows = eddy::bench::abl::run(&args.scene.clone(), &args.into())?;
            print!("{}", eddy::bench::abl::table(&rows));
        }
        Command::BenchCoupling(args) => {
            let bench = eddy::bench::coupling::run(&args.scene.clone(), &args.into())?;
            print!("{}", eddy::bench::coupling::table(&bench));
        }
        Command::Compare {
            runs,
            out,
            label,
            column,
            reference_csv,
        } => {
            use eddy::io::plot::RunSeries;
            if !label.is_empty() && label.len() != runs.len() {
                anyhow::bail!(
                    "--label gives {} labels for {} runs",
                    label.len(),
                    runs.len()
                );
            }
            let (file, column) = match column.as_deref().map(|c| c.split_once(':')) {
                None => ("metrics", None),
                Some(Some((file @ ("metrics" | "probes"), name))) => (file, Some(name)),
                Some(_) => anyhow::bail!(
                    "--column {}: expected metrics:COLUMN or probes:COLUMN",
                    column.unwrap_or_default()
                ),
            };
            let mut series = runs
                .iter()
                .map(|d| RunSeries::read_file(d, &format!("{file}.csv")))
                .collect::<Result<Vec<_>, _>>()?;
            for (s, l) in series.iter_mut().zip(label) {
                s.label = l;
            }
            let skipped = match column {
                None => eddy::io::plot::compare(&series, &out)?,
                Some(name) => {
                    if let Some(missing) = series.iter().find(|s| s.column(name).is_none()) {
                        anyhow::bail!("run {} has no {file} column `{name}`", missing.label);
                    }
                    let table = reference_csv.map(|p| RunSeries::read_csv(&p)).transpose()?;
                    let lacks =
                        |t: &&RunSeries| t.column("time").is_none() || t.column(name).is_none();
                    if let Some(t) = table.as_ref().filter(lacks) {
                        anyhow::bail!(
                            "--reference-csv {}: no `time` and `{name}` columns",
                            t.label
                        );
                    }
                    eddy::io::plot::compare_column(&series, name, table.as_ref(), &out)?
                }
            };
            if skipped > 0 {
                eprintln!(
                    "eddy: warning: left out {skipped} points whose time or value is not finite"
                );
            }
            eprintln!("eddy: wrote {}", out.display());
        }
        Command::Slice(args) => cli::slice::run(&args)?,
        Command::Spectrum(args) => cli::spectrum::run(&args)?,
        Command::Lookup(args) => cli::abl::lookup(&args)?,
        Command::Info(args) => cli::abl::info(&args)?,
        Command::SceneKeys { markdown } => {
            use eddy::scene::reference;
            print!(
                "{}",
                if markdown {
                    reference::markdown()
                } else {
                    reference::text()
                }
            );
        }
    }
    Ok(())
}

/// A flag SIGINT and SIGTERM set (what a scheduler sends before it kills a job): the run
/// writes a checkpoint after the step in progress and stops. A second signal ends the process
/// at once.
fn stop_flag() -> anyhow::Result<Arc<AtomicBool>> {
    use signal_hook::consts::{SIGINT, SIGTERM};
    let flag = Arc::new(AtomicBool::new(false));
    for signal in [SIGINT, SIGTERM] {
        signal_hook::flag::register_conditional_shutdown(signal, 130, flag.clone())?;
        signal_hook::flag::register(signal, flag.clone())?;
    }
    Ok(flag)
}

/// `eddy run`: the plan, or the run with its summary line.
fn run_one(scene: PathBuf, mut options: RunOptions, plan: bool) -> anyhow::Result<()> {
    options.progress = std::io::stderr().is_terminal();
    let resolved = run::resolve(&scene, &options)?;
    if plan {
        let built =
            Pipeline::build(&resolved).with_context(|| format!("building {}", scene.display()))?;
        print!("{}", Plan::of(&built));
        return Ok(());
    }
    eprintln!(
        "eddy: {} {} -> {}",
        if options.resume {
            "resuming"
        } else {
            "running"
        },
        scene.display(),
        run::output_dir(&resolved, &options).display()
    );
    options.stop = Some(stop_flag()?);
    let s = run::run_scene(&resolved, &options)
        .with_context(|| format!("running {}", scene.display()))?;
    let rate = |n: usize| s.steps as f64 * n as f64 / s.wall_seconds / 1e6;
    let mut sizes = Vec::new();
    if s.fluid_particles > 0 {
        let lost = match s.lost_particles {
            0 => String::new(),
            n => format!(" ({n} lost through open sides)"),
        };
        sizes.push(format!(
            "{} fluid particles{lost}, {} boundary particles, {:.2} M fluid particle-steps/s",
            s.fluid_particles,
            s.boundary_particles,
            rate(s.fluid_particles)
        ));
    }
    if s.grid_cells > 0 {
        sizes.push(format!(
            "{} cells, {:.2} M cell-steps/s",
            s.grid_cells,
            rate(s.grid_cells)
        ));
    }
    eprintln!(
        "eddy: {} steps to t = {:.4} s in {:.1} s ({}); {} frames in {}",
        s.steps,
        s.time,
        s.wall_seconds,
        sizes.join("; "),
        s.frames,
        s.out.display()
    );
    Ok(())
}
