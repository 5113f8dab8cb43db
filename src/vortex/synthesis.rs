//! Vorticity synthesis (Pfaff et al. 2009, section 4.3): the three-step process.
//!
//! 1. The sink's own vorticity (finite differences on a grid, the point set's curl for SPH).
//! 2. The desired vorticity `omega_D`, the sum of all particle kernels (see [`kernel`]).
//! 3. Each particle adds `w_k` times its kernel velocity, with Eq. 14:
//!    `w_k = sum (omega_D - omega) . a_k / sum omega_D . a_k` over the samples inside the
//!    particle's cut-off, `a_k` its unit axis. A particle whose denominator is negligible
//!    (under `1e-6` of the sum of `|omega_D . a_k|`) or that covers no sample is skipped with
//!    weight zero (PAPER-NOTES.md, Eq. 14 guard).
//!
//! On a grid, the samples of Eq. 14 are the cells of a synthesis lattice `upsample` times finer
//! than the sink's (the sink's vorticity interpolated trilinearly onto it), and each face of the
//! sink receives the mean kernel velocity over `upsample^2` points spread over the face: the
//! face-averaging restriction of a finer synthesis grid, which keeps the fluxes through the
//! coarse faces and so the divergence of the kernel. Point sums are unweighted: SPH particles
//! share one mass at near-rest density, so each stands for the same volume.
//!
//! Kernel evaluations only touch samples within the cut-off: particles are found through a
//! hashed grid (points) or visit the index box around their centre (lattices); periodic axes
//! are handled with particle images.

use ndarray::{Array3, Axis};
use rayon::prelude::*;

use super::spatial::PointHash;
use super::{kernel, Lattice, SinkField, SinkLayout, VelocitySink, VortexError, VortexParticles};
use crate::{Real, Vec3};

/// What one synthesis did.
#[derive(Debug, Clone, Default)]
pub struct SynthesisReport {
    /// Eq. 14 weight per particle (zero where skipped).
    pub weights: Vec<Real>,
    /// Particles skipped by the guard.
    pub skipped: usize,
}

/// Synthesizes the particles onto `sink`, on a synthesis lattice `upsample` times finer than a
/// grid sink's (ignored for point sinks).
pub fn synthesize<S: VelocitySink + ?Sized>(
    particles: &VortexParticles,
    sink: &mut S,
    upsample: usize,
) -> Result<SynthesisReport, VortexError> {
    if upsample == 0 {
        return Err(VortexError::InvalidSettings(
            "synthesis upsample factor must be at least 1".into(),
        ));
    }
    if particles.is_empty() {
        return Ok(SynthesisReport::default());
    }
    let vorticity = sink.vorticity();
    let (field, report) = match sink.layout() {
        SinkLayout::Faces(lattice) => {
            if vorticity.len() != lattice.cell_count() {
                return Err(VortexError::Layout(format!(
                    "{} vorticity samples for {} cells",
                    vorticity.len(),
                    lattice.cell_count()
                )));
            }
            let images = Image::all(particles, &lattice);
            let sums = lattice_sums(particles, &images, &lattice, upsample, &vorticity);
            let report = weights(particles, &sums);
            let faces = lattice_velocity(particles, &images, &report.weights, &lattice, upsample);
            (SinkField::Faces(Box::new(faces)), report)
        }
        SinkLayout::Points(points) => {
            if vorticity.len() != points.len() {
                return Err(VortexError::Layout(format!(
                    "{} vorticity samples for {} points",
                    vorticity.len(),
                    points.len()
                )));
            }
            let hash = PointHash::new(&particles.x, max_sigma(particles) * kernel::VELOCITY_REACH);
            let sums = point_sums(particles, &hash, points, &vorticity);
            let report = weights(particles, &sums);
            let v = point_velocity(particles, &hash, &report.weights, points);
            (SinkField::Points(v), report)
        }
    };
    sink.add_velocity(&field)?;
    Ok(report)
}

/// The Eq. 14 sums of one particle: sum omega_D . a, sum omega . a, sum |omega_D . a|.
type Sums = [Real; 3];

/// Eq. 14 with the guard.
fn weights(particles: &VortexParticles, sums: &[Sums]) -> SynthesisReport {
    let weights: Vec<Real> = sums
        .iter()
        .map(|&[desired, have, scale]| {
            if scale > 0.0 && desired.abs() > 1e-6 * scale {
                (desired - have) / desired
            } else {
                0.0
            }
        })
        .collect();
    let skipped = sums
        .iter()
        .zip(&weights)
        .filter(|(s, &w)| w == 0.0 && s[0] != s[1])
        .count();
    debug_assert_eq!(weights.len(), particles.len());
    SynthesisReport { weights, skipped }
}

