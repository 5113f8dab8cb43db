//! Synthetic turbulence on the grid's inflow sides: the normal velocity of every inflow face is
//! the side's own plus a fluctuation, a sum of random Fourier modes (Kraichnan 1970's
//! random-mode field) carried past the side at the inflow velocity (Taylor's frozen
//! turbulence), so the same scene on a finer grid receives the same disturbances.
//!
//! Why: a backward-facing step's shear layer is convectively unstable. It amplifies the
//! disturbances that reach it and forgets them once they leave, so a steady inflow lets a fine,
//! nearly inviscid grid stay laminar behind the step. Le, Moin and Kim (1997), the simulation
//! Pfaff et al. 2009 cite for Figure 8's reference, feed their step a turbulent inflow for this
//! reason.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::{Real, Vec3};

/// Seed stream of the modes, so they do not repeat another stage's random numbers.
const INFLOW_STREAM: u64 = 0x1f10_7b0c;

/// Shortest and longest wavelength of the modes, in eddy sizes.
const WAVELENGTHS: [Real; 2] = [0.5, 2.0];

fn default_modes() -> usize {
    64
}

/// `[grid.inflow_turbulence]`: fluctuations added to every inflow side's normal velocity.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct InflowTurbulence {
    /// Root-mean-square of the normal fluctuation, a fraction of the local inflow speed, in
    /// (0, 0.5].
    pub intensity: Real,
    /// Eddy size l, m: the modes' wavelengths are spread log-uniformly over [l/2, 2 l].
    pub length: Real,
    /// Number of random modes, in 1..=4096 (default 64).
    #[serde(default = "default_modes")]
    pub modes: usize,
}

/// The random modes of one run: wave vectors and phases drawn from the scene's seed.
#[derive(Debug, Clone, PartialEq)]
pub struct InflowModes {
    pub spec: InflowTurbulence,
    modes: Vec<(Vec3, Real)>,
}

impl InflowModes {
    /// Draws `spec.modes` wave vectors, uniform in direction, with wavelengths log-uniform over
    /// [`WAVELENGTHS`] eddy sizes, and phases uniform in [0, 2 pi).
    pub fn new(spec: &InflowTurbulence, seed: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ INFLOW_STREAM);
        let tau = std::f64::consts::TAU as Real;
        let modes = (0..spec.modes)
            .map(|_| {
                let z: Real = rng.random_range(-1.0..1.0);
                let azimuth: Real = rng.random_range(0.0..tau);
                let across = (1.0 - z * z).sqrt();
                let direction = Vec3::new(across * azimuth.cos(), across * azimuth.sin(), z);
                let [short, long] = WAVELENGTHS.map(|w| (w * spec.length).ln());
                let wavelength = rng.random_range(short..long).exp();
                (direction * (tau / wavelength), rng.random_range(0.0..tau))
            })
            .collect();
        Self {
            spec: spec.clone(),
            modes,
        }
    }

    /// The fluctuation of unit variance at `x` (m) and time `t` (s) in a flow passing at
    /// `carrier` (m/s): sqrt(2 / N) sum_m cos(k_m . (x - carrier t) + phi_m). Over time and
    /// phases its mean is 0 and its mean square 1 (each cosine contributes 1/2).
    pub fn unit(&self, x: &Vec3, t: Real, carrier: &Vec3) -> Real {
        let at = x - carrier * t;
        let sum: Real = self
            .modes
            .iter()
            .map(|(k, phase)| (k.dot(&at) + phase).cos())
            .sum();
        sum * (2.0 / self.modes.len() as Real).sqrt()
    }

    /// The normal velocity of an inflow face at `x` whose side prescribes `base` there:
    /// base_a + intensity |base| unit(x, t, base), so the fluctuation scales with the local
    /// speed (none where a profiled inflow is at rest against a wall).
    pub fn normal_velocity(&self, base: &Vec3, a: usize, x: &Vec3, t: Real) -> Real {
        base[a] + self.spec.intensity * base.norm() * self.unit(x, t, base)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec() -> InflowTurbulence {
        InflowTurbulence {
            intensity: 0.1,
            length: 0.25,
            modes: 64,
        }
    }

    /// Sampled over a long time at a point of the side, the fluctuation has the mean and rms it
    /// is built for, and its time scale is the eddy size over the carrier speed: the sample
    /// autocorrelation one eddy-passing apart has fallen well below 1.
    #[test]
    fn the_fluctuation_has_zero_mean_and_the_set_intensity() {
        let modes = InflowModes::new(&spec(), 7);
        let carrier = Vec3::new(1.0, 0.0, 0.0);
        let x = Vec3::new(0.0, 0.3, 0.1);
        let dt = 0.01;
        let n = 200_000;
        let samples: Vec<Real> = (0..n)
            .map(|i| modes.normal_velocity(&carrier, 0, &x, i as Real * dt) - 1.0)
            .collect();
        let mean = samples.iter().sum::<Real>() / n as Real;
        let rms = (samples.iter().map(|s| s * s).sum::<Real>() / n as Real).sqrt();
        assert!(mean.abs() < 0.01, "mean fluctuation {mean}");
        assert!((rms - 0.1).abs() < 0.01, "rms {rms} against intensity 0.1");
        let lag = (0.25 / dt) as usize;
        let lagged: Real = samples
            .windows(lag + 1)
            .map(|w| w[0] * w[lag])
            .sum::<Real>()
            / (n - lag) as Real;
        assert!(
            lagged / (rms * rms) < 0.5,
            "correlation {}",
            lagged / (rms * rms)
        );
    }

    /// The same seed draws the same modes; another seed other ones.
    #[test]
    fn the_modes_follow_the_seed() {
        let x = Vec3::new(0.0, 0.2, 0.4);
        let c = Vec3::new(1.0, 0.0, 0.0);
        let a = InflowModes::new(&spec(), 1).unit(&x, 0.5, &c);
        assert_eq!(a, InflowModes::new(&spec(), 1).unit(&x, 0.5, &c));
        assert_ne!(a, InflowModes::new(&spec(), 2).unit(&x, 0.5, &c));
    }
}
