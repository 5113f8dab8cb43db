//! The hashed cell grid and z-order shared by the SPH neighbour search and the vortex layer
//! (after Ihmsen et al. 2011).
//!
//! Points are sorted by the Morton (z-order) code of their cell, so that points close in space
//! are close in memory. The non-empty cells form a compact list, each a range of the sorted
//! points, and an open-addressing hash table maps each non-empty aligned 2 x 2 x 2 block of
//! cells to its eight cells' ranges. The at most eight blocks that hold the 27 cells around a
//! cell are looked up once per cell, not once per point.

use crate::{Real, Vec3};
use rayon::prelude::*;

/// Bias that makes cell coordinates non-negative for the 21-bit-per-axis Morton code.
const BIAS: i64 = 1 << 20;
/// Key of an empty hash slot (Morton codes use 63 bits).
const EMPTY: u64 = u64::MAX;

/// Spreads the low 21 bits of `v` so that two zero bits separate each (for Morton codes).
fn spread(v: u64) -> u64 {
    let mut x = v & 0x1f_ffff;
    x = (x | (x << 32)) & 0x1f00000000ffff;
    x = (x | (x << 16)) & 0x1f0000ff0000ff;
    x = (x | (x << 8)) & 0x100f00f00f00f00f;
    x = (x | (x << 4)) & 0x10c30c30c30c30c3;
    x = (x | (x << 2)) & 0x1249249249249249;
    x
}

/// A cell coordinate made non-negative (and clamped to 21 bits) for the Morton code.
#[inline]
fn biased(v: i64) -> u64 {
    (v + BIAS).clamp(0, 2 * BIAS - 1) as u64
}

/// Morton code of integer cell coordinates.
fn morton(c: [i64; 3]) -> u64 {
    spread(biased(c[0])) | (spread(biased(c[1])) << 1) | (spread(biased(c[2])) << 2)
}

/// Integer coordinates of the cell holding `x`.
#[inline]
pub(crate) fn cell_of(x: &Vec3, inv_cell: Real) -> [i64; 3] {
    [
        (x.x * inv_cell).floor() as i64,
        (x.y * inv_cell).floor() as i64,
        (x.z * inv_cell).floor() as i64,
    ]
}

/// Cells are this much wider than asked, so that rounding in `x / cell` can never put two points
/// closer than the cell size two cells apart (which would hide them from each other).
const CELL_MARGIN: Real = 1.0 + 1e-9;

/// The permutation that sorts `points` by the Morton code of their cell (cell size `cell`):
/// entry k of the result is the old index of the point that goes to place k.
pub fn cell_order(points: &[Vec3], cell: Real) -> Vec<u32> {
    cell_order_and_codes(points, cell).0
}

/// [`cell_order`] and the cell codes of the points in that order, which
/// [`CellGrid::from_codes`] builds on once the points are permuted: the codes the sort
/// computed are not computed again.
pub fn cell_order_and_codes(points: &[Vec3], cell: Real) -> (Vec<u32>, Vec<u64>) {
    let inv = 1.0 / (cell * CELL_MARGIN);
    let mut keyed: Vec<(u64, u32)> = points
        .par_iter()
        .enumerate()
        .map(|(i, x)| (morton(cell_of(x, inv)), i as u32))
        .collect();
    keyed.par_sort_unstable();
    keyed.into_par_iter().map(|(code, i)| (i, code)).unzip()
}

/// Reorders `data` so that `data[k]` becomes the old `data[perm[k]]`.
pub fn permute<T: Copy + Send + Sync>(data: &mut Vec<T>, perm: &[u32]) {
    let reordered: Vec<T> = perm.par_iter().map(|&i| data[i as usize]).collect();
    *data = reordered;
}

/// Keeps the entries of `data` where `keep` holds, in order, then appends `added` copies of
/// `value`: how per-particle state follows particles removed and spawned at open boundaries.
/// A vector that does not hold one entry per particle (state not made yet) is left alone.
pub fn resize<T: Clone>(data: &mut Vec<T>, keep: &[bool], added: usize, value: T) {
    if data.len() != keep.len() {
        return;
    }
    let mut k = keep.iter();
    data.retain(|_| *k.next().expect("one flag per entry"));
    data.extend(std::iter::repeat_n(value, added));
}

/// The smallest box (lower and upper corner) holding every point; for no points the lower
/// corner is +infinity and the upper -infinity, so every test against it fails.
pub fn bounding_box(points: &[Vec3]) -> (Vec3, Vec3) {
    let far = Vec3::repeat(Real::INFINITY);
    points
        .iter()
        .fold((far, -far), |(lo, hi), x| (lo.inf(x), hi.sup(x)))
}

/// One non-empty cell: its coordinates and the range of sorted points inside it.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Cell {
    pub(crate) coord: [i64; 3],
    pub(crate) start: u32,
    pub(crate) end: u32,
}

