//! Mollified Biot–Savart sums (Ye et al. Eq. 26): the direct O(N_f N) sum and a treecode.
//!
//! u(x) = sum_k beta_k x g(x - x_k), g(y) = y / (4 pi (|y|^2 + d^2)^(3/2)): the Rosenhead–Moore
//! kernel of core d (see `super::mcvsph`), with beta_k a vortex particle's vorticity times
//! volume.
//!
//! **Treecode.** MCVSPH has few sources (N_f / 100) and many targets (every fluid particle), so
//! the far field is built on both sides, in the manner of Barnes & Hut with target clusters:
//!
//! - an octree over the sources, each node with its total strength B = sum beta_k and first
//!   moments about its centroid c, a = sum beta_k x delta_k and M = sum beta_k delta_k^T
//!   (delta_k = x_k - c). Vector strengths of both signs have no centre that cancels the
//!   dipole, so it is kept: with y = x - c and s^2 = |y|^2 + d^2, the Taylor expansion
//!   g(y - delta) = g(y) - J(y) delta gives
//!   u(x) = (B x y / s^3 - a / s^3 + 3 (M y) x y / s^5) / (4 pi) + O((R / |y|)^2),
//!   R the node's radius about c;
//! - targets in an octree of clusters (`super::clusters`: cubes of about five particle
//!   spacings, about 125 targets, and their parents). A node is far from a cluster when
//!   R + r < theta |c - o|, with o and r the centre and half-diagonal of the cluster's bounding
//!   box. Far nodes are evaluated at the box's eight corners and interpolated trilinearly to
//!   each target (second-order error, (r / |y|)^2 <= theta^2 relative, like the expansion
//!   itself); a node that is neither far nor larger than the cluster is handed down to the
//!   sub-clusters, and at the finest level near leaves are summed directly, per target, with
//!   the exact mollified kernel. The coarse levels take the distant nodes, so the corner
//!   evaluations per target stay few. A cluster's far field is handed down to its
//!   sub-clusters as its values at their corners (restricting a trilinear field to a sub-box
//!   is exact), so each target is interpolated once, at the level where its descent ends.
//! - both inner loops (near sources per target, far nodes per eight corners) run in f32
//!   lanes, on AVX2 and FMA where the CPU has them (module `simd`); at 91k fluid particles
//!   and 911 vortex particles the near field is about half the work.
//!
//! The error is O(theta^2) relative to each far node's contribution and vanishes as
//! theta -> 0 (at theta = 0 every pair is direct); `tests/refine_operators.rs` checks both.

use super::clusters::{bounds, Clusters};
use crate::Mat3;
use crate::{Real, Vec3};
use nalgebra::Vector3;
use rayon::prelude::*;
use std::f64::consts::PI;

/// Default opening parameter. The tree's error only has to stay well below the Monte Carlo
/// error of the sample it sums, which is large: on the dam-break vorticity at 91k fluid
/// particles (`eddy bench --mcvsph-error`, 5 seeds) the estimate's relative RMS error against
/// the full sum is 1.06 at 1 % vortex particles and 0.30 at 10 %. At theta = 0.5 the tree
/// adds 2.4 % and 1.5 % (RMS, against the direct sum of the same sample), and the total error
/// is unchanged to three digits; it takes 29 % less time than theta = 0.35 (0.76 % and
/// 0.59 %), and 0.6 another 13 % less for 3.4 % and 2.3 %.
pub const DEFAULT_THETA: Real = 0.5;

/// Most sources in a leaf of the octree.
const LEAF: usize = 4;

/// Octree depth beyond which a node stays a leaf (coincident sources).
const MAX_DEPTH: usize = 40;

/// f32 lanes of the direct sum (independent partial sums the compiler can vectorise).
const LANES: usize = 8;

/// [`LANES`] sources in f32, structure of arrays: positions and strengths.
#[derive(Default, Clone, Copy)]
struct Block {
    x: [f32; LANES],
    y: [f32; LANES],
    z: [f32; LANES],
    bx: [f32; LANES],
    by: [f32; LANES],
    bz: [f32; LANES],
}

