//! The bundled CLAP plugin in a real host: clack-host loads `target/bundled/QSA Strings.clap`,
//! instantiates, activates and processes it on an audio thread, exactly as a DAW would.
//!
//! - The host sees an instrument: no audio input, one stereo output, a note input in the CLAP and
//!   MIDI dialects, and the documented parameters ([`parameters_have_the_documented_ids`]).
//! - Every factory preset survives saving and loading into a fresh instance: parameters, the
//!   persistent preset id and the samples ([`every_preset_survives_save_and_load_into_a_fresh_instance`]).
//! - Notes sound at their pitch in both modes; host buffer sizes never change a sample;
//!   automating `Slide position` moves the pitch as the speaking length says.
//! - Per note: CLAP tuning, pressure and brightness expressions and polyphonic modulation of
//!   `Slide position` and `Hand height` change the addressed note and leave the other one alone;
//!   every note's end comes back as a note-end event. The parameters come in the editor's groups
//!   (CLAP modules), and the choice parameters name every value.
//! - Bad input (non-finite and out-of-range parameter values, 10,000 random MIDI events in one
//!   block, every channel, extreme keys, velocity 0, stray note-offs, sample rates 22.05 to
//!   192 kHz, blocks of 1 to 8192 samples, garbage state) never panics, never gives NaN, and
//!   garbage state is refused with the previous state kept.
//! - The same notes and random events run against the debug bundle built with
//!   `assert_process_allocs` (`target/bundled-debug/`), in a child process so that an abort
//!   (an allocation in `process`) shows as a failing test with the child's output.
//!
//! The bundles are built by `cargo xtask bundle qsa-plugin --release` (and `.ci/run`); a missing
//! or stale bundle fails the tests with that instruction. The host harness is shared with
//! `host_fuzz.rs` (`support/host.rs`).

use std::ffi::CString;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use clack_extensions::audio_ports::{AudioPortInfoBuffer, PluginAudioPorts};
use clack_extensions::note_ports::{NoteDialect, NotePortInfoBuffer, PluginNotePorts};
use clack_extensions::params::{ParamInfoBuffer, ParamInfoFlags};
use clack_host::prelude::*;
use qsa_dsp::instrument::{CEILING, Settings, pan_gains};
use qsa_tests::{fundamental, seeded_rng, spectral_peak};
use rand::RngExt;

#[path = "support/bundle.rs"]
mod bundle;
#[path = "support/host.rs"]
mod host;
use bundle::{checked_bundle, target_dir};
use host::{Audio, Ev, Expression, PARAMETERS, Plugin, Score, Target, clap_id, param, release_bundle};

// ------------------------------------------------------------------------------------------------
// Bundles
// ------------------------------------------------------------------------------------------------

/// Environment variable naming the bundle the ignored child test runs against.
const CHILD_BUNDLE_ENV: &str = "QSA_HOST_TEST_BUNDLE";

/// Set to run the tests without the allocation-checked bundle (its test then only notes that it
/// is missing); unset, a missing bundle fails the test, as in `cargo xtask test`.
const SKIP_DEBUG_ENV: &str = "QSA_SKIP_DEBUG_BUNDLE";

/// How `cargo xtask test` builds the allocation-checked bundle: in the test profile, whose debug
/// assertions arm nice-plug's check (both bundles land in `target/bundled/` first).
const BUILD_DEBUG: &str = "cargo xtask bundle qsa-plugin --profile test-release --features assert_process_allocs \
                           && rm -rf target/bundled-debug && cp -r target/bundled target/bundled-debug \
                           && cargo xtask bundle qsa-plugin --release";

/// Where `.ci/run` copies the debug `assert_process_allocs` bundle.
fn debug_bundle_path() -> PathBuf {
    target_dir().join("bundled-debug/QSA Strings.clap")
}

/// The CLAP value of `Slide position` `p` semitones (a linear 0..=24 st range).
fn slide_value(p: f64) -> f64 {
    p / 24.0
}

// ------------------------------------------------------------------------------------------------
// Measurements
// ------------------------------------------------------------------------------------------------

/// Equal-tempered frequency of a MIDI key (A4 = 440 Hz), written out here so that the expected
/// pitches do not come from the code under test.
fn key_hz(key: u8) -> f64 {
    440.0 * 2f64.powf((f64::from(key) - 69.0) / 12.0)
}

/// Relative pitch error tolerated: 1 %, the instrument's requirement (a sixth of a semitone). The
/// estimators are far finer: the spectral peak resolves a small fraction of a 2–4 Hz bin, the
/// autocorrelation peak is refined by a parabola to about 0.05 % at these lags.
const PITCH_TOLERANCE: f64 = 0.01;

/// "Not silent": a peak above −60 dBFS. A mezzo-forte note peaks between 0.01 and 0.5 of full
/// scale (the engine's output scales put a fortissimo C4 near 0.5); silence is exactly 0.
const AUDIBLE: f32 = 1e-3;

/// Piano pitch: the first partial, the largest spectral peak within ±10 % of the key's frequency,
/// from 50 ms on (after the hammer). The stiff string's first partial is f0·√(1 + B), at most
/// 0.1 % sharp for these keys.
fn piano_pitch(audio: &Audio, fs: f64, key: u8) -> f64 {
    let expected = key_hz(key);
    spectral_peak(&audio.tail((0.05 * fs) as usize), fs, 0.9 * expected, 1.1 * expected)
}

/// Slide pitch: the period by autocorrelation, searched within ±20 % of `expected`, from
/// `from_s` seconds on. (The slide rides on the hand spring, which pulls the first partial about
/// 1 % sharp while the harmonic series keeps the speaking length's spacing: the period, like the
/// ear, follows the series; see `tests/tests/instrument.rs`.)
fn slide_pitch(signal: &[f64], fs: f64, expected: f64) -> f64 {
    fundamental(signal, fs, 0.8 * expected, 1.2 * expected)
}

fn assert_pitch(measured: f64, expected: f64, what: &str) {
    println!("{what}: {measured:.3} Hz (expected {expected:.3} Hz, {:+.3} %)", 100.0 * (measured / expected - 1.0));
    assert!(
        (measured / expected - 1.0).abs() < PITCH_TOLERANCE,
        "{what}: {measured} Hz, expected {expected} Hz within 1 %"
    );
}

/// The safety limiter's ceiling (−0.1 dBFS, [`CEILING`]) as the f32 the host receives: with the
/// limiter on no sample may exceed it, whatever the gain and the notes (the limiter clamps every
/// frame to it, then rounds to f32).
const LIMITER_CEILING: f32 = CEILING as f32;

/// The largest magnitude one note may reach with the limiter off at 0 dB output gain: +12 dBFS
/// (×3.98), the bound `host_fuzz.rs` justifies and checks over thousands of parameter
/// permutations (one voice at the most energetic corner settings measured +4.8 dBFS; a runaway
/// of the physics goes far beyond).
const UNLIMITED_PEAK_PER_NOTE: f32 = 3.981_071_7;

/// `Output gain` at its minimum, −36 dB, as a linear factor.
const MIN_GAIN: f32 = 0.015_848_932;

fn bit_identical(a: &Audio, b: &Audio) -> Option<usize> {
    let (x, y) = (a.left.iter().chain(&a.right), b.left.iter().chain(&b.right));
    if a.left.len() != b.left.len() {
        return Some(0);
    }
    x.zip(y).position(|(p, q)| p.to_bits() != q.to_bits())
}

// ------------------------------------------------------------------------------------------------
// Core cases (also run against the debug assert_process_allocs bundle)
// ------------------------------------------------------------------------------------------------

const FS: f64 = 48_000.0;

/// Notes in both modes: finite, not silent, at their pitch; a piano key's two channels differ
/// by its pan gains alone (the soundboard of each channel is the same linear system).
fn core_notes(bundle: &Path) {
    for key in [36u8, 60, 84] {
        let mut p = Plugin::at_48k(bundle, &[]);
        let audio = p.render_blocks(&[(0, Ev::On(0, key, 0.7)), (19_200, Ev::Off(0, key))], 24_000, 512);
        audio.assert_finite("piano");
        assert!(audio.peak() > AUDIBLE, "piano key {key} is silent: peak {}", audio.peak());
        let rms = |x: &[f32]| x.iter().map(|&v| f64::from(v) * f64::from(v)).sum::<f64>().sqrt();
        let [gl, gr] = pan_gains(key, Settings::default().stereo_width);
        let (got, want) = (20.0 * (rms(&audio.left) / rms(&audio.right)).log10(), 20.0 * (gl / gr).log10());
        assert!((got - want).abs() < 0.01, "piano key {key}: left over right {got} dB, the pan law's {want} dB");
        assert_pitch(piano_pitch(&audio, FS, key), key_hz(key), &format!("piano key {key}, peak {:.3}", audio.peak()));
    }
    for key in [52u8, 57, 64] {
        let mut p = Plugin::at_48k(bundle, &[param("mode", 1.0)]);
        let audio = p.render_blocks(&[(0, Ev::On(0, key, 0.8))], 24_000, 512);
        audio.assert_finite("slide");
        assert!(audio.peak() > AUDIBLE, "slide key {key} is silent: peak {}", audio.peak());
        let f = slide_pitch(&audio.tail(7_200), FS, key_hz(key));
        assert_pitch(f, key_hz(key), &format!("slide key {key}, peak {:.3}", audio.peak()));
    }
}

/// 10,000 random MIDI and note events in one 8192-sample block (every status byte, data bytes
/// beyond 127, all channels, keys 0..=127, velocity 0, stray note-offs, CLAP note-offs and chokes
/// with wildcards, pedals, all-notes-off), in both modes: every sample finite, and CC120 (all
/// sound off) afterwards gives exact silence, so the instrument is still under control.
fn core_random_events(bundle: &Path) {
    for (mode, seed) in [(0.0, 11u64), (1.0, 12)] {
        let mut p = Plugin::at_48k(bundle, &[param("mode", mode)]);
        let score = random_events(seed, 10_000, 8192);
        let start = Instant::now();
        let garbage = p.render_blocks(&score, 8192, 8192);
        let after = p.render_blocks(&[], 3 * 8192, 8192);
        println!("mode {mode}: 10,000 events + 0.68 s rendered in {:.2} s", start.elapsed().as_secs_f64());
        garbage.assert_finite("the block with 10,000 random events");
        after.assert_finite("after 10,000 random events");
        assert!(garbage.peak() > AUDIBLE, "the random notes sound (peak {})", garbage.peak());
        let silenced = p.render_blocks(&[(0, Ev::Midi([0xB0, 120, 0]))], 4096, 4096);
        assert_eq!(silenced.peak(), 0.0, "all sound off after the random events");
    }
}

/// `count` random events at random times in `0..samples`, time-ordered.
fn random_events(seed: u64, count: usize, samples: usize) -> Score {
    let mut rng = seeded_rng(seed);
    let mut score: Score = (0..count)
        .map(|_| {
            let t = rng.random_range(0..samples);
            let ch = rng.random_range(0..16u8);
            let (a, b) = (rng.random_range(0..=127u8), rng.random_range(0..=127u8));
            let ev = match rng.random_range(0..14) {
                0..=2 => Ev::Midi([0x90 | ch, a, [0, b][rng.random_range(0..2)]]),
                3 => Ev::Midi([0x80 | ch, a, b]),
                4 => Ev::Midi([0xB0 | ch, [1, 64, 120, 123, a][rng.random_range(0..5)], b]),
                5 => Ev::Midi([0xE0 | ch, a, b]),
                6 => Ev::Midi([0xD0 | ch, a, 0]),
                7 => Ev::Midi([0xA0 | ch, a, b]),
                8 => Ev::Midi([rng.random(), rng.random(), rng.random()]),
                9 => Ev::On(
                    ch,
                    [0, 127, a][rng.random_range(0..3)],
                    [0.0, 1.0, f64::NAN, rng.random_range(0.0..1.0)][rng.random_range(0..4)],
                ),
                10 => Ev::Off(ch, a),
                11 | 12 => {
                    let target = Target {
                        note_id: rng.random_bool(0.2).then(|| rng.random_range(0..4)),
                        channel: rng.random_bool(0.6).then_some(ch),
                        key: rng.random_bool(0.6).then_some(a),
                    };
                    if rng.random_bool(0.5) { Ev::OffAt(target) } else { Ev::Choke(target) }
                }
                _ => Ev::On(ch, a, rng.random_range(0.0..1.0)),
            };
            (t, ev)
        })
        .collect();
    score.sort_by_key(|e| e.0);
    score
}

