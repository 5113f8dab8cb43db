//! Vortex-particle dynamics (Pfaff et al. 2009, section 4.2): advection, stretching with the
//! strength kept, and the energy dynamics of Eq. 10: dissipation of particles too small for the
//! grid, the cascade (split) in the inertial subrange and merging in the model-dependent range.
//!
//! The boundary between the ranges is a radius: particles with radius `sqrt(6) sigma` at most
//! `inertial_radius` are in the inertial subrange and split; larger ones merge.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::{kernel, VelocitySource, VortexError, VortexParticles};
use crate::spatial::PointHash;
use crate::{Real, Vec3};

/// Parameters of the energy dynamics.
#[derive(Debug, Clone)]
pub struct DynamicsSettings {
    /// Particles with a radius below this many cells are dissipated (2 in the paper).
    pub dissipation_cells: Real,
    /// Radius (m) at and below which a particle is in the inertial subrange.
    pub inertial_radius: Real,
    /// Children per split, n (2 in the paper).
    pub children: usize,
    /// sigma_child / sigma_parent; the default 2^(-1/3) gives two children the parent's volume.
    pub child_scale: Real,
    /// C of the cascade time scale dt = C (kappa_a^(-2/3) - kappa_b^(-2/3)), s / m^(2/3).
    pub cascade_time: Real,
    /// Children are displaced by this fraction of the parent's sigma, in a random direction.
    pub jitter_position: Real,
    /// Children's axes are tilted by up to this angle, rad.
    pub jitter_angle: Real,
}

impl Default for DynamicsSettings {
    fn default() -> Self {
        Self {
            dissipation_cells: 2.0,
            inertial_radius: 0.0,
            children: 2,
            child_scale: 0.5_f64.powf(1.0 / 3.0),
            cascade_time: 1.0,
            jitter_position: 0.25,
            jitter_angle: 0.1,
        }
    }
}

impl DynamicsSettings {
    /// Checks the ranges.
    pub fn validate(&self) -> Result<(), VortexError> {
        let bad = |what: &str| Err(VortexError::InvalidSettings(what.into()));
        if self.dissipation_cells.is_nan() || self.dissipation_cells < 0.0 {
            return bad("dissipation_cells must be >= 0");
        }
        if self.inertial_radius.is_nan() || self.inertial_radius < 0.0 {
            return bad("inertial_radius must be >= 0");
        }
        if self.children < 2 {
            return bad("children must be at least 2");
        }
        if !(self.child_scale > 0.0 && self.child_scale < 1.0) {
            return bad("child_scale must lie in (0, 1)");
        }
        if !(self.cascade_time >= 0.0 && self.jitter_position >= 0.0 && self.jitter_angle >= 0.0) {
            return bad("cascade_time and the jitters must be >= 0");
        }
        Ok(())
    }

    /// Time a particle of scale `sigma` lives before it splits (Kolmogorov time scale with
    /// kappa = 1 / sigma).
    pub fn split_time(&self, sigma: Real) -> Real {
        let child = sigma * self.child_scale;
        self.cascade_time * (sigma.powf(2.0 / 3.0) - child.powf(2.0 / 3.0))
    }
}

/// Second-order (midpoint) advection with the source's velocity.
pub fn advect<S: VelocitySource + Sync + ?Sized>(p: &mut VortexParticles, source: &S, dt: Real) {
    p.x.par_iter_mut().for_each(|x| {
        let mid = *x + 0.5 * dt * source.velocity(x);
        *x += dt * source.velocity(&mid);
    });
}

/// Vortex stretching, omega += dt (omega . grad) u, then rescaled to the old strength: only
/// the axis turns (section 4.2).
pub fn stretch<S: VelocitySource + Sync + ?Sized>(p: &mut VortexParticles, source: &S, dt: Real) {
    p.omega
        .par_iter_mut()
        .zip(p.x.par_iter())
        .for_each(|(w, x)| {
            let strength = w.norm();
            let turned = *w + dt * (source.velocity_gradient(x) * *w);
            let n = turned.norm();
            if n > 0.0 {
                *w = turned * (strength / n);
            }
        });
}

