//! The grid's turbulence stage: Pfaff et al. 2009, Figure 9, lines 1–25, run before the grid's
//! own step (line 28). Each part is named as the plan names it:
//!
//! - `wall layer` (lines 2–6): for each obstacle with a database, its motion relative to the
//!   ambient flow, the lookup, and at each wall-attached cell the nearest precomputed point's
//!   value, kept where it is larger in magnitude than the field's (PAPER-NOTES, line 5).
//! - `abl advection` (line 9): omega_ABL, a cell-centred vector field, advected with the
//!   grid's own scheme and zeroed inside obstacles.
//! - `seeding` (lines 11–20): the shared routine of [`crate::abl::seeding`] over the cells with
//!   nonzero omega_ABL, with the distance to the nearest wall as mixing length.
//! - `vortex dynamics` (lines 23–24) and `synthesis` (line 25): the vortex layer, reading and
//!   writing the grid through its source and sink.
//!
//! **Ambient flow.** An obstacle's velocity relative to the flow is its own velocity minus the
//! mean cell velocity over a shell of fluid cells between [`SHELL_INNER`] and
//! [`SHELL_OUTER`] times its reach (half its bounding-box diagonal, at least two cells) from
//! its surface. The disturbance a body makes in a potential flow is a dipole at leading order,
//! whose mean over a shell around the body vanishes, so the shell mean reads the stream the
//! body sits in: a fixed sphere in a stream U sees -U, one moving at V in still air sees V.
//! The obstacle's own angular velocity is used as is: the flow a spinning body drags along is
//! its own boundary layer, not an ambient rotation.

use std::time::Instant;

use ndarray::Array3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::simulation::{Simulation, StepError};
use super::stages::{Stage, StepRecord};
use super::RunError;
use crate::abl::seeding::{scatter, seed, SeedSamples, SeedingParams};
use crate::abl::{AblDatabase, AblSettings, Seeding, WallLayer};
use crate::grid::advect::advect_into;
use crate::grid::walls::{boundary_cells, mean_velocity, shell_cells, wall_distance};
use crate::grid::{Advection, GridSolver};
use crate::vortex::{synthesize, Dynamics, DynamicsSettings, VortexParticles};
use crate::{Real, Vec3};

/// Inner radius of the ambient-flow shell, in reaches of the obstacle from its surface.
pub const SHELL_INNER: Real = 0.5;
/// Outer radius of the ambient-flow shell, in reaches of the obstacle from its surface.
pub const SHELL_OUTER: Real = 1.5;

/// Salt of the seeding generator's seed, so it draws a different stream from the split
/// displacements of the same scene seed.
const SEEDING_STREAM: u64 = 0x5eed_ab1e;

/// The turbulence state a grid scene carries from step to step.
pub struct Turbulence {
    /// omega_ABL per cell, 1/s, one array per component.
    pub abl: [Array3<Real>; 3],
    pub vortices: VortexParticles,
}

/// What the turbulence stage did in one step.
#[derive(Debug, Clone, Copy, Default)]
pub struct TurbulenceStats {
    pub seeded: usize,
    pub split: usize,
    pub merged: usize,
    pub dissipated: usize,
    /// Particles after the step's dynamics.
    pub particles: usize,
    /// Total kernel energy of the particles, m^5/s^2.
    pub energy: Real,
    /// Sum of |omega_ABL| over the cells after seeding, 1/s.
    pub abl_sum: Real,
    /// Wall time of each part, in the order of [`PARTS`].
    pub seconds: [f64; 5],
}

/// The stage's parts, in order.
pub const PARTS: [&str; 5] = [
    "wall layer",
    "abl advection",
    "seeding",
    "vortex dynamics",
    "synthesis",
];

/// Below this fraction of the field's largest magnitude, omega_ABL is flushed to zero after
/// advection. Interpolating advection spreads a plume's tails over the whole grid within a few
/// hundred steps (211,000 of the 288,000 cells of the cavity at paper scale held some), and
/// every nonzero cell costs a random draw and a place in the seeding's neighbour search; what
/// is flushed is at most this fraction of the peak per cell.
pub const FLUSH: Real = 1e-6;

/// Zeroes omega_ABL inside obstacles and where its magnitude is below [`FLUSH`] of the largest.
fn flush(abl: &mut [Array3<Real>; 3], grid: &GridSolver) {
    let [x, y, z] = abl;
    let magnitude2 = |a: Real, b: Real, c: Real| a * a + b * b + c * c;
    let peak2 = ndarray::Zip::from(&*x)
        .and(&*y)
        .and(&*z)
        .fold(0.0, |m: Real, &a, &b, &c| m.max(magnitude2(a, b, c)));
    let floor2 = FLUSH * FLUSH * peak2;
    ndarray::Zip::indexed(x)
        .and(y)
        .and(z)
        .par_for_each(|(i, j, k), a, b, c| {
            if magnitude2(*a, *b, *c) < floor2 || grid.bounds.is_solid([i, j, k]) {
                (*a, *b, *c) = (0.0, 0.0, 0.0);
            }
        });
}

