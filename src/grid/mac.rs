//! The staggered (MAC) velocity field: component a lives on the faces normal to axis a, so the
//! discrete divergence of a cell is a difference of its own six face values.

use ndarray::{Array3, Axis, Zip};
use rayon::prelude::*;

use super::interp::{axis_weights, corners, trilinear, AxisWeights, Stagger};
use crate::{Real, Vec3};

/// Face velocities on a box of cubic cells.
#[derive(Debug, Clone)]
pub struct MacGrid {
    /// Cells along x, y, z.
    pub dims: [usize; 3],
    /// Cell size, m.
    pub dx: Real,
    /// Lower corner of the grid, m.
    pub origin: Vec3,
    /// Axes that wrap; on them face n duplicates face 0 (kept equal by [`Self::sync_periodic`]).
    pub periodic: [bool; 3],
    /// Face velocity components, `u[a]` of shape `dims + e_a`, m/s.
    pub u: [Array3<Real>; 3],
}

impl MacGrid {
    /// A fluid at rest.
    pub fn new(dims: [usize; 3], dx: Real, origin: Vec3, periodic: [bool; 3]) -> Self {
        let u = std::array::from_fn(|a| Array3::zeros(Stagger::faces(dims, periodic, a).shape));
        Self {
            dims,
            dx,
            origin,
            periodic,
            u,
        }
    }

    /// The grid's lower and upper corners, m: the domain its sides bound.
    pub fn corners(&self) -> (Vec3, Vec3) {
        let size = Vec3::from(self.dims.map(|d| d as Real)) * self.dx;
        (self.origin, self.origin + size)
    }

    /// Number of cells.
    pub fn cell_count(&self) -> usize {
        self.dims.iter().product()
    }

    /// How the faces of component `a` are laid out.
    pub fn face_stagger(&self, a: usize) -> Stagger {
        Stagger::faces(self.dims, self.periodic, a)
    }

    /// How cell-centred fields are laid out.
    pub fn cell_stagger(&self) -> Stagger {
        Stagger::cells(self.dims, self.periodic)
    }

    /// World position of a point given in cell units from the origin.
    pub fn world(&self, g: [Real; 3]) -> Vec3 {
        self.origin + Vec3::new(g[0], g[1], g[2]) * self.dx
    }

    /// A world position in cell units from the origin.
    pub fn grid_coords(&self, x: &Vec3) -> [Real; 3] {
        let g = (x - self.origin) / self.dx;
        [g.x, g.y, g.z]
    }

    /// Centre of cell (i, j, k), m.
    pub fn cell_center(&self, idx: [usize; 3]) -> Vec3 {
        self.world(self.cell_stagger().position(idx))
    }

    /// Centre of face (i, j, k) of component `a`, m.
    pub fn face_center(&self, a: usize, idx: [usize; 3]) -> Vec3 {
        self.world(self.face_stagger(a).position(idx))
    }

