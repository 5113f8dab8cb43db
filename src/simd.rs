//! One source for the vector kernels (the SPH neighbour search and pair cache, the Biot–Savart
//! sums), run at the widest instruction set the CPU has: AVX-512, AVX2 with FMA, or the
//! baseline every x86-64 CPU runs (SSE2, called scalar here).
//!
//! A kernel is a [`pulp::WithSimd`] whose body is written once, generic over pulp's [`Simd`]
//! trait, and marked `#[inline(always)]` (as is every helper it calls). [`Level::run`] runs it
//! compiled under the level's target features with 512-bit vectors at every level (eight
//! f64, sixteen f32): one register on AVX-512 (pulp's `V4`), two on AVX2 (`V3_512b`), arrays
//! at the scalar level (`Scalar512b`), so a kernel's lane layout does not depend on the level.
//! The kernels use no fused multiply-add and no approximate instructions, so each level
//! computes the same bits; the tests run every level the CPU has against the scalar one.
//!
//! **Why pulp.** It is the dispatch layer of the faer linear-algebra crates, kept current, and
//! runs on stable Rust (its AVX-512 level since Rust 1.89 stabilised those target features).
//! Its levels are values (`V4::try_new()`), so a test or a benchmark can run a kernel at each
//! level the CPU has; `multiversion` hides its per-target copies behind one generated
//! dispatcher, and `wide` fixes the width when the crate is compiled, with no run-time choice.
//! Left to LLVM's auto-vectoriser, the same lane loops came out half scalar; pulp's explicit
//! operations do not.

use pulp::{NullaryFnOnce, Simd, WithSimd};
use std::sync::OnceLock;

/// f64 lanes of a kernel's vectors.
pub const LANES: usize = 8;

/// An instruction-set level, narrowest first.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Level {
    /// The x86-64 baseline (SSE2), or any other architecture.
    Scalar,
    /// AVX2 and FMA (x86-64-v3: Haswell, Zen 1 and later).
    Avx2,
    /// AVX-512 F, VL, BW, DQ and CD on top of AVX2 (x86-64-v4: Skylake-X, Zen 4).
    Avx512,
}

impl Level {
    /// Every level, narrowest first.
    pub const ALL: [Level; 3] = [Level::Scalar, Level::Avx2, Level::Avx512];

    /// The level's name, as `EDDY_SIMD` takes it.
    pub fn name(self) -> &'static str {
        match self {
            Level::Scalar => "scalar",
            Level::Avx2 => "avx2",
            Level::Avx512 => "avx512",
        }
    }

    /// Whether this CPU runs the level.
    pub fn supported(self) -> bool {
        match self {
            Level::Scalar => true,
            #[cfg(target_arch = "x86_64")]
            Level::Avx2 => pulp::x86::V3::try_new().is_some(),
            #[cfg(target_arch = "x86_64")]
            Level::Avx512 => pulp::x86::V4::try_new().is_some(),
            #[cfg(not(target_arch = "x86_64"))]
            _ => false,
        }
    }

    /// The level kernels run at: the widest this CPU has, capped by the environment variable
    /// `EDDY_SIMD` (`scalar`, `avx2` or `avx512`), so a narrower level can be measured on a
    /// wide machine. Read once per process; an unknown value is ignored with a warning.
    pub fn active() -> Level {
        static ACTIVE: OnceLock<Level> = OnceLock::new();
        *ACTIVE.get_or_init(|| {
            let widest = Level::ALL
                .into_iter()
                .rfind(|l| l.supported())
                .unwrap_or(Level::Scalar);
            let Ok(cap) = std::env::var("EDDY_SIMD") else {
                return widest;
            };
            match Level::ALL.into_iter().find(|l| l.name() == cap) {
                Some(cap) => widest.min(cap),
                None => {
                    tracing::warn!("EDDY_SIMD={cap:?} is not scalar, avx2 or avx512: ignored");
                    widest
                }
            }
        })
    }

    /// Runs `kernel` compiled for this level, or for the widest narrower one the CPU has.
    #[inline]
    pub fn run<K: WithSimd>(self, kernel: K) -> K::Output {
        #[cfg(target_arch = "x86_64")]
        {
            use pulp::x86::{V3_512b, V3, V4};
            if self >= Level::Avx512 {
                if let Some(simd) = V4::try_new() {
                    return simd.vectorize(At(kernel, simd));
                }
            }
            if self >= Level::Avx2 {
                if let Some(simd) = V3::try_new() {
                    return simd.vectorize(At(kernel, V3_512b(simd)));
                }
            }
        }
        kernel.with_simd(pulp::Scalar512b)
    }
}

/// A kernel and the vectors it runs on, as the closure pulp compiles under a level's target
/// features.
struct At<K, S>(K, S);

impl<K: WithSimd, S: Simd> NullaryFnOnce for At<K, S> {
    type Output = K::Output;

    #[inline(always)]
    fn call(self) -> K::Output {
        self.0.with_simd(self.1)
    }
}

