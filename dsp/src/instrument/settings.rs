//! Instrument settings: what host parameters control, in physical units, with safe clamping.

use crate::contact::Method;

/// Most QSA segments the instrument offers (every voice's spline is sized for it up front).
pub const MAX_SEGMENTS: usize = 64;

/// Longest control block N_b (samples).
pub const MAX_BLOCK: usize = 256;

/// The felt's stiffness the instrument allows, relative to the per-note rule (×): the
/// `Hardness` setting's range, which a note's CC74 stays within too.
pub const HARDNESS_RANGE: (f64, f64) = (0.1, 10.0);

/// The output gain's range (dB): −36 to +12.
pub const GAIN_RANGE_DB: (f64, f64) = (-36.0, 12.0);

/// Which instrument the engine is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Mode {
    /// Hammer–string: a piano.
    #[default]
    Piano,
    /// Slide–string: a slide guitar.
    Slide,
}

/// Where the slide's hand height comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum HandSource {
    /// The `hand_height` setting.
    #[default]
    Parameter,
    /// The mod wheel (CC1) of the note's channel (or of its MPE zone's master channel, the
    /// latest of the two): 0 lifts the slide, full presses it.
    ModWheel,
    /// Channel pressure of the note's channel (per note with MPE; the master channel's, sent
    /// later, reaches every note of its zone).
    ChannelPressure,
    /// Poly pressure of the note's key.
    PolyPressure,
    /// CC74 of the note's channel, MPE's third dimension (per note with MPE; the master channel's,
    /// sent later, reaches every note of its zone), or the note's own brightness where the host
    /// sent one.
    Timbre,
}

/// What the slide guitar's listener hears.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SlideBody {
    /// An electric guitar: the string's velocity under a magnetic pickup, through its circuit
    /// ([`crate::pickup`]).
    #[default]
    Pickup,
    /// An acoustic guitar: the string ends on the guitar's body (its air and top resonances and
    /// the top's higher modes), which it drives and which drains it, and the body radiates
    /// ([`crate::body::BodyParams::guitar`]).
    Acoustic,
}

/// Lowest and highest hand height a controller maps to (m): lifted at 0, pressed at full.
pub const HAND_RANGE: (f64, f64) = (2e-3, -2e-3);

/// Farthest the `hand_height` setting (with a note's offset) holds the hand above or presses
/// it below the string's line (m): the setting reaches past a controller's [`HAND_RANGE`].
pub const HAND_HEIGHT_LIMIT: f64 = 3e-3;

