//! Obstacle files: the shipped examples load, overrides apply, bad values and obstacles the grid
//! cannot see are refused with errors that name the key.

use std::path::Path;

use eddy::abl::MotionKind;
use eddy::Vec3;
use eddy_precompute::solve::{solve, Surface};
use eddy_precompute::spec::PerAxis;
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
    assert_eq!(
        (spec.grid.resolution, spec.sampling.rotation),
        (PerAxis::Same(24), [4, 6])
    );
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

fn parse(text: &str, overrides: &[&str]) -> ObstacleSpec {
    let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    ObstacleSpec::parse(text, Path::new("box.toml"), &o).expect("valid obstacle file")
}

/// Box domains: per-axis multiples of a rod's extent make a box of cubic cells whose sides
/// cover at least those multiples, with far fewer cells than the cube; the same multiple on
/// every axis of a sphere is the cube, and computes the same omega_pre bit for bit.
#[test]
fn box_domains_follow_the_object_per_axis() {
    let rod = "name = \"rod\"\nshape = { type = \"box\", half_extents = [1.0, 0.1, 0.1] }\n";
    let cube = parse(rod, &["grid.resolution=32"]).grid_box().expect("box");
    assert_eq!(cube.cells, [32; 3]);
    // x: 2 x 2 x 1 m = 4 m in 32 cells of 0.125 m; y, z: 2 x 6 x 0.1 m = 1.2 m, rounded to
    // 10 cells (1.25 m).
    let b = parse(rod, &["grid.domain=[2.0, 6.0, 6.0]", "grid.resolution=32"])
        .grid_box()
        .expect("box");
    assert_eq!(b.cells, [32, 10, 10]);
    assert!((b.dx - 0.125).abs() < 1e-15, "{}", b.dx);
    assert!((b.half[0] - 2.0).abs() < 1e-15 && (b.half[1] - 0.625).abs() < 1e-12);
    // Per-axis counts: the cell is the largest side over its count, max(4/40, 1.2/8) = 0.15 m.
    let b = parse(
        rod,
        &["grid.domain=[2.0, 6.0, 6.0]", "grid.resolution=[40, 8, 8]"],
    )
    .grid_box()
    .expect("box");
    assert_eq!(b.cells, [40, 8, 8]);
    assert!((b.dx - 0.15).abs() < 1e-15, "{}", b.dx);
    assert!(b.half[0] * 2.0 >= 4.0 && b.half[1] * 2.0 >= 1.2 - 1e-12);
    assert!(err(rod, &["grid.domain=[2.0, 1.0, 6.0]"]).contains("grid.domain"));
    assert!(err(rod, &["grid.resolution=[32, 4, 8]"]).contains("grid.resolution"));
    let two = err(rod, &["grid.domain=[4.0, 3.0]"]);
    assert!(
        two.contains("grid.domain") && two.contains("[x, y, z]"),
        "{two}"
    );

    let sphere = "name = \"s\"\nshape = { type = \"sphere\", radius = 0.5 }\n";
    let steps = [
        "grid.resolution=12",
        "grid.stabilise_steps=3",
        "grid.average_steps=2",
    ];
    let a = parse(sphere, &steps);
    let mut each = steps.to_vec();
    each.push("grid.domain=[4.0, 4.0, 4.0]");
    let b = parse(sphere, &each);
    assert_eq!(a.grid_box().expect("box"), b.grid_box().expect("box"));
    let surface = Surface::of(&a).expect("surface");
    let d = Vec3::new(0.3, -0.2, 0.9).normalize();
    for kind in MotionKind::ALL {
        assert_eq!(
            solve(&a, &surface, kind, &d).expect("solves"),
            solve(&b, &surface, kind, &d).expect("solves")
        );
    }
}
