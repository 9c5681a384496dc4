//! The playable instrument: a fixed pool of voices driven by note and controller events, shared
//! by the plugin and the offline MIDI renderer.
//!
//! # Piano mode
//!
//! - A key gets the string and hammer of the per-note rule ([`crate::preset::piano_note`]),
//!   adjusted by the relative [`Settings`] (hardness, hammer mass, striking position, damping,
//!   brightness), every string band-limited to `max_frequency` so that the sound is the same at
//!   every sample rate.
//! - Note velocity sets the hammer speed: `v = 0.5 · 12^velocity` m/s (0.5 to 6 m/s,
//!   [`hammer_speed`]); the voicing ([`voicing_gain`]) evens the loudness of the keys at every
//!   velocity.
//! - CC74 (MPE's third dimension, a note's timbre) voices the felt of the hammers it meets: the
//!   channel's latest value when the hammer is thrown (sent before the note-on or at its sample,
//!   or while the note waits for a steal fade; an MPE zone's master channel speaks for its
//!   members), or the note's own brightness sent with it, makes the felt stiffer or softer than
//!   the hardness setting, twice as stiff every 32 steps above the middle ([`felt_hardness`]). A
//!   key struck with no CC74 sent on its channel keeps the setting.
//! - Note-off lets the damper down: a felt pad whose extra decay rises towards `damper_rate` (at
//!   the fundamental, faster for higher modes) with time constant `damper_time`, changing how fast
//!   the string decays, never its state. The sustain pedal (CC64 on the note's channel, or on an
//!   MPE zone's master channel, 1 or 16, which speaks for every channel) holds dampers off: its
//!   value is how far it is down, and part of the way down the dampers hover above the strings,
//!   taking only what swings beyond their lift ([`damper_lift`], [`contact_share`]).
//! - The sostenuto pedal (CC66 ≥ 64, read on the channels as the sustain pedal is) holds up the
//!   dampers of the keys held down as it goes down, until it comes up.
//! - The soft pedal (CC67 ≥ 64, read on the channels as the sustain pedal is) shifts the hammers:
//!   a key struck while it is down meets one string fewer of a bichord or trichord
//!   ([`struck_strings`]); a key already sounding keeps the strike it had.
//! - Striking a key that still sounds strikes the same, still vibrating string: the hammer meets
//!   it wherever it swings ([`PianoVoice`]).
//!
//! # Slide mode
//!
//! Each note plucks a slide-guitar string ([`SlideVoice`]): the slide position follows the played
//! key (legato notes glide, and letting go of the key played glides back to the latest key still
//! held on its channel; the key played, struck again, plucks again) or the `slide_position`
//! setting, plus pitch bend (as far as the channel's pitch-bend sensitivity or MPE zone says,
//! `bend`); the hand height comes from the setting or from the mod wheel, channel pressure,
//! poly pressure or CC74 (or the note's brightness). Bend and pressure are kept per channel, so
//! with MPE (a channel per note) every voice glides on its own.
//!
//! # Per-note expression
//!
//! Hosts that address single notes (CLAP note expressions and polyphonic modulation, VST3 note
//! expressions) reach a voice by the voice id given at note-on ([`Event::NoteOnWithId`]) or by
//! channel and key ([`NoteTarget`]). In slide mode a note's tuning moves its slide
//! ([`Event::NoteTuning`]), its pressure is its poly pressure ([`Event::NotePressure`]), its
//! brightness is its own CC74 ([`Event::NoteBrightness`]), and polyphonic modulation offsets its
//! `slide_position` and `hand_height` ([`Event::NoteModulation`]); see [`SlideVoice`]. In piano
//! mode a note's brightness sent with its note-on (at the same sample, before the hammer moves)
//! voices its felt as CC74 does; the rest is ignored: a struck string keeps its tuning, and a
//! thrown hammer its felt. Whatever the mode, every note's end is queued for the host
//! ([`Instrument::drain_ended`]).
//!
//! # Voices
//!
//! The pool is sized once ([`Instrument::new`]); nothing allocates after that. A piano note takes a
//! free voice or, when none is free, steals the least audible one (the quietest output over its
//! latest window of 20 ms, a note not heard over a whole window yet counting as the loudest): that
//! voice fades out over 5 ms at a decay rate of 2000/s before its new note starts, so stealing does
//! not click. When every voice fades already, the piano voice whose waiting note came first gives
//! it up to the new note, the newest notes winning. A slide note takes a free voice or the one
//! whose string moves least, a voice still plucking last, and plucks its string as it is: the
//! string keeps its motion, so reuse does not click. A piano voice is released when its strings'
//! energy falls 100 dB below its strike's. A host's choke ([`Event::Choke`]) fades the notes it
//! addresses out the same way, whatever the pedals, and ends them.
//!
//! # Output
//!
//! What a listener hears (docs/physics.md §13):
//! - the piano's voices, each panned by its key's place along the bridge
//!   ([`pan_gains`], `Settings::stereo_width`), sum into a left and a right bridge force, each
//!   radiated through the soundboard ([`crate::body`]), then scaled by [`OUTPUT_SCALE`];
//! - the slide guitar's voices sum: on the electric guitar, centred, through the pickup's
//!   circuit ([`crate::pickup`]), scaled by [`SLIDE_SCALE`]; on the acoustic guitar
//!   (`Settings::slide_body`), what the body their strings end on radiates, scaled by
//!   [`ACOUSTIC_SCALE`], its two lowest modes in the centre and its higher modes panned
//!   alternately left and right by the stereo width ([`side_gains`]). A string keeps the guitar
//!   it was plucked on from silence until it falls silent, through the notes that take it over.
//!
//! [`Instrument::set_raw_output`] gives the dry signals instead, centred. Both then pass the
//! output stage ([`OutputStage`]): the gain, smoothed over a few milliseconds, and the safety
//! limiter, which holds every sample at or below −0.1 dBFS when it is on. The limiter looks 1 ms
//! ahead, so the output is late by [`Instrument::latency`] samples, on or off.
//!
//! # Timing
//!
//! Events are handled at their sample, and a note starts there. What an event changes in a
//! sounding voice's controls (a bend, a pressure, the mod wheel, a pedal, the damper a release
//! lets fall) the voice takes up at the next control-block boundary, as it takes [`Settings`]
//! changes: at most a block late (1.3 ms for 64 samples at 48 kHz), blocks being counted from the
//! first sample. Nothing depends on how the host splits its buffers: rendering in calls of any
//! size gives the same samples.

mod bend;
mod memo;
mod midi;
mod monitor;
mod notes;
mod output;
mod params;
mod partners;
mod piano_voice;
mod presets;
mod settings;
mod slide_scale;
mod slide_voice;
mod solvers;
mod voicing;

pub use bend::{MPE_MASTER_RANGE, MPE_MEMBER_RANGE};
pub use midi::{bend_from_normalised, event_from_midi};
pub use monitor::{Monitor, SHAPE_POINTS};
pub use notes::{EndedNote, MAX_TUNING, Note, NoteParam, NoteTarget};
pub use output::{CEILING, LOOKAHEAD, OutputStage, RELEASE, lookahead_samples};
pub use params::{
    Group, PARAM_IDS, PARAMETERS, PLAYER_SETTINGS, ParamError, ParamKind, ParamSpec, ParamValues, Scale, ValueDisplay,
    param_index, param_spec, plain_values_differ,
};
pub use partners::{
    MAX_PARTNER_MODES, PARTNER_BAND, PARTNER_KEYS, PARTNER_TOLERANCE_CENTS, PartnerTable, STRIKING_PARTIALS,
};
pub use piano_voice::{
    DAMPER_UPDATE, DAMPER_WIDTH, Dampers, Elsewhere, FIRST_UNDAMPED_KEY, GUARD_FACTOR, HOVER_LIFTS, PianoVoice,
    RELEASE_ENERGY, STEAL_RATE, STEAL_TIME, Strike, TIMBRE_CENTRE, TIMBRE_HARDNESS_STEP, contact_share, damper_lift,
    damper_shares, felt_hardness, has_damper, struck_strings,
};
pub use presets::{
    CATEGORIES, FACTORY_PRESETS, Preset, PresetError, factory_presets, find_preset, load_factory_presets, parse_preset,
};
pub use settings::{
    GAIN_RANGE_DB, HAND_HEIGHT_LIMIT, HAND_RANGE, HARDNESS_RANGE, HandSource, MAX_BLOCK, MAX_SEGMENTS, Mode, Settings,
    SlideBody, hammer_speed,
};
pub use slide_scale::SlideScale;
pub use slide_voice::{
    BRAKING, ChannelState, FINGER_LIFT, HAND_ACCELERATION, HAND_SPEED, LANDING_SPEED, MUTE_FINGER_DAMPING,
    MUTE_HAND_DAMPING, MUTE_TIME, MUTED_LIMIT, OPEN_KEY, PICKUP_APERTURE, PLUCK_RELEASE, PLUCK_TIME, REST_FORCE,
    SLIDE_ACCELERATION, SLIDE_SPEED, SlideVoice, TRAIL, hand_reach, pluck_force, pluck_point, trailing_finger,
};
pub use solvers::Solvers;
pub use voicing::{VOICING_DB, VOICING_VELOCITIES, voicing_gain};

use crate::body::{Body, BodyParams};
use crate::pickup::PickupCircuit;
use crate::scene::{MAX_PARTNERS, Shared, Watch};
use crate::string::ModalString;
use bend::Bends;
use notes::NoteBook;
use std::ops::Range;

/// Time constant with which a voice struck again moves to its new voicing gain (s).
pub const VOICING_TIME: f64 = 0.005;

/// Fastest the slide guitar's pickup moves along the string when its parameter changes (string
/// lengths per second): a jump across the whole range takes half a second.
pub const PICKUP_SPEED: f64 = 1.0;

/// How fast the pickup's resonance follows its setting (s per octave).
pub const PICKUP_GLIDE: f64 = 0.05;

/// Most voices an instrument may have.
pub const MAX_VOICES: usize = 128;

/// Most piano voices that bring their partners onto their bridges in one control block when the
/// pedal goes down after their strikes (each re-derives its coupling, about as costly as a
/// strike): all 88 keys pedalled at once take 11 blocks of 64 samples, 15 ms at 48 kHz, instead of
/// one block costing three times its duration.
pub const PARTNER_SEEKS: usize = 8;

/// Output scale of the piano (1/N): bridge force to full scale, before each key's voicing
/// ([`voicing_gain`]), which sets the loudness (−46.0 LUFS for a key struck alone at velocity 80).
pub const OUTPUT_SCALE: f64 = 0.016;

/// Output scale of the slide guitar (s/m): string velocity at the pickup to full scale. The
/// slide voice listens as a magnetic pickup does, whose coil's voltage follows the rate of change
/// of the flux the string modulates, so the string's velocity under it: a slide or finger holding
/// the string deflected gives no signal, where a displacement output would carry that
/// deflection as a DC offset and step at every press and release. A note plucked at velocity 80
/// (D3, the slide pressed), heard through the pickup's circuit, measures −39.3 LUFS over 2 s and
/// peaks at 0.053.
pub const SLIDE_SCALE: f64 = 0.06;

