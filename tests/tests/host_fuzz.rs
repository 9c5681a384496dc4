//! The bundled CLAP plugin under a host's parameter fuzzer: clack-host loads
//! `target/bundled/QSA Strings.clap` and drives it through thousands of random parameter
//! permutations while notes and controllers play, the way a host's plug-in validator does, and
//! every output sample is checked.
//!
//! - A permutation sets every parameter but `Output gain` to its minimum, its maximum or a random
//!   value (a random step of the stepped ones); a third of them send every parameter to the
//!   extreme opposite to where it was, so the settings often jump from one end of every range to
//!   the other. Every pairing of mode and solver is in force for dozens of notes (checked).
//! - Permutations follow each other at intervals of 1, 10, 100 or 1,000 samples, in runs that
//!   end with a hold of up to a tenth of a second, and land anywhere inside the host's buffers,
//!   whose sizes are random from 1 to 4,096 samples: the changes are sample-accurate (CLAP
//!   parameter events timed inside a buffer). `Voices` takes effect when the host re-activates
//!   the plugin, which it does every 500 permutations, each time at the next of 96, 44.1, 22.05
//!   and 48 kHz (it starts at 48 kHz).
//! - Meanwhile notes (CLAP note events and MIDI note messages: single keys, repeated keys,
//!   chords, CLAP note-ons at velocity 0, releases, CLAP chokes and note-offs of a key on every
//!   channel or of every note), the sustain, sostenuto and soft pedals (CC64, CC66, CC67), pitch
//!   bend and the parameter-number controllers (CC101, CC100, CC99, CC98, CC6: pitch-bend
//!   sensitivity, MPE zones, a non-registered parameter), channel and
//!   poly pressure, the mod wheel (CC1), CC74, reset-all-controllers (CC121) and all-notes-off
//!   (CC123) play on every channel.
//!
//! The default run is 2,000 permutations with a fixed seed; `QSA_FUZZ_PERMUTATIONS=20000` runs
//! longer and `QSA_FUZZ_SEED=n` picks another seed. A failure names the seed, the permutation,
//! the sample, the parameter values in force and the events leading up to it, and the command
//! that replays it.
//!
//! The bundle is built by `cargo xtask bundle qsa-plugin --release`; a missing or stale bundle
//! fails the test with that instruction.

use std::fmt::Write as _;
use std::time::Instant;

use qsa_tests::seeded_rng;
use rand::RngExt;
use rand_pcg::Pcg64;

#[path = "support/bundle.rs"]
mod bundle;
#[path = "support/host.rs"]
mod host;
use host::{Ev, PARAMETERS, Plugin, Score, Target, clap_id, release_bundle};

/// Sample rate of the fuzzed instance as it starts.
const FS: f64 = 48_000.0;

/// The sample rates of the re-activations, in turn: a host's session switched to another rate
/// (the times below stay counted in samples).
const RATES: [f64; 4] = [96_000.0, 44_100.0, 22_050.0, 48_000.0];

/// The sample rate in force for permutation `index`.
fn rate_at(index: usize) -> f64 {
    match index / REACTIVATE_EVERY {
        0 => FS,
        n => RATES[(n - 1) % RATES.len()],
    }
}

/// Largest host buffer (the instance is activated for it).
const MAX_HOST_BUFFER: usize = 4096;

/// Samples between consecutive permutations within a run.
const INTERVALS: [usize; 4] = [1, 10, 100, 1_000];

/// Permutations in the default run, and the environment variable that sets another count.
const DEFAULT_PERMUTATIONS: usize = 2_000;
const PERMUTATIONS_ENV: &str = "QSA_FUZZ_PERMUTATIONS";

/// The default seed, and the environment variable that sets another.
const DEFAULT_SEED: u64 = 20_240_611;
const SEED_ENV: &str = "QSA_FUZZ_SEED";

/// The ceiling every sample must stay under, in dBFS (with `Output gain` at its default, 0 dB).
const CEILING_DB: f64 = 12.0;

/// Permutations per render call (the host's buffers run across permutations within a call).
const PERMUTATIONS_PER_CALL: usize = 50;

