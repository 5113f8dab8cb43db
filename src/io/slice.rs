//! `eddy slice`: a quick look at one field of a run's frames without ParaView, for tests,
//! documentation and work over ssh. A plane across one axis is drawn as a colour map with a
//! colour bar (the field's unit on it), axes in metres and the frame's time in the title: the
//! grid's layer of cells holding the plane, or the particles of a slab around it as dots, into
//! a PNG or SVG; a range of frames into a numbered series of them or one animated GIF, all on
//! one colour scale, so a colour means the same value in every frame.
//!
//! The frames are the run's HDF5 frames or, when it wrote none, its VTK frames (`source.rs`
//! reads both). On the grid, the obstacles are outlined: the edges between the cells its
//! `solid` field marks (1 in obstacle cells, 0 in the fluid, as eddy's grid frames store it)
//! and the fluid's cells. Particle frames store no obstacles, and nothing is outlined on them.

mod animation;
mod source;

use std::ops::Range;
use std::path::{Path, PathBuf};

use ndarray::{ArrayD, Ix2};
use plotters::prelude::*;
use plotters::style::colors::colormaps::ViridisRGB;

use self::animation::Animation;
use self::source::{locate, Fields, Frame, Series};
use super::hdf5_read::FrameChoice;
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

/// Which frames [`draw`] draws.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FrameSelection {
    /// One frame, into the figure named.
    One(FrameChoice),
    /// Frames `first` to `last`, both included, counting from 0.
    Span(usize, usize),
    /// Every frame.
    All,
}

/// What [`draw`] draws.
#[derive(Debug, Clone)]
pub struct SliceOptions {
    /// A field of the frames; a vector field is drawn as its magnitude, `NAME.x` (`.y`, `.z`)
    /// draws one component.
    pub field: String,
    /// The axis the plane is normal to.
    pub axis: Axis,
    /// Where the plane crosses `axis`, m; the middle of the grid (or of the particles of the
    /// first frame drawn) if None.
    pub at: Option<Real>,
    pub frames: FrameSelection,
    /// Which frames of a run that has both; the grid's if None.
    pub kind: Option<SliceKind>,
    /// The values at the colour map's bottom and top; if None, the least and greatest finite
    /// value of all the frames drawn.
    pub range: Option<Range<Real>>,
    /// The figure: `.png`, or `.svg` for a vector image, or `.gif` for an animation. A
    /// [`FrameSelection::Span`] or [`FrameSelection::All`] into a PNG or SVG writes one file
    /// per frame, `STEM_NNNNNN.EXT` by the frame's number.
    pub out: PathBuf,
}

/// What [`draw`] is doing, for a progress report: reading the frames for their common colour
/// scale and extent, then drawing them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    Reading,
    Drawing,
}

/// What [`draw`] drew of one frame, for a caller to report or check.
#[derive(Debug, Clone)]
pub struct SliceSummary {
    /// The field as asked for (`NAME` or `NAME.x`).
    pub field: String,
    pub kind: SliceKind,
    /// The frame index file read (`.h5`, `.pvd`) or the one VTK frame.
    pub file: PathBuf,
    /// The image drawn: the figure, one of a numbered series, or the GIF it is a frame of.
    pub image: PathBuf,
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
    /// Of the cells, the obstacle's, outlined.
    pub obstacle_cells: usize,
    /// The frame's least and greatest finite value (infinite if it has none).
    pub min: Real,
    pub max: Real,
    /// The values at the colour map's bottom and top colours, the same for every frame drawn.
    pub scale: Range<Real>,
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
        if let Some(unit) = unit(&self.field) {
            write!(f, " {unit}")?;
        }
        if self.non_finite > 0 {
            write!(f, " ({} not finite, grey)", self.non_finite)?;
        }
        if self.obstacle_cells > 0 {
            write!(f, " ({} obstacle cells outlined)", self.obstacle_cells)?;
        }
        Ok(())
    }
}

/// One line for a series drawn: the images, the frames and their times, the colour range.
pub fn series_line(drawn: &[SliceSummary]) -> String {
    let (Some(first), Some(last)) = (drawn.first(), drawn.last()) else {
        return "drew no frames".to_owned();
    };
    let written = if first.image == last.image {
        format!("wrote {}", first.image.display())
    } else {
        format!(
            "wrote {} to {}",
            first.image.display(),
            last.image.display()
        )
    };
    let unit = unit(&first.field).map_or(String::new(), |u| format!(" {u}"));
    format!(
        "{written}: {} frames ({} to {}, t = {} to {} s), {} on one colour range {} to {}{unit}",
        drawn.len(),
        first.frame,
        last.frame,
        short(first.time, 4),
        short(last.time, 4),
        first.field,
        short(first.scale.start, 6),
        short(first.scale.end, 6)
    )
}

