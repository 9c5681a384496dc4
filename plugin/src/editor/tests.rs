//! The editor drawn headless, as a host opens it (default size), at rest, with voices sounding
//! and with each factory preset chosen: every parameter is shown, every character is in egui's
//! default fonts (no missing-glyph boxes), no text is drawn over other text, and nothing is cut
//! off by the window.

use std::collections::BTreeMap;
use std::sync::Arc;

use egui::{MissingGlyphPolicy, Pos2, RawInput, Rect, Shape, Vec2, vec2};
use nice_plug::context::gui::{GuiContext, GuiContextInner};
use nice_plug::prelude::{Param, ParamPtr, Params, PluginApi, PluginState};
use qsa_dsp::instrument::{Mode, Monitor, factory_presets};

use super::{EditorApp, SIZE};
use crate::meter::Shared;
use crate::params::QsaParams;

/// A host that records the gestures the editor begins and ends, by parameter, and counts its
/// restart requests; it changes nothing.
#[derive(Default)]
struct Host {
    gestures: std::sync::Mutex<Vec<(&'static str, ParamPtr)>>,
    restarts: std::sync::atomic::AtomicUsize,
}

// nice-plug declares the parameter callbacks `unsafe`; these only record their arguments.
#[allow(unsafe_code)]
impl GuiContextInner for Host {
    fn plugin_api(&self) -> PluginApi {
        PluginApi::Clap
    }

    unsafe fn raw_begin_set_parameter(&self, param: ParamPtr) {
        self.gestures.lock().unwrap().push(("begin", param));
    }

    unsafe fn raw_set_parameter_normalized(&self, _: ParamPtr, _: f32) {}

    unsafe fn raw_end_set_parameter(&self, param: ParamPtr) {
        self.gestures.lock().unwrap().push(("end", param));
    }

    fn get_state(&self) -> PluginState {
        PluginState { version: String::new(), params: BTreeMap::new(), fields: BTreeMap::new() }
    }

    fn set_state(&self, _: PluginState) {}

    fn request_restart(&self) {
        self.restarts.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    }
}

/// Twelve voices sounding, the loudest of `mode` with its contact at `contact` of the length.
fn sounding(mode: Mode, contact: f64, guard_trips: u32) -> Monitor {
    let mut m = Monitor {
        sounding: 12,
        guard_trips,
        mode,
        key: 97,
        energy: 2.5e-3,
        compression: 1.2e-5,
        force: -12.5,
        contact_position: contact,
        length: 0.65,
        ..Monitor::default()
    };
    // A slide presses the string down, a hammer pushes it up: the contact label goes to the
    // other edge.
    let amplitude = match mode {
        Mode::Slide => -2e-4,
        Mode::Piano => 2e-4,
    };
    let last = (m.shape.len() - 1) as f32;
    for (k, y) in m.shape.iter_mut().enumerate() {
        *y = amplitude * (std::f32::consts::PI * k as f32 / last).sin();
    }
    m
}

/// The parameters with the factory preset `preset` chosen (empty: none, the defaults): every
/// value it sets, and its id.
#[allow(unsafe_code)] // nice-plug's type-erased parameter calls are `unsafe`; see SAFETY.
fn with_preset(preset: &str) -> QsaParams {
    let params = QsaParams::default();
    if let Some(chosen) = qsa_dsp::instrument::find_preset(preset) {
        for (id, param, _) in params.param_map() {
            if let Some(plain) = chosen.values.plain(&id).filter(|_| chosen.sets(&id)) {
                // SAFETY: `param` comes from the parameter map of `params`, alive here.
                unsafe { param._internal_set_normalized_value(param.preview_normalized(plain)) };
            }
        }
    }
    *params.preset.write().unwrap() = preset.to_owned();
    params
}

/// The parameter values an editor is drawn with: a factory preset's (by id; empty: the
/// defaults), or every parameter at one normalised value (0: the bottoms of the ranges, 1 the
/// tops), where the longest value texts lie.
#[derive(Debug, Clone, Copy)]
pub(super) enum Values<'a> {
    Preset(&'a str),
    Every(f32),
}

impl<'a> From<&'a str> for Values<'a> {
    fn from(preset: &'a str) -> Self {
        Self::Preset(preset)
    }
}

impl<'a> From<&'a String> for Values<'a> {
    fn from(preset: &'a String) -> Self {
        Self::Preset(preset)
    }
}

impl Values<'_> {
    #[allow(unsafe_code)] // nice-plug's type-erased parameter calls are `unsafe`; see SAFETY.
    fn params(self) -> QsaParams {
        match self {
            Self::Preset(id) => with_preset(id),
            Self::Every(normalized) => {
                let params = QsaParams::default();
                for (_, param, _) in params.param_map() {
                    // SAFETY: `param` comes from the parameter map of `params`, alive here.
                    unsafe { param._internal_set_normalized_value(normalized) };
                }
                params
            }
        }
    }
}

