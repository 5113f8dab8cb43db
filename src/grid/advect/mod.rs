//! Advection of staggered and cell-centred fields through the MAC velocity, by the scheme a
//! scene chose: semi-Lagrangian with a midpoint (second-order) backtrace, MacCormack (Selle et
//! al. 2008), or one registered from outside eddy ([`register`]).

mod maccormack;
mod registry;
mod semi_lagrangian;

use std::ops::Range;

use ndarray::Array3;

use super::interp::Stagger;
use super::mac::MacGrid;
use crate::Real;
pub use registry::{find, register, schemes, Advection, Scheme, Step, BUILT_IN};

/// `field` (laid out as `stagger`) carried by `vel` over `dt`.
pub fn advect(
    field: &Array3<Real>,
    stagger: Stagger,
    vel: &MacGrid,
    dt: Real,
    scheme: Advection,
) -> Array3<Real> {
    let mut out = Array3::zeros(field.raw_dim());
    advect_into(field, stagger, vel, dt, scheme, &mut out);
    out
}

/// [`advect`] into `out` (resized when its shape differs): a solver that keeps `out` between
/// steps allocates nothing.
pub fn advect_into(
    field: &Array3<Real>,
    stagger: Stagger,
    vel: &MacGrid,
    dt: Real,
    scheme: Advection,
    out: &mut Array3<Real>,
) {
    let band = stagger.shape.map(|n| 0..n);
    advect_band_into(field, stagger, vel, dt, scheme, &band, out);
}

/// A box of sample indices, `[i, j, k]` ranges.
pub type Band = [Range<usize>; 3];

/// [`advect_into`] of a field that is zero outside `band` shrunk by twice the largest number
/// of cells a sample travels in `dt`, plus three: only the samples in `band` are traced (the
/// others are zero, as they are in the full step), so a field confined to a small part of the
/// grid (the boundary layer's plume) costs its band, not the grid.
pub fn advect_band_into(
    field: &Array3<Real>,
    stagger: Stagger,
    vel: &MacGrid,
    dt: Real,
    scheme: Advection,
    band: &Band,
    out: &mut Array3<Real>,
) {
    if out.raw_dim() != field.raw_dim() || !out.is_standard_layout() {
        *out = Array3::zeros(field.raw_dim());
    }
    (scheme.scheme().advect)(field, stagger, vel, dt, band, out);
}

/// Every face component of `vel` carried by `vel` itself over `dt`.
pub fn advect_velocity(vel: &MacGrid, dt: Real, scheme: Advection) -> [Array3<Real>; 3] {
    std::array::from_fn(|a| advect(&vel.u[a], vel.face_stagger(a), vel, dt, scheme))
}

/// [`advect_velocity`] into `out` (see [`advect_into`]).
pub fn advect_velocity_into(
    vel: &MacGrid,
    dt: Real,
    scheme: Advection,
    out: &mut [Array3<Real>; 3],
) {
    for (a, out) in out.iter_mut().enumerate() {
        advect_into(&vel.u[a], vel.face_stagger(a), vel, dt, scheme, out);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Vec3;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The semi-Lagrangian step of one sample written out plainly: midpoint backtrace through
    /// the interpolated velocity, then the field interpolated at the departure point.
    fn reference(field: &Array3<Real>, stagger: &Stagger, vel: &MacGrid, dt: Real) -> Array3<Real> {
        let dt_cells = dt / vel.dx;
        Array3::from_shape_fn(field.raw_dim(), |(i, j, k)| {
            let g = stagger.position([i, j, k]);
            let v1 = vel.velocity_at_grid(g);
            let mid: [Real; 3] = std::array::from_fn(|a| g[a] - 0.5 * dt_cells * v1[a]);
            let v = vel.velocity_at_grid(mid);
            stagger.sample(field, std::array::from_fn(|a| g[a] - dt_cells * v[a]))
        })
    }

    /// The row-wise advection (flat slices, the velocity at the samples read from their faces,
    /// the row traced in passes) equals the plain per-sample step to 1e-12, for cell-centred and
    /// face fields, on clamped and periodic axes, with departure points beyond the domain.
    #[test]
    fn semi_lagrangian_equals_the_plain_per_sample_step() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        for periodic in [[false; 3], [true, false, true], [false, true, false]] {
            let mut mac = MacGrid::new([6, 5, 4], 0.1, Vec3::new(0.2, -0.1, 0.3), periodic);
            for u in mac.u.iter_mut() {
                u.mapv_inplace(|_| rng.random_range(-2.0..2.0));
            }
            mac.sync_periodic();
            // Up to 2 m/s over 0.08 s: departure points up to 1.6 cells away, past the ends.
            let dt = 0.08;
            let mut staggers = vec![mac.cell_stagger()];
            staggers.extend((0..3).map(|a| mac.face_stagger(a)));
            for stagger in staggers {
                let field = Array3::from_shape_fn(stagger.shape, |_| rng.random_range(-1.0..1.0));
                let fast = advect(&field, stagger, &mac, dt, Advection::SEMI_LAGRANGIAN);
                let plain = reference(&field, &stagger, &mac, dt);
                for ((idx, a), b) in fast.indexed_iter().zip(&plain) {
                    assert!(
                        (a - b).abs() < 1e-12,
                        "{periodic:?} {:?} sample {idx:?}: {a} against {b}",
                        stagger.offset
                    );
                }
            }
        }
    }

    /// A field that is zero outside a box advects in a band around it (the box widened by
    /// twice the cells a sample travels, plus three) exactly as over the whole grid, bit for
    /// bit, with both schemes.
    #[test]
    fn band_advection_equals_the_full_step() {
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        let mut mac = MacGrid::new([24, 22, 20], 0.1, Vec3::zeros(), [false; 3]);
        for u in mac.u.iter_mut() {
            u.mapv_inplace(|_| rng.random_range(-2.0..2.0));
        }
        // Up to 2 m/s over 0.08 s: 1.6 cells, so the band is the box widened by 2 * 2 + 3.
        let dt = 0.08;
        let stagger = mac.cell_stagger();
        let boxed = [9..13, 8..12, 10..13];
        let field = Array3::from_shape_fn(stagger.shape, |(i, j, k)| {
            let inside = boxed[0].contains(&i) && boxed[1].contains(&j) && boxed[2].contains(&k);
            if inside {
                rng.random_range(-1.0..1.0)
            } else {
                0.0
            }
        });
        let band: Band = std::array::from_fn(|a| {
            boxed[a].start.saturating_sub(7)..(boxed[a].end + 7).min(stagger.shape[a])
        });
        assert!(band[0] != (0..24), "the band is smaller than the grid");
        for scheme in [Advection::SEMI_LAGRANGIAN, Advection::MACCORMACK] {
            let full = advect(&field, stagger, &mac, dt, scheme);
            let mut banded = Array3::from_elem(stagger.shape, 7.0);
            advect_band_into(&field, stagger, &mac, dt, scheme, &band, &mut banded);
            assert!(full == banded, "{scheme:?}");
            assert!(full.iter().any(|&v| v != 0.0));
        }
    }
}
