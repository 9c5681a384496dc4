//! The plugin's parameters: stable short ids (never change once released), units and ranges, and
//! their mapping to the engine's [`Settings`].
//!
//! Hosts see them in four groups, the editor's sections (VST3 units, CLAP modules): Engine
//! (`mode` to `voices`), Piano (`hard` to `damper`), Slide (`slide` to `pickup`) and Output
//! (`gain`, `limit`), in the order of the table. `slide` and `hand` take CLAP polyphonic
//! modulation: a per-note offset, in the parameter's units, added to the value for that note
//! alone (the sum clamped to the range), where the parameter acts (`slide` when the slide does not
//! follow keys, `hand` when `Hand height from` is Parameter).
//!
//! | id | name | range | maps to |
//! |---|---|---|---|
//! | `mode` | Mode | Piano, Slide | [`Settings::mode`] |
//! | `solver` | Solver | QSA, EXP, IMP | [`Settings::method`] |
//! | `segs` | QSA segments | 1..=64 | [`Settings::segments`] |
//! | `nb` | Control block | 1..=256 samples | [`Settings::block`] |
//! | `voices` | Voices | 1..=128 (next activation) | pool size |
//! | `hard` | Hardness | ×0.1..=×10 of the per-note felt κ | [`Settings::hardness`] |
//! | `hmass` | Hammer mass | ×0.25..=×4 | [`Settings::hammer_mass`] |
//! | `strike` | Strike position | ×0.25..=×2.5 | [`Settings::strike_position`] |
//! | `damp` | String damping | ×0.1..=×10 | [`Settings::damping`] |
//! | `bright` | Brightness (inharmonicity) | ×0..=×4 of B | [`Settings::brightness`] |
//! | `damper` | Damper | 1..=500 1/s | [`Settings::damper_rate`] |
//! | `slide` | Slide position | 0..=24 semitones; poly modulation | [`Settings::slide_position`] |
//! | `follow` | Slide follows key | on/off | [`Settings::follow_key`] |
//! | `glide` | Glide time | 1..=2000 ms | [`Settings::glide_time`] |
//! | `bend` | Bend range | 0..=24 semitones | [`Settings::bend_range`] |
//! | `hand` | Hand height | −3..=3 mm; poly modulation | [`Settings::hand_height`] |
//! | `handsrc` | Hand height from | Parameter, Mod wheel, Channel pressure, Poly pressure | [`Settings::hand_source`] |
//! | `smass` | Slide mass | 5..=200 g | [`Settings::slide_mass`] |
//! | `hstiff` | Hand stiffness | 1e2..=1e6 N/m | [`Settings::hand_stiffness`] |
//! | `hdamp` | Hand damping | 0..=100 kg/s | [`Settings::hand_damping`] |
//! | `fdamp` | Finger damping | 0..=50 s/m | [`Settings::finger_damping`] |
//! | `kappa` | Slide stiffness κ | 1e6..=1e13 N/m^α | [`Settings::slide_kappa`] |
//! | `alpha` | Slide exponent α | 1..=3 | [`Settings::slide_alpha`] |
//! | `pluck` | Pluck position | 0.5..=0.98 of the length | [`Settings::pluck_position`] |
//! | `pickup` | Pickup position | 0.5..=0.98 of the length | [`Settings::pickup_position`] |
//! | `gain` | Output gain | −36..=12 dB | [`Settings::gain`] |
//! | `limit` | Safety limiter | on/off | [`Settings::limiter`] |

use std::sync::Arc;

use nice_plug::prelude::*;
use qsa_dsp::contact::Method;
use qsa_dsp::instrument::{HandSource, Mode, NoteParam, ParamValues, Settings};

/// Instrument mode parameter.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Enum)]
pub enum ModeParam {
    /// Hammer–string.
    #[id = "piano"]
    Piano,
    /// Slide–string.
    #[id = "slide"]
    Slide,
}

/// Contact solver parameter.
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

/// Hand height source parameter.
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
}

/// Range of `slide` (semitones).
pub const SLIDE_RANGE: (f32, f32) = (0.0, 24.0);

/// Range of `hand` (mm).
pub const HAND_RANGE_MM: (f32, f32) = (-3.0, 3.0);

/// Polyphonic modulation id of `slide` (nice-plug's `with_poly_modulation_id`).
pub const POLY_SLIDE: u32 = 0;

/// Polyphonic modulation id of `hand`.
pub const POLY_HAND: u32 = 1;

