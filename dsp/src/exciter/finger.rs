//! Fingers on the string (seed eqs. 45–48, 52, 62; docs/physics.md §7.1).
//!
//! A finger φ presses with force `F_φe(t)` (N, a control input) spread over the half-cosine window
//! `χ_φ(x) = π/(2W) · cos(π(x − x_φ)/W)` for `|x − x_φ| ≤ W/2` (seed eq. 48, ∫χ = 1), and
//! damps the string with `F_φR = −r |F_φe| d_t u_φ`, `u_φ = h_φᵀũ` (seed eq. 46, r in s/m).
//! The modal vector (seed eq. 52) is
//!
//! ```text
//! h_φ,i = π² cos(β_i W/2) / (π² − β_i² W²) · sin(β_i x_φ)
//! ```
//!
//! with a removable singularity at `β_i W = π`, where the window factor tends to `π/4`.
//! The window factor depends only on W, so it is computed once per string; moving the finger
//! only changes the sines.

use crate::string::ModalString;

/// Finger parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FingerParams {
    /// Window width W (m), > 0.
    pub width: f64,
    /// Damping parameter r (s/m), ≥ 0: `r·|F_φe|` is a damping coefficient (kg/s).
    pub damping: f64,
}

/// The window factors `π² cos(β_i W/2)/(π² − β_i² W²)` for every mode of `string`, as a vector of
/// the string's [`padded_len`](ModalString::padded_len) (zero past M).
pub fn window_factors(string: &ModalString, width: f64) -> Vec<f64> {
    let pi2 = std::f64::consts::PI.powi(2);
    let mut factors = string.vector();
    for (f, &beta) in factors.iter_mut().zip(string.wavenumbers()) {
        let bw = beta * width;
        let den = pi2 - bw * bw;
        *f = if den.abs() < 1e-8 * pi2 { std::f64::consts::FRAC_PI_4 } else { pi2 * (0.5 * bw).cos() / den };
    }
    factors
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::string::{Damping, StringParams};

    /// The closed form equals the quadrature of eq. 52, including the mode at β W = π.
    #[test]
    fn window_factor_matches_quadrature() {
        let params = StringParams {
            length: 0.65,
            tension: 100.0,
            linear_density: 4.9e-3,
            bending_stiffness: 0.0,
            damping: Damping::LOSSLESS,
        };
        let string = ModalString::new(params, 44100.0).unwrap();
        // W = L/10 puts mode 10 exactly on the singularity β W = π.
        let width = 0.065;
        let factors = window_factors(&string, width);
        for (i, (&beta, &f)) in string.wavenumbers().iter().zip(&factors).enumerate().take(40) {
            let n = 20_000;
            let h = width / n as f64;
            let quad: f64 = (0..n)
                .map(|k| {
                    let x = -0.5 * width + (k as f64 + 0.5) * h;
                    std::f64::consts::PI / (2.0 * width)
                        * (std::f64::consts::PI * x / width).cos()
                        * (beta * x).cos()
                        * h
                })
                .sum();
            assert!((f - quad).abs() < 1e-8, "mode {}: closed form {f}, quadrature {quad}", i + 1);
        }
    }
}
