//! The MAC grid's linear solvers: MGPCG pressure (residuals checked independently through
//! `apply`, analytic eigenmodes, singular components, iteration counts against resolution) and
//! implicit diffusion (exact discrete decay of eigenmodes, fixed cells, huge viscosity).

use eddy::grid::{
    solve_diffusion, Boundary, CellKind, DiffusionBoundary, DiffusionSide, PoissonSystem, Side,
    SolveError, SolverSettings,
};
use eddy::Real;
use ndarray::Array3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::PI;

fn settings(tolerance: Real) -> SolverSettings {
    SolverSettings {
        tolerance,
        max_iterations: 100,
    }
}

fn random_field(n: (usize, usize, usize), seed: u64) -> Array3<Real> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    Array3::from_shape_fn(n, |_| rng.random::<Real>() * 2.0 - 1.0)
}

fn norm(v: impl Iterator<Item = Real>) -> Real {
    v.map(|v| v * v).sum::<Real>().sqrt()
}

/// `|rhs - A x| / |rhs|` over the fluid cells, with `A` applied by `PoissonSystem::apply`.
fn relative_residual(
    sys: &PoissonSystem,
    cells: &Array3<CellKind>,
    rhs: &Array3<Real>,
    x: &Array3<Real>,
) -> Real {
    let mut ax = Array3::zeros(x.dim());
    sys.apply(x, &mut ax);
    let fluid = || cells.iter().map(|&c| c == CellKind::Fluid);
    let r = norm(
        fluid()
            .zip(rhs.iter().zip(&ax))
            .filter(|(f, _)| *f)
            .map(|(_, (b, a))| b - a),
    );
    let b = norm(fluid().zip(rhs).filter(|(f, _)| *f).map(|(_, b)| *b));
    r / b
}

/// A ball of `kind` (centre `c`, radius `r`, in cell units) drawn into `cells`.
fn draw_ball(cells: &mut Array3<CellKind>, c: [Real; 3], r: Real, kind: CellKind) {
    for ((i, j, k), cell) in cells.indexed_iter_mut() {
        let d2: Real = [i, j, k]
            .iter()
            .zip(c)
            .map(|(&v, c)| (v as Real + 0.5 - c).powi(2))
            .sum();
        if d2 < r * r {
            *cell = kind;
        }
    }
}

fn assert_zero_outside_fluid(cells: &Array3<CellKind>, x: &Array3<Real>) {
    for (c, v) in cells.iter().zip(x) {
        if *c != CellKind::Fluid {
            assert_eq!(*v, 0.0, "x must be zero outside the fluid");
        }
    }
}

#[test]
fn residual_with_obstacles_open_cells_open_side_and_periodic_axis() {
    let n = (40, 24, 20);
    let mut cells = Array3::from_elem(n, CellKind::Fluid);
    for i in 12..20 {
        for j in 6..14 {
            for k in 6..12 {
                cells[(i, j, k)] = CellKind::Solid;
            }
        }
    }
    for i in 30..34 {
        for j in 0..24 {
            cells[(i, j, 19)] = CellKind::Open;
        }
    }
    let boundary = Boundary {
        periodic: [false, true, false],
        sides: [[Side::Wall, Side::Open], [Side::Wall; 2], [Side::Wall; 2]],
    };
    let mut sys = PoissonSystem::new(&cells, boundary);
    assert_eq!(sys.singular_components(), 0);
    let rhs = random_field(n, 1);
    let mut x = random_field(n, 2); // a non-zero initial guess, with junk outside the fluid
    let tol = 1e-8;
    let stats = sys.solve(&rhs, &mut x, &settings(tol)).expect("converges");
    let res = relative_residual(&sys, &cells, &rhs, &x);
    assert!(res <= tol * 1.001, "residual {res:e}, stats {stats:?}");
    assert!(
        (res - stats.relative_residual).abs() <= 1e-3 * tol,
        "reported {stats:?}, measured {res:e}"
    );
    assert_zero_outside_fluid(&cells, &x);
    // Warm start from the solution: nothing left to do.
    let again = sys.solve(&rhs, &mut x, &settings(tol)).expect("converges");
    assert_eq!(again.iterations, 0);
}

