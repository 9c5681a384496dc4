//! How the piano compares with real grands: `cargo xtask realism` writes `docs/report/realism.md`
//! with its pictures and sound examples in `docs/report/realism/`.
//!
//! - **Two-stage decay**: the partial envelopes of C4 struck at velocity 0.6 (2.2 m/s) and held,
//!   with the default unison spread and with the unison tuned exactly alike.
//! - **Contact duration** against key at mezzo-forte and forte, beside the string's period and
//!   the published measurements of docs/physics.md §8.4.
//! - **Inharmonicity** `B` against key beside the grands measured by Lehtonen et al. and Rigaud
//!   et al., and Young's plain strings of six pianos.
//! - **String scale**: the rule's speaking lengths beside a measured grand's, and its strings as
//!   steel wires.
//! - **Decay rates** of the first two partials against key, prompt sound and aftersound, and the
//!   fundamental's T60 beside a measured grand's at C2–C4 with the pedal up and down.
//! - **Sympathetic resonance**: what the pedal adds to C3 at each key's pitch.
//! - **A scale at three dynamics**: C4 to C5 at velocities 40, 80 and 120, mono 16-bit WAV.
//! - **The slide guitar on its two bodies**: each note's loudness on the electric and on the
//!   acoustic guitar, the acoustic body's transmittance, and a short phrase on each, mono 16-bit WAV;
//!   the acoustic guitar's notes in stereo at the default width (their channels' correlation and
//!   loudness against centred).
//!
//! The measuring functions here are also what the tests use (`tests/tests/piano_rule.rs`,
//! `tests/tests/piano_realism.rs`).

use std::io::Write;
use std::path::{Path, PathBuf};

use clap::Args;
use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use qsa_dsp::instrument::PianoVoice;
use qsa_dsp::instrument::{Event, Instrument, Mode, Settings, SlideBody, hammer_speed};
use qsa_dsp::preset::piano_note;
use qsa_dsp::string::StringParams;

/// Key `key`'s string as the instrument tunes it with the default settings, octave stretch and
/// all (the first string of its unison).
pub fn tuned(key: u8) -> StringParams {
    PianoVoice::string_for(key, &Settings::default())
}

/// Key `key`'s fundamental as the instrument tunes it with the default settings (Hz).
pub fn pitch(key: u8) -> f64 {
    tuned(key).partial(1)
}

/// Sample rate of every measurement (Hz).
pub const FS: f64 = 48_000.0;

/// Window of the partial levels (s).
pub const LEVEL_WINDOW: f64 = 0.05;

/// The slowest a partial can decay (dB/s): the strings' own loss alone, `b1` = 0.5 1/s on every
/// key (docs/physics.md §8.2), 20·0.5/ln 10.
pub const OWN_LOSS_RATE: f64 = 10.0 / std::f64::consts::LN_10;

/// The prompt sound's and the aftersound's spans (s) for decay rates.
pub const PROMPT: (f64, f64) = (0.05, 0.6);
pub const AFTERSOUND: (f64, f64) = (2.0, 4.5);

/// Hammer speeds of piano, mezzo-forte and forte (m/s): Askenfelt & Jansson give about 5 m/s for
/// forte; Chaigne & Askenfelt simulate mezzo-forte at 2.5 m/s.
pub const PIANO: f64 = 1.0;
pub const MEZZO_FORTE: f64 = 2.5;
pub const FORTE: f64 = 5.0;

/// The MIDI velocity (0–1) at which the instrument's hammer leaves at `speed` (m/s), or `None`
/// outside the velocity curve.
pub fn velocity_for(speed: f64) -> Option<f32> {
    let v = (speed / hammer_speed(0.0)).ln() / (hammer_speed(1.0) / hammer_speed(0.0)).ln();
    ((0.0..=1.0).contains(&v) && (hammer_speed(v) - speed).abs() < 1e-9 * speed).then_some(v as f32)
}

/// Duration of the hammer's first contact with its strings (s) when `key` is struck at `speed`
/// (m/s): the first continuous stretch of samples in which the instrument's hammer touches
/// (`Instrument::in_contact`), one sample per call at [`FS`], so to ±1 sample. `None` if no
/// contact ends within 20 ms or the speed is outside the velocity curve.
pub fn contact_duration(key: u8, speed: f64) -> Option<f64> {
    let mut piano = Instrument::new(FS, 1, Settings { limiter: false, ..Settings::default() });
    piano.handle(Event::NoteOn { channel: 0, key, velocity: velocity_for(speed)? });
    let (mut l, mut r) = ([0.0f32; 1], [0.0f32; 1]);
    let mut first = None;
    for n in 0..(0.02 * FS) as usize {
        piano.process(&mut l, &mut r);
        match (piano.in_contact() > 0, first) {
            (true, None) => first = Some(n),
            (false, Some(start)) => return Some((n - start) as f64 / FS),
            _ => {}
        }
    }
    None
}

/// Key `key` struck at `velocity` and held (its damper off, the pedal up: no sympathetic
/// partners), `seconds` long, with a unison spread of `detune` cents: the dry bridge force (full
/// scale as the output).
pub fn held_note(key: u8, velocity: f32, detune: f64, seconds: f64) -> Vec<f64> {
    held_note_shifted(key, velocity, detune, false, seconds)
}

/// [`held_note`], struck with the soft pedal down (`soft`: the una corda, one string fewer).
pub fn held_note_shifted(key: u8, velocity: f32, detune: f64, soft: bool, seconds: f64) -> Vec<f64> {
    let settings = Settings { unison_detune: detune, limiter: false, ..Settings::default() };
    let mut piano = Instrument::new(FS, 4, settings);
    // The strings' own decay: the dry bridge force, without the soundboard's radiation (whose
    // modes add their own ringing to a partial's envelope).
    piano.set_raw_output(true);
    piano.handle(Event::SoftPedal { channel: 0, down: soft });
    piano.handle(Event::NoteOn { channel: 0, key, velocity });
    let n = (seconds * FS) as usize;
    let (mut left, mut right) = (vec![0.0f32; n], vec![0.0f32; n]);
    for (l, r) in left.chunks_mut(256).zip(right.chunks_mut(256)) {
        piano.process(l, r);
    }
    left.into_iter().map(f64::from).collect()
}

/// The level (dB) of the component at `frequency` (Hz) of `signal` (sampled at [`FS`]), by
/// heterodyning, every [`LEVEL_WINDOW`], among partials `spacing` (Hz) apart: each level is taken
/// over a Hann window centred on its [`LEVEL_WINDOW`] and at least four partials' periods of
/// beating long (`4/spacing`), so that the neighbouring partials, four of its bins away, leak in
/// more than 60 dB down (a 50 ms rectangle, 20 Hz wide, let C1's neighbours in at −15 dB). The
/// signal is silent before its start; the levels run while a whole window fits before its end.
pub fn partial_levels(signal: &[f64], frequency: f64, spacing: f64) -> Vec<f64> {
    let hop = (LEVEL_WINDOW * FS) as usize;
    let w = hop.max((4.0 / spacing * FS).ceil() as usize);
    let hann = |i: usize| 0.5 - 0.5 * (std::f64::consts::TAU * (i as f64 + 0.5) / w as f64).cos();
    let gain: f64 = (0..w).map(hann).sum();
    (0..)
        .map(|k| (k * hop + hop / 2) as isize - (w / 2) as isize)
        .take_while(|&start| start + w as isize <= signal.len() as isize)
        .map(|start| {
            let (mut re, mut im) = (0.0, 0.0);
            for i in 0..w {
                let n = start + i as isize;
                let Some(&x) = usize::try_from(n).ok().and_then(|n| signal.get(n)) else { continue };
                let phase = std::f64::consts::TAU * frequency * n as f64 / FS;
                let h = hann(i) * x;
                re += h * phase.cos();
                im += h * phase.sin();
            }
            10.0 * ((re * re + im * im) / (gain * gain)).log10()
        })
        .collect()
}

/// Least-squares slope (dB/s) of `levels` (one per [`LEVEL_WINDOW`]) over `span` (s).
pub fn decay_rate(levels: &[f64], span: (f64, f64)) -> f64 {
    let points: Vec<(f64, f64)> = levels
        .iter()
        .enumerate()
        .map(|(k, &l)| ((k as f64 + 0.5) * LEVEL_WINDOW, l))
        .filter(|&(t, _)| t >= span.0 && t <= span.1)
        .collect();
    let n = points.len() as f64;
    let (mt, ml) = (points.iter().map(|p| p.0).sum::<f64>() / n, points.iter().map(|p| p.1).sum::<f64>() / n);
    let cov: f64 = points.iter().map(|p| (p.0 - mt) * (p.1 - ml)).sum();
    let var: f64 = points.iter().map(|p| (p.0 - mt).powi(2)).sum();
    cov / var
}

/// Decay rates (dB/s) of partial `partial` of `key` struck at velocity 0.6 with a unison spread of
/// `detune` cents: `(prompt sound, aftersound)`.
pub fn two_stages(key: u8, partial: usize, detune: f64) -> (f64, f64) {
    let out = held_note(key, 0.6, detune, 5.0);
    let levels = partial_levels(&out, tuned(key).partial(partial), pitch(key));
    (decay_rate(&levels, PROMPT), decay_rate(&levels, AFTERSOUND))
}

/// Published inharmonicity coefficients of grands: `(key, low, high, source)`.
pub const MEASURED_B: [(u8, f64, f64, &str); 6] = [
    (36, 3.8e-5, 3.8e-5, "Lehtonen et al. 2007"),
    (60, 3.3e-4, 3.3e-4, "Lehtonen et al. 2007"),
    (84, 2.3e-3, 2.3e-3, "Lehtonen et al. 2007"),
    (60, 3.1e-4, 3.3e-4, "Rigaud et al. 2013"),
    (84, 2.8e-3, 3.2e-3, "Rigaud et al. 2013"),
    (108, 2.6e-2, 3.1e-2, "Rigaud et al. 2013"),
];

