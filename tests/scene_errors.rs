//! Scene loading: a valid scene loads, the resolved scene round-trips, and every kind of bad input
//! gives an error that names the file, the key, the value and what is allowed.

use std::path::{Path, PathBuf};

use eddy::scene::{apply_override, load, parse_str, PressureSolverKind, Scene, SceneError, Shape};
use proptest::prelude::*;

/// A small valid scene; line numbers below refer to it.
const MINIMAL: &str = r#"name = "tiny"

[domain]
min = [0, 0, 0]
max = [1, 1, 1]

[time]
end = 1.0

[fluid]
spacing = 0.05

[[fluid.blocks]]
min = [0, 0, 0]
max = [0.5, 0.5, 0.5]
"#;

fn origin() -> &'static Path {
    Path::new("scenes/tiny.toml")
}

fn parse(text: &str) -> Result<Scene, SceneError> {
    parse_str(text, origin(), &[])
}

fn parse_with(text: &str, overrides: &[&str]) -> Result<Scene, SceneError> {
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    parse_str(text, origin(), &overrides)
}

/// The error's message, which must name the scene file.
fn message(result: Result<Scene, SceneError>) -> String {
    match result {
        Ok(scene) => panic!("expected an error, got {scene:?}"),
        Err(e) => e.to_string(),
    }
}

fn assert_contains(message: &str, parts: &[&str]) {
    for part in parts {
        assert!(
            message.contains(part),
            "message {message:?} should contain {part:?}"
        );
    }
}

#[test]
fn minimal_scene_parses_with_defaults() {
    let scene = parse(MINIMAL).expect("minimal scene");
    assert_eq!(scene.name, "tiny");
    assert_eq!(scene.time.end, Some(1.0));
    assert_eq!(scene.time.steps, None);
    assert_eq!(scene.time.cfl, 0.4);
    assert_eq!(scene.gravity, [0.0, -9.81, 0.0]);
    let fluid = scene.fluid.as_ref().expect("fluid");
    assert_eq!(fluid.density, 1000.0);
    assert_eq!(fluid.blocks.len(), 1);
    assert_eq!(scene.pressure.solver, PressureSolverKind::Dfsph);
}

/// A scene that uses every part of the schema, with a mesh file in a temporary folder.
fn rich_scene(dir: &Path) -> String {
    std::fs::create_dir_all(dir.join("meshes")).expect("mesh folder");
    std::fs::write(dir.join("meshes/tank.obj"), "v 0 0 0\n").expect("mesh file");
    r#"name = "rich"
seed = 7
gravity = [0, -9.81, 0.5]

[domain]
min = [-1, 0, -1]
max = [2, 1.5, 1]

[time]
steps = 200
cfl = 0.3
dt = 0.001

[fluid]
spacing = 0.02
density = 998.2

[[fluid.blocks]]
min = [0, 0, 0]
max = [0.5, 0.4, 0.3]
velocity = [0.1, 0, 0]

[[fluid.blocks]]
min = [1, 0, 0]
max = [1.2, 0.2, 0.3]

[container]
name = "tank"
shape = { type = "mesh", path = "meshes/tank.obj", scale = 2.0 }

[[obstacles]]
name = "ball"
shape = { type = "sphere", radius = 0.1 }
position = [0.5, 0.5, 0]

[obstacles.motion]
keyframes = [
  { t = 0, position = [0.5, 0.5, 0] },
  { t = 1.5, position = [1, 0.5, 0], rotation = [0, 1, 0] },
]

[[obstacles]]
shape = { type = "capsule", radius = 0.05, half_height = 0.2 }
motion = { linear = [0, 0, 1], angular = [0, 1, 0] }

[[obstacles]]
shape = { type = "box", half_extents = [0.1, 0.2, 0.3] }

[pressure]
solver = "iisph"
density_tolerance = 0.001
min_iterations = 3
max_iterations = 500

[viscosity]
kinematic = 1e-6
xsph = 0.05

[[probes]]
type = "front"
name = "front_x"
axis = "x"
origin = 0.5

[[probes]]
type = "point"
name = "p1"
position = [1, 0.1, 0]

[output]
dir = "out/rich"
interval = 0.02
hdf5 = true
metrics = ["max_speed", "kinetic_energy"]
"#
    .to_owned()
}

