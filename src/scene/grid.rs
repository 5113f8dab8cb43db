//! The `[grid]` section of a scene: a MAC-grid fluid on the scene's domain, its boundaries,
//! advection scheme, pressure solve, smoke and averaging, and the checks of its values.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::validate::{Checker, Interval};
use super::{Number, Scene, SceneError, Shape};
pub use crate::grid::{
    Advection, GridBoundary, GridSide, InflowTurbulence, ObstacleSurface, Smoke, SmokeSource,
    ViscosityScheme,
};
use crate::Real;

/// Largest number of cells: 1024^3 would need 25 GiB for the velocity alone.
const MAX_CELLS: usize = 512 * 512 * 512;

/// Relative mismatch allowed between the cell sizes along the three axes.
const CUBIC_TOLERANCE: Real = 1e-6;

/// A MAC grid covering the scene's domain with cubic cells.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Grid {
    /// Cells along x, y and z; the domain's extents divided by these must give cubic cells.
    pub resolution: [usize; 3],
    /// `semi_lagrangian` or `maccormack` (default).
    #[serde(default)]
    pub advection: Advection,
    /// Advection–reflection (Zehnder et al. 2018): two half-step projections per step, much
    /// less energy lost to the advect-then-project splitting. Off by default.
    #[serde(default)]
    pub reflection: bool,
    /// Time discretisation of the implicit viscosity: `backward_euler` (default; damps every
    /// mode, safe for the huge viscosities of the precomputation) or `crank_nicolson`
    /// (second order; high-frequency modes ring when nu dt / dx^2 is large).
    #[serde(default)]
    pub viscosity_scheme: ViscosityScheme,
    /// What lies beyond each side of the domain (all no-slip walls by default).
    #[serde(default)]
    pub boundary: GridBoundary,
    /// How the obstacles meet the cells: `cut` (the projection weighs each face by its open
    /// fraction, the no-slip wall sits on the true surface) or `staircase` (each cell solid or
    /// fluid by its centre, first order; slightly cheaper). Default: `cut`, and `staircase` in
    /// coupled scenes, where cut cells are refused: an obstacle's partly open cells under the
    /// water close off pockets of the air's pressure system that the projection cannot solve.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub obstacle_surface: Option<ObstacleSurface>,
    /// Carry the last step's pressure gradient into the momentum and project its increment
    /// only (default true; Goda 1979): the splitting error beside no-slip walls becomes second
    /// order in dt. Off under `reflection` and in coupled scenes, which project the whole
    /// pressure.
    #[serde(default = "super::schema::default_true")]
    pub incremental_pressure: bool,
    /// Synthetic turbulence on the inflow sides (`intensity`, `length`, `modes`): random
    /// Fourier modes carried in at the inflow velocity, drawn from the scene's seed. None when
    /// left out. The normal velocity of each inflow face not under an obstacle is the side's own
    /// plus `intensity` |v| f, f = sqrt(2/N) sum cos(k.(x - v t) + phi) over the N modes,
    /// directions uniform.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inflow_turbulence: Option<InflowTurbulence>,
    /// Fluid density, kg/m^3; scales pressures and forces only (default 1).
    #[serde(default = "default_grid_density")]
    pub density: Real,
    /// Uniform velocity of the fluid at t = 0, m/s.
    #[serde(default)]
    pub initial_velocity: [Real; 3],
    /// An analytic flow at t = 0 instead of the uniform `initial_velocity`: `taylor_green`,
    /// u = (sin x cos y, -cos x sin y, 0) m/s with x, y in m, on a domain periodic in x and y
    /// (2 pi wide for one period), whose kinetic energy decays as exp(-4 nu t) (what
    /// `eddy sweep --analytic taylor-green` measures a run against). Adds `taylor_green_error`
    /// to the metrics.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub initial_flow: Option<InitialFlow>,
    /// Relative residual |r| / |b| the pressure solve stops at.
    #[serde(default = "default_pressure_tolerance")]
    pub pressure_tolerance: Real,
    /// Most pressure iterations per step; a solve that hits it stops the run.
    #[serde(default = "default_pressure_max_iterations")]
    pub pressure_max_iterations: u32,
    /// Apply the scene's gravity as a body force. In one incompressible fluid it is balanced by
    /// a hydrostatic pressure gradient and moves nothing; it shows in the pressure and in the
    /// force probes (buoyancy of obstacles). Off by default: smoke rises by `grid.smoke`
    /// buoyancy along gravity's direction either way.
    #[serde(default)]
    pub gravity: bool,
    /// Vorticity confinement strength epsilon (Fedkiw et al. 2001), dimensionless; 0 is off.
    #[serde(default)]
    pub vorticity_confinement: Real,
    /// Smoke: a passive density (and temperature) with buoyancy, when given.
    #[serde(default)]
    pub smoke: Option<Smoke>,
    /// Start of the time-averaged velocity, s; no average is kept when left out.
    #[serde(default)]
    pub average_from: Option<Real>,
    /// Static flow-field mode (Pfaff et al. 2009, Figure 11): the velocity of a stored grid
    /// frames file (`RUN/frames.h5` of an earlier run on the same grid, relative to the scene)
    /// instead of a solved flow; only the smoke, the boundary layer and the vortex particles
    /// move. Off when left out.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub static_flow: Option<std::path::PathBuf>,
    /// The frame of `static_flow` (counting from 0); the last when left out.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub static_flow_frame: Option<usize>,
    /// Stop once the relative velocity change per unit time, |u^{n+1} - u^n| / (|u^n| dt),
    /// falls below this (steady state); runs to the end when left out.
    #[serde(default)]
    pub steady_tolerance: Option<Real>,
}

