//! `eddy sweep` and `eddy plot-sweep` on the command line: their options, the study they
//! describe, a progress bar and the messages. The study itself (points, runs as child
//! processes, sweep.csv, measures, shards, curves) is the library's [`eddy::study`].

use std::io::IsTerminal;
use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use eddy::study::{self, Analytic, Design, Measure, Status, Stress, Study};

/// Options of `eddy sweep`.
#[derive(Debug, Clone, clap::Args)]
pub struct SweepArgs {
    /// The scene (TOML).
    #[arg(required_unless_present = "collect")]
    pub scene: Option<PathBuf>,
    /// A scene key and its values, e.g. --vary fluid.spacing=0.02,0.01 (repeatable; an array
    /// value keeps its commas: --vary grid.resolution=[32,32,1],[64,64,1]).
    #[arg(long, value_name = "KEY=V1,V2,...")]
    pub vary: Vec<String>,
    /// Pair varied lists of one length instead of taking their product: all of them, or only
    /// the keys given (--zip grid.resolution,domain.max), which then vary together while the
    /// product runs over them and the other keys.
    #[arg(long, num_args = 0.., value_delimiter = ',', value_name = "KEYS")]
    pub zip: Option<Vec<String>>,
    /// A scene key held for every point, e.g. --set time.end=0.5 (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Runs at once; the cores are split between them.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..))]
    pub jobs: u64,
    /// Run every N-th point starting at k, into sweep-k-of-N.csv (join with --collect).
    #[arg(long, value_name = "k/N", value_parser = eddy::io::parse_shard)]
    pub shard: Option<(usize, usize)>,
    /// Stop a run after this many wall-clock seconds and record it as timed out.
    #[arg(long)]
    pub timeout: Option<f64>,
    /// The study's folder (default: out/sweep_<scene name>); with --collect, the joined
    /// sweep.csv (default: sweep.csv in the first folder).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Error of each run against an analytic solution eddy knows
    /// (docs/src/parameter-studies.md): `taylor-green` (a scene with grid.initial_flow = "taylor_green"): the largest
    /// |ln(E / E_exact)| of the energy decay over the run; `hydrostatic` (a fluid with gravity
    /// and point probes): the probes' pressure over the run's second half against rho |g|
    /// depth; `poiseuille` (a grid channel periodic in x between walls at y, driven by gravity
    /// along x with grid.gravity = true): the line probes' u at the end against the flow
    /// started from rest. Column `error_<name>`.
    #[arg(long, value_parser = analytic_names())]
    pub analytic: Option<Analytic>,
    /// A reference run's folder: each --compare column of the runs is compared with its own
    /// (relative L2 norm over the reference's rows; see docs/src/parameter-studies.md).
    #[arg(long, value_name = "RUN_DIR", requires = "compare")]
    pub reference: Option<PathBuf>,
    /// A column compared with the reference run: metrics:NAME or probes:NAME (against time),
    /// or profile:PROBE:COLUMN (a line probe's profile_PROBE.csv at the end of the run, against
    /// the distance s along it), repeatable.
    #[arg(long, value_name = "FILE:COLUMN", requires = "reference")]
    pub compare: Vec<String>,
    /// A table of published values (CSV with a `time` column; `#` starts a comment line) to
    /// compare --column with, e.g. scenes/reference/martin_moyce_1952.csv.
    #[arg(long, value_name = "FILE", requires = "column")]
    pub reference_csv: Option<PathBuf>,
    /// The column of --reference-csv, compared with the run's metrics or probes column of
    /// that name (sweep.csv column error_<NAME>_<table file stem>).
    #[arg(long, value_name = "NAME", requires = "reference_csv")]
    pub column: Option<String>,
    /// Stability study: run each point long (up to --stress-steps steps, or the scene's end if
    /// that comes first), count energy growth beyond --energy-growth over its running minimum
    /// as unstable too, and report the largest stable value of each varied key
    /// (stability.csv).
    #[arg(long)]
    pub stress: bool,
    /// Steps of a --stress run.
    #[arg(long, default_value_t = 10_000, requires = "stress")]
    pub stress_steps: u64,
    /// With --stress: a run whose energy (total_energy of SPH metrics, else kinetic_energy)
    /// exceeds this factor times its running minimum is unstable; 0 turns the check off
    /// (for a grid that starts at rest and is driven, whose energy grows by design).
    #[arg(long, default_value_t = 10.0, requires = "stress")]
    pub energy_growth: f64,
    /// Join the sweep-k-of-N.csv files of these folders into one sweep.csv.
    #[arg(long, num_args = 1.., value_name = "DIR", conflicts_with_all = ["scene", "vary", "shard"])]
    pub collect: Vec<PathBuf>,
}