#[test]
fn rich_scene_loads_and_resolves_mesh_path() {
    let dir = tempfile::tempdir().expect("temp dir");
    let file = dir.path().join("rich.toml");
    std::fs::write(&file, rich_scene(dir.path())).expect("scene file");
    let scene = load(&file, &[]).expect("rich scene");
    let Some(Shape::Mesh { path, scale }) = scene.container.as_ref().map(|c| &c.shape) else {
        panic!("container should be a mesh");
    };
    assert!(path.is_absolute(), "{path:?} should be absolute");
    assert_eq!(path, &dir.path().join("meshes/tank.obj"));
    assert_eq!(*scale, 2.0);
    assert_eq!(scene.obstacles.len(), 3);
    assert_eq!(scene.obstacles[0].motion.keyframes.len(), 2);
    assert_eq!(scene.pressure.solver, PressureSolverKind::Iisph);
}

#[test]
fn resolved_scene_round_trips() {
    let dir = tempfile::tempdir().expect("temp dir");
    let file = dir.path().join("rich.toml");
    std::fs::write(&file, rich_scene(dir.path())).expect("scene file");
    for scene in [
        load(&file, &[]).expect("rich scene"),
        parse(MINIMAL).expect("minimal scene"),
    ] {
        let text = scene.to_toml();
        // Written elsewhere, the absolute mesh path must still resolve.
        let again = parse_str(&text, Path::new("/elsewhere/resolved.toml"), &[])
            .unwrap_or_else(|e| panic!("{e}\n---\n{text}"));
        assert_eq!(again, scene, "\n---\n{text}");
    }
}

#[test]
fn unreadable_file_names_the_path() {
    let missing = PathBuf::from("/definitely/not/here/scene.toml");
    let e = load(&missing, &[]).expect_err("missing file");
    assert!(matches!(e, SceneError::Io { .. }));
    assert_contains(
        &e.to_string(),
        &["/definitely/not/here/scene.toml", "could not read"],
    );
}

#[test]
fn syntax_error_gives_line_and_column() {
    let text = "name = \"tiny\"\n[domain]\nmin = [0, 0\nmax = [1, 1, 1]\n";
    let e = parse(text).expect_err("syntax error");
    let SceneError::Syntax { line, .. } = &e else {
        panic!("expected a syntax error, got {e:?}");
    };
    assert!(*line == 3 || *line == 4, "line {line}");
    let text = "name = \"tiny\"\n\nseed = = 3\n";
    let e = parse(text).expect_err("syntax error");
    let SceneError::Syntax { line, column, .. } = &e else {
        panic!("expected a syntax error, got {e:?}");
    };
    assert_eq!((*line, *column), (3, 8));
    assert_contains(&e.to_string(), &["tiny.toml", "line 3, column 8", "syntax"]);
}

#[test]
fn unknown_top_level_key() {
    let text = MINIMAL.replace("name = \"tiny\"", "name = \"tiny\"\ncolour = \"red\"");
    let m = message(parse(&text));
    assert_contains(
        &m,
        &[
            "tiny.toml",
            "line 2, column 1",
            "`colour`",
            "unknown key",
            "`seed`",
        ],
    );
}

#[test]
fn unknown_nested_key() {
    let text = format!("{MINIMAL}colour = \"red\"\n");
    let m = message(parse(&text));
    assert_contains(
        &m,
        &[
            "tiny.toml",
            "line 16",
            "`fluid.blocks[0].colour`",
            "unknown key `colour`",
            "`velocity`",
        ],
    );
}

#[test]
fn unknown_key_in_inline_shape() {
    let text = format!(
        "{MINIMAL}\n[[obstacles]]\nshape = {{ type = \"sphere\", radius = 0.1, colour = 1 }}\n"
    );
    let m = message(parse(&text));
    assert_contains(
        &m,
        &[
            "tiny.toml",
            "`obstacles[0].shape.colour`",
            "unknown key `colour`",
        ],
    );
}

#[test]
fn unknown_variant_names_the_key() {
    let text = format!("{MINIMAL}\n[[obstacles]]\nshape = {{ type = \"ball\", radius = 0.1 }}\n");
    let m = message(parse(&text));
    assert_contains(&m, &["`obstacles[0].shape.type`", "`ball`", "`sphere`"]);
}

#[test]
fn missing_key_names_its_table() {
    let text = MINIMAL.replace("spacing = 0.05", "density = 1000");
    let m = message(parse(&text));
    assert_contains(&m, &["tiny.toml", "`fluid`", "missing key `spacing`"]);
    let text = MINIMAL.replace("name = \"tiny\"", "");
    let m = message(parse(&text));
    assert_contains(&m, &["tiny.toml", "top level", "missing key `name`"]);
}

