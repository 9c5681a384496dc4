//! The per-mode loops of a string step, written once over [`Lanes`] (see `simd`).
//!
//! Every array has a length that is a multiple of [`LANES`] (the string pads its modes with inert
//! zero modes), so each loop runs over whole chunks with no tail and no bounds checks inside.
//! A dot product keeps two partial sums per lane, one for the even chunks and one for the odd
//! (two independent addition chains, so the loop is not bound by the latency of one), adds the
//! two and sums the lanes in a fixed order; with no fused multiply-adds anywhere, every
//! instruction set gives bit-identical results.

use super::simd::{Chunk, Isa, Kernel, LANES, Lanes, chunks, chunks_mut, lane_sum};

/// Run `$body` for every chunk index `$c` in `0..$n` (or `$lo..$hi` with `@range`) with `$acc`
/// bound to the even or the odd accumulator by the parity of `$c`, two chunks per iteration, so
/// the two stay in registers. A range's chunks add to the accumulators exactly as they do in a
/// pass over `0..$n`, so a loop split into ranges gives the same sums.
///
/// With `fits = false` (both sets of accumulators and the loop's temporaries would not fit the
/// vector registers together) it runs two sweeps instead, the even chunks into `$acc0`, then
/// the odd ones into `$acc1`, so only one set is live at a time: the same sums in the same
/// order, with half the registers.
macro_rules! paired {
    (@range $lo:expr, $hi:expr, fits = $fits:expr, $acc0:ident, $acc1:ident, |$c:ident, $acc:ident| $body:block) => {{
        let (lo, hi): (usize, usize) = ($lo, $hi);
        if $fits {
            let mut pair = lo;
            if pair < hi && pair % 2 == 1 {
                let $c = pair;
                let $acc = &mut $acc1;
                $body
                pair += 1;
            }
            while pair + 2 <= hi {
                {
                    let $c = pair;
                    let $acc = &mut $acc0;
                    $body
                }
                {
                    let $c = pair + 1;
                    let $acc = &mut $acc1;
                    $body
                }
                pair += 2;
            }
            if pair < hi {
                let $c = pair;
                let $acc = &mut $acc0;
                $body
            }
        } else {
            paired!(@sweep lo + lo % 2, hi, $acc0, |$c, $acc| $body);
            paired!(@sweep lo + 1 - lo % 2, hi, $acc1, |$c, $acc| $body);
        }
    }};
    (@sweep $first:expr, $hi:expr, $into:ident, |$c:ident, $acc:ident| $body:block) => {{
        let mut next = $first;
        while next < $hi {
            let $c = next;
            let $acc = &mut $into;
            $body
            next += 2;
        }
    }};
    ($n:expr, fits = $fits:expr, $acc0:ident, $acc1:ident, |$c:ident, $acc:ident| $body:block) => {
        paired!(@range 0, $n, fits = $fits, $acc0, $acc1, |$c, $acc| $body)
    };
    ($n:expr, $acc0:ident, $acc1:ident, |$c:ident, $acc:ident| $body:block) => {
        paired!(@range 0, $n, fits = true, $acc0, $acc1, |$c, $acc| $body)
    };
}

/// Whether `chunks` chunks fit the vector registers of `L` at once.
#[inline(always)]
const fn fits<L: Lanes>(chunks: usize) -> bool {
    chunks <= L::REGISTERS
}

/// Add chunk `c` of each vector times `z` to its partial sum. (Functions, not closures: a
/// closure would be compiled outside the target feature.)
#[inline(always)]
fn accumulate<L: Lanes, const K: usize>(s: L, acc: &mut [L::V; K], vectors: &[&[Chunk]; K], c: usize, z: L::V) {
    for k in 0..K {
        acc[k] = s.add(acc[k], s.mul(s.load(&vectors[k][c]), z));
    }
}

/// The dot products from their even and odd partial sums, in the fixed order.
#[inline(always)]
fn finish<L: Lanes, const K: usize>(s: L, even: [L::V; K], odd: [L::V; K]) -> [f64; K] {
    let mut sums = [0.0; K];
    for k in 0..K {
        sums[k] = s.sum(s.add(even[k], odd[k]));
    }
    sums
}

/// Pass 1: `zt = b∘up − a∘un`; returns the projections `vectors_kᵀ zt`.
#[inline]
pub fn history<const K: usize>(
    isa: Isa,
    a: &[f64],
    b: &[f64],
    up: &[f64],
    un: &[f64],
    zt: &mut [f64],
    vectors: [&[f64]; K],
) -> [f64; K] {
    struct History<'a, const K: usize> {
        a: &'a [Chunk],
        b: &'a [Chunk],
        up: &'a [Chunk],
        un: &'a [Chunk],
        zt: &'a mut [Chunk],
        vectors: [&'a [Chunk]; K],
    }
    impl<const K: usize> Kernel for History<'_, K> {
        type Output = [f64; K];
        #[inline(always)]
        fn run<L: Lanes>(self, s: L) -> [f64; K] {
            let n = self.zt.len();
            let (a, b, up, un) = (&self.a[..n], &self.b[..n], &self.up[..n], &self.un[..n]);
            let mut vectors = self.vectors;
            for v in &mut vectors {
                *v = &v[..n];
            }
            let zts = self.zt;
            // Accumulators: the K projections, twice; temporaries: `zt` and two products.
            let (mut even, mut odd) = ([s.splat(0.0); K], [s.splat(0.0); K]);
            paired!(n, fits = fits::<L>(2 * K + 3), even, odd, |c, acc| {
                let z = s.sub(s.mul(s.load(&b[c]), s.load(&up[c])), s.mul(s.load(&a[c]), s.load(&un[c])));
                s.store(&mut zts[c], z);
                accumulate(s, acc, &vectors, c, z);
            });
            finish(s, even, odd)
        }
    }
    isa.run(History {
        a: chunks(a),
        b: chunks(b),
        up: chunks(up),
        un: chunks(un),
        zt: chunks_mut(zt),
        vectors: vectors.map(chunks),
    })
}

