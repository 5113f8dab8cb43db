//! Round trips of the writers in `eddy::io`: what is written reads back identically, and a
//! failure leaves no half-written file behind.

mod common;

use std::fs;
use std::path::Path;

use eddy::io::{
    write_atomic, write_particles_vtk, AttrValue, CsvSeries, Field, Hdf5Frames, IoError,
    ParticleFrame, Precision, PvdSeries, VtkOptions,
};
use eddy::{Real, Vec3};

use common::vtk_read::read_vtk;

/// Values whose decimal forms are awkward: they catch writers that lose digits.
const AWKWARD: [Real; 8] = [
    0.1,
    1.0 / 3.0,
    -2.5e-7,
    1e-300,
    1e300,
    f64::MIN_POSITIVE,
    5e-324,
    -0.0,
];

fn positions(n: usize, seed: Real) -> Vec<Vec3> {
    (0..n)
        .map(|i| {
            let t = i as Real + seed;
            Vec3::new(t.sin() / 3.0, (t * 0.7).cos() * 1e-3, t * 1e5 + 0.1)
        })
        .collect()
}

fn flat(v: &[Vec3]) -> Vec<Real> {
    v.iter().flat_map(|p| [p.x, p.y, p.z]).collect()
}

fn no_temp_files(dir: &Path) {
    let leftovers: Vec<_> = fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
}

#[test]
fn io_error_can_cross_threads_and_anyhow() {
    fn check<E: std::error::Error + Send + Sync + 'static>() {}
    check::<IoError>();
}

// ---------------------------------------------------------------- write_atomic

#[test]
fn write_atomic_replaces_and_leaves_no_temp() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.txt");
    write_atomic(&path, |w| w.write_all(b"first")).unwrap();
    write_atomic(&path, |w| w.write_all(b"second")).unwrap();
    assert_eq!(fs::read_to_string(&path).unwrap(), "second");
    assert!(!dir.path().join(".out.txt.tmp").exists());
    no_temp_files(dir.path());
}

#[test]
fn write_atomic_failure_keeps_previous_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.txt");
    write_atomic(&path, |w| w.write_all(b"good")).unwrap();
    let err = write_atomic(&path, |w| {
        w.write_all(b"half of the new cont")?;
        Err(std::io::Error::other("writer gave up"))
    })
    .unwrap_err();
    assert!(matches!(err, IoError::Io { .. }), "{err:?}");
    let msg = err.to_string();
    assert!(
        msg.contains("out.txt") && msg.contains("writer gave up"),
        "{msg}"
    );
    assert_eq!(fs::read_to_string(&path).unwrap(), "good");
    no_temp_files(dir.path());
}

#[test]
fn write_atomic_failure_without_previous_file_creates_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("new.txt");
    let result = write_atomic(&path, |w| {
        w.write_all(b"partial")?;
        Err(std::io::Error::other("boom"))
    });
    assert!(result.is_err());
    assert!(!path.exists());
    assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 0);
}

#[test]
fn write_atomic_into_missing_directory_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("no_such_dir").join("x.txt");
    let err = write_atomic(&path, |w| w.write_all(b"x")).unwrap_err();
    assert!(err.to_string().contains("no_such_dir"), "{err}");
}

// ---------------------------------------------------------------- VTK

const EXACT: VtkOptions = VtkOptions {
    precision: Precision::F64,
    compression: 4,
};

/// The particle frame of the round trips: awkward values, a vector with a -0.0 and a name
/// that needs XML escaping.
struct Particles {
    pos: Vec<Vec3>,
    density: Vec<Real>,
    velocity: Vec<Vec3>,
    pressure: Vec<Real>,
}

impl Particles {
    fn new(n: usize) -> Self {
        Particles {
            pos: positions(n, 0.25),
            density: (0..n)
                .map(|i| AWKWARD[i % AWKWARD.len()] + i as Real)
                .collect(),
            velocity: (0..n)
                .map(|i| Vec3::new(AWKWARD[i % 8], -(i as Real) / 7.0, 1e-12 * i as Real))
                .collect(),
            pressure: (0..n).map(|i| -(i as Real).sqrt()).collect(),
        }
    }

