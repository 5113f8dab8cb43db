//! The ABL database without a fluid solve: write/read round trip and the h5py layout, lookup
//! exactness at samples, linearity in speed, continuity across the azimuth seam and at the
//! poles, the world frame, and clear errors for wrong, truncated, foreign or incomplete files.

use eddy::abl::{
    geometry_fingerprint, AblData, AblDatabase, AblError, AblHeader, DirectionTable, MotionKind,
    Sampling, ABL_FORMAT_VERSION,
};
use eddy::scene::Shape;
use eddy::{Point3, Real, Vec3};
use nalgebra::{Isometry3, Translation3, UnitQuaternion};
use std::path::Path;

const POINTS: usize = 37;

fn sphere() -> Shape {
    Shape::Sphere { radius: 0.5 }
}

/// A smooth, non-linear vector function of the direction d for point p, standing in for omega.
fn field(p: usize, d: &Vec3, kind: MotionKind) -> Vec3 {
    let s = p as Real * 0.37
        + if kind == MotionKind::Rotation {
            1.0
        } else {
            0.0
        };
    Vec3::new(
        d.x * s.cos() + d.y * d.z,
        d.y - 0.5 * d.x * d.x + s.sin(),
        d.z * (1.0 + s) + d.x * d.y * d.z,
    )
}

/// A complete database over `sampling` whose rows hold [`field`] at the sampled directions.
fn synthetic(sampling: Sampling) -> AblData {
    let points: Vec<Point3> = (0..POINTS)
        .map(|p| {
            let a = p as Real;
            Point3::new(a.sin(), a.cos(), 0.1 * a)
        })
        .collect();
    let normals = points.iter().map(|x| x.coords.normalize()).collect();
    let table = |kind| {
        let mut t = DirectionTable::empty(sampling, POINTS);
        for (i, j) in sampling.distinct() {
            let d = sampling.direction(i, j);
            let values: Vec<Vec3> = (0..POINTS).map(|p| field(p, &d, kind)).collect();
            t.set(i, j, &values);
        }
        t
    };
    AblData {
        header: AblHeader {
            obstacle: "sphere".into(),
            fingerprint: "f".repeat(64),
            geometry_fingerprint: geometry_fingerprint(&sphere()).expect("analytic shape"),
            beta: 1.5,
            layer_thickness: 0.1,
            spacing: 0.0625,
            settings: "resolution = 16\n".into(),
        },
        points,
        normals,
        translation: table(MotionKind::Translation),
        rotation: table(MotionKind::Rotation),
    }
}

fn written(dir: &Path, data: &AblData) -> std::path::PathBuf {
    let path = dir.join("db.h5");
    data.write(&path).expect("writes");
    path
}

fn sampling() -> Sampling {
    Sampling::new(10, 20).expect("valid sampling")
}

/// Direction from polar and azimuth angles.
fn dir(theta: Real, phi: Real) -> Vec3 {
    Vec3::new(
        theta.sin() * phi.cos(),
        theta.sin() * phi.sin(),
        theta.cos(),
    )
}

#[test]
fn round_trip_is_identical_and_leaves_no_temporary() {
    let tmp = tempfile::tempdir().expect("temp dir");
    let data = synthetic(Sampling::new(5, 7).expect("valid"));
    let path = written(tmp.path(), &data);
    let back = AblData::read(&path).expect("reads");
    assert_eq!(back, data);
    let names: Vec<_> = std::fs::read_dir(tmp.path())
        .expect("lists")
        .map(|e| e.expect("entry").file_name())
        .collect();
    assert_eq!(names, vec![std::ffi::OsString::from("db.h5")]);
}

