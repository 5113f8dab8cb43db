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

use super::quad;
use crate::{Real, Vec3};

/// Interpolation weights closer than this to 0 or 1 are snapped, so that a lookup at a sampled
/// direction (whose angles come back from acos/atan2 with rounding) returns the stored row bit
/// for bit.
const SNAP: Real = 1e-9;

/// A latitude–longitude sampling of directions.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Sampling {
    /// Polar samples, both poles included (at least 3).
    pub polar: usize,
    /// Azimuth samples (at least 3).
    pub azimuth: usize,
}

impl Sampling {
    /// A sampling, or why it is not one.
    pub fn new(polar: usize, azimuth: usize) -> Result<Self, String> {
        // Fewer rings or meridians leave cells whose corners do not span a cone of directions
        // (two meridians are one great circle), so the interpolation could not cover the sphere.
        if polar < 3 || azimuth < 3 {
            return Err(format!(
                "sampling [{polar}, {azimuth}]: need at least 3 polar samples (the poles and a \
                 ring) and 3 azimuths"
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

    /// The four (row, weight) pairs of the bilinear spherical interpolation at the unit
    /// direction `d` (section 5.1, "a bilinear spherical interpolation is performed").
    ///
    /// The weights are `lambda (1-s)(1-t)`, `lambda s(1-t)`, `lambda (1-s)t`, `lambda st` on
    /// the corners of the sample cell, with (s, t) the point where the bilinear blend of the four
    /// corner directions points along `d` and `lambda = d.B / |B|^2` (see [`super::quad`]), so
    /// that `sum w_i d_i = d` exactly: any quantity linear in the direction is reproduced. That
    /// matters because omega_pre is close to linear in the flow direction (for a sphere in
    /// potential flow `omega_pre = 1.5 beta (d x n)` exactly); plain bilinear weights in
    /// (theta, phi) shrink such a field by `(dtheta^2 + sin^2 theta dphi^2) / 8` at a cell
    /// centre (2.8 % on the equator at 10 x 20 samples), which alone is more than the paper's
    /// 1.6 % mean error at 20 azimuth samples (Figure 12). It is still bilinear (in the
    /// cell's own parameters), exact at the samples, and continuous: two cells sharing an edge
    /// share its chord and give the same weights there; at a pole every azimuth's cell tends to
    /// the pole row. The weights sum to `lambda`, slightly above 1 inside a cell: a constant
    /// field is not reproduced, which costs nothing for omega_pre, odd in the direction to
    /// leading order.
    ///
    /// The cell is found from (theta, phi); a constant-theta edge is a great-circle arc, not a
    /// circle of latitude, so a direction near it may lie in the neighbouring ring's cell, which
    /// the search moves to.
    pub fn weights(&self, d: &Vec3) -> [(usize, Real); 4] {
        let theta = d.z.clamp(-1.0, 1.0).acos();
        let mut phi = d.y.atan2(d.x);
        if phi < 0.0 {
            phi += 2.0 * PI;
        }
        let along = theta * (self.polar - 1) as Real / PI;
        let mut i0 = (along.floor() as usize).min(self.polar - 2);
        let mut t = along - i0 as Real;
        let around = phi * self.azimuth as Real / (2.0 * PI);
        let j0 = (around.floor() as usize) % self.azimuth;
        let j1 = (j0 + 1) % self.azimuth;
        let mut s = around - around.floor();
        let corners = |i0: usize| {
            [
                self.direction(i0, j0),
                self.direction(i0, j1),
                self.direction(i0 + 1, j0),
                self.direction(i0 + 1, j1),
            ]
        };
        let mut c = corners(i0);
        // Every move is followed by a solve in the new cell; the cap only guards the loop.
        for moves in 0.. {
            (s, t) = quad::invert(&c, d, s, t);
            if t < -SNAP && i0 > 0 && moves < self.polar {
                (i0, t) = (i0 - 1, 1.0);
            } else if t > 1.0 + SNAP && i0 + 2 < self.polar && moves < self.polar {
                (i0, t) = (i0 + 1, 0.0);
            } else {
                break;
            }
            c = corners(i0);
        }
        let t = snap(t.clamp(0.0, 1.0));
        let on_pole = (i0 == 0 && t == 0.0) || (i0 + 2 == self.polar && t == 1.0);
        // On a pole the azimuth parameter is meaningless; one pole row carries the weight.
        let s = if on_pole {
            0.0
        } else {
            snap(s.clamp(0.0, 1.0))
        };
        let at_sample = (s == 0.0 || s == 1.0) && (t == 0.0 || t == 1.0);
        let lambda = if at_sample {
            1.0
        } else {
            let b = quad::blend(&c, s, t);
            d.dot(&b) / b.norm_squared()
        };
        [
            (self.row(i0, j0), lambda * (1.0 - s) * (1.0 - t)),
            (self.row(i0, j1), lambda * s * (1.0 - t)),
            (self.row(i0 + 1, j0), lambda * (1.0 - s) * t),
            (self.row(i0 + 1, j1), lambda * s * t),
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
    fn weights_reproduce_the_direction_and_wrap_the_seam() {
        let s = Sampling::new(10, 20).expect("valid");
        // Just below phi = 2 pi the bracketing meridians are the last and the first.
        let d = Vec3::new(1.0, -1e-3, 0.2).normalize();
        let w = s.weights(&d);
        let cols: Vec<usize> = w.iter().map(|(r, _)| r % s.azimuth).collect();
        assert!(cols.contains(&19) && cols.contains(&0), "{cols:?}");
        // Just poleward of ring 3 (60 degrees) half-way between two meridians: the cell's
        // great-circle edge bulges 0.3 degrees further poleward, so the direction belongs to
        // the cell below the ring, not to the (theta, phi) cell above it.
        let ring = PI / (s.polar - 1) as Real;
        let (theta, phi) = (3.0 * ring - 1e-3, 0.5 * 2.0 * PI / s.azimuth as Real);
        let below_ring = Vec3::new(
            theta.sin() * phi.cos(),
            theta.sin() * phi.sin(),
            theta.cos(),
        );
        let rings: Vec<usize> = s
            .weights(&below_ring)
            .iter()
            .map(|(r, _)| r / s.azimuth)
            .collect();
        assert_eq!(rings, [3, 3, 4, 4]);
        // There, near the seam, off any edge and next to a pole, the weights give d back.
        for d in [
            below_ring,
            d,
            Vec3::new(0.3, 0.2, 0.93).normalize(),
            Vec3::new(-0.5, 0.7, -0.1).normalize(),
            Vec3::new(1e-4, 2e-4, -1.0).normalize(),
        ] {
            let w = s.weights(&d);
            let back: Vec3 = w
                .iter()
                .map(|&(r, w)| s.direction(r / s.azimuth, r % s.azimuth) * w)
                .sum();
            assert!((back - d).norm() < 1e-14, "{d:?}: {back:?}");
            assert!(w.iter().all(|&(_, w)| w >= 0.0), "{w:?}");
        }
    }
}