#[test]
fn two_dimensional_periodic_slab() {
    // 64 x 64 x 1, periodic in x and z, wall below, open above, a cylinder in the middle.
    let n = (64, 64, 1);
    let mut cells = Array3::from_elem(n, CellKind::Fluid);
    for ((i, j, _), c) in cells.indexed_iter_mut() {
        if (i as Real + 0.5 - 32.0).powi(2) + (j as Real + 0.5 - 28.0).powi(2) < 100.0 {
            *c = CellKind::Solid;
        }
    }
    let boundary = Boundary {
        periodic: [true, false, true],
        sides: [[Side::Wall; 2], [Side::Wall, Side::Open], [Side::Wall; 2]],
    };
    let mut sys = PoissonSystem::new(&cells, boundary);
    let rhs = random_field(n, 3);
    let mut x = Array3::zeros(n);
    let tol = 1e-6;
    let stats = sys.solve(&rhs, &mut x, &settings(tol)).expect("converges");
    let res = relative_residual(&sys, &cells, &rhs, &x);
    assert!(res <= tol * 1.001, "residual {res:e}, stats {stats:?}");
    assert!(stats.iterations <= 20, "{stats:?}");
    assert_zero_outside_fluid(&cells, &x);
}

/// Solves `A x = lambda x_exact` for a discrete eigenmode and checks that `x_exact` comes back.
fn recover_mode(
    cells: &Array3<CellKind>,
    boundary: Boundary,
    exact: &Array3<Real>,
    lambda: Real,
) -> Real {
    let mut sys = PoissonSystem::new(cells, boundary);
    let rhs = exact.mapv(|v| lambda * v);
    let mut x = Array3::zeros(exact.dim());
    let stats = sys
        .solve(&rhs, &mut x, &settings(1e-10))
        .expect("converges");
    assert!(stats.removed_mean.abs() < 1e-12, "{stats:?}");
    norm(x.iter().zip(exact).map(|(a, b)| a - b)) / norm(exact.iter().copied())
}

#[test]
fn manufactured_dirichlet_modes_are_recovered() {
    // Open sides: ghost cells at i = -1 and i = n hold zero, so sin(pi m (i + 1) / (n + 1)) is an
    // eigenvector with eigenvalue 2 - 2 cos(pi m / (n + 1)) along each axis.
    let n = [30usize, 22, 17];
    let m = [2.0, 1.0, 3.0];
    let exact = Array3::from_shape_fn((n[0], n[1], n[2]), |(i, j, k)| {
        [i, j, k]
            .iter()
            .zip(n)
            .zip(m)
            .map(|((&c, n), m)| (PI * m * (c + 1) as Real / (n + 1) as Real).sin())
            .product()
    });
    let lambda: Real = n
        .iter()
        .zip(m)
        .map(|(&n, m)| 2.0 - 2.0 * (PI * m / (n + 1) as Real).cos())
        .sum();
    let cells = Array3::from_elem(exact.dim(), CellKind::Fluid);
    let boundary = Boundary {
        periodic: [false; 3],
        sides: [[Side::Open; 2]; 3],
    };
    let err = recover_mode(&cells, boundary, &exact, lambda);
    assert!(err < 1e-8, "relative error {err:e}");
}

