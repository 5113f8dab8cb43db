//! Boundary conditions of the MAC grid: the domain's sides and the obstacles voxelised onto its
//! cells. A face is *fixed* when its velocity is prescribed (a wall, an inflow, or a face touching
//! an obstacle cell, which carries the obstacle's velocity there); the projection and the
//! viscosity solve leave fixed faces alone, which is the solid velocity boundary condition.
//!
//! With cut cells ([`ObstacleSurface::Cut`]) only the faces an obstacle covers entirely are
//! fixed; a partly covered face is free, weighs its open fraction in the projection, and its
//! covered part carries the obstacle's velocity in the divergence ([`Boundaries::add_outflow`]).

use ndarray::{s, Array3, Axis, Zip};
use rayon::prelude::*;

use super::cut::CutFaces;
use super::diffusion::{DiffusionBoundary, DiffusionSide};
use super::inflow_turbulence::InflowModes;
use super::liquid::Liquid;
use super::mac::{cells_beside_face, MacGrid};
use super::params::{GridSide, ObstacleSurface};
use super::poisson::{Boundary, CellKind, FaceFractions, Side};
use crate::geometry::RigidBody;
use crate::{Point3, Real, Vec3};
use std::sync::Arc;

/// Owner value of a cell no obstacle covers.
const FLUID: u16 = u16::MAX;

/// Owner value of a cell a coupled liquid covers (see [`Liquid`]).
const LIQUID: u16 = u16::MAX - 1;

/// The grid's boundary state at one time.
#[derive(Debug, Clone)]
pub struct Boundaries {
    /// The domain's sides, `[axis][0 = min, 1 = max]`.
    pub sides: [[GridSide; 2]; 3],
    /// Index of the obstacle whose inside holds each cell centre, `LIQUID` under a coupled
    /// liquid, or `FLUID`.
    owner: Array3<u16>,
    /// Faces whose velocity is prescribed, per component.
    pub fixed: [Array3<bool>; 3],
    /// The prescribed velocity of fixed faces, and the obstacle's velocity on partly covered
    /// faces (0 elsewhere), per component.
    pub fixed_value: [Array3<Real>; 3],
    /// Faces with a static obstacle cell on both sides: their values only ever enter
    /// interpolation, so advection reads velocity extrapolated from the fluid there.
    inside: [Array3<bool>; 3],
    /// With cut cells, the obstacles' faces and the partly covered ones.
    cut: Option<Cut>,
}

/// The cut cells' state: the faces' open fractions and distances, and the partly covered faces.
#[derive(Debug, Clone)]
struct Cut {
    faces: Arc<CutFaces>,
    partial: Vec<PartialFace>,
}

/// A free face an obstacle covers in part (one per face: on a periodic axis the last face,
/// the first one's copy, is left out).
#[derive(Debug, Clone, Copy)]
struct PartialFace {
    axis: usize,
    idx: [usize; 3],
    open: Real,
    /// The obstacle's normal velocity there.
    solid: Real,
}

impl Boundaries {
    /// Voxelises `bodies` at time `t` (with `container`, the first body holds the fluid: the
    /// cells outside it are its) and the cells `liquid` covers, and classifies every face; with
    /// cut cells, from the obstacles' open fractions.
    pub fn new(
        grid: &MacGrid,
        sides: [[GridSide; 2]; 3],
        bodies: &[RigidBody],
        t: Real,
        (container, surface): (bool, ObstacleSurface),
        liquid: Option<&Liquid>,
    ) -> Self {
        let owner = voxelize(grid, bodies, t, container);
        // A container (a coupled scene's tank) stays voxelised: the water's cells lie along it.
        let cut_bodies = &bodies[usize::from(container).min(bodies.len())..];
        let cut = (surface == ObstacleSurface::Cut && !cut_bodies.is_empty())
            .then(|| Arc::new(CutFaces::new(grid, cut_bodies, t)));
        Self::from_owner(grid, sides, owner, bodies, t, liquid, cut)
    }

    /// These boundaries with the coupled liquid replaced by `liquid`, the obstacles where they
    /// are (for static obstacles: no signed distance is evaluated again).
    pub fn with_liquid(
        &self,
        grid: &MacGrid,
        bodies: &[RigidBody],
        t: Real,
        liquid: Option<&Liquid>,
    ) -> Self {
        let owner = self.owner.mapv(|o| if o == LIQUID { FLUID } else { o });
        let cut = self.cut.as_ref().map(|c| c.faces.clone());
        Self::from_owner(grid, self.sides.clone(), owner, bodies, t, liquid, cut)
    }

