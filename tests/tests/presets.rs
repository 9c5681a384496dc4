//! The factory presets through the instrument engine: every preset plays a phrase safely, and the
//! presets sound as their descriptions say, measured: brightness (spectral centroid), decay, pitch
//! and the rattle of the attack, one preset against another.
//!
//! Each render is the engine the plugin runs ([`Instrument`] with `preset.values.settings()`),
//! at 48 kHz, with the events at fixed samples.

use qsa_dsp::instrument::{Event, Instrument, ParamValues, Preset, factory_presets, find_preset};
use qsa_tests::fundamental;
use rustfft::FftPlanner;
use rustfft::num_complex::Complex;

const FS: f64 = 48_000.0;

/// Render `events` (time in s, event) for `seconds` with `values`; the left channel.
fn render(values: &ParamValues, events: &[(f64, Event)], seconds: f64) -> Vec<f64> {
    let samples = (seconds * FS) as usize;
    let mut engine = Instrument::new(FS, values.voices.clamp(1, 128) as usize, values.settings());
    // The dry signals: what a preset sets (strings, hammer, slide); the soundboard's radiation,
    // the pan and the pickup's circuit are common to every preset (tests/tests/radiation.rs).
    engine.set_raw_output(true);
    let (mut left, mut right) = (vec![0.0f32; samples], vec![0.0f32; samples]);
    let mut t = 0;
    let mut next = 0;
    while t < samples {
        while next < events.len() && (events[next].0 * FS) as usize <= t {
            engine.handle(events[next].1);
            next += 1;
        }
        let until = events.get(next).map_or(samples, |e| ((e.0 * FS) as usize).clamp(t + 1, samples));
        engine.process(&mut left[t..until], &mut right[t..until]);
        t = until;
    }
    left.iter().map(|&v| f64::from(v)).collect()
}

fn on(key: u8, velocity: f32) -> Event {
    Event::NoteOn { channel: 0, key, velocity }
}

fn off(key: u8) -> Event {
    Event::NoteOff { channel: 0, key }
}

/// A short phrase for either mode: two legato notes with a bend, the mod wheel raised half-way
/// with the second, a fortissimo four-note chord under the pedal, then a note with the mod wheel
/// all the way up (where the mod wheel is the hand, the first note sounds the open string, the
/// slide rattles on the second and the chord, and presses on the last).
fn phrase() -> Vec<(f64, Event)> {
    let bend = |t, value| (t, Event::PitchBend { channel: 0, value });
    let mut events = vec![
        (0.0, on(52, 0.8)),
        (0.3, Event::ModWheel { channel: 0, value: 0.5 }),
        (0.3, on(55, 0.7)),
        (0.32, off(52)),
        bend(0.45, 0.5),
        bend(0.55, -0.5),
        bend(0.65, 0.0),
        (0.7, off(55)),
        (0.8, Event::Sustain { channel: 0, depth: 1.0 }),
    ];
    events.extend([48, 60, 67, 76].map(|k| (0.8, on(k, 1.0))));
    events.extend([48, 60, 67, 76].map(|k| (1.2, off(k))));
    events.extend([
        (1.4, Event::Sustain { channel: 0, depth: 0.0 }),
        (1.5, Event::ModWheel { channel: 0, value: 1.0 }),
        (1.55, on(57, 1.0)),
    ]);
    events
}

fn peak(x: &[f64]) -> f64 {
    x.iter().fold(0.0f64, |m, v| m.max(v.abs()))
}

fn db(x: f64) -> f64 {
    20.0 * x.log10()
}

fn rms(x: &[f64]) -> f64 {
    (x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64).sqrt()
}

/// Seconds `a..b` of `x`.
fn window(x: &[f64], a: f64, b: f64) -> &[f64] {
    &x[(a * FS) as usize..((b * FS) as usize).min(x.len())]
}

