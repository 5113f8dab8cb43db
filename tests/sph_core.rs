//! Core SPH building blocks: the cubic-spline kernel, the lattice kernel sum behind the particle
//! mass, and the compact hashed-grid neighbour search, each checked against an independent
//! reference (quadrature, finite differences, brute force).

use eddy::sph::fluid::lattice_kernel_sum;
use eddy::sph::neighbors::{cell_order, permute};
use eddy::sph::{CellGrid, CubicSpline, NeighborLists};
use eddy::{Real, Vec3};
use proptest::prelude::*;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::PI;

// ---------------------------------------------------------------------------------------------
// Helpers
// ---------------------------------------------------------------------------------------------

fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

fn uniform_point(rng: &mut ChaCha8Rng, lo: Real, hi: Real) -> Vec3 {
    Vec3::new(
        rng.random_range(lo..hi),
        rng.random_range(lo..hi),
        rng.random_range(lo..hi),
    )
}

/// A standard normal sample (Box-Muller).
fn gaussian(rng: &mut ChaCha8Rng) -> Real {
    let u1: Real = 1.0 - rng.random::<Real>(); // (0, 1]
    let u2: Real = rng.random();
    (-2.0 * u1.ln()).sqrt() * (2.0 * PI * u2).cos()
}

/// A random direction, uniform on the unit sphere.
fn unit_vector(rng: &mut ChaCha8Rng) -> Vec3 {
    loop {
        let v = uniform_point(rng, -1.0, 1.0);
        let n = v.norm();
        if n > 1e-3 && n <= 1.0 {
            return v / n;
        }
    }
}

/// Composite Simpson rule on [a, b] with `n` (even) intervals.
fn simpson(f: impl Fn(Real) -> Real, a: Real, b: Real, n: usize) -> Real {
    assert!(n.is_multiple_of(2));
    let dx = (b - a) / n as Real;
    let mut s = f(a) + f(b);
    for i in 1..n {
        let w = if i % 2 == 1 { 4.0 } else { 2.0 };
        s += w * f(a + i as Real * dx);
    }
    s * dx / 3.0
}

/// Sorts `points` into cell order and returns them.
fn sorted(mut points: Vec<Vec3>, cell: Real) -> Vec<Vec3> {
    let perm = cell_order(&points, cell);
    assert_is_permutation(&perm, points.len());
    permute(&mut points, &perm);
    points
}

fn assert_is_permutation(perm: &[u32], n: usize) {
    assert_eq!(perm.len(), n, "cell_order returned the wrong length");
    let mut seen = vec![false; n];
    for &p in perm {
        assert!((p as usize) < n, "cell_order index {p} out of range {n}");
        assert!(!seen[p as usize], "cell_order repeats index {p}");
        seen[p as usize] = true;
    }
}

/// Brute-force neighbours of `x` among `targets` (same strict `<` test as the library).
fn brute_near(x: &Vec3, targets: &[Vec3], radius: Real, skip: Option<usize>) -> Vec<u32> {
    let r2 = radius * radius;
    targets
        .iter()
        .enumerate()
        .filter(|&(j, y)| Some(j) != skip && (x - y).norm_squared() < r2)
        .map(|(j, _)| j as u32)
        .collect()
}

/// Builds the neighbour lists of `queries` against `targets` (both already in cell order) and
/// checks every list against brute force. Returns the total number of neighbour pairs found.
fn check_lists(
    queries: &[Vec3],
    targets: &[Vec3],
    cell: Real,
    radius: Real,
    exclude_self: bool,
    what: &str,
) -> usize {
    let qgrid = CellGrid::build(queries, cell);
    let tgrid = CellGrid::build(targets, cell);
    let lists = NeighborLists::build(queries, &qgrid, targets, &tgrid, radius, exclude_self);
    assert_eq!(lists.len(), queries.len(), "{what}: one list per query");
    assert_eq!(lists.offsets.len(), queries.len() + 1, "{what}: offsets");
    assert_eq!(
        *lists.offsets.last().unwrap() as usize,
        lists.indices.len(),
        "{what}: last offset"
    );
    let mut total = 0;
    for (i, xi) in queries.iter().enumerate() {
        let mut got = lists.of(i).to_vec();
        got.sort_unstable();
        let want = brute_near(xi, targets, radius, exclude_self.then_some(i));
        assert_eq!(
            got, want,
            "{what}: neighbours of sorted query {i} at {xi:?} differ from brute force"
        );
        total += want.len();
    }
    total
}

