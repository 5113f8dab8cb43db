//! The figure of `eddy spectrum`: one spectrum on log-log axes, with the peak of a frequency
//! spectrum marked by a vertical line, or a power law (Kolmogorov's k^(-5/3)) beside an
//! energy spectrum to read its slope against.

use std::path::Path;

use plotters::prelude::*;

use super::plot::{legend, write_figure, Canvas, Figure};
use super::IoError;
use crate::Real;

/// How far below its largest value a spectrum is drawn: the round-off floor of a transform
/// lies some 16 decades down and would flatten the rest.
const DECADES: i32 = 12;
/// Up to this many points each gets a marker, so that a short spectrum (a few shells) reads
/// as points, not only as a line.
const MARKED: usize = 64;

/// What [`spectrum_figure`] draws.
#[derive(Debug, Clone)]
pub struct SpectrumFigure<'a> {
    pub title: &'a str,
    pub x_label: &'a str,
    pub y_label: &'a str,
    /// The curve's legend entry.
    pub label: &'a str,
    /// (x, y) points. Those a log axis cannot show (zero, negative, not finite) and those more
    /// than 12 decades below the largest are left out; up to 64 are marked.
    pub curve: &'a [(Real, Real)],
    /// A vertical line at this x, with its legend entry (a spectrum's peak).
    pub mark: Option<(Real, String)>,
    /// A power law y ~ x^slope through the curve's point nearest the middle of the x range on
    /// the log axis, with its legend entry.
    pub guide: Option<(Real, String)>,
}

/// Draws `figure` into the PNG or SVG `out`, written under a temporary name and renamed.
pub fn spectrum_figure(out: &Path, figure: &SpectrumFigure<'_>) -> Result<(), IoError> {
    let top = figure
        .curve
        .iter()
        .map(|p| p.1)
        .filter(|y| y.is_finite())
        .fold(0.0, Real::max);
    let floor = top * 10.0_f64.powi(-DECADES);
    let shown: Vec<(Real, Real)> = figure
        .curve
        .iter()
        .copied()
        .filter(|&(x, y)| x.is_finite() && x > 0.0 && y.is_finite() && y > 0.0 && y >= floor)
        .collect();
    let span = |f: fn(&(Real, Real)) -> Real| {
        shown
            .iter()
            .map(f)
            .fold((Real::MAX, Real::MIN), |(a, b), v| (a.min(v), b.max(v)))
    };
    if shown.is_empty() {
        return Err(IoError::invalid(
            out,
            "plotting: no positive value to show on log axes",
        ));
    }
    let ((x0, x1), (y0, y1)) = (span(|p| p.0), span(|p| p.1));
    // A lone point (a spectrum with one mode) is shown in a decade around it.
    let pad = if x1 > x0 { 1.2 } else { 3.0 };
    let ranges = (x0 / pad..x1 * pad, y0 / 3.0..y1 * 3.0);
    write_figure(
        out,
        (1000, 700),
        Drawing {
            figure,
            shown,
            ranges,
        },
    )
}

/// The figure of [`spectrum_figure`]: the points it shows and the axes' ranges.
struct Drawing<'a> {
    figure: &'a SpectrumFigure<'a>,
    shown: Vec<(Real, Real)>,
    ranges: (std::ops::Range<Real>, std::ops::Range<Real>),
}

impl Figure for Drawing<'_> {
    type Output = ();

    fn draw<DB: DrawingBackend>(self, root: &Canvas<DB>, out: &Path) -> Result<(), IoError> {
        let fail = |e: &dyn std::fmt::Display| IoError::invalid(out, format!("plotting: {e}"));
        let Self {
            figure,
            shown,
            ranges: (x, y),
        } = self;
        let mut chart = ChartBuilder::on(root)
            .caption(figure.title, ("sans-serif", 20))
            .margin(16)
            .x_label_area_size(48)
            .y_label_area_size(96)
            .build_cartesian_2d(x.clone().log_scale(), y.clone().log_scale())
            .map_err(|e| fail(&e))?;
        let sci = |v: &Real| format!("{v:.1e}");
        chart
            .configure_mesh()
            .x_desc(figure.x_label)
            .y_desc(figure.y_label)
            .x_label_formatter(&sci)
            .y_label_formatter(&sci)
            .x_labels(8)
            .y_labels(8)
            .light_line_style(TRANSPARENT)
            .label_style(("sans-serif", 16))
            .draw()
            .map_err(|e| fail(&e))?;
        let blue = BLUE.to_rgba();
        chart
            .draw_series(LineSeries::new(shown.iter().copied(), blue.stroke_width(2)))
            .map_err(|e| fail(&e))?
            .label(figure.label)
            .legend(move |(px, py)| {
                PathElement::new(vec![(px, py), (px + 20, py)], blue.stroke_width(2))
            });
        if shown.len() <= MARKED {
            chart
                .draw_series(shown.iter().map(|&p| Circle::new(p, 3, blue.filled())))
                .map_err(|e| fail(&e))?;
        }
        if let Some((at, label)) = &figure.mark {
            let red = RED.stroke_width(2);
            chart
                .draw_series(LineSeries::new([(*at, y.start), (*at, y.end)], red))
                .map_err(|e| fail(&e))?
                .label(label)
                .legend(move |(px, py)| PathElement::new(vec![(px, py), (px + 20, py)], red));
        }
        if let Some((slope, label)) = &figure.guide {
            let middle = (x.start * x.end).sqrt();
            let through = shown.iter().copied().min_by(|a, b| {
                (a.0 / middle)
                    .ln()
                    .abs()
                    .total_cmp(&(b.0 / middle).ln().abs())
            });
            if let Some(line) = through.and_then(|p| power_law(p, *slope, &x, &y)) {
                let grey = BLACK.mix(0.5).stroke_width(2);
                chart
                    .draw_series(LineSeries::new(line, grey))
                    .map_err(|e| fail(&e))?
                    .label(label)
                    .legend(move |(px, py)| PathElement::new(vec![(px, py), (px + 20, py)], grey));
            }
        }
        legend(&mut chart, shown.iter().copied()).map_err(|e| fail(&e))
    }
}

/// Points along the line y = p.1 (x / p.0)^slope where it lies inside the axes' ranges (evenly
/// spaced on the log axis, so it is drawn straight), or None when none of it does.
fn power_law(
    p: (Real, Real),
    slope: Real,
    x: &std::ops::Range<Real>,
    y: &std::ops::Range<Real>,
) -> Option<Vec<(Real, Real)>> {
    let at = |x: Real| p.1 * (x / p.0).powf(slope);
    let (mut lo, mut hi) = (x.start, x.end);
    if slope != 0.0 {
        // Where the line crosses the bottom and top of the y range.
        let cross = |y: Real| p.0 * (y / p.1).powf(1.0 / slope);
        let (a, b) = (cross(y.start), cross(y.end));
        lo = lo.max(a.min(b));
        hi = hi.min(a.max(b));
    }
    const POINTS: usize = 64;
    (lo < hi).then(|| {
        (0..=POINTS)
            .map(|i| lo * (hi / lo).powf(i as Real / POINTS as Real))
            .map(|x| (x, at(x)))
            .collect()
    })
}
