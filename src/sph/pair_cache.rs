//! Per-pair kernel gradients of one step, evaluated once right after the neighbour search.
//!
//! A DFSPH step runs some fifteen passes over every pair (density and factor, viscosity, each
//! iteration of the divergence and density solves), and each used to re-evaluate grad W. The
//! positions do not move between the neighbour search and the position update, so the gradients
//! are stored here once per step in the compressed-row layout of [`NeighborLists`], in the same
//! pass that computes the densities and DFSPH factors.
//!
//! **Precision.** Gradients are stored as f32: 12 bytes a pair keeps the whole state under the
//! 1 KiB per particle budget (f64 would add some 800 bytes per particle), and the pass reads
//! half the memory. f32's relative rounding (6e-8) is three orders of magnitude below the
//! solvers' tolerances (5e-4 of the density), and rounding is odd, so grad W_ji = -grad W_ij
//! holds exactly in the cache and the pair forces still cancel. Densities and factors are
//! computed in f64 from the exact gradients.
//!
//! **Walls.** Boundary samples do not move within a step, so the pressure solvers need only
//! two per-particle sums of the boundary pairs: sum_b V_b grad W_ib and sum_b V_b v_b . grad W_ib
//! (Akinci et al. 2012 Eq. 10 pushes with the fluid particle's own stiffness). The solver
//! iterations then never visit the boundary pairs.

use super::boundary::BoundaryParticles;
use super::kernel::{CubicSpline, KernelConstants};
use super::neighbors::NeighborLists;
use crate::simd::{norm2, Level, LANES};
use crate::{Real, Vec3};
use pulp::{Simd, WithSimd};
use rayon::prelude::*;

/// A kernel gradient stored in single precision.
pub type Grad32 = [f32; 3];

/// Particles per parallel block of the cache build.
const BLOCK: usize = 256;

/// Widens a stored gradient.
#[inline]
pub fn widen(g: &Grad32) -> Vec3 {
    Vec3::new(g[0] as Real, g[1] as Real, g[2] as Real)
}

/// Kernel gradients and wall sums of one step (see the module doc).
#[derive(Debug, Clone, Default)]
pub struct PairCache {
    /// grad W_ij for every entry of the fluid neighbour lists, in their layout.
    pub fluid: Vec<Grad32>,
    /// grad W_ib for every entry of the boundary neighbour lists, in their layout.
    pub boundary: Vec<Grad32>,
    /// Per fluid particle, sum_b V_b grad W_ib.
    pub wall_grad: Vec<Vec3>,
    /// Per fluid particle, sum_b V_b v_b . grad W_ib (nonzero only next to moving bodies).
    pub wall_rate: Vec<Real>,
}

/// What the cache build computes per fluid particle besides the cache.
pub struct Densities<'a> {
    /// rho_i / rho_0 = V W(0) + sum_j V W_ij + sum_b V_b W_ib.
    pub ratio: &'a mut [Real],
    /// The DFSPH factor: one over the change of rho_i / rho_0 per unit of k_i dt^2,
    /// 1 / (|G_f + G_b|^2 + sum_j |V grad W_ij|^2) with G_f = sum_j V grad W_ij and
    /// G_b = sum_b V_b grad W_ib; zero without neighbours.
    pub factor: &'a mut [Real],
}

impl PairCache {
    /// Recomputes the cache for fluid positions `x` (rest volume `volume` each) with neighbour
    /// lists `fluid_lists` and `boundary_lists`, and writes densities and DFSPH factors to `out`.
    /// Reuses the cache's memory.
    #[allow(clippy::too_many_arguments)]
    pub fn update(
        &mut self,
        kernel: &CubicSpline,
        x: &[Vec3],
        volume: Real,
        fluid_lists: &NeighborLists,
        boundary_lists: &NeighborLists,
        boundary: &BoundaryParticles,
        out: Densities,
    ) {
        let n = x.len();
        fit(&mut self.fluid, fluid_lists.indices.len(), [0.0; 3]);
        fit(&mut self.boundary, boundary_lists.indices.len(), [0.0; 3]);
        fit(&mut self.wall_grad, n, Vec3::zeros());
        fit(&mut self.wall_rate, n, 0.0);
        let tiny = 1e-9 * volume * volume / kernel.support().powi(8);
        let w0 = volume * kernel.w_zero();
        let fluid = Targets {
            x,
            volume: Volumes::Uniform(volume),
            v: None,
        };
        let walls = Targets {
            x: &boundary.x,
            volume: Volumes::Each(&boundary.volume),
            v: Some(&boundary.v),
        };
        let rows = Rows {
            kernel: kernel.constants(),
            x,
            fluid: &fluid,
            walls: &walls,
            fluid_lists,
            boundary_lists,
            w0,
            tiny,
        };
        let level = Level::active();
        let fluid_blocks = split_blocks(fluid_lists, &mut self.fluid);
        let boundary_blocks = split_blocks(boundary_lists, &mut self.boundary);
        fluid_blocks
            .into_par_iter()
            .zip(boundary_blocks)
            .zip(out.ratio.par_chunks_mut(BLOCK))
            .zip(out.factor.par_chunks_mut(BLOCK))
            .zip(self.wall_grad.par_chunks_mut(BLOCK))
            .zip(self.wall_rate.par_chunks_mut(BLOCK))
            .enumerate()
            .for_each(
                |(blk, (((((fluid, boundary), ratio), factor), wall_grad), wall_rate))| {
                    level.run(Block {
                        rows: &rows,
                        first: blk * BLOCK,
                        fluid,
                        boundary,
                        ratio,
                        factor,
                        wall_grad,
                        wall_rate,
                    })
                },
            );
    }

