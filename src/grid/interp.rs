//! Trilinear interpolation of staggered fields. A field's sample (i, j, k) sits at
//! `origin + dx * ((i, j, k) + offset)`; cell-centred fields have offset 0.5 on every axis, the
//! face component along axis a has offset 0 on a. Periodic axes wrap, the others clamp to the
//! outermost samples (zero-gradient extrapolation beyond the domain).

use ndarray::{Array3, ArrayRef, Ix3};

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

    /// The two sample indices and the weight of the second along axis `a`, for a position
    /// `g` in cell units from the grid origin.
    #[inline(always)]
    fn axis(&self, a: usize, g: Real) -> AxisWeights {
        axis_weights(g - self.offset[a], self.shape[a], self.period[a])
    }

    /// The eight samples of `data` (the field's standard-layout array as a slice) around
    /// position `g` (cell units from the grid origin), x fastest, and the weights along x, y, z.
    #[inline(always)]
    fn corners(&self, data: &[Real], g: [Real; 3]) -> ([Real; 8], [Real; 3]) {
        corners(
            data,
            self.shape,
            [self.axis(0, g[0]), self.axis(1, g[1]), self.axis(2, g[2])],
        )
    }

    /// The field whose standard-layout array is `data` at position `g` (cell units from the
    /// grid origin), with the smallest and largest of the samples it was interpolated from.
    #[inline(always)]
    pub(crate) fn sample_slice_with_range(
        &self,
        data: &[Real],
        g: [Real; 3],
    ) -> (Real, Real, Real) {
        let (c, f) = self.corners(data, g);
        let (lo, hi) = c
            .iter()
            .fold((Real::INFINITY, Real::NEG_INFINITY), |(lo, hi), &v| {
                (lo.min(v), hi.max(v))
            });
        (trilinear(&c, f), lo, hi)
    }

    /// The field whose standard-layout array is `data` at position `g` (cell units from the
    /// grid origin): [`Self::sample`] without the layout check, for loops over many samples.
    #[inline(always)]
    pub(crate) fn sample_slice(&self, data: &[Real], g: [Real; 3]) -> Real {
        let (c, f) = self.corners(data, g);
        trilinear(&c, f)
    }

    /// The field at position `g` (cell units from the grid origin).
    #[inline]
    pub fn sample(&self, field: &Array3<Real>, g: [Real; 3]) -> Real {
        self.sample_slice(standard(field), g)
    }

    /// The eight samples around position `g` (cell units from the grid origin) with their
    /// trilinear weights, x fastest: the transpose of [`Self::sample`], for spreading a
    /// quantity onto the samples it is read from. A clamped end repeats a sample at weight 0.
    pub fn weights(&self, g: [Real; 3]) -> [([usize; 3], Real); 8] {
        let w = [self.axis(0, g[0]), self.axis(1, g[1]), self.axis(2, g[2])];
        std::array::from_fn(|c| {
            let pick = |a: usize| {
                let (lo, hi, f) = w[a];
                if (c >> a) & 1 == 1 {
                    (hi, f)
                } else {
                    (lo, 1.0 - f)
                }
            };
            let (x, y, z) = (pick(0), pick(1), pick(2));
            ([x.0, y.0, z.0], x.1 * y.1 * z.1)
        })
    }

    /// The axis whose faces the samples sit on, or None for cell centres.
    pub fn face_axis(&self) -> Option<usize> {
        (0..3).find(|&a| self.offset[a] == 0.0)
    }

    /// Position of sample (i, j, k) in cell units from the grid origin.
    #[inline]
    pub fn position(&self, idx: [usize; 3]) -> [Real; 3] {
        std::array::from_fn(|a| idx[a] as Real + self.offset[a])
    }
}

/// The elements of a grid field in standard layout (as the grid makes them; callers that take
/// arrays from outside pass them through `as_standard_layout` first).
#[inline(always)]
pub(crate) fn standard(field: &ArrayRef<Real, Ix3>) -> &[Real] {
    field
        .as_slice()
        .expect("grid fields are in standard layout")
}

/// Trilinear interpolation of eight corner values (x fastest) at weights `f`.
#[inline(always)]
pub(crate) fn trilinear(c: &[Real; 8], f: [Real; 3]) -> Real {
    let lerp = |a: Real, b: Real, t: Real| a + (b - a) * t;
    let x00 = lerp(c[0], c[1], f[0]);
    let x10 = lerp(c[2], c[3], f[0]);
    let x01 = lerp(c[4], c[5], f[0]);
    let x11 = lerp(c[6], c[7], f[0]);
    lerp(lerp(x00, x10, f[1]), lerp(x01, x11, f[1]), f[2])
}

/// Two neighbouring sample indices along one axis and the weight of the second.
pub(crate) type AxisWeights = (usize, usize, Real);

