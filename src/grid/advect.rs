//! Advection of staggered and cell-centred fields through the MAC velocity: semi-Lagrangian
//! with a midpoint (second-order) backtrace, and MacCormack (Selle et al. 2008).
//!
//! MacCormack traces with one Euler step from the velocity at the sample itself (read from two
//! or four faces, no interpolation): the forward-backward error estimate cancels the Euler
//! trace's O(dt^2) position error along with the interpolation error, so the scheme stays
//! second order in time, and each sample costs one interpolation instead of four.

use std::ops::Range;

use ndarray::{Array3, Zip};
use rayon::prelude::*;

use super::interp::{standard, Stagger};
use super::mac::{MacGrid, MacView};
use super::params::Advection;
use crate::Real;

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
    match scheme {
        Advection::SemiLagrangian => {
            semi_lagrangian(field, stagger, vel, dt, Trace::Midpoint, band, out, false);
        }
        Advection::Maccormack => maccormack(field, stagger, vel, dt, band, out),
    }
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

/// How a sample's departure point is found.
#[derive(Clone, Copy)]
enum Trace {
    /// Midpoint rule: second order in the trajectory.
    Midpoint,
    /// One Euler step with the velocity at the sample.
    Euler,
}

/// One semi-Lagrangian step into `out` (of the field's shape, standard layout); with `range`,
/// also the smallest and largest sample each new value was interpolated from (MacCormack's
/// clamp). The samples are visited an x-slab at a time (one parallel task each), with the field
/// and the velocity read as flat slices.
#[allow(clippy::too_many_arguments)]
fn semi_lagrangian(
    field: &Array3<Real>,
    stagger: Stagger,
    vel: &MacGrid,
    dt: Real,
    trace: Trace,
    band: &Band,
    out: &mut Array3<Real>,
    range: bool,
) -> Option<[Array3<Real>; 2]> {
    let run = match stagger.face_axis() {
        Some(0) => semi_lagrangian_on::<0>,
        Some(1) => semi_lagrangian_on::<1>,
        Some(2) => semi_lagrangian_on::<2>,
        _ => semi_lagrangian_on::<3>,
    };
    run(field, stagger, vel, dt, trace, band, out, range)
}

/// [`semi_lagrangian`] for a field on the faces of axis `F` (3: cell centres); samples
/// outside `band` are set to zero.
#[allow(clippy::too_many_arguments)]
fn semi_lagrangian_on<const F: usize>(
    field: &Array3<Real>,
    stagger: Stagger,
    vel: &MacGrid,
    dt: Real,
    trace: Trace,
    band: &Band,
    out: &mut Array3<Real>,
    range: bool,
) -> Option<[Array3<Real>; 2]> {
    let dt_cells = dt / vel.dx;
    let view = vel.view();
    let field = field.as_standard_layout();
    let data = standard(&field);
    let [_, ny, nz] = stagger.shape;
    let slab = (ny * nz).max(1);
    let full = band[1] == (0..ny) && band[2] == (0..nz);
    // Zeroes a slab outside the band; true when it lies in the band's x range.
    let inside = |i: usize, s: &mut [Real]| {
        let inside = band[0].contains(&i);
        if !inside || !full {
            s.fill(0.0);
        }
        inside
    };
    let out_slabs = slabs(out, slab);
    if !range {
        out_slabs.enumerate().for_each(|(i, o)| {
            if inside(i, o) {
                departures::<F>(&view, &stagger, i, band, dt_cells, trace, |c, g| {
                    o[c] = stagger.sample_slice(data, g)
                });
            }
        });
        return None;
    }
    let mut lo = Array3::zeros(field.raw_dim());
    let mut hi = Array3::zeros(field.raw_dim());
    out_slabs
        .zip(slabs(&mut lo, slab).zip(slabs(&mut hi, slab)))
        .enumerate()
        .for_each(|(i, (o, (l, h)))| {
            if inside(i, o) {
                departures::<F>(&view, &stagger, i, band, dt_cells, trace, |c, g| {
                    (o[c], l[c], h[c]) = stagger.sample_slice_with_range(data, g)
                });
            }
        });
    Some([lo, hi])
}

/// Calls `visit(index in the slab, departure point in cell units)` for every sample of x-slab
/// `i` of a field on the faces of axis `F` (3: cell centres): where the fluid there was `dt`
/// ago. A z-row is traced in passes (the Euler or midpoint points of the whole row, then
/// the velocity at each): the samples are independent, and separate passes let the processor
/// overlap their long chains of dependent arithmetic instead of waiting on each in turn.
#[inline(always)]
fn departures<const F: usize>(
    vel: &MacView,
    stagger: &Stagger,
    i: usize,
    band: &Band,
    dt_cells: Real,
    trace: Trace,
    mut visit: impl FnMut(usize, [Real; 3]),
) {
    let nz = stagger.shape[2];
    let ks = band[2].clone();
    let mut row: Vec<[Real; 3]> = Vec::with_capacity(ks.len());
    for j in band[1].clone() {
        row.clear();
        row.extend(ks.clone().map(|k| {
            let g = stagger.position([i, j, k]);
            let v = vel.velocity_at_sample::<F>([i, j, k]);
            let step = match trace {
                Trace::Euler => dt_cells,
                Trace::Midpoint => 0.5 * dt_cells,
            };
            std::array::from_fn(|a| g[a] - step * v[a])
        }));
        if let Trace::Midpoint = trace {
            for (k, p) in ks.clone().zip(row.iter_mut()) {
                let g = stagger.position([i, j, k]);
                let v = vel.velocity_at_grid(*p);
                *p = std::array::from_fn(|a| g[a] - dt_cells * v[a]);
            }
        }
        for (k, &p) in ks.clone().zip(&row) {
            visit(j * nz + k, p);
        }
    }
}

/// The x-slabs of a new array, for parallel writing.
fn slabs(a: &mut Array3<Real>, slab: usize) -> rayon::slice::ChunksMut<'_, Real> {
    a.as_slice_mut()
        .expect("a new array is in standard layout")
        .par_chunks_mut(slab)
}

/// MacCormack: a forward and a backward semi-Lagrangian step estimate the forward step's
/// error, half of which is removed; the result is clamped to the range of the samples the
/// forward step read, which keeps the scheme free of new extrema (Selle et al. 2008, Eq. 6–8).
fn maccormack(
    field: &Array3<Real>,
    stagger: Stagger,
    vel: &MacGrid,
    dt: Real,
    band: &Band,
    forward: &mut Array3<Real>,
) {
    let [lo, hi] = semi_lagrangian(field, stagger, vel, dt, Trace::Euler, band, forward, true)
        .expect("requested with range");
    let mut back = Array3::zeros(field.raw_dim());
    semi_lagrangian(
        forward,
        stagger,
        vel,
        -dt,
        Trace::Euler,
        band,
        &mut back,
        false,
    );
    Zip::from(forward)
        .and(field)
        .and(&back)
        .and(&lo)
        .and(&hi)
        .par_for_each(|f, &orig, &b, &l, &h| {
            *f = (*f + 0.5 * (orig - b)).clamp(l, h);
        });
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
                let fast = advect(&field, stagger, &mac, dt, Advection::SemiLagrangian);
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
        for scheme in [Advection::SemiLagrangian, Advection::Maccormack] {
            let full = advect(&field, stagger, &mac, dt, scheme);
            let mut banded = Array3::from_elem(stagger.shape, 7.0);
            advect_band_into(&field, stagger, &mac, dt, scheme, &band, &mut banded);
            assert!(full == banded, "{scheme:?}");
            assert!(full.iter().any(|&v| v != 0.0));
        }
    }
}
