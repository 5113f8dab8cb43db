//! Probes of a grid scene: pressure and velocity at a point over time, the force of the fluid
//! on an obstacle over time, and velocity profiles along lines.

use std::path::Path;

use super::spec::Probe;
use crate::io::{CsvSeries, IoError};
use crate::{Point3, Real, Vec3};
use nalgebra::{Matrix4, Vector4};

use crate::grid::boundary::cells_near;
use crate::grid::cut::CutFaces;
use crate::grid::GridSolver;

/// The force of the fluid on one obstacle, N.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Force {
    /// -sum p n dA over the obstacle's faces (n the obstacle's outward normal).
    pub pressure: Vec3,
    /// sum rho nu (u_fluid - u_body)_tangential / (dx / 2) dA: the wall shear, first order.
    pub viscous: Vec3,
}

/// The force of the fluid on obstacle `body` (an index into the solver's bodies): on its cut
/// surface with cut cells ([`cut_force_on`]), else on the faces between its cells and fluid
/// cells (a staircase surface: first order in dx).
pub fn force_on(solver: &GridSolver, body: usize) -> Force {
    if let Some(faces) = solver.bounds.cut_faces() {
        if body + faces.bodies() >= solver.bodies.len() {
            return cut_force_on(solver, faces, body);
        }
    }
    let mac = &solver.mac;
    let bounds = &solver.bounds;
    let vel = mac.cell_velocity();
    let area = mac.dx * mac.dx;
    let mu = solver.density() * solver.viscosity();
    let mut f = Force::default();
    let dims = mac.dims;
    for i in 0..dims[0] {
        for j in 0..dims[1] {
            for k in 0..dims[2] {
                let cell = [i, j, k];
                if bounds.owner(cell) != Some(body) {
                    continue;
                }
                for a in 0..3 {
                    for dir in [-1isize, 1] {
                        let Some(nb) = neighbour(cell, a, dir, dims, mac.periodic) else {
                            continue;
                        };
                        if bounds.is_solid(nb) {
                            continue;
                        }
                        let mut n = Vec3::zeros();
                        n[a] = dir as Real;
                        f.pressure -= solver.pressure[nb] * area * n;
                        let face = mac.cell_center(cell) + 0.5 * mac.dx * n;
                        let u_body =
                            solver.bodies[body].velocity_at(solver.time(), &Point3::from(face));
                        let u = Vec3::new(vel[0][nb], vel[1][nb], vel[2][nb]);
                        let rel = u - u_body;
                        let tangential = rel - rel.dot(&n) * n;
                        f.viscous += mu * tangential / (0.5 * mac.dx) * area;
                    }
                }
            }
        }
    }
    f
}

/// How far off the surface the shear's nearer sample lies, in cells. Farther samples miss more
/// of the profile's curvature: the DFG 2D-1 cylinder's viscous drag at 5, 10 and 20 cells per
/// diameter read 1.48, 1.88, 2.04 with one cell, 1.18, 1.71, 1.95 with 1.5.
const WALL_SAMPLE: Real = 1.0;

/// The force on `body` over its cut surface. By the divergence theorem on the fluid's part of
/// a cell, the surface inside it has the area vector A sum_f open_f n_f (n_f the faces' outward
/// normals, A = dx^2; zero in a cell the surface does not cross), pointing out of the obstacle;
/// the pressure force is -sum p A sum_f open_f n_f, exactly what the cut-cell projection's
/// pressure exerts. The shear comes from the tangential velocity relative to the obstacle at
/// h and 2 h off the surface along its normal (h = [`WALL_SAMPLE`] cells), as the one-sided
/// second-order wall gradient (4 u(h) - u(2 h)) / (2 h) with u(0) = 0 (no-slip), exact for a
/// parabolic profile. A cell counts for the obstacle nearest its centre; `body` is one of the
/// obstacles that cut cells.
pub fn cut_force_on(solver: &GridSolver, faces: &CutFaces, body: usize) -> Force {
    let (mac, t) = (&solver.mac, solver.time());
    let bodies = &solver.bodies;
    let area = mac.dx * mac.dx;
    let mu = solver.density() * solver.viscosity();
    let h = WALL_SAMPLE * mac.dx;
    // The obstacles that cut cells are the last ones (a container before them is voxelised).
    let cutting = bodies.len() - faces.bodies()..bodies.len();
    let nearest = |x: &Point3| {
        let distance = |b: &crate::geometry::RigidBody| b.signed_distance(t, x);
        cutting
            .clone()
            .min_by(|&p, &q| distance(&bodies[p]).total_cmp(&distance(&bodies[q])))
    };
    let mut f = Force::default();
    let [rx, ry, rz] = cells_near(mac, &bodies[body], t, mac.dx);
    for i in rx.clone() {
        for j in ry.clone() {
            for k in rz.clone() {
                let cell = [i, j, k];
                let mut surface = Vec3::zeros();
                for a in 0..3 {
                    let mut upper = cell;
                    upper[a] += 1;
                    surface[a] = Real::from(faces.open[a][upper] - faces.open[a][cell]);
                }
                let centre = Point3::from(mac.cell_center(cell));
                if surface != Vec3::zeros() && nearest(&centre) == Some(body) {
                    f.pressure -= solver.pressure[cell] * area * surface;
                    let normal = surface.normalize();
                    let wall = centre - bodies[body].signed_distance(t, &centre) * normal;
                    let u_body = bodies[body].velocity_at(t, &wall);
                    let relative = |s: Real| mac.velocity_at(&(wall + s * normal).coords) - u_body;
                    let gradient = (4.0 * relative(h) - relative(2.0 * h)) / (2.0 * h);
                    let tangential = gradient - gradient.dot(&normal) * normal;
                    f.viscous += mu * tangential * area * surface.norm();
                }
            }
        }
    }
    f
}

