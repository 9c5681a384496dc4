//! The plugin's parameters, built from the engine's parameter table
//! ([`qsa_dsp::instrument::PARAMETERS`]), which defines each once: stable short id (never changes
//! once released), name, group, range, unit, default, display, and its place in [`ParamValues`],
//! mapped to the engine's [`Settings`] by [`ParamValues::settings`].
//!
//! Hosts see them in four groups, the editor's sections (VST3 units, CLAP modules): Engine
//! (`mode` to `guard`), Piano (`hard` to `stretch`), Slide (`slide` to `sbody`) and Output
//! (`gain`, `limit`, `width`), in the order of the table. `slide` and `hand` take CLAP polyphonic
//! modulation: a per-note offset, in the parameter's units, added to the value for that note
//! alone (the sum clamped to the range), where the parameter acts (`slide` when the slide does not
//! follow keys, `hand` when `Hand height from` is Parameter).
//!
//! The table below is the parameter table's (a test checks it row by row):
//!
//! | id | name | range | default | maps to |
//! |---|---|---|---|---|
//! | `mode` | Mode | Piano, Slide | Piano | [`Settings::mode`] |
//! | `solver` | Solver | QSA, EXP, IMP | QSA | [`Settings::method`] |
//! | `segs` | QSA segments | 1..=64 | 6 | [`Settings::segments`] |
//! | `nb` | Control block | 1..=256 smp | 64 smp | [`Settings::block`] |
//! | `voices` | Voices | 1..=128 | 32 | voice pool size (at the next activation) |
//! | `guard` | Overload guard | on/off | on | the plugin's overload guard (real-time processing only; offline rendering never sheds) |
//! | `hard` | Hardness | 0.1..=10× | 1× | [`Settings::hardness`] |
//! | `hmass` | Hammer mass | 0.25..=4× | 1× | [`Settings::hammer_mass`] |
//! | `strike` | Strike position | 0.25..=2.5× | 1× | [`Settings::strike_position`] |
//! | `damp` | String damping | 0.1..=20× | 1× | [`Settings::damping`] |
//! | `bright` | Brightness | 0..=4× | 1× | [`Settings::brightness`] (inharmonicity) |
//! | `damper` | Damper | 1..=500 1/s | 60 1/s | [`Settings::damper_rate`] |
//! | `detune` | Unison detune | 0..=20 ct | 2.5 ct | [`Settings::unison_detune`] (spread of each unison, cents) |
//! | `stretch` | Octave stretch | 0..=2× | 1× | [`Settings::stretch`] (octaves tuned on the partials) |
//! | `hpfrom` | Half pedal from | 0..=100 % | 20 % | [`Settings::half_pedal_from`] (×0.01 of the sustain pedal's travel: below, the dampers rest on the strings) |
//! | `hpto` | Half pedal to | 0..=100 % | 80 % | [`Settings::half_pedal_to`] (×0.01: above, the dampers are clear of the strings) |
//! | `slide` | Slide position | 0..=24 st | 5 st | [`Settings::slide_position`] |
//! | `follow` | Slide follows key | on/off | on | [`Settings::follow_key`] |
//! | `glide` | Glide time | 1..=2000 ms | 50 ms | [`Settings::glide_time`] |
//! | `bend` | Bend range | 0..=24 st | 2 st | [`Settings::bend_range`] |
//! | `hand` | Hand height | -3..=3 mm | -1.5 mm | [`Settings::hand_height`] |
//! | `handsrc` | Hand height from | Parameter, Mod wheel, Channel pressure, Poly pressure, CC74 (timbre) | Parameter | [`Settings::hand_source`] |
//! | `smass` | Slide mass | 5..=200 g | 30 g | [`Settings::slide_mass`] |
//! | `hstiff` | Hand stiffness | 100..=1e6 N/m | 10000 N/m | [`Settings::hand_stiffness`] |
//! | `hdamp` | Hand damping | 0..=100 kg/s | 5 kg/s | [`Settings::hand_damping`] |
//! | `fdamp` | Finger damping | 0..=50 s/m | 5 s/m | [`Settings::finger_damping`] |
//! | `kappa` | Slide stiffness | 1e6..=1e13 N/m^a | 1e9 N/m^a | [`Settings::slide_kappa`] (κ) |
//! | `alpha` | Slide exponent | 1..=3 | 1.5 | [`Settings::slide_alpha`] (α) |
//! | `pluck` | Pluck position | 0.5..=0.98 | 0.9 | [`Settings::pluck_position`] (fraction of the length) |
//! | `pickup` | Pickup position | 0.5..=0.98 | 0.9 | [`Settings::pickup_position`] (fraction of the length) |
//! | `ptone` | Pickup resonance | 1000..=10000 Hz | 3500 Hz | [`Settings::pickup_resonance`] (the loaded pickup's resonance) |
//! | `sbody` | Guitar | Electric, Acoustic | Electric | [`Settings::slide_body`] (new notes) |
//! | `gain` | Output gain | -36..=12 dB | 0 dB | [`Settings::gain`] (linear) |
//! | `limit` | Safety limiter | on/off | on | [`Settings::limiter`] |
//! | `width` | Stereo width | -100..=100 % | 60 % | [`Settings::stereo_width`] (×0.01; the piano's keys panned along the bridge, the acoustic guitar body's higher modes left and right) |

