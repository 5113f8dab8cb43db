//! Closed triangle meshes from OBJ and STL files, and their surface samples.
//!
//! Signed distance on a mesh is only meaningful when the mesh is watertight and its triangles
//! face outward (parry decides inside/outside from angle-weighted pseudo-normals), so loading
//! welds identical vertices, rejects open or non-manifold meshes, and turns inside-out meshes
//! the right way round.

use std::collections::HashMap;
use std::io::Cursor;
use std::path::Path;

use parry3d_f64::math::Vector as GVec;
use parry3d_f64::shape::{TriMesh, TriMeshFlags};
use rayon::prelude::*;

use super::sampling::{parts, thin};
use super::GeometryError;
use crate::{Point3, Real};

/// Vertices and triangles as read, before welding.
type Soup = (Vec<[Real; 3]>, Vec<[u32; 3]>);

/// Names the body and file in errors.
struct Source<'a> {
    body: &'a str,
    path: &'a Path,
}

impl Source<'_> {
    fn parse(&self, message: String) -> GeometryError {
        GeometryError::MeshParse {
            body: self.body.to_string(),
            path: self.path.to_path_buf(),
            message,
        }
    }

    fn not_closed(&self, problem: String) -> GeometryError {
        GeometryError::MeshNotClosed {
            body: self.body.to_string(),
            path: self.path.to_path_buf(),
            problem,
        }
    }

    fn io(&self, e: std::io::Error) -> GeometryError {
        let (body, path) = (self.body.to_string(), self.path.to_path_buf());
        if e.kind() == std::io::ErrorKind::NotFound {
            GeometryError::MeshNotFound { body, path }
        } else {
            GeometryError::MeshUnreadable {
                body,
                path,
                reason: e.to_string(),
            }
        }
    }
}

/// Loads `path` (.obj or .stl), scales it by `scale`, and checks that it is closed. `body` names
/// the body in errors.
pub(crate) fn load(body: &str, path: &Path, scale: Real) -> Result<TriMesh, GeometryError> {
    let src = Source { body, path };
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    if ext != "obj" && ext != "stl" {
        return Err(GeometryError::UnsupportedFormat {
            body: body.to_string(),
            path: path.to_path_buf(),
            ext,
        });
    }
    let bytes = std::fs::read(path).map_err(|e| src.io(e))?;
    let (vertices, triangles) = if ext == "obj" {
        parse_obj(&bytes)
    } else {
        parse_stl(&bytes)
    }
    .map_err(|m| src.parse(m))?;
    if let Some(bad) = triangles
        .iter()
        .flatten()
        .find(|&&i| i as usize >= vertices.len())
    {
        return Err(src.parse(format!(
            "a face refers to vertex {bad}, but the file has {} vertices",
            vertices.len()
        )));
    }
    let vertices: Vec<[Real; 3]> = vertices.iter().map(|v| v.map(|c| c * scale)).collect();
    if vertices.iter().flatten().any(|c| !c.is_finite()) {
        return Err(src.parse("a vertex coordinate is not finite".into()));
    }
    let (vertices, mut triangles) = weld(&vertices, &triangles);
    if triangles.is_empty() {
        return Err(GeometryError::EmptyMesh {
            body: body.to_string(),
            path: path.to_path_buf(),
        });
    }
    check_closed(&triangles).map_err(|m| src.not_closed(m))?;
    let volume = signed_volume(&vertices, &triangles);
    if volume.abs() <= 1e-12 * bounding_extent(&vertices).powi(3) {
        return Err(src.not_closed("it encloses no volume".into()));
    }
    if volume < 0.0 {
        tracing::warn!(
            "body '{body}': mesh {} faces inward; flipping its triangles",
            path.display()
        );
        for t in &mut triangles {
            t.swap(1, 2);
        }
    }
    let vertices = vertices.iter().map(|v| GVec::from_array(*v)).collect();
    TriMesh::with_flags(
        vertices,
        triangles,
        TriMeshFlags::ORIENTED | TriMeshFlags::MERGE_DUPLICATE_VERTICES,
    )
    .map_err(|e| src.parse(e.to_string()))
}

/// Reads every object of an OBJ file, polygons fanned into triangles; materials are ignored.
fn parse_obj(bytes: &[u8]) -> Result<Soup, String> {
    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, _materials) = tobj::load_obj_buf(&mut Cursor::new(bytes), &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|e| e.to_string())?;
    let mut vertices = Vec::new();
    let mut triangles = Vec::new();
    for model in &models {
        let offset = vertices.len() as u32;
        let mesh = &model.mesh;
        vertices.extend(
            mesh.positions
                .chunks_exact(3)
                .map(|c| [c[0] as Real, c[1] as Real, c[2] as Real]),
        );
        triangles.extend(
            mesh.indices
                .chunks_exact(3)
                .map(|t| [t[0] + offset, t[1] + offset, t[2] + offset]),
        );
    }
    Ok((vertices, triangles))
}

/// Reads an ASCII or binary STL. A binary file is recognised by its size (84 + 50 bytes per
/// triangle), even when its free-form header starts with "solid" as some exporters write.
fn parse_stl(bytes: &[u8]) -> Result<Soup, String> {
    let announced = bytes
        .get(80..84)
        .map(|c| 84 + 50 * u32::from_le_bytes([c[0], c[1], c[2], c[3]]) as u64);
    let is_binary = announced == Some(bytes.len() as u64);
    let mesh = if is_binary {
        // stl_io takes anything that starts with "solid " for ASCII.
        let mut patched = bytes.to_vec();
        patched[0] = b'#';
        stl_io::read_stl(&mut Cursor::new(patched))
    } else if bytes.starts_with(b"solid") {
        stl_io::read_stl(&mut Cursor::new(bytes))
    } else {
        return Err(format!(
            "neither ASCII STL (it does not start with \"solid\") nor binary STL (it has {} \
             bytes, {})",
            bytes.len(),
            match announced {
                Some(n) => format!("its header announces {n}"),
                None => "fewer than the 84 of a header".into(),
            }
        ));
    }
    .map_err(|e| e.to_string())?;
    let vertices = mesh
        .vertices
        .iter()
        .map(|v| v.0.map(|c| c as Real))
        .collect();
    let triangles = mesh
        .faces
        .iter()
        .map(|f| f.vertices.map(|i| i as u32))
        .collect();
    Ok((vertices, triangles))
}

