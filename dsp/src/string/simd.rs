//! Eight `f64` lanes on whatever vector unit the CPU has, picked at run time.
//!
//! The string's per-mode loops work on chunks of [`LANES`] modes. [`Lanes`] is the arithmetic
//! they need on one chunk (load, store, add, subtract, multiply, and the sum of the lanes), and it
//! has three implementations: one 512-bit register (AVX-512F), two 256-bit registers (AVX), and a
//! plain array that any CPU runs. Every one performs exactly the same IEEE operations on every
//! lane (never a fused multiply-add) and sums the lanes in the same order, so the three give
//! bit-identical results and the distributed binary needs no particular CPU.
//!
//! A kernel is written once, generic over [`Lanes`], as a [`Kernel`]; [`Isa::run`] calls it
//! through a function compiled for the detected instruction set, into which everything is inlined.
//!
//! This is the one module of the workspace allowed `unsafe`: calling vector intrinsics outside a
//! function compiled for their feature, and loading from pointers. Each use says why it holds.

#![allow(unsafe_code)]

use std::sync::atomic::{AtomicU8, Ordering};

/// Modes per chunk; per-mode arrays are padded to a multiple of it.
pub const LANES: usize = 8;

/// One chunk of modes.
pub type Chunk = [f64; LANES];

/// The whole chunks of a per-mode array padded to a multiple of [`LANES`].
#[inline(always)]
pub fn chunks(x: &[f64]) -> &[Chunk] {
    let (chunks, rest) = x.as_chunks::<LANES>();
    debug_assert!(rest.is_empty(), "per-mode arrays hold whole chunks");
    chunks
}

/// [`chunks`], mutable.
#[inline(always)]
pub fn chunks_mut(x: &mut [f64]) -> &mut [Chunk] {
    let (chunks, rest) = x.as_chunks_mut::<LANES>();
    debug_assert!(rest.is_empty(), "per-mode arrays hold whole chunks");
    chunks
}

/// Sum of the lanes in a fixed order: the halving tree of a vector reduction (lanes `i` and
/// `i+4`, then `i` and `i+2`, then the last two).
#[inline(always)]
pub fn lane_sum(acc: Chunk) -> f64 {
    ((acc[0] + acc[4]) + (acc[2] + acc[6])) + ((acc[1] + acc[5]) + (acc[3] + acc[7]))
}

/// Arithmetic on one chunk of [`LANES`] values.
pub trait Lanes: Copy {
    /// A chunk in registers.
    type V: Copy;
    /// Chunks a register-resident loop keeps in registers, each with two states and three
    /// coefficients (`kernel::free_run`): four with 32 registers of a chunk (AVX-512), two with
    /// 16 registers of half a chunk (AVX), one otherwise. More would spill to the stack.
    const RESIDENT: usize;
    /// Independent chunk-wide multiply–add chains that fill the vector unit without spilling
    /// (`bench_support::peak_probe`): enough to hide the latency of a multiply and an add on every
    /// arithmetic port.
    const CHAINS: usize;
    /// Chunks the vector register file holds.
    const REGISTERS: usize;
    /// Load a chunk.
    fn load(self, x: &Chunk) -> Self::V;
    /// Store a chunk.
    fn store(self, x: &mut Chunk, v: Self::V);
    /// Every lane `x`.
    fn splat(self, x: f64) -> Self::V;
    /// `a + b` per lane.
    fn add(self, a: Self::V, b: Self::V) -> Self::V;
    /// `a − b` per lane.
    fn sub(self, a: Self::V, b: Self::V) -> Self::V;
    /// `a · b` per lane.
    fn mul(self, a: Self::V, b: Self::V) -> Self::V;
    /// The lanes summed in the order of [`lane_sum`].
    fn sum(self, v: Self::V) -> f64;
}

/// A computation over chunks, written once for every [`Lanes`].
pub trait Kernel {
    /// What it returns.
    type Output;
    /// Run on `lanes`.
    fn run<L: Lanes>(self, lanes: L) -> Self::Output;
}

/// The vector unit to run kernels on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Isa {
    /// One 512-bit register per chunk.
    #[cfg(target_arch = "x86_64")]
    Avx512,
    /// Two 256-bit registers per chunk.
    #[cfg(target_arch = "x86_64")]
    Avx,
    /// Plain arrays (the compiler vectorises what it can for the baseline target).
    Portable,
}

/// The widest unit [`Isa::detect`] may return, as [`Isa::rank`] ([`Isa::cap`]).
static WIDEST: AtomicU8 = AtomicU8::new(u8::MAX);

