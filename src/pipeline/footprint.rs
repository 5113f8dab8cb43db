//! What a run will allocate, estimated from its specification alone before anything is built,
//! so that a run too large for the machine is refused with the numbers instead of swapping or
//! hanging (a `fluid.spacing` of 1e-5 m asks for 10^14 particles).

use std::fmt;

use super::spec::RunSpec;
use crate::metrics::statistics;
use crate::Real;

/// Bytes per fluid particle: state, neighbour lists and the pair cache of ~50 neighbours
/// (`eddy bench` measures 750–820 B with the boundary's share); a refinement's are added
/// (each method declares its own: `crate::refine::registry::Method::keeping`).
const BYTES_PER_PARTICLE: u64 = 1024;
/// Bytes of a refinement's step hook apart from its per-particle arrays: the hook itself, its
/// parameters, generator and vector headers (a few hundred bytes), rounded up.
const REFINEMENT_FIXED: u64 = 4096;
/// Bytes per boundary sample: position, local position, velocity, volume, body, cell grid.
const BYTES_PER_SAMPLE: u64 = 128;
/// Bytes per grid cell: about 50 f64 fields (velocities and their copies, pressure, the
/// multigrid hierarchy, viscosity systems, smoke).
const BYTES_PER_CELL: u64 = 400;

/// Sizes and memory of a scene, upper estimates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Footprint {
    /// Lattice sites of the fluid blocks (sites inside obstacles are dropped later).
    pub particles: f64,
    /// Boundary samples: one layer over each body's bounding box at the particle spacing.
    pub samples: f64,
    pub cells: f64,
    pub bytes: f64,
}

impl Footprint {
    /// The footprint of the run `spec`.
    pub fn of(spec: &RunSpec) -> Self {
        let (mut particles, mut samples) = (0.0, 0.0);
        if let Some(sph) = &spec.sph {
            let h = sph.params.spacing;
            particles = sph
                .params
                .blocks
                .iter()
                .map(|b| {
                    (0..3)
                        .map(|a| ((b.max[a] - b.min[a]) / h).floor().max(0.0))
                        .product::<Real>()
                })
                .sum();
            samples = spec
                .bodies
                .iter()
                .map(|b| {
                    let (lo, hi) = b.local_aabb();
                    let e = hi - lo;
                    2.0 * (e.x * e.y + e.y * e.z + e.z * e.x) / (h * h)
                })
                .sum();
        }
        let cells = spec.grid.as_ref().map_or(0.0, |g| {
            g.params.resolution.iter().map(|&n| n as f64).product()
        });
        // The running statistics: the grid's cells, and a particle fluid's bins.
        let statistics = spec.statistics.as_ref().map_or(0.0, |stats| {
            let (lo, hi) = stats.domain;
            let bins = spec.sph.as_ref().map_or(0.0, |_| {
                (0..3)
                    .map(|a| ((hi[a] - lo[a]) / stats.bin).ceil().max(1.0))
                    .product::<Real>()
            });
            cells * statistics::BYTES_PER_CELL as f64 + bins * statistics::BYTES_PER_BIN as f64
        });
        let refinement = match &spec.sph {
            Some(sph) if !sph.refinement.is_none() => {
                // The hook's own arrays, and the operators' volumes the solver keeps for any
                // hook.
                let per_particle =
                    sph.refinement.bytes_per_particle() + std::mem::size_of::<Real>() as u64;
                particles * per_particle as f64 + REFINEMENT_FIXED as f64
            }
            _ => 0.0,
        };
        let bytes = particles * BYTES_PER_PARTICLE as f64
            + refinement
            + samples * BYTES_PER_SAMPLE as f64
            + cells * BYTES_PER_CELL as f64
            + statistics;
        Self {
            particles,
            samples,
            cells,
            bytes,
        }
    }
}

impl fmt::Display for Footprint {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "about {:.0} MiB", self.bytes / (1024.0 * 1024.0))?;
        let mut parts = Vec::new();
        if self.particles > 0.0 {
            parts.push(format!(
                "{:.3e} fluid particles, {:.3e} boundary samples",
                self.particles, self.samples
            ));
        }
        if self.cells > 0.0 {
            parts.push(format!("{:.3e} grid cells", self.cells));
        }
        if !parts.is_empty() {
            write!(f, " for {}", parts.join(" and "))?;
        }
        Ok(())
    }
}

/// Memory the system can give a new allocation now (Linux `MemAvailable`), bytes; None where
/// it cannot be read.
pub fn available_memory() -> Option<f64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024.0)
}