/// Permutations between re-activations (which apply `Voices`). A multiple of [`PERMUTATIONS_PER_CALL`].
const REACTIVATE_EVERY: usize = 500;

/// Longest hold after a run of permutations (0.1 s), and the ring-out after the last one.
const MAX_HOLD: usize = 4_800;
const RING_OUT: usize = 24_000;

/// Most permutations in a run at one interval.
const MAX_RUN: usize = 12;

/// Samples after a note-on during which the fuzz counts the note as sounding for the ceiling:
/// one second (a slide note is muted at note-off; a piano note's damper falls, or the pedal
/// holds it, but its level has long fallen from its attack).
const SOUNDING: usize = 48_000;

/// Samples after the plugin reports a note ended during which the fuzz still counts it: 10 ms,
/// twice a stolen or choked note's 5 ms fade.
const END_MARGIN: usize = 480;

/// Most keys held at once (beyond it, the oldest is released before a new note).
const MAX_HELD: usize = 12;

/// The fuzzed parameters: every documented one but `Output gain`, which stays at its default
/// (0 dB) so that the ceiling is the instrument's own level. (id, step count of a stepped
/// parameter: CLAP values span 0..=steps, or 0..=1 for a continuous one.)
fn fuzzed() -> Vec<(&'static str, Option<u32>)> {
    PARAMETERS.iter().filter(|p| p.0 != "gain").map(|&(id, _, steps)| (id, steps)).collect()
}

/// One set of parameter values and when it takes effect.
#[derive(Debug, Clone)]
struct Permutation {
    /// Sample (from the start of the run) of its parameter events.
    start: usize,
    /// Spacing of its run.
    interval: usize,
    /// CLAP values, in the order of [`fuzzed`].
    values: Vec<f64>,
}

impl Permutation {
    /// The CLAP value of a fuzzed parameter.
    fn get(&self, params: &[(&str, Option<u32>)], id: &str) -> f64 {
        self.values[params.iter().position(|p| p.0 == id).expect("a fuzzed id")]
    }
}

/// The whole fuzz run: permutations and the events (parameters, notes, controllers) in time
/// order, generated up front from the seed. Permutation `i` and everything before it do not
/// depend on how many follow, so a shorter run replays a longer one's beginning exactly.
struct Run {
    params: Vec<(&'static str, Option<u32>)>,
    permutations: Vec<Permutation>,
    score: Score,
    samples: usize,
    /// Note-ons per (mode, solver) of the permutation in force.
    notes_by_setting: [[usize; 3]; 2],
}

/// Generator state: the random stream, the keys held (channel, key) and keys played recently.
struct Generator {
    rng: Pcg64,
    held: Vec<(u8, u8)>,
    recent: Vec<(u8, u8)>,
}

impl Run {
    fn new(seed: u64, count: usize) -> Self {
        let params = fuzzed();
        let mut g = Generator { rng: seeded_rng(seed), held: Vec::new(), recent: Vec::new() };
        let mut permutations: Vec<Permutation> = Vec::with_capacity(count);
        let mut score = Score::new();
        let mut notes_by_setting = [[0; 3]; 2];
        let (mut t, mut next_gesture) = (0, 0);
        while permutations.len() < count {
            let interval = INTERVALS[g.rng.random_range(0..INTERVALS.len())];
            let run = g.rng.random_range(1..=MAX_RUN).min(count - permutations.len());
            for i in 0..run {
                let previous = permutations.last().map(|p| p.values.as_slice());
                let values = g.values(&params, previous);
                score.extend(params.iter().zip(&values).map(|(p, &v)| (t, Ev::Param(clap_id(p.0), v))));
                let p = Permutation { start: t, interval, values };
                // Drawn for every permutation, so that a shorter run draws the same numbers.
                let hold = g.rng.random_range(0..=MAX_HOLD);
                let hold = if i + 1 == run { hold } else { 0 };
                let end = t + interval + hold;
                let (mode, solver) = (p.get(&params, "mode") as usize, p.get(&params, "solver") as usize);
                while next_gesture < end {
                    let notes = g.gesture(next_gesture, &mut score);
                    notes_by_setting[mode][solver] += notes;
                    next_gesture += g.gap();
                }
                permutations.push(p);
                t = end;
            }
        }
        let samples = t + RING_OUT;
        score.extend(g.held.drain(..).map(|(channel, key)| (t, Ev::Off(channel, key))));
        score.sort_by_key(|e| e.0);
        Self { params, permutations, score, samples, notes_by_setting }
    }

