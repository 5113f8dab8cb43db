//! Spectra (`eddy::metrics::spectrum`, `eddy spectrum`): Welch's PSD finds a noisy, unevenly
//! sampled sine's frequency and integrates to its variance; E(k) puts known Fourier modes'
//! energies in their shells; the peak of a real cylinder wake's lift is its shedding frequency
//! from zero crossings; and the command writes its files and names what is wrong.

mod common;

use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;

use eddy::metrics::spectrum::{
    energy_spectrum, resample, welch, welch_series, Mean, ShellOptions, WelchOptions,
};
use eddy::pipeline::{resolve, run_scene, RunOptions};
use eddy::Real;
use ndarray::Array3;

/// A sine of 3.1 Hz and amplitude 1 with uniform noise of ±0.3, sampled at steps that vary by
/// ±30 % around 2 ms (as a CFL step does) for 60 s.
fn noisy_sine() -> (Vec<Real>, Vec<Real>) {
    let mut state: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut uniform = move || {
        // xorshift64*: a fixed, dependency-free sequence in [0, 1).
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        (state.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as Real / (1u64 << 53) as Real
    };
    let (mut t, mut time, mut values) = (0.0, Vec::new(), Vec::new());
    let mut i = 0;
    while t <= 60.0 {
        time.push(t);
        values.push((2.0 * PI * 3.1 * t + 0.7).sin() + 0.6 * (uniform() - 0.5));
        t += 2e-3 * (1.0 + 0.3 * (0.37 * i as Real).sin());
        i += 1;
    }
    (time, values)
}

#[test]
fn a_noisy_unevenly_sampled_sine_peaks_at_its_frequency_and_keeps_its_variance() {
    let (time, values) = noisy_sine();
    let options = WelchOptions::default();
    let psd = welch_series(&time, &values, None, &options).expect("a long series");
    assert!(psd.segments >= 8, "{} segments", psd.segments);
    let peak = psd.peak().expect("a peak");
    let error = peak.frequency / 3.1 - 1.0;
    eprintln!(
        "sine: peak {} Hz ({:+.4} %), {} segments of {}, resolution {} Hz",
        peak.frequency,
        100.0 * error,
        psd.segments,
        psd.segment,
        psd.resolution()
    );
    assert!(error.abs() < 0.005, "{peak:?}");

    // Parseval, the discrete identity of `welch`: the mean of the resampled segments'
    // window-weighted variances, computed here from its definition.
    let (rate, x) = resample(&time, &values, None).expect("increasing times");
    assert_eq!(rate, psd.rate);
    let m = psd.segment;
    let w: Vec<Real> = (0..m)
        .map(|n| 0.5 - 0.5 * (2.0 * PI * n as Real / m as Real).cos())
        .collect();
    let s: Real = w.iter().map(|w| w * w).sum();
    let weighted = (0..psd.segments)
        .map(|k| {
            let seg = &x[k * m / 2..k * m / 2 + m];
            let mean = seg.iter().sum::<Real>() / m as Real;
            let sum: Real = seg
                .iter()
                .zip(&w)
                .map(|(x, w)| (w * (x - mean)).powi(2))
                .sum();
            sum / s
        })
        .sum::<Real>()
        / psd.segments as Real;
    let residual = (psd.integral() - weighted).abs() / weighted;
    // And the plain variance of the resampled series, which a stationary signal's weighted
    // variance estimates: a wrong window normalisation would miss it by a factor.
    let mean = x.iter().sum::<Real>() / x.len() as Real;
    let variance = x.iter().map(|x| (x - mean).powi(2)).sum::<Real>() / x.len() as Real;
    eprintln!(
        "sine: Parseval residual {residual:.2e}; integral {} against variance {variance}",
        psd.integral()
    );
    assert!(residual < 1e-10, "{residual}");
    assert!((psd.integral() / variance - 1.0).abs() < 0.02);

    // The same series given at the mean step's rate is resampled there, and peaks alike.
    let at = welch_series(&time, &values, Some(400.0), &options).expect("a long series");
    assert_eq!(at.rate, 400.0);
    let f = at.peak().expect("a peak").frequency;
    assert!((f / 3.1 - 1.0).abs() < 0.005, "{f}");
}

/// Three velocity components made of sine modes on a periodic 32³ box of side 2 pi, so the
/// shells are 1 rad/m wide and a mode of wavenumber vector kappa lands in shell round(|kappa|).
#[test]
fn known_fourier_modes_land_in_their_shells_with_their_energies() {
    let n = 32;
    let dx = 2.0 * PI / n as Real;
    let grid = |f: &dyn Fn(Real, Real, Real) -> Real| {
        Array3::from_shape_fn([n, n, n], |(i, j, k)| {
            let c = |i: usize| (i as Real + 0.5) * dx;
            f(c(i), c(j), c(k))
        })
    };
    let (a, b, c, d) = (0.8, 0.5, 0.3, 0.2);
    let mean = 1.5;
    // u: |kappa| = 2; v: |(3, 0, 4)| = 5 and |(6, 6, 0)| = 8.49 -> shell 8; w: 9.
    let u = grid(&|_, y, _| mean + a * (2.0 * y).sin());
    let v = grid(&|x, y, z| b * (3.0 * x + 4.0 * z + 0.3).cos() + d * (6.0 * x + 6.0 * y).sin());
    let w = grid(&|x, _, _| c * (9.0 * x).sin());
    // A mode of amplitude A holds ½⟨(A sin)²⟩ = A²/4 of kinetic energy per unit mass.
    let expected = [
        (2, a * a / 4.0),
        (5, b * b / 4.0),
        (8, d * d / 4.0),
        (9, c * c / 4.0),
    ];
    for keep in [false, true] {
        let options = ShellOptions {
            periodic: [true; 3],
            mean: if keep { Mean::Keep } else { Mean::Remove },
            solid: None,
        };
        let e = energy_spectrum([u.view(), v.view(), w.view()], dx, &options).expect("valid");
        assert!((e.dk - 1.0).abs() < 1e-14, "{}", e.dk);
        assert!((e.mean[0] - mean).abs() < 1e-12, "{:?}", e.mean);
        let shell = |s: usize| e.energy[s] * e.dk;
        let mut worst: Real = 0.0;
        for (s, energy) in expected {
            let relative = (shell(s) - energy).abs() / energy;
            worst = worst.max(relative);
            assert!(relative < 1e-10, "shell {s}: {} against {energy}", shell(s));
        }
        let mean_energy = if keep { 0.5 * mean * mean } else { 0.0 };
        assert!((shell(0) - mean_energy).abs() < 1e-10 * mean_energy.max(1.0));
        let total: Real = expected.iter().map(|e| e.1).sum::<Real>() + mean_energy;
        let stray: Real = (0..e.energy.len())
            .filter(|s| *s != 0 && expected.iter().all(|e| e.0 != *s))
            .map(shell)
            .sum();
        assert!(stray < 1e-14 * total, "{stray} outside the modes' shells");
        // Parseval: sum E dk = ½⟨|u'|²⟩, u' the velocity less its mean (or as it is).
        let half_mean_square = 0.5
            * [&u, &v, &w]
                .iter()
                .enumerate()
                .map(|(k, f)| {
                    let shift = if keep || k > 0 { 0.0 } else { mean };
                    f.iter().map(|x| (x - shift).powi(2)).sum::<Real>()
                })
                .sum::<Real>()
            / (n * n * n) as Real;
        let residual = (e.integral() - half_mean_square).abs() / half_mean_square;
        eprintln!(
            "modes (mean {}): worst shell {worst:.2e}, Parseval residual {residual:.2e}",
            if keep { "kept" } else { "removed" }
        );
        assert!(
            residual < 1e-10,
            "{} against {half_mean_square}",
            e.integral()
        );
        assert!((e.integral() - total).abs() < 1e-10 * total);
    }
}

/// The DFG 2D-2 cylinder at 10 cells per diameter in a channel cut to 1.1 m (110 x 41 x 1
/// cells, CFL 1) to 7 s: the wake sheds from about 3.5 s on. Run once for the tests that read
/// it.
fn wake() -> &'static Path {
    static RUN: OnceLock<(tempfile::TempDir, PathBuf)> = OnceLock::new();
    let (_, out) = RUN.get_or_init(|| {
        let dir = tempfile::tempdir().expect("a temporary folder");
        let out = dir.path().join("wake");
        let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/dfg_2d2.toml");
        let options = RunOptions {
            out: Some(out.clone()),
            overrides: [
                "grid.resolution=[110,41,1]",
                "domain.max=[1.1,0.41,0.01]",
                "obstacles.0.position=[0.2,0.2,0.005]",
                "time.end=7.0",
                "time.cfl=1.0",
            ]
            .map(String::from)
            .to_vec(),
            progress: false,
            ..RunOptions::default()
        };
        let resolved = resolve(&scene, &options).expect("the scene loads");
        run_scene(&resolved, &options).expect("the run finishes");
        (dir, out)
    });
    out
}

