//! One output frame of a regular cell grid, borrowed from the solver so writing copies nothing up
//! front.

use std::collections::HashSet;
use std::path::Path;

use ndarray::ArrayView3;

use super::IoError;
use crate::{Real, Vec3};

/// Cell values of one grid field, each view of shape `dims`, indexed `[i, j, k] = [x, y, z]`.
///
/// Views may be strided (a slice of a larger array with ghost cells, a face-to-cell average held
/// elsewhere): the writers read them in logical index order, never as raw memory.
#[derive(Clone, Copy, Debug)]
pub enum GridFieldData<'a> {
    /// One value per cell.
    Scalar(ArrayView3<'a, Real>),
    /// One 3-vector per cell, as its x, y and z components.
    Vector([ArrayView3<'a, Real>; 3]),
    /// One symmetric 3 x 3 tensor per cell, as its six components xx, yy, zz, xy, yz, xz:
    /// VTK's order for six-component arrays, which ParaView's tensor filters read as symmetric
    /// tensors (XDMF's `Tensor6`).
    Tensor([ArrayView3<'a, Real>; 6]),
}

impl<'a> GridFieldData<'a> {
    /// The views the field is made of: one for a scalar, three for a vector.
    fn components(&self) -> &[ArrayView3<'a, Real>] {
        match self {
            GridFieldData::Scalar(v) => std::slice::from_ref(v),
            GridFieldData::Vector(v) => v,
            GridFieldData::Tensor(v) => v,
        }
    }

    /// Values per cell: 1, 3 or 6.
    pub fn count(&self) -> usize {
        self.components().len()
    }

    /// The name of component `c` in messages (`x`, `xy`, ...); empty for a scalar.
    fn component_name(&self, c: usize) -> &'static str {
        match self {
            GridFieldData::Scalar(_) => "",
            GridFieldData::Vector(_) => ["x", "y", "z"][c],
            GridFieldData::Tensor(_) => ["xx", "yy", "zz", "xy", "yz", "xz"][c],
        }
    }

    /// All values in one flat buffer, cells in the logical order of `order(view)` and the
    /// components of a cell side by side: the identity gives HDF5's C order, reversed axes give
    /// VTK's x-fastest order.
    pub(crate) fn flatten(
        &self,
        order: impl Fn(ArrayView3<'a, Real>) -> ArrayView3<'a, Real>,
    ) -> Vec<Real> {
        match *self {
            GridFieldData::Scalar(s) => order(s).iter().copied().collect(),
            GridFieldData::Vector([x, y, z]) => {
                let (x, y, z) = (order(x), order(y), order(z));
                let mut out = Vec::with_capacity(3 * x.len());
                for ((a, b), c) in x.iter().zip(y.iter()).zip(z.iter()) {
                    out.extend([*a, *b, *c]);
                }
                out
            }
            GridFieldData::Tensor(components) => {
                let views = components.map(order);
                let mut out = Vec::with_capacity(6 * views[0].len());
                let mut iters = views.each_ref().map(|v| v.iter());
                for _ in 0..views[0].len() {
                    for it in &mut iters {
                        out.extend(it.next());
                    }
                }
                out
            }
        }
    }
}

/// A named cell-centred field (pressure, smoke density, velocity, ...).
#[derive(Clone, Copy, Debug)]
pub struct GridField<'a> {
    pub name: &'a str,
    pub data: GridFieldData<'a>,
}

impl<'a> GridField<'a> {
    /// A scalar field.
    pub fn scalar(name: &'a str, values: ArrayView3<'a, Real>) -> Self {
        GridField {
            name,
            data: GridFieldData::Scalar(values),
        }
    }

    /// A symmetric tensor field from its components xx, yy, zz, xy, yz, xz.
    pub fn tensor(name: &'a str, components: [ArrayView3<'a, Real>; 6]) -> Self {
        GridField {
            name,
            data: GridFieldData::Tensor(components),
        }
    }

    /// A vector field from its x, y and z components.
    pub fn vector(name: &'a str, components: [ArrayView3<'a, Real>; 3]) -> Self {
        GridField {
            name,
            data: GridFieldData::Vector(components),
        }
    }
}

/// One output frame of a regular grid of cubic cells: cell `(i, j, k)` spans
/// `origin + spacing * [i, i + 1] x [j, j + 1] x [k, k + 1]`, and every field holds one value (or
/// 3-vector) per cell.
#[derive(Clone, Debug)]
pub struct GridFrame<'a> {
    /// Solver step the frame was taken at.
    pub step: u64,
    /// Simulation time of the frame.
    pub time: Real,
    /// Lower corner of cell `(0, 0, 0)`.
    pub origin: Vec3,
    /// Edge length of a cell.
    pub spacing: Real,
    /// Cells along x, y and z.
    pub dims: [usize; 3],
    pub fields: Vec<GridField<'a>>,
}

impl GridFrame<'_> {
    /// Checks what every writer needs before it touches the file (`path` only names the file in
    /// the error): finite time and origin, positive finite spacing, at least one cell along every
    /// axis, every field of shape `dims`, and field names that are non-empty, unique and free of
    /// `/` (an HDF5 path separator) and control characters. Values are not checked.
    pub fn validate(&self, path: &Path) -> Result<(), IoError> {
        let fail = |reason: String| Err(IoError::invalid(path, reason));
        if !self.time.is_finite() {
            return fail(format!("grid frame time {} is not finite", self.time));
        }
        if !self.origin.iter().all(|c| c.is_finite()) {
            return fail(format!(
                "grid origin {:?} is not finite",
                self.origin.as_slice()
            ));
        }
        if !(self.spacing.is_finite() && self.spacing > 0.0) {
            return fail(format!(
                "grid spacing {} is not positive and finite",
                self.spacing
            ));
        }
        // VTK extents are 32-bit point indices, so nx + 1 must fit in an i32.
        if self.dims.iter().any(|&n| n == 0 || n >= i32::MAX as usize) {
            return fail(format!(
                "grid dims {:?} must each be at least 1 and below {}",
                self.dims,
                i32::MAX
            ));
        }
        let mut seen = HashSet::new();
        for field in &self.fields {
            let name = field.name;
            if name.is_empty()
                || name == "."
                || name.contains('/')
                || name.chars().any(char::is_control)
            {
                return fail(format!(
                    "grid field name {name:?} is empty or holds '/' or control characters"
                ));
            }
            if !seen.insert(name) {
                return fail(format!("grid field name {name:?} appears twice"));
            }
            for (c, view) in field.data.components().iter().enumerate() {
                if view.shape() != self.dims {
                    let which = match field.data.component_name(c) {
                        "" => String::new(),
                        name => format!(" ({name} component)"),
                    };
                    return fail(format!(
                        "grid field {name:?}{which} has shape {:?}, the grid has dims {:?}",
                        view.shape(),
                        self.dims
                    ));
                }
            }
        }
        Ok(())
    }
}