    /// The face arrays as flat slices, for loops that sample the velocity many times.
    #[inline]
    pub(crate) fn view(&self) -> MacView<'_> {
        MacView {
            u: std::array::from_fn(|a| {
                self.u[a]
                    .as_slice()
                    .expect("face arrays are in standard layout")
            }),
            dims: self.dims,
            periodic: self.periodic,
        }
    }

    /// Velocity at a point given in cell units, by trilinear interpolation of each component.
    #[inline]
    pub fn velocity_at_grid(&self, g: [Real; 3]) -> Vec3 {
        Vec3::from(self.view().velocity_at_grid(g))
    }

    /// Velocity exactly at sample `idx` of a field on the faces of component `face_axis` (or at
    /// a cell centre for None): the value trilinear interpolation gives there, read from two or
    /// four faces per component instead of eight weighted samples (advection's hot path).
    #[inline]
    pub fn velocity_at_sample(&self, face_axis: Option<usize>, idx: [usize; 3]) -> Vec3 {
        Vec3::from(self.view().velocity_at_sample_dyn(face_axis, idx))
    }

    /// Velocity at a world position, m/s.
    pub fn velocity_at(&self, x: &Vec3) -> Vec3 {
        self.velocity_at_grid(self.grid_coords(x))
    }

    /// Copies face 0 onto face n along every periodic axis, so both copies agree.
    pub fn sync_periodic(&mut self) {
        for a in 0..3 {
            if self.periodic[a] {
                let n = self.dims[a];
                let first = self.u[a].index_axis(Axis(a), 0).to_owned();
                self.u[a].index_axis_mut(Axis(a), n).assign(&first);
            }
        }
    }

    /// Net outflow of every cell, sum over its faces of u . n (m/s); the divergence is this / dx.
    pub fn net_outflow(&self) -> Array3<Real> {
        let mut out = Array3::zeros(self.dims);
        self.net_outflow_scaled(1.0, &mut out);
        out
    }

    /// `out = sign * net outflow` (`sign` is 1 or -1; the projection wants the inflow), row by
    /// row over flat slices.
    pub(crate) fn net_outflow_scaled(&self, sign: Real, out: &mut Array3<Real>) {
        let [_, n1, n2] = self.dims;
        let [u, v, w] = self.view().u;
        let out = out
            .as_slice_mut()
            .expect("a cell array is in standard layout");
        if out.is_empty() {
            return;
        }
        out.par_chunks_mut(n1 * n2)
            .enumerate()
            .for_each(|(i, slab)| {
                for (j, row) in slab.chunks_mut(n2).enumerate() {
                    // Rows of u at x-faces i and i + 1, of v at y-faces j and j + 1, of w at (i, j).
                    let u0 = &u[(i * n1 + j) * n2..][..n2];
                    let u1 = &u[((i + 1) * n1 + j) * n2..][..n2];
                    let v0 = &v[(i * (n1 + 1) + j) * n2..][..n2];
                    let v1 = &v[(i * (n1 + 1) + j + 1) * n2..][..n2];
                    let w = &w[(i * n1 + j) * (n2 + 1)..][..n2 + 1];
                    for k in 0..n2 {
                        row[k] = sign * (u1[k] - u0[k] + v1[k] - v0[k] + w[k + 1] - w[k]);
                    }
                }
            });
    }

    /// Velocity averaged to cell centres.
    pub fn cell_velocity(&self) -> [Array3<Real>; 3] {
        std::array::from_fn(|a| {
            let f = &self.u[a];
            let mut out = Array3::zeros(self.dims);
            Zip::indexed(&mut out).par_for_each(|(i, j, k), c| {
                let mut next = [i, j, k];
                next[a] += 1;
                *c = 0.5 * (f[[i, j, k]] + f[next]);
            });
            out
        })
    }

    /// Largest |face velocity|, m/s; NaN if any face is not a number (so one pass both bounds
    /// the step and detects a blown-up state). Each chunk keeps eight running maxima and NaN
    /// flags, one per lane, with a compare-and-select instead of `f64::max` (whose NaN rule
    /// stops the compiler vectorising a reduction): four times faster at 64^3.
    pub fn max_face_speed(&self) -> Real {
        const LANES: usize = 8;
        let chunk = |c: &[Real]| {
            let mut m = [0.0 as Real; LANES];
            let mut nan = [false; LANES];
            let lanes = c.chunks_exact(LANES);
            let rest = lanes.remainder();
            for w in lanes {
                for l in 0..LANES {
                    let a = w[l].abs();
                    m[l] = if a > m[l] { a } else { m[l] };
                    nan[l] |= a.is_nan();
                }
            }
            for (l, x) in rest.iter().enumerate() {
                m[l] = m[l].max(x.abs());
                nan[l] |= x.is_nan();
            }
            if nan.contains(&true) {
                Real::NAN
            } else {
                m.into_iter().fold(0.0, Real::max)
            }
        };
        let nan_max = |a: Real, b: Real| {
            if a.is_nan() || b.is_nan() {
                Real::NAN
            } else {
                a.max(b)
            }
        };
        self.view()
            .u
            .iter()
            .map(|u| u.par_chunks(1 << 14).map(chunk).reduce(|| 0.0, nan_max))
            .fold(0.0, nan_max)
    }

    /// 1/2 |u|^2 integrated over the cells where `fluid` is true, per unit density.
    pub fn kinetic_energy(&self, fluid: &Array3<bool>) -> Real {
        let cells = self.cell_velocity_squared();
        let volume = self.dx.powi(3);
        Zip::from(&cells)
            .and(fluid)
            .fold(0.0, |acc, &e, &f| if f { acc + e } else { acc })
            * 0.5
            * volume
    }

    /// |u|^2 per cell, from the mean of u_a^2 over each pair of opposite faces (exact for the
    /// face-based energy, unlike squaring the averaged velocity).
    fn cell_velocity_squared(&self) -> Array3<Real> {
        let mut out = Array3::zeros(self.dims);
        Zip::indexed(&mut out).par_for_each(|(i, j, k), e| {
            *e = (0..3)
                .map(|a| {
                    let mut next = [i, j, k];
                    next[a] += 1;
                    0.5 * (self.u[a][[i, j, k]].powi(2) + self.u[a][next].powi(2))
                })
                .sum();
        });
        out
    }
}