use std::sync::Arc;

use nice_plug::prelude::*;
use qsa_dsp::instrument::{
    NoteParam, PARAMETERS, ParamKind, ParamSpec, ParamValues, Scale, Settings, ValueDisplay, param_index,
};

/// Instrument mode parameter (the options of `mode` in [`PARAMETERS`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Enum)]
pub enum ModeParam {
    /// Hammer–string.
    #[id = "piano"]
    Piano,
    /// Slide–string.
    #[id = "slide"]
    Slide,
}

/// Contact solver parameter (the options of `solver`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Enum)]
pub enum SolverParam {
    /// Quadratic spline approximation (non-iterative).
    #[id = "qsa"]
    #[name = "QSA"]
    Qsa,
    /// Explicit energy quadratisation.
    #[id = "exp"]
    #[name = "EXP"]
    Exp,
    /// Implicit, Newton's method.
    #[id = "imp"]
    #[name = "IMP"]
    Imp,
}

/// Hand height source parameter (the options of `handsrc`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Enum)]
pub enum HandSourceParam {
    /// The Hand height parameter.
    #[id = "param"]
    Parameter,
    /// Mod wheel (CC1).
    #[id = "modwheel"]
    #[name = "Mod wheel"]
    ModWheel,
    /// Channel pressure.
    #[id = "chanpress"]
    #[name = "Channel pressure"]
    ChannelPressure,
    /// Poly pressure.
    #[id = "polypress"]
    #[name = "Poly pressure"]
    PolyPressure,
    /// CC74, MPE's third dimension (or a note's CLAP or VST3 brightness).
    #[id = "cc74"]
    #[name = "CC74 (timbre)"]
    Timbre,
}

/// Slide guitar body parameter (the options of `sbody`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Enum)]
pub enum SlideBodyParam {
    /// The electric guitar: the string's end held, heard through a magnetic pickup.
    #[id = "electric"]
    Electric,
    /// The acoustic guitar: the string's end on its body.
    #[id = "acoustic"]
    Acoustic,
}

/// Polyphonic modulation id of `slide` (nice-plug's `with_poly_modulation_id`).
pub const POLY_SLIDE: u32 = 0;

/// Polyphonic modulation id of `hand`.
pub const POLY_HAND: u32 = 1;

/// The key under which a saved state holds the factory preset last chosen ([`QsaParams::preset`]).
pub const PRESET_FIELD: &str = "preset";

/// The polyphonic modulation id of the per-note offset `note`.
fn poly_id(note: NoteParam) -> u32 {
    match note {
        NoteParam::SlidePosition => POLY_SLIDE,
        NoteParam::HandHeight => POLY_HAND,
    }
}

