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
//! - both inner loops (near sources per target, far nodes per eight corners) run in vectors
//!   of sixteen f32 at the CPU's widest level ([`crate::simd`]); at 91k fluid particles and
//!   911 vortex particles the near field is about half the work.
//!
//! The error is O(theta^2) relative to each far node's contribution and vanishes as
//! theta -> 0 (at theta = 0 every pair is direct); `tests/refine_operators.rs` checks both.

use super::clusters::{bounds, Clusters};
use crate::simd::{self, Level};
use crate::Mat3;
use crate::{Real, Vec3};
use pulp::{Simd, WithSimd};
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

/// f32 lanes of a vector: sources per block of the direct sum, two nodes' eight corners in the
/// far field.
const LANES: usize = 2 * simd::LANES;

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
}

/// u(p) = sum_k b_k x (p - x_k) / (|p - x_k|^2 + d2)^(3/2) / (4 pi) over `sources`, at each of
/// `targets` (`origin` the sources' origin), added to `out`.
///
/// This loop is the sums' whole near-field cost, so it runs in f32 (twice the SIMD lanes of
/// f64) with positions relative to a nearby origin; the lanes are added up in f64. The
/// relative accuracy, about 1e-6, is far below the Monte Carlo error.
struct NearSum<'a> {
    sources: &'a Lanes,
    origin: Vec3,
    targets: &'a [Vec3],
    d2: f32,
    out: &'a mut [Vec3],
}

impl WithSimd for NearSum<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        let splat = |v: f32| simd.splat_f32s(v);
        let d2 = splat(self.d2);
        for (u, p) in self.out.iter_mut().zip(self.targets) {
            let p = (p - self.origin).cast::<f32>();
            let (px, py, pz) = (splat(p.x), splat(p.y), splat(p.z));
            let (mut ux, mut uy, mut uz) = (splat(0.0), splat(0.0), splat(0.0));
            for b in &self.sources.blocks {
                let load = |a: &[f32; LANES]| -> S::f32s { pulp::cast(*a) };
                let dx = simd.sub_f32s(px, load(&b.x));
                let dy = simd.sub_f32s(py, load(&b.y));
                let dz = simd.sub_f32s(pz, load(&b.z));
                let r2 = simd.add_f32s(
                    simd.add_f32s(
                        simd.add_f32s(simd.mul_f32s(dx, dx), simd.mul_f32s(dy, dy)),
                        simd.mul_f32s(dz, dz),
                    ),
                    d2,
                );
                let inv = simd.div_f32s(splat(1.0), simd.mul_f32s(r2, simd.sqrt_f32s(r2)));
                let (bx, by, bz) = (load(&b.bx), load(&b.by), load(&b.bz));
                let cross =
                    |p1, q2, p2, q1| simd.sub_f32s(simd.mul_f32s(p1, q2), simd.mul_f32s(p2, q1));
                ux = simd.add_f32s(ux, simd.mul_f32s(cross(by, dz, bz, dy), inv));
                uy = simd.add_f32s(uy, simd.mul_f32s(cross(bz, dx, bx, dz), inv));
                uz = simd.add_f32s(uz, simd.mul_f32s(cross(bx, dy, by, dx), inv));
            }
            let sum = |v: S::f32s| {
                let lanes: [f32; LANES] = pulp::cast(v);
                lanes.iter().map(|&x| Real::from(x)).sum::<Real>()
            };
            *u += Vec3::new(sum(ux), sum(uy), sum(uz)) / (4.0 * PI);
        }
    }
}

/// The direct mollified Biot–Savart sum at every target, in parallel over targets.
pub fn biot_savart(targets: &[Vec3], sources: &[Vec3], beta: &[Vec3], core: Real) -> Vec<Vec3> {
    let origin = sources.first().copied().unwrap_or_else(Vec3::zeros);
    let mut lanes = Lanes::default();
    for (x, b) in sources.iter().zip(beta) {
        lanes.push(x - origin, *b);
    }
    let level = Level::active();
    let d2 = (core * core) as f32;
    let mut out = vec![Vec3::zeros(); targets.len()];
    out.par_chunks_mut(256)
        .zip(targets.par_chunks(256))
        .for_each(|(out, targets)| {
            level.run(NearSum {
                sources: &lanes,
                origin,
                targets,
                d2,
                out,
            })
        });
    out
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
            Level::active().run(NearSum {
                sources: &near,
                origin,
                targets,
                d2: (self.core * self.core) as f32,
                out,
            });
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
    fn far_at_corners(&self, far: &[usize], origin: Vec3, half: Vec3) -> [Vec3; 8] {
        Level::active().run(FarAtCorners {
            tree: self,
            far,
            origin,
            half,
        })
    }
}

