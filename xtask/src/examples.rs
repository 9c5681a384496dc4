//! `cargo xtask examples [--out DIR] [--scenes DIR]`: short audio examples of the preset
//! categories, with their spectrograms, for the documentation (`docs/examples/`).
//!
//! Each category has a showcase preset ([`SHOWCASES`]; the slide two, the electric and the
//! acoustic guitar) played on one of the phrases in `scenes/` through the MIDI renderer
//! ([`crate::render::midi`]: the plugin's engine and parameter mapping). For each it writes
//! - `<preset>.wav`: the first seconds of the render in stereo, as the plugin plays it, 16-bit,
//!   [`RATE`] Hz, peak-normalised to −1 dBFS, the last 50 ms faded out (about 440 kB);
//! - `<preset>.png`: the spectrogram of its mid signal `(L + R)/2`, time against log frequency, dB
//!   relative to its peak;
//! - `README.md`: a table linking them, with each render's own peak level, the mid signal's
//!   spectral centroid and the correlation of the two channels (1 for a centred sound).
//!
//! Everything is deterministic: the same sources give the same files. Files are written to
//! temporary files and renamed into place.

use std::io::Write;
use std::path::{Path, PathBuf};

use clap::Args;
use plotters::prelude::*;
use qsa_dsp::instrument::{Preset, find_preset};
use rustfft::FftPlanner;
use rustfft::num_complex::Complex;

use crate::render::midi;

/// Sample rate of the examples (Hz): the engine keeps every mode below 16 kHz, and a 3.4 s stereo
/// 16-bit file stays near 435 kB.
pub const RATE: u32 = 32_000;

/// Peak level the examples are normalised to (dBFS).
pub const PEAK_DBFS: f64 = -1.0;

/// Fade-out at the end of an example (s).
const FADE: f64 = 0.05;

/// A category's example: its preset, the phrase it plays (in the scenes folder) and how many
/// seconds of it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Showcase {
    /// Preset category.
    pub category: &'static str,
    /// Preset id.
    pub preset: &'static str,
    /// MIDI file in the scenes folder.
    pub midi: &'static str,
    /// Length of the example (s).
    pub seconds: f64,
}

/// The showcases: every category's, in [`CATEGORIES`](qsa_dsp::instrument::CATEGORIES) order
/// (the slide's electric and acoustic guitar).
pub const SHOWCASES: [Showcase; 5] = [
    Showcase { category: "Paper", preset: "slide-phrase", midi: "slide-phrase.mid", seconds: 3.4 },
    Showcase { category: "Piano", preset: "concert-grand", midi: "piano-phrase.mid", seconds: 3.4 },
    Showcase { category: "Slide", preset: "lap-steel", midi: "slide-phrase.mid", seconds: 3.4 },
    Showcase { category: "Slide", preset: "acoustic-slide", midi: "slide-phrase.mid", seconds: 3.4 },
    Showcase { category: "Contact", preset: "steel-hammer", midi: "piano-phrase.mid", seconds: 3.4 },
];

/// Arguments of `examples`.
#[derive(Debug, Clone, Args)]
pub struct ExamplesArgs {
    /// Output folder.
    #[arg(long, default_value = "docs/examples")]
    pub out: PathBuf,
    /// Folder holding the MIDI phrases.
    #[arg(long, default_value = "scenes")]
    pub scenes: PathBuf,
    /// Write into an output folder that holds files but not the examples' README (replacing
    /// files of the same names).
    #[arg(long)]
    pub force: bool,
}

/// First line of the examples' README, which marks a folder as theirs ([`crate::folder::claim`]).
pub const TITLE: &str = "# Audio examples";

/// Why the examples could not be made.
#[derive(Debug, thiserror::Error)]
pub enum ExamplesError {
    /// A file could not be read or written.
    #[error("{path}: {message}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// A showcase names something that does not exist.
    #[error("{0}")]
    Setup(String),
}

fn io(path: &Path) -> impl Fn(std::io::Error) -> ExamplesError + '_ {
    move |e| ExamplesError::Io { path: path.to_owned(), message: e.to_string() }
}

/// One example made.
#[derive(Debug, Clone, PartialEq)]
pub struct Example {
    /// The showcase.
    pub showcase: Showcase,
    /// Its preset.
    pub preset: &'static Preset,
    /// The render's own peak before normalising (dBFS).
    pub peak_dbfs: f64,
    /// Spectral centroid of the example's mid signal (Hz).
    pub centroid: f64,
    /// Correlation coefficient of the two channels (1: the same signal in both).
    pub correlation: f64,
    /// The normalised left and right channels written to the WAV (before 16-bit rounding).
    pub channels: [Vec<f64>; 2],
}

