//! Boundary particles after Akinci et al. 2012, placed as a mirror layer of the fluid lattice:
//! one layer of samples on every body surface, moved [`MIRROR_DEPTH`] spacings into the solid,
//! and fluid filled from half a spacing off the surface (as a lattice block fills its box). The
//! effective wall is then the body's surface, so a block holds the volume and mass the scene
//! gives and starts at the rest density.
//!
//! Each sample's volume is Akinci's V_b = 1 / sum_k W_bk over the samples of its own body (an
//! unevenly sampled wall still contributes evenly, Psi_b = rho_0 V_b), times a gain fixed so
//! that on a flat wall sampled at the fluid spacing the layer adds to the first fluid layer
//! exactly what the lattice beyond the surface would: with the kernel support at two spacings,
//! one lattice plane a spacing away, P(s) / S_3 (P(d) the kernel sum over a square lattice at
//! distance d, S_3 over the cubic lattice). The gain is P(s) / P(d_m) * P(0) / S_3, with d_m
//! the layer's distance from the first fluid layer.
//!
//! Why not the exact mirror (the layer half a spacing in, gain P(0) / S_3): the wall force of
//! Akinci's Eq. 10 pushes with the particle's own pressure only (the form that makes the
//! pressure solve a projection, so it cannot add energy), which under load is weaker than the
//! fluid it replaces, and so soft a wall lets a loaded first layer sink into it; IISPH's
//! Jacobi iteration also diverges at the corners of a tank, where a full mirrored
//! neighbourhood leaves a particle's own pressure almost no effect on its density. A layer
//! further in with a larger gain has the same density at the first layer and a steeper rise
//! towards the wall. Measured on `hydrostatic_tank.toml` and the dam break of the tests
//! (docs/src/sph.md): at 0.5 IISPH diverges and the dam break goes unstable; the deeper
//! the layer, the better the column holds (potential energy down 0.36 J of 125.6 in 2 s at
//! 0.8), but the stiffer wall hands stored compression back as energy (0.02 % in one step of
//! the dam break at 0.8, 7e-6 at 0.65); at 0.6 no step gains 1e-6, and the column's
//! potential energy falls 0.94 J in 1 s (the old layer on the surface, with fluid a spacing
//! off, let it fall 12 J).
//! A particle alone at a wall (a splash) is pushed back only where the wall's density alone
//! reaches the rest density, which lies a little past the surface (about a millimetre at a
//! spacing of 2 cm in the sloshing tank); it is behind the wall once it is behind the samples.
//!
//! Samples move with their kinematic body; their volumes stay fixed because the motion is rigid.

use super::fluid::{lattice_kernel_sum, plane_kernel_sum_at};
use super::kernel::CubicSpline;
use super::neighbors::{cell_order_and_codes, permute, CellGrid, NeighborLists};
use crate::geometry::RigidBody;
use crate::state::{Persist, Restorer, Saver, StateError};
use crate::{Point3, Real, Vec3};
use rayon::prelude::*;

/// How far behind a body's surface its samples lie, in fluid spacings (see the module doc).
pub const MIRROR_DEPTH: Real = 0.6;

/// The factor on a wall's viscosity that makes it no-slip at the fluid's: with it, a wall whose
/// `wall_viscosity` equals `viscosity.kinematic` pulls the first fluid layer of a linear shear
/// flow u = (gamma y, 0, 0) exactly as the fluid lattice beyond the surface carrying that flow
/// on would (the mirror no-slip condition), so a steady shear flow feels no net viscous force
/// there. Eq. 4 of Liu et al. 2021 over that missing lattice against the same sum over the
/// [`MIRROR_DEPTH`] layer of samples at rest, with their flat-wall volumes (about 2.17 at a
/// support of two spacings: the one layer stands in for the lattice, and is still).
pub fn no_slip_gain(kernel: &CubicSpline, spacing: Real) -> Real {
    let eps = 0.01 * kernel.support() * kernel.support();
    let reach = (kernel.support() / spacing).ceil() as i64;
    let plane = |d: Real| plane_kernel_sum_at(kernel, spacing, d * spacing);
    // The fluid's particle volume (its lattice sums to the rest density) and a flat wall's
    // sample volume (`compute_volumes` with its own plane's sum P(0)).
    let volume = 1.0 / lattice_kernel_sum(kernel, spacing);
    let sample_volume = plane(1.0) / plane(MIRROR_DEPTH + 0.5) * volume;
    // Eq. 4's pull along x on the first layer (half a spacing off the wall) from a point at
    // offset x moving at u_x.
    let first = Vec3::new(0.0, 0.5 * spacing, 0.0);
    let pull = |offset: Vec3, u: Real| {
        let x = first - offset;
        let shear = 0.5 * spacing - u;
        shear * x[0] * kernel.grad(&x)[0] / (x.norm_squared() + eps)
    };
    let (mut lattice, mut wall) = (0.0, 0.0);
    for a in -reach..=reach {
        for c in -reach..=reach {
            let (ax, cz) = (a as Real * spacing, c as Real * spacing);
            for b in 1..=reach {
                let y = 0.5 * spacing - b as Real * spacing;
                lattice += volume * pull(Vec3::new(ax, y, cz), y);
            }
            wall += sample_volume * pull(Vec3::new(ax, -MIRROR_DEPTH * spacing, cz), 0.0);
        }
    }
    lattice / wall
}

/// All boundary particles of a scene, in cell order.
#[derive(Debug, Clone)]
pub struct BoundaryParticles {
    pub x: Vec<Vec3>,
    pub v: Vec<Vec3>,
    /// Akinci volume V_b, m^3.
    pub volume: Vec<Real>,
    /// Index of the body each sample belongs to.
    pub body: Vec<u32>,
    /// Position in the body's frame.
    local: Vec<Vec3>,
    /// Grid over `x`, rebuilt when a body moves.
    pub grid: CellGrid,
    cell: Real,
}

