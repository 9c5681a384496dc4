//! The body as a listener hears it: the force the strings put on their bridge, radiated
//! (docs/physics.md §13).
//!
//! # Transmittance
//!
//! A body mode `j` (natural frequency `ω_j`, loss factor `η_j`, effective mass `M_j` at the
//! bridge, as in [`crate::bridge`]) moves under the bridge force `F` as
//!
//! ```text
//! M_j (ẍ_j + η_j ω_j ẋ_j + ω_j² x_j) = F
//! ```
//!
//! and what reaches a listener is a weighted sum of the modes' velocities,
//!
//! ```text
//! p = Σ_j r_j ẋ_j,       P(ω)/F(ω) = Σ_j r_j iω / (M_j(ω_j² − ω² + iη_jω_jω))
//! ```
//!
//! the body's transmittance: the poles are the body's, as in its admittance at the bridge, the
//! zeros are set by how each mode radiates (Smith, *Physical Audio Signal Processing*, "Building
//! a synthetic guitar bridge admittance"). The weight `r_j` (kg/s) follows from the mode's
//! radiated power: with `½M_j v_j²` the mode's kinetic energy at bridge velocity `v_j`, the
//! board's mean-square velocity is `M_j v_j²/M` (`M` the radiating plate's mass), and a mode of
//! radiation efficiency `σ_j` radiates `W_j = ρ₀cSσ_j M_j v_j²/M`. The pressure it makes goes with
//! `√W_j`, so
//!
//! ```text
//! r_j = s_j √(σ_j M_j) · g
//! ```
//!
//! with `s_j = ±1` the sign of the mode's shape where the listener is (fixed per mode), and `g`
//! one gain for the whole body, chosen so that the transmittance's mean power gain over a band
//! where the body radiates well is 1 (the output is in newtons, as the bridge force it replaces).
//!
//! # Exact step
//!
//! The strings drive the body with a force that is constant over each sample (zero-order hold),
//! so each mode steps exactly: with `σ = ηω_0/2`, `ω_d = √(ω_0² − σ²)`, `e = e^{−σΔt}`,
//! `c = cos ω_dΔt`, `s = sin ω_dΔt`,
//!
//! ```text
//! x' = A₁₁x + A₁₂v + B₁F/M,   v' = A₂₁x + A₂₂v + B₂F/M
//! A₁₁ = e(c + σs/ω_d),  A₁₂ = e s/ω_d,  A₂₁ = −ω_0² e s/ω_d,  A₂₂ = e(c − σs/ω_d)
//! B₁ = (1 − A₁₁)/ω_0²,   B₂ = A₁₂
//! ```
//!
//! Nothing is approximated but the hold: a body never goes unstable and rings at its own
//! frequencies at any sample rate. A mode at or above 0.49 of the sample rate is left out.

use crate::bridge::{BridgeMode, BridgeParams, SOUNDBOARD_BAND, SOUNDBOARD_CONDUCTANCE};
use crate::string::simd::{Chunk, Isa, Kernel, LANES, Lanes, chunks, chunks_mut};

/// Speed of sound in air (m/s) at 20 °C.
pub const SPEED_OF_SOUND: f64 = 343.0;

/// One body mode and how it radiates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RadiatingMode {
    /// Frequency, effective mass at the bridge and loss factor.
    pub mode: BridgeMode,
    /// Radiation weight `r_j` (kg/s): the output per unit of the mode's velocity at the bridge.
    pub radiation: f64,
}

/// A body: its modes at the bridge and their radiation.
#[derive(Debug, Clone, PartialEq)]
pub struct BodyParams {
    /// The modes.
    pub modes: Vec<RadiatingMode>,
}

impl BodyParams {
    /// A body of `modes`, each radiating with efficiency `efficiency(f)` (0 to 1) and the sign
    /// `sign(j)`, its gain set so that the transmittance's mean power gain over `band` (Hz, on
    /// a logarithmic grid) is 1.
    pub fn radiating(
        modes: &[BridgeMode],
        efficiency: impl Fn(f64) -> f64,
        sign: impl Fn(usize) -> f64,
        band: (f64, f64),
    ) -> Self {
        let modes = modes
            .iter()
            .enumerate()
            .map(|(j, &mode)| RadiatingMode {
                mode,
                radiation: sign(j) * (efficiency(mode.frequency).clamp(0.0, 1.0) * mode.mass).sqrt(),
            })
            .collect();
        let mut body = Self { modes };
        let gain = body.mean_power_gain(band);
        if gain > 0.0 && gain.is_finite() {
            let g = 1.0 / gain.sqrt();
            body.modes.iter_mut().for_each(|m| m.radiation *= g);
        }
        body
    }