const AXES: [Axis; 3] = [Axis::X, Axis::Y, Axis::Z];
const NAMES: [&str; 3] = ["x", "y", "z"];

/// The colour of a value that is not finite: no colour of the map, so it reads as missing.
const NOT_FINITE: RGBColor = RGBColor(170, 170, 170);
/// The obstacles' outline: a red no part of the colour map comes near.
const OUTLINE: RGBColor = RGBColor(230, 20, 20);

/// The units of the fields eddy writes, for the colour bar; a field not listed gets none.
const UNITS: [(&str, &str); 5] = [
    ("pressure", "Pa"),
    ("velocity", "m/s"),
    ("vorticity", "1/s"),
    ("abl_vorticity", "1/s"),
    ("density", "kg/m³"),
];

/// The unit of `field` (`NAME` or a component `NAME.x`), if it is a known field.
fn unit(field: &str) -> Option<&'static str> {
    let base = field.split_once('.').map_or(field, |(b, _)| b);
    UNITS.iter().find(|(f, _)| *f == base).map(|(_, u)| *u)
}

/// Draws the plane `opts` asks for of the run folder `run` (or of one frames file, such as a
/// run's `smoke_fine.h5`, `grid.pvd` or one `grid_000012.vti`) into `opts.out`, every file
/// written under a temporary name and renamed when complete; calls `progress` with the stage,
/// the frames done and their number as it goes. Returns what it drew of each frame. HDF5 holds
/// a global lock: call from one thread.
pub fn draw(
    run: &Path,
    opts: &SliceOptions,
    progress: &mut dyn FnMut(Stage, usize, usize),
) -> Result<Vec<SliceSummary>, IoError> {
    let target = Target::of(opts)?;
    let series = locate(run, opts.kind)?;
    let frames = chosen(&series, opts.frames)?;
    let kind = series.kind();
    let at = position(&series, frames[0], opts)?;
    let depth = match kind {
        SliceKind::Grid => None,
        SliceKind::Particles => Some(series.particle_spacing()?),
    };
    let read = |k: usize| {
        let frame = series.frame(k)?;
        match depth {
            None => grid_plane(&frame, opts, at),
            Some(h) => particle_plane(&frame, opts, at, h),
        }
    };
    // The first pass: one colour scale, extent and image size for all the frames.
    let mut scan = Scan::default();
    let mut kept = None;
    for (n, &k) in frames.iter().enumerate() {
        let plane = read(k)?;
        scan.add(&plane, &title(opts, &plane));
        kept = (frames.len() == 1).then_some(plane);
        progress(Stage::Reading, n + 1, frames.len());
    }
    let look = scan.look(&series, opts, &frames, (at, depth))?;
    let mut sink = target.open(opts, look.size)?;
    let mut summaries = Vec::with_capacity(frames.len());
    for (n, &k) in frames.iter().enumerate() {
        let plane = match kept.take() {
            Some(plane) => plane,
            None => read(k)?,
        };
        summaries.push(sink.draw(&plane, &look, opts, &series)?);
        progress(Stage::Drawing, n + 1, frames.len());
    }
    sink.finish()?;
    Ok(summaries)
}

/// What the figure named by `--out` is.
#[derive(Clone, Copy)]
enum Target {
    /// One PNG or SVG.
    Figure,
    /// PNGs or SVGs numbered by frame.
    Numbered,
    Gif,
}

impl Target {
    /// The target of `opts.out` for `opts.frames`, refusing a name that is none of them.
    fn of(opts: &SliceOptions) -> Result<Self, IoError> {
        let ext = opts.out.extension().and_then(|e| e.to_str());
        match ext.map(str::to_ascii_lowercase).as_deref() {
            Some("gif") => Ok(Target::Gif),
            Some("png" | "svg") if matches!(opts.frames, FrameSelection::One(_)) => {
                Ok(Target::Figure)
            }
            Some("png" | "svg") => Ok(Target::Numbered),
            _ => Err(IoError::invalid(
                &opts.out,
                "the figure must be a .png or an .svg file, or a .gif for an animation",
            )),
        }
    }