/// The engine's per-note offset for a polyphonic modulation of normalized offset `normalized` of
/// the parameter with poly modulation id `id`: the setting and the offset in its unit
/// (semitones, metres). Both parameters are linear, so a normalized offset is the same plain
/// offset from any value: `normalized × span`.
pub fn poly_offset(id: u32, normalized: f32) -> Option<(NoteParam, f32)> {
    let (note, to_engine_unit) = match id {
        POLY_SLIDE => (NoteParam::SlidePosition, 1.0),
        POLY_HAND => (NoteParam::HandHeight, 1e-3),
        _ => return None,
    };
    let (min, max) = PARAMETERS.iter().find_map(|spec| match spec.kind {
        ParamKind::Float { min, max, poly: Some(p), .. } if p == note => Some((min, max)),
        _ => None,
    })?;
    Some((note, normalized * (max - min) * to_engine_unit))
}

/// A framework parameter built from its [`ParamSpec`], whose plain value it reports as
/// [`ParamSpec::get`] gives it (choices as their index, switches 0 or 1).
trait FromSpec {
    /// The parameter `spec` describes: name, range, default, unit, display, step, poly modulation,
    /// and text entry as [`ParamSpec::parse_typed`] reads it (no NaN, units optional).
    fn from_spec(spec: &'static ParamSpec) -> Self;

    /// The current plain value.
    fn plain(&self) -> f32;
}

impl FromSpec for FloatParam {
    fn from_spec(spec: &'static ParamSpec) -> Self {
        let ParamKind::Float { min, max, default, unit, scale, display, step, poly } = spec.kind else {
            panic!("{} is not a continuous parameter", spec.id)
        };
        let (range, default) = match scale {
            Scale::Linear => (FloatRange::Linear { min, max }, default),
            Scale::Skewed(exponent) => {
                (FloatRange::Skewed { min, max, factor: FloatRange::skew_factor(exponent) }, default)
            }
            Scale::Decibels => (
                FloatRange::Skewed {
                    min: util::db_to_gain(min),
                    max: util::db_to_gain(max),
                    factor: FloatRange::gain_skew_factor(min, max),
                },
                util::db_to_gain(default),
            ),
        };
        let mut param = FloatParam::new(spec.name, default, range)
            .with_unit(unit)
            .with_string_to_value(Arc::new(|text| spec.parse_typed(text).map(|shown| spec.to_plain(shown))));
        param = match (scale, display) {
            (Scale::Decibels, ValueDisplay::Rounded(digits)) => {
                param.with_value_to_string(formatters::v2s_f32_gain_to_db(digits))
            }
            (_, ValueDisplay::Rounded(digits)) => param.with_value_to_string(formatters::v2s_f32_rounded(digits)),
            (_, ValueDisplay::Scientific(digits)) => {
                param.with_value_to_string(Arc::new(move |v| format!("{v:.digits$e}")))
            }
            (_, ValueDisplay::Plain) => param,
        };
        if let Some(step) = step {
            param = param.with_step_size(step);
        }
        if let Some(note) = poly {
            param = param.with_poly_modulation_id(poly_id(note));
        }
        param
    }

    fn plain(&self) -> f32 {
        self.value()
    }
}

/// The parameters that act only when the plugin is activated: hosts offer no automation of them,
/// which would do nothing.
const AT_ACTIVATION: [&str; 1] = ["voices"];

impl FromSpec for IntParam {
    fn from_spec(spec: &'static ParamSpec) -> Self {
        let ParamKind::Int { min, max, default, unit } = spec.kind else {
            panic!("{} is not a whole-number parameter", spec.id)
        };
        let param = IntParam::new(spec.name, default, IntRange::Linear { min, max })
            .with_unit(unit)
            .with_string_to_value(Arc::new(|text| spec.parse_typed(text).map(|v| v as i32)));
        if AT_ACTIVATION.contains(&spec.id) { param.non_automatable() } else { param }
    }

