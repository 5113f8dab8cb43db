//! One direction of the precomputation (Pfaff et al. 2009, section 5.1 and Figure 5): run the
//! MAC-grid solver with raised viscosity, average the flow, and evaluate
//! `omega_pre = beta (U(x + l n) x n)` at every boundary point.

use anyhow::bail;
use eddy::abl::MotionKind;
use eddy::geometry::Body;
use eddy::grid::params::PRESSURE_MAX_ITERATIONS;
use eddy::grid::poisson::SolverSettings;
use eddy::grid::{GridParams, GridSide, GridSolver, ViscosityScheme};
use eddy::stepping::StepLimits;
use eddy::{Point3, Real, Vec3};

use crate::spec::ObstacleSpec;

/// The boundary points and normals, in the object's frame.
#[derive(Debug, Clone)]
pub struct Surface {
    pub points: Vec<Point3>,
    pub normals: Vec<Vec3>,
}

impl Surface {
    /// Points about `layer.point_spacing` cells apart on the obstacle's surface.
    pub fn of(spec: &ObstacleSpec) -> anyhow::Result<Self> {
        let body = spec.body()?;
        let points = body.sample_surface(spec.layer.point_spacing * spec.spacing()?);
        let normals = points.iter().map(|p| body.normal_local(p)).collect();
        Ok(Self { points, normals })
    }
}

/// The grid of one direction and the obstacle in it. Translation: the object is fixed and the free stream
/// `-direction` (the object moving along `direction` through still fluid) is prescribed on every
/// side of the box. The boundary conditions are then linear in the direction, so omega_pre is a
/// smooth function of it; with open outflow sides (inflow where the stream enters, zero pressure
/// elsewhere) a side switched from one to the other as a flow component crossed zero, and
/// omega_pre jumped by 2.6 % there (sphere, 24^3), right on the sample meridians
/// phi = 0, 90, 180, 270 degrees and the equator, which no interpolation can follow.
/// Rotation: still fluid,
/// the object spins at 1 rad/s about `direction`, and every side is open (zero pressure), so the
/// pumping of a spinning body leaves and enters as it would in unbounded fluid, rather than
/// being spun up or down by walls.
pub fn grid(
    spec: &ObstacleSpec,
    kind: MotionKind,
    direction: &Vec3,
) -> anyhow::Result<(GridParams, Body)> {
    let g = &spec.grid;
    let grid_box = spec.grid_box()?;
    let dx = grid_box.dx;
    let speed = match kind {
        MotionKind::Translation => 1.0,
        MotionKind::Rotation => reach(spec)?,
    };
    let dt = g.cfl * dx / speed;
    let flow = -direction;
    let (side, initial_velocity, angular) = match kind {
        MotionKind::Translation => (GridSide::Inflow(flow.into()), flow, [0.0; 3]),
        MotionKind::Rotation => (GridSide::Open, Vec3::zeros(), (*direction).into()),
    };
    let params = GridParams {
        resolution: grid_box.cells,
        dx,
        origin: grid_box.origin(),
        initial_velocity,
        sides: std::array::from_fn(|_| [side.clone(), side.clone()]),
        inflow_turbulence: None,
        advection: g.advection,
        reflection: false,
        viscosity_scheme: ViscosityScheme::BackwardEuler,
        viscosity: g.viscosity,
        density: 1.0,
        confinement: 0.0,
        gravity: Vec3::zeros(),
        gravity_force: false,
        limits: StepLimits {
            fixed_dt: Some(dt),
            dt_max: dt,
            dt_min: dt * 1e-3,
            ..StepLimits::default()
        },
        pressure: SolverSettings {
            tolerance: g.stabilise_tolerance,
            max_iterations: PRESSURE_MAX_ITERATIONS,
        },
        smoke: None,
        smoke_refinement: 1,
        average_from: None,
        container: false,
        obstacle_surface: g.obstacle_surface,
        incremental_pressure: g.incremental_pressure,
    };
    Ok((params, spec.body_entry(angular)))
}

/// Largest distance of the object's bounding box from its origin: the fastest wall speed at
/// 1 rad/s.
fn reach(spec: &ObstacleSpec) -> anyhow::Result<Real> {
    let (lo, hi) = spec.body()?.local_aabb();
    Ok(lo.coords.abs().sup(&hi.coords.abs()).norm())
}

