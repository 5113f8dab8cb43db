//! Figures for `eddy compare`, `eddy plot-sweep` and `eddy bench-abl`: energy and vorticity
//! against time for several runs in one figure (the comparison every refinement paper shows:
//! Liu et al. Fig. 7, Wang et al. Fig. 11, Ye et al. Fig. 10), run time against error, and a
//! study's curves or stability map. A figure is a PNG, or an SVG (vector, for a paper) when
//! the output's name ends in `.svg`: every figure is drawn by one function generic over the
//! plotters backend.
//!
//! PNG text is drawn with a bundled font (DejaVu Sans Mono, `assets/fonts`, free licence beside
//! it) through ab_glyph, so plotting needs no system fonts or fontconfig; SVG text names the
//! font family and is drawn by the viewer.

use super::IoError;
use crate::Real;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::{register_font, FontStyle};
use std::path::{Path, PathBuf};
use std::sync::Once;

/// The columns of one run's `metrics.csv` (or another CSV of numbers with a `time` column).
#[derive(Debug, Clone)]
pub struct RunSeries {
    /// Legend label (the run folder's name).
    pub label: String,
    header: Vec<String>,
    rows: Vec<Vec<Real>>,
}

impl RunSeries {
    /// Reads `DIR/metrics.csv`.
    pub fn read(dir: &Path) -> Result<Self, IoError> {
        Self::read_file(dir, "metrics.csv")
    }

    /// Reads the run's `DIR/FILE` (e.g. `probes.csv`), labelled by the folder's name.
    pub fn read_file(dir: &Path, file: &str) -> Result<Self, IoError> {
        let mut series = Self::read_csv(&dir.join(file))?;
        series.label = dir
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| dir.display().to_string());
        Ok(series)
    }

    /// Reads the CSV `path`, labelled by its file stem; lines starting with `#` are comments
    /// (a published table's source, as in `scenes/reference/`).
    pub fn read_csv(path: &Path) -> Result<Self, IoError> {
        let path = path.to_path_buf();
        let text = std::fs::read_to_string(&path).map_err(|e| IoError::io(&path, "reading", e))?;
        let mut lines = text.lines().filter(|l| !l.starts_with('#'));
        let header: Vec<String> = lines
            .next()
            .ok_or_else(|| IoError::invalid(&path, "empty file, no header"))?
            .split(',')
            .map(|c| c.trim().trim_matches('"').to_owned())
            .collect();
        let rows = lines
            .enumerate()
            .filter(|(_, l)| !l.trim().is_empty())
            .map(|(n, line)| {
                line.split(',')
                    .map(|c| c.trim().parse::<Real>())
                    .collect::<Result<Vec<_>, _>>()
                    .map_err(|e| IoError::invalid(&path, format!("line {}: {e}", n + 2)))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let label = path
            .file_stem()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| path.display().to_string());
        Ok(Self {
            label,
            header,
            rows,
        })
    }

    /// The columns' names, in the file's order.
    pub fn columns(&self) -> &[String] {
        &self.header
    }

    /// The column of that name, if the run wrote it.
    pub fn column(&self, name: &str) -> Option<Vec<Real>> {
        let k = self.header.iter().position(|h| h == name)?;
        Some(self.rows.iter().filter_map(|r| r.get(k).copied()).collect())
    }

    /// A quantity against time: the sum of the named columns (those present), None when the
    /// run has no time column or none of them. Points whose time or value is not finite are
    /// left out; the second value counts them.
    fn curve<C: AsRef<str>>(&self, columns: &[C]) -> Option<(Vec<(Real, Real)>, usize)> {
        let time = self.column("time")?;
        let parts: Vec<Vec<Real>> = columns
            .iter()
            .filter_map(|c| self.column(c.as_ref()))
            .collect();
        if parts.is_empty() {
            return None;
        }
        let all: Vec<(Real, Real)> = time
            .iter()
            .enumerate()
            .map(|(i, &t)| (t, parts.iter().fold(0.0, |s, p| s + p[i])))
            .collect();
        let finite: Vec<_> = all
            .iter()
            .copied()
            .filter(|(t, y)| t.is_finite() && y.is_finite())
            .collect();
        let skipped = all.len() - finite.len();
        Some((finite, skipped))
    }
}

