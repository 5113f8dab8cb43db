//! `eddy sweep`: a parameter study of one scene. Every point of the study (the product of the
//! varied values, `--zip` pairing lists) is one `eddy run` in its own folder, as a
//! child process: a point that blows up, panics or runs out of time is recorded and the study
//! goes on, and its peak memory is its own. The rows land in `sweep.csv` (rewritten after each
//! run, so a killed study keeps what finished); `--shard k/N` runs every N-th point into
//! `sweep-k-of-N.csv` and `--collect` joins the shards' rows.

use std::collections::BTreeMap;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use anyhow::{bail, Context};

use super::analytic::Analytic;

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
    #[arg(long, value_enum)]
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

/// `eddy plot-sweep`: y against x of a sweep's rows, a curve per value of `by`, the points of
/// a curve in order of x; rows without a number in either column are left out.
pub fn plot(args: &PlotArgs) -> anyhow::Result<()> {
    let mut reader = csv::Reader::from_path(&args.sweep)
        .with_context(|| format!("reading {}", args.sweep.display()))?;
    let header = reader.headers()?.clone();
    let col = |name: &str| {
        header.iter().position(|h| h == name).with_context(|| {
            format!(
                "{} has no column `{name}` (it has: {})",
                args.sweep.display(),
                header.iter().collect::<Vec<_>>().join(", ")
            )
        })
    };
    let (x, y) = (col(&args.x)?, col(&args.y)?);
    let by: Vec<(usize, &String)> = args
        .by
        .iter()
        .map(|name| Ok((col(name)?, name)))
        .collect::<anyhow::Result<_>>()?;
    let mut curves: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    for record in reader.records() {
        let r = record?;
        let (Some(px), Some(py)) = (
            r.get(x).and_then(|v| v.parse::<f64>().ok()),
            r.get(y).and_then(|v| v.parse::<f64>().ok()),
        ) else {
            continue;
        };
        let label = if by.is_empty() {
            args.y.clone()
        } else {
            by.iter()
                .map(|&(c, name)| format!("{name} = {}", r.get(c).unwrap_or_default()))
                .collect::<Vec<_>>()
                .join(", ")
        };
        match curves.iter_mut().find(|(l, _)| *l == label) {
            Some((_, c)) => c.push((px, py)),
            None => curves.push((label, vec![(px, py)])),
        }
    }
    for (_, c) in &mut curves {
        c.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    // A map by status reads red for unstable (the palette's first colour), green for finished
    // (its second).
    let rank = |label: &str| {
        ["unstable", "finished", "failed", "timed out"]
            .iter()
            .position(|s| label.contains(&format!("status = {s}")))
    };
    curves.sort_by_key(|(label, _)| rank(label));
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

/// What each run is measured against: a column of sweep.csv each.
#[derive(Debug, Clone)]
enum Measure {
    /// An analytic solution eddy knows.
    Analytic(Analytic),
    /// A series of the run against the same series of a reference (time or s, value), from
    /// the run's `file` (metrics, probes, profile_NAME; None: metrics or probes, whichever has
    /// the column).
    Series {
        file: Option<String>,
        along: &'static str,
        column: String,
        /// The sweep.csv column is error_<name>.
        name: String,
        reference: Vec<(f64, f64)>,
    },
}

impl Measure {
    fn name(&self) -> String {
        match self {
            Measure::Analytic(a) => a.column().into(),
            Measure::Series { name, .. } => format!("error_{name}"),
        }
    }

    /// The error of the run in `dir`; None when it has no such series.
    fn error(&self, dir: &Path) -> Option<f64> {
        match self {
            Measure::Analytic(a) => a.error(dir),
            Measure::Series {
                file,
                along,
                column,
                reference,
                ..
            } => {
                let files = match file {
                    Some(f) => vec![f.as_str()],
                    None => vec!["metrics", "probes"],
                };
                let run = files
                    .iter()
                    .find_map(|f| series(&dir.join(format!("{f}.csv")), along, column))?;
                relative_l2(&run, reference)
            }
        }
    }
}

/// The measures `args` ask for, their references read and checked before any run.
fn measures(args: &SweepArgs) -> anyhow::Result<Vec<Measure>> {
    let mut out = Vec::new();
    if let Some(a) = args.analytic {
        out.push(Measure::Analytic(a));
    }
    if let Some(dir) = &args.reference {
        for c in &args.compare {
            let parts: Vec<&str> = c.split(':').collect();
            let (file, along, column, name) = match parts[..] {
                ["metrics", col] | ["probes", col] => {
                    (parts[0].to_string(), "time", col, col.to_string())
                }
                ["profile", probe, col] => (
                    format!("profile_{probe}"),
                    "s",
                    col,
                    format!("{probe}_{col}"),
                ),
                _ => bail!(
                    "--compare `{c}`: expected metrics:COLUMN, probes:COLUMN or \
                     profile:PROBE:COLUMN"
                ),
            };
            let path = dir.join(format!("{file}.csv"));
            let reference = series(&path, along, column).with_context(|| {
                format!(
                    "--compare {c}: the reference {} has no such column",
                    path.display()
                )
            })?;
            out.push(Measure::Series {
                file: Some(file),
                along,
                column: column.to_string(),
                name,
                reference,
            });
        }
    }
    if let (Some(path), Some(column)) = (&args.reference_csv, &args.column) {
        let reference = series(path, "time", column).with_context(|| {
            format!(
                "--reference-csv {}: no `time` and `{column}` columns",
                path.display()
            )
        })?;
        // Named after the table too, so it cannot clash with --compare's error of the column.
        let table = path.file_stem().unwrap_or_default().to_string_lossy();
        out.push(Measure::Series {
            file: None,
            along: "time",
            column: column.clone(),
            name: format!("{column}_{table}"),
            reference,
        });
    }
    Ok(out)
}

/// (`along`, value) of `column` of a CSV with an `along` column (time, or s of a profile);
/// None when either is missing. Lines starting with `#` are comments (a published table's
/// source, as in `scenes/reference/`).
pub(super) fn series(path: &Path, along: &str, column: &str) -> Option<Vec<(f64, f64)>> {
    let mut reader = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .from_path(path)
        .ok()?;
    let header = reader.headers().ok()?.clone();
    let t = header.iter().position(|h| h == along)?;
    let c = header.iter().position(|h| h == column)?;
    Some(
        reader
            .records()
            .filter_map(Result::ok)
            .filter_map(|r| Some((r.get(t)?.parse().ok()?, r.get(c)?.parse().ok()?)))
            .collect(),
    )
}

/// sqrt(sum (a(t_k) - r_k)^2 / sum r_k^2) over the reference rows (t_k, r_k) inside the run's
/// span of t (time, or s along a profile), with a(t) the run's series interpolated linearly;
/// None when none overlap.
fn relative_l2(run: &[(f64, f64)], reference: &[(f64, f64)]) -> Option<f64> {
    let (first, last) = (run.first()?.0, run.last()?.0);
    let (mut num, mut den, mut n) = (0.0, 0.0, 0);
    for &(t, r) in reference.iter().filter(|(t, _)| *t >= first && *t <= last) {
        let i = run.partition_point(|(s, _)| *s < t);
        let a = match (i.checked_sub(1).map(|j| run[j]), run.get(i)) {
            (_, Some(&(s, v))) if s == t => v,
            (Some((s0, v0)), Some(&(s1, v1))) => v0 + (v1 - v0) * (t - s0) / (s1 - s0),
            (Some((_, v)), None) | (None, Some(&(_, v))) => v,
            (None, None) => return None,
        };
        num += (a - r) * (a - r);
        den += r * r;
        n += 1;
    }
    (n > 0).then(|| {
        if den > 0.0 {
            (num / den).sqrt()
        } else {
            num.sqrt()
        }
    })
}

/// One varied key and its values, as given.
#[derive(Debug, Clone, PartialEq)]
struct Axis {
    key: String,
    values: Vec<String>,
}

/// `KEY=V1,V2,...`, split at the commas outside brackets and quotes.
fn parse_vary(s: &str) -> anyhow::Result<Axis> {
    let (key, list) = s
        .split_once('=')
        .with_context(|| format!("--vary `{s}`: expected KEY=V1,V2,..."))?;
    let key = key.trim();
    if key.is_empty() {
        bail!("--vary `{s}`: the key is empty");
    }
    let (mut values, mut depth, mut quoted, mut start) = (Vec::new(), 0i32, false, 0);
    for (i, c) in list.char_indices() {
        match c {
            '"' => quoted = !quoted,
            '[' | '{' if !quoted => depth += 1,
            ']' | '}' if !quoted => depth -= 1,
            ',' if !quoted && depth == 0 => {
                values.push(list[start..i].trim().to_string());
                start = i + 1;
            }
            _ => {}
        }
    }
    values.push(list[start..].trim().to_string());
    if let Some(i) = values.iter().position(String::is_empty) {
        bail!("--vary `{s}`: value {} is empty", i + 1);
    }
    Ok(Axis {
        key: key.to_string(),
        values,
    })
}

/// The points of the study: for each, its value of every axis (in the order given). The
/// axes in `zip` (all of them for an empty list) vary together, as one axis; the product runs
/// over that one and the others.
fn points(axes: &[Axis], zip: Option<&[String]>) -> anyhow::Result<Vec<Vec<String>>> {
    let zipped = |a: &Axis| zip.is_some_and(|z| z.is_empty() || z.contains(&a.key));
    if let Some(key) = zip
        .unwrap_or_default()
        .iter()
        .find(|k| !axes.iter().any(|a| &a.key == *k))
    {
        bail!("--zip {key}: not a --vary key");
    }
    // Each slot is a list of choices; a choice sets some axes (by index) to values.
    let mut slots: Vec<Vec<Vec<(usize, String)>>> = Vec::new();
    let group: Vec<usize> = (0..axes.len()).filter(|&i| zipped(&axes[i])).collect();
    for (i, a) in axes.iter().enumerate() {
        if group.first() == Some(&i) {
            let n = a.values.len();
            if let Some(&j) = group.iter().find(|&&j| axes[j].values.len() != n) {
                bail!(
                    "--zip pairs lists of one length: {} has {n} values, {} has {}",
                    a.key,
                    axes[j].key,
                    axes[j].values.len()
                );
            }
            slots.push(
                (0..n)
                    .map(|k| {
                        group
                            .iter()
                            .map(|&j| (j, axes[j].values[k].clone()))
                            .collect()
                    })
                    .collect(),
            );
        } else if !group.contains(&i) {
            slots.push(a.values.iter().map(|v| vec![(i, v.clone())]).collect());
        }
    }
    let choices = slots.iter().fold(vec![Vec::new()], |acc, slot| {
        acc.iter()
            .flat_map(|p: &Vec<(usize, String)>| {
                slot.iter().map(move |c| {
                    let mut p = p.clone();
                    p.extend(c.iter().cloned());
                    p
                })
            })
            .collect()
    });
    Ok(choices
        .into_iter()
        .map(|mut c| {
            c.sort_by_key(|(i, _)| *i);
            c.into_iter().map(|(_, v)| v).collect()
        })
        .collect())
}

/// How a run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    Finished,
    /// The solver stopped on an instability (its cause is in the row).
    Unstable,
    /// Any other error (the scene could not be built, a file could not be written).
    Failed,
    TimedOut,
}

impl Status {
    pub fn name(self) -> &'static str {
        match self {
            Status::Finished => "finished",
            Status::Unstable => "unstable",
            Status::Failed => "failed",
            Status::TimedOut => "timed out",
        }
    }
}

