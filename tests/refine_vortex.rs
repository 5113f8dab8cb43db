//! The sign of VRSPH's refinement on a single decaying vortex (Liu et al. Sec. 4.1, Fig. 8):
//! a Gaussian vortex in a closed box of still fluid without gravity loses kinetic energy to
//! viscosity and to the solver's numerical dissipation; VRSPH gives back vorticity the step
//! lost, so its kinetic energy must decay more slowly than DFSPH's.

use eddy::metrics;
use eddy::pipeline::sph_solver;
use eddy::scene;
use eddy::{Real, Vec3};
use std::path::Path;

const SPACING: Real = 0.02;
const SIDE: Real = 0.32;

/// The kinetic energy at the start and after `steps` steps of a Gaussian (Lamb–Oseen) vortex
/// about the box's vertical axis, core radius 3 spacings, peak speed about 0.3 m/s.
fn decay(refinement: &str, nu: Real, steps: usize) -> (Real, Real) {
    let text = format!(
        "name = \"vortex\"\ngravity = [0.0, 0.0, 0.0]\n[domain]\nmin = [-0.1, -0.1, -0.1]\n\
         max = [0.45, 0.45, 0.45]\n[time]\nsteps = {steps}\ndt = 0.002\n[fluid]\n\
         spacing = {SPACING}\n[[fluid.blocks]]\nmin = [0.0, 0.0, 0.0]\n\
         max = [{SIDE}, {SIDE}, {SIDE}]\n[container]\n\
         shape = {{ type = \"box\", half_extents = [0.2, 0.2, 0.2] }}\n\
         position = [0.16, 0.16, 0.16]\n[viscosity]\nkinematic = {nu}\n[output]\nvtk = false\n\
         metrics = []\n[refinement]\n{refinement}\n"
    );
    let scene = scene::parse_str(&text, Path::new("vortex.toml"), &[]).expect("scene");
    let mut s = sph_solver(&scene).expect("solver builds");
    let centre = Vec3::new(0.5 * SIDE, 0.5 * SIDE, 0.0);
    let core = 3.0 * SPACING;
    let circulation = 0.3 * 2.0 * std::f64::consts::PI * core / 0.638;
    for (x, v) in s.fluid.x.iter().zip(s.fluid.v.iter_mut()) {
        let d = x - centre;
        let r2 = d.x * d.x + d.y * d.y;
        *v = if r2 > 0.0 {
            let speed_over_r = circulation / (2.0 * std::f64::consts::PI * r2)
                * (1.0 - (-r2 / (core * core)).exp());
            speed_over_r * Vec3::new(-d.y, d.x, 0.0)
        } else {
            Vec3::zeros()
        };
    }
    let initial = metrics::kinetic_energy(s.fluid.mass, &s.fluid.v);
    for _ in 0..steps {
        s.step(scene.time.end).expect("stable");
    }
    (initial, metrics::kinetic_energy(s.fluid.mass, &s.fluid.v))
}

/// At the dam break's viscosity (nu = 0.01 m^2/s), over 50 steps (0.1 s, about a quarter of
/// the core's turnover), DFSPH loses more than a tenth of the vortex's kinetic energy; VRSPH
/// (alpha = 1) must lose at most 80 % of what DFSPH loses, and not end above the initial
/// energy (it restores, it does not create).
#[test]
fn vrsph_slows_the_decay_of_a_single_vortex() {
    let steps = 50;
    let nu = 0.01;
    let (initial, dfsph) = decay("method = \"none\"", nu, steps);
    let (_, vrsph) = decay("method = \"vrsph\"\nalpha = 1.0", nu, steps);
    let lost = |e: Real| initial - e;
    assert!(lost(dfsph) > 0.1 * initial, "DFSPH: {initial} -> {dfsph}");
    assert!(
        lost(vrsph) < 0.8 * lost(dfsph),
        "VRSPH {vrsph} J vs DFSPH {dfsph} J from {initial} J"
    );
    assert!(
        vrsph < initial,
        "VRSPH created energy: {initial} -> {vrsph}"
    );
}