impl Isa {
    /// The widest unit this CPU has, within [`Isa::cap`].
    pub fn detect() -> Isa {
        #[cfg(target_arch = "x86_64")]
        {
            let widest = WIDEST.load(Ordering::Relaxed);
            if Isa::Avx512.rank() <= widest && std::arch::is_x86_feature_detected!("avx512f") {
                return Isa::Avx512;
            }
            if Isa::Avx.rank() <= widest && std::arch::is_x86_feature_detected!("avx") {
                return Isa::Avx;
            }
        }
        Isa::Portable
    }

    /// From now on, [`Isa::detect`] returns `widest` or a narrower unit: strings and bodies built
    /// afterwards run as on a CPU without the wider ones (the bench measures an AVX2 machine's
    /// speed on an AVX-512 one this way; the results are the same bits on every unit).
    pub fn cap(widest: Isa) {
        WIDEST.store(widest.rank(), Ordering::Relaxed);
    }

    /// Order by width: portable 0, AVX 1, AVX-512 2.
    fn rank(self) -> u8 {
        match self {
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512 => 2,
            #[cfg(target_arch = "x86_64")]
            Isa::Avx => 1,
            Isa::Portable => 0,
        }
    }

    /// Every unit this CPU can run, widest first (for tests that compare them).
    pub fn available() -> Vec<Isa> {
        let mut all = Vec::new();
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx512f") {
                all.push(Isa::Avx512);
            }
            if std::arch::is_x86_feature_detected!("avx") {
                all.push(Isa::Avx);
            }
        }
        all.push(Isa::Portable);
        all
    }

    /// Run `kernel` on this unit. Crate-private: the unit must be one this CPU has, and a
    /// public function given an `Isa` from outside checks it against [`Isa::available`] first.
    #[inline]
    pub(crate) fn run<K: Kernel>(self, kernel: K) -> K::Output {
        match self {
            // SAFETY: an `Isa` other than `Portable` that reaches here comes from `detect` or
            // `available`, which return it only when the CPU has the feature, or has been
            // checked against `available` (`bench_support::peak_probe`).
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512 => unsafe { x86::run_avx512(kernel) },
            #[cfg(target_arch = "x86_64")]
            Isa::Avx => unsafe { x86::run_avx(kernel) },
            Isa::Portable => kernel.run(Portable),
        }
    }
}

/// Plain arrays.
#[derive(Debug, Clone, Copy)]
pub struct Portable;

impl Lanes for Portable {
    type V = Chunk;
    const RESIDENT: usize = 1;
    const CHAINS: usize = 3;
    const REGISTERS: usize = 4;

