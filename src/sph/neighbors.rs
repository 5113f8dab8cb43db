//! Neighbour search on the compact hashed uniform grid of [`crate::spatial`]: neighbour lists
//! built in parallel, cell chunk by cell chunk, into one compressed-row (CSR) array of `u32`.

use crate::simd::{bits, norm2, pack_indices, Level, LANES};
use crate::spatial::Cell;
pub use crate::spatial::{cell_order, cell_order_and_codes, permute, resize, CellGrid};
use crate::{Real, Vec3};
use pulp::{Simd, WithSimd};
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
        let search = Search {
            queries,
            query_grid,
            targets: &Components::of(targets),
            target_grid,
            r2: radius * radius,
            exclude_self,
        };
        search.run(Level::active())
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

/// One search: what [`NeighborLists::build`] takes, the targets by component.
struct Search<'a> {
    queries: &'a [Vec3],
    query_grid: &'a CellGrid,
    targets: &'a Components,
    target_grid: &'a CellGrid,
    r2: Real,
    exclude_self: bool,
}

impl Search<'_> {
    /// The lists, with the distance test compiled for `level`.
    fn run(&self, level: Level) -> NeighborLists {
        const CHUNK: usize = 64;
        let parts: Vec<(Vec<u32>, Vec<u32>)> = self
            .query_grid
            .cells
            .par_chunks(CHUNK)
            .map(|cells| {
                level.run(Chunk {
                    search: self,
                    cells,
                })
            })
            .collect();
        NeighborLists::assemble(self.queries.len(), &parts)
    }
}

/// The neighbour counts and indices of the query points of a chunk of cells.
struct Chunk<'a> {
    search: &'a Search<'a>,
    cells: &'a [Cell],
}

impl WithSimd for Chunk<'_> {
    type Output = (Vec<u32>, Vec<u32>);

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) -> Self::Output {
        let s = self.search;
        let points = self.cells.iter().map(|c| (c.end - c.start) as usize).sum();
        let mut counts = Vec::with_capacity(points);
        // About 33 neighbours a particle inside a fluid at rest density (h = 2 spacings);
        // reserving them up front saves the copies of a growing list.
        let mut idx = Vec::with_capacity(points * 40);
        let mut ranges = Vec::with_capacity(27);
        let mut found = Vec::new();
        for c in self.cells {
            s.target_grid.ranges_around(c.coord, &mut ranges);
            if ranges.is_empty() {
                // No targets near (the walls' grid, seen from inside the fluid).
                counts.extend(std::iter::repeat_n(0, (c.end - c.start) as usize));
                continue;
            }
            merge_adjacent(&mut ranges);
            let candidates: usize = ranges.iter().map(|&(s, e)| (e - s) as usize).sum();
            found.resize((candidates + LANES).max(found.len()), 0);
            for i in c.start..c.end {
                let skip = if s.exclude_self { i } else { u32::MAX };
                let xi = s.queries[i as usize];
                let n = near(simd, s.targets, &ranges, &xi, s.r2, skip, &mut found);
                idx.extend_from_slice(&found[..n]);
                counts.push(n as u32);
            }
        }
        (counts, idx)
    }
}

/// Target positions by component, so that [`LANES`] consecutive points are one vector load
/// each, followed by [`LANES`] points at infinity, so that a range's last vector can be
/// loaded whole.
#[derive(Debug)]
struct Components {
    x: Vec<Real>,
    y: Vec<Real>,
    z: Vec<Real>,
}

impl Components {
    fn of(points: &[Vec3]) -> Self {
        let padded = |axis: usize| {
            let mut c = Vec::with_capacity(points.len() + LANES);
            c.par_extend(points.par_iter().map(|p| p[axis]));
            c.extend([Real::INFINITY; LANES]);
            c
        };
        Self {
            x: padded(0),
            y: padded(1),
            z: padded(2),
        }
    }
}

/// Joins consecutive index ranges that continue one another (cells next to each other in
/// z-order, such as the two halves of an aligned pair along x), so the filter runs fewer,
/// longer ranges.
fn merge_adjacent(ranges: &mut Vec<(u32, u32)>) {
    ranges.dedup_by(|next, prev| {
        let joins = next.0 == prev.1;
        if joins {
            prev.1 = next.1;
        }
        joins
    });
}

