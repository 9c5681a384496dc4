//! Per-note expression in the engine. In slide mode a note's tuning, pressure, brightness and
//! polyphonic modulation offsets reach that note alone, addressed by the host's voice id or by
//! channel and key; in piano mode its CC74 or brightness voices its hammer's felt. Host garbage
//! (NaN, infinities) is clamped; ended notes are reported once each; host buffer sizes change
//! nothing.
//!
//! References come from the engine itself without per-note events: a note whose tuning or offset
//! arrives with its note-on must render exactly as the note the offset describes (another key, or
//! the setting changed for everyone), and two notes are independent voices, so a pair renders as
//! the sum of the two notes rendered alone (to f32 rounding; the output stage is linear below its
//! ceiling, and these mezzo-piano notes peak far below it).

use qsa_dsp::contact::Method;
use qsa_dsp::instrument::{Event, HandSource, Instrument, Mode, NoteParam, NoteTarget, Settings};
use qsa_dsp::preset::key_frequency;
use qsa_tests::fundamental;
use rustfft::{FftPlanner, num_complex::Complex};

const FS: f64 = 48_000.0;

type Score = Vec<(usize, Event)>;

/// A slide instrument of 4 voices.
fn slide(settings: Settings) -> Instrument {
    Instrument::new(FS, 4, Settings { mode: Mode::Slide, ..settings })
}

/// A note-on with a host voice id, mezzo-piano: a pair of them stays far below the output
/// stage's ceiling, where the stage is linear.
fn on(channel: u8, key: u8, voice: i32) -> Event {
    Event::NoteOnWithId { channel, key, velocity: 0.3, voice }
}

/// Render `samples` samples of `score` in host calls of `chunk` samples (split at events).
fn play(instrument: &mut Instrument, score: &Score, samples: usize, chunk: usize) -> Vec<f32> {
    let (mut left, mut right) = (vec![0.0f32; samples], vec![0.0f32; samples]);
    let (mut next, mut t) = (0, 0);
    while t < samples {
        while next < score.len() && score[next].0 <= t {
            instrument.handle(score[next].1);
            next += 1;
        }
        let until = score.get(next).map_or(samples, |e| e.0);
        let n = chunk.min(until - t).min(samples - t).max(1);
        instrument.process(&mut left[t..t + n], &mut right[t..t + n]);
        t += n;
    }
    left
}

/// Pitch (Hz) of a slide note in `out[from..to]`: the period of the running sum (the string's
/// displacement at the pickup) by autocorrelation, searched within 20 % of `expected` (as in
/// `instrument.rs`).
fn pitch(out: &[f32], from: usize, to: usize, expected: f64) -> f64 {
    let signal = qsa_tests::displacement(&out[from..to]);
    fundamental(&signal, FS, 0.8 * expected, 1.2 * expected)
}

fn peak(x: &[f32]) -> f32 {
    x.iter().fold(0.0f32, |m, v| m.max(v.abs()))
}

/// Largest difference between `both` and `a + b`, relative to the peak of `both`.
fn mixture_error(both: &[f32], a: &[f32], b: &[f32]) -> f32 {
    let worst = both.iter().zip(a.iter().zip(b)).map(|(m, (x, y))| (m - (x + y)).abs()).fold(0.0f32, f32::max);
    worst / peak(both)
}

/// Bit-identical.
fn same(a: &[f32], b: &[f32]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
}

/// A tuning that arrives with its note-on (the way hosts send a note's expression) renders
/// exactly the note it tunes to: key 57 tuned +2 semitones is key 59, sample for sample. Tuning
/// note 2 of a pair (addressed by its voice id, then by channel and key) leaves note 1 as it
/// was: the pair renders as note 1 alone plus the tuned note 2 alone.
#[test]
fn a_tuning_at_note_on_plays_the_tuned_note_and_leaves_the_other_alone() {
    let reference = play(&mut slide(Settings::default()), &vec![(0, on(2, 59, 22))], 24_000, 256);
    let note_1 = play(&mut slide(Settings::default()), &vec![(0, on(1, 50, 11))], 24_000, 256);
    for target in [NoteTarget::voice(22), NoteTarget::key(2, 57)] {
        let tune = (0, Event::NoteTuning { note: target, semitones: 2.0 });
        let tuned = play(&mut slide(Settings::default()), &vec![(0, on(2, 57, 22)), tune], 24_000, 256);
        assert!(same(&tuned, &reference), "{target:?}: key 57 tuned +2 st differs from key 59");
        let pair = vec![(0, on(1, 50, 11)), (0, on(2, 57, 22)), tune];
        let both = play(&mut slide(Settings::default()), &pair, 24_000, 256);
        let error = mixture_error(&both, &note_1, &tuned);
        println!("{target:?}: pair vs note 1 + tuned note 2: {error:.2e} of the peak");
        assert!(error < 1e-6, "{target:?}: the tuning reached note 1 ({error:e} of the peak)");
    }
    let f = pitch(&reference, 7_200, 24_000, key_frequency(59));
    println!("key 57 tuned +2 st: {f:.2} Hz (key 59: {:.2} Hz)", key_frequency(59));
    assert!((f / key_frequency(59) - 1.0).abs() < 0.01);
}

