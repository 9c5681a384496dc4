//! The egui editor: the parameters grouped by section, and live views of the loudest voice (its
//! string's shape and contact point, contact force and energy histories), the voices sounding
//! and the DSP load.
//!
//! The audio thread never waits for the editor: it publishes snapshots and the load through
//! [`crate::meter::Shared`] (a lock-free queue and atomics) and sets the repaint flag, which the
//! editor's window polls. The editor drains the queue each frame into its own `History`.

mod presets;
mod slider;
#[cfg(test)]
mod tests;
mod views;

use std::collections::VecDeque;
use std::sync::Arc;
use std::sync::atomic::Ordering;
use std::time::Duration;

use egui::{Color32, RichText, Ui, vec2};
use nice_plug::context::gui::GuiContext;
use nice_plug::editor::dpi::LogicalSize;
use nice_plug::prelude::{Param, ParamSetter};
use nice_plug_egui::baseview::HandlerError;
use nice_plug_egui::{EguiEditor, EguiEditorState, EguiNiceSettings, NiceEguiApp, create_egui_editor};
use qsa_dsp::instrument::{Mode, Monitor};

use crate::meter::Shared;
use crate::params::{ModeParam, QsaParams};
use views::History;

/// Editor window size (logical pixels).
pub const SIZE: (f64, f64) = (1000.0, 775.0);

/// Width of the parameter sliders (logical pixels).
const SLIDER_WIDTH: f32 = 96.0;

/// The editor's state (its size and whether it is open), kept by the plugin.
pub fn default_state() -> Arc<EguiEditorState> {
    EguiEditorState::from_size(LogicalSize::new(SIZE.0, SIZE.1), 1.0)
}

/// The editor, for `Plugin::editor`.
pub fn create(
    params: Arc<QsaParams>,
    shared: Arc<Shared>,
    state: Arc<EguiEditorState>,
) -> Option<EguiEditor<EditorApp>> {
    let repaint = shared.repaint.clone();
    let app = EditorApp::new(params, shared);
    create_egui_editor(state, repaint, EguiNiceSettings::new().with_tile("QSA Strings"), app)
}

/// The editor's app: parameters, shared meters and the GUI-side history.
#[allow(missing_debug_implementations)]
pub struct EditorApp {
    params: Arc<QsaParams>,
    shared: Arc<Shared>,
    /// The host's context, given when the window opens.
    gui: Option<GuiContext>,
    /// The latest snapshot.
    latest: Monitor,
    history: History,
    /// The peak loads of the last [`PEAK_HOLD`] seconds that a later one has not exceeded, with
    /// when each was taken (egui time, s), oldest and largest first: the first is shown.
    peak_hold: VecDeque<(f64, f32)>,
    /// The sliders' gestures under way.
    gestures: slider::Gestures,
    /// The voice count the editor last asked the host to restart the plugin for, forgotten once
    /// the plugin runs with the count the parameter holds and when the window opens: a count
    /// asked for, had, and left for another with the window closed is asked for again.
    restart_asked: Option<usize>,
    /// The voice count the parameter holds and since when (egui time, s).
    voices_since: (usize, f64),
}

/// How long a new voice count holds before the editor asks for a restart (s): the parameter
/// reads what the host has taken, which can trail what the slider sent by a few calls.
const VOICES_SETTLE: f64 = 0.3;

/// How long the peak load is held (s).
const PEAK_HOLD: f64 = 1.5;

impl NiceEguiApp for EditorApp {
    fn build(
        &mut self,
        egui_ctx: egui::Context,
        nice_gui_ctx: GuiContext,
        _frame: &mut nice_plug_egui::Frame,
    ) -> Result<(), HandlerError> {
        egui_ctx.set_theme(egui::Theme::Dark);
        self.open_with(nice_gui_ctx);
        Ok(())
    }

    fn ui(&mut self, ui: &mut Ui, _frame: &mut nice_plug_egui::Frame) {
        self.show(ui);
    }
}

impl EditorApp {
    /// The app before its window opens.
    fn new(params: Arc<QsaParams>, shared: Arc<Shared>) -> Self {
        Self {
            params,
            shared,
            gui: None,
            latest: Monitor::default(),
            history: History::default(),
            peak_hold: VecDeque::new(),
            gestures: slider::Gestures::default(),
            restart_asked: None,
            voices_since: (0, 0.0),
        }
    }