/// Energy-weighted mean frequency of `x` (Hz), Hann-windowed.
fn centroid(x: &[f64]) -> f64 {
    let n = x.len();
    let mut buffer: Vec<Complex<f64>> = x
        .iter()
        .enumerate()
        .map(|(i, &v)| Complex::new(v * (0.5 - 0.5 * (std::f64::consts::TAU * i as f64 / n as f64).cos()), 0.0))
        .collect();
    FftPlanner::new().plan_fft_forward(n).process(&mut buffer);
    let (mut weighted, mut total) = (0.0, 0.0);
    for (k, c) in buffer.iter().take(n / 2 + 1).enumerate() {
        weighted += c.norm_sqr() * k as f64 * FS / n as f64;
        total += c.norm_sqr();
    }
    weighted / total
}

/// Time (s) at which the 20 ms RMS envelope of `x` first falls `drop_db` below its maximum.
fn decay_time(x: &[f64], drop_db: f64) -> f64 {
    let n = (0.02 * FS) as usize;
    let envelope: Vec<f64> = x.chunks_exact(n).map(rms).collect();
    let top = envelope.iter().fold(0.0f64, |m, &v| m.max(v));
    let start = envelope.iter().position(|&v| v == top).unwrap_or(0);
    let below = envelope[start..].iter().position(|&v| db(v / top) < -drop_db);
    below.map_or(x.len() as f64 / FS, |i| (start + i) as f64 * 0.02)
}

/// How periodic `x` is: the largest normalised autocorrelation at lags of 60..700 Hz (1 is a
/// steady tone; a rattle lowers it).
fn periodicity(x: &[f64]) -> f64 {
    let r = |lag: usize| x.iter().zip(&x[lag..]).map(|(a, b)| a * b).sum::<f64>();
    let r0 = r(0);
    ((FS / 700.0) as usize..=(FS / 60.0) as usize).map(|lag| r(lag) / r0).fold(f64::NEG_INFINITY, f64::max)
}

fn preset(id: &str) -> &'static Preset {
    find_preset(id).unwrap_or_else(|| panic!("no factory preset {id}"))
}

/// A held C4 (velocity 0.8) for 3 s.
fn piano_note(id: &str) -> Vec<f64> {
    render(&preset(id).values, &[(0.0, on(60, 0.8))], 3.0)
}

/// A held `key` (velocity 0.8) for 1.2 s on the slide guitar (A3, 57: the slide stops the open A2
/// string an octave up).
fn slide_note(id: &str, key: u8) -> Vec<f64> {
    render(&preset(id).values, &[(0.0, on(key, 0.8))], 1.2)
}

/// Every factory preset plays the phrase (legato notes, a bend, a fortissimo chord under the pedal,
/// the mod wheel) with finite samples, audibly (peak above −40 dBFS), and below +12 dBFS with the
/// safety limiter switched off, so that none depends on the limiter to stay sane.
#[test]
fn every_preset_renders_a_phrase_finite_and_below_12_dbfs() {
    let presets = factory_presets();
    assert!(presets.len() >= 16);
    for p in presets {
        let values = ParamValues { limiter: false, ..p.values };
        let x = render(&values, &phrase(), 2.2);
        assert!(x.iter().all(|v| v.is_finite()), "{}: non-finite output", p.id);
        let level = db(peak(&x));
        println!("{:18} peak {level:+6.1} dBFS, rms {:+6.1} dBFS", p.id, db(rms(&x)));
        assert!(level < 12.0, "{}: peak {level:.1} dBFS", p.id);
        assert!(level > -40.0, "{}: peak {level:.1} dBFS is nearly silent", p.id);
    }
}