impl Example {
    /// The mid signal `(L + R)/2`.
    pub fn mid(&self) -> Vec<f64> {
        let [left, right] = &self.channels;
        left.iter().zip(right).map(|(l, r)| 0.5 * (l + r)).collect()
    }
}

/// Correlation coefficient `Σlr/√(Σl²·Σr²)` of two channels (1 when either is silent), summed in
/// `f64`.
pub fn correlation<T: Copy + Into<f64>>(left: &[T], right: &[T]) -> f64 {
    let dot = |x: &[T], y: &[T]| x.iter().zip(y).map(|(&a, &b)| a.into() * b.into()).sum::<f64>();
    let power = dot(left, left) * dot(right, right);
    if power > 0.0 { dot(left, right) / power.sqrt() } else { 1.0 }
}

/// Render the showcase `s` from the phrases in `scenes`: the two channels at [`RATE`], normalised
/// together and faded.
pub fn render_showcase(s: &Showcase, scenes: &Path) -> Result<Example, ExamplesError> {
    let preset = find_preset(s.preset)
        .ok_or_else(|| ExamplesError::Setup(format!("showcase of {}: no preset {}", s.category, s.preset)))?;
    let path = scenes.join(s.midi);
    let bytes = std::fs::read(&path).map_err(io(&path))?;
    let fs = f64::from(RATE);
    let score =
        midi::score(&bytes, fs).map_err(|e| ExamplesError::Io { path: path.clone(), message: e.to_string() })?;
    let samples = (s.seconds * fs).round() as usize;
    let (left, right, _) = midi::render_signals(&score, &preset.values, fs, (samples, &mut || 512), false);
    let mut channels = [left, right].map(|c| c.iter().map(|&v| f64::from(v)).collect::<Vec<f64>>());
    if let Some(bad) = channels.iter().find_map(|c| c.iter().position(|v| !v.is_finite())) {
        return Err(ExamplesError::Setup(format!("{}: non-finite sample at {bad}", s.preset)));
    }
    let peak = channels.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    if peak == 0.0 {
        return Err(ExamplesError::Setup(format!("{}: the render is silent", s.preset)));
    }
    let scale = 10f64.powf(PEAK_DBFS / 20.0) / peak;
    let fade = (FADE * fs) as usize;
    for channel in &mut channels {
        for (i, v) in channel.iter_mut().enumerate() {
            let to_end = samples - i;
            let ramp = if to_end < fade {
                0.5 - 0.5 * (std::f64::consts::PI * to_end as f64 / fade as f64).cos()
            } else {
                1.0
            };
            *v *= scale * ramp;
        }
    }
    let correlation = correlation(&channels[0], &channels[1]);
    let mut example =
        Example { showcase: *s, preset, peak_dbfs: 20.0 * peak.log10(), centroid: 0.0, correlation, channels };
    example.centroid = spectral_centroid(&example.mid(), fs);
    Ok(example)
}

/// Energy-weighted mean frequency of `x` (Hz).
pub fn spectral_centroid(x: &[f64], fs: f64) -> f64 {
    let n = x.len().next_power_of_two();
    let mut buffer: Vec<Complex<f64>> = x.iter().map(|&v| Complex::new(v, 0.0)).collect();
    buffer.resize(n, Complex::new(0.0, 0.0));
    FftPlanner::new().plan_fft_forward(n).process(&mut buffer);
    let (mut weighted, mut total) = (0.0, 0.0);
    for (k, c) in buffer.iter().take(n / 2 + 1).enumerate() {
        let power = c.norm_sqr();
        weighted += power * k as f64 * fs / n as f64;
        total += power;
    }
    if total > 0.0 { weighted / total } else { 0.0 }
}

/// `cargo xtask examples`: render every showcase, write WAV, PNG and README; print one line per
/// example.
pub fn run(args: &ExamplesArgs, out: &mut dyn Write) -> Result<Vec<Example>, ExamplesError> {
    crate::folder::claim(&args.out, "examples", TITLE, args.force).map_err(ExamplesError::Setup)?;
    let mut made = Vec::new();
    for s in &SHOWCASES {
        let example = render_showcase(s, &args.scenes)?;
        let wav = args.out.join(format!("{}.wav", s.preset));
        let png = args.out.join(format!("{}.png", s.preset));
        let [left, right] = &example.channels;
        write_atomically(&wav, |file| write_wav(file, &[left, right]))?;
        let title = format!("{} ({}): {}, mid", example.preset.name, s.category, s.midi);
        draw_into(&png, |path| spectrogram_png(path, &example.mid(), f64::from(RATE), &title))?;
        writeln!(
            out,
            "{}: {} and {} (render peak {:.1} dBFS, centroid {:.0} Hz, channels correlated {:.2})",
            s.category,
            wav.display(),
            png.display(),
            example.peak_dbfs,
            example.centroid,
            example.correlation
        )
        .map_err(io(Path::new("<stdout>")))?;
        made.push(example);
    }
    let readme = args.out.join("README.md");
    let text = readme_text(&made);
    write_atomically(&readme, |file| file.write_all(text.as_bytes()))?;
    Ok(made)
}

