//! The multigrid V-cycle that preconditions the outer CG (MGPCG, McAdams et al. 2010).
//!
//! Levels coarsen every axis longer than one cell by 2 (odd lengths leave a last coarse cell of
//! one child) until no axis is longer than [`COARSEST_MAX_SIDE`]. A coarse cell is an unknown if
//! any child is one, else Dirichlet if any child is, else solid. Its operator is the Galerkin
//! product of piecewise-constant aggregation divided by 2 for faces normal to a coarsened axis:
//! face weights sum the unknown-unknown faces of the children across the coarse face, Dirichlet
//! terms sum the children's, and the `/2` turns those sums into the rediscretised operator of
//! the coarse spacing (area x4, distance x2 in 3D). The shift (diffusion's identity term) sums
//! the children's, as a volume term does. Every level is therefore the same kind of positive
//! (semi-)definite 7-point operator, singular exactly on the components of the fine level that
//! touch no Dirichlet cell.
//!
//! With weighted faces (cut cells), the Dirichlet terms the coarsening sums are weighted as the
//! fine diagonal's are, and coarse unknowns whose faces are open less than [`WEAK`] of a full
//! cell's are left out of the coarse level (see there).
//!
//! Smoothing is red-black Gauss–Seidel (colour classes from [`Layout::colour_groups`]), forward
//! before the coarse correction and in reverse order after it, and the transfers are transposes
//! of each other ([`super::transfer`]), so the V-cycle is a symmetric positive definite operator
//! and CG stays valid (on singular components, positive definite on the range of A, which is all
//! CG sees). The V-cycle runs in f32: it only has to approximate the inverse, while the outer CG
//! keeps f64 residuals, so the attainable accuracy is that of f64.

use super::layout::Layout;
use super::poisson::coordinates;
use super::stencil::{
    for_each_slab, CoarseCoefficients, Coefficients, DirichletTable, FineCoefficients, FineStencil,
    Problem, Row, DIRICHLET, FLUID, PARALLEL_MIN_CELLS, SOLID,
};
use super::transfer::Transfer;
use rayon::prelude::*;

/// Gauss–Seidel sweeps before and after the coarse correction on the finest level (its sweeps
/// dominate the cost of a cycle) and on the coarse levels.
const FINE_SWEEPS: usize = 2;
const COARSE_SWEEPS: usize = 2;
/// Symmetric sweep pairs on the coarsest level (a few dozen cells): close to an exact solve.
const COARSEST_SWEEPS: usize = 20;
/// Coarsening stops once no axis is longer than this.
const COARSEST_MAX_SIDE: usize = 4;
/// With weighted faces, a coarse unknown whose diagonal is less than this share of a fully open
/// cell's is made solid, its faces closed: the transfers are trilinear, so its restricted
/// right-hand side gathers the residuals of well-coupled fine cells around it, which its tiny
/// diagonal (the sum of sliver faces) turns into a huge value that the prolongation spreads
/// back over them. As a solid cell it takes the mean of its neighbours instead, as the
/// staircase's covered cells do. On the cut sphere at 128^3 this takes MGPCG from 8 iterations
/// to the staircase's 6 (any share from 0.005 to 0.2 does; 1e-6 relative residual).
const WEAK: f32 = 0.01;

/// A slice that several threads write at provably disjoint places: during one Gauss–Seidel
/// colour class every thread writes only cells of that class and reads only cells of other
/// classes, and no two cells of one class are neighbours ([`Layout::colour_groups`]).
#[derive(Clone, Copy)]
struct SharedSlice {
    ptr: *mut f32,
    len: usize,
}

// SAFETY: see the type's documentation; accesses go through raw pointers, never references.
unsafe impl Send for SharedSlice {}
unsafe impl Sync for SharedSlice {}

impl SharedSlice {
    fn new(x: &mut [f32]) -> Self {
        Self {
            ptr: x.as_mut_ptr(),
            len: x.len(),
        }
    }

    /// # Safety
    /// `i < len`, and no other thread writes `i` concurrently.
    #[inline(always)]
    unsafe fn read(self, i: usize) -> f32 {
        debug_assert!(i < self.len);
        self.ptr.add(i).read()
    }

    /// # Safety
    /// `i < len`, and no other thread reads or writes `i` concurrently.
    #[inline(always)]
    unsafe fn write(self, i: usize, v: f32) {
        debug_assert!(i < self.len);
        self.ptr.add(i).write(v)
    }
}