/// The engine's per-note offset for a polyphonic modulation of normalized offset `normalized` of
/// the parameter with poly modulation id `id`: the setting and the offset in its unit
/// (semitones, metres). Both parameters are linear, so a normalized offset is the same plain
/// offset from any value: `normalized × span`.
pub fn poly_offset(id: u32, normalized: f32) -> Option<(NoteParam, f32)> {
    let span = |(lo, hi): (f32, f32)| normalized * (hi - lo);
    match id {
        POLY_SLIDE => Some((NoteParam::SlidePosition, span(SLIDE_RANGE))),
        POLY_HAND => Some((NoteParam::HandHeight, span(HAND_RANGE_MM) * 1e-3)),
        _ => None,
    }
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
    /// under the key `preset`.
    #[persist = "preset"]
    pub preset: Arc<std::sync::RwLock<String>>,
}

/// The Engine group.
#[allow(missing_debug_implementations)]
#[derive(Params)]
pub struct EngineParams {
    /// Piano or slide guitar.
    #[id = "mode"]
    pub mode: EnumParam<ModeParam>,
    /// Contact solver.
    #[id = "solver"]
    pub solver: EnumParam<SolverParam>,
    /// QSA segments N.
    #[id = "segs"]
    pub segments: IntParam,
    /// Control block N_b (samples).
    #[id = "nb"]
    pub block: IntParam,
    /// Voice pool size (takes effect at the next activation).
    #[id = "voices"]
    pub voices: IntParam,
}

/// The Piano group (relative to the per-note rule).
#[allow(missing_debug_implementations)]
#[derive(Params)]
pub struct PianoParams {
    /// Felt hardness, relative.
    #[id = "hard"]
    pub hardness: FloatParam,
    /// Hammer mass, relative.
    #[id = "hmass"]
    pub hammer_mass: FloatParam,
    /// Striking position, relative.
    #[id = "strike"]
    pub strike_position: FloatParam,
    /// String damping, relative.
    #[id = "damp"]
    pub damping: FloatParam,
    /// Inharmonicity, relative.
    #[id = "bright"]
    pub brightness: FloatParam,
    /// Damper decay rate (1/s).
    #[id = "damper"]
    pub damper: FloatParam,
}

/// The Slide group.
#[allow(missing_debug_implementations)]
#[derive(Params)]
pub struct SlideParams {
    /// Slide position (semitones).
    #[id = "slide"]
    pub slide_position: FloatParam,
    /// Slide follows the played key.
    #[id = "follow"]
    pub follow_key: BoolParam,
    /// Glide time (ms).
    #[id = "glide"]
    pub glide: FloatParam,
    /// Pitch-bend range (semitones).
    #[id = "bend"]
    pub bend_range: FloatParam,
    /// Hand height (mm).
    #[id = "hand"]
    pub hand_height: FloatParam,
    /// Where the hand height comes from.
    #[id = "handsrc"]
    pub hand_source: EnumParam<HandSourceParam>,
    /// Slide mass (g).
    #[id = "smass"]
    pub slide_mass: FloatParam,
    /// Hand stiffness (N/m).
    #[id = "hstiff"]
    pub hand_stiffness: FloatParam,
    /// Hand damping (kg/s).
    #[id = "hdamp"]
    pub hand_damping: FloatParam,
    /// Finger damping (s/m).
    #[id = "fdamp"]
    pub finger_damping: FloatParam,
    /// Slide contact stiffness κ (N/m^α).
    #[id = "kappa"]
    pub kappa: FloatParam,
    /// Slide contact exponent α.
    #[id = "alpha"]
    pub alpha: FloatParam,
    /// Pluck position (fraction of the length).
    #[id = "pluck"]
    pub pluck_position: FloatParam,
    /// Pickup position (fraction of the length).
    #[id = "pickup"]
    pub pickup_position: FloatParam,
}

/// The Output group.
#[allow(missing_debug_implementations)]
#[derive(Params)]
pub struct OutputParams {
    /// Output gain (linear, shown in dB).
    #[id = "gain"]
    pub gain: FloatParam,
    /// Safety limiter on the output.
    #[id = "limit"]
    pub limiter: BoolParam,
}

/// A relative ("×") parameter on a log scale around 1.
fn ratio(name: &str, min: f32, max: f32) -> FloatParam {
    FloatParam::new(name, 1.0, FloatRange::Skewed { min, max, factor: FloatRange::skew_factor(-1.5) })
        .with_unit("×")
        .with_value_to_string(formatters::v2s_f32_rounded(2))
}