/// The piano presets differ as their descriptions say, on a held C4: bright above dark and steel
/// above cotton in spectral centroid (first 0.3 s), felt below the Fig. 5 hammer; the concert
/// grand rings longer than the upright, and the paper's soft-hammer example (damping ×16, η0 = 8 1/s at C4) dies
/// far sooner than the Fig. 5 string.
#[test]
fn piano_presets_differ_in_brightness_and_decay_as_described() {
    let ids = [
        "fig5-hammer",
        "concert-grand",
        "felt-piano",
        "bright-piano",
        "dark-piano",
        "upright",
        "tack-piano",
        "bell-strings",
        "soft-hammer",
        "steel-hammer",
        "cotton-hammer",
    ];
    let measured: Vec<(f64, f64)> = ids
        .iter()
        .map(|id| {
            let x = piano_note(id);
            let m = (centroid(window(&x, 0.0, 0.3)), decay_time(&x, 20.0));
            println!("{id:14} centroid {:6.0} Hz, −20 dB after {:.2} s", m.0, m.1);
            m
        })
        .collect();
    let get = |id: &str| measured[ids.iter().position(|i| *i == id).unwrap()];
    let ratio = |a: &str, b: &str, which: fn((f64, f64)) -> f64| which(get(a)) / which(get(b));
    let brightness = |m: (f64, f64)| m.0;
    let decay = |m: (f64, f64)| m.1;
    for (a, b, min) in [
        ("bright-piano", "dark-piano", 1.6),
        ("steel-hammer", "cotton-hammer", 2.5),
        ("fig5-hammer", "felt-piano", 1.25),
        ("tack-piano", "fig5-hammer", 1.3),
    ] {
        let r = ratio(a, b, brightness);
        assert!(r > min, "{a} is brighter than {b}: centroid ratio {r:.2}, wanted > {min}");
    }
    for (a, b, min) in [("concert-grand", "upright", 2.0), ("fig5-hammer", "soft-hammer", 4.0)] {
        let r = ratio(a, b, decay);
        assert!(r > min, "{a} rings longer than {b}: decay ratio {r:.2}, wanted > {min}");
    }
}

/// The slide presets differ as described, on a held A3 (E3 for the attack): the very soft contact lets the slide sink
/// in, so the note is flat and dies fast, where the paper's set-up sounds at pitch; the very stiff,
/// hard-pressed slide picked at the bridge is far brighter; the dobro rattle's attack is much
/// less periodic than the bottleneck's.
#[test]
fn slide_presets_differ_in_pitch_brightness_and_rattle_as_described() {
    let reference = slide_note("slide-phrase", 57);
    let soft = slide_note("soft-slide", 57);
    let pitch = |x: &[f64]| fundamental(window(x, 0.1, 0.5), FS, 180.0, 260.0);
    let fall = |x: &[f64]| db(rms(window(x, 0.5, 0.6)) / rms(window(x, 0.1, 0.2)));
    let (f_ref, f_soft) = (pitch(&reference), pitch(&soft));
    let cents = 1200.0 * (f_soft / f_ref).log2();
    println!("pitch: slide-phrase {f_ref:.2} Hz, soft-slide {f_soft:.2} Hz ({cents:+.0} cents)");
    println!("fall 0.15 → 0.55 s: slide-phrase {:.1} dB, soft-slide {:.1} dB", fall(&reference), fall(&soft));
    assert!((f_ref / 220.0 - 1.0).abs() < 0.01, "the paper's set-up plays A3 at 220 Hz: {f_ref}");
    assert!(cents < -15.0, "the soft contact plays flat: {cents:.0} cents");
    assert!(fall(&soft) < fall(&reference) - 6.0, "the soft contact dies faster");

    let stiff = slide_note("stiff-slide", 57);
    let (c_ref, c_stiff) = (centroid(window(&reference, 0.0, 0.5)), centroid(window(&stiff, 0.0, 0.5)));
    println!("centroid: slide-phrase {c_ref:.0} Hz, stiff-slide {c_stiff:.0} Hz");
    assert!(c_stiff > 1.5 * c_ref, "the stiff slide at the bridge is brighter");

    let attack = |id: &str| periodicity(window(&slide_note(id, 52), 0.0, 0.1));
    let (bottleneck, dobro) = (attack("bottleneck"), attack("dobro-rattle"));
    println!("attack periodicity: bottleneck {bottleneck:.2}, dobro-rattle {dobro:.2}");
    assert!(bottleneck > 0.85, "a pressed slide's attack is a tone: {bottleneck:.2}");
    assert!(dobro < bottleneck - 0.2, "the dobro's attack rattles: {dobro:.2}");
}

