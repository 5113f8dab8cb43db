//! Body forces on the MAC grid: smoke buoyancy and vorticity confinement (Fedkiw, Stam and
//! Jensen 2001), both computed at cell centres and averaged onto the faces.

use ndarray::{Array3, Zip};

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
    let vel = grid.cell_velocity();
    let d = |f: &Array3<Real>, axis: usize| derivative(f, axis, grid.periodic[axis], grid.dx);
    let (du, dv, dw) = (&vel[0], &vel[1], &vel[2]);
    let dw_dy = d(dw, 1);
    let dv_dz = d(dv, 2);
    let du_dz = d(du, 2);
    let dw_dx = d(dw, 0);
    let dv_dx = d(dv, 0);
    let du_dy = d(du, 1);
    [&dw_dy - &dv_dz, &du_dz - &dw_dx, &dv_dx - &du_dy]
}

/// d f / d x_axis at cell centres.
fn derivative(f: &Array3<Real>, axis: usize, periodic: bool, dx: Real) -> Array3<Real> {
    let n = f.shape()[axis];
    let mut out = Array3::zeros(f.raw_dim());
    if n < 2 {
        return out;
    }
    Zip::indexed(&mut out).par_for_each(|(i, j, k), o| {
        let idx = [i, j, k];
        let at = |c: usize| {
            let mut cell = idx;
            cell[axis] = c;
            f[cell]
        };
        let c = idx[axis];
        let (lo, hi) = if periodic {
            ((c + n - 1) % n, (c + 1) % n)
        } else {
            (c.saturating_sub(1), (c + 1).min(n - 1))
        };
        let span = if periodic { 2 } else { hi - lo };
        *o = (at(hi) - at(lo)) / (span as Real * dx);
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
