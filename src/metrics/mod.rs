//! Per-step diagnostics and probes. Each is computed only when a scene asks for it. Spectra
//! of a run's probes and fields are computed after it (`eddy spectrum`).

pub mod grid_probes;
pub mod probes;
pub mod series;
mod spec;
pub mod spectrum;
pub mod stations;
pub mod statistics;

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

/// [`VorticityStats`] of a MAC grid's fluid cells: their cell-centred vorticity's mean and
/// largest magnitude, and the enstrophy sum |omega|^2 dV / 2. Summed per x slab, then the slabs
/// in order, so runs reproduce on any thread count.
pub fn grid_vorticity_stats(solver: &crate::grid::GridSolver) -> VorticityStats {
    let mac = &solver.mac;
    let fluid = solver.bounds.fluid_mask();
    let cells = crate::grid::forces::CellVorticity::new(mac);
    let [nx, ny, nz] = mac.dims;
    let slabs: Vec<[Real; 4]> = (0..nx)
        .into_par_iter()
        .map(|i| {
            let mut row = vec![Vec3::zeros(); nz];
            let mut s = [0.0; 4];
            for j in 0..ny {
                cells.row([i, j, 0], &mut row);
                for (k, w) in row.iter().enumerate() {
                    if !fluid[[i, j, k]] {
                        continue;
                    }
                    let m = w.norm();
                    s[0] += 1.0;
                    s[1] += m;
                    s[2] = s[2].max(m);
                    s[3] += w.norm_squared();
                }
            }
            s
        })
        .collect();
    let total = slabs.iter().fold([0.0; 4], |a, s| {
        [a[0] + s[0], a[1] + s[1], a[2].max(s[2]), a[3] + s[3]]
    });
    if total[0] == 0.0 {
        return VorticityStats::default();
    }
    VorticityStats {
        mean: total[1] / total[0],
        max: total[2],
        enstrophy: 0.5 * mac.dx.powi(3) * total[3],
    }
}

/// Largest particle speed, m/s.
pub fn max_speed(v: &[Vec3]) -> Real {
    v.par_iter().map(|v| v.norm()).reduce(|| 0.0, Real::max)
}