/// The point ranges of the eight cells of one aligned 2 x 2 x 2 block of cells, by the low
/// three bits of their Morton codes; an empty cell's range is empty. One cache line.
#[derive(Debug, Clone, Copy, Default)]
#[repr(C, align(64))]
struct BlockRanges([(u32, u32); 8]);

/// A compact hashed grid over a set of points that is already in cell order.
#[derive(Debug, Clone)]
pub struct CellGrid {
    pub(crate) cell: Real,
    pub(crate) cells: Vec<Cell>,
    /// Open-addressing table (linear probing) of the non-empty 2 x 2 x 2 blocks of cells, a
    /// power of two long: block codes (a cell's Morton code without its low three bits) in
    /// `keys`, the eight cells' point ranges beside them in `ranges`. The 27 cells around a
    /// cell lie in at most eight blocks, so a search looks up at most eight keys per cell,
    /// and a block absent from the table (the walls' grid, seen from most fluid cells) is
    /// a short probe into a table at most half full.
    keys: Vec<u64>,
    ranges: Vec<BlockRanges>,
}

impl CellGrid {
    /// Builds the grid over `points`, which must be in the order [`cell_order`] gives for the
    /// same cell size (each cell's points must be contiguous).
    pub fn build(points: &[Vec3], cell: Real) -> Self {
        let inv = 1.0 / (cell * CELL_MARGIN);
        let codes: Vec<u64> = points.par_iter().map(|x| morton(cell_of(x, inv))).collect();
        Self::from_codes(points, &codes, cell)
    }

    /// [`Self::build`] from the points' cell codes at the same cell size, in their order
    /// ([`cell_order_and_codes`]).
    pub fn from_codes(points: &[Vec3], codes: &[u64], cell: Real) -> Self {
        assert_eq!(points.len(), codes.len(), "one cell code per point");
        let cell = cell * CELL_MARGIN;
        let inv = 1.0 / cell;
        let mut cells: Vec<Cell> = Vec::new();
        for (i, (x, &key)) in points.iter().zip(codes).enumerate() {
            match cells.last_mut() {
                Some(c) if codes[c.start as usize] == key => c.end = i as u32 + 1,
                _ => cells.push(Cell {
                    coord: cell_of(x, inv),
                    start: i as u32,
                    end: i as u32 + 1,
                }),
            }
        }
        let blocks = 1 + cells
            .windows(2)
            .filter(|w| codes[w[0].start as usize] >> 3 != codes[w[1].start as usize] >> 3)
            .count();
        let size = (2 * blocks).next_power_of_two().max(16);
        let mut keys = vec![EMPTY; size];
        let mut ranges = vec![BlockRanges::default(); size];
        for c in &cells {
            let code = codes[c.start as usize];
            let slot = Self::probe(&keys, code >> 3);
            keys[slot] = code >> 3;
            ranges[slot].0[(code & 7) as usize] = (c.start, c.end);
        }
        Self {
            cell,
            cells,
            keys,
            ranges,
        }
    }

    /// The slot of block code `block` in `keys`: where it is, or the empty slot where it goes.
    #[inline]
    fn probe(keys: &[u64], block: u64) -> usize {
        let mask = keys.len() - 1;
        let mut slot = (block.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 32) as usize & mask;
        while keys[slot] != EMPTY && keys[slot] != block {
            slot = (slot + 1) & mask;
        }
        slot
    }

    /// The slot of block code `block`, if the block holds points.
    #[inline]
    fn block(&self, block: u64) -> Option<usize> {
        let slot = Self::probe(&self.keys, block);
        (self.keys[slot] == block).then_some(slot)
    }

    /// Ranges of points in the up to 27 cells around `coord`, in the order z, y, x (each
    /// outermost to innermost, -1 to +1).
    pub(crate) fn ranges_around(&self, coord: [i64; 3], out: &mut Vec<(u32, u32)>) {
        out.clear();
        self.each_range_around(coord, |r| out.push(r));
    }

    /// Calls `f` with the range of points of each non-empty cell of the 27 around `coord`, in
    /// the order of [`Self::ranges_around`].
    #[inline]
    fn each_range_around(&self, coord: [i64; 3], mut f: impl FnMut((u32, u32))) {
        // A cell's block is its biased coordinates halved (the Morton code of the halves is
        // the cell's code without its low three bits). The 27 cells span one or two blocks
        // along each axis: look each block up once.
        let first = coord.map(|c| biased(c - 1) >> 1);
        let span = coord.map(|c| (biased(c + 1) >> 1) - (biased(c - 1) >> 1));
        let mut slots = [[[None; 2]; 2]; 2];
        for (bz, plane) in slots.iter_mut().enumerate().take(span[2] as usize + 1) {
            for (by, row) in plane.iter_mut().enumerate().take(span[1] as usize + 1) {
                for (bx, slot) in row.iter_mut().enumerate().take(span[0] as usize + 1) {
                    let b = [
                        first[0] + bx as u64,
                        first[1] + by as u64,
                        first[2] + bz as u64,
                    ];
                    *slot = self.block(spread(b[0]) | (spread(b[1]) << 1) | (spread(b[2]) << 2));
                }
            }
        }
        if slots.iter().flatten().flatten().all(Option::is_none) {
            return;
        }
        let axis = |a: usize| [-1, 0, 1].map(|d| biased(coord[a] + d));
        let (xs, ys, zs) = (axis(0), axis(1), axis(2));
        for z in zs {
            let plane = &slots[((z >> 1) - first[2]) as usize];
            for y in ys {
                let row = &plane[((y >> 1) - first[1]) as usize];
                for x in xs {
                    if let Some(slot) = row[((x >> 1) - first[0]) as usize] {
                        let low = (x & 1) | ((y & 1) << 1) | ((z & 1) << 2);
                        let r = self.ranges[slot].0[low as usize];
                        if r.0 != r.1 {
                            f(r);
                        }
                    }
                }
            }
        }
    }

