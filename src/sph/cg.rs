//! The two DFSPH solves with signed pressure, by preconditioned conjugate gradients.
//!
//! Why: the Jacobi solves of [`super::dfsph`] clamp the pressure at zero, so that a free surface
//! does not pull; a fluid that fills its walls then cannot hold the suction behind an obstacle,
//! and the wake cavitates (docs/src/sph.md, "Open boundaries"). Unclamped, the Jacobi iteration gains
//! energy and diverges: its diagonal estimate is no contraction for errors of both signs.
//!
//! The pressure acceleration of a stiffness field k,
//! a(k)_i = -sum_j V (k_i + k_j) grad W_ij - k_i sum_b V_b grad W_ib
//! ([`Neighborhood::stiffness_acceleration`], the walls of Akinci et al. 2012 Eq. 10), and the
//! density rate of a velocity field with the walls still,
//! D(u)_i = sum_j V (u_i - u_j) . grad W_ij + u_i . sum_b V_b grad W_ib
//! ([`Neighborhood::density_rate`]), are adjoint: summing over ordered pairs with
//! grad W_ji = -grad W_ij and one fluid volume V,
//! sum_i r_i D(a(k))_i = -sum_i a(r)_i . a(k)_i for any two fields r and k.
//! So A = -D a is symmetric and positive semi-definite, conjugate gradients solve it, and the
//! divergence solve v <- v + dt a(k), with no particle held at a pressure other than zero, is
//! the orthogonal projection of v onto the fields of zero density rate: it removes kinetic
//! energy and never adds any.
//!
//! Both solves are A x = e with x = k dt^2 and e the density-ratio error the step would leave
//! without pressure: e_i = dt D(v)_i (with the walls' own velocities) for the divergence solve,
//! e_i = rho_i / rho_0 - 1 + dt D(v)_i (+ dt^2 / 2 the density curvature, second order) for the
//! density solve. The DFSPH factor 1 / A_ii preconditions.
//!
//! Not every particle is an unknown ([`Role`]). One within a kernel support of an outflow plane
//! has its support cut by the plane: it is held at the ambient pressure, the Dirichlet
//! condition of projection SPH at an open side (Cummins & Rudman 1999), and still feels its
//! neighbours' pressure. An inflow's buffer particle has its velocity prescribed: to the solve
//! it is a moving wall sample of volume V, which pushes back with its neighbour's own stiffness
//! as Akinci's samples do (k = 0 and a = 0 on it do exactly that in the sums above). Restricted
//! to the unknowns, A stays symmetric and positive semi-definite: a held particle's row is
//! dropped and its stiffness moves to the right-hand side; a fixed one's acceleration is zero.
//! There is no free-surface rule: a particle short of neighbours is an unknown like any other,
//! so a cavity pulls itself shut; the signed solve is for fluids that fill their walls.
//!
//! **The ambient pressure.** Where the pressure is negative the pair force of the symmetric
//! gradient attracts, and SPH particles clump in pairs and strings, leaving voids at the
//! rest density (the tensile instability, Swegle et al. 1995): on the cylinder channel, with
//! zero held at the outflow, the shear layers behind the cylinder opened into empty bands
//! three spacings wide within 0.3 s. Holding the outflow at an ambient pressure above the
//! flow's deepest suction keeps the pressure positive everywhere and the pair forces
//! repulsive; incompressible flow depends on pressure differences only.

use super::dfsph::{Bounds, Solve, SolveResult};
use super::neighborhood::Neighborhood;
use super::open::OpenBoundaries;
use crate::parallel::{ordered_sum, BLOCK};
use crate::{Real, Vec3};
use rayon::prelude::*;

/// What a particle is to the solve.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// An unknown.
    Free,
    /// Held at the ambient pressure, moved by its neighbours' (near an outflow).
    Held,
    /// Velocity prescribed (an inflow's buffer): a moving wall.
    Fixed,
}

/// Every particle's role in this step's neighbourhood.
pub fn roles(nb: &Neighborhood, open: &OpenBoundaries) -> Vec<Role> {
    let reach = nb.kernel.support();
    nb.x.par_iter()
        .map(|x| {
            if open.in_buffer(x) {
                Role::Fixed
            } else if open.near_outflow(x, reach) {
                Role::Held
            } else {
                Role::Free
            }
        })
        .collect()
}

