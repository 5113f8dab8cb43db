//! Pressure projection: makes the face velocities discretely divergence-free in every fluid
//! cell. With y = p dt / (rho dx) the update of a free face is u -= y_right - y_left, and the
//! net outflow D(u) of a cell changes by (A y), A the unit-spacing Laplacian of
//! [`PoissonSystem`]; so A y = -D(u) makes it vanish. Fixed faces (walls, inflow, obstacles) are
//! not updated, which is the Neumann condition A leaves out; open sides hold y = 0.

use ndarray::{Array3, Zip};

use super::boundary::Boundaries;
use super::mac::{cells_beside_face, MacGrid};
use super::poisson::{PoissonSystem, SolveError, SolveStats, SolverSettings};
use crate::Real;

/// Projects `grid` and returns the solver's statistics. `y` carries the scaled pressure
/// p dt / (rho dx): the warm start on entry, the solution on exit.
pub fn project(
    grid: &mut MacGrid,
    bounds: &Boundaries,
    system: &mut PoissonSystem,
    y: &mut Array3<Real>,
    settings: &SolverSettings,
) -> Result<SolveStats, SolveError> {
    let mut rhs = grid.net_outflow();
    rhs.mapv_inplace(|d| -d);
    let stats = system.solve(&rhs, y, settings)?;
    subtract_gradient(grid, bounds, y);
    grid.sync_periodic();
    Ok(stats)
}

/// u -= y_right - y_left on every face that is not fixed; y is 0 beyond an open side.
fn subtract_gradient(grid: &mut MacGrid, bounds: &Boundaries, y: &Array3<Real>) {
    let dims = grid.dims;
    let periodic = bounds.periodic();
    for a in 0..3 {
        let n = dims[a];
        Zip::indexed(&mut grid.u[a])
            .and(&bounds.fixed[a])
            .par_for_each(|(i, j, k), u, &fixed| {
                if fixed {
                    return;
                }
                let idx = [i, j, k];
                let at = |c: usize| {
                    let mut cell = idx;
                    cell[a] = c;
                    y[cell]
                };
                let (left, right) = cells_beside_face(idx[a], n, periodic[a]);
                *u -= right.map_or(0.0, at) - left.map_or(0.0, at);
            });
    }
}

/// Largest |divergence| over the fluid cells, 1/s.
pub fn max_divergence(grid: &MacGrid, fluid: &Array3<bool>) -> Real {
    let d = grid.net_outflow();
    Zip::from(&d)
        .and(fluid)
        .fold(0.0, |m: Real, &d, &f| if f { m.max(d.abs()) } else { m })
        / grid.dx
}
