//! The clack-host harness the real-host CLAP tests share (`host_clap.rs`, `host_fuzz.rs`): the
//! release bundle's path, a host that loads, activates and processes the plugin on an audio
//! thread, parameter ids by their documented string ids, and timed note, MIDI and parameter
//! events, CLAP note-offs and chokes with wildcards, note expressions and polyphonic modulation;
//! renders collect the note-end events the plugin sends. The host renders offline (CLAP's render
//! extension), as a DAW exporting does: the tests compare samples across buffer sizes and with the
//! offline renderer, and the plugin's overload guard, which sheds voices when real-time processing
//! cannot keep up, must not act on how fast the test machine is.
//!
//! Used as `#[path = "support/host.rs"] mod host;` next to `#[path = "support/bundle.rs"] mod
//! bundle;` (this module finds the bundle through `crate::bundle`).
//!
//! `unsafe` is allowed for one reason: loading a plugin binary (`PluginEntry::load`) runs foreign
//! code, which no compiler can check.
#![allow(dead_code)] // each test binary uses part of the harness
#![allow(unsafe_code)] // loading a plugin binary is inherently unsafe (clack-host's `PluginEntry::load`)

use std::ffi::CString;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Mutex, PoisonError};

use clack_extensions::params::PluginParams;
use clack_extensions::render::{PluginRender, RenderMode};
use clack_extensions::state::PluginState;
use clack_host::events::Match;
use clack_host::events::event_types::{
    MidiEvent, NoteChokeEvent, NoteEndEvent, NoteExpressionEvent, NoteExpressionType, NoteOffEvent, NoteOnEvent,
    ParamModEvent, ParamValueEvent,
};
use clack_host::prelude::*;

use crate::bundle::{BUILD_RELEASE, checked_bundle, target_dir};

/// The plugin's CLAP id (`ClapPlugin::CLAP_ID`).
pub const PLUGIN_ID: &str = "org.qsa-strings.qsa-strings";

/// The release bundle.
pub fn release_bundle() -> PathBuf {
    checked_bundle(target_dir().join("bundled/QSA Strings.clap"), BUILD_RELEASE)
}

/// Every bundle loaded so far, kept loaded until the process exits, as a host keeps a plugin
/// binary loaded. clack-host unloads a bundle when its last instance goes; a test thread that ran
/// the plugin's code and exits after that would run thread-local destructors the plugin
/// registered, in code no longer mapped (a SIGSEGV at thread exit when tests run in parallel).
static ENTRIES: Mutex<Vec<(PathBuf, PluginEntry)>> = Mutex::new(Vec::new());

/// The loaded entry of `bundle` (loaded on first use).
fn entry(bundle: &Path) -> PluginEntry {
    let mut entries = ENTRIES.lock().unwrap_or_else(PoisonError::into_inner);
    if let Some((_, entry)) = entries.iter().find(|(path, _)| path == bundle) {
        return entry.clone();
    }
    // SAFETY: loading a plugin binary runs its initialisation code; the bundle is this project's
    // own build.
    let entry = unsafe { PluginEntry::load(bundle) }.unwrap_or_else(|e| panic!("loading {}: {e:?}", bundle.display()));
    entries.push((bundle.to_path_buf(), entry.clone()));
    entry
}

/// The host's handlers: nothing but a flag for the plugin's main-thread callback requests.
pub struct TestHost;

pub struct Shared {
    callback_requested: AtomicBool,
    restarts_requested: AtomicUsize,
}

impl<'a> SharedHandler<'a> for Shared {
    fn request_restart(&self) {
        self.restarts_requested.fetch_add(1, Ordering::SeqCst);
    }
    fn request_process(&self) {}
    fn request_callback(&self) {
        self.callback_requested.store(true, Ordering::SeqCst);
    }
}

impl HostHandlers for TestHost {
    type Shared<'a> = Shared;
    type MainThread<'a> = ();
    type AudioProcessor<'a> = ();
}

