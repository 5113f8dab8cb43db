//! The grid's turbulence stage (see the parent module). Its parts, named as the plan names
//! them:
//!
//! - `wall layer` (lines 2–6): for each obstacle with a database, its motion relative to the
//!   ambient flow, the lookup, and at each wall-attached cell the nearest precomputed point's
//!   value, kept where it is larger in magnitude than the field's (docs/src/paper-notes.md, "Figure 9, line 5").
//! - `abl advection` (line 9): omega_ABL, a cell-centred vector field, advected with the
//!   grid's own scheme and zeroed inside obstacles.
//! - `seeding` (lines 11–20): the shared routine over the cells with nonzero omega_ABL, with
//!   the distance to the nearest wall as mixing length.
//! - `vortex dynamics` (lines 23–24) and `synthesis` (line 25): the vortex layer, reading and
//!   writing the grid through its source and sink. With `upsample = 2` and smoke, the flow's
//!   velocity is first interpolated onto the smoke's grid twice as fine (section 5.2) and the
//!   kernels are added there too, so the smoke is carried by them at that resolution.

use ndarray::Array3;

use super::{
    push_seeds, Common, Laps, Resolution, Turbulence, TurbulenceStats, DYNAMICS, SEEDING,
    SHELL_INNER, SHELL_OUTER, SYNTHESIS, WALL_LAYER,
};
use crate::abl::seeding::{scatter, seed, SeedSamples};
use crate::abl::{AblSettings, Seeding};
use crate::grid::advect::{advect_band_into, Band};
use crate::grid::walls::{boundary_cells, mean_velocity, shell_cells, wall_distance};
use crate::grid::{Advection, GridSolver};
use crate::pipeline::order::Built;
use crate::pipeline::outputs::Kind;
use crate::pipeline::simulation::{Simulation, StepError};
use crate::pipeline::spec::RunSpec;
use crate::pipeline::stages::{AddedColumns, Stage, StepRecord};
use crate::pipeline::RunError;
use crate::vortex::{synthesize, synthesize_refined, VortexParticles};
use crate::{Real, Vec3};

const ABL_ADVECTION: &str = "abl advection";

/// The stage's parts, in order.
pub const PARTS: [&str; 5] = [WALL_LAYER, ABL_ADVECTION, SEEDING, DYNAMICS, SYNTHESIS];

/// Below this fraction of the field's largest magnitude, omega_ABL is flushed to zero after
/// advection. Interpolating advection spreads a plume's tails over the whole grid within a few
/// hundred steps (most of the cavity's cells at paper scale held some), and every nonzero cell costs a random draw and a place in the seeding's neighbour search; what
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

/// The cells omega_ABL can reach in a step: the box of its nonzero cells widened as
/// [`advect_band_into`] asks (twice the cells the fastest face moves in `dt`, plus three), so
/// its advection costs the plume's extent, not the grid's. Empty when the field is zero.
fn band(abl: &[Array3<Real>; 3], grid: &GridSolver, dt: Real) -> Band {
    let dims = grid.mac.dims;
    let (mut lo, mut hi) = (dims, [0; 3]);
    for field in abl {
        for ((i, j, k), &w) in field.indexed_iter() {
            if w != 0.0 {
                for (a, c) in [i, j, k].into_iter().enumerate() {
                    lo[a] = lo[a].min(c);
                    hi[a] = hi[a].max(c + 1);
                }
            }
        }
    }
    if hi[0] == 0 {
        return [0..0, 0..0, 0..0];
    }
    let pad = 2 * (grid.mac.max_face_speed() * dt / grid.mac.dx).ceil() as usize + 3;
    std::array::from_fn(|a| lo[a].saturating_sub(pad)..(hi[a] + pad).min(dims[a]))
}

/// What is cached of an obstacle's cells while it does not move.
#[derive(Default)]
struct Cells {
    /// Wall-attached cells and, per cell, its nearest boundary point.
    attached: Vec<[usize; 3]>,
    nearest: Vec<usize>,
    /// The ambient-flow shell.
    shell: Vec<[usize; 3]>,
}

/// The stage (see the module documentation).
pub struct GridTurbulence {
    common: Common,
    /// Per obstacle of `common`, its cells.
    cells: Vec<Cells>,
    scheme: Advection,
    /// Wall distance per cell, kept while no body moves.
    distance: Option<Array3<Real>>,
    /// The advected omega_ABL component, swapped with the field's (no allocation per step).
    advected: Array3<Real>,
    moving: bool,
}

