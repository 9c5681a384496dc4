//! The playable instrument: a fixed pool of voices driven by note and controller events, shared
//! by the plugin and the offline MIDI renderer.
//!
//! # Piano mode
//!
//! - A key gets the string and hammer of the per-note rule ([`crate::preset::piano_note`]),
//!   adjusted by the relative [`Settings`] (hardness, hammer mass, striking position, damping,
//!   brightness), every string band-limited to `max_frequency` so that the sound is the same at
//!   every sample rate.
//! - Note velocity sets the hammer speed: `v = 0.3 · 20^velocity` m/s (0.3 to 6 m/s,
//!   [`hammer_speed`]).
//! - Note-off lets the damper down: a felt pad whose extra decay rises towards `damper_rate` (at
//!   the fundamental, faster for higher modes) with time constant `damper_time`, changing how fast
//!   the string decays, never its state. The sustain pedal (CC64 ≥ 64 on the note's channel) holds
//!   dampers off.
//! - Striking a key that still sounds strikes the same, still vibrating string: the hammer meets
//!   it wherever it swings ([`PianoVoice`]).
//!
//! # Slide mode
//!
//! Each note plucks a slide-guitar string ([`SlideVoice`]): the slide position follows the played
//! key (legato notes glide) or the `slide_position` setting, plus pitch bend; the hand height comes
//! from the setting or from the mod wheel, channel pressure or poly pressure. Bend and pressure
//! are kept per channel, so with MPE (a channel per note) every voice glides on its own.
//!
//! # Voices
//!
//! The pool is sized once ([`Instrument::new`]); nothing allocates after that. A note takes a free
//! voice or, when none is free, steals the least audible one (the quietest output over its latest
//! block): that voice fades out over 5 ms at a decay rate of 2000/s before its new note starts, so
//! stealing does not click. A piano voice is released when its string's energy falls 140 dB below
//! its strike's.
//!
//! # Timing
//!
//! Events take effect at the sample they are handled at; [`Settings`] changes at the next control
//! block boundary, blocks being counted from the first sample. Nothing depends on how the host
//! splits its buffers: rendering in calls of any size gives the same samples.

mod midi;
mod monitor;
mod params;
mod settings;
mod slide_voice;
mod solvers;
mod voice;

pub use midi::event_from_midi;
pub use monitor::{Monitor, SHAPE_POINTS};
pub use params::{PARAM_IDS, ParamError, ParamValues};
pub use settings::{HAND_RANGE, HandSource, MAX_BLOCK, MAX_SEGMENTS, Mode, Settings, hammer_speed};
pub use slide_voice::{
    ChannelState, GUARD_FACTOR, HAND_SPEED, OPEN_KEY, PLUCK_TIME, REST_FORCE, SLIDE_SPEED, SlideVoice, TRAIL,
};
pub use solvers::Solvers;
pub use voice::{
    DAMPER_UPDATE, DAMPER_WIDTH, PianoVoice, RELEASE_ENERGY, STEAL_RATE, STEAL_TIME, Strike, damper_shares,
};

use crate::string::ModalString;

/// Most voices an instrument may have.
pub const MAX_VOICES: usize = 128;

/// Output scale of the piano (1/N): bridge force to full scale. A fortissimo C4 (6 m/s) peaks
/// near 0.5.
pub const OUTPUT_SCALE: f64 = 0.016;

/// Output scale of the slide guitar (s/m): string velocity at the pickup to full scale. The
/// slide voice listens as a magnetic pickup does, whose coil's voltage follows the rate of change
/// of the flux the string modulates, so the string's velocity under it: a slide or finger holding
/// the string deflected gives no signal, where a displacement output would carry that
/// deflection as a DC offset and step at every press and release. A plucked note peaks near 0.5.
pub const SLIDE_SCALE: f64 = 0.3;

