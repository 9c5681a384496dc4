//! `cargo xtask render --midi`: MIDI files through the instrument engine.

use std::path::PathBuf;

use qsa_tests::fundamental;
use xtask::render::{Outcome, RenderArgs, run};

fn scene(name: &str) -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes")).join(name)
}

fn render(args: RenderArgs) -> (Outcome, Vec<f32>, Vec<f32>) {
    let mut stdout = Vec::new();
    let outcome = run(&args, &mut stdout).expect("the MIDI file renders");
    let line = String::from_utf8(stdout).unwrap();
    assert_eq!(line.lines().count(), 1, "one JSON line");
    let json: serde_json::Value = serde_json::from_str(line.trim()).unwrap();
    for key in
        ["scene", "method", "segments", "sample_rate", "samples", "contacts", "peak_force", "wall_seconds", "rtf"]
    {
        assert!(json.get(key).is_some(), "summary has {key}");
    }
    let mut reader = hound::WavReader::open(args.out.as_ref().unwrap()).unwrap();
    assert_eq!(reader.spec().channels, 2);
    let samples: Vec<f32> = reader.samples::<f32>().map(Result::unwrap).collect();
    let left = samples.iter().step_by(2).copied().collect();
    let right = samples.iter().skip(1).step_by(2).copied().collect();
    (outcome, left, right)
}

fn midi_args(file: &str, out: PathBuf) -> RenderArgs {
    RenderArgs { midi: Some(scene(file)), out: Some(out), tail: Some(1.0), ..RenderArgs::default() }
}

/// The piano phrase: every note is played (14), the sound is finite, audible and below full
/// scale, and rendering in calls of 1 or 4096 samples or of seeded random sizes (`--chunk 0`)
/// gives the same samples.
#[test]
fn piano_phrase_renders_the_same_in_any_calls() {
    let dir = tempfile::tempdir().unwrap();
    let (outcome, left, right) =
        render(RenderArgs { chunk: Some(4096), ..midi_args("piano-phrase.mid", dir.path().join("a.wav")) });
    let Outcome::Midi(summary) = outcome else { panic!("a MIDI summary") };
    assert_eq!(summary.contacts, 14);
    let peak = left.iter().chain(&right).fold(0.0f32, |m, v| m.max(v.abs()));
    assert!(left.iter().chain(&right).all(|v| v.is_finite()) && peak > 0.05 && peak < 1.0, "peak {peak}");
    for (chunk, name) in [(1, "b.wav"), (0, "c.wav")] {
        let (_, other_left, other_right) =
            render(RenderArgs { chunk: Some(chunk), ..midi_args("piano-phrase.mid", dir.path().join(name)) });
        let same =
            |a: &[f32], b: &[f32]| a.len() == b.len() && a.iter().zip(b).all(|(a, b)| a.to_bits() == b.to_bits());
        assert!(same(&other_left, &left) && same(&other_right, &right), "--chunk {chunk}");
    }
}

/// The slide phrase in slide mode: its first note (E3) sounds at 164.8 Hz within 1 %.
#[test]
fn slide_phrase_plays_in_slide_mode() {
    let dir = tempfile::tempdir().unwrap();
    let args = RenderArgs { mode: Some("slide".into()), ..midi_args("slide-phrase.mid", dir.path().join("s.wav")) };
    let (_, left, _) = render(args);
    let first: Vec<f64> = left[4_800..28_000].iter().map(|&v| f64::from(v)).collect();
    let f = fundamental(&first, 48_000.0, 130.0, 200.0);
    assert!((f / 164.81 - 1.0).abs() < 0.01, "E3 at {f} Hz");
}

