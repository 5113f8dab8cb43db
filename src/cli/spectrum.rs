//! `eddy spectrum`: the power spectral density of one column of a run's probes.csv or
//! metrics.csv (Welch), or the energy spectrum E(k) of one of its grid frames, as a CSV and a
//! log-log figure, with the peak printed.

use std::ffi::OsString;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context};
use clap::ArgGroup;
use eddy::grid::GridSide;
use eddy::io::plot::RunSeries;
use eddy::io::spectrum_plot::{spectrum_figure, SpectrumFigure};
use eddy::metrics::spectrum::{self, Mean, ShellOptions, WelchOptions};
use eddy::Real;

/// Options of `eddy spectrum`.
#[derive(Debug, Clone, clap::Args)]
#[command(group(ArgGroup::new("what").required(true).args(["probe", "column", "frame"])))]
pub struct SpectrumArgs {
    /// The run folder (`eddy run --out`).
    pub run: PathBuf,
    /// A probe of the run's probes.csv, its column chosen by --component.
    #[arg(long)]
    pub probe: Option<String>,
    /// Of --probe: u, v, w or p (a point probe's NAME_vx, NAME_vy, NAME_vz, NAME_p), or the
    /// rest of any of its columns' names, e.g. fy_pressure of a force probe [default: u].
    #[arg(long, requires = "probe")]
    pub component: Option<String>,
    /// Any column, named as `eddy compare` names it: probes:COLUMN or metrics:COLUMN, e.g.
    /// probes:cylinder_fy_pressure or metrics:kinetic_energy.
    #[arg(long, value_name = "FILE:COLUMN")]
    pub column: Option<String>,
    /// The energy spectrum E(k) of grid frame N (counting from 0) of the run's HDF5 frames.
    #[arg(long, value_name = "N")]
    pub frame: Option<usize>,
    /// Only the samples from this time on, s: leaves out a start-up transient.
    #[arg(long, value_name = "SECONDS", conflicts_with = "frame")]
    pub from: Option<Real>,
    /// Samples per Welch segment [default: the largest power of two that gives at least 8
    /// half-overlapping segments].
    #[arg(long, conflicts_with = "frame")]
    pub segment: Option<usize>,
    /// The uniform rate the series is resampled to, Hz [default: one over the median step].
    #[arg(long, value_name = "HZ", conflicts_with = "frame")]
    pub rate: Option<Real>,
    /// Zero-padding factor of each segment's transform: a finer grid of frequencies for the
    /// same density, and a peak interpolated with less bias.
    #[arg(long, default_value_t = 1, conflicts_with = "frame")]
    pub pad: usize,
    /// Keep the mean flow in E(k) (its energy at k = 0) instead of removing it.
    #[arg(long, requires = "frame")]
    pub keep_mean: bool,
    /// A length, m: with --speed, the Strouhal number f L / U of the peak is printed.
    #[arg(long, requires = "speed", conflicts_with = "frame")]
    pub length: Option<Real>,
    /// A speed, m/s, for the Strouhal number (with --length).
    #[arg(long, requires = "length")]
    pub speed: Option<Real>,
    /// What to write: PREFIX.csv and PREFIX.png [default: RUN/spectrum_COLUMN, or
    /// RUN/spectrum_frame_NNNNNN].
    #[arg(long, value_name = "PREFIX")]
    pub out: Option<PathBuf>,
}

/// Runs `eddy spectrum`.
pub fn run(args: &SpectrumArgs) -> anyhow::Result<()> {
    let run = &args.run;
    if !run.is_dir() {
        bail!("{}: no such run folder", run.display());
    }
    match args.frame {
        Some(frame) => field_spectrum(args, frame),
        None => series_spectrum(args),
    }
}

/// The file (`probes` or `metrics`) and column that --probe or --column names.
fn chosen_column(args: &SpectrumArgs) -> anyhow::Result<(&'static str, String)> {
    if let Some(probe) = &args.probe {
        let suffix = match args.component.as_deref().unwrap_or("u") {
            "u" => "vx",
            "v" => "vy",
            "w" => "vz",
            other => other,
        };
        return Ok(("probes", format!("{probe}_{suffix}")));
    }
    let column = args.column.as_deref().unwrap_or_default();
    match column.split_once(':') {
        Some(("probes", name)) => Ok(("probes", name.to_owned())),
        Some(("metrics", name)) => Ok(("metrics", name.to_owned())),
        _ => bail!("--column {column}: expected metrics:COLUMN or probes:COLUMN"),
    }
}

