//! Boundary particles after Akinci et al. 2012: one layer of samples on every body surface,
//! each with the volume V_b = 1 / sum_k W_bk over the samples of its own body, so that an
//! unevenly sampled wall still contributes evenly (Psi_b = rho_0 V_b).
//!
//! Such a single layer stands in for more fluid than is missing at half a spacing (a flush
//! lattice reads rho / rho_0 = 0.85 + 0.70), so fluid settles about one and a half spacings
//! off a wall, where the wall's density contribution is steep and makes a firm barrier; fluid
//! blocks are filled to match (see [`super::fluid::FluidParticles::from_blocks`]).
//!
//! Samples move with their kinematic body; their volumes stay fixed because the motion is rigid.

use super::kernel::CubicSpline;
use super::neighbors::{cell_order, permute, CellGrid, NeighborLists};
use crate::geometry::RigidBody;
use crate::{Point3, Real, Vec3};
use rayon::prelude::*;

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
    /// Samples every body at `spacing` at time `t` and computes the volumes.
    pub fn sample(bodies: &[RigidBody], spacing: Real, kernel: &CubicSpline, t: Real) -> Self {
        let mut local = Vec::new();
        let mut body = Vec::new();
        for (bi, b) in bodies.iter().enumerate() {
            let samples = b.sample_surface(spacing);
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
        me.compute_volumes(kernel);
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
        let perm = cell_order(&self.x, self.cell);
        permute(&mut self.x, &perm);
        permute(&mut self.v, &perm);
        permute(&mut self.volume, &perm);
        permute(&mut self.body, &perm);
        permute(&mut self.local, &perm);
        self.grid = CellGrid::build(&self.x, self.cell);
    }

    fn compute_volumes(&mut self, kernel: &CubicSpline) {
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
            *vol = 1.0 / sum;
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
