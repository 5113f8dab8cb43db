//! Synthesis onto a MAC lattice, in slab-parallel passes: each task owns a few x-planes of the
//! samples and visits the particle images whose reach touches them, so splats need no locks
//! and no field the size of the grid is ever allocated.
//!
//! Kernel evaluations use the separability of the Gaussian: `exp(-r^2 / 2 sigma^2)` is the
//! product of one factor per axis, so an image tabulates its offsets and factors along each
//! axis once ([`Separable`]) and a sample costs a few multiplications instead of an
//! exponential.

use ndarray::{ArrayViewMut3, Axis};
use rayon::prelude::*;

use super::{axis, Image, Sums};
use crate::vortex::{kernel, CellRows, Lattice, VortexError, VortexParticles};
use crate::{Real, Vec3};

/// Planes of samples per parallel task.
const PLANES: usize = 4;

/// Where a lattice's samples lie along each axis: `origin + (index + offset + sub) dx` for
/// `index` in `0..len` and each `sub`-sample offset.
struct Stagger {
    origin: Vec3,
    dx: Real,
    len: [usize; 3],
    offset: [Real; 3],
    subs: [Vec<Real>; 3],
}

impl Stagger {
    /// The cell centres of `lattice`.
    fn cells(lattice: &Lattice) -> Self {
        Self {
            origin: lattice.origin,
            dx: lattice.dx,
            len: lattice.dims,
            offset: [0.5; 3],
            subs: std::array::from_fn(|_| vec![0.0]),
        }
    }

    /// The faces normal to `a`, each sampled at `upsample^2` points spread over the face (the
    /// face means of a synthesis lattice `upsample` times finer).
    fn faces(lattice: &Lattice, a: usize, upsample: usize) -> Self {
        let spread: Vec<Real> = (0..upsample)
            .map(|s| (s as Real + 0.5) / upsample as Real - 0.5)
            .collect();
        let mut len = lattice.dims;
        len[a] += 1;
        Self {
            origin: lattice.origin,
            dx: lattice.dx,
            len,
            offset: std::array::from_fn(|b| if b == a { 0.0 } else { 0.5 }),
            subs: std::array::from_fn(|b| if b == a { vec![0.0] } else { spread.clone() }),
        }
    }
}

/// One sample coordinate along an axis: its lattice index, offset `d` from the image centre,
/// `d^2`, and Gaussian factor `exp(-d^2 / 2 sigma^2)`.
#[derive(Debug, Clone, Copy)]
struct Sample {
    index: usize,
    d: Real,
    d2: Real,
    g: Real,
}

/// The samples within `reach` of an image centre, tabulated per axis in index order.
struct Separable {
    axes: [Vec<Sample>; 3],
}

impl Separable {
    fn new(centre: &Vec3, sigma: Real, reach: Real, at: &Stagger) -> Self {
        let inv = 1.0 / (2.0 * sigma * sigma);
        let reach2 = reach * reach;
        Self {
            axes: std::array::from_fn(|b| {
                let c = (centre[b] - at.origin[b]) / at.dx - at.offset[b];
                let (lo_sub, hi_sub) = at.subs[b]
                    .iter()
                    .fold((0.0 as Real, 0.0 as Real), |(l, h), &s| {
                        (l.min(s), h.max(s))
                    });
                let r = reach / at.dx;
                let lo = ((c - r - hi_sub).ceil() as i64).max(0);
                let hi = ((c + r - lo_sub).floor() as i64).min(at.len[b] as i64 - 1);
                let mut out =
                    Vec::with_capacity(((hi - lo + 1).max(0) as usize) * at.subs[b].len());
                for index in lo..=hi {
                    for &s in &at.subs[b] {
                        let d = (index as Real + s - c) * at.dx;
                        let d2 = d * d;
                        if d2 < reach2 {
                            let g = (-d2 * inv).exp();
                            out.push(Sample {
                                index: index as usize,
                                d,
                                d2,
                                g,
                            });
                        }
                    }
                }
                out
            }),
        }
    }

