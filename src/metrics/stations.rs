//! Stations: time-averaged profiles of the velocity `U` and the turbulent kinetic energy `k`
//! across a box cut into bins along one axis, read from a lattice's running statistics
//! ([`super::statistics`]), with confidence intervals by batch means.
//!
//! **Profile.** A bin's `U` and `k` are the averages of its lattice cells' (those whose centre
//! lies in the bin), each cell weighted by the weight of its samples: on a grid every fluid
//! cell alike, on particle bins by the particles they held, so `U` is the particles' average.
//! `k` is then the mean of the cells' own temporal fluctuations (the mean shear across a bin is
//! not counted as turbulence), the same on a grid and on particles. Along a homogeneous
//! direction (a periodic span) the cells can be pooled first (`pool`): their moments combine as
//! one ensemble (Chan, Golub & LeVeque's rule), so the spread of their means counts as
//! fluctuation, as averaging over the span does in channel-flow statistics.
//!
//! **Confidence.** The averaging window is cut into batches of equal length; each batch's bin
//! values come from the moments its samples added (the lattice's moments at its end less those
//! at its start, by the combination rule of Chan, Golub & LeVeque 1979 read backwards). With `B`
//! complete batches of values `x_b`, the 95 % half-width is `t(0.975, B - 1) s / sqrt(B)`, `s`
//! the batches' standard deviation (the method of batch means, e.g. Law & Kelton, *Simulation
//! Modeling and Analysis*, §9.5.3): batches much longer than the flow's correlation time are
//! close to independent, so the interval holds for the time average as a whole.

use statrs::distribution::{ContinuousCDF, StudentsT};

use super::statistics::{restore_moments, save_moments, CellMoments, Lattice, STRESS_PAIRS};
use crate::state::{Persist, Restorer, Saver, StateError};
use crate::{Real, Vec3};

/// A station as a scene gives it: a box from `min` to `max` cut into `bins` along `axis`.
#[derive(Debug, Clone, PartialEq)]
pub struct StationSpec {
    pub name: String,
    pub min: Vec3,
    pub max: Vec3,
    /// 0, 1 or 2 for x, y, z.
    pub axis: usize,
    pub bins: usize,
    /// The axis along which cells are pooled as one ensemble, if any.
    pub pool: Option<usize>,
}

/// One bin of a profile: its centre along the axis, `U`, `k` and their 95 % half-widths (NaN
/// before two batches are complete, or where no sample found fluid).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BinProfile {
    pub position: Real,
    pub mean: [Real; 3],
    pub k: Real,
    pub mean_ci: [Real; 3],
    pub k_ci: Real,
}

/// A bin's `U` and `k`.
type BinValues = ([Real; 3], Real);

/// A station on a lattice: its bins' cells and the values of the batches completed so far.
#[derive(Debug, Clone)]
pub struct Station {
    pub spec: StationSpec,
    /// Per bin, its groups of lattice cells (flat indices) pooled as one ensemble: one cell
    /// each without `pool`, the cells of one line along the pooled axis with it.
    cells: Vec<Vec<Vec<usize>>>,
    /// Its cells' moments when the current batch began, in the order of `cells`.
    start: Vec<CellMoments>,
    /// Per complete batch, per bin: `U` and `k` of the batch's samples.
    batches: Vec<Vec<BinValues>>,
}