/// Pass 2: `up = up − zt + Σ_k g_k F_k`; returns `outᵀ up`. In the same pass, the next step's
/// pass 1: `zt = b∘un − a∘up` with the new `up` (the state moves on by a swap, so this is exactly
/// what [`history`] would compute next), and its projections on the `J` vectors `next` (the sums
/// [`history`] and [`projections`] return for the same `zt`, bit for bit).
#[inline]
#[allow(clippy::too_many_arguments)]
pub fn advance<const K: usize, const J: usize>(
    isa: Isa,
    a: &[f64],
    b: &[f64],
    up: &mut [f64],
    un: &[f64],
    zt: &mut [f64],
    forces: [(&[f64], f64); K],
    out: &[f64],
    next: [&[f64]; J],
) -> (f64, [f64; J]) {
    let whole = Tail { start: up.len(), forces: [], next: [] };
    let (out, next, []) = advance_split(isa, a, b, up, un, zt, forces, out, next, whole);
    (out, next)
}

/// The modes of a bank from `start` on, with forces and projected vectors of their own (a
/// piano key's bridge after its strings): see `advance_split`.
#[derive(Debug)]
pub struct Tail<'a, const K: usize, const J: usize> {
    /// The first mode of the tail.
    pub start: usize,
    /// The forces on the tail, with their gains.
    pub forces: [(&'a [f64], f64); K],
    /// The vectors the next `zt` is projected on over the tail.
    pub next: [&'a [f64]; J],
}

/// [`advance`] over a bank whose modes before `tail.start` (the head) feel the `forces` and are
/// projected on `next` and `out`, and whose modes from `tail.start` on feel `tail.forces` and are
/// projected on `tail.next`: every gain and vector is zero on the other part, so their products
/// are skipped there and the sums are the same bits as [`advance`] with every vector over the
/// whole bank. Returns `outᵀ up` and the projections of the head's and the tail's vectors.
#[inline]
#[allow(clippy::too_many_arguments)]
pub fn advance_split<const K: usize, const J: usize, const KT: usize, const JT: usize>(
    isa: Isa,
    a: &[f64],
    b: &[f64],
    up: &mut [f64],
    un: &[f64],
    zt: &mut [f64],
    forces: [(&[f64], f64); K],
    out: &[f64],
    next: [&[f64]; J],
    tail: Tail<'_, KT, JT>,
) -> (f64, [f64; J], [f64; JT]) {
    /// One side of the split: the gains of its forces, the forces, its projected vectors.
    struct Side<'a, const K: usize, const J: usize> {
        gains: [&'a [Chunk]; K],
        forces: [f64; K],
        next: [&'a [Chunk]; J],
    }
    struct Advance<'a, const K: usize, const J: usize, const KT: usize, const JT: usize> {
        a: &'a [Chunk],
        b: &'a [Chunk],
        up: &'a mut [Chunk],
        un: &'a [Chunk],
        zt: &'a mut [Chunk],
        out: &'a [Chunk],
        head: Side<'a, K, J>,
        tail: Side<'a, KT, JT>,
        /// The chunks with head modes end here; those with tail modes start at `tail_start`.
        head_end: usize,
        tail_start: usize,
    }
    /// The output sum and both sides' projections, as partial sums.
    type Sums<V, const J: usize, const JT: usize> = (V, [V; J], [V; JT]);
    /// Chunks `lo..hi`, with the head's terms if `HEAD` and the tail's if `TAIL`.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn segment<
        L: Lanes,
        const K: usize,
        const J: usize,
        const KT: usize,
        const JT: usize,
        const HEAD: bool,
        const TAIL: bool,
    >(
        s: L,
        run: &mut Advance<'_, K, J, KT, JT>,
        lo: usize,
        hi: usize,
        even: &mut Sums<L::V, J, JT>,
        odd: &mut Sums<L::V, J, JT>,
    ) {
        let n = run.up.len();
        let (a, b, un, out) = (&run.a[..n], &run.b[..n], &run.un[..n], &run.out[..n]);
        let (ups, zts) = (&mut *run.up, &mut run.zt[..n]);
        let head_forces: [L::V; K] = std::array::from_fn(|k| s.splat(run.head.forces[k]));
        let tail_forces: [L::V; KT] = std::array::from_fn(|k| s.splat(run.tail.forces[k]));
        let head_gains: [&[Chunk]; K] = run.head.gains.map(|g| &g[..n]);
        let tail_gains: [&[Chunk]; KT] = run.tail.gains.map(|g| &g[..n]);
        let head_next: [&[Chunk]; J] = run.head.next.map(|v| &v[..n]);
        let tail_next: [&[Chunk]; JT] = run.tail.next.map(|v| &v[..n]);
        // Accumulators: the output sum and the projections of the sides present, twice; with the
        // forces, the new state, `zt` and a product as temporaries.
        let sides = (if HEAD { 1 + J } else { 0 }) + (if TAIL { JT } else { 0 });
        let pushes = (if HEAD { K } else { 0 }) + (if TAIL { KT } else { 0 });
        let (mut e, mut o) = (&mut *even, &mut *odd);
        paired!(@range lo, hi, fits = fits::<L>(2 * sides + pushes + 3), e, o, |c, acc| {
            let mut next = s.sub(s.load(&ups[c]), s.load(&zts[c]));
            if HEAD {
                for k in 0..K {
                    next = s.add(next, s.mul(s.load(&head_gains[k][c]), head_forces[k]));
                }
            }
            if TAIL {
                for k in 0..KT {
                    next = s.add(next, s.mul(s.load(&tail_gains[k][c]), tail_forces[k]));
                }
            }
            s.store(&mut ups[c], next);
            if HEAD {
                acc.0 = s.add(acc.0, s.mul(s.load(&out[c]), next));
            }
            let z = s.sub(s.mul(s.load(&b[c]), s.load(&un[c])), s.mul(s.load(&a[c]), next));
            s.store(&mut zts[c], z);
            if HEAD {
                accumulate(s, &mut acc.1, &head_next, c, z);
            }
            if TAIL {
                accumulate(s, &mut acc.2, &tail_next, c, z);
            }
        });
    }
    impl<const K: usize, const J: usize, const KT: usize, const JT: usize> Kernel for Advance<'_, K, J, KT, JT> {
        type Output = (f64, [f64; J], [f64; JT]);
        #[inline(always)]
        fn run<L: Lanes>(mut self, s: L) -> Self::Output {
            let n = self.up.len();
            let (head_end, tail_start) = (self.head_end.min(n), self.tail_start.min(n));
            let zero = s.splat(0.0);
            let (mut even, mut odd) = ((zero, [zero; J], [zero; JT]), (zero, [zero; J], [zero; JT]));
            let run = &mut self;
            segment::<L, K, J, KT, JT, true, false>(s, run, 0, tail_start.min(head_end), &mut even, &mut odd);
            segment::<L, K, J, KT, JT, true, true>(s, run, tail_start, head_end, &mut even, &mut odd);
            segment::<L, K, J, KT, JT, false, true>(s, run, head_end.max(tail_start), n, &mut even, &mut odd);
            (s.sum(s.add(even.0, odd.0)), finish(s, even.1, odd.1), finish(s, even.2, odd.2))
        }
    }
    isa.run(Advance {
        a: chunks(a),
        b: chunks(b),
        up: chunks_mut(up),
        un: chunks(un),
        zt: chunks_mut(zt),
        out: chunks(out),
        head: Side { gains: forces.map(|(g, _)| chunks(g)), forces: forces.map(|(_, f)| f), next: next.map(chunks) },
        tail: Side {
            gains: tail.forces.map(|(g, _)| chunks(g)),
            forces: tail.forces.map(|(_, f)| f),
            next: tail.next.map(chunks),
        },
        head_end: tail.start.div_ceil(LANES),
        tail_start: tail.start / LANES,
    })
}

/// The projections `vectors_kᵀ zt` of a `zt` already computed by [`advance`]: the sums
/// [`history`] returns for the same `zt`, bit for bit.
#[inline]
pub fn projections<const K: usize>(isa: Isa, zt: &[f64], vectors: [&[f64]; K]) -> [f64; K] {
    struct Projections<'a, const K: usize> {
        zt: &'a [Chunk],
        vectors: [&'a [Chunk]; K],
    }
    impl<const K: usize> Kernel for Projections<'_, K> {
        type Output = [f64; K];
        #[inline(always)]
        fn run<L: Lanes>(self, s: L) -> [f64; K] {
            let n = self.zt.len();
            let zt = self.zt;
            let mut vectors = self.vectors;
            for v in &mut vectors {
                *v = &v[..n];
            }
            // Accumulators: the K projections, twice; temporaries: `zt` and a product.
            let (mut even, mut odd) = ([s.splat(0.0); K], [s.splat(0.0); K]);
            paired!(n, fits = fits::<L>(2 * K + 2), even, odd, |c, acc| {
                accumulate(s, acc, &vectors, c, s.load(&zt[c]));
            });
            finish(s, even, odd)
        }
    }
    isa.run(Projections { zt: chunks(zt), vectors: vectors.map(chunks) })
}