#[test]
fn notes_sound_at_their_pitch_in_both_modes() {
    core_notes(&release_bundle());
}

#[test]
fn random_midi_flood_is_safe() {
    core_random_events(&release_bundle());
}

/// Run by [`debug_bundle_does_not_allocate_in_process`] in a child process, against the bundle
/// named by `QSA_HOST_TEST_BUNDLE`.
#[test]
#[ignore = "run in a child process by debug_bundle_does_not_allocate_in_process"]
fn debug_bundle_child() {
    let bundle = PathBuf::from(std::env::var_os(CHILD_BUNDLE_ENV).expect("QSA_HOST_TEST_BUNDLE names the bundle"));
    let start = Instant::now();
    core_notes(&bundle);
    core_random_events(&bundle);
    println!("debug bundle core cases: {:.1} s", start.elapsed().as_secs_f64());
}

/// The debug bundle built with `assert_process_allocs` aborts the host on any allocation in
/// `process`. The core cases run against it in a child process (this test binary, re-invoked
/// on the ignored [`debug_bundle_child`]); an abort fails here with the child's output. The
/// framework lets its input-event queue grow on the audio thread (a permitted allocation it
/// logs as "Input event buffer filled up"), which the child's log must not show either.
#[test]
fn debug_bundle_does_not_allocate_in_process() {
    let path = debug_bundle_path();
    if !path.is_file() {
        let message = format!(
            "the debug assert_process_allocs bundle {} is missing: build it with `{BUILD_DEBUG}` (`cargo xtask \
             test` does), or set {SKIP_DEBUG_ENV}=1 to leave the allocation check out",
            path.display()
        );
        assert!(std::env::var_os(SKIP_DEBUG_ENV).is_some(), "{message}");
        eprintln!("NOTE: {message}; {SKIP_DEBUG_ENV} is set: skipping the allocation check");
        return;
    }
    let path = checked_bundle(path, BUILD_DEBUG);
    let start = Instant::now();
    let output = Command::new(std::env::current_exe().expect("test binary"))
        .args(["--ignored", "--exact", "debug_bundle_child", "--nocapture", "--test-threads=1"])
        .env(CHILD_BUNDLE_ENV, &path)
        .env("NICE_LOG", "stderr")
        .output()
        .expect("run the child test");
    let (stdout, stderr) = (String::from_utf8_lossy(&output.stdout), String::from_utf8_lossy(&output.stderr));
    println!("child ran {:.1} s\n{stdout}", start.elapsed().as_secs_f64());
    assert!(
        output.status.success(),
        "the host aborted or failed with the debug assert_process_allocs bundle ({}). \"memory allocation of N \
         bytes failed\" means `process` allocated; `gdb -batch -ex run -ex bt --args {} --ignored --exact \
         debug_bundle_child` with {CHILD_BUNDLE_ENV}={} shows where.\n--- stdout\n{stdout}\n--- stderr\n{stderr}",
        output.status,
        std::env::current_exe().map(|p| p.display().to_string()).unwrap_or_default(),
        path.display(),
    );
    assert!(stdout.contains("1 passed"), "the child test did not run:\n{stdout}");
    let grown = stderr.lines().filter(|l| l.contains("Input event buffer filled up")).count();
    assert_eq!(
        grown, 0,
        "nice-plug's input event queue grew on the audio thread (an allocation in process, permitted by the \
         framework) {grown} times; the plugin's INPUT_EVENT_CAPACITY must hold 10,000 events"
    );
}

// ------------------------------------------------------------------------------------------------
// Parameters
// ------------------------------------------------------------------------------------------------

/// The host's view of the plugin: an instrument (no audio input, one stereo main output, one note
/// input taking CLAP notes and MIDI), and exactly the documented parameters.
///
/// What is checkable about the ids: CLAP ids are numbers, hashed from the string ids, so the test
/// checks that the plugin's ids are exactly the hashes of the documented string ids (a renamed or
/// missing id changes the set), with the documented names and step counts. Values: the documented
/// defaults read back; set-by-id (a parameter event) and get-by-id agree; the plugin's own text
/// conversion maps the documented ranges (`Slide position` 0..=24 st, `Hand height` −3..=3 mm,
/// enum names); an unknown id is refused.
#[test]
fn parameters_have_the_documented_ids() {
    let mut p = Plugin::at_48k(&release_bundle(), &[]);
    let handle = p.instance.plugin_handle();
    let ports: PluginAudioPorts = handle.get_extension().expect("audio-ports extension");
    assert_eq!(ports.count(&handle, true), 0, "audio inputs");
    assert_eq!(ports.count(&handle, false), 1, "audio outputs");
    let mut port_buffer = AudioPortInfoBuffer::new();
    let out = ports.get(&handle, 0, false, &mut port_buffer).expect("output port info");
    assert_eq!(out.channel_count, 2, "stereo output");
    let notes: PluginNotePorts = handle.get_extension().expect("note-ports extension");
    assert_eq!((notes.count(&handle, true), notes.count(&handle, false)), (1, 0), "note ports in, out");
    let mut note_buffer = NotePortInfoBuffer::new();
    let note_port = notes.get(&handle, 0, true, &mut note_buffer).expect("note port info");
    assert!(note_port.supported_dialects.supports(NoteDialect::Clap), "CLAP note events");
    assert!(note_port.supported_dialects.supports(NoteDialect::Midi), "MIDI events");

    let params = p.params();
    let handle = p.instance.plugin_handle();
    let count = params.count(&handle);
    let mut listed = Vec::new();
    for index in 0..count {
        let mut buffer = ParamInfoBuffer::new();
        let info = params.get_info(&handle, index, &mut buffer).expect("param info");
        listed.push((
            info.id.get(),
            String::from_utf8_lossy(info.name).into_owned(),
            info.flags.contains(ParamInfoFlags::IS_STEPPED),
            info.min_value,
            info.max_value,
            info.default_value,
        ));
    }
    println!("{count} parameters:");
    for (id, name, stepped, min, max, default) in &listed {
        println!("  {id:>10}  {name:<20} stepped {stepped:<5} {min}..={max} default {default}");
    }
    assert_eq!(count as usize, PARAMETERS.len(), "parameter count");
    for (id, name, steps) in PARAMETERS {
        let hash = clap_id(id);
        let Some(info) = listed.iter().find(|l| l.0 == hash) else { panic!("no parameter with the id of {id:?}") };
        assert_eq!(info.1, name, "name of {id:?}");
        assert_eq!(info.2, steps.is_some(), "{id:?} stepped");
        assert_eq!((info.3, info.4), (0.0, f64::from(steps.unwrap_or(1))), "CLAP range of {id:?}");
        assert_eq!(params.get_value(&handle, ClapId::new(hash)), Some(info.5), "{id:?} starts at its default");
    }
    let unknown = (1..).find(|i| !listed.iter().any(|l| l.0 == *i)).expect("a free id");
    assert_eq!(params.get_value(&handle, ClapId::new(unknown)), None, "an unknown id is refused");

    // Documented defaults and ranges, through the plugin's own conversions.
    let text = |id: &str, value: f64| {
        let mut buffer = [0u8; 64];
        let t = params.value_to_text(&handle, ClapId::new(clap_id(id)), value, &mut buffer).expect("value_to_text");
        String::from_utf8_lossy(t).into_owned()
    };
    let parse = |id: &str, text: &str| {
        params.text_to_value(&handle, ClapId::new(clap_id(id)), &CString::new(text).expect("text"))
    };
    let defaults: Vec<(&str, String)> = PARAMETERS
        .iter()
        .map(|(id, ..)| (*id, text(id, params.get_value(&handle, ClapId::new(clap_id(id))).expect("value"))))
        .collect();
    println!("defaults: {defaults:?}");
    let default = |id: &str| defaults.iter().find(|d| d.0 == id).map(|d| d.1.clone()).expect("listed");
    assert_eq!(default("mode"), "Piano");
    assert_eq!(default("solver"), "QSA");
    assert_eq!(default("slide"), "5.00 st");
    assert_eq!(default("voices"), "32");
    assert_eq!(text("mode", 1.0), "Slide");
    assert_eq!(text("solver", 2.0), "IMP");
    assert_eq!(text("slide", 1.0), "24.00 st", "Slide position tops out at two octaves");
    assert_eq!(text("hand", 0.0), "-3.00 mm");
    let twelve = parse("slide", "12").expect("parse 12 st");
    assert!((twelve - 0.5).abs() < 1e-6, "12 st is half the 0..=24 range: {twelve}");
    let level = parse("hand", "0").expect("parse 0 mm");
    assert!((level - 0.5).abs() < 1e-6, "0 mm is the middle of −3..=3 mm: {level}");

    // Set by id (an automation event), get by id.
    let _ = p.render_blocks(&[(0, param("slide", slide_value(7.0))), (10, param("mode", 1.0))], 64, 64);
    let slide = p.value(clap_id("slide")).expect("slide value");
    assert!((slide - slide_value(7.0)).abs() < 1e-6, "slide reads back {slide}");
    assert_eq!(p.value(clap_id("mode")), Some(1.0), "mode reads back Slide");
}

// ------------------------------------------------------------------------------------------------
// Host buffers and automation
// ------------------------------------------------------------------------------------------------

/// A phrase over both modes: notes, pedal, pitch bend, mod wheel and parameter automation at
/// fixed sample times (some landing inside a control block); the slide on the acoustic guitar,
/// whose stereo width moves while it sounds.
fn phrase() -> Score {
    vec![
        (0, Ev::On(0, 60, 0.7)),
        (700, param("hard", 0.8)),
        (1_000, Ev::Midi([0x90, 64, 90])),
        (2_345, Ev::Midi([0xB0, 64, 127])),
        (3_000, param("bright", 0.25)),
        (5_000, Ev::Off(0, 60)),
        (6_001, Ev::Midi([0xB0, 64, 0])),
        (7_777, Ev::On(0, 67, 0.9)),
        (9_000, param("mode", 1.0)),
        (9_000, param("follow", 0.0)),
        (9_000, param("slide", slide_value(3.0))),
        (9_000, param("sbody", 1.0)),
        (9_500, Ev::On(1, 50, 0.8)),
        (11_111, Ev::Midi([0xE1, 0, 80])),
        (11_500, param("width", 0.1)),
        (12_000, param("slide", slide_value(5.5))),
        (13_000, Ev::Midi([0xB1, 1, 70])),
        (14_000, Ev::Off(1, 50)),
        (15_000, param("mode", 0.0)),
        (15_500, Ev::On(2, 72, 0.5)),
    ]
}

/// Host buffer sizes never change the output: blocks of 1, 32 and 512 samples and seeded random
/// sizes (1..=700) give bit-identical samples to one 8192-sample block at a time, with the events
/// at the same absolute sample times.
#[test]
fn host_block_sizes_give_identical_samples() {
    let bundle = release_bundle();
    let (score, samples) = (phrase(), 19_200);
    let reference = Plugin::at_48k(&bundle, &[]).render_blocks(&score, samples, 8192);
    reference.assert_finite("reference");
    assert!(reference.peak() > AUDIBLE, "the phrase sounds");
    for block in [1usize, 32, 512] {
        let start = Instant::now();
        let audio = Plugin::at_48k(&bundle, &[]).render_blocks(&score, samples, block);
        println!("blocks of {block}: {:.2} s", start.elapsed().as_secs_f64());
        assert_eq!(bit_identical(&audio, &reference), None, "blocks of {block}: first differing sample");
    }
    let mut rng = seeded_rng(5);
    let audio = Plugin::at_48k(&bundle, &[]).render(&score, samples, move || rng.random_range(1..=700));
    assert_eq!(bit_identical(&audio, &reference), None, "random blocks: first differing sample");
}