impl GridTurbulence {
    /// The stage of a run with a grid and an obstacle with a database.
    pub(in crate::pipeline) fn stage(spec: &RunSpec, sim: &mut Simulation) -> Built {
        let (Some(settings), Some(grid)) = (&spec.abl, &spec.grid) else {
            return Ok(None);
        };
        let scheme = grid.params.advection;
        let stage = Self::build(settings.clone(), sim, &spec.shapes, scheme)?;
        Ok(Some(Box::new(stage)))
    }

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
        let res = Resolution {
            dx,
            thickness: dx,
            on_particles: false,
        };
        let common = Common::build(settings, shapes, &grid.bodies, res)?;
        let moving = grid.bodies.iter().any(|b| b.is_moving());
        sim.grid_turbulence = Some(Turbulence::new(
            Some(std::array::from_fn(|_| Array3::zeros(grid.mac.dims))),
            &PARTS,
        ));
        Ok(Self {
            cells: common.obstacles.iter().map(|_| Cells::default()).collect(),
            common,
            scheme,
            distance: None,
            advected: Array3::zeros(grid.mac.dims),
            moving,
        })
    }

    /// Lines 2–6: the wall-attached layer of every obstacle into `abl`.
    fn attach(&mut self, grid: &GridSolver, abl: &mut [Array3<Real>; 3]) {
        let t = grid.time();
        let scale = self.common.scale();
        for (o, cells) in self.common.obstacles.iter().zip(&mut self.cells) {
            let body = &grid.bodies[o.body];
            if cells.attached.is_empty() || self.moving {
                cells.attached = boundary_cells(grid, o.body);
                let pose = body.pose(t);
                cells.nearest = cells
                    .attached
                    .iter()
                    .map(|&c| {
                        let x = crate::Point3::from(grid.mac.cell_center(c));
                        o.layer.nearest(&pose.inverse_transform_point(&x))
                    })
                    .collect();
                cells.shell =
                    shell_cells(grid, o.body, SHELL_INNER * o.reach, SHELL_OUTER * o.reach);
            }
            let values = o.values(body, t, mean_velocity(grid, &cells.shell), scale);
            for (&c, &p) in cells.attached.iter().zip(&cells.nearest) {
                let pre = values[p];
                let now = Vec3::new(abl[0][c], abl[1][c], abl[2][c]);
                if pre.norm_squared() > now.norm_squared() {
                    (0..3).for_each(|a| abl[a][c] = pre[a]);
                }
            }
        }
    }

    /// Lines 11–20: seeds particles from the cells with nonzero omega_ABL.
    fn seed(
        &mut self,
        grid: &GridSolver,
        abl: &mut [Array3<Real>; 3],
        vortices: &mut VortexParticles,
        dt: Real,
    ) -> usize {
        if self.distance.is_none() || self.moving {
            self.distance = Some(wall_distance(grid));
        }
        let distance = self.distance.as_ref().expect("computed above");
        let dx = grid.mac.dx;
        let mut samples = SeedSamples::default();
        let mut cells = Vec::new();
        for (idx, &l) in distance.indexed_iter() {
            let idx = [idx.0, idx.1, idx.2];
            let w = Vec3::new(abl[0][idx], abl[1][idx], abl[2][idx]);
            if w != Vec3::zeros() {
                samples.push(grid.mac.cell_center(idx), w, dx * dx * dx, l);
                cells.push(idx);
            }
        }
        let params = self.common.seeding_params();
        let rng = &mut self.common.rng;
        let mut seeds = seed(&mut samples, &params, dt, rng);
        for (idx, w) in cells.iter().zip(&samples.omega) {
            (0..3).for_each(|a| abl[a][*idx] = w[a]);
        }
        if self.common.settings.params.seeding == Seeding::Random && !seeds.is_empty() {
            let fluid: Vec<[usize; 3]> = distance
                .indexed_iter()
                .filter(|(_, &l)| l > 0.0)
                .map(|(i, _)| [i.0, i.1, i.2])
                .collect();
            let sites: Vec<Vec3> = fluid.iter().map(|&c| grid.mac.cell_center(c)).collect();
            let site_distance: Vec<Real> = fluid.iter().map(|&c| distance[c]).collect();
            scatter(&mut seeds, &sites, &site_distance, dx, rng);
        }
        push_seeds(&seeds, vortices);
        seeds.len()
    }
}

