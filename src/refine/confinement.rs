//! Vorticity confinement in SPH form (Fedkiw et al. 2001; for SPH, Macklin & Müller 2013):
//! a_i = epsilon (N_i x omega_i) with omega = curl v and N = eta / |eta|, eta = grad |omega|,
//! both by the shared difference operators. It pushes fluid around existing vortices' cores
//! and so strengthens them; it cannot create vortices, which is why the papers compare
//! against it. Where eta vanishes there is no direction and no force.

use super::registry::{Interval, Method, MethodParams};
use super::{StepContext, StepHook};
use crate::sph::operators::WallField;
use crate::state::{Persist, Restorer, Saver, StateError};
use crate::{Real, Vec3};
use rayon::prelude::*;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// `method = "confinement"`.
// Keeps nothing between steps: its curl and gradient are the step's own.
pub const METHOD: Method = Method::new::<Params>(
    "confinement",
    "vorticity confinement in SPH form, a baseline of the refinement papers",
    &[("epsilon", Interval::ge(0.0))],
)
.keeping(0);

/// The keys of `method = "confinement"`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Confinement strength epsilon, m/s.
    #[serde(default = "default_epsilon")]
    pub epsilon: Real,
    /// The wall samples take part in the method's difference operators. It models no-slip
    /// walls: pair it with `viscosity.boundary > 0` (the book's SPH refinements chapter says why it is off).
    #[serde(default)]
    pub walls: bool,
}

/// No paper gives one; 0.1 m/s gives about 0.1 g at a vorticity of 10 / s.
fn default_epsilon() -> Real {
    0.1
}

impl MethodParams for Params {
    fn build(&self, _n: usize, _seed: u64) -> Box<dyn StepHook> {
        Box::new(Confinement::new(self.epsilon, self.walls))
    }
}

/// Confinement with strength epsilon, m/s.
pub struct Confinement {
    epsilon: Real,
    /// Boundary samples take part in the operators.
    walls: bool,
}

impl Confinement {
    pub fn new(epsilon: Real, walls: bool) -> Self {
        Self { epsilon, walls }
    }
}

/// Confinement reads only the step's velocity: nothing carries over.
impl Persist for Confinement {
    fn save(&self, _into: &mut Saver) {}

    fn restore(&mut self, _from: &Restorer) -> Result<(), StateError> {
        Ok(())
    }
}

impl StepHook for Confinement {
    fn name(&self) -> &'static str {
        "refine"
    }

    fn describe(&self) -> String {
        super::plan_line(
            format!("vorticity confinement, epsilon = {} m/s", self.epsilon),
            self.walls,
        )
    }

    fn walls(&self) -> bool {
        self.walls
    }

    fn before_advection(&mut self, ctx: &StepContext, v: &mut [Vec3], accel: &mut [Vec3]) {
        if self.epsilon == 0.0 {
            return;
        }
        let ops = &ctx.ops;
        let omega = ops.curl(v, WallField::Velocity);
        let magnitude: Vec<Real> = omega.par_iter().map(|w| w.norm()).collect();
        let eta = ops.scalar_gradient(&magnitude);
        accel
            .par_iter_mut()
            .zip(eta.par_iter().zip(omega.par_iter()))
            .for_each(|(a, (eta, w))| {
                let norm = eta.norm();
                if norm > 0.0 {
                    *a += (self.epsilon / norm) * eta.cross(w);
                }
            });
    }
}