/// A note struck in the sample its automation changes takes the new value through the plugin,
/// whichever of the two the host lists first: the mode switched to slide, and in piano mode the
/// hardness raised, each in the sample of a note at 1,000 (within a control block), render to
/// the bit as with the new value set at sample 0, and not as the old value does. (The framework
/// splits the buffer at the change; a note listed before it ends the first part.)
#[test]
fn a_note_struck_with_an_automation_step_takes_the_new_value() {
    let bundle = release_bundle();
    let samples = 9_600;
    for (id, old, new) in [("mode", 0.0, 1.0), ("hard", 0.3, 0.9)] {
        let render = |at: usize, value: f64, note_first: bool| {
            let (change, note) = ((at, param(id, value)), (1_000, Ev::On(0, 50, 0.8)));
            let score = if note_first && at == 1_000 {
                vec![(0, param(id, old)), note, change]
            } else {
                vec![(0, param(id, old)), change, note]
            };
            Plugin::at_48k(&bundle, &[]).render_blocks(&score, samples, 512)
        };
        let reference = render(0, new, false);
        assert!(reference.peak() > AUDIBLE, "{id}: the note sounds");
        for note_first in [false, true] {
            let listed = if note_first { "the note listed first" } else { "the change listed first" };
            let heard = render(1_000, new, note_first);
            assert_eq!(bit_identical(&heard, &reference), None, "{id}, {listed}: first differing sample");
            let other = render(1_000, old, note_first);
            assert!(bit_identical(&other, &reference).is_some(), "{id}, {listed}: the old value gives another note");
        }
    }
}

/// Blocks of every size from 1 to 8192 samples (a sequence mixing 1, primes, powers of two and
/// the maximum) give the same samples as 8192-sample blocks.
#[test]
fn extreme_block_sizes_change_nothing() {
    let bundle = release_bundle();
    let score = phrase();
    let samples = 3 * 8192;
    let reference = Plugin::at_48k(&bundle, &[]).render_blocks(&score, samples, 8192);
    let sizes = [1usize, 2, 3, 7, 13, 64, 127, 1000, 4096, 8192, 1, 8191, 256];
    let mut i = 0;
    let audio = Plugin::at_48k(&bundle, &[]).render(&score, samples, move || {
        i += 1;
        sizes[(i - 1) % sizes.len()]
    });
    audio.assert_finite("mixed block sizes");
    assert_eq!(bit_identical(&audio, &reference), None, "mixed block sizes: first differing sample");
}

/// Automating `Slide position` (not following keys) moves the pitch as the speaking length says:
/// the slide at `p` semitones above the open A2 string stops it at `L(1 − 2^(−p/12))`, so the
/// note sounds at `110 Hz · 2^(p/12)`. One note, the parameter automated from 2 to 9 semitones
/// at 0.45 s; the pitch is measured before (0.15–0.45 s) and after the glide has settled
/// (0.75–1.0 s: 6 glide time constants of 50 ms, leaving 0.02 semitones = 0.1 %).
#[test]
fn slide_position_automation_moves_the_pitch() {
    let bundle = release_bundle();
    let (p1, p2) = (2.0, 9.0);
    let setup = [param("mode", 1.0), param("follow", 0.0), param("slide", slide_value(p1))];
    let mut p = Plugin::at_48k(&bundle, &setup);
    let score = vec![(0, Ev::On(0, 60, 0.9)), ((0.45 * FS) as usize, param("slide", slide_value(p2)))];
    let audio = p.render_blocks(&score, (1.0 * FS) as usize, 256);
    audio.assert_finite("slide automation");
    let window = |a: f64, b: f64| {
        audio.left[(a * FS) as usize..(b * FS) as usize].iter().map(|&v| f64::from(v)).collect::<Vec<_>>()
    };
    let (before, after) = (window(0.15, 0.45), window(0.75, 1.0));
    let rms = |x: &[f64]| (x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64).sqrt();
    println!("rms before {:.4}, after {:.4}", rms(&before), rms(&after));
    assert!(rms(&after) > f64::from(AUDIBLE) * 0.1, "the note still sounds after the move");
    for (signal, p) in [(&before, p1), (&after, p2)] {
        let expected = 110.0 * 2f64.powf(p / 12.0);
        assert_pitch(slide_pitch(signal, FS, expected), expected, &format!("slide at {p} st"));
    }
}

// ------------------------------------------------------------------------------------------------
// Bad input
// ------------------------------------------------------------------------------------------------

/// Non-finite and out-of-range parameter values, for every parameter, while notes play in both
/// modes: no NaN. What the host reads back is concrete: a non-finite value is ignored (the
/// previous value stays), an out-of-range one is clamped to the CLAP range 0..=max. With every
/// parameter at its maximum (limiter on, +12 dB gain) two fortissimo notes stay at or below the
/// limiter's ceiling ([`LIMITER_CEILING`]); at its minimum (limiter off, −36 dB gain) within the
/// per-note bound of `host_fuzz.rs` for two notes at that gain (2 × [`UNLIMITED_PEAK_PER_NOTE`] ×
/// [`MIN_GAIN`]); in both cases they sound.
#[test]
fn non_finite_and_out_of_range_parameters_are_safe() {
    let bundle = release_bundle();
    let mut p = Plugin::at_48k(&bundle, &[]);
    let ids: Vec<(u32, f64)> =
        PARAMETERS.iter().map(|(id, _, steps)| (clap_id(id), f64::from(steps.unwrap_or(1)))).collect();
    let all = |value: f64| ids.iter().map(move |&(id, max)| Ev::Param(id, value * max));
    let mut score: Score = Vec::new();
    let mut t = 0;
    for value in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 1e30, -1e30, 1.5, -0.5, 0.0, 1.0, f64::NAN] {
        score.extend(all(value).map(|e| (t, e)));
        score.push((t, Ev::On(0, 48 + (t / 2400) as u8, 0.8)));
        t += 2400;
    }
    let audio = p.render_blocks(&score, t + 4800, 512);
    audio.assert_finite("non-finite and out-of-range parameters");
    // The last finite values were 1.0 × max (all at maximum); the trailing NaN changed nothing.
    for &(id, max) in &ids {
        assert_eq!(p.value(id), Some(max), "parameter {id} after NaN (last finite value: its maximum)");
    }
    // Out of range clamps.
    let _ = p.render_blocks(&all(-7.0).map(|e| (0, e)).collect::<Score>(), 64, 64);
    for &(id, _) in &ids {
        assert_eq!(p.value(id), Some(0.0), "parameter {id} after −7 × max");
    }
    let _ = p.render_blocks(&all(1e9).map(|e| (0, e)).collect::<Score>(), 64, 64);
    for &(id, max) in &ids {
        assert_eq!(p.value(id), Some(max), "parameter {id} after 1e9 × max");
    }
    // Every parameter at its extremes, in each mode (voices takes effect at activation): at the
    // maximum the limiter is on and the gain +12 dB, at the minimum the limiter is off and the
    // gain −36 dB.
    for extreme in [0.0, 1.0] {
        for mode in [0.0, 1.0] {
            let setup: Vec<Ev> = all(extreme).chain([param("mode", mode)]).collect();
            let mut q = Plugin::at_48k(&bundle, &setup);
            let score = vec![(0, Ev::On(0, 52, 1.0)), (100, Ev::On(0, 57, 0.5)), (9_000, Ev::Off(0, 52))];
            let audio = q.render_blocks(&score, 14_400, 1024);
            let what = format!("all parameters at {extreme}, mode {mode}");
            audio.assert_finite(&what);
            let bound = if extreme == 1.0 { LIMITER_CEILING } else { UNLIMITED_PEAK_PER_NOTE * 2.0 * MIN_GAIN };
            println!("{what}: peak {:.4} (bound {bound:.4})", audio.peak());
            assert!(audio.peak() > 0.0, "{what}: the notes sound");
            assert!(audio.peak() <= bound, "{what}: peak {} above {bound}", audio.peak());
        }
    }
}

/// Notes on all 16 channels sound the same as on channel 1 (only the channel's own pedal, bend
/// and pressure could differ, and none is set); a velocity-0 note-on (a note-off by MIDI's rule)
/// and note-offs without note-ons give exact silence. (Keys 0 and 127:
/// [`piano_keys_0_and_127_sound_at_the_rules_pitch_and_level`],
/// [`slide_keys_0_and_127_play_the_ends_of_the_slides_range`].)
#[test]
fn channels_sound_alike_and_stray_events_are_silent() {
    let bundle = release_bundle();
    for mode in [0.0, 1.0] {
        let setup = [param("mode", mode)];
        let render =
            |score: &[(usize, Ev)], samples: usize| Plugin::at_48k(&bundle, &setup).render_blocks(score, samples, 480);
        let reference = render(&[(0, Ev::Midi([0x90, 55, 100]))], 4_800);
        assert!(reference.peak() > AUDIBLE, "mode {mode}: a note on channel 1 sounds");
        for channel in 1..16u8 {
            let audio = render(&[(0, Ev::Midi([0x90 | channel, 55, 100]))], 4_800);
            assert_eq!(bit_identical(&audio, &reference), None, "mode {mode}: channel {}", channel + 1);
        }
        let chord: Score = (0..16u8).map(|c| (0, Ev::Midi([0x90 | c, 40 + 3 * c, 100]))).collect();
        let audio = render(&chord, 9_600);
        audio.assert_finite("a note on every channel");
        println!("mode {mode}: 16-channel chord peak {:.3}", audio.peak());
        assert!(audio.peak() > reference.peak(), "mode {mode}: 16 notes are louder than one");
        let stray = vec![
            (0, Ev::Midi([0x90, 60, 0])),
            (0, Ev::On(3, 64, 0.0)),
            (10, Ev::Off(0, 61)),
            (20, Ev::Midi([0x85, 0, 64])),
            (30, Ev::Midi([0x8F, 127, 0])),
            (40, Ev::Off(15, 127)),
        ];
        let audio = render(&stray, 4_800);
        assert_eq!(audio.peak(), 0.0, "mode {mode}: velocity 0 and stray note-offs are silent");
    }
}

/// A key struck fortissimo (velocity 1.0) and held for `seconds` in `mode`, every other
/// parameter at its default.
fn held_note(bundle: &Path, mode: f64, key: u8, seconds: f64) -> Audio {
    let audio = Plugin::at_48k(bundle, &[param("mode", mode)]).render_blocks(
        &[(0, Ev::On(0, key, 1.0))],
        (seconds * FS) as usize,
        512,
    );
    audio.assert_finite(&format!("mode {mode}, key {key}"));
    audio
}

/// Loudness an out-of-range key may stand above or below the piano key whose voicing gains it
/// takes (LU): the 6 LU band `tests/tests/loudness.rs` holds the whole keyboard A0–C8 to.
const KEYBOARD_BAND_LU: f64 = 6.0;