#[test]
fn lookup_at_samples_is_exact_and_linear_in_speed() {
    let tmp = tempfile::tempdir().expect("temp dir");
    let s = sampling();
    let path = written(tmp.path(), &synthetic(s));
    let db = AblDatabase::open(&path, Some(&sphere())).expect("opens");
    for (i, j) in [(0, 0), (1, 0), (3, 7), (5, 19), (8, 11), (9, 0)] {
        let d = s.direction(i, j);
        for scale in [1.0, 2.5] {
            let v = d * scale;
            // Exactly the stored row times |v| (the norm as computed, which may round).
            let speed = v.norm();
            let t = db.lookup(&v, &Vec3::zeros());
            let r = db.lookup(&Vec3::zeros(), &v);
            for p in 0..POINTS {
                assert_eq!(t[p], field(p, &d, MotionKind::Translation) * speed);
                assert_eq!(r[p], field(p, &d, MotionKind::Rotation) * speed);
            }
        }
    }
    // Off the samples: linear in each speed, and translation plus rotation is the sum.
    let (v, w) = (Vec3::new(0.3, -0.7, 0.2), Vec3::new(-0.1, 0.4, 0.9));
    let both = db.lookup(&v, &w);
    let t1 = db.lookup(&v, &Vec3::zeros());
    let t3 = db.lookup(&(v * 3.0), &Vec3::zeros());
    let r1 = db.lookup(&Vec3::zeros(), &w);
    for p in 0..POINTS {
        assert!((t3[p] - t1[p] * 3.0).norm() <= 1e-12 * t3[p].norm());
        assert!((both[p] - t1[p] - r1[p]).norm() <= 1e-12 * both[p].norm());
    }
    assert!(db
        .lookup(&Vec3::zeros(), &Vec3::zeros())
        .iter()
        .all(|w| *w == Vec3::zeros()));
}

/// A field linear in the direction, `omega_p(d) = A_p d` with a different matrix per point and
/// kind (the sphere in potential flow, `1.5 beta (d x n)`, is one), is reproduced exactly at
/// off-sample directions: random ones, ones next to the poles, on both sides of the azimuth
/// seam and next to a ring. Bilinear weights in (theta, phi) miss it by up to about 3 %.
#[test]
fn lookup_reproduces_a_field_linear_in_the_direction() {
    use rand::{RngExt, SeedableRng};
    let linear = |p: usize, d: &Vec3, kind: MotionKind| -> Vec3 {
        let a = p as Real * 0.37
            + if kind == MotionKind::Rotation {
                2.0
            } else {
                0.0
            };
        let m = nalgebra::Matrix3::new(
            a.cos(),
            1.0,
            -0.5, //
            0.3,
            a.sin(),
            2.0, //
            -1.0,
            0.25 * a,
            1.5,
        );
        m * d
    };
    let tmp = tempfile::tempdir().expect("temp dir");
    let s = sampling();
    let mut data = synthetic(s);
    for kind in MotionKind::ALL {
        let t = data.table_mut(kind);
        for (i, j) in s.distinct() {
            let d = s.direction(i, j);
            let values: Vec<Vec3> = (0..POINTS).map(|p| linear(p, &d, kind)).collect();
            t.set(i, j, &values);
        }
    }
    let db = AblDatabase::open(&written(tmp.path(), &data), None).expect("opens");
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let mut directions: Vec<Vec3> = (0..200)
        .map(|_| {
            let z: Real = rng.random_range(-1.0..1.0);
            let phi: Real = rng.random_range(0.0..std::f64::consts::TAU);
            dir(z.acos(), phi)
        })
        .collect();
    let ring = std::f64::consts::PI / (s.polar - 1) as Real;
    for phi in [0.0, 0.3, 2.0, 4.4] {
        for eps in [1e-3, 1e-7] {
            directions.push(dir(eps, phi));
            directions.push(dir(std::f64::consts::PI - eps, phi));
            directions.push(dir(3.0 * ring + eps, phi + 0.05));
        }
    }
    for theta in [0.4, 1.6, 2.9] {
        for phi in [1e-9, -1e-9, 1e-4, -1e-4] {
            directions.push(dir(theta, phi));
        }
    }
    for d in &directions {
        let v = *d * 1.7;
        let w = db.lookup(&v, &Vec3::zeros());
        let r = db.lookup(&Vec3::zeros(), &v);
        for p in 0..POINTS {
            let (te, re) = (
                linear(p, &v, MotionKind::Translation),
                linear(p, &v, MotionKind::Rotation),
            );
            assert!(
                (w[p] - te).norm() <= 1e-12 * te.norm().max(1.0),
                "{d:?}, point {p}"
            );
            assert!(
                (r[p] - re).norm() <= 1e-12 * re.norm().max(1.0),
                "{d:?}, point {p}"
            );
        }
    }
}

