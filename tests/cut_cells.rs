//! Obstacles that cut cells (`grid.obstacle_surface = "cut"`): a slanted wall at rest under
//! gravity holds the hydrostatic pressure to round-off, a probe on its surface reads it, and the
//! projection around a moving sphere is divergence-free on the fluid's share of every cell.

mod common;

use eddy::grid::GridSolver;
use eddy::metrics::grid_probes::sample_point;
use eddy::pipeline::grid_solver;
use eddy::scene::{self, Scene};
use eddy::{Point3, Real, Vec3};
use std::path::Path;

fn scene_from(text: &str) -> Scene {
    scene::parse_str(text, Path::new("test.toml"), &[]).expect("test scene is valid")
}

/// A closed 1 x 1 m box, 24 x 24 cells and 2 deep (periodic in z), with a floor tilted by 20
/// degrees about z: a box whose top face runs through (0.5, 0.3) at that slope.
fn tilted_tank(surface: &str) -> GridSolver {
    let s = scene_from(&format!(
        r#"
        name = "tilted tank"
        gravity = [0.0, -9.81, 0.0]
        domain = {{ min = [0.0, 0.0, 0.0], max = [1.0, 1.0, 0.08333333333333333] }}
        time = {{ end = 1.0, cfl = 0.5, dt_max = 0.01 }}
        viscosity = {{ kinematic = 0.0 }}
        [grid]
        resolution = [24, 24, 2]
        gravity = true
        pressure_tolerance = 1e-13
        obstacle_surface = "{surface}"
        boundary = {{ z_min = "periodic", z_max = "periodic" }}
        [[obstacles]]
        name = "floor"
        shape = {{ type = "box", half_extents = [1.0, 0.3, 1.0] }}
        position = [0.5, 0.0, 0.04]
        rotation = [0.0, 0.0, 0.3490658503988659]
        "#
    ));
    grid_solver(&s).expect("grid builds")
}

/// The floor's top surface: its point above x (the box's top face, tilted by 20 degrees about
/// its centre (0.5, 0)).
fn floor_height(x: Real) -> Real {
    let angle: Real = 20.0_f64.to_radians();
    (x - 0.5) * angle.tan() + 0.3 / angle.cos()
}

/// Gravity on faces the tilted floor cuts: each face's share is in the divergence and the
/// matrix alike, so a hydrostatic pressure cancels the pull exactly. After ten steps no face
/// moves faster than round-off, p + rho g y is the same in every cell with a pressure, and a
/// probe on the slanted surface reads the hydrostatic value there. A staircase holds the rest
/// too, but its probe reads the cells a voxel off the surface.
#[test]
fn a_tilted_floor_at_rest_under_gravity_holds_the_hydrostatic_pressure() {
    let mut g = tilted_tank("cut");
    assert!(g.bounds.cut_faces().is_some());
    for _ in 0..10 {
        g.step(None).expect("stable");
    }
    let speed = g.mac.max_face_speed();
    assert!(speed < 1e-11, "the fluid at rest moves at {speed:e} m/s");
    let rho_g = g.density() * 9.81;
    let head: Vec<Real> = g
        .pressure
        .indexed_iter()
        .filter(|(c, _)| g.bounds.has_pressure([c.0, c.1, c.2]))
        .map(|(c, &p)| p + rho_g * g.mac.cell_center([c.0, c.1, c.2]).y)
        .collect();
    let (lo, hi) = head
        .iter()
        .fold((Real::MAX, Real::MIN), |(l, h), &v| (l.min(v), h.max(v)));
    assert!(
        hi - lo < 1e-9 * rho_g,
        "p + rho g y spans {:e} Pa over {} cells",
        hi - lo,
        head.len()
    );
    let cut_cells = head.len() - g.bounds.fluid_cells();
    assert!(cut_cells > 20, "only {cut_cells} cut cells");
    for x in [0.3, 0.55, 0.8] {
        let on = Vec3::new(x, floor_height(x), 0.04);
        let (p, _) = sample_point(&g, &on);
        let expected = lo - rho_g * on.y;
        assert!(
            (p - expected).abs() < 1e-9 * rho_g,
            "probe on the floor at x = {x}: {p} Pa, hydrostatic {expected} Pa"
        );
    }
}

/// The moving sphere in a channel with cut cells: after each step the net outflow of the
/// fluid's share of every cell with a pressure is below 1e-9 |u|max / dx, the faces the sphere
/// covers entirely carry its velocity, and hundreds of faces are cut.
#[test]
fn the_projection_with_cut_cells_is_divergence_free_around_a_moving_sphere() {
    let s = scene_from(&common::moving_ball_channel("cut"));
    let mut g = grid_solver(&s).expect("grid builds");
    assert!(
        g.bounds.cut_faces().is_some(),
        "the scene key reaches the solver"
    );
    for _ in 0..3 {
        common::step_divergence_free(&mut g);
        let faces = g.bounds.cut_faces().expect("cut cells");
        let ball = &g.bodies[0];
        let (mut covered, mut cut) = (0, 0);
        for a in 0..3 {
            for (idx, &open) in faces.open[a].indexed_iter() {
                let idx = [idx.0, idx.1, idx.2];
                let x = Point3::from(g.mac.face_center(a, idx));
                if open == 0.0 && ball.signed_distance(g.time(), &x) < 0.0 {
                    covered += 1;
                    let v = ball.velocity_at(g.time(), &x)[a];
                    assert_eq!(g.mac.u[a][idx], v, "covered face {idx:?}/{a}");
                } else if open < 1.0 {
                    cut += 1;
                }
            }
        }
        assert!(covered > 100 && cut > 100, "{covered} covered, {cut} cut");
    }
}

