//! XDMF descriptions of the HDF5 frames, so ParaView (its XDMF reader, `vtkXdmfReader`) opens a
//! run's `frames.h5` as a time series without a plug-in: `STEM.xmf` beside each `STEM.h5`.
//!
//! An XDMF file is XML naming, for every frame, the grids of that time and where in which HDF5
//! file each array lies (`STEM_NNNNNN.h5:/velocity`, relative to the `.xmf`). Each frame is a
//! spatial collection inside one temporal collection: the frame's own grid and each particle
//! set beside it (the vortex particles) as a block of its own.
//!
//! - Particles are a `Polyvertex` set: one vertex per particle, fields at the nodes.
//! - Grid frames keep the solver's C order, x slowest, while XDMF's structured grids run their
//!   first index along VTK's z. A uniform grid description would swap x and z, so grid frames
//!   are a `3DSMesh` whose node coordinates (`STEM_points.h5:/points`, written once) put every
//!   cell where it is; fields are cell-centred.

use std::fmt::Write as _;
use std::path::Path;

use super::vtk_xml::xml_escape;
use super::{write_atomic, FieldData, GridFrame, IoError, ParticleFrame};
use crate::Real;

/// The node coordinates of a grid, x slowest, as the `3DSMesh` geometry reads them, and their
/// shape (nodes x 3).
pub(super) fn grid_points(frame: &GridFrame) -> (Vec<Real>, [usize; 2]) {
    let [nx, ny, nz] = frame.dims.map(|n| n + 1);
    let (o, h) = (frame.origin, frame.spacing);
    let mut points = Vec::with_capacity(3 * nx * ny * nz);
    for i in 0..nx {
        for j in 0..ny {
            for k in 0..nz {
                points.extend([
                    o.x + h * i as Real,
                    o.y + h * j as Real,
                    o.z + h * k as Real,
                ]);
            }
        }
    }
    (points, [nx * ny * nz, 3])
}

/// A `DataItem` of f64 values of `shape` at `file:path`.
fn item(shape: &[usize], file: &str, path: &str) -> String {
    let dims: Vec<String> = shape.iter().map(usize::to_string).collect();
    format!(
        "<DataItem Dimensions=\"{}\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">{}:{}</DataItem>",
        dims.join(" "),
        xml_escape(file),
        xml_escape(path)
    )
}

/// A symmetric tensor stored in VTK's component order (xx, yy, zz, xy, yz, xz) as the
/// `DataItem` XDMF's `Tensor6` reads, whose order is xx, xy, xz, yy, yz, zz: the six
/// components as hyperslabs of the stored array, joined in XDMF's order.
fn tensor6_item([nx, ny, nz]: [usize; 3], file: &str, path: &str) -> String {
    let stored = item(&[nx, ny, nz, 6], file, path);
    let slabs: String = [0, 3, 5, 1, 4, 2]
        .iter()
        .map(|c| {
            format!(
                "<DataItem ItemType=\"HyperSlab\" Dimensions=\"{nx} {ny} {nz} 1\" \
                 Type=\"HyperSlab\"><DataItem Dimensions=\"3 4\" Format=\"XML\">0 0 0 {c} \
                 1 1 1 1 {nx} {ny} {nz} 1</DataItem>{stored}</DataItem>"
            )
        })
        .collect();
    format!(
        "<DataItem ItemType=\"Function\" Function=\"JOIN($0, $1, $2, $3, $4, $5)\" \
         Dimensions=\"{nx} {ny} {nz} 6\">{slabs}</DataItem>"
    )
}

/// An `Attribute` element: a scalar, a 3-vector or a symmetric tensor (6 values) per node or
/// cell.
fn attribute(name: &str, center: &str, components: usize, data_item: &str) -> String {
    let kind = match components {
        3 => "Vector",
        6 => "Tensor6",
        _ => "Scalar",
    };
    format!(
        "<Attribute Name=\"{}\" AttributeType=\"{kind}\" Center=\"{center}\">{data_item}</Attribute>\n",
        xml_escape(name)
    )
}

