//! Control inputs and their block-wise linear interpolation (seed §6.7).
//!
//! Hosts and scene files give control values at any rate. The engine samples them only at block
//! boundaries `n = k·N_b` and interpolates linearly inside each block of `N_b` samples, so the
//! output never depends on how a host splits its buffers. The expensive quantities that depend on
//! positions (mode-shape vectors, their Gram matrix, `q`) are recomputed once per block, from the
//! values at the block's start.
//!
//! Whether a scene's controls can change at all is a property of the source's *type*
//! ([`ControlSource::VARYING`]): a scene driven by [`Fixed`] controls never recomputes anything,
//! and the check compiles away.

/// Piecewise-linear automation: `(time (s), value)` breakpoints, held constant before the first
/// and after the last point.
#[derive(Debug, Clone, PartialEq)]
pub struct Breakpoints {
    points: Vec<(f64, f64)>,
}

/// Why a breakpoint list is invalid.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BreakpointError {
    /// No points at all.
    #[error("needs at least one [time, value] point")]
    Empty,
    /// A time or value is NaN or infinite, or a time is negative.
    #[error("point {index} is not finite, or has a negative time")]
    NotFinite {
        /// Index of the point.
        index: usize,
    },
    /// Times must strictly increase.
    #[error("point {index}: times must strictly increase ({previous} then {time})")]
    NotIncreasing {
        /// Index of the point.
        index: usize,
        /// The previous time (s).
        previous: f64,
        /// This time (s).
        time: f64,
    },
}

impl Breakpoints {
    /// Validate and wrap `(time, value)` points.
    pub fn new(points: Vec<(f64, f64)>) -> Result<Self, BreakpointError> {
        if points.is_empty() {
            return Err(BreakpointError::Empty);
        }
        for (index, &(t, v)) in points.iter().enumerate() {
            if !(t.is_finite() && v.is_finite() && t >= 0.0) {
                return Err(BreakpointError::NotFinite { index });
            }
            if index > 0 && t <= points[index - 1].0 {
                return Err(BreakpointError::NotIncreasing { index, previous: points[index - 1].0, time: t });
            }
        }
        Ok(Self { points })
    }

    /// A single constant value.
    pub fn constant(value: f64) -> Self {
        Self { points: vec![(0.0, value)] }
    }

    /// The points.
    pub fn points(&self) -> &[(f64, f64)] {
        &self.points
    }

    /// Smallest and largest value.
    pub fn range(&self) -> (f64, f64) {
        self.points.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &(_, v)| (lo.min(v), hi.max(v)))
    }

    /// Value at time `t` (s).
    pub fn at(&self, t: f64) -> f64 {
        self.interpolate(t, self.points.partition_point(|&(tp, _)| tp <= t))
    }

    /// [`at`](Self::at) for non-decreasing times: `cursor` (start it at 0) remembers the segment,
    /// so a sweep through all the points costs one comparison per call. Any `t` gives the same
    /// value as [`at`](Self::at); going back in time only costs a search from the start.
    pub fn at_cursor(&self, t: f64, cursor: &mut usize) -> f64 {
        let p = &self.points;
        if *cursor > p.len() || (*cursor > 0 && p[*cursor - 1].0 > t) {
            *cursor = 0;
        }
        while *cursor < p.len() && p[*cursor].0 <= t {
            *cursor += 1;
        }
        self.interpolate(t, *cursor)
    }

    /// The value at `t` with `i` the number of points at or before `t`.
    fn interpolate(&self, t: f64, i: usize) -> f64 {
        let p = &self.points;
        if i == 0 {
            return p[0].1;
        }
        if i == p.len() {
            return p[i - 1].1;
        }
        let ((t0, v0), (t1, v1)) = (p[i - 1], p[i]);
        if v0 == v1 {
            // What the line below gives for a flat segment (`t0 ≤ t`), without its division.
            return v0 + 0.0;
        }
        v0 + (v1 - v0) * (t - t0) / (t1 - t0)
    }
}

