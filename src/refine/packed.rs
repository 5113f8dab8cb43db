//! The difference operators of `crate::sph::operators` in single precision on packed fields: the
//! neighbour passes of the Rankine, VRSPH and MCVSPH refinements.
//!
//! **Why.** These refinements are a few passes over every pair, and their cost is measured
//! against the DFSPH step. In f64 on `Vec3`s a curl is ten scalar loads a pair and the cross
//! product's scalar arithmetic. In a [`Field`] each particle's vector and volume V_j fill
//! four f32 lanes ([`F4`]), so a neighbour is one 16-byte load and the arithmetic runs on
//! four lanes, faster for every operator. Four neighbours side by side (transposed into one
//! row per component) are slower for the fused curl and Laplacian: the rows and their
//! constants need more than SSE's 16 registers. The stream function, whose only per-pair work
//! is a weight of the distance, runs that way ([`Packed::quads`]). The timings behind both
//! choices are in the book's benchmarks chapter ("Measurements behind design choices").
//!
//! **Precision.** The fields, positions (relative to the first particle) and sums are f32,
//! like the cached kernel gradients the sums already read (relative rounding 6e-8): a result
//! is within a few 1e-7 of its magnitude scale of the f64 operators, far below the
//! refinements' own discretisation error. The f64 [`Operators`] remain the reference for
//! metrics, the baselines and the tests, which check that both agree.
//!
//! **Walls.** Boundary samples enter as in [`Operators`], summed in f64 (they are few).

use super::lanes::{CrossSum, F4};
use crate::sph::operators::{Operators, WallField};
use crate::state::{Restorer, Saver, StateError};
use crate::Mat3;
use crate::{Real, Vec3};
use rayon::prelude::*;

/// A vector field packed for the operators: per fluid particle its vector in f32 and its
/// volume V_j in the fourth lane (the weight of every sum), of the step it was packed in.
#[derive(Clone, Default)]
pub struct Field(Vec<F4>);

impl Field {
    /// Number of particles.
    pub fn len(&self) -> usize {
        self.0.len()
    }

    /// Whether the field is empty.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// The vector of particle i, widened.
    #[inline(always)]
    pub fn vec(&self, i: usize) -> Vec3 {
        self.0[i].vec()
    }

    /// The packed lanes, one per particle.
    pub fn lanes(&self) -> &[F4] {
        &self.0
    }

    /// Reorders the field as the fluid was reordered (`perm[k]` is the old index at k).
    pub fn permute(&mut self, perm: &[u32]) {
        crate::spatial::permute(&mut self.0, perm);
    }

    /// Saves the lanes exactly (f32 widens to f64 without rounding): the vectors as `name`,
    /// the volumes they were packed with as `name_volume`.
    pub fn save(&self, into: &mut Saver, name: &str) {
        let vectors: Vec<Vec3> = self.0.iter().map(|f| f.vec()).collect();
        let volumes: Vec<Real> = self.0.iter().map(|f| f.to_array()[3].into()).collect();
        into.vec3s(name, &vectors);
        into.reals(&format!("{name}_volume"), &volumes);
    }

    /// The field [`Self::save`] saved as `name`.
    pub fn restore(from: &Restorer, name: &str) -> Result<Self, StateError> {
        let vectors = from.vec3s(name)?;
        let volumes = from.reals_n(&format!("{name}_volume"), vectors.len())?;
        let lanes = vectors.iter().zip(&volumes);
        Ok(Self(lanes.map(|(v, &w)| F4::from_vec(v, w)).collect()))
    }

    /// Follows the fluid's open boundaries (see [`crate::spatial::resize`]): new particles
    /// hold zero.
    pub fn resize(&mut self, keep: &[bool], added: usize) {
        let zero = F4::from_vec(&Vec3::zeros(), 0.0);
        crate::spatial::resize(&mut self.0, keep, added, zero);
    }
}

/// Sets `out` to `f(i)` for i < n, in parallel, keeping its allocation. The refinements keep
/// their per-step buffers across steps: allocated afresh each step, a VRSPH step at 389k
/// particles touched 44 MB of new pages (11 000 page faults a step; none with the buffers).
pub fn fill<T: Copy + Default + Send>(out: &mut Vec<T>, n: usize, f: impl Fn(usize) -> T + Sync) {
    out.resize(n, T::default());
    out.par_iter_mut().enumerate().for_each(|(i, o)| *o = f(i));
}