/// What the editor draws in a window of `size` with the parameters at `values`, after the audio
/// thread sent `monitors`: its texts, each with the bounds of its glyphs, and the bounds of
/// everything but the panel's background (which grows with what it holds). Panics on a
/// character no font has.
pub(super) fn draw<'a>(monitors: &[Monitor], values: impl Into<Values<'a>>, size: Vec2) -> (Vec<(String, Rect)>, Rect) {
    let shared = Arc::new(Shared::default());
    for m in monitors {
        shared.monitors.force_push(*m);
    }
    let mut app = EditorApp::new(Arc::new(values.into().params()), shared);
    app.gui = Some(GuiContext::new(Arc::new(Host::default())));

    let ctx = egui::Context::default();
    ctx.set_theme(egui::Theme::Dark);
    ctx.set_missing_glyph_policy(MissingGlyphPolicy::Panic);
    let input = RawInput { screen_rect: Some(Rect::from_min_size(Pos2::ZERO, size)), ..RawInput::default() };
    // Grids and columns settle their sizes over the first passes. Nothing here uploads textures,
    // so each pass's font-atlas updates are dropped on purpose (epaint's debug assertions insist
    // that a dropped update be cleared first).
    for _ in 0..2 {
        ctx.run_ui(input.clone(), |ui| app.show(ui)).textures_delta.clear();
    }
    let mut output = ctx.run_ui(input, |ui| app.show(ui));
    output.textures_delta.clear();

    fn collect(shape: &Shape, texts: &mut Vec<(String, Rect)>) {
        match shape {
            Shape::Text(t) if !t.galley.text().trim().is_empty() => {
                texts.push((t.galley.text().to_owned(), t.visual_bounding_rect()));
            }
            Shape::Vec(shapes) => shapes.iter().for_each(|s| collect(s, texts)),
            _ => {}
        }
    }
    let mut texts = Vec::new();
    let mut drawn = Rect::NOTHING;
    for clipped in &output.shapes {
        collect(&clipped.shape, &mut texts);
        let bounds = clipped.shape.visual_bounding_rect();
        if bounds.min != Pos2::ZERO {
            drawn = drawn.union(bounds);
        }
    }
    (texts, drawn)
}

/// Draws the editor in its default window and in a taller one, and checks what it drew.
fn check<'a>(case: &str, monitors: &[Monitor], values: impl Into<Values<'a>>) {
    let values = values.into();
    let window = vec2(SIZE.0 as f32, SIZE.1 as f32);
    let screen = Rect::from_min_size(Pos2::ZERO, window);
    // The panel's margin, less half a stroke.
    let margin = egui::Frame::central_panel(&egui::Style::default()).inner_margin.bottom as f32 - 0.5;
    let (shown, drawn) = draw(monitors, values, window);
    assert!(shown.iter().any(|(t, _)| t == "QSA Strings"), "{case}: nothing drawn");
    assert!(
        screen.shrink(margin).contains_rect(drawn),
        "{case}: the editor draws over {drawn:?}, beyond the {SIZE:?} window's margin"
    );
    for (i, (a, ra)) in shown.iter().enumerate() {
        for (b, rb) in &shown[i + 1..] {
            assert!(!ra.shrink(0.5).intersects(rb.shrink(0.5)), "{case}: {a:?} at {ra:?} overlaps {b:?} at {rb:?}");
        }
    }
    // A taller window shows nothing more: nothing lies wholly below the default one.
    let mut all: Vec<String> =
        draw(monitors, values, vec2(window.x, 3.0 * window.y)).0.into_iter().map(|(t, _)| t).collect();
    let mut shown: Vec<String> = shown.into_iter().map(|(t, _)| t).collect();
    all.sort();
    shown.sort();
    assert_eq!(shown, all, "{case}: the default window hides some of the editor");
}

#[test]
fn the_editor_fits_its_window_without_missing_glyphs_or_overlaps() {
    check("at rest", &[], "");
    check("slide", &[sounding(Mode::Slide, 0.3, 0); 20], "");
    check("slide, contact near the bridge", &[sounding(Mode::Slide, 0.9, 0); 20], "");
    check("piano, guard tripped", &[sounding(Mode::Piano, 0.12, 3); 20], "");
    let overloaded = Monitor { shed: 24, ..sounding(Mode::Piano, 0.12, 3) };
    check("piano, guard tripped and voices shed", &[overloaded; 20], "");
    check("every parameter at the bottom of its range", &[], Values::Every(0.0));
    check("every parameter at the top of its range", &[sounding(Mode::Slide, 0.3, 0); 20], Values::Every(1.0));
    let window = vec2(SIZE.0 as f32, SIZE.1 as f32);
    let (shown, _) = draw(&[overloaded; 20], "", window);
    assert!(shown.iter().any(|(t, _)| t == "shed 24"), "the shed voices are not shown");
}