/// A note or controller event, as MIDI delivers them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Event {
    /// Key pressed. Velocity 0 is a note-off.
    NoteOn {
        /// MIDI channel, 0..=15.
        channel: u8,
        /// MIDI key, 0..=127.
        key: u8,
        /// Velocity, 0..=1.
        velocity: f32,
    },
    /// Key released.
    NoteOff {
        /// MIDI channel, 0..=15.
        channel: u8,
        /// MIDI key, 0..=127.
        key: u8,
    },
    /// Sustain pedal (CC64) on a channel.
    Sustain {
        /// MIDI channel, 0..=15.
        channel: u8,
        /// Pedal down.
        down: bool,
    },
    /// Release every key and pedal (CC123), letting the notes ring out under their dampers.
    AllNotesOff,
    /// Silence everything at once (CC120).
    AllSoundOff,
    /// Pitch bend of a channel, −1..=1 (moves the slide).
    PitchBend {
        /// MIDI channel, 0..=15.
        channel: u8,
        /// Bend, −1..=1.
        value: f32,
    },
    /// Channel pressure, 0..=1.
    ChannelPressure {
        /// MIDI channel, 0..=15.
        channel: u8,
        /// Pressure, 0..=1.
        value: f32,
    },
    /// Poly (key) pressure, 0..=1.
    PolyPressure {
        /// MIDI channel, 0..=15.
        channel: u8,
        /// MIDI key, 0..=127.
        key: u8,
        /// Pressure, 0..=1.
        value: f32,
    },
    /// Mod wheel (CC1), 0..=1.
    ModWheel {
        /// MIDI channel, 0..=15.
        channel: u8,
        /// Position, 0..=1.
        value: f32,
    },
}

/// A controller value from a host, made safe: NaN gives 0, the rest is clamped to `[lo, 1]`.
fn unit(value: f32, lo: f64) -> f64 {
    if value.is_nan() { 0.0 } else { f64::from(value).clamp(lo, 1.0) }
}

/// The instrument engine.
#[derive(Debug, Clone)]
pub struct Instrument {
    sample_rate: f64,
    /// Settings as last set.
    requested: Settings,
    /// Settings in force for the current control block.
    settings: Settings,
    voices: Vec<PianoVoice>,
    slides: Vec<SlideVoice>,
    /// Controllers per channel (MPE gives each note its own channel).
    channels: [ChannelState; 16],
    /// Pickup position the slide voices were last set to.
    pickup: f64,
    /// Sustain pedal per channel.
    sustain: [bool; 16],
    /// Samples rendered since the start.
    now: u64,
    /// Samples into the current control block.
    in_block: usize,
    /// One control block of one voice's output.
    scratch: Vec<f64>,
    /// Notes that had to take a busy voice.
    steals: u64,
}

impl Instrument {
    /// An instrument with `voices` voices (1..=[`MAX_VOICES`]) at `sample_rate` (Hz). Allocates
    /// everything it will ever need: every voice gets room for the longest string of the keyboard.
    pub fn new(sample_rate: f64, voices: usize, settings: Settings) -> Self {
        let sample_rate = if sample_rate.is_finite() && sample_rate >= 1000.0 { sample_rate } else { 44100.0 };
        let settings = settings.sanitized();
        let modes = Self::largest_string(sample_rate, &settings);
        let count = voices.clamp(1, MAX_VOICES);
        Self {
            sample_rate,
            requested: settings,
            settings,
            voices: (0..count).map(|_| PianoVoice::new(modes, sample_rate)).collect(),
            slides: (0..count).map(|_| SlideVoice::new(sample_rate, &settings)).collect(),
            channels: [ChannelState::default(); 16],
            pickup: settings.pickup_position,
            sustain: [false; 16],
            now: 0,
            in_block: 0,
            scratch: vec![0.0; MAX_BLOCK],
            steals: 0,
        }
    }

    /// Most modes any key can need at `sample_rate`: the largest count over the keyboard at the
    /// settings' extremes (the flexible, lowest-damping string, band-limited at 24 kHz).
    fn largest_string(sample_rate: f64, settings: &Settings) -> usize {
        let extreme = Settings { brightness: 0.0, damping: 0.1, max_frequency: 24_000.0, ..*settings };
        (0..=127u8)
            .map(|key| {
                let string = PianoVoice::string_for(key, &extreme);
                ModalString::band_limited(string, sample_rate, extreme.max_frequency).map_or(0, |s| s.modes())
            })
            .max()
            .unwrap_or(0)
            .min(crate::string::MAX_MODES)
    }

