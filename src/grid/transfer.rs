//! Grid transfers between a multigrid level and the next coarser one.
//!
//! Prolongation is cell-centred trilinear interpolation (weights 3/4 and 1/4 per axis, McAdams
//! et al. 2010 section 4), restriction is its exact transpose, so the V-cycle stays symmetric and
//! the preconditioner SPD. Both are tensor products of 1D tables, one per axis, which also
//! absorb the sides of the grid: a periodic axis wraps, a wall side extrapolates the boundary
//! value (zero normal derivative), a Dirichlet side drops the ghost (value zero).
//!
//! Coarse cells that are not unknowns enter the interpolation through an extension `E`: a
//! Dirichlet cell contributes zero, a solid cell the mean of its unknown face neighbours (a
//! Neumann-like continuation into obstacles, instead of the zero that would pull the correction
//! down next to every wall). Restriction applies `E^T`.

use super::layout::Layout;
use super::stencil::{FLUID, PARALLEL_MIN_CELLS, SOLID};
use rayon::prelude::*;

/// The 1D interpolation along one axis.
#[derive(Clone, Debug)]
struct AxisTransfer {
    /// For each fine coordinate: two (coarse coordinate, weight) pairs.
    up: Vec<[(usize, f32); 2]>,
    /// For each coarse coordinate: the (fine coordinate, weight) pairs of the transpose.
    down: Vec<Vec<(usize, f32)>>,
}

impl AxisTransfer {
    /// `fine` cells coarsened by `factor` (1 or 2); `sides` are the Dirichlet weights of the two
    /// sides (0 = wall), ignored on a periodic axis.
    fn new(fine: usize, factor: usize, periodic: bool, sides: [u8; 2]) -> Self {
        let coarse = fine.div_ceil(factor);
        let up: Vec<[(usize, f32); 2]> = (0..fine)
            .map(|f| {
                if factor == 1 {
                    return [(f, 1.0), (f, 0.0)];
                }
                let parent = f / 2;
                let (outside, side) = if f % 2 == 0 {
                    (parent == 0, 0)
                } else {
                    (parent + 1 == coarse, 1)
                };
                let other = if !outside {
                    (if side == 0 { parent - 1 } else { parent + 1 }, 0.25)
                } else if periodic {
                    (if side == 0 { coarse - 1 } else { 0 }, 0.25)
                } else if sides[side] == 0 {
                    (parent, 0.25)
                } else {
                    (parent, 0.0)
                };
                [(parent, 0.75), other]
            })
            .collect();
        let mut down = vec![Vec::new(); coarse];
        for (f, pairs) in up.iter().enumerate() {
            for &(c, w) in pairs {
                if w != 0.0 {
                    down[c].push((f, w));
                }
            }
        }
        Self { up, down }
    }
}

/// A (solid coarse cell, unknown neighbour, weight) entry of the extension `E`.
#[derive(Clone, Copy, Debug)]
struct Link {
    solid: usize,
    fluid: usize,
    weight: f32,
}

/// Transfer between a fine level and its coarse level.
#[derive(Clone, Debug)]
pub(crate) struct Transfer {
    fine: Layout,
    coarse: Layout,
    axes: [AxisTransfer; 3],
    links: Vec<Link>,
    /// Fine rows restricted along z only (`fine.n[0] * fine.n[1] * coarse.n[2]`).
    tmp: Vec<f32>,
}

impl Transfer {
    /// `factors[axis]` is 2 where the axis is coarsened and 1 where it is kept.
    pub fn new(
        fine: Layout,
        coarse: Layout,
        factors: [usize; 3],
        side_weight: [[u8; 2]; 3],
        coarse_kinds: &[u8],
    ) -> Self {
        let axes = [0, 1, 2]
            .map(|a| AxisTransfer::new(fine.n[a], factors[a], fine.periodic[a], side_weight[a]));
        let mut links = Vec::new();
        for i in 0..coarse.n[0] {
            for j in 0..coarse.n[1] {
                for k in 0..coarse.n[2] {
                    let s = coarse.index(i, j, k);
                    if coarse_kinds[s] != SOLID {
                        continue;
                    }
                    let start = links.len();
                    let c = [i, j, k];
                    for axis in 0..3 {
                        for up in [false, true] {
                            if let Some(t) = coarse.step(axis, c[axis], up) {
                                let mut nb = c;
                                nb[axis] = t;
                                let f = coarse.index(nb[0], nb[1], nb[2]);
                                if coarse_kinds[f] == FLUID {
                                    links.push(Link {
                                        solid: s,
                                        fluid: f,
                                        weight: 0.0,
                                    });
                                }
                            }
                        }
                    }
                    let w = 1.0 / (links.len() - start).max(1) as f32;
                    links[start..].iter_mut().for_each(|l| l.weight = w);
                }
            }
        }
        let tmp = vec![0.0; fine.rows() * coarse.n[2]];
        Self {
            fine,
            coarse,
            axes,
            links,
            tmp,
        }
    }