/// The cell beside `cell` along axis `a` in direction `dir`, wrapping on periodic axes.
fn neighbour(
    cell: [usize; 3],
    a: usize,
    dir: isize,
    dims: [usize; 3],
    periodic: [bool; 3],
) -> Option<[usize; 3]> {
    let c = cell[a] as isize + dir;
    let n = dims[a] as isize;
    let mut out = cell;
    if (0..n).contains(&c) {
        out[a] = c as usize;
    } else if periodic[a] {
        out[a] = c.rem_euclid(n) as usize;
    } else {
        return None;
    }
    Some(out)
}

/// Pressure and velocity at a world position, as the fluid there holds them: the pressure from
/// the fluid cells around it ([`fluid_sample`]); the velocity trilinear in the faces, whose
/// values in and on an obstacle are its own velocity, the no-slip condition.
pub fn sample_point(solver: &GridSolver, x: &Vec3) -> (Real, Vec3) {
    (
        fluid_sample(solver, &solver.pressure, x),
        solver.mac.velocity_at(x),
    )
}

/// A cell-centred `field` at `x` from the cells with a pressure only
/// ([`crate::grid::Boundaries::has_pressure`]: the fluid cells, and with cut cells the cut ones
/// too): trilinear in the eight cell centres around `x` where all eight have one; else, as on
/// or beside an obstacle's surface, the value at `x` of the linear function fitted by weighted
/// least squares to those cells among the 4 x 4 x 4 around it (weights exp(-(r / dx)^2)), exact
/// for a linear field such as a hydrostatic pressure. Never a blend with solid cells, whose
/// pressure is no fluid's (the DFG cylinder's front stagnation point read half its value). NaN
/// where none of the 64 has a pressure.
pub fn fluid_sample(solver: &GridSolver, field: &ndarray::Array3<Real>, x: &Vec3) -> Real {
    let (mac, bounds) = (&solver.mac, &solver.bounds);
    let g = mac.grid_coords(x);
    let (mut sum, mut all) = (0.0, true);
    for (cell, w) in mac.cell_stagger().weights(g) {
        all &= bounds.has_pressure(cell);
        sum += w * field[cell];
    }
    if all {
        return sum;
    }
    let base = g.map(|c| (c - 0.5).floor() as isize);
    let (mut normal, mut rhs) = (Matrix4::<Real>::zeros(), Vector4::<Real>::zeros());
    for di in -1..=2isize {
        for dj in -1..=2isize {
            for dk in -1..=2isize {
                let c = [base[0] + di, base[1] + dj, base[2] + dk];
                if (0..3).any(|a| !(0..mac.dims[a] as isize).contains(&c[a])) {
                    continue;
                }
                let cell = c.map(|v| v as usize);
                if !bounds.has_pressure(cell) {
                    continue;
                }
                let d = (mac.cell_center(cell) - x) / mac.dx;
                let row = Vector4::new(1.0, d.x, d.y, d.z);
                let w = (-d.norm_squared()).exp();
                normal += w * row * row.transpose();
                rhs += w * field[cell] * row;
            }
        }
    }
    if normal[(0, 0)] == 0.0 {
        return Real::NAN;
    }
    // A flat layer of cells (a 2-D run) leaves a direction undetermined: the least-norm fit.
    normal
        .svd(true, true)
        .solve(&rhs, 1e-12 * normal[(0, 0)])
        .map_or(Real::NAN, |beta| beta[0])
}

