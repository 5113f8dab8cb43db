//! The running statistics (`[statistics]`): the online moments equal a two-pass computation
//! over the same samples, on a grid and on particles; a steady laminar flow gives its analytic
//! mean and no fluctuation; a uniform stream's bins give its velocity and zero stress.

mod common;

use std::path::Path;

use eddy::grid::forces::vorticity;
use eddy::metrics::statistics::{CellMoments, STRESS_PAIRS};
use eddy::pipeline::{Pipeline, Plan};
use eddy::{Real, Vec3};

/// One sample of one cell: weight, velocity, vorticity, enstrophy.
type Sample = (Real, [Real; 3], [Real; 3], Real);

/// Mean velocity, stresses (STRESS_PAIRS order), mean vorticity, mean enstrophy.
type Moments = ([Real; 3], [Real; 6], [Real; 3], Real);

/// The moments of `samples` by two passes: the weighted means first, then the weighted mean of
/// the products of deviations.
fn two_pass(samples: &[Sample]) -> Moments {
    let w: Real = samples.iter().map(|s| s.0).sum();
    let mean = |f: &dyn Fn(&Sample) -> Real| samples.iter().map(|s| s.0 * f(s)).sum::<Real>() / w;
    let u: [Real; 3] = std::array::from_fn(|c| mean(&|s| s.1[c]));
    let stress = STRESS_PAIRS.map(|(a, b)| mean(&|s| (s.1[a] - u[a]) * (s.1[b] - u[b])));
    let omega = std::array::from_fn(|c| mean(&|s| s.2[c]));
    (u, stress, omega, mean(&|s| s.3))
}

/// A cell's running moments.
fn running(c: &CellMoments) -> Moments {
    (c.mean, c.stress(), c.vorticity, c.enstrophy)
}

/// Checks every cell's running moments against the two-pass ones of its samples, each
/// quantity to 1e-12 of its largest magnitude over the lattice.
fn assert_two_pass(cells: &[CellMoments], samples: &[Vec<Sample>]) {
    let reference: Vec<Option<Moments>> = samples
        .iter()
        .map(|s| (!s.is_empty()).then(|| two_pass(s)))
        .collect();
    type Part = fn(&Moments) -> Vec<Real>;
    let quantities: [(&str, Part); 4] = [
        ("mean", |m| m.0.to_vec()),
        ("stress", |m| m.1.to_vec()),
        ("vorticity", |m| m.2.to_vec()),
        ("enstrophy", |m| vec![m.3]),
    ];
    for (name, part) in quantities {
        let scale = reference
            .iter()
            .flatten()
            .flat_map(part)
            .fold(0.0, |m: Real, v| m.max(v.abs()));
        assert!(
            scale > 0.0,
            "{name}: every sample is zero, nothing is checked"
        );
        for (i, (cell, r)) in cells.iter().zip(&reference).enumerate() {
            let Some(r) = r else {
                assert_eq!(cell.samples, 0, "cell {i} has no sample");
                continue;
            };
            assert_eq!(cell.samples as usize, samples[i].len(), "cell {i}");
            for (a, b) in part(&running(cell)).iter().zip(part(r)) {
                assert!(
                    (a - b).abs() <= 1e-12 * scale,
                    "cell {i} {name}: running {a:e}, two-pass {b:e} (scale {scale:e})"
                );
            }
        }
    }
}

fn load(text: &str) -> Pipeline {
    common::built(text, "statistics.toml")
}

/// The cylinder in a channel at a coarse resolution, shedding from the start: every cell's
/// running moments over 40 steps equal the two-pass ones of the same cell-centred velocities
/// and vorticities, each weighted by its step, and the cylinder's cells have no sample.
#[test]
fn running_moments_equal_two_pass_on_a_grid() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cylinder_channel.toml");
    let scene = eddy::scene::load(
        &path,
        &[
            "grid.resolution=[64, 16, 1]".into(),
            "domain.max=[4.0, 1.0, 0.0625]".into(),
            "statistics.from=0".into(),
            "grid.initial_velocity=[1.0, 0.2, 0.0]".into(),
        ],
    )
    .expect("loads");
    let mut p = Pipeline::build(&scene).expect("builds");
    let n = common::grid(&p).mac.cell_count();
    let mut samples: Vec<Vec<Sample>> = vec![Vec::new(); n];
    for _ in 0..40 {
        let rec = p.step(None, None).expect("steps");
        let g = common::grid(&p);
        let u = g.mac.cell_velocity();
        let w = vorticity(&g.mac);
        let fluid = g.bounds.fluid_mask();
        for ((idx, &f), cell) in fluid.indexed_iter().zip(&mut samples) {
            if f {
                let (i, j, k) = idx;
                let ui = [0, 1, 2].map(|a| u[a][[i, j, k]]);
                let wi = [0, 1, 2].map(|a| w[a][[i, j, k]]);
                let e = 0.5 * wi.iter().map(|x| x * x).sum::<Real>();
                cell.push((rec.dt, ui, wi, e));
            }
        }
    }
    let stats = &p.sim.statistics[0].stats;
    assert!(samples.iter().any(Vec::is_empty), "the cylinder's cells");
    assert_two_pass(&stats.cells, &samples);
    let span = stats.span.expect("sampled");
    assert!(
        span.0 == 0.0 && (span.1 - p.sim.time()).abs() < 1e-12,
        "{span:?}"
    );
}