    /// The transmittance `P(ω)/F(ω)` at `frequency` (Hz): `(real, imaginary)`.
    pub fn response(&self, frequency: f64) -> (f64, f64) {
        let w = std::f64::consts::TAU * frequency;
        self.modes.iter().fold((0.0, 0.0), |(re, im), m| {
            let wj = std::f64::consts::TAU * m.mode.frequency;
            let (a, b) = (m.mode.mass * (wj * wj - w * w), m.mode.mass * m.mode.loss_factor * wj * w);
            let den = a * a + b * b;
            (re + m.radiation * w * b / den, im + m.radiation * w * a / den)
        })
    }

    /// The transmittance's power gain `|P/F|²` averaged over `band` (Hz) on a logarithmic grid
    /// of 2,000 frequencies.
    pub fn mean_power_gain(&self, band: (f64, f64)) -> f64 {
        let n = 2000;
        let ratio = band.1 / band.0;
        (0..n)
            .map(|k| {
                let (re, im) = self.response(band.0 * ratio.powf((k as f64 + 0.5) / n as f64));
                re * re + im * im
            })
            .sum::<f64>()
            / n as f64
    }

    /// The piano's soundboard as it radiates: the strings' soundboard (its band, mean
    /// conductance and loss factor) with the modes [`RADIATING_RATIO`] apart, each radiating with
    /// the efficiency [`soundboard_radiation_efficiency`], signs from a fixed pattern (the lowest
    /// three in phase: the board's lowest modes move it as one), power gain 1 over 1–4 kHz.
    pub fn piano() -> Self {
        let (low, high, _) = SOUNDBOARD_BAND;
        let board = BridgeParams::mean_value(SOUNDBOARD_CONDUCTANCE, (low, high, RADIATING_RATIO));
        Self::radiating(&board.modes, soundboard_radiation_efficiency, fixed_sign, (1000.0, 4000.0))
    }

    /// Check every mode.
    pub fn validate(&self) -> Result<(), String> {
        if self.modes.len() > crate::bridge::MAX_BRIDGE_MODES {
            return Err(format!("a body has at most {} modes", crate::bridge::MAX_BRIDGE_MODES));
        }
        BridgeParams { modes: self.modes.iter().map(|m| m.mode).collect() }.validate().map_err(|e| e.0)?;
        match self.modes.iter().position(|m| !m.radiation.is_finite()) {
            Some(j) => Err(format!("body mode {j}: the radiation weight must be finite")),
            None => Ok(()),
        }
    }
}

/// `+1` for the lowest three modes, then a fixed pseudo-random pattern of signs (the sign of each
/// mode's shape at the listener's position, which a mean-value body does not know).
pub fn fixed_sign(j: usize) -> f64 {
    if j < 3 || (j as f64 * 0.754_877_666_246_692_8).fract() < 0.5 { 1.0 } else { -1.0 }
}

/// Ratio between neighbouring modes of the radiating soundboard. The strings' bank is coarse
/// (ratio 1.2, [`SOUNDBOARD_BAND`]): what drains a string is the board's mean conductance. The
/// ear hears the transmittance's detail, whose resonances overlap on a real board: its modal
/// overlap `η·f·n(f) = η/(r − 1)` is 0.5 here (0.1 with the strings' bank, whose valleys between
/// modes would colour each key), and its density `1/((r − 1)f)` 0.025 modes/Hz at 1 kHz, within
/// the 0.01–0.05 modes/Hz Ege and Boutillon measured over 300–2,500 Hz.
pub const RADIATING_RATIO: f64 = 1.04;

/// Area of a concert grand's soundboard (m²).
pub const SOUNDBOARD_AREA: f64 = 1.8;

/// Coincidence frequency of the soundboard (Hz): where the bending wave's speed in the board
/// reaches the speed of sound. Below it a plate radiates from its edges and corners only.
pub const SOUNDBOARD_COINCIDENCE: f64 = 1400.0;

/// The radiation efficiency of the piano's soundboard at `frequency` (Hz), 0 to 1 (module docs,
/// docs/physics.md §13.2): a baffled piston of the board's area, `(ka)²/(2 + (ka)²)` (its limits
/// `(ka)²/2` and 1), times the edge-radiation law `√(f/f_c)` below coincidence.
pub fn soundboard_radiation_efficiency(frequency: f64) -> f64 {
    let radius = (SOUNDBOARD_AREA / std::f64::consts::PI).sqrt();
    let ka = std::f64::consts::TAU * frequency / SPEED_OF_SOUND * radius;
    let piston = ka * ka / (2.0 + ka * ka);
    piston * (frequency / SOUNDBOARD_COINCIDENCE).sqrt().min(1.0)
}