    fn frame(&self) -> ParticleFrame<'_> {
        ParticleFrame {
            step: 3,
            time: 0.03,
            positions: &self.pos,
            fields: vec![
                Field::scalar("density", &self.density),
                Field::vector("velocity", &self.velocity),
                Field::scalar("p \"gauge\" & <rel>", &self.pressure),
            ],
        }
    }
}

#[test]
fn vtk_roundtrip_points_fields_and_names() {
    // 40,000 particles: the points and the velocity span several compressed blocks.
    for (n, level) in [(50, 0), (50, 4), (40_000, 1), (40_000, 9)] {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("frame_000003.vtp");
        let p = Particles::new(n);
        let options = VtkOptions {
            compression: level,
            ..EXACT
        };
        write_particles_vtk(&path, &p.frame(), options).unwrap();
        no_temp_files(dir.path());

        let file = read_vtk(&path);
        assert_eq!(file.attr("VTKFile", "type"), "PolyData");
        assert_eq!(file.attr("Piece", "NumberOfPoints"), n.to_string());
        assert_eq!(file.attr("Piece", "NumberOfVerts"), n.to_string());
        assert_eq!(file.section("FieldData")[0].values, [0.03]);
        let points = file.section("Points");
        assert_eq!(
            (points[0].kind.as_str(), points[0].components),
            ("Float64", 3)
        );
        assert_eq!(points[0].values, flat(&p.pos));
        let verts = file.section("Verts");
        let ids = |from: usize| (from..n + from).map(|i| i as Real).collect::<Vec<_>>();
        assert_eq!(
            (verts[0].name.as_str(), &verts[0].values),
            ("connectivity", &ids(0))
        );
        assert_eq!(
            (verts[1].name.as_str(), &verts[1].values),
            ("offsets", &ids(1))
        );

        let arrays: Vec<_> = file
            .section("PointData")
            .into_iter()
            .map(|a| (a.name.as_str(), a.components, &a.values))
            .collect();
        assert_eq!(arrays.len(), 3);
        assert_eq!(arrays[0], ("density", 1, &p.density));
        assert_eq!(arrays[1], ("velocity", 3, &flat(&p.velocity)));
        assert_eq!(arrays[2], ("p \"gauge\" & <rel>", 1, &p.pressure));
        // -0.0 == 0.0 above; check the sign bit survived too.
        assert!(arrays[1].2[7 * 3].is_sign_negative());
        assert_eq!(file.attr("PointData", "Vectors"), "velocity");
    }
}

#[test]
fn vtk_f32_frames_round_to_the_nearest_float_and_compress() {
    let dir = tempfile::tempdir().unwrap();
    let p = Particles::new(40_000);
    let size = |name: &str, options: VtkOptions| {
        let path = dir.path().join(name);
        write_particles_vtk(&path, &p.frame(), options).unwrap();
        (read_vtk(&path), fs::metadata(&path).unwrap().len())
    };
    let (exact, exact_bytes) = size("exact.vtp", EXACT);
    let (plain, plain_bytes) = size(
        "plain.vtp",
        VtkOptions {
            compression: 0,
            ..EXACT
        },
    );
    let (small, small_bytes) = size("small.vtp", VtkOptions::default());
    assert_eq!(plain.arrays.len(), exact.arrays.len());
    for (a, b) in small.arrays.iter().zip(&exact.arrays) {
        let want: Vec<Real> = match a.kind.as_str() {
            "Float32" => b.values.iter().map(|&v| v as f32 as Real).collect(),
            "Int64" | "Float64" => b.values.clone(),
            other => panic!("{other}"),
        };
        assert_eq!(a.values, want, "{}", a.name);
    }
    assert_eq!(small.section("PointData")[0].kind, "Float32");
    // f64 raw: 8 bytes a value, 8 values and 2 ids a particle.
    let raw = 8 * 10 * 40_000;
    assert!(
        plain_bytes > raw && plain_bytes < raw + 4096,
        "{plain_bytes}"
    );
    assert!(exact_bytes < plain_bytes, "{exact_bytes} vs {plain_bytes}");
    // f32 raw: 4 bytes a real, 8 bytes an id.
    let raw_f32 = (4 * 8 + 8 * 2) * 40_000;
    assert!(small_bytes < exact_bytes, "{small_bytes} vs {exact_bytes}");
    assert!(small_bytes < raw_f32, "{small_bytes} vs {raw_f32}");
}

