//! Loudness of the piano across the keyboard, and its voicing.
//!
//! Each key is struck alone at a MIDI velocity, held (no damper) for [`SECONDS`], and its
//! integrated loudness measured as ITU-R BS.1770-4 / EBU R128 define it (K-weighting, 400 ms
//! blocks, relative gate −10 LU; the `ebur128` crate; the absolute gate, see below), in LUFS. Its
//! brightness is the RMS frequency `f_rms = (1/2π) √(Σ ẋ² / Σ x²)` of the same span (the square
//! root of the power spectrum's second moment), with ẋ the central difference.
//!
//! `cargo xtask loudness` measures every key from A0 (21) to C8 (108) at velocities
//! [`VELOCITIES`] and the fortissimo chords [`CHORDS`], prints one JSON summary line and, with
//! `--write`, writes `docs/report/loudness.csv` and `docs/report/loudness.png`. With `--voice` it
//! rewrites the voicing table (`dsp/src/instrument/voicing.rs`) so that every key at each of the
//! table's velocities meets its [`target`]: the output is linear in the voicing gain and the
//! measure does not depend on the signal's scale, so one pass puts each key on target (the table
//! adds what each key misses), and a second, after a rebuild, finds each within rounding.
//!
//! Each signal is metered scaled to an RMS of −20 dBFS and the scale taken off again
//! ([`integrated_lufs`]), so that the absolute gate at −70 LUFS never acts: the measure is the
//! relative-gated loudness, the same for a note at any level. A meter on the plugin's output,
//! whose absolute gate drops a soft note's quietest blocks, reads a fast-decaying soft note up to
//! about 3 LU louder than this (a tone decaying 60 dB/s, measured here at −63 LUFS).

use std::path::{Path, PathBuf};

use clap::Args;
use plotters::prelude::*;
use qsa_dsp::instrument::{Event, Instrument, Settings, VOICING_VELOCITIES};

/// Seconds each key is held and measured.
pub const SECONDS: f64 = 2.0;

/// Sample rate of the measurement (Hz).
pub const SAMPLE_RATE: f64 = 48_000.0;

/// MIDI velocities the report measures and plots: piano, mezzo-forte, fortissimo. All three are
/// velocities of the voicing table, so the report shows the keys meeting its targets; the
/// loudness tests check the velocities between them, where the table interpolates.
pub const VELOCITIES: [u8; 3] = [40, 80, 120];

/// Loudness every key has after voicing at MIDI velocity 80 (LUFS)...
pub const TARGET_LUFS_AT_80: f64 = -46.0;

/// ...and its rise per step of MIDI velocity (LU): the middle register's own dynamic range (C4
/// rises 9 LU from velocity 40 to 80 and 8.5 LU from 80 to 120), at a level where the loudest
/// ten-note chord of [`CHORDS`] peaks below 0 dBFS.
pub const TARGET_LU_PER_VELOCITY: f64 = 0.22;

/// The loudness the voicing gives every key at `velocity` (LUFS).
pub fn target(velocity: u8) -> f64 {
    TARGET_LUFS_AT_80 + TARGET_LU_PER_VELOCITY * (f64::from(velocity) - 80.0)
}

/// The piano's keys: A0 to C8.
pub const KEYS: std::ops::RangeInclusive<u8> = 21..=108;

/// Ten-note chords struck fortissimo (velocity 127) together: two hands of five fingers in the
/// middle, in the bass and in the treble, and the loudest cluster the keyboard allows.
pub const CHORDS: [(&str, [u8; 10]); 4] = [
    ("C major, both hands", [48, 52, 55, 60, 64, 67, 72, 76, 79, 84]),
    ("bass octaves", [21, 28, 33, 36, 40, 43, 45, 48, 52, 55]),
    ("treble", [84, 88, 91, 93, 96, 98, 100, 103, 105, 108]),
    ("cluster C3–A3", [48, 49, 50, 51, 52, 53, 54, 55, 56, 57]),
];

/// One key at one velocity.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KeyLoudness {
    /// MIDI key.
    pub key: u8,
    /// MIDI velocity.
    pub velocity: u8,
    /// Integrated loudness (LUFS).
    pub lufs: f64,
    /// RMS frequency (Hz).
    pub rms_frequency: f64,
    /// Largest sample (full scale = 1).
    pub peak: f64,
}

