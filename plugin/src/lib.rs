//! QSA Strings as a CLAP and VST3 instrument (nice-plug).
//!
//! This file holds the `Plugin` implementation only: the parameters are in [`params`], all sound
//! comes from the engine in `qsa_dsp::instrument`, the same code the offline renderer runs.
//!
//! - `activate` (the only place that allocates) builds the engine for the sample rate with the
//!   `Voices` parameter's pool size.
//! - `process` splits the host buffer at every event's sample, hands the event to the engine and
//!   renders up to the next one. Parameter changes arrive split sample-accurately by the
//!   framework; the engine samples them at its control-block boundaries, so host buffer sizes never
//!   change the output.
//! - Notes end by note-off, or at once by a CLAP note choke (a faded stop whatever the pedals);
//!   CLAP note-offs and chokes may address every note of a key, a channel or all of them.
//! - MIDI: notes; CC64 sustain (continuous: half-pedalling), CC66 sostenuto, CC67 soft pedal
//!   (una corda), CC1 mod wheel, CC74 (MPE's third dimension), CC120 all sound off, CC121 reset
//!   all controllers, CC123 all notes off; pitch bend moves the slide, as far as the channel's
//!   pitch-bend sensitivity (RPN 0) or MPE zone (RPN 6) says; the mod wheel, channel and poly
//!   pressure and CC74 can press it (per channel, so MPE works); in piano mode CC74 voices the
//!   felt of the hammers struck on its channel.
//! - `reset` (each activation and start of processing) returns the engine to how it was made
//!   ([`Instrument::reset`]): what follows is a new instance's output, to the bit, but for the
//!   controller's configuration (pitch-bend sensitivities and MPE zones), which stays, through a
//!   change of sample rate or voice count too.
//! - Per note: in slide mode CLAP and VST3 tuning expressions move the note's slide, CLAP
//!   pressure expressions (nice-plug delivers them, like MIDI poly aftertouch and VST3 poly
//!   pressure, as `PolyPressure`) are its poly pressure, CLAP and VST3 brightness expressions are
//!   its own CC74, and CLAP polyphonic modulation offsets its `slide` and `hand` ([`params`]); in
//!   piano mode a brightness expression sent with the note-on voices its hammer's felt. Notes are
//!   addressed by the host's voice id, else channel and key. Every note's end goes back to the
//!   host as `VoiceTerminated` (CLAP note-end), which CLAP polyphonic modulation needs to free
//!   its per-voice modulators.
//!
//! - When the audio thread cannot keep up in real-time processing, the least audible voices fade
//!   out ([`overload`]) rather than the host dropping buffers.
//! - The editor ([`editor`]) shows the parameters and the loudest voice. `process` times itself
//!   and, every 1/30 s of audio while the editor is open, hands the engine's monitor snapshot to
//!   it through the lock-free [`meter`] path (no allocation, lock or I/O on the audio thread).
//!
//! State (parameters) is saved by the framework with the plugin's version, which `filter_state`
//! sees first: it reads every value as its parameter's type and brings it into the range, gives
//! a value it cannot read (a corrupt one, a choice this version does not have) and a parameter
//! the state leaves out the default (the player's settings stay), and it is where later releases
//! migrate old state. A value of the wrong JSON type (an `i32` of
//! 64.5, say) fails the framework's parse before that: such a state does not load at all, and
//! the instance keeps what it had.

pub mod editor;
pub mod meter;
pub mod overload;
pub mod params;

use std::num::NonZeroU32;
use std::sync::Arc;
use std::time::Instant;

use nice_plug::midi::{Channel, Key, VoiceID};
use nice_plug::plugin::ParamValue;
use nice_plug::prelude::*;
use nice_plug_egui::{EguiEditor, EguiEditorState};
use qsa_dsp::instrument::{Event, Instrument, Note, NoteTarget, ParamKind, ParamSpec, bend_from_normalised};

use meter::{Shared, Tap};
use overload::OverloadGuard;
use params::{PRESET_FIELD, QsaParams};