/// Sources in blocks of [`LANES`], relative to an origin; the last block is padded with zero
/// strengths.
#[derive(Default)]
struct Lanes {
    blocks: Vec<Block>,
    len: usize,
}

impl Lanes {
    /// Adds a source at `x` (relative to the origin) of strength `b`.
    fn push(&mut self, x: Vec3, b: Vec3) {
        let l = self.len % LANES;
        if l == 0 {
            self.blocks.push(Block::default());
        }
        if let Some(block) = self.blocks.last_mut() {
            block.x[l] = x.x as f32;
            block.y[l] = x.y as f32;
            block.z[l] = x.z as f32;
            block.bx[l] = b.x as f32;
            block.by[l] = b.y as f32;
            block.bz[l] = b.z as f32;
        }
        self.len += 1;
    }

    /// sum_k b_k x (p - x_k) / (|p - x_k|^2 + d2)^(3/2), without the 1 / (4 pi).
    ///
    /// This loop is the sums' whole near-field cost, so it runs in f32 (twice the SIMD lanes
    /// of f64) with positions relative to a nearby origin, and on 256-bit vectors where the
    /// CPU has them; the lanes are added up in f64. The relative accuracy, about 1e-6, is far
    /// below the Monte Carlo error.
    fn sum_at(&self, p: Vector3<f32>, d2: f32) -> Vec3 {
        #[cfg(target_arch = "x86_64")]
        if simd::available() {
            // SAFETY: the CPU has AVX2 and FMA, checked just above.
            return unsafe { simd::sum_at(&self.blocks, p, d2) };
        }
        self.sum_lanes(p, d2)
    }

    /// The portable body of [`Self::sum_at`].
    fn sum_lanes(&self, p: Vector3<f32>, d2: f32) -> Vec3 {
        let (mut ux, mut uy, mut uz) = ([0f32; LANES], [0f32; LANES], [0f32; LANES]);
        for b in &self.blocks {
            for l in 0..LANES {
                let (dx, dy, dz) = (p.x - b.x[l], p.y - b.y[l], p.z - b.z[l]);
                let r2 = dx * dx + dy * dy + dz * dz + d2;
                let inv = 1.0 / (r2 * r2.sqrt());
                ux[l] += (b.by[l] * dz - b.bz[l] * dy) * inv;
                uy[l] += (b.bz[l] * dx - b.bx[l] * dz) * inv;
                uz[l] += (b.bx[l] * dy - b.by[l] * dx) * inv;
            }
        }
        let sum = |a: [f32; LANES]| a.iter().map(|&x| Real::from(x)).sum::<Real>();
        Vec3::new(sum(ux), sum(uy), sum(uz))
    }
}

/// The direct mollified Biot–Savart sum at every target, in parallel over targets.
pub fn biot_savart(targets: &[Vec3], sources: &[Vec3], beta: &[Vec3], core: Real) -> Vec<Vec3> {
    let origin = sources.first().copied().unwrap_or_else(Vec3::zeros);
    let mut lanes = Lanes::default();
    for (x, b) in sources.iter().zip(beta) {
        lanes.push(x - origin, *b);
    }
    let d2 = (core * core) as f32;
    targets
        .par_iter()
        .map(|p| lanes.sum_at((p - origin).cast::<f32>(), d2) / (4.0 * PI))
        .collect()
}

/// One octree node: its sources (a range of the tree's sorted sources), children and moments.
struct Node {
    /// Centroid of the source positions, the expansion centre.
    centre: Vec3,
    /// Largest distance from the centre to a source.
    radius: Real,
    /// The far-field moments in f32, the precision the far field is evaluated in: the total
    /// strength B, a = sum beta_k x delta_k and M = sum beta_k delta_k^T (row-major).
    moments: Moments,
    sources: std::ops::Range<usize>,
    /// Children are `children` consecutive nodes (none for a leaf).
    first_child: usize,
    children: usize,
}

/// A node's far-field moments (module documentation), f32.
#[derive(Clone, Copy)]
struct Moments {
    total: [f32; 3],
    twist: [f32; 3],
    moment: [f32; 9],
}

/// A Barnes–Hut octree over vortex particles, evaluated at clusters of targets.
pub struct BiotSavartTree {
    nodes: Vec<Node>,
    /// Source positions and strengths in tree order.
    x: Vec<Vec3>,
    beta: Vec<Vec3>,
    core: Real,
}