/// omega_pre per unit speed at every point of `surface`, object frame, for one direction.
///
/// The velocity just outside the layer is taken relative to the wall and in the object's frame,
/// `U_rel = R^T (U(x_e) - v_body(x_e))` at `x_e = pose (x + l n)`, and averaged over the
/// averaging steps: for the fixed object of a translation this is the paper's average of U;
/// for a spinning object it is the average in the co-rotating frame, where the boundary layer
/// is steady, and a spinning sphere in inviscid fluid keeps its full slip (the confined
/// vorticity a real no-slip wall would hold).
pub fn solve(
    spec: &ObstacleSpec,
    surface: &Surface,
    kind: MotionKind,
    direction: &Vec3,
) -> anyhow::Result<Vec<Vec3>> {
    let (params, body) = grid(spec, kind, direction)?;
    let body = eddy::geometry::RigidBody::from_scene(&body, 0)?;
    let mut solver = GridSolver::new(&params, vec![body])?;
    let grid_box = spec.grid_box()?;
    if solver.bounds.fluid_cells() == grid_box.cells.iter().product::<usize>() {
        bail!(
            "obstacle '{}' covers no cell centre of the {} precomputation grid: raise \
             grid.resolution or lower grid.domain",
            spec.name,
            grid_box.describe()
        );
    }
    if kind == MotionKind::Translation {
        // Start from the projected free stream: the discrete potential flow around the object,
        // which is already the inviscid answer and close to the viscous one away from the wall.
        let flow = -direction;
        solver.set_velocity(|_| flow)?;
    }
    let l = spec.layer.thickness * spec.spacing()?;
    let outside: Vec<Point3> = surface
        .points
        .iter()
        .zip(&surface.normals)
        .map(|(x, n)| x + n * l)
        .collect();
    let mut settle = Settle::new(spec.grid.settle_tolerance);
    for _ in 0..spec.grid.stabilise_steps {
        solver.step(None)?;
        if settle.steady(&relative_flow(&solver, &outside)) {
            break;
        }
    }
    // The scene's solves ran at the stabilising tolerance; the averaged flow gets its own.
    solver.set_solver_tolerance(spec.grid.tolerance);
    let steps = if settle.settled {
        STEADY_AVERAGE_STEPS.min(spec.grid.average_steps)
    } else {
        spec.grid.average_steps
    };
    let mut sum = vec![Vec3::zeros(); outside.len()];
    let mut time = 0.0;
    for _ in 0..steps {
        let dt = solver.step(None)?.dt;
        for (s, u) in sum.iter_mut().zip(relative_flow(&solver, &outside)) {
            *s += u * dt;
        }
        time += dt;
    }
    let beta = spec.layer.beta;
    Ok(sum
        .iter()
        .zip(&surface.normals)
        .map(|(s, n)| (s / time).cross(n) * beta)
        .collect())
}

/// Steps averaged once the flow has settled: the average of a steady flow is the flow, and a
/// few steps smooth what is left of its approach.
pub const STEADY_AVERAGE_STEPS: u32 = 5;

/// Steps over which the decay rate of the change is measured.
const DECAY_WINDOW: usize = 5;

/// `U_rel = R^T (U(x_e) - v_body(x_e))` at the world positions of the object-frame points
/// `outside`: the flow just outside the layer, relative to the wall, in the object's frame.
fn relative_flow(solver: &GridSolver, outside: &[Point3]) -> Vec<Vec3> {
    let body = &solver.bodies[0];
    let t = solver.time();
    let pose = body.pose(t);
    outside
        .iter()
        .map(|xe| {
            let world = pose * xe;
            let u = solver.mac.velocity_at(&world.coords) - body.velocity_at(t, &world);
            pose.rotation.inverse_transform_vector(&u)
        })
        .collect()
}

/// Whether the sampled flow has settled. Its relative change per step, c_k = sum |U_k -
/// U_(k-1)| / sum |U_k|, decays geometrically as a steady flow is approached (ratio r per
/// step, measured over [`DECAY_WINDOW`] steps), so the distance still to go is about
/// c_k r / (1 - r); the flow counts as steady once that estimate is below the tolerance. A
/// flow that keeps changing (a wake that sheds; the spin-up around a rotating object, whose
/// samples also move across the grid) has r near 1 and never settles: it gets the full step
/// counts.
struct Settle {
    tolerance: Real,
    last: Option<Vec<Vec3>>,
    changes: Vec<Real>,
    settled: bool,
}

impl Settle {
    fn new(tolerance: Real) -> Self {
        Self {
            tolerance,
            last: None,
            changes: Vec::new(),
            settled: false,
        }
    }

    /// Takes the samples of one more step; true once the flow has settled.
    fn steady(&mut self, flow: &[Vec3]) -> bool {
        if self.tolerance <= 0.0 {
            return false;
        }
        if let Some(last) = &self.last {
            let change: Real = flow.iter().zip(last).map(|(a, b)| (a - b).norm()).sum();
            let size: Real = flow.iter().map(|a| a.norm()).sum();
            self.changes
                .push(if size > 0.0 { change / size } else { 0.0 });
        }
        self.last = Some(flow.to_vec());
        let n = self.changes.len();
        if n > DECAY_WINDOW {
            let (now, before) = (self.changes[n - 1], self.changes[n - 1 - DECAY_WINDOW]);
            if now == 0.0 {
                self.settled = true;
            } else if before > 0.0 {
                let r = (now / before).powf(1.0 / DECAY_WINDOW as Real);
                self.settled = r < 1.0 && now * r / (1.0 - r) < self.tolerance;
            }
        }
        self.settled
    }
}
