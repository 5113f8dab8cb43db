//! Hashed spatial acceleration for particle-particle and particle-point queries: the compact
//! hashed cell grid of the SPH neighbour search, over a sorted copy of the positions.

use crate::sph::neighbors::{cell_order, CellGrid};
use crate::{Real, Vec3};

/// A hashed grid over a set of positions that keeps their original indices.
pub(crate) struct PointHash {
    sorted: Vec<Vec3>,
    original: Vec<u32>,
    grid: CellGrid,
    cell: Real,
}

impl PointHash {
    /// The hash over `points` with cells of size `cell` (the largest query radius).
    pub(crate) fn new(points: &[Vec3], cell: Real) -> Self {
        let original = cell_order(points, cell);
        let sorted: Vec<Vec3> = original.iter().map(|&i| points[i as usize]).collect();
        let grid = CellGrid::build(&sorted, cell);
        Self {
            sorted,
            original,
            grid,
            cell,
        }
    }

    /// Calls `f(i)` with the original index of every point closer than `radius` (at most the
    /// cell size) to `p`.
    #[inline]
    pub(crate) fn for_each_near(&self, p: &Vec3, radius: Real, mut f: impl FnMut(usize)) {
        debug_assert!(radius <= self.cell * (1.0 + 1e-12));
        self.grid
            .for_each_near(p, &self.sorted, radius, |j| f(self.original[j] as usize));
    }
}
