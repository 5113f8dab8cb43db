//! Rigid bodies: signed distance against closed forms, surface samples fit for Akinci boundary
//! particles (on the surface, no holes, no clumps, about one per spacing^2), meshes read from
//! OBJ and STL agreeing with the analytic box, kinematic motion, and load errors.

use std::f64::consts::PI;
use std::path::Path;

use eddy::geometry::{GeometryError, RigidBody};
use eddy::scene::{Body, Keyframe, Motion, Shape};
use eddy::{Point3, Real, Vec3};
use nalgebra::{Rotation3, UnitQuaternion};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn rng() -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(7)
}

fn body(shape: Shape) -> Body {
    Body {
        name: None,
        shape,
        position: [0.3, -0.2, 0.5],
        rotation: [0.4, -0.7, 0.25],
        motion: Motion::default(),
        abl: None,
        wall_viscosity: None,
    }
}

fn build(b: &Body) -> RigidBody {
    RigidBody::from_scene(b, 1).expect("valid body")
}

fn uniform(rng: &mut ChaCha8Rng, lo: Real, hi: Real) -> Real {
    lo + (hi - lo) * rng.random::<Real>()
}

fn unit(rng: &mut ChaCha8Rng) -> Vec3 {
    loop {
        let v = Vec3::from_fn(|_, _| uniform(rng, -1.0, 1.0));
        let n = v.norm();
        if n > 0.1 && n <= 1.0 {
            return v / n;
        }
    }
}

/// Picks index `i` with probability weights[i] / sum.
fn pick(rng: &mut ChaCha8Rng, weights: &[Real]) -> usize {
    let mut u = rng.random::<Real>() * weights.iter().sum::<Real>();
    for (i, w) in weights.iter().enumerate() {
        if u < *w {
            return i;
        }
        u -= w;
    }
    weights.len() - 1
}

fn nearest(samples: &[Point3], x: &Point3) -> Real {
    samples
        .iter()
        .map(|s| (s - x).norm())
        .fold(Real::INFINITY, Real::min)
}

fn min_pairwise(samples: &[Point3]) -> Real {
    let mut best = Real::INFINITY;
    for (i, a) in samples.iter().enumerate() {
        for b in &samples[i + 1..] {
            best = best.min((a - b).norm());
        }
    }
    best
}

/// What a boundary sampling must give: every sample on the surface, between `count.0` and
/// `count.1` times area / spacing^2 of them, no two closer than 0.4 spacing, and no surface point
/// farther than 0.75 spacing from a sample. `surface` draws uniform body-local points on the
/// true surface.
fn check_samples(
    b: &RigidBody,
    spacing: Real,
    area: Real,
    count: (Real, Real),
    surface: impl Fn(&mut ChaCha8Rng) -> Point3,
) {
    let samples = b.sample_surface(spacing);
    let (lo, hi) = b.local_aabb();
    let size = (hi - lo).norm();
    let pose = b.pose(0.0);
    for s in &samples {
        let d = b.signed_distance(0.0, &(pose * s));
        assert!(
            d.abs() < 1e-9 * size,
            "{}: sample {s} off the surface by {d}",
            b.name()
        );
    }
    let expected = area / (spacing * spacing);
    let ratio = samples.len() as Real / expected;
    assert!(
        count.0 <= ratio && ratio <= count.1,
        "{}: {} samples for {expected:.0} expected",
        b.name(),
        samples.len()
    );
    let closest = min_pairwise(&samples);
    assert!(
        closest > 0.4 * spacing,
        "{}: two samples {closest} apart at spacing {spacing}",
        b.name()
    );
    let mut rng = rng();
    let gap = (0..3000)
        .map(|_| nearest(&samples, &surface(&mut rng)))
        .fold(0.0, Real::max);
    assert!(
        gap < 0.75 * spacing,
        "{}: a surface point lies {gap} from every sample at spacing {spacing}",
        b.name()
    );
    eprintln!(
        "{}: {} samples ({ratio:.3} of area/spacing^2), closest pair {:.3} spacing, widest gap {:.3} spacing",
        b.name(),
        samples.len(),
        closest / spacing,
        gap / spacing
    );
}