/// What `eddy run --status FILE` writes when the run ends: how, why, and the process's peak
/// resident memory.
pub fn write_status(path: &Path, status: Status, cause: &str) -> anyhow::Result<()> {
    let mut t = toml::Table::new();
    t.insert("status".into(), status.name().into());
    t.insert("cause".into(), cause.into());
    if let Some(bytes) = peak_memory() {
        t.insert("peak_memory_bytes".into(), (bytes as i64).into());
    }
    let text = toml::to_string(&t)?;
    eddy::io::write_atomic(path, |w| w.write_all(text.as_bytes()))?;
    Ok(())
}

/// Peak resident memory of this process (Linux: VmHWM), bytes.
fn peak_memory() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// One row of sweep.csv.
#[derive(Debug, Clone)]
struct Row {
    index: usize,
    values: Vec<String>,
    status: Status,
    cause: String,
    steps: Option<u64>,
    time: Option<f64>,
    wall_seconds: f64,
    peak_memory_mib: Option<f64>,
    /// One per measure, in the order of the study's measures.
    errors: Vec<Option<f64>>,
}

/// The fixed columns after the varied keys (the error columns come before `folder`).
const COLUMNS: [&str; 7] = [
    "status",
    "cause",
    "steps",
    "end_time",
    "wall_seconds",
    "peak_memory_mib",
    "folder",
];