/// Speaking lengths (mm) of a grand's plain strings, B2 (MIDI key 47) to C8 (108): a Steinway
/// model M (1.70 m) from 1936, measured by a piano technician (P. Stewart, RPT, on the Piano
/// Technicians Guild's Pianotech list, thread "String lengths?", 16 October 2019).
pub const MEASURED_LENGTHS: (u8, [u16; 62]) = (
    47,
    [
        1009, 1001, 990, 979, 965, 948, 922, 900, 847, 798, 756, 715, 678, 640, 607, 572, 542, 511, 482, 456, 432, 412,
        392, 374, 355, 340, 327, 312, 290, 274, 259, 245, 232, 219, 208, 196, 186, 176, 164, 156, 149, 142, 135, 129,
        123, 114, 109, 102, 95, 90, 85, 80, 75, 71, 68, 64, 61, 58, 56, 54, 52, 50,
    ],
);

/// The Steinway model M's speaking length at `key` (m), where [`MEASURED_LENGTHS`] has it.
pub fn measured_length(key: u8) -> Option<f64> {
    let (first, lengths) = MEASURED_LENGTHS;
    lengths.get(usize::from(key.checked_sub(first)?)).map(|&mm| f64::from(mm) * 1e-3)
}

/// A concert grand's speaking lengths at its lowest and highest modelled keys (m): Chabassier,
/// Chaigne and Joly's strings from a Steinway D's scale (JASA 134(1), 2013), D♯1 and F♯7.
pub const CONCERT_GRAND_LENGTHS: [(u8, f64); 2] = [(27, 1.965), (102, 0.069)];

/// Young's inharmonicity of plain steel strings (JASA 24(3), 1952, six pianos of several makes
/// and sizes), as `B`: "about 1.2 cents" for the second mode of C4, doubling every eight semitones
/// above. His cents are a mode's departure from `n` times the flexible string's fundamental,
/// `1200·log2 √(1 + Bn²) ≈ (600/ln 2)·Bn²`, so C4's `B` is `1.2 ln 2/(600·4)`.
pub fn young_inharmonicity(key: u8) -> f64 {
    1.2 * std::f64::consts::LN_2 / (600.0 * 4.0) * 2f64.powf((f64::from(key) - 60.0) / 8.0)
}

/// The measured grands' `B` from C4 up ([`MEASURED_B`], both values of each row) over Young's
/// line at their keys.
pub fn measured_over_young() -> impl Iterator<Item = f64> {
    MEASURED_B.iter().filter(|m| m.0 >= 60).flat_map(|m| [m.1, m.2].map(|b| b / young_inharmonicity(m.0)))
}

/// Steel's density (kg/m³) and its Young's modulus over density (m²/s²; Young 1952 took
/// 25.5·10¹⁰ cm²/s²).
const STEEL: (f64, f64) = (7850.0, 2.55e7);

/// The diameters (m) of the solid steel wires that have `key`'s string's mass per length and its
/// bending stiffness per mass: `ρA = ρπd²/4` and `EI/ρA = (E/ρ)d²/16`. For a plain string the two
/// agree; a wound string is heavier than its core's stiffness says.
pub fn steel_diameters(key: u8) -> (f64, f64) {
    let string = piano_note(key).string;
    let (density, specific_modulus) = STEEL;
    let by_mass = (4.0 * string.linear_density / (std::f64::consts::PI * density)).sqrt();
    let by_stiffness = 4.0 * (string.bending_stiffness / (string.linear_density * specific_modulus)).sqrt();
    (by_mass, by_stiffness)
}

/// Published decay times of a grand's fundamental: `(key, T60 with the pedal up, T60 with the
/// pedal down)` (s). Lehtonen, Penttinen, Rauhala & Välimäki, JASA 122(3), 2007, Table III (one
/// grand; the table's D5 and C6 rows were not read).
pub const MEASURED_T60: [(u8, f64, f64); 3] = [(36, 9.3, 14.8), (48, 10.0, 14.3), (60, 10.3, 17.0)];

/// Decay times listeners do not tell from a reference, as fractions of it: 75 % to 140 %
/// (Tolonen & Järveläinen, "Perceptual study of decay parameters in plucked string synthesis",
/// AES 109th Convention, 2000, preprint 5205: a time constant 25 % shorter or 40 % longer was not
/// heard; the tolerance Lehtonen et al. judge the pedal's effect by).
pub const T60_TOLERANCE: (f64, f64) = (0.75, 1.40);

/// The span over which a fundamental's whole decay is fitted (s).
pub const WHOLE: (f64, f64) = (0.05, 6.0);

/// T60 of `key`'s fundamental (s): struck at velocity 0.7 and held, the pedal down from the strike
/// or never ([`held_with_pedal`]), 60 dB over the least-squares decay rate of its level over
/// [`WHOLE`] (one rate for both stages, as a T60 read off a recorded tone).
pub fn fundamental_t60(key: u8, pedal: bool) -> f64 {
    let out = held_with_pedal(key, pedal.then_some(0.0), WHOLE.1 + 0.5);
    let levels = partial_levels(&out, tuned(key).partial(1), pitch(key));
    -60.0 / decay_rate(&levels, WHOLE)
}

/// Published contact durations: `(key, speed (m/s), low (ms), high (ms), source)`.
pub const MEASURED_CONTACT: [(u8, f64, f64, f64, &str); 3] = [
    (24, MEZZO_FORTE, 4.0, 5.0, "Askenfelt & Jansson 1990: 4–5 ms at C1"),
    (108, MEZZO_FORTE, 0.0, 1.0, "Askenfelt & Jansson 1990: under 1 ms in the top treble"),
    (96, MEZZO_FORTE, 0.602, 0.602, "Chaigne & Askenfelt 1994: 1.26 periods at C7, 2.5 m/s"),
];

/// Arguments of `cargo xtask realism`.
#[derive(Debug, Args)]
pub struct RealismArgs {
    /// Repository root (docs/report/ is written under it).
    #[arg(long, default_value = ".")]
    pub root: PathBuf,
}

const BLUE: RGBColor = RGBColor(31, 119, 180);
const GREEN: RGBColor = RGBColor(44, 160, 44);
const RED: RGBColor = RGBColor(214, 39, 40);
const PURPLE: RGBColor = RGBColor(148, 103, 189);

/// Key `key` struck at velocity 0.7 and held for `seconds`, the sustain pedal going down `pedal`
/// seconds after the strike (at 0, just before it) or never (`None`): the dry output, centred
/// (what `tests/tests/sympathetic.rs` compares).
pub fn held_with_pedal(key: u8, pedal: Option<f64>, seconds: f64) -> Vec<f64> {
    let strike = (0.0, Event::NoteOn { channel: 0, key, velocity: 0.7 });
    let events = match pedal.map(|t| t.max(0.0)) {
        Some(t) if (t * FS) as usize == 0 => vec![(0.0, Event::Sustain { channel: 0, depth: 1.0 }), strike],
        Some(t) => vec![strike, (t, Event::Sustain { channel: 0, depth: 1.0 })],
        None => vec![strike],
    };
    performed_in(128, &events, seconds)
}

/// Key `key` struck at velocity 0.7 with the pedal down from the strike (`pedal`) or never, let
/// go after `release` s, the pedal (if down) lifted after `lift` s: `seconds` of the dry output,
/// centred (as [`held_with_pedal`]).
pub fn played(key: u8, pedal: bool, release: f64, lift: f64, seconds: f64) -> Vec<f64> {
    let mut events =
        vec![(0.0, Event::NoteOn { channel: 0, key, velocity: 0.7 }), (release, Event::NoteOff { channel: 0, key })];
    if pedal {
        events.insert(0, (0.0, Event::Sustain { channel: 0, depth: 1.0 }));
        events.push((lift, Event::Sustain { channel: 0, depth: 0.0 }));
    }
    performed(&events, seconds)
}

/// `seconds` of the piano's dry output, centred, playing `events`, each at its time (s), in
/// 64-sample blocks: an event takes effect at the start of the block it falls in, in the order
/// given.
pub fn performed(events: &[(f64, Event)], seconds: f64) -> Vec<f64> {
    performed_in(64, events, seconds)
}

/// What `events` add to the sound of `background` (played alone and with them, [`performed`]):
/// the other voices' sound cancels, the same in both.
pub fn added_to(background: &[(f64, Event)], events: &[(f64, Event)], seconds: f64) -> Vec<f64> {
    let (both, alone) = (performed(&[background, events].concat(), seconds), performed(background, seconds));
    both.iter().zip(&alone).map(|(b, a)| b - a).collect()
}

/// [`performed`] in blocks of `block` samples.
fn performed_in(block: usize, events: &[(f64, Event)], seconds: f64) -> Vec<f64> {
    perform(&mut dry_piano(8), block, events, seconds)
}

/// A piano of `voices` voices with its dry output, centred, without the limiter: what the
/// realism measurements play.
pub fn dry_piano(voices: usize) -> Instrument {
    let mut piano = Instrument::new(FS, voices, Settings { limiter: false, stereo_width: 0.0, ..Settings::default() });
    piano.set_raw_output(true);
    piano
}