/// Every factory preset, its values set, fits the editor, which shows each value it sets away
/// from the default.
#[test]
#[allow(unsafe_code)] // nice-plug's type-erased parameter calls are `unsafe`; see SAFETY.
fn every_factory_preset_fits_the_editor() {
    let defaults = QsaParams::default();
    let shown_value = |param: &ParamPtr| {
        // SAFETY: the pointers come from parameter maps alive for the whole test.
        unsafe { param.normalized_value_to_string(param.unmodulated_normalized_value(), true) }
    };
    let default_text: BTreeMap<String, String> =
        defaults.param_map().into_iter().map(|(id, param, _)| (id, shown_value(&param))).collect();
    for preset in factory_presets() {
        let case = format!("preset {}", preset.id);
        check(&case, &[], &preset.id);
        let params = with_preset(&preset.id);
        let moved: Vec<String> = (params.param_map().into_iter())
            .map(|(id, param, _)| (id, shown_value(&param)))
            .filter(|(id, text)| default_text[id] != *text)
            .map(|(_, text)| text)
            .collect();
        assert!(!moved.is_empty() || preset.id == "fig5-hammer", "{case}: sets nothing away from the defaults");
        let (texts, _) = draw(&[], &preset.id, vec2(SIZE.0 as f32, SIZE.1 as f32));
        for text in moved {
            assert!(texts.iter().any(|(t, _)| *t == text), "{case}: its value {text:?} is not shown");
        }
    }
}

/// The editor shows every parameter the host sees: each name in the parameter table is drawn in
/// the default window.
#[test]
fn the_editor_shows_every_parameter() {
    let (shown, _) = draw(&[], "", vec2(SIZE.0 as f32, SIZE.1 as f32));
    for spec in &qsa_dsp::instrument::PARAMETERS {
        assert!(shown.iter().any(|(text, _)| text == spec.name), "{} is not shown", spec.name);
    }
}

/// A voice count other than the one the plugin was activated with asks the host to restart the
/// plugin, once, after it has held for `VOICES_SETTLE`: the parameter at its default of 32
/// against an activation with 16 asks within ten frames of 50 ms and not again in the next
/// ten; activated with 32 (the restart done), nothing more; and before any activation,
/// nothing.
#[test]
fn a_new_voice_count_asks_the_host_once_to_restart_the_plugin() {
    let shared = Arc::new(Shared::default());
    let host = Arc::new(Host::default());
    let mut app = EditorApp::new(Arc::new(QsaParams::default()), shared.clone());
    app.gui = Some(GuiContext::new(host.clone()));
    let ctx = egui::Context::default();
    let screen = Some(Rect::from_min_size(Pos2::ZERO, vec2(1000.0, 775.0)));
    let mut time = 0.0;
    let mut frames = |n: usize| {
        for _ in 0..n {
            time += 0.05;
            let input = RawInput { screen_rect: screen, time: Some(time), ..RawInput::default() };
            ctx.run_ui(input, |ui| app.show(ui)).textures_delta.clear();
        }
        host.restarts.load(std::sync::atomic::Ordering::Relaxed)
    };
    assert_eq!(frames(3), 0, "before any activation");
    shared.voices.store(16, std::sync::atomic::Ordering::Relaxed);
    assert_eq!(frames(10), 1, "activated with 16, 32 asked for");
    assert_eq!(frames(10), 1, "asked once");
    shared.voices.store(32, std::sync::atomic::Ordering::Relaxed);
    assert_eq!(frames(10), 1, "restarted with 32");
}