impl Default for QsaParams {
    fn default() -> Self {
        let d = Settings::default();
        Self {
            engine: EngineParams {
                mode: EnumParam::new("Mode", ModeParam::Piano),
                solver: EnumParam::new("Solver", SolverParam::Qsa),
                segments: IntParam::new("QSA segments", d.segments as i32, IntRange::Linear { min: 1, max: 64 }),
                block: IntParam::new("Control block", d.block as i32, IntRange::Linear { min: 1, max: 256 })
                    .with_unit(" smp"),
                voices: IntParam::new("Voices", 32, IntRange::Linear { min: 1, max: 128 }),
            },
            piano: PianoParams {
                hardness: ratio("Hardness", 0.1, 10.0),
                hammer_mass: ratio("Hammer mass", 0.25, 4.0),
                strike_position: ratio("Strike position", 0.25, 2.5),
                damping: ratio("String damping", 0.1, 10.0),
                brightness: FloatParam::new("Brightness", 1.0, FloatRange::Linear { min: 0.0, max: 4.0 })
                    .with_unit("×")
                    .with_value_to_string(formatters::v2s_f32_rounded(2)),
                damper: FloatParam::new(
                    "Damper",
                    d.damper_rate as f32,
                    FloatRange::Skewed { min: 1.0, max: 500.0, factor: FloatRange::skew_factor(-2.0) },
                )
                .with_unit(" 1/s")
                .with_value_to_string(formatters::v2s_f32_rounded(1)),
            },
            slide: SlideParams {
                slide_position: FloatParam::new(
                    "Slide position",
                    d.slide_position as f32,
                    FloatRange::Linear { min: SLIDE_RANGE.0, max: SLIDE_RANGE.1 },
                )
                .with_unit(" st")
                .with_value_to_string(formatters::v2s_f32_rounded(2))
                .with_poly_modulation_id(POLY_SLIDE),
                follow_key: BoolParam::new("Slide follows key", d.follow_key),
                glide: FloatParam::new(
                    "Glide time",
                    (d.glide_time * 1000.0) as f32,
                    FloatRange::Skewed { min: 1.0, max: 2000.0, factor: FloatRange::skew_factor(-2.0) },
                )
                .with_unit(" ms")
                .with_value_to_string(formatters::v2s_f32_rounded(1)),
                bend_range: FloatParam::new(
                    "Bend range",
                    d.bend_range as f32,
                    FloatRange::Linear { min: 0.0, max: 24.0 },
                )
                .with_unit(" st")
                .with_step_size(0.5),
                hand_height: FloatParam::new(
                    "Hand height",
                    (d.hand_height * 1000.0) as f32,
                    FloatRange::Linear { min: HAND_RANGE_MM.0, max: HAND_RANGE_MM.1 },
                )
                .with_unit(" mm")
                .with_value_to_string(formatters::v2s_f32_rounded(2))
                .with_poly_modulation_id(POLY_HAND),
                hand_source: EnumParam::new("Hand height from", HandSourceParam::Parameter),
                slide_mass: FloatParam::new(
                    "Slide mass",
                    (d.slide_mass * 1000.0) as f32,
                    FloatRange::Skewed { min: 5.0, max: 200.0, factor: FloatRange::skew_factor(-1.5) },
                )
                .with_unit(" g")
                .with_value_to_string(formatters::v2s_f32_rounded(1)),
                hand_stiffness: FloatParam::new(
                    "Hand stiffness",
                    d.hand_stiffness as f32,
                    FloatRange::Skewed { min: 1e2, max: 1e6, factor: FloatRange::skew_factor(-2.5) },
                )
                .with_unit(" N/m")
                .with_value_to_string(formatters::v2s_f32_rounded(0)),
                hand_damping: FloatParam::new(
                    "Hand damping",
                    d.hand_damping as f32,
                    FloatRange::Linear { min: 0.0, max: 100.0 },
                )
                .with_unit(" kg/s")
                .with_value_to_string(formatters::v2s_f32_rounded(1)),
                finger_damping: FloatParam::new(
                    "Finger damping",
                    d.finger_damping as f32,
                    FloatRange::Linear { min: 0.0, max: 50.0 },
                )
                .with_unit(" s/m")
                .with_value_to_string(formatters::v2s_f32_rounded(1)),
                kappa: FloatParam::new(
                    "Slide stiffness",
                    d.slide_kappa as f32,
                    FloatRange::Skewed { min: 1e6, max: 1e13, factor: FloatRange::skew_factor(-3.0) },
                )
                .with_unit(" N/m^a")
                .with_value_to_string(Arc::new(|v| format!("{v:.2e}"))),
                alpha: FloatParam::new(
                    "Slide exponent",
                    d.slide_alpha as f32,
                    FloatRange::Linear { min: 1.0, max: 3.0 },
                )
                .with_value_to_string(formatters::v2s_f32_rounded(2)),
                pluck_position: FloatParam::new(
                    "Pluck position",
                    d.pluck_position as f32,
                    FloatRange::Linear { min: 0.5, max: 0.98 },
                )
                .with_value_to_string(formatters::v2s_f32_rounded(3)),
                pickup_position: FloatParam::new(
                    "Pickup position",
                    d.pickup_position as f32,
                    FloatRange::Linear { min: 0.5, max: 0.98 },
                )
                .with_value_to_string(formatters::v2s_f32_rounded(3)),
            },
            output: OutputParams {
                gain: FloatParam::new(
                    "Output gain",
                    1.0,
                    FloatRange::Skewed {
                        min: util::db_to_gain(-36.0),
                        max: util::db_to_gain(12.0),
                        factor: FloatRange::gain_skew_factor(-36.0, 12.0),
                    },
                )
                .with_unit(" dB")
                .with_value_to_string(formatters::v2s_f32_gain_to_db(1))
                .with_string_to_value(formatters::s2v_f32_gain_to_db()),
                limiter: BoolParam::new("Safety limiter", d.limiter),
            },
            preset: Arc::new(std::sync::RwLock::new(String::new())),
        }
    }
}

