//! One zlib stream in memory: the unit both compressed formats store (a VTK array block, an
//! HDF5 chunk through its deflate filter).

use std::io::Write;

use flate2::write::ZlibEncoder;
use flate2::Compression;

/// `bytes` as one zlib stream at `level` (clamped to 9).
pub(super) fn zlib(bytes: &[u8], level: u8) -> Vec<u8> {
    let level = Compression::new(u32::from(level.min(9)));
    let mut z = ZlibEncoder::new(Vec::with_capacity(bytes.len() / 2), level);
    // Writing into a Vec cannot fail.
    z.write_all(bytes).expect("zlib into memory");
    z.finish().expect("zlib into memory")
}