/// [`BiotSavartTree::far_at_corners`]: with y = x - c and s^2 = |y|^2 + d^2,
/// u = (B x y - a) / s^3 + 3 (M y) x y / s^5 (module documentation).
///
/// These evaluations are most of the treecode's far-field cost, so they run in f32, two nodes
/// a vector: the eight corners of one node in the lower lanes, of the next in the upper ones
/// (an odd last node pairs with a node of zero moments), positions relative to the box centre;
/// relative accuracy about 1e-6, like the near field.
struct FarAtCorners<'a> {
    tree: &'a BiotSavartTree,
    far: &'a [usize],
    origin: Vec3,
    half: Vec3,
}

impl WithSimd for FarAtCorners<'_> {
    type Output = [Vec3; 8];

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) -> [Vec3; 8] {
        const CORNERS: usize = 8;
        let side = |axis: usize| -> S::f32s {
            let h = self.half[axis] as f32;
            let lanes: [f32; LANES] = std::array::from_fn(|l| {
                if (l % CORNERS) >> axis & 1 == 1 {
                    h
                } else {
                    -h
                }
            });
            pulp::cast(lanes)
        };
        let (cx, cy, cz) = (side(0), side(1), side(2));
        let d2 = simd.splat_f32s((self.tree.core * self.tree.core) as f32);
        let (mut ux, mut uy, mut uz) = (
            simd.splat_f32s(0.0),
            simd.splat_f32s(0.0),
            simd.splat_f32s(0.0),
        );
        let none = Moments {
            total: [0.0; 3],
            twist: [0.0; 3],
            moment: [0.0; 9],
        };
        for pair in self.far.chunks(2) {
            let node = |k: usize| {
                let node = &self.tree.nodes[pair[k.min(pair.len() - 1)]];
                let moments = if k < pair.len() { node.moments } else { none };
                ((node.centre - self.origin).cast::<f32>(), moments)
            };
            let ((c0, n0), (c1, n1)) = (node(0), node(1));
            // One value per node: the first node's in the lower lanes, the second's above.
            let s = |a: f32, b: f32| -> S::f32s {
                let lanes: [f32; LANES] = std::array::from_fn(|l| if l < CORNERS { a } else { b });
                pulp::cast(lanes)
            };
            let yx = simd.sub_f32s(cx, s(c0.x, c1.x));
            let yy = simd.sub_f32s(cy, s(c0.y, c1.y));
            let yz = simd.sub_f32s(cz, s(c0.z, c1.z));
            let s2 = simd.add_f32s(
                simd.add_f32s(
                    simd.add_f32s(simd.mul_f32s(yx, yx), simd.mul_f32s(yy, yy)),
                    simd.mul_f32s(yz, yz),
                ),
                d2,
            );
            let inv3 = simd.div_f32s(simd.splat_f32s(1.0), simd.mul_f32s(s2, simd.sqrt_f32s(s2)));
            let inv5 = simd.div_f32s(simd.mul_f32s(simd.splat_f32s(3.0), inv3), s2);
            let m = |e: usize| s(n0.moment[e], n1.moment[e]);
            let row = |e: usize| {
                simd.add_f32s(
                    simd.add_f32s(simd.mul_f32s(m(e), yx), simd.mul_f32s(m(e + 1), yy)),
                    simd.mul_f32s(m(e + 2), yz),
                )
            };
            let (mx, my, mz) = (row(0), row(3), row(6));
            let b = |e: usize| s(n0.total[e], n1.total[e]);
            let a = |e: usize| s(n0.twist[e], n1.twist[e]);
            let cross =
                |p1, q2, p2, q1| simd.sub_f32s(simd.mul_f32s(p1, q2), simd.mul_f32s(p2, q1));
            // (B x y - a) / s^3 + 3 (M y) x y / s^5, one component.
            let comp = |mono, twist, dip| {
                simd.add_f32s(
                    simd.mul_f32s(simd.sub_f32s(mono, twist), inv3),
                    simd.mul_f32s(dip, inv5),
                )
            };
            ux = simd.add_f32s(
                ux,
                comp(cross(b(1), yz, b(2), yy), a(0), cross(my, yz, mz, yy)),
            );
            uy = simd.add_f32s(
                uy,
                comp(cross(b(2), yx, b(0), yz), a(1), cross(mz, yx, mx, yz)),
            );
            uz = simd.add_f32s(
                uz,
                comp(cross(b(0), yy, b(1), yx), a(2), cross(mx, yy, my, yx)),
            );
        }
        let lanes = |v: S::f32s| -> [f32; LANES] { pulp::cast(v) };
        let (ux, uy, uz) = (lanes(ux), lanes(uy), lanes(uz));
        let corner = |u: &[f32; LANES], c: usize| Real::from(u[c]) + Real::from(u[c + CORNERS]);
        std::array::from_fn(|c| {
            Vec3::new(corner(&ux, c), corner(&uy, c), corner(&uz, c)) / (4.0 * PI)
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

    /// Every level the CPU runs gives the scalar level's near-field sums bit for bit, and
    /// they equal the f64 sum to f32 rounding.
    #[test]
    fn near_field_levels_agree() {
        let (x, b) = sources(37);
        let mut lanes = Lanes::default();
        for (x, b) in x.iter().zip(&b) {
            lanes.push(*x, *b);
        }
        let targets = [Vec3::new(0.1, -0.3, 0.2), Vec3::new(2.0, 1.0, -1.5)];
        let d2 = 1e-3;
        let run = |level: Level| {
            let mut out = vec![Vec3::zeros(); targets.len()];
            level.run(NearSum {
                sources: &lanes,
                origin: Vec3::zeros(),
                targets: &targets,
                d2,
                out: &mut out,
            });
            out
        };
        let scalar = run(Level::Scalar);
        for (p, u) in targets.iter().zip(&scalar) {
            let exact: Vec3 = x
                .iter()
                .zip(&b)
                .map(|(x, b)| {
                    let y = p - x;
                    b.cross(&y) / (y.norm_squared() + Real::from(d2)).powf(1.5)
                })
                .sum::<Vec3>()
                / (4.0 * PI);
            assert!((u - exact).norm() < 1e-5 * exact.norm(), "{u} vs {exact}");
        }
        for level in Level::ALL.into_iter().filter(|l| l.supported()) {
            assert_eq!(run(level), scalar, "{level:?}");
        }
    }

    /// The same for the far field at a box's eight corners, from every node of a tree (an
    /// odd number of nodes, so one pairs with nothing), against the expansion in f64.
    #[test]
    fn far_field_levels_agree() {
        let (x, b) = sources(300);
        let tree = BiotSavartTree::new(&x, &b, 0.01);
        let mut nodes: Vec<usize> = (1..tree.nodes.len()).collect();
        if nodes.len().is_multiple_of(2) {
            nodes.pop();
        }
        let (origin, half) = (Vec3::new(4.0, 0.5, -3.0), Vec3::new(0.2, 0.1, 0.3));
        let run = |level: Level| {
            level.run(FarAtCorners {
                tree: &tree,
                far: &nodes,
                origin,
                half,
            })
        };
        let scalar = run(Level::Scalar);
        for (c, u) in scalar.iter().enumerate() {
            let pick = |a: usize| if c >> a & 1 == 1 { half[a] } else { -half[a] };
            let corner = origin + Vec3::new(pick(0), pick(1), pick(2));
            let exact: Vec3 = nodes
                .iter()
                .map(|&n| {
                    let node = &tree.nodes[n];
                    let m = &node.moments;
                    let f = |v: &[f32]| Vec3::new(v[0].into(), v[1].into(), v[2].into());
                    let (total, twist) = (f(&m.total), f(&m.twist));
                    let moment = Mat3::from_fn(|i, j| m.moment[3 * i + j].into());
                    let y = corner - node.centre;
                    let s2 = y.norm_squared() + tree.core * tree.core;
                    (total.cross(&y) - twist) / s2.powf(1.5)
                        + 3.0 * (moment * y).cross(&y) / s2.powf(2.5)
                })
                .sum::<Vec3>()
                / (4.0 * PI);
            assert!((u - exact).norm() < 1e-5 * exact.norm(), "{u} vs {exact}");
        }
        for level in Level::ALL.into_iter().filter(|l| l.supported()) {
            assert_eq!(run(level), scalar, "{level:?}");
        }
    }
}
