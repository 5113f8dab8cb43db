//! Per-step diagnostics and probes. Each is computed only when a scene asks for it.

pub mod probes;
pub mod series;

use crate::{Real, Vec3};
use rayon::prelude::*;

pub use probes::ProbeRecorder;
pub use series::MetricsRecorder;

/// Kinetic energy sum_i m |v_i|^2 / 2, J.
pub fn kinetic_energy(mass: Real, v: &[Vec3]) -> Real {
    0.5 * mass * v.par_iter().map(|v| v.norm_squared()).sum::<Real>()
}

/// Potential energy -sum_i m g . x_i, J (zero at the origin).
pub fn potential_energy(mass: Real, x: &[Vec3], gravity: &Vec3) -> Real {
    -mass * x.par_iter().map(|x| gravity.dot(x)).sum::<Real>()
}

/// Average and maximum compression max(rho / rho_0 - 1, 0) over the particles. Only
/// compression counts: particles at a free surface lack neighbours and read low densities
/// that are not an error of the solver.
pub fn density_errors(density: &[Real], rest_density: Real) -> (Real, Real) {
    if density.is_empty() {
        return (0.0, 0.0);
    }
    let (sum, max) = density
        .par_iter()
        .map(|rho| (rho / rest_density - 1.0).max(0.0))
        .fold(|| (0.0, 0.0), |(s, m), e| (s + e, Real::max(m, e)))
        .reduce(|| (0.0, 0.0), |a, b| (a.0 + b.0, a.1.max(b.1)));
    (sum / density.len() as Real, max)
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
    let (sum, max, sq) = omega
        .par_iter()
        .map(|w| {
            let m = w.norm();
            (m, m, m * m)
        })
        .reduce(
            || (0.0, 0.0, 0.0),
            |a, b| (a.0 + b.0, Real::max(a.1, b.1), a.2 + b.2),
        );
    VorticityStats {
        mean: sum / omega.len() as Real,
        max,
        enstrophy: 0.5 * volume * sq,
    }
}

/// Largest particle speed, m/s.
pub fn max_speed(v: &[Vec3]) -> Real {
    v.par_iter().map(|v| v.norm()).reduce(|| 0.0, Real::max)
}