/// What a packed field holds, for its noise floor (see [`Packed`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quantity {
    /// m/s.
    Velocity,
    /// 1/s: vorticity and its losses.
    Vorticity,
    /// m^2/s.
    StreamFunction,
}

/// The noise floor of a packed field as a fraction of the step's velocity scale (see
/// [`Packed`]).
const NOISE: Real = 1e-12;

/// `a` with the components below `floor` in magnitude set to zero.
#[inline(always)]
fn below(a: Vec3, floor: Real) -> Vec3 {
    a.map(|c| if c.abs() < floor { 0.0 } else { c })
}

/// The operators over one step's neighbourhood, with its positions and volumes packed.
///
/// **Noise floor.** Components of a packed field below 1e-12 of the step's largest fluid
/// speed U (times 1/h for a vorticity, h for a stream function, h the support) are packed as
/// zero. In a fluid at rest the fields are rounding noise, and their products with the
/// near-zero gradient components of lattice-aligned pairs (`crate::sph::pair_cache`) fall below
/// f32's normal range; x86 computes subnormal results in microcode. At the second step of the
/// dam break VRSPH's passes took 104–118 ms without the floor and 70–80 ms with it (389k
/// particles). The floor is four orders above f64 rounding and five below f32's resolution
/// of U. (The gradients' near-zero components stay: they break a lattice's symmetry, and
/// DFSPH's hydrostatic tank settles 3 % off rho g without them.)
pub struct Packed<'a> {
    pub ops: Operators<'a>,
    /// x_j - x_0 in the first three lanes and V_j in the fourth, per fluid particle.
    xv: &'a [F4],
    /// The step's largest fluid speed U, m/s.
    speed: Real,
    /// The step's kernel gradients, three f32 per pair in the neighbour lists' layout.
    grads: &'a [f32],
}

impl<'a> Packed<'a> {
    /// Packs the positions and volumes of `ops` into `positions` (a buffer kept across steps),
    /// with the noise floors of the fluid velocity `v`.
    pub fn new(ops: Operators<'a>, positions: &'a mut Vec<F4>, v: &[Vec3]) -> Self {
        let x = ops.nb.x;
        let origin = x.first().copied().unwrap_or_else(Vec3::zeros);
        fill(positions, x.len(), |i| {
            F4::from_vec(&(x[i] - origin), ops.volume[i])
        });
        Self {
            ops,
            xv: positions,
            speed: crate::metrics::max_speed(v),
            grads: ops.nb.pairs.fluid.as_flattened(),
        }
    }

    /// `a` with the components below the noise floor of `quantity` set to zero.
    #[inline(always)]
    pub fn denoise(&self, quantity: Quantity, a: Vec3) -> Vec3 {
        below(a, self.floor(quantity))
    }

    /// The noise floor of `quantity` this step.
    fn floor(&self, quantity: Quantity) -> Real {
        let h = self.ops.nb.kernel.support();
        let length = match quantity {
            Quantity::Velocity => 1.0,
            Quantity::Vorticity => 1.0 / h,
            Quantity::StreamFunction => h,
        };
        NOISE * self.speed * length
    }

    /// x_j - x_0 and V_j per fluid particle.
    pub fn positions(&self) -> &[F4] {
        self.xv
    }

    /// The velocity field `v` packed with this step's volumes into `out`.
    pub fn pack(&self, v: &[Vec3], out: &mut Field) {
        self.field(out, Quantity::Velocity, None, |i| v[i])
    }

    /// The field `f(i)` of `quantity` at every particle (zero where `only` is given and
    /// false), packed with this step's volumes into `out`.
    pub fn field(
        &self,
        out: &mut Field,
        quantity: Quantity,
        only: Option<&[bool]>,
        f: impl Fn(usize) -> Vec3 + Sync,
    ) {
        // A vector of () holds no memory.
        self.field_with(out, &mut Vec::new(), quantity, only, |i| (f(i), ()));
    }

