//! `cargo xtask bench`: real-time factors of whole voices, one JSON line per case.
//!
//! Each case renders a shipped scene through the real-time path ([`TimedOutput`] on the scene
//! [`qsa_dsp::scene_file::build()`] makes: output only, no energy bookkeeping) in calls of 64
//! samples, as a plugin would, `--runs` times; the line reports the median and the fastest RTF
//! (wall seconds per simulated second) measured in this one run of the command, after one
//! discarded warm-up run. Cases:
//! - `hammer-c4/{qsa,exp,imp}`: the Fig. 5 voice (C4 string, 56 modes at 44.1 kHz), QSA N = 6;
//! - `slide-phrase/nb{1,8,64}`: the slide phrase with control blocks of 1, 8 and 64 samples; on
//!   an AVX-512 machine (without `--isa`), `slide-phrase/nb{1,64}/avx` right after each, with the
//!   kernels an AVX2 machine runs, since their goal is an AVX2 machine's too (as are
//!   `piano/16-voices/64/avx` and `piano/88-keys/avx`);
//! - `piano/16-voices/{64,512}` and `slide/16-voices/{64,512}`: the instrument engine (the
//!   plugin's process path) at 48 kHz with 16 keys from C3 to C6 played together, pedal down,
//!   rendered in 64- and 512-sample calls; `slide/16-voices/64/acoustic` the slide notes on the
//!   acoustic guitar (each string on its copy of the body); `piano/16-voices/arpeggio` the same
//!   16 keys struck one after another every 80 ms, the pedal up, each held, in 64-sample calls:
//!   each key joins as a partner the bridges of the sounding keys whose partials it meets;
//! - `slide/1-voice/nb1/vibrato`: one slide note (A3) with a control block of one sample and a
//!   1.5 Hz vibrato by pitch bend, so that the slide and the finger trailing it move at every
//!   sample: the plugin's slide voice where it costs most;
//! - `piano/c4`: one C4 voice of the instrument at 48 kHz; its line says how many such voices fit
//!   in real time on one core: the radiating soundboards' cost (the voice's RTF less that of its
//!   dry output) paid once, each voice's over it ([`voices_that_fit`]);
//!   `piano/c4/nb1` the same with a control block of one sample (every block's work done every
//!   sample);
//! - `piano/88-keys`: all 88 keys (A0 to C8) struck together, pedal down, 48 kHz: the whole
//!   piano at once; `piano/88-keys/late-pedal` the same with the pedal pressed 0.5 s after the
//!   strike, when every key brings its partners onto its bridge (its worst call);
//! - `piano/automated` (a line of its own, not in the table): 8 keys ringing under the pedal, a
//!   second of calls with every continuous parameter moved before each call against the same
//!   second with them still; the ratio is 1 within the noise;
//! - `piano/restrike/{qsa,exp,imp}`: the 16 keys struck together at velocity 0.7, then again every
//!   40 ms, 49 times, each time at a seeded random velocity in [`RESTRIKE_VELOCITIES`] (the same
//!   for all 16, so that their contacts overlap), in calls of 16 samples, for each solver: every
//!   voice in contact at once, strike after strike, with contacts of many strengths.
//!
//! Instrument cases also time every process call: for each call the fastest of the runs (which
//! removes most of the machine's noise), then `call_mean_us`; `first_call_us`, the call that
//! starts every note; `call_worst_us`, the costliest of the others, with `worst_ratio` (over the
//! mean) and `worst_in_contact` (voices in contact as it began); `most_in_contact`; and
//! `worst_rtf`, the costliest call of all against its own duration.
//!
//! **All voices in contact at once.** A call counts as one when every voice played is in contact
//! as it begins and as it ends (a hammer touches its string over one stretch of time, a pressed
//! slide all along): `contact_calls` such calls, their mean `contact_mean_us`, the costliest
//! `contact_worst_us` and `contact_ratio`, worst over mean. This is the cost bound of the
//! contact step itself: with no data-dependent iteration the costliest such call stays close to
//! their mean, whatever the strength of the contacts. (`worst_ratio` instead compares a strike's
//! calls with a whole render's mean, mostly free strings, which take one register-resident pass a
//! sample and no solve.)
//!
//! The `peak` line measures the vector unit's peak (independent multiply–add chains, the
//! string's arithmetic without fusing) in Gflop/s. Lines of cases that are mostly free string
//! vibration (the paper's hammer voices) carry `roofline`: the measured mode updates per second
//! times [`FREE_STEP_FLOPS`] over that peak, the fraction of one core's arithmetic the modal loop
//! achieves. (A piano key's low modes step with the bridge at every sample, so it is not a free
//! string.)
//!
//! `--write` also writes `docs/report/bench.md` (the table and the JSON lines) and the table in
//! README.md between its `bench-table` markers.

use std::io::Write;
use std::path::{Path, PathBuf};

