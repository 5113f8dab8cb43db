//! Body forces on the MAC grid: smoke buoyancy and vorticity confinement (Fedkiw, Stam and
//! Jensen 2001), both computed at cell centres and averaged onto the faces.

use ndarray::{Array3, Zip};
use rayon::prelude::*;

use super::mac::{cells_beside_face_clamped, MacGrid};
use crate::{Real, Vec3};

/// Adds dt times a cell-centred acceleration to the faces (the mean of the two cells beside
/// each face; a boundary face takes its one cell's value). Fixed faces are reset afterwards by
/// the boundary conditions.
pub fn add_cell_acceleration(grid: &mut MacGrid, accel: &[Array3<Real>; 3], dt: Real) {
    let dims = grid.dims;
    let periodic = grid.periodic;
    for a in 0..3 {
        let f = &accel[a];
        let n = dims[a];
        Zip::indexed(&mut grid.u[a]).par_for_each(|(i, j, k), u| {
            let idx = [i, j, k];
            let at = |c: usize| {
                let mut cell = idx;
                cell[a] = c;
                f[cell]
            };
            let (l, r) = cells_beside_face_clamped(idx[a], n, periodic[a]);
            *u += dt * 0.5 * (at(l) + at(r));
        });
    }
}

/// Buoyancy (Fedkiw et al. 2001, Eq. 8, with density rising): the acceleration
/// (buoyancy * s + heat_buoyancy * T) along `up` per cell.
pub fn buoyancy(
    smoke: &Array3<Real>,
    temperature: Option<&Array3<Real>>,
    buoyancy: Real,
    heat_buoyancy: Real,
    up: Vec3,
) -> [Array3<Real>; 3] {
    let mut lift = smoke.mapv(|s| buoyancy * s);
    if let Some(t) = temperature {
        Zip::from(&mut lift)
            .and(t)
            .par_for_each(|l, &t| *l += heat_buoyancy * t);
    }
    std::array::from_fn(|a| lift.mapv(|l| l * up[a]))
}

/// Cell-centred vorticity by central differences of the cell-centred velocity (one-sided at
/// non-periodic ends), 1/s.
pub fn vorticity(grid: &MacGrid) -> [Array3<Real>; 3] {
    let cells = CellVorticity::new(grid);
    let [_, ny, nz] = grid.dims;
    let mut w: [Array3<Real>; 3] = std::array::from_fn(|_| Array3::zeros(grid.dims));
    let [wx, wy, wz] = &mut w;
    wx.outer_iter_mut()
        .into_par_iter()
        .zip(wy.outer_iter_mut())
        .zip(wz.outer_iter_mut())
        .enumerate()
        .for_each(|(i, ((mut x, mut y), mut z))| {
            let mut row = vec![Vec3::zeros(); nz];
            for j in 0..ny {
                cells.row([i, j, 0], &mut row);
                for (k, v) in row.iter().enumerate() {
                    (x[[j, k]], y[[j, k]], z[[j, k]]) = (v.x, v.y, v.z);
                }
            }
        });
    w
}

/// The stencil of a central difference at cell `c` of an axis of `n` cells: the cells below
/// and above (wrapped on a periodic axis, clamped to one-sided at the ends of another) and the
/// distance between them in cells (zero on an axis of one cell, where the derivative is zero).
#[inline]
fn central(c: usize, n: usize, periodic: bool) -> (usize, usize, usize) {
    if n < 2 {
        (c, c, 0)
    } else if periodic {
        ((c + n - 1) % n, (c + 1) % n, 2)
    } else {
        let (lo, hi) = (c.saturating_sub(1), (c + 1).min(n - 1));
        (lo, hi, hi - lo)
    }
}

/// The grid's cell-centred vorticity one cell at a time (the stencil of [`vorticity`]), for
/// callers that need it only where something samples it (the vortex layer's Eq. 14 sums).
pub struct CellVorticity<'a> {
    faces: [&'a [Real]; 3],
    /// Flat strides of each face array.
    strides: [[usize; 3]; 3],
    dims: [usize; 3],
    periodic: [bool; 3],
    dx: Real,
}

impl<'a> CellVorticity<'a> {
    pub fn new(grid: &'a MacGrid) -> Self {
        Self {
            faces: grid.u.each_ref().map(|f| {
                f.as_slice()
                    .expect("MAC face arrays are allocated in standard layout")
            }),
            strides: std::array::from_fn(|a| {
                let s = grid.u[a].shape();
                [s[1] * s[2], s[2], 1]
            }),
            dims: grid.dims,
            periodic: grid.periodic,
            dx: grid.dx,
        }
    }

    /// The vorticity of the cells from `idx` along z, one per entry of `out`, 1/s.
    pub fn row(&self, [i, j, k]: [usize; 3], out: &mut [Vec3]) {
        let nz = self.dims[2];
        if out.is_empty() || !self.interior([i, j, 1], 1) || nz < 3 {
            for (m, o) in out.iter_mut().enumerate() {
                *o = self.general([i, j, k + m]);
            }
            return;
        }
        // Only the row's ends can touch the z ends.
        let lo = 1usize.saturating_sub(k).min(out.len());
        let hi = (nz - 1).saturating_sub(k).clamp(lo, out.len());
        for (m, o) in out.iter_mut().enumerate() {
            if m < lo || m >= hi {
                *o = self.general([i, j, k + m]);
            }
        }
        if hi > lo {
            self.interior_row([i, j, k + lo], &mut out[lo..hi]);
        }
    }