/// Most steps [`free_run`] takes per call.
pub const RUN: usize = 64;

/// `outputs.len()` (at most [`RUN`]) steps without forces, by the homogeneous recursion itself:
/// `up = a∘un − (b − 1)∘up`, i.e. `ũ^{n+1} = 2P ũ^n − Q ũ^{n−1}` with the full step's own
/// coefficients (`b − 1 = Q` exactly: `b = 1 + Q` lies in `[1, 2]`, so the subtraction is exact,
/// and padded modes stay zero). The state is kept in registers: `up`, `un` hold `ũ^{n−1}`, `ũ^n`
/// on entry and the last two states on return (no swap needed), and `outputs[t]` receives
/// `outᵀũ^{n+1+t}`.
///
/// [`history`] then [`advance`] with every force zero compute `up − (b∘up − a∘un)`: the same
/// recursion, rounded differently (agreeing to a few ulps of the terms per step). This form has a
/// product and one subtraction on each mode's dependency chain from one step to the next, where
/// that one has a product and two subtractions, so a run of free steps, which is bound by that
/// chain's latency, is about a third shorter per step.
///
/// The loops run over groups of chunks (as many as the vector registers hold: `Lanes::RESIDENT`,
/// four with AVX-512, two with AVX), and within a group over the samples: the chunks'
/// recursions are independent, so their latencies overlap, and nothing goes through memory but
/// the per-sample partial sums. Those are added chunk after chunk, the even chunks into one sum and
/// the odd into another, in the order of one pass over the modes, so the outputs are the same bits
/// whatever the group size (and on every instruction set). A group's step is bound by the
/// latency of one recursion step (a product and a subtraction), which two chunks' work just
/// fills with AVX.
#[inline]
pub fn free_run(isa: Isa, a: &[f64], b: &[f64], up: &mut [f64], un: &mut [f64], out: &[f64], outputs: &mut [f64]) {
    struct FreeRun<'a> {
        a: &'a [Chunk],
        b: &'a [Chunk],
        up: &'a mut [Chunk],
        un: &'a mut [Chunk],
        out: &'a [Chunk],
        outputs: &'a mut [f64],
    }
    #[inline(always)]
    fn group<L: Lanes, const G: usize>(s: L, run: &mut FreeRun<'_>, first: usize, sums: &mut [[Chunk; 2]]) {
        let (zero, one) = (s.splat(0.0), s.splat(1.0));
        let (mut a, mut q, mut w, mut prev, mut now) = ([zero; G], [zero; G], [zero; G], [zero; G], [zero; G]);
        for i in 0..G {
            let c = first + i;
            (a[i], q[i], w[i]) = (s.load(&run.a[c]), s.sub(s.load(&run.b[c]), one), s.load(&run.out[c]));
            (prev[i], now[i]) = (s.load(&run.up[c]), s.load(&run.un[c]));
        }
        // Chunk `first + i` adds to the partial sum of its parity, as in a single pass.
        let (parity, opposite) = (first % 2, 1 - first % 2);
        for sum in sums.iter_mut() {
            let (mut same, mut other) = (s.load(&sum[parity]), s.load(&sum[opposite]));
            paired!(G, same, other, |i, acc| {
                let next = s.sub(s.mul(a[i], now[i]), s.mul(q[i], prev[i]));
                *acc = s.add(*acc, s.mul(w[i], next));
                (prev[i], now[i]) = (now[i], next);
            });
            s.store(&mut sum[parity], same);
            s.store(&mut sum[opposite], other);
        }
        for i in 0..G {
            s.store(&mut run.up[first + i], prev[i]);
            s.store(&mut run.un[first + i], now[i]);
        }
    }
    impl Kernel for FreeRun<'_> {
        type Output = ();
        #[inline(always)]
        fn run<L: Lanes>(self, s: L) {
            // The partial sums live on the stack, zeroed for the run's length: a run of one
            // sample (a one-sample control block) does not clear a whole run's worth.
            match self.outputs.len() {
                0..=1 => sweep::<L, 1>(s, self),
                2..=8 => sweep::<L, 8>(s, self),
                _ => sweep::<L, RUN>(s, self),
            }
        }
    }
    /// The run (at most `S` steps) with its partial sums in an array of `S`.
    #[inline(always)]
    fn sweep<L: Lanes, const S: usize>(s: L, mut run: FreeRun<'_>) {
        let mut sums = [[[0.0; LANES]; 2]; S];
        let sums = &mut sums[..run.outputs.len().min(S)];
        let n = run.up.len().min(run.un.len()).min(run.a.len()).min(run.b.len()).min(run.out.len());
        let mut first = 0;
        let whole = L::RESIDENT.clamp(1, 4);
        while first < n {
            let size = whole.min(n - first);
            match size {
                4 => group::<L, 4>(s, &mut run, first, sums),
                3 => group::<L, 3>(s, &mut run, first, sums),
                2 => group::<L, 2>(s, &mut run, first, sums),
                _ => group::<L, 1>(s, &mut run, first, sums),
            }
            first += size;
        }
        for (o, sum) in run.outputs.iter_mut().zip(sums.iter()) {
            *o = s.sum(s.add(s.load(&sum[0]), s.load(&sum[1])));
        }
    }
    // One length for every array: a short one would leave the modes past it unstepped.
    let n = up.len();
    debug_assert!([a.len(), b.len(), un.len(), out.len()].iter().all(|&m| m == n), "free_run: unequal lengths");
    isa.run(FreeRun { a: chunks(a), b: chunks(b), up: chunks_mut(up), un: chunks_mut(un), out: chunks(out), outputs })
}

