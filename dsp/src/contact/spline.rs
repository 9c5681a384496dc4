//! The quadratic spline approximation (QSA) of the contact potential (seed §2.2, eqs. 5–10).
//!
//! Knots `y_j = j·Δy`, `j = 0..N`, with `Δy = y_ref/N` and `y_ref` from the reference energy
//! (seed eq. 5). The spline is zero for `y ≤ 0`, the quadratic `V_j` on `(y_{j−1}, y_j]`, and the
//! last quadratic `V_N` extended without limit beyond `y_{N−1}`. It interpolates V at every knot
//! and is C¹ (seed eqs. 6–10).
//!
//! # Construction: bidiagonal recursion in local form (docs/physics.md §1.4)
//!
//! With `Vk_j = V(y_j)` and the knot slopes `D_j = V̂'(y_j)`:
//!
//! ```text
//! V_j(y) = Vk_{j−1} + D_{j−1}·(y − y_{j−1}) + A_j·(y − y_{j−1})²
//! A_j    = (Vk_j − Vk_{j−1} − D_{j−1}·Δy) / Δy²
//! D_j    = D_{j−1} + 2·A_j·Δy          (⇔ D_{j−1} + D_j = 2(Vk_j − Vk_{j−1})/Δy)
//! D_0 = 0,  Vk_0 = 0,  A_0 = 0 (segment 0 is the zero potential)
//! ```
//!
//! The slope relation is the lower-bidiagonal system the seed mentions, solved here by forward
//! substitution in O(N). The local form avoids the large, cancelling global coefficients `c_j`.
//! For α = 1 it reproduces V exactly (`A_j = κ/2`, `D_j = κ y_j`).
//!
//! The spline must be convex (`A_j > 0` for all `j ≥ 1`) for the branched solve to be valid; this
//! is checked at construction. The curvatures are *not* monotone in `j` for α < 2.

use super::{ContactError, PowerLaw};

/// A C¹ piecewise-quadratic approximation of a [`PowerLaw`] potential.
#[derive(Debug, Clone)]
pub struct QuadSpline {
    law: PowerLaw,
    /// Knot spacing Δy (m).
    dy: f64,
    /// Number of segments N ≥ 1.
    segments: usize,
    /// `Vk_j = V(y_j)` (J), `j = 0..=N`.
    knot_potential: Vec<f64>,
    /// `D_j = V̂'(y_j)` (N), `j = 0..=N`.
    knot_slope: Vec<f64>,
    /// `A_j` (N/m, half the second derivative on segment j), `j = 0..=N`, `A_0 = 0`.
    curvature: Vec<f64>,
}

impl QuadSpline {
    /// Fit N = `segments` quadratics over `[0, y_ref]`, with `y_ref` the compression at which the
    /// law stores `v_ref` joules (seed eq. 5).
    pub fn from_reference_energy(law: PowerLaw, v_ref: f64, segments: usize) -> Result<Self, ContactError> {
        if !(v_ref.is_finite() && v_ref > 0.0) {
            return Err(ContactError::invalid("v_ref", "must be finite and > 0", v_ref));
        }
        Self::new(law, law.compression_at_energy(v_ref), segments)
    }

    /// Fit N = `segments` quadratics over `[0, y_ref]` (m).
    pub fn new(law: PowerLaw, y_ref: f64, segments: usize) -> Result<Self, ContactError> {
        let mut spline = Self::unfitted(law, segments);
        spline.refit(law, y_ref, segments)?;
        Ok(spline)
    }

    /// A spline with room for `segments` segments, fitted with one segment over 1 mm until
    /// [`refit`](Self::refit) says otherwise.
    ///
    /// # Panics
    ///
    /// If `law` cannot be fitted so: its potential over 1 mm underflows to zero (an exponent of
    /// about 100 and more, or a stiffness near the smallest floats). The instrument makes its
    /// solvers with a law of ordinary numbers; [`new`](Self::new) reports any law that fails.
    pub fn with_capacity(law: PowerLaw, segments: usize) -> Self {
        let mut spline = Self::unfitted(law, segments);
        spline.refit(law, 1e-3, 1).expect("one segment over 1 mm fits a law of ordinary numbers");
        spline
    }