/// Removes the particles whose radius is below `cells` cells of size `dx`; returns how many.
pub fn dissipate(p: &mut VortexParticles, dx: Real, cells: Real) -> usize {
    let keep: Vec<bool> = p
        .sigma
        .iter()
        .map(|&s| kernel::radius(s) >= cells * dx)
        .collect();
    let removed = keep.iter().filter(|k| !**k).count();
    p.retain(&keep);
    removed
}

/// Splits every inertial-range particle whose age reached its cascade time into `children`
/// particles of scale `child_scale sigma` with E_parent / E_child = n (kappa_a/kappa_b)^(-5/3);
/// returns how many split.
pub fn split(p: &mut VortexParticles, s: &DynamicsSettings, rng: &mut ChaCha8Rng) -> usize {
    let n = s.children as Real;
    let mut keep = vec![true; p.len()];
    let mut born = VortexParticles::new();
    for (i, kept) in keep.iter_mut().enumerate() {
        let sigma = p.sigma[i];
        if kernel::radius(sigma) > s.inertial_radius || p.age[i] < s.split_time(sigma) {
            continue;
        }
        *kept = false;
        let child = sigma * s.child_scale;
        // E_b = E_a (sigma_b/sigma_a)^(5/3) / n with E ~ omega^2 sigma^5.
        let strength = p.omega[i].norm() * s.child_scale.powf(-5.0 / 3.0) / n.sqrt();
        let a = axis_or_x(&p.omega[i]);
        for _ in 0..s.children {
            let offset = random_unit(rng) * (s.jitter_position * sigma * rng.random::<Real>());
            let tilt = random_unit(rng).cross(&a);
            let angle = s.jitter_angle * rng.random::<Real>();
            let axis = if tilt.norm() > 1e-12 {
                nalgebra::Rotation3::new(tilt.normalize() * angle) * a
            } else {
                a
            };
            born.x.push(p.x[i] + offset);
            born.omega.push(axis * strength);
            born.sigma.push(child);
            born.age.push(0.0);
        }
    }
    p.retain(&keep);
    let count = born.len() / s.children;
    p.x.extend(born.x);
    p.omega.extend(born.omega);
    p.sigma.extend(born.sigma);
    p.age.extend(born.age);
    count
}

/// Merges model-range particles (radius above `inertial_radius`) closer than the smaller of
/// their radii, each at most once per call, nearest partner first, in index order. The merged
/// particle keeps E = E1 + E2 and E / V = E1 / V1 + E2 / V2 (V ~ sigma^3), sits at the
/// energy-weighted centre and points along the energy-weighted mean axis. Returns how many
/// pairs merged.
pub fn merge(p: &mut VortexParticles, s: &DynamicsSettings) -> usize {
    let model: Vec<bool> = p
        .sigma
        .iter()
        .map(|&sg| kernel::radius(sg) > s.inertial_radius)
        .collect();
    let r_max = (0..p.len())
        .filter(|&i| model[i])
        .map(|i| p.radius(i))
        .fold(0.0, Real::max);
    if r_max == 0.0 {
        return 0;
    }
    let hash = PointHash::new(&p.x, r_max);
    let mut used = vec![false; p.len()];
    let mut keep = vec![true; p.len()];
    let mut merged = 0;
    for i in 0..p.len() {
        if used[i] || !model[i] {
            continue;
        }
        let mut best: Option<(Real, usize)> = None;
        hash.for_each_near(&p.x[i], p.radius(i), |j| {
            let d = (p.x[i] - p.x[j]).norm();
            if j != i && !used[j] && model[j] && d < p.radius(j) && best.is_none_or(|b| d < b.0) {
                best = Some((d, j));
            }
        });
        let Some((_, j)) = best else { continue };
        used[i] = true;
        used[j] = true;
        keep[j] = false;
        let (e1, e2) = (p.energy(i), p.energy(j));
        let (v1, v2) = (p.sigma[i].powi(3), p.sigma[j].powi(3));
        let energy = e1 + e2;
        let density = e1 / v1 + e2 / v2;
        if energy <= 0.0 {
            continue;
        }
        let sigma = (energy / density).cbrt();
        let strength = (energy / (kernel::ENERGY * sigma.powi(5))).sqrt();
        let dir = e1 * axis_or_x(&p.omega[i]) + e2 * axis_or_x(&p.omega[j]);
        let dir = if dir.norm() > 1e-12 * energy {
            dir.normalize()
        } else {
            axis_or_x(&p.omega[if e1 >= e2 { i } else { j }])
        };
        p.x[i] = (e1 * p.x[i] + e2 * p.x[j]) / energy;
        p.omega[i] = dir * strength;
        p.sigma[i] = sigma;
        p.age[i] = 0.0;
        merged += 1;
    }
    p.retain(&keep);
    merged
}