#[test]
fn vtk_empty_frame_roundtrips() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("empty.vtp");
    let frame = ParticleFrame {
        step: 0,
        time: 0.0,
        positions: &[],
        fields: vec![Field::scalar("density", &[])],
    };
    write_particles_vtk(&path, &frame, VtkOptions::default()).unwrap();
    // VTK's reader needs the zero counts spelled out.
    let file = read_vtk(&path);
    assert_eq!(file.attr("Piece", "NumberOfPoints"), "0");
    assert_eq!(file.attr("Piece", "NumberOfVerts"), "0");
    let density = file.section("PointData");
    assert_eq!(
        (density[0].name.as_str(), density[0].values.len()),
        ("density", 0)
    );
}

#[test]
fn vtk_rejects_bad_frames_without_writing() {
    let dir = tempfile::tempdir().unwrap();
    let pos = positions(3, 0.0);
    let short = [1.0, 2.0];
    let ok = [1.0, 2.0, 3.0];
    let cases: Vec<(&str, ParticleFrame)> = vec![
        (
            "a.vtp",
            ParticleFrame {
                step: 0,
                time: 0.0,
                positions: &pos,
                fields: vec![Field::scalar("density", &short)],
            },
        ),
        (
            "b.vtp",
            ParticleFrame {
                step: 0,
                time: 0.0,
                positions: &pos,
                fields: vec![Field::scalar("d", &ok), Field::scalar("d", &ok)],
            },
        ),
        (
            "c.vtk",
            ParticleFrame {
                step: 0,
                time: 0.0,
                positions: &pos,
                fields: vec![],
            },
        ),
    ];
    for (name, frame) in cases {
        let path = dir.path().join(name);
        let err = write_particles_vtk(&path, &frame, VtkOptions::default()).unwrap_err();
        assert!(matches!(err, IoError::Invalid { .. }), "{name}: {err:?}");
        assert!(err.to_string().contains(name), "{err}");
        assert!(!path.exists());
    }
    assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 0);
}

// ---------------------------------------------------------------- PVD

/// Parses `<DataSet timestep=".." ... file=".."/>` lines; the writer puts one per line.
fn pvd_entries(text: &str) -> Vec<(Real, String)> {
    text.lines()
        .filter(|l| l.trim_start().starts_with("<DataSet "))
        .map(|l| {
            let attr = |key: &str| {
                let start = l.find(&format!(" {key}=\"")).unwrap() + key.len() + 3;
                let len = l[start..].find('"').unwrap();
                l[start..start + len].to_string()
            };
            (attr("timestep").parse().unwrap(), attr("file"))
        })
        .collect()
}

#[test]
fn pvd_lists_frames_in_order_after_every_push() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("particles.pvd");
    let mut series = PvdSeries::new(&path);
    assert!(!path.exists(), "nothing is written before the first frame");
    let times = [0.0, 0.1, 1.0 / 3.0];
    for (i, &t) in times.iter().enumerate() {
        let name = format!("frames/particles_{i:06}.vtp");
        series.push(t, &name).unwrap();
        // After each push the file is complete and lists every frame so far.
        let text = fs::read_to_string(&path).unwrap();
        assert!(text.starts_with("<?xml"));
        assert!(text.contains("<VTKFile type=\"Collection\""));
        assert!(text.trim_end().ends_with("</VTKFile>"));
        let entries = pvd_entries(&text);
        assert_eq!(entries.len(), i + 1);
        for (j, (time, file)) in entries.iter().enumerate() {
            assert_eq!(*time, times[j]);
            assert_eq!(*file, format!("frames/particles_{j:06}.vtp"));
        }
    }
    assert_eq!(series.len(), 3);
    no_temp_files(dir.path());
}

