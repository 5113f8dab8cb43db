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

use ndarray::{Array3, ArrayView3, Axis, Slice, Zip};

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
    let faces = ViscousFaces::new(bounds, c);
    faces.hold(bounds, c, u);
    match scheme {
        ViscosityScheme::BackwardEuler => backward_euler(&faces, bounds, c, a, u, settings, system),
        ViscosityScheme::CrankNicolson => {
            // Without forces u0 is u itself, and the half-sum below is u already.
            let mut old = unforced.map_or_else(|| u.clone(), Array3::clone);
            faces.hold(bounds, c, &mut old);
            if unforced.is_some() {
                Zip::from(&mut *u)
                    .and(&old)
                    .par_for_each(|u, &u0| *u = 0.5 * (*u + u0));
            }
            let stats = backward_euler(&faces, bounds, c, 0.5 * a, u, settings, system)?;
            Zip::from(u)
                .and(&old)
                .par_for_each(|y, &u0| *y = 2.0 * *y - u0);
            Ok(stats)
        }
    }
}

/// The faces of one component the viscosity solves for: the free ones, and with cut cells only
/// those whose centre lies outside every obstacle; the others hold their value, a free face
/// inside an obstacle the obstacle's own ([`Self::hold`]).
struct ViscousFaces<'a> {
    unknown: Array3<bool>,
    /// With cut cells, the signed distance at the faces' centres.
    phi: Option<&'a Array3<f32>>,
}

impl<'a> ViscousFaces<'a> {
    fn new(bounds: &'a Boundaries, c: usize) -> Self {
        let phi = bounds.cut_faces().map(|f| &f.phi[c]);
        let unknown = match phi {
            Some(phi) => Zip::from(&bounds.fixed[c])
                .and(phi)
                .par_map_collect(|&f, &d| !f && d > 0.0),
            None => bounds.fixed[c].mapv(|f| !f),
        };
        Self { unknown, phi }
    }

    /// Sets the free faces inside an obstacle to its velocity: the wall value of the ghost fluid.
    fn hold(&self, bounds: &Boundaries, c: usize, u: &mut Array3<Real>) {
        if self.phi.is_none() {
            return;
        }
        Zip::from(u)
            .and(&self.unknown)
            .and(&bounds.fixed[c])
            .and(&bounds.fixed_value[c])
            .par_for_each(|u, &unknown, &fixed, &solid| {
                if !unknown && !fixed {
                    *u = solid;
                }
            });
    }
}

/// Solves (1 + a L) u_new = u.
fn backward_euler(
    faces: &ViscousFaces,
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
        let period = Slice::from(..n);
        let mut values = u.slice_axis(Axis(c), period).to_owned();
        let unknown = faces.unknown.slice_axis(Axis(c), period).to_owned();
        let weights = faces
            .phi
            .map(|phi| ghost_weights(&unknown, &phi.slice_axis(Axis(c), period), &boundary));
        let stats = solve_with_walls(
            &unknown,
            &boundary,
            &wall,
            a,
            weights,
            &mut values,
            settings,
            system,
        )?;
        u.slice_axis_mut(Axis(c), period).assign(&values);
        let first = values.index_axis(Axis(c), 0).to_owned();
        u.index_axis_mut(Axis(c), n).assign(&first);
        return Ok(stats);
    }
    let weights = faces
        .phi
        .map(|phi| ghost_weights(&faces.unknown, &phi.view(), &boundary));
    solve_with_walls(
        &faces.unknown,
        &boundary,
        &wall,
        a,
        weights,
        u,
        settings,
        system,
    )
}

/// Faces closer to the wall than this share of a cell take it at this distance (the weight
/// 1 / s stays bounded).
const MIN_WALL_DISTANCE: f32 = 0.05;

/// Where the wall lies between a face at signed distance `d` and its neighbour at `d_held`,
/// as the share of the way from the first (at least [`MIN_WALL_DISTANCE`]); None unless the
/// first is outside the obstacle and the second inside.
pub fn wall_share(d: f32, d_held: f32) -> Option<f32> {
    (d > 0.0 && d_held <= 0.0).then(|| (d / (d - d_held)).max(MIN_WALL_DISTANCE))
}

/// The ghost-fluid weights of the viscosity (Gibou, Fedkiw, Cheng & Kang 2002, Eq. 9): between
/// an unknown face at distance d > 0 outside an obstacle and a held one at d' <= 0 inside it,
/// the wall lies at the share s = d / (d - d') of the way, and the term (u_wall - u) / s
/// replaces (u' - u): the face weighs 1 / s. Every other face weighs one.
fn ghost_weights(
    unknown: &Array3<bool>,
    phi: &ArrayView3<f32>,
    boundary: &DiffusionBoundary,
) -> [Vec<f32>; 3] {
    let dims = unknown.dim();
    let n = [dims.0, dims.1, dims.2];
    std::array::from_fn(|b| {
        let mut w = Array3::from_elem(dims, 1.0f32);
        Zip::indexed(&mut w).par_for_each(|(i, j, k), w| {
            let here = [i, j, k];
            let mut next = here;
            next[b] += 1;
            if next[b] == n[b] {
                if !boundary.periodic[b] {
                    return;
                }
                next[b] = 0;
            }
            if unknown[here] == unknown[next] {
                return;
            }
            let (inner, held) = if unknown[here] {
                (here, next)
            } else {
                (next, here)
            };
            if let Some(share) = wall_share(phi[inner], phi[held]) {
                *w = 1.0 / share;
            }
        });
        w.into_raw_vec_and_offset().0
    })
}

/// The diffusion solve with the moving-wall correction of the right-hand side.
#[allow(clippy::too_many_arguments)]
fn solve_with_walls(
    unknown: &Array3<bool>,
    boundary: &DiffusionBoundary,
    wall: &[[Real; 2]; 3],
    a: Real,
    weights: Option<[Vec<f32>; 3]>,
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
        Some(s) if s.matches(unknown, boundary, a, &weights) => s,
        _ => system.insert(DiffusionSystem::new(unknown, boundary, a, weights)?),
    };
    system.solve(u, settings)
}
