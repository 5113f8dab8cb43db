//! Probes of a grid scene: pressure and velocity at a point over time, the force of the fluid
//! on an obstacle over time, and velocity profiles along lines.

use std::path::Path;

use super::spec::Probe;
use crate::io::{CsvSeries, IoError};
use crate::{Point3, Real, Vec3};

use crate::grid::GridSolver;

/// The force of the fluid on one obstacle, N.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Force {
    /// -sum p n dA over the obstacle's faces (n the obstacle's outward normal).
    pub pressure: Vec3,
    /// sum rho nu (u_fluid - u_body)_tangential / (dx / 2) dA: the wall shear, first order.
    pub viscous: Vec3,
}

/// The force of the fluid on obstacle `body` (an index into the solver's bodies), from the
/// faces between its cells and fluid cells (a staircase surface: first order in dx).
pub fn force_on(solver: &GridSolver, body: usize) -> Force {
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

/// A cell-centred `field` at `x` from the fluid cells only: trilinear in the eight cell centres
/// around `x` with the solid ones left out and the others' weights renormalised, so a probe on
/// an obstacle's surface reads the fluid beside it, not a blend with solid cells (whose
/// pressure is no fluid's: the DFG cylinder's front stagnation point read half its value).
/// Where all eight are solid, the nearest fluid cell centre within two cells; NaN if none.
pub fn fluid_sample(solver: &GridSolver, field: &ndarray::Array3<Real>, x: &Vec3) -> Real {
    let (mac, bounds) = (&solver.mac, &solver.bounds);
    let g = mac.grid_coords(x);
    let (mut sum, mut weight) = (0.0, 0.0);
    for (cell, w) in mac.cell_stagger().weights(g) {
        if w > 0.0 && !bounds.is_solid(cell) {
            sum += w * field[cell];
            weight += w;
        }
    }
    if weight > 0.0 {
        return sum / weight;
    }
    let at = g.map(|c| (c - 0.5).round() as isize);
    let mut nearest: Option<(Real, [usize; 3])> = None;
    for di in -2..=2isize {
        for dj in -2..=2isize {
            for dk in -2..=2isize {
                let c = [at[0] + di, at[1] + dj, at[2] + dk];
                if (0..3).any(|a| !(0..mac.dims[a] as isize).contains(&c[a])) {
                    continue;
                }
                let cell = c.map(|v| v as usize);
                if bounds.is_solid(cell) {
                    continue;
                }
                let d = (mac.cell_center(cell) - x).norm();
                if nearest.is_none_or(|(best, _)| d < best) {
                    nearest = Some((d, cell));
                }
            }
        }
    }
    nearest.map_or(Real::NAN, |(_, cell)| field[cell])
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