#[test]
fn pvd_escapes_names_and_parses_as_xml() {
    let _serial = common::hdf5_or_child();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s.pvd");
    let mut series = PvdSeries::new(&path);
    series.push(0.5, "a&b <\"q\">.vtp").unwrap();
    series.push(1.5, "plain.vtp").unwrap();
    let text = fs::read_to_string(&path).unwrap();
    assert!(
        text.contains("file=\"a&amp;b &lt;&quot;q&quot;&gt;.vtp\""),
        "{text}"
    );
    assert!(series.push(Real::NAN, "x.vtp").is_err());
    assert_eq!(fs::read_to_string(&path).unwrap(), text);

    // A real XML parser, when one is installed, must agree with what was written.
    let script = "import sys, xml.etree.ElementTree as E\n\
                  r = E.parse(sys.argv[1]).getroot()\n\
                  assert r.tag == 'VTKFile' and r.get('type') == 'Collection'\n\
                  for d in r.find('Collection'): print(d.get('timestep'), d.get('file'))\n";
    if let Ok(out) = std::process::Command::new("python3")
        .arg("-c")
        .arg(script)
        .arg(&path)
        .output()
    {
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert_eq!(
            String::from_utf8_lossy(&out.stdout),
            "0.5 a&b <\"q\">.vtp\n1.5 plain.vtp\n"
        );
    }
}

// ---------------------------------------------------------------- HDF5

fn read_attr<T: hdf5::H5Type>(loc: &hdf5::Group, name: &str) -> T {
    loc.attr(name).unwrap().read_scalar::<T>().unwrap()
}

#[test]
fn hdf5_frames_roundtrip() {
    let _serial = common::hdf5_or_child();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("frames.h5");
    let mut out = Hdf5Frames::create(
        &path,
        &[
            ("scene", AttrValue::Str("dam break ü".into())),
            ("particle_spacing", AttrValue::Real(0.0125)),
            ("seed", AttrValue::Int(-7)),
        ],
    )
    .unwrap();
    no_temp_files(dir.path());

    let counts = [5usize, 0, 17];
    let mut written = Vec::new();
    for (k, &n) in counts.iter().enumerate() {
        let pos = positions(n, k as Real);
        let density: Vec<Real> = (0..n).map(|i| 1000.0 + AWKWARD[i % 8]).collect();
        let velocity: Vec<Vec3> = (0..n)
            .map(|i| Vec3::new(i as Real, -(k as Real), 1.0 / (i as Real + 1.0)))
            .collect();
        let frame = ParticleFrame {
            step: 100 * k as u64 + 1,
            time: 0.1 * k as Real,
            positions: &pos,
            fields: vec![
                Field::scalar("density", &density),
                Field::vector("velocity", &velocity),
            ],
        };
        out.append(&frame).unwrap();
        written.push((frame.step, frame.time, pos, density, velocity));
    }
    assert_eq!(out.len(), 3);

    let file = hdf5::File::open(&path).unwrap();
    let scene: hdf5::types::VarLenUnicode = read_attr(&file, "scene");
    assert_eq!(scene.as_str(), "dam break ü");
    assert_eq!(read_attr::<f64>(&file, "particle_spacing"), 0.0125);
    assert_eq!(read_attr::<i64>(&file, "seed"), -7);
    assert_eq!(file.member_names().unwrap(), vec!["frames".to_string()]);

    let frames = file.group("frames").unwrap();
    assert_eq!(
        frames.member_names().unwrap(),
        vec!["000000", "000001", "000002"]
    );
    for (k, (step, time, pos, density, velocity)) in written.iter().enumerate() {
        let g = frames.group(&format!("{k:06}")).unwrap();
        assert_eq!(read_attr::<u64>(&g, "step"), *step);
        assert_eq!(read_attr::<f64>(&g, "time"), *time);
        let n = pos.len();
        let p = g.dataset("position").unwrap();
        assert_eq!(p.shape(), vec![n, 3]);
        assert_eq!(p.dtype().unwrap().size(), 8);
        assert_eq!(p.read_raw::<f64>().unwrap(), flat(pos));
        let d = g.dataset("density").unwrap();
        assert_eq!(d.shape(), vec![n]);
        assert_eq!(d.read_raw::<f64>().unwrap(), *density);
        let v = g.dataset("velocity").unwrap();
        assert_eq!(v.shape(), vec![n, 3]);
        assert_eq!(v.read_raw::<f64>().unwrap(), flat(velocity));
    }
}

