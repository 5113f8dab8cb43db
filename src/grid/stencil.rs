//! The 7-point operator `shift * I + scale * L` on a cell grid, where `L` is the unit-spacing
//! Laplacian with the positive semi-definite sign (the pressure and the diffusion systems differ
//! only in `shift` and `scale`).
//!
//! Cells are unknowns (`FLUID`), fixed at a Dirichlet value (`DIRICHLET`) or not part of the
//! problem (`SOLID`, no flux). A Dirichlet cell next to an unknown adds `scale` to its diagonal
//! (the fixed value goes to the right-hand side), a side of the grid adds `scale` times its
//! weight: 0 for a no-flux wall, 1 for a ghost cell held at zero, 2 for a mirror ghost (the value
//! -x_i, a zero-value wall half a cell outside).
//!
//! The fine operator packs one byte per cell: bits 0..3 say whether the face to the upper
//! neighbour along x, y, z couples two unknowns, bits 3..7 hold the diagonal count (unknown and
//! Dirichlet neighbours plus side weights, at most 12), bit 7 marks an unknown.

use super::layout::{Layout, RowNeighbours};
use rayon::prelude::*;
use std::ops::{Add, Mul};

pub(crate) const SOLID: u8 = 0;
pub(crate) const FLUID: u8 = 1;
pub(crate) const DIRICHLET: u8 = 2;

const FLUID_BIT: u8 = 1 << 7;
const COUNT_SHIFT: u32 = 3;

/// Grids with fewer cells than this are processed on one thread (spawning costs more).
pub(crate) const PARALLEL_MIN_CELLS: usize = 1 << 14;

/// The system to solve, as the public entry points describe it.
#[derive(Clone, Debug)]
pub(crate) struct Problem {
    pub layout: Layout,
    /// `SOLID`, `FLUID` or `DIRICHLET` per cell, flat C order.
    pub kinds: Vec<u8>,
    /// Dirichlet weight of the ghost beyond each side, `[axis][0 = low, 1 = high]`.
    pub side_weight: [[u8; 2]; 3],
    pub shift: f64,
    pub scale: f64,
}

impl Problem {
    /// Dirichlet weight along each axis of cell `(i, j, k)` (zero for cells that are not unknowns).
    pub fn dirichlet_weights(&self, c: [usize; 3]) -> [u8; 3] {
        let mut d = [0u8; 3];
        if self.kinds[self.layout.index(c[0], c[1], c[2])] != FLUID {
            return d;
        }
        for (axis, da) in d.iter_mut().enumerate() {
            for (side, up) in [false, true].into_iter().enumerate() {
                match self.layout.step(axis, c[axis], up) {
                    Some(s) => {
                        let mut nb = c;
                        nb[axis] = s;
                        if self.kinds[self.layout.index(nb[0], nb[1], nb[2])] == DIRICHLET {
                            *da += 1;
                        }
                    }
                    None if !self.layout.periodic[axis] => *da += self.side_weight[axis][side],
                    None => {}
                }
            }
        }
        d
    }

    /// The packed byte of cell `(i, j, k)` (see the module documentation).
    fn code(&self, c: [usize; 3]) -> u8 {
        let l = &self.layout;
        if self.kinds[l.index(c[0], c[1], c[2])] != FLUID {
            return 0;
        }
        let mut bits = 0u8;
        let mut count: u8 = self.dirichlet_weights(c).iter().sum();
        for axis in 0..3 {
            for up in [false, true] {
                if let Some(s) = l.step(axis, c[axis], up) {
                    let mut nb = c;
                    nb[axis] = s;
                    if self.kinds[l.index(nb[0], nb[1], nb[2])] == FLUID {
                        count += 1;
                        if up {
                            bits |= 1 << axis;
                        }
                    }
                }
            }
        }
        FLUID_BIT | (count << COUNT_SHIFT) | bits
    }
}

/// Runs `f(i)` for every x-slab `i < n`, in parallel when the grid is large enough.
pub(crate) fn for_each_slab(layout: &Layout, f: impl Fn(usize) + Sync + Send) {
    if layout.len() >= PARALLEL_MIN_CELLS {
        (0..layout.n[0]).into_par_iter().for_each(f);
    } else {
        (0..layout.n[0]).for_each(f);
    }
}

/// Coefficients of one multigrid level, read cell by cell by the smoothing kernels.
pub(crate) trait Coefficients: Sync {
    /// Weight of the face between cell `idx` and its upper neighbour along `axis`, before
    /// [`Coefficients::scale`].
    fn upper(&self, axis: usize, idx: usize) -> f32;
    /// Factor on the neighbour sum.
    fn scale(&self) -> f32;
    fn diagonal(&self, idx: usize) -> f32;
    /// `1 / diagonal`, or 0 for cells that are not unknowns (their value stays 0).
    fn inv_diagonal(&self, idx: usize) -> f32;
}

