//! Running statistics of a flow on a lattice of cells: per cell the time-averaged velocity
//! `U_i = <u_i>`, the Reynolds stresses `<u'_i u'_j>` (u' = u - U), the turbulent kinetic
//! energy `k = <u'_i u'_i> / 2`, the mean vorticity and the mean enstrophy `<|omega|^2> / 2`
//! (Pope, *Turbulent Flows*, §3.3 and §5.1).
//!
//! **Update.** Each sample enters with a weight (the time it stands for) through West's
//! weighted form of Welford's online update (West 1979, "Updating mean and variance estimates"):
//! with `W' = W + w` and `d = u - U`, `U += (w / W') d` and the co-moment
//! `C_ij += w (W / W') d_i d_j`, so `<u'_i u'_j> = C_ij / W`. Unlike summing `u` and `u^2`, it
//! never subtracts two large numbers, so the stresses of a fast steady flow stay at round-off
//! instead of drowning in the mean's square.
//!
//! **Where.** On a MAC grid the lattice is the grid's cells, sampled at the cell-centred
//! velocity (the mean of a cell's two faces per axis) and vorticity, fluid cells only. On
//! particles it is a lattice of bins over the fluid's domain: each sample adds, per bin that
//! holds fluid, the bin's mean velocity, vorticity and enstrophy over its particles, weighted by
//! the time and the particle count, so a bin's average is the particles' average; its stresses
//! are then those of the bin-filtered velocity (the fluctuation of the bin means over time).

use ndarray::Array3;
use rayon::prelude::*;

use super::stations::{Station, StationSpec};
use crate::grid::forces::CellVorticity;
use crate::grid::GridSolver;
use crate::state::{Persist, Restorer, Saver, StateError};
use crate::{Real, Vec3};

/// The running moments of one cell.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct CellMoments {
    /// Sum of the samples' weights (s on a grid, particle-seconds in a bin).
    pub weight: Real,
    /// Samples that found fluid in the cell.
    pub samples: u64,
    /// Mean velocity, m/s.
    pub mean: [Real; 3],
    /// Co-moments `sum w u'_i u'_j` in the order xx, yy, zz, xy, yz, xz, m²/s² times weight.
    pub co: [Real; 6],
    /// Mean vorticity, 1/s.
    pub vorticity: [Real; 3],
    /// Mean enstrophy |omega|² / 2, 1/s².
    pub enstrophy: Real,
}

/// The index pairs of the six stress components, VTK's order for symmetric tensors.
pub const STRESS_PAIRS: [(usize, usize); 6] = [(0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (0, 2)];

impl CellMoments {
    /// Adds one sample of velocity `u`, vorticity `omega` and enstrophy `enstrophy` with weight
    /// `w` (> 0).
    pub fn add(&mut self, w: Real, u: [Real; 3], omega: [Real; 3], enstrophy: Real) {
        if w <= 0.0 {
            return;
        }
        let total = self.weight + w;
        let f = w / total;
        let d: [Real; 3] = std::array::from_fn(|c| u[c] - self.mean[c]);
        let g = w * (self.weight / total);
        for (co, (a, b)) in self.co.iter_mut().zip(STRESS_PAIRS) {
            *co += g * d[a] * d[b];
        }
        for c in 0..3 {
            self.mean[c] += f * d[c];
            self.vorticity[c] += f * (omega[c] - self.vorticity[c]);
        }
        self.enstrophy += f * (enstrophy - self.enstrophy);
        self.weight = total;
        self.samples += 1;
    }

    /// The Reynolds stresses `<u'_i u'_j>`, m²/s², in [`STRESS_PAIRS`] order; NaN without a
    /// sample.
    pub fn stress(&self) -> [Real; 6] {
        let w = self.weight;
        self.co.map(|c| if w > 0.0 { c / w } else { Real::NAN })
    }

    /// Turbulent kinetic energy `k = (<u'u'> + <v'v'> + <w'w'>) / 2`, m²/s².
    pub fn k(&self) -> Real {
        let s = self.stress();
        0.5 * (s[0] + s[1] + s[2])
    }
}

/// A lattice of cubic cells: cell `(i, j, k)` spans `origin + spacing * [i, i + 1] x ...`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lattice {
    pub origin: Vec3,
    pub spacing: Real,
    pub dims: [usize; 3],
}

impl Lattice {
    /// Cells of edge `spacing` covering the box from `lo` to `hi` (at least one per axis).
    pub fn covering(lo: Vec3, hi: Vec3, spacing: Real) -> Self {
        let dims = std::array::from_fn(|a| (((hi[a] - lo[a]) / spacing).ceil() as usize).max(1));
        Self {
            origin: lo,
            spacing,
            dims,
        }
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.dims.iter().product()
    }

    /// True for a lattice without cells (never built: every axis has one).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The flat (C-order) index of the cell holding `x`, if any.
    pub fn cell_of(&self, x: &Vec3) -> Option<usize> {
        let mut flat = 0;
        for a in 0..3 {
            // In range the cast truncates, which is the floor (without a call to libm's).
            let g = (x[a] - self.origin[a]) / self.spacing;
            if !(g >= 0.0 && g < self.dims[a] as Real) {
                return None;
            }
            flat = flat * self.dims[a] + g as usize;
        }
        Some(flat)
    }
}

