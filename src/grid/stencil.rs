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
//! Faces inside the grid may carry a weight other than one ([`Problem::weights`]): the fluid's
//! share of the face for the pressure of cut cells (Ng, Min & Gibou 2009, Eq. 11), one over the
//! distance to the wall for the ghost-fluid viscosity (Gibou et al. 2002, Eq. 9). A weighted
//! face scales the coupling or the Dirichlet term it carries; it keeps the matrix symmetric.
//!
//! The fine operator packs two bytes per cell: bit `2 * axis + up` says whether that face couples
//! two unknowns, bits 6..10 hold the diagonal count (unknown and Dirichlet neighbours plus side
//! weights, at most 12), bit 10 marks an unknown, bit 11 a cell with a weighted face, whose
//! weights and diagonal are stored apart. Cells with all six faces coupled at unit weight (most
//! of a fluid region) take a fast path with no weights at all.

use super::layout::{Layout, RowNeighbours};
use crate::parallel::ordered_sum;
use rayon::prelude::*;
use std::ops::{Add, Mul};

pub(crate) const SOLID: u8 = 0;
pub(crate) const FLUID: u8 = 1;
pub(crate) const DIRICHLET: u8 = 2;

const FACES: u16 = 0x3f;
const COUNT_SHIFT: u32 = 6;
const FLUID_BIT: u16 = 1 << 10;
const WEIGHTED_BIT: u16 = 1 << 11;

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
    /// Weight of the face between each cell and its upper neighbour along each axis, flat C
    /// order per axis (`None`: every face weighs one). Faces to the ghosts beyond a side weigh
    /// one whatever is stored.
    pub weights: Option<[Vec<f32>; 3]>,
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

    /// The Dirichlet terms along `axis` of unknown `c` with their faces' weights (the sides with
    /// theirs), as its weighted diagonal counts them.
    pub fn weighted_dirichlet(&self, axis: usize, c: [usize; 3]) -> f32 {
        let mut sum = 0.0;
        for face in self.faces(axis, c).into_iter().flatten() {
            match face {
                Face::Cell { kind, weight } if kind == DIRICHLET => sum += weight,
                Face::Cell { .. } => {}
                Face::Side(weight) => sum += f32::from(weight),
            }
        }
        sum
    }

    /// The two faces of cell `c` along `axis`, low then high: the cell beyond with the face's
    /// weight, or the domain's side with its ghost's weight (None across a periodic side).
    fn faces(&self, axis: usize, c: [usize; 3]) -> [Option<Face>; 2] {
        let l = &self.layout;
        let idx = l.index(c[0], c[1], c[2]);
        [false, true].map(|up| match l.step(axis, c[axis], up) {
            Some(s) => {
                let mut nb = c;
                nb[axis] = s;
                let j = l.index(nb[0], nb[1], nb[2]);
                Some(Face::Cell {
                    kind: self.kinds[j],
                    weight: self.weight(axis, if up { idx } else { j }),
                })
            }
            None if !l.periodic[axis] => Some(Face::Side(self.side_weight[axis][usize::from(up)])),
            None => None,
        })
    }

    /// Per-axis Dirichlet weights of every cell, computed once for the builders.
    pub fn dirichlet_table(&self) -> DirichletTable {
        let l = self.layout;
        let open_side =
            (0..3).any(|a| !l.periodic[a] && self.side_weight[a].iter().any(|&w| w > 0));
        if !open_side && !self.kinds.contains(&DIRICHLET) {
            return DirichletTable(None);
        }
        let mut t = vec![[0u8; 3]; l.len()];
        let fill = |(i, slab): (usize, &mut [[u8; 3]])| {
            for j in 0..l.n[1] {
                for k in 0..l.n[2] {
                    slab[j * l.n[2] + k] = self.dirichlet_weights([i, j, k]);
                }
            }
        };
        if l.len() >= PARALLEL_MIN_CELLS {
            t.par_chunks_mut(l.slab()).enumerate().for_each(fill);
        } else {
            t.chunks_mut(l.slab()).enumerate().for_each(fill);
        }
        DirichletTable(Some(t))
    }

    /// Weight of the face between cell `lower` and its upper neighbour along `axis`.
    #[inline]
    fn weight(&self, axis: usize, lower: usize) -> f32 {
        self.weights.as_ref().map_or(1.0, |w| w[axis][lower])
    }

    /// The packed code of cell `(i, j, k)` (see the module documentation) without the weighted
    /// bit: a face couples two unknowns when its weight is not zero.
    fn code(&self, c: [usize; 3], dirichlet: &DirichletTable) -> u16 {
        let l = &self.layout;
        let idx = l.index(c[0], c[1], c[2]);
        if self.kinds[idx] != FLUID {
            return 0;
        }
        let mut bits = 0u16;
        let mut count: u16 = dirichlet.get(idx).iter().map(|&d| u16::from(d)).sum();
        for axis in 0..3 {
            for up in [false, true] {
                if let Some(s) = l.step(axis, c[axis], up) {
                    let mut nb = c;
                    nb[axis] = s;
                    let j = l.index(nb[0], nb[1], nb[2]);
                    let lower = if up { idx } else { j };
                    if self.kinds[j] == FLUID && self.weight(axis, lower) > 0.0 {
                        count += 1;
                        bits |= 1 << (2 * axis + usize::from(up));
                    }
                }
            }
        }
        FLUID_BIT | (count << COUNT_SHIFT) | bits
    }

    /// The weighted sum of an unknown's coupled and Dirichlet faces (sides with their weight),
    /// and whether any of those faces weighs other than one.
    fn weighted_count(&self, c: [usize; 3]) -> (f64, bool) {
        let (mut sum, mut weighted) = (0.0, false);
        for axis in 0..3 {
            for face in self.faces(axis, c).into_iter().flatten() {
                match face {
                    Face::Cell { kind, weight } if kind != SOLID && weight > 0.0 => {
                        sum += f64::from(weight);
                        weighted |= weight != 1.0;
                    }
                    Face::Cell { .. } => {}
                    Face::Side(weight) => sum += f64::from(weight),
                }
            }
        }
        (sum, weighted)
    }
}