    /// Starts writing images of `size` pixels.
    fn open(self, opts: &SliceOptions, size: (u32, u32)) -> Result<Sink, IoError> {
        Ok(match self {
            Target::Gif => Sink::Gif(Animation::create(&opts.out, size, OUTLINE)?),
            Target::Figure => Sink::Files(None),
            Target::Numbered => Sink::Files(Some(numbered_stem(&opts.out)?)),
        })
    }
}

/// Where the frames go as they are drawn.
enum Sink {
    /// Files: `--out` itself, or (stem, extension) of a numbered series.
    Files(Option<(PathBuf, String)>),
    Gif(Animation),
}

/// The path before the number, and the extension, of a numbered series named by `out`.
fn numbered_stem(out: &Path) -> Result<(PathBuf, String), IoError> {
    let stem = out
        .file_stem()
        .ok_or_else(|| IoError::invalid(out, "no file name"))?;
    let ext = out.extension().unwrap_or_default().to_string_lossy();
    Ok((out.with_file_name(stem), ext.into_owned()))
}

impl Sink {
    /// Draws `plane` of the series' frames as `look` says.
    fn draw(
        &mut self,
        plane: &Plane,
        look: &Look,
        opts: &SliceOptions,
        series: &Series,
    ) -> Result<SliceSummary, IoError> {
        let title = title(opts, plane);
        let label = bar_label(&opts.field);
        let drawing = Drawing {
            plane,
            look,
            title: &title,
            label: &label,
        };
        let (image, pixels) = match self {
            Sink::Files(numbered) => {
                let image = match numbered {
                    None => opts.out.clone(),
                    Some((stem, ext)) => {
                        let mut name = stem.clone().into_os_string();
                        name.push(format!("_{:06}.{ext}", plane.frame));
                        PathBuf::from(name)
                    }
                };
                let pixels = write_figure(&image, look.size, drawing)?;
                (image, pixels)
            }
            Sink::Gif(animation) => (opts.out.clone(), animation.push(drawing)?),
        };
        let (min, max) = finite_range(&plane.values);
        Ok(SliceSummary {
            field: opts.field.clone(),
            kind: series.kind(),
            file: series.path().to_path_buf(),
            image,
            frame: plane.frame,
            time: plane.time,
            axis: opts.axis,
            at: plane.at,
            count: plane.values.len(),
            non_finite: plane.values.iter().filter(|v| !v.is_finite()).count(),
            obstacle_cells: plane.solid.iter().flatten().filter(|s| **s).count(),
            min,
            max,
            scale: look.scale.clone(),
            axes: plane.axes.map(|a| AXES[a]),
            extent: look.extent.clone(),
            pixels,
        })
    }

    fn finish(self) -> Result<(), IoError> {
        match self {
            Sink::Files(_) => Ok(()),
            Sink::Gif(animation) => animation.finish(),
        }
    }
}

/// The frames `selection` picks of `series`, in order; one out of bounds is refused with the
/// frames there are.
fn chosen(series: &Series, selection: FrameSelection) -> Result<Vec<usize>, IoError> {
    let n = series.count();
    let picked: Option<Vec<usize>> = match selection {
        FrameSelection::One(FrameChoice::Last) => n.checked_sub(1).map(|k| vec![k]),
        FrameSelection::One(FrameChoice::Index(k)) => (k < n).then(|| vec![k]),
        FrameSelection::One(FrameChoice::Time(t)) if n > 0 && t.is_finite() => {
            let times = (0..n)
                .map(|k| series.time(k))
                .collect::<Result<Vec<_>, _>>()?;
            let gap = |k: usize| (times[k] - t).abs();
            Some(vec![(1..n).fold(0, |best, k| {
                if gap(k) < gap(best) {
                    k
                } else {
                    best
                }
            })])
        }
        FrameSelection::Span(a, b) => (a <= b && b < n).then(|| (a..=b).collect()),
        FrameSelection::All => (n > 0).then(|| (0..n).collect()),
        FrameSelection::One(FrameChoice::Time(_)) => None,
    };
    picked.ok_or_else(|| {
        let asked = match selection {
            FrameSelection::One(FrameChoice::Last) => "the last frame".to_owned(),
            FrameSelection::One(FrameChoice::Index(k)) => format!("frame {k}"),
            FrameSelection::One(FrameChoice::Time(t)) => format!("the frame nearest t = {t} s"),
            FrameSelection::Span(a, b) => format!("frames {a} to {b}"),
            FrameSelection::All => "every frame".to_owned(),
        };
        let there = match n {
            0 => "no frames".to_owned(),
            n => format!("{n} frame(s), 0 to {}", n - 1),
        };
        IoError::invalid(series.path(), format!("{asked} asked for, it has {there}"))
    })
}

