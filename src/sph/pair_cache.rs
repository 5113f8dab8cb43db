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
use super::kernel::CubicSpline;
use super::neighbors::NeighborLists;
use crate::{Real, Vec3};
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
        self.fluid.resize(fluid_lists.indices.len(), [0.0; 3]);
        self.boundary.resize(boundary_lists.indices.len(), [0.0; 3]);
        self.wall_grad.resize(n, Vec3::zeros());
        self.wall_rate.resize(n, 0.0);
        let tiny = 1e-9 * volume * volume / kernel.support().powi(8);
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
                |(blk, (((((mut fg, mut bg), ratio), factor), wall_grad), wall_rate))| {
                    for k in 0..ratio.len() {
                        let i = blk * BLOCK + k;
                        let xi = x[i];
                        let mut sum = volume * kernel.w_zero();
                        let (mut gf, mut gb, mut sq, mut rate) =
                            (Vec3::zeros(), Vec3::zeros(), 0.0, 0.0);
                        let fl = fluid_lists.of(i);
                        let (seg, rest) = fg.split_at_mut(fl.len());
                        fg = rest;
                        for (slot, &j) in seg.iter_mut().zip(fl) {
                            let xij = xi - x[j as usize];
                            let (w, g) = kernel.w_grad(&xij);
                            sum += volume * w;
                            *slot = narrow(&g);
                            let vg = volume * g;
                            gf += vg;
                            sq += vg.norm_squared();
                        }
                        let bl = boundary_lists.of(i);
                        let (seg, rest) = bg.split_at_mut(bl.len());
                        bg = rest;
                        for (slot, &b) in seg.iter_mut().zip(bl) {
                            let b = b as usize;
                            let xib = xi - boundary.x[b];
                            let vb = boundary.volume[b];
                            let (w, g) = kernel.w_grad(&xib);
                            sum += vb * w;
                            *slot = narrow(&g);
                            gb += vb * g;
                            rate += vb * boundary.v[b].dot(&g);
                        }
                        ratio[k] = sum;
                        let denom = sq + (gf + gb).norm_squared();
                        factor[k] = if denom > tiny { 1.0 / denom } else { 0.0 };
                        wall_grad[k] = gb;
                        wall_rate[k] = rate;
                    }
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

#[inline]
fn narrow(g: &Vec3) -> Grad32 {
    [g.x as f32, g.y as f32, g.z as f32]
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
