//! A parameter's slider with its value beside it, each change it makes inside a gesture of the
//! host's.
//!
//! A host records automation, and keeps undo steps, between a parameter's begin and end of a
//! gesture: a change outside one is not recorded as the user's, and a gesture left open keeps the
//! parameter "touched", its automation overwritten, until the session ends. So every gesture the
//! slider begins it ends, whatever the pointer did:
//!
//! - pressing the bar with the primary button begins one, and letting go (after a drag, a click
//!   that moved too little to count as a drag, or a press carried off the bar) ends it; a press
//!   and release within one frame is a gesture of its own; the other buttons change nothing;
//! - the value follows the pointer across the bar, or with Shift held moves finely with the
//!   pointer's travel ([`FINE`] of the range per point), and Ctrl or Cmd puts it at the default, as
//!   does a double-click;
//! - a value typed into the field that a click on the value opens is set in one gesture of its
//!   own when Enter is pressed (Escape, or clicking elsewhere, leaves it unset).
//!
//! The gestures under way are kept by parameter in the editor's [`Gestures`], not in egui's
//! memory, so one slider's gesture never ends or begins another's, and those still open when the
//! window closed (on a drag) are ended when it opens again.

use std::cell::RefCell;

use egui::emath::GuiRounding;
use egui::{Id, Key, Response, Sense, Stroke, StrokeKind, TextEdit, TextStyle, Ui, Widget, vec2};
use nice_plug::prelude::{Param, ParamPtr, ParamSetter};

/// Change of the normalized value per logical point of pointer travel with Shift held.
const FINE: f32 = 0.0015;

/// A parameter's slider and value (see the module docs).
#[must_use = "a slider is shown by `ui.add`"]
pub struct Slider<'a, P: Param> {
    param: &'a P,
    setter: &'a ParamSetter<'a>,
    gestures: &'a Gestures,
    /// Width of the bar (logical points).
    width: f32,
}

/// The gestures the editor's sliders have begun and not ended yet, by parameter.
#[derive(Debug, Default)]
pub struct Gestures(RefCell<Vec<(ParamPtr, Gesture)>>);

impl Gestures {
    /// Whether a gesture of `param` is under way.
    pub fn holds(&self, param: &impl Param) -> bool {
        self.get(param.as_ptr()).is_some()
    }

    fn get(&self, param: ParamPtr) -> Option<Gesture> {
        self.0.borrow().iter().find(|(p, _)| *p == param).map(|(_, g)| *g)
    }

    fn begin(&self, setter: &ParamSetter, param: &impl Param) -> Gesture {
        setter.begin_set_parameter(param);
        let gesture = Gesture::default();
        self.0.borrow_mut().push((param.as_ptr(), gesture));
        gesture
    }

    fn keep(&self, param: ParamPtr, gesture: Gesture) {
        if let Some(slot) = self.0.borrow_mut().iter_mut().find(|(p, _)| *p == param) {
            slot.1 = gesture;
        }
    }

    fn end(&self, setter: &ParamSetter, param: &impl Param) {
        setter.end_set_parameter(param);
        self.0.borrow_mut().retain(|(p, _)| *p != param.as_ptr());
    }

    /// End every gesture still open (the window closed in the middle of a drag).
    #[allow(unsafe_code)] // nice-plug's type-erased parameter calls are `unsafe`; see SAFETY.
    pub fn end_all(&self, setter: &ParamSetter) {
        for (param, _) in self.0.take() {
            // SAFETY: `param` was taken from a parameter of the `QsaParams` the editor holds for
            // its whole life, so it points at a live parameter; the call is made from the GUI
            // thread, as `ParamSetter::end_set_parameter` makes it.
            unsafe { setter.raw_context.raw_end_set_parameter(param) };
        }
    }
}