impl BoundaryParticles {
    /// Samples every body at `spacing` at time `t`, [`MIRROR_DEPTH`] spacings inside its solid
    /// (outside body 0 when it is the `container`), and computes the volumes.
    pub fn sample(
        bodies: &[RigidBody],
        container: bool,
        spacing: Real,
        kernel: &CubicSpline,
        t: Real,
    ) -> Self {
        let mut local = Vec::new();
        let mut body = Vec::new();
        for (bi, b) in bodies.iter().enumerate() {
            let into_solid = if bi == 0 && container { 1.0 } else { -1.0 };
            let samples = b.sample_offset_surface(spacing, MIRROR_DEPTH * spacing * into_solid);
            body.extend(std::iter::repeat_n(bi as u32, samples.len()));
            local.extend(samples.into_iter().map(|p| p.coords));
        }
        let n = local.len();
        let mut me = Self {
            x: vec![Vec3::zeros(); n],
            v: vec![Vec3::zeros(); n],
            volume: vec![0.0; n],
            body,
            local,
            grid: CellGrid::build(&[], kernel.support()),
            cell: kernel.support(),
        };
        me.place(bodies, t, true);
        me.compute_volumes(kernel, spacing);
        me
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// True without samples.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Moves the samples of moving bodies to time `t`, sets their velocities, and re-sorts and
    /// re-grids when anything moved (or when `force`).
    pub fn place(&mut self, bodies: &[RigidBody], t: Real, force: bool) {
        let moving: Vec<bool> = bodies.iter().map(|b| b.is_moving()).collect();
        if !force && !moving.iter().any(|&m| m) {
            return;
        }
        let poses: Vec<_> = bodies.iter().map(|b| b.pose(t)).collect();
        self.x
            .par_iter_mut()
            .zip(self.v.par_iter_mut())
            .zip(self.local.par_iter().zip(self.body.par_iter()))
            .for_each(|((x, v), (l, &b))| {
                let b = b as usize;
                if force || moving[b] {
                    let p = poses[b] * Point3::from(*l);
                    *x = p.coords;
                    *v = bodies[b].velocity_at(t, &p);
                }
            });
        let (perm, codes) = cell_order_and_codes(&self.x, self.cell);
        permute(&mut self.x, &perm);
        permute(&mut self.v, &perm);
        permute(&mut self.volume, &perm);
        permute(&mut self.body, &perm);
        permute(&mut self.local, &perm);
        self.grid = CellGrid::from_codes(&self.x, &codes, self.cell);
    }

    fn compute_volumes(&mut self, kernel: &CubicSpline, spacing: Real) {
        let plane = |d: Real| plane_kernel_sum_at(kernel, spacing, d * spacing);
        let plane_volume = plane(1.0) / plane(MIRROR_DEPTH + 0.5) * plane(0.0)
            / lattice_kernel_sum(kernel, spacing);
        let lists = NeighborLists::build(
            &self.x,
            &self.grid,
            &self.x,
            &self.grid,
            kernel.support(),
            true,
        );
        let (x, body) = (&self.x, &self.body);
        self.volume.par_iter_mut().enumerate().for_each(|(i, vol)| {
            let sum: Real = kernel.w_zero()
                + lists
                    .of(i)
                    .iter()
                    .filter(|&&j| body[j as usize] == body[i])
                    .map(|&j| kernel.w((x[i] - x[j as usize]).norm()))
                    .sum::<Real>();
            *vol = plane_volume / sum;
        });
    }

    /// Bytes held by the samples and their grid.
    pub fn memory_bytes(&self) -> usize {
        (self.x.capacity() + self.v.capacity() + self.local.capacity())
            * std::mem::size_of::<Vec3>()
            + self.volume.capacity() * std::mem::size_of::<Real>()
            + self.body.capacity() * std::mem::size_of::<u32>()
            + self.grid.memory_bytes()
    }
}

/// The samples in their current order. Each re-sort after a body moved breaks ties within a
/// cell by the order before it, so the order after many steps is not that of samples placed
/// afresh at the same time: it is stored, with every per-sample array. The solver saves this
/// only while a body moves (still samples stay as sampled) and re-places the samples after
/// restoring them, which rebuilds the grid (a re-sort of sorted samples keeps their order).
impl Persist for BoundaryParticles {
    fn save(&self, into: &mut Saver) {
        into.vec3s("x", &self.x);
        into.vec3s("v", &self.v);
        into.reals("volume", &self.volume);
        into.u64s(
            "body",
            &self.body.iter().map(|&b| b.into()).collect::<Vec<_>>(),
        );
        into.vec3s("local", &self.local);
    }

    fn restore(&mut self, from: &Restorer) -> Result<(), StateError> {
        let n = self.len();
        let bodies = self.body.iter().max().map_or(0, |&b| u64::from(b) + 1);
        let body = from.u64s("body")?;
        if body.len() != n {
            let found = format!("{} u64 values", body.len());
            return Err(from.invalid("body", found, format!("{n} u64 values")));
        }
        if let Some(b) = body.iter().find(|&&b| b >= bodies) {
            let expected = format!("body indices below {bodies}");
            return Err(from.invalid("body", format!("body index {b}"), expected));
        }
        let x = from.vec3s_n("x", n)?;
        let v = from.vec3s_n("v", n)?;
        let volume = from.reals_n("volume", n)?;
        let local = from.vec3s_n("local", n)?;
        (self.x, self.v, self.volume, self.local) = (x, v, volume, local);
        self.body = body.into_iter().map(|b| b as u32).collect();
        Ok(())
    }
}