/// Same set for queries and targets, self excluded.
fn check_self(points: Vec<Vec3>, cell: Real, radius: Real, what: &str) -> usize {
    let pts = sorted(points, cell);
    check_lists(&pts, &pts, cell, radius, true, what)
}

// ---------------------------------------------------------------------------------------------
// 1. Kernel
// ---------------------------------------------------------------------------------------------

const SUPPORTS: [Real; 4] = [1.0, 0.1, 0.02, 3.7];

#[test]
fn kernel_radial_integral_is_one() {
    for &h in &SUPPORTS {
        let k = CubicSpline::new(h);
        let f = |r: Real| 4.0 * PI * r * r * k.w(r);
        // Split at the break point h/2, where the polynomial pieces change.
        let total = simpson(f, 0.0, 0.5 * h, 2000) + simpson(f, 0.5 * h, h, 2000);
        assert!(
            (total - 1.0).abs() < 1e-6,
            "h = {h}: radial integral of W is {total}"
        );
        // Nothing beyond the support (starting just past h: see `kernel_w_at_support_is_zero`).
        let tail = simpson(f, h * (1.0 + 1e-12), 2.0 * h, 200);
        assert_eq!(tail, 0.0, "h = {h}: W has mass beyond its support");
    }
}

#[test]
fn kernel_cartesian_integral_is_one() {
    for &h in &[1.0, 0.05] {
        let k = CubicSpline::new(h);
        let n = 100; // cells per axis over [-h, h]
        let dx = 2.0 * h / n as Real;
        let mut sum = 0.0;
        for i in 0..n {
            let x = -h + (i as Real + 0.5) * dx;
            for j in 0..n {
                let y = -h + (j as Real + 0.5) * dx;
                for l in 0..n {
                    let z = -h + (l as Real + 0.5) * dx;
                    sum += k.w((x * x + y * y + z * z).sqrt());
                }
            }
        }
        let total = sum * dx * dx * dx;
        assert!(
            (total - 1.0).abs() < 1e-3,
            "h = {h}: midpoint-grid integral of W is {total}"
        );
    }
}

#[test]
fn kernel_values_at_known_points() {
    let h = 0.3;
    let k = CubicSpline::new(h);
    let norm = 8.0 / (PI * h * h * h);
    assert!((k.w_zero() - norm).abs() <= 1e-12 * norm);
    assert!((k.w(0.0) - k.w_zero()).abs() <= 1e-12 * norm);
    // q = 1/2: 6/8 - 6/4 + 1 = 1/4 from the inside, 2 (1/2)^3 = 1/4 from the outside.
    assert!((k.w(0.5 * h) - 0.25 * norm).abs() <= 1e-12 * norm);
    // q = 3/4: 2 (1/4)^3.
    assert!((k.w(0.75 * h) - 2.0 / 64.0 * norm).abs() <= 1e-12 * norm);
    // Monotonically decreasing on [0, h].
    let mut prev = k.w(0.0);
    for i in 1..=1000 {
        let w = k.w(h * i as Real / 1000.0);
        assert!(
            w < prev || (w == 0.0 && prev == 0.0),
            "W not decreasing at i = {i}"
        );
        assert!(w >= 0.0);
        prev = w;
    }
}

