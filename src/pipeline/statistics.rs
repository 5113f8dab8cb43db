//! The statistics stage: after the solvers' step it adds the new state to each medium's
//! running statistics (`crate::metrics::statistics`), from `statistics.from` on and every
//! `statistics.every` steps, each sample weighted by the simulated time it stands for. The
//! accumulators live in the [`Simulation`] (`Simulation::statistics`), where the statistics
//! output and the Python bindings read them.

use super::order::Built;
use super::outputs::Kind;
use super::simulation::{Simulation, StepError};
use super::spec::RunSpec;
use super::stages::{Stage, StepRecord};
use super::RunError;
use crate::metrics::stations::StationSpec;
use crate::metrics::statistics::{FlowStatistics, Lattice, BYTES_PER_BIN, BYTES_PER_CELL};
use crate::state::{Restorer, Saver, StateError};
use crate::{Real, Vec3};

/// What `[statistics]` asks for, resolved by `scene::build`.
#[derive(Debug, Clone, PartialEq)]
pub struct StatisticsSpec {
    /// Time the averaging starts, s.
    pub from: Real,
    /// Sample every this many steps.
    pub every: u64,
    /// Edge of an SPH fluid's bins, m.
    pub bin: Real,
    /// The box an SPH fluid's lattice covers: the scene's domain.
    pub domain: (Vec3, Vec3),
    /// Profiles across boxes, with confidence intervals.
    pub stations: Vec<StationSpec>,
    /// The length of the stations' batches, s (none without an end time).
    pub batch: Option<Real>,
}

/// The running statistics of one medium.
#[derive(Debug, Clone)]
pub struct MediumStatistics {
    pub kind: Kind,
    pub stats: FlowStatistics,
}

/// Samples every medium's statistics after the step.
pub struct StatisticsStage {
    spec: StatisticsSpec,
    /// Steps since the last sample, and the simulated time they cover after `from`.
    pending: (u64, Real),
    /// Whether the last step took a sample.
    sampled: bool,
}

impl StatisticsStage {
    /// The stage of a run with a `[statistics]` section.
    pub(super) fn stage(spec: &RunSpec, sim: &mut Simulation) -> Built {
        let Some(statistics) = &spec.statistics else {
            return Ok(None);
        };
        Ok(Some(Box::new(Self::build(statistics.clone(), sim)?)))
    }

    /// The stage, with an empty accumulator per medium of `sim` put into it: on the grid's
    /// cells, on the bins of `spec.bin` over the domain for an SPH fluid; each with the
    /// stations. A station finer than a lattice is refused.
    pub fn build(spec: StatisticsSpec, sim: &mut Simulation) -> Result<Self, RunError> {
        let mut lattices = Vec::new();
        if let Some(grid) = sim.grid.as_ref() {
            let mac = &grid.mac;
            let lattice = Lattice {
                origin: mac.origin,
                spacing: mac.dx,
                dims: mac.dims,
            };
            lattices.push((Kind::Grid, lattice));
        }
        if sim.sph.is_some() {
            let (lo, hi) = spec.domain;
            lattices.push((Kind::Particles, Lattice::covering(lo, hi, spec.bin)));
        }
        for (kind, lattice) in lattices {
            let mut stats = FlowStatistics::new(lattice);
            stats
                .add_stations(&spec.stations, spec.from, spec.batch)
                .map_err(RunError::Unsupported)?;
            sim.statistics.push(MediumStatistics { kind, stats });
        }
        Ok(Self {
            spec,
            pending: (0, 0.0),
            sampled: false,
        })
    }
}

impl Stage for StatisticsStage {
    fn name(&self) -> &'static str {
        "statistics"
    }

    fn describe(&self, sim: &Simulation) -> (String, Vec<(&'static str, String)>) {
        let every = match self.spec.every {
            1 => "every step".to_owned(),
            n => format!("every {n} steps"),
        };
        let parts = sim
            .statistics
            .iter()
            .map(|m| {
                let l = &m.stats.lattice;
                let [nx, ny, nz] = l.dims;
                let bytes = match m.kind {
                    Kind::Grid => BYTES_PER_CELL,
                    Kind::Particles => BYTES_PER_BIN,
                };
                let mib = (l.len() * bytes) as Real / (1024.0 * 1024.0);
                let (part, on) = match m.kind {
                    Kind::Grid => ("grid", format!("the grid's {nx} x {ny} x {nz} cells")),
                    Kind::Particles => (
                        "particles",
                        format!(
                            "{nx} x {ny} x {nz} bins of {} m over the domain, each sample \
                             the bins' particle means weighted by their counts",
                            l.spacing
                        ),
                    ),
                };
                (part, format!("{on}, {mib:.1} MiB"))
            })
            .collect();
        (
            format!(
                "mean velocity, Reynolds stresses, k, mean vorticity and enstrophy (Welford, \
                 weighted by time) from t = {} s, {every}",
                self.spec.from
            ),
            parts,
        )
    }

    fn save(&self, into: &mut Saver) {
        into.u64("pending_steps", self.pending.0);
        into.real("pending_time", self.pending.1);
    }

    fn restore(&mut self, from: &Restorer) -> Result<(), StateError> {
        self.pending = (from.u64("pending_steps")?, from.real("pending_time")?);
        Ok(())
    }

    fn run(&mut self, sim: &mut Simulation, rec: &mut StepRecord) -> Result<(), StepError> {
        self.sampled = false;
        let end = rec.time + rec.dt;
        if end <= self.spec.from {
            return Ok(());
        }
        let covered = end - rec.time.max(self.spec.from);
        self.pending = (self.pending.0 + 1, self.pending.1 + covered);
        if self.pending.0 < self.spec.every {
            return Ok(());
        }
        let weight = std::mem::take(&mut self.pending).1;
        self.sampled = true;
        let span = (end - weight, end);
        let Simulation {
            grid,
            sph,
            statistics,
            particle_vorticity,
            ..
        } = sim;
        for m in statistics.iter_mut() {
            match (m.kind, grid.as_ref(), sph.as_ref()) {
                (Kind::Grid, Some(g), _) => m.stats.sample_grid(g, weight, span),
                (Kind::Particles, _, Some(s)) => {
                    let omega = particle_vorticity.get_or_insert_with(|| s.vorticity());
                    m.stats
                        .sample_particles(&s.fluid.x, &s.fluid.v, omega, weight, span);
                }
                _ => {}
            }
        }
        Ok(())
    }

    fn measures_only(&self) -> bool {
        true
    }

    fn ran<'a>(&self, sim: &'a Simulation) -> &'a [&'static str] {
        const PARTS: [&str; 2] = ["grid", "particles"];
        let n = if self.sampled {
            sim.statistics.len()
        } else {
            0
        };
        let first = usize::from(sim.grid.is_none());
        &PARTS[first..first + n]
    }
}