#[test]
fn manufactured_periodic_modes_are_recovered() {
    // Fully periodic (singular, zero-mean modes): cos(2 pi m i / n) has eigenvalue
    // 2 - 2 cos(2 pi m / n) along each axis.
    let n = [24usize, 20, 15];
    let m = [1.0, 3.0, 2.0];
    let exact = Array3::from_shape_fn((n[0], n[1], n[2]), |(i, j, k)| {
        [i, j, k]
            .iter()
            .zip(n)
            .zip(m)
            .map(|((&c, n), m)| (2.0 * PI * m * c as Real / n as Real + 0.3).cos())
            .product()
    });
    let lambda: Real = n
        .iter()
        .zip(m)
        .map(|(&n, m)| 2.0 - 2.0 * (2.0 * PI * m / n as Real).cos())
        .sum();
    let cells = Array3::from_elem(exact.dim(), CellKind::Fluid);
    let boundary = Boundary {
        periodic: [true; 3],
        sides: [[Side::Wall; 2]; 3],
    };
    let err = recover_mode(&cells, boundary, &exact, lambda);
    assert!(err < 1e-8, "relative error {err:e}");
}

#[test]
fn closed_box_removes_the_incompatible_mean() {
    let n = (20, 18, 16);
    let mut cells = Array3::from_elem(n, CellKind::Fluid);
    draw_ball(&mut cells, [10.0, 9.0, 8.0], 4.0, CellKind::Solid);
    let rhs = random_field(n, 4).mapv(|v| v + 0.25);
    let fluid: Vec<bool> = cells.iter().map(|&c| c == CellKind::Fluid).collect();
    let count = fluid.iter().filter(|&&f| f).count() as Real;
    let mean = rhs
        .iter()
        .zip(&fluid)
        .filter(|(_, &f)| f)
        .map(|(v, _)| v)
        .sum::<Real>()
        / count;
    let mut sys = PoissonSystem::new(&cells, Boundary::closed());
    let mut x = Array3::zeros(n);
    let tol = 1e-7;
    let stats = sys.solve(&rhs, &mut x, &settings(tol)).expect("converges");
    assert_eq!(stats.singular_components, 1);
    assert!(
        (stats.removed_mean - mean).abs() < 1e-12,
        "{stats:?} vs mean {mean}"
    );
    let x_mean = x
        .iter()
        .zip(&fluid)
        .filter(|(_, &f)| f)
        .map(|(v, _)| v)
        .sum::<Real>()
        / count;
    let x_max = x.iter().fold(0.0 as Real, |m, v| m.max(v.abs()));
    assert!(x_mean.abs() < 1e-12 * x_max, "solution mean {x_mean:e}");
    let compatible = rhs.mapv(|v| v - mean);
    let res = relative_residual(&sys, &cells, &compatible, &x);
    assert!(res <= tol * 1.001, "residual {res:e}");
}

#[test]
fn enclosed_pocket_is_solved_for_zero_mean() {
    // A solid spherical shell holds a fluid pocket that touches no open cell; the fluid around
    // it drains through the open top side.
    let n = (24, 24, 24);
    let mut cells = Array3::from_elem(n, CellKind::Fluid);
    draw_ball(&mut cells, [12.0; 3], 8.0, CellKind::Solid);
    draw_ball(&mut cells, [12.0; 3], 5.5, CellKind::Fluid);
    let pocket = |i: usize, j: usize, k: usize| {
        [i, j, k]
            .iter()
            .map(|&v| (v as Real + 0.5 - 12.0).powi(2))
            .sum::<Real>()
            < 5.5 * 5.5
    };
    let boundary = Boundary {
        periodic: [false; 3],
        sides: [[Side::Wall; 2], [Side::Wall; 2], [Side::Wall, Side::Open]],
    };
    let mut sys = PoissonSystem::new(&cells, boundary);
    assert_eq!(sys.singular_components(), 1);
    let rhs = random_field(n, 5).mapv(|v| v + 1.0);
    let (mut sum, mut count) = (0.0, 0.0);
    for ((i, j, k), v) in rhs.indexed_iter() {
        if pocket(i, j, k) {
            sum += v;
            count += 1.0;
        }
    }
    let pocket_mean = sum / count;
    let mut x = Array3::zeros(n);
    let tol = 1e-8;
    let stats = sys.solve(&rhs, &mut x, &settings(tol)).expect("converges");
    assert!(
        (stats.removed_mean - pocket_mean).abs() < 1e-12,
        "{stats:?}"
    );
    let x_pocket: Real = x
        .indexed_iter()
        .filter(|((i, j, k), _)| pocket(*i, *j, *k))
        .map(|(_, v)| v)
        .sum();
    assert!(
        x_pocket.abs() / count < 1e-12,
        "pocket mean {:e}",
        x_pocket / count
    );
    let compatible = Array3::from_shape_fn(n, |(i, j, k)| {
        rhs[(i, j, k)] - if pocket(i, j, k) { pocket_mean } else { 0.0 }
    });
    let res = relative_residual(&sys, &cells, &compatible, &x);
    assert!(res <= tol * 1.001, "residual {res:e}");
}

