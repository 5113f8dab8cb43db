//! Smoke density and temperature: carried by the flow, set by their sources every step, zero
//! inside obstacles, lifting the flow by buoyancy (Fedkiw et al. 2001). They live on the
//! flow's cells, or with a refinement on a finer grid ([`FineGrid`], Pfaff et al. 2009
//! section 5.2), where they are advected by the fine velocity; the sources' velocity and the
//! buoyancy act on the flow's faces either way.

use std::borrow::Cow;

use ndarray::{s, Array3, Zip};

use super::advect::{advect, Advection};
use super::boundary::{cells_near, Boundaries};
use super::fine::FineGrid;
use super::forces::buoyancy;
use super::mac::MacGrid;
use super::params::{Smoke, SmokeSource};
use super::solver::GridError;
use crate::geometry::{Body, RigidBody};
use crate::{Point3, Real, Vec3};

/// Smoke density, temperature and their sources.
#[derive(Debug, Clone)]
pub struct SmokeState {
    /// Density on the smoke's cells (the fine grid's when refined).
    pub density: Array3<Real>,
    /// Temperature on the same cells, when a source sets one.
    pub temperature: Option<Array3<Real>>,
    buoyancy: Real,
    heat_buoyancy: Real,
    sources: Vec<SourceRegion>,
    /// The finer grid the fields live on, when refined.
    pub fine: Option<FineGrid>,
}

/// The cells and faces under a smoke source.
#[derive(Debug, Clone)]
struct SourceRegion {
    /// The smoke's cells inside the source.
    cells: Array3<bool>,
    /// The flow's faces inside the source, and the velocity they are set to.
    faces: Option<([Array3<bool>; 3], Vec3)>,
    density: Real,
    temperature: Real,
    /// The source's shape and motion, when it moves: its cells and faces follow it.
    moving: Option<RigidBody>,
}

impl SmokeState {
    /// The fields at zero with the sources voxelised, on a grid `refinement` times finer than
    /// `flow` (1: the flow's own), the obstacles `bodies` at t = 0 (`container` as
    /// [`super::GridParams::container`]).
    pub(super) fn new(
        flow: &MacGrid,
        smoke: &Smoke,
        refinement: usize,
        bodies: &[RigidBody],
        container: bool,
    ) -> Result<Self, GridError> {
        let fine =
            (refinement > 1).then(|| FineGrid::new(flow, refinement, bodies, 0.0, container));
        let cells_on = fine.as_ref().map_or(flow, |f| &f.mac);
        let sources = smoke
            .sources
            .iter()
            .enumerate()
            .map(|(i, s)| SourceRegion::new(cells_on, flow, s, i))
            .collect::<Result<Vec<_>, _>>()?;
        for (i, src) in sources.iter().enumerate() {
            if src.moving.is_none() && !src.cells.iter().any(|&c| c) {
                tracing::warn!(
                    "grid.smoke.sources[{i}] covers no cell of the {:.3e} m grid and emits \
                     nothing: make it at least a cell across or place it on cell centres",
                    cells_on.dx
                );
            }
        }
        Ok(Self {
            density: Array3::zeros(cells_on.dims),
            temperature: smoke
                .has_temperature()
                .then(|| Array3::zeros(cells_on.dims)),
            buoyancy: smoke.buoyancy,
            heat_buoyancy: smoke.heat_buoyancy,
            sources,
            fine,
        })
    }

    /// Carries the fields over `dt` with `flow` (its velocity extrapolated into obstacles) or
    /// the fine velocity of step `step`.
    pub(super) fn advect(&mut self, flow: &MacGrid, dt: Real, scheme: Advection, step: u64) {
        let vel = match self.fine.as_mut() {
            Some(fine) => fine.velocity_for(flow, step),
            None => flow,
        };
        let stagger = vel.cell_stagger();
        self.density = advect(&self.density, stagger, vel, dt, scheme);
        if let Some(t) = self.temperature.as_mut() {
            *t = advect(t, stagger, vel, dt, scheme);
        }
    }

    /// The sources' density, temperature and face velocities at time `t`, and no smoke in
    /// obstacles or under a coupled liquid.
    pub(super) fn apply_sources(&mut self, flow: &mut MacGrid, bounds: &Boundaries, t: Real) {
        let cells_on = self.fine.as_ref().map_or(&*flow, |f| &f.mac);
        for src in &mut self.sources {
            if let Some(body) = &src.moving {
                src.cells = mark(cells_on, body, t, None);
                if let Some((faces, _)) = src.faces.as_mut() {
                    *faces = std::array::from_fn(|a| mark(flow, body, t, Some(a)));
                }
            }
        }
        for src in &self.sources {
            set_where(&mut self.density, &src.cells, src.density);
            if let Some(t) = self.temperature.as_mut() {
                set_where(t, &src.cells, src.temperature);
            }
            if let Some((faces, v)) = &src.faces {
                for a in 0..3 {
                    set_where(&mut flow.u[a], &faces[a], v[a]);
                }
            }
        }
        match &self.fine {
            Some(fine) => fine.zero_outside(&mut self.density, |c| !bounds.is_liquid(c)),
            None => {
                let fluid = bounds.fluid_mask();
                Zip::from(&mut self.density)
                    .and(&fluid)
                    .par_for_each(|s, &f| {
                        if !f {
                            *s = 0.0;
                        }
                    });
            }
        }
    }