/// Where the plane crosses its axis: `opts.at`, or the middle of the grid or of the particles
/// of frame `k`; refused outside them.
fn position(series: &Series, k: usize, opts: &SliceOptions) -> Result<Real, IoError> {
    let frame = series.frame(k)?;
    let a = opts.axis.index();
    let (span, what) = match series.kind() {
        SliceKind::Grid => (frame.grid()?.span(a), "the grid".to_owned()),
        SliceKind::Particles => (
            bounds(&frame.positions()?, a),
            format!("the particles of frame {k}"),
        ),
    };
    let at = opts.at.unwrap_or(0.5 * (span.start + span.end));
    if (span.start..=span.end).contains(&at) {
        return Ok(at);
    }
    let n = NAMES[a];
    Err(IoError::invalid(
        frame.path(),
        format!(
            "{n} = {at} m lies outside {what} ({n} = {} to {} m)",
            span.start, span.end
        ),
    ))
}

/// The least and greatest finite position along axis `b` of `positions` (an empty range of
/// infinities if none).
fn bounds(positions: &ndarray::Array2<Real>, b: usize) -> Range<Real> {
    positions
        .column(b)
        .iter()
        .fold(Real::INFINITY..Real::NEG_INFINITY, |r, &x| {
            r.start.min(x)..r.end.max(x)
        })
}

/// The least and greatest finite value of `values` (infinities if none is finite).
fn finite_range(values: &[Real]) -> (Real, Real) {
    values
        .iter()
        .filter(|v| v.is_finite())
        .fold((Real::INFINITY, Real::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        })
}

/// A plane's values and where they lie, ready to draw.
struct Plane {
    frame: usize,
    time: Real,
    /// The plane's position on its axis, m.
    at: Real,
    /// Of particles, the slab's half depth, m.
    depth: Option<Real>,
    /// Indices of the horizontal and vertical axes, and the metres the values span on them.
    axes: [usize; 2],
    extent: [Range<Real>; 2],
    marks: Marks,
    /// One value per cell (C order over the two axes) or per dot.
    values: Vec<Real>,
    /// Of cells, which are the obstacle's, in the values' order; None when the frame has no
    /// `solid` field.
    solid: Option<Vec<bool>>,
}

/// How a plane's values are drawn.
enum Marks {
    /// A layer of grid cells, this many along each axis, filling the extent.
    Cells([usize; 2]),
    /// Dots of this diameter (m) at these points of the plane.
    Dots(Vec<[Real; 2]>, Real),
}

/// The title over a plane: the field, the plane, the time and the frame.
fn title(opts: &SliceOptions, plane: &Plane) -> String {
    format!(
        "{}, {} = {}{} m, t = {} s (frame {})",
        opts.field,
        NAMES[opts.axis.index()],
        short(plane.at, 4),
        plane
            .depth
            .map_or(String::new(), |d| format!(" ± {}", short(d, 4))),
        short(plane.time, 4),
        plane.frame
    )
}

/// What the first pass gathers over the frames.
struct Scan {
    min: Real,
    max: Real,
    extent: Option<[Range<Real>; 2]>,
    /// Characters of the longest title.
    title: usize,
    /// Cells or dots over all frames.
    count: usize,
}

impl Default for Scan {
    fn default() -> Self {
        Scan {
            min: Real::INFINITY,
            max: Real::NEG_INFINITY,
            extent: None,
            title: 0,
            count: 0,
        }
    }
}

/// How every frame of a series is drawn: one colour scale, extent and image size.
struct Look {
    scale: Range<Real>,
    extent: [Range<Real>; 2],
    size: (u32, u32),
}

impl Scan {
    fn add(&mut self, plane: &Plane, title: &str) {
        let (min, max) = finite_range(&plane.values);
        self.min = self.min.min(min);
        self.max = self.max.max(max);
        self.extent = Some(match self.extent.take() {
            None => plane.extent.clone(),
            Some(e) => [0, 1]
                .map(|d| e[d].start.min(plane.extent[d].start)..e[d].end.max(plane.extent[d].end)),
        });
        self.title = self.title.max(title.chars().count());
        self.count += plane.values.len();
    }