/// Runs one solve on the velocities `v`, with the arguments of [`super::dfsph::solve`], the
/// particles' [`roles`] and the stiffness the held ones keep, `held` (as x = k dt^2): `warm`
/// holds the last step's x (the whole of it starts the iteration) and receives this step's.
/// The error reported is the mean of |e - A x| over all particles, in density-ratio units:
/// expansion counts as much as compression.
#[allow(clippy::too_many_arguments)]
pub fn solve(
    nb: &Neighborhood,
    which: Solve,
    roles: &[Role],
    held: Real,
    density_ratio: &[Real],
    factor: &[Real],
    v: &mut [Vec3],
    warm: &mut [Real],
    dt: Real,
    bounds: Bounds,
    second_order: bool,
) -> SolveResult {
    let n = v.len();
    let error: Vec<Real> = (0..n)
        .into_par_iter()
        .map(|i| {
            if roles[i] != Role::Free {
                return 0.0;
            }
            let rate = dt * nb.density_rate(i, v, false);
            match which {
                Solve::Divergence => rate,
                Solve::Density if second_order => {
                    density_ratio[i] - 1.0 + rate + 0.5 * dt * dt * nb.density_curvature(i, v)
                }
                Solve::Density => density_ratio[i] - 1.0 + rate,
            }
        })
        .collect();
    let mut x: Vec<Real> = warm
        .par_iter()
        .zip(roles.par_iter())
        .map(|(&w, &role)| match role {
            Role::Free => w,
            Role::Held => held,
            Role::Fixed => 0.0,
        })
        .collect();
    let mut accel = vec![Vec3::zeros(); n];
    let mut r = vec![0.0; n];
    operator(nb, &x, roles, &mut accel, &mut r);
    r.par_iter_mut()
        .zip(error.par_iter())
        .for_each(|(r, e)| *r = e - *r);
    let mut z: Vec<Real> = r
        .par_iter()
        .zip(factor.par_iter())
        .map(|(r, f)| r * f)
        .collect();
    let mut p = z.clone();
    let mut q = vec![0.0; n];
    let mut rz = dot(&r, &z);
    let mut iterations = 0;
    let mut avg = mean_abs(&r);
    while iterations < bounds.max_iterations
        && (iterations < bounds.min_iterations || avg > bounds.tolerance)
        && rz > 0.0
    {
        operator(nb, &p, roles, &mut accel, &mut q);
        let pq = dot(&p, &q);
        if pq <= 0.0 {
            break;
        }
        let alpha = rz / pq;
        x.par_iter_mut()
            .zip(r.par_iter_mut())
            .zip(p.par_iter().zip(q.par_iter()))
            .for_each(|((x, r), (p, q))| {
                *x += alpha * p;
                *r -= alpha * q;
            });
        z.par_iter_mut()
            .zip(r.par_iter().zip(factor.par_iter()))
            .for_each(|(z, (r, f))| *z = r * f);
        let rz_next = dot(&r, &z);
        let beta = rz_next / rz;
        rz = rz_next;
        p.par_iter_mut()
            .zip(z.par_iter())
            .for_each(|(p, z)| *p = z + beta * *p);
        avg = mean_abs(&r);
        iterations += 1;
    }
    // v += dt a(x / dt^2) = a(x) / dt.
    accelerations(nb, &x, roles, &mut accel);
    v.par_iter_mut()
        .zip(accel.par_iter())
        .for_each(|(v, a)| *v += a / dt);
    warm.copy_from_slice(&x);
    SolveResult {
        iterations,
        error: avg,
    }
}

/// out = A k on the free particles (zero elsewhere), with A = -D a of the module
/// documentation; `accel` receives a(k). `k` must be zero on the fixed particles.
pub fn operator(
    nb: &Neighborhood,
    k: &[Real],
    roles: &[Role],
    accel: &mut [Vec3],
    out: &mut [Real],
) {
    accelerations(nb, k, roles, accel);
    out.par_iter_mut().enumerate().for_each(|(i, o)| {
        *o = match roles[i] {
            Role::Free => -nb.density_rate(i, accel, true),
            _ => 0.0,
        }
    });
}

/// accel = a(k), zero on the fixed particles.
fn accelerations(nb: &Neighborhood, k: &[Real], roles: &[Role], accel: &mut [Vec3]) {
    accel.par_iter_mut().enumerate().for_each(|(i, a)| {
        *a = match roles[i] {
            Role::Fixed => Vec3::zeros(),
            _ => nb.stiffness_acceleration(i, k),
        }
    });
}

/// sum_i a_i b_i, in the fixed order of [`crate::parallel`].
fn dot(a: &[Real], b: &[Real]) -> Real {
    ordered_sum(
        a.par_chunks(BLOCK)
            .zip(b.par_chunks(BLOCK))
            .map(|(a, b)| a.iter().zip(b).map(|(a, b)| a * b).sum::<Real>()),
    )
}

/// Mean of |r_i| (zero when empty).
fn mean_abs(r: &[Real]) -> Real {
    if r.is_empty() {
        0.0
    } else {
        crate::parallel::sum_by(r, |r| r.abs()) / r.len() as Real
    }
}