    /// Index of the permutation in force at `sample`.
    fn at(&self, sample: usize) -> usize {
        self.permutations.partition_point(|p| p.start <= sample).saturating_sub(1)
    }

    /// Samples `from..to` of the run: the span of permutations `first..last` (and the ring-out
    /// after the last permutation).
    fn span(&self, first: usize, last: usize) -> (usize, usize) {
        let end = self.permutations.get(last).map_or(self.samples, |p| p.start);
        (self.permutations[first].start, end)
    }
}

impl Generator {
    /// The next permutation's CLAP values: with probability 1/3 every parameter at the extreme
    /// opposite to where it was, else each at its minimum, its maximum or a random value.
    fn values(&mut self, params: &[(&str, Option<u32>)], previous: Option<&[f64]>) -> Vec<f64> {
        let mirror = previous.filter(|_| self.rng.random_bool(1.0 / 3.0));
        params
            .iter()
            .enumerate()
            .map(|(i, &(_, steps))| {
                let max = steps.map_or(1.0, f64::from);
                match (mirror, self.rng.random_range(0..3), steps) {
                    (Some(previous), ..) if previous[i] < 0.5 * max => max,
                    (Some(_), ..) | (None, 0, _) => 0.0,
                    (None, 1, _) => max,
                    (None, _, Some(steps)) => f64::from(self.rng.random_range(0..=steps)),
                    (None, _, None) => self.rng.random_range(0.0..=1.0),
                }
            })
            .collect()
    }

    /// Samples to the next gesture: often none (a chord of gestures) or a few, mostly up to
    /// 2,000 (about 50 gestures a second).
    fn gap(&mut self) -> usize {
        match self.rng.random_range(0..10) {
            0 => 0,
            1..=2 => self.rng.random_range(1..=50),
            _ => self.rng.random_range(50..=2_000),
        }
    }

    /// A channel: mostly the first, else any (MPE style), often one a held key is on.
    fn channel(&mut self) -> u8 {
        match self.rng.random_range(0..4) {
            0 | 1 => 0,
            2 if !self.held.is_empty() => self.held[self.rng.random_range(0..self.held.len())].0,
            _ => self.rng.random_range(0..16),
        }
    }

    /// A MIDI 7-bit controller value: an extreme or random.
    fn value7(&mut self) -> u8 {
        match self.rng.random_range(0..4) {
            0 => 0,
            1 => 127,
            _ => self.rng.random_range(0..=127),
        }
    }

    /// Press `key` on `channel` at `t`, as a CLAP note or a MIDI message; velocity often the
    /// loudest.
    fn press(&mut self, t: usize, channel: u8, key: u8, score: &mut Score) {
        if self.held.len() >= MAX_HELD {
            let (c, k) = self.held.remove(0);
            score.push((t, Ev::Off(c, k)));
        }
        let velocity = match self.rng.random_range(0..16) {
            0..=3 => 1.0,
            4 | 5 => 1.0 / 127.0,
            // A CLAP note-on at velocity 0 (a note-off); as MIDI, the softest note.
            6 => 0.0,
            _ => self.rng.random_range(0.01..=1.0),
        };
        let ev = if self.rng.random_bool(0.5) {
            Ev::On(channel, key, velocity)
        } else {
            Ev::Midi([0x90 | channel, key, ((velocity * 127.0).round() as u8).max(1)])
        };
        score.push((t, ev));
        self.held.retain(|&h| h != (channel, key));
        self.held.push((channel, key));
        self.recent.retain(|&h| h != (channel, key));
        self.recent.push((channel, key));
        if self.recent.len() > 8 {
            self.recent.remove(0);
        }
    }

