//! The turbulence stages: Pfaff et al. 2009, Figure 9, lines 1–25, run before the solver's own
//! step (line 28), on a grid ([`grid`]) or on SPH particles ([`sph`]). Both share what this
//! module holds: the obstacles' databases, the ambient flow around an obstacle, the seeding
//! routine of [`crate::abl::seeding`] (one function for cells and particles), and the vortex
//! layer's dynamics, reading and writing the solver through its velocity source and sink.
//!
//! **Ambient flow.** An obstacle's velocity relative to the flow is its own velocity minus the
//! mean fluid velocity over a shell between [`SHELL_INNER`] and [`SHELL_OUTER`] times its
//! reach (half its bounding-box diagonal, at least two cells or spacings) from its surface.
//! The disturbance a body makes in a potential flow is a dipole at leading order, whose mean
//! over a shell around the body vanishes, so the shell mean reads the stream the body sits in:
//! a fixed sphere in a stream U sees -U, one moving at V in still fluid sees V. The obstacle's
//! own angular velocity is used as is: the flow a spinning body drags along is its own boundary
//! layer, not an ambient rotation.

mod grid;
mod sph;

pub use grid::GridTurbulence;
pub use sph::{fit_to_liquid, SphTurbulence, Surface, ABL_FIELD};

use std::time::Instant;

use ndarray::Array3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::state::{Persist, Restorer, Saver, StateError};

use super::outputs::Kind;
use super::stages::{AddedColumns, StepRecord};
use super::RunError;
use crate::abl::seeding::{Seed, SeedingParams};
use crate::abl::{AblDatabase, AblSettings, Seeding, WallLayer};
use crate::geometry::{RigidBody, Shape};
use crate::vortex::dynamics::StepReport;
use crate::vortex::{Dynamics, DynamicsSettings, VortexParticles};
use crate::{Real, Vec3};

/// Inner radius of the ambient-flow shell, in reaches of the obstacle from its surface.
pub const SHELL_INNER: Real = 0.5;
/// Outer radius of the ambient-flow shell, in reaches of the obstacle from its surface.
pub const SHELL_OUTER: Real = 1.5;

/// Salt of the seeding generator's seed, so it draws a different stream from the split
/// displacements of the same scene seed.
const SEEDING_STREAM: u64 = 0x5eed_ab1e;

/// The turbulence state a scene carries from step to step.
pub struct Turbulence {
    /// omega_ABL per grid cell, 1/s, one array per component (grid scenes; on SPH particles
    /// it rides on the fluid as the carried field [`ABL_FIELD`]).
    pub abl: Option<[Array3<Real>; 3]>,
    pub vortices: VortexParticles,
    /// The stage's parts, in order (the `*_seconds` columns of the metrics).
    pub parts: &'static [&'static str; 5],
    /// What the stage did in its last step.
    pub last: Option<TurbulenceStats>,
}

/// What the turbulence stage did in one step: the particle budget balances,
/// `particles = previous + seeded + born - split - merged - dissipated - removed`.
#[derive(Debug, Clone, Copy, Default)]
pub struct TurbulenceStats {
    pub seeded: usize,
    /// Particles that split (each into `children`).
    pub split: usize,
    /// Children born of the splits.
    pub born: usize,
    /// Pairs merged into one.
    pub merged: usize,
    /// Particles dissipated below the dissipation radius (section 4.2).
    pub dissipated: usize,
    /// (SPH) particles removed by the liquid bounds: centred outside the liquid (section 6).
    pub removed: usize,
    /// Particles after the step's dynamics.
    pub particles: usize,
    /// Total kernel energy of the particles, m^5/s^2.
    pub energy: Real,
    /// Sum of |omega_ABL| over the cells or particles after seeding, 1/s.
    pub abl_sum: Real,
    /// Wall time of each part, in the order of [`Turbulence::parts`].
    pub seconds: [f64; 5],
}