    /// The look of `frames` of `series` on the plane at `at` (of particles, a slab `depth` to
    /// each side): `opts.range`, or the values' own range (a constant field is drawn in the
    /// map's middle colour, on a bar around its value). Refuses frames with nothing to draw.
    fn look(
        self,
        series: &Series,
        opts: &SliceOptions,
        frames: &[usize],
        (at, depth): (Real, Option<Real>),
    ) -> Result<Look, IoError> {
        let which = match frames {
            [k] => format!("frame {k}"),
            _ => format!("frames {} to {}", frames[0], frames[frames.len() - 1]),
        };
        let fail = |what: String| IoError::invalid(series.path(), format!("{which}: {what}"));
        let (Some(extent), true) = (self.extent, self.count > 0) else {
            let a = NAMES[opts.axis.index()];
            return Err(fail(format!(
                "no particle lies within {} m of {a} = {at} m",
                depth.unwrap_or(0.0)
            )));
        };
        let scale = match &opts.range {
            Some(r) => r.clone(),
            None if self.min > self.max => {
                return Err(fail(format!(
                    "`{}` has no finite value on this plane",
                    opts.field
                )))
            }
            None => {
                let half = if self.max > self.min {
                    0.0
                } else {
                    0.5 * self.min.abs().max(1.0)
                };
                (self.min - half)..(self.max + half)
            }
        };
        let size = figure_size(&extent, self.title, &bar_label(&opts.field));
        Ok(Look {
            scale,
            extent,
            size,
        })
    }
}

/// The plot area's pixels for `extent`: about 640 on the longer side, in the metres' true
/// proportion unless that makes the other side thinner than 160.
fn plot_size(extent: &[Range<Real>; 2]) -> [u32; 2] {
    let [w, h] = extent.clone().map(|r| r.end - r.start);
    [w, h].map(|l| (640.0 * l / w.max(h)).clamp(160.0, 640.0) as u32)
}

/// The pixels text of `chars` characters in `font` takes: the bundled font's advance
/// (monospace, a little over 0.5 em as plotters sizes it).
fn text_width(chars: usize, font: u32) -> u32 {
    (0.55 * font as Real * chars as Real) as u32
}

/// The image's size: the plot with room for the labels, the colour bar labelled `label` and a
/// title of `title` characters.
fn figure_size(extent: &[Range<Real>; 2], title: usize, label: &str) -> (u32, u32) {
    let [w, h] = plot_size(extent);
    let main = (Y_LABELS + w).max(text_width(title, TITLE_FONT));
    (
        2 * MARGIN + main + bar_area(label),
        2 * MARGIN + CAPTION + h + X_LABELS,
    )
}

/// The width right of the plot: the colour bar with its values, and its label under it.
fn bar_area(label: &str) -> u32 {
    let over = text_width(label.chars().count(), LABEL_FONT) + MARGIN;
    BAR_GAP + (BAR + BAR_LABELS).max(over)
}

/// The colour bar's label: the field and its unit, if known.
fn bar_label(field: &str) -> String {
    match unit(field) {
        Some(u) => format!("{field} ({u})"),
        None => field.to_owned(),
    }
}

const MARGIN: u32 = 16;
const TITLE_FONT: u32 = 20;
const CAPTION: u32 = 36;
const X_LABELS: u32 = 50;
const Y_LABELS: u32 = 70;
const LABEL_FONT: u32 = 14;
/// The colour bar's width, the gap before it and the width of its values.
const BAR: u32 = 24;
const BAR_GAP: u32 = 24;
const BAR_LABELS: u32 = 90;

/// The two axes across a plane normal to axis `a`, in x, y, z order.
fn across(a: usize) -> [usize; 2] {
    let mut others = (0..3).filter(|&b| b != a);
    [0, 1].map(|_| others.next().unwrap_or(a))
}