/// One face of a cell ([`Problem::faces`]).
enum Face {
    /// Towards the cell beyond, of that kind, with the face's weight.
    Cell { kind: u8, weight: f32 },
    /// On a domain side that is not periodic, with its ghost's weight.
    Side(u8),
}

/// Per-axis Dirichlet weights of the cells (`None`: zero everywhere).
pub(crate) struct DirichletTable(Option<Vec<[u8; 3]>>);

impl DirichletTable {
    #[inline]
    pub fn get(&self, idx: usize) -> [u8; 3] {
        self.0.as_ref().map_or([0; 3], |t| t[idx])
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
    /// Weight of the face between cell `idx` and its lower neighbour `below` along `axis`.
    #[inline(always)]
    fn lower(&self, axis: usize, _idx: usize, below: usize) -> f32 {
        self.upper(axis, below)
    }
    /// Whether all six faces of `idx` have unit weight (the sum needs no weights).
    #[inline(always)]
    fn unit_faces(&self, _idx: usize) -> bool {
        false
    }
    /// Factor on the neighbour sum.
    fn scale(&self) -> f32;
    fn diagonal(&self, idx: usize) -> f32;
    /// `1 / diagonal`, or 0 for cells that are not unknowns (their value stays 0).
    fn inv_diagonal(&self, idx: usize) -> f32;
}

/// Flat offsets of a row and its neighbour rows; a missing neighbour row is replaced by the row
/// itself, with a zero mask on the lower faces (upper faces to nothing have zero weight).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Row {
    base: usize,
    nz: usize,
    xm: usize,
    xp: usize,
    ym: usize,
    yp: usize,
    mask_xm: f32,
    mask_ym: f32,
    /// The lower z neighbour of k = 0 (the last cell on a periodic axis).
    z_low: Option<usize>,
}

impl Row {
    pub fn new(l: &Layout, i: usize, j: usize) -> Self {
        let nb: RowNeighbours = l.row_neighbours(i, j);
        let mask = |o: Option<usize>| if o.is_some() { 1.0 } else { 0.0 };
        Self {
            base: nb.base,
            nz: l.n[2],
            xm: nb.xm.unwrap_or(nb.base),
            xp: nb.xp.unwrap_or(nb.base),
            ym: nb.ym.unwrap_or(nb.base),
            yp: nb.yp.unwrap_or(nb.base),
            mask_xm: mask(nb.xm),
            mask_ym: mask(nb.ym),
            z_low: l.step(2, 0, false),
        }
    }

    pub fn base(&self) -> usize {
        self.base
    }

    /// Calls `f(k, sum_j w_ij v_j)` (unscaled, over the six faces of cell `base + k`) for
    /// `k = first, first + step, ...` along the row. The two end cells take the general path
    /// (z wrap or missing neighbour); the cells between need no z checks.
    #[inline(always)]
    pub fn face_sums<V, C>(
        &self,
        first: usize,
        step: usize,
        coef: &C,
        get: impl Fn(usize) -> V,
        mut f: impl FnMut(usize, V),
    ) where
        V: Copy + Add<Output = V> + Mul<Output = V> + From<f32>,
        C: Coefficients + ?Sized,
    {
        let mut k = first;
        if k == 0 && self.nz > 0 {
            f(0, self.face_sum(0, coef, &get));
            k += step;
        }
        while k + 1 < self.nz {
            let c = self.base + k;
            f(k, self.sum(k, c - 1, 1.0, c + 1, coef, &get));
            k += step;
        }
        if k + 1 == self.nz {
            f(k, self.face_sum(k, coef, &get));
        }
    }