    fn from_owner(
        grid: &MacGrid,
        sides: [[GridSide; 2]; 3],
        mut owner: Array3<u16>,
        bodies: &[RigidBody],
        t: Real,
        liquid: Option<&Liquid>,
        cut: Option<Arc<CutFaces>>,
    ) -> Self {
        if let Some(liquid) = liquid {
            Zip::from(&mut owner)
                .and(&liquid.cells)
                .par_for_each(|o, &covered| {
                    if covered && *o == FLUID {
                        *o = LIQUID;
                    }
                });
        }
        let mut b = Self {
            sides,
            owner,
            fixed: std::array::from_fn(|a| Array3::from_elem(grid.u[a].raw_dim(), false)),
            fixed_value: std::array::from_fn(|a| Array3::zeros(grid.u[a].raw_dim())),
            inside: std::array::from_fn(|a| Array3::from_elem(grid.u[a].raw_dim(), false)),
            cut: None,
        };
        b.classify_faces(grid, bodies, t, liquid);
        if let Some(faces) = cut {
            let container = bodies.len() - faces.bodies();
            b.open_cut_faces(grid, &bodies[container..], container, t, faces);
        }
        b
    }

    /// Whether cell `idx` is inside an obstacle or under the coupled liquid.
    pub fn is_solid(&self, idx: [usize; 3]) -> bool {
        self.owner[idx] != FLUID
    }

    /// Whether cell `idx` is under the coupled liquid (and in no obstacle).
    pub fn is_liquid(&self, idx: [usize; 3]) -> bool {
        self.owner[idx] == LIQUID
    }

    /// True for the cells the fluid occupies.
    pub fn fluid_mask(&self) -> Array3<bool> {
        self.owner.mapv(|o| o == FLUID)
    }

    /// Number of fluid cells.
    pub fn fluid_cells(&self) -> usize {
        self.owner.iter().filter(|&&o| o == FLUID).count()
    }

    /// The obstacle covering cell `idx`, if any.
    pub fn owner(&self, idx: [usize; 3]) -> Option<usize> {
        let o = self.owner[idx];
        (o != FLUID && o != LIQUID).then_some(o as usize)
    }

    /// The cell kinds of the pressure solve: the fluid cells, and with cut cells the obstacle
    /// cells with a free face too (the fluid holds part of them).
    pub fn cell_kinds(&self) -> Array3<CellKind> {
        let mut kinds = self.owner.mapv(|o| {
            if o == FLUID {
                CellKind::Fluid
            } else {
                CellKind::Solid
            }
        });
        if self.cut.is_some() {
            Zip::indexed(&mut kinds)
                .and(&self.owner)
                .par_for_each(|(i, j, k), kind, &o| {
                    if o != FLUID && o != LIQUID && self.has_free_face([i, j, k]) {
                        *kind = CellKind::Fluid;
                    }
                });
        }
        kinds
    }

    /// Whether the projection solves for the pressure of cell `idx`: a fluid cell, or with cut
    /// cells an obstacle cell with a free face (its pressure is the fluid's, continued).
    pub fn has_pressure(&self, idx: [usize; 3]) -> bool {
        let o = self.owner[idx];
        o == FLUID || (self.cut.is_some() && o != LIQUID && self.has_free_face(idx))
    }

    /// Whether one of the six faces of `cell` is free.
    fn has_free_face(&self, cell: [usize; 3]) -> bool {
        (0..3).any(|a| {
            let mut upper = cell;
            upper[a] += 1;
            !self.fixed[a][cell] || !self.fixed[a][upper]
        })
    }

    /// With cut cells, the open fractions the pressure system weighs its faces by.
    pub fn face_fractions(&self, dims: [usize; 3]) -> Option<FaceFractions> {
        self.cut.as_ref().map(|c| c.faces.upper_fractions(dims))
    }

    /// With cut cells, the obstacles' faces (open fractions and face-centre distances).
    pub fn cut_faces(&self) -> Option<&CutFaces> {
        self.cut.as_ref().map(|c| &*c.faces)
    }

