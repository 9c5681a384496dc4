//! `cargo xtask bench`: real-time factors of whole voices, one JSON line per case.
//!
//! Each case renders a shipped scene through the real-time path
//! ([`qsa_dsp::render::render_output`]: output only, no energy bookkeeping) in calls of 64
//! samples, as a plugin would, `--runs` times; the line reports the median and the fastest RTF
//! (wall seconds per simulated second) measured in this one run of the command, after one
//! discarded warm-up run. Cases:
//! - `hammer-c4/{qsa,exp,imp}`: the Fig. 5 voice (C4 string, 56 modes at 44.1 kHz), QSA N = 6;
//! - `slide-phrase/nb{1,8,64}`: the slide phrase with control blocks of 1, 8 and 64 samples;
//! - `piano/16-voices/{64,512}` and `slide/16-voices/{64,512}`: the instrument engine (the
//!   plugin's process path) at 48 kHz with 16 keys from C3 to C6 played together, pedal down,
//!   rendered in 64- and 512-sample calls;
//! - `piano/88-keys`: all 88 keys (A0 to C8) struck together, pedal down, 48 kHz: the whole
//!   piano at once. Its line also says how many C4 voices fit in real time on one core.

use std::io::Write;
use std::path::{Path, PathBuf};

use clap::Args;
use qsa_dsp::contact::{Method, SolverSettings};
use qsa_dsp::instrument::{Event, Instrument, Mode, Settings};
use qsa_dsp::render::{SceneDescription, parse_scene, render_output};
use qsa_dsp::string::ModalString;
use serde::Serialize;

/// Arguments of `bench`.
#[derive(Debug, Clone, Args)]
pub struct BenchArgs {
    /// Runs per case; the median is reported.
    #[arg(long, default_value_t = 5)]
    pub runs: usize,
    /// Directory holding the shipped scene files.
    #[arg(long, default_value = "scenes")]
    pub scenes: PathBuf,
    /// Only run cases whose name contains this text.
    #[arg(long, default_value = "")]
    pub filter: String,
}

/// One line of the bench report.
#[derive(Debug, Clone, Serialize)]
pub struct BenchLine {
    /// Case name.
    pub name: String,
    /// Solver.
    pub method: &'static str,
    /// QSA segments (0 for the others).
    pub segments: usize,
    /// Control block N_b (0 where the scene has none).
    pub block: usize,
    /// Sample rate (Hz).
    pub sample_rate: u32,
    /// String modes.
    pub modes: usize,
    /// Simulated seconds per run.
    pub seconds: f64,
    /// Median real-time factor over the runs.
    pub rtf: f64,
    /// Fastest run's real-time factor.
    pub rtf_min: f64,
    /// Median cost per sample (ns).
    pub ns_per_sample: f64,
    /// Runs measured.
    pub runs: usize,
    /// Voices sounding (instrument cases; 1 for single scenes).
    pub voices: usize,
}

/// Why the bench could not run.
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    /// A scene file could not be read or parsed.
    #[error("{0}")]
    Scene(String),
}

fn load(dir: &Path, name: &str) -> Result<SceneDescription, BenchError> {
    let path = dir.join(name);
    let text = std::fs::read_to_string(&path)
        .map_err(|e| BenchError::Scene(format!("cannot read {}: {e}", path.display())))?;
    parse_scene(&text).map_err(|e| BenchError::Scene(format!("{}: {e}", path.display())))
}

/// Time `scene` `runs` times.
pub fn measure(name: &str, scene: &SceneDescription, runs: usize) -> Result<BenchLine, BenchError> {
    let common = scene.common();
    let fs = common.sample_rate;
    let (modes, block) = match scene {
        SceneDescription::HammerString(d) => (string_modes(&d.params.string, fs), 0),
        SceneDescription::SlideString(d) => (string_modes(&d.params.string, fs), d.params.block),
        SceneDescription::MassBarrier(_) => (0, 0),
    };
    let seconds = common.samples as f64 / f64::from(fs);
    let mut rtfs = Vec::with_capacity(runs);
    // One discarded warm-up run (page faults, clock ramp-up, CPU feature detection).
    render_output(scene, 64).map_err(|e| BenchError::Scene(e.to_string()))?;
    for _ in 0..runs.max(1) {
        let (_, wall) = render_output(scene, 64).map_err(|e| BenchError::Scene(e.to_string()))?;
        rtfs.push(wall / seconds);
    }
    rtfs.sort_by(f64::total_cmp);
    let rtf = rtfs[rtfs.len() / 2];
    Ok(BenchLine {
        name: name.to_owned(),
        method: common.solver.method.name(),
        segments: if common.solver.method == Method::Qsa { common.solver.segments } else { 0 },
        block,
        sample_rate: fs,
        modes,
        seconds,
        rtf,
        rtf_min: rtfs[0],
        ns_per_sample: rtf * 1e9 / f64::from(fs),
        runs: rtfs.len(),
        voices: 1,
    })
}