/// Bad input is an error naming what is wrong, and writes nothing: not a MIDI file, one cut short
/// (a note's track ending before its header says) or with a corrupt event, a header of 0 ticks per
/// quarter note or (SMPTE) per frame, a tempo of 0, a tempo event shorter than its 3 bytes, a file
/// beyond 16 MiB, a render of more samples than the renderer holds (590 s at 768 kHz, 3.6 GB), an
/// unknown parameter id, a value that is not a number.
#[test]
fn bad_midi_input_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let file = |name: &str, bytes: &[u8]| {
        let path = dir.path().join(name);
        std::fs::write(&path, bytes).unwrap();
        path
    };
    let junk = file("junk.mid", b"this is not a MIDI file");
    let note = [0, 0x90, 60, 100, 0x60, 0x80, 60, 0, 0, 0xff, 0x2f, 0];
    let whole = smf(&note);
    let cut = file("cut.mid", &whole[..whole.len() - 4]);
    let corrupt = file("corrupt.mid", &smf(&[0, 0x90, 0xc8, 100, 0x60, 0x80, 60, 0, 0, 0xff, 0x2f, 0]));
    let mut untimed = whole.clone();
    untimed[12..14].copy_from_slice(&[0, 0]);
    let untimed = file("untimed.mid", &untimed);
    let stopped = file("stopped.mid", &smf(&[0, 0xff, 0x51, 3, 0, 0, 0, 0, 0x90, 60, 100, 0, 0xff, 0x2f, 0]));
    let short_tempo = file("short.mid", &smf(&[0, 0xff, 0x51, 2, 0x0f, 0x42, 0, 0x90, 60, 100, 0, 0xff, 0x2f, 0]));
    let mut frameless = whole.clone();
    frameless[12..14].copy_from_slice(&[0xe7, 0]);
    let frameless = file("frameless.mid", &frameless);
    let mut huge = whole.clone();
    huge.resize(16 * 1024 * 1024 + 1, 0);
    let huge = file("huge.mid", &huge);
    let midi = |path: &std::path::Path, out: &str| RenderArgs {
        midi: Some(path.to_owned()),
        out: Some(dir.path().join(out)),
        ..RenderArgs::default()
    };
    let cases = [
        (midi(&cut, "cut.wav"), "malformed"),
        (midi(&corrupt, "corrupt.wav"), "malformed"),
        (midi(&untimed, "untimed.wav"), "0 ticks per quarter note"),
        (midi(&stopped, "stopped.wav"), "tempo of 0"),
        (midi(&short_tempo, "short.wav"), "a tempo event of 2 bytes"),
        (midi(&frameless, "frameless.wav"), "0 ticks per frame"),
        (midi(&huge, "huge-file.wav"), "more than 16777216 bytes"),
        (
            RenderArgs { rate: Some(768_000), tail: Some(590.0), ..midi(&file("whole.mid", &whole), "huge.wav") },
            "at most 6e7",
        ),
        (
            RenderArgs { midi: Some(junk.clone()), out: Some(dir.path().join("1.wav")), ..RenderArgs::default() },
            "not a MIDI file",
        ),
        (RenderArgs { set: vec!["kapa=3".into()], ..midi_args("piano-phrase.mid", dir.path().join("2.wav")) }, "kapa"),
        (
            RenderArgs { set: vec!["hard=lots".into()], ..midi_args("piano-phrase.mid", dir.path().join("3.wav")) },
            "hard",
        ),
        (
            RenderArgs { set: vec!["hard".into()], ..midi_args("piano-phrase.mid", dir.path().join("4.wav")) },
            "ID=VALUE",
        ),
    ];
    for (args, needle) in cases {
        let out = args.out.clone().unwrap();
        let err = run(&args, &mut Vec::new()).expect_err(needle).to_string();
        assert!(err.contains(needle), "error for {needle}: {err}");
        assert!(!out.exists(), "no output for {needle}");
    }
}

/// A standard MIDI file with one track holding `body` (the track's bytes).
fn smf(body: &[u8]) -> Vec<u8> {
    let mut out = b"MThd\0\0\0\x06\0\0\0\x01\x01\xe0MTrk".to_vec();
    out.extend_from_slice(&(body.len() as u32).to_be_bytes());
    out.extend_from_slice(body);
    out
}