/// A parameter's CLAP id: nice-plug derives it from the stable string id with this hash
/// (`hash_param_id` in nice-plug 0.4.2, `wrapper/util.rs`; VST3 uses the same), so the documented
/// string ids determine the ids a host stores in its automation.
pub fn clap_id(id: &str) -> u32 {
    id.bytes().fold(0u32, |h, b| h.wrapping_mul(31).wrapping_add(u32::from(b))) & !(1 << 31)
}

/// One host event.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Ev {
    /// CLAP note-on (channel, key, velocity 0..1).
    On(u8, u8, f64),
    /// CLAP note-off (channel, key).
    Off(u8, u8),
    /// A raw MIDI 1.0 message.
    Midi([u8; 3]),
    /// A parameter value (CLAP id, CLAP value: normalised 0..1, or the step index of stepped ones).
    Param(u32, f64),
    /// CLAP note-on with a note id (channel, key, velocity 0..1, note id).
    OnId(u8, u8, f64, u32),
    /// A CLAP note expression for the notes `target` addresses.
    Expr(Expression, Target, f64),
    /// CLAP polyphonic modulation: parameter (CLAP id), the note id it modulates, amount (in CLAP
    /// value units, like `Param`).
    Mod(u32, u32, f64),
    /// CLAP note-off for the notes `target` addresses (wildcards allowed).
    OffAt(Target),
    /// CLAP note choke for the notes `target` addresses (wildcards allowed).
    Choke(Target),
}

/// The CLAP note expressions the tests send.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Expression {
    /// Tuning, semitones.
    Tuning,
    /// Pressure, 0..=1.
    Pressure,
    /// Brightness, 0..=1.
    Brightness,
}

/// The notes a CLAP note event addresses: note id, channel and key, each a wildcard when `None`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Target {
    pub note_id: Option<u32>,
    pub channel: Option<u8>,
    pub key: Option<u8>,
}

impl Target {
    /// The note with host note id `id` (channel and key wildcards).
    pub fn id(id: u32) -> Self {
        Self { note_id: Some(id), channel: None, key: None }
    }

    /// The notes on `channel` and `key` (note id wildcard).
    pub fn key(channel: u8, key: u8) -> Self {
        Self { note_id: None, channel: Some(channel), key: Some(key) }
    }

    fn pckn(self) -> Pckn {
        let channel = self.channel.map_or(Match::All, |c| Match::Specific(u16::from(c)));
        let key = self.key.map_or(Match::All, |k| Match::Specific(u16::from(k)));
        Pckn::new(0u16, channel, key, self.note_id.map_or(Match::All, Match::Specific))
    }
}

/// A note-end event the plugin sent: (sample from the start of the render, note id or −1, channel,
/// key).
pub type NoteEnd = (usize, i32, i16, i16);

/// Timed events: (sample from the start of a render, event), in time order.
pub type Score = Vec<(usize, Ev)>;

/// A parameter change by string id.
pub fn param(id: &str, value: f64) -> Ev {
    Ev::Param(clap_id(id), value)
}

/// Audio of one render: left and right channels, and the note-end events the plugin sent.
pub struct Audio {
    pub left: Vec<f32>,
    pub right: Vec<f32>,
    pub note_ends: Vec<NoteEnd>,
}

impl Audio {
    pub fn peak(&self) -> f32 {
        self.left.iter().chain(&self.right).fold(0.0f32, |m, v| m.max(v.abs()))
    }

    pub fn assert_finite(&self, what: &str) {
        let bad = self.left.iter().chain(&self.right).position(|v| !v.is_finite());
        assert!(bad.is_none(), "{what}: non-finite sample at index {bad:?}");
    }

    /// The left channel from `from` samples on, as f64.
    pub fn tail(&self, from: usize) -> Vec<f64> {
        self.left[from..].iter().map(|&v| f64::from(v)).collect()
    }
}

