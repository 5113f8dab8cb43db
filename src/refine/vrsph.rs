//! Vorticity refinement (VRSPH, Liu et al. 2021, Algorithm 2, Eqs. 5–17).
//!
//! At the point after the divergence solve, where the velocity is the papers' v~ (Eq. 12),
//! in the order of Algorithm 2:
//!
//! 1. zeta~ = curl v~ (Eq. 6) and the ideal vorticity zeta^(n+1) = zeta^n + dt (zeta^n . grad
//!    v^n + nu Laplacian zeta^n) (Eqs. 7–11), from the zeta^n and stretching the particles carry
//!    from the end of the last step; the Laplacian is taken at this step's positions, where
//!    Algorithm 2 evaluates D zeta^n / Dt (after "correct divergence"), in the same pass as
//!    zeta~;
//! 2. the loss Delta zeta = zeta^(n+1) - zeta~ (Eq. 12);
//! 3. the local stream function psi (Eq. 15) and the refinement Delta v = curl psi (Eq. 16);
//! 4. v^(n+1) = v~ + alpha Delta v (Eq. 17);
//! 5. zeta^n of the next step, curl v^(n+1), and its stretching (zeta . grad) v^(n+1) (Eq. 9),
//!    from one gradient pass (Algorithm 2's first line, at the positions where v^(n+1) is
//!    formed).
//!
//! Four passes over the neighbours a step: the gradient, the fused curl and Laplacian, the
//! stream function and its curl.
//!
//! **Regularised distance in Eq. 15.** The sum runs over the fluid neighbours within the
//! support and the particle itself, with |x_ij| replaced by sqrt(|x_ij|^2 + e^2),
//! e = 2a / 3 and a = (3 V / (4 pi))^(1/3) the radius of a sphere of the particle's rest
//! volume V. With this e, the self term V / (4 pi e) equals the exact stream function at the
//! centre of a uniformly vortical sphere of volume V (a^2 / 2), so the self term is the
//! particle's own contribution rather than a singularity (e is about 0.41 spacings, 0.21 h).
//! Walls carry no loss, so they add nothing to psi.
//!
//! **What Eq. 15 restores.** Truncating the Green's function 1 / (4 pi r) at the support h
//! makes the refinement a band-pass filter: for a divergence-free loss of wavenumber k,
//! psi^(k) = (1 - cos kh) / k^2 loss^(k), so curl Delta v = (1 - cos kh) x loss. Structures much
//! larger than h get back only (kh)^2 / 2 of their loss; those of wavelength about 2h
//! (kh = pi) get back up to twice theirs. `tests/refine_vortex.rs` checks the sign on a single
//! Gaussian vortex of core 1.5 h (VRSPH keeps more of its kinetic energy than DFSPH); at
//! nu = 0 the same vortex gains energy under VRSPH (+30 % in 125 steps, where DFSPH keeps it
//! within 0.1 %), the over-restoration at the particle scale.

use super::lanes::F4;
use super::packed::{fill, Field, Packed, Quantity};
use super::registry::{Interval, Method, MethodParams};
use super::{StepContext, StepHook};
use crate::spatial::{permute, resize};
use crate::sph::operators::{curl_of, WallField};
use crate::state::{Persist, Restorer, Saver, StateError};
use crate::{Real, Vec3};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// VRSPH with gain alpha.
/// `method = "vrsph"`.
// Kept between steps: the stretch; zeta, positions, velocity, strength and psi packed.
pub const METHOD: Method = Method::new::<Params>(
    "vrsph",
    "vorticity refinement through a stream function (Liu et al. 2021, Algorithm 2)",
    &[("alpha", Interval::closed(0.0, 2.0))],
)
.keeping(std::mem::size_of::<Vec3>() as u64 + 5 * std::mem::size_of::<F4>() as u64);

/// The keys of `method = "vrsph"`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Gain alpha of the velocity refinement (Liu et al. 2021 Eq. 17); 1 is the ideal refinement.
    #[serde(default = "super::registry::one")]
    pub alpha: Real,
    /// The wall samples take part in the method's difference operators. It models no-slip
    /// walls: pair it with `viscosity.boundary > 0` (the book's SPH refinements chapter says why it is off).
    #[serde(default)]
    pub walls: bool,
}

impl MethodParams for Params {
    fn build(&self, _n: usize, _seed: u64) -> Box<dyn StepHook> {
        Box::new(Vrsph::new(self.alpha, self.walls))
    }
}

pub struct Vrsph {
    alpha: Real,
    /// Boundary samples take part in the operators.
    walls: bool,
    /// zeta^n = curl v^n per fluid particle, packed (its Laplacian reads it at neighbours);
    /// empty before the first step.
    zeta: Field,
    /// The stretching (zeta^n . grad) v^n per fluid particle.
    stretch: Vec<Vec3>,
    /// Buffers of one step (kept for their memory): packed positions and velocity, the
    /// loss's stream strengths and the stream function.
    positions: Vec<F4>,
    velocity: Field,
    strength: Vec<F4>,
    psi: Field,
}

