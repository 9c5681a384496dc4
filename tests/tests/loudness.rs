//! The piano's output as a musician meets it: even loudness across the keyboard at every dynamic
//! level, velocity that makes every key louder and brighter, chords that do not clip at the
//! default gain, and a safety limiter that holds whatever the voices do below 0 dBFS.
//!
//! Loudness is the integrated loudness of ITU-R BS.1770 / EBU R128 (the `ebur128` crate) of
//! each key struck alone and held 2 s (`xtask::loudness`).

use qsa_dsp::instrument::{CEILING, Event, Instrument, Settings};
use qsa_tests::dc_db;
use xtask::loudness::{self, KEYS, KeyLoudness, chord_peaks, measure};

/// Largest loudness step allowed between neighbouring keys (LU).
const NEIGHBOURS_LU: f64 = 1.5;
/// Widest spread of loudness allowed over the keyboard at one velocity (LU).
const BAND_LU: f64 = 6.0;

fn row(velocity: u8) -> Vec<KeyLoudness> {
    KEYS.map(|key| measure(key, velocity, &Settings::default())).collect()
}

fn evenness(velocity: u8) -> (f64, f64) {
    let l: Vec<f64> = row(velocity).iter().map(|r| r.lufs).collect();
    let neighbours = l.windows(2).map(|w| (w[1] - w[0]).abs()).fold(0.0, f64::max);
    let (lo, hi) = l.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x)));
    let worst = l.windows(2).enumerate().max_by(|a, b| (a.1[1] - a.1[0]).abs().total_cmp(&(b.1[1] - b.1[0]).abs()));
    let at = worst.map_or(0, |(i, _)| usize::from(*KEYS.start()) + i);
    println!(
        "velocity {velocity}: largest neighbour step {neighbours:.2} LU (keys {at}-{}), band {:.2} LU ({lo:.1} to {hi:.1} LUFS)",
        at + 1,
        hi - lo
    );
    (neighbours, hi - lo)
}

/// At the report's three velocities (40, 80, 120) and half-way between the voicing table's
/// velocities (where it interpolates and nothing was measured), every key of A0–C8 is within
/// 1.5 LU of its neighbours and the keyboard within a 6 LU band.
#[test]
fn loudness_is_even_across_the_keyboard_at_every_dynamic_level() {
    let rows: Vec<(u8, f64, f64)> = [3, 11, 17, 19, 25, 27, 35, 40, 50, 66, 80, 82, 98, 114, 120, 126]
        .map(|v| (v, evenness(v)))
        .map(|(v, (n, b))| (v, n, b))
        .to_vec();
    for (velocity, neighbours, band) in rows {
        assert!(neighbours <= NEIGHBOURS_LU, "velocity {velocity}: neighbouring keys differ by {neighbours:.2} LU");
        assert!(band <= BAND_LU, "velocity {velocity}: the keyboard spans {band:.2} LU");
    }
}

/// Highest key whose brightness rises at every step of velocity. Above it (F♯5 and up) the hammer
/// stays on the string for about a period or longer, as on measured grands, and in the top octave
/// for two to three periods at the quietest velocities: the zeros of the contact pulse's spectrum
/// sweep across the few partials as the hammer speeds up, and the RMS frequency of neighbouring
/// velocities wanders (by up to 22 % at velocities 7–15 in C7–C8, under 1 % between mezzo-forte
/// velocities), though fortissimo is still brighter than piano there (docs/physics.md §8.4).
const BRIGHTNESS_EVERY_STEP_UP_TO: u8 = 77;

/// On every third key, each velocity step of 8 makes the note louder (integrated loudness); up to
/// F5 each step also makes it brighter (RMS frequency), and on every key fortissimo (120) is
/// brighter than piano (40): the dynamic levels are ordered as a pianist expects.
#[test]
fn velocity_makes_every_key_louder_and_brighter() {
    let velocities: Vec<u8> = (7..=127).step_by(8).collect();
    for key in KEYS.step_by(3) {
        let rows: Vec<KeyLoudness> = velocities.iter().map(|&v| measure(key, v, &Settings::default())).collect();
        for pair in rows.windows(2) {
            let (a, b) = (pair[0], pair[1]);
            assert!(
                b.lufs > a.lufs,
                "key {key}: velocity {} gives {:.2} LUFS, {} gives {:.2}",
                a.velocity,
                a.lufs,
                b.velocity,
                b.lufs
            );
            assert!(
                key > BRIGHTNESS_EVERY_STEP_UP_TO || b.rms_frequency > a.rms_frequency,
                "key {key}: velocity {} is {:.0} Hz bright, {} is {:.0} Hz",
                a.velocity,
                a.rms_frequency,
                b.velocity,
                b.rms_frequency
            );
        }
        let (first, last) = (rows[0], rows[rows.len() - 1]);
        println!(
            "key {key}: {:.1} to {:.1} LUFS, {:.0} to {:.0} Hz RMS frequency",
            first.lufs, last.lufs, first.rms_frequency, last.rms_frequency
        );
    }
    for key in KEYS {
        let (piano, forte) = (measure(key, 40, &Settings::default()), measure(key, 120, &Settings::default()));
        assert!(
            forte.rms_frequency > piano.rms_frequency,
            "key {key}: fortissimo {:.0} Hz is not brighter than piano {:.0} Hz",
            forte.rms_frequency,
            piano.rms_frequency
        );
    }
}

