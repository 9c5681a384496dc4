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
//! and Boutillon measured on a piano soundboard (docs/physics.md §12 has the sources).

use crate::string::{Coefficients, Mode};

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
/// impedance of 2,500 kg/s, within the range measured at piano bridges (about 1,000 kg/s at
/// 100 Hz falling to 10 kg/s at 10 kHz in magnitude on an upright, Wogram; the real part lies
/// below the magnitude between resonances). See docs/physics.md §12 for what it sets.
pub const SOUNDBOARD_CONDUCTANCE: f64 = 4e-4;

/// The soundboard's loss factor (dimensionless): the ~2 % mean modal loss factor Ege and
/// Boutillon measured on a piano soundboard in playing condition.
pub const SOUNDBOARD_LOSS_FACTOR: f64 = 0.02;

/// Lowest and highest soundboard mode (Hz), and the ratio between neighbours. Below about
/// 100 Hz a piano's soundboard assembly is stiffness-controlled (impedance phase near −90°,
/// Wogram), so the bank starts just below it; a modal bank is spring-like below its lowest mode.
pub const SOUNDBOARD_BAND: (f64, f64, f64) = (90.0, 16_000.0, 1.2);

impl BridgeParams {
    /// The piano's soundboard (module docs): modes from [`SOUNDBOARD_BAND`]'s lowest frequency up
    /// to its highest, each a ratio apart with a fixed jitter of up to ±35 % of the spacing (a
    /// regular comb would give every octave the same pattern), effective masses from the mean
    /// conductance `conductance` (s/kg) and the loss factor [`SOUNDBOARD_LOSS_FACTOR`].
    pub fn soundboard(conductance: f64) -> Self {
        let (low, high, ratio) = SOUNDBOARD_BAND;
        let count = ((high / low).ln() / ratio.ln()).floor() as usize + 1;
        let modes = (0..count)
            .map(|j| {
                // A fixed low-discrepancy jitter in [−0.35, 0.35) of a step.
                let jitter = 0.7 * ((j as f64 * 0.618_033_988_749_895).fract() - 0.5);
                let frequency = low * ratio.powf(j as f64 + jitter);
                // The bank's own modal density there: one mode per spacing `(r − 1)f`.
                let density = 1.0 / ((ratio - 1.0) * frequency);
                BridgeMode { frequency, mass: density / (4.0 * conductance), loss_factor: SOUNDBOARD_LOSS_FACTOR }
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

/// The bridge's modes prepared for one sample rate: coefficients and state.
#[derive(Debug, Clone)]
pub struct Bridge {
    /// `2P_j`.
    coef_a: Vec<f64>,
    /// `1 + Q_j`.
    coef_b: Vec<f64>,
    /// `C_j` (m/N).
    coef_c: Vec<f64>,
    /// `K̂_j` (N/m).
    stiffness: Vec<f64>,
    /// `R̂_j` (kg/s).
    resistance: Vec<f64>,
    /// `M_j` (kg).
    mass: Vec<f64>,
    /// `q^{n−1}`, `q^n` (m).
    q_prev: Vec<f64>,
    q_now: Vec<f64>,
    /// `q^{n−1} − z̃` of the coming step (m).
    free: Vec<f64>,
    /// `C_Σ = Σ_j C_j` (m/N).
    compliance: f64,
    /// `b^{n−1}`, `b^n` (m), kept as the sums of `q^{n−1}`, `q^n`.
    b: (f64, f64),
    /// `b_free` of the coming step (m).
    b_free: f64,
    sample_rate: f64,
}

/// Energy terms of one bridge step (J).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct BridgeEnergy {
    /// `Σ_j ½M_j((q^{n+1} − q^n)/Δt)² + ½K̂_j((q^{n+1} + q^n)/2)²` (J).
    pub stored: f64,
    /// `Δt Σ_j R̂_j ((q^{n+1} − q^{n−1})/(2Δt))²` (J).
    pub dissipated: f64,
}

impl Bridge {
    /// Prepare `params` at `sample_rate` (Hz), at rest, with the modes below 0.98 of Nyquist (a
    /// mode's scheme is exact below it; the modes above would only alias).
    pub fn new(params: &BridgeParams, sample_rate: f64) -> Result<Self, BridgeError> {
        params.validate()?;
        if !(sample_rate > 0.0 && sample_rate.is_finite()) {
            return Err(BridgeError("the sample rate must be positive".into()));
        }
        let dt = 1.0 / sample_rate;
        let mut bridge = Self {
            coef_a: Vec::new(),
            coef_b: Vec::new(),
            coef_c: Vec::new(),
            stiffness: Vec::new(),
            resistance: Vec::new(),
            mass: Vec::new(),
            q_prev: Vec::new(),
            q_now: Vec::new(),
            free: Vec::new(),
            compliance: 0.0,
            b: (0.0, 0.0),
            b_free: 0.0,
            sample_rate,
        };
        let kept = params.modes.iter().filter(|m| m.frequency < 0.49 * sample_rate);
        for m in kept {
            let omega0 = std::f64::consts::TAU * m.frequency;
            let (p, q) = Mode::oscillator(omega0, 0.5 * m.loss_factor * omega0).recursion(dt);
            let c = Coefficients::new(p, q, dt, m.mass);
            bridge.coef_a.push(c.a);
            bridge.coef_b.push(c.b);
            bridge.coef_c.push(c.c);
            bridge.stiffness.push(c.stiffness);
            bridge.resistance.push(c.resistance);
            bridge.mass.push(m.mass);
        }
        let modes = bridge.mass.len();
        bridge.q_prev.resize(modes, 0.0);
        bridge.q_now.resize(modes, 0.0);
        bridge.free.resize(modes, 0.0);
        bridge.compliance = bridge.coef_c.iter().sum();
        Ok(bridge)
    }

    /// Number of modes.
    pub fn modes(&self) -> usize {
        self.mass.len()
    }

    /// The bridge at rest.
    pub fn reset(&mut self) {
        self.q_prev.fill(0.0);
        self.q_now.fill(0.0);
        self.b = (0.0, 0.0);
    }

    /// `(b^{n−1}, b^n)` (m).
    #[inline]
    pub fn displacement(&self) -> (f64, f64) {
        self.b
    }

    /// First half of a step: `(b_free, C_Σ)` (m, m/N), where the bridge would be at `n+1`
    /// with no force, and how far a force moves it (module docs).
    #[inline]
    pub fn predict(&mut self) -> (f64, f64) {
        // Four partial sums, so that the additions do not wait on each other.
        let mut sums = [0.0; 4];
        let modes = self.free.len();
        let (a, b, prev, now, free) = (&self.coef_a, &self.coef_b, &self.q_prev, &self.q_now, &mut self.free);
        for j in 0..modes {
            let f = prev[j] - (b[j] * prev[j] - a[j] * now[j]);
            free[j] = f;
            sums[j % 4] += f;
        }
        self.b_free = (sums[0] + sums[1]) + (sums[2] + sums[3]);
        (self.b_free, self.compliance)
    }

    /// Second half: apply the force `f` (N) and step on. Returns `b^{n+1}` (m).
    #[inline]
    pub fn advance(&mut self, f: f64) -> f64 {
        for ((q, &free), &c) in self.q_prev.iter_mut().zip(&self.free).zip(&self.coef_c) {
            *q = free + c * f;
        }
        std::mem::swap(&mut self.q_prev, &mut self.q_now);
        let next = self.b_free + self.compliance * f;
        self.b = (self.b.1, next);
        next
    }

    /// [`advance`](Self::advance), also returning the energy terms of the step.
    pub fn advance_monitored(&mut self, f: f64) -> (f64, BridgeEnergy) {
        let fs = self.sample_rate;
        let mut energy = BridgeEnergy::default();
        for j in 0..self.free.len() {
            let next = self.free[j] + self.coef_c[j] * f;
            let (now, before) = (self.q_now[j], self.q_prev[j]);
            let (v, mean) = ((next - now) * fs, 0.5 * (next + now));
            energy.stored += 0.5 * self.mass[j] * v * v + 0.5 * self.stiffness[j] * mean * mean;
            let centred = 0.5 * (next - before) * fs;
            energy.dissipated += self.resistance[j] * centred * centred / fs;
            self.q_prev[j] = next;
        }
        std::mem::swap(&mut self.q_prev, &mut self.q_now);
        let next = self.b_free + self.compliance * f;
        self.b = (self.b.1, next);
        (next, energy)
    }

    /// The bridge's own energy `H^{n−1/2}` between `q^{n−1}` and `q^n` (J).
    pub fn energy(&self) -> f64 {
        let fs = self.sample_rate;
        (0..self.mass.len())
            .map(|j| {
                let (v, mean) = ((self.q_now[j] - self.q_prev[j]) * fs, 0.5 * (self.q_now[j] + self.q_prev[j]));
                0.5 * self.mass[j] * v * v + 0.5 * self.stiffness[j] * mean * mean
            })
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The soundboard's mobility averaged over its band has the real part it was built for
    /// (the mean-value relation `n/(4M)` holds to the bank's discreteness: within 25 % over
    /// 200 Hz – 8 kHz, averaged on a log grid), and every mode is a valid mass.
    #[test]
    fn the_soundboard_has_its_mean_conductance() {
        let board = BridgeParams::soundboard(SOUNDBOARD_CONDUCTANCE);
        board.validate().unwrap();
        let n = 4000;
        let mean = (0..n).map(|k| board.mobility(200.0 * 40f64.powf(k as f64 / n as f64)).0).sum::<f64>() / n as f64;
        println!("mean Re Y {mean:e} s/kg over 200 Hz – 8 kHz, {} modes", board.modes.len());
        assert!((mean / SOUNDBOARD_CONDUCTANCE - 1.0).abs() < 0.25, "{mean:e}");
    }

    /// A free bridge mode rings at its frequency and decays at `σ = ηω/2`: the exact scheme,
    /// to 1e-9 after 4,800 steps, and a bridge driven by a force impulse holds what the force
    /// put in, less what it dissipated, to rounding.
    #[test]
    fn a_bridge_mode_rings_exactly_and_keeps_its_energy_balance() {
        let params = BridgeParams { modes: vec![BridgeMode { frequency: 220.0, mass: 0.5, loss_factor: 0.02 }] };
        let fs = 48_000.0;
        let mut bridge = Bridge::new(&params, fs).unwrap();
        let (w0, sigma) = (std::f64::consts::TAU * 220.0, 0.01 * std::f64::consts::TAU * 220.0);
        let w = (w0 * w0 - sigma * sigma).sqrt();
        let exact = |n: f64| (-sigma * n / fs).exp() * (w * n / fs).cos();
        bridge.q_prev[0] = exact(-1.0);
        bridge.q_now[0] = exact(0.0);
        bridge.b = (exact(-1.0), exact(0.0));
        for n in 1..=4800 {
            bridge.predict();
            let b = bridge.advance(0.0);
            assert!((b - exact(n as f64)).abs() < 1e-9, "step {n}: {b} vs {}", exact(n as f64));
        }
        let mut bridge = Bridge::new(&BridgeParams::soundboard(SOUNDBOARD_CONDUCTANCE), fs).unwrap();
        let (mut work, mut losses, mut stored) = (0.0, 0.0, 0.0);
        for n in 0..2000 {
            let f = if n < 3 { 10.0 } else { 0.0 };
            let (before, now) = bridge.displacement();
            bridge.predict();
            let (next, e) = bridge.advance_monitored(f);
            // The force's work over the step, f·(b^{n+1} − b^{n−1})/2.
            work += 0.5 * f * (next - before);
            let _ = now;
            losses += e.dissipated;
            stored = e.stored;
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
            assert!(Bridge::new(&BridgeParams { modes: vec![m] }, 48_000.0).is_err(), "{m:?}");
        }
    }
}