/// Keys 0 and 127, beyond the piano's A0–C8, in piano mode.
///
/// Pitch: the per-note rule (`qsa_dsp::preset::piano_note`) covers every MIDI key and tunes each
/// string's first partial to exactly `440·2^((k−69)/12)`, 8.176 Hz and 12,543.85 Hz, moved by the
/// default octave stretch of the nearest keyboard key (`qsa_dsp::preset::stretch_cents`, A0's
/// −0.98 cents and C8's +32.6 cents); key 0 has one string, key 127 three, detuned by the key's
/// pattern of the default 2.5-cent spread. The modal
/// update keeps each mode's frequency exactly, up to the damping's shift `√(1 − (σ/ω)²) − 1`
/// (below 1e-6 at both keys), so the measured first partial (the largest spectral peak within
/// ±10 % of the key's frequency) may lie only between the unison's lowest and highest string,
/// widened by the estimator's error: at most half its grid step, `fs/(16N)` for `N` samples
/// analysed. Key 0 is analysed over 1.95 s (0.032 Hz, 0.39 %), key 127 over 0.15 s (0.42 Hz,
/// 0.003 %), both from 50 ms on.
///
/// Level (integrated loudness, EBU R128, 2 s held, as `cargo xtask loudness` measures): keys
/// outside A0–C8 take the voicing gains of the nearest piano key (`voicing_gain`). Key 0's string
/// continues the bass rule (1.9 m, the length's clamp), so it must stay within
/// [`KEYBOARD_BAND_LU`] of key 21 (measured 2.3 LU louder). Key 127's string is a single
/// partial at 12.5 kHz (its second lies beyond the 20 kHz band limit) struck by the rule's
/// stiffest felt (κ at its 1e13 clamp), which takes far less from the hammer than key 108's: it
/// must sound (above the −70 LUFS absolute gate of EBU R128) and be no louder than key 108, the
/// keyboard's top (measured 31.7 LU below it).
#[test]
fn piano_keys_0_and_127_sound_at_the_rules_pitch_and_level() {
    let bundle = release_bundle();
    let stereo = |a: &Audio| xtask::loudness::integrated_lufs_stereo(&a.left, &a.right, FS);
    let lufs = |key: u8| stereo(&held_note(&bundle, 0.0, key, 2.0));
    let (a0, c8) = (lufs(21), lufs(108));
    let from = (0.05 * FS) as usize;
    for (key, analysed) in [(0u8, (2.0 * FS) as usize - from), (127, (0.15 * FS) as usize)] {
        let audio = held_note(&bundle, 0.0, key, 2.0);
        let signal = &audio.tail(from)[..analysed];
        let expected = key_hz(key) * 2f64.powf(qsa_dsp::preset::stretch_cents(key, 1.0) / 1200.0);
        let f = spectral_peak(signal, FS, 0.9 * expected, 1.1 * expected);
        let tolerance = FS / (16.0 * analysed as f64);
        // The unison's strings, each `2^{c/1200}` from the key for its detuning of `c` cents.
        let note = qsa_dsp::preset::piano_note(key);
        let cents = note.detune[..note.strings].iter().map(|d| d * Settings::default().unison_detune);
        let (low, high) = cents.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), c| (l.min(c), h.max(c)));
        let (lowest, highest) = (expected * 2f64.powf(low / 1200.0), expected * 2f64.powf(high / 1200.0));
        let level = stereo(&audio);
        let neighbour = if key == 0 { a0 } else { c8 };
        println!(
            "key {key}: {f:.4} Hz (expected {expected:.4} Hz, {:+.5} %, tolerance {tolerance:.3} Hz); {level:.2} LUFS, \
             key {} {neighbour:.2} LUFS ({:+.2} LU)",
            100.0 * (f / expected - 1.0),
            if key == 0 { 21 } else { 108 },
            level - neighbour
        );
        assert!(
            f >= lowest - tolerance && f <= highest + tolerance,
            "key {key}: {f} Hz, expected {lowest}–{highest} Hz within {tolerance} Hz"
        );
        if key == 0 {
            assert!((level - a0).abs() <= KEYBOARD_BAND_LU, "key 0: {level:.2} LUFS against key 21's {a0:.2}");
        } else {
            assert!(level > -70.0 && level <= c8, "key 127: {level:.2} LUFS against key 108's {c8:.2}");
        }
    }
}

/// Keys 0 and 127 in slide mode (following keys) play the ends of the slide's range: the slide
/// position `L(1 − 2^(−(k−45)/12))` is held between 5 mm from the nut and 0.8 L, so key 0 plays
/// exactly what the open string's key 45 plays and key 127 exactly what key 84 (C6, beyond the
/// 0.8 L clamp from key 73 on) plays, sample for sample, and so at their levels. Their pitches
/// are those of the speaking lengths `L − 5 mm` (110 Hz · L/(L − 5 mm)) and 0.2 L (550 Hz),
/// within [`PITCH_TOLERANCE`] (the hand spring pulls the first partial about 1 % sharp; the
/// period follows the series).
#[test]
fn slide_keys_0_and_127_play_the_ends_of_the_slides_range() {
    let bundle = release_bundle();
    let length = qsa_dsp::preset::slide_guitar().string.length;
    for (key, inside, expected) in [(0u8, 45u8, 110.0 * length / (length - 0.005)), (127, 84, 110.0 / 0.2)] {
        let audio = held_note(&bundle, 1.0, key, 0.5);
        let reference = held_note(&bundle, 1.0, inside, 0.5);
        assert_eq!(bit_identical(&audio, &reference), None, "slide key {key} against key {inside}: first difference");
        assert!(audio.peak() > AUDIBLE, "slide key {key} is silent: peak {}", audio.peak());
        let f = slide_pitch(&audio.tail(7_200), FS, expected);
        assert_pitch(f, expected, &format!("slide key {key} (as key {inside}), peak {:.3}", audio.peak()));
    }
}

/// Every sample rate from 22.05 to 192 kHz: a note in each mode, and on each guitar, is finite
/// and at its pitch (the engine band-limits every string to 20 kHz, or Nyquist below 40 kHz, so
/// the sound is the same). A slide's pitch is measured from 0.4 s on: on the acoustic guitar A3
/// sits on the top's 219 Hz resonance, and for the first few hundred milliseconds the string's
/// first partial and the body's mode trade energy, which pulls the period (at 22.05 kHz +1.7 %
/// over 0.15–0.4 s, +0.8 % over 0.4–1 s; the electric guitar +0.7 % over both).
#[test]
fn sample_rates_from_22_to_192_khz() {
    let bundle = release_bundle();
    for fs in [22_050.0, 44_100.0, 48_000.0, 88_200.0, 96_000.0, 176_400.0, 192_000.0] {
        let samples = (0.4 * fs) as usize;
        let mut piano = Plugin::new(&bundle, fs, 4096, &[]);
        let audio = piano.render_blocks(&[(0, Ev::On(0, 69, 0.7))], samples, 1024);
        audio.assert_finite(&format!("piano at {fs} Hz"));
        assert!(audio.peak() > AUDIBLE, "piano at {fs} Hz is silent");
        assert_pitch(piano_pitch(&audio, fs, 69), 440.0, &format!("piano A4 at {fs} Hz"));
        let guitars = [("electric", 0.0), ("acoustic", 1.0)].map(|(guitar, body)| {
            let mut slide = Plugin::new(&bundle, fs, 4096, &[param("mode", 1.0), param("sbody", body)]);
            let audio = slide.render_blocks(&[(0, Ev::On(0, 57, 0.8))], 2 * samples, 1024);
            let what = format!("{guitar} slide A3 at {fs} Hz");
            audio.assert_finite(&what);
            assert!(audio.peak() > AUDIBLE, "{what} is silent");
            assert_pitch(slide_pitch(&audio.tail(samples), fs, 220.0), 220.0, &what);
            audio
        });
        assert!(bit_identical(&guitars[0], &guitars[1]).is_some(), "the two guitars sound alike at {fs} Hz");
    }
}

/// A host whose session changes its sample rate deactivates the instance while notes ring and
/// activates it at the new rate (up, down, back to a rate used before, and the same rate again).
/// The notes played after each activation sound as on a fresh instance at that rate, to the bit:
/// nothing of the notes held before is heard, and nothing of the old rate is left. In each mode,
/// with the sustain pedal held across the change.
#[test]
fn a_new_sample_rate_from_the_host_sounds_as_a_fresh_instance_at_that_rate() {
    let bundle = release_bundle();
    let rates = [96_000.0, 44_100.0, 192_000.0, 22_050.0, 22_050.0, 48_000.0];
    for (mode, keys) in [("piano", [45u8, 57, 64, 69]), ("slide", [45, 52, 57, 60])] {
        let setup = [param("mode", if mode == "piano" { 0.0 } else { 1.0 })];
        // A chord struck under the pedal and still sounding when the host stops.
        let held: Vec<(usize, Ev)> = std::iter::once((0, Ev::Midi([0xB0, 64, 127])))
            .chain(keys.iter().enumerate().map(|(i, &k)| (100 + 50 * i, Ev::On(0, k, 0.9))))
            .collect();
        // The notes after the change: a key struck, released and struck again, with the pedal up.
        let after = [
            (0, Ev::Midi([0xB0, 64, 0])),
            (10, Ev::On(0, 69, 0.7)),
            (3000, Ev::Off(0, 69)),
            (6000, Ev::On(0, 69, 0.5)),
        ];
        let mut host = Plugin::new(&bundle, FS, 4096, &setup);
        let mut fs = FS;
        for &rate in &rates {
            let before = host.render_blocks(&held, (0.3 * fs) as usize, 512);
            assert!(before.peak() > AUDIBLE, "{mode}: the chord at {fs} Hz is silent");
            host.reactivate_at(rate);
            fs = rate;
            let samples = (0.3 * fs) as usize;
            let heard = host.render_blocks(&after, samples, 1024);
            let fresh = Plugin::new(&bundle, fs, 4096, &setup).render_blocks(&after, samples, 1024);
            heard.assert_finite(&format!("{mode} after the change to {fs} Hz"));
            assert!(fresh.peak() > AUDIBLE, "{mode}: the fresh instance at {fs} Hz is silent");
            if let Some(i) = bit_identical(&heard, &fresh) {
                panic!(
                    "{mode} after the change to {fs} Hz differs from a fresh instance from sample {i}: \
                     {} against {}",
                    heard.left.get(i).copied().unwrap_or(f32::NAN),
                    fresh.left.get(i).copied().unwrap_or(f32::NAN)
                );
            }
            println!("{mode} at {fs} Hz: as a fresh instance, peak {:.3}", heard.peak());
        }
    }
}

/// Parameters set while the host has the plugin stopped (a flush between stop and start, or a
/// state loaded then, as when a project is restored or an edit made while the transport stood)
/// sound from the first sample once it starts again, as on a fresh instance made with them, to
/// the bit: nothing glides from the values before the stop. The gain goes from +12 to −36 dB
/// (the limiter off), and in slide mode the pickup and its resonance move across their ranges,
/// with notes ringing when the host stops.
#[test]
fn parameters_set_while_stopped_sound_from_the_first_sample_after_the_restart() {
    let bundle = release_bundle();
    for mode in [0.0, 1.0] {
        let before =
            [param("mode", mode), param("limit", 0.0), param("gain", 1.0), param("pickup", 0.0), param("ptone", 1.0)];
        let after =
            [param("mode", mode), param("limit", 0.0), param("gain", 0.0), param("pickup", 1.0), param("ptone", 0.0)];
        let held: Score = [48u8, 55, 64].iter().enumerate().map(|(i, &k)| (100 * i, Ev::On(0, k, 0.9))).collect();
        let score: Score = vec![(0, Ev::On(0, 57, 0.9)), (4_800, Ev::Off(0, 57))];
        let samples = 14_400;
        let fresh = Plugin::at_48k(&bundle, &after).render_blocks(&score, samples, 512);
        assert!(fresh.peak() > 1e-4, "mode {mode}: the fresh instance is silent");
        let state = Plugin::at_48k(&bundle, &after).save();
        for by_state in [false, true] {
            let what = format!("mode {mode}, {}", if by_state { "a state loaded" } else { "a flush" });
            let mut host = Plugin::at_48k(&bundle, &before);
            let ringing = host.render_blocks(&held, 4_800, 512);
            assert!(ringing.peak() > 10.0 * fresh.peak(), "{what}: the notes before are louder");
            host.restart(|p| {
                if by_state {
                    assert!(p.load(&state), "{what}: the state loads");
                } else {
                    p.flush_inactive(&after);
                }
            });
            let heard = host.render_blocks(&score, samples, 512);
            if let Some(i) = bit_identical(&heard, &fresh) {
                panic!(
                    "{what}: differs from a fresh instance from sample {i}: {} against {}",
                    heard.left.get(i).copied().unwrap_or(f32::NAN),
                    fresh.left.get(i).copied().unwrap_or(f32::NAN)
                );
            }
        }
    }
}