/// Ten-note chords struck together at velocity 127 (two hands in the middle, in the bass, in
/// the treble, a cluster) peak below 0 dBFS at the default gain with the limiter off: the
/// limiter is a safety net, not part of the sound.
#[test]
fn a_fortissimo_ten_note_chord_stays_below_full_scale_at_the_default_gain() {
    for (name, peak) in chord_peaks(&Settings::default()) {
        println!("{name}: peak {peak:.3} ({:.1} dBFS)", 20.0 * peak.log10());
        assert!(peak < 1.0, "{name} peaks at {peak}");
    }
}

/// With the gain at its top, +12 dB, 32 voices struck fortissimo reach well beyond full scale
/// (+5.2 dBFS); the safety limiter holds every sample at its ceiling (−0.1 dBFS), and switched
/// off it lets them through.
#[test]
fn the_safety_limiter_holds_thirty_two_fortissimo_voices_below_full_scale() {
    let keys: Vec<u8> = (36..68).collect();
    let gain = 10f64.powf(12.0 / 20.0);
    let peak = |limiter: bool| {
        let settings = Settings { gain, limiter, ..Settings::default() };
        let mut piano = Instrument::new(48_000.0, 32, settings);
        let mut peak = 0.0f32;
        let (mut l, mut r) = (vec![0.0f32; 333], vec![0.0f32; 333]);
        for block in 0..300 {
            if block % 40 == 0 {
                for &key in &keys {
                    piano.handle(Event::NoteOn { channel: 0, key, velocity: 1.0 });
                }
            }
            piano.process(&mut l, &mut r);
            peak = l.iter().chain(&r).fold(peak, |m, x| m.max(x.abs()));
        }
        f64::from(peak)
    };
    let (limited, open) = (peak(true), peak(false));
    println!("32 voices at +12 dB: peak {open:.2} without the limiter, {limited:.4} with it");
    assert!(open > 1.5, "the case must overload without the limiter: {open}");
    assert!(limited <= CEILING + 1e-7, "limited peak {limited}");
    assert!(limited > 0.9 * CEILING, "the limiter holds the peak at its ceiling, not far below: {limited}");
}

/// The loudness measure itself: BS.1770 calibrates a 997 Hz sine at 0 dBFS peak in one channel
/// to −3.01 LUFS, so at −20 dBFS in one channel −23.01 LUFS, and in both channels of a stereo
/// pair (powers add) −20.0 LUFS.
#[test]
fn the_loudness_meter_reads_a_reference_sine_as_bs1770_specifies() {
    let fs = 48_000.0;
    let amplitude = 10f64.powf(-20.0 / 20.0);
    let sine: Vec<f32> = (0..(5.0 * fs) as usize)
        .map(|i| (amplitude * (std::f64::consts::TAU * 997.0 * i as f64 / fs).sin()) as f32)
        .collect();
    let lufs = loudness::integrated_lufs(&sine, fs);
    println!("997 Hz at -20 dBFS on two channels: {lufs:.3} LUFS");
    assert!((lufs - (-20.0)).abs() < 0.1, "{lufs}");
}

/// A held piano note carries no DC: once the hammer has left, the bridge force of strings and a
/// bridge vibrating in their modes averages to zero. In the dry output (the bridge force itself:
/// the soundboard, heard by its velocity, would hide a DC in it), over 0.1–2 s after the strike
/// (Hann-weighted) the mean is below −60 dB of the RMS on the lowest, middle and highest keys,
/// soft and loud.
#[test]
fn a_held_piano_note_has_no_dc() {
    for key in [21u8, 60, 108] {
        for velocity in [30u8, 127] {
            let mut piano = Instrument::new(48_000.0, 1, Settings::default());
            piano.set_raw_output(true);
            piano.handle(Event::NoteOn { channel: 0, key, velocity: f32::from(velocity) / 127.0 });
            let (mut left, mut right) = (vec![0.0f32; 96_000], vec![0.0f32; 96_000]);
            for (l, r) in left.chunks_mut(512).zip(right.chunks_mut(512)) {
                piano.process(l, r);
            }
            let out: Vec<f64> = left.into_iter().map(f64::from).collect();
            let db = dc_db(&out, 4_800..out.len());
            let rms = (out[4_800..].iter().map(|x| x * x).sum::<f64>() / (out.len() - 4_800) as f64).sqrt();
            println!("key {key} velocity {velocity}: DC {db:.1} dB of the RMS {rms:.2e}");
            assert!(db < -60.0, "key {key} velocity {velocity}: DC {db:.1} dB");
        }
    }
}
