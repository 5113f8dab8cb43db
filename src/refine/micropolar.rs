//! Micropolar SPH as summarised by Wang et al. 2020, Eq. 16 (after Bender et al. 2019):
//!
//!   Dv/Dt = ... + nu Laplacian v + (nu + nu_t) curl omega,
//!   epsilon Domega/Dt = nu_t (curl v - 2 omega)
//!
//! with omega a per-particle angular velocity (starting at zero), nu_t the transfer coefficient
//! and epsilon the micro-inertia per unit mass (m^2); external torques are left out. The
//! relaxation term -2 omega nu_t / epsilon is integrated implicitly,
//! omega' = (omega + dt nu_t / epsilon curl v) / (1 + 2 dt nu_t / epsilon), so a small
//! micro-inertia cannot make the step unstable. Both curls are the shared difference curls
//! (walls hold zero angular velocity). The rotational energy is sum_i m epsilon |omega_i|^2 / 2.

use super::registry::{Interval, Method, MethodParams};
use super::{StepContext, StepHook};
use crate::spatial::{permute, resize};
use crate::sph::operators::WallField;
use crate::state::{Persist, Restorer, Saver, StateError};
use crate::{Real, Vec3};
use rayon::prelude::*;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Micropolar model state.
/// `method = "micropolar"`.
// Kept between steps: omega.
pub const METHOD: Method = Method::new::<Params>(
    "micropolar",
    "micropolar SPH (Bender et al. 2019), a baseline of the refinement papers",
    &[
        ("nu_t", Interval::closed(0.0, 1.0)),
        ("micro_inertia", Interval::gt(0.0)),
    ],
)
.keeping(std::mem::size_of::<Vec3>() as u64);

/// The keys of `method = "micropolar"`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Transfer coefficient nu_t, m^2/s.
    #[serde(default = "default_nu_t")]
    pub nu_t: Real,
    /// Micro-inertia per unit mass epsilon, m^2.
    #[serde(default = "default_micro_inertia")]
    pub micro_inertia: Real,
    /// The wall samples take part in the method's difference operators. It models no-slip
    /// walls: pair it with `viscosity.boundary > 0` (the book's SPH refinements chapter says why it is off).
    #[serde(default)]
    pub walls: bool,
}

/// Wang et al. Sec. 5 and Liu et al. Sec. 5: nu_t = 0.05 matches beta = 1 and alpha = 1.
fn default_nu_t() -> Real {
    0.05
}
/// No paper gives one; 0.01 m^2 relaxes omega towards curl(v) / 2 in epsilon / (2 nu_t) = 0.1 s
/// at the default nu_t.
fn default_micro_inertia() -> Real {
    0.01
}

impl MethodParams for Params {
    fn build(&self, n: usize, _seed: u64) -> Box<dyn StepHook> {
        Box::new(Micropolar::new(
            n,
            self.nu_t,
            self.micro_inertia,
            self.walls,
        ))
    }
}

pub struct Micropolar {
    nu_t: Real,
    inertia: Real,
    /// Boundary samples take part in the operators.
    walls: bool,
    /// Angular velocity per fluid particle, rad/s.
    omega: Vec<Vec3>,
}

impl Micropolar {
    pub fn new(n: usize, nu_t: Real, inertia: Real, walls: bool) -> Self {
        Self {
            nu_t,
            inertia,
            walls,
            omega: vec![Vec3::zeros(); n],
        }
    }
}

/// The angular velocities, which the next step relaxes from.
impl Persist for Micropolar {
    fn save(&self, into: &mut Saver) {
        into.vec3s("omega", &self.omega);
    }

    fn restore(&mut self, from: &Restorer) -> Result<(), StateError> {
        self.omega = from.vec3s("omega")?;
        Ok(())
    }
}

impl StepHook for Micropolar {
    fn name(&self) -> &'static str {
        "refine"
    }

    fn describe(&self) -> String {
        super::plan_line(
            format!(
                "micropolar (Wang et al. 2020 Eq. 16) nu_t = {}, micro-inertia = {} m^2",
                self.nu_t, self.inertia
            ),
            self.walls,
        )
    }

    fn walls(&self) -> bool {
        self.walls
    }

    fn permute(&mut self, perm: &[u32]) {
        permute(&mut self.omega, perm);
    }

    fn resize(&mut self, keep: &[bool], added: usize) {
        resize(&mut self.omega, keep, added, Vec3::zeros());
    }

    fn before_advection(&mut self, ctx: &StepContext, v: &mut [Vec3], accel: &mut [Vec3]) {
        if self.nu_t == 0.0 {
            return;
        }
        let ops = &ctx.ops;
        let curl_v = ops.curl(v, WallField::Velocity);
        let rate = ctx.dt * self.nu_t / self.inertia;
        self.omega
            .par_iter_mut()
            .zip(curl_v.par_iter())
            .for_each(|(w, c)| *w = (*w + rate * c) / (1.0 + 2.0 * rate));
        let curl_w = ops.curl(&self.omega, WallField::Zero);
        let coupling = ctx.nu + self.nu_t;
        accel
            .par_iter_mut()
            .zip(curl_w.par_iter())
            .for_each(|(a, c)| *a += coupling * c);
    }

    fn particles(&self) -> Option<usize> {
        Some(self.omega.len())
    }

    fn rotational_energy(&self, mass: Real) -> Real {
        0.5 * mass * self.inertia * crate::parallel::sum_by(&self.omega, |w| w.norm_squared())
    }

    fn fields(&self) -> Vec<(&'static str, &[Vec3])> {
        vec![("angular_velocity", &self.omega)]
    }
}
