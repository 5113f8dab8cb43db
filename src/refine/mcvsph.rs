//! Monte Carlo vortical SPH (Ye et al., Algorithms 1 and 2, Eqs. 18–29).
//!
//! - At v^n (after the divergence solve): omega^n = curl v^n (Eq. 21, with the curl's sign
//!   fixed, see `crate::sph::operators`) and the stretching (omega^n . grad) v^n of its ideal
//!   successor omega^(n+1) = omega^n + dt ((omega^n . grad) v + nu Laplacian omega^n) (Eq. 18,
//!   Alg. 1). The Laplacian of omega^n is taken after the pressure solve, in the pass that
//!   takes the curl there: the positions have not moved in between, so it is the same sum.
//!   Algorithm 1 stretches with the gradient of v~ = v^n + dt f_non-pressure; we use the
//!   gradient of v^n, which differs only by dt times the gradient of the viscous acceleration
//!   (gravity is uniform and drops out), and saves a pass.
//! - After the pressure solve: the loss omega_loss = omega^(n+1) - curl v^(n+1) (Eq. 20).
//!   **Loss reference.** Ye et al. allow the curl before or after the projection because the
//!   continuous curl of a pressure gradient vanishes; the discrete SPH one does not, and the
//!   projection is where the paper (Fig. 2) says detail is lost, so we take the curl *after*
//!   the projection: the loss then includes what the pressure solve dissipated, and it is
//!   measured on the very field the correction is added to.
//! - The loss smoothed onto the vortex particles (Eq. 28) and the Monte Carlo Biot–Savart
//!   correction (Eq. 26 with P_k = 1 / N_f, Eq. 27), added to every fluid velocity (Eq. 29).
//!   Each term carries its own particle's volume c V_k (docs/src/paper-notes.md, "Eq. 26"), so the
//!   prefactor is c N_f / N.
//!
//! **Vortex particles.** A seeded random subset of N = round(fraction N_f) fluid particles,
//! drawn once (Algorithm 2, line 1) and moving with them.
//!
//! **Mollified kernel.** K(x) = -x / (4 pi |x|^3) (Eq. 14) is singular; we use the
//! Rosenhead–Moore kernel K_d(x) = -x / (4 pi (|x|^2 + d^2)^(3/2)) with core d = one particle
//! spacing: it is the exact field of a vortex blob of that size, bounded by
//! 1 / (6 sqrt(3) pi d^2) |beta|, and K_d(0) = 0, so the k = i term vanishes by itself.
//!
//! **Far field.** The sum over the N vortex particles at all N_f fluid particles is evaluated
//! by the treecode of `super::biot_savart` (opening parameter `theta` of the scene, default
//! `super::biot_savart::DEFAULT_THETA`), O(N_f log N)
//! instead of O(N_f N) (directly below [`DIRECT_BELOW`] vortex particles, where that is
//! cheaper); its error is a small fraction of the Monte Carlo error.

use super::lanes::F4;
use super::packed::{fill, Field, Packed, Quantity};
use super::registry::{Interval, Method, MethodParams};
use super::{add_scaled, StepContext, StepHook};
use crate::spatial::{permute, resize};
use crate::sph::operators::{curl_of, Operators, WallField};
use crate::state::{Persist, Restorer, Saver, StateError};
use crate::{Real, Vec3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::biot_savart::{biot_savart, BiotSavartTree};

/// MCVSPH state.
/// `method = "mcvsph"`.
// Kept between steps: the sampled and reach flags; omega, positions and velocity packed;
// stretch and loss.
pub const METHOD: Method = Method::new::<Params>(
    "mcvsph",
    "Monte Carlo vortical SPH (Ye et al., Algorithm 2)",
    &[
        ("sample_fraction", Interval::open_closed(0.0, 1.0)),
        ("volume_coefficient", Interval::closed_open(0.0, 1.0)),
        ("theta", Interval::closed_open(0.0, 1.0)),
    ],
)
.keeping(
    2 * std::mem::size_of::<bool>() as u64
        + 3 * std::mem::size_of::<F4>() as u64
        + 2 * std::mem::size_of::<Vec3>() as u64,
);

/// The keys of `method = "mcvsph"`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Fraction N / N_f of fluid particles paired with vortex particles.
    #[serde(default = "default_sample_fraction")]
    pub sample_fraction: Real,
    /// Volume coefficient c of the vortex particles (Ye et al. Eq. 24).
    #[serde(default = "default_volume_coefficient")]
    pub volume_coefficient: Real,
    /// Opening parameter of the Biot–Savart treecode: its error grows about as theta^2 and its
    /// cost falls; 0 sums every pair directly.
    #[serde(default = "default_theta")]
    pub theta: Real,
    /// The wall samples take part in the method's difference operators. It models no-slip
    /// walls: pair it with `viscosity.boundary > 0` (the book's SPH refinements chapter says why it is off).
    #[serde(default)]
    pub walls: bool,
}