impl BiotSavartTree {
    /// The tree over `sources` with strengths `beta` and mollifier core `core`.
    pub fn new(sources: &[Vec3], beta: &[Vec3], core: Real) -> Self {
        let mut order: Vec<usize> = (0..sources.len().min(beta.len())).collect();
        let mut tree = Self {
            nodes: Vec::new(),
            x: Vec::new(),
            beta: Vec::new(),
            core,
        };
        if order.is_empty() {
            return tree;
        }
        let (lo, hi) = bounds(order.iter().map(|&k| sources[k]));
        let half = 0.5 * (hi - lo).max();
        tree.nodes.push(tree.node(sources, beta, &order, 0));
        tree.split(0, sources, beta, &mut order, 0.5 * (lo + hi), half, 0);
        tree.x = order.iter().map(|&k| sources[k]).collect();
        tree.beta = order.iter().map(|&k| beta[k]).collect();
        tree
    }

    /// The node over `order[range]`'s sources (moments; no children yet).
    fn node(&self, x: &[Vec3], beta: &[Vec3], idx: &[usize], start: usize) -> Node {
        let centre = idx.iter().map(|&k| x[k]).sum::<Vec3>() / idx.len() as Real;
        let (mut radius, mut total, mut twist, mut moment) =
            (0.0, Vec3::zeros(), Vec3::zeros(), Mat3::zeros());
        for &k in idx {
            let delta = x[k] - centre;
            radius = Real::max(radius, delta.norm());
            total += beta[k];
            twist += beta[k].cross(&delta);
            moment += beta[k] * delta.transpose();
        }
        let f = |v: Vec3| [v.x as f32, v.y as f32, v.z as f32];
        Node {
            centre,
            radius,
            moments: Moments {
                total: f(total),
                twist: f(twist),
                moment: std::array::from_fn(|e| moment[(e / 3, e % 3)] as f32),
            },
            sources: start..start + idx.len(),
            first_child: 0,
            children: 0,
        }
    }

    /// Splits node `n` (cube of centre `mid` and half side `half`) into its octants,
    /// reordering `order[n.sources]` so each child's sources are contiguous.
    #[allow(clippy::too_many_arguments)]
    fn split(
        &mut self,
        n: usize,
        x: &[Vec3],
        beta: &[Vec3],
        order: &mut [usize],
        mid: Vec3,
        half: Real,
        depth: usize,
    ) {
        let range = self.nodes[n].sources.clone();
        if range.len() <= LEAF || depth >= MAX_DEPTH {
            return;
        }
        let octant = |k: usize| {
            let p = x[k];
            usize::from(p.x > mid.x) | usize::from(p.y > mid.y) << 1 | usize::from(p.z > mid.z) << 2
        };
        order[range.clone()].sort_unstable_by_key(|&k| octant(k));
        let mut parts = Vec::with_capacity(8);
        let mut start = range.start;
        while start < range.end {
            let o = octant(order[start]);
            let end = start + order[start..range.end].partition_point(|&k| octant(k) == o);
            parts.push((o, start..end));
            start = end;
        }
        let first = self.nodes.len();
        for (_, r) in &parts {
            let node = self.node(x, beta, &order[r.clone()], r.start);
            self.nodes.push(node);
        }
        self.nodes[n].first_child = first;
        self.nodes[n].children = parts.len();
        let q = 0.5 * half;
        for (c, (o, _)) in parts.into_iter().enumerate() {
            let sign = |bit: usize| if o >> bit & 1 == 1 { q } else { -q };
            let child_mid = mid + Vec3::new(sign(0), sign(1), sign(2));
            self.split(first + c, x, beta, order, child_mid, q, depth + 1);
        }
    }

