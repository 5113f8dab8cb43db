//! The exchange across the water surface of a coupled scene (`[coupling]`): air on the MAC
//! grid, water in SPH, one step for both. Every exchange moves momentum from one medium to the
//! other and never creates it, so what the water gains the air loses.
//!
//! Both directions go through the grid's cells. The particles' occupancy
//! c(x) = sum_j V_j W(x - x_j) / (1 - sum_b V_b W(x - x_b)) (the walls' share of the kernel
//! divided out) and their Shepard-normalised velocity are sampled at every cell centre near the
//! water; c is 1 inside the liquid, beside walls too, and 0 outside it. The order in a step,
//! all at the state the step starts from:
//!
//! 1. **liquid** (water on air): cells with c at or above the threshold are a moving solid for
//!    the air; the faces beside them carry the water's velocity at those cells' centres (the
//!    mean of the two where both sides are liquid).
//! 2. **drag** (air on water): |grad c| is a smeared surface delta (Brackbill et al. 1992):
//!    summed over the cells, |grad c| dx^3 is the surface's area, exactly for a flat surface
//!    however the particles below it are arranged. Each cell with |grad c| > 0 feels
//!    tau |grad c| dx^3 with tau = rho_air C_d |u_air - v| (u_air - v), v the water's velocity
//!    at the cell, u_air read by trilinear interpolation 1.5 cells outside the surface along
//!    n = -grad c / |grad c|, over the faces that are air. The water's share goes to the
//!    particles near the cell by their kernel weights at its centre; the opposite impulse goes
//!    onto exactly the air faces it was read from, with the same weights, added in the grid's
//!    step after its advection and before its projection, as a force.
//! 3. the grid's step, whose projection sees the liquid as a moving solid;
//! 4. **surface pressure**: the projection's pressure force on each liquid cell
//!    ([`crate::grid::GridSolver::liquid_pressure_forces`], the momentum it took from the air
//!    through the cell's faces) goes to the particles near that cell by their kernel weights;
//! 5. the SPH step and its neighbourhood update.
//!
//! Not exchanged: the air's viscous stress on the liquid faces (the grid's viscosity holds
//! them at the water's velocity; the drag law stands for the surface stress), and the air
//! momentum of faces that the moving surface covers or uncovers between steps (a
//! discretisation term of the kinematic boundary, like advection's).

use ndarray::{s, Array3, Zip};
use rayon::prelude::*;

use super::outputs::Kind;
use super::simulation::{Simulation, StepError};
use super::stages::{AddedColumns, Stage, StepRecord};
use crate::grid::mac::cell_beside;
use crate::grid::{GridSolver, Liquid, MacGrid};
use crate::scene::Coupling;
use crate::spatial::bounding_box;
use crate::sph::vortex_coupling::SphVelocity;
use crate::sph::SphSolver;
use crate::{Real, Vec3};

/// Air velocity for the drag is read this many grid cells outside the surface.
pub const DRAG_HEIGHT: Real = 1.5;

/// What the water received across its surface in one step.
#[derive(Debug, Clone, Copy, Default)]
pub struct Exchange {
    /// Impulse of the air's drag, N s.
    pub drag: Vec3,
    /// Impulse of the air's pressure, N s.
    pub pressure: Vec3,
    /// Cells under the liquid.
    pub liquid_cells: usize,
    /// The surface area the drag acted on, sum |grad c| dx^3, m^2.
    pub area: Real,
}

/// Stages 1 and 2: the liquid as the air's moving solid, and the drag both ways.
pub struct SurfaceExchange {
    pub coupling: Coupling,
}

/// Stage 4: the air's pressure on the liquid cells, to the particles under them.
pub struct SurfacePressure;

const PARTS: [&str; 2] = ["liquid", "drag"];

