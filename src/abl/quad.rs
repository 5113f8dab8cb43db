//! The bilinear blend of a cell's four corner directions and its inverse: the parameters
//! (s, t) at which the blend points along a given direction.
//!
//! A cell of the latitude–longitude sampling has corner directions `c[0] = (i, j)`,
//! `c[1] = (i, j + 1)`, `c[2] = (i + 1, j)`, `c[3] = (i + 1, j + 1)`. The blend
//! `B(s, t) = (1-s)(1-t) c[0] + s(1-t) c[1] + (1-s) t c[2] + s t c[3]` is a ruled patch whose
//! edges are the chords between neighbouring corners; seen from the centre, a chord covers the
//! great-circle arc between its ends, so the cells, as cones of directions, are spherical
//! quadrilaterals with great-circle edges that tile the sphere (two cells sharing an edge share
//! its chord).

use crate::{Real, Vec3};

/// Newton stops when the step in (s, t) is below this (a few ulps of a parameter in [0, 1]).
const STEP_TOL: Real = 1e-14;
/// Newton's iteration cap; from the (theta, phi) guess it converges in three or four.
const MAX_NEWTON: usize = 16;

/// `B(s, t)` for the corners `c`.
pub(super) fn blend(c: &[Vec3; 4], s: Real, t: Real) -> Vec3 {
    c[0] * ((1.0 - s) * (1.0 - t))
        + c[1] * (s * (1.0 - t))
        + c[2] * ((1.0 - s) * t)
        + c[3] * (s * t)
}

/// The (s, t) near the guess `(s, t)` at which `B(s, t)` is parallel to `d`, by Newton's method
/// on the two components of `B` perpendicular to `d`. The result may lie outside [0, 1]^2 when
/// `d` is outside the cell; the caller moves to the neighbouring cell then.
pub(super) fn invert(c: &[Vec3; 4], d: &Vec3, mut s: Real, mut t: Real) -> (Real, Real) {
    let (e1, e2) = tangent_basis(d);
    let twist = c[0] - c[1] - c[2] + c[3];
    for _ in 0..MAX_NEWTON {
        let b = blend(c, s, t);
        let bs = c[1] - c[0] + twist * t;
        let bt = c[2] - c[0] + twist * s;
        let (f1, f2) = (e1.dot(&b), e2.dot(&b));
        let (j11, j12, j21, j22) = (e1.dot(&bs), e1.dot(&bt), e2.dot(&bs), e2.dot(&bt));
        let det = j11 * j22 - j12 * j21;
        // Singular only on a pole's degenerate edge (t = 0 of a polar triangle), where B is
        // already the pole.
        if det == 0.0 || !det.is_finite() {
            break;
        }
        let ds = (f2 * j12 - f1 * j22) / det;
        let dt = (f1 * j21 - f2 * j11) / det;
        s += ds;
        t += dt;
        if ds.abs().max(dt.abs()) <= STEP_TOL {
            break;
        }
    }
    (s, t)
}

/// Two unit vectors perpendicular to `d` and to each other.
fn tangent_basis(d: &Vec3) -> (Vec3, Vec3) {
    let n = d.normalize();
    // Cross with the axis least aligned with d, so the first tangent is well conditioned.
    let a = n.abs();
    let axis = if a.x <= a.y && a.x <= a.z {
        Vec3::x()
    } else if a.y <= a.z {
        Vec3::y()
    } else {
        Vec3::z()
    };
    let e1 = n.cross(&axis).normalize();
    (e1, n.cross(&e1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_blend_points_along_the_direction() {
        let c = [
            Vec3::new(0.9, 0.1, 0.4).normalize(),
            Vec3::new(0.7, 0.6, 0.4).normalize(),
            Vec3::new(0.95, 0.1, 0.1).normalize(),
            Vec3::new(0.7, 0.7, 0.1).normalize(),
        ];
        let target = blend(&c, 0.3, 0.8).normalize();
        let (s, t) = invert(&c, &target, 0.5, 0.5);
        assert!(
            (s - 0.3).abs() < 1e-13 && (t - 0.8).abs() < 1e-13,
            "{s} {t}"
        );
    }
}
