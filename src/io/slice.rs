//! `eddy slice`: a quick look at one field of a run's HDF5 frames without ParaView, for tests,
//! documentation and work over ssh. A plane across one axis is drawn as a colour map with a
//! colour bar, axes in metres and the frame's time in the title: the grid's layer of cells
//! holding the plane, or the particles of a slab around it as dots, into a PNG or SVG.

use std::ops::Range;
use std::path::{Path, PathBuf};

use hdf5::{Dataset, Group, Hyperslab, SliceOrIndex};
use ndarray::{Array2, ArrayD, Ix2, IxDyn};
use plotters::prelude::*;
use plotters::style::colors::colormaps::ViridisRGB;

use super::hdf5_grid::{grid_geometry, GRID_FORMAT};
use super::hdf5_read::{FrameChoice, FrameSeries, StoredFrame};
use super::plot::{write_figure, Canvas, Figure};
use super::IoError;
use crate::metrics::Axis;
use crate::Real;

/// The frames a run can be sliced from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SliceKind {
    Grid,
    Particles,
}

impl SliceKind {
    /// What the frames hold, as an error names them.
    fn frames(self) -> &'static str {
        match self {
            SliceKind::Grid => "grid",
            SliceKind::Particles => "particle",
        }
    }
}

/// What [`draw`] draws.
#[derive(Debug, Clone)]
pub struct SliceOptions {
    /// A field of the frames; a vector field is drawn as its magnitude, `NAME.x` (`.y`, `.z`)
    /// draws one component.
    pub field: String,
    /// The axis the plane is normal to.
    pub axis: Axis,
    /// Where the plane crosses `axis`, m; the middle of the grid (or of the particles) if None.
    pub at: Option<Real>,
    pub frame: FrameChoice,
    /// Which frames of a run that has both; the grid's if None.
    pub kind: Option<SliceKind>,
    /// The figure: `.png`, or `.svg` for a vector image.
    pub out: PathBuf,
}

/// What [`draw`] drew, for a caller to report or check.
#[derive(Debug, Clone)]
pub struct SliceSummary {
    /// The field as asked for (`NAME` or `NAME.x`).
    pub field: String,
    pub kind: SliceKind,
    /// The frame index file read.
    pub file: PathBuf,
    pub frame: usize,
    /// The frame's time, s.
    pub time: Real,
    /// The axis the plane is normal to.
    pub axis: Axis,
    /// The plane's position, m: the centre of the grid cells drawn (their values lie there), or
    /// the middle of the particles' slab.
    pub at: Real,
    /// Cells or particles drawn.
    pub count: usize,
    /// Of them, those whose value is not finite, drawn grey outside the colour scale.
    pub non_finite: usize,
    /// The least and greatest finite value: the colour map's bottom and top colours.
    pub min: Real,
    pub max: Real,
    /// The plot's horizontal and vertical axes: the other two in x, y, z order.
    pub axes: [Axis; 2],
    /// The metres the plot spans along them.
    pub extent: [Range<Real>; 2],
    /// The plot area in image pixels: columns (left to right), rows (top to bottom), so a
    /// point's pixel follows from `extent` for a test or a caption.
    pub pixels: [Range<i32>; 2],
}

/// One line: what was drawn, where and when, and the values' range.
impl std::fmt::Display for SliceSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let what = match self.kind {
            SliceKind::Grid => "cells",
            SliceKind::Particles => "particles",
        };
        write!(
            f,
            "{} on {} = {} m, frame {} at t = {} s: {} {what} from {} to {}",
            self.field,
            NAMES[self.axis.index()],
            short(self.at, 4),
            self.frame,
            short(self.time, 4),
            self.count,
            short(self.min, 6),
            short(self.max, 6)
        )?;
        if self.non_finite > 0 {
            write!(f, " ({} not finite, grey)", self.non_finite)?;
        }
        Ok(())
    }
}

const AXES: [Axis; 3] = [Axis::X, Axis::Y, Axis::Z];
const NAMES: [&str; 3] = ["x", "y", "z"];

/// The colour of a value that is not finite: no colour of the map, so it reads as missing.
const NOT_FINITE: RGBColor = RGBColor(170, 170, 170);

