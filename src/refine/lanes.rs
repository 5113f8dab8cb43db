//! Four f32 lanes: the unit of the refinements' packed neighbour passes (see `super::packed`).
//!
//! A particle's 3-vector and one scalar fill one 16-byte load, and a pair's cross or outer
//! product becomes a few four-lane operations. The lanes run across a vector's components, not
//! across neighbours: eight neighbours at once need hardware gathers, which measured slower
//! (the book's benchmarks chapter, "Measurements behind design choices"). Where a pair's work is one scalar of the distance (VRSPH's
//! stream function), four neighbours' loads are transposed into rows instead
//! ([`F4::transpose3`]).

use crate::{Real, Vec3};
use std::ops::{Add, AddAssign, Mul, Sub};

/// Four f32 lanes (x, y, z, w). On x86_64 a vector register through SSE (part of the baseline
/// instruction set, so no CPU check is needed), elsewhere an array.
#[derive(Clone, Copy, Debug)]
pub struct F4(imp::Lanes);

impl Default for F4 {
    fn default() -> Self {
        F4::ZERO
    }
}

impl F4 {
    pub const ZERO: F4 = F4(imp::ZERO);

    /// The lanes (x, y, z, w).
    #[inline(always)]
    pub fn new(x: f32, y: f32, z: f32, w: f32) -> Self {
        F4(imp::new(x, y, z, w))
    }

    /// A 3-vector rounded to f32, with `w` in the fourth lane.
    #[inline(always)]
    pub fn from_vec(v: &Vec3, w: Real) -> Self {
        F4::new(v.x as f32, v.y as f32, v.z as f32, w as f32)
    }

    /// The four lanes.
    #[inline(always)]
    pub fn to_array(self) -> [f32; 4] {
        imp::to_array(self.0)
    }

    /// The first three lanes, widened.
    #[inline(always)]
    pub fn vec(self) -> Vec3 {
        let a = self.to_array();
        Vec3::new(a[0].into(), a[1].into(), a[2].into())
    }

    /// `s` in every lane.
    #[inline(always)]
    pub fn splat(s: f32) -> Self {
        F4(imp::splat(s))
    }

    /// Lane `K` in every lane.
    #[inline(always)]
    pub fn lane<const K: usize>(self) -> Self {
        F4(imp::broadcast::<K>(self.0))
    }

    /// The first three lanes rotated: (y, z, x, w).
    #[inline(always)]
    pub fn yzx(self) -> Self {
        F4(imp::yzx(self.0))
    }

    /// 1 / sqrt, lane by lane: on x86_64 the hardware estimate (12 bits) and one Newton step
    /// (relative error at most 2.1e-7, 1.8 f32 epsilons, measured over 1e-6..1e6 on Zen 4;
    /// the estimate differs between CPU makers, so the last bits do too), exact elsewhere.
    #[inline(always)]
    pub fn rsqrt(self) -> Self {
        F4(imp::rsqrt(self.0))
    }

    /// The dot product of the first three lanes.
    #[inline(always)]
    pub fn dot3(self, o: Self) -> f32 {
        imp::sum3(imp::mul(self.0, o.0))
    }

    /// Ones in the first `n` lanes, zeros in the others (`n` <= 4).
    #[inline(always)]
    pub fn first(n: usize) -> Self {
        const MASKS: [[f32; 4]; 5] = [
            [0.0; 4],
            [1.0, 0.0, 0.0, 0.0],
            [1.0, 1.0, 0.0, 0.0],
            [1.0, 1.0, 1.0, 0.0],
            [1.0; 4],
        ];
        F4(imp::load(&MASKS[n]))
    }

    /// The first three lanes of four vectors as three rows (x, y, z), lane k of each row from
    /// `v[k]`: four neighbours side by side, so that a per-pair scalar such as a distance is
    /// one four-lane operation.
    #[inline(always)]
    pub fn transpose3(v: [F4; 4]) -> [F4; 3] {
        imp::transpose3(v.map(|v| v.0)).map(F4)
    }