    /// Whether every cell of the row of `n` from `[i, j, k]` has both neighbours along every
    /// axis.
    #[inline]
    fn interior(&self, [i, j, k]: [usize; 3], n: usize) -> bool {
        let inside = |c: usize, last: usize, axis: usize| c >= 1 && last + 1 < self.dims[axis];
        inside(i, i, 0) && inside(j, j, 1) && inside(k, k + n - 1, 2)
    }

    /// Away from the ends every difference spans two cells: the stencil written out over
    /// contiguous runs of face values, since this is what the vortex layer's Eq. 14 sums
    /// spend their time on.
    fn interior_row(&self, [i, j, k]: [usize; 3], out: &mut [Vec3]) {
        let n = out.len();
        let [u, v, w] = self.faces;
        let [su, sv, sw] = self.strides;
        let (ou, ov, ow) = (
            i * su[0] + j * su[1] + k,
            i * sv[0] + j * sv[1] + k,
            i * sw[0] + j * sw[1] + k,
        );
        // The four runs whose sum, (hi + hi') - (lo + lo'), is twice the cell-centred
        // component (the mean of its two faces) differenced across `along`, along the row.
        let runs = |f: &'a [Real], o: usize, along: usize, own: usize| -> [&'a [Real]; 4] {
            let run = |start: usize| &f[start..start + n];
            [
                run(o + along),
                run(o + along + own),
                run(o - along),
                run(o - along + own),
            ]
        };
        let [a0, a1, a2, a3] = runs(w, ow, sw[1], 1); // d w / d y
        let [b0, b1, b2, b3] = runs(v, ov, 1, sv[1]); // d v / d z
        let [c0, c1, c2, c3] = runs(u, ou, 1, su[0]); // d u / d z
        let [e0, e1, e2, e3] = runs(w, ow, sw[0], 1); // d w / d x
        let [f0, f1, f2, f3] = runs(v, ov, sv[0], sv[1]); // d v / d x
        let [g0, g1, g2, g3] = runs(u, ou, su[1], su[0]); // d u / d y
        let scale = 0.25 / self.dx;
        for m in 0..n {
            let dw_dy = a0[m] + a1[m] - a2[m] - a3[m];
            let dv_dz = b0[m] + b1[m] - b2[m] - b3[m];
            let du_dz = c0[m] + c1[m] - c2[m] - c3[m];
            let dw_dx = e0[m] + e1[m] - e2[m] - e3[m];
            let dv_dx = f0[m] + f1[m] - f2[m] - f3[m];
            let du_dy = g0[m] + g1[m] - g2[m] - g3[m];
            out[m] = scale * Vec3::new(dw_dy - dv_dz, du_dz - dw_dx, dv_dx - du_dy);
        }
    }

    /// Any cell, with the stencils of [`central`].
    fn general(&self, idx: [usize; 3]) -> Vec3 {
        let stencil: [(usize, usize, usize); 3] =
            std::array::from_fn(|b| central(idx[b], self.dims[b], self.periodic[b]));
        let d = |c: usize, b: usize| {
            let (lo, hi, span) = stencil[b];
            if span == 0 {
                return 0.0;
            }
            let (f, s) = (self.faces[c], &self.strides[c]);
            let base = idx[0] * s[0] + idx[1] * s[1] + idx[2] * s[2] - idx[b] * s[b];
            let (h, l) = (base + hi * s[b], base + lo * s[b]);
            0.5 * (f[h] + f[h + s[c]] - f[l] - f[l + s[c]]) / (span as Real * self.dx)
        };
        Vec3::new(d(2, 1) - d(1, 2), d(0, 2) - d(2, 0), d(1, 0) - d(0, 1))
    }
}

/// d f / d x_axis at cell centres.
fn derivative(f: &Array3<Real>, axis: usize, periodic: bool, dx: Real) -> Array3<Real> {
    let n = f.shape()[axis];
    let mut out = Array3::zeros(f.raw_dim());
    Zip::indexed(&mut out).par_for_each(|(i, j, k), o| {
        let mut idx = [i, j, k];
        let (lo, hi, span) = central(idx[axis], n, periodic);
        if span == 0 {
            return;
        }
        idx[axis] = hi;
        let above = f[idx];
        idx[axis] = lo;
        *o = (above - f[idx]) / (span as Real * dx);
    });
    out
}

/// Vorticity confinement (Fedkiw et al. 2001, Eqs. 9–11): f = epsilon dx (N x omega), with
/// N = grad|omega| / |grad|omega|| pointing towards stronger vorticity.
pub fn confinement(grid: &MacGrid, epsilon: Real) -> [Array3<Real>; 3] {
    let w = vorticity(grid);
    let mag = Zip::from(&w[0])
        .and(&w[1])
        .and(&w[2])
        .map_collect(|a, b, c| (a * a + b * b + c * c).sqrt());
    let grad: [Array3<Real>; 3] =
        std::array::from_fn(|a| derivative(&mag, a, grid.periodic[a], grid.dx));
    let mut f: [Array3<Real>; 3] = std::array::from_fn(|_| Array3::zeros(grid.dims));
    let scale = epsilon * grid.dx;
    let [fx, fy, fz] = &mut f;
    Zip::indexed(fx)
        .and(fy)
        .and(fz)
        .par_for_each(|idx, fx, fy, fz| {
            let g = Vec3::new(grad[0][idx], grad[1][idx], grad[2][idx]);
            let norm = g.norm();
            if norm < 1e-12 {
                return;
            }
            let om = Vec3::new(w[0][idx], w[1][idx], w[2][idx]);
            let force = scale * (g / norm).cross(&om);
            (*fx, *fy, *fz) = (force.x, force.y, force.z);
        });
    f
}
