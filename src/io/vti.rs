//! Grid frames as VTK XML ImageData (`.vti`) for ParaView.
//!
//! ImageData is VTK's regular grid: an extent of point indices plus origin and spacing, so the
//! file holds no coordinates at all. Our values are cell-centred, so the extent runs over the
//! `nx + 1` corner points per axis and every field is cell data. VTK orders cells x-fastest
//! (`i + nx * (j + ny * k)`), the transpose of our C-order `[i, j, k]` arrays. Arrays are
//! appended raw and compressed ([`super::vtk_xml`]); origin and spacing are written at full f64
//! precision whatever the arrays' precision, so cells never drift on large or offset grids.

use std::fmt::Write as _;
use std::path::Path;

use super::vtk_xml::{active_arrays, time_field, VtkOptions, XmlVtk};
use super::{write_atomic, GridFrame, IoError};

/// One VTK file per frame (XML ImageData, so `path` must end in `.vti`) with each field as cell
/// data (scalars, 3-component vectors) stored as `options` say, written atomically. The time
/// is stored as the field `TimeValue`; a series gets it from its
/// [`PvdSeries`](super::PvdSeries) entry.
pub fn write_grid_vtk(path: &Path, frame: &GridFrame, options: VtkOptions) -> Result<(), IoError> {
    if path.extension().and_then(|e| e.to_str()) != Some("vti") {
        return Err(IoError::invalid(
            path,
            "grid frames are VTK XML ImageData and need the .vti extension",
        ));
    }
    frame.validate(path)?;

    let mut vtk = XmlVtk::new(options);
    let mut arrays = String::new();
    for field in &frame.fields {
        let values = field.data.flatten(|v| v.reversed_axes());
        arrays += &vtk.reals(field.name, field.data.count(), &values);
        arrays.push('\n');
    }
    let first = |c: usize| {
        let f = frame.fields.iter();
        f.map(|f| (f.name, f.data)).find(|(_, d)| d.count() == c)
    };
    let active = active_arrays(first(1).map(|f| f.0), first(3).map(|f| f.0));
    let [nx, ny, nz] = frame.dims;
    let extent = format!("0 {nx} 0 {ny} 0 {nz}");
    let (o, h) = (frame.origin, frame.spacing);
    let mut body = String::new();
    // `{}` of f64 prints the shortest text that parses back to the same value.
    let _ = write!(
        body,
        "<ImageData WholeExtent=\"{extent}\" Origin=\"{} {} {}\" Spacing=\"{h} {h} {h}\">\n{}\
         <Piece Extent=\"{extent}\">\n<CellData{active}>\n{arrays}</CellData>\n</Piece>\n\
         </ImageData>\n",
        o.x,
        o.y,
        o.z,
        time_field(frame.time)
    );
    write_atomic(path, |out| vtk.finish(out, "ImageData", &body))
}