/// When the wake is established: the lift's start-up has died out by then.
const SHEDDING_FROM: Real = 4.0;

#[test]
fn a_cylinder_wake_peaks_at_its_shedding_frequency() {
    let probes = eddy::io::plot::RunSeries::read_file(wake(), "probes.csv").expect("probes");
    let time = probes.column("time").expect("time");
    let lift = probes.column("cylinder_fy_pressure").expect("the lift");
    let from = time.partition_point(|&t| t < SHEDDING_FROM);
    let (t, l) = (&time[from..], &lift[from..]);
    let period = eddy::bench::dfg::period(t, l).expect("the lift oscillates");
    let crossings = 1.0 / period;
    // Segments of 256 steps (about 1.3 s, three and a half periods): the default's 128 would
    // hold under two periods, where the window's leakage from the negative frequency and the
    // removed mean pull the peak by several per cent.
    let options = WelchOptions {
        segment: Some(256),
        pad: 1,
    };
    let psd = welch_series(t, l, None, &options).expect("enough samples");
    let peak = psd.peak().expect("a peak").frequency;
    let error = peak / crossings - 1.0;
    let strouhal = peak * 0.1 / 1.0;
    eprintln!(
        "wake: Welch peak {peak} Hz, zero crossings {crossings} Hz ({:+.3} %), St {strouhal}, \
         {} segments of {} at {} Hz",
        100.0 * error,
        psd.segments,
        psd.segment,
        psd.rate
    );
    assert!(psd.segments >= 3, "{} segments", psd.segments);
    assert!(error.abs() < 0.01, "{peak} against {crossings}");
    // A Kármán street: D f / U near 0.3 (this coarse, short channel sheds somewhat slower
    // than the benchmark's 0.295–0.305).
    assert!((0.25..0.32).contains(&strouhal), "{strouhal}");
}