/// Render `keys` struck together at `velocity` and held for `seconds`, with `settings` (the
/// safety limiter as the settings say). Returns the left and right channels.
pub fn strike(keys: &[u8], velocity: u8, settings: &Settings, seconds: f64) -> (Vec<f32>, Vec<f32>) {
    let mut piano = Instrument::new(SAMPLE_RATE, keys.len().max(1), *settings);
    for &key in keys {
        piano.handle(Event::NoteOn { channel: 0, key, velocity: f32::from(velocity) / 127.0 });
    }
    let n = (seconds * SAMPLE_RATE) as usize;
    let (mut left, mut right) = (vec![0.0f32; n], vec![0.0f32; n]);
    for (l, r) in left.chunks_mut(512).zip(right.chunks_mut(512)) {
        piano.process(l, r);
    }
    (left, right)
}

/// Integrated loudness (LUFS) of a mono signal played on both channels of a stereo pair (as
/// the instrument plays it); −∞ for silence. The signal is metered scaled to an RMS of −20 dBFS
/// and the scale taken off again, so that a very quiet note is measured rather than gated out by
/// the absolute gate at −70 LUFS (the relative gate, and so the result, does not depend on the
/// scale).
pub fn integrated_lufs(signal: &[f32], sample_rate: f64) -> f64 {
    integrated_lufs_stereo(signal, signal, sample_rate)
}

/// Integrated loudness (LUFS) of a stereo pair, metered as [`integrated_lufs`] meters one signal.
pub fn integrated_lufs_stereo(left: &[f32], right: &[f32], sample_rate: f64) -> f64 {
    let power = left.iter().chain(right).map(|&x| f64::from(x).powi(2)).sum::<f64>();
    let rms = (power / (left.len() + right.len()).max(1) as f64).sqrt();
    if !(rms > 0.0) {
        return f64::NEG_INFINITY;
    }
    let scale = 0.1 / rms;
    let scaled = |x: &[f32]| x.iter().map(|&x| (f64::from(x) * scale) as f32).collect::<Vec<f32>>();
    let (l, r) = (scaled(left), scaled(right));
    let Ok(mut meter) = ebur128::EbuR128::new(2, sample_rate as u32, ebur128::Mode::I) else {
        return f64::NAN;
    };
    if meter.add_frames_planar_f32(&[&l, &r]).is_err() {
        return f64::NAN;
    }
    meter.loudness_global().map_or(f64::NAN, |l| l - 20.0 * scale.log10())
}

/// RMS frequency (Hz) of `signal`: `(1/2π) √(Σ ẋ² / Σ x²)`.
pub fn rms_frequency(signal: &[f32], sample_rate: f64) -> f64 {
    let x = |i: usize| f64::from(signal[i]);
    let power: f64 = (1..signal.len().saturating_sub(1)).map(|i| x(i) * x(i)).sum();
    let slope: f64 =
        (1..signal.len().saturating_sub(1)).map(|i| (0.5 * (x(i + 1) - x(i - 1)) * sample_rate).powi(2)).sum();
    (slope / power).sqrt() / std::f64::consts::TAU
}

/// Measure one key, centred: a key panned by the stereo width has the same loudness, since the pan
/// keeps its power (`g_L² + g_R² = 2`, [`qsa_dsp::instrument::pan_gains`]) and both channels
/// pass the same soundboard.
pub fn measure(key: u8, velocity: u8, settings: &Settings) -> KeyLoudness {
    let (out, _) = strike(&[key], velocity, &Settings { limiter: false, stereo_width: 0.0, ..*settings }, SECONDS);
    KeyLoudness {
        key,
        velocity,
        lufs: integrated_lufs(&out, SAMPLE_RATE),
        rms_frequency: rms_frequency(&out, SAMPLE_RATE),
        peak: out.iter().fold(0.0f64, |m, &x| m.max(f64::from(x).abs())),
    }
}

/// Every key of [`KEYS`] at every velocity of [`VELOCITIES`], in key order per velocity.
pub fn keyboard(settings: &Settings) -> Vec<KeyLoudness> {
    VELOCITIES.iter().flat_map(|&v| KEYS.map(move |k| measure(k, v, settings))).collect()
}

