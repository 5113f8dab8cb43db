//! The wall-attached boundary layer of one obstacle (Pfaff et al. 2009, Figure 9, lines 2–6): its
//! database, and for any point near its surface the nearest precomputed boundary point.
//!
//! The precomputation grid and the simulation's samples (grid cells, SPH particles) differ in
//! resolution, so a sample takes the value of the *nearest* boundary point in the object's
//! frame (Figure 9, line 3: "find corresponding (x_pre, omega_pre)"), rotated to the world
//! frame. Where the simulation is finer than the database, neighbouring samples share a point;
//! where it is coarser, a sample takes the value of the one point nearest to it and the points
//! between samples go unused.

use nalgebra::Isometry3;

use super::AblDatabase;
use crate::spatial::PointHash;
use crate::{Point3, Real, Vec3};

/// An obstacle's database with a search structure over its boundary points.
pub struct WallLayer {
    db: AblDatabase,
    points: Vec<Vec3>,
    hash: PointHash,
    reach: Real,
}

impl WallLayer {
    /// The layer of `db`, searched within `reach` (m) of a query before falling back to every
    /// point: the simulation's cell size plus the database's point spacing covers a cell centre
    /// beside the surface.
    pub fn new(db: AblDatabase, reach: Real) -> Self {
        let points: Vec<Vec3> = db.points().iter().map(|p| p.coords).collect();
        let hash = PointHash::new(&points, reach);
        Self {
            db,
            points,
            hash,
            reach,
        }
    }

    /// The database.
    pub fn database(&self) -> &AblDatabase {
        &self.db
    }

    /// Index of the boundary point nearest to `local`, a point in the object's frame (ties go
    /// to the lower index, so the mapping does not depend on the search order).
    pub fn nearest(&self, local: &Point3) -> usize {
        let consider = |best: &mut (Real, usize), i: usize| {
            let d = (self.points[i] - local.coords).norm_squared();
            if d < best.0 || (d == best.0 && i < best.1) {
                *best = (d, i);
            }
        };
        let mut best = (Real::INFINITY, usize::MAX);
        self.hash
            .for_each_near(&local.coords, self.reach, |i| consider(&mut best, i));
        if best.1 == usize::MAX {
            (0..self.points.len()).for_each(|i| consider(&mut best, i));
        }
        best.1
    }

    /// omega_pre at every boundary point in the world frame, times `scale` (the run time's gain
    /// over the layer's thickness, 1/m), for the object at `pose` moving with `linear` (m/s)
    /// relative to the surrounding flow and spinning with `angular` (rad/s), both in the world
    /// frame (section 5.1, "Applying the precomputed set").
    pub fn values(
        &self,
        pose: &Isometry3<Real>,
        linear: &Vec3,
        angular: &Vec3,
        scale: Real,
    ) -> Vec<Vec3> {
        let mut values = self.db.lookup_world(pose, linear, angular);
        if scale != 1.0 {
            values.iter_mut().for_each(|w| *w *= scale);
        }
        values
    }
}
