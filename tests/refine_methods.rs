//! The refinements through their public trait: a vortex that lost vorticity gets it back in its
//! own sense and by no more than it lost; zero parameters leave DFSPH and IISPH unchanged; bad
//! parameters give clear errors.

use eddy::pipeline::sph_solver;
use eddy::refine::{self, StepContext};
use eddy::scene::{self, Scene};
use eddy::sph::operators::{volumes, Operators, WallField};
use eddy::sph::SphSolver;
use eddy::{Real, Vec3};
use std::path::Path;

const SPACING: Real = 0.02;

fn scene_text(refinement: &str) -> String {
    format!(
        "name = \"m\"\nseed = 5\n[domain]\nmin = [-0.1, -0.1, -0.1]\nmax = [0.5, 0.5, 0.5]\n\
         [time]\nsteps = 1\n[fluid]\nspacing = {SPACING}\n[[fluid.blocks]]\n\
         min = [0.0, 0.0, 0.0]\nmax = [0.32, 0.32, 0.32]\n[output]\nvtk = false\nmetrics = []\n\
         [refinement]\n{refinement}\n"
    )
}

fn solver(scene: &Scene) -> SphSolver {
    sph_solver(scene).expect("solver builds")
}

/// A Gaussian vortex about the z axis through the block's centre: v = (w0 / 2) exp(-r^2 /
/// sigma^2) e_z x (x - c), whose vorticity at the axis is w0 e_z.
fn vortex(x: &[Vec3], w0: Real) -> Vec<Vec3> {
    let c = Vec3::new(0.16, 0.16, 0.16);
    let sigma = 3.0 * SPACING;
    x.iter()
        .map(|x| {
            let d = Vec3::new(x.x - c.x, x.y - c.y, 0.0);
            0.5 * w0 * (-d.norm_squared() / (sigma * sigma)).exp() * Vec3::z().cross(&d)
        })
        .collect()
}

/// Particles within one spacing of the vortex axis and one support inside the block.
fn core(x: &[Vec3]) -> Vec<usize> {
    (0..x.len())
        .filter(|&i| {
            let (dx, dy) = (x[i].x - 0.16, x[i].y - 0.16);
            dx.hypot(dy) < 1.01 * SPACING && (0.05..0.27).contains(&x[i].z)
        })
        .collect()
}

/// Rankine, VRSPH and MCVSPH: the vortex is seen at full strength w0 at step n, then at half
/// strength (it lost w0 / 2 on its axis). The refinement's velocity change has a curl along
/// +z on the axis (the lost vorticity comes back, not reversed) no larger than the loss (not
/// doubled).
#[test]
fn a_vortex_that_lost_vorticity_gets_it_back() {
    let w0 = 4.0;
    for method in [
        "method = \"rankine\"\nbeta = 1.0",
        "method = \"vrsph\"\nalpha = 1.0",
        "method = \"mcvsph\"\nsample_fraction = 1.0\nvolume_coefficient = 0.9",
    ] {
        let scene = scene::parse_str(&scene_text(method), Path::new("m.toml"), &[]).expect("ok");
        let s = solver(&scene);
        let vol = volumes(s.fluid.mass, &s.fluid.density);
        let ops = Operators {
            nb: s.neighborhood(),
            volume: &vol,
            walls: false,
        };
        // nu dt large enough that the Rankine core (r_c = 0.5 spacing) matters.
        let ctx = StepContext {
            ops,
            dt: 1e-3,
            nu: (0.5 * SPACING).powi(2) / (4.0 * refine::rankine::OSEEN * 1e-3),
            spacing: SPACING,
        };
        let mut r = scene
            .refinement
            .build(s.fluid.len(), scene.seed)
            .expect("method");
        let n = s.fluid.len();
        let mut accel = vec![Vec3::zeros(); n];
        // Step n starts at the full vortex and ends (after the pressure solve) at half strength;
        // step n + 1 starts there. Each method acts at its own point.
        let mut v = vortex(&s.fluid.x, w0);
        r.before_advection(&ctx, &mut v, &mut accel);
        let weak = vortex(&s.fluid.x, 0.5 * w0);
        let mut v = weak.clone();
        r.after_pressure(&ctx, &mut v);
        r.before_advection(&ctx, &mut v, &mut accel);
        let dv: Vec<Vec3> = v.iter().zip(&weak).map(|(a, b)| a - b).collect();
        let back = ops.curl(&dv, WallField::Zero);
        let lost: Vec<Vec3> = ops
            .curl(&vortex(&s.fluid.x, w0), WallField::Velocity)
            .iter()
            .zip(ops.curl(&weak, WallField::Velocity))
            .map(|(a, b)| a - b)
            .collect();
        let axis = core(&s.fluid.x);
        assert!(!axis.is_empty());
        for &i in &axis {
            let ratio = back[i].z / lost[i].z;
            assert!(
                ratio > 0.0 && ratio <= 1.0,
                "{method}: restored {ratio} of the loss"
            );
        }
    }
}