/// Ye et al. Sec. 5.1.1: about 1 % of the fluid particles.
fn default_sample_fraction() -> Real {
    0.01
}
/// Ye et al. Figs. 5, 8, 13.
fn default_volume_coefficient() -> Real {
    0.05
}
/// Under 1 % of the signal from the direct sum on the dam break (`super::biot_savart`).
fn default_theta() -> Real {
    super::biot_savart::DEFAULT_THETA
}

impl MethodParams for Params {
    fn build(&self, n: usize, seed: u64) -> Box<dyn StepHook> {
        Box::new(Mcvsph::new(
            n,
            self.sample_fraction,
            self.volume_coefficient,
            self.theta,
            seed,
            self.walls,
        ))
    }
}

pub struct Mcvsph {
    volume_coefficient: Real,
    /// Opening parameter of the Biot–Savart treecode.
    theta: Real,
    /// Boundary samples take part in the operators.
    walls: bool,
    /// Whether each fluid particle carries a vortex particle.
    sampled: Vec<bool>,
    /// The fraction sampled, and the generator that samples particles entering at an inflow.
    fraction: Real,
    rng: ChaCha8Rng,
    /// omega^n = curl v^n of the current step, packed (its Laplacian reads it at the
    /// neighbours of `reach`).
    omega: Field,
    /// The stretching (omega^n . grad) v^n, on `reach`.
    stretch: Vec<Vec3>,
    /// The vortex particles and their fluid neighbours this step: the only particles whose
    /// loss the smoothing of Eq. 28 reads.
    reach: Vec<bool>,
    /// Buffers of one step (kept for their memory): packed positions and velocity, the loss.
    positions: Vec<F4>,
    velocity: Field,
    loss: Vec<Vec3>,
}

impl Mcvsph {
    /// Draws round(`fraction` n) vortex particles (at least one) among `n` fluid particles;
    /// `theta` is the treecode's opening parameter.
    pub fn new(
        n: usize,
        fraction: Real,
        volume_coefficient: Real,
        theta: Real,
        seed: u64,
        walls: bool,
    ) -> Self {
        let count = ((fraction * n as Real).round() as usize).clamp(1.min(n), n);
        let mut sampled = vec![false; n];
        for i in sample_indices(n, count, seed) {
            sampled[i] = true;
        }
        Self {
            volume_coefficient,
            theta,
            walls,
            sampled,
            fraction,
            rng: ChaCha8Rng::seed_from_u64(seed ^ INFLOW_STREAM),
            omega: Field::default(),
            stretch: Vec::new(),
            reach: Vec::new(),
            positions: Vec::new(),
            velocity: Field::default(),
            loss: Vec::new(),
        }
    }
}

impl Mcvsph {
    /// Marks in `reach` the vortex particles and their fluid neighbours, from the vortex
    /// particles' own neighbour lists (fluid neighbourhoods are symmetric): a pass over 1 % of
    /// the lists instead of all of them.
    fn mark_reach(&mut self, ops: &Operators) {
        self.reach.clone_from(&self.sampled);
        for s in (0..self.reach.len()).filter(|&i| self.sampled[i]) {
            for &j in ops.nb.fluid.of(s) {
                self.reach[j as usize] = true;
            }
        }
    }
}

/// Salt of the generator that samples entering particles, apart from the initial draw's.
const INFLOW_STREAM: u64 = 0x1f10_u64;

/// `count` distinct indices below `n`, uniformly at random from the seed.
pub fn sample_indices(n: usize, count: usize, seed: u64) -> Vec<usize> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rand::seq::index::sample(&mut rng, n, count).into_vec()
}

/// Which particles carry a vortex particle and the generator that draws those of entering
/// particles. The vorticity, stretching and reach are taken afresh before the step reads
/// them; the rest are one step's buffers.
impl Persist for Mcvsph {
    fn save(&self, into: &mut Saver) {
        into.bytes(
            "sampled",
            &self.sampled.iter().map(|&s| s.into()).collect::<Vec<_>>(),
        );
        into.rng("rng", &self.rng);
    }

    fn restore(&mut self, from: &Restorer) -> Result<(), StateError> {
        let sampled = from.bytes("sampled")?.iter().map(|&s| s != 0).collect();
        self.rng = from.rng("rng")?;
        self.sampled = sampled;
        Ok(())
    }
}