/// A closed box of side `n` with a solid sphere of radius n / 4 in the middle.
fn sphere_box(n: usize) -> Array3<CellKind> {
    let mut cells = Array3::from_elem((n, n, n), CellKind::Fluid);
    let c = n as Real / 2.0;
    draw_ball(&mut cells, [c; 3], n as Real / 4.0, CellKind::Solid);
    cells
}

#[test]
fn iteration_count_nearly_flat_from_32_to_128_cubed() {
    let tol = 1e-6;
    let mut iterations = Vec::new();
    for n in [32, 128] {
        let cells = sphere_box(n);
        let mut sys = PoissonSystem::new(&cells, Boundary::closed());
        let rhs = random_field((n, n, n), 6);
        let mut x = Array3::zeros((n, n, n));
        let stats = sys.solve(&rhs, &mut x, &settings(tol)).expect("converges");
        let mean = stats.removed_mean;
        let compatible = rhs.mapv(|v| v - mean);
        let res = relative_residual(&sys, &cells, &compatible, &x);
        assert!(res <= tol * 1.001, "{n}^3: residual {res:e}");
        iterations.push(stats.iterations);
    }
    let (coarse, fine) = (iterations[0], iterations[1]);
    assert!(
        fine < 2 * coarse,
        "iterations {coarse} at 32^3, {fine} at 128^3"
    );
    assert!(
        fine <= 20,
        "the project target is at most 20 iterations at 128^3, got {fine}"
    );
}

#[test]
fn bad_input_gives_errors() {
    let cells = Array3::from_elem((6, 5, 4), CellKind::Fluid);
    let mut sys = PoissonSystem::new(&cells, Boundary::closed());
    let mut x = Array3::zeros((6, 5, 4));
    let wrong = Array3::zeros((6, 5, 3));
    assert!(matches!(
        sys.solve(&wrong, &mut x, &settings(1e-6)),
        Err(SolveError::ShapeMismatch { .. })
    ));
    let mut rhs = random_field((6, 5, 4), 7);
    rhs[(1, 2, 3)] = Real::NAN;
    assert!(matches!(
        sys.solve(&rhs, &mut x, &settings(1e-6)),
        Err(SolveError::NonFinite {
            cell: [1, 2, 3],
            ..
        })
    ));
    let rhs = random_field((6, 5, 4), 8);
    assert!(matches!(
        sys.solve(&rhs, &mut x, &settings(0.0)),
        Err(SolveError::InvalidParameter { .. })
    ));
    let few = SolverSettings {
        tolerance: 1e-12,
        max_iterations: 1,
    };
    assert!(matches!(
        sys.solve(&rhs, &mut x, &few),
        Err(SolveError::NotConverged { iterations: 1, .. })
    ));
    let unknown = Array3::from_elem((6, 5, 4), true);
    let b = DiffusionBoundary {
        periodic: [false; 3],
        sides: [[DiffusionSide::Neumann; 2]; 3],
    };
    let mut v = random_field((6, 5, 4), 9);
    assert!(matches!(
        solve_diffusion(&unknown, &b, -1.0, &mut v, &settings(1e-6)),
        Err(SolveError::InvalidParameter { .. })
    ));
}