/// `xᵀy` over whole chunks, summed lane by lane.
#[inline]
pub fn dot(isa: Isa, x: &[f64], y: &[f64]) -> f64 {
    struct Dot<'a> {
        x: &'a [Chunk],
        y: &'a [Chunk],
    }
    impl Kernel for Dot<'_> {
        type Output = f64;
        #[inline(always)]
        fn run<L: Lanes>(self, s: L) -> f64 {
            dot_chunks(s, self.x, self.y)
        }
    }
    isa.run(Dot { x: chunks(x), y: chunks(y) })
}

/// [`dot`]'s sum, for kernels already running on `L`.
#[inline(always)]
fn dot_chunks<L: Lanes>(s: L, x: &[Chunk], y: &[Chunk]) -> f64 {
    let n = x.len().min(y.len());
    let (x, y) = (&x[..n], &y[..n]);
    let (mut even, mut odd) = (s.splat(0.0), s.splat(0.0));
    paired!(n, even, odd, |c, acc| {
        *acc = s.add(*acc, s.mul(s.load(&x[c]), s.load(&y[c])));
    });
    s.sum(s.add(even, odd))
}

/// `(Σ (un − up)², Σ k (un + up)²)` over whole chunks, for the string's energy.
#[inline]
pub fn energy_sums(isa: Isa, up: &[f64], un: &[f64], k: &[f64]) -> (f64, f64) {
    struct EnergySums<'a> {
        up: &'a [Chunk],
        un: &'a [Chunk],
        k: &'a [Chunk],
    }
    impl Kernel for EnergySums<'_> {
        type Output = (f64, f64);
        #[inline(always)]
        fn run<L: Lanes>(self, s: L) -> (f64, f64) {
            let n = self.up.len().min(self.un.len()).min(self.k.len());
            let (up, un, k) = (&self.up[..n], &self.un[..n], &self.k[..n]);
            let zero = s.splat(0.0);
            let (mut even, mut odd) = ([zero; 2], [zero; 2]);
            paired!(n, even, odd, |c, acc| {
                let (p, q) = (s.load(&up[c]), s.load(&un[c]));
                let (step, sum) = (s.sub(q, p), s.add(q, p));
                acc[0] = s.add(acc[0], s.mul(step, step));
                acc[1] = s.add(acc[1], s.mul(s.load(&k[c]), s.mul(sum, sum)));
            });
            (s.sum(s.add(even[0], odd[0])), s.sum(s.add(even[1], odd[1])))
        }
    }
    isa.run(EnergySums { up: chunks(up), un: chunks(un), k: chunks(k) })
}

/// `(Σ m (un − up)², Σ k (un + up)²)` over the chunks `range`, for a bank's energy (modes of
/// their own masses `m` and stiffnesses `k`).
#[inline]
pub fn weighted_energy_sums(
    isa: Isa,
    up: &[f64],
    un: &[f64],
    m: &[f64],
    k: &[f64],
    range: std::ops::Range<usize>,
) -> (f64, f64) {
    struct WeightedEnergySums<'a> {
        up: &'a [Chunk],
        un: &'a [Chunk],
        m: &'a [Chunk],
        k: &'a [Chunk],
        range: std::ops::Range<usize>,
    }
    impl Kernel for WeightedEnergySums<'_> {
        type Output = (f64, f64);
        #[inline(always)]
        fn run<L: Lanes>(self, s: L) -> (f64, f64) {
            let n = self.up.len().min(self.un.len()).min(self.m.len()).min(self.k.len());
            let (up, un, m, k) = (&self.up[..n], &self.un[..n], &self.m[..n], &self.k[..n]);
            let zero = s.splat(0.0);
            let (mut even, mut odd) = ([zero; 2], [zero; 2]);
            paired!(@range self.range.start.min(n), self.range.end.min(n), fits = true, even, odd, |c, acc| {
                let (p, q) = (s.load(&up[c]), s.load(&un[c]));
                let (step, sum) = (s.sub(q, p), s.add(q, p));
                acc[0] = s.add(acc[0], s.mul(s.load(&m[c]), s.mul(step, step)));
                acc[1] = s.add(acc[1], s.mul(s.load(&k[c]), s.mul(sum, sum)));
            });
            (s.sum(s.add(even[0], odd[0])), s.sum(s.add(even[1], odd[1])))
        }
    }
    isa.run(WeightedEnergySums { up: chunks(up), un: chunks(un), m: chunks(m), k: chunks(k), range })
}

/// One contact vector of [`ModalString::gram`](super::ModalString::gram): `shape` is `h` (dimensionless) and `gain` is `C∘h` (m/N),
/// whole chunks each.
#[derive(Debug)]
pub struct GramVector<'a> {
    /// The vector `h` (dimensionless), whole chunks.
    pub shape: &'a mut [f64],
    /// `C∘h` (m/N), whole chunks.
    pub gain: &'a mut [f64],
    /// Per-mode window factors for a fresh vector (whole chunks, zero past M), or none.
    pub window: Option<&'a [f64]>,
    /// `Some((sin θ, cos θ))`: make the vector afresh, `h_i = sin((i+1)θ)` (the mode shapes of
    /// [`ModalString::mode_shapes`](super::ModalString::mode_shapes)) times the window if any, zero past the modes, and write `shape` and `gain`.
    /// `None`: `shape` and `gain` already hold the vector and are only read.
    pub fresh: Option<(f64, f64)>,
}