    /// The velocity the sources induce at every target, with opening parameter `theta`
    /// (0 sums every pair directly).
    pub fn evaluate(&self, targets: &[Vec3], theta: Real) -> Vec<Vec3> {
        if self.nodes.is_empty() || targets.is_empty() {
            return vec![Vec3::zeros(); targets.len()];
        }
        let clusters = Clusters::new(targets, self.core);
        let mut sorted = vec![Vec3::zeros(); targets.len()];
        self.descend(&clusters, 0, &mut sorted, &[0], theta, None);
        let mut out = vec![Vec3::zeros(); targets.len()];
        for (&k, u) in clusters.order.iter().zip(sorted) {
            out[k] = u;
        }
        out
    }

    /// Adds to `out` (the targets of cluster `c`) the field of the `candidates` nodes: nodes
    /// far from the whole cluster at its box's corners, added to the far field `inherited`
    /// from the enclosing cluster (trilinear, so restricting it to the sub-box by its corners
    /// is exact) and interpolated to the targets once, where the hierarchy ends; the other
    /// nodes are handed down to the sub-clusters, or summed directly at the finest level.
    fn descend(
        &self,
        clusters: &Clusters,
        c: usize,
        out: &mut [Vec3],
        candidates: &[usize],
        theta: Real,
        inherited: Option<&Field>,
    ) {
        let cluster = &clusters.nodes[c];
        let finest = cluster.children.is_empty();
        let (lo, hi) = (cluster.lo, cluster.hi);
        let origin = 0.5 * (lo + hi);
        let reach = 0.5 * (hi - lo).norm();
        let (mut far, mut rest) = (Vec::new(), Vec::new());
        let mut stack = candidates.to_vec();
        let theta2 = theta * theta;
        while let Some(n) = stack.pop() {
            let node = &self.nodes[n];
            let gap = node.radius + reach;
            if gap * gap < theta2 * (node.centre - origin).norm_squared() {
                far.push(n);
            } else if node.children > 0 && (finest || node.radius > reach) {
                stack.extend(node.first_child..node.first_child + node.children);
            } else {
                rest.push(n);
            }
        }
        let mut field = inherited.map(|f| f.restricted(lo, hi));
        if !far.is_empty() {
            let values = self.far_at_corners(&far, origin, 0.5 * (hi - lo));
            field = Some(match field {
                Some(f) => Field {
                    values: std::array::from_fn(|c| f.values[c] + values[c]),
                    ..f
                },
                None => Field { lo, hi, values },
            });
        }
        let targets = &clusters.x[cluster.targets.clone()];
        if finest || rest.is_empty() {
            if let Some(f) = &field {
                for (u, p) in out.iter_mut().zip(targets) {
                    *u += f.at(p);
                }
            }
        }
        if finest {
            let mut near = Lanes::default();
            for &n in &rest {
                for k in self.nodes[n].sources.clone() {
                    near.push(self.x[k] - origin, self.beta[k]);
                }
            }
            let d2 = (self.core * self.core) as f32;
            for (u, p) in out.iter_mut().zip(targets) {
                *u += near.sum_at((p - origin).cast::<f32>(), d2) / (4.0 * PI);
            }
        } else if !rest.is_empty() {
            // The sub-clusters cover the cluster's targets in order.
            let mut parts = Vec::with_capacity(cluster.children.len());
            let mut tail = out;
            for &child in &cluster.children {
                let (part, more) = tail.split_at_mut(clusters.nodes[child].targets.len());
                parts.push((child, part));
                tail = more;
            }
            parts.into_par_iter().for_each(|(child, part)| {
                self.descend(clusters, child, part, &rest, theta, field.as_ref())
            });
        }
    }

    /// The far field of the `far` nodes at the eight corners `origin +- half` of a box
    /// (corner c has bit a set for the upper side along axis a).
    ///
    /// These evaluations are most of the treecode's far-field cost, so the eight corners run
    /// as eight f32 lanes (on AVX2 where the CPU has it), positions relative to the box
    /// centre; relative accuracy about 1e-6, like the near field.
    fn far_at_corners(&self, far: &[usize], origin: Vec3, half: Vec3) -> [Vec3; 8] {
        #[cfg(target_arch = "x86_64")]
        if simd::available() {
            // SAFETY: the CPU has AVX2 and FMA, checked just above.
            return unsafe { simd::far_at_corners(self, far, origin, half) };
        }
        self.far_corner_lanes(far, origin, half)
    }