/// Draws the plane `opts` asks for of the run folder `run` (or of one frame index file, such
/// as a run's `smoke_fine.h5`) into `opts.out`, written under a temporary name and renamed.
/// HDF5 holds a global lock: call from one thread.
pub fn draw(run: &Path, opts: &SliceOptions) -> Result<SliceSummary, IoError> {
    let ext = opts.out.extension().and_then(|e| e.to_str());
    if !matches!(
        ext.map(str::to_ascii_lowercase).as_deref(),
        Some("png" | "svg")
    ) {
        return Err(IoError::invalid(
            &opts.out,
            "the figure must be a .png or an .svg file",
        ));
    }
    let (kind, series) = locate(run, opts.kind)?;
    let plane = match kind {
        SliceKind::Grid => grid_plane(&series, opts)?,
        SliceKind::Particles => particle_plane(&series, opts)?,
    };
    let values = || plane.values.iter().copied();
    let (min, max) = values()
        .filter(|v| v.is_finite())
        .fold((Real::INFINITY, Real::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if min > max {
        return Err(IoError::invalid(
            &series.path,
            format!(
                "frame {}: `{}` has no finite value on this plane",
                plane.frame.index, opts.field
            ),
        ));
    }
    // A constant field is drawn in the map's middle colour, on a bar around its value.
    let half = if max > min {
        0.0
    } else {
        0.5 * min.abs().max(1.0)
    };
    let title = format!(
        "{}, {} = {}{} m, t = {} s (frame {})",
        opts.field,
        NAMES[opts.axis.index()],
        short(plane.at, 4),
        plane
            .depth
            .map_or(String::new(), |d| format!(" ± {}", short(d, 4))),
        short(plane.frame.time, 4),
        plane.frame.index
    );
    let pixels = write_figure(
        &opts.out,
        plane.figure_size(&title),
        Drawing {
            plane: &plane,
            scale: (min - half)..(max + half),
            title: &title,
        },
    )?;
    Ok(SliceSummary {
        field: opts.field.clone(),
        kind,
        file: series.path.clone(),
        frame: plane.frame.index,
        time: plane.frame.time,
        axis: opts.axis,
        at: plane.at,
        count: plane.values.len(),
        non_finite: values().filter(|v| !v.is_finite()).count(),
        min,
        max,
        axes: plane.axes.map(|a| AXES[a]),
        extent: plane.extent.clone(),
        pixels,
    })
}

/// The frame series of `run` to slice: of a folder its `frames.h5`, or of a coupled scene its
/// `grid_frames.h5` or `particles_frames.h5` as `kind` asks (the grid's by default); a file is
/// taken as the index itself.
fn locate(run: &Path, kind: Option<SliceKind>) -> Result<(SliceKind, FrameSeries), IoError> {
    let files: Vec<PathBuf> = if run.is_dir() {
        let existing = |names: &[&str]| -> Vec<PathBuf> {
            names
                .iter()
                .map(|n| run.join(n))
                .filter(|p| p.is_file())
                .collect()
        };
        let coupled = existing(&["grid_frames.h5", "particles_frames.h5"]);
        if coupled.is_empty() {
            existing(&["frames.h5"])
        } else {
            coupled
        }
    } else if run.is_file() {
        vec![run.to_path_buf()]
    } else {
        return Err(IoError::invalid(run, "no such run folder or frames file"));
    };
    if files.is_empty() {
        return Err(IoError::invalid(
            run,
            "no HDF5 frames here (frames.h5, or grid_frames.h5 and particles_frames.h5 of a \
             coupled scene): the scene's [output] must ask for them with hdf5 = true, e.g. \
             `eddy run SCENE --set output.hdf5=true`",
        ));
    }
    let mut found = files
        .iter()
        .map(|path| {
            let series = FrameSeries::open(path)?;
            let grid = series.format().as_deref() == Some(GRID_FORMAT);
            let kind = if grid {
                SliceKind::Grid
            } else {
                SliceKind::Particles
            };
            Ok((kind, series))
        })
        .collect::<Result<Vec<_>, IoError>>()?;
    let wanted = kind.unwrap_or(SliceKind::Grid);
    match found.iter().position(|(k, _)| *k == wanted) {
        Some(i) => Ok(found.swap_remove(i)),
        None if kind.is_none() => Ok(found.swap_remove(0)),
        None => Err(IoError::invalid(
            run,
            format!(
                "holds no {} frames, only {} frames",
                wanted.frames(),
                found[0].0.frames()
            ),
        )),
    }
}

/// A plane's values and where they lie, ready to draw.
struct Plane {
    frame: StoredFrame,
    /// The plane's position on its axis, m.
    at: Real,
    /// Of particles, the slab's half depth, m.
    depth: Option<Real>,
    /// Indices of the horizontal and vertical axes, and the metres the plot spans on them.
    axes: [usize; 2],
    extent: [Range<Real>; 2],
    marks: Marks,
    /// One value per cell (C order over the two axes) or per dot.
    values: Vec<Real>,
}

/// How a plane's values are drawn.
enum Marks {
    /// A layer of grid cells, this many along each axis, filling the extent.
    Cells([usize; 2]),
    /// Dots of this diameter (m) at these points of the plane.
    Dots(Vec<[Real; 2]>, Real),
}

impl Plane {
    /// The plot area's pixels: about 640 on the longer side, in the metres' true proportion
    /// unless that makes the other side thinner than 160.
    fn plot_size(&self) -> [u32; 2] {
        let [w, h] = self.extent.clone().map(|r| r.end - r.start);
        [w, h].map(|l| (640.0 * l / w.max(h)).clamp(160.0, 640.0) as u32)
    }

    /// The image's size: the plot with room for the labels, the colour bar and `title`, whose
    /// width is estimated from the bundled font's advance (monospace, a little over 0.5 em as
    /// plotters sizes it).
    fn figure_size(&self, title: &str) -> (u32, u32) {
        let [w, h] = self.plot_size();
        let title = (0.55 * TITLE_FONT as Real * title.chars().count() as Real) as u32;
        let main = (Y_LABELS + w).max(title);
        (
            2 * MARGIN + main + BAR_AREA,
            2 * MARGIN + CAPTION + h + X_LABELS,
        )
    }
}

const MARGIN: u32 = 16;
const TITLE_FONT: u32 = 20;
const CAPTION: u32 = 36;
const X_LABELS: u32 = 50;
const Y_LABELS: u32 = 70;
/// The colour bar's width, the gap before it and its labels' width.
const BAR: u32 = 24;
const BAR_GAP: u32 = 24;
const BAR_LABELS: u32 = 90;
const BAR_AREA: u32 = BAR_GAP + BAR + BAR_LABELS;

/// The two axes across a plane normal to axis `a`, in x, y, z order.
fn across(a: usize) -> [usize; 2] {
    let mut others = (0..3).filter(|&b| b != a);
    [0, 1].map(|_| others.next().unwrap_or(a))
}

/// Refuses a plane at `at` outside `span` (what spans it named by `what`).
fn check_inside(
    path: &Path,
    axis: usize,
    at: Real,
    span: &Range<Real>,
    what: &str,
) -> Result<(), IoError> {
    if (span.start..=span.end).contains(&at) {
        return Ok(());
    }
    let n = NAMES[axis];
    Err(IoError::invalid(
        path,
        format!(
            "{n} = {at} m lies outside {what} ({n} = {} to {} m)",
            span.start, span.end
        ),
    ))
}

/// The grid's layer of cells holding the plane.
fn grid_plane(series: &FrameSeries, opts: &SliceOptions) -> Result<Plane, IoError> {
    let path = &series.path;
    let g = grid_geometry(series)?;
    let frame = series.pick(opts.frame)?;
    let a = opts.axis.index();
    let span = |b: usize| g.origin[b]..g.origin[b] + g.spacing * g.dims[b] as Real;
    let at = opts.at.unwrap_or(0.5 * (span(a).start + span(a).end));
    check_inside(path, a, at, &span(a), "the grid")?;
    let layer = (((at - g.origin[a]) / g.spacing) as usize).min(g.dims[a].saturating_sub(1));
    let (dataset, pick) = field(series, &frame, &opts.field, 3)?;
    if dataset.shape()[..3] != g.dims {
        return Err(IoError::invalid(
            path,
            format!(
                "frame {}: `{}` has shape {:?}, the grid is {:?}",
                frame.index,
                opts.field,
                dataset.shape(),
                g.dims
            ),
        ));
    }
    let selection: Vec<SliceOrIndex> = (0..dataset.ndim())
        .map(|d| if d == a { layer.into() } else { (..).into() })
        .collect();
    let data = dataset
        .read_slice::<Real, _, IxDyn>(Hyperslab::from(selection))
        .map_err(|e| read_failure(series, &frame, &opts.field, e))?;
    let values: Array2<Real> = pick
        .apply(data)
        .into_dimensionality::<Ix2>()
        .map_err(|e| IoError::invalid(path, format!("`{}`: {e}", opts.field)))?;
    let axes = across(a);
    Ok(Plane {
        at: g.origin[a] + (layer as Real + 0.5) * g.spacing,
        depth: None,
        axes,
        extent: axes.map(span),
        marks: Marks::Cells([values.nrows(), values.ncols()]),
        values: values.iter().copied().collect(),
        frame,
    })
}

/// The particles within one particle spacing of the plane.
fn particle_plane(series: &FrameSeries, opts: &SliceOptions) -> Result<Plane, IoError> {
    let path = &series.path;
    let h = series
        .file
        .attr("particle_spacing")
        .and_then(|a| a.read_scalar::<Real>())
        .ok()
        .filter(|h| h.is_finite() && *h > 0.0)
        .ok_or_else(|| IoError::invalid(path, "no positive root attribute `particle_spacing`"))?;
    let frame = series.pick(opts.frame)?;
    let fail = |what: String| IoError::invalid(path, format!("frame {}: {what}", frame.index));
    let positions = frame
        .group
        .dataset("position")
        .and_then(|d| d.read::<Real, Ix2>())
        .map_err(|e| fail(format!("dataset `position`: {e}")))?;
    if positions.ncols() != 3 || positions.nrows() == 0 {
        return Err(fail(format!(
            "no particles (`position` has shape {:?})",
            positions.shape()
        )));
    }
    let (dataset, pick) = field(series, &frame, &opts.field, 1)?;
    let data = dataset
        .read_dyn::<Real>()
        .map_err(|e| read_failure(series, &frame, &opts.field, e))?;
    let values = pick.apply(data);
    if values.len() != positions.nrows() {
        return Err(fail(format!(
            "`{}` holds {} values for {} particles",
            opts.field,
            values.len(),
            positions.nrows()
        )));
    }
    let bounds = |b: usize| {
        positions
            .column(b)
            .iter()
            .fold(Real::INFINITY..Real::NEG_INFINITY, |r, &x| {
                r.start.min(x)..r.end.max(x)
            })
    };
    let a = opts.axis.index();
    let span = bounds(a);
    let at = opts.at.unwrap_or(0.5 * (span.start + span.end));
    let what = format!("the particles of frame {}", frame.index);
    check_inside(path, a, at, &span, &what)?;
    let axes = across(a);
    let (points, values): (Vec<[Real; 2]>, Vec<Real>) = positions
        .rows()
        .into_iter()
        .zip(values.iter())
        .filter(|(p, _)| (p[a] - at).abs() <= h && axes.iter().all(|&b| p[b].is_finite()))
        .map(|(p, &v)| (axes.map(|b| p[b]), v))
        .unzip();
    if points.is_empty() {
        return Err(fail(format!(
            "no particle lies within {h} m of {} = {at} m",
            NAMES[a]
        )));
    }
    Ok(Plane {
        at,
        depth: Some(h),
        axes,
        // Padded by a spacing, so the dots at the edges are drawn whole.
        extent: axes.map(|b| {
            let r = bounds(b);
            r.start - h..r.end + h
        }),
        marks: Marks::Dots(points, h),
        values,
        frame,
    })
}

/// How a field's datasets become one value per cell or particle.
#[derive(Debug, Clone, Copy)]
enum Pick {
    Scalar,
    Magnitude,
    Component(usize),
}

impl Pick {
    /// The values of `data`, whose last axis holds a vector's components unless `Scalar`.
    fn apply(self, data: ArrayD<Real>) -> ArrayD<Real> {
        let last = ndarray::Axis(data.ndim().saturating_sub(1));
        match self {
            Pick::Scalar => data,
            Pick::Magnitude => data.map_axis(last, |v| v.dot(&v).sqrt()),
            Pick::Component(c) => data.index_axis(last, c).to_owned(),
        }
    }
}

/// The dataset of the field `name` in `frame` (`NAME.x`, `.y`, `.z`: a vector's component) and
/// how to read it, with `rank` the rank of a scalar field (3 on the grid, 1 for particles). An
/// unknown name is refused with the fields there are.
fn field(
    series: &FrameSeries,
    frame: &StoredFrame,
    name: &str,
    rank: usize,
) -> Result<(Dataset, Pick), IoError> {
    let fields = fields(&frame.group, rank);
    let find = |n: &str| fields.iter().find(|(f, _)| f == n);
    let fail =
        |what: String| IoError::invalid(&series.path, format!("frame {}: {what}", frame.index));
    let component = name
        .rsplit_once('.')
        .and_then(|(base, c)| Some((base, c, find(base)?.1)));
    let (found, pick) = match (find(name), component) {
        (Some((_, true)), _) => (name, Pick::Magnitude),
        (Some((_, false)), _) => (name, Pick::Scalar),
        (None, Some((base, c, true))) => match NAMES.iter().position(|n| *n == c) {
            Some(c) => (base, Pick::Component(c)),
            None => {
                return Err(fail(format!(
                    "`{base}` is a vector field: `.{c}` is no component of it (.x, .y or .z)"
                )))
            }
        },
        (None, Some((base, c, false))) => {
            return Err(fail(format!(
                "`{base}` is a scalar field: it has no component `.{c}`"
            )))
        }
        (None, None) => {
            let list: Vec<String> = fields
                .iter()
                .map(|(f, v)| {
                    if *v {
                        format!("{f} (vector)")
                    } else {
                        f.clone()
                    }
                })
                .collect();
            return Err(fail(format!(
                "no field `{name}`; the fields are {} (a vector is drawn as its magnitude; \
                 NAME.x, NAME.y or NAME.z draws a component)",
                list.join(", ")
            )));
        }
    };
    let dataset = frame
        .group
        .dataset(found)
        .map_err(|e| fail(format!("dataset `{found}`: {e}")))?;
    Ok((dataset, pick))
}

/// The fields of a frame group: its datasets of scalar `rank`, or one more with 3 components
/// (flagged true), in name order; particle positions are where the values lie, not a field.
fn fields(group: &Group, rank: usize) -> Vec<(String, bool)> {
    let names = group.member_names().unwrap_or_default();
    names
        .into_iter()
        .filter(|n| n != "position")
        .filter_map(|n| {
            let shape = group.dataset(&n).ok()?.shape();
            match shape.len() {
                r if r == rank => Some((n, false)),
                r if r == rank + 1 && shape[rank] == 3 => Some((n, true)),
                _ => None,
            }
        })
        .collect()
}

fn read_failure(series: &FrameSeries, frame: &StoredFrame, name: &str, e: hdf5::Error) -> IoError {
    IoError::invalid(
        &series.path,
        format!("frame {}: reading `{name}`: {e}", frame.index),
    )
}

/// `v` to `digits` significant digits without trailing zeros, or in scientific notation when
/// it is tiny or huge: labels that stay short at any scale.
fn short(v: Real, digits: i32) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    if !(1e-3..1e5).contains(&v.abs()) {
        return format!("{v:.prec$e}", prec = (digits - 1).max(0) as usize);
    }
    let decimals = (digits - 1 - v.abs().log10().floor() as i32).max(0) as usize;
    let s = format!("{v:.decimals$}");
    let s = if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.')
    } else {
        &s
    };
    if s == "-0" { "0" } else { s }.to_owned()
}