use clap::Args;
use qsa_dsp::contact::{Method, SolverSettings};
use qsa_dsp::instrument::{Event, Instrument, Mode, Settings, SlideBody};
use qsa_dsp::scene::Scene;
use qsa_dsp::scene_file::{Sampling, SceneDescription, SceneJob, build, parse_scene};
use qsa_dsp::string::{Isa, ModalString};
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
    /// Also write docs/report/bench.md and the table in README.md (needs every case).
    #[arg(long)]
    pub write: bool,
    /// Repository root, where `--write` writes.
    #[arg(long, default_value = ".")]
    pub root: PathBuf,
    /// Run the kernels on this vector unit or a narrower one, as a CPU without the wider units
    /// would (`avx` is what an AVX2 machine runs); the widest this CPU has by default.
    #[arg(long, value_enum)]
    pub isa: Option<IsaArg>,
}

/// A vector unit named on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum IsaArg {
    /// 512-bit registers.
    Avx512,
    /// 256-bit registers (AVX and AVX2 machines).
    Avx,
    /// No vector intrinsics.
    Portable,
}

impl IsaArg {
    fn isa(self) -> Isa {
        match self {
            IsaArg::Avx512 => Isa::Avx512,
            IsaArg::Avx => Isa::Avx,
            IsaArg::Portable => Isa::Portable,
        }
    }
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
    /// Fraction of the measured vector peak the modal loop achieves (free-vibration cases).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub roofline: Option<f64>,
    /// Voices like this one that fit in real time on one core.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fit: Option<usize>,
    /// Per-call figures (instrument cases).
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub calls: Option<CallStats>,
}

/// Costs of single process calls, each the fastest over the runs. The first call is the first
/// after every note began (the note-ons, which prepare each voice's strings, are handled before
/// it and not timed: docs/performance.md, *Starting a note*); the others step the strings and
/// the contacts.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct CallStats {
    /// Samples per call.
    pub call: usize,
    /// Mean cost of a call (µs).
    pub call_mean_us: f64,
    /// The first call after every note began (µs).
    pub first_call_us: f64,
    /// Costliest call after the first (µs).
    pub call_worst_us: f64,
    /// `call_worst_us / call_mean_us`.
    pub worst_ratio: f64,
    /// Voices in contact when the costliest call after the first began.
    pub worst_in_contact: usize,
    /// Most voices in contact at the start of any call.
    pub most_in_contact: usize,
    /// RTF of the costliest call of all (the first included) alone.
    pub worst_rtf: f64,
    /// Calls with every voice played in contact as they began and as they ended (after the
    /// first call).
    pub contact_calls: usize,
    /// Mean cost of those calls (µs; `null` without any).
    pub contact_mean_us: f64,
    /// Costliest of those calls (µs; `null` without any).
    pub contact_worst_us: f64,
    /// `contact_worst_us / contact_mean_us` (`null` without any).
    pub contact_ratio: f64,
}

/// Flops per mode and sample of a free string step ([`ModalString::free_steps`]: the recursion
/// `ũ^{n+1} = 2P ũ^n − Q ũ^{n−1}`, two products and a difference, and the output's product and
/// sum), for the roofline.
pub const FREE_STEP_FLOPS: f64 = 5.0;

/// The vector unit's measured peak, in Gflop/s (best of `runs`).
pub fn peak_gflops(runs: usize) -> f64 {
    let isa = qsa_dsp::string::Isa::detect();
    let iterations = 2_000_000;
    let (mut flops, mut best) = (0.0, f64::INFINITY);
    for _ in 0..runs.max(1) + 1 {
        let start = std::time::Instant::now();
        flops = qsa_dsp::bench_support::peak_probe(isa, std::hint::black_box(iterations));
        best = best.min(start.elapsed().as_secs_f64());
    }
    flops / best / 1e9
}

/// Why the bench could not run.
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    /// A scene file could not be read or parsed.
    #[error("{0}")]
    Scene(String),
    /// The documents could not be written.
    #[error("{0}")]
    Write(String),
}

/// The cases measured a second time with the AVX kernels on an AVX-512 machine (`NAME/avx`):
/// those whose goals an AVX2 machine must meet too.
const AVX_TWINS: [&str; 4] = ["slide-phrase/nb1", "slide-phrase/nb64", "piano/16-voices/64", "piano/88-keys"];

/// On an AVX-512 machine, unless `--isa` chose the kernels, a case of [`AVX_TWINS`] measured
/// again right after its own line with the kernels an AVX2 machine runs (the same bits), named
/// `NAME/avx`.
fn avx_twin<T>(name: &str, isa_chosen: bool, measure: impl FnOnce(&str) -> T) -> Option<T> {
    if !AVX_TWINS.contains(&name) || isa_chosen || Isa::detect() != Isa::Avx512 {
        return None;
    }
    Isa::cap(Isa::Avx);
    let twin = measure(&format!("{name}/avx"));
    Isa::cap(Isa::Avx512);
    Some(twin)
}

/// The real-time-factor goal of each case that has one.
fn goal(name: &str) -> &'static str {
    match name {
        "hammer-c4/qsa" => "≤ 0.001",
        "slide-phrase/nb1" | "slide-phrase/nb64" | "slide-phrase/nb1/avx" | "slide-phrase/nb64/avx" => "≤ 0.01",
        "piano/16-voices/64" | "piano/16-voices/512" | "piano/16-voices/64/avx" => "≤ 0.1",
        "piano/88-keys" | "piano/88-keys/avx" => "≤ 0.5",
        _ => "",
    }
}