/// Peak of each of [`CHORDS`] struck fortissimo with the limiter off, over both channels (full
/// scale = 1).
pub fn chord_peaks(settings: &Settings) -> Vec<(&'static str, f64)> {
    CHORDS
        .iter()
        .map(|(name, keys)| {
            let (left, right) = strike(keys, 127, &Settings { limiter: false, ..*settings }, 0.5);
            (*name, left.iter().chain(&right).fold(0.0f64, |m, &x| m.max(f64::from(x).abs())))
        })
        .collect()
}

/// What the keyboard measurement says, per velocity.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Evenness {
    /// MIDI velocity.
    pub velocity: u8,
    /// Largest loudness difference between neighbouring keys (LU).
    pub neighbours: f64,
    /// Loudest minus quietest key (LU).
    pub band: f64,
    /// Mean loudness over the keys (LUFS).
    pub mean: f64,
}

/// Evenness of each velocity's row of `rows` (as [`keyboard`] orders them).
pub fn evenness(rows: &[KeyLoudness]) -> Vec<Evenness> {
    VELOCITIES
        .iter()
        .map(|&velocity| {
            let l: Vec<f64> = rows.iter().filter(|r| r.velocity == velocity).map(|r| r.lufs).collect();
            let neighbours = l.windows(2).map(|w| (w[1] - w[0]).abs()).fold(0.0, f64::max);
            let (lo, hi) = l.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x)));
            Evenness { velocity, neighbours, band: hi - lo, mean: l.iter().sum::<f64>() / l.len() as f64 }
        })
        .collect()
}

/// `cargo xtask loudness`.
#[derive(Debug, Args)]
pub struct LoudnessArgs {
    /// Write docs/report/loudness.csv and loudness.png.
    #[arg(long)]
    pub write: bool,
    /// Rewrite the voicing table (dsp/src/instrument/voicing.rs) so every key meets the target
    /// loudness at each measured velocity; rebuild and run again to see the result.
    #[arg(long)]
    pub voice: bool,
    /// Repository root.
    #[arg(long, default_value = ".")]
    pub root: PathBuf,
}

/// Run `cargo xtask loudness`.
pub fn run(args: &LoudnessArgs, stdout: &mut dyn std::io::Write) -> Result<(), String> {
    let settings = Settings::default();
    let rows = keyboard(&settings);
    let even = evenness(&rows);
    let chords = chord_peaks(&settings);
    let summary = serde_json::json!({
        "target_lufs": VELOCITIES.map(target),
        "velocities": even.iter().map(|e| serde_json::json!({
            "velocity": e.velocity, "mean_lufs": e.mean, "largest_neighbour_step_lu": e.neighbours, "band_lu": e.band,
        })).collect::<Vec<_>>(),
        "chords": chords.iter().map(|(name, peak)| serde_json::json!({
            "chord": name, "peak": peak, "peak_dbfs": 20.0 * peak.log10(),
        })).collect::<Vec<_>>(),
    });
    writeln!(stdout, "{summary}").map_err(|e| e.to_string())?;
    if args.write {
        let dir = args.root.join("docs/report");
        write_csv(&dir.join("loudness.csv"), &rows)?;
        crate::examples::draw_atomically(&dir.join("loudness.png"), |path| plot(path, &rows))?;
    }
    if args.voice {
        let path = args.root.join("dsp/src/instrument/voicing.rs");
        let mut table = qsa_dsp::instrument::VOICING_DB;
        for (column, &velocity) in VOICING_VELOCITIES.iter().enumerate() {
            for key in KEYS {
                let measured = measure(key, velocity, &settings).lufs;
                table[usize::from(key)][column] += (target(velocity) - measured) as f32;
            }
        }
        if let Some((key, gains)) = table.iter().enumerate().find(|(_, gains)| gains.iter().any(|g| !g.is_finite())) {
            return Err(format!(
                "key {key}: no finite voicing gain ({gains:?}): a key measured silent; voicing.rs is left as it was"
            ));
        }
        // Keys beyond the piano's take their nearest piano key's voicing.
        let (lo, hi) = (usize::from(*KEYS.start()), usize::from(*KEYS.end()));
        for k in 0..lo {
            table[k] = table[lo];
        }
        for k in hi + 1..128 {
            table[k] = table[hi];
        }
        write_voicing(&path, &table)?;
    }
    Ok(())
}