#[test]
fn kernel_gradient_is_antisymmetric() {
    let mut rng = rng(1);
    for &h in &SUPPORTS {
        let k = CubicSpline::new(h);
        for _ in 0..2000 {
            let x = uniform_point(&mut rng, -1.2 * h, 1.2 * h);
            let g = k.grad(&x);
            let gm = k.grad(&(-x));
            assert_eq!(g, -gm, "h = {h}: grad(-x) != -grad(x) at x = {x:?}");
            // Points towards the centre inside the support (W decreases outwards).
            let r = x.norm();
            if r < h && r > 1e-6 * h {
                assert!(g.dot(&x) < 0.0, "h = {h}: gradient not inward at {x:?}");
            }
        }
    }
}

#[test]
fn kernel_has_compact_support() {
    let mut rng = rng(2);
    for &h in &SUPPORTS {
        let k = CubicSpline::new(h);
        assert_eq!(k.support(), h);
        assert_eq!(k.w(h), 0.0, "h = {h}: W(h) = {}", k.w(h));
        for f in [1.0 + 1e-12, 1.001, 1.5, 10.0, 1e6] {
            assert_eq!(k.w(f * h), 0.0, "h = {h}: W({f} h) != 0");
            // (Random directions only off the sphere |x| = h, where rounding of |x| matters.)
            for _ in 0..20 {
                let x = unit_vector(&mut rng) * (f * h);
                assert_eq!(k.grad(&x), Vec3::zeros(), "h = {h}: grad at |x| = {f} h");
            }
        }
        // Exactly on the support along the axes.
        for x in [Vec3::x() * h, -Vec3::y() * h, Vec3::z() * h] {
            assert_eq!(k.grad(&x), Vec3::zeros(), "h = {h}: grad at |x| = h");
        }
        // Strictly positive just inside, with a non-zero gradient.
        for f in [0.999, 0.9999, 1.0 - 1e-6] {
            assert!(k.w(f * h) > 0.0, "h = {h}: W({f} h) not > 0");
            let x = unit_vector(&mut rng) * (f * h);
            assert!(k.grad(&x).norm() > 0.0, "h = {h}: grad at {f} h is zero");
        }
    }
}

/// W cuts off on r >= h exactly like its gradient; a cut on q = r * (1 / h) > 1 once left
/// W(3.7) = 1e-49 for h = 3.7 (regression test).
#[test]
fn kernel_w_at_support_is_zero() {
    let k = CubicSpline::new(3.7);
    assert_eq!(k.w(3.7), 0.0);
}

/// The Hessian quadratic form (the second-order density prediction of IISPH) is the second
/// derivative of W along the direction, by central differences, and W and its gradient from the
/// joint evaluation equal the separate ones exactly.
#[test]
fn kernel_hessian_form_and_joint_evaluation_match() {
    let mut rng = rng(5);
    for &h in &SUPPORTS {
        let k = CubicSpline::new(h);
        let d = 1e-4 * h;
        for _ in 0..3000 {
            let r = rng.random_range(0.02 * h..0.98 * h);
            let x = unit_vector(&mut rng) * r;
            let u = unit_vector(&mut rng) * rng.random_range(0.1..3.0);
            let along = |s: Real| k.w((x + s * u).norm());
            let fd = (along(d) - 2.0 * along(0.0) + along(-d)) / (d * d);
            let form = k.hessian_form(&x, &u);
            // The second derivative jumps at q = 1/2; skip samples whose stencil straddles it.
            if ((x + d * u).norm() - 0.5 * h).abs() < 3.0 * d * u.norm() + 1e-3 * h {
                continue;
            }
            let scale = k.w_zero() / (h * h) * u.norm_squared();
            assert!(
                (form - fd).abs() < 1e-4 * scale,
                "h = {h}: u^T H u = {form:e} vs finite difference {fd:e} at {x:?}, u = {u:?}"
            );
            let (w, g) = k.w_grad(&x);
            assert_eq!(w, k.w(x.norm()));
            assert_eq!(g, k.grad(&x));
        }
        assert_eq!(k.hessian_form(&(Vec3::x() * h), &Vec3::y()), 0.0);
        assert_eq!(k.w_grad(&(Vec3::x() * h)), (0.0, Vec3::zeros()));
    }
}