/// The grid's layer of cells holding the plane at `at`, with its obstacle cells.
fn grid_plane(frame: &Frame, opts: &SliceOptions, at: Real) -> Result<Plane, IoError> {
    let g = frame.grid()?;
    if g.dims.contains(&0) {
        return Err(frame.fail(format!("an empty grid of {:?} cells", g.dims)));
    }
    let a = opts.axis.index();
    // Saturating: a plane below the grid's start reads its first layer.
    let layer = (((at - g.origin[a]) / g.spacing[a]) as usize).min(g.dims[a] - 1);
    let fields = frame.fields(SliceKind::Grid);
    let (name, pick) = resolve(&fields, &opts.field).map_err(|e| frame.fail(e))?;
    let cells = |name: &str, pick: Pick| {
        let data = frame.grid_layer(name, &g, a, layer)?;
        pick.apply(data)
            .into_dimensionality::<Ix2>()
            .map_err(|e| frame.fail(format!("`{name}`: {e}")))
    };
    let values = cells(&name, pick)?;
    let solid = match fields.iter().any(|(f, v)| f == "solid" && !v) {
        true => Some(
            cells("solid", Pick::Scalar)?
                .iter()
                .map(|s| *s > 0.5)
                .collect(),
        ),
        false => None,
    };
    let axes = across(a);
    Ok(Plane {
        frame: frame.index,
        time: frame.time,
        at: g.origin[a] + (layer as Real + 0.5) * g.spacing[a],
        depth: None,
        axes,
        extent: axes.map(|b| g.span(b)),
        marks: Marks::Cells([values.nrows(), values.ncols()]),
        values: values.iter().copied().collect(),
        solid,
    })
}