/// Unit axis of a vorticity vector (zero for a zero vector).
#[inline]
fn axis(omega: &Vec3) -> Vec3 {
    let n = omega.norm();
    if n > 0.0 {
        omega / n
    } else {
        Vec3::zeros()
    }
}

fn max_sigma(particles: &VortexParticles) -> Real {
    particles.sigma.iter().copied().fold(0.0, Real::max)
}

/// A particle or one of its periodic copies.
#[derive(Debug, Clone, Copy)]
struct Image {
    particle: usize,
    x: Vec3,
}

impl Image {
    /// Every particle, plus its copies shifted by a period along the periodic axes where its
    /// velocity reach crosses the lattice's end.
    fn all(particles: &VortexParticles, lattice: &Lattice) -> Vec<Self> {
        let mut out = Vec::with_capacity(particles.len());
        for (particle, (x, &s)) in particles.x.iter().zip(&particles.sigma).enumerate() {
            let reach = kernel::velocity_radius(s);
            let shifts: [Vec<Real>; 3] = std::array::from_fn(|a| {
                let mut v = vec![0.0];
                if lattice.periodic[a] {
                    let len = lattice.dims[a] as Real * lattice.dx;
                    let lo = lattice.origin[a];
                    if x[a] - reach < lo {
                        v.push(len);
                    }
                    if x[a] + reach > lo + len {
                        v.push(-len);
                    }
                }
                v
            });
            for &sx in &shifts[0] {
                for &sy in &shifts[1] {
                    for &sz in &shifts[2] {
                        out.push(Self {
                            particle,
                            x: x + Vec3::new(sx, sy, sz),
                        });
                    }
                }
            }
        }
        out
    }
}

/// Inclusive index range of samples at `offset + i` (cell units) within `reach` (cell units)
/// of coordinate `c`, clipped to `0..len` unless `wrap`.
#[inline]
fn index_range(c: Real, reach: Real, offset: Real, len: usize, wrap: bool) -> (i64, i64) {
    let lo = (c - reach - offset).ceil() as i64;
    let hi = (c + reach - offset).floor() as i64;
    if wrap {
        (lo, hi)
    } else {
        (lo.max(0), hi.min(len as i64 - 1))
    }
}

/// The desired vorticity omega_D at the cells of the synthesis lattice `fine`: every particle
/// image adds its kernel vorticity to the cells within its velocity reach. Built once, in
/// parallel over slabs of x-planes with the images binned per slab, so the Eq. 14 sums read it
/// instead of re-summing the neighbouring kernels at every cell of every particle.
fn desired_field(particles: &VortexParticles, images: &[Image], fine: &Lattice) -> Vec<Vec3> {
    let [nx, ny, nz] = fine.dims;
    let ranges: Vec<[(i64, i64); 3]> = images
        .iter()
        .map(|m| {
            let g = (m.x - fine.origin) / fine.dx;
            let reach = kernel::velocity_radius(particles.sigma[m.particle]) / fine.dx;
            std::array::from_fn(|b| index_range(g[b], reach, 0.5, fine.dims[b], false))
        })
        .collect();
    let bins = slab_bins(&ranges, nx);
    let mut out = vec![Vec3::zeros(); nx * ny * nz];
    out.par_chunks_mut(PLANES * ny * nz)
        .zip(bins.par_iter())
        .enumerate()
        .for_each(|(chunk, (block, bin))| {
            let first = (chunk * PLANES) as i64;
            let last = first + (block.len() / (ny * nz)) as i64 - 1;
            for_each_in_slab(bin, &ranges, first, last, |n, [i, j, k]| {
                let m = &images[n];
                let (wq, sq) = (particles.omega[m.particle], particles.sigma[m.particle]);
                let idx = [i, j, k];
                let d = fine.origin + Vec3::from_fn(|b, _| (idx[b] as Real + 0.5) * fine.dx) - m.x;
                if d.norm_squared() < kernel::velocity_radius(sq).powi(2) {
                    let cell = ((i - first) as usize * ny + j as usize) * nz + k as usize;
                    block[cell] += kernel::vorticity(&wq, sq, &d);
                }
            });
        });
    out
}

