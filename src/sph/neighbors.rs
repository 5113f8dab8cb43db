//! Neighbour search on the compact hashed uniform grid of [`crate::spatial`]: neighbour lists
//! built in parallel, cell chunk by cell chunk, into one compressed-row (CSR) array of `u32`.

pub use crate::spatial::{cell_order, cell_order_and_codes, permute, resize, CellGrid};
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
        let soa = Components::of(targets);
        const CHUNK: usize = 64;
        let parts: Vec<(Vec<u32>, Vec<u32>)> = query_grid
            .cells
            .par_chunks(CHUNK)
            .map(|chunk| {
                let points = chunk.iter().map(|c| (c.end - c.start) as usize).sum();
                let mut counts = Vec::with_capacity(points);
                // About 33 neighbours a particle inside a fluid at rest density (h = 2 spacings);
                // reserving them up front saves the copies of a growing list.
                let mut idx = Vec::with_capacity(points * 40);
                let mut ranges = Vec::with_capacity(27);
                let mut found = Vec::new();
                for c in chunk {
                    target_grid.ranges_around(c.coord, &mut ranges);
                    if ranges.is_empty() {
                        // No targets near (the walls' grid, seen from inside the fluid).
                        counts.extend(std::iter::repeat_n(0, (c.end - c.start) as usize));
                        continue;
                    }
                    merge_adjacent(&mut ranges);
                    let candidates: usize = ranges.iter().map(|&(s, e)| (e - s) as usize).sum();
                    found.resize((candidates + filter::LANES).max(found.len()), 0);
                    for i in c.start..c.end {
                        let skip = if exclude_self { i } else { u32::MAX };
                        let xi = queries[i as usize];
                        let n = filter::near(&soa, &ranges, &xi, r2, skip, &mut found);
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

/// Target positions by component, so that eight consecutive points are one vector load each.
#[derive(Debug)]
struct Components {
    x: Vec<Real>,
    y: Vec<Real>,
    z: Vec<Real>,
}

impl Components {
    fn of(points: &[Vec3]) -> Self {
        Self {
            x: points.par_iter().map(|p| p.x).collect(),
            y: points.par_iter().map(|p| p.y).collect(),
            z: points.par_iter().map(|p| p.z).collect(),
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
/// except the index `skip`, written to the front of `found` (at least [`LANES`] longer than the
/// ranges hold); returns how many. Both forms compute |x_i - x_j|^2 with the same f64
/// operations in the same order (no fused multiply-add), so they find exactly the same
/// neighbours.
mod filter {
    use super::Components;
    use crate::{Real, Vec3};

    /// Candidates per vector of the wide form.
    pub const LANES: usize = 8;

    /// Every candidate is written and the count advances only for a neighbour, without a
    /// branch: about one candidate in six is a neighbour, and once particles leave the lattice
    /// a branch on it mispredicts so often that the search took twice as long.
    pub fn scalar(
        c: &Components,
        ranges: &[(u32, u32)],
        xi: &Vec3,
        r2: Real,
        skip: u32,
        found: &mut [u32],
    ) -> usize {
        let mut n = 0;
        for &(s, e) in ranges {
            for j in s..e {
                let k = j as usize;
                let (dx, dy, dz) = (xi.x - c.x[k], xi.y - c.y[k], xi.z - c.z[k]);
                found[n] = j;
                let near = dx * dx + dy * dy + dz * dz < r2;
                n += usize::from(near & (j != skip));
            }
        }
        n
    }

    /// The neighbours by [`wide`] where the CPU runs it, else by [`scalar`].
    pub fn near(
        c: &Components,
        ranges: &[(u32, u32)],
        xi: &Vec3,
        r2: Real,
        skip: u32,
        found: &mut [u32],
    ) -> usize {
        #[cfg(target_arch = "x86_64")]
        if wide_available() {
            // SAFETY: the CPU has the features, checked just above.
            return unsafe { wide(c, ranges, xi, r2, skip, found) };
        }
        scalar(c, ranges, xi, r2, skip, found)
    }

    /// Whether the CPU runs [`wide`].
    #[cfg(target_arch = "x86_64")]
    pub fn wide_available() -> bool {
        is_x86_feature_detected!("avx512f")
            && is_x86_feature_detected!("avx512vl")
            && is_x86_feature_detected!("popcnt")
    }

    /// [`scalar`] eight candidates at a time on AVX-512: masked loads read a range's last,
    /// partial vector, the distance test gives a lane mask, and the hardware compress packs the
    /// neighbours' indices to the front of a vector, which is stored whole at `found[n]` (the
    /// lanes past the count are overwritten next).
    ///
    /// # Safety
    /// The CPU must have AVX-512F, AVX-512VL and POPCNT ([`wide_available`]).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,avx512vl,popcnt")]
    pub unsafe fn wide(
        c: &Components,
        ranges: &[(u32, u32)],
        xi: &Vec3,
        r2: Real,
        skip: u32,
        found: &mut [u32],
    ) -> usize {
        use std::arch::x86_64::*;
        let total: usize = ranges.iter().map(|&(s, e)| (e - s) as usize).sum();
        assert!(found.len() >= total + LANES);
        let (px, py, pz) = (
            _mm512_set1_pd(xi.x),
            _mm512_set1_pd(xi.y),
            _mm512_set1_pd(xi.z),
        );
        let (r2, skip) = (_mm512_set1_pd(r2), _mm256_set1_epi32(skip as i32));
        let lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
        let mut n = 0;
        for &(s, e) in ranges {
            assert!(e as usize <= c.x.len() && e as usize <= c.y.len() && e as usize <= c.z.len());
            for k in (s..e).step_by(LANES) {
                // The lanes below `e`, computed without a branch (an if/else here made the
                // search in the dam-break step 1.7 times slower).
                let valid = ((1u16 << (e - k).min(LANES as u32)) - 1) as u8;
                let k = k as usize;
                // SAFETY: the masked loads touch only lanes below `e`, inside the arrays
                // (asserted above); `n + LANES <= total + LANES <= found.len()`.
                unsafe {
                    let load = |a: &[Real]| _mm512_maskz_loadu_pd(valid, a.as_ptr().add(k));
                    let dx = _mm512_sub_pd(px, load(&c.x));
                    let dy = _mm512_sub_pd(py, load(&c.y));
                    let dz = _mm512_sub_pd(pz, load(&c.z));
                    let d2 = _mm512_add_pd(
                        _mm512_add_pd(_mm512_mul_pd(dx, dx), _mm512_mul_pd(dy, dy)),
                        _mm512_mul_pd(dz, dz),
                    );
                    let index = _mm256_add_epi32(_mm256_set1_epi32(k as i32), lane);
                    let near = _mm512_cmp_pd_mask::<_CMP_LT_OQ>(d2, r2)
                        & _mm256_cmpneq_epi32_mask(index, skip)
                        & valid;
                    let packed = _mm256_maskz_compress_epi32(near, index);
                    _mm256_storeu_si256(found.as_mut_ptr().add(n).cast(), packed);
                    n += near.count_ones() as usize;
                }
            }
        }
        n
    }
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

    /// The vector filter and the scalar one find the same neighbours, in the same order, and
    /// both are the brute-force set, for every point with and without the self exclusion.
    /// (Without AVX-512 on the CPU only the scalar filter runs.)
    #[test]
    fn the_vector_and_scalar_filters_find_exactly_the_pairs_within_the_radius() {
        let x = points(7);
        let radius = 0.2;
        let grid = CellGrid::build(&x, radius);
        let soa = Components::of(&x);
        let (mut ranges, mut found) = (Vec::new(), vec![0; 1000]);
        let mut pairs = 0;
        for c in &grid.cells {
            grid.ranges_around(c.coord, &mut ranges);
            merge_adjacent(&mut ranges);
            for i in c.start..c.end {
                for skip in [i, u32::MAX] {
                    let xi = x[i as usize];
                    let n = filter::scalar(&soa, &ranges, &xi, radius * radius, skip, &mut found);
                    let mut got = found[..n].to_vec();
                    got.sort_unstable();
                    let want: Vec<u32> = (0..x.len() as u32)
                        .filter(|&j| {
                            j != skip && (xi - x[j as usize]).norm_squared() < radius * radius
                        })
                        .collect();
                    assert_eq!(got, want, "point {i}");
                    pairs += n;
                    #[cfg(target_arch = "x86_64")]
                    if filter::wide_available() {
                        let mut wide_found = vec![0; found.len()];
                        // SAFETY: the CPU has the features, checked just above.
                        let m = unsafe {
                            filter::wide(&soa, &ranges, &xi, radius * radius, skip, &mut wide_found)
                        };
                        assert_eq!(&wide_found[..m], &found[..n], "point {i}");
                    }
                }
            }
        }
        assert!(
            pairs > 20 * x.len(),
            "{pairs} pairs: the test would be vacuous"
        );
    }
}
