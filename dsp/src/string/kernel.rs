//! The per-mode loops of a string step, written for SIMD.
//!
//! Every array has a length that is a multiple of [`LANES`] (the string pads its modes with inert
//! zero modes). Each pass is a plain element-wise loop over equal-length slices (which the loop
//! vectoriser turns into full-width SIMD) followed by dot products that keep one partial sum per
//! lane, so there are no tail loops, no per-element bounds checks, and no loop-carried
//! dependency longer than one chunk. (Fusing the projections into the element-wise loop, one
//! loop per pass, was measured 1.5 times slower: the vectoriser then emits 128-bit code.) The partial sums are combined in a fixed order
//! ([`lane_sum`]), and Rust never contracts `a*b + c` into a fused multiply-add, so every
//! instruction set gives bit-identical results. The kernels are compiled for several x86-64
//! levels and the best one the CPU supports is picked at run time (`multiversion`); the
//! distributed binary needs no particular CPU.

use multiversion::multiversion;

/// Modes per chunk; arrays are padded to a multiple of it.
pub const LANES: usize = 8;

/// Sum of the lane partial sums, in a fixed order: the halving tree of a vector reduction
/// (lanes `i` and `i+4`, then `i` and `i+2`, then the last two), which SIMD code can follow
/// without shuffling lanes inside the loop.
#[inline(always)]
pub fn lane_sum(acc: [f64; LANES]) -> f64 {
    ((acc[0] + acc[4]) + (acc[2] + acc[6])) + ((acc[1] + acc[5]) + (acc[3] + acc[7]))
}

/// `aᵀb` with [`LANES`] partial sums combined in a fixed order. The slices have equal length,
/// a multiple of [`LANES`].
#[inline(always)]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut acc = [0.0; LANES];
    for c in (0..a.len()).step_by(LANES) {
        let x: [f64; LANES] = a[c..c + LANES].try_into().expect("whole chunks");
        let y: [f64; LANES] = b[c..c + LANES].try_into().expect("whole chunks");
        for l in 0..LANES {
            acc[l] += x[l] * y[l];
        }
    }
    lane_sum(acc)
}

/// Pass 1: `zt = b∘up − a∘un`; returns the projections `vectors_kᵀ zt`.
#[multiversion(targets("x86_64+avx512f+avx512vl+avx2+fma", "x86_64+avx2+fma", "x86_64+avx"))]
pub fn history<const K: usize>(
    a: &[f64],
    b: &[f64],
    up: &[f64],
    un: &[f64],
    zt: &mut [f64],
    vectors: [&[f64]; K],
) -> [f64; K] {
    let n = zt.len();
    let (a, b, up, un) = (&a[..n], &b[..n], &up[..n], &un[..n]);
    for i in 0..n {
        zt[i] = b[i] * up[i] - a[i] * un[i];
    }
    let mut sums = [0.0; K];
    for k in 0..K {
        sums[k] = dot(&vectors[k][..n], zt);
    }
    sums
}

/// Pass 2: `up = up − zt + Σ_k g_k F_k`; returns `outᵀ up`.
#[multiversion(targets("x86_64+avx512f+avx512vl+avx2+fma", "x86_64+avx2+fma", "x86_64+avx"))]
pub fn advance<const K: usize>(up: &mut [f64], zt: &[f64], forces: [(&[f64], f64); K], out: &[f64]) -> f64 {
    let n = up.len();
    let zt = &zt[..n];
    let mut gains = [&[][..]; K];
    let mut f = [0.0; K];
    for k in 0..K {
        gains[k] = &forces[k].0[..n];
        f[k] = forces[k].1;
    }
    for i in 0..n {
        let mut next = up[i] - zt[i];
        for k in 0..K {
            next += gains[k][i] * f[k];
        }
        up[i] = next;
    }
    dot(&out[..n], up)
}

/// Pass 2 with the energy terms: as [`advance`], and also returns
/// `(Σ (u' − un)², Σ K̂ (u' + un)², Σ R̂ (u' − up)²)` with `u'` the new state.
#[allow(clippy::too_many_arguments)]
pub fn advance_monitored<const K: usize>(
    up: &mut [f64],
    un: &[f64],
    zt: &[f64],
    forces: [(&[f64], f64); K],
    out: &[f64],
    stiffness: &[f64],
    resistance: &[f64],
) -> (f64, [f64; 3]) {
    let n = up.len();
    let mut sums = [[0.0; LANES]; 3];
    for c in (0..n).step_by(LANES) {
        for l in 0..LANES {
            let i = c + l;
            let mut next = up[i] - zt[i];
            for (g, f) in &forces {
                next += g[i] * f;
            }
            let (d, s, r) = (next - un[i], next + un[i], next - up[i]);
            sums[0][l] += d * d;
            sums[1][l] += stiffness[i] * s * s;
            sums[2][l] += resistance[i] * r * r;
            up[i] = next;
        }
    }
    (dot(&out[..n], up), [lane_sum(sums[0]), lane_sum(sums[1]), lane_sum(sums[2])])
}
