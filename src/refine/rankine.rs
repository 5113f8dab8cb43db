//! Rankine-vortex velocity refinement (Wang et al. 2020, Algorithm 1, Eqs. 6–15).
//!
//! Each step, before advection: omega^n = curl v^n (Eq. 6), the change since the last step,
//! and the velocity that every fluid particle's Rankine core induces at its neighbours
//! (Eq. 15), added to v^n (Algorithm 1, line 6). The core radius is
//! r_c = beta sqrt(4 alpha nu dt) with the Oseen constant alpha = 1.25643 (Eq. 11).
//!
//! **Sign.** Algorithm 1 prints `delta omega = omega^n - omega^(n-1)` and feeds it to Eq. 15 as
//! is; the text (after Eq. 7) asks for "a negative factor to the vortex centre": the refinement
//! gives back the vorticity a particle *lost*. We therefore induce with
//! `omega^(n-1) - omega^n`, so a vortex that lost vorticity is turned further in its own sense
//! (tested in `tests/refine_methods.rs`).
//!
//! **Reading of line 5.** The velocity at particle j is the sum, over its fluid neighbours i,
//! of what i's core induces at j (Eqs. 13–15 with e_theta from x_i to x_j), not i's own change
//! crossed with its own directions. Inside the core (r <= r_c) the Rankine profile is that of
//! a rigid core, (r / 2) (lost omega_i) x e_theta (Eq. 9 with r/r_c <= 1). Boundary samples
//! carry no vorticity (Wang et al. Sec. 4.3), so only fluid cores induce velocity.
//!
//! **No regeneration.** omega^(n-1) is stored as the curl of the *refined* velocity, so the
//! next step measures only what the dynamics changed, never the refinement's own injection
//! (the feedback Wang et al. Fig. 8 warns against).
//!
//! **Stability bound on r_c.** Summed over a neighbourhood of radius h, Eq. 15 acts on a loss
//! field of wavenumber k like curl dv = C r_c^2 k^2 (lost omega) with C = (2 pi / 9) (h / s)^3
//! (about 5.6 at h = 2 s; the continuum moment of the 1 / r^2 kernel, checked by the restore
//! test at 0.57 for a smooth vortex). At the particle scale k = pi / s this gain exceeds one
//! as soon as r_c > s / (pi sqrt(C)) = 0.13 s, and the refinement then amplifies particle
//! noise step after step (a sloshing tank at nu = 0.01 m^2/s blew up within 200 steps at
//! beta = 1). The core radius is therefore capped at that bound: below it the method never
//! gives back more than was lost at any scale, which is the paper's stability argument.

use super::lanes::{CrossSum, F4};
use super::packed::{Field, Packed, Quantity};
use super::registry::{Interval, Method, MethodParams};
use super::{StepContext, StepHook};
use crate::spatial::{permute, resize};
use crate::sph::operators::{per_particle, WallField};
use crate::state::{Persist, Restorer, Saver, StateError};
use crate::{Real, Vec3};
use rayon::prelude::*;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// `method = "rankine"`.
// Kept between steps: omega^(n-1); lost, positions, omega^n and dv packed.
pub const METHOD: Method = Method::new::<Params>(
    "rankine",
    "Rankine vortex refinement (Wang et al. 2020, Algorithm 1)",
    &[("beta", Interval::closed(0.0, 1.0))],
)
.keeping(std::mem::size_of::<Vec3>() as u64 + 4 * std::mem::size_of::<F4>() as u64);

/// The keys of `method = "rankine"`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Core-radius factor beta: r_c = beta sqrt(4 alpha_Oseen nu dt) (Wang et al. 2020 Eq. 11).
    #[serde(default = "super::registry::one")]
    pub beta: Real,
    /// The wall samples take part in the method's difference operators. It models no-slip
    /// walls: pair it with `viscosity.boundary > 0` (the book's SPH refinements chapter says why it is off).
    #[serde(default)]
    pub walls: bool,
}

impl MethodParams for Params {
    fn build(&self, _n: usize, _seed: u64) -> Box<dyn StepHook> {
        Box::new(Rankine::new(self.beta, self.walls))
    }
}

/// The Oseen parameter of the Lamb–Oseen core growth, r_c = sqrt(4 alpha nu t) (Eq. 10).
pub const OSEEN: Real = 1.25643;

/// Rankine refinement with core-radius factor beta.
pub struct Rankine {
    beta: Real,
    /// Boundary samples take part in the operators.
    walls: bool,
    /// omega^(n-1), per fluid particle; empty before the first step.
    previous: Vec<Vec3>,
    /// Buffers of one step (kept for their memory): the lost vorticity omega^(n-1) -
    /// omega^n, the packed positions, velocity and induced velocity.
    lost: Vec<F4>,
    positions: Vec<F4>,
    now: Field,
    dv: Field,
}