/// The largest difference at point `p` between two samples of `table` that are neighbours in
/// azimuth on ring `i` or `i + 1`, or neighbours between the two rings.
fn neighbour_difference(table: &DirectionTable, s: Sampling, i: usize, p: usize) -> Real {
    let value = |i: usize, j: usize| {
        let r = table.row(s.row(i, j % s.azimuth), POINTS);
        Vec3::from_column_slice(&r[3 * p..3 * p + 3])
    };
    let mut m: Real = 0.0;
    for j in 0..s.azimuth {
        for (a, b) in [
            ((i, j), (i, j + 1)),
            ((i + 1, j), (i + 1, j + 1)),
            ((i, j), (i + 1, j)),
        ] {
            m = m.max((value(a.0, a.1) - value(b.0, b.1)).norm());
        }
    }
    m
}

/// Across the azimuth seam phi = 0 = 2 pi the lookup is continuous: the values at phi = +-eps
/// differ by no more than the neighbouring samples' difference times the share 2 eps / dphi of
/// a sample interval that separates them, down to eps = 1e-9, where a jump would show.
#[test]
fn lookup_is_continuous_across_the_azimuth_seam() {
    let tmp = tempfile::tempdir().expect("temp dir");
    let s = sampling();
    let data = synthetic(s);
    let db = AblDatabase::open(&written(tmp.path(), &data), None).expect("opens");
    let dphi = 2.0 * std::f64::consts::PI / s.azimuth as Real;
    let dtheta = std::f64::consts::PI / (s.polar - 1) as Real;
    for theta in [0.4, 1.234, 2.0 * dtheta, 2.5] {
        let ring = ((theta / dtheta).floor() as usize).min(s.polar - 2);
        for eps in [1e-3, 1e-6, 1e-9] {
            let after = db.lookup(&dir(theta, eps), &Vec3::zeros());
            let before = db.lookup(&dir(theta, -eps), &Vec3::zeros());
            for p in 0..POINTS {
                let gap = (after[p] - before[p]).norm();
                let bound = neighbour_difference(&data.translation, s, ring, p) * 2.0 * eps / dphi;
                assert!(
                    gap <= bound + 1e-12,
                    "theta {theta}, eps {eps:e}, point {p}: gap {gap:.3e}, bound {bound:.3e}"
                );
            }
        }
    }
}

