//! The solver's state between steps (see [`crate::state`]). Stored: the clock and the last
//! step's size (the warm starts are rescaled by it), the fluid's particles in their current
//! order, the moving bodies' samples in theirs, the emitters' phases, the lost particles, the
//! energy bound once fixed, and each hook's own state.
//!
//! Rebuilt: the neighbourhood (grid, neighbour lists, pair gradients, densities and DFSPH
//! factors), by the same update that ended the step the state was saved after; its sort keeps
//! the stored order, which is already the sorted one. Not stored: what the scene gives (kernel,
//! bodies, parameters, ramp, wall viscosities), the non-pressure accelerations a `stable_dt`
//! computed ahead of its `advance` (a cache of the state, recomputed alike), the hooks' operator
//! volumes (set from the densities before the hooks run) and the names of the parts the last
//! step ran.

use super::SphSolver;
use crate::geometry::RigidBody;
use crate::state::{Persist, Restorer, Saver, StateError};

impl SphSolver {
    /// Whether a body moves: only then do its samples change after they are sampled.
    fn any_moving(&self) -> bool {
        self.bodies.iter().any(RigidBody::is_moving)
    }
}

/// The section of hook `k`, by its place and name.
fn hook_section(k: usize, name: &str) -> String {
    format!("{k}_{name}")
}

impl Persist for SphSolver {
    fn save(&self, into: &mut Saver) {
        into.real("time", self.time);
        into.u64("step", self.step);
        into.reals("last_dt", self.last_dt.as_slice());
        self.fluid.save(&mut into.section("fluid"));
        if self.any_moving() {
            self.boundary.save(&mut into.section("boundary"));
        }
        self.open.save(&mut into.section("open"));
        self.lost.save(&mut into.section("lost"));
        self.energy.save(&mut into.section("energy"));
        let mut hooks = into.section("hooks");
        for (k, hook) in self.hooks.iter().enumerate() {
            hook.save(&mut hooks.section(&hook_section(k, hook.name())));
        }
    }

    /// Restores into a solver built from the same scene, then rebuilds the neighbourhood of
    /// the restored state.
    fn restore(&mut self, from: &Restorer) -> Result<(), StateError> {
        let time = from.real("time")?;
        let step = from.u64("step")?;
        let last_dt = match from.reals("last_dt")?.as_slice() {
            [] => None,
            _ => Some(from.real("last_dt")?),
        };
        self.fluid.restore(&from.section("fluid"))?;
        if self.any_moving() {
            self.boundary.restore(&from.section("boundary"))?;
        }
        self.open.restore(&from.section("open"))?;
        self.lost.restore(&from.section("lost"))?;
        self.energy.restore(&from.section("energy"))?;
        let hooks = from.section("hooks");
        let n = self.fluid.len();
        for (k, hook) in self.hooks.iter_mut().enumerate() {
            let name = hook_section(k, hook.name());
            hook.restore(&hooks.section(&name))?;
            if let Some(m) = hook.particles().filter(|&m| m != n) {
                let found = format!("state for {m} particles");
                return Err(hooks.invalid(&name, found, format!("{n}, the fluid's")));
            }
        }
        (self.time, self.step, self.last_dt) = (time, step, last_dt);
        self.update_neighborhoods();
        Ok(())
    }
}
