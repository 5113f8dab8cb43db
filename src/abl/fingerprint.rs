//! Fingerprints: a SHA-256 of the obstacle geometry, so a database is never applied to an
//! obstacle it was not computed for, whatever the file names say.

use sha2::{Digest, Sha256};

use super::AblError;
use crate::geometry::Shape;

/// Lower-case hex SHA-256 of the concatenated `parts`, each prefixed by its length so that
/// `["ab", "c"]` and `["a", "bc"]` differ.
pub fn hash_hex(parts: &[&[u8]]) -> String {
    let mut h = Sha256::new();
    for p in parts {
        h.update((p.len() as u64).to_le_bytes());
        h.update(p);
    }
    h.finalize().iter().map(|b| format!("{b:02x}")).collect()
}

/// The fingerprint of an obstacle's geometry in its own frame: the shape kind and the exact bits
/// of its parameters, or for a mesh its scale and the bytes of its file (not its path, so a
/// moved or renamed mesh still matches). Position, rotation and motion are not part of it:
/// the database is stored in the object's frame.
pub fn geometry_fingerprint(shape: &Shape) -> Result<String, AblError> {
    let bits = |v: &[f64]| -> Vec<u8> { v.iter().flat_map(|x| x.to_le_bytes()).collect() };
    match shape {
        Shape::Box { half_extents } => Ok(hash_hex(&[b"box", &bits(half_extents)])),
        Shape::Sphere { radius } => Ok(hash_hex(&[b"sphere", &bits(&[*radius])])),
        Shape::Cylinder {
            radius,
            half_height,
        } => Ok(hash_hex(&[b"cylinder", &bits(&[*radius, *half_height])])),
        Shape::Capsule {
            radius,
            half_height,
        } => Ok(hash_hex(&[b"capsule", &bits(&[*radius, *half_height])])),
        Shape::Mesh { path, scale } => {
            let bytes = std::fs::read(path).map_err(|source| AblError::Mesh {
                path: path.clone(),
                source,
            })?;
            Ok(hash_hex(&[b"mesh", &bits(&[*scale]), &bytes]))
        }
    }
}