    fn plain(&self) -> f32 {
        self.value() as f32
    }
}

impl FromSpec for BoolParam {
    fn from_spec(spec: &'static ParamSpec) -> Self {
        let ParamKind::Bool { default } = spec.kind else { panic!("{} is not a switch", spec.id) };
        BoolParam::new(spec.name, default)
            .with_string_to_value(Arc::new(|text| spec.parse_typed(text).map(|v| v != 0.0)))
    }

    fn plain(&self) -> f32 {
        if self.value() { 1.0 } else { 0.0 }
    }
}

impl<T: Enum + PartialEq + 'static> FromSpec for EnumParam<T> {
    fn from_spec(spec: &'static ParamSpec) -> Self {
        let ParamKind::Choice { default, .. } = spec.kind else { panic!("{} is not a choice", spec.id) };
        EnumParam::new(spec.name, T::from_index(default))
    }

    fn plain(&self) -> f32 {
        self.value().to_index() as f32
    }
}

/// A parameter group: a struct of parameters with their ids (the fields' framework attribute and
/// their [`ParamSpec`], found at compile time), built from the table and read back into
/// [`ParamValues`] through it.
macro_rules! param_group {
    ($(#[$meta:meta])* $group:ident { $($(#[$field_meta:meta])* $field:ident: $kind:ty = $id:tt,)* }) => {
        $(#[$meta])*
        #[allow(missing_debug_implementations)]
        #[derive(Params)]
        pub struct $group {
            $(
                $(#[$field_meta])*
                #[id = $id]
                pub $field: $kind,
            )*
        }

        impl Default for $group {
            fn default() -> Self {
                Self { $($field: FromSpec::from_spec(&PARAMETERS[const { param_index($id) }]),)* }
            }
        }

        impl $group {
            /// Store every parameter's plain value in `values`.
            fn read(&self, values: &mut ParamValues) {
                $((PARAMETERS[const { param_index($id) }].put)(values, self.$field.plain());)*
            }
        }
    };
}

/// All parameters, in the four groups the editor shows (VST3 units, CLAP modules: Engine, Piano,
/// Slide, Output). The groups nest without id prefixes, so the ids, the saved state and the
/// display order are those of a flat list. (No `Debug`: the framework's parameter types do not
/// implement it.)
#[allow(missing_debug_implementations)]
#[derive(Params)]
pub struct QsaParams {
    /// Mode, solver, control block, voices.
    #[nested(group = "Engine")]
    pub engine: EngineParams,
    /// The piano's relative settings.
    #[nested(group = "Piano")]
    pub piano: PianoParams,
    /// The slide guitar's settings.
    #[nested(group = "Slide")]
    pub slide: SlideParams,
    /// Gain and limiter.
    #[nested(group = "Output")]
    pub output: OutputParams,
    /// Id of the factory preset last chosen in the editor (empty: none), saved with the state
    /// under the key `preset` ([`PRESET_FIELD`]).
    #[persist = "preset"]
    pub preset: Arc<std::sync::RwLock<String>>,
}

param_group! {
    /// The Engine group.
    EngineParams {
        /// Piano or slide guitar.
        mode: EnumParam<ModeParam> = "mode",
        /// Contact solver.
        solver: EnumParam<SolverParam> = "solver",
        /// QSA segments N.
        segments: IntParam = "segs",
        /// Control block N_b (samples).
        block: IntParam = "nb",
        /// Voice pool size (takes effect at the next activation).
        voices: IntParam = "voices",
        /// Shed voices when real-time processing falls behind ([`crate::overload`]).
        overload_guard: BoolParam = "guard",
    }
}

param_group! {
    /// The Piano group (relative to the per-note rule).
    PianoParams {
        /// Felt hardness, relative.
        hardness: FloatParam = "hard",
        /// Hammer mass, relative.
        hammer_mass: FloatParam = "hmass",
        /// Striking position, relative.
        strike_position: FloatParam = "strike",
        /// String damping, relative.
        damping: FloatParam = "damp",
        /// Inharmonicity, relative.
        brightness: FloatParam = "bright",
        /// Damper decay rate (1/s).
        damper: FloatParam = "damper",
        /// Spread of each unison's tuning (cents).
        unison_detune: FloatParam = "detune",
        /// Octave stretch, relative to octaves tuned on the partials.
        stretch: FloatParam = "stretch",
        /// Where the sustain pedal's half-way zone begins (% of its travel).
        half_pedal_from: FloatParam = "hpfrom",
        /// Where it ends (% of its travel).
        half_pedal_to: FloatParam = "hpto",
    }
}

param_group! {
    /// The Slide group.
    SlideParams {
        /// Slide position (semitones).
        slide_position: FloatParam = "slide",
        /// Slide follows the played key.
        follow_key: BoolParam = "follow",
        /// Glide time (ms).
        glide: FloatParam = "glide",
        /// Pitch-bend range (semitones).
        bend_range: FloatParam = "bend",
        /// Hand height (mm).
        hand_height: FloatParam = "hand",
        /// Where the hand height comes from.
        hand_source: EnumParam<HandSourceParam> = "handsrc",
        /// Slide mass (g).
        slide_mass: FloatParam = "smass",
        /// Hand stiffness (N/m).
        hand_stiffness: FloatParam = "hstiff",
        /// Hand damping (kg/s).
        hand_damping: FloatParam = "hdamp",
        /// Finger damping (s/m).
        finger_damping: FloatParam = "fdamp",
        /// Slide contact stiffness κ (N/m^α).
        kappa: FloatParam = "kappa",
        /// Slide contact exponent α.
        alpha: FloatParam = "alpha",
        /// Pluck position (fraction of the length).
        pluck_position: FloatParam = "pluck",
        /// Pickup position (fraction of the length).
        pickup_position: FloatParam = "pickup",
        /// The loaded pickup's resonance (Hz).
        pickup_resonance: FloatParam = "ptone",
        /// The guitar new notes sound on: electric (the pickup) or acoustic.
        body: EnumParam<SlideBodyParam> = "sbody",
    }
}

param_group! {
    /// The Output group.
    OutputParams {
        /// Output gain (linear, shown in dB).
        gain: FloatParam = "gain",
        /// Safety limiter on the output.
        limiter: BoolParam = "limit",
        /// Stereo width of the piano's keys and of the acoustic guitar body's modes (%).
        stereo_width: FloatParam = "width",
    }
}

impl Default for QsaParams {
    fn default() -> Self {
        Self {
            engine: EngineParams::default(),
            piano: PianoParams::default(),
            slide: SlideParams::default(),
            output: OutputParams::default(),
            preset: Arc::new(std::sync::RwLock::new(String::new())),
        }
    }
}

impl QsaParams {
    /// The plain parameter values, as the shared mapping to engine settings takes them.
    /// Allocation-free.
    pub fn values(&self) -> ParamValues {
        let mut values = ParamValues::default();
        self.engine.read(&mut values);
        self.piano.read(&mut values);
        self.slide.read(&mut values);
        self.output.read(&mut values);
        values
    }

    /// The engine settings these parameters describe. Allocation-free (called every process
    /// call); the engine clamps whatever it gets.
    pub fn settings(&self) -> Settings {
        self.values().settings()
    }
}

#[cfg(test)]
mod tests {
    use qsa_dsp::instrument::PARAM_IDS;

    use super::*;

    /// The plugin's ids are the shared list, in order, and its defaults are the shared defaults,
    /// so the offline renderer's `--set ID=VALUE` and a host set the same thing.
    #[test]
    fn ids_and_defaults_match_the_engine() {
        let params = QsaParams::default();
        let ids: Vec<String> = params.param_map().into_iter().map(|(id, _, _)| id).collect();
        assert_eq!(ids, PARAM_IDS.map(String::from).to_vec());
        assert_eq!(params.values(), ParamValues::default());
    }

    /// Every parameter is the table's: name, group, unit, default, range, step count and poly
    /// modulation; choices list the table's options (names and ids) in its order.
    #[test]
    #[allow(unsafe_code)] // nice-plug's type-erased parameter calls are `unsafe`; see SAFETY.
    fn every_parameter_is_its_table_entry() {
        let params = QsaParams::default();
        let map = params.param_map();
        assert_eq!(map.len(), PARAMETERS.len());
        for ((id, param, group), spec) in map.into_iter().zip(&PARAMETERS) {
            assert_eq!((id.as_str(), group.as_str()), (spec.id, spec.group.name()));
            // SAFETY: `param` comes from the parameter map of `params`, which lives to the end of
            // the test, so it points at a live parameter.
            let (name, unit, default, steps, poly, bottom, top) = unsafe {
                (
                    param.name(),
                    param.unit(),
                    param.default_plain_value(),
                    param.step_count(),
                    param.poly_modulation_id(),
                    param.preview_plain(0.0),
                    param.preview_plain(1.0),
                )
            };
            assert_eq!(name, spec.name, "{id}");
            assert_eq!(default, spec.default_plain(), "{id}: default");
            assert_eq!(steps.map(|s| s as u32), spec.step_count(), "{id}: step count");
            let (min, max) = match spec.kind {
                ParamKind::Float { min, max, unit: u, poly: p, .. } => {
                    assert_eq!(unit, u, "{id}: unit");
                    assert_eq!(poly, p.map(poly_id), "{id}: poly modulation");
                    (spec.to_plain(min), spec.to_plain(max))
                }
                ParamKind::Int { min, max, unit: u, .. } => {
                    assert_eq!(unit, u, "{id}: unit");
                    (min as f32, max as f32)
                }
                ParamKind::Bool { .. } => (0.0, 1.0),
                ParamKind::Choice { options, .. } => {
                    let (names, ids) = match id.as_str() {
                        "mode" => (ModeParam::variants(), ModeParam::ids()),
                        "solver" => (SolverParam::variants(), SolverParam::ids()),
                        "handsrc" => (HandSourceParam::variants(), HandSourceParam::ids()),
                        "sbody" => (SlideBodyParam::variants(), SlideBodyParam::ids()),
                        _ => panic!("{id}: a choice without its enum here"),
                    };
                    assert_eq!(names, options.iter().map(|(_, name)| *name).collect::<Vec<_>>(), "{id}");
                    assert_eq!(ids, Some(&options.iter().map(|(id, _)| *id).collect::<Vec<_>>()[..]), "{id}");
                    (0.0, (options.len() - 1) as f32)
                }
            };
            let near = |a: f32, b: f32| (a - b).abs() <= 1e-6 * a.abs().max(b.abs()).max(1.0);
            assert!(near(bottom, min) && near(top, max), "{id}: range {bottom}..={top}, table {min}..={max}");
        }
    }

    /// Text typed into a host's or the editor's field reaches a parameter as
    /// [`ParamSpec::parse_typed`] reads it: NaN and words change nothing (the framework's own
    /// reading passed NaN on and turned a switch off at any word but `true` or `on`), a unit
    /// may follow without its space, and the value is clamped to the range.
    #[test]
    #[allow(unsafe_code)] // nice-plug's type-erased parameter calls are `unsafe`; see SAFETY.
    fn typed_text_sets_finite_values_and_refuses_the_rest() {
        let params = QsaParams::default();
        let map = params.param_map();
        let param = |id: &str| map.iter().find(|(i, _, _)| i == id).map(|(_, p, _)| *p).unwrap();
        let typed = |id: &str, text: &str| {
            // SAFETY: the pointer comes from the parameter map of `params`, alive to the end.
            unsafe { param(id).string_to_normalized_value(text) }
        };
        let plain = |id: &str, normalized: f32| {
            // SAFETY: as above.
            unsafe { param(id).preview_plain(normalized) }
        };
        for (id, text) in [("glide", "nan"), ("glide", "NaN ms"), ("gain", "nan"), ("gain", "-inf"), ("nb", "x")] {
            assert_eq!(typed(id, text), None, "{id}: {text:?}");
        }
        for text in ["yes", "1x", ""] {
            assert_eq!(typed("limit", text), None, "limit: {text:?}");
        }
        assert_eq!(typed("limit", "1").map(|n| plain("limit", n)), Some(1.0));
        assert_eq!(typed("limit", "Off").map(|n| plain("limit", n)), Some(0.0));
        let near = |a: f32, b: f32| (a - b).abs() <= 1e-5 * b.abs();
        let read = typed("glide", "120ms").map(|n| plain("glide", n));
        assert!(read.is_some_and(|v| near(v, 120.0)), "glide: {read:?}");
        let read = typed("gain", "-6dB").map(|n| plain("gain", n));
        assert!(read.is_some_and(|v| near(v, util::db_to_gain(-6.0))), "gain: {read:?}");
        assert_eq!(typed("nb", "6.5").map(|n| plain("nb", n)), Some(7.0));
        assert_eq!(typed("nb", "1e9 smp").map(|n| plain("nb", n)), Some(plain("nb", 1.0)), "clamped");
    }

    /// The table at the top of this file is the parameter table's, row by row.
    #[test]
    fn the_documentation_table_is_the_parameter_table() {
        let source = include_str!("params.rs");
        let documented: Vec<&str> = source.lines().filter(|l| l.starts_with("//! | `")).collect();
        let expected: Vec<String> = PARAMETERS
            .iter()
            .map(|p| {
                format!("//! | `{}` | {} | {} | {} | {} |", p.id, p.name, p.range_text(), p.default_text(), p.maps_to)
            })
            .collect();
        assert!(
            documented == expected,
            "the module documentation's table should read:\n//! | id | name | range | default | maps to |\n//! \
             |---|---|---|---|---|\n{}",
            expected.join("\n")
        );
    }

    /// Every parameter is in the group of the editor section that shows it.
    #[test]
    fn parameters_are_grouped_as_the_editor_shows_them() {
        let groups: Vec<(String, String)> =
            QsaParams::default().param_map().into_iter().map(|(id, _, group)| (id, group)).collect();
        let expected = |id: &str| match id {
            "mode" | "solver" | "segs" | "nb" | "voices" | "guard" => "Engine",
            "hard" | "hmass" | "strike" | "damp" | "bright" | "damper" | "detune" | "stretch" | "hpfrom" | "hpto" => {
                "Piano"
            }
            "gain" | "limit" | "width" => "Output",
            _ => "Slide",
        };
        for (id, group) in &groups {
            assert_eq!(group, expected(id), "group of {id}");
        }
    }

    /// `voices`, which acts only at activation, cannot be automated; the other whole-number
    /// parameters, which act at once, can.
    #[test]
    fn the_voice_count_alone_of_the_whole_numbers_is_not_automatable() {
        let params = QsaParams::default();
        let automatable = |p: &IntParam| !p.flags().contains(ParamFlags::NON_AUTOMATABLE);
        let engine = &params.engine;
        assert!(!automatable(&engine.voices));
        assert!(automatable(&engine.block) && automatable(&engine.segments));
    }

    /// `slide` and `hand` (and no other parameter) take polyphonic modulation, and the engine's
    /// offset for a normalized offset is the parameter's own plain difference from any value.
    #[test]
    fn poly_modulation_offsets_are_the_parameters_plain_differences() {
        let p = QsaParams::default();
        assert_eq!(p.slide.slide_position.poly_modulation_id(), Some(POLY_SLIDE));
        assert_eq!(p.slide.hand_height.poly_modulation_id(), Some(POLY_HAND));
        assert_eq!(p.slide.glide.poly_modulation_id(), None);
        for (id, param, scale) in [(POLY_SLIDE, &p.slide.slide_position, 1.0), (POLY_HAND, &p.slide.hand_height, 1e-3)]
        {
            for (base, offset) in [(0.2f32, 0.3f32), (0.5, -0.25), (0.9, 0.05)] {
                let plain = (param.preview_plain(base + offset) - param.preview_plain(base)) * scale;
                let (_, engine) = poly_offset(id, offset).expect("a poly modulation id");
                assert!((engine - plain).abs() < 1e-5 * scale.max(1e-3), "id {id}: {engine} vs {plain}");
            }
        }
        assert_eq!(poly_offset(7, 0.5), None);
    }
}
