//! The power-law contact: force, potential, and the exact discrete gradient.
//!
//! With compression `y` (m) and `[y]+ = max(y, 0)`, seed eqs. 1–2:
//!
//! ```text
//! F(y)  = −κ [y]+^α = −V'(y)              (N)
//! V(y)  = κ/(α+1) · [y]+^(α+1)            (J)
//! V''(y) = κ α [y]+^(α−1)                 (N/m)
//! ```
//!
//! κ > 0 (N/m^α), α ≥ 1. `V` is convex and C¹.
//!
//! The explicit (EXP) scheme quadratises the potential: `ψ = √(2V)` and its gradient
//! `g = dψ/dy = √(κ(α+1)/2) · [y]+^((α−1)/2)`. (The seed prints the exponent of `g` as α−1,
//! a misprint: ψ·g must equal `V' = κ[y]+^α`, which needs (α−1)/2.)
//!
//! # Discrete gradient without cancellation (docs/physics.md §5.1)
//!
//! `DG(y0, y1) = (V(y1) − V(y0)) / (y1 − y0)` is the secant slope used by the energy-conserving
//! Newton scheme (seed eq. 22). The plain difference quotient loses every digit when
//! `|y1 − y0| ≪ y`. With `x0 = [y0]+`, `x1 = [y1]+`, `xb = max`, `xs = min` and
//! `r = (xs − xb)/xb ∈ (−1, 0)`:
//!
//! ```text
//! V(xs) − V(xb) = κ/(α+1) · xb^(α+1) · ((1 + r)^(α+1) − 1)
//!               = κ/(α+1) · xb^(α+1) · expm1((α+1)·ln1p(r))
//! DG            = κ/(α+1) · xb^α · expm1((α+1)·ln1p(r)) / r
//! ```
//!
//! using `xs − xb = r·xb`. `|expm1(…)| < 1`, so nothing overflows. The mixed case (one side
//! out of contact) has no cancellation and uses the plain quotient.

use super::ContactError;

/// The power law `F = −κ [y]+^α` (seed eq. 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PowerLaw {
    kappa: f64,
    alpha: f64,
}

impl PowerLaw {
    /// A contact with stiffness `kappa` (N/m^α, > 0) and exponent `alpha` (≥ 1).
    pub fn new(kappa: f64, alpha: f64) -> Result<Self, ContactError> {
        if !(kappa.is_finite() && kappa > 0.0) {
            return Err(ContactError::invalid("kappa", "must be finite and > 0", kappa));
        }
        if !(alpha.is_finite() && alpha >= 1.0) {
            return Err(ContactError::invalid("alpha", "must be finite and >= 1", alpha));
        }
        Ok(Self { kappa, alpha })
    }

    /// Stiffness κ (N/m^α).
    pub fn kappa(&self) -> f64 {
        self.kappa
    }

    /// Exponent α (dimensionless).
    pub fn alpha(&self) -> f64 {
        self.alpha
    }

    /// Potential `V(y)` (J) at compression `y` (m).
    pub fn potential(&self, y: f64) -> f64 {
        if y <= 0.0 {
            return 0.0;
        }
        self.kappa / (self.alpha + 1.0) * y.powf(self.alpha + 1.0)
    }

    /// `V'(y) = κ [y]+^α` (N): the magnitude of the contact force.
    pub fn potential_slope(&self, y: f64) -> f64 {
        if y <= 0.0 {
            return 0.0;
        }
        self.kappa * y.powf(self.alpha)
    }

    /// `V''(y) = κ α [y]+^(α−1)` (N/m). At `y = 0` with α = 1 this is the one-sided value κ.
    pub fn potential_curvature(&self, y: f64) -> f64 {
        if y < 0.0 || (y == 0.0 && self.alpha > 1.0) {
            return 0.0;
        }
        self.kappa * self.alpha * y.powf(self.alpha - 1.0)
    }

    /// The contact force `F(y) = −V'(y)` (N).
    pub fn force(&self, y: f64) -> f64 {
        -self.potential_slope(y)
    }

