//! The pressure Poisson system of the MAC grid and its MGPCG solver (McAdams, Sifakis, Teran
//! 2010, "A parallel multigrid Poisson solver for fluids simulation on large grids").
//!
//! The matrix is the unit-spacing 7-point Laplacian with the positive semi-definite sign on the
//! fluid cells (see [`PoissonSystem::solve`]); it is never stored: the fine level packs one byte
//! per cell ([`super::stencil`]). CG runs in f64, preconditioned by one f32 multigrid V-cycle per
//! iteration ([`super::multigrid`]).

use super::components::SingularComponents;
use super::layout::Layout;
use super::multigrid::Multigrid;
use super::pcg::{self, Workspace};
use super::stencil::{FineStencil, Problem, DIRICHLET, FLUID, SOLID};
use crate::Real;
use ndarray::Array3;
use rayon::prelude::*;

pub use super::diffusion::{solve_diffusion, DiffusionBoundary, DiffusionSide};

/// What a cell is to the pressure solve.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum CellKind {
    Fluid,
    Solid,
    /// Pressure held at zero (free surface, outflow).
    Open,
}

/// Condition beyond the grid on one side of a non-periodic axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// No flux (homogeneous Neumann).
    Wall,
    /// A ghost cell held at zero pressure.
    Open,
}

/// Periodicity and side conditions of the grid.
#[derive(Clone, Copy, Debug)]
pub struct Boundary {
    pub periodic: [bool; 3],
    /// `sides[axis][0 = low, 1 = high]`; ignored on periodic axes.
    pub sides: [[Side; 2]; 3],
}

impl Boundary {
    /// A closed box: no periodic axis, walls on every side.
    pub fn closed() -> Self {
        Self {
            periodic: [false; 3],
            sides: [[Side::Wall; 2]; 3],
        }
    }
}

/// When to stop iterating.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolverSettings {
    /// Relative residual `|b - A x| / |b|` to reach.
    pub tolerance: Real,
    pub max_iterations: usize,
}

impl Default for SolverSettings {
    fn default() -> Self {
        Self {
            tolerance: 1e-6,
            max_iterations: 200,
        }
    }
}

/// What a solve did.
#[derive(Clone, Copy, Debug, Default)]
pub struct SolveStats {
    /// CG iterations (one V-cycle each).
    pub iterations: usize,
    /// `|b - A x| / |b|` at exit, with `b` the right-hand side after mean removal.
    pub relative_residual: Real,
    /// Fluid components without Dirichlet contact (singular, solved for zero mean).
    pub singular_components: usize,
    /// The largest (by magnitude) mean removed from the right-hand side over a singular
    /// component: the incompatibility of the data there (e.g. net inflow into a closed box).
    pub removed_mean: Real,
    /// Multigrid levels, the finest included.
    pub levels: usize,
}

/// Why a solve failed.
#[derive(Debug, thiserror::Error)]
pub enum SolveError {
    #[error("{what} has shape {found:?} but the cell layout is {expected:?}")]
    ShapeMismatch {
        what: &'static str,
        expected: [usize; 3],
        found: [usize; 3],
    },
    #[error("{what} is not finite at cell {cell:?}")]
    NonFinite {
        what: &'static str,
        cell: [usize; 3],
    },
    #[error("{name} = {value} is out of range: {allowed}")]
    InvalidParameter {
        name: &'static str,
        value: Real,
        allowed: &'static str,
    },
    #[error(
        "no convergence: relative residual {relative_residual:e} after {iterations} iterations"
    )]
    NotConverged {
        iterations: usize,
        relative_residual: Real,
    },
    #[error("the iteration produced a non-finite value after {iterations} iterations")]
    Breakdown { iterations: usize },
}

fn shape(a: &Array3<impl Sized>) -> [usize; 3] {
    let d = a.dim();
    [d.0, d.1, d.2]
}

/// Checks that `a` has the layout's shape.
pub(crate) fn check_shape(
    l: &Layout,
    what: &'static str,
    a: &Array3<impl Sized>,
) -> Result<(), SolveError> {
    if shape(a) == l.n {
        Ok(())
    } else {
        Err(SolveError::ShapeMismatch {
            what,
            expected: l.n,
            found: shape(a),
        })
    }
}

/// The cell `[i, j, k]` of flat index `idx`.
pub(crate) fn coordinates(l: &Layout, idx: usize) -> [usize; 3] {
    let (ij, k) = (idx / l.n[2], idx % l.n[2]);
    [ij / l.n[1], ij % l.n[1], k]
}