/// Everything the host can set. Piano quantities are relative to the per-note rule
/// ([`crate::preset::piano_note`]), so the keyboard keeps its natural variation; slide quantities
/// are absolute.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Settings {
    /// Piano or slide guitar. New notes use the mode in force; sounding ones ring out.
    pub mode: Mode,
    /// Contact solver of new notes.
    pub method: Method,
    /// QSA segments N of new notes, 1..=[`MAX_SEGMENTS`].
    pub segments: usize,
    /// Control block N_b (samples), 1..=[`MAX_BLOCK`]: controls are sampled every N_b samples.
    pub block: usize,
    /// Highest mode frequency kept in every string (Hz), 1 kHz to 24 kHz (and below Nyquist):
    /// the same modes, and so the same sound, at every sample rate above twice this. A piano
    /// note takes it as it is struck; the slide voices' strings keep the value the instrument
    /// was made with ([`Instrument::new`](super::Instrument::new)).
    pub max_frequency: f64,
    /// Felt stiffness κ relative to the per-note value, 0.1..=10.
    pub hardness: f64,
    /// Hammer mass relative to the per-note value, 0.25..=4.
    pub hammer_mass: f64,
    /// Striking position relative to the per-note value, 0.25..=2.5 (the result is kept in
    /// 0.02..=0.5 of the length).
    pub strike_position: f64,
    /// String damping (b1 and b3 of the per-mode law) relative to the per-note value, 0.1..=20.
    pub damping: f64,
    /// Inharmonicity B relative to the per-note value, 0..=4 (0 is a flexible string).
    pub brightness: f64,
    /// Spread of each unison's tuning, lowest to highest string (cents), 0..=20: every key
    /// detunes its strings by its own pattern of this ([`crate::preset::unison_detune`]).
    pub unison_detune: f64,
    /// Octave stretch relative to octaves tuned beatless on the lower key's second partial,
    /// 0..=2: each key sits this times [`crate::preset::stretch_cents`] from equal temperament
    /// (0 is equal temperament of the fundamentals).
    pub stretch: f64,
    /// Extra decay rate a damper adds when it rests on the string (1/s), 1..=500.
    pub damper_rate: f64,
    /// Time for a damper to settle on or lift off the string (s), 0.001..=0.1.
    pub damper_time: f64,
    /// One end of the sustain pedal's half-way zone, as a fraction of its travel (CC64/127),
    /// 0..=1: up to the lower of the two ends the dampers rest on the strings, from the higher
    /// they are clear of them, and in between they hover ([`crate::instrument::damper_lift`]).
    /// Equal ends make the pedal a switch there.
    pub half_pedal_from: f64,
    /// The zone's other end, 0..=1 (see [`half_pedal_from`](Self::half_pedal_from)).
    pub half_pedal_to: f64,
    /// Output gain (linear), [`GAIN_RANGE_DB`]: 0.0158..=3.98.
    pub gain: f64,
    /// Whether the safety limiter holds the output at or below its ceiling (−0.1 dBFS).
    pub limiter: bool,
    /// Stereo width, −1..=1: each piano key is panned by its place along the bridge, the lowest
    /// key to the left and the highest to the right at 1 (the pianist's view), mirrored below 0
    /// (the audience's), all keys centred at 0; the acoustic guitar body's higher modes are
    /// panned alternately left and right as far (docs/physics.md §13.6).
    pub stereo_width: f64,
    /// Slide position in semitones above the open string, 0..=24 (when not following the key).
    pub slide_position: f64,
    /// Whether the slide follows the played key (legato notes glide there).
    pub follow_key: bool,
    /// Time constant of the slide's glide to a new position (s), 0.001..=2.
    pub glide_time: f64,
    /// Pitch-bend range (semitones of slide travel), 0..=24.
    pub bend_range: f64,
    /// Hand height (m), −3 mm..=3 mm: the slide's rest height; negative presses it on the string.
    pub hand_height: f64,
    /// Where the hand height comes from.
    pub hand_source: HandSource,
    /// Slide mass (kg), 5 g..=200 g.
    pub slide_mass: f64,
    /// Hand stiffness k_H (N/m), 1e2..=1e6.
    pub hand_stiffness: f64,
    /// Hand damping r_H (kg/s), 0..=100.
    pub hand_damping: f64,
    /// Finger damping r (s/m), 0..=50.
    pub finger_damping: f64,
    /// Plucking position, fraction of the length from the nut, 0.5..=0.98.
    pub pluck_position: f64,
    /// Pickup position, fraction of the length from the nut, 0.5..=0.98.
    pub pickup_position: f64,
    /// Resonance of the pickup loaded by its cable (Hz), 1 kHz..=10 kHz
    /// ([`crate::pickup::PickupCircuit`]).
    pub pickup_resonance: f64,
    /// The slide guitar's body: a magnetic pickup or an acoustic body. A note plucked from
    /// silence takes the one in force; a sounding string keeps its own, through the notes that
    /// take it over (legato, or stolen with every voice busy), until it falls silent.
    pub slide_body: SlideBody,
    /// Slide contact stiffness κ (N/m^α), 1e6..=1e13.
    pub slide_kappa: f64,
    /// Slide contact exponent α, 1..=3.
    pub slide_alpha: f64,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            mode: Mode::Piano,
            method: Method::Qsa,
            segments: 6,
            block: 64,
            max_frequency: 20_000.0,
            hardness: 1.0,
            hammer_mass: 1.0,
            strike_position: 1.0,
            damping: 1.0,
            brightness: 1.0,
            unison_detune: 2.5,
            stretch: 1.0,
            damper_rate: 60.0,
            damper_time: 0.01,
            half_pedal_from: 0.2,
            half_pedal_to: 0.8,
            gain: 1.0,
            limiter: true,
            stereo_width: 0.6,
            slide_position: 5.0,
            follow_key: true,
            glide_time: 0.05,
            bend_range: 2.0,
            hand_height: -1.5e-3,
            hand_source: HandSource::Parameter,
            slide_mass: 0.03,
            hand_stiffness: 1e4,
            hand_damping: 5.0,
            finger_damping: 5.0,
            pluck_position: 0.9,
            pickup_position: 0.9,
            pickup_resonance: 3500.0,
            slide_body: SlideBody::Pickup,
            slide_kappa: 1e9,
            slide_alpha: 1.5,
        }
    }
}

/// The linear gain of `db` decibels.
fn db_to_gain(db: f64) -> f64 {
    10f64.powf(db / 20.0)
}

/// `value` clamped to `[lo, hi]`; NaN gives `fallback`.
fn clamp(value: f64, lo: f64, hi: f64, fallback: f64) -> f64 {
    if value.is_nan() { fallback } else { value.clamp(lo, hi) }
}