    /// The x-indices the samples span, if any.
    fn x_span(&self) -> Option<(usize, usize)> {
        if self.axes.iter().any(Vec::is_empty) {
            return None;
        }
        let x = &self.axes[0];
        Some((x[0].index, x[x.len() - 1].index))
    }

    /// Calls `f` for every row along z of the samples with x-index in `first..=last` closer
    /// than `sqrt(reach2)` to the centre.
    #[inline]
    fn for_each_row(&self, first: usize, last: usize, reach2: Real, mut f: impl FnMut(Row<'_>)) {
        let [xs, ys, zs] = &self.axes;
        for x in xs.iter().filter(|s| (first..=last).contains(&s.index)) {
            for y in ys {
                let r2xy = x.d2 + y.d2;
                if r2xy >= reach2 {
                    continue;
                }
                // r^2 falls, then rises along the row, so the samples inside form one run,
                // found by scanning in from both ends.
                let inside = |s: &Sample| r2xy + s.d2 < reach2;
                let Some(lo) = zs.iter().position(inside) else {
                    continue;
                };
                let hi = zs.iter().rposition(inside).unwrap_or(lo);
                f(Row {
                    x,
                    y,
                    r2xy,
                    gxy: x.g * y.g,
                    z: &zs[lo..=hi],
                });
            }
        }
    }
}

/// A run of samples along z inside an image's reach, at one x and one y sample.
struct Row<'t> {
    x: &'t Sample,
    y: &'t Sample,
    /// `d_x^2 + d_y^2`.
    r2xy: Real,
    /// The x and y Gaussian factors' product.
    gxy: Real,
    z: &'t [Sample],
}

impl Row<'_> {
    /// Offset of the row's first plane-local sample in a slab starting at x-index `first` of a
    /// lattice with `ny` by `nz` samples per plane.
    #[inline]
    fn base(&self, first: usize, ny: usize, nz: usize) -> usize {
        ((self.x.index - first) * ny + self.y.index) * nz
    }
}

/// For each slab of `PLANES` x-planes of an axis of `len` samples, the tables that touch it.
fn slab_bins(tables: &[Separable], len: usize) -> Vec<Vec<usize>> {
    let mut bins: Vec<Vec<usize>> = vec![Vec::new(); len.div_ceil(PLANES)];
    for (n, t) in tables.iter().enumerate() {
        if let Some((lo, hi)) = t.x_span() {
            for bin in &mut bins[lo / PLANES..=hi / PLANES] {
                bin.push(n);
            }
        }
    }
    bins
}

/// Eq. 14 sums of every particle over the cells of the synthesis lattice under its cut-off.
pub(super) fn sums(
    particles: &VortexParticles,
    images: &[Image],
    lattice: &Lattice,
    upsample: usize,
    vorticity: &CellRows<'_>,
) -> Vec<Sums> {
    let fine = lattice.refined(upsample);
    let cells = Stagger::cells(&fine);
    let tables: Vec<Separable> = images
        .par_iter()
        .map(|m| {
            let s = particles.sigma[m.particle];
            Separable::new(&m.x, s, kernel::velocity_radius(s), &cells)
        })
        .collect();
    let slab = Slab {
        particles,
        images,
        tables: &tables,
        lattice,
        upsample,
        vorticity,
    };
    let partial: Vec<Vec<(usize, Sums)>> = slab_bins(&tables, fine.dims[0])
        .par_iter()
        .enumerate()
        .map(|(n, bin)| slab.sums(n * PLANES, bin))
        .collect();
    let mut out = vec![[0.0; 3]; particles.len()];
    for (p, s) in partial.into_iter().flatten() {
        for c in 0..3 {
            out[p][c] += s[c];
        }
    }
    out
}