/// One colour class of a Gauss–Seidel sweep: `x_c = (b_c + scale * sum_j w_cj x_j) / d_c`.
fn relax_class<C: Coefficients>(l: &Layout, coef: &C, b: &[f32], x: &mut [f32], class: usize) {
    assert_eq!(x.len(), l.len(), "smoother buffer does not match its level");
    if x.is_empty() {
        return;
    }
    let (group, parity) = (class / 2, class % 2);
    let xs = SharedSlice::new(x);
    let scale = coef.scale();
    let z_groups = l.group_of(2, l.n[2] - 1) > 0;
    for_each_slab(l, |i| {
        for j in 0..l.n[1] {
            let gij = l.group_of(0, i) + l.group_of(1, j);
            if gij > group || gij + usize::from(z_groups) < group {
                continue;
            }
            let row = Row::new(l, i, j);
            let first = (i + j + parity) % 2;
            // SAFETY: indices come from the layout (in range); the neighbours read are of
            // other colour classes than the cell written, which this class never writes.
            // (`move`: the closures hold their own copy of the pointer, which the compiler
            // then keeps in a register instead of reloading it after every raw write.)
            let read = move |m: usize| unsafe { xs.read(m) };
            let update = move |k: usize, s: f32| {
                let c = row.base() + k;
                unsafe { xs.write(c, (b[c] + scale * s) * coef.inv_diagonal(c)) };
            };
            if !z_groups {
                row.face_sums(first, 2, coef, read, update);
                continue;
            }
            for k in (first..l.n[2]).step_by(2) {
                if gij + l.group_of(2, k) == group {
                    update(k, row.face_sum(k, coef, read));
                }
            }
        }
    });
}

/// The first colour class of a sweep from a zero initial guess, which needs no neighbours:
/// `x = b / d` on class 0 and `x = 0` elsewhere, in one contiguous pass.
fn relax_first_from_zero<C: Coefficients>(l: &Layout, coef: &C, b: &[f32], x: &mut [f32]) {
    let slab = |(i, xs): (usize, &mut [f32])| {
        for j in 0..l.n[1] {
            let gij = l.group_of(0, i) + l.group_of(1, j);
            for k in 0..l.n[2] {
                let local = j * l.n[2] + k;
                let c = i * l.slab() + local;
                let first = (i + j + k) % 2 == 0 && gij + l.group_of(2, k) == 0;
                xs[local] = if first {
                    b[c] * coef.inv_diagonal(c)
                } else {
                    0.0
                };
            }
        }
    };
    if l.len() >= PARALLEL_MIN_CELLS {
        x.par_chunks_mut(l.slab()).enumerate().for_each(slab);
    } else {
        x.chunks_mut(l.slab()).enumerate().for_each(slab);
    }
}

/// Pre-smoothing from a zero initial guess: `sweeps` Gauss–Seidel sweeps, classes in
/// increasing order.
fn presmooth<C: Coefficients>(l: &Layout, coef: &C, b: &[f32], x: &mut [f32], sweeps: usize) {
    let classes = 2 * l.colour_groups();
    relax_first_from_zero(l, coef, b, x);
    for c in 1..classes * sweeps {
        relax_class(l, coef, b, x, c % classes);
    }
}

/// One forward sweep from the current `x` (the coarsest level's repeated symmetric sweeps).
fn presmooth_continue<C: Coefficients>(l: &Layout, coef: &C, b: &[f32], x: &mut [f32]) {
    for c in 0..2 * l.colour_groups() {
        relax_class(l, coef, b, x, c);
    }
}

/// Post-smoothing: `sweeps` sweeps with the classes in decreasing order (the adjoint of
/// [`presmooth`], which keeps the V-cycle symmetric).
fn postsmooth<C: Coefficients>(l: &Layout, coef: &C, b: &[f32], x: &mut [f32], sweeps: usize) {
    let classes = 2 * l.colour_groups();
    for c in (0..classes * sweeps).rev() {
        relax_class(l, coef, b, x, c % classes);
    }
}

/// `r = b - A x`.
fn residual<C: Coefficients>(l: &Layout, coef: &C, b: &[f32], x: &[f32], r: &mut [f32]) {
    let scale = coef.scale();
    let slab = |(i, rs): (usize, &mut [f32])| {
        for j in 0..l.n[1] {
            let row = Row::new(l, i, j);
            let out = &mut rs[j * l.n[2]..][..l.n[2]];
            row.face_sums(
                0,
                1,
                coef,
                |m| x[m],
                |k, s: f32| {
                    let c = row.base() + k;
                    out[k] = b[c] - coef.diagonal(c) * x[c] + scale * s;
                },
            );
        }
    };
    if l.len() >= PARALLEL_MIN_CELLS {
        r.par_chunks_mut(l.slab()).enumerate().for_each(slab);
    } else {
        r.chunks_mut(l.slab()).enumerate().for_each(slab);
    }
}