#[test]
fn sphere_samples_cover_the_surface_evenly() {
    let r = 0.25;
    let b = build(&body(Shape::Sphere { radius: r }));
    assert_eq!(b.name(), "sphere_1");
    check_samples(&b, 0.02, 4.0 * PI * r * r, (0.99, 1.01), |rng| {
        Point3::from(unit(rng) * r)
    });
}

fn random_on_box(rng: &mut ChaCha8Rng, h: &Vec3) -> Point3 {
    let faces = [h.y * h.z, h.x * h.z, h.x * h.y];
    let axis = pick(rng, &faces);
    let mut p = Vec3::from_fn(|i, _| uniform(rng, -h[i], h[i]));
    p[axis] = if rng.random::<bool>() {
        h[axis]
    } else {
        -h[axis]
    };
    Point3::from(p)
}

#[test]
fn box_samples_cover_the_surface_evenly() {
    let h = Vec3::new(0.3, 0.2, 0.1);
    let b = build(&body(Shape::Box {
        half_extents: h.into(),
    }));
    let area = 8.0 * (h.x * h.y + h.y * h.z + h.x * h.z);
    let samples = b.sample_surface(0.023);
    // Edges and corners are shared by the faces, not repeated.
    let mut keys: Vec<[u64; 3]> = samples
        .iter()
        .map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
        .collect();
    keys.sort_unstable();
    keys.dedup();
    assert_eq!(keys.len(), samples.len(), "duplicate box samples");
    check_samples(&b, 0.023, area, (0.95, 1.1), |rng| random_on_box(rng, &h));
}

#[test]
fn cylinder_samples_cover_the_surface_evenly() {
    let (r, hh) = (0.2, 0.3);
    let b = build(&body(Shape::Cylinder {
        radius: r,
        half_height: hh,
    }));
    let parts = [2.0 * PI * r * 2.0 * hh, PI * r * r, PI * r * r];
    check_samples(&b, 0.02, parts.iter().sum(), (0.95, 1.1), |rng| {
        let a = uniform(rng, 0.0, 2.0 * PI);
        match pick(rng, &parts) {
            0 => Point3::new(r * a.cos(), uniform(rng, -hh, hh), r * a.sin()),
            cap => {
                let rho = r * rng.random::<Real>().sqrt();
                let y = if cap == 1 { -hh } else { hh };
                Point3::new(rho * a.cos(), y, rho * a.sin())
            }
        }
    });
}

#[test]
fn capsule_samples_cover_the_surface_evenly() {
    // Half height 0 is a sphere sampled by latitude rings.
    let r = 0.2;
    let sphere = build(&body(Shape::Capsule {
        radius: r,
        half_height: 0.0,
    }));
    check_samples(&sphere, 0.02, 4.0 * PI * r * r, (0.95, 1.1), |rng| {
        Point3::from(unit(rng) * r)
    });
    let (r, hh) = (0.15, 0.2);
    let b = build(&body(Shape::Capsule {
        radius: r,
        half_height: hh,
    }));
    let parts = [2.0 * PI * r * 2.0 * hh, 4.0 * PI * r * r];
    check_samples(&b, 0.02, parts.iter().sum(), (0.95, 1.1), |rng| {
        if pick(rng, &parts) == 0 {
            let a = uniform(rng, 0.0, 2.0 * PI);
            Point3::new(r * a.cos(), uniform(rng, -hh, hh), r * a.sin())
        } else {
            let n = unit(rng) * r;
            Point3::new(n.x, n.y + hh * n.y.signum(), n.z)
        }
    });
}