    /// Bytes held by the cache.
    pub fn memory_bytes(&self) -> usize {
        (self.fluid.capacity() + self.boundary.capacity()) * std::mem::size_of::<Grad32>()
            + self.wall_grad.capacity() * std::mem::size_of::<Vec3>()
            + self.wall_rate.capacity() * std::mem::size_of::<Real>()
    }
}

/// Resizes `v` to `len`, growing its allocation by a few percent rather than doubling it (the
/// pair count drifts a little every step; doubling would hold up to twice the memory).
fn fit<T: Clone>(v: &mut Vec<T>, len: usize, fill: T) {
    if len > v.capacity() {
        v.reserve_exact(len + len / 32 - v.len());
    }
    v.resize(len, fill);
}

/// The points a row of pairs reaches: their positions, volumes and (for walls) velocities.
struct Targets<'a> {
    x: &'a [Vec3],
    volume: Volumes<'a>,
    v: Option<&'a [Vec3]>,
}

/// One volume for every target (fluid) or one each (boundary samples).
#[derive(Clone, Copy)]
enum Volumes<'a> {
    Uniform(Real),
    Each(&'a [Real]),
}

/// The sums over one particle's row of pairs j: w0 + sum V_j W_ij, sum V_j grad W_ij,
/// sum |V_j grad W_ij|^2 and sum V_j v_j . grad W_ij (zero without target velocities).
#[derive(Debug, Default, Clone, Copy, PartialEq)]
struct RowSums {
    w: Real,
    grad: Vec3,
    grad_sq: Real,
    rate: Real,
}

/// What every row of a cache update reads.
struct Rows<'a> {
    kernel: KernelConstants,
    x: &'a [Vec3],
    fluid: &'a Targets<'a>,
    walls: &'a Targets<'a>,
    fluid_lists: &'a NeighborLists,
    boundary_lists: &'a NeighborLists,
    /// The self contribution to the density ratio, V W(0).
    w0: Real,
    /// The DFSPH factor's denominator below which a particle gets no factor.
    tiny: Real,
}

/// The rows of the [`BLOCK`] particles from `first` on: their cache entries (`fluid`,
/// `boundary`) and per-particle outputs.
struct Block<'a> {
    rows: &'a Rows<'a>,
    first: usize,
    fluid: &'a mut [Grad32],
    boundary: &'a mut [Grad32],
    ratio: &'a mut [Real],
    factor: &'a mut [Real],
    wall_grad: &'a mut [Vec3],
    wall_rate: &'a mut [Real],
}

impl WithSimd for Block<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        let r = self.rows;
        let (mut fg, mut bg) = (self.fluid, self.boundary);
        for k in 0..self.ratio.len() {
            let i = self.first + k;
            let fl = r.fluid_lists.of(i);
            let (fseg, rest) = fg.split_at_mut(fl.len());
            fg = rest;
            let bl = r.boundary_lists.of(i);
            let (bseg, rest) = bg.split_at_mut(bl.len());
            bg = rest;
            let f = row(simd, &r.kernel, &r.x[i], r.fluid, fl, fseg, r.w0);
            let b = row(simd, &r.kernel, &r.x[i], r.walls, bl, bseg, f.w);
            self.ratio[k] = b.w;
            let denom = f.grad_sq + (f.grad + b.grad).norm_squared();
            self.factor[k] = if denom > r.tiny { 1.0 / denom } else { 0.0 };
            self.wall_grad[k] = b.grad;
            self.wall_rate[k] = b.rate;
        }
    }
}