    /// [`Self::field`] for `f(i) = (a_i, t_i)`, with the t_i into `rest` (the default where
    /// `only` is false).
    pub fn field_with<T: Default + Send>(
        &self,
        out: &mut Field,
        rest: &mut Vec<T>,
        quantity: Quantity,
        only: Option<&[bool]>,
        f: impl Fn(usize) -> (Vec3, T) + Sync,
    ) {
        let volume = self.ops.volume;
        let floor = self.floor(quantity);
        out.0.resize(volume.len(), F4::ZERO);
        rest.resize_with(volume.len(), T::default);
        let pairs = out.0.par_iter_mut().zip(rest.par_iter_mut());
        pairs.enumerate().for_each(|(i, (o, t))| {
            let (a, rest) = if only.is_none_or(|only| only[i]) {
                f(i)
            } else {
                (Vec3::zeros(), T::default())
            };
            (*o, *t) = (F4::from_vec(&below(a, floor), volume[i]), rest);
        });
    }

    /// Sets `values[i]` to `f(i, values[i])` at every particle and packs the new field of
    /// `quantity` into `out`, in the same pass (VRSPH's refined velocity, which its gradient
    /// reads next).
    pub fn update(
        &self,
        values: &mut [Vec3],
        out: &mut Field,
        quantity: Quantity,
        f: impl Fn(usize, Vec3) -> Vec3 + Sync,
    ) {
        let volume = self.ops.volume;
        let floor = self.floor(quantity);
        out.0.resize(values.len(), F4::ZERO);
        let pairs = out.0.par_iter_mut().zip(values.par_iter_mut());
        pairs.enumerate().for_each(|(i, (o, a))| {
            *a = f(i, *a);
            *o = F4::from_vec(&below(*a, floor), volume[i]);
        });
    }

    /// Calls `f(j, x_i - x_j)` for every fluid neighbour j of i.
    #[inline(always)]
    pub fn pairs(&self, i: usize, mut f: impl FnMut(usize, F4)) {
        let xi = self.xv[i];
        for &j in self.ops.nb.fluid.of(i) {
            f(j as usize, xi - self.xv[j as usize])
        }
    }

    /// Calls `f(j, n, [x, y, z])` for the fluid neighbours of i in groups of four, side by
    /// side: `j` the group's members (padded with i after the `n` real ones in the last
    /// group), `x, y, z` the rows of x_i - x_j ([`F4::transpose3`]). A pass whose per-pair work
    /// is a scalar function of the distance (VRSPH's stream function) evaluates it once per
    /// group: 2.2–2.4 against 3.0–3.4 ms for Eq. 15 one pair at a time (91k particles).
    #[inline(always)]
    pub fn quads(&self, i: usize, mut f: impl FnMut([usize; 4], usize, [F4; 3])) {
        let xi = self.xv[i];
        let xi = [xi.lane::<0>(), xi.lane::<1>(), xi.lane::<2>()];
        let rows = |j: [usize; 4]| {
            let [x, y, z] = F4::transpose3(j.map(|j| self.xv[j]));
            [xi[0] - x, xi[1] - y, xi[2] - z]
        };
        let mut groups = self.ops.nb.fluid.of(i).chunks_exact(4);
        for js in groups.by_ref() {
            let j = [js[0], js[1], js[2], js[3]].map(|j| j as usize);
            f(j, 4, rows(j));
        }
        let rest = groups.remainder();
        if !rest.is_empty() {
            let j = std::array::from_fn(|l| rest.get(l).map_or(i, |&j| j as usize));
            f(j, rest.len(), rows(j));
        }
    }

    /// Calls `f(j, grad W_ij)` for every fluid neighbour j of i.
    #[inline(always)]
    fn pairs_grad(&self, i: usize, mut f: impl FnMut(usize, F4)) {
        let lists = self.ops.nb.fluid;
        let range = lists.offsets[i] as usize..lists.offsets[i + 1] as usize;
        for (k, &j) in range.clone().zip(&lists.indices[range]) {
            f(j as usize, F4::load3(self.grads, 3 * k))
        }
    }

