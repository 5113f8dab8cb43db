//! The database file: one HDF5 file that h5py reads without eddy.
//!
//! ```text
//! /                        attributes: format = "eddy-abl-database", format_version = 1,
//!                          obstacle (str), fingerprint (str, SHA-256 of geometry and settings),
//!                          geometry_fingerprint (str), units (str), beta (f64),
//!                          layer_thickness (f64, m), spacing (f64, m), settings (str, TOML)
//! /points                  P x 3 f64, boundary points in the object's frame, m
//! /normals                 P x 3 f64, outward unit normals in the object's frame
//! /translation, /rotation  groups, attributes polar_samples, azimuth_samples (u64)
//!   polar_angles           n_polar f64, radians from +z, both poles included
//!   azimuth_angles         n_azimuth f64, radians from +x towards +y
//!   directions             D x 3 f64 unit vectors, D = n_polar * n_azimuth, row i * n_azimuth + j
//!   omega                  D x P x 3 f64, omega_pre per unit speed, object frame
//!   complete               D u8, 1 where the row was computed (all 1 in a finished database)
//! ```
//!
//! Translation row d holds omega_pre for the object moving with unit velocity along direction d
//! through still fluid (the precomputation holds the object and blows the free stream -d at
//! it); rotation row d for the object spinning at 1 rad/s about axis d in still fluid.

use std::path::Path;

use hdf5::types::VarLenUnicode;
use hdf5::{File, Group, H5Type};

use super::{AblError, Sampling};
use crate::{Point3, Real, Vec3};

/// Value of the root attribute `format`.
pub const ABL_FORMAT: &str = "eddy-abl-database";
/// Value of the root attribute `format_version`; raised when the layout changes.
pub const ABL_FORMAT_VERSION: i64 = 1;

/// Value of the root attribute `units`.
const UNITS: &str = "SI: points, spacing, layer_thickness in m; translation omega in 1/s per m/s \
                     of object velocity; rotation omega in 1/s per rad/s of angular velocity";

/// The two motions a database samples.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MotionKind {
    Translation,
    Rotation,
}

impl MotionKind {
    /// Both kinds, in file order.
    pub const ALL: [MotionKind; 2] = [MotionKind::Translation, MotionKind::Rotation];

    /// Name of the kind's group in the file.
    pub fn name(self) -> &'static str {
        match self {
            MotionKind::Translation => "translation",
            MotionKind::Rotation => "rotation",
        }
    }
}

/// The root attributes that describe how a database was made.
#[derive(Debug, Clone, PartialEq)]
pub struct AblHeader {
    /// The obstacle's name (informative).
    pub obstacle: String,
    /// Hash of the geometry and every precomputation setting: shards and resumed runs must match.
    pub fingerprint: String,
    /// Hash of the geometry alone ([`super::geometry_fingerprint`]): a scene's obstacle must match.
    pub geometry_fingerprint: String,
    /// Vortex gain beta of Eq. 1.
    pub beta: Real,
    /// Boundary-layer thickness l of Figure 5, m.
    pub layer_thickness: Real,
    /// Cell size of the precomputation grid, m.
    pub spacing: Real,
    /// The precomputation settings as TOML (informative).
    pub settings: String,
}

/// omega_pre for every sampled direction of one motion kind.
#[derive(Debug, Clone, PartialEq)]
pub struct DirectionTable {
    pub sampling: Sampling,
    /// Row-major `[row][point][component]`, `sampling.len() * P * 3` values.
    pub omega: Vec<Real>,
    /// Which rows were computed.
    pub complete: Vec<bool>,
}

impl DirectionTable {
    /// A table of `points` points with nothing computed yet.
    pub fn empty(sampling: Sampling, points: usize) -> Self {
        Self {
            sampling,
            omega: vec![0.0; sampling.len() * points * 3],
            complete: vec![false; sampling.len()],
        }
    }

