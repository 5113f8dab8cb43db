//! The analytic solutions `eddy sweep --analytic` measures runs against. Each checks before any
//! run that the scene is the flow it describes (refusing it with what is missing), and reads a
//! finished run's error from its folder: the resolved `scene.toml` and the CSV files the run
//! wrote, so a study's error is the one a reader can recompute from the run.

use std::path::Path;

use super::measure::series;
use super::StudyError;
use crate::grid::GridSide;
use crate::metrics::Probe;
use crate::scene::Scene;

/// Analytic solutions a sweep can measure its runs against ([`Analytic::summary`] says what
/// each is).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Analytic {
    TaylorGreen,
    Hydrostatic,
    Poiseuille,
}

/// Terms of the start-up series of [`poiseuille_velocity`]: the n-th decays as
/// exp(-n^2 pi^2 nu t / H^2) and weighs 1/n^3, so 1,000 odd terms leave less than 1e-9 of the
/// steady flow at t = 0 and nothing measurable after.
const SERIES_TERMS: usize = 1000;

impl Analytic {
    /// Every one, in the order the command line lists them.
    pub const ALL: [Analytic; 3] = [
        Analytic::TaylorGreen,
        Analytic::Hydrostatic,
        Analytic::Poiseuille,
    ];

    /// Its name on the command line (`--analytic NAME`) and in messages.
    pub fn name(self) -> &'static str {
        match self {
            Analytic::TaylorGreen => "taylor-green",
            Analytic::Hydrostatic => "hydrostatic",
            Analytic::Poiseuille => "poiseuille",
        }
    }

    /// What it is, in a line (the command line's help for its name).
    pub fn summary(self) -> &'static str {
        match self {
            Analytic::TaylorGreen => {
                "Taylor–Green energy decay (a grid scene with \
                 `grid.initial_flow = \"taylor_green\"`)"
            }
            Analytic::Hydrostatic => {
                "Hydrostatic pressure rho |g| depth at the point probes of a fluid at rest"
            }
            Analytic::Poiseuille => {
                "Plane Poiseuille flow started from rest, at the line probes across a \
                 body-force-driven grid channel"
            }
        }
    }

    /// The study's column for this measure.
    pub fn column(self) -> &'static str {
        match self {
            Analytic::TaylorGreen => "error_taylor_green",
            Analytic::Hydrostatic => "error_hydrostatic",
            Analytic::Poiseuille => "error_poiseuille",
        }
    }

    /// Refuses a scene this solution does not describe, naming what is missing.
    pub fn check(self, scene: &Scene) -> Result<(), StudyError> {
        match self {
            Analytic::TaylorGreen => {
                self.require(
                    scene.grid.as_ref().and_then(|g| g.initial_flow).is_some(),
                    || "the scene has no `grid.initial_flow = \"taylor_green\"`".into(),
                )?;
            }
            Analytic::Hydrostatic => {
                hydrostatic_probes(scene)?;
            }
            Analytic::Poiseuille => {
                poiseuille_channel(scene)?;
            }
        }
        Ok(())
    }

    /// The error of the finished run in `dir`; None when it wrote nothing to measure.
    pub fn error(self, dir: &Path) -> Option<f64> {
        match self {
            Analytic::TaylorGreen => {
                let values = series(&dir.join("metrics.csv"), "time", "taylor_green_error")?;
                values.iter().map(|&(_, v)| v).reduce(f64::max)
            }
            Analytic::Hydrostatic => hydrostatic_error(dir),
            Analytic::Poiseuille => poiseuille_error(dir),
        }
    }

    /// The error of a scene this solution does not describe, saying what is missing.
    fn refuses(self, reason: String) -> StudyError {
        StudyError::NotDescribed {
            analytic: self.name(),
            reason,
        }
    }

    /// Refuses the scene, saying `reason`, unless `holds`.
    fn require(self, holds: bool, reason: impl FnOnce() -> String) -> Result<(), StudyError> {
        if holds {
            Ok(())
        } else {
            Err(self.refuses(reason()))
        }
    }
}