/// Output scale of the acoustic slide guitar: what the body radiates (in newtons of bridge force
/// above a kilohertz, [`crate::body::BodyParams::guitar`]) to full scale, set so that the note
/// [`SLIDE_SCALE`] is set by measures the same loudness on either guitar.
pub const ACOUSTIC_SCALE: f64 = 0.076;

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
    /// Sustain pedal (CC64) on a channel, pressed `depth` of its travel: the dampers rest on the
    /// strings, hover partly up or are clear of them ([`damper_lift`]).
    Sustain {
        /// MIDI channel, 0..=15.
        channel: u8,
        /// How far the pedal is down, 0..=1 (0 up, 1 down).
        depth: f32,
    },
    /// Soft pedal (una corda, CC67) on a channel: the piano's keys struck while it is down are
    /// struck on one string fewer (docs/physics.md §12.9).
    SoftPedal {
        /// MIDI channel, 0..=15.
        channel: u8,
        /// Pedal down.
        down: bool,
    },
    /// Sostenuto pedal (CC66) on a channel: going down, it holds up the dampers of the keys held
    /// down at that moment until it comes up; keys struck later are damped as usual.
    Sostenuto {
        /// MIDI channel, 0..=15.
        channel: u8,
        /// Pedal down.
        down: bool,
    },
    /// Reset all controllers of a channel (CC121): its pitch bend to the centre, its channel
    /// and poly pressures and the mod wheel to 0, its three pedals up (MIDI RP-015). CC74, a
    /// sound controller, keeps its value, as RP-015 asks, and so do the notes' brightness
    /// expressions. The notes play on.
    ResetControllers {
        /// MIDI channel, 0..=15.
        channel: u8,
    },
    /// Release the keys of the addressed notes, as their note-offs do. A CLAP note-off may leave
    /// its channel or key open, releasing every note on a key or a channel (or all of them), or
    /// name a note by its voice id alone. Naming its id, channel and key, it releases that note:
    /// not a later note on the key that the host let overlap it (which it then leaves held), and,
    /// when the id is one the engine was never told, the key, as [`Event::NoteOff`] does.
    Release {
        /// The notes: a key held down counts when the target names no voice id, or its press's.
        note: NoteTarget,
    },
    /// Stop the addressed notes whatever the pedals: their keys are released and their voices
    /// fade out over [`STEAL_TIME`], as a stolen voice does, and fall silent, the notes ending
    /// (a CLAP note choke: a drum pad choked by another, or a host's stop that ends every note).
    Choke {
        /// The notes: a key held down counts when the target names no voice id.
        note: NoteTarget,
    },
    /// A controller of MIDI's registered-parameter protocol on a channel: CC101 and CC100 select
    /// a parameter (CC99 and CC98 a non-registered one), CC6 and CC38 set its value. The engine
    /// takes pitch-bend sensitivity (RPN 0), how far a full bend moves the slide on that
    /// channel, and the MPE configuration (RPN 6), which sets up a zone whose master channel
    /// bends every note of the zone.
    RegisteredParameter {
        /// MIDI channel, 0..=15.
        channel: u8,
        /// The controller: 6, 38 or 98 to 101 (others are ignored).
        controller: u8,
        /// Its value, 0..=127.
        value: u8,
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
    /// CC74, MPE's third dimension (a key surface's forward position, "timbre" or "slide"),
    /// 0..=1.
    Timbre {
        /// MIDI channel, 0..=15.
        channel: u8,
        /// Value, 0..=1.
        value: f32,
    },
    /// Key pressed, with the host's voice (note) id, which per-note events can address. Velocity
    /// 0 is a note-off: of the sounding note with that id if there is one, which ends when its
    /// voice falls silent; otherwise the note ends at once, never played.
    NoteOnWithId {
        /// MIDI channel, 0..=15.
        channel: u8,
        /// MIDI key, 0..=127.
        key: u8,
        /// Velocity, 0..=1.
        velocity: f32,
        /// The host's voice (note) id.
        voice: i32,
    },
    /// Tuning of the addressed notes (semitones, clamped to ±[`MAX_TUNING`]; NaN is 0): moves
    /// their slides (slide mode).
    NoteTuning {
        /// The notes.
        note: NoteTarget,
        /// Tuning (semitones).
        semitones: f32,
    },
    /// Pressure of the addressed notes, 0..=1: their poly pressure.
    NotePressure {
        /// The notes.
        note: NoteTarget,
        /// Pressure, 0..=1.
        value: f32,
    },
    /// Brightness of the addressed notes, 0..=1: their own CC74 (their channel's no longer
    /// reaches them).
    NoteBrightness {
        /// The notes.
        note: NoteTarget,
        /// Brightness, 0..=1.
        value: f32,
    },
    /// Polyphonic modulation: an offset of a slide setting for the addressed notes, in the
    /// setting's unit (semitones, metres), clamped to ± the setting's span (NaN is 0).
    NoteModulation {
        /// The notes.
        note: NoteTarget,
        /// The setting.
        param: NoteParam,
        /// Offset added to the setting (the sum is clamped to its range).
        offset: f32,
    },
}

/// A controller value from a host, made safe: NaN gives 0, the rest is clamped to `[lo, 1]`.
fn unit(value: f32, lo: f64) -> f64 {
    if value.is_nan() { 0.0 } else { f64::from(value).clamp(lo, 1.0) }
}

/// A key's latest press on its channel.
#[derive(Debug, Clone, Copy, Default)]
struct Press {
    /// When, in presses counted from the start: a slide following keys returns to the latest key
    /// still held when the key it plays is let go.
    order: u64,
    /// The host's note id: a note-off or choke by id alone finds its key held down though the
    /// note ended early (its voice taken by another).
    id: Option<i32>,
    /// The latest poly pressure or pressure expression since, 0..=1: a slide voice that returns
    /// to the key takes it.
    pressure: f64,
    /// Whether the key was played on a slide: a slide returns only to keys it could have played,
    /// not to a key held on the piano from before the mode changed.
    slide: bool,
    /// The ids of the presses this one came over while the key was still down (a host's notes on
    /// one key may overlap), the latest last: such a note's own note-off, by id, lets go of its
    /// own voice if it still has one, not of the key.
    under: [Option<i32>; OVERLAPS],
}

/// How many earlier notes a key's latest press remembers having come over ([`Press::under`]).
const OVERLAPS: usize = 3;

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
    /// Each channel's pitch-bend sensitivity and the MPE zones.
    bends: Bends,
    /// Pickup position the slide voices were last set to.
    pickup: f64,
    /// Sustain pedal per channel: how far it is down, 0..=1.
    sustain: [f64; 16],
    /// Soft pedal per channel.
    soft: [bool; 16],
    /// Sostenuto pedal per channel, and the keys whose dampers it holds up.
    sostenuto: [bool; 16],
    caught: [u128; 16],
    /// The keys held down on each channel, one bit per MIDI key: their dampers are off their
    /// strings, so they ring as partners of the keys struck meanwhile (docs/physics.md §14).
    keys_down: [u128; 16],
    /// Each key's latest press, per channel.
    pressed: Vec<[Press; 128]>,
    /// Presses since the start.
    presses: u64,
    /// Samples rendered since the start.
    now: u64,
    /// Samples into the current control block.
    in_block: usize,
    /// One control block of one voice's output.
    scratch: Vec<f64>,
    /// Every key's strings as partners of the keys struck (docs/physics.md §14).
    partners: PartnerTable,
    /// For each piano voice whose hammer meets its strings' motion on other voices' bridges,
    /// that motion at its striking point over one control block (m), which those voices hand
    /// it (docs/physics.md §14.3).
    backgrounds: Vec<Vec<f64>>,
    /// Those voices, in the order they render: after every other, the oldest strike first.
    meeting: Vec<usize>,
    /// Notes that had to take a busy voice.
    steals: u64,
    /// Voices shed to lighten the load ([`Instrument::shed_voices`]).
    shed: u64,
    /// The piano's soundboard radiating the left and right channels' bridge forces.
    boards: [Body; 2],
    /// One control block of the piano's bridge forces, left and right, and of the slide
    /// guitars' signals: the pickup's and the acoustic body's.
    buses: [Vec<f64>; 4],
    /// The acoustic body's sides and their pan.
    sides: BodySides,
    /// The slide guitar's pickup circuit, and the resonance it is tuned to now (Hz).
    circuit: PickupCircuit,
    resonance: f64,
    /// Whether the output is the dry signals (no body, pan or pickup circuit).
    raw: bool,
    /// Gain ramp and safety limiter.
    output: OutputStage,
    /// Fraction of the way a voice's voicing gain moves to its target each sample.
    voicing_rate: f64,
    /// The host note on each voice (piano voices first, then slide voices) and the ended ones.
    notes: NoteBook,
}

impl Instrument {
    /// An instrument with `voices` voices (1..=[`MAX_VOICES`]) at `sample_rate` (Hz). Allocates
    /// everything it will ever need: every voice gets room for the longest string of the keyboard.
    pub fn new(sample_rate: f64, voices: usize, settings: Settings) -> Self {
        let sample_rate = if sample_rate.is_finite() && sample_rate >= 1000.0 { sample_rate } else { 44100.0 };
        let settings = settings.sanitized();
        let modes = Self::largest_string(sample_rate, &settings);
        let count = voices.clamp(1, MAX_VOICES);
        let mut instrument = Self {
            sample_rate,
            requested: settings,
            settings,
            voices: (0..count).map(|_| PianoVoice::new(modes, sample_rate)).collect(),
            slides: (0..count).map(|_| SlideVoice::new(sample_rate, &settings)).collect(),
            channels: [ChannelState::default(); 16],
            bends: Bends::default(),
            pickup: settings.pickup_position,
            sustain: [0.0; 16],
            soft: [false; 16],
            sostenuto: [false; 16],
            caught: [0; 16],
            keys_down: [0; 16],
            pressed: vec![[Press::default(); 128]; 16],
            presses: 0,
            now: 0,
            in_block: 0,
            scratch: vec![0.0; MAX_BLOCK],
            partners: PartnerTable::new(sample_rate, &settings),
            backgrounds: (0..count).map(|_| vec![0.0; MAX_BLOCK]).collect(),
            meeting: Vec::with_capacity(count),
            boards: [(); 2].map(|_| Body::new(&BodyParams::piano(), sample_rate)),
            buses: [(); 4].map(|_| vec![0.0; MAX_BLOCK]),
            sides: BodySides::new(),
            circuit: PickupCircuit::new(settings.pickup_resonance, sample_rate),
            resonance: settings.pickup_resonance,
            raw: false,
            steals: 0,
            shed: 0,
            output: OutputStage::new(sample_rate, settings.gain),
            voicing_rate: 1.0 - (-1.0 / (VOICING_TIME * sample_rate)).exp(),
            notes: NoteBook::new(2 * count),
        };
        instrument.prepare_voices();
        instrument
    }

