//! Trilinear interpolation of staggered fields. A field's sample (i, j, k) sits at
//! `origin + dx * ((i, j, k) + offset)`; cell-centred fields have offset 0.5 on every axis, the
//! face component along axis a has offset 0 on a. Periodic axes wrap, the others clamp to the
//! outermost samples (zero-gradient extrapolation beyond the domain).

use ndarray::Array3;

use crate::Real;

/// Where a field's samples sit and how its axes continue past the ends.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stagger {
    /// Shape of the field's array.
    pub shape: [usize; 3],
    /// Sample offset in cells (0.5 cell-centred, 0 on a face's own axis).
    pub offset: [Real; 3],
    /// Period in samples along each axis (the cell count), or None where the axis clamps.
    pub period: [Option<usize>; 3],
}

impl Stagger {
    /// A cell-centred field on `dims` cells.
    pub fn cells(dims: [usize; 3], periodic: [bool; 3]) -> Self {
        Self {
            shape: dims,
            offset: [0.5; 3],
            period: std::array::from_fn(|a| periodic[a].then_some(dims[a])),
        }
    }

    /// The face component along `axis` on `dims` cells (one more sample along `axis`).
    pub fn faces(dims: [usize; 3], periodic: [bool; 3], axis: usize) -> Self {
        let mut s = Self::cells(dims, periodic);
        s.shape[axis] += 1;
        s.offset[axis] = 0.0;
        s
    }

    /// The two sample indices and the weight of the second along one axis, for a position `g`
    /// in cell units from the grid origin.
    #[inline]
    fn axis(&self, a: usize, g: Real) -> (usize, usize, Real) {
        let c = g - self.offset[a];
        let base = c.floor();
        let f = c - base;
        let i0 = base as isize;
        match self.period[a] {
            Some(n) => {
                let n = n as isize;
                let lo = i0.rem_euclid(n);
                ((lo) as usize, ((lo + 1) % n) as usize, f)
            }
            None => {
                let last = self.shape[a] as isize - 1;
                if i0 < 0 {
                    (0, 0, 0.0)
                } else if i0 >= last {
                    (last as usize, last as usize, 0.0)
                } else {
                    (i0 as usize, i0 as usize + 1, f)
                }
            }
        }
    }

    /// The field at position `g` (cell units from the grid origin), with the smallest and
    /// largest of the samples it was interpolated from.
    #[inline]
    pub fn sample_with_range(&self, field: &Array3<Real>, g: [Real; 3]) -> (Real, Real, Real) {
        let (i0, i1, fx) = self.axis(0, g[0]);
        let (j0, j1, fy) = self.axis(1, g[1]);
        let (k0, k1, fz) = self.axis(2, g[2]);
        let at = |i, j, k| field[[i, j, k]];
        let c = [
            at(i0, j0, k0),
            at(i1, j0, k0),
            at(i0, j1, k0),
            at(i1, j1, k0),
            at(i0, j0, k1),
            at(i1, j0, k1),
            at(i0, j1, k1),
            at(i1, j1, k1),
        ];
        let lerp = |a: Real, b: Real, t: Real| a + (b - a) * t;
        let x00 = lerp(c[0], c[1], fx);
        let x10 = lerp(c[2], c[3], fx);
        let x01 = lerp(c[4], c[5], fx);
        let x11 = lerp(c[6], c[7], fx);
        let value = lerp(lerp(x00, x10, fy), lerp(x01, x11, fy), fz);
        let (lo, hi) = c
            .iter()
            .fold((Real::INFINITY, Real::NEG_INFINITY), |(lo, hi), &v| {
                (lo.min(v), hi.max(v))
            });
        (value, lo, hi)
    }

    /// The field at position `g` (cell units from the grid origin).
    #[inline]
    pub fn sample(&self, field: &Array3<Real>, g: [Real; 3]) -> Real {
        self.sample_with_range(field, g).0
    }

    /// Position of sample (i, j, k) in cell units from the grid origin.
    #[inline]
    pub fn position(&self, idx: [usize; 3]) -> [Real; 3] {
        std::array::from_fn(|a| idx[a] as Real + self.offset[a])
    }
}