    /// The buoyancy acceleration on the flow's cells, along `up`; `None` without buoyancy.
    pub(super) fn lift(&self, up: Vec3) -> Option<[Array3<Real>; 3]> {
        if self.buoyancy == 0.0 && self.heat_buoyancy == 0.0 {
            return None;
        }
        let density = self.on_flow_cells(&self.density);
        let temperature = self.temperature.as_ref().map(|t| self.on_flow_cells(t));
        Some(buoyancy(
            &density,
            temperature.as_deref(),
            self.buoyancy,
            self.heat_buoyancy,
            up,
        ))
    }

    /// A field of the smoke's cells on the flow's cells: itself, or the cell means of a fine
    /// one (which keep its total).
    pub fn on_flow_cells<'a>(&self, field: &'a Array3<Real>) -> Cow<'a, Array3<Real>> {
        match &self.fine {
            Some(fine) => Cow::Owned(fine.restrict(field)),
            None => Cow::Borrowed(field),
        }
    }

    /// Voxelises the obstacles on the fine grid again, at time `t` (they moved).
    pub(super) fn place_obstacles(&mut self, bodies: &[RigidBody], t: Real, container: bool) {
        if let Some(fine) = self.fine.as_mut() {
            fine.place_obstacles(bodies, t, container);
        }
    }

    /// The plan's words for what the smoke is and where it lives.
    pub(super) fn describe(&self) -> String {
        let what = if self.temperature.is_some() {
            "smoke density, temperature"
        } else {
            "smoke density"
        };
        match &self.fine {
            Some(f) => format!(
                "{what} on a grid {}x finer, by the flow's velocity interpolated plus the fine \
                 kernels",
                f.factor
            ),
            None => what.to_owned(),
        }
    }

    /// Number of sources.
    pub(super) fn source_count(&self) -> usize {
        self.sources.len()
    }

    /// The buoyancy coefficients (per unit density, per unit temperature), m/s^2.
    pub(super) fn buoyancy(&self) -> (Real, Real) {
        (self.buoyancy, self.heat_buoyancy)
    }
}

impl SourceRegion {
    /// Source `index`, its cells voxelised on `cells_on`, its faces (with a velocity) on
    /// `flow`.
    fn new(
        cells_on: &MacGrid,
        flow: &MacGrid,
        source: &SmokeSource,
        index: usize,
    ) -> Result<Self, GridError> {
        let body = RigidBody::from_scene(
            &Body {
                name: Some(format!("smoke source {index}")),
                shape: source.shape.clone(),
                position: source.position,
                rotation: source.rotation,
                motion: source.motion.clone(),
                abl: None,
                wall_viscosity: None,
            },
            index,
        )?;
        let faces = source.velocity.map(|v| {
            let marks = std::array::from_fn(|a| mark(flow, &body, 0.0, Some(a)));
            (marks, Vec3::from(v))
        });
        Ok(Self {
            cells: mark(cells_on, &body, 0.0, None),
            faces,
            density: source.density,
            temperature: source.temperature,
            moving: body.is_moving().then_some(body),
        })
    }
}

/// The cells of `grid` (or with `face` the faces of that component) whose centres lie in `body`
/// at `t`. Only the samples under the body's bounding box (a cell wider on every side, so the
/// faces on its edges are in) are tested: a moving source is placed again every step.
fn mark(grid: &MacGrid, body: &RigidBody, t: Real, face: Option<usize>) -> Array3<bool> {
    let pose = body.pose(t);
    let inside = |x: Vec3| {
        body.signed_distance_local(&pose.inverse_transform_point(&Point3::from(x))) <= 0.0
    };
    let near = cells_near(grid, body, t, grid.dx);
    let shape = match face {
        Some(a) => grid.face_stagger(a).shape,
        None => grid.dims,
    };
    let mut out = Array3::from_elem(shape, false);
    // The ranges reach one further along `face` (a face array has a sample more there).
    let [rx, ry, rz]: [std::ops::Range<usize>; 3] = std::array::from_fn(|a| {
        let end = near[a].end + usize::from(face == Some(a));
        near[a].start..end.min(shape[a])
    });
    let origin = [rx.start, ry.start, rz.start];
    Zip::indexed(out.slice_mut(s![rx, ry, rz])).par_for_each(|(i, j, k), m| {
        let idx = [origin[0] + i, origin[1] + j, origin[2] + k];
        *m = inside(match face {
            Some(a) => grid.face_center(a, idx),
            None => grid.cell_center(idx),
        })
    });
    out
}

/// Sets `field` to `value` where `mask` holds.
fn set_where(field: &mut Array3<Real>, mask: &Array3<bool>, value: Real) {
    Zip::from(field).and(mask).par_for_each(|f, &m| {
        if m {
            *f = value;
        }
    });
}
