//! The hashed cell grid and z-order shared by the SPH neighbour search and the vortex layer
//! (after Ihmsen et al. 2011).
//!
//! Points are sorted by the Morton (z-order) code of their cell, so that points close in space
//! are close in memory. The non-empty cells form a compact list, each a range of the sorted
//! points, and an open-addressing hash table maps a cell's code to its place in that list. The
//! 27 cells around a cell are looked up once per cell, not once per point.

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

/// Morton code of integer cell coordinates.
fn morton(c: [i64; 3]) -> u64 {
    let b = |v: i64| (v + BIAS).clamp(0, 2 * BIAS - 1) as u64;
    spread(b(c[0])) | (spread(b(c[1])) << 1) | (spread(b(c[2])) << 2)
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
    let inv = 1.0 / (cell * CELL_MARGIN);
    let mut keyed: Vec<(u64, u32)> = points
        .par_iter()
        .enumerate()
        .map(|(i, x)| (morton(cell_of(x, inv)), i as u32))
        .collect();
    keyed.par_sort_unstable();
    keyed.into_par_iter().map(|(_, i)| i).collect()
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

/// One slot of the hash table: a cell's Morton code and its range of points.
#[derive(Debug, Clone, Copy)]
struct Slot {
    key: u64,
    start: u32,
    end: u32,
}

/// A compact hashed grid over a set of points that is already in cell order.
#[derive(Debug, Clone)]
pub struct CellGrid {
    pub(crate) cell: Real,
    pub(crate) cells: Vec<Cell>,
    /// Open-addressing table (linear probing) of the non-empty cells, a power of two long.
    /// It holds the point ranges itself, so a lookup touches one place in memory.
    table: Vec<Slot>,
}

impl CellGrid {
    /// Builds the grid over `points`, which must be in the order [`cell_order`] gives for the
    /// same cell size (each cell's points must be contiguous).
    pub fn build(points: &[Vec3], cell: Real) -> Self {
        let cell = cell * CELL_MARGIN;
        let inv = 1.0 / cell;
        let mut cells: Vec<Cell> = Vec::new();
        let mut last_key = None;
        for (i, x) in points.iter().enumerate() {
            let coord = cell_of(x, inv);
            let key = morton(coord);
            if last_key == Some(key) {
                if let Some(c) = cells.last_mut() {
                    c.end = i as u32 + 1;
                }
            } else {
                cells.push(Cell {
                    coord,
                    start: i as u32,
                    end: i as u32 + 1,
                });
                last_key = Some(key);
            }
        }
        let size = (2 * cells.len()).next_power_of_two().max(16);
        let empty = Slot {
            key: EMPTY,
            start: 0,
            end: 0,
        };
        let mut table = vec![empty; size];
        for c in &cells {
            let key = morton(c.coord);
            let mut slot = Self::hash(key, size);
            while table[slot].key != EMPTY && table[slot].key != key {
                slot = (slot + 1) & (size - 1);
            }
            table[slot] = Slot {
                key,
                start: c.start,
                end: c.end,
            };
        }
        Self { cell, cells, table }
    }

    /// Home slot of a Morton code. The eight cells of an aligned 2 x 2 x 2 block (which share
    /// all but the lowest three bits of their code) get neighbouring slots, so the 27 lookups
    /// around a cell touch a few cache lines rather than 27.
    #[inline]
    fn hash(key: u64, size: usize) -> usize {
        let block = ((key >> 3).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 20) << 3;
        (block | (key & 7)) as usize & (size - 1)
    }

    /// The range of points in the cell with coordinates `coord`, if it holds any.
    #[inline]
    fn lookup(&self, coord: [i64; 3]) -> Option<(u32, u32)> {
        let key = morton(coord);
        let size = self.table.len();
        let mut slot = Self::hash(key, size);
        loop {
            let s = self.table[slot];
            if s.key == key {
                return Some((s.start, s.end));
            }
            if s.key == EMPTY {
                return None;
            }
            slot = (slot + 1) & (size - 1);
        }
    }

    /// Ranges of points in the up to 27 cells around `coord`.
    pub(crate) fn ranges_around(&self, coord: [i64; 3], out: &mut Vec<(u32, u32)>) {
        out.clear();
        for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    if let Some(r) = self.lookup([coord[0] + dx, coord[1] + dy, coord[2] + dz]) {
                        out.push(r);
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
            + self.table.capacity() * std::mem::size_of::<Slot>()
    }
}

impl CellGrid {
    /// Calls `f(j)` for every point j of `points` (the set this grid was built over) closer
    /// than `radius` (at most the cell size) to the arbitrary point `p`.
    pub fn for_each_near(&self, p: &Vec3, points: &[Vec3], radius: Real, mut f: impl FnMut(usize)) {
        let c = cell_of(p, 1.0 / self.cell);
        for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let Some((s, e)) = self.lookup([c[0] + dx, c[1] + dy, c[2] + dz]) else {
                        continue;
                    };
                    for j in s..e {
                        if (p - points[j as usize]).norm_squared() < radius * radius {
                            f(j as usize);
                        }
                    }
                }
            }
        }
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
        let original = cell_order(points, cell);
        let sorted: Vec<Vec3> = original.iter().map(|&i| points[i as usize]).collect();
        let grid = CellGrid::build(&sorted, cell);
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
