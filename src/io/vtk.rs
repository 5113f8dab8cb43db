//! Particle frames as VTK XML PolyData (`.vtp`) for ParaView.
//!
//! PolyData with one vertex cell per particle is the smallest VTK form ParaView renders as points
//! directly. Arrays are appended raw and compressed ([`super::vtk_xml`]).

use std::path::Path;

use super::frame::flatten;
use super::vtk_xml::{active_arrays, time_field, VtkOptions, XmlVtk};
use super::{write_atomic, FieldData, IoError, ParticleFrame};

/// One VTK file per frame (XML PolyData, so `path` must end in `.vtp`) with positions as
/// points, one vertex cell per particle, and each field as point data (scalars, 3-component
/// vectors), stored as `options` say and written atomically. The time is stored as the field
/// `TimeValue`; a series gets it from its [`PvdSeries`](super::PvdSeries) entry.
pub fn write_particles_vtk(
    path: &Path,
    frame: &ParticleFrame,
    options: VtkOptions,
) -> Result<(), IoError> {
    if path.extension().and_then(|e| e.to_str()) != Some("vtp") {
        return Err(IoError::invalid(
            path,
            "particle frames are VTK XML PolyData and need the .vtp extension",
        ));
    }
    frame.validate(path, "")?;

    let n = frame.positions.len();
    let mut vtk = XmlVtk::new(options);
    let points = vtk.reals("Points", 3, &flatten(frame.positions));
    let ids: Vec<i64> = (0..n as i64).collect();
    let connectivity = vtk.ints("connectivity", &ids);
    let offsets: Vec<i64> = (1..=n as i64).collect();
    let offsets = vtk.ints("offsets", &offsets);
    let mut arrays = String::new();
    for field in &frame.fields {
        arrays += &match field.data {
            FieldData::Scalar(v) => vtk.reals(field.name, 1, v),
            FieldData::Vector(v) => vtk.reals(field.name, 3, &flatten(v)),
        };
        arrays.push('\n');
    }
    let first = |vector: bool| {
        let mut f = frame.fields.iter();
        f.find(|f| matches!(f.data, FieldData::Vector(_)) == vector)
            .map(|f| f.name)
    };
    let active = active_arrays(first(false), first(true));
    let body = format!(
        "<PolyData>\n{}<Piece NumberOfPoints=\"{n}\" NumberOfVerts=\"{n}\" NumberOfLines=\"0\" \
         NumberOfStrips=\"0\" NumberOfPolys=\"0\">\n<Points>\n{points}\n</Points>\n\
         <Verts>\n{connectivity}\n{offsets}\n</Verts>\n<PointData{active}>\n{arrays}</PointData>\n\
         </Piece>\n</PolyData>\n",
        time_field(frame.time)
    );
    write_atomic(path, |out| vtk.finish(out, "PolyData", &body))
}