/// Make the fresh vectors and return their Gram matrix in the C metric, `θ_ab = h_aᵀ(C∘h_b)`
/// for `a ≤ b` (entries below the diagonal are zero), and the projections `(h_0ᵀup, h_0ᵀun)` of
/// the state on the first vector. `c` is zero past the `modes` modes. Each sum is the one [`dot`]
/// would give for the finished vectors.
///
/// One pass a vector makes it in registers (the rotation chain of [`sines`]), windows it, writes
/// it and its gain and sums `θ_aa`, so a fresh vector is never written bare and read back; a
/// last pass sums the cross terms and the state projections from the finished vectors. (One
/// pass for everything would need more registers than AVX has, as a two-vector chain alone takes
/// eight of its sixteen.)
#[inline]
pub fn gram<const K: usize>(
    isa: Isa,
    c: &[f64],
    up: &[f64],
    un: &[f64],
    modes: usize,
    vectors: [GramVector<'_>; K],
) -> ([[f64; K]; K], [f64; 2]) {
    struct Vector<'a> {
        shape: &'a mut [Chunk],
        gain: &'a mut [Chunk],
        window: Option<&'a [Chunk]>,
        fresh: Option<(f64, f64)>,
    }
    struct Gram<'a, const K: usize> {
        c: &'a [Chunk],
        up: &'a [Chunk],
        un: &'a [Chunk],
        modes: usize,
        vectors: [Vector<'a>; K],
    }
    /// `hᵀ(C∘h)` of one vector, made afresh (see [`make`]) or read.
    #[inline(always)]
    fn diagonal<L: Lanes>(s: L, c: &[Chunk], v: &mut Vector<'_>) -> f64 {
        let n = c.len();
        let (shape, gain) = (&mut v.shape[..n], &mut v.gain[..n]);
        match (v.fresh, v.window) {
            (None, _) => dot_chunks(s, shape, gain),
            // Two copies of the loop, with and without the window.
            (Some(angle), Some(w)) => make(s, c, shape, gain, Some(&w[..n]), angle),
            (Some(angle), None) => make(s, c, shape, gain, None, angle),
        }
    }
    /// Make a vector from the rotation chain at `angle`, times `window`, write it and its gain,
    /// and return `hᵀ(C∘h)`.
    #[inline(always)]
    fn make<L: Lanes>(
        s: L,
        c: &[Chunk],
        shape: &mut [Chunk],
        gain: &mut [Chunk],
        window: Option<&[Chunk]>,
        angle: (f64, f64),
    ) -> f64 {
        let n = c.len();
        let mut chain = Rotation::new(s, angle);
        let zero = s.splat(0.0);
        let (mut even, mut odd) = (zero, zero);
        paired!(n, even, odd, |i, acc| {
            let mut h = chain.next(s);
            if let Some(w) = window {
                h = s.mul(h, s.load(&w[i]));
            }
            s.store(&mut shape[i], h);
            let g = s.mul(s.load(&c[i]), h);
            s.store(&mut gain[i], g);
            *acc = s.add(*acc, s.mul(h, g));
        });
        s.sum(s.add(even, odd))
    }
    impl<const K: usize> Kernel for Gram<'_, K> {
        type Output = ([[f64; K]; K], [f64; 2]);
        #[inline(always)]
        fn run<L: Lanes>(self, s: L) -> Self::Output {
            let mut n = self.c.len().min(self.up.len()).min(self.un.len());
            for v in &self.vectors {
                n = n.min(v.shape.len()).min(v.gain.len());
                if let Some(w) = v.window {
                    n = n.min(w.len());
                }
            }
            let c = &self.c[..n];
            let mut vectors = self.vectors;
            let mut gram = [[0.0; K]; K];
            for (k, v) in vectors.iter_mut().enumerate() {
                gram[k][k] = diagonal(s, c, v);
                // Past the modes a fresh shape holds the rotation's values and its gain `0·h`
                // (`c` is zero there, so `θ_kk` did not see them): make both zero.
                if v.fresh.is_some() {
                    let m = self.modes.min(n * LANES);
                    v.shape.as_flattened_mut()[m..].fill(0.0);
                    v.gain.as_flattened_mut()[m..].fill(0.0);
                }
            }
            let zero = s.splat(0.0);
            // Accumulators: the K(K−1)/2 cross terms and the two state projections, twice;
            // temporaries: the K vectors.
            let (mut even, mut odd) = (([[zero; K]; K], [zero; 2]), ([[zero; K]; K], [zero; 2]));
            let states = [&self.up[..n], &self.un[..n]];
            paired!(n, fits = fits::<L>(K * K.saturating_sub(1) + 4 + K), even, odd, |i, acc| {
                for a in 0..K {
                    let h = s.load(&vectors[a].shape[i]);
                    for b in a + 1..K {
                        acc.0[a][b] = s.add(acc.0[a][b], s.mul(h, s.load(&vectors[b].gain[i])));
                    }
                    if a == 0 {
                        accumulate(s, &mut acc.1, &states, i, h);
                    }
                }
            });
            for a in 0..K {
                for b in a + 1..K {
                    gram[a][b] = s.sum(s.add(even.0[a][b], odd.0[a][b]));
                }
            }
            (gram, finish(s, even.1, odd.1))
        }
    }
    isa.run(Gram {
        c: chunks(c),
        up: chunks(up),
        un: chunks(un),
        modes,
        vectors: vectors.map(|v| Vector {
            shape: chunks_mut(v.shape),
            gain: chunks_mut(v.gain),
            window: v.window.map(chunks),
            fresh: v.fresh,
        }),
    })
}

