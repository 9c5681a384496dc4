//! `cargo xtask render --midi FILE.mid`: a MIDI file through the instrument engine, exactly as
//! the plugin plays it.
//!
//! The tracks of a format 0 or 1 file play together, merged into one timeline; those of a
//! format 2 file (independent patterns) play one after another, each from where the one before
//! it ended. Times follow the file's tempo map (metrical files) or its SMPTE rate, and land on the
//! nearest sample. Channel messages become engine events with
//! [`event_from_midi`], the conversion a host and the plugin apply, and the parameters come from
//! [`ParamValues`] (the defaults, or a factory preset's with `--preset`) with `--mode` and
//! `--set ID=VALUE` applied, so the samples equal those of the plugin given
//! the same parameters and events at the same samples. The render runs until the file's last
//! event of any kind (its end of track included, which a sequencer puts at the end of the last
//! bar) plus `--tail` seconds, and always includes that event's sample.

use midly::{Format, MetaMessage, MidiMessage, Smf, Timing, TrackEventKind};
use qsa_dsp::instrument::{Event, Instrument, ParamValues, event_from_midi, factory_presets, find_preset};

/// A MIDI file turned into engine events at sample offsets.
#[derive(Debug, Clone, PartialEq)]
pub struct Score {
    /// `(sample, event)`, in time order (file order within a sample).
    pub events: Vec<(u64, Event)>,
    /// Notes the file plays.
    pub notes: usize,
    /// Sample of the file's last event of any kind: a controller the engine ignores, or the end
    /// of a track (at or after the last of [`Self::events`]).
    pub end: u64,
}

impl Score {
    /// Samples a render of the score with `tail` seconds (at `sample_rate`, Hz) after its end
    /// lasts: through the end's sample at least, so that an event there acts.
    pub fn samples(&self, tail: f64, sample_rate: f64) -> u64 {
        let tail = (tail.max(0.0) * sample_rate).round() as u64;
        self.end.saturating_add(tail).max(self.end.saturating_add(1))
    }
}

/// Largest MIDI file read (bytes): far beyond any performance (a 600 s render of a
/// thousand events a second takes about 2 MB), and small enough that the parsed events and the
/// timeline made from them (about 100 bytes an event) stay within a few hundred MB: the most any
/// input may have ([`super::MAX_INPUT_BYTES`]).
pub const MAX_FILE_BYTES: usize = super::MAX_INPUT_BYTES;

/// Most samples a MIDI render may ask for: the render holds about 16 bytes a sample (both
/// channels, and the WAV made from them), so this bounds its memory near 1 GB.
pub const MAX_SAMPLES: usize = 60_000_000;

/// Why a MIDI file cannot be rendered.
#[derive(Debug, thiserror::Error)]
pub enum MidiError {
    /// Not a standard MIDI file.
    #[error("not a MIDI file: {0}")]
    Parse(String),
}

/// A channel message at its sample: `(sample, [status, data1, data2])`.
pub type TimedMessage = (u64, [u8; 3]);

/// The channel messages of `bytes` (a standard MIDI file) with their sample offsets at
/// `sample_rate` (Hz): `(sample, [status, data1, data2])`, in time order (file order within a tick).
pub fn timed_messages(bytes: &[u8], sample_rate: f64) -> Result<Vec<TimedMessage>, MidiError> {
    timed_file(bytes, sample_rate).map(|(messages, _)| messages)
}