/// A gesture under way: what the slider remembers between frames while its bar is held.
#[derive(Clone, Copy, Debug, Default)]
pub struct Gesture {
    /// The normalized value last sent to the host in this gesture, if any: the parameter's own
    /// lags it until the host has taken the change.
    sent: Option<f32>,
    /// A fine (Shift) drag: the normalized value it began from and the points travelled since.
    fine: Option<(f32, f32)>,
}

impl<'a, P: Param> Slider<'a, P> {
    /// A slider `width` logical points wide for `param`, whose changes go through `setter` in
    /// gestures kept in `gestures`.
    pub fn new(param: &'a P, setter: &'a ParamSetter<'a>, gestures: &'a Gestures, width: f32) -> Self {
        Self { param, setter, gestures, width }
    }

    /// Send `normalized` (0..=1, snapped to the parameter's steps) in the gesture `gesture`,
    /// unless the gesture sent it last. A gesture's first value is always sent: the parameter's
    /// own value may not show yet what the host was sent before.
    fn send(&self, gesture: &mut Gesture, normalized: f32) {
        let snapped = self.param.preview_normalized(self.param.preview_plain(normalized.clamp(0.0, 1.0)));
        if gesture.sent != Some(snapped) {
            gesture.sent = Some(snapped);
            self.setter.set_parameter_normalized(self.param, snapped);
        }
    }

    /// The value a held bar asks for this frame, given the gesture so far.
    fn held(&self, ui: &Ui, bar: &Response, gesture: &mut Gesture) -> Option<f32> {
        let modifiers = ui.input(|i| i.modifiers);
        if modifiers.command {
            gesture.fine = None;
            return Some(self.param.default_normalized_value());
        }
        if modifiers.shift {
            let from = gesture.sent.unwrap_or_else(|| self.param.unmodulated_normalized_value());
            let (start, travelled) = gesture.fine.get_or_insert((from, 0.0));
            *travelled += bar.drag_delta().x;
            return Some(*start + *travelled * FINE);
        }
        gesture.fine = None;
        let x = bar.interact_pointer_pos()?.x;
        Some((x - bar.rect.left()) / bar.rect.width().max(1.0))
    }

    /// Handle the bar's input: begin, change and end gestures.
    fn interact(&self, ui: &Ui, bar: &Response) {
        let ptr = self.param.as_ptr();
        let ongoing = self.gestures.get(ptr);
        if bar.is_pointer_button_down_on() && ui.input(|i| i.pointer.primary_down()) {
            let mut gesture = ongoing.unwrap_or_else(|| self.gestures.begin(self.setter, self.param));
            if let Some(normalized) = self.held(ui, bar, &mut gesture) {
                self.send(&mut gesture, normalized);
            }
            self.gestures.keep(ptr, gesture);
            return;
        }
        // Let go; or pressed and let go within this frame (a click, or the second of a
        // double-click), which no frame saw held.
        let primary = bar.clicked_by(egui::PointerButton::Primary) && bar.interact_pointer_pos().is_some();
        let (reset, tapped) = (bar.double_clicked(), primary && ongoing.is_none());
        if ongoing.is_none() && !reset && !tapped {
            return;
        }
        let mut gesture = ongoing.unwrap_or_else(|| self.gestures.begin(self.setter, self.param));
        if reset {
            self.send(&mut gesture, self.param.default_normalized_value());
        } else if tapped && let Some(normalized) = self.held(ui, bar, &mut gesture) {
            self.send(&mut gesture, normalized);
        }
        self.gestures.end(self.setter, self.param);
    }

