//! QSA: the non-iterative branched solve on the spline potential (seed §4.2, docs/physics.md §3).
//!
//! With the discrete-gradient force `F^n = −(V̂(y^{n−1}+s) − V̂(y^{n−1}))/s` (seed eq. 22) the
//! scalar problem becomes
//!
//! ```text
//! G(s) = s + z + q·(V̂(yp + s) − V̂(yp))/s = 0,     yp = y^{n−1}          (seed eq. 24)
//! ```
//!
//! (G is the whole left-hand side; the seed's underbrace covers only the fraction). V̂ is convex,
//! so `G' ≥ 1`: G is strictly increasing with exactly one root. Once the segment `p` that holds
//! `y^{n+1}` is known, `λ(s) = s·G(s)` is a quadratic (seed Table 1):
//!
//! ```text
//! a_λ = 1 + q·A_p,   b_λ = z + q·V_p'(yp),   c_λ = q·(V_p(yp) − V̂(yp))
//! ```
//!
//! # Segment search (seed eq. 26, docs/physics.md §3.2)
//!
//! At the knot offsets `s_j = y_j − yp` the sign of G needs no division:
//! `λ_j = s_j(s_j + z) + q(V(y_j) − V̂(yp))` and `sign G(s_j) = sign λ_j · sign s_j`
//! (`sign G(0) = sign g0` with `g0 = G(0) = z + q·V̂'(yp)`). G(s_j) increases with j, so
//! `p = #{j < N : G(s_j) < 0}`. Instead of the seed's linear scan this solver uses
//! - a free-flight fast path: `yp ≤ 0` and `yp − z ≤ 0` ⇒ `p = 0`, `s = −z`, no sign test;
//! - a warm start: test the previous step's segment first, gallop outwards (±1, ±2, ±4, …) and
//!   finish with a binary search.
//!
//! A sign test that lands exactly on the root (`λ_j = 0`) ends the search with `s = s_j`.
//!
//! # Root without cancellation (docs/physics.md §3.3–3.5)
//!
//! With `k = seg(yp)`: if `p = k` then `c_λ = 0`, `b_λ = g0` and `s = −g0/a_λ`, a perfectly
//! conditioned root. Otherwise the quadratic is re-centred on the knot `y_m` between `y^{n−1}` and
//! `y^{n+1}` (`m = p−1` if `p > k`, `m = p` if `p < k`), with `e = yp − y_m` and
//! `t = y^{n+1} − y_m`:
//!
//! ```text
//! (1 + q·A_p)·t² + (z − 2e + q·D_m)·t + (e² − z·e + q·(V(y_m) − V̂(yp))) = 0,   s = t − e
//! ```
//!
//! The wanted root is where G crosses zero upwards: the larger root if `g0 < 0` (`s* > 0`), the
//! smaller if `g0 > 0`, each taken in the form that avoids cancellation
//! (`(−b ± √d)/(2a)` or `2c/(−b ∓ √d)`). Re-centring keeps about 2.5 more digits at extreme
//! stiffness (docs/physics.md §3.5) and makes the root's cost independent of `|p − k|`.
//!
//! # Cost bound
//!
//! Per step, with ⌈·⌉ = ⌈log2(N+1)⌉: free flight costs no sign test; the warm-started search costs
//! at most `2⌈·⌉ + 1` sign tests (1 for the guess, at most ⌈·⌉ galloping, at most ⌈·⌉ − 1 in the
//! final bisection) and at most 2 when the segment is unchanged; the plain binary search costs at
//! most ⌈·⌉. The root then costs one square root. Nothing else depends on the data.

use super::{ContactProblem, ContactSolution, ContactSolver, Method, QuadSpline};

/// How the QSA solver finds the segment of `y^{n+1}`. All three give bit-identical results.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SegmentSearch {
    /// The seed's scan over knots `j = 0, 1, …` (kept as the obviously-correct reference).
    Linear,
    /// Binary search over all N segments: ⌈log2(N+1)⌉ sign tests.
    Binary,
    /// Previous segment first, then galloping, then binary search.
    #[default]
    WarmStart,
}

/// The QSA solver (seed §4.2).
#[derive(Debug, Clone)]
pub struct QsaSolver {
    spline: QuadSpline,
    search: SegmentSearch,
    last_segment: usize,
    last_tests: u32,
}