/// A tuning during a note glides that note's slide there at the slide's speed limit: note 2 (key
/// 57, 220 Hz) tuned −3 semitones at 0.25 s sounds at key 54's pitch once it has arrived (measured
/// from 0.35 s; the slide needs `distance / 5 m/s`, printed), while note 1 (key 50) keeps its
/// pitch: the pair is note 1 alone plus the tuned note 2 alone.
#[test]
fn a_tuning_during_a_note_moves_only_that_note() {
    let tune = (12_000, Event::NoteTuning { note: NoteTarget::voice(22), semitones: -3.0 });
    let note_1 = play(&mut slide(Settings::default()), &vec![(0, on(1, 50, 11))], 48_000, 256);
    let note_2 = play(&mut slide(Settings::default()), &vec![(0, on(2, 57, 22)), tune], 48_000, 256);
    let both = play(&mut slide(Settings::default()), &vec![(0, on(1, 50, 11)), (0, on(2, 57, 22)), tune], 48_000, 256);
    let error = mixture_error(&both, &note_1, &note_2);
    let length = qsa_dsp::preset::slide_guitar().string.length;
    let distance = length * (2f64.powf(-9.0 / 12.0) - 2f64.powf(-12.0 / 12.0));
    println!(
        "pair vs the notes alone: {error:.2e} of the peak; the slide travels {distance:.3} m in {:.1} ms",
        1e3 * distance / qsa_dsp::instrument::SLIDE_SPEED
    );
    assert!(distance / qsa_dsp::instrument::SLIDE_SPEED < 0.05, "arrives well before the window");
    assert!(error < 1e-6, "the tuning reached note 1 ({error:e} of the peak)");
    let before = pitch(&note_2, 7_200, 12_000, key_frequency(57));
    let after = pitch(&note_2, 16_800, 48_000, key_frequency(54));
    println!(
        "note 2: {before:.2} Hz before, {after:.2} Hz after −3 st (keys 57, 54: {:.2}, {:.2} Hz)",
        key_frequency(57),
        key_frequency(54)
    );
    assert!((before / key_frequency(57) - 1.0).abs() < 0.01, "before: {before} Hz");
    assert!((after / key_frequency(54) - 1.0).abs() < 0.01, "after: {after} Hz");
}

/// A bend that arrives before its note-on (as MPE controllers send a note's initial bend, and as
/// a bend wheel held from an earlier note leaves it) places the slide from the start: key 50 bent
/// +12 semitones renders sample for sample as key 62 unbent, with `Bend range` 12, on a member
/// channel of an MPE zone (a quarter of its ±48), and on a channel whose earlier bent note was
/// let go. From 40 to 100 ms it sounds at key 62's pitch (within 1 %, against a swoop from an octave
/// below when the slide starts unbent and glides there).
#[test]
fn a_slide_note_bent_before_its_note_on_starts_at_its_bent_pitch() {
    let wide = Settings { bend_range: 12.0, ..Settings::default() };
    let plain = |key: u8| Event::NoteOn { channel: 2, key, velocity: 0.3 };
    let bend = |value: f32| Event::PitchBend { channel: 2, value };
    let rpn = |controller: u8, value: u8| Event::RegisteredParameter { channel: 0, controller, value };
    let mpe_zone = [rpn(101, 0), rpn(100, 6), rpn(6, 15)];
    let reference = play(&mut slide(wide), &vec![(0, plain(62))], 24_000, 256);
    let mut cases: Vec<(&str, Settings, Score)> = vec![
        ("bend range 12, bent +1", wide, vec![(0, bend(1.0)), (0, plain(50))]),
        ("an MPE member channel bent +0.25", Settings::default(), vec![(0, bend(0.25)), (0, plain(50))]),
    ];
    cases[1].2.splice(0..0, mpe_zone.iter().map(|&e| (0, e)));
    for (what, settings, score) in &cases {
        let bent = play(&mut slide(*settings), score, 24_000, 256);
        assert!(same(&bent, &reference), "{what}: key 50 bent +12 st differs from key 62");
        let early = pitch(&bent, 1_920, 4_800, key_frequency(62));
        println!("{what}: {early:.2} Hz over 40–100 ms (key 62: {:.2} Hz)", key_frequency(62));
        assert!((early / key_frequency(62) - 1.0).abs() < 0.01, "{what}: starts at {early} Hz");
    }
    // The channel's earlier note, bent, is let go; the next note on it keeps the channel's bend.
    let (first, again) = (24_000, 72_000);
    let score =
        vec![(0, bend(1.0)), (0, plain(50)), (first, Event::NoteOff { channel: 2, key: 50 }), (again, plain(50))];
    let reused = play(&mut slide(wide), &score, again + 4_800, 256);
    let early = pitch(&reused, again + 1_920, again + 4_800, key_frequency(62));
    println!("the channel's next note: {early:.2} Hz over 40–100 ms");
    assert!((early / key_frequency(62) - 1.0).abs() < 0.01, "the next note starts at {early} Hz");
}

