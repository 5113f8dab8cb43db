//! What the run-time boundary layer asks of the SPH fluid (Pfaff et al. 2009, Figure 9 on
//! particles): the distance of a point to the nearest wall (the mixing length l_m of Eq. 8),
//! the fluid particles within a band of an obstacle's surface (the wall-attached layer and the
//! ambient-flow shell), and the free surface, which bounds a vortex kernel as walls do
//! (section 6: "we reduce a particle's kernel size once it extends past the liquid phase").

use rayon::prelude::*;

use super::dfsph::MIN_NEIGHBORS_FOR_DIVERGENCE;
use super::solver::SphSolver;
use crate::geometry::RigidBody;
use crate::{Point3, Real, Vec3};

/// Distance from `x` to the nearest wall of `bodies` at time `t`, negative inside a solid:
/// the inside of the container (body 0 when `container`) and the outside of every obstacle.
pub fn wall_distance(bodies: &[RigidBody], container: bool, t: Real, x: &Point3) -> Real {
    bodies
        .iter()
        .enumerate()
        .map(|(i, b)| {
            let d = b.signed_distance(t, x);
            if i == 0 && container {
                -d
            } else {
                d
            }
        })
        .fold(Real::INFINITY, Real::min)
}

impl SphSolver {
    /// [`wall_distance`] of this fluid's bodies at its time.
    pub fn wall_distance(&self, x: &Point3) -> Real {
        wall_distance(&self.bodies, self.has_container(), self.time(), x)
    }

    /// The fluid particles whose signed distance to the surface of `body` lies in `[lo, hi)`,
    /// in index order. Only particles inside the body's bounding box widened by `hi` are
    /// measured.
    pub fn particles_near(&self, body: usize, lo: Real, hi: Real) -> Vec<usize> {
        let b = &self.bodies[body];
        let t = self.time();
        let (min, max) = b.world_aabb(t);
        let (min, max) = (min.add_scalar(-hi), max.add_scalar(hi));
        let inverse = b.pose(t).inverse();
        self.fluid
            .x
            .par_iter()
            .enumerate()
            .filter(|(_, x)| (0..3).all(|a| x[a] >= min[a] && x[a] <= max[a]))
            .filter(|(_, x)| {
                let d = b.signed_distance_local(&(inverse * Point3::from(**x)));
                d >= lo && d < hi
            })
            .map(|(i, _)| i)
            .collect()
    }

    /// Mean velocity of the fluid particles `idx`; `None` when there are none.
    pub fn mean_velocity(&self, idx: &[usize]) -> Option<Vec3> {
        let sum: Vec3 = idx.iter().map(|&i| self.fluid.v[i]).sum();
        (!idx.is_empty()).then(|| sum / idx.len() as Real)
    }

    /// Positions of the free-surface particles: fewer than [`MIN_NEIGHBORS_FOR_DIVERGENCE`]
    /// fluid and boundary neighbours, the criterion the divergence solve uses (a particle with
    /// a full neighbourhood, walls counted, is inside the liquid).
    pub fn surface_positions(&self) -> Vec<Vec3> {
        let nb = self.neighborhood();
        self.fluid
            .x
            .iter()
            .enumerate()
            .filter(|&(i, _)| nb.count(i) < MIN_NEIGHBORS_FOR_DIVERGENCE)
            .map(|(_, x)| *x)
            .collect()
    }
}