/// The Fig. 5 hammer with the Newton reference (IMP) sounds like the QSA one: the same centroid
/// within 1 % and level within 0.1 dB (the paper's point: the QSA needs no iterations to match).
#[test]
fn the_imp_reference_preset_sounds_like_the_qsa_one() {
    let (qsa, imp) = (piano_note("fig5-hammer"), piano_note("fig5-hammer-imp"));
    let (cq, ci) = (centroid(window(&qsa, 0.0, 0.3)), centroid(window(&imp, 0.0, 0.3)));
    let level = db(rms(&imp) / rms(&qsa));
    println!("centroid QSA {cq:.1} Hz, IMP {ci:.1} Hz; level IMP − QSA {level:+.3} dB");
    assert!((ci / cq - 1.0).abs() < 0.01 && level.abs() < 0.1);
}

/// No two presets sound alike (but for the IMP twin of the Fig. 5 hammer, which must not differ):
/// on the phrase, every pair differs by more than a listener's threshold in at least one of
/// brightness (spectral centroid, 5 %), level (RMS, 1.5 dB) or sustain (the chord's ring after the
/// pedal lifts relative to its onset, 3 dB).
#[test]
fn every_pair_of_presets_sounds_different() {
    let presets = factory_presets();
    let prints: Vec<[f64; 3]> = presets
        .iter()
        .map(|p| {
            let x = render(&p.values, &phrase(), 2.2);
            let sustain = db(rms(window(&x, 1.4, 1.55)) / rms(window(&x, 0.8, 0.95)));
            let print = [centroid(&x).log2(), db(rms(&x)), sustain];
            println!(
                "{:18} centroid {:6.0} Hz, rms {:+6.1} dBFS, sustain {:+6.1} dB",
                p.id,
                centroid(&x),
                print[1],
                sustain
            );
            print
        })
        .collect();
    let thresholds = [(1.05f64).log2(), 1.5, 3.0];
    let mut closest = (f64::INFINITY, "", "");
    for i in 0..presets.len() {
        for j in i + 1..presets.len() {
            let (a, b) = (&presets[i].id, &presets[j].id);
            // How many thresholds apart they are in their most different feature.
            let apart = (0..3).map(|k| (prints[i][k] - prints[j][k]).abs() / thresholds[k]).fold(0.0, f64::max);
            if (a.as_str(), b.as_str()) == ("fig5-hammer", "fig5-hammer-imp") {
                assert!(apart < 0.2, "the IMP twin sounds like the QSA Fig. 5 hammer: {apart:.2}");
                continue;
            }
            if apart < closest.0 {
                closest = (apart, a, b);
            }
            assert!(apart > 1.0, "{a} and {b} sound alike: {apart:.2} thresholds apart at most");
        }
    }
    println!("closest pair: {} and {}, {:.2} thresholds apart", closest.1, closest.2, closest.0);
}

// ------------------------------------------------------------------------------------------------
// The command line: `render --midi --preset`, `presets`, `examples`
// ------------------------------------------------------------------------------------------------

fn scenes() -> std::path::PathBuf {
    std::path::PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes"))
}

/// Run `cargo xtask ARGS` in-process: exit code, stdout, stderr.
fn xtask(args: &[&str]) -> (i32, String, String) {
    let (mut out, mut err) = (Vec::new(), Vec::new());
    let code = xtask::run(args.iter().map(std::ffi::OsString::from), &mut out, &mut err);
    (code, String::from_utf8(out).unwrap(), String::from_utf8(err).unwrap())
}

/// The stereo samples of a float WAV.
fn wav_samples(path: &std::path::Path) -> Vec<f32> {
    hound::WavReader::open(path).unwrap().samples::<f32>().map(Result::unwrap).collect()
}