/// Analytic initial flows of a grid scene.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum InitialFlow {
    /// The 2-D Taylor–Green vortex.
    TaylorGreen,
}

impl InitialFlow {
    /// The velocity at `x`, m/s.
    pub fn velocity(self, x: &crate::Vec3) -> crate::Vec3 {
        match self {
            InitialFlow::TaylorGreen => {
                crate::Vec3::new(x.x.sin() * x.y.cos(), -x.x.cos() * x.y.sin(), 0.0)
            }
        }
    }
}

pub(super) fn default_grid_density() -> Real {
    1.0
}
fn default_pressure_tolerance() -> Real {
    1e-6
}
fn default_pressure_max_iterations() -> u32 {
    crate::grid::params::PRESSURE_MAX_ITERATIONS as u32
}

impl Grid {
    /// The cell size, m (cubic cells; checked by validation).
    pub fn spacing(&self, scene: &Scene) -> Real {
        (scene.domain.max[0] - scene.domain.min[0]) / self.resolution[0] as Real
    }

    /// Whether a temperature field is needed.
    pub fn has_temperature(&self) -> bool {
        self.smoke.as_ref().is_some_and(Smoke::has_temperature)
    }
}

impl Scene {
    /// Incompressible fluid in a domain without an open side must take in what it lets out:
    /// inflows that do not balance leave the projection an impossible system (the divergence
    /// sticks at net inflow / volume).
    fn check_net_inflow(&self, c: &Checker, sides: &[[GridSide; 2]; 3]) -> Result<(), SceneError> {
        if sides.iter().flatten().any(|s| *s == GridSide::Open) {
            return Ok(());
        }
        let extent: [Real; 3] = std::array::from_fn(|a| self.domain.max[a] - self.domain.min[a]);
        let (lo, hi) = (
            crate::Vec3::from(self.domain.min),
            crate::Vec3::from(self.domain.max),
        );
        let (mut net, mut scale) = (0.0, 0.0);
        for (axis, pair) in sides.iter().enumerate() {
            let area = extent[(axis + 1) % 3] * extent[(axis + 2) % 3];
            for (s, side) in pair.iter().enumerate() {
                let mean = match side {
                    GridSide::ProfiledInflow(p) => p.mean_factor(&lo, &hi),
                    _ => 1.0,
                };
                if let Some(v) = side.inflow_peak() {
                    let inward = mean * if s == 0 { v[axis] } else { -v[axis] };
                    net += inward * area;
                    scale += inward.abs() * area;
                }
            }
        }
        if net.abs() > 1e-9 * scale {
            return Err(c.invalid(
                "grid.boundary",
                format!(
                    "inflows bringing {} m^3/s into a closed domain",
                    Number(net)
                ),
                "an \"open\" side for the flow to leave by, or inflows that balance",
            ));
        }
        Ok(())
    }