#[test]
fn kernel_gradient_matches_finite_difference() {
    let mut rng = rng(3);
    for &h in &SUPPORTS {
        let k = CubicSpline::new(h);
        let wf = |x: &Vec3| k.w(x.norm());
        let d = 1e-6 * h;
        let mut checked = 0;
        for _ in 0..3000 {
            let r = rng.random_range(0.02 * h..0.98 * h);
            let x = unit_vector(&mut rng) * r;
            let g = k.grad(&x);
            let mut fd = Vec3::zeros();
            for a in 0..3 {
                let mut e = Vec3::zeros();
                e[a] = d;
                fd[a] = (wf(&(x + e)) - wf(&(x - e))) / (2.0 * d);
            }
            let err = (g - fd).norm() / g.norm();
            assert!(
                err < 1e-5,
                "h = {h}: grad {g:?} vs finite difference {fd:?} at {x:?} (rel. err {err:e})"
            );
            checked += 1;
        }
        assert_eq!(checked, 3000);
    }
}

#[test]
fn kernel_is_c1_at_half_support() {
    for &h in &SUPPORTS {
        let k = CubicSpline::new(h);
        let r0 = 0.5 * h;
        let d = 1e-5 * h;
        // One-sided (second-order) finite differences from each side.
        let left = (3.0 * k.w(r0) - 4.0 * k.w(r0 - d) + k.w(r0 - 2.0 * d)) / (2.0 * d);
        let right = (-3.0 * k.w(r0) + 4.0 * k.w(r0 + d) - k.w(r0 + 2.0 * d)) / (2.0 * d);
        // dW/dr at q = 1/2 is k (18/4 - 6) / h = -1.5 k / h from both pieces.
        let exact = -1.5 * k.w_zero() / h;
        assert!(
            (left - exact).abs() < 1e-6 * exact.abs(),
            "h = {h}: left derivative {left} vs {exact}"
        );
        assert!(
            (right - exact).abs() < 1e-6 * exact.abs(),
            "h = {h}: right derivative {right} vs {exact}"
        );
        // The analytic gradient is continuous across q = 1/2 too.
        let gl = k.grad(&(Vec3::x() * (r0 * (1.0 - 1e-9))));
        let gr = k.grad(&(Vec3::x() * (r0 * (1.0 + 1e-9))));
        assert!(
            (gl.x - exact).abs() < 1e-6 * exact.abs() && (gr.x - exact).abs() < 1e-6 * exact.abs(),
            "h = {h}: grad jumps at q = 1/2: {} vs {} (expected {exact})",
            gl.x,
            gr.x
        );
        // And W itself is continuous.
        assert!((k.w(r0 * (1.0 - 1e-12)) - k.w(r0 * (1.0 + 1e-12))).abs() < 1e-9 * k.w_zero());
    }
}

// ---------------------------------------------------------------------------------------------
// 2. Lattice kernel sum (particle mass choice)
// ---------------------------------------------------------------------------------------------

#[test]
fn lattice_kernel_sum_times_volume_is_near_one() {
    for &spacing in &[1.0, 0.01, 0.025, 0.3] {
        let k = CubicSpline::new(2.0 * spacing);
        let s = lattice_kernel_sum(&k, spacing);
        let v = s * spacing * spacing * spacing;
        assert!(
            (v - 1.0).abs() < 0.01,
            "spacing {spacing}: lattice sum * spacing^3 = {v}"
        );
        // The self term is included and the sum is scale-free.
        assert!(s > k.w_zero());
        let v1 = lattice_kernel_sum(&CubicSpline::new(2.0), 1.0);
        assert!(
            (v - v1).abs() < 1e-9,
            "lattice sum not scale-invariant: {v} vs {v1}"
        );
    }
    // A finer lattice relative to the support converges to the integral even closer.
    let k = CubicSpline::new(1.0);
    let fine = lattice_kernel_sum(&k, 0.1) * 1e-3;
    assert!((fine - 1.0).abs() < 1e-3, "fine lattice sum {fine}");
}