/// Goal of the all-in-contact column: the costliest call with every voice in contact within
/// 1.5 times the mean of such calls (a bounded cost: no data-dependent iteration).
const CONTACT_GOAL: f64 = 1.5;

/// The Markdown table of `lines`.
pub fn table(lines: &[BenchLine]) -> String {
    let mut t = String::from(
        "| case | modes | voices | RTF (median) | goal | roofline | all voices in contact: worst / mean call (calls) | worst call / mean (in contact) | first call / mean | worst call RTF |\n\
         |---|---|---|---|---|---|---|---|---|---|\n",
    );
    for l in lines {
        let roofline = l.roofline.map_or(String::new(), |r| format!("{:.0} %", r * 100.0));
        let (contact, worst, first, worst_rtf) = l.calls.map_or(Default::default(), |c| {
            let contact = if c.contact_calls == 0 {
                "none".to_owned()
            } else {
                let verdict = if c.contact_ratio <= CONTACT_GOAL { "" } else { ", over the goal" };
                format!("{:.2} ({}{verdict})", c.contact_ratio, c.contact_calls)
            };
            (
                contact,
                format!("{:.2} ({}/{})", c.worst_ratio, c.worst_in_contact, c.most_in_contact),
                format!("{:.1}", c.first_call_us / c.call_mean_us),
                format!("{:.3}", c.worst_rtf),
            )
        });
        let fit = l.fit.map_or(String::new(), |f| format!(" ({f} fit)"));
        t += &format!(
            "| {} | {} | {} | {:.2e}{fit} | {} | {roofline} | {contact} | {worst} | {first} | {worst_rtf} |\n",
            l.name,
            l.modes,
            l.voices,
            l.rtf,
            goal(&l.name)
        );
    }
    t
}

const BEGIN: &str = "<!-- bench-table:begin -->";
const END: &str = "<!-- bench-table:end -->";

/// Write `docs/report/bench.md` and the table between the README's markers under `root`, each
/// through a temporary file renamed into place; a README without the markers in order is left as
/// it is.
fn write_docs(root: &Path, lines: &[BenchLine], peak: f64, isa: &str) -> Result<(), BenchError> {
    let err = |what: &Path, e: String| BenchError::Write(format!("{}: {e}", what.display()));
    let table = table(lines);
    let head = format!(
        "One run of `cargo xtask bench --write` on this machine ({} cores, {isa} kernels, measured \
         peak {peak:.1} Gflop/s for unfused multiply–adds).\n\n",
        std::thread::available_parallelism().map_or(1, |n| n.get())
    );
    let json: String = lines.iter().map(|l| serde_json::to_string(l).expect("serialises") + "\n").collect();
    let doc = format!(
        "# Benchmarks\n\nWritten by `cargo xtask bench --write`; see `xtask/src/bench.rs` for the cases \
         and the columns.\n\n{head}{table}\n```json\n{json}```\n"
    );
    let write = |path: &Path, text: &str| {
        crate::examples::write_atomically(path, |file| file.write_all(text.as_bytes()))
            .map_err(|e| err(path, e.to_string()))
    };
    let readme_path = root.join("README.md");
    let readme = std::fs::read_to_string(&readme_path).map_err(|e| err(&readme_path, e.to_string()))?;
    let Some((b, e)) = readme.find(BEGIN).zip(readme.find(END)).filter(|&(b, e)| b < e) else {
        return Err(err(&readme_path, format!("no {BEGIN} … {END} markers, in that order")));
    };
    write(&root.join("docs/report/bench.md"), &doc)?;
    write(&readme_path, &format!("{}{BEGIN}\n{head}{table}{}", &readme[..b], &readme[e..]))
}

fn load(dir: &Path, name: &str) -> Result<SceneDescription, BenchError> {
    let path = dir.join(name);
    let text = std::fs::read_to_string(&path)
        .map_err(|e| BenchError::Scene(format!("cannot read {}: {e}", path.display())))?;
    parse_scene(&text).map_err(|e| BenchError::Scene(format!("{}: {e}", path.display())))
}

/// Job: the real-time path of a scene, [`Scene::process_output`] in calls of `chunk` samples
/// with no frames and no energy bookkeeping; returns the wall-clock seconds it took.
#[derive(Debug, Clone, Copy)]
pub struct TimedOutput {
    /// Samples per call (at least 1).
    pub chunk: usize,
}

impl SceneJob for TimedOutput {
    type Output = f64;

    fn run(self, mut scene: impl Scene, samples: usize, _segments: usize) -> f64 {
        let mut out = vec![0.0; samples];
        // Write every page before the clock starts (a fresh zeroed allocation is mapped lazily):
        // a host's buffers are mapped already, so first-touch page faults are not the scene's cost.
        out.fill(std::hint::black_box(0.0));
        let start = std::time::Instant::now();
        for block in out.chunks_mut(self.chunk.max(1)) {
            scene.process_output(block);
        }
        let wall = start.elapsed().as_secs_f64();
        std::hint::black_box(&out);
        wall
    }
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
    let timed = || {
        build(scene, &common.solver, Sampling::NATIVE, TimedOutput { chunk: 64 })
            .map_err(|e| BenchError::Scene(e.to_string()))
    };
    timed()?;
    for _ in 0..runs.max(1) {
        let wall = timed()?;
        rtfs.push(wall / seconds);
    }
    let rtf = median(&mut rtfs);
    Ok(BenchLine {
        name: name.to_owned(),
        method: common.solver.method.name(),
        segments: qsa_segments(common.solver.method, common.solver.segments),
        block,
        sample_rate: fs,
        modes,
        seconds,
        rtf,
        rtf_min: rtfs[0],
        ns_per_sample: rtf * 1e9 / f64::from(fs),
        runs: rtfs.len(),
        voices: 1,
        roofline: None,
        fit: None,
        calls: None,
    })
}

