//! The stage plan: what a scene will compute each step, decided before the first step, so that
//! nothing a scene does not need is built or run. `eddy run --plan` prints it.

use super::schema::{PressureSolverKind, Scene};
use std::fmt;

/// One stage of a step, or a writer.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Stage {
    /// Short name.
    pub name: &'static str,
    /// What it does in this scene.
    pub detail: String,
}

/// The stages of a scene, in the order they run.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Plan {
    pub stages: Vec<Stage>,
}

impl Plan {
    /// The plan of `scene`.
    pub fn of(scene: &Scene) -> Self {
        let mut stages = Vec::new();
        let mut push = |name, detail: String| stages.push(Stage { name, detail });
        let bodies = scene.container.iter().chain(&scene.obstacles);
        let moving = bodies.clone().filter(|b| is_moving(b)).count();
        if let Some(fluid) = &scene.fluid {
            let n_bodies = bodies.count();
            if n_bodies > 0 {
                push(
                    "boundary",
                    format!(
                        "Akinci boundary samples on {n_bodies} bodies at {} m{}",
                        fluid.spacing,
                        if moving > 0 {
                            format!(", {moving} moving (re-placed and re-sorted every step)")
                        } else {
                            ", all static (sorted once)".into()
                        }
                    ),
                );
            }
            push(
                "neighbours",
                format!(
                    "z-order sort and compact hashed grid, cell = support = {} m",
                    2.0 * fluid.spacing
                ),
            );
            push("density", "densities and DFSPH factors".into());
            let p = &scene.pressure;
            let dfsph = p.solver == PressureSolverKind::Dfsph;
            if dfsph && p.divergence_solver {
                push(
                    "divergence",
                    format!(
                        "DFSPH divergence solve, tolerance {}",
                        p.divergence_tolerance
                    ),
                );
            }
            let v = &scene.viscosity;
            push(
                "forces",
                format!(
                    "gravity {:?}{}{}",
                    scene.gravity,
                    if v.kinematic > 0.0 || v.boundary > 0.0 {
                        format!(
                            ", Laplacian viscosity (Liu et al. 2021 Eq. 4) nu = {}, walls {}",
                            v.kinematic, v.boundary
                        )
                    } else {
                        String::new()
                    },
                    if v.xsph > 0.0 {
                        format!(", XSPH {}", v.xsph)
                    } else {
                        String::new()
                    }
                ),
            );
            push(
                "pressure",
                format!(
                    "{} density solve, tolerance {} ({} to {} iterations)",
                    if dfsph { "DFSPH" } else { "IISPH" },
                    p.density_tolerance,
                    p.min_iterations,
                    p.max_iterations
                ),
            );
            if let Some(line) = scene.refinement.plan_line() {
                push("refine", line);
            }
            push("advect", "positions, then NaN and domain checks".into());
        }
        if let Some(grid) = &scene.grid {
            for (name, detail) in grid.stages(scene) {
                push(name, detail);
            }
        }
        let out = &scene.output;
        if scene.grid.is_some() {
            push(
                "metrics",
                "metrics.csv: kinetic energy, max divergence, pressure and viscosity iterations, \
                 CFL, change rate, stage times"
                    .into(),
            );
        } else if !out.metrics.is_empty() {
            let names: Vec<_> = out.metrics.iter().map(|m| m.column()).collect();
            push("metrics", format!("metrics.csv: {}", names.join(", ")));
        }
        if !scene.probes.is_empty() {
            let names: Vec<_> = scene.probes.iter().map(|p| p.name()).collect();
            push("probes", format!("probes.csv: {}", names.join(", ")));
        }
        if out.vtk {
            push(
                "vtk",
                format!(
                    "VTK frames + {}.pvd every {} s",
                    if scene.grid.is_some() {
                        "grid"
                    } else {
                        "particles"
                    },
                    out.interval
                ),
            );
        }
        if out.hdf5 {
            push("hdf5", format!("frames.h5 every {} s", out.interval));
        }
        Plan { stages }
    }

    /// True when the plan has a stage of this name.
    pub fn has(&self, name: &str) -> bool {
        self.stages.iter().any(|s| s.name == name)
    }
}

pub(super) fn is_moving(b: &super::schema::Body) -> bool {
    let m = &b.motion;
    !m.keyframes.is_empty() || m.linear.iter().chain(&m.angular).any(|&c| c != 0.0)
}

impl fmt::Display for Plan {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, s) in self.stages.iter().enumerate() {
            writeln!(f, "{:>2}. {:<11} {}", i + 1, s.name, s.detail)?;
        }
        Ok(())
    }
}
