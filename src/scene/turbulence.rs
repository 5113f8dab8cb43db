//! The artificial-boundary-layer part of a scene: obstacles with `abl = { database = ... }` and
//! the `[turbulence]` table, their checks, and the velocity scale |U_0| of Eq. 8.

use super::validate::{Checker, Interval};
use super::{Body, Scene, SceneError};
use crate::abl::TurbulenceParams;
use crate::geometry::RigidBody;
use crate::Real;

impl Scene {
    /// The obstacles with a database, with their index among the bodies (container first).
    pub fn abl_obstacles(&self) -> impl Iterator<Item = (usize, &Body)> {
        self.indexed_obstacles().filter(|(_, b)| b.abl.is_some())
    }

    /// |U_0| of Eq. 8: `turbulence.u0`, else the fastest inflow side, else the fastest surface
    /// point of an obstacle with a database (linear speed plus angular speed times its
    /// reach); `None` when all of these are zero.
    pub fn turbulence_u0(&self) -> Option<Real> {
        if let Some(u0) = self.turbulence.as_ref().and_then(|t| t.u0) {
            return Some(u0);
        }
        let inflow = self.grid.iter().flat_map(|g| g.boundary.sides()).flatten();
        let inflow = inflow
            .filter_map(|side| side.inflow_peak().map(norm))
            .chain(
                self.fluid
                    .iter()
                    .flat_map(|f| &f.inflow)
                    .map(|f| norm(f.velocity)),
            )
            .fold(0.0, Real::max);
        if inflow > 0.0 {
            return Some(inflow);
        }
        let obstacle = self
            .abl_obstacles()
            .map(|(i, b)| obstacle_speed(b, i))
            .fold(0.0, Real::max);
        (obstacle > 0.0).then_some(obstacle)
    }

    pub(super) fn validate_turbulence(&self, c: &Checker) -> Result<(), SceneError> {
        if let Some(b) = self.container.as_ref().filter(|b| b.abl.is_some()) {
            let name = b.name.as_deref().unwrap_or("container");
            return Err(c.invalid(
                "container.abl",
                name,
                "no `abl` on the container: boundary layers belong to obstacles",
            ));
        }
        let with_abl = self.abl_obstacles().count();
        for (i, b) in self.obstacles.iter().enumerate() {
            let Some(abl) = &b.abl else { continue };
            if !abl.database.is_file() {
                return Err(c.invalid(
                    format!("obstacles[{i}].abl.database"),
                    abl.database.display(),
                    how_to_precompute(&abl.database, b.name.as_deref()),
                ));
            }
        }
        if let Some(t) = &self.turbulence {
            if with_abl == 0 {
                return Err(c.invalid(
                    "turbulence",
                    "a table",
                    "an obstacle with `abl = { database = \"...\" }` for it to act on",
                ));
            }
            check_params(c, t, self.grid.is_none())?;
            if t.upsample != 1 && self.grid.is_none() {
                return Err(c.invalid(
                    "turbulence.upsample",
                    t.upsample,
                    "1 in a scene without [grid]: SPH particles receive the kernels' velocity \
                     at their own positions",
                ));
            }
        }
        if with_abl > 0 && self.turbulence_u0().is_none() {
            return Err(c.invalid(
                "turbulence.u0",
                "nothing",
                "a speed in m/s: the scene has no inflow and its obstacles with a database do \
                 not move, so Eq. 8 has no velocity scale",
            ));
        }
        Ok(())
    }
}

/// `on_particles`: the stage drives SPH particles (a scene without a grid).
fn check_params(c: &Checker, t: &TurbulenceParams, on_particles: bool) -> Result<(), SceneError> {
    c.ranged("turbulence.c_p", t.c_p)?;
    if let Some(u0) = t.u0 {
        c.ranged("turbulence.u0", u0)?;
    }
    c.ranged("turbulence.gain", t.gain)?;
    let dissipation = t.dissipation(on_particles);
    c.ranged("turbulence.dissipation_radius", dissipation)?;
    c.num(
        "turbulence.r_max",
        t.r_max,
        Interval::ge(dissipation.max(0.5))
            .noted("cells, at least the dissipation radius (smaller particles would vanish)"),
    )?;
    c.ranged("turbulence.split_radius", t.split_radius)?;
    c.ranged("turbulence.cascade_time", t.cascade_time)?;
    c.count("turbulence.upsample", t.upsample as u64)?;
    c.count("turbulence.children", t.children as u64)
}

/// The fastest surface speed of `body`: keyframed paths by their fastest segment.
fn obstacle_speed(body: &Body, index: usize) -> Real {
    let m = &body.motion;
    if !m.keyframes.is_empty() {
        return m
            .keyframes
            .windows(2)
            .map(|k| {
                let d: [Real; 3] = std::array::from_fn(|a| k[1].position[a] - k[0].position[a]);
                norm(d) / (k[1].t - k[0].t)
            })
            .fold(0.0, Real::max);
    }
    let spin = norm(m.angular);
    let reach = if spin > 0.0 {
        RigidBody::from_scene(body, index).map_or(0.0, |r| {
            let (lo, hi) = r.local_aabb();
            lo.coords.abs().sup(&hi.coords.abs()).norm()
        })
    } else {
        0.0
    };
    norm(m.linear) + spin * reach
}

fn norm(v: [Real; 3]) -> Real {
    v.iter().map(|x| x * x).sum::<Real>().sqrt()
}

/// What a missing database's error asks for: the command that writes it, naming the obstacle
/// file beside it (`db/sphere.toml` for `db/sphere.h5`, as the shipped scenes keep them) when
/// there is one, and otherwise the file to write first.
fn how_to_precompute(database: &std::path::Path, obstacle: Option<&str>) -> String {
    let spec = database.with_extension("toml");
    if spec.is_file() {
        format!(
            "an existing database file; write this one with `eddy-precompute {} --out {}`",
            spec.display(),
            database.display()
        )
    } else {
        format!(
            "an existing database file; describe the obstacle{} (its shape as in this scene) in \
             an obstacle file such as {} and run `eddy-precompute {} --out {}`",
            obstacle.map(|n| format!(" `{n}`")).unwrap_or_default(),
            spec.display(),
            spec.display(),
            database.display()
        )
    }
}