/// Sample rate of the instrument cases (Hz).
const PIANO_RATE: f64 = 48_000.0;

/// The median of `values` (sorted in place): the middle one, or the mean of the middle two.
pub fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n % 2 == 1 { values[n / 2] } else { 0.5 * (values[n / 2 - 1] + values[n / 2]) }
}

/// How many voices fit in real time on one core, from the RTF of an instrument with one voice
/// sounding, `with_one`, and the part of it the instrument pays once whatever sounds, `shared`
/// (its radiating soundboards): that part once, and each voice's over it until the core is full.
/// `None` if the voice costs nothing measurable.
pub fn voices_that_fit(with_one: f64, shared: f64) -> Option<usize> {
    let shared = shared.max(0.0);
    let voice = with_one - shared;
    (voice > 0.0 && shared < 1.0).then(|| ((1.0 - shared) / voice) as usize)
}

/// Velocities of the re-strikes (0..1, as the instrument takes them): hammer speeds of 0.64 to
/// 2.85 m/s ([`qsa_dsp::instrument::hammer_speed`]), soft enough that the 16 contacts of a strike
/// often overlap for whole 16-sample calls.
pub const RESTRIKE_VELOCITIES: std::ops::Range<f32> = 0.1..0.7;

/// What an instrument case plays: `keys` together with the pedal down at velocity 0.7, and, with
/// `restrike`, all of them again every `restrike.0` calls at one velocity drawn from
/// [`RESTRIKE_VELOCITIES`] by a generator seeded with `restrike.1`; with `arpeggio`, one after
/// another with the pedal up instead, held.
#[derive(Debug, Clone, Copy)]
pub struct Performance<'a> {
    /// MIDI keys.
    pub keys: &'a [u8],
    /// Calls between strikes and the velocities' seed.
    pub restrike: Option<(usize, u64)>,
    /// The call before which the sustain pedal goes down, if not with the first strike.
    pub late_pedal: Option<usize>,
    /// Calls between the keys struck one at a time, the pedal up, each held: every key joins the
    /// bridges of the sounding keys whose partials it meets as a partner.
    pub arpeggio: Option<usize>,
    /// A vibrato of this rate (Hz) by pitch bend, ±half the bend range, set before every call:
    /// a slide that never stops moving.
    pub vibrato: Option<f64>,
    /// Whether the instrument gives its dry output, without the radiating soundboards.
    pub dry: bool,
}