/// Approaching either pole along any azimuth, the lookup tends to the pole's value: at angle
/// eps from the pole the cell parameter towards the ring is t <= eps / (sin dtheta cos(dphi / 2))
/// (the chord between two ring samples passes at cos(dphi / 2) of their distance from the
/// axis), and the lookup differs from the pole value by at most t times the ring-to-pole
/// difference plus the excess of the weight sum, (1 - cos dtheta) t times the pole value.
#[test]
fn lookup_is_continuous_at_the_poles() {
    let tmp = tempfile::tempdir().expect("temp dir");
    let s = sampling();
    let data = synthetic(s);
    let db = AblDatabase::open(&written(tmp.path(), &data), None).expect("opens");
    let dtheta = std::f64::consts::PI / (s.polar - 1) as Real;
    let dphi = 2.0 * std::f64::consts::PI / s.azimuth as Real;
    for (pole, ring, theta0, sign) in [(0, 1, 0.0, 1.0), (9, 8, std::f64::consts::PI, -1.0)] {
        let pole_value = db.lookup(&Vec3::zeros(), &s.direction(pole, 0));
        let ring_diff = |p: usize| -> Real {
            (0..s.azimuth)
                .map(|j| {
                    let r = data.rotation.row(s.row(ring, j), POINTS);
                    (Vec3::from_column_slice(&r[3 * p..3 * p + 3]) - pole_value[p]).norm()
                })
                .fold(0.0, Real::max)
        };
        for eps in [1e-3, 1e-6, 1e-9] {
            let t_max = eps / (dtheta.sin() * (dphi / 2.0).cos());
            for phi in [0.0, 0.1, 1.0, 3.0, 5.5, 6.2] {
                let v = db.lookup(&Vec3::zeros(), &dir(theta0 + sign * eps, phi));
                for p in 0..POINTS {
                    let gap = (v[p] - pole_value[p]).norm();
                    let bound =
                        t_max * (ring_diff(p) + (1.0 - dtheta.cos()) * pole_value[p].norm());
                    // Terms of second order in t make up the 1 %.
                    assert!(
                        gap <= bound * 1.01 + 1e-12,
                        "eps {eps:e}, phi {phi}, point {p}"
                    );
                }
            }
        }
    }
}

/// In the world frame the velocities are taken into the object's frame and omega comes back
/// rotated: turning the object and the velocity together turns omega with them.
#[test]
fn world_lookup_follows_the_pose() {
    let tmp = tempfile::tempdir().expect("temp dir");
    let db = AblDatabase::open(&written(tmp.path(), &synthetic(sampling())), None).expect("opens");
    let (v, w) = (Vec3::new(0.3, -0.7, 0.2), Vec3::new(-0.1, 0.4, 0.9));
    let rot = UnitQuaternion::from_scaled_axis(Vec3::new(0.4, -1.1, 0.7));
    let pose = Isometry3::from_parts(Translation3::new(5.0, 1.0, -2.0), rot);
    let local = db.lookup(&v, &w);
    let world = db.lookup_world(&pose, &(rot * v), &(rot * w));
    for (l, g) in local.iter().zip(&world) {
        assert!((rot * l - g).norm() <= 1e-12 * l.norm().max(1.0));
    }
}

fn open_err(path: &Path, obstacle: Option<&Shape>) -> (AblError, String) {
    let e = AblDatabase::open(path, obstacle).expect_err("must be refused");
    let msg = e.to_string();
    (e, msg)
}

