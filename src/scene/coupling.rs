//! `[coupling]`: the exchange across the water surface of a scene with both a `[grid]` (the
//! air) and a `[fluid]` (the water), and its checks.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::validate::Checker;
use super::{Scene, SceneError};
use crate::Real;

/// The coupling's parameters; the defaults are air over water.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Coupling {
    /// Drag coefficient C_d of the surface stress tau = rho_air C_d |u_air - u_water|
    /// (u_air - u_water), with u_air read 1.5 grid cells outside the surface. In [0, 0.1];
    /// about 1e-3 over the sea at 10 m height (Large & Pond 1981).
    #[serde(default = "default_drag")]
    pub drag_coefficient: Real,
    /// Air density, kg/m^3, in (0, 100]: the grid's density in a coupled scene (`grid.density`
    /// is left out or equal).
    #[serde(default = "default_air_density")]
    pub air_density: Real,
    /// A grid cell is liquid where the particles' occupancy sum_j V_j W(x_c - x_j) at its
    /// centre reaches this, in (0, 1): 1 inside the liquid, about 0.5 on its surface.
    #[serde(default = "default_threshold")]
    pub occupancy_threshold: Real,
}

fn default_drag() -> Real {
    1.3e-3
}
fn default_air_density() -> Real {
    1.2
}
fn default_threshold() -> Real {
    0.5
}

impl Default for Coupling {
    fn default() -> Self {
        Self {
            drag_coefficient: default_drag(),
            air_density: default_air_density(),
            occupancy_threshold: default_threshold(),
        }
    }
}

impl Scene {
    /// A `[coupling]` needs a grid and a fluid, its values in range, one air density, and
    /// what the exchange supports: one projection per step, a solved flow.
    pub(super) fn validate_coupling(&self, c: &Checker) -> Result<(), SceneError> {
        let Some(coupling) = &self.coupling else {
            return Ok(());
        };
        let (Some(grid), Some(_)) = (&self.grid, &self.fluid) else {
            let missing = match (&self.grid, &self.fluid) {
                (None, None) => "[grid] and [fluid]",
                (None, _) => "[grid]",
                _ => "[fluid]",
            };
            return Err(c.invalid(
                "coupling",
                "[coupling]",
                format!("a scene with both [grid] (the air) and [fluid] (the water); this one has no {missing}"),
            ));
        };
        c.ranged("coupling.drag_coefficient", coupling.drag_coefficient)?;
        c.ranged("coupling.air_density", coupling.air_density)?;
        c.ranged("coupling.occupancy_threshold", coupling.occupancy_threshold)?;
        if grid.density != super::grid::default_grid_density()
            && grid.density != coupling.air_density
        {
            return Err(c.invalid(
                "grid.density",
                super::Number(grid.density),
                format!(
                    "left out or equal to coupling.air_density ({}): the grid holds the air",
                    super::Number(coupling.air_density)
                ),
            ));
        }
        let unsupported = [
            (grid.reflection, "grid.reflection", "true"),
            (
                grid.static_flow.is_some(),
                "grid.static_flow",
                "a stored flow",
            ),
        ];
        if let Some((_, key, value)) = unsupported.into_iter().find(|u| u.0) {
            return Err(c.invalid(
                key,
                value,
                "not in a coupled scene: the exchange takes the pressure of one projection per \
                 step from a solved flow",
            ));
        }
        Ok(())
    }
}
