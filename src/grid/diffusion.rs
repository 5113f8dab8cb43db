//! Implicit (backward Euler) diffusion of one velocity component: `(1 + a L) x_new = x_old`,
//! `a = nu dt / dx^2`, solved by the same MGPCG as the pressure with a diagonal shift. The
//! shift makes the matrix definite for every `a >= 0`, and the V-cycle keeps the iteration
//! count bounded from `a ~ 1e-2` (nearly the identity) to `a ~ 1e4` (nearly a Poisson solve).

use super::layout::Layout;
use super::multigrid::Multigrid;
use super::pcg::{self, Workspace};
use super::poisson::{
    check_settings, check_shape, coordinates, finish, SolveError, SolveStats, SolverSettings,
};
use super::stencil::{FineStencil, Problem, DIRICHLET, FLUID};
use crate::Real;
use ndarray::Array3;
use rayon::prelude::*;

/// Condition beyond the array on one side of a non-periodic axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DiffusionSide {
    /// Ghost value equal to the boundary value (no flux).
    Neumann,
    /// Ghost value `-x_i`: a no-slip wall half a cell outside.
    Mirror,
}

/// Periodicity and side conditions of a diffused component.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DiffusionBoundary {
    pub periodic: [bool; 3],
    /// `sides[axis][0 = low, 1 = high]`; ignored on periodic axes.
    pub sides: [[DiffusionSide; 2]; 3],
}

/// Solves `(1 + a L) x_new = x_old` on the cells where `unknown` is true, with `L` the
/// unit-spacing Laplacian of [`super::PoissonSystem::solve`] and `a = nu dt / dx^2 >= 0`.
/// Cells where `unknown` is false hold fixed (Dirichlet) values in `x` and are not changed.
/// Beyond the array, per side: [`DiffusionSide::Neumann`] (ghost = x_i),
/// [`DiffusionSide::Mirror`] (ghost = -x_i), or periodic. `x` is the initial guess too.
/// Builds the system for this one solve; [`DiffusionSystem`] keeps it for the next.
pub fn solve_diffusion(
    unknown: &Array3<bool>,
    boundary: &DiffusionBoundary,
    a: Real,
    x: &mut Array3<Real>,
    settings: &SolverSettings,
) -> Result<SolveStats, SolveError> {
    DiffusionSystem::new(unknown, boundary, a, None)?.solve(x, settings)
}

/// The diffusion system `(1 + a L)` of one set of unknowns, sides and `a`, with its multigrid
/// hierarchy. Building the hierarchy costs about as much as a solve, and the unknowns, sides
/// and `a` stay the same from step to step at a fixed time step around a static (or rigidly
/// spinning, symmetric) obstacle, so a solver keeps the system while [`Self::matches`] holds.
pub struct DiffusionSystem {
    unknown: Array3<bool>,
    boundary: DiffusionBoundary,
    a: Real,
    problem: Problem,
    stencil: FineStencil,
    multigrid: Multigrid,
    work: Workspace,
    /// The unknowns next to fixed cells, with those neighbours and their faces' weights: the
    /// only cells whose right-hand side is not just their old value.
    fixed_neighbours: Vec<(usize, Vec<(usize, f64)>)>,
}

/// Every unknown with fixed (Dirichlet) neighbours, and their indices and face weights in the
/// order the right-hand side adds them (axis by axis, lower neighbour first).
fn fixed_neighbours(problem: &Problem) -> Vec<(usize, Vec<(usize, f64)>)> {
    let layout = problem.layout;
    let weight = |axis: usize, lower: usize| {
        problem
            .weights
            .as_ref()
            .map_or(1.0, |w| f64::from(w[axis][lower]))
    };
    (0..layout.len())
        .filter(|&idx| problem.kinds[idx] == FLUID)
        .filter_map(|idx| {
            let c = coordinates(&layout, idx);
            let fixed: Vec<(usize, f64)> = (0..3)
                .flat_map(|axis| [false, true].map(|up| (axis, up)))
                .filter_map(|(axis, up)| {
                    let mut nb = c;
                    nb[axis] = layout.step(axis, c[axis], up)?;
                    let j = layout.index(nb[0], nb[1], nb[2]);
                    let w = weight(axis, if up { idx } else { j });
                    (problem.kinds[j] == DIRICHLET).then_some((j, w))
                })
                .collect();
            (!fixed.is_empty()).then_some((idx, fixed))
        })
        .collect()
}

