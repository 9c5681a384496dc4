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
//! so each mode steps exactly. With `σ = ηω_0/2`, `ω_d = √(ω_0² − σ²)` and the pole
//! `s = −σ + iω_d`, the complex coordinate `z = ẋ − s̄x = (ẋ + σx) + iω_d x` obeys the first-order
//! `ż = s z + F/M`, whose step under a held force is
//!
//! ```text
//! z' = λ z + β F,   λ = e^{sΔt},   β = (λ − 1)/(sM)
//! ẋ = Re z − (σ/ω_d) Im z,         so  r ẋ' = Re(γ w'),  γ = r(1 + iσ/ω_d)β
//! ```
//!
//! with `w = z/β`, which steps as `w' = λw + F`: four coefficients per mode (`λ`, `γ`), two
//! products and a sum per coordinate. Nothing is approximated but the hold: a body never goes
//! unstable and rings at its own frequencies at any sample rate. A mode at or above 0.49 of the
//! sample rate is left out; a loss factor is taken at most 1 (a resonance, `ω_d > 0`).
//!
//! The hold itself weighs a sampled force at `ω` by `sinc(ωΔt/2)` (−2.0 dB at 8 kHz at
//! 22.05 kHz, −0.4 dB at 48 kHz), which would make the treble depend on the sample rate. Each
//! mode's output weight is divided by that factor at its own frequency, `r_j·x_j/sin x_j` with
//! `x_j = ω_dΔt/2`, which makes up for it where the mode is heard most. Only the output changes
//! (the body takes nothing back from the strings): the transmittance then holds within 0.5 % up
//! to 10 kHz at 44.1 kHz and 3.4 % at 22.05 kHz (7.6 % and 28 % without), for a body heard by
//! its acceleration too (its mean acceleration over a sample is exact for the mass-like tails
//! above its modes, and the same factor serves it best there).
//!
//! The steps run a few chunks of modes at a time across a run of samples, their coefficients and
//! state held in registers, each sample's partial sum of the output added chunk after chunk in
//! the order of the modes: the same bits on every instruction set.
//!
//! # A compact body: pressure from acceleration
//!
//! A body small against the wavelength (a guitar below a few hundred hertz) radiates as a
//! monopole, whose far-field pressure follows the rate of change of its net volume velocity:
//! `p = Σ_j r_j ẍ_j` ([`Heard::Acceleration`]), `P/F = Σ_j r_j (iω)²/(M_j(ω_j² − ω² + iη_jω_jω))`.
//! Each sample's output is then the mean acceleration over the sample, `Σ_j r_j (v_j' − v_j)/Δt`,
//! exact under the held force as the steps are.
//!
//! # The guitar's low-frequency function
//!
//! Christensen and Vistisen's two-mass model of the guitar: the top plate (effective mass `m_p`
//! at the bridge, on its own spring) and the air in the sound hole (a piston of mass `m_h`),
//! coupled by the cavity's air spring. Driven at the bridge, the plate's mobility has two
//! resonances `ω₋`, `ω₊` and between them an antiresonance at the cavity's Helmholtz frequency
//! `ω_h` (where the air in the hole, resonating, holds the plate still):
//!
//! ```text
//! Y(ω) = iω (ω_h² − ω²) / (m_p (ω₋² − ω²)(ω₊² − ω²))
//!      = Σ_± iω / (M_± (ω_±² − ω²)),   M_± = m_p (ω₊² − ω₋²) / |ω_h² − ω_±²|
//! ```
//!
//! In mode `±` the hole's air moves against the plate by `−(A_p/A_h) ω_h²/(ω_h² − ω_±²)` of the
//! plate's displacement, so the net volume the body sweeps is `A_p ω_±²/(ω_±² − ω_h²)` per unit of
//! plate displacement (the hole's area cancels). That is each mode's weight, `r_± ∝ ω_±²/(ω_±² −
//! ω_h²)`: the two modes' volumes cancel at low frequency, leaving `P/F ∝ ω⁴/((ω₋² − ω²)(ω₊² −
//! ω²))` (lossless): the guitar's 24 dB per octave fall below its air resonance, a bass-reflex
//! loudspeaker's, and a flat response above `ω₊`, where the plate moves as a mass.
//!
//! # The top above its lowest mode
//!
//! Above `ω₊` the top is a plate with modes of its own, which the two-mass model leaves out. The
//! model's numbers give them (docs/physics.md §13.5). The coupled frequencies' squares sum to the
//! uncoupled ones', so the top with the hole closed resonates at `f_p² = f₋² + f₊² − f_h²` with
//! the mass `m_p` at the bridge. Taken as a simply supported plate of aspect `A` whose lowest mode
//! is that one, the top has the constant modal density and the mass
//!
//! ```text
//! n = (S/2)√(ρh/D) = (π/4)(A + 1/A)/f_p,     M = 4m_p,     G = n/(4M)
//! ```
//!
//! (the lowest mode of a plate weighs a quarter of it at the centre), and `G` is its mean
//! driving-point conductance, Skudrzyk's mean value as for the piano's soundboard
//! ([`crate::bridge`]). [`guitar_top_modes`] spreads a mean-value bank with that conductance above
//! `f₊`. Each plate mode is heard as a monopole radiating the mode's power `ρ₀cSσ_j·½M_j v_j²/M`:
//! its weight is `r_j = s_j (c/ω_j)√(4πSσ_jM_j/M)`, beside the pair's swept volumes
//! `A_p ω_±²/(ω_±² − ω_h²)` with `A_p = (4/π²)S`, the lowest mode's volume per unit of its centre's
//! motion.
//!
//! # Stereo
//!
//! Each mode carries a [`Side`]. The pair moves the top and the air in the sound hole together
//! and is heard alike from anywhere in front: the centre. Each higher mode of the top radiates
//! more from some regions than from others, so that two microphones a little apart hear it at
//! different levels; a mean-value body does not know which mode favours which, as it does not
//! know their signs, and places neighbouring modes alternately left and right, so that a partial
//! between two modes is heard between them. The instrument pans each side with constant power by
//! the stereo width.

