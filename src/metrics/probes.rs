//! Probes declared in the scene, written to `probes.csv` one row per step: the fluid front along
//! an axis, and pressure and velocity at a point.

use super::spec::Probe;
use crate::io::{CsvSeries, IoError};
use crate::sph::SphSolver;
use crate::{Real, Vec3};
use std::path::Path;

/// Samples every probe of a scene.
pub struct ProbeRecorder {
    probes: Vec<Probe>,
    csv: CsvSeries,
    row: Vec<Real>,
}

/// What a point probe reads: Shepard-normalised kernel interpolation of pressure and velocity,
/// sum_j V_j A_j W(p - x_j) / sum_j V_j W(p - x_j). None where no fluid particle is in reach.
pub fn sample_point(solver: &SphSolver, p: &Vec3) -> Option<(Real, Vec3)> {
    let fluid = &solver.fluid;
    let k = &solver.kernel;
    let (mut wsum, mut pressure, mut velocity) = (0.0, 0.0, Vec3::zeros());
    solver.grid().for_each_near(p, &fluid.x, k.support(), |j| {
        let w = fluid.mass / fluid.density[j] * k.w((p - fluid.x[j]).norm());
        wsum += w;
        pressure += w * fluid.pressure[j];
        velocity += w * fluid.v[j];
    });
    (wsum > 0.0).then(|| (pressure / wsum, velocity / wsum))
}

/// The fluid front: the largest coordinate along `axis` of any fluid particle, less `origin`.
pub fn front(x: &[Vec3], axis: usize, origin: Real) -> Real {
    use rayon::prelude::*;
    x.par_iter()
        .map(|x| x[axis])
        .reduce(|| Real::NEG_INFINITY, Real::max)
        - origin
}

impl ProbeRecorder {
    /// The series it writes into.
    pub fn series(&self) -> &CsvSeries {
        &self.csv
    }

    /// The series, to go on from a checkpoint's rows.
    pub fn series_mut(&mut self) -> &mut CsvSeries {
        &mut self.csv
    }

    /// Creates `path` with a header: step, time, then a front probe's name, or a point probe's
    /// `NAME_p, NAME_vx, NAME_vy, NAME_vz`.
    pub fn create(path: &Path, probes: &[Probe]) -> Result<Self, IoError> {
        let mut columns: Vec<String> = vec!["step".into(), "time".into()];
        for p in probes {
            match p {
                Probe::Front { name, .. } => columns.push(name.clone()),
                Probe::Point { name, .. } => {
                    columns.extend(["p", "vx", "vy", "vz"].map(|c| format!("{name}_{c}")))
                }
                // Grid-only probes; validation keeps them out of SPH scenes.
                Probe::Line { .. } | Probe::Force { .. } => {}
            }
        }
        Ok(Self {
            probes: probes.to_vec(),
            csv: CsvSeries::create(path, &columns)?,
            row: Vec::new(),
        })
    }

    /// Samples every probe on the current state (NaN where a point probe has no fluid).
    pub fn record(&mut self, solver: &SphSolver) -> Result<(), IoError> {
        self.row.clear();
        self.row.extend([solver.steps() as Real, solver.time()]);
        for p in &self.probes {
            match p {
                Probe::Front { axis, origin, .. } => {
                    self.row.push(front(&solver.fluid.x, axis.index(), *origin))
                }
                Probe::Point { position, .. } => {
                    let (p, v) = sample_point(solver, &Vec3::from(*position))
                        .unwrap_or((Real::NAN, Vec3::repeat(Real::NAN)));
                    self.row.extend([p, v.x, v.y, v.z]);
                }
                Probe::Line { .. } | Probe::Force { .. } => {}
            }
        }
        self.csv.row(&self.row)
    }
}