    /// Stores the values of sample (i, j), and of every row of its pole when it is one.
    pub fn set(&mut self, i: usize, j: usize, values: &[Vec3]) {
        let s = self.sampling;
        let n = values.len() * 3;
        let cols: Vec<usize> = if s.is_pole(i) {
            (0..s.azimuth).collect()
        } else {
            vec![j]
        };
        for c in cols {
            let row = s.row(i, c);
            let dst = &mut self.omega[row * n..(row + 1) * n];
            for (d, v) in dst.chunks_exact_mut(3).zip(values) {
                d.copy_from_slice(v.as_slice());
            }
            self.complete[row] = true;
        }
    }

    /// The values of a row.
    pub fn row(&self, row: usize, points: usize) -> &[Real] {
        &self.omega[row * points * 3..(row + 1) * points * 3]
    }

    /// Sample (polar, azimuth) of every row not computed.
    pub fn missing(&self) -> Vec<(usize, usize)> {
        let a = self.sampling.azimuth;
        (0..self.sampling.len())
            .filter(|&r| !self.complete[r])
            .map(|r| (r / a, r % a))
            .collect()
    }
}

/// A whole database in memory, possibly with rows not yet computed (a shard).
#[derive(Debug, Clone, PartialEq)]
pub struct AblData {
    pub header: AblHeader,
    pub points: Vec<Point3>,
    pub normals: Vec<Vec3>,
    pub translation: DirectionTable,
    pub rotation: DirectionTable,
}

type Failure = String;

fn ctx<T>(r: hdf5::Result<T>, what: &str) -> Result<T, Failure> {
    r.map_err(|e| format!("{what}: {e}"))
}

impl AblData {
    /// The table of one motion kind.
    pub fn table(&self, kind: MotionKind) -> &DirectionTable {
        match kind {
            MotionKind::Translation => &self.translation,
            MotionKind::Rotation => &self.rotation,
        }
    }

    /// The table of one motion kind, mutably.
    pub fn table_mut(&mut self, kind: MotionKind) -> &mut DirectionTable {
        match kind {
            MotionKind::Translation => &mut self.translation,
            MotionKind::Rotation => &mut self.rotation,
        }
    }

