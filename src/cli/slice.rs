//! `eddy slice`: a colour map of one field of a run's frames, a quick look without ParaView.

use std::path::PathBuf;

use clap::builder::{PossibleValuesParser, TypedValueParser};
use eddy::io::slice::{SliceKind, SliceOptions};
use eddy::io::FrameChoice;
use eddy::metrics::Axis;
use eddy::Real;

/// Options of `eddy slice`.
#[derive(Debug, Clone, clap::Args)]
pub struct SliceArgs {
    /// The run folder (`eddy run --out`) with its HDF5 frames, or one frames file of it such as
    /// smoke_fine.h5.
    pub run: PathBuf,
    /// The field to colour by, e.g. pressure, velocity, density. A vector field is drawn as
    /// its magnitude; NAME.x, NAME.y or NAME.z draws one component. A wrong name lists the
    /// fields there are.
    #[arg(long)]
    pub field: String,
    /// The axis the plane is normal to; the plot spans the other two, the first of them in x,
    /// y, z order across.
    #[arg(long, value_parser = PossibleValuesParser::new(["x", "y", "z"]).map(|a| axis(&a)))]
    pub axis: Axis,
    /// Where the plane crosses the axis, m (default: the middle of the grid, or of the
    /// particles). The grid's layer of cells holding it is drawn, or the particles within one
    /// particle spacing of it.
    #[arg(long, allow_hyphen_values = true)]
    pub at: Option<Real>,
    /// The frame to draw, counting from 0 (default: the last).
    #[arg(long, conflicts_with = "time")]
    pub frame: Option<usize>,
    /// Draw the frame whose time is nearest this, s.
    #[arg(long)]
    pub time: Option<Real>,
    /// The grid's or the particles' frames, for a coupled run that has both (default: grid).
    #[arg(long, value_parser = PossibleValuesParser::new(["grid", "particles"])
        .map(|k| if k == "grid" { SliceKind::Grid } else { SliceKind::Particles }))]
    pub kind: Option<SliceKind>,
    /// The figure: FIG.png, or FIG.svg for a vector image.
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

/// Runs `eddy slice`: draws the figure and says what it shows.
pub fn run(args: &SliceArgs) -> anyhow::Result<()> {
    let frame = match (args.frame, args.time) {
        (Some(k), _) => FrameChoice::Index(k),
        (None, Some(t)) => FrameChoice::Time(t),
        (None, None) => FrameChoice::Last,
    };
    let options = SliceOptions {
        field: args.field.clone(),
        axis: args.axis,
        at: args.at,
        frame,
        kind: args.kind,
        out: args.out.clone(),
    };
    let summary = eddy::io::slice::draw(&args.run, &options)?;
    eprintln!("eddy: wrote {}: {summary}", args.out.display());
    Ok(())
}