/// What the coarsening reads from a level.
trait LevelView: Sync {
    fn layout(&self) -> Layout;
    fn kind(&self, idx: usize) -> u8;
    /// Face weight to the upper neighbour along `axis`, scale included.
    fn upper(&self, axis: usize, idx: usize) -> f32;
    /// Dirichlet weight along `axis`, scale included.
    fn dirichlet(&self, axis: usize, idx: usize) -> f32;
    fn shift(&self, idx: usize) -> f32;
    /// Weight of a fully open face along each axis, scale included.
    fn unit(&self) -> [f32; 3];
    /// Whether faces may weigh other than [`LevelView::unit`] (the fine problem has weights).
    fn weighted(&self) -> bool;
}

struct FineView<'a> {
    problem: &'a Problem,
    stencil: &'a FineStencil,
    dirichlet: &'a DirichletTable,
}

impl LevelView for FineView<'_> {
    fn layout(&self) -> Layout {
        self.problem.layout
    }
    fn kind(&self, idx: usize) -> u8 {
        self.problem.kinds[idx]
    }
    fn upper(&self, axis: usize, idx: usize) -> f32 {
        self.stencil.upper_weight(axis, idx) * self.problem.scale as f32
    }
    fn dirichlet(&self, axis: usize, idx: usize) -> f32 {
        let count = self.dirichlet.get(idx)[axis];
        let sum = if count == 0 || !self.weighted() {
            f32::from(count)
        } else {
            self.problem
                .weighted_dirichlet(axis, coordinates(&self.problem.layout, idx))
        };
        sum * self.problem.scale as f32
    }
    fn shift(&self, idx: usize) -> f32 {
        if self.problem.kinds[idx] == FLUID {
            self.problem.shift as f32
        } else {
            0.0
        }
    }
    fn unit(&self) -> [f32; 3] {
        [self.problem.scale as f32; 3]
    }
    fn weighted(&self) -> bool {
        self.problem.weights.is_some()
    }
}

/// A coarse level's operator with the per-axis Dirichlet terms and shifts it was built from.
struct CoarseOperator {
    layout: Layout,
    kinds: Vec<u8>,
    coef: CoarseCoefficients,
    dirichlet: [Vec<f32>; 3],
    shift: Vec<f32>,
    unit: [f32; 3],
    weighted: bool,
}

impl LevelView for CoarseOperator {
    fn layout(&self) -> Layout {
        self.layout
    }
    fn kind(&self, idx: usize) -> u8 {
        self.kinds[idx]
    }
    fn upper(&self, axis: usize, idx: usize) -> f32 {
        self.coef.upper[axis][idx]
    }
    fn dirichlet(&self, axis: usize, idx: usize) -> f32 {
        self.dirichlet[axis][idx]
    }
    fn shift(&self, idx: usize) -> f32 {
        self.shift[idx]
    }
    fn unit(&self) -> [f32; 3] {
        self.unit
    }
    fn weighted(&self) -> bool {
        self.weighted
    }
}

/// One coarse cell as the coarsening computes it.
#[derive(Clone, Copy, Default)]
struct CoarseCell {
    kind: u8,
    upper: [f32; 3],
    dirichlet: [f32; 3],
    shift: f32,
}