/// Welch's PSD of one column against the run's `time`.
fn series_spectrum(args: &SpectrumArgs) -> anyhow::Result<()> {
    let (file, name) = chosen_column(args)?;
    let csv = format!("{file}.csv");
    if !args.run.join(&csv).is_file() {
        bail!("{}: no {csv} in this run folder", args.run.display());
    }
    let series = RunSeries::read_file(&args.run, &csv)?;
    let Some(values) = series.column(&name) else {
        let what = if args.probe.is_some() {
            " (--probe NAME --component C reads the column NAME_vx, NAME_vy, NAME_vz or \
             NAME_p for C = u, v, w or p, else NAME_C)"
        } else {
            ""
        };
        bail!(
            "{}: {csv} has no column `{name}`{what}; its columns are: {}",
            args.run.display(),
            series.columns().join(", ")
        );
    };
    let Some(time) = series.column("time") else {
        bail!("{}: {csv} has no `time` column", args.run.display());
    };
    if time.len() != values.len() {
        bail!(
            "{}: {csv} has {} times for {} values of `{name}` (a short row?)",
            args.run.display(),
            time.len(),
            values.len()
        );
    }
    let from = args.from.unwrap_or(Real::NEG_INFINITY);
    let start = time.partition_point(|&t| t < from);
    let (time, values) = (&time[start..], &values[start..]);
    let options = WelchOptions {
        segment: args.segment,
        pad: args.pad,
    };
    let psd = spectrum::welch_series(time, values, args.rate, &options).with_context(|| {
        let since = args
            .from
            .map_or(String::new(), |t| format!(" from t = {t} s"));
        format!("the spectrum of `{name}` ({csv}{since})")
    })?;
    let peak = psd.peak();
    let prefix = prefix(args, &format!("spectrum_{name}"));
    let csv_out = with_extension(&prefix, "csv");
    write_csv(
        &csv_out,
        "frequency,psd",
        psd.frequency.iter().zip(&psd.density),
    )?;
    let curve: Vec<(Real, Real)> = psd
        .frequency
        .iter()
        .copied()
        .zip(psd.density.iter().copied())
        .collect();
    let padded = if args.pad > 1 {
        format!(", padded x{}", args.pad)
    } else {
        String::new()
    };
    let title = format!(
        "PSD of {name}: {} segments of {} samples at {} Hz{padded}",
        psd.segments,
        psd.segment,
        short(psd.rate)
    );
    let figure_out = with_extension(&prefix, "png");
    spectrum_figure(
        &figure_out,
        &SpectrumFigure {
            title: &title,
            x_label: "frequency (Hz)",
            y_label: "PSD (unit^2/Hz)",
            label: &name,
            curve: &curve,
            mark: peak.map(|p| (p.frequency, format!("peak {} Hz", short(p.frequency)))),
            guide: None,
        },
    )?;
    eprintln!(
        "eddy: wrote {} and {}",
        csv_out.display(),
        figure_out.display()
    );
    println!(
        "{name}: {} rows from t = {} to {} s, resampled at {} Hz; {} segments of {}, \
         resolution {} Hz; variance {}",
        time.len(),
        short(time[0]),
        short(time[time.len() - 1]),
        short(psd.rate),
        psd.segments,
        psd.segment,
        short(psd.resolution()),
        short(psd.integral())
    );
    let Some(peak) = peak else {
        println!("no peak: the signal is constant");
        return Ok(());
    };
    // The peak's bin is about the periods a segment holds; with few, the window's leakage
    // from the negative frequency and the removed mean pull it.
    let periods = peak.bin as Real / args.pad as Real;
    if periods < 3.0 {
        eprintln!(
            "eddy: warning: a segment of {} samples holds about {} periods of the peak, whose \
             frequency may then be off by a few per cent: a longer --segment holds more",
            psd.segment,
            short(periods)
        );
    }
    println!(
        "peak frequency: {} Hz (period {} s)",
        short(peak.frequency),
        short(1.0 / peak.frequency)
    );
    if let (Some(l), Some(u)) = (args.length, args.speed) {
        println!(
            "Strouhal number: {} (f L / U with L = {l} m, U = {u} m/s)",
            short(peak.frequency * l / u)
        );
    }
    Ok(())
}

