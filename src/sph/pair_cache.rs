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
                        let fl = fluid_lists.of(i);
                        let (fseg, rest) = fg.split_at_mut(fl.len());
                        fg = rest;
                        let bl = boundary_lists.of(i);
                        let (bseg, rest) = bg.split_at_mut(bl.len());
                        bg = rest;
                        let f = row::sums(kernel, &x[i], &fluid, fl, fseg, w0);
                        let b = row::sums(kernel, &x[i], &walls, bl, bseg, f.w);
                        ratio[k] = b.w;
                        let denom = f.grad_sq + (f.grad + b.grad).norm_squared();
                        factor[k] = if denom > tiny { 1.0 / denom } else { 0.0 };
                        wall_grad[k] = b.grad;
                        wall_rate[k] = b.rate;
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

/// One particle's row of the cache: grad W_ij into `out` (one slot per entry of `list`) and the
/// row's sums, the density sum continuing from `w0`. The scalar and the wide form evaluate each
/// pair with the same f64 operations and add the sums in the same order, so they give the same
/// results to the last bit.
mod row {
    use super::{Grad32, RowSums, Targets, Volumes};
    use crate::sph::kernel::CubicSpline;
    use crate::{Real, Vec3};

    pub fn scalar(
        kernel: &CubicSpline,
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
        for (slot, &j) in out.iter_mut().zip(list) {
            let j = j as usize;
            let (w, g) = kernel.w_grad(&(xi - t.x[j]));
            let vj = match t.volume {
                Volumes::Uniform(v) => v,
                Volumes::Each(v) => v[j],
            };
            *slot = [g.x as f32, g.y as f32, g.z as f32];
            let vg = vj * g;
            sums.w += vj * w;
            sums.grad += vg;
            sums.grad_sq += vg.norm_squared();
            if let Some(v) = t.v {
                sums.rate += vj * v[j].dot(&g);
            }
        }
        sums
    }

    /// The row by [`wide`] where the CPU runs it, else by [`scalar`].
    pub fn sums(
        kernel: &CubicSpline,
        xi: &Vec3,
        t: &Targets,
        list: &[u32],
        out: &mut [Grad32],
        w0: Real,
    ) -> RowSums {
        #[cfg(target_arch = "x86_64")]
        if wide_available() {
            // SAFETY: the CPU has the feature, checked just above.
            return unsafe { wide(kernel, xi, t, list, out, w0) };
        }
        scalar(kernel, xi, t, list, out, w0)
    }

    /// Whether the CPU runs [`wide`].
    #[cfg(target_arch = "x86_64")]
    pub fn wide_available() -> bool {
        is_x86_feature_detected!("avx512f") && is_x86_feature_detected!("avx512vl")
    }

