//! What a scene can ask the diagnostics for, as its `[[probes]]` and `output.metrics` write it:
//! probes sampled every step into `probes.csv`, and the per-step metrics of `metrics.csv`.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::Real;

/// A coordinate axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Axis {
    X,
    Y,
    Z,
}

impl Axis {
    /// Index of the axis in a vector.
    pub fn index(self) -> usize {
        match self {
            Axis::X => 0,
            Axis::Y => 1,
            Axis::Z => 2,
        }
    }
}

/// A probe, sampled every step into `probes.csv`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum Probe {
    /// The fluid front: the largest coordinate along `axis` of any fluid particle, less `origin`.
    Front {
        /// Names the probe's columns in `probes.csv` (a line probe's: its profile file).
        name: String,
        /// The axis the front advances along.
        axis: Axis,
        /// Subtracted from the front's coordinate, m.
        #[serde(default)]
        origin: Real,
    },
    /// Pressure and velocity at a point: kernel-interpolated (Shepard-normalised) on SPH,
    /// trilinear on the grid.
    Point {
        /// Names the probe's columns.
        name: String,
        /// Where it samples, m.
        position: [Real; 3],
    },
    /// Grid only: the velocity at `points` evenly spaced samples from `from` to `to`, written
    /// as `profile_NAME.csv` at the end of the run.
    Line {
        /// Names the profile file.
        name: String,
        /// First sample, m.
        from: [Real; 3],
        /// Last sample, m.
        to: [Real; 3],
        /// Number of samples.
        #[serde(default = "default_line_points")]
        points: usize,
    },
    /// Grid only: the force of the fluid on an obstacle (named by its `name`), pressure and
    /// viscous parts, N.
    Force {
        /// Names the probe's columns.
        name: String,
        /// The `name` of the obstacle whose force is measured.
        body: String,
    },
}

fn default_line_points() -> usize {
    65
}

impl Probe {
    /// The probe's name.
    pub fn name(&self) -> &str {
        match self {
            Probe::Front { name, .. }
            | Probe::Point { name, .. }
            | Probe::Line { name, .. }
            | Probe::Force { name, .. } => name,
        }
    }
}

/// Per-step metrics a scene can ask for; each is a column of `metrics.csv`. An SPH fluid
/// offers [`Metric::SPH`], a MAC grid [`Metric::GRID`]; the names they share mean the same.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Metric {
    /// Kinetic energy, J (on a grid: of the flow after the step, rho sum |u|^2 dV / 2).
    KineticEnergy,
    PotentialEnergy,
    DensityErrorAvg,
    DensityErrorMax,
    MaxSpeed,
    /// Iterations of the pressure solve.
    PressureIterations,
    DivergenceIterations,
    /// Rotational energy of a micropolar refinement, J (zero for other methods).
    RotationalEnergy,
    /// Kinetic (linear plus rotational) plus potential energy, J.
    TotalEnergy,
    /// Mean |curl v| over the fluid particles (or fluid cells), 1/s.
    VorticityMean,
    /// Largest |curl v|, 1/s.
    VorticityMax,
    /// Enstrophy sum V |curl v|^2 / 2 over the particles (or fluid cells), m^3/s^2.
    Enstrophy,
    /// Wall-clock time of the refinement in the step, s.
    RefinementSeconds,
    /// Fluid particles at the start of the step (open boundaries change it).
    Particles,
    /// Wall-clock time of the open boundaries in the step (buffers, removal, spawning), s.
    OpenBoundarySeconds,
    /// Wall-clock time of the whole step, s.
    StepSeconds,
    /// Grid: largest |div u| after the projection, 1/s.
    MaxDivergence,
    /// Grid: relative residual the pressure solve ended at.
    PressureResidual,
    /// Grid: iterations of the implicit viscosity solve.
    ViscosityIterations,
    /// Grid: the step's CFL number, max |u| dt / dx.
    Cfl,
    /// Grid: |u^(n+1) - u^n| / (|u^n| dt), 1/s: how far from steady.
    ChangeRate,
    /// Grid: wall-clock time of the advection, s.
    AdvectSeconds,
    /// Grid: wall-clock time of the projection, s.
    ProjectSeconds,
    /// Fluid particles that have left the domain through sides no wall closes, removed and
    /// counted so far (cumulative, the step's own included; see `fluid.lost_fraction`).
    LostParticles,
}

impl Metric {
    /// What an SPH fluid offers, in column order.
    pub const SPH: [Metric; 17] = [
        Metric::KineticEnergy,
        Metric::PotentialEnergy,
        Metric::DensityErrorAvg,
        Metric::DensityErrorMax,
        Metric::MaxSpeed,
        Metric::PressureIterations,
        Metric::DivergenceIterations,
        Metric::RotationalEnergy,
        Metric::TotalEnergy,
        Metric::VorticityMean,
        Metric::VorticityMax,
        Metric::Enstrophy,
        Metric::RefinementSeconds,
        Metric::Particles,
        Metric::OpenBoundarySeconds,
        Metric::StepSeconds,
        Metric::LostParticles,
    ];

    /// What a MAC grid offers, in column order.
    pub const GRID: [Metric; 13] = [
        Metric::KineticEnergy,
        Metric::MaxDivergence,
        Metric::PressureIterations,
        Metric::PressureResidual,
        Metric::ViscosityIterations,
        Metric::Cfl,
        Metric::ChangeRate,
        Metric::AdvectSeconds,
        Metric::ProjectSeconds,
        Metric::StepSeconds,
        Metric::VorticityMean,
        Metric::VorticityMax,
        Metric::Enstrophy,
    ];

    /// Column name in `metrics.csv`.
    pub fn column(self) -> &'static str {
        match self {
            Metric::KineticEnergy => "kinetic_energy",
            Metric::PotentialEnergy => "potential_energy",
            Metric::DensityErrorAvg => "density_error_avg",
            Metric::DensityErrorMax => "density_error_max",
            Metric::MaxSpeed => "max_speed",
            Metric::PressureIterations => "pressure_iterations",
            Metric::DivergenceIterations => "divergence_iterations",
            Metric::RotationalEnergy => "rotational_energy",
            Metric::TotalEnergy => "total_energy",
            Metric::VorticityMean => "vorticity_mean",
            Metric::VorticityMax => "vorticity_max",
            Metric::Enstrophy => "enstrophy",
            Metric::RefinementSeconds => "refinement_seconds",
            Metric::Particles => "particles",
            Metric::OpenBoundarySeconds => "open_boundary_seconds",
            Metric::StepSeconds => "step_seconds",
            Metric::MaxDivergence => "max_divergence",
            Metric::PressureResidual => "pressure_residual",
            Metric::ViscosityIterations => "viscosity_iterations",
            Metric::Cfl => "cfl",
            Metric::ChangeRate => "change_rate",
            Metric::AdvectSeconds => "advect_seconds",
            Metric::ProjectSeconds => "project_seconds",
            Metric::LostParticles => "lost_particles",
        }
    }

    /// Of `asked` (every one when `None`), those `offered` has, in `asked`'s order (`offered`'s
    /// when every one).
    pub fn chosen(asked: Option<&[Metric]>, offered: &[Metric]) -> Vec<Metric> {
        match asked {
            None => offered.to_vec(),
            Some(asked) => asked
                .iter()
                .filter(|m| offered.contains(m))
                .copied()
                .collect(),
        }
    }
}