/// The plugin. (No `Debug`: the framework's parameter types do not implement it.)
#[allow(missing_debug_implementations)]
pub struct QsaStrings {
    params: Arc<QsaParams>,
    /// The engine, built in `activate`.
    engine: Option<Instrument>,
    /// The editor's size and open state.
    editor_state: Arc<EguiEditorState>,
    /// The audio side of the data path to the editor (load, monitor snapshots).
    tap: Tap,
    /// Sheds voices when the audio thread cannot keep up ([`overload`]).
    guard: OverloadGuard,
    /// Whether the host waits for each buffer (the guard acts only then; [`keeps_time`]).
    realtime: bool,
    /// Events stamped at the end of the latest call, which take the next call's first sample
    /// (the same engine sample); at most [`DEFERRED_EVENTS`], allocated here.
    deferred: Vec<Event>,
    /// The voice count the plugin last asked the host to restart it for, if any.
    restart_asked: Option<usize>,
}

/// How many events stamped at a call's end wait for the next call; the one beyond them is
/// played at once after them, in order, and the next ones wait again.
const DEFERRED_EVENTS: usize = 256;

impl Default for QsaStrings {
    fn default() -> Self {
        Self {
            params: Arc::new(QsaParams::default()),
            engine: None,
            editor_state: editor::default_state(),
            tap: Tap::new(Arc::new(Shared::default())),
            guard: OverloadGuard::default(),
            realtime: false,
            deferred: Vec::with_capacity(DEFERRED_EVENTS),
            restart_asked: None,
        }
    }
}

/// The notes a host's per-note event addresses: its voice id (a negative one is none) and its
/// channel and key, each a wildcard when absent.
fn target(voice_id: VoiceID, channel: Channel, key: Key) -> NoteTarget {
    NoteTarget { voice: voice_id.id().filter(|&v| v >= 0), channel: channel.number(), key: key.number() }
}

/// The engine event for a host note event from plugin API `api`, if it is one the engine plays.
fn engine_event<S>(event: &NoteEvent<S>, api: PluginApi) -> Option<Event> {
    let note = |channel: &Channel, key: &Key| Some((channel.number().unwrap_or(0), key.number()?));
    Some(match *event {
        NoteEvent::NoteOn { voice_id: VoiceID::ID(voice), channel, key, velocity, .. } if voice >= 0 => {
            let (channel, key) = note(&channel, &key)?;
            Event::NoteOnWithId { channel, key, velocity, voice }
        }
        NoteEvent::NoteOn { channel, key, velocity, .. } => {
            let (channel, key) = note(&channel, &key)?;
            Event::NoteOn { channel, key, velocity }
        }
        NoteEvent::NoteOff { voice_id, channel: Channel::Number(channel), key: Key::Number(key), .. }
            if voice_id.id().is_none_or(|v| v < 0) =>
        {
            Event::NoteOff { channel, key }
        }
        // CLAP note-offs and chokes may leave the channel or key open (all of them) or name a
        // note by its id, alone or with its channel and key: a note-off by id lets go of that
        // note, not of a later one on the same key that the host let overlap it.
        NoteEvent::NoteOff { voice_id, channel, key, .. } => Event::Release { note: target(voice_id, channel, key) },
        NoteEvent::Choke { voice_id, channel, key, .. } => Event::Choke { note: target(voice_id, channel, key) },
        // MIDI poly aftertouch (and VST3 poly pressure without a note id): as the offline renderer.
        NoteEvent::PolyPressure {
            voice_id: VoiceID::Wildcard,
            channel: Channel::Number(channel),
            key: Key::Number(key),
            pressure,
            ..
        } => Event::PolyPressure { channel, key, value: pressure },
        // CLAP pressure expressions and VST3 poly pressure with a note id.
        NoteEvent::PolyPressure { voice_id, channel, key, pressure, .. } => {
            Event::NotePressure { note: target(voice_id, channel, key), value: pressure }
        }
        NoteEvent::PolyTuning { voice_id, channel, key, tuning, .. } => {
            Event::NoteTuning { note: target(voice_id, channel, key), semitones: tuning }
        }
        NoteEvent::PolyModulation { voice_id, poly_modulation_id, normalized_offset, .. } => {
            let (param, offset) = params::poly_offset(poly_modulation_id, normalized_offset)?;
            Event::NoteModulation { note: NoteTarget::voice(voice_id), param, offset }
        }
        // A note's brightness: CLAP's arrives as `PolyBrightness`, but nice-plug 0.4.2 reads a
        // VST3 note's brightness (kBrightnessTypeID) as `PolyExpression` and its expression
        // (kExpressionTypeID) as `PolyBrightness`.
        NoteEvent::PolyBrightness { voice_id, channel, key, brightness: value, .. } if api == PluginApi::Clap => {
            Event::NoteBrightness { note: target(voice_id, channel, key), value }
        }
        NoteEvent::PolyExpression { voice_id, channel, key, expression: value, .. } if api == PluginApi::Vst3 => {
            Event::NoteBrightness { note: target(voice_id, channel, key), value }
        }
        NoteEvent::MidiChannelPressure { channel, pressure, .. } => Event::ChannelPressure { channel, value: pressure },
        NoteEvent::MidiPitchBend { channel, value, .. } => {
            Event::PitchBend { channel, value: bend_from_normalised(value) }
        }
        NoteEvent::MidiCC { channel, cc, value, .. } => match cc {
            1 => Event::ModWheel { channel, value },
            74 => Event::Timbre { channel, value },
            6 | 38 | 98..=101 => Event::RegisteredParameter {
                channel,
                controller: cc,
                value: (value * 127.0).round().clamp(0.0, 127.0) as u8,
            },
            64 => Event::Sustain { channel, depth: value },
            66 => Event::Sostenuto { channel, down: value >= 0.5 },
            67 => Event::SoftPedal { channel, down: value >= 0.5 },
            120 => Event::AllSoundOff,
            121 => Event::ResetControllers { channel },
            123 => Event::AllNotesOff,
            _ => return None,
        },
        _ => return None,
    })
}