/// Sample rate of the instrument cases (Hz).
const PIANO_RATE: f64 = 48_000.0;

/// Time the instrument (in `mode`) playing `keys` together with the pedal down, `runs` times,
/// rendering `seconds` in calls of `call` samples.
pub fn measure_piano(name: &str, mode: Mode, keys: &[u8], seconds: f64, call: usize, runs: usize) -> BenchLine {
    let settings = Settings { mode, ..Settings::default() };
    let samples = (seconds * PIANO_RATE) as usize;
    let once = || {
        let mut piano = Instrument::new(PIANO_RATE, keys.len().max(1), settings);
        // One channel per note (the MPE way) so that slide notes are separate voices, not glides.
        for (i, &key) in keys.iter().enumerate() {
            let channel = if mode == Mode::Slide { (i % 16) as u8 } else { 0 };
            piano.handle(Event::Sustain { channel, down: true });
            piano.handle(Event::NoteOn { channel, key, velocity: 0.7 });
        }
        let (mut left, mut right) = (vec![0.0f32; call], vec![0.0f32; call]);
        let start = std::time::Instant::now();
        for _ in 0..samples / call {
            piano.process(&mut left, &mut right);
        }
        (start.elapsed().as_secs_f64(), piano.sounding())
    };
    once();
    let mut rtfs = Vec::with_capacity(runs);
    let mut sounding = 0;
    for _ in 0..runs.max(1) {
        let (wall, voices) = once();
        sounding = voices;
        rtfs.push(wall / seconds);
    }
    rtfs.sort_by(f64::total_cmp);
    let rtf = rtfs[rtfs.len() / 2];
    let modes = keys
        .iter()
        .map(|&k| {
            let string = match mode {
                Mode::Piano => qsa_dsp::instrument::PianoVoice::string_for(k, &settings),
                Mode::Slide => qsa_dsp::preset::slide_guitar().string,
            };
            qsa_dsp::string::ModalString::band_limited(string, PIANO_RATE, settings.max_frequency)
                .map_or(0, |s| s.modes())
        })
        .sum();
    BenchLine {
        name: name.to_owned(),
        method: settings.method.name(),
        segments: settings.segments,
        block: settings.block,
        sample_rate: PIANO_RATE as u32,
        modes,
        seconds,
        rtf,
        rtf_min: rtfs[0],
        ns_per_sample: rtf * 1e9 / PIANO_RATE,
        runs: rtfs.len(),
        voices: sounding,
    }
}

fn string_modes(params: &qsa_dsp::string::StringParams, fs: u32) -> usize {
    ModalString::new(*params, f64::from(fs)).map_or(0, |s| s.modes())
}

/// Run every case, printing one JSON line each.
pub fn run(args: &BenchArgs, stdout: &mut dyn Write) -> Result<Vec<BenchLine>, BenchError> {
    let hammer = load(&args.scenes, "fig5-hammer-c4.toml")?;
    let slide = load(&args.scenes, "slide-phrase.toml")?;
    let mut cases = Vec::new();
    for (method, segments) in [(Method::Qsa, 6), (Method::Exp, 6), (Method::Imp, 6)] {
        let scene = hammer.with_solver(SolverSettings { method, segments, v_ref: None });
        cases.push((format!("hammer-c4/{}", method.name()), scene));
    }
    for block in [1, 8, 64] {
        let mut scene = slide.clone();
        if let SceneDescription::SlideString(d) = &mut scene {
            d.params.block = block;
        }
        cases.push((format!("slide-phrase/nb{block}"), scene));
    }
    let mut lines = Vec::new();
    let mut emit = |line: BenchLine, lines: &mut Vec<BenchLine>| {
        writeln!(stdout, "{}", serde_json::to_string(&line).expect("a bench line serialises")).ok();
        lines.push(line);
    };
    for (name, scene) in cases.iter().filter(|(name, _)| name.contains(&args.filter)) {
        emit(measure(name, scene, args.runs)?, &mut lines);
    }
    // C3 (48) to C6 (84): 16 keys.
    let sixteen: Vec<u8> = (0..16).map(|i| 48 + (i * 36 / 15) as u8).collect();
    let all: Vec<u8> = (21..=108).collect();
    let cases = [
        ("piano/16-voices/64", Mode::Piano, &sixteen, 64),
        ("piano/16-voices/512", Mode::Piano, &sixteen, 512),
        ("slide/16-voices/64", Mode::Slide, &sixteen, 64),
        ("slide/16-voices/512", Mode::Slide, &sixteen, 512),
        ("piano/88-keys", Mode::Piano, &all, 64),
    ];
    for (name, mode, keys, call) in cases {
        if name.contains(&args.filter) {
            emit(measure_piano(name, mode, keys, 2.0, call, args.runs), &mut lines);
        }
    }
    Ok(lines)
}