impl DiffusionSystem {
    /// The system of [`solve_diffusion`]'s `unknown`, `boundary` and `a`; `weights` scale each
    /// face's term (per axis, the face between each cell and its upper neighbour, flat C
    /// order): the ghost-fluid wall of cut cells, where the face to a fixed value at distance
    /// s dx weighs 1 / s.
    pub fn new(
        unknown: &Array3<bool>,
        boundary: &DiffusionBoundary,
        a: Real,
        weights: Option<[Vec<f32>; 3]>,
    ) -> Result<Self, SolveError> {
        if !(a >= 0.0 && a.is_finite()) {
            return Err(SolveError::InvalidParameter {
                name: "a (nu dt / dx^2)",
                value: a,
                allowed: "finite and not negative",
            });
        }
        let d = unknown.dim();
        let layout = Layout {
            n: [d.0, d.1, d.2],
            periodic: boundary.periodic,
        };
        let kinds: Vec<u8> = unknown
            .iter()
            .map(|&u| if u { FLUID } else { DIRICHLET })
            .collect();
        let side_weight = boundary
            .sides
            .map(|s| s.map(|s| if s == DiffusionSide::Mirror { 2 } else { 0 }));
        let problem = Problem {
            layout,
            kinds,
            side_weight,
            shift: 1.0,
            scale: a,
            weights,
        };
        let dirichlet = problem.dirichlet_table();
        let stencil = FineStencil::new(&problem, &dirichlet);
        let multigrid = Multigrid::new(&problem, &stencil, &dirichlet);
        let fixed_neighbours = fixed_neighbours(&problem);
        Ok(Self {
            unknown: unknown.clone(),
            boundary: *boundary,
            a,
            stencil,
            multigrid,
            work: Workspace::new(layout.len()),
            fixed_neighbours,
            problem,
        })
    }

    /// Whether this is the system of `unknown`, `boundary`, `a` and `weights` (bit for bit).
    pub fn matches(
        &self,
        unknown: &Array3<bool>,
        boundary: &DiffusionBoundary,
        a: Real,
        weights: &Option<[Vec<f32>; 3]>,
    ) -> bool {
        self.a.to_bits() == a.to_bits()
            && self.boundary == *boundary
            && self.unknown == *unknown
            && self.problem.weights == *weights
    }

    /// Solves `(1 + a L) x_new = x_old` as [`solve_diffusion`] does; `x` is the initial guess.
    pub fn solve(
        &mut self,
        x: &mut Array3<Real>,
        settings: &SolverSettings,
    ) -> Result<SolveStats, SolveError> {
        let (problem, layout, a) = (&self.problem, self.problem.layout, self.a);
        check_shape(&layout, "x", x)?;
        check_settings(settings)?;
        let copy: Vec<Real>;
        let old = match x.as_slice() {
            Some(old) => old,
            None => {
                copy = x.iter().copied().collect();
                &copy
            }
        };
        if let Some(idx) = old.iter().position(|v| !v.is_finite()) {
            return Err(SolveError::NonFinite {
                what: "x",
                cell: coordinates(&layout, idx),
            });
        }
        if a == 0.0 {
            return Ok(SolveStats::default());
        }
        let work = &mut self.work;
        // The initial guess x_old on the unknowns (zero elsewhere), and b = x_old + a * (sum
        // of fixed neighbours) there: x_old here (the sum is empty for all but the cells next
        // to fixed ones, and x + a * 0 = x but for the sign of a zero), the fixed neighbours next.
        work.x
            .par_chunks_mut(layout.slab())
            .zip(work.b.par_chunks_mut(layout.slab()))
            .zip(old.par_chunks(layout.slab()))
            .zip(problem.kinds.par_chunks(layout.slab()))
            .for_each(|(((x, b), old), kinds)| {
                for (((x, b), &old), &kind) in x.iter_mut().zip(b).zip(old).zip(kinds) {
                    (*x, *b) = if kind == FLUID {
                        (old, old)
                    } else {
                        (0.0, 0.0)
                    };
                }
            });
        for (cell, neighbours) in &self.fixed_neighbours {
            let fixed = neighbours.iter().fold(0.0, |s, &(j, w)| s + w * old[j]);
            work.b[*cell] = old[*cell] + a * fixed;
        }
        let stats = SolveStats {
            levels: self.multigrid.depth(),
            ..Default::default()
        };
        let b_norm = work.b.iter().map(|v| v * v).sum::<f64>().sqrt();
        let result = if b_norm == 0.0 {
            work.x.fill(0.0);
            Ok(stats)
        } else {
            let o = pcg::solve(
                &self.stencil,
                &mut self.multigrid,
                work,
                b_norm,
                settings.tolerance,
                settings.max_iterations,
            );
            finish(o, stats)
        };
        // A standard-layout array's element iterator walks a slice.
        for ((x, &v), &k) in x.iter_mut().zip(&work.x).zip(&problem.kinds) {
            if k == FLUID {
                *x = v;
            }
        }
        result
    }
}