/// The drag coefficient of the DFG 2D-1 cylinder (Re 20) in a channel shortened to 0.6 m, after
/// 2 s (steady to 1e-4), at `cells` per diameter.
fn short_channel_drag(cells: usize, surface: &str) -> Real {
    let dx = 0.1 / cells as Real;
    let s = scene_from(&format!(
        r#"
        name = "short dfg 2d-1"
        gravity = [0.0, 0.0, 0.0]
        domain = {{ min = [0.0, 0.0, 0.0], max = [0.6, 0.4, {dx}] }}
        time = {{ end = 2.0, cfl = 0.5, dt_max = 0.01 }}
        viscosity = {{ kinematic = 0.001 }}
        [grid]
        resolution = [{nx}, {ny}, 1]
        obstacle_surface = "{surface}"
        [grid.boundary]
        x_min = {{ profiled_inflow = {{ velocity = [0.3, 0.0, 0.0], shape = "plane", across = 1 }} }}
        x_max = "open"
        z_min = "periodic"
        z_max = "periodic"
        [[obstacles]]
        name = "cylinder"
        shape = {{ type = "cylinder", radius = 0.05, half_height = 1.0 }}
        position = [0.2, 0.2, 0.0]
        rotation = [1.5707963267948966, 0.0, 0.0]
        "#,
        nx = 6 * cells,
        ny = 4 * cells,
    ));
    let mut g = grid_solver(&s).expect("grid builds");
    // Whole CFL steps only: a step shortened to land on a time moves the pressure with it.
    while g.time() < 2.0 {
        g.step(None).expect("stable");
    }
    let f = eddy::metrics::grid_probes::force_on(&g, 0);
    let (mean, diameter) = (0.2, 0.1);
    2.0 * (f.pressure.x + f.viscous.x) / (g.density() * mean * mean * diameter * dx)
}

/// Cut cells converge: the cylinder's drag at 10, 20 and 40 cells per diameter changes by less
/// than 0.35 times as much between the two finer grids as between the two coarser ones (an
/// observed order above 1.5; first order would halve it), and lies within 3 % of the
/// benchmark's 5.58 (the channel is shorter here). Measured at t = 3 s: 5.599, 5.733, 5.754.
#[test]
fn the_drag_of_a_cut_cylinder_converges_at_better_than_first_order() {
    let c: Vec<Real> = [10, 20, 40]
        .iter()
        .map(|&n| short_channel_drag(n, "cut"))
        .collect();
    println!("c_D at 10, 20, 40 cells per diameter: {c:?}");
    let (coarse, fine) = ((c[1] - c[0]).abs(), (c[2] - c[1]).abs());
    assert!(
        fine < 0.35 * coarse,
        "c_D changes by {coarse:.4} then {fine:.4}: order {:.2}",
        (coarse / fine).log2()
    );
    assert!((c[2] / 5.58 - 1.0).abs() < 0.03, "c_D {}", c[2]);
}

/// The CFL step reads the flow's speed, not the velocity of a sliver of a face: past a sphere
/// in a 1 m/s stream on cut cells (the demo's wake without its boundary layers, 16 cells across
/// the sphere), the speed the CFL rule reads after three steps is within 5 % of potential
/// flow's peak at the equator, 1.5 m/s (1.446 measured). The largest face speed sits on a
/// partly covered face and runs above it (1.63 m/s, 9 % over, on a face 11.7 % open); bounding
/// the step by it made the steps 10 % shorter.
#[test]
fn the_cfl_step_reads_the_flow_speed_past_a_cut_sphere() {
    let text = r#"
        name = "sphere_in_a_stream"
        gravity = [0.0, 0.0, 0.0]
        [domain]
        min = [0.0, 0.0, 0.0]
        max = [6.0, 3.0, 3.0]
        [time]
        end = 1.0
        cfl = 0.8
        dt_max = 0.05
        [grid]
        resolution = [64, 32, 32]
        advection = "maccormack"
        initial_velocity = [1.0, 0.0, 0.0]
        obstacle_surface = "cut"
        [grid.boundary]
        x_min = { inflow = [1.0, 0.0, 0.0] }
        x_max = "open"
        y_min = "slip"
        y_max = "slip"
        z_min = "slip"
        z_max = "slip"
        [[obstacles]]
        shape = { type = "sphere", radius = 0.5 }
        position = [1.5, 1.5, 1.5]
    "#;
    let scene = scene::parse_str(text, Path::new("sphere.toml"), &[]).expect("the scene is valid");
    let mut grid = grid_solver(&scene).expect("the grid builds");
    let mut last = None;
    for _ in 0..3 {
        last = Some(grid.step(None).expect("a step"));
    }
    let stats = last.expect("three steps");
    let speed = stats.cfl * grid.mac.dx / stats.dt;
    assert!(
        (speed / 1.5 - 1.0).abs() < 0.05,
        "the CFL rule reads {speed:.4} m/s"
    );
}