/// The distance test of the search: the points of `ranges` closer than sqrt(`r2`) to `xi`,
/// except the index `skip`, written in index order to the front of `found` (at least
/// [`LANES`] longer than the ranges hold); returns how many.
///
/// [`LANES`] candidates at a time: |x_i - x_j|^2 in one vector (the same f64 operations, no
/// fused multiply-add, at every level, so every level finds the same neighbours), the test as
/// a bit mask, and the neighbours' indices packed to the front of `found` without a branch:
/// about one candidate in six is a neighbour, and once particles leave the lattice a branch
/// on it mispredicts so often that the search took twice as long.
#[inline(always)]
fn near<S: Simd>(
    simd: S,
    c: &Components,
    ranges: &[(u32, u32)],
    xi: &Vec3,
    r2: Real,
    skip: u32,
    found: &mut [u32],
) -> usize {
    let (px, py, pz) = (
        simd.splat_f64s(xi.x),
        simd.splat_f64s(xi.y),
        simd.splat_f64s(xi.z),
    );
    let r2 = simd.splat_f64s(r2);
    // Candidate indices as f64 lanes (exact below 2^53), tested against the range's end and
    // `skip` in vector compares.
    let lane: [Real; LANES] = std::array::from_fn(|l| l as Real);
    let (lane, step) = (pulp::cast(lane), simd.splat_f64s(LANES as Real));
    let skip = simd.splat_f64s(Real::from(skip));
    let mut n = 0;
    for &(s, e) in ranges {
        // The range's candidates in whole vectors: the last one reads past `e` into the next
        // points or the padding, lanes the mask below drops.
        let (s, len) = (s as usize, ((e - s) as usize).next_multiple_of(LANES));
        let (x, y, z) = (&c.x[s..s + len], &c.y[s..s + len], &c.z[s..s + len]);
        let (x, y, z) = (
            S::as_simd_f64s(x).0,
            S::as_simd_f64s(y).0,
            S::as_simd_f64s(z).0,
        );
        let end = simd.splat_f64s(Real::from(e));
        let mut index = simd.add_f64s(simd.splat_f64s(s as Real), lane);
        let vectors = x.iter().zip(y).zip(z);
        for (((&x, &y), &z), k) in vectors.zip((s as u32..).step_by(LANES)) {
            let (dx, dy, dz) = (
                simd.sub_f64s(px, x),
                simd.sub_f64s(py, y),
                simd.sub_f64s(pz, z),
            );
            let d2 = norm2(simd, dx, dy, dz);
            // Within the radius, below `e` and not `skip`, without a branch (an if/else for
            // the range's last vector made the search in the dam-break step 1.7 times slower).
            let near = simd.and_m64s(
                simd.and_m64s(simd.less_than_f64s(d2, r2), simd.less_than_f64s(index, end)),
                simd.not_m64s(simd.equal_f64s(index, skip)),
            );
            index = simd.add_f64s(index, step);
            let out = (&mut found[n..n + LANES]).try_into().unwrap();
            n += pack_indices(bits::<S>(near), k, out);
        }
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    /// Points on a lattice of spacing `s` (so that many pairs lie exactly at the radius 2 s,
    /// which the strict test excludes) and, apart from it, uniform random points.
    fn points(seed: u64) -> Vec<Vec3> {
        let s = 0.1;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let mut x: Vec<Vec3> = (0..8)
            .flat_map(|i| (0..8).flat_map(move |j| (0..8).map(move |k| (i, j, k))))
            .map(|(i, j, k)| Vec3::new(i as Real, j as Real, k as Real) * s)
            .collect();
        x.extend((0..600).map(|_| {
            Vec3::new(
                rng.random::<Real>(),
                rng.random::<Real>(),
                rng.random::<Real>(),
            ) * 1.6
                - Vec3::repeat(0.4)
        }));
        let perm = cell_order(&x, 2.0 * s);
        permute(&mut x, &perm);
        x
    }

    /// At every level the CPU runs, the lists are exactly the scalar level's (same
    /// neighbours in the same order) and hold exactly the brute-force pairs within the
    /// radius: of a set with itself (self excluded) and of another set (nothing excluded).
    #[test]
    fn every_level_finds_exactly_the_pairs_within_the_radius() {
        let (x, others) = (points(7), points(8));
        let radius = 0.2;
        let grid = CellGrid::build(&x, radius);
        let other_grid = CellGrid::build(&others, radius);
        for (targets, target_grid, exclude_self) in
            [(&x, &grid, true), (&others, &other_grid, false)]
        {
            let search = Search {
                queries: &x,
                query_grid: &grid,
                targets: &Components::of(targets),
                target_grid,
                r2: radius * radius,
                exclude_self,
            };
            let scalar = search.run(Level::Scalar);
            for (i, xi) in x.iter().enumerate() {
                let mut got = scalar.of(i).to_vec();
                got.sort_unstable();
                let want: Vec<u32> = (0..targets.len() as u32)
                    .filter(|&j| {
                        !(exclude_self && j == i as u32)
                            && (xi - targets[j as usize]).norm_squared() < radius * radius
                    })
                    .collect();
                assert_eq!(got, want, "point {i}");
            }
            assert!(
                scalar.indices.len() > 10 * x.len(),
                "{} pairs: the test would be vacuous",
                scalar.indices.len()
            );
            for level in Level::ALL.into_iter().filter(|l| l.supported()) {
                let lists = search.run(level);
                assert_eq!(lists.offsets, scalar.offsets, "{level:?}");
                assert_eq!(lists.indices, scalar.indices, "{level:?}");
            }
        }
    }
}
