//! Semi-Lagrangian advection: each sample takes the field's value where the fluid there was
//! `dt` ago, traced back through the velocity and interpolated trilinearly. The step here also
//! serves MacCormack, whose forward and backward steps are it with an Euler trace.

use ndarray::Array3;
use rayon::prelude::*;

use super::{Band, Scheme};
use crate::grid::interp::{standard, Stagger};
use crate::grid::mac::{MacGrid, MacView};
use crate::Real;

/// The scheme, with a midpoint (second-order) backtrace.
pub(super) static SCHEME: Scheme = Scheme {
    name: "semi_lagrangian",
    label: "semi-Lagrangian",
    summary: "Semi-Lagrangian, trilinear, second-order (midpoint) backtrace.",
    advect,
};

/// [`step`] with a midpoint trace.
fn advect(
    field: &Array3<Real>,
    stagger: Stagger,
    vel: &MacGrid,
    dt: Real,
    band: &Band,
    out: &mut Array3<Real>,
) {
    step(field, stagger, vel, dt, Trace::Midpoint, band, out, false);
}

/// How a sample's departure point is found.
#[derive(Clone, Copy)]
pub(super) enum Trace {
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
pub(super) fn step(
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
        Some(0) => step_on::<0>,
        Some(1) => step_on::<1>,
        Some(2) => step_on::<2>,
        _ => step_on::<3>,
    };
    run(field, stagger, vel, dt, trace, band, out, range)
}

/// [`step`] for a field on the faces of axis `F` (3: cell centres); samples outside `band` are
/// set to zero.
#[allow(clippy::too_many_arguments)]
fn step_on<const F: usize>(
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