/// The panels of the comparison: title and the metrics.csv columns summed into it. A panel
/// no run has a column for is left out (the vortex panels belong to boundary-layer runs).
const PANELS: [(&str, &[&str]); 5] = [
    (
        "kinetic energy, linear + rotational (J)",
        &["kinetic_energy", "rotational_energy"],
    ),
    ("total energy (J)", &["total_energy"]),
    ("mean vorticity magnitude (1/s)", &["vorticity_mean"]),
    ("vortex particles", &["vortex_particles"]),
    ("vortex kernel energy (m^5/s^2)", &["vortex_energy"]),
];

fn register_bundled_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The font is compiled in; a failure here would be a corrupt asset, caught by the tests.
        let _ = register_font(
            "sans-serif",
            FontStyle::Normal,
            include_bytes!("../../assets/fonts/DejaVuSansMono.ttf"),
        );
    });
}

/// Draws energy and vorticity against time for `runs` into the PNG or SVG `out` (written under
/// a temporary name and renamed when complete). Returns how many points were left out for a
/// time or value that is not finite; the axes span the finite ones.
pub fn compare(runs: &[RunSeries], out: &Path) -> Result<usize, IoError> {
    let panels: Vec<(&str, &[&str])> = PANELS
        .iter()
        .copied()
        .filter(|(_, columns)| runs.iter().any(|r| r.curve(columns).is_some()))
        .collect();
    let panels = if panels.is_empty() {
        vec![PANELS[0]]
    } else {
        panels
    };
    draw_compare(runs, &panels, None, out)
}

/// Draws one column against time for `runs` (e.g. a front probe of their `probes.csv`), with
/// the rows of a published `table` as markers when given (e.g. Martin & Moyce's surge front);
/// otherwise as [`compare`].
pub fn compare_column(
    runs: &[RunSeries],
    column: &str,
    table: Option<&RunSeries>,
    out: &Path,
) -> Result<usize, IoError> {
    draw_compare(runs, &[(column, &[column])], table, out)
}

fn draw_compare(
    runs: &[RunSeries],
    panels: &[(&str, &[&str])],
    table: Option<&RunSeries>,
    out: &Path,
) -> Result<usize, IoError> {
    if runs.is_empty() {
        return Err(IoError::invalid(out, "no runs to compare"));
    }
    let height = 400 * panels.len() as u32;
    write_figure(
        out,
        (1200, height),
        Compare {
            runs,
            panels,
            table,
        },
    )
}

/// The figure of [`compare`] and [`compare_column`]: a panel per (title, summed columns), a
/// line per run, the table's points as markers.
struct Compare<'a> {
    runs: &'a [RunSeries],
    panels: &'a [(&'a str, &'a [&'a str])],
    table: Option<&'a RunSeries>,
}

impl Figure for Compare<'_> {
    type Output = usize;

    fn draw<DB: DrawingBackend>(self, root: &Canvas<DB>, out: &Path) -> Result<usize, IoError> {
        let Self {
            runs,
            panels,
            table,
        } = self;
        let fail = |e: &dyn std::fmt::Display| IoError::invalid(out, format!("plotting: {e}"));
        let areas = root.split_evenly((panels.len(), 1));
        let mut skipped = 0;
        for (area, &(title, columns)) in areas.iter().zip(panels) {
            let curves: Vec<(usize, Vec<(Real, Real)>)> = runs
                .iter()
                .enumerate()
                .filter_map(|(k, r)| r.curve(columns).map(|c| (k, c)))
                .map(|(k, (c, left_out))| {
                    skipped += left_out;
                    (k, c)
                })
                .collect();
            let marks = table
                .and_then(|t| t.curve(columns))
                .map(|(c, _)| c)
                .unwrap_or_default();
            let points = || curves.iter().flat_map(|(_, c)| c.iter()).chain(&marks);
            let (t0, t1) =
                points().fold((Real::MAX, Real::MIN), |(a, b), p| (a.min(p.0), b.max(p.0)));
            let (y0, y1) =
                points().fold((Real::MAX, Real::MIN), |(a, b), p| (a.min(p.1), b.max(p.1)));
            if curves.is_empty() || t1.partial_cmp(&t0) != Some(std::cmp::Ordering::Greater) {
                area.titled(&format!("{title}: no data"), ("sans-serif", 20))
                    .map_err(|e| fail(&e))?;
                continue;
            }
            let pad = 0.05 * (y1 - y0).max(1e-12 * y1.abs().max(1.0));
            // A range wider than f64 holds (values near +-1e308) has no axis to draw on.
            if !((y1 + pad) - (y0 - pad)).is_finite() || !(t1 - t0).is_finite() {
                area.titled(
                    &format!("{title}: values span more than a float can hold"),
                    ("sans-serif", 20),
                )
                .map_err(|e| fail(&e))?;
                continue;
            }
            let mut chart = ChartBuilder::on(area)
                .caption(title, ("sans-serif", 20))
                .margin(12)
                .x_label_area_size(36)
                .y_label_area_size(80)
                .build_cartesian_2d(t0..t1, (y0 - pad)..(y1 + pad))
                .map_err(|e| fail(&e))?;
            chart
                .configure_mesh()
                .x_desc("time (s)")
                .label_style(("sans-serif", 14))
                .draw()
                .map_err(|e| fail(&e))?;
            for (k, curve) in &curves {
                line(&mut chart, *k, &runs[*k].label, curve.iter().copied())
                    .map_err(|e| fail(&e))?;
            }
            if let (Some(table), false) = (table, marks.is_empty()) {
                chart
                    .draw_series(
                        marks
                            .iter()
                            .map(|&p| Circle::new(p, 5, BLACK.stroke_width(2))),
                    )
                    .map_err(|e| fail(&e))?
                    .label(&table.label)
                    .legend(|(x, y)| Circle::new((x + 10, y), 5, BLACK.stroke_width(2)));
            }
            legend(&mut chart, points().copied()).map_err(|e| fail(&e))?;
        }
        Ok(skipped)
    }
}

