//! `metrics.csv`: step, time, dt and the metrics the scene asks for, one row per step.

use super::spec::Metric;
use crate::io::{CsvSeries, IoError};
use crate::sph::{SphSolver, StepStats};
use crate::{Real, Vec3};
use std::path::Path;

/// Writes the requested metrics of each step.
pub struct MetricsRecorder {
    metrics: Vec<Metric>,
    csv: CsvSeries,
    row: Vec<Real>,
}

/// The state-dependent metrics of one step, measured before the step advances the state.
#[derive(Debug, Clone, Default)]
pub struct StateMetrics {
    values: Vec<Real>,
}

impl MetricsRecorder {
    /// The series it writes into.
    pub fn series(&self) -> &CsvSeries {
        &self.csv
    }

    /// The series, to go on from a checkpoint's rows.
    pub fn series_mut(&mut self) -> &mut CsvSeries {
        &mut self.csv
    }

    /// Creates `path` with the header for `metrics`, then the `extra` columns another stage
    /// reports (the turbulence stage's).
    pub fn create(path: &Path, metrics: &[Metric], extra: &[String]) -> Result<Self, IoError> {
        let mut columns: Vec<String> = ["step", "time", "dt"].map(String::from).to_vec();
        columns.extend(metrics.iter().map(|m| m.column().to_string()));
        columns.extend(extra.iter().cloned());
        Ok(Self {
            metrics: metrics.to_vec(),
            csv: CsvSeries::create(path, &columns)?,
            row: Vec::with_capacity(columns.len()),
        })
    }

    /// Measures the state of `solver` (call before it advances); only requested metrics run.
    /// `omega` is the state's vorticity when another stage took it; taken here, it is left
    /// there for the next.
    pub fn measure(
        &self,
        solver: &SphSolver,
        gravity: &Vec3,
        omega: &mut Option<Vec<Vec3>>,
    ) -> StateMetrics {
        let fluid = &solver.fluid;
        let mut errors = None;
        let mut density_errors = || {
            *errors.get_or_insert_with(|| super::density_errors(&fluid.density, fluid.rest_density))
        };
        let mut vorticity = None;
        let mut vorticity = || {
            *vorticity.get_or_insert_with(|| {
                let omega = omega.get_or_insert_with(|| solver.vorticity());
                super::vorticity_stats(omega, fluid.volume())
            })
        };
        let total = || {
            super::kinetic_energy(fluid.mass, &fluid.v)
                + solver.rotational_energy()
                + super::potential_energy(fluid.mass, &fluid.x, gravity)
        };
        let values = self
            .metrics
            .iter()
            .map(|m| match m {
                Metric::KineticEnergy => super::kinetic_energy(fluid.mass, &fluid.v),
                Metric::PotentialEnergy => super::potential_energy(fluid.mass, &fluid.x, gravity),
                Metric::RotationalEnergy => solver.rotational_energy(),
                Metric::TotalEnergy => total(),
                Metric::VorticityMean => vorticity().mean,
                Metric::VorticityMax => vorticity().max,
                Metric::Enstrophy => vorticity().enstrophy,
                Metric::DensityErrorAvg => density_errors().0,
                Metric::DensityErrorMax => density_errors().1,
                Metric::MaxSpeed => super::max_speed(&fluid.v),
                Metric::Particles => fluid.len() as Real,
                // Filled in from the step's statistics in `write`.
                Metric::PressureIterations
                | Metric::DivergenceIterations
                | Metric::RefinementSeconds
                | Metric::OpenBoundarySeconds
                | Metric::StepSeconds
                | Metric::LostParticles => 0.0,
                // A grid's: validation keeps them out of an SPH fluid's list.
                Metric::MaxDivergence
                | Metric::PressureResidual
                | Metric::ViscosityIterations
                | Metric::Cfl
                | Metric::ChangeRate
                | Metric::AdvectSeconds
                | Metric::ProjectSeconds => Real::NAN,
            })
            .collect();
        StateMetrics { values }
    }

    /// Writes the row of a step: the state it started from, what the step did, and the values
    /// of the extra columns.
    pub fn write(
        &mut self,
        step: u64,
        time: Real,
        state: &StateMetrics,
        stats: &StepStats,
        extra: &[Real],
    ) -> Result<(), IoError> {
        self.row.clear();
        self.row.extend([step as Real, time, stats.dt]);
        for (m, v) in self.metrics.iter().zip(&state.values) {
            self.row.push(match m {
                Metric::PressureIterations => stats.pressure.iterations as Real,
                Metric::DivergenceIterations => stats.divergence.iterations as Real,
                Metric::RefinementSeconds => stats.refinement_seconds,
                Metric::OpenBoundarySeconds => stats.open_seconds,
                Metric::StepSeconds => stats.step_seconds,
                Metric::LostParticles => stats.lost as Real,
                _ => *v,
            });
        }
        self.row.extend_from_slice(extra);
        self.csv.row(&self.row)
    }
}
