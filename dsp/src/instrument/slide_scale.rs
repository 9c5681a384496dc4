//! The slide's scale: where the slide stops the string to sound a pitch (docs/physics.md §7.6).
//!
//! An ideal string of length `L` stopped at `x` sounds as its speaking length `L − x`, so `p`
//! semitones above the open string the slide would go to
//!
//! ```text
//! x_p = L(1 − 2^(−p/12))
//! ```
//!
//! The model's string stopped there sounds sharp: under a point force it is stiffer than the ideal
//! string it stands for: it keeps only the `N` modes below its frequency limit. (The voice's core
//! reaches each mode through the continuous mode's stiffness `m̃ω_i²`, not the scheme's `K̂_i`,
//! which exceeds it the more the nearer the mode is to Nyquist: `ModalString::coupling_weights`.)
//! The point compliance it lacks at `x` is
//!
//! ```text
//! R(x) = x(L − x)/(TL) − Σ_{i≤N} sin²(β_i x)/(m̃ω_i²)        (m/N)
//! ```
//!
//! the ideal string's static compliance less the model's. For the notes the slide plays, far below
//! the modes that are missing or stiffened, the stopped model behaves as the ideal string stopped
//! through a spring of compliance `−R`; and a string that ends on a spring of compliance `c` sounds
//! as a string `T·c` longer. So the model sounds as a speaking length shorter by the end correction
//!
//! ```text
//! δ(x) = T·R(x)        (m)
//! ```
//!
//! about `L/(π²N)` from the modes beyond the limit (the tail of `Σ 2L sin²(iπx/L)/(i²π²T)`, with
//! `sin²` at its mean ½), whatever the time step. The slide is placed `δ` nearer the nut, as a
//! player places a slide by ear:
//!
//! ```text
//! x_o = x_p − δ(x_p)
//! ```
//!
//! kept between 5 mm and 0.8 L (`δ` is taken at `x_p`, not at `x_o`; it varies slowly along the
//! string but within the first table interval from the nut, where the slide stops at 5 mm).
//!
//! Measured against the flexible string, `R` also holds the shortening a point support gives a
//! stiff string, about `√(EI/T)/2`, so the slide makes up for that too.
//!
//! What the player's slide does to the pitch is left as it is, as a player hears it: the slide's
//! mass `M` on the hand's spring `K_H` raises partial `n` by the end correction
//! `T/(Mω_n² − K_H)` (0.456 mm at 440 Hz for 30 g on 10⁴ N/m), and a softer contact lowers it.

use crate::string::ModalString;

/// Nearest the nut the slide goes (m): the open string's key sounds as a string shorter by 5 mm
/// plus the end correction there (0.54 mm).
const NEAREST_NUT: f64 = 0.005;

/// Farthest from the nut the slide goes, as a fraction of the string's length.
const REACH: f64 = 0.8;

/// Points of the end-correction table, evenly spaced from the nut to [`REACH`].
const POINTS: usize = 65;

/// Where the slide stops one string for each pitch.
#[derive(Debug, Clone, PartialEq)]
pub struct SlideScale {
    /// The string's length `L` (m).
    length: f64,
    /// Spacing of the table's points (m).
    step: f64,
    /// End correction `δ` (m) at the table's points.
    correction: [f64; POINTS],
}

impl SlideScale {
    /// The scale of `string`, for its modes and time step.
    pub fn new(string: &ModalString) -> Self {
        let (length, tension) = (string.params().length, string.params().tension);
        let modes = string.modes();
        // The voice's core couples to each mode through the continuous mode's stiffness m̃ω0²
        // (`ModalString::coupling_weights`), not the scheme's K̂.
        let (m, omega0) = (string.modal_mass(), &string.angular_frequencies()[..modes]);
        let stiffness: Vec<f64> = omega0.iter().map(|&w| m * w * w).collect();
        let wavenumbers = &string.wavenumbers()[..modes];
        let step = REACH * length / (POINTS - 1) as f64;
        let correction = std::array::from_fn(|j| {
            let x = j as f64 * step;
            let kept: f64 = wavenumbers.iter().zip(&stiffness).map(|(&beta, &k)| (beta * x).sin().powi(2) / k).sum();
            tension * (x * (length - x) / (tension * length) - kept)
        });
        Self { length, step, correction }
    }

    /// End correction `δ` (m) of the string stopped at `x` (m), between the table's points.
    pub fn end_correction(&self, x: f64) -> f64 {
        let at = (x / self.step).clamp(0.0, (POINTS - 1) as f64);
        let j = (at as usize).min(POINTS - 2);
        let t = at - j as f64;
        self.correction[j] + t * (self.correction[j + 1] - self.correction[j])
    }