    /// Adds `sign` times the net outflow through the covered parts of the partly covered faces,
    /// sum (1 - open) (u_obstacle - u) . n, to `out`: with it, `grid`'s net outflow is that of
    /// the fluid's faces at their velocity and the obstacle's at its own (Ng, Min & Gibou 2009,
    /// Eq. 11's right-hand side).
    pub fn add_outflow(&self, grid: &MacGrid, sign: Real, out: &mut Array3<Real>) {
        let Some(cut) = &self.cut else {
            return;
        };
        let periodic = self.periodic();
        for p in &cut.partial {
            let a = p.axis;
            let flux = sign * (1.0 - p.open) * (p.solid - grid.u[a][p.idx]);
            let (below, above) = cells_beside_face(p.idx[a], grid.dims[a], periodic[a]);
            let mut cell = p.idx;
            if let Some(c) = below {
                cell[a] = c;
                out[cell] += flux;
            }
            if let Some(c) = above {
                cell[a] = c;
                out[cell] -= flux;
            }
        }
    }

    /// Periodic axes.
    pub fn periodic(&self) -> [bool; 3] {
        std::array::from_fn(|a| self.sides[a][0] == GridSide::Periodic)
    }

    /// The sides as the pressure solve sees them: open sides hold p = 0, every other side is a
    /// prescribed normal velocity (no flux through it beyond what the fixed face carries).
    pub fn pressure_boundary(&self) -> Boundary {
        Boundary {
            periodic: self.periodic(),
            sides: std::array::from_fn(|a| {
                std::array::from_fn(|s| match self.sides[a][s] {
                    GridSide::Open => Side::Open,
                    _ => Side::Wall,
                })
            }),
        }
    }

    /// The sides as the viscosity solve of component `a` sees them, with the wall value of
    /// `a` on each side: no-slip walls and inflows hold their tangential velocity at the wall
    /// (a mirror ghost about that value); slip walls and open sides have no shear. The sides
    /// normal to `a` are fixed faces themselves (or open, zero-gradient).
    pub fn diffusion_boundary(&self, a: usize) -> (DiffusionBoundary, [[Real; 2]; 3]) {
        // A profiled inflow is normal to its side (the scene checks it), so its tangential
        // value is zero everywhere on it.
        let condition = |b: usize, side: &GridSide| match side {
            _ if b == a => (DiffusionSide::Neumann, 0.0),
            GridSide::Wall => (DiffusionSide::Mirror, 0.0),
            GridSide::MovingWall(v) | GridSide::Inflow(v) => (DiffusionSide::Mirror, v[a]),
            GridSide::ProfiledInflow(p) => (DiffusionSide::Mirror, p.velocity[a]),
            GridSide::Slip | GridSide::Open | GridSide::Periodic => (DiffusionSide::Neumann, 0.0),
        };
        let both: [[(DiffusionSide, Real); 2]; 3] =
            std::array::from_fn(|b| std::array::from_fn(|s| condition(b, &self.sides[b][s])));
        (
            DiffusionBoundary {
                periodic: self.periodic(),
                sides: both.map(|pair| pair.map(|c| c.0)),
            },
            both.map(|pair| pair.map(|c| c.1)),
        )
    }

    /// Writes the prescribed velocity onto the fixed faces, extrapolates the normal velocity
    /// through open sides (zero gradient, before the projection corrects it), and makes the
    /// periodic copies agree.
    pub fn apply(&self, grid: &mut MacGrid) {
        for a in 0..3 {
            Zip::from(&mut grid.u[a])
                .and(&self.fixed[a])
                .and(&self.fixed_value[a])
                .par_for_each(|u, &f, &v| {
                    if f {
                        *u = v;
                    }
                });
            let n = grid.dims[a];
            for (s, side) in self.sides[a].iter().enumerate() {
                if *side != GridSide::Open || n < 2 {
                    continue;
                }
                let (face, inner) = if s == 0 { (0, 1) } else { (n, n - 1) };
                let inner_values = grid.u[a].index_axis(Axis(a), inner).to_owned();
                let fixed = self.fixed[a].index_axis(Axis(a), face);
                Zip::from(grid.u[a].index_axis_mut(Axis(a), face))
                    .and(&inner_values)
                    .and(fixed)
                    .for_each(|u, &v, &f| {
                        if !f {
                            *u = v;
                        }
                    });
            }
        }
        grid.sync_periodic();
    }