/// `(1 + a L) x - x_old` and the right-hand side `x_old + a * (fixed neighbours)`, evaluated
/// cell by cell with ghosts per side, independently of the solver.
fn diffusion_residual(
    unknown: &Array3<bool>,
    b: &DiffusionBoundary,
    a: Real,
    old: &Array3<Real>,
    x: &Array3<Real>,
) -> (Real, Real) {
    let d = x.dim();
    let n = [d.0, d.1, d.2];
    let (mut r2, mut b2) = (0.0, 0.0);
    for ((i, j, k), &u) in unknown.indexed_iter() {
        if !u {
            continue;
        }
        let c = [i, j, k];
        let (mut lap, mut fixed) = (0.0, 0.0);
        for axis in 0..3 {
            for (side, delta) in [(0, -1i64), (1, 1)] {
                let t = c[axis] as i64 + delta;
                let mut nb = c;
                let value = if t >= 0 && t < n[axis] as i64 {
                    nb[axis] = t as usize;
                    x[(nb[0], nb[1], nb[2])]
                } else if b.periodic[axis] {
                    nb[axis] = t.rem_euclid(n[axis] as i64) as usize;
                    x[(nb[0], nb[1], nb[2])]
                } else {
                    match b.sides[axis][side] {
                        DiffusionSide::Neumann => x[(i, j, k)],
                        DiffusionSide::Mirror => -x[(i, j, k)],
                    }
                };
                lap += x[(i, j, k)] - value;
                if nb != c && !unknown[(nb[0], nb[1], nb[2])] {
                    fixed += x[(nb[0], nb[1], nb[2])];
                }
            }
        }
        r2 += (x[(i, j, k)] + a * lap - old[(i, j, k)]).powi(2);
        b2 += (old[(i, j, k)] + a * fixed).powi(2);
    }
    (r2.sqrt(), b2.sqrt())
}

#[test]
fn diffusion_of_a_sine_mode_decays_by_the_exact_discrete_factor() {
    // Periodic in x: cos(2 pi m i / n); mirror walls in y: sin(pi m (j + 1/2) / n) (zero half a
    // cell outside); Neumann in z: cos(pi m (k + 1/2) / n). Each has eigenvalue
    // 2 - 2 cos(theta) of L, so one backward Euler step multiplies it by 1 / (1 + a lambda).
    let n = [32usize, 24, 20];
    let mode = Array3::from_shape_fn((n[0], n[1], n[2]), |(i, j, k)| {
        (2.0 * PI * 2.0 * i as Real / 32.0).cos()
            * (PI * (j as Real + 0.5) / 24.0).sin()
            * (PI * 3.0 * (k as Real + 0.5) / 20.0).cos()
    });
    let lambda = (2.0 - 2.0 * (2.0 * PI * 2.0 / 32.0).cos())
        + (2.0 - 2.0 * (PI / 24.0).cos())
        + (2.0 - 2.0 * (PI * 3.0 / 20.0).cos());
    let boundary = DiffusionBoundary {
        periodic: [true, false, false],
        sides: [
            [DiffusionSide::Neumann; 2],
            [DiffusionSide::Mirror; 2],
            [DiffusionSide::Neumann; 2],
        ],
    };
    let unknown = Array3::from_elem(mode.dim(), true);
    for a in [1e-2, 1.0, 1e4] {
        let mut x = mode.clone();
        let stats =
            solve_diffusion(&unknown, &boundary, a, &mut x, &settings(1e-12)).expect("converges");
        let expected = mode.mapv(|v| v / (1.0 + a * lambda));
        let err =
            norm(x.iter().zip(&expected).map(|(x, e)| x - e)) / norm(expected.iter().copied());
        assert!(err < 1e-7, "a = {a}: relative error {err:e}, {stats:?}");
    }
}