/// The fields of a lattice's statistics, each indexed `[i, j, k]` like the lattice; NaN where
/// no sample found fluid.
pub struct StatisticsFields {
    pub mean_velocity: [Array3<Real>; 3],
    /// xx, yy, zz, xy, yz, xz.
    pub reynolds_stress: [Array3<Real>; 6],
    pub k: Array3<Real>,
    pub mean_vorticity: [Array3<Real>; 3],
    pub mean_enstrophy: Array3<Real>,
    pub samples: Array3<Real>,
}

/// One bin's sums over its particles in one sample: count, velocity, vorticity, enstrophy.
type BinSum = [Real; 8];

/// The running statistics of one medium on its lattice.
#[derive(Debug, Clone)]
pub struct FlowStatistics {
    pub lattice: Lattice,
    /// One per cell, C order.
    pub cells: Vec<CellMoments>,
    /// The time the samples span, s: from the start of the first sampled interval to the end
    /// of the last.
    pub span: Option<(Real, Real)>,
    /// Samples taken.
    pub steps: u64,
    /// Profiles read from the cells, with their batches.
    pub stations: Vec<Station>,
    /// When the current batch of the stations ends and how long a batch is, s.
    batch: Option<(Real, Real)>,
    /// Per-bin sums of the sample being taken (particles only) and the bins it touched.
    bins: Vec<BinSum>,
    touched: Vec<usize>,
}

/// Bytes the statistics hold per grid cell: its moments.
pub const BYTES_PER_CELL: usize = std::mem::size_of::<CellMoments>();
/// Bytes the statistics hold per particle bin: its moments and the sums of a sample.
pub const BYTES_PER_BIN: usize = BYTES_PER_CELL + std::mem::size_of::<BinSum>();

impl FlowStatistics {
    /// No samples yet on `lattice`.
    pub fn new(lattice: Lattice) -> Self {
        Self {
            lattice,
            cells: vec![CellMoments::default(); lattice.len()],
            span: None,
            steps: 0,
            stations: Vec::new(),
            batch: None,
            bins: Vec::new(),
            touched: Vec::new(),
        }
    }

    /// Adds stations on this lattice whose batches are `length` s long from `from` on (no
    /// confidence intervals without a length); an error names a station finer than the
    /// lattice.
    pub fn add_stations(
        &mut self,
        specs: &[StationSpec],
        from: Real,
        length: Option<Real>,
    ) -> Result<(), String> {
        for spec in specs {
            self.stations
                .push(Station::new(spec.clone(), &self.lattice)?);
        }
        self.batch = length.filter(|l| *l > 0.0).map(|l| (from + l, l));
        Ok(())
    }

    /// Records that a sample stands for the interval `span`, and ends the stations' batch when
    /// its time has come.
    fn extend(&mut self, (from, to): (Real, Real)) {
        self.span = Some(self.span.map_or((from, to), |(a, _)| (a, to)));
        self.steps += 1;
        while let Some((end, length)) = self.batch.filter(|(end, l)| to >= end - 1e-9 * l) {
            for s in &mut self.stations {
                s.next_batch(&self.cells);
            }
            self.batch = Some((end + length, length));
        }
    }

    /// Adds the grid's current fluid cells as one sample of weight `weight` (the time it
    /// stands for) over the interval `span`; the lattice must be the grid's cells.
    pub fn sample_grid(&mut self, solver: &GridSolver, weight: Real, span: (Real, Real)) {
        let mac = &solver.mac;
        debug_assert_eq!(
            mac.dims, self.lattice.dims,
            "statistics on the grid's cells"
        );
        let fluid = solver.bounds.fluid_mask();
        let vorticity = CellVorticity::new(mac);
        let [_, ny, nz] = mac.dims;
        let faces = &mac.u;
        self.cells
            .par_chunks_mut(ny * nz)
            .enumerate()
            .for_each(|(i, slab)| {
                let mut omega = vec![Vec3::zeros(); nz];
                for (j, row) in slab.chunks_mut(nz).enumerate() {
                    vorticity.row([i, j, 0], &mut omega);
                    for (k, cell) in row.iter_mut().enumerate() {
                        if !fluid[[i, j, k]] {
                            continue;
                        }
                        let u = std::array::from_fn(|a| {
                            let mut next = [i, j, k];
                            next[a] += 1;
                            0.5 * (faces[a][[i, j, k]] + faces[a][next])
                        });
                        let w = omega[k];
                        cell.add(weight, u, w.into(), 0.5 * w.norm_squared());
                    }
                }
            });
        self.extend(span);
    }