/// The index is rewritten whole for every frame and no frame file is touched once written: an
/// index cut in half, emptied or deleted is replaced at the next append by a complete one that
/// lists every frame; an append whose folder is gone fails without advancing.
#[test]
fn hdf5_index_is_rewritten_whole() {
    let _serial = common::hdf5_or_child();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cut.h5");
    let mut out = Hdf5Frames::create(&path, &[("scene", AttrValue::from("cut"))]).unwrap();
    let pos = positions(200, 0.0);
    let frame = ParticleFrame {
        step: 1,
        time: 0.5,
        positions: &pos,
        fields: vec![],
    };
    out.append(&frame).unwrap();
    out.append(&frame).unwrap();
    let len = fs::metadata(&path).unwrap().len();
    let damage: [&dyn Fn(); 3] = [
        &|| {
            fs::OpenOptions::new()
                .write(true)
                .open(&path)
                .unwrap()
                .set_len(len / 2)
                .unwrap()
        },
        &|| fs::write(&path, b"").unwrap(),
        &|| fs::remove_file(&path).unwrap(),
    ];
    for damage in damage {
        damage();
        out.append(&frame).unwrap();
        let file = hdf5::File::open(&path).unwrap();
        let scene: hdf5::types::VarLenUnicode = read_attr(&file, "scene");
        assert_eq!(scene.as_str(), "cut");
        let frames = file.group("frames").unwrap();
        assert_eq!(frames.len() as u64, out.len());
        for name in frames.member_names().unwrap() {
            let p = frames.group(&name).unwrap().dataset("position").unwrap();
            assert_eq!(p.read_raw::<f64>().unwrap(), flat(&pos), "frame {name}");
        }
    }
    assert_eq!(out.len(), 5);
    no_temp_files(dir.path());

    drop(dir);
    let err = out.append(&frame).unwrap_err();
    assert!(err.to_string().contains("cut"), "{err}");
    assert_eq!(out.len(), 5, "a failed append must not advance the index");
}

/// A particle set appended with a frame (the vortex particles beside the fluid) reads back as
/// its own group under the frame; a set named like a field, or twice, or holding a bad field,
/// is refused and the index does not advance.
#[test]
fn hdf5_particle_sets_ride_in_their_frame() {
    let _serial = common::hdf5_or_child();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("frames.h5");
    let mut out = Hdf5Frames::create(&path, &[]).unwrap();
    let (fluid, vortices) = (positions(4, 0.0), positions(2, 7.0));
    let density = [1000.0, 1001.0, 999.0, 1000.5];
    let radius = [AWKWARD[1], AWKWARD[2]];
    let frame = |fields| ParticleFrame {
        step: 3,
        time: 0.25,
        positions: &fluid,
        fields,
    };
    let set = |name, values: &'static [Real]| ParticleFrame {
        step: 3,
        time: 0.25,
        positions: &vortices,
        fields: vec![Field::scalar(name, values)],
    };
    let (good, short) = (set("radius", &[0.0; 2]), set("radius", &[0.0; 1]));
    let main = frame(vec![Field::scalar("density", &density)]);
    for bad in [
        vec![("density", &good)],
        vec![("vortices", &good), ("vortices", &good)],
        vec![("a/b", &good)],
        vec![("vortices", &short)],
    ] {
        let err = out.append_with(&main, &bad).unwrap_err();
        assert!(matches!(err, IoError::Invalid { .. }), "{err:?}");
    }
    assert_eq!(out.len(), 0);
    let sets = ParticleFrame {
        fields: vec![Field::scalar("radius", &radius)],
        ..set("radius", &[0.0; 2])
    };
    out.append_with(&main, &[("vortices", &sets)]).unwrap();
    let file = hdf5::File::open(&path).unwrap();
    let g = file.group("frames/000000/vortices").unwrap();
    assert_eq!(g.dataset("position").unwrap().shape(), vec![2, 3]);
    assert_eq!(
        g.dataset("position").unwrap().read_raw::<f64>().unwrap(),
        flat(&vortices)
    );
    assert_eq!(
        g.dataset("radius").unwrap().read_raw::<f64>().unwrap(),
        radius
    );
    let d = file.dataset("frames/000000/density").unwrap();
    assert_eq!(d.read_raw::<f64>().unwrap(), density);
}