/// Time the instrument with `settings` playing `play` for `seconds` in calls of `call` samples,
/// `runs` times.
pub fn measure_piano(
    name: &str,
    settings: Settings,
    play: Performance<'_>,
    seconds: f64,
    call: usize,
    runs: usize,
) -> BenchLine {
    use rand::{RngExt, SeedableRng};
    let (mode, keys) = (settings.mode, play.keys);
    let samples = (seconds * PIANO_RATE) as usize;
    let strike = |piano: &mut Instrument, velocity: f32| {
        // One channel per note (the MPE way) so that slide notes are separate voices, not glides.
        for (i, &key) in keys.iter().enumerate() {
            let channel = if mode == Mode::Slide { (i % 16) as u8 } else { 0 };
            if play.late_pedal.is_none() && play.arpeggio.is_none() {
                piano.handle(Event::Sustain { channel, depth: 1.0 });
            }
            piano.handle(Event::NoteOn { channel, key, velocity });
        }
    };
    let once = || {
        let mut piano = Instrument::new(PIANO_RATE, keys.len().max(1), settings);
        piano.set_raw_output(play.dry);
        let mut velocities = rand_pcg::Pcg64::seed_from_u64(play.restrike.map_or(0, |r| r.1));
        if play.arpeggio.is_none() {
            strike(&mut piano, 0.7);
        }
        let (mut left, mut right) = (vec![0.0f32; call], vec![0.0f32; call]);
        let mut calls = Vec::with_capacity(samples / call);
        let start = std::time::Instant::now();
        for n in 0..samples / call {
            if let Some((every, _)) = play.restrike
                && n > 0
                && n % every == 0
            {
                strike(&mut piano, velocities.random_range(RESTRIKE_VELOCITIES));
            }
            if play.late_pedal == Some(n) {
                piano.handle(Event::Sustain { channel: 0, depth: 1.0 });
            }
            if let Some(every) = play.arpeggio
                && n % every == 0
                && let Some(&key) = keys.get(n / every)
            {
                piano.handle(Event::NoteOn { channel: 0, key, velocity: 0.7 });
            }
            if let Some(rate) = play.vibrato {
                let phase = std::f64::consts::TAU * rate * (n * call) as f64 / PIANO_RATE;
                let value = (0.5 * phase.sin()) as f32;
                for channel in 0..keys.len().min(16) as u8 {
                    piano.handle(Event::PitchBend { channel, value });
                }
            }
            let in_contact = piano.in_contact();
            let t = std::time::Instant::now();
            piano.process(&mut left, &mut right);
            calls.push(Call { seconds: t.elapsed().as_secs_f64(), in_contact, after: piano.in_contact() });
        }
        (start.elapsed().as_secs_f64(), piano.sounding(), calls)
    };
    // The warm-up run is discarded. The wall time covers the events handled between the calls
    // (note-ons, the pedal, bends) as a plugin's process call pays for them; the simulated time
    // is that of the whole calls made.
    let simulated = (samples / call * call) as f64 / PIANO_RATE;
    let _ = once();
    let mut rtfs = Vec::with_capacity(runs);
    let mut sounding = 0;
    let mut fastest: Vec<Call> = Vec::new();
    for _ in 0..runs.max(1) {
        let (wall, voices, calls) = once();
        sounding = voices;
        rtfs.push(wall / simulated);
        if fastest.is_empty() {
            fastest = calls;
        } else {
            for (best, c) in fastest.iter_mut().zip(calls) {
                best.seconds = best.seconds.min(c.seconds);
            }
        }
    }
    let calls = CallStats::of(&fastest, keys.len(), call);
    let rtf = median(&mut rtfs);
    // The modes a voice steps as it is struck: a piano key's strings and its copy of the
    // soundboard (not the partner strings it steps with the pedal down); a slide voice's string,
    // and the acoustic guitar's body when it sounds on one.
    let board = qsa_dsp::bridge::BridgeParams::soundboard(qsa_dsp::bridge::SOUNDBOARD_CONDUCTANCE);
    let board_modes = board.modes.iter().filter(|m| m.frequency < 0.49 * PIANO_RATE).count();
    let body_modes = match settings.slide_body {
        SlideBody::Acoustic => {
            let body = qsa_dsp::body::BodyParams::guitar();
            body.modes.iter().filter(|m| m.mode.frequency < 0.49 * PIANO_RATE).count()
        }
        SlideBody::Pickup => 0,
    };
    let modes = keys
        .iter()
        .map(|&k| {
            let (string, strings, bridge) = match mode {
                Mode::Piano => (
                    qsa_dsp::instrument::PianoVoice::string_for(k, &settings),
                    qsa_dsp::preset::piano_note(k).strings,
                    board_modes,
                ),
                Mode::Slide => (qsa_dsp::preset::slide_guitar().string, 1, body_modes),
            };
            let one = qsa_dsp::string::ModalString::band_limited(string, PIANO_RATE, settings.max_frequency)
                .map_or(0, |s| s.modes());
            strings * one + bridge
        })
        .sum();
    BenchLine {
        name: name.to_owned(),
        method: settings.method.name(),
        segments: qsa_segments(settings.method, settings.segments),
        block: settings.block,
        sample_rate: PIANO_RATE as u32,
        modes,
        seconds,
        rtf,
        rtf_min: rtfs[0],
        ns_per_sample: rtf * 1e9 / PIANO_RATE,
        runs: rtfs.len(),
        voices: sounding,
        roofline: None,
        fit: None,
        calls: Some(calls),
    }
}

/// One timed process call.
#[derive(Debug, Clone, Copy)]
struct Call {
    /// Wall time (s).
    seconds: f64,
    /// Voices in contact as the call began.
    in_contact: usize,
    /// Voices in contact as it ended.
    after: usize,
}

impl CallStats {
    /// The figures of `calls` (each the fastest over the runs) of `call` samples, with `played`
    /// voices played.
    fn of(calls: &[Call], played: usize, call: usize) -> Self {
        let mean_of = |c: &[f64]| c.iter().sum::<f64>() / c.len() as f64;
        let all: Vec<f64> = calls.iter().map(|c| c.seconds).collect();
        let mean = mean_of(&all);
        let first = all[0];
        let (worst, worst_in_contact) = calls
            .iter()
            .skip(1)
            .map(|c| (c.seconds, c.in_contact))
            .max_by(|a, b| a.0.total_cmp(&b.0))
            .unwrap_or((first, calls[0].in_contact));
        let contact: Vec<f64> =
            calls.iter().skip(1).filter(|c| c.in_contact == played && c.after == played).map(|c| c.seconds).collect();
        // With no such call both are NaN (0/0 and the fold's start): `null` in the JSON line.
        let contact_mean = mean_of(&contact);
        let contact_worst = contact.iter().copied().fold(f64::NAN, f64::max);
        CallStats {
            call,
            call_mean_us: mean * 1e6,
            first_call_us: first * 1e6,
            call_worst_us: worst * 1e6,
            worst_ratio: worst / mean,
            worst_in_contact,
            most_in_contact: calls.iter().map(|c| c.in_contact).max().unwrap_or(0),
            worst_rtf: worst.max(first) / (call as f64 / PIANO_RATE),
            contact_calls: contact.len(),
            contact_mean_us: contact_mean * 1e6,
            contact_worst_us: contact_worst * 1e6,
            contact_ratio: contact_worst / contact_mean,
        }
    }
}