/// The coarse operator of `fine` (see the module documentation) and the coarsening factors.
fn coarsen(fine: &impl LevelView) -> (CoarseOperator, [usize; 3]) {
    let fl = fine.layout();
    let factors = fl.n.map(|n| if n > 1 { 2 } else { 1 });
    let cl = Layout {
        n: [0, 1, 2].map(|a| fl.n[a].div_ceil(factors[a])),
        periodic: fl.periodic,
    };
    let children = |a: usize, c: usize| {
        let first = c * factors[a];
        first..(first + factors[a]).min(fl.n[a])
    };
    let cell = |idx: usize| {
        let (ij, k) = (idx / cl.n[2], idx % cl.n[2]);
        let c = [ij / cl.n[1], ij % cl.n[1], k];
        let mut out = CoarseCell {
            kind: SOLID,
            ..Default::default()
        };
        let last = [0, 1, 2].map(|a| children(a, c[a]).end - 1);
        let has_upper = [0, 1, 2].map(|a| cl.step(a, c[a], true).is_some());
        for fi in children(0, c[0]) {
            for fj in children(1, c[1]) {
                for fk in children(2, c[2]) {
                    let f = fl.index(fi, fj, fk);
                    match fine.kind(f) {
                        FLUID => out.kind = FLUID,
                        DIRICHLET if out.kind == SOLID => out.kind = DIRICHLET,
                        _ => {}
                    }
                    if fine.kind(f) != FLUID {
                        continue;
                    }
                    out.shift += fine.shift(f);
                    let fc = [fi, fj, fk];
                    for a in 0..3 {
                        out.dirichlet[a] += fine.dirichlet(a, f) / factors[a] as f32;
                        if has_upper[a] && fc[a] == last[a] {
                            out.upper[a] += fine.upper(a, f) / factors[a] as f32;
                        }
                    }
                }
            }
        }
        out
    };
    let mut cells: Vec<CoarseCell> = if cl.len() >= PARALLEL_MIN_CELLS {
        (0..cl.len()).into_par_iter().map(cell).collect()
    } else {
        (0..cl.len()).map(cell).collect()
    };
    let fine_unit = fine.unit();
    let unit: [f32; 3] = std::array::from_fn(|a| {
        let area: usize = (0..3).filter(|&b| b != a).map(|b| factors[b]).product();
        fine_unit[a] * area as f32 / factors[a] as f32
    });
    if fine.weighted() {
        drop_weak(&cl, &mut cells, unit);
    }
    let diag: Vec<f32> = (0..cl.len())
        .map(|idx| diagonal(&cl, &cells, unit, idx).0)
        .collect();
    let inv = diag
        .iter()
        .zip(&cells)
        .map(|(&d, c)| {
            if c.kind == FLUID && d > 0.0 {
                1.0 / d
            } else {
                0.0
            }
        })
        .collect();
    let op = CoarseOperator {
        layout: cl,
        kinds: cells.iter().map(|c| c.kind).collect(),
        dirichlet: [0, 1, 2].map(|a| cells.iter().map(|c| c.dirichlet[a]).collect()),
        shift: cells.iter().map(|c| c.shift).collect(),
        unit,
        weighted: fine.weighted(),
        coef: CoarseCoefficients {
            upper: [0, 1, 2].map(|a| cells.iter().map(|c| c.upper[a]).collect()),
            diag,
            inv,
        },
    };
    (op, factors)
}

/// The diagonal of coarse cell `idx` (shift, Dirichlet terms and the weights of its faces) and
/// the sum of its faces' weights were they fully open (`unit` per axis).
fn diagonal(cl: &Layout, cells: &[CoarseCell], unit: [f32; 3], idx: usize) -> (f32, f32) {
    let c = &cells[idx];
    let coord = coordinates(cl, idx);
    let mut d = c.shift + c.dirichlet.iter().sum::<f32>();
    let mut full = 0.0;
    for a in 0..3 {
        d += c.upper[a];
        if cl.step(a, coord[a], true).is_some() {
            full += unit[a];
        }
        if let Some(s) = cl.step(a, coord[a], false) {
            let mut nb = coord;
            nb[a] = s;
            d += cells[cl.index(nb[0], nb[1], nb[2])].upper[a];
            full += unit[a];
        }
    }
    (d, full)
}

/// Makes the [`WEAK`] coarse unknowns solid and closes their faces (the matrix stays symmetric;
/// their neighbours' diagonals lose those faces' weights).
fn drop_weak(cl: &Layout, cells: &mut [CoarseCell], unit: [f32; 3]) {
    let weak: Vec<bool> = (0..cl.len())
        .map(|idx| {
            let (d, full) = diagonal(cl, cells, unit, idx);
            cells[idx].kind == FLUID && d < WEAK * full
        })
        .collect();
    for (idx, &w) in weak.iter().enumerate() {
        if w {
            cells[idx] = CoarseCell {
                kind: SOLID,
                ..Default::default()
            };
        }
        let coord = coordinates(cl, idx);
        for a in 0..3 {
            if let Some(s) = cl.step(a, coord[a], true) {
                let mut nb = coord;
                nb[a] = s;
                if weak[cl.index(nb[0], nb[1], nb[2])] {
                    cells[idx].upper[a] = 0.0;
                }
            }
        }
    }
}