    /// The 3-vector stored at `flat[at..at + 3]` (the fourth lane reads `flat[at + 3]` when it
    /// exists, zero otherwise: one load for every entry but the last).
    #[inline(always)]
    pub fn load3(flat: &[f32], at: usize) -> Self {
        match flat.get(at..at + 4) {
            Some(s) => F4(imp::load(s.try_into().expect("a slice of four"))),
            None => F4::new(flat[at], flat[at + 1], flat[at + 2], 0.0),
        }
    }
}

impl Add for F4 {
    type Output = F4;
    #[inline(always)]
    fn add(self, o: F4) -> F4 {
        F4(imp::add(self.0, o.0))
    }
}

impl AddAssign for F4 {
    #[inline(always)]
    fn add_assign(&mut self, o: F4) {
        *self = *self + o;
    }
}

impl Sub for F4 {
    type Output = F4;
    #[inline(always)]
    fn sub(self, o: F4) -> F4 {
        F4(imp::sub(self.0, o.0))
    }
}

impl Mul for F4 {
    type Output = F4;
    #[inline(always)]
    fn mul(self, o: F4) -> F4 {
        F4(imp::mul(self.0, o.0))
    }
}

/// The lanes as an SSE register. Written per lane, LLVM drops lanes whose results go unused
/// (the fourth) and splits the rest into two-lane and scalar instructions, which measured
/// 1.7 times slower than the SSE forms.
#[cfg(target_arch = "x86_64")]
mod imp {
    use std::arch::x86_64::*;

    pub type Lanes = __m128;
    // SAFETY (every `unsafe` below): SSE and SSE2 belong to the x86_64 baseline, and the
    // loads and stores touch only the four floats of their arrays.
    pub const ZERO: Lanes = unsafe { std::mem::transmute::<[f32; 4], Lanes>([0.0; 4]) };

    #[inline(always)]
    pub fn new(x: f32, y: f32, z: f32, w: f32) -> Lanes {
        unsafe { _mm_setr_ps(x, y, z, w) }
    }
    #[inline(always)]
    pub fn load(a: &[f32; 4]) -> Lanes {
        unsafe { _mm_loadu_ps(a.as_ptr()) }
    }
    #[inline(always)]
    pub fn to_array(v: Lanes) -> [f32; 4] {
        let mut a = [0.0; 4];
        unsafe { _mm_storeu_ps(a.as_mut_ptr(), v) };
        a
    }
    #[inline(always)]
    pub fn splat(s: f32) -> Lanes {
        unsafe { _mm_set1_ps(s) }
    }
    #[inline(always)]
    pub fn broadcast<const K: usize>(v: Lanes) -> Lanes {
        unsafe {
            match K {
                0 => _mm_shuffle_ps::<0x00>(v, v),
                1 => _mm_shuffle_ps::<0x55>(v, v),
                2 => _mm_shuffle_ps::<0xaa>(v, v),
                _ => _mm_shuffle_ps::<0xff>(v, v),
            }
        }
    }
    #[inline(always)]
    pub fn yzx(v: Lanes) -> Lanes {
        unsafe { _mm_shuffle_ps::<0b11_00_10_01>(v, v) }
    }
    #[inline(always)]
    pub fn transpose3([a, b, c, d]: [Lanes; 4]) -> [Lanes; 3] {
        unsafe {
            // (x0 x1 y0 y1), (x2 x3 y2 y3), (z0 z1 w0 w1), (z2 z3 w2 w3).
            let (ab, cd) = (_mm_unpacklo_ps(a, b), _mm_unpacklo_ps(c, d));
            let (ab_z, cd_z) = (_mm_unpackhi_ps(a, b), _mm_unpackhi_ps(c, d));
            [
                _mm_movelh_ps(ab, cd),
                _mm_movehl_ps(cd, ab),
                _mm_movelh_ps(ab_z, cd_z),
            ]
        }
    }
    #[inline(always)]
    pub fn sum3(v: Lanes) -> f32 {
        unsafe {
            let xy = _mm_add_ss(v, _mm_shuffle_ps::<0x55>(v, v));
            _mm_cvtss_f32(_mm_add_ss(xy, _mm_movehl_ps(v, v)))
        }
    }
    #[inline(always)]
    pub fn add(a: Lanes, b: Lanes) -> Lanes {
        unsafe { _mm_add_ps(a, b) }
    }
    #[inline(always)]
    pub fn sub(a: Lanes, b: Lanes) -> Lanes {
        unsafe { _mm_sub_ps(a, b) }
    }
    #[inline(always)]
    pub fn mul(a: Lanes, b: Lanes) -> Lanes {
        unsafe { _mm_mul_ps(a, b) }
    }
    #[inline(always)]
    pub fn rsqrt(v: Lanes) -> Lanes {
        unsafe {
            let y = _mm_rsqrt_ps(v);
            let half_vyy = _mm_mul_ps(_mm_mul_ps(_mm_set1_ps(0.5), v), _mm_mul_ps(y, y));
            _mm_mul_ps(y, _mm_sub_ps(_mm_set1_ps(1.5), half_vyy))
        }
    }
}