// ---------------------------------------------------------------------------------------------
// 3. Neighbour search against brute force
// ---------------------------------------------------------------------------------------------

#[test]
fn neighbors_uniform_random() {
    let mut rng = rng(10);
    let points: Vec<Vec3> = (0..5000)
        .map(|_| uniform_point(&mut rng, 0.0, 1.0))
        .collect();
    let radius = 0.05;
    // Cell equal to the radius and a cell larger than it.
    let total = check_self(points.clone(), radius, radius, "uniform, cell = r");
    // ~ 5000 * 4/3 pi 0.05^3 * 5000 ≈ 13 000 pairs: make sure the test is not vacuous.
    assert!(total > 5000, "too few pairs: {total}");
    let total2 = check_self(points, 0.08, radius, "uniform, cell = 1.6 r");
    assert_eq!(total, total2);
}

#[test]
fn neighbors_clustered_negative_and_duplicates() {
    let mut rng = rng(11);
    let centers = [
        Vec3::new(-0.7, -0.3, -0.9),
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(0.4, -0.05, 0.6),
        Vec3::new(-3.0, 2.5, -0.01),
    ];
    let mut points = Vec::new();
    for (ci, c) in centers.iter().enumerate() {
        let sigma = 0.01 + 0.01 * ci as Real;
        for _ in 0..400 {
            let d = Vec3::new(gaussian(&mut rng), gaussian(&mut rng), gaussian(&mut rng));
            points.push(c + d * sigma);
        }
    }
    // Outliers, including far-away ones.
    for _ in 0..200 {
        points.push(uniform_point(&mut rng, -4.0, 4.0));
    }
    points.push(Vec3::new(-100.0, 50.0, -25.0));
    points.push(Vec3::new(-100.01, 50.0, -25.0));
    // Signed zeros and points straddling zero.
    points.push(Vec3::new(0.0, -0.0, 0.0));
    points.push(Vec3::new(-0.0, 0.0, -0.0));
    points.push(Vec3::new(-1e-12, 1e-12, -1e-300));
    // Exact duplicates (several copies of some points).
    for i in (0..points.len()).step_by(37) {
        let p = points[i];
        points.push(p);
        if i % 2 == 0 {
            points.push(p);
        }
    }
    let n = points.len();
    // Shuffle so duplicates are not adjacent in input order.
    for i in (1..n).rev() {
        let j = rng.random_range(0..=i);
        points.swap(i, j);
    }
    let total = check_self(points.clone(), 0.05, 0.05, "clustered, cell = r");
    assert!(total > 50_000, "clusters should be dense: {total}");
    check_self(points.clone(), 0.05, 0.03, "clustered, r < cell");
    check_self(points, 0.011, 0.011, "clustered, small cells");
}

#[test]
fn neighbors_points_on_cell_boundaries() {
    for &cell in &[0.1, 0.125, 0.07, 1.0 / 3.0] {
        let spacing = cell / 2.0;
        let mut points = Vec::new();
        for i in -8..=8 {
            for j in -8..=8 {
                for l in -8..=8 {
                    points.push(Vec3::new(
                        i as Real * spacing,
                        j as Real * spacing,
                        l as Real * spacing,
                    ));
                }
            }
        }
        for &radius in &[cell, cell * (1.0 - 1e-9), 0.75 * cell] {
            let what = format!("lattice, cell {cell}, radius {radius}");
            let total = check_self(points.clone(), cell, radius, &what);
            assert!(total > 0, "{what}: no pairs");
        }
    }
}