/// A drag under way when the window closes is ended when the editor opens again, through the
/// host context it began in: the editor draws its sliders, a press on the Solver's bar begins a
/// gesture in the first window's context, and opening a second window ends it there, with
/// nothing sent through the second.
#[test]
fn a_drag_the_window_closed_on_ends_when_the_editor_opens_again() {
    let (first, second) = (Arc::new(Host::default()), Arc::new(Host::default()));
    let params = Arc::new(QsaParams::default());
    let mut app = EditorApp::new(params.clone(), Arc::new(Shared::default()));
    app.open_with(GuiContext::new(first.clone()));
    let ctx = egui::Context::default();
    let screen = Some(Rect::from_min_size(Pos2::ZERO, vec2(SIZE.0 as f32, SIZE.1 as f32)));
    let frame = |events: Vec<egui::Event>, app: &mut EditorApp| {
        let input = RawInput { screen_rect: screen, events, ..RawInput::default() };
        ctx.run_ui(input, |ui| app.show(ui)).textures_delta.clear();
    };
    for _ in 0..3 {
        frame(vec![], &mut app);
    }
    // The Solver's value is drawn just right of its bar.
    let (texts, _) = draw(&[], "", vec2(SIZE.0 as f32, SIZE.1 as f32));
    let label = texts.iter().find(|(t, _)| t == "Solver").expect("the Solver row").1;
    let value = texts.iter().find(|(t, r)| t == "QSA" && (r.center().y - label.center().y).abs() < 4.0);
    let value = value.expect("the Solver's value").1;
    let at = egui::pos2(value.left() - 40.0, value.center().y);
    let press = egui::Event::PointerButton {
        pos: at,
        button: egui::PointerButton::Primary,
        pressed: true,
        modifiers: egui::Modifiers::NONE,
    };
    frame(vec![egui::Event::PointerMoved(at), press], &mut app);
    let solver = params.engine.solver.as_ptr();
    assert_eq!(*first.gestures.lock().unwrap(), [("begin", solver)], "the press began a gesture");
    app.open_with(GuiContext::new(second.clone()));
    assert_eq!(*first.gestures.lock().unwrap(), [("begin", solver), ("end", solver)], "ended where it began");
    assert!(second.gestures.lock().unwrap().is_empty());
}

/// A voice count asked for before is asked for again once the plugin has run with another: asked
/// for 48 against an activation with 32 and restarted with it, brought back to 32 with the
/// editor away (a host's undo, restarted by the plugin itself), then set to 48 again, the editor
/// asks a second time rather than leave the slider at 48 over a pool of 32.
#[test]
fn a_voice_count_asked_for_before_is_asked_for_again_after_the_plugin_ran_with_another() {
    let shared = Arc::new(Shared::default());
    let host = Arc::new(Host::default());
    let params = Arc::new(QsaParams::default());
    let mut app = EditorApp::new(params.clone(), shared.clone());
    app.gui = Some(GuiContext::new(host.clone()));
    let ctx = egui::Context::default();
    let screen = Some(Rect::from_min_size(Pos2::ZERO, vec2(1000.0, 775.0)));
    let mut time = 0.0;
    let mut frames = |n: usize, app: &mut EditorApp| {
        for _ in 0..n {
            time += 0.05;
            let input = RawInput { screen_rect: screen, time: Some(time), ..RawInput::default() };
            ctx.run_ui(input, |ui| app.show(ui)).textures_delta.clear();
        }
        host.restarts.load(std::sync::atomic::Ordering::Relaxed)
    };
    #[allow(unsafe_code)] // nice-plug's type-erased parameter calls are `unsafe`; see SAFETY.
    let voices = |n: i32| {
        let voices = &params.engine.voices;
        // SAFETY: the pointer comes from `params`, alive here.
        unsafe { voices.as_ptr()._internal_set_normalized_value(voices.preview_normalized(n)) };
    };
    shared.voices.store(32, std::sync::atomic::Ordering::Relaxed);
    voices(48);
    assert_eq!(frames(10, &mut app), 1, "48 asked for");
    shared.voices.store(48, std::sync::atomic::Ordering::Relaxed);
    assert_eq!(frames(10, &mut app), 1, "restarted with 48");
    voices(32);
    shared.voices.store(32, std::sync::atomic::Ordering::Relaxed);
    assert_eq!(frames(1, &mut app), 1, "back to 32, restarted without the editor");
    voices(48);
    assert_eq!(frames(10, &mut app), 2, "48 asked for again");
}

/// The peak load shown is the largest of the last 1.5 s: 90 % at 0 s, 80 % at 1.0 s and 10 % at
/// 1.6 s show 90 %, 90 % and then 80 % (taken 0.6 s before), until 2.5 s, when 10 % is the
/// largest left.
#[test]
fn a_peak_hold_that_expires_shows_the_largest_peak_of_its_window() {
    let shared = Arc::new(Shared::default());
    let mut app = EditorApp::new(Arc::new(QsaParams::default()), shared.clone());
    let ctx = egui::Context::default();
    let screen = Some(Rect::from_min_size(Pos2::ZERO, vec2(1000.0, 775.0)));
    let mut shown = |time: f64, peak: f32| {
        shared.peak.store(peak, std::sync::atomic::Ordering::Relaxed);
        let input = RawInput { screen_rect: screen, time: Some(time), ..RawInput::default() };
        ctx.run_ui(input, |ui| app.show(ui)).textures_delta.clear();
        app.peak_hold.front().map(|&(_, p)| p)
    };
    assert_eq!(shown(0.0, 0.9), Some(0.9));
    assert_eq!(shown(1.0, 0.8), Some(0.9));
    assert_eq!(shown(1.6, 0.1), Some(0.8));
    assert_eq!(shown(2.4, 0.0), Some(0.8));
    assert_eq!(shown(2.6, 0.0), Some(0.1));
}
