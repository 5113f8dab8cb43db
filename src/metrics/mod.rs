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

/// Largest particle speed, m/s.
pub fn max_speed(v: &[Vec3]) -> Real {
    v.par_iter().map(|v| v.norm()).reduce(|| 0.0, Real::max)
}