impl Stage for SurfaceExchange {
    fn name(&self) -> &'static str {
        "coupling"
    }

    fn describe(&self, _sim: &Simulation) -> (String, Vec<(&'static str, String)>) {
        let c = &self.coupling;
        (
            format!(
                "air (grid, rho {} kg/m^3) and water (SPH) across the surface, through the \
                 particles' occupancy c at the cell centres",
                c.air_density
            ),
            vec![
                (
                    PARTS[0],
                    format!(
                        "cells with c >= {} are a moving solid for the air, faces at the \
                         water's velocity",
                        c.occupancy_threshold
                    ),
                ),
                (
                    PARTS[1],
                    format!(
                        "surface drag rho_air C_d |du| du |grad c| dx^3 per cell, C_d = {}, \
                         air read {DRAG_HEIGHT} cells out; the opposite impulse onto those air \
                         faces",
                        c.drag_coefficient
                    ),
                ),
            ],
        )
    }

    fn run(&mut self, sim: &mut Simulation, rec: &mut StepRecord) -> Result<(), StepError> {
        let (Some(sph), Some(grid)) = (sim.sph.as_mut(), sim.grid.as_mut()) else {
            return Ok(());
        };
        let c = &self.coupling;
        let field = Occupancy::sample(sph, &grid.mac);
        let liquid = Liquid::new(
            &grid.mac,
            &field
                .cells
                .map(|&(c_, v)| (c_ >= c.occupancy_threshold).then_some(v)),
        );
        let liquid_cells = liquid.cells.iter().filter(|&&c| c).count();
        grid.set_liquid(liquid, rec.dt);
        let (drag, area) = exchange_drag(sph, grid, &field, c, rec.dt);
        sim.exchange = Some(Exchange {
            drag,
            pressure: Vec3::zeros(),
            liquid_cells,
            area,
        });
        Ok(())
    }

    fn ran<'a>(&self, _sim: &'a Simulation) -> &'a [&'static str] {
        &PARTS
    }
}

impl Stage for SurfacePressure {
    fn name(&self) -> &'static str {
        "surface pressure"
    }

    fn describe(&self, _sim: &Simulation) -> (String, Vec<(&'static str, String)>) {
        (
            "the projection's pressure force on each liquid cell, to the particles near it by \
             kernel weight"
                .into(),
            Vec::new(),
        )
    }

    fn run(&mut self, sim: &mut Simulation, rec: &mut StepRecord) -> Result<(), StepError> {
        let (Some(sph), Some(grid)) = (sim.sph.as_mut(), sim.grid.as_ref()) else {
            return Ok(());
        };
        let impulses: Vec<(Vec3, Vec3)> = grid
            .liquid_pressure_forces()
            .into_iter()
            .map(|(cell, force)| (grid.mac.cell_center(cell), force * rec.dt))
            .collect();
        let (total, _) = give_to_particles(sph, &impulses);
        let e = sim.exchange.get_or_insert_with(Exchange::default);
        e.pressure = total;
        let (drag, pressure) = (e.drag / rec.dt, e.pressure / rec.dt);
        let mut row: Vec<Real> = drag.iter().chain(pressure.iter()).copied().collect();
        row.extend([e.liquid_cells as Real, e.area]);
        rec.added.push((Kind::Grid, row));
        Ok(())
    }

    /// The exchange of both stages, as the forces the water felt.
    fn added_columns(&self, _sim: &Simulation) -> Option<AddedColumns> {
        Some(AddedColumns {
            to: Kind::Grid,
            names: COLUMNS.map(String::from).to_vec(),
            note: "the air's drag and pressure force on the water, liquid cells, surface area",
        })
    }
}

/// The columns of the exchange in the grid's metrics: the forces on the water (the air's are
/// opposite), N, the cells under the liquid and the area the drag acted on, m^2.
const COLUMNS: [&str; 8] = [
    "drag_force_x",
    "drag_force_y",
    "drag_force_z",
    "pressure_force_x",
    "pressure_force_y",
    "pressure_force_z",
    "liquid_cells",
    "surface_area",
];