/// The squared length x^2 + y^2 + z^2 of each lane's vector, summed in that order (no fused
/// multiply-add, so every level gives the same bits).
#[inline(always)]
pub fn norm2<S: Simd>(simd: S, x: S::f64s, y: S::f64s, z: S::f64s) -> S::f64s {
    simd.add_f64s(
        simd.add_f64s(simd.mul_f64s(x, x), simd.mul_f64s(y, y)),
        simd.mul_f64s(z, z),
    )
}

/// The lanes of the f64 mask `m` as the bits of an integer (lane l is bit l).
#[inline(always)]
pub fn bits<S: Simd>(m: S::m64s) -> u32 {
    let bytes = pulp::bytemuck::bytes_of(&m);
    if let [b] = bytes {
        // AVX-512: the mask register itself.
        return u32::from(*b);
    }
    // Elsewhere a vector of all-ones or all-zeros u64 lanes: each keeps its own bit, and an
    // OR across the vector joins them.
    let lanes: [u64; LANES] = pulp::bytemuck::pod_read_unaligned(bytes);
    let mut out = 0;
    for (l, lane) in lanes.iter().enumerate() {
        out |= lane & (1 << l);
    }
    out as u32
}

/// For every mask of [`LANES`] bits, the lanes of its set bits in increasing order, then
/// zeros, two u32 to a u64 (the first in the low half): the offsets that pack a vector's
/// selected lanes to its front.
static PACK: [[u64; LANES / 2]; 1 << LANES] = {
    let mut table = [[0; LANES / 2]; 1 << LANES];
    let mut m = 0;
    while m < table.len() {
        let (mut l, mut n) = (0, 0);
        while l < LANES {
            if m >> l & 1 == 1 {
                table[m][n / 2] |= (l as u64) << (32 * (n % 2));
                n += 1;
            }
            l += 1;
        }
        m += 1;
    }
    table
};

/// Writes `first + l` for every set lane l of `bits` (as from [`bits`]) to the front of `out`,
/// in increasing order, and returns how many; the entries past the count are overwritten with
/// junk. A table row added to `first` in both halves of four u64, without a branch.
#[inline(always)]
pub fn pack_indices(bits: u32, first: u32, out: &mut [u32; LANES]) -> usize {
    let both = u64::from(first) * 0x1_0000_0001;
    for (pair, &offsets) in out.chunks_exact_mut(2).zip(&PACK[(bits & 0xff) as usize]) {
        let v = offsets + both;
        pair[0] = v as u32;
        pair[1] = (v >> 32) as u32;
    }
    bits.count_ones() as usize
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A kernel that reports pulp's type for the level's vectors.
    struct Name;

    impl WithSimd for Name {
        type Output = &'static str;
        #[inline(always)]
        fn with_simd<S: Simd>(self, _: S) -> Self::Output {
            assert_eq!(S::F64_LANES, LANES);
            std::any::type_name::<S>()
        }
    }

    /// Each level runs on its own vectors (eight f64 everywhere) where the CPU has it, the
    /// scalar arrays otherwise, and the active level is one the CPU runs.
    #[test]
    fn each_level_runs_its_own_instruction_set() {
        for (level, name) in Level::ALL.into_iter().zip(["Scalar512b", "V3_512b", "V4"]) {
            let want = if level.supported() {
                name
            } else {
                "Scalar512b"
            };
            let got = level.run(Name);
            assert!(got.ends_with(want), "{level:?}: {got}");
        }
        assert!(Level::active().supported());
    }

    /// A kernel that compares two vectors lane by lane.
    struct Less([f64; LANES], [f64; LANES]);

    impl WithSimd for Less {
        type Output = u32;
        #[inline(always)]
        fn with_simd<S: Simd>(self, simd: S) -> u32 {
            let (a, b) = (pulp::cast(self.0), pulp::cast(self.1));
            bits::<S>(simd.less_than_f64s(a, b))
        }
    }

    /// A kernel that packs the lanes of a mask, from 100 on.
    struct Pack<'a>(u32, &'a mut [u32; LANES]);

    impl WithSimd for Pack<'_> {
        type Output = usize;
        #[inline(always)]
        fn with_simd<S: Simd>(self, _: S) -> usize {
            pack_indices(self.0, 100, self.1)
        }
    }

    /// For every mask, at every level the CPU runs, a comparison gives the mask's bits, and
    /// packing writes exactly the selected indices, in order.
    #[test]
    fn masks_and_packing_keep_the_selected_lanes_in_order() {
        for m in 0..1u32 << LANES {
            let a = std::array::from_fn(|l| if m >> l & 1 == 1 { -1.0 } else { 1.0 });
            for level in Level::ALL.into_iter().filter(|l| l.supported()) {
                assert_eq!(
                    level.run(Less(a, [0.0; LANES])),
                    m,
                    "{level:?}, mask {m:#b}"
                );
                let mut out = [0; LANES];
                let n = level.run(Pack(m, &mut out));
                let want: Vec<u32> = (0..LANES as u32)
                    .filter(|l| m >> l & 1 == 1)
                    .map(|l| 100 + l)
                    .collect();
                assert_eq!(&out[..n], want.as_slice(), "{level:?}, mask {m:#b}");
            }
        }
    }
}