    /// Sample rate (Hz).
    pub fn sample_rate(&self) -> f64 {
        self.sample_rate
    }

    /// Size of the voice pool.
    pub fn voices(&self) -> usize {
        self.voices.len()
    }

    /// Voices currently sounding.
    pub fn sounding(&self) -> usize {
        self.voices.iter().filter(|v| v.sounding || v.fading()).count()
            + self.slides.iter().filter(|v| v.sounding).count()
    }

    /// The keys the piano voices sound (or will, after a steal fade), in pool order.
    pub fn piano_keys(&self) -> impl Iterator<Item = u8> + '_ {
        self.voices.iter().filter_map(PianoVoice::upcoming_key)
    }

    /// How many notes have had to take a busy voice (a steal) since the instrument was made.
    pub fn steals(&self) -> u64 {
        self.steals
    }

    /// How many times the guard has silenced a voice since the instrument was made (see
    /// [`SlideVoice`]'s guard): zero unless the physics misbehaved.
    pub fn guard_trips(&self) -> u32 {
        self.voices.iter().map(PianoVoice::guard_trips).sum::<u32>()
            + self.slides.iter().map(SlideVoice::guard_trips).sum::<u32>()
    }

    /// Voices whose exciter touches the string (or is about to): hammers in contact and slides
    /// pressed on. Each costs a contact solve per sample; the others step their strings alone
    /// or, once a hammer is out of reach, without it.
    pub fn in_contact(&self) -> usize {
        self.voices.iter().filter(|v| v.in_contact()).count()
            + self.slides.iter().filter(|v| v.sounding && v.in_contact()).count()
    }

    /// Set what the host controls; takes effect at the next control block. Values out of range
    /// are clamped and NaN replaced by the default.
    pub fn set_settings(&mut self, settings: &Settings) {
        self.requested = settings.sanitized();
    }

    /// Handle one event at the current sample.
    pub fn handle(&mut self, event: Event) {
        match event {
            Event::NoteOn { channel, key, velocity } if velocity > 0.0 => {
                let strike = Strike { channel: channel & 15, key: key & 127, velocity: f64::from(velocity.min(1.0)) };
                match self.settings.mode {
                    Mode::Piano => self.note_on(strike),
                    Mode::Slide => self.slide_on(strike),
                }
            }
            Event::NoteOn { channel, key, .. } | Event::NoteOff { channel, key } => {
                let (channel, key) = (channel & 15, key & 127);
                for v in &mut self.voices {
                    v.key_up(channel, key);
                }
                for v in self.slides.iter_mut().filter(|v| v.strike.channel == channel && v.strike.key == key) {
                    v.key_up();
                }
            }
            Event::PitchBend { channel, value } => self.channels[usize::from(channel & 15)].bend = unit(value, -1.0),
            Event::ChannelPressure { channel, value } => {
                self.channels[usize::from(channel & 15)].pressure = unit(value, 0.0)
            }
            Event::ModWheel { channel, value } => self.channels[usize::from(channel & 15)].mod_wheel = unit(value, 0.0),
            Event::PolyPressure { channel, key, value } => {
                let (channel, key) = (channel & 15, key & 127);
                for v in self.slides.iter_mut().filter(|v| v.strike.channel == channel && v.strike.key == key) {
                    v.poly_pressure = unit(value, 0.0);
                }
            }
            Event::Sustain { channel, down } => self.sustain[usize::from(channel & 15)] = down,
            Event::AllNotesOff => {
                self.sustain = [false; 16];
                self.voices.iter_mut().for_each(PianoVoice::release);
                self.slides.iter_mut().for_each(SlideVoice::key_up);
            }
            Event::AllSoundOff => {
                self.sustain = [false; 16];
                self.voices.iter_mut().for_each(PianoVoice::silence);
                self.slides.iter_mut().for_each(SlideVoice::silence);
            }
        }
    }

    fn note_on(&mut self, strike: Strike) {
        let now = self.now;
        // The same key again: strike the same string.
        if let Some(v) = self.voices.iter_mut().find(|v| v.upcoming_key() == Some(strike.key)) {
            if v.fading() {
                v.steal(strike, self.sample_rate, now);
            } else {
                v.play(strike, &self.settings, now);
            }
            return;
        }
        if let Some(v) = self.voices.iter_mut().find(|v| !v.sounding && !v.fading()) {
            v.play(strike, &self.settings, now);
            return;
        }
        // Steal the least audible voice: the quietest output over its latest block.
        let victim = self
            .voices
            .iter()
            .enumerate()
            .filter(|(_, v)| !v.fading())
            .min_by(|(_, a), (_, b)| a.loudness().total_cmp(&b.loudness()))
            .map(|(i, _)| i);
        if let Some(i) = victim {
            self.steals += 1;
            self.voices[i].steal(strike, self.sample_rate, now);
        }
    }

    fn slide_on(&mut self, strike: Strike) {
        let now = self.now;
        let settings = self.settings;
        // Following keys, a new key while another is held on the channel glides there (legato).
        if settings.follow_key
            && let Some(v) =
                self.slides.iter_mut().find(|v| v.sounding && v.key_down && v.strike.channel == strike.channel)
        {
            v.play(strike, &settings, true, now);
            return;
        }
        // A free voice, else the oldest: its string keeps its motion, so reuse does not click.
        let index = self
            .slides
            .iter()
            .position(|v| !v.sounding)
            .or_else(|| self.slides.iter().enumerate().min_by_key(|(_, v)| v.started).map(|(i, _)| i));
        if let Some(i) = index {
            self.slides[i].play(strike, &settings, false, now);
        }
    }

    /// Render into `left` and `right` (the same length), replacing their contents.
    pub fn process(&mut self, left: &mut [f32], right: &mut [f32]) {
        let n = left.len().min(right.len());
        left.fill(0.0);
        right.fill(0.0);
        let mut done = 0;
        while done < n {
            if self.in_block == 0 {
                self.begin_block();
            }
            let len = (self.settings.block - self.in_block).min(n - done);
            let (piano_scale, slide_scale) = (OUTPUT_SCALE * self.settings.gain, SLIDE_SCALE * self.settings.gain);
            let scratch = &mut self.scratch[..len];
            let (l, r) = (&mut left[done..done + len], &mut right[done..done + len]);
            for voice in self.voices.iter_mut().filter(|v| v.sounding) {
                voice.render(scratch);
                mix(scratch, piano_scale, l, r);
            }
            for voice in self.slides.iter_mut().filter(|v| v.sounding) {
                voice.render(scratch);
                mix(scratch, slide_scale, l, r);
            }
            done += len;
            self.now += len as u64;
            self.in_block += len;
            if self.in_block >= self.settings.block {
                self.in_block = 0;
            }
        }
    }

    fn begin_block(&mut self) {
        self.settings = self.requested;
        let len = self.settings.block;
        for v in &mut self.voices {
            let sustained = self.sustain[usize::from(v.strike.channel)];
            v.begin_block(&self.settings, sustained, len, self.now);
        }
        let move_pickup = self.pickup != self.settings.pickup_position;
        self.pickup = self.settings.pickup_position;
        for v in &mut self.slides {
            if move_pickup {
                v.set_pickup(self.pickup);
            }
            if v.sounding {
                v.begin_block(&self.settings, &self.channels[usize::from(v.strike.channel)], len);
            }
        }
    }
}

/// Add `x · scale` to both channels.
fn mix(x: &[f64], scale: f64, left: &mut [f32], right: &mut [f32]) {
    for ((l, r), &v) in left.iter_mut().zip(right.iter_mut()).zip(x) {
        let y = (v * scale) as f32;
        *l += y;
        *r += y;
    }
}