/// Eq. 14 sums of every particle over the cells of the synthesis lattice under its cut-off.
fn lattice_sums(
    particles: &VortexParticles,
    images: &[Image],
    lattice: &Lattice,
    upsample: usize,
    vorticity: &[Vec3],
) -> Vec<Sums> {
    let fine = lattice.refined(upsample);
    let desired_at = desired_field(particles, images, &fine);
    (0..particles.len())
        .into_par_iter()
        .map(|p| {
            let (xp, sp) = (particles.x[p], particles.sigma[p]);
            let rp = kernel::radius(sp);
            let ap = axis(&particles.omega[p]);
            let g = (xp - fine.origin) / fine.dx;
            let range: [(i64, i64); 3] = std::array::from_fn(|a| {
                index_range(g[a], rp / fine.dx, 0.5, fine.dims[a], fine.periodic[a])
            });
            let mut sums = [0.0; 3];
            for i in range[0].0..=range[0].1 {
                for j in range[1].0..=range[1].1 {
                    for k in range[2].0..=range[2].1 {
                        let idx = [i, j, k];
                        let c =
                            fine.origin + Vec3::from_fn(|a, _| (idx[a] as Real + 0.5) * fine.dx);
                        if (c - xp).norm_squared() >= rp * rp {
                            continue;
                        }
                        let wrapped: [i64; 3] =
                            std::array::from_fn(|a| idx[a].rem_euclid(fine.dims[a] as i64));
                        let [wi, wj, wk] = wrapped.map(|v| v as usize);
                        let desired = desired_at[(wi * fine.dims[1] + wj) * fine.dims[2] + wk];
                        let have = if upsample == 1 {
                            vorticity[(wi * lattice.dims[1] + wj) * lattice.dims[2] + wk]
                        } else {
                            let gc =
                                Vec3::from_fn(|a, _| (wrapped[a] as Real + 0.5) / upsample as Real);
                            sample_cells(vorticity, lattice, &gc)
                        };
                        let d = desired.dot(&ap);
                        sums[0] += d;
                        sums[1] += have.dot(&ap);
                        sums[2] += d.abs();
                    }
                }
            }
            sums
        })
        .collect()
}

/// Trilinear interpolation of a cell-centred field at `g` (cell units from the origin), clamped
/// at the ends of non-periodic axes, wrapped on periodic ones.
fn sample_cells(field: &[Vec3], lattice: &Lattice, g: &Vec3) -> Vec3 {
    let w: [(usize, usize, Real); 3] = std::array::from_fn(|a| {
        let n = lattice.dims[a] as i64;
        let c = g[a] - 0.5;
        let i0 = c.floor() as i64;
        let t = c - i0 as Real;
        if lattice.periodic[a] {
            (
                i0.rem_euclid(n) as usize,
                (i0 + 1).rem_euclid(n) as usize,
                t,
            )
        } else if i0 < 0 {
            (0, 0, 0.0)
        } else if i0 >= n - 1 {
            ((n - 1) as usize, (n - 1) as usize, 0.0)
        } else {
            (i0 as usize, i0 as usize + 1, t)
        }
    });
    let [ny, nz] = [lattice.dims[1], lattice.dims[2]];
    let mut out = Vec3::zeros();
    for (di, wi) in [(w[0].0, 1.0 - w[0].2), (w[0].1, w[0].2)] {
        for (dj, wj) in [(w[1].0, 1.0 - w[1].2), (w[1].1, w[1].2)] {
            for (dk, wk) in [(w[2].0, 1.0 - w[2].2), (w[2].1, w[2].2)] {
                out += field[(di * ny + dj) * nz + dk] * (wi * wj * wk);
            }
        }
    }
    out
}

/// Planes of faces per parallel task.
const PLANES: usize = 2;

/// For each slab of `PLANES` x-planes of an axis of `len` samples, the index boxes (inclusive
/// ranges per axis) that touch it; empty boxes are left out.
fn slab_bins(ranges: &[[(i64, i64); 3]], len: usize) -> Vec<Vec<usize>> {
    let mut bins: Vec<Vec<usize>> = vec![Vec::new(); len.div_ceil(PLANES)];
    for (n, r) in ranges.iter().enumerate() {
        if r[0].0 <= r[0].1 && r[1].0 <= r[1].1 && r[2].0 <= r[2].1 {
            for bin in &mut bins[r[0].0 as usize / PLANES..=r[0].1 as usize / PLANES] {
                bin.push(n);
            }
        }
    }
    bins
}