/// A source of control values of type `T`, sampled at block boundaries.
pub trait ControlSource<T> {
    /// Whether the values can change over time. When `false`, scenes never recompute the
    /// quantities that depend on them.
    const VARYING: bool;

    /// The values at sample `n`. Called with non-decreasing `n`.
    fn at(&mut self, n: u64) -> T;
}

/// Controls that never change.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fixed<T>(pub T);

impl<T: Copy> ControlSource<T> for Fixed<T> {
    const VARYING: bool = false;

    fn at(&mut self, _n: u64) -> T {
        self.0
    }
}

/// Controls that something outside sets before each block (an instrument voice): the value
/// held when a block starts is that block's target, reached at its end.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Live<T>(pub T);

impl<T: Copy> ControlSource<T> for Live<T> {
    const VARYING: bool = true;

    fn at(&mut self, _n: u64) -> T {
        self.0
    }
}

/// A linear ramp across one block: value `start + slope·k` at sample `k` of the block.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Ramp {
    start: f64,
    slope: f64,
}

impl Ramp {
    /// A ramp from `from` (at the block's first sample) to `to` (at the next block's first
    /// sample) over `len` samples.
    #[inline]
    pub fn new(from: f64, to: f64, len: usize) -> Self {
        // A one-sample block (N_b = 1, every sample) needs no division: `x / 1 = x` exactly.
        let rise = to - from;
        Self { start: from, slope: if len == 1 { rise } else { rise / len as f64 } }
    }

    /// Value at sample `k` of the block (`k = len` gives the end value).
    #[inline]
    pub fn at(&self, k: usize) -> f64 {
        self.start + self.slope * k as f64
    }
}

/// A parabola across a span, from `from` to `to`, passing `sag` below the straight line between
/// them halfway along: `from + (to − from)·a − 4·sag·a(1 − a)` a fraction `a` of the way.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Bow {
    /// Value at the span's start.
    pub from: f64,
    /// Value at its end.
    pub to: f64,
    /// How far below the straight line it passes halfway along.
    pub sag: f64,
}

impl Bow {
    /// The value a fraction `a` of the way along.
    #[inline]
    pub fn at(&self, a: f64) -> f64 {
        self.from + (self.to - self.from) * a - 4.0 * self.sag * a * (1.0 - a)
    }

    /// The sag of a part of it a fraction `share` of its length long: the part has the same
    /// curvature, so `sag·share²`.
    #[inline]
    pub fn sag_of_part(&self, share: f64) -> f64 {
        self.sag * share * share
    }
}

/// A ramp across one block bowed into a parabola: value `start + k·(slope + curve·k)` at sample
/// `k` of a block of `N` samples, passing `sag` below the straight ramp at mid-block
/// (`curve = 4·sag/N²`, and `slope` the straight ramp's less `curve·N`). Unbowed (`sag = 0`) it
/// is the [`Ramp`] to the bit.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Bowed {
    start: f64,
    /// Per sample.
    slope: f64,
    /// Per sample².
    curve: f64,
}

impl Bowed {
    /// A parabola from `from` (at the block's first sample) to `to` (at the next block's first
    /// sample) over `len` samples, `sag` below the straight line between them at mid-block.
    #[inline]
    pub fn new(from: f64, to: f64, len: usize, sag: f64) -> Self {
        let n = len as f64;
        let (ramp, curve) = (Ramp::new(from, to, len), 4.0 * sag / (n * n));
        Self { start: ramp.start, slope: ramp.slope - curve * n, curve }
    }