use crate::bridge::{BridgeMode, BridgeParams, SOUNDBOARD_BAND, SOUNDBOARD_CONDUCTANCE, mean_value_mass, mode_jitter};
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
    /// Where the stereo picture places the mode.
    pub side: Side,
}

/// Where a body mode is heard in the stereo picture (docs/physics.md §13.6): in the centre, or
/// panned towards one side by the stereo width, keeping its power.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    Centre,
    Left,
    Right,
}

/// What of a body's motion a listener hears (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Heard {
    /// `p = Σ r_j ẋ_j`: a large radiator, each mode heard by its radiated power.
    Velocity,
    /// `p = Σ r_j ẍ_j`: a compact source, a monopole's pressure.
    Acceleration,
}

/// A body: its modes at the bridge and their radiation.
#[derive(Debug, Clone, PartialEq)]
pub struct BodyParams {
    /// The modes.
    pub modes: Vec<RadiatingMode>,
    /// What the radiation weights multiply.
    pub heard: Heard,
}

impl BodyParams {
    /// A body of `modes`, each radiating with efficiency `efficiency(f)` (0 to 1) and the sign
    /// `sign(j)`, heard in the centre, its gain set so that the transmittance's mean power gain
    /// over `band` (Hz, on a logarithmic grid) is 1.
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
                side: Side::Centre,
            })
            .collect();
        Self { modes, heard: Heard::Velocity }.normalized(band)
    }

    /// These modes with every radiation weight scaled so that the transmittance's mean power
    /// gain over `band` (Hz) is 1.
    fn normalized(mut self, band: (f64, f64)) -> Self {
        let gain = self.mean_power_gain(band);
        if gain > 0.0 && gain.is_finite() {
            let g = 1.0 / gain.sqrt();
            self.modes.iter_mut().for_each(|m| m.radiation *= g);
        }
        self
    }

    /// The transmittance `P(ω)/F(ω)` at `frequency` (Hz): `(real, imaginary)`.
    pub fn response(&self, frequency: f64) -> (f64, f64) {
        let w = std::f64::consts::TAU * frequency;
        let (re, im) = self.modes.iter().fold((0.0, 0.0), |(re, im), m| {
            let wj = std::f64::consts::TAU * m.mode.frequency;
            let (a, b) = (m.mode.mass * (wj * wj - w * w), m.mode.mass * m.mode.loss_factor * wj * w);
            let den = a * a + b * b;
            (re + m.radiation * w * b / den, im + m.radiation * w * a / den)
        });
        match self.heard {
            Heard::Velocity => (re, im),
            // Times iω.
            Heard::Acceleration => (-w * im, w * re),
        }
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

    /// The piano's soundboard as it radiates: the strings' soundboard (its band and mean
    /// conductance) with the modes [`RADIATING_RATIO`] apart, close enough for the measured loss
    /// factor to give the board's modal overlap ([`BridgeParams::mean_value`]), each radiating with
    /// the efficiency [`soundboard_radiation_efficiency`], signs from a fixed pattern (the lowest
    /// three in phase: the board's lowest modes move it as one), power gain 1 over 1–4 kHz.
    pub fn piano() -> Self {
        let (low, high, _) = SOUNDBOARD_BAND;
        let board = BridgeParams::mean_value(SOUNDBOARD_CONDUCTANCE, (low, high, RADIATING_RATIO));
        Self::radiating(&board.modes, soundboard_radiation_efficiency, fixed_sign, (1000.0, 4000.0))
    }

    /// A guitar's body (module docs): Christensen and Vistisen's two-mass model with their
    /// measured guitar's [`GUITAR_AIR`], [`GUITAR_HELMHOLTZ`], [`GUITAR_TOP`], [`GUITAR_TOP_MASS`]
    /// and quality factors, then the top's higher modes ([`guitar_top_modes`]), heard as a compact
    /// source (every mode by its acceleration), its power gain 1 over 1–4 kHz (the output is in
    /// newtons, as the bridge force it replaces). The pair is heard in the centre; the top's
    /// higher modes alternately on the left and on the right (docs/physics.md §13.6).
    pub fn guitar() -> Self {
        let w2 = |f: f64| (std::f64::consts::TAU * f).powi(2);
        let (low, helmholtz, top) = (w2(GUITAR_AIR), w2(GUITAR_HELMHOLTZ), w2(GUITAR_TOP));
        let piston = GUITAR_TOP_AREA * 4.0 / std::f64::consts::PI.powi(2);
        let pair = [(GUITAR_AIR, low, GUITAR_Q.0), (GUITAR_TOP, top, GUITAR_Q.1)].map(|(frequency, w, q)| {
            let mass = GUITAR_TOP_MASS * (top - low) / (helmholtz - w).abs();
            let mode = BridgeMode { frequency, mass, loss_factor: 1.0 / q };
            RadiatingMode { mode, radiation: piston * w / (w - helmholtz), side: Side::Centre }
        });
        let (plate, coincidence) = (guitar_top_plate_mass(), guitar_top_coincidence());
        let higher = guitar_top_modes().into_iter().enumerate().map(|(j, mode)| {
            let w = std::f64::consts::TAU * mode.frequency;
            let efficiency = radiation_efficiency(mode.frequency, GUITAR_TOP_AREA, coincidence);
            let power = 4.0 * std::f64::consts::PI * GUITAR_TOP_AREA * efficiency * mode.mass / plate;
            let radiation = fixed_sign(j) * SPEED_OF_SOUND / w * power.sqrt();
            RadiatingMode { mode, radiation, side: if j % 2 == 0 { Side::Left } else { Side::Right } }
        });
        let modes = pair.into_iter().chain(higher).collect();
        Self { modes, heard: Heard::Acceleration }.normalized((1000.0, 4000.0))
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

/// The guitar's lower resonance (Hz): the air in the body, the sound hole's piston on the cavity's
/// spring, moving with the top plate. Christensen and Vistisen, "Simple model for low-frequency
/// guitar function", JASA 68(3), 1980, their Fig. 4's guitar (90–120 Hz across the guitars they
/// measured).
pub const GUITAR_AIR: f64 = 104.0;

/// The Helmholtz frequency of the guitar's cavity with the top held still (Hz): the
/// antiresonance of the plate's mobility between the two resonances. Christensen and Vistisen,
/// Fig. 4 (122–135 Hz across their guitars).
pub const GUITAR_HELMHOLTZ: f64 = 127.0;

/// The guitar's upper resonance (Hz): the top plate's lowest mode, moving against the air.
/// Christensen and Vistisen, Fig. 4 (170–250 Hz across their guitars).
pub const GUITAR_TOP: f64 = 219.0;

/// The top plate's effective mass at the bridge (kg). Christensen and Vistisen, Fig. 4.
pub const GUITAR_TOP_MASS: f64 = 0.112;

/// The quality factors of the lower and upper resonance. Christensen and Vistisen, Fig. 4.
pub const GUITAR_Q: (f64, f64) = (29.0, 25.8);

/// Area of the guitar's top (m²): a choice of the order of a steel-string guitar's top (a
/// dreadnought's lower bout is about 0.4 m wide, its body 0.5 m long, with a waist). It sets how
/// the top radiates, not how it drains the string.
pub const GUITAR_TOP_AREA: f64 = 0.14;

/// Length over width of the plate that stands for the top's vibrating part (the lower bout, on
/// which the bridge sits): a choice. The modal density below depends on it only through
/// `A + 1/A` (2.11 here, at least 2 for any shape).
pub const GUITAR_TOP_ASPECT: f64 = 1.4;

/// Highest frequency of the top's modes the body carries (Hz): above it a slide string's partials
/// are faint, and the modes' mass lines keep the body's response flat.
pub const GUITAR_TOP_HIGHEST: f64 = 8000.0;

/// The ratio `r` that keeps the top's modes apart: their spacing is at least `(r − 1)f`, so above
/// the frequency at which the plate's own spacing `1/n` is narrower, one mode of the bank stands
/// for several of the plate's (docs/physics.md §13.5).
pub const GUITAR_TOP_RATIO: f64 = 1.1;

/// The top's lowest mode with the sound hole closed (Hz): the two-mass model's plate on its own
/// spring and the cavity's, `f_p² = f₋² + f₊² − f_h²` (the coupled frequencies' squares sum to the
/// uncoupled ones', the trace of its stiffness over its mass), 206.5 Hz for the measured guitar.
pub fn guitar_top_closed() -> f64 {
    (GUITAR_AIR.powi(2) + GUITAR_TOP.powi(2) - GUITAR_HELMHOLTZ.powi(2)).sqrt()
}

/// The top's modal density (modes/Hz), the same at every frequency, as a plate's: the top as a
/// simply supported plate of aspect [`GUITAR_TOP_ASPECT`] whose lowest mode is
/// [`guitar_top_closed`], `n = (S/2)√(ρh/D) = (π/4)(A + 1/A)/f_p` (the lowest mode is
/// `f_p = (π/2)√(D/ρh)(1/a² + 1/b²)`), 0.0080 modes/Hz: a mode every 124 Hz.
pub fn guitar_top_density() -> f64 {
    std::f64::consts::FRAC_PI_4 * (GUITAR_TOP_ASPECT + 1.0 / GUITAR_TOP_ASPECT) / guitar_top_closed()
}

/// The plate's mass (kg), `M = 4m_p`: a simply supported plate's lowest mode weighs a quarter of
/// the plate at its centre. 0.45 kg: the top, its braces and bridge and the air they carry.
pub fn guitar_top_plate_mass() -> f64 {
    4.0 * GUITAR_TOP_MASS
}

/// The top's mean driving-point conductance (s/kg), Skudrzyk's mean value `n/(4M)` with the
/// [`guitar_top_plate_mass`]: `n/(16 m_p)`, 4.5·10⁻³ s/kg.
pub fn guitar_top_conductance() -> f64 {
    guitar_top_density() / (4.0 * guitar_top_plate_mass())
}

/// The top's coincidence frequency (Hz), `(c²/2π)√(ρh/D)` with the bending stiffness the lowest
/// mode gives, `c²(1/a² + 1/b²)/(4f_p)` for the plate of [`GUITAR_TOP_AREA`] and
/// [`GUITAR_TOP_ASPECT`]: 2.15 kHz.
pub fn guitar_top_coincidence() -> f64 {
    let width = (GUITAR_TOP_AREA / GUITAR_TOP_ASPECT).sqrt();
    let length = GUITAR_TOP_ASPECT * width;
    SPEED_OF_SOUND.powi(2) * (length.powi(-2) + width.powi(-2)) / (4.0 * guitar_top_closed())
}

/// The top's modes above its lowest (docs/physics.md §13.5), a mean-value bank: from one spacing
/// above [`GUITAR_TOP`] to [`GUITAR_TOP_HIGHEST`], a mode every `1/n` ([`guitar_top_density`]) as
/// on the plate, or every `(r − 1)f` ([`GUITAR_TOP_RATIO`]) where that is wider, each moved by a
/// fixed jitter of up to ±35 % of its spacing ([`mode_jitter`], as the soundboard's). Each mode's
/// mass at the bridge is `n_j/(4G)` ([`mean_value_mass`]) from the bank's own density `n_j`
/// ([`guitar_top_conductance`]); its loss factor is the top's resonance's, `1/Q₊`, times `n/n_j`,
/// so that where a mode stands for several the bank's modes overlap as the plate's do.
pub fn guitar_top_modes() -> Vec<BridgeMode> {
    let (density, conductance) = (guitar_top_density(), guitar_top_conductance());
    let spacing = |f: f64| (1.0 / density).max((GUITAR_TOP_RATIO - 1.0) * f);
    let mut modes = Vec::new();
    let mut nominal = GUITAR_TOP + spacing(GUITAR_TOP);
    while nominal <= GUITAR_TOP_HIGHEST {
        let step = spacing(nominal);
        let bank_density = 1.0 / step;
        modes.push(BridgeMode {
            frequency: nominal + mode_jitter(modes.len()) * step,
            mass: mean_value_mass(bank_density, conductance),
            loss_factor: density / bank_density / GUITAR_Q.1,
        });
        nominal += step;
    }
    modes
}

/// Area of a concert grand's soundboard (m²).
pub const SOUNDBOARD_AREA: f64 = 1.8;

/// Coincidence frequency of the soundboard (Hz): where the bending wave's speed in the board
/// reaches the speed of sound. Below it a plate radiates from its edges and corners only.
pub const SOUNDBOARD_COINCIDENCE: f64 = 1400.0;

/// The radiation efficiency of the piano's soundboard at `frequency` (Hz), 0 to 1 (module docs,
/// docs/physics.md §13.2): [`radiation_efficiency`] of a board of [`SOUNDBOARD_AREA`] below its
/// [`SOUNDBOARD_COINCIDENCE`].
pub fn soundboard_radiation_efficiency(frequency: f64) -> f64 {
    radiation_efficiency(frequency, SOUNDBOARD_AREA, SOUNDBOARD_COINCIDENCE)
}

/// The radiation efficiency of a plate of `area` (m²) with coincidence frequency `coincidence`
/// (Hz) at `frequency` (Hz), 0 to 1: a baffled piston of that area, `(ka)²/(2 + (ka)²)` (its
/// limits `(ka)²/2` and 1, `a = √(area/π)`), times the edge-radiation law `√(f/f_c)` below
/// coincidence, where the plate's bending waves are slower than sound and only its edges and
/// corners radiate.
pub fn radiation_efficiency(frequency: f64, area: f64, coincidence: f64) -> f64 {
    let radius = (area / std::f64::consts::PI).sqrt();
    let ka = std::f64::consts::TAU * frequency / SPEED_OF_SOUND * radius;
    let piston = ka * ka / (2.0 + ka * ka);
    piston * (frequency / coincidence).sqrt().min(1.0)
}

/// A body stepping exactly under a held force (module docs): force in, radiated out.
#[derive(Debug, Clone)]
pub struct Body {
    /// `Re λ`, `Im λ`, `Re γ`, `Im γ` of each mode, padded with inert modes to whole chunks.
    lambda: [Vec<f64>; 2],
    gamma: [Vec<f64>; 2],
    /// `|β|²` (m²/(N·s)²): the weight of `|w|²` in the silence test.
    beta2: Vec<f64>,
    /// `Re w`, `Im w` (N).
    w: [Vec<f64>; 2],
    /// What the listener hears, the sample rate (Hz) and, heard as acceleration, the latest
    /// `Σ r_j v_j` (what the next sample's mean acceleration is taken from).
    heard: Heard,
    sample_rate: f64,
    last: f64,
    /// Whether every mode is exactly at rest (zero), as [`reset`](Self::reset) leaves them: then
    /// silence in gives silence out without looking at the modes.
    resting: bool,
    /// Samples stepped since the last multiple of [`REST_CHECK`]: where the silence test falls.
    clock: usize,
    /// The vector unit the steps run on.
    isa: Isa,
}

/// Below this sum over the modes of `|z_j|²` (m²/s²), a body has fallen silent.
const SILENT: f64 = 1e-40;

/// Samples between the silence tests of a ringing body. They fall on a fixed grid of the samples
/// it has stepped, so that where it comes to rest does not depend on how its input is cut into
/// calls.
const REST_CHECK: usize = 1024;

/// Samples between the flushes of a ringing body's quiet modes, on the same grid.
const FLUSH_INTERVAL: usize = 64;

/// Below this `|z_j|²` (m²/s²) a mode is brought to rest at a flush: a motion of 10⁻²² m/s,
/// far below anything heard and far above the subnormal numbers, which a mode decaying on its
/// own would otherwise reach (and, rounding, cycle among) long before the whole body is silent,
/// each operation on them costing up to a hundred times a normal one on some processors.
const FLUSH_BELOW: f64 = 1e-44;

/// Most samples one pass of [`Step`] runs (its partial sums live on the stack).
const RUN: usize = 64;

/// The complex product `(a + ib)(c + id)`.
fn times((a, b): (f64, f64), (c, d): (f64, f64)) -> (f64, f64) {
    (a * c - b * d, a * d + b * c)
}

impl Body {
    /// `params` at `sample_rate` (Hz). Allocates: build it before the audio thread runs.
    pub fn new(params: &BodyParams, sample_rate: f64) -> Self {
        let dt = 1.0 / sample_rate;
        let kept: Vec<&RadiatingMode> = params.modes.iter().filter(|m| m.mode.frequency < 0.49 * sample_rate).collect();
        let padded = kept.len().div_ceil(LANES) * LANES;
        let zeros = || vec![0.0; padded];
        let mut body = Self {
            lambda: [zeros(), zeros()],
            gamma: [zeros(), zeros()],
            beta2: zeros(),
            w: [zeros(), zeros()],
            heard: params.heard,
            sample_rate,
            last: 0.0,
            resting: true,
            clock: 0,
            isa: Isa::detect(),
        };
        for (j, m) in kept.iter().enumerate() {
            let w0 = std::f64::consts::TAU * m.mode.frequency;
            let sigma = 0.5 * m.mode.loss_factor.min(1.0) * w0;
            let wd = (w0 * w0 - sigma * sigma).sqrt();
            let (sin, cos) = (wd * dt).sin_cos();
            let decay = (-sigma * dt).exp();
            let lambda = (decay * cos, decay * sin);
            // β = (λ − 1)/(sM) = (λ − 1)·s̄/(ω_0² M).
            let scale = 1.0 / (w0 * w0 * m.mode.mass);
            let beta = times((lambda.0 - 1.0, lambda.1), (-sigma * scale, -wd * scale));
            // The hold's droop, made up for at the mode's own frequency (module docs).
            let x = 0.5 * wd * dt;
            let r = m.radiation * x / x.sin();
            let gamma = times((r, r * sigma / wd), beta);
            (body.lambda[0][j], body.lambda[1][j]) = lambda;
            (body.gamma[0][j], body.gamma[1][j]) = gamma;
            body.beta2[j] = beta.0 * beta.0 + beta.1 * beta.1;
        }
        body
    }

    /// How many modes step, padded with inert ones to a whole number of lanes.
    pub fn modes(&self) -> usize {
        self.beta2.len()
    }

    /// As made: every mode at rest, and the silence tests' grid from the next sample.
    pub fn reset(&mut self) {
        self.rest_modes();
        self.last = 0.0;
        self.clock = 0;
    }

    /// Bring every mode to rest.
    fn rest_modes(&mut self) {
        self.w.iter_mut().for_each(|w| w.fill(0.0));
        self.resting = true;
    }

    /// Bring the modes whose motion is below [`FLUSH_BELOW`] to rest (a select per mode, not a
    /// branch).
    fn flush_quiet_modes(&mut self) {
        let [re, im] = &mut self.w;
        for ((b, x), y) in self.beta2.iter().zip(re.iter_mut()).zip(im.iter_mut()) {
            let quiet = b * (*x * *x + *y * *y) < FLUSH_BELOW;
            (*x, *y) = if quiet { (0.0, 0.0) } else { (*x, *y) };
        }
    }

    /// Whether every mode is at rest (to `SILENT`).
    pub fn is_silent(&self) -> bool {
        let [re, im] = &self.w;
        let motion: f64 = self.beta2.iter().zip(re.iter().zip(im)).map(|(b, (x, y))| b * (x * x + y * y)).sum();
        motion < SILENT
    }

    /// Replace the bridge force in `io` (N, one value per sample) by the radiated signal
    /// (module docs), sample by sample: for a body heard by its acceleration, each sample's
    /// mean acceleration. A body at rest given no force stays at rest at no cost (it does not
    /// even look at its modes, which matters when a call is a single sample). A ringing body's
    /// quiet modes are flushed to rest on a fixed grid of the samples it steps (every 64), and
    /// the body is tested for silence on it (every 1024) and brought to rest once silent: the
    /// same samples come out however the input is cut into calls (unless forces beyond any
    /// instrument's overflow the state, which silences the rest of the call).
    pub fn process(&mut self, io: &mut [f64]) {
        // A force that is not finite (no voice hands one on) is dropped, sample by sample.
        io.iter_mut().filter(|f| !f.is_finite()).for_each(|f| *f = 0.0);
        let silent_in = |x: &[f64]| x.iter().all(|&f| f == 0.0);
        if self.resting && self.last == 0.0 && silent_in(io) {
            self.clock = (self.clock + io.len()) % REST_CHECK;
            return;
        }
        let mut done = 0;
        while done < io.len() {
            let end = io.len().min(done + FLUSH_INTERVAL - self.clock % FLUSH_INTERVAL);
            let run = &mut io[done..end];
            // Modes at rest given no force stay exactly at rest: stepping them changes nothing.
            if !(self.resting && silent_in(run)) {
                self.resting = false;
                let [w_re, w_im] = &mut self.w;
                for piece in run.chunks_mut(RUN) {
                    self.isa.run(Step {
                        lambda: [chunks(&self.lambda[0]), chunks(&self.lambda[1])],
                        gamma: [chunks(&self.gamma[0]), chunks(&self.gamma[1])],
                        w: [chunks_mut(w_re), chunks_mut(w_im)],
                        io: piece,
                    });
                }
            }
            // Every mode, the padded ones too, adds `γ·w` to each output, so a state gone
            // non-finite shows in the outputs (`0·∞` and `γ·NaN` are NaN): looking at them is
            // enough.
            let bad = run.iter().position(|y| !y.is_finite());
            let good = bad.unwrap_or(run.len());
            if self.heard == Heard::Acceleration {
                for y in &mut run[..good] {
                    (*y, self.last) = ((*y - self.last) * self.sample_rate, *y);
                }
            }
            if let Some(bad) = bad {
                // Silence from that sample on, the modes at rest, the grid kept.
                io[done + bad..].fill(0.0);
                self.rest_modes();
                self.last = 0.0;
                self.clock = (self.clock + io.len() - done) % REST_CHECK;
                return;
            }
            self.clock = (self.clock + run.len()) % REST_CHECK;
            done = end;
            if self.clock.is_multiple_of(FLUSH_INTERVAL) && !self.resting {
                self.flush_quiet_modes();
                if self.clock == 0 && self.is_silent() {
                    self.rest_modes();
                }
            }
        }
    }
}

/// One run of at most [`RUN`] samples of a body's exact steps (module docs).
struct Step<'a> {
    lambda: [&'a [Chunk]; 2],
    gamma: [&'a [Chunk]; 2],
    w: [&'a mut [Chunk]; 2],
    io: &'a mut [f64],
}

impl Step<'_> {
    /// The `G` chunks from `first` across the run, in registers; each sample's output added to
    /// its partial sum in `sums`.
    #[inline(always)]
    fn group<L: Lanes, const G: usize>(&mut self, s: L, first: usize, sums: &mut [Chunk]) {
        let zero = s.splat(0.0);
        let (mut lr, mut li, mut gr, mut gi, mut wr, mut wi) =
            ([zero; G], [zero; G], [zero; G], [zero; G], [zero; G], [zero; G]);
        for i in 0..G {
            let c = first + i;
            (lr[i], li[i]) = (s.load(&self.lambda[0][c]), s.load(&self.lambda[1][c]));
            (gr[i], gi[i]) = (s.load(&self.gamma[0][c]), s.load(&self.gamma[1][c]));
            (wr[i], wi[i]) = (s.load(&self.w[0][c]), s.load(&self.w[1][c]));
        }
        for (sum, &force) in sums.iter_mut().zip(self.io.iter()) {
            let f = s.splat(force);
            let mut acc = s.load(sum);
            for i in 0..G {
                let re = s.add(s.sub(s.mul(lr[i], wr[i]), s.mul(li[i], wi[i])), f);
                let im = s.add(s.mul(lr[i], wi[i]), s.mul(li[i], wr[i]));
                acc = s.add(acc, s.sub(s.mul(gr[i], re), s.mul(gi[i], im)));
                (wr[i], wi[i]) = (re, im);
            }
            s.store(sum, acc);
        }
        for i in 0..G {
            s.store(&mut self.w[0][first + i], wr[i]);
            s.store(&mut self.w[1][first + i], wi[i]);
        }
    }

    /// The run (at most `S` samples) with its partial sums in an array of `S`.
    #[inline(always)]
    fn sweep<L: Lanes, const S: usize>(mut self, s: L) {
        let mut sums = [[0.0; LANES]; S];
        let sums = &mut sums[..self.io.len().min(S)];
        let n = self.w[0].len();
        // As many chunks as a register-resident run holds: a chunk's four coefficients and two
        // states, six registers, are a little more than `free_run`'s five, but measured on AVX
        // the second chunk's latency hiding outweighs what spills (44 against 61 ns a sample).
        let whole = L::RESIDENT.clamp(1, 4);
        let mut first = 0;
        while first < n {
            let size = whole.min(n - first);
            match size {
                4 => self.group::<L, 4>(s, first, sums),
                3 => self.group::<L, 3>(s, first, sums),
                2 => self.group::<L, 2>(s, first, sums),
                _ => self.group::<L, 1>(s, first, sums),
            }
            first += size;
        }
        for (y, sum) in self.io.iter_mut().zip(sums.iter()) {
            *y = s.sum(s.load(sum));
        }
    }
}

impl Kernel for Step<'_> {
    type Output = ();

    #[inline(always)]
    fn run<L: Lanes>(self, s: L) {
        // The partial sums live on the stack, zeroed for the run's length: a run of one sample
        // (a one-sample control block) does not clear a whole run's worth.
        match self.io.len() {
            0..=1 => self.sweep::<L, 1>(s),
            2..=8 => self.sweep::<L, 8>(s),
            _ => self.sweep::<L, RUN>(s),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A body's step is exact: a sine force (constant over each sample) drives it, and after
    /// the start has died out the output's amplitude at that frequency is the transmittance's to
    /// 0.5 % of the larger of the two and the body's mean gain (which is 1) up to 1 kHz at
    /// 48 kHz, for the piano's soundboard (heard by its velocity) and the guitar (by its
    /// acceleration, around its resonances): the hold, sampling the force at each sample's middle,
    /// is all that differs.
    #[test]
    fn a_body_steps_to_its_transmittance() {
        let fs = 48_000.0;
        let cases = [
            (BodyParams::piano(), &[110.0, 262.0, 523.0, 1000.0][..]),
            (BodyParams::guitar(), &[60.0, 104.0, 127.0, 219.0, 1000.0][..]),
        ];
        for (params, frequencies) in cases {
            body_follows_its_transmittance(&params, frequencies, fs, (5e-3, 1.0));
        }
    }

    /// The hold's droop is made up for: the treble comes out as the transmittance says at
    /// every rate, from 150 Hz to 10 kHz within 4 % of it at 22.05 kHz (measured 3.4 %; the hold
    /// alone takes 28 % off the piano at 10 kHz), 1 % at 44.1 kHz (0.5 %; 7.6 % without the
    /// correction) and 0.2 % at 96 kHz (0.1 %; 1.7 % without).
    #[test]
    fn a_body_steps_to_its_transmittance_in_the_treble_at_every_rate() {
        for (fs, tolerance) in [(22_050.0, 0.04), (44_100.0, 0.01), (96_000.0, 0.002)] {
            for params in [BodyParams::piano(), BodyParams::guitar()] {
                let frequencies = [150.0, 1_000.0, 4_000.0, 6_000.0, 8_000.0, 10_000.0];
                body_follows_its_transmittance(&params, &frequencies, fs, (tolerance, 0.0));
            }
        }
    }

    /// `params` stepped at `fs` (Hz) against its transmittance at `frequencies` (Hz): amplitudes
    /// within `tolerance` of the larger of the transmittance's and `floor`.
    fn body_follows_its_transmittance(
        params: &BodyParams,
        frequencies: &[f64],
        fs: f64,
        (tolerance, floor): (f64, f64),
    ) {
        for &f in frequencies {
            let mut body = Body::new(params, fs);
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
            println!("{f} Hz at {fs} Hz: amplitude {got:.6} vs {want:.6} ({:+.2} %)", 100.0 * (got / want - 1.0));
            assert!((got - want).abs() < tolerance * want.max(floor), "{f} Hz at {fs} Hz: {got} vs {want}");
        }
    }

    /// The guitar's lowest two modes are Christensen and Vistisen's two-mass model: their
    /// mobility at the bridge vanishes at the Helmholtz frequency (within 0.1 Hz of 127 Hz, losses
    /// aside) and tends to the top plate's mass above (their inverse masses sum to `1/m_p`, to
    /// 1e-12); alone they radiate as a bass-reflex box, the pressure falling 24 dB per octave
    /// below the air resonance (10 to 20 Hz: 24 dB within 0.5 dB, the lossless model's 24.2).
    /// With the top's higher modes the whole body's power gain is 1 over 1–4 kHz and its two
    /// resonances stand above that plateau (measured +7.1 and +19.0 dB; +18.4 and +30.3 with the
    /// pair alone, whose response is flat above the top's resonance).
    #[test]
    fn the_guitar_body_starts_with_the_two_mass_model() {
        let body = BodyParams::guitar();
        body.validate().unwrap();
        let pair = BodyParams { modes: body.modes[..2].to_vec(), heard: Heard::Acceleration };
        let inverse: f64 = pair.modes.iter().map(|m| 1.0 / m.mode.mass).sum();
        assert!((inverse * GUITAR_TOP_MASS - 1.0).abs() < 1e-12, "{inverse}");
        let mobility = |f: f64| -> f64 {
            let w = std::f64::consts::TAU * f;
            pair.modes
                .iter()
                .map(|m| w / (m.mode.mass * ((std::f64::consts::TAU * m.mode.frequency).powi(2) - w * w)))
                .sum()
        };
        let zero =
            (0..=400).map(|k| 125.0 + 0.01 * k as f64).min_by(|a, b| mobility(*a).abs().total_cmp(&mobility(*b).abs()));
        let zero = zero.unwrap();
        let db = |body: &BodyParams, f: f64| {
            let (re, im) = body.response(f);
            10.0 * (re * re + im * im).log10()
        };
        let octave = db(&pair, 20.0) - db(&pair, 10.0);
        let (air, top) = (db(&body, GUITAR_AIR), db(&body, GUITAR_TOP));
        println!("mobility zero at {zero:.2} Hz; 10–20 Hz rises {octave:.2} dB; resonances {air:+.1} and {top:+.1} dB");
        assert!((zero - GUITAR_HELMHOLTZ).abs() < 0.1, "{zero}");
        assert!((octave - 24.0).abs() < 0.5, "{octave}");
        assert!((body.mean_power_gain((1000.0, 4000.0)) - 1.0).abs() < 1e-12);
        assert!(air > 6.0 && top > 6.0, "{air} {top}");
    }

    /// Above its lowest mode the guitar's top is a plate, drawn from the two-mass model's own
    /// numbers (docs/physics.md §13.5): its lowest mode with the hole closed is 206.5 Hz, from
    /// `f₋² + f₊² = f_p² + f_h²`; where the bank's modes lie a plate's spacing `1/n` apart (below
    /// the frequency where that is a tenth of their frequency; the six below 1 kHz checked), each
    /// has the plate's mass `4m_p` and the top's loss factor `1/Q₊`; and the bank's mean
    /// conductance over 400 Hz – 8 kHz is the plate's, `n/(16m_p)`, within 10 % (measured −3 %):
    /// what drains the string's partials above the top's resonance.
    #[test]
    fn the_guitar_top_above_its_lowest_mode_is_a_plate() {
        let closed = guitar_top_closed();
        assert!((closed - 206.5).abs() < 0.05, "{closed}");
        let (density, conductance) = (guitar_top_density(), guitar_top_conductance());
        let modes = guitar_top_modes();
        // Below `0.8/(n(r − 1))` every mode is on the plate's spacing, jitter included.
        let plate: Vec<&BridgeMode> =
            modes.iter().filter(|m| m.frequency < 0.8 / (density * (GUITAR_TOP_RATIO - 1.0))).collect();
        assert!(plate.len() >= 6, "{}", plate.len());
        for m in plate {
            assert!((m.mass / guitar_top_plate_mass() - 1.0).abs() < 1e-12, "{m:?}");
            assert!((m.loss_factor * GUITAR_Q.1 - 1.0).abs() < 1e-12, "{m:?}");
        }
        let bank = BridgeParams { modes: BodyParams::guitar().modes.iter().map(|m| m.mode).collect() };
        let (n, (low, high)) = (400, (400.0f64, 8000.0f64));
        let mean = (0..n).map(|k| bank.mobility(low * (high / low).powf((k as f64 + 0.5) / n as f64)).0).sum::<f64>()
            / n as f64;
        println!(
            "{} top modes; n = {density:.5} modes/Hz; G = {conductance:.3e} s/kg, the bank's mean {mean:.3e}",
            modes.len()
        );
        assert!((mean / conductance - 1.0).abs() < 0.1, "{mean} {conductance}");
    }

    /// The guitar's stereo picture (docs/physics.md §13.6): the pair alone in the centre, the
    /// higher modes alternately left and right. Where the pair carries the sound, 80–250 Hz, the
    /// modes on either side have a power gain 25 dB or more below the pair's (measured 27 and 41),
    /// so the bass stays in the centre; over 1–4 kHz the two sides' gains are within 1.5 dB of
    /// each other (measured 1.1), so the picture leans to neither side.
    #[test]
    fn the_guitar_body_keeps_its_pair_in_the_centre_and_its_sides_balanced() {
        let body = BodyParams::guitar();
        let gain = |side: Side, band: (f64, f64)| {
            let modes = body.modes.iter().filter(|m| m.side == side).copied().collect();
            BodyParams { modes, heard: body.heard }.mean_power_gain(band)
        };
        let sides = [Side::Centre, Side::Left, Side::Right];
        assert_eq!(body.modes.iter().take(2).map(|m| m.side).collect::<Vec<_>>(), [Side::Centre; 2]);
        assert!(body.modes[2..].iter().all(|m| m.side != Side::Centre));
        assert!(body.modes[2..].windows(2).all(|w| w[0].side != w[1].side), "neighbours alternate");
        let db = |a: f64, b: f64| 10.0 * (a / b).log10();
        let [pair, left, right] = sides.map(|s| gain(s, (80.0, 250.0)));
        println!(
            "80–250 Hz: pair {pair:.4}, left {left:.4} ({:.1} dB), right {right:.4} ({:.1} dB)",
            db(left, pair),
            db(right, pair)
        );
        assert!(db(left, pair) <= -25.0 && db(right, pair) <= -25.0);
        let [_, left, right] = sides.map(|s| gain(s, (1000.0, 4000.0)));
        println!("1–4 kHz: left {left:.3}, right {right:.3} ({:.2} dB apart)", db(left, right));
        assert!(db(left, right).abs() <= 1.5);
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

    /// The complex step is the exact zero-order-hold step of each mode's position and velocity,
    /// `x' = A₁₁x + A₁₂v + B₁F/M`, `v' = A₂₁x + A₂₂v + B₂F/M` (the matrix exponential, written
    /// out here mode by mode), each mode heard with its hold made up for at its own frequency:
    /// over 3,000 samples of a varying force, at 44.1 and 96 kHz, the outputs agree to 1e-12 of
    /// their peak; and every vector unit gives the same bits.
    #[test]
    fn the_complex_step_is_the_exact_real_step_on_every_vector_unit() {
        let params = BodyParams::piano();
        for fs in [44_100.0, 96_000.0] {
            let force: Vec<f64> = (0..3000).map(|k| (k as f64 * 0.37).sin() + (k as f64 * 0.011).cos()).collect();
            let dt = 1.0 / fs;
            let mut want = vec![0.0; force.len()];
            for m in params.modes.iter().filter(|m| m.mode.frequency < 0.49 * fs) {
                let w0 = std::f64::consts::TAU * m.mode.frequency;
                let sigma = 0.5 * m.mode.loss_factor * w0;
                let wd = (w0 * w0 - sigma * sigma).sqrt();
                let (e, (sn, c)) = ((-sigma * dt).exp(), (wd * dt).sin_cos());
                let (a11, a12) = (e * (c + sigma * sn / wd), e * sn / wd);
                let (a21, a22) = (-w0 * w0 * e * sn / wd, e * (c - sigma * sn / wd));
                let (b1, b2) = ((1.0 - a11) / (w0 * w0) / m.mode.mass, a12 / m.mode.mass);
                let (mut x, mut v) = (0.0, 0.0);
                let made_up = (0.5 * wd * dt) / (0.5 * wd * dt).sin();
                for (y, f) in want.iter_mut().zip(&force) {
                    (x, v) = (a11 * x + a12 * v + b1 * f, a21 * x + a22 * v + b2 * f);
                    *y += m.radiation * made_up * v;
                }
            }
            let peak = want.iter().fold(0.0f64, |m, y| m.max(y.abs()));
            let mut first: Option<Vec<u64>> = None;
            for isa in Isa::available() {
                let mut body = Body::new(&params, fs);
                body.isa = isa;
                let mut got = force.clone();
                // Runs of every length the instrument's blocks may take.
                let mut done = 0;
                for len in [1, 63, 64, 65, 256, 7].iter().cycle() {
                    let end = (done + len).min(got.len());
                    body.process(&mut got[done..end]);
                    done = end;
                    if done == got.len() {
                        break;
                    }
                }
                let worst = got.iter().zip(&want).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
                println!("{fs} Hz, {isa:?}: worst {:.1e} of the peak {peak:.3}", worst / peak);
                assert!(worst < 1e-12 * peak, "{isa:?}: {worst:e}");
                let bits: Vec<u64> = got.iter().map(|y| y.to_bits()).collect();
                match &first {
                    Some(first) => assert!(first == &bits, "{isa:?} gives other bits"),
                    None => first = Some(bits),
                }
            }
        }
    }

    /// A struck body given silence rings on (the shortcut for a body at rest does not cut it
    /// off) until it has died away below the silence test, then rests and stays at rest: calls
    /// of one, five and 37 samples give the bits of 64-sample calls all the way, the ring lasting
    /// half a second on and the rest coming at the same sample.
    #[test]
    fn a_ringing_body_rings_and_comes_to_rest_alike_however_its_calls_are_cut() {
        let params = BodyParams::piano();
        let samples = 48_000 * 12;
        let mut by_block = vec![0.0; samples];
        by_block[0] = 1.0;
        let mut whole = Body::new(&params, 48_000.0);
        by_block.chunks_mut(64).for_each(|block| whole.process(block));
        assert!(whole.resting, "still ringing 12 s on");
        let late = by_block[24_000..24_064].iter().map(|y| y * y).sum::<f64>();
        println!("0.5 s after the strike, 64 samples' energy {late:e}");
        assert!(late > 0.0, "the body still rings half a second on");
        let last = by_block.iter().rposition(|&y| y != 0.0).unwrap();
        println!("last sound {:.3} s after the strike", last as f64 / 48_000.0);
        assert!(last < samples - 48_000, "the body rests a second before the end");
        for len in [1, 5, 37] {
            let mut cut = vec![0.0; samples];
            cut[0] = 1.0;
            let mut body = Body::new(&params, 48_000.0);
            cut.chunks_mut(len).for_each(|call| body.process(call));
            assert!(cut == by_block, "calls of {len} samples");
            assert!(body.resting && body.is_silent());
        }
        let mut silence = [0.0; 1];
        whole.process(&mut silence);
        assert!(whole.resting && silence[0] == 0.0);
    }

    /// A force sample that is not finite is dropped as if it were zero, however the calls are
    /// cut: with NaN and infinities among a driving force, calls of 1, 37 and 64 samples give the
    /// bits of the force with zeros there.
    #[test]
    fn a_non_finite_force_sample_is_dropped_however_the_calls_are_cut() {
        let mut force: Vec<f64> = (0..4_000).map(|n| (0.01 * n as f64).sin()).collect();
        let render = |force: &[f64], len: usize| {
            let mut body = Body::new(&BodyParams::piano(), 48_000.0);
            let mut io = force.to_vec();
            io.chunks_mut(len).for_each(|call| body.process(call));
            io
        };
        for at in [1_500, 1_501, 2_900] {
            force[at] = 0.0;
        }
        let zeros = render(&force, 64);
        assert!(zeros.iter().all(|y| y.is_finite()) && zeros[3_000..].iter().any(|&y| y != 0.0));
        for (at, bad) in [(1_500, f64::NAN), (1_501, f64::INFINITY), (2_900, f64::NEG_INFINITY)] {
            force[at] = bad;
        }
        for len in [1, 37, 64] {
            assert!(render(&force, len) == zeros, "calls of {len}");
        }
    }

    /// A ringing body's modes never hold a subnormal state, and their flushes change nothing
    /// heard: the piano's soundboard struck by 1 N and left to ring for 12 s at 48 kHz in
    /// 64-sample calls (where its 16 kHz mode, decaying alone, went subnormal 0.7 s on and cycled
    /// among the smallest numbers until the whole board fell silent seconds later) and in calls
    /// of 37 samples, which flush at the same samples and give the same bits.
    #[test]
    fn a_ringing_body_never_holds_a_subnormal_state() {
        let run = |len: usize| {
            let mut body = Body::new(&BodyParams::piano(), 48_000.0);
            let mut io = vec![0.0; 48_000 * 12];
            io[0] = 1.0;
            for (call, chunk) in io.chunks_mut(len).enumerate() {
                body.process(chunk);
                let subnormal = body.w.iter().flatten().position(|x| x.is_subnormal());
                assert!(subnormal.is_none(), "calls of {len}: call {call}, mode {subnormal:?} subnormal");
            }
            io
        };
        assert!(run(64) == run(37));
    }

    /// No force, no state: a body costs nothing and outputs zeros; a non-finite force is
    /// dropped instead of filling it with NaN.
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