/// A dam break on bins of 5 cm: each bin's running moments equal the two-pass ones of its
/// per-step particle means, weighted by step and count (the bins computed here, apart).
#[test]
fn running_moments_equal_two_pass_on_particles() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/dam_break.toml");
    let bin = 0.05;
    let scene = eddy::scene::load(
        &path,
        &[
            "fluid.spacing=0.04".into(),
            "statistics.from=0".into(),
            format!("statistics.bin={bin}"),
        ],
    )
    .expect("loads");
    let lo = Vec3::from(scene.domain.min);
    let hi = Vec3::from(scene.domain.max);
    let dims: [usize; 3] = std::array::from_fn(|a| ((hi[a] - lo[a]) / bin).ceil() as usize);
    let mut p = Pipeline::build(&scene).expect("builds");
    let mut samples: Vec<Vec<Sample>> = vec![Vec::new(); dims.iter().product()];
    for _ in 0..30 {
        let rec = p.step(None, None).expect("steps");
        let sph = p.sim.sph.as_ref().expect("a fluid");
        let omega = sph.vorticity();
        let mut sums = vec![(0.0, [0.0; 3], [0.0; 3], 0.0); samples.len()];
        for ((x, v), w) in sph.fluid.x.iter().zip(&sph.fluid.v).zip(&omega) {
            let g = [0, 1, 2].map(|a| ((x[a] - lo[a]) / bin).floor() as usize);
            let s = &mut sums[(g[0] * dims[1] + g[1]) * dims[2] + g[2]];
            s.0 += 1.0;
            for c in 0..3 {
                s.1[c] += v[c];
                s.2[c] += w[c];
            }
            s.3 += 0.5 * w.norm_squared();
        }
        for (cell, (count, u, w, e)) in samples.iter_mut().zip(sums) {
            if count > 0.0 {
                cell.push((
                    rec.dt * count,
                    u.map(|x| x / count),
                    w.map(|x| x / count),
                    e / count,
                ));
            }
        }
    }
    let stats = &p.sim.statistics[0].stats;
    assert_eq!(stats.lattice.dims, dims);
    assert_two_pass(&stats.cells, &samples);
}

/// The statistics and the metrics share one curl of the state they both measure
/// (`Simulation::particle_vorticity`): after every step, sampled (every second step) or not,
/// what they shared is the vorticity of the state the step ended with, never an earlier
/// step's; and each metrics row's enstrophy is that of the state its step started from,
/// computed here apart.
#[test]
fn the_statistics_and_the_metrics_share_the_current_vorticity() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/dam_break.toml");
    let scene = eddy::scene::load(
        &path,
        &[
            "fluid.spacing=0.04".into(),
            "statistics.from=0".into(),
            "statistics.every=2".into(),
            "output.vtk=false".into(),
        ],
    )
    .expect("loads");
    let dir = tempfile::tempdir().expect("temp dir");
    let mut p = Pipeline::build(&scene).expect("builds");
    p.open(dir.path()).expect("opens");
    let mut enstrophy = Vec::new();
    for step in 0..8 {
        p.step(None, None).expect("steps");
        let sph = p.sim.sph.as_ref().expect("a fluid");
        let now = sph.vorticity();
        let shared = p.sim.particle_vorticity.as_ref().expect("taken this step");
        assert!(
            shared == &now,
            "step {step}: the shared vorticity is not the current state's"
        );
        enstrophy.push(eddy::metrics::vorticity_stats(&now, sph.fluid.volume()).enstrophy);
    }
    let metrics = std::fs::read_to_string(dir.path().join("metrics.csv")).expect("metrics");
    let mut lines = metrics.lines();
    let header: Vec<&str> = lines.next().expect("a header").split(',').collect();
    let column = header
        .iter()
        .position(|c| *c == "enstrophy")
        .expect("enstrophy");
    let written: Vec<Real> = lines
        .map(|l| {
            l.split(',')
                .nth(column)
                .expect("a value")
                .parse()
                .expect("a number")
        })
        .collect();
    // Row k holds the state step k started from: the one step k - 1 ended with.
    assert_eq!(written.len(), 8);
    assert!(enstrophy[0] > 0.0, "a dam break has enstrophy");
    assert_eq!(&written[1..], &enstrophy[..7]);
}

