//! Per-step diagnostics and probes. Each is computed only when a scene asks for it. Spectra
//! of a run's probes and fields are computed after it (`eddy spectrum`).

pub mod grid_probes;
pub mod probes;
pub mod series;
mod spec;
pub mod spectrum;

use crate::parallel::sum_by;
use crate::{Real, Vec3};
use rayon::prelude::*;

pub use grid_probes::GridProbeRecorder;
pub use probes::ProbeRecorder;
pub use series::MetricsRecorder;
pub use spec::{Axis, Metric, Probe};

/// Kinetic energy sum_i m |v_i|^2 / 2, J.
pub fn kinetic_energy(mass: Real, v: &[Vec3]) -> Real {
    0.5 * mass * sum_by(v, |v| v.norm_squared())
}

/// Potential energy -sum_i m g . x_i, J (zero at the origin).
pub fn potential_energy(mass: Real, x: &[Vec3], gravity: &Vec3) -> Real {
    -mass * sum_by(x, |x| gravity.dot(x))
}

/// Average and maximum compression max(rho / rho_0 - 1, 0) over the particles. Only
/// compression counts: particles at a free surface lack neighbours and read low densities
/// that are not an error of the solver.
pub fn density_errors(density: &[Real], rest_density: Real) -> (Real, Real) {
    if density.is_empty() {
        return (0.0, 0.0);
    }
    let compression = |rho: &Real| (rho / rest_density - 1.0).max(0.0);
    let max = density
        .par_iter()
        .map(compression)
        .reduce(|| 0.0, Real::max);
    (sum_by(density, compression) / density.len() as Real, max)
}

/// Vorticity statistics of a fluid: mean and largest |omega|, and the enstrophy
/// sum_i V |omega_i|^2 / 2 with the rest volume V.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct VorticityStats {
    pub mean: Real,
    pub max: Real,
    pub enstrophy: Real,
}

/// [`VorticityStats`] of the vorticities `omega` of particles of rest volume `volume`.
pub fn vorticity_stats(omega: &[Vec3], volume: Real) -> VorticityStats {
    if omega.is_empty() {
        return VorticityStats::default();
    }
    VorticityStats {
        mean: sum_by(omega, |w| w.norm()) / omega.len() as Real,
        max: max_speed(omega),
        enstrophy: 0.5 * volume * sum_by(omega, |w| w.norm_squared()),
    }
}

/// Largest particle speed, m/s.
pub fn max_speed(v: &[Vec3]) -> Real {
    v.par_iter().map(|v| v.norm()).reduce(|| 0.0, Real::max)
}