    /// Draw the bar: the range's background, the part up to the value filled, a frame.
    fn paint_bar(&self, ui: &Ui, bar: &Response) {
        if !ui.is_rect_visible(bar.rect) {
            return;
        }
        let visuals = ui.visuals();
        let painter = ui.painter();
        painter.rect_filled(bar.rect, 0.0, visuals.widgets.inactive.bg_fill);
        let share = self.param.modulated_normalized_value().clamp(0.0, 1.0);
        if share > 0.0 {
            let mut filled = bar.rect;
            filled.set_width(bar.rect.width() * share);
            let fill =
                if bar.hovered() { visuals.selection.bg_fill.gamma_multiply(1.3) } else { visuals.selection.bg_fill };
            painter.rect_filled(filled, 0.0, fill);
        }
        painter.rect_stroke(bar.rect, 0.0, Stroke::new(1.0, visuals.widgets.active.bg_fill), StrokeKind::Middle);
    }

    /// The value as text, or the field it is typed into once the value was clicked.
    fn value(&self, ui: &mut Ui, field: Id) {
        if ui.memory(|m| m.has_focus(field)) {
            let mut text: String = ui.data(|d| d.get_temp(field)).unwrap_or_default();
            ui.add(TextEdit::singleline(&mut text).id(field).font(TextStyle::Monospace).desired_width(self.width));
            let (enter, escape) = ui.input(|i| (i.key_pressed(Key::Enter), i.key_pressed(Key::Escape)));
            let held = self.gestures.holds(self.param);
            if enter
                && !held
                && let Some(normalized) = self.param.string_to_normalized_value(&text)
            {
                self.setter.begin_set_parameter(self.param);
                self.send(&mut Gesture::default(), normalized);
                self.setter.end_set_parameter(self.param);
            }
            if enter || escape {
                ui.memory_mut(|m| m.surrender_focus(field));
            }
            ui.data_mut(|d| d.insert_temp(field, text));
            return;
        }
        if ui.button(self.param.to_string()).clicked() {
            ui.data_mut(|d| d.insert_temp(field, self.param.to_string()));
            ui.memory_mut(|m| m.request_focus(field));
        }
    }
}