/// The mode shapes' rotation chain, `sin((i+1)θ)` a chunk at a time: the first chunk by doubling
/// (lanes `[0, w)` rotated by `wθ` give lanes `[w, 2w)`, for w = 1, 2, 4), every later one the
/// chunk before rotated by `LANES·θ`:
///
/// ```text
/// sin((i+k)θ) = sin(iθ) cos kθ + cos(iθ) sin kθ,   cos((i+k)θ) = cos(iθ) cos kθ − sin(iθ) sin kθ
/// ```
///
/// A rotation is orthogonal, so each one adds a rounding error without amplifying earlier ones,
/// at every angle: after `M/LANES` chunks the error is a few `M/LANES · ε` (the three-term
/// recurrence `2cos φ·s_n − s_{n−1}` turns an error `ε` in `cos φ` into a phase error `√(2ε)`
/// when `φ` is near a multiple of π, which a stride of `LANES·θ` makes common). The chain costs a
/// rotation's latency a chunk: in [`gram`] a chunk's other work (window, gain, θ) hides it;
/// [`sines`] alone, which runs only when a pickup or a striking point moves, is bound by it.
struct Rotation<L: Lanes> {
    sin: L::V,
    cos: L::V,
    step: (L::V, L::V),
}

impl<L: Lanes> Rotation<L> {
    /// The chain for `(sin θ, cos θ)`, at its first chunk.
    #[inline(always)]
    fn new(s: L, (sin, cos): (f64, f64)) -> Self {
        /// `(sin(a + b), cos(a + b))` from `(sin a, cos a)` and `(sin b, cos b)`.
        #[inline(always)]
        fn rotate((sa, ca): (f64, f64), (sb, cb): (f64, f64)) -> (f64, f64) {
            (sa * cb + ca * sb, ca * cb - sa * sb)
        }
        let (mut first_sin, mut first_cos) = ([0.0; LANES], [0.0; LANES]);
        (first_sin[0], first_cos[0]) = (sin, cos);
        let mut width = 1;
        while width < LANES {
            let step = (first_sin[width - 1], first_cos[width - 1]);
            for l in 0..width {
                (first_sin[width + l], first_cos[width + l]) = rotate((first_sin[l], first_cos[l]), step);
            }
            width *= 2;
        }
        let step = (s.splat(first_sin[LANES - 1]), s.splat(first_cos[LANES - 1]));
        Self { sin: s.load(&first_sin), cos: s.load(&first_cos), step }
    }

    /// This chunk's sines; the chain moves on to the next chunk.
    #[inline(always)]
    fn next(&mut self, s: L) -> L::V {
        let (sn, cs, (sb, cb)) = (self.sin, self.cos, self.step);
        self.sin = s.add(s.mul(sn, cb), s.mul(cs, sb));
        self.cos = s.sub(s.mul(cs, cb), s.mul(sn, sb));
        sn
    }
}

/// `out_i = sin((i+1)θ)` for whole chunks, from `sin θ` and `cos θ`, by the rotation chain that
/// [`gram`] runs for a fresh vector (so the two give the same bits).
#[inline]
pub fn sines(isa: Isa, sin: f64, cos: f64, out: &mut [f64]) {
    struct Sines<'a> {
        angle: (f64, f64),
        out: &'a mut [Chunk],
    }
    impl Kernel for Sines<'_> {
        type Output = ();
        #[inline(always)]
        fn run<L: Lanes>(self, s: L) {
            let mut chain = Rotation::new(s, self.angle);
            for chunk in self.out {
                s.store(chunk, chain.next(s));
            }
        }
    }
    isa.run(Sines { angle: (sin, cos), out: chunks_mut(out) })
}

