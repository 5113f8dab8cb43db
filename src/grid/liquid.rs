//! A liquid simulated elsewhere (the SPH water of a coupled scene) as a moving solid for the
//! air on this grid: the cells it covers leave the pressure solve, the faces touching them carry
//! the liquid's velocity (the solid velocity boundary condition), and the air's pressure on
//! those faces is the force the liquid feels back.

use ndarray::{Array3, Zip};

use super::mac::{cell_beside, cells_beside_face, MacGrid};
use super::params::GridSide;
use super::solver::GridSolver;
use crate::geometry::RigidBody;
use crate::{Real, Vec3};

/// The cells a liquid covers and its velocity on the faces touching them.
#[derive(Debug, Clone)]
pub struct Liquid {
    pub cells: Array3<bool>,
    /// Component a of the liquid's velocity on every a-face beside a covered cell (0 elsewhere).
    pub face_velocity: [Array3<Real>; 3],
}

impl Liquid {
    /// The liquid over the cells where `velocity` is given (the liquid's velocity at the cell
    /// centre): each face beside a covered cell carries the mean of the covered cells beside it.
    pub fn new(grid: &MacGrid, velocity: &Array3<Option<Vec3>>) -> Self {
        let face_velocity = std::array::from_fn(|a| {
            let mut u = Array3::zeros(grid.u[a].raw_dim());
            let (n, periodic) = (grid.dims[a], grid.periodic[a]);
            Zip::indexed(&mut u).par_for_each(|(i, j, k), u| {
                let idx = [i, j, k];
                let (lo, hi) = cells_beside_face(idx[a], n, periodic);
                let at = |c: Option<usize>| {
                    c.and_then(|c| {
                        let mut m = idx;
                        m[a] = c;
                        velocity[m]
                    })
                };
                *u = match (at(lo), at(hi)) {
                    (Some(l), Some(h)) => 0.5 * (l[a] + h[a]),
                    (Some(v), None) | (None, Some(v)) => v[a],
                    (None, None) => 0.0,
                };
            });
            u
        });
        Self {
            cells: velocity.map(|v| v.is_some()),
            face_velocity,
        }
    }
}

impl GridSolver {
    /// Makes `liquid` the grid's moving solid from now on (until the next call): its cells leave
    /// the pressure solve and its faces carry its velocity. With moving obstacles `dt` is the
    /// coming step's: they are placed where that step's projection sees them, once.
    pub fn set_liquid(&mut self, liquid: Liquid, dt: Real) {
        self.liquid = Some(liquid);
        let moving = self.bodies.iter().any(RigidBody::is_moving);
        let t = self.time() + if moving { dt } else { 0.0 };
        self.rebuild_boundaries(t);
        self.bounds_time = Some(t);
        self.bounds.apply(&mut self.mac);
    }

    /// Whether a coupled liquid is this grid's moving solid.
    pub fn has_liquid(&self) -> bool {
        self.liquid.is_some()
    }

    /// Adds `du` (m/s) to face `idx` of component `a` in the next step, after its advection and
    /// before its projection, as a force would: the reaction of the water's drag on the air.
    /// A face index along a periodic axis is below the cell count.
    pub fn add_face_impulse(&mut self, a: usize, idx: [usize; 3], du: Real) {
        let mac = &self.mac;
        self.impulses
            .get_or_insert_with(|| std::array::from_fn(|b| Array3::zeros(mac.u[b].raw_dim())))
            [a][idx] += du;
    }

    /// Adds the pending impulses to the face velocities and clears them.
    pub(super) fn apply_impulses(&mut self) {
        if let Some(du) = self.impulses.take() {
            for (u, du) in self.mac.u.iter_mut().zip(du) {
                *u += &du;
            }
            self.mac.sync_periodic();
        }
    }

    /// The force of the air's pressure on every liquid cell it touches, N: on each face between
    /// an air cell c and a liquid cell, p_c dx^2 along the face normal into the liquid. This is
    /// exactly the momentum the last projection took from the air through that face, over dt
    /// (the update u -= dt / (rho dx) (p_r - p_l) telescopes along every row of faces to these
    /// terms and the walls'). Where no side is open the pressure is known only up to a constant,
    /// so the mean over the liquid's faces is taken off: a uniform pressure pushes no liquid.
    pub fn liquid_pressure_forces(&self) -> Vec<([usize; 3], Vec3)> {
        let dims = self.mac.dims;
        let mut faces: Vec<([usize; 3], usize, Real, Real)> = Vec::new();
        for (idx, &p) in self.pressure.indexed_iter() {
            let idx = [idx.0, idx.1, idx.2];
            if self.bounds.is_solid(idx) {
                continue;
            }
            for a in 0..3 {
                for (sign, up) in [(-1.0, false), (1.0, true)] {
                    let Some(c) = cell_beside(idx[a], up, dims[a], self.mac.periodic[a]) else {
                        continue;
                    };
                    let mut s = idx;
                    s[a] = c;
                    if self.bounds.is_liquid(s) {
                        faces.push((s, a, sign, p));
                    }
                }
            }
        }
        let open = self
            .bounds
            .sides
            .iter()
            .flatten()
            .any(|s| *s == GridSide::Open);
        let reference = if open || faces.is_empty() {
            0.0
        } else {
            faces.iter().map(|f| f.3).sum::<Real>() / faces.len() as Real
        };
        let area = self.mac.dx * self.mac.dx;
        let mut forces: Vec<([usize; 3], Vec3)> = Vec::new();
        faces.sort_by_key(|f| f.0);
        for (s, a, sign, p) in faces {
            let mut f = Vec3::zeros();
            f[a] = sign * (p - reference) * area;
            match forces.last_mut() {
                Some((last, sum)) if *last == s => *sum += f,
                _ => forces.push((s, f)),
            }
        }
        forces
    }
}
