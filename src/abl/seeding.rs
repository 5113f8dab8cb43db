//! Vortex-particle seeding from the artificial boundary layer (Pfaff et al. 2009, Eq. 8,
//! section 4.3 "Vortex particle seeding" and Figure 9, lines 11–20), shared by the grid runtime
//! (samples are cells) and the SPH runtime (samples are fluid particles near walls): it sees
//! only positions, omega_ABL, volumes and wall distances.
//!
//! Each sample with nonzero omega_ABL seeds with the probability p_T of Eq. 8. A seed takes all
//! omega_ABL within its radius out of the layer (lines 15–17) and becomes a particle whose
//! kernel holds that vorticity (line 18), with the largest radius that does not touch a wall,
//! capped at r_max (section 4.3). [`scatter`] moves seeds to random places along the walls, the
//! baseline of Figure 8 (middle).

use rand::RngExt;
use rand_chacha::ChaCha8Rng;

use crate::spatial::PointHash;
use crate::vortex::dynamics::random_unit;
use crate::vortex::kernel;
use crate::{Real, Vec3};

/// Samples of the artificial boundary layer, structure of arrays.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SeedSamples {
    /// Positions, m.
    pub x: Vec<Vec3>,
    /// omega_ABL, 1/s; zeroed where a seed takes it (Figure 9, line 17).
    pub omega: Vec<Vec3>,
    /// Volume each sample stands for, m^3.
    pub volume: Vec<Real>,
    /// Distance to the nearest wall, the mixing length l_m of Eq. 8, m.
    pub wall_distance: Vec<Real>,
    /// Largest radius a seed here may take, m: the wall distance, which
    /// [`SeedSamples::limit_room`] may lower (on SPH particles, to the distance to the free
    /// surface).
    pub room: Vec<Real>,
}

impl SeedSamples {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Appends one sample.
    pub fn push(&mut self, x: Vec3, omega: Vec3, volume: Real, wall_distance: Real) {
        self.x.push(x);
        self.omega.push(omega);
        self.volume.push(volume);
        self.wall_distance.push(wall_distance);
        self.room.push(wall_distance);
    }

    /// Lowers the room of sample `i` to at most `r`, m.
    pub fn limit_room(&mut self, i: usize, r: Real) {
        self.room[i] = self.room[i].min(r);
    }
}

/// Parameters of the seeding; the caller checks their ranges.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeedingParams {
    /// c_p of Eq. 8, 1/s: p_T is a probability per sample and step while dt carries seconds
    /// (docs/src/paper-notes.md, "Eq. 8").
    pub c_p: Real,
    /// |U_0| of Eq. 8, m/s, > 0.
    pub u0: Real,
    /// Largest particle radius `sqrt(6) sigma`, m (section 4.3: 6 cells).
    pub r_max: Real,
    /// A seed whose largest radius is below this is not made: it would be dissipated at once
    /// (section 4.2), so its vorticity stays in the layer. m.
    pub r_min: Real,
}

/// One seeded vortex particle.
#[derive(Debug, Clone, PartialEq)]
pub struct Seed {
    /// Centre, m.
    pub x: Vec3,
    /// Kernel strength and axis omega_p, 1/s.
    pub omega: Vec3,
    /// Kernel scale, m.
    pub sigma: Real,
    /// Sum of omega_ABL times volume taken from the layer, m^3/s (Figure 9, line 16).
    pub removed: Vec3,
    /// How many samples with nonzero omega_ABL it took.
    pub samples: usize,
}

/// `2 c_p dt / |U_0|^2`, the factor of Eq. 8 shared by every sample; 0 without a positive
/// |U_0| (Eq. 8 normalises by it, so a scene without a reference speed has no transition).
fn rate(c_p: Real, dt: Real, u0: Real) -> Real {
    if u0 > 0.0 {
        2.0 * c_p * dt / (u0 * u0)
    } else {
        0.0
    }
}

/// Eq. 8 from its shared factor and `|omega_ABL|^2`, clamped to [0, 1]; NaN gives 0.
#[inline]
fn probability(rate: Real, l_m: Real, omega2: Real) -> Real {
    let p = rate * l_m * l_m * omega2;
    if p >= 1.0 {
        1.0
    } else if p > 0.0 {
        p
    } else {
        0.0
    }
}