/// Pairs a, a + gap along one axis with gap just below `radius` and a on, just below or just
/// above a cell face: the cell search must still find every pair closer than `radius`.
fn check_pairs_across_faces(seed: u64, cell: Real, radius: Real) {
    let mut rng = rng(seed);
    let mut points = Vec::new();
    for _ in 0..2000 {
        let n: i64 = rng.random_range(-50..50);
        let face = n as Real * cell;
        let jitter = [0.0, 1e-16, -1e-16, 1e-15, -1e-15][rng.random_range(0..5)];
        let a = face + jitter * cell.max(face.abs());
        let mut gap = radius;
        for _ in 0..rng.random_range(1..4) {
            gap = gap.next_down();
        }
        let axis = rng.random_range(0..3);
        let mut pa = uniform_point(&mut rng, -2.0, 2.0);
        pa[axis] = a;
        let mut pb = pa;
        pb[axis] = a + gap;
        points.push(pa);
        points.push(pb);
    }
    let what = format!("pairs across faces, cell {cell}, radius {radius}");
    let total = check_self(points, cell, radius, &what);
    assert!(total > 1000, "{what}: too few pairs {total}");
}

#[test]
fn neighbors_pairs_just_inside_radius_across_faces() {
    // Radius a hair below the cell size: rounding in the cell index cannot split such pairs.
    for &cell in &[0.1, 0.05, 0.3, 1.0 / 3.0, 0.07] {
        check_pairs_across_faces(12, cell, cell * (1.0 - 1e-12));
    }
}

/// With radius == cell size (how the solver calls it), a pair closer than the radius by a few
/// ulps must not land two cells apart through rounding of x / cell: 0.8999999999999999 * 10
/// rounds to 9.0 while 0.7999999999999999 * 10 stays below 8, yet their distance is
/// 0.09999999999999998 < 0.1 (a regression test for the cell margin in `neighbors`).
#[test]
fn neighbors_radius_equal_to_cell_finds_pairs_a_few_ulps_inside() {
    let cell = 0.1;
    let a = Vec3::new(0.7999999999999999, 0.0, 0.0);
    let b = Vec3::new(0.8999999999999999, 0.0, 0.0);
    assert!((b - a).norm_squared() < cell * cell);
    let pts = sorted(vec![a, b], cell);
    let grid = CellGrid::build(&pts, cell);
    let mut hits = 0;
    grid.for_each_near(&a, &pts, cell, |_| hits += 1);
    assert_eq!(hits, 2, "for_each_near misses the partner");
    check_lists(&pts, &pts, cell, cell, true, "minimal repro");
    for &cell in &[0.1, 0.05, 0.3, 1.0 / 3.0, 0.07] {
        check_pairs_across_faces(12, cell, cell);
    }
}