/// Garbage as saved state (random bytes, a plausible length prefix before random bytes, valid
/// JSON of the wrong shape, a truncated real state) is refused, and every parameter keeps its
/// value; a real saved state still loads afterwards and restores its values; the instrument
/// still plays.
#[test]
fn garbage_state_is_refused_and_the_previous_state_kept() {
    let mut p = Plugin::at_48k(&release_bundle(), &[]);
    let _ = p.render_blocks(&[(0, param("slide", slide_value(7.0))), (0, param("hard", 0.8))], 64, 64);
    let saved = p.save();
    println!("saved state: {} bytes", saved.len());
    let _ = p.render_blocks(&[(0, param("slide", slide_value(3.0))), (0, param("mode", 1.0))], 64, 64);
    let ids: Vec<u32> = PARAMETERS.iter().map(|(id, ..)| clap_id(id)).collect();
    let snapshot = |p: &mut Plugin| ids.iter().map(|&id| p.value(id)).collect::<Vec<_>>();
    let before = snapshot(&mut p);

    let mut rng = seeded_rng(99);
    let mut garbage: Vec<Vec<u8>> = vec![Vec::new(), vec![0u8; 3]];
    for len in [8usize, 64, 1000, 4096] {
        garbage.push((0..len).map(|_| rng.random()).collect());
    }
    let prefixed = |body: &[u8]| [&(body.len() as u64).to_le_bytes()[..], body].concat();
    let noise: Vec<u8> = (0..500).map(|_| rng.random()).collect();
    garbage.push(prefixed(&noise));
    for json in ["null", "[1, 2, 3]", "{\"params\": 5}", "{\"version\": {}, \"params\": []}"] {
        garbage.push(prefixed(json.as_bytes()));
    }
    garbage.push(saved[..saved.len() / 2].to_vec());
    for (i, bytes) in garbage.iter().enumerate() {
        assert!(!p.load(bytes), "garbage state {i} ({} bytes) was accepted", bytes.len());
        assert_eq!(snapshot(&mut p), before, "garbage state {i} changed the parameters");
    }
    assert!(p.load(&saved), "a saved state loads");
    let slide = p.value(clap_id("slide")).expect("slide");
    assert!((slide - slide_value(7.0)).abs() < 1e-6, "the saved slide position is back: {slide}");
    assert_eq!(p.value(clap_id("mode")), Some(0.0), "the saved mode (Piano) is back");
    let audio = p.render_blocks(&[(0, Ev::On(0, 60, 0.7))], 9_600, 512);
    audio.assert_finite("after garbage state");
    assert!(audio.peak() > AUDIBLE, "the instrument still plays after garbage state");
}

/// CC121 (reset all controllers) reaches the engine: a piano note held under the sustain and
/// soft pedals, then CC121 on its channel, then the key released, is damped as with both pedals
/// let up by their own messages at that sample, to the bit; without either, it rings on (14 dB
/// louder a quarter of a second after the release, at least).
#[test]
fn reset_all_controllers_from_the_host_lets_the_pedals_up() {
    let bundle = release_bundle();
    let score = |at_reset: &[[u8; 3]]| -> Score {
        let mut score: Score =
            vec![(0, Ev::Midi([0xB0, 64, 127])), (0, Ev::Midi([0xB0, 67, 127])), (10, Ev::Midi([0x90, 48, 100]))];
        score.extend(at_reset.iter().map(|&m| (4_800, Ev::Midi(m))));
        score.push((9_600, Ev::Midi([0x80, 48, 0])));
        score
    };
    let render = |score: &Score| Plugin::at_48k(&bundle, &[]).render_blocks(score, 24_000, 512);
    let reset = render(&score(&[[0xB0, 121, 0]]));
    let let_up = render(&score(&[[0xB0, 64, 0], [0xB0, 67, 0]]));
    let held = render(&score(&[]));
    reset.assert_finite("after CC121");
    if let Some(n) = bit_identical(&reset, &let_up) {
        panic!("CC121 differs from the pedals let up from sample {n}");
    }
    let rms = |a: &Audio| (a.left[21_600..].iter().map(|&x| f64::from(x).powi(2)).sum::<f64>() / 2_400.0).sqrt();
    let (damped, ringing) = (rms(&reset), rms(&held));
    println!("0.25–0.3 s after the release: rms {damped:.2e} with CC121, {ringing:.2e} with the pedal held");
    assert!(ringing > 5.0 * damped, "the note under the held pedal rings on: {ringing} against {damped}");
}

/// The same MIDI file through the offline renderer (`cargo xtask render --midi`) and through the
/// `.clap` in a host gives identical samples: the file's raw MIDI messages go to the plugin at the
/// sample offsets the renderer uses, every parameter at its default, in 512-sample host blocks.
/// Checked for the piano phrase in piano mode and the slide phrase in slide mode.
#[test]
fn midi_file_renders_the_same_offline_and_in_the_host() {
    use qsa_dsp::instrument::ParamValues;
    use xtask::render::midi;

    let fs = 48_000.0;
    for (file, slide) in [("piano-phrase.mid", false), ("slide-phrase.mid", true)] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes").join(file);
        let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let mut params = ParamValues::default();
        if slide {
            params.set("mode", "slide").unwrap();
        }
        let score = midi::score(&bytes, fs).unwrap();
        let (left, right, _) = midi::render(&score, &params, fs, 0.5, 512);
        let samples = left.len();
        let host_score: Score =
            midi::timed_messages(&bytes, fs).unwrap().into_iter().map(|(t, m)| (t as usize, Ev::Midi(m))).collect();
        let setup = if slide { vec![param("mode", 1.0)] } else { Vec::new() };
        let mut plugin = Plugin::at_48k(&release_bundle(), &setup);
        let audio = plugin.render_blocks(&host_score, samples, 512);
        let offline = Audio { left, right, note_ends: Vec::new() };
        assert!(offline.peak() > 0.01, "{file}: the offline render is not silent");
        if let Some(n) = bit_identical(&audio, &offline) {
            panic!("{file}: host and offline renderer differ first at sample {n}");
        }
    }
}

/// A state saved by a later version or written by hand (a newer version string, a parameter
/// this version does not know, values beyond this version's ranges, a choice it does not have,
/// values saved as another type) loads what this version understands, the same in any instance:
/// unknown parameters are left out, numbers are clamped into their ranges, a whole number saved
/// as a float is rounded, a switch saved as a number is on unless 0, and an unknown choice or a
/// value that is no number takes the default (not the instance's value: this one had IMP and a
/// stereo width of 100 %), and the instrument plays finite samples.
#[test]
fn a_state_from_a_later_version_loads_what_it_can() {
    let moved = [param("solver", 1.0), param("width", 1.0)];
    let mut p = Plugin::at_48k(&release_bundle(), &moved);
    let mut fresh = Plugin::at_48k(&release_bundle(), &[]);
    assert_ne!(p.value(clap_id("solver")), fresh.value(clap_id("solver")), "the solver moved");
    assert_ne!(p.value(clap_id("width")), fresh.value(clap_id("width")), "the width moved");
    let saved = p.save();
    let mut state: serde_json::Value = serde_json::from_slice(&saved[8..]).expect("the state is JSON after its length");
    state["version"] = serde_json::json!("99.0.0");
    let params = state["params"].as_object_mut().expect("a params object");
    params.insert("harmonics".into(), serde_json::json!({ "f32": 3.0 }));
    params.insert("slide".into(), serde_json::json!({ "f32": 1e9 }));
    params.insert("segs".into(), serde_json::json!({ "i32": 100_000 }));
    params.insert("hand".into(), serde_json::json!({ "f32": -1e30 }));
    params.insert("solver".into(), serde_json::json!({ "string": "harp" }));
    params.insert("nb".into(), serde_json::json!({ "f32": 95.6 }));
    params.insert("width".into(), serde_json::json!({ "string": "wide" }));
    params.insert("limit".into(), serde_json::json!({ "i32": 0 }));
    params.insert("follow".into(), serde_json::json!({ "f32": 0.0 }));
    let body = serde_json::to_vec(&state).expect("JSON");
    let bytes = [&(body.len() as u64).to_le_bytes()[..], &body].concat();
    assert!(p.load(&bytes), "a later version's state loads");
    let value = |p: &mut Plugin, id: &str| p.value(clap_id(id)).expect(id);
    assert_eq!(value(&mut p, "slide"), 1.0, "Slide position clamped to its top");
    assert_eq!(value(&mut p, "hand"), 0.0, "Hand height clamped to its bottom");
    assert_eq!(value(&mut p, "segs"), 63.0, "QSA segments clamped to 64");
    assert_eq!(value(&mut p, "solver"), value(&mut fresh, "solver"), "an unknown solver takes the default");
    assert_eq!(value(&mut p, "width"), value(&mut fresh, "width"), "a word for the width takes the default");
    // (A whole number's CLAP value counts from its range's bottom, 1.)
    let block = value(&mut p, "nb");
    assert!((block - 95.0).abs() < 1e-4, "a control block of 95.6 samples rounded to 96: {block}");
    assert_eq!(value(&mut p, "limit"), 0.0, "the limiter saved as the number 0 is off");
    assert_eq!(value(&mut p, "follow"), 0.0, "following keys saved as the number 0.0 is off");
    let audio =
        p.render_blocks(&[(0, param("mode", 1.0)), (0, Ev::On(0, 57, 0.8)), (0, Ev::On(0, 60, 0.8))], 19_200, 512);
    audio.assert_finite("after a later version's state");
    assert!(audio.peak() > AUDIBLE, "the instrument plays after a later version's state");
}

/// A state loaded while the plugin runs with the editor closed, with another voice count than
/// the pool was built for, asks the host to restart the plugin (the pool is sized at
/// activation) once for that count, and the restart builds the pool it asks for; a state with
/// the count the pool has asks for nothing, and a count asked for again after it asks again.
#[test]
fn a_state_with_another_voice_count_asks_the_host_for_a_restart() {
    let bundle = release_bundle();
    let score: Score = vec![(0, Ev::On(0, 60, 0.8))];
    let with_voices = |voices: i64| {
        let mut p = Plugin::at_48k(&bundle, &[]);
        let mut state = state_json(&p.save());
        state["params"]["voices"] = serde_json::json!({ "i32": voices });
        state_bytes(&state)
    };
    let mut p = Plugin::at_48k(&bundle, &[]);
    let built = p.value(clap_id("voices")).expect("voices");
    assert!(p.load(&with_voices(32)), "the state loads");
    p.render_blocks(&score, 1_024, 256);
    assert_eq!(p.restarts_requested(), 0, "the pool's own count asks for nothing (built for {built})");
    assert!(p.load(&with_voices(8)), "the state loads");
    p.render_blocks(&score, 1_024, 256);
    assert_eq!(p.restarts_requested(), 1, "another count asks once, however many blocks run");
    p.restart(|_| {});
    p.render_blocks(&score, 1_024, 256);
    assert_eq!(p.restarts_requested(), 1, "restarted with 8 voices, nothing more to ask");
    // A count asked for, left for the pool's own and asked for again, with the host not
    // restarting in between, is asked for again.
    for (voices, asked) in [(32, 2), (8, 2), (32, 3)] {
        assert!(p.load(&with_voices(voices)), "the state loads");
        p.render_blocks(&score, 1_024, 256);
        assert_eq!(p.restarts_requested(), asked, "{voices} voices against a pool of 8");
    }
}