/// The run's resolved scene.
fn run_scene(dir: &Path) -> Option<Scene> {
    crate::scene::load(&dir.join("scene.toml"), &[]).ok()
}

/// The point probes of a fluid at rest with the exact pressure rho |g| d at each, d the depth
/// under the top of the fluid blocks along gravity (where the surface of a block that holds its
/// volume lies at rest). Errs without a fluid, gravity or a point probe under the surface.
fn hydrostatic_probes(scene: &Scene) -> Result<Vec<(String, f64)>, StudyError> {
    let hydrostatic = Analytic::Hydrostatic;
    let Some(fluid) = &scene.fluid else {
        return Err(hydrostatic.refuses("the scene has no [fluid]".into()));
    };
    let g = crate::Vec3::from(scene.gravity);
    hydrostatic.require(g.norm() > 0.0, || "the scene has no gravity".into())?;
    let up = -g / g.norm();
    let height = |p: &[f64; 3]| crate::Vec3::from(*p).dot(&up);
    let top = fluid
        .blocks
        .iter()
        .flat_map(|b| {
            // The highest corner of the box along `up`.
            (0..8).map(move |c| {
                let pick = |a: usize| if c >> a & 1 == 1 { b.max[a] } else { b.min[a] };
                height(&[pick(0), pick(1), pick(2)])
            })
        })
        .fold(f64::NEG_INFINITY, f64::max);
    hydrostatic.require(top.is_finite(), || "the fluid has no blocks".into())?;
    let mut probes = Vec::new();
    for p in &scene.probes {
        if let Probe::Point { name, position } = p {
            let depth = top - height(position);
            hydrostatic.require(depth > 0.0, || {
                format!(
                    "point probe `{name}` lies {:.4} m above the fluid's top",
                    -depth
                )
            })?;
            probes.push((name.clone(), fluid.density * g.norm() * depth));
        }
    }
    hydrostatic.require(!probes.is_empty(), || "the scene has no point probe".into())?;
    Ok(probes)
}

/// Relative L2 error of the point probes' pressure, each averaged over the second half of the
/// run (after the start has settled), against rho |g| depth.
fn hydrostatic_error(dir: &Path) -> Option<f64> {
    let probes = hydrostatic_probes(&run_scene(dir)?).ok()?;
    let path = dir.join("probes.csv");
    let (mut num, mut den) = (0.0, 0.0);
    for (name, exact) in probes {
        let p = series(&path, "time", &format!("{name}_p"))?;
        let end = p.last()?.0;
        let late: Vec<f64> = p
            .iter()
            .filter(|(t, _)| *t >= 0.5 * end)
            .map(|v| v.1)
            .collect();
        let mean = late.iter().sum::<f64>() / late.len() as f64;
        num += (mean - exact).powi(2);
        den += exact * exact;
    }
    (den > 0.0).then(|| (num / den).sqrt())
}

/// A plane Poiseuille channel: (body force along x, kinematic viscosity, the plates' y, the
/// line probes' names). Errs unless the grid applies a gravity along x as a force, is periodic
/// in x, has no-slip walls at y_min and y_max, and has a line probe.
fn poiseuille_channel(scene: &Scene) -> Result<(f64, f64, [f64; 2], Vec<String>), StudyError> {
    let poiseuille = Analytic::Poiseuille;
    let Some(grid) = &scene.grid else {
        return Err(poiseuille.refuses("the scene has no [grid]".into()));
    };
    poiseuille.require(
        grid.gravity && scene.gravity[1] == 0.0 && scene.gravity[2] == 0.0,
        || {
            "the channel is driven by a body force along x: set `gravity = [g, 0, 0]` and \
             `grid.gravity = true`"
                .into()
        },
    )?;
    let b = &grid.boundary;
    poiseuille.require(
        b.x_min == GridSide::Periodic && b.y_min == GridSide::Wall && b.y_max == GridSide::Wall,
        || {
            "the channel is periodic along x (grid.boundary.x_min, x_max) between no-slip walls \
             at y_min and y_max"
                .into()
        },
    )?;
    let lines: Vec<String> = scene
        .probes
        .iter()
        .filter_map(|p| match p {
            Probe::Line { name, .. } => Some(name.clone()),
            _ => None,
        })
        .collect();
    poiseuille.require(!lines.is_empty(), || {
        "the scene has no line probe to compare".into()
    })?;
    Ok((
        scene.gravity[0],
        scene.viscosity.kinematic,
        [scene.domain.min[1], scene.domain.max[1]],
        lines,
    ))
}