impl Station {
    /// The station on `lattice`; an error when a bin holds no cell centre (finer than the
    /// lattice) or the box lies outside it.
    pub fn new(spec: StationSpec, lattice: &Lattice) -> Result<Self, String> {
        let width = (spec.max[spec.axis] - spec.min[spec.axis]) / spec.bins as Real;
        let mut groups: Vec<Vec<([usize; 3], usize)>> = vec![Vec::new(); spec.bins];
        let [nx, ny, nz] = lattice.dims;
        for i in 0..nx {
            for j in 0..ny {
                for k in 0..nz {
                    let c = lattice.origin
                        + Vec3::new(i as Real + 0.5, j as Real + 0.5, k as Real + 0.5)
                            * lattice.spacing;
                    if (0..3).any(|a| c[a] < spec.min[a] || c[a] >= spec.max[a]) {
                        continue;
                    }
                    let b = ((c[spec.axis] - spec.min[spec.axis]) / width).floor() as usize;
                    let mut key = [i, j, k];
                    if let Some(a) = spec.pool {
                        key[a] = 0;
                    }
                    groups[b.min(spec.bins - 1)].push((key, (i * ny + j) * nz + k));
                }
            }
        }
        let cells: Vec<Vec<Vec<usize>>> = groups
            .into_iter()
            .map(|mut bin| {
                bin.sort_by_key(|&(key, flat)| (key, flat));
                bin.chunk_by(|a, b| a.0 == b.0)
                    .map(|g| g.iter().map(|&(_, flat)| flat).collect())
                    .collect()
            })
            .collect();
        if let Some(b) = cells.iter().position(Vec::is_empty) {
            return Err(format!(
                "station {:?}: bin {b} ({width:.4} m along {}) holds no cell centre of the \
                 statistics' lattice (cells of {} m): use fewer bins or a finer lattice \
                 (`statistics.bin` on particles), and keep the box inside the domain",
                spec.name,
                ["x", "y", "z"][spec.axis],
                lattice.spacing
            ));
        }
        let n = cells.iter().flatten().map(Vec::len).sum();
        Ok(Self {
            spec,
            cells,
            start: vec![CellMoments::default(); n],
            batches: Vec::new(),
        })
    }

    /// Ends the current batch at the lattice's moments `cells`, keeping its bin values, and
    /// begins the next.
    pub fn next_batch(&mut self, cells: &[CellMoments]) {
        let now = self.moments(cells);
        let since: Vec<CellMoments> = now
            .iter()
            .zip(&self.start)
            .map(|(n, s)| n.since(s))
            .collect();
        self.batches.push(self.bins(&since));
        self.start = now;
    }

    /// Complete batches so far.
    pub fn batches(&self) -> usize {
        self.batches.len()
    }

    /// The station's cells' moments, in the order of `cells`.
    fn moments(&self, cells: &[CellMoments]) -> Vec<CellMoments> {
        self.cells
            .iter()
            .flatten()
            .flatten()
            .map(|&c| cells[c])
            .collect()
    }

    /// Per bin, `U` and `k` of `moments` (its cells' moments, in the order of `cells`): each
    /// group pooled, then the groups averaged.
    fn bins(&self, moments: &[CellMoments]) -> Vec<BinValues> {
        let mut at = 0;
        self.cells
            .iter()
            .map(|bin| {
                let pooled: Vec<CellMoments> = bin
                    .iter()
                    .map(|group| {
                        let own = &moments[at..at + group.len()];
                        at += group.len();
                        own.iter().fold(CellMoments::default(), |a, c| a.merge(c))
                    })
                    .collect();
                average(&pooled)
            })
            .collect()
    }

    /// The profile of the lattice's moments `cells`, with the batches' half-widths.
    pub fn profile(&self, cells: &[CellMoments]) -> Vec<BinProfile> {
        let now = self.moments(cells);
        let width = (self.spec.max[self.spec.axis] - self.spec.min[self.spec.axis])
            / self.spec.bins as Real;
        self.bins(&now)
            .into_iter()
            .enumerate()
            .map(|(b, (mean, k))| {
                let spread = |f: &dyn Fn(&BinValues) -> Real| {
                    half_width(
                        &self
                            .batches
                            .iter()
                            .map(|batch| f(&batch[b]))
                            .collect::<Vec<_>>(),
                    )
                };
                BinProfile {
                    position: self.spec.min[self.spec.axis] + (b as Real + 0.5) * width,
                    mean,
                    k,
                    mean_ci: std::array::from_fn(|c| spread(&|v| v.0[c])),
                    k_ci: spread(&|v| v.1),
                }
            })
            .collect()
    }
}

/// `U` and `k` over cells, each weighted by its samples' weight; NaN without one.
fn average(cells: &[CellMoments]) -> BinValues {
    let w: Real = cells.iter().map(|c| c.weight).sum();
    if w <= 0.0 {
        return ([Real::NAN; 3], Real::NAN);
    }
    let sampled = cells.iter().filter(|c| c.weight > 0.0);
    let (mut mean, mut k) = ([0.0; 3], 0.0);
    for c in sampled {
        for (m, u) in mean.iter_mut().zip(c.mean) {
            *m += c.weight * u;
        }
        k += c.weight * c.k();
    }
    (mean.map(|m| m / w), k / w)
}