    /// Where the slide may go (m): from `NEAREST_NUT` to `REACH` of the length.
    pub fn range(&self) -> (f64, f64) {
        (NEAREST_NUT, REACH * self.length)
    }

    /// Slide position `x_o` (m) that sounds `semitones` above the open string, between
    /// `NEAREST_NUT` and `REACH` of the length.
    pub fn position(&self, semitones: f64) -> f64 {
        let ideal = self.length * (1.0 - 2f64.powf(-semitones / 12.0));
        let (nearest, farthest) = self.range();
        (ideal - self.end_correction(ideal)).clamp(nearest, farthest)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::preset::slide_guitar;
    use crate::string::{Damping, StringParams};

    /// The slide guitar's A string without bending stiffness or damping: an ideal string.
    fn ideal() -> StringParams {
        let p = slide_guitar().string;
        StringParams { bending_stiffness: 0.0, damping: Damping::LOSSLESS, ..p }
    }

    /// At a sample rate far above its modes, the only stiffness an ideal string lacks is that of
    /// the modes beyond its limit: `Σ_{i>N} 2L sin²(iπx/L)/(i²π²)`, which is `L/(π²N)` within
    /// `1/N` where `sin²` averages ½ over the tail (here within 2 % of it, away from the ends).
    #[test]
    fn an_ideal_string_finely_stepped_lacks_the_compliance_of_its_missing_modes() {
        let string = ModalString::band_limited(ideal(), 4_000_000.0, 20_000.0).expect("a valid string");
        let (l, n) = (string.params().length, string.modes() as f64);
        let scale = SlideScale::new(&string);
        let tail = l / (std::f64::consts::PI.powi(2) * n);
        for x in [0.1, 0.2, 0.325, 0.4, 0.5] {
            let delta = scale.end_correction(x);
            println!("x = {x} m: δ = {:.4} mm, L/(π²N) = {:.4} mm ({n} modes)", 1e3 * delta, 1e3 * tail);
            assert!((delta / tail - 1.0).abs() < 0.02, "x = {x}: δ {delta} m vs {tail} m");
        }
    }

    /// The time step adds nothing: the slide core reaches each mode through `m̃ω²`, not the
    /// scheme's `K̂ = (4m̃/Δt²) tan²(ωΔt/2)`, so the same modes lack the same compliance at 48 kHz
    /// as at 4 MHz. The table's interpolation is the exact sum at its points to 1e-9 m.
    #[test]
    fn the_time_step_adds_no_compliance() {
        let fine = SlideScale::new(&ModalString::band_limited(ideal(), 4_000_000.0, 20_000.0).expect("valid"));
        let string = ModalString::band_limited(ideal(), 48_000.0, 20_000.0).expect("valid");
        let coarse = SlideScale::new(&string);
        let l = string.params().length;
        for x in [0.1, 0.2, 0.325, 0.4, 0.5] {
            let added = coarse.end_correction(x) - fine.end_correction(x);
            assert!(added.abs() < 1e-9, "x = {x}: the time step adds {added} m");
        }
        let x = 7.0 * coarse.step;
        let m = string.modal_mass();
        let kept: f64 = (1..=string.modes())
            .map(|i| {
                (i as f64 * std::f64::consts::PI * x / l).sin().powi(2)
                    / (m * string.angular_frequencies()[i - 1].powi(2))
            })
            .sum();
        let exact = string.params().tension * (x * (l - x) / (string.params().tension * l) - kept);
        assert!((coarse.end_correction(x) - exact).abs() < 1e-9);
    }

    /// The slide goes nearer the nut than the ideal fret by its end correction (checked against
    /// the modes' sum above; the pitch it gives in `slide_motion.rs`), which on the guitar
    /// string is between 0.5 and 2 mm from 1 to 24 semitones, and stays within its reach.
    #[test]
    fn the_slide_stops_the_string_short_by_half_a_millimetre_to_two_within_its_reach() {
        let string = ModalString::band_limited(slide_guitar().string, 48_000.0, 20_000.0).expect("valid");
        let scale = SlideScale::new(&string);
        let l = string.params().length;
        for p in [1.0, 5.0, 12.0, 24.0] {
            let ideal = l * (1.0 - 2f64.powf(-p / 12.0));
            let delta = ideal - scale.position(p);
            assert!(delta > 5e-4 && delta < 2e-3, "{p} semitones: δ = {delta} m");
        }
        assert_eq!(scale.position(0.0), NEAREST_NUT);
        assert_eq!(scale.position(40.0), REACH * l);
        assert_eq!(scale.position(-3.0), NEAREST_NUT);
    }
}