/// A plugin instance in clack-host, active and processing.
pub struct Plugin {
    pub instance: PluginInstance<TestHost>,
    processor: Option<StartedPluginAudioProcessor<TestHost>>,
    config: PluginAudioConfiguration,
    max_block: usize,
}

impl Plugin {
    /// Load `bundle`, instantiate the plugin, set `setup` (by flushing parameter events while
    /// inactive, as a host restoring a project does), activate at `sample_rate` with blocks of up
    /// to `max_block` samples and start processing.
    pub fn new(bundle: &Path, sample_rate: f64, max_block: usize, setup: &[Ev]) -> Self {
        let entry = entry(bundle);
        let factory = entry.get_plugin_factory().expect("the entry has a plugin factory");
        let ids: Vec<String> =
            factory.plugin_descriptors().filter_map(|d| d.id().map(|id| id.to_string_lossy().into_owned())).collect();
        assert_eq!(ids, [PLUGIN_ID], "plugins in the bundle");
        let host_info = HostInfo::new("qsa-tests", "QSA Strings", "https://example.invalid", "0.1.0").expect("host");
        let id = CString::new(PLUGIN_ID).expect("id");
        let mut instance = PluginInstance::<TestHost>::new(
            |_| Shared { callback_requested: AtomicBool::new(false), restarts_requested: AtomicUsize::new(0) },
            |_| (),
            &entry,
            &id,
            &host_info,
        )
        .expect("instantiate");
        let render: PluginRender = instance.plugin_handle().get_extension().expect("render extension");
        render.set(&instance.plugin_handle(), RenderMode::Offline).expect("offline rendering");
        flush_inactive(&mut instance, setup);
        let config = PluginAudioConfiguration { sample_rate, min_frames_count: 1, max_frames_count: max_block as u32 };
        let processor = instance.activate(|_, _| (), config).expect("activate").start_processing().expect("start");
        Self { instance, processor: Some(processor), config, max_block }
    }

    /// Stop processing, deactivate and activate again at `sample_rate`, as a host does to apply
    /// a change that needs a restart (`Voices`) or when its session's sample rate changes.
    pub fn reactivate_at(&mut self, sample_rate: f64) {
        if let Some(processor) = self.processor.take() {
            self.instance.deactivate(processor.stop_processing());
        }
        self.config.sample_rate = sample_rate;
        let processor =
            self.instance.activate(|_, _| (), self.config).expect("activate").start_processing().expect("start");
        self.processor = Some(processor);
    }

    /// Stop processing and deactivate, run `while_stopped` (which may set parameters with
    /// [`flush_inactive`] or load state), then activate at the same sample rate and start again,
    /// as a host does around edits made while its transport stands.
    pub fn restart(&mut self, while_stopped: impl FnOnce(&mut Self)) {
        if let Some(processor) = self.processor.take() {
            self.instance.deactivate(processor.stop_processing());
        }
        while_stopped(self);
        let processor =
            self.instance.activate(|_, _| (), self.config).expect("activate").start_processing().expect("start");
        self.processor = Some(processor);
    }

    /// Set parameter values by flushing them while the instance is inactive.
    pub fn flush_inactive(&mut self, values: &[Ev]) {
        assert!(self.processor.is_none(), "flush_inactive while active");
        flush_inactive(&mut self.instance, values);
    }

    /// A 48 kHz instance taking blocks of up to 8192 samples.
    pub fn at_48k(bundle: &Path, setup: &[Ev]) -> Self {
        Self::new(bundle, 48_000.0, 8192, setup)
    }

    pub fn params(&mut self) -> PluginParams {
        self.instance.plugin_handle().get_extension().expect("params extension")
    }

    /// The plugin's text for a parameter's CLAP value.
    pub fn value_text(&mut self, id: u32, value: f64) -> String {
        let params = self.params();
        let mut buffer = [0u8; 64];
        params
            .value_to_text(&self.instance.plugin_handle(), ClapId::new(id), value, &mut buffer)
            .map_or_else(|e| format!("<value_to_text failed: {e:?}>"), |t| String::from_utf8_lossy(t).into_owned())
    }