fn load_error(refinement: &str) -> String {
    match scene::parse_str(&scene_text(refinement), Path::new("bad.toml"), &[]) {
        Ok(s) => panic!("accepted {:?}", s.refinement),
        Err(e) => e.to_string(),
    }
}

/// Out-of-range, misplaced, unknown and malformed refinement parameters give errors that name
/// the file, the key, the value and what is allowed.
#[test]
fn bad_refinement_parameters_give_clear_errors() {
    let cases: [(&str, &[&str]); 9] = [
        (
            "method = \"rankine\"\nbeta = 1.5",
            &["bad.toml", "refinement.beta", "1.5", "[0, 1]", "rankine"],
        ),
        (
            "method = \"vrsph\"\nalpha = -0.1",
            &["bad.toml", "refinement.alpha", "-0.1", "[0, 2]"],
        ),
        (
            "method = \"mcvsph\"\nsample_fraction = 0.0",
            &["refinement.sample_fraction", "(0, 1]"],
        ),
        (
            "method = \"mcvsph\"\nvolume_coefficient = 1.0",
            &["refinement.volume_coefficient", "[0, 1)"],
        ),
        (
            "method = \"mcvsph\"\ntheta = 1.0",
            &["refinement.theta", "[0, 1)"],
        ),
        (
            "method = \"micropolar\"\nmicro_inertia = 0.0",
            &["refinement.micro_inertia", "> 0"],
        ),
        (
            "method = \"confinement\"\nepsilon = nan",
            &["refinement.epsilon", "NaN", ">= 0"],
        ),
        (
            "method = \"rankine\"\nalpha = 1.0",
            &[
                "bad.toml",
                "refinement",
                "unknown key `alpha`",
                "`beta` or `walls`",
            ],
        ),
        ("method = \"vortex\"", &["bad.toml", "refinement", "vortex"]),
    ];
    for (text, needles) in cases {
        let e = load_error(text);
        for n in needles {
            assert!(e.contains(n), "{text:?}: {e:?} lacks {n:?}");
        }
    }
    let e = load_error("method = \"vrsph\"\nalpha = \"high\"");
    assert!(e.contains("refinement") && e.contains("line"), "{e}");
    // Defaults are the papers' values, and validation accepts them; the resolved scene
    // writes them back.
    let file = Path::new("ok.toml");
    for (text, expected) in [
        (
            "method = \"rankine\"",
            "method = \"rankine\"\nbeta = 1.0\nwalls = false\n".to_owned(),
        ),
        (
            "method = \"mcvsph\"",
            format!(
                "method = \"mcvsph\"\nsample_fraction = 0.01\nvolume_coefficient = 0.05\n\
                 theta = {:?}\nwalls = false\n",
                eddy::refine::biot_savart::DEFAULT_THETA
            ),
        ),
    ] {
        let s = scene::parse_str(&scene_text(text), file, &[]).expect("valid");
        assert_eq!(toml::to_string(&s.refinement).expect("writes"), expected);
        s.refinement.validate().expect("defaults are valid");
    }
}
