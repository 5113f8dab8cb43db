//! Parameter studies of one scene, the engine of `eddy sweep` and `eddy plot-sweep`. Every
//! point of a study (the product of the varied values, or `--zip`'s pairing) is one `eddy run`
//! in its own folder, as a child process: a point that blows up, panics or runs out of time is
//! recorded and the study goes on, and its peak memory is its own. The rows land in sweep.csv
//! (rewritten after each run, so a killed study keeps what finished); a shard runs every N-th
//! point into sweep-k-of-N.csv and [`collect()`] joins the shards' rows.
//!
//! By file: `axes.rs` the varied keys and the points ([`Design`]); `sweep.rs` a [`Study`]
//! checked into a [`Plan`] and run; `point.rs` one point as a child process; `status.rs` the
//! status file a run leaves for the study; `rows.rs` sweep.csv; `measure.rs` the error
//! columns against a reference run or table; `analytic.rs` the analytic solutions;
//! `stability.rs` energy growth and where each key turns unstable; `collect.rs` joining
//! shards; `plot.rs` the curves of `eddy plot-sweep`. The command line (clap options, progress
//! bar, messages) is `src/cli/sweep.rs`.

mod analytic;
mod axes;
mod collect;
mod error;
mod measure;
mod plot;
mod point;
mod rows;
mod stability;
mod status;
mod sweep;

pub use analytic::{poiseuille_velocity, Analytic};
pub use axes::Design;
pub use collect::collect;
pub use error::StudyError;
pub use measure::{Measure, Series};
pub use plot::{curves, Curve};
pub use rows::Row;
pub use stability::Bound;
pub use status::{write_status, Status};
pub use sweep::{Plan, Stress, Study};