    /// `coarse_b = E^T T^T fine_r`, zero outside the coarse unknowns.
    pub fn restrict(&mut self, fine_r: &[f32], coarse_b: &mut [f32], coarse_kinds: &[u8]) {
        let (f, c) = (self.fine, self.coarse);
        let [ax, ay, az] = &self.axes;
        let z_rows = |(row, t): (usize, &mut [f32])| {
            let src = &fine_r[row * f.n[2]..(row + 1) * f.n[2]];
            for (tk, pairs) in t.iter_mut().zip(&az.down) {
                *tk = pairs.iter().map(|&(fz, w)| w * src[fz]).sum();
            }
        };
        if f.len() >= PARALLEL_MIN_CELLS {
            self.tmp.par_chunks_mut(c.n[2]).enumerate().for_each(z_rows);
        } else {
            self.tmp.chunks_mut(c.n[2]).enumerate().for_each(z_rows);
        }
        let tmp = &self.tmp;
        let xy = |(i, slab): (usize, &mut [f32])| {
            for j in 0..c.n[1] {
                let out = &mut slab[j * c.n[2]..(j + 1) * c.n[2]];
                out.fill(0.0);
                for &(fx, wx) in &ax.down[i] {
                    for &(fy, wy) in &ay.down[j] {
                        let w = wx * wy;
                        let row = (fx * f.n[1] + fy) * c.n[2];
                        for (o, t) in out.iter_mut().zip(&tmp[row..row + c.n[2]]) {
                            *o += w * t;
                        }
                    }
                }
            }
        };
        if c.len() >= PARALLEL_MIN_CELLS {
            coarse_b.par_chunks_mut(c.slab()).enumerate().for_each(xy);
        } else {
            coarse_b.chunks_mut(c.slab()).enumerate().for_each(xy);
        }
        for l in &self.links {
            coarse_b[l.fluid] += l.weight * coarse_b[l.solid];
        }
        for (b, &kind) in coarse_b.iter_mut().zip(coarse_kinds) {
            if kind != FLUID {
                *b = 0.0;
            }
        }
    }

    /// `fine_x += T E coarse_x` on the fine unknowns. Writes the extension into the solid cells
    /// of `coarse_x` (which hold zero and are reset before the next use).
    pub fn prolong_add(
        &mut self,
        coarse_x: &mut [f32],
        fine_x: &mut [f32],
        fine_unknown: impl Fn(usize) -> bool + Sync,
    ) {
        for l in &self.links {
            coarse_x[l.solid] += l.weight * coarse_x[l.fluid];
        }
        let (f, c) = (self.fine, self.coarse);
        let [ax, ay, az] = &self.axes;
        let coarse_x = &*coarse_x;
        // Per fine row: interpolate in x and y into a coarse-length row of `tmp`, then in z.
        let slab = |(i, (xs, ts)): (usize, (&mut [f32], &mut [f32]))| {
            for j in 0..f.n[1] {
                let t = &mut ts[j * c.n[2]..(j + 1) * c.n[2]];
                t.fill(0.0);
                for &(cx, wx) in &ax.up[i] {
                    for &(cy, wy) in &ay.up[j] {
                        let w = wx * wy;
                        if w == 0.0 {
                            continue;
                        }
                        let start = c.index(cx, cy, 0);
                        for (t, s) in t.iter_mut().zip(&coarse_x[start..start + c.n[2]]) {
                            *t += w * s;
                        }
                    }
                }
                let base = f.index(i, j, 0);
                let row = &mut xs[j * f.n[2]..(j + 1) * f.n[2]];
                for (k, (x, p)) in row.iter_mut().zip(&az.up).enumerate() {
                    if fine_unknown(base + k) {
                        *x += p[0].1 * t[p[0].0] + p[1].1 * t[p[1].0];
                    }
                }
            }
        };
        let chunks = fine_x
            .par_chunks_mut(f.slab())
            .zip(self.tmp.par_chunks_mut(f.n[1] * c.n[2]));
        if f.len() >= PARALLEL_MIN_CELLS {
            chunks.enumerate().for_each(slab);
        } else {
            fine_x
                .chunks_mut(f.slab())
                .zip(self.tmp.chunks_mut(f.n[1] * c.n[2]))
                .enumerate()
                .for_each(slab);
        }
    }
}