/// u(y, t) of plane Poiseuille flow between plates at y0 and y1 = y0 + H, started from rest
/// by the body force g at t = 0: the steady parabola g (y - y0)(y1 - y) / (2 nu) less its
/// start-up series, sum over odd n of 4 g H^2 / (nu pi^3 n^3) sin(n pi s) exp(-n^2 pi^2 nu t /
/// H^2), s = (y - y0) / H (separation of variables of u_t = g + nu u_yy with u = 0 at the
/// plates).
pub fn poiseuille_velocity(g: f64, nu: f64, plates: [f64; 2], y: f64, t: f64) -> f64 {
    let h = plates[1] - plates[0];
    let s = (y - plates[0]) / h;
    let steady = g * h * h * s * (1.0 - s) / (2.0 * nu);
    let pi = std::f64::consts::PI;
    let transient: f64 = (0..SERIES_TERMS)
        .map(|k| (2 * k + 1) as f64)
        .map(|n| {
            4.0 * g * h * h / (nu * pi.powi(3) * n.powi(3))
                * (n * pi * s).sin()
                * (-n * n * pi * pi * nu * t / (h * h)).exp()
        })
        .sum();
    steady - transient
}

/// Relative L2 error of every line probe's u, at the end of the run, against
/// [`poiseuille_velocity`] at its samples' y. The end is the last metrics row's time plus its
/// step (a row describes the state at `time` and the step taken from it).
fn poiseuille_error(dir: &Path) -> Option<f64> {
    let (g, nu, plates, lines) = poiseuille_channel(&run_scene(dir)?).ok()?;
    let metrics = dir.join("metrics.csv");
    let (t, dt) = (
        series(&metrics, "step", "time")?.last()?.1,
        series(&metrics, "step", "dt")?.last()?.1,
    );
    let end = t + dt;
    let (mut num, mut den) = (0.0, 0.0);
    for name in lines {
        let path = dir.join(format!("profile_{name}.csv"));
        let (y, u) = (series(&path, "s", "y")?, series(&path, "s", "u")?);
        for ((_, y), (_, u)) in y.iter().zip(&u) {
            let exact = poiseuille_velocity(g, nu, plates, *y, end);
            num += (u - exact).powi(2);
            den += exact * exact;
        }
    }
    (den > 0.0).then(|| (num / den).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The series starts the flow from rest and relaxes it to the parabola: at t = 0 the
    /// velocity vanishes across the channel to the series' truncation, and after 20 H^2 / nu it
    /// is the steady g H^2 / (8 nu) at the centre line.
    #[test]
    fn poiseuille_starts_at_rest_and_ends_parabolic() {
        let (g, nu, plates) = (0.8, 0.1, [0.0, 1.0]);
        for y in [0.1, 0.3, 0.5, 0.9] {
            assert!(poiseuille_velocity(g, nu, plates, y, 0.0).abs() < 1e-6);
        }
        let centre = poiseuille_velocity(g, nu, plates, 0.5, 200.0);
        assert!((centre - g / (8.0 * nu)).abs() < 1e-12);
    }
}
