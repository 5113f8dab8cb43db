//! Obstacle files: the shipped examples load, overrides apply, bad values and obstacles the grid
//! cannot see are refused with errors that name the key.

use std::path::Path;

use eddy::abl::MotionKind;
use eddy::Vec3;
use eddy_precompute::solve::{solve, Surface};
use eddy_precompute::ObstacleSpec;

fn err(text: &str, overrides: &[&str]) -> String {
    let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    format!(
        "{:#}",
        ObstacleSpec::parse(text, Path::new("bad.toml"), &o).expect_err("must be refused")
    )
}

#[test]
fn shipped_obstacles_load_and_overrides_apply() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("obstacles");
    for name in ["sphere", "box", "plate"] {
        let spec = ObstacleSpec::load(&dir.join(format!("{name}.toml")), &[]).expect(name);
        assert_eq!(spec.name, name);
        assert_eq!(spec.sampling.translation, [10, 20]);
    }
    let spec = ObstacleSpec::load(
        &dir.join("sphere.toml"),
        &[
            "grid.resolution=24".into(),
            "sampling.rotation=[4, 6]".into(),
        ],
    )
    .expect("overrides");
    assert_eq!((spec.grid.resolution, spec.sampling.rotation), (24, [4, 6]));
    // The fingerprint covers the settings: an override changes it, the geometry part stays.
    let base = ObstacleSpec::load(&dir.join("sphere.toml"), &[]).expect("loads");
    let (a, ga) = base.fingerprints().expect("fingerprints");
    let (b, gb) = spec.fingerprints().expect("fingerprints");
    assert_ne!(a, b);
    assert_eq!(ga, gb);
}

#[test]
fn bad_values_name_their_key() {
    let ok = "name = \"s\"\nshape = { type = \"sphere\", radius = 0.5 }\n";
    assert!(err(ok, &["grid.resolution=0"]).contains("grid.resolution"));
    assert!(err(ok, &["grid.domain=1.0"]).contains("grid.domain"));
    assert!(err(ok, &["grid.viscosity=-1.0"]).contains("grid.viscosity"));
    assert!(err(ok, &["layer.thickness=0.0"]).contains("layer.thickness"));
    assert!(err(ok, &["sampling.translation=[1, 20]"]).contains("sampling.translation"));
    assert!(err(ok, &["grid.bogus=1"]).contains("bogus"));
    assert!(err(
        "name = \"s\"\nshape = { type = \"sphere\", radius = -1.0 }\n",
        &[]
    )
    .contains("radius"));
}

/// A plate thinner than a cell covers no cell centre: the run says so instead of storing the
/// boundary layer of an obstacle the grid never saw.
#[test]
fn an_obstacle_the_grid_cannot_resolve_is_refused() {
    let text = "name = \"foil\"\nshape = { type = \"box\", half_extents = [0.5, 0.5, 0.01] }\n\
                [grid]\nresolution = 16\nstabilise_steps = 0\naverage_steps = 1\n";
    let spec = ObstacleSpec::parse(text, Path::new("foil.toml"), &[]).expect("valid file");
    let surface = Surface::of(&spec).expect("surface");
    let e = solve(&spec, &surface, MotionKind::Translation, &Vec3::x()).expect_err("unresolved");
    assert!(e.to_string().contains("covers no cell"), "{e}");
}
