//! Grid frames as VTK XML ImageData (`.vti`) for ParaView.
//!
//! ImageData is VTK's regular grid: an extent of point indices plus origin and spacing, so the
//! file holds no coordinates at all. Our values are cell-centred, so the extent runs over the
//! `nx + 1` corner points per axis and every field is cell data. VTK orders cells x-fastest
//! (`i + nx * (j + ny * k)`), the transpose of our C-order `[i, j, k]` arrays. vtkio writes the
//! arrays inline as base64 binary (`header_type` UInt64, no compression) in the machine's byte
//! order, at full f64 precision.

use std::ops::Range;
use std::path::Path;

use vtkio::model::{
    Attribute, Attributes, ByteOrder, DataSet, Extent, ImageDataPiece, Version, Vtk,
};

use super::{write_atomic, GridFieldData, GridFrame, IoError};
use crate::Real;

/// One VTK file per frame (XML ImageData, so `path` must end in `.vti`) with each field as cell
/// data (scalars, 3-component vectors), written atomically.
///
/// As with particle frames, `step` and `time` are not stored in the file; the time reaches
/// ParaView through the [`PvdSeries`](super::PvdSeries) entry.
pub fn write_grid_vtk(path: &Path, frame: &GridFrame) -> Result<(), IoError> {
    if path.extension().and_then(|e| e.to_str()) != Some("vti") {
        return Err(IoError::invalid(
            path,
            "grid frames are VTK XML ImageData and need the .vti extension",
        ));
    }
    frame.validate(path)?;

    let cell_data = frame
        .fields
        .iter()
        .map(|field| {
            let values = field.data.flatten(|v| v.reversed_axes());
            match field.data {
                GridFieldData::Scalar(_) => Attribute::scalars(field.name, 1).with_data(values),
                GridFieldData::Vector(_) => Attribute::vectors(field.name).with_data(values),
            }
        })
        .collect();
    // `validate` keeps every count below i32::MAX.
    let [nx, ny, nz] = frame.dims.map(|n| n as i32);
    let extent = Extent::Ranges([0..=nx, 0..=ny, 0..=nz]);
    let vtk = Vtk {
        // 1.0 is the oldest XML version with 64-bit headers: every ParaView since 4.x reads it.
        version: Version::new_xml(1, 0),
        title: String::new(),
        byte_order: ByteOrder::native(),
        file_path: None,
        data: DataSet::ImageData {
            extent: extent.clone(),
            // vtkio keeps these in f32; the exact f64 values are put back into the text below.
            origin: frame.origin.map(|c| c as f32).into(),
            spacing: [frame.spacing as f32; 3],
            meta: None,
            pieces: vec![vtkio::model::Piece::Inline(Box::new(ImageDataPiece {
                extent,
                data: Attributes {
                    point: Vec::new(),
                    cell: cell_data,
                },
            }))],
        },
    };

    let mut buf = Vec::new();
    vtk.write_xml(&mut buf).map_err(|source| IoError::Vtk {
        path: path.to_path_buf(),
        source,
    })?;
    let origin = frame.origin;
    let (tag_range, tag) =
        exact_geometry_tag(&buf, [origin.x, origin.y, origin.z], [frame.spacing; 3]).ok_or_else(
            || {
                IoError::invalid(
                    path,
                    "vtkio wrote no ImageData Origin and Spacing attributes to replace",
                )
            },
        )?;
    write_atomic(path, |out| {
        out.write_all(&buf[..tag_range.start])?;
        out.write_all(tag.as_bytes())?;
        out.write_all(&buf[tag_range.end..])
    })
}

/// The byte range of the `<ImageData ...` opening tag in `xml` and that tag with its `Origin`
/// and `Spacing` rewritten at full f64 precision: vtkio keeps them in f32, whose relative error
/// of 6e-8 would grow with the cell index into visible misplacement on large or offset grids.
/// `None` if either attribute is missing.
fn exact_geometry_tag(
    xml: &[u8],
    origin: [Real; 3],
    spacing: [Real; 3],
) -> Option<(Range<usize>, String)> {
    let start = find(xml, b"<ImageData ")?;
    let end = start + find(&xml[start..], b">")?;
    let mut tag = std::str::from_utf8(&xml[start..end]).ok()?.to_string();
    for (key, v) in [("Origin", origin), ("Spacing", spacing)] {
        let open = format!(" {key}=\"");
        let value_start = tag.find(&open)? + open.len();
        let value_end = value_start + tag[value_start..].find('"')?;
        // `{}` of f64 prints the shortest text that parses back to the same value.
        tag.replace_range(
            value_start..value_end,
            &format!("{} {} {}", v[0], v[1], v[2]),
        );
    }
    Some((start..end, tag))
}

fn find(haystack: &[u8], needle: &[u8]) -> Option<usize> {
    haystack.windows(needle.len()).position(|w| w == needle)
}
