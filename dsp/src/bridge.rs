//! The bridge and soundboard as the strings see them: a bank of damped modes at the bridge point
//! (docs/physics.md §12).
//!
//! # Model
//!
//! The bridge's transverse displacement where the strings cross it is `b = Σ_j q_j`, the sum of
//! `J` modal displacements, each mode normalised to 1 there, so its modal mass `M_j` (kg) is the
//! mode's effective mass at the bridge point. A transverse force `f` (N) applied there drives every
//! mode alike:
//!
//! ```text
//! M_j q̈_j + 2M_jσ_j q̇_j + M_jω_j² q_j = f,       Y(ω) = Σ_j iω / (M_j(ω_j² − ω² + 2iσ_jω))
//! ```
//!
//! `Y` is the driving-point mobility (m/(N·s)). Each mode steps with the exact scheme of the
//! string's modes (docs/physics.md §6.2), with its own `P_j`, `Q_j`, `C_j = Δt²(1 + 2P + Q)/(4M_j)`:
//!
//! ```text
//! q_j^{n+1} = q_j^{n−1} − z̃_j + C_j f,   z̃_j = (1 + Q_j) q_j^{n−1} − 2P_j q_j^n
//! ```
//!
//! so that `b^{n+1} = b_free + C_Σ f` with `b_free = Σ_j (q_j^{n−1} − z̃_j)` and `C_Σ = Σ_j C_j`:
//! what a coupled step needs to eliminate the bridge in closed form.
//!
//! # The piano's soundboard
//!
//! [`BridgeParams::soundboard`] spreads `J` modes over the audio band with a mean mobility
//! given by the mean-value (Skudrzyk) view of a large plate: the real part of the driving-point
//! mobility averaged over many modes is `Re Y = n(f)/(4 M(f))`, the modal density (modes/Hz)
//! over four times the effective mass, and for a plate it is independent of frequency
//! (`1/(8√(Bm''))` for an infinite plate of bending stiffness `B` and surface mass `m''`). Each
//! mode's effective mass is therefore `M_j = n_j/(4 G)` for a chosen mean conductance `G`,
//! where `n_j` is the bank's own modal density at mode `j`. The loss factor is the ~2 % that Ege
//! and Boutillon measured on a piano soundboard or, for a bank sparser than the board, the larger
//! one that gives it the board's modal overlap (docs/physics.md §12.2 has the sources).

/// The fixed jitter of a mean-value bank's `j`-th mode, in [−0.35, 0.35) of its spacing: a
/// low-discrepancy (golden-ratio) sequence, so that a regular comb does not give every band the
/// same pattern of peaks and valleys.
pub fn mode_jitter(j: usize) -> f64 {
    0.7 * ((j as f64 * 0.618_033_988_749_895).fract() - 0.5)
}

/// The effective mass (kg) at the bridge of a mean-value bank's mode where the bank has `density`
/// modes per hertz, for the mean conductance `conductance` (s/kg): Skudrzyk's `n/(4G)`.
pub fn mean_value_mass(density: f64, conductance: f64) -> f64 {
    density / (4.0 * conductance)
}

/// Most bridge modes a bank may have.
pub const MAX_BRIDGE_MODES: usize = 256;

/// One mode of the bridge at the bridge point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BridgeMode {
    /// Natural frequency (Hz), > 0.
    pub frequency: f64,
    /// Effective mass at the bridge point (kg), > 0.
    pub mass: f64,
    /// Loss factor η = 2σ/ω (dimensionless), ≥ 0.
    pub loss_factor: f64,
}

/// A modal bank at the bridge point.
#[derive(Debug, Clone, PartialEq)]
pub struct BridgeParams {
    /// The modes.
    pub modes: Vec<BridgeMode>,
}

/// Why a bridge could not be made.
#[derive(Debug, Clone, PartialEq)]
pub struct BridgeError(pub String);

impl std::fmt::Display for BridgeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for BridgeError {}

/// The soundboard's mean driving-point conductance, `Re Y` averaged over modes (s/kg): an
/// impedance of 2,500 kg/s, above the magnitudes Wogram measured at an upright's bridge (about
/// 1,000 kg/s at 100 Hz falling to 10 kg/s at 10 kHz): the mobility's real part lies below its
/// magnitude between resonances, and a grand's board is larger. See docs/physics.md §12.2 for
/// what it sets.
pub const SOUNDBOARD_CONDUCTANCE: f64 = 4e-4;

/// The soundboard's loss factor (dimensionless): the ~2 % mean modal loss factor Ege and
/// Boutillon measured on a piano soundboard in playing condition.
pub const SOUNDBOARD_LOSS_FACTOR: f64 = 0.02;