/// The examples' README: how they are made and a table linking them.
pub fn readme_text(examples: &[Example]) -> String {
    let mut text = format!(
        "{TITLE}\n\n\
         An example per preset category, two for the slide (the electric and the acoustic guitar),\n\
         made by `cargo xtask examples` (do not edit by hand: run it again). Each is the showcase\n\
         preset playing the start of a phrase from `scenes/` through the MIDI renderer, the plugin's\n\
         own engine and parameter mapping (`cargo xtask render --midi scenes/FILE --preset ID` renders\n\
         the whole phrase).\n\n",
    );
    text += &format!(
        "The WAVs are stereo, as the plugin plays them at its default stereo width (the piano's keys\n\
         across the picture, the acoustic guitar's body in the centre and its higher modes left and\n\
         right, the electric guitar's pickup in the centre), 16-bit, {} kHz, peak-normalised to\n\
         {PEAK_DBFS} dBFS (the render's own peak is listed), with a 50 ms fade-out. The correlation of\n\
         the two channels is 1 for a sound in the centre and falls as the picture widens. The\n\
         spectrograms are of the mid signal (L + R)/2: time against log frequency, in dB below its\n\
         peak (2048-point Hann windows, 80 dB range).\n\n",
        RATE / 1000
    );
    text +=
        "| category | preset | phrase | audio | spectrogram | render peak | spectral centroid | L/R correlation |\n";
    text += "|---|---|---|---|---|---|---|---|\n";
    for e in examples {
        let s = &e.showcase;
        text += &format!(
            "| {} | {} (`{}`): {} | `scenes/{}`, first {} s | [{id}.wav]({id}.wav) | [{id}.png]({id}.png) | {:.1} dBFS | {:.0} Hz | {:.2} |\n",
            s.category,
            e.preset.name,
            s.preset,
            e.preset.description,
            s.midi,
            s.seconds,
            e.peak_dbfs,
            e.centroid,
            e.correlation,
            id = s.preset,
        );
    }
    for e in examples {
        text += &format!(
            "\n## {}: {}\n\n![Spectrogram of {}]({}.png)\n",
            e.showcase.category, e.preset.name, e.preset.name, e.showcase.preset
        );
    }
    text
}

fn temp_beside(path: &Path) -> Result<tempfile::NamedTempFile, ExamplesError> {
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let mut builder = tempfile::Builder::new();
    // The image encoder goes by the extension.
    let suffix = path.extension().map(|e| format!(".{}", e.to_string_lossy())).unwrap_or_default();
    builder.prefix(".example-").suffix(&suffix);
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o644));
    builder.tempfile_in(dir).map_err(io(dir))
}

fn persist(temp: tempfile::NamedTempFile, path: &Path) -> Result<(), ExamplesError> {
    temp.persist(path).map_err(|e| ExamplesError::Io { path: path.to_owned(), message: e.error.to_string() })?;
    Ok(())
}

/// Draw a picture into `path` through a temporary file beside it (the encoder goes by its
/// extension), put in place once `draw` has succeeded: a failed or interrupted drawing leaves the
/// picture that was there.
pub(crate) fn draw_atomically<T>(path: &Path, draw: impl FnOnce(&Path) -> Result<T, String>) -> Result<T, String> {
    draw_into(path, draw).map_err(|e| e.to_string())
}

/// [`draw_atomically`], its failure naming the picture.
fn draw_into<T>(path: &Path, draw: impl FnOnce(&Path) -> Result<T, String>) -> Result<T, ExamplesError> {
    let temp = temp_beside(path)?;
    let made = draw(temp.path()).map_err(|message| ExamplesError::Io { path: path.to_owned(), message })?;
    persist(temp, path)?;
    Ok(made)
}

pub(crate) fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut std::fs::File) -> std::io::Result<()>,
) -> Result<(), ExamplesError> {
    let mut temp = temp_beside(path)?;
    write(temp.as_file_mut()).and_then(|()| temp.as_file().sync_all()).map_err(io(path))?;
    persist(temp, path)
}