    /// The window opens with the host's context `gui`. The window before it may have closed on
    /// a drag (nice-plug-egui tells the app nothing when it closes): its gestures end here,
    /// through the context they began in, so that the host does not keep the parameter touched.
    fn open_with(&mut self, gui: GuiContext) {
        if let Some(old) = &self.gui {
            self.gestures.end_all(&old.param_setter());
        }
        self.gui = Some(gui);
        self.restart_asked = None;
    }

    /// A frame of the editor (what [`NiceEguiApp::ui`] draws; the tests draw it headless).
    fn show(&mut self, ui: &mut Ui) {
        // Snapshots arrive with a repaint request; this keeps the load moving when they do not.
        ui.ctx().request_repaint_after(Duration::from_millis(250));
        while let Some(monitor) = self.shared.monitors.pop() {
            self.history.push(&monitor);
            self.latest = monitor;
        }
        let now = ui.input(|i| i.time);
        let load = self.shared.load.load(Ordering::Relaxed);
        let peak = self.shared.peak.swap(0.0, Ordering::Relaxed).max(load);
        let held = &mut self.peak_hold;
        while held.back().is_some_and(|&(_, p)| p <= peak) {
            held.pop_back();
        }
        held.push_back((now, peak));
        while held.front().is_some_and(|&(t, _)| now - t > PEAK_HOLD) {
            held.pop_front();
        }

        let Some(gui) = &self.gui else {
            return;
        };
        // The voice pool is sized when the plugin is activated: a new count, once the slider
        // has let it go and it has held for `VOICES_SETTLE`, asks the host to restart the plugin
        // (once per count).
        let voices = &self.params.engine.voices;
        let (wanted, active) = (voices.value().clamp(1, 128) as usize, self.shared.voices.load(Ordering::Relaxed));
        if self.voices_since.0 != wanted {
            self.voices_since = (wanted, now);
        }
        let settled = now - self.voices_since.1 >= VOICES_SETTLE && !self.gestures.holds(voices);
        if wanted == active {
            self.restart_asked = None;
        } else if active != 0 && self.restart_asked != Some(wanted) && settled {
            gui.request_restart();
            self.restart_asked = Some(wanted);
        }
        let setter = gui.param_setter();
        let peak = self.peak_hold.front().map_or(0.0, |&(_, p)| p);
        let (params, latest, history) = (&*self.params, &self.latest, &self.history);
        let gestures = &self.gestures;
        egui::CentralPanel::default().show(ui, |ui| {
            header(ui, latest, load, peak);
            ui.add_space(6.0);
            live_view(ui, latest, history);
            ui.add_space(6.0);
            ui.separator();
            parameters(ui, params, Controls { setter: &setter, gestures });
        });
    }
}

/// Title, what the loudest voice is, how many voices the energy guard silenced and the overload
/// guard shed (if any), and the DSP load.
fn header(ui: &mut Ui, m: &Monitor, load: f32, peak: f32) {
    ui.horizontal(|ui| {
        ui.label(RichText::new("QSA Strings").size(20.0).strong());
        ui.add_space(12.0);
        let voice = if m.sounding == 0 {
            "no voice sounding".to_owned()
        } else {
            let mode = match m.mode {
                Mode::Piano => "piano",
                Mode::Slide => "slide",
            };
            format!(
                "{} sounding · loudest: {} ({}), {mode}",
                plural(m.sounding, "voice"),
                views::note_name(m.key),
                m.key
            )
        };
        ui.label(voice);
        if m.guard_trips > 0 {
            // The energy guard silenced voices whose physics misbehaved: worth a bug report.
            let text = format!("guard silenced {}", plural(m.guard_trips as usize, "voice"));
            ui.label(RichText::new(text).color(Color32::from_rgb(230, 120, 40)));
        }
        if m.shed > 0 {
            ui.label(RichText::new(format!("shed {}", m.shed)).color(Color32::from_rgb(230, 180, 40))).on_hover_text(
                "Voices faded out because the audio thread could not keep up: play fewer voices, use a larger \
                 buffer or a faster machine. Switching Overload guard (Engine) off keeps every voice and leaves \
                 the host to drop buffers instead.",
            );
        }
        ui.with_layout(egui::Layout::right_to_left(egui::Align::Center), |ui| {
            ui.label(RichText::new(format!("{:5.1} % (peak {:.1} %)", load * 100.0, peak * 100.0)).monospace());
            views::load_bar(ui, vec2(160.0, 14.0), load, peak);
            ui.label("DSP load");
        });
    });
}