/// `seconds` of `piano`'s left channel playing `events` in blocks of `block` samples, each event
/// at the start of the block its time (s) falls in, in the order given.
pub fn perform(piano: &mut Instrument, block: usize, events: &[(f64, Event)], seconds: f64) -> Vec<f64> {
    let n = (seconds * FS) as usize;
    let (mut left, mut right) = (vec![0.0f32; n], vec![0.0f32; n]);
    for (k, (l, r)) in left.chunks_mut(block).zip(right.chunks_mut(block)).enumerate() {
        for (_, event) in events.iter().filter(|(at, _)| (at * FS) as usize / block == k) {
            piano.handle(*event);
        }
        piano.process(l, r);
    }
    left.into_iter().map(f64::from).collect()
}

/// The keys held down in [`held_ring`]: C4 and G4, whose strings C3's 2nd and 3rd partials meet,
/// and C♯4, whose strings no partial of C3 meets.
pub const HELD_KEYS: [u8; 3] = [60, 67, 61];

/// `(held key, amplitude at its pitch, amplitude a semitone above)` on the dry output, as
/// [`held_ring`] gives.
pub type HeldRing = (u8, f64, f64);

/// C3 struck with the pedal up and let go after 0.2 s, with each of [`HELD_KEYS`] held down,
/// pressed at velocity 1/127 (as softly as MIDI can) `press` s after C3 (0: just before it): what
/// C3 adds to the held key's own sound 0.5–1.5 s after its strike, its own strings silenced by
/// their damper (docs/physics.md §14).
pub fn held_ring(press: f64) -> [HeldRing; 3] {
    let c3 =
        [(0.0, Event::NoteOn { channel: 0, key: 48, velocity: 0.7 }), (0.2, Event::NoteOff { channel: 0, key: 48 })];
    let from = (0.5 * FS) as usize;
    HELD_KEYS.map(|key| {
        let held = [(press.max(0.0), Event::NoteOn { channel: 0, key, velocity: 1.0 / 127.0 })];
        let added = added_to(&held, &c3, 1.5);
        (key, level_near(&added, from, pitch(key)), level_near(&added, from, pitch(key + 1)))
    })
}

/// The strings without dampers that C5's 3rd and 4th partials meet: G6 and C7.
pub const UNDAMPED_PARTNERS: [u8; 2] = [91, 96];

/// C5 struck with the pedal up and let go after 0.2 s, its own strings silenced by their damper:
/// how much louder it still sounds 0.5–1.5 s later at the pitch of each of
/// [`UNDAMPED_PARTNERS`] than at its upper neighbour's (dB), what the strings without dampers
/// add (docs/physics.md §14).
pub fn undamped_ring() -> [(u8, f64); 2] {
    let out = played(72, false, 0.2, f64::INFINITY, 1.5);
    let from = (0.5 * FS) as usize;
    UNDAMPED_PARTNERS.map(|key| {
        let (on, beside) = (level_near(&out, from, pitch(key)), level_near(&out, from, pitch(key + 1)));
        (key, 20.0 * (on / beside).log10())
    })
}

pub fn amplitude_at(x: &[f64], from: usize, frequency: f64) -> f64 {
    let w = std::f64::consts::TAU * frequency / FS;
    let (s, c) = x[from..].iter().enumerate().fold((0.0, 0.0), |(s, c), (n, &v)| {
        let t = w * (n + from) as f64;
        (s + v * t.sin(), c + v * t.cos())
    });
    2.0 * s.hypot(c) / (x.len() - from).max(1) as f64
}

/// The largest amplitude of `x` within ±0.3 % of `frequency` (Hz), over `from..` (a partial's
/// level, wherever inharmonicity and tuning put it).
pub fn level_near(x: &[f64], from: usize, frequency: f64) -> f64 {
    (0..=60).map(|k| amplitude_at(x, from, frequency * (0.997 + 1e-4 * k as f64))).fold(0.0, f64::max)
}

/// Write the pictures, the sound examples and `docs/report/realism.md`.
pub fn run(args: &RealismArgs, out: &mut dyn Write) -> Result<(), String> {
    use crate::examples::draw_atomically;
    let dir = args.root.join("docs/report/realism");
    std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let envelopes = draw_atomically(&dir.join("envelopes.png"), envelopes)?;
    let shifted = draw_atomically(&dir.join("una-corda.png"), una_corda)?;
    let half = draw_atomically(&dir.join("half-pedal.png"), half_pedal)?;
    let contacts = draw_atomically(&dir.join("contact.png"), contacts)?;
    draw_atomically(&dir.join("inharmonicity.png"), inharmonicity)?;
    draw_atomically(&dir.join("lengths.png"), lengths)?;
    let decays = draw_atomically(&dir.join("decay.png"), decays)?;
    let t60 = MEASURED_T60.map(|m| (m, fundamental_t60(m.0, false), fundamental_t60(m.0, true)));
    let sympathy = draw_atomically(&dir.join("sympathetic.png"), sympathetic)?;
    let undamped = undamped_ring();
    let held = held_ring(0.0);
    let guitars = draw_atomically(&dir.join("acoustic.png"), acoustic)?;
    let stereo = stereo_guitar(&guitars);
    draw_atomically(&dir.join("guitar-body.png"), guitar_body)?;
    // The fortissimo scale peaking at −1 dBFS: the dynamics stay audible.
    let scales = [("pp", 40u8), ("mf", 80), ("ff", 120)].map(|(name, velocity)| (name, scale(velocity)));
    write_at_one_gain(&dir, "scale", &scales)?;
    let phrases = [("electric", SlideBody::Pickup), ("acoustic", SlideBody::Acoustic)]
        .map(|(name, body)| (name, guitar_phrase(body)));
    write_at_one_gain(&dir, "guitar", &phrases)?;
    let text = readme(
        &envelopes,
        (&shifted, &half),
        &contacts,
        &decays,
        &t60,
        (&sympathy, undamped, held),
        (&guitars, &stereo),
    );
    let path = args.root.join("docs/report/realism.md");
    crate::examples::write_atomically(&path, |file| std::io::Write::write_all(file, text.as_bytes()))
        .map_err(|e| e.to_string())?;
    writeln!(out, "{}", serde_json::json!({ "written": path.display().to_string() })).map_err(|e| e.to_string())
}

/// C4's partial levels: `(partial, detune, levels)` for partials 1–3 at the default spread and
/// partial 2 tuned exactly.
type Envelope = (usize, f64, Vec<f64>);

fn envelopes(path: &Path) -> Result<Vec<Envelope>, String> {
    let spread = Settings::default().unison_detune;
    let (detuned, exact) = (held_note(60, 0.6, spread, 5.0), held_note(60, 0.6, 0.0, 5.0));
    let c4 = tuned(60);
    let mut rows: Vec<Envelope> =
        (1..=3).map(|p| (p, spread, partial_levels(&detuned, c4.partial(p), c4.partial(1)))).collect();
    rows.push((2, 0.0, partial_levels(&exact, c4.partial(2), c4.partial(1))));
    let lines =
        rows.iter().zip([BLUE, GREEN, RED, PURPLE]).map(|((partial, detune, levels), colour)| match *detune > 0.0 {
            true => (levels.as_slice(), colour, format!("partial {partial}, unison spread {detune} cents"), 2),
            false => (levels.as_slice(), colour, format!("partial {partial}, unison tuned exactly alike"), 1),
        });
    let caption =
        format!("C4 struck at {:.1} m/s (velocity 0.6) and held: partial levels (every 50 ms)", hammer_speed(0.6));
    draw_levels(path, &caption, lines.collect())?;
    Ok(rows)
}

/// C4's partial levels with the pedal up and with the soft pedal down: `(partial, soft, levels)`
/// for partials 1 and 2.
type Shifted = (usize, bool, Vec<f64>);

fn una_corda(path: &Path) -> Result<Vec<Shifted>, String> {
    let spread = Settings::default().unison_detune;
    let notes = [false, true].map(|soft| (soft, held_note_shifted(60, 0.6, spread, soft, 5.0)));
    let c4 = tuned(60);
    let rows: Vec<Shifted> = [1, 2]
        .into_iter()
        .flat_map(|p| {
            notes.iter().map(move |(soft, out)| (p, *soft, partial_levels(out, c4.partial(p), c4.partial(1))))
        })
        .collect();
    let lines = rows.iter().zip([BLUE, BLUE, RED, RED]).map(|((partial, soft, levels), colour)| match soft {
        true => (levels.as_slice(), colour, format!("partial {partial}, una corda: two strings struck"), 1),
        false => (levels.as_slice(), colour, format!("partial {partial}, all three strings struck"), 2),
    });
    let caption = format!(
        "C4 struck at {:.1} m/s (velocity 0.6) and held, with and without the una corda (levels every 50 ms)",
        hammer_speed(0.6)
    );
    draw_levels(path, &caption, lines.collect())?;
    Ok(rows)
}

/// How far down the sustain pedal is in `half_pedal`'s renders: up, three points of its
/// half-way zone (the dampers hovering) and down.
pub const HALF_PEDALS: [f32; 5] = [0.0, 0.4, 0.5, 0.6, 1.0];

/// When [`half_pedal`]'s key is let go (s).
const HALF_PEDAL_RELEASE: f64 = 0.5;

/// C2's fundamental level, struck at velocity 0.7 and let go after [`HALF_PEDAL_RELEASE`], with
/// the sustain pedal at each of [`HALF_PEDALS`]: `(depth, levels)`.
type HalfPedal = (f32, Vec<f64>);

