//! The XDMF beside each `frames.h5` names exactly the datasets of every listed frame, with their
//! shapes: for a particle run, a grid run, a coupled run and frames with particle sets. VTK's
//! own XDMF reader opens the same files in `tests/vtk_readers.rs`.

mod common;

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use eddy::io::{Field, GridField, GridFrame, Hdf5Frames, Hdf5GridFrames, ParticleFrame};
use eddy::pipeline::{run, RunOptions};
use eddy::{Real, Vec3};
use ndarray::Array3;
use quick_xml::events::Event;

/// (file, dataset path, shape) of one array.
type Item = (String, String, Vec<usize>);

/// What an XDMF file references: its arrays, its frames' times, following XIncludes.
#[derive(Default, Debug)]
struct Described {
    items: BTreeSet<Item>,
    times: Vec<Real>,
}

fn describe(xmf: &Path, into: &mut Described) {
    let text = std::fs::read_to_string(xmf).unwrap_or_else(|e| panic!("{}: {e}", xmf.display()));
    let mut reader = quick_xml::Reader::from_str(&text);
    let mut dims: Option<Vec<usize>> = None;
    loop {
        match reader.read_event().expect("well-formed XML") {
            Event::Start(e) | Event::Empty(e) => {
                let attr = |key: &[u8]| {
                    e.attributes()
                        .map(|a| a.expect("attribute"))
                        .find(|a| a.key.as_ref() == key)
                        .map(|a| a.unescape_value().expect("value").into_owned())
                };
                match e.name().as_ref() {
                    b"DataItem" => {
                        assert_eq!(attr(b"Format").as_deref(), Some("HDF"));
                        assert_eq!(attr(b"Precision").as_deref(), Some("8"));
                        let d = attr(b"Dimensions").expect("Dimensions");
                        dims = Some(d.split(' ').map(|n| n.parse().expect("a size")).collect());
                    }
                    b"Time" => into
                        .times
                        .push(attr(b"Value").expect("Value").parse().expect("a time")),
                    b"xi:include" => {
                        let href = attr(b"href").expect("href");
                        describe(&xmf.with_file_name(href), into);
                    }
                    _ => {}
                }
            }
            Event::Text(t) if dims.is_some() => {
                let text = t.unescape().expect("text").into_owned();
                let (file, path) = text.split_once(':').expect("FILE:PATH");
                let item = (file.to_owned(), path.to_owned(), dims.take().unwrap());
                // Every grid frame stands on the same nodes; any other array is named once.
                let shared = file.ends_with("_points.h5");
                assert!(into.items.insert(item.clone()) || shared, "{item:?} twice");
            }
            Event::Eof => break,
            _ => {}
        }
    }
}

/// Every dataset of an HDF5 file (groups walked, no links followed), with its shape.
fn datasets(dir: &Path, file: &str, into: &mut BTreeSet<Item>) {
    fn walk(g: &hdf5::Group, prefix: &str, file: &str, into: &mut BTreeSet<Item>) {
        for ds in g.datasets().expect("datasets") {
            let name = ds.name().rsplit('/').next().unwrap().to_owned();
            into.insert((file.to_owned(), format!("{prefix}/{name}"), ds.shape()));
        }
        for sub in g.groups().expect("groups") {
            let name = sub.name().rsplit('/').next().unwrap().to_owned();
            walk(&sub, &format!("{prefix}/{name}"), file, into);
        }
    }
    let h5 = hdf5::File::open(dir.join(file)).expect("an HDF5 file");
    walk(&h5, "", file, into);
}

/// The datasets of every frame file `index` lists, and of the grid's node file where there is
/// one; and the frames' times.
fn stored(index: &Path) -> (BTreeSet<Item>, Vec<Real>) {
    let dir = index.parent().unwrap();
    let h5 = hdf5::File::open(index).expect("the index");
    let frames = h5.group("frames").expect("/frames");
    let mut names = frames.member_names().expect("frames");
    names.sort();
    let stem = index.file_stem().unwrap().to_string_lossy();
    let mut items = BTreeSet::new();
    let mut times = Vec::new();
    for (k, name) in names.iter().enumerate() {
        assert_eq!(name, &format!("{k:06}"));
        let file = format!("{stem}_{k:06}.h5");
        datasets(dir, &file, &mut items);
        let frame = hdf5::File::open(dir.join(&file)).expect("a frame");
        times.push(frame.attr("time").unwrap().read_scalar().unwrap());
    }
    let points = format!("{stem}_points.h5");
    if dir.join(&points).exists() {
        datasets(dir, &points, &mut items);
    }
    (items, times)
}

/// Particle sets with no particles are left out of the XDMF (it cannot describe an empty set).
fn without_empty(items: BTreeSet<Item>) -> BTreeSet<Item> {
    let empty: BTreeSet<(String, String)> = items
        .iter()
        .filter(|(_, path, shape)| path.ends_with("/position") && shape[0] == 0)
        .map(|(file, path, _)| (file.clone(), path.trim_end_matches("position").to_owned()))
        .collect();
    items
        .into_iter()
        .filter(|(file, path, _)| {
            let group = &path[..=path.rfind('/').unwrap()];
            !empty.contains(&(file.clone(), group.to_owned()))
        })
        .collect()
}