/// An MPE controller hands the channel of a note let go to a later note, whose own bend it
/// sends before that note-on: the note let go, still ringing out, keeps its bend rather than
/// glide with the new note's. On a member channel of an MPE zone, key 50 bent +12 semitones is
/// let go at 0.2 s; 9 ms later, its finger's mute not yet complete, its channel is bent back to 0,
/// and a control block (of 64 samples) begins before key 57's note-on 0.8 ms after. The whole
/// renders as the bent note alone plus key 57 alone (to f32 rounding, as the other pairs here),
/// where a released note that followed its channel would swoop an octave down as it dies away
/// (an all-notes-off just after, which lets go of key 57, changes nothing for key 50). On
/// a channel outside any zone the note let go follows its channel, as under any synthesiser: the
/// same performance with a bend of +0.5 semitone there is not the sum of its notes (it differs by
/// more than a hundred times the rounding bound).
#[test]
fn a_note_let_go_keeps_its_bend_when_its_channel_plays_another_note() {
    let rpn = |controller: u8, value: u8| Event::RegisteredParameter { channel: 0, controller, value };
    let zone: Score = [rpn(101, 0), rpn(100, 6), rpn(6, 15)].iter().map(|&e| (0, e)).collect();
    let bend = |value: f32| Event::PitchBend { channel: 2, value };
    let first: Score = vec![(0, bend(0.25)), (0, on(2, 50, 1)), (9_600, Event::NoteOff { channel: 2, key: 50 })];
    let second: Score = vec![(10_040, bend(0.0)), (10_080, on(2, 57, 2)), (10_200, Event::AllNotesOff)];
    assert_eq!(Settings::default().block, 64, "a block begins at sample 10,048, between the bend and the note-on");
    let render = |zone: &Score, parts: &[&Score]| {
        let mut score = zone.clone();
        parts.iter().for_each(|part| score.extend(part.iter().copied()));
        score.sort_by_key(|e| e.0);
        play(&mut slide(Settings::default()), &score, 43_200, 256)
    };
    for (what, zone) in [("an MPE member channel", zone), ("a channel outside any zone", vec![])] {
        let (both, alone, next) =
            (render(&zone, &[&first, &second]), render(&zone, &[&first]), render(&zone, &[&second]));
        let ringing = peak(&alone[10_080..10_560]) / peak(&alone);
        println!("{what}: the note let go, 10-20 ms after its release: {ringing:.2e} of its peak");
        assert!(ringing > 1e-2, "{what}: the note let go still sounds when its channel is taken");
        let error = mixture_error(&both, &alone, &next);
        println!("{what}: the pair against the notes alone: {error:.2e} of the peak");
        if zone.is_empty() {
            assert!(error > 1e-4, "{what}: the note let go follows its channel ({error:e} of the peak)");
        } else {
            assert!(error < 1e-6, "{what}: the later note's bend reached the note let go ({error:e} of the peak)");
        }
    }
}

/// Polyphonic modulation offsets a setting for one note: with the slide at 5 semitones (not
/// following keys), +3 semitones for voice 22 at its note-on renders exactly as the setting at 8
/// for everyone (and sounds at 8 semitones above the open string); a hand-height offset of
/// +4.5 mm on −1.5 mm renders exactly as the hand at +3 mm (the slide lifted: another sound). The other note of the pair is untouched. (Both instruments are
/// made with the same settings, the reference's changed before its note, which starts after the
/// first control block: a voice made with other settings would rest elsewhere before its note.)
#[test]
fn poly_modulation_offsets_a_setting_for_one_note() {
    let fixed = Settings { follow_key: false, slide_position: 5.0, ..Default::default() };
    let cases = [
        (NoteParam::SlidePosition, 3.0f32, Settings { slide_position: 8.0, ..fixed }),
        (NoteParam::HandHeight, 4.5e-3, Settings { hand_height: fixed.hand_height + f64::from(4.5e-3f32), ..fixed }),
    ];
    for (param, offset, reference_settings) in cases {
        let mut changed = slide(fixed);
        changed.set_settings(&Settings { mode: Mode::Slide, ..reference_settings });
        let reference = play(&mut changed, &vec![(64, on(2, 60, 22))], 24_000, 256);
        let modulate = (64, Event::NoteModulation { note: NoteTarget::voice(22), param, offset });
        let modulated = play(&mut slide(fixed), &vec![(64, on(2, 60, 22)), modulate], 24_000, 256);
        assert!(same(&modulated, &reference), "{param:?} {offset}: differs from the setting moved by it");
        let note_1 = play(&mut slide(fixed), &vec![(64, on(1, 60, 11))], 24_000, 256);
        let both = play(&mut slide(fixed), &vec![(64, on(1, 60, 11)), (64, on(2, 60, 22)), modulate], 24_000, 256);
        let error = mixture_error(&both, &note_1, &modulated);
        println!("{param:?} +{offset}: pair vs note 1 + modulated note 2: {error:.2e} of the peak");
        assert!(error < 1e-6, "{param:?}: the modulation reached note 1 ({error:e} of the peak)");
    }
    // What the offsets do: the slide at 8 semitones sounds there; the lifted hand changes the
    // sound (by more than half its rms).
    let render = |settings| play(&mut slide(settings), &vec![(0, on(2, 60, 22))], 24_000, 256);
    let expected = 110.0 * 2f64.powf(8.0 / 12.0);
    let f = pitch(&render(cases[0].2), 7_200, 24_000, expected);
    let (pressed, lifted) = (render(fixed), render(cases[1].2));
    let rms = |x: &[f32]| (x.iter().map(|&v| f64::from(v).powi(2)).sum::<f64>() / x.len() as f64).sqrt();
    let diff: Vec<f32> = pressed.iter().zip(&lifted).map(|(a, b)| a - b).collect();
    let change = rms(&diff[7_200..]) / rms(&pressed[7_200..]);
    println!("slide at 5 + 3 st: {f:.2} Hz (expected {expected:.2}); hand lifted: {change:.2} of the rms changed");
    assert!((f / expected - 1.0).abs() < 0.01, "slide at 8 st: {f} Hz");
    assert!(change > 0.5, "lifting the hand changed only {change} of the rms");
}