/// Calls `f(n, [i, j, k])` for every index of every box `n` in `bin` whose x-index lies in the
/// slab `first..=last`: each slab is written by one task, so splats need no locks.
fn for_each_in_slab(
    bin: &[usize],
    ranges: &[[(i64, i64); 3]],
    first: i64,
    last: i64,
    mut f: impl FnMut(usize, [i64; 3]),
) {
    for &n in bin {
        let r = ranges[n];
        for i in r[0].0.max(first)..=r[0].1.min(last) {
            for j in r[1].0..=r[1].1 {
                for k in r[2].0..=r[2].1 {
                    f(n, [i, j, k]);
                }
            }
        }
    }
}

/// The weighted kernel velocities on the lattice's faces, each face the mean over
/// `upsample^2` points spread over it.
fn lattice_velocity(
    particles: &VortexParticles,
    images: &[Image],
    weights: &[Real],
    lattice: &Lattice,
    upsample: usize,
) -> [Array3<Real>; 3] {
    let sub: Vec<Real> = (0..upsample)
        .map(|s| (s as Real + 0.5) / upsample as Real - 0.5)
        .collect();
    let samples = (upsample * upsample) as Real;
    let active: Vec<&Image> = images
        .iter()
        .filter(|m| weights[m.particle] != 0.0)
        .collect();
    std::array::from_fn(|a| {
        let mut shape = lattice.dims;
        shape[a] += 1;
        let offset: [Real; 3] = std::array::from_fn(|b| if b == a { 0.0 } else { 0.5 });
        // A face's sample points lie up to half a cell off its centre across the face.
        let spread: [Real; 3] = std::array::from_fn(|b| if b == a { 0.0 } else { 0.5 });
        let ranges: Vec<[(i64, i64); 3]> = active
            .iter()
            .map(|m| {
                let g = (m.x - lattice.origin) / lattice.dx;
                let reach = kernel::velocity_radius(particles.sigma[m.particle]) / lattice.dx;
                std::array::from_fn(|b| {
                    index_range(g[b], reach + spread[b], offset[b], shape[b], false)
                })
            })
            .collect();
        let bins = slab_bins(&ranges, shape[0]);
        let mut out = Array3::zeros(shape);
        out.axis_chunks_iter_mut(Axis(0), PLANES)
            .into_par_iter()
            .zip(bins.par_iter())
            .enumerate()
            .for_each(|(chunk, (mut block, bin))| {
                let first = (chunk * PLANES) as i64;
                let last = first + block.shape()[0] as i64 - 1;
                for_each_in_slab(bin, &ranges, first, last, |n, [i, j, k]| {
                    let m = active[n];
                    let q = m.particle;
                    let (wq, sq) = (particles.omega[q] * weights[q], particles.sigma[q]);
                    let reach2 = kernel::velocity_radius(sq).powi(2);
                    let idx = [i, j, k];
                    let centre = lattice.origin
                        + Vec3::from_fn(|b, _| (idx[b] as Real + offset[b]) * lattice.dx)
                        - m.x;
                    let (t1, t2) = ((a + 1) % 3, (a + 2) % 3);
                    let mut sum = 0.0;
                    for &s1 in &sub {
                        for &s2 in &sub {
                            let mut d = centre;
                            d[t1] += s1 * lattice.dx;
                            d[t2] += s2 * lattice.dx;
                            if d.norm_squared() < reach2 {
                                sum += kernel::velocity(&wq, sq, &d)[a];
                            }
                        }
                    }
                    block[[(i - first) as usize, j as usize, k as usize]] += sum / samples;
                });
            });
        out
    })
}

/// Eq. 14 sums of every particle over the points under its cut-off.
fn point_sums(
    particles: &VortexParticles,
    hash: &PointHash,
    points: &[Vec3],
    vorticity: &[Vec3],
) -> Vec<Sums> {
    let reach = kernel::velocity_radius(max_sigma(particles));
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
                    if (x - particles.x[q]).norm() >= particles.radius(q) {
                        continue;
                    }
                    let a = axis(&particles.omega[q]);
                    let d = desired.dot(&a);
                    let s = &mut sums[q];
                    s[0] += d;
                    s[1] += have.dot(&a);
                    s[2] += d.abs();
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
fn point_velocity(
    particles: &VortexParticles,
    hash: &PointHash,
    weights: &[Real],
    points: &[Vec3],
) -> Vec<Vec3> {
    let reach = kernel::velocity_radius(max_sigma(particles));
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