/// One obstacle's database and what is cached of its cells while it does not move.
struct Obstacle {
    body: usize,
    layer: WallLayer,
    /// Wall-attached cells and, per cell, its nearest boundary point.
    cells: Vec<[usize; 3]>,
    nearest: Vec<usize>,
    /// The ambient-flow shell.
    shell: Vec<[usize; 3]>,
    /// Half the bounding-box diagonal, m.
    reach: Real,
}

/// The stage (see the module documentation).
pub struct GridTurbulence {
    settings: AblSettings,
    obstacles: Vec<Obstacle>,
    dynamics: Dynamics,
    rng: ChaCha8Rng,
    scheme: Advection,
    /// Wall distance per cell, kept while no body moves.
    distance: Option<Array3<Real>>,
    /// The advected omega_ABL component, swapped with the field's (no allocation per step).
    advected: Array3<Real>,
    moving: bool,
}

impl GridTurbulence {
    /// Opens every database (checking it belongs to its obstacle) and builds the empty state
    /// into `sim`.
    pub fn build(
        settings: AblSettings,
        sim: &mut Simulation,
        shapes: &[crate::geometry::Shape],
        scheme: Advection,
    ) -> Result<Self, RunError> {
        let grid = sim.grid.as_ref().expect("turbulence is built for a grid");
        let dx = grid.mac.dx;
        let mut obstacles = Vec::new();
        for (body, path) in &settings.databases {
            let db = AblDatabase::open(path, Some(&shapes[*body]))?;
            let spacing = db.header().spacing;
            let (lo, hi) = grid.bodies[*body].local_aabb();
            obstacles.push(Obstacle {
                body: *body,
                layer: WallLayer::new(db, 2.0 * (dx + spacing)),
                cells: Vec::new(),
                nearest: Vec::new(),
                shell: Vec::new(),
                reach: (0.5 * (hi - lo).norm()).max(2.0 * dx),
            });
        }
        let p = &settings.params;
        let dynamics = Dynamics::new(
            DynamicsSettings {
                dissipation_cells: p.dissipation_radius,
                inertial_radius: p.split_radius * dx,
                children: p.children,
                cascade_time: p.cascade_time,
                ..Default::default()
            },
            settings.seed,
        )?;
        let moving = grid.bodies.iter().any(|b| b.is_moving());
        sim.turbulence = Some(Turbulence {
            abl: std::array::from_fn(|_| Array3::zeros(grid.mac.dims)),
            vortices: VortexParticles::new(),
        });
        Ok(Self {
            rng: ChaCha8Rng::seed_from_u64(settings.seed ^ SEEDING_STREAM),
            settings,
            obstacles,
            dynamics,
            scheme,
            distance: None,
            advected: Array3::zeros(grid.mac.dims),
            moving,
        })
    }

    /// Lines 2–6: the wall-attached layer of every obstacle into `abl`.
    fn attach(&mut self, grid: &GridSolver, abl: &mut [Array3<Real>; 3]) {
        let t = grid.time();
        for o in &mut self.obstacles {
            let body = &grid.bodies[o.body];
            if o.cells.is_empty() || self.moving {
                o.cells = boundary_cells(grid, o.body);
                let pose = body.pose(t);
                o.nearest = o
                    .cells
                    .iter()
                    .map(|&c| {
                        let x = crate::Point3::from(grid.mac.cell_center(c));
                        o.layer.nearest(&pose.inverse_transform_point(&x))
                    })
                    .collect();
                o.shell = shell_cells(grid, o.body, SHELL_INNER * o.reach, SHELL_OUTER * o.reach);
            }
            let ambient = mean_velocity(grid, &o.shell).unwrap_or_else(Vec3::zeros);
            let linear = body.linear_velocity(t) - ambient;
            let values = o.layer.values(
                &body.pose(t),
                &linear,
                &body.angular_velocity(t),
                self.settings.params.gain,
            );
            for (&c, &p) in o.cells.iter().zip(&o.nearest) {
                let pre = values[p];
                let now = Vec3::new(abl[0][c], abl[1][c], abl[2][c]);
                if pre.norm_squared() > now.norm_squared() {
                    (0..3).for_each(|a| abl[a][c] = pre[a]);
                }
            }
        }
    }