/// A note's pressure expression (addressed by voice id) is its poly pressure: with the hand
/// height from poly pressure, it renders exactly as MIDI poly aftertouch on the note's channel and
/// key, and it presses that note's slide alone (the other note stays lifted, at the open string).
#[test]
fn a_pressure_expression_presses_only_its_note() {
    let settings = Settings { hand_source: HandSource::PolyPressure, ..Default::default() };
    let expression = (0, Event::NotePressure { note: NoteTarget::voice(22), value: 1.0 });
    let aftertouch = (0, Event::PolyPressure { channel: 2, key: 57, value: 1.0 });
    let pressed = play(&mut slide(settings), &vec![(0, on(2, 57, 22)), expression], 24_000, 256);
    let midi = play(&mut slide(settings), &vec![(0, on(2, 57, 22)), aftertouch], 24_000, 256);
    assert!(same(&pressed, &midi), "the pressure expression differs from poly aftertouch");
    presses_only_its_note(settings, &pressed, expression, "pressure");
}

/// A slide following keys that glides back to a key still held, when the key played over it is
/// let go, plays that key's note again with its id: the pressure expression sent to it before
/// (kept while the other note played) and the one sent to it after reach it, rendering exactly
/// as the same pressures sent as MIDI poly aftertouch; without them the slide lifts.
#[test]
fn a_note_returned_to_keeps_its_pressure_expressions() {
    let settings = Settings { hand_source: HandSource::PolyPressure, follow_key: true, ..Default::default() };
    let render = |score: &Score| play(&mut slide(settings), score, 28_800, 256);
    let played = |first: Event, second: Event, later: Event| -> Score {
        vec![
            (0, on(1, 45, 1)),
            (0, first),
            (4_800, on(1, 52, 2)),
            (4_800, second),
            (9_600, Event::NoteOff { channel: 1, key: 52 }),
            (19_200, later),
        ]
    };
    let expression = |id, value| Event::NotePressure { note: NoteTarget::voice(id), value };
    let aftertouch = |key, value| Event::PolyPressure { channel: 1, key, value };
    let by_id = render(&played(expression(1, 0.8), expression(2, 0.8), expression(1, 0.3)));
    let midi = render(&played(aftertouch(45, 0.8), aftertouch(52, 0.8), aftertouch(45, 0.3)));
    let first = by_id.iter().zip(&midi).position(|(a, b)| a.to_bits() != b.to_bits());
    assert_eq!(first, None, "the expressions differ from poly aftertouch from this sample on");
    let lifted = render(&played(expression(1, 0.8), expression(2, 0.8), expression(3, 0.3)));
    let rms = |x: &[f32]| (x.iter().map(|&v| f64::from(v).powi(2)).sum::<f64>() / x.len() as f64).sqrt();
    let diff: Vec<f32> = by_id[19_200..].iter().zip(&lifted[19_200..]).map(|(a, b)| a - b).collect();
    let change = rms(&diff) / rms(&by_id[19_200..]);
    println!("the later expression changes {change:.2} of the rms");
    assert!(change > 0.1, "the expression after the return changed only {change} of the rms");
}

/// A choke that names the note a slide following keys plays over a key still held fades that
/// voice out, as a choke does: silent (below 1e-6 of its peak) from 10 ms after it, rather than
/// gliding back to the held key and sounding on.
#[test]
fn a_choked_legato_note_falls_silent_rather_than_returning() {
    let settings = Settings { follow_key: true, ..Default::default() };
    let score: Score =
        vec![(0, on(1, 45, 1)), (4_800, on(1, 52, 2)), (9_600, Event::Choke { note: NoteTarget::voice(2) })];
    let out = play(&mut slide(settings), &score, 19_200, 256);
    let peak = out.iter().fold(0.0f32, |m, x| m.max(x.abs()));
    let after = out[9_600 + 480..].iter().fold(0.0f32, |m, x| m.max(x.abs()));
    println!("peak {peak:.3e}, after the choke {after:.3e}");
    assert!(peak > 1e-3 && after <= 1e-6 * peak, "{after:e} of a peak {peak:e} sounds on after the choke");
}

/// A choke by the id a held key was pressed with reaches the slide voice that glided back to
/// that key (following keys) when the key played over it was let go: the voice fades out,
/// silent (below 1e-6 of its peak) from 10 ms after the choke, instead of sounding on.
#[test]
fn a_choke_by_id_reaches_a_note_returned_to() {
    let settings = Settings { follow_key: true, ..Default::default() };
    let score: Score = vec![
        (0, on(1, 45, 1)),
        (4_800, on(1, 52, 2)),
        (9_600, Event::NoteOff { channel: 1, key: 52 }),
        (14_400, Event::Choke { note: NoteTarget::voice(1) }),
    ];
    let out = play(&mut slide(settings), &score, 24_000, 256);
    let peak = out.iter().fold(0.0f32, |m, x| m.max(x.abs()));
    let before = out[13_000..14_400].iter().fold(0.0f32, |m, x| m.max(x.abs()));
    let after = out[14_400 + 480..].iter().fold(0.0f32, |m, x| m.max(x.abs()));
    println!("peak {peak:.3e}, before the choke {before:.3e}, after {after:.3e}");
    assert!(before > 0.01 * peak, "the returned note sounds before the choke");
    assert!(after <= 1e-6 * peak, "{after:e} of a peak {peak:e} sounds on after the choke");
}