/// Plane Poiseuille flow between plates 1 m apart, nu = 1 m²/s and g = 8 m/s² (u_max = 1 m/s),
/// which settles in a few tenths of a second (the slowest mode decays as exp(-pi² nu t)):
/// averaged over t = 2–3 s the mean is the steady profile g y (H - y) / (2 nu) within the
/// solver's error (the same as the instantaneous flow's) and the fluctuations are below 1e-8
/// of the mean's square.
#[test]
fn a_steady_laminar_flow_has_its_analytic_mean_and_no_fluctuation() {
    let text = r#"
        name = "poiseuille"
        gravity = [8.0, 0.0, 0.0]
        [domain]
        min = [0.0, 0.0, 0.0]
        max = [0.25, 1.0, 0.125]
        [time]
        end = 3.0
        cfl = 0.5
        dt_max = 0.01
        [viscosity]
        kinematic = 1.0
        [grid]
        resolution = [4, 16, 2]
        gravity = true
        pressure_tolerance = 1e-12
        [grid.boundary]
        x_min = "periodic"
        x_max = "periodic"
        z_min = "periodic"
        z_max = "periodic"
        [statistics]
        from = 2.0
        batches = 4
        [[statistics.stations]]
        name = "across"
        min = [0.0, 0.0, 0.0]
        max = [0.25, 1.0, 0.125]
        axis = "y"
        bins = 8
        [output]
        vtk = false
        metrics = []
    "#;
    let mut p = load(text);
    let plan = Plan::of(&p);
    let names: Vec<_> = plan.stages.iter().map(|s| s.name).collect();
    assert_eq!(names, ["grid", "statistics"], "{plan}");
    let stage = &plan.stages[1];
    assert!(
        stage.parts[0].1.contains("MiB") && stage.detail.contains("t = 2 s"),
        "{plan}"
    );
    while p.sim.time() < 3.0 - 1e-12 {
        p.step(Some(3.0), None).expect("steps");
    }
    let g = common::grid(&p);
    let now = g.mac.cell_velocity();
    let stats = &p.sim.statistics[0].stats;
    let f = stats.fields();
    let (mut worst_mean, mut worst_now, mut worst_stress, mut u_max) = (0.0, 0.0, 0.0, 0.0);
    for ((i, j, k), u) in f.mean_velocity[0].indexed_iter() {
        let y = (j as Real + 0.5) / 16.0;
        let exact = 8.0 * y * (1.0 - y) / 2.0;
        u_max = Real::max(u_max, exact);
        worst_mean = Real::max(worst_mean, (u - exact).abs());
        worst_now = Real::max(worst_now, (now[0][[i, j, k]] - exact).abs());
        for s in 0..6 {
            worst_stress = Real::max(worst_stress, f.reynolds_stress[s][[i, j, k]].abs());
        }
        for a in 1..3 {
            assert!(f.mean_velocity[a][[i, j, k]].abs() < 1e-12, "no cross-flow");
        }
    }
    assert!(
        (worst_mean - worst_now).abs() < 1e-9 && worst_now < 0.02 * u_max,
        "mean's error {worst_mean:e}, the flow's own {worst_now:e} (u_max {u_max})"
    );
    assert!(
        worst_stress < 1e-8 * u_max * u_max,
        "largest stress {worst_stress:e}"
    );
    let span = stats.span.expect("sampled");
    assert!(
        (span.0 - 2.0).abs() < 1e-12 && (span.1 - 3.0).abs() < 1e-12,
        "{span:?}"
    );
}

/// A block of water moving at 0.5 m/s without gravity or walls: every bin it crosses reads its
/// velocity, and no stress.
#[test]
fn the_bins_of_a_uniform_stream_give_its_velocity_and_zero_stress() {
    let text = r#"
        name = "stream"
        gravity = [0.0, 0.0, 0.0]
        [domain]
        min = [-1.0, -1.0, -1.0]
        max = [1.0, 1.0, 1.0]
        [time]
        steps = 20
        dt = 2e-3
        [fluid]
        spacing = 0.05
        [[fluid.blocks]]
        min = [-0.3, -0.2, -0.2]
        max = [0.3, 0.2, 0.2]
        velocity = [0.5, -0.1, 0.2]
        [statistics]
        bin = 0.125
        [output]
        vtk = false
        metrics = []
    "#;
    let mut p = load(text);
    for _ in 0..20 {
        p.step(None, None).expect("steps");
    }
    let v = [0.5, -0.1, 0.2];
    let stats = &p.sim.statistics[0].stats;
    let mut bins = 0;
    for c in stats.cells.iter().filter(|c| c.samples > 0) {
        bins += 1;
        for (u, v) in c.mean.iter().zip(v) {
            assert!((u - v).abs() < 1e-12, "{:?}", c.mean);
        }
        assert!(
            c.stress().iter().all(|s| s.abs() < 1e-24),
            "{:?}",
            c.stress()
        );
        assert!(c.k().abs() < 1e-24);
    }
    assert!(bins > 50, "{bins} bins sampled");
}