    /// [`scalar`] for eight pairs at a time on AVX-512: the targets' positions (and volumes
    /// and velocities) gathered by index, [`CubicSpline::w_grad`]'s operations lane by lane
    /// with its two branches as masks, the gradients rounded to f32 and stored pair by pair.
    ///
    /// # Safety
    /// The CPU must have AVX-512F and AVX-512VL ([`wide_available`]). Without VL enabled here
    /// the masked 256-bit index load compiles to a call that spills every vector register.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,avx512vl")]
    pub unsafe fn wide(
        kernel: &CubicSpline,
        xi: &Vec3,
        t: &Targets,
        list: &[u32],
        out: &mut [Grad32],
        w0: Real,
    ) -> RowSums {
        use std::arch::x86_64::*;
        assert_eq!(out.len(), list.len());
        assert!(list.iter().all(|&j| (j as usize) < t.x.len()));
        if let Volumes::Each(v) = t.volume {
            assert_eq!(v.len(), t.x.len());
        }
        if let Some(v) = t.v {
            assert_eq!(v.len(), t.x.len());
        }
        let c = kernel.constants();
        let splat = _mm512_set1_pd;
        let (h2, tiny) = (c.h * c.h, 1e-24 * c.h * c.h);
        let mut sums = RowSums {
            w: w0,
            ..RowSums::default()
        };
        let base = t.x.as_ptr().cast::<f64>();
        for start in (0..list.len()).step_by(8) {
            let lanes = (list.len() - start).min(8);
            let valid = (((1u16 << lanes) - 1) & 0xff) as u8;
            // SAFETY: the masked load reads only the `lanes` entries left in `list`, and every
            // gather reads only valid lanes, at indices checked against the arrays above.
            unsafe {
                let index = _mm256_maskz_loadu_epi32(valid, list.as_ptr().add(start).cast::<i32>());
                let three = _mm256_add_epi32(_mm256_add_epi32(index, index), index);
                let gather = |offset: usize| {
                    _mm512_mask_i32gather_pd::<8>(splat(0.0), valid, three, base.add(offset))
                };
                let dx = _mm512_sub_pd(splat(xi.x), gather(0));
                let dy = _mm512_sub_pd(splat(xi.y), gather(1));
                let dz = _mm512_sub_pd(splat(xi.z), gather(2));
                let r2 = _mm512_add_pd(
                    _mm512_add_pd(_mm512_mul_pd(dx, dx), _mm512_mul_pd(dy, dy)),
                    _mm512_mul_pd(dz, dz),
                );
                let r = _mm512_sqrt_pd(r2);
                let q = _mm512_mul_pd(r, splat(c.inv_h));
                let inner = _mm512_cmp_pd_mask::<_CMP_LE_OQ>(q, splat(0.5));
                let t1 = _mm512_sub_pd(splat(1.0), q);
                let tw = _mm512_max_pd(t1, splat(0.0));
                // W: k (6 q q (q - 1) + 1) inside q <= 1/2, k 2 t^3 outside.
                let w_in = _mm512_mul_pd(
                    splat(c.k),
                    _mm512_add_pd(
                        _mm512_mul_pd(
                            _mm512_mul_pd(_mm512_mul_pd(splat(6.0), q), q),
                            _mm512_sub_pd(q, splat(1.0)),
                        ),
                        splat(1.0),
                    ),
                );
                let w_out =
                    _mm512_mul_pd(_mm512_mul_pd(_mm512_mul_pd(splat(c.k * 2.0), tw), tw), tw);
                let w = _mm512_mask_blend_pd(inner, w_out, w_in);
                // dW/dq: l q (3 q - 2) inside, -l t^2 outside; grad W = x dW/dq / (r h).
                let d_in = _mm512_mul_pd(
                    _mm512_mul_pd(splat(c.l), q),
                    _mm512_sub_pd(_mm512_mul_pd(splat(3.0), q), splat(2.0)),
                );
                let d_out = _mm512_mul_pd(_mm512_mul_pd(splat(-c.l), t1), t1);
                let f = _mm512_div_pd(
                    _mm512_mask_blend_pd(inner, d_out, d_in),
                    _mm512_mul_pd(r, splat(c.h)),
                );
                // Inside the support and apart (a coincident pair has W(0) and no gradient).
                let near = valid & _mm512_cmp_pd_mask::<_CMP_LT_OQ>(r2, splat(h2));
                let apart = near & _mm512_cmp_pd_mask::<_CMP_GE_OQ>(r2, splat(tiny));
                let w = _mm512_maskz_mov_pd(near, w);
                let f = _mm512_maskz_mov_pd(apart, f);
                let (gx, gy, gz) = (
                    _mm512_mul_pd(dx, f),
                    _mm512_mul_pd(dy, f),
                    _mm512_mul_pd(dz, f),
                );
                let mut rows = [[0f32; 8]; 3];
                _mm256_storeu_ps(rows[0].as_mut_ptr(), _mm512_cvtpd_ps(gx));
                _mm256_storeu_ps(rows[1].as_mut_ptr(), _mm512_cvtpd_ps(gy));
                _mm256_storeu_ps(rows[2].as_mut_ptr(), _mm512_cvtpd_ps(gz));
                for (l, slot) in out[start..start + lanes].iter_mut().enumerate() {
                    *slot = [rows[0][l], rows[1][l], rows[2][l]];
                }
                let vj = match t.volume {
                    Volumes::Uniform(v) => splat(v),
                    Volumes::Each(v) => {
                        _mm512_mask_i32gather_pd::<8>(splat(0.0), valid, index, v.as_ptr())
                    }
                };
                let (vx, vy, vz) = (
                    _mm512_mul_pd(vj, gx),
                    _mm512_mul_pd(vj, gy),
                    _mm512_mul_pd(vj, gz),
                );
                let sq = _mm512_add_pd(
                    _mm512_add_pd(_mm512_mul_pd(vx, vx), _mm512_mul_pd(vy, vy)),
                    _mm512_mul_pd(vz, vz),
                );
                let rate = match t.v {
                    Some(v) => {
                        let vb = v.as_ptr().cast::<f64>();
                        let gv = |offset: usize| {
                            _mm512_mask_i32gather_pd::<8>(splat(0.0), valid, three, vb.add(offset))
                        };
                        let dot = _mm512_add_pd(
                            _mm512_add_pd(_mm512_mul_pd(gv(0), gx), _mm512_mul_pd(gv(1), gy)),
                            _mm512_mul_pd(gv(2), gz),
                        );
                        _mm512_mul_pd(vj, dot)
                    }
                    None => splat(0.0),
                };
                // The sums pair by pair, in the scalar form's order, so that both give the
                // same densities and factors to the last bit (a different order changes the
                // run's trajectory at the rounding level).
                let mut terms = [[0.0; 8]; 6];
                for (row, term) in
                    terms
                        .iter_mut()
                        .zip([_mm512_mul_pd(vj, w), vx, vy, vz, sq, rate])
                {
                    _mm512_storeu_pd(row.as_mut_ptr(), term);
                }
                let [w, gx, gy, gz, sq, rate] = &terms;
                for l in 0..lanes {
                    sums.w += w[l];
                    sums.grad += Vec3::new(gx[l], gy[l], gz[l]);
                    sums.grad_sq += sq[l];
                    sums.rate += rate[l];
                }
            }
        }
        sums
    }
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

    /// The vector row stores the same gradients and sums as the scalar one, bit for bit, on
    /// fluid rows (one volume) and wall rows (a volume and a velocity
    /// each), including a coincident pair, rows of every length from 0 to 40 (partial
    /// vectors) and pairs beyond the support. (Without AVX-512 on the CPU it does not run.)
    #[test]
    #[cfg(target_arch = "x86_64")]
    fn the_vector_row_matches_the_scalar_row() {
        if !row::wide_available() {
            return;
        }
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
                let (mut a, mut b) = (vec![[0f32; 3]; len], vec![[1f32; 3]; len]);
                let want = row::scalar(&kernel, &xi, &t, &list, &mut a, 0.5);
                // SAFETY: the CPU has the feature, checked above.
                let got = unsafe { row::wide(&kernel, &xi, &t, &list, &mut b, 0.5) };
                assert_eq!(a, b, "gradients, {len} pairs");
                assert_eq!(got, want, "sums, {len} pairs");
                if len > 0 {
                    assert!(want.w > 0.0, "the coincident first pair carries W(0)");
                }
            }
        }
    }
}