    /// Calls `f(V_b, a_b, grad W_ib)` for the boundary samples of i when walls take part.
    #[inline(always)]
    fn walls(&self, i: usize, wall: WallField, mut f: impl FnMut(Real, Vec3, Vec3)) {
        if self.ops.walls {
            let b = self.ops.nb.boundary;
            self.ops.nb.boundary_pairs_grad(i, |k, _, g| {
                let ak = match wall {
                    WallField::Velocity => b.v[k],
                    WallField::Zero => Vec3::zeros(),
                };
                f(b.volume[k], ak, g)
            });
        }
    }

    /// The curl (Liu Eq. 6) of the field `a` at particle i.
    #[inline(always)]
    pub fn curl_at(&self, i: usize, a: &Field, wall: WallField) -> Vec3 {
        let a = &a.0;
        let ai = a[i];
        let mut c = CrossSum::default();
        self.pairs_grad(i, |j, g| c.add((ai - a[j]) * a[j].lane::<3>(), g));
        let mut c = c.total();
        let ai = ai.vec();
        self.walls(i, wall, |vb, ab, g| c += vb * (ai - ab).cross(&g));
        c
    }

    /// The gradient tensor (Ye Eq. 7) of the field `a` at particle i.
    #[inline(always)]
    pub fn gradient_at(&self, i: usize, a: &Field, wall: WallField) -> Mat3 {
        let a = &a.0;
        let ai = a[i];
        let mut cols = [F4::ZERO; 3];
        self.pairs_grad(i, |j, g| {
            let d = (a[j] - ai) * a[j].lane::<3>();
            cols[0] += d * g.lane::<0>();
            cols[1] += d * g.lane::<1>();
            cols[2] += d * g.lane::<2>();
        });
        let mut grad = Mat3::from_columns(&cols.map(F4::vec));
        let ai = ai.vec();
        self.walls(i, wall, |vb, ab, g| {
            grad += (vb * (ab - ai)) * g.transpose()
        });
        grad
    }

    /// The curl of `v` (walls at their velocity) and the Laplacian (Ye Eq. 8, d = 3) of the
    /// vorticity-like field `a` (walls hold zero) at particle i, in one pass over its
    /// neighbours: VRSPH and MCVSPH read both at the same point of the step. The volumes come
    /// from `v`, so `a` may have been packed in an earlier step.
    #[inline(always)]
    pub fn curl_laplacian_at(&self, i: usize, v: &Field, a: &Field) -> (Vec3, Vec3) {
        let (v, a) = (&v.0, &a.0);
        let h = self.ops.nb.kernel.support();
        let eps = (0.01 * h * h) as f32;
        let (vi, ai, xi) = (v[i], a[i], self.xv[i]);
        let (mut c, mut l) = (CrossSum::default(), F4::ZERO);
        self.pairs_grad(i, |j, g| {
            let vj = v[j].lane::<3>();
            c.add((vi - v[j]) * vj, g);
            let xij = xi - self.xv[j];
            let q = F4::splat((ai - a[j]).dot3(xij) / (xij.dot3(xij) + eps));
            l += q * vj * g;
        });
        let (mut c, mut l) = (c.total(), l.vec());
        if self.ops.walls {
            let (vi, ai, eps) = (vi.vec(), ai.vec(), Real::from(eps));
            let b = self.ops.nb.boundary;
            self.ops.nb.boundary_pairs_grad(i, |k, xik, g| {
                c += b.volume[k] * (vi - b.v[k]).cross(&g);
                l += (b.volume[k] * ai.dot(&xik) / (xik.norm_squared() + eps)) * g;
            });
        }
        (c, 10.0 * l)
    }

    /// The curl of `v` and `nu` times the Laplacian of `a` at particle i:
    /// [`Self::curl_laplacian_at`] where `nu` > 0, the curl alone (and zero) otherwise. The
    /// vorticity equation's viscous term of VRSPH and MCVSPH.
    #[inline(always)]
    pub fn curl_diffusion_at(&self, i: usize, v: &Field, a: &Field, nu: Real) -> (Vec3, Vec3) {
        if nu > 0.0 {
            let (curl, laplacian) = self.curl_laplacian_at(i, v, a);
            (curl, nu * laplacian)
        } else {
            (self.curl_at(i, v, WallField::Velocity), Vec3::zeros())
        }
    }
}