/// Modal overlap `η·f·n(f)` of a piano soundboard (dimensionless): about 0.5, from the 2 % loss
/// factor and the 0.01–0.05 modes/Hz Ege and Boutillon measured over 300–2,500 Hz (0.3 at 300 Hz,
/// 0.5 from 1 to 2.5 kHz).
pub const SOUNDBOARD_OVERLAP: f64 = 0.5;

/// Lowest and highest soundboard mode (Hz), and the ratio between neighbours. Below about
/// 100 Hz a piano's soundboard assembly is stiffness-controlled (impedance phase near −90°,
/// Wogram), so the bank starts just below it; a modal bank is spring-like below its lowest mode.
pub const SOUNDBOARD_BAND: (f64, f64, f64) = (90.0, 16_000.0, 1.2);

impl BridgeParams {
    /// The piano's soundboard (module docs): [`mean_value`](Self::mean_value) over
    /// [`SOUNDBOARD_BAND`].
    pub fn soundboard(conductance: f64) -> Self {
        Self::mean_value(conductance, SOUNDBOARD_BAND)
    }

    /// A mean-value plate (module docs): modes from `low` up to `high` (Hz), each `ratio` apart
    /// with a fixed jitter of up to ±35 % of the spacing (a regular comb would give every octave
    /// the same pattern), effective masses from the mean conductance `conductance` (s/kg), and the
    /// loss factor [`SOUNDBOARD_LOSS_FACTOR`] or, for a bank sparser than a real board, the larger
    /// one that gives it the board's modal overlap [`SOUNDBOARD_OVERLAP`]: each mode then stands
    /// for the board's modes in its band, and the conductance between modes dips no deeper than
    /// the board's (the mean, `∫Re Y` over a mode, does not depend on the loss factor).
    pub fn mean_value(conductance: f64, (low, high, ratio): (f64, f64, f64)) -> Self {
        let loss_factor = SOUNDBOARD_LOSS_FACTOR.max(SOUNDBOARD_OVERLAP * (ratio - 1.0));
        let count = ((high / low).ln() / ratio.ln()).floor() as usize + 1;
        let modes = (0..count)
            .map(|j| {
                let frequency = low * ratio.powf(j as f64 + mode_jitter(j));
                // The bank's own modal density there: one mode per spacing `(r − 1)f`.
                let density = 1.0 / ((ratio - 1.0) * frequency);
                BridgeMode { frequency, mass: mean_value_mass(density, conductance), loss_factor }
            })
            .collect();
        Self { modes }
    }

    /// The driving-point mobility at `frequency` (Hz): `(Re Y, Im Y)` (s/kg).
    pub fn mobility(&self, frequency: f64) -> (f64, f64) {
        let w = std::f64::consts::TAU * frequency;
        self.modes.iter().fold((0.0, 0.0), |(re, im), m| {
            let wj = std::f64::consts::TAU * m.frequency;
            // iω / (M(ωj² − ω² + iηωjω))
            let (a, b) = (m.mass * (wj * wj - w * w), m.mass * m.loss_factor * wj * w);
            let den = a * a + b * b;
            (re + w * b / den, im + w * a / den)
        })
    }

    /// The mean real part of the driving-point mobility over 100 Hz – 10 kHz (s/kg), averaged on
    /// a logarithmic grid of 400 frequencies: the conductance a string sees on average.
    pub fn mean_conductance(&self) -> f64 {
        let n = 400;
        (0..n).map(|k| self.mobility(100.0 * 100f64.powf((k as f64 + 0.5) / n as f64)).0).sum::<f64>() / n as f64
    }

