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
//! - MIDI: notes; CC64 sustain, CC1 mod wheel, CC120 all sound off, CC123 all notes off; pitch bend
//!   moves the slide; channel and poly pressure can press it (per channel, so MPE works).
//!
//! - The editor ([`editor`]) shows the parameters and the loudest voice. `process` times itself
//!   and, every 1/30 s of audio while the editor is open, hands the engine's monitor snapshot to
//!   it through the lock-free [`meter`] path (no allocation, lock or I/O on the audio thread).
//!
//! State (parameters) is saved by the framework with the plugin's version, which `filter_state`
//! sees first: that is where later releases migrate old state.

pub mod editor;
pub mod meter;
pub mod params;

use std::num::NonZeroU32;
use std::sync::Arc;
use std::time::Instant;

use nice_plug::midi::{Channel, Key};
use nice_plug::prelude::*;
use nice_plug_egui::{EguiEditor, EguiEditorState};
use qsa_dsp::instrument::{Event, Instrument};

use meter::{Shared, Tap};
use params::QsaParams;

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
}

impl Default for QsaStrings {
    fn default() -> Self {
        Self {
            params: Arc::new(QsaParams::default()),
            engine: None,
            editor_state: editor::default_state(),
            tap: Tap::new(Arc::new(Shared::default())),
        }
    }
}

/// The engine event for a host note event, if it is one the engine plays.
fn engine_event<S>(event: &NoteEvent<S>) -> Option<Event> {
    let note = |channel: &Channel, key: &Key| Some((channel.number().unwrap_or(0), key.number()?));
    Some(match *event {
        NoteEvent::NoteOn { channel, key, velocity, .. } => {
            let (channel, key) = note(&channel, &key)?;
            Event::NoteOn { channel, key, velocity }
        }
        NoteEvent::NoteOff { channel, key, .. } | NoteEvent::Choke { channel, key, .. } => {
            let (channel, key) = note(&channel, &key)?;
            Event::NoteOff { channel, key }
        }
        NoteEvent::PolyPressure { channel, key, pressure, .. } => {
            let (channel, key) = note(&channel, &key)?;
            Event::PolyPressure { channel, key, value: pressure }
        }
        NoteEvent::MidiChannelPressure { channel, pressure, .. } => Event::ChannelPressure { channel, value: pressure },
        NoteEvent::MidiPitchBend { channel, value, .. } => Event::PitchBend { channel, value: 2.0 * value - 1.0 },
        NoteEvent::MidiCC { channel, cc, value, .. } => match cc {
            1 => Event::ModWheel { channel, value },
            64 => Event::Sustain { channel, down: value >= 0.5 },
            120 => Event::AllSoundOff,
            123 => Event::AllNotesOff,
            _ => return None,
        },
        _ => return None,
    })
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
        _context: &mut impl ActivateContext<Self>,
    ) -> bool {
        let voices = self.params.voices.value().clamp(1, 128) as usize;
        let fs = f64::from(buffer_config.sample_rate);
        let reuse = self.engine.as_ref().is_some_and(|e| e.sample_rate() == fs && e.voices() == voices);
        if !reuse {
            self.engine = Some(Instrument::new(fs, voices, self.params.settings()));
        }
        self.tap.set_sample_rate(fs);
        true
    }

    fn reset(&mut self) {
        if let Some(engine) = &mut self.engine {
            engine.handle(Event::AllSoundOff);
        }
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
        let (left, right) = match channels {
            [left, right, ..] => (left, right),
            _ => return ProcessStatus::Normal,
        };
        let mut done = 0;
        let mut next = context.next_event();
        while done < samples {
            while let Some(event) = next {
                if event.timing() as usize > done {
                    break;
                }
                if let Some(e) = engine_event(&event) {
                    engine.handle(e);
                }
                next = context.next_event();
            }
            let until = next.map_or(samples, |e| (e.timing() as usize).clamp(done + 1, samples));
            engine.process(&mut left[done..until], &mut right[done..until]);
            done = until;
        }
        // Events stamped at the very end of the buffer.
        while let Some(event) = next {
            if let Some(e) = engine_event(&event) {
                engine.handle(e);
            }
            next = context.next_event();
        }
        // Snapshots only while someone looks at them; the load always.
        let open = self.editor_state.is_open();
        self.tap.after_process(samples, start.elapsed(), self.engine.as_ref().filter(|_| open));
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
}

impl Vst3Plugin for QsaStrings {
    const VST3_CLASS_ID: [u8; 16] = *b"QsaStringsPlugin";
    const VST3_SUBCATEGORIES: &'static [Vst3SubCategory] = &[Vst3SubCategory::Instrument, Vst3SubCategory::Synth];
}

nice_export_clap!(QsaStrings);
nice_export_vst3!(QsaStrings);

#[cfg(test)]
mod tests {
    use super::*;

    /// Every channel message becomes the same engine event through the framework's parser and
    /// this plugin's mapping as through the offline renderer's `event_from_midi`.
    #[test]
    fn midi_maps_like_the_offline_renderer() {
        for status in (0x80..=0xef).step_by(1) {
            for (d1, d2) in
                [(0u8, 0u8), (60, 1), (60, 64), (127, 127), (1, 100), (64, 63), (64, 64), (120, 0), (123, 5)]
            {
                let via_host = NoteEvent::<()>::from_midi(0, &[status, d1, d2]).ok().and_then(|e| engine_event(&e));
                let offline = qsa_dsp::instrument::event_from_midi(status, d1, d2);
                assert_eq!(via_host, offline, "status {status:#x} data {d1} {d2}");
            }
        }
    }
}