/// One level's buffers and its transfer to the next coarser level.
struct Level {
    layout: Layout,
    kinds: Vec<u8>,
    /// `None` on the finest level, whose operator is the packed [`FineStencil`].
    coef: Option<CoarseCoefficients>,
    x: Vec<f32>,
    b: Vec<f32>,
    r: Vec<f32>,
    down: Option<Transfer>,
}

impl Level {
    fn new(layout: Layout, kinds: Vec<u8>, coef: Option<CoarseCoefficients>) -> Self {
        let n = layout.len();
        Self {
            layout,
            kinds,
            coef,
            x: vec![0.0; n],
            b: vec![0.0; n],
            r: vec![0.0; n],
            down: None,
        }
    }
}

/// Runs `$body` with `$c` bound to the level's coefficients (fine or coarse) as a generic type.
macro_rules! with_coef {
    ($level:expr, $fine:expr, |$c:ident| $body:expr) => {
        match &$level.coef {
            Some($c) => $body,
            None => {
                let $c = &FineCoefficients::new($fine);
                $body
            }
        }
    };
}

/// The level hierarchy of one problem, with all buffers (nothing is allocated per cycle).
pub(crate) struct Multigrid {
    levels: Vec<Level>,
}

impl Multigrid {
    pub fn new(problem: &Problem, stencil: &FineStencil, dirichlet: &DirichletTable) -> Self {
        let mut levels = vec![Level::new(problem.layout, problem.kinds.clone(), None)];
        let done = |l: &Layout| l.n.iter().all(|&n| n <= COARSEST_MAX_SIDE);
        if done(&problem.layout) {
            return Self { levels };
        }
        let (mut op, mut factors) = coarsen(&FineView {
            problem,
            stencil,
            dirichlet,
        });
        loop {
            let fine = levels.last_mut().expect("the finest level always exists");
            fine.down = Some(Transfer::new(
                fine.layout,
                op.layout,
                factors,
                problem.side_weight,
                &op.kinds,
            ));
            let finished = done(&op.layout);
            let next = if finished { None } else { Some(coarsen(&op)) };
            levels.push(Level::new(op.layout, op.kinds, Some(op.coef)));
            match next {
                Some((o, f)) => (op, factors) = (o, f),
                None => break,
            }
        }
        Self { levels }
    }

    pub fn depth(&self) -> usize {
        self.levels.len()
    }

    /// The finest level's right-hand side, to be filled before [`Multigrid::vcycle`].
    pub fn rhs_mut(&mut self) -> &mut [f32] {
        &mut self.levels[0].b
    }

    /// The result of the last [`Multigrid::vcycle`] on the finest level.
    pub fn solution(&self) -> &[f32] {
        &self.levels[0].x
    }

    /// One V-cycle from a zero initial guess: `solution() ~ A^-1 rhs`.
    pub fn vcycle(&mut self, stencil: &FineStencil) {
        cycle(&mut self.levels, stencil);
    }
}

fn cycle(levels: &mut [Level], stencil: &FineStencil) {
    let (level, coarser) = levels
        .split_first_mut()
        .expect("cycle on an empty hierarchy");
    let l = level.layout;
    let sweeps = if level.coef.is_none() {
        FINE_SWEEPS
    } else {
        COARSE_SWEEPS
    };
    let Some(coarse) = coarser.first_mut() else {
        with_coef!(level, stencil, |c| {
            presmooth(&l, c, &level.b, &mut level.x, 1);
            postsmooth(&l, c, &level.b, &mut level.x, 1);
            for _ in 1..COARSEST_SWEEPS {
                presmooth_continue(&l, c, &level.b, &mut level.x);
                postsmooth(&l, c, &level.b, &mut level.x, 1);
            }
        });
        return;
    };
    with_coef!(level, stencil, |c| {
        presmooth(&l, c, &level.b, &mut level.x, sweeps);
        residual(&l, c, &level.b, &level.x, &mut level.r);
    });
    let down = level
        .down
        .as_mut()
        .expect("every level but the coarsest has a transfer");
    down.restrict(&level.r, &mut coarse.b, &coarse.kinds);
    cycle(coarser, stencil);
    let coarse = &mut coarser[0];
    let kinds = &level.kinds;
    down.prolong_add(&mut coarse.x, &mut level.x, |f| kinds[f] == FLUID);
    with_coef!(level, stencil, |c| postsmooth(
        &l,
        c,
        &level.b,
        &mut level.x,
        sweeps
    ));
}