/// The whole drawing area of a figure on backend `DB`.
pub(crate) type Canvas<DB> = DrawingArea<DB, Shift>;

/// A chart with linear axes, as `compare` and the profile panel draw them.
type LinearChart<'a, DB> = ChartContext<
    'a,
    DB,
    Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
>;

/// A figure that draws itself on any backend ([`write_figure`] picks PNG or SVG).
pub(crate) trait Figure {
    type Output;
    /// Draws onto the white `root`; `out` names the file in errors.
    fn draw<DB: DrawingBackend>(
        self,
        root: &Canvas<DB>,
        out: &Path,
    ) -> Result<Self::Output, IoError>;
}

/// Draws curve `k` of a figure in the `k`-th palette colour, with its legend entry.
fn line<DB: DrawingBackend>(
    chart: &mut LinearChart<'_, DB>,
    k: usize,
    label: &str,
    points: impl IntoIterator<Item = (Real, Real)>,
) -> Result<(), String> {
    let color = Palette99::pick(k).to_rgba();
    chart
        .draw_series(LineSeries::new(points, color.stroke_width(2)))
        .map_err(|e| e.to_string())?
        .label(label)
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
    Ok(())
}

/// The legend box every panel of eddy's figures draws, in the corner of the plot whose
/// 40 % x 40 % box holds the fewest of the panel's `data` points (upper right on a tie), so it
/// sits off the data.
pub(crate) fn legend<'a, DB, CT>(
    chart: &mut ChartContext<'a, DB, CT>,
    data: impl IntoIterator<Item = CT::From>,
) -> Result<(), String>
where
    DB: DrawingBackend + 'a,
    CT: plotters::coord::CoordTranslate,
{
    let (px, py) = chart.plotting_area().get_pixel_range();
    let fraction =
        |v: i32, r: &std::ops::Range<i32>| (v - r.start) as Real / (r.end - r.start).max(1) as Real;
    // Pixel rows grow downwards: a small y fraction is the top of the plot.
    let mut count = [0usize; 4];
    for p in data {
        let (x, y) = chart.as_coord_spec().translate(&p);
        let (fx, fy) = (fraction(x, &px), fraction(y, &py));
        let column = if fx < 0.4 {
            Some(0)
        } else {
            (fx > 0.6).then_some(1)
        };
        let row = if fy < 0.4 {
            Some(0)
        } else {
            (fy > 0.6).then_some(2)
        };
        if let (Some(c), Some(r)) = (column, row) {
            count[r + c] += 1;
        }
    }
    use SeriesLabelPosition::{LowerLeft, LowerRight, UpperLeft, UpperRight};
    let corner = [
        (1, UpperRight),
        (0, UpperLeft),
        (3, LowerRight),
        (2, LowerLeft),
    ]
    .into_iter()
    .min_by_key(|&(k, _)| count[k])
    .map_or(UpperRight, |(_, c)| c);
    chart
        .configure_series_labels()
        .position(corner)
        .label_font(("sans-serif", 14))
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(|e| e.to_string())
}

