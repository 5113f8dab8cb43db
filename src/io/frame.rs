//! One output frame of particle data, borrowed from the solver so writing copies nothing up front.

use std::collections::HashSet;
use std::path::Path;

use super::IoError;
use crate::{Real, Vec3};

/// Per-particle values of one field.
#[derive(Clone, Copy, Debug)]
pub enum FieldData<'a> {
    /// One value per particle.
    Scalar(&'a [Real]),
    /// One 3-vector per particle.
    Vector(&'a [Vec3]),
}

impl FieldData<'_> {
    /// Number of particles the field covers.
    pub fn len(&self) -> usize {
        match self {
            FieldData::Scalar(v) => v.len(),
            FieldData::Vector(v) => v.len(),
        }
    }

    /// True when the field covers no particle.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// A named per-particle field (density, pressure, velocity, ...).
#[derive(Clone, Copy, Debug)]
pub struct Field<'a> {
    pub name: &'a str,
    pub data: FieldData<'a>,
}

impl<'a> Field<'a> {
    /// A scalar field.
    pub fn scalar(name: &'a str, values: &'a [Real]) -> Self {
        Field {
            name,
            data: FieldData::Scalar(values),
        }
    }

    /// A 3-vector field.
    pub fn vector(name: &'a str, values: &'a [Vec3]) -> Self {
        Field {
            name,
            data: FieldData::Vector(values),
        }
    }
}

/// The particles of one output frame: positions plus any number of fields, all of equal length.
#[derive(Clone, Debug)]
pub struct ParticleFrame<'a> {
    /// Solver step the frame was taken at.
    pub step: u64,
    /// Simulation time of the frame.
    pub time: Real,
    pub positions: &'a [Vec3],
    pub fields: Vec<Field<'a>>,
}

impl ParticleFrame<'_> {
    /// Checks what every writer needs before it touches the file: finite time, one value per
    /// particle in every field, and field names that are non-empty, unique, not `reserved`, and
    /// free of `/` (an HDF5 path separator) and control characters.
    pub(crate) fn validate(&self, path: &Path, reserved: &str) -> Result<(), IoError> {
        if !self.time.is_finite() {
            return Err(IoError::invalid(
                path,
                format!("frame time {} is not finite", self.time),
            ));
        }
        let n = self.positions.len();
        let mut seen = HashSet::new();
        for field in &self.fields {
            let name = field.name;
            if name.is_empty()
                || name == "."
                || name == reserved
                || name.contains('/')
                || name.chars().any(char::is_control)
            {
                return Err(IoError::invalid(
                    path,
                    format!(
                        "field name {name:?} is empty, reserved or holds '/' or control characters"
                    ),
                ));
            }
            if !seen.insert(name) {
                return Err(IoError::invalid(
                    path,
                    format!("field name {name:?} appears twice"),
                ));
            }
            if field.data.len() != n {
                return Err(IoError::invalid(
                    path,
                    format!(
                        "field {name:?} has {} values for {n} particles",
                        field.data.len()
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// Positions or vectors as one flat `x0 y0 z0 x1 ...` buffer, the layout VTK and HDF5 expect.
pub(crate) fn flatten(v: &[Vec3]) -> Vec<Real> {
    let mut out = Vec::with_capacity(3 * v.len());
    for p in v {
        out.extend_from_slice(&[p.x, p.y, p.z]);
    }
    out
}