fn run_folder(index: usize) -> String {
    format!("run_{index:04}")
}

impl Row {
    fn record(&self) -> Vec<String> {
        let mut r = vec![self.index.to_string()];
        r.extend(self.values.iter().cloned());
        r.extend([
            self.status.name().to_string(),
            self.cause.clone(),
            self.steps.map_or(String::new(), |s| s.to_string()),
            self.time.map_or(String::new(), |t| format!("{t}")),
            format!("{:.3}", self.wall_seconds),
            self.peak_memory_mib
                .map_or(String::new(), |m| format!("{m:.1}")),
        ]);
        r.extend(
            self.errors
                .iter()
                .map(|e| e.map_or(String::new(), |e| format!("{e:e}"))),
        );
        r.push(run_folder(self.index));
        r
    }
}

/// Writes the header and `rows` (in point order) to `path`, atomically.
fn write_rows(path: &Path, keys: &[String], errors: &[String], rows: &[Row]) -> anyhow::Result<()> {
    let mut header = vec!["point".to_string()];
    header.extend(keys.iter().cloned());
    let (fixed, folder) = COLUMNS.split_at(COLUMNS.len() - 1);
    header.extend(fixed.iter().map(|c| c.to_string()));
    header.extend(errors.iter().cloned());
    header.extend(folder.iter().map(|c| c.to_string()));
    let mut sorted: Vec<&Row> = rows.iter().collect();
    sorted.sort_by_key(|r| r.index);
    let mut records = vec![header];
    records.extend(sorted.iter().map(|r| r.record()));
    write_records(path, &records)
}