/// [`timed_messages`], and the sample of the file's last event of any kind.
fn timed_file(bytes: &[u8], sample_rate: f64) -> Result<(Vec<TimedMessage>, u64), MidiError> {
    if bytes.len() > MAX_FILE_BYTES {
        return Err(MidiError::Parse(format!("{} bytes; at most {MAX_FILE_BYTES} (16 MiB)", bytes.len())));
    }
    // Parsed strictly (midly's `strict`): a corrupt or cut file is refused, not played in part.
    let smf = Smf::parse(bytes).map_err(|e| MidiError::Parse(e.to_string()))?;
    match smf.header.timing {
        Timing::Metrical(tpb) if tpb.as_int() == 0 => {
            return Err(MidiError::Parse("the header gives 0 ticks per quarter note".into()));
        }
        Timing::Timecode(_, 0) => return Err(MidiError::Parse("the header gives 0 ticks per frame".into())),
        _ => {}
    }
    let sequential = smf.header.format == Format::Sequential;
    // (tick, track, index in track, kind)
    let mut timeline = Vec::new();
    let mut start: u64 = 0;
    for (track, events) in smf.tracks.iter().enumerate() {
        let mut tick = if sequential { start } else { 0 };
        for (index, e) in events.iter().enumerate() {
            tick += u64::from(e.delta.as_int());
            timeline.push((tick, track, index, e.kind));
        }
        start = tick;
    }
    timeline.sort_by_key(|&(tick, track, index, _)| (tick, track, index));
    let seconds_per_tick_at = |tempo_us: f64| match smf.header.timing {
        Timing::Metrical(tpb) => tempo_us * 1e-6 / f64::from(tpb.as_int().max(1)),
        Timing::Timecode(fps, sub) => 1.0 / (f64::from(fps.as_f32()) * f64::from(sub)),
    };
    let mut tempo = 500_000.0;
    let (mut last_tick, mut seconds) = (0u64, 0.0f64);
    let mut out = Vec::new();
    let at = |seconds: f64| (seconds * sample_rate).round() as u64;
    for (tick, _, _, kind) in timeline {
        seconds += (tick - last_tick) as f64 * seconds_per_tick_at(tempo);
        last_tick = tick;
        match kind {
            TrackEventKind::Meta(MetaMessage::Tempo(t)) if t.as_int() == 0 => {
                return Err(MidiError::Parse(format!("a tempo of 0 µs per quarter note at tick {tick}")));
            }
            TrackEventKind::Meta(MetaMessage::Tempo(t)) => tempo = f64::from(t.as_int()),
            // A tempo event holds three bytes; shorter, it is corrupt (midly leaves it unknown).
            TrackEventKind::Meta(MetaMessage::Unknown(0x51, data)) => {
                return Err(MidiError::Parse(format!(
                    "a tempo event of {} bytes at tick {tick}; a tempo takes 3",
                    data.len()
                )));
            }
            TrackEventKind::Midi { channel, message } => {
                let (status, d1, d2) = match message {
                    MidiMessage::NoteOff { key, vel } => (0x80, key.as_int(), vel.as_int()),
                    MidiMessage::NoteOn { key, vel } => (0x90, key.as_int(), vel.as_int()),
                    MidiMessage::Aftertouch { key, vel } => (0xa0, key.as_int(), vel.as_int()),
                    MidiMessage::Controller { controller, value } => (0xb0, controller.as_int(), value.as_int()),
                    MidiMessage::ChannelAftertouch { vel } => (0xd0, vel.as_int(), 0),
                    MidiMessage::PitchBend { bend } => {
                        let raw = bend.0.as_int();
                        (0xe0, (raw & 0x7f) as u8, (raw >> 7) as u8)
                    }
                    MidiMessage::ProgramChange { .. } => continue,
                };
                out.push((at(seconds), [status | channel.as_int(), d1, d2]));
            }
            _ => {}
        }
    }
    Ok((out, at(seconds)))
}

/// Read `bytes` (a standard MIDI file) into engine events at `sample_rate` (Hz).
pub fn score(bytes: &[u8], sample_rate: f64) -> Result<Score, MidiError> {
    let mut notes = 0;
    let (messages, end) = timed_file(bytes, sample_rate)?;
    let events = messages
        .into_iter()
        .filter_map(|(sample, [status, d1, d2])| {
            let event = event_from_midi(status, d1, d2)?;
            notes += usize::from(matches!(event, Event::NoteOn { .. }));
            Some((sample, event))
        })
        .collect();
    Ok(Score { events, notes, end })
}

/// Render `score` with `params` at `sample_rate` (Hz) for [`Score::samples`] with `tail` seconds,
/// in calls of `chunk` samples (split at every event). Returns left and right channels and the
/// wall-clock seconds spent in the engine.
pub fn render(
    score: &Score,
    params: &ParamValues,
    sample_rate: f64,
    tail: f64,
    chunk: usize,
) -> (Vec<f32>, Vec<f32>, f64) {
    let samples = score.samples(tail, sample_rate) as usize;
    render_signals(score, params, sample_rate, (samples, &mut || chunk), false)
}

