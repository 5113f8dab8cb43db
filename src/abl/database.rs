//! A finished database opened for lookups: bilinear spherical interpolation of the translation
//! and rotation tables, scaled by the magnitudes and summed (Pfaff et al. 2009, section 5.1,
//! "Applying the precomputed set").

use std::path::{Path, PathBuf};

use nalgebra::Isometry3;
use rayon::prelude::*;

use super::{geometry_fingerprint, AblData, AblError, AblHeader, MotionKind, Sampling};
use crate::geometry::Shape;
use crate::{Point3, Real, Vec3};

/// Points per parallel task of a lookup: large enough that a task outweighs its scheduling.
const CHUNK: usize = 2048;

/// Speeds below this (m/s or rad/s) contribute nothing: their direction is undefined.
const TINY_SPEED: Real = 1e-300;

/// A complete, validated ABL database.
#[derive(Debug, Clone)]
pub struct AblDatabase {
    path: PathBuf,
    data: AblData,
}

impl AblDatabase {
    /// Opens and validates `path`: format, version, array shapes, every direction computed,
    /// and, when `obstacle` is given, that its geometry fingerprint matches the database's.
    pub fn open(path: &Path, obstacle: Option<&Shape>) -> Result<Self, AblError> {
        let data = AblData::read(path)?;
        for kind in MotionKind::ALL {
            let missing = data.table(kind).missing();
            if let Some(&(polar, azimuth)) = missing.first() {
                return Err(AblError::Incomplete {
                    path: path.to_path_buf(),
                    kind: kind.name(),
                    count: missing.len(),
                    polar,
                    azimuth,
                });
            }
        }
        if let Some(shape) = obstacle {
            let expected = geometry_fingerprint(shape)?;
            if expected != data.header.geometry_fingerprint {
                return Err(AblError::WrongObstacle {
                    path: path.to_path_buf(),
                    stored_name: data.header.obstacle.clone(),
                    stored: data.header.geometry_fingerprint.clone(),
                    expected,
                });
            }
        }
        Ok(Self {
            path: path.to_path_buf(),
            data,
        })
    }

    /// The file it was read from.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// How the database was made.
    pub fn header(&self) -> &AblHeader {
        &self.data.header
    }

    /// Everything it holds.
    pub fn data(&self) -> &AblData {
        &self.data
    }

    /// Boundary points in the object's frame, m.
    pub fn points(&self) -> &[Point3] {
        &self.data.points
    }

    /// Outward unit normals in the object's frame.
    pub fn normals(&self) -> &[Vec3] {
        &self.data.normals
    }

    /// Number of boundary points.
    pub fn len(&self) -> usize {
        self.data.points.len()
    }

    /// Never true for an opened database (it has at least one point).
    pub fn is_empty(&self) -> bool {
        self.data.points.is_empty()
    }

    /// The direction sampling of a motion kind.
    pub fn sampling(&self, kind: MotionKind) -> Sampling {
        self.data.table(kind).sampling
    }

    /// omega_pre at every boundary point, object frame, for the object moving with `linear`
    /// (m/s) relative to the surrounding fluid and spinning with `angular` (rad/s), both in the
    /// object's frame: interpolated per unit speed for each direction, times the magnitude,
    /// translation plus rotation.
    pub fn lookup(&self, linear: &Vec3, angular: &Vec3) -> Vec<Vec3> {
        let mut out = vec![Vec3::zeros(); self.len()];
        self.lookup_into(linear, angular, &mut out);
        out
    }

    /// [`Self::lookup`] into `out` (one entry per boundary point), without allocating.
    ///
    /// # Panics
    /// If `out.len()` is not the number of boundary points.
    pub fn lookup_into(&self, linear: &Vec3, angular: &Vec3, out: &mut [Vec3]) {
        assert_eq!(out.len(), self.len(), "one output per boundary point");
        let p = self.len();
        // Up to eight (row slice, weight) terms: four per motion kind.
        let mut terms: Vec<(&[Real], Real)> = Vec::with_capacity(8);
        for (kind, v) in [
            (MotionKind::Translation, linear),
            (MotionKind::Rotation, angular),
        ] {
            let mut speed = v.norm();
            if speed.is_nan() || speed <= TINY_SPEED {
                continue;
            }
            let direction = if speed.is_finite() {
                v / speed
            } else {
                // |v|^2 overflowed: scale by the largest component first, so the direction
                // is kept (v / inf would be zero and the lookup silently zero).
                let scaled = v / v.amax();
                speed = v.amax() * scaled.norm();
                scaled.normalize()
            };
            let table = self.data.table(kind);
            for (row, w) in table.sampling.weights(&direction) {
                if w != 0.0 {
                    terms.push((table.row(row, p), w * speed));
                }
            }
        }
        out.par_chunks_mut(CHUNK)
            .enumerate()
            .for_each(|(c, chunk)| {
                let base = c * CHUNK * 3;
                for (k, o) in chunk.iter_mut().enumerate() {
                    let at = base + 3 * k;
                    let mut acc = [0.0; 3];
                    for (row, w) in &terms {
                        let r = &row[at..at + 3];
                        acc[0] += w * r[0];
                        acc[1] += w * r[1];
                        acc[2] += w * r[2];
                    }
                    *o = Vec3::from(acc);
                }
            });
    }

    /// omega_pre at every boundary point in the world frame for the object at `pose`, moving
    /// with the world-frame `linear` velocity relative to the fluid and `angular` velocity; the
    /// points themselves are at `pose * points()`.
    pub fn lookup_world(&self, pose: &Isometry3<Real>, linear: &Vec3, angular: &Vec3) -> Vec<Vec3> {
        let r = pose.rotation;
        let mut out = self.lookup(
            &r.inverse_transform_vector(linear),
            &r.inverse_transform_vector(angular),
        );
        out.par_iter_mut().for_each(|w| *w = r * *w);
        out
    }
}
