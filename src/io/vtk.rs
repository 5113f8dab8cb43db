//! Particle frames as VTK XML PolyData (`.vtp`) for ParaView.
//!
//! PolyData with one vertex cell per particle is the smallest VTK form ParaView renders as points
//! directly. vtkio writes XML arrays inline as base64 binary (no compression, `header_type`
//! UInt64), in the machine's byte order, at full f64 precision.

use std::path::Path;

use vtkio::model::{
    Attribute, Attributes, ByteOrder, DataSet, PolyDataPiece, Version, VertexNumbers, Vtk,
};

use super::frame::flatten;
use super::{write_atomic, FieldData, IoError, ParticleFrame};

/// One VTK file per frame (XML PolyData, so `path` must end in `.vtp`) with positions as
/// points, one vertex cell per particle, and each field as point data (scalars, 3-component
/// vectors), written atomically.
///
/// The frame's `step` and `time` are not stored in the file (vtkio cannot write XML field data);
/// the time reaches ParaView through the [`PvdSeries`](super::PvdSeries) entry.
pub fn write_particles_vtk(path: &Path, frame: &ParticleFrame) -> Result<(), IoError> {
    if path.extension().and_then(|e| e.to_str()) != Some("vtp") {
        return Err(IoError::invalid(
            path,
            "particle frames are VTK XML PolyData and need the .vtp extension",
        ));
    }
    frame.validate(path, "")?;

    let n = frame.positions.len() as u64;
    let point_data = frame
        .fields
        .iter()
        .map(|field| match field.data {
            FieldData::Scalar(v) => Attribute::scalars(field.name, 1).with_data(v.to_vec()),
            FieldData::Vector(v) => Attribute::vectors(field.name).with_data(flatten(v)),
        })
        .collect();
    let piece = PolyDataPiece {
        points: flatten(frame.positions).into(),
        verts: Some(VertexNumbers::XML {
            connectivity: (0..n).collect(),
            offsets: (1..=n).collect(),
        }),
        data: Attributes {
            point: point_data,
            cell: Vec::new(),
        },
        ..Default::default()
    };
    let vtk = Vtk {
        // 1.0 is the oldest XML version with 64-bit headers: every ParaView since 4.x reads it.
        version: Version::new_xml(1, 0),
        title: String::new(),
        byte_order: ByteOrder::native(),
        file_path: None,
        data: DataSet::inline(piece),
    };

    if n == 0 {
        return write_empty(path, vtk);
    }
    // vtkio streams into the temp file; its own error is kept aside so the caller sees it
    // rather than an io::Error wrapping its text.
    let mut vtk_error = None;
    let result = write_atomic(path, |out| {
        vtk.write_xml(out).map_err(|e| {
            let err = std::io::Error::other(e.to_string());
            vtk_error = Some(e);
            err
        })
    });
    match (result, vtk_error) {
        (Err(_), Some(source)) => Err(IoError::Vtk {
            path: path.to_path_buf(),
            source,
        }),
        (result, _) => result,
    }
}

/// vtkio omits zero counts, but VTK's reader rejects a `Piece` without `NumberOfPoints`, so an
/// empty frame (all particles gone) would break the ParaView series; put the counts back.
fn write_empty(path: &Path, vtk: Vtk) -> Result<(), IoError> {
    let mut buf = Vec::new();
    vtk.write_xml(&mut buf).map_err(|source| IoError::Vtk {
        path: path.to_path_buf(),
        source,
    })?;
    let text = String::from_utf8_lossy(&buf).replacen(
        "<Piece>",
        "<Piece NumberOfPoints=\"0\" NumberOfVerts=\"0\">",
        1,
    );
    write_atomic(path, |out| out.write_all(text.as_bytes()))
}