/// `render --midi --preset` plays the preset's values (found by id or display name), and
/// `--mode` and `--set` apply on top: the WAV equals the MIDI renderer given the preset's values
/// with those changes, sample for sample.
#[test]
fn render_with_a_preset_plays_its_values_and_set_overrides_them() {
    use xtask::render::midi;

    let dir = tempfile::tempdir().unwrap();
    let midi_file = scenes().join("slide-phrase.mid");
    let out = |name: &str| dir.path().join(name).to_string_lossy().into_owned();
    let render_args = |preset: &str, wav: &str, extra: &[&str]| {
        let mut args = vec!["render", "--midi", midi_file.to_str().unwrap(), "--preset", preset, "--tail", "0.5"];
        args.extend_from_slice(extra);
        args.extend(["--out", wav]);
        args.into_iter().map(str::to_owned).collect::<Vec<_>>()
    };
    let run = |args: Vec<String>| {
        let refs: Vec<&str> = args.iter().map(String::as_str).collect();
        let (code, _, err) = xtask(&refs);
        assert_eq!(code, 0, "{err}");
    };
    let (by_id, by_name, changed) = (out("id.wav"), out("name.wav"), out("changed.wav"));
    run(render_args("lap-steel", &by_id, &[]));
    run(render_args("Lap Steel", &by_name, &[]));
    run(render_args("lap-steel", &changed, &["--mode", "piano", "--set", "hard=2", "--set", "gain=-6"]));

    let bytes = std::fs::read(&midi_file).unwrap();
    let score = midi::score(&bytes, 48_000.0).unwrap();
    let interleave =
        |(l, r, _): (Vec<f32>, Vec<f32>, f64)| -> Vec<f32> { l.iter().zip(&r).flat_map(|(a, b)| [*a, *b]).collect() };
    let preset = find_preset("lap-steel").unwrap().values;
    let expected = interleave(midi::render(&score, &preset, 48_000.0, 0.5, 512));
    assert_eq!(wav_samples(std::path::Path::new(&by_id)), expected, "--preset lap-steel");
    assert_eq!(wav_samples(std::path::Path::new(&by_name)), expected, "--preset \"Lap Steel\"");
    let mut overridden = preset;
    for (id, value) in [("mode", "piano"), ("hard", "2"), ("gain", "-6")] {
        overridden.set(id, value).unwrap();
    }
    let expected = interleave(midi::render(&score, &overridden, 48_000.0, 0.5, 512));
    assert_eq!(wav_samples(std::path::Path::new(&changed)), expected, "--preset with --mode and --set");
}

/// An unknown preset is an error that lists every factory preset, and writes nothing.
#[test]
fn an_unknown_preset_is_refused_with_the_list_of_presets() {
    let dir = tempfile::tempdir().unwrap();
    let wav = dir.path().join("x.wav");
    let midi_file = scenes().join("piano-phrase.mid");
    let args = ["render", "--midi", midi_file.to_str().unwrap(), "--preset", "banjo", "--out", wav.to_str().unwrap()];
    let (code, _, err) = xtask(&args);
    assert_eq!(code, 1);
    assert!(err.contains("--preset banjo: no such preset; the factory presets are: "), "{err}");
    for p in factory_presets() {
        assert!(err.contains(&p.id), "the list names {}: {err}", p.id);
    }
    assert!(!wav.exists());
}

/// `cargo xtask presets` prints a header and one line per preset: id, category, name and
/// description, in the menu's order.
#[test]
fn the_presets_command_lists_id_category_and_description() {
    let (code, out, err) = xtask(&["presets"]);
    assert_eq!(code, 0, "{err}");
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines.len(), factory_presets().len() + 1);
    assert!(lines[0].starts_with("id "), "{}", lines[0]);
    for (line, p) in lines[1..].iter().zip(factory_presets()) {
        let words: Vec<&str> = line.split_whitespace().collect();
        assert_eq!((words[0], words[1]), (p.id.as_str(), p.category.as_str()), "{line}");
        assert!(line.ends_with(&format!("{}: {}", p.name, p.description)), "{line}");
    }
}

