//! `eddy slice`: a colour map of one field of a run's frames, a quick look without ParaView; a
//! range of frames as a numbered series of images or an animated GIF.

use std::io::IsTerminal;
use std::ops::Range;
use std::path::PathBuf;

use clap::builder::{PossibleValuesParser, TypedValueParser};
use eddy::io::slice::{FrameSelection, SliceKind, SliceOptions, Stage};
use eddy::io::FrameChoice;
use eddy::metrics::Axis;
use eddy::Real;

/// Options of `eddy slice`.
#[derive(Debug, Clone, clap::Args)]
pub struct SliceArgs {
    /// The run folder (`eddy run --out`) with its frames: the HDF5 frames if it wrote them,
    /// else the VTK frames (grid.pvd, particles.pvd). Or one frames file of it: smoke_fine.h5,
    /// a .pvd series, one .vti or .vtp frame.
    pub run: PathBuf,
    /// The field to colour by, e.g. pressure, velocity, vorticity, density. A vector field is
    /// drawn as its magnitude; NAME.x, NAME.y or NAME.z draws one component. A wrong name lists
    /// the fields there are.
    #[arg(long)]
    pub field: String,
    /// The axis the plane is normal to; the plot spans the other two, the first of them in x,
    /// y, z order across.
    #[arg(long, value_parser = PossibleValuesParser::new(["x", "y", "z"]).map(|a| axis(&a)))]
    pub axis: Axis,
    /// Where the plane crosses the axis, m (default: the middle of the grid, or of the
    /// particles of the first frame drawn). The grid's layer of cells holding it is drawn, or
    /// the particles within one particle spacing of it.
    #[arg(long, allow_hyphen_values = true)]
    pub at: Option<Real>,
    /// The frame to draw, counting from 0 (default: the last; every frame into a .gif).
    #[arg(long, conflicts_with_all = ["time", "frames"])]
    pub frame: Option<usize>,
    /// Draw the frame whose time is nearest this, s.
    #[arg(long, conflicts_with = "frames")]
    pub time: Option<Real>,
    /// Frames A to B (both included, counting from 0), or `all`: into a .gif, or a numbered
    /// series FIG_NNNNNN.png (.svg) by frame. One colour range for them all: --range, or the
    /// least and greatest value of all the frames drawn.
    #[arg(long, value_name = "A:B|all", value_parser = frames)]
    pub frames: Option<FrameSelection>,
    /// The values at the colour map's bottom and top (default: the least and greatest finite
    /// value of the frames drawn), e.g. --range 0:5 or --range -2e3:2e3.
    #[arg(long, value_name = "MIN:MAX", allow_hyphen_values = true, value_parser = range)]
    pub range: Option<Range<Real>>,
    /// The grid's or the particles' frames, for a coupled run that has both (default: grid).
    #[arg(long, value_parser = PossibleValuesParser::new(["grid", "particles"])
        .map(|k| if k == "grid" { SliceKind::Grid } else { SliceKind::Particles }))]
    pub kind: Option<SliceKind>,
    /// The figure: FIG.png, or FIG.svg for a vector image, or ANIMATION.gif (10 frames a
    /// second, looping).
    #[arg(long, value_name = "FIG")]
    pub out: PathBuf,
}

fn axis(name: &str) -> Axis {
    match name {
        "x" => Axis::X,
        "y" => Axis::Y,
        _ => Axis::Z,
    }
}

/// `A:B` (frames A to B) or `all`.
fn frames(text: &str) -> Result<FrameSelection, String> {
    if text == "all" {
        return Ok(FrameSelection::All);
    }
    let parsed = text
        .split_once(':')
        .and_then(|(a, b)| Some((a.trim().parse().ok()?, b.trim().parse().ok()?)));
    match parsed {
        Some((a, b)) if a <= b => Ok(FrameSelection::Span(a, b)),
        Some((a, b)) => Err(format!("the first frame {a} comes after the last {b}")),
        None => Err(format!(
            "{text:?} is not A:B (frames A to B, counting from 0) or `all`"
        )),
    }
}

/// `MIN:MAX`, finite with MIN below MAX.
fn range(text: &str) -> Result<Range<Real>, String> {
    let parsed = text.split_once(':').and_then(|(a, b)| {
        let (a, b): (Real, Real) = (a.trim().parse().ok()?, b.trim().parse().ok()?);
        (a.is_finite() && b.is_finite()).then_some(a..b)
    });
    match parsed {
        Some(r) if r.start < r.end => Ok(r),
        Some(r) => Err(format!("MIN {} is not below MAX {}", r.start, r.end)),
        None => Err(format!("{text:?} is not MIN:MAX, two finite numbers")),
    }
}

/// Runs `eddy slice`: draws the figure (or the frames) and says what it shows.
pub fn run(args: &SliceArgs) -> anyhow::Result<()> {
    let gif = args
        .out
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gif"));
    let frames = match (args.frames, args.frame, args.time) {
        (Some(f), ..) => f,
        (None, Some(k), _) => FrameSelection::One(FrameChoice::Index(k)),
        (None, None, Some(t)) => FrameSelection::One(FrameChoice::Time(t)),
        (None, None, None) if gif => FrameSelection::All,
        (None, None, None) => FrameSelection::One(FrameChoice::Last),
    };
    let options = SliceOptions {
        field: args.field.clone(),
        axis: args.axis,
        at: args.at,
        frames,
        kind: args.kind,
        range: args.range.clone(),
        out: args.out.clone(),
    };
    let mut report = Progress::default();
    let drawn = eddy::io::slice::draw(&args.run, &options, &mut |stage, done, of| {
        report.update(stage, done, of)
    })?;
    report.bar.finish_and_clear();
    match drawn.as_slice() {
        [one] if !matches!(frames, FrameSelection::Span(..) | FrameSelection::All) => {
            eprintln!("eddy: wrote {}: {one}", one.image.display());
        }
        all => eprintln!("eddy: {}", eddy::io::slice::series_line(all)),
    }
    Ok(())
}

/// How many frames pass between two progress lines when standard error is no terminal.
const LINES_EVERY: usize = 25;

/// The progress of a series: a bar on a terminal, else a line every [`LINES_EVERY`] frames.
struct Progress {
    bar: indicatif::ProgressBar,
    stage: Option<Stage>,
    terminal: bool,
}

impl Default for Progress {
    fn default() -> Self {
        Progress {
            bar: indicatif::ProgressBar::hidden(),
            stage: None,
            terminal: std::io::stderr().is_terminal(),
        }
    }
}

impl Progress {
    fn update(&mut self, stage: Stage, done: usize, of: usize) {
        let doing = match stage {
            Stage::Reading => "reading",
            Stage::Drawing => "drawing",
        };
        if of < 2 {
            return;
        }
        if !self.terminal {
            if done.is_multiple_of(LINES_EVERY) || done == of {
                eprintln!("eddy: slice: {doing}, {done} of {of} frames done");
            }
            return;
        }
        if self.stage != Some(stage) {
            self.stage = Some(stage);
            self.bar.finish_and_clear();
            self.bar = indicatif::ProgressBar::new(of as u64);
            if let Ok(style) =
                indicatif::ProgressStyle::with_template("{msg} {bar:40} {pos}/{len} frames")
            {
                self.bar.set_style(style);
            }
            self.bar.set_message(doing);
        }
        self.bar.set_position(done as u64);
    }
}