/// `sum_j w_ij v_j` over the six faces of cell `base + k` of a row (unscaled).
#[inline(always)]
pub(crate) fn neighbour_sum<V, C>(
    nb: &RowNeighbours,
    k: usize,
    kz: (Option<usize>, Option<usize>),
    coef: &C,
    get: impl Fn(usize) -> V,
) -> V
where
    V: Copy + Add<Output = V> + Mul<Output = V> + From<f32>,
    C: Coefficients + ?Sized,
{
    let c = nb.base + k;
    let mut s = V::from(0.0);
    if let Some(r) = nb.xp {
        s = s + V::from(coef.upper(0, c)) * get(r + k);
    }
    if let Some(r) = nb.xm {
        s = s + V::from(coef.upper(0, r + k)) * get(r + k);
    }
    if let Some(r) = nb.yp {
        s = s + V::from(coef.upper(1, c)) * get(r + k);
    }
    if let Some(r) = nb.ym {
        s = s + V::from(coef.upper(1, r + k)) * get(r + k);
    }
    if let Some(kk) = kz.1 {
        s = s + V::from(coef.upper(2, c)) * get(nb.base + kk);
    }
    if let Some(kk) = kz.0 {
        s = s + V::from(coef.upper(2, nb.base + kk)) * get(nb.base + kk);
    }
    s
}

/// The fine operator, one byte per cell, applied in f64 by the outer CG.
#[derive(Clone, Debug)]
pub(crate) struct FineStencil {
    pub layout: Layout,
    pub code: Vec<u8>,
    pub scale: f64,
    /// Diagonal by `code >> 3` (unknown bit and count).
    diag: [f64; 32],
}

impl FineStencil {
    pub fn new(p: &Problem) -> Self {
        let l = p.layout;
        let mut code = vec![0u8; l.len()];
        let fill = |(i, slab): (usize, &mut [u8])| {
            for j in 0..l.n[1] {
                for k in 0..l.n[2] {
                    slab[j * l.n[2] + k] = p.code([i, j, k]);
                }
            }
        };
        if l.len() >= PARALLEL_MIN_CELLS {
            code.par_chunks_mut(l.slab()).enumerate().for_each(fill);
        } else {
            code.chunks_mut(l.slab()).enumerate().for_each(fill);
        }
        let mut diag = [0.0; 32];
        for (count, d) in diag[16..].iter_mut().enumerate() {
            *d = p.shift + p.scale * count as f64;
        }
        Self {
            layout: l,
            code,
            scale: p.scale,
            diag,
        }
    }

    pub fn is_unknown(&self, idx: usize) -> bool {
        self.code[idx] & FLUID_BIT != 0
    }

    /// `y = A x`, and returns `x . y` (the CG needs both; fused to read `x` once).
    pub fn apply_dot(&self, x: &[f64], y: &mut [f64]) -> f64 {
        let l = self.layout;
        let coef = FineCoefficients::unscaled(self);
        let slab = |(i, ys): (usize, &mut [f64])| {
            let mut dot = 0.0;
            for j in 0..l.n[1] {
                let nb = l.row_neighbours(i, j);
                for k in 0..l.n[2] {
                    let c = nb.base + k;
                    let kz = (l.step(2, k, false), l.step(2, k, true));
                    let s: f64 = neighbour_sum(&nb, k, kz, &coef, |m| x[m]);
                    let v =
                        self.diag[usize::from(self.code[c] >> COUNT_SHIFT)] * x[c] - self.scale * s;
                    ys[j * l.n[2] + k] = v;
                    dot += v * x[c];
                }
            }
            dot
        };
        if l.len() >= PARALLEL_MIN_CELLS {
            y.par_chunks_mut(l.slab()).enumerate().map(slab).sum()
        } else {
            y.chunks_mut(l.slab()).enumerate().map(slab).sum()
        }
    }
}

/// The fine operator seen by the f32 multigrid smoother.
pub(crate) struct FineCoefficients<'a> {
    code: &'a [u8],
    scale: f32,
    diag: [f32; 32],
    inv: [f32; 32],
}

impl<'a> FineCoefficients<'a> {
    pub fn new(s: &'a FineStencil) -> Self {
        let diag = s.diag.map(|d| d as f32);
        let inv = diag.map(|d| if d > 0.0 { 1.0 / d } else { 0.0 });
        Self {
            code: &s.code,
            scale: s.scale as f32,
            diag,
            inv,
        }
    }

    /// Face weights without the scale (0 or 1), for the exact f64 apply.
    fn unscaled(s: &'a FineStencil) -> Self {
        Self {
            code: &s.code,
            scale: 1.0,
            diag: [0.0; 32],
            inv: [0.0; 32],
        }
    }
}

impl Coefficients for FineCoefficients<'_> {
    #[inline(always)]
    fn upper(&self, axis: usize, idx: usize) -> f32 {
        f32::from((self.code[idx] >> axis) & 1)
    }
    #[inline(always)]
    fn scale(&self) -> f32 {
        self.scale
    }
    #[inline(always)]
    fn diagonal(&self, idx: usize) -> f32 {
        self.diag[usize::from(self.code[idx] >> COUNT_SHIFT)]
    }
    #[inline(always)]
    fn inv_diagonal(&self, idx: usize) -> f32 {
        self.inv[usize::from(self.code[idx] >> COUNT_SHIFT)]
    }
}

/// Coefficients of a coarse level, stored per cell (the scale is folded into the weights).
#[derive(Clone, Debug, Default)]
pub(crate) struct CoarseCoefficients {
    pub upper: [Vec<f32>; 3],
    pub diag: Vec<f32>,
    pub inv: Vec<f32>,
}

impl Coefficients for CoarseCoefficients {
    #[inline(always)]
    fn upper(&self, axis: usize, idx: usize) -> f32 {
        self.upper[axis][idx]
    }
    #[inline(always)]
    fn scale(&self) -> f32 {
        1.0
    }
    #[inline(always)]
    fn diagonal(&self, idx: usize) -> f32 {
        self.diag[idx]
    }
    #[inline(always)]
    fn inv_diagonal(&self, idx: usize) -> f32 {
        self.inv[idx]
    }
}