/// Options of `eddy plot-sweep`.
#[derive(Debug, Clone, clap::Args)]
pub struct PlotArgs {
    /// A sweep.csv.
    pub sweep: PathBuf,
    /// The column along x (e.g. wall_seconds).
    #[arg(long)]
    pub x: String,
    /// The column along y (e.g. error_taylor_green).
    #[arg(long)]
    pub y: String,
    /// One curve per value of these columns (e.g. varied keys: one curve per method); one
    /// curve when left out.
    #[arg(long, value_delimiter = ',')]
    pub by: Vec<String>,
    /// Linear axes instead of log-log.
    #[arg(long)]
    pub linear: bool,
    /// Markers only, no lines: with two varied keys as --x and --y and --by status, a
    /// stability map.
    #[arg(long)]
    pub points: bool,
    /// The PNG to write.
    #[arg(long)]
    pub out: PathBuf,
}

/// `--analytic`'s names, each with what it is for the help.
fn analytic_names() -> impl TypedValueParser<Value = Analytic> {
    PossibleValuesParser::new(Analytic::ALL.map(|a| PossibleValue::new(a.name()).help(a.summary())))
        .try_map(|name| {
            Analytic::ALL
                .into_iter()
                .find(|a| a.name() == name)
                .ok_or("not an analytic solution eddy knows")
        })
}

/// `eddy plot-sweep`: y against x of a sweep's rows, a curve per value of `by`, the points of
/// a curve in order of x; rows without a number in either column are left out.
pub fn plot(args: &PlotArgs) -> anyhow::Result<()> {
    let curves = study::curves(&args.sweep, &args.x, &args.y, &args.by)?;
    let left_out = eddy::io::plot::study_figure(
        &args.out,
        (&args.x, &args.y),
        &curves,
        !args.linear,
        !args.points,
    )?;
    if left_out > 0 {
        eprintln!("eddy: left out {left_out} points a log axis cannot show (use --linear)");
    }
    eprintln!("eddy: wrote {}", args.out.display());
    Ok(())
}

/// The study `args` describe (all but --collect): its points, and its measures with their
/// references read.
fn study(args: &SweepArgs) -> anyhow::Result<Study> {
    let scene = args.scene.clone().context("give the scene to sweep")?;
    let design = Design::new(&args.vary, args.zip.as_deref())?;
    let mut measures: Vec<Measure> = args.analytic.map(Measure::Analytic).into_iter().collect();
    if let Some(dir) = &args.reference {
        for c in &args.compare {
            measures.push(Measure::compare(dir, c)?);
        }
    }
    if let (Some(path), Some(column)) = (&args.reference_csv, &args.column) {
        measures.push(Measure::table(path, column)?);
    }
    Ok(Study {
        scene,
        design,
        set: args.set.clone(),
        measures,
        stress: args.stress.then_some(Stress {
            steps: args.stress_steps,
            energy_growth: args.energy_growth,
        }),
        jobs: args.jobs as usize,
        shard: args.shard,
        timeout: args.timeout,
        out: args.out.clone(),
    })
}

/// Runs `eddy sweep`; `exe` is the `eddy` binary the points run with.
pub fn run(args: &SweepArgs, exe: &Path) -> anyhow::Result<()> {
    if !args.collect.is_empty() {
        let out = args
            .out
            .clone()
            .unwrap_or_else(|| args.collect[0].join("sweep.csv"));
        let n = study::collect(&args.collect, &out)?;
        eprintln!("eddy: {n} rows -> {}", out.display());
        return Ok(());
    }
    let study = study(args)?;
    let plan = study.plan()?;
    eprintln!(
        "eddy: sweeping {} over {} points ({} here), {} at once with {} threads each -> {}",
        study.scene.display(),
        study.design.points().len(),
        plan.here.len(),
        plan.jobs,
        plan.threads,
        plan.out.display()
    );
    let bar = progress_bar(plan.here.len() as u64);
    let rows = plan.run(exe, |row| {
        if let Some(row) = row {
            bar.set_message(format!("point {}: {}", row.index, row.status.name()));
        }
        bar.inc(1);
    });
    bar.finish_and_clear();
    let rows = rows?;
    if let Some(bounds) = plan.bounds(&rows) {
        for b in &bounds {
            eprintln!(
                "eddy: {}: largest stable {}, smallest unstable {}",
                b.key,
                b.largest_stable.as_deref().unwrap_or("none"),
                b.smallest_unstable.as_deref().unwrap_or("none")
            );
        }
        plan.write_bounds(&bounds)?;
    }
    let count = |s: Status| rows.iter().filter(|r| r.status == s).count();
    eprintln!(
        "eddy: {} finished, {} unstable, {} failed, {} timed out -> {}",
        count(Status::Finished),
        count(Status::Unstable),
        count(Status::Failed),
        count(Status::TimedOut),
        plan.csv.display()
    );
    Ok(())
}

fn progress_bar(len: u64) -> indicatif::ProgressBar {
    if !std::io::stderr().is_terminal() {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(len);
    if let Ok(style) = indicatif::ProgressStyle::with_template(
        "{bar:40} {pos}/{len} runs, {elapsed} elapsed, ~{eta} left, {msg}",
    ) {
        bar.set_style(style);
    }
    bar
}