/// Tell the host about the notes whose voices have ended (CLAP note-end events; VST3 has none),
/// at their samples relative to the buffer that began at engine sample `origin`.
fn report_ended<P: Plugin>(engine: &mut Instrument, context: &mut impl ProcessContext<P>, origin: u64) {
    for ended in engine.drain_ended() {
        let Note { voice, channel, key } = ended.note;
        let timing = u32::try_from(ended.at.saturating_sub(origin)).unwrap_or(u32::MAX);
        let voice_id = voice.map_or(VoiceID::Wildcard, VoiceID::ID);
        // A full host queue drops the notice; the host then ends the voice itself.
        let _ = context.try_send_event(NoteEvent::VoiceTerminated {
            timing,
            voice_id,
            channel: Channel::Number(channel),
            key: Key::Number(key),
        });
    }
}

/// `saved`, a state's value for the parameter `spec`, as the framework reads that parameter's
/// type, in its range; `None` if it cannot be read as one ([`QsaStrings::filter_state`]).
fn state_value(spec: &ParamSpec, saved: &ParamValue) -> Option<ParamValue> {
    let number = match saved {
        ParamValue::F32(v) => Some(*v),
        ParamValue::I32(v) => Some(*v as f32),
        ParamValue::Bool(on) => Some(if *on { 1.0 } else { 0.0 }),
        ParamValue::String(_) => None,
    }
    .filter(|v| v.is_finite());
    let whole = |v: f32| ParamValue::I32(spec.clamp_plain(v.round()) as i32);
    match spec.kind {
        ParamKind::Float { .. } => number.map(|v| ParamValue::F32(spec.clamp_plain(v))),
        ParamKind::Int { .. } => number.map(whole),
        ParamKind::Bool { .. } => number.map(|v| ParamValue::Bool(v != 0.0)),
        ParamKind::Choice { options, .. } => match saved {
            ParamValue::String(id) => options.iter().any(|(known, _)| known == id).then(|| saved.clone()),
            _ => number.map(whole),
        },
    }
}

/// The parameter `spec`'s default as the framework stores its type.
fn default_value(spec: &ParamSpec) -> ParamValue {
    let default = spec.default_plain();
    match spec.kind {
        ParamKind::Float { .. } => ParamValue::F32(default),
        ParamKind::Bool { .. } => ParamValue::Bool(default != 0.0),
        ParamKind::Int { .. } | ParamKind::Choice { .. } => ParamValue::I32(default as i32),
    }
}

impl Plugin for QsaStrings {
    const NAME: &'static str = "QSA Strings";
    const VENDOR: &'static str = "QSA Strings";
    const URL: &'static str = "https://example.invalid/qsa-strings";
    const EMAIL: &'static str = "qsa-strings@example.invalid";
    const VERSION: &'static str = env!("CARGO_PKG_VERSION");