fn write_records(path: &Path, records: &[Vec<String>]) -> anyhow::Result<()> {
    let mut w = csv::Writer::from_writer(Vec::new());
    for r in records {
        w.write_record(r)?;
    }
    let bytes = w.into_inner().map_err(|e| anyhow::anyhow!("{e}"))?;
    eddy::io::write_atomic(path, |out| out.write_all(&bytes))?;
    Ok(())
}

/// Runs `eddy sweep`; `exe` is the `eddy` binary the points run with.
pub fn run(args: &SweepArgs, exe: &Path) -> anyhow::Result<()> {
    if !args.collect.is_empty() {
        let out = args
            .out
            .clone()
            .unwrap_or_else(|| args.collect[0].join("sweep.csv"));
        let n = collect(&args.collect, &out)?;
        eprintln!("eddy: {n} rows -> {}", out.display());
        return Ok(());
    }
    let scene_path = args.scene.as_ref().context("give the scene to sweep")?;
    let axes: Vec<Axis> = args
        .vary
        .iter()
        .map(|v| parse_vary(v))
        .collect::<anyhow::Result<_>>()?;
    for (i, a) in axes.iter().enumerate() {
        if axes[..i].iter().any(|b| b.key == a.key) {
            bail!("--vary {} is given twice", a.key);
        }
    }
    let all = points(&axes, args.zip.as_deref())?;
    let measures = measures(args)?;
    let error_names: Vec<String> = measures.iter().map(Measure::name).collect();
    // Every point's scene is loaded and validated before any run starts: a bad key or value
    // stops the study here, naming the point.
    let mut name = String::new();
    for (i, values) in all.iter().enumerate() {
        let scene = eddy::scene::load(scene_path, &overrides(&args.set, &axes, values))
            .with_context(|| format!("point {i} ({})", describe(&axes, values)))?;
        if let Some(a) = args.analytic {
            a.check(&scene)
                .with_context(|| format!("point {i} ({})", describe(&axes, values)))?;
        }
        name = scene.name;
    }
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| Path::new("out").join(format!("sweep_{name}")));
    std::fs::create_dir_all(&out).with_context(|| format!("creating {}", out.display()))?;
    let (k, n) = args.shard.unwrap_or((0, 1));
    let mine: Vec<usize> = (0..all.len()).filter(|i| i % n == k).collect();
    let csv_path = match args.shard {
        Some((k, n)) => out.join(format!("sweep-{k}-of-{n}.csv")),
        None => out.join("sweep.csv"),
    };
    let keys: Vec<String> = axes.iter().map(|a| a.key.clone()).collect();
    let jobs = (args.jobs as usize).min(mine.len()).max(1);
    let cores = std::thread::available_parallelism().map_or(1, |c| c.get());
    let threads = (cores / jobs).max(1);
    eprintln!(
        "eddy: sweeping {} over {} points ({} here), {jobs} at once with {threads} threads each \
         -> {}",
        scene_path.display(),
        all.len(),
        mine.len(),
        out.display()
    );
    let bar = progress_bar(mine.len() as u64);
    let rows: Mutex<Vec<Row>> = Mutex::new(Vec::new());
    let next = AtomicUsize::new(0);
    let failure: Mutex<Option<anyhow::Error>> = Mutex::new(None);
    std::thread::scope(|scope| {
        for _ in 0..jobs {
            scope.spawn(|| {
                while let Some(&index) = mine.get(next.fetch_add(1, Ordering::Relaxed)) {
                    let point = Point {
                        index,
                        values: &all[index],
                        overrides: overrides(&args.set, &axes, &all[index]),
                        steps: args.stress.then_some(args.stress_steps),
                    };
                    let result = run_point(exe, scene_path, &out, &point, threads, args.timeout)
                        .and_then(|mut row| {
                            let dir = out.join(run_folder(index));
                            row.errors = measures.iter().map(|m| m.error(&dir)).collect();
                            if args.stress && args.energy_growth > 0.0 {
                                flag_energy_growth(&mut row, &dir, args.energy_growth);
                            }
                            bar.set_message(format!("point {index}: {}", row.status.name()));
                            let mut rows = rows.lock().unwrap_or_else(|p| p.into_inner());
                            rows.push(row);
                            write_rows(&csv_path, &keys, &error_names, &rows)
                        });
                    bar.inc(1);
                    if let Err(e) = result {
                        failure
                            .lock()
                            .unwrap_or_else(|p| p.into_inner())
                            .get_or_insert(e);
                        return;
                    }
                }
            });
        }
    });
    bar.finish_and_clear();
    if let Some(e) = failure.into_inner().unwrap_or_else(|p| p.into_inner()) {
        return Err(e);
    }
    let rows = rows.into_inner().unwrap_or_else(|p| p.into_inner());
    write_rows(&csv_path, &keys, &error_names, &rows)?;
    if args.stress {
        let path = out.join(match args.shard {
            Some((k, n)) => format!("stability-{k}-of-{n}.csv"),
            None => "stability.csv".into(),
        });
        let report = stability(&axes, &rows);
        for r in &report[1..] {
            eprintln!(
                "eddy: {}: largest stable {}, smallest unstable {}",
                r[0],
                if r[1].is_empty() { "none" } else { &r[1] },
                if r[2].is_empty() { "none" } else { &r[2] }
            );
        }
        write_records(&path, &report)?;
    }
    let count = |s: Status| rows.iter().filter(|r| r.status == s).count();
    eprintln!(
        "eddy: {} finished, {} unstable, {} failed, {} timed out -> {}",
        count(Status::Finished),
        count(Status::Unstable),
        count(Status::Failed),
        count(Status::TimedOut),
        csv_path.display()
    );
    Ok(())
}