/// A MIDI file with garbage events renders safely or is refused with a clear error, and never
/// panics, hangs or writes a non-finite sample: (1) well-formed tracks of random channel
/// messages (notes on every channel with any key and velocity, controllers including the
/// sustain pedal and all-notes-off, pitch bends, pressures, program changes), system-exclusive
/// messages, unknown meta events and extreme tempo changes (1 µs to 16.7 s per quarter note);
/// (2) tracks of random bytes; (3) a track shorter than its header says. Seeded.
#[test]
fn midi_files_with_garbage_events_render_safely_or_are_refused() {
    use rand::RngExt;
    let dir = tempfile::tempdir().unwrap();
    let mut rng = qsa_tests::seeded_rng(0x6a7b);
    let mut files: Vec<(String, Vec<u8>)> = Vec::new();
    for f in 0..3 {
        let mut body = Vec::new();
        for _ in 0..600 {
            body.push(rng.random_range(0..40u8)); // delta time, one byte
            match rng.random_range(0..10) {
                0 => body.extend_from_slice(&[0xf0, 3, rng.random(), rng.random(), 0xf7]),
                // Unknown meta events (a tempo's type, 0x51, given two bytes would be corrupt).
                1 => {
                    let kind = rng.random_range(0x10..0x7f);
                    body.extend_from_slice(&[
                        0xff,
                        if kind == 0x51 { 0x52 } else { kind },
                        2,
                        rng.random(),
                        rng.random(),
                    ]);
                }
                2 => {
                    let tempo: u32 = if rng.random_bool(0.5) { 1 } else { 0x00ff_ffff };
                    body.extend_from_slice(&[0xff, 0x51, 3]);
                    body.extend_from_slice(&tempo.to_be_bytes()[1..]);
                }
                _ => {
                    let status = rng.random_range(0x80..=0xefu8);
                    body.push(status);
                    body.push(rng.random_range(0..128u8));
                    if !matches!(status & 0xf0, 0xc0 | 0xd0) {
                        body.push(rng.random_range(0..128u8));
                    }
                }
            }
        }
        body.extend_from_slice(&[0, 0xff, 0x2f, 0]);
        files.push((format!("structured-{f}"), smf(&body)));
        let noise: Vec<u8> = (0..2000).map(|_| rng.random()).collect();
        files.push((format!("noise-{f}"), smf(&noise)));
    }
    let mut short = smf(&[0, 0x90, 60, 100, 0x60, 0x80, 60, 0]);
    short.truncate(short.len() - 3);
    files.push(("truncated".into(), short));
    let (mut rendered, mut refused) = (0, 0);
    for (name, bytes) in files {
        let path = dir.path().join(format!("{name}.mid"));
        std::fs::write(&path, &bytes).unwrap();
        let out = dir.path().join(format!("{name}.wav"));
        let args = RenderArgs { midi: Some(path), out: Some(out.clone()), tail: Some(0.5), ..RenderArgs::default() };
        match run(&args, &mut Vec::new()) {
            Ok(_) => {
                let mut reader = hound::WavReader::open(&out).unwrap();
                let samples: Vec<f32> = reader.samples::<f32>().map(Result::unwrap).collect();
                assert!(samples.iter().all(|v| v.is_finite()), "{name}: a non-finite sample");
                rendered += 1;
            }
            Err(e) => {
                let message = e.to_string();
                println!("{name}: refused: {message}");
                assert!(!message.is_empty() && !out.exists(), "{name}: a clear error and no output");
                refused += 1;
            }
        }
    }
    println!("{rendered} rendered, {refused} refused");
    assert!(rendered >= 3, "the well-formed files with garbage events render");
}

/// The summary line of a MIDI render holds every key of a scene render's (in the same order,
/// `null` where a MIDI render does not measure it), so that one reader takes both.
#[test]
fn a_midi_summary_has_every_key_of_a_scene_summary() {
    let dir = tempfile::tempdir().unwrap();
    let keys = |args: RenderArgs| {
        let mut stdout = Vec::new();
        run(&args, &mut stdout).expect("renders");
        let line = String::from_utf8(stdout).unwrap();
        let json: serde_json::Value = serde_json::from_str(&line).unwrap();
        // In the order the line gives them (the parsed map sorts them).
        let mut keys: Vec<String> = json.as_object().unwrap().keys().cloned().collect();
        keys.sort_by_key(|k| line.find(&format!("\"{k}\":")));
        keys
    };
    let scene_keys = keys(RenderArgs {
        scene: Some(scene("fig4-mass-barrier.toml")),
        out: Some(dir.path().join("scene.wav")),
        ..RenderArgs::default()
    });
    let midi_keys = keys(midi_args("piano-phrase.mid", dir.path().join("midi.wav")));
    let shared: Vec<&String> = midi_keys.iter().filter(|k| scene_keys.contains(k)).collect();
    assert_eq!(shared, scene_keys.iter().collect::<Vec<_>>(), "MIDI summary keys {midi_keys:?}");
}

