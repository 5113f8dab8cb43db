//! Implicit (backward Euler) viscosity of one velocity component on the MAC grid, stable for
//! the raised viscosities of the precomputation. A wall that holds a non-zero tangential
//! velocity g (a moving lid, an inflow) has the ghost value 2 g - x_i; the diffusion solver
//! knows the mirror ghost -x_i, and the difference, 2 a g, moves to the right-hand side.
//! Crank–Nicolson needs no explicit operator: with y the backward-Euler solution over half the
//! coefficient, (1 + a/2 L) y = u, the Crank–Nicolson value (1 + a/2 L)^-1 (1 - a/2 L) u is
//! exactly 2 y - u. The step's forces f dt belong to the right-hand side, not under the
//! explicit half: with u0 the velocity before them and u = u0 + f dt, the update
//! (1 + a/2 L)^-1 ((1 - a/2 L) u0 + f dt) is 2 y - u0 with (1 + a/2 L) y = (u0 + u) / 2.
//! Treating u as the old velocity instead leaves -(a/2) L f dt, which a constant force makes
//! non-zero beside a no-slip wall (its ghost mirrors it): the forced channel's flow was first
//! order in dt and its steady state wrong there (`tests/sweep.rs`, plane Poiseuille).
//!
//! The caller keeps each component's [`DiffusionSystem`] between steps: it is rebuilt only when
//! the unknown faces, the sides or `a` change.

use ndarray::{Array3, Axis, Slice, Zip};

use super::boundary::Boundaries;
use super::diffusion::{DiffusionBoundary, DiffusionSystem};
use super::params::ViscosityScheme;
use super::poisson::{SolveError, SolveStats, SolverSettings};
use crate::Real;

/// Diffuses component `c` of the faces over one step, a = nu dt / dx^2, with the fixed faces
/// of `bounds` held; `unforced` is the component before this step's forces (None: `u` is),
/// which Crank–Nicolson needs (module doc); `system` is the component's system of the last
/// call (None at first), reused when it still applies and replaced otherwise.
#[allow(clippy::too_many_arguments)]
pub fn diffuse_component(
    bounds: &Boundaries,
    c: usize,
    a: Real,
    scheme: ViscosityScheme,
    u: &mut Array3<Real>,
    unforced: Option<&Array3<Real>>,
    settings: &SolverSettings,
    system: &mut Option<DiffusionSystem>,
) -> Result<SolveStats, SolveError> {
    match scheme {
        ViscosityScheme::BackwardEuler => backward_euler(bounds, c, a, u, settings, system),
        ViscosityScheme::CrankNicolson => {
            // Without forces u0 is u itself, and the half-sum below is u already.
            let copy;
            let old = match unforced {
                Some(u0) => {
                    Zip::from(&mut *u)
                        .and(u0)
                        .par_for_each(|u, &u0| *u = 0.5 * (*u + u0));
                    u0
                }
                None => {
                    copy = u.clone();
                    &copy
                }
            };
            let stats = backward_euler(bounds, c, 0.5 * a, u, settings, system)?;
            Zip::from(u)
                .and(old)
                .par_for_each(|y, &u0| *y = 2.0 * *y - u0);
            Ok(stats)
        }
    }
}

/// Solves (1 + a L) u_new = u.
fn backward_euler(
    bounds: &Boundaries,
    c: usize,
    a: Real,
    u: &mut Array3<Real>,
    settings: &SolverSettings,
    system: &mut Option<DiffusionSystem>,
) -> Result<SolveStats, SolveError> {
    let (boundary, wall) = bounds.diffusion_boundary(c);
    // A component that is zero everywhere, walls included (w of a 2-D run), stays zero.
    if wall.iter().flatten().all(|&g| g == 0.0) && u.iter().all(|&x| x == 0.0) {
        return Ok(SolveStats::default());
    }
    if boundary.periodic[c] {
        // Along its own periodic axis the last face duplicates the first: solve on one period.
        let n = u.shape()[c] - 1;
        let mut period = u.slice_axis(Axis(c), Slice::from(..n)).to_owned();
        let unknown = bounds.fixed[c]
            .slice_axis(Axis(c), Slice::from(..n))
            .mapv(|f| !f);
        let stats = solve_with_walls(&unknown, &boundary, &wall, a, &mut period, settings, system)?;
        u.slice_axis_mut(Axis(c), Slice::from(..n)).assign(&period);
        let first = period.index_axis(Axis(c), 0).to_owned();
        u.index_axis_mut(Axis(c), n).assign(&first);
        return Ok(stats);
    }
    let unknown = bounds.fixed[c].mapv(|f| !f);
    solve_with_walls(&unknown, &boundary, &wall, a, u, settings, system)
}

/// The diffusion solve with the moving-wall correction of the right-hand side.
fn solve_with_walls(
    unknown: &Array3<bool>,
    boundary: &DiffusionBoundary,
    wall: &[[Real; 2]; 3],
    a: Real,
    u: &mut Array3<Real>,
    settings: &SolverSettings,
    system: &mut Option<DiffusionSystem>,
) -> Result<SolveStats, SolveError> {
    for (axis, values) in wall.iter().enumerate() {
        let n = u.shape()[axis];
        for (side, &g) in values.iter().enumerate() {
            if g == 0.0 || boundary.periodic[axis] {
                continue;
            }
            let layer = if side == 0 { 0 } else { n - 1 };
            Zip::from(u.index_axis_mut(Axis(axis), layer))
                .and(unknown.index_axis(Axis(axis), layer))
                .for_each(|u, &free| {
                    if free {
                        *u += 2.0 * a * g;
                    }
                });
        }
    }
    let system = match system {
        Some(s) if s.matches(unknown, boundary, a) => s,
        _ => system.insert(DiffusionSystem::new(unknown, boundary, a)?),
    };
    system.solve(u, settings)
}