/// The samples around coordinate `c` (in samples) on an axis of `len` samples: wrapped with
/// period `period`, or clamped to the end samples (zero weight beyond them).
#[inline(always)]
pub(crate) fn axis_weights(c: Real, len: usize, period: Option<usize>) -> AxisWeights {
    let Some(n) = period else {
        return clamped_axis_weights(c, len);
    };
    // floor by truncation: `f64::floor` is a libm call on baseline x86-64.
    let t = c as isize;
    let i0 = if (t as Real) > c { t - 1 } else { t };
    let f = c - i0 as Real;
    let n = n as isize;
    let lo = if (0..n).contains(&i0) {
        i0
    } else {
        i0.rem_euclid(n)
    };
    let hi = if lo + 1 == n { 0 } else { lo + 1 };
    (lo as usize, hi as usize, f)
}

/// [`axis_weights`] on an axis that clamps: the range test comes first, so that inside it the
/// floor is a plain truncation (the saturating `as` conversion costs a third of the call on
/// the advection's hot path). A NaN coordinate gives a NaN weight, which carries it on.
#[inline(always)]
fn clamped_axis_weights(c: Real, len: usize) -> AxisWeights {
    let last = len.saturating_sub(1);
    let end = last as i64 as Real;
    if c >= 0.0 && c < end {
        // SAFETY: 0 <= c < last (finite, so not NaN), so c truncates to an integer in range.
        let i0 = unsafe { c.to_int_unchecked::<i64>() };
        (i0 as usize, i0 as usize + 1, c - i0 as Real)
    } else if c >= end {
        (last, last, 0.0)
    } else if c < 0.0 || last == 0 {
        (0, 0, 0.0)
    } else {
        (0, 1, c)
    }
}

/// The eight samples of a standard-layout array of `shape` at the given axis weights, x
/// fastest, and the weights.
#[inline(always)]
pub(crate) fn corners(
    data: &[Real],
    shape: [usize; 3],
    [(i0, i1, fx), (j0, j1, fy), (k0, k1, fz)]: [AxisWeights; 3],
) -> ([Real; 8], [Real; 3]) {
    let sy = shape[2];
    let sx = shape[1] * sy;
    let (x0, x1, y0, y1) = (i0 * sx, i1 * sx, j0 * sy, j1 * sy);
    (
        [
            data[x0 + y0 + k0],
            data[x1 + y0 + k0],
            data[x0 + y1 + k0],
            data[x1 + y1 + k0],
            data[x0 + y0 + k1],
            data[x1 + y0 + k1],
            data[x0 + y1 + k1],
            data[x1 + y1 + k1],
        ],
        [fx, fy, fz],
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The clamped weights by their definition: the floor of the coordinate, clamped to the
    /// end samples with zero weight beyond them; the weight is the coordinate less the index.
    fn by_floor(c: Real, len: usize) -> AxisWeights {
        let last = len - 1;
        let fl = c.floor();
        if fl < 0.0 {
            (0, 0, 0.0)
        } else if fl >= last as Real {
            (last, last, 0.0)
        } else {
            (fl as usize, fl as usize + 1, c - (fl as usize) as Real)
        }
    }

    /// The clamped weights (range test first, then truncation) are the floor's, bit for bit,
    /// at random coordinates inside and beyond the axis, at the samples themselves, just off
    /// them and at the ends; a NaN coordinate gives a NaN weight.
    #[test]
    fn clamped_axis_weights_follow_the_floor() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        for len in [1, 2, 3, 17] {
            let l = len as Real;
            let mut coords: Vec<Real> =
                (0..2000).map(|_| rng.random_range(-3.0..l + 3.0)).collect();
            for s in -2..=len as i32 + 2 {
                let s = s as Real;
                coords.extend([s, s - 1e-15, s + 1e-15, s - 0.5, -0.0]);
            }
            for c in coords {
                let (i0, i1, f) = axis_weights(c, len, None);
                let (j0, j1, g) = by_floor(c, len);
                assert!(
                    (i0, i1) == (j0, j1) && f.to_bits() == g.to_bits(),
                    "len {len}, c = {c:e}: {:?} against {:?}",
                    (i0, i1, f),
                    (j0, j1, g)
                );
            }
            if len > 1 {
                assert!(axis_weights(Real::NAN, len, None).2.is_nan());
            }
        }
    }

    /// Spreading with [`Stagger::weights`] is the transpose of sampling: the weighted sum of a
    /// field's samples at the eight indices is the sampled value, on clamped and periodic
    /// axes, at random points inside and beyond the grid, and the weights sum to one.
    #[test]
    fn weights_are_the_samples_of_interpolation() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let dims = [5, 4, 3];
        for (axis, periodic) in [(0, [false; 3]), (1, [true, false, true]), (2, [true; 3])] {
            let stagger = Stagger::faces(dims, periodic, axis);
            let field = Array3::from_shape_fn(stagger.shape, |_| rng.random_range(-1.0..1.0));
            for _ in 0..500 {
                let g = std::array::from_fn(|a| rng.random_range(-1.0..dims[a] as Real + 1.0));
                let w = stagger.weights(g);
                let spread: Real = w.iter().map(|(idx, w)| w * field[*idx]).sum();
                let total: Real = w.iter().map(|(_, w)| w).sum();
                assert!(
                    (spread - stagger.sample(&field, g)).abs() < 1e-12,
                    "at {g:?}"
                );
                assert!(
                    (total - 1.0).abs() < 1e-12,
                    "weights sum to {total} at {g:?}"
                );
            }
        }
    }
}