/// Draws `figure` into a white image of `size` pixels: an SVG when `out` ends in `.svg`, else a
/// bitmap in the format its extension names (PNG for eddy's figures, with the bundled font).
/// It is drawn under a temporary name and renamed to `out` when complete, so `out` is never
/// half drawn.
pub(crate) fn write_figure<F: Figure>(
    out: &Path,
    size: (u32, u32),
    figure: F,
) -> Result<F::Output, IoError> {
    register_bundled_font();
    let name = out
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "plot.png".into());
    let ext = out
        .extension()
        .map(|e| e.to_string_lossy().to_lowercase())
        .unwrap_or_else(|| "png".into());
    let tmp: PathBuf = out.with_file_name(format!(".{name}.tmp.{ext}"));
    let result = if ext == "svg" {
        draw_on(SVGBackend::new(&tmp, size).into_drawing_area(), figure, out)
    } else {
        draw_on(
            BitMapBackend::new(&tmp, size).into_drawing_area(),
            figure,
            out,
        )
    };
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    let result = result?;
    std::fs::rename(&tmp, out).map_err(|e| IoError::io(out, "renaming the finished plot to", e))?;
    Ok(result)
}

/// Draws `figure` on white into `root` and presents it; `out` names the figure in errors.
fn draw_on<DB: DrawingBackend, F: Figure>(
    root: Canvas<DB>,
    figure: F,
    out: &Path,
) -> Result<F::Output, IoError> {
    let fail = |e: &dyn std::fmt::Display| IoError::invalid(out, format!("plotting: {e}"));
    root.fill(&WHITE).map_err(|e| fail(&e))?;
    let result = figure.draw(&root, out)?;
    root.present().map_err(|e| fail(&e))?;
    Ok(result)
}

/// Draws `figure` as [`write_figure`] draws a bitmap, into memory: RGB bytes, row by row, of
/// `size` pixels (an animation's frame; `out` names it in errors).
pub(crate) fn draw_pixels<F: Figure>(
    out: &Path,
    size: (u32, u32),
    figure: F,
) -> Result<(Vec<u8>, F::Output), IoError> {
    register_bundled_font();
    let mut pixels = vec![0; 3 * size.0 as usize * size.1 as usize];
    let result = draw_on(
        BitMapBackend::with_buffer(&mut pixels, size).into_drawing_area(),
        figure,
        out,
    )?;
    Ok((pixels, result))
}

/// One run of a run-time-against-error study: its label, wall seconds and errors (one per
/// panel; NaN where it has none, e.g. the reference itself).
#[derive(Debug, Clone)]
pub struct ErrorPoint {
    pub label: String,
    pub seconds: f64,
    pub errors: Vec<Real>,
}

/// A panel of curves, one per run: its title, the x axis's label, and per run a label and
/// (x, value) points.
#[derive(Debug, Clone, Copy)]
pub struct CurvePanel<'a> {
    pub title: &'a str,
    pub x_label: &'a str,
    pub curves: &'a [(String, Vec<(Real, Real)>)],
}

/// Error against wall time, log-log, one panel per error (titled by `panels`), one marker per
/// run; then `profile` drawn as lines. Into the PNG or SVG `out`, written under a temporary
/// name and renamed.
pub fn error_figure(
    out: &Path,
    panels: &[&str],
    points: &[ErrorPoint],
    profile: CurvePanel<'_>,
) -> Result<(), IoError> {
    let rows = panels.len() + 1;
    let figure = ErrorFigure {
        panels,
        points,
        profile,
    };
    write_figure(out, (1200, 400 * rows as u32), figure)
}

/// The figure of [`error_figure`].
struct ErrorFigure<'a> {
    panels: &'a [&'a str],
    points: &'a [ErrorPoint],
    profile: CurvePanel<'a>,
}

