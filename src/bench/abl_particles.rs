//! Figure 8's protocol on SPH particles (see [`super::abl`]): the wake statistics of a stream
//! past obstacles in a channel, from the fluid particles.
//!
//! **Measure.** Each station is a slab one coarse spacing thick across the stream (x), cut into
//! bins one coarse spacing wide across the channel (z) and taking the whole depth (y). Every
//! step, each fluid particle in a bin adds `dt`, `u_i dt` and `u_i^2 dt`; the bin's
//! time-averaged velocity is then `U_i = sum u_i dt / sum dt` (the particles' mean, weighted by
//! time) and its turbulent kinetic energy `k = 1/2 sum (<u_i^2> - U_i^2)`. The finer
//! reference's particles fall into the same bins, so its small-scale fluctuation counts as
//! fluctuation, as on the grid.

use super::abl::Profiles;
use crate::geometry::RigidBody;
use crate::pipeline::Pipeline;
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
    /// One coarse spacing wide, over the z extent of the scene's fluid blocks.
    pub fn across(scene: &Scene) -> Option<Self> {
        let fluid = scene.fluid.as_ref()?;
        let (lo, hi) = fluid
            .blocks
            .iter()
            .fold((Real::MAX, Real::MIN), |(lo, hi), b| {
                (lo.min(b.min[2]), hi.max(b.max[2]))
            });
        let count = ((hi - lo) / fluid.spacing).round().max(1.0) as usize;
        Some(Self {
            origin: lo,
            size: (hi - lo) / count as Real,
            count,
        })
    }
}

/// Time sums per station and bin: `[dt, u dt, v dt, w dt, uu dt, vv dt, ww dt]`.
pub struct ParticleStations {
    stations: Vec<Real>,
    /// Half the slab thickness, m.
    half: Real,
    bins: Bins,
    sums: Vec<[Real; 7]>,
}

impl ParticleStations {
    pub fn new(stations: &[Real], bins: Bins) -> Self {
        Self {
            stations: stations.to_vec(),
            half: 0.5 * bins.size,
            bins,
            sums: vec![[0.0; 7]; stations.len() * bins.count],
        }
    }

    /// Adds the fluid's state over a step of `dt`.
    pub fn add(&mut self, p: &Pipeline, dt: Real) {
        let fluid = &p.sim.sph.as_ref().expect("an SPH scene").fluid;
        for (x, v) in fluid.x.iter().zip(&fluid.v) {
            let Some(s) = self
                .stations
                .iter()
                .position(|&xs| (x.x - xs).abs() < self.half)
            else {
                continue;
            };
            let b = ((x.z - self.bins.origin) / self.bins.size).floor();
            if b < 0.0 || b >= self.bins.count as Real {
                continue;
            }
            let sum = &mut self.sums[s * self.bins.count + b as usize];
            sum[0] += dt;
            for c in 0..3 {
                sum[1 + c] += v[c] * dt;
                sum[4 + c] += v[c] * v[c] * dt;
            }
        }
    }

    /// Per station, per bin: (U, k); NaN where no particle ever passed.
    pub fn profiles(&self) -> Profiles {
        self.sums
            .chunks(self.bins.count)
            .map(|station| {
                station
                    .iter()
                    .map(|s| {
                        if s[0] <= 0.0 {
                            return (Real::NAN, Real::NAN);
                        }
                        let mean: [Real; 3] = std::array::from_fn(|c| s[1 + c] / s[0]);
                        let k = 0.5
                            * (0..3)
                                .map(|c| (s[4 + c] / s[0] - mean[c] * mean[c]).max(0.0))
                                .sum::<Real>();
                        (mean[0], k)
                    })
                    .collect()
            })
            .collect()
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_steady_bin_has_its_velocity_and_no_energy_and_a_fluctuating_one_its_variance() {
        let bins = Bins {
            origin: 0.0,
            size: 0.1,
            count: 2,
        };
        let mut s = ParticleStations::new(&[1.0], bins);
        // Bin 0 sees u = 2 always; bin 1 sees u = 1 +- 0.5 in alternation, w = 0.
        for step in 0..10 {
            let sign = if step % 2 == 0 { 1.0 } else { -1.0 };
            for (b, u) in [(0, 2.0), (1, 1.0 + 0.5 * sign)] {
                let sum = &mut s.sums[b];
                sum[0] += 0.01;
                sum[1] += u * 0.01;
                sum[4] += u * u * 0.01;
            }
        }
        let p = s.profiles();
        assert!((p[0][0].0 - 2.0).abs() < 1e-12 && p[0][0].1.abs() < 1e-12);
        assert!((p[0][1].0 - 1.0).abs() < 1e-12);
        assert!((p[0][1].1 - 0.5 * 0.25).abs() < 1e-12, "k = {}", p[0][1].1);
    }
}
