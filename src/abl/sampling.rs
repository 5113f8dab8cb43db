//! Directions on the unit sphere sampled on a latitude–longitude grid, and the weights of the
//! bilinear spherical interpolation between them (Pfaff et al. 2009, section 5.1: 10 x 20 samples
//! in spherical coordinates).
//!
//! Polar angles `theta_i = i pi / (n_polar - 1)` include both poles, azimuths
//! `phi_j = 2 pi j / n_azimuth` wrap around; the direction is
//! `(sin theta cos phi, sin theta sin phi, cos theta)` in the object's frame. A pole row holds
//! one direction `n_azimuth` times with identical values, so the interpolation tends to the pole
//! value from every azimuth (continuity at the poles) and the azimuth index wraps modulo
//! `n_azimuth` (continuity across the seam at phi = 0 = 2 pi).

use std::f64::consts::PI;

use crate::{Real, Vec3};

/// Interpolation weights closer than this to 0 or 1 are snapped, so that a lookup at a sampled
/// direction (whose angles come back from acos/atan2 with rounding) returns the stored row bit
/// for bit.
const SNAP: Real = 1e-9;

/// A latitude–longitude sampling of directions.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Sampling {
    /// Polar samples, both poles included (at least 2).
    pub polar: usize,
    /// Azimuth samples (at least 1).
    pub azimuth: usize,
}

impl Sampling {
    /// A sampling, or why it is not one.
    pub fn new(polar: usize, azimuth: usize) -> Result<Self, String> {
        if polar < 2 || azimuth < 1 {
            return Err(format!(
                "sampling [{polar}, {azimuth}]: need at least 2 polar samples (the poles) and 1 azimuth"
            ));
        }
        Ok(Self { polar, azimuth })
    }

    /// Number of stored rows, `polar * azimuth` (pole rows repeated).
    pub fn len(&self) -> usize {
        self.polar * self.azimuth
    }

    /// Never true for a valid sampling.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Row of polar sample `i` and azimuth sample `j`.
    pub fn row(&self, i: usize, j: usize) -> usize {
        i * self.azimuth + j
    }

    /// Polar angle of sample `i`, radians.
    pub fn polar_angle(&self, i: usize) -> Real {
        i as Real * PI / (self.polar - 1) as Real
    }

    /// Azimuth of sample `j`, radians.
    pub fn azimuth_angle(&self, j: usize) -> Real {
        2.0 * PI * j as Real / self.azimuth as Real
    }

    /// Whether polar sample `i` is a pole.
    pub fn is_pole(&self, i: usize) -> bool {
        i == 0 || i + 1 == self.polar
    }

    /// The unit direction of sample (i, j); exactly +-z at the poles.
    pub fn direction(&self, i: usize, j: usize) -> Vec3 {
        if i == 0 {
            return Vec3::z();
        }
        if i + 1 == self.polar {
            return -Vec3::z();
        }
        let (st, ct) = self.polar_angle(i).sin_cos();
        let (sp, cp) = self.azimuth_angle(j).sin_cos();
        Vec3::new(st * cp, st * sp, ct)
    }

    /// The samples that need their own computation, in the canonical order: every (i, j) off
    /// the poles and (pole, 0) once per pole, polar-major.
    pub fn distinct(&self) -> Vec<(usize, usize)> {
        (0..self.polar)
            .flat_map(|i| {
                let n = if self.is_pole(i) { 1 } else { self.azimuth };
                (0..n).map(move |j| (i, j))
            })
            .collect()
    }

    /// The four (row, weight) pairs of the bilinear interpolation at the unit direction `d`
    /// (weights sum to 1). Bilinear in (theta, phi): linear in the polar angle between the two
    /// bracketing rings, linear in azimuth between the two bracketing meridians, wrapping.
    pub fn weights(&self, d: &Vec3) -> [(usize, Real); 4] {
        let theta = d.z.clamp(-1.0, 1.0).acos();
        let mut phi = d.y.atan2(d.x);
        if phi < 0.0 {
            phi += 2.0 * PI;
        }
        let t = theta * (self.polar - 1) as Real / PI;
        let i0 = (t.floor() as usize).min(self.polar - 2);
        let a = snap(t - i0 as Real);
        let s = phi * self.azimuth as Real / (2.0 * PI);
        let j_floor = s.floor();
        let b = snap(s - j_floor);
        let j0 = (j_floor as usize) % self.azimuth;
        let j1 = (j0 + 1) % self.azimuth;
        [
            (self.row(i0, j0), (1.0 - a) * (1.0 - b)),
            (self.row(i0, j1), (1.0 - a) * b),
            (self.row(i0 + 1, j0), a * (1.0 - b)),
            (self.row(i0 + 1, j1), a * b),
        ]
    }
}

/// A fraction in [0, 1] with values within [`SNAP`] of either end set to that end.
fn snap(f: Real) -> Real {
    if f < SNAP {
        0.0
    } else if f > 1.0 - SNAP {
        1.0
    } else {
        f
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_at_samples_pick_one_row() {
        let s = Sampling::new(7, 12).expect("valid");
        for i in 0..s.polar {
            for j in 0..s.azimuth {
                let w = s.weights(&s.direction(i, j));
                let picked: Vec<_> = w.iter().filter(|(_, w)| *w != 0.0).collect();
                assert_eq!(picked.len(), 1, "sample ({i}, {j}): {w:?}");
                let row = picked[0].0;
                // At a pole any azimuth of that pole row is the same direction.
                let (ri, rj) = (row / s.azimuth, row % s.azimuth);
                assert_eq!(ri, i);
                assert!(
                    s.is_pole(i) || rj == j,
                    "sample ({i}, {j}) picked row {row}"
                );
                assert_eq!(picked[0].1, 1.0);
            }
        }
    }

    #[test]
    fn weights_sum_to_one_and_wrap_the_seam() {
        let s = Sampling::new(10, 20).expect("valid");
        // Just below phi = 2 pi the bracketing meridians are the last and the first.
        let d = Vec3::new(1.0, -1e-3, 0.2).normalize();
        let w = s.weights(&d);
        let total: Real = w.iter().map(|(_, w)| w).sum();
        assert!((total - 1.0).abs() < 1e-14);
        let cols: Vec<usize> = w.iter().map(|(r, _)| r % s.azimuth).collect();
        assert!(cols.contains(&19) && cols.contains(&0), "{cols:?}");
    }
}