/// The QSA segment count a line reports: `segments` for QSA, 0 for the solvers without any.
fn qsa_segments(method: Method, segments: usize) -> usize {
    if method == Method::Qsa { segments } else { 0 }
}

fn string_modes(params: &qsa_dsp::string::StringParams, fs: u32) -> usize {
    ModalString::new(*params, f64::from(fs)).map_or(0, |s| s.modes())
}

/// Run every case, printing one JSON line each.
pub fn run(args: &BenchArgs, stdout: &mut dyn Write) -> Result<Vec<BenchLine>, BenchError> {
    if args.write && (!args.filter.is_empty() || args.isa.is_some()) {
        return Err(BenchError::Write("--write documents every case on this CPU; drop --filter and --isa".into()));
    }
    if let Some(isa) = args.isa {
        qsa_dsp::string::Isa::cap(isa.isa());
    }
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
    let peak = peak_gflops(args.runs);
    let isa = format!("{:?}", qsa_dsp::string::Isa::detect());
    writeln!(stdout, "{}", serde_json::json!({ "name": "peak", "isa": isa, "gflops": peak })).ok();
    // Fraction of the peak reached by `modes × samples` free-step mode updates in `rtf`.
    let roofline = |modes: usize, fs: u32, rtf: f64| modes as f64 * f64::from(fs) * FREE_STEP_FLOPS / rtf / 1e9 / peak;
    let mut lines = Vec::new();
    let mut emit = |line: BenchLine, lines: &mut Vec<BenchLine>| {
        writeln!(stdout, "{}", serde_json::to_string(&line).expect("a bench line serialises")).ok();
        lines.push(line);
    };
    for (name, scene) in cases.iter().filter(|(name, _)| name.contains(&args.filter)) {
        let mut line = measure(name, scene, args.runs)?;
        if name.starts_with("hammer") {
            line.roofline = Some(roofline(line.modes, line.sample_rate, line.rtf));
        }
        emit(line, &mut lines);
        if let Some(twin) = avx_twin(name, args.isa.is_some(), |name| measure(name, scene, args.runs)) {
            emit(twin?, &mut lines);
        }
    }
    // C3 (48) to C6 (84): 16 keys.
    let sixteen: Vec<u8> = (0..16).map(|i| 48 + (i * 36 / 15) as u8).collect();
    let all: Vec<u8> = (21..=108).collect();
    let c4 = vec![60u8];
    let piano = Settings { mode: Mode::Piano, ..Settings::default() };
    let slide = Settings { mode: Mode::Slide, ..Settings::default() };
    let acoustic = Settings { slide_body: SlideBody::Acoustic, ..slide };
    let once = |keys| Performance { keys, restrike: None, late_pedal: None, arpeggio: None, vibrato: None, dry: false };
    // Every 120 calls of 16 samples: 40 ms, 50 strikes in 2 s.
    let restrike = Performance { restrike: Some((120, 6)), ..once(&sixteen) };
    // A key every 80 ms, the pedal up, held: 16 keys in 1.28 s.
    let arpeggio = Performance { arpeggio: Some(60), ..once(&sixteen) };
    // The pedal 0.5 s after the strike: every key brings its partners in.
    let late_pedal = Performance { late_pedal: Some(375), ..once(&all) };
    // A3 with a 1.5 Hz vibrato of ±1 semitone (half the default bend range of 2), at N_b = 1.
    let a3 = vec![57u8];
    let vibrato = Performance { vibrato: Some(1.5), ..once(&a3) };
    let slide_nb1 = Settings { block: 1, ..slide };
    let piano_nb1 = Settings { block: 1, ..piano };
    let with = |method| Settings { method, ..piano };
    let cases = [
        ("piano/c4", piano, once(&c4), 64),
        ("piano/c4/nb1", piano_nb1, once(&c4), 64),
        ("piano/16-voices/64", piano, once(&sixteen), 64),
        ("piano/16-voices/512", piano, once(&sixteen), 512),
        ("piano/16-voices/arpeggio", piano, arpeggio, 64),
        ("slide/16-voices/64", slide, once(&sixteen), 64),
        ("slide/16-voices/512", slide, once(&sixteen), 512),
        ("slide/16-voices/64/acoustic", acoustic, once(&sixteen), 64),
        ("slide/1-voice/nb1/vibrato", slide_nb1, vibrato, 64),
        ("piano/88-keys", piano, once(&all), 64),
        ("piano/88-keys/late-pedal", piano, late_pedal, 64),
        ("piano/restrike/qsa", with(Method::Qsa), restrike, 16),
        ("piano/restrike/exp", with(Method::Exp), restrike, 16),
        ("piano/restrike/imp", with(Method::Imp), restrike, 16),
    ];
    for (name, settings, play, call) in cases {
        if name.contains(&args.filter) {
            let mut line = measure_piano(name, settings, play, 2.0, call, args.runs);
            if name == "piano/c4" {
                let dry = Performance { dry: true, ..play };
                let dry = measure_piano("piano/c4/dry", settings, dry, 2.0, call, args.runs);
                line.fit = voices_that_fit(line.rtf, line.rtf - dry.rtf);
            }
            emit(line, &mut lines);
            let twin = |name: &str| measure_piano(name, settings, play, 2.0, call, args.runs);
            if let Some(twin) = avx_twin(name, args.isa.is_some(), twin) {
                emit(twin, &mut lines);
            }
        }
    }
    if "piano/after-release".contains(&args.filter) {
        writeln!(stdout, "{}", after_release(args.runs)).ok();
    }
    if "piano/automated".contains(&args.filter) {
        writeln!(stdout, "{}", automated(args.runs)).ok();
    }
    if args.write {
        write_docs(&args.root, &lines, peak, &isa)?;
    }
    Ok(lines)
}