    /// The portable body of [`Self::far_at_corners`]: with y = x - c and
    /// s^2 = |y|^2 + d^2, u = (B x y - a) / s^3 + 3 (M y) x y / s^5 (module documentation).
    fn far_corner_lanes(&self, far: &[usize], origin: Vec3, half: Vec3) -> [Vec3; 8] {
        let side = |c: usize, axis: usize| {
            let h = half[axis] as f32;
            if c >> axis & 1 == 1 {
                h
            } else {
                -h
            }
        };
        let cx: [f32; 8] = std::array::from_fn(|c| side(c, 0));
        let cy: [f32; 8] = std::array::from_fn(|c| side(c, 1));
        let cz: [f32; 8] = std::array::from_fn(|c| side(c, 2));
        let d2 = (self.core * self.core) as f32;
        let (mut ux, mut uy, mut uz) = ([0f32; 8], [0f32; 8], [0f32; 8]);
        for &n in far {
            let node = &self.nodes[n];
            let c = (node.centre - origin).cast::<f32>();
            let Moments {
                total: b,
                twist: a,
                moment: m,
            } = node.moments;
            for l in 0..8 {
                let (yx, yy, yz) = (cx[l] - c.x, cy[l] - c.y, cz[l] - c.z);
                let s2 = yx * yx + yy * yy + yz * yz + d2;
                let inv3 = 1.0 / (s2 * s2.sqrt());
                let inv5 = 3.0 * inv3 / s2;
                let mx = m[0] * yx + m[1] * yy + m[2] * yz;
                let my = m[3] * yx + m[4] * yy + m[5] * yz;
                let mz = m[6] * yx + m[7] * yy + m[8] * yz;
                ux[l] += (b[1] * yz - b[2] * yy - a[0]) * inv3 + (my * yz - mz * yy) * inv5;
                uy[l] += (b[2] * yx - b[0] * yz - a[1]) * inv3 + (mz * yx - mx * yz) * inv5;
                uz[l] += (b[0] * yy - b[1] * yx - a[2]) * inv3 + (mx * yy - my * yx) * inv5;
            }
        }
        std::array::from_fn(|c| {
            Vec3::new(Real::from(ux[c]), Real::from(uy[c]), Real::from(uz[c])) / (4.0 * PI)
        })
    }
}

/// The two inner loops on AVX2 and FMA: eight f32 lanes, and 1 / s^3 from the reciprocal
/// square root estimate refined by one Newton step (relative error about 1e-7, like f32
/// rounding) instead of a square root and a division, which would take most of the time.
#[cfg(target_arch = "x86_64")]
mod simd {
    use super::{BiotSavartTree, Block, Moments, Real, Vec3, PI};
    use nalgebra::Vector3;
    use std::arch::x86_64::*;

    /// Whether the CPU runs [`sum_at`] and [`far_at_corners`].
    pub fn available() -> bool {
        is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma")
    }

    /// 1 / sqrt(r2), lane by lane: the hardware estimate (12 bits) and one Newton step.
    #[inline(always)]
    unsafe fn rsqrt(r2: __m256) -> __m256 {
        let y = _mm256_rsqrt_ps(r2);
        let half_r2 = _mm256_mul_ps(_mm256_set1_ps(0.5), r2);
        let correction = _mm256_fnmadd_ps(half_r2, _mm256_mul_ps(y, y), _mm256_set1_ps(1.5));
        _mm256_mul_ps(y, correction)
    }

    /// The eight lanes of `v` added up in f64.
    #[inline(always)]
    unsafe fn total(v: __m256) -> Real {
        let mut lanes = [0f32; 8];
        _mm256_storeu_ps(lanes.as_mut_ptr(), v);
        lanes.iter().map(|&x| Real::from(x)).sum()
    }