    /// Exact discrete gradient `(V(y1) − V(y0)) / (y1 − y0)` (N), free of cancellation;
    /// equals `V'(y0)` when `y1 == y0`.
    pub fn discrete_gradient(&self, y0: f64, y1: f64) -> f64 {
        let x0 = y0.max(0.0);
        let x1 = y1.max(0.0);
        if x0 == 0.0 && x1 == 0.0 {
            return 0.0;
        }
        if y0 == y1 {
            return self.potential_slope(x0);
        }
        if x0 == 0.0 || x1 == 0.0 {
            // One side out of contact: V there is 0 and the quotient has no cancellation.
            return (self.potential(x1) - self.potential(x0)) / (y1 - y0);
        }
        let (xb, xs) = if x0 >= x1 { (x0, x1) } else { (x1, x0) };
        let r = (xs - xb) / xb;
        if r == 0.0 {
            return self.potential_slope(xb);
        }
        let n = self.alpha + 1.0;
        self.kappa / n * xb.powf(self.alpha) * ((n * r.ln_1p()).exp_m1() / r)
    }

    /// Compression (m) at which the potential stores `energy` (J): seed eq. 5,
    /// `y = ((α+1) E / κ)^(1/(α+1))`.
    pub fn compression_at_energy(&self, energy: f64) -> f64 {
        ((self.alpha + 1.0) * energy / self.kappa).powf(1.0 / (self.alpha + 1.0))
    }

    /// Quadratised potential `ψ(y) = √(2V(y))` (√J).
    pub fn psi(&self, y: f64) -> f64 {
        (2.0 * self.potential(y)).sqrt()
    }

    /// `g(y) = dψ/dy = √(κ(α+1)/2) · [y]+^((α−1)/2)` (√J/m). At `y = 0` with α = 1 this is
    /// the one-sided value √κ.
    pub fn psi_gradient(&self, y: f64) -> f64 {
        if y < 0.0 || (y == 0.0 && self.alpha > 1.0) {
            return 0.0;
        }
        (self.kappa * (self.alpha + 1.0) / 2.0).sqrt() * y.powf((self.alpha - 1.0) / 2.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_invalid_parameters() {
        assert!(PowerLaw::new(0.0, 1.5).is_err());
        assert!(PowerLaw::new(-1.0, 1.5).is_err());
        assert!(PowerLaw::new(f64::NAN, 1.5).is_err());
        assert!(PowerLaw::new(1e8, 0.99).is_err());
        assert!(PowerLaw::new(1e8, f64::INFINITY).is_err());
    }

    #[test]
    fn quadratised_potential_reproduces_the_force() {
        let law = PowerLaw::new(4.5e9, 2.5).unwrap();
        for &y in &[1e-6, 3e-5, 7.9e-4] {
            let rel = (law.psi(y) * law.psi_gradient(y) - law.potential_slope(y)).abs() / law.potential_slope(y);
            assert!(rel < 1e-14, "psi*g != V' at y = {y}: rel {rel}");
        }
    }

    #[test]
    fn discrete_gradient_matches_the_quotient_and_the_limit() {
        let law = PowerLaw::new(1e8, 1.3).unwrap();
        // Far apart: the plain quotient is accurate.
        let (a, b) = (2e-5, 7e-5);
        let plain = (law.potential(b) - law.potential(a)) / (b - a);
        assert!((law.discrete_gradient(a, b) - plain).abs() < 1e-13 * plain);
        assert_eq!(law.discrete_gradient(a, b), law.discrete_gradient(b, a));
        // Nearly equal: tends to V' (the plain quotient would have lost ~10 digits).
        let y = 5e-5;
        let dg = law.discrete_gradient(y, y * (1.0 + 1e-12));
        assert!((dg - law.potential_slope(y)).abs() < 1e-11 * law.potential_slope(y));
        // Mixed and free cases.
        assert_eq!(law.discrete_gradient(-1e-5, -2e-5), 0.0);
        let mixed = law.potential(3e-5) / 4e-5;
        assert!((law.discrete_gradient(-1e-5, 3e-5) - mixed).abs() < 1e-15 * mixed);
    }
}