    /// The CLAP value the plugin reads from `text` for a parameter (its own text-to-value
    /// conversion, as a host's text entry uses), if it reads one.
    pub fn text_value(&mut self, id: u32, text: &str) -> Option<f64> {
        let params = self.params();
        let text = CString::new(text).ok()?;
        params.text_to_value(&self.instance.plugin_handle(), ClapId::new(id), &text)
    }

    /// Current CLAP value of a parameter.
    pub fn value(&mut self, id: u32) -> Option<f64> {
        let params = self.params();
        params.get_value(&self.instance.plugin_handle(), ClapId::new(id))
    }

    /// Render `samples` samples with `score`, calling `process` with blocks of the sizes `sizes`
    /// yields (at most `max_block`), on a separate audio thread. Events go to the block holding
    /// their sample, with block-relative times.
    pub fn render(&mut self, score: &[(usize, Ev)], samples: usize, mut sizes: impl FnMut() -> usize + Send) -> Audio {
        assert!(score.windows(2).all(|w| w[0].0 <= w[1].0), "score out of order");
        assert!(score.iter().all(|e| e.0 < samples), "event after the end of the render");
        let max_block = self.max_block;
        let processor = self.processor.as_mut().expect("processing");
        let audio = std::thread::scope(|s| {
            s.spawn(move || {
                let (mut left, mut right) = (vec![0.0f32; samples], vec![0.0f32; samples]);
                let mut ports = AudioPorts::with_capacity(2, 1);
                let mut events = EventBuffer::with_capacity(score.len().min(20_000));
                // Room for a note-end per event of a flood: a host's output queue must not grow
                // inside `process` (the debug bundle aborts on any allocation there).
                let mut output_events = EventBuffer::with_capacity(20_000);
                let mut note_ends = Vec::new();
                let (mut t, mut next) = (0, 0);
                while t < samples {
                    let n = sizes().clamp(1, max_block).min(samples - t);
                    events.clear();
                    while next < score.len() && score[next].0 < t + n {
                        push_event(&mut events, (score[next].0 - t) as u32, score[next].1);
                        next += 1;
                    }
                    let (l, r) = (&mut left[t..t + n], &mut right[t..t + n]);
                    let mut outputs = ports.with_output_buffers([AudioPortBuffer {
                        latency: 0,
                        channels: AudioPortBufferType::f32_output_only([l, r].into_iter()),
                    }]);
                    output_events.clear();
                    processor
                        .process(
                            &InputAudioBuffers::empty(),
                            &mut outputs,
                            &events.as_input(),
                            &mut output_events.as_output(),
                            None,
                            None,
                        )
                        .expect("process");
                    for event in output_events.iter() {
                        if let Some(end) = event.as_event::<NoteEndEvent>() {
                            let pckn = end.pckn();
                            let time = t + end.header().time() as usize;
                            note_ends.push((time, pckn.raw_note_id(), pckn.raw_channel(), pckn.raw_key()));
                        }
                    }
                    t += n;
                }
                Audio { left, right, note_ends }
            })
            .join()
            .expect("the audio thread panicked")
        });
        self.main_thread_callback();
        audio
    }

    /// Render with blocks of one size.
    pub fn render_blocks(&mut self, score: &[(usize, Ev)], samples: usize, block: usize) -> Audio {
        self.render(score, samples, || block)
    }

    /// Run the plugin's main-thread callback if it asked for one.
    pub fn main_thread_callback(&mut self) {
        if self.instance.access_shared_handler(|s| s.callback_requested.swap(false, Ordering::SeqCst)) {
            self.instance.call_on_main_thread_callback();
        }
    }

    /// Saved state (the state extension).
    pub fn save(&mut self) -> Vec<u8> {
        let state: PluginState = self.instance.plugin_handle().get_extension().expect("state extension");
        let mut bytes = Vec::new();
        state.save(&self.instance.plugin_handle(), &mut bytes).expect("save state");
        bytes
    }