#[test]
fn wrong_type() {
    let text = MINIMAL.replace("spacing = 0.05", "spacing = \"fine\"");
    let m = message(parse(&text));
    assert_contains(
        &m,
        &[
            "tiny.toml",
            "line 11",
            "`fluid.spacing`",
            "invalid type",
            "\"fine\"",
        ],
    );
    let text = MINIMAL.replace("max = [1, 1, 1]", "max = [1, 1]");
    let m = message(parse(&text));
    assert_contains(&m, &["`domain.max`", "length 2"]);
}

#[test]
fn out_of_range_values() {
    let text = MINIMAL.replace("end = 1.0", "end = 1.0\ncfl = 1.5");
    let m = message(parse(&text));
    assert_contains(&m, &["tiny.toml", "`time.cfl`", "1.5", "(0, 1]"]);

    let text = MINIMAL.replace("spacing = 0.05", "spacing = -0.1");
    let m = message(parse(&text));
    assert_contains(&m, &["tiny.toml", "`fluid.spacing`", "-0.1", "> 0"]);

    let text = MINIMAL.replace("spacing = 0.05", "spacing = 0.3");
    let m = message(parse(&text));
    assert_contains(&m, &["`fluid.spacing`", "0.3", "<= 0.25", "quarter"]);

    let text = MINIMAL.replace("max = [0.5, 0.5, 0.5]", "max = [0.5, 1.5, 0.5]");
    let m = message(parse(&text));
    assert_contains(&m, &["`fluid.blocks[0].max[1]`", "1.5", "[0, 1]", "domain"]);

    let text = MINIMAL.replace("end = 1.0", "end = nan");
    let m = message(parse(&text));
    assert_contains(&m, &["`time.end`", "NaN", "finite"]);

    let text = MINIMAL.replace("max = [1, 1, 1]", "max = [1, 0, 1]");
    let m = message(parse(&text));
    assert_contains(&m, &["`domain.max[1]`", "> 0", "`domain.min[1]`"]);

    let text = format!("{MINIMAL}[pressure]\nmin_iterations = 0\n");
    let m = message(parse(&text));
    assert_contains(&m, &["`pressure.min_iterations`", "= 0", "[1, 100]"]);

    let m = message(parse_with(
        MINIMAL,
        &[
            "pressure.max_iterations=50",
            "pressure.divergence_min_iterations=51",
        ],
    ));
    assert_contains(
        &m,
        &["`pressure.divergence_min_iterations`", "= 51", "[1, 50]"],
    );

    let m = message(parse_with(
        MINIMAL,
        &["pressure.solver=iisph", "pressure.signed=true"],
    ));
    assert_contains(&m, &["`pressure.signed`", "true", "iisph", "DFSPH"]);

    let text = format!("{MINIMAL}[[probes]]\ntype = \"front\"\nname = \"a b\"\naxis = \"x\"\n");
    let m = message(parse(&text));
    assert_contains(&m, &["`probes[0].name`", "\"a b\""]);

    let text = format!("{MINIMAL}[output]\nmetrics = [\"max_speed\", \"max_speed\"]\n");
    let m = message(parse(&text));
    assert_contains(&m, &["`output.metrics[1]`", "max_speed"]);
}

/// `output.metrics` selects columns on every kind of scene: a name the scene's solvers do not
/// offer is refused with the names they do (a grid's for a grid scene, an SPH fluid's for a
/// fluid), and one either offers is taken.
#[test]
fn a_metric_the_scene_does_not_offer_is_refused_with_those_it_does() {
    let text = format!("{MINIMAL}[output]\nmetrics = [\"kinetic_energy\", \"max_divergence\"]\n");
    let m = message(parse(&text));
    assert_contains(
        &m,
        &[
            "`output.metrics[1]`",
            "max_divergence",
            "an SPH fluid offers",
            "density_error_avg",
        ],
    );
    assert!(!m.contains("a grid offers"), "{m}");
    let grid = "name = \"g\"\n[domain]\nmin = [0, 0, 0]\nmax = [1, 1, 1]\n[time]\nsteps = 1\n\
                [grid]\nresolution = [8, 8, 8]\n";
    let m = message(parse(&format!(
        "{grid}[output]\nmetrics = [\"max_speed\"]\n"
    )));
    assert_contains(
        &m,
        &[
            "`output.metrics[0]`",
            "max_speed",
            "a grid offers",
            "cfl",
            "enstrophy",
        ],
    );
    let scene = parse(&format!(
        "{grid}[output]\nmetrics = [\"enstrophy\", \"cfl\"]\n"
    ))
    .expect("a grid's metrics");
    assert_eq!(
        scene.output.metrics,
        Some(vec![
            eddy::metrics::Metric::Enstrophy,
            eddy::metrics::Metric::Cfl
        ])
    );
}