/// The velocity at `x` with the domain's walls as boundary conditions: a tangential component's
/// samples lie half a cell inside a side, where trilinear interpolation stops (a cavity's lid
/// would read 0.95 instead of 1); within that half cell of a no-slip, moving or inflow side the
/// component is interpolated linearly to the side's own velocity at the side. Free-slip, open and
/// periodic sides keep the interpolated value (zero gradient or no side at all).
pub fn velocity_with_walls(solver: &GridSolver, x: &Vec3) -> Vec3 {
    let mac = &solver.mac;
    let half = 0.5 * mac.dx;
    let mut v = mac.velocity_at(x);
    let (lo, hi) = mac.corners();
    for (b, sides) in solver.bounds.sides.iter().enumerate() {
        let extent = mac.dims[b] as Real * mac.dx;
        for (end, side) in sides.iter().enumerate() {
            let plane = mac.origin[b] + if end == 0 { 0.0 } else { extent };
            let mut on = *x;
            on[b] = plane;
            let Some(wall) = side.velocity_at(&on, &lo, &hi, b) else {
                continue;
            };
            let gap = (x[b] - plane).abs();
            if gap >= half {
                continue;
            }
            let mut inner = *x;
            inner[b] = plane + if end == 0 { half } else { -half };
            let at_sample = mac.velocity_at(&inner);
            for a in (0..3).filter(|&a| a != b) {
                v[a] = wall[a] + (at_sample[a] - wall[a]) * gap / half;
            }
        }
    }
    v
}

/// Writes the velocity along a line probe as `path`: s (m along the line), x, y, z, u, v, w.
pub fn write_profile(
    solver: &GridSolver,
    path: &Path,
    from: [Real; 3],
    to: [Real; 3],
    points: usize,
) -> Result<(), IoError> {
    let columns = ["s", "x", "y", "z", "u", "v", "w"].map(String::from);
    let mut csv = CsvSeries::create(path, &columns)?;
    let (a, b) = (Vec3::from(from), Vec3::from(to));
    let length = (b - a).norm();
    for i in 0..points {
        let t = i as Real / (points - 1) as Real;
        let x = a + (b - a) * t;
        let v = velocity_with_walls(solver, &x);
        csv.row(&[t * length, x.x, x.y, x.z, v.x, v.y, v.z])?;
    }
    Ok(())
}

/// The per-step probes of a grid scene (point and force), written to `probes.csv`.
pub struct GridProbeRecorder {
    probes: Vec<(Probe, Option<usize>)>,
    csv: CsvSeries,
    row: Vec<Real>,
}

impl GridProbeRecorder {
    /// The series it writes into.
    pub fn series(&self) -> &CsvSeries {
        &self.csv
    }

    /// The series, to go on from a checkpoint's rows.
    pub fn series_mut(&mut self) -> &mut CsvSeries {
        &mut self.csv
    }

    /// Creates `path` with step, time, then `NAME_p, NAME_vx, NAME_vy, NAME_vz` per point probe
    /// and `NAME_{fx,fy,fz}_{pressure,viscous}` per force probe. `body_index` maps an obstacle
    /// name to its index among the solver's bodies.
    pub fn create(
        path: &Path,
        probes: &[Probe],
        body_index: impl Fn(&str) -> Option<usize>,
    ) -> Result<Self, IoError> {
        let mut columns: Vec<String> = vec!["step".into(), "time".into()];
        let mut kept = Vec::new();
        for p in probes {
            match p {
                Probe::Point { name, .. } => {
                    columns.extend(["p", "vx", "vy", "vz"].map(|c| format!("{name}_{c}")));
                    kept.push((p.clone(), None));
                }
                Probe::Force { name, body } => {
                    for part in ["pressure", "viscous"] {
                        columns.extend(["fx", "fy", "fz"].map(|c| format!("{name}_{c}_{part}")));
                    }
                    kept.push((p.clone(), body_index(body)));
                }
                Probe::Line { .. } | Probe::Front { .. } => {}
            }
        }
        Ok(Self {
            probes: kept,
            csv: CsvSeries::create(path, &columns)?,
            row: Vec::new(),
        })
    }

    /// Samples every probe on the current state.
    pub fn record(&mut self, solver: &GridSolver) -> Result<(), IoError> {
        self.row.clear();
        self.row.extend([solver.steps() as Real, solver.time()]);
        for (p, body) in &self.probes {
            match (p, body) {
                (Probe::Point { position, .. }, _) => {
                    let (pressure, v) = sample_point(solver, &Vec3::from(*position));
                    self.row.extend([pressure, v.x, v.y, v.z]);
                }
                (Probe::Force { .. }, Some(b)) => {
                    let f = force_on(solver, *b);
                    self.row.extend(f.pressure.iter().chain(f.viscous.iter()));
                }
                _ => self.row.extend([Real::NAN; 6]),
            }
        }
        self.csv.row(&self.row)
    }
}
