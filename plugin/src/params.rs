//! The plugin's parameters: stable short ids (never change once released), units and ranges, and
//! their mapping to the engine's [`Settings`].
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
//! | `slide` | Slide position | 0..=24 semitones | [`Settings::slide_position`] |
//! | `follow` | Slide follows key | on/off | [`Settings::follow_key`] |
//! | `glide` | Glide time | 1..=2000 ms | [`Settings::glide_time`] |
//! | `bend` | Bend range | 0..=24 semitones | [`Settings::bend_range`] |
//! | `hand` | Hand height | −3..=3 mm | [`Settings::hand_height`] |
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

use std::sync::Arc;

use nice_plug::prelude::*;
use qsa_dsp::contact::Method;
use qsa_dsp::instrument::{HandSource, Mode, ParamValues, Settings};

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

/// All parameters. (No `Debug`: the framework's parameter types do not implement it.)
#[allow(missing_debug_implementations)]
#[derive(Params)]
pub struct QsaParams {
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
    /// Output gain (linear, shown in dB).
    #[id = "gain"]
    pub gain: FloatParam,
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
            mode: EnumParam::new("Mode", ModeParam::Piano),
            solver: EnumParam::new("Solver", SolverParam::Qsa),
            segments: IntParam::new("QSA segments", d.segments as i32, IntRange::Linear { min: 1, max: 64 }),
            block: IntParam::new("Control block", d.block as i32, IntRange::Linear { min: 1, max: 256 })
                .with_unit(" smp"),
            voices: IntParam::new("Voices", 32, IntRange::Linear { min: 1, max: 128 }),
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
            slide_position: FloatParam::new(
                "Slide position",
                d.slide_position as f32,
                FloatRange::Linear { min: 0.0, max: 24.0 },
            )
            .with_unit(" st")
            .with_value_to_string(formatters::v2s_f32_rounded(2)),
            follow_key: BoolParam::new("Slide follows key", d.follow_key),
            glide: FloatParam::new(
                "Glide time",
                (d.glide_time * 1000.0) as f32,
                FloatRange::Skewed { min: 1.0, max: 2000.0, factor: FloatRange::skew_factor(-2.0) },
            )
            .with_unit(" ms")
            .with_value_to_string(formatters::v2s_f32_rounded(1)),
            bend_range: FloatParam::new("Bend range", d.bend_range as f32, FloatRange::Linear { min: 0.0, max: 24.0 })
                .with_unit(" st")
                .with_step_size(0.5),
            hand_height: FloatParam::new(
                "Hand height",
                (d.hand_height * 1000.0) as f32,
                FloatRange::Linear { min: -3.0, max: 3.0 },
            )
            .with_unit(" mm")
            .with_value_to_string(formatters::v2s_f32_rounded(2)),
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
            alpha: FloatParam::new("Slide exponent", d.slide_alpha as f32, FloatRange::Linear { min: 1.0, max: 3.0 })
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
        }
    }
}

impl QsaParams {
    /// The plain parameter values, as the shared mapping to engine settings takes them.
    pub fn values(&self) -> ParamValues {
        ParamValues {
            mode: match self.mode.value() {
                ModeParam::Piano => Mode::Piano,
                ModeParam::Slide => Mode::Slide,
            },
            method: match self.solver.value() {
                SolverParam::Qsa => Method::Qsa,
                SolverParam::Exp => Method::Exp,
                SolverParam::Imp => Method::Imp,
            },
            segments: self.segments.value(),
            block: self.block.value(),
            voices: self.voices.value(),
            hardness: self.hardness.value(),
            hammer_mass: self.hammer_mass.value(),
            strike_position: self.strike_position.value(),
            damping: self.damping.value(),
            brightness: self.brightness.value(),
            damper: self.damper.value(),
            slide_position: self.slide_position.value(),
            follow_key: self.follow_key.value(),
            glide_ms: self.glide.value(),
            bend_range: self.bend_range.value(),
            hand_mm: self.hand_height.value(),
            hand_source: match self.hand_source.value() {
                HandSourceParam::Parameter => HandSource::Parameter,
                HandSourceParam::ModWheel => HandSource::ModWheel,
                HandSourceParam::ChannelPressure => HandSource::ChannelPressure,
                HandSourceParam::PolyPressure => HandSource::PolyPressure,
            },
            slide_mass_g: self.slide_mass.value(),
            hand_stiffness: self.hand_stiffness.value(),
            hand_damping: self.hand_damping.value(),
            finger_damping: self.finger_damping.value(),
            kappa: self.kappa.value(),
            alpha: self.alpha.value(),
            pluck_position: self.pluck_position.value(),
            pickup_position: self.pickup_position.value(),
            gain: self.gain.value(),
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
}