    /// Checks the `[grid]` section.
    pub(super) fn validate_grid(&self, c: &Checker) -> Result<(), SceneError> {
        let Some(grid) = &self.grid else {
            return Ok(());
        };
        if self.coupling.is_some() && grid.obstacle_surface == Some(ObstacleSurface::Cut) {
            return Err(c.invalid(
                "grid.obstacle_surface",
                "\"cut\"",
                "\"staircase\" in a coupled scene (cut cells do not meet the water yet)",
            ));
        }
        if grid.static_flow_frame.is_some() && grid.static_flow.is_none() {
            return Err(c.invalid(
                "grid.static_flow_frame",
                grid.static_flow_frame.unwrap_or_default(),
                "only with grid.static_flow",
            ));
        }
        if let Some(path) = &grid.static_flow {
            if !path.is_file() {
                return Err(c.invalid(
                    "grid.static_flow",
                    path.display(),
                    "an existing grid frames file (frames.h5 of a run with output.hdf5 = true)",
                ));
            }
            if let Some(b) = self.all_bodies().find(|b| b.motion != Default::default()) {
                return Err(c.invalid(
                    "grid.static_flow",
                    path.display(),
                    format!(
                        "only with static obstacles: '{}' moves, and a stored flow cannot follow it",
                        b.name.as_deref().unwrap_or("an obstacle")
                    ),
                ));
            }
        }
        let n = grid.resolution;
        for (axis, &cells) in n.iter().enumerate() {
            if cells == 0 {
                return Err(c.invalid(format!("grid.resolution[{axis}]"), 0, "at least 1 cell"));
            }
        }
        let total = n.iter().try_fold(1usize, |acc, &m| acc.checked_mul(m));
        if total.is_none_or(|t| t > MAX_CELLS) {
            return Err(c.invalid(
                "grid.resolution",
                format!("{n:?}"),
                format!("at most {MAX_CELLS} cells in all (512^3)"),
            ));
        }
        let extent = |a: usize| self.domain.max[a] - self.domain.min[a];
        let dx = extent(0) / n[0] as Real;
        for (axis, &cells) in n.iter().enumerate().skip(1) {
            let d = extent(axis) / cells as Real;
            if (d - dx).abs() > CUBIC_TOLERANCE * dx {
                return Err(c.invalid(
                    format!("grid.resolution[{axis}]"),
                    cells,
                    cubic_cells(extent(axis), dx),
                ));
            }
        }
        let sides = grid.boundary.sides();
        if grid.initial_flow == Some(InitialFlow::TaylorGreen)
            && (sides[0][0] != GridSide::Periodic || sides[1][0] != GridSide::Periodic)
        {
            return Err(c.invalid(
                "grid.initial_flow",
                "\"taylor_green\"",
                "a grid periodic in x and y (grid.boundary x_min, x_max, y_min, y_max = \"periodic\")",
            ));
        }
        const NAMES: [[&str; 2]; 3] = [["x_min", "x_max"], ["y_min", "y_max"], ["z_min", "z_max"]];
        for (axis, pair) in sides.iter().enumerate() {
            let periodic = [0, 1].map(|s| pair[s] == GridSide::Periodic);
            if periodic[0] != periodic[1] {
                let lone = if periodic[0] { 0 } else { 1 };
                return Err(c.invalid(
                    format!("grid.boundary.{}", NAMES[axis][lone]),
                    "\"periodic\"",
                    format!(
                        "periodic on both sides or neither (`grid.boundary.{}` is not)",
                        NAMES[axis][1 - lone]
                    ),
                ));
            }
            for (s, side) in pair.iter().enumerate() {
                let key = format!("grid.boundary.{}", NAMES[axis][s]);
                match side {
                    GridSide::MovingWall(v) => {
                        c.vec3(&key, *v)?;
                        if v[axis] != 0.0 {
                            return Err(c.invalid(
                                format!("{key}.moving_wall[{axis}]"),
                                v[axis],
                                "0: a wall moves in its own plane",
                            ));
                        }
                    }
                    GridSide::Inflow(v) => c.vec3(&key, *v)?,
                    GridSide::ProfiledInflow(p) => check_profile(c, &key, p, axis)?,
                    _ => {}
                }
            }
        }
        self.check_net_inflow(c, &sides)?;
        if let Some(t) = &grid.inflow_turbulence {
            check_inflow_turbulence(c, t, &sides, grid.static_flow.is_some())?;
        }
        c.ranged("grid.density", grid.density)?;
        c.vec3("grid.initial_velocity", grid.initial_velocity)?;
        c.ranged("grid.pressure_tolerance", grid.pressure_tolerance)?;
        c.ranged(
            "grid.pressure_max_iterations",
            Real::from(grid.pressure_max_iterations),
        )?;
        c.ranged("grid.vorticity_confinement", grid.vorticity_confinement)?;
        if let Some(t) = grid.average_from {
            c.ranged("grid.average_from", t)?;
        }
        if let Some(tol) = grid.steady_tolerance {
            c.ranged("grid.steady_tolerance", tol)?;
        }
        if let Some(smoke) = &grid.smoke {
            c.ranged("grid.smoke.buoyancy", smoke.buoyancy)?;
            c.ranged("grid.smoke.heat_buoyancy", smoke.heat_buoyancy)?;
            for (i, source) in smoke.sources.iter().enumerate() {
                let key = format!("grid.smoke.sources[{i}]");
                if matches!(source.shape, Shape::Mesh { .. }) {
                    return Err(c.invalid(
                        format!("{key}.shape.type"),
                        "\"mesh\"",
                        "box, sphere, cylinder or capsule",
                    ));
                }
                c.shape(&format!("{key}.shape"), &source.shape)?;
                c.vec3(&format!("{key}.position"), source.position)?;
                // A source outside the domain emits nothing.
                if source.motion.keyframes.is_empty() {
                    self.point_inside(c, &format!("{key}.position"), &source.position)?;
                }
                for (k, frame) in source.motion.keyframes.iter().enumerate() {
                    let at = format!("{key}.motion.keyframes[{k}].position");
                    self.point_inside(c, &at, &frame.position)?;
                }
                c.vec3(&format!("{key}.rotation"), source.rotation)?;
                c.ranged(&format!("{key}.density"), source.density)?;
                c.ranged(&format!("{key}.temperature"), source.temperature)?;
                if let Some(v) = source.velocity {
                    c.vec3(&format!("{key}.velocity"), v)?;
                }
                c.motion(&format!("{key}.motion"), &source.motion)?;
            }
        }
        if !self.refinement.is_none() && self.fluid.is_none() {
            return Err(c.invalid(
                "refinement.method",
                format!("{:?}", self.refinement.method()),
                "\"none\" in a grid scene without [fluid] (the refinements act on SPH particles)",
            ));
        }
        if self.fluid.is_some() && !self.probes.is_empty() {
            return Err(c.invalid(
                "probes",
                format!("{} probes", self.probes.len()),
                "none in a scene with both [grid] and [fluid] yet (a probe would not say which \
                 solver it samples)",
            ));
        }
        Ok(())
    }
}