impl QsaSolver {
    /// A solver on `spline` using the warm-started search.
    pub fn new(spline: QuadSpline) -> Self {
        Self::with_search(spline, SegmentSearch::WarmStart)
    }

    /// A solver on `spline` with the given search strategy.
    pub fn with_search(spline: QuadSpline, search: SegmentSearch) -> Self {
        Self { spline, search, last_segment: 0, last_tests: 0 }
    }

    /// The spline this solver works on.
    pub fn spline(&self) -> &QuadSpline {
        &self.spline
    }

    /// The spline, to refit in place (for example for a new strike's reference energy).
    pub fn spline_mut(&mut self) -> &mut QuadSpline {
        &mut self.spline
    }

    /// The segment that held `y^{n+1}` in the last step (0 = no contact).
    pub fn last_segment(&self) -> usize {
        self.last_segment
    }

    /// Upper bound on sign tests per step for this N and search (see the module docs).
    pub fn max_sign_tests(&self) -> u32 {
        let log = usize::BITS - self.spline.segments().leading_zeros(); // ⌈log2(N+1)⌉
        match self.search {
            SegmentSearch::Linear => self.spline.segments() as u32,
            SegmentSearch::Binary => log,
            SegmentSearch::WarmStart => 2 * log + 1,
        }
    }

    fn root_in_segment(&self, p: usize, st: &StepData) -> f64 {
        let sp = &self.spline;
        let a = 1.0 + st.q * sp.curvature(p);
        if p == st.k {
            return -st.g0 / a;
        }
        let m = if p > st.k { p - 1 } else { p };
        let e = st.yp - sp.knot(m);
        let b = st.z - 2.0 * e + st.q * sp.knot_slope(m);
        let c = e * e - st.z * e + st.q * knot_rise(sp, m, st);
        let t = if st.g0 < 0.0 { larger_root(a, b, c) } else { smaller_root(a, b, c) };
        t - e
    }
}

/// Quantities of one step that do not depend on the candidate segment.
#[derive(Debug, Clone, Copy)]
struct StepData {
    yp: f64,
    z: f64,
    q: f64,
    /// `seg(yp)`.
    k: usize,
    /// `V̂(yp)` (J).
    v_yp: f64,
    /// `G(0) = z + q·V̂'(yp)` (m).
    g0: f64,
}

/// The sign of `G(s_j)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Sign {
    Below,
    Root,
    Above,
}

/// Segment search over the sign sequence `G(s_0) < … < G(s_{N−1})`, counting tests.
struct Search<'a> {
    spline: &'a QuadSpline,
    st: &'a StepData,
    tests: u32,
}

/// Where the search ended: the segment, and whether `y^{n+1}` sits exactly on knot `p`.
type Located = (usize, bool);

impl Search<'_> {
    #[inline(always)]
    fn sign(&mut self, j: usize) -> Sign {
        self.tests += 1;
        let st = self.st;
        let s = self.spline.knot(j) - st.yp;
        if s == 0.0 {
            return if st.g0 < 0.0 { Sign::Below } else { Sign::Above };
        }
        let lambda = s * (s + st.z) + st.q * knot_rise(self.spline, j, st);
        if lambda == 0.0 {
            Sign::Root
        } else if (lambda < 0.0) != (s < 0.0) {
            Sign::Below
        } else {
            Sign::Above
        }
    }

    fn linear(&mut self) -> Located {
        let n = self.spline.segments();
        for j in 0..n {
            match self.sign(j) {
                Sign::Below => {}
                Sign::Above => return (j, false),
                Sign::Root => return (j, true),
            }
        }
        (n, false)
    }

    /// First non-negative sign in `[lo, hi]`, given `G(s_{lo−1}) < 0` and `G(s_hi) ≥ 0`
    /// (or `hi = N`).
    fn bisect(&mut self, mut lo: usize, mut hi: usize) -> Located {
        while lo < hi {
            let mid = lo + (hi - lo) / 2;
            match self.sign(mid) {
                Sign::Below => lo = mid + 1,
                Sign::Above => hi = mid,
                Sign::Root => return (mid, true),
            }
        }
        (lo, false)
    }

    fn warm(&mut self, guess: usize) -> Located {
        let n = self.spline.segments();
        let mut hi = n;
        if guess < n {
            match self.sign(guess) {
                Sign::Root => return (guess, true),
                Sign::Above => hi = guess,
                Sign::Below => {
                    // Gallop up: G(s_{lo−1}) < 0 is known.
                    let mut lo = guess + 1;
                    let mut step = 1;
                    while lo < n {
                        let j = (lo + step - 1).min(n - 1);
                        match self.sign(j) {
                            Sign::Below => lo = j + 1,
                            Sign::Above => return self.bisect(lo, j),
                            Sign::Root => return (j, true),
                        }
                        step *= 2;
                    }
                    return (n, false);
                }
            }
        }
        // Gallop down: G(s_hi) ≥ 0 (or hi = N) is known.
        let mut step = 1;
        while hi > 0 {
            let j = hi.saturating_sub(step);
            match self.sign(j) {
                Sign::Above => hi = j,
                Sign::Below => return self.bisect(j + 1, hi),
                Sign::Root => return (j, true),
            }
            step *= 2;
        }
        (0, false)
    }
}