    /// `sum_j w_ij v_j` over the six faces of cell `base + k` (unscaled).
    #[inline(always)]
    pub fn face_sum<V, C>(&self, k: usize, coef: &C, get: impl Fn(usize) -> V) -> V
    where
        V: Copy + Add<Output = V> + Mul<Output = V> + From<f32>,
        C: Coefficients + ?Sized,
    {
        let c = self.base + k;
        let (zm, mask_zm) = if k > 0 {
            (c - 1, 1.0)
        } else {
            match self.z_low {
                Some(kk) => (self.base + kk, 1.0),
                None => (c, 0.0),
            }
        };
        let zp = if k + 1 < self.nz {
            c + 1
        } else if self.z_low.is_some() {
            self.base
        } else {
            c
        };
        self.sum(k, zm, mask_zm, zp, coef, get)
    }

    /// [`Self::face_sum`] with the z neighbours `zm` (weighted by `mask_zm`) and `zp` given.
    #[inline(always)]
    fn sum<V, C>(
        &self,
        k: usize,
        zm: usize,
        mask_zm: f32,
        zp: usize,
        coef: &C,
        get: impl Fn(usize) -> V,
    ) -> V
    where
        V: Copy + Add<Output = V> + Mul<Output = V> + From<f32>,
        C: Coefficients + ?Sized,
    {
        let c = self.base + k;
        if coef.unit_faces(c) {
            return get(self.xp + k)
                + get(self.xm + k)
                + get(self.yp + k)
                + get(self.ym + k)
                + get(zp)
                + get(zm);
        }
        let up = |axis: usize| V::from(coef.upper(axis, c));
        let low = |axis: usize, below: usize, mask: f32| V::from(mask * coef.lower(axis, c, below));
        up(0) * get(self.xp + k)
            + low(0, self.xm + k, self.mask_xm) * get(self.xm + k)
            + up(1) * get(self.yp + k)
            + low(1, self.ym + k, self.mask_ym) * get(self.ym + k)
            + up(2) * get(zp)
            + low(2, zm, mask_zm) * get(zm)
    }
}

/// The fine operator, two bytes per cell, applied in f64 by the outer CG.
#[derive(Clone, Debug)]
pub(crate) struct FineStencil {
    pub layout: Layout,
    code: Vec<u16>,
    pub scale: f64,
    /// Diagonal by `code >> COUNT_SHIFT` (unknown bit and count).
    diag: [f64; 32],
    /// The cells with a weighted face, stored apart (empty without [`Problem::weights`]).
    weighted: Weighted,
}

/// The weights of a fine operator with weighted faces: per axis the weight of each cell's upper
/// face where it couples two unknowns (zero elsewhere), and the diagonal of the weighted cells
/// (f64 for the CG's apply, f32 with its inverse for the smoother).
#[derive(Clone, Debug, Default)]
struct Weighted {
    upper: [Vec<f32>; 3],
    diag: Vec<f64>,
    diag32: Vec<f32>,
    inv32: Vec<f32>,
}