/// The string shape on the left; force and energy traces on the right.
fn live_view(ui: &mut Ui, m: &Monitor, history: &History) {
    let height = 240.0;
    let gap = ui.spacing().item_spacing.x;
    let width = ui.available_width();
    let left = (width * 0.58).floor();
    let right = width - left - gap;
    ui.horizontal(|ui| {
        views::string_shape(ui, vec2(left, height), m, history);
        ui.vertical(|ui| {
            let h = (height - ui.spacing().item_spacing.y) / 2.0;
            views::force_trace(ui, vec2(right, h), m, history);
            views::energy_trace(ui, vec2(right, h), m, history);
        });
    });
    let compression = if m.compression > 0.0 { views::metres(m.compression) } else { "none".to_owned() };
    ui.label(
        RichText::new(format!(
            "Contact: compression {compression}, force {:.3} N.  Energy: {:.3e} J.",
            m.force.abs(),
            m.energy
        ))
        .small(),
    );
}

/// The parameters in three columns: Engine and Output, Piano, Slide.
fn parameters(ui: &mut Ui, p: &QsaParams, controls: Controls) {
    let mode = p.engine.mode.value();
    ui.columns(3, |columns| {
        let ui = &mut columns[0];
        section(ui, "Engine", None, |ui| {
            row(ui, &p.engine.mode, controls);
            row(ui, &p.engine.solver, controls);
            row(ui, &p.engine.segments, controls);
            row(ui, &p.engine.block, controls);
            row(ui, &p.engine.voices, controls);
            row(ui, &p.engine.overload_guard, controls);
        });
        ui.label(RichText::new("A new voice count: the host is asked to restart the plugin.").small().weak());
        ui.add_space(10.0);
        section(ui, "Output", None, |ui| {
            row(ui, &p.output.gain, controls);
            row(ui, &p.output.limiter, controls);
            row(ui, &p.output.stereo_width, controls);
        });
        ui.add_space(10.0);
        presets::section(ui, p, controls.setter);

        section(&mut columns[1], "Piano", Some(mode == ModeParam::Piano), |ui| {
            row(ui, &p.piano.hardness, controls);
            row(ui, &p.piano.hammer_mass, controls);
            row(ui, &p.piano.strike_position, controls);
            row(ui, &p.piano.damping, controls);
            row(ui, &p.piano.brightness, controls);
            row(ui, &p.piano.damper, controls);
            row(ui, &p.piano.unison_detune, controls);
            row(ui, &p.piano.stretch, controls);
            row(ui, &p.piano.half_pedal_from, controls);
            row(ui, &p.piano.half_pedal_to, controls);
        });

        section(&mut columns[2], "Slide", Some(mode == ModeParam::Slide), |ui| {
            row(ui, &p.slide.slide_position, controls);
            row(ui, &p.slide.follow_key, controls);
            row(ui, &p.slide.glide, controls);
            row(ui, &p.slide.bend_range, controls);
            row(ui, &p.slide.hand_height, controls);
            row(ui, &p.slide.hand_source, controls);
            row(ui, &p.slide.slide_mass, controls);
            row(ui, &p.slide.hand_stiffness, controls);
            row(ui, &p.slide.hand_damping, controls);
            row(ui, &p.slide.finger_damping, controls);
            row(ui, &p.slide.kappa, controls);
            row(ui, &p.slide.alpha, controls);
            row(ui, &p.slide.pluck_position, controls);
            row(ui, &p.slide.pickup_position, controls);
            row(ui, &p.slide.pickup_resonance, controls);
            row(ui, &p.slide.body, controls);
        });
    });
}

/// A titled grid of parameter rows; `active` marks the section of the current mode.
fn section(ui: &mut Ui, title: &str, active: Option<bool>, rows: impl FnOnce(&mut Ui)) {
    ui.horizontal(|ui| {
        ui.label(RichText::new(title).size(16.0).strong());
        if let Some(active) = active {
            views::mode_mark(ui, active);
        }
    });
    egui::Grid::new(title).num_columns(2).spacing([8.0, 4.0]).show(ui, |ui| rows(ui));
}

/// What the sliders change parameters through: the host's setter, and the gestures under way.
#[derive(Clone, Copy)]
struct Controls<'a> {
    setter: &'a ParamSetter<'a>,
    gestures: &'a slider::Gestures,
}

/// A parameter's name and its slider.
fn row<P: Param>(ui: &mut Ui, param: &P, controls: Controls) {
    ui.label(param.name());
    ui.add(slider::Slider::new(param, controls.setter, controls.gestures, SLIDER_WIDTH));
    ui.end_row();
}

/// "1 voice", "3 voices".
fn plural(n: usize, word: &str) -> String {
    if n == 1 { format!("1 {word}") } else { format!("{n} {word}s") }
}