/// A profiled inflow is normal to its side, varies across an axis along the side (`plane`,
/// `table`), and a table's coordinates increase with finite factors.
fn check_profile(
    c: &Checker,
    key: &str,
    p: &crate::grid::InflowProfile,
    axis: usize,
) -> Result<(), SceneError> {
    use crate::grid::ProfileShape;
    let key = format!("{key}.profiled_inflow");
    c.vec3(&format!("{key}.velocity"), p.velocity)?;
    if let Some(a) = (0..3).find(|&a| a != axis && p.velocity[a] != 0.0) {
        return Err(c.invalid(
            format!("{key}.velocity[{a}]"),
            p.velocity[a],
            "0: a profiled inflow is normal to its side",
        ));
    }
    let needs_axis = matches!(p.shape, ProfileShape::Plane | ProfileShape::Table);
    match p.across {
        Some(a) if a > 2 || a == axis => {
            return Err(c.invalid(
                format!("{key}.across"),
                a,
                format!("an axis along the side (0, 1 or 2 for x, y, z; not {axis}, its normal)"),
            ))
        }
        None if needs_axis => {
            return Err(c.invalid(
                format!("{key}.across"),
                "nothing",
                "the axis along the side the profile varies across (0, 1 or 2 for x, y, z)",
            ))
        }
        _ => {}
    }
    if p.shape == ProfileShape::Table {
        if p.table.is_empty() {
            return Err(c.invalid(format!("{key}.table"), "[]", "[coordinate, factor] pairs"));
        }
        for (i, pair) in p.table.iter().enumerate() {
            c.ranged(&format!("{key}.table[{i}][1]"), pair[1])?;
            let after = i.checked_sub(1).map(|j| p.table[j][0]);
            let allowed = match after {
                Some(x) => Interval::gt(x).noted("the coordinate before it (increasing)"),
                None => Interval::any(),
            };
            c.num(&format!("{key}.table[{i}][0]"), pair[0], allowed)?;
        }
    } else if !p.table.is_empty() {
        return Err(c.invalid(
            format!("{key}.table"),
            "a table",
            "no table unless shape = \"table\"",
        ));
    }
    Ok(())
}