impl FineStencil {
    pub fn new(p: &Problem, dirichlet: &DirichletTable) -> Self {
        let l = p.layout;
        let mut code = vec![0u16; l.len()];
        let fill = |(i, slab): (usize, &mut [u16])| {
            for j in 0..l.n[1] {
                for k in 0..l.n[2] {
                    slab[j * l.n[2] + k] = p.code([i, j, k], dirichlet);
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
        let weighted = p
            .weights
            .as_ref()
            .map_or_else(Weighted::default, |w| Weighted::new(p, w, &mut code));
        Self {
            layout: l,
            code,
            scale: p.scale,
            diag,
            weighted,
        }
    }

    pub fn is_unknown(&self, idx: usize) -> bool {
        self.code[idx] & FLUID_BIT != 0
    }

    /// The weight of the face of `idx` to its upper neighbour along `axis` if it couples two
    /// unknowns, else 0.
    pub fn upper_weight(&self, axis: usize, idx: usize) -> f32 {
        if self.code[idx] & (1 << (2 * axis + 1)) == 0 {
            0.0
        } else if self.weighted.upper[axis].is_empty() {
            1.0
        } else {
            self.weighted.upper[axis][idx]
        }
    }

    /// The diagonal of cell `c`.
    #[inline(always)]
    fn diagonal(&self, c: usize) -> f64 {
        let code = self.code[c];
        if code & WEIGHTED_BIT != 0 {
            self.weighted.diag[c]
        } else {
            self.diag[usize::from(code >> COUNT_SHIFT)]
        }
    }

    /// `y = A x`, and returns `x . y` (the CG needs both; fused to read `x` once).
    pub fn apply_dot(&self, x: &[f64], y: &mut [f64]) -> f64 {
        let l = self.layout;
        let coef = FineCoefficients::unscaled(self);
        let slab = |(i, ys): (usize, &mut [f64])| {
            let mut dot = 0.0;
            for j in 0..l.n[1] {
                let row = Row::new(&l, i, j);
                let out = &mut ys[j * l.n[2]..][..l.n[2]];
                row.face_sums(
                    0,
                    1,
                    &coef,
                    |m| x[m],
                    |k, s: f64| {
                        let c = row.base + k;
                        let v = self.diagonal(c) * x[c] - self.scale * s;
                        out[k] = v;
                        dot += v * x[c];
                    },
                );
            }
            dot
        };
        if l.len() >= PARALLEL_MIN_CELLS {
            ordered_sum(y.par_chunks_mut(l.slab()).enumerate().map(slab))
        } else {
            y.chunks_mut(l.slab()).enumerate().map(slab).sum()
        }
    }
}

impl Weighted {
    /// Marks the weighted cells in `code` and stores their weights and diagonals.
    fn new(p: &Problem, weights: &[Vec<f32>; 3], code: &mut [u16]) -> Self {
        let l = p.layout;
        let upper = std::array::from_fn(|a| {
            (0..l.len())
                .map(|c| {
                    if code[c] & (1 << (2 * a + 1)) != 0 {
                        weights[a][c]
                    } else {
                        0.0
                    }
                })
                .collect()
        });
        let mut diag = vec![0.0; l.len()];
        for (c, (code, d)) in code.iter_mut().zip(&mut diag).enumerate() {
            if *code & FLUID_BIT == 0 {
                continue;
            }
            let (sum, weighted) = p.weighted_count(super::poisson::coordinates(&l, c));
            if weighted {
                *code |= WEIGHTED_BIT;
                *d = p.shift + p.scale * sum;
            }
        }
        let diag32: Vec<f32> = diag.iter().map(|&d| d as f32).collect();
        let inv32 = diag32
            .iter()
            .map(|&d| if d > 0.0 { 1.0 / d } else { 0.0 })
            .collect();
        Self {
            upper,
            diag,
            diag32,
            inv32,
        }
    }
}

/// The fine operator seen by the f32 multigrid smoother.
pub(crate) struct FineCoefficients<'a> {
    code: &'a [u16],
    weighted: &'a Weighted,
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
            weighted: &s.weighted,
            scale: s.scale as f32,
            diag,
            inv,
        }
    }

    /// Face weights without the scale, for the exact f64 apply.
    fn unscaled(s: &'a FineStencil) -> Self {
        Self {
            code: &s.code,
            weighted: &s.weighted,
            scale: 1.0,
            diag: [0.0; 32],
            inv: [0.0; 32],
        }
    }

    #[inline(always)]
    fn is_weighted(&self, idx: usize) -> bool {
        self.code[idx] & WEIGHTED_BIT != 0
    }
}

impl Coefficients for FineCoefficients<'_> {
    #[inline(always)]
    fn upper(&self, axis: usize, idx: usize) -> f32 {
        if self.is_weighted(idx) {
            self.weighted.upper[axis][idx]
        } else {
            f32::from((self.code[idx] >> (2 * axis + 1)) & 1)
        }
    }
    #[inline(always)]
    fn lower(&self, axis: usize, idx: usize, below: usize) -> f32 {
        if self.is_weighted(idx) {
            self.weighted.upper[axis][below]
        } else {
            f32::from((self.code[idx] >> (2 * axis)) & 1)
        }
    }
    #[inline(always)]
    fn unit_faces(&self, idx: usize) -> bool {
        self.code[idx] & (FACES | WEIGHTED_BIT) == FACES
    }
    #[inline(always)]
    fn scale(&self) -> f32 {
        self.scale
    }
    #[inline(always)]
    fn diagonal(&self, idx: usize) -> f32 {
        if self.is_weighted(idx) {
            self.weighted.diag32[idx]
        } else {
            self.diag[usize::from(self.code[idx] >> COUNT_SHIFT)]
        }
    }
    #[inline(always)]
    fn inv_diagonal(&self, idx: usize) -> f32 {
        if self.is_weighted(idx) {
            self.weighted.inv32[idx]
        } else {
            self.inv[usize::from(self.code[idx] >> COUNT_SHIFT)]
        }
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