/// Note 2 (key 57, voice 22, channel 3) pressed by `expression` under `settings` renders as
/// `pressed`: with note 1 (key 50, voice 11, channel 2) the pair is the sum of the notes alone,
/// within 1e-6 of its peak; pressed, the note sounds at its key (220 Hz within 1 %), and
/// unpressed (the slide held 2 mm off) it is another sound altogether, more than half its rms
/// changed.
fn presses_only_its_note(settings: Settings, pressed: &[f32], expression: (usize, Event), what: &str) {
    let render = |score: &Score| play(&mut slide(settings), score, 24_000, 256);
    let note_1 = render(&vec![(0, on(1, 50, 11))]);
    let both = render(&vec![(0, on(1, 50, 11)), (0, on(2, 57, 22)), expression]);
    let error = mixture_error(&both, &note_1, pressed);
    let unpressed = render(&vec![(0, on(2, 57, 22))]);
    let f = pitch(pressed, 7_200, 24_000, 220.0);
    let rms = |x: &[f32]| (x.iter().map(|&v| f64::from(v).powi(2)).sum::<f64>() / x.len() as f64).sqrt();
    let diff: Vec<f32> = pressed.iter().zip(&unpressed).map(|(a, b)| a - b).collect();
    let change = rms(&diff[7_200..]) / rms(&pressed[7_200..]);
    println!(
        "{what}: note 2 at {f:.2} Hz (key 57: 220 Hz); unpressed differs by {change:.2} of its rms; pair error {error:.1e}"
    );
    assert!(error < 1e-6, "the {what} reached note 1 ({error:e} of the peak)");
    assert!((f / 220.0 - 1.0).abs() < 0.01, "pressed by its {what}: {f} Hz");
    assert!(change > 0.5, "{what} changed the note by only {change} of its rms");
}

/// A note's brightness expression is its own CC74: with the hand height from CC74, brightness
/// 1 on a note (addressed by voice id, then by channel and key) renders exactly as CC74 at 127 on
/// its channel, presses that note alone (the pair is the sum of the notes alone; the pressed note
/// sounds at its key), and stands for the channel's CC74 from then on: the channel's CC74 sent
/// later no longer reaches the note. Reset-all-controllers keeps both (CC74 is a sound
/// controller, which MIDI's RP-015 leaves alone): the note stays pressed.
#[test]
fn a_brightness_expression_is_its_notes_own_cc74() {
    let settings = Settings { hand_source: HandSource::Timbre, ..Default::default() };
    let render = |score: &Score| play(&mut slide(settings), score, 24_000, 256);
    let cc74 = |at: usize, value: f32| (at, Event::Timbre { channel: 2, value });
    let reset = (4_800, Event::ResetControllers { channel: 2 });
    let midi = render(&vec![(0, on(2, 57, 22)), cc74(0, 1.0)]);
    assert!(same(&render(&vec![(0, on(2, 57, 22)), cc74(0, 1.0), reset]), &midi), "reset-all-controllers kept CC74");
    for target in [NoteTarget::voice(22), NoteTarget::key(2, 57)] {
        let brightness = (0, Event::NoteBrightness { note: target, value: 1.0 });
        let pressed = render(&vec![(0, on(2, 57, 22)), brightness]);
        assert!(same(&pressed, &midi), "{target:?}: the brightness differs from the channel's CC74");
        let later = render(&vec![(0, on(2, 57, 22)), brightness, cc74(4_800, 0.0)]);
        assert!(same(&later, &midi), "{target:?}: the channel's CC74 reached a note with its own brightness");
        let kept = render(&vec![(0, on(2, 57, 22)), brightness, reset]);
        assert!(same(&kept, &midi), "{target:?}: reset-all-controllers kept the brightness");
    }
    let brightness = (0, Event::NoteBrightness { note: NoteTarget::voice(22), value: 1.0 });
    presses_only_its_note(settings, &midi, brightness, "brightness");
}

/// Host garbage is clamped, never played: NaN tuning and offsets are 0 (the note renders as with
/// none), infinite ones the largest value (finite samples), pressure, brightness and CC74 beyond
/// 0..=1 are clamped.
#[test]
fn non_finite_per_note_values_are_clamped() {
    let plain = play(&mut slide(Settings::default()), &vec![(0, on(2, 57, 22))], 9_600, 256);
    let target = NoteTarget::voice(22);
    let nan: Score = vec![
        (0, on(2, 57, 22)),
        (0, Event::NoteTuning { note: target, semitones: f32::NAN }),
        (0, Event::NoteModulation { note: target, param: NoteParam::SlidePosition, offset: f32::NAN }),
        (0, Event::NoteModulation { note: target, param: NoteParam::HandHeight, offset: f32::NAN }),
    ];
    assert!(same(&play(&mut slide(Settings::default()), &nan, 9_600, 256), &plain), "NaN is 0");
    for value in [f32::INFINITY, f32::NEG_INFINITY, 1e30, -1e30] {
        let score: Score = vec![
            (0, on(2, 57, 22)),
            (100, Event::NoteTuning { note: target, semitones: value }),
            (200, Event::NoteModulation { note: target, param: NoteParam::SlidePosition, offset: value }),
            (300, Event::NoteModulation { note: target, param: NoteParam::HandHeight, offset: value }),
            (400, Event::NotePressure { note: NoteTarget::default(), value }),
            (500, Event::NoteBrightness { note: NoteTarget::default(), value }),
            (600, Event::Timbre { channel: 2, value }),
        ];
        for hand_source in [HandSource::PolyPressure, HandSource::Timbre] {
            let settings = Settings { follow_key: false, hand_source, ..Default::default() };
            let out = play(&mut slide(settings), &score, 9_600, 256);
            assert!(out.iter().all(|v| v.is_finite()), "{value}, {hand_source:?}: non-finite output");
        }
    }
}