/// Copies `src` into `dst` on the unknowns (zero elsewhere), checking finiteness there.
pub(crate) fn load(
    l: &Layout,
    what: &'static str,
    src: &Array3<Real>,
    unknown: impl Fn(usize) -> bool + Sync,
    dst: &mut [f64],
) -> Result<(), SolveError> {
    match src.as_slice() {
        Some(src) => dst
            .par_chunks_mut(l.slab())
            .zip(src.par_chunks(l.slab()))
            .enumerate()
            .for_each(|(i, (d, s))| copy_masked(i * l.slab(), d, s.iter(), &unknown)),
        None => copy_masked(0, dst, src.iter(), &unknown),
    }
    match dst.iter().position(|v| !v.is_finite()) {
        Some(idx) => Err(SolveError::NonFinite {
            what,
            cell: coordinates(l, idx),
        }),
        None => Ok(()),
    }
}

/// `dst[i] = src[i]` where `unknown(offset + i)`, else 0.
fn copy_masked<'a>(
    offset: usize,
    dst: &mut [f64],
    src: impl Iterator<Item = &'a Real>,
    unknown: &impl Fn(usize) -> bool,
) {
    for (idx, (d, &s)) in (offset..).zip(dst.iter_mut().zip(src)) {
        *d = if unknown(idx) { s } else { 0.0 };
    }
}

/// Copies `src` into `dst` (same shape as the layout).
pub(crate) fn store(l: &Layout, src: &[f64], dst: &mut Array3<Real>) {
    match dst.as_slice_mut() {
        Some(d) => d
            .par_chunks_mut(l.slab())
            .zip(src.par_chunks(l.slab()))
            .for_each(|(d, s)| d.copy_from_slice(s)),
        None => dst.iter_mut().zip(src).for_each(|(d, &s)| *d = s),
    }
}

/// Checks the settings.
pub(crate) fn check_settings(s: &SolverSettings) -> Result<(), SolveError> {
    if s.tolerance > 0.0 && s.tolerance.is_finite() {
        Ok(())
    } else {
        Err(SolveError::InvalidParameter {
            name: "tolerance",
            value: s.tolerance,
            allowed: "a positive finite relative residual",
        })
    }
}

/// Turns a CG outcome into stats or an error.
pub(crate) fn finish(o: pcg::Outcome, stats: SolveStats) -> Result<SolveStats, SolveError> {
    let stats = SolveStats {
        iterations: o.iterations,
        relative_residual: o.relative_residual,
        ..stats
    };
    if o.non_finite {
        Err(SolveError::Breakdown {
            iterations: o.iterations,
        })
    } else if o.converged {
        Ok(stats)
    } else {
        Err(SolveError::NotConverged {
            iterations: o.iterations,
            relative_residual: o.relative_residual,
        })
    }
}

/// The pressure Poisson system on one cell layout; build once per step (cells may change when
/// obstacles move), reuse the multigrid hierarchy inside.
pub struct PoissonSystem {
    stencil: FineStencil,
    multigrid: Multigrid,
    singular: SingularComponents,
    work: Workspace,
}

/// The fluid's share of every face inside the grid, for cut cells: per axis, the open fraction
/// of the face between each cell and its upper neighbour (flat C order over the cells).
pub type FaceFractions = [Vec<f32>; 3];

impl PoissonSystem {
    pub fn new(cells: &Array3<CellKind>, boundary: Boundary) -> Self {
        Self::with_fractions(cells, boundary, None)
    }

    /// The system whose faces weigh their open fraction (Ng, Min & Gibou 2009, Eq. 11): each
    /// face's term of [`Self::solve`]'s sum is scaled by it, and a face of fraction zero couples
    /// nothing. The matrix stays symmetric positive (semi-)definite.
    pub fn with_fractions(
        cells: &Array3<CellKind>,
        boundary: Boundary,
        fractions: Option<FaceFractions>,
    ) -> Self {
        let d = cells.dim();
        let layout = Layout {
            n: [d.0, d.1, d.2],
            periodic: boundary.periodic,
        };
        let kinds = cells
            .iter()
            .map(|c| match c {
                CellKind::Fluid => FLUID,
                CellKind::Solid => SOLID,
                CellKind::Open => DIRICHLET,
            })
            .collect();
        let side_weight = boundary.sides.map(|s| s.map(|s| u8::from(s == Side::Open)));
        let problem = Problem {
            layout,
            kinds,
            side_weight,
            shift: 0.0,
            scale: 1.0,
            weights: fractions,
        };
        let dirichlet = problem.dirichlet_table();
        let stencil = FineStencil::new(&problem, &dirichlet);
        let multigrid = Multigrid::new(&problem, &stencil, &dirichlet);
        let singular = SingularComponents::new(&problem, &dirichlet);
        Self {
            stencil,
            multigrid,
            singular,
            work: Workspace::new(layout.len()),
        }
    }