/// The face arrays of a [`MacGrid`] as flat slices: the layout check and the shapes are worked
/// out once per loop instead of once per sample (advection samples the velocity four times
/// per face and step).
#[derive(Clone, Copy)]
pub(crate) struct MacView<'a> {
    u: [&'a [Real]; 3],
    dims: [usize; 3],
    periodic: [bool; 3],
}

impl MacView<'_> {
    /// Shape of component `a`'s array.
    #[inline(always)]
    fn shape(&self, a: usize) -> [usize; 3] {
        let mut s = self.dims;
        s[a] += 1;
        s
    }

    /// Flat index of `idx` in component `A`'s array.
    #[inline(always)]
    fn flat<const A: usize>(&self, idx: [usize; 3]) -> usize {
        let s = self.shape(A);
        (idx[0] * s[1] + idx[1]) * s[2] + idx[2]
    }

    /// See [`MacGrid::velocity_at_grid`]. The axis weights are shared: along each axis a
    /// component sits either on faces (its own axis, offset 0) or at cell centres (offset 1/2).
    #[inline(always)]
    pub fn velocity_at_grid(&self, g: [Real; 3]) -> [Real; 3] {
        let w = [
            self.weights::<0>(g[0]),
            self.weights::<1>(g[1]),
            self.weights::<2>(g[2]),
        ];
        [
            self.interpolate::<0>(&w),
            self.interpolate::<1>(&w),
            self.interpolate::<2>(&w),
        ]
    }

    /// The weights along axis `B` at coordinate `g` (cell units) of the faces and of the cell
    /// centres.
    #[inline(always)]
    fn weights<const B: usize>(&self, g: Real) -> [AxisWeights; 2] {
        let period = self.periodic[B].then_some(self.dims[B]);
        [
            axis_weights(g, self.dims[B] + 1, period),
            axis_weights(g - 0.5, self.dims[B], period),
        ]
    }

    /// Component `A` at the axis weights `w` (`[axis][0 = faces, 1 = cell centres]`).
    #[inline(always)]
    fn interpolate<const A: usize>(&self, w: &[[AxisWeights; 2]; 3]) -> Real {
        let pick = |b: usize| w[b][usize::from(b != A)];
        let (c, f) = corners(self.u[A], self.shape(A), [pick(0), pick(1), pick(2)]);
        trilinear(&c, f)
    }

    /// See [`MacGrid::velocity_at_sample`], with the face axis `F` (3 for cell centres) fixed
    /// at compile time, so that each component reduces to its two or four reads.
    #[inline(always)]
    pub fn velocity_at_sample<const F: usize>(&self, idx: [usize; 3]) -> [Real; 3] {
        [
            self.at_sample::<F, 0>(idx),
            self.at_sample::<F, 1>(idx),
            self.at_sample::<F, 2>(idx),
        ]
    }

    /// Component `B` at sample `idx` of a field on the faces of axis `F` (3: cell centres).
    #[inline(always)]
    fn at_sample<const F: usize, const B: usize>(&self, idx: [usize; 3]) -> Real {
        let u = self.u[B];
        // Offset of the next face along B.
        let up = match B {
            0 => self.dims[1] * self.dims[2],
            1 => self.dims[2],
            _ => 1,
        };
        let faces_mean = |cell: [usize; 3]| {
            let i = self.flat::<B>(cell);
            0.5 * (u[i] + u[i + up])
        };
        if F == B {
            u[self.flat::<B>(idx)]
        } else if F < 3 {
            let (mut l, mut r) = (idx, idx);
            (l[F], r[F]) = cells_beside_face_clamped(idx[F], self.dims[F], self.periodic[F]);
            0.5 * (faces_mean(l) + faces_mean(r))
        } else {
            faces_mean(idx)
        }
    }

    /// [`Self::velocity_at_sample`] with the face axis given at run time.
    #[inline]
    fn velocity_at_sample_dyn(&self, face_axis: Option<usize>, idx: [usize; 3]) -> [Real; 3] {
        match face_axis {
            Some(0) => self.velocity_at_sample::<0>(idx),
            Some(1) => self.velocity_at_sample::<1>(idx),
            Some(2) => self.velocity_at_sample::<2>(idx),
            _ => self.velocity_at_sample::<3>(idx),
        }
    }
}