    const AUDIO_IO_LAYOUTS: &'static [AudioIOLayout] = &[AudioIOLayout {
        main_input_channels: None,
        main_output_channels: NonZeroU32::new(2),
        ..AudioIOLayout::const_default()
    }];

    const MIDI_INPUT: MidiConfig = MidiConfig::MidiCCs;
    const SAMPLE_ACCURATE_AUTOMATION: bool = true;
    /// Room for a flood of events in one block: the framework's queue grows (allocates) on the
    /// audio thread past this, and the host tests send 10,000 random events in one block.
    const INPUT_EVENT_CAPACITY: usize = 16_384;

    type Editor = EguiEditor<editor::EditorApp>;
    type SysExMessage = ();
    type BackgroundTask = ();

    /// Every value in a state being loaded is read as its parameter's type and brought into its
    /// range: a number into the range (a choice saved by its index included), a whole number or
    /// a choice's index rounded, a switch as any number other than 0, a choice saved by its id
    /// kept if this version knows the id. A value it cannot be read as (a word for a number, a
    /// choice this version does not have, a number that is not finite: JSON reads 1e39 as an
    /// `f32` infinity) takes the default, as does a parameter the state leaves out (one an older
    /// version did not have, or a hand-made state): the framework would otherwise skip it and
    /// leave the instance's value, so that one state would load differently in two instances,
    /// and would store a non-finite number as it is. The player's settings
    /// ([`PLAYER_SETTINGS`](qsa_dsp::instrument::PLAYER_SETTINGS)) stay as the player set them
    /// instead. The engine then never hears a value the parameter cannot take, and the state the
    /// host saves next can be read back. The factory preset the editor names (the `preset`
    /// field) is none when the state names none or names it as anything but a JSON string: the
    /// name of the preset the instance had would otherwise stay over values it no longer has.
    fn filter_state(state: &mut PluginState) {
        let named = state.fields.get(PRESET_FIELD).is_some_and(|f| serde_json::from_str::<String>(f).is_ok());
        if !named {
            state.fields.insert(PRESET_FIELD.to_owned(), "\"\"".to_owned());
        }
        for spec in &qsa_dsp::instrument::PARAMETERS {
            match state.params.get(spec.id).map(|saved| state_value(spec, saved)) {
                Some(Some(value)) => {
                    state.params.insert(spec.id.to_owned(), value);
                }
                _ if qsa_dsp::instrument::PLAYER_SETTINGS.contains(&spec.id) => {
                    state.params.remove(spec.id);
                }
                _ => {
                    state.params.insert(spec.id.to_owned(), default_value(spec));
                }
            }
        }
    }

    fn params(&self) -> Arc<dyn Params> {
        self.params.clone()
    }

    fn editor(&mut self, _async_executor: AsyncExecutor<Self>) -> Option<Self::Editor> {
        editor::create(self.params.clone(), self.tap.shared().clone(), self.editor_state.clone())
    }

    fn activate(
        &mut self,
        _audio_io_layout: &AudioIOLayout,
        buffer_config: &BufferConfig,
        context: &mut impl ActivateContext<Self>,
    ) -> bool {
        let voices = self.params.engine.voices.value().clamp(1, 128) as usize;
        context.set_current_voice_capacity(voices as u32);
        self.tap.shared().voices.store(voices, std::sync::atomic::Ordering::Relaxed);
        let fs = f64::from(buffer_config.sample_rate);
        let reuse = self.engine.as_ref().is_some_and(|e| e.sample_rate() == fs && e.voices() == voices);
        if !reuse {
            let mut engine = Instrument::new(fs, voices, self.params.settings());
            // The controller told the old engine its configuration once; the new one keeps it,
            // and reports the end of the old one's notes at its first sample.
            if let Some(old) = &mut self.engine {
                engine.take_over(old);
            }
            self.engine = Some(engine);
        }
        if let Some(engine) = &self.engine {
            context.set_latency_samples(engine.latency() as u32);
        }
        self.tap.set_sample_rate(fs);
        self.realtime = keeps_time(buffer_config.process_mode);
        self.guard.reset();
        self.restart_asked = None;
        true
    }

    fn deactivate(&mut self) {
        self.tap.rest(self.engine.as_ref());
    }

    fn reset(&mut self) {
        if let Some(engine) = &mut self.engine {
            // Parameters set while the plugin was not processing (a state loaded, a host's flush
            // while stopped) count from the reset's first sample, as on a new instance.
            engine.set_settings(&self.params.settings());
            // Events waiting from the latest call reach the engine before it is reset, so that
            // their notes end with the others.
            self.deferred.drain(..).for_each(|e| engine.handle(e));
            engine.reset();
        }
        self.guard.reset();
    }

    fn process(
        &mut self,
        buffer: &mut Buffer,
        _aux: &mut AuxiliaryBuffers,
        context: &mut impl ProcessContext<Self>,
    ) -> ProcessStatus {
        let start = Instant::now();
        let samples = buffer.samples();
        let channels = buffer.as_slice();
        let Some(engine) = &mut self.engine else {
            channels.iter_mut().for_each(|c| c.fill(0.0));
            return ProcessStatus::Normal;
        };
        engine.set_settings(&self.params.settings());
        // The voice pool is sized at activation. A new count the open editor did not set (it asks
        // once its slider has settled), a state loaded with the editor closed say, asks the host
        // to restart the plugin, once per count; a count asked for, left for the pool's own and
        // set again before the host restarted is asked for again.
        let voices = self.params.engine.voices.value().clamp(1, 128) as usize;
        if voices == engine.voices() {
            self.restart_asked = None;
        } else if !self.editor_state.is_open() && self.restart_asked != Some(voices) {
            context.request_restart();
            self.restart_asked = Some(voices);
        }
        let (left, right) = match channels {
            [left, right, ..] => (left, right),
            _ => return ProcessStatus::Normal,
        };
        let origin = engine.now();
        // Events stamped at the latest call's end take their sample now, under its settings.
        for e in self.deferred.drain(..) {
            engine.handle(e);
            report_ended(engine, context, origin);
        }
        let api = context.plugin_api();
        let mut done = 0;
        let mut next = context.next_event();
        while done < samples {
            while let Some(event) = next {
                if event.timing() as usize > done {
                    break;
                }
                if let Some(e) = engine_event(&event, api) {
                    engine.handle(e);
                    report_ended(engine, context, origin);
                }
                next = context.next_event();
            }
            let until = next.map_or(samples, |e| (e.timing() as usize).clamp(done + 1, samples));
            engine.process(&mut left[done..until], &mut right[done..until]);
            report_ended(engine, context, origin);
            done = until;
        }
        // Events stamped at the very end of the buffer belong to the next call's first sample,
        // the same engine sample. The framework ends a call there when it splits a host's buffer
        // at a parameter change, and applies that change with the next call's settings: a note
        // the host listed before the change at its sample then takes it, as a note listed after
        // does.
        while let Some(event) = next {
            if let Some(e) = engine_event(&event, api) {
                if self.deferred.len() < DEFERRED_EVENTS {
                    self.deferred.push(e);
                } else {
                    for e in self.deferred.drain(..).chain([e]) {
                        engine.handle(e);
                        report_ended(engine, context, origin);
                    }
                }
            }
            next = context.next_event();
        }
        let elapsed = start.elapsed();
        // Snapshots only while someone looks at them; the load always.
        let open = self.editor_state.is_open();
        self.tap.after_process(samples, elapsed, self.engine.as_ref().filter(|_| open));
        self.guard.switch(self.params.engine.overload_guard.value());
        if self.realtime
            && let Some(engine) = &mut self.engine
        {
            let duration = samples as f64 / engine.sample_rate();
            let shed = self.guard.after_call(duration, elapsed.as_secs_f64(), engine.sounding());
            if shed > 0 {
                engine.shed_voices(shed);
            }
        }
        ProcessStatus::KeepAlive
    }
}