    /// Number of fluid components with no Dirichlet contact.
    pub fn singular_components(&self) -> usize {
        self.singular.len()
    }

    /// Solves A x = rhs. A is the unit-spacing 7-point Laplacian (positive semi-definite sign):
    /// for a Fluid cell i, (A x)_i = sum over its 6 neighbours j of: (x_i - x_j) if j is Fluid;
    /// x_i if j is Open or beyond an Open side; nothing if j is Solid or beyond a Wall side;
    /// periodic axes wrap. rhs and x outside Fluid cells are ignored / set to 0. `x` holds the
    /// initial guess on entry (warm start), the solution on exit (also the last iterate when
    /// the solve fails to converge).
    ///
    /// Connected fluid components with no Dirichlet (Open) contact are singular: the mean of
    /// rhs over each is removed before solving (the largest is reported as
    /// [`SolveStats::removed_mean`]) and the solution has zero mean there.
    pub fn solve(
        &mut self,
        rhs: &Array3<Real>,
        x: &mut Array3<Real>,
        settings: &SolverSettings,
    ) -> Result<SolveStats, SolveError> {
        self.solve_relative_to(rhs, x, settings, 0.0)
    }

    /// [`Self::solve`] with the residual measured against `reference` where that exceeds |rhs|
    /// (after mean removal): the increment of a pressure whose full right-hand side has the
    /// norm `reference` is solved as accurately as that full pressure would be, not relative
    /// to its own smaller right-hand side.
    pub fn solve_relative_to(
        &mut self,
        rhs: &Array3<Real>,
        x: &mut Array3<Real>,
        settings: &SolverSettings,
        reference: Real,
    ) -> Result<SolveStats, SolveError> {
        let l = self.stencil.layout;
        check_shape(&l, "rhs", rhs)?;
        check_shape(&l, "x", x)?;
        check_settings(settings)?;
        let stencil = &self.stencil;
        load(&l, "rhs", rhs, |i| stencil.is_unknown(i), &mut self.work.b)?;
        load(&l, "x", x, |i| stencil.is_unknown(i), &mut self.work.x)?;
        let mut stats = SolveStats {
            singular_components: self.singular.len(),
            removed_mean: self.singular.remove_means(&mut self.work.b),
            levels: self.multigrid.depth(),
            ..Default::default()
        };
        let own_norm = self.work.b.iter().map(|v| v * v).sum::<f64>().sqrt();
        let b_norm = own_norm.max(reference);
        let result = if own_norm == 0.0 {
            self.work.x.fill(0.0);
            Ok(stats)
        } else {
            let o = pcg::solve(
                &self.stencil,
                &mut self.multigrid,
                &mut self.work,
                b_norm,
                settings.tolerance,
                settings.max_iterations,
            );
            stats.iterations = o.iterations;
            finish(o, stats)
        };
        self.singular.remove_means(&mut self.work.x);
        store(&l, &self.work.x, x);
        result
    }

    /// y = A x (for tests and for the caller's residual checks); zero outside Fluid cells.
    ///
    /// # Panics
    /// If `x` or `y` does not have the shape of the cell layout.
    pub fn apply(&self, x: &Array3<Real>, y: &mut Array3<Real>) {
        let l = self.stencil.layout;
        assert!(
            shape(x) == l.n && shape(y) == l.n,
            "apply: arrays must have the cell layout's shape"
        );
        let xs: Vec<f64> = x
            .iter()
            .enumerate()
            .map(|(i, &v)| if self.stencil.is_unknown(i) { v } else { 0.0 })
            .collect();
        let mut ys = vec![0.0; l.len()];
        self.stencil.apply_dot(&xs, &mut ys);
        y.iter_mut().zip(ys).for_each(|(y, v)| *y = v);
    }
}