/// The lanes as an array, lane by lane.
#[cfg(not(target_arch = "x86_64"))]
mod imp {
    pub type Lanes = [f32; 4];
    pub const ZERO: Lanes = [0.0; 4];

    pub fn new(x: f32, y: f32, z: f32, w: f32) -> Lanes {
        [x, y, z, w]
    }
    pub fn load(a: &[f32; 4]) -> Lanes {
        *a
    }
    pub fn to_array(v: Lanes) -> [f32; 4] {
        v
    }
    pub fn splat(s: f32) -> Lanes {
        [s; 4]
    }
    pub fn broadcast<const K: usize>(v: Lanes) -> Lanes {
        [v[K]; 4]
    }
    pub fn yzx(v: Lanes) -> Lanes {
        [v[1], v[2], v[0], v[3]]
    }
    pub fn transpose3(v: [Lanes; 4]) -> [Lanes; 3] {
        std::array::from_fn(|row| v.map(|v| v[row]))
    }
    pub fn sum3(v: Lanes) -> f32 {
        v[0] + v[1] + v[2]
    }
    pub fn add(a: Lanes, b: Lanes) -> Lanes {
        std::array::from_fn(|k| a[k] + b[k])
    }
    pub fn sub(a: Lanes, b: Lanes) -> Lanes {
        std::array::from_fn(|k| a[k] - b[k])
    }
    pub fn mul(a: Lanes, b: Lanes) -> Lanes {
        std::array::from_fn(|k| a[k] * b[k])
    }
    pub fn rsqrt(v: Lanes) -> Lanes {
        v.map(|x| 1.0 / x.sqrt())
    }
}

/// A running sum of cross products a x b in two rotated accumulators:
/// a x b = (a * b.yzx - a.yzx * b).yzx, and the outer rotation is applied once, to the total.
#[derive(Clone, Copy, Default)]
pub struct CrossSum(F4, F4);

impl CrossSum {
    /// Adds a x b.
    #[inline(always)]
    pub fn add(&mut self, a: F4, b: F4) {
        self.0 += a * b.yzx();
        self.1 += a.yzx() * b;
    }

    /// The sum so far.
    #[inline(always)]
    pub fn total(self) -> Vec3 {
        (self.0 - self.1).yzx().vec()
    }
}

#[cfg(test)]
mod tests {
    use super::F4;

    #[test]
    fn transpose3_puts_neighbour_k_in_lane_k() {
        let v: [F4; 4] = std::array::from_fn(|k| {
            let k = k as f32;
            F4::new(k, 10.0 + k, 20.0 + k, -1.0)
        });
        let rows = F4::transpose3(v).map(F4::to_array);
        for (c, row) in rows.iter().enumerate() {
            for (k, &x) in row.iter().enumerate() {
                assert_eq!(x, v[k].to_array()[c], "component {c} of neighbour {k}");
            }
        }
    }

    #[test]
    fn first_masks_the_lanes_after_n() {
        for n in 0..=4 {
            let mask = F4::first(n).to_array();
            assert!(mask[..n].iter().all(|&m| m == 1.0) && mask[n..].iter().all(|&m| m == 0.0));
        }
    }
}