/// One particle's row of the cache: grad W_ij into `out` (one slot per entry of `list`) and the
/// row's sums, the density sum continuing from `w0`.
///
/// [`LANES`] pairs at a time: the targets' positions (and volumes and velocities) gathered by
/// index, [`CubicSpline::w_grad`]'s f64 operations in the same order lane by lane, with its
/// two branches as masks, the gradients rounded to f32 and stored pair by pair; the sums are
/// then added pair by pair in the list's order. So every level gives `w_grad`'s results to the
/// last bit (a different order of the sums changes a run's trajectory at the rounding level).
#[inline(always)]
fn row<S: Simd>(
    simd: S,
    c: &KernelConstants,
    xi: &Vec3,
    t: &Targets,
    list: &[u32],
    out: &mut [Grad32],
    w0: Real,
) -> RowSums {
    let mut sums = RowSums {
        w: w0,
        ..RowSums::default()
    };
    let splat = |v: Real| simd.splat_f64s(v);
    let (h2, tiny) = (c.h * c.h, 1e-24 * c.h * c.h);
    for (js, slots) in list.chunks(LANES).zip(out.chunks_mut(LANES)) {
        let dx = simd.sub_f64s(splat(xi.x), gather::<S>(js, |j| t.x[j].x));
        let dy = simd.sub_f64s(splat(xi.y), gather::<S>(js, |j| t.x[j].y));
        let dz = simd.sub_f64s(splat(xi.z), gather::<S>(js, |j| t.x[j].z));
        let r2 = norm2(simd, dx, dy, dz);
        let r = simd.sqrt_f64s(r2);
        let q = simd.mul_f64s(r, splat(c.inv_h));
        let inner = simd.less_than_or_equal_f64s(q, splat(0.5));
        let t1 = simd.sub_f64s(splat(1.0), q);
        let tw = simd.max_f64s(t1, splat(0.0));
        // W: k (6 q q (q - 1) + 1) inside q <= 1/2, k 2 t^3 outside.
        let six_qq = simd.mul_f64s(simd.mul_f64s(splat(6.0), q), q);
        let w_in = simd.mul_f64s(
            splat(c.k),
            simd.add_f64s(
                simd.mul_f64s(six_qq, simd.sub_f64s(q, splat(1.0))),
                splat(1.0),
            ),
        );
        let w_out = simd.mul_f64s(simd.mul_f64s(simd.mul_f64s(splat(c.k * 2.0), tw), tw), tw);
        // dW/dq: l q (3 q - 2) inside, -l t^2 outside; grad W = x dW/dq / (r h).
        let d_in = simd.mul_f64s(
            simd.mul_f64s(splat(c.l), q),
            simd.sub_f64s(simd.mul_f64s(splat(3.0), q), splat(2.0)),
        );
        let d_out = simd.mul_f64s(simd.mul_f64s(splat(-c.l), t1), t1);
        let f = simd.div_f64s(
            simd.select_f64s(inner, d_in, d_out),
            simd.mul_f64s(r, splat(c.h)),
        );
        // Inside the support and apart (a coincident pair has W(0) and no gradient).
        let near = simd.less_than_f64s(r2, splat(h2));
        let apart = simd.and_m64s(near, simd.greater_than_or_equal_f64s(r2, splat(tiny)));
        let w = simd.select_f64s(near, simd.select_f64s(inner, w_in, w_out), splat(0.0));
        let f = simd.select_f64s(apart, f, splat(0.0));
        let (gx, gy, gz) = (
            simd.mul_f64s(dx, f),
            simd.mul_f64s(dy, f),
            simd.mul_f64s(dz, f),
        );
        let vj = match t.volume {
            Volumes::Uniform(v) => splat(v),
            Volumes::Each(v) => gather::<S>(js, |j| v[j]),
        };
        let (vx, vy, vz) = (
            simd.mul_f64s(vj, gx),
            simd.mul_f64s(vj, gy),
            simd.mul_f64s(vj, gz),
        );
        let sq = norm2(simd, vx, vy, vz);
        let rate = match t.v {
            Some(v) => {
                let dot = simd.add_f64s(
                    simd.add_f64s(
                        simd.mul_f64s(gather::<S>(js, |j| v[j].x), gx),
                        simd.mul_f64s(gather::<S>(js, |j| v[j].y), gy),
                    ),
                    simd.mul_f64s(gather::<S>(js, |j| v[j].z), gz),
                );
                simd.mul_f64s(vj, dot)
            }
            None => splat(0.0),
        };
        let lanes = |v: S::f64s| -> [Real; LANES] { pulp::cast(v) };
        let (gx, gy, gz) = (lanes(gx), lanes(gy), lanes(gz));
        let (w, vx, vy, vz) = (lanes(simd.mul_f64s(vj, w)), lanes(vx), lanes(vy), lanes(vz));
        let (sq, rate) = (lanes(sq), lanes(rate));
        for (l, slot) in slots.iter_mut().enumerate() {
            *slot = [gx[l] as f32, gy[l] as f32, gz[l] as f32];
            sums.w += w[l];
            sums.grad += Vec3::new(vx[l], vy[l], vz[l]);
            sums.grad_sq += sq[l];
            sums.rate += rate[l];
        }
    }
    sums
}