    /// Check every mode.
    pub fn validate(&self) -> Result<(), BridgeError> {
        if self.modes.len() > MAX_BRIDGE_MODES {
            return Err(BridgeError(format!("a bridge has at most {MAX_BRIDGE_MODES} modes")));
        }
        for (j, m) in self.modes.iter().enumerate() {
            let ok = m.frequency > 0.0 && m.frequency.is_finite() && m.mass > 0.0 && m.mass.is_finite();
            if !(ok && m.loss_factor >= 0.0 && m.loss_factor.is_finite()) {
                return Err(BridgeError(format!(
                    "bridge mode {j}: frequency and mass must be positive and finite, the loss factor ≥ 0"
                )));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::string::ModalBank;

    /// The soundboard's mobility averaged over its band has the real part it was built for
    /// (the mean-value relation `n/(4M)` holds to the bank's discreteness: within 10 % over
    /// 200 Hz – 8 kHz, averaged on a log grid; measured 4.21e-4 s/kg, −5 %, and 4.27e-4 over
    /// 100 Hz – 10 kHz, the figures docs/physics.md §12.2 gives), and every mode is a valid mass.
    #[test]
    fn the_soundboard_has_its_mean_conductance() {
        let board = BridgeParams::soundboard(SOUNDBOARD_CONDUCTANCE);
        board.validate().unwrap();
        let n = 4000;
        let mean = (0..n).map(|k| board.mobility(200.0 * 40f64.powf(k as f64 / n as f64)).0).sum::<f64>() / n as f64;
        let whole = board.mean_conductance();
        println!(
            "mean Re Y {mean:e} s/kg over 200 Hz – 8 kHz, {whole:e} over 100 Hz – 10 kHz, {} modes",
            board.modes.len()
        );
        assert!((mean / SOUNDBOARD_CONDUCTANCE - 1.0).abs() < 0.1, "{mean:e}");
        assert!((mean / 4.21e-4 - 1.0).abs() < 5e-3 && (whole / 4.27e-4 - 1.0).abs() < 5e-3, "{mean:e}, {whole:e}");
    }

    /// A bridge mode, stepped as the unison steps it (an oscillator of a [`ModalBank`]), rings at
    /// its frequency and decays at `σ = ηω/2`: the exact scheme, to 1e-9 after 4,800 steps; and the
    /// soundboard driven at the bridge by a force pulse holds what the force put in, less what it
    /// dissipated, to rounding.
    #[test]
    fn a_bridge_mode_rings_exactly_and_keeps_its_energy_balance() {
        let fs = 48_000.0;
        let (w0, sigma) = (std::f64::consts::TAU * 220.0, 0.01 * std::f64::consts::TAU * 220.0);
        let mut bank = ModalBank::with_capacity(1, fs);
        bank.push_oscillator(w0, sigma, 0.5);
        bank.finish();
        let w = (w0 * w0 - sigma * sigma).sqrt();
        let exact = |n: f64| (-sigma * n / fs).exp() * (w * n / fs).cos();
        bank.set_state(&[exact(-1.0)], &[exact(0.0)]);
        let mut probe = vec![0.0; bank.padded_len()];
        probe[0] = 1.0;
        let mut out = vec![0.0; 4800];
        bank.free_steps(&probe, &mut out);
        for (n, &b) in out.iter().enumerate() {
            assert!((b - exact(n as f64 + 1.0)).abs() < 1e-9, "step {n}: {b} vs {}", exact(n as f64 + 1.0));
        }
        let board = BridgeParams::soundboard(SOUNDBOARD_CONDUCTANCE);
        let mut bank = ModalBank::with_capacity(board.modes.len(), fs);
        for m in &board.modes {
            let omega0 = std::f64::consts::TAU * m.frequency;
            bank.push_oscillator(omega0, 0.5 * m.loss_factor * omega0, m.mass);
        }
        bank.finish();
        let ones: Vec<f64> = (0..bank.padded_len()).map(|i| if i < bank.modes() { 1.0 } else { 0.0 }).collect();
        let gains: Vec<f64> = ones.iter().zip(bank.input_gains()).map(|(e, c)| e * c).collect();
        let (mut work, mut losses, mut stored) = (0.0, 0.0, 0.0);
        for n in 0..2000 {
            let f = if n < 3 { 10.0 } else { 0.0 };
            let before = bank.project_state(&ones).0;
            bank.history([]);
            let (next, e, lost) = bank.advance_monitored([(&gains[..], f)], &ones);
            // The force's work over the step, f·(b^{n+1} − b^{n−1})/2.
            work += 0.5 * f * (next - before);
            losses += lost;
            stored = e;
        }
        println!("stored {stored:e} J, losses {losses:e} J, work {work:e} J");
        assert!(work > 0.0 && losses > 0.0);
        assert!((stored + losses - work).abs() < 1e-12 * work, "{}", stored + losses - work);
    }

    /// Bad modes are errors, not panics.
    #[test]
    fn invalid_bridge_modes_are_errors() {
        for m in [
            BridgeMode { frequency: 0.0, mass: 1.0, loss_factor: 0.02 },
            BridgeMode { frequency: 100.0, mass: f64::NAN, loss_factor: 0.02 },
            BridgeMode { frequency: 100.0, mass: 1.0, loss_factor: -1.0 },
        ] {
            assert!(BridgeParams { modes: vec![m] }.validate().is_err(), "{m:?}");
        }
    }
}