/// The particles within `h` (one particle spacing) of the plane at `at`.
fn particle_plane(frame: &Frame, opts: &SliceOptions, at: Real, h: Real) -> Result<Plane, IoError> {
    let positions = frame.positions()?;
    if positions.nrows() == 0 {
        return Err(frame.fail("no particles"));
    }
    let fields = frame.fields(SliceKind::Particles);
    let (name, pick) = resolve(&fields, &opts.field).map_err(|e| frame.fail(e))?;
    let values = pick.apply(frame.particle_values(&name, !matches!(pick, Pick::Scalar))?);
    if values.len() != positions.nrows() {
        return Err(frame.fail(format!(
            "`{}` holds {} values for {} particles",
            opts.field,
            values.len(),
            positions.nrows()
        )));
    }
    let a = opts.axis.index();
    let axes = across(a);
    let (points, values): (Vec<[Real; 2]>, Vec<Real>) = positions
        .rows()
        .into_iter()
        .zip(values.iter())
        .filter(|(p, _)| (p[a] - at).abs() <= h && axes.iter().all(|&b| p[b].is_finite()))
        .map(|(p, &v)| (axes.map(|b| p[b]), v))
        .unzip();
    Ok(Plane {
        frame: frame.index,
        time: frame.time,
        at,
        depth: Some(h),
        axes,
        // Padded by a spacing, so the dots at the edges are drawn whole.
        extent: axes.map(|b| {
            let r = bounds(&positions, b);
            r.start - h..r.end + h
        }),
        marks: Marks::Dots(points, h),
        values,
        solid: None,
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

/// The field of `fields` that `name` names (`NAME.x`, `.y`, `.z`: a vector's component) and
/// how to read it; an unknown name is refused with the fields there are.
fn resolve(fields: &Fields, name: &str) -> Result<(String, Pick), String> {
    let find = |n: &str| fields.iter().find(|(f, _)| f == n);
    let component = name
        .rsplit_once('.')
        .and_then(|(base, c)| Some((base, c, find(base)?.1)));
    match (find(name), component) {
        (Some((_, true)), _) => Ok((name.to_owned(), Pick::Magnitude)),
        (Some((_, false)), _) => Ok((name.to_owned(), Pick::Scalar)),
        (None, Some((base, c, true))) => match NAMES.iter().position(|n| *n == c) {
            Some(c) => Ok((base.to_owned(), Pick::Component(c))),
            None => Err(format!(
                "`{base}` is a vector field: `.{c}` is no component of it (.x, .y or .z)"
            )),
        },
        (None, Some((base, c, false))) => Err(format!(
            "`{base}` is a scalar field: it has no component `.{c}`"
        )),
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
            Err(format!(
                "no field `{name}`; the fields are {} (a vector is drawn as its magnitude; \
                 NAME.x, NAME.y or NAME.z draws a component)",
                list.join(", ")
            ))
        }
    }
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

/// The edges between obstacle and fluid cells of a layer of `[nu, nv]` cells (obstacle cells
/// flagged in `solid`, C order) spanning `extent`, as segments in metres.
fn outline(
    solid: &[bool],
    [nu, nv]: [usize; 2],
    extent: &[Range<Real>; 2],
) -> Vec<[(Real, Real); 2]> {
    let du = (extent[0].end - extent[0].start) / nu as Real;
    let dv = (extent[1].end - extent[1].start) / nv as Real;
    let corner = |i: usize, j: usize| {
        (
            extent[0].start + i as Real * du,
            extent[1].start + j as Real * dv,
        )
    };
    let mut edges = Vec::new();
    for i in 0..nu {
        for j in 0..nv {
            let here = solid[i * nv + j];
            if i + 1 < nu && here != solid[(i + 1) * nv + j] {
                edges.push([corner(i + 1, j), corner(i + 1, j + 1)]);
            }
            if j + 1 < nv && here != solid[i * nv + j + 1] {
                edges.push([corner(i, j + 1), corner(i + 1, j + 1)]);
            }
        }
    }
    edges
}

/// The figure of one frame: a plane on the series' look, under `title`, the colour bar
/// labelled `label`.
struct Drawing<'a> {
    plane: &'a Plane,
    look: &'a Look,
    title: &'a str,
    label: &'a str,
}

impl Drawing<'_> {
    /// The colour map's colour of `v`, grey when it is not finite.
    fn colour(&self, v: Real) -> RGBColor {
        if !v.is_finite() {
            return NOT_FINITE;
        }
        let Range { start, end } = self.look.scale;
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
        let [eu, ev] = self.look.extent.clone();
        let (width, height) = root.dim_in_pixel();
        let main_width = width.saturating_sub(bar_area(self.label));
        let (main, bar) = root.split_horizontally(main_width);
        // A title wider than the plot leaves room, on the left, so the bar stays beside it.
        let [plot_w, plot_h] = plot_size(&self.look.extent);
        let room = main_width.saturating_sub(2 * MARGIN + Y_LABELS + plot_w);
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
            .label_style(("sans-serif", LABEL_FONT))
            .draw()
            .map_err(|e| fail(&e))?;
        let (px, py) = chart.plotting_area().get_pixel_range();
        match &plane.marks {
            Marks::Cells([nu, nv]) => {
                let [cu, cv] = &plane.extent;
                let du = (cu.end - cu.start) / *nu as Real;
                let dv = (cv.end - cv.start) / *nv as Real;
                let cells = plane.values.iter().enumerate().map(|(n, &v)| {
                    let (u, w) = (
                        cu.start + (n / nv) as Real * du,
                        cv.start + (n % nv) as Real * dv,
                    );
                    Rectangle::new([(u, w), (u + du, w + dv)], self.colour(v).filled())
                });
                chart.draw_series(cells).map_err(|e| fail(&e))?;
                let edges = plane
                    .solid
                    .as_deref()
                    .map(|s| outline(s, [*nu, *nv], &plane.extent))
                    .unwrap_or_default();
                let lines = edges
                    .into_iter()
                    .map(|e| PathElement::new(e.to_vec(), OUTLINE.stroke_width(2)));
                chart.draw_series(lines).map_err(|e| fail(&e))?;
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
        // The colour bar: beside the plot and as tall, its values on the right, the field and
        // its unit under it (over it, a title wider than the plot may reach).
        let style = ("sans-serif", LABEL_FONT).into_text_style(&bar);
        let under = (BAR_GAP as i32, py.end + LABEL_FONT as i32);
        bar.draw_text(self.label, &style, under)
            .map_err(|e| fail(&e))?;
        let scale_range = self.look.scale.clone();
        let right = bar_area(self.label) - BAR_GAP - BAR - BAR_LABELS;
        let strip = bar.margin(
            py.start,
            height as i32 - py.end,
            BAR_GAP as i32,
            right as i32,
        );
        let mut scale = ChartBuilder::on(&strip)
            .set_label_area_size(LabelAreaPosition::Right, BAR_LABELS)
            .build_cartesian_2d(0.0..1.0, scale_range.clone())
            .map_err(|e| fail(&e))?;
        const BANDS: usize = 256;
        let step = (scale_range.end - scale_range.start) / BANDS as Real;
        let bands = (0..BANDS).map(|k| {
            let v = scale_range.start + k as Real * step;
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
            .label_style(("sans-serif", LABEL_FONT))
            .draw()
            .map_err(|e| fail(&e))?;
        Ok([px, py])
    }
}