/// Adds each impulse (at a point, N s) to the particles near its point, shared by their kernel
/// weights there; returns the impulse given and whether each was (one with no particle near
/// is not).
fn give_to_particles(sph: &mut SphSolver, impulses: &[(Vec3, Vec3)]) -> (Vec3, Vec<bool>) {
    let view = sph.velocity_source();
    let shares: Vec<Vec<(usize, Vec3)>> = impulses
        .par_iter()
        .map(|(x, impulse)| {
            let mut weights: Vec<(usize, Real)> = Vec::new();
            view.for_each_weight(x, |j, w| weights.push((j, w)));
            let sum: Real = weights.iter().map(|w| w.1).sum();
            weights
                .into_iter()
                .map(|(j, w)| (j, impulse * (w / sum)))
                .collect()
        })
        .collect();
    let mut dv = vec![Vec3::zeros(); sph.fluid.len()];
    let mut total = Vec3::zeros();
    for ((_, impulse), share) in impulses.iter().zip(&shares) {
        if share.is_empty() {
            continue;
        }
        total += impulse;
        for (j, p) in share {
            dv[*j] += p;
        }
    }
    let mass = sph.fluid.mass;
    for (v, dv) in sph.fluid.v.iter_mut().zip(&dv) {
        *v += dv / mass;
    }
    (total, shares.iter().map(|s| !s.is_empty()).collect())
}

/// The particles' occupancy and Shepard velocity at the cell centres within the kernel's
/// reach of the particles' bounding box (0 elsewhere); 1 and the particles' mean velocity in
/// the cells inside the liquid.
struct Occupancy {
    cells: Array3<(Real, Vec3)>,
    /// The cells sampled.
    range: [std::ops::Range<usize>; 3],
}

impl Occupancy {
    fn sample(sph: &SphSolver, mac: &MacGrid) -> Self {
        let view: SphVelocity<'_> = sph.velocity_source();
        let mut cells = Array3::from_elem(mac.dims, (0.0, Vec3::zeros()));
        let mut sampled = [0..0, 0..0, 0..0];
        let reach = sph.kernel.support();
        let (lo, hi) = bounding_box(&sph.fluid.x);
        if lo.x <= hi.x {
            let range = |a: usize| {
                let cell = |x: Real| ((x - mac.origin[a]) / mac.dx).clamp(0.0, mac.dims[a] as Real);
                let (from, to) = (cell(lo[a] - reach), cell(hi[a] + reach));
                (from.floor() as usize)..(to.ceil() as usize).min(mac.dims[a])
            };
            sampled = [range(0), range(1), range(2)];
            let [rx, ry, rz] = sampled.clone();
            let origin = [rx.start, ry.start, rz.start];
            let shape = [rx.len(), ry.len(), rz.len()];
            // The particles binned into the sampled cells, with their summed velocities. A cell
            // whose 26 neighbours all hold particles lies inside the liquid, where the
            // occupancy is 1 up to sampling noise: it is set to 1 with the particles' mean
            // velocity, and only the cells near the surface or a wall are sampled.
            let mut bins = Array3::from_elem(shape, (0u32, Vec3::zeros()));
            for (x, v) in sph.fluid.x.iter().zip(&sph.fluid.v) {
                let g = mac.grid_coords(x);
                let idx: [usize; 3] = std::array::from_fn(|a| {
                    (g[a].floor().max(0.0) as usize).saturating_sub(origin[a])
                });
                if let Some(bin) = bins.get_mut(idx) {
                    bin.0 += 1;
                    bin.1 += v;
                }
            }
            let interior = |[i, j, k]: [usize; 3]| {
                let inner = (0..3).all(|a| [i, j, k][a] >= 1 && [i, j, k][a] + 1 < shape[a]);
                inner
                    && bins
                        .slice(s![i - 1..=i + 1, j - 1..=j + 1, k - 1..=k + 1])
                        .iter()
                        .all(|b| b.0 > 0)
            };
            Zip::indexed(cells.slice_mut(s![rx, ry, rz])).par_for_each(|(i, j, k), c| {
                *c = if interior([i, j, k]) {
                    let (n, v) = bins[[i, j, k]];
                    (1.0, v / n as Real)
                } else {
                    let idx = [origin[0] + i, origin[1] + j, origin[2] + k];
                    view.occupancy(&mac.cell_center(idx))
                };
            });
        }
        Self {
            cells,
            range: sampled,
        }
    }