impl Figure for ErrorFigure<'_> {
    type Output = ();

    fn draw<DB: DrawingBackend>(self, root: &Canvas<DB>, out: &Path) -> Result<(), IoError> {
        let Self {
            panels,
            points,
            profile,
        } = self;
        let fail = |e: &dyn std::fmt::Display| IoError::invalid(out, format!("plotting: {e}"));
        let rows = panels.len() + 1;
        let areas = root.split_evenly((rows, 1));
        for (p, (area, title)) in areas.iter().zip(panels).enumerate() {
            let shown: Vec<(usize, f64, Real)> = points
                .iter()
                .enumerate()
                .filter(|(_, q)| q.seconds > 0.0 && q.errors[p] > 0.0 && q.errors[p].is_finite())
                .map(|(k, q)| (k, q.seconds, q.errors[p]))
                .collect();
            if shown.is_empty() {
                area.titled(&format!("{title}: no data"), ("sans-serif", 20))
                    .map_err(|e| fail(&e))?;
                continue;
            }
            let span = |f: fn(&(usize, f64, Real)) -> f64| {
                let (lo, hi) = shown
                    .iter()
                    .map(f)
                    .fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(v), b.max(v)));
                (lo / 2.0)..(hi * 2.0)
            };
            let mut chart = ChartBuilder::on(area)
                .caption(*title, ("sans-serif", 20))
                .margin(12)
                .x_label_area_size(36)
                .y_label_area_size(80)
                .build_cartesian_2d(span(|q| q.1).log_scale(), span(|q| q.2).log_scale())
                .map_err(|e| fail(&e))?;
            chart
                .configure_mesh()
                .x_desc("wall time (s)")
                .x_label_formatter(&|v| format!("{v:.3}"))
                .y_label_formatter(&|v| format!("{v:.3e}"))
                .label_style(("sans-serif", 14))
                .draw()
                .map_err(|e| fail(&e))?;
            for &(k, t, e) in &shown {
                let color = Palette99::pick(k).to_rgba();
                chart
                    .draw_series(std::iter::once(Circle::new((t, e), 6, color.filled())))
                    .map_err(|e| fail(&e))?
                    .label(points[k].label.clone())
                    .legend(move |(x, y)| Circle::new((x + 10, y), 5, color.filled()));
            }
            legend(&mut chart, shown.iter().map(|&(_, t, e)| (t, e))).map_err(|e| fail(&e))?;
        }
        let CurvePanel {
            title,
            x_label,
            curves,
        } = profile;
        let all = || curves.iter().flat_map(|(_, c)| c.iter());
        let (x0, x1) = all().fold((Real::MAX, Real::MIN), |(a, b), p| (a.min(p.0), b.max(p.0)));
        let (y0, y1) = all().fold((Real::MAX, Real::MIN), |(a, b), p| (a.min(p.1), b.max(p.1)));
        let area = &areas[rows - 1];
        if !(x1 > x0 && y1 >= y0) {
            area.titled(&format!("{title}: no data"), ("sans-serif", 20))
                .map_err(|e| fail(&e))?;
            return Ok(());
        }
        let pad = 0.05 * (y1 - y0).max(1e-12);
        let mut chart = ChartBuilder::on(area)
            .caption(title, ("sans-serif", 20))
            .margin(12)
            .x_label_area_size(36)
            .y_label_area_size(80)
            .build_cartesian_2d(x0..x1, (y0 - pad)..(y1 + pad))
            .map_err(|e| fail(&e))?;
        chart
            .configure_mesh()
            .x_desc(x_label)
            .label_style(("sans-serif", 14))
            .draw()
            .map_err(|e| fail(&e))?;
        for (k, (label, curve)) in curves.iter().enumerate() {
            line(&mut chart, k, label, curve.iter().copied()).map_err(|e| fail(&e))?;
        }
        legend(&mut chart, all().copied()).map_err(|e| fail(&e))?;
        Ok(())
    }
}

/// Curves of a parameter study, `y` against `x` (log-log, or linear axes with `log = false`),
/// one per group with a marker at each run (markers alone with `lines = false`: a stability
/// map of two varied keys, grouped by status), into the PNG or SVG `out` (written under a
/// temporary name and renamed). Points that a log axis cannot show (zero, negative, not
/// finite) are left out and counted in the result.
pub fn study_figure(
    out: &Path,
    labels: (&str, &str),
    curves: &[(String, Vec<(Real, Real)>)],
    log: bool,
    lines: bool,
) -> Result<usize, IoError> {
    let shown =
        |p: &(Real, Real)| p.0.is_finite() && p.1.is_finite() && (!log || (p.0 > 0.0 && p.1 > 0.0));
    let kept: Vec<(String, Vec<(Real, Real)>)> = curves
        .iter()
        .map(|(l, c)| (l.clone(), c.iter().copied().filter(shown).collect()))
        .collect();
    let left_out = curves.iter().map(|(_, c)| c.len()).sum::<usize>()
        - kept.iter().map(|(_, c)| c.len()).sum::<usize>();
    let all = || kept.iter().flat_map(|(_, c)| c.iter());
    let (x0, x1) = all().fold((Real::MAX, Real::MIN), |(a, b), p| (a.min(p.0), b.max(p.0)));
    let (y0, y1) = all().fold((Real::MAX, Real::MIN), |(a, b), p| (a.min(p.1), b.max(p.1)));
    if !(x1 >= x0 && y1 >= y0) {
        return Err(IoError::invalid(out, "plotting: no point to show"));
    }
    let figure = Study {
        labels,
        curves: &kept,
        ranges: (x0..x1, y0..y1),
        log,
        lines,
    };
    write_figure(out, (1000, 700), figure)?;
    Ok(left_out)
}

