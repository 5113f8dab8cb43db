//! Figure 8's protocol on SPH particles (see [`super::abl`]): where a stream past obstacles in
//! a channel is measured. Each station is a slab two coarse spacings thick across the stream
//! (x), cut into bins two coarse spacings wide across the channel (z) and taking the whole
//! depth (y), on the statistics' lattice of that size: each bin's mean then averages about
//! eight of the coarse run's particles (a bin one spacing wide holds about one, whose own
//! noise would count as turbulence).

use crate::geometry::RigidBody;
use crate::scene::build::abl_settings;
use crate::scene::Scene;
use crate::Real;

/// The bins across the channel: `count` of `size` m from `origin` (m, along z).
#[derive(Debug, Clone, Copy)]
pub struct Bins {
    pub origin: Real,
    pub size: Real,
    pub count: usize,
}

impl Bins {
    /// Two coarse spacings wide, over the z extent of the scene's fluid blocks.
    pub fn across(scene: &Scene) -> Option<Self> {
        let fluid = scene.fluid.as_ref()?;
        let (lo, hi) = fluid
            .blocks
            .iter()
            .fold((Real::MAX, Real::MIN), |(lo, hi), b| {
                (lo.min(b.min[2]), hi.max(b.max[2]))
            });
        let count = ((hi - lo) / (2.0 * fluid.spacing)).round().max(1.0) as usize;
        Some(Self {
            origin: lo,
            size: (hi - lo) / count as Real,
            count,
        })
    }
}

/// Stations two and four obstacle lengths (along x) behind each obstacle with a database,
/// sorted, in m along x; `bodies` as [`crate::scene::build::bodies`] builds them.
pub fn default_stations(scene: &Scene, bodies: &[RigidBody]) -> Vec<Real> {
    let Some(settings) = abl_settings(scene) else {
        return Vec::new();
    };
    let mut stations: Vec<Real> = settings
        .databases
        .iter()
        .flat_map(|(body, _)| {
            let b = &bodies[*body];
            let (lo, hi) = b.local_aabb();
            let centre = b.pose(0.0).translation.vector.x;
            let length = hi.x - lo.x;
            [2.0, 4.0].map(|n| centre + n * length)
        })
        .collect();
    stations.sort_by(Real::total_cmp);
    stations
}
