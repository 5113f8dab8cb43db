//! Synthesis onto a point set (SPH particles): Eq. 14 sums over the points under each cut-off,
//! then the weighted kernel velocities (Eq. 12) at the points, both through a hashed grid over
//! the vortex particles.

use rayon::prelude::*;

use super::{axis, weights, Sums, SynthesisReport};
use crate::vortex::spatial::PointHash;
use crate::vortex::{kernel, VortexParticles};
use crate::{Real, Vec3};

/// The Eq. 14 weights and the velocity increment at every point.
pub(super) fn synthesize(
    particles: &VortexParticles,
    points: &[Vec3],
    vorticity: &[Vec3],
) -> (SynthesisReport, Vec<Vec3>) {
    let reach = kernel::velocity_radius(max_sigma(particles));
    let hash = PointHash::new(&particles.x, reach);
    let report = weights(&sums(particles, &hash, reach, points, vorticity));
    let v = velocity(particles, &hash, reach, &report.weights, points);
    (report, v)
}

fn max_sigma(particles: &VortexParticles) -> Real {
    particles.sigma.iter().copied().fold(0.0, Real::max)
}

/// Eq. 14 sums of every particle over the points under its cut-off.
fn sums(
    particles: &VortexParticles,
    hash: &PointHash,
    reach: Real,
    points: &[Vec3],
    vorticity: &[Vec3],
) -> Vec<Sums> {
    let n = particles.len();
    points
        .par_iter()
        .zip(vorticity.par_iter())
        .fold(
            || (vec![[0.0; 3]; n], Vec::new()),
            |(mut sums, mut near), (x, have)| {
                near.clear();
                hash.for_each_near(x, reach, |q| {
                    if (x - particles.x[q]).norm() < kernel::velocity_radius(particles.sigma[q]) {
                        near.push(q);
                    }
                });
                let desired: Vec3 = near
                    .iter()
                    .map(|&q| {
                        kernel::vorticity(
                            &particles.omega[q],
                            particles.sigma[q],
                            &(x - particles.x[q]),
                        )
                    })
                    .sum();
                for &q in &near {
                    if (x - particles.x[q]).norm() < particles.radius(q) {
                        accumulate(&mut sums[q], &desired, have, &axis(&particles.omega[q]));
                    }
                }
                (sums, near)
            },
        )
        .map(|(sums, _)| sums)
        .reduce(
            || vec![[0.0; 3]; n],
            |mut a, b| {
                for (x, y) in a.iter_mut().zip(&b) {
                    for c in 0..3 {
                        x[c] += y[c];
                    }
                }
                a
            },
        )
}

/// The weighted kernel velocities (Eq. 12) at the points.
fn velocity(
    particles: &VortexParticles,
    hash: &PointHash,
    reach: Real,
    weights: &[Real],
    points: &[Vec3],
) -> Vec<Vec3> {
    points
        .par_iter()
        .map(|x| {
            let mut v = Vec3::zeros();
            hash.for_each_near(x, reach, |q| {
                let d = x - particles.x[q];
                let s = particles.sigma[q];
                if weights[q] != 0.0 && d.norm_squared() < kernel::velocity_radius(s).powi(2) {
                    v += kernel::velocity(&(particles.omega[q] * weights[q]), s, &d);
                }
            });
            v
        })
        .collect()
}

/// Adds one sample's contribution to a particle's Eq. 14 sums.
#[inline]
fn accumulate(sums: &mut Sums, desired: &Vec3, have: &Vec3, axis: &Vec3) {
    let d = desired.dot(axis);
    sums[0] += d;
    sums[1] += have.dot(axis);
    sums[2] += d.abs();
}
