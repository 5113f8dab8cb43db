//! `cargo bench --bench vortex`: vortex-particle synthesis time (Pfaff et al. 2009, section 4.3)
//! onto a MAC grid at rest against particle count and sigma at 64^3 and 128^3, and onto 100k
//! SPH-like points. Particles are seeded uniformly with a fixed seed; each time is the median of
//! five runs after one warm-up. Numbers after `--` pick the grid sizes (default 64 and 128).

use eddy::grid::MacGrid;
use eddy::vortex::{
    synthesize, AddVelocity, SinkLayout, SinkSamples, SinkVorticity, VelocitySink, VortexError,
    VortexParticles,
};
use eddy::{Real, Vec3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::time::Instant;

fn particles(count: usize, sigma: Real, extent: Real, seed: u64) -> VortexParticles {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut p = VortexParticles::new();
    for _ in 0..count {
        let x = Vec3::from_fn(|_, _| extent * rng.random::<Real>());
        let w = Vec3::from_fn(|_, _| 2.0 * rng.random::<Real>() - 1.0);
        p.push(x, w, sigma).expect("valid particle");
    }
    p
}

fn median_ms(mut run: impl FnMut()) -> Real {
    run();
    let mut t: Vec<Real> = (0..5)
        .map(|_| {
            let s = Instant::now();
            run();
            s.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    t.sort_by(Real::total_cmp);
    t[2]
}

/// A bare point set at rest (the SPH sink without the solver around it).
struct Points {
    x: Vec<Vec3>,
    v: Vec<Vec3>,
}

impl VelocitySink for Points {
    fn layout(&self) -> SinkLayout<'_> {
        SinkLayout::Points(&self.x)
    }
    fn vorticity(&self, _only: Option<&[bool]>) -> SinkVorticity<'_> {
        SinkVorticity::Points(vec![Vec3::zeros(); self.x.len()])
    }
    fn add_velocity(&mut self, add: &mut AddVelocity<'_>) -> Result<(), VortexError> {
        add(SinkSamples::Points(&mut self.v))
    }
}

fn main() {
    // `cargo bench --bench vortex -- 128` times only the grids named (cargo adds `--bench`).
    let mut grids: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    if grids.is_empty() {
        grids = vec![64, 128];
    }
    println!(
        "grid synthesis, ms (rayon threads: {})",
        rayon::current_num_threads()
    );
    println!(
        "{:>5} {:>7} {:>6} {:>9} {:>9}",
        "n", "count", "sigma", "upsample", "ms"
    );
    for &n in &grids {
        let dx = 1.0 / n as Real;
        for sigma_cells in [2.0, 3.0, 4.0] {
            for count in [100, 1000, 10000] {
                let p = particles(count, sigma_cells * dx, 1.0, 1);
                let mut g = MacGrid::new([n; 3], dx, Vec3::zeros(), [false; 3]);
                let ms = median_ms(|| {
                    synthesize(&p, &mut g, 1).expect("synthesis");
                });
                println!("{n:>5} {count:>7} {sigma_cells:>6} {:>9} {ms:>9.1}", 1);
            }
        }
    }
    let side = 47usize;
    let spacing = 1.0 / side as Real;
    let x: Vec<Vec3> = (0..side * side * side)
        .map(|i| {
            let idx = [i / (side * side), (i / side) % side, i % side];
            Vec3::from_fn(|a, _| (idx[a] as Real + 0.5) * spacing)
        })
        .collect();
    let mut pts = Points {
        v: vec![Vec3::zeros(); x.len()],
        x,
    };
    for count in [100, 1000] {
        let p = particles(count, 3.0 * spacing, 1.0, 2);
        let ms = median_ms(|| {
            synthesize(&p, &mut pts, 1).expect("synthesis");
        });
        println!(
            "points {} particles {count} sigma 3 spacings: {ms:.1} ms",
            pts.x.len()
        );
    }
}