    /// Checks that the arrays agree with each other and hold what a lookup can use: finite
    /// points, unit normals, finite values in every computed row, and positive lengths.
    pub fn check(&self) -> Result<(), String> {
        let p = self.points.len();
        if p == 0 {
            return Err("no boundary points".into());
        }
        if self.normals.len() != p {
            return Err(format!("{} normals for {p} points", self.normals.len()));
        }
        let h = &self.header;
        for (name, v) in [
            ("spacing", h.spacing),
            ("layer_thickness", h.layer_thickness),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("attribute {name} = {v}: must be positive"));
            }
        }
        if !h.beta.is_finite() {
            return Err(format!("attribute beta = {}: must be finite", h.beta));
        }
        if let Some(i) = self
            .points
            .iter()
            .position(|x| !x.iter().all(|c| c.is_finite()))
        {
            return Err(format!(
                "point {i} is {:?}: not finite",
                self.points[i].coords.as_slice()
            ));
        }
        // Outward unit normals: a zero or unnormalised normal means a broken precomputation.
        if let Some(i) = self.normals.iter().position(|n| {
            let off = (n.norm() - 1.0).abs();
            off.is_nan() || off >= 1e-6
        }) {
            return Err(format!(
                "normal {i} is {:?}: not a unit vector",
                self.normals[i].as_slice()
            ));
        }
        for kind in MotionKind::ALL {
            let t = self.table(kind);
            Sampling::new(t.sampling.polar, t.sampling.azimuth)?;
            let d = t.sampling.len();
            if t.omega.len() != d * p * 3 || t.complete.len() != d {
                return Err(format!(
                    "{}: {} values and {} completion flags for {d} directions x {p} points",
                    kind.name(),
                    t.omega.len(),
                    t.complete.len()
                ));
            }
            for (row, _) in t.complete.iter().enumerate().filter(|(_, &c)| c) {
                let values = t.row(row, p);
                if let Some(k) = values.iter().position(|v| !v.is_finite()) {
                    let s = t.sampling.azimuth;
                    return Err(format!(
                        "{}: direction (polar {}, azimuth {}) holds {} at point {}",
                        kind.name(),
                        row / s,
                        row % s,
                        values[k],
                        k / 3
                    ));
                }
            }
        }
        Ok(())
    }

    /// Writes the file under a temporary sibling name and renames it, so `path` is never a
    /// half-written database. HDF5 holds a global lock: call from one thread at a time.
    pub fn write(&self, path: &Path) -> Result<(), AblError> {
        self.check().map_err(AblError::Invalid)?;
        let fail = |message: String| AblError::Write {
            path: path.to_path_buf(),
            message,
        };
        let name = path
            .file_name()
            .ok_or_else(|| fail("the path has no file name".into()))?;
        let tmp = path.with_file_name(format!(".{}.tmp", name.to_string_lossy()));
        let result = self.write_hdf5(&tmp).map_err(fail).and_then(|()| {
            std::fs::rename(&tmp, path)
                .map_err(|e| fail(format!("renaming the temporary file: {e}")))
        });
        if result.is_err() {
            let _ = std::fs::remove_file(&tmp);
        }
        result
    }

    fn write_hdf5(&self, path: &Path) -> Result<(), Failure> {
        let file = ctx(File::create(path), "creating the file")?;
        {
            let root: &Group = &file;
            let h = &self.header;
            for (name, text) in [
                ("format", ABL_FORMAT),
                ("obstacle", h.obstacle.as_str()),
                ("fingerprint", h.fingerprint.as_str()),
                ("geometry_fingerprint", h.geometry_fingerprint.as_str()),
                ("units", UNITS),
                ("settings", h.settings.as_str()),
            ] {
                write_str_attr(root, name, text)?;
            }
            write_attr(root, "format_version", &ABL_FORMAT_VERSION)?;
            write_attr(root, "beta", &h.beta)?;
            write_attr(root, "layer_thickness", &h.layer_thickness)?;
            write_attr(root, "spacing", &h.spacing)?;
            let p = self.points.len();
            let pts: Vec<Real> = self
                .points
                .iter()
                .flat_map(|x| x.coords.data.0[0])
                .collect();
            let nrm: Vec<Real> = self.normals.iter().flat_map(|n| n.data.0[0]).collect();
            write_data(root, "points", &pts, &[p, 3])?;
            write_data(root, "normals", &nrm, &[p, 3])?;
            for kind in MotionKind::ALL {
                let t = self.table(kind);
                let s = t.sampling;
                let g = ctx(root.create_group(kind.name()), "creating a group")?;
                write_attr(&g, "polar_samples", &(s.polar as u64))?;
                write_attr(&g, "azimuth_samples", &(s.azimuth as u64))?;
                let polar: Vec<Real> = (0..s.polar).map(|i| s.polar_angle(i)).collect();
                let azimuth: Vec<Real> = (0..s.azimuth).map(|j| s.azimuth_angle(j)).collect();
                let dirs: Vec<Real> = (0..s.polar)
                    .flat_map(|i| (0..s.azimuth).flat_map(move |j| s.direction(i, j).data.0[0]))
                    .collect();
                write_data(&g, "polar_angles", &polar, &[s.polar])?;
                write_data(&g, "azimuth_angles", &azimuth, &[s.azimuth])?;
                write_data(&g, "directions", &dirs, &[s.len(), 3])?;
                write_data(&g, "omega", &t.omega, &[s.len(), p, 3])?;
                let done: Vec<u8> = t.complete.iter().map(|&c| u8::from(c)).collect();
                write_data(&g, "complete", &done, &[s.len()])?;
            }
        }
        ctx(file.close(), "closing the file")
    }

    /// Reads a database or a shard of one, checking its format, version and array shapes (not
    /// its completeness: see [`super::AblDatabase::open`]).
    pub fn read(path: &Path) -> Result<Self, AblError> {
        // HDF5 says "not an HDF5 file" of a file that is not there: ask the file system first.
        std::fs::metadata(path).map_err(|cause| AblError::Missing {
            path: path.to_path_buf(),
            cause,
        })?;
        let file = File::open(path).map_err(|e| AblError::Unreadable {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
        let corrupt = |what: String| AblError::Corrupt {
            path: path.to_path_buf(),
            what,
        };
        match read_str_attr(&file, "format") {
            Ok(f) if f == ABL_FORMAT => {}
            Ok(f) => {
                return Err(AblError::Foreign {
                    path: path.to_path_buf(),
                    found: format!("\"{f}\""),
                })
            }
            Err(_) => {
                return Err(AblError::Foreign {
                    path: path.to_path_buf(),
                    found: "missing".into(),
                })
            }
        }
        let version: i64 = read_attr(&file, "format_version").map_err(corrupt)?;
        if version != ABL_FORMAT_VERSION {
            return Err(AblError::Version {
                path: path.to_path_buf(),
                found: version,
            });
        }
        read_body(&file).map_err(corrupt)
    }
}

fn read_body(file: &File) -> Result<AblData, Failure> {
    let header = AblHeader {
        obstacle: read_str_attr(file, "obstacle")?,
        fingerprint: read_str_attr(file, "fingerprint")?,
        geometry_fingerprint: read_str_attr(file, "geometry_fingerprint")?,
        beta: read_attr(file, "beta")?,
        layer_thickness: read_attr(file, "layer_thickness")?,
        spacing: read_attr(file, "spacing")?,
        settings: read_str_attr(file, "settings")?,
    };
    let pts: Vec<Real> = read_data(file, "points", None)?;
    let p = pts.len() / 3;
    let nrm: Vec<Real> = read_data(file, "normals", Some(&[p, 3]))?;
    let triples = |v: &[Real]| -> Vec<Vec3> {
        v.chunks_exact(3)
            .map(|c| Vec3::new(c[0], c[1], c[2]))
            .collect()
    };
    let mut tables = Vec::new();
    for kind in MotionKind::ALL {
        let name = kind.name();
        let g = ctx(file.group(name), &format!("group /{name} missing"))?;
        let polar: u64 = read_attr(&g, "polar_samples")?;
        let azimuth: u64 = read_attr(&g, "azimuth_samples")?;
        let sampling = Sampling::new(polar as usize, azimuth as usize)?;
        let d = sampling.len();
        let omega = read_data(&g, "omega", Some(&[d, p, 3])).map_err(|e| format!("/{name}/{e}"))?;
        let done: Vec<u8> =
            read_data(&g, "complete", Some(&[d])).map_err(|e| format!("/{name}/{e}"))?;
        check_directions(&g, sampling).map_err(|e| format!("/{name}/{e}"))?;
        tables.push(DirectionTable {
            sampling,
            omega,
            complete: done.iter().map(|&c| c != 0).collect(),
        });
    }
    let rotation = tables.pop().ok_or("no rotation table")?;
    let translation = tables.pop().ok_or("no translation table")?;
    let data = AblData {
        header,
        points: triples(&pts).into_iter().map(Point3::from).collect(),
        normals: triples(&nrm),
        translation,
        rotation,
    };
    data.check()?;
    Ok(data)
}

/// The stored polar and azimuth angles and directions must be the ones the sampling defines
/// (this eddy's row order and angle conventions): a table written in another order would be
/// looked up at the wrong directions without a sign.
fn check_directions(g: &Group, s: Sampling) -> Result<(), Failure> {
    let close = |a: Real, b: Real| (a - b).abs() <= 1e-9 * (1.0 + b.abs());
    let polar: Vec<Real> = read_data(g, "polar_angles", Some(&[s.polar]))?;
    if let Some(i) = (0..s.polar).find(|&i| !close(polar[i], s.polar_angle(i))) {
        return Err(format!(
            "polar_angles[{i}] = {}, expected {} (both poles included, from +z)",
            polar[i],
            s.polar_angle(i)
        ));
    }
    let azimuth: Vec<Real> = read_data(g, "azimuth_angles", Some(&[s.azimuth]))?;
    if let Some(j) = (0..s.azimuth).find(|&j| !close(azimuth[j], s.azimuth_angle(j))) {
        return Err(format!(
            "azimuth_angles[{j}] = {}, expected {} (increasing from +x towards +y)",
            azimuth[j],
            s.azimuth_angle(j)
        ));
    }
    let dirs: Vec<Real> = read_data(g, "directions", Some(&[s.len(), 3]))?;
    for i in 0..s.polar {
        for j in 0..s.azimuth {
            let r = s.row(i, j);
            let want = s.direction(i, j);
            if (0..3).any(|c| !close(dirs[3 * r + c], want[c])) {
                return Err(format!(
                    "directions[{r}] = {:?} disagrees with polar_angles[{i}] and \
                     azimuth_angles[{j}] ({:?})",
                    &dirs[3 * r..3 * r + 3],
                    want.as_slice()
                ));
            }
        }
    }
    Ok(())
}

fn write_str_attr(loc: &Group, name: &str, text: &str) -> Result<(), Failure> {
    let what = format!("writing attribute {name}");
    let v: VarLenUnicode = text.parse().map_err(|e| format!("{what}: {e}"))?;
    let attr = ctx(
        loc.new_attr::<VarLenUnicode>().shape(()).create(name),
        &what,
    )?;
    ctx(attr.as_writer().write_scalar(&v), &what)
}

fn write_attr<T: H5Type>(loc: &Group, name: &str, v: &T) -> Result<(), Failure> {
    let what = format!("writing attribute {name}");
    let attr = ctx(loc.new_attr::<T>().shape(()).create(name), &what)?;
    ctx(attr.as_writer().write_scalar(v), &what)
}

fn write_data<T: H5Type>(
    loc: &Group,
    name: &str,
    data: &[T],
    shape: &[usize],
) -> Result<(), Failure> {
    let what = format!("writing dataset {name}");
    // Chunked (one direction per chunk for the tables) with HDF5's Fletcher-32 checksum, which
    // h5py reads transparently: a flipped byte makes the read fail instead of a wrong value.
    let builder = loc.new_dataset::<T>().shape(shape);
    let ds = if shape.iter().all(|&n| n > 0) {
        let mut chunk = shape.to_vec();
        if chunk.len() == 3 {
            chunk[0] = 1;
        }
        ctx(builder.chunk(chunk).fletcher32().create(name), &what)?
    } else {
        ctx(builder.create(name), &what)?
    };
    if !data.is_empty() {
        ctx(ds.as_writer().write_raw(data), &what)?;
    }
    Ok(())
}

fn read_str_attr(loc: &Group, name: &str) -> Result<String, Failure> {
    let attr = ctx(loc.attr(name), &format!("attribute {name} missing"))?;
    let v: VarLenUnicode = ctx(
        attr.read_scalar(),
        &format!("attribute {name} is not a string"),
    )?;
    Ok(v.as_str().to_owned())
}

fn read_attr<T: H5Type>(loc: &Group, name: &str) -> Result<T, Failure> {
    let attr = ctx(loc.attr(name), &format!("attribute {name} missing"))?;
    ctx(attr.read_scalar(), &format!("attribute {name} unreadable"))
}

/// Reads a dataset, checking its shape when `shape` is given.
fn read_data<T: H5Type>(
    loc: &Group,
    name: &str,
    shape: Option<&[usize]>,
) -> Result<Vec<T>, Failure> {
    let ds = ctx(loc.dataset(name), &format!("dataset {name} missing"))?;
    let found = ds.shape();
    if let Some(expected) = shape {
        if found != expected {
            return Err(format!(
                "dataset {name} has shape {found:?}, expected {expected:?}"
            ));
        }
    } else if found.len() != 2 || found[1] != 3 {
        return Err(format!(
            "dataset {name} has shape {found:?}, expected [P, 3]"
        ));
    }
    ctx(ds.read_raw(), &format!("reading dataset {name}"))
}
