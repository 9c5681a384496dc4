//! The piano's unisons on their bridge against what measured pianos show: a key's partials decay
//! in two stages, a prompt sound and an aftersound, when the strings of its unison are slightly
//! mistuned, and in one stage when they are tuned exactly alike (Weinreich, JASA 62(6), 1977:
//! the strings moving together drain into the bridge fast, their antisymmetric motion, which only
//! the mistuning excites, barely at all; docs/physics.md §12).
//!
//! A partial's level is measured by heterodyning the output at the partial's frequency over
//! 50 ms windows; a stage's decay rate (dB/s) is the least-squares slope of the level over its
//! span.

use qsa_dsp::instrument::{Event, Instrument, Settings};
use qsa_dsp::preset::piano_note;

const FS: f64 = 48_000.0;
const WINDOW: f64 = 0.05;

/// Key `key` struck at `velocity` with the sustain pedal down, `seconds` long, with a unison
/// spread of `detune` cents: the left channel.
fn render(key: u8, velocity: f32, detune: f64, seconds: f64) -> Vec<f64> {
    let settings = Settings { unison_detune: detune, ..Settings::default() };
    let mut piano = Instrument::new(FS, 4, settings);
    piano.handle(Event::Sustain { channel: 0, down: true });
    piano.handle(Event::NoteOn { channel: 0, key, velocity });
    let n = (seconds * FS) as usize;
    let (mut left, mut right) = (vec![0.0f32; n], vec![0.0f32; n]);
    for (l, r) in left.chunks_mut(256).zip(right.chunks_mut(256)) {
        piano.process(l, r);
    }
    left.into_iter().map(f64::from).collect()
}

/// The level (dB) of the component at `frequency` (Hz) in each 50 ms window.
fn levels(signal: &[f64], frequency: f64) -> Vec<f64> {
    let w = (WINDOW * FS) as usize;
    signal
        .chunks_exact(w)
        .enumerate()
        .map(|(k, chunk)| {
            let (mut re, mut im) = (0.0, 0.0);
            for (i, x) in chunk.iter().enumerate() {
                let phase = std::f64::consts::TAU * frequency * (k * w + i) as f64 / FS;
                re += x * phase.cos();
                im += x * phase.sin();
            }
            10.0 * ((re * re + im * im) / (w * w) as f64).log10()
        })
        .collect()
}

/// Least-squares slope (dB/s) of `levels` over the windows from `from` to `to` (s).
fn slope(levels: &[f64], from: f64, to: f64) -> f64 {
    let points: Vec<(f64, f64)> = levels
        .iter()
        .enumerate()
        .map(|(k, &l)| ((k as f64 + 0.5) * WINDOW, l))
        .filter(|&(t, _)| t >= from && t <= to)
        .collect();
    let n = points.len() as f64;
    let (mt, ml) = (points.iter().map(|p| p.0).sum::<f64>() / n, points.iter().map(|p| p.1).sum::<f64>() / n);
    let cov: f64 = points.iter().map(|p| (p.0 - mt) * (p.1 - ml)).sum();
    let var: f64 = points.iter().map(|p| (p.0 - mt).powi(2)).sum();
    cov / var
}

/// Decay rates (dB/s) of partial `partial` of `key` struck mezzo-forte with a unison spread of
/// `detune` cents: the prompt sound over 0.05–0.6 s and the aftersound over 2–4.5 s.
fn stages(key: u8, partial: usize, detune: f64) -> (f64, f64) {
    let out = render(key, 0.6, detune, 5.0);
    let l = levels(&out, piano_note(key).string.partial(partial));
    (slope(&l, 0.05, 0.6), slope(&l, 2.0, 4.5))
}

/// Mid-range keys (G3, C4, G4, C5) with the default unison spread: the second partial's prompt
/// sound decays at least twice as fast as its aftersound (measured 2.3–2.7 times; the prompt
/// sound 20–49 dB/s, the aftersound 8–21 dB/s).
#[test]
fn a_mistuned_unison_decays_in_two_stages() {
    for key in [55u8, 60, 67, 72] {
        let (prompt, after) = stages(key, 2, 2.5);
        println!(
            "key {key}, partial 2: prompt sound {prompt:.1} dB/s, aftersound {after:.1} dB/s, ratio {:.2}",
            prompt / after
        );
        assert!(prompt < 0.0 && after < 0.0, "key {key}: both stages decay");
        assert!(prompt / after >= 2.0, "key {key}: {prompt:.1} dB/s then {after:.1} dB/s");
    }
}

/// The same C4 with its three strings tuned exactly alike: the hammer moves them together, the
/// aftersound's antisymmetric motion is never excited, and the second partial decays in one
/// stage (the two rates within 15 % of each other; measured 8 %).
#[test]
fn an_exact_unison_decays_in_one_stage() {
    let (prompt, after) = stages(60, 2, 0.0);
    println!("C4 tuned exactly, partial 2: {prompt:.1} dB/s, then {after:.1} dB/s");
    assert!((prompt / after - 1.0).abs() < 0.15, "{prompt:.1} dB/s then {after:.1} dB/s");
}