/// A column of the stage in `metrics.csv` and its value in a step.
type Column = (&'static str, fn(&TurbulenceStats) -> Real);

/// Columns of the turbulence stage in `metrics.csv`, then one `*_seconds` per part.
const COLUMNS: [Column; 9] = [
    ("vortex_particles", |s| s.particles as Real),
    ("seeded", |s| s.seeded as Real),
    ("split", |s| s.split as Real),
    ("born", |s| s.born as Real),
    ("merged", |s| s.merged as Real),
    ("dissipated", |s| s.dissipated as Real),
    ("removed", |s| s.removed as Real),
    ("vortex_energy", |s| s.energy),
    ("abl_magnitude_sum", |s| s.abl_sum),
];

impl Turbulence {
    /// The state of a turbulence stage with these parts, before its first step.
    fn new(abl: Option<[Array3<Real>; 3]>, parts: &'static [&'static str; 5]) -> Self {
        Self {
            abl,
            vortices: VortexParticles::new(),
            parts,
            last: None,
        }
    }

    /// The metrics columns its stage adds to the metrics of `to`'s solver.
    fn added_columns(&self, to: Kind) -> AddedColumns {
        let mut names: Vec<String> = COLUMNS.map(|(name, _)| name.to_owned()).to_vec();
        names.extend(
            self.parts
                .map(|p| format!("{}_seconds", p.replace(' ', "_"))),
        );
        AddedColumns {
            to,
            names,
            note: "vortex particles and their budget (seeded, split, born, merged, dissipated, \
                   removed), vortex energy, ABL magnitude sum, turbulence part times",
        }
    }

    /// Keeps what the stage did this step, and adds its values to the metrics of `to`.
    fn record(&mut self, stats: TurbulenceStats, to: Kind, rec: &mut StepRecord) {
        rec.added.push((to, stats.row()));
        self.last = Some(stats);
    }
}

impl TurbulenceStats {
    /// Its values in the order of the stage's columns.
    fn row(&self) -> Vec<Real> {
        let mut row: Vec<Real> = COLUMNS.map(|(_, value)| value(self)).to_vec();
        row.extend(self.seconds);
        row
    }

    /// Records what the vortex dynamics did.
    fn dynamics(&mut self, report: StepReport) {
        self.split = report.split;
        self.born = report.born;
        self.merged = report.merged;
        self.dissipated = report.dissipated;
    }
}

/// One obstacle with a database.
struct Obstacle {
    /// Its index among the solver's bodies.
    body: usize,
    layer: WallLayer,
    /// Half the bounding-box diagonal, at least two cells or spacings, m.
    reach: Real,
}

impl Obstacle {
    /// omega_pre at its boundary points in the world frame at time `t`, for the obstacle moving
    /// relative to the `ambient` flow (see the module documentation), times `scale`.
    fn values(&self, body: &RigidBody, t: Real, ambient: Option<Vec3>, scale: Real) -> Vec<Vec3> {
        let linear = body.linear_velocity(t) - ambient.unwrap_or_else(Vec3::zeros);
        self.layer
            .values(&body.pose(t), &linear, &body.angular_velocity(t), scale)
    }
}

/// What both stages build the same way: the databases, the vortex dynamics and the seeding
/// generator.
struct Common {
    settings: AblSettings,
    obstacles: Vec<Obstacle>,
    dynamics: Dynamics,
    rng: ChaCha8Rng,
    /// The cell size or particle spacing the radii of [`crate::abl::TurbulenceParams`] count
    /// in, m.
    dx: Real,
    /// Thickness of the wall-attached layer, m (see [`crate::abl::TurbulenceParams::gain`]).
    thickness: Real,
    /// The dissipation radius, cells or spacings.
    dissipation: Real,
}

/// How the solver a stage drives resolves the flow.
struct Resolution {
    /// Cell size or particle spacing, m.
    dx: Real,
    /// Thickness of the wall-attached layer, m.
    thickness: Real,
    /// Whether the samples are SPH particles (for the default dissipation radius).
    on_particles: bool,
}

/// The boundary-layer field on the grid's cells (on particles it rides on the fluid, saved
/// with it) and the vortex particles.
impl Persist for Turbulence {
    fn save(&self, into: &mut Saver) {
        if let Some(abl) = &self.abl {
            let mut s = into.section("abl");
            for (a, f) in abl.iter().enumerate() {
                s.reals(AXES[a], f.as_slice().expect("fields are contiguous"));
            }
        }
        self.vortices.save(&mut into.section("vortices"));
    }

    fn restore(&mut self, from: &Restorer) -> Result<(), StateError> {
        if let Some(abl) = self.abl.as_mut() {
            let s = from.section("abl");
            for (a, f) in abl.iter_mut().enumerate() {
                s.reals_into(AXES[a], f.as_slice_mut().expect("fields are contiguous"))?;
            }
        }
        self.vortices.restore(&from.section("vortices"))
    }
}

const AXES: [&str; 3] = ["x", "y", "z"];