fn eddy(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_eddy"))
        .args(args)
        .output()
        .expect("eddy runs")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// The header and rows of a CSV of two numbers a row.
fn read_pairs(path: &Path) -> (String, Vec<(Real, Real)>) {
    let csv = std::fs::read_to_string(path).expect("the CSV");
    let mut lines = csv.lines();
    let header = lines.next().expect("a header").to_owned();
    let rows = lines
        .map(|l| {
            let (a, b) = l.split_once(',').expect("two columns");
            (a.parse().expect("a number"), b.parse().expect("a number"))
        })
        .collect();
    (header, rows)
}

fn is_png(path: &Path) -> bool {
    std::fs::read(path).is_ok_and(|b| b.starts_with(b"\x89PNG\r\n\x1a\n"))
}

#[test]
fn the_command_writes_a_probe_spectrum_and_names_what_is_wrong() {
    let run = wake();
    let run_arg = run.to_str().expect("a UTF-8 path");
    let _guard = common::hdf5_or_child();
    let from = SHEDDING_FROM.to_string();
    let ok = eddy(&[
        "spectrum",
        run_arg,
        "--probe",
        "cylinder",
        "--component",
        "fy_pressure",
        "--from",
        &from,
        "--segment",
        "256",
        "--length",
        "0.1",
        "--speed",
        "1.0",
    ]);
    let stdout = text(&ok.stdout);
    assert!(ok.status.success(), "{}{}", stdout, text(&ok.stderr));
    let (header, rows) = read_pairs(&run.join("spectrum_cylinder_fy_pressure.csv"));
    assert_eq!(header, "frequency,psd");
    assert_eq!(rows.len(), 129, "256 samples a segment: bins 0 to 128");
    assert!(is_png(&run.join("spectrum_cylinder_fy_pressure.png")));
    // The printed peak is the library's, and lies on the CSV's largest bin.
    let printed = |label: &str| -> Real {
        let line = stdout.lines().find(|l| l.starts_with(label)).expect(label);
        let value = line[label.len()..]
            .split_whitespace()
            .next()
            .expect("a value");
        value.parse().expect("a number")
    };
    let peak = printed("peak frequency:");
    let top = rows
        .iter()
        .skip(1)
        .fold((0.0, 0.0), |b, &r| if r.1 > b.1 { r } else { b });
    let df = rows[1].0;
    assert!(
        (peak - top.0).abs() <= 0.5 * df,
        "{peak} against bin {}",
        top.0
    );
    assert!((printed("Strouhal number:") - 0.1 * peak).abs() < 1e-5 * peak);

    // A metrics column, named as `eddy compare` names it, written where --out says.
    let prefix = run.join("energy");
    let energy = eddy(&[
        "spectrum",
        run_arg,
        "--column",
        "metrics:kinetic_energy",
        "--out",
        prefix.to_str().expect("UTF-8"),
    ]);
    assert!(energy.status.success(), "{}", text(&energy.stderr));
    assert!(run.join("energy.csv").is_file() && is_png(&run.join("energy.png")));

    let fails = |args: &[&str], needles: &[&str]| {
        let out = eddy(args);
        let stderr = text(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(!stderr.contains("panicked"), "{stderr}");
        for needle in needles {
            assert!(
                stderr.contains(needle),
                "{args:?}: no `{needle}` in {stderr}"
            );
        }
    };
    fails(
        &["spectrum", run_arg, "--probe", "behind"],
        &["no column `behind_vx`", "cylinder_fy_pressure", "front_p"],
    );
    fails(
        &["spectrum", run_arg, "--column", "metrics:nothing"],
        &["metrics.csv has no column `nothing`", "kinetic_energy"],
    );
    fails(
        &["spectrum", run_arg, "--probe", "back", "--from", "6.99"],
        &["samples, a spectrum needs at least"],
    );
    fails(
        &["spectrum", "/no/such/run", "--probe", "back"],
        &["/no/such/run: no such run folder"],
    );
    fails(
        &["spectrum", run_arg, "--frame", "0"],
        &["no grid frames", "output.hdf5 = true"],
    );
}

/// A Taylor–Green frame, u = (sin x cos y, -cos x sin y) on the periodic [0, 2 pi]², holds all
/// its energy in the wavenumbers (±1, ±1): the shell round(√2) = 1.
#[test]
fn the_command_writes_the_energy_spectrum_of_a_grid_frame() {
    let dir = tempfile::tempdir().expect("a temporary folder");
    let out = dir.path().join("tg");
    let _guard = common::hdf5_or_child();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/taylor_green.toml");
    let options = RunOptions {
        out: Some(out.clone()),
        overrides: [
            "output.hdf5=true",
            "output.vtk=false",
            "output.interval=0.01",
        ]
        .map(String::from)
        .to_vec(),
        steps: Some(2),
        progress: false,
        ..RunOptions::default()
    };
    run_scene(&resolve(&scene, &options).expect("loads"), &options).expect("runs");
    let run = out.to_str().expect("UTF-8");
    let ok = eddy(&["spectrum", run, "--frame", "0"]);
    assert!(ok.status.success(), "{}", text(&ok.stderr));
    let (header, rows) = read_pairs(&out.join("spectrum_frame_000000.csv"));
    assert_eq!(header, "k,E");
    assert!(is_png(&out.join("spectrum_frame_000000.png")));
    let total: Real = rows.iter().map(|r| r.1).sum();
    assert_eq!(rows[1].0, 1.0, "shells 1 rad/m wide");
    assert!(rows[1].1 > 0.999 * total, "{rows:?}");
    // ½⟨|u|²⟩ of the Taylor–Green field is 1/4, less what the cell averages lose.
    assert!((total - 0.25).abs() < 0.01, "{total}");
    assert!(
        text(&ok.stdout).contains("periodic"),
        "{}",
        text(&ok.stdout)
    );
    let bad = eddy(&["spectrum", run, "--frame", "9"]);
    let stderr = text(&bad.stderr);
    assert!(!bad.status.success());
    assert!(
        stderr.contains("frame 9 asked for, the file has 3 frame(s)"),
        "{stderr}"
    );
}

/// Welch's segment length and padding are refused when they cannot work, with the numbers.
#[test]
fn a_series_too_short_for_its_segment_is_refused() {
    let x = vec![0.0; 100];
    let options = WelchOptions {
        segment: Some(128),
        pad: 1,
    };
    let error = welch(&x, 10.0, &options).unwrap_err().to_string();
    assert_eq!(error, "100 samples, a spectrum needs at least 128");
}