/// Closed-form signed distances of the analytic shapes (cylinder and capsule along y).
fn exact_distance(shape: &Shape, p: &Point3) -> Real {
    match *shape {
        Shape::Sphere { radius } => p.coords.norm() - radius,
        Shape::Box { half_extents } => {
            let q = p.coords.abs() - Vec3::from(half_extents);
            q.map(|c| c.max(0.0)).norm() + q.max().min(0.0)
        }
        Shape::Cylinder {
            radius,
            half_height,
        } => {
            let d = [p.x.hypot(p.z) - radius, p.y.abs() - half_height];
            d[0].max(d[1]).min(0.0) + d[0].max(0.0).hypot(d[1].max(0.0))
        }
        Shape::Capsule {
            radius,
            half_height,
        } => {
            let axis = Point3::new(0.0, p.y.clamp(-half_height, half_height), 0.0);
            (p - axis).norm() - radius
        }
        Shape::Mesh { .. } => unreachable!(),
    }
}

#[test]
fn signed_distance_matches_closed_forms() {
    let shapes = [
        Shape::Sphere { radius: 0.3 },
        Shape::Box {
            half_extents: [0.3, 0.2, 0.1],
        },
        Shape::Cylinder {
            radius: 0.2,
            half_height: 0.3,
        },
        Shape::Capsule {
            radius: 0.15,
            half_height: 0.2,
        },
    ];
    let mut rng = rng();
    for shape in shapes {
        let b = build(&body(shape.clone()));
        let pose = b.pose(0.0);
        let mut inside = 0;
        for _ in 0..2000 {
            let local = Point3::from(Vec3::from_fn(|_, _| uniform(&mut rng, -0.6, 0.6)));
            let want = exact_distance(&shape, &local);
            let got = b.signed_distance(0.0, &(pose * local));
            assert!(
                (got - want).abs() < 1e-12,
                "{shape:?} at {local}: {got} != {want}"
            );
            assert!((b.signed_distance_local(&local) - want).abs() < 1e-12);
            inside += usize::from(want < 0.0);
        }
        assert!(inside > 20, "{shape:?}: too few inside points tested");
    }
}

#[test]
fn normals_point_outward() {
    let b = build(&body(Shape::Sphere { radius: 0.3 }));
    let pose = b.pose(0.0);
    let mut rng = rng();
    for _ in 0..200 {
        let dir = unit(&mut rng);
        for radius in [0.1, 0.3, 0.5] {
            let x = pose * Point3::from(dir * radius);
            let n = b.normal(0.0, &x);
            assert!((n - pose.rotation * dir).norm() < 1e-9, "{n} vs {dir}");
        }
    }
}

/// The box [-h, h] as 8 corners and 6 outward quads (OBJ numbering from 1).
fn cube(h: [Real; 3]) -> (Vec<[Real; 3]>, Vec<[usize; 4]>) {
    let corners = (0..8)
        .map(|i| {
            let s = |bit: usize| if i & bit == 0 { -1.0 } else { 1.0 };
            [s(1) * h[0], s(2) * h[1], s(4) * h[2]]
        })
        .collect();
    let quads = vec![
        [0, 4, 6, 2], // -x
        [1, 3, 7, 5], // +x
        [0, 1, 5, 4], // -y
        [2, 6, 7, 3], // +y
        [0, 2, 3, 1], // -z
        [4, 5, 7, 6], // +z
    ];
    (corners, quads)
}

fn triangles(quads: &[[usize; 4]]) -> Vec<[usize; 3]> {
    quads
        .iter()
        .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .collect()
}

fn write_obj(path: &Path, vertices: &[[Real; 3]], faces: &[Vec<usize>]) {
    let mut text = String::from("# written by tests/geometry.rs\no shape\n");
    for v in vertices {
        text += &format!("v {} {} {}\n", v[0], v[1], v[2]);
    }
    for f in faces {
        let ids: Vec<String> = f.iter().map(|i| (i + 1).to_string()).collect();
        text += &format!("f {}\n", ids.join(" "));
    }
    std::fs::write(path, text).unwrap();
}

fn stl_triangles(vertices: &[[Real; 3]], tris: &[[usize; 3]]) -> Vec<stl_io::Triangle> {
    let v = |i: usize| stl_io::Vector::new(vertices[i].map(|c| c as f32));
    tris.iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| Vec3::from(vertices[i]));
            let n = (b - a).cross(&(c - a)).normalize();
            stl_io::Triangle {
                normal: stl_io::Vector::new([n.x as f32, n.y as f32, n.z as f32]),
                vertices: [v(t[0]), v(t[1]), v(t[2])],
            }
        })
        .collect()
}

