//! Target clusters for the Biot–Savart treecode (`super::biot_savart`): an octree of cubes
//! over the targets.
//!
//! The treecode's cost at a cluster grows with the cluster's size r (a source node is far
//! when R + r < theta |c - o|, so the near field holds the sources within about
//! (R + r) / theta), and its interpolation error with (r / |y|)^2. Runs of consecutive
//! fluid particles in the solver's cell order are compact only on average (on the dam break,
//! runs of 128 have a mean half-diagonal of 6.3 spacings, a tenth of them above 8.8, where a
//! cube of 128 has 4.4), so the targets are grouped here by cubes of a fixed edge instead:
//! a counting sort by cube, the cubes in Morton order, and the octree over them; nodes of at
//! most [`MERGE_BELOW`] targets stay whole.

use crate::{Real, Vec3};
use rayon::prelude::*;
use std::ops::Range;

/// Cube edge in units of the mollifier core (one particle spacing in MCVSPH): about 125
/// targets in a full cube.
pub const CUBE: Real = 5.0;

/// A node with at most this many targets is not split further (few sparse cubes at the
/// free surface make one cluster rather than many tiny ones).
pub const MERGE_BELOW: usize = 160;

/// Most bits per axis of a cube's Morton code.
const BITS: u32 = 20;

/// One cluster: a range of the sorted targets, their bounding box and sub-clusters.
pub struct Cluster {
    pub targets: Range<usize>,
    pub lo: Vec3,
    pub hi: Vec3,
    /// Sub-clusters (consecutive, covering `targets` in order); empty at the finest level.
    pub children: Vec<usize>,
}

/// The targets in cluster order and the cluster octree (root first).
pub struct Clusters {
    /// `order[k]`: the caller's index of the k-th sorted target.
    pub order: Vec<usize>,
    /// The targets in cluster order.
    pub x: Vec<Vec3>,
    pub nodes: Vec<Cluster>,
}

impl Clusters {
    /// Clusters over `targets` (at least one) with cubes of edge about `CUBE * core`.
    pub fn new(targets: &[Vec3], core: Real) -> Self {
        let (lo, hi) = bounds(targets.iter().copied());
        let extent = hi - lo;
        // Edge: CUBE cores, but no more cubes than targets over the bounding box (a few stray
        // particles far away must not make the grid huge), and at most 2^BITS a side.
        let volume = extent.x.max(core) * extent.y.max(core) * extent.z.max(core);
        let mut edge = (CUBE * core)
            .max((volume / targets.len() as Real).cbrt())
            .max(Real::MIN_POSITIVE);
        while extent.max() / edge >= Real::from(1u32 << BITS) {
            edge *= 2.0;
        }
        let dims = extent.map(|e| (e / edge) as usize + 1);
        let cell = |p: &Vec3| {
            let c = |a: usize| (((p[a] - lo[a]) / edge) as usize).min(dims[a] - 1);
            (c(0), c(1), c(2))
        };
        let linear = |(i, j, k): (usize, usize, usize)| (i * dims.y + j) * dims.z + k;
        let cube: Vec<usize> = targets.par_iter().map(|p| linear(cell(p))).collect();
        let mut count = vec![0usize; dims.x * dims.y * dims.z];
        for &c in &cube {
            count[c] += 1;
        }
        // Occupied cubes in Morton order, then a stable counting sort of the targets.
        let mut occupied: Vec<(u64, usize)> = count
            .iter()
            .enumerate()
            .filter(|(_, &n)| n > 0)
            .map(|(c, _)| {
                let (i, j, k) = (c / (dims.y * dims.z), c / dims.z % dims.y, c % dims.z);
                (morton(i as u64, j as u64, k as u64), c)
            })
            .collect();
        occupied.sort_unstable();
        let mut start = vec![0usize; count.len()];
        let mut cubes = Vec::with_capacity(occupied.len());
        let mut next = 0;
        for &(code, c) in &occupied {
            start[c] = next;
            cubes.push((code, next..next + count[c]));
            next += count[c];
        }
        let mut order = vec![0usize; targets.len()];
        for (k, &c) in cube.iter().enumerate() {
            order[start[c]] = k;
            start[c] += 1;
        }
        let x: Vec<Vec3> = order.par_iter().map(|&k| targets[k]).collect();
        let mut clusters = Self {
            order,
            x,
            nodes: Vec::new(),
        };
        clusters.nodes.push(Cluster {
            targets: 0..0,
            lo,
            hi,
            children: Vec::new(),
        });
        clusters.build(0, &cubes, 3 * (BITS - 1));
        clusters
    }