/// The cells on either side of face `face` along an axis of `n` cells: wrapped on a periodic
/// axis, None beyond the ends of another.
#[inline]
pub fn cells_beside_face(face: usize, n: usize, periodic: bool) -> (Option<usize>, Option<usize>) {
    if periodic {
        (Some((face + n - 1) % n), Some(face % n))
    } else {
        ((face > 0).then(|| face - 1), (face < n).then_some(face))
    }
}

/// The cell next to cell `i` along an axis of `n` cells, above it (`up`) or below: wrapped on a
/// periodic axis, None beyond the ends of another.
#[inline]
pub fn cell_beside(i: usize, up: bool, n: usize, periodic: bool) -> Option<usize> {
    if up {
        cells_beside_face(i + 1, n, periodic).1
    } else {
        cells_beside_face(i, n, periodic).0
    }
}

/// As [`cells_beside_face`], with the one cell standing for both at a non-periodic end.
#[inline]
pub fn cells_beside_face_clamped(face: usize, n: usize, periodic: bool) -> (usize, usize) {
    match cells_beside_face(face, n, periodic) {
        (Some(l), Some(r)) => (l, r),
        (Some(c), None) | (None, Some(c)) => (c, c),
        (None, None) => unreachable!("an axis has at least one cell"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The flat-slice velocity (all three components from shared axis weights) equals each
    /// component interpolated on its own by [`Stagger::sample`], to 1e-12, at random points
    /// inside, near and beyond the ends of clamped and periodic axes.
    #[test]
    fn velocity_at_grid_equals_each_component_sampled_alone() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for periodic in [[false; 3], [true, false, true], [false, true, true]] {
            let mut mac = MacGrid::new([5, 4, 6], 0.1, Vec3::zeros(), periodic);
            for u in mac.u.iter_mut() {
                u.mapv_inplace(|_| rng.random_range(-1.0..1.0));
            }
            mac.sync_periodic();
            for _ in 0..3000 {
                let g: [Real; 3] =
                    std::array::from_fn(|a| rng.random_range(-2.0..mac.dims[a] as Real + 2.0));
                let v = mac.velocity_at_grid(g);
                for a in 0..3 {
                    let alone = mac.face_stagger(a).sample(&mac.u[a], g);
                    assert!(
                        (v[a] - alone).abs() < 1e-12,
                        "{periodic:?} at {g:?}, component {a}: {} against {alone}",
                        v[a]
                    );
                }
            }
        }
    }

    /// The lane-wise maximum equals the largest |u| of a plain scan, and one NaN anywhere (in
    /// the lanes or the remainder of a chunk) makes it NaN.
    #[test]
    fn max_face_speed_is_the_largest_magnitude_and_sees_every_nan() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let mut mac = MacGrid::new([7, 5, 3], 0.1, Vec3::zeros(), [false; 3]);
        for u in mac.u.iter_mut() {
            u.mapv_inplace(|_| rng.random_range(-2.0..2.0));
        }
        let scan = mac
            .u
            .iter()
            .flat_map(|u| u.iter())
            .fold(0.0, |m: Real, x| m.max(x.abs()));
        assert_eq!(mac.max_face_speed(), scan);
        for a in 0..3 {
            for at in [0, mac.u[a].len() / 2, mac.u[a].len() - 1] {
                let mut bad = mac.clone();
                bad.u[a].as_slice_mut().expect("standard layout")[at] = Real::NAN;
                assert!(
                    bad.max_face_speed().is_nan(),
                    "NaN at {at} of component {a}"
                );
            }
        }
    }
}
