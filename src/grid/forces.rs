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

    /// Any cell: the sum over the axes b of e_b x d u / d x_b, with the stencils of
    /// [`central`].
    fn general(&self, idx: [usize; 3]) -> Vec3 {
        // 1 / (2 span dx) for span 0, 1, 2 cells (no difference across an axis of one cell).
        let scale = [0.0, 0.5 / self.dx, 0.25 / self.dx];
        let mut out = Vec3::zeros();
        for b in 0..3 {
            let (lo, hi, span) = central(idx[b], self.dims[b], self.periodic[b]);
            // d u_c / d x_b from twice the cell-centred u_c (the sum of its two faces).
            let d = |c: usize| {
                let (f, s) = (self.faces[c], &self.strides[c]);
                let base = idx[0] * s[0] + idx[1] * s[1] + idx[2] * s[2] - idx[b] * s[b];
                let cell = |at: usize| f[base + at * s[b]] + f[base + at * s[b] + s[c]];
                scale[span] * (cell(hi) - cell(lo))
            };
            // With (b, c1, c2) cyclic, e_b x e_c1 = e_c2 and e_b x e_c2 = -e_c1.
            let (c1, c2) = ((b + 1) % 3, (b + 2) % 3);
            out[c2] += d(c1);
            out[c1] -= d(c2);
        }
        out
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

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A grid whose face velocities are `f` of the face centres.
    fn grid_of(dims: [usize; 3], periodic: [bool; 3], f: impl Fn(usize, Vec3) -> Real) -> MacGrid {
        let dx = 0.1;
        let mut g = MacGrid::new(dims, dx, Vec3::new(-0.3, 0.2, 0.05), periodic);
        let origin = g.origin;
        for (a, u) in g.u.iter_mut().enumerate() {
            for ((i, j, k), v) in u.indexed_iter_mut() {
                let idx = [i, j, k];
                let x = origin
                    + Vec3::from_fn(|b, _| (idx[b] as Real + if b == a { 0.0 } else { 0.5 }) * dx);
                *v = f(a, x);
            }
        }
        g.sync_periodic();
        g
    }

    /// Central and one-sided differences are exact for a linear field, so its vorticity is
    /// the curl of the matrix everywhere, ends included.
    #[test]
    fn vorticity_of_a_linear_field_is_exact_at_every_cell() {
        let m = nalgebra::Matrix3::new(0.3, -1.2, 0.7, 2.1, -0.4, 0.9, -1.6, 0.5, 0.2);
        let curl = Vec3::new(
            m[(2, 1)] - m[(1, 2)],
            m[(0, 2)] - m[(2, 0)],
            m[(1, 0)] - m[(0, 1)],
        );
        let g = grid_of([5, 4, 6], [false; 3], |a, x| (m * x)[a]);
        let w = vorticity(&g);
        for (idx, _) in w[0].indexed_iter() {
            let got = Vec3::new(w[0][idx], w[1][idx], w[2][idx]);
            assert!(
                (got - curl).norm() < 1e-12,
                "cell {idx:?}: {got} against {curl}"
            );
        }
    }

    /// Any run of a row, as the vortex layer asks for it, equals that run of the full field,
    /// at walls and across periodic ends alike.
    #[test]
    fn runs_of_a_row_equal_the_cell_vorticity() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for periodic in [[false; 3], [true, false, true], [false, true, false]] {
            let noise: Vec<Real> = (0..4000).map(|_| rng.random::<Real>() - 0.5).collect();
            let g = grid_of([6, 5, 7], periodic, |a, x| {
                let h = ((x[0] * 131.0 + x[1] * 71.0 + x[2] * 37.0 + a as Real * 11.0).abs() * 97.0)
                    as usize;
                noise[h % noise.len()]
            });
            let w = vorticity(&g);
            let cells = CellVorticity::new(&g);
            let [nx, ny, nz] = g.dims;
            for (i, j) in (0..nx).flat_map(|i| (0..ny).map(move |j| (i, j))) {
                for k in 0..nz {
                    for n in 1..=nz - k {
                        let mut run = vec![Vec3::zeros(); n];
                        cells.row([i, j, k], &mut run);
                        for (m, got) in run.iter().enumerate() {
                            let c = [i, j, k + m];
                            let want = Vec3::new(w[0][c], w[1][c], w[2][c]);
                            assert!(
                                (got - want).norm() < 1e-12 * (1.0 + want.norm()),
                                "{periodic:?} cell {c:?} of the run from {k} of {n}: {got} against {want}"
                            );
                        }
                    }
                }
            }
        }
    }
}