/// Merges bit-identical vertices (OBJ and STL repeat them per face) and drops triangles that
/// thereby lose a corner.
fn weld(vertices: &[[Real; 3]], triangles: &[[u32; 3]]) -> (Vec<[Real; 3]>, Vec<[u32; 3]>) {
    let mut index: HashMap<[u64; 3], u32> = HashMap::new();
    let mut welded = Vec::new();
    // `+ 0.0` turns -0.0 into 0.0 so the two weld.
    let remap: Vec<u32> = vertices
        .iter()
        .map(|v| {
            let key = v.map(|c| (c + 0.0).to_bits());
            *index.entry(key).or_insert_with(|| {
                welded.push(*v);
                welded.len() as u32 - 1
            })
        })
        .collect();
    let triangles = triangles
        .iter()
        .map(|t| t.map(|i| remap[i as usize]))
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[2] != t[0])
        .collect();
    (welded, triangles)
}

/// Checks that every edge is used exactly once in each direction: no holes, no edge shared by
/// more than two triangles, neighbours facing the same way.
fn check_closed(triangles: &[[u32; 3]]) -> Result<(), String> {
    let mut directed: HashMap<(u32, u32), u32> = HashMap::new();
    for t in triangles {
        for k in 0..3 {
            *directed.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
        }
    }
    let open = directed
        .keys()
        .filter(|(a, b)| !directed.contains_key(&(*b, *a)))
        .count();
    let repeated = directed.values().filter(|&&n| n > 1).count();
    let mut problems = Vec::new();
    if open > 0 {
        problems.push(format!(
            "{open} edges border a hole (they have one triangle)"
        ));
    }
    if repeated > 0 {
        problems.push(format!(
            "{repeated} edges are shared by more than two triangles or by neighbours facing \
             opposite ways"
        ));
    }
    if problems.is_empty() {
        Ok(())
    } else {
        Err(problems.join("; "))
    }
}

/// Volume enclosed by a closed mesh, positive when its triangles face outward.
fn signed_volume(vertices: &[[Real; 3]], triangles: &[[u32; 3]]) -> Real {
    triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| nalgebra::Vector3::from(vertices[i as usize]));
            a.dot(&b.cross(&c)) / 6.0
        })
        .sum()
}

/// Largest side of the bounding box.
fn bounding_extent(vertices: &[[Real; 3]]) -> Real {
    (0..3)
        .map(|axis| {
            let (lo, hi) = vertices.iter().fold((Real::MAX, Real::MIN), |(lo, hi), v| {
                (lo.min(v[axis]), hi.max(v[axis]))
            });
            hi - lo
        })
        .fold(0.0, Real::max)
}

/// Surface samples of a mesh: every vertex, points at most `spacing` apart along every edge,
/// and a lattice inside every triangle, then thinned to at least `spacing / 2` apart.
///
/// The lattice of a triangle steps along its two sides that meet at the corner opposite its
/// longest side, so a right triangle (half a quad) gets a square grid of about one point per
/// spacing^2 rather than the denser grid that stepping along the hypotenuse would give.
pub(crate) fn sample_mesh(mesh: &TriMesh, spacing: Real) -> Vec<Point3> {
    let v: Vec<Point3> = mesh
        .vertices()
        .iter()
        .map(|p| Point3::new(p.x, p.y, p.z))
        .collect();
    let mut edges: Vec<(u32, u32)> = mesh
        .indices()
        .iter()
        .flat_map(|t| (0..3).map(move |k| (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]))))
        .collect();
    edges.sort_unstable();
    edges.dedup();
    let mut candidates = v.clone();
    for &(a, b) in &edges {
        let (a, b) = (v[a as usize], v[b as usize]);
        let n = parts((b - a).norm(), spacing);
        candidates.extend((1..n).map(|k| a + (b - a) * (k as Real / n as Real)));
    }
    let interiors: Vec<Vec<Point3>> = mesh
        .indices()
        .par_iter()
        .map(|t| triangle_interior(t.map(|i| v[i as usize]), spacing))
        .collect();
    candidates.extend(interiors.into_iter().flatten());
    thin(candidates, 0.5 * spacing)
}

/// Lattice points strictly inside a triangle, stepping at most `spacing` along the two sides
/// that meet at the corner opposite the longest side.
fn triangle_interior(p: [Point3; 3], spacing: Real) -> Vec<Point3> {
    let opposite_len = |k: usize| (p[(k + 1) % 3] - p[(k + 2) % 3]).norm();
    let o = (0..3)
        .max_by(|&a, &b| opposite_len(a).total_cmp(&opposite_len(b)))
        .unwrap_or(0);
    let (origin, ea, eb) = (p[o], p[(o + 1) % 3] - p[o], p[(o + 2) % 3] - p[o]);
    let (na, nb) = (parts(ea.norm(), spacing), parts(eb.norm(), spacing));
    let mut out = Vec::new();
    for i in 1..na {
        let u = i as Real / na as Real;
        for j in 1..nb {
            let w = j as Real / nb as Real;
            if u + w < 1.0 - 1e-9 {
                out.push(origin + ea * u + eb * w);
            }
        }
    }
    out
}
