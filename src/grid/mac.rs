//! The staggered (MAC) velocity field: component a lives on the faces normal to axis a, so the
//! discrete divergence of a cell is a difference of its own six face values.

use ndarray::{Array3, Axis, Zip};

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

    /// Velocity at a point given in cell units, by trilinear interpolation of each component.
    /// The axis weights are shared: along each axis a component sits either on faces (its own
    /// axis, offset 0) or at cell centres (offset 1/2).
    #[inline]
    pub fn velocity_at_grid(&self, g: [Real; 3]) -> Vec3 {
        let weights: [[AxisWeights; 2]; 3] = std::array::from_fn(|b| {
            let period = self.periodic[b].then_some(self.dims[b]);
            [
                axis_weights(g[b], self.dims[b] + 1, period),
                axis_weights(g[b] - 0.5, self.dims[b], period),
            ]
        });
        Vec3::from_fn(|a, _| {
            let data = self.u[a]
                .as_slice()
                .expect("face arrays are in standard layout");
            let mut shape = self.dims;
            shape[a] += 1;
            let pick = |b: usize| weights[b][usize::from(b != a)];
            let (c, f) = corners(data, shape, [pick(0), pick(1), pick(2)]);
            trilinear(&c, f)
        })
    }

    /// Velocity exactly at sample `idx` of a field on the faces of component `face_axis` (or at
    /// a cell centre for None): the value trilinear interpolation gives there, read from two or
    /// four faces per component instead of eight weighted samples (advection's hot path).
    #[inline]
    pub fn velocity_at_sample(&self, face_axis: Option<usize>, idx: [usize; 3]) -> Vec3 {
        let beside = |a: usize| {
            let (mut l, mut r) = (idx, idx);
            (l[a], r[a]) = cells_beside_face_clamped(idx[a], self.dims[a], self.periodic[a]);
            (l, r)
        };
        let faces_mean = |b: usize, cell: [usize; 3]| {
            let mut up = cell;
            up[b] += 1;
            0.5 * (self.u[b][cell] + self.u[b][up])
        };
        Vec3::from_fn(|b, _| match face_axis {
            Some(a) if a == b => self.u[b][idx],
            Some(a) => {
                let (l, r) = beside(a);
                0.5 * (faces_mean(b, l) + faces_mean(b, r))
            }
            None => faces_mean(b, idx),
        })
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
        let [u, v, w] = &self.u;
        let mut out = Array3::zeros(self.dims);
        Zip::indexed(&mut out).par_for_each(|(i, j, k), d| {
            *d = u[[i + 1, j, k]] - u[[i, j, k]] + v[[i, j + 1, k]] - v[[i, j, k]]
                + w[[i, j, k + 1]]
                - w[[i, j, k]];
        });
        out
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

    /// Largest face speed component, m/s.
    /// Largest |face velocity|, m/s; NaN if any face is not a number (so one pass both bounds
    /// the step and detects a blown-up state).
    pub fn max_face_speed(&self) -> Real {
        let nan_max = |a: Real, b: Real| {
            if a.is_nan() || b.is_nan() {
                Real::NAN
            } else {
                a.max(b)
            }
        };
        self.u
            .iter()
            .map(|c| Zip::from(c).par_fold(|| 0.0, |m, &x| nan_max(m, x.abs()), nan_max))
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

/// As [`cells_beside_face`], with the one cell standing for both at a non-periodic end.
#[inline]
pub fn cells_beside_face_clamped(face: usize, n: usize, periodic: bool) -> (usize, usize) {
    match cells_beside_face(face, n, periodic) {
        (Some(l), Some(r)) => (l, r),
        (Some(c), None) | (None, Some(c)) => (c, c),
        (None, None) => unreachable!("an axis has at least one cell"),
    }
}