impl ClapPlugin for QsaStrings {
    const CLAP_ID: &'static str = "org.qsa-strings.qsa-strings";
    const CLAP_DESCRIPTION: Option<&'static str> =
        Some("Physical modelling of collisions on strings: piano hammers and guitar slides (QSA)");
    const CLAP_MANUAL_URL: Option<&'static str> = None;
    const CLAP_SUPPORT_URL: Option<&'static str> = None;
    const CLAP_FEATURES: &'static [ClapFeature] =
        &[ClapFeature::Instrument, ClapFeature::Synthesizer, ClapFeature::Stereo];
    /// Polyphonic modulation of `slide` and `hand`. Note-offs reach notes by channel and key, so
    /// the plugin does not claim overlapping notes (notes on one key told apart by voice id alone).
    const CLAP_POLY_MODULATION_CONFIG: Option<PolyModulationConfig> =
        Some(PolyModulationConfig { max_voice_capacity: 128, supports_overlapping_voices: false });
}

impl Vst3Plugin for QsaStrings {
    /// Also written into the factory presets' VST3 preset files (`xtask::presets`), which hosts
    /// refuse for any other id (the VST3 host test loads them).
    const VST3_CLASS_ID: [u8; 16] = *b"QsaStringsPlugin";
    const VST3_SUBCATEGORIES: &'static [Vst3SubCategory] = &[Vst3SubCategory::Instrument, Vst3SubCategory::Synth];
}