/// A body stepping exactly under a held force (module docs): force in, radiated out.
#[derive(Debug, Clone)]
pub struct Body {
    a11: Vec<f64>,
    a12: Vec<f64>,
    a21: Vec<f64>,
    a22: Vec<f64>,
    b1: Vec<f64>,
    b2: Vec<f64>,
    radiation: Vec<f64>,
    x: Vec<f64>,
    v: Vec<f64>,
    /// The vector unit the steps run on.
    isa: Isa,
}

/// Below this mean-square velocity (m²/s²) with no force, a body has fallen silent.
const SILENT: f64 = 1e-40;

impl Body {
    /// `params` at `sample_rate` (Hz). Allocates: build it before the audio thread runs.
    pub fn new(params: &BodyParams, sample_rate: f64) -> Self {
        let dt = 1.0 / sample_rate;
        let mut body = Self {
            a11: Vec::new(),
            a12: Vec::new(),
            a21: Vec::new(),
            a22: Vec::new(),
            b1: Vec::new(),
            b2: Vec::new(),
            radiation: Vec::new(),
            x: Vec::new(),
            v: Vec::new(),
            isa: Isa::detect(),
        };
        for m in params.modes.iter().filter(|m| m.mode.frequency < 0.49 * sample_rate) {
            let w0 = std::f64::consts::TAU * m.mode.frequency;
            let sigma = 0.5 * m.mode.loss_factor * w0;
            let wd = (w0 * w0 - sigma * sigma).max(0.0).sqrt();
            let e = (-sigma * dt).exp();
            let (s, c) = (wd * dt).sin_cos();
            // s/ω_d, continuous at ω_d → 0 (critical damping).
            let sinc = if wd > 0.0 { s / wd } else { dt };
            let (a11, a12) = (e * (c + sigma * sinc), e * sinc);
            let (a21, a22) = (-w0 * w0 * e * sinc, e * (c - sigma * sinc));
            body.a11.push(a11);
            body.a12.push(a12);
            body.a21.push(a21);
            body.a22.push(a22);
            body.b1.push((1.0 - a11) / (w0 * w0) / m.mode.mass);
            body.b2.push(a12 / m.mode.mass);
            body.radiation.push(m.radiation);
        }
        // Pad to whole lanes with inert modes (no coefficients, no input, no radiation).
        while !body.a11.len().is_multiple_of(LANES) {
            for v in [&mut body.a11, &mut body.a12, &mut body.a21, &mut body.a22, &mut body.b1, &mut body.b2] {
                v.push(0.0);
            }
            body.radiation.push(0.0);
        }
        body.x = vec![0.0; body.a11.len()];
        body.v = vec![0.0; body.a11.len()];
        body
    }

    /// How many modes step, padded with inert ones to a whole number of lanes.
    pub fn modes(&self) -> usize {
        self.x.len()
    }

    /// Bring every mode to rest.
    pub fn reset(&mut self) {
        self.x.fill(0.0);
        self.v.fill(0.0);
    }

    /// Whether every mode is at rest (to [`SILENT`]).
    pub fn is_silent(&self) -> bool {
        self.v.iter().map(|v| v * v).sum::<f64>() < SILENT
    }

    /// Replace the bridge force in `io` (N, one value per sample) by the radiated signal
    /// (module docs), sample by sample. A silent body given no force stays silent at no cost.
    pub fn process(&mut self, io: &mut [f64]) {
        if io.iter().all(|&f| f == 0.0) && self.is_silent() {
            self.reset();
            return;
        }
        let step = Step {
            a: [chunks(&self.a11), chunks(&self.a12), chunks(&self.a21), chunks(&self.a22)],
            b: [chunks(&self.b1), chunks(&self.b2)],
            r: chunks(&self.radiation),
            x: chunks_mut(&mut self.x),
            v: chunks_mut(&mut self.v),
            io,
        };
        self.isa.run(step);
        if !self.v.iter().all(|v| v.is_finite()) {
            self.reset();
            io.fill(0.0);
        }
    }
}