/// `grid.inflow_turbulence`: values in range, an inflow to act on and an open side for the
/// fluctuating flux to leave by (a closed domain's projection needs the inflow to balance at
/// every step); not with a stored flow, which no inflow changes.
fn check_inflow_turbulence(
    c: &Checker,
    t: &InflowTurbulence,
    sides: &[[GridSide; 2]; 3],
    static_flow: bool,
) -> Result<(), SceneError> {
    let key = "grid.inflow_turbulence";
    c.ranged(&format!("{key}.intensity"), t.intensity)?;
    c.ranged(&format!("{key}.length"), t.length)?;
    c.ranged(&format!("{key}.modes"), t.modes as Real)?;
    let all = sides.iter().flatten();
    if !all.clone().any(|s| s.inflow_peak().is_some()) {
        return Err(c.invalid(key, "a table", "a grid with an inflow side to fluctuate"));
    }
    if !all.clone().any(|s| *s == GridSide::Open) {
        return Err(c.invalid(
            key,
            "a table",
            "an \"open\" side for the fluctuating inflow to leave by",
        ));
    }
    if static_flow {
        return Err(c.invalid(
            key,
            "a table",
            "not with grid.static_flow (no inflow is solved)",
        ));
    }
    Ok(())
}

impl Grid {
    /// The obstacle surface the scene asks for, or its default (see `obstacle_surface`).
    pub fn surface(&self, coupled: bool) -> ObstacleSurface {
        self.obstacle_surface.unwrap_or(if coupled {
            ObstacleSurface::Staircase
        } else {
            ObstacleSurface::Cut
        })
    }
}

/// What a resolution along an axis must be for cells of side `dx` (the first axis's) over
/// `extent`: the whole number of cells that fits, or, when not even one does, the extent to
/// change.
fn cubic_cells(extent: Real, dx: Real) -> String {
    let cells = (extent / dx).round();
    if cells >= 1.0 {
        format!(
            "{} for cubic cells of {} m (domain extent {} m along this axis)",
            Number(cells),
            Number(dx),
            Number(extent)
        )
    } else {
        format!(
            "cubic cells: the domain's {} m along this axis holds less than one cell of {} m; \
             widen the domain or refine the first axis",
            Number(extent),
            Number(dx)
        )
    }
}