    /// Release a held key: a CLAP note-off, a MIDI note-off or note-on at velocity 0, a CLAP
    /// choke, or a CLAP note-off for the key on every channel.
    fn release(&mut self, t: usize, index: usize, score: &mut Score) {
        let (channel, key) = self.held.remove(index);
        let ev = match self.rng.random_range(0..5) {
            0 => Ev::Off(channel, key),
            1 => Ev::Midi([0x80 | channel, key, self.rng.random_range(0..=127)]),
            2 => Ev::Midi([0x90 | channel, key, 0]),
            3 => Ev::Choke(Target::key(channel, key)),
            _ => {
                self.held.retain(|&(_, k)| k != key);
                Ev::OffAt(Target { note_id: None, channel: None, key: Some(key) })
            }
        };
        score.push((t, ev));
    }

    /// A key: mostly the piano's range, sometimes any MIDI key.
    fn key(&mut self) -> u8 {
        if self.rng.random_bool(0.9) { self.rng.random_range(21..=108) } else { self.rng.random_range(0..=127) }
    }

    /// One musical gesture at `t`; the number of notes it starts.
    fn gesture(&mut self, t: usize, score: &mut Score) -> usize {
        let channel = self.channel();
        match self.rng.random_range(0..100) {
            // A chord of 3 to 6 keys, at once or strummed over a few samples.
            30..=37 => {
                let (n, root, strum) = (self.rng.random_range(3..=6), self.key(), self.rng.random_range(0..=3));
                for i in 0..n {
                    let key = root.saturating_add([0, 4, 7, 12, 16, 19][i]).min(127);
                    self.press(t + i * strum, channel, key, score);
                }
                n
            }
            // The same key again (a held or recent one).
            38..=47 if !self.recent.is_empty() => {
                let (c, key) = self.recent[self.rng.random_range(0..self.recent.len())];
                self.press(t, c, key, score);
                1
            }
            // Release one held key.
            48..=67 if !self.held.is_empty() => {
                let index = self.rng.random_range(0..self.held.len());
                self.release(t, index, score);
                0
            }
            // A single note (also when there is no key to repeat or release).
            0..=67 => {
                let key = self.key();
                self.press(t, channel, key, score);
                1
            }
            // Release every held key, one by one or by a CLAP note-off or choke of every note.
            68..=71 => {
                let every = Target { note_id: None, channel: None, key: None };
                match self.rng.random_range(0..4) {
                    0 => score.push((t, Ev::OffAt(every))),
                    1 => score.push((t, Ev::Choke(every))),
                    _ => {
                        while !self.held.is_empty() {
                            self.release(t, 0, score);
                        }
                    }
                }
                self.held.clear();
                0
            }
            // Sustain pedal, or the sostenuto or soft pedal, or reset all controllers, or a
            // registered or non-registered parameter's selection or value (pitch-bend
            // sensitivity, MPE zones).
            72..=78 => {
                let value = [0, 127, self.value7()][self.rng.random_range(0..3)];
                let pedal = [64, 64, 66, 67, 121, 101, 100, 6, 99, 98][self.rng.random_range(0..10)];
                score.push((t, Ev::Midi([0xB0 | channel, pedal, value])));
                0
            }
            // Pitch bend: down, centre, up or anywhere.
            79..=85 => {
                let bend: u16 = [0, 8192, 16383, self.rng.random_range(0..16384)][self.rng.random_range(0..4)];
                score.push((t, Ev::Midi([0xE0 | channel, (bend & 127) as u8, (bend >> 7) as u8])));
                0
            }
            // Channel pressure.
            86..=90 => {
                let value = self.value7();
                score.push((t, Ev::Midi([0xD0 | channel, value, 0])));
                0
            }
            // Poly pressure on a held key (or any key).
            91..=95 => {
                let (c, key) = match self.held.len() {
                    0 => (channel, self.key()),
                    n => self.held[self.rng.random_range(0..n)],
                };
                let value = self.value7();
                score.push((t, Ev::Midi([0xA0 | c, key, value])));
                0
            }
            // Mod wheel or CC74.
            96..=98 => {
                let (cc, value) = ([1, 74][self.rng.random_range(0..2)], self.value7());
                score.push((t, Ev::Midi([0xB0 | channel, cc, value])));
                0
            }
            // All notes off.
            _ => {
                score.push((t, Ev::Midi([0xB0 | channel, 123, 0])));
                self.held.clear();
                0
            }
        }
    }
}

/// A host buffer size: 1, 4,096, a few samples, a power of two or anything in between.
fn block_size(rng: &mut Pcg64) -> usize {
    match rng.random_range(0..10) {
        0 => 1,
        1 => MAX_HOST_BUFFER,
        2 | 3 => rng.random_range(1..=16),
        4 | 5 => 1 << rng.random_range(5..=12),
        _ => rng.random_range(1..=MAX_HOST_BUFFER),
    }
}

/// The fuzz run's size and seed, from the environment or the defaults.
fn settings() -> (usize, u64) {
    let read = |name: &str| {
        std::env::var(name).ok().map(|v| v.trim().parse::<u64>().unwrap_or_else(|e| panic!("{name}={v:?}: {e}")))
    };
    let count = read(PERMUTATIONS_ENV).map_or(DEFAULT_PERMUTATIONS, |n| n as usize).max(1);
    (count, read(SEED_ENV).unwrap_or(DEFAULT_SEED))
}

/// The parameter values of permutation `index`, as CLAP values and the plugin's own text.
fn describe(plugin: &mut Plugin, run: &Run, index: usize) -> String {
    let p = &run.permutations[index];
    let mut text = format!("permutation {index} (from sample {}, interval {}):", p.start, p.interval);
    for (&(id, _), &value) in run.params.iter().zip(&p.values) {
        let shown = plugin.value_text(clap_id(id), value);
        let _ = write!(text, " {id}={value} ({shown})");
    }
    text
}

/// The failure report for a bad `value` at `sample` of the run (`what`: why it is bad).
fn failure(plugin: &mut Plugin, run: &Run, seed: u64, sample: usize, value: f32, what: &str) -> String {
    let index = run.at(sample);
    let p = &run.permutations[index];
    let window = sample.saturating_sub(4_800);
    let events: Vec<String> = run
        .score
        .iter()
        .filter(|e| (window..=sample).contains(&e.0) && !matches!(e.1, Ev::Param(..)))
        .map(|e| format!("{}: {:?}", e.0, e.1))
        .collect();
    let mut report = format!(
        "seed {seed}: sample {sample} is {value} ({what}); {} samples into permutation {index} of {}, at {} Hz.\n  \
         in force: {}",
        sample - p.start,
        run.permutations.len(),
        rate_at(index),
        describe(plugin, run, index)
    );
    if index > 0 {
        let _ = write!(report, "\n  before it: {}", describe(plugin, run, index - 1));
    }
    let _ = write!(
        report,
        "\n  note and MIDI events in the 4,800 samples before it (CLAP notes: channel, key, velocity): {events:?}\n  \
         replay: {SEED_ENV}={seed} {PERMUTATIONS_ENV}={} cargo test --release -p qsa-tests --test host_fuzz -- \
         --nocapture",
        index + 1
    );
    report
}

/// Every parameter but `Output gain` (held at its default, 0 dB) through thousands of random
/// permutations (each at its minimum, maximum or a random value, often jumping between opposite
/// extremes), in both modes and all three solvers, changed sample-accurately at intervals of 1,
/// 10, 100 and 1,000 samples inside host buffers of 1 to 4,096 samples, while notes, chords,
/// repeated keys, the sustain pedal, pitch bend, channel and poly pressure and the mod wheel
/// play: every output sample is finite and within ±10^(12/20) (+12 dBFS) for every note that
/// may sound then (the notes started in the last [`SOUNDING`] samples, but no more than have
/// started and not been reported ended [`END_MARGIN`] before: at most the voices; at least one).
///
/// Why +12 dBFS a note: the instrument is scaled so that a fortissimo note peaks near 0.5
/// (−6 dBFS, `OUTPUT_SCALE`, `SLIDE_SCALE`), and one voice at the most energetic corner settings
/// stays under +6 dBFS (measured over 4,096 single slide notes at corner settings: +4.8 dBFS);
/// what no setting may do is make the physics gain energy and run away, which shows as a sample
/// far beyond that (a pluck inheriting a pressed slide under a stiffer contact reached +110 dBFS).
/// +12 dBFS is four times full scale and eight times a fortissimo note. Why per note: voices add.
/// In slide mode with `Slide follows key` off every note sounds the same pitch, and their
/// plucks add coherently: 32 unison voices at the loudest settings reach +24.6 dBFS with every
/// voice within its own bound, which is physics, not a fault (a limiter is the output stage's
/// job, not the model's). The default run's loudest sample is −0.1 dBFS, and its largest for
/// each note that may sound −2.7 dBFS (one voice). NaN or infinity anywhere is a failure
/// outright.
#[test]
fn random_parameter_permutations_never_give_a_non_finite_or_loud_sample() {
    let (count, seed) = settings();
    let ceiling = 10f64.powf(CEILING_DB / 20.0) as f32;
    let start = Instant::now();
    let run = Run::new(seed, count);
    println!(
        "seed {seed}: {count} permutations of {} parameters, {} events, {} samples of audio ({:.1} s at {FS} Hz; \
         re-activated every {REACTIVATE_EVERY} permutations at {RATES:?} Hz in turn)",
        run.params.len(),
        run.score.len(),
        run.samples,
        run.samples as f64 / FS
    );
    // When notes start: CLAP and MIDI note-ons with a non-zero velocity.
    let onsets: Vec<usize> = run
        .score
        .iter()
        .filter(|(_, ev)| match ev {
            Ev::On(_, _, velocity) => *velocity > 0.0,
            Ev::Midi([status, _, velocity]) => status & 0xf0 == 0x90 && *velocity > 0,
            _ => false,
        })
        .map(|&(t, _)| t)
        .collect();
    // Where the plugin reported notes ended (samples from the run's start), in order.
    let mut ends: Vec<usize> = Vec::new();
    // The notes that may sound at `t`: started in the last `SOUNDING` samples, and no more than
    // have started and not been reported ended `END_MARGIN` samples before (at least one).
    let sounding = |t: usize, ends: &[usize]| {
        let started = onsets.partition_point(|&s| s <= t);
        let recent = started - onsets.partition_point(|&s| s + SOUNDING <= t);
        let live = started.saturating_sub(ends.partition_point(|&e| e + END_MARGIN <= t));
        recent.min(live).max(1)
    };
    let bundle = release_bundle();
    let mut plugin = Plugin::new(&bundle, FS, MAX_HOST_BUFFER, &[]);
    // Each permutation's peak and the sample it is at.
    let mut peaks = vec![(0.0f32, 0usize); count];
    // The largest sample over the notes that may sound, where, and how many.
    let mut worst_per_note = (0.0f32, 0usize, 1usize);
    let mut blocks: Vec<usize> = Vec::new();
    let mut inside = [0usize; INTERVALS.len()];
    let mut next_event = 0;
    for first in (0..count).step_by(PERMUTATIONS_PER_CALL) {
        if first > 0 && first % REACTIVATE_EVERY == 0 {
            plugin.reactivate_at(rate_at(first));
        }
        let (from, to) = run.span(first, first + PERMUTATIONS_PER_CALL);
        let end = run.score[next_event..].partition_point(|e| e.0 < to) + next_event;
        let chunk: Score = run.score[next_event..end].iter().map(|&(t, ev)| (t - from, ev)).collect();
        next_event = end;
        // Buffer sizes from a stream of their own for each chunk, so a shorter replay cuts the
        // same buffers.
        let mut rng = seeded_rng(seed ^ (first as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15));
        let first_block = blocks.len();
        let sizes = &mut blocks;
        let audio = plugin.render(&chunk, to - from, move || {
            let n = block_size(&mut rng);
            sizes.push(n);
            n
        });
        ends.extend(audio.note_ends.iter().map(|end| end.0 + from));
        ends.sort_unstable();
        // Where the buffers began, to count the permutations that changed inside one.
        let mut boundaries = Vec::with_capacity(blocks.len() - first_block);
        let mut t = from;
        for n in &mut blocks[first_block..] {
            boundaries.push(t);
            *n = (*n).min(to - t);
            t += *n;
        }
        for p in &run.permutations[first..(first + PERMUTATIONS_PER_CALL).min(count)] {
            let b = boundaries[boundaries.partition_point(|&s| s <= p.start) - 1];
            if p.start > b {
                inside[INTERVALS.iter().position(|&i| i == p.interval).expect("an interval")] += 1;
            }
        }
        // Every sample, permutation by permutation.
        for index in first..(first + PERMUTATIONS_PER_CALL).min(count) {
            let (a, b) = run.span(index, index + 1);
            for (channel, samples) in
                [("left", &audio.left[a - from..b - from]), ("right", &audio.right[a - from..b - from])]
            {
                for (i, &x) in samples.iter().enumerate() {
                    let notes = sounding(a + i, &ends);
                    if !x.is_finite() || x.abs() > ceiling * notes as f32 {
                        let what = if x.is_finite() {
                            format!(
                                "{channel} channel, beyond {notes} × ±{ceiling:.3} (+{CEILING_DB} dBFS for each of the \
                                 {notes} notes that may sound)"
                            )
                        } else {
                            format!("{channel} channel, not finite")
                        };
                        panic!("{}", failure(&mut plugin, &run, seed, a + i, x, &what));
                    }
                    if x.abs() > peaks[index].0 {
                        peaks[index] = (x.abs(), a + i);
                    }
                    let per_note = x.abs() / notes as f32;
                    if per_note > worst_per_note.0 {
                        worst_per_note = (per_note, a + i, notes);
                    }
                }
            }
        }
    }
    let elapsed = start.elapsed().as_secs_f64();
    let db = |x: f32| 20.0 * f64::from(x).log10();
    println!("rendered in {elapsed:.1} s ({:.0} samples a second)", run.samples as f64 / elapsed);
    let mut loudest: Vec<usize> = (0..count).collect();
    loudest.sort_by(|&a, &b| peaks[b].0.total_cmp(&peaks[a].0));
    for &index in loudest.iter().take(3) {
        let (peak, at) = peaks[index];
        println!("peak {peak:.4} ({:+.1} dBFS) at sample {at}, {}", db(peak), describe(&mut plugin, &run, index));
    }
    let above = |x: f32| peaks.iter().filter(|p| p.0 > x).count();
    println!(
        "permutations peaking above -6 dBFS: {}, above 0 dBFS: {}, above +6 dBFS: {}",
        above(0.5),
        above(1.0),
        above(2.0)
    );
    let (per_note, at, notes) = worst_per_note;
    println!(
        "largest sample per sounding note: {per_note:.4} ({:+.1} dBFS) at sample {at}, {notes} notes",
        db(per_note)
    );
    println!("note-ons by mode (Piano, Slide) and solver (QSA, EXP, IMP): {:?}", run.notes_by_setting);
    println!(
        "host buffers: {} of 1..={} samples (1: {}, {MAX_HOST_BUFFER}: {}); permutations changing inside a buffer at \
         intervals {INTERVALS:?}: {inside:?}",
        blocks.len(),
        blocks.iter().max().copied().unwrap_or(0),
        blocks.iter().filter(|&&n| n == 1).count(),
        blocks.iter().filter(|&&n| n == MAX_HOST_BUFFER).count(),
    );
    // The run covered what it claims to (a short replay need not).
    if count >= DEFAULT_PERMUTATIONS {
        let fewest = run.notes_by_setting.iter().flatten().min().copied().unwrap_or(0);
        assert!(fewest >= 10, "a mode and solver pairing started only {fewest} notes: {:?}", run.notes_by_setting);
        assert!(inside.iter().all(|&n| n > 0), "a permutation interval never landed inside a buffer: {inside:?}");
        assert!(blocks.contains(&1) && blocks.contains(&MAX_HOST_BUFFER), "buffers of 1 and {MAX_HOST_BUFFER} samples");
    }
}