#[test]
fn neighbors_query_set_differs_from_target_set() {
    let mut rng = rng(13);
    let cell = 0.04;
    let radius = 0.04;
    // Fluid: random points in a box that touches the walls.
    let fluid: Vec<Vec3> = (0..3000)
        .map(|_| uniform_point(&mut rng, 0.0, 0.5))
        .collect();
    // Boundary: two layers of particles on the floor and a wall at x = 0, partly outside (negative).
    let s = 0.02;
    let mut boundary = Vec::new();
    for layer in 0..2 {
        let off = -(layer as Real) * s;
        for i in -2..30 {
            for j in -2..30 {
                boundary.push(Vec3::new(i as Real * s, j as Real * s, off));
                boundary.push(Vec3::new(off, i as Real * s, j as Real * s + 0.01));
            }
        }
    }
    let fluid = sorted(fluid, cell);
    let boundary = sorted(boundary, cell);
    let fb = check_lists(&fluid, &boundary, cell, radius, false, "fluid -> boundary");
    let bf = check_lists(&boundary, &fluid, cell, radius, false, "boundary -> fluid");
    assert!(fb > 1000, "fluid sees too few boundary particles: {fb}");
    // The neighbour relation is symmetric, so both directions count the same pairs.
    assert_eq!(fb, bf);
    // Same set without exclude_self: each point is its own neighbour.
    let ff = check_lists(
        &fluid,
        &fluid,
        cell,
        radius,
        false,
        "fluid -> fluid, self kept",
    );
    let ff_ex = check_lists(&fluid, &fluid, cell, radius, true, "fluid -> fluid");
    assert_eq!(ff, ff_ex + fluid.len());
    // An empty target set.
    let empty: Vec<Vec3> = Vec::new();
    let none = check_lists(&fluid, &empty, cell, radius, false, "fluid -> nothing");
    assert_eq!(none, 0);
    // An empty query set.
    let none = check_lists(
        &empty,
        &boundary,
        cell,
        radius,
        false,
        "nothing -> boundary",
    );
    assert_eq!(none, 0);
}

#[test]
fn for_each_near_matches_brute_force() {
    let mut rng = rng(14);
    let cell = 0.05;
    let mut points: Vec<Vec3> = (0..5000)
        .map(|_| uniform_point(&mut rng, 0.0, 1.0))
        .collect();
    points.extend((0..200).map(|_| uniform_point(&mut rng, -0.5, 0.0)));
    let points = sorted(points, cell);
    let grid = CellGrid::build(&points, cell);
    assert!(grid.cell_count() > 1000);
    let mut found_any = 0;
    for q in 0..3000 {
        let p = if q % 10 == 0 {
            // Queries exactly on cell faces / corners.
            Vec3::new(
                rng.random_range(-10..25) as Real * cell,
                rng.random_range(-10..25) as Real * cell,
                rng.random_range(-10..25) as Real * cell,
            )
        } else {
            uniform_point(&mut rng, -0.6, 1.2)
        };
        for &radius in &[cell, 0.6 * cell] {
            let mut got = Vec::new();
            grid.for_each_near(&p, &points, radius, |j| got.push(j as u32));
            got.sort_unstable();
            let want = brute_near(&p, &points, radius, None);
            assert_eq!(got, want, "for_each_near at {p:?}, radius {radius}");
            found_any += want.len();
        }
    }
    assert!(found_any > 1000, "too few hits: {found_any}");
}

// ---------------------------------------------------------------------------------------------
// 4. Property test
// ---------------------------------------------------------------------------------------------

fn point_strategy() -> impl Strategy<Value = Vec3> {
    (-1.0..=1.0f64, -1.0..=1.0f64, -1.0..=1.0f64).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

/// Small point sets, with some exact duplicates mixed in.
fn cloud_strategy() -> impl Strategy<Value = Vec<Vec3>> {
    (
        prop::collection::vec(point_strategy(), 0..200),
        prop::collection::vec(any::<prop::sample::Index>(), 0..20),
    )
        .prop_map(|(mut pts, dups)| {
            if !pts.is_empty() {
                for d in dups {
                    let p = pts[d.index(pts.len())];
                    pts.push(p);
                }
            }
            pts
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn prop_neighbor_lists_equal_brute_force(
        points in cloud_strategy(),
        radius in 0.02..0.6f64,
        cell_factor in 1.0..2.0f64,
    ) {
        let cell = radius * cell_factor;
        check_self(points, cell, radius, "proptest self");
    }

    #[test]
    fn prop_cross_lists_equal_brute_force(
        queries in prop::collection::vec(point_strategy(), 0..100),
        targets in prop::collection::vec(point_strategy(), 0..100),
        radius in 0.05..0.8f64,
    ) {
        let queries = sorted(queries, radius);
        let targets = sorted(targets, radius);
        check_lists(&queries, &targets, radius, radius, false, "proptest cross");
    }
}