/// Per-note events take effect at their sample like other events, so host buffer sizes change
/// nothing: blocks of 1, 7, 64 and 4096 samples give the same samples.
#[test]
fn per_note_events_are_buffer_invariant() {
    let score: Score = vec![
        (0, on(1, 50, 11)),
        (0, on(2, 57, 22)),
        (1_000, Event::NoteTuning { note: NoteTarget::voice(22), semitones: 1.5 }),
        (3_333, Event::NoteModulation { note: NoteTarget::voice(11), param: NoteParam::HandHeight, offset: 1e-3 }),
        (5_000, Event::NotePressure { note: NoteTarget::key(1, 50), value: 0.7 }),
        (7_777, Event::NoteTuning { note: NoteTarget::key(1, 50), semitones: -2.0 }),
        (9_000, Event::NoteOff { channel: 2, key: 57 }),
    ];
    let reference = play(&mut slide(Settings::default()), &score, 14_400, 14_400);
    for chunk in [1usize, 7, 64, 4096] {
        assert!(same(&play(&mut slide(Settings::default()), &score, 14_400, chunk), &reference), "blocks of {chunk}");
    }
}

/// Every note's end is reported once, with its voice id, channel and key: a released slide note
/// when its string falls silent (its key let go after the key it glided from), a note whose voice
/// a legato glide takes over at once, a piano note struck again on its string at the new strike,
/// and a piano note let go by a velocity-0 note-on with its id, when its strings and the partners
/// on its bridge fall silent (within 3 s; not at the note-on, while they still ring), and a
/// velocity-0 note-on with an id no note has, at once.
#[test]
fn ended_notes_are_reported_once() {
    let mut s = slide(Settings::default());
    let score: Score = vec![
        (0, on(0, 50, 1)),
        (4_800, on(0, 55, 2)),
        (8_000, Event::NoteOff { channel: 0, key: 50 }),
        (9_000, Event::NoteOff { channel: 0, key: 55 }),
    ];
    let _ = play(&mut s, &score, 9_600, 256);
    let legato: Vec<_> = s.drain_ended().collect();
    assert_eq!(legato.len(), 1, "{legato:?}");
    assert_eq!((legato[0].note.voice, legato[0].note.key, legato[0].at), (Some(1), 50, 4_800));
    let _ = play(&mut s, &vec![], 4 * 48_000, 4096);
    let released: Vec<_> = s.drain_ended().collect();
    assert_eq!(released.len(), 1, "{released:?}");
    assert_eq!((released[0].note.voice, released[0].note.channel, released[0].note.key), (Some(2), 0, 55));
    println!("slide note released at 0.2 s reported ended at {:.3} s", released[0].at as f64 / FS);
    assert!(released[0].at > 9_000);
    assert_eq!(s.drain_ended().count(), 0, "nothing twice");

    let mut p = Instrument::new(FS, 4, Settings::default());
    let _ = play(&mut p, &vec![(0, on(0, 60, 7)), (2_400, on(0, 60, 8))], 4_800, 256);
    let restruck: Vec<_> = p.drain_ended().collect();
    assert_eq!(restruck.len(), 1, "{restruck:?}");
    assert_eq!((restruck[0].note.voice, restruck[0].at), (Some(7), 2_400));
    p.handle(Event::AllSoundOff);
    let silenced: Vec<_> = p.drain_ended().map(|e| e.note.voice).collect();
    assert_eq!(silenced, [Some(8)]);

    let mut p = Instrument::new(FS, 4, Settings::default());
    let off = |voice| Event::NoteOnWithId { channel: 0, key: 60, velocity: 0.0, voice };
    let _ = play(&mut p, &vec![(0, on(0, 60, 5)), (4_800, off(5)), (4_800, off(9))], 4_801, 256);
    let at_once: Vec<_> = p.drain_ended().map(|e| (e.note.voice, e.at)).collect();
    assert_eq!(at_once, [(Some(9), 4_800)], "only the note never played ends at its note-on");
    assert_eq!(p.sounding(), 1, "the note let go rings under its damper");
    let _ = play(&mut p, &vec![], 3 * 48_000, 4096);
    let damped: Vec<_> = p.drain_ended().map(|e| e.note.voice).collect();
    assert_eq!((damped, p.sounding()), (vec![Some(5)], 0), "the note let go ends once, when silent");
}

// Piano mode: a note's CC74 voices its hammer's felt.

/// A piano of 2 voices under `settings`.
fn piano(settings: Settings) -> Instrument {
    Instrument::new(FS, 2, Settings { mode: Mode::Piano, ..settings })
}