nice_export_clap!(QsaStrings);
nice_export_vst3!(QsaStrings);

/// Whether the host waits for each buffer in `mode`, so that a call running late costs it audio
/// and the overload guard may shed voices: in real time, and when it processes ahead of time
/// (VST3's prefetch, Cubase's ASIO-Guard), which buys slack but underruns all the same when the
/// load stays above a buffer's duration. Only offline rendering waits as long as it takes.
fn keeps_time(mode: ProcessMode) -> bool {
    mode != ProcessMode::Offline
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_guard_watches_real_time_and_prefetch_processing_and_never_offline_rendering() {
        assert!(keeps_time(ProcessMode::Realtime));
        assert!(keeps_time(ProcessMode::Buffered));
        assert!(!keeps_time(ProcessMode::Offline));
    }

    /// A note's brightness reaches the engine from either plugin API, whichever event nice-plug
    /// gives it as (CLAP's `PolyBrightness`, VST3's `PolyExpression`), and a VST3 note's
    /// expression (nice-plug's `PolyBrightness` there) and CLAP's expression reach nothing.
    #[test]
    fn a_notes_brightness_reaches_the_engine_from_clap_and_from_vst3() {
        let (voice_id, channel, key) = (VoiceID::ID(7), Channel::Number(2), Key::Number(57));
        let brightness = NoteEvent::<()>::PolyBrightness { timing: 0, voice_id, channel, key, brightness: 0.75 };
        let expression = NoteEvent::<()>::PolyExpression { timing: 0, voice_id, channel, key, expression: 0.75 };
        let note = NoteTarget { voice: Some(7), channel: Some(2), key: Some(57) };
        let engine = Some(Event::NoteBrightness { note, value: 0.75 });
        assert_eq!(engine_event(&brightness, PluginApi::Clap), engine);
        assert_eq!(engine_event(&expression, PluginApi::Vst3), engine);
        assert_eq!(engine_event(&brightness, PluginApi::Vst3), None);
        assert_eq!(engine_event(&expression, PluginApi::Clap), None);
    }

    /// Every channel message becomes the same engine event through the framework's parser and
    /// this plugin's mapping as through the offline renderer's `event_from_midi`.
    #[test]
    fn midi_maps_like_the_offline_renderer() {
        for status in (0x80..=0xef).step_by(1) {
            for (d1, d2) in [
                (0u8, 0u8),
                (60, 1),
                (60, 64),
                (127, 127),
                (1, 100),
                (64, 63),
                (64, 64),
                (66, 63),
                (66, 64),
                (67, 63),
                (67, 64),
                (74, 0),
                (74, 127),
                (120, 0),
                (123, 5),
                (6, 48),
                (38, 50),
                (100, 6),
                (101, 127),
                (99, 1),
                (98, 8),
                (0, 64),
                (127, 63),
            ] {
                let via_host = NoteEvent::<()>::from_midi(0, &[status, d1, d2])
                    .ok()
                    .and_then(|e| engine_event(&e, PluginApi::Clap));
                let offline = qsa_dsp::instrument::event_from_midi(status, d1, d2);
                assert_eq!(via_host, offline, "status {status:#x} data {d1} {d2}");
            }
        }
    }
}