/// The cost of a piano that has played and fallen silent against one that never played: 200
/// short notes (50 ms each, one every 60 ms, seeded keys with dampers, A0–D♯6, and velocities) on
/// 32 voices, then 8 s for the release tails (the partners without dampers that the notes set
/// ringing sound on for a few seconds, and the radiating soundboard after them), then one more
/// second of 64-sample calls, timed (fastest of `runs` per call, summed), against the same second
/// of a fresh instrument. Released voices cost nothing, so the ratio is 1 within the noise. (The
/// keys without dampers ring on after release, for up to 22 s, and cost what a held note does.)
fn after_release(runs: usize) -> serde_json::Value {
    use rand::{RngExt, SeedableRng};
    let call = 64;
    let second = (PIANO_RATE as usize) / call;
    let settings = Settings::default();
    let played = || {
        let mut piano = Instrument::new(PIANO_RATE, 32, settings);
        let mut rng = rand_pcg::Pcg64::seed_from_u64(200);
        let (mut left, mut right) = (vec![0.0f32; call], vec![0.0f32; call]);
        let (note, gap) = ((0.05 * PIANO_RATE) as usize / call, (0.06 * PIANO_RATE) as usize / call);
        for _ in 0..200 {
            let key = rng.random_range(21..qsa_dsp::instrument::FIRST_UNDAMPED_KEY);
            piano.handle(Event::NoteOn { channel: 0, key, velocity: rng.random_range(0.1..1.0f32) });
            for n in 0..gap {
                if n == note {
                    piano.handle(Event::NoteOff { channel: 0, key });
                }
                piano.process(&mut left, &mut right);
            }
        }
        for _ in 0..8 * second {
            piano.process(&mut left, &mut right);
        }
        piano
    };
    let timed = |piano: &mut Instrument| {
        let (mut left, mut right) = (vec![0.0f32; call], vec![0.0f32; call]);
        (0..second)
            .map(|_| {
                let t = std::time::Instant::now();
                piano.process(&mut left, &mut right);
                t.elapsed().as_secs_f64()
            })
            .collect::<Vec<f64>>()
    };
    let (mut idle, mut after) = (vec![f64::INFINITY; second], vec![f64::INFINITY; second]);
    let mut sounding = 0;
    for _ in 0..runs.max(1) {
        let mut fresh = Instrument::new(PIANO_RATE, 32, settings);
        let mut used = played();
        sounding = used.sounding();
        keep_fastest(&mut idle, timed(&mut fresh));
        keep_fastest(&mut after, timed(&mut used));
    }
    serde_json::json!({
        "name": "piano/after-release",
        "voices": 32,
        "sounding": sounding,
        "idle_call_us": mean_us(&idle),
        "after_call_us": mean_us(&after),
        "ratio": mean_us(&after) / mean_us(&idle),
    })
}

/// What a host automating every parameter costs the piano: 8 keys (C2 to C6) struck with the
/// pedal down and held on 32 voices, then, from a quarter second after the strike, one second of
/// 64-sample calls timed (fastest of `runs` per call, summed), with every continuous parameter
/// moved before every call (each along a triangle from its lowest to its highest value and back,
/// at its own rate, 100 to 224 calls a period), against the same second with the parameters
/// still. In piano mode they change only notes struck later, or nothing that sounds (the slide
/// guitar's), so the ratio is 1 within the noise.
fn automated(runs: usize) -> serde_json::Value {
    use qsa_dsp::instrument::{PARAMETERS, ParamKind, ParamValues};
    let call = 64;
    let second = (PIANO_RATE as usize) / call;
    let keys = [36u8, 43, 48, 55, 60, 64, 67, 84];
    let moved = |n: usize| {
        let mut values = ParamValues::default();
        for (i, spec) in PARAMETERS.iter().enumerate() {
            if let ParamKind::Float { min, max, scale, .. } = spec.kind {
                let period = 100 + 4 * i;
                let phase = (n % period) as f32 / period as f32;
                let x = 1.0 - (2.0 * phase - 1.0).abs();
                (spec.put)(&mut values, scale.to_plain(min + (max - min) * x));
            }
        }
        values.settings()
    };
    let timed = |automate: bool| {
        let mut piano = Instrument::new(PIANO_RATE, 32, Settings::default());
        piano.handle(Event::Sustain { channel: 0, depth: 1.0 });
        for key in keys {
            piano.handle(Event::NoteOn { channel: 0, key, velocity: 0.7 });
        }
        let (mut left, mut right) = (vec![0.0f32; call], vec![0.0f32; call]);
        // The strike's calls first, untimed: what is compared is the ringing chord.
        for _ in 0..second / 4 {
            piano.process(&mut left, &mut right);
        }
        (0..second)
            .map(|n| {
                let settings = if automate { moved(n) } else { Settings::default() };
                let t = std::time::Instant::now();
                piano.set_settings(&settings);
                piano.process(&mut left, &mut right);
                t.elapsed().as_secs_f64()
            })
            .collect::<Vec<f64>>()
    };
    let (mut still, mut swept) = (vec![f64::INFINITY; second], vec![f64::INFINITY; second]);
    for _ in 0..runs.max(1) {
        keep_fastest(&mut still, timed(false));
        keep_fastest(&mut swept, timed(true));
    }
    serde_json::json!({
        "name": "piano/automated",
        "voices": 32,
        "keys": keys.len(),
        "still_call_us": mean_us(&still),
        "automated_call_us": mean_us(&swept),
        "ratio": mean_us(&swept) / mean_us(&still),
    })
}