/// `channels` (one, or left and right, of one length) as a 16-bit WAV at [`RATE`].
pub(crate) fn write_wav(file: &mut std::fs::File, channels: &[&[f64]]) -> std::io::Result<()> {
    let count = u16::try_from(channels.len()).map_err(std::io::Error::other)?;
    let spec = hound::WavSpec {
        channels: count,
        sample_rate: RATE,
        bits_per_sample: 16,
        sample_format: hound::SampleFormat::Int,
    };
    let frames = channels.iter().map(|c| c.len()).min().unwrap_or(0);
    let mut buffer = std::io::Cursor::new(Vec::with_capacity(44 + 2 * channels.len() * frames));
    {
        let mut writer = hound::WavWriter::new(&mut buffer, spec).map_err(std::io::Error::other)?;
        for i in 0..frames {
            for channel in channels {
                let sample = (channel[i] * 32767.0).round().clamp(-32768.0, 32767.0) as i16;
                writer.write_sample(sample).map_err(std::io::Error::other)?;
            }
        }
        writer.finalize().map_err(std::io::Error::other)?;
    }
    file.write_all(buffer.get_ref())
}

/// Window of the spectrogram (samples) and hop between frames.
const WINDOW: usize = 2048;
const HOP: usize = 256;
/// Frequency range shown (Hz) and rows drawn across it.
const FREQ_RANGE: (f64, f64) = (40.0, 16_000.0);
const ROWS: usize = 220;
/// Dynamic range shown (dB).
const RANGE_DB: f64 = 80.0;

/// Power spectrogram of `x`: one row of `WINDOW / 2 + 1` bins (dB) per frame of [`HOP`] samples.
fn stft_db(x: &[f64]) -> Vec<Vec<f64>> {
    let fft = FftPlanner::new().plan_fft_forward(WINDOW);
    let window: Vec<f64> =
        (0..WINDOW).map(|i| 0.5 - 0.5 * (2.0 * std::f64::consts::PI * i as f64 / WINDOW as f64).cos()).collect();
    let frames = x.len().saturating_sub(WINDOW) / HOP + 1;
    let mut buffer = vec![Complex::new(0.0, 0.0); WINDOW];
    (0..frames)
        .map(|f| {
            for (i, b) in buffer.iter_mut().enumerate() {
                *b = Complex::new(x.get(f * HOP + i).copied().unwrap_or(0.0) * window[i], 0.0);
            }
            fft.process(&mut buffer);
            buffer.iter().take(WINDOW / 2 + 1).map(|c| 10.0 * (c.norm_sqr() + 1e-30).log10()).collect()
        })
        .collect()
}