/// One block of a body's exact steps (module docs), a chunk of [`LANES`] modes at a time on
/// whatever vector unit the CPU has.
struct Step<'a> {
    /// `A₁₁, A₁₂, A₂₁, A₂₂`, `B₁/M, B₂/M`, `r`.
    a: [&'a [Chunk]; 4],
    b: [&'a [Chunk]; 2],
    r: &'a [Chunk],
    x: &'a mut [Chunk],
    v: &'a mut [Chunk],
    io: &'a mut [f64],
}

impl Kernel for Step<'_> {
    type Output = ();

    #[inline(always)]
    fn run<L: Lanes>(self, s: L) {
        let [a11, a12, a21, a22] = self.a;
        let [b1, b2] = self.b;
        for y in self.io.iter_mut() {
            let f = s.splat(*y);
            let mut sum = s.splat(0.0);
            for (j, (x, v)) in self.x.iter_mut().zip(self.v.iter_mut()).enumerate() {
                let (xj, vj) = (s.load(x), s.load(v));
                let x_next =
                    s.add(s.add(s.mul(s.load(&a11[j]), xj), s.mul(s.load(&a12[j]), vj)), s.mul(s.load(&b1[j]), f));
                let v_next =
                    s.add(s.add(s.mul(s.load(&a21[j]), xj), s.mul(s.load(&a22[j]), vj)), s.mul(s.load(&b2[j]), f));
                s.store(x, x_next);
                s.store(v, v_next);
                sum = s.add(sum, s.mul(s.load(&self.r[j]), v_next));
            }
            *y = s.sum(sum);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A body's step is exact: a sine force (constant over each sample) drives it, and after
    /// the start has died out the output's amplitude and phase at that frequency are the
    /// transmittance's to 0.5 % of the body's mean gain (which is 1) up to 1 kHz at 48 kHz: the
    /// hold, sampling the force at each sample's middle, is all that differs.
    #[test]
    fn a_body_steps_to_its_transmittance() {
        let fs = 48_000.0;
        let params = BodyParams::piano();
        for f in [110.0, 262.0, 523.0, 1000.0] {
            let mut body = Body::new(&params, fs);
            let n = 96_000;
            let w = std::f64::consts::TAU * f / fs;
            // Hold the force at the value at each sample's middle, so the hold's delay cancels.
            let mut io: Vec<f64> = (0..n).map(|k| ((k as f64 + 0.5) * w).sin()).collect();
            body.process(&mut io);
            // Project the last half on sin and cos at sample times n+1 (the state's time).
            let (mut s, mut c) = (0.0, 0.0);
            for (k, y) in io.iter().enumerate().skip(n / 2) {
                let t = (k as f64 + 1.0) * w;
                s += y * t.sin();
                c += y * t.cos();
            }
            let (s, c) = (2.0 * s / (n / 2) as f64, 2.0 * c / (n / 2) as f64);
            let (re, im) = params.response(f);
            let (got, want) = ((s * s + c * c).sqrt(), (re * re + im * im).sqrt());
            println!("{f} Hz: amplitude {got:.6} vs {want:.6}");
            assert!((got - want).abs() < 5e-3 * want.max(1.0), "{f} Hz: {got} vs {want}");
        }
    }

    /// The piano body has power gain 1 over 1–4 kHz (its normalisation), and below 100 Hz the
    /// board barely radiates (Wogram's observation): around 40 Hz its power gain is more than
    /// 15 dB below (measured 22.2 dB), the board being small against the sound's wavelength there.
    #[test]
    fn the_soundboard_radiates_little_below_100_hz() {
        let body = BodyParams::piano();
        body.validate().unwrap();
        let gain = body.mean_power_gain((1000.0, 4000.0));
        let low = body.mean_power_gain((35.0, 45.0));
        println!("mean power gain 1–4 kHz {gain:.4}, 35–45 Hz {low:.2e}");
        assert!((gain - 1.0).abs() < 1e-12);
        assert!(low < 10f64.powf(-1.5), "{low}");
    }

    /// No force, no state: a body costs nothing and outputs zeros; a non-finite force silences
    /// it instead of filling it with NaN.
    #[test]
    fn a_silent_body_stays_silent_and_bad_force_is_dropped() {
        let mut body = Body::new(&BodyParams::piano(), 48_000.0);
        let mut io = [0.0; 64];
        body.process(&mut io);
        assert!(io.iter().all(|&y| y == 0.0) && body.is_silent());
        io[3] = f64::NAN;
        body.process(&mut io);
        assert!(io.iter().all(|&y| y == 0.0) && body.is_silent());
    }
}