    /// Sets the normal velocity of every inflow face not covered by an obstacle to the side's
    /// value plus the fluctuation of `modes` at time `t` (see [`InflowModes`]); [`Self::apply`]
    /// then writes it onto the grid.
    pub fn fluctuate_inflow(&mut self, grid: &MacGrid, modes: &InflowModes, t: Real) {
        let (lo, hi) = grid.corners();
        for a in 0..3 {
            for (s, side) in self.sides[a].iter().enumerate() {
                if side.inflow_peak().is_none() {
                    continue;
                }
                let (face, cell) = if s == 0 {
                    (0, 0)
                } else {
                    (grid.dims[a], grid.dims[a] - 1)
                };
                let owner = self.owner.index_axis(Axis(a), cell);
                let plane = self.fixed_value[a].index_axis_mut(Axis(a), face);
                Zip::indexed(plane)
                    .and(owner)
                    .par_for_each(|(j, k), value, &o| {
                        if o != FLUID && o != LIQUID {
                            return;
                        }
                        // The plane drops axis `a`; the other two keep their order.
                        let idx = match a {
                            0 => [face, j, k],
                            1 => [j, face, k],
                            _ => [j, k, face],
                        };
                        let x = grid.face_center(a, idx);
                        if let Some(base) = side.velocity_at(&x, &lo, &hi, a) {
                            *value = modes.normal_velocity(&base, a, &x, t);
                        }
                    });
            }
        }
    }

    /// Replaces the velocity on faces inside static obstacles by the mean of their neighbours
    /// in the same component, layer by layer from the fluid inwards (`layers` deep), so that
    /// interpolation near a wall reads fluid velocity rather than the obstacle's zero: without
    /// it advection drags the flow along every wall, an artificial no-slip. [`Self::apply`]
    /// puts the prescribed values back before the solves.
    pub fn extrapolate_into_obstacles(&self, grid: &mut MacGrid, layers: usize) {
        for a in 0..3 {
            let inside = &self.inside[a];
            if !inside.iter().any(|&i| i) {
                continue;
            }
            let mut known = inside.mapv(|i| !i);
            let shape = known.raw_dim();
            let mut todo: Vec<[usize; 3]> = inside
                .indexed_iter()
                .filter(|(_, &i)| i)
                .map(|((i, j, k), _)| [i, j, k])
                .collect();
            for _ in 0..layers {
                let u = &grid.u[a];
                let mut next: Vec<([usize; 3], Real)> = Vec::new();
                for &[i, j, k] in &todo {
                    let (mut sum, mut count) = (0.0, 0);
                    for b in 0..3 {
                        for up in [false, true] {
                            let mut n = [i, j, k];
                            if up {
                                n[b] += 1;
                                if n[b] >= shape[b] {
                                    continue;
                                }
                            } else if n[b] == 0 {
                                continue;
                            } else {
                                n[b] -= 1;
                            }
                            if known[n] {
                                sum += u[n];
                                count += 1;
                            }
                        }
                    }
                    if count > 0 {
                        next.push(([i, j, k], sum / count as Real));
                    }
                }
                if next.is_empty() {
                    break;
                }
                for &(idx, v) in &next {
                    grid.u[a][idx] = v;
                    known[idx] = true;
                }
                todo.retain(|&idx| !known[idx]);
            }
        }
    }

    /// Frees the faces an obstacle does not cover entirely, and fixes those it covers between
    /// two fluid cells (a thin part of it), from the open fractions of `faces` (of `bodies`, the
    /// obstacles after the `container` ones, 0 or 1); a side's, a liquid's and a container's
    /// faces keep their conditions. Collects the partly covered free faces.
    fn open_cut_faces(
        &mut self,
        grid: &MacGrid,
        bodies: &[RigidBody],
        container: usize,
        t: Real,
        faces: Arc<CutFaces>,
    ) {
        let periodic = self.periodic();
        let owner = &self.owner;
        let is_obstacle = |o: u16| o != FLUID && o != LIQUID;
        for a in 0..3 {
            let n = grid.dims[a];
            Zip::indexed(&mut self.fixed[a])
                .and(&mut self.fixed_value[a])
                .and(&mut self.inside[a])
                .and(&faces.open[a])
                .par_for_each(|(i, j, k), fixed, value, inside, &open| {
                    let idx = [i, j, k];
                    let (Some(l), Some(r)) = cells_beside_face(idx[a], n, periodic[a]) else {
                        return;
                    };
                    let beside = [l, r].map(|c| {
                        let mut cell = idx;
                        cell[a] = c;
                        owner[cell]
                    });
                    if beside.contains(&LIQUID)
                        || beside.iter().any(|&o| usize::from(o) < container)
                    {
                        return;
                    }
                    let obstacle = beside.iter().any(|&o| is_obstacle(o));
                    if open <= 0.0 {
                        if !obstacle {
                            *fixed = true;
                            *value = obstacle_velocity(bodies, t, grid.face_center(a, idx), a);
                        }
                    } else if obstacle || open < 1.0 {
                        *fixed = false;
                        *inside = false;
                        if !obstacle {
                            *value = obstacle_velocity(bodies, t, grid.face_center(a, idx), a);
                        }
                    }
                });
        }
        let mut partial = Vec::new();
        for a in 0..3 {
            let last = grid.dims[a] - usize::from(periodic[a]);
            for ((i, j, k), &open) in faces.open[a].indexed_iter() {
                let idx = [i, j, k];
                if open > 0.0 && open < 1.0 && !self.fixed[a][idx] && idx[a] <= last {
                    partial.push(PartialFace {
                        axis: a,
                        idx,
                        open: Real::from(open),
                        solid: self.fixed_value[a][idx],
                    });
                }
            }
        }
        self.cut = Some(Cut { faces, partial });
    }