fn write_ascii_stl(path: &Path, vertices: &[[Real; 3]], tris: &[[usize; 3]]) {
    let mut text = String::from("solid cube\n");
    for t in stl_triangles(vertices, tris) {
        let n = t.normal.0;
        text += &format!(
            "  facet normal {} {} {}\n    outer loop\n",
            n[0], n[1], n[2]
        );
        for v in t.vertices {
            text += &format!("      vertex {} {} {}\n", v.0[0], v.0[1], v.0[2]);
        }
        text += "    endloop\n  endfacet\n";
    }
    text += "endsolid cube\n";
    std::fs::write(path, text).unwrap();
}

fn write_binary_stl(path: &Path, vertices: &[[Real; 3]], tris: &[[usize; 3]]) {
    let mut file = std::fs::File::create(path).unwrap();
    stl_io::write_stl(&mut file, stl_triangles(vertices, tris).iter()).unwrap();
}

fn mesh_body(path: &Path, scale: Real) -> Body {
    body(Shape::Mesh {
        path: path.to_path_buf(),
        scale,
    })
}

#[test]
fn cube_meshes_match_the_analytic_box() {
    let dir = tempfile::tempdir().unwrap();
    let h = [0.25, 0.125, 0.375];
    let (vertices, quads) = cube(h);
    let tris = triangles(&quads);
    let obj = dir.path().join("cube.obj");
    let quad_faces: Vec<Vec<usize>> = quads.iter().map(|q| q.to_vec()).collect();
    write_obj(&obj, &vertices, &quad_faces);
    let ascii = dir.path().join("cube_ascii.stl");
    write_ascii_stl(&ascii, &vertices, &tris);
    let binary = dir.path().join("cube_binary.STL");
    write_binary_stl(&binary, &vertices, &tris);
    // Inside-out triangles are turned the right way round.
    let inverted = dir.path().join("inverted.obj");
    let flipped: Vec<Vec<usize>> = tris.iter().map(|t| vec![t[0], t[2], t[1]]).collect();
    write_obj(&inverted, &vertices, &flipped);

    let scale = 2.0;
    let doubled = h.map(|c| c * scale);
    let analytic = build(&body(Shape::Box {
        half_extents: doubled,
    }));
    let pose = analytic.pose(0.0);
    let mut rng = rng();
    // Points in a box around the body, plus points near its faces, edges and corners.
    let points: Vec<Point3> = (0..3000)
        .map(|i| {
            let p = Vec3::from_fn(|k, _| uniform(&mut rng, -1.3, 1.3) * doubled[k]);
            let p = if i % 2 == 0 {
                p
            } else {
                Vec3::from_fn(|k, _| {
                    let snap = rng.random::<Real>() < 0.6;
                    if snap {
                        p[k].signum() * doubled[k] + uniform(&mut rng, -1e-3, 1e-3)
                    } else {
                        p[k]
                    }
                })
            };
            pose * Point3::from(p)
        })
        .collect();
    for path in [&obj, &ascii, &binary, &inverted] {
        let mesh = build(&mesh_body(path, scale));
        assert_eq!(mesh.name(), "mesh_1");
        let (lo, hi) = mesh.local_aabb();
        assert!((hi.coords - Vec3::from(doubled)).norm() < 1e-12);
        assert!((lo.coords + Vec3::from(doubled)).norm() < 1e-12);
        for x in &points {
            let (got, want) = (
                mesh.signed_distance(0.0, x),
                analytic.signed_distance(0.0, x),
            );
            assert!(
                (got - want).abs() < 1e-9,
                "{}: at {x}: mesh {got}, box {want}",
                path.display()
            );
        }
        let spacing = 0.05;
        let samples = mesh.sample_surface(spacing);
        for s in &samples {
            assert!(mesh.signed_distance_local(s).abs() < 1e-9);
            assert!(analytic.signed_distance_local(s).abs() < 1e-9);
        }
        let area =
            8.0 * (doubled[0] * doubled[1] + doubled[1] * doubled[2] + doubled[0] * doubled[2]);
        let d = doubled.into();
        check_samples(&mesh, spacing, area, (0.95, 1.1), |rng| {
            random_on_box(rng, &d)
        });
    }
}