/// The tracks of a format 2 file are independent patterns and play one after another: of two
/// tracks, each a quarter note (0.5 s at the default tempo), the second starts where the first
/// ended, at 24,000 samples at 48 kHz, not with it. Those of a format 1 file play together.
#[test]
fn the_tracks_of_a_format_2_file_play_one_after_another() {
    use xtask::render::midi::timed_messages;
    let track = |key: u8| {
        let body = [0, 0x90, key, 100, 0x83, 0x60, 0x80, key, 0, 0, 0xff, 0x2f, 0];
        let mut out = b"MTrk".to_vec();
        out.extend_from_slice(&(body.len() as u32).to_be_bytes());
        out.extend_from_slice(&body);
        out
    };
    let file = |format: u8| {
        let mut out = b"MThd\0\0\0\x06\0".to_vec();
        out.extend_from_slice(&[format, 0, 2, 0x01, 0xe0]);
        out.extend(track(60));
        out.extend(track(64));
        out
    };
    let note_on = |messages: &[(u64, [u8; 3])], key: u8| {
        messages.iter().find(|(_, m)| m[0] == 0x90 && m[1] == key).map(|&(at, _)| at)
    };
    let sequential = timed_messages(&file(2), 48_000.0).unwrap();
    assert_eq!((note_on(&sequential, 60), note_on(&sequential, 64)), (Some(0), Some(24_000)));
    let together = timed_messages(&file(1), 48_000.0).unwrap();
    assert_eq!((note_on(&together, 60), note_on(&together, 64)), (Some(0), Some(0)));
}

/// With no tail, the render still reaches the last event's sample: the last note the summary
/// counts is handed to the engine rather than left past the end.
#[test]
fn a_render_without_a_tail_reaches_the_last_event() {
    use xtask::render::midi::{render, score};
    let bytes = smf(&[0x83, 0x60, 0x90, 60, 100, 0, 0xff, 0x2f, 0]);
    let score = score(&bytes, 48_000.0).unwrap();
    assert_eq!((score.notes, score.events.last().map(|e| e.0)), (1, Some(24_000)));
    let (left, right, _) = render(&score, &Default::default(), 48_000.0, 0.0, 512);
    assert_eq!((left.len(), right.len()), (24_001, 24_001));
}

/// The render lasts until the file's last event of any kind, not its last note: a volume
/// controller the engine ignores (at 2 s) and the end of the track (at 4 s, where a sequencer
/// closes the last bar) each carry it on, 4 s and one sample at 48 kHz with no tail.
#[test]
fn a_render_lasts_until_the_files_last_event_of_any_kind() {
    use xtask::render::midi::{render, score};
    // 480 ticks a quarter note at 120 bpm: the note lasts 480 ticks (0.5 s); 0x8b 0x20 is 1440
    // ticks more (to 2 s), 0x8f 0x00 1920 more (to 4 s).
    let note = [0, 0x90, 60, 100, 0x83, 0x60, 0x80, 60, 0];
    let volume = [0x8b, 0x20, 0xb0, 7, 90];
    let end = [0x8f, 0x00, 0xff, 0x2f, 0];
    let bytes = smf(&[&note[..], &volume, &end].concat());
    let score = score(&bytes, 48_000.0).unwrap();
    assert_eq!(score.events.last().map(|e| e.0), Some(24_000), "the note-off is the last engine event");
    assert_eq!(score.end, 192_000);
    let (left, right, _) = render(&score, &Default::default(), 48_000.0, 0.0, 512);
    assert_eq!((left.len(), right.len()), (192_001, 192_001));
    let (left, _, _) = render(&score, &Default::default(), 48_000.0, 0.5, 512);
    assert_eq!(left.len(), 216_000);
}