impl Stage for GridTurbulence {
    fn name(&self) -> &'static str {
        "turbulence"
    }

    fn save(&self, into: &mut crate::state::Saver) {
        self.common.save(into);
    }

    fn restore(&mut self, from: &crate::state::Restorer) -> Result<(), crate::state::StateError> {
        self.common.restore(from)
    }

    fn describe(&self, sim: &Simulation) -> (String, Vec<(&'static str, String)>) {
        let fine_smoke = sim
            .grid
            .as_ref()
            .and_then(|g| g.smoke.as_ref())
            .is_some_and(|s| s.fine.is_some());
        let (headline, [wall, seeding, dynamics]) = self.common.describe("cells");
        (
            headline,
            vec![
                (
                    WALL_LAYER,
                    format!("{wall}, nearest point per wall cell, max magnitude"),
                ),
                (
                    ABL_ADVECTION,
                    format!(
                        "omega_ABL by {} over the band its nonzero cells can reach, zero in \
                         obstacles, flushed below {FLUSH:e} of its peak",
                        self.scheme.label()
                    ),
                ),
                (SEEDING, seeding),
                (DYNAMICS, dynamics),
                (
                    SYNTHESIS,
                    format!(
                        "Eq. 14 weights onto the grid's faces, on a lattice {}x finer{}",
                        self.common.settings.params.upsample,
                        if fine_smoke {
                            ", and onto the smoke's fine faces"
                        } else {
                            ""
                        }
                    ),
                ),
            ],
        )
    }

    fn run(&mut self, sim: &mut Simulation, rec: &mut StepRecord) -> Result<(), StepError> {
        let grid = sim.grid.as_mut().expect("turbulence is built for a grid");
        let state = sim
            .grid_turbulence
            .as_mut()
            .expect("built with the turbulence state");
        let abl = state.abl.as_mut().expect("a grid's omega_ABL is on cells");
        let dt = rec.dt;
        let mut stats = TurbulenceStats::default();
        let mut laps = Laps::start(&PARTS);
        self.attach(grid, abl);
        laps.lap(WALL_LAYER);
        let stagger = grid.mac.cell_stagger();
        let band = band(abl, grid, dt);
        for field in abl.iter_mut() {
            advect_band_into(
                field,
                stagger,
                &grid.mac,
                dt,
                self.scheme,
                &band,
                &mut self.advected,
            );
            std::mem::swap(field, &mut self.advected);
        }
        flush(abl, grid);
        laps.lap(ABL_ADVECTION);
        stats.seeded = self.seed(grid, abl, &mut state.vortices, dt);
        laps.lap(SEEDING);
        let report = self
            .common
            .dynamics
            .step(&mut state.vortices, &grid.mac, dt, grid.mac.dx);
        stats.dynamics(report);
        laps.lap(DYNAMICS);
        let upsample = self.common.settings.params.upsample;
        match grid.lend_fine_velocity() {
            (flow, Some(fine)) => {
                let [u, v, w] = &mut fine.u;
                let faces = [u.view_mut(), v.view_mut(), w.view_mut()];
                synthesize_refined(&state.vortices, flow, upsample, faces)?;
                fine.sync_periodic();
            }
            (flow, None) => {
                synthesize(&state.vortices, flow, upsample)?;
            }
        }
        if grid.has_liquid() {
            // The faces under a coupled liquid carry its velocity, not the air's kernels.
            grid.bounds.apply(&mut grid.mac);
        }
        laps.lap(SYNTHESIS);
        stats.seconds = laps.seconds;
        stats.particles = state.vortices.len();
        stats.energy = state.vortices.total_energy();
        let [x, y, z] = &*abl;
        stats.abl_sum = ndarray::Zip::from(x)
            .and(y)
            .and(z)
            .fold(0.0, |s, &a, &b, &c| s + (a * a + b * b + c * c).sqrt());
        state.record(stats, Kind::Grid, rec);
        Ok(())
    }

    fn ran<'a>(&self, _sim: &'a Simulation) -> &'a [&'static str] {
        &PARTS
    }

    fn added_columns(&self, sim: &Simulation) -> Option<AddedColumns> {
        let state = sim.grid_turbulence.as_ref()?;
        Some(state.added_columns(Kind::Grid))
    }
}