/// The Eq. 14 sums, slab by slab: each slab task builds the desired vorticity `omega_D` on its
/// own planes (every image whose velocity reach touches them adds its kernel vorticity) and the
/// sink's vorticity on the runs of its rows that some cut-off covers, then sums both under the
/// cut-off of each image. Each field is so computed once per cell rather than once for every
/// particle covering the cell, and never for the whole grid at once.
struct Slab<'s, 'v> {
    particles: &'s VortexParticles,
    images: &'s [Image],
    tables: &'s [Separable],
    lattice: &'s Lattice,
    upsample: usize,
    vorticity: &'s CellRows<'v>,
}

impl Slab<'_, '_> {
    /// The sums over the planes from `first` of each image in `bin`.
    fn sums(&self, first: usize, bin: &[usize]) -> Vec<(usize, Sums)> {
        let [nx, ny, nz] = self.lattice.refined(self.upsample).dims;
        let last = (first + PLANES).min(nx) - 1;
        let cutoff2 = |n: usize| self.particles.radius(self.images[n].particle).powi(2);
        let mut desired = vec![Vec3::zeros(); (last + 1 - first) * ny * nz];
        for &n in bin {
            let p = self.images[n].particle;
            let (w, s) = (self.particles.omega[p], self.particles.sigma[p]);
            let inv = 1.0 / (2.0 * s * s);
            let reach2 = kernel::velocity_radius(s).powi(2);
            // The kernel vorticity (see `kernel::vorticity`) with the tabulated Gaussian.
            self.tables[n].for_each_row(first, last, reach2, |row| {
                let b = row.base(first, ny, nz);
                for z in row.z {
                    let d = Vec3::new(row.x.d, row.y.d, z.d);
                    let r2 = row.r2xy + z.d2;
                    desired[b + z.index] +=
                        (row.gxy * z.g) * (w * (1.0 - r2 * inv) + d * (d.dot(&w) * inv));
                }
            });
        }
        let have = self.sink_vorticity(first, last, bin);
        bin.iter()
            .map(|&n| {
                let p = self.images[n].particle;
                let a = axis(&self.particles.omega[p]);
                let mut sums = [0.0; 3];
                self.tables[n].for_each_row(first, last, cutoff2(n), |row| {
                    let b = row.base(first, ny, nz);
                    for z in row.z {
                        let h = match &have {
                            Some(have) => have[b + z.index],
                            None => {
                                let idx = [row.x.index, row.y.index, z.index];
                                let g = Vec3::from_fn(|c, _| idx[c] as Real + 0.5);
                                sample_cells(
                                    self.vorticity,
                                    self.lattice,
                                    &(g / self.upsample as Real),
                                )
                            }
                        };
                        let d = desired[b + z.index].dot(&a);
                        sums[0] += d;
                        sums[1] += h.dot(&a);
                        sums[2] += d.abs();
                    }
                });
                (p, sums)
            })
            .collect()
    }

    /// The sink's vorticity on the slab's cells under some image's cut-off (one run per row,
    /// from the first covered cell to the last); `None` on a finer synthesis lattice, whose
    /// cells interpolate the sink's.
    fn sink_vorticity(&self, first: usize, last: usize, bin: &[usize]) -> Option<Vec<Vec3>> {
        if self.upsample != 1 {
            return None;
        }
        let [_, ny, nz] = self.lattice.dims;
        let mut span = vec![(usize::MAX, 0); (last + 1 - first) * ny];
        for &n in bin {
            let cutoff2 = self.particles.radius(self.images[n].particle).powi(2);
            self.tables[n].for_each_row(first, last, cutoff2, |row| {
                let s = &mut span[row.base(first, ny, nz) / nz];
                s.0 = s.0.min(row.z[0].index);
                s.1 = s.1.max(row.z[row.z.len() - 1].index);
            });
        }
        let mut have = vec![Vec3::zeros(); span.len() * nz];
        for (r, &(lo, hi)) in span.iter().enumerate().filter(|(_, s)| s.0 <= s.1) {
            let (i, j) = (first + r / ny, r % ny);
            (self.vorticity)([i, j, lo], &mut have[r * nz + lo..=r * nz + hi]);
        }
        Some(have)
    }
}