fn half_pedal(path: &Path) -> Result<Vec<HalfPedal>, String> {
    let c2 = tuned(36);
    let rows: Vec<HalfPedal> = HALF_PEDALS
        .into_iter()
        .map(|depth| {
            let events = [
                (0.0, Event::Sustain { channel: 0, depth }),
                (0.0, Event::NoteOn { channel: 0, key: 36, velocity: 0.7 }),
                (HALF_PEDAL_RELEASE, Event::NoteOff { channel: 0, key: 36 }),
            ];
            (depth, partial_levels(&performed(&events, 5.0), c2.partial(1), c2.partial(1)))
        })
        .collect();
    let lines = rows.iter().zip([BLACK, RED, GREEN, BLUE, PURPLE]).map(|((depth, levels), colour)| {
        let label = match *depth {
            0.0 => "pedal up".to_string(),
            1.0 => "pedal down".to_string(),
            d => format!(
                "pedal at {d}: dampers {:.0} µm above",
                1e6 * qsa_dsp::instrument::damper_lift(f64::from(d), &Settings::default())
            ),
        };
        (levels.as_slice(), colour, label, 2)
    });
    let caption = "C2 struck at velocity 0.7, let go at 0.5 s: its fundamental's level (every 50 ms)";
    draw_levels(path, caption, lines.collect())?;
    Ok(rows)
}

/// Draw partial levels over 5 s into `path`, each line `(levels per LEVEL_WINDOW, colour, label,
/// width)`, the scale spanning 80 dB below the highest.
fn draw_levels(path: &Path, caption: &str, lines: Vec<(&[f64], RGBColor, String, u32)>) -> Result<(), String> {
    let top = lines.iter().flat_map(|l| l.0.iter().copied()).fold(f64::NEG_INFINITY, f64::max);
    let root = BitMapBackend::new(path, (960, 560)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let mut chart = ChartBuilder::on(&root)
        .caption(caption, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(60)
        .build_cartesian_2d(0f64..5f64, (top - 80.0)..(top + 3.0))
        .map_err(|e| e.to_string())?;
    chart.configure_mesh().x_desc("time (s)").y_desc("level (dB)").draw().map_err(|e| e.to_string())?;
    for (levels, colour, label, width) in lines {
        let points = levels.iter().enumerate().map(|(k, &l)| ((k as f64 + 0.5) * LEVEL_WINDOW, l));
        chart
            .draw_series(LineSeries::new(points, colour.stroke_width(width)))
            .map_err(|e| e.to_string())?
            .label(label)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(width)));
    }
    crate::report::plot::legend(&mut chart, SeriesLabelPosition::UpperRight)?;
    root.present().map_err(|e| e.to_string())
}

/// Contact durations (ms) per key: `(key, mezzo-forte, forte)`.
type Contact = (u8, f64, f64);

fn contacts(path: &Path) -> Result<Vec<Contact>, String> {
    let rows: Vec<Contact> = (21..=108u8)
        .filter_map(|k| Some((k, contact_duration(k, MEZZO_FORTE)? * 1e3, contact_duration(k, FORTE)? * 1e3)))
        .collect();
    let root = BitMapBackend::new(path, (960, 560)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let mut chart = against_key(&root, "Hammer–string contact duration against key", (0.1, 10.0), 60)?;
    chart.configure_mesh().x_desc(KEY_AXIS).y_desc("duration (ms)").draw().map_err(|e| e.to_string())?;
    let series = [
        (rows.iter().map(|r| (f64::from(r.0), r.1)).collect::<Vec<_>>(), BLUE, "the model, mezzo-forte (2.5 m/s)"),
        (rows.iter().map(|r| (f64::from(r.0), r.2)).collect::<Vec<_>>(), RED, "the model, forte (5 m/s)"),
        (
            (21..=108u8).map(|k| (f64::from(k), 1e3 / pitch(k))).collect(),
            RGBColor(128, 128, 128),
            "the string's period",
        ),
    ];
    for (points, colour, label) in series {
        chart
            .draw_series(LineSeries::new(points, colour.stroke_width(2)))
            .map_err(|e| e.to_string())?
            .label(label)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2)));
    }
    for (key, _, low, high, source) in MEASURED_CONTACT {
        let (x, low) = (f64::from(key), low.max(0.1));
        chart
            .draw_series([
                PathElement::new(vec![(x, low), (x, high)], GREEN.stroke_width(3)),
                PathElement::new(vec![(x - 0.6, high), (x + 0.6, high)], GREEN.stroke_width(3)),
            ])
            .map_err(|e| e.to_string())?;
        chart.draw_series([Circle::new((x, high), 4, GREEN.filled())]).map_err(|e| e.to_string())?;
        let _ = source;
    }
    chart
        .draw_series([Circle::new((0.0, 0.0), 0, GREEN.filled())])
        .map_err(|e| e.to_string())?
        .label("measured on grands (docs/physics.md §8.4)")
        .legend(|(x, y)| Circle::new((x + 10, y), 4, GREEN.filled()));
    crate::report::plot::legend(&mut chart, SeriesLabelPosition::UpperRight)?;
    root.present().map_err(|e| e.to_string())?;
    Ok(rows)
}

/// The x axis of the pictures against key.
const KEY_AXIS: &str = "MIDI key (21 = A0, 60 = C4, 108 = C8)";

/// A chart over the keyboard (MIDI keys 20 to 109) of a quantity on a log scale from `low` to
/// `high`, with `y_area` pixels for its labels.
fn against_key<'a, 'b>(
    root: &'b DrawingArea<BitMapBackend<'a>, Shift>,
    caption: &str,
    (low, high): (f64, f64),
    y_area: u32,
) -> Result<ChartContext<'b, BitMapBackend<'a>, Cartesian2d<RangedCoordf64, LogCoord<f64>>>, String> {
    ChartBuilder::on(root)
        .caption(caption, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(y_area)
        .build_cartesian_2d(20f64..109f64, (low..high).log_scale())
        .map_err(|e| e.to_string())
}

fn inharmonicity(path: &Path) -> Result<(), String> {
    let root = BitMapBackend::new(path, (960, 560)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let mut chart = against_key(&root, "Inharmonicity coefficient B against key", (1e-5, 0.1), 70)?;
    chart
        .configure_mesh()
        .x_desc(KEY_AXIS)
        .y_desc("B")
        .y_label_formatter(&|b| format!("{b:.0e}"))
        .draw()
        .map_err(|e| e.to_string())?;
    let model: Vec<(f64, f64)> = (21..=108u8).map(|k| (f64::from(k), piano_note(k).string.inharmonicity())).collect();
    chart
        .draw_series(LineSeries::new(model, BLUE.stroke_width(2)))
        .map_err(|e| e.to_string())?
        .label("the per-note rule")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE.stroke_width(2)));
    let young: Vec<(f64, f64)> = (60..=108u8).map(|k| (f64::from(k), young_inharmonicity(k))).collect();
    chart
        .draw_series(DashedLineSeries::new(young, 6, 4, BLACK.stroke_width(2)))
        .map_err(|e| e.to_string())?
        .label("plain wire, six pianos: Young 1952")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.stroke_width(2)));
    for (source, colour) in [("Lehtonen et al. 2007", RED), ("Rigaud et al. 2013", GREEN)] {
        let marks: Vec<_> = MEASURED_B.iter().filter(|m| m.3 == source).collect();
        for m in &marks {
            let x = f64::from(m.0) + if colour == RED { -0.5 } else { 0.5 };
            chart
                .draw_series([PathElement::new(vec![(x, m.1), (x, m.2)], colour.stroke_width(3))])
                .map_err(|e| e.to_string())?;
        }
        chart
            .draw_series(marks.iter().map(|m| {
                let x = f64::from(m.0) + if colour == RED { -0.5 } else { 0.5 };
                Circle::new((x, (m.1 * m.2).sqrt()), 4, colour.filled())
            }))
            .map_err(|e| e.to_string())?
            .label(format!("measured: {source}"))
            .legend(move |(x, y)| Circle::new((x + 10, y), 4, colour.filled()));
    }
    crate::report::plot::legend(&mut chart, SeriesLabelPosition::UpperLeft)?;
    root.present().map_err(|e| e.to_string())
}

fn lengths(path: &Path) -> Result<(), String> {
    let root = BitMapBackend::new(path, (960, 560)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let mut chart = against_key(&root, "Speaking length against key", (0.04, 2.5), 70)?;
    chart
        .configure_mesh()
        .x_desc(KEY_AXIS)
        .y_desc("speaking length (m)")
        .y_labels(12)
        .light_line_style(WHITE)
        .y_label_formatter(&|l| format!("{l:.2}"))
        .draw()
        .map_err(|e| e.to_string())?;
    let model: Vec<(f64, f64)> = (21..=108u8).map(|k| (f64::from(k), piano_note(k).string.length)).collect();
    chart
        .draw_series(LineSeries::new(model, BLUE.stroke_width(2)))
        .map_err(|e| e.to_string())?
        .label("the per-note rule")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE.stroke_width(2)));
    let measured = (21..=108u8).filter_map(|k| Some((f64::from(k), measured_length(k)?)));
    chart
        .draw_series(measured.map(|p| Circle::new(p, 3, RED.filled())))
        .map_err(|e| e.to_string())?
        .label("measured: Steinway M (1936)")
        .legend(|(x, y)| Circle::new((x + 10, y), 3, RED.filled()));
    chart
        .draw_series(CONCERT_GRAND_LENGTHS.iter().map(|&(k, l)| Circle::new((f64::from(k), l), 5, GREEN.filled())))
        .map_err(|e| e.to_string())?
        .label("Steinway D (Chabassier et al. 2013)")
        .legend(|(x, y)| Circle::new((x + 10, y), 5, GREEN.filled()));
    crate::report::plot::legend(&mut chart, SeriesLabelPosition::UpperRight)?;
    root.present().map_err(|e| e.to_string())
}

/// Decay rates (dB/s) per key: `(key, [(prompt, aftersound); 2], whole)` for partials 1 and 2,
/// and partial 1's whole decay over [`WHOLE`].
type Decay = (u8, [(f64, f64); 2], f64);