    /// How many times the plugin has asked the host to restart it (deactivate and activate).
    pub fn restarts_requested(&self) -> usize {
        self.instance.access_shared_handler(|s| s.restarts_requested.load(Ordering::SeqCst))
    }

    /// Load state; whether the plugin accepted it.
    pub fn load(&mut self, bytes: &[u8]) -> bool {
        let state: PluginState = self.instance.plugin_handle().get_extension().expect("state extension");
        let accepted = state.load(&self.instance.plugin_handle(), &mut &bytes[..]).is_ok();
        self.main_thread_callback();
        accepted
    }
}

impl Drop for Plugin {
    fn drop(&mut self) {
        if let Some(processor) = self.processor.take() {
            self.instance.deactivate(processor.stop_processing());
        }
    }
}

/// Set `values` (parameter values only) on an inactive instance by a parameter flush, as a host
/// restoring a project does.
fn flush_inactive(instance: &mut PluginInstance<TestHost>, values: &[Ev]) {
    if values.is_empty() {
        return;
    }
    let params: PluginParams = instance.plugin_handle().get_extension().expect("params extension");
    let mut events = EventBuffer::new();
    for ev in values {
        let Ev::Param(id, value) = *ev else { panic!("a flush takes parameter values only") };
        events.push(&ParamValueEvent::new(0, ClapId::new(id), Pckn::match_all(), value));
    }
    let mut output = EventBuffer::new();
    let mut handle = instance.inactive_plugin_handle().expect("inactive");
    params.flush(&mut handle, &events.as_input(), &mut output.as_output());
}

pub fn push_event(buffer: &mut EventBuffer, time: u32, ev: Ev) {
    let note = |channel: u8, key: u8| Pckn::new(0u16, u16::from(channel), u16::from(key), Match::All);
    match ev {
        Ev::On(channel, key, velocity) => buffer.push(&NoteOnEvent::new(time, note(channel, key), velocity)),
        Ev::Off(channel, key) => buffer.push(&NoteOffEvent::new(time, note(channel, key), 0.0)),
        Ev::Midi(data) => buffer.push(&MidiEvent::new(time, 0, data)),
        Ev::Param(id, value) => buffer.push(&ParamValueEvent::new(time, ClapId::new(id), Pckn::match_all(), value)),
        Ev::OnId(channel, key, velocity, id) => buffer.push(&NoteOnEvent::new(
            time,
            Target { note_id: Some(id), ..Target::key(channel, key) }.pckn(),
            velocity,
        )),
        Ev::Expr(expression, target, value) => {
            let kind = match expression {
                Expression::Tuning => NoteExpressionType::Tuning,
                Expression::Pressure => NoteExpressionType::Pressure,
                Expression::Brightness => NoteExpressionType::Brightness,
            };
            buffer.push(&NoteExpressionEvent::new(time, target.pckn(), kind, value));
        }
        Ev::Mod(param, id, amount) => {
            buffer.push(&ParamModEvent::new(time, ClapId::new(param), Target::id(id).pckn(), amount))
        }
        Ev::OffAt(target) => buffer.push(&NoteOffEvent::new(time, target.pckn(), 0.0)),
        Ev::Choke(target) => buffer.push(&NoteChokeEvent::new(time, target.pckn())),
    }
}

/// The plugin's parameters (the engine's table, `qsa_dsp::instrument::PARAMETERS`): string id,
/// name, and the step count of the stepped ones (CLAP value range 0..=steps; continuous ones span
/// 0..=1).
pub const PARAMETERS: [(&str, &str, Option<u32>); qsa_dsp::instrument::PARAMETERS.len()] = {
    let mut list = [("", "", None); qsa_dsp::instrument::PARAMETERS.len()];
    let mut i = 0;
    while i < list.len() {
        let spec = &qsa_dsp::instrument::PARAMETERS[i];
        list[i] = (spec.id, spec.name, spec.step_count());
        i += 1;
    }
    list
};