#[test]
fn hdf5_rejects_bad_frames_and_attributes() {
    let _serial = common::hdf5_or_child();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.h5");
    let dup = Hdf5Frames::create(&path, &[("a", AttrValue::Int(1)), ("a", AttrValue::Int(2))]);
    assert!(matches!(dup, Err(IoError::Invalid { .. })));
    assert!(!path.exists());

    let mut out = Hdf5Frames::create(&path, &[]).unwrap();
    let pos = positions(3, 0.0);
    let vals = [1.0, 2.0, 3.0];
    for name in ["position", "a/b", ""] {
        let frame = ParticleFrame {
            step: 0,
            time: 0.0,
            positions: &pos,
            fields: vec![Field::scalar(name, &vals)],
        };
        let err = out.append(&frame).unwrap_err();
        assert!(matches!(err, IoError::Invalid { .. }), "{name:?}: {err:?}");
    }
    let frame = ParticleFrame {
        step: 0,
        time: 0.0,
        positions: &pos,
        fields: vec![Field::scalar("short", &vals[..2])],
    };
    assert!(matches!(out.append(&frame), Err(IoError::Invalid { .. })));
    assert_eq!(out.len(), 0);
    let file = hdf5::File::open(&path).unwrap();
    assert_eq!(file.group("frames").unwrap().len(), 0);
}

#[test]
fn hdf5_leftover_of_a_crashed_append_is_dropped() {
    let _serial = common::hdf5_or_child();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("crash.h5");
    let mut out = Hdf5Frames::create(&path, &[]).unwrap();
    let pos = positions(3, 0.0);
    let frame = ParticleFrame {
        step: 1,
        time: 0.5,
        positions: &pos,
        fields: vec![],
    };
    out.append(&frame).unwrap();
    // What a crash mid-append leaves: a started frame outside /frames.
    {
        let file = hdf5::File::open_rw(&path).unwrap();
        let roots = file.member_names().unwrap();
        assert_eq!(
            roots,
            vec!["frames"],
            "no partial group after a clean append"
        );
        let partial = file.create_group("partial_frame").unwrap();
        partial
            .new_dataset::<f64>()
            .shape((7, 3))
            .create("position")
            .unwrap();
    }
    out.append(&frame).unwrap();
    let file = hdf5::File::open(&path).unwrap();
    assert_eq!(file.member_names().unwrap(), vec!["frames"]);
    let frames = file.group("frames").unwrap();
    assert_eq!(frames.member_names().unwrap(), vec!["000000", "000001"]);
    let p = frames.group("000001").unwrap().dataset("position").unwrap();
    assert_eq!(p.read_raw::<f64>().unwrap(), flat(&pos));
}

// ---------------------------------------------------------------- CSV

#[test]
fn csv_header_rows_and_exact_numbers() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("metrics.csv");
    let columns: Vec<String> = ["time", "energy", "odd, \"name\""]
        .iter()
        .map(|s| s.to_string())
        .collect();
    let mut csv = CsvSeries::create(&path, &columns).unwrap();
    assert_eq!(
        fs::read_to_string(&path).unwrap(),
        "time,energy,\"odd, \"\"name\"\"\"\n",
        "the header is on disk before any row"
    );
    let mut rows: Vec<[Real; 3]> = AWKWARD
        .chunks(2)
        .enumerate()
        .map(|(i, c)| [i as Real * 0.1, c[0], c[1]])
        .collect();
    rows.push([f64::MAX, -f64::MAX, 123456789.0]);
    rows.push([Real::INFINITY, Real::NEG_INFINITY, 1e15]);
    for r in &rows {
        csv.row(r).unwrap();
        // Flushed every row: the file already holds it, without dropping the writer.
        let lines = fs::read_to_string(&path).unwrap().lines().count();
        assert!(lines >= 2);
    }

    let wrong = csv.row(&[1.0, 2.0]).unwrap_err();
    assert!(matches!(wrong, IoError::Invalid { .. }), "{wrong:?}");
    assert!(wrong.to_string().contains("metrics.csv"), "{wrong}");
    assert!(csv.row(&[1.0, 2.0, 3.0, 4.0]).is_err());

    let text = fs::read_to_string(&path).unwrap();
    let mut lines = text.lines();
    lines.next();
    let read: Vec<Vec<Real>> = lines
        .map(|l| l.split(',').map(|s| s.parse::<Real>().unwrap()).collect())
        .collect();
    assert_eq!(read.len(), rows.len(), "bad rows wrote nothing");
    for (r, w) in read.iter().zip(&rows) {
        assert_eq!(r.len(), 3);
        for (a, b) in r.iter().zip(w) {
            assert_eq!(a.to_bits(), b.to_bits(), "{a} vs {b}");
        }
    }
    // Exponent form keeps 1e300 and 1e-300 short instead of 300 digits.
    assert!(
        text.split([',', '\n']).all(|v| v.len() <= 24),
        "overlong numbers: {text}"
    );
}