    /// Marks the fixed faces of every component and their velocities, a row of faces along z
    /// at a time over flat slices (a moving obstacle reclassifies every face on every step).
    /// An obstacle's velocity comes first, then a side's, then the liquid's.
    fn classify_faces(
        &mut self,
        grid: &MacGrid,
        bodies: &[RigidBody],
        t: Real,
        liquid: Option<&Liquid>,
    ) {
        let [_, n1, n2] = grid.dims;
        let owner = self
            .owner
            .as_slice()
            .expect("the owner array is in standard layout");
        let moving: Vec<bool> = bodies.iter().map(RigidBody::is_moving).collect();
        // Each body's v, w and origin at t, for v + w x (x - origin) at its faces
        // ([`RigidBody::velocity_at`], whose pose would otherwise be rebuilt at every face).
        let motion: Vec<(Vec3, Vec3, Vec3)> = bodies
            .iter()
            .map(|b| {
                let origin = b.pose(t).translation.vector;
                (b.linear_velocity(t), b.angular_velocity(t), origin)
            })
            .collect();
        for a in 0..3 {
            let n = grid.dims[a];
            let periodic = self.sides[a][0] == GridSide::Periodic;
            let sides = &self.sides[a];
            let (side_lo, side_hi) = grid.corners();
            let [m1, m2] = [n1 + usize::from(a == 1), n2 + usize::from(a == 2)];
            fn slabs<T: Send>(x: &mut Array3<T>, len: usize) -> rayon::slice::ChunksMut<'_, T> {
                x.as_slice_mut()
                    .expect("face arrays are in standard layout")
                    .par_chunks_mut(len.max(1))
            }
            let liquid_faces = liquid.map(|l| {
                l.face_velocity[a]
                    .as_slice()
                    .expect("face arrays are in standard layout")
            });
            slabs(&mut self.fixed[a], m1 * m2)
                .zip(slabs(&mut self.fixed_value[a], m1 * m2))
                .zip(slabs(&mut self.inside[a], m1 * m2))
                .enumerate()
                .for_each(|(i, ((fixed, value), inside))| {
                    let owner_row = |i: usize, j: usize| &owner[(i * n1 + j) * n2..][..n2];
                    for j in 0..m1 {
                        // Along x and y the cells beside a row of faces are two rows of cells;
                        // along z they are neighbours in one row.
                        let rows = match a {
                            0 => cells_beside_face(i, n, periodic),
                            1 => cells_beside_face(j, n, periodic),
                            _ => (None, None),
                        };
                        let (lo, hi) = if a == 0 {
                            (
                                rows.0.map(|c| owner_row(c, j)),
                                rows.1.map(|c| owner_row(c, j)),
                            )
                        } else {
                            (
                                rows.0.map(|c| owner_row(i, c)),
                                rows.1.map(|c| owner_row(i, c)),
                            )
                        };
                        for k in 0..m2 {
                            let idx = [i, j, k];
                            // The cells on either side; None beyond a non-periodic side.
                            let (left, right) = if a == 2 {
                                let row = owner_row(i, j);
                                let (l, r) = cells_beside_face(k, n, periodic);
                                (l.map(|c| row[c]), r.map(|c| row[c]))
                            } else {
                                (lo.map(|r| r[k]), hi.map(|r| r[k]))
                            };
                            let beside = [left, right].into_iter().flatten();
                            let solid = beside.clone().find(|&o| o != FLUID && o != LIQUID);
                            let wet = beside.clone().any(|o| o == LIQUID);
                            let f = j * m2 + k;
                            let is_static = |o: u16| o != LIQUID && !moving[o as usize];
                            inside[f] = match (left, right) {
                                (Some(l), Some(r)) => {
                                    l != FLUID && r != FLUID && is_static(l) && is_static(r)
                                }
                                _ => false,
                            };
                            let prescribed = if let Some(body) = solid {
                                let x = grid.face_center(a, idx);
                                let (v, w, origin) = &motion[body as usize];
                                Some((v + w.cross(&(x - origin)))[a])
                            } else if left.is_none() || right.is_none() {
                                match &sides[usize::from(left.is_some())] {
                                    GridSide::Slip => Some(0.0),
                                    side => side
                                        .velocity_at(
                                            &grid.face_center(a, idx),
                                            &side_lo,
                                            &side_hi,
                                            a,
                                        )
                                        .map(|v| v[a]),
                                }
                            } else if wet {
                                liquid_faces.map(|l| l[(i * m1 + j) * m2 + k])
                            } else {
                                None
                            };
                            fixed[f] = prescribed.is_some();
                            value[f] = prescribed.unwrap_or(0.0);
                        }
                    }
                });
        }
    }
}

