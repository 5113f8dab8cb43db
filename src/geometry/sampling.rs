//! Surface samples for Akinci et al. 2012 boundary particles.
//!
//! The SPH code gives every sample the volume 1 / sum_k W_bk, so mild unevenness is corrected
//! for, but a hole lets fluid through and a clump wastes work. The lattice samplers therefore
//! divide lengths into `ceil(length / spacing)` equal parts (steps at most `spacing`, more than
//! half of it) and place each shared point (box edges, cylinder rims) exactly once; spheres use
//! a Fibonacci lattice, and mesh samples are thinned of near-duplicates.

use std::collections::HashMap;
use std::f64::consts::PI;

use crate::{Point3, Real, Vec3};

/// Number of equal parts of at most `spacing` that cover `length`; the small tolerance keeps an
/// exact multiple (1.0 / 0.02) from gaining a part to rounding.
pub(crate) fn parts(length: Real, spacing: Real) -> usize {
    ((length / spacing) * (1.0 - 1e-9)).ceil().max(1.0) as usize
}

/// The `i`-th of `n + 1` evenly spaced values from `a` to `b`, hitting both ends exactly.
fn lerp(a: Real, b: Real, i: usize, n: usize) -> Real {
    if i == n {
        b
    } else {
        a + (b - a) * (i as Real / n as Real)
    }
}

/// Lattice points on the surface of the box `[-h, h]`: a grid of at most `spacing` on every
/// face, edges and corners once.
pub(crate) fn sample_box(h: &Vec3, spacing: Real) -> Vec<Point3> {
    let n = h.map(|hi| parts(2.0 * hi, spacing));
    let coord = |axis: usize, i: usize| lerp(-h[axis], h[axis], i, n[axis]);
    let mut out = Vec::new();
    for i in 0..=n.x {
        for j in 0..=n.y {
            let on_side = i == 0 || i == n.x || j == 0 || j == n.y;
            // Inside the x/y outline only the two z faces are surface.
            let k_step = if on_side { 1 } else { n.z };
            out.extend(
                (0..=n.z)
                    .step_by(k_step)
                    .map(|k| Point3::new(coord(0, i), coord(1, j), coord(2, k))),
            );
        }
    }
    out
}

/// Points on the faces of the box `[-h, h]` grown by `offset` > 0, each face a grid whose
/// columns continue those of a lattice filling the box from half a step inside its faces (the
/// steps as [`sample_box`] divides the edges), with the columns that still fall on the grown
/// face added around it. A fluid lattice inside the box thus sees its mirror image on every
/// face (the boundary's mirror layer) with no misalignment.
pub(crate) fn sample_box_shell(h: &Vec3, offset: Real, spacing: Real) -> Vec<Point3> {
    let columns = |axis: usize| -> Vec<Real> {
        let n = parts(2.0 * h[axis], spacing);
        let step = 2.0 * h[axis] / n as Real;
        let extra = ((offset / step) + 0.5 + 1e-9).floor() as i64;
        (-extra..n as i64 + extra)
            .map(|k| -h[axis] + (k as Real + 0.5) * step)
            .collect()
    };
    let cols: Vec<Vec<Real>> = (0..3).map(columns).collect();
    let mut out = Vec::new();
    for a in 0..3 {
        let (b, c) = ((a + 1) % 3, (a + 2) % 3);
        for side in [-1.0, 1.0] {
            for &u in &cols[b] {
                for &w in &cols[c] {
                    let mut p = Point3::origin();
                    p[a] = side * (h[a] + offset);
                    p[b] = u;
                    p[c] = w;
                    out.push(p);
                }
            }
        }
    }
    out
}

/// Appends a circle of radius `radius` about the y axis at height `y`, with steps of at most
/// `spacing`, turned by `phase` steps (0.5 staggers it against its neighbour rings). A circle of
/// radius 0 (up to rounding, as at the pole of an arc) is its centre.
fn ring(radius: Real, y: Real, spacing: Real, phase: Real, out: &mut Vec<Point3>) {
    if radius < 1e-9 * spacing {
        out.push(Point3::new(0.0, y, 0.0));
        return;
    }
    let m = parts(2.0 * PI * radius, spacing);
    out.extend((0..m).map(|i| {
        let a = 2.0 * PI * (i as Real + phase) / m as Real;
        Point3::new(radius * a.cos(), y, radius * a.sin())
    }));
}