/// Transition probability of Eq. 8 (Figure 9, line 13), `p_T = 2 c_p dt (l_m |omega_ABL| /
/// |U_0|)^2`, per sample and step, clamped to [0, 1]. With omega in 1/s, l_m in m, |U_0| in m/s
/// and dt in s, c_p carries 1/s. NaN inputs and a non-positive `u0` give 0.
pub fn transition_probability(c_p: Real, dt: Real, l_m: Real, omega: Real, u0: Real) -> Real {
    probability(rate(c_p, dt, u0), l_m, omega * omega)
}

/// K(sigma), m^3: the vorticity of [`kernel::vorticity`] integrated over the kernel's support,
/// the ball `|d| < r_c = sqrt(6) sigma` (section 4.3), is `K(sigma) omega_p`. Section 4.3 sets
/// omega_p so that this integral equals the removed vorticity. Over all space the integral is
/// zero (the field is a curl of a decaying velocity), so the cut-off ball is the only reading
/// of "integrated over the kernel" that can hold any vorticity.
///
/// **Derivation.** By the divergence theorem, `int_B curl u dV = int_dB n x u dS`. On the
/// sphere `|d| = R`, `n = d / R` and `u = (1/2) g(R) a x d` with `a = omega_p`, so
/// `n x (a x d) = R a - d (d . a) / R`. With `int_dB dS = 4 pi R^2` and `int_dB d d^T dS =
/// (4 pi R^4 / 3) I`, the surface integral is `(1/2) g(R) (4 pi R^3 - 4 pi R^3 / 3) a =
/// (4/3) pi R^3 g(R) a`. At `R = r_c`, `g(r_c) = exp(-3)`, so
/// `K = (4/3) pi 6^(3/2) exp(-3) sigma^3`, about `3.065 sigma^3`.
pub fn kernel_vorticity_integral(sigma: Real) -> Real {
    let r = kernel::radius(sigma);
    4.0 / 3.0 * std::f64::consts::PI * r * r * r * (-3.0_f64).exp()
}

/// Figure 9, lines 11–20: visits the samples in index order and seeds at each with nonzero
/// omega_ABL with probability p_T (Eq. 8), drawing one uniform number per such sample. A seed
/// at sample i has the radius `r = min(r_max, room_i)` (section 4.3: as large as possible
/// without touching an object; the room is l_m,i unless the caller lowered it); below `r_min` none is made and the layer is left as it is.
/// Otherwise the samples closer than r (i included) give up their omega_ABL times volume
/// (lines 15–17) and a particle at x_i gets `omega_p = removed / K(sigma)` (line 18,
/// [`kernel_vorticity_integral`]). A sample emptied earlier in the call draws nothing.
///
/// Cost: one pass over the samples; the neighbour search is built at the first seed, at most
/// once per call.
pub fn seed(
    samples: &mut SeedSamples,
    params: &SeedingParams,
    dt: Real,
    rng: &mut ChaCha8Rng,
) -> Vec<Seed> {
    let n = samples.len();
    debug_assert!(
        samples.omega.len() == n
            && samples.volume.len() == n
            && samples.wall_distance.len() == n
            && samples.room.len() == n
    );
    let mut seeds = Vec::new();
    if params.u0.is_nan() || params.u0 <= 0.0 {
        return seeds;
    }
    let rate = rate(params.c_p, dt, params.u0);
    let mut hash: Option<PointHash> = None;
    let mut near = Vec::new();
    for i in 0..n {
        let omega2 = samples.omega[i].norm_squared();
        if omega2.is_nan() || omega2 <= 0.0 {
            continue;
        }
        let l_m = samples.wall_distance[i];
        if rng.random::<Real>() >= probability(rate, l_m, omega2) {
            continue;
        }
        let r = params.r_max.min(samples.room[i]);
        if r <= 0.0 || r < params.r_min {
            continue;
        }
        let xi = samples.x[i];
        let hash = hash.get_or_insert_with(|| PointHash::new(&samples.x, params.r_max));
        near.clear();
        let mut removed = Vec3::zeros();
        hash.for_each_near(&xi, r, |j| {
            if samples.omega[j] != Vec3::zeros() {
                removed += samples.omega[j] * samples.volume[j];
                near.push(j);
            }
        });
        if removed == Vec3::zeros() || !removed.iter().all(|c| c.is_finite()) {
            continue;
        }
        for &j in &near {
            samples.omega[j] = Vec3::zeros();
        }
        let sigma = kernel::sigma_for_radius(r);
        seeds.push(Seed {
            x: xi,
            omega: removed / kernel_vorticity_integral(sigma),
            sigma,
            removed,
            samples: near.len(),
        });
    }
    seeds
}