    /// The sampled cells' indices, in standard order.
    fn indices(&self) -> Vec<[usize; 3]> {
        let [rx, ry, rz] = self.range.clone();
        let mut out = Vec::with_capacity(rx.len() * ry.len() * rz.len());
        for i in rx {
            for j in ry.clone() {
                out.extend(rz.clone().map(|k| [i, j, k]));
            }
        }
        out
    }

    /// Central differences of c at `idx`; a side beyond a wall or in an obstacle repeats the
    /// cell's own value, so walls make no surface.
    fn gradient(&self, grid: &GridSolver, idx: [usize; 3]) -> Vec3 {
        let mac = &grid.mac;
        let here = self.cells[idx].0;
        let at = |a: usize, up: bool| -> Real {
            let Some(j) = cell_beside(idx[a], up, mac.dims[a], mac.periodic[a]) else {
                return here;
            };
            let mut m = idx;
            m[a] = j;
            if grid.bounds.owner(m).is_some() {
                here
            } else {
                self.cells[m].0
            }
        };
        Vec3::from_fn(|a, _| (at(a, true) - at(a, false)) / (2.0 * mac.dx))
    }
}

/// Stage 2: the drag on every surface cell and its opposite on the air faces it read; returns
/// the impulse the water received, N s, and the area it acted on, m^2.
fn exchange_drag(
    sph: &mut SphSolver,
    grid: &mut GridSolver,
    field: &Occupancy,
    coupling: &Coupling,
    dt: Real,
) -> (Vec3, Real) {
    let mac = &grid.mac;
    let (rho, cd) = (coupling.air_density, coupling.drag_coefficient);
    let dx = mac.dx;
    // Per surface cell: its centre, its impulse, its area, and per component the eight faces
    // read with their weights normalised over the air faces (zero on fixed ones).
    type Stencil = [[([usize; 3], Real); 8]; 3];
    let drag: Vec<(Vec3, Vec3, Real, Stencil)> = field
        .indices()
        .par_iter()
        .filter_map(|&idx| {
            let (c, water) = field.cells[idx];
            if c <= 0.0 || grid.bounds.owner(idx).is_some() {
                return None;
            }
            let grad = field.gradient(grid, idx);
            let g = grad.norm();
            if g * dx < 1e-6 {
                return None;
            }
            let normal = -grad / g;
            let centre = mac.cell_center(idx);
            let to_surface = ((c - coupling.occupancy_threshold) / g).clamp(-dx, dx);
            let at = mac.grid_coords(&(centre + normal * (to_surface + DRAG_HEIGHT * dx)));
            let mut air = Vec3::zeros();
            let mut stencil: Stencil = [[([0; 3], 0.0); 8]; 3];
            for (a, faces) in stencil.iter_mut().enumerate() {
                *faces = mac.face_stagger(a).weights(at);
                for (f, w) in faces.iter_mut() {
                    if grid.bounds.fixed[a][*f] {
                        *w = 0.0;
                    }
                }
                let sum: Real = faces.iter().map(|f| f.1).sum();
                if sum <= 0.0 {
                    return None;
                }
                for (f, w) in faces.iter_mut() {
                    *w /= sum;
                    air[a] += *w * mac.u[a][*f];
                }
            }
            let du = air - water;
            let area = g * dx.powi(3);
            Some((
                centre,
                du * (rho * cd * du.norm() * area * dt),
                area,
                stencil,
            ))
        })
        .collect();
    let impulses: Vec<(Vec3, Vec3)> = drag.iter().map(|d| (d.0, d.1)).collect();
    let (given, received) = give_to_particles(sph, &impulses);
    let air_mass = rho * dx.powi(3);
    for ((_, impulse, _, stencil), _) in drag.iter().zip(&received).filter(|d| *d.1) {
        for (a, faces) in stencil.iter().enumerate() {
            for &(f, w) in faces.iter().filter(|f| f.1 > 0.0) {
                grid.add_face_impulse(a, f, -impulse[a] * w / air_mass);
            }
        }
    }
    (given, drag.iter().map(|d| d.2).sum())
}