/// The figure of [`study_figure`]: the curves it keeps and the ranges they span.
struct Study<'a> {
    labels: (&'a str, &'a str),
    curves: &'a [(String, Vec<(Real, Real)>)],
    ranges: (std::ops::Range<Real>, std::ops::Range<Real>),
    log: bool,
    lines: bool,
}

impl Figure for Study<'_> {
    type Output = ();

    fn draw<DB: DrawingBackend>(self, root: &Canvas<DB>, out: &Path) -> Result<(), IoError> {
        let Self {
            labels,
            curves: kept,
            ranges: (x, y),
            log,
            lines,
        } = self;
        let (x0, x1, y0, y1) = (x.start, x.end, y.start, y.end);
        let fail = |e: &dyn std::fmt::Display| IoError::invalid(out, format!("plotting: {e}"));
        let mut chart = ChartBuilder::on(root);
        chart.margin(16).x_label_area_size(48).y_label_area_size(96);
        if log {
            let mut c = chart
                .build_cartesian_2d(
                    ((x0 / 1.5)..(x1 * 1.5)).log_scale(),
                    ((y0 / 1.5)..(y1 * 1.5)).log_scale(),
                )
                .map_err(|e| fail(&e))?;
            draw_curves(&mut c, labels, kept, lines).map_err(|e| fail(&e))?;
        } else {
            let pad = |a: Real, b: Real| 0.05 * (b - a).max(1e-12);
            let mut c = chart
                .build_cartesian_2d(
                    (x0 - pad(x0, x1))..(x1 + pad(x0, x1)),
                    (y0 - pad(y0, y1))..(y1 + pad(y0, y1)),
                )
                .map_err(|e| fail(&e))?;
            draw_curves(&mut c, labels, kept, lines).map_err(|e| fail(&e))?;
        }
        Ok(())
    }
}

/// The axes (labelled `labels`, ticks in scientific notation) and curves of
/// [`study_figure`], a line and markers each, with the legend.
fn draw_curves<'a, DB: DrawingBackend + 'a, X, Y>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<X, Y>>,
    labels: (&str, &str),
    curves: &[(String, Vec<(Real, Real)>)],
    lines: bool,
) -> Result<(), String>
where
    X: Ranged<ValueType = Real> + plotters::coord::ranged1d::ValueFormatter<Real>,
    Y: Ranged<ValueType = Real> + plotters::coord::ranged1d::ValueFormatter<Real>,
{
    let sci = |v: &Real| format!("{v:.1e}");
    chart
        .configure_mesh()
        .x_desc(labels.0)
        .y_desc(labels.1)
        .x_labels(6)
        .y_labels(8)
        .x_label_formatter(&sci)
        .y_label_formatter(&sci)
        .light_line_style(TRANSPARENT)
        .label_style(("sans-serif", 16))
        .draw()
        .map_err(|e| e.to_string())?;
    for (k, (label, curve)) in curves.iter().enumerate() {
        let color = Palette99::pick(k).to_rgba();
        let markers = chart
            .draw_series(curve.iter().map(|&p| Circle::new(p, 6, color.filled())))
            .map_err(|e| e.to_string())?;
        if !lines {
            markers
                .label(label.clone())
                .legend(move |(x, y)| Circle::new((x + 10, y), 5, color.filled()));
            continue;
        }
        chart
            .draw_series(LineSeries::new(
                curve.iter().copied(),
                color.stroke_width(2),
            ))
            .map_err(|e| e.to_string())?
            .label(label.clone())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
            });
    }
    legend(chart, curves.iter().flat_map(|(_, c)| c.iter().copied()))
}