#[test]
fn keyframes_must_increase() {
    let text = format!(
        "{MINIMAL}[[obstacles]]\nshape = {{ type = \"sphere\", radius = 0.1 }}\n\
         motion = {{ keyframes = [{{ t = 1, position = [0, 0, 0] }}, \
         {{ t = 1, position = [0, 0, 0] }}] }}\n"
    );
    let m = message(parse(&text));
    assert_contains(
        &m,
        &["`obstacles[0].motion.keyframes[1].t`", "> 1", "increasing"],
    );
}

#[test]
fn end_or_steps_required() {
    let text = MINIMAL.replace("end = 1.0", "cfl = 0.5");
    let m = message(parse(&text));
    assert_contains(&m, &["tiny.toml", "time.end", "time.steps", "at least one"]);
    // Both: the run ends at whichever comes first (a resolved scene of a `--steps` run).
    let text = MINIMAL.replace("end = 1.0", "end = 1.0\nsteps = 10");
    let s = parse(&text).expect("end and steps together");
    assert_eq!((s.time.end, s.time.steps), (Some(1.0), Some(10)));
    let m = message(parse(&MINIMAL.replace("end = 1.0", "end = 1.0\nsteps = 0")));
    assert_contains(&m, &["time.steps", ">= 1"]);
}

#[test]
fn missing_mesh_file() {
    let dir = tempfile::tempdir().expect("temp dir");
    let file = dir.path().join("scene.toml");
    let text =
        format!("{MINIMAL}[container]\nshape = {{ type = \"mesh\", path = \"nope.obj\" }}\n");
    std::fs::write(&file, text).expect("scene file");
    let e = load(&file, &[]).expect_err("missing mesh");
    let SceneError::MissingMesh { path, .. } = &e else {
        panic!("expected a missing mesh, got {e:?}");
    };
    assert_eq!(path, &dir.path().join("nope.obj"));
    assert_contains(
        &e.to_string(),
        &[
            "scene.toml",
            "`container.shape.path`",
            "nope.obj",
            "does not exist",
        ],
    );
}

#[test]
fn override_changes_values() {
    let scene = parse_with(MINIMAL, &["time.end=2"]).expect("override");
    assert_eq!(scene.time.end, Some(2.0));

    let scene = parse_with(MINIMAL, &["fluid.blocks.0.max=[1,1,1]"]).expect("override");
    assert_eq!(scene.fluid.expect("fluid").blocks[0].max, [1.0, 1.0, 1.0]);

    let scene = parse_with(MINIMAL, &["pressure.solver=iisph"]).expect("bare string");
    assert_eq!(scene.pressure.solver, PressureSolverKind::Iisph);

    let scene = parse_with(
        MINIMAL,
        &["obstacles=[{ shape = { type = \"sphere\", radius = 0.1 } }]"],
    )
    .expect("array override");
    assert_eq!(scene.obstacles[0].shape, Shape::Sphere { radius: 0.1 });

    // Later overrides win, and steps replaces end.
    let scene =
        parse_with(MINIMAL, &["time.end=3", "time.end=4", "name=\"renamed\""]).expect("overrides");
    assert_eq!(scene.time.end, Some(4.0));
    assert_eq!(scene.name, "renamed");
}