#[test]
fn diffusion_keeps_fixed_cells_and_solves_the_system() {
    let n = (20, 16, 12);
    let mut rng = ChaCha8Rng::seed_from_u64(10);
    let unknown = Array3::from_shape_fn(n, |_| rng.random::<Real>() < 0.9);
    let boundary = DiffusionBoundary {
        periodic: [false, false, true],
        sides: [
            [DiffusionSide::Mirror, DiffusionSide::Neumann],
            [DiffusionSide::Neumann, DiffusionSide::Mirror],
            [DiffusionSide::Neumann; 2],
        ],
    };
    let old = random_field(n, 11);
    let tol = 1e-9;
    for a in [3.0, 1e4] {
        let mut x = old.clone();
        let stats =
            solve_diffusion(&unknown, &boundary, a, &mut x, &settings(tol)).expect("converges");
        for ((u, x), o) in unknown.iter().zip(&x).zip(&old) {
            if !u {
                assert_eq!(x.to_bits(), o.to_bits(), "a fixed cell changed");
            }
        }
        let (r, b) = diffusion_residual(&unknown, &boundary, a, &old, &x);
        assert!(
            r <= tol * b * 1.001,
            "a = {a}: residual {:e}, {stats:?}",
            r / b
        );
    }
}

#[test]
fn diffusion_converges_for_huge_viscosity_around_an_obstacle() {
    let n = 48;
    let cells = sphere_box(n);
    let unknown = cells.map(|&c| c == CellKind::Fluid);
    // Solid velocity 0.5 inside the sphere, no-slip mirror walls outside the box.
    let old = Array3::from_shape_fn((n, n, n), |idx| if unknown[idx] { 1.0 } else { 0.5 });
    let boundary = DiffusionBoundary {
        periodic: [false; 3],
        sides: [[DiffusionSide::Mirror; 2]; 3],
    };
    let tol = 1e-6;
    let mut x = old.clone();
    let stats =
        solve_diffusion(&unknown, &boundary, 1e4, &mut x, &settings(tol)).expect("converges");
    assert!(stats.iterations <= 20, "{stats:?}");
    let (r, b) = diffusion_residual(&unknown, &boundary, 1e4, &old, &x);
    assert!(r <= tol * b * 1.001, "residual {:e}", r / b);
    // A maximum principle: the values stay between the wall value 0 and the initial 1.
    assert!(
        x.iter().all(|&v| (0.0..=1.0).contains(&v)),
        "values left [0, 1]"
    );
}

#[test]
fn degenerate_layouts_are_solved() {
    let s = settings(1e-8);
    // No cells at all, and no unknowns at all: nothing to do, x is zero.
    for cells in [
        Array3::from_elem((0, 4, 4), CellKind::Fluid),
        Array3::from_elem((3, 4, 5), CellKind::Solid),
    ] {
        let mut sys = PoissonSystem::new(&cells, Boundary::closed());
        let mut x = Array3::from_elem(cells.dim(), 1.0);
        let stats = sys
            .solve(&Array3::from_elem(cells.dim(), 1.0), &mut x, &s)
            .expect("trivial");
        assert_eq!(stats.iterations, 0);
        assert!(x.iter().all(|&v| v == 0.0));
    }
    // A line of cells with one open end: x_i solves a tridiagonal system; for rhs = e_last the
    // exact solution is x_i = i + 1 (the open ghost at i = -1 holds 0).
    let n = 9;
    let cells = Array3::from_elem((n, 1, 1), CellKind::Fluid);
    let boundary = Boundary {
        periodic: [false; 3],
        sides: [[Side::Open, Side::Wall], [Side::Wall; 2], [Side::Wall; 2]],
    };
    let mut sys = PoissonSystem::new(&cells, boundary);
    let mut rhs = Array3::zeros((n, 1, 1));
    rhs[(n - 1, 0, 0)] = 1.0;
    let mut x = Array3::zeros((n, 1, 1));
    sys.solve(&rhs, &mut x, &s).expect("converges");
    for i in 0..n {
        assert!(
            (x[(i, 0, 0)] - (i + 1) as Real).abs() < 1e-6,
            "x[{i}] = {}",
            x[(i, 0, 0)]
        );
    }
    // One fluid cell walled in by solid: a singular component of one cell; x = 0.
    let mut cells = Array3::from_elem((3, 3, 3), CellKind::Solid);
    cells[(1, 1, 1)] = CellKind::Fluid;
    let mut sys = PoissonSystem::new(&cells, boundary);
    let mut x = Array3::zeros((3, 3, 3));
    let stats = sys
        .solve(&Array3::from_elem((3, 3, 3), 2.0), &mut x, &s)
        .expect("trivial");
    assert_eq!((stats.singular_components, stats.removed_mean), (1, 2.0));
    assert_eq!(x[(1, 1, 1)], 0.0);
}

