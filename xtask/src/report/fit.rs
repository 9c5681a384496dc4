//! Convergence orders by least squares.
//!
//! An error that converges as `‖e‖ ≈ C·h^p` is a straight line in log–log coordinates:
//! `log10‖e‖ = log10 C + p·log10 h`. With the report's errors already in log10 (see
//! [`super::error`]) and `x = log10 h`, the order is the slope of the least-squares line
//!
//! ```text
//! minimise Σ_i (y_i − a − b·x_i)²   over (a, b),      order p = ±b
//! ```
//!
//! solved with faer's QR least-squares solver on the m×2 design matrix `[1, x_i]`. For the error
//! against the segment count, `h = Δy/y_ref = 1/N`; against oversampling, `h = Δt = 1/(k·fs)`.
//! So in both cases the order is `p = −slope` of the error against `log10 N` or `log10 k`.
//! The fit also reports `R²` and the range of `h` it covers, since orders only hold over a
//! range (the pre-asymptotic start and the rounding floor are left out by the caller).

use faer::prelude::*;

/// A least-squares line `y = intercept + slope·x`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LineFit {
    /// Slope b.
    pub slope: f64,
    /// Intercept a.
    pub intercept: f64,
    /// Coefficient of determination `1 − Σ residual² / Σ (y − ȳ)²`.
    pub r2: f64,
    /// Points used.
    pub points: usize,
}

/// Fit a line to the finite points of `points` (`(x, y)`); `None` with fewer than two distinct x.
pub fn fit_line(points: &[(f64, f64)]) -> Option<LineFit> {
    let pts: Vec<(f64, f64)> = points.iter().copied().filter(|(x, y)| x.is_finite() && y.is_finite()).collect();
    let m = pts.len();
    let distinct = pts.iter().any(|p| p.0 != pts[0].0);
    if m < 2 || !distinct {
        return None;
    }
    let a = Mat::from_fn(m, 2, |i, j| if j == 0 { 1.0 } else { pts[i].0 });
    let b = Mat::from_fn(m, 1, |i, _| pts[i].1);
    let x = a.qr().solve_lstsq(&b);
    let (intercept, slope) = (x[(0, 0)], x[(1, 0)]);
    let mean = pts.iter().map(|p| p.1).sum::<f64>() / m as f64;
    let total: f64 = pts.iter().map(|p| (p.1 - mean).powi(2)).sum();
    let residual: f64 = pts.iter().map(|p| (p.1 - intercept - slope * p.0).powi(2)).sum();
    let r2 = if total > 0.0 { 1.0 - residual / total } else { 1.0 };
    Some(LineFit { slope, intercept, r2, points: m })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_a_known_line() {
        let pts: Vec<(f64, f64)> = (0..6).map(|i| (i as f64, 1.5 - 2.0 * i as f64)).collect();
        let fit = fit_line(&pts).unwrap();
        assert!((fit.slope + 2.0).abs() < 1e-12 && (fit.intercept - 1.5).abs() < 1e-12, "{fit:?}");
        assert!((fit.r2 - 1.0).abs() < 1e-12);
        assert_eq!(fit.points, 6);
    }

    #[test]
    fn least_squares_of_noisy_points_and_degenerate_input() {
        // Residuals of ±0.1 around y = x: slope Sxy/Sxx = 4.8/5 = 0.96.
        let fit = fit_line(&[(0.0, 0.1), (1.0, 0.9), (2.0, 2.1), (3.0, 2.9)]).unwrap();
        assert!((fit.slope - 0.96).abs() < 1e-12, "{fit:?}");
        assert!(fit.r2 < 1.0 && fit.r2 > 0.98);
        assert!(fit_line(&[(1.0, 2.0)]).is_none());
        assert!(fit_line(&[(1.0, 2.0), (1.0, 3.0)]).is_none());
        assert!(fit_line(&[(0.0, f64::NEG_INFINITY), (1.0, 3.0)]).is_none());
    }
}