    /// `Lanes::sum_at`: sum_k b_k x (p - x_k) / (|p - x_k|^2 + d2)^(3/2).
    #[target_feature(enable = "avx2,fma")]
    pub unsafe fn sum_at(blocks: &[Block], p: Vector3<f32>, d2: f32) -> Vec3 {
        let (px, py, pz) = (
            _mm256_set1_ps(p.x),
            _mm256_set1_ps(p.y),
            _mm256_set1_ps(p.z),
        );
        let d2 = _mm256_set1_ps(d2);
        let (mut ux, mut uy, mut uz) = (
            _mm256_setzero_ps(),
            _mm256_setzero_ps(),
            _mm256_setzero_ps(),
        );
        for b in blocks {
            let dx = _mm256_sub_ps(px, _mm256_loadu_ps(b.x.as_ptr()));
            let dy = _mm256_sub_ps(py, _mm256_loadu_ps(b.y.as_ptr()));
            let dz = _mm256_sub_ps(pz, _mm256_loadu_ps(b.z.as_ptr()));
            let r2 = _mm256_fmadd_ps(dx, dx, _mm256_fmadd_ps(dy, dy, _mm256_fmadd_ps(dz, dz, d2)));
            let y = rsqrt(r2);
            let inv = _mm256_mul_ps(y, _mm256_mul_ps(y, y));
            let bx = _mm256_loadu_ps(b.bx.as_ptr());
            let by = _mm256_loadu_ps(b.by.as_ptr());
            let bz = _mm256_loadu_ps(b.bz.as_ptr());
            ux = _mm256_fmadd_ps(_mm256_fmsub_ps(by, dz, _mm256_mul_ps(bz, dy)), inv, ux);
            uy = _mm256_fmadd_ps(_mm256_fmsub_ps(bz, dx, _mm256_mul_ps(bx, dz)), inv, uy);
            uz = _mm256_fmadd_ps(_mm256_fmsub_ps(bx, dy, _mm256_mul_ps(by, dx)), inv, uz);
        }
        Vec3::new(total(ux), total(uy), total(uz))
    }

    /// `BiotSavartTree::far_at_corners`, one corner per lane.
    #[target_feature(enable = "avx2,fma")]
    pub unsafe fn far_at_corners(
        tree: &BiotSavartTree,
        far: &[usize],
        origin: Vec3,
        half: Vec3,
    ) -> [Vec3; 8] {
        let side = |axis: usize| {
            let h = half[axis] as f32;
            let lanes: [f32; 8] = std::array::from_fn(|c| if c >> axis & 1 == 1 { h } else { -h });
            _mm256_loadu_ps(lanes.as_ptr())
        };
        let (cx, cy, cz) = (side(0), side(1), side(2));
        let d2 = _mm256_set1_ps((tree.core * tree.core) as f32);
        let (mut ux, mut uy, mut uz) = (
            _mm256_setzero_ps(),
            _mm256_setzero_ps(),
            _mm256_setzero_ps(),
        );
        for &n in far {
            let node = &tree.nodes[n];
            let c = (node.centre - origin).cast::<f32>();
            let Moments {
                total: b,
                twist: a,
                moment: m,
            } = node.moments;
            let s = _mm256_set1_ps;
            let yx = _mm256_sub_ps(cx, s(c.x));
            let yy = _mm256_sub_ps(cy, s(c.y));
            let yz = _mm256_sub_ps(cz, s(c.z));
            let s2 = _mm256_fmadd_ps(yx, yx, _mm256_fmadd_ps(yy, yy, _mm256_fmadd_ps(yz, yz, d2)));
            let r = rsqrt(s2);
            let r2 = _mm256_mul_ps(r, r);
            let inv3 = _mm256_mul_ps(r, r2);
            let inv5 = _mm256_mul_ps(_mm256_mul_ps(s(3.0), inv3), r2);
            let row = |i: usize| {
                _mm256_fmadd_ps(
                    s(m[i]),
                    yx,
                    _mm256_fmadd_ps(s(m[i + 1]), yy, _mm256_mul_ps(s(m[i + 2]), yz)),
                )
            };
            let (mx, my, mz) = (row(0), row(3), row(6));
            // (B x y - a) / s^3 + 3 (M y) x y / s^5, one component.
            let comp =
                |b1: f32, y2: __m256, b2: f32, y1: __m256, a0: f32, m1: __m256, m2: __m256| {
                    let mono =
                        _mm256_sub_ps(_mm256_fmsub_ps(s(b1), y2, _mm256_mul_ps(s(b2), y1)), s(a0));
                    let dip = _mm256_fmsub_ps(m1, y2, _mm256_mul_ps(m2, y1));
                    _mm256_fmadd_ps(mono, inv3, _mm256_mul_ps(dip, inv5))
                };
            ux = _mm256_add_ps(ux, comp(b[1], yz, b[2], yy, a[0], my, mz));
            uy = _mm256_add_ps(uy, comp(b[2], yx, b[0], yz, a[1], mz, mx));
            uz = _mm256_add_ps(uz, comp(b[0], yy, b[1], yx, a[2], mx, my));
        }
        let lanes = |v: __m256| {
            let mut l = [0f32; 8];
            _mm256_storeu_ps(l.as_mut_ptr(), v);
            l
        };
        let (ux, uy, uz) = (lanes(ux), lanes(uy), lanes(uz));
        std::array::from_fn(|c| {
            Vec3::new(Real::from(ux[c]), Real::from(uy[c]), Real::from(uz[c])) / (4.0 * PI)
        })
    }
}

