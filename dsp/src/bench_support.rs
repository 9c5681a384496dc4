//! What `cargo xtask bench` needs from inside the crate: a measure of the vector unit's peak on
//! the string kernels' own arithmetic (their `Lanes`, which are not public). Not part of the physics
//! API: hidden from the docs, and nothing in the crate uses it.

use crate::string::simd::{Isa, Kernel, LANES, Lanes};

/// A measure of the vector unit's peak: `iterations` steps of `Lanes::CHAINS` independent chains
/// `x ← x·m + c` (a multiply and an add, as in the string's loops, never fused) on chunks of
/// [`LANES`]. Returns the flops done, `iterations · CHAINS · LANES · 2`; the result of the chains
/// goes through [`std::hint::black_box`] so the work is kept. A unit this CPU lacks is measured
/// on the portable one.
pub fn peak_probe(isa: Isa, iterations: usize) -> f64 {
    struct Probe(usize);
    impl Kernel for Probe {
        type Output = f64;
        #[inline(always)]
        fn run<L: Lanes>(self, s: L) -> f64 {
            let (m, c) = (s.splat(0.999_999), s.splat(1e-9));
            let mut x = [s.splat(1.0); 16];
            let chains = L::CHAINS.min(x.len());
            for (j, v) in x.iter_mut().enumerate() {
                *v = s.splat(1.0 + j as f64 * 1e-3);
            }
            for _ in 0..self.0 {
                for v in &mut x[..chains] {
                    *v = s.add(s.mul(*v, m), c);
                }
            }
            let mut sum = 0.0;
            for v in &x[..chains] {
                sum += s.sum(*v);
            }
            std::hint::black_box(sum);
            (self.0 * chains * LANES * 2) as f64
        }
    }
    let isa = if Isa::available().contains(&isa) { isa } else { Isa::Portable };
    isa.run(Probe(iterations))
}