#[test]
fn override_errors() {
    let m = message(parse_with(MINIMAL, &["fluid.blocks.3.max=[1,1,1]"]));
    assert_contains(
        &m,
        &[
            "fluid.blocks.3.max",
            "index 3",
            "`fluid.blocks`",
            "length 1",
        ],
    );

    let m = message(parse_with(MINIMAL, &["obstacles.0.position=[1,2,3]"]));
    assert_contains(&m, &["index 0", "`obstacles`", "length 0"]);

    let m = message(parse_with(MINIMAL, &["time.cfl"]));
    assert_contains(&m, &["time.cfl", "dotted.key=value"]);

    let m = message(parse_with(MINIMAL, &["time..cfl=1"]));
    assert_contains(&m, &["empty segment"]);

    let m = message(parse_with(MINIMAL, &["fluid.blocks.0.max=[1, 1"]));
    assert_contains(&m, &["not a valid TOML value"]);

    let m = message(parse_with(MINIMAL, &["time.end.x=1"]));
    assert_contains(&m, &["`time.end`", "float"]);

    // An override of a key the schema lacks is an unknown-key error like in the file, told
    // against the override that wrote it (the file only says on what).
    let m = message(parse_with(MINIMAL, &["time.finish=2"]));
    assert_contains(
        &m,
        &[
            "--set \"time.finish=2\" on ",
            "tiny.toml",
            "`time.finish`",
            "unknown key `finish`",
        ],
    );
    // A value out of range: the last override of the key is the one named; a key that no
    // override wrote is told against the file alone.
    let m = message(parse_with(
        MINIMAL,
        &["time.cfl=0.5", "time.cfl=2", "time.end=3"],
    ));
    assert!(m.starts_with("--set \"time.cfl=2\" on "), "{m}");
    assert_contains(&m, &["invalid `time.cfl` = 2"]);
    let m = message(parse_with(
        MINIMAL,
        &["obstacles=[{ shape = { type = \"sphere\", radius = -1.0 } }]"],
    ));
    assert!(
        m.starts_with("--set \"obstacles="),
        "a table holding the key: {m}"
    );
    let m = message(parse_with(
        MINIMAL,
        &["time.end=3", "domain.max=[1.0, 1.0, -5.0]"],
    ));
    assert!(!m.contains("time.end=3"), "{m}");

    let m = message(parse_with(MINIMAL, &["fluid.blocks.0.colour=2"]));
    assert_contains(&m, &["`fluid.blocks[0].colour`", "unknown key"]);

    // An override's range error is reported like the file's own.
    let m = message(parse_with(MINIMAL, &["time.cfl=1.5"]));
    assert_contains(&m, &["tiny.toml", "`time.cfl`", "1.5", "(0, 1]"]);

    // A wrong type after an override names the key, though not a line.
    let m = message(parse_with(MINIMAL, &["time.cfl=fast"]));
    assert_contains(&m, &["`time.cfl`", "invalid type", "\"fast\""]);
}

#[test]
fn apply_override_on_table() {
    let mut table = toml::Table::new();
    apply_override(&mut table, "a.b.c=1").expect("creates tables");
    apply_override(&mut table, "list=[1, 2]").expect("array");
    apply_override(&mut table, "list.1 = \"x\"").expect("index");
    assert_eq!(table["a"]["b"]["c"].as_integer(), Some(1));
    assert_eq!(table["list"][1].as_str(), Some("x"));
    let e = apply_override(&mut table, "list.2=3").expect_err("past end");
    assert_contains(&e.to_string(), &["index 2", "`list`", "length 2"]);
    let e = apply_override(&mut table, "list.x=3").expect_err("not an index");
    assert_contains(&e.to_string(), &["`list` is an array", "`x`"]);
}

proptest! {
    #[test]
    fn cfl_override_gives_value_or_range_error(cfl in proptest::num::f64::NORMAL | proptest::num::f64::ZERO | proptest::num::f64::SUBNORMAL) {
        // Debug keeps the exponent, so the text is a TOML float and not a bare string.
        let assignment = format!("time.cfl={cfl:?}");
        match parse_with(MINIMAL, &[&assignment]) {
            Ok(scene) => {
                prop_assert_eq!(scene.time.cfl, cfl);
                prop_assert!(cfl > 0.0 && cfl <= 1.0);
            }
            Err(SceneError::Invalid { key, value, allowed, .. }) => {
                prop_assert_eq!(key, "time.cfl");
                prop_assert_eq!(value.parse::<f64>().ok(), Some(cfl));
                prop_assert!(allowed.contains("(0, 1]"));
                prop_assert!(!(cfl > 0.0 && cfl <= 1.0));
            }
            Err(e) => prop_assert!(false, "unexpected error {}", e),
        }
    }

    #[test]
    fn any_cfl_text_never_panics(text in "\\PC{0,12}") {
        let _ = parse_with(MINIMAL, &[&format!("time.cfl={text}")]);
    }
}

