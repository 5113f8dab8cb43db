//! VTK XML files with their arrays appended as raw binary and zlib-compressed in blocks: the
//! layout VTK's own XML writers produce in appended mode with `vtkZLibDataCompressor`, which
//! ParaView and every VTK reader open natively.
//!
//! vtkio, which wrote the frames before, writes arrays inline as base64 (a third larger) and
//! compresses each array as one block on one thread; it cannot write appended raw data. The
//! format is small enough to write here: the XML head names each array with its byte offset
//! into the appended section, which starts after `<AppendedData encoding="raw">` and an
//! underscore. An array there is, with `header_type="UInt64"` and little-endian bytes:
//!
//! - uncompressed (level 0): its byte count, then its bytes;
//! - compressed: `[nb][nu][np][nc_1]...[nc_nb]` (the number of blocks, the block size before
//!   compression, the size of the last block if it is partial or 0, each block's compressed
//!   size), then the blocks, each a zlib stream. Blocks are compressed in parallel.

use std::fmt::Write as _;
use std::io::Write;

use rayon::prelude::*;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::zlib::zlib;
use crate::Real;

/// Bytes of an array compressed as one block: VTK's reader allocates one block at a time, and
/// 64 KiB leaves zlib its whole 32 KiB window while a frame of a few MB still splits into
/// enough blocks for every core.
const BLOCK: usize = 1 << 16;

/// Floating-point precision of the arrays in VTK frames.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum Precision {
    /// 4-byte floats: half the bytes, a relative rounding of 6e-8, plenty to look at.
    #[default]
    F32,
    /// 8-byte floats: the solver's values exactly.
    F64,
}

/// How VTK frames store their arrays.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct VtkOptions {
    pub precision: Precision,
    /// zlib level, 0 (stored uncompressed) to 9.
    pub compression: u8,
}

impl Default for VtkOptions {
    /// f32, zlib level 4: the scene defaults.
    fn default() -> Self {
        VtkOptions {
            precision: Precision::F32,
            compression: 4,
        }
    }
}

/// The head of a VTK XML file being built, and the appended section its arrays point into.
pub(super) struct XmlVtk {
    options: VtkOptions,
    appended: Vec<u8>,
}

impl XmlVtk {
    pub(super) fn new(options: VtkOptions) -> Self {
        XmlVtk {
            options,
            appended: Vec::new(),
        }
    }

    /// Appends real values (`components` per tuple) at the file's precision and returns the
    /// `<DataArray>` tag that refers to them.
    pub(super) fn reals(&mut self, name: &str, components: usize, values: &[Real]) -> String {
        let (kind, bytes) = match self.options.precision {
            Precision::F32 => ("Float32", to_bytes(values, |v| (*v as f32).to_le_bytes())),
            Precision::F64 => ("Float64", to_bytes(values, |v| v.to_le_bytes())),
        };
        self.array(kind, name, components, &bytes)
    }

    /// Appends 64-bit integers (connectivity, offsets) and returns their `<DataArray>` tag.
    pub(super) fn ints(&mut self, name: &str, values: &[i64]) -> String {
        let bytes = to_bytes(values, |v| v.to_le_bytes());
        self.array("Int64", name, 1, &bytes)
    }

    fn array(&mut self, kind: &str, name: &str, components: usize, bytes: &[u8]) -> String {
        let offset = self.appended.len();
        match self.options.compression {
            0 => {
                self.appended
                    .extend_from_slice(&(bytes.len() as u64).to_le_bytes());
                self.appended.extend_from_slice(bytes);
            }
            level => compress_into(&mut self.appended, bytes, level),
        }
        format!(
            "<DataArray type=\"{kind}\" Name=\"{}\" NumberOfComponents=\"{components}\" \
             format=\"appended\" offset=\"{offset}\"/>",
            xml_escape(name)
        )
    }

    /// Writes the whole file: the `VTKFile` element of `kind` around `body` (the dataset
    /// element, whose arrays came from this builder), then the appended section.
    pub(super) fn finish(self, out: &mut dyn Write, kind: &str, body: &str) -> std::io::Result<()> {
        let compressor = if self.options.compression > 0 {
            " compressor=\"vtkZLibDataCompressor\""
        } else {
            ""
        };
        // 1.0 is the oldest XML version with 64-bit headers: every ParaView since 4.x reads it.
        write!(
            out,
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"{kind}\" version=\"1.0\" \
             byte_order=\"LittleEndian\" header_type=\"UInt64\"{compressor}>\n{body}\
             <AppendedData encoding=\"raw\">\n_"
        )?;
        out.write_all(&self.appended)?;
        out.write_all(b"\n</AppendedData>\n</VTKFile>\n")
    }
}

/// The `<FieldData>` element that carries the frame's time, which ParaView reads as the
/// dataset's time when a file is opened alone (`TimeValue`).
pub(super) fn time_field(time: Real) -> String {
    format!(
        "<FieldData><DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" \
         format=\"ascii\">{time}</DataArray></FieldData>\n"
    )
}

/// Little-endian bytes of `values`, converted in parallel for large arrays.
fn to_bytes<T: Sync, const N: usize>(values: &[T], le: impl Fn(&T) -> [u8; N] + Sync) -> Vec<u8> {
    let mut bytes = vec![0u8; N * values.len()];
    bytes
        .par_chunks_mut(N * 4096)
        .zip(values.par_chunks(4096))
        .for_each(|(out, chunk)| {
            for (o, v) in out.chunks_exact_mut(N).zip(chunk) {
                o.copy_from_slice(&le(v));
            }
        });
    bytes
}

/// Appends `bytes` as VTK's compressed array: the block header, then each [`BLOCK`] as a zlib
/// stream at `level`.
fn compress_into(out: &mut Vec<u8>, bytes: &[u8], level: u8) {
    let blocks: Vec<Vec<u8>> = bytes
        .par_chunks(BLOCK)
        .map(|block| zlib(block, level))
        .collect();
    let partial = bytes.len() % BLOCK;
    let header = [blocks.len(), BLOCK, partial]
        .into_iter()
        .chain(blocks.iter().map(Vec::len));
    for n in header {
        out.extend_from_slice(&(n as u64).to_le_bytes());
    }
    for block in &blocks {
        out.extend_from_slice(block);
    }
}

/// `s` with the five XML special characters escaped, for an attribute value.
pub(crate) fn xml_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c => out.push(c),
        }
    }
    out
}

/// The attributes of a data element's opening tag (`PointData`, `CellData`) that name its
/// active scalar and vector arrays (the first of each, as VTK's writers choose them).
pub(super) fn active_arrays(scalars: Option<&str>, vectors: Option<&str>) -> String {
    let mut s = String::new();
    if let Some(n) = scalars {
        let _ = write!(s, " Scalars=\"{}\"", xml_escape(n));
    }
    if let Some(n) = vectors {
        let _ = write!(s, " Vectors=\"{}\"", xml_escape(n));
    }
    s
}