/// The far field over a box, trilinear between its values at the eight corners (corner c has
/// bit a set for the upper side along axis a).
struct Field {
    lo: Vec3,
    hi: Vec3,
    values: [Vec3; 8],
}

impl Field {
    /// The interpolated field at `p` (inside the box).
    fn at(&self, p: &Vec3) -> Vec3 {
        let extent = self.hi - self.lo;
        let fraction = |a: usize| {
            if extent[a] > 0.0 {
                (p[a] - self.lo[a]) / extent[a]
            } else {
                0.0
            }
        };
        let t = Vec3::new(fraction(0), fraction(1), fraction(2));
        let mut u = Vec3::zeros();
        for (c, value) in self.values.iter().enumerate() {
            let w = |a: usize| if c >> a & 1 == 1 { t[a] } else { 1.0 - t[a] };
            u += (w(0) * w(1) * w(2)) * value;
        }
        u
    }

    /// The same field on the sub-box `(lo, hi)`, by its values there.
    fn restricted(&self, lo: Vec3, hi: Vec3) -> Field {
        let values = std::array::from_fn(|c| {
            let pick = |a: usize| if c >> a & 1 == 1 { hi[a] } else { lo[a] };
            self.at(&Vec3::new(pick(0), pick(1), pick(2)))
        });
        Field { lo, hi, values }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Random sources in a cube of side 2 around the origin, with strengths of both signs.
    fn sources(count: usize) -> (Vec<Vec3>, Vec<Vec3>) {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut point = || {
            Vec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            )
        };
        let x = (0..count).map(|_| point()).collect();
        let b = (0..count).map(|_| point()).collect();
        (x, b)
    }

    /// The dispatched near-field sum (SIMD where the CPU has it) equals the portable loop to
    /// f32 rounding: the Newton-refined reciprocal square root costs no accuracy.
    #[test]
    fn near_field_lanes_agree() {
        let (x, b) = sources(37);
        let mut lanes = Lanes::default();
        for (x, b) in x.iter().zip(&b) {
            lanes.push(*x, *b);
        }
        for p in [Vec3::new(0.1, -0.3, 0.2), Vec3::new(2.0, 1.0, -1.5)] {
            let p = p.cast::<f32>();
            let (fast, portable) = (lanes.sum_at(p, 1e-3), lanes.sum_lanes(p, 1e-3));
            assert!(
                (fast - portable).norm() < 1e-5 * portable.norm(),
                "{fast} vs {portable}"
            );
        }
    }

    /// The same for the far field at a box's eight corners, from every node of a tree.
    #[test]
    fn far_field_lanes_agree() {
        let (x, b) = sources(300);
        let tree = BiotSavartTree::new(&x, &b, 0.01);
        let nodes: Vec<usize> = (1..tree.nodes.len()).collect();
        let (origin, half) = (Vec3::new(4.0, 0.5, -3.0), Vec3::new(0.2, 0.1, 0.3));
        let fast = tree.far_at_corners(&nodes, origin, half);
        let portable = tree.far_corner_lanes(&nodes, origin, half);
        for (f, p) in fast.iter().zip(&portable) {
            assert!((f - p).norm() < 1e-5 * p.norm(), "{f} vs {p}");
        }
    }
}