fn decays(path: &Path) -> Result<Vec<Decay>, String> {
    let spread = Settings::default().unison_detune;
    let rows: Vec<Decay> = (24..=96u8)
        .step_by(3)
        .map(|k| {
            let out = held_note(k, 0.6, spread, WHOLE.1 + 0.5);
            let note = tuned(k);
            let levels = [1, 2].map(|p| partial_levels(&out, note.partial(p), note.partial(1)));
            let rates = levels.each_ref().map(|l| (-decay_rate(l, PROMPT), -decay_rate(l, AFTERSOUND)));
            (k, rates, -decay_rate(&levels[0], WHOLE))
        })
        .collect();
    let top = rows.iter().flat_map(|r| r.1.iter().flat_map(|p| [p.0, p.1])).fold(1.0, f64::max);
    let root = BitMapBackend::new(path, (960, 560)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!("Decay rates of the first two partials (velocity 0.6, {:.1} m/s, held)", hammer_speed(0.6)),
            ("sans-serif", 22),
        )
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(60)
        .build_cartesian_2d(20f64..100f64, (0.5f64..top * 1.5).log_scale())
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_desc("MIDI key (21 = A0, 60 = C4, 96 = C7)")
        .y_desc("decay rate (dB/s)")
        .draw()
        .map_err(|e| e.to_string())?;
    let lines = [
        (0, true, BLUE, "partial 1, prompt sound (0.05–0.6 s)"),
        (0, false, RGBColor(150, 190, 220), "partial 1, aftersound (2–4.5 s)"),
        (1, true, RED, "partial 2, prompt sound"),
        (1, false, RGBColor(235, 150, 150), "partial 2, aftersound"),
    ];
    for (p, prompt, colour, label) in lines {
        let points: Vec<(f64, f64)> = rows
            .iter()
            .map(|r| (f64::from(r.0), if prompt { r.1[p].0 } else { r.1[p].1 }))
            .filter(|&(_, v)| v > 0.5)
            .collect();
        chart
            .draw_series(LineSeries::new(points, colour.stroke_width(2)))
            .map_err(|e| e.to_string())?
            .label(label)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2)));
    }
    let whole: Vec<(f64, f64)> = rows.iter().map(|r| (f64::from(r.0), r.2)).filter(|&(_, v)| v > 0.5).collect();
    chart
        .draw_series(LineSeries::new(whole, BLACK.stroke_width(2)))
        .map_err(|e| e.to_string())?
        .label(format!("partial 1, whole decay ({}–{} s)", WHOLE.0, WHOLE.1))
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.stroke_width(2)));
    chart
        .draw_series(MEASURED_T60.iter().map(|m| Circle::new((f64::from(m.0), 60.0 / m.1), 5, BLACK.filled())))
        .map_err(|e| e.to_string())?
        .label("measured: a grand's fundamental, 60 dB / T60 (Lehtonen et al. 2007)")
        .legend(|(x, y)| Circle::new((x + 10, y), 4, BLACK.filled()));
    crate::report::plot::legend(&mut chart, SeriesLabelPosition::UpperLeft)?;
    root.present().map_err(|e| e.to_string())?;
    Ok(rows)
}

/// The name of `key` (MIDI), sharps for black keys: 61 is C♯4.
fn name_of(key: u8) -> String {
    const NAMES: [&str; 12] = ["C", "C♯", "D", "D♯", "E", "F", "F♯", "G", "G♯", "A", "A♯", "B"];
    format!("{}{}", NAMES[usize::from(key % 12)], i32::from(key / 12) - 1)
}

/// What the pedal adds to C3 (held 3 s, over 1–3 s) at the pitch of each key from C3 to C6,
/// against C3 with the pedal up at the same pitch: `(key, added, pedal up)` amplitudes.
type Sympathy = Vec<(u8, f64, f64)>;

fn sympathetic(path: &Path) -> Result<Sympathy, String> {
    let (down, up) = (held_with_pedal(48, Some(0.0), 3.0), held_with_pedal(48, None, 3.0));
    let added: Vec<f64> = down.iter().zip(&up).map(|(d, u)| d - u).collect();
    let from = FS as usize;
    let rows: Sympathy =
        (49..=84u8).map(|k| (k, level_near(&added, from, pitch(k)), level_near(&up, from, pitch(k)))).collect();
    let db = |a: f64| 20.0 * a.max(1e-12).log10();
    let top = rows.iter().map(|r| db(r.1).max(db(r.2))).fold(f64::NEG_INFINITY, f64::max);
    let root = BitMapBackend::new(path, (960, 520)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let mut chart = ChartBuilder::on(&root)
        .caption("C3 held, 1–3 s: what the pedal adds at each key's pitch", ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(60)
        .build_cartesian_2d(48.5f64..84.5f64, (top - 90.0)..(top + 5.0))
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_desc("key (MIDI): 60 C4, 67 G4, 72 C5, 76 E5")
        .y_desc("amplitude (dB)")
        .draw()
        .map_err(|e| e.to_string())?;
    let added_points = rows.iter().map(|r| (f64::from(r.0), db(r.1)));
    chart
        .draw_series(added_points.clone().map(|(x, y)| Circle::new((x, y), 4, RED.filled())))
        .map_err(|e| e.to_string())?
        .label("added by the pedal (pedal down − pedal up)")
        .legend(|(x, y)| Circle::new((x + 10, y), 4, RED.filled()));
    chart.draw_series(LineSeries::new(added_points, RED.stroke_width(1))).map_err(|e| e.to_string())?;
    let up_points = rows.iter().map(|r| (f64::from(r.0), db(r.2)));
    chart
        .draw_series(LineSeries::new(up_points, BLUE.stroke_width(2)))
        .map_err(|e| e.to_string())?
        .label("C3 with the pedal up")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE.stroke_width(2)));
    crate::report::plot::legend(&mut chart, SeriesLabelPosition::LowerLeft)?;
    root.present().map_err(|e| e.to_string())?;
    Ok(rows)
}

/// A slide note of `key` at velocity 80 held 2 s on the guitar `body`, at [`FS`] with the limiter
/// off, the guitar changed to `change_to` 0.21 s in if given (a sounding note keeps its own):
/// what a listener hears, centred (stereo width 0; the acoustic body's pan keeps each mode's
/// power).
pub fn slide_note(body: SlideBody, key: u8, change_to: Option<SlideBody>) -> Vec<f32> {
    let [left, _] = slide_note_heard(body, key, 0.0, change_to);
    left
}

/// [`slide_note`] at stereo width `width` (−1..=1): the left and right channels.
pub fn slide_note_heard(body: SlideBody, key: u8, width: f64, change_to: Option<SlideBody>) -> [Vec<f32>; 2] {
    let settings =
        Settings { mode: Mode::Slide, slide_body: body, limiter: false, stereo_width: width, ..Settings::default() };
    let mut guitar = Instrument::new(FS, 4, settings);
    guitar.handle(Event::NoteOn { channel: 0, key, velocity: 80.0 / 127.0 });
    let n = (2.0 * FS) as usize;
    let (mut left, mut right) = (vec![0.0f32; n], vec![0.0f32; n]);
    for (k, (l, r)) in left.chunks_mut(256).zip(right.chunks_mut(256)).enumerate() {
        if k == 40
            && let Some(other) = change_to
        {
            guitar.set_settings(&Settings { slide_body: other, ..settings });
        }
        guitar.process(l, r);
    }
    [left, right]
}

/// The slide guitar's notes A2–C5, each its integrated loudness (LUFS) on the electric and on the
/// acoustic guitar: `(key, electric, acoustic)`.
type Guitars = Vec<(u8, f64, f64)>;