/// A state that leaves parameters out (an older version's, or a hand-made one) gives each its
/// default rather than the value the instance had: a float (width), a choice (the guitar's
/// body), a switch (the limiter) and a whole number (control block). The player's settings it
/// leaves out (voices) stay as the player set them. Loaded into an instance that had a factory
/// preset chosen, it names none (the state the instance saves next holds an empty `preset`),
/// whether it leaves the field out or holds something other than a JSON string there.
#[test]
fn a_state_that_leaves_parameters_out_gives_them_their_defaults() {
    let ids = ["width", "sbody", "limit", "nb", "voices"];
    let mut fresh = Plugin::at_48k(&release_bundle(), &[]);
    let defaults: Vec<f64> = ids.iter().map(|id| fresh.value(clap_id(id)).expect(id)).collect();
    let moved: Vec<Ev> = ids.iter().zip(&defaults).map(|(id, d)| param(id, if *d > 0.5 { 0.0 } else { 1.0 })).collect();
    let mut p = Plugin::at_48k(&release_bundle(), &moved);
    let set: Vec<f64> = ids.iter().map(|id| p.value(clap_id(id)).expect(id)).collect();
    assert!(set.iter().zip(&defaults).all(|(s, d)| s != d), "every value moved: {set:?} from {defaults:?}");
    let saved = p.save();
    let mut state: serde_json::Value = serde_json::from_slice(&saved[8..]).expect("the state is JSON after its length");
    let params = state["params"].as_object_mut().expect("a params object");
    for id in ids {
        assert!(params.remove(id).is_some(), "{id} was saved");
    }
    let fields = state["fields"].as_object_mut().expect("a fields object");
    assert!(fields.remove("preset").is_some(), "the preset was saved");
    let body = serde_json::to_vec(&state).expect("JSON");
    let named = |p: &mut Plugin, preset: &str| {
        let mut named = state_json(&p.save());
        named["fields"]["preset"] = serde_json::json!(serde_json::to_string(preset).unwrap());
        assert!(p.load(&state_bytes(&named)), "the state naming {preset} loads");
        assert_eq!(state_json(&p.save())["fields"]["preset"], serde_json::json!(format!("\"{preset}\"")));
    };
    named(&mut p, "lap-steel");
    assert!(p.load(&[&(body.len() as u64).to_le_bytes()[..], &body].concat()), "the state loads");
    for (i, id) in ids.iter().enumerate() {
        let want = if *id == "voices" { set[i] } else { defaults[i] };
        assert_eq!(p.value(clap_id(id)), Some(want), "{id}");
    }
    assert_eq!(state_json(&p.save())["fields"]["preset"], serde_json::json!("\"\""), "a state without a preset");
    named(&mut p, "lap-steel");
    let mut garbled = state.clone();
    garbled["fields"]["preset"] = serde_json::json!("lap-steel");
    assert!(p.load(&state_bytes(&garbled)), "the state with a garbled preset loads");
    assert_eq!(state_json(&p.save())["fields"]["preset"], serde_json::json!("\"\""), "a garbled preset");
}

/// A state whose numbers lie beyond their parameters' ranges (a hand-edited or corrupt preset)
/// plays them at the ranges' ends: a gain of 1000 (the limiter off) sounds as +12 dB, to the bit,
/// not louder. A number too large for an `f32` (1e39, which reads as infinity) takes the
/// parameter's default, and the state the plugin then saves loads back with the same values
/// (an infinity would be saved as `null`, which no instance could read).
#[test]
fn a_states_numbers_beyond_their_ranges_play_at_the_ranges_ends() {
    let bundle = release_bundle();
    let score: Score = vec![(0, Ev::On(0, 60, 1.0))];
    let with_values = |values: &[(&str, serde_json::Value)]| {
        let mut p = Plugin::at_48k(&bundle, &[]);
        let mut state = state_json(&p.save());
        for (id, value) in values {
            state["params"][*id] = value.clone();
        }
        assert!(p.load(&state_bytes(&state)), "the state {values:?} loads");
        p
    };
    let off = ("limit", serde_json::json!({ "bool": false }));
    let top = with_values(&[off.clone(), ("gain", serde_json::json!({ "f32": 3.981_071_7 }))])
        .render_blocks(&score, 9_600, 512);
    let beyond =
        with_values(&[off.clone(), ("gain", serde_json::json!({ "f32": 1000.0 }))]).render_blocks(&score, 9_600, 512);
    assert!(top.peak() > AUDIBLE, "the note at +12 dB is silent");
    if let Some(i) = bit_identical(&beyond, &top) {
        panic!("a gain of 1000 differs from +12 dB from sample {i}: peaks {} and {}", beyond.peak(), top.peak());
    }
    let mut p =
        with_values(&[("gain", serde_json::json!({ "f32": 1e39 })), ("hard", serde_json::json!({ "f32": -1e39 }))]);
    let mut defaults = Plugin::at_48k(&bundle, &[]);
    for id in ["gain", "hard"] {
        assert_eq!(p.value(clap_id(id)), defaults.value(clap_id(id)), "{id}: a non-finite number takes the default");
    }
    let resaved = p.save();
    let mut again = Plugin::at_48k(&bundle, &[param("gain", 1.0), param("hard", 1.0)]);
    assert!(again.load(&resaved), "the state saved after a non-finite number loads");
    for id in ["gain", "hard"] {
        assert_eq!(again.value(clap_id(id)), defaults.value(clap_id(id)), "{id}: read back");
    }
}

// ------------------------------------------------------------------------------------------------
// Per-note expression, groups and value names
// ------------------------------------------------------------------------------------------------

/// A mezzo-piano slide note with a CLAP note id: a pair of them stays far below the safety
/// limiter's ceiling, where the output stage is a pure delay, so a pair renders as the sum of its
/// notes rendered alone.
fn on_id(channel: u8, key: u8, id: u32) -> Ev {
    Ev::OnId(channel, key, 0.3, id)
}

/// Largest difference between `both` and `a + b` (left channels), relative to the peak of `both`.
fn mixture_error(both: &Audio, a: &Audio, b: &Audio) -> f32 {
    let worst =
        both.left.iter().zip(a.left.iter().zip(&b.left)).map(|(m, (x, y))| (m - (x + y)).abs()).fold(0.0f32, f32::max);
    worst / both.peak()
}

/// The rms of `a − b` over `b`'s, from `from` samples on (left channels).
fn relative_change(a: &Audio, b: &Audio, from: usize) -> f64 {
    let rms = |x: &mut dyn Iterator<Item = f32>| {
        let v: Vec<f64> = x.map(f64::from).collect();
        (v.iter().map(|v| v * v).sum::<f64>() / v.len() as f64).sqrt()
    };
    rms(&mut a.left[from..].iter().zip(&b.left[from..]).map(|(x, y)| x - y)) / rms(&mut b.left[from..].iter().copied())
}

/// The pitch of a slide note's displacement (the running sum of the pickup's velocity signal)
/// over `a..b` seconds, searched within 20 % of `expected`.
fn slide_pitch_between(audio: &Audio, a: f64, b: f64, expected: f64) -> f64 {
    let signal = qsa_tests::displacement(&audio.left[(a * FS) as usize..(b * FS) as usize]);
    slide_pitch(&signal, FS, expected)
}

/// A CLAP host's notes on one key may overlap, each with its note id: the first note's note-off
/// (its id, channel and key) lets go of nothing while the second holds the key, so the piano
/// renders to the bit as without it (passed on as the key's note-off, it would drop the damper
/// on the held note); the second's note-off then damps as a note-off does.
#[test]
fn clap_a_note_off_by_id_leaves_a_later_note_on_its_key_held() {
    let bundle = release_bundle();
    let samples = FS as usize;
    let render = |score: &[(usize, Ev)]| Plugin::at_48k(&bundle, &[]).render_blocks(score, samples, 512);
    let off = |id| Ev::OffAt(Target { note_id: Some(id), channel: Some(0), key: Some(60) });
    let first = [(0, Ev::OnId(0, 60, 0.8, 1)), (9_600, Ev::OnId(0, 60, 0.8, 2))];
    let overlapped = render(&[first[0], first[1], (19_200, off(1)), (38_400, off(2))]);
    let without = render(&[first[0], first[1], (38_400, off(2))]);
    let held = render(&first);
    if let Some(i) = bit_identical(&overlapped, &without) {
        panic!("the first note's note-off changed the sound from sample {i}");
    }
    let tail = |a: &Audio| a.left[40_000..].iter().map(|v| f64::from(*v).powi(2)).sum::<f64>().sqrt();
    println!("after the second note-off {:.2e}, held {:.2e}", tail(&without), tail(&held));
    assert!(tail(&without) < 0.5 * tail(&held), "the second note's note-off let nothing go");
}

/// A CLAP tuning expression moves its note's slide and nothing else. Note 1 (channel 2, key 50)
/// and note 2 (channel 3, key 57, 220 Hz) sound; note 2 is tuned −3 semitones at 0.25 s,
/// addressed by its note id. Note 2 alone sounds at 220 Hz before and at key 54's 185 Hz after
/// (the slide glides there at its 5 m/s limit, in about 12 ms); the pair renders as note 1 alone
/// plus the tuned note 2 alone (to f32 rounding), so note 1 did not move.
#[test]
fn clap_tuning_expression_moves_only_its_note() {
    let bundle = release_bundle();
    let setup = [param("mode", 1.0)];
    let tune = ((0.25 * FS) as usize, Ev::Expr(Expression::Tuning, Target::id(2), -3.0));
    let samples = FS as usize;
    let render = |score: &[(usize, Ev)]| Plugin::at_48k(&bundle, &setup).render_blocks(score, samples, 512);
    let note_1 = render(&[(0, on_id(2, 50, 1))]);
    let note_2 = render(&[(0, on_id(3, 57, 2)), tune]);
    let both = render(&[(0, on_id(2, 50, 1)), (0, on_id(3, 57, 2)), tune]);
    both.assert_finite("tuned pair");
    let error = mixture_error(&both, &note_1, &note_2);
    let (before, after) =
        (slide_pitch_between(&note_2, 0.15, 0.25, 220.0), slide_pitch_between(&note_2, 0.35, 1.0, key_hz(54)));
    println!("pair vs the notes alone: {error:.2e} of the peak {:.3}", both.peak());
    assert!(error < 1e-6, "the tuning of note 2 reached note 1 ({error:e} of the peak)");
    assert_pitch(before, 220.0, "note 2 before its tuning");
    assert_pitch(after, key_hz(54), "note 2 tuned −3 st");
}

/// A CLAP pressure expression presses its note's slide (`Hand height from` = Poly pressure) and
/// nothing else: addressed by channel and key it renders exactly as MIDI poly aftertouch at full
/// pressure; addressed by note id, the same; the pressed note sounds at its key (220 Hz); the
/// unpressed one is another sound (more than half its rms differs); the pair is the sum of the
/// notes alone.
#[test]
fn clap_pressure_expression_presses_only_its_note() {
    let render = slide_notes(3.0);
    let aftertouch = render(&[(0, on_id(3, 57, 2)), (0, Ev::Midi([0xA3, 57, 127]))]);
    let by_key = render(&[(0, on_id(3, 57, 2)), (0, Ev::Expr(Expression::Pressure, Target::key(3, 57), 1.0))]);
    let pressure = (0, Ev::Expr(Expression::Pressure, Target::id(2), 1.0));
    let by_id = render(&[(0, on_id(3, 57, 2)), pressure]);
    assert_eq!(bit_identical(&by_key, &aftertouch), None, "pressure by channel and key vs poly aftertouch");
    assert_eq!(bit_identical(&by_id, &aftertouch), None, "pressure by note id vs poly aftertouch");
    presses_only_its_note(render, &by_id, pressure, "pressure");
}