/// Keep in `best` each call's fastest time (s) of the runs so far, given this run's `times`.
fn keep_fastest(best: &mut [f64], times: Vec<f64>) {
    for (best, t) in best.iter_mut().zip(times) {
        *best = best.min(t);
    }
}

/// The mean of call times `x` (s), in µs.
fn mean_us(x: &[f64]) -> f64 {
    x.iter().sum::<f64>() / x.len() as f64 * 1e6
}

#[cfg(test)]
mod tests {
    use super::*;

    fn call(micros: f64, in_contact: usize, after: usize) -> Call {
        Call { seconds: micros * 1e-6, in_contact, after }
    }

    /// The median of an even number of runs is the mean of the middle two, not the slower one.
    #[test]
    fn the_median_of_an_even_count_is_the_mean_of_the_middle_two() {
        assert_eq!(median(&mut [3.0, 1.0]), 2.0);
        assert_eq!(median(&mut [4.0, 1.0, 3.0, 2.0]), 2.5);
        assert_eq!(median(&mut [5.0, 1.0, 3.0]), 3.0);
    }

    /// The soundboards' cost is paid once, not once per voice: with the README's figures, a C4
    /// voice and the instrument at 6.16e-3 of the core, the soundboards' share 2.9e-3 of it,
    /// 305 voices fit, not the 162 that `1/rtf` gives; a voice costing nothing says nothing.
    #[test]
    fn voices_that_fit_pay_the_instruments_own_cost_once() {
        assert_eq!(voices_that_fit(6.16e-3, 2.9e-3), Some(305));
        assert_eq!(voices_that_fit(6.16e-3, 0.0), Some(162));
        assert_eq!(voices_that_fit(2.9e-3, 2.9e-3), None);
    }

    #[test]
    fn contact_figures_take_only_calls_with_every_voice_in_contact_throughout() {
        // Two voices played. The first call (which starts the notes) never counts; a call
        // counts only with both voices in contact as it begins and as it ends.
        let calls = [
            call(50.0, 2, 2), // first call: excluded although in contact
            call(10.0, 2, 2),
            call(14.0, 2, 2),
            call(30.0, 2, 1), // contact ends inside the call
            call(20.0, 1, 2), // contact begins inside the call
            call(2.0, 0, 0),
        ];
        let s = CallStats::of(&calls, 2, 64);
        assert_eq!(s.contact_calls, 2);
        assert!((s.contact_mean_us - 12.0).abs() < 1e-9);
        assert!((s.contact_worst_us - 14.0).abs() < 1e-9);
        assert!((s.contact_ratio - 14.0 / 12.0).abs() < 1e-12);
        // The whole-render figures: mean over every call, worst after the first.
        assert!((s.call_mean_us - 126.0 / 6.0).abs() < 1e-9);
        assert!((s.call_worst_us - 30.0).abs() < 1e-9);
        assert_eq!((s.worst_in_contact, s.most_in_contact), (2, 2));
        // The costliest call of all (the first) against a 64-sample call's duration.
        assert!((s.worst_rtf - 50e-6 / (64.0 / PIANO_RATE)).abs() < 1e-12);
    }

    #[test]
    fn contact_figures_are_absent_without_such_calls() {
        let calls = [call(50.0, 1, 1), call(3.0, 1, 0), call(2.0, 0, 0)];
        let s = CallStats::of(&calls, 1, 64);
        assert_eq!(s.contact_calls, 0);
        assert!(s.contact_mean_us.is_nan() && s.contact_ratio.is_nan());
        let line = BenchLine {
            name: "piano/x".into(),
            method: "qsa",
            segments: 6,
            block: 64,
            sample_rate: 48_000,
            modes: 53,
            seconds: 1.0,
            rtf: 1e-3,
            rtf_min: 1e-3,
            ns_per_sample: 20.0,
            runs: 1,
            voices: 1,
            roofline: None,
            fit: None,
            calls: Some(s),
        };
        assert!(table(std::slice::from_ref(&line)).contains("| none |"));
        // NaN figures serialise as JSON null, not as an invalid number.
        let json = serde_json::to_string(&line).expect("serialises");
        assert!(json.contains("\"contact_ratio\":null"), "{json}");
    }
}