/// Unit axis, or x for a zero vector.
fn axis_or_x(w: &Vec3) -> Vec3 {
    let n = w.norm();
    if n > 0.0 {
        w / n
    } else {
        Vec3::x()
    }
}

/// A direction drawn uniformly on the sphere: z uniform in [-1, 1] (Archimedes) and a uniform
/// azimuth.
pub fn random_unit(rng: &mut ChaCha8Rng) -> Vec3 {
    let z: Real = 2.0 * rng.random::<Real>() - 1.0;
    let phi = std::f64::consts::TAU * rng.random::<Real>();
    let s = (1.0 - z * z).max(0.0).sqrt();
    Vec3::new(s * phi.cos(), s * phi.sin(), z)
}

/// What one dynamics step did: the count changes by `born - split - merged - dissipated`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct StepReport {
    pub dissipated: usize,
    /// Particles that split.
    pub split: usize,
    /// Children born of the splits.
    pub born: usize,
    /// Pairs merged into one.
    pub merged: usize,
}

/// The dynamics with their settings and seeded generator.
#[derive(Debug, Clone)]
pub struct Dynamics {
    pub settings: DynamicsSettings,
    rng: ChaCha8Rng,
}

/// The split displacements' generator is the dynamics' only state between steps.
impl crate::state::Persist for Dynamics {
    fn save(&self, into: &mut crate::state::Saver) {
        into.rng("rng", &self.rng);
    }

    fn restore(&mut self, from: &crate::state::Restorer) -> Result<(), crate::state::StateError> {
        self.rng = from.rng("rng")?;
        Ok(())
    }
}

impl Dynamics {
    /// Dynamics with validated settings and a seed for the split displacements.
    pub fn new(settings: DynamicsSettings, seed: u64) -> Result<Self, VortexError> {
        settings.validate()?;
        Ok(Self {
            settings,
            rng: ChaCha8Rng::seed_from_u64(seed),
        })
    }

    /// One step of section 4.2 on a grid of cell size `dx`: advect, stretch, age, merge,
    /// split, dissipate.
    pub fn step<S: VelocitySource + Sync + ?Sized>(
        &mut self,
        p: &mut VortexParticles,
        source: &S,
        dt: Real,
        dx: Real,
    ) -> StepReport {
        stretch(p, source, dt);
        advect(p, source, dt);
        p.age.iter_mut().for_each(|a| *a += dt);
        let merged = merge(p, &self.settings);
        let split = split(p, &self.settings, &mut self.rng);
        let dissipated = dissipate(p, dx, self.settings.dissipation_cells);
        StepReport {
            dissipated,
            split,
            born: split * self.settings.children,
            merged,
        }
    }
}