/// Renders of 0.5 s in slide mode with `Hand height from` at option `hand_source`, in buffers of
/// 512 samples, each on a new instance.
fn slide_notes(hand_source: f64) -> impl Fn(&[(usize, Ev)]) -> Audio {
    let bundle = release_bundle();
    let setup = [param("mode", 1.0), param("handsrc", hand_source)];
    move |score| Plugin::at_48k(&bundle, &setup).render_blocks(score, (0.5 * FS) as usize, 512)
}

/// Note 2 (key 57, note id 2, channel 4) pressed by `expression` renders as `pressed`: it sounds
/// at its key (220 Hz), more than half its rms differs from the note unpressed, and with note 1
/// (key 50, note id 1, channel 3) the pair is the sum of the notes alone, within 1e-6 of its
/// peak: the expression reaches note 2 alone.
fn presses_only_its_note(
    render: impl Fn(&[(usize, Ev)]) -> Audio,
    pressed: &Audio,
    expression: (usize, Ev),
    what: &str,
) {
    let unpressed = render(&[(0, on_id(3, 57, 2))]);
    let note_1 = render(&[(0, on_id(2, 50, 1))]);
    let both = render(&[(0, on_id(2, 50, 1)), (0, on_id(3, 57, 2)), expression]);
    let error = mixture_error(&both, &note_1, pressed);
    let change = relative_change(&unpressed, pressed, 7_200);
    println!("{what}: pair vs the notes alone {error:.2e} of the peak; unpressed vs pressed {change:.2} of the rms");
    assert!(error < 1e-6, "the {what} on note 2 reached note 1 ({error:e} of the peak)");
    assert!(change > 0.5, "{what} changed only {change} of the rms");
    assert_pitch(slide_pitch_between(pressed, 0.15, 0.5, 220.0), 220.0, &format!("note 2 pressed by its {what}"));
}

/// A CLAP brightness expression is its note's own CC74 (`Hand height from` = CC74): addressed by
/// note id it renders exactly as MIDI CC74 at 127 on the note's channel, and presses that note
/// alone (the pair is the sum of the notes alone; more than half the rms of the note changes).
#[test]
fn clap_brightness_expression_presses_only_its_note() {
    let render = slide_notes(4.0);
    let cc74 = render(&[(0, on_id(3, 57, 2)), (0, Ev::Midi([0xB3, 74, 127]))]);
    let brightness = (0, Ev::Expr(Expression::Brightness, Target::id(2), 1.0));
    let by_id = render(&[(0, on_id(3, 57, 2)), brightness]);
    assert_eq!(bit_identical(&by_id, &cc74), None, "brightness by note id vs CC74");
    presses_only_its_note(render, &by_id, brightness, "brightness");
}

/// In piano mode a CLAP brightness expression sent with its note-on voices that note's hammer
/// felt: by note id it renders exactly as MIDI CC74 at the same value sent on the note's channel
/// before the note-on, and at 1.0 (a felt 3.9 times as stiff) more than a tenth of the note's rms
/// differs from the note without it (measured 0.26). Sent 64 samples later, once the hammer is
/// thrown, it changes nothing.
#[test]
fn clap_brightness_expression_voices_a_piano_notes_felt_at_its_note_on() {
    let bundle = release_bundle();
    let render = |score: &[(usize, Ev)]| Plugin::at_48k(&bundle, &[]).render_blocks(score, (0.5 * FS) as usize, 512);
    let cc74 = render(&[(0, Ev::Midi([0xB3, 74, 127])), (0, on_id(3, 60, 2))]);
    let by_id = render(&[(0, on_id(3, 60, 2)), (0, Ev::Expr(Expression::Brightness, Target::id(2), 1.0))]);
    let plain = render(&[(0, on_id(3, 60, 2))]);
    let late = render(&[(0, on_id(3, 60, 2)), (64, Ev::Expr(Expression::Brightness, Target::id(2), 1.0))]);
    let change = relative_change(&plain, &by_id, 0);
    println!("piano brightness: {change:.2} of the rms changed");
    assert_eq!(bit_identical(&by_id, &cc74), None, "brightness by note id vs CC74 before the note-on");
    assert!(change > 0.1, "the brightness changed only {change} of the rms");
    assert_eq!(bit_identical(&late, &plain), None, "a brightness after the strike changed the note");
}

/// CLAP polyphonic modulation of `Slide position` and `Hand height` offsets one note's value:
/// +3 semitones on a slide at 6 (not following keys) renders exactly as the parameter at 9 for
/// everyone, and sounds there; +6 mm on the hand at −1.5 mm renders exactly as the parameter at
/// its top, +3 mm (the sum is clamped to the range). The other note of each pair is untouched.
/// Both instruments start from the same setup; the reference's parameter moves at sample 0 and
/// its note starts at 64, the start of the second control block, like the modulated one.
#[test]
fn clap_poly_modulation_offsets_one_note() {
    let bundle = release_bundle();
    let setup = [param("mode", 1.0), param("follow", 0.0), param("slide", slide_value(6.0))];
    let samples = (0.5 * FS) as usize;
    let render = |score: &[(usize, Ev)]| Plugin::at_48k(&bundle, &setup).render_blocks(score, samples, 512);
    let cases = [("slide", 3.0 / 24.0, slide_value(9.0)), ("hand", 6.0 / 6.0, 1.0)];
    for (id, amount, global) in cases {
        let modulate = (64, Ev::Mod(clap_id(id), 2, amount));
        let reference = render(&[(0, param(id, global)), (64, on_id(3, 60, 2))]);
        let modulated = render(&[(64, on_id(3, 60, 2)), modulate]);
        let plain = render(&[(64, on_id(3, 60, 2))]);
        assert_eq!(bit_identical(&modulated, &reference), None, "{id}: poly modulation vs the parameter moved");
        let note_1 = render(&[(64, on_id(2, 60, 1))]);
        let both = render(&[(64, on_id(2, 60, 1)), (64, on_id(3, 60, 2)), modulate]);
        let error = mixture_error(&both, &note_1, &modulated);
        let change = relative_change(&modulated, &plain, 7_200);
        println!("{id} +{amount}: pair vs the notes alone {error:.2e} of the peak; {change:.2} of the rms changed");
        assert!(error < 1e-6, "{id}: the modulation of note 2 reached note 1 ({error:e} of the peak)");
        assert!(change > 0.5, "{id}: the modulation changed only {change} of the rms");
        if id == "slide" {
            let expected = 110.0 * 2f64.powf(9.0 / 12.0);
            assert_pitch(slide_pitch_between(&modulated, 0.15, 0.5, expected), expected, "slide 6 st + 3 st");
        }
    }
}

/// Every note's end comes back to the host as a CLAP note-end event, once, with the note id,
/// channel and key of its note-on (−1 for a MIDI note, which has no id): a note released at
/// 0.1 s when its string falls silent, a note whose voice a legato glide takes over at once
/// (slide mode follows keys), and a note silenced by all-sound-off at once. Polyphonic
/// modulation needs these to free the host's per-voice modulators.
#[test]
fn clap_note_ends_are_reported() {
    let bundle = release_bundle();
    let mut p = Plugin::at_48k(&bundle, &[param("mode", 1.0)]);
    let score = vec![
        (0, on_id(0, 50, 5)),
        (2_400, on_id(0, 55, 6)),
        (3_600, Ev::Off(0, 50)),
        (4_800, Ev::Off(0, 55)),
        (4_800, Ev::Midi([0x91, 62, 90])),
    ];
    let audio = p.render_blocks(&score, 3 * 48_000, 512);
    println!("note ends: {:?}", audio.note_ends);
    let find = |id: i32| audio.note_ends.iter().filter(|e| e.1 == id).copied().collect::<Vec<_>>();
    assert_eq!(find(5), [(2_400, 5, 0, 50)], "legato: note 5 ends when note 6 takes its voice");
    let released = find(6);
    assert_eq!(released.len(), 1, "note 6 ends once: {released:?}");
    assert_eq!((released[0].1, released[0].2, released[0].3), (6, 0, 55));
    assert!(released[0].0 > 4_800, "note 6 ends after its release, when its string is silent: {released:?}");
    assert!(find(-1).is_empty(), "the held MIDI note has not ended");
    let silenced = p.render_blocks(&[(100, Ev::Midi([0xB0, 120, 0]))], 512, 512);
    assert_eq!(silenced.note_ends, [(100, -1, 1, 62)], "all sound off ends the MIDI note at once");
}

/// A note sounding when the host activates the plugin again reports its end at the first sample
/// after, whether the engine is kept (the same rate and voices: it is reset) or made anew (another
/// sample rate): a slide note with id 5 held, then the plugin reactivated at 48 kHz and at
/// 44.1 kHz.
#[test]
fn a_note_sounding_at_a_reactivation_reports_its_end() {
    let bundle = release_bundle();
    for rate in [48_000.0, 44_100.0] {
        let mut p = Plugin::at_48k(&bundle, &[param("mode", 1.0)]);
        let held = p.render_blocks(&[(0, on_id(0, 50, 5))], 4_800, 512);
        assert!(held.note_ends.is_empty(), "{:?}", held.note_ends);
        p.reactivate_at(rate);
        let after = p.render_blocks(&[], 512, 512);
        assert_eq!(after.note_ends, [(0, 5, 0, 50)], "reactivated at {rate} Hz");
    }
}

/// CLAP note-offs with wildcards, or naming a note by its id alone, are, to the bit, a note-off
/// for each key they address at that sample: every key of channel 0, the note with id 7, every
/// note. Notes on three channels, released under no pedal, so each release changes the sound.
#[test]
fn clap_note_offs_with_wildcards_release_each_addressed_key() {
    let bundle = release_bundle();
    let held: Score =
        vec![(0, Ev::On(0, 48, 0.7)), (0, Ev::On(0, 55, 0.6)), (0, on_id(1, 60, 7)), (0, Ev::On(2, 67, 0.5))];
    let render = |at: &[Ev]| {
        let mut score = held.clone();
        score.extend(at.iter().map(|&e| (4_800, e)));
        Plugin::at_48k(&bundle, &[]).render_blocks(&score, 14_400, 512)
    };
    let untouched = render(&[]);
    let every = Target { note_id: None, channel: None, key: None };
    let cases: [(Target, &[(u8, u8)]); 3] = [
        (Target { channel: Some(0), ..every }, &[(0, 48), (0, 55)]),
        (Target::id(7), &[(1, 60)]),
        (every, &[(0, 48), (0, 55), (1, 60), (2, 67)]),
    ];
    for (target, keys) in cases {
        let heard = render(&[Ev::OffAt(target)]);
        let offs: Vec<Ev> = keys.iter().map(|&(channel, key)| Ev::Off(channel, key)).collect();
        if let Some(n) = bit_identical(&heard, &render(&offs)) {
            panic!("{target:?}: differs from the note-offs of {keys:?} from sample {n}");
        }
        let change = relative_change(&heard, &untouched, 4_800);
        println!("{target:?}: releases {keys:?}, a change of {change:.3} after it");
        assert!(change > 0.05, "{target:?}: the release changes the sound by only {change}");
    }
}