/// Pass 2 with the energy terms: as [`advance`], and also returns
/// `(Σ (u' − un)², Σ K̂ (u' + un)², Σ R̂ (u' − up)²)` with `u'` the new state. Not dispatched: it
/// serves the offline harness, which wants the energy, not the speed.
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
    let output = dot(Isa::Portable, &out[..n], up);
    (output, [lane_sum(sums[0]), lane_sum(sums[1]), lane_sum(sums[2])])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One step of [`free_run`]'s recursion, `up = a∘un − (b − 1)∘up`, in one pass over the modes
    /// (chunk after chunk, the even and the odd ones into two partial sums); returns `outᵀ up`. The
    /// reference the register-resident run is checked against.
    fn free(isa: Isa, a: &[f64], b: &[f64], up: &mut [f64], un: &[f64], out: &[f64]) -> f64 {
        struct Free<'a> {
            a: &'a [Chunk],
            b: &'a [Chunk],
            up: &'a mut [Chunk],
            un: &'a [Chunk],
            out: &'a [Chunk],
        }
        impl Kernel for Free<'_> {
            type Output = f64;
            #[inline(always)]
            fn run<L: Lanes>(self, s: L) -> f64 {
                let n = self.up.len();
                let (a, b, un, out) = (&self.a[..n], &self.b[..n], &self.un[..n], &self.out[..n]);
                let ups = self.up;
                let one = s.splat(1.0);
                let (mut even, mut odd) = (s.splat(0.0), s.splat(0.0));
                paired!(n, even, odd, |c, acc| {
                    let q = s.sub(s.load(&b[c]), one);
                    let next = s.sub(s.mul(s.load(&a[c]), s.load(&un[c])), s.mul(q, s.load(&ups[c])));
                    s.store(&mut ups[c], next);
                    *acc = s.add(*acc, s.mul(s.load(&out[c]), next));
                });
                s.sum(s.add(even, odd))
            }
        }
        isa.run(Free { a: chunks(a), b: chunks(b), up: chunks_mut(up), un: chunks(un), out: chunks(out) })
    }

    /// Deterministic values in (−1, 1) with varied exponents.
    fn data(n: usize, seed: u64) -> Vec<f64> {
        let mut x = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (0..n)
            .map(|_| {
                x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                let unit = (x >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0;
                unit * 10f64.powi((x % 7) as i32 - 3)
            })
            .collect()
    }

    /// Every instruction-set level compiled for this target, widest first. The `match` fails to
    /// compile when [`Isa`] gains a level, so that it is added here too.
    fn compiled_levels() -> Vec<Isa> {
        let levels = vec![
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512,
            #[cfg(target_arch = "x86_64")]
            Isa::Avx,
            Isa::Portable,
        ];
        for level in &levels {
            match level {
                #[cfg(target_arch = "x86_64")]
                Isa::Avx512 | Isa::Avx => {}
                Isa::Portable => {}
            }
        }
        levels
    }

    /// The kernels give the same bits on every compiled instruction-set level the CPU runs
    /// (AVX-512, AVX and portable on x86-64) as on the portable one, so a render does not depend
    /// on the machine. The levels the CPU lacks are printed as skipped.
    #[test]
    fn every_instruction_set_gives_the_same_bits() {
        let n = 7 * LANES;
        let [a, b, up0, un, v0, v1, g0, g1, out] = [0, 1, 2, 3, 4, 5, 6, 7, 8].map(|s| data(n, s));
        let run = |isa: Isa| {
            let (mut up, mut zt) = (up0.clone(), vec![0.0; n]);
            let h = history(isa, &a, &b, &up, &un, &mut zt, [&v0, &v1]);
            let (o, p) = advance(isa, &a, &b, &mut up, &un, &mut zt, [(&g0, 0.3), (&g1, -1.7)], &out, [&v0, &v1]);
            let mut free_up = up0.clone();
            let f = free(isa, &a, &b, &mut free_up, &un, &out);
            let mut shapes = vec![0.0; n];
            sines(isa, 0.3f64.sin(), 0.3f64.cos(), &mut shapes);
            let d = dot(isa, &v0, &v1);
            (h, o, up, zt, p, f, free_up, shapes, d)
        };
        let reference = run(Isa::Portable);
        let available = Isa::available();
        let (levels, skipped): (Vec<Isa>, Vec<Isa>) =
            compiled_levels().into_iter().partition(|level| available.contains(level));
        println!("instruction-set levels compared: {levels:?}; skipped, not on this CPU: {skipped:?}");
        assert!(levels.contains(&Isa::Portable), "the portable level always runs");
        for isa in levels {
            let got = run(isa);
            assert_eq!(format!("{got:?}"), format!("{reference:?}"), "{isa:?}");
        }
    }

    /// A free step is the full step with no force, up to rounding: per mode, both round a few
    /// terms no larger than `|a·un| + |b·up|`, so they differ by at most a few ulps of that
    /// (4ε allowed). Coefficients as a real string's: `a = 2P`, `b = 1 + Q`, `P = e^{−σΔt}cos ωΔt`,
    /// `Q = e^{−2σΔt}`; the last chunk is padding (`a = b = 0`) and must stay exactly zero.
    #[test]
    fn free_step_is_history_then_advance_without_forces() {
        let n = 3 * LANES;
        let [decay, phase, up0, un, out] = [10, 11, 12, 13, 14].map(|s| data(n, s));
        let modes = n - LANES;
        let r: Vec<f64> = (0..n).map(|i| if i < modes { (-decay[i].abs()).exp() } else { 0.0 }).collect();
        let a: Vec<f64> = (0..n).map(|i| if i < modes { 2.0 * r[i] * (3.0 * phase[i]).cos() } else { 0.0 }).collect();
        let b: Vec<f64> = (0..n).map(|i| if i < modes { 1.0 + r[i] * r[i] } else { 0.0 }).collect();
        let (mut up0, mut un) = (up0, un);
        up0[modes..].fill(0.0);
        un[modes..].fill(0.0);
        for isa in Isa::available() {
            let (mut up, mut zt) = (up0.clone(), vec![0.0; n]);
            history::<0>(isa, &a, &b, &up, &un, &mut zt, []);
            let (o, []) = advance::<0, 0>(isa, &a, &b, &mut up, &un, &mut zt, [], &out, []);
            let mut free_up = up0.clone();
            let f = free(isa, &a, &b, &mut free_up, &un, &out);
            let mut scale = 0.0;
            for i in 0..n {
                let bound = 4.0 * f64::EPSILON * ((a[i] * un[i]).abs() + (b[i] * up0[i]).abs());
                assert!((up[i] - free_up[i]).abs() <= bound, "{isa:?}, mode {i}: {} vs {}", up[i], free_up[i]);
                scale += (out[i] * bound).abs();
            }
            assert_eq!(free_up[modes..], up[modes..], "{isa:?}: padding stays zero");
            assert!((o - f).abs() <= 2.0 * scale, "{isa:?}: output {o} vs {f}");
        }
    }

    /// The next step's `z̃` that `advance` leaves behind, and its projections (made in the same
    /// pass or after it), are those of a separate first pass.
    /// A bank split into a head and a tail, each with its own forces and vectors (zero on the
    /// other part), steps exactly as the whole bank with every vector: the same state, `zt`,
    /// output and projections, bit for bit, with the tail starting inside a chunk, on a chunk's
    /// edge, at the first mode and past the last, on every instruction set. (With two
    /// accumulator sets or, on AVX, the two sweeps that [`paired!`] falls back to.)
    #[test]
    fn a_split_advance_is_the_whole_advance() {
        let n = 7 * LANES;
        for start in [0, 13, 16, 29, 40, n] {
            let [a, b, up0, un, zt0, out] = [40, 41, 42, 43, 44, 45].map(|s| data(n, s));
            let head = |v: Vec<f64>| -> Vec<f64> {
                v.iter().enumerate().map(|(i, x)| if i < start { *x } else { 0.0 }).collect()
            };
            let tail = |v: Vec<f64>| -> Vec<f64> {
                v.iter().enumerate().map(|(i, x)| if i >= start { *x } else { 0.0 }).collect()
            };
            let out = head(out);
            let [h0, h1] = [46, 47].map(|s| head(data(n, s)));
            let [g0, g1] = [48, 49].map(|s| head(data(n, s)));
            let [t0, r0] = [50, 51].map(|s| tail(data(n, s)));
            for isa in Isa::available() {
                let (mut up, mut zt) = (up0.clone(), zt0.clone());
                let forces = [(&g0[..], 0.3), (&g1[..], -1.7), (&r0[..], 2.9)];
                let (o, p) = advance(isa, &a, &b, &mut up, &un, &mut zt, forces, &out, [&h0, &h1, &t0]);
                let (mut up_s, mut zt_s) = (up0.clone(), zt0.clone());
                let rest = Tail { start, forces: [(&r0[..], 2.9)], next: [&t0[..]] };
                let head_forces = [(&g0[..], 0.3), (&g1[..], -1.7)];
                let (o_s, [p0, p1], [p2]) =
                    advance_split(isa, &a, &b, &mut up_s, &un, &mut zt_s, head_forces, &out, [&h0, &h1], rest);
                let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&up_s), bits(&up), "{isa:?}, tail from {start}");
                assert_eq!(bits(&zt_s), bits(&zt), "{isa:?}, tail from {start}");
                assert_eq!(o_s.to_bits(), o.to_bits(), "{isa:?}, tail from {start}");
                assert_eq!([p0, p1, p2].map(f64::to_bits), p.map(f64::to_bits), "{isa:?}, tail from {start}");
            }
        }
    }

    #[test]
    fn advance_leaves_the_next_history() {
        for chunks in [1, 5, 6] {
            let n = chunks * LANES;
            let [a, b, up0, un, v0, v1, g0] = [30, 31, 32, 33, 34, 35, 36].map(|s| data(n, s));
            for isa in Isa::available() {
                let (mut up, mut zt) = (up0.clone(), vec![0.0; n]);
                history(isa, &a, &b, &up, &un, &mut zt, [&v0]);
                let (_, fused) = advance(isa, &a, &b, &mut up, &un, &mut zt, [(&g0, 0.7)], &data(n, 37), [&v1, &v0]);
                let after = projections(isa, &zt, [&v0, &v1]);
                // The state moves on: ũ^n becomes ũ^{n−1}, the new state ũ^{n+1}.
                let mut want_zt = vec![0.0; n];
                let want = history(isa, &a, &b, &un, &up, &mut want_zt, [&v0, &v1]);
                assert_eq!(zt, want_zt, "{isa:?}");
                assert_eq!(after.map(f64::to_bits), want.map(f64::to_bits), "{isa:?}");
                assert_eq!([fused[1], fused[0]].map(f64::to_bits), want.map(f64::to_bits), "{isa:?}, {chunks} chunks");
            }
        }
    }

    /// `gram` makes fresh vectors as `sines` and a window would, and gives the sums that `dot`
    /// gives for the finished vectors, bit for bit, on every instruction set (AVX-512 keeps both
    /// sets of cross-term accumulators in registers; AVX and the portable lanes sweep the even and
    /// odd chunks). Past the modes (where `c` is zero) fresh shapes and gains are zero.
    #[test]
    fn gram_is_the_separate_passes() {
        let cases =
            [1, 5, 6].into_iter().flat_map(|chunks| Isa::available().into_iter().map(move |i| (chunks * LANES, i)));
        for (n, isa) in cases {
            let modes = n - 3;
            let [mut c, up, un, kept, kept_gain, mut window] = [40, 41, 42, 45, 46, 47].map(|s| data(n, s));
            c[modes..].fill(0.0);
            window[modes..].fill(0.0);
            let angles = [0.3f64, 2.1].map(f64::sin_cos);
            let (mut s0, mut s1, mut s2) = (data(n, 43), data(n, 44), kept.clone());
            let (mut g0, mut g1, mut g2) = (data(n, 48), data(n, 49), kept_gain.clone());
            let (t, state) = gram(
                isa,
                &c,
                &up,
                &un,
                modes,
                [
                    GramVector { shape: &mut s0, gain: &mut g0, window: None, fresh: Some(angles[0]) },
                    GramVector { shape: &mut s1, gain: &mut g1, window: Some(&window), fresh: Some(angles[1]) },
                    GramVector { shape: &mut s2, gain: &mut g2, window: Some(&window), fresh: None },
                ],
            );
            let bare = angles.map(|(sin, cos)| {
                let mut out = vec![0.0; n];
                sines(isa, sin, cos, &mut out);
                out[modes..].fill(0.0);
                out
            });
            let w1: Vec<f64> = bare[1].iter().zip(&window).map(|(h, w)| h * w).collect();
            let shapes = [bare[0].clone(), w1, kept.clone()];
            let gains: Vec<Vec<f64>> = vec![
                c.iter().zip(&shapes[0]).map(|(c, h)| c * h).collect(),
                c.iter().zip(&shapes[1]).map(|(c, h)| c * h).collect(),
                kept_gain.clone(),
            ];
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!([&s0, &s1, &s2].map(|v| bits(v)), [0, 1, 2].map(|k| bits(&shapes[k])), "{isa:?}");
            assert_eq!([&g0, &g1].map(|v| bits(&v[modes..])), [vec![0; n - modes], vec![0; n - modes]], "{isa:?}");
            assert_eq!([&g0, &g1, &g2], [&gains[0], &gains[1], &gains[2]], "{isa:?}");
            for a in 0..3 {
                for b in a..3 {
                    assert_eq!(
                        t[a][b].to_bits(),
                        dot(isa, &shapes[a], &gains[b]).to_bits(),
                        "{isa:?} {n}: θ[{a}][{b}]"
                    );
                }
            }
            assert_eq!(state[0].to_bits(), dot(isa, &up, &shapes[0]).to_bits(), "{isa:?}");
            assert_eq!(state[1].to_bits(), dot(isa, &un, &shapes[0]).to_bits(), "{isa:?}");
        }
    }

    /// Runs of 1, 5 and 37 steps (each size of partial-sum array) are the free steps one by one.
    #[test]
    fn free_run_is_repeated_free_steps() {
        for (chunks, steps) in [1, 3, 4, 7, 9].into_iter().flat_map(|c| [1, 5, 37].map(|s| (c, s))) {
            let n = chunks * LANES;
            let [a, b, up0, un0, out] = [20, 21, 22, 23, 24].map(|s| data(n, s));
            for isa in Isa::available() {
                let (mut up, mut un) = (up0.clone(), un0.clone());
                let mut want = vec![0.0; steps];
                for w in &mut want {
                    *w = free(isa, &a, &b, &mut up, &un, &out);
                    std::mem::swap(&mut up, &mut un);
                }
                let (mut run_up, mut run_un) = (up0.clone(), un0.clone());
                let mut got = vec![0.0; steps];
                free_run(isa, &a, &b, &mut run_up, &mut run_un, &out, &mut got);
                assert_eq!(got, want, "{isa:?}, {chunks} chunks, {steps} steps");
                assert_eq!((run_up, run_un), (up, un), "{isa:?}, {chunks} chunks, {steps} steps");
            }
        }
    }

    #[test]
    fn strided_sines_match_the_sine() {
        let pi = std::f64::consts::PI;
        for theta in [1e-4, 0.05, 0.3, 1.0, 1.57, 2.9, pi / 8.0, pi / 4.0, pi / 2.0, 3.0 * pi / 8.0, pi - 1e-4] {
            let mut out = vec![0.0; 512];
            sines(Isa::detect(), f64::sin(theta), f64::cos(theta), &mut out);
            for (i, &got) in out.iter().enumerate() {
                let want = ((i + 1) as f64 * theta).sin();
                assert!((got - want).abs() < 1e-11, "θ = {theta}, i = {i}: {got} vs {want}");
            }
        }
    }
}