    /// Number of non-empty cells.
    pub fn cell_count(&self) -> usize {
        self.cells.len()
    }

    /// Bytes held by the grid.
    pub fn memory_bytes(&self) -> usize {
        self.cells.capacity() * std::mem::size_of::<Cell>()
            + self.keys.capacity() * std::mem::size_of::<u64>()
            + self.ranges.capacity() * std::mem::size_of::<BlockRanges>()
    }
}

impl CellGrid {
    /// Calls `f(j)` for every point j of `points` (the set this grid was built over) closer
    /// than `radius` (at most the cell size) to the arbitrary point `p`.
    pub fn for_each_near(&self, p: &Vec3, points: &[Vec3], radius: Real, mut f: impl FnMut(usize)) {
        self.each_range_around(cell_of(p, 1.0 / self.cell), |(s, e)| {
            for j in s..e {
                if (p - points[j as usize]).norm_squared() < radius * radius {
                    f(j as usize);
                }
            }
        });
    }
}

/// A hashed grid over a set of positions that keeps their original indices.
pub(crate) struct PointHash {
    sorted: Vec<Vec3>,
    original: Vec<u32>,
    grid: CellGrid,
    cell: Real,
    /// Bounding box of the points: a query farther than its radius from it is answered
    /// without touching the table (most queries, when a few points sit among many queries).
    lo: Vec3,
    hi: Vec3,
}

impl PointHash {
    /// The hash over `points` with cells of size `cell` (the largest query radius).
    pub(crate) fn new(points: &[Vec3], cell: Real) -> Self {
        let (original, codes) = cell_order_and_codes(points, cell);
        let sorted: Vec<Vec3> = original.iter().map(|&i| points[i as usize]).collect();
        let grid = CellGrid::from_codes(&sorted, &codes, cell);
        let (lo, hi) = bounding_box(&sorted);
        Self {
            sorted,
            original,
            grid,
            cell,
            lo,
            hi,
        }
    }

    /// Calls `f(i)` with the original index of every point closer than `radius` (at most the
    /// cell size) to `p`.
    #[inline]
    pub(crate) fn for_each_near(&self, p: &Vec3, radius: Real, mut f: impl FnMut(usize)) {
        debug_assert!(radius <= self.cell * (1.0 + 1e-12));
        if (0..3).any(|a| p[a] < self.lo[a] - radius || p[a] > self.hi[a] + radius) {
            return;
        }
        self.grid
            .for_each_near(p, &self.sorted, radius, |j| f(self.original[j] as usize));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    /// Every query finds exactly the points within the radius, once each, through the block
    /// table: on a dense cloud straddling the origin (negative cell coordinates, blocks cut
    /// by the sign change) and on sparse points far apart (blocks holding one cell, most
    /// neighbouring blocks absent), from queries inside and outside the clouds.
    #[test]
    fn queries_find_exactly_the_points_within_the_radius() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let mut random = |scale: Real| {
            Vec3::new(rng.random(), rng.random(), rng.random()).map(|c: Real| (c - 0.5) * scale)
        };
        let radius = 0.1;
        for (points, spread, hits) in [(2000, 1.0, 1000), (300, 20.0, 200)] {
            let cloud: Vec<Vec3> = (0..points).map(|_| random(spread)).collect();
            let hash = PointHash::new(&cloud, radius);
            let mut within = 0;
            for k in 0..400 {
                let p = if k % 2 == 0 {
                    cloud[k % points] + random(0.1)
                } else {
                    random(1.5 * spread)
                };
                let mut got = Vec::new();
                hash.for_each_near(&p, radius, |i| got.push(i));
                got.sort_unstable();
                let want: Vec<usize> = (0..points)
                    .filter(|&i| (p - cloud[i]).norm_squared() < radius * radius)
                    .collect();
                assert_eq!(got, want, "query {k} at {p:?}");
                within += want.len();
            }
            assert!(within >= hits, "{within} hits: the test would be vacuous");
        }
    }
}