    /// Value at sample `k` of the block (`k = len` gives the end value).
    #[inline]
    pub fn at(&self, k: usize) -> f64 {
        let k = k as f64;
        self.start + k * (self.slope + self.curve * k)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn breakpoints_interpolate_and_hold() {
        let b = Breakpoints::new(vec![(0.5, 1.0), (1.5, 3.0)]).unwrap();
        assert_eq!(b.at(0.0), 1.0);
        let mut cursor = 0;
        for t in [0.0, 0.2, 0.5, 0.7, 1.0, 1.5, 2.0, 0.6, 3.0] {
            assert_eq!(b.at_cursor(t, &mut cursor), b.at(t), "t = {t}");
        }
        assert_eq!(b.at(1.0), 2.0);
        assert_eq!(b.at(9.0), 3.0);
        assert_eq!(b.range(), (1.0, 3.0));
    }

    /// The shortcuts (a flat segment, a one-sample ramp) give the general formulas' bits.
    #[test]
    fn shortcuts_give_the_general_formulas_bits() {
        let general = |(t0, v0): (f64, f64), (t1, v1): (f64, f64), t: f64| v0 + (v1 - v0) * (t - t0) / (t1 - t0);
        for v in [-1.5e-3, 0.3, 0.0, -0.0, 1e300] {
            let b = Breakpoints::new(vec![(0.0, 7.0), (0.25, v), (2.45, v), (3.0, 1.0)]).unwrap();
            let mut cursor = 0;
            for t in [0.25, 0.26, 1.0, 2.449] {
                let want = general((0.25, v), (2.45, v), t);
                assert_eq!(b.at(t).to_bits(), want.to_bits(), "v = {v}, t = {t}");
                assert_eq!(b.at_cursor(t, &mut cursor).to_bits(), want.to_bits(), "v = {v}, t = {t}");
            }
        }
        for (from, to) in [(0.1, 0.3), (-1.5e-3, 3e-3), (0.2, 0.2)] {
            let ramp = Ramp::new(from, to, 1);
            assert_eq!(ramp.at(1).to_bits(), (from + (to - from) / 1.0 * 1.0).to_bits());
            assert_eq!(ramp.at(0), from);
        }
    }

    /// Unbowed, a bowed ramp is the straight one to the bit; bowed, it keeps its ends, passes
    /// `sag` below the line at mid-block, and its slope changes by the same amount every sample
    /// (a constant second difference `2·bow`).
    #[test]
    fn a_bowed_ramp_keeps_its_ends_and_sags_by_its_sag_mid_block() {
        for (from, to, len) in [(0.1, 0.3, 1), (-1.5e-3, 3e-3, 64), (0.2, 0.2, 7), (2e-3, -1.5e-3, 256)] {
            let (ramp, flat) = (Ramp::new(from, to, len), Bowed::new(from, to, len, 0.0));
            for k in 0..=len {
                assert_eq!(flat.at(k).to_bits(), ramp.at(k).to_bits(), "({from}, {to}, {len}) at {k}");
            }
            let sag = 1e-4;
            let bowed = Bowed::new(from, to, len, sag);
            let scale = from.abs().max(to.abs()).max(sag);
            assert!((bowed.at(0) - from).abs() <= 4.0 * f64::EPSILON * scale);
            assert!((bowed.at(len) - to).abs() <= 4.0 * f64::EPSILON * scale * len as f64);
            if len % 2 == 0 {
                let middle = ramp.at(len / 2) - bowed.at(len / 2);
                assert!((middle - sag).abs() <= 8.0 * f64::EPSILON * scale, "({from}, {to}, {len}): {middle}");
            }
            let second = 8.0 * sag / (len * len) as f64;
            for k in 1..len {
                let d2 = bowed.at(k + 1) - 2.0 * bowed.at(k) + bowed.at(k - 1);
                assert!((d2 - second).abs() <= 16.0 * f64::EPSILON * scale, "({from}, {to}, {len}) at {k}: {d2}");
            }
        }
    }

    #[test]
    fn invalid_breakpoints_are_refused() {
        assert_eq!(Breakpoints::new(vec![]), Err(BreakpointError::Empty));
        assert!(matches!(
            Breakpoints::new(vec![(0.0, 1.0), (0.0, 2.0)]),
            Err(BreakpointError::NotIncreasing { index: 1, .. })
        ));
        assert!(matches!(Breakpoints::new(vec![(0.0, f64::NAN)]), Err(BreakpointError::NotFinite { index: 0 })));
        assert!(matches!(Breakpoints::new(vec![(-1.0, 0.0)]), Err(BreakpointError::NotFinite { index: 0 })));
    }
}
