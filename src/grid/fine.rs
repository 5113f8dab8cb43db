//! The smoke's finer grid (Pfaff et al. 2009, section 5.2 and Table 1's "ABL upscaling"): smoke
//! and temperature live on a grid `factor` times finer than the flow's, carried by a fine
//! velocity, while the pressure projection stays on the coarse grid.
//!
//! The fine velocity is the flow's faces interpolated trilinearly to the fine faces (each fine
//! face reads its component at its own centre, as [`super::interp::Stagger::sample`] would),
//! plus the vortex kernels evaluated on the fine faces by the turbulence stage. The smoke's
//! buoyancy acts on the flow through the cell means of the fine smoke
//! ([`FineGrid::restrict`]), which keep its total.

use ndarray::{Array3, Axis, Zip};
use rayon::prelude::*;

use super::boundary::voxel_free;
use super::interp::{axis_weights, AxisWeights};
use super::mac::MacGrid;
use crate::geometry::RigidBody;
use crate::Real;

/// The fine grid's velocity and obstacle cells.
#[derive(Debug, Clone)]
pub struct FineGrid {
    /// The fine face velocities, m/s.
    pub mac: MacGrid,
    /// Fine cells per coarse cell along each axis.
    pub factor: usize,
    /// Fine cells outside every obstacle, voxelised at the fine resolution.
    free: Array3<bool>,
    /// The flow's faces as [`Self::refresh`] reads them, kept so a step allocates nothing.
    flow: MacGrid,
    /// The step (of the flow's count) whose velocity `mac` holds with the kernels added, set
    /// by [`Self::refresh`]; a step without it interpolates the flow afresh.
    fresh: Option<u64>,
}

impl FineGrid {
    /// The grid `factor` times finer than `flow`, covering the same box, with the obstacles
    /// voxelised at time `t`.
    pub fn new(
        flow: &MacGrid,
        factor: usize,
        bodies: &[RigidBody],
        t: Real,
        container: bool,
    ) -> Self {
        let mac = MacGrid::new(
            flow.dims.map(|n| n * factor),
            flow.dx / factor as Real,
            flow.origin,
            flow.periodic,
        );
        let free = voxel_free(&mac, bodies, t, container);
        Self {
            mac,
            factor,
            free,
            flow: flow.clone(),
            fresh: None,
        }
    }

    /// Voxelises the obstacles again, at time `t` (they moved).
    pub fn place_obstacles(&mut self, bodies: &[RigidBody], t: Real, container: bool) {
        self.free = voxel_free(&self.mac, bodies, t, container);
    }

    /// Interpolates the flow's velocity onto the fine faces ([`prolong`]).
    pub fn prolong(&mut self, flow: &MacGrid) {
        prolong(flow, &mut self.mac, self.factor);
    }

    /// [`Self::prolong`] of `flow` as `prepare` leaves a copy of it (the faces extrapolated
    /// into obstacles), for step `step`, marked so that the step's advection uses it with
    /// whatever is added to it meanwhile (the turbulence stage's fine kernels).
    pub fn refresh(&mut self, flow: &MacGrid, prepare: impl FnOnce(&mut MacGrid), step: u64) {
        for (copy, u) in self.flow.u.iter_mut().zip(&flow.u) {
            copy.assign(u);
        }
        prepare(&mut self.flow);
        prolong(&self.flow, &mut self.mac, self.factor);
        self.fresh = Some(step);
    }

    /// The fine velocity for step `step`'s advection: the refreshed one, or the flow's
    /// interpolated now. Either way the next step starts afresh.
    pub fn velocity_for(&mut self, flow: &MacGrid, step: u64) -> &MacGrid {
        if self.fresh.take() != Some(step) {
            self.prolong(flow);
        }
        &self.mac
    }

    /// Zeroes the fine cell-centred `field` inside obstacles and under the flow's cells that
    /// `open` excludes (a coupled liquid's).
    pub fn zero_outside(&self, field: &mut Array3<Real>, open: impl Fn([usize; 3]) -> bool + Sync) {
        let f = self.factor;
        Zip::indexed(field)
            .and(&self.free)
            .par_for_each(|(i, j, k), s, &free| {
                if !free || !open([i / f, j / f, k / f]) {
                    *s = 0.0;
                }
            });
    }

    /// The cell means of a fine cell-centred `field` on the flow's cells.
    pub fn restrict(&self, field: &Array3<Real>) -> Array3<Real> {
        let f = self.factor;
        let [nx, ny, nz] = self.mac.dims.map(|n| n / f);
        let inv = 1.0 / (f * f * f) as Real;
        let mut out = Array3::zeros((nx, ny, nz));
        Zip::indexed(&mut out).par_for_each(|(i, j, k), m| {
            let mut sum = 0.0;
            for di in 0..f {
                for dj in 0..f {
                    for dk in 0..f {
                        sum += field[[i * f + di, j * f + dj, k * f + dk]];
                    }
                }
            }
            *m = sum * inv;
        });
        out
    }
}

/// Interpolates the velocity of `flow` onto the faces of `fine_grid`, `factor` times finer:
/// per axis, each fine sample's two coarse neighbours and weight are tabulated once
/// ([`axis_weights`], the trilinear interpolation of [`super::interp::Stagger::sample`]), then
/// each fine face sums its eight corners.
fn prolong(flow: &MacGrid, fine_grid: &mut MacGrid, factor: usize) {
    let scale = 1.0 / factor as Real;
    for a in 0..3 {
        let (coarse, fine) = (flow.face_stagger(a), fine_grid.face_stagger(a));
        let tables: [Vec<AxisWeights>; 3] = std::array::from_fn(|b| {
            (0..fine.shape[b])
                .map(|f| {
                    let g = (f as Real + fine.offset[b]) * scale - coarse.offset[b];
                    axis_weights(g, coarse.shape[b], coarse.period[b])
                })
                .collect()
        });
        let src = flow.u[a]
            .as_slice()
            .expect("face arrays are in standard layout");
        let [_, ny, nz] = coarse.shape;
        let [tx, ty, tz] = &tables;
        fine_grid.u[a]
            .axis_iter_mut(Axis(0))
            .into_par_iter()
            .zip(tx.par_iter())
            .for_each(|(mut plane, &(x0, x1, wx))| {
                for ((j, k), v) in plane.indexed_iter_mut() {
                    let ((y0, y1, wy), (z0, z1, wz)) = (ty[j], tz[k]);
                    let row = |x: usize, y: usize| {
                        let r = (x * ny + y) * nz;
                        (1.0 - wz) * src[r + z0] + wz * src[r + z1]
                    };
                    let plane_at = |x: usize| (1.0 - wy) * row(x, y0) + wy * row(x, y1);
                    *v = (1.0 - wx) * plane_at(x0) + wx * plane_at(x1);
                }
            });
    }
}