    /// Adds the particles at `x` with velocities `v` and vorticities `omega` as one sample of
    /// weight `weight` per particle over the interval `span`: each bin that holds particles
    /// adds its mean velocity and vorticity with the weight times its count.
    pub fn sample_particles(
        &mut self,
        x: &[Vec3],
        v: &[Vec3],
        omega: &[Vec3],
        weight: Real,
        span: (Real, Real),
    ) {
        if self.bins.len() != self.cells.len() {
            self.bins = vec![[0.0; 8]; self.cells.len()];
        }
        for ((x, v), w) in x.iter().zip(v).zip(omega) {
            let Some(b) = self.lattice.cell_of(x) else {
                continue;
            };
            let sum = &mut self.bins[b];
            if sum[0] == 0.0 {
                self.touched.push(b);
            }
            sum[0] += 1.0;
            for c in 0..3 {
                sum[1 + c] += v[c];
                sum[4 + c] += w[c];
            }
            sum[7] += 0.5 * w.norm_squared();
        }
        for &b in &self.touched {
            let sum = std::mem::take(&mut self.bins[b]);
            let n = sum[0];
            let u = std::array::from_fn(|c| sum[1 + c] / n);
            let w = std::array::from_fn(|c| sum[4 + c] / n);
            self.cells[b].add(weight * n, u, w, sum[7] / n);
        }
        self.touched.clear();
        self.extend(span);
    }

    /// The fields, NaN where no sample found fluid.
    pub fn fields(&self) -> StatisticsFields {
        let dims = self.lattice.dims;
        let field = |f: &(dyn Fn(&CellMoments) -> Real + Sync)| {
            let values: Vec<Real> = self
                .cells
                .par_iter()
                .map(|c| if c.samples > 0 { f(c) } else { Real::NAN })
                .collect();
            Array3::from_shape_vec(dims, values).expect("one value per cell")
        };
        StatisticsFields {
            mean_velocity: std::array::from_fn(|a| field(&|c| c.mean[a])),
            reynolds_stress: std::array::from_fn(|s| field(&|c| c.stress()[s])),
            k: field(&CellMoments::k),
            mean_vorticity: std::array::from_fn(|a| field(&|c| c.vorticity[a])),
            mean_enstrophy: field(&|c| c.enstrophy),
            samples: Array3::from_shape_vec(
                dims,
                self.cells.iter().map(|c| c.samples as Real).collect(),
            )
            .expect("one value per cell"),
        }
    }
}

/// Reals per cell in a checkpoint: weight, mean, co-moments, vorticity, enstrophy.
const REALS_PER_CELL: usize = 14;

/// Packs moments for a checkpoint (the counts apart, as integers).
pub(crate) fn save_moments(into: &mut Saver, name: &str, cells: &[CellMoments]) {
    let mut s = into.section(name);
    let reals: Vec<Real> = cells
        .iter()
        .flat_map(|c| {
            std::iter::once(c.weight)
                .chain(c.mean)
                .chain(c.co)
                .chain(c.vorticity)
                .chain([c.enstrophy])
        })
        .collect();
    s.reals("reals", &reals);
    s.u64s(
        "samples",
        &cells.iter().map(|c| c.samples).collect::<Vec<_>>(),
    );
}

/// Unpacks [`save_moments`] into `cells`, whose length the lattice fixes.
pub(crate) fn restore_moments(
    from: &Restorer,
    name: &str,
    cells: &mut [CellMoments],
) -> Result<(), StateError> {
    let r = from.section(name);
    let reals = r.reals_n("reals", REALS_PER_CELL * cells.len())?;
    let samples = r.u64s("samples")?;
    if samples.len() != cells.len() {
        return Err(r.invalid(
            "samples",
            format!("{} values", samples.len()),
            format!("{}, one per cell", cells.len()),
        ));
    }
    for ((c, v), &n) in cells
        .iter_mut()
        .zip(reals.chunks_exact(REALS_PER_CELL))
        .zip(&samples)
    {
        *c = CellMoments {
            weight: v[0],
            samples: n,
            mean: [v[1], v[2], v[3]],
            co: [v[4], v[5], v[6], v[7], v[8], v[9]],
            vorticity: [v[10], v[11], v[12]],
            enstrophy: v[13],
        };
    }
    Ok(())
}

/// The moments, the span and count of the samples, the stations' batches and when the next
/// batch ends; a sample's bin sums are scratch.
impl Persist for FlowStatistics {
    fn save(&self, into: &mut Saver) {
        save_moments(into, "cells", &self.cells);
        if let Some((a, b)) = self.span {
            into.reals("span", &[a, b]);
        }
        into.u64("steps", self.steps);
        if let Some((end, length)) = self.batch {
            into.reals("batch", &[end, length]);
        }
        for (i, s) in self.stations.iter().enumerate() {
            s.save(&mut into.section(&format!("station_{i}")));
        }
    }

    fn restore(&mut self, from: &Restorer) -> Result<(), StateError> {
        restore_moments(from, "cells", &mut self.cells)?;
        let pair = |name| -> Result<Option<(Real, Real)>, StateError> {
            if !from.has(name) {
                return Ok(None);
            }
            let v = from.reals_n(name, 2)?;
            Ok(Some((v[0], v[1])))
        };
        self.span = pair("span")?;
        self.batch = pair("batch")?;
        self.steps = from.u64("steps")?;
        for (i, s) in self.stations.iter_mut().enumerate() {
            s.restore(&from.section(&format!("station_{i}")))?;
        }
        Ok(())
    }
}