    /// Tune every piano voice, before the first note, to the keys that reach furthest into its
    /// arrays under the settings, and search every key's partners: the first chord then finds
    /// the voices' memory in place and the partners found, as every later chord does, instead of
    /// faulting in pages and searching on the audio thread. Allocates nothing further.
    fn prepare_voices(&mut self) {
        let Some((first, rest)) = self.voices.split_first_mut() else { return };
        // `(reach, key)` of the keys with the most modes on the bridge, off it, and on one string.
        let mut widest = [(0, 0u8); 3];
        for key in 0..=127u8 {
            let (coupled, free, string) = first.prepare(key, &self.settings, &self.partners);
            for (w, reach) in widest.iter_mut().zip([coupled, free, string]) {
                if reach > w.0 {
                    *w = (reach, key);
                }
            }
        }
        for voice in rest {
            for &(_, key) in &widest {
                voice.prepare(key, &self.settings, &self.partners);
            }
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

    /// Samples by which the output is late: the safety limiter's look-ahead, the same whether
    /// the limiter is on or off (a host compensates it).
    pub fn latency(&self) -> usize {
        self.output.latency()
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

    /// Fade out the `count` least audible sounding voices over [`STEAL_TIME`] and let them fall
    /// silent, their notes ending: what a host's audio thread that cannot keep up calls for. Piano
    /// voices go first, the quietest output over their latest block first, fading as a stolen
    /// voice does; then slide voices, the least moving string first, their output faded. Voices
    /// fading already are left to their fade. Returns how many began to fade.
    pub fn shed_voices(&mut self, count: usize) -> usize {
        let fs = self.sample_rate;
        let pianos =
            shed_lowest(&mut self.voices, count, |v| (v.sounding && !v.fading()).then(|| v.loudness()), |v| v.shed(fs));
        let slides = shed_lowest(
            &mut self.slides,
            count - pianos,
            |v| (v.sounding && !v.shedding()).then(|| v.motion()),
            |v| v.shed(fs),
        );
        self.shed += (pianos + slides) as u64;
        pianos + slides
    }

    /// How many voices have been shed since the instrument was made.
    pub fn shed_count(&self) -> u64 {
        self.shed
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

    /// Set what the host controls; takes effect at the next control block, and at once for the
    /// notes struck from now on (the mode, and what a note keeps from its strike). Values out of
    /// range are clamped and NaN replaced by the default.
    pub fn set_settings(&mut self, settings: &Settings) {
        self.requested = settings.sanitized();
    }

    /// Samples rendered since the instrument was made (the time [`EndedNote::at`] counts in).
    pub fn now(&self) -> u64 {
        self.now
    }

    /// The notes whose voices have ended since the last call, oldest first: each once, with the
    /// sample it ended at. Never allocates: between calls the queue holds 8 × [`Self::voices`]
    /// notes (four per piano and per slide voice); notes ending while it is full go unreported.
    pub fn drain_ended(&mut self) -> impl Iterator<Item = EndedNote> + '_ {
        self.notes.drain_ended()
    }

    /// Return to the state the instrument was made in, without allocating: every voice silent,
    /// the pedals and every channel's controllers at rest, the output stage empty and the clock
    /// at zero, so that the control blocks start again at the next sample. What follows renders
    /// to the bit as on an instrument just made at this sample rate with these settings and
    /// told the controller's configuration, with no parameter number selected: the pitch-bend
    /// sensitivities and MPE zones stay, as reset-all-controllers keeps them (a controller sends
    /// them once, and hosts reset at every start of processing). A host that resets the
    /// instrument before each bounce gets the same bounce each time. The notes that were
    /// sounding end at sample 0 ([`Self::drain_ended`]); the counts of steals, sheds and guard
    /// trips go on.
    pub fn reset(&mut self) {
        self.handle_event(Event::AllSoundOff);
        self.channels = [ChannelState::default(); 16];
        self.bends.deselect_all();
        self.pressed.iter_mut().for_each(|keys| keys.fill(Press::default()));
        self.presses = 0;
        self.now = 0;
        self.in_block = 0;
        self.notes.end_all(0);
        self.voices.iter_mut().for_each(PianoVoice::reset);
        // As made with the settings in force: the pickup and its resonance where they ask, not
        // gliding there.
        let settings = self.requested;
        self.settings = settings;
        self.pickup = settings.pickup_position;
        self.resonance = settings.pickup_resonance;
        self.circuit.set(self.resonance, self.sample_rate);
        self.slides.iter_mut().for_each(|v| v.reset(&settings));
        self.sides.reset();
        self.output.set_gain(settings.gain);
        self.output.reset();
    }

    /// Take `other`'s controller configuration (pitch-bend sensitivities and MPE zones, no
    /// parameter number selected), as a reset keeps it: for an instrument made anew in its place
    /// (another sample rate or voice count).
    pub fn keep_controller_configuration(&mut self, other: &Instrument) {
        self.bends = other.bends.clone();
        self.bends.deselect_all();
    }

    /// Take over from `old`, an instrument this one replaces (a host's new sample rate or voice
    /// count): keep its controller configuration ([`keep_controller_configuration`]), and end its
    /// notes, those still sounding and those ended but not yet drained, queued here at sample 0
    /// ([`Self::drain_ended`]), so that the host hears of every note's end as after a
    /// [`reset`](Self::reset). Allocates nothing, but belongs with making an instrument, off the
    /// audio thread.
    ///
    /// [`keep_controller_configuration`]: Self::keep_controller_configuration
    pub fn take_over(&mut self, old: &mut Instrument) {
        self.keep_controller_configuration(old);
        self.notes.take_ends_from(&mut old.notes, 0);
    }

    /// Handle one event at the current sample.
    pub fn handle(&mut self, event: Event) {
        self.handle_event(event);
        self.check_ended();
    }

    fn handle_event(&mut self, event: Event) {
        match event {
            Event::NoteOn { channel, key, velocity } if velocity > 0.0 => self.play(channel, key, velocity, None),
            Event::NoteOnWithId { channel, key, velocity, voice } if velocity > 0.0 => {
                self.play(channel, key, velocity, Some(voice))
            }
            Event::NoteOn { channel, key, .. } | Event::NoteOff { channel, key } => self.key_up(channel, key),
            Event::NoteOnWithId { channel, key, voice, .. } => {
                if self.notes.addressed(NoteTarget::voice(voice)).next().is_some() {
                    // The id of a note that sounds: that note's note-off. It ends, and is
                    // reported, once its voice falls silent.
                    self.release(NoteTarget { voice: Some(voice), channel: Some(channel), key: Some(key) });
                } else {
                    self.key_up(channel, key);
                    let note = Note { voice: Some(voice), channel: channel & 15, key: key & 127 };
                    self.notes.end_unplayed(note, self.now);
                }
            }
            Event::Release { note } => self.release(note),
            Event::Choke { note } => {
                // A note a later press of its key came over fades alone, the key kept held; any
                // other's keys go up, faded first: a choked slide following keys lets go rather
                // than gliding back to a key still held.
                let note = self.with_its_key(note);
                let keys = if self.take_under(note) { [0; 16] } else { self.addressed_keys(note) };
                self.choke(note);
                self.keys_up(&keys);
            }
            Event::PitchBend { channel, value } => self.channels[usize::from(channel & 15)].bend = unit(value, -1.0),
            Event::ChannelPressure { channel, value } => self.set_controller(channel, value, |c| &mut c.pressure),
            Event::ModWheel { channel, value } => self.set_controller(channel, value, |c| &mut c.mod_wheel),
            Event::Timbre { channel, value } => {
                // NaN is no CC74: the slide reads 0, the piano's felt keeps the setting.
                let value = (!value.is_nan()).then(|| unit(value, 0.0));
                let mut channels = 0u16;
                for c in self.bends.spoken_for(channel) {
                    self.channels[c].timbre = value;
                    channels |= 1 << c;
                }
                // A strike still to come on those channels takes it too.
                let (now, settings, pianos) = (self.now, self.note_settings(), self.pools().0);
                for i in self.notes.live_in(pianos) {
                    self.voices[i].set_channel_timbre(channels, value, &settings, now);
                }
            }
            Event::PolyPressure { channel, key, value } => {
                let value = unit(value, 0.0);
                self.pressed[usize::from(channel & 15)][usize::from(key & 127)].pressure = value;
                self.each_slide(NoteTarget::key(channel, key), |v, _| v.poly_pressure = value);
            }
            Event::NotePressure { note, value } => {
                let value = unit(value, 0.0);
                // Kept by key too, as poly pressure is: a slide that returns to a key held with
                // this note takes it.
                for (c, mut keys) in self.addressed_keys(note).into_iter().enumerate() {
                    while keys != 0 {
                        self.pressed[c][keys.trailing_zeros() as usize].pressure = value;
                        keys &= keys - 1;
                    }
                }
                self.each_slide(note, |v, _| v.poly_pressure = value);
            }
            Event::NoteBrightness { note, value: raw } => {
                let value = unit(raw, 0.0);
                self.each_slide(note, |v, _| v.brightness = Some(value));
                // NaN voices no felt.
                let (now, settings) = (self.now, self.note_settings());
                for (i, _) in self.notes.addressed(note).filter(|_| !raw.is_nan()) {
                    if let Some(v) = self.voices.get_mut(i) {
                        v.set_brightness(value, &settings, now);
                    }
                }
            }
            Event::NoteTuning { note, semitones } => {
                let semitones = notes::sanitize_tuning(semitones);
                self.each_slide(note, |v, settings| v.set_tuning(semitones, settings));
            }
            Event::NoteModulation { note, param, offset } => {
                let offset = param.sanitize(offset);
                self.each_slide(note, |v, settings| v.set_offset(param, offset, settings));
            }
            Event::Sustain { channel, depth } => self.sustain[usize::from(channel & 15)] = unit(depth, 0.0),
            Event::SoftPedal { channel, down } => self.soft[usize::from(channel & 15)] = down,
            Event::Sostenuto { channel, down } => self.sostenuto(channel & 15, down),
            Event::ResetControllers { channel } => {
                let channel = channel & 15;
                let c = usize::from(channel);
                self.channels[c] = ChannelState { timbre: self.channels[c].timbre, ..ChannelState::default() };
                // A zone's master speaks for its members' mod wheel and pressure: theirs rest too
                // (whoever sent them: a channel does not record it).
                for m in self.bends.spoken_for(channel).skip(1) {
                    (self.channels[m].mod_wheel, self.channels[m].pressure) = (0.0, 0.0);
                }
                self.bends.reset_controllers(channel);
                self.sustain[c] = 0.0;
                self.soft[c] = false;
                self.sostenuto(channel, false);
                self.slides.iter_mut().filter(|v| v.strike.channel == channel).for_each(|v| v.poly_pressure = 0.0);
                self.pressed[c].iter_mut().for_each(|press| press.pressure = 0.0);
            }
            Event::RegisteredParameter { channel, controller, value } => {
                self.bends.controller(channel, controller, value, self.requested.bend_range)
            }
            Event::AllNotesOff => {
                self.sustain = [0.0; 16];
                self.soft = [false; 16];
                self.sostenuto = [false; 16];
                self.caught = [0; 16];
                self.keys_down = [0; 16];
                self.voices.iter_mut().for_each(PianoVoice::release);
                let kept = self.kept_channels();
                self.slides.iter_mut().for_each(|v| release_slide(v, &kept));
            }
            Event::AllSoundOff => {
                self.sustain = [0.0; 16];
                self.soft = [false; 16];
                self.sostenuto = [false; 16];
                self.caught = [0; 16];
                self.keys_down = [0; 16];
                self.voices.iter_mut().for_each(PianoVoice::silence);
                self.slides.iter_mut().for_each(SlideVoice::silence);
                self.output.clear();
                self.boards.iter_mut().for_each(Body::reset);
                self.circuit.reset();
            }
        }
    }

    /// Play a note (velocity above 0) in the current mode, and note which voice took it.
    fn play(&mut self, channel: u8, key: u8, velocity: f32, voice: Option<i32>) {
        let channel = channel & 15;
        let shifted = for_channel(&self.soft, channel, |a, b| a | b);
        let timbre = self.channels[usize::from(channel)].timbre;
        let strike = Strike { channel, key: key & 127, velocity: f64::from(velocity.min(1.0)), shifted, timbre };
        let down = self.keys_down[usize::from(strike.channel)] >> strike.key & 1 == 1;
        self.keys_down[usize::from(strike.channel)] |= 1 << strike.key;
        self.presses += 1;
        let press = &mut self.pressed[usize::from(strike.channel)][usize::from(strike.key)];
        let mut under = [None; OVERLAPS];
        if down && let Some(id) = press.id.filter(|&id| voice != Some(id)) {
            // The oldest drops out when more overlap.
            under[..OVERLAPS - 1].copy_from_slice(&press.under[1..]);
            under[OVERLAPS - 1] = Some(id);
        }
        *press =
            Press { order: self.presses, id: voice, pressure: 0.0, slide: self.requested.mode == Mode::Slide, under };
        let note = Note { voice, channel: strike.channel, key: strike.key };
        // A note takes the settings of its own sample, the latest the host set, though the
        // controls they steer go on at the control block's: a mode, a hardness or a slide's mass
        // automated to change with a note is that note's, wherever the blocks fall.
        let index = match self.requested.mode {
            Mode::Piano => self.note_on(strike),
            Mode::Slide => self.slide_on(strike).map(|i| self.voices.len() + i),
        };
        if let Some(i) = index {
            self.notes.start(i, note, self.now);
        }
    }

    /// Release `key` on `channel`: its note-off.
    fn key_up(&mut self, channel: u8, key: u8) {
        let mut keys = [0; 16];
        keys[usize::from(channel & 15)] = 1 << (key & 127);
        self.keys_up(&keys);
    }

    /// Release `keys` (one bit per MIDI key, a word per channel), as their note-offs do: their
    /// dampers fall unless a pedal holds them, and their slides let go, or, following keys,
    /// glide back to the latest key still held on their channel.
    fn keys_up(&mut self, keys: &[u128; 16]) {
        let released = |channel: u8, key: u8| keys[usize::from(channel & 15)] >> (key & 127) & 1 == 1;
        for (down, up) in self.keys_down.iter_mut().zip(keys) {
            *down &= !up;
        }
        for v in &mut self.voices {
            v.keys_up(released);
        }
        // Following keys as a note struck now would (the setting of this sample, not the block's).
        let (follow, offset) = (self.requested.follow_key, self.voices.len());
        let kept = self.kept_channels();
        // The keys other slide voices play, held: a voice let go returns to none of them (with
        // following keys switched on under notes that each took a voice).
        let mut playing = [0u128; 16];
        for v in self.slides.iter().filter(|v| v.sounding && v.key_down && !released(v.strike.channel, v.strike.key)) {
            playing[usize::from(v.strike.channel)] |= 1 << v.strike.key;
        }
        for (j, v) in self.slides.iter_mut().enumerate().filter(|(_, v)| released(v.strike.channel, v.strike.key)) {
            let c = usize::from(v.strike.channel);
            let (down, pressed) = (self.keys_down[c] & !playing[c], &self.pressed[c]);
            let latest = (0..128u8)
                .filter(|&k| down >> k & 1 == 1 && pressed[usize::from(k)].slide)
                .max_by_key(|&k| pressed[usize::from(k)].order);
            match latest {
                Some(key) if follow && v.key_down => {
                    // The released note ends; the voice plays the held key's, whose own note
                    // ended (and was reported) when this one took its voice: a note without an
                    // id, which events for the key reach, and those for the id the key was
                    // pressed with (`each_slide`).
                    v.return_to(key, pressed[usize::from(key)].pressure);
                    playing[c] |= 1 << key;
                    self.notes.start(offset + j, Note { voice: None, channel: v.strike.channel, key }, self.now);
                }
                _ => release_slide(v, &kept),
            }
        }
    }

    /// The keys `target` addresses, a word of bits per channel: those of the sounding notes it
    /// matches and the keys held down on its channels (those pressed with its voice id, when it
    /// names one).
    fn addressed_keys(&self, target: NoteTarget) -> [u128; 16] {
        let mut keys = [0; 16];
        let on_key = target.key.map_or(u128::MAX, |k| 1 << (k & 127));
        for (c, (keys, down)) in keys.iter_mut().zip(self.keys_down).enumerate() {
            if target.channel.is_some_and(|channel| usize::from(channel & 15) != c) {
                continue;
            }
            *keys = match target.voice {
                None => down & on_key,
                Some(id) => {
                    (0..128).filter(|&k| self.pressed[c][k].id == Some(id)).fold(0, |m, k| m | 1 << k) & down & on_key
                }
            };
        }
        for (_, note) in self.notes.addressed(target) {
            keys[usize::from(note.channel)] |= 1 << note.key;
        }
        keys
    }

    /// The note-off of the notes `target` addresses ([`Event::Release`]): the keys they hold go
    /// up. A note-off naming an id, a channel and a key (or an id alone, which the held key
    /// pressed with it gives the rest: [`with_its_key`](Self::with_its_key)) is that note's: for
    /// a note a later press of its key came over, held down, only its own voice lets go (a slide
    /// not following keys gives each press a voice), the key staying held; for an id that
    /// addresses nothing (one the engine was never told), its key goes up as at a MIDI note-off.
    fn release(&mut self, target: NoteTarget) {
        let target = self.with_its_key(target);
        let (Some(_), Some(channel), Some(key)) = (target.voice, target.channel, target.key) else {
            self.keys_up(&self.addressed_keys(target));
            return;
        };
        if self.take_under(target) {
            let offset = self.voices.len();
            for (i, _) in self.notes.addressed(target) {
                match i.checked_sub(offset) {
                    None => self.voices[i].release(),
                    Some(j) => self.slides[j].key_up(),
                }
            }
            return;
        }
        let mut keys = self.addressed_keys(target);
        if keys == [0; 16] {
            keys[usize::from(channel & 15)] = 1 << (key & 127);
        }
        self.keys_up(&keys);
    }

    /// `target` with the channel and key it leaves out filled in, when it names an id that
    /// exactly one held key was pressed with or came over (a host may end a note by its id
    /// alone); else `target` as it is.
    fn with_its_key(&self, target: NoteTarget) -> NoteTarget {
        let Some(id) = target.voice.filter(|_| target.channel.is_none() || target.key.is_none()) else {
            return target;
        };
        let mut found = None;
        for c in 0..16u8 {
            if target.channel.is_some_and(|channel| channel & 15 != c) {
                continue;
            }
            for k in 0..128u8 {
                let press = &self.pressed[usize::from(c)][usize::from(k)];
                let held = self.keys_down[usize::from(c)] >> k & 1 == 1;
                if held
                    && target.key.is_none_or(|key| key & 127 == k)
                    && (press.id == Some(id) || press.under.contains(&Some(id)))
                {
                    if found.is_some() {
                        return target;
                    }
                    found = Some((c, k));
                }
            }
        }
        found.map_or(target, |(c, k)| NoteTarget { voice: Some(id), channel: Some(c), key: Some(k) })
    }

    /// Whether `target` (an id, a channel and a key) names a note that a later press of its key,
    /// still held, came over: then it is struck off the press's list, and only its own voice is
    /// to let go or fade.
    fn take_under(&mut self, target: NoteTarget) -> bool {
        let (Some(id), Some(channel), Some(key)) = (target.voice, target.channel, target.key) else { return false };
        let (c, key) = (usize::from(channel & 15), key & 127);
        let held = self.keys_down[c] >> key & 1 == 1;
        let press = &mut self.pressed[c][usize::from(key)];
        match press.under.iter_mut().find(|under| **under == Some(id)).filter(|_| held) {
            Some(slot) => {
                *slot = None;
                true
            }
            None => false,
        }
    }

    /// Fade out the voices of the notes `target` addresses and let them fall silent
    /// ([`Event::Choke`]).
    fn choke(&mut self, target: NoteTarget) {
        let fs = self.sample_rate;
        for (i, _) in self.notes.addressed(target) {
            if let Some(voice) = self.voices.get_mut(i) {
                voice.choke(fs);
            }
        }
        self.each_slide(target, |v, _| {
            v.shed(fs);
        });
    }

    /// Set a channel controller (0..=1, NaN is 0) that `field` picks, on `channel` and on the
    /// channels it speaks for (an MPE zone's master channel speaks for its members).
    fn set_controller(&mut self, channel: u8, value: f32, field: fn(&mut ChannelState) -> &mut f64) {
        let value = unit(value, 0.0);
        self.bends.spoken_for(channel).for_each(|c| *field(&mut self.channels[c]) = value);
    }

    /// Apply `f` (with the latest settings, those a note struck now takes) to the slide voices
    /// playing the addressed notes: a target naming an id reaches too the note a voice returned
    /// to (following keys), in the book without an id, when its key was pressed with that id.
    /// Expressions and chokes reach slide voices through here.
    fn each_slide(&mut self, target: NoteTarget, mut f: impl FnMut(&mut SlideVoice, &Settings)) {
        let (offset, settings) = (self.voices.len(), self.note_settings());
        let pressed = &self.pressed;
        let returned = |note: &Note| {
            note.voice.is_none()
                && target
                    .voice
                    .is_some_and(|id| pressed[usize::from(note.channel)][usize::from(note.key)].id == Some(id))
                && NoteTarget { voice: None, ..target }.matches(note)
        };
        for j in self.notes.live_in(offset..offset + self.slides.len()) {
            if self.notes.get(offset + j).is_some_and(|note| target.matches(&note) || returned(&note)) {
                f(&mut self.slides[j], &settings);
            }
        }
    }

    /// The flat voice indices of the note book: the piano voices', then the slide voices'.
    fn pools(&self) -> (Range<usize>, Range<usize>) {
        let pianos = self.voices.len();
        (0..pianos, pianos..pianos + self.slides.len())
    }

    /// Queue the notes of voices that have fallen silent.
    fn check_ended(&mut self) {
        let now = self.now;
        // Only voices with a live note can end one: the book knows which, without a pass over
        // every voice.
        let (voices, slides) = (&self.voices, &self.slides);
        let offset = voices.len();
        self.notes.check_live(now, |i| match voices.get(i) {
            Some(v) => v.sounding || v.fading(),
            None => slides.get(i - offset).is_some_and(|v| v.sounding),
        });
    }

    /// The dampers as the pedals leave them for notes on `channel`: the sustain pedal's and the
    /// keys the sostenuto pedal holds, read through [`for_channel`], and the keys held down.
    fn dampers(&self, channel: u8) -> Dampers {
        Dampers {
            lift: damper_lift(for_channel(&self.sustain, channel, f64::max), &self.settings),
            held: self.held_keys(),
            caught: for_channel(&self.caught, channel, |a, b| a | b),
        }
    }

    /// The sostenuto pedal on `channel` goes down or up. Going down it catches the dampers of
    /// the keys held down on its channel, on every channel for an MPE zone's master channel (1
    /// or 16, as the sustain pedal speaks for every channel there); a pedal already down
    /// catches nothing more. Coming up it lets them go.
    fn sostenuto(&mut self, channel: u8, down: bool) {
        let c = usize::from(channel);
        if down && !self.sostenuto[c] {
            self.caught[c] = if c == 0 || c == 15 { self.held_keys() } else { self.keys_down[c] };
        } else if !down {
            self.caught[c] = 0;
        }
        self.sostenuto[c] = down;
    }

    /// The keys held down, whatever their channel, one bit per MIDI key.
    fn held_keys(&self) -> u128 {
        self.keys_down.iter().fold(0, |held, keys| held | keys)
    }

    /// The settings a note takes at its own sample: the latest the host set, in the control block
    /// under way.
    fn note_settings(&self) -> Settings {
        Settings { block: self.settings.block, ..self.requested }
    }

    /// Strike `strike` on a piano voice under the latest settings; the index of the voice that
    /// took it.
    fn note_on(&mut self, strike: Strike) -> Option<usize> {
        let (now, settings) = (self.now, self.note_settings());
        let dampers = self.dampers(strike.channel);
        self.partners.request(&settings);
        // The same key again: strike the same string.
        if let Some(i) = self.voices.iter().position(|v| v.upcoming_key() == Some(strike.key)) {
            if self.voices[i].fading() {
                self.voices[i].steal(strike, &settings, now);
            } else {
                Self::meet_elsewhere(&mut self.voices, i, strike.key, &settings);
                self.voices[i].play_with(strike, &settings, now, Some((self.partners.ready(), dampers)));
            }
            return Some(i);
        }
        // A free voice: the one that last played this key, whose strings are prepared for it
        // while the settings stay, else the one whose note began longest ago, so that the free
        // voices keep the keys played latest prepared.
        let free = |v: &PianoVoice| !v.sounding && !v.fading();
        let last_played = self.voices.iter().position(|v| free(v) && v.strike.key == strike.key);
        let oldest = || {
            let (i, _) = self.voices.iter().enumerate().filter(|(_, v)| free(v)).min_by_key(|(_, v)| v.started)?;
            Some(i)
        };
        if let Some(i) = last_played.or_else(oldest) {
            Self::meet_elsewhere(&mut self.voices, i, strike.key, &settings);
            self.voices[i].play_with(strike, &settings, now, Some((self.partners.ready(), dampers)));
            return Some(i);
        }
        // Steal the least audible voice: the quietest over its latest window, the notes not
        // heard yet last and the oldest of them first. When every voice is fading already, the
        // one whose next note came first (or that has none) gives it up to this note, the newest:
        // that note ends unheard.
        let victim = (self.voices.iter().enumerate())
            .filter(|(_, v)| !v.fading())
            .min_by(|(_, a), (_, b)| a.loudness().total_cmp(&b.loudness()).then(a.started.cmp(&b.started)))
            .or_else(|| self.voices.iter().enumerate().min_by_key(|(_, v)| v.started))
            .map(|(i, _)| i);
        if let Some(i) = victim {
            self.steals += 1;
            self.voices[i].steal(strike, &settings, now);
        }
        victim
    }

    /// Tell voice `index`, about to strike `key`, where the key's strings are on the other
    /// voices' bridges at its striking point: the hammer meets them there too (docs/physics.md
    /// §14.3).
    fn meet_elsewhere(voices: &mut [PianoVoice], index: usize, key: u8, settings: &Settings) {
        let ell = voices[index].striking_point_for(key, settings);
        let elsewhere = (voices.iter().enumerate())
            .filter_map(|(i, v)| v.partner_index(key).filter(|_| i != index).map(|j| v.partner_motion(j, ell)))
            .fold(Elsewhere::default(), |sum, x| sum + x);
        voices[index].meet(elsewhere);
    }

    /// Pluck `strike` on a slide voice under the latest settings; the index of the voice that
    /// took it.
    fn slide_on(&mut self, strike: Strike) -> Option<usize> {
        let (now, settings) = (self.now, self.note_settings());
        let channel = self.channel_state(strike.channel);
        // Following keys, a new key while another is held on the channel glides there (legato).
        if settings.follow_key
            && let Some(i) =
                self.slides.iter().position(|v| v.sounding && v.key_down && v.strike.channel == strike.channel)
        {
            // The key it plays, struck again, plucks again.
            let legato = self.slides[i].strike.key != strike.key;
            self.slides[i].play(strike, &settings, &channel, legato, now);
            return Some(i);
        }
        // A free voice, else the one whose string moves least (the oldest among equals), not being
        // shed: its string keeps its motion, so reuse does not click. A voice still plucking goes
        // last, so that the notes of a chord never take one another's voices. The motion is
        // weighed at control blocks, so the choice does not depend on the host's buffers.
        let quietest = |shedding: bool| {
            let candidates = self.slides.iter().enumerate().filter(|(_, v)| shedding || !v.shedding());
            candidates.min_by(|(_, a), (_, b)| {
                (a.plucking().cmp(&b.plucking()))
                    .then(a.motion().total_cmp(&b.motion()))
                    .then(a.started.cmp(&b.started))
            })
        };
        let index = (self.slides.iter().position(|v| !v.sounding))
            .or_else(|| quietest(false).map(|(i, _)| i))
            .or_else(|| quietest(true).map(|(i, _)| i));
        if let Some(i) = index {
            self.steals += u64::from(self.slides[i].sounding);
            let voice = &mut self.slides[i];
            // A silent voice's pickup stayed where the voice last sounded (see `begin_block`).
            if voice.pickup() != self.pickup {
                voice.set_pickup(self.pickup, 0);
            }
            voice.play(strike, &settings, &channel, false, now);
        }
        index
    }

    /// Render into `left` and `right` (the same length), replacing their contents.
    pub fn process(&mut self, left: &mut [f32], right: &mut [f32]) {
        let n = left.len().min(right.len());
        left.fill(0.0);
        right.fill(0.0);
        let (pianos, slides) = self.pools();
        let mut done = 0;
        while done < n {
            if self.in_block == 0 {
                self.begin_block();
            }
            self.begin_first_slide_blocks();
            let len = (self.settings.block - self.in_block).min(n - done);
            let scratch = &mut self.scratch[..len];
            let [bus_l, bus_r, bus_s, bus_a] = &mut self.buses;
            let (bus_l, bus_r) = (&mut bus_l[..len], &mut bus_r[..len]);
            let (bus_s, bus_a) = (&mut bus_s[..len], &mut bus_a[..len]);
            for bus in [&mut *bus_l, &mut *bus_r, &mut *bus_s, &mut *bus_a] {
                bus.fill(0.0);
            }
            self.sides.begin();
            let width = if self.raw { 0.0 } else { self.settings.stereo_width };
            // Only the voices with live notes can sound: the others are not looked at. Those whose
            // hammers meet their strings' motion on other voices' bridges come last.
            let (voices, backgrounds, meeting) = (&mut self.voices, &mut self.backgrounds, &mut self.meeting);
            order_meetings(voices, self.notes.live_in(pianos.clone()), meeting, backgrounds, len);
            let meets = meeting.iter().fold(0u128, |m, &i| m | 1 << i);
            let others = self.notes.live_in(pianos.clone()).filter(move |&i| meets & 1 << i == 0).map(|i| (i, 0));
            for (i, later) in others.chain(self.meeting.iter().enumerate().map(|(k, &i)| (i, k + 1))) {
                if !self.voices[i].sounding {
                    continue;
                }
                render_piano(&mut self.voices, &mut self.backgrounds, &self.meeting, i, later, scratch);
                let voice = &mut self.voices[i];
                let pan = pan_gains(voice.strike.key, width);
                let gains = Gains { voicing: voice.voicing, pan, rate: self.voicing_rate };
                mix_voiced(scratch, &gains, &mut voice.voiced, &mut voice.pan, bus_l, bus_r);
            }
            for i in self.notes.live_in(slides.clone()) {
                let voice = &mut self.slides[i];
                if !voice.sounding {
                    continue;
                }
                if voice.body == SlideBody::Acoustic && !self.raw {
                    self.sides.render(voice, scratch);
                } else {
                    voice.render(scratch);
                }
                let bus = match voice.body {
                    SlideBody::Pickup => &mut *bus_s,
                    SlideBody::Acoustic => &mut *bus_a,
                };
                add(bus, scratch);
            }
            if !self.raw {
                self.boards[0].process(bus_l);
                self.boards[1].process(bus_r);
                self.circuit.process(bus_s);
            }
            let (l, r) = (&mut left[done..done + len], &mut right[done..done + len]);
            for (((l, r), (pl, pr)), (s, a)) in
                l.iter_mut().zip(r.iter_mut()).zip(bus_l.iter().zip(bus_r.iter())).zip(bus_s.iter().zip(bus_a.iter()))
            {
                let slide = s * SLIDE_SCALE + a * ACOUSTIC_SCALE;
                *l = (pl * OUTPUT_SCALE + slide) as f32;
                *r = (pr * OUTPUT_SCALE + slide) as f32;
            }
            self.sides.pan(l, r, width, self.voicing_rate);
            self.output.process(l, r, self.settings.limiter);
            done += len;
            self.now += len as u64;
            self.in_block += len;
            if self.in_block >= self.settings.block {
                self.in_block = 0;
            }
        }
    }

    /// Output the dry signals (`true`): each piano key's bridge force and each slide voice's
    /// string velocity at the pickup (on the acoustic guitar, what its body radiates, which its
    /// string is coupled to), centred, without the soundboard's radiation, the stereo pan or the
    /// pickup's circuit; what research renders compare against the scenes. The soundboards and
    /// the circuit, which the dry signals pass by, start again from rest when they come back:
    /// what they held when left would ring out under signals that never went through them.
    pub fn set_raw_output(&mut self, raw: bool) {
        if raw != self.raw {
            self.boards.iter_mut().for_each(Body::reset);
            self.circuit.reset();
        }
        self.raw = raw;
    }

    fn begin_block(&mut self) {
        self.settings = self.requested;
        let len = self.settings.block;
        self.output.set_gain(self.settings.gain);
        // The pickup's resonance glides, an octave per 50 ms at most, instead of stepping.
        let target = self.settings.pickup_resonance;
        if self.resonance != target {
            let octaves = len as f64 / self.sample_rate / PICKUP_GLIDE;
            let (down, up) = (0.5f64.powf(octaves), 2f64.powf(octaves));
            self.resonance = (self.resonance * (target / self.resonance).clamp(down, up))
                .clamp(target.min(self.resonance), target.max(self.resonance));
            self.circuit.tune(self.resonance, self.sample_rate, len);
        }
        self.partners.request(&self.settings);
        let mut seeks = PARTNER_SEEKS;
        let dampers: [Dampers; 16] = std::array::from_fn(|channel| self.dampers(channel as u8));
        // A voice neither sounding nor fading for a new note has nothing to do at a block's start;
        // only those with live notes can be either.
        let (pianos, slides) = self.pools();
        for i in self.notes.live_in(pianos) {
            if let Some((key, settings)) = self.voices[i].starts_now() {
                let settings = *settings;
                Self::meet_elsewhere(&mut self.voices, i, key, &settings);
            }
            let v = &mut self.voices[i];
            if !(v.sounding || v.fading()) {
                continue;
            }
            let dampers = dampers[usize::from(v.channel_now() & 15)];
            v.begin_block(&self.settings, dampers, len, self.now, Some(&mut self.partners), &mut seeks);
        }
        // The pickup slides to a new position instead of jumping: its weights move a little in
        // each block, linearly across the block, never in one audible step.
        let reach = PICKUP_SPEED * len as f64 / self.sample_rate;
        let pickup = self.pickup + (self.settings.pickup_position - self.pickup).clamp(-reach, reach);
        let move_pickup = self.pickup != pickup;
        self.pickup = pickup;
        for i in self.notes.live_in(slides) {
            if !self.slides[i].sounding {
                continue;
            }
            let channel = self.channel_state(self.slides[i].strike.channel);
            let v = &mut self.slides[i];
            // Only the voices sounding follow the pickup; a silent one takes its place when
            // plucked (`slide_on`), so that the idle voices cost nothing while it moves.
            if move_pickup {
                v.set_pickup(pickup, len);
            }
            v.begin_block(&self.settings, &channel, len);
        }
        self.check_ended();
    }

    /// The slide voices plucked from silence inside this control block begin their first block
    /// at once, for the rest of this one: their notes sound from their own sample, and their
    /// blocks fall on the instrument's.
    fn begin_first_slide_blocks(&mut self) {
        let (_, slides) = self.pools();
        let len = self.settings.block - self.in_block;
        for i in self.notes.live_in(slides) {
            if self.slides[i].fresh() {
                let (settings, channel) = (self.note_settings(), self.channel_state(self.slides[i].strike.channel));
                self.slides[i].begin_block(&settings, &channel, len);
            }
        }
    }

    /// What a slide note let go keeps of each channel: the state of an MPE zone's member
    /// channels, which the controller hands to the next note (none for the other channels, whose
    /// release tails follow them as they do under any synthesiser).
    fn kept_channels(&self) -> [Option<ChannelState>; 16] {
        std::array::from_fn(|c| self.bends.master(c as u8).map(|_| self.channel_state(c as u8)))
    }

    /// What a slide voice reads from `channel`: its controllers, its pitch-bend sensitivity and
    /// the bend of its MPE zone's master channel (semitones).
    fn channel_state(&self, channel: u8) -> ChannelState {
        let range = |c: u8| self.bends.range(c).unwrap_or(self.settings.bend_range);
        let zone_bend = self.bends.master(channel).map_or(0.0, |m| self.channels[usize::from(m)].bend * range(m));
        ChannelState { bend_range: self.bends.range(channel), zone_bend, ..self.channels[usize::from(channel & 15)] }
    }
}

/// Let go of `v`'s key, the note keeping its channel's state if `kept` holds one for it
/// ([`Instrument::kept_channels`]).
fn release_slide(v: &mut SlideVoice, kept: &[Option<ChannelState>; 16]) {
    match &kept[usize::from(v.strike.channel & 15)] {
        Some(channel) => v.key_up_keeping(channel),
        None => v.key_up(),
    }
}

/// What a per-channel controller says for notes on `channel`: its own channel's value joined (by
/// `join`) with those of an MPE zone's master channels (MIDI channel 1 for the lower zone, 16 for
/// the upper), whose controllers apply to every note of the zone.
fn for_channel<T: Copy>(per_channel: &[T; 16], channel: u8, join: impl Fn(T, T) -> T) -> T {
    join(join(per_channel[usize::from(channel & 15)], per_channel[0]), per_channel[15])
}

/// Shed up to `count` of `voices` with `shed` (whether the voice began to fade), the lowest
/// `rank` first among those it ranks (the voices that may be shed); how many.
fn shed_lowest<V>(
    voices: &mut [V],
    count: usize,
    rank: impl Fn(&V) -> Option<f64>,
    mut shed: impl FnMut(&mut V) -> bool,
) -> usize {
    let mut done = 0;
    while done < count {
        let lowest =
            (voices.iter().enumerate()).filter_map(|(i, v)| rank(v).map(|r| (i, r))).min_by(|a, b| a.1.total_cmp(&b.1));
        let Some((i, _)) = lowest else { break };
        if !shed(&mut voices[i]) {
            break;
        }
        done += 1;
    }
    done
}

/// Find the piano voices among `live` whose hammers can still touch strings that ring on other
/// voices' bridges, put them in `meeting` in the order they render (the oldest strike first) and
/// clear their backgrounds for the coming `len` samples.
fn order_meetings(
    voices: &[PianoVoice],
    live: impl Iterator<Item = usize> + Clone,
    meeting: &mut Vec<usize>,
    backgrounds: &mut [Vec<f64>],
    len: usize,
) {
    meeting.clear();
    let live = live.filter(|&i| voices[i].sounding);
    if !live.clone().any(|i| voices[i].hammer_live()) {
        return;
    }
    let rung = live.clone().fold(0u128, |m, i| m | voices[i].partner_mask());
    meeting.extend(live.filter(|&i| voices[i].hammer_live() && rung & 1 << voices[i].strike.key != 0));
    meeting.sort_unstable_by_key(|&i| (voices[i].started, i));
    for &i in meeting.iter() {
        backgrounds[i][..len].fill(0.0);
    }
}

/// Render piano voice `index` into `out`, handing the motion of its partners to the voices
/// `meeting[later..]` that strike them, and meeting its own strings' motion on the bridges of the
/// voices rendered before it if it is among `meeting` (docs/physics.md §14.3).
fn render_piano(
    voices: &mut [PianoVoice],
    backgrounds: &mut [Vec<f64>],
    meeting: &[usize],
    index: usize,
    later: usize,
    out: &mut [f64],
) {
    if meeting.is_empty() {
        voices[index].render(out);
        return;
    }
    let mut watches = [Watch::default(); MAX_PARTNERS];
    let mut count = 0;
    for &c in &meeting[later.min(meeting.len())..] {
        let (struck, voice) = (&voices[c], &voices[index]);
        if let Some(j) = voice.partner_index(struck.strike.key).filter(|_| count < MAX_PARTNERS && c != index) {
            watches[count] = Watch::new(j, struck.striking_position(), c);
            count += 1;
        }
    }
    let meets = meeting.contains(&index);
    let background = if meets { std::mem::take(&mut backgrounds[index]) } else { Vec::new() };
    let shared = Shared {
        background: &background[..out.len().min(background.len())],
        watches: &watches[..count],
        sinks: backgrounds,
    };
    voices[index].render_shared(out, shared);
    if meets {
        backgrounds[index] = background;
    }
}

/// Where a piano voice's gains go: its voicing, its pan, and the fraction of the way a gain
/// moves to its target each sample.
struct Gains {
    voicing: f64,
    pan: [f64; 2],
    rate: f64,
}

/// The left and right gains of `key` at stereo width `width` (−1..=1): a constant-power pan by
/// the key's place along the bridge, A0 at `−width` and C8 at `+width` (`−1` full left), the
/// gains `√2·cos θ` and `√2·sin θ`, `θ = (1 + place)·π/4`: 1 and 1 in the centre, and the same
/// power (`g_L² + g_R² = 2`) everywhere.
pub fn pan_gains(key: u8, width: f64) -> [f64; 2] {
    let place = ((f64::from(key) - 64.5) / 43.5).clamp(-1.0, 1.0) * width.clamp(-1.0, 1.0);
    let angle = (1.0 + place) * std::f64::consts::FRAC_PI_4;
    [std::f64::consts::SQRT_2 * angle.cos(), std::f64::consts::SQRT_2 * angle.sin()]
}

/// The left and right gains of the acoustic guitar body's modes heard on the left at stereo
/// width `width` (−1..=1); those on the right take them the other way round. A constant-power pan
/// to the place `−width` (the gains `cos x + sin x` and `cos x − sin x`, `x = width·π/4`, as
/// [`pan_gains`]'s): 1 and 1 at width 0, where the guitar is heard as its whole body radiates,
/// and the same power (`g_L² + g_R² = 2`) at every width.
pub fn side_gains(width: f64) -> [f64; 2] {
    let (s, c) = (width.clamp(-1.0, 1.0) * std::f64::consts::FRAC_PI_4).sin_cos();
    [c + s, c - s]
}

/// Add `x` to `bus`.
fn add(bus: &mut [f64], x: &[f64]) {
    bus.iter_mut().zip(x).for_each(|(b, x)| *b += x);
}

/// The acoustic guitar body's sides (docs/physics.md §13.6): the shares of the body's output that
/// its modes on the left and on the right radiate, summed over the voices for one control block,
/// and the gains that pan them.
#[derive(Debug, Clone)]
struct BodySides {
    /// One voice's block of the two shares, and their sums over the voices.
    scratch: [Vec<f64>; 2],
    buses: [Vec<f64>; 2],
    /// Whether a voice has put its shares on the buses in this block, and in the block before.
    heard: bool,
    heard_before: bool,
    /// The gains of the modes on the left in the left and the right channel, gliding to
    /// [`side_gains`] at the stereo width (the right's are the other way round).
    gains: [f64; 2],
}

impl BodySides {
    fn new() -> Self {
        let block = || vec![0.0; MAX_BLOCK];
        Self {
            scratch: [block(), block()],
            buses: [block(), block()],
            heard: false,
            heard_before: false,
            gains: [1.0; 2],
        }
    }

    /// As made: nothing heard, the gains where they start.
    fn reset(&mut self) {
        self.heard = false;
        self.heard_before = false;
        self.gains = [1.0; 2];
    }

    /// Start a block: no voice has put its shares on the buses yet.
    fn begin(&mut self) {
        self.heard_before = self.heard;
        self.heard = false;
    }

    /// Render `voice` into `out` and add its shares to the buses (the first voice of a block
    /// clears them).
    fn render(&mut self, voice: &mut SlideVoice, out: &mut [f64]) {
        let len = out.len();
        if !self.heard {
            self.buses.iter_mut().for_each(|b| b[..len].fill(0.0));
            self.heard = true;
        }
        let [x, y] = &mut self.scratch;
        voice.render_sides(out, [&mut x[..len], &mut y[..len]]);
        for (bus, share) in self.buses.iter_mut().zip(&self.scratch) {
            add(&mut bus[..len], &share[..len]);
        }
    }

    /// Pan the block's shares in `left` and `right`, which hold the body's output centred: each
    /// share moves from gain 1 in both channels to its gains at stereo `width`, gliding there by
    /// `rate` of the way each sample. Nothing to do when no voice put its shares on the buses.
    fn pan(&mut self, left: &mut [f32], right: &mut [f32], width: f64, rate: f64) {
        if !self.heard {
            return;
        }
        let target = side_gains(width);
        if !self.heard_before {
            // Nothing was heard through the gains: they start where the width puts them.
            self.gains = target;
        }
        let [mut to_left, mut to_right] = self.gains;
        let [x, y] = &self.buses;
        for (((l, r), x), y) in left.iter_mut().zip(right.iter_mut()).zip(x).zip(y) {
            to_left += (target[0] - to_left) * rate;
            to_right += (target[1] - to_right) * rate;
            *l += (((to_left - 1.0) * x + (to_right - 1.0) * y) * ACOUSTIC_SCALE) as f32;
            *r += (((to_right - 1.0) * x + (to_left - 1.0) * y) * ACOUSTIC_SCALE) as f32;
        }
        self.gains = [to_left, to_right];
    }
}

/// Add `x · g · p_L` and `x · g · p_R` to the buses, with the voicing gain `g` (from `voiced`)
/// and the pan gains `p` (from `pan`, or the target for a note not mixed yet) moving towards
/// their targets by `gains.rate` each sample: a voice struck again at another dynamic level, or
/// a width moved, changes smoothly.
fn mix_voiced(
    x: &[f64],
    gains: &Gains,
    voiced: &mut f64,
    pan: &mut Option<[f64; 2]>,
    left: &mut [f64],
    right: &mut [f64],
) {
    let (mut g, [mut pl, mut pr]) = (*voiced, pan.unwrap_or(gains.pan));
    for ((l, r), &v) in left.iter_mut().zip(right.iter_mut()).zip(x) {
        g += (gains.voicing - g) * gains.rate;
        pl += (gains.pan[0] - pl) * gains.rate;
        pr += (gains.pan[1] - pr) * gains.rate;
        *l += v * g * pl;
        *r += v * g * pr;
    }
    *voiced = g;
    *pan = Some([pl, pr]);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Which piano voice sounds `key`.
    fn voice_of(instrument: &Instrument, key: u8) -> Option<usize> {
        instrument.voices.iter().position(|v| v.sounding && v.strike.key == key)
    }

    /// A new instrument has searched every key's partners before its first note, and preparing
    /// its voices sounds nothing.
    #[test]
    fn a_new_instrument_has_found_every_keys_partners_and_is_silent() {
        for voices in [1, 3] {
            let mut instrument = Instrument::new(48_000.0, voices, Settings::default());
            let (searched, keys) = instrument.partners.searched();
            assert_eq!((searched, keys), (88, 88), "{voices} voices");
            let (mut left, mut right) = ([1.0; 64], [1.0; 64]);
            instrument.process(&mut left, &mut right);
            assert!(left.iter().chain(&right).all(|&x| x == 0.0), "{voices} voices");
        }
    }

    /// Automating a setting that shapes strings while keys ring retunes no partner string until
    /// a key is struck: with a chord held under the pedal and the octave stretch moved at every
    /// block, every key's partners found when the instrument was made are still kept 50 blocks
    /// later (a retune forgets them), and the key struck then gets the partners that a table made
    /// for the stretch in force gives it, after one search.
    #[test]
    fn a_swept_setting_retunes_the_partners_only_when_a_key_is_struck() {
        let mut instrument = Instrument::new(48_000.0, 8, Settings::default());
        let (mut left, mut right) = ([0.0; 64], [0.0; 64]);
        instrument.handle(Event::Sustain { channel: 0, depth: 1.0 });
        for key in [36, 48, 55, 60] {
            instrument.handle(Event::NoteOn { channel: 0, key, velocity: 0.6 });
        }
        let mut settings = Settings::default();
        for block in 0..50 {
            settings.stretch = 2.0 * f64::from(block) / 49.0;
            instrument.set_settings(&settings);
            instrument.process(&mut left, &mut right);
        }
        assert_eq!(instrument.partners.searched(), (88, 88), "a retune while no key was struck");
        instrument.handle(Event::NoteOn { channel: 0, key: 43, velocity: 0.6 });
        assert_eq!(instrument.partners.searched(), (1, 88), "G2 struck at the stretch in force");
        let pick = |table: &PartnerTable| {
            let mut out = [(0, 0); crate::scene::MAX_PARTNERS];
            let count = table.pick(43, &mut out);
            out[..count].to_vec()
        };
        let fresh = PartnerTable::new(48_000.0, &settings);
        assert!(!pick(&fresh).is_empty());
        assert_eq!(pick(&instrument.partners), pick(&fresh));
    }

    /// A key struck again strikes its ringing strings where their hammer meets them, which is
    /// where it first struck them: with the sustain pedal down, C3 and C4 ringing (C4's strings
    /// sounding on C3's bridge too), the strike position moved from 1 to 1.15 before C4 is struck
    /// again changes nothing, to the bit.
    #[test]
    fn a_key_struck_again_strikes_its_strings_where_it_first_struck_them() {
        let render = |moved: f64| {
            let mut instrument = Instrument::new(48_000.0, 4, Settings::default());
            instrument.handle(Event::Sustain { channel: 0, depth: 1.0 });
            let mut out = Vec::new();
            let (mut left, mut right) = ([0.0; 64], [0.0; 64]);
            for block in 0..120 {
                if block == 0 {
                    for key in [48, 60] {
                        instrument.handle(Event::NoteOn { channel: 0, key, velocity: 0.6 });
                    }
                }
                if block == 20 {
                    instrument.set_settings(&Settings { strike_position: moved, ..Settings::default() });
                    instrument.handle(Event::NoteOn { channel: 0, key: 60, velocity: 0.9 });
                }
                instrument.process(&mut left, &mut right);
                out.extend(left.iter().chain(&right).map(|x| x.to_bits()));
            }
            let c4 = voice_of(&instrument, 60).map(|i| instrument.voices[i].striking_position());
            (out, c4.unwrap())
        };
        let (still, at_still) = render(1.0);
        let (moved, at_moved) = render(1.15);
        assert_eq!(at_still, at_moved, "C4's striking point");
        assert!(still == moved, "a re-strike under a moved strike position sounds as under the first");
    }

    /// A string keeps the guitar it was plucked on from silence until it falls silent: with one
    /// voice, a note that takes it over while it rings (stolen, and legato) stays on the electric
    /// guitar after the acoustic one was chosen, and the note after all sound off is on the
    /// acoustic one.
    #[test]
    fn a_sounding_string_keeps_its_guitar_through_the_notes_that_take_it_over() {
        let electric = Settings { mode: Mode::Slide, ..Settings::default() };
        let acoustic = Settings { slide_body: SlideBody::Acoustic, ..electric };
        let mut instrument = Instrument::new(48_000.0, 1, electric);
        let (mut left, mut right) = ([0.0; 64], [0.0; 64]);
        let on = |key| Event::NoteOn { channel: 0, key, velocity: 0.7 };
        instrument.handle(on(45));
        instrument.process(&mut left, &mut right);
        instrument.handle(Event::NoteOff { channel: 0, key: 45 });
        instrument.set_settings(&acoustic);
        for event in [on(50), on(52)] {
            instrument.process(&mut left, &mut right);
            instrument.handle(event);
            assert!(instrument.slides[0].sounding);
            assert_eq!(instrument.slides[0].body, SlideBody::Pickup, "{event:?}");
        }
        instrument.handle(Event::AllSoundOff);
        instrument.handle(on(50));
        assert_eq!(instrument.slides[0].body, SlideBody::Acoustic);
    }

    /// A slide voice silent while the pickup moved hears the string where the pickup is when
    /// plucked: the pickup moved from 0.9 to 0.5 of the length before the first note (0.4 s at
    /// its top speed), the note sounds bit for bit as on an instrument made with the pickup at 0.5.
    #[test]
    fn a_silent_slide_voice_plucked_after_the_pickup_moved_hears_it_where_it_is() {
        let at = |pickup_position| Settings { mode: Mode::Slide, pickup_position, ..Settings::default() };
        let render = |instrument: &mut Instrument, blocks: usize| {
            let (mut left, mut right, mut all) = ([0.0; 64], [0.0; 64], Vec::new());
            for _ in 0..blocks {
                instrument.process(&mut left, &mut right);
                all.extend_from_slice(&left);
            }
            all
        };
        let mut moved = Instrument::new(48_000.0, 4, at(0.9));
        moved.set_settings(&at(0.5));
        let mut made_there = Instrument::new(48_000.0, 4, at(0.5));
        let before = 0.45 * 48_000.0 / 64.0;
        for instrument in [&mut moved, &mut made_there] {
            assert!(render(instrument, before as usize).iter().all(|&x| x == 0.0));
            instrument.handle(Event::NoteOn { channel: 0, key: 52, velocity: 0.7 });
        }
        assert_eq!(moved.pickup, 0.5);
        let heard = render(&mut moved, 40);
        assert!(heard.iter().any(|&x| x != 0.0));
        assert!(heard == render(&mut made_there, 40));
    }

    /// A note takes the free voice that last played its key, whose strings are prepared for it,
    /// else the free voice whose note began longest ago (one never played counts as begun at the
    /// start): with C4, D4 and E4 played one after another on four voices and silenced, D4 takes
    /// D4's voice, G4 the unplayed one, A4 C4's, and B4 E4's.
    #[test]
    fn a_note_takes_the_voice_that_played_its_key_else_the_longest_free() {
        let mut instrument = Instrument::new(48_000.0, 4, Settings::default());
        let (mut left, mut right) = ([0.0; 64], [0.0; 64]);
        instrument.process(&mut left, &mut right);
        let mut play = |instrument: &mut Instrument, key: u8| {
            instrument.handle(Event::NoteOn { channel: 0, key, velocity: 0.6 });
            instrument.process(&mut left, &mut right);
            voice_of(instrument, key)
        };
        let first: Vec<_> = [60, 62, 64].into_iter().map(|key| play(&mut instrument, key)).collect();
        assert_eq!(first, [Some(0), Some(1), Some(2)]);
        instrument.handle(Event::AllSoundOff);
        assert_eq!(play(&mut instrument, 62), Some(1), "D4 again");
        assert_eq!(play(&mut instrument, 67), Some(3), "G4, a new key");
        assert_eq!(play(&mut instrument, 69), Some(0), "A4");
        assert_eq!(play(&mut instrument, 71), Some(2), "B4");
    }

    /// Play the keys `lower` at velocity 0.7 with the pedal down, then C4 at velocity 0.7 `delay`
    /// seconds later (host buffers of `buffer` samples until then). Returns the instrument and
    /// C4's voice.
    fn c4_after(lower: &[u8], delay: f64, buffer: usize) -> (Instrument, usize) {
        let mut instrument = Instrument::new(48_000.0, 8, Settings::default());
        instrument.handle(Event::Sustain { channel: 0, depth: 1.0 });
        for &key in lower {
            instrument.handle(Event::NoteOn { channel: 0, key, velocity: 0.7 });
        }
        let n = (delay * 48_000.0) as usize;
        let (mut left, mut right) = (vec![0.0f32; n], vec![0.0f32; n]);
        for (l, r) in left.chunks_mut(buffer).zip(right.chunks_mut(buffer)) {
            instrument.process(l, r);
        }
        instrument.handle(Event::NoteOn { channel: 0, key: 60, velocity: 0.7 });
        let c4 = voice_of(&instrument, 60).unwrap();
        (instrument, c4)
    }

    /// C4 struck while C2 and C3 ring its strings on their bridges (the pedal down): at every
    /// step while its hammer can touch them, the motion its hammer meets besides its own strings'
    /// is the sum of what the two bridges give C4's strings at its striking point (to 1e-12 of
    /// its largest), and it is there (above 1 µm). Host buffers of 1 sample and of sizes that
    /// split the control blocks anywhere give C4 the same contact forces to 1e-12 of the peak:
    /// the voices that ring the strings render first in every part of a block.
    #[test]
    fn a_key_struck_while_its_strings_ring_on_other_bridges_meets_them_there() {
        let forces = |sizes: &[usize]| {
            let (mut instrument, c4) = c4_after(&[36, 48], 0.5, 64);
            let ell = instrument.voices[c4].striking_position();
            let (mut worst, mut largest, mut forces) = (0.0f64, 0.0f64, vec![]);
            let (mut left, mut right) = ([0.0f32; 256], [0.0f32; 256]);
            let mut done = 0;
            for &n in sizes.iter().cycle() {
                if done >= 480 {
                    break;
                }
                instrument.process(&mut left[..n], &mut right[..n]);
                done += n;
                forces.push((done, instrument.voices[c4].contact().1));
                if !instrument.voices[c4].hammer_live() {
                    continue;
                }
                let elsewhere: f64 = instrument
                    .voices
                    .iter()
                    .filter_map(|v| v.partner_index(60).map(|j| v.partner_motion(j, ell).motion.1))
                    .sum();
                worst = worst.max((instrument.voices[c4].background() - elsewhere).abs());
                largest = largest.max(elsewhere.abs());
            }
            (worst, largest, forces)
        };
        let (worst, largest, one) = forces(&[1]);
        println!("background: largest {largest:.3e} m, worst difference {worst:.1e} m");
        assert!(largest > 1e-6, "C2 and C3 ring C4's strings: {largest:e}");
        assert!(worst <= 1e-12 * largest, "{worst:e}");
        let peak = one.iter().map(|(_, f)| f.abs()).fold(0.0, f64::max);
        for sizes in [&[7usize, 64, 100, 1, 33][..], &[256], &[63, 65]] {
            let (_, _, other) = forces(sizes);
            for (done, force) in other.into_iter().filter(|&(done, _)| done <= one.len()) {
                let (_, want) = one[done - 1];
                assert!(
                    (force - want).abs() <= 1e-12 * peak,
                    "buffers {sizes:?}, sample {done}: {force} against {want}"
                );
            }
        }
    }

    /// C4 struck 1 s after C3 with the pedal down meets its strings moving as C3 set them
    /// ringing: struck at 16 instants a quarter of a millisecond apart (a period of C4 and
    /// more), its peak contact force against C4 struck alone rises and falls with the strings'
    /// phase, by at least 5 % from the lowest to the highest (measured 0.952 to 1.055), and stays
    /// within what the strings' motion can change: from their speed at the striking point, at
    /// most 0.24 m/s against the hammer's 2.85 m/s (velocity 0.7), and a felt of exponent
    /// `α` = 2.5 whose peak force follows the speed as `v^(2α/(α+1)) = v^1.43` (docs/physics.md
    /// §14.3), between `(2.61/2.85)^1.43 = 0.882` and `(3.09/2.85)^1.43 = 1.122`.
    #[test]
    fn a_hammer_strikes_strings_ringing_from_another_key_harder_or_softer_by_their_phase() {
        let peak = |lower: &[u8], delay: f64| {
            let (mut instrument, c4) = c4_after(lower, delay, 64);
            let (mut left, mut right) = ([0.0f32; 1], [0.0f32; 1]);
            let mut peak = 0.0f64;
            for _ in 0..480 {
                instrument.process(&mut left, &mut right);
                peak = peak.max(instrument.voices[c4].contact().1.abs());
            }
            peak
        };
        let alone = peak(&[], 1.0);
        let ratios: Vec<f64> = (0..16).map(|k| peak(&[48], 1.0 + 2.5e-4 * f64::from(k)) / alone).collect();
        let (low, high) = ratios.iter().fold((f64::INFINITY, 0.0f64), |(l, h), &r| (l.min(r), h.max(r)));
        println!("peak force against C4 alone ({alone:.2} N): {low:.3} to {high:.3}");
        assert!(high - low >= 0.05, "{low} to {high}");
        let hammer = hammer_speed(0.7);
        let reach = |speed: f64| (speed / hammer).powf(5.0 / 3.5);
        assert!(low >= reach(hammer - 0.24) && high <= reach(hammer + 0.24), "{low} to {high}");
    }

    /// A key struck while its strings ring on another key's bridge takes the energy of that
    /// motion into its strike's reference (docs/physics.md §14.3): struck softly (velocity
    /// 1/127, 0.05) or as loud (0.7) while C3 rings its strings under the pedal, C4's strings and
    /// bridge never hold more than the reference over 1 s (measured at most 0.69 of it; 2.1
    /// without that motion's energy), and the guard never fires.
    #[test]
    fn a_key_struck_among_strings_ringing_elsewhere_stays_within_its_energy_bound() {
        for (c3, c4, delay) in [(1.0, 1.0 / 127.0, 0.1), (1.0, 1.0 / 127.0, 1.0), (0.7, 0.7, 1.0), (1.0, 0.05, 0.3)] {
            let mut instrument = Instrument::new(48_000.0, 8, Settings::default());
            instrument.handle(Event::Sustain { channel: 0, depth: 1.0 });
            instrument.handle(Event::NoteOn { channel: 0, key: 48, velocity: c3 });
            let (mut left, mut right) = ([0.0f32; 64], [0.0f32; 64]);
            for _ in 0..(delay * 750.0) as usize {
                instrument.process(&mut left, &mut right);
            }
            instrument.handle(Event::NoteOn { channel: 0, key: 60, velocity: c4 });
            let c4_voice = voice_of(&instrument, 60).unwrap();
            let mut most = 0.0f64;
            for _ in 0..750 {
                instrument.process(&mut left, &mut right);
                most = most.max(instrument.voices[c4_voice].energy_share());
            }
            println!("C3 at {c3}, C4 at {c4:.3} after {delay} s: at most {most:.3} of the reference");
            assert!(most <= 1.0, "C3 at {c3}, C4 at {c4} after {delay} s: {most}");
            assert_eq!(instrument.guard_trips(), 0);
        }
    }

    /// Played hard: keys struck, struck again and let go at random (half of them among C2, G2,
    /// C3, G3, C4, G4, C5 and E5, which ring one another's strings), at velocities from 1/127 to
    /// full, the sustain pedal pressed part or all of the way and lifted, the sostenuto and soft
    /// pedals pressed and lifted, voices stolen (4 to 32 voices for about 600 note-ons each), host
    /// buffers of 1 to 4,096 samples, and over half of each run every piano parameter (the half
    /// pedal's zone among them), the solver and the control block sent to either end of its range
    /// or anywhere between before one event in twenty. No voice's strings and bridge ever hold
    /// more than 1.1 times its latest strike's reference energy, the energy it had to give as the
    /// motion elsewhere stood at the strike, the guard never fires (at ten times it) and every
    /// sample is finite. The reference is exact while the copies of the key's strings on other
    /// voices' bridges keep their energy; those voices' own strings drive them, and can through
    /// a contact: in the 16-voice run a G4 struck again at velocity 0.42, among copies ringing,
    /// holds 1.029 of its reference at the end of a host call (1.041 sample by sample, 1.2 ms in;
    /// docs/physics.md §14.3); the other runs stay below 0.994 of it. A voice fading out for a
    /// stolen note is left out: its fade's damping weighs its energy anew, and the guard does not
    /// read it.
    #[test]
    fn every_voice_stays_within_a_tenth_over_its_strikes_energy_through_steals_pedalling_and_parameter_jumps() {
        use crate::contact::Method;
        use rand::{RngExt, SeedableRng};
        let extreme = |rng: &mut rand_pcg::Pcg64, lo: f64, hi: f64| match rng.random_range(0..3) {
            0 => lo,
            1 => hi,
            _ => lo * (hi / lo).powf(rng.random_range(0.0..1.0)),
        };
        let pick = |rng: &mut rand_pcg::Pcg64, values: &[f64]| values[rng.random_range(0..values.len())];
        for (seed, voices) in [4usize, 8, 16, 32].into_iter().enumerate() {
            let mut rng = rand_pcg::Pcg64::seed_from_u64(seed as u64);
            let mut instrument = Instrument::new(48_000.0, voices, Settings::default());
            let (mut left, mut right) = (vec![0.0f32; 4096], vec![0.0f32; 4096]);
            let (steps, mut most) = (1500, 0.0f64);
            for step in 0..steps {
                let key = if rng.random_range(0..2) == 0 {
                    [36u8, 43, 48, 55, 60, 67, 72, 76][rng.random_range(0..8)]
                } else {
                    rng.random_range(21..=108)
                };
                let jumping = (step < steps / 2) == (seed % 2 == 0);
                match rng.random_range(0..20) {
                    0..8 => {
                        let velocity =
                            if rng.random_range(0..3) == 0 { 1.0 / 127.0 } else { rng.random_range(0.01..=1.0) };
                        instrument.handle(Event::NoteOn { channel: 0, key, velocity });
                    }
                    8..12 => instrument.handle(Event::NoteOff { channel: 0, key }),
                    12 => {
                        // Up, partly down (the dampers hovering) or down.
                        let depth = match rng.random_range(0..4) {
                            0 => 0.0,
                            1 => rng.random_range(0.0..1.0),
                            _ => 1.0,
                        };
                        instrument.handle(Event::Sustain { channel: 0, depth });
                    }
                    13 => {
                        let down = rng.random_range(0..2) != 0;
                        instrument.handle(if rng.random_range(0..2) == 0 {
                            Event::SoftPedal { channel: 0, down }
                        } else {
                            Event::Sostenuto { channel: 0, down }
                        })
                    }
                    14 if jumping => {
                        let settings = Settings {
                            method: [Method::Qsa, Method::Exp, Method::Imp][rng.random_range(0..3)],
                            block: [1, 7, 64, MAX_BLOCK][rng.random_range(0..4)],
                            hardness: extreme(&mut rng, 0.1, 10.0),
                            hammer_mass: extreme(&mut rng, 0.25, 4.0),
                            strike_position: extreme(&mut rng, 0.25, 2.5),
                            damping: extreme(&mut rng, 0.1, 20.0),
                            brightness: pick(&mut rng, &[0.0, 1.0, 4.0]),
                            unison_detune: pick(&mut rng, &[0.0, 2.5, 20.0]),
                            stretch: pick(&mut rng, &[0.0, 1.0, 2.0]),
                            damper_rate: extreme(&mut rng, 1.0, 500.0),
                            damper_time: extreme(&mut rng, 0.001, 0.1),
                            half_pedal_from: pick(&mut rng, &[0.0, 0.2, 0.5, 1.0]),
                            half_pedal_to: pick(&mut rng, &[0.0, 0.5, 0.8, 1.0]),
                            ..Settings::default()
                        };
                        instrument.set_settings(&settings);
                    }
                    _ => {}
                }
                let n = [1, 16, 64, 100, 480, 4096][rng.random_range(0..6)];
                instrument.process(&mut left[..n], &mut right[..n]);
                assert!(left[..n].iter().chain(&right[..n]).all(|x| x.is_finite()), "seed {seed}, step {step}");
                for v in instrument.voices.iter().filter(|v| v.sounding && !v.fading()) {
                    let share = v.energy_share();
                    assert!(share <= 1.1, "seed {seed}, step {step}, key {}: {share}", v.strike.key);
                    most = most.max(share);
                }
            }
            println!("{voices} voices: at most {most:.4} of the reference, {} steals", instrument.steals());
            assert_eq!(instrument.guard_trips(), 0, "seed {seed}");
        }
    }

    /// `blocks` blocks of 64 samples of `instrument` playing `events`, each `(block, event)`
    /// handled before its block: both channels' samples, a block at a time, as bits.
    fn blocks_played(instrument: &mut Instrument, events: &[(usize, Event)], blocks: usize) -> Vec<u32> {
        let (mut left, mut right) = ([0.0; 64], [0.0; 64]);
        let mut out = Vec::with_capacity(blocks * 128);
        for block in 0..blocks {
            events.iter().filter(|(at, _)| *at == block).for_each(|&(_, e)| instrument.handle(e));
            instrument.process(&mut left, &mut right);
            out.extend(left.iter().chain(&right).map(|x| x.to_bits()));
        }
        out
    }

    /// The raw output is centred from a note's first sample: A0 and C8, the keys the default
    /// width pans furthest, sound the same on the left and on the right to the bit, with no
    /// glide from their places in the mix.
    #[test]
    fn a_raw_note_is_centred_from_its_first_sample() {
        for key in [21, 108] {
            let mut instrument = Instrument::new(48_000.0, 2, Settings::default());
            assert!(instrument.settings.stereo_width > 0.0);
            instrument.set_raw_output(true);
            instrument.handle(Event::NoteOn { channel: 0, key, velocity: 0.7 });
            let (mut left, mut right) = ([0.0; 64], [0.0; 64]);
            let mut peak: f32 = 0.0;
            for block in 0..16 {
                instrument.process(&mut left, &mut right);
                peak = left.iter().fold(peak, |m, x| m.max(x.abs()));
                assert_eq!(left, right, "key {key}, block {block}");
            }
            assert!(peak > 0.0, "key {key} sounds");
        }
    }

    /// Render `key` struck at `velocity` on channel 0 with the soft pedal down or up, the raw
    /// (centred) output for `seconds`, and how many strings its hammer met.
    fn una_corda(key: u8, velocity: f32, soft: bool, seconds: f64) -> (Vec<f64>, usize) {
        let mut instrument = Instrument::new(48_000.0, 4, Settings::default());
        instrument.set_raw_output(true);
        instrument.handle(Event::SoftPedal { channel: 0, down: soft });
        instrument.handle(Event::NoteOn { channel: 0, key, velocity });
        let struck = voice_of(&instrument, key).map(|i| instrument.voices[i].strings_struck()).unwrap();
        let n = (seconds * 48_000.0) as usize;
        let mut out = Vec::with_capacity(n + 64);
        let (mut left, mut right) = ([0.0; 64], [0.0; 64]);
        while out.len() < n {
            instrument.process(&mut left, &mut right);
            out.extend(left.iter().map(|&x| f64::from(x)));
        }
        (out, struck)
    }

    /// CC67 at 64 and above puts the soft pedal down on its channel (an MPE zone's master
    /// channel, 1 or 16, for every channel), and a key struck while it is down meets one string
    /// fewer: A0's single string, one of E2's two, two of C4's three; with the pedal up, all of
    /// them. A key keeps the strike it had: C4 struck before the pedal goes down sounds to the
    /// bit as with no pedal, and struck again under it meets two strings. A0, a single string,
    /// sounds to the bit as without the pedal.
    #[test]
    fn the_soft_pedal_strikes_one_string_fewer_on_keys_struck_while_it_is_down() {
        let pedal = |channel: u8, down: bool| event_from_midi(0xb0 | channel, 67, if down { 64 } else { 63 }).unwrap();
        assert_eq!(pedal(2, true), Event::SoftPedal { channel: 2, down: true });
        assert_eq!(pedal(2, false), Event::SoftPedal { channel: 2, down: false });
        let struck = |events: &[Event], channel: u8, key: u8| {
            let mut instrument = Instrument::new(48_000.0, 2, Settings::default());
            events.iter().for_each(|&e| instrument.handle(e));
            instrument.handle(Event::NoteOn { channel, key, velocity: 0.6 });
            voice_of(&instrument, key).map(|i| instrument.voices[i].strings_struck())
        };
        for (key, strings) in [(21, 1), (40, 2), (60, 3)] {
            assert_eq!(struck(&[], 0, key), Some(strings), "key {key}, pedal up");
            assert_eq!(struck(&[pedal(0, true)], 0, key), Some(strings.max(2) - 1), "key {key}");
            assert_eq!(struck(&[pedal(0, true), pedal(0, false)], 0, key), Some(strings), "key {key}");
        }
        assert_eq!(struck(&[pedal(3, true)], 3, 60), Some(2), "its own channel");
        assert_eq!(struck(&[pedal(3, true)], 4, 60), Some(3), "another channel");
        assert_eq!(struck(&[pedal(15, true)], 4, 60), Some(2), "the upper zone's master channel");
        assert_eq!(struck(&[pedal(0, true), Event::AllNotesOff], 0, 60), Some(3), "all notes off lifts it");

        let render = |events: &[(usize, Event)]| {
            let mut instrument = Instrument::new(48_000.0, 2, Settings::default());
            let out = blocks_played(&mut instrument, events, 400);
            (out, voice_of(&instrument, 60).map(|i| instrument.voices[i].strings_struck()))
        };
        let c4 = Event::NoteOn { channel: 0, key: 60, velocity: 0.6 };
        let (alone, _) = render(&[(0, c4)]);
        let (pressed_after, met) = render(&[(0, c4), (100, pedal(0, true))]);
        assert!(alone == pressed_after && met == Some(3), "a sounding key keeps its strike");
        let (restruck, met) = render(&[(0, c4), (100, pedal(0, true)), (200, c4)]);
        assert!(restruck[..400 * 128 / 2] == alone[..400 * 128 / 2] && met == Some(2), "struck again under it");
        let a0 = Event::NoteOn { channel: 0, key: 21, velocity: 0.6 };
        assert!(render(&[(0, a0)]).0 == render(&[(0, pedal(0, true)), (0, a0)]).0, "a single string");
    }

    /// The una corda's sound. Put the same energy into `S_h` of a unison's `S` strings, each
    /// moving alike: their bridge force goes as `√(S_h·E)`, so the prompt sound (the first
    /// 0.1 s) is `10·log10(S_h/S)` dB below the whole unison's, −1.76 dB on a trichord and
    /// −3.01 dB on a bichord. The hammer, as heavy and with a felt `S_h/S` as stiff, hands over
    /// not quite the same energy: within 1 dB of that, measured at E2, C4 and C5 at velocities
    /// 0.3 and 0.7. Struck strings and missed ones start out of step, so more of the unison's
    /// motion lies in the patterns that barely move the bridge, the slow aftersound (Weinreich
    /// 1977): 2–3 s after the strike the level stands higher against the prompt sound than with
    /// the whole unison struck, by more than 0.3 dB at each (0.55 to 5.5 dB measured).
    #[test]
    fn the_una_corda_is_softer_by_the_struck_strings_share_and_leaves_more_aftersound() {
        let rms = |x: &[f64], from: f64, to: f64| {
            let x = &x[(from * 48_000.0) as usize..(to * 48_000.0) as usize];
            (x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64).sqrt()
        };
        let db = |ratio: f64| 20.0 * ratio.log10();
        for key in [40, 60, 72] {
            for velocity in [0.3, 0.7] {
                let (whole, strings) = una_corda(key, velocity, false, 3.0);
                let (shifted, met) = una_corda(key, velocity, true, 3.0);
                let expected = 10.0 * (met as f64 / strings as f64).log10();
                let prompt = db(rms(&shifted, 0.0, 0.1) / rms(&whole, 0.0, 0.1));
                let after = |x: &[f64]| db(rms(x, 2.0, 3.0) / rms(x, 0.0, 0.1));
                let (gain, more) = (prompt - expected, after(&shifted) - after(&whole));
                println!(
                    "key {key} at {velocity}: {met} of {strings} strings, prompt sound {prompt:.2} dB \
                     (expected {expected:.2}), aftersound {more:+.2} dB against the prompt sound"
                );
                assert!(gain.abs() < 1.0, "key {key} at {velocity}: {prompt} dB against {expected}");
                assert!(more > 0.3, "key {key} at {velocity}: {more} dB");
            }
        }
    }

    /// The sostenuto pedal (CC66 at 64 and above) holds up the dampers of the keys held down as
    /// it goes down, and only theirs, until it comes up. Every render below is compared to the
    /// bit with one that holds the same dampers up by holding keys down instead, over 2 s:
    /// - C4 held, the pedal down, C4 let go, E4 struck staccato: as C4 held throughout with E4
    ///   struck staccato (C4 rings on, E4's damper falls);
    /// - the pedal then coming up at 1 s: as C4 let go at 1 s;
    /// - the pedal down before any key, C4 struck and let go: as no pedal at all;
    /// - the pedal sent again (a controller's values 70, then 90) while E4 is held: E4 is not
    ///   caught by the second;
    /// - on channel 4, it catches the keys held on channel 4 alone; on channel 1 (an MPE zone's
    ///   master channel, 0 here) those held on every channel.
    #[test]
    fn the_sostenuto_holds_up_the_dampers_of_the_keys_down_as_it_goes_down_and_only_those() {
        let sostenuto = |channel: u8, value: u8| event_from_midi(0xb0 | channel, 66, value).unwrap();
        assert_eq!(sostenuto(3, 64), Event::Sostenuto { channel: 3, down: true });
        assert_eq!(sostenuto(3, 63), Event::Sostenuto { channel: 3, down: false });
        let on = |channel: u8, key: u8| Event::NoteOn { channel, key, velocity: 0.6 };
        let off = |channel: u8, key: u8| Event::NoteOff { channel, key };
        let render = |events: &[(usize, Event)]| {
            blocks_played(&mut Instrument::new(48_000.0, 4, Settings::default()), events, 1500)
        };
        let same = |name: &str, a: &[(usize, Event)], b: &[(usize, Event)]| {
            let (a, b) = (render(a), render(b));
            assert!(a.iter().any(|&x| x != 0), "{name}: sounds");
            assert!(a == b, "{name}");
        };
        let c4_rings = [(0, on(0, 60)), (30, on(0, 64)), (60, off(0, 64))];
        let caught = [(0, on(0, 60)), (10, sostenuto(0, 127)), (20, off(0, 60)), (30, on(0, 64)), (60, off(0, 64))];
        same("C4 caught, E4 not", &caught, &c4_rings);
        let lifted = [caught.as_slice(), &[(750, sostenuto(0, 0))]].concat();
        let let_go = [c4_rings.as_slice(), &[(750, off(0, 60))]].concat();
        same("the pedal coming up", &lifted, &let_go);
        same(
            "nothing caught",
            &[(0, sostenuto(0, 127)), (10, on(0, 60)), (40, off(0, 60))],
            &[(10, on(0, 60)), (40, off(0, 60))],
        );
        same(
            "sent again",
            &[
                (0, on(0, 60)),
                (10, sostenuto(0, 70)),
                (20, on(0, 64)),
                (30, sostenuto(0, 90)),
                (40, off(0, 60)),
                (60, off(0, 64)),
            ],
            &[(0, on(0, 60)), (20, on(0, 64)), (60, off(0, 64))],
        );
        same(
            "its own channel",
            &[(0, on(4, 60)), (0, on(5, 64)), (10, sostenuto(4, 127)), (20, off(4, 60)), (20, off(5, 64))],
            &[(0, on(4, 60)), (0, on(5, 64)), (20, off(5, 64))],
        );
        same(
            "the master channel",
            &[(0, on(4, 60)), (0, on(5, 64)), (10, sostenuto(0, 127)), (20, off(4, 60)), (20, off(5, 64))],
            &[(0, on(4, 60)), (0, on(5, 64))],
        );
    }

    /// The swing of key `key`'s strings at its damper's pad (m) at 0.1, 0.2, … 4 s, struck at
    /// velocity 0.8 and let go at 0.2 s with the sustain pedal pressed `depth` of its way.
    fn swings_under_the_pedal(key: u8, depth: f32) -> Vec<f64> {
        swings_under_the_pedal_with(key, depth, Settings::default())
    }

    /// [`swings_under_the_pedal`] under `settings`.
    fn swings_under_the_pedal_with(key: u8, depth: f32, settings: Settings) -> Vec<f64> {
        let mut instrument = Instrument::new(48_000.0, 2, settings);
        instrument.handle(Event::Sustain { channel: 0, depth });
        instrument.handle(Event::NoteOn { channel: 0, key, velocity: 0.8 });
        let (mut left, mut right) = (vec![0.0f32; 4_800], vec![0.0f32; 4_800]);
        (0..40)
            .map(|tenth| {
                if tenth == 2 {
                    instrument.handle(Event::NoteOff { channel: 0, key });
                }
                instrument.process(&mut left, &mut right);
                instrument.voices.iter().find(|v| v.strike.key == key).map_or(0.0, PianoVoice::pad_swing)
            })
            .collect()
    }

    /// A sustain pedal pressed part of the way holds the dampers above the strings (Lehtonen,
    /// Askenfelt and Välimäki, JASA 126, EL49, 2009): after the key is let go the damper takes the
    /// swing beyond its lift quickly, then the strings ring on freely at a lower rate. C2 and C4
    /// at 0.4, 0.5 and 0.6 of the pedal's way (lifts 20, 63 and 200 µm), let go at 0.2 s:
    /// - over the first 0.1 s after the release the swing decays more than 5 times as fast as
    ///   with the pedal down;
    /// - 0.2 s after the release it is within 0.8 to 1.25 times the lift, where with the pedal
    ///   down it is still over twice the lift: the damper has taken it down to the lift (from
    ///   above: 1.25 allows for the slowing approach, as the felt touches less of each period),
    ///   and not much further (0.8: the strings' own decay over 0.2 s, under 1 1/s);
    /// - from 1 s to 3 s after the release its decay rate is within 20 % of the pedal-down one:
    ///   the strings ring freely (the damper has changed what their modes hold).
    #[test]
    fn a_half_pressed_sustain_pedal_damps_the_swing_down_to_the_dampers_lift_and_lets_it_ring() {
        let rate = |x: &[f64], from: usize, to: usize| (x[from] / x[to]).ln() / ((to - from) as f64 / 10.0);
        for key in [36u8, 60] {
            let down = swings_under_the_pedal(key, 1.0);
            for depth in [0.4f32, 0.5, 0.6] {
                let lift = damper_lift(f64::from(depth), &Settings::default());
                let half = swings_under_the_pedal(key, depth);
                // `half[k]` is the swing at (k + 1)/10 s; the key is let go at 0.2 s, after `half[1]`.
                let (early, down_early) = (rate(&half, 1, 2), rate(&down, 1, 2));
                let (late, free) = (rate(&half, 11, 31), rate(&down, 11, 31));
                println!(
                    "key {key}, depth {depth}: decay over 0.2–0.3 s {early:.2} 1/s (pedal down {down_early:.2}); \
                     at 0.4 s {:.3} of the lift (pedal down {:.1}); over 1.2–3.2 s {late:.3} 1/s (pedal down \
                     {free:.3})",
                    half[3] / lift,
                    down[3] / lift
                );
                assert!(early > 5.0 * down_early, "key {key}, depth {depth}: the damper takes the swing fast");
                assert!(down[3] > 2.0 * lift, "the swing stays well above the lift with the pedal down");
                assert!((0.8..1.25).contains(&(half[3] / lift)), "key {key}, depth {depth}: damped to the lift");
                assert!((late / free - 1.0).abs() < 0.2, "key {key}, depth {depth}: then free");
            }
        }
    }

    /// The half pedal's zone is where the player sets it, its ends in either order: C2 let go at
    /// 0.2 s under the pedal at depths around the ends of the zones 0.3 to 0.9, 0.9 to 0.3 and
    /// the switches at 0.5, at the full travel and at none is bit for bit as with the pedal up
    /// below the zone and down above it (a switch from its point on), and within the zone is
    /// neither (the dampers hover: its swing at 4 s lies between).
    #[test]
    fn the_half_pedal_zone_lies_where_the_player_sets_it() {
        let key = 36;
        let (up, down) = (swings_under_the_pedal(key, 0.0), swings_under_the_pedal(key, 1.0));
        let zones = [(0.3, 0.9), (0.9, 0.3), (0.5, 0.5), (1.0, 1.0), (0.0, 0.0)];
        for (from, to) in zones {
            let settings = Settings { half_pedal_from: from, half_pedal_to: to, ..Settings::default() };
            let (rest, clear) = (from.min(to) as f32, from.max(to) as f32);
            let swings = |depth: f32| swings_under_the_pedal_with(key, depth, settings);
            // A switch clears from its point on: at the full travel for one there.
            let above = if clear > rest { clear + 0.01 } else { clear };
            assert_eq!(swings((rest - 0.01).max(0.0)), up, "zone {from}–{to}: resting below it");
            assert_eq!(swings(above.clamp(0.01, 1.0)), down, "zone {from}–{to}: clear above it");
            if clear > rest {
                let within = swings(0.5 * (rest + clear));
                println!("zone {from}–{to}: at 4 s {:.3e} m (up {:.3e}, down {:.3e})", within[39], up[39], down[39]);
                assert!(up[39] < within[39] && within[39] < down[39], "zone {from}–{to}: hovering within it");
            }
        }
    }

    /// The sustain pedal's ends: up to [`Settings::half_pedal_from`] (0.2) of its way the
    /// dampers rest on the strings as with the pedal up, and from [`Settings::half_pedal_to`]
    /// (0.8) they are clear of them as with it down, bit for bit: C2 and C4 let go at 0.2 s, over
    /// 4 s.
    #[test]
    fn the_sustain_pedal_is_up_to_its_rest_point_and_down_from_its_clear_point_to_the_bit() {
        for key in [36u8, 60] {
            let up = swings_under_the_pedal(key, 0.0);
            let down = swings_under_the_pedal(key, 1.0);
            assert!(down[39] > 1e3 * up[39], "up and down differ");
            // (0.2 in `f32` is a little above 0.2 in `f64`; a MIDI pedal sends 25/127 or 26/127.)
            for depth in [0.1f32, 25.0 / 127.0] {
                assert_eq!(swings_under_the_pedal(key, depth), up, "key {key}, depth {depth}");
            }
            for depth in [102.0 / 127.0, 0.9] {
                assert_eq!(swings_under_the_pedal(key, depth), down, "key {key}, depth {depth}");
            }
        }
    }
}