#[test]
fn csv_nan_and_empty_columns() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("probes.csv");
    assert!(CsvSeries::create(&path, &[]).is_err());
    let mut csv = CsvSeries::create(&path, &["x".to_string()]).unwrap();
    csv.row(&[Real::NAN]).unwrap();
    let text = fs::read_to_string(&path).unwrap();
    let v: Real = text.lines().nth(1).unwrap().parse().unwrap();
    assert!(v.is_nan());
}

/// `output.compression`: at level 4 every non-empty dataset of a particle and a grid frame is
/// chunked, shuffled and deflated (the filters h5py reports as `shuffle` and `gzip`; the
/// chunks compressed here and written raw), reads back bit for bit across several chunks, and a field of few distinct values (a rest density, a solid flag) takes
/// less than half its raw size; at level 0 there are no filters.
#[test]
fn hdf5_frames_compress_losslessly() {
    use eddy::io::{GridField, GridFrame, Hdf5GridFrames};
    use hdf5::filters::Filter;
    let _serial = common::hdf5_or_child();
    let dir = tempfile::tempdir().unwrap();
    // Several chunks of about 1 MiB, the last one partial, for both kinds of frame.
    let n = 100_003;
    let pos = positions(n, 0.5);
    let steps: Vec<Real> = (0..n).map(|i| 1000.0 + (i / 500) as Real).collect();
    let cells = ndarray::Array3::from_shape_fn((96, 48, 40), |(i, j, k)| {
        (i as Real * 0.1).sin() + j as Real * 0.01 - k as Real
    });
    let mut sizes = Vec::new();
    for level in [0u8, 4] {
        let path = dir.path().join(format!("p{level}.h5"));
        let mut particles = Hdf5Frames::create(&path, &[]).unwrap().compressed(level);
        particles
            .append(&ParticleFrame {
                step: 1,
                time: 0.5,
                positions: &pos,
                fields: vec![Field::scalar("density", &steps)],
            })
            .unwrap();
        let grid_path = dir.path().join(format!("g{level}.h5"));
        let mut grid = Hdf5GridFrames::create(&grid_path, &[])
            .unwrap()
            .compressed(level);
        let frame = GridFrame {
            step: 1,
            time: 0.5,
            origin: Vec3::zeros(),
            spacing: 0.1,
            dims: [96, 48, 40],
            fields: vec![GridField::scalar("pressure", cells.view())],
        };
        grid.append(&frame).unwrap();
        let want = if level > 0 {
            vec![Filter::Shuffle, Filter::Deflate(level)]
        } else {
            Vec::new()
        };
        let p = hdf5::File::open(&path)
            .unwrap()
            .group("frames/000000")
            .unwrap();
        for name in ["position", "density"] {
            assert_eq!(p.dataset(name).unwrap().filters(), want, "{name}");
        }
        assert_eq!(
            p.dataset("position").unwrap().read_raw::<f64>().unwrap(),
            flat(&pos)
        );
        let density = p.dataset("density").unwrap();
        assert_eq!(density.read_raw::<f64>().unwrap(), steps);
        sizes.push(density.storage_size());
        let g = hdf5::File::open(&grid_path)
            .unwrap()
            .group("frames/000000")
            .unwrap();
        let pressure = g.dataset("pressure").unwrap();
        assert_eq!(pressure.filters(), want);
        assert_eq!(
            pressure.read_raw::<f64>().unwrap(),
            cells.iter().copied().collect::<Vec<_>>()
        );
    }
    assert!(
        sizes[1] * 2 < sizes[0],
        "deflated {} against {} bytes",
        sizes[1],
        sizes[0]
    );
}