/// A piece of the profile of a surface of revolution about the y axis: `at(u)` gives
/// (radius, height) for u in [0, 1], and `length` its arc length.
pub(crate) struct Piece {
    length: Real,
    at: Box<dyn Fn(Real) -> (Real, Real)>,
}

impl Piece {
    /// The straight profile from `a` to `b`, each (radius, height); the ends are hit exactly.
    pub(crate) fn line(a: (Real, Real), b: (Real, Real)) -> Self {
        Piece {
            length: (b.0 - a.0).hypot(b.1 - a.1),
            at: Box::new(move |u| (a.0 * (1.0 - u) + b.0 * u, a.1 * (1.0 - u) + b.1 * u)),
        }
    }

    /// A circular arc of radius `r` about the point (0, `centre_y`), from polar angle `from` to
    /// `to` (radians from +y).
    pub(crate) fn arc(r: Real, centre_y: Real, from: Real, to: Real) -> Self {
        Piece {
            length: r * (to - from).abs(),
            at: Box::new(move |u| {
                let angle = from + (to - from) * u;
                (r * angle.sin().abs(), centre_y + r * angle.cos())
            }),
        }
    }
}

/// Samples the surface of revolution whose profile runs through `pieces` end to end: rings at
/// most `spacing` apart along the profile (junctions once), each with steps of at most
/// `spacing`, alternate rings staggered. Ends of the profile on the axis become single points.
pub(crate) fn revolve(pieces: &[Piece], spacing: Real) -> Vec<Point3> {
    let mut out = Vec::new();
    let mut k = 0;
    for (p, piece) in pieces.iter().filter(|p| p.length > 0.0).enumerate() {
        let n = parts(piece.length, spacing);
        // Each piece starts where the previous one ended.
        for j in usize::from(p > 0)..=n {
            let (radius, y) = (piece.at)(j as Real / n as Real);
            ring(radius, y, spacing, 0.5 * (k % 2) as Real, &mut out);
            k += 1;
        }
    }
    out
}

/// Appends a Fibonacci lattice of round(4 pi r^2 / spacing^2) points on the sphere of radius
/// `radius`, so each point stands for about spacing^2 of surface.
pub(crate) fn fibonacci_sphere(radius: Real, spacing: Real) -> Vec<Point3> {
    let area = 4.0 * PI * radius * radius;
    let n = (area / (spacing * spacing)).round().max(1.0) as usize;
    let golden_angle = PI * (3.0 - Real::sqrt(5.0));
    (0..n)
        .map(|i| {
            // Equal-area bands in y (Archimedes), each point at the middle of its band.
            let y = 1.0 - 2.0 * (i as Real + 0.5) / n as Real;
            let rho = (1.0 - y * y).max(0.0).sqrt();
            let a = golden_angle * i as Real;
            Point3::new(radius * rho * a.cos(), radius * y, radius * rho * a.sin())
        })
        .collect()
}

/// Keeps the points, in order, that lie at least `min_dist` from every point kept before them.
/// Shared mesh edges and sliver triangles produce such near-duplicates.
pub(crate) fn thin(points: Vec<Point3>, min_dist: Real) -> Vec<Point3> {
    let cell_of = |p: &Point3| p.coords.map(|c| (c / min_dist).floor() as i64);
    let mut grid: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
    let mut kept: Vec<Point3> = Vec::with_capacity(points.len());
    let min_dist2 = min_dist * min_dist;
    for p in points {
        let c = cell_of(&p);
        let mut neighbours = (-1..=1).flat_map(|dx| {
            (-1..=1).flat_map(move |dy| (-1..=1).map(move |dz| [c.x + dx, c.y + dy, c.z + dz]))
        });
        let crowded = neighbours.any(|key| {
            grid.get(&key).is_some_and(|ids| {
                ids.iter()
                    .any(|&i| (kept[i] - p).norm_squared() < min_dist2)
            })
        });
        if !crowded {
            grid.entry([c.x, c.y, c.z]).or_default().push(kept.len());
            kept.push(p);
        }
    }
    kept
}