/// Trilinear interpolation of a cell-centred field at `g` (cell units from the origin), clamped
/// at the ends of non-periodic axes, wrapped on periodic ones.
fn sample_cells(field: &CellRows<'_>, lattice: &Lattice, g: &Vec3) -> Vec3 {
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
    let mut out = Vec3::zeros();
    for (di, wi) in [(w[0].0, 1.0 - w[0].2), (w[0].1, w[0].2)] {
        for (dj, wj) in [(w[1].0, 1.0 - w[1].2), (w[1].1, w[1].2)] {
            for (dk, wk) in [(w[2].0, 1.0 - w[2].2), (w[2].1, w[2].2)] {
                let mut cell = [Vec3::zeros()];
                field([di, dj, dk], &mut cell);
                out += cell[0] * (wi * wj * wk);
            }
        }
    }
    out
}

/// Adds the weighted kernel velocities to the lattice's faces, in place, each face the mean
/// over `upsample^2` points spread over it.
pub(super) fn add_velocity(
    particles: &VortexParticles,
    images: &[Image],
    weights: &[Real],
    lattice: &Lattice,
    upsample: usize,
    faces: [ArrayViewMut3<'_, Real>; 3],
) -> Result<(), VortexError> {
    let active: Vec<&Image> = images
        .iter()
        .filter(|m| weights[m.particle] != 0.0)
        .collect();
    let scale = 0.5 / (upsample * upsample) as Real;
    for (a, mut face) in faces.into_iter().enumerate() {
        let at = Stagger::faces(lattice, a, upsample);
        if face.shape() != at.len || !face.is_standard_layout() {
            return Err(VortexError::Layout(format!(
                "face array {a} of shape {:?} for faces of shape {:?} (standard layout)",
                face.shape(),
                at.len
            )));
        }
        let tables: Vec<Separable> = active
            .par_iter()
            .map(|m| {
                let s = particles.sigma[m.particle];
                Separable::new(&m.x, s, kernel::velocity_radius(s), &at)
            })
            .collect();
        let bins = slab_bins(&tables, at.len[0]);
        let [ny, nz] = [at.len[1], at.len[2]];
        face.axis_chunks_iter_mut(Axis(0), PLANES)
            .into_par_iter()
            .zip(bins.par_iter())
            .enumerate()
            .for_each(|(slab, (mut block, bin))| {
                let first = slab * PLANES;
                let last = first + block.shape()[0] - 1;
                let block = block
                    .as_slice_mut()
                    .expect("planes of a standard-layout array are contiguous");
                for &n in bin {
                    let q = active[n].particle;
                    let w = particles.omega[q] * (weights[q] * scale);
                    let reach2 = kernel::velocity_radius(particles.sigma[q]).powi(2);
                    // Component a of (1/2) g (omega x d) never involves d_a; along a row
                    // only d_z varies, so it is alpha + beta d_z there.
                    tables[n].for_each_row(first, last, reach2, |row| {
                        let (dx, dy) = (row.x.d, row.y.d);
                        let (alpha, beta) = match a {
                            0 => (-w[2] * dy, w[1]),
                            1 => (w[2] * dx, -w[0]),
                            _ => (w[0] * dy - w[1] * dx, 0.0),
                        };
                        let base = row.base(first, ny, nz);
                        let add = |z: &Sample| row.gxy * z.g * (alpha + beta * z.d);
                        if at.subs[2].len() == 1 {
                            // One sample per face: the row is a contiguous run of faces.
                            let start = base + row.z[0].index;
                            let run = &mut block[start..start + row.z.len()];
                            run.iter_mut().zip(row.z).for_each(|(f, z)| *f += add(z));
                        } else {
                            row.z.iter().for_each(|z| block[base + z.index] += add(z));
                        }
                    });
                }
            });
    }
    Ok(())
}