fn assert_matches(index: &Path) {
    let mut xmf = Described::default();
    describe(&index.with_extension("xmf"), &mut xmf);
    let (items, times) = stored(index);
    assert!(!times.is_empty(), "{} holds no frames", index.display());
    assert_eq!(xmf.times, times, "{}", index.display());
    let items = without_empty(items);
    let missing: Vec<_> = items.difference(&xmf.items).collect();
    let extra: Vec<_> = xmf.items.difference(&items).collect();
    assert!(
        missing.is_empty() && extra.is_empty(),
        "{}: not described {missing:?}, described but not stored {extra:?}",
        index.display()
    );
}

fn run_scene(scene: &str, overrides: &[&str]) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let mut set = vec!["output.hdf5=true".to_owned(), "output.vtk=false".to_owned()];
    set.extend(overrides.iter().map(|s| s.to_string()));
    let options = RunOptions {
        out: Some(dir.path().to_owned()),
        overrides: set,
        steps: Some(3),
        ..RunOptions::default()
    };
    let scene = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(scene);
    run(&scene, &options).expect("the scene runs");
    let out = dir.path().to_owned();
    (dir, out)
}

#[test]
fn xdmf_of_a_particle_run_names_every_dataset_of_every_frame() {
    let _serial = common::hdf5_or_child();
    let (_dir, out) = run_scene("dam_break.toml", &["output.interval=0.0005"]);
    assert_matches(&out.join("frames.h5"));
}

#[test]
fn xdmf_of_a_grid_run_names_every_dataset_of_every_frame() {
    let _serial = common::hdf5_or_child();
    let (_dir, out) = run_scene("smoke_plume.toml", &["output.interval=0.01"]);
    assert_matches(&out.join("frames.h5"));
}

#[test]
fn xdmf_of_a_coupled_run_opens_both_series() {
    let _serial = common::hdf5_or_child();
    let (_dir, out) = run_scene("coupled_wind_over_tank.toml", &["output.interval=0.001"]);
    for index in ["particles_frames.h5", "grid_frames.h5"] {
        assert_matches(&out.join(index));
    }
    // frames.xmf includes both series whole.
    let mut both = Described::default();
    describe(&out.join("frames.xmf"), &mut both);
    let mut each = Described::default();
    describe(&out.join("particles_frames.xmf"), &mut each);
    describe(&out.join("grid_frames.xmf"), &mut each);
    assert_eq!((both.items, both.times), (each.items, each.times));
}

#[test]
fn xdmf_describes_particle_sets_and_leaves_out_empty_ones() {
    let _serial = common::hdf5_or_child();
    let dir = tempfile::tempdir().unwrap();
    let pos: Vec<Vec3> = (0..5).map(|i| Vec3::new(i as Real, 0.0, 1.0)).collect();
    let values: Vec<Real> = (0..5).map(|i| i as Real).collect();
    let frame = |n: usize, time| ParticleFrame {
        step: 0,
        time,
        positions: &pos[..n],
        fields: vec![Field::scalar("age", &values[..n])],
    };
    let mut particles = Hdf5Frames::create(&dir.path().join("frames.h5"), &[]).unwrap();
    let mut grid = Hdf5GridFrames::create(&dir.path().join("grid_frames.h5"), &[]).unwrap();
    let smoke = Array3::<Real>::zeros((3, 2, 4));
    let cells = |time| GridFrame {
        step: 0,
        time,
        origin: Vec3::zeros(),
        spacing: 0.5,
        dims: [3, 2, 4],
        fields: vec![GridField::scalar("smoke", smoke.view())],
    };
    for (k, n) in [0usize, 5, 2].into_iter().enumerate() {
        let time = 0.1 * k as Real;
        let set = frame(n, time);
        particles
            .append_with(&frame(5, time), &[("vortices", &set)])
            .unwrap();
        grid.append_with(&cells(time), &[("vortices", &set)])
            .unwrap();
    }
    for index in ["frames.h5", "grid_frames.h5"] {
        assert_matches(&dir.path().join(index));
    }
    // The node file holds the corners of 3 x 2 x 4 cells: 4 x 3 x 5 nodes.
    let points = hdf5::File::open(dir.path().join("grid_frames_points.h5")).unwrap();
    let nodes: Vec<Real> = points.dataset("points").unwrap().read_raw().unwrap();
    assert_eq!(nodes.len(), 3 * 4 * 3 * 5);
    // Node (i, j, k), x slowest, sits at (i, j, k) spacings from the origin.
    let (i, j, k) = (2, 1, 3);
    let at = 3 * (k + 5 * (j + 3 * i));
    assert_eq!(nodes[at..at + 3], [1.0, 0.5, 1.5]);
}
