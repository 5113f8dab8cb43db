//! Synthesis onto a point set (SPH particles): Eq. 14 sums over the points under each cut-off,
//! then the weighted kernel velocities (Eq. 12) at the points, both through a hashed grid over
//! the vortex particles.

use rayon::prelude::*;

use super::{axis, weights, Sums, SynthesisReport};
use crate::spatial::PointHash;
use crate::vortex::{kernel, VortexParticles};
use crate::{Real, Vec3};

/// The Eq. 14 weights and the velocity increment at every point; `under` is [`covered`].
pub(super) fn synthesize(
    particles: &VortexParticles,
    points: &[Vec3],
    vorticity: &[Vec3],
    under: &[bool],
) -> (SynthesisReport, Vec<Vec3>) {
    let reach = kernel::velocity_radius(max_sigma(particles));
    let hash = PointHash::new(&particles.x, reach);
    let report = weights(&sums(particles, &hash, reach, points, vorticity, under));
    let v = velocity(particles, &hash, reach, &report.weights, points);
    (report, v)
}

/// Which points lie under some particle's cut-off `sqrt(6) sigma`: the only points whose
/// vorticity the Eq. 14 sums read.
pub(super) fn covered(particles: &VortexParticles, points: &[Vec3]) -> Vec<bool> {
    let reach = kernel::radius(max_sigma(particles));
    let hash = PointHash::new(&particles.x, reach);
    points
        .par_iter()
        .map(|x| {
            let mut under = false;
            hash.for_each_near(x, reach, |q| {
                under |= (x - particles.x[q]).norm() < particles.radius(q);
            });
            under
        })
        .collect()
}

fn max_sigma(particles: &VortexParticles) -> Real {
    particles.sigma.iter().copied().fold(0.0, Real::max)
}

/// Eq. 14 sums of every particle over the points under its cut-off (those `under` some
/// cut-off; the others add nothing).
fn sums(
    particles: &VortexParticles,
    hash: &PointHash,
    reach: Real,
    points: &[Vec3],
    vorticity: &[Vec3],
    under: &[bool],
) -> Vec<Sums> {
    let n = particles.len();
    // Blocks of points accumulate in parallel, and their sums are added in block order, a wave
    // of blocks at a time (so that the result does not depend on scheduling; see
    // `crate::parallel`).
    let block_sums = |((xs, haves), unders): ((&[Vec3], &[Vec3]), &[bool])| {
        let (mut sums, mut near) = (vec![[0.0; 3]; n], Vec::new());
        for ((x, have), _) in xs.iter().zip(haves).zip(unders).filter(|(_, u)| **u) {
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
        }
        sums
    };
    let mut total = vec![[0.0; 3]; n];
    let wave = POINTS_PER_BLOCK * BLOCKS_PER_WAVE;
    let waves = points.chunks(wave).zip(vorticity.chunks(wave));
    for ((xs, haves), unders) in waves.zip(under.chunks(wave)) {
        let blocks: Vec<Vec<Sums>> = xs
            .par_chunks(POINTS_PER_BLOCK)
            .zip(haves.par_chunks(POINTS_PER_BLOCK))
            .zip(unders.par_chunks(POINTS_PER_BLOCK))
            .map(block_sums)
            .collect();
        for block in &blocks {
            for (t, s) in total.iter_mut().zip(block) {
                for c in 0..3 {
                    t[c] += s[c];
                }
            }
        }
    }
    total
}

/// Points per block of the Eq. 14 sums.
const POINTS_PER_BLOCK: usize = 1 << 13;

/// Blocks summed in parallel before their sums are added (each holds a sum per particle).
const BLOCKS_PER_WAVE: usize = 16;

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