impl QsaParams {
    /// The plain parameter values, as the shared mapping to engine settings takes them.
    pub fn values(&self) -> ParamValues {
        ParamValues {
            mode: match self.engine.mode.value() {
                ModeParam::Piano => Mode::Piano,
                ModeParam::Slide => Mode::Slide,
            },
            method: match self.engine.solver.value() {
                SolverParam::Qsa => Method::Qsa,
                SolverParam::Exp => Method::Exp,
                SolverParam::Imp => Method::Imp,
            },
            segments: self.engine.segments.value(),
            block: self.engine.block.value(),
            voices: self.engine.voices.value(),
            hardness: self.piano.hardness.value(),
            hammer_mass: self.piano.hammer_mass.value(),
            strike_position: self.piano.strike_position.value(),
            damping: self.piano.damping.value(),
            brightness: self.piano.brightness.value(),
            damper: self.piano.damper.value(),
            slide_position: self.slide.slide_position.value(),
            follow_key: self.slide.follow_key.value(),
            glide_ms: self.slide.glide.value(),
            bend_range: self.slide.bend_range.value(),
            hand_mm: self.slide.hand_height.value(),
            hand_source: match self.slide.hand_source.value() {
                HandSourceParam::Parameter => HandSource::Parameter,
                HandSourceParam::ModWheel => HandSource::ModWheel,
                HandSourceParam::ChannelPressure => HandSource::ChannelPressure,
                HandSourceParam::PolyPressure => HandSource::PolyPressure,
            },
            slide_mass_g: self.slide.slide_mass.value(),
            hand_stiffness: self.slide.hand_stiffness.value(),
            hand_damping: self.slide.hand_damping.value(),
            finger_damping: self.slide.finger_damping.value(),
            kappa: self.slide.kappa.value(),
            alpha: self.slide.alpha.value(),
            pluck_position: self.slide.pluck_position.value(),
            pickup_position: self.slide.pickup_position.value(),
            gain: self.output.gain.value(),
            limiter: self.output.limiter.value(),
        }
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

    /// Every parameter is in the group of the editor section that shows it.
    #[test]
    fn parameters_are_grouped_as_the_editor_shows_them() {
        let groups: Vec<(String, String)> =
            QsaParams::default().param_map().into_iter().map(|(id, _, group)| (id, group)).collect();
        let expected = |id: &str| match id {
            "mode" | "solver" | "segs" | "nb" | "voices" => "Engine",
            "hard" | "hmass" | "strike" | "damp" | "bright" | "damper" => "Piano",
            "gain" | "limit" => "Output",
            _ => "Slide",
        };
        for (id, group) in &groups {
            assert_eq!(group, expected(id), "group of {id}");
        }
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