/// Share of `x`'s power above `from` (Hz), in dB, Hann-windowed.
fn upper_share_db(x: &[f32], from: f64) -> f64 {
    let n = x.len();
    let hann = |i: usize| 0.5 - 0.5 * (std::f64::consts::TAU * i as f64 / n as f64).cos();
    let mut buffer: Vec<Complex<f64>> =
        x.iter().enumerate().map(|(i, &v)| Complex::new(f64::from(v) * hann(i), 0.0)).collect();
    FftPlanner::new().plan_fft_forward(n).process(&mut buffer);
    let (mut upper, mut total) = (0.0, 0.0);
    for (k, c) in buffer.iter().take(n / 2 + 1).enumerate() {
        if k as f64 * FS / n as f64 >= from {
            upper += c.norm_sqr();
        }
        total += c.norm_sqr();
    }
    10.0 * (upper / total).log10()
}

/// CC74 on a piano note's channel before its note-on voices the hammer's felt exactly as the
/// `Hardness` setting does: CC 0, 32, 64, 96 and 127 sound as the hardness `2^((CC − 64)/32)`
/// (a quarter, a half, 1, 2 and 3.9) with no CC74, to f32 rounding of the output. The harder felt
/// is brighter: the share of C4's power above 2 kHz over its first 0.3 s rises by more than 2 dB
/// with each doubling of the felt's stiffness (measured 2.7 to 7.2 dB, 17.7 dB from CC 0 to 127:
/// a shorter contact reaches higher partials). A key struck on a
/// channel that never had CC74 keeps the setting; a hardness near the top of its range, pushed
/// further by CC74, stops at the range's top (10).
#[test]
fn a_piano_notes_cc74_voices_its_hammers_felt_as_the_hardness_setting_does() {
    let strike = |settings: Settings, score: Score| play(&mut piano(settings), &score, 14_400, 256);
    let note = (0, Event::NoteOn { channel: 3, key: 60, velocity: 0.5 });
    let cc74 = |value: f32| (0, Event::Timbre { channel: 3, value });
    let plain = strike(Settings::default(), vec![note]);
    let mut uppers = Vec::new();
    for cc in [0u8, 32, 64, 96, 127] {
        let voiced = strike(Settings::default(), vec![cc74(f32::from(cc) / 127.0), note]);
        let hardness = 2f64.powf((f64::from(cc) - 64.0) / 32.0);
        let reference = strike(Settings { hardness, ..Default::default() }, vec![note]);
        let error = mixture_error(&voiced, &reference, &vec![0.0; reference.len()]);
        uppers.push(upper_share_db(&voiced, 2_000.0));
        println!(
            "CC74 {cc:3}: hardness {hardness:.3}, error {error:.1e}, above 2 kHz {:.1} dB",
            uppers.last().unwrap()
        );
        assert!(error < 1e-6, "CC74 {cc} differs from the hardness {hardness} by {error:.1e} of the peak");
        if cc != 64 {
            assert!(mixture_error(&voiced, &plain, &vec![0.0; plain.len()]) > 1e-3, "CC74 {cc} changed nothing");
        }
    }
    assert!(uppers.windows(2).all(|w| w[1] > w[0] + 2.0), "the upper partials do not rise with CC74: {uppers:?}");
    let other_channel = strike(Settings::default(), vec![(0, Event::Timbre { channel: 4, value: 1.0 }), note]);
    assert!(same(&other_channel, &plain), "another channel's CC74 reached the note");
    let top = Settings { hardness: 8.0, ..Default::default() };
    let clamped = strike(top, vec![cc74(1.0), note]);
    let at_top = strike(Settings { hardness: 10.0, ..Default::default() }, vec![note]);
    assert!(mixture_error(&clamped, &at_top, &vec![0.0; at_top.len()]) < 1e-6, "hardness 8 at CC74 127 is not 10");
}