/// The first `samples` of `score` rendered as [`render`] does, in calls of the sizes `chunks`
/// gives (split at every event), with `raw` the dry signals ([`Instrument::set_raw_output`]).
pub fn render_signals(
    score: &Score,
    params: &ParamValues,
    sample_rate: f64,
    (samples, chunks): (usize, &mut dyn FnMut() -> usize),
    raw: bool,
) -> (Vec<f32>, Vec<f32>, f64) {
    let mut engine = Instrument::new(sample_rate, params.voices.clamp(1, 128) as usize, params.settings());
    engine.set_raw_output(raw);
    let (mut left, mut right) = (vec![0.0f32; samples], vec![0.0f32; samples]);
    let start = std::time::Instant::now();
    let mut next = 0;
    let mut t = 0usize;
    while t < samples {
        while next < score.events.len() && score.events[next].0 as usize <= t {
            engine.handle(score.events[next].1);
            next += 1;
        }
        let until_event = score.events.get(next).map_or(samples, |e| (e.0 as usize).min(samples));
        let n = chunks().max(1).min(until_event - t).min(samples - t).max(1);
        engine.process(&mut left[t..t + n], &mut right[t..t + n]);
        t += n;
    }
    (left, right, start.elapsed().as_secs_f64())
}

/// The summary line of a MIDI render: the keys of a scene render's summary, `null` where a MIDI
/// render does not measure them.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct MidiSummary {
    /// Always `"midi"`.
    pub scene: &'static str,
    /// Solver.
    pub method: &'static str,
    /// QSA segments.
    pub segments: usize,
    /// Sample rate (Hz).
    pub sample_rate: u32,
    /// Samples rendered.
    pub samples: usize,
    /// Not measured.
    pub contact_samples: Option<usize>,
    /// Notes played.
    pub contacts: usize,
    /// Not measured.
    pub contact_duration: Option<f64>,
    /// Not measured.
    pub peak_force: Option<f64>,
    /// Not measured.
    pub max_compression: Option<f64>,
    /// Not measured.
    pub rebound_velocity: Option<f64>,
    /// Not measured.
    pub energy_drift_rel: Option<f64>,
    /// Not measured.
    pub max_work: Option<u32>,
    /// Not measured.
    pub mean_contact_work: Option<f64>,
    /// Largest output sample magnitude (full scale 1).
    pub peak: f64,
    /// Wall-clock time of the engine (s).
    pub wall_seconds: f64,
    /// Wall seconds per simulated second.
    pub rtf: f64,
}

/// The values of the factory preset `name` (its id or display name), or an error listing the
/// presets there are.
pub fn preset_values(name: &str) -> Result<ParamValues, String> {
    find_preset(name).map(|p| p.values).ok_or_else(|| {
        let ids: Vec<&str> = factory_presets().iter().map(|p| p.id.as_str()).collect();
        format!("--preset {name}: no such preset; the factory presets are: {}", ids.join(", "))
    })
}

/// Apply one `--set ID=VALUE` to `params` ([`ParamValues::set`]: any id of the parameter table,
/// in the unit the plugin shows), or say why not.
pub fn apply_set(params: &mut ParamValues, assignment: &str) -> Result<(), String> {
    let (id, value) = assignment.split_once('=').ok_or_else(|| format!("--set {assignment}: expected ID=VALUE"))?;
    params.set(id.trim(), value.trim()).map_err(|e| format!("--set {assignment}: {e}"))
}