impl ContactSolver for QsaSolver {
    const METHOD: Method = Method::Qsa;

    fn start(&mut self, _y_prev: f64, y_now: f64) {
        self.last_segment = self.spline.segment_of(y_now);
        self.last_tests = 0;
    }

    fn solve(&mut self, problem: &ContactProblem) -> ContactSolution {
        let ContactProblem { y_prev: yp, z, q, .. } = *problem;
        if yp <= 0.0 && yp - z <= 0.0 {
            // Free flight: no contact at n−1 nor at n+1.
            self.last_segment = 0;
            self.last_tests = 0;
            return ContactSolution { s: -z, force: 0.0 };
        }
        let sp = &self.spline;
        let k = sp.segment_of(yp);
        let st = StepData { yp, z, q, k, v_yp: sp.segment_potential(k, yp), g0: z + q * sp.segment_slope(k, yp) };
        if st.g0 == 0.0 {
            self.last_segment = k;
            self.last_tests = 0;
            return ContactSolution::from_increment(0.0, problem);
        }
        let mut search = Search { spline: sp, st: &st, tests: 0 };
        let (p, on_knot) = match self.search {
            SegmentSearch::Linear => search.linear(),
            SegmentSearch::Binary => search.bisect(0, sp.segments()),
            SegmentSearch::WarmStart => search.warm(self.last_segment.min(sp.segments())),
        };
        let tests = search.tests;
        let s = if on_knot { sp.knot(p) - yp } else { self.root_in_segment(p, &st) };
        self.last_segment = p;
        self.last_tests = tests;
        ContactSolution::from_increment(s, problem)
    }

    fn stored_energy(&self, y_next: f64, y_now: f64) -> f64 {
        0.5 * (self.spline.potential(y_next) + self.spline.potential(y_now))
    }

    fn last_work(&self) -> u32 {
        self.last_tests
    }

    fn segments(&self) -> usize {
        self.spline.segments()
    }
}

/// `V(y_j) − V̂(yp)` (J). At the two knots that bound `yp`'s own segment `k` (`j = k − 1, k`) it
/// is that segment's quadratic, `s_j(D_j − A_k s_j)` with `s_j = y_j − yp`: near a knot the two
/// potentials are nearly equal and their difference loses every digit, which could give a sign
/// test the wrong sign and the root the wrong segment (docs/physics.md §3.5).
#[inline]
fn knot_rise(spline: &QuadSpline, j: usize, st: &StepData) -> f64 {
    if st.k >= 1 && (j + 1 == st.k || j == st.k) {
        let s = spline.knot(j) - st.yp;
        s * (spline.knot_slope(j) - spline.curvature(st.k) * s)
    } else {
        spline.knot_potential(j) - st.v_yp
    }
}

/// The larger root of `a x² + b x + c` (a > 0), without cancellation; `b² − 4ac` is clamped at 0
/// (a negative discriminant can only come from rounding here).
#[inline]
fn larger_root(a: f64, b: f64, c: f64) -> f64 {
    let sq = (b * b - 4.0 * a * c).max(0.0).sqrt();
    if b <= 0.0 { (-b + sq) / (2.0 * a) } else { 2.0 * c / (-b - sq) }
}