/// An "inferno"-like colour for `t` in 0..=1 (dark to bright).
fn heat(t: f64) -> RGBColor {
    const STOPS: [(u8, u8, u8); 8] = [
        (0, 0, 4),
        (40, 11, 84),
        (101, 21, 110),
        (159, 42, 99),
        (212, 72, 66),
        (245, 125, 21),
        (250, 193, 39),
        (252, 255, 164),
    ];
    let x = t.clamp(0.0, 1.0) * (STOPS.len() - 1) as f64;
    let i = (x.floor() as usize).min(STOPS.len() - 2);
    let f = x - i as f64;
    let mix = |a: u8, b: u8| (f64::from(a) + f * (f64::from(b) - f64::from(a))).round() as u8;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// Draw the spectrogram of `x` (sampled at `fs`) into the PNG `path`.
pub fn spectrogram_png(path: &Path, x: &[f64], fs: f64, title: &str) -> Result<(), String> {
    let frames = stft_db(x);
    let top = frames.iter().flatten().fold(f64::NEG_INFINITY, |m, &v| m.max(v));
    let (f_lo, f_hi) = FREQ_RANGE;
    let f_hi = f_hi.min(0.5 * fs);
    let duration = x.len() as f64 / fs;
    let root = BitMapBackend::new(path, (880, 380)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 18))
        .margin(10)
        .x_label_area_size(36)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..duration, (f_lo..f_hi).log_scale())
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("time (s)")
        .y_desc("frequency (Hz)")
        .y_label_formatter(&|f| if *f >= 1000.0 { format!("{:.0}k", f / 1000.0) } else { format!("{f:.0}") })
        .label_style(("sans-serif", 13))
        .draw()
        .map_err(|e| e.to_string())?;
    let ratio = (f_hi / f_lo).powf(1.0 / ROWS as f64);
    let bin_hz = fs / WINDOW as f64;
    let cells = frames.iter().enumerate().flat_map(|(i, spectrum)| {
        // Each frame is drawn over the hop around its window's centre.
        let t0 = (i * HOP + WINDOW / 2 - HOP / 2) as f64 / fs;
        let t1 = t0 + HOP as f64 / fs;
        (0..ROWS).map(move |r| {
            let (lo, hi) = (f_lo * ratio.powi(r as i32), f_lo * ratio.powi(r as i32 + 1));
            // The loudest bin in the row (or the nearest one, where rows are narrower than bins).
            let (a, b) =
                ((lo / bin_hz).round() as usize, ((hi / bin_hz).round() as usize).max((lo / bin_hz).round() as usize));
            let level = spectrum[a.min(spectrum.len() - 1)..=b.min(spectrum.len() - 1)]
                .iter()
                .fold(f64::NEG_INFINITY, |m, &v| m.max(v));
            let t = 1.0 + (level - top) / RANGE_DB;
            Rectangle::new([(t0, lo), (t1, hi)], heat(t).filled())
        })
    });
    chart.draw_series(cells).map_err(|e| e.to_string())?;
    root.present().map_err(|e| e.to_string())?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use qsa_dsp::instrument::CATEGORIES;

    use super::*;

    #[test]
    fn every_category_has_a_showcase_and_each_is_a_small_file() {
        let mut categories: Vec<&str> = SHOWCASES.iter().map(|s| s.category).collect();
        categories.dedup();
        assert_eq!(categories, CATEGORIES);
        for s in SHOWCASES {
            let preset = find_preset(s.preset).unwrap_or_else(|| panic!("no preset {}", s.preset));
            assert_eq!(preset.category, s.category, "{} is in {}", s.preset, s.category);
            let size = 44.0 + 2.0 * 2.0 * s.seconds * f64::from(RATE);
            assert!(size < 500e3, "{}: {size} bytes", s.preset);
        }
    }

    #[test]
    fn channels_correlate_as_their_signals_do() {
        // Ten whole periods in 1000 samples.
        let w = 2.0 * std::f64::consts::PI * 10.0 / 1000.0;
        let x: Vec<f64> = (0..1000).map(|n| (w * n as f64).sin()).collect();
        let minus: Vec<f64> = x.iter().map(|v| -v).collect();
        let half: Vec<f64> = x.iter().map(|v| 0.5 * v).collect();
        let y: Vec<f64> = (0..1000).map(|n| (w * n as f64).cos()).collect();
        assert!((correlation(&x, &half) - 1.0).abs() < 1e-12);
        assert!((correlation(&x, &minus) + 1.0).abs() < 1e-12);
        // Sine and cosine over whole periods are orthogonal.
        assert!(correlation(&x, &y).abs() < 1e-12, "{}", correlation(&x, &y));
        assert_eq!(correlation(&x, &[0.0; 1000]), 1.0);
    }

    /// An example renders only its own seconds of the phrase: a phrase whose last event lies
    /// 4.5·10⁹ s on (the longest tempo, one tick a quarter note, the longest delta) makes its
    /// example as a short one does, rather than asking for memory for the whole file.
    #[test]
    fn an_example_renders_only_its_own_seconds_of_the_phrase() {
        let dir = tempfile::TempDir::new().unwrap();
        let track = [
            &[0x00, 0xff, 0x51, 3, 0xff, 0xff, 0xff][..],
            &[0x00, 0x90, 60, 100],
            &[0xff, 0xff, 0xff, 0x7f, 0x80, 60, 0],
            &[0x00, 0xff, 0x2f, 0],
        ]
        .concat();
        let mut file = b"MThd\0\0\0\x06\0\0\0\x01\0\x01MTrk".to_vec();
        file.extend_from_slice(&(track.len() as u32).to_be_bytes());
        file.extend_from_slice(&track);
        let showcase = SHOWCASES[1];
        std::fs::write(dir.path().join(showcase.midi), &file).unwrap();
        let example = render_showcase(&showcase, dir.path()).unwrap();
        let samples = (showcase.seconds * f64::from(RATE)).round() as usize;
        assert_eq!(example.channels.map(|c| c.len()), [samples; 2]);
        assert!(example.peak_dbfs.is_finite());
    }

    #[test]
    fn centroid_of_a_sine_is_its_frequency() {
        let fs = 32_000.0;
        let x: Vec<f64> = (0..32_000).map(|n| (2.0 * std::f64::consts::PI * 1000.0 * n as f64 / fs).sin()).collect();
        let c = spectral_centroid(&x, fs);
        assert!((c - 1000.0).abs() < 5.0, "{c}");
    }
}