impl Rankine {
    pub fn new(beta: Real, walls: bool) -> Self {
        Self {
            beta,
            walls,
            previous: Vec::new(),
            lost: Vec::new(),
            positions: Vec::new(),
            now: Field::default(),
            dv: Field::default(),
        }
    }
}

/// omega^(n-1), which the next step's loss is measured against (empty before the first
/// step); the rest are one step's buffers.
impl Persist for Rankine {
    fn save(&self, into: &mut Saver) {
        into.vec3s("previous", &self.previous);
    }

    fn restore(&mut self, from: &Restorer) -> Result<(), StateError> {
        self.previous = from.vec3s("previous")?;
        Ok(())
    }
}

impl StepHook for Rankine {
    fn name(&self) -> &'static str {
        "refine"
    }

    fn describe(&self) -> String {
        super::plan_line(
            format!(
                "Rankine vortex (Wang et al. 2020, Alg. 1) before advection, beta = {}",
                self.beta
            ),
            self.walls,
        )
    }

    fn walls(&self) -> bool {
        self.walls
    }

    fn permute(&mut self, perm: &[u32]) {
        if self.previous.len() == perm.len() {
            permute(&mut self.previous, perm);
        }
    }

    fn resize(&mut self, keep: &[bool], added: usize) {
        resize(&mut self.previous, keep, added, Vec3::zeros());
    }

    fn particles(&self) -> Option<usize> {
        (!self.previous.is_empty()).then_some(self.previous.len())
    }

    fn before_advection(&mut self, ctx: &StepContext, v: &mut [Vec3], _accel: &mut [Vec3]) {
        let Self {
            beta,
            walls: _,
            previous,
            lost,
            positions,
            now,
            dv,
        } = self;
        if *beta == 0.0 {
            return;
        }
        let ops = Packed::new(ctx.ops, positions, v);
        let rc = core_radius(
            *beta,
            ctx.nu,
            ctx.dt,
            ctx.spacing,
            ops.ops.nb.kernel.support(),
        );
        ops.pack(v, now);
        if previous.len() != v.len() || rc == 0.0 {
            *previous = per_particle(v.len(), None, |i| ops.curl_at(i, now, WallField::Velocity));
            return;
        }
        // omega^n and the loss in one pass; `previous` becomes omega^n.
        lost.resize(v.len(), F4::ZERO);
        let pairs = previous.par_iter_mut().zip(lost.par_iter_mut());
        pairs.enumerate().for_each(|(i, (previous, lost))| {
            let omega = ops.curl_at(i, now, WallField::Velocity);
            *lost = F4::from_vec(&ops.denoise(Quantity::Vorticity, *previous - omega), 0.0);
            *previous = omega;
        });
        induced_velocity(&ops, lost, rc, dv);
        // v + dv, and curl(v + dv) = curl v + curl dv (walls do not move with the refinement).
        previous
            .par_iter_mut()
            .enumerate()
            .for_each(|(i, omega)| *omega += ops.curl_at(i, dv, WallField::Zero));
        v.par_iter_mut()
            .enumerate()
            .for_each(|(i, v)| *v += dv.vec(i));
    }
}

/// The core radius r_c = beta sqrt(4 alpha nu dt) (Eq. 11), capped at the stability bound
/// s / (pi sqrt(C)), C = (2 pi / 9) (h / s)^3, for spacing s and support h (see the module
/// documentation).
pub fn core_radius(beta: Real, nu: Real, dt: Real, spacing: Real, support: Real) -> Real {
    let c = 2.0 * std::f64::consts::PI / 9.0 * (support / spacing).powi(3);
    let bound = spacing / (std::f64::consts::PI * c.sqrt());
    (beta * (4.0 * OSEEN * nu * dt).sqrt()).min(bound)
}

/// The velocity the Rankine cores of strength `lost` (core radius `rc`) induce at every fluid
/// particle, into `dv`: dv_j = sum_i f(r) lost_i x e_ij, e_ij = (x_j - x_i) / r, with
/// f(r) = r_c^2 / (2 r) outside the core and r / 2 inside (Wang et al. Eqs. 9, 15).
pub fn induced_velocity(ops: &Packed, lost: &[F4], rc: Real, dv: &mut Field) {
    let rc2 = (rc * rc) as f32;
    ops.field(dv, Quantity::Velocity, None, |j| {
        let mut dv = CrossSum::default();
        // x_ji = x_j - x_i points from core i to particle j.
        ops.pairs(j, |i, xji| {
            let r2 = xji.dot3(xji);
            if r2 > 0.0 {
                // f(r) / r, since e = x_ji / r.
                let f_over_r = if r2 > rc2 { 0.5 * rc2 / r2 } else { 0.5 };
                dv.add(lost[i] * F4::splat(f_over_r), xji);
            }
        });
        dv.total()
    })
}