/// A piano note's brightness sent with its note-on (the same sample, as hosts send a note's
/// expressions) voices its felt exactly as its channel's CC74 before the note-on would, on a free
/// voice, on a voice struck again and on a voice stolen (the strike waiting for the steal's
/// fade), under each solver (the felt fitted twice in one sample is fitted once); so does the
/// channel's CC74 sent just after the note-on, unless the note has a brightness of its own. Sent
/// a sample later, once the hammer has been thrown, either leaves the note as it was; the
/// channel's next note takes the CC74, and a stolen note fading out, its hammer still on the
/// strings (its successor choked at once), keeps its felt. A NaN brightness voices nothing, and
/// a NaN CC74 is none. Host buffers of any size give the same samples.
#[test]
fn a_piano_notes_brightness_at_its_note_on_voices_its_felt_and_later_changes_nothing() {
    let on_at = |at: usize, key: u8, voice: i32| (at, Event::NoteOnWithId { channel: 3, key, velocity: 0.5, voice });
    let bright = |at: usize, voice: i32| (at, Event::NoteBrightness { note: NoteTarget::voice(voice), value: 0.9 });
    let cc74 = |at: usize| (at, Event::Timbre { channel: 3, value: 0.9 });
    for method in [Method::Qsa, Method::Exp, Method::Imp] {
        let settings = Settings { method, ..Default::default() };
        let strike = |score: &Score, chunk: usize| play(&mut piano(settings), score, 9_600, chunk);
        // A free voice; the same key struck again; a third key stealing one of the two voices.
        let scores: [(Score, Score); 3] = [
            (vec![on_at(0, 60, 1), bright(0, 1)], vec![cc74(0), on_at(0, 60, 1)]),
            (
                vec![on_at(0, 60, 1), on_at(2_400, 60, 2), bright(2_400, 2)],
                vec![on_at(0, 60, 1), cc74(2_400), on_at(2_400, 60, 2)],
            ),
            (
                vec![on_at(0, 60, 1), on_at(10, 64, 2), on_at(2_400, 67, 3), bright(2_400, 3)],
                vec![on_at(0, 60, 1), on_at(10, 64, 2), cc74(2_400), on_at(2_400, 67, 3)],
            ),
        ];
        for (case, (expression, midi)) in scores.iter().enumerate() {
            let reference = strike(midi, 256);
            for chunk in [1, 7, 64, 4096] {
                let voiced = strike(expression, chunk);
                assert!(same(&voiced, &reference), "{method:?}, case {case}, chunks of {chunk}: not its CC74");
            }
            let by_brightness = |e: &(usize, Event)| matches!(e.1, Event::NoteBrightness { .. });
            let plain: Score = expression.iter().copied().filter(|e| !by_brightness(e)).collect();
            assert!(!same(&reference, &strike(&plain, 256)), "{method:?}, case {case}: the brightness did nothing");
            // The channel's CC74 just after the note-on counts as well, but not over the note's own.
            let after: Score = plain.iter().copied().chain([cc74(plain.last().unwrap().0)]).collect();
            assert!(same(&strike(&after, 256), &reference), "{method:?}, case {case}: CC74 after the note-on");
            let darker = (plain.last().unwrap().0, Event::Timbre { channel: 3, value: 0.1 });
            let both: Score = expression.iter().copied().chain([darker]).collect();
            assert!(same(&strike(&both, 256), &reference), "{method:?}, case {case}: CC74 over the brightness");
        }
    }
    let strike = |score: &Score| play(&mut piano(Settings::default()), score, 9_600, 256);
    let plain = strike(&vec![on_at(0, 60, 1)]);
    assert!(same(&strike(&vec![on_at(0, 60, 1), bright(1, 1)]), &plain), "a brightness after the strike");
    assert!(same(&strike(&vec![on_at(0, 60, 1), cc74(1)]), &plain), "CC74 after the strike");
    let next = strike(&vec![on_at(0, 60, 1), cc74(1), on_at(2_400, 60, 2)]);
    let voiced = strike(&vec![on_at(0, 60, 1), cc74(2_400), on_at(2_400, 60, 2)]);
    assert!(same(&next, &voiced), "the next strike did not take the CC74 sent during the note before it");
    let nan_brightness = (0, Event::NoteBrightness { note: NoteTarget::voice(1), value: f32::NAN });
    assert!(same(&strike(&vec![on_at(0, 60, 1), nan_brightness]), &plain), "a NaN brightness voiced the felt");
    let nan_cc74 = (0, Event::Timbre { channel: 3, value: f32::NAN });
    assert!(same(&strike(&vec![cc74(0), nan_cc74, on_at(0, 60, 1)]), &plain), "a NaN CC74 is none");
    assert!(same(&strike(&vec![cc74(0), on_at(0, 60, 1), nan_cc74]), &plain), "a NaN CC74 after the note-on");
    // A note stealing a voice whose hammer still touches its strings, and choked at once, leaves
    // the stolen note fading with its felt.
    let choked: Score =
        vec![on_at(0, 60, 1), on_at(10, 64, 2), on_at(20, 67, 3), (20, Event::Choke { note: NoteTarget::voice(3) })];
    let with_cc74: Score = choked.iter().copied().chain([cc74(20)]).collect();
    assert!(same(&strike(&with_cc74), &strike(&choked)), "CC74 re-voiced a stolen note's thrown hammer");
}

/// An MPE zone's master channel speaks for its members' hammers as for their slides: CC74 on
/// channel 1, with a lower zone set up (RPN 6 on channel 1), voices the felt of a note on member
/// channel 3 exactly as the member's own CC74 does, sent before the note-on, just after it, or
/// while the note waits for a stolen voice's fade (a pool of two voices); without a zone,
/// channel 1's CC74 leaves the note alone.
#[test]
fn an_mpe_zones_master_cc74_voices_its_members_hammers() {
    let zone: Score = [(101, 0), (100, 6), (6, 3)]
        .map(|(controller, value)| (0, Event::RegisteredParameter { channel: 0, controller, value }))
        .to_vec();
    let cc74 = |at, channel| (at, Event::Timbre { channel, value: 0.9 });
    let strike = |score: Score| play(&mut piano(Settings::default()), &score, 9_600, 256);
    // A free voice, and a third note stealing one of two (C4 and E4 on channel 5, outside the
    // zone of channels 2 to 4).
    let earlier = vec![
        (0, Event::NoteOn { channel: 4, key: 60, velocity: 0.5 }),
        (10, Event::NoteOn { channel: 4, key: 64, velocity: 0.5 }),
    ];
    for (at, before) in [(0, vec![]), (2_400, earlier)] {
        let note = (at, Event::NoteOn { channel: 2, key: 67, velocity: 0.5 });
        let with = |events: Vec<(usize, Event)>| strike([zone.clone(), before.clone(), events].concat());
        let own = with(vec![cc74(at, 2), note]);
        assert!(same(&with(vec![cc74(at, 0), note]), &own), "at {at}: the master's CC74 before the note-on");
        assert!(same(&with(vec![note, cc74(at, 0)]), &own), "at {at}: the master's CC74 after the note-on");
        assert!(!same(&own, &with(vec![note])), "at {at}: the member's CC74 did nothing");
    }
    let note = (0, Event::NoteOn { channel: 2, key: 67, velocity: 0.5 });
    assert!(same(&strike(vec![cc74(0, 0), note]), &strike(vec![note])), "without a zone, channel 1 speaks for itself");
}