    /// Lines 11–20: seeds particles from the cells with nonzero omega_ABL.
    fn seed(&mut self, grid: &GridSolver, state: &mut Turbulence, dt: Real) -> usize {
        if self.distance.is_none() || self.moving {
            self.distance = Some(wall_distance(grid));
        }
        let distance = self.distance.as_ref().expect("computed above");
        let dx = grid.mac.dx;
        let mut samples = SeedSamples::default();
        let mut cells = Vec::new();
        for (idx, &l) in distance.indexed_iter() {
            let idx = [idx.0, idx.1, idx.2];
            let w = Vec3::new(state.abl[0][idx], state.abl[1][idx], state.abl[2][idx]);
            if w != Vec3::zeros() {
                samples.push(grid.mac.cell_center(idx), w, dx * dx * dx, l);
                cells.push(idx);
            }
        }
        let p = &self.settings.params;
        let params = SeedingParams {
            c_p: p.c_p,
            u0: self.settings.u0,
            r_max: p.r_max * dx,
            r_min: p.dissipation_radius * dx,
        };
        let mut seeds = seed(&mut samples, &params, dt, &mut self.rng);
        for (idx, w) in cells.iter().zip(&samples.omega) {
            (0..3).for_each(|a| state.abl[a][*idx] = w[a]);
        }
        if p.seeding == Seeding::Random && !seeds.is_empty() {
            let fluid: Vec<[usize; 3]> = distance
                .indexed_iter()
                .filter(|(_, &l)| l > 0.0)
                .map(|(i, _)| [i.0, i.1, i.2])
                .collect();
            let sites: Vec<Vec3> = fluid.iter().map(|&c| grid.mac.cell_center(c)).collect();
            let site_distance: Vec<Real> = fluid.iter().map(|&c| distance[c]).collect();
            scatter(&mut seeds, &sites, &site_distance, dx, &mut self.rng);
        }
        for s in &seeds {
            state
                .vortices
                .push(s.x, s.omega, s.sigma)
                .expect("seeds are finite with a positive scale");
        }
        seeds.len()
    }
}

impl Stage for GridTurbulence {
    fn name(&self) -> &'static str {
        "turbulence"
    }

    fn describe(&self, _sim: &Simulation) -> (String, Vec<(&'static str, String)>) {
        let p = &self.settings.params;
        let names: Vec<String> = self
            .obstacles
            .iter()
            .map(|o| {
                let h = o.layer.database().header();
                format!(
                    "{} ({}, {} points)",
                    h.obstacle,
                    o.layer.database().path().display(),
                    o.layer.database().len()
                )
            })
            .collect();
        let seeding = match p.seeding {
            Seeding::Abl => "Eq. 8 from omega_ABL",
            Seeding::Random => "random along the walls (Figure 8 baseline)",
        };
        (
            format!(
                "artificial boundary layers (Pfaff et al. 2009, Figure 9) of {}",
                names.join(", ")
            ),
            vec![
                (
                    PARTS[0],
                    format!(
                        "lookup per obstacle, gain {}, nearest point per wall cell, max magnitude",
                        p.gain
                    ),
                ),
                (
                    PARTS[1],
                    format!(
                        "omega_ABL by {:?}, zero in obstacles, flushed below {FLUSH:e} of its peak",
                        self.scheme
                    ),
                ),
                (
                    PARTS[2],
                    format!(
                        "{seeding}: c_p = {} 1/s, |U_0| = {} m/s, r_max = {} cells",
                        p.c_p, self.settings.u0, p.r_max
                    ),
                ),
                (
                    PARTS[3],
                    format!(
                        "advect, stretch, merge, split at radius <= {} cells into {}, \
                         dissipate below {} cells",
                        p.split_radius, p.children, p.dissipation_radius
                    ),
                ),
                (PARTS[4], "Eq. 14 weights onto the grid's faces".into()),
            ],
        )
    }

    fn run(&mut self, sim: &mut Simulation, rec: &mut StepRecord) -> Result<(), StepError> {
        let grid = sim.grid.as_mut().expect("turbulence is built for a grid");
        let state = sim
            .turbulence
            .as_mut()
            .expect("built with the turbulence state");
        let dt = rec.dt;
        let mut stats = TurbulenceStats::default();
        let mut clock = Instant::now();
        let mut lap = |part: usize, stats: &mut TurbulenceStats| {
            stats.seconds[part] = clock.elapsed().as_secs_f64();
            clock = Instant::now();
        };
        self.attach(grid, &mut state.abl);
        lap(0, &mut stats);
        let stagger = grid.mac.cell_stagger();
        for a in 0..3 {
            advect_into(
                &state.abl[a],
                stagger,
                &grid.mac,
                dt,
                self.scheme,
                &mut self.advected,
            );
            std::mem::swap(&mut state.abl[a], &mut self.advected);
        }
        flush(&mut state.abl, grid);
        lap(1, &mut stats);
        stats.seeded = self.seed(grid, state, dt);
        lap(2, &mut stats);
        let report = self
            .dynamics
            .step(&mut state.vortices, &grid.mac, dt, grid.mac.dx);
        stats.split = report.split;
        stats.merged = report.merged;
        stats.dissipated = report.dissipated;
        lap(3, &mut stats);
        synthesize(&state.vortices, &mut grid.mac, 1)?;
        lap(4, &mut stats);
        stats.particles = state.vortices.len();
        stats.energy = state.vortices.total_energy();
        let [x, y, z] = &state.abl;
        stats.abl_sum = ndarray::Zip::from(x)
            .and(y)
            .and(z)
            .fold(0.0, |s, &a, &b, &c| s + (a * a + b * b + c * c).sqrt());
        rec.turbulence = Some(stats);
        Ok(())
    }

    fn ran<'a>(&self, _sim: &'a Simulation) -> &'a [&'static str] {
        &PARTS
    }
}