fn acoustic(path: &Path) -> Result<Guitars, String> {
    let lufs = |body, key| crate::loudness::integrated_lufs(&slide_note(body, key, None), FS);
    let rows: Guitars = (45..=72u8).map(|k| (k, lufs(SlideBody::Pickup, k), lufs(SlideBody::Acoustic, k))).collect();
    let (low, high) = rows
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), r| (lo.min(r.1).min(r.2), hi.max(r.1).max(r.2)));
    let root = BitMapBackend::new(path, (960, 520)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let mut chart = ChartBuilder::on(&root)
        .caption("Slide notes at velocity 80 on the two guitars", ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(60)
        .build_cartesian_2d(44.5f64..72.5f64, (low - 3.0)..(high + 3.0))
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_desc("key (MIDI): 45 A2, the open string; 57 A3, on the top's 219 Hz resonance")
        .y_desc("integrated loudness over 2 s (LUFS)")
        .draw()
        .map_err(|e| e.to_string())?;
    for (label, color, pick) in [
        ("electric: the pickup and its circuit", BLUE, (|r: &(u8, f64, f64)| r.1) as fn(&(u8, f64, f64)) -> f64),
        ("acoustic: the string on the body, coupled both ways", RED, |r| r.2),
    ] {
        let points = rows.iter().map(move |r| (f64::from(r.0), pick(r)));
        chart
            .draw_series(LineSeries::new(points, color.stroke_width(2)))
            .map_err(|e| e.to_string())?
            .label(label)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
    }
    crate::report::plot::legend(&mut chart, SeriesLabelPosition::UpperRight)?;
    root.present().map_err(|e| e.to_string())?;
    Ok(rows)
}

/// The acoustic guitar's notes A2–C5 heard in stereo at the default width, each the correlation
/// of its two channels and its integrated loudness against the same note centred (LU):
/// `(key, correlation, change)`.
type StereoGuitar = Vec<(u8, f64, f64)>;

/// [`StereoGuitar`] for the notes of `guitars`, whose acoustic loudness is the centred one.
fn stereo_guitar(guitars: &Guitars) -> StereoGuitar {
    let width = Settings::default().stereo_width;
    guitars
        .iter()
        .map(|&(key, _, centred)| {
            let [left, right] = slide_note_heard(SlideBody::Acoustic, key, width, None);
            let change = crate::loudness::integrated_lufs_stereo(&left, &right, FS) - centred;
            (key, crate::examples::correlation(&left, &right), change)
        })
        .collect()
}

/// The acoustic guitar's body as a listener hears it: the transmittance's power gain (dB, 1 over
/// 1–4 kHz) from 60 Hz to 10 kHz, of the whole body and of the two-mass pair alone (normalised
/// alike), the air and top resonances marked.
fn guitar_body(path: &Path) -> Result<(), String> {
    use qsa_dsp::body::{BodyParams, GUITAR_AIR, GUITAR_TOP, Heard};
    let body = BodyParams::guitar();
    let pair = BodyParams { modes: body.modes[..2].to_vec(), heard: Heard::Acceleration };
    let pair_gain = 1.0 / pair.mean_power_gain((1000.0, 4000.0));
    let db = |b: &BodyParams, scale: f64, f: f64| {
        let (re, im) = b.response(f);
        10.0 * (scale * (re * re + im * im)).log10()
    };
    let (low, high, n) = (60.0f64, 10_000.0f64, 1500);
    let grid: Vec<f64> = (0..n).map(|k| low * (high / low).powf(k as f64 / (n - 1) as f64)).collect();
    let root = BitMapBackend::new(path, (960, 520)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let mut chart = ChartBuilder::on(&root)
        .caption("The acoustic guitar's body: pressure per bridge force", ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(60)
        .build_cartesian_2d((low..high).log_scale(), -40.0f64..40.0f64)
        .map_err(|e| e.to_string())?;
    let hertz = |x: &f64| if crate::report::plot::is_labelled_log_tick(*x) { format!("{x:.0}") } else { String::new() };
    chart
        .configure_mesh()
        .x_desc("frequency (Hz); the air resonance at 104 Hz, the top's at 219 Hz")
        .y_desc("power gain (dB), 0 dB the mean over 1–4 kHz")
        .x_label_formatter(&hertz)
        .draw()
        .map_err(|e| e.to_string())?;
    for (label, color, b, scale) in [
        ("the two-mass pair alone (Christensen & Vistisen)", BLUE, &pair, pair_gain),
        ("with the top's higher modes (the instrument's body)", RED, &body, 1.0),
    ] {
        let points: Vec<(f64, f64)> = grid.iter().map(|&f| (f, db(b, scale, f))).collect();
        chart
            .draw_series(LineSeries::new(points, color.stroke_width(2)))
            .map_err(|e| e.to_string())?
            .label(label)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
    }
    let grey = BLACK.mix(0.4).stroke_width(1);
    for f in [GUITAR_AIR, GUITAR_TOP] {
        chart.draw_series(LineSeries::new([(f, -40.0), (f, 40.0)], grey)).map_err(|e| e.to_string())?;
    }
    crate::report::plot::legend(&mut chart, SeriesLabelPosition::LowerRight)?;
    root.present().map_err(|e| e.to_string())?;
    Ok(())
}

/// Write each of `sounds` as `<prefix>-<name>.wav` in `dir`, all raised by the one gain that
/// brings the loudest peak among them to −1 dBFS: they keep their levels against one another.
fn write_at_one_gain(dir: &Path, prefix: &str, sounds: &[(&str, Vec<f64>)]) -> Result<(), String> {
    let peak = sounds.iter().flat_map(|s| s.1.iter()).fold(0.0f64, |m, x| m.max(x.abs()));
    let gain = 10f64.powf(-1.0 / 20.0) / peak.max(f64::MIN_POSITIVE);
    for (name, sound) in sounds {
        let path = dir.join(format!("{prefix}-{name}.wav"));
        let scaled: Vec<f64> = sound.iter().map(|x| x * gain).collect();
        crate::examples::write_atomically(&path, |f| crate::examples::write_wav(f, &[&scaled]))
            .map_err(|e| e.to_string())?;
    }
    Ok(())
}

/// A2, C3, E3, A3 and C4 on the slide guitar `body` at velocity 80, the slide following the key,
/// a note every 0.45 s held 0.4 s and the last 1 s, at [`crate::examples::RATE`] with the limiter
/// off: what a listener hears, centred (stereo width 0).
fn guitar_phrase(body: SlideBody) -> Vec<f64> {
    let fs = f64::from(crate::examples::RATE);
    let settings =
        Settings { mode: Mode::Slide, slide_body: body, limiter: false, stereo_width: 0.0, ..Settings::default() };
    let mut guitar = Instrument::new(fs, 4, settings);
    let keys = [45u8, 48, 52, 57, 60];
    let step = (0.45 * fs) as usize;
    let n = step * (keys.len() - 1) + (1.2 * fs) as usize;
    let mut events: Vec<(usize, Event)> = Vec::new();
    for (i, &key) in keys.iter().enumerate() {
        events.push((i * step, Event::NoteOn { channel: 0, key, velocity: 80.0 / 127.0 }));
        let hold = if i + 1 == keys.len() { fs } else { 0.4 * fs } as usize;
        events.push((i * step + hold, Event::NoteOff { channel: 0, key }));
    }
    played_at_samples(&mut guitar, events, n)
}

/// C4 to C5 (C major) at MIDI `velocity`, a note every 0.3 s held 0.28 s, the last held 1.5 s,
/// at [`crate::examples::RATE`]: what a listener hears, centred (stereo width 0).
fn scale(velocity: u8) -> Vec<f64> {
    let fs = f64::from(crate::examples::RATE);
    let mut piano = Instrument::new(fs, 16, Settings { stereo_width: 0.0, ..Settings::default() });
    let keys = [60u8, 62, 64, 65, 67, 69, 71, 72];
    let step = (0.3 * fs) as usize;
    let n = step * keys.len() + (2.0 * fs) as usize;
    let mut events: Vec<(usize, Event)> = Vec::new();
    for (i, &key) in keys.iter().enumerate() {
        let velocity = f32::from(velocity) / 127.0;
        events.push((i * step, Event::NoteOn { channel: 0, key, velocity }));
        let hold = if i + 1 == keys.len() { (1.5 * fs) as usize } else { (0.28 * fs) as usize };
        events.push((i * step + hold, Event::NoteOff { channel: 0, key }));
    }
    played_at_samples(&mut piano, events, n)
}

/// `n` samples of `instrument`'s left channel playing `events`, each at its sample (in time
/// order; those at one sample in the order given).
fn played_at_samples(instrument: &mut Instrument, mut events: Vec<(usize, Event)>, n: usize) -> Vec<f64> {
    events.sort_by_key(|e| e.0);
    let (mut left, mut right) = (vec![0.0f32; n], vec![0.0f32; n]);
    let mut t = 0;
    for (at, event) in events.into_iter().chain([(n, Event::AllNotesOff)]) {
        if at > t {
            instrument.process(&mut left[t..at], &mut right[t..at]);
            t = at;
        }
        if at < n {
            instrument.handle(event);
        }
    }
    left.into_iter().map(f64::from).collect()
}

/// A published T60 row beside the model's: `((key, up, down), model up, model down)` (s).
type T60Row = ((u8, f64, f64), f64, f64);

/// Whether a partial's decay rates (dB/s, positive for a decay) read two stages: a prompt sound at
/// least twice as fast as an aftersound that is no slower than the strings' own loss allows (a
/// slower one reads a beat slower than the span it is fitted over, not a stage).
pub fn two_stage(prompt: f64, after: f64) -> bool {
    after >= OWN_LOSS_RATE && prompt >= 2.0 * after
}

/// An aftersound's rate (dB/s) as a table shows it: slower than the strings' own loss allows, it
/// reads a beat slower than the span it is fitted over, and says so.
fn aftersound_cell(rate: f64) -> String {
    if rate < OWN_LOSS_RATE { format!("{rate:.1} (a beat)") } else { format!("{rate:.1}") }
}

fn readme(
    envelopes: &[Envelope],
    (shifted, half): (&[Shifted], &[HalfPedal]),
    contacts: &[Contact],
    decays: &[Decay],
    t60: &[T60Row],
    (sympathy, undamped, held): (&Sympathy, [(u8, f64); 2], [HeldRing; 3]),
    (guitars, stereo): (&Guitars, &StereoGuitar),
) -> String {
    let (spread, own) = (Settings::default().unison_detune, OWN_LOSS_RATE);
    let at = |levels: &[f64], span| -decay_rate(levels, span);
    let mut rows = String::new();
    for (partial, detune, levels) in envelopes {
        rows += &format!(
            "| {partial} | {} | {:.1} | {:.1} | {:.2} |\n",
            if *detune > 0.0 { format!("{detune} cents") } else { "tuned alike".into() },
            at(levels, PROMPT),
            at(levels, AFTERSOUND),
            at(levels, PROMPT) / at(levels, AFTERSOUND)
        );
    }
    // Each partial's level over the first 0.1 s, and how far it stands below the whole
    // unison's.
    let first = |levels: &[f64]| {
        let w = (0.1 / LEVEL_WINDOW).round() as usize;
        10.0 * (levels[..w].iter().map(|l| 10f64.powf(l / 10.0)).sum::<f64>() / w as f64).log10()
    };
    let mut una_rows = String::new();
    for (partial, soft, levels) in shifted {
        let whole = shifted.iter().find(|r| r.0 == *partial && !r.1).map_or(f64::NAN, |r| first(&r.2));
        una_rows += &format!(
            "| {partial} | {} | {:+.1} | {:.1} | {} |\n",
            if *soft { "down (two strings)" } else { "up (three strings)" },
            first(levels) - whole,
            at(levels, PROMPT),
            aftersound_cell(at(levels, AFTERSOUND))
        );
    }
    let half_rows: String = half
        .iter()
        .map(|(depth, levels)| {
            let lift = qsa_dsp::instrument::damper_lift(f64::from(*depth), &Settings::default());
            let release = HALF_PEDAL_RELEASE;
            // The pedal-up tone has fallen silent by 2 s: no rate to read.
            let rate = |span| match at(levels, span) {
                r if r.is_finite() => format!("{r:.1}"),
                _ => "silent".into(),
            };
            format!(
                "| {depth} | {} | {} | {} |\n",
                if lift.is_finite() { format!("{:.0}", 1e6 * lift) } else { "clear".into() },
                rate((release, release + 0.2)),
                rate((2.0, 4.5))
            )
        })
        .collect();
    let t60_rows: String = t60
        .iter()
        .map(|&((key, up, down), model_up, model_down)| {
            format!(
                "| {} | {up:.1} | {model_up:.1} | {:.0} % | {down:.1} | {model_down:.1} | {:.2} | {:.2} |\n",
                name_of(key),
                100.0 * model_up / up,
                down / up,
                model_down / model_up
            )
        })
        .collect();
    let contact = |key: u8| contacts.iter().find(|c| c.0 == key).map_or(f64::NAN, |c| c.1);
    let crossover = contacts.iter().find(|c| c.1 * 1e-3 * pitch(c.0) >= 1.0).map_or(0, |c| c.0);
    let two_stage = decays.iter().filter(|d| two_stage(d.1[1].0, d.1[1].1)).count();
    let b = |key: u8| piano_note(key).string.inharmonicity();
    let percent = |ratio: f64| 100.0 * (ratio - 1.0);
    let span = |values: &mut dyn Iterator<Item = f64>| {
        values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)))
    };
    let (young_low, young_high) = span(&mut (60..=108u8).map(|k| percent(b(k) / young_inharmonicity(k))));
    let (grands_low, grands_high) = span(&mut measured_over_young().map(percent));
    let length = |key: u8| piano_note(key).string.length;
    let against_m = |key: u8| measured_length(key).map(|m| percent(length(key) / m));
    let (treble_low, treble_high) = span(&mut (60..=108u8).filter_map(against_m));
    let (tenor_low, tenor_high) = span(&mut (47..60u8).filter_map(against_m).map(|d| -d));
    let (concert_f7, m_f7) = (CONCERT_GRAND_LENGTHS[1].1, measured_length(102).unwrap_or(f64::NAN));
    let (f7, grands_f7) = (percent(length(102) / concert_f7), percent(concert_f7 / m_f7));
    let steel_treble = (60..=108u8)
        .map(steel_diameters)
        .map(|(mass, stiff)| 100.0 * (mass.max(stiff) / mass.min(stiff) - 1.0))
        .fold(0.0, f64::max);
    let ((c4_mass, c4_stiff), (c3_mass, c3_stiff)) = (steel_diameters(60), steel_diameters(48));
    let [c4_mass, c4_stiff, c3_mass, c3_stiff] = [c4_mass, c4_stiff, c3_mass, c3_stiff].map(|d| 1e3 * d);
    let added = |key: u8| sympathy.iter().find(|r| r.0 == key).map_or(f64::NAN, |r| r.1);
    let names = [(60u8, "C4"), (67, "G4"), (72, "C5"), (76, "E5")];
    let sympathy_rows = names
        .iter()
        .map(|&(key, name)| {
            format!("{name} {:.1} dB above {}", 20.0 * (added(key) / added(key + 1)).log10(), name_of(key + 1))
        })
        .collect::<Vec<_>>()
        .join(", ");
    let undamped_rows = undamped
        .iter()
        .map(|&(key, db)| format!("{} {db:.1} dB above {}", name_of(key), name_of(key + 1)))
        .collect::<Vec<_>>()
        .join(", ");
    let held_rows = held
        .iter()
        .map(|&(key, on, beside)| match on > 0.0 {
            true => format!(
                "with {0} held, {0} {1:.1} dB above {2}",
                name_of(key),
                20.0 * (on / beside).log10(),
                name_of(key + 1)
            ),
            false => format!("with {} held, whose strings none of C3's partials meet, nothing", name_of(key)),
        })
        .collect::<Vec<_>>()
        .join("; ");
    let c7_measured = MEASURED_CONTACT.iter().find(|m| m.0 == 96).map_or(f64::NAN, |m| m.2);
    let d3 = guitars.iter().find(|r| r.0 == 50).copied().unwrap_or((50, f64::NAN, f64::NAN));
    // The body's colour of each note: its loudness on the acoustic over the electric, each
    // relative to D3 on its guitar.
    let colour_of = |r: &(u8, f64, f64)| (r.2 - d3.2) - (r.1 - d3.1);
    let colour =
        guitars.iter().map(colour_of).fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), c| (lo.min(c), hi.max(c)));
    let a3 = guitars.iter().find(|r| r.0 == 57).map_or(f64::NAN, colour_of);
    let span = |pick: fn(&(u8, f64, f64)) -> f64| {
        stereo.iter().map(pick).fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)))
    };
    let (correlations, changes) = (span(|r| r.1), span(|r| r.2));
    let correlation_of = |key: u8| stereo.iter().find(|r| r.0 == key).map_or(f64::NAN, |r| r.1);
    let stereo_text = format!(
        "Heard in stereo at the default width ({:.0} %), the top's higher modes alternately on the left and on \
         the right and its lowest two in the centre (docs/physics.md §13.6), the notes' channels correlate \
         {:.2} to {:.2}: D3 {:.2}, whose partials lie on the top's higher modes, A3 {:.2}, on the top's \
         resonance; each note is {:+.1} to {:+.1} LU against its loudness centred (the figures above are \
         centred). The [audio examples](../examples/README.md) are in stereo.",
        100.0 * Settings::default().stereo_width,
        correlations.0,
        correlations.1,
        correlation_of(50),
        correlation_of(57),
        changes.0,
        changes.1,
    );
    format!(
        "# How the piano compares with real grands\n\n\
         Written by `cargo xtask realism` (`xtask/src/realism.rs`); the model is in docs/physics.md §12, the \
         published measurements and their sources in §8.4.\n\n\
         ## Two-stage decay\n\n\
         ![C4's partial levels](realism/envelopes.png)\n\n\
         C4 struck at velocity 0.6 ({:.1} m/s) and held, the pedal up, on the dry bridge force. Each partial's level is its heterodyned \
         amplitude on a Hann window every 50 ms, at least four periods of the fundamental long (the \
         neighbouring partials kept out); a stage's decay rate is the least-squares slope over the prompt sound \
         ({}–{} s) and the aftersound ({}–{} s). With the unison's strings mistuned (the default spread, {spread} \
         cents) the strings soon move apart, and the motion that does not push the bridge decays slowly: the \
         aftersound, with beats. Tuned exactly alike they stay together and decay in one stage (Weinreich, JASA \
         62(6), 1977).\n\n\
         | partial | unison | prompt sound (dB/s) | aftersound (dB/s) | ratio |\n|---|---|---|---|---|\n{rows}\n\
         ## The soft pedal\n\n\
         ![C4 with the una corda](realism/una-corda.png)\n\n\
         C4 struck as above, with the soft pedal down: the hammer shifted off one of the three strings \
         (docs/physics.md §12.9). The first 0.1 s is against the whole unison's level; the rates are measured \
         as above. The string the hammer misses rings from the bridge alone, and the strings start out of \
         step, so more of the motion lies in patterns that barely move the bridge: both partials start \
         lower and their prompt sounds decay more slowly; the aftersound's rates differ partial by \
         partial, as its beats fall elsewhere (a rate below the strings' own loss, {own:.2} dB/s, reads a \
         beat slower than the 2–4.5 s it is fitted over). Over all partials the note's first 0.1 s is about 2 dB \
         softer and its sound 2–3 s later stands higher against it (docs/physics.md §12.9 measures both at E2, C4 and \
         C5).\n\n\
         | partial | soft pedal | first 0.1 s (dB) | prompt sound (dB/s) | aftersound (dB/s) |\n|---|---|---|---|---|\n{una_rows}\n\
         ## Half-pedalling\n\n\
         ![C2 under the half pedal](realism/half-pedal.png)\n\n\
         C2 struck at velocity 0.7 and let go after 0.5 s, with the sustain pedal up, down and at three points \
         between, where the dampers hover above the strings and take only what swings beyond their lift \
         (docs/physics.md §6.5). As on the grand that Lehtonen, Askenfelt and Välimäki measured (JASA 126(2), \
         EL49, 2009), the released tone has three intervals: it rings freely while the key is held, decays \
         fast while the strings reach the felt, and rings on at about its free rate once they no longer do. \
         The deeper the pedal, the higher the level it rings on from. Decay rates of the fundamental over the \
         first 0.2 s after the release and over 2–4.5 s:\n\n\
         | pedal (of its way) | dampers' lift (µm) | after the release (dB/s) | from 2 s (dB/s) |\n|---|---|---|---|\n{half_rows}\n\
         ## Decay rates against key\n\n\
         ![decay rates](realism/decay.png)\n\n\
         Every third key from C1 to C7, struck at velocity 0.6 and held: the second partial's prompt sound decays \
         at least twice as fast as its aftersound on {two_stage} of {} keys (an aftersound no slower than the \
         strings' own loss allows: a slower one reads a beat slower than its span). The black line is the \
         fundamental's whole decay, one least-squares rate over {}–{} s, as a T60 is read off a recorded \
         tone; the dots are a \
         grand's measured fundamentals (Lehtonen et al., JASA 122(3), 2007, Table III; their D5 and C6 rows were \
         not read). Struck at velocity 0.7 and held, with the pedal up and with it down from the strike:\n\n\
         | key | T60 measured, pedal up (s) | model (s) | model / measured | T60 measured, pedal down (s) | model (s) | pedal's lengthening, measured | model |\n\
         |---|---|---|---|---|---|---|---|\n{t60_rows}\n\
         With the pedal up every model T60 lies within {:.0}–{:.0} % of the measured one, the range in which \
         listeners do not tell decay times apart (Tolonen & Järveläinen, AES 109th Convention, 2000). The \
         pedal's lengthening (the last two columns) is not the measured one. Two things stand in its way \
         (docs/physics.md §12.7): the strings' own loss alone keeps every partial decaying at 4.34 dB/s or faster (a T60 of \
         13.8 s; a fit across beats reads a little longer), short of every measured pedal-down T60, and a partner tuned almost exactly to a partial forms with it a motion that barely \
         moves the bridge, so its energy is not heard. The factor also swings with the partners' exact tuning: \
         every partner retuned by the same 1.5 or 3 cents, less than a unison's own spread, moves it to anywhere \
         from 0.64 to 1.35 at these three keys, in no common direction.\n\n\
         ## Contact duration against key\n\n\
         ![contact duration](realism/contact.png)\n\n\
         The hammer's first contact with its strings (±21 µs), at 2.5 m/s and 5 m/s. At mezzo-forte it lasts \
         {:.2} ms at C1 (measured on grands: 4–5 ms), {:.2} ms at C4 and {:.2} ms at C7 (Chaigne & Askenfelt: \
         {c7_measured:.2} ms); it first outlasts the string's period at key {crossover} (grands: about C6, key 84). The first \
         bichords (F1–G1) part from their strings and strike again (§8.4).\n\n\
         ## Inharmonicity against key\n\n\
         ![inharmonicity](realism/inharmonicity.png)\n\n\
         The rule's B beside Lehtonen et al. (JASA 122(3), 2007, one grand) and Rigaud et al. (JASA 133(5), \
         2013, the spread of their fit). The rule takes C2 and C4 from Lehtonen's grand ({:.2e} and {:.2e}) \
         and lies within Rigaud's spread widened by 10 % at C4, C6 and C8; below C2 it falls to \
         its clamp, where no measured bass string was found. The dashed line is what Young measured on the \
         plain strings of six pianos (JASA 24(3), 1952: about 1.2 cents on C4's second mode, doubling every \
         eight semitones): from C4 to C8 the rule lies {young_low:+.0} % to {young_high:+.0} % from it, the \
         measured grands above {grands_low:+.0} % to {grands_high:+.0} %.\n\n\
         ## String scale\n\n\
         ![speaking lengths](realism/lengths.png)\n\n\
         The rule's speaking lengths beside a measured grand's, a Steinway M from 1936 (B2 to C8, by a piano \
         technician; docs/physics.md §8.4), and the two ends of a Steinway D's modelled by Chabassier et al. \
         (JASA 134(1), 2013). From C4 to C8 the rule lies {treble_low:+.1} % to {treble_high:+.1} % from the M \
         (at F♯7 {f7:+.1} % from the D, whose string is {grands_f7:.0} % longer than the M's). From B2 to B3 it is \
         {tenor_low:.0} % to {tenor_high:.0} % shorter than the M, a smaller grand. The rule's strings as \
         steel wires: from C4 up, the wire with a string's mass and the wire with its bending stiffness \
         differ by at most {steel_treble:.0} % ({c4_mass:.2} and {c4_stiff:.2} mm at C4); at C3 the string weighs as a \
         {c3_mass:.2} mm wire but bends like a {c3_stiff:.2} mm one, as a wound string would, where a grand's \
         tenor has plain wire (docs/physics.md §8.4; given the M's lengths, the tenor's decay barely moves).\n\n\
         ## A scale at three dynamics\n\n\
         C4 to C5 at MIDI velocities 40, 80 and 120, each note held 0.28 s, 32 kHz mono 16-bit, all three \
         raised by one gain that brings the fortissimo scale's peak to −1 dBFS: [pianissimo](realism/scale-pp.wav), [mezzo-forte](realism/scale-mf.wav), \
         [fortissimo](realism/scale-ff.wav).\n\n\
         ## Sympathetic resonance\n\n\
         ![sympathetic resonance](realism/sympathetic.png)\n\n\
         C3 struck at velocity 0.7 and held 3 s, with the pedal down and with it up (dry, centred); over 1–3 s, \
         the amplitude of their difference at each key's pitch (what the pedal adds: the partner strings \
         ringing, and C3's partials giving up the energy they take, docs/physics.md §14), beside C3 alone. \
         The pedal adds most where C3's partials meet other keys' strings: {sympathy_rows}. With the pedal up \
         the strings without dampers, from E6 up (docs/physics.md §6.5), still ring: C5 let go after 0.2 s, its own \
         strings silenced, still sounds 0.5–1.5 s later where its 3rd and 4th partials meet them: \
         {undamped_rows}. So do the strings of a key held down, whose damper its key lifts: C3 let go after 0.2 s, \
         with another key pressed just before it at velocity 1/127 and held, adds over the same span {held_rows}.\n\n\
         ## The acoustic slide guitar\n\n\
         ![the two guitars](realism/acoustic.png)\n\n\
         ![the guitar's body](realism/guitar-body.png)\n\n\
         Each slide note A2–C5 plucked at velocity 80, the slide pressed, measured over 2 s. On the acoustic \
         guitar the string ends on the body (docs/physics.md §13.5): Christensen and Vistisen's measured air \
         and top resonances, and above them the top's higher modes, a plate drawn from the same measurements. \
         The string drives the body, which drains it and radiates. D3 measures {:.1} LUFS on the electric \
         guitar and {:.1} on the acoustic (the two are voiced alike there). Against the electric guitar (each \
         note relative to D3 on its guitar), the body colours the notes by {:+.1} to {:+.1} LU, and A3, on the \
         top's 219 Hz resonance, by {:+.1} LU: the two-mass model alone, flat above its resonances, leaves A3 \
         10.7 LU out. The second picture shows why: the pair alone is flat above the top's resonance, which \
         stands 30 dB above that plateau; with the top's higher modes the plateau rises, the resonance stands \
         19 dB above it, and the plate's modes put their own peaks and valleys in it from 300 Hz up. \
         A2, C3, E3, A3 and C4 at velocity 80 on each, a note every 0.45 s, 32 kHz mono 16-bit, one gain for \
         both: [electric](realism/guitar-electric.wav), [acoustic](realism/guitar-acoustic.wav).\n\n\
         {stereo_text}\n\n\
         ## Not shown yet\n\n\
         Each key has its own copy of the soundboard and of its partners. The copies add up to one shared \
         bridge, and a key struck meets its strings where the other copies ring them, but a partner is its \
         key's unison moving in phase, with its lowest modes only, and of keys struck in the same instant \
         each meets only what the ones rendered before it give its strings (docs/physics.md §14.3, §14.4). \
         Decay times above C4 have no measured grand beside them. The string scale is the rule's: its lengths \
         follow a measured grand's from C4 up, but no grand's tensions, tenor inharmonicity or wound bass \
         strings were found to set it from (docs/physics.md §8.4). The acoustic guitar's top above \
         its lowest mode is a mean-value plate drawn from the two-mass model's numbers, not a measured \
         guitar's modes (docs/physics.md §13.5).\n",
        hammer_speed(0.6),
        PROMPT.0,
        PROMPT.1,
        AFTERSOUND.0,
        AFTERSOUND.1,
        decays.len(),
        WHOLE.0,
        WHOLE.1,
        100.0 * T60_TOLERANCE.0,
        100.0 * T60_TOLERANCE.1,
        contact(24),
        contact(60),
        contact(96),
        b(36),
        b(60),
        d3.1,
        d3.2,
        colour.0,
        colour.1,
        a3,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two decaying partials `spacing` (Hz) apart, the second `louder` (dB) above the first at
    /// the start: `(rate of the first, rate of the second)` (dB/s) as the estimator reads them
    /// over the prompt sound's span.
    fn read_rates(f0: f64, rates: (f64, f64), louder: f64) -> (f64, f64) {
        let n = (1.0 * FS) as usize;
        let gain = 10f64.powf(louder / 20.0);
        let signal: Vec<f64> = (0..n)
            .map(|i| {
                let t = i as f64 / FS;
                let decay = |rate: f64| 10f64.powf(-rate * t / 20.0);
                decay(rates.0) * (std::f64::consts::TAU * f0 * t).sin()
                    + gain * decay(rates.1) * (std::f64::consts::TAU * 2.0 * f0 * t).sin()
            })
            .collect();
        let rate = |f| -decay_rate(&partial_levels(&signal, f, f0), PROMPT);
        (rate(f0), rate(2.0 * f0))
    }

    /// A partial's level keeps its neighbours out, at C1 too, where two partials lie 32.7 Hz
    /// apart: a fundamental decaying at 5 dB/s under a second partial 10 dB louder decaying at
    /// 20 dB/s reads 5 dB/s within 0.2, and the second 20 within 0.2 (a 50 ms rectangle, 20 Hz
    /// wide, read the first at 6.6).
    #[test]
    fn a_partial_at_c1_does_not_read_its_neighbours_decay() {
        let (first, second) = read_rates(32.7, (5.0, 20.0), 10.0);
        println!("C1: {first:.2} and {second:.2} dB/s");
        assert!((first - 5.0).abs() < 0.2 && (second - 20.0).abs() < 0.2, "{first}, {second}");
    }

    /// An aftersound slower than the strings' own loss allows is a beat, not a stage.
    #[test]
    fn a_sub_floor_aftersound_does_not_count_as_two_stage() {
        assert!(!two_stage(9.8, 2.2));
        assert!(two_stage(29.4, 5.8));
        assert!(!two_stage(21.1, 21.1));
    }
}