/// The overrides of a point: the held keys, then its varied values.
fn overrides(set: &[String], axes: &[Axis], values: &[String]) -> Vec<String> {
    let mut o = set.to_vec();
    o.extend(
        axes.iter()
            .zip(values)
            .map(|(a, v)| format!("{}={v}", a.key)),
    );
    o
}

fn describe(axes: &[Axis], values: &[String]) -> String {
    axes.iter()
        .zip(values)
        .map(|(a, v)| format!("{}={v}", a.key))
        .collect::<Vec<_>>()
        .join(", ")
}

struct Point<'a> {
    index: usize,
    values: &'a [String],
    overrides: Vec<String>,
    /// `eddy run --steps`: the step cap of a stress run.
    steps: Option<u64>,
}

/// Runs one point as `eddy run` in its folder and reads how it ended.
fn run_point(
    exe: &Path,
    scene: &Path,
    out: &Path,
    point: &Point,
    threads: usize,
    timeout: Option<f64>,
) -> anyhow::Result<Row> {
    let dir = out.join(run_folder(point.index));
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let status_file = dir.join("status.toml");
    let _ = std::fs::remove_file(&status_file);
    let log = std::fs::File::create(dir.join("log.txt"))
        .with_context(|| format!("creating the log in {}", dir.display()))?;
    let mut command = Command::new(exe);
    command
        .arg("run")
        .arg(scene)
        .arg("--out")
        .arg(&dir)
        .arg("--status")
        .arg(&status_file)
        .env("RAYON_NUM_THREADS", threads.to_string())
        .stdout(Stdio::null())
        .stderr(log);
    for o in &point.overrides {
        command.arg("--set").arg(o);
    }
    if let Some(steps) = point.steps {
        // A stress run goes on to its step cap unless the scene's end comes first.
        command.arg("--steps").arg(steps.to_string());
    }
    let started = Instant::now();
    let mut child = command
        .spawn()
        .with_context(|| format!("starting {}", exe.display()))?;
    let mut timed_out = false;
    loop {
        if child.try_wait()?.is_some() {
            break;
        }
        if timeout.is_some_and(|t| started.elapsed().as_secs_f64() > t) {
            child.kill()?;
            child.wait()?;
            timed_out = true;
            break;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let wall_seconds = started.elapsed().as_secs_f64();
    let report: Option<toml::Table> = std::fs::read_to_string(&status_file)
        .ok()
        .and_then(|t| t.parse().ok());
    let field = |k: &str| report.as_ref().and_then(|r| r.get(k));
    let (status, cause) = if timed_out {
        (
            Status::TimedOut,
            format!("stopped after {:.0} s", timeout.unwrap_or_default()),
        )
    } else {
        let status = match field("status").and_then(|s| s.as_str()) {
            Some("finished") => Status::Finished,
            Some("unstable") => Status::Unstable,
            _ => Status::Failed,
        };
        let cause = field("cause")
            .and_then(|c| c.as_str())
            .map(String::from)
            .unwrap_or_else(|| "the run ended without a status (see log.txt)".into());
        (status, cause)
    };
    let (steps, time) = last_metrics(&dir.join("metrics.csv"));
    Ok(Row {
        index: point.index,
        values: point.values.to_vec(),
        status,
        cause,
        steps,
        time,
        wall_seconds,
        peak_memory_mib: field("peak_memory_bytes")
            .and_then(|b| b.as_integer())
            .map(|b| b as f64 / (1024.0 * 1024.0)),
        errors: Vec::new(),
    })
}

/// Marks a finished run unstable when its energy grew beyond `factor` times its running
/// minimum (a blow-up that has not reached NaN yet): the energy is the metrics' total_energy
/// (SPH: kinetic, potential and rotational), else kinetic_energy (grid). A running minimum of
/// zero (a run that starts at rest) is not a base for a factor and is skipped.
fn flag_energy_growth(row: &mut Row, dir: &Path, factor: f64) {
    if row.status != Status::Finished {
        return;
    }
    let path = dir.join("metrics.csv");
    let Some(energy) =
        series(&path, "time", "total_energy").or_else(|| series(&path, "time", "kinetic_energy"))
    else {
        return;
    };
    let mut least = f64::INFINITY;
    for (t, e) in energy {
        least = least.min(e);
        if least > 0.0 && e > factor * least {
            row.status = Status::Unstable;
            row.cause = format!(
                "energy {e:.4e} at t = {t:.6} s is more than {factor} times its running minimum \
                 {least:.4e}"
            );
            return;
        }
    }
}

/// Per varied key: the largest value at which every point was stable (finished) and the
/// smallest at which one was not, numerically when the values are numbers (else in the order
/// given). Rows: key, largest stable, smallest unstable.
fn stability(axes: &[Axis], rows: &[Row]) -> Vec<Vec<String>> {
    let mut out = vec![vec![
        "key".to_string(),
        "largest_stable".into(),
        "smallest_unstable".into(),
    ]];
    for (k, axis) in axes.iter().enumerate() {
        let rank = |v: &str| -> f64 {
            v.parse::<f64>()
                .unwrap_or_else(|_| axis.values.iter().position(|x| x == v).unwrap_or(0) as f64)
        };
        let stable_at = |v: &String| {
            let mine: Vec<&Row> = rows.iter().filter(|r| &r.values[k] == v).collect();
            !mine.is_empty() && mine.iter().all(|r| r.status == Status::Finished)
        };
        let tried = |v: &String| rows.iter().any(|r| &r.values[k] == v);
        let by_rank = |a: &&String, b: &&String| rank(a).total_cmp(&rank(b));
        let stable = axis.values.iter().filter(|v| stable_at(v)).max_by(by_rank);
        let unstable = axis
            .values
            .iter()
            .filter(|v| tried(v) && !stable_at(v))
            .min_by(by_rank);
        out.push(vec![
            axis.key.clone(),
            stable.cloned().unwrap_or_default(),
            unstable.cloned().unwrap_or_default(),
        ]);
    }
    out
}

/// The steps a run took and the time it ended at, from its metrics.csv.
fn last_metrics(path: &Path) -> (Option<u64>, Option<f64>) {
    let Ok(mut reader) = csv::Reader::from_path(path) else {
        return (None, None);
    };
    let Ok(header) = reader.headers().cloned() else {
        return (None, None);
    };
    let col = |name: &str| header.iter().position(|h| h == name);
    let (Some(step), Some(time), Some(dt)) = (col("step"), col("time"), col("dt")) else {
        return (None, None);
    };
    let Some(last) = reader.records().filter_map(Result::ok).last() else {
        return (None, None);
    };
    let value = |c: usize| last.get(c).and_then(|v| v.parse::<f64>().ok());
    // A row records the step that starts at `time` (step 0 at t = 0): the run has taken one
    // step more than the last row's index and ended at its time plus its dt.
    (
        last.get(step)
            .and_then(|s| s.parse::<u64>().ok())
            .map(|s| s + 1),
        value(time).zip(value(dt)).map(|(t, dt)| t + dt),
    )
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

/// Joins the rows of the `sweep-k-of-N.csv` files in `dirs` into `out`: every shard 0..N
/// present once, one header for all, no point twice. Returns the number of rows.
fn collect(dirs: &[PathBuf], out: &Path) -> anyhow::Result<usize> {
    let mut shards: BTreeMap<usize, PathBuf> = BTreeMap::new();
    let mut count = None;
    for dir in dirs {
        let entries =
            std::fs::read_dir(dir).with_context(|| format!("listing {}", dir.display()))?;
        for entry in entries {
            let path = entry?.path();
            let Some((k, n)) = path
                .file_name()
                .and_then(|n| n.to_str())
                .and_then(|n| n.strip_prefix("sweep-")?.strip_suffix(".csv"))
                .and_then(|kn| {
                    let (k, n) = kn.split_once("-of-")?;
                    Some((k.parse::<usize>().ok()?, n.parse::<usize>().ok()?))
                })
            else {
                continue;
            };
            if *count.get_or_insert(n) != n {
                bail!(
                    "{} belongs to a study in {n} shards, the others to one in {}",
                    path.display(),
                    count.unwrap_or(n)
                );
            }
            if let Some(other) = shards.insert(k, path.clone()) {
                bail!(
                    "shard {k} is there twice: {} and {}",
                    other.display(),
                    path.display()
                );
            }
        }
    }
    let n = count.context("no sweep-k-of-N.csv in the folders given")?;
    if let Some(k) = (0..n).find(|k| !shards.contains_key(k)) {
        bail!("shard {k} of {n} is missing: run it with --shard {k}/{n}");
    }
    let mut header: Option<csv::StringRecord> = None;
    let mut rows: BTreeMap<usize, Vec<String>> = BTreeMap::new();
    for path in shards.values() {
        let mut reader =
            csv::Reader::from_path(path).with_context(|| format!("reading {}", path.display()))?;
        let h = reader.headers()?.clone();
        if header.get_or_insert_with(|| h.clone()) != &h {
            bail!("{} has other columns than the first shard", path.display());
        }
        for record in reader.records() {
            let record = record.with_context(|| format!("reading {}", path.display()))?;
            let index: usize = record
                .get(0)
                .and_then(|s| s.parse().ok())
                .with_context(|| format!("{}: a row without a point number", path.display()))?;
            if rows
                .insert(index, record.iter().map(String::from).collect())
                .is_some()
            {
                bail!("point {index} is in two shards");
            }
        }
    }
    let mut records = vec![header
        .map(|h| h.iter().map(String::from).collect())
        .unwrap_or_default()];
    let n_rows = rows.len();
    records.extend(rows.into_values());
    write_records(out, &records)?;
    Ok(n_rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vary_lists_split_outside_brackets_and_quotes() {
        let a = parse_vary("grid.resolution=[32,32,1],[64,64,1]").expect("parses");
        assert_eq!(a.values, ["[32,32,1]", "[64,64,1]"]);
        let a = parse_vary("name=\"a,b\",c").expect("parses");
        assert_eq!(a.values, ["\"a,b\"", "c"]);
        assert!(parse_vary("fluid.spacing").is_err());
        assert!(parse_vary("fluid.spacing=0.1,,0.2").is_err());
    }

    #[test]
    fn points_are_the_product_or_the_pairs() {
        let axes = [
            parse_vary("a=1,2").expect("parses"),
            parse_vary("b=x,y,z").expect("parses"),
        ];
        let p = points(&axes, None).expect("product");
        assert_eq!(p.len(), 6);
        assert_eq!(p[0], ["1", "x"]);
        assert_eq!(p[5], ["2", "z"]);
        assert!(points(&axes, Some(&[])).is_err(), "lists of unequal length");
        let zipped = points(&axes[..1], Some(&[])).expect("one axis");
        assert_eq!(zipped, [["1"], ["2"]]);
        // Two keys paired, the product over that pair and a third key.
        let axes = [
            parse_vary("n=32,64").expect("parses"),
            parse_vary("m=x,y").expect("parses"),
            parse_vary("depth=0.2,0.1").expect("parses"),
        ];
        let keys = ["n".to_string(), "depth".to_string()];
        let p = points(&axes, Some(&keys)).expect("group");
        assert_eq!(
            p,
            [
                ["32", "x", "0.2"],
                ["32", "y", "0.2"],
                ["64", "x", "0.1"],
                ["64", "y", "0.1"]
            ]
        );
        assert!(
            points(&axes, Some(&["q".to_string()])).is_err(),
            "not a varied key"
        );
    }
}
