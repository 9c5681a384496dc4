//! The preset section of the editor (first column, under Output): the factory presets in a menu
//! grouped by category, previous and next buttons, and the current preset's description.
//!
//! Choosing a preset sets every parameter it sets ([`Preset::sets`]: all but the player's
//! settings, voices, the overload guard and the half-pedal range, that its file leaves out) as
//! the host's own gestures (begin, set, end for each parameter, found by id in the parameter
//! map), so hosts record it as automation and undo. The chosen preset's id is kept in [`QsaParams::preset`], a persistent
//! field, so it comes back with the saved state; the name is marked " *" once a parameter the
//! preset sets differs from it.

use egui::{Id, Label, RichText, Ui};
use nice_plug::prelude::{GuiContextInner, ParamSetter, Params};
use qsa_dsp::instrument::{CATEGORIES, Preset, factory_presets, plain_values_differ};

use crate::params::QsaParams;

/// How long after choosing a preset the " *" mark waits (s): the host applies the parameter
/// changes asynchronously (CLAP at its next flush or process call).
const SETTLE: f64 = 0.5;

/// Width of the preset menu (logical pixels).
const MENU_WIDTH: f32 = 200.0;

/// The egui memory key holding when a preset was last applied.
fn applied_key() -> Id {
    Id::unique("qsa-preset-applied")
}

/// The index in [`factory_presets`] of the preset `id` names.
pub fn index_of(id: &str) -> Option<usize> {
    factory_presets().iter().position(|p| p.id == id)
}

/// The preset `step` places after `current` (before, when negative), wrapping around; from no
/// preset, forward starts at the first and backward at the last.
pub fn step(current: Option<usize>, step: isize, count: usize) -> usize {
    let count = count.max(1) as isize;
    let start = match current {
        Some(i) => i as isize,
        None if step > 0 => -1,
        None => count,
    };
    (start + step).rem_euclid(count) as usize
}

/// The preset section: its heading, ◀, the menu (grouped by category), ▶, and the current
/// preset's category and description.
pub fn section(ui: &mut Ui, params: &QsaParams, setter: &ParamSetter) {
    let presets = factory_presets();
    let current_id = params.preset.read().map(|id| id.clone()).unwrap_or_default();
    let current = index_of(&current_id);
    let now = ui.input(|i| i.time);
    let applied = ui.ctx().data(|d| d.get_temp::<f64>(applied_key())).unwrap_or(f64::NEG_INFINITY);
    let mut choice = None;
    ui.label(RichText::new("Preset").size(16.0).strong());
    ui.horizontal(|ui| {
        if ui.button("<").on_hover_text("Previous preset").clicked() {
            choice = Some(step(current, -1, presets.len()));
        }
        let shown = match current {
            Some(i) if now - applied > SETTLE && modified(params, &presets[i]) => format!("{} *", presets[i].name),
            Some(i) => presets[i].name.clone(),
            None => "(none)".to_owned(),
        };
        egui::ComboBox::from_id_salt("qsa-preset").selected_text(shown).width(MENU_WIDTH).height(600.0).show_ui(
            ui,
            |ui| {
                for category in CATEGORIES {
                    ui.label(RichText::new(category).small().strong());
                    for (i, p) in presets.iter().enumerate().filter(|(_, p)| p.category == category) {
                        let item = ui.selectable_label(current == Some(i), format!("  {}", p.name));
                        if item.on_hover_text(&p.description).clicked() {
                            choice = Some(i);
                        }
                    }
                }
            },
        );
        if ui.button(">").on_hover_text("Next preset").clicked() {
            choice = Some(step(current, 1, presets.len()));
        }
    });
    let about = match current {
        Some(i) => format!("{}: {}", presets[i].category, presets[i].description),
        None => "Factory presets set every parameter but the player's settings (voices, overload guard, \
         half-pedal range); the menu lists them by category."
            .to_owned(),
    };
    // A little narrower than the column: a wrapped line's glyphs may overhang its width.
    ui.scope(|ui| {
        ui.set_max_width(ui.available_width() - 4.0);
        ui.add(Label::new(RichText::new(about).small().weak()).wrap());
    });
    if let Some(preset) = choice.and_then(|i| presets.get(i)) {
        apply(params, setter, preset);
        ui.ctx().data_mut(|d| d.insert_temp(applied_key(), now));
    }
}