/// An icosahedron subdivided `levels` times and pushed onto the sphere of radius `r`.
fn icosphere(r: Real, levels: usize) -> (Vec<[Real; 3]>, Vec<[usize; 3]>) {
    let g = (1.0 + 5.0_f64.sqrt()) / 2.0;
    let mut v: Vec<Vec3> = [
        [-1.0, g, 0.0],
        [1.0, g, 0.0],
        [-1.0, -g, 0.0],
        [1.0, -g, 0.0],
        [0.0, -1.0, g],
        [0.0, 1.0, g],
        [0.0, -1.0, -g],
        [0.0, 1.0, -g],
        [g, 0.0, -1.0],
        [g, 0.0, 1.0],
        [-g, 0.0, -1.0],
        [-g, 0.0, 1.0],
    ]
    .iter()
    .map(|p| Vec3::from(*p).normalize())
    .collect();
    let mut faces: Vec<[usize; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..levels {
        let mut mids = std::collections::HashMap::new();
        let mut mid = |a: usize, b: usize, v: &mut Vec<Vec3>| {
            *mids.entry((a.min(b), a.max(b))).or_insert_with(|| {
                v.push(((v[a] + v[b]) / 2.0).normalize());
                v.len() - 1
            })
        };
        faces = faces
            .iter()
            .flat_map(|&[a, b, c]| {
                let (ab, bc, ca) = (mid(a, b, &mut v), mid(b, c, &mut v), mid(c, a, &mut v));
                [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
            })
            .collect();
    }
    (v.iter().map(|p| (p * r).into()).collect(), faces)
}

#[test]
fn icosphere_mesh_is_sampled_without_holes_or_clumps() {
    let dir = tempfile::tempdir().unwrap();
    let r = 0.3;
    let spacing = 0.02;
    // Coarse triangles (edges ~ 4 spacings) and fine ones (edges ~ half a spacing). Every
    // vertex of a fine mesh that is half a spacing from the others is kept, so fine meshes get
    // more samples than area / spacing^2; the Akinci volumes account for that.
    for (levels, count) in [(2, (0.95, 1.6)), (4, (0.95, 4.0))] {
        let (vertices, tris) = icosphere(r, levels);
        let path = dir.path().join(format!("ico{levels}.obj"));
        let faces: Vec<Vec<usize>> = tris.iter().map(|t| t.to_vec()).collect();
        write_obj(&path, &vertices, &faces);
        let mut b = mesh_body(&path, 1.0);
        b.name = Some(format!("ico{levels}"));
        let mesh = build(&b);
        // The mesh as read (f32 coordinates), for drawing uniform surface points.
        let v32: Vec<Vec3> = vertices
            .iter()
            .map(|p| Vec3::from(p.map(|c| c as f32 as Real)))
            .collect();
        let areas: Vec<Real> = tris
            .iter()
            .map(|t| {
                0.5 * (v32[t[1]] - v32[t[0]])
                    .cross(&(v32[t[2]] - v32[t[0]]))
                    .norm()
            })
            .collect();
        let area: Real = areas.iter().sum();
        check_samples(&mesh, spacing, area, count, |rng| {
            let t = tris[pick(rng, &areas)];
            let (mut a, mut b) = (rng.random::<Real>(), rng.random::<Real>());
            if a + b > 1.0 {
                (a, b) = (1.0 - a, 1.0 - b);
            }
            Point3::from(v32[t[0]] + (v32[t[1]] - v32[t[0]]) * a + (v32[t[2]] - v32[t[0]]) * b)
        });
    }
}

#[test]
fn open_mesh_is_rejected() {
    let dir = tempfile::tempdir().unwrap();
    let (vertices, quads) = cube([0.5; 3]);
    let path = dir.path().join("open.obj");
    let faces: Vec<Vec<usize>> = quads[..5].iter().map(|q| q.to_vec()).collect();
    write_obj(&path, &vertices, &faces);
    let err = RigidBody::from_scene(&mesh_body(&path, 1.0), 0).unwrap_err();
    assert!(matches!(err, GeometryError::MeshNotClosed { .. }), "{err}");
    assert!(
        err.to_string().contains(&path.display().to_string()),
        "{err}"
    );
}

#[test]
fn bad_mesh_files_name_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.obj");
    let garbage_obj = dir.path().join("garbage.obj");
    std::fs::write(&garbage_obj, [0xff, 0xfe, 0x00, 0x9c, 0x80, 0x0a, 0xc3]).unwrap();
    let garbage_stl = dir.path().join("garbage.stl");
    std::fs::write(&garbage_stl, "this is not a mesh\n").unwrap();
    let empty_obj = dir.path().join("empty.obj");
    std::fs::write(&empty_obj, "# nothing here\nv 0 0 0\n").unwrap();
    let unsupported = dir.path().join("shape.ply");
    std::fs::write(&unsupported, "ply\n").unwrap();
    for path in [
        &missing,
        &garbage_obj,
        &garbage_stl,
        &empty_obj,
        &unsupported,
    ] {
        let err = RigidBody::from_scene(&mesh_body(path, 1.0), 3).unwrap_err();
        let msg = err.to_string();
        assert!(msg.contains(&path.display().to_string()), "{msg}");
        assert!(msg.contains("mesh_3"), "{msg}");
        eprintln!("{msg}");
    }
    let err = RigidBody::from_scene(&mesh_body(&missing, 1.0), 0).unwrap_err();
    assert!(matches!(err, GeometryError::MeshNotFound { .. }), "{err}");
    let err = RigidBody::from_scene(&mesh_body(&unsupported, 1.0), 0).unwrap_err();
    assert!(
        matches!(err, GeometryError::UnsupportedFormat { .. }),
        "{err}"
    );
    let err = RigidBody::from_scene(&mesh_body(&empty_obj, 1.0), 0).unwrap_err();
    assert!(matches!(err, GeometryError::EmptyMesh { .. }), "{err}");
}

#[test]
fn invalid_shapes_and_motions_are_errors() {
    let mut b = body(Shape::Sphere { radius: -1.0 });
    b.name = Some("ball".into());
    let err = RigidBody::from_scene(&b, 0).unwrap_err();
    assert!(matches!(err, GeometryError::InvalidShape { .. }), "{err}");
    assert!(err.to_string().contains("ball"), "{err}");
    b.shape = Shape::Sphere { radius: 1.0 };
    b.motion.keyframes = vec![
        Keyframe {
            t: 1.0,
            position: [0.0; 3],
            rotation: [0.0; 3],
        },
        Keyframe {
            t: 1.0,
            position: [1.0; 3],
            rotation: [0.0; 3],
        },
    ];
    let err = RigidBody::from_scene(&b, 0).unwrap_err();
    assert!(matches!(err, GeometryError::InvalidMotion { .. }), "{err}");
    b.motion.keyframes.truncate(1);
    assert!(RigidBody::from_scene(&b, 0).is_err());
}

/// The velocity of a point fixed in the body equals the time derivative of its world position.
fn check_velocity_is_pose_derivative(b: &RigidBody, t: Real) {
    let local = Point3::new(0.3, -0.4, 0.7);
    let dt = 1e-6;
    let x = b.pose(t) * local;
    let fd = (b.pose(t + dt) * local - b.pose(t - dt) * local) / (2.0 * dt);
    let v = b.velocity_at(t, &x);
    assert!(
        (fd - v).norm() < 1e-6 * (1.0 + v.norm()),
        "t = {t}: {v} vs {fd}"
    );
}

#[test]
fn constant_motion_moves_and_spins_about_the_origin() {
    let mut b = body(Shape::Box {
        half_extents: [0.1, 0.2, 0.3],
    });
    let still = build(&b);
    assert!(!still.is_moving());
    assert_eq!(
        still.velocity_at(3.0, &Point3::new(1.0, 2.0, 3.0)),
        Vec3::zeros()
    );
    b.motion.linear = [0.5, -1.0, 2.0];
    b.motion.angular = [0.0, 0.0, 2.0];
    let moving = build(&b);
    assert!(moving.is_moving());
    let rot0 = Rotation3::new(Vec3::from(b.rotation));
    for t in [0.0, 0.3, 1.7] {
        let pose = moving.pose(t);
        let origin = Vec3::from(b.position) + Vec3::from(b.motion.linear) * t;
        assert!((pose.translation.vector - origin).norm() < 1e-12);
        // Spinning about world z at 2 rad/s on top of the initial orientation.
        let want = Rotation3::from_axis_angle(&Vec3::z_axis(), 2.0 * t) * rot0;
        let local = Point3::new(0.1, 0.2, 0.3);
        assert!((pose.rotation * local - want * local).norm() < 1e-12);
        assert_eq!(moving.linear_velocity(t), Vec3::from(b.motion.linear));
        assert_eq!(moving.angular_velocity(t), Vec3::new(0.0, 0.0, 2.0));
        check_velocity_is_pose_derivative(&moving, t);
        // A point on the spin axis through the origin only translates.
        let on_axis = Point3::from(origin + Vec3::new(0.0, 0.0, 5.0));
        assert!((moving.velocity_at(t, &on_axis) - Vec3::from(b.motion.linear)).norm() < 1e-12);
        // The signed distance moves with the body.
        let inside = pose * Point3::new(0.05, 0.0, 0.0);
        assert!((moving.signed_distance(t, &inside) + 0.05).abs() < 1e-12);
    }
}

#[test]
fn keyframes_interpolate_and_hold() {
    let mut b = body(Shape::Sphere { radius: 0.1 });
    let keys = [
        (1.0, [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]),
        (2.0, [1.0, 2.0, 0.0], [0.0, 0.0, PI / 2.0]),
        (4.0, [1.0, 0.0, -2.0], [PI / 3.0, 0.0, 0.0]),
    ];
    b.motion.keyframes = keys
        .iter()
        .map(|&(t, position, rotation)| Keyframe {
            t,
            position,
            rotation,
        })
        .collect();
    let body = build(&b);
    assert!(body.is_moving());
    let q = |i: usize| UnitQuaternion::from_scaled_axis(Vec3::from(keys[i].2));
    let p = |i: usize| Vec3::from(keys[i].1);
    let same_pose = |t: Real, pos: Vec3, rot: UnitQuaternion<Real>| {
        let pose = body.pose(t);
        assert!((pose.translation.vector - pos).norm() < 1e-12, "t = {t}");
        assert!(pose.rotation.angle_to(&rot) < 1e-12, "t = {t}");
    };
    // Held before the first and after the last key, at rest.
    for (t, k) in [(0.0, 0), (1.0, 0), (4.0, 2), (9.0, 2)] {
        same_pose(t, p(k), q(k));
    }
    for t in [0.0, 0.5, 4.0, 9.0] {
        assert_eq!(body.linear_velocity(t), Vec3::zeros());
        assert_eq!(body.angular_velocity(t), Vec3::zeros());
    }
    // Linear in position and slerp in rotation in between.
    same_pose(1.5, (p(0) + p(1)) / 2.0, q(0).slerp(&q(1), 0.5));
    same_pose(2.5, p(1) * 0.75 + p(2) * 0.25, q(1).slerp(&q(2), 0.25));
    same_pose(3.0, (p(1) + p(2)) / 2.0, q(1).slerp(&q(2), 0.5));
    // Velocities are the segment's constant rates.
    assert!((body.linear_velocity(1.5) - (p(1) - p(0))).norm() < 1e-12);
    assert!((body.linear_velocity(3.0) - (p(2) - p(1)) / 2.0).norm() < 1e-12);
    assert!((body.angular_velocity(1.5) - Vec3::new(0.0, 0.0, PI / 2.0)).norm() < 1e-12);
    for t in [1.25, 1.5, 2.5, 3.9] {
        check_velocity_is_pose_derivative(&body, t);
    }
}