#[test]
fn wrong_obstacle_missing_direction_truncated_and_foreign_files_are_refused() {
    let tmp = tempfile::tempdir().expect("temp dir");
    let s = Sampling::new(4, 6).expect("valid");
    let mut data = synthetic(s);
    let path = written(tmp.path(), &data);

    let (e, msg) = open_err(&path, Some(&Shape::Sphere { radius: 0.6 }));
    assert!(matches!(e, AblError::WrongObstacle { .. }), "{msg}");
    assert!(msg.contains("'sphere'") && msg.contains("db.h5"), "{msg}");

    data.rotation.complete[s.row(2, 4)] = false;
    data.write(&path).expect("writes");
    let (e, msg) = open_err(&path, None);
    assert!(matches!(e, AblError::Incomplete { count: 1, .. }), "{msg}");
    assert!(
        msg.contains("rotation") && msg.contains("polar 2, azimuth 4"),
        "{msg}"
    );

    data.rotation.complete[s.row(2, 4)] = true;
    data.write(&path).expect("writes");
    let bytes = std::fs::read(&path).expect("reads");
    let cut = tmp.path().join("cut.h5");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).expect("writes");
    let (e, msg) = open_err(&cut, None);
    assert!(matches!(e, AblError::Unreadable { .. }), "{msg}");
    assert!(msg.contains("truncated") && msg.contains("cut.h5"), "{msg}");

    let text = tmp.path().join("notes.h5");
    std::fs::write(&text, "not hdf5").expect("writes");
    assert!(matches!(
        open_err(&text, None).0,
        AblError::Unreadable { .. }
    ));

    let foreign = tmp.path().join("frames.h5");
    let f = hdf5::File::create(&foreign).expect("creates");
    f.new_attr::<i64>().shape(()).create("steps").expect("attr");
    f.close().expect("closes");
    let (e, msg) = open_err(&foreign, None);
    assert!(matches!(e, AblError::Foreign { .. }), "{msg}");

    let f = hdf5::File::open_rw(&path).expect("opens");
    f.delete_attr("format_version").expect("deletes");
    let a = f
        .new_attr::<i64>()
        .shape(())
        .create("format_version")
        .expect("attr");
    a.as_writer().write_scalar(&99i64).expect("writes");
    f.close().expect("closes");
    let (e, msg) = open_err(&path, None);
    assert!(matches!(e, AblError::Version { found: 99, .. }), "{msg}");

    let f = hdf5::File::open_rw(&path).expect("opens");
    f.delete_attr("format_version").expect("deletes");
    let a = f
        .new_attr::<i64>()
        .shape(())
        .create("format_version")
        .expect("attr");
    a.as_writer()
        .write_scalar(&ABL_FORMAT_VERSION)
        .expect("writes");
    f.unlink("rotation/omega").expect("unlinks");
    let g = f.group("rotation").expect("group");
    g.new_dataset::<f64>()
        .shape([24, POINTS, 2])
        .create("omega")
        .expect("dataset");
    f.close().expect("closes");
    let (e, msg) = open_err(&path, None);
    assert!(matches!(e, AblError::Corrupt { .. }), "{msg}");
    assert!(msg.contains("/rotation/dataset omega has shape"), "{msg}");
}

/// A speed whose square overflows keeps its direction: the lookup at |v| = 1.7e200 is the
/// unit lookup times |v|, not zero.
#[test]
fn huge_speeds_keep_their_direction() {
    let tmp = tempfile::tempdir().expect("temp dir");
    let db = AblDatabase::open(&written(tmp.path(), &synthetic(sampling())), None).expect("opens");
    let unit = db.lookup(&Vec3::new(1.0, 1.0, 1.0), &Vec3::zeros());
    let huge = db.lookup(&Vec3::new(1e200, 1e200, 1e200), &Vec3::zeros());
    for (u, h) in unit.iter().zip(&huge) {
        assert!(
            (h / 1e200 - u).norm() <= 1e-12 * u.norm().max(1.0),
            "{h:?} against {u:?}"
        );
    }
    assert!(huge.iter().any(|h| h.norm() > 1e199));
}