/// E(k) of grid frame `frame`, the periodic axes read from the run's scene.
fn field_spectrum(args: &SpectrumArgs, frame: usize) -> anyhow::Result<()> {
    let run = &args.run;
    let Some(file) = ["frames.h5", "grid_frames.h5"]
        .iter()
        .map(|f| run.join(f))
        .find(|p| p.is_file())
    else {
        let vtk = std::fs::read_dir(run)
            .with_context(|| format!("listing {}", run.display()))?
            .filter_map(|e| e.ok())
            .any(|e| {
                let name = e.file_name().to_string_lossy().into_owned();
                name.starts_with("grid_") && name.ends_with(".vti")
            });
        let has = if vtk {
            "only VTK grid frames (grid_NNNNNN.vti), which eddy spectrum does not read"
        } else {
            "no grid frames"
        };
        bail!(
            "{}: {has}; E(k) reads the HDF5 grid frames (frames.h5): run the scene with \
             output.hdf5 = true, e.g. `eddy run SCENE --set output.hdf5=true`",
            run.display()
        );
    };
    let scene = eddy::scene::load(&run.join("scene.toml"), &[])
        .with_context(|| format!("{}: reading the run's scene", run.display()))?;
    let Some(grid) = scene.grid.as_ref() else {
        bail!("{}: the run's scene has no [grid]", run.display());
    };
    let periodic = grid
        .boundary
        .sides()
        .map(|[lo, hi]| lo == GridSide::Periodic && hi == GridSide::Periodic);
    let stored = eddy::io::read_velocity(&file, Some(frame))?;
    let solid = eddy::io::read_solid(&file, frame)?;
    let options = ShellOptions {
        periodic,
        mean: if args.keep_mean {
            Mean::Keep
        } else {
            Mean::Remove
        },
        solid: solid.as_ref().map(|s| s.view()),
    };
    let [u, v, w] = &stored.velocity;
    let e = spectrum::energy_spectrum([u.view(), v.view(), w.view()], stored.spacing, &options)
        .with_context(|| format!("{}: E(k) of frame {frame}", file.display()))?;
    let prefix = prefix(args, &format!("spectrum_frame_{frame:06}"));
    let csv_out = with_extension(&prefix, "csv");
    write_csv(&csv_out, "k,E", e.k.iter().zip(&e.energy))?;
    let names = ["x", "y", "z"];
    let windowed: Vec<&str> = (0..3)
        .filter(|&a| e.windowed[a])
        .map(|a| names[a])
        .collect();
    let windows = if windowed.is_empty() {
        "periodic".to_owned()
    } else {
        format!("Hann window along {}", windowed.join(", "))
    };
    let title = format!(
        "E(k) of frame {} at t = {} s ({windows})",
        stored.frame,
        short(stored.time)
    );
    let curve: Vec<(Real, Real)> = e.k.iter().copied().zip(e.energy.iter().copied()).collect();
    let figure_out = with_extension(&prefix, "png");
    spectrum_figure(
        &figure_out,
        &SpectrumFigure {
            title: &title,
            x_label: "k (rad/m)",
            y_label: "E(k) (m^3/s^2)",
            label: "E(k)",
            curve: &curve,
            mark: Some((
                std::f64::consts::PI / stored.spacing,
                "pi/dx: shells beyond it are partly filled".into(),
            )),
            guide: Some((-5.0 / 3.0, "k^(-5/3)".into())),
        },
    )?;
    eprintln!(
        "eddy: wrote {} and {}",
        csv_out.display(),
        figure_out.display()
    );
    let [nx, ny, nz] = stored.dims;
    println!(
        "frame {} at t = {} s: {nx} x {ny} x {nz} cells, {} shells of dk = {} rad/m ({windows}); \
         mean velocity ({}, {}, {}) m/s {}; sum E dk = {} m^2/s^2",
        stored.frame,
        short(stored.time),
        e.k.len(),
        short(e.dk),
        short(e.mean[0]),
        short(e.mean[1]),
        short(e.mean[2]),
        if args.keep_mean { "kept" } else { "removed" },
        short(e.integral())
    );
    let top = (1..e.energy.len()).max_by(|&a, &b| e.energy[a].total_cmp(&e.energy[b]));
    if let Some(n) = top.filter(|&n| e.energy[n] > 0.0) {
        println!(
            "peak wavenumber: {} rad/m (wavelength {} m)",
            short(e.k[n]),
            short(2.0 * std::f64::consts::PI / e.k[n])
        );
    }
    Ok(())
}

/// --out, or `RUN/default`.
fn prefix(args: &SpectrumArgs, default: &str) -> PathBuf {
    args.out.clone().unwrap_or_else(|| args.run.join(default))
}

/// `prefix` with `.ext` appended (a prefix may hold dots of its own).
fn with_extension(prefix: &Path, ext: &str) -> PathBuf {
    let mut name = OsString::from(prefix.as_os_str());
    name.push(".");
    name.push(ext);
    PathBuf::from(name)
}

/// Writes `header` and one row per pair (the value in scientific notation: densities span
/// many decades), atomically.
fn write_csv<'a>(
    path: &Path,
    header: &str,
    rows: impl Iterator<Item = (&'a Real, &'a Real)>,
) -> anyhow::Result<()> {
    let rows: Vec<(Real, Real)> = rows.map(|(a, b)| (*a, *b)).collect();
    eddy::io::write_atomic(path, |w| {
        writeln!(w, "{header}")?;
        for (a, b) in &rows {
            writeln!(w, "{a},{b:e}")?;
        }
        Ok(())
    })?;
    Ok(())
}

/// `v` to 6 significant digits, for the printed lines and titles.
fn short(v: Real) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    if !(1e-3..1e6).contains(&v.abs()) {
        return format!("{v:.5e}");
    }
    let decimals = (5 - v.abs().log10().floor() as i32).max(0) as usize;
    let s = format!("{v:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_owned()
    } else {
        s
    }
}