/// A CLAP note choke ends the notes it addresses at once whatever the pedals, and the plugin
/// reports their ends: under the sustain pedal, with every key let go, chokes by note id, by
/// channel and of every note each end their notes within the steal's fade (5 ms in whole control
/// blocks of 64 samples, from the block after the choke). After the last, the output falls by
/// more than 20 dB in 0.2 s and 35 dB in 0.45 s, as the soundboard rings out (docs/physics.md
/// §13.2), where the pedalled notes without the chokes fall by less than 10 dB.
#[test]
fn a_clap_choke_ends_its_notes_under_the_pedal_and_reports_their_ends() {
    let bundle = release_bundle();
    let mut score: Score = vec![
        (0, Ev::Midi([0xB0, 64, 127])),
        (0, on_id(0, 48, 1)),
        (0, on_id(1, 60, 2)),
        (0, Ev::On(2, 67, 0.6)),
        (4_800, Ev::Off(0, 48)),
        (4_800, Ev::Off(1, 60)),
        (4_800, Ev::Off(2, 67)),
    ];
    let render = |score: &Score| Plugin::at_48k(&bundle, &[]).render_blocks(score, 48_000, 512);
    let ringing = render(&score);
    assert!(ringing.note_ends.is_empty(), "the pedal holds every note: {:?}", ringing.note_ends);
    let every = Target { note_id: None, channel: None, key: None };
    let chokes = [
        (9_600, Target::id(2), (2, 1, 60)),
        (14_400, Target { channel: Some(0), ..every }, (1, 0, 48)),
        (19_200, every, (-1, 2, 67)),
    ];
    score.extend(chokes.iter().map(|&(t, target, _)| (t, Ev::Choke(target))));
    let choked = render(&score);
    println!("note ends: {:?}", choked.note_ends);
    assert_eq!(choked.note_ends.len(), 3, "{:?}", choked.note_ends);
    // The fade (240 samples at 48 kHz) in whole blocks from the next block, and the block that
    // finds it over.
    let fade = (qsa_dsp::instrument::STEAL_TIME * 48_000.0).ceil() as usize;
    for (&(t, _, (id, channel, key)), &(at, end_id, end_channel, end_key)) in chokes.iter().zip(&choked.note_ends) {
        let by = t.div_ceil(64) * 64 + fade.div_ceil(64) * 64 + 64;
        assert_eq!((end_id, end_channel, end_key), (id, channel, key), "the choke at {t} ends its note");
        assert!((t + 1..=by).contains(&at), "the choke at {t} ends its note at {at}, by {by} at the latest");
    }
    // Mean square over 50 ms from `from` (dB).
    let level = |a: &Audio, from: usize| {
        10.0 * (a.left[from..from + 2_400].iter().map(|&x| f64::from(x).powi(2)).sum::<f64>() / 2_400.0).log10()
    };
    let before = level(&choked, 19_200 - 2_400);
    let falls = [9_600, 21_600].map(|after| before - level(&choked, 19_200 + after));
    let held = before - level(&ringing, 19_200 + 21_600);
    println!("before the last choke {before:.1} dB; after it, down {falls:.1?} dB at 0.2 and 0.45 s ({held:.1} held)");
    assert!(falls[0] > 20.0 && falls[1] > 35.0, "the output falls by {falls:.1?} dB");
    assert!(held < 10.0, "the pedalled notes, unchoked, fall by {held:.1} dB");
}

/// The host sees the editor's sections as parameter groups (CLAP `module`): Engine, Piano, Slide,
/// Output, in the documented order; `Slide position` and `Hand height`, and nothing else, are
/// modulatable per note id (polyphonic modulation).
#[test]
fn parameters_are_grouped_and_slide_and_hand_are_polyphonic() {
    let mut p = Plugin::at_48k(&release_bundle(), &[]);
    let params = p.params();
    let handle = p.instance.plugin_handle();
    let mut listed = Vec::new();
    for index in 0..params.count(&handle) {
        let mut buffer = ParamInfoBuffer::new();
        let info = params.get_info(&handle, index, &mut buffer).expect("param info");
        let module = String::from_utf8_lossy(info.module).into_owned();
        listed.push((info.id.get(), module, info.flags.contains(ParamInfoFlags::IS_MODULATABLE_PER_NOTE_ID)));
    }
    let expected_group = |id: &str| match id {
        "mode" | "solver" | "segs" | "nb" | "voices" | "guard" => "Engine",
        "hard" | "hmass" | "strike" | "damp" | "bright" | "damper" | "detune" | "stretch" | "hpfrom" | "hpto" => {
            "Piano"
        }
        "gain" | "limit" | "width" => "Output",
        _ => "Slide",
    };
    let order: Vec<u32> = PARAMETERS.iter().map(|(id, ..)| clap_id(id)).collect();
    assert_eq!(listed.iter().map(|l| l.0).collect::<Vec<_>>(), order, "the documented order");
    for ((id, ..), (_, module, per_note)) in PARAMETERS.iter().zip(&listed) {
        println!("  {id:<8} module {module:<7} per-note {per_note}");
        assert_eq!(module, expected_group(id), "module of {id}");
        assert_eq!(*per_note, matches!(*id, "slide" | "hand"), "{id} modulatable per note id");
    }
}

/// Every choice parameter names every value in the host (`value_to_text` at each step), and the
/// names parse back to their steps (`text_to_value`): what a host lists in a menu. (nice-plug
/// sets neither CLAP's `IS_ENUM` nor VST3's `kIsList`, so a host that needs that flag for a menu
/// still shows a stepped slider, labelled with these names.)
#[test]
fn choice_parameters_name_every_value() {
    let mut p = Plugin::at_48k(&release_bundle(), &[]);
    let choices: [(&str, &[&str]); 7] = [
        ("mode", &["Piano", "Slide"]),
        ("solver", &["QSA", "EXP", "IMP"]),
        ("handsrc", &["Parameter", "Mod wheel", "Channel pressure", "Poly pressure", "CC74 (timbre)"]),
        ("sbody", &["Electric", "Acoustic"]),
        ("follow", &["Off", "On"]),
        ("limit", &["Off", "On"]),
        ("guard", &["Off", "On"]),
    ];
    let params = p.params();
    for (id, names) in choices {
        let shown: Vec<String> = (0..names.len()).map(|step| p.value_text(clap_id(id), step as f64)).collect();
        println!("{id}: {shown:?}");
        assert_eq!(shown, names, "value names of {id}");
        for (step, name) in names.iter().enumerate() {
            let handle = p.instance.plugin_handle();
            let text = CString::new(*name).expect("name");
            let value = params.text_to_value(&handle, ClapId::new(clap_id(id)), &text);
            // The plugin's normalized value times the step count, in f32: a step within 1e-6.
            let parsed = value.unwrap_or_else(|| panic!("{id}: \"{name}\" does not parse"));
            assert!((parsed - step as f64).abs() < 1e-6, "{id}: \"{name}\" parses to {parsed}, not step {step}");
        }
    }
}

// ------------------------------------------------------------------------------------------------
// Presets
// ------------------------------------------------------------------------------------------------

/// The CLAP value that sets parameter `id` to the plain value `plain` of a preset: choices and
/// switches by index, everything else through the plugin's own text-to-value conversion of the
/// number in the unit it shows (`gain` in dB), as a host's text entry does.
fn preset_clap_value(p: &mut Plugin, id: &str, plain: f32) -> f64 {
    if ["mode", "solver", "handsrc", "sbody", "follow", "limit", "guard"].contains(&id) {
        return f64::from(plain);
    }
    let text = if id == "gain" { format!("{}", 20.0 * plain.log10()) } else { format!("{plain}") };
    let value = p.text_value(clap_id(id), &text).unwrap_or_else(|| panic!("{id}: the plugin reads {text:?}"));
    if ["segs", "nb", "voices"].contains(&id) { value.round() } else { value }
}

/// The plain parameter values in a saved state (its `params` object), as preset values: numbers
/// as stored (`gain` linear), choices by their ids, switches on/off.
fn state_values(state: &serde_json::Value) -> qsa_dsp::instrument::ParamValues {
    let mut values = qsa_dsp::instrument::ParamValues::default();
    let params = state["params"].as_object().expect("a params object");
    for (id, ..) in PARAMETERS {
        let stored = params.get(id).unwrap_or_else(|| panic!("the state holds {id}"));
        let text = match (stored.get("f32"), stored.get("i32"), stored.get("bool"), stored.get("string")) {
            (Some(v), ..) if id == "gain" => format!("{}", 20.0 * v.as_f64().unwrap().log10()),
            (Some(v), ..) => v.to_string(),
            (_, Some(v), ..) => v.to_string(),
            (_, _, Some(v), _) => (if v.as_bool().unwrap() { "on" } else { "off" }).to_owned(),
            (_, _, _, Some(v)) => v.as_str().unwrap().to_owned(),
            _ => panic!("{id}: unexpected {stored}"),
        };
        values.set(id, &text).unwrap_or_else(|e| panic!("{id}: {e}"));
    }
    values
}

/// A saved state as JSON (after its 8-byte length).
fn state_json(bytes: &[u8]) -> serde_json::Value {
    serde_json::from_slice(&bytes[8..]).expect("the state is JSON after its length")
}

fn state_bytes(state: &serde_json::Value) -> Vec<u8> {
    let body = serde_json::to_vec(state).expect("JSON");
    [&(body.len() as u64).to_le_bytes()[..], &body].concat()
}

/// Every factory preset survives the plugin's saved state. For each: its values go to a running
/// instance as parameter changes (what the editor's preset menu sends), the state is saved with
/// the preset's id in the persistent `preset` field (which the editor keeps), and loaded into a
/// fresh instance. That instance's parameters are the preset's: the CLAP values equal the first
/// instance's exactly, and the plain values in its own saved state equal the preset's within the
/// f32 normalisation (relative 1e-5), the preset id included; and both instances play a phrase
/// in identical samples.
#[test]
fn every_preset_survives_save_and_load_into_a_fresh_instance() {
    use qsa_dsp::instrument::{Mode, factory_presets};

    let bundle = release_bundle();
    let mut worst = (0.0f64, String::new());
    for preset in factory_presets() {
        let mut first = Plugin::at_48k(&bundle, &[]);
        let changes: Score = PARAMETERS
            .iter()
            .map(|(id, ..)| {
                let plain = preset.values.plain(id).unwrap_or_else(|| panic!("{id} has a plain value"));
                (0, Ev::Param(clap_id(id), preset_clap_value(&mut first, id, plain)))
            })
            .collect();
        let _ = first.render_blocks(&changes, 64, 64);
        let mut state = state_json(&first.save());
        state["fields"]["preset"] = serde_json::json!(serde_json::to_string(&preset.id).unwrap());
        let saved = state_bytes(&state);

        let mut fresh = Plugin::at_48k(&bundle, &[]);
        assert!(fresh.load(&saved), "{}: the state loads", preset.id);
        let _ = fresh.render_blocks(&[], 64, 64);
        for (id, ..) in PARAMETERS {
            let (a, b) = (first.value(clap_id(id)), fresh.value(clap_id(id)));
            assert_eq!(a, b, "{}: CLAP value of {id}", preset.id);
        }
        let resaved = state_json(&fresh.save());
        assert_eq!(resaved["fields"]["preset"], serde_json::json!(format!("\"{}\"", preset.id)), "{}", preset.id);
        let restored = state_values(&resaved);
        for (id, ..) in PARAMETERS {
            let (want, got) = (f64::from(preset.values.plain(id).unwrap()), f64::from(restored.plain(id).unwrap()));
            let error = (got - want).abs() / want.abs().max(1e-3);
            if error > worst.0 {
                worst = (error, format!("{} {id}: {got} for {want}", preset.id));
            }
            assert!(error < 1e-5, "{} {id}: restored {got}, preset {want}", preset.id);
        }

        let score: Score = match preset.values.mode {
            Mode::Piano => vec![(0, Ev::On(0, 60, 0.7)), (100, Ev::On(0, 64, 0.6)), (12_000, Ev::On(0, 67, 0.9))],
            Mode::Slide => vec![(0, Ev::On(0, 52, 0.8)), (14_400, Ev::On(0, 57, 0.8)), (15_000, Ev::Off(0, 52))],
        };
        let a = first.render_blocks(&score, 36_000, 512);
        let b = fresh.render_blocks(&score, 36_000, 512);
        a.assert_finite(&preset.id);
        assert!(a.peak() > AUDIBLE, "{}: the phrase sounds (peak {})", preset.id, a.peak());
        assert_eq!(bit_identical(&a, &b), None, "{}: first differing sample", preset.id);
    }
    println!("largest relative error of a restored plain value: {:.2e} ({})", worst.0, worst.1);
}