impl<P: Param> Widget for Slider<'_, P> {
    fn ui(self, ui: &mut Ui) -> Response {
        ui.horizontal(|ui| {
            // The bar a little slimmer than a row, centred in it.
            let row = ui.text_style_height(&TextStyle::Body).max(ui.spacing().interact_size.y * 0.8);
            let height = (row * 0.8).round_to_pixels(ui.painter().pixels_per_point());
            let (space, _) = ui.allocate_exact_size(vec2(self.width, row), Sense::hover());
            let rect = egui::Rect::from_center_size(space.center(), vec2(self.width, height));
            let bar = ui.interact(rect, ui.make_persistent_id(self.param.name()), Sense::click_and_drag());
            self.interact(ui, &bar);
            self.paint_bar(ui, &bar);
            self.value(ui, bar.id.with("typed"));
            bar
        })
        .inner
    }
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;
    use std::sync::{Arc, Mutex};

    use egui::{Event, Modifiers, PointerButton, Pos2, RawInput, Rect, pos2};
    use nice_plug::context::gui::{GuiContext, GuiContextInner};
    use nice_plug::prelude::{BoolParam, FloatParam, FloatRange, ParamPtr, PluginApi, PluginState};

    use super::*;

    /// What the editor asked of the host, in order.
    #[derive(Clone, Copy, Debug, PartialEq)]
    enum Asked {
        Begin(ParamPtr),
        Set(ParamPtr, f32),
        End(ParamPtr),
    }

    /// A host that records what it is asked and changes nothing (a real one applies the values
    /// later, at its next flush).
    #[derive(Default)]
    struct Recorder(Mutex<Vec<Asked>>);

    // nice-plug declares the parameter callbacks `unsafe`; these only record their arguments.
    #[allow(unsafe_code)]
    impl GuiContextInner for Recorder {
        fn plugin_api(&self) -> PluginApi {
            PluginApi::Clap
        }

        unsafe fn raw_begin_set_parameter(&self, param: ParamPtr) {
            self.0.lock().unwrap().push(Asked::Begin(param));
        }

        unsafe fn raw_set_parameter_normalized(&self, param: ParamPtr, normalized: f32) {
            self.0.lock().unwrap().push(Asked::Set(param, normalized));
        }

        unsafe fn raw_end_set_parameter(&self, param: ParamPtr) {
            self.0.lock().unwrap().push(Asked::End(param));
        }

        fn get_state(&self) -> PluginState {
            PluginState { version: String::new(), params: BTreeMap::new(), fields: BTreeMap::new() }
        }

        fn set_state(&self, _: PluginState) {}

        fn request_restart(&self) {}
    }

    /// Two sliders, a gain and a switch, drawn frame by frame with the input a user gives them.
    struct Bench {
        ctx: egui::Context,
        host: Arc<Recorder>,
        gui: GuiContext,
        gain: FloatParam,
        switch: BoolParam,
        gestures: Gestures,
        time: f64,
        /// Where each slider's bar and value were drawn: gain, switch.
        bars: [Rect; 2],
        values: [Rect; 2],
    }

    impl Bench {
        fn new() -> Self {
            let host = Arc::new(Recorder::default());
            let mut bench = Self {
                ctx: egui::Context::default(),
                gui: GuiContext::new(host.clone()),
                host,
                gain: FloatParam::new("Gain", 0.0, FloatRange::Linear { min: -36.0, max: 12.0 }),
                switch: BoolParam::new("Switch", true),
                gestures: Gestures::default(),
                time: 0.0,
                bars: [Rect::NOTHING; 2],
                values: [Rect::NOTHING; 2],
            };
            bench.frame(vec![], Modifiers::NONE);
            bench.frame(vec![], Modifiers::NONE);
            bench
        }

        /// One frame, 50 ms after the last, with `events` and `modifiers` held.
        fn frame(&mut self, events: Vec<Event>, modifiers: Modifiers) {
            self.time += 0.05;
            let screen = Rect::from_min_size(Pos2::ZERO, vec2(400.0, 200.0));
            let events = [Event::ModifiersChanged(modifiers)].into_iter().chain(events).collect();
            let input = RawInput { screen_rect: Some(screen), time: Some(self.time), events, ..Default::default() };
            let setter = self.gui.param_setter();
            let (gain, switch, gestures) = (&self.gain, &self.switch, &self.gestures);
            let mut bars = [Rect::NOTHING; 2];
            let mut values = [Rect::NOTHING; 2];
            let mut output = self.ctx.run_ui(input, |ui| {
                egui::CentralPanel::default().show(ui, |ui| {
                    for (k, response) in [
                        ui.add(Slider::new(gain, &setter, gestures, 100.0)),
                        ui.add(Slider::new(switch, &setter, gestures, 100.0)),
                    ]
                    .into_iter()
                    .enumerate()
                    {
                        // The value's button follows the bar after the spacing between items.
                        let bar = response.rect;
                        let left = bar.right() + ui.spacing().item_spacing.x;
                        bars[k] = bar;
                        values[k] = Rect::from_min_max(pos2(left, bar.top()), pos2(left + 20.0, bar.bottom()));
                    }
                });
            });
            output.textures_delta.clear();
            (self.bars, self.values) = (bars, values);
        }

        fn press(&mut self, at: Pos2, pressed: bool, modifiers: Modifiers) {
            let button = Event::PointerButton { pos: at, button: PointerButton::Primary, pressed, modifiers };
            self.frame(vec![Event::PointerMoved(at), button], modifiers);
        }

        /// A second later, as a new action rather than the next click of the last: press at
        /// `from`, move to each of `path`, let go at the last, with `modifiers` held.
        fn drag(&mut self, from: Pos2, path: &[Pos2], modifiers: Modifiers) {
            self.time += 1.0;
            self.press(from, true, modifiers);
            for &at in path {
                self.frame(vec![Event::PointerMoved(at)], modifiers);
            }
            self.press(*path.last().unwrap_or(&from), false, modifiers);
            self.frame(vec![], Modifiers::NONE);
        }

        /// A click at `at`: pressed and let go in consecutive frames, without moving.
        fn click(&mut self, at: Pos2, modifiers: Modifiers) {
            self.drag(at, &[], modifiers);
        }

        fn asked(&self) -> Vec<Asked> {
            std::mem::take(&mut *self.host.0.lock().unwrap())
        }
    }

    /// The gestures in `asked`: each as its parameter and the values set in it. Panics unless
    /// each change lies inside a gesture of its own parameter and every gesture begun has ended.
    fn gestures(asked: &[Asked]) -> Vec<(ParamPtr, Vec<f32>)> {
        let mut done = Vec::new();
        let mut open: Option<(ParamPtr, Vec<f32>)> = None;
        for &a in asked {
            match (a, &mut open) {
                (Asked::Begin(p), None) => open = Some((p, Vec::new())),
                (Asked::Set(p, v), Some((q, values))) if p == *q => values.push(v),
                (Asked::End(p), Some((q, _))) if p == *q => done.extend(open.take()),
                _ => panic!("{a:?} with {open:?} open, in {asked:?}"),
            }
        }
        assert!(open.is_none(), "a gesture was left open: {asked:?}");
        done
    }

    /// A click on a switch, a drag on the gain after it, a click on the gain's bar, a
    /// double-click and a Ctrl-click (each to the default), a Shift drag and a typed value: each
    /// is exactly one gesture of its own parameter (two for the double-click's two presses), each
    /// closed, its values where the pointer or the text put them. egui does not call a click
    /// that moves too little a drag: a gesture ended only at a drag's end would stay open, and
    /// the next slider's changes would come outside any gesture.
    #[test]
    fn every_change_lies_in_one_closed_gesture_of_its_own_parameter() {
        let mut bench = Bench::new();
        let (gain, switch) = (bench.gain.as_ptr(), bench.switch.as_ptr());
        let [gain_bar, switch_bar] = bench.bars;
        let at = |bar: Rect, share: f32| pos2(bar.left() + share * bar.width(), bar.center().y);

        bench.click(at(switch_bar, 0.1), Modifiers::NONE);
        assert_eq!(gestures(&bench.asked()), [(switch, vec![0.0])], "a click on the switch's off side");

        let path = [at(gain_bar, 0.4), at(gain_bar, 0.6), at(gain_bar, 1.3)];
        bench.drag(at(gain_bar, 0.2), &path, Modifiers::NONE);
        let dragged = gestures(&bench.asked());
        assert_eq!(dragged.len(), 1);
        assert_eq!(dragged[0].0, gain);
        let expected = [0.2, 0.4, 0.6, 1.0];
        assert_eq!(dragged[0].1.len(), expected.len(), "{dragged:?}");
        for (v, e) in dragged[0].1.iter().zip(expected) {
            assert!((v - e).abs() < 0.01, "dragged to {v}, not {e}");
        }

        bench.click(at(gain_bar, 0.25), Modifiers::NONE);
        let clicked = gestures(&bench.asked());
        assert_eq!(clicked.len(), 1);
        assert!((clicked[0].1[0] - 0.25).abs() < 0.01, "{clicked:?}");

        let default = bench.gain.default_normalized_value();
        let press = |bench: &mut Bench, pressed| bench.press(at(gain_bar, 0.1), pressed, Modifiers::NONE);
        bench.time += 1.0;
        press(&mut bench, true);
        press(&mut bench, false);
        press(&mut bench, true);
        press(&mut bench, false);
        let double = gestures(&bench.asked());
        assert_eq!(double.len(), 2, "{double:?}");
        assert_eq!(*double[1].1.last().unwrap(), default, "a double-click sets the default");

        bench.click(at(gain_bar, 0.9), Modifiers::COMMAND);
        let reset = gestures(&bench.asked());
        assert_eq!(reset, [(gain, vec![default])], "a Ctrl-click sets the default");

        // A fine drag of 100 points moves the value by 100 FINE from where it was (the host has
        // applied nothing, so from the parameter's own value), to the f32's rounding.
        let from = at(gain_bar, 0.5);
        bench.drag(from, &[from + vec2(40.0, 0.0), from + vec2(100.0, 0.0)], Modifiers::SHIFT);
        let fine = gestures(&bench.asked());
        assert_eq!(fine.len(), 1, "{fine:?}");
        let end = *fine[0].1.last().unwrap();
        assert!((end - (default + 100.0 * FINE)).abs() < 1e-6, "fine drag ended at {end}");

        let value = bench.values[0].center();
        bench.click(value, Modifiers::NONE);
        assert_eq!(bench.asked(), [], "opening the field changes nothing");
        let select_all =
            Event::Key { key: Key::A, physical_key: None, pressed: true, repeat: false, modifiers: Modifiers::COMMAND };
        bench.frame(vec![select_all, Event::Text("-6".into())], Modifiers::NONE);
        let enter = Event::Key {
            key: Key::Enter,
            physical_key: None,
            pressed: true,
            repeat: false,
            modifiers: Modifiers::NONE,
        };
        bench.frame(vec![enter], Modifiers::NONE);
        let typed = gestures(&bench.asked());
        assert_eq!(typed.len(), 1, "{typed:?}");
        assert_eq!(typed[0].1, [bench.gain.preview_normalized(-6.0)], "the typed value");
    }

    /// A press and release within one frame (a quick tap on a slow frame) is one gesture with
    /// the value under the pointer; a press of the secondary button changes nothing.
    #[test]
    fn a_tap_within_one_frame_is_a_gesture_and_other_buttons_change_nothing() {
        let mut bench = Bench::new();
        let gain = bench.gain.as_ptr();
        let bar = bench.bars[0];
        let at = pos2(bar.left() + 0.3 * bar.width(), bar.center().y);
        let button = |button, pressed| Event::PointerButton { pos: at, button, pressed, modifiers: Modifiers::NONE };
        bench.time += 1.0;
        let tap =
            vec![Event::PointerMoved(at), button(PointerButton::Primary, true), button(PointerButton::Primary, false)];
        bench.frame(tap, Modifiers::NONE);
        bench.frame(vec![], Modifiers::NONE);
        let tapped = gestures(&bench.asked());
        assert_eq!(tapped.len(), 1, "{tapped:?}");
        assert_eq!(tapped[0].0, gain);
        assert!((tapped[0].1[0] - 0.3).abs() < 0.01, "{tapped:?}");
        bench.time += 1.0;
        for pressed in [true, false] {
            bench.frame(vec![Event::PointerMoved(at), button(PointerButton::Secondary, pressed)], Modifiers::NONE);
        }
        bench.frame(vec![], Modifiers::NONE);
        assert_eq!(bench.asked(), [], "the secondary button");
    }

    /// A drag the window closed on is ended through its own context, and the editor opened
    /// again (a new egui context) begins its next gesture afresh.
    #[test]
    fn a_gesture_open_as_the_window_closes_is_ended() {
        let mut bench = Bench::new();
        let bar = bench.bars[0];
        let at = pos2(bar.left() + 0.6 * bar.width(), bar.center().y);
        bench.time += 1.0;
        bench.press(at, true, Modifiers::NONE);
        bench.gestures.end_all(&bench.gui.param_setter());
        assert_eq!(gestures(&bench.asked()).len(), 1, "the open drag ended");
        bench.ctx = egui::Context::default();
        bench.frame(vec![], Modifiers::NONE);
        bench.frame(vec![], Modifiers::NONE);
        bench.click(at, Modifiers::NONE);
        assert_eq!(gestures(&bench.asked()).len(), 1, "a new gesture, begun and ended");
    }
}