/// The 95 % half-width of the mean of `values` by Student's t with `n - 1` degrees of
/// freedom; NaN for fewer than two values or any NaN among them.
pub fn half_width(values: &[Real]) -> Real {
    let n = values.len();
    if n < 2 || values.iter().any(|v| v.is_nan()) {
        return Real::NAN;
    }
    let mean = values.iter().sum::<Real>() / n as Real;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<Real>() / (n - 1) as Real;
    let t = StudentsT::new(0.0, 1.0, (n - 1) as Real)
        .map(|d| d.inverse_cdf(0.975))
        .unwrap_or(Real::NAN);
    t * (var / n as Real).sqrt()
}

/// The moments its batch began from and the completed batches' bin values.
impl Persist for Station {
    fn save(&self, into: &mut Saver) {
        save_moments(into, "start", &self.start);
        let values: Vec<Real> = self
            .batches
            .iter()
            .flatten()
            .flat_map(|(u, k)| u.iter().copied().chain([*k]))
            .collect();
        into.reals("batches", &values);
    }

    fn restore(&mut self, from: &Restorer) -> Result<(), StateError> {
        restore_moments(from, "start", &mut self.start)?;
        let values = from.reals("batches")?;
        let per_batch = (4 * self.cells.len()).max(1);
        if values.len() % per_batch != 0 {
            return Err(from.invalid(
                "batches",
                format!("{} values", values.len()),
                format!("a multiple of {per_batch} (U and k per bin)"),
            ));
        }
        self.batches = values
            .chunks_exact(per_batch)
            .map(|b| {
                b.chunks_exact(4)
                    .map(|v| ([v[0], v[1], v[2]], v[3]))
                    .collect()
            })
            .collect();
        Ok(())
    }
}

impl CellMoments {
    /// The moments of this cell's samples and `other`'s together (Chan, Golub & LeVeque 1979):
    /// W = W_a + W_b, U = U_a + (W_b / W) d, C = C_a + C_b + (W_a W_b / W) d d, d = U_b - U_a.
    pub fn merge(&self, other: &CellMoments) -> CellMoments {
        let w = self.weight + other.weight;
        if other.weight <= 0.0 {
            return *self;
        }
        if self.weight <= 0.0 {
            return *other;
        }
        let f = other.weight / w;
        let d: [Real; 3] = std::array::from_fn(|c| other.mean[c] - self.mean[c]);
        let g = self.weight * other.weight / w;
        let mut co = self.co;
        for ((co, b), (x, y)) in co.iter_mut().zip(other.co).zip(STRESS_PAIRS) {
            *co += b + g * d[x] * d[y];
        }
        let blend = |a: Real, b: Real| a + f * (b - a);
        CellMoments {
            weight: w,
            samples: self.samples + other.samples,
            mean: std::array::from_fn(|c| self.mean[c] + f * d[c]),
            co,
            vorticity: std::array::from_fn(|c| blend(self.vorticity[c], other.vorticity[c])),
            enstrophy: blend(self.enstrophy, other.enstrophy),
        }
    }