/// The smaller root of `a x² + b x + c` (a > 0), without cancellation.
#[inline]
fn smaller_root(a: f64, b: f64, c: f64) -> f64 {
    let sq = (b * b - 4.0 * a * c).max(0.0).sqrt();
    if b >= 0.0 { (-b - sq) / (2.0 * a) } else { 2.0 * c / (-b + sq) }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::PowerLaw;

    #[test]
    fn stable_roots_match_the_textbook_formula() {
        for &(a, b, c) in &[(2.0_f64, -3.0_f64, -5.0_f64), (1.0, 5.0, 6.0), (3.0, 1e8, -1.0), (1.0, -1e8, 1.0)] {
            let d = (b * b - 4.0 * a * c).sqrt();
            let (lo, hi) = ((-b - d) / (2.0 * a), (-b + d) / (2.0 * a));
            let (l, h) = (smaller_root(a, b, c), larger_root(a, b, c));
            // Each must be an accurate root: check the residual relative to the terms.
            for x in [l, h] {
                let r = a * x * x + b * x + c;
                let scale = (a * x * x).abs() + (b * x).abs() + c.abs();
                assert!(r.abs() <= 1e-14 * scale, "residual {r} for root {x} of ({a},{b},{c})");
            }
            assert!(l <= h);
            // Both roots, the small one included where the textbook formula cancels: Vieta's
            // product and sum, and the textbook root where it does not cancel (the larger one).
            assert!((l * h - c / a).abs() <= 1e-14 * (c / a).abs(), "product of ({a},{b},{c})");
            assert!((l + h + b / a).abs() <= 1e-14 * (b / a).abs().max(h.abs()), "sum of ({a},{b},{c})");
            let (far, textbook) = if b > 0.0 { (l, lo) } else { (h, hi) };
            assert!((far - textbook).abs() <= 1e-14 * textbook.abs(), "larger root of ({a},{b},{c})");
        }
    }

    /// `y^{n−1}` an ulp or a few past a knot: the sign tests at the two knots around it must not
    /// difference two nearly equal potentials (every digit lost, the sign noise). Every search
    /// then finds the segment `y^{n+1}` lands in, and all three give the same bits, for
    /// `y^{n−1}` from 3 ulps below to 3 above each interior knot, on a C4-like felt.
    #[test]
    fn a_step_from_next_to_a_knot_finds_the_segment_it_lands_in() {
        let law = PowerLaw::new(4.5e9, 2.5).unwrap();
        let spline = QuadSpline::new(law, 8e-4, 6).unwrap();
        let (q, z) = (1.7312762516664185e-7, -5.040192616168495e-6);
        let mut cases = 0;
        for j in 1..spline.segments() {
            let mut yp = spline.knot(j);
            for _ in 0..3 {
                yp = yp.next_down();
            }
            for _ in 0..7 {
                let problem = ContactProblem { y_prev: yp, y_now: yp, z, q };
                let mut found = Vec::new();
                for search in [SegmentSearch::Linear, SegmentSearch::Binary, SegmentSearch::WarmStart] {
                    let mut qsa = QsaSolver::with_search(spline.clone(), search);
                    qsa.start(yp, yp);
                    let s = qsa.solve(&problem).s;
                    let landed = spline.segment_of(yp + s);
                    // A root on a knot belongs to either segment.
                    let on_knot = (yp + s) == spline.knot(landed) || (yp + s) == spline.knot(landed.saturating_sub(1));
                    assert!(
                        qsa.last_segment() == landed || on_knot,
                        "{search:?}, knot {j}, yp {yp:e}: segment {} but y lands in {landed}",
                        qsa.last_segment()
                    );
                    found.push(s.to_bits());
                }
                assert!(found.windows(2).all(|w| w[0] == w[1]), "knot {j}, yp {yp:e}: the searches differ");
                yp = yp.next_up();
                cases += 1;
            }
        }
        assert_eq!(cases, 35);
    }

    #[test]
    fn warm_start_costs_two_tests_when_the_segment_is_unchanged() {
        let law = PowerLaw::new(1e8, 1.3).unwrap();
        let spline = QuadSpline::new(law, 1e-4, 20).unwrap();
        let mut qsa = QsaSolver::new(spline.clone());
        // Deep in segment 11, moving slowly: y^{n+1} stays in segment 11.
        let yp = 10.5 * spline.knot_spacing();
        let problem = ContactProblem { y_prev: yp, y_now: yp, z: 1e-9, q: 1e-12 };
        qsa.start(yp, yp);
        qsa.solve(&problem);
        assert_eq!(qsa.last_segment(), 11);
        qsa.solve(&problem);
        assert_eq!(qsa.last_work(), 2);
    }
}
