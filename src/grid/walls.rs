//! What the run-time boundary layer asks of the grid's walls (Pfaff et al. 2009, Figure 9): the
//! cells beside each obstacle, the distance of every cell to the nearest wall (the mixing length
//! l_m of Eq. 8), and the ambient flow around an obstacle.

use ndarray::{s, Array3, Zip};

use super::boundary::cells_near;
use super::params::GridSide;
use super::solver::GridSolver;
use crate::{Point3, Real, Vec3};

/// The fluid cells sharing a face with a cell of obstacle `body` at the solver's time: the
/// wall-attached voxels of Figure 9, line 2.
pub fn boundary_cells(solver: &GridSolver, body: usize) -> Vec<[usize; 3]> {
    let b = &solver.bounds;
    let dims = solver.mac.dims;
    let [rx, ry, rz] = cells_near(&solver.mac, &solver.bodies[body], solver.time(), 0.0);
    let widen = |r: std::ops::Range<usize>, n: usize| r.start.saturating_sub(1)..(r.end + 1).min(n);
    let (rx, ry, rz) = (widen(rx, dims[0]), widen(ry, dims[1]), widen(rz, dims[2]));
    let mut cells = Vec::new();
    for i in rx {
        for j in ry.clone() {
            for k in rz.clone() {
                let idx = [i, j, k];
                if b.is_solid(idx) {
                    continue;
                }
                let touches = (0..3).any(|a| {
                    [-1i64, 1].iter().any(|&d| {
                        let n = idx[a] as i64 + d;
                        if n < 0 || n >= dims[a] as i64 {
                            return false;
                        }
                        let mut m = idx;
                        m[a] = n as usize;
                        b.owner(m) == Some(body)
                    })
                });
                if touches {
                    cells.push(idx);
                }
            }
        }
    }
    cells
}

/// Distance from every cell centre to the nearest wall, m: the obstacles' surfaces (0 inside
/// them; a container's from inside), and the domain sides that are walls (no-slip, moving or
/// free-slip; inflow, open and periodic sides are not walls).
pub fn wall_distance(solver: &GridSolver) -> Array3<Real> {
    let mac = &solver.mac;
    let sides = &solver.bounds.sides;
    let t = solver.time();
    let poses: Vec<_> = solver.bodies.iter().map(|b| b.pose(t)).collect();
    let container = solver.has_container();
    let mut out = Array3::zeros(mac.dims);
    Zip::indexed(&mut out).par_for_each(|(i, j, k), d| {
        let x = mac.cell_center([i, j, k]);
        let mut best = Real::INFINITY;
        for a in 0..3 {
            let extent = mac.dims[a] as Real * mac.dx;
            for (side, gap) in [
                (0, x[a] - mac.origin[a]),
                (1, mac.origin[a] + extent - x[a]),
            ] {
                if is_wall(&sides[a][side]) {
                    best = best.min(gap);
                }
            }
        }
        for (i, (body, pose)) in solver.bodies.iter().zip(&poses).enumerate() {
            let local = pose.inverse_transform_point(&Point3::from(x));
            let d = body.signed_distance_local(&local);
            best = best.min(if i == 0 && container { -d } else { d });
        }
        *d = best.max(0.0);
    });
    out
}

fn is_wall(side: &GridSide) -> bool {
    matches!(
        side,
        GridSide::Wall | GridSide::MovingWall(_) | GridSide::Slip
    )
}

/// The fluid cells whose centres lie between `inner` and `outer` (m) from the surface of
/// obstacle `body` at the solver's time: the shell the ambient flow is measured on.
pub fn shell_cells(solver: &GridSolver, body: usize, inner: Real, outer: Real) -> Vec<[usize; 3]> {
    let mac = &solver.mac;
    let rigid = &solver.bodies[body];
    let pose = rigid.pose(solver.time());
    let [rx, ry, rz] = cells_near(mac, rigid, solver.time(), outer);
    let (x0, y0, z0) = (rx.start, ry.start, rz.start);
    let mut inside = Array3::from_elem((rx.len(), ry.len(), rz.len()), false);
    Zip::indexed(&mut inside).par_for_each(|(i, j, k), hit| {
        let idx = [x0 + i, y0 + j, z0 + k];
        let c = Point3::from(mac.cell_center(idx));
        let d = rigid.signed_distance_local(&pose.inverse_transform_point(&c));
        *hit = d >= inner && d <= outer && !solver.bounds.is_solid(idx);
    });
    let mut cells = Vec::new();
    for ((i, j, k), &hit) in inside.slice(s![.., .., ..]).indexed_iter() {
        if hit {
            cells.push([x0 + i, y0 + j, z0 + k]);
        }
    }
    cells
}

/// Mean cell-centre velocity over `cells`; `None` for no cells.
pub fn mean_velocity(solver: &GridSolver, cells: &[[usize; 3]]) -> Option<Vec3> {
    if cells.is_empty() {
        return None;
    }
    let sum: Vec3 = cells
        .iter()
        .map(|&idx| solver.mac.velocity_at_sample(None, idx))
        .sum();
    Some(sum / cells.len() as Real)
}