/// `cargo xtask presets --vst3 DIR` lists the presets, then writes one VST3 preset file per preset
/// into DIR (made if missing) under its name and says how many; `--force` without `--vst3` is a
/// usage error.
#[test]
fn the_presets_command_writes_vst3_preset_files_when_asked() {
    let dir = std::env::temp_dir().join(format!("qsa-presets-command-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let (code, out, err) = xtask(&["presets", "--vst3", dir.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    let count = factory_presets().len();
    assert_eq!(out.lines().count(), count + 2, "{out}");
    assert!(out.ends_with(&format!("wrote {count} VST3 presets to {}\n", dir.display())), "{out}");
    for p in factory_presets() {
        let file = std::fs::read(dir.join(format!("{}.vstpreset", p.name))).unwrap();
        assert_eq!(file, xtask::presets::vst3_preset(p), "{}", p.id);
    }
    std::fs::remove_dir_all(&dir).unwrap();
    let (code, _, err) = xtask(&["presets", "--force"]);
    assert_eq!(code, 2, "a usage error");
    assert!(err.contains("--vst3"), "{err}");
}

/// `cargo xtask examples` writes, per showcase (every category's, the slide's electric and
/// acoustic guitar), a stereo 16-bit WAV at 32 kHz under 500 kB peaking at −1 dBFS and its
/// spectrogram PNG, and a README linking them all; a second run gives the same bytes
/// (deterministic). The examples are heard as the plugin plays them: the electric guitar's pickup
/// in the centre (the channels the same), the acoustic guitar's body across the picture (its
/// channels correlated at most 0.9, as its D3 in the stereo test of `slide_body.rs`).
#[test]
fn the_examples_command_writes_a_stereo_wav_and_spectrogram_per_showcase() {
    use xtask::examples::SHOWCASES;

    let runs: Vec<tempfile::TempDir> = (0..2).map(|_| tempfile::tempdir().unwrap()).collect();
    let scenes = scenes();
    for dir in &runs {
        let args = ["examples", "--out", dir.path().to_str().unwrap(), "--scenes", scenes.to_str().unwrap()];
        let (code, out, err) = xtask(&args);
        assert_eq!(code, 0, "{err}");
        assert_eq!(out.lines().count(), SHOWCASES.len(), "{out}");
    }
    let readme = std::fs::read_to_string(runs[0].path().join("README.md")).unwrap();
    for s in SHOWCASES {
        let wav = runs[0].path().join(format!("{}.wav", s.preset));
        let png = runs[0].path().join(format!("{}.png", s.preset));
        let size = std::fs::metadata(&wav).unwrap().len();
        let mut reader = hound::WavReader::open(&wav).unwrap();
        let spec = reader.spec();
        assert_eq!((spec.channels, spec.bits_per_sample, spec.sample_rate), (2, 16, 32_000), "{}", s.preset);
        let samples: Vec<i16> = reader.samples::<i16>().map(Result::unwrap).collect();
        let (left, right): (Vec<f64>, Vec<f64>) =
            samples.chunks_exact(2).map(|f| (f64::from(f[0]) / 32767.0, f64::from(f[1]) / 32767.0)).unzip();
        let peak = left.iter().chain(&right).map(|v| v.abs()).fold(0.0, f64::max);
        let correlation = xtask::examples::correlation(&left, &right);
        println!(
            "{}: {size} bytes, {:.2} s, peak {:.2} dBFS, channels correlated {correlation:.3}",
            s.preset,
            left.len() as f64 / 32e3,
            db(peak)
        );
        assert!(size < 500_000, "{}: {size} bytes", s.preset);
        assert!((db(peak) + 1.0).abs() < 0.01, "{}: peak {:.3} dBFS", s.preset, db(peak));
        match s.preset {
            "lap-steel" => assert_eq!(left, right, "the electric guitar is heard in the centre"),
            "acoustic-slide" => assert!(correlation <= 0.9, "the acoustic guitar's channels correlate {correlation}"),
            _ => {}
        }
        let image = std::fs::read(&png).unwrap();
        assert_eq!(&image[..8], b"\x89PNG\r\n\x1a\n", "{}: a PNG", s.preset);
        assert!(readme.contains(&format!("]({}.wav)", s.preset)) && readme.contains(&format!("]({}.png)", s.preset)));
        for file in [format!("{}.wav", s.preset), format!("{}.png", s.preset)] {
            let again = std::fs::read(runs[1].path().join(&file)).unwrap();
            assert!(std::fs::read(runs[0].path().join(&file)).unwrap() == again, "{file} differs between runs");
        }
    }
    assert_eq!(readme, std::fs::read_to_string(runs[1].path().join("README.md")).unwrap());
}