    /// Room for `segments` segments, not fitted yet.
    fn unfitted(law: PowerLaw, segments: usize) -> Self {
        let n = segments.max(1) + 1;
        Self {
            law,
            dy: 1e-3,
            segments: 1,
            knot_potential: Vec::with_capacity(n),
            knot_slope: Vec::with_capacity(n),
            curvature: Vec::with_capacity(n),
        }
    }

    /// Refit in place: N = `segments` quadratics over `[0, y_ref]` (m) for `law`. Never allocates
    /// while `segments` is within the capacity the spline was made with. On error the spline is
    /// left unchanged.
    pub fn refit(&mut self, law: PowerLaw, y_ref: f64, segments: usize) -> Result<(), ContactError> {
        if segments == 0 {
            return Err(ContactError::invalid("segments", "must be >= 1", 0.0));
        }
        if !(y_ref.is_finite() && y_ref > 0.0) {
            return Err(ContactError::invalid(
                "v_ref",
                "gives a reference compression y_ref that is not finite and > 0",
                y_ref,
            ));
        }
        let dy = y_ref / segments as f64;
        // Check convexity before touching the fit, so a failure leaves it intact.
        let (mut vk, mut d) = (0.0, 0.0);
        for j in 1..=segments {
            let next = law.potential(j as f64 * dy);
            let a = (next - vk - d * dy) / (dy * dy);
            if !(a.is_finite() && a > 0.0) {
                return Err(ContactError::NotConvex { segment: j, curvature: a });
            }
            vk = next;
            d += 2.0 * a * dy;
        }
        let n = segments;
        for v in [&mut self.knot_potential, &mut self.knot_slope, &mut self.curvature] {
            v.clear();
            v.resize(n + 1, 0.0);
        }
        for j in 1..=n {
            self.knot_potential[j] = law.potential(j as f64 * dy);
            let a = (self.knot_potential[j] - self.knot_potential[j - 1] - self.knot_slope[j - 1] * dy) / (dy * dy);
            self.curvature[j] = a;
            self.knot_slope[j] = self.knot_slope[j - 1] + 2.0 * a * dy;
        }
        self.law = law;
        self.dy = dy;
        self.segments = n;
        Ok(())
    }

    /// The power law this spline approximates.
    pub fn law(&self) -> &PowerLaw {
        &self.law
    }

    /// Number of segments N.
    pub fn segments(&self) -> usize {
        self.segments
    }

    /// Knot spacing Δy (m).
    pub fn knot_spacing(&self) -> f64 {
        self.dy
    }

    /// Position of knot `j` (m): `y_j = j·Δy`.
    #[inline]
    pub fn knot(&self, j: usize) -> f64 {
        j as f64 * self.dy
    }

    /// The reference compression covered by the fit, `y_N` (m).
    pub fn reference_compression(&self) -> f64 {
        self.knot(self.segments)
    }

    /// `V(y_j)` (J).
    #[inline]
    pub fn knot_potential(&self, j: usize) -> f64 {
        self.knot_potential[j]
    }

    /// `D_j = V̂'(y_j)` (N).
    #[inline]
    pub fn knot_slope(&self, j: usize) -> f64 {
        self.knot_slope[j]
    }

    /// Curvature coefficient `A_j` of segment `j` (N/m); `A_0 = 0`.
    #[inline]
    pub fn curvature(&self, j: usize) -> f64 {
        self.curvature[j]
    }

    /// Segment containing `y`: 0 for `y ≤ 0`, else `min(⌈y/Δy⌉, N)` (seed eq. 26 with the clamp
    /// the seed's text implies). A point on a knot belongs to the lower segment, to rounding: as
    /// computed, `knot(j)/Δy` can round just above `j` (about one knot in twenty), and the knot
    /// then falls in the upper segment, which meets the lower one there in value and slope.
    #[inline]
    pub fn segment_of(&self, y: f64) -> usize {
        if y > 0.0 {
            // ⌈x⌉ without `f64::ceil` (a libm call on baseline x86-64): the cast truncates (and
            // saturates, so huge y lands in segment N) and is exact wherever x has a fraction.
            let x = y / self.dy;
            let below = x as usize;
            let up = if (below as f64) < x { below.saturating_add(1) } else { below };
            up.clamp(1, self.segments)
        } else {
            0
        }
    }