    /// The moments of the samples added since `earlier` (this cell's moments at an earlier
    /// time): the combination rule of Chan, Golub & LeVeque read backwards, W_b = W - W_e,
    /// U_b = (W U - W_e U_e) / W_b, C_b = C - C_e - (W_e W_b / W) (U_b - U_e)(U_b - U_e).
    pub fn since(&self, earlier: &CellMoments) -> CellMoments {
        let w = self.weight - earlier.weight;
        if w <= 0.0 || self.samples <= earlier.samples {
            return CellMoments::default();
        }
        let later = |now: Real, then: Real| (self.weight * now - earlier.weight * then) / w;
        let mean: [Real; 3] = std::array::from_fn(|c| later(self.mean[c], earlier.mean[c]));
        let d: [Real; 3] = std::array::from_fn(|c| mean[c] - earlier.mean[c]);
        let g = earlier.weight * w / self.weight;
        let mut co = self.co;
        for ((co, e), (a, b)) in co.iter_mut().zip(earlier.co).zip(STRESS_PAIRS) {
            *co -= e + g * d[a] * d[b];
        }
        CellMoments {
            weight: w,
            samples: self.samples - earlier.samples,
            mean,
            co,
            vorticity: std::array::from_fn(|c| later(self.vorticity[c], earlier.vorticity[c])),
            enstrophy: later(self.enstrophy, earlier.enstrophy),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Moments of the second half of a series, by `since`, equal those of the second half
    /// alone, and the halves merged those of the whole; the half-width of known values is
    /// t s / sqrt(n).
    #[test]
    fn moments_since_an_earlier_time_are_those_of_the_later_samples() {
        let sample = |n: usize| {
            let t = n as Real;
            (
                0.01 + 0.001 * (t * 0.3).sin().abs(),
                [1.0 + (t * 0.7).sin(), 0.5 * (t * 1.3).cos(), 0.1 * t.sin()],
                [(t * 0.2).cos(), 0.0, 2.0 * (t * 0.9).sin()],
                (t * 0.5).sin().powi(2),
            )
        };
        let (mut all, mut first, mut second) = Default::default();
        let add = |m: &mut CellMoments, n| {
            let (w, u, o, e) = sample(n);
            m.add(w, u, o, e);
        };
        for n in 0..50 {
            add(&mut all, n);
            add(&mut first, n);
        }
        for n in 50..130 {
            add(&mut all, n);
            add(&mut second, n);
        }
        let merged = first.merge(&second);
        let since = CellMoments::since(&all, &first);
        assert_eq!(since.samples, second.samples);
        let close = |a: Real, b: Real| (a - b).abs() <= 1e-12 * (1.0 + b.abs());
        assert!(close(since.weight, second.weight));
        for c in 0..3 {
            assert!(close(since.mean[c], second.mean[c]), "{since:?} {second:?}");
            assert!(close(since.vorticity[c], second.vorticity[c]));
        }
        for (a, b) in since.stress().iter().zip(second.stress()) {
            assert!(close(*a, b), "{a} {b}");
        }
        assert!(close(since.enstrophy, second.enstrophy));
        // ... and the two halves merged are the whole.
        assert_eq!(merged.samples, all.samples);
        for (a, b) in merged.stress().iter().zip(all.stress()) {
            assert!(close(*a, b), "{a} {b}");
        }
        for c in 0..3 {
            assert!(close(merged.mean[c], all.mean[c]));
        }
        // t(0.975, 3) = 3.182446; values 1, 2, 3, 4: s = sqrt(5/3).
        let h = half_width(&[1.0, 2.0, 3.0, 4.0]);
        assert!(
            (h - 3.182446 * (5.0 / 3.0 as Real).sqrt() / 2.0).abs() < 1e-5,
            "{h}"
        );
        assert!(half_width(&[1.0]).is_nan());
    }

    /// Batch means' intervals of a stationary random signal hold its mean about 95 % of the
    /// time: over 400 seeded series of 1,000 samples (mean 2, standard deviation 0.5, in 10
    /// batches) the count that miss lies where a 5 % miss rate puts it (binomial, 400 trials:
    /// 20 expected, 8 to 32 at more than three standard deviations).
    #[test]
    fn batch_means_intervals_hold_the_mean_nineteen_times_in_twenty() {
        use super::super::statistics::FlowStatistics;
        use rand::{RngExt, SeedableRng};
        let lattice = Lattice {
            origin: Vec3::zeros(),
            spacing: 1.0,
            dims: [1, 1, 1],
        };
        let spec = StationSpec {
            name: "s".into(),
            min: Vec3::zeros(),
            max: Vec3::repeat(1.0),
            axis: 0,
            bins: 1,
            pool: None,
        };
        let mut missed = 0;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for _ in 0..400 {
            let mut stats = FlowStatistics::new(lattice);
            stats
                .add_stations(std::slice::from_ref(&spec), 0.0, Some(100.0))
                .expect("a station");
            for n in 0..1000 {
                // Box-Muller: a normal sample from two uniform ones.
                let (a, b): (Real, Real) = (rng.random(), rng.random());
                let z = (-2.0 * (1.0 - a).ln()).sqrt() * (std::f64::consts::TAU * b).cos();
                let t = n as Real;
                let centre = [Vec3::repeat(0.5)];
                let v = [Vec3::new(2.0 + 0.5 * z, 0.0, 0.0)];
                stats.sample_particles(&centre, &v, &[Vec3::zeros()], 1.0, (t, t + 1.0));
            }
            let station = &stats.stations[0];
            assert_eq!(station.batches(), 10);
            let bin = station.profile(&stats.cells)[0];
            missed += usize::from((bin.mean[0] - 2.0).abs() > bin.mean_ci[0]);
        }
        assert!(
            (8..=32).contains(&missed),
            "{missed} of 400 intervals miss the mean"
        );
    }
}