impl Vrsph {
    pub fn new(alpha: Real, walls: bool) -> Self {
        Self {
            alpha,
            walls,
            zeta: Field::default(),
            stretch: Vec::new(),
            positions: Vec::new(),
            velocity: Field::default(),
            strength: Vec::new(),
            psi: Field::default(),
        }
    }
}

/// zeta^n and its stretching, which the next step's ideal vorticity starts from (empty
/// before the first step); the rest are one step's buffers.
impl Persist for Vrsph {
    fn save(&self, into: &mut Saver) {
        self.zeta.save(into, "zeta");
        into.vec3s("stretch", &self.stretch);
    }

    fn restore(&mut self, from: &Restorer) -> Result<(), StateError> {
        let zeta = Field::restore(from, "zeta")?;
        self.stretch = from.vec3s_n("stretch", zeta.len())?;
        self.zeta = zeta;
        Ok(())
    }
}

impl StepHook for Vrsph {
    fn name(&self) -> &'static str {
        "refine"
    }

    fn describe(&self) -> String {
        super::plan_line(
            format!(
                "VRSPH (Liu et al. 2021, Alg. 2) after the divergence solve, alpha = {}",
                self.alpha
            ),
            self.walls,
        )
    }

    fn walls(&self) -> bool {
        self.walls
    }

    fn permute(&mut self, perm: &[u32]) {
        if self.zeta.len() == perm.len() {
            self.zeta.permute(perm);
            permute(&mut self.stretch, perm);
        }
    }

    fn resize(&mut self, keep: &[bool], added: usize) {
        self.zeta.resize(keep, added);
        resize(&mut self.stretch, keep, added, Vec3::zeros());
    }

    fn particles(&self) -> Option<usize> {
        (!self.zeta.is_empty()).then_some(self.zeta.len())
    }

    fn before_advection(&mut self, ctx: &StepContext, v: &mut [Vec3], _accel: &mut [Vec3]) {
        let Self {
            alpha,
            walls: _,
            zeta,
            stretch,
            positions,
            velocity,
            strength,
            psi,
        } = self;
        if *alpha == 0.0 {
            return;
        }
        let ops = Packed::new(ctx.ops, positions, v);
        if zeta.len() == v.len() {
            let (nu, dt) = (ctx.nu, ctx.dt);
            ops.pack(v, velocity);
            fill(strength, v.len(), |i| {
                let (now, diffusion) = ops.curl_diffusion_at(i, velocity, zeta, nu);
                let loss = zeta.vec(i) + dt * (stretch[i] + diffusion) - now;
                stream_strength(ops.ops.volume[i], &ops.denoise(Quantity::Vorticity, loss))
            });
            stream_function(&ops, strength, psi);
            ops.update(v, velocity, Quantity::Velocity, |i, v| {
                v + *alpha * ops.curl_at(i, psi, WallField::Zero)
            });
        } else {
            ops.pack(v, velocity);
        }
        ops.field_with(zeta, stretch, Quantity::Vorticity, None, |i| {
            let grad = ops.gradient_at(i, velocity, WallField::Velocity);
            let zeta = curl_of(&grad);
            (zeta, grad * zeta)
        });
    }
}

/// The regularisation length e of Eq. 15 for a particle of rest volume `volume` (see the
/// module documentation).
pub fn stream_core(volume: Real) -> Real {
    2.0 / 3.0 * (3.0 * volume / (4.0 * PI)).cbrt()
}

/// The strength s = V zeta / (4 pi) of a particle of volume V and vorticity zeta in Eq. 15,
/// packed for [`stream_function`].
pub fn stream_strength(volume: Real, zeta: &Vec3) -> F4 {
    F4::from_vec(&(volume / (4.0 * PI) * zeta), 0.0)
}

/// The local stream function (Liu Eq. 15) of the strengths s_j = V_j zeta_j / (4 pi)
/// ([`stream_strength`]), into `psi`: psi_i = sum_{j in N(i) + i} s_j / sqrt(|x_ij|^2 + e^2),
/// four neighbours' weights at a time ([`Packed::quads`]).
pub fn stream_function(ops: &Packed, strength: &[F4], psi: &mut Field) {
    let e = stream_core(ops.ops.nb.volume);
    let e2 = F4::splat((e * e) as f32);
    let self_weight = F4::splat((1.0 / e) as f32);
    ops.field(psi, Quantity::StreamFunction, None, |i| {
        let mut psi = strength[i] * self_weight;
        ops.quads(i, |j, n, [x, y, z]| {
            let w = (x * x + y * y + z * z + e2).rsqrt() * F4::first(n);
            psi += (strength[j[0]] * w.lane::<0>() + strength[j[1]] * w.lane::<1>())
                + (strength[j[2]] * w.lane::<2>() + strength[j[3]] * w.lane::<3>());
        });
        psi.vec()
    })
}