impl StepHook for Mcvsph {
    fn name(&self) -> &'static str {
        "refine"
    }

    fn describe(&self) -> String {
        super::plan_line(
            format!(
                "MCVSPH (Ye et al., Alg. 2) after the pressure solve, {} % vortex particles, \
                 c = {}, treecode theta = {}",
                100.0 * self.fraction,
                self.volume_coefficient,
                self.theta
            ),
            self.walls,
        )
    }

    fn walls(&self) -> bool {
        self.walls
    }

    fn permute(&mut self, perm: &[u32]) {
        permute(&mut self.sampled, perm);
    }

    /// Particles entering at an inflow carry a vortex particle with probability `fraction`,
    /// so the sampled share of the fluid stays what the scene asked for.
    fn resize(&mut self, keep: &[bool], added: usize) {
        resize(&mut self.sampled, keep, 0, false);
        let Self { rng, fraction, .. } = self;
        let drawn: Vec<bool> = (0..added)
            .map(|_| rng.random::<Real>() < *fraction)
            .collect();
        self.sampled.extend(drawn);
    }

    fn particles(&self) -> Option<usize> {
        Some(self.sampled.len())
    }

    fn before_advection(&mut self, ctx: &StepContext, v: &mut [Vec3], _accel: &mut [Vec3]) {
        if self.volume_coefficient == 0.0 {
            return;
        }
        // Only the loss next to a vortex particle is used (Eq. 28), so the ideal vorticity is
        // needed on `reach`, and the vorticity one neighbourhood further (its Laplacian). The
        // stretching term needs the whole gradient only on `reach`; elsewhere the curl is
        // enough. At a few per cent vortex particles that ring holds most of the fluid, and
        // taking the curl everywhere costs less than finding the ring (the book's benchmarks
        // chapter, "Measurements behind design choices").
        self.mark_reach(&ctx.ops);
        let ops = Packed::new(ctx.ops, &mut self.positions, v);
        let (reach, velocity) = (&self.reach, &mut self.velocity);
        ops.pack(v, velocity);
        let (omega, stretch) = (&mut self.omega, &mut self.stretch);
        ops.field_with(omega, stretch, Quantity::Vorticity, None, |i| {
            if reach[i] {
                let g = ops.gradient_at(i, velocity, WallField::Velocity);
                let omega = curl_of(&g);
                (omega, g * omega)
            } else {
                (ops.curl_at(i, velocity, WallField::Velocity), Vec3::zeros())
            }
        });
    }

    fn after_pressure(&mut self, ctx: &StepContext, v: &mut [Vec3]) {
        if self.volume_coefficient == 0.0 || self.omega.len() != v.len() {
            return;
        }
        let ops = Packed::new(ctx.ops, &mut self.positions, v);
        let (omega, stretch, (nu, dt)) = (&self.omega, &self.stretch, (ctx.nu, ctx.dt));
        // The ideal omega^(n+1) = omega^n + dt ((omega^n . grad) v^n + nu Laplacian omega^n)
        // (Eq. 18, Alg. 1) less the curl after the projection (Eq. 20), in one pass: the
        // positions have not moved since omega^n was taken, so its Laplacian is the same here.
        let (reach, now) = (&self.reach, &mut self.velocity);
        ops.pack(v, now);
        fill(&mut self.loss, v.len(), |i| {
            if reach[i] {
                let (curl, diffusion) = ops.curl_diffusion_at(i, now, omega, nu);
                omega.vec(i) + dt * (stretch[i] + diffusion) - curl
            } else {
                Vec3::zeros()
            }
        });
        let loss = &self.loss;
        let ops = &ctx.ops;
        let samples: Vec<usize> = (0..v.len()).filter(|&i| self.sampled[i]).collect();
        let k = ops.nb.kernel;
        // Smoothed loss at each vortex particle (Eq. 28; walls carry none), times its volume.
        let beta: Vec<Vec3> = samples
            .par_iter()
            .map(|&s| {
                let mut smooth = ops.volume[s] * k.w_zero() * loss[s];
                ops.nb.fluid_pairs(s, |j, xsj| {
                    smooth += ops.volume[j] * k.w(xsj.norm()) * loss[j]
                });
                self.volume_coefficient * ops.volume[s] * smooth
            })
            .collect();
        let sources: Vec<Vec3> = samples.iter().map(|&s| ops.nb.x[s]).collect();
        let correction =
            monte_carlo_biot_savart(ops.nb.x, &sources, &beta, v.len(), ctx.spacing, self.theta);
        add_scaled(v, &correction, 1.0);
    }
}

/// Below this many vortex particles the direct sum is cheaper than the treecode, and exact
/// (instructions on the dam-break vorticity at 1 %: 220 sources, 20.5 M direct against
/// 20.4 M by the tree; 467 sources, 84 M against 54 M).
pub const DIRECT_BELOW: usize = 256;

/// The Monte Carlo estimate (Ye Eq. 26, P_k = 1 / N_f) of the velocity that a population of
/// `population` vortex particles induces at `targets`, from a uniform sample of them at
/// `sources` with strengths `beta` (vorticity times volume): (N_f / N) times the sample's
/// Biot–Savart sum, by the treecode with opening parameter `theta` (0, or fewer sources than
/// [`DIRECT_BELOW`]: the direct sum). Unbiased for the sum over the whole population (up to
/// the tree's error).
pub fn monte_carlo_biot_savart(
    targets: &[Vec3],
    sources: &[Vec3],
    beta: &[Vec3],
    population: usize,
    core: Real,
    theta: Real,
) -> Vec<Vec3> {
    if sources.is_empty() {
        return vec![Vec3::zeros(); targets.len()];
    }
    let scale = population as Real / sources.len() as Real;
    let scaled: Vec<Vec3> = beta.iter().map(|b| scale * b).collect();
    if theta == 0.0 || sources.len() < DIRECT_BELOW {
        biot_savart(targets, sources, &scaled, core)
    } else {
        BiotSavartTree::new(sources, &scaled, core).evaluate(targets, theta)
    }
}