impl Common {
    /// Opens every database of `settings` (checking it belongs to its obstacle in `shapes`) for
    /// a solver of resolution `res` among `bodies`.
    fn build(
        settings: AblSettings,
        shapes: &[Shape],
        bodies: &[RigidBody],
        res: Resolution,
    ) -> Result<Self, RunError> {
        let dx = res.dx;
        let mut obstacles = Vec::new();
        for (body, path) in &settings.databases {
            let db = AblDatabase::open(path, Some(&shapes[*body]))?;
            let spacing = db.header().spacing;
            let (lo, hi) = bodies[*body].local_aabb();
            obstacles.push(Obstacle {
                body: *body,
                layer: WallLayer::new(db, 2.0 * (dx + spacing)),
                reach: (0.5 * (hi - lo).norm()).max(2.0 * dx),
            });
        }
        let p = &settings.params;
        let dissipation = p.dissipation(res.on_particles);
        let dynamics = Dynamics::new(
            DynamicsSettings {
                dissipation_cells: dissipation,
                inertial_radius: p.split_radius * dx,
                children: p.children,
                cascade_time: p.cascade_time,
                ..Default::default()
            },
            settings.seed,
        )?;
        Ok(Self {
            rng: ChaCha8Rng::seed_from_u64(settings.seed ^ SEEDING_STREAM),
            settings,
            obstacles,
            dynamics,
            dx,
            thickness: res.thickness,
            dissipation,
        })
    }

    /// The seeding's and the dynamics' generators: what a stage carries between steps.
    fn save(&self, into: &mut Saver) {
        into.rng("seeding_rng", &self.rng);
        self.dynamics.save(&mut into.section("dynamics"));
    }

    fn restore(&mut self, from: &Restorer) -> Result<(), StateError> {
        self.rng = from.rng("seeding_rng")?;
        self.dynamics.restore(&from.section("dynamics"))
    }

    /// The factor on omega_pre that gives the wall-attached layer's vorticity, 1/m: the gain
    /// over the layer's thickness.
    fn scale(&self) -> Real {
        self.settings.params.gain / self.thickness
    }

    /// Eq. 8's parameters in metres.
    fn seeding_params(&self) -> SeedingParams {
        let p = &self.settings.params;
        SeedingParams {
            c_p: p.c_p,
            u0: self.settings.u0,
            r_max: p.r_max * self.dx,
            r_min: self.dissipation * self.dx,
        }
    }

    /// The plan's headline and its lines for the wall layer, seeding and vortex dynamics;
    /// `unit` names what the radii count ("cells", "spacings").
    fn describe(&self, unit: &str) -> (String, [String; 3]) {
        let p = &self.settings.params;
        let names: Vec<String> = self
            .obstacles
            .iter()
            .map(|o| {
                let db = o.layer.database();
                format!(
                    "{} ({}, {} points)",
                    db.header().obstacle,
                    db.path().display(),
                    db.len()
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
            [
                format!(
                    "lookup per obstacle, gain {} over a layer {:.3e} m thick",
                    p.gain, self.thickness
                ),
                format!(
                    "{seeding}: c_p = {} 1/s, |U_0| = {} m/s, r_max = {} {unit}",
                    p.c_p, self.settings.u0, p.r_max
                ),
                format!(
                    "advect, stretch, merge, split at radius <= {} {unit} into {}, dissipate \
                     below {} {unit}",
                    p.split_radius, p.children, self.dissipation
                ),
            ],
        )
    }
}

/// Adds the seeds to the vortex particles.
fn push_seeds(seeds: &[Seed], vortices: &mut VortexParticles) {
    for s in seeds {
        vortices
            .push(s.x, s.omega, s.sigma)
            .expect("seeds are finite with a positive scale");
    }
}

/// Parts both stages run, by these names in the plan, the metrics' `*_seconds` columns and
/// [`Laps::lap`].
const WALL_LAYER: &str = "wall layer";
const SEEDING: &str = "seeding";
const DYNAMICS: &str = "vortex dynamics";
const SYNTHESIS: &str = "synthesis";

/// Wall time of each part of a step, in the order of the stage's parts.
struct Laps {
    parts: &'static [&'static str; 5],
    clock: Instant,
    seconds: [f64; 5],
}

impl Laps {
    fn start(parts: &'static [&'static str; 5]) -> Self {
        Self {
            parts,
            clock: Instant::now(),
            seconds: [0.0; 5],
        }
    }

    /// Ends `part`, one of the stage's parts.
    fn lap(&mut self, part: &str) {
        let i = self
            .parts
            .iter()
            .position(|p| *p == part)
            .expect("a lap ends one of the stage's parts");
        self.seconds[i] = self.clock.elapsed().as_secs_f64();
        self.clock = Instant::now();
    }
}
