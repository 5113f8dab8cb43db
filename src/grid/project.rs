//! Pressure projection: makes the face velocities discretely divergence-free in every fluid
//! cell. With y = p dt / (rho dx) the update of a free face is u -= y_right - y_left, and the
//! net outflow D(u) of a cell changes by (A y), A the unit-spacing Laplacian of
//! [`PoissonSystem`]; so A y = -D(u) makes it vanish. Fixed faces (walls, inflow, obstacles) are
//! not updated, which is the Neumann condition A leaves out; open sides hold y = 0. With cut
//! cells every term of D and A weighs its face's open fraction ([`Boundaries::add_outflow`],
//! [`PoissonSystem::with_fractions`]), and the update is the same.

use ndarray::{Array3, Zip};
use rayon::prelude::*;

use super::boundary::Boundaries;
use super::interp::standard;
use super::mac::{cells_beside_face, MacGrid};
use super::poisson::{CellKind, PoissonSystem, SolveError, SolveStats, SolverSettings};
use crate::Real;

/// Projects `grid` and returns the solver's statistics. `y` carries the scaled pressure
/// p dt / (rho dx): the warm start on entry, the solution on exit. With `carried`, the scaled
/// pressure whose gradient the faces already lost this step, `y` is its increment, solved to
/// the accuracy of the whole (the residual relative to the right-hand side with `carried`'s
/// gradient put back, |rhs + A carried|).
pub fn project(
    grid: &mut MacGrid,
    bounds: &Boundaries,
    system: &mut PoissonSystem,
    y: &mut Array3<Real>,
    settings: &SolverSettings,
    carried: Option<&Array3<Real>>,
) -> Result<SolveStats, SolveError> {
    let mut rhs = Array3::zeros(grid.dims);
    grid.net_outflow_scaled(-1.0, &mut rhs);
    bounds.add_outflow(grid, -1.0, &mut rhs);
    let reference = carried.map_or(0.0, |c| {
        let mut whole = Array3::zeros(grid.dims);
        system.apply(c, &mut whole);
        whole += &rhs;
        whole.iter().map(|v| v * v).sum::<Real>().sqrt()
    });
    let stats = system.solve_relative_to(&rhs, y, settings, reference)?;
    subtract_gradient(grid, bounds, y);
    grid.sync_periodic();
    Ok(stats)
}

/// u -= y_right - y_left on every face that is not fixed; y is 0 beyond an open side. Row by
/// row over flat slices: a row of faces along z, and the one or two rows of cells beside it.
pub(crate) fn subtract_gradient(grid: &mut MacGrid, bounds: &Boundaries, y: &Array3<Real>) {
    let [n0, n1, n2] = grid.dims;
    let periodic = bounds.periodic();
    let y = y.as_standard_layout();
    let y = standard(&y);
    let cell_row = |i: usize, j: usize| &y[(i * n1 + j) * n2..][..n2];
    for a in 0..3 {
        let fixed = bounds.fixed[a]
            .as_slice()
            .expect("face masks are in standard layout");
        let u = grid.u[a]
            .as_slice_mut()
            .expect("face arrays are in standard layout");
        let [m1, m2] = [n1 + usize::from(a == 1), n2 + usize::from(a == 2)];
        if u.is_empty() {
            continue;
        }
        u.par_chunks_mut(m1 * m2)
            .zip(fixed.par_chunks(m1 * m2))
            .enumerate()
            .for_each(|(i, (slab, fixed))| {
                for (j, (row, fixed)) in slab.chunks_mut(m2).zip(fixed.chunks(m2)).enumerate() {
                    if a == 2 {
                        let cells = cell_row(i, j);
                        for (k, (u, &f)) in row.iter_mut().zip(fixed).enumerate() {
                            let (l, r) = cells_beside_face(k, n2, periodic[2]);
                            if !f {
                                *u -= r.map_or(0.0, |c| cells[c]) - l.map_or(0.0, |c| cells[c]);
                            }
                        }
                        continue;
                    }
                    let (face, n) = if a == 0 { (i, n0) } else { (j, n1) };
                    let beside = |c: Option<usize>| {
                        c.map(|c| {
                            if a == 0 {
                                cell_row(c, j)
                            } else {
                                cell_row(i, c)
                            }
                        })
                    };
                    let (l, r) = cells_beside_face(face, n, periodic[a]);
                    let (l, r) = (beside(l), beside(r));
                    for (k, (u, &f)) in row.iter_mut().zip(fixed).enumerate() {
                        if !f {
                            *u -= r.map_or(0.0, |c| c[k]) - l.map_or(0.0, |c| c[k]);
                        }
                    }
                }
            });
    }
}

/// Largest |divergence| over the cells the projection solves for, 1/s (with cut cells, of
/// the fluid's share of each: the covered parts of faces move with the obstacle).
pub fn max_divergence(grid: &MacGrid, bounds: &Boundaries) -> Real {
    let mut d = grid.net_outflow();
    bounds.add_outflow(grid, 1.0, &mut d);
    Zip::from(&d)
        .and(&bounds.cell_kinds())
        .fold(0.0, |m: Real, &d, &c| {
            if c == CellKind::Fluid {
                m.max(d.abs())
            } else {
                m
            }
        })
        / grid.dx
}