/// `f` of the [`LANES`] targets `js` (the last one repeated in the lanes past its end).
#[inline(always)]
fn gather<S: Simd>(js: &[u32], f: impl Fn(usize) -> Real) -> S::f64s {
    let lanes: [Real; LANES] = std::array::from_fn(|l| f(js[l.min(js.len() - 1)] as usize));
    pulp::cast(lanes)
}

/// Splits `data` (one entry per neighbour, laid out like `lists`) into the parts that belong to
/// consecutive blocks of [`BLOCK`] points.
fn split_blocks<'a, T>(lists: &NeighborLists, mut data: &'a mut [T]) -> Vec<&'a mut [T]> {
    let n = lists.len();
    let mut blocks = Vec::with_capacity(n.div_ceil(BLOCK));
    for start in (0..n).step_by(BLOCK) {
        let end = (start + BLOCK).min(n);
        let len = (lists.offsets[end] - lists.offsets[start]) as usize;
        let (head, tail) = data.split_at_mut(len);
        blocks.push(head);
        data = tail;
    }
    blocks
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    /// A row computed at a given level.
    struct Row<'a> {
        kernel: KernelConstants,
        xi: Vec3,
        t: &'a Targets<'a>,
        list: &'a [u32],
        out: &'a mut [Grad32],
    }

    impl WithSimd for Row<'_> {
        type Output = RowSums;
        #[inline(always)]
        fn with_simd<S: Simd>(self, simd: S) -> RowSums {
            row(
                simd,
                &self.kernel,
                &self.xi,
                self.t,
                self.list,
                self.out,
                0.5,
            )
        }
    }

    /// At every level the CPU runs, a row stores the gradients of [`CubicSpline::w_grad`]
    /// and adds its sums pair by pair, bit for bit: on fluid rows (one volume) and wall rows
    /// (a volume and a velocity each), including a coincident pair, rows of every length from
    /// 0 to 40 (partial vectors) and pairs beyond the support.
    #[test]
    fn every_level_computes_the_kernel_rows_bit_for_bit() {
        let kernel = CubicSpline::new(0.2);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let mut random = || Vec3::new(rng.random(), rng.random(), rng.random()) * 0.5;
        let x: Vec<Vec3> = (0..200).map(|_| random()).collect();
        let v: Vec<Vec3> = (0..200).map(|_| random()).collect();
        let volume: Vec<Real> = (0..200).map(|k| 1e-3 * (1.0 + k as Real / 200.0)).collect();
        let xi = x[0];
        for len in 0..=40 {
            let list: Vec<u32> = (0..len as u32).map(|k| k * 5 % 200).collect();
            for t in [
                Targets {
                    x: &x,
                    volume: Volumes::Uniform(1e-3),
                    v: None,
                },
                Targets {
                    x: &x,
                    volume: Volumes::Each(&volume),
                    v: Some(&v),
                },
            ] {
                let mut want = RowSums {
                    w: 0.5,
                    ..RowSums::default()
                };
                let mut grads = Vec::new();
                for &j in &list {
                    let j = j as usize;
                    let (w, g) = kernel.w_grad(&(xi - x[j]));
                    let vj = match t.volume {
                        Volumes::Uniform(v) => v,
                        Volumes::Each(v) => v[j],
                    };
                    grads.push([g.x as f32, g.y as f32, g.z as f32]);
                    let vg = vj * g;
                    want.w += vj * w;
                    want.grad += vg;
                    want.grad_sq += vg.norm_squared();
                    if let Some(v) = t.v {
                        want.rate += vj * v[j].dot(&g);
                    }
                }
                if len > 0 {
                    assert!(want.w > 0.5, "the coincident first pair carries W(0)");
                }
                for level in Level::ALL.into_iter().filter(|l| l.supported()) {
                    let mut out = vec![[1f32; 3]; len];
                    let got = level.run(Row {
                        kernel: kernel.constants(),
                        xi,
                        t: &t,
                        list: &list,
                        out: &mut out,
                    });
                    assert_eq!(out, grads, "{level:?}: gradients, {len} pairs");
                    assert_eq!(got, want, "{level:?}: sums, {len} pairs");
                }
            }
        }
    }
}