/// Content a lookup cannot use is refused when the file is opened, naming what is wrong: a
/// NaN in a computed row, a zero normal, azimuth angles in another order, directions that
/// disagree with their angles, a flipped bit (Fletcher-32). Writing such data is refused too.
#[test]
fn content_a_lookup_cannot_use_is_refused() {
    let tmp = tempfile::tempdir().expect("temp dir");
    let s = Sampling::new(4, 6).expect("valid");
    let data = synthetic(s);
    let tamper = |dataset: &str, edit: &dyn Fn(&mut Vec<f64>)| {
        let path = written(tmp.path(), &data);
        let f = hdf5::File::open_rw(&path).expect("opens");
        let ds = f.dataset(dataset).expect(dataset);
        let mut v: Vec<f64> = ds.read_raw().expect("reads");
        edit(&mut v);
        ds.as_writer().write_raw(&v).expect("writes");
        f.close().expect("closes");
        let (e, msg) = open_err(&path, None);
        assert!(matches!(e, AblError::Corrupt { .. }), "{msg}");
        msg
    };
    let msg = tamper("translation/omega", &|v| v[3 * POINTS * 7 + 5] = f64::NAN);
    assert!(
        msg.contains("translation") && msg.contains("polar 1, azimuth 1") && msg.contains("NaN"),
        "{msg}"
    );
    let msg = tamper("rotation/omega", &|v| v[11] = f64::INFINITY);
    assert!(msg.contains("rotation") && msg.contains("inf"), "{msg}");
    let msg = tamper("normals", &|v| v[9..12].fill(0.0));
    assert!(
        msg.contains("normal 3") && msg.contains("not a unit vector"),
        "{msg}"
    );
    let msg = tamper("translation/azimuth_angles", &|v| v.reverse());
    assert!(msg.contains("/translation/azimuth_angles[0]"), "{msg}");
    let msg = tamper("rotation/directions", &|v| v.swap(24, 26));
    assert!(
        msg.contains("/rotation/directions[8]") && msg.contains("disagrees"),
        "{msg}"
    );
    let msg = tamper("points", &|v| v[0] = f64::NEG_INFINITY);
    assert!(
        msg.contains("point 0") && msg.contains("not finite"),
        "{msg}"
    );

    // A flipped bit inside a table's data: the Fletcher-32 checksum refuses the read.
    let path = written(tmp.path(), &data);
    let mut bytes = std::fs::read(&path).expect("reads");
    let value = data.translation.omega[3 * POINTS * 9 + 4].to_le_bytes();
    let at = bytes
        .windows(8)
        .position(|w| w == value)
        .expect("the value is stored raw");
    bytes[at + 3] ^= 0x10;
    std::fs::write(&path, &bytes).expect("writes");
    let (e, msg) = open_err(&path, None);
    assert!(matches!(e, AblError::Corrupt { .. }), "{msg}");
    assert!(
        msg.contains("translation") && msg.contains("omega"),
        "{msg}"
    );

    let mut bad = data.clone();
    bad.normals[0] = Vec3::zeros();
    let e = bad.write(&tmp.path().join("bad.h5")).expect_err("refused");
    assert!(e.to_string().contains("normal 0"), "{e}");
    assert!(!tmp.path().join("bad.h5").exists());
}

/// A mesh's fingerprint is that of its bytes and scale: the same mesh under another name gives
/// the same fingerprint, a moved vertex or another scale a different one, so a database made
/// for one mesh opens for its copy and is refused for the edited mesh.
#[test]
fn mesh_fingerprint_follows_the_geometry_not_the_file_name() {
    let tmp = tempfile::tempdir().expect("temp dir");
    let tetrahedron = |top: &str| {
        format!("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 {top}\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n")
    };
    let write = |name: &str, text: &str| {
        let path = tmp.path().join(name);
        std::fs::write(&path, text).expect("writes the mesh");
        path
    };
    let mesh = |path: &Path, scale: Real| Shape::Mesh {
        path: path.to_path_buf(),
        scale,
    };
    let original = write("original.obj", &tetrahedron("1"));
    let copy = write("renamed.obj", &tetrahedron("1"));
    let moved = write("moved.obj", &tetrahedron("1.001"));
    let fp = |shape: &Shape| geometry_fingerprint(shape).expect("fingerprints");
    let base = fp(&mesh(&original, 1.0));
    assert_eq!(base, fp(&mesh(&copy, 1.0)));
    assert_ne!(base, fp(&mesh(&moved, 1.0)));
    assert_ne!(base, fp(&mesh(&original, 2.0)));
    assert_eq!(base.len(), 64);
    assert!(matches!(
        geometry_fingerprint(&mesh(&tmp.path().join("missing.obj"), 1.0)),
        Err(AblError::Mesh { .. })
    ));

    let mut data = synthetic(Sampling::new(4, 6).expect("valid"));
    data.header.geometry_fingerprint = base;
    let path = written(tmp.path(), &data);
    AblDatabase::open(&path, Some(&mesh(&copy, 1.0))).expect("the same mesh opens");
    let (e, msg) = open_err(&path, Some(&mesh(&moved, 1.0)));
    assert!(matches!(e, AblError::WrongObstacle { .. }), "{msg}");
}