    #[inline(always)]
    fn load(self, x: &Chunk) -> Chunk {
        *x
    }
    #[inline(always)]
    fn store(self, x: &mut Chunk, v: Chunk) {
        *x = v;
    }
    #[inline(always)]
    fn splat(self, x: f64) -> Chunk {
        [x; LANES]
    }
    #[inline(always)]
    fn add(self, a: Chunk, b: Chunk) -> Chunk {
        std::array::from_fn(|l| a[l] + b[l])
    }
    #[inline(always)]
    fn sub(self, a: Chunk, b: Chunk) -> Chunk {
        std::array::from_fn(|l| a[l] - b[l])
    }
    #[inline(always)]
    fn mul(self, a: Chunk, b: Chunk) -> Chunk {
        std::array::from_fn(|l| a[l] * b[l])
    }
    #[inline(always)]
    fn sum(self, v: Chunk) -> f64 {
        lane_sum(v)
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    //! The x86-64 units. Their tokens are created only inside functions compiled for the feature,
    //! which [`Isa::run`](super::Isa::run) calls only when the CPU has it.

    use std::arch::x86_64::*;

    use super::{Chunk, Kernel, Lanes};

    /// AVX-512F: one `zmm` register per chunk.
    #[derive(Debug, Clone, Copy)]
    pub struct Avx512(());

    /// AVX: two `ymm` registers per chunk, lanes 0–3 and 4–7.
    #[derive(Debug, Clone, Copy)]
    pub struct Avx(());

    /// # Safety
    /// The CPU must have AVX-512F.
    #[target_feature(enable = "avx512f")]
    pub unsafe fn run_avx512<K: Kernel>(kernel: K) -> K::Output {
        kernel.run(Avx512(()))
    }

    /// # Safety
    /// The CPU must have AVX.
    #[target_feature(enable = "avx")]
    pub unsafe fn run_avx<K: Kernel>(kernel: K) -> K::Output {
        kernel.run(Avx(()))
    }

    // SAFETY (every block below): an `Avx512` token exists only inside `run_avx512`, so the CPU has
    // AVX-512F; pointers come from references to whole chunks of eight `f64`.
    impl Lanes for Avx512 {
        type V = __m512d;
        const RESIDENT: usize = 4;
        const CHAINS: usize = 16;
        const REGISTERS: usize = 32;

        #[inline(always)]
        fn load(self, x: &Chunk) -> __m512d {
            unsafe { _mm512_loadu_pd(x.as_ptr()) }
        }
        #[inline(always)]
        fn store(self, x: &mut Chunk, v: __m512d) {
            unsafe { _mm512_storeu_pd(x.as_mut_ptr(), v) }
        }
        #[inline(always)]
        fn splat(self, x: f64) -> __m512d {
            unsafe { _mm512_set1_pd(x) }
        }
        #[inline(always)]
        fn add(self, a: __m512d, b: __m512d) -> __m512d {
            unsafe { _mm512_add_pd(a, b) }
        }
        #[inline(always)]
        fn sub(self, a: __m512d, b: __m512d) -> __m512d {
            unsafe { _mm512_sub_pd(a, b) }
        }
        #[inline(always)]
        fn mul(self, a: __m512d, b: __m512d) -> __m512d {
            unsafe { _mm512_mul_pd(a, b) }
        }
        #[inline(always)]
        fn sum(self, v: __m512d) -> f64 {
            unsafe {
                // [a0+a4, a1+a5, a2+a6, a3+a7], then [(a0+a4)+(a2+a6), (a1+a5)+(a3+a7)].
                let quarter = _mm256_add_pd(_mm512_castpd512_pd256(v), _mm512_extractf64x4_pd::<1>(v));
                let half = _mm_add_pd(_mm256_castpd256_pd128(quarter), _mm256_extractf128_pd::<1>(quarter));
                _mm_cvtsd_f64(_mm_add_sd(half, _mm_unpackhi_pd(half, half)))
            }
        }
    }

    // SAFETY (every block below): an `Avx` token exists only inside `run_avx`, so the CPU has
    // AVX; pointers come from references to whole chunks of eight `f64` (two halves of four).
    impl Lanes for Avx {
        type V = (__m256d, __m256d);
        const RESIDENT: usize = 2;
        const CHAINS: usize = 6;
        const REGISTERS: usize = 8;

        #[inline(always)]
        fn load(self, x: &Chunk) -> Self::V {
            unsafe { (_mm256_loadu_pd(x.as_ptr()), _mm256_loadu_pd(x.as_ptr().add(4))) }
        }
        #[inline(always)]
        fn store(self, x: &mut Chunk, v: Self::V) {
            unsafe {
                _mm256_storeu_pd(x.as_mut_ptr(), v.0);
                _mm256_storeu_pd(x.as_mut_ptr().add(4), v.1);
            }
        }
        #[inline(always)]
        fn splat(self, x: f64) -> Self::V {
            unsafe { (_mm256_set1_pd(x), _mm256_set1_pd(x)) }
        }
        #[inline(always)]
        fn add(self, a: Self::V, b: Self::V) -> Self::V {
            unsafe { (_mm256_add_pd(a.0, b.0), _mm256_add_pd(a.1, b.1)) }
        }
        #[inline(always)]
        fn sub(self, a: Self::V, b: Self::V) -> Self::V {
            unsafe { (_mm256_sub_pd(a.0, b.0), _mm256_sub_pd(a.1, b.1)) }
        }
        #[inline(always)]
        fn mul(self, a: Self::V, b: Self::V) -> Self::V {
            unsafe { (_mm256_mul_pd(a.0, b.0), _mm256_mul_pd(a.1, b.1)) }
        }
        #[inline(always)]
        fn sum(self, v: Self::V) -> f64 {
            unsafe {
                let quarter = _mm256_add_pd(v.0, v.1);
                let half = _mm_add_pd(_mm256_castpd256_pd128(quarter), _mm256_extractf128_pd::<1>(quarter));
                _mm_cvtsd_f64(_mm_add_sd(half, _mm_unpackhi_pd(half, half)))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cap makes `detect` return that unit or a narrower one the CPU has, and lifting it (the
    /// widest cap) gives the widest again; `available` is not capped.
    #[test]
    fn a_cap_limits_detect_to_that_unit_or_narrower() {
        let widest = Isa::detect();
        let all = Isa::available();
        Isa::cap(Isa::Portable);
        let capped = Isa::detect();
        #[cfg(target_arch = "x86_64")]
        Isa::cap(Isa::Avx512);
        #[cfg(not(target_arch = "x86_64"))]
        Isa::cap(Isa::Portable);
        assert_eq!(capped, Isa::Portable);
        assert_eq!(Isa::detect(), widest);
        assert_eq!(Isa::available(), all);
        #[cfg(target_arch = "x86_64")]
        if all.contains(&Isa::Avx) {
            Isa::cap(Isa::Avx);
            let avx = Isa::detect();
            Isa::cap(Isa::Avx512);
            assert_eq!(avx, Isa::Avx);
        }
    }
}
