//! Neighbour search on the compact hashed uniform grid of [`crate::spatial`]: neighbour lists
//! built in parallel, cell chunk by cell chunk, into one compressed-row (CSR) array of `u32`.

pub use crate::spatial::{cell_order, permute, resize, CellGrid};
use crate::{Real, Vec3};
use rayon::prelude::*;

/// Neighbour lists in compressed-row form: the neighbours of point i are
/// `indices[offsets[i]..offsets[i + 1]]`.
#[derive(Debug, Clone, Default)]
pub struct NeighborLists {
    pub offsets: Vec<u32>,
    pub indices: Vec<u32>,
}

impl NeighborLists {
    /// The neighbours of point i.
    #[inline]
    pub fn of(&self, i: usize) -> &[u32] {
        &self.indices[self.offsets[i] as usize..self.offsets[i + 1] as usize]
    }

    /// Number of points the lists are for.
    pub fn len(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// True when there are no points.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Bytes held by the lists.
    pub fn memory_bytes(&self) -> usize {
        (self.offsets.capacity() + self.indices.capacity()) * std::mem::size_of::<u32>()
    }

    /// For every point of `queries` (in cell order, with its grid `query_grid` of the same
    /// cell size), the points of `targets` (with grid `target_grid`) closer than `radius`.
    /// With `exclude_self`, `queries` and `targets` are the same set and i is not its own
    /// neighbour. `radius` must not exceed the cell size.
    pub fn build(
        queries: &[Vec3],
        query_grid: &CellGrid,
        targets: &[Vec3],
        target_grid: &CellGrid,
        radius: Real,
        exclude_self: bool,
    ) -> Self {
        debug_assert!(radius <= query_grid.cell * (1.0 + 1e-12));
        let r2 = radius * radius;
        const CHUNK: usize = 64;
        let parts: Vec<(Vec<u32>, Vec<u32>)> = query_grid
            .cells
            .par_chunks(CHUNK)
            .map(|chunk| {
                let mut counts = Vec::new();
                let mut idx = Vec::new();
                let mut ranges = Vec::with_capacity(27);
                let mut found = Vec::new();
                for c in chunk {
                    target_grid.ranges_around(c.coord, &mut ranges);
                    let candidates: usize = ranges.iter().map(|&(s, e)| (e - s) as usize).sum();
                    found.resize(candidates.max(found.len()), 0);
                    for i in c.start..c.end {
                        let xi = queries[i as usize];
                        // Every candidate is written and the count advances only for a
                        // neighbour, without a branch: about one candidate in six is a
                        // neighbour, and once particles leave the lattice a branch on it
                        // mispredicts so often that the search took twice as long.
                        let mut n = 0;
                        for &(s, e) in &ranges {
                            for j in s..e {
                                found[n] = j;
                                let near = (xi - targets[j as usize]).norm_squared() < r2;
                                n += usize::from(near & (i != j || !exclude_self));
                            }
                        }
                        idx.extend_from_slice(&found[..n]);
                        counts.push(n as u32);
                    }
                }
                (counts, idx)
            })
            .collect();
        Self::assemble(queries.len(), &parts)
    }

    /// Joins per-chunk (counts, indices) parts, in order, into one set of lists, copying the
    /// parts in parallel.
    fn assemble(len: usize, parts: &[(Vec<u32>, Vec<u32>)]) -> Self {
        let mut offsets = Vec::with_capacity(len + 1);
        offsets.push(0u32);
        let mut total = 0u32;
        for (counts, _) in parts {
            for &c in counts {
                total += c;
                offsets.push(total);
            }
        }
        let mut indices = vec![0u32; total as usize];
        let mut rest = indices.as_mut_slice();
        let mut slots = Vec::with_capacity(parts.len());
        for (_, idx) in parts {
            let (head, tail) = rest.split_at_mut(idx.len());
            slots.push(head);
            rest = tail;
        }
        slots
            .into_par_iter()
            .zip(parts.par_iter())
            .for_each(|(slot, (_, idx))| slot.copy_from_slice(idx));
        Self { offsets, indices }
    }
}