/// The figure of [`draw`]: a plane on the colour scale `scale`, under `title`.
struct Drawing<'a> {
    plane: &'a Plane,
    scale: Range<Real>,
    title: &'a str,
}

impl Drawing<'_> {
    /// The colour map's colour of `v`, grey when it is not finite.
    fn colour(&self, v: Real) -> RGBColor {
        if !v.is_finite() {
            return NOT_FINITE;
        }
        let Range { start, end } = self.scale;
        ViridisRGB::get_color(((v - start) / (end - start)).clamp(0.0, 1.0))
    }
}

impl Figure for Drawing<'_> {
    /// The plot area's pixels.
    type Output = [Range<i32>; 2];

    fn draw<DB: DrawingBackend>(
        self,
        root: &Canvas<DB>,
        out: &Path,
    ) -> Result<Self::Output, IoError> {
        let fail = |e: &dyn std::fmt::Display| IoError::invalid(out, format!("plotting: {e}"));
        let plane = self.plane;
        let [eu, ev] = plane.extent.clone();
        let (width, height) = root.dim_in_pixel();
        let (main, bar) = root.split_horizontally(width - BAR_AREA);
        // A title wider than the plot leaves room, on the left, so the bar stays beside it.
        let [plot_w, plot_h] = plane.plot_size();
        let room = (width - BAR_AREA).saturating_sub(2 * MARGIN + Y_LABELS + plot_w);
        let mut chart = ChartBuilder::on(&main)
            .caption(self.title, ("sans-serif", TITLE_FONT))
            .margin(MARGIN)
            .margin_left(MARGIN + room)
            .x_label_area_size(X_LABELS)
            .y_label_area_size(Y_LABELS)
            .build_cartesian_2d(eu.clone(), ev.clone())
            .map_err(|e| fail(&e))?;
        let label = |v: &Real| short(*v, 4);
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc(format!("{} (m)", NAMES[plane.axes[0]]))
            .y_desc(format!("{} (m)", NAMES[plane.axes[1]]))
            .x_label_formatter(&label)
            .y_label_formatter(&label)
            .x_labels((plot_w / 80) as usize)
            .y_labels((plot_h / 50) as usize)
            .label_style(("sans-serif", 14))
            .draw()
            .map_err(|e| fail(&e))?;
        let (px, py) = chart.plotting_area().get_pixel_range();
        match &plane.marks {
            Marks::Cells([nu, nv]) => {
                let du = (eu.end - eu.start) / *nu as Real;
                let dv = (ev.end - ev.start) / *nv as Real;
                let cells = plane.values.iter().enumerate().map(|(n, &v)| {
                    let (u, w) = (
                        eu.start + (n / nv) as Real * du,
                        ev.start + (n % nv) as Real * dv,
                    );
                    Rectangle::new([(u, w), (u + du, w + dv)], self.colour(v).filled())
                });
                chart.draw_series(cells).map_err(|e| fail(&e))?;
            }
            Marks::Dots(points, diameter) => {
                let per_metre = (px.end - px.start) as Real / (eu.end - eu.start);
                let radius = (0.5 * diameter * per_metre).round().max(2.0) as i32;
                let dots = points
                    .iter()
                    .zip(&plane.values)
                    .map(|(p, &v)| Circle::new((p[0], p[1]), radius, self.colour(v).filled()));
                chart.draw_series(dots).map_err(|e| fail(&e))?;
            }
        }
        // The colour bar: beside the plot and as tall, its values on the right.
        let strip = bar.margin(py.start, height as i32 - py.end, BAR_GAP as i32, 0);
        let mut scale = ChartBuilder::on(&strip)
            .set_label_area_size(LabelAreaPosition::Right, BAR_LABELS)
            .build_cartesian_2d(0.0..1.0, self.scale.clone())
            .map_err(|e| fail(&e))?;
        const BANDS: usize = 256;
        let step = (self.scale.end - self.scale.start) / BANDS as Real;
        let bands = (0..BANDS).map(|k| {
            let v = self.scale.start + k as Real * step;
            Rectangle::new(
                [(0.0, v), (1.0, v + step)],
                self.colour(v + 0.5 * step).filled(),
            )
        });
        scale.draw_series(bands).map_err(|e| fail(&e))?;
        scale
            .configure_mesh()
            .disable_mesh()
            .disable_x_axis()
            .y_label_formatter(&|v| short(*v, 6))
            .label_style(("sans-serif", 14))
            .draw()
            .map_err(|e| fail(&e))?;
        Ok([px, py])
    }
}