/// Component `a` of the velocity at `x` of the obstacle nearest inside (smallest signed
/// distance) among `bodies` at time `t`.
fn obstacle_velocity(bodies: &[RigidBody], t: Real, x: Vec3, a: usize) -> Real {
    let x = Point3::from(x);
    bodies
        .iter()
        .min_by(|p, q| {
            p.signed_distance(t, &x)
                .total_cmp(&q.signed_distance(t, &x))
        })
        .map_or(0.0, |b| b.velocity_at(t, &x)[a])
}

/// The cells of `grid` outside every obstacle at `t` (inside the container with `container`).
pub(super) fn voxel_free(
    grid: &MacGrid,
    bodies: &[RigidBody],
    t: Real,
    container: bool,
) -> Array3<bool> {
    voxelize(grid, bodies, t, container).mapv(|o| o == FLUID)
}

/// The obstacle index of every cell whose centre lies inside one (the last body listed wins
/// where bodies overlap), `FLUID` elsewhere. Only the cells under each body's bounding box are
/// tested; with `container` the first body owns the cells outside it instead.
fn voxelize(grid: &MacGrid, bodies: &[RigidBody], t: Real, container: bool) -> Array3<u16> {
    let mut owner = Array3::from_elem(grid.dims, FLUID);
    if let Some(tank) = bodies.first().filter(|_| container) {
        let pose = tank.pose(t);
        Zip::indexed(&mut owner).par_for_each(|(i, j, k), o| {
            let c = Point3::from(grid.cell_center([i, j, k]));
            if tank.signed_distance_local(&pose.inverse_transform_point(&c)) > 0.0 {
                *o = 0;
            }
        });
    }
    for (index, body) in bodies.iter().enumerate().skip(usize::from(container)) {
        let [rx, ry, rz] = cells_near(grid, body, t, 0.0);
        let (x0, y0, z0) = (rx.start, ry.start, rz.start);
        let pose = body.pose(t);
        Zip::indexed(owner.slice_mut(s![rx, ry, rz])).par_for_each(|(i, j, k), o| {
            let c = Point3::from(grid.cell_center([x0 + i, y0 + j, z0 + k]));
            // `signed_distance(t, c)` with the pose built once.
            if body.signed_distance_local(&pose.inverse_transform_point(&c)) < 0.0 {
                *o = index as u16;
            }
        });
    }
    owner
}

/// The ranges of cell indices whose centres may lie within `margin` (m) of `body` at time `t`
/// (its world bounding box, widened by half a cell).
pub fn cells_near(
    grid: &MacGrid,
    body: &RigidBody,
    t: Real,
    margin: Real,
) -> [std::ops::Range<usize>; 3] {
    let (lo, hi) = body.world_aabb(t);
    std::array::from_fn(|a| {
        let g0 = ((lo[a] - margin - grid.origin[a]) / grid.dx - 0.5)
            .floor()
            .max(0.0) as usize;
        let g1 = ((hi[a] + margin - grid.origin[a]) / grid.dx + 0.5)
            .ceil()
            .max(0.0) as usize;
        g0.min(grid.dims[a])..g1.min(grid.dims[a])
    })
}