/// The grid of a particle frame whose datasets lie in `file` under `group` (`/` or
/// `/NAME/`); `None` for a frame without particles, which XDMF cannot describe.
pub(super) fn particle_grid(
    name: &str,
    file: &str,
    group: &str,
    frame: &ParticleFrame,
) -> Option<String> {
    let n = frame.positions.len();
    if n == 0 {
        return None;
    }
    let mut s = format!(
        "<Grid Name=\"{}\" GridType=\"Uniform\">\n\
         <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"{n}\" NodesPerElement=\"1\"/>\n\
         <Geometry GeometryType=\"XYZ\">{}</Geometry>\n",
        xml_escape(name),
        item(&[n, 3], file, &format!("{group}position"))
    );
    for field in &frame.fields {
        let vector = matches!(field.data, FieldData::Vector(_));
        let shape: &[usize] = if vector { &[n, 3] } else { &[n] };
        let data = item(shape, file, &format!("{group}{}", field.name));
        s += &attribute(field.name, "Node", if vector { 3 } else { 1 }, &data);
    }
    s.push_str("</Grid>\n");
    Some(s)
}

/// The grid of a grid frame whose fields lie at the root of `file`, on the nodes in
/// `points_file` ([`grid_points`]).
pub(super) fn cell_grid(name: &str, file: &str, points_file: &str, frame: &GridFrame) -> String {
    let [nx, ny, nz] = frame.dims;
    let mut s = format!(
        "<Grid Name=\"{}\" GridType=\"Uniform\">\n\
         <Topology TopologyType=\"3DSMesh\" Dimensions=\"{} {} {}\"/>\n\
         <Geometry GeometryType=\"XYZ\">{}</Geometry>\n",
        xml_escape(name),
        nx + 1,
        ny + 1,
        nz + 1,
        item(&[(nx + 1) * (ny + 1) * (nz + 1), 3], points_file, "/points")
    );
    for field in &frame.fields {
        let c = field.data.count();
        let shape: &[usize] = if c > 1 {
            &[nx, ny, nz, c]
        } else {
            &[nx, ny, nz]
        };
        let path = format!("/{}", field.name);
        let data = if c == 6 {
            tensor6_item(frame.dims, file, &path)
        } else {
            item(shape, file, &path)
        };
        s += &attribute(field.name, "Cell", c, &data);
    }
    s.push_str("</Grid>\n");
    s
}

/// One frame: the spatial collection of `grids` at `time`.
pub(super) fn frame(index: usize, time: Real, grids: &[String]) -> String {
    let mut s = String::new();
    // `{}` of f64 prints the shortest text that parses back to the same value.
    let _ = writeln!(
        s,
        "<Grid Name=\"frame_{index:06}\" GridType=\"Collection\" CollectionType=\"Spatial\">\n\
         <Time Value=\"{time}\"/>"
    );
    for g in grids {
        s += g;
    }
    s.push_str("</Grid>\n");
    s
}

/// Writes `path` whole (atomically) as one grid (no time series).
pub(super) fn write_single(path: &Path, grid: &str) -> Result<(), IoError> {
    write_atomic(path, |out| {
        out.write_all(b"<?xml version=\"1.0\" ?>\n<Xdmf Version=\"2.0\">\n<Domain>\n")?;
        out.write_all(grid.as_bytes())?;
        out.write_all(b"</Domain>\n</Xdmf>\n")
    })
}

/// Writes `path` whole (atomically) as the temporal collection `name` of `frames`.
pub(super) fn write_series(path: &Path, name: &str, frames: &[String]) -> Result<(), IoError> {
    write_atomic(path, |out| {
        write!(
            out,
            "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"2.0\">\n<Domain>\n\
             <Grid Name=\"{}\" GridType=\"Collection\" CollectionType=\"Temporal\">\n",
            xml_escape(name)
        )?;
        for f in frames {
            out.write_all(f.as_bytes())?;
        }
        out.write_all(b"</Grid>\n</Domain>\n</Xdmf>\n")
    })
}

/// Writes `path` (atomically) as one XDMF file that opens the series of each of `files` (their
/// temporal collections, by XInclude): a coupled scene's `frames.xmf`, with the particles' and
/// the grid's frames as two blocks.
pub fn write_includes(path: &Path, files: &[&str]) -> Result<(), IoError> {
    write_atomic(path, |out| {
        out.write_all(
            b"<?xml version=\"1.0\" ?>\n\
              <Xdmf Version=\"2.0\" xmlns:xi=\"http://www.w3.org/2001/XInclude\">\n<Domain>\n",
        )?;
        for f in files {
            writeln!(
                out,
                "<xi:include href=\"{}\" xpointer=\"xpointer(//Xdmf/Domain/Grid)\"/>",
                xml_escape(f)
            )?;
        }
        out.write_all(b"</Domain>\n</Xdmf>\n")
    })
}