/// The random baseline of Figure 8 (middle): the same particles, count and strength, seeded
/// uniformly along the walls. Each seed moves to a site drawn uniformly among those whose
/// `site_distance` (to the nearest wall) lies in `[r, r + band)`, r its radius, so that it sits
/// near a wall without touching it; failing that among those at distance >= r; failing that it
/// is dropped. Its axis is drawn uniformly on the sphere with |omega_p| kept; sigma, removed
/// and samples are kept.
pub fn scatter(
    seeds: &mut Vec<Seed>,
    sites: &[Vec3],
    site_distance: &[Real],
    band: Real,
    rng: &mut ChaCha8Rng,
) {
    debug_assert_eq!(sites.len(), site_distance.len());
    // Sites by distance, so that each band is a contiguous range found by bisection.
    let mut order: Vec<usize> = (0..sites.len())
        .filter(|&k| !site_distance[k].is_nan())
        .collect();
    order.sort_by(|&a, &b| site_distance[a].total_cmp(&site_distance[b]));
    let first_at_least = |d: Real| order.partition_point(|&k| site_distance[k] < d);
    seeds.retain_mut(|s| {
        let r = kernel::radius(s.sigma);
        let lo = first_at_least(r);
        let hi = first_at_least(r + band);
        let range = if hi > lo { lo..hi } else { lo..order.len() };
        if range.is_empty() {
            return false;
        }
        s.x = sites[order[rng.random_range(range)]];
        s.omega = random_unit(rng) * s.omega.norm();
        true
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    /// A lattice of `m^3` samples with spacing h starting at the origin, omega varying in
    /// direction and size (zero on one plane), wall distance `z + h/2` (a wall at z = -h/2).
    fn lattice(m: usize, h: Real) -> SeedSamples {
        let mut s = SeedSamples::default();
        for k in 0..m {
            for j in 0..m {
                for i in 0..m {
                    let x = Vec3::new(i as Real, j as Real, k as Real) * h;
                    let omega = if j == 2 {
                        Vec3::zeros()
                    } else {
                        Vec3::new(
                            (1.3 * x.y).sin() + 0.2,
                            (0.7 * x.x).cos() - 0.5 * x.z,
                            1.0 + 0.1 * (i as Real) - 0.05 * (k as Real),
                        )
                    };
                    s.push(x, omega, h * h * h, x.z + 0.5 * h);
                }
            }
        }
        s
    }

    fn weighted_sum(s: &SeedSamples) -> Vec3 {
        s.omega.iter().zip(&s.volume).map(|(w, v)| w * *v).sum()
    }

    #[test]
    fn eq8_values_and_clamp() {
        // 2 * 1.5 * 0.01 * (0.2 * 3 / 2)^2 = 0.03 * 0.09 = 0.0027.
        let p = transition_probability(1.5, 0.01, 0.2, 3.0, 2.0);
        assert!((p - 0.0027).abs() < 1e-15, "p = {p}");
        // The sign of omega does not matter (Eq. 8 squares its norm).
        assert_eq!(p, transition_probability(1.5, 0.01, 0.2, -3.0, 2.0));
        // 2 * 4 * 0.1 * (1 * 10 / 1)^2 = 80, clamped.
        assert_eq!(transition_probability(4.0, 0.1, 1.0, 10.0, 1.0), 1.0);
        assert_eq!(transition_probability(4.0, 0.1, 1.0, 0.0, 1.0), 0.0);
        assert_eq!(transition_probability(-4.0, 0.1, 1.0, 1.0, 1.0), 0.0);
        assert_eq!(transition_probability(Real::NAN, 0.1, 1.0, 1.0, 1.0), 0.0);
        assert_eq!(transition_probability(4.0, 0.1, Real::NAN, 1.0, 1.0), 0.0);
        assert_eq!(transition_probability(4.0, 0.1, 1.0, 1.0, 0.0), 0.0);
    }

    #[test]
    fn kernel_integral_matches_quadrature() {
        let sigma = 0.37;
        let a = Vec3::new(0.3, -1.1, 0.8) * 2.5;
        let rc = kernel::radius(sigma);
        // Midpoint rule in r, cos(theta) and phi over the ball.
        let (nr, nu, nphi) = (400, 400, 12);
        let (hr, hu, hphi) = (
            rc / nr as Real,
            2.0 / nu as Real,
            std::f64::consts::TAU / nphi as Real,
        );
        let mut sum = Vec3::zeros();
        for ir in 0..nr {
            let r = (ir as Real + 0.5) * hr;
            let mut shell = Vec3::zeros();
            for iu in 0..nu {
                let u = -1.0 + (iu as Real + 0.5) * hu;
                let s = (1.0 - u * u).sqrt();
                for ip in 0..nphi {
                    let phi = (ip as Real + 0.5) * hphi;
                    let d = Vec3::new(s * phi.cos(), s * phi.sin(), u) * r;
                    shell += kernel::vorticity(&a, sigma, &d);
                }
            }
            sum += shell * (r * r * hr * hu * hphi);
        }
        let k = kernel_vorticity_integral(sigma);
        let exact = a * k;
        let err = (sum - exact).norm() / exact.norm();
        assert!(err < 1e-4, "relative error {err}: {sum:?} vs {exact:?}");
        // Parallel to omega_p, same sense.
        assert!(sum.cross(&a).norm() < 1e-4 * sum.norm() * a.norm());
        assert!(sum.dot(&a) > 0.0);
        let ratio = k / sigma.powi(3);
        assert!((ratio - 3.0650).abs() < 1e-3, "K / sigma^3 = {ratio}");
    }

    /// Counts seeds over `n` trials of one fresh sample with `p_T = p`.
    fn count_seeds(p: Real, n: usize, rng: &mut ChaCha8Rng) -> usize {
        // p_T = 2 c_p dt (l |omega| / u0)^2 = 2 * 1 * dt * 1 with l = |omega| = u0 = 1.
        let params = SeedingParams {
            c_p: 1.0,
            u0: 1.0,
            r_max: 0.5,
            r_min: 0.1,
        };
        let dt = p / 2.0;
        let omega = Vec3::new(0.6, 0.0, 0.8);
        assert!((transition_probability(1.0, dt, 1.0, omega.norm(), 1.0) - p).abs() < 1e-15);
        let mut k = 0;
        for _ in 0..n {
            let mut s = SeedSamples::default();
            s.push(Vec3::new(1.0, 2.0, 3.0), omega, 1e-3, 1.0);
            let seeds = seed(&mut s, &params, dt, rng);
            assert!(seeds.len() <= 1);
            k += seeds.len();
        }
        k
    }

    #[test]
    fn eq8_statistics() {
        // k is binomial(N, p); a correct sampler falls outside 5 standard deviations with a
        // probability of about 5.7e-7 (two-sided normal tail) per assertion.
        let mut rng = ChaCha8Rng::seed_from_u64(2009);
        let n = 20_000;
        for p in [0.3, 0.02] {
            let k = count_seeds(p, n, &mut rng) as Real;
            let mean = n as Real * p;
            let sd = (mean * (1.0 - p)).sqrt();
            assert!(
                (k - mean).abs() < 5.0 * sd,
                "p = {p}: {k} seeds, expected {mean}"
            );
        }
    }

    #[test]
    fn seeding_conserves_vorticity() {
        let h = 0.1;
        let mut s = lattice(10, h);
        // Far from the block and too close to a wall to seed: their omega stays.
        for k in 0..5 {
            let x = Vec3::new(100.0 + k as Real * h, 0.0, 0.0);
            s.push(x, Vec3::new(1.0, -2.0, 0.5 * k as Real), h * h * h, 0.05);
        }
        let before = weighted_sum(&s);
        let scale: Real = s
            .omega
            .iter()
            .zip(&s.volume)
            .map(|(w, v)| w.norm() * v)
            .sum();
        let nonzero_before = s.omega.iter().filter(|w| **w != Vec3::zeros()).count();
        let params = SeedingParams {
            c_p: 1e12,
            u0: 1.0,
            r_max: 0.35,
            r_min: 0.12,
        };
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let seeds = seed(&mut s, &params, 0.01, &mut rng);
        assert!(seeds.len() > 5, "{} seeds", seeds.len());
        let mut removed = Vec3::zeros();
        let mut taken = 0;
        for sd in &seeds {
            let back = sd.omega * kernel_vorticity_integral(sd.sigma);
            assert!((back - sd.removed).norm() <= 1e-12 * sd.removed.norm());
            let r = kernel::radius(sd.sigma);
            let i =
                s.x.iter()
                    .position(|x| *x == sd.x)
                    .expect("seeded at a sample");
            assert!(r <= s.wall_distance[i] * (1.0 + 1e-12) && r <= params.r_max * (1.0 + 1e-12));
            assert!(r >= params.r_min);
            removed += sd.removed;
            taken += sd.samples;
        }
        let after = weighted_sum(&s);
        assert!(after != Vec3::zeros(), "the far samples keep their omega");
        assert!(
            (removed + after - before).norm() <= 1e-12 * scale,
            "{removed:?} + {after:?} != {before:?}"
        );
        let nonzero_after = s.omega.iter().filter(|w| **w != Vec3::zeros()).count();
        assert_eq!(taken, nonzero_before - nonzero_after);
    }

    #[test]
    fn no_seed_closer_than_r_min() {
        let params = SeedingParams {
            c_p: 1e12,
            u0: 1.0,
            r_max: 0.5,
            r_min: 0.2,
        };
        let mut s = SeedSamples::default();
        for i in 0..20 {
            let x = Vec3::new(i as Real * 0.05, 0.0, 0.0);
            s.push(x, Vec3::new(0.0, 1.0, 0.5), 1e-4, 0.19);
        }
        let before = s.clone();
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        assert!(seed(&mut s, &params, 0.1, &mut rng).is_empty());
        assert_eq!(s, before);
        // One admissible sample far away seeds, with the radius its wall distance allows.
        s.push(Vec3::new(10.0, 0.0, 0.0), Vec3::z(), 1e-4, 0.25);
        let seeds = seed(&mut s, &params, 0.1, &mut rng);
        assert_eq!(seeds.len(), 1);
        assert_eq!(seeds[0].x, Vec3::new(10.0, 0.0, 0.0));
        assert!((kernel::radius(seeds[0].sigma) - 0.25).abs() < 1e-15);
        assert_eq!(s.omega[..20], before.omega[..]);
    }

    #[test]
    fn only_nonzero_samples_draw() {
        let params = SeedingParams {
            c_p: 1e12,
            u0: 1.0,
            r_max: 0.5,
            r_min: 0.0,
        };
        let mut s = SeedSamples::default();
        s.push(Vec3::zeros(), Vec3::zeros(), 1e-3, 1.0);
        s.push(Vec3::x(), Vec3::z(), 1e-3, 1.0);
        // Within reach of the seed at x, emptied before its turn.
        s.push(Vec3::new(1.2, 0.0, 0.0), Vec3::y(), 1e-3, 1.0);
        s.push(Vec3::new(5.0, 0.0, 0.0), Vec3::x(), 1e-3, 1.0);
        let mut rng = ChaCha8Rng::seed_from_u64(21);
        let seeds = seed(&mut s, &params, 0.1, &mut rng);
        assert_eq!(seeds.len(), 2);
        assert_eq!(seeds[0].samples, 2);
        assert!(s.omega.iter().all(|w| *w == Vec3::zeros()));
        // Exactly two numbers were drawn, one per sample that still held vorticity.
        let mut fresh = ChaCha8Rng::seed_from_u64(21);
        fresh.random::<Real>();
        fresh.random::<Real>();
        assert_eq!(rng.random::<u64>(), fresh.random::<u64>());
    }

    #[test]
    fn seeding_is_reproducible() {
        // p_T between 0 and 1 at every nonzero sample.
        let params = SeedingParams {
            c_p: 0.5,
            u0: 1.0,
            r_max: 0.25,
            r_min: 0.05,
        };
        let run = |rng_seed: u64| {
            let mut s = lattice(8, 0.1);
            let mut rng = ChaCha8Rng::seed_from_u64(rng_seed);
            let seeds = seed(&mut s, &params, 0.5, &mut rng);
            (seeds, s)
        };
        let (a, sa) = run(11);
        assert!(!a.is_empty() && a.len() < 100, "{} seeds", a.len());
        assert_eq!(run(11), (a.clone(), sa));
        assert_ne!(run(12).0, a);
    }

    #[test]
    fn no_seeds_without_reference_speed() {
        let mut s = lattice(4, 0.1);
        let before = s.clone();
        let params = SeedingParams {
            c_p: 1e12,
            u0: 0.0,
            r_max: 0.25,
            r_min: 0.0,
        };
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        assert!(seed(&mut s, &params, 0.1, &mut rng).is_empty());
        assert_eq!(s, before);
    }

    #[test]
    fn scatter_keeps_strength_and_clears_walls() {
        // Sites along a line at wall distances 0.005, 0.015, ..., 0.995 (site k at x = k),
        // clear of the band edges below.
        let sites: Vec<Vec3> = (0..100).map(|k| Vec3::new(k as Real, 0.0, 0.0)).collect();
        let dist: Vec<Real> = (0..100).map(|k| k as Real * 0.01 + 0.005).collect();
        let band = 0.05;
        let n = 3000;
        let mut seeds: Vec<Seed> = (0..n)
            .map(|k| {
                let r = 0.1 + 0.2 * (k % 5) as Real;
                Seed {
                    x: Vec3::zeros(),
                    omega: Vec3::new(0.0, 0.0, 1.0 + k as Real),
                    sigma: kernel::sigma_for_radius(r),
                    removed: Vec3::new(k as Real, 1.0, 2.0),
                    samples: k,
                }
            })
            .collect();
        // Radius 1.2: no site admits it.
        seeds[8].sigma = kernel::sigma_for_radius(1.2);
        let original = seeds.clone();
        let mut rng = ChaCha8Rng::seed_from_u64(8);
        scatter(&mut seeds, &sites, &dist, band, &mut rng);
        assert_eq!(seeds.len(), n - 1);
        let kept = original.iter().filter(|s| s.samples != 8);
        let mut mean_axis = Vec3::zeros();
        for (s, o) in seeds.iter().zip(kept) {
            assert_eq!(
                (s.sigma, s.removed, s.samples),
                (o.sigma, o.removed, o.samples)
            );
            assert!((s.omega.norm() - o.omega.norm()).abs() <= 1e-12 * o.omega.norm());
            let k = sites
                .iter()
                .position(|x| *x == s.x)
                .expect("moved to a site");
            let r = kernel::radius(s.sigma);
            assert!(dist[k] >= r, "site at {} for radius {r}", dist[k]);
            assert!(dist[k] < r + band, "site at {} for radius {r}", dist[k]);
            mean_axis += s.omega / s.omega.norm();
        }
        // Uniform axes: each component has variance 1/3, so its mean lies within 5 sd.
        mean_axis /= seeds.len() as Real;
        let sd = (1.0 / (3.0 * seeds.len() as Real)).sqrt();
        assert!(mean_axis.amax() < 5.0 * sd, "mean axis {mean_axis:?}");
        // Seeds of radius 0.1 spread over all five sites of their band [0.1, 0.15).
        let used: std::collections::BTreeSet<usize> = seeds
            .iter()
            .filter(|s| (kernel::radius(s.sigma) - 0.1).abs() < 1e-12)
            .map(|s| s.x.x as usize)
            .collect();
        assert_eq!(
            used.into_iter().collect::<Vec<_>>(),
            vec![10, 11, 12, 13, 14]
        );
    }

    #[test]
    fn scatter_falls_back_beyond_the_band() {
        let sites = vec![Vec3::x(), Vec3::y(), Vec3::z()];
        let dist = vec![0.05, 2.0, 3.0];
        let mut seeds = vec![Seed {
            x: Vec3::zeros(),
            omega: Vec3::new(0.0, 2.0, 0.0),
            sigma: kernel::sigma_for_radius(0.5),
            removed: Vec3::y(),
            samples: 3,
        }];
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        scatter(&mut seeds, &sites, &dist, 0.1, &mut rng);
        assert_eq!(seeds.len(), 1);
        assert!(seeds[0].x == Vec3::y() || seeds[0].x == Vec3::z());
        assert!((seeds[0].omega.norm() - 2.0).abs() < 1e-12);
    }
}
