//! Implicit incompressible SPH (Ihmsen et al. 2014), in the relaxed-Jacobi form of the pressure
//! Poisson equation A p = s with omega = 0.5.
//!
//! Written in the stiffness kappa = rho_0 p / rho^2 and density-ratio units, so it shares the
//! neighbourhood operators with DFSPH: the pressure acceleration is
//! a_i = -sum_j V (k_i + k_j) grad W_ij - sum_b V_b k_i grad W_ib, the operator is
//! (A k)_i = dt^2 D(rho/rho_0)/Dt of those accelerations (walls have none), the source is
//! s_i = 1 - (rho_i + dt D rho_i / Dt) / rho_0 for the advected velocities, and the diagonal is
//! a_ii = -dt^2 (|sum_j V grad W_ij + sum_b V_b grad W_ib|^2 + sum_j |V grad W_ij|^2)
//! = -dt^2 / factor_i. Pressures are clamped at zero (free surface) every iteration.

use super::dfsph::{mean_positive, Bounds, SolveResult};
use super::neighborhood::Neighborhood;
use crate::{Real, Vec3};
use rayon::prelude::*;

/// Relaxation of the Jacobi update (Ihmsen et al. 2014 use 0.5).
pub const OMEGA: Real = 0.5;

/// Solves for the pressure of one step and applies it to the advected velocities `v`.
/// `warm` holds kappa dt^2 (read: half of it starts the iteration; written: this step's value).
pub fn solve(
    nb: &Neighborhood,
    density_ratio: &[Real],
    factor: &[Real],
    v: &mut [Vec3],
    warm: &mut [Real],
    dt: Real,
    bounds: Bounds,
) -> SolveResult {
    let n = v.len();
    let dt2 = dt * dt;
    let source: Vec<Real> = (0..n)
        .into_par_iter()
        .map(|i| 1.0 - density_ratio[i] - dt * nb.density_rate(i, v, false))
        .collect();
    let mut predicted = vec![Vec3::zeros(); n];
    let mut kappa: Vec<Real> = warm.par_iter().map(|w| 0.5 * w / dt2).collect();
    let mut accel = vec![Vec3::zeros(); n];
    let mut residual = vec![0.0; n];
    let mut iterations = 0;
    let mut avg;
    loop {
        accel
            .par_iter_mut()
            .enumerate()
            .for_each(|(i, a)| *a = nb.stiffness_acceleration(i, &kappa));
        // residual_i = (A k)_i - s_i + dt^2 / 2 D^2(rho_i / rho_0)/Dt^2: the density-ratio
        // error predicted after the step, to second order in dt. Ihmsen et al. stop at the
        // first order; velocity noise then compresses the fluid by O(dt^2) every step (see
        // `Neighborhood::density_curvature`), which left the measured compression some three
        // times the tolerance. The second-order term depends on the final velocities, so it is
        // re-evaluated every iteration (the Jacobi update keeps the linear diagonal).
        predicted
            .par_iter_mut()
            .zip(v.par_iter().zip(accel.par_iter()))
            .for_each(|(p, (v, a))| *p = v + dt * a);
        residual.par_iter_mut().enumerate().for_each(|(i, r)| {
            *r = dt2 * nb.density_rate(i, &accel, true) - source[i]
                + 0.5 * dt2 * nb.density_curvature(i, &predicted);
        });
        avg = mean_positive(&residual);
        if iterations >= bounds.max_iterations
            || (iterations >= bounds.min_iterations && avg <= bounds.tolerance)
        {
            break;
        }
        kappa.par_iter_mut().enumerate().for_each(|(i, k)| {
            // a_ii = -dt^2 / factor_i; k += omega (s - A k) / a_ii.
            *k = (*k + OMEGA * residual[i] * factor[i] / dt2).max(0.0);
        });
        iterations += 1;
    }
    v.par_iter_mut()
        .zip(accel.par_iter())
        .for_each(|(vi, a)| *vi += dt * a);
    warm.par_iter_mut()
        .zip(kappa.par_iter())
        .for_each(|(w, k)| *w = k * dt2);
    SolveResult {
        iterations,
        error: avg,
    }
}