/// Whether a parameter `preset` sets differs from it by more than the host's normalisation can
/// explain.
pub fn modified(params: &QsaParams, preset: &Preset) -> bool {
    preset.first_difference(&params.values()).is_some()
}

/// Set every parameter `preset` sets to its value, each as one host gesture (begin, set, end),
/// and remember the preset's id. A parameter at the preset's value already (within the tolerance
/// that marks a preset modified) is left alone: the host records no automation or undo step for
/// it. (A value the editor sent the host a moment ago, which has not come back yet, counts as
/// not sent: the parameter is compared as it stands.)
pub fn apply(params: &QsaParams, setter: &ParamSetter, preset: &Preset) {
    let now = params.values();
    for (id, param, _) in params.param_map() {
        if let Some(plain) = preset.values.plain(&id).filter(|_| preset.sets(&id))
            && now.plain(&id).is_none_or(|current| plain_values_differ(current, plain))
        {
            set_plain(setter.raw_context, param, plain);
        }
    }
    if let Ok(mut id) = params.preset.write() {
        id.clone_from(&preset.id);
    }
}

/// One gesture setting the parameter `param` to the plain value `plain` (choices by index,
/// switches 0 or 1), as `ParamSetter`'s typed methods do.
#[allow(unsafe_code)] // nice-plug's type-erased parameter calls are `unsafe`; see SAFETY.
fn set_plain(context: &dyn GuiContextInner, param: nice_plug::prelude::ParamPtr, plain: f32) {
    // SAFETY: `param` comes from the parameter map of the `QsaParams` the editor holds in an
    // `Arc` for the whole call, so it points at a live parameter; the calls are made from the GUI
    // thread, as `ParamSetter::set_parameter` makes them.
    unsafe {
        let normalized = param.preview_normalized(plain);
        context.raw_begin_set_parameter(param);
        context.raw_set_parameter_normalized(param, normalized);
        context.raw_end_set_parameter(param);
    }
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;
    use std::sync::{Arc, Mutex};

    use egui::{MissingGlyphPolicy, RawInput};
    use nice_plug::prelude::{ParamPtr, PluginApi, PluginState};
    use qsa_dsp::instrument::{PLAYER_SETTINGS, find_preset};

    use super::*;

    /// A host that records the editor's parameter calls and applies the values at once, as a host
    /// does after its flush.
    #[derive(Default)]
    struct RecordingHost {
        calls: Mutex<Vec<(&'static str, ParamPtr, f32)>>,
    }

    #[allow(unsafe_code)]
    impl GuiContextInner for RecordingHost {
        fn plugin_api(&self) -> PluginApi {
            PluginApi::Clap
        }

        unsafe fn raw_begin_set_parameter(&self, param: ParamPtr) {
            self.calls.lock().unwrap().push(("begin", param, f32::NAN));
        }

        unsafe fn raw_set_parameter_normalized(&self, param: ParamPtr, normalized: f32) {
            self.calls.lock().unwrap().push(("set", param, normalized));
            // SAFETY: the test's parameters outlive the call.
            unsafe { param._internal_set_normalized_value(normalized) };
        }

        unsafe fn raw_end_set_parameter(&self, param: ParamPtr) {
            self.calls.lock().unwrap().push(("end", param, f32::NAN));
        }

        fn get_state(&self) -> PluginState {
            PluginState { version: String::new(), params: BTreeMap::new(), fields: BTreeMap::new() }
        }

        fn set_state(&self, _: PluginState) {}

        fn request_restart(&self) {}
    }

    /// Choosing a preset sets every parameter but the player's settings that is not at the
    /// preset's value already, each in its own begin–set–end gesture, to the preset's value
    /// (after the host's normalisation, within `first_difference`'s tolerance), and the chosen id
    /// is kept; choosing it again sends nothing; changing a parameter afterwards marks the preset
    /// modified.
    #[test]
    #[allow(unsafe_code)] // nice-plug's type-erased parameter calls are `unsafe`; see SAFETY.
    fn choosing_a_preset_sets_every_parameter_it_changes_in_one_gesture_each() {
        for preset in factory_presets() {
            let params = Arc::new(QsaParams::default());
            let map: Vec<_> =
                params.param_map().into_iter().filter(|(id, ..)| !PLAYER_SETTINGS.contains(&id.as_str())).collect();
            // SAFETY: the pointers come from the parameter map of `params`, alive to the end.
            let at = |param: &ParamPtr| unsafe { param.unmodulated_normalized_value() };
            let before: Vec<f32> = map.iter().map(|(_, param, _)| at(param)).collect();
            let host = RecordingHost::default();
            apply(&params, &ParamSetter::new(&host), preset);
            let changed: Vec<_> = (map.iter().zip(&before))
                .filter(|((_, param, _), was)| at(param) != **was)
                .map(|((_, param, _), _)| *param)
                .collect();
            // The default preset changes nothing on a fresh instance; no preset changes everything.
            assert!(changed.len() < map.len(), "{}: {} changed", preset.id, changed.len());
            assert_eq!(changed.is_empty(), preset.id == "fig5-hammer", "{}: {} changed", preset.id, changed.len());
            let calls = host.calls.lock().unwrap().clone();
            assert_eq!(calls.len(), 3 * changed.len(), "{}: three calls per parameter it changes", preset.id);
            for (k, chunk) in calls.chunks(3).enumerate() {
                let kinds: Vec<&str> = chunk.iter().map(|c| c.0).collect();
                assert_eq!(kinds, ["begin", "set", "end"], "{}: gesture {k}", preset.id);
                assert!(chunk.iter().all(|c| c.1 == changed[k]), "{}: one parameter per gesture", preset.id);
            }
            let got = params.values();
            assert_eq!(got.first_difference(&preset.values), None, "{}: {got:?}", preset.id);
            assert!(!modified(&params, preset), "{} is not modified right after choosing it", preset.id);
            assert_eq!(*params.preset.read().unwrap(), preset.id);
            let again = RecordingHost::default();
            apply(&params, &ParamSetter::new(&again), preset);
            assert_eq!(again.calls.lock().unwrap().len(), 0, "{}: chosen again, nothing to send", preset.id);
        }
        let params = Arc::new(QsaParams::default());
        let host = RecordingHost::default();
        let setter = ParamSetter::new(&host);
        let preset = find_preset("lap-steel").unwrap();
        apply(&params, &setter, preset);
        setter.set_parameter(&params.slide.alpha, 2.5);
        assert!(modified(&params, preset), "a changed exponent marks the preset modified");
        assert_eq!(params.values().first_difference(&preset.values), Some("alpha"));
    }

    /// The player's voice count and overload guard stay as they were set through every factory
    /// preset (none names them), without marking it modified, and changing them afterwards does
    /// not mark it either; a preset whose file names them sets them like any other parameter.
    #[test]
    fn presets_leave_the_players_settings_unless_they_name_them() {
        let params = Arc::new(QsaParams::default());
        let host = RecordingHost::default();
        let setter = ParamSetter::new(&host);
        setter.set_parameter(&params.engine.voices, 48);
        setter.set_parameter(&params.engine.overload_guard, false);
        for preset in factory_presets() {
            apply(&params, &setter, preset);
            assert_eq!(params.engine.voices.value(), 48, "{}: voices kept", preset.id);
            assert!(!params.engine.overload_guard.value(), "{}: guard kept off", preset.id);
            assert!(!modified(&params, preset), "{}: the player's settings do not mark it modified", preset.id);
        }
        setter.set_parameter(&params.engine.voices, 96);
        assert!(!modified(&params, factory_presets().last().unwrap()), "changing the voices afterwards");

        let text =
            "name = \"Big\"\ncategory = \"Piano\"\ndescription = \"Names its voices.\"\n[params]\nvoices = 128\n";
        let naming = qsa_dsp::instrument::parse_preset("big", text).unwrap();
        apply(&params, &setter, &naming);
        assert_eq!(params.engine.voices.value(), 128, "a preset naming the voices sets them");
        assert!(!params.engine.overload_guard.value(), "and still leaves the guard it does not name");
        setter.set_parameter(&params.engine.voices, 64);
        assert_eq!(naming.first_difference(&params.values()), Some("voices"), "and marks them modified");
    }

    #[test]
    fn previous_and_next_wrap_around_the_list() {
        assert_eq!(step(Some(0), -1, 20), 19);
        assert_eq!(step(Some(19), 1, 20), 0);
        assert_eq!(step(Some(4), 1, 20), 5);
        assert_eq!(step(None, 1, 20), 0);
        assert_eq!(step(None, -1, 20), 19);
        assert_eq!(index_of("lap-steel").map(|i| factory_presets()[i].id.as_str()), Some("lap-steel"));
        assert_eq!(index_of("nothing"), None);
    }

    /// The whole editor, drawn headless in its default window with each preset chosen: the
    /// preset section (heading, menu, wrapped description) stays inside the first column and
    /// above the tallest column's end, so it adds no height, and no text overlaps another.
    #[test]
    fn the_preset_section_fits_the_first_column_with_every_preset() {
        use egui::{Pos2, Rect, vec2};

        use crate::editor::SIZE;

        let window = Rect::from_min_size(Pos2::ZERO, vec2(SIZE.0 as f32, SIZE.1 as f32));
        for preset in factory_presets() {
            let (texts, _) = crate::editor::tests::draw(&[], &preset.id, window.size());
            let about = format!("{}: ", preset.category);
            // The name, marked " *" where the default parameters differ from the preset's.
            let named = |t: &str| t.strip_suffix(" *").unwrap_or(t) == preset.name;
            let ours = |t: &str| t == "Preset" || named(t) || t.starts_with(&about);
            let section = texts.iter().filter(|(t, _)| ours(t)).fold(Rect::NOTHING, |r, (_, b)| r.union(*b));
            let rest = texts.iter().filter(|(t, _)| !ours(t)).fold(Rect::NOTHING, |r, (_, b)| r.union(*b));
            assert!(texts.iter().any(|(t, _)| named(t)), "{}: its name is in the menu", preset.id);
            let column = window.width() / 3.0;
            assert!(section.max.x < column, "{}: the section reaches x = {}", preset.id, section.max.x);
            assert!(section.max.y < rest.max.y, "{}: the section ends at y = {}", preset.id, section.max.y);
            for (i, (a, ra)) in texts.iter().enumerate() {
                for (b, rb) in &texts[i + 1..] {
                    assert!(!ra.shrink(0.5).intersects(rb.shrink(0.5)), "{}: {a:?} overlaps {b:?}", preset.id);
                }
            }
        }
    }

    /// Every preset's name and description draws with egui's default fonts (no missing-glyph
    /// boxes for κ, α, η, ×, ≈ and the like).
    #[test]
    fn preset_texts_have_every_glyph_in_the_default_fonts() {
        let ctx = egui::Context::default();
        ctx.set_missing_glyph_policy(MissingGlyphPolicy::Panic);
        let mut output = ctx.run_ui(RawInput::default(), |ui| {
            for p in factory_presets() {
                ui.label(format!("{} * ({}): {}", p.name, p.category, p.description));
            }
            ui.label("Preset < > (none) Factory presets set every parameter; the menu lists them by category.");
        });
        // Nothing is drawn, so the font atlas's updates are dropped (cleared, as epaint requires).
        output.textures_delta.clear();
    }
}