/// A `[[probes]]` entry is a table tagged by `type`, whose errors serde reports for the whole
/// array: the message still names the entry that is wrong, its key and its line.
#[test]
fn errors_inside_probes_point_at_the_entry_and_key() {
    let probes = |second: &str| {
        format!(
            "{MINIMAL}[[probes]]\ntype = \"front\"\nname = \"a\"\naxis = \"x\"\n\n[[probes]]\n{second}"
        )
    };
    // MINIMAL has 15 lines; the second entry's keys start on line 22.
    for (second, parts) in [
        (
            "type = \"point\"\nname = \"b\"\npositon = [0.5, 0.5, 0.5]\n",
            &["`probes[1].positon`", "line 24", "unknown key `positon`"][..],
        ),
        (
            "type = \"pont\"\nname = \"b\"\n",
            &["`probes[1].type`", "line 22", "unknown variant `pont`"][..],
        ),
        (
            "type = \"point\"\nname = \"b\"\nposition = [0.5, \"x\", 0.5]\n",
            &["`probes[1]`", "line 22", "invalid type"][..],
        ),
        (
            "type = \"point\"\nname = \"b\"\n",
            &["`probes[1]`", "missing key `position`"][..],
        ),
    ] {
        assert_contains(&message(parse(&probes(second))), parts);
    }
}

/// Issue 52's degenerate container: `refine_sloshing.toml` with the tank 4e-7 m tall (and a
/// viscosity of 10 and a domain 50 m deep) passed the memory estimate, then its boundary shell,
/// one column per 4e-7 m of the wall's offset, packed millions of samples into a few neighbour
/// cells. Every body of an SPH scene must now be a spacing thick; the refusal names the key
/// and comes at once, before anything is built.
#[test]
fn a_container_thinner_than_a_spacing_is_refused_at_once() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/refine_sloshing.toml");
    let started = std::time::Instant::now();
    let overrides: Vec<String> = [
        "container.shape.half_extents=[0.25, 2e-7, 0.05]",
        "viscosity.kinematic=10",
        "domain.min=[-0.05, -50.0, -0.05]",
    ]
    .map(String::from)
    .to_vec();
    let err = load(&path, &overrides).expect_err("a degenerate container");
    assert!(
        started.elapsed().as_secs_f64() < 1.0,
        "{:?}",
        started.elapsed()
    );
    assert_contains(
        &err.to_string(),
        &[
            "container.shape.half_extents[1]",
            "2e-7",
            "half the fluid spacing",
        ],
    );
    // An obstacle too, and each shape's own key: a ball of radius 1 mm at a 2 cm spacing.
    let text = format!(
        "{MINIMAL}\n[[obstacles]]\nshape = {{ type = \"sphere\", radius = 0.001 }}\n\
         position = [0.7, 0.7, 0.7]\n"
    );
    assert_contains(
        &message(parse(&text)),
        &["obstacles[0].shape.radius", "0.025"],
    );
    // A grid scene keeps its thin plates (the paper's whisk): no fluid spacing to hold them to.
    let plate = "name = \"plate\"\n[domain]\nmin = [0, 0, 0]\nmax = [1, 1, 1]\n[time]\nend = 1.0\n\
        [grid]\nresolution = [8, 8, 8]\n[[obstacles]]\n\
        shape = { type = \"box\", half_extents = [0.2, 0.2, 0.001] }\nposition = [0.5, 0.5, 0.5]\n";
    parse(plate).expect("a thin plate in a grid scene");
}

/// `output.compression` is a deflate level: 0 to 9.
#[test]
fn compression_is_a_deflate_level() {
    assert_eq!(parse(MINIMAL).expect("minimal").output.compression, 4);
    let msg = message(parse_with(MINIMAL, &["output.compression=10"]));
    assert_contains(&msg, &["output.compression", "10", "deflate level"]);
    assert_eq!(
        parse_with(MINIMAL, &["output.compression=0"])
            .expect("uncompressed")
            .output
            .compression,
        0
    );
}

/// Numbers in messages are written compactly: a domain of 3e300 m gives `3e300`, not 301 digits.
#[test]
fn huge_and_tiny_numbers_are_written_with_exponents() {
    let grid = r#"name = "huge"
[domain]
min = [0, 0, 0]
max = [3e300, 1, 1]
[time]
end = 1.0
[grid]
resolution = [64, 64, 64]
"#;
    let m = message(parse(grid));
    assert_contains(&m, &["grid.resolution[1]", "cell of 4.6875e298 m"]);
    assert!(
        m.split(|c: char| !c.is_ascii_digit())
            .all(|run| run.len() < 20),
        "a long run of digits: {m}"
    );
}