fn write_csv(path: &Path, rows: &[KeyLoudness]) -> Result<(), String> {
    let mut text = String::from("key,velocity,lufs,rms_frequency_hz,peak\n");
    for r in rows {
        text += &format!("{},{},{:.3},{:.1},{:.5}\n", r.key, r.velocity, r.lufs, r.rms_frequency, r.peak);
    }
    write_text(path, &text)
}

/// Write `text` to `path` through a temporary file renamed into place.
fn write_text(path: &Path, text: &str) -> Result<(), String> {
    use std::io::Write;
    crate::examples::write_atomically(path, |file| file.write_all(text.as_bytes())).map_err(|e| e.to_string())
}

fn write_voicing(path: &Path, table: &[[f32; 43]; 128]) -> Result<(), String> {
    let old = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let (begin, end) = ("// voicing-table:begin\n", "// voicing-table:end");
    let Some((a, b)) = old.find(begin).zip(old.find(end)).filter(|&(a, b)| a < b) else {
        return Err(format!("{}: no voicing-table markers, in order", path.display()));
    };
    let mut rows = String::new();
    for (key, gains) in table.iter().enumerate() {
        let values: Vec<String> = gains.iter().map(|g| format!("{g:.2}")).collect();
        rows += &format!("    [{}], // {key}\n", values.join(", "));
    }
    let new = format!(
        "{}{begin}#[rustfmt::skip]\n#[allow(clippy::approx_constant)] // measured gains, some of which happen to be near π\npub static VOICING_DB: [[f32; 43]; 128] = [\n{rows}];\n{}",
        &old[..a],
        &old[b..]
    );
    write_text(path, &new)
}

fn plot(path: &Path, rows: &[KeyLoudness]) -> Result<(), String> {
    let root = BitMapBackend::new(path, (960, 560)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    // What the strings give before voicing: the voicing gain taken off again.
    let unvoiced = |r: &KeyLoudness| {
        r.lufs - 20.0 * qsa_dsp::instrument::voicing_gain(r.key, f64::from(r.velocity) / 127.0).log10()
    };
    let (lo, hi) = rows
        .iter()
        .flat_map(|r| [r.lufs, unvoiced(r)])
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), l| (a.min(l), b.max(l)));
    let mut chart = ChartBuilder::on(&root)
        .caption("Integrated loudness per key (EBU R128), each key alone, held 2 s", ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(60)
        .build_cartesian_2d(20f64..109f64, (lo - 3.0).floor()..(hi + 3.0).ceil())
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_label_formatter(&|k| format!("{k:.0}"))
        .x_desc("MIDI key (21 = A0, 60 = C4, 108 = C8)")
        .y_desc("loudness (LUFS)")
        .draw()
        .map_err(|e| e.to_string())?;
    let colours = [RGBColor(31, 119, 180), RGBColor(44, 160, 44), RGBColor(214, 39, 40)];
    for (&velocity, colour) in VELOCITIES.iter().zip(colours) {
        let points: Vec<(f64, f64)> =
            rows.iter().filter(|r| r.velocity == velocity).map(|r| (f64::from(r.key), r.lufs)).collect();
        chart
            .draw_series(LineSeries::new(points, colour.stroke_width(2)))
            .map_err(|e| e.to_string())?
            .label(format!("velocity {velocity}"))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2)));
        let raw: Vec<(f64, f64)> =
            rows.iter().filter(|r| r.velocity == velocity).map(|r| (f64::from(r.key), unvoiced(r))).collect();
        let light = colour.mix(0.45);
        chart
            .draw_series(LineSeries::new(raw, light.stroke_width(1)))
            .map_err(|e| e.to_string())?
            .label(format!("velocity {velocity}, before voicing"))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], light.stroke_width(1)));
    }
    crate::report::plot::legend(&mut chart, SeriesLabelPosition::LowerLeft)?;
    root.present().map_err(|e| e.to_string())
}