    /// `V_p(y)` (J): the quadratic of segment `p`, extended to any `y` (`V_0 ≡ 0`).
    #[inline]
    pub fn segment_potential(&self, p: usize, y: f64) -> f64 {
        if p == 0 {
            return 0.0;
        }
        let h = y - self.knot(p - 1);
        self.knot_potential[p - 1] + h * (self.knot_slope[p - 1] + self.curvature[p] * h)
    }

    /// `V_p'(y)` (N): the slope of segment `p`'s quadratic, extended to any `y`.
    #[inline]
    pub fn segment_slope(&self, p: usize, y: f64) -> f64 {
        if p == 0 {
            return 0.0;
        }
        self.knot_slope[p - 1] + 2.0 * self.curvature[p] * (y - self.knot(p - 1))
    }

    /// The spline potential `V̂(y)` (J).
    #[inline]
    pub fn potential(&self, y: f64) -> f64 {
        self.segment_potential(self.segment_of(y), y)
    }

    /// The spline slope `V̂'(y)` (N), the magnitude of the approximated force.
    #[inline]
    pub fn slope(&self, y: f64) -> f64 {
        self.segment_slope(self.segment_of(y), y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolates_and_is_c1_at_every_knot() {
        let law = PowerLaw::new(4.5e9, 2.5).unwrap();
        let s = QuadSpline::new(law, 7.9e-4, 7).unwrap();
        for j in 1..7 {
            let y = s.knot(j);
            let v = law.potential(y);
            assert!((s.segment_potential(j, y) - v).abs() <= 1e-14 * v);
            assert!((s.segment_potential(j + 1, y) - v).abs() <= 1e-14 * v);
            let d = s.segment_slope(j, y);
            assert!((s.segment_slope(j + 1, y) - d).abs() <= 1e-13 * d);
        }
        assert_eq!(s.potential(-1e-3), 0.0);
        assert_eq!(s.segment_of(1.0), 7, "compression past y_N stays in the last segment");
    }

    /// The segment is `min(⌈y/Δy⌉, N)` (at least 1) for every positive y: on knots (which belong to
    /// the lower segment), one ulp either side of them, tiny, huge and infinite; 0 otherwise.
    #[test]
    fn segment_of_is_the_ceiling_of_y_over_dy() {
        let law = PowerLaw::new(4.5e9, 2.5).unwrap();
        let s = QuadSpline::new(law, 7.9e-4, 7).unwrap();
        let dy = s.knot(1);
        let want = |y: f64| if y > 0.0 { ((y / dy).ceil() as usize).clamp(1, 7) } else { 0 };
        let mut ys = vec![0.0, -0.0, -1.0, f64::NAN, f64::INFINITY, f64::MAX, f64::MIN_POSITIVE, 5e-324, 1e3];
        for j in 0..=8 {
            let y = j as f64 * dy;
            ys.extend([
                y,
                f64::from_bits(y.to_bits() + 1),
                f64::from_bits(y.to_bits().saturating_sub(1)),
                y + 0.5 * dy,
            ]);
        }
        for y in ys {
            assert_eq!(s.segment_of(y), want(y), "y = {y:e}");
        }
    }

    #[test]
    fn invalid_inputs_are_errors() {
        let law = PowerLaw::new(1e8, 1.3).unwrap();
        assert!(QuadSpline::new(law, 1e-4, 0).is_err());
        assert!(QuadSpline::new(law, 0.0, 5).is_err());
        assert!(QuadSpline::new(law, f64::NAN, 5).is_err());
        assert!(QuadSpline::from_reference_energy(law, -1.0, 5).is_err());
        assert!(QuadSpline::from_reference_energy(law, f64::INFINITY, 5).is_err());
    }
}