    /// Fills node `n` over the Morton-ordered `cubes` (code, target range), splitting by the
    /// octant digit at `shift` and below.
    fn build(&mut self, n: usize, cubes: &[(u64, Range<usize>)], shift: u32) {
        let targets = cubes[0].1.start..cubes[cubes.len() - 1].1.end;
        self.nodes[n].targets = targets.clone();
        if cubes.len() == 1 || targets.len() <= MERGE_BELOW {
            (self.nodes[n].lo, self.nodes[n].hi) = bounds(self.x[targets].iter().copied());
            return;
        }
        // The first digit, from `shift` down, at which the cubes differ (they are distinct).
        let digit = |code: u64, s: u32| (code >> s) & 7;
        let mut s = shift;
        while digit(cubes[0].0, s) == digit(cubes[cubes.len() - 1].0, s) {
            s -= 3;
        }
        let (mut lo, mut hi) = (Vec3::repeat(Real::MAX), Vec3::repeat(Real::MIN));
        let mut first = 0;
        while first < cubes.len() {
            let d = digit(cubes[first].0, s);
            let len = cubes[first..].partition_point(|c| digit(c.0, s) == d);
            let child = self.nodes.len();
            self.nodes.push(Cluster {
                targets: 0..0,
                lo,
                hi,
                children: Vec::new(),
            });
            self.nodes[n].children.push(child);
            self.build(child, &cubes[first..first + len], s.saturating_sub(3));
            lo = lo.inf(&self.nodes[child].lo);
            hi = hi.sup(&self.nodes[child].hi);
            first += len;
        }
        (self.nodes[n].lo, self.nodes[n].hi) = (lo, hi);
    }
}

/// Interleaves the low [`BITS`] bits of i, j, k (i highest in each triple).
fn morton(i: u64, j: u64, k: u64) -> u64 {
    (0..BITS).fold(0, |code, b| {
        code | (i >> b & 1) << (3 * b + 2) | (j >> b & 1) << (3 * b + 1) | (k >> b & 1) << (3 * b)
    })
}

/// Componentwise bounding box of `points` (at least one).
pub fn bounds(points: impl Iterator<Item = Vec3>) -> (Vec3, Vec3) {
    points.fold(
        (Vec3::repeat(Real::MAX), Vec3::repeat(Real::MIN)),
        |(lo, hi), p| (lo.inf(&p), hi.sup(&p)),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The clusters partition the targets: `order` is a permutation, each cluster's box holds
    /// its targets, sub-clusters cover their parent's range in order, and a finest cluster
    /// spans at most one cube unless it has few targets.
    #[test]
    fn clusters_partition_the_targets_into_compact_boxes() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        // A dense block and a sparse far-away cloud (a splash).
        let targets: Vec<Vec3> = (0..20_000)
            .map(|k| {
                let scale = if k < 19_000 { 1.0 } else { 8.0 };
                Vec3::new(
                    rng.random_range(0.0..scale),
                    rng.random_range(0.0..1.0),
                    rng.random_range(0.0..scale),
                )
            })
            .collect();
        let core = 0.03;
        let clusters = Clusters::new(&targets, core);
        let mut seen = vec![false; targets.len()];
        for &k in &clusters.order {
            assert!(!seen[k], "target {k} twice");
            seen[k] = true;
        }
        assert!(seen.iter().all(|&s| s));
        for (k, &i) in clusters.order.iter().enumerate() {
            assert_eq!(clusters.x[k], targets[i]);
        }
        let root = &clusters.nodes[0];
        assert_eq!(root.targets, 0..targets.len());
        let mut finest = 0;
        for c in &clusters.nodes {
            for p in &clusters.x[c.targets.clone()] {
                assert!(p >= &c.lo && p <= &c.hi, "{p} outside its box");
            }
            if c.children.is_empty() {
                finest += c.targets.len();
                let diagonal = (c.hi - c.lo).norm();
                assert!(
                    c.targets.len() <= MERGE_BELOW || diagonal <= 3f64.sqrt() * CUBE * core,
                    "{} targets over {diagonal}",
                    c.targets.len()
                );
            } else {
                let mut next = c.targets.start;
                for &child in &c.children {
                    assert_eq!(clusters.nodes[child].targets.start, next);
                    next = clusters.nodes[child].targets.end;
                }
                assert_eq!(next, c.targets.end);
            }
        }
        assert_eq!(finest, targets.len());
    }
}