impl Settings {
    /// The same settings with every value brought into its range (NaN becomes the default):
    /// whatever a host sends, the engine gets something it can play.
    pub fn sanitized(&self) -> Self {
        let d = Self::default();
        Self {
            method: self.method,
            segments: self.segments.clamp(1, MAX_SEGMENTS),
            block: self.block.clamp(1, MAX_BLOCK),
            max_frequency: clamp(self.max_frequency, 1_000.0, 24_000.0, d.max_frequency),
            hardness: clamp(self.hardness, HARDNESS_RANGE.0, HARDNESS_RANGE.1, d.hardness),
            hammer_mass: clamp(self.hammer_mass, 0.25, 4.0, d.hammer_mass),
            strike_position: clamp(self.strike_position, 0.25, 2.5, d.strike_position),
            damping: clamp(self.damping, 0.1, 20.0, d.damping),
            brightness: clamp(self.brightness, 0.0, 4.0, d.brightness),
            unison_detune: clamp(self.unison_detune, 0.0, 20.0, d.unison_detune),
            stretch: clamp(self.stretch, 0.0, 2.0, d.stretch),
            half_pedal_from: clamp(self.half_pedal_from, 0.0, 1.0, d.half_pedal_from),
            half_pedal_to: clamp(self.half_pedal_to, 0.0, 1.0, d.half_pedal_to),
            damper_rate: clamp(self.damper_rate, 1.0, 500.0, d.damper_rate),
            damper_time: clamp(self.damper_time, 0.001, 0.1, d.damper_time),
            gain: clamp(self.gain, db_to_gain(GAIN_RANGE_DB.0), db_to_gain(GAIN_RANGE_DB.1), d.gain),
            limiter: self.limiter,
            stereo_width: clamp(self.stereo_width, -1.0, 1.0, d.stereo_width),
            mode: self.mode,
            slide_position: clamp(self.slide_position, 0.0, 24.0, d.slide_position),
            follow_key: self.follow_key,
            glide_time: clamp(self.glide_time, 0.001, 2.0, d.glide_time),
            bend_range: clamp(self.bend_range, 0.0, 24.0, d.bend_range),
            hand_height: clamp(self.hand_height, -HAND_HEIGHT_LIMIT, HAND_HEIGHT_LIMIT, d.hand_height),
            hand_source: self.hand_source,
            slide_mass: clamp(self.slide_mass, 0.005, 0.2, d.slide_mass),
            hand_stiffness: clamp(self.hand_stiffness, 1e2, 1e6, d.hand_stiffness),
            hand_damping: clamp(self.hand_damping, 0.0, 100.0, d.hand_damping),
            finger_damping: clamp(self.finger_damping, 0.0, 50.0, d.finger_damping),
            pluck_position: clamp(self.pluck_position, 0.5, 0.98, d.pluck_position),
            pickup_position: clamp(self.pickup_position, 0.5, 0.98, d.pickup_position),
            pickup_resonance: clamp(self.pickup_resonance, 1000.0, 10_000.0, d.pickup_resonance),
            slide_body: self.slide_body,
            slide_kappa: clamp(self.slide_kappa, 1e6, 1e13, d.slide_kappa),
            slide_alpha: clamp(self.slide_alpha, 1.0, 3.0, d.slide_alpha),
        }
    }
}

/// Hammer speed (m/s) for a MIDI note velocity `velocity` in (0, 1]: exponential from 0.5 m/s
/// (pianissimo) to 6 m/s (fortissimo), `v = 0.5 · 12^velocity`, so equal velocity steps are
/// equal ratios of speed (and roughly equal steps in loudness).
///
/// Slower strikes are left out on purpose: below about 0.45 m/s the per-note rule's top-octave
/// hammers, whose contact lasts several periods of their strings, excite the few partials below
/// 20 kHz unevenly, so that C7 to C8 grow quieter as the hammer speeds up and neighbouring keys
/// differ by 2.5 to 3 LU whatever the voicing (`cargo xtask loudness`).
pub fn hammer_speed(velocity: f64) -> f64 {
    let v = if velocity.is_nan() { 0.0 } else { velocity.clamp(0.0, 1.0) };
    0.5 * 12f64.powf(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn velocity_curve_spans_the_documented_range() {
        assert!((hammer_speed(0.0) - 0.5).abs() < 1e-12);
        assert!((hammer_speed(1.0) - 6.0).abs() < 1e-12);
        assert!((hammer_speed(0.5) - (0.5f64 * 6.0).sqrt()).abs() < 1e-12, "geometric mid-point");
        assert_eq!(hammer_speed(f64::NAN), 0.5);
    }

    #[test]
    fn sanitizing_clamps_and_replaces_nan() {
        let s = Settings { hardness: f64::NAN, gain: f64::INFINITY, segments: 0, block: 100_000, ..Default::default() };
        let c = s.sanitized();
        assert_eq!(c.hardness, 1.0);
        assert!((c.gain - 3.981_071_705_534_972).abs() < 1e-12, "+12 dB: {}", c.gain);
        assert_eq!(c.segments, 1);
        assert_eq!(c.block, MAX_BLOCK);
    }
}