/// Face weights (the open fractions of cut cells): the weighted operator is symmetric, MGPCG
/// solves it to its tolerance (residual checked through `apply`), a face of weight zero couples
/// nothing, and weights of one half everywhere halve the operator, so the solution doubles.
#[test]
fn weighted_faces_keep_the_operator_symmetric_and_solvable() {
    let n = (24, 20, 16);
    let mut cells = Array3::from_elem(n, CellKind::Fluid);
    draw_ball(&mut cells, [12.0, 10.0, 8.0], 4.0, CellKind::Solid);
    let mut boundary = Boundary::closed();
    boundary.sides[0][1] = Side::Open;
    let len = n.0 * n.1 * n.2;
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let weights: [Vec<f32>; 3] = std::array::from_fn(|_| {
        (0..len)
            .map(|_| match rng.random::<f32>() {
                w if w < 0.1 => 0.0,
                w if w < 0.7 => 1.0,
                w => w,
            })
            .collect()
    });
    let mut sys = PoissonSystem::with_fractions(&cells, boundary, Some(weights));
    let (x, y) = (random_field(n, 1), random_field(n, 2));
    let (mut ax, mut ay) = (Array3::zeros(n), Array3::zeros(n));
    sys.apply(&x, &mut ax);
    sys.apply(&y, &mut ay);
    let fluid = |a: &Array3<Real>, b: &Array3<Real>| {
        a.iter()
            .zip(b)
            .zip(&cells)
            .filter(|(_, &c)| c == CellKind::Fluid)
            .map(|((a, b), _)| a * b)
            .sum::<Real>()
    };
    let (yax, xay) = (fluid(&y, &ax), fluid(&x, &ay));
    assert!((yax - xay).abs() < 1e-12 * yax.abs(), "{yax} vs {xay}");
    let rhs = random_field(n, 3);
    let mut solution = Array3::zeros(n);
    sys.solve(&rhs, &mut solution, &settings(1e-10))
        .expect("converges");
    assert!(relative_residual(&sys, &cells, &rhs, &solution) < 1e-9);

    // Closed: a ghost beyond an open side weighs one whatever the faces inside do.
    let half: [Vec<f32>; 3] = std::array::from_fn(|_| vec![0.5; len]);
    let mut halved = PoissonSystem::with_fractions(&cells, Boundary::closed(), Some(half));
    let mut unit = PoissonSystem::new(&cells, Boundary::closed());
    let (mut xh, mut xu) = (Array3::zeros(n), Array3::zeros(n));
    halved
        .solve(&rhs, &mut xh, &settings(1e-11))
        .expect("converges");
    unit.solve(&rhs, &mut xu, &settings(1e-11))
        .expect("converges");
    let worst = xh
        .iter()
        .zip(&xu)
        .fold(0.0 as Real, |m, (h, u)| m.max((h - 2.0 * u).abs()));
    let scale = xu.iter().fold(0.0 as Real, |m, u| m.max(u.abs()));
    assert!(worst < 1e-8 * scale, "off by {worst:e} of {scale}");
}