/// `render --midi`: read, render, write the WAV; return the summary.
pub fn run(args: &super::RenderArgs, path: &std::path::Path) -> Result<MidiSummary, super::RenderError> {
    use super::RenderError;
    // A file far beyond any performance is refused without being read into memory.
    let bytes = super::read_input(path)?;
    let mut params = match &args.preset {
        None => ParamValues::default(),
        Some(name) => preset_values(name).map_err(RenderError::Midi)?,
    };
    if let Some(mode) = &args.mode {
        params.set("mode", mode).map_err(|e| RenderError::Midi(e.to_string()))?;
    }
    for assignment in &args.set {
        apply_set(&mut params, assignment).map_err(RenderError::Midi)?;
    }
    let (rate, tail) = (args.rate.unwrap_or(super::MIDI_RATE), args.tail.unwrap_or(super::MIDI_TAIL));
    if !(1000..=768_000).contains(&rate) {
        return Err(RenderError::Midi(format!("--rate {rate}: must be 1000 to 768000 Hz")));
    }
    if !(tail.is_finite() && (0.0..=600.0).contains(&tail)) {
        return Err(RenderError::Midi(format!("--tail {tail}: must be 0 to 600 s")));
    }
    let fs = f64::from(rate);
    let score = score(&bytes, fs).map_err(|e| RenderError::Midi(format!("{}: {e}", path.display())))?;
    let seconds = score.end as f64 / fs + tail;
    if seconds > 600.0 {
        return Err(RenderError::Midi(format!("{}: lasts {seconds:.0} s; at most 600 s", path.display())));
    }
    if seconds * fs > MAX_SAMPLES as f64 {
        return Err(RenderError::Midi(format!(
            "{}: {seconds:.0} s at {} Hz is {:.2e} samples; at most {MAX_SAMPLES:.0e} (600 s at 96 kHz)",
            path.display(),
            rate,
            seconds * fs
        )));
    }
    let wav_path = args.out.clone().unwrap_or_else(|| path.with_extension("wav"));
    super::check_output_path(&wav_path, path)?;
    // In calls of 512 samples unless `--chunk` says otherwise (0: seeded random sizes).
    let mut sizes = super::chunk_sizes(Some(args.chunk.unwrap_or(512)));
    let samples = score.samples(tail, fs) as usize;
    let (left, right, wall) =
        render_signals(&score, &params, fs, (samples, &mut || sizes.next().unwrap_or(usize::MAX)), args.raw);
    let spec = hound::WavSpec {
        channels: 2,
        sample_rate: rate,
        bits_per_sample: 32,
        sample_format: hound::SampleFormat::Float,
    };
    let wav = super::write_temp(&wav_path, |w| {
        let mut buffer = std::io::Cursor::new(Vec::with_capacity(44 + 8 * left.len()));
        {
            let mut writer = hound::WavWriter::new(&mut buffer, spec).map_err(std::io::Error::other)?;
            for (l, r) in left.iter().zip(&right) {
                writer.write_sample(*l).map_err(std::io::Error::other)?;
                writer.write_sample(*r).map_err(std::io::Error::other)?;
            }
            writer.finalize().map_err(std::io::Error::other)?;
        }
        std::io::Write::write_all(w, buffer.get_ref())
    })?;
    wav.persist()?;
    let settings = params.settings().sanitized();
    let samples = left.len();
    Ok(MidiSummary {
        scene: "midi",
        method: settings.method.name(),
        segments: settings.segments,
        sample_rate: rate,
        samples,
        contact_samples: None,
        contacts: score.notes,
        contact_duration: None,
        peak_force: None,
        max_compression: None,
        rebound_velocity: None,
        energy_drift_rel: None,
        max_work: None,
        mean_contact_work: None,
        peak: left.iter().chain(&right).fold(0.0f32, |m, v| m.max(v.abs())).into(),
        wall_seconds: wall,
        rtf: wall / (samples as f64 / fs),
    })
}

#[cfg(test)]
mod tests {
    use qsa_dsp::instrument::{PARAMETERS, ParamKind};

    use super::*;

    /// `--set` takes every parameter of the table, at either end of its range (choices: every
    /// option), and stores what the plugin would hold.
    #[test]
    fn set_accepts_every_parameter() {
        for spec in &PARAMETERS {
            let values: Vec<(String, f32)> = match spec.kind {
                ParamKind::Float { min, max, .. } => vec![(min.to_string(), min), (max.to_string(), max)],
                ParamKind::Int { min, max, .. } => vec![(min.to_string(), min as f32), (max.to_string(), max as f32)],
                ParamKind::Bool { .. } => vec![("off".into(), 0.0), ("on".into(), 1.0)],
                ParamKind::Choice { options, .. } => {
                    options.iter().enumerate().map(|(i, (id, _))| ((*id).to_owned(), i as f32)).collect()
                }
            };
            for (text, shown) in values {
                let mut params = ParamValues::default();
                apply_set(&mut params, &format!("{}={text}", spec.id)).unwrap_or_else(|e| panic!("{e}"));
                assert_eq!(params.plain(spec.id), Some(spec.to_plain(shown)), "--set {}={text}", spec.id);
            }
        }
        let mut params = ParamValues::default();
        assert!(apply_set(&mut params, "hard").unwrap_err().contains("expected ID=VALUE"));
        assert!(apply_set(&mut params, "kapa=1").unwrap_err().contains("unknown parameter id"));
    }
}
